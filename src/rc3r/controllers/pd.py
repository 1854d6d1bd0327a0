r"""Law ``pd``: PD plus gravity compensation from the model's theta, one module (:mod:`.base`).

:math:`v = a = 0` (so :math:`Y(q, \dot q, 0, 0)\,\theta = g(q)`), :math:`r = 0`,
:math:`w = K_p (q_d - q) + K_d (\dot q_d - \dot q)`, :math:`\theta_{\mathrm{eff}} = \theta_0`, no state
(the kernels of :mod:`.pd_gains`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .base import Layout, at, packed, register_law
from .pd_gains import (C_FIXED_OUTPUT, PDGains, c_constants, directions, inertia_gain, state_gain,  # noqa: F401
                       theta, theta_columns)

__all__ = ["PDGravity", "LAYOUT"]

_INLINE = dict(cache=True, nogil=True, inline="always")
_DERIV = dict(_INLINE, error_model="numpy")


@dataclass(frozen=True, eq=False)
class PDGravity(PDGains):
    """PD plus gravity compensation from the model theta: ``Kp`` [N m/rad], ``Kd`` [N m s/rad]."""

    Kp: float | np.ndarray = packed(500.0, ("Kp", "n"))
    name = "pd"
    code = 4


#: ``[p, theta (p), Kp (n), Kd (n)]``.
LAYOUT = Layout.of(PDGravity)
_KP, _KD = LAYOUT.index("Kp"), LAYOUT.index("Kd")
USES_XI = False


@njit(**_INLINE)
def signals(cp, q, qd, ref, v, a, r, w):
    """PD + gravity: Y(q, qd, 0, 0) theta = g(q); w = Kp (q_d - q) + Kd (qd_d - qd); all (n,)."""
    n = q.shape[0]
    p = int(cp[0])
    kp, kd = at(_KP, n, p), at(_KD, n, p)
    for i in range(n):
        v[i] = 0.0
        a[i] = 0.0
        r[i] = 0.0
        w[i] = cp[kp + i] * (ref[0, i] - q[i]) + cp[kd + i] * (ref[1, i] - qd[i])


@njit(**_DERIV)
def slopes(cp, n, ref, jerk, G, Wx):
    """v = a = r = 0: ``G`` (3, n, 3) zero; ``Wx`` (n, 2n + 1) = dw/d(q, qd, t) = (-Kp, -Kd, Kp qd_d + Kd qdd_d)."""
    p = int(cp[0])
    kpo, kdo = at(_KP, n, p), at(_KD, n, p)
    for i in range(n):
        for c in range(2 * n + 1):
            Wx[i, c] = 0.0
    for j in range(n):
        kp, kd = cp[kpo + j], cp[kdo + j]
        for k in range(3):
            G[k, j, 0], G[k, j, 1], G[k, j, 2] = 0.0, 0.0, 0.0
        Wx[j, j], Wx[j, n + j], Wx[j, 2 * n] = -kp, -kd, kp * ref[1, j] + kd * ref[2, j]


def c_source(law, n: int) -> dict:
    """The law in C (:func:`rc3r.export.c.controller_sources`): its constants, the per-joint body of
    ``rc3r_law_signals`` and the body of ``rc3r_law_output``."""
    return {"constants": c_constants(law, n),
            "signals": """        v[i] = 0.0;
        a[i] = 0.0;
        r[i] = 0.0;
        w[i] = rc3r_Kp[i] * (ref[0][i] - q[i]) + rc3r_Kd[i] * (ref[1][i] - qd[i]);""",
            "output": C_FIXED_OUTPUT}


register_law(PDGravity)
