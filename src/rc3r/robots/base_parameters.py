r"""Numerical base parameters of a Pinocchio model (the ``theta`` of :class:`~rc3r.robots.pinocchio.PinocchioRobot`).

The inverse dynamics of a rigid serial arm is linear in the standard parameters
``pi`` (10 per moving body, Pinocchio's order and frame, :data:`STD_KEYS`):
``rnea(q, qd, qdd) = W(q, qd, qdd) pi`` with ``W`` the ``n x 10 nb``
``pinocchio.computeJointTorqueRegressor``. Its columns, as functions of the
state, are linearly dependent (some are identically zero, e.g. the mass of a
body on a vertical first joint; others are fixed combinations of earlier ones),
so only ``p <= 10 nb`` combinations of ``pi`` -- the *base parameters* -- are
identifiable, and every identity of the model holds with them.

Construction (:func:`base_parameters`)
    1. Stack ``W`` at ``10 * (10 nb)`` random states (``numpy.random.default_rng(seed)``;
       q uniform in [-pi, pi], qd and qdd uniform in [-5, 5]) and scale every
       column to unit norm; columns of norm ``<= ZERO_RTOL * max norm`` are zero
       (they never enter the dynamics).
    2. Rank ``p`` = number of singular values of the scaled matrix above
       ``RANK_RTOL * s_1``.
    3. Choose the independent columns **greedily in column order**: column ``j`` is
       kept iff its relative residual after projection on the span of the
       columns already kept exceeds :data:`INDEPENDENCE_TOL`. Whether column ``j``
       is in the span of the columns ``< j`` is a property of the functions, not of
       the sampled states, so the chosen set (and hence ``p``) does not depend on
       the seed (unlike column-pivoted QR, whose pivots follow the sampled values).
       The greedy count must equal the SVD rank, else the model is refused
       (:class:`~rc3r.errors.UrdfError`: no clear numerical rank).
    4. With ``B`` the chosen columns and ``D`` the others, ``W_D = W_B K``
       (least squares, exact up to rounding), so ``W pi = W_B (pi_B + K pi_D)``:

       .. math::  \theta = \pi_B + K \pi_D = T \pi, \qquad Y_{\mathrm{base}} = W_{[:, B]},

       with ``T`` the ``p x 10 nb`` matrix ``T[:, B] = I``, ``T[:, D] = K``.

Tolerances. Measured for the UR5, the Panda and the 3R arm (seeds 0, 1, 2): the
greedy residuals of dependent columns are <= 1.2e-15, those of independent
columns >= 0.60 (``benchmarks/base_parameter_gap.py``); the scaled singular values drop from s_p/s_1 >= 0.2 to
s_{p+1}/s_1 <= 5e-16. Any threshold between ~1e-13 and ~1e-2 selects the same
set; :data:`INDEPENDENCE_TOL` = 1e-7 and :data:`RANK_RTOL` = 1e-9 sit far from both
ends (``tests/test_robot_pinocchio.py`` asserts the gap). Entries of ``K`` of
magnitude <= :data:`K_ATOL` are rounding noise (measured <= 1e-17) and set to zero.

Identifiability (:func:`identifiability`). A kept column can still be *barely* independent: in
SI units its direction of theta may move the torques far less than the others (SO-101:
s_p/s_1 = 2.7e-7). Below :data:`IDENTIFIABILITY_RTOL` ``verify-model`` warns (never fails).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..conventions import STD_KEYS
from ..errors import UrdfError

__all__ = ["ZERO_RTOL", "RANK_RTOL", "INDEPENDENCE_TOL", "K_ATOL", "IDENTIFIABILITY_RTOL",
           "BaseParameters", "standard_parameter_names", "standard_regressor_stack", "base_parameters",
           "identifiability", "physical_issues", "check_model"]

#: A scaled-regressor column whose norm is at most this times the largest one is zero.
ZERO_RTOL = 1e-10

#: Relative singular-value threshold for the numerical rank (of the unit-norm columns).
RANK_RTOL = 1e-9

#: Relative projection residual above which a column is independent of the earlier ones.
INDEPENDENCE_TOL = 1e-7

#: Entries of K at most this large are rounding noise of the least squares (set to 0).
K_ATOL = 1e-12

#: A base parameter is *barely identifiable* when the stacked regressor Y (SI units; in
#: ``verify-model``, its identification states) has a singular value below this times its largest:
#: that direction of theta changes the torques 10^4 times less than the best-seen one, so a torque
#: error of 0.01 % of the torque scale (far below friction or sensor errors) hides it. Measured
#: s_p/s_1: 3R 0.10, UR5 0.033, Panda 0.03, double pendulum 0.23; SO-101 2.7e-7, SO-100 6.1e-7 (their
#: first axis is vertical up to the URDF's rpy "3.14159" for pi: a 2.7e-6 rad tilt lets gravity
#: act on body 1's first moments, mcx1 and mcy1, just barely). A warning, never a failure.
IDENTIFIABILITY_RTOL = 1e-4


def standard_parameter_names(nbodies: int) -> tuple[str, ...]:
    """``("m1", "mcx1", ..., "Izz1", "m2", ...)``: :data:`STD_KEYS` with the body number (1-based)."""
    return tuple(f"{key}{k}" for k in range(1, nbodies + 1) for key in STD_KEYS)


def standard_regressor_stack(model, states: int, seed: int = 0) -> np.ndarray:
    """``computeJointTorqueRegressor`` at ``states`` random states, stacked: (states * nv, 10 nb).

    q uniform in [-pi, pi], then qd, qdd uniform in [-5, 5], from
    ``numpy.random.default_rng(seed)``.
    """
    import pinocchio as pin

    rng = np.random.default_rng(seed)
    nv = model.nv
    Q = rng.uniform(-np.pi, np.pi, (states, nv))
    QD, QDD = rng.uniform(-5.0, 5.0, (2, states, nv))
    data = model.createData()
    return np.vstack([pin.computeJointTorqueRegressor(model, data, q, qd, qdd)
                      for q, qd, qdd in zip(Q, QD, QDD)])


@dataclass(frozen=True, eq=False)
class BaseParameters:
    """The linear map from standard to base parameters of one kinematic structure.

    Attributes
    ----------
    independent : ndarray of int, shape (p,)
        Standard-parameter columns kept (increasing): ``Y_base = W[:, independent]``.
    dependent : ndarray of int, shape (10 nb - p,)
        The other columns.
    K : ndarray, shape (p, 10 nb - p)
        ``W[:, dependent] = W[:, independent] @ K`` (zero columns give zero columns of K).
    T : ndarray, shape (p, 10 nb)
        ``theta = T @ pi`` (``T[:, independent] = I``, ``T[:, dependent] = K``).
    names : tuple of str
        Standard-parameter names (:func:`standard_parameter_names`).
    singular_values : ndarray
        Of the unit-column stacked regressor, descending (the rank gap is at ``p``).
    residuals : ndarray, shape (10 nb,)
        Greedy step: relative residual of each column against the columns kept before it
        (0 for zero columns).
    seed, states : int
        The sampling used.
    """

    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    T: np.ndarray
    names: tuple
    singular_values: np.ndarray
    residuals: np.ndarray
    seed: int = 0
    states: int = 0

    @property
    def p(self) -> int:
        """Number of base parameters."""
        return int(self.independent.size)

    def theta(self, std) -> np.ndarray:
        """Base parameters of standard-parameter vectors, (..., 10 nb) -> (..., p)."""
        std = np.asarray(std, dtype=float)
        if std.shape[-1:] != (self.T.shape[1],):
            raise ValueError(f"expected {self.T.shape[1]} standard parameters, got shape {std.shape}")
        return std @ self.T.T

    def coefficient_names(self) -> tuple[str, ...]:
        """One name per base parameter: its independent standard parameter, ``+`` if others add to it."""
        return tuple(self.names[j] + ("+" if np.any(self.K[k] != 0.0) else "")
                     for k, j in enumerate(self.independent))

    def expressions(self, digits: int = 6) -> tuple[str, ...]:
        """Each base parameter as text, e.g. ``"Izz2 + 0.0182 m3 + 0.2 mcx3"`` (non-zero K entries)."""
        out = []
        for k, j in enumerate(self.independent):
            terms = [self.names[j]]
            for c, d in zip(self.K[k], self.dependent):
                if c != 0.0:
                    terms.append(f"{'-' if c < 0 else '+'} {abs(c):.{digits}g} {self.names[d]}")
            out.append(" ".join(terms))
        return tuple(out)


def _greedy_independent(Wn: np.ndarray, zero: np.ndarray) -> tuple[list[int], np.ndarray]:
    """Columns of unit-norm ``Wn`` independent of the earlier kept ones (Gram--Schmidt, twice)."""
    basis = np.empty((Wn.shape[0], 0))
    kept, residuals = [], np.zeros(Wn.shape[1])
    for j in range(Wn.shape[1]):
        if zero[j]:
            continue
        r = Wn[:, j].copy()
        for _ in range(2):  # re-orthogonalization keeps the residual at rounding level
            r -= basis @ (basis.T @ r)
        residuals[j] = np.linalg.norm(r)
        if residuals[j] > INDEPENDENCE_TOL:
            kept.append(j)
            basis = np.column_stack([basis, r / residuals[j]])
    return kept, residuals


def base_parameters(model, seed: int = 0, states: int | None = None, where: str = "model") -> BaseParameters:
    """Base parameters of ``model``'s kinematic structure (module docstring: the algorithm).

    Parameters
    ----------
    model : pinocchio.Model
        Joints all 1-DoF (``nq == nv``); its inertias are not used.
    seed : int
        Seed of the random states (the result does not depend on it).
    states : int, optional
        Number of states to stack (default ``10 * 10 nb``, i.e. 10 per standard parameter).
    where : str
        Name of the model in error messages.

    Raises
    ------
    UrdfError
        The regressor is identically zero, or its numerical rank is ambiguous
        (greedy count differs from the SVD rank).
    """
    nb = model.njoints - 1
    size = 10 * nb
    states = int(states or 10 * size)
    W = standard_regressor_stack(model, states, seed)
    norms = np.linalg.norm(W, axis=0)
    if not norms.max() > 0:
        raise UrdfError(f"{where}: the joint-torque regressor is identically zero (no body moves)")
    zero = norms <= ZERO_RTOL * norms.max()
    Wn = W / np.where(zero, 1.0, norms)
    Wn[:, zero] = 0.0
    s = np.linalg.svd(Wn, compute_uv=False)
    rank = int(np.sum(s > RANK_RTOL * s[0]))
    kept, residuals = _greedy_independent(Wn, zero)
    if len(kept) != rank:
        raise UrdfError(f"{where}: regressor has no clear numerical rank (SVD rank {rank}, "
                        f"{len(kept)} greedily independent columns)")
    B = np.array(kept, dtype=int)
    D = np.array([j for j in range(size) if j not in set(kept)], dtype=int)
    K = np.linalg.lstsq(W[:, B], W[:, D], rcond=None)[0] if D.size else np.zeros((B.size, 0))
    K[:, zero[D]] = 0.0
    K[np.abs(K) <= K_ATOL] = 0.0
    T = np.zeros((B.size, size))
    T[:, B] = np.eye(B.size)
    T[:, D] = K
    for arr in (B, D, K, T, s, residuals):
        arr.flags.writeable = False
    return BaseParameters(B, D, K, T, standard_parameter_names(nb), s, residuals, seed, states)


def identifiability(Y_stacked: np.ndarray, names) -> tuple[float, list[str]]:
    """``s_p / s_1`` of the stacked regressor (SI units) and a warning if below :data:`IDENTIFIABILITY_RTOL`.

    The warning counts the singular values below the threshold and names, for each, the base
    parameters that carry its right singular vector (entries >= 0.3 in magnitude).
    """
    _, s, Vt = np.linalg.svd(Y_stacked, full_matrices=False)
    ratio = float(s[-1] / s[0]) if s.size and s[0] > 0 else 0.0
    weak = np.flatnonzero(s < IDENTIFIABILITY_RTOL * s[0]) if s.size else np.array([], int)
    if not weak.size:
        return ratio, []
    who = sorted({names[i] for k in weak for i in np.flatnonzero(np.abs(Vt[k]) >= 0.3)})
    vals = ", ".join(f"s{k + 1}/s1 = {s[k] / s[0]:.1e}" for k in weak)
    return ratio, [f"{weak.size} base-parameter direction(s) barely identifiable: {vals} < "
                   f"{IDENTIFIABILITY_RTOL:g} (mostly {', '.join(who)}): their effect on the torques is "
                   "that much smaller than the largest, so bounds and estimates of them rest on tiny torques"]


def physical_issues(std, body_names=None) -> list[str]:
    """Physical-consistency problems of standard parameters (10 per body, :data:`STD_KEYS`).

    Per body: mass < 0, or 0 with non-zero moments; inertia about the CoM
    ``I_O - m (|c|^2 1 - c c^T)`` (``c = m c / m``) not positive definite; principal
    moments violating the triangle inequality ``e1 + e2 >= e3`` (both up to
    1e-12 of the largest principal moment). A body whose 10 parameters are all zero
    (a massless link between two joints) is no issue.
    """
    std = np.asarray(std, dtype=float)
    issues = []
    for k in range(std.size // 10):
        m, mc, (ixx, ixy, iyy, ixz, iyz, izz) = std[10 * k], std[10 * k + 1: 10 * k + 4], std[10 * k + 4: 10 * k + 10]
        who = f"body {k + 1}" + (f" ({body_names[k]})" if body_names is not None else "")
        if m == 0.0 and not np.any(std[10 * k: 10 * k + 10]):
            continue
        if m <= 0:
            issues.append(f"{who}: mass {m:g} kg <= 0")
            continue
        c = mc / m
        I_c = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]) - m * (c @ c * np.eye(3) - np.outer(c, c))
        e = np.linalg.eigvalsh(I_c)
        scale = max(abs(e).max(), 1e-300)
        if e[0] <= 1e-12 * scale:
            issues.append(f"{who}: inertia about the CoM not positive definite (eigenvalues {e.tolist()})")
        elif e[0] + e[1] < e[2] - 1e-12 * scale:
            issues.append(f"{who}: principal moments {e.tolist()} violate the triangle inequality")
    return issues


def check_model(model, where: str, samples: int = 5, seed: int = 0) -> None:
    """UrdfError unless every joint is 1-DoF, some body has mass, and M(q) is positive definite.

    M(q) is checked by a Cholesky factorization of ``crba`` at ``samples`` random
    configurations (q uniform in [-pi, pi], ``numpy.random.default_rng(seed)``); a
    joint that moves no mass or inertia makes it singular everywhere.
    """
    import pinocchio as pin

    if model.njoints < 2:
        raise UrdfError(f"{where}: no moving joint")
    for i in range(1, model.njoints):
        j = model.joints[i]
        if j.nq != 1 or j.nv != 1:
            raise UrdfError(f"{where}: joint '{model.names[i]}' ({j.shortname()}, nq={j.nq}, nv={j.nv}) is not "
                            "1-DoF with nq = nv = 1 (revolute or prismatic; continuous ones through from_urdf)")
    if not any(model.inertias[i].mass > 0 for i in range(1, model.njoints)):
        raise UrdfError(f"{where}: no inertias (every moving body has zero mass)")
    data = model.createData()
    for q in np.random.default_rng(seed).uniform(-math.pi, math.pi, (samples, model.nv)):
        M = np.array(pin.crba(model, data, q))
        try:
            np.linalg.cholesky(np.triu(M) + np.triu(M, 1).T)
        except np.linalg.LinAlgError:
            raise UrdfError(f"{where}: M(q) is singular at q = {np.round(q, 3).tolist()}: "
                            "some joint moves no mass or inertia") from None
