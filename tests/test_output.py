"""rc3r.cli._output and rc3r.provenance: run directories written as a whole, checked before any
work, locked, with the user's umask; every output carries its provenance."""
from __future__ import annotations

import errno
import json
import os
import shutil
import stat
import time

from pathlib import Path

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
    """A rerun replaces rc3r's files as a whole (an older run's animation.gif does not survive
    beside the new ones) and keeps what rc3r did not write, the very same files; an interrupt
    mid-run leaves the old directory byte for byte, and no temporary files."""
    out = tmp_path / "r"
    assert main(RUN + ["--out", str(out)]) == 0
    (out / "animation.gif").write_text("an older run's animation")  # rc3r's name: replaced
    (out / "notes.txt").write_text("my notes on this run")  # not rc3r's: kept
    (out / "extra").mkdir()
    (out / "extra" / "fit.py").write_text("x = 1")
    inode = (out / "notes.txt").stat().st_ino
    assert main(RUN + ["--controller", "pd", "--out", str(out)]) == 2  # an earlier result: not without --force
    assert "--force" in _err(capsys)
    assert main(RUN + ["--controller", "pd", "--out", str(out), "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["extra", "metrics.json", "notes.txt", "run.png", "timeseries.csv"]
    assert (out / "notes.txt").read_text() == "my notes on this run" and (out / "notes.txt").stat().st_ino == inode
    assert (out / "extra" / "fit.py").read_text() == "x = 1"
    assert json.loads((out / "metrics.json").read_text())["controller"] == "pd"
    before = {p.name: p.read_bytes() if p.is_file() else None for p in out.iterdir()}

    def interrupted(spec):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_run, "execute", interrupted)
    assert main(RUN + ["--out", str(out), "--force"]) == 130
    assert {p.name: p.read_bytes() if p.is_file() else None for p in out.iterdir()} == before
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


# ---- a place that cannot be written: found before any work, or one line at write time ------------------


def _no_simulation(monkeypatch):
    monkeypatch.setattr(cli_run, "execute", lambda spec: pytest.fail("simulated despite an unwritable --out"))


@pytest.mark.parametrize("where, needle", [
    (lambda tmp: tmp / "afile" / "r", "Not a directory"),  # a regular file on the way
    (lambda tmp: Path("/proc") / "rc3r-out", "cannot write in /proc"),  # procfs: no file can be created, even by root
    (lambda tmp: tmp / ("r" * 250), "File name too long"),  # the name fits, .<name>.lock.XXXXXXXX does not (255)
    (lambda tmp: tmp / ("r" * 300), "File name too long"),
], ids=["under-a-file", "proc", "name-250", "name-300"])
def test_unwritable_out_is_refused_before_any_work(tmp_path, capsys, monkeypatch, where, needle):
    """As root, permission bits do not stop writes, so writability is tried (a file created and removed
    where the lock will be): the refusal is the only line on stderr (no progress line, no compile
    announcement), exit 2, before simulating. On main these were exit 70 (name too long) or an exit 2
    printed after the progress lines, once the lock could not be created."""
    (tmp_path / "afile").write_text("x")
    _no_simulation(monkeypatch)
    assert main(RUN + ["--out", str(where(tmp_path))]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("rc3r: error: --out") and needle in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


@pytest.mark.parametrize("fail_at", ["write", "swap"])
def test_an_oserror_at_write_time_is_one_line_and_keeps_the_earlier_results(tmp_path, capsys, monkeypatch, fail_at):
    """A file system that turns read-only (or full) after the checks: writing the results (the CSV) or
    swapping the directory in raises OSError(EROFS). Simulated by raising it where the OS would (as
    root no chmod makes a directory unwritable). Expected: exit 2, one line naming the error, the
    earlier result byte for byte, no temporary directory left. On main: exit 70 (internal error)
    for the write, and for the swap the same unless the errno happened to be in a list of four."""
    from rc3r.simulate import export

    out = tmp_path / "r"
    assert main(RUN + ["--out", str(out)]) == 0
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    rofs = OSError(errno.EROFS, os.strerror(errno.EROFS))
    if fail_at == "write":
        def write_csv(res, path):
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(path))
        monkeypatch.setattr(export, "write_csv", write_csv)
    else:
        real = os.replace

        def replace(src, dst):
            if Path(dst) == out and ".r.tmp-" in str(src):  # the new directory onto --out
                raise rofs
            return real(src, dst)
        monkeypatch.setattr(os, "replace", replace)
    assert main(RUN + ["--controller", "pd", "--out", str(out), "--force"]) == 2
    line = _err(capsys)
    assert "Read-only file system" in line and "earlier results in it are kept" in line, line
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]


# ---- the lock: never empty, so a second writer cannot slip in; stale locks broken safely ---------------


def test_an_empty_young_lock_is_held_not_stale(tmp_path):
    """An empty lock file is the state between an exclusive create and the PID write (of a writer on a
    file system without hard links, or an older rc3r). A second writer must not take it as stale. On
    main _acquire deleted it and took the lock: two writers."""
    from rc3r.cli._output import _acquire
    from rc3r.errors import ConfigError

    lock = tmp_path / ".r.lock"
    lock.touch()  # just created, PID not written yet
    with pytest.raises(ConfigError, match="taking the lock"):
        _acquire(lock)
    assert lock.exists() and lock.read_text() == ""
    old = time.time() - 60  # an empty lock a minute old: its writer died before writing; stale
    os.utime(lock, (old, old))
    _acquire(lock)
    assert lock.read_text() == str(os.getpid())


def test_the_lock_appears_with_its_pid_and_a_racing_writer_is_refused(tmp_path, monkeypatch):
    """Deterministic interleaving: at the very moment the lock file appears (inside os.link), a second
    writer runs its _acquire. It must find the first writer's PID there (the file is never empty) and
    be refused. On main the lock was created empty by os.open and filled afterwards: os.link was
    never called (the hook below fails) and a writer in that gap deleted the 'stale' empty lock."""
    from rc3r.cli import _output
    from rc3r.errors import ConfigError

    lock = tmp_path / ".r.lock"
    real, seen = os.link, []

    def link(src, dst, **kw):
        real(src, dst, **kw)
        if Path(dst) == lock and not seen:
            seen.append(lock.read_text())
            with pytest.raises(ConfigError, match=f"pid {os.getpid()}"):
                _output._acquire(lock)  # the second writer, in the race window

    monkeypatch.setattr(os, "link", link)
    ino = _output._acquire(lock)
    assert seen == [str(os.getpid())] and lock.stat().st_ino == ino and lock.read_text() == str(os.getpid())
    assert [p.name for p in tmp_path.iterdir()] == [".r.lock"]  # its temporary file is gone


def test_breaking_a_stale_lock_never_removes_a_fresh_one(tmp_path, monkeypatch):
    """Two writers find the same stale lock (a dead PID). Writer B breaks it and places its own lock
    between A's read and A's rename; A's rename then moves B's fresh lock. A must notice (another
    inode), put B's lock back, and be refused; B's lock is intact."""
    from rc3r.cli import _output
    from rc3r.errors import ConfigError

    lock = tmp_path / ".r.lock"
    lock.write_text("999999999")  # no such process
    real = os.rename

    def rename(src, dst):
        if Path(src) == lock and not (tmp_path / "b").exists():
            (tmp_path / "b").write_text(str(os.getpid()))  # writer B (alive: this process) ...
            os.unlink(lock)
            os.link(tmp_path / "b", lock)  # ... took the lock in between
        return real(src, dst)

    monkeypatch.setattr(os, "rename", rename)
    with pytest.raises(ConfigError, match=f"pid {os.getpid()}"):
        _output._acquire(lock)
    assert lock.read_text() == str(os.getpid()) and lock.stat().st_ino == (tmp_path / "b").stat().st_ino
    assert sorted(p.name for p in tmp_path.iterdir()) == [".r.lock", "b"]


# ---- rc3r.io: the native stderr trap, strict JSON, targets a file may not replace -----------------------


def test_native_stderr_catches_fd2_and_restores_it(capfd):
    """What is written on file descriptor 2 inside the block (as C++ does, bypassing sys.stderr) is
    caught, not shown; fd 2 works again afterwards, also when the block raises."""
    from rc3r.io import native_stderr

    with native_stderr() as cpp:
        os.write(2, b"Error:   Failed to build tree: parent link [x] of joint [j] not found.  This is not valid.\n"
                    b"         at line 262 in model.cpp\n")
    assert cpp.first_line == "Failed to build tree: parent link [x] of joint [j] not found"
    assert cpp.folded("malformed URDF u", "Pinocchio: bad") == (
        "malformed URDF u: Failed to build tree: parent link [x] of joint [j] not found (Pinocchio: bad)")
    with pytest.raises(RuntimeError), native_stderr() as quiet:
        os.write(2, b"Error: link 'tool' is not unique.\n")
        raise RuntimeError
    assert quiet.first_line == "link 'tool' is not unique"
    os.write(2, b"after\n")
    assert capfd.readouterr().err == "after\n"
    with native_stderr() as nothing:
        pass
    assert nothing.folded("m", "d") == "m: d" and nothing.folded("m") == "m"


def test_json_files_are_strict(tmp_path):
    """NaN and infinities become null (they are not JSON: strict parsers refuse them); finite values
    are unchanged."""
    from rc3r.io import atomic_write_json

    path = atomic_write_json(tmp_path / "m.json", {"a": float("nan"), "b": [float("inf"), 1.5], "c": (-float("inf"),)})

    def refuse(name):
        raise AssertionError(f"{name} in strict JSON")

    assert json.loads(path.read_text(), parse_constant=refuse) == {"a": None, "b": [None, 1.5], "c": [None]}


def test_atomic_path_never_replaces_what_is_not_a_regular_file(tmp_path):
    """A symbolic link, a FIFO, a directory: refused, left as they were; a regular file is replaced."""
    from rc3r.errors import ConfigError
    from rc3r.io import atomic_write_text

    (tmp_path / "t").write_text("target")
    (tmp_path / "l").symlink_to(tmp_path / "t")
    os.mkfifo(tmp_path / "f")
    (tmp_path / "d").mkdir()
    for name, needle in (("l", "symbolic link"), ("f", "not a regular file"), ("d", "is a directory")):
        with pytest.raises(ConfigError, match=needle):
            atomic_write_text(tmp_path / name, "new")
    assert (tmp_path / "l").is_symlink() and (tmp_path / "t").read_text() == "target"
    assert stat.S_ISFIFO(os.lstat(tmp_path / "f").st_mode) and (tmp_path / "d").is_dir()
    atomic_write_text(tmp_path / "t", "new")
    assert (tmp_path / "t").read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "f", "l", "t"]


def test_native_stderr_without_a_temporary_file_runs_the_block_as_it_is(monkeypatch, capfd):
    """No place for the trap's temporary file (a read-only TMPDIR): the URDF is still parsed (the block
    runs, nothing is caught), instead of an OSError for a user who did nothing wrong."""
    import tempfile

    from rc3r.io import native_stderr

    def no_tmp(*a, **k):
        raise OSError(30, "Read-only file system")

    monkeypatch.setattr(tempfile, "TemporaryFile", no_tmp)
    ran = []
    with native_stderr() as cpp:
        ran.append(True)
        os.write(2, b"shown\n")
    assert ran == [True] and cpp.text == "" and capfd.readouterr().err == "shown\n"
