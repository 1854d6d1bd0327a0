"""Many jobs on a local process pool or a Dask cluster, each row written as it completes.

:class:`RunTable` is a CSV file that only grows: one line per finished job, written
with a single ``write`` and flushed to disk (``fsync``) before the next, so an
interrupt, a killed worker or a killed driver loses no finished row. On
:meth:`RunTable.open` an existing file is checked (same columns) and a torn last line
(a driver killed in the middle of a write) is cut off; :attr:`RunTable.done` lists the
job ids already there, which :func:`run_many` skips: a resumed campaign never
duplicates a row.

:func:`run_many` maps :func:`rc3r.campaign.jobs.run_job` over the jobs with

* ``workers=K`` -- a ``concurrent.futures.ProcessPoolExecutor`` of K processes
  (``fork`` start where the OS has it: workers inherit the loaded kernels and a script
  needs no ``if __name__ == "__main__"`` guard; ``spawn`` elsewhere). Workers ignore
  SIGINT so that Ctrl-C reaches the driver only; on an interrupt the driver terminates
  them (a run in progress is dropped, to be run again by ``--resume``);
* ``scheduler="tcp://HOST:PORT"`` -- an existing Dask cluster
  (``dask.distributed.Client``), e.g. started with ``dask scheduler`` and
  ``dask worker``; Dask re-runs the jobs of a worker that dies.

Rows are written by the driver, in completion order; :func:`sorted_rows` gives the
table in job order.
"""
from __future__ import annotations

import csv
import io
import math
import os
import signal
from pathlib import Path

from ..errors import ConfigError
from .jobs import Job, run_job

__all__ = ["RunTable", "run_many", "read_rows", "sorted_rows", "format_value"]


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
    """The rows of a campaign CSV as dicts of Python values (numbers parsed, empty = None)."""
    with open(path, newline="") as f:
        return [{k: _parse(v) for k, v in r.items()} for r in csv.DictReader(f)]


class RunTable:
    """An append-only CSV of rows keyed by their ``job`` column (module docstring)."""

    def __init__(self, path, columns):
        self.path = Path(path)
        self.columns = tuple(columns)
        self.done: set[str] = set()
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
        data = self.path.read_bytes()
        cut = data.rfind(b"\n") + 1
        if cut < len(data):  # a torn last line: the driver died while writing it
            with open(self.path, "r+b") as f:
                f.truncate(cut)
            data = data[:cut]
        rows = list(csv.reader(io.StringIO(data.decode())))
        if not rows or tuple(rows[0]) != self.columns:
            raise ConfigError(f"{self.path} has other columns than this campaign writes; use another --out")
        self.done = {r[0] for r in rows[1:] if r}

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


def _worker_init() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the driver handles Ctrl-C and stops the pool
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # and terminates workers (not the inherited "SIGTERM = Ctrl-C")


def _local(jobs, workers: int):
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context(method),
                               initializer=_worker_init)
    pending = {pool.submit(run_job, job) for job in jobs}
    try:
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                yield fut.result()
    finally:
        if pending:  # interrupted, or a job failed: stop the workers now (a run in progress is dropped);
            # the pool then fails its pending futures itself (cancelling them here instead races
            # with its management thread)
            for proc in list(getattr(pool, "_processes", {}).values()):
                if proc.is_alive():
                    proc.terminate()
        pool.shutdown(wait=True)


def _dask(jobs, scheduler: str):
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ConfigError("--scheduler needs dask.distributed: pip install 'rc3r[dask]'") from None
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
    try:
        futures = client.map(run_job, list(jobs), pure=False)
        try:
            for fut in as_completed(futures):
                yield fut.result()
        finally:
            client.cancel(futures)
    finally:
        client.close()


def run_many(jobs, table: RunTable, timing: RunTable | None = None, *, workers: int | None = None,
             scheduler: str | None = None, progress=None) -> int:
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
    """
    todo = [j for j in jobs if j.id not in table.done]
    if not todo:
        return 0
    if scheduler is not None:
        stream = _dask(todo, scheduler)
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
