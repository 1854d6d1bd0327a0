"""rc3r.runspec: one source of truth for a run (plant and controller bounds from the same box),
the provenance in metrics.json, engine choice, and DivergenceError."""
from __future__ import annotations

import json
import textwrap

import numpy as np
import pytest

from rc3r.cli import main
from rc3r.controllers import make_law
from rc3r.errors import DivergenceError, ParameterError
from rc3r.simulate import SimOptions, simulate
from rc3r.runspec import build_run, execute

BOX = textwrap.dedent("""
    description = "a smaller box than the paper's, and a heavier last link"
    [delta]
    mass = [0, 2]
    com = [0, 0.2]
    inertia = [0, 0.1]
    [[link]]
    index = 3
    m = [-1, 5]
""")


@pytest.fixture
def box_file(tmp_path):
    f = tmp_path / "box.toml"
    f.write_text(BOX)
    return f


def test_run_with_box_uses_the_bounds_of_that_box(box_file, tmp_path, capsys):
    """metrics.json's theta_0 and rho equal `rc3r bounds --box FILE --json` (paper method), not the
    paper's box; the certified per-coefficient radius of robust-coeff equals the bounds' too."""
    assert main(["bounds", "--box", str(box_file), "--json"]) == 0
    b = json.loads(capsys.readouterr().out)
    out = tmp_path / "run"
    assert main(["run", "--box", str(box_file), "--controller", "robust", "--perturbed", "--duration", "0.2",
                 "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    np.testing.assert_allclose(m["model"]["theta0"], b["paper"]["theta0"], rtol=0, atol=1e-12)
    assert m["model"]["rho"] == pytest.approx(b["paper"]["rho"], rel=1e-14)
    assert m["rho"] == pytest.approx(b["paper"]["rho"], rel=1e-14)  # the law got it
    assert m["model"]["box"] == str(box_file)
    assert abs(m["model"]["rho"] - 186.8129) > 10  # not the paper's box
    out2 = tmp_path / "run2"
    assert main(["run", "--box", str(box_file), "--controller", "robust-coeff", "--perturbed",
                 "--duration", "0.2", "--out", str(out2)]) == 0
    m2 = json.loads((out2 / "metrics.json").read_text())
    np.testing.assert_allclose(m2["model"]["rho_i"], b["paper_theta0_certified"]["rho_i"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(m2["rho"], b["paper_theta0_certified"]["rho_i"], rtol=0, atol=1e-12)


def test_plant_is_drawn_from_the_same_box(box_file):
    """--plant upper with --box FILE: the plant is nominal + the box's upper deltas (m3 + 5 kg)."""
    nominal = build_run(controller="fbl").true_rigid
    spec = build_run(controller="fbl", perturbed=True, plant="upper", box=str(box_file))
    d = spec.true_rigid.standard_parameters() - nominal.standard_parameters()
    names = list(spec.true_rigid.standard_parameter_names)
    assert d[names.index("m3")] == pytest.approx(5.0) and d[names.index("m1")] == pytest.approx(2.0)
    assert d[names.index("Ixy2")] == pytest.approx(0.1)


def test_default_run_records_where_its_model_came_from():
    spec = build_run(controller="robust", perturbed=True)
    assert spec.model["rho"] == pytest.approx(186.8129, abs=5e-5)
    assert "paper's method" in spec.model["theta_source"] and spec.model["box"].endswith("paper_box.toml")
    assert spec.model["nominal"] == "nominal"
    ideal = build_run(controller="fbl")
    np.testing.assert_array_equal(ideal.model["theta0"], ideal.true_rigid.theta)
    assert ideal.model["theta_source"].startswith("theta of the plant")


def test_engine_auto_picks_fast_for_compiled_laws_and_python_otherwise():
    spec = build_run(controller="fbl", perturbed=True, duration=0.05)
    res, m = execute(spec)
    assert res.engine == "fast" and m["engine"] == "fast"

    class Py(type(spec.law)):  # same law, no compiled kernel: must go to the python engine
        code = None

        def signals(self, q, qd, ref):
            n = len(q)
            return qd, ref[2] + 100 * (ref[1] - qd) + 100 * (ref[0] - q), np.zeros(n), np.zeros(n)

        def output(self, Y, r, z):
            return self.theta, np.zeros(0), 0.0

    py = Py(spec.law.theta)
    res_py = simulate(spec.true_rigid, py, spec.trajectory, SimOptions(duration=0.05))
    assert res_py.engine == "python" and res_py.ok
    with pytest.raises(ParameterError, match="no compiled kernel"):
        simulate(spec.true_rigid, py, spec.trajectory, SimOptions(duration=0.05, engine="fast"))


def test_python_engine_matches_fast_engine_sampled():
    """Same law, same ZOH + RK4 scheme: the python engine (Pinocchio ABA plant, law from Python)
    and the fast engine (compiled closed form) agree to 1e-9 rad over 1 s at 1 kHz."""
    spec = build_run(controller="robust", perturbed=True, rate=1000.0, duration=1.0, eps=50.0)
    fast = simulate(spec.true_rigid, spec.law, spec.trajectory, spec.options)
    py = simulate(spec.true_rigid, spec.law, spec.trajectory, SimOptions(duration=1.0, rate=1000.0, engine="python"))
    assert fast.ok and py.ok and fast.engine == "fast" and py.engine == "python"
    np.testing.assert_array_equal(fast.t, py.t)
    assert np.abs(fast.q - py.q).max() <= 1e-9


def test_divergence_raises_with_the_result_attached():
    """The paper's robust gains at 1 kHz diverge: raise_for_status raises DivergenceError (exit 3)
    and carries the data up to the divergence."""
    spec = build_run(controller="robust", perturbed=True, rate=1000.0, duration=1.0, eps=0.5)  # given: no rule
    res, _ = execute(spec)
    assert not res.ok
    with pytest.raises(DivergenceError) as e:
        res.raise_for_status()
    assert e.value.exit_code == 3 and e.value.result is res and "diverged at t = " in str(e.value)


def test_law_and_robot_sizes_must_match():
    spec = build_run(controller="fbl", duration=0.01)
    with pytest.raises(ParameterError, match="15"):
        simulate(spec.true_rigid, make_law("fbl", np.ones(4)), spec.trajectory)


def test_unknown_gain_in_config_is_refused(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text('[controller]\nkind = "pd"\nKpp = 5\n')
    assert main(["run", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "unknown key 'Kpp' in [controller]; did you mean 'Kp'?" in err and "Traceback" not in err


@pytest.mark.parametrize("text, needle", [
    ("simulaton = {}", "did you mean 'simulation'?"),
    ("[simulation]\nduraton = 1", "did you mean 'duration'?"),
    ("[simulation]\nduration = \"abc\"", "duration must be a number"),
    ("[simulation]\nduration = 1e9", "would store"),
    ("[simulation]\nrate = 1e12", "controller samples"),
    ("[simulation]\nrate = 0.01\nduration = 1", "slower than the duration"),
    ("[simulation]\nnsub = true", "nsub must be an integer"),
    ("seed = 1e400", "seed must be an integer"),
    ("seed = -1", "seed must be an integer"),
    ("perturbed = \"yes\"", "perturbed must be true or false"),
    ("[controller]\nkind = 5", "kind must be one of"),
    ("[controller]\nkind = \"robust\"\nLamda = 3", "did you mean 'Lambda'?"),
    ("[plant]\nspec = 3", "spec must be a string"),
    ("[model]\nrho = \"big\"", "rho must be"),
    ("controller = 5", "must be a table"),
])
def test_bad_config_values_refused_in_one_line(tmp_path, capsys, text, needle):
    """Typos, wrong types and sizes that cannot be simulated: one line naming the problem, exit 2,
    before anything is simulated or written."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(text + "\n")
    out = tmp_path / "o"
    assert main(["run", "--config", str(cfg), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("rc3r: error: ")]
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in err, err
    assert not out.exists()


def test_run_robot_with_payload_from_the_command_line(tmp_path, capsys):
    """`rc3r run --robot ur5 --payload 0:5`: the plant carries 5 kg, the controller's theta_0 is the
    middle of the exact payload segment, and metrics.json says so."""
    out = tmp_path / "u"
    assert main(["run", "--robot", "ur5", "--payload", "0:5", "--payload-com", "0,0,0.1", "--controller", "fbl",
                 "--perturbed", "--rate", "1000", "--duration", "0.2", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["robot"] == "pinocchio" and len(m["max_abs_error"]) == 6
    assert m["engine"] == "fast"  # the compiled engine runs any URDF arm (rc3r.simulate.engines)
    assert m["plant"].endswith("+ payload 5 kg") and "payload segment" in m["model"]["theta_source"]
    assert m["model"]["box"].startswith("payload of 0..5 kg")


@pytest.mark.parametrize("argv, needle", [
    (["--payload", "5:1"], "LO <= HI"),
    (["--payload", "a:b"], "LO:HI"),
    (["--payload-com", "1,2"], "X,Y,Z"),
    (["--robot", "nope"], "unknown robot"),
])
def test_bad_robot_or_payload_options(tmp_path, capsys, argv, needle):
    assert main(["run", "--robot", "ur5"] + argv + ["--out", str(tmp_path / "x")]) == 2 if "--robot" not in argv \
        else main(["run"] + argv + ["--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err


def test_verify_model_generic_robots_report_base_parameters(capsys):
    """`rc3r verify-model --robot ur5 --json`: passes, 36 base parameters (the issue's reference count)."""
    assert main(["verify-model", "--robot", "ur5", "--json", "--samples", "30"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["pass"] and d["base_parameters"] == 36


# ---- a payload range is unknown to the controller (rc3r run --payload) ---------------------------


def test_payload_alone_makes_the_controller_not_know_the_payload(ur5):
    """`--payload 0:5` without --perturbed: the plant carries 5 kg (the upper end), while the controller's
    theta_0 is the middle of the range, i.e. theta of the UR5 carrying 2.5 kg (theta is linear in the
    mass: built here independently by with_payload), and rho > 0 is the range's exact radius; the run
    is recorded as perturbed. theta_0 differs from the plant's theta by 2.5 kg x B w: far above rounding."""
    from rc3r.uncertainty.payload import with_payload

    com = (0.0, 0.0, 0.1)
    spec = build_run(robot="ur5", controller="robust", payload=(0.0, 5.0), payload_com=com, duration=0.01)
    assert spec.scenario == "perturbed" and spec.name == "robust-perturbed"
    th0, plant = np.array(spec.model["theta0"]), np.asarray(spec.true_rigid.theta)
    np.testing.assert_allclose(plant, with_payload(ur5, 5.0, com).theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(th0, with_payload(ur5, 2.5, com).theta, rtol=0, atol=1e-12)
    assert np.abs(th0 - plant).max() > 0.1
    assert spec.model["rho"] == pytest.approx(np.linalg.norm(plant - th0), rel=1e-9)  # an end is attained
    assert "payload segment" in spec.model["theta_source"]


def test_payload_with_explicit_ideal_knowledge(ur5):
    """[model] theta = "plant" is the explicit exception: the controller gets the loaded plant's theta,
    the run is ideal."""
    spec = build_run(robot="ur5", controller="fbl", payload=(0.0, 5.0), config={"model": {"theta": "plant"}},
                     duration=0.01)
    assert spec.scenario == "ideal"
    np.testing.assert_array_equal(spec.model["theta0"], spec.true_rigid.theta)


def test_payload_help_says_the_controller_does_not_know_it(capsys):
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "controller does not know it" in text and "implied by --payload" in text


# ---- what rc3r run announces -----------------------------------------------------------------------


def test_perturbed_run_says_the_perturbation_is_in_the_controller_model(tmp_path, capsys):
    """`rc3r run --perturbed` names the plant (the nominal robot itself) and the controller's model:
    theta_0 by the paper's method and rho = 186.813 (the paper's rho, 186.8129, to 6 digits); an ideal run
    says its model is the plant's theta, and names the plant's effects as a perturbed run does."""
    assert main(["run", "--perturbed", "--duration", "0.05", "--out", str(tmp_path / "r")]) == 0
    line = next(ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("rc3r run:"))
    assert "plant 'nominal' (the nominal robot)" in line
    assert "controller model (perturbed): theta_0 by the paper's method (a)" in line
    assert "rho = 186.813 " in line
    assert main(["run", "--duration", "0.05", "--out", str(tmp_path / "i")]) == 0
    line = next(ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("rc3r run:"))
    assert "controller model = the plant's theta (ideal)" in line
    assert main(["run", "--stribeck", "1:1.5:0.1:0.5", "--rate", "1000", "--duration", "0.05",
                 "--out", str(tmp_path / "s")]) == 0  # an ideal run's plant effects are named too
    line = next(ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("rc3r run:"))
    assert "(ideal); plant effects: stribeck (config)" in line


# ---- defaults that could not follow the robot: warnings ------------------------------------------


def test_degenerate_joint_limits_give_a_moving_default_trajectory_and_a_warning(monkeypatch, tmp_path, capsys):
    """The double pendulum of example-robot-data has lower = upper = 0 on both joints. Its default
    trajectory moves each joint by 0.5 rad (q_d(t) = 0.5 sin(t + i pi/3), evaluated by hand at t = 0 and
    pi/2), build_run records one warning naming both joints, metrics.json keeps it, and `rc3r run`
    prints it as one `rc3r: warning:` line."""
    import math

    import rc3r.runspec as study
    from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir

    dp = PinocchioRobot.from_urdf(example_robot_data_dir() / "double_pendulum_description/urdf/double_pendulum.urdf")
    lo, hi = dp.joint_limits
    assert np.all(lo == 0) and np.all(hi == 0)
    traj = dp.default_trajectory()
    for t in (0.0, math.pi / 2):
        q = np.asarray(traj.evaluate(t)[0]).ravel()
        np.testing.assert_allclose(q, [0.5 * math.sin(t), 0.5 * math.sin(t + math.pi / 3)], atol=1e-12)
    real = study.load_robot
    monkeypatch.setattr(study, "load_robot", lambda name: dp if name == "dp" else real(name))
    spec = build_run(robot="dp", controller="fbl", duration=0.05, engine="python")
    assert len(spec.warnings) == 1 and all(j in spec.warnings[0] for j in dp.joint_names)
    assert "fixed amplitude 0.5" in spec.warnings[0]
    _, m = execute(spec)
    assert m["warnings"] == list(spec.warnings)
    assert not build_run(controller="fbl", duration=0.05).warnings  # the 3R: none
    assert main(["run", "--robot", "dp", "--controller", "fbl", "--engine", "python", "--duration", "0.05",
                 "--out", str(tmp_path / "dp")]) == 0
    warns = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("rc3r: warning:")]
    assert len(warns) == 1 and "lower >= upper" in warns[0]
