"""Every arm from the command line (--urdf, --lock), plant options, verdict-first summary lines,
bounds of a payload on any URDF arm: the done-when of the plant-seam issue, checked end to end."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rc3r.cli import main
from rc3r.robots.pinocchio import example_robot_data_dir

ERD = example_robot_data_dir()


def _run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def _metrics(d):
    return json.loads((d / "metrics.json").read_text())


@pytest.mark.slow
def test_z1_friction_from_its_urdf_grows_the_fbl_error(tmp_path, capsys):
    """The Z1's URDF has <dynamics damping friction>: FBL (which does not model friction) tracks
    to 1e-4 rad on the frictionless plant and is measurably worse with --friction urdf; the
    summary line starts with the verdict and metrics.json records the effect's values."""
    z1 = str(ERD / "z1_description/urdf/z1.urdf")
    base = ["run", "--urdf", z1, "--lock", "jointGripper=0", "--controller", "fbl", "--rate", "1000",
            "--duration", "1"]
    code, out, _ = _run(base + ["--out", str(tmp_path / "a")], capsys)
    assert code == 0 and out.startswith("clean, within 0.01 rad: fbl-ideal")
    code, out, _ = _run(base + ["--friction", "urdf", "--out", str(tmp_path / "b")], capsys)
    a, b = _metrics(tmp_path / "a"), _metrics(tmp_path / "b")
    assert code == 0 and out.startswith("clean, outside 0.01 rad")
    assert max(b["max_abs_error"]) > 100 * max(a["max_abs_error"])
    fric = [e for e in b["effects"] if e["effect"] == "friction"][0]
    assert fric["source"] == "urdf" and fric["viscous"][:2] == [1.0, 2.0]  # the Z1 file: damping 1, 2, ...


def test_torque_limit_urdf_keeps_every_torque_within_the_effort_limit(tmp_path, capsys):
    """UR5 with a 5 kg payload under FBL with --torque-limit urdf: |u_j| <= the URDF's effort limit."""
    import xml.etree.ElementTree as ET

    urdf = ERD / "ur_description/urdf/ur5_robot.urdf"
    root = ET.parse(urdf).getroot()
    names = [j.get("name") for j in root.findall("joint") if j.get("type") in ("revolute", "continuous")]
    effort = np.array([float(root.find(f"joint[@name='{n}']/limit").get("effort")) for n in names])
    code, _, _ = _run(["run", "--robot", "ur5", "--payload", "0:5", "--controller", "fbl", "--rate", "1000",
                       "--duration", "1", "--torque-limit", "urdf", "--out", str(tmp_path / "r")], capsys)
    m = _metrics(tmp_path / "r")
    assert code == 0 and np.all(np.array(m["max_abs_torque"]) <= effort * (1 + 1e-12))
    assert m["saturation_fraction"] is not None


def test_ur5_on_mujoco_equals_the_pinocchio_plant(tmp_path, capsys):
    """UR5, FBL, 1 kHz, 1 s: the MuJoCo plant equals the Pinocchio plant to 1e-6 rad (measured 1e-11)."""
    pytest.importorskip("mujoco")
    for eng in ("pinocchio", "mujoco"):
        code, _, _ = _run(["run", "--robot", "ur5", "--controller", "fbl", "--rate", "1000", "--duration", "1",
                           "--plant-engine", eng, "--out", str(tmp_path / eng)], capsys)
        assert code == 0
    a, b = (np.loadtxt(tmp_path / e / "timeseries.csv", delimiter=",", skiprows=1) for e in ("pinocchio", "mujoco"))
    assert a.shape == b.shape and np.abs(a[:, 1:7] - b[:, 1:7]).max() <= 1e-6


def test_bounds_of_a_payload_on_the_ur10(capsys):
    """bounds --urdf UR10 --payload 0:3 --json: theta_0 is the payload segment's centre, rho its
    half-length (theta is affine in the mass): both recomputed from two plants of 0 and 3 kg."""
    from rc3r.robots.pinocchio import PinocchioRobot
    from rc3r.uncertainty.payload import with_payload

    urdf = ERD / "ur_description/urdf/ur10_robot.urdf"
    code, out, _ = _run(["bounds", "--urdf", str(urdf), "--payload", "0:3", "--json"], capsys)
    d = json.loads(out)
    ur10 = PinocchioRobot.from_urdf(urdf)
    t0, t3 = ur10.theta, with_payload(ur10, 3.0, np.zeros(3), label="3 kg").theta
    assert code == 0 and d["nominal"]["p"] == 36
    np.testing.assert_allclose(d["theta0"], (t0 + t3) / 2, rtol=1e-12, atol=1e-12)
    assert d["rho"] == pytest.approx(np.linalg.norm(t3 - t0) / 2, rel=1e-12)


@pytest.mark.parametrize("argv, what", [
    (["--lock", "nojoint"], "JOINT=VALUE"),
    (["--friction", "1:x"], "VISCOUS:COULOMB"),
    (["--noise=-1:0"], "SIGMA_Q:SIGMA_QD"),
    (["--torque-limit", "0"], "> 0"),
    (["--noise", "1e-3:0"], "sampled controller"),
])
def test_bad_plant_options_are_one_line(argv, what, tmp_path, capsys):
    code, out, err = _run(["run", "--duration", "0.01", "--out", str(tmp_path / "x")] + argv, capsys)
    assert code == 2 and err.count("\n") == 1 and err.startswith("rc3r: error:") and what in err
    assert not (tmp_path / "x").exists()


def test_model_friction_option_replaces_the_configs_and_sets_the_ranges(tmp_path, capsys):
    """``--model-friction`` is ``[model] friction`` from the command line and replaces the config's value whole:
    with the config's viscous = 5 and the option's viscous = 2, coulomb = 1,2,3 (default range 0.5..1.5), the
    controller's joint coefficients are the intervals' centres 2 2 2 1 2 3 and its rho_i their half-widths
    (0.5 x nominal, by hand), not the config's; a bad value is one line and exit 2, before any output."""
    cfg = tmp_path / "c.toml"
    cfg.write_text("perturbed = true\n[model.friction]\nviscous = 5.0\n")
    base = ["run", "--controller", "robust-coeff", "--duration", "0.01", "--engine", "python", "--config", str(cfg)]
    code, _, _ = _run(base + ["--model-friction", "viscous=2;coulomb=1,2,3", "--out", str(tmp_path / "a")], capsys)
    m = _metrics(tmp_path / "a")["model"]
    nom = [2.0, 2.0, 2.0, 1.0, 2.0, 3.0]
    assert code == 0 and m["theta0"][15:] == nom
    np.testing.assert_allclose(m["rho_i"][15:], 0.5 * np.array(nom), rtol=1e-15)
    code, _, _ = _run(base + ["--out", str(tmp_path / "b")], capsys)  # without the option: the config's
    assert code == 0 and _metrics(tmp_path / "b")["model"]["theta0"][15:] == [5.0, 5.0, 5.0]
    for bad, what in (("viscous", "KEY=VALUE"), ("viscous=x", "KEY=VALUE"), ("viscous=-1", ">= 0"),
                      ("viscous=1;range=1.2,2", "range"), ("stiction=1", "unknown key")):
        code, out, err = _run(base + ["--model-friction", bad, "--out", str(tmp_path / "x")], capsys)
        assert code == 2 and err.count("\n") == 1 and err.startswith("rc3r: error:") and what in err, err
        assert not (tmp_path / "x").exists()
