r"""Joint friction: viscous, smooth Coulomb, and a constant offset, per joint.

.. math::

    \tau_f = -\left(F_v \dot q + F_c \tanh(\dot q / v_s) + \tau_{off}\right)

(element-wise). The Coulomb term is smoothed by ``tanh`` with velocity scale ``v_s``
[rad/s] so the continuous-time integrators see a Lipschitz right-hand side; with
``v_s -> 0`` it tends to ``F_c sign(qd)``. Values come from a configuration or from the
URDF's ``<dynamics damping="F_v" friction="F_c">`` (read by Pinocchio into
``model.damping`` and ``model.friction``). In a campaign each coefficient may be an
uncertain range ``{lo = ..., hi = ...}``, drawn uniformly per joint and plant
(:meth:`Friction.draw`).

The module is the effect's one home: the class, its packed :data:`LAYOUT`, the compiled value
(:func:`torque`) and derivative (:func:`damping`) the engines dispatch to by its ``code``, and how
a configuration (``[plant] friction = ...``, ``[plant.friction]``) and the command line
(``--friction``) reach it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from ..errors import ConfigError
from ._kernels import KERNEL_JIT, at
from .base import (JOINT, SCALAR, Effect, Layout, Option, nonnegative_numbers, pair, per_joint,
                   register_effect)

__all__ = ["Friction", "MAX_FRICTION", "LAYOUT", "torque", "damping"]

#: Largest friction coefficient of a plant: viscous [N m s/rad], Coulomb and offset [N m] (in magnitude).
#: The largest industrial arms' joints deliver some 1e4 N m; 1e5 bounds what is physically plausible and
#: keeps the plant integrable (a viscous 1e300 left the arm frozen, "clean").
MAX_FRICTION = 1e5


#: The packed parameters (:meth:`rc3r.plants.Plant.pack`): the fields of :class:`Friction` by name.
LAYOUT = Layout(viscous=JOINT, coulomb=JOINT, offset=JOINT, v_s=SCALAR)
_FV, _FC, _OFF, _VS = LAYOUT.slots


@njit(**KERNEL_JIT)
def torque(fx, o, n, j, qd):
    """Friction torque [N m] at joint j for its speed ``qd`` [rad/s]: ``-(F_v qd + F_c tanh(qd / v_s) + offset)``
    from the block at ``fx[o:]`` (:data:`LAYOUT`)."""
    vs = fx[at(_VS, o, n)]
    return -(fx[at(_FV, o, n) + j] * qd + fx[at(_FC, o, n) + j] * math.tanh(qd / vs) + fx[at(_OFF, o, n) + j])


@njit(**KERNEL_JIT)
def damping(fx, o, n, j, qd):
    """``-d torque / d qd`` [N m s/rad] at joint j: ``F_v + F_c (1 - tanh^2(qd / v_s)) / v_s`` (0 on a joint
    without viscous and Coulomb friction)."""
    fv, fc = fx[at(_FV, o, n) + j], fx[at(_FC, o, n) + j]
    if fv != 0.0 or fc != 0.0:
        vs = fx[at(_VS, o, n)]
        th = math.tanh(qd / vs)
        return fv + fc * (1.0 - th * th) / vs
    return 0.0


def _vector(name, x, n) -> np.ndarray:
    return per_joint(f"friction {name}", x, n)


def _parse(text: str) -> str:
    """``--friction``: ``urdf`` or ``VISCOUS:COULOMB`` (finite, >= 0)."""
    return text if text == "urdf" else nonnegative_numbers(text, "'urdf' or VISCOUS:COULOMB")


@register_effect
@dataclass(frozen=True)
class Friction(Effect):
    """Viscous ``viscous`` [N m s/rad], Coulomb ``coulomb`` [N m], ``offset`` [N m], each (n,).

    ``v_s`` [rad/s] smooths the Coulomb term (default 0.01 rad/s: 99 % of ``F_c`` at 0.026 rad/s).
    ``offset`` may be negative (a constant bias torque); the others are >= 0.
    """

    viscous: np.ndarray = field(default_factory=lambda: np.zeros(0))
    coulomb: np.ndarray | None = None
    offset: np.ndarray | None = None
    v_s: float = 0.01
    source: str = "config"

    name = "friction"
    compiled = True
    code = 1
    role = "torque"
    LAYOUT = LAYOUT
    value_kernel = staticmethod(torque)
    slope_kernel = staticmethod(damping)
    config_keys = ("friction",)
    cli = (Option("--friction", "friction", _parse, "urdf|VISCOUS:COULOMB",
                  "joint friction of the plant: the URDF's <dynamics damping friction> or values [N m s/rad]:[N m]"),)

    def __post_init__(self):
        fv = np.asarray(self.viscous, dtype=float)
        n = fv.size if fv.ndim == 1 and fv.size else (np.asarray(self.coulomb).size if self.coulomb is not None else 0)
        if n == 0:
            raise ConfigError("friction needs per-joint viscous and/or coulomb coefficients")
        object.__setattr__(self, "viscous", _vector("viscous", fv if fv.size else 0.0, n))
        object.__setattr__(self, "coulomb", _vector("coulomb", 0.0 if self.coulomb is None else self.coulomb, n))
        off = np.zeros(n) if self.offset is None else np.asarray(self.offset, dtype=float)
        if off.ndim == 0:
            off = np.full(n, float(off))
        if off.shape != (n,) or not np.all(np.isfinite(off)):
            raise ConfigError(f"friction offset must be {n} finite numbers, got {np.ravel(off).tolist()}")
        object.__setattr__(self, "offset", off)
        if not (np.isfinite(self.v_s) and self.v_s > 0):
            raise ConfigError(f"friction v_s must be finite and > 0, got {self.v_s}")
        for name in ("viscous", "coulomb", "offset"):
            x = getattr(self, name)
            if np.any(np.abs(x) > MAX_FRICTION):
                shown = ", ".join(f"{v:g}" for v in np.ravel(x))
                raise ConfigError(f"friction {name} [{shown}] is beyond {MAX_FRICTION:g} "
                                  f"({'N m s/rad' if name == 'viscous' else 'N m'}): not a physical joint")

    @property
    def n(self) -> int:
        return self.viscous.size

    def joint_torque(self, q, qd) -> np.ndarray:
        qd = np.asarray(qd, dtype=float)
        return -(self.viscous * qd + self.coulomb * np.tanh(qd / self.v_s) + self.offset)

    def damping(self) -> np.ndarray:
        """``F_v + F_c / v_s`` (n,) [N m s/rad]: the largest slope of the friction torque in ``qd``
        (``tanh``'s at ``qd = 0``)."""
        return self.viscous + self.coulomb / self.v_s

    def active(self) -> bool:
        """False if every coefficient is zero (the compiled engines then skip it, as a rigid plant)."""
        return bool(np.any(self.viscous) or np.any(self.coulomb) or np.any(self.offset))

    @classmethod
    def from_config(cls, robot, key, value, rng=None):
        """``value``: None/false (none), ``"urdf"``, ``"VISCOUS:COULOMB"``, ``[viscous, coulomb]`` or a table
        ``{"viscous": x, "coulomb": ..., "offset": ..., "v_s": ...}`` (``[plant.friction]``) where x is one
        number, n numbers, or an uncertain range ``{lo = ..., hi = ...}`` drawn per joint with ``rng``
        (a campaign's per-plant generator; seed 0 if None)."""
        if value is None or value is False:
            return None
        n = robot.n
        if value == "urdf":
            return cls.from_model(robot)
        if isinstance(value, dict):
            unknown = sorted(set(value) - {"viscous", "coulomb", "offset", "v_s"})
            if unknown:
                raise ConfigError(f"[plant.friction]: unknown key(s) {', '.join(unknown)} "
                                  "(valid: viscous, coulomb, offset, v_s)")
            if any(isinstance(v, dict) for v in value.values()):
                return cls.draw(value, n, np.random.default_rng(0) if rng is None else rng)
            return cls(value.get("viscous", 0.0), value.get("coulomb", 0.0), value.get("offset", 0.0),
                       v_s=float(value.get("v_s", 0.01)))
        fv, fc = pair(value, "friction")
        return cls(np.full(n, float(fv)), np.full(n, float(fc)))

    @classmethod
    def from_model(cls, robot, scale: float = 1.0) -> "Friction":
        """The URDF's ``<dynamics damping friction>`` of ``robot`` (its Pinocchio model), times ``scale``."""
        m = robot.model
        fv, fc = np.array(m.damping, dtype=float), np.array(m.friction, dtype=float)
        if fv.size != robot.n:
            raise ConfigError(f"robot {robot.label!r}: its model has {fv.size} damping entries for {robot.n} joints")
        if not np.any(fv) and not np.any(fc):
            raise ConfigError(f"robot {robot.label!r}: its URDF has no <dynamics damping friction> "
                              "(give --friction VISCOUS:COULOMB)")
        return cls(scale * fv, scale * fc, source="urdf")

    @classmethod
    def draw(cls, ranges: dict, n: int, rng) -> "Friction":
        """A friction drawn from ``ranges`` ``{"viscous": {"lo": a, "hi": b} | value, ...}``: each range
        uniformly per joint with ``rng``, in the order viscous, coulomb, offset."""
        vals = {}
        for key in ("viscous", "coulomb", "offset"):
            spec = ranges.get(key, 0.0)
            if isinstance(spec, dict):
                try:
                    lo, hi = float(spec["lo"]), float(spec["hi"])
                except (KeyError, TypeError, ValueError):
                    raise ConfigError(f"friction {key} range must be {{lo = a, hi = b}}, got {spec}") from None
                if set(spec) - {"lo", "hi"} or not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                    raise ConfigError(f"friction {key} range must be {{lo = a, hi = b}} with a <= b, got {spec}")
                vals[key] = rng.uniform(lo, hi, n)
            else:
                vals[key] = spec
        return cls(vals["viscous"], vals["coulomb"], vals["offset"], v_s=float(ranges.get("v_s", 0.01)),
                   source="drawn")

    def describe(self) -> dict:
        return {"effect": self.name, "viscous": self.viscous.tolist(), "coulomb": self.coulomb.tolist(),
                "offset": self.offset.tolist(), "v_s": self.v_s, "source": self.source}
