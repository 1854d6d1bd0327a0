r"""Analytic derivatives of the 3R's closed form, for the compiled engine's Jacobian. GENERATED.

Written by :mod:`.tangents_gen` (SymPy) from :func:`.kernels.slotine_li_scalars`: do not edit,
regenerate (``python -m rc3r.robots.rr3.tangents_gen``). Columns ``z = (q (3), qd (3), v (3), a (3))``;
q1 does not enter (its column is zero).

* :func:`torque_tangent` -- ``D`` (3, 12) = d(Y(q, qd, v, a) theta)/dz, any ``theta`` (15,).

Checked against Pinocchio's ``computeRNEADerivatives`` and central differences in
``tests/test_rr3_tangents.py``.
"""
from __future__ import annotations

from numba import njit

from .kernels import _trig

_JIT = dict(cache=True, nogil=True, error_model="numpy")


@njit(**_JIT)
def torque_tangent(th, q2, q3, qd1, qd2, qd3, v1, v2, v3, a1, a2, a3, l2, g0, D):
    """D (3, 12) = d(Y theta)/d(q, qd, v, a) at the state; ``th`` (15,)."""
    s2, c2, s3, c3, s23, c23 = _trig(q2, q3)
    t0 = qd2*v2
    t1 = s2**2
    t2 = c2**2
    t3 = qd1*v2 + qd2*v1
    t4 = c2*s2
    t5 = c2*c23
    t6 = s2*s23
    t7 = t5 - t6
    t8 = t3*t7
    t9 = qd1*v3 + qd3*v1
    t10 = c23*s2
    t11 = 2.0*a1
    t12 = c2*s23
    t13 = t11*t12 + t5*t9
    t14 = t10 + t12
    t15 = t14*t3
    t16 = -t11*t5 + t12*t9
    t17 = 2*a1
    t18 = a2 + a3
    t19 = qd2 + qd3
    t20 = qd3*v2 + t19*v3
    t21 = t0 + t20
    t22 = s23**2
    t23 = c23**2
    t24 = t3 + t9
    t25 = c23*s23
    t26 = -(c23*t18 - s23*t21)*th[10] + (c23*t21 + s23*t18)*th[9] + (a1*t22 - a1*t23 + 2.0*t24*t25)*th[4] - (t17*t25 - t22*t24 + t23*t24)*th[3]
    t27 = t4*th[1]
    t28 = v2 + v3
    t29 = t25*th[3]
    t30 = 0.5*(-t1 + t2)*th[2]
    t31 = 0.5*(-t22 + t23)*th[4]
    t32 = c2*th[8]
    t33 = t7*th[5]
    t34 = s2*th[7]
    t35 = t14*th[6]
    t36 = c23*th[10]
    t37 = s23*th[9]
    t38 = t28*t36 - t28*t37 + t29*v1 + t31*v1
    t39 = t5*th[5]
    t40 = t12*th[6]
    t41 = qd1*t29 + qd1*t31 + t19*t36 - t19*t37
    t42 = t4*th[2]
    t43 = t25*th[4]
    t44 = t1*th[1]
    t45 = t22*th[3]
    t46 = c23*th[9] + s23*th[10]
    t47 = c2*th[7] + s2*th[8] + t46
    t48 = g0/l2
    t49 = c23*t48
    t50 = qd1*v1
    t51 = t14*t50
    t52 = s23*t48
    t53 = t50*t7
    t54 = 2.0*t50
    t55 = a1*t36 - a1*t37 - t23*t50*th[3] + t43*t54 + t45*t50
    t56 = 2.0*a2 + a3
    t57 = t29 + t31
    t58 = t14*th[6] - t27 - t30 - t33 - t57
    t59 = c3*th[5] - s3*th[6]
    t60 = c3*th[6]
    t61 = s3*th[5]
    t62 = t60 + t61 + th[12]
    t63 = t12*t50 + t49
    t64 = -t5*t50 + t52
    t65 = c2*s23*th[6] - t39 - t57
    t66 = -t59
    D[:, :] = 0.0
    D[0, 1] = -t26 + (a2*c2 - s2*t0)*th[8] - (a2*s2 + c2*t0)*th[7] - (a1*t1 - a1*t2 + 2.0*t3*t4)*th[2] + (-t1*t3 + t17*t4 + t2*t3)*th[1] - (t10*t11 + t13 - t6*t9 + 2*t8)*th[6] - (t10*t9 + t11*t6 + 2*t15 + t16)*th[5]
    D[0, 2] = -t26 - (t13 + t8)*th[6] - (t15 + t16)*th[5]
    D[0, 3] = t27*v2 + t28*t29 + t28*t31 + t30*v2 - (t12*v3 + t14*v2)*th[6] + (t5*v3 + t7*v2)*th[5]
    D[0, 4] = t27*v1 + t30*v1 + t32*v2 + t33*v1 - t34*v2 - t35*v1 + t38
    D[0, 5] = t38 + t39*v1 - t40*v1
    D[0, 6] = qd2*t27 + qd2*t30 + t19*t29 + t19*t31 - (qd2*t14 + qd3*t12)*th[6] + (qd2*t7 + qd3*t5)*th[5]
    D[0, 7] = qd1*t27 + qd1*t30 + qd1*t33 - qd1*t35 + qd2*t32 - qd2*t34 + t41
    D[0, 8] = qd1*t39 - qd1*t40 + t41
    D[0, 9] = 2.0*t12*th[5] + t42 + t43 + t44 + t45 + 2.0*t5*th[6] + th[0]
    D[0, 10] = t47
    D[0, 11] = t46
    D[1, 1] = a1*t32 - a1*t34 + c2*g0*th[14] - g0*s2*th[13] - t2*t50*th[1] + t42*t54 + t44*t50 + t55 + (t49 + 2*t51)*th[5] - (t52 - 2*t53)*th[6]
    D[1, 2] = t55 - (c3*t20 + s3*t56 + t52 - t53)*th[6] + (c3*t56 - s3*t20 + t49 + t51)*th[5]
    D[1, 3] = t58*v1
    D[1, 4] = t59*v3
    D[1, 5] = t28*t59
    D[1, 6] = qd1*t58
    D[1, 7] = qd3*t59
    D[1, 8] = t19*t59
    D[1, 9] = t47
    D[1, 10] = 2.0*t60 + 2.0*t61 + th[11]
    D[1, 11] = t62
    D[2, 1] = t55 + (t10*t50 + t63)*th[5] - (t50*t6 + t64)*th[6]
    D[2, 2] = t55 + (a2*c3 + s3*t0 + t63)*th[5] - (a2*s3 - c3*t0 + t64)*th[6]
    D[2, 3] = t65*v1
    D[2, 4] = t66*v2
    D[2, 6] = qd1*t65
    D[2, 7] = qd2*t66
    D[2, 9] = t46
    D[2, 10] = t62
    D[2, 11] = th[12]
