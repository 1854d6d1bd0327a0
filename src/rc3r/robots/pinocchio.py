r"""Any serial arm of 1-DoF joints, from a URDF or a ``pinocchio.Model``, as a :class:`~rc3r.robots.base.Robot`.

:class:`PinocchioRobot` computes everything with Pinocchio on its own model: the
model terms (``crba``, ``computeCoriolisMatrix``, ``computeGeneralizedGravity``),
the plant (``aba``) and the Slotine--Li regressor in the model's **base
parameters** (:mod:`rc3r.robots.base_parameters`), which are its ``theta``.

Slotine--Li regressor from the joint-torque regressor
    ``R(q, x, b) = computeJointTorqueRegressor(q, x, b)`` satisfies
    ``R(q, x, b) pi = M(q) b + C(q, x) x + g(q)`` in the standard parameters ``pi``.
    Since ``C(q, x) y`` is bilinear and symmetric in ``(x, y)`` for 1-DoF joints
    (``computeCoriolisMatrix`` is the Christoffel matrix), with
    ``s = (qd + v)/2`` and ``d = (qd - v)/2``:
    ``C(q, s) s - C(q, d) d = C(q, qd) v``. Hence, with ``R_0`` the regressor of a
    zero-gravity copy of the model,

    .. math::

        Y_{\pi}(q, \dot q, v, a) = R(q, s, a/2) - R_0(q, d, -a/2), \qquad
        Y_{\pi}\,\pi = M a + C(q, \dot q) v + g(q),

    two regressor calls per state, gravity counted once, and the base regressor
    is ``Y = Y_pi[:, independent]`` with ``Y theta = Y_pi pi``. The plain
    ``R(q, qd, a)`` is *not* a Slotine--Li regressor: it gives ``C(q, qd) qd``,
    not ``C(q, qd) v`` (``tests/test_robot_pinocchio.py`` shows it failing).
    This is :meth:`PinocchioRobot.regressor_pinocchio`, the reference (~7 ``rnea``
    calls per state through Python). :meth:`PinocchioRobot.regressor` evaluates the
    same two passes with the compiled kernel of :mod:`rc3r.robots.pinocchio_kernel`
    (revolute and prismatic joints; equal to the reference to ~1e-15 relative;
    ~2 ``rnea`` calls per state on a batch, ~5 for one state per call, measured by
    :func:`bench_regressor`); other 1-DoF joints (helical) use the reference.

Continuous joints
    Pinocchio represents a URDF ``continuous`` joint with ``nq = 2`` (cos, sin),
    but the contract's state is ``n = nv`` angles. :meth:`PinocchioRobot.from_urdf`
    therefore edits the URDF text before parsing: every ``continuous`` joint
    becomes ``revolute`` with limits ``-/+`` :data:`CONTINUOUS_LIMIT` rad (its
    dynamics are identical; only the configuration representation changes).

Standard parameters are Pinocchio's, 10 per moving body, about the joint-frame
origin in the joint frame (:data:`~rc3r.conventions.STD_KEYS`); a
body is a joint with everything rigidly attached to it (fixed joints are merged
by Pinocchio, locked joints by ``pinocchio.buildReducedModel``).
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from functools import cached_property
from pathlib import Path

import numpy as np

from ..errors import ConfigError, ParameterError, UrdfError
from ..io import MAGNITUDE_NOTE, native_stderr, number_problem, require_file
from .base import Robot, stack_states
from ..urdf_names import ERD_PREFIX, erd_name, example_robot_data_dir, mimic_advice, resolve_erd
from .base_parameters import (BaseParameters, base_parameters, check_model, physical_issues,
                              standard_parameter_names)

#: ``example_robot_data_dir``, ``ERD_PREFIX``, ``resolve_erd``, ``erd_name``, ``mimic_advice`` live in
#: :mod:`rc3r.urdf_names` (imported here, where they were first defined).
__all__ = ["PinocchioRobot", "NAMED", "CONTINUOUS_LIMIT", "VELOCITY_SHARE", "example_robot_data_dir", "ERD_PREFIX",
           "resolve_erd", "erd_name"]

#: Position limit [rad] given to ``continuous`` joints rebuilt as ``revolute``.
CONTINUOUS_LIMIT = 1000.0

#: The default trajectory's peak speed is at most this share of a joint's URDF velocity limit.
VELOCITY_SHARE = 0.5

#: ``PinocchioRobot.named(name)``: URDF path inside example-robot-data's ``robots/``
#: directory and the joints to lock (name -> value [rad or m]).
NAMED = {
    "ur5": ("ur_description/urdf/ur5_robot.urdf", {}),
    "panda": ("panda_description/urdf/panda.urdf", {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}),
}


#: Numeric attributes checked before parsing: element tag -> attributes.
_NUMERIC = {"origin": ("xyz", "rpy"), "axis": ("xyz",), "mass": ("value",),
            "inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), "limit": ("lower", "upper", "effort", "velocity")}


def _urdf_text(path: Path) -> tuple[str, tuple[str, ...], tuple[tuple[str, str], ...]]:
    """The URDF with continuous joints made revolute; their names; (mimic joint, mimicked) pairs."""
    try:
        root = ET.fromstring(path.read_text())
    except OSError as exc:
        raise UrdfError(f"cannot read URDF {path}: {exc.strerror or exc}") from None
    except ET.ParseError as exc:
        raise UrdfError(f"malformed URDF {path}: {exc}") from None
    if root.tag != "robot":
        raise UrdfError(f"malformed URDF {path}: root element is <{root.tag}>, expected <robot>")
    for tag, attrs in _NUMERIC.items():  # urdfdom only warns about these and builds a wrong model
        for el, attr in ((el, a) for el in root.iter(tag) for a in attrs if el.get(a) is not None):
            want = 3 if attr in ("xyz", "rpy") else 1
            if number_problem(el.get(attr), want, bounded=tag != "limit"):  # 1e300 overflows the arithmetic
                raise UrdfError(f"malformed URDF {path}: <{tag} {attr}={el.get(attr)!r}> is not "
                                f"{'3 numbers' if want == 3 else 'a number'}{'' if tag == 'limit' else MAGNITUDE_NOTE}")
    continuous, mimic = [], []
    for joint in root.iter("joint"):
        if joint.find("mimic") is not None:
            mimic.append((joint.get("name"), joint.find("mimic").get("joint")))
        if joint.get("type") == "continuous":
            continuous.append(joint.get("name"))
            joint.set("type", "revolute")
            limit = joint.find("limit") if joint.find("limit") is not None else ET.SubElement(joint, "limit")
            limit.set("lower", repr(-CONTINUOUS_LIMIT))
            limit.set("upper", repr(CONTINUOUS_LIMIT))
            limit.set("effort", limit.get("effort", "1e6"))
            limit.set("velocity", limit.get("velocity", "1e3"))
    return ET.tostring(root, encoding="unicode"), tuple(continuous), tuple(mimic)


#: Suffix given for the time of ``pinocchio.buildReducedModel`` to a frame that shares its name with a
#: joint (:func:`_reduced_model`).
_RENAMED = "@rc3r-frame"


def _reduced_model(model, ids, q_ref):
    """``pinocchio.buildReducedModel(model, ids, q_ref)``, also when a link and a joint share a name.

    Pinocchio 3 looks the locked joints' frames up by name alone and refuses a name that two frames
    carry ("Several frames match the filter"): the SO-100 of example-robot-data has a link and a
    joint both named ``gripper``. The frames that are not joint frames but carry a joint's name are
    renamed for the reduction and get their names back after it.
    """
    import pinocchio as pin

    joints = set(model.names)
    for frame in model.frames:
        if frame.type != pin.FrameType.JOINT and frame.name in joints:
            frame.name = frame.name + _RENAMED
    try:
        reduced = pin.buildReducedModel(model, ids, q_ref)
    finally:
        for frame in model.frames:
            if frame.name.endswith(_RENAMED):
                frame.name = frame.name[:-len(_RENAMED)]
    for frame in reduced.frames:
        if frame.name.endswith(_RENAMED):
            frame.name = frame.name[:-len(_RENAMED)]
    return reduced


#: Below this many states, :meth:`PinocchioRobot.regressor` takes Pinocchio's path while the compiled
#: kernel is not built (:meth:`~rc3r.robots.pinocchio_kernel.ChainKernel.ready`): two
#: ``computeJointTorqueRegressor`` calls cost 19 us per state on the UR5 ("Y (2 Pinocchio calls)" in
#: ``rc3r bench``, 2026-12-02), numba's first compilation of the kernel tens of seconds of CPU.
COLD_PINOCCHIO_STATES = 200_000


class PinocchioRobot(Robot):
    """A serial arm of 1-DoF joints with one parameter set, computed by Pinocchio.

    Parameters
    ----------
    model : pinocchio.Model
        Fixed-base model whose joints are all 1-DoF (revolute, prismatic; no
        ``continuous`` joint with nq = 2: use :meth:`from_urdf`), with its gravity.
    robot_name : str, optional
        What the arm is (``"ur5"``); default ``model.name``.
    label : str, optional
        Where this parameter set came from; default the URDF path or ``robot_name``.
    urdf : str, optional
        The URDF it was read from.
    base : BaseParameters, optional
        The base-parameter map of this kinematic structure (computed if omitted;
        passed on by :meth:`with_model`, whose kinematics are the same).
    kernel : ChainKernel, optional
        The compiled regressor of this structure and gravity (built if omitted).
    seed : int
        Seed of the states that determine the base parameters (the result does
        not depend on it).

    Raises
    ------
    UrdfError
        A joint that is not 1-DoF, no mass, a singular M(q), or no clear
        numerical rank of the regressor.
    """

    name = "pinocchio"

    #: M, C and g are Pinocchio's own crba, computeCoriolisMatrix, computeGeneralizedGravity on
    #: :attr:`model`: ``verify-model`` does not compare them with themselves (:mod:`rc3r.verify`).
    model_terms_are_pinocchio = True

    #: What theta's entries are (``verify-model`` prints it): see :attr:`coefficient_names`.
    theta_order = ("base parameters, in the order of rc3r.robots.base_parameters: the kept standard-parameter "
                   "columns, increasing; names in coefficient_names")

    def __init__(self, model, robot_name: str | None = None, label: str | None = None,
                 urdf: str | None = None, base: BaseParameters | None = None, seed: int = 0, kernel=None):
        import pinocchio as pin

        self.robot_name = robot_name or model.name or "robot"
        self.urdf = None if urdf is None else str(urdf)
        self._label = label or self.urdf or self.robot_name
        if base is None:
            check_model(model, self.urdf or self.robot_name)
            base = base_parameters(model, seed, where=self.urdf or self.robot_name)
        self._model = model
        self._model0 = model.copy()
        self._model0.gravity = pin.Motion.Zero()
        self.base = base
        if kernel is None:
            from .pinocchio_kernel import ChainKernel

            kernel = ChainKernel(model)
        #: The compiled regressor (:mod:`.pinocchio_kernel`), None for joints it does not handle.
        self.kernel = kernel if kernel.supported else None
        self._columns = np.ascontiguousarray(base.independent, dtype=np.int64)
        self.locked: dict = {}
        self.continuous: tuple = ()

    # ---- construction -----------------------------------------------------------------
    @classmethod
    def from_urdf(cls, path, lock: dict | None = None, robot_name: str | None = None,
                  label: str | None = None, gravity=None, seed: int = 0) -> "PinocchioRobot":
        """Read a URDF (a path, or ``erd:REL`` for a file of example-robot-data: :data:`ERD_PREFIX`); lock
        the joints of ``lock`` (``{"joint": value}``) at their values.

        ``continuous`` joints become ``revolute`` (module docstring). A ``<mimic>``
        joint must be locked. ``gravity`` (3,) [m/s^2] replaces Pinocchio's default
        ``(0, 0, -9.81)``.

        Raises
        ------
        UrdfError
            Missing or malformed file, unknown locked joint, unlocked mimic joint,
            or a model :class:`PinocchioRobot` refuses.
        """
        import pinocchio as pin

        path = require_file(resolve_erd(path), "URDF", UrdfError)  # not found, not a file, a name too long ...
        text, continuous, mimic = _urdf_text(path)
        try:  # urdfdom prints its reason on fd 2: caught, and folded into the one line
            with native_stderr() as cpp:
                model = pin.buildModelFromXML(text)
        except (RuntimeError, ValueError) as exc:
            msg = str(exc).strip().splitlines()
            raise UrdfError(cpp.folded(f"Pinocchio cannot read URDF {path}",
                                       msg[0] if msg else type(exc).__name__)) from None
        lock = dict(lock or {})
        free = [(joint, leader) for joint, leader in mimic if joint not in lock]
        if free:
            raise UrdfError(mimic_advice(path, free))
        if lock:
            unknown = [j for j in lock if not model.existJointName(j)]
            if unknown:
                raise UrdfError(f"{path}: cannot lock unknown joint(s) {', '.join(unknown)}")
            q_ref, ids = pin.neutral(model), [model.getJointId(j) for j in lock]
            for jid, (joint, value) in zip(ids, lock.items()):
                if model.joints[jid].nq != 1:
                    raise UrdfError(f"{path}: cannot lock joint '{joint}': it is not 1-DoF")
                q_ref[model.idx_qs[jid]] = float(value)
            model = _reduced_model(model, ids, q_ref)
        if gravity is not None:
            model.gravity = pin.Motion(np.asarray(gravity, dtype=float), np.zeros(3))
        robot = cls(model, robot_name or model.name, label or erd_name(path), urdf=str(path), seed=seed)
        robot.locked, robot.continuous = {k: float(v) for k, v in lock.items()}, continuous
        return robot

    @classmethod
    def named(cls, name: str, **kwargs) -> "PinocchioRobot":
        """An arm of example-robot-data by name (:data:`NAMED`: ``ur5``, ``panda`` with fingers locked);
        a ``lock`` keyword locks more joints (or the same at other values)."""
        if name not in NAMED:
            raise ConfigError(f"unknown named robot {name!r} (known: {', '.join(NAMED)})")
        rel, lock = NAMED[name]
        lock = {**lock, **(kwargs.pop("lock", None) or {})}
        path = example_robot_data_dir() / rel
        if not path.is_file():
            raise UrdfError(f"example-robot-data has no {rel} under {path.parents[len(Path(rel).parts) - 1]}")
        return cls.from_urdf(path, lock=lock, robot_name=name, **kwargs)

    @classmethod
    def nominal(cls, name: str = "ur5") -> "PinocchioRobot":
        """The registry's constructor: :meth:`named`."""
        return cls.named(name)

    def default_box(self):
        """None: a URDF arm has no default uncertainty (give ``--box`` or ``--payload``)."""
        return None

    def _sine_centres(self, amplitude: float, omega: float = 1.0):
        """Centre c (n,) and amplitude A (n,) of each joint's default sine, and the degenerate joints."""
        lo, hi = self.joint_limits
        degenerate = ~(hi - lo > 0)  # lower >= upper (or NaN): no range to stay inside
        with np.errstate(invalid="ignore"):
            mid = np.where(degenerate, np.where(np.isfinite(lo), lo, 0.0), 0.5 * (lo + hi))
        c = np.clip(np.nan_to_num(mid, nan=0.0), -math.pi, math.pi)
        amp = np.where(degenerate, amplitude, np.minimum(amplitude, 0.3 * 0.5 * (hi - lo)))
        vel = np.asarray(self._model.velocityLimit, dtype=float)  # 0 or inf: no limit given
        speed = np.where((vel > 0) & np.isfinite(vel), VELOCITY_SHARE * vel / abs(omega), np.inf)
        return c, np.minimum(amp, speed), np.flatnonzero(degenerate)

    def default_trajectory(self, amplitude: float = 0.5, omega: float = 1.0):
        r"""Sines inside the joint limits: :math:`q_{d,i} = c_i + A_i \sin(\omega t + i\pi/3)`.

        ``c_i`` is the middle of joint i's range (clipped to [-pi, pi]), ``A_i = min(amplitude,
        0.3 x half the range, VELOCITY_SHARE x v_max,i / omega)`` [rad], ``omega`` [rad/s]; so the
        reference stays inside the limits with a margin of at least 70 % of the half range, and its
        speed at most half the URDF's velocity limit ``v_max,i`` (where one is given: the Kinova's
        0.63 rad/s makes its sines 0.31 rad; the other arms' limits are above 1 rad/s). A joint whose limits are no range
        (``lower >= upper``, e.g. the double pendulum of example-robot-data: both 0) gets
        ``c_i = lower`` (clipped) and the fixed amplitude ``A_i = amplitude``, instead of a
        constant q_d; :meth:`default_trajectory_warnings` says so.
        """
        from ..trajectory import Sines

        c, amp, _ = self._sine_centres(amplitude, omega)
        terms = tuple((i + 1, float(amp[i]), float(omega), i * math.pi / 3) for i in range(self.n))
        return Sines(tuple(float(x) for x in c), terms)

    def default_trajectory_warnings(self, amplitude: float = 0.5) -> list[str]:
        """Why :meth:`default_trajectory` did not follow the joint limits: one line, or none."""
        c, amp, bad = self._sine_centres(amplitude)
        if not bad.size:
            return []
        lo, hi = self.joint_limits
        joints = ", ".join(f"{self.joint_names[i]} ({lo[i]:g}..{hi[i]:g})" for i in bad)
        return [f"joint limits lower >= upper are no range for {joints}: the default trajectory moves "
                f"{'that joint' if bad.size == 1 else 'those joints'} by the fixed amplitude {amplitude:g} "
                f"about c = {', '.join(f'{c[i]:g}' for i in bad)} (q_d,i = c + {amplitude:g} sin(t + i pi/3)); "
                "the plant does not enforce the limits"]

    #: theta is linear in the standard parameters (first moments, inertia about the joint frame),
    #: so exact ranges over a box follow from interval arithmetic (:mod:`rc3r.uncertainty.bounds`).
    linear_in_standard_parameters = True
    compiled_kernels = property(lambda self: None if self.kernel is None else self.kernel.supply(self))

    # ---- sizes and parameters ---------------------------------------------------------
    @property
    def n(self) -> int:
        return int(self._model.nv)

    @property
    def p(self) -> int:
        return self.base.p

    @property
    def nbodies(self) -> int:
        """Number of moving bodies (one per joint)."""
        return int(self._model.njoints - 1)

    @cached_property
    def theta(self) -> np.ndarray:
        """Base parameters of this parameter set, (p,) (read-only)."""
        th = self.base.theta(self.standard_parameters())
        th.flags.writeable = False
        return th

    @property
    def coefficient_names(self) -> tuple[str, ...]:
        """Each base parameter's independent standard parameter, ``+`` if others add (``base.expressions()``)."""
        return self.base.coefficient_names()

    @property
    def standard_parameter_names(self) -> tuple[str, ...]:
        return standard_parameter_names(self.nbodies)

    @property
    def label(self) -> str:
        return self._label

    @property
    def model(self):
        return self._model

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the n joints, in q order."""
        return tuple(self._model.names[1:])

    @property
    def joint_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """The model's position limits ``(lower, upper)`` [rad or m] (continuous joints: +-1000 rad)."""
        return np.array(self._model.lowerPositionLimit), np.array(self._model.upperPositionLimit)

    # ---- dynamics ---------------------------------------------------------------------
    def _datas(self):
        if getattr(self, "_pin_datas", None) is None:
            self._pin_datas = (self._model.createData(), self._model0.createData())
        return self._pin_datas

    def _states(self, *xs) -> tuple[bool, np.ndarray]:
        """(single, X) with X (len(xs), N, n) from (n,) or (N, n) arrays (:func:`~rc3r.robots.base.stack_states`)."""
        return stack_states(self.n, *xs)

    def regressor(self, q, qd, v, a) -> np.ndarray:
        """Slotine--Li regressor in the base parameters, (n, p) or (N, n, p) (module docstring).

        Identity: ``regressor(q, qd, v, a) @ theta == M(q) a + C(q, qd) v + g(q)``.
        """
        single, X = self._states(q, qd, v, a)
        if self.kernel is None or (X.shape[1] < COLD_PINOCCHIO_STATES and not self.kernel.ready()):
            return self.regressor_pinocchio(q, qd, v, a)
        out = self.kernel(X, self._columns)
        return out[0] if single else out

    def regressor_pinocchio(self, q, qd, v, a, standard: bool = False) -> np.ndarray:
        """:meth:`regressor` by two ``computeJointTorqueRegressor`` calls per state (the reference).

        With ``standard=True`` all 10 nb standard-parameter columns ``Y_pi``,
        (n, 10 nb) or (N, n, 10 nb): ``Y_pi @ standard_parameters() == M a + C v + g``.
        """
        import pinocchio as pin

        single, (Q, QD, V, A) = self._states(q, qd, v, a)
        S, D, H = 0.5 * (QD + V), 0.5 * (QD - V), 0.5 * A
        m, m0 = self._model, self._model0
        d, d0 = self._datas()
        f = pin.computeJointTorqueRegressor
        out = np.array([np.reshape(f(m, d, qi, si, hi) - f(m0, d0, qi, di, -hi), (m.nv, -1))  # 1 DoF: a vector
                        for qi, si, di, hi in zip(Q, S, D, H)])
        if not standard:
            out = np.ascontiguousarray(out[:, :, self.base.independent])
        return out[0] if single else out

    def _batch(self, fn: str, *args) -> np.ndarray:
        """Pinocchio function ``fn`` of (n,) states, or looped over (N, n) states."""
        import pinocchio as pin

        fn, data = getattr(pin, fn), self._datas()[0]
        single, X = self._states(*args)
        out = np.array([np.array(fn(self._model, data, *row), copy=True) for row in zip(*X)])
        return out[0] if single else out

    def mass_matrix(self, q) -> np.ndarray:
        """M(q) from ``pinocchio.crba`` (upper triangle mirrored), (n, n) or (N, n, n)."""
        M = self._batch("crba", q)
        return np.triu(M) + np.swapaxes(np.triu(M, 1), -1, -2)

    def coriolis_matrix(self, q, qd) -> np.ndarray:
        """Christoffel matrix C(q, qd) from ``pinocchio.computeCoriolisMatrix``, (n, n) or (N, n, n)."""
        return self._batch("computeCoriolisMatrix", q, qd)

    def gravity(self, q) -> np.ndarray:
        """g(q) from ``pinocchio.computeGeneralizedGravity``, (n,) or (N, n) [N m or N]."""
        return self._batch("computeGeneralizedGravity", q)

    def forward_dynamics(self, q, qd, u) -> np.ndarray:
        """Joint accelerations by ``pinocchio.aba``, (n,) or (N, n)."""
        if np.ndim(q) == 1 and np.ndim(qd) == 1 and np.ndim(u) == 1:  # the simulator's path: one state
            import pinocchio as pin

            return np.array(pin.aba(self._model, self._datas()[0], np.asarray(q, float), np.asarray(qd, float),
                                    np.asarray(u, float)))
        return self._batch("aba", q, qd, u)

    # ---- parameter sets ---------------------------------------------------------------
    def standard_parameters(self) -> np.ndarray:
        """``inertias[i].toDynamicParameters()`` of every moving body, concatenated: (10 nb,)."""
        return np.concatenate([self._model.inertias[i].toDynamicParameters()
                               for i in range(1, self._model.njoints)])

    def theta_of_standard(self, std) -> np.ndarray:
        """Base parameters ``T @ std``, (..., 10 nb) -> (..., p)."""
        return self.base.theta(std)

    def with_model(self, model, label: str) -> "PinocchioRobot":
        """The same robot with ``model``: same kinematics (not checked), other inertias or gravity."""
        same_gravity = np.array_equal(model.gravity.vector, self._model.gravity.vector)
        out = type(self)(model, self.robot_name, label, urdf=self.urdf, base=self.base,
                         kernel=self.kernel if same_gravity and self.kernel else None)
        out.locked, out.continuous = dict(self.locked), self.continuous
        return out

    def with_standard_parameters(self, std, label: str) -> "PinocchioRobot":
        """A copy whose inertias are ``pinocchio.Inertia.FromDynamicParameters`` of ``std`` (10 nb,).

        A body whose 10 parameters are all zero gets a zero inertia; a zero mass
        with non-zero moments cannot be represented (ParameterError).
        """
        import pinocchio as pin

        std = np.asarray(std, dtype=float)
        if std.shape != (10 * self.nbodies,) or not np.all(np.isfinite(std)):
            raise ParameterError(f"expected {10 * self.nbodies} finite standard parameters, got shape {std.shape}")
        model = self._model.copy()
        for k in range(self.nbodies):
            block = std[10 * k: 10 * k + 10]
            if block[0] == 0.0 and np.any(block != 0.0):
                raise ParameterError(f"body {k + 1} ({self._model.names[k + 1]}): zero mass with non-zero moments")
            model.inertias[k + 1] = (pin.Inertia.Zero() if block[0] == 0.0
                                     else pin.Inertia.FromDynamicParameters(block))
        return self.with_model(model, label)

    def physical_issues(self) -> list[str]:
        """Per body: mass, inertia about the CoM, triangle inequality (:func:`.base_parameters.physical_issues`)."""
        return physical_issues(self.standard_parameters(), self.joint_names)

    def describe(self) -> dict:
        """Contract fields plus ``robot_name`` and, if any, ``urdf``, ``locked``, ``continuous_as_revolute``."""
        extra = {"urdf": self.urdf, "locked": dict(self.locked), "continuous_as_revolute": list(self.continuous)}
        return {**super().describe(), "robot_name": self.robot_name, **{k: v for k, v in extra.items() if v}}

    def __repr__(self) -> str:
        return f"<PinocchioRobot {self.robot_name!r} n={self.n} p={self.p} label={self.label!r}>"

    def __getstate__(self):  # pinocchio Data is rebuilt after unpickling
        state = dict(self.__dict__)
        state.pop("_pin_datas", None)
        return state

