r"""The identification regressor: the arm's base regressor and per-joint friction columns.

The logged torque of joint ``j`` is modelled as

.. math::

    \tau_j = \bigl[Y(q, \dot q, \dot q, \ddot q)\,\theta\bigr]_j
             + f_{v,j}\,\dot q_j + f_{c,j}\,\mathrm{sign}(\dot q_j) + f_{0,j},

with ``Y`` the robot's regressor in its own coefficients (:meth:`Robot.regressor` with
``v = qd``, ``a = qdd``: the inverse-dynamics regressor), viscous ``f_v`` [N m s/rad],
Coulomb ``f_c`` [N m] and a constant offset ``f_0`` [N m] (a torque sensor's bias or a
static load the model lacks). Each friction kind adds one column per joint, nonzero
only in that joint's row. :data:`FRICTION_KINDS` lists them in the order their columns
follow ``theta``: for every kind, joints 1..n.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError

__all__ = ["FRICTION_KINDS", "parse_friction", "friction_names", "friction_columns", "identification_regressor"]

#: Friction kinds and the prefix of their coefficient names.
FRICTION_KINDS = {"viscous": "fv", "coulomb": "fc", "offset": "f0"}


def parse_friction(text) -> tuple[str, ...]:
    """``"viscous,coulomb"`` (or a sequence) -> ``("viscous", "coulomb")`` in :data:`FRICTION_KINDS` order.

    ``""`` or ``"none"`` give no friction columns; an unknown kind is a one-line ConfigError.
    """
    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text)]
    items = [s for s in items if s and s != "none"]
    bad = [s for s in items if s not in FRICTION_KINDS]
    if bad:
        raise ConfigError(f"unknown friction kind(s) {', '.join(bad)} (choose from {', '.join(FRICTION_KINDS)})")
    return tuple(k for k in FRICTION_KINDS if k in items)


def friction_names(kinds, n: int) -> tuple[str, ...]:
    """``("fv1", ..., "fvn", "fc1", ...)`` for the kinds given."""
    return tuple(f"{FRICTION_KINDS[k]}{j}" for k in kinds for j in range(1, n + 1))


def friction_columns(qd, kinds) -> np.ndarray:
    """Friction regressor (N, n, n * len(kinds)) of velocities ``qd`` (N, n)."""
    qd = np.atleast_2d(np.asarray(qd, dtype=float))
    N, n = qd.shape
    out = np.zeros((N, n, n * len(kinds)))
    idx = np.arange(n)
    for k, kind in enumerate(kinds):
        val = qd if kind == "viscous" else np.sign(qd) if kind == "coulomb" else np.ones_like(qd)
        out[:, idx, k * n + idx] = val
    return out


def identification_regressor(robot, q, qd, qdd, kinds) -> np.ndarray:
    """``[Y(q, qd, qd, qdd) | friction]``, shape (N, n, p + n len(kinds))."""
    q, qd, qdd = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, qd, qdd))
    Y = np.asarray(robot.regressor(q, qd, qd, qdd), dtype=float)
    if Y.ndim == 2:
        Y = Y[None]
    return np.concatenate([Y, friction_columns(qd, kinds)], axis=2)
