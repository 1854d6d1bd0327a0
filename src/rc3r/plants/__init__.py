"""Plants: the true system under a controller (:mod:`.base`), its effects, and the loop between.

* :class:`Plant` -- a rigid body (:class:`RigidBody`, :mod:`.rigid`: a
  :class:`~rc3r.robots.base.Robot` or MuJoCo's) and effects;
* :class:`Friction` (:mod:`.friction`), :class:`Saturation` (:mod:`.saturation`),
  :class:`Stribeck` (:mod:`.stribeck`), :class:`JointLimits` (:mod:`.limits`, a monitor) -- the
  registered effects (:data:`EFFECTS`), each one module from its class to its compiled kernels;
* :class:`LoopEffects` (:mod:`.loop`) -- noise, quantization, delay, initial error of a
  sampled controller;
* :class:`~rc3r.plants.mujoco.MujocoRigidBody` -- MuJoCo as the rigid body (optional extra).

:func:`resolve` turns the command line's and a ``[plant]`` table's options into effects
(``docs/control.md``, "Plants"): every registered effect reads its own keys
(:attr:`Effect.config_keys`, ``[plant.<name>]``) and declares its command-line option
(:attr:`Effect.cli`), so :data:`EFFECTS` drives both.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import ConfigError
from .base import EFFECTS, Effect, Layout, Option, Plant, as_plant, pair as _pair, register_effect
# the built-in effects register in this order (EFFECTS' order; a plant applies them by code, :func:`registered`)
from .friction import Friction
from .saturation import Saturation
from .limits import JointLimits, crossings  # noqa: I001 - registration order, not the alphabet
from .stribeck import Stribeck
from .loop import LoopEffects
from .rigid import RigidBody

__all__ = ["Plant", "RigidBody", "Effect", "EFFECTS", "register_effect", "as_plant", "Friction", "Saturation",
           "JointLimits", "Stribeck", "crossings", "LoopEffects", "build_effects", "build_loop", "resolve",
           "PLANT_KEYS", "PLANT_ENGINES", "LOOP_KEYS", "Layout", "Option", "registered", "effect_keys"]

#: Rigid-body engines of a plant (``--plant-engine``).
PLANT_ENGINES = ("pinocchio", "mujoco")

#: Keys of a ``[plant]`` table that describe the sampled loop and the rigid body's engine.
LOOP_KEYS = ("noise", "quantization", "delay", "q0_error", "qd0_error", "noise_seed", "engine")


def registered() -> tuple:
    """The registered effect classes in the order a plant applies them: compiled effects by code, then
    the other acting effects, then the monitors."""
    return tuple(sorted(EFFECTS.values(), key=lambda c: (c.monitor, c.code is None, c.code or 0)))


def effect_keys() -> tuple[str, ...]:
    """The ``[plant]`` keys of every registered effect (:attr:`Effect.config_keys`), in :func:`registered` order."""
    return tuple(k for c in registered() for k in c.config_keys)


class _Keys(Sequence):
    """A tuple of ``[plant]`` keys that reads :data:`EFFECTS` each time (an effect registered later is
    a valid key at once): ``head``, the effects' keys, :data:`LOOP_KEYS`. ``tuple + _Keys`` is one too."""

    def __init__(self, head=()):
        self._head = tuple(head)

    def _all(self) -> tuple:
        return self._head + effect_keys() + LOOP_KEYS

    def __getitem__(self, i):
        return self._all()[i]

    def __len__(self) -> int:
        return len(self._all())

    def __contains__(self, key) -> bool:
        return key in self._all()

    def __radd__(self, other):
        return _Keys(tuple(other) + self._head)

    def __eq__(self, other):
        return tuple(self) == tuple(other) if isinstance(other, Sequence) else NotImplemented

    __hash__ = None

    def __repr__(self) -> str:
        return repr(self._all())


#: Keys of a ``[plant]`` configuration table that describe effects (besides spec, urdf, box): every
#: registered effect's :attr:`~Effect.config_keys`, then :data:`LOOP_KEYS`. Live: read from :data:`EFFECTS`.
PLANT_KEYS = _Keys()


def build_effects(robot, friction=None, torque_limit=None, limits=None, rng=None, **options) -> list[Effect]:
    """The plant effects of ``robot`` (the rigid body, n joints) from ``[plant]`` options.

    Every registered effect (:data:`EFFECTS`) reads its own keys (:attr:`Effect.config_keys`,
    :meth:`Effect.from_config`); ``options`` holds the keys of effects beyond the three named here.

    Parameters
    ----------
    friction : None, "urdf", "VISCOUS:COULOMB", [viscous, coulomb] or a table
        ``{"viscous": x, "coulomb": ..., "offset": ..., "v_s": ...}`` where x is one number, n
        numbers, or an uncertain range ``{lo = ..., hi = ...}`` drawn per joint with ``rng`` (a
        campaign's per-plant generator; seed 0 if None).
    torque_limit : None, "urdf", a number [N m] or n numbers
    limits : None, "urdf" or False
        Joint position and velocity limits reported when crossed (default "urdf" when the
        robot's model has any).
    **options
        Other effects' keys (``saturation = {limit = ...}``, ``stribeck = {...}``, ...).
    """
    given = dict(options, friction=friction, torque_limit=torque_limit, limits=limits)
    known = effect_keys()
    unknown = sorted(k for k in given if k not in known)
    if unknown:
        raise ConfigError(f"[plant]: unknown effect key(s) {', '.join(unknown)} (valid: {', '.join(known)})")
    effects: list[Effect] = []
    for cls in registered():
        vals = [(k, given[k]) for k in cls.config_keys if given.get(k) is not None and given.get(k) is not False]
        if len(vals) > 1:
            raise ConfigError(f"[plant]: {' and '.join(k for k, _ in vals)} both give the {cls.name} effect; "
                              "give one")
        if vals:
            e = cls.from_config(robot, vals[0][0], vals[0][1], rng=rng)
            if e is not None:
                effects.append(e)
    return effects


def build_loop(n: int, noise=None, quantization=None, delay=None, q0_error=None, qd0_error=None,
               seed: int = 0) -> LoopEffects | None:
    """The loop effects from options (``noise`` "SIGMA_Q:SIGMA_QD" or a pair), or None if none is given."""
    if all(x is None for x in (noise, quantization, delay, q0_error, qd0_error)):
        return None
    sq, sqd = _pair(noise, "noise") if noise is not None else (0.0, 0.0)
    return LoopEffects(n, noise_q=sq, noise_qd=sqd, quantization=0.0 if quantization is None else quantization,
                       delay=0 if delay is None else delay, q0_error=0.0 if q0_error is None else q0_error,
                       qd0_error=0.0 if qd0_error is None else qd0_error, seed=seed)


def _mujoco_rigid(robot):
    """MuJoCo's rigid body of ``robot``: its URDF (or, for a robot that ships one, the physically
    consistent arm with the same theta: ``robot.mujoco_urdf()``). Refused for a plant whose
    parameters are not its URDF's own (a drawn or payload plant): MuJoCo reads them from the file."""
    from .mujoco import MujocoRigidBody

    if robot.mujoco_urdf is not None:
        path = robot.mujoco_urdf()
        if path is None:
            raise ConfigError(f"--plant-engine mujoco simulates a URDF's own parameters; plant '{robot.label}' "
                              "is not the nominal arm")
        return MujocoRigidBody.from_urdf(path, g0=float(-robot.model.gravity.linear[2]))
    urdf = robot.urdf
    if urdf is None:
        raise ConfigError(f"--plant-engine mujoco needs a URDF; plant '{robot.label}' has none")
    locked = dict(robot.locked or {})
    reread = type(robot).from_urdf(urdf, lock=locked or None)
    if not np.allclose(reread.standard_parameters(), robot.standard_parameters(), rtol=1e-12, atol=1e-12):
        raise ConfigError(f"--plant-engine mujoco simulates the URDF's own parameters; plant '{robot.label}' "
                          "differs from them (a drawn or payload plant): use --plant-engine pinocchio")
    return MujocoRigidBody.from_urdf(urdf, locked=locked or None, g0=float(-robot.model.gravity.linear[2]),
                                     joint_names=robot.joint_names)


def resolve(robot, table: dict | None = None, *, rate=None, seed: int = 0, rng=None, **options):
    """The plant of a run and its loop: ``(Plant, LoopEffects or None, plant engine)``.

    ``table`` is a configuration's ``[plant]`` table (keys :data:`PLANT_KEYS`); ``options`` the
    command line's (``friction``, ``torque_limit``, ``noise``, ``delay``, ``quantization``,
    ``plant_engine``), which win where given. ``robot`` is the true rigid body (Pinocchio or the
    closed form); ``rng`` draws uncertain friction ranges (a campaign's per-plant generator);
    ``seed`` seeds the sensor noise unless ``noise_seed`` is given.
    """
    cfg = {k: v for k, v in (table or {}).items() if k in PLANT_KEYS}
    cfg.update({k: v for k, v in options.items() if v is not None})
    engine = cfg.pop("plant_engine", cfg.pop("engine", "pinocchio"))
    if engine not in PLANT_ENGINES:
        raise ConfigError(f"plant engine must be one of {', '.join(PLANT_ENGINES)}, got {engine!r}")
    for cls in registered():  # an effect on by default (the URDF's limits) unless a key of it is given
        if cls.config_keys and not any(k in cfg for k in cls.config_keys):
            default = cls.default_config(robot)
            if default is not None:
                cfg[cls.config_keys[0]] = default
    keys = effect_keys()
    effects = build_effects(robot, rng=rng, **{k: v for k, v in cfg.items() if k in keys})
    loop = build_loop(robot.n, noise=cfg.get("noise"), quantization=cfg.get("quantization"), delay=cfg.get("delay"),
                      q0_error=cfg.get("q0_error"), qd0_error=cfg.get("qd0_error"),
                      seed=int(cfg.get("noise_seed", seed)))
    rigid = _mujoco_rigid(robot) if engine == "mujoco" else robot
    return Plant(rigid, effects, label=robot.label), loop, engine
