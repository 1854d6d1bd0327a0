"""Joint position and velocity limits, reported when crossed (a monitor: the dynamics are untouched).

A real arm stops at its limits (a hard stop, a safety controller); a simulation that
crosses them is not a faithful prediction, and says so: the verdict of such a run is
``limit-violated``, with the first crossing per joint in its metrics
(:func:`crossings`). Limits come from the URDF (Pinocchio's ``lowerPositionLimit``,
``upperPositionLimit``, ``velocityLimit``) or from a configuration. Crossings are read
from the stored time series (``output_rate``, 1 kHz by default).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .base import Effect, register_effect

__all__ = ["JointLimits", "crossings"]


@register_effect
@dataclass(frozen=True)
class JointLimits(Effect):
    """Position limits ``lower``, ``upper`` (n,) [rad] and speed limits ``velocity`` (n,) [rad/s]."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    source: str = "config"

    name = "limits"
    monitor = True
    stiff = False
    config_keys = ("limits",)

    @classmethod
    def from_config(cls, robot, key, value, rng=None):
        """``limits = "urdf"`` (the URDF's), false or None (none), or a table
        ``{lower = [...], upper = [...], velocity = [...]}`` (``[plant.limits]``, [rad] and [rad/s])."""
        if value is None or value is False:
            return None
        if isinstance(value, dict):
            missing = sorted({"lower", "upper", "velocity"} - set(value))
            extra = sorted(set(value) - {"lower", "upper", "velocity"})
            if missing or extra:
                raise ConfigError(f"[plant.limits] needs lower, upper, velocity (n numbers each), got "
                                  f"{', '.join(sorted(value)) or 'nothing'}")
            return cls(value["lower"], value["upper"], value["velocity"])
        if value != "urdf":
            raise ConfigError(f"plant limits must be 'urdf' or false, got {value!r}")
        return cls.from_model(robot)

    @classmethod
    def default_config(cls, robot):
        """``"urdf"`` for a robot read from a URDF (its limits are reported), else None."""
        return "urdf" if robot.urdf else None

    def __post_init__(self):
        lo, hi, vel = (np.atleast_1d(np.asarray(x, dtype=float)) for x in (self.lower, self.upper, self.velocity))
        if not (lo.shape == hi.shape == vel.shape and lo.ndim == 1) or np.any(np.isnan(lo) | np.isnan(hi) | np.isnan(vel)) \
                or np.any(lo > hi) or np.any(vel <= 0):
            raise ConfigError(f"joint limits need lower <= upper and velocity > 0 per joint, got "
                              f"{lo.tolist()}, {hi.tolist()}, {vel.tolist()}")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "velocity", vel)

    @property
    def n(self) -> int:
        return self.lower.size

    @classmethod
    def from_model(cls, robot) -> "JointLimits":
        """The URDF's limits; a joint with lower == upper (no range given) or no velocity limit is unbounded."""
        m = robot.model
        lo, hi = np.array(m.lowerPositionLimit, float), np.array(m.upperPositionLimit, float)
        vel = np.array(m.velocityLimit, float)
        if lo.size != robot.n:
            raise ConfigError(f"robot {robot.label!r}: {lo.size} position limits for {robot.n} joints")
        none = lo >= hi
        lo[none], hi[none] = -np.inf, np.inf
        vel[~(vel > 0) | ~np.isfinite(vel)] = np.inf
        return cls(lo, hi, vel, source="urdf")

    def describe(self) -> dict:
        def lst(x):
            return [None if not np.isfinite(v) else float(v) for v in x]

        return {"effect": self.name, "lower": lst(self.lower), "upper": lst(self.upper),
                "velocity": lst(self.velocity), "source": self.source}


def crossings(limits: JointLimits, t, q, qd) -> dict:
    """First time [s] each joint left its position or speed range, or None: ``{"position": [...],
    "velocity": [...], "violated": bool}`` from stored rows ``t`` (N,), ``q``, ``qd`` (N, n)."""
    out = {}
    for key, bad in (("position", (q < limits.lower) | (q > limits.upper)),
                     ("velocity", np.abs(qd) > limits.velocity)):
        first = []
        for j in range(bad.shape[1]):
            idx = np.flatnonzero(bad[:, j])
            first.append(float(t[idx[0]]) if idx.size else None)
        out[key] = first
    out["violated"] = any(x is not None for x in out["position"] + out["velocity"])
    return out
