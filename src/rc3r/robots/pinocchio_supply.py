r"""The compiled engine's kernel supply for any serial chain (:mod:`rc3r.simulate.engines._template`).

The regressor and forward dynamics of :mod:`.pinocchio_kernel` behind the supply contract, on
:meth:`~.pinocchio_kernel.ChainKernel.pack`'s constants ``kc``, and the law's two contractions
of the regressor without forming it, in O(n):

* :func:`passes_into` -- the world-frame kinematics and, for both passes of the polarization
  (``x = (qd + v)/2, b = a/2`` with gravity, minus ``x = (qd - v)/2, b = -a/2`` without), each
  body's local ``omega``, ``a_c = a + omega x v`` and ``alpha`` (the arithmetic of
  :func:`.pinocchio_kernel._regressor_one` up to the body regressor);
* :func:`xi_into` -- :math:`\xi = Y^T r`: ``xi_j = F_j^T rho_j`` with ``rho_j = sum_{i carries j}
  r_i S_i`` (accumulated from the base outwards) in body j's frame;
* :func:`apply_into` -- :math:`u = w + Y \theta`: each body's Newton--Euler wrench with theta
  scattered into its 10 standard parameters (zero outside the base columns), carried to the
  world frame and summed over its subtree from the tip inwards, ``u_i = w_i + S_i . W_i``;
* :func:`mass_into` -- :math:`M_\theta(q)\, r` on the same kinematics (one pass of accelerations
  ``S_j r_j``, no velocity, no gravity): the scheduled K of the sliding laws.

``F_j`` is body j's Newton--Euler regressor (6 x 10) and ``Y[i, 10 j + c] = S_i . F_j[:, c]``
(:mod:`.pinocchio_kernel`); the two contractions are the ones the C export computes
(:mod:`rc3r.export.chain`, the same formulas in the same order). They cost about what one
forward pass does, where forming ``Y`` costs ``n^2`` projections of ``F_j`` and the dense products
``n p`` each (the UR5: 5.3 us per state for ``Y`` against 0.6 us for the forward dynamics).
``tests/test_pinocchio_supply.py`` checks them against Pinocchio's regressor.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .pinocchio_kernel import _cross, _forward_dynamics_one, _fd_work, _kinematics, _mv, _needed, _regressor_one, _work

__all__ = ["make_work", "regressor_into", "forward_dynamics_into", "passes_into", "xi_into", "apply_into",
           "mass_into"]

_JIT = dict(cache=True, nogil=True, fastmath=False)
_INLINE = dict(_JIT, inline="always")


@njit(**_INLINE)
def _unpack(kc):
    """``(geo, ints, columns, geoz, piz)`` views of ``kc`` (:meth:`ChainKernel.pack`)."""
    n, p = int(kc[0]), int(kc[1])
    o1 = 2 + 15 * (n + 1)
    o2 = o1 + n * (n + 2)
    o3 = o2 + p
    return (kc[2:o1].reshape((n + 1, 15)), kc[o1:o2].reshape((n, n + 2)), kc[o2:o3],
            kc[o3:o3 + 12 * n].reshape((n, 12)), kc[o3 + 12 * n:o3 + 22 * n].reshape((n, 10)))


@njit(**_JIT)
def _contract_work(n):
    """Scratch of the contractions: R (n, 3, 3), P (n, 3), S (n, 6), V, A (2, n, 6), the local motion
    Mo (n, 2, 9) = (omega, a_c, alpha) per pass, B (n, 6) (rho, then the wrenches W), X (n, 10)
    (per-body xi, then the scattered theta), T (8, 3) and a 6-vector."""
    return (np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 6)), np.zeros((2, n, 6)), np.zeros((2, n, 6)),
            np.empty((n, 2, 9)), np.empty((n, 6)), np.empty((n, 10)), np.empty((3, 3)), np.empty((8, 3)),
            np.empty(6))


@njit(**_INLINE)
def _passes(q, qd, v, a, geo, ints, cw):
    """Fill ``cw``'s R, P, S and Mo at ``(q, qd, v, a)``."""
    R, P, S, Vel, Acc, Mo, _B, _X, Rl, T, xs = cw
    n = q.shape[0]
    t, t2, ac = T[0], T[1], T[2]
    _kinematics(q, geo, ints, R, P, S, Rl, t, t2, ac)
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
            vj = Vel[k, j]  # A_j += V_j x (S x)
            _cross(vj[3:], xs[:3], t)
            _cross(vj[:3], xs[3:], t2)
            for r in range(3):
                Acc[k, j, r] += t[r] + t2[r]
            _cross(vj[3:], xs[3:], t)
            for r in range(3):
                Acc[k, j, 3 + r] += t[r]
        for k in range(2):  # local v, omega, a, alpha: (R^T (lin + ang x p), R^T ang)
            for m in range(2):
                X = Vel[k, j] if m == 0 else Acc[k, j]
                _cross(X[3:], P[j], t)
                for r in range(3):
                    t[r] += X[r]
                _mv(R[j], t, T[3 + 2 * m], True)
                _mv(R[j], X[3:], T[4 + 2 * m], True)
            _cross(T[4], T[3], t)  # a_c = a + omega x v
            for r in range(3):
                Mo[j, k, r] = T[4, r]
                Mo[j, k, 3 + r] = T[5, r] + t[r]
                Mo[j, k, 6 + r] = T[6, r]


@njit(**_INLINE)
def _xi(ints, columns, r, xi, cw):
    """xi (p,) = Y[:, columns]^T r from :func:`_passes`' arrays."""
    R, P, S, _V, _A, Mo, B, X, _Rl, T, _xs = cw
    n = r.shape[0]
    t, t2, b, lin, ang = T[0], T[1], T[2], T[3], T[4]
    for j in range(n):
        lam = int(ints[j, 0])
        for k in range(6):
            B[j, k] = (B[lam, k] if lam >= 0 else 0.0) + r[j] * S[j, k]
        _cross(B[j, 3:], P[j], t)
        for k in range(3):
            t[k] += B[j, k]
        _mv(R[j], t, lin, True)
        _mv(R[j], B[j, 3:], ang, True)
        x = X[j]
        x[:] = 0.0
        for k in range(2):
            sg = 1.0 if k == 0 else -1.0
            om, acc, al = Mo[j, k, 0:3], Mo[j, k, 3:6], Mo[j, k, 6:9]
            w2 = om[0] * om[0] + om[1] * om[1] + om[2] * om[2]
            ro = lin[0] * om[0] + lin[1] * om[1] + lin[2] * om[2]
            x[0] += sg * (lin[0] * acc[0] + lin[1] * acc[1] + lin[2] * acc[2])  # mass: f = a_c
            _cross(lin, al, t)  # first moments: f = alpha x h + omega x (omega x h), n = h x a_c
            _cross(acc, ang, t2)
            for c in range(3):
                x[1 + c] += sg * (t[c] + ro * om[c] - w2 * lin[c] + t2[c])
            _cross(ang, om, b)  # inertia (xx, xy, yy, xz, yz, zz): n = I alpha + omega x (I omega)
            x[4] += sg * (al[0] * ang[0] + om[0] * b[0])
            x[5] += sg * (al[1] * ang[0] + al[0] * ang[1] + om[1] * b[0] + om[0] * b[1])
            x[6] += sg * (al[1] * ang[1] + om[1] * b[1])
            x[7] += sg * (al[2] * ang[0] + al[0] * ang[2] + om[2] * b[0] + om[0] * b[2])
            x[8] += sg * (al[2] * ang[1] + al[1] * ang[2] + om[2] * b[1] + om[1] * b[2])
            x[9] += sg * (al[2] * ang[2] + om[2] * b[2])
    for c in range(columns.size):
        col = int(columns[c])
        xi[c] = X[col // 10, col % 10]


@njit(**_INLINE)
def _apply(ints, columns, th, w, u, cw):
    """u (n,) = w + Y[:, columns] th from :func:`_passes`' arrays."""
    R, P, S, _V, _A, Mo, W, X, _Rl, T, f = cw
    n = u.shape[0]
    X[:, :] = 0.0
    for c in range(columns.size):
        col = int(columns[c])
        X[col // 10, col % 10] = th[c]
    t, t2, t3, Ia, Io = T[0], T[1], T[2], T[3], T[4]
    for j in range(n):
        pi = X[j]
        h, I = pi[1:4], pi[4:10]
        f[:] = 0.0
        for k in range(2):
            sg = 1.0 if k == 0 else -1.0
            om, acc, al = Mo[j, k, 0:3], Mo[j, k, 3:6], Mo[j, k, 6:9]
            _cross(al, h, t)
            _cross(om, h, t2)
            _cross(om, t2, t3)
            for r in range(3):
                f[r] += sg * (pi[0] * acc[r] + t[r] + t3[r])
            Ia[0] = I[0] * al[0] + I[1] * al[1] + I[3] * al[2]
            Ia[1] = I[1] * al[0] + I[2] * al[1] + I[4] * al[2]
            Ia[2] = I[3] * al[0] + I[4] * al[1] + I[5] * al[2]
            Io[0] = I[0] * om[0] + I[1] * om[1] + I[3] * om[2]
            Io[1] = I[1] * om[0] + I[2] * om[1] + I[4] * om[2]
            Io[2] = I[3] * om[0] + I[4] * om[1] + I[5] * om[2]
            _cross(h, acc, t)
            _cross(om, Io, t2)
            for r in range(3):
                f[3 + r] += sg * (t[r] + Ia[r] + t2[r])
        _mv(R[j], f[:3], W[j, :3], False)  # f_O = R f
        _mv(R[j], f[3:], t, False)  # n_O = R n + p x f_O
        _cross(P[j], W[j, :3], W[j, 3:])
        for k in range(3):
            W[j, 3 + k] += t[k]
    for j in range(n - 1, -1, -1):  # children have larger indices
        lam = int(ints[j, 0])
        acc = 0.0
        for k in range(6):
            acc += S[j, k] * W[j, k]
        u[j] = w[j] + acc
        if lam >= 0:
            for k in range(6):
                W[lam, k] += W[j, k]


@njit(**_INLINE)
def _mass(ints, columns, th, r, out, cw, mw):
    """out (n,) = M_th(q) r on the kinematics of the last :func:`_passes` (at q): the recursive
    Newton--Euler wrench of the accelerations ``A_j = A_lambda + S_j r_j`` alone (no velocity, no
    gravity), theta scattered into the 10 standard parameters of each body. ``mw``: (n, 6) A, (n, 6) W,
    (n, 10) pi, (4, 3) scratch."""
    R, P, S = cw[0], cw[1], cw[2]
    A, W, X, T = mw
    n = out.shape[0]
    X[:, :] = 0.0
    for c in range(columns.size):
        col = int(columns[c])
        X[col // 10, col % 10] = th[c]
    t, lin, ang, t2 = T[0], T[1], T[2], T[3]
    for j in range(n):
        lam = int(ints[j, 0])
        for k in range(6):
            A[j, k] = (A[lam, k] if lam >= 0 else 0.0) + S[j, k] * r[j]
        _cross(A[j, 3:], P[j], t)  # local (a, alpha) = (R^T (A_lin + A_ang x p), R^T A_ang)
        for k in range(3):
            t[k] += A[j, k]
        _mv(R[j], t, lin, True)
        _mv(R[j], A[j, 3:], ang, True)
        pi = X[j]
        h, I = pi[1:4], pi[4:10]
        _cross(ang, h, t)  # f = m a + alpha x h, n = h x a + I alpha
        f0, f1, f2 = pi[0] * lin[0] + t[0], pi[0] * lin[1] + t[1], pi[0] * lin[2] + t[2]
        _cross(h, lin, t2)
        n0 = t2[0] + I[0] * ang[0] + I[1] * ang[1] + I[3] * ang[2]
        n1 = t2[1] + I[1] * ang[0] + I[2] * ang[1] + I[4] * ang[2]
        n2 = t2[2] + I[3] * ang[0] + I[4] * ang[1] + I[5] * ang[2]
        t[0], t[1], t[2] = f0, f1, f2
        _mv(R[j], t, W[j, :3], False)  # f_O = R f
        t[0], t[1], t[2] = n0, n1, n2
        _mv(R[j], t, t2, False)  # n_O = R n + p x f_O
        _cross(P[j], W[j, :3], W[j, 3:])
        for k in range(3):
            W[j, 3 + k] += t2[k]
    for j in range(n - 1, -1, -1):
        lam = int(ints[j, 0])
        acc = 0.0
        for k in range(6):
            acc += S[j, k] * W[j, k]
        out[j] = acc
        if lam >= 0:
            for k in range(6):
                W[lam, k] += W[j, k]


@njit(**_JIT)
def make_work(kc):
    """``(constants, regressor scratch, dynamics scratch, column mask, contraction scratch, mass scratch)``: the views of
    ``kc`` (made once, not per call), the arrays of :func:`.pinocchio_kernel._work`,
    :func:`.pinocchio_kernel._fd_work` and :func:`_contract_work` for ``n = kc[0]``, the column mask."""
    n = int(kc[0])
    consts = _unpack(kc)
    return consts, _work(n), _fd_work(n), _needed(consts[2], n), _contract_work(n), \
        (np.empty((n, 6)), np.empty((n, 6)), np.empty((n, 10)), np.empty((4, 3)))


@njit(**_INLINE)
def regressor_into(kc, q, qd, v, a, Y, wk):
    """Y (n, p): the Slotine--Li regressor in the base-parameter columns of ``kc``."""
    geo, ints, columns, _geoz, _piz = wk[0]
    _regressor_one(q, qd, v, a, geo, ints, columns, wk[3], Y, wk[1])


@njit(**_INLINE)
def forward_dynamics_into(kc, q, qd, tau, qdd, wk):
    """qdd of the chain with the standard parameters of ``kc``; False if M is not PD."""
    geo, ints, _columns, geoz, piz = wk[0]
    return _forward_dynamics_one(q, qd, tau, geoz, ints, piz, geo[geo.shape[0] - 1], qdd, wk[2])


@njit(**_INLINE)
def passes_into(kc, q, qd, v, a, Y, wk):
    """Prepare :func:`xi_into` and :func:`apply_into` at ``(q, qd, v, a)`` (``Y`` is not formed)."""
    geo, ints, _columns, _geoz, _piz = wk[0]
    _passes(q, qd, v, a, geo, ints, wk[4])


@njit(**_INLINE)
def xi_into(kc, Y, r, xi, wk):
    """xi (p,) = Y^T r at the state of the last :func:`passes_into`."""
    _geo, ints, columns, _geoz, _piz = wk[0]
    _xi(ints, columns, r, xi, wk[4])


@njit(**_INLINE)
def apply_into(kc, Y, th, w, u, wk):
    """u (n,) = w + Y th at the state of the last :func:`passes_into`."""
    _geo, ints, columns, _geoz, _piz = wk[0]
    _apply(ints, columns, th, w, u, wk[4])


@njit(**_INLINE)
def mass_into(kc, q, th, r, out, Y, wk):
    """out (n,) = M_th(q) r at the q of the last :func:`passes_into` (its kinematics; ``q`` unused)."""
    _geo, ints, columns, _geoz, _piz = wk[0]
    _mass(ints, columns, th, r, out, wk[4], wk[5])
