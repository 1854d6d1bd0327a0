"""Campaigns killed in every way resume to the same table, with no process left behind.

The faults are real: ``kill -9`` of the driver, ``kill -9`` of one local pool worker,
a Dask cluster whose workers are all killed, a short row in ``runs.csv``. Each test
compares the resumed ``runs.csv`` with one uninterrupted run of the same campaign
(``reference``; the rows are deterministic, so the tables are equal as sets of lines)
and checks ``/proc`` for processes that outlived their campaign. Every process a test
starts is in its own session and is killed (whole process group) in a ``finally``.
"""
from __future__ import annotations

import csv
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rc3r.campaign import RunTable, read_rows
from rc3r.cli import main

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc (Linux)")

RC3R = [str(Path(sys.executable).parent / "rc3r")]
#: 20 runs of 1 s on the 3R: about 3 s on 2 workers, long enough to be hit while running.
#: What a campaign prints on stderr before its runs (the progress bar is off without a terminal).
BANNER = ("rc3r montecarlo: ", "rc3r: compiling the simulator's kernels")
CAMPAIGN = ["montecarlo", "--n", "10", "--seed", "3", "--duration", "1", "--controllers", "fbl,robust"]


def _table(path) -> list[list[str]]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return [rows[0]] + sorted(rows[1:])


def _rows(path) -> int:
    try:
        return max(0, Path(path).read_bytes().count(b"\n") - 1)
    except OSError:
        return 0


def _stat(pid: int):
    """(state, ppid, pgrp) of a live process, or None if it is gone (or a zombie)."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    state, ppid, pgrp = text.rpartition(")")[2].split()[:3]
    return None if state in "ZX" else (state, int(ppid), int(pgrp))


def _procs(where) -> list[int]:
    """Live processes with ``where(pid, ppid, pgrp)`` true."""
    found = []
    for d in os.listdir("/proc"):
        if d.isdigit() and (st := _stat(int(d))) is not None and where(int(d), st[1], st[2]):
            found.append(int(d))
    return found


def _wait_gone(pids, timeout: float) -> list[int]:
    """Wait up to ``timeout`` s for ``pids`` to end; return those still alive."""
    deadline = time.monotonic() + timeout
    alive = list(pids)
    while alive and time.monotonic() < deadline:
        time.sleep(0.05)
        alive = [p for p in alive if _stat(p) is not None]
    return alive


def _killpg(pgid: int) -> None:
    try:
        os.killpg(pgid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> list[list[str]]:
    """runs.csv of the campaign run once, in this process, without any fault."""
    out = tmp_path_factory.mktemp("ref") / "mc"
    assert main([*CAMPAIGN, "--workers", "1", "--out", str(out)]) == 0
    return _table(out / "runs.csv")


def _start(out: Path) -> subprocess.Popen:
    """The campaign on 2 local workers in its own session; returns when it has written a row."""
    proc = subprocess.Popen(RC3R + CAMPAIGN + ["--workers", "2", "--out", str(out)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + 180
    while _rows(out / "runs.csv") < 1 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.02)
    assert proc.poll() is None, "the campaign ended before the fault: " + proc.stderr.read()
    return proc


def _resume_and_compare(out: Path, reference) -> None:
    done = subprocess.run(RC3R + CAMPAIGN + ["--workers", "2", "--out", str(out), "--resume"],
                          capture_output=True, text=True, timeout=300, start_new_session=True)
    assert done.returncode == 0, done.stderr
    assert _table(out / "runs.csv") == reference


def _kept_rows_are_reference_rows(out: Path, reference) -> int:
    kept = _table(out / "runs.csv")
    assert kept[0] == reference[0] and all(r in reference[1:] for r in kept[1:])
    return len(kept) - 1


# --- kill -9 of the driver ----------------------------------------------------------------------

def test_sigkill_of_the_driver_kills_its_workers_and_resume_completes_the_table(tmp_path, reference):
    """The workers die with the driver (PR_SET_PDEATHSIG, else the parent watchdog of
    rc3r.campaign.runner): within 3 s of `kill -9` no process of the campaign is left
    (they were orphans of ~177 MB each, alive after the resume)."""
    out = tmp_path / "mc"
    proc = _start(out)
    try:
        workers = _procs(lambda pid, ppid, pgrp: ppid == proc.pid)
        assert len(workers) >= 2, workers  # the pool (and nothing else is required)
        proc.kill()
        proc.wait(timeout=10)
        assert _wait_gone(workers, 3.0) == []
        assert _procs(lambda pid, ppid, pgrp: pgrp == proc.pid) == []  # nothing of its session either
    finally:
        _killpg(proc.pid)
        proc.stderr.close()
    _kept_rows_are_reference_rows(out, reference)
    _resume_and_compare(out, reference)


def test_a_worker_exits_within_the_poll_period_when_its_parent_dies_without_prctl(tmp_path):
    """The fallback (no PR_SET_PDEATHSIG, e.g. not Linux): the watchdog thread of a worker
    sees its parent gone and exits within PARENT_POLL_S (0.5 s; 3 s allowed for a busy machine)."""
    code = (
        "import os, sys, time\n"
        "import rc3r.campaign.runner as runner\n"
        "runner.sys = type('S', (), {'platform': 'none'})()  # skip prctl: only the watchdog is left\n"
        "parent = os.getpid()\n"
        "if os.fork() == 0:\n"
        "    if os.fork() == 0:\n"
        "        runner._worker_init(os.getppid())\n"
        "        print(os.getpid(), flush=True)\n"
        "        time.sleep(60)\n"
        "        os._exit(0)\n"
        "    time.sleep(60)\n"
        "    os._exit(0)\n"
        "time.sleep(60)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, start_new_session=True)
    try:
        worker = int(proc.stdout.readline())
        middle = _stat(worker)[1]  # the worker's parent, which is not the session leader
        assert middle != proc.pid
        os.kill(middle, signal.SIGKILL)
        assert _wait_gone([worker], 3.0) == []
    finally:
        _killpg(proc.pid)
        proc.wait(timeout=10)
        proc.stdout.close()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="prctl is Linux's")
def test_a_worker_asks_the_kernel_for_sigkill_at_its_parents_death():
    """_worker_init sets PR_SET_PDEATHSIG to SIGKILL (read back with PR_GET_PDEATHSIG = 2 in a
    forked child, so this test process is left as it was)."""
    code = (
        "import ctypes, os, signal\n"
        "import rc3r.campaign.runner as runner\n"
        "r, w = os.pipe()\n"
        "pid = os.fork()\n"
        "if pid == 0:\n"
        "    runner._worker_init(os.getppid())\n"
        "    sig = ctypes.c_int(0)\n"
        "    ctypes.CDLL(None).prctl(2, ctypes.byref(sig), 0, 0, 0)\n"
        "    os.write(w, str(sig.value).encode())\n"
        "    os._exit(0)\n"
        "os.waitpid(pid, 0)\n"
        "print(os.read(r, 16).decode())\n"
    )
    got = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert int(got.stdout) == signal.SIGKILL


# --- a killed local worker ----------------------------------------------------------------------

def test_a_killed_local_worker_is_one_line_exit_75_and_resume_completes_the_table(tmp_path, reference):
    """`kill -9` of one pool worker: one line naming it and --resume, exit 75 (was 70,
    'internal error: BrokenProcessPool'), the rows written so far kept, no process left."""
    out = tmp_path / "mc"
    proc = _start(out)
    try:
        workers = _procs(lambda pid, ppid, pgrp: ppid == proc.pid)
        victim = workers[0]
        os.kill(victim, signal.SIGKILL)
        err = proc.communicate(timeout=60)[1]
        assert proc.returncode == 75, err
        assert _wait_gone(workers, 3.0) == []
        assert _procs(lambda pid, ppid, pgrp: pgrp == proc.pid) == []
    finally:
        _killpg(proc.pid)
    errors = [line for line in err.splitlines() if not line.startswith(BANNER)]
    assert len(errors) == 1 and "Traceback" not in err, err  # nothing but the banner and one line
    assert errors[0].startswith(f"rc3r: error: a local worker process died (pid {victim}, killed by SIGKILL)")
    kept = _kept_rows_are_reference_rows(out, reference)
    assert f"{kept} of 20 runs are in {out}/runs.csv" in errors[0] and errors[0].endswith("--resume runs the rest")
    _resume_and_compare(out, reference)


# --- a torn row ---------------------------------------------------------------------------------

def test_a_short_row_ending_in_a_newline_is_dropped_and_run_again(tmp_path):
    """A row is done only if it has every column: a short line (even with its newline) is cut
    out of the file, its job not counted as done; read_rows leaves such a line out too."""
    path = tmp_path / "runs.csv"
    path.write_text("job,x,y\na,1,2\nb,3\nc,5,6\n,7,8\n\n")
    assert [r["job"] for r in read_rows(path)] == ["a", "c"]
    with RunTable(path, ("job", "x", "y")).open(resume=True) as t:
        assert t.done == {"a", "c"} and t.dropped == 2
        t.append({"job": "b", "x": 3, "y": 4})
    assert path.read_text() == "job,x,y\na,1,2\nc,5,6\nb,3,4\n"
    # a file without rows to drop is left byte for byte
    before = path.stat().st_ino
    RunTable(path, ("job", "x", "y")).open(resume=True).close()
    assert path.stat().st_ino == before


def test_resume_after_a_torn_row_gives_the_same_table(tmp_path, reference, capsys):
    """The campaign's table with one row cut short (newline kept) and a torn last line:
    --resume says it dropped them, runs those jobs again and ends with the same table
    (it ended with exit 70, 'TypeError: int() argument ... NoneType')."""
    out = tmp_path / "mc"
    assert main([*CAMPAIGN, "--workers", "1", "--out", str(out)]) == 0
    lines = (out / "runs.csv").read_bytes().split(b"\n")
    lines[3] = lines[3][:40]  # a short row in the middle, still ending in a newline
    (out / "runs.csv").write_bytes(b"\n".join(lines[:-2]) + b"\n" + lines[-2][:25])  # and a torn last line
    capsys.readouterr()
    assert main([*CAMPAIGN, "--workers", "1", "--out", str(out), "--resume"]) == 0
    err = capsys.readouterr().err
    assert "2 incomplete row(s) of" in err and "18 already done" in err, err
    assert _table(out / "runs.csv") == reference


# --- Dask: all workers die ----------------------------------------------------------------------

def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _stop(procs) -> None:
    for p in procs:
        if p.poll() is None:
            p.terminate()
    for p in procs:
        try:
            p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass
        _killpg(p.pid)  # the process and anything it started (a worker's nanny child)
        p.wait(timeout=10)


@pytest.mark.slow
def test_a_dask_cluster_without_workers_stops_with_one_line_and_resume_completes(tmp_path, reference):
    """`dask scheduler` + two `dask worker`s, both killed (SIGKILL, nanny and worker) after the
    first row: the campaign stops within RC3R_DASK_GRACE (3 s) + the polling, exit 75, one
    line naming the scheduler and --resume (it waited silently for 10 min); rows stay;
    --resume on local workers ends with the same table; no process is left."""
    pytest.importorskip("distributed")
    dask = str(Path(sys.executable).parent / "dask")
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    servers = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard",
                                 "--idle-timeout", "600"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)]
    out = tmp_path / "mc"
    try:
        workers = [subprocess.Popen([dask, "worker", addr, "--host", "127.0.0.1", "--nworkers", "1", "--nthreads",
                                     "1", "--no-dashboard", "--death-timeout", "60"], stdout=subprocess.DEVNULL,
                                    stderr=subprocess.DEVNULL, cwd=tmp_path, start_new_session=True)
                   for _ in range(2)]
        servers += workers
        from distributed import Client

        with Client(addr, timeout="30s") as c:
            c.wait_for_workers(2, timeout=120)
        driver = subprocess.Popen(RC3R + CAMPAIGN + ["--scheduler", addr, "--out", str(out)],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                  env=dict(os.environ, RC3R_DASK_GRACE="3"), start_new_session=True)
        servers.append(driver)
        deadline = time.monotonic() + 180
        while _rows(out / "runs.csv") < 1 and time.monotonic() < deadline and driver.poll() is None:
            time.sleep(0.02)
        assert driver.poll() is None, "the campaign ended before its workers were killed"
        for w in workers:
            _killpg(w.pid)
        t0 = time.monotonic()
        err = driver.communicate(timeout=60)[1]  # it waited forever; 60 s bound the test
        waited = time.monotonic() - t0
        assert driver.returncode == 75, err
        assert waited < 20, waited  # grace 3 s + polls of 1 s; 20 s allowed for a busy machine
        assert err.count("\n") == len(err.splitlines())
        lines = [line for line in err.splitlines() if not line.startswith(BANNER)]
        assert len(lines) == 1 and "Traceback" not in err, err  # nothing but the banner and one line
        assert lines[0].startswith(f"rc3r: error: the Dask scheduler at {addr} has had no workers for 3 s")
        assert lines[0].endswith("--resume runs the rest")
        assert servers[0].poll() is None  # the scheduler lives on; only its workers are gone
    finally:
        _stop(servers)
    kept = _kept_rows_are_reference_rows(out, reference)
    assert 1 <= kept < 20
    assert _procs(lambda pid, ppid, pgrp: pgrp in {p.pid for p in servers}) == []
    _resume_and_compare(out, reference)
    # no child of this process left (a busy machine may take seconds to reap a finished pool's workers)
    def ours(pid, ppid, pgrp):  # a child of this test process that runs rc3r or dask (what the test started)
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            return False
        return ppid == os.getpid() and (b"rc3r" in cmd or b"dask" in cmd or b"distributed" in cmd)

    assert _wait_gone(_procs(ours), 15.0) == []


# --- kill -9 of a writer of a whole output directory (rc3r design, run, identify) ----------------

#: A writer of an output directory that stops inside it: prints its temporary directory, then sleeps
#: (rc3r design killed while its verification runs fill .<out>.tmp-XXXXXXXX).
_WRITER = """
import sys, time
from rc3r.cli._output import output_dir
with output_dir(sys.argv[1], own=("metrics.json",)) as tmp:
    (tmp / "metrics.json").write_text("partial")
    print(tmp, flush=True)
    time.sleep(600)
"""


def _dead_pid() -> int:
    """The PID of a process that has ended (and been reaped)."""
    p = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True,
                       check=True)
    return int(p.stdout)


def test_a_rerun_removes_the_temporary_directory_of_a_writer_killed_with_sigkill(tmp_path):
    """Property: after ``kill -9`` of a writer (a real subprocess inside rc3r.cli._output.output_dir) its
    lock and its ``.out.tmp-XXXXXXXX`` stay behind, and the earlier result is untouched; the next writer
    takes the stale lock over and removes that temporary directory (on main it stayed for good), while a
    live writer's is never touched (the second writer is refused first), nor the temporary directory of
    another output whose name starts the same (``out.tmp-x``), nor a symbolic link of that form."""
    from rc3r.cli._output import output_dir
    from rc3r.errors import ConfigError

    out = tmp_path / "out"
    out.mkdir()
    (out / "metrics.json").write_text("earlier")
    other = tmp_path / ".out.tmp-x.tmp-abcdefgh"  # the live temporary directory of the output "out.tmp-x"
    other.mkdir()
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / ".out.tmp-zzzzzzzz").symlink_to(tmp_path / "elsewhere")
    proc = subprocess.Popen([sys.executable, "-c", _WRITER, str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        left = Path(proc.stdout.readline().strip())
        assert left.parent == tmp_path and left.name.startswith(".out.tmp-"), proc.stderr.read()
        with pytest.raises(ConfigError, match=f"pid {proc.pid}"):  # a live writer: refused, nothing removed
            with output_dir(out):
                pass
        assert (left / "metrics.json").read_text() == "partial"
        proc.kill()
        proc.wait(timeout=10)
    finally:
        _killpg(proc.pid)
        proc.stdout.close()
        proc.stderr.close()
    assert left.is_dir() and (tmp_path / ".out.lock").exists()  # the fault: both left behind
    assert (out / "metrics.json").read_text() == "earlier"
    with output_dir(out, own=("metrics.json",)) as tmp:
        assert not left.exists()  # removed as soon as the lock is ours, before the new results are written
        (tmp / "metrics.json").write_text("new")
    assert (out / "metrics.json").read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["out", ".out.tmp-x.tmp-abcdefgh", ".out.tmp-zzzzzzzz", "elsewhere"])
    assert (tmp_path / ".out.tmp-zzzzzzzz").is_symlink() and other.is_dir()


def test_rc3r_run_removes_a_planted_stale_temporary_directory(tmp_path, capfd):
    """Property: the command line does it too: a stale lock with a dead PID and a killed run's
    ``.run.tmp-XXXXXXXX`` (with a partial timeseries.csv) beside --out; ``rc3r run --force`` takes the
    lock over, writes its result and leaves no temporary directory (rc3r design and identify write through
    the same rc3r.cli._output.output_dir)."""
    out = tmp_path / "run"
    out.mkdir()
    (out / "metrics.json").write_text('{"earlier": true}')
    (tmp_path / ".run.lock").write_text(str(_dead_pid()))
    stale = tmp_path / ".run.tmp-k1ll3d_9"
    stale.mkdir()
    (stale / "timeseries.csv").write_text("t,q1\n0,")
    assert main(["run", "--controller", "fbl", "--rate", "1000", "--duration", "0.05", "--engine", "python",
                 "--force", "--out", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    assert (out / "timeseries.csv").read_text().startswith("t,")
