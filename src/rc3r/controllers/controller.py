r"""A controller for loops rc3r does not run: ``u = ctrl.step(t, q, qd)``.

:class:`Controller` holds what a law needs between calls -- the reference trajectory, the
law's state (the adaptive estimate :math:`\hat\theta`), the zero-order hold of a digital
controller at ``rate`` Hz, and the delay line -- so that another simulator (MuJoCo, a
user's own integrator) or a real-time loop can call it with measured states only. It does
what rc3r's sampled simulator does, sample for sample: at the first call at or after
:math:`t_k = k T` it updates the law's state by forward Euler
(:math:`z_k = z_{k-1} + T \dot z_{k-1}`), computes :math:`u_k` from that call's
:math:`(q, \dot q)`, pushes it into the delay line and from then on returns the delayed
command :math:`u_{k-d}` (:math:`u_0` while :math:`k < d`) until :math:`t_{k+1}`. Without a
rate every call computes a fresh torque and integrates the state by forward Euler between
calls (a continuous controller as seen by a fine-stepping caller).

The hold, the delay line and the Euler step are :class:`rc3r.controllers.sampled.SampledLoop`, the
same object the ``python`` engine samples with. ``examples/external_loop.py`` drives a plant rc3r does not simulate and reproduces
``rc3r run`` of the same specification.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .sampled import SampledLoop

__all__ = ["Controller"]


class Controller:
    """A law, the model it evaluates its regressor on, a trajectory, a rate and a delay.

    Parameters
    ----------
    law : rc3r.controllers.Law
    model : rc3r.robots.base.Robot
        Whose regressor Y the law uses (kinematics and gravity; never the plant's parameters).
    trajectory : rc3r.trajectory.Trajectory
    rate : float, optional
        Controller rate [Hz]; None: continuous (a torque at every call).
    delay : int
        Samples between a measurement and its torque (sampled only).

    Examples
    --------
    >>> import rc3r
    >>> spec = rc3r.build_run(controller="fbl", perturbed=True, rate=1000.0, duration=1.0)
    >>> ctrl = rc3r.Controller.from_run(spec)
    >>> q, qd, _ = spec.trajectory.evaluate(0.0)
    >>> ctrl.step(0.0, q, qd).shape
    (3,)
    """

    def __init__(self, law, model, trajectory, rate: float | None = None, delay: int = 0):
        if trajectory.n != model.n or law.p != model.p:
            raise ParameterError(f"controller parts do not fit: model n = {model.n}, p = {model.p}; "
                                 f"trajectory n = {trajectory.n}; law p = {law.p}")
        if rate is not None and not (np.isfinite(rate) and rate > 0):
            raise ParameterError(f"controller rate must be finite and > 0 Hz, got {rate}")
        if isinstance(delay, bool) or not isinstance(delay, (int, np.integer)) or delay < 0:
            raise ParameterError(f"delay must be a whole number of samples >= 0, got {delay!r}")
        if delay and rate is None:
            raise ParameterError("a delay needs a sampled controller (a rate)")
        self.law, self.model, self.trajectory = law, model, trajectory
        self.rate, self.delay = rate, int(delay)
        self._finite = np.empty(2 * model.n + 1)
        self._loop = SampledLoop(law, None if rate is None else 1.0 / rate, self.delay)
        self.reset()

    @classmethod
    def from_run(cls, spec) -> "Controller":
        """The controller of a run specification (:func:`rc3r.build_run`): its law, model, trajectory,
        rate and loop delay."""
        model = spec.controller_model if spec.controller_model is not None else spec.true_rigid
        return cls(spec.law, model, spec.trajectory, spec.options.rate, 0 if spec.loop is None else spec.loop.delay)

    def reset(self) -> None:
        """Back to t = 0: the law's initial state, an empty hold and delay line."""
        self._loop.reset()
        self._t_last = None   # continuous: time of the last call
        self.u = None

    @property
    def z(self) -> np.ndarray:
        """The law's state (the adaptive estimate), as of the last sample (or call, continuous); settable (a
        warm start), as before it lived in the shared loop."""
        return self._loop.z

    @z.setter
    def z(self, value) -> None:
        self._loop.z = np.array(value, dtype=float)

    @property
    def diagnostic(self) -> float:
        """The law's third output at the last sample (``||Y^T r||`` for the laws here)."""
        return self._loop.diagnostic

    def _torque(self, t, q, qd, z):
        qd_ref = np.empty((3, self.model.n))
        pos, vel, acc = self.trajectory.evaluate(float(t))
        qd_ref[0], qd_ref[1], qd_ref[2] = pos, vel, acc
        u, zdot, diag = self.law.torque(self.model, q, qd, qd_ref, z)
        return np.asarray(u, dtype=float), np.asarray(zdot, dtype=float), float(diag)

    @staticmethod
    def _which_bad(t, q, qd, what: str) -> str:
        """The message of a call with an argument that is not a finite number: which one, and its value."""
        for name, x in (("t", t), ("q", q), ("qd", qd)):
            try:
                ok = bool(np.isfinite(np.asarray(x, dtype=float)).all())
            except (TypeError, ValueError):
                ok = False
            if not ok:
                return f"Controller.step: {name} {what}: {x!r}"
        return f"Controller.step: an argument {what}"  # pragma: no cover - one of them failed

    def step(self, t: float, q, qd) -> np.ndarray:
        """The torque (n,) [N m] to apply from time ``t`` [s] on, given the measured ``q``, ``qd`` (n,).

        Calls must come in non-decreasing ``t``; a sampled controller computes a new torque at most
        once per period and holds it in between.

        Raises
        ------
        ParameterError
            Naming the argument: ``t``, ``q`` or ``qd`` not numbers, NaN or infinite (a torque computed
            from them would be NaN), shapes other than (n,), or ``t`` before the last sample.
        """
        try:
            t = float(t)
            q = np.asarray(q, dtype=float)
            qd = np.asarray(qd, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(self._which_bad(t, q, qd, "is not a number")) from None
        if q.shape != (self.model.n,) or qd.shape != (self.model.n,):
            raise ParameterError(f"q and qd must be ({self.model.n},), got {q.shape}, {qd.shape}")
        buf = self._finite  # t, q, qd side by side: one isfinite on the hot path
        buf[0], buf[1:self.model.n + 1], buf[self.model.n + 1:] = t, q, qd
        if not np.isfinite(buf).all():
            raise ParameterError(self._which_bad(t, q, qd, "is NaN or infinite"))
        loop = self._loop
        if self.rate is None:
            if self._t_last is not None:
                if t < self._t_last:
                    raise ParameterError(f"controller called at t = {t} after t = {self._t_last}")
                loop.euler(t - self._t_last)
            self.u = loop.evaluate(self._torque, t, q, qd)
            self._t_last = t
            return self.u
        T = loop.period
        k = int(np.floor(t / T + 1e-9))
        if k < loop.k:
            raise ParameterError(f"controller called at t = {t} s, before its last sample {loop.k * T} s")
        if k > loop.k:
            self.u = loop.sample(k, self._torque, q, qd)  # the simulator's own sampled loop
        return self.u
