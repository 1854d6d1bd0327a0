r"""Actuator saturation: the delivered torque is the command clipped to :math:`|u_j| \le \bar u_j`.

Limits come from a configuration or from the URDF's ``<limit effort="...">`` (Pinocchio's
``model.effortLimit``). A run records how often the command was at the limit
(``saturation_fraction`` in its metrics; verdict ``saturated`` above
:data:`rc3r.simulate.verdict.SATURATION_FRACTION`).

The module is the effect's one home: the class, its packed :data:`LAYOUT`, the compiled clip
(:func:`clip`) and its slope (:func:`passes`), and how a configuration (``[plant.saturation]
limit = ...``, or the older ``[plant] torque_limit = ...``) and the command line
(``--torque-limit``) reach it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..errors import ConfigError
from ._kernels import KERNEL_JIT, at
from .base import JOINT, Effect, Layout, Option, register_effect

__all__ = ["Saturation", "LAYOUT", "clip", "passes"]

#: The packed parameters (:meth:`rc3r.plants.Plant.pack`): the torque limit per joint.
LAYOUT = Layout(limit=JOINT)
_LIM, = LAYOUT.slots


@njit(**KERNEL_JIT)
def clip(fx, o, n, j, u):
    """The delivered torque [N m] at joint j for the command ``u``: ``u`` clipped to ``|u| <= limit_j``."""
    lim = fx[at(_LIM, o, n) + j]
    return lim if u > lim else (-lim if u < -lim else u)


@njit(**KERNEL_JIT)
def passes(fx, o, n, j, u):
    """``d clip / d u`` at joint j: 0 at or beyond the limit (the delivered torque does not move), else 1."""
    return 0.0 if abs(u) >= fx[at(_LIM, o, n) + j] else 1.0


def _parse(text: str):
    """``--torque-limit``: ``urdf`` or one limit [N m] (finite, > 0) for every joint."""
    if text == "urdf":
        return text
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f"expected 'urdf' or a number, got {text!r}") from None
    if not (math.isfinite(x) and x > 0):
        raise ValueError(f"must be finite and > 0, got {text}")
    return x


@register_effect
@dataclass(frozen=True)
class Saturation(Effect):
    """Torque limit ``limit`` (n,) [N m] (> 0) on every joint's actuator."""

    limit: np.ndarray
    source: str = "config"

    name = "saturation"
    compiled = True
    stiff = False
    code = 2
    role = "actuator"
    LAYOUT = LAYOUT
    value_kernel = staticmethod(clip)
    slope_kernel = staticmethod(passes)
    config_keys = ("saturation", "torque_limit")
    cli = (Option("--torque-limit", "torque_limit", _parse, "urdf|NM",
                  "actuator saturation: the URDF's effort limits or one limit [N m] for every joint"),)

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

    @classmethod
    def from_config(cls, robot, key, value, rng=None):
        """``torque_limit = value`` or ``[plant.saturation] limit = value``: None/false (none), ``"urdf"``, a
        number [N m] (every joint) or n numbers."""
        if key == "saturation":
            if not isinstance(value, dict) or set(value) - {"limit"} or "limit" not in value:
                raise ConfigError(f"[plant.saturation] must be a table {{limit = NM | [n numbers] | \"urdf\"}}, "
                                  f"got {value!r}")
            value = value["limit"]
        if value is None or value is False:
            return None
        if value == "urdf":
            return cls.from_model(robot)
        lim = np.asarray(value, dtype=float) if not isinstance(value, str) else None
        if lim is None:
            try:
                lim = np.array(float(value))
            except ValueError:
                raise ConfigError(f"torque limit must be 'urdf' or N m, got {value!r}") from None
        return cls(np.full(robot.n, float(lim)) if lim.ndim == 0 else lim)

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
