r"""Regressors of the 3R arm, linear in the 15 coefficients theta.

* :func:`regressor` -- :math:`Y(q, \dot q, \ddot q)`, section 3.1.1:
  :math:`Y(q, \dot q, \ddot q)\,\theta = M\ddot q + S\dot q + g` (inverse dynamics).
* :func:`slotine_li_regressor` -- :math:`Y(q, \dot q, v, a)`, eq. (3):
  :math:`Y(q, \dot q, v, a)\,\theta = M(q) a + S(q, \dot q) v + g(q)`.
  The paper's listing in section 3.2 is unreadable; this one is derived from
  the identity with the paper's S (``docs/model.md``) and checked against
  Pinocchio by ``rc3r verify-model``.

Shapes: states (3,) or (N, 3); output (3, 15) or (N, 3, 15). ``l2`` [m] and
``g0`` [m/s^2] are the kinematic constants that appear in the gravity columns.
"""
from __future__ import annotations

import numpy as np

from . import kernels as K
from ._batch import as_states, as_theta
from .params import G0

__all__ = ["regressor", "slotine_li_regressor", "inverse_dynamics"]


def slotine_li_regressor(q, qd, v, a, *, l2: float, g0: float = G0) -> np.ndarray:
    r"""Slotine-Li regressor :math:`Y(q, \dot q, v, a)`, shape (3, 15) or (N, 3, 15).

    Non-zero entries, with :math:`P_{12} = v_1\dot q_2 + \dot q_1 v_2`,
    :math:`P_{13} = v_1\dot q_3 + \dot q_1 v_3`,
    :math:`W = \dot q_3 v_2 + (\dot q_2 + \dot q_3) v_3`:

    .. math::

        y_{1,1} &= a_1,\quad y_{1,2} = a_1 s_2^2 + P_{12} s_2 c_2,\quad
        y_{1,3} = a_1 s_2 c_2 + \tfrac12 P_{12}(c_2^2 - s_2^2) \\
        y_{1,4} &= a_1 s_{23}^2 + (P_{12} + P_{13}) s_{23} c_{23},\quad
        y_{1,5} = a_1 s_{23} c_{23} + \tfrac12 (P_{12} + P_{13})(c_{23}^2 - s_{23}^2) \\
        y_{1,6} &= 2 a_1 c_2 s_{23} + P_{12} c_{2+23} + P_{13} c_2 c_{23},\quad
        y_{1,7} = 2 a_1 c_2 c_{23} - P_{12} s_{2+23} - P_{13} c_2 s_{23} \\
        y_{1,8} &= a_2 c_2 - \dot q_2 v_2 s_2,\quad y_{1,9} = a_2 s_2 + \dot q_2 v_2 c_2 \\
        y_{1,10} &= (a_2 + a_3) c_{23} - (\dot q_2 v_2 + W) s_{23},\quad
        y_{1,11} = (a_2 + a_3) s_{23} + (\dot q_2 v_2 + W) c_{23} \\
        y_{2,2} &= -\dot q_1 v_1 s_2 c_2,\quad y_{2,3} = -\tfrac12 \dot q_1 v_1 (c_2^2 - s_2^2),\quad
        y_{2,4} = y_{3,4} = -\dot q_1 v_1 s_{23} c_{23} \\
        y_{2,5} &= y_{3,5} = -\tfrac12 \dot q_1 v_1 (c_{23}^2 - s_{23}^2) \\
        y_{2,6} &= (2a_2 + a_3) s_3 - \dot q_1 v_1 c_{2+23} + W c_3 + \tfrac{g_0}{l_2} s_{23} \\
        y_{2,7} &= (2a_2 + a_3) c_3 + \dot q_1 v_1 s_{2+23} - W s_3 + \tfrac{g_0}{l_2} c_{23} \\
        y_{2,8} &= a_1 c_2,\ y_{2,9} = a_1 s_2,\ y_{2,10} = y_{3,10} = a_1 c_{23},\
        y_{2,11} = y_{3,11} = a_1 s_{23},\ y_{2,12} = a_2,\ y_{2,13} = a_3 \\
        y_{2,14} &= g_0 c_2,\ y_{2,15} = g_0 s_2,\ y_{3,13} = a_2 + a_3 \\
        y_{3,6} &= a_2 s_3 - \dot q_1 v_1 c_2 c_{23} - \dot q_2 v_2 c_3 + \tfrac{g_0}{l_2} s_{23} \\
        y_{3,7} &= a_2 c_3 + \dot q_1 v_1 c_2 s_{23} + \dot q_2 v_2 s_3 + \tfrac{g_0}{l_2} c_{23}

    where :math:`c_{2+23} = \cos(2q_2 + q_3)`, :math:`s_{2+23} = \sin(2q_2 + q_3)`.
    """
    (Q, QD, V, A), single = as_states(q, qd, v, a)
    out = np.empty((Q.shape[0], 3, 15))
    K.slotine_li_batch(Q, QD, V, A, float(l2), float(g0), out)
    return out[0] if single else out


def regressor(q, qd, qdd, *, l2: float, g0: float = G0) -> np.ndarray:
    r"""Inverse-dynamics regressor :math:`Y(q, \dot q, \ddot q) = Y(q, \dot q, \dot q, \ddot q)`.

    Identity: ``regressor(q, qd, qdd) @ theta == pinocchio.rnea(q, qd, qdd)``.
    """
    return slotine_li_regressor(q, qd, qd, qdd, l2=l2, g0=g0)


def inverse_dynamics(theta, q, qd, qdd, *, l2: float, g0: float = G0) -> np.ndarray:
    r"""Joint torques :math:`\tau = Y(q, \dot q, \ddot q)\,\theta` [N m], (3,) or (N, 3).

    Evaluated in compiled code as :math:`M\ddot q + S\dot q + g` from the same term
    functions as :mod:`rc3r.model`, without materializing Y (the fast path benchmarked
    against ``pinocchio.rnea`` by ``rc3r bench``; equal to ``regressor(...) @ theta``).
    """
    th = as_theta(theta)
    (Q, QD, QDD), single = as_states(q, qd, qdd)
    out = np.empty((Q.shape[0], 3))
    K.inverse_dynamics_batch(th, Q, QD, QDD, float(l2), float(g0), out)
    return out[0] if single else out
