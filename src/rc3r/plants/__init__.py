"""Plants: the true system under a controller (:mod:`.base`), its effects, and the loop between.

* :class:`Plant` -- a rigid body (:class:`RigidBody`, :mod:`.rigid`: a
  :class:`~rc3r.robots.base.Robot` or MuJoCo's) and effects;
* :class:`Friction` (:mod:`.friction`), :class:`Saturation` (:mod:`.saturation`),
  :class:`JointLimits` (:mod:`.limits`, a monitor) -- the registered effects (:data:`EFFECTS`);
* :class:`LoopEffects` (:mod:`.loop`) -- noise, quantization, delay, initial error of a
  sampled controller;
* :class:`~rc3r.plants.mujoco.MujocoRigidBody` -- MuJoCo as the rigid body (optional extra).

:func:`plant_options` turns the command line's and a ``[plant]`` table's options into
effects (``docs/control.md``, "Plants").
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from .base import EFFECTS, Effect, Plant, as_plant, register_effect
from .friction import Friction
from .limits import JointLimits, crossings
from .loop import LoopEffects
from .rigid import RigidBody
from .saturation import Saturation

__all__ = ["Plant", "RigidBody", "Effect", "EFFECTS", "register_effect", "as_plant", "Friction", "Saturation",
           "JointLimits", "crossings", "LoopEffects", "build_effects", "build_loop", "resolve", "PLANT_KEYS",
           "PLANT_ENGINES"]

#: Rigid-body engines of a plant (``--plant-engine``).
PLANT_ENGINES = ("pinocchio", "mujoco")

#: Keys of a ``[plant]`` configuration table that describe effects (besides spec, urdf, box).
PLANT_KEYS = ("friction", "torque_limit", "limits", "noise", "quantization", "delay", "q0_error", "qd0_error",
              "noise_seed", "engine")


def _pair(text, what: str):
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


def build_effects(robot, friction=None, torque_limit=None, limits=None, rng=None) -> list[Effect]:
    """The plant effects of ``robot`` (the rigid body, n joints) from options.

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
    """
    effects: list[Effect] = []
    n = robot.n
    if friction is not None and friction is not False:
        if friction == "urdf":
            effects.append(Friction.from_model(robot))
        elif isinstance(friction, dict):
            unknown = sorted(set(friction) - {"viscous", "coulomb", "offset", "v_s"})
            if unknown:
                raise ConfigError(f"[plant.friction]: unknown key(s) {', '.join(unknown)} "
                                  "(valid: viscous, coulomb, offset, v_s)")
            if any(isinstance(v, dict) for v in friction.values()):
                effects.append(Friction.draw(friction, n, np.random.default_rng(0) if rng is None else rng))
            else:
                effects.append(Friction(friction.get("viscous", 0.0), friction.get("coulomb", 0.0),
                                        friction.get("offset", 0.0), v_s=float(friction.get("v_s", 0.01))))
        else:
            fv, fc = _pair(friction, "friction")
            effects.append(Friction(np.full(n, float(fv)), np.full(n, float(fc))))
    if torque_limit is not None and torque_limit is not False:
        if torque_limit == "urdf":
            effects.append(Saturation.from_model(robot))
        else:
            lim = np.asarray(torque_limit, dtype=float) if not isinstance(torque_limit, str) else None
            if lim is None:
                try:
                    lim = np.array(float(torque_limit))
                except ValueError:
                    raise ConfigError(f"torque limit must be 'urdf' or N m, got {torque_limit!r}") from None
            effects.append(Saturation(np.full(n, float(lim)) if lim.ndim == 0 else lim))
    if limits not in (None, False):
        if limits != "urdf":
            raise ConfigError(f"plant limits must be 'urdf' or false, got {limits!r}")
        effects.append(JointLimits.from_model(robot))
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
    limits = cfg.get("limits", "urdf" if robot.urdf else None)
    effects = build_effects(robot, friction=cfg.get("friction"), torque_limit=cfg.get("torque_limit"),
                            limits=limits, rng=rng)
    loop = build_loop(robot.n, noise=cfg.get("noise"), quantization=cfg.get("quantization"), delay=cfg.get("delay"),
                      q0_error=cfg.get("q0_error"), qd0_error=cfg.get("qd0_error"),
                      seed=int(cfg.get("noise_seed", seed)))
    rigid = _mujoco_rigid(robot) if engine == "mujoco" else robot
    return Plant(rigid, effects, label=robot.label), loop, engine
