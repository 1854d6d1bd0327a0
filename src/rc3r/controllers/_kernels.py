r"""Compiled kernels of the built-in control laws, generic over n joints and p coefficients.

Every law here has the form :math:`u = Y(q, \dot q, v, a)\,\theta_{\mathrm{eff}} + w`,
computed in two stages around the robot's regressor:

1. :func:`law_signals` -- from the state and the reference ``ref`` (rows
   :math:`q_d, \dot q_d, \ddot q_d`), the regressor arguments ``v``, ``a``, the
   sliding variable ``r`` and the additive term ``w``;
2. the caller evaluates ``Y = Y(q, qd, v, a)`` with its robot's kernel;
3. :func:`regressor_transpose` -- ``xi = Y^T r`` (the laws for which :func:`uses_xi`);
4. :func:`law_theta` -- :math:`\theta_{\mathrm{eff}}` from ``xi`` (in place), the
   controller-state rate ``zdot``, and :math:`\|Y^T r\|` for diagnostics;
5. :func:`apply_regressor` -- ``u = Y th_eff + w``.

Only ``xi = Y^T r`` and ``Y th_eff`` enter: a robot's kernel supply may compute both without
forming ``Y`` (:mod:`rc3r.robots.pinocchio_supply`, O(n)) and call :func:`law_theta` between them.
Each stage is a leaf (it calls no other jitted function), so its ``py_func`` runs without
compiling anything (the cold start, :func:`rc3r._numba_cache.ready_or_python`).

The law is picked by an integer ``code`` (a short static dispatch: numba does
not cache a function that receives another jitted function as an argument).
``cp`` packs ``[p, theta (p), gains ...]``; each law class's ``pack`` documents
its layout. The arithmetic of every law is written once, here; the Python path
(:meth:`rc3r.controllers.Law.torque`) calls these same kernels.
"""
from __future__ import annotations

import math

from numba import njit

FBL, ROBUST, ROBUST_COEFF, ADAPTIVE, PD = 0, 1, 2, 3, 4

_JIT = dict(cache=True, nogil=True)

#: Inlined into the caller at numba IR level: a robot's compiled simulator calls these once or
#: more per right-hand side, and a separate call with a dozen array arguments costs more than
#: the law's arithmetic (measured: 1.47x on the 10 s robust run without inlining).
_INLINE = dict(_JIT, inline="always")


@njit(**_INLINE)
def law_signals(code, cp, q, qd, ref, v, a, r, w):
    """Fill v, a (regressor arguments), r (sliding variable) and w (additive torque), each (n,)."""
    n = q.shape[0]
    p = int(cp[0])
    g = 1 + p  # first gain
    if code == FBL:
        # computed torque: v = qd, a = qdd_d + Kd (qd_d - qd) + Kp (q_d - q), w = 0
        for i in range(n):
            v[i] = qd[i]
            a[i] = ref[2, i] + cp[g + n + i] * (ref[1, i] - qd[i]) + cp[g + i] * (ref[0, i] - q[i])
            r[i] = 0.0
            w[i] = 0.0
    elif code == PD:
        # PD + gravity: Y(q, qd, 0, 0) theta = g(q); w = Kp (q_d - q) + Kd (qd_d - qd)
        for i in range(n):
            v[i] = 0.0
            a[i] = 0.0
            r[i] = 0.0
            w[i] = cp[g + i] * (ref[0, i] - q[i]) + cp[g + n + i] * (ref[1, i] - qd[i])
    else:
        # sliding laws: e = q - q_d, v = qd_d - Lambda e, a = qdd_d - Lambda e_dot,
        # r = qd - v = e_dot + Lambda e, w = -K r (K diagonal, plus its off-diagonal part if packed;
        # the scheduled -K_inertia M(q) r is the caller's: it needs the robot, :func:`inertia_gain`)
        for i in range(n):
            lam = cp[g + n + i]
            e = q[i] - ref[0, i]
            ed = qd[i] - ref[1, i]
            r[i] = ed + lam * e
            v[i] = ref[1, i] - lam * e
            a[i] = ref[2, i] - lam * ed
            w[i] = -cp[g + i] * r[i]
        o = tail(code, cp, n)  # [K_inertia, has_matrix, off-diagonal K (n * n)]
        if cp[o + 1] != 0.0:  # a matrix K: its off-diagonal part, row-major
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += cp[o + 2 + i * n + j] * r[j]
                w[i] -= acc


@njit(**_INLINE)
def tail(code, cp, n):
    """Index in ``cp`` of a sliding law's tail ``[K_inertia, has_matrix, ...]`` (after the law's own entries)."""
    p = int(cp[0])
    return 1 + p + 2 * n + (2 if code == ROBUST else 2 * p if code == ROBUST_COEFF else p)


@njit(**_INLINE)
def inertia_gain(code, cp, n):
    """A sliding law's ``K_inertia`` b [1/s] (0 for FBL and PD): the caller subtracts ``b M(q) r`` from w."""
    if code == FBL or code == PD:
        return 0.0
    return cp[tail(code, cp, n)]


@njit(**_INLINE)
def uses_xi(code):
    """True if the law ``code`` needs ``xi = Y^T r`` (every law but FBL and PD)."""
    return code != FBL and code != PD


@njit(**_INLINE)
def regressor_transpose(Y, r, xi):
    """xi (p,) = Y^T r."""
    n, p = Y.shape
    for j in range(p):
        acc = 0.0
        for i in range(n):
            acc += Y[i, j] * r[i]
        xi[j] = acc


@njit(**_INLINE)
def law_theta(code, cp, n, z, th_eff, zdot):
    """From ``th_eff`` = xi = Y^T r (ignored by FBL and PD) of an n-joint arm: the effective parameters
    into ``th_eff`` and ``zdot``; returns ||xi|| (0 for FBL and PD). A supply that contracts Y without forming it
    (:mod:`rc3r.robots.pinocchio_supply`) calls this after its own ``xi_into``."""
    p = int(cp[0])
    if code == FBL or code == PD:
        for j in range(p):
            th_eff[j] = cp[1 + j]
        return 0.0
    nrm2 = 0.0
    for j in range(p):
        nrm2 += th_eff[j] * th_eff[j]
    nrm = math.sqrt(nrm2)
    s = 1 + p + 2 * n  # first law-specific entry after theta, K, Lambda
    if code == ROBUST:
        # eq. (6): delta = -rho xi / max(||xi||, eps)
        scale = cp[s] / max(nrm, cp[s + 1])
        for j in range(p):
            th_eff[j] = cp[1 + j] - scale * th_eff[j]
    elif code == ROBUST_COEFF:
        # eq. (7): delta_i = -rho_i xi_i / max(|xi_i|, eps_i)
        for j in range(p):
            th_eff[j] = cp[1 + j] - cp[s + j] * th_eff[j] / max(abs(th_eff[j]), cp[s + p + j])
    else:  # ADAPTIVE: theta_hat is the controller state z; d theta_hat/dt = -Gamma Y^T r
        for j in range(p):
            zdot[j] = -cp[s + j] * th_eff[j]
            th_eff[j] = z[j]
    return nrm


@njit(**_INLINE)
def apply_regressor(Y, th_eff, w, u):
    """u = w + Y th_eff, shape (n,)."""
    n, p = Y.shape
    for i in range(n):
        acc = 0.0
        for j in range(p):
            acc += Y[i, j] * th_eff[j]
        u[i] = w[i] + acc


# ---- derivatives, for the compiled engine's analytic Jacobian (rc3r.simulate.engines._jacobian) ----


@njit(**_INLINE)
def law_slopes(code, cp, n, ref, jerk, G, Wx):
    r"""Slopes of the law's signals in the state and time, for a law with ``inertia_gain == 0``.

    ``G`` (3, n, 3): ``G[k, j] = (d s_j/d q_j, d s_j/d qd_j, d s_j/d t)`` for the signals
    ``s = v, a, r`` (k = 0, 1, 2); each depends on joint j's own q, qd only (diagonal gains).
    ``Wx`` (n, 2n + 1): ``dw/d(q, qd, t)`` of the additive term (the full K of a sliding law).
    ``ref`` rows q_d, qd_d, qdd_d and ``jerk`` (n,) its third derivative at t.
    """
    p = int(cp[0])
    g = 1 + p
    for i in range(n):
        for c in range(2 * n + 1):
            Wx[i, c] = 0.0
    if code == FBL:  # v = qd, a = qdd_d + Kd (qd_d - qd) + Kp (q_d - q)
        for j in range(n):
            kp, kd = cp[g + j], cp[g + n + j]
            G[0, j, 0], G[0, j, 1], G[0, j, 2] = 0.0, 1.0, 0.0
            G[1, j, 0], G[1, j, 1], G[1, j, 2] = -kp, -kd, jerk[j] + kd * ref[2, j] + kp * ref[1, j]
            G[2, j, 0], G[2, j, 1], G[2, j, 2] = 0.0, 0.0, 0.0
    elif code == PD:  # v = a = 0, w = Kp (q_d - q) + Kd (qd_d - qd)
        for j in range(n):
            kp, kd = cp[g + j], cp[g + n + j]
            for k in range(3):
                G[k, j, 0], G[k, j, 1], G[k, j, 2] = 0.0, 0.0, 0.0
            Wx[j, j], Wx[j, n + j], Wx[j, 2 * n] = -kp, -kd, kp * ref[1, j] + kd * ref[2, j]
    else:  # v = qd_d - L e, a = qdd_d - L e_dot, r = e_dot + L e, w = -K r
        for j in range(n):
            lam = cp[g + n + j]
            G[0, j, 0], G[0, j, 1], G[0, j, 2] = -lam, 0.0, ref[2, j] + lam * ref[1, j]
            G[1, j, 0], G[1, j, 1], G[1, j, 2] = 0.0, -lam, jerk[j] + lam * ref[2, j]
            G[2, j, 0], G[2, j, 1], G[2, j, 2] = lam, 1.0, -(ref[2, j] + lam * ref[1, j])
        o = tail(code, cp, n)
        full = cp[o + 1] != 0.0
        for i in range(n):
            for j in range(n):
                kij = (cp[g + i] if i == j else 0.0) + (cp[o + 2 + i * n + j] if full else 0.0)
                Wx[i, j] = -kij * G[2, j, 0]
                Wx[i, n + j] = -kij
                Wx[i, 2 * n] -= kij * G[2, j, 2]
