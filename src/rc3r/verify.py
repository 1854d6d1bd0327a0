r"""Cross-check of a robot's model against Pinocchio (``rc3r verify-model``).

:func:`verify_model` takes any :class:`~rc3r.robots.base.Robot` and compares its
model terms (M, C, g), its coefficients theta and its Slotine--Li regressor with
Pinocchio's rigid-body algorithms on the robot's own Pinocchio model
(:attr:`Robot.model`) at random states. For the paper's arm that proves the
closed forms of :mod:`rc3r.robots.rr3` right. Each comparison is a :class:`Check`;
a run passes iff every check passes. Physical-consistency problems of the
parameters (:meth:`Robot.physical_issues`) and barely identifiable base parameters
(:data:`IDENTIFIABILITY_RTOL`) are reported as warnings and never fail a run.

A robot whose M, C and g *are* Pinocchio's ``crba``, ``computeCoriolisMatrix`` and
``computeGeneralizedGravity`` on its own model (``model_terms_are_pinocchio``, e.g.
:class:`~rc3r.robots.pinocchio.PinocchioRobot`) would compare Pinocchio with itself
there (error exactly 0: checks that cannot fail). For it those three checks are
replaced by M, C and g rebuilt from the robot's regressor (``Y theta``, a separate
compiled kernel) against Pinocchio, and the report says so (``notes``). Every robot
also gets two checks that need no reference model: the energy identity along a
simulated motion and the skew symmetry of ``dM/dt - 2 C`` with ``dM/dt`` by finite
differences of the robot's own M.

Error measure (defined once, here and in ``docs/conventions.md``): for a value
``x`` and a reference ``r`` (all entries at all samples of one check)

.. math::

    e_{abs} = \max |x - r|, \qquad e_{rel} = e_{abs} / \max(1, \max |r|)

i.e. relative to the largest reference magnitude, but never to less than one
unit (so a reference that is zero everywhere, like the first entry of ``g``, is
compared absolutely). A check passes iff :math:`e_{rel} \le` :data:`TOL`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .robots.base_parameters import IDENTIFIABILITY_RTOL, identifiability


__all__ = [
    "TOL",
    "RANK_RTOL",
    "MINIMALITY_STATES",
    "ENERGY_TOL",
    "FD_STEP",
    "FD_TOL",
    "IDENTIFIABILITY_RTOL",
    "Check",
    "VerifyReport",
    "sample_states",
    "compare",
    "mass_matrix_derivative",
    "pinocchio_references",
    "check_minimality",
    "model_from_regressor",
    "mass_matrix_derivative_fd",
    "check_energy",
    "identifiability",
    "verify_model",
]

#: Pass threshold on the relative error of every check. Each entry of M, S, g, Y is a sum of
#: O(10..100) float64 products of magnitudes up to O(100..1000) (theta up to ~10^2, qd qd up to
#: 25): rounding ~100 * 2.2e-16 * 1e3 ~ 2e-11 absolute, <= 1e-11 relative; Pinocchio's recursive
#: algorithms err as much. 1e-9 leaves a margin of ~100 and is 10^6 times below any modelling
#: error (a wrong sign or a missing l2 factor gives e_rel ~ 1e-2 .. 1).
TOL = 1e-9

#: Relative singular-value threshold for numerical rank (``s_k > RANK_RTOL * s_1``).
#: The stacked regressors have their 15th singular value near 1e-1 s_1 (measured
#: 0.07..0.12 on Table 1 and other arms) and the 16th at rounding level
#: (~1e-16 s_1), so any threshold in between gives the same rank; 1e-9 sits
#: far from both ends of that gap.
RANK_RTOL = 1e-9

#: The identification checks (``theta_least_squares``, ``minimality``) stack at
#: least this many states whatever ``samples`` is: fewer than 5 states cannot
#: determine 15 coefficients, and (3 * 200) x 30 is ample and cheap to SVD.
MINIMALITY_STATES = 200

#: Pass threshold of ``energy_identity``: the integral identity holds to the integrator's
#: error (DOP853 at rtol 1e-11, atol 1e-12 over 1 s: measured <= 1.7e-11 relative on the 3R, UR5,
#: Panda, SO-100/101, double pendulum); a 1 % error in g or M gives >= 1e-3.
ENERGY_TOL = 1e-8

#: Step h [s] of the 5-point central difference ``dM/dt ~ (M(q - 2h qd) - 8 M(q - h qd) +
#: 8 M(q + h qd) - M(q + 2h qd)) / (12 h)``: truncation ``O(h^4 |qd|^5)``, rounding O(1e-16 / h);
#: measured 2.6e-9 at h = 1e-3, 1.2e-12 at 1e-4 (best), 5e-12 at 2e-5 (3R, UR5, Panda, 1000 states).
FD_STEP = 1e-4
#: Pass threshold of ``skew_symmetry_fd`` (as :data:`TOL`; ~800 x the measured error).
FD_TOL = 1e-9

@dataclass(frozen=True)
class Check:
    """Result of one comparison.

    Attributes
    ----------
    max_abs_err : float
        ``max |x - r|`` over all entries and samples.
    max_rel_err : float
        ``max_abs_err / max(1, max |r|)`` (module docstring).
    tol : float
        Pass threshold on ``max_rel_err``.
    passed : bool
        ``max_rel_err <= tol`` (False if an error is NaN), plus any extra
        condition of the check (ranks for ``minimality``).
    detail : str
        Optional extra information (e.g. ranks).
    """

    max_abs_err: float
    max_rel_err: float
    tol: float
    passed: bool
    detail: str = ""


@dataclass(frozen=True)
class VerifyReport:
    """Outcome of :func:`verify_model`.

    Attributes
    ----------
    urdf : str
        Where the robot came from (its URDF path, or its label).
    theta : tuple of p float
        The robot's coefficients theta.
    checks : dict of str to Check
        One entry per identity (names in :func:`verify_model`).
    warnings : tuple of str
        Physical-consistency problems of the parameters (never fail the run).
    passed : bool
        True iff every check passed.
    samples, seed : int
        Number of random states and the RNG seed used.
    robot : str
        The robot's registry name.
    notes : tuple of str
        Checks not run and why (tautologies for a robot computed by Pinocchio).
    theta_order : str
        What the entries of theta are, in order (the robot's ``theta_order``).
    identifiability : float
        ``s_p / s_1`` of the stacked regressor Y (:func:`identifiability`).
    """

    urdf: str
    theta: tuple
    checks: dict = field(default_factory=dict)
    warnings: tuple = ()
    passed: bool = False
    samples: int = 0
    seed: int = 0
    robot: str = ""
    notes: tuple = ()
    theta_order: str = ""
    identifiability: float = math.nan


def compare(value, reference, tol: float = TOL) -> Check:
    """Compare ``value`` with ``reference`` (same shape) with the module's error measure.

    Parameters
    ----------
    value, reference : array_like, same shape
        Computed and reference arrays (any shape; all entries are pooled).
    tol : float
        Threshold on the relative error.

    Returns
    -------
    Check
    """
    x = np.asarray(value, dtype=float)
    r = np.asarray(reference, dtype=float)
    if x.shape != r.shape:
        raise ValueError(f"shape mismatch: {x.shape} vs {r.shape}")
    abs_err = float(np.max(np.abs(x - r))) if x.size else 0.0
    scale = max(1.0, float(np.max(np.abs(r)))) if r.size else 1.0
    rel_err = abs_err / scale
    return Check(abs_err, rel_err, tol, bool(rel_err <= tol))


def sample_states(n: int, seed: int = 0, joints: int = 3) -> dict[str, np.ndarray]:
    """Random states, each an (n, joints) array, from ``np.random.default_rng(seed)``.

    ``q`` is uniform in [-pi, pi] [rad]; ``qd``, ``qdd``, ``v``, ``a`` are
    uniform in [-5, 5] [rad/s, rad/s^2]; drawn in that order.
    """
    if n < 1:
        raise ValueError(f"need at least one sample, got {n}")
    rng = np.random.default_rng(seed)
    out = {"q": rng.uniform(-math.pi, math.pi, (n, joints))}
    for key in ("qd", "qdd", "v", "a"):
        out[key] = rng.uniform(-5.0, 5.0, (n, joints))
    return out


# ---- Pinocchio references ---------------------------------------------------------------


def _symmetrize_upper(M: np.ndarray) -> np.ndarray:
    """Full symmetric matrix from the upper triangle (``crba`` fills only that one)."""
    return np.triu(M) + np.triu(M, 1).T


def mass_matrix_derivative(model, data, q, qd) -> np.ndarray:
    r"""Exact :math:`\dot M(q) = \sum_k \partial M/\partial q_k\,\dot q_k` (n, n) from Pinocchio.

    With ``tau(q, 0, a) = M(q) a + g(q)``, column *j* of :math:`\dot M` is
    ``(dtau_dq(q, 0, e_j) - dtau_dq(q, 0, 0)) @ qd``, ``dtau_dq`` the first output of
    ``pinocchio.computeRNEADerivatives``: analytic, exact up to rounding (~1e-13). The robot's
    own M differentiated numerically is :func:`mass_matrix_derivative_fd`.
    """
    import pinocchio as pin

    nv = model.nv
    zero = np.zeros(nv)
    base = np.array(pin.computeRNEADerivatives(model, data, q, zero, zero)[0], copy=True)
    Md = np.empty((nv, nv))
    for j in range(nv):
        e = np.zeros(nv)
        e[j] = 1.0
        dq = np.array(pin.computeRNEADerivatives(model, data, q, zero, e)[0], copy=True)
        Md[:, j] = (dq - base) @ qd
    return Md


def pinocchio_references(model, states: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Pinocchio's values at each state (arrays with a leading axis N).

    Returns
    -------
    dict
        ``M`` (N,3,3) symmetrized ``crba``; ``C`` (N,3,3) ``computeCoriolisMatrix``;
        ``g`` (N,3) ``computeGeneralizedGravity``; ``c`` (N,3) ``rnea(q, qd, 0) - g``;
        ``tau`` (N,3) ``rnea(q, qd, qdd)``; ``tau_sl`` (N,3) ``M a + C v + g``;
        ``Mdot`` (N,3,3) :func:`mass_matrix_derivative`.
    """
    import pinocchio as pin

    data = model.createData()
    Q, QD, QDD, V, A = (states[k] for k in ("q", "qd", "qdd", "v", "a"))
    n = Q.shape[0]
    nv = model.nv
    out = {k: np.empty((n, nv, nv)) for k in ("M", "C", "Mdot")}
    out.update({k: np.empty((n, nv)) for k in ("g", "c", "tau", "tau_sl")})
    zero = np.zeros(nv)
    for i in range(n):
        q, qd = Q[i], QD[i]
        M = _symmetrize_upper(np.array(pin.crba(model, data, q), copy=True))
        C = np.array(pin.computeCoriolisMatrix(model, data, q, qd), copy=True)
        g = np.array(pin.computeGeneralizedGravity(model, data, q), copy=True)
        out["M"][i], out["C"][i], out["g"][i] = M, C, g
        out["c"][i] = pin.rnea(model, data, q, qd, zero) - g
        out["tau"][i] = pin.rnea(model, data, q, qd, QDD[i])
        out["tau_sl"][i] = M @ A[i] + C @ V[i] + g
        out["Mdot"][i] = mass_matrix_derivative(model, data, q, qd)
    return out


def _rnea(model, states: dict[str, np.ndarray]) -> np.ndarray:
    """``pinocchio.rnea(q, qd, qdd)`` at each state, shape (N, n)."""
    import pinocchio as pin

    data = model.createData()
    return np.array([pin.rnea(model, data, q, qd, qdd)
                     for q, qd, qdd in zip(states["q"], states["qd"], states["qdd"])])


# ---- the checks -------------------------------------------------------------------------


def _orthonormal_basis(X: np.ndarray, rtol: float) -> tuple[np.ndarray, int, np.ndarray]:
    """Orthonormal basis of the column space of X, its numerical rank, singular values."""
    U, s, _ = np.linalg.svd(X, full_matrices=False)
    rank = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0
    return U[:, :rank], rank, s


def _projection_residual(cols: np.ndarray, basis: np.ndarray) -> tuple[float, float]:
    """Largest residual of projecting the non-zero columns of ``cols`` on span(basis).

    Returns ``(max_abs, max_rel)`` with ``rel = ||(I - P) c|| / ||c||``; columns with
    ``||c|| <= RANK_RTOL * max ||c||`` (parameters that do not enter the dynamics,
    e.g. the mass of link 1) are in every span and skipped.
    """
    norms = np.linalg.norm(cols, axis=0)
    keep = norms > RANK_RTOL * norms.max()
    C = cols[:, keep]
    res = np.linalg.norm(C - basis @ (basis.T @ C), axis=0)
    return float(res.max()), float((res / norms[keep]).max())


def check_minimality(model, Y_stacked: np.ndarray, states: dict[str, np.ndarray],
                     tol: float = TOL) -> Check:
    r"""Theta is a *minimal* parametrization: span(Y) == span(Pinocchio regressor).

    Stacks ``pinocchio.computeJointTorqueRegressor`` (n x 10 bodies per state, the 10
    standard parameters of each body) over the states of ``Y_stacked``
    (:func:`verify_model` uses :data:`MINIMALITY_STATES` states). Since theta is
    linear in Pinocchio's parameters, span(Y_pin) is a subspace of span(Y); the
    check requires both numerical ranks to be p (:data:`RANK_RTOL`) and the
    relative residual of projecting each column of one matrix onto the column
    space of the other to be <= ``tol``.

    Parameters
    ----------
    Y_stacked : ndarray, shape (n * states, p)
        The robot's inverse-dynamics regressor at the first states of ``states``.
    states : dict
        As returned by :func:`sample_states` (``q``, ``qd``, ``qdd`` used).
    """
    import pinocchio as pin

    data = model.createData()
    nj = states["q"].shape[1]
    p = Y_stacked.shape[1]
    n = Y_stacked.shape[0] // nj
    Yp = np.vstack([
        np.array(pin.computeJointTorqueRegressor(model, data, states["q"][i], states["qd"][i],
                                                 states["qdd"][i]), copy=True)
        for i in range(n)
    ])
    Bp, rank_p, sp = _orthonormal_basis(Yp, RANK_RTOL)
    By, rank_y, _ = _orthonormal_basis(Y_stacked, RANK_RTOL)
    a1, r1 = _projection_residual(Yp, By)
    a2, r2 = _projection_residual(Y_stacked, Bp)
    gap = sp[p] / sp[0] if sp.size > p else 0.0
    detail = (f"rank(Pinocchio {nj}x{Yp.shape[1]} regressor, {n} states) = {rank_p}, rank(Y) = {rank_y}; "
              f"s{p + 1}/s1 = {gap:.1e}, s{p}/s1 = {sp[p - 1] / sp[0]:.1e}")
    rel = max(r1, r2)
    passed = rank_p == p and rank_y == p and bool(rel <= tol)
    return Check(max(a1, a2), rel, tol, passed, detail)


def _y_theta(robot, th, Q, QD, V, A, chunk: int = 2048) -> np.ndarray:
    """``robot.regressor(q, qd, v, a) @ th`` at (N, n) states, in chunks (bounded memory)."""
    out = np.empty(Q.shape)
    for k in range(0, Q.shape[0], chunk):
        sl = slice(k, k + chunk)
        out[sl] = robot.regressor(Q[sl], QD[sl], V[sl], A[sl]) @ th
    return out


def model_from_regressor(robot, theta, Q, QD) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""M (N,n,n), C (N,n,n), g (N,n) rebuilt from the Slotine--Li regressor alone.

    With :math:`Y(q, \dot q, v, a)\theta = M a + C(q, \dot q) v + g`:
    ``g = Y(q, 0, 0, 0) theta``, column j of M is ``Y(q, 0, 0, e_j) theta - g`` and column j
    of C is ``Y(q, qd, e_j, 0) theta - g``.
    """
    th = np.asarray(theta, dtype=float)
    N, n = Q.shape
    zero = np.zeros_like(Q)
    g = _y_theta(robot, th, Q, zero, zero, zero)
    M, C = np.empty((N, n, n)), np.empty((N, n, n))
    for j in range(n):
        e = np.zeros_like(Q)
        e[:, j] = 1.0
        M[:, :, j] = _y_theta(robot, th, Q, zero, zero, e) - g
        C[:, :, j] = _y_theta(robot, th, Q, QD, e, zero) - g
    return M, C, g


def mass_matrix_derivative_fd(robot, Q, QD, h: float = FD_STEP) -> np.ndarray:
    """dM/dt (N,n,n) along qd by the 5-point central difference of ``robot.mass_matrix`` (:data:`FD_STEP`)."""
    Mf = [robot.mass_matrix(Q + k * h * QD) for k in (-2, -1, 1, 2)]
    return (Mf[0] - 8.0 * Mf[1] + 8.0 * Mf[2] - Mf[3]) / (12.0 * h)


def check_energy(robot, seed: int = 0, duration: float = 1.0, points: int = 51) -> Check:
    r"""Energy identity :math:`\tfrac{d}{dt}\tfrac12 \dot q^T M \dot q = \dot q^T (\tau - g)` along a motion.

    The motion is ``robot.forward_dynamics`` (the plant) from a seeded state (q uniform in
    [-pi, pi], qd in [-1, 1]) under seeded torques ``tau_i = A_i sin(w_i t + phi_i)``
    (``A_i = 2 M_ii(q0) + |g_i(q0)|``, w in [1, 5] rad/s), integrated by DOP853 (rtol 1e-11,
    atol 1e-12) together with the work ``W(t) = int qd^T (tau - g(q)) dt``. Checks
    ``E(t) - E(0) == W(t)`` at ``points`` times, with ``E = qd^T M(q) qd / 2`` from the robot's
    ``mass_matrix``, ``g`` from its ``gravity`` (tolerance :data:`ENERGY_TOL`). C does no work
    and does not enter: a wrong M, g or plant fails it.
    """
    from scipy.integrate import solve_ivp

    n = robot.n
    rng = np.random.default_rng([seed, 2])  # a stream of its own: the random states are unchanged
    q0, qd0 = rng.uniform(-math.pi, math.pi, n), rng.uniform(-1.0, 1.0, n)
    amp = 2.0 * np.diag(robot.mass_matrix(q0)) + np.abs(robot.gravity(q0))
    w, phi = rng.uniform(1.0, 5.0, n), rng.uniform(0.0, 2 * math.pi, n)

    def rhs(t, y):
        q, qd = y[:n], y[n:2 * n]
        u = amp * np.sin(w * t + phi)
        return np.concatenate([qd, robot.forward_dynamics(q, qd, u), [qd @ (u - robot.gravity(q))]])

    with np.errstate(all="ignore"):
        sol = solve_ivp(rhs, (0.0, duration), np.concatenate([q0, qd0, [0.0]]), method="DOP853",
                        rtol=1e-11, atol=1e-12, t_eval=np.linspace(0.0, duration, points))
    if sol.status != 0 or sol.y.shape[1] != points:
        return Check(math.nan, math.nan, ENERGY_TOL, False, f"the motion could not be integrated: {sol.message}")
    Q, QD, W = sol.y[:n].T, sol.y[n:2 * n].T, sol.y[2 * n]
    E = 0.5 * np.einsum("ni,nij,nj->n", QD, robot.mass_matrix(Q), QD)
    return replace(compare(E - E[0], W, ENERGY_TOL), detail=f"{duration:g} s of forward_dynamics under seeded "
                   f"sine torques, {points} points: max|W| = {np.abs(W).max():.3g} J, max kinetic energy {E.max():.3g} J")


#: The tautological checks a robot computed by Pinocchio skips, and why (in the report's notes).
TAUTOLOGY_NOTE = ("M_vs_crba, S_vs_coriolis_matrix and g_vs_gravity are not run: this robot's M, C and g are "
                  "Pinocchio's crba, computeCoriolisMatrix and computeGeneralizedGravity on the same model, so "
                  "they would compare Pinocchio with itself (error exactly 0, a check that cannot fail); "
                  "M, C and g rebuilt from the compiled regressor Y theta replace them (*_from_regressor_*)")


def verify_model(robot, samples: int = 1000, seed: int = 0) -> VerifyReport:
    r"""Compare a robot's model and regressor with Pinocchio at random states.

    Parameters
    ----------
    robot : rc3r.robots.base.Robot
        The robot; its Pinocchio model (:attr:`Robot.model`) is the reference.
    samples : int
        Number of random states (:func:`sample_states`: q uniform in [-pi, pi],
        qd, qdd, v, a uniform in [-5, 5]).
    seed : int
        Seed of ``np.random.default_rng``.

    Returns
    -------
    VerifyReport
        Checks, each over all samples (shapes per state in parentheses):

        ===================================  ==========================================================
        ``M_vs_crba``                        M(q) (n,n) == crba (symmetrized)
        ``S_vs_coriolis_matrix``             C(q, qd) (n,n) == computeCoriolisMatrix
        ``g_vs_gravity``                     g(q) (n,) == computeGeneralizedGravity
        ``M_from_regressor_vs_crba``         instead of the three above when the robot's M, C, g are
        ``C_from_regressor_vs_coriolis``     Pinocchio's own (``model_terms_are_pinocchio``): M, C, g of
        ``g_from_regressor_vs_gravity``      :func:`model_from_regressor` against the same references
        ``Sqd_vs_rnea``                      C qd (n,) == rnea(q, qd, 0) - g
        ``Y_theta_vs_rnea``                  Y(q, qd, qd, qdd) theta (n,) == rnea(q, qd, qdd)
        ``Ysl_theta_vs_pinocchio``           Y(q, qd, v, a) theta (n,) == M a + C v + g (Pinocchio)
        ``skew_symmetry``                    C + C^T (n,n) == dM/dt (:func:`mass_matrix_derivative`)
        ``skew_symmetry_fd``                 C + C^T == dM/dt by :func:`mass_matrix_derivative_fd` of
                                             the robot's own M (dM/dt - 2C skew), tol :data:`FD_TOL`
        ``energy_identity``                  :func:`check_energy`, tol :data:`ENERGY_TOL`
        ``theta_least_squares``              lstsq of stacked Y (nN,p) against stacked rnea == theta (p,)
        ``minimality``                       :func:`check_minimality` on the first
                                             :data:`MINIMALITY_STATES` states
        ===================================  ==========================================================

        The two identification checks use the same states as the others if
        ``samples >= MINIMALITY_STATES``, else :data:`MINIMALITY_STATES` states
        drawn with the same seed; :func:`identifiability` of the same stack adds a warning.
    """
    th = np.asarray(robot.theta, dtype=float)
    nj, p = robot.n, robot.p
    model = robot.model
    st = sample_states(samples, seed, nj)
    Q, QD, QDD, V, A = (st[k] for k in ("q", "qd", "qdd", "v", "a"))
    ref = pinocchio_references(model, st)

    S = robot.coriolis_matrix(Q, QD)
    Y = robot.regressor(Q, QD, QD, QDD)
    Ysl = robot.regressor(Q, QD, V, A)
    Y_stacked = Y.reshape(-1, p)
    if samples >= MINIMALITY_STATES:
        st_id, Y_id, tau_id = st, Y_stacked, ref["tau"]
    else:  # too few states to identify p coefficients: use MINIMALITY_STATES of the same seed
        st_id = sample_states(MINIMALITY_STATES, seed, nj)
        Y_id = robot.regressor(st_id["q"], st_id["qd"], st_id["qd"], st_id["qdd"]).reshape(-1, p)
        tau_id = _rnea(model, st_id)
    theta_hat = np.linalg.lstsq(Y_id, tau_id.reshape(-1), rcond=None)[0]

    notes = []
    if robot.model_terms_are_pinocchio:
        M_y, C_y, g_y = model_from_regressor(robot, th, Q, QD)
        checks = {"M_from_regressor_vs_crba": compare(M_y, ref["M"]),
                  "C_from_regressor_vs_coriolis": compare(C_y, ref["C"]),
                  "g_from_regressor_vs_gravity": compare(g_y, ref["g"])}
        notes.append(TAUTOLOGY_NOTE)
    else:
        checks = {"M_vs_crba": compare(robot.mass_matrix(Q), ref["M"]),
                  "S_vs_coriolis_matrix": compare(S, ref["C"]),
                  "g_vs_gravity": compare(robot.gravity(Q), ref["g"])}
    sym = S + np.swapaxes(S, 1, 2)
    checks.update({
        "Sqd_vs_rnea": compare(np.einsum("nij,nj->ni", S, QD), ref["c"]),
        "Y_theta_vs_rnea": compare(Y @ th, ref["tau"]),
        "Ysl_theta_vs_pinocchio": compare(Ysl @ th, ref["tau_sl"]),
        "skew_symmetry": compare(sym, ref["Mdot"]),
        "skew_symmetry_fd": compare(sym, mass_matrix_derivative_fd(robot, Q, QD), FD_TOL),
        "energy_identity": check_energy(robot, seed),
        "theta_least_squares": compare(theta_hat, th),
        "minimality": check_minimality(model, Y_id[: nj * MINIMALITY_STATES], st_id),
    })
    ratio, weak = identifiability(Y_id[: nj * MINIMALITY_STATES], tuple(robot.coefficient_names))
    return VerifyReport(
        urdf=str(robot.urdf or robot.label),
        theta=tuple(float(x) for x in th),
        checks=checks,
        warnings=tuple(robot.physical_issues()) + tuple(weak),
        passed=all(c.passed for c in checks.values()),
        samples=samples,
        seed=seed,
        robot=robot.name,
        notes=tuple(notes),
        theta_order=robot.theta_order,
        identifiability=ratio,
    )
