"""The 3R's closed-form Slotine--Li regressor as C99 source, for ``rc3r export`` (:mod:`rc3r.export`).

:func:`c_regressor_source` writes :func:`.kernels.slotine_li_scalars` in C, term for term and in
the same order of operations, with the arm's two kinematic constants (the DH length ``a2`` and
gravity ``g0``) as literals. It fulfils the regressor contract of :mod:`rc3r.export.c`: a type
``rc3r_regressor`` and the functions ``rc3r_regressor_eval`` (Y at one state), ``rc3r_regressor_xi``
(``xi = Y^T r``) and ``rc3r_regressor_apply`` (``u = w + Y theta``), whose loops are those of
:func:`rc3r.controllers._kernels.regressor_transpose` and ``apply_regressor``.
"""
from __future__ import annotations

import math

__all__ = ["c_regressor_source"]

_TEMPLATE = r"""/* ---- the 3R's closed-form Slotine--Li regressor (rc3r.robots.rr3.kernels.slotine_li_scalars) ---- */
#if RC3R_N != 3 || RC3R_P != 15
#error "the 3R's regressor is 3 x 15"
#endif

typedef struct {
    double Y[3][15];  /* Y(q, qd, v, a), Y theta = M(q) a + S(q, qd) v + g(q) */
} rc3r_regressor;

static inline void rc3r_regressor_eval(rc3r_regressor *wk, const double *q, const double *qd,
                                       const double *v, const double *a)
{
    const double l2 = @L2@;  /* DH length a2 [m] */
    const double g0 = @G0@;  /* gravity [m/s^2] */
    const double qd1 = qd[0], qd2 = qd[1], qd3 = qd[2];
    const double v1 = v[0], v2 = v[1], v3 = v[2];
    const double a1 = a[0], a2 = a[1], a3 = a[2];
    const double s2 = sin(q[1]), c2 = cos(q[1]);
    const double s3 = sin(q[2]), c3 = cos(q[2]);
    const double s23 = s2 * c3 + c2 * s3, c23 = c2 * c3 - s2 * s3;
    const double P12 = v1 * qd2 + qd1 * v2;
    const double P13 = v1 * qd3 + qd1 * v3;
    const double W = qd3 * v2 + (qd2 + qd3) * v3;
    const double w11 = qd1 * v1;
    const double w22 = qd2 * v2;
    const double cs2 = c2 * s2, d2 = 0.5 * (c2 * c2 - s2 * s2);
    const double cs23 = c23 * s23, d23 = 0.5 * (c23 * c23 - s23 * s23);
    const double k6 = c2 * c23 - s2 * s23;  /* cos(2 q2 + q3) */
    const double k7 = s2 * c23 + c2 * s23;  /* sin(2 q2 + q3) */
    const double gl = g0 / l2;
    const double a23 = a2 + a3;
    double (*Y)[15] = wk->Y;
    /* row 1: m11 a1 + m12 a2 + m13 a3 + (S v)_1 */
    Y[0][0] = a1;
    Y[0][1] = a1 * s2 * s2 + P12 * cs2;
    Y[0][2] = a1 * cs2 + P12 * d2;
    Y[0][3] = a1 * s23 * s23 + (P12 + P13) * cs23;
    Y[0][4] = a1 * cs23 + (P12 + P13) * d23;
    Y[0][5] = 2.0 * a1 * c2 * s23 + P12 * k6 + P13 * c2 * c23;
    Y[0][6] = 2.0 * a1 * c2 * c23 - P12 * k7 - P13 * c2 * s23;
    Y[0][7] = a2 * c2 - w22 * s2;
    Y[0][8] = a2 * s2 + w22 * c2;
    Y[0][9] = a23 * c23 - (w22 + W) * s23;
    Y[0][10] = a23 * s23 + (w22 + W) * c23;
    Y[0][11] = 0.0; Y[0][12] = 0.0; Y[0][13] = 0.0; Y[0][14] = 0.0;
    /* row 2: m12 a1 + m22 a2 + m23 a3 + (S v)_2 + g2 */
    Y[1][0] = 0.0;
    Y[1][1] = -w11 * cs2;
    Y[1][2] = -w11 * d2;
    Y[1][3] = -w11 * cs23;
    Y[1][4] = -w11 * d23;
    Y[1][5] = (2.0 * a2 + a3) * s3 - w11 * k6 + W * c3 + gl * s23;
    Y[1][6] = (2.0 * a2 + a3) * c3 + w11 * k7 - W * s3 + gl * c23;
    Y[1][7] = a1 * c2;
    Y[1][8] = a1 * s2;
    Y[1][9] = a1 * c23;
    Y[1][10] = a1 * s23;
    Y[1][11] = a2;
    Y[1][12] = a3;
    Y[1][13] = g0 * c2;
    Y[1][14] = g0 * s2;
    /* row 3: m13 a1 + m23 a2 + m33 a3 + (S v)_3 + g3 */
    Y[2][0] = 0.0; Y[2][1] = 0.0; Y[2][2] = 0.0;
    Y[2][3] = -w11 * cs23;
    Y[2][4] = -w11 * d23;
    Y[2][5] = a2 * s3 - w11 * c2 * c23 - w22 * c3 + gl * s23;
    Y[2][6] = a2 * c3 + w11 * c2 * s23 + w22 * s3 + gl * c23;
    Y[2][7] = 0.0; Y[2][8] = 0.0;
    Y[2][9] = a1 * c23;
    Y[2][10] = a1 * s23;
    Y[2][11] = 0.0;
    Y[2][12] = a23;
    Y[2][13] = 0.0; Y[2][14] = 0.0;
}

/* xi = Y^T r (15) */
static inline void rc3r_regressor_xi(const rc3r_regressor *wk, const double *r, double *xi)
{
    int i, j;
    for (j = 0; j < 15; ++j) {
        double acc = 0.0;
        for (i = 0; i < 3; ++i)
            acc += wk->Y[i][j] * r[i];
        xi[j] = acc;
    }
}

/* u = w + Y th (3) */
static inline void rc3r_regressor_apply(const rc3r_regressor *wk, const double *th, const double *w, double *u)
{
    int i, j;
    for (i = 0; i < 3; ++i) {
        double acc = 0.0;
        for (j = 0; j < 15; ++j)
            acc += wk->Y[i][j] * th[j];
        u[i] = w[i] + acc;
    }
}
"""


def c_regressor_source(robot) -> str:
    """C99 source of the 3R's Slotine--Li regressor (module docstring) for the kinematics of ``robot``.

    Parameters
    ----------
    robot : RR3
        The controller's model; only its DH length ``a2`` and gravity ``g0`` enter Y, written as
        ``repr`` of the floats (the shortest decimal that reads back to the same double).

    Returns
    -------
    str
        The source, to be placed after ``RC3R_N``, ``RC3R_P`` and ``<math.h>``.

    Raises
    ------
    ParameterError
        A constant that is not finite.
    """
    from ...errors import ParameterError

    consts = {"@L2@": float(robot.params.lengths[1]), "@G0@": float(robot.params.g0)}
    if not all(math.isfinite(x) for x in consts.values()):
        raise ParameterError(f"the arm's a2 and g0 must be finite, got {list(consts.values())}")
    out = _TEMPLATE
    for key, x in consts.items():
        out = out.replace(key, repr(x))
    return out
