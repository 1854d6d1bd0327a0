r"""The plant contract: the true system a controller is simulated against.

A :class:`Plant` is a **rigid body** (a :class:`~rc3r.robots.base.Robot`, whose
``forward_dynamics`` is the closed form or Pinocchio's ABA; MuJoCo in
:mod:`rc3r.plants.mujoco`) and a tuple of **effects** acting on it. With the commanded
torque :math:`u` the plant's joints move by

.. math::

    M(q)\,\ddot q + C(q, \dot q)\,\dot q + g(q) = \tau, \qquad
    \tau = \sum_k \tau_k(q, \dot q) + a(u),

where :math:`a = a_m \circ \dots \circ a_1` are the effects' actuator maps (saturation
clips :math:`u`) and :math:`\tau_k` their joint torques (friction
:math:`-F_v \dot q - F_c \tanh(\dot q / v_s) - \tau_{off}`). The controller never sees
the plant: it has its own model (a :class:`~rc3r.robots.base.Robot` of the same
kinematics) and the measured state.

**To add an effect** (one file and one registration, like a control law)::

    @register_effect
    @dataclass(frozen=True)
    class Backlash(Effect):
        name = "backlash"
        width: float = 0.01
        def joint_torque(self, q, qd): ...        # (n,) [N m], added at the joints
        def actuator(self, u, q, qd): ...         # (n,) the torque delivered for the command u
        def describe(self): ...                  # JSON-ready

A Python effect runs in the ``python`` engine (``engine = "auto"`` picks it). The
built-in effects (friction, saturation) are also **fields of the compiled engines'
model** (:meth:`Plant.pack`, applied by :func:`rc3r.plants._kernels.apply_effects`),
not code paths: an effect with ``compiled = True`` must say how it packs.

Monitors (``monitor = True``, e.g. :class:`~rc3r.plants.limits.JointLimits`) do not act
on the dynamics; they are read from the result (a verdict ``limit-violated``).
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError

__all__ = ["Effect", "Plant", "EFFECTS", "register_effect", "as_plant", "per_joint"]


def per_joint(name, x, n, signed=False) -> np.ndarray:
    """``x`` as n finite numbers (one number broadcast), ``>= 0`` unless ``signed``; ConfigError naming ``name``."""
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be numbers, got {x!r}") from None
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,) or not np.all(np.isfinite(arr)) or (not signed and np.any(arr < 0)):
        raise ConfigError(f"{name} must be {n} finite numbers{'' if signed else ' >= 0'} (or one), "
                          f"got {np.ravel(arr).tolist()}")
    return arr


class Effect:
    """Base of every plant effect (module docstring: what to implement).

    Attributes
    ----------
    name : str
        Registry name (``[plant.<name>]`` in a run configuration).
    compiled : bool
        True if the compiled engines apply it from :meth:`Plant.pack`.
    monitor : bool
        True if it does not act on the dynamics (read from the result).
    """

    name = "?"
    compiled = False
    monitor = False
    #: Joints the effect is sized for, or None (any number of joints).
    n = None
    #: Where its values came from (``config``, ``urdf``, ``drawn``).
    source = "config"

    def joint_torque(self, q, qd) -> np.ndarray | None:
        """Torque (n,) [N m] the effect adds at the joints, or None for none."""
        return None

    def actuator(self, u, q, qd) -> np.ndarray:
        """The torque (n,) delivered for the command ``u`` (identity by default)."""
        return u

    def damping(self) -> np.ndarray | None:
        """The largest slope ``-d joint_torque / d qd`` (n,) [N m s/rad] the effect can have, or None: what
        makes it stiff for an explicit integrator (:func:`rc3r.simulate.default_substeps`)."""
        return None

    def describe(self) -> dict:
        """JSON-ready description (``metrics.json``, campaign rows)."""
        return {"effect": self.name}


#: name -> effect class; :func:`register_effect` adds to it.
EFFECTS: dict[str, type[Effect]] = {}


def register_effect(cls: type[Effect]) -> type[Effect]:
    """Class decorator: make ``cls`` available by ``cls.name``."""
    if not (isinstance(cls, type) and issubclass(cls, Effect)) or cls.name in ("?", ""):
        raise TypeError("register_effect needs an Effect subclass with a name")
    EFFECTS[cls.name] = cls
    return cls


class Plant:
    """A rigid body and the effects acting on it.

    Parameters
    ----------
    rigid : rc3r.plants.RigidBody
        The rigid-body dynamics (its parameters are the true ones): a :class:`~rc3r.robots.base.Robot`
        or MuJoCo's rigid body (contract: :mod:`rc3r.plants.rigid`).
    effects : sequence of Effect
        Applied in order (actuator maps), their joint torques summed.
    label : str, optional
        Default ``rigid.label``.

    Attributes
    ----------
    n, p : int
        Joints and coefficients of the rigid body.

    Examples
    --------
    >>> import numpy as np, rc3r
    >>> from rc3r.plants import Plant, Friction, Saturation
    >>> arm = rc3r.load_robot()
    >>> plant = Plant(arm, [Friction(viscous=np.full(3, 2.0)), Saturation(limit=np.full(3, 50.0))])
    >>> q, qd = np.zeros(3), np.ones(3)
    >>> tau = plant.joint_torque(q, qd, np.full(3, 80.0))   # clipped to 50, minus 2 N m s/rad * 1 rad/s
    >>> tau.tolist()
    [48.0, 48.0, 48.0]
    """

    def __init__(self, rigid, effects=(), label: str | None = None):
        self.rigid = rigid
        self.effects = tuple(effects)
        for e in self.effects:
            if not isinstance(e, Effect):
                raise ConfigError(f"plant effects must be Effect objects, got {e!r}")
            if e.n is not None and e.n != rigid.n:
                raise ConfigError(f"plant effect {e.name!r} is sized for {e.n} joints, the robot has {rigid.n}")
        self._label = label
        names = [e.name for e in self.effects]
        dup = sorted({x for x in names if names.count(x) > 1})
        if dup:
            raise ConfigError(f"plant effect(s) given twice: {', '.join(dup)}")

    # ---- sizes and identity -------------------------------------------------------------
    @property
    def n(self) -> int:
        return self.rigid.n

    @property
    def p(self) -> int:
        return self.rigid.p

    @property
    def label(self) -> str:
        return self._label or self.rigid.label

    @property
    def theta(self) -> np.ndarray:
        """The rigid body's true coefficients (p,); None for a rigid body without them (MuJoCo)."""
        return self.rigid.theta

    def effect(self, name: str):
        """The effect called ``name``, or None."""
        return next((e for e in self.effects if e.name == name), None)

    @property
    def compiled(self) -> bool:
        """True if every effect is one the compiled engines apply (or a monitor)."""
        return all(e.compiled or e.monitor for e in self.effects)

    # ---- dynamics ------------------------------------------------------------------------
    def applied_torque(self, q, qd, u) -> np.ndarray:
        """The actuators' torque (n,) for the command ``u``: every actuator map in order."""
        out = np.asarray(u, dtype=float)
        for e in self.effects:
            out = e.actuator(out, q, qd)
        return out

    def joint_torque(self, q, qd, u) -> np.ndarray:
        r"""The total joint torque :math:`\tau` (n,) [N m] for the command ``u``."""
        return self.delivered_joint_torque(q, qd, self.applied_torque(q, qd, u))

    def delivered_joint_torque(self, q, qd, ua) -> np.ndarray:
        """The joint torque (n,) for the actuators' torque ``ua`` (already through the actuator maps)."""
        tau = np.array(ua, dtype=float)
        for e in self.effects:
            extra = e.joint_torque(q, qd)
            if extra is not None:
                tau = tau + extra
        return tau

    def forward_dynamics(self, q, qd, u, delivered: bool = False) -> np.ndarray:
        r""":math:`\ddot q` (n,) [rad/s^2] of the plant under the command ``u`` (n,) [N m]; with
        ``delivered=True`` ``u`` is the actuators' torque (the actuator maps are not applied again)."""
        tau = self.delivered_joint_torque(q, qd, u) if delivered else self.joint_torque(q, qd, u)
        return self.rigid.forward_dynamics(q, qd, tau)

    def pack(self) -> np.ndarray:
        """The compiled engines' effect fields ``[viscous (n), coulomb (n), offset (n), v_s, u_max (n)]``.

        Zero friction and an infinite torque limit when the effect is absent (so a rigid plant's
        arithmetic is unchanged: ``min(max(u, -inf), inf) - 0 = u``).
        """
        n = self.n
        fx = np.zeros(4 * n + 1)
        fx[3 * n] = 1.0
        fx[3 * n + 1:] = np.inf
        for e in self.effects:
            if e.compiled:
                e.pack_into(fx, n)
        return fx

    def describe(self) -> dict:
        """JSON-ready: the rigid body (``Robot.describe``) and each effect."""
        return {**self.rigid.describe(), "effects": [e.describe() for e in self.effects]}

    def __repr__(self) -> str:
        names = ", ".join(e.name for e in self.effects) or "rigid"
        return f"<Plant {self.label!r} n={self.n} ({names})>"


def as_plant(x) -> Plant:
    """A :class:`Plant` as is; a bare robot as the rigid plant with no effects."""
    return x if isinstance(x, Plant) else Plant(x)
