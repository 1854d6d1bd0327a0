r"""Effects between the plant and a sampled controller: what the controller measures, and when its
torque arrives.

At sample :math:`k` (time :math:`t_k = k T`) the controller sees

.. math::

    q_m = Q_\Delta(q(t_k) + \nu_q), \qquad \dot q_m = \dot q(t_k) + \nu_{\dot q},

with seeded Gaussian noise :math:`\nu \sim N(0, \sigma^2)` per joint and encoder quantization
:math:`Q_\Delta(x) = \Delta\,\mathrm{round}(x / \Delta)` (no quantization where
:math:`\Delta = 0`; velocities are a separate estimate, noisy but not quantized). Its torque
:math:`u_k` reaches the plant ``delay`` samples later: during :math:`[t_k, t_{k+1})` the plant
gets :math:`u_{k-d}`, and :math:`u_0` for the first :math:`d` periods (the arm is held by the
first command until the loop catches up). The run starts at the trajectory's state plus
``q0_error``, ``qd0_error``. Continuous-time runs have no sample, so these need ``rate``.

The noise of a run is drawn once, before it starts, from
``numpy.random.default_rng(seed)`` (:meth:`LoopEffects.noise`): every engine sees the same
sequence, and the seed is recorded with the result.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .base import per_joint as _vec

__all__ = ["LoopEffects", "MAX_NOISE"]

#: Largest standard deviation of the sensor noise and largest encoder step, per joint: ``noise_q`` and
#: ``quantization`` 1 rad (or m), ``noise_qd`` 100 rad/s (or m/s). Beyond them no sensor is meant (a
#: noise of 1e300 made every run "diverged at t = 0").
MAX_NOISE = {"noise_q": 1.0, "noise_qd": 100.0, "quantization": 1.0}


@dataclass(frozen=True)
class LoopEffects:
    """Sensor noise, encoder quantization, delay and initial error of a sampled loop (n joints).

    Attributes
    ----------
    n : int
    noise_q, noise_qd : (n,) standard deviations [rad], [rad/s]
    quantization : (n,) encoder step [rad] (0: none)
    delay : int
        Samples between a measurement and the torque computed from it reaching the plant.
    q0_error, qd0_error : (n,) initial state error [rad], [rad/s]
    seed : int
        Seed of the noise.

    Examples
    --------
    >>> from rc3r.plants import LoopEffects
    >>> fx = LoopEffects(3, noise_q=1e-4, quantization=2 * 3.141592653589793 / 2**17, delay=1, seed=7)
    >>> fx.noise(4).shape, fx.active
    ((5, 6), True)
    """

    n: int
    noise_q: np.ndarray | float = 0.0
    noise_qd: np.ndarray | float = 0.0
    quantization: np.ndarray | float = 0.0
    delay: int = 0
    q0_error: np.ndarray | float = 0.0
    qd0_error: np.ndarray | float = 0.0
    seed: int = 0

    def __post_init__(self):
        n = self.n
        for name in ("noise_q", "noise_qd", "quantization"):
            object.__setattr__(self, name, _vec(name, getattr(self, name), n))
            if np.any(getattr(self, name) > MAX_NOISE[name]):
                shown = ", ".join(f"{v:g}" for v in getattr(self, name))
                raise ConfigError(f"{name} [{shown}] is beyond {MAX_NOISE[name]:g} "
                                  f"({'rad/s' if name == 'noise_qd' else 'rad'}): not a sensor")
        for name in ("q0_error", "qd0_error"):
            object.__setattr__(self, name, _vec(name, getattr(self, name), n, signed=True))
        if isinstance(self.delay, bool) or not isinstance(self.delay, (int, np.integer)) or not 0 <= self.delay <= 1000:
            raise ConfigError(f"delay must be a whole number of samples in [0, 1000], got {self.delay!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ConfigError(f"noise seed must be an integer >= 0, got {self.seed!r}")

    @property
    def noisy(self) -> bool:
        return bool(np.any(self.noise_q) or np.any(self.noise_qd))

    @property
    def active(self) -> bool:
        """True if anything differs from a perfect loop (noise, quantization, delay)."""
        return self.noisy or bool(np.any(self.quantization)) or self.delay > 0

    def noise(self, nsamples: int) -> np.ndarray:
        """Noise of samples 0..nsamples, (nsamples + 1, 2 n): columns q then qd; (0, 2 n) if none."""
        if not self.noisy:
            return np.zeros((0, 2 * self.n))
        rng = np.random.default_rng(self.seed)
        z = rng.standard_normal((nsamples + 1, 2 * self.n))
        return z * np.concatenate([self.noise_q, self.noise_qd])

    def x0(self, q0, qd0) -> np.ndarray:
        """The initial state (2 n,): the trajectory's plus the initial error."""
        return np.concatenate([np.asarray(q0) + self.q0_error, np.asarray(qd0) + self.qd0_error])

    def measure(self, x, k: int, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(q_m, qd_m)`` at sample k from the state ``x`` (2 n + nz,) (module docstring)."""
        n = self.n
        q, qd = np.array(x[:n], dtype=float), np.array(x[n:2 * n], dtype=float)
        if noise.shape[0]:
            q += noise[k, :n]
            qd += noise[k, n:]
        step = self.quantization
        if np.any(step):
            nz = step > 0
            q[nz] = step[nz] * np.rint(q[nz] / step[nz])
        return q, qd

    def describe(self) -> dict:
        return {"noise_q": self.noise_q.tolist(), "noise_qd": self.noise_qd.tolist(),
                "quantization": self.quantization.tolist(), "delay": int(self.delay),
                "q0_error": self.q0_error.tolist(), "qd0_error": self.qd0_error.tolist(), "seed": int(self.seed)}
