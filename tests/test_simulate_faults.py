"""Faults of a simulation: a loop too stiff to integrate stops within a bounded work, a law that
returns NaN ends the run as 'diverged' in every engine, a run stops at the first state past its
bound, and the step-size underflow exit fires where it says."""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pytest

import rc3r
from rc3r.controllers import Law, Robust
from rc3r.simulate import SimOptions, simulate
from rc3r.simulate import status as S


@pytest.fixture(scope="module")
def perturbed():
    return rc3r.build_run(controller="robust", perturbed=True, duration=1.0)


def test_tiny_eps_stops_on_the_work_budget_and_names_eps(perturbed):
    """eps = 1e-6 (valid) made the fast engine run for hours (34 M steps in 0.1 s of simulated time).
    With the budget (max_steps per simulated second, checked inside the compiled loop) it stops at once
    with a message naming eps; the steps it took are within one chunk's budget."""
    law = Robust(perturbed.law.theta, rho=perturbed.law.rho, eps=1e-6)
    opt = SimOptions(duration=10.0, max_steps=2e4)
    t0 = time.perf_counter()
    res = simulate(perturbed.true_rigid, law, perturbed.trajectory, opt)
    assert time.perf_counter() - t0 < 120  # generous: the point is 'not hours'; 2e4 steps take ~0.1 s
    assert res.outcome == "diverged" and res.engine == "fast"
    assert "eps = 1e-06" in res.message and "max_steps" in res.message
    assert res.t_end < 0.5  # the first chunk's budget (2e4 x 0.5 s = 1e4 steps) is spent early
    assert res.steps + res.rejected_steps <= 1e4 + 1  # one chunk, one attempt past the budget at most
    assert res.t.size >= 1 and np.all(np.isfinite(res.q))


def test_budget_does_not_touch_normal_runs(perturbed):
    """The paper's robust run needs ~8e3 steps per second: the default budget (1e6) never fires."""
    res = simulate(perturbed.true_rigid, perturbed.law, perturbed.trajectory, perturbed.options)
    assert res.ok and res.steps + res.rejected_steps < 1e5


def test_python_engine_budget(perturbed):
    """The python engine counts right-hand-side evaluations (10 per step of the budget)."""
    law = Robust(perturbed.law.theta, rho=perturbed.law.rho, eps=1e-6)
    res = simulate(perturbed.true_rigid, law, perturbed.trajectory, SimOptions(duration=1.0, max_steps=50.0,
                                                                            engine="python"))
    assert res.outcome == "diverged" and "eps = 1e-06" in res.message
    assert res.rhs_evals <= 10 * 50 * 1.0 + 1000 + 1


@dataclass(frozen=True, eq=False)
class _NaNAfter(Law):
    """A user's Python law: zero torque, NaN from t_nan on (it sees time through q_d's row)."""

    name = "nan-after"
    q_nan: float = 0.2

    def signals(self, q, qd, ref):
        n = len(q)
        w = np.full(n, np.nan) if ref[0][0] > self.q_nan else np.zeros(n)
        return np.zeros(n), np.zeros(n), np.zeros(n), w

    def output(self, Y, r, z):
        return np.zeros(self.p), np.zeros(0), 0.0


@pytest.mark.parametrize("engine", ["python", "reference"])
@pytest.mark.parametrize("rate", [None, 1000.0])
def test_nan_torque_is_a_divergence_not_an_exception(perturbed, engine, rate):
    """simulate's contract: a diverging run never raises. SciPy's Radau raised ValueError on a NaN
    torque; now the run ends 'diverged' (non-finite) near the time the law turns NaN (q_d1 = sin t
    passes 0.2 at t = asin(0.2) = 0.2014 s) and keeps the rows before it."""
    law = _NaNAfter(perturbed.law.theta)
    res = simulate(perturbed.true_rigid, law, perturbed.trajectory, SimOptions(duration=0.5, rate=rate,
                                                                            engine=engine))
    assert res.outcome == "diverged" and "NaN" in res.message
    assert 0.19 < res.t_end < 0.21
    assert res.t.size > 100 and np.all(np.isfinite(res.q))


@pytest.mark.parametrize("which", ["q", "qd"])
def test_run_stops_at_the_first_sample_past_its_bound(perturbed, which):
    """The bound stated in the message is where the run stops: FBL tracks q_d2 = 2 sin t (for the |q|
    bound) or 2 cos t (so qd_d2 = -2 sin t, for the |qd| bound), the other joints sin t, at 1 kHz:
    |q2| or |qd2| passes 1.5 at asin(0.75) = 0.848 s. The last stored sample is past the bound, the
    one before is not (a bound checked 10x too loose, or a sample late, fails)."""
    from rc3r.trajectory import Sines

    phase = {"q": 0.0, "qd": np.pi / 2}[which]
    traj = Sines((0.0, 0.0, 0.0), ((1, 1.0, 1.0, 0.0), (2, 2.0, 1.0, phase), (3, 1.0, 1.0, 0.0)))
    law = rc3r.make_law("fbl", perturbed.true_rigid.theta)
    bounds = {"q": dict(q_max=1.5), "qd": dict(qd_max=1.5)}[which]
    res = simulate(perturbed.true_rigid, law, traj, SimOptions(duration=2.0, rate=1000.0, **bounds))
    unit = {"q": "rad", "qd": "rad/s"}[which]
    assert res.outcome == "diverged" and f"|{which}| exceeded its bound (1.5 {unit})" in res.message
    x = res.q if which == "q" else res.qd
    peak = np.max(np.abs(x), axis=1)
    assert peak[-1] > 1.5 >= peak[-2]
    assert res.t_end == pytest.approx(np.arcsin(0.75), abs=2e-3)


def test_step_underflow_exit_fires_at_its_threshold(perturbed):
    """Every step is rejected when the velocity is so large (1e150 rad/s, inside a bound of 1e300) that
    any stage point overflows qd^2; the error estimate is then 1e300 and h -> h / 10 per rejection. The
    fast engine gives up once h < 1e-14 max(1, t): from its first step h0 = 1e-5 s that is exactly
    10 rejections (1e-5 -> 1e-15), at t = 0; a threshold of 1e-20 would take 15."""
    from rc3r.simulate import _fast

    law = rc3r.make_law("fbl", perturbed.true_rigid.theta)
    opt = SimOptions(duration=0.01, q_max=1e300, qd_max=1e300, u_max=1e308, engine="fast")
    x0 = np.array([0.0, 5.0, 0.0, 1e150, 0.0, 0.0])
    from rc3r.plants import as_plant

    res = _fast.run(as_plant(perturbed.true_rigid), law, perturbed.trajectory, opt, x0)
    assert res.outcome == "diverged" and S.STATUS_TEXT[S.HMIN] in res.message
    assert res.t_end == 0.0 and res.steps == 0
    assert res.rejected_steps == 10


def test_a_signal_lost_inside_numba_still_stops_the_run(perturbed, monkeypatch):
    """A SIGINT during numba's compilation raised KeyboardInterrupt inside numba, which lost it: the
    run went on for its whole duration (seen: a 2000 s run ignoring Ctrl-C sent 6 s after start). The
    command line's handler also sets status.STOP, which simulate checks after compiling: a warm-up
    that 'swallows' the interrupt (sets the flag, returns normally) must still end the run."""
    import signal

    import importlib

    SIM = importlib.import_module("rc3r.simulate")
    from rc3r import cli

    def swallowing_warm_up(*args):
        with pytest.raises(KeyboardInterrupt):
            cli._interrupt(signal.SIGINT, None)  # what the handler does on Ctrl-C
        # ... and numba's compiler catches the KeyboardInterrupt: nothing propagates

    monkeypatch.setattr(SIM, "_warm_up", swallowing_warm_up)
    try:
        with pytest.raises(KeyboardInterrupt):
            simulate(perturbed.true_rigid, perturbed.law, perturbed.trajectory, SimOptions(duration=0.1))
    finally:
        monkeypatch.undo()
        S.STOP.clear()
    assert simulate(perturbed.true_rigid, perturbed.law, perturbed.trajectory, SimOptions(duration=0.01)).ok
