r"""A robot with joint friction and rotor inertia (armature) in its model: :class:`ActuatedRobot`.

Any robot of the contract (the 3R's closed form, a Pinocchio URDF arm) gains per-joint coefficients of the kinds
of :data:`rc3r.identify.regressors.JOINT_KINDS` (``viscous`` fv [N m s/rad], ``coulomb`` fc [N m], ``offset`` f0
[N m], ``armature`` ia [kg m^2]), the columns identification estimates (:func:`~rc3r.identify.regressors.
joint_columns`). Its coefficients are ``theta = [theta_r, fv_1..fv_n, fc_1.., f0_1.., ia_1..]`` (the kinds
present, in that order) and its regressor ``Y = [Y_r(q, qd, v, a) | joint columns(qd, a)]``:

.. math::

    Y(q, \dot q, v, a)\,\theta = (M(q) + \mathrm{diag}(i_a))\,a + C(q, \dot q)\,v + g(q)
        + f_v \dot q + f_c \tanh(\dot q / v_s) + f_0 .

**Where each term sits.** ``mass_matrix`` is ``M + diag(ia)`` (the armature is inertia: Pinocchio's
``model.armature``, which ``crba``, ``rnea`` and ``aba`` include); ``coriolis_matrix`` and ``gravity`` are the
rigid body's; friction and offset are in none of them but in :meth:`ActuatedRobot.joint_friction`
(``f_v qd + f_c tanh(qd / v_s) + f_0``, the torque the joints need to overcome them). The control laws see the
model only through ``Y``, so every law compensates friction through ``Y theta_0`` at the **measured** velocity
(computed torque and PD+ included; PD plus "gravity" compensates the offset and the friction at ``qd`` too), and
the robust terms' rho, rho_i, P cover its uncertainty with the rigid coefficients'.

As a plant's rigid body it is the rigid body **with its armature** (:meth:`forward_dynamics`:
``(M + diag(ia)) qdd = u - C qd - g``); the plant's friction is the :class:`~rc3r.plants.Friction` effect with
the same coefficients (:func:`rc3r.plants.actuated.actuated_plant`), so the engines' stiff-friction integration
sees it. Its compiled kernels wrap the inner robot's (:mod:`.actuated_supply`, one copy per inner supply
written by :func:`supply_module`), its C regressor the inner one plus the joint columns (:mod:`.actuated_c`, which
:func:`rc3r.export.c.regressor_source` calls).
"""
from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from .. import _numba_cache
from ..errors import ConfigError, ParameterError
from ..identify.regressors import JOINT_KINDS, friction_names, joint_columns, parse_friction
from .base import Robot

__all__ = ["ActuatedRobot", "supply_module", "parse_kinds", "SUPPLY"]

#: The template supply and the inner supply its ``# inner supply`` line names as it stands.
SUPPLY = "rc3r.robots.actuated_supply"
_TEMPLATE_INNER = "rc3r.robots.pinocchio_supply"
#: The tangents section's stubs: from the first line to the second, replaced in a copy by the inner ones.
_STUBS = ("# inner tangents: stubs", "# end of the inner tangents")
_TANGENTS_MARK = "\n# ---- tangents (kept only"
_MODULES: dict = {}


def parse_kinds(kinds) -> tuple[str, ...]:
    """``"viscous,coulomb"`` or a sequence -> the kinds in :data:`JOINT_KINDS` order; ConfigError naming an
    unknown one."""
    return parse_friction(kinds, JOINT_KINDS, "joint coefficient kind")


class ActuatedRobot(Robot):
    """``robot`` with per-joint friction and armature coefficients (module docstring).

    Parameters
    ----------
    robot : Robot
        The rigid body (its theta: the first ``robot.p`` coefficients).
    kinds : sequence of str or str
        Joint coefficient kinds (:data:`~rc3r.identify.regressors.JOINT_KINDS`), stored in that order.
    coulomb_velocity : float
        Smoothing velocity v_s [rad/s] of the Coulomb column ``tanh(qd / v_s)`` (0: ``sign``; refused by
        :meth:`physical_issues`, a plant's Coulomb friction needs v_s > 0).
    joint : array_like, optional
        The joint coefficients, (n len(kinds),) in :func:`~rc3r.identify.regressors.friction_names` order
        (default zeros).
    label : str, optional
        Default: the rigid body's label.
    """

    def __init__(self, robot: Robot, kinds, coulomb_velocity: float = 0.0, joint=None, label: str | None = None):
        if isinstance(robot, ActuatedRobot):
            raise ParameterError("an ActuatedRobot wraps a rigid body, not another ActuatedRobot")
        self.rigid = robot
        self.kinds = parse_kinds(kinds)
        if not self.kinds:
            raise ConfigError("an actuated robot needs at least one joint coefficient kind")
        self.coulomb_velocity = float(coulomb_velocity)
        if not np.isfinite(self.coulomb_velocity) or self.coulomb_velocity < 0:
            raise ConfigError(f"Coulomb smoothing velocity must be finite and >= 0, got {coulomb_velocity}")
        m = robot.n * len(self.kinds)
        joint = np.zeros(m) if joint is None else np.asarray(joint, dtype=float).ravel()
        if joint.shape != (m,) or not np.all(np.isfinite(joint)):
            raise ParameterError(f"joint coefficients must be {m} finite numbers ({', '.join(self.kinds)} for "
                                 f"{robot.n} joints), got shape {joint.shape}")
        self.joint = joint
        self._label = robot.label if label is None else str(label)
        self.name = robot.name
        self._model_cache = None

    # ---- the joint coefficients by kind ------------------------------------------------
    def coefficients(self, kind: str) -> np.ndarray:
        """The (n,) coefficients of ``kind`` (zeros if it is not one of :attr:`kinds`)."""
        n = self.n
        if kind not in JOINT_KINDS:
            raise ConfigError(f"unknown joint coefficient kind {kind!r}")
        if kind not in self.kinds:
            return np.zeros(n)
        k = self.kinds.index(kind)
        return self.joint[k * n:(k + 1) * n].copy()

    @property
    def armature(self) -> np.ndarray:
        """ia (n,) [kg m^2] (zeros without the ``armature`` kind)."""
        return self.coefficients("armature")

    def with_joint(self, joint, label: str | None = None) -> "ActuatedRobot":
        """The same rigid body with other joint coefficients."""
        return ActuatedRobot(self.rigid, self.kinds, self.coulomb_velocity, joint, self.label if label is None
                             else label)

    def with_rigid(self, rigid: Robot, label: str | None = None) -> "ActuatedRobot":
        """Another rigid body (same n) with these joint coefficients."""
        return ActuatedRobot(rigid, self.kinds, self.coulomb_velocity, self.joint,
                             rigid.label if label is None else label)

    def joint_friction(self, qd) -> np.ndarray:
        """``fv qd + fc tanh(qd / v_s) + f0`` (n,) or (N, n) [N m]: the model's friction torque (the joints'
        resistance; a plant's :class:`~rc3r.plants.Friction` applies its negative)."""
        qd = np.asarray(qd, dtype=float)
        J = joint_columns(qd, np.zeros_like(qd), self.kinds, self.coulomb_velocity)
        ia = self.kinds.index("armature") * self.n if "armature" in self.kinds else None
        jt = self.joint.copy()
        if ia is not None:
            jt[ia:ia + self.n] = 0.0
        out = J @ jt
        return out[0] if qd.ndim == 1 else out

    def as_plant(self, effects=(), label: str | None = None):
        """The plant of this parameter set: this rigid body (with its armature) and a
        :class:`~rc3r.plants.Friction` effect with its viscous, Coulomb and offset coefficients (v_s =
        :attr:`coulomb_velocity`; none if they are all zero), then ``effects``."""
        from ..plants import Friction, Plant

        fv, fc, f0 = (self.coefficients(k) for k in ("viscous", "coulomb", "offset"))
        fr = []
        if np.any(fv) or np.any(fc) or np.any(f0):
            vs = self.coulomb_velocity if self.coulomb_velocity > 0 else 0.01  # unused without Coulomb friction
            fr = [Friction(fv, fc, f0, v_s=vs, source="model")]
        return Plant(self, fr + list(effects), label=label)

    # ---- the contract --------------------------------------------------------------------
    @property
    def n(self) -> int:
        return self.rigid.n

    @property
    def p(self) -> int:
        return self.rigid.p + self.joint.size

    @property
    def rigid_p(self) -> int:
        """Coefficients of the rigid body (the first ones of theta)."""
        return self.rigid.p

    @property
    def theta(self) -> np.ndarray:
        return np.concatenate([np.asarray(self.rigid.theta, dtype=float), self.joint])

    @property
    def coefficient_names(self) -> tuple[str, ...]:
        return tuple(self.rigid.coefficient_names) + friction_names(self.kinds, self.n)

    @property
    def label(self) -> str:
        return self._label

    @property
    def joint_limits(self):
        return self.rigid.joint_limits

    @property
    def model(self):
        """The rigid body's ``pinocchio.Model`` (a copy) with ``armature`` = ia (friction is not Pinocchio's)."""
        if self._model_cache is None:
            m = self.rigid.model.copy()
            m.armature = self.armature
            self._model_cache = m
        return self._model_cache

    def regressor(self, q, qd, v, a) -> np.ndarray:
        """``[Y_r(q, qd, v, a) | joint_columns(qd, a)]``, (n, p) or (N, n, p)."""
        Y = np.asarray(self.rigid.regressor(q, qd, v, a), dtype=float)
        J = joint_columns(qd, a, self.kinds, self.coulomb_velocity)
        if Y.ndim == 2:
            return np.concatenate([Y, J[0]], axis=1)
        return np.concatenate([Y, np.broadcast_to(J, Y.shape[:2] + J.shape[2:])], axis=2)

    def mass_matrix(self, q) -> np.ndarray:
        """``M(q) + diag(ia)``, (n, n) or (N, n, n)."""
        return np.asarray(self.rigid.mass_matrix(q), dtype=float) + np.diag(self.armature)

    def coriolis_matrix(self, q, qd) -> np.ndarray:
        return self.rigid.coriolis_matrix(q, qd)

    def gravity(self, q) -> np.ndarray:
        return self.rigid.gravity(q)

    def forward_dynamics(self, q, qd, u) -> np.ndarray:
        """The rigid body with its armature: ``(M + diag(ia))^-1 (u - C qd - g)`` (no friction: a plant's
        friction is its Friction effect), (n,) or (N, n)."""
        ia = self.armature
        if not np.any(ia):
            return self.rigid.forward_dynamics(q, qd, u)
        q, qd, u = (np.asarray(x, dtype=float) for x in (q, qd, u))
        h = np.asarray(self.rigid.regressor(q, qd, qd, np.zeros_like(qd)), dtype=float) @ np.asarray(
            self.rigid.theta, dtype=float)
        return np.linalg.solve(self.mass_matrix(q), (u - h)[..., None])[..., 0]

    # ---- parameter sets: the rigid body's standard parameters, then the joint coefficients ----
    @property
    def standard_parameter_names(self) -> tuple[str, ...]:
        return tuple(self.rigid.standard_parameter_names) + friction_names(self.kinds, self.n)

    def standard_parameters(self) -> np.ndarray:
        return np.concatenate([np.asarray(self.rigid.standard_parameters(), dtype=float), self.joint])

    def _split(self, std):
        std = np.asarray(std, dtype=float)
        s = std.shape[-1] - self.joint.size
        return std[..., :s], std[..., s:]

    def theta_of_standard(self, std) -> np.ndarray:
        """theta of standard-parameter vectors (..., S + n m): the rigid body's map, the joint part unchanged."""
        rs, js = self._split(std)
        return np.concatenate([np.asarray(self.rigid.theta_of_standard(rs), dtype=float), js], axis=-1)

    def with_standard_parameters(self, std, label: str) -> "ActuatedRobot":
        rs, js = self._split(std)
        return ActuatedRobot(self.rigid.with_standard_parameters(rs, label), self.kinds, self.coulomb_velocity,
                             js, label)

    @property
    def linear_in_standard_parameters(self) -> bool:
        return self.rigid.linear_in_standard_parameters

    def physical_issues(self) -> list[str]:
        """The rigid body's, then negative viscous, Coulomb or armature coefficients and a Coulomb column
        without smoothing velocity (v_s <= 0)."""
        out = list(self.rigid.physical_issues())
        units = {"viscous": "N m s/rad", "coulomb": "N m", "armature": "kg m^2"}
        for kind, unit in units.items():
            c = self.coefficients(kind)
            bad = [f"{JOINT_KINDS[kind]}{j + 1} = {c[j]:.4g}" for j in np.flatnonzero(c < 0)]
            if bad:
                out.append(f"negative {kind} coefficient(s) {', '.join(bad)} [{unit}]")
        if "coulomb" in self.kinds and self.coulomb_velocity <= 0:
            out.append("Coulomb friction needs a smoothing velocity v_s > 0 (tanh(qd / v_s)); got "
                       f"{self.coulomb_velocity:g}")
        return out

    # ---- optional capabilities -----------------------------------------------------------------
    @property
    def compiled_kernels(self):
        """``(module, kc)``: :mod:`.actuated_supply` over the rigid body's supply (None if it has none)."""
        inner = self.rigid.compiled_kernels
        if inner is None:
            return None
        module, kc = inner
        return supply_module(module), self.pack(kc)

    def pack(self, inner_kc) -> np.ndarray:
        """``kc`` of :mod:`.actuated_supply` on the inner constants ``inner_kc``."""
        inner_kc = np.asarray(inner_kc, dtype=float)
        slots = [float(self.kinds.index(k)) if k in self.kinds else -1.0 for k in JOINT_KINDS]
        plant = np.concatenate([self.coefficients(k) for k in JOINT_KINDS])
        return np.concatenate([inner_kc, [self.n, self.rigid.p, self.coulomb_velocity], slots, plant,
                               [inner_kc.size]]).astype(np.float64)

    urdf = property(lambda self: self.rigid.urdf)
    locked = property(lambda self: self.rigid.locked)
    joint_names = property(lambda self: self.rigid.joint_names)
    robot_name = property(lambda self: self.rigid.robot_name)
    theta_order = property(lambda self: f"{self.rigid.theta_order}, then " + ", ".join(
        f"{k} ({JOINT_KINDS[k]}1..{JOINT_KINDS[k]}{self.n})" for k in self.kinds))

    @property
    def with_model(self):
        """``with_model(model, label)``: the rigid body on another model (a payload), same joint coefficients."""
        if self.rigid.with_model is None:
            return None
        return lambda model, label: self.with_rigid(self.rigid.with_model(model, label), label)

    def default_trajectory(self):
        return self.rigid.default_trajectory()

    def default_trajectory_warnings(self) -> list[str]:
        return self.rigid.default_trajectory_warnings()

    def describe(self) -> dict:
        """The rigid body's description with the joint kinds, v_s and coefficients."""
        return {**self.rigid.describe(), "label": self.label, "p": self.p, "joint_kinds": list(self.kinds),
                "coulomb_velocity": self.coulomb_velocity,
                "joint": dict(zip(friction_names(self.kinds, self.n), self.joint.tolist()))}

    def __getstate__(self):
        return {**self.__dict__, "_model_cache": None}

    def __repr__(self) -> str:
        return (f"<ActuatedRobot {self.rigid!r} + {','.join(self.kinds)} v_s={self.coulomb_velocity:g} "
                f"label={self.label!r}>")


# ---- the supply copies -------------------------------------------------------------------------------------

def _roots():
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        yield Path(env) / "rc3r_supplies"
        return
    yield Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rc3r" / "supplies"
    yield Path(tempfile.gettempdir()) / f"rc3r-supplies-{os.getuid() if os.name == 'posix' else 0}"


def _write_once(path: Path, text: str) -> None:
    """``path`` holds ``text`` (never rewritten if it does: numba stamps its cache with the file's time)."""
    try:
        if path.read_text() == text:
            return
    except (OSError, UnicodeDecodeError):
        pass
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    tmp.write_text(text)
    try:
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def supply_module(inner: str) -> str:
    """The dotted name of :mod:`.actuated_supply`'s copy over the inner supply ``inner``, imported in this process.

    The copy has its ``# inner supply`` line naming ``inner`` and, if ``inner`` has ``tangents_into`` and
    ``plant_tangents_into``, imports them in place of the template's stubs (else the tangents section is dropped:
    no analytic derivatives). It is written once under ``$NUMBA_CACHE_DIR/rc3r_supplies`` (else the user's
    cache) in a directory keyed by the text and :func:`rc3r._numba_cache.package_hash`, and imported under a
    name of that key (the compiled engine imports it by name: it is registered in ``sys.modules`` here first)."""
    if inner in _MODULES:
        return _MODULES[inner]
    try:
        mod = importlib.import_module(inner)
    except ImportError as exc:
        raise ParameterError(f"kernel supply {inner!r} cannot be imported: {exc}") from None
    template = (Path(__file__).resolve().parent / "actuated_supply.py").read_text()
    head, mark, tail = template.partition(_TANGENTS_MARK)
    stubs_a, stubs_b = tail.find(_STUBS[0]), tail.find(_STUBS[1])
    if not mark or template.count(f"from {_TEMPLATE_INNER} import") != 1 or stubs_a < 0 or stubs_b < stubs_a:
        raise RuntimeError("rc3r.robots.actuated_supply lost its inner-supply lines")
    if all(hasattr(mod, f) for f in ("tangents_into", "plant_tangents_into")):
        source = (head + mark + tail[:stubs_a] + f"from {inner} import plant_tangents_into as _i_ptangents, "
                  "tangents_into as _i_tangents  # noqa: E402 inner supply (tangents)\n" + tail[stubs_b:])
    else:
        source = head
    source = source.replace(f"from {_TEMPLATE_INNER} import", f"from {inner} import")
    h = hashlib.sha256(f"{_numba_cache.package_hash()}\0{inner}\0".encode() + source.encode())
    file_ = getattr(mod, "__file__", None)
    if file_ and not _numba_cache._inside(file_):
        h.update(Path(file_).read_bytes())
    key = h.hexdigest()[:16]
    name = f"_rc3r_actuated_{inner.replace('.', '_')}_{key}"
    if name not in sys.modules:
        errors = []
        for root in _roots():
            path = root / key / f"{name}.py"
            try:
                _write_once(path, source)
                break
            except OSError as exc:
                errors.append(f"{root}: {exc.strerror or exc}")
        else:
            raise ParameterError("cannot write the actuated kernel supply: " + "; ".join(errors))
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    _MODULES[inner] = name
    return name
