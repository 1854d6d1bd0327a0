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

A Python effect runs in the ``python`` engine (``engine = "auto"`` picks it). A
**compiled** effect (``compiled = True``: friction, saturation, Stribeck friction) is one
module that also holds, beside its class, what the compiled engines need
(docs/architecture.md, "Adding a compiled plant effect"):

* ``code`` (an int, unique) and ``role`` (``"torque"``: it adds ``tau_j(qd_j)`` at joint j;
  ``"actuator"``: it maps the command ``u_j`` to the delivered torque);
* ``LAYOUT``, a :class:`Layout` of its packed parameters named by its fields (:meth:`Plant.pack`
  writes the block, the kernels read it by the layout's slots);
* ``value_kernel(fx, o, n, j, x)``: njit, the torque at joint j (``x = qd_j``) or the delivered
  torque (``x = u_j``) from the block at ``fx[o:]``;
* ``slope_kernel(fx, o, n, j, x)``: njit, its derivative for the analytic Jacobian and the implicit
  periods: ``-d tau_j / d qd_j`` (a torque) or ``d u_a,j / d u_j`` (an actuator).

The compiled engines' dispatch over the registered codes is generated from :data:`EFFECTS`
when an engine is instantiated (:mod:`rc3r.simulate.engines._effects`). Every effect also
declares how a configuration reaches it: ``config_keys`` (the ``[plant]`` keys it reads, its
``[plant.<name>]`` table first), :meth:`Effect.from_config`, and ``cli`` (its command-line
:class:`Option`); ``stiff`` says whether it adds a state-dependent force (shorter explicit
steps, :mod:`rc3r.simulate.steps`).

Monitors (``monitor = True``, e.g. :class:`~rc3r.plants.limits.JointLimits`) do not act
on the dynamics; they are read from the result (a verdict ``limit-violated``).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError

__all__ = ["Effect", "Plant", "EFFECTS", "register_effect", "as_plant", "per_joint", "Layout", "Option",
           "JOINT", "SCALAR", "nonnegative_numbers", "pair"]


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


def pair(text, what: str):
    """Two numbers from ``"A:B"`` or ``[A, B]``; ConfigError naming ``what``."""
    if isinstance(text, str):
        parts = text.split(":")
        try:
            vals = [float(x) for x in parts]
        except ValueError:
            raise ConfigError(f"{what} must be A:B (two numbers), got {text!r}") from None
        if len(vals) != 2:
            raise ConfigError(f"{what} must be A:B (two numbers), got {text!r}")
        return vals
    if isinstance(text, (list, tuple)) and len(text) == 2:
        return list(text)
    raise ConfigError(f"{what} must be A:B or [A, B], got {text!r}")


def nonnegative_numbers(text: str, form: str, count: int = 2) -> str:
    """``A:B[:...]`` (``count`` finite numbers >= 0) normalised to ``repr(A):repr(B)...``; ValueError naming
    ``form`` (the command line's spelling) otherwise. The parse of an effect's :class:`Option`."""
    try:
        vals = [float(x) for x in text.split(":")]
    except ValueError:
        raise ValueError(f"expected {form}, got {text!r}") from None
    if len(vals) != count:
        raise ValueError(f"expected {form}, got {text!r}")
    if not all(math.isfinite(v) and v >= 0 for v in vals):
        raise ValueError(f"expected finite {form.split(' or ')[-1]} >= 0, got {text!r}")
    return ":".join(repr(v) for v in vals)


#: A :class:`Layout` field of n numbers (one per joint) and one of a single number.
JOINT, SCALAR = "joint", "scalar"


class Layout:
    """Named offsets of a compiled effect's packed parameters, written once from its fields.

    ``Layout(viscous=JOINT, v_s=SCALAR)``: the block is the fields in this order, a ``JOINT`` field n
    numbers, a ``SCALAR`` one 1. Field ``k`` of the block starting at ``o`` starts at
    ``o + a n + b`` with ``(a, b) = slots[k]`` (read in njit code by
    :func:`rc3r.plants._kernels.at`).

    Examples
    --------
    >>> L = Layout(viscous=JOINT, coulomb=JOINT, v_s=SCALAR, limit=JOINT)
    >>> L.slots, L.size(3)
    (((0, 0), (1, 0), (2, 0), (2, 1)), 10)
    """

    def __init__(self, **fields):
        a = b = 0
        slots = []
        for name, kind in fields.items():
            if kind not in (JOINT, SCALAR):
                raise TypeError(f"Layout field {name!r} must be JOINT or SCALAR, got {kind!r}")
            slots.append((a, b))
            a, b = (a + 1, b) if kind == JOINT else (a, b + 1)
        self.fields = tuple(fields.items())
        #: ``(a, b)`` per field, in order: the field starts at ``o + a n + b``.
        self.slots = tuple(slots)
        self._ab = (a, b)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(k for k, _ in self.fields)

    def size(self, n: int) -> int:
        """Length of the block for n joints."""
        return self._ab[0] * n + self._ab[1]

    def pack(self, effect, n: int) -> np.ndarray:
        """The block (:meth:`size`,) of ``effect``: its fields by name, a JOINT field broadcast to n."""
        out = []
        for name, kind in self.fields:
            x = np.asarray(getattr(effect, name), dtype=float)
            out.append(np.broadcast_to(x, (n,)) if kind == JOINT else np.reshape(x, (1,)))
        return np.concatenate(out) if out else np.zeros(0)

    def __repr__(self) -> str:
        return "Layout(" + ", ".join(f"{k}={v.upper()}" for k, v in self.fields) + ")"


class Option:
    """An effect's command-line option: ``flag`` (``--friction``) sets the ``[plant]`` key ``key`` to
    ``parse(text)`` (which raises ValueError with a one-line message on bad text); ``metavar``, ``help``
    as argparse's. Read by :func:`rc3r.cli.plant_args` and :func:`rc3r.cli.run.plant_options`."""

    def __init__(self, flag: str, key: str, parse, metavar: str, help: str):
        self.flag, self.key, self.parse, self.metavar, self.help = flag, key, parse, metavar, help

    @property
    def dest(self) -> str:
        return self.flag.lstrip("-").replace("-", "_")

    def __repr__(self) -> str:
        return f"Option({self.flag!r} -> [plant] {self.key})"


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
    stiff : bool
        True if it adds a state-dependent force to the rigid body (explicit steps get shorter:
        :func:`rc3r.simulate.default_substeps`); False for actuator maps and monitors.
    config_keys : tuple of str
        The ``[plant]`` keys it is built from (:meth:`from_config`), ``name`` (its ``[plant.<name>]``
        table) first where it has one; later ones are older spellings that keep working.
    cli : tuple of Option
        Its command-line options (each sets one of ``config_keys``).
    code, role, LAYOUT, value_kernel, slope_kernel
        A compiled effect's (module docstring); None otherwise.
    """

    name = "?"
    compiled = False
    monitor = False
    #: Joints the effect is sized for, or None (any number of joints).
    n = None
    #: Where its values came from (``config``, ``urdf``, ``drawn``).
    source = "config"
    stiff = True
    config_keys: tuple = ()
    cli: tuple = ()
    code: int | None = None
    role: str | None = None
    LAYOUT: Layout | None = None
    value_kernel = None
    slope_kernel = None

    @classmethod
    def from_config(cls, robot, key: str, value, rng=None):
        """The effect for ``robot`` from the ``[plant]`` key ``key`` (one of :attr:`config_keys`) holding
        ``value`` (a string, numbers or a table), or None for none; ``rng`` draws uncertain ranges.
        ConfigError on a bad value."""
        raise ConfigError(f"plant effect {cls.name!r} cannot be configured")

    @classmethod
    def default_config(cls, robot):
        """The value of :attr:`config_keys`' first key when a run gives none (None: the effect is off)."""
        return None

    def active(self) -> bool:
        """False if the effect is compiled but leaves the dynamics as they are (zero friction): then
        :meth:`Plant.pack` leaves it out, so the engine skips its arithmetic."""
        return True

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
    if cls.compiled:
        _check_compiled(cls)
    taken = {k: o.name for o in EFFECTS.values() if o.name != cls.name for k in o.config_keys}
    clash = sorted(k for k in cls.config_keys if k in taken)
    if clash:
        raise TypeError(f"effect {cls.name!r}: [plant] key(s) {', '.join(clash)} already read by "
                        f"{', '.join(sorted({taken[k] for k in clash}))}")
    EFFECTS[cls.name] = cls
    return cls


def _check_compiled(cls) -> None:
    """A compiled effect declares a unique positive code, a role, a LAYOUT of its own fields and both kernels."""
    where = f"compiled effect {cls.name!r}"
    if not isinstance(cls.code, int) or isinstance(cls.code, bool) or cls.code <= 0:
        raise TypeError(f"{where} needs an int code > 0, got {cls.code!r}")
    other = next((o.name for o in EFFECTS.values() if o.compiled and o.code == cls.code and o.name != cls.name), None)
    if other:
        raise TypeError(f"{where}: code {cls.code} is {other!r}'s")
    if cls.role not in ("torque", "actuator"):
        raise TypeError(f"{where}: role must be 'torque' or 'actuator', got {cls.role!r}")
    if not isinstance(cls.LAYOUT, Layout):
        raise TypeError(f"{where} needs a LAYOUT (rc3r.plants.base.Layout)")
    fields = getattr(cls, "__dataclass_fields__", {})
    bad = [k for k in cls.LAYOUT.names if k not in fields]
    if bad:
        raise TypeError(f"{where}: LAYOUT names {', '.join(bad)}, not fields of the class")
    for kind in ("value_kernel", "slope_kernel"):
        if getattr(getattr(cls, kind, None), "py_func", None) is None:
            raise TypeError(f"{where}: {kind} must be a numba.njit function")


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

    def packed(self) -> tuple:
        """The effects :meth:`pack` writes, in order: the compiled, :meth:`~Effect.active` non-monitors."""
        return tuple(e for e in self.effects if e.compiled and not e.monitor and e.active())

    def pack(self) -> np.ndarray:
        """The compiled engines' effects ``fx``: ``[m, code_1, o_1, ..., code_m, o_m, block_1, ..., block_m]``.

        ``m`` effects (:meth:`packed`), each by its registered ``code`` and the offset ``o`` of its block
        (its ``LAYOUT``'s fields) in ``fx``. A rigid plant is ``[0]``: the engine's arithmetic is the
        rigid body's alone. Applied by the dispatch generated from :data:`EFFECTS`
        (:mod:`rc3r.simulate.engines._effects`): actuator maps in order, then the joint torques summed.
        """
        n = self.n
        effects = self.packed()
        head = np.zeros(1 + 2 * len(effects))
        head[0] = len(effects)
        blocks, o = [], head.size
        for k, e in enumerate(effects):
            block = e.LAYOUT.pack(e, n)
            head[1 + 2 * k], head[2 + 2 * k] = e.code, o
            blocks.append(block)
            o += block.size
        return np.concatenate([head] + blocks)

    def describe(self) -> dict:
        """JSON-ready: the rigid body (``Robot.describe``) and each effect."""
        return {**self.rigid.describe(), "effects": [e.describe() for e in self.effects]}

    def __repr__(self) -> str:
        names = ", ".join(e.name for e in self.effects) or "rigid"
        return f"<Plant {self.label!r} n={self.n} ({names})>"


def as_plant(x) -> Plant:
    """A :class:`Plant` as is; a bare robot as the rigid plant with no effects."""
    return x if isinstance(x, Plant) else Plant(x)
