"""rc3r.Controller: an external loop through step(t, q, qd) reproduces rc3r's own sampled simulation
(the same RK4 of Pinocchio's ABA, examples/external_loop.py), with the adaptive state and a delay."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import rc3r
from rc3r.errors import ParameterError
from rc3r.plants import LoopEffects
from rc3r.simulate import SimOptions, simulate

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "external_loop.py"


def _example():
    spec = importlib.util.spec_from_file_location("external_loop", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("robot, controller", [("rr3", "adaptive"), ("ur5", "fbl")])
def test_external_loop_reproduces_rc3r_run(robot, controller):
    """Issue's done-when: an external loop through Controller.step reproduces rc3r run to 1e-6 rad
    (measured: 0 to 4e-16 rad, the same arithmetic)."""
    ex = _example()
    spec = rc3r.build_run(robot=robot, controller=controller, rate=1000.0, duration=0.5)
    res, _ = rc3r.execute(spec)
    q_ext = ex.external_run(spec, "pinocchio")
    assert res.ok and q_ext.shape == res.q.shape
    assert np.abs(q_ext - res.q).max() <= 1e-6


def test_external_loop_on_mujoco():
    pytest.importorskip("mujoco")
    ex = _example()
    spec = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=0.3)
    res, _ = rc3r.execute(spec)
    assert np.abs(ex.external_run(spec, "mujoco") - res.q).max() <= 1e-6


def test_delay_and_hold_match_the_simulator():
    """Controller(delay=2) called every 0.25 ms (4 calls per 1 ms sample) holds u_{k-2} like the
    simulator's delay line: its torques at the sample times equal simulate(..., loop=delay 2)."""
    spec = rc3r.build_run(controller="fbl", perturbed=True, rate=1000.0, duration=0.02)
    res = simulate(spec.true_rigid, spec.law, spec.trajectory, spec.options, loop=LoopEffects(3, delay=2))
    ctrl = rc3r.Controller(spec.law, spec.true_rigid, spec.trajectory, rate=1000.0, delay=2)
    for k in range(len(res.t) - 1):
        for sub in range(4):
            t = k * 1e-3 + sub * 2.5e-4
            frac = sub / 4.0  # the state inside the period does not change the held torque
            q = res.q[k] + frac * (res.q[k + 1] - res.q[k])
            u = ctrl.step(t, q if sub else res.q[k], res.qd[k])
            np.testing.assert_allclose(u, res.u[k], rtol=1e-12, atol=1e-12)


def test_bad_calls():
    spec = rc3r.build_run(controller="fbl", rate=1000.0, duration=0.01)
    ctrl = rc3r.Controller.from_run(spec)
    q, qd, _ = spec.trajectory.evaluate(0.0)
    ctrl.step(0.002, q, qd)
    with pytest.raises(ParameterError, match="before its last sample"):
        ctrl.step(0.0, q, qd)
    with pytest.raises(ParameterError, match="q and qd"):
        ctrl.step(0.003, q[:2], qd)
    with pytest.raises(ParameterError, match="needs a sampled controller"):
        rc3r.Controller(spec.law, spec.true_rigid, spec.trajectory, rate=None, delay=1)


@pytest.mark.parametrize("where, bad, words", [
    ("q", np.nan, "q is NaN or infinite"),
    ("qd", np.inf, "qd is NaN or infinite"),
    ("q", -np.inf, "q is NaN or infinite"),
    ("t", np.nan, "t is NaN or infinite"),
    ("t", np.inf, "t is NaN or infinite"),
    ("t", "soon", "t is not a number"),
    ("q", "abc", "q is not a number"),
    ("qd", [1.0, "b", 3.0], "qd is not a number"),
])
@pytest.mark.parametrize("rate", [1000.0, None])
def test_non_finite_or_non_numeric_arguments_raise_parameter_error(where, bad, words, rate):
    """Property: Controller.step with a NaN or infinite entry of q or qd, a NaN or infinite t, or an
    argument that is not numbers raises ParameterError naming that argument -- never returns a NaN torque
    (main: silently NaN) and never leaks numpy's or Python's ValueError/OverflowError -- sampled or
    continuous; and the controller still works afterwards with good arguments."""
    spec = rc3r.build_run(controller="fbl", rate=1000.0, duration=0.01)
    ctrl = rc3r.Controller(spec.law, spec.true_rigid, spec.trajectory, rate=rate)
    q, qd, _ = spec.trajectory.evaluate(0.0)
    args = {"t": 0.001, "q": q.copy(), "qd": qd.copy()}
    if where == "t" or isinstance(bad, (str, list)):
        args[where] = bad
    else:
        args[where][1] = bad
    with pytest.raises(ParameterError, match=words):
        ctrl.step(args["t"], args["q"], args["qd"])
    assert np.all(np.isfinite(ctrl.step(0.001, q, qd)))
