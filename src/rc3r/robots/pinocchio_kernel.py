r"""Compiled (numba) Slotine--Li regressor of a serial chain of revolute/prismatic joints.

:class:`~rc3r.robots.pinocchio.PinocchioRobot` gets its regressor from two calls
of Pinocchio's ``computeJointTorqueRegressor`` per state (the reference path,
``PinocchioRobot.regressor_pinocchio``); through Python that costs ~5-7 ``rnea``
calls per state. This kernel computes the same matrix from the model's
kinematic constants (read once from the ``pinocchio.Model``) in one compiled
loop over the states, ~1-2 ``rnea`` calls per state, and
``tests/test_robot_pinocchio.py`` checks it against the Pinocchio path to 1e-12.

Algorithm (spatial vectors ``(linear, angular)`` as in Pinocchio). Joint ``j``
has parent ``lambda(j)`` (bodies and joints are numbered alike; with 1-DoF
joints joint ``j`` is velocity ``j``), fixed placement ``(R0_j, p0_j)`` in its
parent's frame and a constant motion subspace in its own frame: ``(0, u_j)``
(revolute about the unit axis ``u_j``) or ``(u_j, 0)`` (prismatic).
Forward pass in the world frame (spatial vectors about the world origin):

* ``R_j = R_lambda R0_j Rot(u_j, q_j)``, ``p_j = p_lambda + R_lambda p0_j`` (``+ w q_j``
  if prismatic), world axis ``w = R_j u_j``, ``S_j = (p_j x w, w)`` or ``(w, 0)``;
* for the two passes ``k`` of the polarization (module :mod:`rc3r.robots.pinocchio`:
  ``x = (qd + v)/2, b = a/2`` with gravity, minus ``x = (qd - v)/2, b = -a/2`` without):
  ``V_j = V_lambda + S_j x_j``, ``A_j = A_lambda + S_j b_j + V_j x (S_j x_j)``,
  ``A_0 = -gravity`` in the first pass only.

Body regressor (the Newton--Euler force ``I a + v x* (I v)`` of body ``j``, linear in
its 10 Pinocchio parameters ``(m, m c, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)`` about its
origin): with the local ``v, omega, a, alpha`` and ``a_c = a + omega x v``,

.. math::

    f = \begin{pmatrix} a_c & [\alpha]_\times + [\omega]_\times^2 & 0 \\
                        0 & -[a_c]_\times & L(\alpha) + [\omega]_\times L(\omega) \end{pmatrix},
    \qquad \bar I x = L(x)\,(I_{xx}, I_{xy}, I_{yy}, I_{xz}, I_{yz}, I_{zz}).

Pass 1 minus pass 2 (:func:`_body_regressor`), projected on every joint ``i`` that carries
body ``j``: ``Y[i, 10 j + c] = S_i . F_j[:, c]`` (``S_i`` carried into body j's frame).

Forward dynamics (the compiled engine's plant, :func:`_forward_dynamics_one`): the same world
frame, bias torques by Newton--Euler at ``qdd = 0``, M by the composite-rigid-body algorithm,
Cholesky (``tests/test_engines.py``: equal to ``pinocchio.aba`` to 1e-10 relative, UR5, Panda).
The compiled engine's kernel supply of a chain, on :meth:`ChainKernel.pack`'s ``kc``, is
:mod:`rc3r.robots.pinocchio_supply` (these kernels and the law's O(n) contractions of ``Y``).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .. import _numba_cache

__all__ = ["ChainKernel"]

_JIT = dict(cache=True, nogil=True, fastmath=False)
#: The dotted name of the chain's kernel supply (:meth:`ChainKernel.supply`).
SUPPLY = "rc3r.robots.pinocchio_supply"
_INLINE = dict(_JIT, inline="always")


@njit(**_JIT)
def _cross(x, y, out):
    """out = x x y (3-vectors; out must not alias x or y)."""
    out[0] = x[1] * y[2] - x[2] * y[1]
    out[1] = x[2] * y[0] - x[0] * y[2]
    out[2] = x[0] * y[1] - x[1] * y[0]


@njit(**_JIT)
def _mv(R, x, out, transpose):
    """out = R x (or R^T x), R (3, 3)."""
    for r in range(3):
        if transpose:
            out[r] = R[0, r] * x[0] + R[1, r] * x[1] + R[2, r] * x[2]
        else:
            out[r] = R[r, 0] * x[0] + R[r, 1] * x[1] + R[r, 2] * x[2]


@njit(**_INLINE)
def _body_regressor(L, F):
    """F (6, 10) = the Newton--Euler regressor of one body, pass 1 minus pass 2 (module docstring), from the
    local ``L`` rows: v1, omega1, v2, omega2 of the two passes, a1 - a2, alpha1 - alpha2. Linear in
    ``a_c = a + omega x v`` and alpha, quadratic in omega only through ``D_ab = w1_a w1_b - w2_a w2_b``."""
    v1x, v1y, v1z, w1x, w1y, w1z = L[0, 0], L[0, 1], L[0, 2], L[1, 0], L[1, 1], L[1, 2]
    v2x, v2y, v2z, w2x, w2y, w2z = L[2, 0], L[2, 1], L[2, 2], L[3, 0], L[3, 1], L[3, 2]
    c0 = L[4, 0] + (w1y * v1z - w1z * v1y) - (w2y * v2z - w2z * v2y)  # a_c1 - a_c2
    c1 = L[4, 1] + (w1z * v1x - w1x * v1z) - (w2z * v2x - w2x * v2z)
    c2 = L[4, 2] + (w1x * v1y - w1y * v1x) - (w2x * v2y - w2y * v2x)
    a0, a1, a2 = L[5, 0], L[5, 1], L[5, 2]
    d00, d11, d22 = w1x * w1x - w2x * w2x, w1y * w1y - w2y * w2y, w1z * w1z - w2z * w2z
    d01, d02, d12 = w1x * w1y - w2x * w2y, w1x * w1z - w2x * w2z, w1y * w1z - w2y * w2z
    tr = d00 + d11 + d22
    F[:, :] = 0.0
    F[0, 0], F[1, 0], F[2, 0] = c0, c1, c2  # m: f = a_c
    # m c_k: f = alpha x e_k + omega omega_k - |omega|^2 e_k, n = e_k x a_c
    F[0, 1], F[1, 1], F[2, 1] = d00 - tr, d01 + a2, d02 - a1
    F[0, 2], F[1, 2], F[2, 2] = d01 - a2, d11 - tr, d12 + a0
    F[0, 3], F[1, 3], F[2, 3] = d02 + a1, d12 - a0, d22 - tr
    F[4, 1], F[5, 1] = -c2, c1
    F[3, 2], F[5, 2] = c2, -c0
    F[3, 3], F[4, 3] = -c1, c0
    # (Ixx, Ixy, Iyy, Ixz, Iyz, Izz): n = L(alpha) + omega x L(omega)
    F[3, 4], F[4, 4], F[5, 4] = a0, d02, -d01
    F[3, 5], F[4, 5], F[5, 5] = a1 - d02, a0 + d12, d00 - d11
    F[3, 6], F[4, 6], F[5, 6] = -d12, a1, d01
    F[3, 7], F[4, 7], F[5, 7] = a2 + d01, d22 - d00, a0 - d12
    F[3, 8], F[4, 8], F[5, 8] = d11 - d22, a2 - d01, a1 + d02
    F[3, 9], F[4, 9], F[5, 9] = d12, -d02, a2


@njit(**_INLINE)
def _kinematics(q, geo, ints, R, P, S, Rl, t, t2, ac):
    """World rotation ``R[j]``, origin ``P[j]`` and motion subspace ``S[j]`` (about the world origin)
    of every joint at ``q``. ``geo`` (n + 1, 15): per joint ``R0`` (row-major), ``p0``, axis; row n:
    gravity (6). ``ints`` (n, n + 2): parent (-1: base), revolute flag, ``support[i, j]``."""
    n = q.shape[0]
    for j in range(n):
        lam = int(ints[j, 0])
        u = geo[j, 12:15]
        for r in range(3):  # Rl = R_lambda R0_j, t = R_lambda p0_j
            if lam >= 0:
                for c in range(3):
                    Rl[r, c] = (R[lam, r, 0] * geo[j, c] + R[lam, r, 1] * geo[j, 3 + c]
                                + R[lam, r, 2] * geo[j, 6 + c])
                t[r] = P[lam, r] + R[lam, r, 0] * geo[j, 9] + R[lam, r, 1] * geo[j, 10] + R[lam, r, 2] * geo[j, 11]
            else:
                for c in range(3):
                    Rl[r, c] = geo[j, 3 * r + c]
                t[r] = geo[j, 9 + r]
        qj = q[j]
        _mv(Rl, u, t2, False)  # world axis w (invariant under the joint's own motion)
        if ints[j, 1]:  # R_j = Rl Rot(u, q): Rodrigues, Rl (I + sin K + (1 - cos) K^2)
            sq, cq = np.sin(qj), 1.0 - np.cos(qj)
            for r in range(3):  # row r of Rl K is Rl[r] x u; Rl K^2 = Rl (u u^T - I) = w u^T - Rl
                _cross(Rl[r], u, ac)
                for c in range(3):
                    R[j, r, c] = Rl[r, c] + sq * ac[c] + cq * (t2[r] * u[c] - Rl[r, c])
                P[j, r] = t[r]
            _cross(t, t2, ac)
            for r in range(3):
                S[j, r] = ac[r]
                S[j, 3 + r] = t2[r]
        else:
            for r in range(3):
                for c in range(3):
                    R[j, r, c] = Rl[r, c]
                P[j, r] = t[r] + t2[r] * qj
                S[j, r] = t2[r]
                S[j, 3 + r] = 0.0


@njit(**_INLINE)
def _regressor_one(q, qd, v, a, geo, ints, columns, need, out, wk):
    """Fill ``out`` (n, len(columns)) with columns of the standard-parameter Slotine--Li regressor at
    one state (``need[c]``: column c is among ``columns``; ``wk``: :func:`_work`'s arrays)."""
    R, P, S, Vel, Acc, Y, Rl, t, t2, ac, loc, F, xs = wk
    n = q.shape[0]
    _kinematics(q, geo, ints, R, P, S, Rl, t, t2, ac)
    Y[:, :] = 0.0
    for j in range(n):
        lam = int(ints[j, 0])
        for k in range(2):  # the two passes of the polarization
            xk = 0.5 * (qd[j] + v[j]) if k == 0 else 0.5 * (qd[j] - v[j])
            bk = 0.5 * a[j] if k == 0 else -0.5 * a[j]
            for r in range(6):
                xs[r] = S[j, r] * xk
                Vel[k, j, r] = (Vel[k, lam, r] if lam >= 0 else 0.0) + xs[r]
                g = geo[n, r] if k == 0 else 0.0
                Acc[k, j, r] = (Acc[k, lam, r] if lam >= 0 else -g) + S[j, r] * bk
            vj = Vel[k, j]  # A_j += V_j x (S x) = (omega x s_lin + v x s_ang, omega x s_ang)
            _cross(vj[3:], xs[:3], t)
            _cross(vj[:3], xs[3:], t2)
            for r in range(3):
                Acc[k, j, r] += t[r] + t2[r]
            _cross(vj[3:], xs[3:], t)
            for r in range(3):
                Acc[k, j, 3 + r] += t[r]
        for k in range(2):  # local v, omega of each pass: (R^T (lin + ang x p), R^T ang)
            M = Vel[k, j]
            _cross(M[3:], P[j], t)
            for r in range(3):
                t[r] += M[r]
            _mv(R[j], t, loc[2 * k], True)
            _mv(R[j], M[3:], loc[2 * k + 1], True)
        for r in range(6):  # the accelerations enter linearly: their difference only
            xs[r] = Acc[0, j, r] - Acc[1, j, r]
        _cross(xs[3:], P[j], t)
        for r in range(3):
            t[r] += xs[r]
        _mv(R[j], t, loc[4], True)
        _mv(R[j], xs[3:], loc[5], True)
        _body_regressor(loc, F)
        for i in range(n):  # S_i . F_O = s'_i . F with s'_i = (R^T (s_lin + s_ang x p), R^T s_ang) in body j's frame
            if ints[i, 2 + j]:
                _cross(S[i, 3:], P[j], t)
                for r in range(3):
                    t[r] += S[i, r]
                _mv(R[j], t, loc[0], True)
                _mv(R[j], S[i, 3:], loc[1], True)
                for c in range(10):
                    if need[10 * j + c]:
                        acc = 0.0
                        for r in range(3):
                            acc += loc[0, r] * F[r, c] + loc[1, r] * F[3 + r, c]
                        Y[i, 10 * j + c] = acc
    for i in range(n):
        for c in range(columns.size):
            out[i, c] = Y[i, int(columns[c])]


@njit(**_JIT)
def _regressor(X, geo, ints, columns, out):
    """Fill out (N, n, len(columns)) with columns of the standard-parameter Slotine--Li regressor.

    ``X`` (4, N, n): q, qd, v, a; ``geo``, ``ints`` as in :func:`_kinematics`. (Few arguments:
    numba's call overhead grows with their number.)
    """
    wk = _work(X.shape[2])
    need = _needed(columns, X.shape[2])
    for s in range(X.shape[1]):
        _regressor_one(X[0, s], X[1, s], X[2, s], X[3, s], geo, ints, columns, need, out[s], wk)


@njit(**_JIT)
def _needed(columns, n):
    """Mask (10 n,) of the standard-parameter columns in ``columns``."""
    need = np.zeros(10 * n, dtype=np.bool_)
    for c in range(columns.size):
        need[int(columns[c])] = True
    return need


@njit(**_INLINE)
def _crs(ax, ay, az, bx, by, bz):
    """a x b as three scalars."""
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(**_INLINE)
def _iapply(Iw, j, vx, vy, vz, wx, wy, wz):
    """The spatial inertia ``I = Iw[j] = (m, h = m c, I_O (xx, xy, yy, xz, yz, zz))`` about the world origin
    applied to the motion ``(v, omega)``: ``(m v - h x omega, h x v + I_O omega)``, six scalars."""
    I = Iw
    m, hx, hy, hz = I[j, 0], I[j, 1], I[j, 2], I[j, 3]
    cx, cy, cz = _crs(hx, hy, hz, wx, wy, wz)
    nx, ny, nz = _crs(hx, hy, hz, vx, vy, vz)
    return (m * vx - cx, m * vy - cy, m * vz - cz, nx + I[j, 4] * wx + I[j, 5] * wy + I[j, 7] * wz,
            ny + I[j, 5] * wx + I[j, 6] * wy + I[j, 8] * wz, nz + I[j, 7] * wx + I[j, 8] * wy + I[j, 9] * wz)


@njit(**_INLINE)
def _forward_dynamics_one(q, qd, tau, geoz, ints, piz, grav, qdd, wk):
    """``qdd = M^{-1} (tau - C qd - g)``; False if the Cholesky factorization of M fails (not PD).

    ``geoz`` (n, 12): per joint ``R0'`` (row-major) and ``p0'`` of the frames turned so that every
    joint axis is z (:meth:`ChainKernel.__init__`), ``piz`` (n, 10) the standard parameters in those
    frames, ``grav`` (6,). World frame, spatial vectors about the world origin (module docstring):
    bias forces by Newton--Euler at ``qdd = 0`` (``A_0 = -gravity``), ``f_j = I_j A_j + V_j x* (I_j V_j)``
    with each body's inertia carried to the origin (``h = m p + R (m c)``, ``I_O = R I R^T - (h p^T +
    p h^T) + m p p^T + (2 h.p - m p.p) 1``); M by the composite-rigid-body algorithm (``I^c`` of a
    subtree is the sum of its bodies' ``I``, ``M[i, j] = S_i . I^c_j S_j`` for i carrying j); then
    ``L L^T = M`` and two triangular solves. Scalar locals throughout (numba keeps them in registers).
    """
    R, P, S, V, A, Iw, Fb, Mm = wk
    n = q.shape[0]
    for j in range(n):
        lam = int(ints[j, 0])
        if lam >= 0:  # Rl = R_lambda R0', t = p_lambda + R_lambda p0'
            a00 = R[lam, 0] * geoz[j, 0] + R[lam, 1] * geoz[j, 3] + R[lam, 2] * geoz[j, 6]
            a01 = R[lam, 0] * geoz[j, 1] + R[lam, 1] * geoz[j, 4] + R[lam, 2] * geoz[j, 7]
            a02 = R[lam, 0] * geoz[j, 2] + R[lam, 1] * geoz[j, 5] + R[lam, 2] * geoz[j, 8]
            a10 = R[lam, 3] * geoz[j, 0] + R[lam, 4] * geoz[j, 3] + R[lam, 5] * geoz[j, 6]
            a11 = R[lam, 3] * geoz[j, 1] + R[lam, 4] * geoz[j, 4] + R[lam, 5] * geoz[j, 7]
            a12 = R[lam, 3] * geoz[j, 2] + R[lam, 4] * geoz[j, 5] + R[lam, 5] * geoz[j, 8]
            a20 = R[lam, 6] * geoz[j, 0] + R[lam, 7] * geoz[j, 3] + R[lam, 8] * geoz[j, 6]
            a21 = R[lam, 6] * geoz[j, 1] + R[lam, 7] * geoz[j, 4] + R[lam, 8] * geoz[j, 7]
            a22 = R[lam, 6] * geoz[j, 2] + R[lam, 7] * geoz[j, 5] + R[lam, 8] * geoz[j, 8]
            tx = P[lam, 0] + R[lam, 0] * geoz[j, 9] + R[lam, 1] * geoz[j, 10] + R[lam, 2] * geoz[j, 11]
            ty = P[lam, 1] + R[lam, 3] * geoz[j, 9] + R[lam, 4] * geoz[j, 10] + R[lam, 5] * geoz[j, 11]
            tz = P[lam, 2] + R[lam, 6] * geoz[j, 9] + R[lam, 7] * geoz[j, 10] + R[lam, 8] * geoz[j, 11]
            vx, vy, vz, wx, wy, wz = V[lam, 0], V[lam, 1], V[lam, 2], V[lam, 3], V[lam, 4], V[lam, 5]
            ax, ay, az, bx, by, bz = A[lam, 0], A[lam, 1], A[lam, 2], A[lam, 3], A[lam, 4], A[lam, 5]
        else:
            a00, a01, a02, a10, a11, a12, a20, a21, a22 = geoz[j, 0], geoz[j, 1], geoz[j, 2], geoz[j, 3], geoz[j, 4], geoz[j, 5], geoz[j, 6], geoz[j, 7], geoz[j, 8]
            tx, ty, tz = geoz[j, 9], geoz[j, 10], geoz[j, 11]
            vx = vy = vz = wx = wy = wz = 0.0
            ax, ay, az, bx, by, bz = -grav[0], -grav[1], -grav[2], -grav[3], -grav[4], -grav[5]
        ux, uy, uz = a02, a12, a22  # the world axis: Rot_z leaves the third column
        if ints[j, 1]:  # revolute: R = Rl Rot_z(q), S = (p x u, u)
            c, s = np.cos(q[j]), np.sin(q[j])
            r00, r01 = a00 * c + a01 * s, a01 * c - a00 * s
            r10, r11 = a10 * c + a11 * s, a11 * c - a10 * s
            r20, r21 = a20 * c + a21 * s, a21 * c - a20 * s
            s0, s1, s2 = _crs(tx, ty, tz, ux, uy, uz)
            s3, s4, s5 = ux, uy, uz
        else:  # prismatic: R = Rl, p = t + q u, S = (u, 0)
            r00, r01, r10, r11, r20, r21 = a00, a01, a10, a11, a20, a21
            tx, ty, tz = tx + ux * q[j], ty + uy * q[j], tz + uz * q[j]
            s0, s1, s2, s3, s4, s5 = ux, uy, uz, 0.0, 0.0, 0.0
        R[j, 0], R[j, 1], R[j, 2], R[j, 3], R[j, 4], R[j, 5], R[j, 6], R[j, 7], R[j, 8] = r00, r01, ux, r10, r11, uy, r20, r21, uz
        P[j, 0], P[j, 1], P[j, 2] = tx, ty, tz
        S[j, 0], S[j, 1], S[j, 2], S[j, 3], S[j, 4], S[j, 5] = s0, s1, s2, s3, s4, s5
        d = qd[j]  # V = V_lambda + S qd, A = A_lambda + V x (S qd)
        x0, x1, x2, x3, x4, x5 = s0 * d, s1 * d, s2 * d, s3 * d, s4 * d, s5 * d
        vx, vy, vz, wx, wy, wz = vx + x0, vy + x1, vz + x2, wx + x3, wy + x4, wz + x5
        c0, c1, c2 = _crs(wx, wy, wz, x0, x1, x2)
        e0, e1, e2 = _crs(vx, vy, vz, x3, x4, x5)
        f0, f1, f2 = _crs(wx, wy, wz, x3, x4, x5)
        ax, ay, az, bx, by, bz = ax + c0 + e0, ay + c1 + e1, az + c2 + e2, bx + f0, by + f1, bz + f2
        V[j, 0], V[j, 1], V[j, 2], V[j, 3], V[j, 4], V[j, 5] = vx, vy, vz, wx, wy, wz
        A[j, 0], A[j, 1], A[j, 2], A[j, 3], A[j, 4], A[j, 5] = ax, ay, az, bx, by, bz
        # the body's inertia about the world origin
        m, Ixx, Ixy, Iyy, Ixz, Iyz, Izz = piz[j, 0], piz[j, 4], piz[j, 5], piz[j, 6], piz[j, 7], piz[j, 8], piz[j, 9]
        t00 = r00 * Ixx + r01 * Ixy + ux * Ixz  # T = R I
        t01 = r00 * Ixy + r01 * Iyy + ux * Iyz
        t02 = r00 * Ixz + r01 * Iyz + ux * Izz
        t10 = r10 * Ixx + r11 * Ixy + uy * Ixz
        t11 = r10 * Ixy + r11 * Iyy + uy * Iyz
        t12 = r10 * Ixz + r11 * Iyz + uy * Izz
        t20 = r20 * Ixx + r21 * Ixy + uz * Ixz
        t21 = r20 * Ixy + r21 * Iyy + uz * Iyz
        t22 = r20 * Ixz + r21 * Iyz + uz * Izz
        hx = m * tx + r00 * piz[j, 1] + r01 * piz[j, 2] + ux * piz[j, 3]
        hy = m * ty + r10 * piz[j, 1] + r11 * piz[j, 2] + uy * piz[j, 3]
        hz = m * tz + r20 * piz[j, 1] + r21 * piz[j, 2] + uz * piz[j, 3]
        diag = 2.0 * (hx * tx + hy * ty + hz * tz) - m * (tx * tx + ty * ty + tz * tz)
        Iw[j, 0], Iw[j, 1], Iw[j, 2], Iw[j, 3] = m, hx, hy, hz
        Iw[j, 4] = t00 * r00 + t01 * r01 + t02 * ux + m * tx * tx - 2.0 * hx * tx + diag
        Iw[j, 5] = t00 * r10 + t01 * r11 + t02 * uy + m * tx * ty - (hx * ty + tx * hy)
        Iw[j, 6] = t10 * r10 + t11 * r11 + t12 * uy + m * ty * ty - 2.0 * hy * ty + diag
        Iw[j, 7] = t00 * r20 + t01 * r21 + t02 * uz + m * tx * tz - (hx * tz + tx * hz)
        Iw[j, 8] = t10 * r20 + t11 * r21 + t12 * uz + m * ty * tz - (hy * tz + ty * hz)
        Iw[j, 9] = t20 * r20 + t21 * r21 + t22 * uz + m * tz * tz - 2.0 * hz * tz + diag
        k0, k1, k2, k3, k4, k5 = _iapply(Iw, j, ax, ay, az, bx, by, bz)  # f = I A + V x* (I V)
        l0, l1, l2_, l3, l4, l5 = _iapply(Iw, j, vx, vy, vz, wx, wy, wz)
        c0, c1, c2 = _crs(wx, wy, wz, l0, l1, l2_)
        e0, e1, e2 = _crs(vx, vy, vz, l0, l1, l2_)
        f0, f1, f2 = _crs(wx, wy, wz, l3, l4, l5)
        Fb[j, 0], Fb[j, 1], Fb[j, 2], Fb[j, 3], Fb[j, 4], Fb[j, 5] = k0 + c0, k1 + c1, k2 + c2, k3 + e0 + f0, k4 + e1 + f1, k5 + e2 + f2
    Mm[:, :] = 0.0
    for j in range(n - 1, -1, -1):  # children have larger indices: Fb[j] and Iw[j] are the subtree's here
        qdd[j] = tau[j] - (S[j, 0] * Fb[j, 0] + S[j, 1] * Fb[j, 1] + S[j, 2] * Fb[j, 2] + S[j, 3] * Fb[j, 3] + S[j, 4] * Fb[j, 4]
                           + S[j, 5] * Fb[j, 5])
        k0, k1, k2, k3, k4, k5 = _iapply(Iw, j, S[j, 0], S[j, 1], S[j, 2], S[j, 3], S[j, 4], S[j, 5])
        i = j
        while i >= 0:
            Mm[i, j] = S[i, 0] * k0 + S[i, 1] * k1 + S[i, 2] * k2 + S[i, 3] * k3 + S[i, 4] * k4 + S[i, 5] * k5
            i = int(ints[i, 0])
        lam = int(ints[j, 0])
        if lam >= 0:
            for r in range(6):
                Fb[lam, r] += Fb[j, r]
            for r in range(10):
                Iw[lam, r] += Iw[j, r]
    for j in range(n):  # Cholesky of M (its upper triangle), L^T in the upper triangle: M = L L^T
        dj = Mm[j, j]
        for k in range(j):
            dj -= Mm[k, j] * Mm[k, j]
        if not dj > 0.0:
            return False
        dj = np.sqrt(dj)
        Mm[j, j] = dj
        for i in range(j + 1, n):
            acc = Mm[j, i]
            for k in range(j):
                acc -= Mm[k, i] * Mm[k, j]
            Mm[j, i] = acc / dj
    for i in range(n):  # L y = b, then L^T x = y (in qdd); L[i, k] = Mm[k, i]
        acc = qdd[i]
        for k in range(i):
            acc -= Mm[k, i] * qdd[k]
        qdd[i] = acc / Mm[i, i]
    for i in range(n - 1, -1, -1):
        acc = qdd[i]
        for k in range(i + 1, n):
            acc -= Mm[i, k] * qdd[k]
        qdd[i] = acc / Mm[i, i]
    return True


@njit(**_JIT)
def _forward_dynamics(X, geoz, ints, piz, grav, out):
    """``out[s] = qdd`` (N, n) at the states ``X`` (3, N, n) = (q, qd, tau); NaN rows where M is not PD."""
    wk = _fd_work(X.shape[2])
    for s in range(X.shape[1]):
        if not _forward_dynamics_one(X[0, s], X[1, s], X[2, s], geoz, ints, piz, grav, out[s], wk):
            out[s, :] = np.nan


# ---- scratch space (also of the engine's kernel supply, rc3r.robots.pinocchio_supply) ------------


@njit(**_JIT)
def _work(n):
    """Scratch arrays of the regressor."""
    return (np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 6)), np.zeros((2, n, 6)), np.zeros((2, n, 6)),
            np.empty((n, 10 * n)), np.empty((3, 3)), np.empty(3), np.empty(3), np.empty(3), np.empty((6, 3)),
            np.empty((6, 10)), np.empty(6))


@njit(**_JIT)
def _fd_work(n):
    """Scratch arrays of the forward dynamics: R (n, 9), p, S, V, A, I (n, 10), f, M."""
    return (np.empty((n, 9)), np.empty((n, 3)), np.empty((n, 6)), np.empty((n, 6)), np.empty((n, 6)),
            np.empty((n, 10)), np.empty((n, 6)), np.empty((n, n)))


def _align(u) -> np.ndarray:
    """A rotation A (3, 3) with ``A e_z = u`` (unit u)."""
    u = np.asarray(u, dtype=float) / np.linalg.norm(u)
    e = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = e - (e @ u) * u
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(u, x), u])


def local_axis(model, data, j: int) -> np.ndarray:
    """Joint ``j``'s motion subspace (6,) in its own frame (Pinocchio's LOCAL Jacobian column; ``data`` after
    ``computeJointJacobians``). A one-DoF model's Jacobian comes back from Pinocchio as a vector, hence
    the reshape."""
    import pinocchio as pin

    return np.asarray(pin.getJointJacobian(model, data, j, pin.LOCAL)).reshape(6, model.nv)[:, model.idx_vs[j]].copy()


class ChainKernel:
    """The compiled regressor for one kinematic structure (constants read from a ``pinocchio.Model``).

    Parameters
    ----------
    model : pinocchio.Model
        Joints all 1-DoF (``nq == nv == 1``).

    Attributes
    ----------
    supported : bool
        True iff every joint is a pure rotation or translation about a constant
        axis through its origin (revolute or prismatic: aligned or not). Helical
        and other 1-DoF joints are left to the Pinocchio path.
    """

    def __init__(self, model):
        import pinocchio as pin

        n = model.njoints - 1
        self.n = n
        self.supported = model.nq == model.nv == n
        self.geo = np.zeros((n + 1, 15))
        self.ints = np.zeros((n, n + 2), dtype=np.int64)
        self.geo[n, :6] = model.gravity.vector
        data = model.createData()
        pin.computeJointJacobians(model, data, pin.neutral(model))
        for j in range(n):
            placement = model.jointPlacements[j + 1]
            Sl = local_axis(model, data, j + 1)
            rev = bool(np.linalg.norm(Sl[3:]) > 0.5)  # motion subspace (0, u) or (u, 0)
            self.supported &= bool(np.linalg.norm(Sl[:3] if rev else Sl[3:]) < 1e-12)
            self.geo[j] = np.concatenate([np.ravel(placement.rotation), placement.translation, Sl[3:] if rev else Sl[:3]])
            self.ints[j, :2] = model.parents[j + 1] - 1, rev
            k = j
            while k >= 0:
                self.ints[k, 2 + j] = 1
                k = self.ints[k, 0]
        # the frames of the forward dynamics: joint j's turned by A_j (A_j e_z = its axis), so that
        # R0' = A_parent^T R0 A_j, p0' = A_parent^T p0 and every joint moves about or along z
        self.align = np.array([_align(self.geo[j, 12:15]) for j in range(n)]).reshape(n, 3, 3)
        self.geoz = np.zeros((n, 12))
        for j in range(n):
            Ap = self.align[self.ints[j, 0]] if self.ints[j, 0] >= 0 else np.eye(3)
            R0 = self.geo[j, :9].reshape(3, 3)
            self.geoz[j] = np.concatenate([np.ravel(Ap.T @ R0 @ self.align[j]), Ap.T @ self.geo[j, 9:12]])

    def aligned_parameters(self, pi) -> np.ndarray:
        """The standard parameters ``pi`` (10 n,) in the turned frames of the forward dynamics, (n, 10):
        ``m``, ``A^T (m c)``, ``A^T I A`` (Pinocchio's order xx, xy, yy, xz, yz, zz)."""
        pi = np.asarray(pi, dtype=float).reshape(self.n, 10)
        out = np.empty_like(pi)
        for j, A in enumerate(self.align):
            xx, xy, yy, xz, yz, zz = pi[j, 4:]
            I = A.T @ np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) @ A
            out[j] = [pi[j, 0], *(A.T @ pi[j, 1:4]), I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]]
        return out

    def pack(self, columns, pi) -> np.ndarray:
        """The engine's constants ``kc = [n, p, geo, ints, columns, geoz, piz]`` (float64, the supply's
        ``kc``) for the base-parameter ``columns`` (p,) and the standard parameters ``pi`` (10 n,)."""
        columns = np.asarray(columns)
        return np.concatenate([[self.n, columns.size], self.geo.ravel(), self.ints.ravel(), columns,
                               self.geoz.ravel(), self.aligned_parameters(pi).ravel()]).astype(np.float64)

    def supply(self, robot) -> tuple[str, np.ndarray]:
        """``robot.compiled_kernels``: the supply module (:data:`SUPPLY`) and :meth:`pack` of the robot's base
        columns and standard parameters, from which the engine builds its simulator
        (:func:`rc3r.simulate._fast.simulator`)."""
        return SUPPLY, self.pack(robot.base.independent, robot.standard_parameters())

    def forward_dynamics(self, X, pi) -> np.ndarray:
        """``qdd`` (N, n) at the states ``X`` (3, N, n) = (q, qd, tau) for standard parameters ``pi``
        (10 n,); NaN rows where M is not positive definite."""
        out = np.empty((X.shape[1], self.n))
        _forward_dynamics(np.ascontiguousarray(X, dtype=float), self.geoz, self.ints.astype(float),
                          self.aligned_parameters(pi), self.geo[self.n, :6].copy(), out)
        return out

    @staticmethod
    def ready() -> bool:
        """True if the regressor runs without compiling (:func:`rc3r._numba_cache.ready_or_python`)."""
        return _numba_cache.ready_or_python(_regressor) is _regressor

    def __call__(self, X, columns) -> np.ndarray:
        """``Y_pi[:, :, columns]`` (N, n, len(columns)) at ``X`` (4, N, n) = (q, qd, v, a): ``Y_pi pi = M a + C v + g``."""
        out = np.empty((X.shape[1], self.n, len(columns)))
        _regressor(np.ascontiguousarray(X, dtype=float), self.geo, self.ints, columns, out)
        return out
