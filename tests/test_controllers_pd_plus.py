"""rc3r.controllers.pd_plus: the worked example of a compiled law added as one module (docs/architecture.md).

Each check compares with a source the law's module does not share: Pinocchio's own algorithms
(``crba``, ``computeCoriolisMatrix``, ``computeGeneralizedGravity``) and the PD term written here by hand;
the compiled engine with the python engine (SciPy on Pinocchio's ABA); the analytic Jacobian with central
differences of the engine's right-hand side; the exported C, built by the real C compiler, with rc3r's
Python controller (``make check``). And it is reachable from a config file and the command line.
"""
from __future__ import annotations

import json
from dataclasses import replace
import shutil

import numpy as np
import pytest

import rc3r
from rc3r.cli import main
from rc3r.controllers import LAWS, make_law
from rc3r.controllers.pd_plus import LAYOUT, PDPlus


def test_registered_with_its_layout_and_code():
    assert LAWS["pd-plus"] is PDPlus and PDPlus.code == 5
    assert LAYOUT.names == ("p", "theta", "Kp", "Kd")
    law = make_law("pd-plus", np.arange(1.0, 4.0), Kp=[1.0, 2.0], Kd=7.0)
    cp = law.pack(2)
    assert cp.tolist() == [3.0, 1.0, 2.0, 3.0, 1.0, 2.0, 7.0, 7.0]
    assert LAYOUT.slice(cp, "Kd", 2).tolist() == [7.0, 7.0]


@pytest.mark.parametrize("robot", ["ur5", "panda"])
def test_torque_equals_pinocchio_feedforward_plus_pd_by_hand(robot, rng):
    """u = M(q) qdd_d + C(q, qd) qd_d + g(q) + Kp (q_d - q) + Kd (qd_d - qd), Pinocchio's M, C, g at the
    model's own parameters (the law's theta is the arm's), to 1e-10 relative."""
    import pinocchio as pin

    arm = rc3r.load_robot(robot)
    n = arm.n
    model = arm.model
    data = model.createData()
    Kp, Kd = rng.uniform(10.0, 500.0, n), rng.uniform(1.0, 100.0, n)
    law = make_law("pd-plus", arm.theta, Kp=Kp, Kd=Kd)
    for _ in range(4):
        q, qd = rng.uniform(-1, 1, (2, n))
        ref = rng.uniform(-1, 1, (3, n))
        u, zdot, diag = law.torque(arm, q, qd, ref)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        C = pin.computeCoriolisMatrix(model, data, q, qd)
        g = pin.computeGeneralizedGravity(model, data, q)
        expect = M @ ref[2] + C @ ref[1] + g + Kp * (ref[0] - q) + Kd * (ref[1] - qd)
        assert np.abs(u - expect).max() <= 1e-10 * max(1.0, np.abs(expect).max())
        assert zdot.size == 0 and diag == 0.0


def _run(engine, perturbed=True, **kw):
    spec = rc3r.build_run(controller="pd-plus", perturbed=perturbed, duration=1.0, engine=engine, **kw)
    return rc3r.simulate(spec.true_plant or spec.true_rigid, spec.law, spec.trajectory, spec.options,
                         loop=spec.loop, model=spec.controller_model)


@pytest.mark.slow
@pytest.mark.parametrize("rate", [None, 1000.0])
def test_compiled_engine_equals_python_engine(rate):
    """The 3R's compiled engine (the dispatch written from LAWS, the law's kernels inlined; analytic Jacobian
    in continuous time) and the python engine (SciPy, Pinocchio ABA) agree on the perturbed 1 s run; with the
    exact model PD+ cancels the dynamics along the reference, so the error stays at the integrator's level."""
    fast = _run("fast", rate=rate)
    slow = _run("python", rate=rate)
    assert fast.outcome == slow.outcome == "finished"
    assert fast.engine == "fast" and slow.engine == "python"
    t = np.linspace(0.0, 1.0, 51)
    qf = np.array([np.interp(t, fast.t, fast.q[:, j]) for j in range(3)])
    qs = np.array([np.interp(t, slow.t, slow.q[:, j]) for j in range(3)])
    assert np.abs(qf - qs).max() <= 1e-5, np.abs(qf - qs).max()
    exact = _run("fast", perturbed=False, rate=rate)  # the exact model from the reference's start: e stays ~0
    assert exact.outcome == "finished" and np.abs(exact.e).max() < (1e-6 if rate is None else 1e-2)


def test_analytic_jacobian_equals_central_differences(rng):
    """The law's ``slopes`` (v = qd_d, a = qdd_d move with t only) compose to the closed loop's J and f_t."""
    from test_jacobian import _analytic, _central, _setup

    spec, mod, n, cp, tp, code, kc, fx, x0 = _setup("pd-plus")
    x = x0 + 0.3 * rng.uniform(-1, 1, x0.size)
    ok, J, Ft = _analytic(mod, 0.37, x, kc, fx, code, cp, tp, n)
    assert ok
    Jc, Ftc = _central(mod, 0.37, x, kc, fx, code, cp, tp, n)
    assert np.abs(J - Jc).max() <= 1e-6 * np.abs(Jc).max()
    assert np.abs(Ft - Ftc).max() <= 1e-6 * max(np.abs(Ftc).max(), 1.0)


def test_reachable_from_a_config_file_and_the_command_line(tmp_path):
    cfg = tmp_path / "run.toml"
    cfg.write_text('[controller]\nkind = "pd-plus"\nKp = 400.0\nKd = 80.0\n\n[simulation]\nduration = 0.2\n')
    out = tmp_path / "cfg"
    assert main(["run", "--config", str(cfg), "--out", str(out), "--perturbed"]) == 0
    info = json.loads((out / "result.json").read_text()) if (out / "result.json").exists() else None
    spec = rc3r.build_run(config={"controller": {"kind": "pd-plus", "Kp": 400.0, "Kd": 80.0}})
    assert isinstance(spec.law, PDPlus) and spec.law.Kp.tolist() == 400.0 and spec.law.Kd.tolist() == 80.0
    assert info is None or "pd-plus" in json.dumps(info)
    assert main(["run", "--controller", "pd-plus", "--duration", "0.2", "--out", str(tmp_path / "cli")]) == 0


@pytest.mark.skipif(shutil.which("cc") is None or shutil.which("make") is None, reason="no C compiler or make")
@pytest.mark.parametrize("robot", ["rr3", "ur5"])
def test_exported_c_equals_rc3r(tmp_path, robot):
    """``rc3r export --controller pd-plus``: the C controller, compiled by cc, equals rc3r's Python controller
    over 1000 sampled calls to 1e-9 N m (the harness's ``make check``)."""
    from test_export import BOUND, _check

    head = {"rr3": "perturbed = true\n",  # the UR5: a payload of 0..3 kg unknown to the controller, gains for its wrist
            "ur5": 'robot = "ur5"\n\n[payload]\nmass = [0.0, 3.0]\n\n[gains."pd-plus"]\nKp = 20.0\nKd = 1.0\n'}[robot]
    cfg = tmp_path / "run.toml"
    cfg.write_text(head + '\n[simulation]\nrate = 1000.0\nengine = "python"\n')
    out = tmp_path / "export"
    assert main(["export", "--config", str(cfg), "--controller", "pd-plus", "--out", str(out)]) == 0
    assert "v[i] = ref[1][i];" in (out / "rc3r_controller.c").read_text()
    code, numbers, stdout = _check(out)
    assert code == 0, stdout
    assert numbers["calls"] == 1000 and numbers["max_abs_diff"] <= BOUND, stdout


def _held_loop_figure(arm, trajectory, Kd, rate: float, duration: float) -> float:
    """T max_t lambda_max(M(q_d(t))^-1 Kd) along the reference, with Pinocchio's crba (every 0.01 s over the run):
    the held loop M qdd = -Kd qd under a zero-order hold is stable only below 2 (forward Euler's bound)."""
    import pinocchio as pin

    data = arm.model.createData()
    worst = 0.0
    for q in trajectory.evaluate(np.arange(0.0, duration + 1e-9, 0.01))[0]:
        M = pin.crba(arm.model, data, np.asarray(q, dtype=float))
        M = np.triu(M) + np.triu(M, 1).T
        worst = max(worst, float(np.max(np.linalg.eigvals(np.linalg.solve(M, np.diag(Kd))).real)))
    return worst / rate


def test_default_sampled_pd_plus_on_the_panda_at_1khz_is_clean():
    """PD+'s class defaults (Kd = 100 on every joint) put the Panda's light wrist far past the held loop's bound
    at 1 kHz (T lambda_max(M^-1 Kd) about 18, stable only below 2: it diverged within 10 ms); a sampled run
    without gains takes the sampled-data rule's, as ``pd`` does: their figure along the run's reference,
    computed here with Pinocchio's M, is the rule's target, K_SHARE real_limit at rate / margin (0.25 at 500 Hz:
    0.125 at 1 kHz; 5 % for the rule's coarser samples), and the 1 s run (python engine) is clean."""
    spec = rc3r.build_run(robot="panda", controller="pd-plus", rate=1000.0, duration=1.0)
    assert "sampled-data rule" in spec.model["gains_source"]
    arm = spec.controller_model
    kd = np.broadcast_to(np.asarray(spec.law.Kd, dtype=float), (arm.n,))
    assert _held_loop_figure(arm, spec.trajectory, np.full(arm.n, 100.0), 1000.0, 1.0) > 2.0
    assert _held_loop_figure(arm, spec.trajectory, kd, 1000.0, 1.0) <= 0.125 * 1.05
    res = rc3r.simulate(spec.true_plant, spec.law, spec.trajectory, replace(spec.options, engine="python"),
                        loop=spec.loop, model=spec.controller_model)
    assert res.outcome == "finished" and res.verdict == "clean", res.message
