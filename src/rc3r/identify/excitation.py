r"""Exciting trajectories: finite Fourier series within the joint limits, condition number minimised.

Each joint follows a finite Fourier series of period ``T`` (the duration: the trajectory closes
on itself), ``omega = 2 pi / T`` (Swevers, Ganseman, Tukel, de Schutter, Van Brussel, "Optimal
robot excitation and identification", IEEE T-RA 13(5), 1997):

.. math::

    q_j(t) = q_{0,j} + \sum_{l=1}^{L} \frac{a_{jl}}{\omega l}\sin(\omega l t)
                     - \frac{b_{jl}}{\omega l}\cos(\omega l t),

linear in the coefficients ``(q_0, a, b)``, as are ``qd`` and ``qdd``. The arm starts and ends at
rest (``qd = qdd = 0`` at ``t = 0`` and ``T``: two linear equalities per joint). Position,
velocity and acceleration limits, checked on a grid of :data:`CONSTRAINT_POINTS` samples per
period, are linear inequalities. The objective is the logarithm of the **condition number of the
column-scaled identification regressor** ``[Y | friction]`` stacked over :data:`OBJECTIVE_POINTS`
samples (scaling each column to unit norm makes the number independent of the coefficients'
units; it is what :func:`rc3r.identify.estimate.check_excitation` bounds). It is minimised by
SLSQP from a random start (``numpy.random.default_rng(seed)``), the best of ``starts`` runs; the
result is finally checked against the limits at the output rate and scaled about ``q_0`` if it
exceeds them there.

The trajectory is an :class:`rc3r.trajectory.Sines` (each harmonic one sine with a phase), so
``rc3r run`` and :func:`rc3r.simulate` can track it as they are.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .regressors import identification_regressor

__all__ = ["HARMONICS", "OBJECTIVE_POINTS", "CONSTRAINT_POINTS", "MAX_VELOCITY", "MAX_ACCELERATION", "LIMIT_MARGIN",
           "Limits", "limits_of", "regressor_condition", "Excitation", "fourier_trajectory", "random_fourier", "excite",
           "MIN_DURATION_S", "MAX_DURATION_S", "MAX_TRAJECTORY_SAMPLES", "check_length"]

#: Harmonics per joint.
HARMONICS = 5

#: Samples of the objective's stacked regressor.
OBJECTIVE_POINTS = 100

#: Samples per period at which the limits are imposed during the optimisation.
CONSTRAINT_POINTS = 400

#: Default velocity bound [rad/s]: min(this, 0.8 x the URDF's limit).
MAX_VELOCITY = 2.0

#: Default acceleration bound [rad/s^2] (URDFs have none).
MAX_ACCELERATION = 10.0

#: Fraction of each position range kept free at both ends; ranges are clipped to [-pi, pi].
LIMIT_MARGIN = 0.1

#: Shortest period of an exciting trajectory [s] (shorter ones cannot move an arm within its velocity and
#: acceleration bounds: the default trajectory's regressor over 0.1 s is rank-deficient).
MIN_DURATION_S = 1.0

#: Longest period [s] (one hour; the synthetic log simulates all of it).
MAX_DURATION_S = 3600.0

#: Most samples of the trajectory file (duration x rate + 1; 1e6 rows are about 100 MB of CSV).
MAX_TRAJECTORY_SAMPLES = 1_000_000


def check_length(duration: float, rate: float) -> int:
    """The number of samples of a trajectory of ``duration`` s at ``rate`` Hz, or a one-line ConfigError.

    Parameters
    ----------
    duration : float
        Period and length of the trajectory [s], in [:data:`MIN_DURATION_S`, :data:`MAX_DURATION_S`].
    rate : float
        Samples per second of its file [Hz].

    Returns
    -------
    int
        ``duration * rate + 1`` samples, in [:data:`rc3r.identify.log.MIN_SAMPLES`,
        :data:`MAX_TRAJECTORY_SAMPLES`] (a log of fewer samples is refused by ``rc3r identify``; more
        would be a file of gigabytes).

    Raises
    ------
    ConfigError
        Naming ``--duration`` (and ``--rate``) when either bound is not met.
    """
    from .log import MIN_SAMPLES

    if not (math.isfinite(duration) and MIN_DURATION_S <= duration <= MAX_DURATION_S):
        raise ConfigError(f"--duration {duration:g} s: an exciting trajectory lasts {MIN_DURATION_S:g} to "
                          f"{MAX_DURATION_S:g} s")
    if not (math.isfinite(rate) and rate > 0):
        raise ConfigError(f"--rate must be finite and > 0 Hz, got {rate:g}")
    samples = duration * rate + 1
    if not MIN_SAMPLES <= samples <= MAX_TRAJECTORY_SAMPLES:
        raise ConfigError(f"--duration {duration:g} s at --rate {rate:g} Hz is {samples:.4g} samples; a trajectory "
                          f"has {MIN_SAMPLES} to {MAX_TRAJECTORY_SAMPLES:.0e}")
    return int(samples)


@dataclass(frozen=True)
class Limits:
    """Per-joint bounds (each (n,)): ``lower``, ``upper`` [rad], ``velocity`` [rad/s], ``acceleration`` [rad/s^2]."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray

    def describe(self) -> dict:
        """JSON-ready."""
        return {k: np.asarray(v, float).tolist() for k, v in self.__dict__.items()}


def limits_of(robot, max_velocity: float | None = None, max_acceleration: float | None = None) -> Limits:
    """The excitation's limits for ``robot`` (module constants; options override the defaults)."""
    lo, hi = (np.asarray(x, dtype=float) for x in robot.joint_limits)
    lo, hi = np.maximum(lo, -math.pi), np.minimum(hi, math.pi)
    if np.any(hi <= lo):
        raise ConfigError("a joint has an empty position range")
    pad = LIMIT_MARGIN * (hi - lo)
    urdf_v = np.asarray(getattr(robot.model, "velocityLimit", np.full(robot.n, np.inf)), dtype=float)
    urdf_v = np.where(urdf_v > 0, urdf_v, np.inf)
    v = np.minimum(0.8 * urdf_v, MAX_VELOCITY) if max_velocity is None else np.full(robot.n, float(max_velocity))
    a = np.full(robot.n, MAX_ACCELERATION if max_acceleration is None else float(max_acceleration))
    for name, x in (("velocity", v), ("acceleration", a)):
        if not np.all(np.isfinite(x) & (x > 0)):
            raise ConfigError(f"maximum {name} must be finite and > 0, got {x.tolist()}")
    return Limits(lo + pad, hi - pad, v, a)


def _basis(t, omega: float, L: int):
    """Matrices (N, 2L + 1) of q, qd, qdd in one joint's coefficients ``(q0, a_1..a_L, b_1..b_L)``."""
    t = np.asarray(t, dtype=float)[:, None]
    l = np.arange(1, L + 1)[None, :]
    wl = omega * l
    s, c = np.sin(wl * t), np.cos(wl * t)
    one, zero = np.ones((t.size, 1)), np.zeros((t.size, 1))
    Bq = np.hstack([one, s / wl, -c / wl])
    Bv = np.hstack([zero, c, s])
    Ba = np.hstack([zero, -wl * s, wl * c])
    return Bq, Bv, Ba


def regressor_condition(robot, q, qd, qdd, kinds=("viscous", "coulomb", "offset")) -> float:
    """Condition number of the column-scaled identification regressor stacked over states (N, n)."""
    A = identification_regressor(robot, q, qd, qdd, kinds).reshape(-1, robot.p + robot.n * len(kinds))
    norms = np.linalg.norm(A, axis=0)
    if np.any(norms == 0):
        return float("inf")
    lam = np.linalg.eigvalsh((A / norms).T @ (A / norms))
    return float(np.sqrt(lam[-1] / lam[0])) if lam[0] > 0 else float("inf")


def fourier_trajectory(coef, duration: float):
    """The :class:`rc3r.trajectory.Sines` of coefficients ``coef`` (n, 2L + 1) with period ``duration``."""
    from ..trajectory import Sines

    coef = np.asarray(coef, dtype=float)
    n, k = coef.shape
    L = (k - 1) // 2
    omega = 2.0 * math.pi / duration
    terms = []
    for j in range(n):
        for l in range(1, L + 1):
            a, b = coef[j, l], coef[j, L + l]
            amp = math.hypot(a, b) / (omega * l)
            if amp > 0:
                terms.append((j + 1, amp, omega * l, math.atan2(-b, a)))
    return Sines(tuple(float(x) for x in coef[:, 0]), tuple(terms))


@dataclass(frozen=True, eq=False)
class Excitation:
    """An optimised exciting trajectory.

    Attributes
    ----------
    trajectory : rc3r.trajectory.Sines
    coefficients : ndarray (n, 2L + 1)
        ``(q0, a_1..a_L, b_1..b_L)`` per joint.
    duration : float
    condition : float
        Condition number of the column-scaled regressor along it (``check_points`` samples).
    baseline_condition : float
        The same for the robot's default (sine) trajectory over the same duration.
    limits : Limits
    seed, starts, iterations : int
    """

    trajectory: object
    coefficients: np.ndarray
    duration: float
    condition: float
    baseline_condition: float
    limits: Limits
    seed: int
    starts: int
    iterations: int

    def describe(self) -> dict:
        """JSON-ready (``excite``'s sidecar file)."""
        return {"duration_s": self.duration, "harmonics": (self.coefficients.shape[1] - 1) // 2,
                "condition_number": self.condition, "baseline_condition_number": self.baseline_condition,
                "baseline": "the robot's default sine trajectory over the same duration",
                "coefficients": self.coefficients.tolist(), "trajectory": self.trajectory.describe(),
                "limits": self.limits.describe(), "seed": self.seed, "starts": self.starts,
                "iterations": self.iterations,
                "condition_definition": "condition number of the column-scaled regressor [Y | friction] stacked "
                                        "over the samples"}


def _feasible_start(rng, n, L, omega, lim: Limits, Bq, Bv, Ba):
    """Random coefficients at rest at t = 0, scaled into the limits (half-way)."""
    coef = np.zeros((n, 2 * L + 1))
    coef[:, 0] = 0.5 * (lim.lower + lim.upper)
    coef[:, 1:] = rng.normal(0.0, 1.0, (n, 2 * L))
    coef = _rest(coef, omega)
    return _shrink(coef, lim, Bq, Bv, Ba, 0.5)


def random_fourier(robot, duration: float, seed: int = 0, harmonics: int = HARMONICS, limits: Limits | None = None,
                   fill: float = 0.5):
    """A random Fourier trajectory at rest at both ends, within ``fill`` x the limits (the optimiser's start).

    Coefficients from ``numpy.random.default_rng(seed)``; returns an :class:`rc3r.trajectory.Sines`.
    """
    lim = limits or limits_of(robot)
    omega = 2.0 * math.pi / duration
    B = _basis(np.arange(0.0, duration, 1e-3), omega, int(harmonics))
    coef = _feasible_start(np.random.default_rng(seed), robot.n, int(harmonics), omega, lim, *B)
    return fourier_trajectory(_shrink(coef, lim, *B, fill), duration)


def _rest(coef, omega):
    """Project each joint's (a, b) onto sum a = 0 and sum l b = 0 (rest at t = 0 and T)."""
    L = (coef.shape[1] - 1) // 2
    l = np.arange(1, L + 1, dtype=float)
    a, b = coef[:, 1:L + 1], coef[:, L + 1:]
    a -= a.mean(axis=1, keepdims=True)
    b -= (b @ l)[:, None] * l[None, :] / (l @ l)
    return coef


def _shrink(coef, lim: Limits, Bq, Bv, Ba, target: float = 1.0):
    """Scale the oscillating part of each joint so that its worst limit ratio is at most ``target``."""
    coef = coef.copy()
    for j in range(coef.shape[0]):
        osc = coef[j].copy()
        osc[0] = 0.0
        c0 = coef[j, 0]
        half = min(c0 - lim.lower[j], lim.upper[j] - c0)
        ratio = max(np.abs(Bq @ osc).max() / half, np.abs(Bv @ osc).max() / lim.velocity[j],
                    np.abs(Ba @ osc).max() / lim.acceleration[j], 1e-300)
        if ratio > target:
            coef[j, 1:] *= target / ratio
    return coef


def excite(robot, duration: float, seed: int = 0, harmonics: int = HARMONICS, limits: Limits | None = None,
           kinds=("viscous", "coulomb", "offset"), starts: int = 1, maxiter: int = 50,
           check_rate: float = 1000.0) -> Excitation:
    """An exciting trajectory of ``duration`` s for ``robot`` (module docstring)."""
    from scipy.optimize import minimize

    check_length(duration, check_rate)
    n, L = robot.n, int(harmonics)
    lim = limits or limits_of(robot)
    omega = 2.0 * math.pi / duration
    tc = np.linspace(0.0, duration, CONSTRAINT_POINTS, endpoint=False)
    Bq, Bv, Ba = _basis(tc, omega, L)
    to = np.linspace(0.0, duration, OBJECTIVE_POINTS, endpoint=False) + 0.5 * duration / OBJECTIVE_POINTS
    Oq, Ov, Oa = _basis(to, omega, L)
    k = 2 * L + 1
    l = np.arange(1, L + 1, dtype=float)

    def states(x):
        c = x.reshape(n, k)
        return (Oq @ c.T, Ov @ c.T, Oa @ c.T)

    def objective(x):
        cond = regressor_condition(robot, *states(x), kinds)
        return math.log(cond) if math.isfinite(cond) else 1e3

    # linear constraints G x <= h (as h - G x >= 0) and equalities E x = 0
    rows, rhs = [], []
    for j in range(n):
        for B, lo, hi in ((Bq, lim.lower[j], lim.upper[j]), (Bv, -lim.velocity[j], lim.velocity[j]),
                          (Ba, -lim.acceleration[j], lim.acceleration[j])):
            G = np.zeros((B.shape[0], n * k))
            G[:, j * k:(j + 1) * k] = B
            rows += [G, -G]
            rhs += [np.full(B.shape[0], hi), np.full(B.shape[0], -lo)]
    G, h = np.vstack(rows), np.concatenate(rhs)
    E = np.zeros((2 * n, n * k))
    for j in range(n):
        E[2 * j, j * k + 1: j * k + 1 + L] = 1.0
        E[2 * j + 1, j * k + 1 + L: (j + 1) * k] = l
    cons = [{"type": "ineq", "fun": lambda x: h - G @ x, "jac": lambda x: -G},
            {"type": "eq", "fun": lambda x: E @ x, "jac": lambda x: E}]
    rng = np.random.default_rng(seed)
    best, best_val, iters = None, np.inf, 0
    for _ in range(max(1, int(starts))):
        x0 = _feasible_start(rng, n, L, omega, lim, Bq, Bv, Ba).ravel()
        res = minimize(objective, x0, method="SLSQP", constraints=cons, options={"maxiter": int(maxiter)})
        iters += int(res.nit)
        x = res.x if np.all(h - G @ res.x >= -1e-6 * np.abs(h).max()) else x0
        val = objective(x)
        if val < best_val:
            best, best_val = x, val
    coef = _rest(best.reshape(n, k).copy(), omega)
    tf = np.arange(0.0, duration, 1.0 / check_rate)
    coef = _shrink(coef, lim, *_basis(tf, omega, L))
    traj = fourier_trajectory(coef, duration)
    tg = np.linspace(0.0, duration, 4 * OBJECTIVE_POINTS, endpoint=False)
    cond = regressor_condition(robot, *traj.evaluate(tg), kinds)
    base = regressor_condition(robot, *robot.default_trajectory().evaluate(tg), kinds)
    return Excitation(traj, coef, float(duration), cond, base, lim, int(seed), int(starts), iters)
