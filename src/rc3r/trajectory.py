r"""Desired joint trajectories :math:`q_d(t)` with their first two derivatives.

Two kinds, both C2 as the robust law requires (section 3.3):

* :class:`Sines` -- :math:`q_{d,i}(t) = c_i + \sum_k A_{ik} \sin(\omega_{ik} t + \phi_{ik})`.
  (The paper's trajectory :math:`(\sin t, 5\cos t, \sin t)` lives with the paper's
  arm, :func:`rc3r.robots.rr3.paper.paper_trajectory`.)
* :class:`Quintic` -- rest-to-rest quintic segments through waypoints
  (:math:`s(\tau) = 10\tau^3 - 15\tau^4 + 6\tau^5`), holding the last waypoint.

Each kind packs into one float vector evaluated by the compiled :func:`reference_into`
(used inside the simulator); :meth:`evaluate` is the NumPy-facing wrapper.
Units: rad, rad/s, rad/s^2, s.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ._numba_cache import ready_or_python

from .errors import ConfigError

__all__ = ["Trajectory", "Sines", "Quintic", "trajectory_from_config", "reference_into", "reference_jerk_into"]

_SINES, _QUINTIC = 0.0, 1.0


@njit(cache=True, nogil=True)
def reference_into(tp, t, ref):
    """Fill ``ref`` (3, n) with rows q_d(t), qd_d(t), qdd_d(t) from packed ``tp``."""
    n = ref.shape[1]
    if tp[0] == 0.0:  # sines: [0, K, c(n), then per joint K x (A, w, phi)]
        K = int(tp[1])
        for i in range(n):
            q = tp[2 + i]
            qd = 0.0
            qdd = 0.0
            base = 2 + n + i * K * 3
            for k in range(K):
                A = tp[base + 3 * k]
                w = tp[base + 3 * k + 1]
                ph = tp[base + 3 * k + 2]
                s = math.sin(w * t + ph)  # libm, not rc3r._trig: the cold start runs this interpreted
                c = math.cos(w * t + ph)
                q += A * s
                qd += A * w * c
                qdd -= A * w * w * s
            ref[0, i] = q
            ref[1, i] = qd
            ref[2, i] = qdd
    else:  # quintic: [1, nseg, durations(nseg), waypoints((nseg+1) x n)]
        nseg = int(tp[1])
        t0 = 0.0
        seg = -1
        for k in range(nseg):
            if t < t0 + tp[2 + k]:
                seg = k
                break
            t0 += tp[2 + k]
        if seg < 0:  # past the end: hold the last waypoint
            wp = 2 + nseg + n * nseg
            for i in range(n):
                ref[0, i] = tp[wp + i]
                ref[1, i] = 0.0
                ref[2, i] = 0.0
            return
        T = tp[2 + seg]
        tau = max(0.0, (t - t0) / T)
        s = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau)
        ds = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau) / T
        dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (T * T)
        a = 2 + nseg + n * seg
        for i in range(n):
            d = tp[a + n + i] - tp[a + i]
            ref[0, i] = tp[a + i] + d * s
            ref[1, i] = d * ds
            ref[2, i] = d * dds


@njit(cache=True, nogil=True)
def reference_jerk_into(tp, t, jerk):
    """Fill ``jerk`` (n,) with the third derivative of q_d at ``t`` [rad/s^3] (the analytic Jacobian's
    time column, :mod:`rc3r.simulate.engines._jacobian`), from the same packed ``tp`` as :func:`reference_into`."""
    n = jerk.shape[0]
    if tp[0] == 0.0:
        K = int(tp[1])
        for i in range(n):
            acc = 0.0
            base = 2 + n + i * K * 3
            for k in range(K):
                A = tp[base + 3 * k]
                w = tp[base + 3 * k + 1]
                acc -= A * w * w * w * math.cos(w * t + tp[base + 3 * k + 2])
            jerk[i] = acc
        return
    nseg = int(tp[1])
    t0 = 0.0
    for k in range(nseg):
        if t < t0 + tp[2 + k]:
            T = tp[2 + k]
            tau = max(0.0, (t - t0) / T)
            ddds = (60.0 - 360.0 * tau + 360.0 * tau * tau) / (T * T * T)
            a = 2 + nseg + n * k
            for i in range(n):
                jerk[i] = (tp[a + n + i] - tp[a + i]) * ddds
            return
        t0 += tp[2 + k]
    for i in range(n):
        jerk[i] = 0.0


class Trajectory:
    """Base of the trajectory kinds: ``n`` joints, :meth:`pack`, :meth:`evaluate`, :meth:`describe`."""

    n: int = 0

    def pack(self) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def describe(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(q_d, qd_d, qdd_d)`` at times ``t`` (scalar -> (n,), array (N,) -> (N, n))."""
        tp = self.pack()
        ts = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.empty((ts.size, 3, self.n))
        fill = reference_into if ts.size > 100_000 else ready_or_python(reference_into)  # cold: interpreted
        for n, tn in enumerate(ts):
            fill(tp, float(tn), out[n])
        if np.ndim(t) == 0:
            return out[0, 0], out[0, 1], out[0, 2]
        return out[:, 0], out[:, 1], out[:, 2]


@dataclass(frozen=True)
class Sines(Trajectory):
    """Sum of sines per joint.

    Attributes
    ----------
    offset : tuple of n float
        Constant term :math:`c_i` [rad]; its length is the number of joints.
    terms : tuple of (joint, amplitude [rad], omega [rad/s], phase [rad])
        ``joint`` is 1-based.
    """

    offset: tuple[float, ...] = (0.0, 0.0, 0.0)
    terms: tuple[tuple[int, float, float, float], ...] = ()

    def __post_init__(self):
        off = np.asarray(self.offset, dtype=float)
        if off.ndim != 1 or off.size == 0:
            raise ConfigError(f"trajectory offset must be one number per joint, got shape {off.shape}")
        n = off.size
        for term in self.terms:
            if len(term) != 4 or not 1 <= int(term[0]) <= n:
                raise ConfigError(f"sine term must be (joint 1..{n}, A, omega, phase), got {term}")
        values = np.concatenate([off] + [np.asarray(t[1:], float) for t in self.terms])
        if not np.all(np.isfinite(values)):
            raise ConfigError("trajectory offset and terms must be finite")

    @property
    def n(self) -> int:
        return len(self.offset)

    def pack(self) -> np.ndarray:
        n = self.n
        per_joint = [[t[1:] for t in self.terms if int(t[0]) == j] for j in range(1, n + 1)]
        K = max(1, max(len(p) for p in per_joint))
        tp = np.zeros(2 + n + 3 * n * K)
        tp[0], tp[1] = _SINES, K
        tp[2:2 + n] = self.offset
        for i, p in enumerate(per_joint):
            for k, (A, w, ph) in enumerate(p):
                base = 2 + n + i * K * 3 + 3 * k
                tp[base: base + 3] = (A, w, ph)
        return tp

    def describe(self) -> str:
        return "sines " + "; ".join(f"q{j}: {A:g} sin({w:g} t + {ph:.4g})" for j, A, w, ph in self.terms)


@dataclass(frozen=True)
class Quintic(Trajectory):
    """Rest-to-rest quintic segments through ``waypoints`` (rad), each lasting ``durations`` (s)."""

    waypoints: tuple[tuple[float, ...], ...]
    durations: tuple[float, ...]

    def __post_init__(self):
        wp = np.asarray(self.waypoints, dtype=float)
        du = np.asarray(self.durations, dtype=float)
        if wp.ndim != 2 or wp.shape[0] < 2:
            raise ConfigError(f"quintic needs >= 2 waypoints of n joints each, got shape {wp.shape}")
        if du.shape != (wp.shape[0] - 1,):
            raise ConfigError(f"quintic needs {wp.shape[0] - 1} durations, got {du.size}")
        if not (np.all(np.isfinite(wp)) and np.all(np.isfinite(du))):
            raise ConfigError("trajectory numbers must be finite")
        if np.any(du <= 0):
            raise ConfigError(f"quintic durations must be > 0, got {du.tolist()}")

    @property
    def n(self) -> int:
        return len(self.waypoints[0])

    def pack(self) -> np.ndarray:
        n = len(self.durations)
        return np.concatenate([[_QUINTIC, n], np.asarray(self.durations, float),
                               np.asarray(self.waypoints, float).ravel()])

    def describe(self) -> str:
        return f"quintic through {len(self.waypoints)} waypoints"


def trajectory_from_config(cfg: dict, default: Trajectory) -> Trajectory:
    """Build a trajectory from a TOML table (``docs/control.md``).

    ``kind = "paper"`` (or ``"default"``): ``default``, the robot's own reference
    trajectory; ``kind = "sines"`` with ``offset`` and ``terms = [[joint, A, omega,
    phase], ...]``; ``kind = "quintic"`` with ``waypoints`` and ``durations``.
    """
    kind = cfg.get("kind", "paper")
    try:
        if kind in ("paper", "default"):
            return default
        if kind == "sines":
            return Sines(tuple(cfg.get("offset", (0.0,) * default.n)),
                         tuple(tuple(t) for t in cfg["terms"]))
        if kind == "quintic":
            return Quintic(tuple(tuple(w) for w in cfg["waypoints"]), tuple(cfg["durations"]))
    except KeyError as exc:
        raise ConfigError(f"trajectory of kind {kind!r} needs key {exc.args[0]!r}") from None
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"bad trajectory: {exc}") from None
    raise ConfigError(f"unknown trajectory kind {kind!r} (paper, sines, quintic)")
