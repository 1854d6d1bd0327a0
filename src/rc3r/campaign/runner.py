"""Many jobs on a local process pool or a Dask cluster, each row written as it completes.

:class:`RunTable` is a CSV file that only grows: one line per finished job, written
with a single ``write`` and flushed to disk (``fsync``) before the next, so an
interrupt, a killed worker or a killed driver loses no finished row. On
:meth:`RunTable.open` an existing file is checked (same columns); a row is *done*
only if it is a whole line with every column and a job id: a torn last line (a
driver killed in the middle of a write) and any short or unreadable line are cut out
of the file (:attr:`RunTable.dropped` counts them) and their jobs run again.
:attr:`RunTable.done` lists the job ids already there, which :func:`run_many` skips:
a resumed campaign never duplicates a row.

:func:`run_many` maps :func:`rc3r.campaign.jobs.run_job` over the jobs with

* ``workers=K`` -- a ``concurrent.futures.ProcessPoolExecutor`` of K processes
  (``fork`` start where the OS has it: workers inherit the loaded kernels and a script
  needs no ``if __name__ == "__main__"`` guard; ``spawn`` elsewhere). Workers ignore
  SIGINT so that Ctrl-C reaches the driver only; on an interrupt the driver terminates
  them (a run in progress is dropped, to be run again by ``--resume``). Workers die
  with the driver: on Linux the kernel kills them when it dies
  (``prctl(PR_SET_PDEATHSIG, SIGKILL)``), and everywhere a thread in each worker
  exits it within :data:`PARENT_POLL_S` of its parent's death (``kill -9`` of the
  driver leaves no process behind). A worker that dies (killed, out of memory) ends
  the campaign with :class:`rc3r.errors.WorkerLostError`, its finished rows kept;
* ``scheduler="tcp://HOST:PORT"`` -- an existing Dask cluster
  (``dask.distributed.Client``), e.g. started with ``dask scheduler`` and
  ``dask worker``; Dask re-runs the jobs of a worker that dies. A cluster that has
  had no worker for ``worker_grace`` seconds (:data:`DASK_GRACE_S`) while runs wait,
  or a job that killed several workers (Dask's ``KilledWorker``), ends the campaign
  with :class:`rc3r.errors.WorkerLostError` instead of a silent wait.

Rows are written by the driver, in completion order; :func:`sorted_rows` gives the
table in job order.
"""
from __future__ import annotations

import asyncio
import concurrent.futures
import csv
import io
import logging
import math
import os
import signal
import sys
import threading
import time
from pathlib import Path

from ..errors import ConfigError, WorkerLostError
from ..io import atomic_path
from .jobs import Job, run_job

__all__ = ["RunTable", "run_many", "plan", "prepare", "read_rows", "sorted_rows", "format_value", "DASK_GRACE_S", "PARENT_POLL_S"]

#: Seconds a Dask cluster may have no worker while runs wait before the campaign stops.
DASK_GRACE_S = 60.0
#: Period [s] at which a local worker checks that its parent (the driver) is alive.
PARENT_POLL_S = 0.5
#: Period [s] of the driver's checks on a Dask cluster while no run finishes.
_DASK_POLL_S = 1.0
#: What a bounded wait on Dask raises: one class from Python 3.11 on, three distinct ones on 3.10
#: (``distributed.wait`` raises asyncio's, ``Future.result`` concurrent.futures').
_TIMEOUTS = (TimeoutError, asyncio.TimeoutError, concurrent.futures.TimeoutError)


def format_value(v) -> str:
    """CSV text of a cell: floats by ``repr`` (round-trips exactly), None as empty."""
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else repr(v)
    return str(v)


def _parse(text: str):
    if text == "":
        return None
    if text in ("true", "false"):
        return text == "true"
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def read_rows(path) -> list[dict]:
    """The rows of a campaign CSV as dicts of Python values (numbers parsed, empty = None).

    A line without every column (torn, short) is not a row and is left out, as
    :meth:`RunTable.open` does.
    """
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        return [{k: _parse(v) for k, v in r.items()} for r in reader
                if None not in r and None not in r.values() and r.get(reader.fieldnames[0])]


def _cells(line: bytes):
    """The cells of one CSV line, or None if it is not one readable line."""
    try:
        rows = list(csv.reader([line.decode()]))
    except (UnicodeDecodeError, csv.Error):
        return None
    return rows[0] if len(rows) == 1 else None


class RunTable:
    """An append-only CSV of rows keyed by their ``job`` column (module docstring)."""

    def __init__(self, path, columns):
        self.path = Path(path)
        self.columns = tuple(columns)
        self.done: set[str] = set()
        #: Lines cut out by :meth:`open` (torn, short or unreadable rows, run again).
        self.dropped = 0
        self._f = None

    def open(self, resume: bool) -> "RunTable":
        """Create the file, or continue it (refused if it has rows and ``resume`` is false)."""
        if self.path.exists() and self.path.stat().st_size > 0:
            self._recover()
            if self.done and not resume:
                raise ConfigError(f"{self.path} already has results: give --resume to continue that campaign, "
                                  "or another --out")
        else:
            with open(self.path, "w", newline="") as f:
                f.write(self._line(self.columns))
                f.flush()
                os.fsync(f.fileno())
        self._f = open(self.path, "a", newline="")
        return self

    def _recover(self) -> None:
        """Read an existing file: check its header, keep its whole rows, cut out the others.

        A row is done only if it is a line ending in a newline, with exactly the table's
        columns and a non-empty job id (the first column); anything else -- a torn last
        line, a short line, bytes that are not CSV -- is removed from the file (rewritten
        atomically) and counted in :attr:`dropped`, so its job runs again.
        """
        data = self.path.read_bytes()
        lines = data.split(b"\n")
        tail = lines.pop()  # after the last newline: empty, or a torn line
        if not lines or _cells(lines[0]) != list(self.columns):
            raise ConfigError(f"{self.path} has other columns than this campaign writes; use another --out")
        keep, done, dropped = [lines[0]], set(), int(bool(tail))
        for line in lines[1:]:
            if not line.strip():
                continue
            cells = _cells(line)
            if cells is None or len(cells) != len(self.columns) or not cells[0] or cells[0] in done:
                dropped += 1
                continue
            keep.append(line)
            done.add(cells[0])
        if dropped or len(keep) != len(lines):
            with atomic_path(self.path) as tmp:
                tmp.write_bytes(b"".join(line + b"\n" for line in keep))
        self.done, self.dropped = done, dropped

    @staticmethod
    def _line(values) -> str:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(values)
        return buf.getvalue()

    def append(self, row: dict) -> None:
        """Write one row (one ``write``, flushed and fsynced) and mark its job done."""
        if row["job"] in self.done:
            return
        self._f.write(self._line(format_value(row.get(c)) for c in self.columns))
        self._f.flush()
        os.fsync(self._f.fileno())
        self.done.add(row["job"])

    def close(self) -> None:
        if self._f is not None:
            self._f.close()
            self._f = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(PARENT_POLL_S)
        if os.getppid() != parent:  # reparented: the driver is gone
            os._exit(1)


def _worker_init(parent: int) -> None:
    """Initializer of a local worker: leave signals to the driver, and die with it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the driver handles Ctrl-C and stops the pool
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # and terminates workers (not the inherited "SIGTERM = Ctrl-C")
    if sys.platform.startswith("linux"):
        try:  # the kernel sends SIGKILL when the thread that forked this worker (the driver's) ends
            import ctypes

            ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass  # the watchdog below still applies
    if os.getppid() != parent:  # the driver died before prctl took effect
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), name="rc3r-parent-watch", daemon=True).start()


def _lost_local(procs) -> str:
    """What happened to the pool's processes (their exit codes are read as the pool reaps them)."""
    deadline = time.monotonic() + 2.0
    while not any(p.exitcode for p in procs) and time.monotonic() < deadline:
        time.sleep(0.02)
    codes = [(p.pid, p.exitcode) for p in procs if p.exitcode]
    if any(code != -signal.SIGTERM for _, code in codes):  # the pool ends the others with SIGTERM itself
        codes = [(pid, code) for pid, code in codes if code != -signal.SIGTERM]
    dead = []
    for pid, code in codes:
        try:
            how = f"killed by {signal.Signals(-code).name}" if code < 0 else f"exit code {code}"
        except ValueError:
            how = f"exit code {code}"
        dead.append(f"pid {pid}, {how}")
    return (f"a local worker process died ({'; '.join(dead) or 'terminated abruptly'}), perhaps killed or out "
            "of memory; its run was not finished")


def _local(jobs, workers: int):
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context(method),
                               initializer=_worker_init, initargs=(os.getpid(),))
    pending = {pool.submit(run_job, job) for job in jobs}
    procs = list(getattr(pool, "_processes", {}).values())  # started by the submits (named in a failure)
    try:
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                try:
                    result = fut.result()
                except BrokenProcessPool:
                    raise WorkerLostError(_lost_local(procs)) from None
                yield result
    finally:
        if pending:  # interrupted, or a job failed: stop the workers now (a run in progress is dropped);
            # the pool then fails its pending futures itself (cancelling them here instead races
            # with its management thread)
            for proc in list(getattr(pool, "_processes", {}).values()):
                if proc.is_alive():
                    proc.terminate()
        pool.shutdown(wait=True)


def _n_workers(client) -> int | None:
    """Workers the scheduler knows now, or None if it cannot be asked."""
    try:
        return len(client.scheduler_info(n_workers=-1).get("workers", {}))
    except Exception:  # noqa: BLE001 -- any failure to ask is "no contact"
        return None


class _NoGatherWarning(logging.Filter):
    """Drops distributed's "Couldn't gather ... rescheduling" (a result lost with its worker:
    handled here, by running the job again or by the no-worker check)."""

    def filter(self, record) -> bool:
        return not str(record.msg).startswith("Couldn't gather")


def _quiet_abandoned_gathers(client) -> None:
    """Keep the client's event loop from logging a gather abandoned by ``result(timeout=...)``
    (its tasks end in distributed's internal ``AllExit``, which nobody retrieves)."""
    loop = getattr(client.loop, "asyncio_loop", None)
    if loop is None or getattr(loop.get_exception_handler(), "_rc3r", False):
        return
    previous = loop.get_exception_handler()

    def handler(lp, context):
        if type(context.get("exception")).__name__ == "AllExit":
            return
        if previous is not None:
            previous(lp, context)
        else:
            lp.default_exception_handler(context)

    handler._rc3r = True
    loop.set_exception_handler(handler)


def _dask(jobs, scheduler: str, grace: float):
    try:
        from distributed import Client, KilledWorker, wait
    except ImportError:
        raise ConfigError("--scheduler needs dask.distributed: pip install 'rc3r[dask]'") from None
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, *_TIMEOUTS) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
    _quiet_abandoned_gathers(client)
    quiet = _NoGatherWarning()
    logging.getLogger("distributed.client").addFilter(quiet)
    try:
        futures = client.map(run_job, list(jobs), pure=False)
        pending = set(futures)
        alone = None  # since when no worker (or no scheduler) has been seen, while runs wait
        try:
            while pending:
                try:
                    finished, pending = wait(pending, timeout=_DASK_POLL_S, return_when="FIRST_COMPLETED")
                    pending = set(pending)
                except _TIMEOUTS:
                    finished = ()
                progressed = False
                for fut in finished:
                    try:  # bounded: a result held by a worker that has died is gathered forever
                        result = fut.result(timeout=_DASK_POLL_S)
                    except _TIMEOUTS:
                        pending.add(fut)  # Dask computes it again (on a worker, if it has one)
                        continue
                    except KilledWorker as exc:
                        raise WorkerLostError(f"Dask workers of the scheduler at {scheduler} died while running "
                                              f"one run ({exc})") from None
                    progressed = True
                    yield result
                if progressed:
                    alone = None
                    continue
                n = _n_workers(client)
                if n:
                    alone = None
                elif alone is None:
                    alone = time.monotonic()
                elif time.monotonic() - alone > grace:
                    what = "has had no workers" if n == 0 else "has not answered"
                    raise WorkerLostError(f"the Dask scheduler at {scheduler} {what} for {grace:g} s while "
                                          f"{len(pending)} runs wait (its workers died or were stopped)")
        finally:
            client.cancel(futures)
    finally:
        client.close()
        logging.getLogger("distributed.client").removeFilter(quiet)


def plan(spec, laws=()) -> None:
    """Plan this process's compiled instance for a campaign (:func:`rc3r.simulate._fast.plan`, kept and
    inherited by the forked workers): the law of the :class:`rc3r.runspec.RunSpec` ``spec`` and the
    registered laws named in ``laws``, on the effects of ``spec``'s plant. Every job then finds the
    one instance :func:`prepare` builds (instead of one compile per law)."""
    from ..controllers import LAWS
    from ..simulate import _fast

    codes = [spec.law.code] + [LAWS[name].code for name in laws if name in LAWS]
    _fast.plan(codes, _fast.effect_codes(spec.true_plant.pack()) if spec.true_plant is not None else ())


def prepare(spec) -> bool:
    """Build the compiled integrator a :class:`rc3r.runspec.RunSpec`'s run would use if it were warm (numba compiles it, or loads
    it from its disk cache), by simulating two control periods on it; True if it did.

    Campaigns call it once before their jobs (``rc3r montecarlo``, ``sweep``, ``design``), after :func:`plan`:
    each job alone is short enough for ``"auto"`` to pass a cold compiled engine over
    (:meth:`~rc3r.simulate.engines.Engine.cold`), so without it a fresh install's campaign would run every
    job on the python engine.
    """
    from dataclasses import replace as _replace

    from ..simulate import planned_engine, simulate

    plant = spec.true_plant if spec.true_plant is not None else spec.true_rigid
    name, why = planned_engine(plant, spec.law, spec.options)
    if why is None:  # warm already, or no compiled engine can run it
        return False
    opt = spec.options
    short = _replace(opt, engine="fast", duration=min(opt.duration, 2.0 / opt.rate))
    before = os.environ.get("RC3R_COLD_START")
    os.environ["RC3R_COLD_START"] = "compile"  # the law's and trajectory's kernels too
    try:
        simulate(plant, spec.law, spec.trajectory, short, loop=spec.loop, model=spec.controller_model)
    finally:
        if before is None:
            os.environ.pop("RC3R_COLD_START", None)
        else:
            os.environ["RC3R_COLD_START"] = before
    return True


def run_many(jobs, table: RunTable, timing: RunTable | None = None, *, workers: int | None = None,
             scheduler: str | None = None, progress=None, worker_grace: float = DASK_GRACE_S) -> int:
    """Run the jobs not yet in ``table``; append each row as it completes. Returns the rows written.

    Parameters
    ----------
    jobs : list of Job
    table, timing : RunTable
        Opened tables for the rows and (optionally) the timings.
    workers : int, optional
        Local processes (default: all cores, ``os.cpu_count()``); 1 runs in this process.
    scheduler : str, optional
        Address of a Dask scheduler; then ``workers`` is ignored.
    progress : callable, optional
        Called with each finished row (a progress bar).
    worker_grace : float, optional
        Seconds a Dask cluster may have no worker while runs wait (default :data:`DASK_GRACE_S`).

    Raises
    ------
    rc3r.errors.WorkerLostError
        A local worker died, or the Dask cluster lost its workers; the rows written so far stay.
    """
    todo = [j for j in jobs if j.id not in table.done]
    if not todo:
        return 0
    if scheduler is not None:
        stream = _dask(todo, scheduler, worker_grace)
    elif (workers or os.cpu_count() or 1) == 1:
        stream = (run_job(j) for j in todo)
    else:
        stream = _local(todo, min(workers or os.cpu_count() or 1, len(todo)))
    written = 0
    try:
        for row, tim in stream:
            table.append(row)
            if timing is not None:
                timing.append(tim)
            written += 1
            if progress is not None:
                progress(row)
    finally:
        close = getattr(stream, "close", None)
        if close is not None:
            close()
    return written


def sorted_rows(rows: list[dict], jobs: list[Job]) -> list[dict]:
    """``rows`` in the order of ``jobs`` (rows of other jobs dropped)."""
    by_id = {r["job"]: r for r in rows}
    return [by_id[j.id] for j in jobs if j.id in by_id]
