r"""Closed-form dynamic model of the 3R arm (section 3.1 of the paper).

.. math::

    M(q)\,\ddot q + S(q, \dot q)\,\dot q + g(q) = u

All functions take the coefficients ``theta`` (15,) (order: ``docs/conventions.md``)
and joint states of shape (3,) or (N, 3) [rad, rad/s]; a batch axis in gives a
batch axis out. Compiled kernels: :mod:`rc3r._kernels`. Each identity below is
checked against Pinocchio by ``rc3r verify-model`` and ``tests/test_model.py``.
"""
from __future__ import annotations

import numpy as np

from . import kernels as K
from ._batch import as_states, as_theta
from .params import G0

__all__ = ["mass_matrix", "coriolis_matrix", "gravity", "coriolis_vector"]


def mass_matrix(theta, q) -> np.ndarray:
    r"""Inertia matrix :math:`M(q)`, shape (3, 3) or (N, 3, 3) [kg m^2 units of theta].

    .. math::

        m_{11} &= \theta_1 + \theta_2 s_2^2 + \theta_3 s_2 c_2 + \theta_4 s_{23}^2
                 + \theta_5 s_{23} c_{23} + 2\theta_6 c_2 s_{23} + 2\theta_7 c_2 c_{23} \\
        m_{12} &= \theta_8 c_2 + \theta_9 s_2 + \theta_{10} c_{23} + \theta_{11} s_{23}, \quad
        m_{13} = \theta_{10} c_{23} + \theta_{11} s_{23} \\
        m_{22} &= \theta_{12} + 2\theta_6 s_3 + 2\theta_7 c_3, \quad
        m_{23} = \theta_{13} + \theta_6 s_3 + \theta_7 c_3, \quad m_{33} = \theta_{13}

    Identity: equals ``pinocchio.crba`` (symmetrized).
    """
    th = as_theta(theta)
    (Q,), single = as_states(q)
    out = np.empty((Q.shape[0], 3, 3))
    K.mass_matrix_batch(th, Q, out)
    return out[0] if single else out


def coriolis_matrix(theta, q, qd) -> np.ndarray:
    r"""The paper's factorization :math:`S(q, \dot q)`, shape (3, 3) or (N, 3, 3).

    :math:`S_{kj} = \sum_i \Gamma_{kji} \dot q_i` with the Christoffel symbols of
    :math:`M`, so :math:`\dot M - 2S` is skew-symmetric (:math:`S + S^T = \dot M`).
    Identity: equals ``pinocchio.computeCoriolisMatrix``.
    """
    th = as_theta(theta)
    (Q, QD), single = as_states(q, qd)
    out = np.empty((Q.shape[0], 3, 3))
    K.coriolis_batch(th, Q, QD, out)
    return out[0] if single else out


def coriolis_vector(theta, q, qd) -> np.ndarray:
    r""":math:`c(q, \dot q) = S(q, \dot q)\,\dot q`, shape (3,) or (N, 3) [N m]."""
    S = coriolis_matrix(theta, q, qd)
    return np.einsum("...ij,...j->...i", S, np.broadcast_to(np.asarray(qd, float), S.shape[:-1]))


def gravity(theta, q, *, l2: float, g0: float = G0) -> np.ndarray:
    r"""Gravity torque :math:`g(q)`, shape (3,) or (N, 3) [N m].

    .. math::

        g = \begin{pmatrix} 0 \\
             g_0(\theta_{14} c_2 + \theta_{15} s_2 + \tfrac{\theta_7}{l_2} c_{23}
                 + \tfrac{\theta_6}{l_2} s_{23}) \\
             g_0(\tfrac{\theta_7}{l_2} c_{23} + \tfrac{\theta_6}{l_2} s_{23})
            \end{pmatrix}

    ``l2`` [m] is a kinematic constant of the arm (``ArmParams.lengths[1]``).
    Identity: equals ``pinocchio.computeGeneralizedGravity``.
    """
    th = as_theta(theta)
    (Q,), single = as_states(q)
    out = np.empty((Q.shape[0], 3))
    K.gravity_batch(th, Q, float(l2), float(g0), out)
    return out[0] if single else out
