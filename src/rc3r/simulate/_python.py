"""The ``python`` and ``reference`` engines: any robot, any law, in plain Python.

The plant is the robot's :meth:`~rc3r.robots.base.Robot.forward_dynamics` (Pinocchio
ABA for the robots here); the controller is :meth:`rc3r.controllers.Law.torque`, which
sees the robot only through its regressor. ``python``: SciPy ``Radau`` at the options'
tolerances (continuous) or RK4 with ``nsub`` sub-steps per period (sampled).
``reference``: ``Radau`` at ``rtol <= 1e-11`` (continuous) or ``DOP853`` per period
(sampled).
"""
from __future__ import annotations

import numpy as np

from ..trajectory import reference_into
from . import _limits, _result, _sample_grid
from . import status as S


class _Loop:
    """Controller and plant of one run, evaluated from Python."""

    def __init__(self, plant, law, trajectory):
        self.plant, self.law = plant, law
        self.n = plant.n
        self.tp = trajectory.pack()
        self.ref = np.empty((3, self.n))
        self.nrhs = 0

    def control(self, t, x):
        """``(u, zdot, ||Y^T r||)`` at time t and state x = (q, qd, z)."""
        n = self.n
        reference_into(self.tp, t, self.ref)
        u, zdot, yn = self.law.torque(self.plant, x[0:n], x[n:2 * n], self.ref, x[2 * n:])
        return np.asarray(u, dtype=float), np.asarray(zdot, dtype=float), float(yn)

    def plant_rhs(self, x, u):
        n = self.n
        self.nrhs += 1
        out = np.empty(2 * n)
        out[:n] = x[n:2 * n]
        out[n:] = self.plant.forward_dynamics(x[0:n], x[n:2 * n], u)
        return out

    def rhs(self, t, x):
        u, zdot, _ = self.control(t, x)
        return np.concatenate([self.plant_rhs(x, u), zdot])


def _margins(x, n, opt) -> tuple[float, float]:
    """Distance of the state to its |q| and |qd| bounds (negative = past it)."""
    return opt.q_max - np.max(np.abs(x[0:n])), opt.qd_max - np.max(np.abs(x[n:2 * n]))


def _bound_event(n, opt):
    def event(t, x):
        return min(_margins(x, n, opt))

    event.terminal = True
    return event


def run(plant, law, trajectory, opt, x0):
    from scipy.integrate import solve_ivp

    loop = _Loop(plant, law, trajectory)
    n = plant.n
    reference = opt.engine == "reference"
    rtol, atol = (min(opt.rtol, 1e-11), min(opt.atol, 1e-12)) if reference else (opt.rtol, opt.atol)
    lim = _limits(opt)
    if opt.rate is None:
        nout = int(round(opt.duration * opt.output_rate)) + 1
        t_eval = np.linspace(0.0, opt.duration, nout)
        with np.errstate(all="ignore"):
            sol = solve_ivp(loop.rhs, (0.0, opt.duration), x0, method="Radau", t_eval=t_eval,
                            rtol=rtol, atol=atol, events=_bound_event(n, opt))
        X = sol.y.T
        m = X.shape[0]
        U = np.zeros((m, n)); R = np.zeros((m, n)); yn = np.zeros(m)
        status = S.OK
        for k in range(m):
            U[k], _, yn[k] = loop.control(sol.t[k], X[k])
            R[k] = loop.ref[0]
            st = S.check(X[k], U[k], lim)
            if st != S.OK:
                status, m = st, k + 1
                break
        t_end = float(sol.t[m - 1]) if m else 0.0
        if status == S.OK and sol.status == 1:  # terminal bound event
            q_margin, qd_margin = _margins(sol.y_events[0][0], n, opt)
            status, t_end = (S.QDBOUND if qd_margin <= q_margin else S.QBOUND), float(sol.t_events[0][0])
        elif status == S.OK and sol.status < 0:
            status, t_end = S.HMIN, float(sol.t[-1]) if sol.t.size else 0.0
        return _result(plant, law, trajectory, opt, sol.t[:m], X[:m], U[:m], R[:m], yn[:m],
                       status, t_end, loop.nrhs, len(sol.t), 0)
    Ts, nsamples, dec = _sample_grid(opt)
    x = x0.copy()
    rows_t, rows_x, rows_u, rows_r, rows_y = [], [], [], [], []
    tv = np.zeros(n)
    uprev = None
    status, t_end = S.OK, opt.duration
    h = Ts / opt.substeps
    for s in range(nsamples + 1):
        t = s * Ts
        u, zdot, yn = loop.control(t, x)
        if uprev is not None:
            tv += np.abs(u - uprev)
        uprev = u
        st = S.check(x, u, lim)
        if s % dec == 0 or st != S.OK:
            rows_t.append(t); rows_x.append(x.copy()); rows_u.append(u); rows_r.append(loop.ref[0].copy())
            rows_y.append(yn)
        if st != S.OK:
            status, t_end = st, t
            break
        if s == nsamples:
            break
        with np.errstate(all="ignore"):
            if reference:
                sol = solve_ivp(lambda _t, y: loop.plant_rhs(y, u), (t, t + Ts), x[:2 * n], method="DOP853",
                                rtol=rtol, atol=atol)
                ok, xs = sol.success, (sol.y[:, -1] if sol.success else None)
            else:
                xs = _rk4(loop, x[:2 * n], u, h, opt.substeps)
                ok = bool(np.all(np.isfinite(xs)))
        if not ok:
            status, t_end = S.NONFINITE, t
            break
        x = np.concatenate([xs, x[2 * n:] + Ts * zdot])  # controller state: forward Euler
    return _result(plant, law, trajectory, opt, np.array(rows_t), np.array(rows_x).reshape(len(rows_t), -1),
                   np.array(rows_u).reshape(len(rows_t), n), np.array(rows_r).reshape(len(rows_t), n),
                   np.array(rows_y), status, t_end, loop.nrhs, nsamples, 0, tv=tv)


def _rk4(loop, x, u, h, nsub):
    """Classical RK4 over ``nsub`` steps of ``h`` with the torque held at ``u``."""
    for _ in range(nsub):
        k1 = loop.plant_rhs(x, u)
        k2 = loop.plant_rhs(x + 0.5 * h * k1, u)
        k3 = loop.plant_rhs(x + 0.5 * h * k2, u)
        k4 = loop.plant_rhs(x + h * k3, u)
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x
