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

Pass 1 minus pass 2, carried to the world frame (``f_O = R f``,
``n_O = R n + p x f_O``) and projected on every joint ``i`` that carries body
``j``: ``Y[i, 10 j + c] = S_i . F_j[:, c]``.
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["ChainKernel"]

_JIT = dict(cache=True, nogil=True, fastmath=False)


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


@njit(**_JIT)
def _body_force(v, om, a, al, sign, F, t, ac):
    """F (6, 10) += sign * (Newton--Euler regressor of one body at local v, omega, a, alpha)."""
    _cross(om, v, t)
    for r in range(3):
        ac[r] = a[r] + t[r]
    w2 = om[0] * om[0] + om[1] * om[1] + om[2] * om[2]
    for r in range(3):
        F[r, 0] += sign * ac[r]
    # first moments m c_k: f = alpha x e_k + omega omega_k - |omega|^2 e_k, n = e_k x a_c = -[a_c]x e_k
    F[0, 2] += sign * -al[2]; F[0, 3] += sign * al[1]
    F[1, 1] += sign * al[2]; F[1, 3] += sign * -al[0]
    F[2, 1] += sign * -al[1]; F[2, 2] += sign * al[0]
    for r in range(3):
        for k in range(3):
            F[r, 1 + k] += sign * (om[r] * om[k] - (w2 if r == k else 0.0))
    F[3, 2] += sign * ac[2]; F[3, 3] += sign * -ac[1]
    F[4, 1] += sign * -ac[2]; F[4, 3] += sign * ac[0]
    F[5, 1] += sign * ac[1]; F[5, 2] += sign * -ac[0]
    # inertia entries (Ixx, Ixy, Iyy, Ixz, Iyz, Izz): n = L(alpha) + omega x L(omega)
    F[3, 4] += sign * al[0]; F[3, 5] += sign * al[1]; F[3, 7] += sign * al[2]
    F[4, 5] += sign * al[0]; F[4, 6] += sign * al[1]; F[4, 8] += sign * al[2]
    F[5, 7] += sign * al[0]; F[5, 8] += sign * al[1]; F[5, 9] += sign * al[2]
    for c in range(6):  # column c of L(omega), crossed with omega
        lx = om[0] if c == 0 else (om[1] if c == 1 else (om[2] if c == 3 else 0.0))
        ly = om[0] if c == 1 else (om[1] if c == 2 else (om[2] if c == 4 else 0.0))
        lz = om[0] if c == 3 else (om[1] if c == 4 else (om[2] if c == 5 else 0.0))
        F[3, 4 + c] += sign * (om[1] * lz - om[2] * ly)
        F[4, 4 + c] += sign * (om[2] * lx - om[0] * lz)
        F[5, 4 + c] += sign * (om[0] * ly - om[1] * lx)


@njit(**_JIT)
def _regressor(X, geo, ints, columns, out):
    """Fill out (N, n, len(columns)) with columns of the standard-parameter Slotine--Li regressor.

    ``X`` (4, N, n): q, qd, v, a. ``geo`` (n + 1, 15): per joint ``R0`` (row-major), ``p0``,
    axis; row n: gravity (6). ``ints`` (n, n + 2): parent (-1: base), revolute flag,
    ``support[i, j]`` (joint i carries body j). (Few arguments: numba's call overhead
    grows with their number.)
    """
    n = X.shape[2]
    N = X.shape[1]
    R = np.empty((n, 3, 3))
    P = np.empty((n, 3))
    S = np.empty((n, 6))
    Vel = np.empty((2, n, 6))
    Acc = np.empty((2, n, 6))
    Y = np.empty((n, 10 * n))
    Rl = np.empty((3, 3))
    t = np.empty(3)
    t2 = np.empty(3)
    ac = np.empty(3)
    loc = np.empty((4, 3))
    F = np.empty((6, 10))
    xs = np.empty(6)
    for s in range(N):
        Y[:, :] = 0.0
        for j in range(n):
            lam = ints[j, 0]
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
            qj = X[0, s, j]
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
            for k in range(2):  # the two passes of the polarization
                xk = 0.5 * (X[1, s, j] + X[2, s, j]) if k == 0 else 0.5 * (X[1, s, j] - X[2, s, j])
                bk = 0.5 * X[3, s, j] if k == 0 else -0.5 * X[3, s, j]
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
            F[:, :] = 0.0
            for k in range(2):  # local v, omega, a, alpha of each pass: (R^T (lin + ang x p), R^T ang)
                for m in range(2):
                    M = Vel[k, j] if m == 0 else Acc[k, j]
                    _cross(M[3:], P[j], t)
                    for r in range(3):
                        t[r] += M[r]
                    _mv(R[j], t, loc[2 * m], True)
                    _mv(R[j], M[3:], loc[2 * m + 1], True)
                _body_force(loc[0], loc[1], loc[2], loc[3], 1.0 if k == 0 else -1.0, F, t, ac)
            for c in range(10):  # world force of column c: f_O = R f, n_O = R n + p x f_O
                for r in range(3):
                    t[r] = F[r, c]
                    t2[r] = F[3 + r, c]
                _mv(R[j], t, loc[0], False)
                _mv(R[j], t2, loc[1], False)
                _cross(P[j], loc[0], loc[2])
                for i in range(n):
                    if ints[i, 2 + j]:
                        acc = 0.0
                        for r in range(3):
                            acc += S[i, r] * loc[0, r] + S[i, 3 + r] * (loc[1, r] + loc[2, r])
                        Y[i, 10 * j + c] = acc
        for i in range(n):
            for c in range(columns.size):
                out[s, i, c] = Y[i, columns[c]]


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
            Sl = np.array(pin.getJointJacobian(model, data, j + 1, pin.LOCAL)[:, model.idx_vs[j + 1]])
            rev = bool(np.linalg.norm(Sl[3:]) > 0.5)  # motion subspace (0, u) or (u, 0)
            self.supported &= bool(np.linalg.norm(Sl[:3] if rev else Sl[3:]) < 1e-12)
            self.geo[j] = np.concatenate([np.ravel(placement.rotation), placement.translation, Sl[3:] if rev else Sl[:3]])
            self.ints[j, :2] = model.parents[j + 1] - 1, rev
            k = j
            while k >= 0:
                self.ints[k, 2 + j] = 1
                k = self.ints[k, 0]

    def __call__(self, X, columns) -> np.ndarray:
        """``Y_pi[:, :, columns]`` (N, n, len(columns)) for states ``X`` (4, N, n) = (q, qd, v, a).

        ``Y_pi pi = M a + C(q, qd) v + g`` in the 10 n standard parameters ``pi``.
        """
        out = np.empty((X.shape[1], self.n, len(columns)))
        _regressor(np.ascontiguousarray(X, dtype=float), self.geo, self.ints, columns, out)
        return out
