r"""The kernel supply of an :class:`~rc3r.robots.actuated.ActuatedRobot`: a rigid body's supply plus joint friction
and rotor inertia (armature), a template.

It wraps an inner supply (:mod:`rc3r.simulate.engines._template`) named on its ``# inner supply`` line (as it
stands a serial chain's, :mod:`rc3r.robots.pinocchio_supply`). It is a template, never a supply itself:
:func:`rc3r.robots.actuated.supply_module` writes a copy per inner supply with that line naming it, and either
imports the inner supply's ``tangents_into`` and ``plant_tangents_into`` in place of the two stubs of the
tangents section (the 3R's closed form has them) or drops that section (the chain has none: the engine then
differentiates numerically). Constants::

    kc = [inner kc (K) | n, p_r, v_s, s_fv, s_fc, s_f0, s_ia | plant fv (n), fc (n), f0 (n), ia (n) | K]

``p_r`` is the inner (rigid) coefficient count, ``v_s`` [rad/s] the Coulomb smoothing velocity, ``s_k`` the
position of kind k among the model's joint kinds (-1: absent), so column ``p_r + s_k n + j`` of ``Y`` is
joint j's column of kind k (:func:`rc3r.identify.regressors.joint_columns`: ``qd_j``, ``tanh(qd_j / v_s)``,
1, ``a_j``). The plant part is the rigid body's own: its armature enters the forward dynamics,
``(M(q) + diag(ia)) qdd = tau - C qd - g``; its friction is **not** here but the plant's
:class:`~rc3r.plants.Friction` effect (so the engines' stiff-friction handling sees it); fv, fc, f0 are
packed for completeness and unused. The law's theta has ``p_r + n m`` entries: ``Y theta`` is the inner
``Y theta_r`` plus the joint columns times their coefficients.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from rc3r.robots.pinocchio_supply import apply_into as _i_apply, forward_dynamics_into as _i_fd, make_work as _i_make_work, mass_into as _i_mass, passes_into as _i_passes, regressor_into as _i_regressor, xi_into as _i_xi  # inner supply

__all__ = ["make_work", "regressor_into", "forward_dynamics_into", "passes_into", "xi_into", "apply_into",
           "mass_into", "HEAD"]

_JIT = dict(cache=True, nogil=True)
_INLINE = dict(_JIT, inline="always")

#: Entries of the header after the inner constants: n, p_r, v_s and the four kind slots.
HEAD = 7


@njit(**_INLINE)
def _k(kc):
    """Length K of the inner constants (the last entry of ``kc``)."""
    return int(kc[kc.shape[0] - 1])


@njit(**_INLINE)
def _column(kind, vs, qd, a):
    """Joint column of ``kind`` (0 viscous, 1 Coulomb, 2 offset, 3 armature) at the joint's ``qd``, ``a``."""
    if kind == 0:
        return qd
    if kind == 1:
        if vs > 0.0:
            return math.tanh(qd / vs)
        return 1.0 if qd > 0.0 else (-1.0 if qd < 0.0 else 0.0)
    if kind == 2:
        return 1.0
    return a


@njit(**_INLINE)
def _slope(kind, vs, qd):
    """d column / d qd of ``kind`` (the armature's column depends on ``a``: 0 here)."""
    if kind == 0:
        return 1.0
    if kind == 1 and vs > 0.0:
        t = math.tanh(qd / vs)
        return (1.0 - t * t) / vs
    return 0.0


@njit(**_JIT)
def make_work(kc):
    """``(inner work, (qd, a, Minv, A, b, t, col, piv))``: the inner supply's scratch and this one's (the state of
    the last :func:`passes_into`, the armature's solve)."""
    K = _k(kc)
    n = int(kc[K])
    return _i_make_work(kc[:K]), (np.zeros(n), np.zeros(n), np.empty((n, n)), np.empty((n, n)), np.empty(n),
                                  np.empty(n), np.empty(n), np.zeros(n, dtype=np.int64))


@njit(**_INLINE)
def _fill_joint(kc, qd, a, Y):
    """The joint columns of ``Y`` (zero outside their joint's row)."""
    K = _k(kc)
    n, pr, vs = int(kc[K]), int(kc[K + 1]), kc[K + 2]
    for c in range(pr, Y.shape[1]):
        for i in range(n):
            Y[i, c] = 0.0
    for kind in range(4):
        s = int(kc[K + 3 + kind])
        if s >= 0:
            for j in range(n):
                Y[j, pr + s * n + j] = _column(kind, vs, qd[j], a[j])


@njit(**_INLINE)
def regressor_into(kc, q, qd, v, a, Y, wk):
    """Y (n, p_r + n m): the inner regressor, then the joint columns."""
    K = _k(kc)
    pr = int(kc[K + 1])
    _i_regressor(kc[:K], q, qd, v, a, Y[:, :pr], wk[0])
    _fill_joint(kc, qd, a, Y)


@njit(**_INLINE)
def passes_into(kc, q, qd, v, a, Y, wk):
    """The inner supply's passes; keeps ``qd`` and ``a`` and fills the joint columns of ``Y``."""
    K = _k(kc)
    pr = int(kc[K + 1])
    _i_passes(kc[:K], q, qd, v, a, Y[:, :pr], wk[0])
    st = wk[1]
    st[0][:] = qd
    st[1][:] = a
    _fill_joint(kc, qd, a, Y)


@njit(**_INLINE)
def xi_into(kc, Y, r, xi, wk):
    """xi = Y^T r: the inner part, then ``column_j r_j`` per joint coefficient."""
    K = _k(kc)
    n, pr, vs = int(kc[K]), int(kc[K + 1]), kc[K + 2]
    _i_xi(kc[:K], Y[:, :pr], r, xi[:pr], wk[0])
    qd, a = wk[1][0], wk[1][1]
    for kind in range(4):
        s = int(kc[K + 3 + kind])
        if s >= 0:
            for j in range(n):
                xi[pr + s * n + j] = _column(kind, vs, qd[j], a[j]) * r[j]


@njit(**_INLINE)
def apply_into(kc, Y, th, w, u, wk):
    """u = w + Y th: the inner part, then the joint torques of ``th``'s joint coefficients."""
    K = _k(kc)
    n, pr, vs = int(kc[K]), int(kc[K + 1]), kc[K + 2]
    _i_apply(kc[:K], Y[:, :pr], th[:pr], w, u, wk[0])
    qd, a = wk[1][0], wk[1][1]
    for kind in range(4):
        s = int(kc[K + 3 + kind])
        if s >= 0:
            for j in range(n):
                u[j] += th[pr + s * n + j] * _column(kind, vs, qd[j], a[j])


@njit(**_INLINE)
def mass_into(kc, q, th, r, out, Y, wk):
    """out = M_th(q) r: the inner part plus ``ia_j r_j`` (``th``'s armature)."""
    K = _k(kc)
    n, pr = int(kc[K]), int(kc[K + 1])
    _i_mass(kc[:K], q, th[:pr], r, out, Y[:, :pr], wk[0])
    s = int(kc[K + 6])
    if s >= 0:
        for j in range(n):
            out[j] += th[pr + s * n + j] * r[j]


@njit(**_INLINE)
def _armature(kc):
    """Offset of the plant's armature (n,) in ``kc`` and whether any entry is nonzero."""
    K = _k(kc)
    n = int(kc[K])
    o = K + HEAD + 3 * n
    for j in range(n):
        if kc[o + j] != 0.0:
            return o, True
    return o, False


@njit(**_JIT)
def forward_dynamics_into(kc, q, qd, tau, qdd, wk):
    """qdd of the rigid body with its armature: ``(M + diag(ia)) qdd = tau - C qd - g``; False if M is not PD.

    Without armature, the inner supply's. With it, from the inner forward dynamics alone: ``qdd0 = M^-1 (tau -
    h)`` and ``M^-1`` column by column (``(fd(tau + s e_j) - qdd0) / s``, ``s = 1 + max |tau|``), then
    ``(I + M^-1 diag(ia)) qdd = qdd0`` by Gaussian elimination with partial pivoting (n + 1 inner calls)."""
    K = _k(kc)
    n = int(kc[K])
    kin = kc[:K]
    ok = _i_fd(kin, q, qd, tau, qdd, wk[0])
    o, any_ia = _armature(kc)
    if not (ok and any_ia):
        return ok
    _qd, _a, Mi, A, b, t, col, piv = wk[1]
    s = 1.0
    for j in range(n):
        s = max(s, 1.0 + abs(tau[j]))
    for j in range(n):
        b[j] = qdd[j]
    for j in range(n):
        for i in range(n):
            t[i] = tau[i]
        t[j] += s
        if not _i_fd(kin, q, qd, t, col, wk[0]):
            return False
        for i in range(n):
            Mi[i, j] = (col[i] - b[i]) / s
    for i in range(n):
        for j in range(n):
            A[i, j] = Mi[i, j] * kc[o + j] + (1.0 if i == j else 0.0)
    for c in range(n):  # LU with partial pivoting, then the two triangular solves
        m, big = c, abs(A[c, c])
        for i in range(c + 1, n):
            if abs(A[i, c]) > big:
                m, big = i, abs(A[i, c])
        if big == 0.0:
            return False
        piv[c] = m
        if m != c:
            for j in range(n):
                A[c, j], A[m, j] = A[m, j], A[c, j]
            b[c], b[m] = b[m], b[c]
        for i in range(c + 1, n):
            f = A[i, c] / A[c, c]
            for j in range(c, n):
                A[i, j] -= f * A[c, j]
            b[i] -= f * b[c]
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= A[i, j] * qdd[j]
        qdd[i] = acc / A[i, i]
    return True


# ---- tangents (kept only when the inner supply has analytic derivatives)
# inner tangents: stubs here; a copy over a supply with derivatives imports its functions in their place
@njit(**_JIT)
def _i_tangents(kc, th, q, qd, v, a, D, wk):
    return False


@njit(**_JIT)
def _i_ptangents(kc, q, qd, qdd, D, wk):
    return False
# end of the inner tangents


__all__ += ["tangents_into", "plant_tangents_into"]


@njit(**_JIT)
def tangents_into(kc, th, q, qd, v, a, D, wk):
    """D (n, 4n) = d(Y th)/d(q, qd, v, a): the inner one plus the joint terms' slopes in qd (viscous, Coulomb)
    and a (armature)."""
    K = _k(kc)
    n, pr, vs = int(kc[K]), int(kc[K + 1]), kc[K + 2]
    if not _i_tangents(kc[:K], th[:pr], q, qd, v, a, D, wk[0]):
        return False
    for kind in (0, 1):
        s = int(kc[K + 3 + kind])
        if s >= 0:
            for j in range(n):
                D[j, n + j] += th[pr + s * n + j] * _slope(kind, vs, qd[j])
    s = int(kc[K + 6])
    if s >= 0:
        for j in range(n):
            D[j, 3 * n + j] += th[pr + s * n + j]
    return True


@njit(**_JIT)
def plant_tangents_into(kc, q, qd, qdd, D, wk):
    """D (n, 4n) of the plant's rigid body: the inner one with its armature on M's diagonal (columns 3n..)."""
    K = _k(kc)
    n = int(kc[K])
    if not _i_ptangents(kc[:K], q, qd, qdd, D, wk[0]):
        return False
    o = K + HEAD + 3 * n
    for j in range(n):
        D[j, 3 * n + j] += kc[o + j]
    return True
