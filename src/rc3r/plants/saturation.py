r"""Actuator saturation: the delivered torque is the command clipped to :math:`|u_j| \le \bar u_j`.

Limits come from a configuration or from the URDF's ``<limit effort="...">`` (Pinocchio's
``model.effortLimit``). A run records how often the command was at the limit
(``saturation_fraction`` in its metrics; verdict ``saturated`` above
:data:`rc3r.simulate.verdict.SATURATION_FRACTION`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .base import Effect, register_effect

__all__ = ["Saturation"]


@register_effect
@dataclass(frozen=True)
class Saturation(Effect):
    """Torque limit ``limit`` (n,) [N m] (> 0) on every joint's actuator."""

    limit: np.ndarray
    source: str = "config"

    name = "saturation"
    compiled = True

    def __post_init__(self):
        try:
            lim = np.atleast_1d(np.asarray(self.limit, dtype=float))
        except (TypeError, ValueError):
            raise ConfigError(f"torque limit must be numbers, got {self.limit!r}") from None
        if lim.ndim != 1 or not np.all(lim > 0) or np.any(np.isnan(lim)):
            raise ConfigError(f"torque limit must be > 0 per joint, got {lim.tolist()}")
        object.__setattr__(self, "limit", lim)

    @property
    def n(self) -> int:
        return self.limit.size

    def actuator(self, u, q, qd) -> np.ndarray:
        return np.clip(u, -self.limit, self.limit)

    def pack_into(self, fx: np.ndarray, n: int) -> None:
        """Fill the torque-limit fields of :meth:`rc3r.plants.base.Plant.pack`."""
        fx[3 * n + 1:] = self.limit

    @classmethod
    def from_model(cls, robot) -> "Saturation":
        """The URDF's effort limits of ``robot`` (its Pinocchio model's ``effortLimit``)."""
        lim = np.array(robot.model.effortLimit, dtype=float)
        if lim.size != robot.n or not np.all(np.isfinite(lim)) or np.any(lim <= 0):
            raise ConfigError(f"robot {robot.label!r}: its URDF has no usable effort limits ({lim.tolist()}); "
                              "give --torque-limit NM")
        return cls(lim, source="urdf")

    def describe(self) -> dict:
        return {"effect": self.name, "limit": self.limit.tolist(), "source": self.source}
