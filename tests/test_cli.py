"""rc3r.cli: exit codes are distinct per kind of outcome, and every error is one line."""
from __future__ import annotations

import pytest

import rc3r.cli as cli
from rc3r.cli import EXIT, main


def test_exit_codes_are_distinct():
    assert len(set(EXIT.values())) == len(EXIT)
    assert EXIT["check_failed"] != EXIT["internal_error"] != EXIT["bad_input"]


def test_internal_error_is_one_line_with_its_own_code(monkeypatch, capsys):
    """A bug (here: a command raising ZeroDivisionError) gives exit 70, one line, no traceback;
    a failed verification gives 1 (tests/test_verify.py), bad input 2, divergence 3."""
    monkeypatch.setattr(cli, "_dispatch", lambda args: 1 / 0)
    monkeypatch.delenv("RC3R_DEBUG", raising=False)
    assert main(["bounds"]) == 70
    err = capsys.readouterr().err
    assert err.startswith("rc3r: internal error: ZeroDivisionError") and err.count("\n") == 1
    assert "Traceback" not in err


def test_debug_env_shows_the_traceback(monkeypatch):
    monkeypatch.setattr(cli, "_dispatch", lambda args: 1 / 0)
    monkeypatch.setenv("RC3R_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        main(["bounds"])


def test_controller_choices_come_from_the_registry():
    from rc3r.controllers import LAWS

    parser = cli.build_parser()
    run = parser._subparsers._group_actions[0].choices["run"]
    ctrl = next(a for a in run._actions if a.dest == "controller")
    assert tuple(ctrl.choices) == tuple(LAWS)


def _erd(rel: str) -> str:
    from rc3r.robots.pinocchio import example_robot_data_dir

    return str(example_robot_data_dir() / rel)


def _options(parser) -> dict:
    """command path -> its option strings, for every (sub)command of ``parser``."""
    out = {}
    for action in parser._actions:
        if isinstance(action, __import__("argparse")._SubParsersAction):
            for name, sub in action.choices.items():
                out[f"{parser.prog} {name}"] = {s for a in sub._actions for s in a.option_strings}
                out.update(_options(sub))
    return out


def test_every_command_that_reads_a_urdf_takes_lock():
    """Issue 33 item 2: a URDF with a finger or a mimic joint needs --lock, so every command with
    --urdf has --lock (verify-model had none; its refusal advised Python syntax)."""
    commands = _options(cli.build_parser())
    with_urdf = sorted(c for c, opts in commands.items() if "--urdf" in opts)
    assert "rc3r verify-model" in with_urdf and "rc3r design" in with_urdf and len(with_urdf) >= 8, with_urdf
    assert [c for c in with_urdf if "--lock" not in commands[c]] == []


def test_verify_model_takes_the_lock_it_advises(capsys):
    """Issue 33 item 2: verify-model on the Panda's URDF (one <mimic> finger joint) is refused in one line
    ending with the options to type; verify-model with exactly those options (and the other finger
    locked) passes."""
    panda = _erd("panda_description/urdf/panda.urdf")
    assert main(["verify-model", "--generic", "--urdf", panda]) == EXIT["bad_input"]
    err = capsys.readouterr().err
    assert err.startswith("rc3r: error: ") and err.count("\n") == 1
    advice = err.strip().rpartition(" with ")[2].split()
    assert advice == ["--lock", "panda_finger_joint2=0"], err
    argv = ["verify-model", "--urdf", panda, *advice, "--lock", "panda_finger_joint1=0", "--samples", "20"]
    assert main(argv) == EXIT["ok"]
    assert "PASS: every check passed" in capsys.readouterr().out


def test_bounds_and_design_lock_a_gripper_whose_link_has_its_name(capsys):
    """Issue 33 item 1: the SO-100 (a link and a joint named ``gripper``) with ``--lock gripper=0``:
    ``rc3r bounds --payload`` exits 0 with the 5-joint arm (it was exit 70, Pinocchio's "Several frames
    match the filter"), and the run ``rc3r design`` resolves before its first simulation is built."""
    import json

    from rc3r.design.verify import design_config
    from rc3r.runspec import build_run

    so100 = _erd("so_arm_description/urdf/so100.urdf")
    assert main(["bounds", "--urdf", so100, "--lock", "gripper=0", "--payload", "0:1", "--json"]) == EXIT["ok"]
    out = json.loads(capsys.readouterr().out)
    assert out["nominal"]["n"] == 5 and out["nominal"]["locked"] == {"gripper": 0.0} and out["rho"] > 0
    cfg = design_config({}, urdf=so100, lock=[("gripper", 0.0)], payload=(0.0, 1.0))
    spec = build_run(controller="robust", config=cfg, rate=500.0, eps=1.0)
    assert spec.true_rigid.n == 5 and spec.controller_model.locked == {"gripper": 0.0}


def test_urdf_takes_a_portable_example_robot_data_name(capsys):
    """Issue 33 item 5: ``--urdf erd:<path under example-robot-data's robots/>`` is that file (the name
    design.toml stores; no venv path to type), and the robot's label is the portable name; ``erd:``
    alone is one line, exit 2."""
    import json

    assert main(["bounds", "--urdf", "erd:ur_description/urdf/ur3_robot.urdf", "--payload", "0:1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["nominal"]["robot"] == "ur3" and out["nominal"]["n"] == 6
    assert out["nominal"]["urdf"] == _erd("ur_description/urdf/ur3_robot.urdf")
    from rc3r.robots import load_urdf_robot

    assert load_urdf_robot("erd:ur_description/urdf/ur3_robot.urdf").label == "erd:ur_description/urdf/ur3_robot.urdf"
    assert main(["bounds", "--urdf", "erd:", "--payload", "0:1"]) == EXIT["bad_input"]
    err = capsys.readouterr().err
    assert err.startswith("rc3r: error: ") and err.count("\n") == 1 and "after 'erd:'" in err
