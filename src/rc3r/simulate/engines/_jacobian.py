r"""The closed loop's Jacobian by the chain rule, for a kernel supply with analytic derivatives (numba).

A Rosenbrock step needs :math:`J = \partial f/\partial x` and :math:`f_t = \partial f/\partial t` of the
closed loop :math:`f(t, x) = (\dot q,\ \ddot q,\ \dot z)`. By forward differences that is one right-hand
side per state and one for t: 7 of RODAS's 13 evaluations per step on the 3R. When the kernel supply
defines ``tangents_into`` and ``plant_tangents_into`` (:mod:`._template`; the 3R's come from SymPy,
:mod:`rc3r.robots.rr3.tangents`), :func:`rc3r.simulate.engines.compiled._tangent_jacobian` composes
them instead, exactly (to rounding). With the columns ``c = (q, qd, t)`` (m = 2n + 1) and the law's
signals ``(v, a, r, w)`` (slopes ``G``, ``W_x`` of :func:`rc3r.controllers._kernels.law_slopes`):

.. math::

    U_c &= W_x + D\,Z_c + Y\,\Theta_c, \qquad
    \Xi_c = X\,Z_c + Y^T R_c, \qquad \Theta_c = \partial\theta_{\mathrm{eff}}/\partial\xi\ \Xi_c, \\
    M(q)\,\ddot q_c &= \partial\tau/\partial u_a\ \partial u_a/\partial u\ U_c + \partial\tau/\partial c
    - \partial(M(q)\ddot q + C(q, \dot q)\dot q + g(q))/\partial c,

where ``D`` = d(Y theta_eff)/d(q, qd, v, a), ``X`` = d(Y^T r)/d(q, qd, v, a), ``Z_c`` the slopes of
``(q, qd, v, a)``, ``u_a`` the torque after the actuator's clip (slope 0 on a clipped joint) and
``tau = u_a + sum_k tau_k(qd)`` (the effects' slopes come from their own modules, :func:`finish`). The
adaptive law adds the columns of z: ``U_z = Y``, ``dz/dt = -Gamma xi``.
A law with a scheduled ``K_inertia`` is differentiated numerically (the caller falls back).
``tests/test_jacobian.py`` checks J and f_t against central differences of the right-hand side for
every compiled law, with friction and a clipping torque limit.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from rc3r.controllers._kernels import ROBUST, regressor_transpose, uses_xi
from rc3r.simulate.engines._linalg import _lu_factor

_JIT = dict(cache=True, nogil=True, error_model="numpy")
_INLINE = dict(_JIT, inline="always")  # the helpers of compose: one copy, in it


@njit(**_JIT)
def work(n, p, nz):
    """Scratch of :func:`compose` and :func:`rc3r.simulate.engines.compiled._tangent_jacobian` for n joints,
    p coefficients and nz controller states: ``(D, Dp, yt, G, Wx, Ux, Xi, jerk, TB, xs, om, Mw, piv, DA, bt, es)``;
    ``TB`` (R, p) the directions b of :func:`xi_rows`, ``DA`` (R, n, 4n) the supply's tangents at them, ``es``
    (2, n) the plant effects' slopes (``effect_slopes`` of the engine's effect dispatch)."""
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
def robust_weights(code, cp, n, xi, om):
    r"""The robust laws' ``d theta_eff = diag(om) d xi + beta xi (xi^T d xi)``; returns beta.

    Eq. (6), ``theta_eff = theta_0 - rho xi / max(||xi||, eps)``: ``om = -rho / max(||xi||, eps)``, and
    ``beta = rho / ||xi||^3`` outside the layer, 0 inside. Eq. (7), per coefficient: ``om_k = -rho_k / eps_k``
    inside its layer ``|xi_k| <= eps_k``, 0 outside (there theta_k = theta_0k - rho_k sign(xi_k)), beta = 0.
    """
    p = xi.shape[0]
    s = 1 + p + 2 * n
    if code == ROBUST:
        nrm = 0.0
        for k in range(p):
            nrm += xi[k] * xi[k]
        nrm = math.sqrt(nrm)
        rho, eps = cp[s], cp[s + 1]
        o = -rho / max(nrm, eps)
        for k in range(p):
            om[k] = o
        return rho / (nrm * nrm * nrm) if nrm > eps else 0.0
    for k in range(p):
        om[k] = -cp[s + k] / cp[s + p + k] if abs(xi[k]) <= cp[s + p + k] else 0.0
    return 0.0


@njit(**_JIT)
def xi_rows(law, cp, Y, r, tw):
    """Fill ``tw``'s ``TB`` with the directions b whose ``b^T d(Y^T r)`` the law needs and return their count:
    none for FBL and PD; the unit vectors (the p rows of d xi) for the adaptive law; for the robust laws
    ``om * Y[i]`` (i < n) and ``xi`` (:func:`robust_weights`; beta into ``tw``'s ``bt``). Also ``xs`` = xi."""
    TB, xs, om, bt = tw[8], tw[9], tw[10], tw[14]
    n, p = Y.shape
    if not uses_xi(law):
        return 0
    regressor_transpose(Y, r, xs)
    if tw[5].shape[1] > 2 * n + 1:  # controller states: the adaptive law
        for i in range(p):
            for k in range(p):
                TB[i, k] = 1.0 if k == i else 0.0
        return p
    bt[0] = robust_weights(law, cp, n, xs, om)
    for i in range(n + 1):
        for k in range(p):
            TB[i, k] = om[k] * Y[i, k] if i < n else xs[k]
    return n + 1


@njit(**_JIT)
def compose(law, cp, es, x, u, Y, r, rows, tw, J, Ft):
    """``J`` (N, N), ``Ft`` (N,) of the closed loop at x (module docstring) from the law's torque ``u``, the
    formed ``Y``, ``r``, the plant effects' slopes ``es`` (:func:`finish`), and in ``tw`` the supply's tangents
    ``D`` (at theta_eff), ``Dp`` (the plant's), ``DA[:rows]`` (at the directions of :func:`xi_rows`) and the
    law's slopes ``G``, ``Wx``. False if M(q) is singular."""
    D, Dp, yt, G, Wx, Ux, Xi, TB, xs, DA, bt = tw[0], tw[1], tw[2], tw[3], tw[4], tw[5], tw[6], tw[8], tw[9], \
        tw[13], tw[14]
    n, p = Y.shape
    m = 2 * n + 1
    nz = x.shape[0] - 2 * n
    through_signals(D, G, Ux)  # U_c = W_c + d(Y theta_eff)/dz Z_c (+ Y dtheta_eff/dc below)
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
    if rows > 0 and nz == 0:  # robust: Y dtheta/dc = Y diag(om) dxi/dc + beta (Y xi)(xi^T dxi/dc)
        for i in range(n):
            yx = 0.0
            for k in range(p):
                yx += Y[i, k] * xs[k]
            for c in range(m):
                Ux[i, c] += Xi[i, c] + bt[0] * yx * Xi[n, c]
    for i in range(n):  # adaptive: u = w + Y z
        for k in range(nz):
            Ux[i, m + k] = Y[i, k]
    s = 1 + p + 2 * n
    return finish(es, x, Dp, Ux, Xi, cp[s:s + nz], J, Ft, tw[11], tw[12])
