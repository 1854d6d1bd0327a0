r"""The closed loop's Jacobian by the chain rule, for a kernel supply with analytic derivatives (numba).

A Rosenbrock step needs :math:`J = \partial f/\partial x` and :math:`f_t = \partial f/\partial t` of the
closed loop :math:`f(t, x) = (\dot q,\ \ddot q,\ \dot z)`. By forward differences that is one right-hand
side per state and one for t: 7 of RODAS's 13 evaluations per step on the 3R. When the kernel supply
defines ``tangents_into`` and ``plant_tangents_into`` (:mod:`._template`; the 3R's come from SymPy,
:mod:`rc3r.robots.rr3.tangents`), :func:`rc3r.simulate.engines.compiled._tangent_jacobian` composes
them instead, exactly (to rounding). With the columns ``c = (q, qd, t)`` (m = 2n + 1) and the law's
signals ``(v, a, r, w)`` (slopes ``G``, ``W_x`` of the law's ``slopes`` kernel, :mod:`rc3r.controllers.base`):

.. math::

    U_c &= W_x + D\,Z_c + Y\,\Theta_c, \qquad
    \Xi_c = X\,Z_c + Y^T R_c, \qquad \Theta_c = \partial\theta_{\mathrm{eff}}/\partial\xi\ \Xi_c, \\
    M(q)\,\ddot q_c &= \partial\tau/\partial u_a\ \partial u_a/\partial u\ U_c + \partial\tau/\partial c
    - \partial(M(q)\ddot q + C(q, \dot q)\dot q + g(q))/\partial c,

where ``D`` = d(Y theta_eff)/d(q, qd, v, a), ``X`` = d(Y^T r)/d(q, qd, v, a), ``Z_c`` the slopes of
``(q, qd, v, a)``, ``u_a`` the torque after the actuator's clip (slope 0 on a clipped joint) and
``tau = u_a + sum_k tau_k(qd)`` (the effects' slopes come from their own modules, :func:`finish`). The
law-independent parts are here (:func:`signal_columns`, :func:`finish`); a
law's own (``Theta_c`` through its ``directions`` and ``theta_columns``, the adaptive law's columns of z
``U_z = Y`` and ``dz/dt = -Gamma xi`` through ``state_gain``) are in its module, and the dispatch
(:mod:`._dispatch`) joins them.
A law with a scheduled ``K_inertia`` is differentiated numerically (the caller falls back).
``tests/test_jacobian.py`` checks J and f_t against central differences of the right-hand side for
every compiled law, with friction and a clipping torque limit.
"""
from __future__ import annotations


import numpy as np
from numba import njit

from rc3r.simulate.engines._linalg import _lu_factor

_JIT = dict(cache=True, nogil=True, error_model="numpy")
_INLINE = dict(_JIT, inline="always")  # the helpers of the dispatch's law_jacobian: one copy, in it


@njit(**_JIT)
def work(n, p, nz):
    """Scratch of the analytic Jacobian (:func:`rc3r.simulate.engines.compiled._tangent_jacobian`) for n joints,
    p coefficients and nz controller states: ``(D, Dp, yt, G, Wx, Ux, Xi, jerk, TB, xs, om, Mw, piv, DA, bt, es)``;
    ``TB`` (R, p) the directions b of the law's ``directions`` kernel, ``DA`` (R, n, 4n) the supply's tangents
    at them; ``xs`` xi, ``om`` and ``bt`` its weights (:mod:`rc3r.controllers.base`); ``es`` (2, n) the plant
    effects' slopes (``effect_slopes`` of the engine's effect dispatch)."""
    m = 2 * n + 1
    R = max(n, nz) + 1
    return (np.empty((n, 4 * n)), np.empty((n, 4 * n)), np.empty(n), np.empty((3, n, 3)), np.empty((n, m)),
            np.empty((n, m + nz)), np.empty((R, m)), np.empty(n), np.empty((R, p)), np.empty(p), np.empty(p),
            np.empty((n, n)), np.zeros(n, dtype=np.int64), np.empty((R, n, 4 * n)), np.empty(1), np.empty((2, n)))


@njit(**_INLINE)
def through_signals(D, G, out):
    """``out[:, :2n+1]`` = D Z_c: the slope through ``(q, qd, v, a)`` (D (rows, 4n)) of columns (q, qd, t),
    where ``dq/dq = dqd/dqd = I`` and the slopes of v, a are the diagonal ``G[0]``, ``G[1]``."""
    n = G.shape[1]
    for i in range(D.shape[0]):
        acc = 0.0
        for j in range(n):
            dv, da = D[i, 2 * n + j], D[i, 3 * n + j]
            out[i, j] = D[i, j] + dv * G[0, j, 0] + da * G[1, j, 0]
            out[i, n + j] = D[i, n + j] + dv * G[0, j, 1] + da * G[1, j, 1]
            acc += dv * G[0, j, 2] + da * G[1, j, 2]
        out[i, 2 * n] = acc


@njit(**_INLINE)
def finish(es, x, Dp, Ux, Xi, gam, J, Ft, Mw, piv):
    """From ``Ux`` (n, 2n + 1 + nz) = du/d(q, qd, t, z) of the law's torque ``u``: through the plant effects'
    slopes ``es`` (2, n) (row 0 ``d u_a / d u`` of the actuators, 0 on a clipped joint; row 1 the joint
    torques' damping ``-d tau / d qd``; each effect's ``slope_kernel``, gathered by the engine's effect
    dispatch), then the plant (``Dp`` of ``plant_tangents_into`` at the state's qdd), fill ``J`` (N, N) and
    ``Ft`` (N,). ``gam`` (nz,): the adaptive law's Gamma (``dz/dt = -Gamma xi``, rows of ``Xi`` = d xi/d(q, qd,
    t)); empty otherwise. ``Mw`` (n, n), ``piv`` (n,): scratch. False if M(q) is singular."""
    n = es.shape[1]
    N = x.shape[0]
    nz = N - 2 * n
    m = 2 * n + 1
    for i in range(n):
        g = es[0, i]
        if g != 1.0:  # clipped (slope 0): the delivered torque does not move
            for c in range(m + nz):
                Ux[i, c] = 0.0 if g == 0.0 else Ux[i, c] * g
        Ux[i, n + i] -= es[1, i]  # tau = u_a + sum_k tau_k(qd)
        for j in range(n):
            Ux[i, j] -= Dp[i, j]
            Ux[i, n + j] -= Dp[i, n + j] + Dp[i, 2 * n + j]
            Mw[i, j] = Dp[i, 3 * n + j]
    if not _lu_factor(Mw, piv):
        return False
    for c in range(m + nz):  # Ux <- M^-1 Ux, column by column (the steps of _lu_solve, inline)
        for k in range(n):
            pk = piv[k]
            if pk != k:
                tmp = Ux[k, c]
                Ux[k, c] = Ux[pk, c]
                Ux[pk, c] = tmp
        for i in range(n):
            acc = Ux[i, c]
            for j in range(i):
                acc -= Mw[i, j] * Ux[j, c]
            Ux[i, c] = acc
        for i in range(n - 1, -1, -1):
            acc = Ux[i, c]
            for j in range(i + 1, n):
                acc -= Mw[i, j] * Ux[j, c]
            Ux[i, c] = acc / Mw[i, i]
    for i in range(N):
        for j in range(N):
            J[i, j] = 0.0
        Ft[i] = 0.0
    for i in range(n):
        J[i, n + i] = 1.0
        for j in range(2 * n):
            J[n + i, j] = Ux[i, j]
        for k in range(nz):
            J[n + i, 2 * n + k] = Ux[i, m + k]
        Ft[n + i] = Ux[i, 2 * n]
    for k in range(nz):
        for j in range(2 * n):
            J[2 * n + k, j] = -gam[k] * Xi[k, j]
        Ft[2 * n + k] = -gam[k] * Xi[k, 2 * n]
    return True


@njit(**_INLINE)
def row_slope(D, r, G, yt, out):
    """``out`` (m,) = d(b^T Y^T r)/d(q, qd, t) at fixed ``b``: ``r^T D Z_c`` (``D`` = d(Y b)/dz from
    ``tangents_into`` at ``b``, the slopes Z_c of ``G`` as in :func:`through_signals`) plus ``yt^T R_c``
    (``yt`` = Y b, the slope of r ``G[2]``)."""
    n = r.shape[0]
    acc_t = 0.0
    for j in range(n):
        cq, cqd, cv, ca = 0.0, 0.0, 0.0, 0.0
        for i in range(n):
            ri = r[i]
            cq += ri * D[i, j]
            cqd += ri * D[i, n + j]
            cv += ri * D[i, 2 * n + j]
            ca += ri * D[i, 3 * n + j]
        out[j] = cq + cv * G[0, j, 0] + ca * G[1, j, 0] + G[2, j, 0] * yt[j]
        out[n + j] = cqd + cv * G[0, j, 1] + ca * G[1, j, 1] + G[2, j, 1] * yt[j]
        acc_t += cv * G[0, j, 2] + ca * G[1, j, 2] + G[2, j, 2] * yt[j]
    out[2 * n] = acc_t


@njit(**_INLINE)
def signal_columns(Y, r, rows, tw):
    """The law-independent part of ``U_c`` and ``Xi_c`` (module docstring): ``Ux[:, :2n+1]`` (``tw[5]``) =
    ``W_x + D Z_c`` and, for each of the ``rows`` directions b of the law's ``directions`` (``tw[8]``, the
    supply's tangents at them in ``tw[13]``), ``Xi[i]`` (``tw[6]``) = ``b_i^T dxi/dc``. The law's own part
    (its ``theta_columns``) and :func:`finish` follow (the dispatch's ``law_jacobian``, :mod:`._dispatch`)."""
    D, yt, G, Wx, Ux, Xi, TB, DA = tw[0], tw[2], tw[3], tw[4], tw[5], tw[6], tw[8], tw[13]
    n, p = Y.shape
    m = 2 * n + 1
    through_signals(D, G, Ux)  # U_c = W_c + d(Y theta_eff)/dz Z_c (+ Y dtheta_eff/dc: the law's)
    for i in range(n):
        for c in range(m):
            Ux[i, c] += Wx[i, c]
    for i in range(rows):  # Xi[i] = b_i^T dxi/dc = r^T d(Y b_i)/dz Z_c + (Y b_i)^T R_c
        for j in range(n):
            acc = 0.0
            for k in range(p):
                acc += Y[j, k] * TB[i, k]
            yt[j] = acc
        row_slope(DA[i], r, G, yt, Xi[i])
