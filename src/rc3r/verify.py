r"""Cross-check of a robot's model against Pinocchio (``rc3r verify-model``).

:func:`verify_model` takes any :class:`~rc3r.robots.base.Robot` and compares its
model terms (M, C, g), its coefficients theta and its Slotine--Li regressor with
Pinocchio's rigid-body algorithms on the robot's own Pinocchio model
(:attr:`Robot.model`) at random states. For the paper's arm that proves the
closed forms of :mod:`rc3r.robots.rr3` right. Each comparison is a :class:`Check`;
a run passes iff every check passes. Physical-consistency problems of the
parameters (:meth:`Robot.physical_issues`) are reported as warnings and never fail
a run.

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
from dataclasses import dataclass, field

import numpy as np


__all__ = [
    "TOL",
    "RANK_RTOL",
    "MINIMALITY_STATES",
    "Check",
    "VerifyReport",
    "sample_states",
    "compare",
    "mass_matrix_derivative",
    "pinocchio_references",
    "check_minimality",
    "verify_model",
]

#: Pass threshold on the relative error of every check. Each entry of M, S, g, Y
#: is a sum of O(10..100) float64 products of magnitudes up to O(100..1000)
#: (theta up to ~10^2, qd qd up to 25), so its rounding error is about
#: 100 * 2.2e-16 * 1e3 ~ 2e-11 absolute, i.e. <= 1e-11 relative to the scale of
#: e_rel; Pinocchio's recursive algorithms have errors of the same order.
#: 1e-9 leaves a margin of ~100 and is still 10^6 times below any modelling
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
    """

    urdf: str
    theta: tuple
    checks: dict = field(default_factory=dict)
    warnings: tuple = ()
    passed: bool = False
    samples: int = 0
    seed: int = 0
    robot: str = ""


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
    r"""Exact :math:`\dot M(q) = \sum_k \partial M/\partial q_k\,\dot q_k` (3, 3) from Pinocchio.

    With ``tau(q, 0, a) = M(q) a + g(q)``, column *j* of :math:`\dot M` is
    ``(dtau_dq(q, 0, e_j) - dtau_dq(q, 0, 0)) @ qd`` where ``dtau_dq`` is the first
    output of ``pinocchio.computeRNEADerivatives``. This is an analytic
    derivative, exact up to rounding (~1e-13). A finite difference of ``crba``
    would carry a truncation error O(h^4) against a rounding error O(eps/h)
    (best ~1e-11 relative, dependent on the scale of M), too close to the 1e-9
    pass threshold to be a reliable reference; ``tests/test_model.py`` uses a
    5-point central difference only to cross-check this function.
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

        ==========================  ==========================================================
        ``M_vs_crba``               M(q) (n,n) == crba (symmetrized)
        ``S_vs_coriolis_matrix``    C(q, qd) (n,n) == computeCoriolisMatrix
        ``Sqd_vs_rnea``             C qd (n,) == rnea(q, qd, 0) - g
        ``g_vs_gravity``            g(q) (n,) == computeGeneralizedGravity
        ``Y_theta_vs_rnea``         Y(q, qd, qd, qdd) theta (n,) == rnea(q, qd, qdd)
        ``Ysl_theta_vs_pinocchio``  Y(q, qd, v, a) theta (n,) == M a + C v + g (Pinocchio)
        ``skew_symmetry``           C + C^T (n,n) == dM/dt (:func:`mass_matrix_derivative`)
        ``theta_least_squares``     lstsq of stacked Y (nN,p) against stacked rnea == theta (p,)
        ``minimality``              :func:`check_minimality` on the first
                                    :data:`MINIMALITY_STATES` states
        ==========================  ==========================================================

        The two identification checks use the same states as the others if
        ``samples >= MINIMALITY_STATES``, else :data:`MINIMALITY_STATES` states
        drawn with the same seed.
    """
    th = np.asarray(robot.theta, dtype=float)
    nj, p = robot.n, robot.p
    model = robot.model
    st = sample_states(samples, seed, nj)
    Q, QD, QDD, V, A = (st[k] for k in ("q", "qd", "qdd", "v", "a"))
    ref = pinocchio_references(model, st)

    M = robot.mass_matrix(Q)
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

    checks = {
        "M_vs_crba": compare(M, ref["M"]),
        "S_vs_coriolis_matrix": compare(S, ref["C"]),
        "Sqd_vs_rnea": compare(np.einsum("nij,nj->ni", S, QD), ref["c"]),
        "g_vs_gravity": compare(robot.gravity(Q), ref["g"]),
        "Y_theta_vs_rnea": compare(Y @ th, ref["tau"]),
        "Ysl_theta_vs_pinocchio": compare(Ysl @ th, ref["tau_sl"]),
        "skew_symmetry": compare(S + np.swapaxes(S, 1, 2), ref["Mdot"]),
        "theta_least_squares": compare(theta_hat, th),
        "minimality": check_minimality(model, Y_id[: nj * MINIMALITY_STATES], st_id),
    }
    return VerifyReport(
        urdf=str(getattr(robot, "urdf", None) or robot.label),
        theta=tuple(float(x) for x in th),
        checks=checks,
        warnings=tuple(robot.physical_issues()),
        passed=all(c.passed for c in checks.values()),
        samples=samples,
        seed=seed,
        robot=robot.name,
    )
