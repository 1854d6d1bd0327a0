"""The ``python`` and ``reference`` engines: any robot, any law, any plant effect, in plain Python.

The plant is :meth:`rc3r.plants.Plant.forward_dynamics` (the rigid body's forward dynamics,
Pinocchio ABA for the robots here, under every effect); the controller is
:meth:`rc3r.controllers.Law.torque` on the *model* (a robot of the same kinematics), which it
sees only through its regressor. In sampled mode the controller gets the measurement of the
loop's effects (:mod:`rc3r.plants.loop`) and its torque goes through their delay line (the hold, the
delay line and the Euler step of the law's state are :class:`rc3r.controllers.sampled.SampledLoop`,
which :meth:`rc3r.Controller.step` shares); a rigid
body with an ``advance(q, qd, u, T)`` method (MuJoCo, :mod:`rc3r.plants.mujoco`) integrates
the held torque itself (its own RK4 at a fine step) instead of this module's RK4. ``python``: SciPy ``Radau`` at the options'
tolerances (continuous) or RK4 with ``nsub`` sub-steps per period (sampled; SciPy's Radau per period
for ``SimOptions.sampled_method`` ``"sdirk"``, ``"ros4"`` or ``"rodas"``, a stiff plant: the reference path the
compiled engine's implicit periods are compared with).
``reference``: ``Radau`` at ``rtol <= 1e-11`` (continuous) or ``DOP853`` per period
(sampled).
"""
from __future__ import annotations

import numpy as np

from .._numba_cache import ready_or_python
from ..controllers.sampled import SampledLoop
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

    def __init__(self, plant, law, trajectory, budget=None, model=None):
        self.plant, self.law = plant, law
        self.model = model if model is not None else plant.rigid
        self.n = plant.n
        self.tp = trajectory.pack()
        self.ref = np.empty((3, self.n))
        self._reference = ready_or_python(reference_into)  # interpreted while numba's cache is cold
        self.nrhs = 0
        self.budget = budget

    def torque(self, t, q, qd, z):
        """``(u, zdot, ||Y^T r||)`` at time t on the measured (q, qd) and the law's state z."""
        self._reference(self.tp, t, self.ref)
        u, zdot, yn = self.law.torque(self.model, q, qd, self.ref, z)
        return np.asarray(u, dtype=float), np.asarray(zdot, dtype=float), float(yn)

    def control(self, t, x):
        """:meth:`torque` at time t on the state x = (q, qd, z)."""
        n = self.n
        return self.torque(t, x[0:n], x[n:2 * n], x[2 * n:])

    def plant_rhs(self, x, u):
        """``(qd, qdd)`` of the plant under the actuators' torque ``u`` (after the actuator maps)."""
        n = self.n
        self.nrhs += 1
        out = np.empty(2 * n)
        out[:n] = x[n:2 * n]
        out[n:] = self.plant.forward_dynamics(x[0:n], x[n:2 * n], u, delivered=True)
        return out

    def rhs(self, t, x):
        if self.budget is not None and self.nrhs >= self.budget:
            raise _Stop(S.WORK, t)
        S.raise_if_stopped()
        u, zdot, _ = self.control(t, x)
        u = self.plant.applied_torque(x[0:self.n], x[self.n:2 * self.n], u)
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


def run(plant, law, trajectory, opt, x0, loop=None, model=None):
    """Simulate ``law`` (on ``model``'s regressor) against the :class:`~rc3r.plants.Plant` ``plant``;
    ``loop``: the sampled loop's effects or None."""
    n = plant.n
    reference = opt.engine == "reference"
    rtol, atol = (min(opt.rtol, 1e-11), min(opt.atol, 1e-12)) if reference else (opt.rtol, opt.atol)
    lim = _limits(opt)
    if opt.rate is None:
        return _continuous(plant, law, trajectory, opt, x0, rtol, atol, lim, model)
    ctl = _Loop(plant, law, trajectory, model=model)
    Ts, nsamples, dec = _sample_grid(opt)
    x = x0.copy()
    rows_t, rows_x, rows_u, rows_r, rows_y = [], [], [], [], []
    tv = np.zeros(n)
    uprev = None
    status, t_end = S.OK, opt.duration
    h = Ts / opt.substeps
    noise = loop.noise(nsamples) if loop is not None else np.zeros((0, 2 * n))
    hold = SampledLoop(law, Ts, loop.delay if loop is not None else 0, z0=x0[2 * n:])
    advance = plant.rigid.advance  # declared: None unless the rigid body integrates itself (MuJoCo)
    check = ready_or_python(S.check)  # interpreted while numba's cache is cold
    for s in range(nsamples + 1):
        t = s * Ts
        S.raise_if_stopped()
        qm, qdm = loop.measure(x, s, noise) if loop is not None else (x[:n], x[n:2 * n])
        held = hold.sample(s, ctl.torque, qm, qdm)  # z_s by forward Euler, u_s into the delay line
        x[2 * n:] = hold.z
        ucmd, yn = hold.command, hold.diagnostic
        u = np.asarray(plant.applied_torque(x[:n], x[n:2 * n], held), dtype=float)  # u_{s-d}, or u_0
        if uprev is not None:
            tv += np.abs(u - uprev)
        uprev = u
        st = check(x, ucmd, lim)
        if s % dec == 0 or st != S.OK:
            rows_t.append(t); rows_x.append(x.copy()); rows_u.append(u); rows_r.append(ctl.ref[0].copy())
            rows_y.append(yn)
        if st != S.OK:
            status, t_end = st, t
            break
        if s == nsamples:
            break
        with np.errstate(all="ignore"):
            if advance is not None:
                q1, qd1 = advance(x[:n], x[n:2 * n], u, Ts)  # simulate() refused joint-torque effects
                xs = np.concatenate([q1, qd1])
                ok = bool(np.all(np.isfinite(xs)))
            elif reference or opt.sampled_method in ("ros4", "rodas", "sdirk"):
                from scipy.integrate import solve_ivp  # here: importing SciPy's integrators costs ~1 s

                sol = solve_ivp(lambda _t, y: ctl.plant_rhs(y, u), (t, t + Ts), x[:2 * n],
                                method="DOP853" if reference else "Radau", rtol=rtol if reference else opt.period_rtol,
                                atol=atol if reference else opt.period_atol)
                ok, xs = sol.success, (sol.y[:, -1] if sol.success else None)
            else:
                xs = _rk4(ctl, x[:2 * n], u, h, opt.substeps)
                ok = bool(np.all(np.isfinite(xs)))
        if not ok:
            status, t_end = S.NONFINITE, t
            break
        x = np.concatenate([xs, x[2 * n:]])  # the controller state: the next sample's Euler step
    return _result(plant, law, trajectory, opt, np.array(rows_t), np.array(rows_x).reshape(len(rows_t), -1),
                   np.array(rows_u).reshape(len(rows_t), n), np.array(rows_r).reshape(len(rows_t), n),
                   np.array(rows_y), status, t_end, ctl.nrhs, nsamples, 0, tv=tv)


def _continuous(plant, law, trajectory, opt, x0, rtol, atol, lim, model=None):
    """Continuous time: SciPy's Radau stepped here (as ``solve_ivp`` does), so that a stop raised in
    the right-hand side (budget, non-finite torque) keeps every row before it. Rows inside a step are
    the solver's dense output (``solve_ivp``'s ``t_eval``); a |q| or |qd| bound crossing is located on
    the dense output of its step (``solve_ivp``'s terminal event)."""
    from scipy.integrate import Radau
    from scipy.optimize import brentq

    n = plant.n
    loop = _Loop(plant, law, trajectory, budget=int(RHS_PER_STEP * opt.max_steps * opt.duration) + 1000,
                 model=model)
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
        ucmd, _, yn[i] = loop.control(t_eval[i], X[i])
        U[i] = plant.applied_torque(X[i, :n], X[i, n:2 * n], ucmd)
        R[i] = loop.ref[0]
        st = S.check(X[i], ucmd, lim)
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
