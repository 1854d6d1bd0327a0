r"""A physically consistent, plausible estimate: least squares in the log-Cholesky chart, pulled to the URDF.

Every body's 10 standard parameters ``pi_k = (m, h, I)`` (Pinocchio's order,
:data:`~rc3r.conventions.STD_KEYS`) are physically consistent exactly when its 4x4
**pseudo-inertia** ``J_k`` is positive definite (Wensing, Kim, Slotine, RA-L 2018;
:func:`rc3r.identify.consistency.pseudo_inertia`). The **log-Cholesky chart** (Rucker, Wensing,
"Smooth parameterization of rigid-body inertia", RA-L 2022) writes ``J = U U^T`` with

.. math::

    U = e^{\alpha}\begin{pmatrix} e^{d_1} & s_{12} & s_{13} & t_1 \\ 0 & e^{d_2} & s_{23} & t_2 \\
        0 & 0 & e^{d_3} & t_3 \\ 0 & 0 & 0 & 1 \end{pmatrix},
    \qquad \eta = (\alpha, d_1, d_2, d_3, s_{12}, s_{23}, s_{13}, t_1, t_2, t_3) \in \mathbb R^{10},

so *every* ``eta`` is a real rigid body and every real body has one ``eta`` (Pinocchio 3+:
``pin.LogCholeskyParameters``, which :func:`standard_of` and :func:`standard_jacobian` use).

**The fit** (:func:`fit_physical`). Unknowns ``z = (eta_1..eta_nb, friction)``, viscous and
Coulomb coefficients >= 0 (bounds), offsets free; ``theta(z) = T pi(eta)``
(:func:`rc3r.identify.consistency.standard_map`). Minimise

.. math::

    F_\gamma(z) = (x(z) - \hat x)^T \mathrm{Cov}(\hat x)^{-1} (x(z) - \hat x)
                 + \gamma \sum_k d(J_k \,\|\, J_{0,k}),
    \qquad d(J \| J_0) = -\log\det(J_0^{-1} J) + \mathrm{tr}(J_0^{-1} J) - 4,

with ``x = (theta, friction)``, ``x_hat`` and ``Cov`` the weighted least-squares estimate and its
covariance (the data term is the weighted residual sum of squares up to a constant and a scale:
:mod:`rc3r.identify.estimate`), and ``d`` the entropic (log-det, Bregman) divergence of the
pseudo-inertias from the URDF's ``J_0`` (Lee, Wensing, Park, "Geometric robot dynamic
identification: a convex programming approach", IEEE T-RO 2020): the directions of ``eta`` that
the data cannot see keep the URDF's values. With ``A = U_0^{-1} U`` (upper triangular, diagonal
``a_i > 0``), ``d = sum_{i<j} A_ij^2 + sum_i (a_i^2 - 1 - 2 log a_i)``: a sum of squares, so
``F`` is solved by :func:`scipy.optimize.least_squares` (trust region reflective with LSMR: no SVD,
analytic Jacobian, at most :data:`MAX_EVALUATIONS` evaluations per ``gamma``), every iterate
physical. ``exp(-gamma d / 2)`` is a Wishart density in ``J`` (mean
``J_0``), so ``F/2`` is a negative log posterior.

**The prior weight** ``gamma``: every ``gamma`` of :data:`GAMMAS` is fitted (largest first, each fit
warm-started from the previous); the chosen one is the largest whose Mahalanobis distance to the
unconstrained estimate, ``sqrt((x - x_hat)^T Cov^-1 (x - x_hat))``, exceeds the smallest ``gamma``'s
(the distance physics forces: the unconstrained estimate may lie outside the consistent set) by at most
:data:`MAHALANOBIS_SLACK`, one standard deviation. The prior thus moves the estimate by at most about
one standard deviation of the data beyond what consistency needs: a wrong URDF cannot drag it far
(measured: inertias 1.5x the truth, ``tests/test_identify_physical.py``). The per-joint training RMS
against the logged torques (at most :data:`RULE_STAMPS` stamps) is reported for every ``gamma``. A URDF
body whose ``J_0`` is not positive definite (the paper's 3R violates the triangle inequality) has
its eigenvalues floored at :data:`PRIOR_FLOOR` times its largest (reported: ``prior_repaired``).

**Uncertainty** (Laplace approximation). ``Cov(z) = (R^T R)^{-1}`` with ``R`` the Jacobian of
the residuals at the optimum (Gauss-Newton Hessian of ``F/2``); ``PhysicalFit.cov`` is
``G Cov(z) G^T``, ``G = d x / d z`` (the delta method). The confidence ellipsoid of ``bounds.toml``
is centred at ``theta(z*)`` and shaped by the *data's* covariance (the unconstrained estimate's,
:func:`rc3r.identify.pipeline.identify`): the prior moves the centre, it does not shrink the
uncertainty. Draws ``eta ~ N(eta*, Cov(eta))`` (:func:`draw_standard`) are all physical; the share
of them whose ``theta`` falls inside the ellipsoid is reported (:func:`draws_inside`): small when the
directions of ``eta`` the data do not see are wide (they move ``theta`` at second order), so plants
are drawn in the ellipsoid and realised in the chart instead (:func:`realise_log_cholesky`,
:func:`rc3r.uncertainty.ellipsoid.draw_from_ellipsoid`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError

__all__ = ["GAMMAS", "MAHALANOBIS_SLACK", "MAX_EVALUATIONS", "RULE_STAMPS", "PRIOR_FLOOR", "INSIDE_DRAWS",
           "REALISE_DRAWS", "upper_cholesky", "log_cholesky_of", "standard_of", "standard_jacobian", "divergence",
           "covariance_factor", "realise_log_cholesky", "draws_inside", "PhysicalFit", "fit_physical",
           "draw_standard", "NONNEGATIVE", "JOINT_PRIOR_WIDTH", "joint_prior"]

#: Prior weights tried, largest first (units: the data term is a Mahalanobis distance, chi2-like). The
#: smallest, 1, is the weakest prior kept: ``exp(-d/2)`` is a Wishart density of one degree of freedom,
#: a barrier that keeps every pseudo-inertia well inside the consistent set and the Laplace covariance
#: finite in the directions the data do not see.
GAMMAS = (1e4, 1e3, 1e2, 1e1, 1.0)

#: The rule for gamma: the fit's Mahalanobis distance to the unconstrained estimate at most this more than
#: the smallest gamma's.
MAHALANOBIS_SLACK = 1.0

#: Function evaluations of one least-squares solve (per gamma; warm-started).
MAX_EVALUATIONS = 300

#: A prior pseudo-inertia's eigenvalues are floored at this x its largest (only if not positive definite).
PRIOR_FLOOR = 1e-3

#: Training stamps (evenly thinned) of the gamma rule's RMS.
RULE_STAMPS = 5000

#: Seeded draws of the Laplace posterior that measure the share inside the ellipsoid.
INSIDE_DRAWS = 1000

#: Seeded draws uniform in the ellipsoid whose realisation by physical link parameters is measured.
REALISE_DRAWS = 20

_SQRT2 = float(np.sqrt(2.0))
#: Position in U (row, column) of eta's entries 1..9 (alpha scales all).
_POS = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))


def upper_cholesky(J) -> np.ndarray:
    """``U`` upper triangular with positive diagonal and ``U U^T = J`` (4x4 positive definite)."""
    F = np.asarray(J, dtype=float)[::-1, ::-1]
    return np.linalg.cholesky(F)[::-1, ::-1]


def _U(eta) -> np.ndarray:
    a, d1, d2, d3, s12, s23, s13, t1, t2, t3 = eta
    return np.exp(a) * np.array([[np.exp(d1), s12, s13, t1], [0.0, np.exp(d2), s23, t2],
                                 [0.0, 0.0, np.exp(d3), t3], [0.0, 0.0, 0.0, 1.0]])


def _dU(eta, U) -> np.ndarray:
    """d U / d eta: (10, 4, 4)."""
    D = np.zeros((10, 4, 4))
    D[0] = U
    e = np.exp(eta[0])
    for k, (i, j) in enumerate(_POS):
        D[k + 1, i, j] = U[i, j] if i == j else e
    return D


def log_cholesky_of(block) -> np.ndarray:
    """The log-Cholesky parameters (10,) of one body's 10 standard parameters (its pseudo-inertia must be PD)."""
    from .consistency import pseudo_inertia

    U = upper_cholesky(pseudo_inertia(block))
    a = np.log(U[3, 3])
    V = U / U[3, 3]
    return np.array([a, np.log(V[0, 0]), np.log(V[1, 1]), np.log(V[2, 2]), V[0, 1], V[1, 2], V[0, 2],
                     V[0, 3], V[1, 3], V[2, 3]])


def standard_of(eta) -> np.ndarray:
    """Standard parameters (10 nb,) of log-Cholesky parameters (10 nb,) (``pin.LogCholeskyParameters``)."""
    import pinocchio as pin

    eta = np.asarray(eta, dtype=float)
    return np.concatenate([pin.LogCholeskyParameters(eta[k:k + 10]).toDynamicParameters()
                           for k in range(0, eta.size, 10)])


def standard_jacobian(eta) -> np.ndarray:
    """``d pi / d eta`` (10 nb, 10 nb), block diagonal (``pin.LogCholeskyParameters.calculateJacobian``)."""
    import pinocchio as pin

    eta = np.asarray(eta, dtype=float)
    nb = eta.size // 10
    G = np.zeros((10 * nb, 10 * nb))
    for k in range(nb):
        block = pin.LogCholeskyParameters(eta[10 * k:10 * k + 10])
        G[10 * k:10 * k + 10, 10 * k:10 * k + 10] = block.calculateJacobian()
    return G


def _diag_residual(a):
    """``s(a) = sign(a - 1) sqrt(a^2 - 1 - 2 log a)`` and ``ds/da`` (smooth; ``s ~ sqrt(2) (a - 1)`` at 1)."""
    v = max(a * a - 1.0 - 2.0 * np.log(a), 0.0)
    s = np.copysign(np.sqrt(v), a - 1.0)
    ds = _SQRT2 if abs(a - 1.0) < 1e-6 else (a - 1.0 / a) / s
    return s, ds


def _prior_residuals(eta, U0inv):
    """Residuals (10,) with squared sum ``d(J(eta) || J0)`` and their Jacobian (10, 10)."""
    U = _U(eta)
    dU = _dU(eta, U)
    A = U0inv @ U
    dA = U0inv[None] @ dU
    r = np.empty(10)
    Jr = np.empty((10, 10))
    for k in range(4):
        s, ds = _diag_residual(A[k, k])
        r[k] = s
        Jr[k] = ds * dA[:, k, k]
    for k, (i, j) in enumerate(((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))):
        r[4 + k] = A[i, j]
        Jr[4 + k] = dA[:, i, j]
    return r, Jr


def divergence(J, J0) -> float:
    """The log-det divergence ``-log det(J0^-1 J) + tr(J0^-1 J) - 4`` of 4x4 pseudo-inertias."""
    X = np.linalg.solve(np.asarray(J0, float), np.asarray(J, float))
    sign, logdet = np.linalg.slogdet(X)
    return float(-logdet + np.trace(X) - 4.0) if sign > 0 else float("inf")


def _prior(robot):
    """``(U0^-1 per body, eta0 (10 nb), repaired body numbers)`` from the robot's own (URDF) inertias."""
    from .consistency import model_standard_parameters, pseudo_inertia

    pi0 = model_standard_parameters(robot.model)
    nb = pi0.size // 10
    inv, eta0, repaired = [], [], []
    for k in range(nb):
        J0 = pseudo_inertia(pi0[10 * k:10 * k + 10])
        lam, V = np.linalg.eigh(J0)
        if lam[0] <= 0:  # not a rigid body: floor its eigenvalues
            repaired.append(k + 1)
            J0 = (V * np.maximum(lam, PRIOR_FLOOR * max(float(lam[-1]), 1e-12))) @ V.T
        U0 = upper_cholesky(J0)
        inv.append(np.linalg.inv(U0))
        a = np.log(U0[3, 3])
        W = U0 / U0[3, 3]
        eta0.append([a, np.log(W[0, 0]), np.log(W[1, 1]), np.log(W[2, 2]), W[0, 1], W[1, 2], W[0, 2],
                     W[0, 3], W[1, 3], W[2, 3]])
    return inv, np.concatenate(eta0), repaired


@dataclass(frozen=True, eq=False)
class PhysicalFit:
    """The physically consistent estimate of :func:`fit_physical`.

    Attributes
    ----------
    x : ndarray (m,)
        ``(theta, friction)``: the base coefficients ``T pi`` and the friction coefficients.
    cov : ndarray (m, m)
        Their covariance (Laplace approximation, delta method).
    eta : ndarray (10 nb,)
        Log-Cholesky parameters of every body (Rucker and Wensing 2022; Pinocchio's order).
    standard : ndarray (10 nb,)
        The standard parameters ``pi(eta)`` (``m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz`` per body).
    cov_eta : ndarray (10 nb, 10 nb)
        Covariance of ``eta`` (Laplace approximation): :func:`draw_standard` draws from it.
    gamma : float
        The prior weight chosen (module docstring's rule).
    p : int
        Number of base coefficients.
    path : list of dict
        Every gamma fitted: ``gamma``, ``rms_ratio`` (per joint, training, against the unconstrained fit's),
        ``divergence`` (sum over links), ``mahalanobis`` (distance to the unconstrained estimate).
    info : dict
        ``repaired`` prior bodies, ``min_eigenvalues`` of the pseudo-inertias, ``masses``, solver status.
    """

    x: np.ndarray
    cov: np.ndarray
    eta: np.ndarray
    standard: np.ndarray
    cov_eta: np.ndarray
    gamma: float
    p: int
    path: list = field(default_factory=list)
    info: dict = field(default_factory=dict)

    @property
    def theta(self) -> np.ndarray:
        """The base coefficients (p,)."""
        return self.x[:self.p]

    @property
    def cov_theta(self) -> np.ndarray:
        """Their covariance (p, p)."""
        return self.cov[:self.p, :self.p]

    @property
    def masses(self) -> np.ndarray:
        """Every body's mass [kg] (nb,)."""
        return self.standard[0::10].copy()


def draw_standard(fit: PhysicalFit, rng, size: int | None = None) -> np.ndarray:
    """Standard parameters (size, 10 nb) (or (10 nb,)) of ``eta ~ N(fit.eta, fit.cov_eta)``: every one physical."""
    k = 1 if size is None else int(size)
    lam, V = np.linalg.eigh(0.5 * (fit.cov_eta + fit.cov_eta.T))
    L = V * np.sqrt(np.maximum(lam, 0.0))
    E = fit.eta + rng.standard_normal((k, fit.eta.size)) @ L.T
    with np.errstate(over="ignore", invalid="ignore"):
        out = np.array([standard_of(e) for e in E])
    return out[0] if size is None else out


def covariance_factor(cov) -> np.ndarray:
    """``S`` with ``S S^T = cov`` (symmetric square root; eigenvalues floored at 0)."""
    lam, V = np.linalg.eigh(0.5 * (np.asarray(cov, float) + np.asarray(cov, float).T))
    return (V * np.sqrt(np.maximum(lam, 0.0))) @ V.T


def realise_log_cholesky(T, theta, eta_start, S, iterations: int = 40, rtol: float = 1e-10, best: bool = False):
    r"""Log-Cholesky parameters near ``eta_start`` whose base coefficients ``T pi(eta)`` are ``theta``, or None.

    With ``best``, the last iterate instead of None when ``theta`` is not reached (the nearest physical
    coefficients the steps found: a real rigid body whose ``T pi`` the caller must check).

    Gauss-Newton with minimum-norm steps in the metric of ``S`` (``S S^T`` the Laplace covariance of
    ``eta``): :math:`\eta \leftarrow \eta + S (J S)^+ (	heta - T\pi(\eta))`, ``J = T d pi / d eta``,
    halving a step that does not reduce the misfit. Every iterate is a physical robot.
    """
    theta = np.asarray(theta, dtype=float)
    eta = np.asarray(eta_start, dtype=float).copy()
    scale = max(float(np.linalg.norm(theta)), 1e-300)
    r = theta - T @ standard_of(eta)
    miss = float(np.linalg.norm(r)) / scale
    for _ in range(int(iterations)):
        if miss <= rtol:
            return eta
        JS = T @ standard_jacobian(eta) @ S
        Gm = JS @ JS.T  # the minimum-norm step S JS^T (JS JS^T)^-1 r (Cholesky: no SVD, fast and thread-free)
        Gm[np.diag_indices_from(Gm)] += 1e-12 * np.trace(Gm) / Gm.shape[0]
        try:
            step = S @ (JS.T @ np.linalg.solve(Gm, r))
        except np.linalg.LinAlgError:
            break
        for _ in range(30):
            with np.errstate(over="ignore", invalid="ignore"):
                r_new = theta - T @ standard_of(eta + step)
                m_new = float(np.linalg.norm(r_new)) / scale
            if np.isfinite(m_new) and m_new < miss:
                break
            step = step / 2.0
        else:
            break
        eta, r, miss = eta + step, r_new, m_new
    return eta if miss <= rtol or best else None


def draws_inside(fit, T, P, rng, draws: int = INSIDE_DRAWS) -> float:
    """Share of ``draws`` seeded ``eta ~ N(fit.eta, fit.cov_eta)`` (all physical) whose ``T pi(eta)`` lies in
    the ellipsoid ``P`` about ``fit.theta``."""
    with np.errstate(over="ignore", invalid="ignore"):
        d = draw_standard(fit, rng, draws) @ np.asarray(T).T - fit.theta
        q = np.einsum("ki,ij,kj->k", d, np.asarray(P), d)
    return float(np.mean(np.isfinite(q) & (q <= 1.0)))


#: Joint-column kinds kept >= 0 by the consistent fit (a rotor inertia, viscous and Coulomb friction dissipate).
NONNEGATIVE = ("viscous", "coulomb", "armature")

#: The weak prior's width: at least this many standard deviations of the unconstrained estimate (:func:`joint_prior`).
JOINT_PRIOR_WIDTH = 3.0


def joint_prior(robot, kinds, columns, c_hat, c_std):
    """The weak prior of the fitted joint columns: centres and widths (each (len(columns),); NaN: none).

    ``viscous``, ``coulomb``, ``armature``: the URDF's ``damping``, ``friction``, ``armature``
    (Pinocchio's ``model.damping``, ``model.friction``, ``model.armature``; 0 where it has none), with
    width ``max(|c0|, |c_hat|, JOINT_PRIOR_WIDTH std)``: one unit of the fit's chi-square at most at the
    unconstrained estimate, so the data decide wherever they see the column (the pull moves it by at
    most about ``1 / JOINT_PRIOR_WIDTH^2`` of a standard deviation) and the prior only keeps the Laplace
    covariance finite. ``offset``: no prior.
    """
    model = robot.model
    n = robot.n
    kinds = tuple(kinds)
    urdf = {"viscous": model.damping, "coulomb": model.friction, "armature": model.armature}  # Pinocchio 3+
    c0 = np.full(len(columns), np.nan)
    for i, c in enumerate(np.asarray(columns, dtype=int)):
        kind, j = kinds[c // n], c % n
        if kind in urdf:
            vals = np.asarray(urdf[kind], dtype=float).ravel()
            c0[i] = float(vals[j]) if vals.size == n else 0.0
    width = np.maximum.reduce([np.abs(np.nan_to_num(c0)), np.abs(np.asarray(c_hat, float)),
                               JOINT_PRIOR_WIDTH * np.asarray(c_std, float)])
    width = np.maximum(width, 1e-12 * max(1.0, float(np.max(width, initial=0.0))))
    return c0, width


def _cov_inverse_factor(cov):
    lam, V = np.linalg.eigh(0.5 * (cov + cov.T))
    lam = np.maximum(lam, lam[-1] * 1e-15)
    return (V / np.sqrt(lam)).T  # W^T W = Cov^-1


def fit_physical(robot, x_hat, cov, A, y, friction_kinds, seed: int = 0, gammas=GAMMAS,
                 slack: float = MAHALANOBIS_SLACK, columns=None) -> PhysicalFit:
    """The physically consistent estimate nearest the data, pulled toward the URDF (module docstring).

    Parameters
    ----------
    robot : Robot
        The arm (its ``model`` gives the bodies and the prior, :func:`~rc3r.identify.consistency.standard_map`
        the map ``theta = T pi``).
    x_hat, cov : ndarray
        The unconstrained estimate (m,) ``(theta, friction)`` and its covariance (m, m).
    A, y : ndarray
        Training rows (N, n, m) and logged torques (N, n), for the reported training RMS.
    friction_kinds : tuple of str
        The joint-column kinds after theta (:data:`~rc3r.identify.regressors.JOINT_KINDS` order; ``viscous``,
        ``coulomb`` and ``armature`` are kept >= 0 and weakly pulled toward the URDF's ``damping``,
        ``friction`` and ``armature``: :func:`joint_prior`).
    seed : int
        Of :func:`standard_map`'s random states (robots without Pinocchio base parameters).
    gammas : sequence of float
        Prior weights tried, largest first.
    slack : float
        The rule's tolerance on the Mahalanobis distance (standard deviations).
    columns : sequence of int, optional
        The fitted joint columns among the ``n len(friction_kinds)`` (default all;
        :func:`~rc3r.identify.regressors.kept_columns`).

    Returns
    -------
    PhysicalFit
    """
    from scipy.optimize import least_squares

    from .consistency import pseudo_inertia, standard_map

    x_hat = np.asarray(x_hat, dtype=float)
    m = x_hat.size
    p = robot.p
    n = robot.n
    T = standard_map(robot, seed)
    nb = T.shape[1] // 10
    U0inv, eta0, repaired = _prior(robot)
    W = _cov_inverse_factor(np.asarray(cov, dtype=float))
    nf = m - p
    cols = np.arange(nf) if columns is None else np.asarray(columns, dtype=int)
    col_kinds = [tuple(friction_kinds)[c // n] for c in cols]
    lo = np.full(10 * nb + nf, -np.inf)
    lo[10 * nb:][np.array([k in NONNEGATIVE for k in col_kinds], dtype=bool)] = 0.0
    hi = np.full_like(lo, np.inf)
    c0, c_scale = joint_prior(robot, friction_kinds, cols, x_hat[p:], np.sqrt(np.maximum(np.diag(cov)[p:], 0.0)))
    pulled = np.isfinite(c0)

    def x_of(z):
        return np.concatenate([T @ standard_of(z[:10 * nb]), z[10 * nb:]])

    def residuals(z, g):
        r_d = W @ (x_of(z) - x_hat)
        r_p = np.concatenate([_prior_residuals(z[10 * k:10 * k + 10], U0inv[k])[0] for k in range(nb)])
        r_j = (z[10 * nb:][pulled] - c0[pulled]) / c_scale[pulled]
        return np.concatenate([r_d, np.sqrt(g) * r_p, r_j])

    def jacobian(z, g):
        G = np.zeros((m, z.size))
        G[:p, :10 * nb] = T @ standard_jacobian(z[:10 * nb])
        G[p:, 10 * nb:] = np.eye(nf)
        Jp = np.zeros((10 * nb, z.size))
        for k in range(nb):
            Jp[10 * k:10 * k + 10, 10 * k:10 * k + 10] = _prior_residuals(z[10 * k:10 * k + 10], U0inv[k])[1]
        Jj = np.zeros((int(pulled.sum()), z.size))
        Jj[np.arange(Jj.shape[0]), 10 * nb + np.nonzero(pulled)[0]] = 1.0 / c_scale[pulled]
        return np.vstack([W @ G, np.sqrt(g) * Jp, Jj]), G

    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)

    def train_rms(x):
        return np.sqrt(np.mean((y - A @ x) ** 2, axis=0))

    rms_hat = np.maximum(train_rms(x_hat), 1e-300)
    z = np.concatenate([eta0, np.maximum(x_hat[p:], lo[10 * nb:])])
    path, fits = [], []
    for g in gammas:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            sol = least_squares(residuals, z, jac=lambda z_, g_=g: jacobian(z_, g_)[0], bounds=(lo, hi), args=(g,),
                                method="trf", tr_solver="lsmr", x_scale="jac", xtol=1e-10, ftol=1e-10, gtol=1e-10,
                                max_nfev=MAX_EVALUATIONS)
        z = sol.x
        x = x_of(z)
        ratio = train_rms(x) / rms_hat
        div = [float(np.sum(_prior_residuals(z[10 * k:10 * k + 10], U0inv[k])[0] ** 2)) for k in range(nb)]
        r_d = W @ (x - x_hat)
        path.append({"gamma": float(g), "rms_ratio": ratio.tolist(), "divergence": float(sum(div)),
                     "mahalanobis": float(np.linalg.norm(r_d)), "status": int(sol.status),
                     "evaluations": int(sol.nfev)})
        fits.append((g, z.copy(), sol))
    floor = path[-1]["mahalanobis"]
    chosen = next(i for i, e in enumerate(path) if e["mahalanobis"] <= floor + slack)
    g, z, sol = fits[chosen]
    Jr, G = jacobian(z, g)
    H = Jr.T @ Jr
    lam, V = np.linalg.eigh(0.5 * (H + H.T))
    if lam[0] <= 0:
        raise ConfigError("the physically consistent fit's Hessian is singular: the prior does not determine "
                          "every link parameter")
    cov_z = (V / lam) @ V.T
    cov_x = G @ cov_z @ G.T
    cov_x = 0.5 * (cov_x + cov_x.T)
    x = x_of(z)
    eta = z[:10 * nb].copy()
    pi = standard_of(eta)
    mins = [float(np.linalg.eigvalsh(pseudo_inertia(pi[10 * k:10 * k + 10]))[0]) for k in range(nb)]
    info = {"repaired": repaired, "min_eigenvalues": mins, "masses": pi[0::10].tolist(),
            "prior_masses": standard_of(eta0)[0::10].tolist(),
            "divergence_per_body": [float(np.sum(_prior_residuals(eta[10 * k:10 * k + 10], U0inv[k])[0] ** 2))
                                    for k in range(nb)],
            "status": int(sol.status), "message": str(sol.message)}
    return PhysicalFit(x, cov_x, eta, pi, cov_z[:10 * nb, :10 * nb].copy(), float(g), p, path, info)
