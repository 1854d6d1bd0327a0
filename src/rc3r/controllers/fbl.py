r"""Law ``fbl``: computed torque (feedback linearization), one module (:mod:`.base`).

:math:`v = \dot q`, :math:`a = \ddot q_d + K_d (\dot q_d - \dot q) + K_p (q_d - q)`, :math:`r = w = 0`,
:math:`\theta_{\mathrm{eff}} = \theta_0`, no state (the kernels of :mod:`.pd_gains`).
"""
from __future__ import annotations

from dataclasses import dataclass

from numba import njit

from .base import Layout, at, register_law
from .pd_gains import (C_FIXED_OUTPUT, PDGains, c_constants, directions, inertia_gain, state_gain,  # noqa: F401
                       theta, theta_columns)

__all__ = ["FeedbackLinearization", "LAYOUT"]

_INLINE = dict(cache=True, nogil=True, inline="always")
_DERIV = dict(_INLINE, error_model="numpy")


@dataclass(frozen=True, eq=False)
class FeedbackLinearization(PDGains):
    """Computed torque with diagonal ``Kp`` [1/s^2] and ``Kd`` [1/s] (the paper's 100, 100)."""

    name = "fbl"
    code = 0


#: ``[p, theta (p), Kp (n), Kd (n)]``.
LAYOUT = Layout.of(FeedbackLinearization)
_KP, _KD = LAYOUT.index("Kp"), LAYOUT.index("Kd")
USES_XI = False


@njit(**_INLINE)
def signals(cp, q, qd, ref, v, a, r, w):
    """Computed torque: v = qd, a = qdd_d + Kd (qd_d - qd) + Kp (q_d - q), r = w = 0; all (n,)."""
    n = q.shape[0]
    p = int(cp[0])
    kp, kd = at(_KP, n, p), at(_KD, n, p)
    for i in range(n):
        v[i] = qd[i]
        a[i] = ref[2, i] + cp[kd + i] * (ref[1, i] - qd[i]) + cp[kp + i] * (ref[0, i] - q[i])
        r[i] = 0.0
        w[i] = 0.0


@njit(**_DERIV)
def slopes(cp, n, ref, jerk, G, Wx):
    """``G`` (3, n, 3): v = qd, a = qdd_d + Kd (qd_d - qd) + Kp (q_d - q), r = 0; ``Wx`` (n, 2n + 1) = 0."""
    p = int(cp[0])
    kpo, kdo = at(_KP, n, p), at(_KD, n, p)
    for i in range(n):
        for c in range(2 * n + 1):
            Wx[i, c] = 0.0
    for j in range(n):
        kp, kd = cp[kpo + j], cp[kdo + j]
        G[0, j, 0], G[0, j, 1], G[0, j, 2] = 0.0, 1.0, 0.0
        G[1, j, 0], G[1, j, 1], G[1, j, 2] = -kp, -kd, jerk[j] + kd * ref[2, j] + kp * ref[1, j]
        G[2, j, 0], G[2, j, 1], G[2, j, 2] = 0.0, 0.0, 0.0


def c_source(law, n: int) -> dict:
    """The law in C (:func:`rc3r.export.c.controller_sources`): its constants, the per-joint body of
    ``rc3r_law_signals`` and the body of ``rc3r_law_output``."""
    return {"constants": c_constants(law, n),
            "signals": """        v[i] = qd[i];
        a[i] = ref[2][i] + rc3r_Kd[i] * (ref[1][i] - qd[i]) + rc3r_Kp[i] * (ref[0][i] - q[i]);
        r[i] = 0.0;
        w[i] = 0.0;""",
            "output": C_FIXED_OUTPUT}


register_law(FeedbackLinearization)
