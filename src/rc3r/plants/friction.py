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
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from .base import Effect, per_joint, register_effect

__all__ = ["Friction", "MAX_FRICTION"]

#: Largest friction coefficient of a plant: viscous [N m s/rad], Coulomb and offset [N m] (in magnitude).
#: The largest industrial arms' joints deliver some 1e4 N m; 1e5 bounds what is physically plausible and
#: keeps the plant integrable (a viscous 1e300 left the arm frozen, "clean").
MAX_FRICTION = 1e5


def _vector(name, x, n) -> np.ndarray:
    return per_joint(f"friction {name}", x, n)


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

    def pack_into(self, fx: np.ndarray, n: int) -> None:
        """Fill the friction fields of :meth:`rc3r.plants.base.Plant.pack`."""
        fx[0:n], fx[n:2 * n], fx[2 * n:3 * n], fx[3 * n] = self.viscous, self.coulomb, self.offset, self.v_s

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
