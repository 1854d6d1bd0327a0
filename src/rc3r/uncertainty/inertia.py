r"""The inertia a coefficient vector gives: :math:`M(q; \theta)`, linear in theta, from a robot's regressor.

Used by ``rc3r design`` (the sampled-data rule on the controller's own model, the worst-plant search)
and by the ellipsoid's ``lightest:`` plants (:mod:`rc3r.uncertainty.ellipsoid`). It needs only the
robot's regressor (a duck: ``n``, ``p``, ``regressor(q, qd, v, a)``), so it sits in this layer,
below the robots, the simulator and the design.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError

__all__ = ["ThetaModel"]


class ThetaModel:
    r"""A robot's kinematics with another theta: the controller's own model (its theta_0).

    :math:`M(q; \theta)` is linear in theta: column j of M is :math:`Y(q, 0, 0, e_j)\theta - Y(q, 0, 0, 0)\theta`
    (the Slotine--Li identity with :math:`\dot q = v = 0`), so :meth:`dM` gives
    :math:`\partial M / \partial\theta_k` (n, n, p) from the regressor alone and :meth:`mass_matrix` is
    ``dM(q) @ theta``: the M the laws use (``b M_theta(q)`` of the scheduled K, the rule's spectrum).

    Parameters
    ----------
    robot : Robot
        The kinematics (its regressor; its own theta is not used).
    theta : (p,) array_like
        The coefficients, e.g. the controller's theta_0.
    label : str
        What this model is (named in ``rc3r design``'s report).
    """

    def __init__(self, robot, theta, label: str = "theta_0"):
        self.robot = robot
        self.theta = np.asarray(theta, dtype=float)
        if self.theta.shape != (robot.p,):
            raise ParameterError(f"theta must have {robot.p} entries, got shape {self.theta.shape}")
        self.n, self.p, self.label = robot.n, robot.p, label

    def dM(self, q) -> np.ndarray:
        r""":math:`\partial M(q) / \partial\theta`, (n, n, p): ``dM(q) @ theta`` is M(q; theta)."""
        n = self.n
        q = np.asarray(q, dtype=float)
        Q = np.broadcast_to(q, (n + 1, n))
        Z = np.zeros((n + 1, n))
        A = np.vstack([np.zeros(n), np.eye(n)])
        Y = np.asarray(self.robot.regressor(Q, Z, Z, A), dtype=float)  # (n + 1, n, p)
        D = Y[1:] - Y[0]  # D[j] = column j of M as a map of theta: (n, p)
        return np.transpose(D, (1, 0, 2)).copy()  # (row i, column j, k)

    def mass_matrix(self, q) -> np.ndarray:
        """M(q; theta), (n, n), symmetrised."""
        M = self.dM(q) @ self.theta
        return 0.5 * (M + M.T)

    def regressor(self, q, qd, v, a) -> np.ndarray:
        """The robot's regressor (kinematics only)."""
        return self.robot.regressor(q, qd, v, a)
