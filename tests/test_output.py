"""rc3r.cli._output and rc3r.provenance: run directories written as a whole, checked before any
work, locked, with the user's umask; every output carries its provenance."""
from __future__ import annotations

import json
import os
import stat

import pytest

import rc3r.cli.run as cli_run
from rc3r.cli import main

RUN = ["run", "--controller", "fbl", "--duration", "0.2"]


def _err(capsys):
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("rc3r: error: ")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("make, needle", [
    (lambda p: p.write_text("x"), "is a file"),
    (lambda p: p.symlink_to(p.parent), "symbolic link"),
], ids=["file", "symlink"])
def test_bad_out_refused_before_simulating(tmp_path, capsys, monkeypatch, make, needle):
    """--out a file or a symlink: one line, exit 2, and the simulation never starts."""
    out = tmp_path / "out"
    make(out)
    monkeypatch.setattr(cli_run, "execute", lambda spec: pytest.fail("simulated despite a bad --out"))
    assert main(RUN + ["--out", str(out)]) == 2
    assert needle in _err(capsys)


def test_out_root_and_device_refused(capsys):
    assert main(RUN + ["--out", "/"]) == 2
    assert "filesystem root" in _err(capsys)
    assert main(RUN + ["--out", "/dev/null"]) == 2
    assert "not a directory" in _err(capsys)


def test_second_writer_refused_stale_lock_taken(tmp_path, capsys):
    out = tmp_path / "r"
    lock = tmp_path / ".r.lock"
    lock.write_text(str(os.getpid()))  # a live process holds it
    assert main(RUN + ["--out", str(out)]) == 2
    assert "is writing to" in _err(capsys)
    lock.write_text("999999999")  # no such process: stale
    assert main(RUN + ["--out", str(out)]) == 0
    assert not lock.exists() and (out / "metrics.json").exists()


def test_directory_replaced_as_a_whole_and_interrupt_keeps_the_old_one(tmp_path, capsys, monkeypatch):
    """A rerun replaces the directory (a file of the old run does not survive beside the new
    ones); an interrupt mid-run leaves the old directory byte for byte, and no temporary files."""
    out = tmp_path / "r"
    assert main(RUN + ["--out", str(out)]) == 0
    (out / "stale-from-an-older-run.txt").write_text("x")
    assert main(RUN + ["--controller", "pd", "--out", str(out)]) == 2  # an earlier result: not without --force
    assert "--force" in _err(capsys)
    assert main(RUN + ["--controller", "pd", "--out", str(out), "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "run.png", "timeseries.csv"]
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def interrupted(spec):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_run, "execute", interrupted)
    assert main(RUN + ["--out", str(out), "--force"]) == 130
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]  # no .tmp-, .old- or .lock left


def test_files_get_the_users_umask(tmp_path):
    old = os.umask(0o027)
    try:
        out = tmp_path / "r"
        assert main(RUN + ["--out", str(out)]) == 0
        assert stat.S_IMODE((out / "metrics.json").stat().st_mode) == 0o640
        assert stat.S_IMODE(out.stat().st_mode) == 0o750
    finally:
        os.umask(old)


def test_metrics_carry_provenance_and_the_seed_actually_used(tmp_path):
    out = tmp_path / "r"
    assert main(["run", "--controller", "pd", "--plant", "random:7", "--duration", "0.2", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["seed"] == 7 and m["plant"] == "random:7"
    prov = m["provenance"]
    assert prov["seed"] == 7
    assert set(prov["versions"]) >= {"rc3r", "numpy", "scipy", "numba", "pinocchio", "python"}
    assert prov["git"] is None or len(prov["git"]["commit"]) == 40
    assert "config" in prov and isinstance(prov["command"], list)


def test_out_never_replaces_a_directory_rc3r_did_not_write(tmp_path, monkeypatch, capsys):
    """`--out ''`, `--out .`, the current directory's parent, a git work tree or any non-empty
    directory without an rc3r result are refused before anything runs, and left as they were.
    (Found the hard way: `rc3r run --out ''` once replaced the whole working directory.)"""
    from rc3r.cli import main

    work = tmp_path / "project" / "sub"
    work.mkdir(parents=True)
    (work / "source.py").write_text("keep me")
    (tmp_path / "repo" / ".git").mkdir(parents=True)
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "todo.txt").write_text("keep me too")
    monkeypatch.chdir(work)
    for out in ("", ".", "..", str(work), str(tmp_path / "repo"), str(tmp_path / "notes")):
        assert main(["run", "--duration", "0.05", "--out", out]) == 2, out
        err = capsys.readouterr().err
        assert err.startswith("rc3r: error: --out") and err.count("\n") == 1, err
    assert (work / "source.py").read_text() == "keep me"
    assert (tmp_path / "notes" / "todo.txt").read_text() == "keep me too"
    assert (tmp_path / "repo" / ".git").is_dir()


def test_default_out_is_out_run_name_and_is_not_overwritten(tmp_path, monkeypatch, capsys):
    """Without --out, `rc3r run` writes out/run/<name>; a second run of the same name is refused."""
    monkeypatch.chdir(tmp_path)
    assert main(RUN) == 0
    assert (tmp_path / "out" / "run" / "fbl-ideal" / "metrics.json").exists()
    assert main(RUN + ["--perturbed"]) == 0
    assert (tmp_path / "out" / "run" / "fbl-perturbed" / "metrics.json").exists()
    capsys.readouterr()
    assert main(RUN) == 2 and "--force" in _err(capsys)
    assert main(RUN + ["--force"]) == 0
