r"""Stribeck friction: a static peak that falls to the Coulomb level as the joint speeds up, per joint.

.. math::

    \tau_f = -\Bigl(\bigl(F_c + (F_s - F_c)\, e^{-(\dot q / v_s)^2}\bigr) \tanh(\dot q / v_\epsilon)
             + F_v \dot q\Bigr)

(element-wise): Coulomb ``coulomb`` :math:`F_c` [N m], static ``static`` :math:`F_s` [N m] (the
breakaway torque), Stribeck speed ``v_s`` [rad/s] (how fast the static peak decays), viscous
``viscous`` :math:`F_v` [N m s/rad], and ``v_eps`` [rad/s], the ``tanh`` smoothing of the sign
that keeps the right-hand side Lipschitz (as :mod:`rc3r.plants.friction`'s ``v_s``). With
:math:`F_s = F_c` it is that module's friction without offset. Between the peak and the Coulomb
level the slope :math:`d\tau_f/d\dot q` is positive (negative damping, the Stribeck effect).

This module is the worked example of docs/architecture.md, "Adding a compiled plant effect":
everything the effect is, in one file --

* :class:`Stribeck`, registered (:func:`~rc3r.plants.base.register_effect`): its Python torque
  (the ``python`` engine), ``stiff``, its ``[plant.stribeck]`` keys (:meth:`Stribeck.from_config`)
  and its ``--stribeck`` option;
* :data:`LAYOUT`: its packed fields, named once;
* :func:`torque` (njit): the value the compiled engines add at each joint;
* :func:`damping` (njit): ``-d torque / d qd``, for the analytic Jacobian and the implicit periods.

Configuration::

    [plant.stribeck]
    coulomb = 1.0        # N m, one number or one per joint
    static = 1.5         # N m
    v_s = 0.1            # rad/s
    viscous = 0.5        # N m s/rad
    v_eps = 0.01         # rad/s (default)

or ``--stribeck COULOMB:STATIC:V_S:VISCOUS`` (the same numbers on every joint).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from ..errors import ConfigError
from ._kernels import KERNEL_JIT, at
from .base import JOINT, SCALAR, Effect, Layout, Option, nonnegative_numbers, per_joint, register_effect
from .friction import MAX_FRICTION

__all__ = ["Stribeck", "LAYOUT", "torque", "damping"]

#: The packed parameters (:meth:`rc3r.plants.Plant.pack`): the fields of :class:`Stribeck` by name.
LAYOUT = Layout(coulomb=JOINT, static=JOINT, v_s=JOINT, viscous=JOINT, v_eps=SCALAR)
_FC, _FS, _VS, _FV, _VE = LAYOUT.slots

#: ``[plant.stribeck]`` keys (all but v_eps are one number or n numbers).
KEYS = ("coulomb", "static", "v_s", "viscous", "v_eps")


@njit(**KERNEL_JIT)
def torque(fx, o, n, j, qd):
    """Stribeck friction torque [N m] at joint j for its speed ``qd`` [rad/s] (module docstring), from the
    block at ``fx[o:]`` (:data:`LAYOUT`)."""
    fc, fs, vs = fx[at(_FC, o, n) + j], fx[at(_FS, o, n) + j], fx[at(_VS, o, n) + j]
    x = qd / vs
    g = fc + (fs - fc) * math.exp(-x * x)
    return -(g * math.tanh(qd / fx[at(_VE, o, n)]) + fx[at(_FV, o, n) + j] * qd)


@njit(**KERNEL_JIT)
def damping(fx, o, n, j, qd):
    """``-d torque / d qd`` [N m s/rad] at joint j:
    ``F_v + g (1 - tanh^2(qd / v_eps)) / v_eps - 2 (F_s - F_c) qd / v_s^2 exp(-(qd / v_s)^2) tanh(qd / v_eps)``
    with ``g = F_c + (F_s - F_c) exp(-(qd / v_s)^2)``; negative where the static peak decays."""
    fc, fs, vs = fx[at(_FC, o, n) + j], fx[at(_FS, o, n) + j], fx[at(_VS, o, n) + j]
    ve = fx[at(_VE, o, n)]
    x = qd / vs
    ex = math.exp(-x * x)
    th = math.tanh(qd / ve)
    g = fc + (fs - fc) * ex
    return fx[at(_FV, o, n) + j] + g * (1.0 - th * th) / ve - 2.0 * (fs - fc) * x / vs * ex * th


def _parse(text: str) -> str:
    """``--stribeck COULOMB:STATIC:V_S:VISCOUS`` (finite, >= 0; V_S > 0 is checked by the class)."""
    return nonnegative_numbers(text, "COULOMB:STATIC:V_S:VISCOUS", count=4)


@register_effect
@dataclass(frozen=True)
class Stribeck(Effect):
    """Coulomb ``coulomb``, static ``static`` [N m], Stribeck speed ``v_s`` [rad/s], viscous ``viscous``
    [N m s/rad], each (n,) (one number broadcast); smoothing ``v_eps`` [rad/s] (module docstring)."""

    coulomb: np.ndarray = field(default_factory=lambda: np.zeros(0))
    static: np.ndarray | None = None
    v_s: np.ndarray | float = 0.1
    viscous: np.ndarray | float = 0.0
    v_eps: float = 0.01
    source: str = "config"

    name = "stribeck"
    compiled = True
    code = 3
    role = "torque"
    LAYOUT = LAYOUT
    value_kernel = staticmethod(torque)
    slope_kernel = staticmethod(damping)
    config_keys = ("stribeck",)
    cli = (Option("--stribeck", "stribeck", _parse, "COULOMB:STATIC:V_S:VISCOUS",
                  "Stribeck joint friction on every joint: Coulomb and static [N m], Stribeck speed [rad/s], "
                  "viscous [N m s/rad] (docs/control.md, \"Plants\")"),)

    def __post_init__(self):
        given = [x for x in (self.coulomb, self.static, self.v_s, self.viscous) if x is not None and np.ndim(x) == 1]
        n = max((np.size(x) for x in given), default=0)
        if n == 0:
            raise ConfigError("stribeck friction needs n numbers for at least one of coulomb, static, v_s, viscous")
        fc = per_joint("stribeck coulomb", self.coulomb if np.size(self.coulomb) else 0.0, n)
        object.__setattr__(self, "coulomb", fc)
        object.__setattr__(self, "static", per_joint("stribeck static", fc if self.static is None else self.static, n))
        object.__setattr__(self, "viscous", per_joint("stribeck viscous", self.viscous, n))
        object.__setattr__(self, "v_s", per_joint("stribeck v_s", self.v_s, n))
        if np.any(self.v_s <= 0):
            raise ConfigError(f"stribeck v_s must be > 0 per joint, got {self.v_s.tolist()}")
        if not (np.isfinite(self.v_eps) and self.v_eps > 0):
            raise ConfigError(f"stribeck v_eps must be finite and > 0, got {self.v_eps}")
        for name in ("coulomb", "static", "viscous"):
            if np.any(getattr(self, name) > MAX_FRICTION):
                raise ConfigError(f"stribeck {name} is beyond {MAX_FRICTION:g}: not a physical joint")

    @property
    def n(self) -> int:
        return self.coulomb.size

    def joint_torque(self, q, qd) -> np.ndarray:
        qd = np.asarray(qd, dtype=float)
        x = qd / self.v_s
        g = self.coulomb + (self.static - self.coulomb) * np.exp(-x * x)
        return -(g * np.tanh(qd / self.v_eps) + self.viscous * qd)

    def damping(self) -> np.ndarray:
        """``F_v + max(F_s, F_c) / v_eps`` (n,) [N m s/rad]: a bound on the friction's largest slope in ``qd``
        (its ``tanh``'s at ``qd = 0``, where the static torque acts)."""
        return self.viscous + np.maximum(self.static, self.coulomb) / self.v_eps

    def active(self) -> bool:
        return bool(np.any(self.coulomb) or np.any(self.static) or np.any(self.viscous))

    @classmethod
    def from_config(cls, robot, key, value, rng=None):
        """``value``: None/false (none), ``"COULOMB:STATIC:V_S:VISCOUS"`` (every joint) or the table
        ``{coulomb, static, v_s, viscous, v_eps}`` (module docstring; each one number or n numbers)."""
        if value is None or value is False:
            return None
        if isinstance(value, str):
            try:
                fc, fs, vs, fv = (float(x) for x in _parse(value).split(":"))
            except ValueError as exc:
                raise ConfigError(f"stribeck: {exc}") from None
            return cls(np.full(robot.n, fc), np.full(robot.n, fs), vs, fv)
        if not isinstance(value, dict):
            raise ConfigError(f"[plant.stribeck] must be a table {{{', '.join(KEYS)}}} or "
                              f"'COULOMB:STATIC:V_S:VISCOUS', got {value!r}")
        unknown = sorted(set(value) - set(KEYS))
        if unknown:
            raise ConfigError(f"[plant.stribeck]: unknown key(s) {', '.join(unknown)} (valid: {', '.join(KEYS)})")
        def joints(x):  # one number -> one per joint of the robot
            return np.full(robot.n, float(x)) if np.ndim(x) == 0 and not isinstance(x, (str, dict)) else x

        static = value.get("static")
        return cls(joints(value.get("coulomb", 0.0)), None if static is None else joints(static),
                   joints(value.get("v_s", 0.1)), joints(value.get("viscous", 0.0)),
                   v_eps=float(value.get("v_eps", 0.01)))

    def describe(self) -> dict:
        return {"effect": self.name, "coulomb": self.coulomb.tolist(), "static": self.static.tolist(),
                "v_s": self.v_s.tolist(), "viscous": self.viscous.tolist(), "v_eps": self.v_eps,
                "source": self.source}
