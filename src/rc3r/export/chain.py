r"""The Slotine--Li regressor of any serial chain in C: a port of :mod:`rc3r.robots.pinocchio_kernel`.

:func:`chain_source` writes the arm's constants read off its ``pinocchio.Model`` by
:class:`~rc3r.robots.pinocchio_kernel.ChainKernel` (per joint: the fixed placement ``R0``, ``p0``,
the axis, the parent, revolute or prismatic; gravity) as arrays, and the kernel's recursive
passes in C, with the same arithmetic in the same order: the world-frame kinematics and the two
passes of the polarization (``x = (qd + v)/2, b = a/2`` with gravity, minus
``x = (qd - v)/2, b = -a/2`` without), each body's local ``omega``, ``a_c = a + omega x v`` and
``alpha`` in both passes.

The kernel then forms each body's Newton--Euler regressor ``F_j`` (6 x 10) and projects it into
``Y_pi`` (n x 10 n). The law needs only ``xi = Y^T r`` and ``u = w + Y theta``, and both are
contractions of ``F_j`` that never need it formed. With ``Y_pi[i, 10 j + c] = S_i . (R_j, p_j)
F_j[:, c]`` for every joint ``i`` carrying body ``j``:

* ``xi``: ``xi_j = F_j^T rho_j`` with ``rho_j = sum_{i carries j} r_i S_i`` (accumulated from the
  base outwards) in body j's frame; per pass ``F^T rho`` is ``rho_f . a_c`` (mass),
  ``rho_f x alpha + (rho_f . omega) omega - |omega|^2 rho_f + a_c x rho_n`` (first moments) and
  ``L(alpha)^T rho_n + L(omega)^T (rho_n x omega)`` (inertia);
* ``u``: ``F_j pi_j``, the Newton--Euler wrench ``(m a_c + alpha x h + omega x (omega x h),
  h x a_c + I alpha + omega x I omega)`` of theta scattered into body j's 10 standard parameters
  (zero outside the base columns), carried to the world frame and summed over the subtree from
  the tip inwards, ``u_i = w_i + S_i . W_i``.

These equal ``Y[:, columns]^T r`` and ``Y[:, columns] @ theta + w`` to rounding (``Y theta = Y_pi
pi``; ``tests/test_export.py`` compares them with Pinocchio's own regressor), in O(n) instead of
the O(n^2 p) of the dense product.
"""
from __future__ import annotations

import numpy as np

from .literals import c_array, c_double

__all__ = ["chain_source"]

_TEMPLATE = r"""/* ---- Slotine--Li regressor of a serial chain (port of rc3r.robots.pinocchio_kernel) ---- */
#if RC3R_N != @N@ || RC3R_P != @P@
#error "the chain's regressor is @N@ x @P@"
#endif

/* per joint: fixed rotation R0 (row-major, 9), position p0 (3) in the parent's frame, unit axis (3) */
static const double rc3r_geo[RC3R_N][15] = @GEO@;
static const double rc3r_gravity[6] = @GRAVITY@;  /* (linear, angular) */
static const int rc3r_parent[RC3R_N] = @PARENT@;  /* -1: the base */
static const int rc3r_revolute[RC3R_N] = @REVOLUTE@;  /* 0: prismatic */
/* base-parameter columns of body j: rc3r_ncol[j] standard parameters c (0..9) at theta[rc3r_cpos] */
static const int rc3r_ncol[RC3R_N] = @NCOL@;
static const int rc3r_cstd[RC3R_N][10] = @CSTD@;
static const int rc3r_cpos[RC3R_N][10] = @CPOS@;

typedef struct {
    double R[RC3R_N][9];      /* world rotation of joint j (row-major) */
    double P[RC3R_N][3];      /* world origin of joint j */
    double S[RC3R_N][6];      /* motion subspace about the world origin (linear, angular) */
    double M[RC3R_N][2][9];   /* per pass: omega, a_c = a + omega x v, alpha of body j (local frame) */
} rc3r_regressor;

static inline void rc3r_cross(const double *x, const double *y, double *out)
{
    out[0] = x[1] * y[2] - x[2] * y[1];
    out[1] = x[2] * y[0] - x[0] * y[2];
    out[2] = x[0] * y[1] - x[1] * y[0];
}

/* out = R x, or R^T x */
static inline void rc3r_mv(const double *R, const double *x, double *out, int transpose)
{
    if (transpose) {
        out[0] = R[0] * x[0] + R[3] * x[1] + R[6] * x[2];
        out[1] = R[1] * x[0] + R[4] * x[1] + R[7] * x[2];
        out[2] = R[2] * x[0] + R[5] * x[1] + R[8] * x[2];
    } else {
        out[0] = R[0] * x[0] + R[1] * x[1] + R[2] * x[2];
        out[1] = R[3] * x[0] + R[4] * x[1] + R[5] * x[2];
        out[2] = R[6] * x[0] + R[7] * x[1] + R[8] * x[2];
    }
}

/* world rotation, origin and motion subspace of every joint at q */
static void rc3r_kinematics(rc3r_regressor *wk, const double *q)
{
    double Rl[9], t[3], t2[3], ac[3];
    int j, r, c;
    for (j = 0; j < RC3R_N; ++j) {
        const int lam = rc3r_parent[j];
        const double *g = rc3r_geo[j];
        const double *u = g + 12;
        for (r = 0; r < 3; ++r) {  /* Rl = R_lambda R0_j, t = p_lambda + R_lambda p0_j */
            if (lam >= 0) {
                const double *Rp = wk->R[lam];
                for (c = 0; c < 3; ++c)
                    Rl[3 * r + c] = Rp[3 * r] * g[c] + Rp[3 * r + 1] * g[3 + c] + Rp[3 * r + 2] * g[6 + c];
                t[r] = wk->P[lam][r] + Rp[3 * r] * g[9] + Rp[3 * r + 1] * g[10] + Rp[3 * r + 2] * g[11];
            } else {
                for (c = 0; c < 3; ++c)
                    Rl[3 * r + c] = g[3 * r + c];
                t[r] = g[9 + r];
            }
        }
        rc3r_mv(Rl, u, t2, 0);  /* world axis */
        if (rc3r_revolute[j]) {  /* R_j = Rl (I + sin K + (1 - cos) K^2) */
            const double sq = sin(q[j]), cq = 1.0 - cos(q[j]);
            for (r = 0; r < 3; ++r) {
                rc3r_cross(Rl + 3 * r, u, ac);
                for (c = 0; c < 3; ++c)
                    wk->R[j][3 * r + c] = Rl[3 * r + c] + sq * ac[c] + cq * (t2[r] * u[c] - Rl[3 * r + c]);
                wk->P[j][r] = t[r];
            }
            rc3r_cross(t, t2, ac);
            for (r = 0; r < 3; ++r) {
                wk->S[j][r] = ac[r];
                wk->S[j][3 + r] = t2[r];
            }
        } else {
            for (r = 0; r < 3; ++r) {
                for (c = 0; c < 3; ++c)
                    wk->R[j][3 * r + c] = Rl[3 * r + c];
                wk->P[j][r] = t[r] + t2[r] * q[j];
                wk->S[j][r] = t2[r];
                wk->S[j][3 + r] = 0.0;
            }
        }
    }
}

static inline void rc3r_regressor_eval(rc3r_regressor *wk, const double *q, const double *qd,
                                       const double *v, const double *a)
{
    double Vel[2][RC3R_N][6], Acc[2][RC3R_N][6], xs[6], t[3], t2[3], loc[4][3];
    int j, k, m, r;
    rc3r_kinematics(wk, q);
    for (j = 0; j < RC3R_N; ++j) {
        const int lam = rc3r_parent[j];
        for (k = 0; k < 2; ++k) {  /* the two passes of the polarization */
            const double xk = k == 0 ? 0.5 * (qd[j] + v[j]) : 0.5 * (qd[j] - v[j]);
            const double bk = k == 0 ? 0.5 * a[j] : -0.5 * a[j];
            double *vj = Vel[k][j], *aj = Acc[k][j];
            for (r = 0; r < 6; ++r) {
                const double g = k == 0 ? rc3r_gravity[r] : 0.0;
                xs[r] = wk->S[j][r] * xk;
                vj[r] = (lam >= 0 ? Vel[k][lam][r] : 0.0) + xs[r];
                aj[r] = (lam >= 0 ? Acc[k][lam][r] : -g) + wk->S[j][r] * bk;
            }
            rc3r_cross(vj + 3, xs, t);  /* A_j += V_j x (S x) */
            rc3r_cross(vj, xs + 3, t2);
            for (r = 0; r < 3; ++r)
                aj[r] += t[r] + t2[r];
            rc3r_cross(vj + 3, xs + 3, t);
            for (r = 0; r < 3; ++r)
                aj[3 + r] += t[r];
        }
        for (k = 0; k < 2; ++k) {  /* local v, omega, a, alpha: (R^T (lin + ang x p), R^T ang) */
            double *Mk = wk->M[j][k];
            for (m = 0; m < 2; ++m) {
                const double *X = m == 0 ? Vel[k][j] : Acc[k][j];
                rc3r_cross(X + 3, wk->P[j], t);
                for (r = 0; r < 3; ++r)
                    t[r] += X[r];
                rc3r_mv(wk->R[j], t, loc[2 * m], 1);
                rc3r_mv(wk->R[j], X + 3, loc[2 * m + 1], 1);
            }
            rc3r_cross(loc[1], loc[0], t);  /* a_c = a + omega x v */
            for (r = 0; r < 3; ++r) {
                Mk[r] = loc[1][r];
                Mk[3 + r] = loc[2][r] + t[r];
                Mk[6 + r] = loc[3][r];
            }
        }
    }
}

/* xi = Y^T r: rho_j = sum of r_i S_i over the joints carrying body j, in body j's frame, against body
 * j's Newton--Euler regressor (pass 1 minus pass 2): xi_j = F_j^T rho_j */
static inline void rc3r_regressor_xi(const rc3r_regressor *wk, const double *r, double *xi)
{
    double Rw[RC3R_N][6], t[3], t2[3], b[3], lin[3], ang[3], x[10];
    int j, c, k;
    for (j = 0; j < RC3R_N; ++j) {
        const int lam = rc3r_parent[j];
        for (k = 0; k < 6; ++k)
            Rw[j][k] = (lam >= 0 ? Rw[lam][k] : 0.0) + r[j] * wk->S[j][k];
        rc3r_cross(Rw[j] + 3, wk->P[j], t);
        for (k = 0; k < 3; ++k)
            t[k] += Rw[j][k];
        rc3r_mv(wk->R[j], t, lin, 1);
        rc3r_mv(wk->R[j], Rw[j] + 3, ang, 1);
        for (c = 0; c < 10; ++c)
            x[c] = 0.0;
        for (k = 0; k < 2; ++k) {
            const double sg = k == 0 ? 1.0 : -1.0;
            const double *om = wk->M[j][k], *ac = om + 3, *al = om + 6;
            const double w2 = om[0] * om[0] + om[1] * om[1] + om[2] * om[2];
            const double ro = lin[0] * om[0] + lin[1] * om[1] + lin[2] * om[2];
            /* mass: f = a_c */
            x[0] += sg * (lin[0] * ac[0] + lin[1] * ac[1] + lin[2] * ac[2]);
            /* first moments h: f = alpha x h + omega x (omega x h), n = h x a_c */
            rc3r_cross(lin, al, t);
            rc3r_cross(ac, ang, t2);
            for (c = 0; c < 3; ++c)
                x[1 + c] += sg * (t[c] + ro * om[c] - w2 * lin[c] + t2[c]);
            /* inertia (xx, xy, yy, xz, yz, zz): n = I alpha + omega x (I omega) */
            rc3r_cross(ang, om, b);
            x[4] += sg * (al[0] * ang[0] + om[0] * b[0]);
            x[5] += sg * (al[1] * ang[0] + al[0] * ang[1] + om[1] * b[0] + om[0] * b[1]);
            x[6] += sg * (al[1] * ang[1] + om[1] * b[1]);
            x[7] += sg * (al[2] * ang[0] + al[0] * ang[2] + om[2] * b[0] + om[0] * b[2]);
            x[8] += sg * (al[2] * ang[1] + al[1] * ang[2] + om[2] * b[1] + om[1] * b[2]);
            x[9] += sg * (al[2] * ang[2] + om[2] * b[2]);
        }
        for (c = 0; c < rc3r_ncol[j]; ++c)
            xi[rc3r_cpos[j][c]] = x[rc3r_cstd[j][c]];
    }
}

/* u = w + Y th: each body's Newton--Euler wrench with theta scattered into its 10 standard
 * parameters, carried to the world frame and summed over each subtree */
static inline void rc3r_regressor_apply(const rc3r_regressor *wk, const double *th, const double *w, double *u)
{
    double W[RC3R_N][6], f[6], pi[10], t[3], t2[3], t3[3], Ia[3], Io[3];
    int j, c, k, r;
    for (j = 0; j < RC3R_N; ++j) {
        const double *h = pi + 1, *I = pi + 4;
        for (c = 0; c < 10; ++c)
            pi[c] = 0.0;
        for (c = 0; c < rc3r_ncol[j]; ++c)
            pi[rc3r_cstd[j][c]] = th[rc3r_cpos[j][c]];
        for (r = 0; r < 6; ++r)
            f[r] = 0.0;
        for (k = 0; k < 2; ++k) {
            const double sg = k == 0 ? 1.0 : -1.0;
            const double *om = wk->M[j][k], *ac = om + 3, *al = om + 6;
            rc3r_cross(al, h, t);
            rc3r_cross(om, h, t2);
            rc3r_cross(om, t2, t3);
            for (r = 0; r < 3; ++r)
                f[r] += sg * (pi[0] * ac[r] + t[r] + t3[r]);
            Ia[0] = I[0] * al[0] + I[1] * al[1] + I[3] * al[2];
            Ia[1] = I[1] * al[0] + I[2] * al[1] + I[4] * al[2];
            Ia[2] = I[3] * al[0] + I[4] * al[1] + I[5] * al[2];
            Io[0] = I[0] * om[0] + I[1] * om[1] + I[3] * om[2];
            Io[1] = I[1] * om[0] + I[2] * om[1] + I[4] * om[2];
            Io[2] = I[3] * om[0] + I[4] * om[1] + I[5] * om[2];
            rc3r_cross(h, ac, t);
            rc3r_cross(om, Io, t2);
            for (r = 0; r < 3; ++r)
                f[3 + r] += sg * (t[r] + Ia[r] + t2[r]);
        }
        rc3r_mv(wk->R[j], f, W[j], 0);         /* f_O = R f */
        rc3r_mv(wk->R[j], f + 3, t, 0);        /* n_O = R n + p x f_O */
        rc3r_cross(wk->P[j], W[j], W[j] + 3);
        for (k = 0; k < 3; ++k)
            W[j][3 + k] += t[k];
    }
    for (j = RC3R_N - 1; j >= 0; --j) {  /* children have larger indices */
        const int lam = rc3r_parent[j];
        double acc = 0.0;
        for (k = 0; k < 6; ++k)
            acc += wk->S[j][k] * W[j][k];
        u[j] = w[j] + acc;
        if (lam >= 0)
            for (k = 0; k < 6; ++k)
                W[lam][k] += W[j][k];
    }
}
"""


def _rows(a, fmt) -> str:
    """``{{...}, {...}}`` of a 2-D array, one row to a brace."""
    return "{\n    " + ",\n    ".join(c_array(row, fmt, per_line=len(row)).replace("\n    ", " ").replace("\n", " ")
                                     for row in a) + "\n}"


def chain_source(kernel, columns) -> str:
    """C99 source of the chain's Slotine--Li regressor in the base-parameter ``columns`` (module docstring).

    Parameters
    ----------
    kernel : rc3r.robots.pinocchio_kernel.ChainKernel
        The arm's constants (``geo``: per joint ``R0``, ``p0``, axis, and gravity; ``ints``: parent,
        revolute flag).
    columns : array of int
        The standard-parameter columns of Y_pi that are the base parameters (``robot._columns``),
        in theta's order.

    Returns
    -------
    str
        The source, fulfilling the regressor contract of :mod:`rc3r.export.c`.
    """
    n = kernel.n
    columns = np.asarray(columns, dtype=np.int64)
    if columns.ndim != 1 or np.unique(columns).size != columns.size or columns.min() < 0 or columns.max() >= 10 * n:
        raise ValueError(f"columns must be distinct indices in [0, {10 * n}), got {columns.tolist()}")
    ncol = np.zeros(n, dtype=int)
    cstd = np.zeros((n, 10), dtype=int)
    cpos = np.zeros((n, 10), dtype=int)
    for pos, col in enumerate(columns):
        j, c = divmod(int(col), 10)
        cstd[j, ncol[j]], cpos[j, ncol[j]] = c, pos
        ncol[j] += 1
    ints = np.asarray(kernel.ints)
    fields = {"@N@": str(n), "@P@": str(columns.size),
              "@GEO@": _rows(kernel.geo[:n], c_double), "@GRAVITY@": c_array(kernel.geo[n, :6], per_line=6),
              "@PARENT@": c_array(ints[:, 0], str, per_line=16), "@REVOLUTE@": c_array(ints[:, 1], str, per_line=16),
              "@NCOL@": c_array(ncol, str, per_line=16), "@CSTD@": _rows(cstd, str), "@CPOS@": _rows(cpos, str)}
    out = _TEMPLATE
    for key, value in fields.items():
        out = out.replace(key, value)
    return out
