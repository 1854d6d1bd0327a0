r"""Desired joint trajectories :math:`q_d(t)` with their first two derivatives.

Two kinds, both C2 as the robust law requires (section 3.3):

* :class:`Sines` -- :math:`q_{d,i}(t) = c_i + \sum_k A_{ik} \sin(\omega_{ik} t + \phi_{ik})`.
  The paper's trajectory :math:`(\sin t, 5\cos t, \sin t)` is :func:`paper_trajectory`.
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

from .errors import ConfigError

__all__ = ["Sines", "Quintic", "paper_trajectory", "trajectory_from_config", "reference_into"]

_SINES, _QUINTIC = 0.0, 1.0


@njit(cache=True, nogil=True)
def reference_into(tp, t, ref):
    """Fill ``ref`` (3, 3) with rows q_d(t), qd_d(t), qdd_d(t) from packed ``tp``."""
    if tp[0] == 0.0:  # sines: [0, K, c(3), then per joint K x (A, w, phi)]
        K = int(tp[1])
        for i in range(3):
            q = tp[2 + i]
            qd = 0.0
            qdd = 0.0
            base = 5 + i * K * 3
            for k in range(K):
                A = tp[base + 3 * k]
                w = tp[base + 3 * k + 1]
                ph = tp[base + 3 * k + 2]
                s = math.sin(w * t + ph)
                c = math.cos(w * t + ph)
                q += A * s
                qd += A * w * c
                qdd -= A * w * w * s
            ref[0, i] = q
            ref[1, i] = qd
            ref[2, i] = qdd
    else:  # quintic: [1, nseg, durations(nseg), waypoints((nseg+1) x 3)]
        nseg = int(tp[1])
        t0 = 0.0
        seg = -1
        for k in range(nseg):
            if t < t0 + tp[2 + k]:
                seg = k
                break
            t0 += tp[2 + k]
        if seg < 0:  # past the end: hold the last waypoint
            wp = 2 + nseg + 3 * nseg
            for i in range(3):
                ref[0, i] = tp[wp + i]
                ref[1, i] = 0.0
                ref[2, i] = 0.0
            return
        T = tp[2 + seg]
        tau = max(0.0, (t - t0) / T)
        s = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau)
        ds = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau) / T
        dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (T * T)
        a = 2 + nseg + 3 * seg
        for i in range(3):
            d = tp[a + 3 + i] - tp[a + i]
            ref[0, i] = tp[a + i] + d * s
            ref[1, i] = d * ds
            ref[2, i] = d * dds


class _Trajectory:
    def pack(self) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(q_d, qd_d, qdd_d)`` at times ``t`` (scalar -> (3,), array (N,) -> (N, 3))."""
        tp = self.pack()
        ts = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.empty((ts.size, 3, 3))
        for n, tn in enumerate(ts):
            reference_into(tp, float(tn), out[n])
        if np.ndim(t) == 0:
            return out[0, 0], out[0, 1], out[0, 2]
        return out[:, 0], out[:, 1], out[:, 2]


@dataclass(frozen=True)
class Sines(_Trajectory):
    """Sum of sines per joint.

    Attributes
    ----------
    offset : tuple of 3 float
        Constant term :math:`c_i` [rad].
    terms : tuple of (joint, amplitude [rad], omega [rad/s], phase [rad])
        ``joint`` is 1-based.
    """

    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    terms: tuple[tuple[int, float, float, float], ...] = ()

    def __post_init__(self):
        for term in self.terms:
            if len(term) != 4 or int(term[0]) not in (1, 2, 3):
                raise ConfigError(f"sine term must be (joint 1..3, A, omega, phase), got {term}")
        values = np.concatenate([np.asarray(self.offset, float).ravel()]
                                + [np.asarray(t[1:], float) for t in self.terms])
        if np.asarray(self.offset).shape != (3,) or not np.all(np.isfinite(values)):
            raise ConfigError("trajectory offset must be 3 finite numbers and terms finite")

    def pack(self) -> np.ndarray:
        per_joint = [[t[1:] for t in self.terms if int(t[0]) == j] for j in (1, 2, 3)]
        K = max(1, max(len(p) for p in per_joint))
        tp = np.zeros(5 + 9 * K)
        tp[0], tp[1] = _SINES, K
        tp[2:5] = self.offset
        for i, p in enumerate(per_joint):
            for k, (A, w, ph) in enumerate(p):
                tp[5 + i * K * 3 + 3 * k: 5 + i * K * 3 + 3 * k + 3] = (A, w, ph)
        return tp

    def describe(self) -> str:
        return "sines " + "; ".join(f"q{j}: {A:g} sin({w:g} t + {ph:.4g})" for j, A, w, ph in self.terms)


def paper_trajectory() -> Sines:
    r"""The paper's :math:`q_d(t) = (\sin t,\ 5\cos t,\ \sin t)` (section 3.3)."""
    return Sines((0.0, 0.0, 0.0), ((1, 1.0, 1.0, 0.0), (2, 5.0, 1.0, math.pi / 2), (3, 1.0, 1.0, 0.0)))


@dataclass(frozen=True)
class Quintic(_Trajectory):
    """Rest-to-rest quintic segments through ``waypoints`` (rad), each lasting ``durations`` (s)."""

    waypoints: tuple[tuple[float, float, float], ...]
    durations: tuple[float, ...]

    def __post_init__(self):
        wp = np.asarray(self.waypoints, dtype=float)
        du = np.asarray(self.durations, dtype=float)
        if wp.ndim != 2 or wp.shape[1] != 3 or wp.shape[0] < 2:
            raise ConfigError(f"quintic needs >= 2 waypoints of 3 joints, got shape {wp.shape}")
        if du.shape != (wp.shape[0] - 1,):
            raise ConfigError(f"quintic needs {wp.shape[0] - 1} durations, got {du.size}")
        if not (np.all(np.isfinite(wp)) and np.all(np.isfinite(du))):
            raise ConfigError("trajectory numbers must be finite")
        if np.any(du <= 0):
            raise ConfigError(f"quintic durations must be > 0, got {du.tolist()}")

    def pack(self) -> np.ndarray:
        n = len(self.durations)
        return np.concatenate([[_QUINTIC, n], np.asarray(self.durations, float),
                               np.asarray(self.waypoints, float).ravel()])

    def describe(self) -> str:
        return f"quintic through {len(self.waypoints)} waypoints"


def trajectory_from_config(cfg: dict) -> _Trajectory:
    """Build a trajectory from a TOML table (``docs/control.md``).

    ``kind = "paper"``; ``kind = "sines"`` with ``offset`` and ``terms = [[joint, A, omega,
    phase], ...]``; ``kind = "quintic"`` with ``waypoints`` and ``durations``.
    """
    kind = cfg.get("kind", "paper")
    try:
        if kind == "paper":
            return paper_trajectory()
        if kind == "sines":
            return Sines(tuple(cfg.get("offset", (0.0, 0.0, 0.0))),
                         tuple(tuple(t) for t in cfg["terms"]))
        if kind == "quintic":
            return Quintic(tuple(tuple(w) for w in cfg["waypoints"]), tuple(cfg["durations"]))
    except KeyError as exc:
        raise ConfigError(f"trajectory of kind {kind!r} needs key {exc.args[0]!r}") from None
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"bad trajectory: {exc}") from None
    raise ConfigError(f"unknown trajectory kind {kind!r} (paper, sines, quintic)")
