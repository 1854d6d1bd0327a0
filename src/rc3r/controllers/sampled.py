r"""The sampled loop of a digital controller, written once for Python: :class:`SampledLoop`.

At sample :math:`k` (time :math:`t_k = k T`) the loop

1. advances the law's state by forward Euler from the previous sample,
   :math:`z_k = z_{k-1} + T \dot z_{k-1}` (nothing at the first sample: :math:`z_0` is the law's
   initial state);
2. evaluates the law on the measured state: :math:`(u_k, \dot z_k) = \mathrm{law}(t_k, q_m, \dot q_m, z_k)`;
3. pushes :math:`u_k` into the delay line and holds :math:`u_{k-d}` (:math:`u_0` while
   :math:`k < d`) until :math:`t_{k+1}` (the zero-order hold).

The measurement (sensor noise, quantization) is the loop effects' own
(:meth:`rc3r.plants.LoopEffects.measure`), applied by whoever holds the true state.

Two Python users share it: the ``python`` and ``reference`` engines
(:mod:`rc3r.simulate._python`) and :meth:`rc3r.Controller.step` (a loop rc3r does not run).
The compiled engine (:func:`rc3r.simulate.engines.compiled.integrate_sampled`) and the exported C
(:mod:`rc3r.export.c`) are its other two copies. ``tests/test_sampled_loop.py`` keeps the python
engine, the compiled engine and :meth:`~rc3r.Controller.step` equal on the same plant, law, noise
seed and delay (``tests/test_export.py`` the C).
"""
from __future__ import annotations

import numpy as np

__all__ = ["SampledLoop"]


class SampledLoop:
    """The zero-order hold, the delay line and the forward-Euler state of one law.

    Parameters
    ----------
    law : rc3r.controllers.Law
        Only its :meth:`~rc3r.controllers.Law.initial_state` is read here; the torque comes from the
        ``torque`` callable of :meth:`sample` (which knows the model and the reference).
    period : float or None
        Sample period T [s]; None: a continuous controller (:meth:`evaluate` and :meth:`euler` only).
    delay : int
        Samples between a measurement and its torque.
    z0 : array_like, optional
        Initial controller state (default ``law.initial_state()``).

    Attributes
    ----------
    z, zdot : ndarray
        The law's state at the last sample and its derivative there.
    k : int
        The last sample computed (-1 before the first).
    u : ndarray or None
        The held torque (the delayed command).
    command : ndarray or None
        The last command the law computed (before the delay line).
    diagnostic : float
        The law's third output at the last evaluation (``||Y^T r||`` for the laws here).
    """

    def __init__(self, law, period: float | None, delay: int = 0, z0=None):
        self.law, self.period, self.delay = law, period, int(delay)
        self.reset(z0)

    def reset(self, z0=None) -> None:
        """Back to before the first sample: the initial state, an empty hold and delay line."""
        self.z = np.array(self.law.initial_state() if z0 is None else z0, dtype=float)
        self.zdot = np.zeros_like(self.z)
        self.k = -1
        self._line: list = []
        self.u = None
        self.command = None
        self.diagnostic = 0.0

    def euler(self, dt: float) -> None:
        """Advance the state by one forward-Euler step of ``dt`` [s]: ``z += dt * zdot``."""
        self.z = self.z + dt * self.zdot

    def evaluate(self, torque, t: float, q, qd) -> np.ndarray:
        """The law's command at ``t`` on the measured ``q``, ``qd`` and the state ``z``:
        ``torque(t, q, qd, z) -> (u, zdot, diagnostic)``; stores ``zdot`` and returns ``u``."""
        u, zdot, diag = torque(t, q, qd, self.z)
        self.command = np.asarray(u, dtype=float)
        self.zdot = np.asarray(zdot, dtype=float)
        self.diagnostic = float(diag)
        return self.command

    def sample(self, k: int, torque, q, qd) -> np.ndarray:
        """Sample ``k`` (module docstring: Euler step, law, delay line); returns the held torque."""
        if self.k >= 0:
            self.euler(self.period)
        ucmd = self.evaluate(torque, k * self.period, q, qd)
        self._line.append(ucmd)
        if len(self._line) > self.delay + 1:
            self._line.pop(0)
        self.u = self._line[0]
        self.k = k
        return self.u
