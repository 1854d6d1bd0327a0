r"""A sampled lower bound on the largest distance ``max over the box of ||theta - theta0||``.

Complements the certified upper bound of :mod:`rc3r.uncertainty.bounds`: every
candidate here is a point of the box, so the result is a true lower bound; the
two together bracket the smallest valid rho around a given ``theta0``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..io import floats as _floats
from .bounds import _structure, _Structure
from .box import Box

__all__ = ["SampledRho", "sampled_rho", "sampled_rho_detail"]

@dataclass(frozen=True, eq=False)
class SampledRho:
    """A lower bound on ``max over the box of ||theta - theta0||`` and how it was found."""

    rho: float
    seed: int
    n_uniform: int
    n_corners: int
    all_corners: bool
    n_ascent_starts: int
    witness: np.ndarray  # standard-parameter vector (10 * bodies,) that attains ``rho``

    def to_dict(self) -> dict:
        return {
            "rho": float(self.rho),
            "seed": self.seed,
            "n_uniform": self.n_uniform,
            "n_corners": self.n_corners,
            "all_relevant_corners": self.all_corners,
            "n_ascent_starts": self.n_ascent_starts,
            "witness": _floats(self.witness),
        }


def _relevant(S: _Structure, box: Box) -> np.ndarray:
    """Parameters with a nonzero interval that enter theta at all."""
    rel = np.zeros(box.size, dtype=bool)
    for k in range(box.bodies):
        rel[10 * k] = np.any(S.a[k] != 0) or np.any(S.b[k] != 0) or np.any(S.Q[k] != 0)
        for j in range(3):
            rel[10 * k + 1 + j] = np.any(np.abs(S.b[k, :, j]) > 1e-14) or np.any(np.abs(S.Q[k, :, j, :]) > 1e-14)
        rel[10 * k + 4 : 10 * k + 10] = np.any(np.abs(S.C[k]) > 1e-14, axis=0)
    return rel & (box.width > 0)


def _norms(std, robot, theta0, chunk: int = 1 << 16) -> np.ndarray:
    out = np.empty(len(std))
    for s in range(0, len(std), chunk):
        out[s : s + chunk] = np.linalg.norm(robot.theta_of_standard(std[s : s + chunk]) - theta0, axis=-1)
    return out


def sampled_rho_detail(robot, box: Box, theta0, n: int = 100_000, seed: int = 0,
                       max_corner_bits: int = 20, ascent_starts: int = 8) -> SampledRho:
    """Lower bound on ``max_{box} ||theta - theta0||`` by evaluation at points of the box.

    Candidates: ``n`` uniform samples (``numpy.random.default_rng(seed)``); every
    corner of the parameters that have a nonzero interval and enter theta if
    there are at most ``max_corner_bits`` of them, else ``n`` random such corners;
    then coordinate ascent from the ``ascent_starts`` best candidates, each step
    maximising exactly along one coordinate (theta is at most quadratic in any
    single standard parameter, so ``||theta - theta0||^2`` is a quartic whose
    maximum on the interval is at an endpoint or a root of its cubic derivative).
    Every candidate is a point of the box, so the result is a true lower bound.
    """
    theta0 = np.asarray(theta0, dtype=float)
    if theta0.shape != robot.theta.shape:
        raise ParameterError(f"theta0 needs {robot.p} entries, got shape {theta0.shape}")
    n = int(n)
    if n < 0:
        raise ParameterError(f"sample count must be >= 0, got {n}")
    box.check(robot)
    L = robot
    nom = robot.standard_parameters()
    lo, hi = nom + box.lower, nom + box.upper
    rng = np.random.default_rng(seed)
    S = _structure(robot)
    rel = np.flatnonzero(_relevant(S, box))

    pts = [nom[None, :], (nom + box.centre)[None, :], lo[None, :], hi[None, :]]
    if n:
        pts.append(lo + rng.random((n, box.size)) * (hi - lo))
    all_corners = rel.size <= max_corner_bits
    if all_corners:
        n_corners = 1 << rel.size
        bits = ((np.arange(n_corners)[:, None] >> np.arange(rel.size)[None, :]) & 1).astype(bool)
    else:
        n_corners = n
        bits = rng.random((n, rel.size)) < 0.5
    corners = np.broadcast_to(lo, (n_corners, box.size)).copy()
    corners[:, rel] = np.where(bits, hi[rel], lo[rel])
    pts.append(corners)
    cand = np.concatenate(pts)
    vals = _norms(cand, L, theta0)

    starts = cand[np.argsort(vals)[::-1][: max(0, ascent_starts)]]
    x = starts.copy()
    for _ in range(100):
        before = _norms(x, L, theta0)
        for j in rel:
            x = _coordinate_max(x, j, lo[j], hi[j], L, theta0)
        after = _norms(x, L, theta0)
        if np.all(after - before <= 1e-12 * (1.0 + after)):
            break
    allp = np.concatenate([cand, x]) if len(x) else cand
    allv = np.concatenate([vals, _norms(x, L, theta0)]) if len(x) else vals
    best = int(np.argmax(allv))
    return SampledRho(
        rho=float(allv[best]),
        seed=int(seed),
        n_uniform=n,
        n_corners=int(n_corners),
        all_corners=bool(all_corners),
        n_ascent_starts=int(len(x)),
        witness=allp[best].copy(),
    )


def _coordinate_max(x, j, lo, hi, robot, theta0):
    """Move coordinate ``j`` of each row of ``x`` to its exact maximiser of ||theta - theta0||."""
    if hi <= lo:
        return x
    ts = np.array([lo, 0.5 * (lo + hi), hi])
    th = []
    for t in ts:
        y = x.copy()
        y[:, j] = t
        th.append(robot.theta_of_standard(y) - theta0)
    # theta(t) - theta0 = A + B t + C t^2 through the three points (exact for a quadratic)
    V = np.vander(ts, 3, increasing=True)
    coef = np.linalg.solve(V, np.stack(th, axis=1))  # (N, 3, 15): A, B, C
    A, B, Cq = coef[:, 0], coef[:, 1], coef[:, 2]
    out = x.copy()
    for r in range(len(x)):
        # d/dt ||A + B t + C t^2||^2 / 2 = (A + B t + C t^2) . (B + 2 C t)
        d = [2 * Cq[r] @ Cq[r], 3 * B[r] @ Cq[r], B[r] @ B[r] + 2 * A[r] @ Cq[r], A[r] @ B[r]]
        roots = np.roots(d) if np.any(np.abs(d) > 0) else np.array([])
        cands = [lo, hi, x[r, j]] + [float(z.real) for z in roots if abs(z.imag) < 1e-9 and lo <= z.real <= hi]
        Y = np.repeat(x[r : r + 1], len(cands), axis=0)
        Y[:, j] = cands
        vals = np.linalg.norm(robot.theta_of_standard(Y) - theta0, axis=-1)
        out[r, j] = cands[int(np.argmax(vals))]
    return out


def sampled_rho(robot, box: Box, theta0, n: int = 100_000, seed: int = 0) -> float:
    """``sampled_rho_detail(...).rho``: a lower bound on ``max_{box} ||theta - theta0||``."""
    return sampled_rho_detail(robot, box, theta0, n=n, seed=seed).rho

