r"""Law ``pd-plus``: Paden and Panja's PD+, the worked example of a compiled law in one module.

PD+ (B. Paden, R. Panja, Int. J. Control 47 (1988)) feeds the model's inverse dynamics along the
reference forward and closes a PD loop around it:

.. math::

    u = M(q)\,\ddot q_d + C(q, \dot q)\,\dot q_d + g(q) + K_p (q_d - q) + K_d (\dot q_d - \dot q),

all with the model's :math:`\theta_0`. In the form of every law,
:math:`u = Y(q, \dot q, v, a)\,\theta_{\mathrm{eff}} + w`: :math:`v = \dot q_d`, :math:`a = \ddot q_d`,
:math:`r = 0`, :math:`w = K_p (q_d - q) + K_d (\dot q_d - \dot q)`, :math:`\theta_{\mathrm{eff}} = \theta_0`,
no state. With the exact model the closed loop is
:math:`M \ddot e + (C + K_d)\dot e + K_p e = 0`, globally asymptotically stable for diagonal
:math:`K_p, K_d > 0` (a passivity argument).

This module is everything the law needs, in the order :mod:`rc3r.controllers.base` asks for:

1. the class (:class:`PDPlus`): its fields, their defaults and how they are packed (:func:`~.base.packed`);
2. ``LAYOUT``: the named offsets of its packed vector, derived from the fields;
3. the value kernels ``signals``, ``theta``, ``inertia_gain`` (numba; ``theta`` and ``inertia_gain`` are
   those of every law whose theta_eff is theta_0 and that has no state, imported from :mod:`.pd_gains`);
4. the derivative kernels for the analytic Jacobian: ``slopes`` (and ``directions``, ``theta_columns``,
   ``state_gain`` from :mod:`.pd_gains`);
5. ``c_source``: its part of ``rc3r export``'s C.

The last line registers it: ``make_law("pd-plus", ...)``, ``rc3r run --controller pd-plus``,
``[controller] kind = "pd-plus"`` in a run's TOML, the compiled engine (its dispatch is written from the
registry) and ``rc3r export`` then reach it. ``tests/test_controllers_pd_plus.py`` checks it against
Pinocchio, the compiled engine against the python one, the analytic Jacobian against differences and
the exported C against Python.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .base import Layout, at, packed, register_law
from .pd_gains import (C_FIXED_OUTPUT, PDGains, c_constants, directions, inertia_gain, state_gain,  # noqa: F401
                       theta, theta_columns)

__all__ = ["PDPlus", "LAYOUT"]

_INLINE = dict(cache=True, nogil=True, inline="always")  # inlined into the engine's integrators
_DERIV = dict(_INLINE, error_model="numpy")  # as the analytic Jacobian that inlines it


# 1. the class: Kp [N m/rad] and Kd [N m s/rad], diagonal, > 0 (validated by PDGains), packed per joint
@dataclass(frozen=True, eq=False)
class PDPlus(PDGains):
    """PD+ (module docstring): model feedforward ``Y(q, qd, qd_d, qdd_d) theta_0`` plus ``Kp e + Kd e_dot``.

    Parameters
    ----------
    theta : (p,) array_like
        The model's coefficients theta_0.
    Kp : float or (n,)
        Position gain [N m/rad], > 0.
    Kd : float or (n,)
        Velocity gain [N m s/rad], > 0.
    """

    Kp: float | np.ndarray = packed(500.0, ("Kp", "n"))
    Kd: float | np.ndarray = packed(100.0, ("Kd", "n"))
    name = "pd-plus"
    code = 5


# 2. the layout, from the fields: [p, theta (p), Kp (n), Kd (n)]; the kernels read offsets from it only
LAYOUT = Layout.of(PDPlus)
_KP, _KD = LAYOUT.index("Kp"), LAYOUT.index("Kd")
USES_XI = False  # theta_eff does not depend on xi = Y^T r: the engine skips that contraction


# 3. the value kernel (a leaf: it calls no other jitted function; ``at`` is plain Python outside numba)
@njit(**_INLINE)
def signals(cp, q, qd, ref, v, a, r, w):
    """v = qd_d, a = qdd_d (so Y theta_0 = M qdd_d + C(q, qd) qd_d + g), r = 0,
    w = Kp (q_d - q) + Kd (qd_d - qd); all (n,), ``ref`` rows q_d, qd_d, qdd_d."""
    n = q.shape[0]
    p = int(cp[0])
    kp, kd = at(_KP, n, p), at(_KD, n, p)
    for i in range(n):
        v[i] = ref[1, i]
        a[i] = ref[2, i]
        r[i] = 0.0
        w[i] = cp[kp + i] * (ref[0, i] - q[i]) + cp[kd + i] * (ref[1, i] - qd[i])


# 4. the derivative: slopes of v, a, r in (q_j, qd_j, t) and dw/d(q, qd, t)
@njit(**_DERIV)
def slopes(cp, n, ref, jerk, G, Wx):
    """``G`` (3, n, 3): v = qd_d and a = qdd_d move with t only (slopes qdd_d and the jerk), r = 0;
    ``Wx`` (n, 2n + 1) = dw/d(q, qd, t) = (-Kp, -Kd, Kp qd_d + Kd qdd_d) on the diagonal."""
    p = int(cp[0])
    kpo, kdo = at(_KP, n, p), at(_KD, n, p)
    for i in range(n):
        for c in range(2 * n + 1):
            Wx[i, c] = 0.0
    for j in range(n):
        kp, kd = cp[kpo + j], cp[kdo + j]
        G[0, j, 0], G[0, j, 1], G[0, j, 2] = 0.0, 0.0, ref[2, j]
        G[1, j, 0], G[1, j, 1], G[1, j, 2] = 0.0, 0.0, jerk[j]
        G[2, j, 0], G[2, j, 1], G[2, j, 2] = 0.0, 0.0, 0.0
        Wx[j, j], Wx[j, n + j], Wx[j, 2 * n] = -kp, -kd, kp * ref[1, j] + kd * ref[2, j]


# 5. the C port: constants from the packed vector (through LAYOUT), the per-joint signals, the output
def c_source(law, n: int) -> dict:
    """The law in C (:func:`rc3r.export.c.controller_sources`): ``rc3r_theta0``, ``rc3r_Kp``, ``rc3r_Kd``,
    the per-joint body of ``rc3r_law_signals`` and the body of ``rc3r_law_output``."""
    return {"constants": c_constants(law, n),
            "signals": """        v[i] = ref[1][i];
        a[i] = ref[2][i];
        r[i] = 0.0;
        w[i] = rc3r_Kp[i] * (ref[0][i] - q[i]) + rc3r_Kd[i] * (ref[1][i] - qd[i]);""",
            "output": C_FIXED_OUTPUT}


register_law(PDPlus)
