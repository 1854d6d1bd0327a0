r"""What the laws on the sliding variable :math:`r = \dot e + \Lambda e` share (``robust``, ``robust-coeff``,
``adaptive``): the class :class:`Sliding`, its packed entries, and the kernels written once for them.

With :math:`e = q - q_d`: :math:`v = \dot q_d - \Lambda e`, :math:`a = \ddot q_d - \Lambda \dot e`,
:math:`r = \dot q - v`, :math:`w = -K r` (K diagonal, plus its off-diagonal part if a matrix; the
scheduled :math:`-K_{\mathrm{inertia}} M(q) r` is the caller's: it needs the robot). The packed prefix
``[p, theta (p), K (n), K_matrix, K_offdiag (n, n), Lambda (n), K_inertia]`` comes from the fields
(:meth:`rc3r.controllers.base.Layout.of`) and is the same for every subclass (their own fields come
after), so :func:`signals`, :func:`inertia_gain` and :func:`slopes` serve them all. The laws whose
:math:`\theta_{\mathrm{eff}}` is a function of :math:`\xi = Y^T r` alone (the robust ones) share
:func:`xi_directions` and :func:`xi_theta_columns` (the analytic Jacobian).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numba.extending import register_jitable

from ..errors import ParameterError
from .base import (Law, Layout, _gain_matrix, _is_matrix, _nonnegative, _positive, _scalar, _sized, at,
                   packed)

__all__ = ["Sliding", "xi_norm", "signals", "inertia_gain", "slopes", "xi_directions", "xi_theta_columns", "no_state_gain",
           "c_parts", "C_XI_HEAD"]

_INLINE = dict(cache=True, nogil=True, inline="always")
_DERIV = dict(_INLINE, error_model="numpy")


@dataclass(frozen=True, eq=False)
class Sliding(Law):
    r"""Laws on r = e_dot + Lambda e: ``K`` [N m s/rad] (a number or a vector > 0: diagonal; or a symmetric
    positive definite (n, n) matrix), ``Lambda`` [1/s] (diagonal, > 0) and ``K_inertia`` b [1/s] (>= 0):

    .. math:: w = -\bigl(K + b\,M_{\theta}(q)\bigr)\, r,

    ``M_theta`` the mass matrix of the law's own theta at the measured q (the compiled engine computes
    :math:`M r` on the kinematics of the law's regressor pass; the Python path as
    :math:`Y(q, 0, 0, r)\theta - Y(q, 0, 0, 0)\theta`). Spong's proof needs only :math:`K(q) \succeq k I`
    uniformly, which a positive definite M gives (K = 0 is allowed with b > 0); the scheduled part puts
    every mode of :math:`M^{-1}K` at b for the model, where a constant K spreads them by M's coupling
    and its variation over the configurations (docs/design.md). K is packed as its diagonal, a flag
    ``K_matrix`` and its off-diagonal part ``K_offdiag`` (n * n, row-major; zeros if diagonal).
    """

    K: float | np.ndarray = packed(100.0, ("K", "n"), ("K_matrix", "1"), ("K_offdiag", "nn"))
    Lambda: float | np.ndarray = packed(50.0, ("Lambda", "n"))
    K_inertia: float = packed(0.0, ("K_inertia", "1"))

    def __post_init__(self):
        super().__post_init__()
        b = _scalar("K_inertia", _nonnegative("K_inertia", self.K_inertia))
        object.__setattr__(self, "K_inertia", b)
        if b > 0.0 and not _is_matrix(self.K):  # b M(q) is positive definite: K >= 0 is enough
            object.__setattr__(self, "K", _nonnegative("K", self.K))
        else:
            object.__setattr__(self, "K", _gain_matrix("K", self.K))
        object.__setattr__(self, "Lambda", _positive("Lambda", self.Lambda))

    def _packed(self, name, size, n):
        """K's entries: its diagonal, 1 if a matrix, its off-diagonal part (zeros if diagonal)."""
        if name not in ("K", "K_matrix", "K_offdiag"):
            return super()._packed(name, size, n)
        full = self.K.ndim == 2
        if full and self.K.shape[0] != n:
            raise ParameterError(f"K is {self.K.shape[0]} x {self.K.shape[1]}, the robot needs {n} x {n}")
        if name == "K":
            return np.diag(self.K).copy() if full else _sized("K", self.K, n)
        if name == "K_matrix":
            return np.array([1.0 if full else 0.0])
        return (self.K - np.diag(np.diag(self.K))).ravel() if full else np.zeros(n * n)

    def k_min(self, m_min: float = 0.0) -> float:
        """The smallest eigenvalue of ``K + K_inertia M(q)`` [N m s/rad] given ``lambda_min(M) >= m_min``
        [kg m^2]: of K (its smallest entry if diagonal) plus ``K_inertia m_min``."""
        k = float(np.linalg.eigvalsh(self.K)[0] if self.K.ndim == 2 else np.min(self.K))
        return k + self.K_inertia * float(m_min)


#: The prefix every sliding law's LAYOUT starts with.
PREFIX = Layout.of(Sliding)
_K, _KM, _KO, _LAM, _KI = (PREFIX.index(k) for k in ("K", "K_matrix", "K_offdiag", "Lambda", "K_inertia"))


@register_jitable
def xi_norm(xi, p):
    """``||xi[:p]||``: the squares summed in index order, then the square root (the robust laws' ``theta`` and
    ``weights``). ``register_jitable``, not ``njit``: called from Python (a value kernel's ``py_func`` on a
    cold start) it runs as plain Python and compiles nothing, so those kernels stay leaves (:mod:`.base`)."""
    s = 0.0
    for j in range(p):
        s += xi[j] * xi[j]
    return math.sqrt(s)


@njit(**_INLINE)
def signals(cp, q, qd, ref, v, a, r, w):
    """e = q - q_d, v = qd_d - Lambda e, a = qdd_d - Lambda e_dot, r = qd - v = e_dot + Lambda e,
    w = -K r (K diagonal, plus its off-diagonal part if a matrix); all (n,)."""
    n = q.shape[0]
    p = int(cp[0])
    k, lo = at(_K, n, p), at(_LAM, n, p)
    for i in range(n):
        lam = cp[lo + i]
        e = q[i] - ref[0, i]
        ed = qd[i] - ref[1, i]
        r[i] = ed + lam * e
        v[i] = ref[1, i] - lam * e
        a[i] = ref[2, i] - lam * ed
        w[i] = -cp[k + i] * r[i]
    if cp[at(_KM, n, p)] != 0.0:  # a matrix K: its off-diagonal part, row-major
        o = at(_KO, n, p)
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += cp[o + i * n + j] * r[j]
            w[i] -= acc


@njit(**_INLINE)
def inertia_gain(cp, n):
    """``K_inertia`` b [1/s]: the caller subtracts ``b M(q) r`` from w (0: no schedule)."""
    return cp[at(_KI, n, int(cp[0]))]


@njit(**_DERIV)
def slopes(cp, n, ref, jerk, G, Wx):
    r"""For ``inertia_gain == 0``: ``G`` (3, n, 3), ``G[k, j] = (d s_j/d q_j, d s_j/d qd_j, d s_j/d t)`` of
    ``s = v, a, r``; ``Wx`` (n, 2n + 1) = dw/d(q, qd, t) of ``w = -K r`` (the full K); ``ref`` rows q_d, qd_d,
    qdd_d and ``jerk`` (n,) its third derivative at t."""
    p = int(cp[0])
    lo, ko, o = at(_LAM, n, p), at(_K, n, p), at(_KO, n, p)
    for i in range(n):
        for c in range(2 * n + 1):
            Wx[i, c] = 0.0
    for j in range(n):
        lam = cp[lo + j]
        G[0, j, 0], G[0, j, 1], G[0, j, 2] = -lam, 0.0, ref[2, j] + lam * ref[1, j]
        G[1, j, 0], G[1, j, 1], G[1, j, 2] = 0.0, -lam, jerk[j] + lam * ref[2, j]
        G[2, j, 0], G[2, j, 1], G[2, j, 2] = lam, 1.0, -(ref[2, j] + lam * ref[1, j])
    full = cp[at(_KM, n, p)] != 0.0
    for i in range(n):
        for j in range(n):
            kij = (cp[ko + i] if i == j else 0.0) + (cp[o + i * n + j] if full else 0.0)
            Wx[i, j] = -kij * G[2, j, 0]
            Wx[i, n + j] = -kij
            Wx[i, 2 * n] -= kij * G[2, j, 2]


@njit(**_DERIV)
def xi_directions(Y, om, xs, TB):
    r"""For ``d theta_eff = diag(om) d xi + beta xi (xi^T d xi)``: the directions ``TB[i] = om * Y[i]``
    (i < n) and ``TB[n] = xi`` (``xs``) whose ``b^T d(Y^T r)`` it needs; returns their count n + 1."""
    n, p = Y.shape
    for i in range(n + 1):
        for k in range(p):
            TB[i, k] = om[k] * Y[i, k] if i < n else xs[k]
    return n + 1


@njit(**_DERIV)
def xi_theta_columns(cp, Y, rows, Ux, Xi, xs, bt):
    """A robust law's ``theta_columns``: ``Ux[:, :2n+1] += Y d theta_eff/dc = Xi[:n] + beta (Y xi) Xi[n]``
    (beta ``bt[0]``; rows of :func:`xi_directions`)."""
    n, p = Y.shape
    m = 2 * n + 1
    if rows > 0:
        for i in range(n):
            yx = 0.0
            for k in range(p):
                yx += Y[i, k] * xs[k]
            for c in range(m):
                Ux[i, c] += Xi[i, c] + bt[0] * yx * Xi[n, c]


@njit(**_DERIV)
def no_state_gain(cp, n):
    """A robust law's ``state_gain``: no controller state, an empty gain."""
    return cp[0:0]


#: The C of a law's output up to its own part: ``th`` holds xi = Y^T r, ``nrm`` its norm.
C_XI_HEAD = """    double nrm2 = 0.0, nrm;
    int j;
    rc3r_regressor_xi(wk, r, th);  /* th holds xi = Y^T r first */
    for (j = 0; j < RC3R_P; ++j)
        nrm2 += th[j] * th[j];
    nrm = sqrt(nrm2);
"""

_C_SIGNALS = """        const double lam = rc3r_Lambda[i];
        const double e = q[i] - ref[0][i];
        const double ed = qd[i] - ref[1][i];
        r[i] = ed + lam * e;
        v[i] = ref[1][i] - lam * e;
        a[i] = ref[2][i] - lam * ed;
        w[i] = -rc3r_K[i] * r[i];"""

_C_SCHEDULE = """    {  /* scheduled K: w -= b (Y(q, 0, 0, r) - Y(q, 0, 0, 0)) theta = b M(q) r */
        double zero[RC3R_N], m1[RC3R_N], m0[RC3R_N];
        int i;
        for (i = 0; i < RC3R_N; ++i)
            zero[i] = 0.0;
        rc3r_regressor_eval(&wk, q, zero, zero, r);
        rc3r_regressor_apply(&wk, rc3r_theta_K, zero, m1);
        rc3r_regressor_eval(&wk, q, zero, zero, zero);
        rc3r_regressor_apply(&wk, rc3r_theta_K, zero, m0);
        for (i = 0; i < RC3R_N; ++i)
            w[i] -= rc3r_K_inertia * (m1[i] - m0[i]);
    }
"""

_C_COUPLING = """    for (i = 0; i < RC3R_N; ++i) {  /* a matrix K: its off-diagonal part */
        double acc = 0.0;
        int j;
        for (j = 0; j < RC3R_N; ++j)
            acc += rc3r_Kc[i][j] * r[j];
        w[i] -= acc;
    }
"""


def c_parts(law, n: int, own: list, output: str, theta0: bool = True) -> dict:
    """A sliding law's ``c_source``: constants (``rc3r_theta0`` if ``theta0``, ``rc3r_K``, ``rc3r_Lambda``, the
    law's ``own`` ``(C name, dimensions, values, comment)``, then the schedule's and the coupling's), the
    signals, the law's ``output`` body, and the schedule and the coupling if the law has them."""
    cp = law.pack(n)
    lay = law.layout()
    consts = [("rc3r_theta0", "[RC3R_P]", lay.slice(cp, "theta", n), "")] if theta0 else []
    consts += [("rc3r_K", "[RC3R_N]", lay.slice(cp, "K", n), ""),
               ("rc3r_Lambda", "[RC3R_N]", lay.slice(cp, "Lambda", n), "")] + list(own)
    out = {"signals": _C_SIGNALS, "output": output}
    b = float(lay.slice(cp, "K_inertia", n)[0])
    if b > 0.0:  # K(q) = K + b M(q): M(q) r through the regressor
        consts += [("rc3r_K_inertia", "", b, "b [1/s]"),
                   ("rc3r_theta_K", "[RC3R_P]", lay.slice(cp, "theta", n), "M's theta")]
        out["schedule"] = _C_SCHEDULE
    if lay.slice(cp, "K_matrix", n)[0] != 0.0:  # a matrix K: w -= K_offdiag r
        consts += [("rc3r_Kc", "[RC3R_N][RC3R_N]", lay.slice(cp, "K_offdiag", n).reshape(n, n),
                    "K's off-diagonal part")]
        out["coupling"] = _C_COUPLING
    out["constants"] = consts
    return out
