"""An :class:`~rc3r.robots.actuated.ActuatedRobot`'s regressor as C99 source, for ``rc3r export``.

:func:`c_regressor_source` wraps the rigid body's C regressor (the regressor contract of :mod:`rc3r.export.c`:
its own ``c_regressor_source()`` or the generic chain) under renamed symbols (``rc3r_rigid_regressor*``, with
``RC3R_P`` its own p while it is read) and writes the contract again over ``[theta_r | joint coefficients]``:
``rc3r_regressor_eval`` evaluates the rigid body's and keeps ``qd`` and ``a``; ``rc3r_regressor_xi`` and
``rc3r_regressor_apply`` add the joint columns (viscous ``qd_j``, Coulomb ``tanh(qd_j / v_s)``, offset 1,
armature ``a_j``) to the rigid body's contractions, in the order of :mod:`.actuated_supply`'s ``xi_into`` and
``apply_into``.
"""
from __future__ import annotations

from ..identify.regressors import JOINT_KINDS

__all__ = ["c_regressor_source"]

_RENAMED = ("rc3r_regressor_eval", "rc3r_regressor_xi", "rc3r_regressor_apply", "rc3r_regressor")


def _column(kind: str, v_s: float) -> str:
    """The C expression of joint ``j``'s column of ``kind`` on ``wk->qd``, ``wk->a``."""
    if kind == "viscous":
        return "wk->qd[j]"
    if kind == "coulomb":
        return (f"tanh(wk->qd[j] / {v_s!r})" if v_s > 0 else
                "(wk->qd[j] > 0.0 ? 1.0 : (wk->qd[j] < 0.0 ? -1.0 : 0.0))")
    if kind == "offset":
        return "1.0"
    return "wk->a[j]"


def c_regressor_source(robot, rigid_source: str) -> str:
    """C99 source of ``robot``'s regressor (an ActuatedRobot) around the rigid body's ``rigid_source``.

    Parameters
    ----------
    robot : ActuatedRobot
        Its kinds, v_s [rad/s], n, p and rigid p.
    rigid_source : str
        The rigid body's C regressor (the contract of :mod:`rc3r.export.c`, for ``RC3R_P`` = its p).

    Returns
    -------
    str
        Source that fulfils the same contract for ``RC3R_P = robot.p``.
    """
    n, pr, vs = robot.n, robot.rigid_p, robot.coulomb_velocity
    ren = "".join(f"#define {s} rc3r_rigid_{s[len('rc3r_'):]}\n" for s in _RENAMED)
    unren = "".join(f"#undef {s}\n" for s in _RENAMED)
    xi, apply = [], []
    for s, kind in enumerate(robot.kinds):
        col = _column(kind, vs)
        xi.append(f"    for (j = 0; j < {n}; ++j)  /* {kind} ({JOINT_KINDS[kind]}) */\n"
                  f"        xi[{pr + s * n} + j] = {col} * r[j];\n")
        apply.append(f"    for (j = 0; j < {n}; ++j)  /* {kind} ({JOINT_KINDS[kind]}) */\n"
                     f"        u[j] += th[{pr + s * n} + j] * {col};\n")
    return f"""/* ---- an actuated robot: the rigid body's regressor (renamed), then {', '.join(robot.kinds)} per joint ---- */
#if RC3R_N != {n} || RC3R_P != {robot.p}
#error "the actuated regressor is {n} x {robot.p}"
#endif
#undef RC3R_P
#define RC3R_P {pr}
{ren}
{rigid_source}
{unren}#undef RC3R_P
#define RC3R_P {robot.p}

typedef struct {{
    rc3r_rigid_regressor rigid;  /* the rigid body's work at this state */
    double qd[{n}];  /* joint velocities [rad/s] */
    double a[{n}];   /* reference accelerations [rad/s^2] */
}} rc3r_regressor;

static inline void rc3r_regressor_eval(rc3r_regressor *wk, const double *q, const double *qd,
                                       const double *v, const double *a)
{{
    int j;
    rc3r_rigid_regressor_eval(&wk->rigid, q, qd, v, a);
    for (j = 0; j < {n}; ++j) {{
        wk->qd[j] = qd[j];
        wk->a[j] = a[j];
    }}
}}

static inline void rc3r_regressor_xi(const rc3r_regressor *wk, const double *r, double *xi)
{{
    int j;
    rc3r_rigid_regressor_xi(&wk->rigid, r, xi);
{''.join(xi)}}}

static inline void rc3r_regressor_apply(const rc3r_regressor *wk, const double *th, const double *w, double *u)
{{
    int j;
    rc3r_rigid_regressor_apply(&wk->rigid, th, w, u);
{''.join(apply)}}}
"""
