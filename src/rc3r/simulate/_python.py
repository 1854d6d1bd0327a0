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


#: Right-hand-side evaluations of SciPy's Radau counted as one step of ``SimOptions.max_steps``.
RHS_PER_STEP = 10


class _Stop(Exception):
    """Raised inside SciPy's right-hand side to end a continuous run: ``status`` at ``t``."""

    def __init__(self, status: int, t: float):
        super().__init__(status, t)
        self.status, self.t = status, t


class _Loop:
    """Controller and plant of one run, evaluated from Python.

    ``budget`` bounds the right-hand-side evaluations of a continuous run (``None``: unbounded);
    a non-finite torque or state derivative ends the run (:class:`_Stop`) instead of reaching
    SciPy, which would raise on it.
    """

    def __init__(self, plant, law, trajectory, budget=None):
        self.plant, self.law = plant, law
        self.n = plant.n
        self.tp = trajectory.pack()
        self.ref = np.empty((3, self.n))
        self.nrhs = 0
        self.budget = budget

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
        if self.budget is not None and self.nrhs >= self.budget:
            raise _Stop(S.WORK, t)
        u, zdot, _ = self.control(t, x)
        out = np.concatenate([self.plant_rhs(x, u), zdot])
        if not np.all(np.isfinite(out)):
            raise _Stop(S.NONFINITE, t)
        return out


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

    n = plant.n
    reference = opt.engine == "reference"
    rtol, atol = (min(opt.rtol, 1e-11), min(opt.atol, 1e-12)) if reference else (opt.rtol, opt.atol)
    lim = _limits(opt)
    if opt.rate is None:
        return _continuous(plant, law, trajectory, opt, x0, rtol, atol, lim)
    loop = _Loop(plant, law, trajectory)
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


def _continuous(plant, law, trajectory, opt, x0, rtol, atol, lim):
    """Continuous time: SciPy's Radau stepped here (as ``solve_ivp`` does), so that a stop raised in
    the right-hand side (budget, non-finite torque) keeps every row before it. Rows inside a step are
    the solver's dense output (``solve_ivp``'s ``t_eval``); a |q| or |qd| bound crossing is located on
    the dense output of its step (``solve_ivp``'s terminal event)."""
    from scipy.integrate import Radau
    from scipy.optimize import brentq

    n = plant.n
    loop = _Loop(plant, law, trajectory, budget=int(RHS_PER_STEP * opt.max_steps * opt.duration) + 1000)
    nout = int(round(opt.duration * opt.output_rate)) + 1
    t_eval = np.linspace(0.0, opt.duration, nout)
    X = np.empty((nout, x0.size))
    X[0] = x0
    k, status, t_end, nsteps = 1, S.OK, opt.duration, 0
    margin = _bound_event(n, opt)
    with np.errstate(all="ignore"):
        try:
            solver = Radau(loop.rhs, 0.0, x0, opt.duration, rtol=rtol, atol=atol)
            while solver.status == "running":
                t_old = solver.t
                solver.step()
                nsteps += 1
                if solver.status == "failed":
                    status, t_end = S.HMIN, float(solver.t)
                    break
                dense = solver.dense_output()
                t_hi = solver.t
                if margin(solver.t, solver.y) < 0:  # the bound is crossed inside this step: find where
                    t_hi = brentq(lambda s: margin(s, dense(s)), t_old, solver.t, xtol=1e-12)
                    q_margin, qd_margin = _margins(dense(t_hi), n, opt)
                    status, t_end = (S.QDBOUND if qd_margin <= q_margin else S.QBOUND), float(t_hi)
                while k < nout and t_eval[k] <= t_hi:
                    X[k] = dense(t_eval[k])
                    k += 1
                if status != S.OK:
                    break
        except _Stop as exc:
            status, t_end = exc.status, float(exc.t)
    m = k
    U = np.zeros((m, n)); R = np.zeros((m, n)); yn = np.zeros(m)
    for i in range(m):
        U[i], _, yn[i] = loop.control(t_eval[i], X[i])
        R[i] = loop.ref[0]
        st = S.check(X[i], U[i], lim)
        if st != S.OK:
            status, m, t_end = st, i + 1, float(t_eval[i])
            break
    return _result(plant, law, trajectory, opt, t_eval[:m], X[:m], U[:m], R[:m], yn[:m],
                   status, t_end, loop.nrhs, nsteps, 0)


def _rk4(loop, x, u, h, nsub):
    """Classical RK4 over ``nsub`` steps of ``h`` with the torque held at ``u``."""
    for _ in range(nsub):
        k1 = loop.plant_rhs(x, u)
        k2 = loop.plant_rhs(x + 0.5 * h * k1, u)
        k3 = loop.plant_rhs(x + 0.5 * h * k2, u)
        k4 = loop.plant_rhs(x + h * k3, u)
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x
