"""Compiled (numba) kernels of the closed-form model: one state in, arrays filled in place.

These are the single implementation of the paper's formulas; :mod:`rc3r.model`,
:mod:`rc3r.regressor`, the controllers and the fast plant all call them. Index
conventions: ``th[0]`` is theta_1 of the paper, ``Y[:, 0]`` its column.
Derivation and typo fixes: ``docs/model.md``.

Notation: ``s2 = sin q2``, ``c23 = cos(q2 + q3)`` etc.; q1 does not enter.
With ``P12 = v1 qd2 + qd1 v2``, ``P13 = v1 qd3 + qd1 v3`` and
``W = qd3 v2 + (qd2 + qd3) v3`` the Slotine-Li regressor is
``Y(q, qd, v, a) theta = M(q) a + S(q, qd) v + g(q)``.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..._trig import FAST_LIMIT, sincos_fast

_JIT = dict(cache=True, nogil=True, fastmath=False)


_INLINE = dict(_JIT, inline="always")


@njit(**_INLINE)
def _trig(q2, q3):
    """(s2, c2, s3, c3, s23, c23); sin/cos(q2 + q3) by the addition theorem (4 libm calls).

    The per-state path (the simulators, the model functions) keeps libm: the chattering runs of the
    paper's eps = 0.05 amplify a last-bit change of the sines into a different torque peak (7 % on
    ``rc3r paper``'s 100 kHz row with :func:`rc3r._trig.sincos`), and the stored baseline holds
    libm's. The batch :func:`inverse_dynamics_batch` takes :func:`rc3r._trig.sincos_fast`."""
    s2 = math.sin(q2); c2 = math.cos(q2)
    s3 = math.sin(q3); c3 = math.cos(q3)
    return s2, c2, s3, c3, s2 * c3 + c2 * s3, c2 * c3 - s2 * s3


@njit(**_INLINE)
def _inertia_terms(th, s2, c2, s3, c3, s23, c23):
    """(m11, m12, m13, m22, m23) of section 3.1 (m11 with the s23 typo fixed); m33 = theta13."""
    m13 = th[9] * c23 + th[10] * s23
    m11 = (th[0] + th[1] * s2 * s2 + th[2] * s2 * c2 + th[3] * s23 * s23 + th[4] * s23 * c23
           + 2.0 * th[5] * c2 * s23 + 2.0 * th[6] * c2 * c23)
    return (m11, th[7] * c2 + th[8] * s2 + m13, m13,
            th[11] + 2.0 * th[5] * s3 + 2.0 * th[6] * c3, th[12] + th[5] * s3 + th[6] * c3)


@njit(**_INLINE)
def _christoffel_terms(th, s2, c2, s3, c3, s23, c23):
    """(A, B, D, E, F): A = dm11/dq2 / 2, B = dm11/dq3 / 2, D = dm12/dq2, E = dm13/dq3, F = dm23/dq3."""
    B = (th[3] * c23 * s23 + 0.5 * th[4] * (c23 * c23 - s23 * s23)
         + th[5] * c2 * c23 - th[6] * c2 * s23)
    A = (th[1] * c2 * s2 + 0.5 * th[2] * (c2 * c2 - s2 * s2) + B
         - th[5] * s2 * s23 - th[6] * s2 * c23)
    E = -th[9] * s23 + th[10] * c23
    D = -th[7] * s2 + th[8] * c2 + E
    F = th[5] * c3 - th[6] * s3
    return A, B, D, E, F


@njit(**_INLINE)
def _coriolis_vector(A, B, D, E, F, qd1, qd2, qd3):
    """c = S(q, qd) qd with the paper's S (rows of :func:`coriolis_into`), expanded."""
    c1 = (qd2 * A + qd3 * B) * qd1 + (qd1 * A + qd2 * D + qd3 * E) * qd2 + (qd1 * B + (qd2 + qd3) * E) * qd3
    c2 = -qd1 * A * qd1 + qd3 * F * qd2 + (qd2 + qd3) * F * qd3
    c3 = -qd1 * B * qd1 - qd2 * F * qd2
    return c1, c2, c3


@njit(**_INLINE)
def _gravity_terms(th, s2, c2, s23, c23, l2, g0):
    """(g2, g3) of section 3.1; theta_6, theta_7 enter divided by l2; g1 = 0."""
    g3 = g0 * (th[6] * c23 + th[5] * s23) / l2
    return g0 * (th[13] * c2 + th[14] * s2) + g3, g3


@njit(**_JIT)
def mass_matrix_into(th, q, M):
    """M(q) (3x3) of section 3.1."""
    s2, c2, s3, c3, s23, c23 = _trig(q[1], q[2])
    m11, m12, m13, m22, m23 = _inertia_terms(th, s2, c2, s3, c3, s23, c23)
    M[0, 0] = m11; M[0, 1] = m12; M[0, 2] = m13
    M[1, 0] = m12; M[1, 1] = m22; M[1, 2] = m23
    M[2, 0] = m13; M[2, 1] = m23; M[2, 2] = th[12]


@njit(**_JIT)
def coriolis_into(th, q, qd, S):
    """The paper's factorization S(q, qd) (3x3); equals the Christoffel-symbol matrix."""
    s2, c2, s3, c3, s23, c23 = _trig(q[1], q[2])
    A, B, D, E, F = _christoffel_terms(th, s2, c2, s3, c3, s23, c23)
    S[0, 0] = qd[1] * A + qd[2] * B
    S[0, 1] = qd[0] * A + qd[1] * D + qd[2] * E
    S[0, 2] = qd[0] * B + (qd[1] + qd[2]) * E
    S[1, 0] = -qd[0] * A
    S[1, 1] = qd[2] * F
    S[1, 2] = (qd[1] + qd[2]) * F
    S[2, 0] = -qd[0] * B
    S[2, 1] = -qd[1] * F
    S[2, 2] = 0.0


@njit(**_JIT)
def gravity_into(th, q, l2, g0, g):
    """g(q) (3,) of section 3.1."""
    s2, c2, _s3, _c3, s23, c23 = _trig(q[1], q[2])
    g2, g3 = _gravity_terms(th, s2, c2, s23, c23, l2, g0)
    g[0] = 0.0
    g[1] = g2
    g[2] = g3


@njit(**_INLINE)
def _terms_from_trig(th, s2, c2, s3, c3, s23, c23, qd1, qd2, qd3, l2, g0):
    """M entries and h = S qd + g from the state's sines: (m11, m12, m13, m22, m23, h1, h2, h3)."""
    m11, m12, m13, m22, m23 = _inertia_terms(th, s2, c2, s3, c3, s23, c23)
    A, B, D, E, F = _christoffel_terms(th, s2, c2, s3, c3, s23, c23)
    c1, c2_, c3_ = _coriolis_vector(A, B, D, E, F, qd1, qd2, qd3)
    g2, g3 = _gravity_terms(th, s2, c2, s23, c23, l2, g0)
    return m11, m12, m13, m22, m23, c1, c2_ + g2, c3_ + g3


@njit(**_INLINE)
def _dynamics_terms(th, q2, q3, qd1, qd2, qd3, l2, g0):
    """M entries and h = S qd + g at one state: (m11, m12, m13, m22, m23, h1, h2, h3)."""
    s2, c2, s3, c3, s23, c23 = _trig(q2, q3)
    return _terms_from_trig(th, s2, c2, s3, c3, s23, c23, qd1, qd2, qd3, l2, g0)


@njit(**_INLINE)
def _tau(th, m11, m12, m13, m22, m23, h1, h2, h3, a1, a2, a3):
    """tau = M a + h (m33 = theta13)."""
    return (m11 * a1 + m12 * a2 + m13 * a3 + h1, m12 * a1 + m22 * a2 + m23 * a3 + h2,
            m13 * a1 + m23 * a2 + th[12] * a3 + h3)


@njit(**_INLINE)
def slotine_li_scalars(q2, q3, qd1, qd2, qd3, v1, v2, v3, a1, a2, a3, l2, g0, Y):
    """Y(q, qd, v, a) (3x15) with ``Y theta = M a + S(q, qd) v + g`` (derived, docs/model.md).

    Scalar arguments (q1 does not enter), so compiled loops pass ``Q[n, 1]`` etc. without
    creating (reference-counted) row views; every entry of ``Y`` is written exactly once.
    """
    s2, c2, s3, c3, s23, c23 = _trig(q2, q3)
    P12 = v1 * qd2 + qd1 * v2
    P13 = v1 * qd3 + qd1 * v3
    W = qd3 * v2 + (qd2 + qd3) * v3
    w11 = qd1 * v1
    w22 = qd2 * v2
    cs2 = c2 * s2; d2 = 0.5 * (c2 * c2 - s2 * s2)
    cs23 = c23 * s23; d23 = 0.5 * (c23 * c23 - s23 * s23)
    k6 = c2 * c23 - s2 * s23      # cos(2 q2 + q3)
    k7 = s2 * c23 + c2 * s23      # sin(2 q2 + q3)
    gl = g0 / l2
    a23 = a2 + a3
    # row 1: m11 a1 + m12 a2 + m13 a3 + (S v)_1
    Y[0, 0] = a1
    Y[0, 1] = a1 * s2 * s2 + P12 * cs2
    Y[0, 2] = a1 * cs2 + P12 * d2
    Y[0, 3] = a1 * s23 * s23 + (P12 + P13) * cs23
    Y[0, 4] = a1 * cs23 + (P12 + P13) * d23
    Y[0, 5] = 2.0 * a1 * c2 * s23 + P12 * k6 + P13 * c2 * c23
    Y[0, 6] = 2.0 * a1 * c2 * c23 - P12 * k7 - P13 * c2 * s23
    Y[0, 7] = a2 * c2 - w22 * s2
    Y[0, 8] = a2 * s2 + w22 * c2
    Y[0, 9] = a23 * c23 - (w22 + W) * s23
    Y[0, 10] = a23 * s23 + (w22 + W) * c23
    Y[0, 11] = 0.0; Y[0, 12] = 0.0; Y[0, 13] = 0.0; Y[0, 14] = 0.0
    # row 2: m12 a1 + m22 a2 + m23 a3 + (S v)_2 + g2
    Y[1, 0] = 0.0
    Y[1, 1] = -w11 * cs2
    Y[1, 2] = -w11 * d2
    Y[1, 3] = -w11 * cs23
    Y[1, 4] = -w11 * d23
    Y[1, 5] = (2.0 * a2 + a3) * s3 - w11 * k6 + W * c3 + gl * s23
    Y[1, 6] = (2.0 * a2 + a3) * c3 + w11 * k7 - W * s3 + gl * c23
    Y[1, 7] = a1 * c2
    Y[1, 8] = a1 * s2
    Y[1, 9] = a1 * c23
    Y[1, 10] = a1 * s23
    Y[1, 11] = a2
    Y[1, 12] = a3
    Y[1, 13] = g0 * c2
    Y[1, 14] = g0 * s2
    # row 3: m13 a1 + m23 a2 + m33 a3 + (S v)_3 + g3
    Y[2, 0] = 0.0; Y[2, 1] = 0.0; Y[2, 2] = 0.0
    Y[2, 3] = -w11 * cs23
    Y[2, 4] = -w11 * d23
    Y[2, 5] = a2 * s3 - w11 * c2 * c23 - w22 * c3 + gl * s23
    Y[2, 6] = a2 * c3 + w11 * c2 * s23 + w22 * s3 + gl * c23
    Y[2, 7] = 0.0; Y[2, 8] = 0.0
    Y[2, 9] = a1 * c23
    Y[2, 10] = a1 * s23
    Y[2, 11] = 0.0
    Y[2, 12] = a23
    Y[2, 13] = 0.0; Y[2, 14] = 0.0



@njit(**_JIT)
def solve_spd3(M, b, x):
    """x = M^{-1} b for a symmetric positive-definite 3x3 M (unrolled Cholesky).

    Returns False (x untouched) if M is not numerically positive definite.
    """
    l11sq = M[0, 0]
    if not l11sq > 0.0:
        return False
    l11 = math.sqrt(l11sq)
    l21 = M[1, 0] / l11
    l31 = M[2, 0] / l11
    l22sq = M[1, 1] - l21 * l21
    if not l22sq > 0.0:
        return False
    l22 = math.sqrt(l22sq)
    l32 = (M[2, 1] - l31 * l21) / l22
    l33sq = M[2, 2] - l31 * l31 - l32 * l32
    if not l33sq > 0.0:
        return False
    l33 = math.sqrt(l33sq)
    y1 = b[0] / l11
    y2 = (b[1] - l21 * y1) / l22
    y3 = (b[2] - l31 * y1 - l32 * y2) / l33
    x[2] = y3 / l33
    x[1] = (y2 - l32 * x[2]) / l22
    x[0] = (y1 - l21 * x[1] - l31 * x[2]) / l11
    return True


@njit(**_JIT)
def forward_dynamics_into(th, q, qd, u, l2, g0, qdd, work33, work3):
    """qdd = M^{-1} (u - S qd - g) with the closed form; False if M is not PD."""
    m11, m12, m13, m22, m23, h1, h2, h3 = _dynamics_terms(th, q[1], q[2], qd[0], qd[1], qd[2], l2, g0)
    work33[0, 0] = m11; work33[0, 1] = m12; work33[0, 2] = m13
    work33[1, 0] = m12; work33[1, 1] = m22; work33[1, 2] = m23
    work33[2, 0] = m13; work33[2, 1] = m23; work33[2, 2] = th[12]
    work3[0] = u[0] - h1
    work3[1] = u[1] - h2
    work3[2] = u[2] - h3
    return solve_spd3(work33, work3, qdd)


# ---- batch loops (leading axis N) -------------------------------------------------------


@njit(**_JIT)
def mass_matrix_batch(th, Q, out):
    for n in range(Q.shape[0]):
        mass_matrix_into(th, Q[n], out[n])


@njit(**_JIT)
def coriolis_batch(th, Q, QD, out):
    for n in range(Q.shape[0]):
        coriolis_into(th, Q[n], QD[n], out[n])


@njit(**_JIT)
def gravity_batch(th, Q, l2, g0, out):
    for n in range(Q.shape[0]):
        gravity_into(th, Q[n], l2, g0, out[n])


@njit(**_JIT)
def slotine_li_batch(Q, QD, V, A, l2, g0, out):
    for n in range(Q.shape[0]):
        slotine_li_scalars(Q[n, 1], Q[n, 2], QD[n, 0], QD[n, 1], QD[n, 2], V[n, 0], V[n, 1], V[n, 2],
                           A[n, 0], A[n, 1], A[n, 2], l2, g0, out[n])


#: States per block of :func:`inverse_dynamics_batch` (its columns: 11 x 128 doubles, 11 KiB).
BLOCK = 128


@njit(**_JIT)
def _tau_columns(th, q2, q3, qd1, qd2, qd3, a1, a2, a3, l2, g0, t1, t2, t3, m):
    """tau of states 0..m-1 given as contiguous columns, every angle ``|q| < FAST_LIMIT``: a
    straight-line loop body (:func:`rc3r._trig.sincos_fast`), which LLVM runs in SIMD lanes."""
    for n in range(m):
        s2, c2 = sincos_fast(q2[n])
        s3, c3 = sincos_fast(q3[n])
        m11, m12, m13, m22, m23, h1, h2, h3 = _terms_from_trig(th, s2, c2, s3, c3, s2 * c3 + c2 * s3,
                                                               c2 * c3 - s2 * s3, qd1[n], qd2[n], qd3[n], l2, g0)
        t1[n], t2[n], t3[n] = _tau(th, m11, m12, m13, m22, m23, h1, h2, h3, a1[n], a2[n], a3[n])


@njit(**_JIT)
def inverse_dynamics_batch(th, Q, QD, QDD, l2, g0, out):
    """tau = M qdd + S qd + g for each state (N, 3), without storing Y.

    In blocks of :data:`BLOCK` states copied into columns (:func:`_tau_columns`, SIMD across
    states); a block whose angles' sum of magnitudes is not below :data:`rc3r._trig.FAST_LIMIT`
    (a NaN or an infinite angle, or angles of hundreds of turns) takes the per-state path of
    :func:`_dynamics_terms` (libm). The same formulas either way; the sines differ by at most 2 ulp.
    """
    N = Q.shape[0]
    C = np.empty((11, BLOCK))
    for b0 in range(0, N, BLOCK):
        m = min(BLOCK, N - b0)
        tot = 0.0  # sum of |angle| over the block: below FAST_LIMIT, every angle is (NaN, inf: not below)
        for i in range(m):
            k = b0 + i
            C[0, i] = Q[k, 1]; C[1, i] = Q[k, 2]
            C[2, i] = QD[k, 0]; C[3, i] = QD[k, 1]; C[4, i] = QD[k, 2]
            C[5, i] = QDD[k, 0]; C[6, i] = QDD[k, 1]; C[7, i] = QDD[k, 2]
            tot += abs(Q[k, 1]) + abs(Q[k, 2])
        if tot < FAST_LIMIT:
            _tau_columns(th, C[0], C[1], C[2], C[3], C[4], C[5], C[6], C[7], l2, g0, C[8], C[9], C[10], m)
            for i in range(m):
                out[b0 + i, 0] = C[8, i]; out[b0 + i, 1] = C[9, i]; out[b0 + i, 2] = C[10, i]
            continue
        for n in range(b0, b0 + m):
            m11, m12, m13, m22, m23, h1, h2, h3 = _dynamics_terms(th, Q[n, 1], Q[n, 2], QD[n, 0], QD[n, 1],
                                                                  QD[n, 2], l2, g0)
            out[n, 0], out[n, 1], out[n, 2] = _tau(th, m11, m12, m13, m22, m23, h1, h2, h3,
                                                   QDD[n, 0], QDD[n, 1], QDD[n, 2])
