r"""Physical consistency of identified coefficients: a semidefinite program on pseudo-inertia matrices.

A body's standard parameters ``pi_k = (m, h, I)`` (mass, first moment ``h = m c``, inertia
``I`` about the joint origin; Pinocchio's order, :data:`~rc3r.conventions.STD_KEYS`)
are physically consistent -- some mass distribution realises them: mass >= 0, inertia about the
centre of mass positive semidefinite *and* satisfying the triangle inequalities -- exactly when
the **pseudo-inertia matrix** is positive semidefinite (Wensing, Kim, Slotine, "Linear matrix
inequalities for physically consistent inertial parameter identification", IEEE RA-L 2018):

.. math::

    J(\pi_k) = \begin{pmatrix} \tfrac12 \mathrm{tr}(I)\,\mathbf 1 - I & h \\ h^T & m \end{pmatrix}
    \succeq 0 .

``J`` is linear in ``pi_k`` and the robot's coefficients are linear in the standard parameters,
``theta = T pi`` (:func:`standard_map`), so "some consistent standard parameters realise
theta_hat" and "the nearest ones" are convex problems. :func:`check_consistency` solves

.. math::

    \min_{\pi} \; \| W (T\pi - \hat\theta) \|_2 \quad\text{s.t.}\quad J(\pi_k) \succeq 0 \;\;\forall k,
    \qquad W^T W = \mathrm{Cov}(\hat\theta)^{-1},

with cvxpy and an open solver shipped with it (Clarabel, else SCS). The optimum ``d`` is the
Mahalanobis distance from the estimate to the set of consistent coefficients: ``d ~ 0`` means the
estimate itself is consistent; otherwise ``theta_consistent = T pi*`` is the nearest consistent
vector in the estimate's own metric (its most likely consistent value), and ``d^2 <= chi2_p(C)``
says it lies inside the confidence ellipsoid (the data do not contradict physics).

For a robot whose ``theta`` is not Pinocchio's base parameters (the paper's 3R), ``T`` is found by
least squares from its regressor and Pinocchio's joint-torque regressor of ``robot.model`` at
random states, and refused if it does not reproduce them (theta not linear in them).
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError

__all__ = ["CONSISTENT_TOL", "pseudo_inertia", "standard_map", "model_standard_parameters", "check_consistency"]

#: A Mahalanobis distance below this counts as "the estimate is consistent" (solver accuracy).
CONSISTENT_TOL = 1e-3


def pseudo_inertia(block) -> np.ndarray:
    """The 4x4 pseudo-inertia matrix of 10 standard parameters ``(m, hx, hy, hz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)``."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = np.asarray(block, dtype=float)
    I = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    J = np.zeros((4, 4))
    J[:3, :3] = 0.5 * np.trace(I) * np.eye(3) - I
    J[:3, 3] = J[3, :3] = (hx, hy, hz)
    J[3, 3] = m
    return J


def model_standard_parameters(model) -> np.ndarray:
    """``toDynamicParameters()`` of every moving body of a ``pinocchio.Model``: (10 nb,)."""
    return np.concatenate([model.inertias[i].toDynamicParameters() for i in range(1, model.njoints)])


def standard_map(robot, seed: int = 0, states: int | None = None) -> np.ndarray:
    """``T`` (p, 10 nb) with ``robot.theta == T @ pi`` for Pinocchio's standard parameters ``pi``.

    A robot with Pinocchio base parameters (``robot.base.T``) gives it directly; any other robot
    by least squares ``Y T = W`` over ``states`` random states (``numpy.random.default_rng(seed)``,
    q in [-pi, pi], qd and qdd in [-3, 3]), ``W`` the joint-torque regressor of ``robot.model``.

    Raises
    ------
    ConfigError
        ``Y T`` does not reproduce ``W`` to 1e-8 (theta is not linear in the standard parameters).
    """
    if robot.base is not None:  # declared by every robot (rc3r.robots.base.Robot.base)
        return np.asarray(robot.base.T, dtype=float)
    import pinocchio as pin

    model = robot.model
    from .regressors import random_states

    Q, QD, QDD, Y = random_states(robot, states, seed)
    data = model.createData()
    W = np.vstack([pin.computeJointTorqueRegressor(model, data, q, qd, qdd) for q, qd, qdd in zip(Q, QD, QDD)])
    T = np.linalg.lstsq(Y, W, rcond=None)[0]
    err = np.linalg.norm(Y @ T - W) / max(np.linalg.norm(W), 1e-300)
    if err > 1e-8:
        raise ConfigError(f"robot '{robot.label}': its coefficients are not linear in Pinocchio's standard "
                          f"parameters (relative misfit {err:.2g}); cannot check physical consistency")
    T[np.abs(T) <= 1e-12 * np.abs(T).max()] = 0.0
    return T


def _solve(problem):
    import cvxpy as cp

    last = None
    for solver in ("CLARABEL", "SCS"):
        if solver not in cp.installed_solvers():
            continue
        try:
            problem.solve(solver=solver)
        except cp.error.SolverError as exc:
            last = exc
            continue
        if problem.status in ("optimal", "optimal_inaccurate"):
            return solver
    raise ConfigError(f"consistency SDP failed ({problem.status if last is None else last})")


def check_consistency(robot, theta_hat, cov_theta, chi2: float, seed: int = 0) -> dict:
    """Is ``theta_hat`` realised by physically consistent standard parameters? The nearest that are.

    Parameters
    ----------
    robot : Robot
        The identified arm (its ``model`` gives the bodies).
    theta_hat, cov_theta : ndarray
        The estimate (p,) and its covariance (p, p).
    chi2 : float
        ``chi2_p(C)`` of the confidence ellipsoid.
    seed : int
        Of :func:`standard_map`'s states.

    Returns
    -------
    dict
        ``checked`` (False with ``reason`` if cvxpy is missing), ``consistent``, ``mahalanobis``
        (``d``), ``within_ellipsoid`` (``d^2 <= chi2``), ``theta_consistent`` (p,),
        ``standard_parameters`` (10 nb,), ``min_eigenvalues`` (per body, of ``J(pi*)``),
        ``nominal_consistent`` (the robot's own parameters), ``solver``, ``status``, ``method``.
    """
    try:
        import cvxpy as cp
    except ImportError:
        return {"checked": False, "reason": "cvxpy is not installed (pip install 'rc3r[identify]')"}
    theta_hat = np.asarray(theta_hat, dtype=float)
    T = standard_map(robot, seed)
    nb = T.shape[1] // 10
    pi_nom = model_standard_parameters(robot.model)
    nominal_ok = bool(all(np.linalg.eigvalsh(pseudo_inertia(pi_nom[10 * k:10 * k + 10]))[0] >= -1e-9 *
                          max(1.0, abs(pi_nom[10 * k:10 * k + 10]).max()) for k in range(nb)))
    evals, evecs = np.linalg.eigh(np.asarray(cov_theta, dtype=float))
    evals = np.maximum(evals, 1e-300)
    W = (evecs / np.sqrt(evals)).T  # W^T W = Cov^{-1}
    scale = np.maximum(np.abs(pi_nom), 1e-3 * max(np.abs(pi_nom).max(), 1.0))  # pi = scale * z: O(1) unknowns
    z = cp.Variable(T.shape[1])
    pi = cp.multiply(scale, z)
    cons = []
    for k in range(nb):
        b = [pi[10 * k + i] for i in range(10)]
        m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = b
        tr = 0.5 * (ixx + iyy + izz)
        J = cp.bmat([[tr - ixx, -ixy, -ixz, hx], [-ixy, tr - iyy, -iyz, hy], [-ixz, -iyz, tr - izz, hz],
                     [hx, hy, hz, m]])
        S = cp.Variable((4, 4), symmetric=True)
        cons += [S == J, S >> 0]
    prob = cp.Problem(cp.Minimize(cp.norm(W @ (T @ pi - theta_hat), 2)), cons)
    solver = _solve(prob)
    pi_star = scale * np.asarray(z.value, dtype=float)
    theta_c = T @ pi_star
    d = float(np.linalg.norm(W @ (theta_c - theta_hat)))
    mins = [float(np.linalg.eigvalsh(pseudo_inertia(pi_star[10 * k:10 * k + 10]))[0]) for k in range(nb)]
    return {"checked": True, "consistent": bool(d <= CONSISTENT_TOL), "mahalanobis": d,
            "within_ellipsoid": bool(d * d <= chi2), "theta_consistent": theta_c.tolist(),
            "standard_parameters": pi_star.tolist(), "min_eigenvalues": mins, "nominal_consistent": nominal_ok,
            "solver": solver, "status": prob.status,
            "method": "min ||W (T pi - theta_hat)|| s.t. pseudo-inertia J(pi_k) >= 0 for every body (cvxpy); "
                      f"consistent if the distance is <= {CONSISTENT_TOL:g}"}
