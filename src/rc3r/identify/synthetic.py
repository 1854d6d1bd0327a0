r"""Synthetic logs of a known arm: what an experiment on it would record, at stated noise levels.

**The motion** (:func:`simulate_motion`). The arm (any :class:`~rc3r.robots.base.Robot`,
e.g. the paper's 3R or the UR5) has joint friction and tracks a trajectory under
computed-torque control on its true state:

.. math::

    M(q)\ddot q + C(q, \dot q)\dot q + g(q) + f_v \dot q + f_c\,\mathrm{sign}(\dot q) = u, \qquad
    u = \mathrm{rnea}\bigl(q, \dot q, \ddot q_d + K_d(\dot q_d - \dot q) + K_p(q_d - q)\bigr),

(``K_p = omega^2``, ``K_d = 2 omega``, ``omega = 30`` rad/s; friction is not compensated),
integrated by Pinocchio's ABA and RNEA on ``robot.model`` with fixed-step RK4 (step
:data:`STEP`), storing ``q, qd, qdd, u`` at every step. The controller sees no noise, so
the motion does not depend on the sensors: one motion serves many logs, as one
experiment repeated gives the same motion and new noise.

**The log** (:func:`sample_log`). Sample times jitter (:class:`SensorNoise`: intervals
``U(0.7, 1.3) x 1 ms``, and with probability 0.5 % a late sample after ``U(2, 9)`` ms: 0.7-9 ms
at a nominal 1 kHz). At each time the motion is interpolated (``q`` quintic Hermite from
``q, qd, qdd`` at the steps, ``qd`` cubic Hermite, ``u`` cubic spline; errors below 1e-9 of
the signals for the default step) and recorded as a real log would: ``q`` quantized by the
encoder (``2 pi / encoder_counts``), ``qd`` (optionally ``velocity_lag`` s late) plus white noise
(or not logged), ``tau = u +``
a constant sensor offset per joint ``+`` white noise. Every random draw comes from
``numpy.random.default_rng(seed)`` in a fixed order (time stamps, velocity noise, torque noise).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .log import Log

__all__ = ["STEP", "SensorNoise", "Friction", "Motion", "sample_times", "simulate_motion", "sample_log",
           "synthetic_log"]

#: RK4 step of the plant [s].
STEP = 5e-4


@dataclass(frozen=True)
class SensorNoise:
    """Noise levels of a synthetic log.

    Attributes
    ----------
    torque_std : float or tuple
        Standard deviation of the white noise on each logged torque [N m] (per joint or one for all).
    torque_offset : float or tuple
        Constant bias of each torque sensor [N m].
    velocity_std : float
        Standard deviation of the white noise on the logged velocities [rad/s].
    encoder_counts : int
        Counts per revolution: positions are logged as multiples of ``2 pi / encoder_counts``.
    period : float
        Nominal sampling period [s].
    jitter : (float, float)
        Ordinary intervals are ``U(jitter) x period``.
    gap_probability : float
        Chance that an interval is a gap instead (a late sample).
    gap : (float, float)
        Gap length range [s].
    velocity_lag : float
        The logged velocities are those of this many seconds earlier [s] (a drive's filtered
        velocity estimate lags; 0: none).
    """

    torque_std: float | tuple = 0.2
    torque_offset: float | tuple = 0.3
    velocity_std: float = 0.01
    encoder_counts: int = 2 ** 16
    period: float = 1e-3
    jitter: tuple = (0.7, 1.3)
    gap_probability: float = 0.005
    gap: tuple = (2e-3, 9e-3)
    velocity_lag: float = 0.0

    def describe(self) -> dict:
        """JSON-ready levels."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


@dataclass(frozen=True)
class Friction:
    """Per-joint viscous [N m s/rad] and Coulomb [N m] friction of the plant (one number: every joint)."""

    viscous: float | tuple = 2.0
    coulomb: float | tuple = 1.0

    def arrays(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """``(f_v, f_c)``, each (n,)."""
        return tuple(np.broadcast_to(np.asarray(x, dtype=float), (n,)).copy() for x in (self.viscous, self.coulomb))


def sample_times(duration: float, noise: SensorNoise, rng) -> np.ndarray:
    """Jittered sample times from 0 to at most ``duration`` (module docstring)."""
    count = int(math.ceil(duration / (noise.period * noise.jitter[0]))) + 2
    dt = noise.period * rng.uniform(noise.jitter[0], noise.jitter[1], count)
    gaps = rng.random(count) < noise.gap_probability
    dt[gaps] = rng.uniform(noise.gap[0], noise.gap[1], int(gaps.sum()))
    t = np.concatenate([[0.0], np.cumsum(dt)])
    return t[t <= duration]


@dataclass(frozen=True, eq=False)
class Motion:
    """A simulated motion: ``t`` (K,) [s] on the RK4 grid, ``q, qd, qdd, u`` (K, n), the truth.

    ``theta`` (p,) are the arm's coefficients, ``viscous`` and ``coulomb`` (n,) its friction,
    ``label`` names the arm, ``max_tracking_error`` [rad] the controller's worst ``|q - q_d|``.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    u: np.ndarray
    theta: np.ndarray
    viscous: np.ndarray
    coulomb: np.ndarray
    label: str
    max_tracking_error: float

    @property
    def duration(self) -> float:
        """Length of the motion [s]."""
        return float(self.t[-1] - self.t[0])


def simulate_motion(robot, trajectory, duration: float, friction: Friction = Friction(),
                    omega: float = 30.0, step: float = STEP) -> Motion:
    """Simulate ``robot`` with ``friction`` tracking ``trajectory`` for ``duration`` s (module docstring).

    Raises
    ------
    FloatingPointError
        The plant left finite values (it cannot for a physical arm and these gains).
    """
    import pinocchio as pin

    model = robot.model
    data = model.createData()
    n = robot.n
    fv, fc = friction.arrays(n)
    Kp, Kd = omega ** 2, 2.0 * omega
    K = int(math.ceil(duration / step - 1e-9))
    ts = step * np.arange(K + 1)
    ref = trajectory.pack()
    from ..trajectory import reference_into

    buf = np.empty((3, n))

    def rhs(t, q, qd):
        reference_into(ref, t, buf)
        u = np.array(pin.rnea(model, data, q, qd, buf[2] + Kd * (buf[1] - qd) + Kp * (buf[0] - q)))
        qdd = np.array(pin.aba(model, data, q, qd, u - fv * qd - fc * np.sign(qd)))
        return qdd, u

    Q, QD, QDD, U = (np.empty((K + 1, n)) for _ in range(4))
    q0, qd0, _ = trajectory.evaluate(0.0)
    q, qd = np.array(q0, dtype=float), np.array(qd0, dtype=float)
    worst, h = 0.0, step
    for k in range(K + 1):
        t = ts[k]
        a1, u = rhs(t, q, qd)
        Q[k], QD[k], QDD[k], U[k] = q, qd, a1, u
        worst = max(worst, float(np.abs(q - buf[0]).max()))
        if k == K:
            break
        q2, v2 = q + 0.5 * h * qd, qd + 0.5 * h * a1
        a2, _ = rhs(t + 0.5 * h, q2, v2)
        q3, v3 = q + 0.5 * h * v2, qd + 0.5 * h * a2
        a3, _ = rhs(t + 0.5 * h, q3, v3)
        q4, v4 = q + h * v3, qd + h * a3
        a4, _ = rhs(t + h, q4, v4)
        q = q + h / 6.0 * (qd + 2 * v2 + 2 * v3 + v4)
        qd = qd + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
            raise FloatingPointError(f"synthetic plant diverged at t = {t + h:.4g} s")
    return Motion(ts, Q, QD, QDD, U, np.asarray(robot.theta, dtype=float).copy(), fv, fc, robot.label, worst)


def _hermite(motion: Motion, t) -> tuple[np.ndarray, np.ndarray]:
    """``q`` (quintic Hermite from q, qd, qdd) and ``qd`` (cubic Hermite from qd, qdd) at times ``t``."""
    tk = motion.t
    i = np.clip(np.searchsorted(tk, t, side="right") - 1, 0, tk.size - 2)
    h = (tk[i + 1] - tk[i])[:, None]
    s = ((t - tk[i])[:, None]) / h
    s2, s3 = s * s, s * s * s
    s4, s5 = s3 * s, s3 * s2
    Q, V, A = motion.q, motion.qd, motion.qdd
    q = ((1 - 10 * s3 + 15 * s4 - 6 * s5) * Q[i] + (s - 6 * s3 + 8 * s4 - 3 * s5) * h * V[i]
         + (0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5) * h * h * A[i] + (0.5 * s3 - s4 + 0.5 * s5) * h * h * A[i + 1]
         + (-4 * s3 + 7 * s4 - 3 * s5) * h * V[i + 1] + (10 * s3 - 15 * s4 + 6 * s5) * Q[i + 1])
    qd = ((2 * s3 - 3 * s2 + 1) * V[i] + (s3 - 2 * s2 + s) * h * A[i] + (-2 * s3 + 3 * s2) * V[i + 1]
          + (s3 - s2) * h * A[i + 1])
    return q, qd


def sample_log(motion: Motion, seed: int = 0, noise: SensorNoise = SensorNoise(),
               log_velocities: bool = True) -> tuple[Log, dict]:
    """Record ``motion`` with sensors of ``noise`` at jittered times (module docstring).

    Returns
    -------
    (Log, dict)
        The log, and the truth: ``theta``, ``viscous``, ``coulomb``, ``offset`` (n,), ``noise``
        (the levels), ``seed``, ``max_tracking_error``.
    """
    from scipy.interpolate import CubicSpline

    rng = np.random.default_rng(seed)
    n = motion.q.shape[1]
    t = sample_times(motion.duration, noise, rng)
    q, qd = _hermite(motion, t)
    u = CubicSpline(motion.t, motion.u, axis=0)(t)
    offset = np.broadcast_to(np.asarray(noise.torque_offset, float), (n,)).copy()
    tstd = np.broadcast_to(np.asarray(noise.torque_std, float), (n,)).copy()
    step = 2.0 * math.pi / noise.encoder_counts
    if noise.velocity_lag > 0:
        qd = _hermite(motion, np.maximum(t - noise.velocity_lag, motion.t[0]))[1]
    vel = qd + rng.normal(0.0, noise.velocity_std, qd.shape)
    tau = u + offset + rng.normal(0.0, 1.0, u.shape) * tstd
    log = Log(t, np.round(q / step) * step, tau, vel if log_velocities else None,
              source=f"synthetic:{motion.label}:seed={seed}")
    truth = {"theta": motion.theta, "viscous": motion.viscous, "coulomb": motion.coulomb, "offset": offset,
             "seed": int(seed), "noise": noise.describe(), "max_tracking_error": motion.max_tracking_error}
    return log, truth


def synthetic_log(robot, trajectory, duration: float, seed: int = 0, noise: SensorNoise = SensorNoise(),
                  friction: Friction = Friction(), log_velocities: bool = True) -> tuple[Log, dict]:
    """:func:`sample_log` of :func:`simulate_motion`: one synthetic log and its truth."""
    return sample_log(simulate_motion(robot, trajectory, duration, friction), seed, noise, log_velocities)
