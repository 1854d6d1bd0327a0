r"""Cross-check of the closed-form model against Pinocchio (``rc3r verify-model``).

:func:`verify_model` loads a URDF of the paper's 3R structure, computes the
coefficients :math:`\theta(p)` of its parameters and compares every closed form
of :mod:`rc3r.model` and :mod:`rc3r.regressor` with Pinocchio's rigid-body
algorithms at random states. Each comparison is a :class:`Check`; a run passes
iff every check passes. Physical-consistency problems of the parameters
(:func:`rc3r.params.physical_issues`) are reported as warnings and never fail a
run.

Error measure (defined once, here and in ``docs/conventions.md``): for a value
``x`` and a reference ``r`` (all entries at all samples of one check)

.. math::

    e_{abs} = \max |x - r|, \qquad e_{rel} = e_{abs} / \max(1, \max |r|)

i.e. relative to the largest reference magnitude, but never to less than one
unit (so a reference that is zero everywhere, like the first entry of ``g``, is
compared absolutely). A check passes iff :math:`e_{rel} \le` :data:`TOL`.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np

from . import model as mdl
from . import regressor as reg
from .params import physical_issues, theta as theta_of
from .urdf import load_arm

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
    "render_text",
    "report_to_dict",
    "cmd_verify_model",
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

#: Number of coefficients theta (columns of Y).
N_THETA = 15


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
        Path of the URDF checked.
    theta : tuple of 15 float
        :math:`\\theta(p)` of the URDF's parameters, paper order.
    checks : dict of str to Check
        One entry per identity (names in :func:`verify_model`).
    warnings : tuple of str
        Physical-consistency problems of the parameters (never fail the run).
    passed : bool
        True iff every check passed.
    samples, seed : int
        Number of random states and the RNG seed used.
    """

    urdf: str
    theta: tuple
    checks: dict = field(default_factory=dict)
    warnings: tuple = ()
    passed: bool = False
    samples: int = 0
    seed: int = 0


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


def sample_states(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Random states, each an (n, 3) array, from ``np.random.default_rng(seed)``.

    ``q`` is uniform in [-pi, pi] [rad]; ``qd``, ``qdd``, ``v``, ``a`` are
    uniform in [-5, 5] [rad/s, rad/s^2]; drawn in that order.
    """
    if n < 1:
        raise ValueError(f"need at least one sample, got {n}")
    rng = np.random.default_rng(seed)
    out = {"q": rng.uniform(-math.pi, math.pi, (n, 3))}
    for key in ("qd", "qdd", "v", "a"):
        out[key] = rng.uniform(-5.0, 5.0, (n, 3))
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

    zero = np.zeros(3)
    base = np.array(pin.computeRNEADerivatives(model, data, q, zero, zero)[0], copy=True)
    Md = np.empty((3, 3))
    for j in range(3):
        e = np.zeros(3)
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
    out = {k: np.empty((n, 3, 3)) for k in ("M", "C", "Mdot")}
    out.update({k: np.empty((n, 3)) for k in ("g", "c", "tau", "tau_sl")})
    zero = np.zeros(3)
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
    """``pinocchio.rnea(q, qd, qdd)`` at each state, shape (N, 3)."""
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

    Stacks ``pinocchio.computeJointTorqueRegressor`` (3 x 30 per state, the 10
    standard parameters of each body) over the n states of ``Y_stacked``
    (:func:`verify_model` uses :data:`MINIMALITY_STATES` states). Since theta is
    linear in Pinocchio's parameters, span(Y_pin) is a subspace of span(Y); the check requires both numerical ranks to be 15
    (:data:`RANK_RTOL`) and the relative residual of projecting each column of
    one matrix onto the column space of the other to be <= ``tol``.

    Parameters
    ----------
    Y_stacked : ndarray, shape (3 n, 15)
        The closed-form regressor at the first n states of ``states``.
    states : dict
        As returned by :func:`sample_states` (``q``, ``qd``, ``qdd`` used).
    """
    import pinocchio as pin

    data = model.createData()
    n = Y_stacked.shape[0] // 3
    Yp = np.vstack([
        np.array(pin.computeJointTorqueRegressor(model, data, states["q"][i], states["qd"][i],
                                                 states["qdd"][i]), copy=True)
        for i in range(n)
    ])
    Bp, rank_p, sp = _orthonormal_basis(Yp, RANK_RTOL)
    By, rank_y, _ = _orthonormal_basis(Y_stacked, RANK_RTOL)
    a1, r1 = _projection_residual(Yp, By)
    a2, r2 = _projection_residual(Y_stacked, Bp)
    gap = sp[N_THETA] / sp[0] if sp.size > N_THETA else 0.0
    detail = (f"rank(Pinocchio 3x30 regressor, {n} states) = {rank_p}, rank(Y) = {rank_y}; "
              f"s16/s1 = {gap:.1e}, s15/s1 = {sp[N_THETA - 1] / sp[0]:.1e}")
    rel = max(r1, r2)
    passed = rank_p == N_THETA and rank_y == N_THETA and bool(rel <= tol)
    return Check(max(a1, a2), rel, tol, passed, detail)


def verify_model(urdf_path=None, samples: int = 1000, seed: int = 0) -> VerifyReport:
    r"""Compare the closed-form model of a URDF's arm with Pinocchio at random states.

    Parameters
    ----------
    urdf_path : path-like, optional
        URDF of a 3R arm of the paper's structure; default the committed
        ``urdf/rr3.urdf`` (:func:`rc3r.urdf.default_urdf_path`).
    samples : int
        Number of random states (:func:`sample_states`: q uniform in [-pi, pi],
        qd, qdd, v, a uniform in [-5, 5]).
    seed : int
        Seed of ``np.random.default_rng``.

    Returns
    -------
    VerifyReport
        Checks, each over all samples (shapes per state in parentheses):

        ``M_vs_crba``            M(q) (3,3) == crba (symmetrized)
        ``S_vs_coriolis_matrix`` S(q, qd) (3,3) == computeCoriolisMatrix
        ``Sqd_vs_rnea``          S qd (3,) == rnea(q, qd, 0) - g
        ``g_vs_gravity``         g(q) (3,) == computeGeneralizedGravity
        ``Y_theta_vs_rnea``      Y(q, qd, qdd) theta (3,) == rnea(q, qd, qdd)
        ``Ysl_theta_vs_pinocchio`` Y(q, qd, v, a) theta (3,) == M a + C v + g (Pinocchio)
        ``skew_symmetry``        S + S^T (3,3) == dM/dt (:func:`mass_matrix_derivative`)
        ``theta_least_squares``  lstsq of stacked Y (3N,15) against stacked rnea == theta (15,)
        ``minimality``           :func:`check_minimality` on the first
                                 :data:`MINIMALITY_STATES` states

        The two identification checks use the same states as the others if
        ``samples >= MINIMALITY_STATES``, else :data:`MINIMALITY_STATES` states
        drawn with the same seed (15 coefficients need at least 5 states).

    Raises
    ------
    UrdfError
        Missing, malformed or non-3R URDF (from :func:`rc3r.urdf.load_arm`).
    """
    arm = load_arm(urdf_path)
    p = arm.params
    th = theta_of(p)
    l2, g0 = p.lengths[1], p.g0
    st = sample_states(samples, seed)
    Q, QD, QDD, V, A = (st[k] for k in ("q", "qd", "qdd", "v", "a"))
    ref = pinocchio_references(arm.model, st)

    M = mdl.mass_matrix(th, Q)
    S = mdl.coriolis_matrix(th, Q, QD)
    Y = reg.regressor(Q, QD, QDD, l2=l2, g0=g0)
    Ysl = reg.slotine_li_regressor(Q, QD, V, A, l2=l2, g0=g0)
    Y_stacked = Y.reshape(-1, N_THETA)
    if samples >= MINIMALITY_STATES:
        st_id, Y_id, tau_id = st, Y_stacked, ref["tau"]
    else:  # too few states to identify 15 coefficients: use MINIMALITY_STATES of the same seed
        st_id = sample_states(MINIMALITY_STATES, seed)
        Y_id = reg.regressor(st_id["q"], st_id["qd"], st_id["qdd"], l2=l2, g0=g0).reshape(-1, N_THETA)
        tau_id = _rnea(arm.model, st_id)
    theta_hat = np.linalg.lstsq(Y_id, tau_id.reshape(-1), rcond=None)[0]

    checks = {
        "M_vs_crba": compare(M, ref["M"]),
        "S_vs_coriolis_matrix": compare(S, ref["C"]),
        "Sqd_vs_rnea": compare(np.einsum("nij,nj->ni", S, QD), ref["c"]),
        "g_vs_gravity": compare(mdl.gravity(th, Q, l2=l2, g0=g0), ref["g"]),
        "Y_theta_vs_rnea": compare(Y @ th, ref["tau"]),
        "Ysl_theta_vs_pinocchio": compare(Ysl @ th, ref["tau_sl"]),
        "skew_symmetry": compare(S + np.swapaxes(S, 1, 2), ref["Mdot"]),
        "theta_least_squares": compare(theta_hat, th),
        "minimality": check_minimality(arm.model, Y_id[: 3 * MINIMALITY_STATES], st_id),
    }
    return VerifyReport(
        urdf=arm.path,
        theta=tuple(float(x) for x in th),
        checks=checks,
        warnings=tuple(physical_issues(p)),
        passed=all(c.passed for c in checks.values()),
        samples=samples,
        seed=seed,
    )


# ---- rendering --------------------------------------------------------------------------


def _finite_or_none(x: float):
    return float(x) if math.isfinite(x) else None


def report_to_dict(report: VerifyReport) -> dict:
    """The ``--json`` object: urdf, theta, checks, warnings, pass (+ tol, samples, seed).

    Non-finite errors become ``null`` so the output is strict JSON.
    """
    return {
        "urdf": report.urdf,
        "theta": list(report.theta),
        "checks": {
            name: {
                "max_abs_err": _finite_or_none(c.max_abs_err),
                "max_rel_err": _finite_or_none(c.max_rel_err),
                "tol": c.tol,
                "pass": c.passed,
                **({"detail": c.detail} if c.detail else {}),
            }
            for name, c in report.checks.items()
        },
        "warnings": list(report.warnings),
        "pass": report.passed,
        "samples": report.samples,
        "seed": report.seed,
    }


def render_text(report: VerifyReport) -> str:
    """Human-readable report: aligned table, theta, warnings, overall PASS/FAIL."""
    w = max(len("check"), *(len(n) for n in report.checks))
    lines = [
        f"rc3r verify-model: {report.urdf}",
        f"{report.samples} random states (seed {report.seed}); "
        "rel err = max|x - ref| / max(1, max|ref|)",
        "",
        f"{'check':<{w}}  {'max abs err':>11}  {'max rel err':>11}  {'tol':>7}  result",
    ]
    for name, c in report.checks.items():
        lines.append(f"{name:<{w}}  {c.max_abs_err:11.3e}  {c.max_rel_err:11.3e}  {c.tol:7.0e}  "
                     f"{'PASS' if c.passed else 'FAIL'}")
    for name, c in report.checks.items():
        if c.detail:
            lines.append(f"  {name}: {c.detail}")
    lines += ["", "theta (paper order, section 3.1.1):"]
    for k in range(0, len(report.theta), 5):
        lines.append("  " + "  ".join(f"th{k + j + 1:<2d} = {x:10.6g}"
                                      for j, x in enumerate(report.theta[k:k + 5])))
    lines.append("")
    if report.warnings:
        lines.append("warnings (do not fail the run):")
        lines += [f"  - {wrn}" for wrn in report.warnings]
    else:
        lines.append("warnings: none (every link is physically consistent)")
    failed = [n for n, c in report.checks.items() if not c.passed]
    lines.append("")
    lines.append("PASS: every check passed" if report.passed
                 else f"FAIL: {len(failed)} check(s) failed: {', '.join(failed)}")
    return "\n".join(lines)


def cmd_verify_model(args) -> int:
    """``rc3r verify-model``: print the report (text or one JSON object); 0 iff all pass."""
    report = verify_model(args.urdf, samples=args.samples, seed=args.seed)
    if args.json:
        print(json.dumps(report_to_dict(report), allow_nan=False))
    else:
        print(render_text(report))
    return 0 if report.passed else 1
