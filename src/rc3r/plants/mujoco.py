r"""MuJoCo as a second rigid-body engine for the plant: :class:`MujocoRigidBody`.

A URDF is compiled by MuJoCo's own URDF importer (``mujoco.MjModel.from_xml_string``) after
four edits of its text: ``<visual>`` and ``<collision>`` elements are removed (the plant needs
no geometry, and meshes would have to be found); a ``<mujoco><compiler .../></mujoco>`` element
fixes the import options (``fusestatic`` merges fixed links, ``balanceinertia="false"`` so that
an inconsistent inertia is **refused**, not silently changed, ``inertiafromgeom="false"`` so
that the URDF's ``<inertial>`` is the only source of mass); every ``<inertial>`` is rewritten
with its inertia in the link frame (MuJoCo < 4 drops the rotation of the inertial frame); and
locked joints become ``fixed`` with their value folded into the joint origin. The compiled
model is then made a pure rigid-body plant: damping, armature, friction loss and stiffness 0,
joint limits off, contacts (and with them every constraint) disabled, gravity ``(0, 0, -g0)``,
MuJoCo's RK4 integrator.

What it computes is therefore ``M(q) qdd + c(q, qd) + g(q) = u`` by MuJoCo's algorithms (CRB for
``M``, RNE for the bias forces, a sparse ``L^T D L`` solve for ``qdd``), independently of
Pinocchio: ``tests/test_plant_mujoco.py`` compares both on the UR5 and the Panda of
example-robot-data and on a physically consistent 3R. MuJoCo refuses a body whose principal
moments violate the triangle inequality (``I_a + I_b >= I_c``), which Pinocchio accepts.
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..errors import ConfigError, ParameterError, UrdfError
from .rigid import RigidBody

__all__ = ["MujocoRigidBody", "MAX_STEP"]

#: Largest internal RK4 step of :meth:`MujocoRigidBody.advance` [s].
MAX_STEP = 1e-4

#: URDF joint types with one degree of freedom.
_ONE_DOF = ("revolute", "continuous", "prismatic")

_COMPILER = {"fusestatic": "true", "discardvisual": "true", "balanceinertia": "false",
             "inertiafromgeom": "false", "angle": "radian"}


def _import_mujoco():
    """The ``mujoco`` module, or ConfigError (one line) if the optional dependency is missing."""
    try:
        import mujoco
    except ImportError:
        raise ConfigError("MuJoCo is not installed: pip install 'rc3r[mujoco]' (mujoco>=3.1)") from None
    return mujoco


def _floats(text: str | None, default) -> np.ndarray:
    return np.array([float(x) for x in text.split()]) if text else np.array(default, dtype=float)


def _lock_joint(joint: ET.Element, value: float) -> None:
    """Make ``joint`` fixed at ``value`` [rad or m]: ``origin <- origin * motion(axis, value)``."""
    from scipy.spatial.transform import Rotation

    origin = joint.find("origin")
    if origin is None:
        origin = ET.SubElement(joint, "origin")
    xyz = _floats(origin.get("xyz"), (0, 0, 0))
    rot = Rotation.from_euler("xyz", _floats(origin.get("rpy"), (0, 0, 0)))  # URDF: Rz(y) Ry(p) Rx(r)
    axis_el = joint.find("axis")
    axis = _floats(axis_el.get("xyz") if axis_el is not None else None, (1, 0, 0))
    axis = axis / np.linalg.norm(axis)
    if joint.get("type") == "prismatic":
        xyz = xyz + rot.apply(axis * value)
    else:
        rot = rot * Rotation.from_rotvec(axis * value)
    origin.set("xyz", " ".join(repr(float(x)) for x in xyz))
    origin.set("rpy", " ".join(repr(float(x)) for x in rot.as_euler("xyz")))
    joint.set("type", "fixed")
    for tag in ("axis", "limit", "dynamics", "mimic", "safety_controller", "calibration"):
        for el in joint.findall(tag):
            joint.remove(el)


def _inertia_in_link_frame(inertial: ET.Element) -> None:
    """Rewrite an ``<inertial>`` with ``rpy = 0``: its inertia rotated into the link frame, ``R I R^T``.

    MuJoCo before 4.0 loses the rotation of ``<inertial><origin rpy>`` when it compiles a URDF
    (google-deepmind/mujoco issue 3559; measured with 3.1.6 and 3.3.0: 0.25 kg m^2 wrong on a
    unit test body); an inertia given in the link frame is read right by every version.
    """
    from scipy.spatial.transform import Rotation

    origin, el = inertial.find("origin"), inertial.find("inertia")
    rpy = _floats(origin.get("rpy") if origin is not None else None, (0, 0, 0))
    if el is None or not np.any(rpy):
        return
    keys = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    v = {k: float(el.get(k, 0.0)) for k in keys}
    inertia = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]],
                        [v["ixz"], v["iyz"], v["izz"]]])
    rot = Rotation.from_euler("xyz", rpy).as_matrix()  # URDF: Rz(y) Ry(p) Rx(r)
    inertia = rot @ inertia @ rot.T
    for key, (i, j) in zip(keys, ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))):
        el.set(key, repr(float(inertia[i, j])))
    origin.set("rpy", "0 0 0")


def plant_urdf_text(text: str, where: str, locked: dict | None = None) -> tuple[str, tuple[str, ...]]:
    """The URDF text MuJoCo compiles, and its moving joints in document order (module docstring).

    Raises
    ------
    UrdfError
        Malformed XML, an unknown or non-1-DoF locked joint, an unlocked ``<mimic>`` joint, or
        a joint that is neither fixed nor 1-DoF.
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise UrdfError(f"malformed URDF {where}: {exc}") from None
    if root.tag != "robot":
        raise UrdfError(f"malformed URDF {where}: root element is <{root.tag}>, expected <robot>")
    locked = dict(locked or {})
    joints = {j.get("name"): j for j in root.findall("joint")}  # not <transmission><joint>
    unknown = [name for name in locked if name not in joints]
    if unknown:
        raise UrdfError(f"{where}: cannot lock unknown joint(s) {', '.join(map(str, unknown))}")
    for name, value in locked.items():
        if joints[name].get("type") not in _ONE_DOF:
            raise UrdfError(f"{where}: cannot lock joint '{name}': it is not 1-DoF")
        _lock_joint(joints[name], float(value))
    moving, mimic = [], []
    for name, joint in joints.items():
        kind = joint.get("type")
        if kind == "fixed":
            continue
        if kind not in _ONE_DOF:
            raise UrdfError(f"{where}: joint '{name}' of type {kind!r} is not 1-DoF (revolute, continuous, prismatic)")
        if joint.find("mimic") is not None:
            mimic.append((name, joint.find("mimic").get("joint")))
        moving.append(name)
    if mimic:
        from ..urdf_names import mimic_advice

        raise UrdfError(mimic_advice(where, mimic))
    for inertial in root.iter("inertial"):
        _inertia_in_link_frame(inertial)
    for parent in list(root.iter()):
        for child in list(parent):
            if child.tag in ("visual", "collision", "mujoco"):
                parent.remove(child)
    ET.SubElement(ET.SubElement(root, "mujoco"), "compiler", _COMPILER)
    return ET.tostring(root, encoding="unicode"), tuple(moving)


class MujocoRigidBody(RigidBody):
    """A fixed-base chain of 1-DoF joints simulated by MuJoCo, as a plant's :class:`~rc3r.plants.RigidBody`.

    It provides ``n``, ``label``, :meth:`forward_dynamics`, :meth:`mass_matrix`, :meth:`describe`,
    :meth:`bias_forces` and :meth:`advance` (it integrates a held torque itself); not ``p``, ``theta``
    (None: MuJoCo reads the masses from the URDF), a regressor or compiled kernels.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model (:meth:`from_urdf` builds and configures it; a model given directly
        is configured the same way: no damping, armature, friction loss, stiffness, joint limits
        or contacts; RK4).
    joint_names : sequence of str
        The plant's joints in the order of ``q`` (default: MuJoCo's joint order).
    g0 : float
        Gravity magnitude [m/s^2]; gravity is ``(0, 0, -g0)`` in the base frame.
    max_step : float
        Largest internal RK4 step of :meth:`advance` [s].
    source : str, optional
        Where the model came from (for messages).

    Attributes
    ----------
    n : int
        Number of joints (``q``, ``qd``, ``u`` have shape ``(n,)``).
    joint_names : tuple of str
        Joint names in ``q`` order.
    model, data : mujoco.MjModel, mujoco.MjData
        MuJoCo's model and its one work data (so one plant is not for concurrent threads).

    Notes
    -----
    Units are SI: ``q`` [rad or m], ``qd`` [rad/s or m/s], ``qdd`` [rad/s^2 or m/s^2], ``u``
    [N m or N] (a generalized force per joint, applied as ``qfrc_applied``).
    """

    name = "mujoco"

    def __init__(self, model, joint_names=None, g0: float = 9.81, max_step: float = MAX_STEP,
                 source: str | None = None):
        mujoco = _import_mujoco()

        self.source = source or "MuJoCo model"
        if not (math.isfinite(max_step) and max_step > 0):
            raise ParameterError(f"max_step must be a positive number of seconds, got {max_step!r}")
        self.max_step = float(max_step)
        m = model
        one_dof = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        if m.nq != m.nv or m.nu or any(int(t) not in one_dof for t in m.jnt_type):
            raise UrdfError(f"{self.source}: the plant needs 1-DoF joints (hinge or slide) only, no actuators")
        if joint_names is None:
            joint_names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]
        ids = []
        for name in joint_names:
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
            if j < 0:
                raise UrdfError(f"{self.source}: MuJoCo's model has no joint {name!r}")
            ids.append(j)
        if sorted(ids) != list(range(m.njnt)):
            raise UrdfError(f"{self.source}: joint_names must name each of the {m.njnt} joints once")
        self.joint_names = tuple(joint_names)
        self._qadr = np.array([m.jnt_qposadr[j] for j in ids], dtype=np.int64)
        self._vadr = np.array([m.jnt_dofadr[j] for j in ids], dtype=np.int64)
        m.dof_damping[:] = 0.0
        m.dof_armature[:] = 0.0
        m.dof_frictionloss[:] = 0.0
        m.jnt_stiffness[:] = 0.0
        m.jnt_limited[:] = 0
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
        autoreset = getattr(mujoco.mjtDisableBit, "mjDSBL_AUTORESET", None)  # MuJoCo >= 3.2
        if autoreset is not None:  # a bad state is kept (and raised by advance), not reset to qpos0
            m.opt.disableflags |= int(autoreset)
        #: Warning count advance() starts from: MuJoCo reports a warning only when its count is 0
        #: (to stderr and MUJOCO_LOG.TXT in the working directory); without auto-reset, starting at 1
        #: keeps it silent and the count still grows.
        self._warned = 1 if autoreset is not None else 0
        m.opt.gravity[:] = (0.0, 0.0, -float(g0))
        m.opt.integrator = int(mujoco.mjtIntegrator.mjINT_RK4)
        self.g0 = float(g0)
        self.model = m
        self.data = mujoco.MjData(m)
        self._mujoco = mujoco

    @classmethod
    def from_urdf(cls, path, locked: dict | None = None, g0: float = 9.81, max_step: float = MAX_STEP,
                  joint_names=None) -> "MujocoRigidBody":
        """Compile a URDF with MuJoCo (module docstring for the edits made before).

        Parameters
        ----------
        path : str or Path
            The URDF; its mesh files are never read.
        locked : dict, optional
            Joints to fix, ``{name: value}`` [rad or m]; a locked joint becomes ``fixed`` at that
            value (the same model as ``pinocchio.buildReducedModel``).
        g0, max_step
            As in the class.
        joint_names : sequence of str, optional
            Order of ``q``; default the URDF's order of its moving joints (document order).

        Raises
        ------
        UrdfError
            Missing or malformed file, bad locked joints, or a model MuJoCo refuses (e.g. a
            body whose inertia violates the triangle inequality), as one line.
        ConfigError
            MuJoCo is not installed.
        """
        mujoco = _import_mujoco()

        path = Path(path)
        try:
            text = path.read_text()
        except OSError as exc:
            raise UrdfError(f"cannot read URDF {path}: {exc.strerror or exc}") from None
        xml, moving = plant_urdf_text(text, str(path), locked)
        try:
            model = mujoco.MjModel.from_xml_string(xml)
        except ValueError as exc:
            msg = "; ".join(line.strip() for line in str(exc).splitlines() if line.strip())
            raise UrdfError(f"MuJoCo cannot compile {path}: {msg}") from None
        return cls(model, joint_names or moving, g0=g0, max_step=max_step, source=str(path))

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.joint_names)

    # ---- state in and out ---------------------------------------------------------------
    def _vec(self, x, name: str) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.shape != (self.n,):
            raise ParameterError(f"{name} must have shape ({self.n},), got {x.shape}")
        return x

    def _set(self, q, qd, u=None) -> None:
        d = self.data
        d.qpos[self._qadr] = self._vec(q, "q")
        d.qvel[self._vadr] = self._vec(qd, "qd")
        d.qfrc_applied[:] = 0.0
        if u is not None:
            d.qfrc_applied[self._vadr] = self._vec(u, "u")
        d.time = 0.0

    # ---- dynamics -----------------------------------------------------------------------
    def forward_dynamics(self, q, qd, u) -> np.ndarray:
        """Joint accelerations ``qdd`` (n,) under the generalized forces ``u`` (n,) (``mj_forward``)."""
        self._set(q, qd, u)
        self._mujoco.mj_forward(self.model, self.data)
        return self.data.qacc[self._vadr].copy()

    def mass_matrix(self, q) -> np.ndarray:
        """The joint-space inertia matrix ``M(q)`` (n, n) [kg m^2 ...] (``mj_fullM``)."""
        self._set(q, np.zeros(self.n))
        self._mujoco.mj_forward(self.model, self.data)
        full = np.zeros((self.model.nv, self.model.nv))
        if hasattr(self.data, "qM"):  # MuJoCo 3.x: mj_fullM(m, dst, qM)
            self._mujoco.mj_fullM(self.model, full, self.data.qM)
        else:  # MuJoCo 4: mj_fullM(m, d, dst)
            self._mujoco.mj_fullM(self.model, self.data, full)
        return full[np.ix_(self._vadr, self._vadr)]

    def bias_forces(self, q, qd) -> np.ndarray:
        """``c(q, qd) + g(q)`` (n,) [N m ...]: the torque that holds ``qdd = 0`` (``qfrc_bias``)."""
        self._set(q, qd)
        self._mujoco.mj_forward(self.model, self.data)
        return self.data.qfrc_bias[self._vadr].copy()

    @property
    def label(self) -> str:
        """Where the model came from (the URDF path)."""
        return self.source

    def describe(self) -> dict:
        """JSON-ready: engine, MuJoCo version, source, joints, gravity, RK4 step bound."""
        return {"engine": "mujoco", "mujoco": self._mujoco.__version__, "source": self.source,
                "joints": list(self.joint_names), "g0": self.g0, "max_step": self.max_step,
                "integrator": "RK4"}

    def steps(self, T: float) -> tuple[int, float]:
        """``(N, dt)``: the number of RK4 steps of :meth:`advance` over ``T`` [s] and their length
        ``dt = T / N <= max_step`` [s]."""
        T = float(T)
        if not (math.isfinite(T) and T > 0):
            raise ParameterError(f"the period T must be a positive number of seconds, got {T!r}")
        N = max(1, math.ceil(T / self.max_step * (1 - 1e-12)))
        return N, T / N

    def advance(self, q, qd, u, T: float) -> tuple[np.ndarray, np.ndarray]:
        """The state after ``T`` [s] under the torque ``u`` held constant (a zero-order hold).

        MuJoCo's RK4 integrator at ``N`` equal steps ``dt = T / N <= max_step`` (:meth:`steps`).

        Parameters
        ----------
        q, qd, u : array_like, shape (n,)
            Start state [rad, rad/s] and the held generalized forces [N m].
        T : float
            Period [s].

        Returns
        -------
        q, qd : ndarray, shape (n,)
            State at ``T``.

        Raises
        ------
        FloatingPointError
            MuJoCo met a non-finite or huge (> 1e10) position, velocity or acceleration. (By
            default MuJoCo would reset the state to ``qpos0`` and go on: auto-reset is disabled
            where MuJoCo has the flag, >= 3.2, and the reset is detected where it has not.)
        """
        mj = self._mujoco
        N, dt = self.steps(T)
        self.model.opt.timestep = dt
        self._set(q, qd, u)
        bad = (mj.mjtWarning.mjWARN_BADQPOS, mj.mjtWarning.mjWARN_BADQVEL, mj.mjtWarning.mjWARN_BADQACC)
        for w in bad:
            self.data.warning[int(w)].number = self._warned
        mj.mj_step(self.model, self.data, nstep=N)
        q1, qd1 = self.data.qpos[self._qadr].copy(), self.data.qvel[self._vadr].copy()
        if (any(self.data.warning[int(w)].number > self._warned for w in bad)
                or not (np.all(np.isfinite(q1)) and np.all(np.isfinite(qd1)))):
            raise FloatingPointError(f"{self.source}: MuJoCo met a non-finite or huge state within {T:g} s "
                                     f"(from q = {np.asarray(q).tolist()}, qd = {np.asarray(qd).tolist()})")
        return q1, qd1

    def __getstate__(self):  # MjData and the module are rebuilt after unpickling
        state = dict(self.__dict__)
        state.pop("data")
        state.pop("_mujoco")
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._mujoco = _import_mujoco()
        self.data = self._mujoco.MjData(self.model)

    def __repr__(self) -> str:
        return f"MujocoRigidBody({self.source!r}, n={self.n}, g0={self.g0:g}, max_step={self.max_step:g})"
