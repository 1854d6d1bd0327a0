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
