"""What the mutation run of the campaigns (tests/mutation/run.py, group ``campaigns``) found the suite
did not check: the CSV cell format, the table's recovery of a damaged file, the job list builders,
the summaries by hand, and run_many's bookkeeping (in this process and on a local pool).

No test here simulates (a fake ``run_job`` stands in where rows are needed), so the file runs in
seconds, also with ``NUMBA_DISABLE_JIT=1``.
"""
from __future__ import annotations

import json
import os
import signal
import statistics
import time
from types import SimpleNamespace

import numpy as np

import pytest

from rc3r.campaign import Job, RunTable, plant_seed, read_rows, run_many
from rc3r.campaign import runner as R
from rc3r.campaign import studies as St
from rc3r.errors import ConfigError, WorkerLostError


# --- cells ------------------------------------------------------------------------------------------

def test_cell_text_by_hand_and_its_parse_inverts_it():
    """format_value: None -> '', booleans 'true'/'false', floats by repr (nan as 'nan'), ints and
    strings as str; _parse inverts each (an empty cell is None, an int stays an int)."""
    cases = [(None, ""), (True, "true"), (False, "false"), (0.1, "0.1"), (1e-300, "1e-300"), (-2.5, "-2.5"),
             (3, "3"), (0, "0"), ("ok", "ok"), (float("inf"), "inf")]
    for value, text in cases:
        assert R.format_value(value) == text
        back = R._parse(text)
        assert back == value and type(back) is type(value)
    assert R.format_value(float("nan")) == "nan"
    nan = R._parse("nan")
    assert isinstance(nan, float) and nan != nan
    assert R._parse("p0001/robust") == "p0001/robust"


def test_read_rows_leaves_out_short_lines_and_parses_the_rest(tmp_path):
    """read_rows: a line without every column, or without a job id, is not a row."""
    path = tmp_path / "t.csv"
    path.write_text("job,x,y\na,1,0.5\nb,2\n,3,4\nc,,true\n")
    assert read_rows(path) == [{"job": "a", "x": 1, "y": 0.5}, {"job": "c", "x": None, "y": True}]


# --- the table --------------------------------------------------------------------------------------

def test_recovery_keeps_whole_rows_and_cuts_every_other_line(tmp_path):
    """A damaged table: a short row, a row with an empty job id, a duplicate job, a line that is not
    UTF-8, a blank line, a row with too many cells and a torn last line. open(resume=True) keeps the
    header and the three whole rows in order, counts 6 dropped lines (the blank one is not a row and
    not counted), rewrites the file to exactly the kept lines and appends after them."""
    path = tmp_path / "runs.csv"
    path.write_bytes(b"job,x\na,1\nshort\n,2\nb,2\na,3\n\xff\xfe,4\n\nc,3\nd,4,5\nt,0.")
    t = RunTable(path, ("job", "x")).open(resume=True)
    assert t.done == {"a", "b", "c"} and t.dropped == 6
    assert path.read_bytes() == b"job,x\na,1\nb,2\nc,3\n"
    t.append({"job": "d", "x": 4.0})
    t.append({"job": "b", "x": 9.0})  # done already: not written again
    t.close()
    assert path.read_text() == "job,x\na,1\nb,2\nc,3\nd,4.0\n"


def test_an_intact_table_is_not_rewritten(tmp_path):
    """A table whose every line is a whole row is read as it is: nothing dropped, the file's bytes and
    its inode unchanged (no atomic rewrite of a good file)."""
    path = tmp_path / "runs.csv"
    path.write_text("job,x\na,1\nb,2\n")
    ino = path.stat().st_ino
    t = RunTable(path, ("job", "x")).open(resume=True)
    t.close()
    assert t.dropped == 0 and t.done == {"a", "b"}
    assert path.stat().st_ino == ino and path.read_text() == "job,x\na,1\nb,2\n"


def test_an_empty_or_header_only_table_is_opened_without_resume(tmp_path):
    """An empty file gets its header; a header-only file has nothing to lose, so resume is not asked;
    a file whose first line is not the header is refused."""
    path = tmp_path / "runs.csv"
    path.write_text("")
    with RunTable(path, ("job", "x")).open(resume=False):
        pass
    assert path.read_text() == "job,x\n"
    with RunTable(path, ("job", "x")).open(resume=False) as t:
        assert t.done == set() and t.dropped == 0
    for header in ("a,1", "x,1", "job,y", "job,x,extra", "job"):  # before and after "job,x" in sort order
        path.write_text(header + "\n")
        with pytest.raises(ConfigError, match="other columns"):
            RunTable(path, ("job", "x")).open(resume=True)


# --- run_many ---------------------------------------------------------------------------------------

def _fake_run_job(job):
    return {"job": job.id, "x": float(job.plant)}, {"job": job.id, "wall_time_s": 0.0}


@pytest.mark.parametrize("workers", [1, 2])
def test_run_many_writes_each_missing_row_once(tmp_path, monkeypatch, workers):
    """run_many with a stand-in run_job (in this process for workers = 1, on a forked local pool for
    2): the jobs already in the table are skipped, every other one gives one row and one timing row,
    progress sees each row, the count returned is the rows written; a second call writes nothing."""
    monkeypatch.setattr(R, "run_job", _fake_run_job)
    jobs = [Job(k, f"random:{k}", "fbl") for k in range(5)]
    path, tpath = tmp_path / "runs.csv", tmp_path / "timing.csv"
    path.write_text(f"job,x\n{jobs[1].id},1.0\n")
    seen = []
    with RunTable(path, ("job", "x")).open(resume=True) as table, \
            RunTable(tpath, ("job", "wall_time_s")).open(resume=False) as timing:
        assert run_many(jobs, table, timing, workers=workers, progress=seen.append) == 4
        assert run_many(jobs, table, timing, workers=workers) == 0
    rows = read_rows(path)
    assert sorted(r["job"] for r in rows) == sorted(j.id for j in jobs)
    assert {r["job"]: r["x"] for r in rows} == {j.id: float(j.plant) for j in jobs}
    assert sorted(r["job"] for r in seen) == sorted(j.id for j in jobs if j.plant != 1)
    assert sorted(r["job"] for r in read_rows(tpath)) == sorted(j.id for j in jobs if j.plant != 1)
    assert [r["job"] for r in R.sorted_rows(list(reversed(rows)) + [{"job": "other"}], jobs)] == [j.id for j in jobs]


# --- jobs -------------------------------------------------------------------------------------------

def test_job_ids_by_hand():
    """Job.id: p<plant, 4 digits>, or the spec for plant -1; eps and rate by repr; the tag last."""
    assert Job(7, "random:1", "robust", 0.5, 1000.0).id == "p0007/robust/eps=0.5/rate=1000.0"
    assert Job(12345, "random:1", "fbl").id == "p12345/fbl/eps=default/continuous"
    assert Job(0, "random:1", "fbl").id == "p0000/fbl/eps=default/continuous"
    assert Job(-1, "nominal", "robust", 0.05, None, tag="K=50.0").id == "nominal/robust/eps=0.05/continuous/K=50.0"


def test_montecarlo_eps_and_rate_jobs_by_hand():
    """The job lists: Monte Carlo is plant-major (every controller on plant 0, then plant 1), plant k
    is random:<plant_seed(seed, k)>, a config's [simulation] rate is every job's unless --rate is
    given; the eps sweep is rate-major on the nominal plant (or on n plants of the box); the rate map
    adds the continuous reference first and tags the jobs of each K."""
    cfg = {"simulation": {"rate": 2000}}
    jobs = St.montecarlo_jobs(2, 9, ["fbl", "robust"], eps=0.1, config=cfg)
    assert [(j.plant, j.controller, j.eps, j.rate) for j in jobs] == \
        [(0, "fbl", None, 2000.0), (0, "robust", 0.1, 2000.0), (1, "fbl", None, 2000.0), (1, "robust", 0.1, 2000.0)]
    assert [j.spec for j in jobs[::2]] == [f"random:{plant_seed(9, 0)}", f"random:{plant_seed(9, 1)}"]
    assert json.loads(jobs[0].config) == cfg
    assert {j.rate for j in St.montecarlo_jobs(1, 0, ["fbl"], rate=500, config=cfg)} == {500.0}
    assert {j.rate for j in St.montecarlo_jobs(1, 0, ["fbl"])} == {None}

    ej = St.eps_jobs([0.5, 0.05], (None, 1000.0), config=cfg)
    assert [(j.plant, j.spec, j.eps, j.rate) for j in ej] == \
        [(-1, "nominal", 0.5, None), (-1, "nominal", 0.05, None), (-1, "nominal", 0.5, 1000.0),
         (-1, "nominal", 0.05, 1000.0)]
    ej = St.eps_jobs([0.5], n_plants=2, seed=3)
    assert [(j.plant, j.spec) for j in ej] == [(0, f"random:{plant_seed(3, 0)}"), (1, f"random:{plant_seed(3, 1)}")]

    rj = St.rate_jobs([0.5], [1e3, 1e4], k_values=(None, 50))
    assert [(j.rate, j.tag) for j in rj] == [(None, ""), (1e3, ""), (1e4, ""), (None, "K=50.0"), (1e3, "K=50.0"),
                                           (1e4, "K=50.0")]
    assert {(j.plant, j.spec) for j in rj} == {(-1, "nominal")}  # the nominal plant unless n_plants is given
    assert json.loads(rj[3].config)["gains"]["robust"]["K"] == 50.0 and json.loads(rj[0].config) == {}


@pytest.mark.parametrize("rate, expected", [(None, None), (0, None), (0.0, None), (1000, 1000.0), (2.5, 2.5)])
def test_config_rate_by_hand(rate, expected):
    """[simulation] rate: absent or 0 is continuous time (None), a positive number its float."""
    cfg = {} if rate is None else {"simulation": {"rate": rate}}
    assert St.config_rate(cfg) == expected


@pytest.mark.parametrize("rate", [-1, float("nan"), float("inf"), True, "1000"])
def test_config_rate_refuses_what_is_not_a_rate(rate):
    with pytest.raises(ConfigError, match="must be a rate in Hz"):
        St.config_rate({"simulation": {"rate": rate}})


# --- summaries --------------------------------------------------------------------------------------

def _mc_row(controller, status, e, covered=None, exceeds=None, bound=None, final=0.01, tv=5.0):
    return {"controller": controller, "status": status, "max_error": e, "final_error": final, "chattering": tv,
            "covered": covered, "exceeds_bound": exceeds, "predicted_bound": bound}


def test_montecarlo_summary_by_hand():
    """Four robust rows (one diverged, three covered of which two were checked against a bound, one
    exceeding it) and two FBL rows (no ball): counts, medians by the standard library, the bound check."""
    rows = [_mc_row("robust", "ok", 0.1, True, False, 0.5, final=0.01, tv=1.0),
            _mc_row("robust", "ok", 0.3, True, True, 0.2, final=0.03, tv=3.0),
            _mc_row("robust", "ok", 0.2, False, None, None, final=0.02, tv=2.0),
            _mc_row("robust", "diverged", 9.0, True, None, None),
            _mc_row("fbl", "ok", 0.05), _mc_row("fbl", "ok", 0.07)]
    s = St.montecarlo_summary(rows)
    assert list(s) == ["fbl", "robust"]
    r = s["robust"]
    assert (r["runs"], r["ok"], r["diverged"]) == (4, 3, 1)
    assert r["max_error_median"] == pytest.approx(0.2, rel=1e-15) and r["max_error_max"] == 0.3
    assert r["max_error_p95"] == pytest.approx(statistics.quantiles([0.1, 0.2, 0.3], n=100, method="inclusive")[94],
                                               rel=1e-12)
    assert r["final_error_median"] == pytest.approx(0.02) and r["chattering_median"] == pytest.approx(2.0)
    assert (r["inside_ball"], r["bound_checked"], r["bound_exceeded"]) == (3, 2, 1)
    assert r["predicted_bound_median"] == pytest.approx(0.35, rel=1e-12)
    f = s["fbl"]
    assert (f["runs"], f["ok"], f["diverged"], f["inside_ball"], f["bound_checked"], f["bound_exceeded"],
            f["predicted_bound_median"]) == (2, 2, 0, None, None, None, None)
    assert f["max_error_median"] == pytest.approx(0.06, rel=1e-12)
    d = St.montecarlo_summary([_mc_row("pd", "diverged", 1.0)])["pd"]
    assert d["max_error_median"] is None and d["max_error_max"] is None and d["ok"] == 0


def test_eps_summary_by_hand():
    """Per (rate, eps), continuous first: the worst final error, max error and chattering over the
    finished plants, and how many diverged."""
    rows = [{"rate_hz": None, "eps": 0.5, "status": "ok", "final_error": 0.1, "max_error": 0.2, "chattering": 3.0},
            {"rate_hz": None, "eps": 0.5, "status": "ok", "final_error": 0.3, "max_error": 0.1, "chattering": 1.0},
            {"rate_hz": 1000.0, "eps": 0.5, "status": "diverged", "final_error": 9, "max_error": 9, "chattering": 9},
            {"rate_hz": None, "eps": 0.05, "status": "ok", "final_error": 0.01, "max_error": 0.02, "chattering": 7.0}]
    assert St.eps_summary(rows) == [
        {"rate_hz": None, "eps": 0.05, "runs": 1, "diverged": 0, "final_error": 0.01, "max_error": 0.02,
         "chattering": 7.0},
        {"rate_hz": None, "eps": 0.5, "runs": 2, "diverged": 0, "final_error": 0.3, "max_error": 0.2,
         "chattering": 3.0},
        {"rate_hz": 1000.0, "eps": 0.5, "runs": 1, "diverged": 1, "final_error": None, "max_error": None,
         "chattering": None}]


def test_rate_map_worst_over_plants_and_the_safe_rate_by_hand():
    """Two plants: a cell is the worst class over them (one chattering plant makes the cell chatter,
    whatever the order of the rows); the safe rate is the lowest from which every higher rate is
    clean; a map with no clean top rate has none; a reference that diverged makes its rates clean
    unless they diverge themselves; the K of a job's config keys its map."""
    jobs = [Job(k, f"random:{k}", "robust", 0.5, r, tag="K=50.0",
                config=json.dumps({"gains": {"robust": {"K": 50.0}}}))
            for k in (0, 1) for r in (None, 1e3, 2e3, 4e3)]
    tv = {(0, None): 1.0, (0, 1e3): 5.0, (0, 2e3): 2.0, (0, 4e3): 1.0,
          (1, None): 1.0, (1, 1e3): 2.0, (1, 2e3): 50.0, (1, 4e3): 1.5}
    rows = [{"job": j.id, "status": "ok", "chattering": tv[(j.plant, j.rate)]} for j in jobs]
    for order in (rows, rows[::-1]):
        m = St.rate_map(order, jobs)
        assert list(m) == [50.0]
        assert m[50.0] == {"eps": [0.5], "rates": [1e3, 2e3, 4e3], "cells": [["clean", "chattering", "clean"]],
                           "safe_rate": {0.5: 4e3}}
    rows2 = [dict(r, status="diverged") if r["job"] == jobs[3].id else r for r in rows]  # plant 0 at 4 kHz
    assert St.rate_map(rows2, jobs)[50.0]["safe_rate"] == {0.5: None}
    rows3 = [dict(r, status="diverged", chattering=0.0) if r["job"] in (jobs[0].id, jobs[4].id) else r
             for r in rows]  # both continuous references diverged
    assert St.rate_map(rows3, jobs)[50.0]["cells"] == [["clean", "clean", "clean"]]
    assert St.classify({"status": "ok", "chattering": 1e9}, None) == "clean"
    assert St.gain_label(50.0) == "50" and St.gain_label([1.0, 2.5]) == "[1, 2.5]"


# --- a local worker that dies -----------------------------------------------------------------------

def _proc(pid, code):
    return SimpleNamespace(pid=pid, exitcode=code)


def test_lost_worker_message_by_hand():
    """_lost_local names the dead workers: a signal by name, an exit code as such, a negative code that
    is no signal as an exit code; the workers the pool itself ended with SIGTERM are left out when
    another died otherwise (SIGKILL, or SIGSYS = 31, a number above SIGTERM's), kept when all did; it
    returns at once when an exit code is known (it waits up to 2 s only for none)."""
    t0 = time.monotonic()
    msg = R._lost_local([_proc(11, -signal.SIGKILL), _proc(12, -signal.SIGTERM), _proc(13, None)])
    assert time.monotonic() - t0 < 1.0
    assert "(pid 11, killed by SIGKILL)" in msg and "12" not in msg
    msg = R._lost_local([_proc(11, -signal.SIGSYS), _proc(12, -signal.SIGTERM)])
    assert "(pid 11, killed by SIGSYS)" in msg and "12" not in msg
    assert "(pid 12, killed by SIGTERM)" in R._lost_local([_proc(12, -signal.SIGTERM)])
    assert "(pid 5, exit code 1; pid 6, exit code -200)" in R._lost_local([_proc(5, 1), _proc(6, -200)])
    assert "perhaps killed or out of memory" in msg


def _dies_on_plant_2(job):
    if job.plant == 2:
        os._exit(3)
    time.sleep(0.05 * job.plant)
    return _fake_run_job(job)


def test_a_dead_local_worker_is_a_worker_lost_error(tmp_path, monkeypatch):
    """A worker that exits in the middle of a job (os._exit(3)) breaks the pool: run_many raises
    WorkerLostError naming that exit code, not concurrent.futures' BrokenProcessPool; the rows written
    before stay in the table, and the job that killed its worker has none."""
    monkeypatch.setattr(R, "run_job", _dies_on_plant_2)
    jobs = [Job(k, f"random:{k}", "fbl") for k in range(4)]
    path = tmp_path / "runs.csv"
    with RunTable(path, ("job", "x")).open(resume=False) as table:
        with pytest.raises(WorkerLostError, match="exit code 3"):
            run_many(jobs, table, workers=2)
    done = {r["job"] for r in read_rows(path)}
    assert jobs[2].id not in done and done <= {j.id for j in jobs}


# --- a row --------------------------------------------------------------------------------------------

def test_a_row_by_hand(tmp_path):
    """run_job on the nominal plant, robust law with its default eps (0.5), 0.05 s continuous on the
    python engine: the row has every column of columns(3); eps is the law's 0.5 (the job left it to
    the law), rate_hz empty, theta_dist the distance of the plant's theta to the model's theta_0,
    max_error the largest per-joint maximum; the plant is inside the law's ball, so every error is
    below the predicted bound (the guarantee) and exceeds_bound is false; the timing row names this
    process."""
    from rc3r.campaign import columns, run_job

    job = Job(-1, "nominal", "robust", None, None, duration=0.05,
              config=json.dumps({"simulation": {"engine": "python"}}))
    row, timing = run_job(job)
    spec = job.build()
    assert set(row) == set(columns(3)) and row["job"] == job.id == "nominal/robust/eps=default/continuous"
    assert row["eps"] == 0.5 and row["rate_hz"] is None and row["status"] == "ok" and row["plant_seed"] is None
    assert row["theta_dist"] == pytest.approx(np.linalg.norm(spec.true_rigid.theta - np.asarray(spec.model["theta0"])),
                                              rel=1e-12)
    e = [row[f"e_max_{j}"] for j in (1, 2, 3)]
    assert row["max_error"] == max(e) and row["max_torque"] == max(row[f"u_max_{j}"] for j in (1, 2, 3))
    assert row["covered"] is True and row["predicted_bound"] > 0
    assert max(e) < row["predicted_bound"] and row["exceeds_bound"] is False  # the guarantee holds here
    assert timing["job"] == job.id and timing["worker"].endswith(f":{os.getpid()}")


def test_a_table_whose_first_line_is_empty_is_refused(tmp_path):
    """An empty first line is not the header: the table is refused as another campaign's (a
    ConfigError, not an IndexError from an empty CSV line)."""
    path = tmp_path / "runs.csv"
    path.write_text("\njob,x\na,1\n")
    with pytest.raises(ConfigError, match="other columns"):
        RunTable(path, ("job", "x")).open(resume=True)


def _slow_job(job):
    time.sleep(0.3)
    return _fake_run_job(job)


def test_an_error_in_the_driver_stops_the_local_workers_at_once(tmp_path, monkeypatch):
    """When the driver's loop fails (here its progress callback raises), run_many closes the pool's
    stream before the exception leaves it: the workers are terminated and joined then, not when the
    exception and its traceback are released (checked while the exception is still held)."""
    import multiprocessing

    monkeypatch.setattr(R, "run_job", _slow_job)
    jobs = [Job(k, f"random:{k}", "fbl") for k in range(8)]

    def stop(row):
        raise RuntimeError("stop")

    with RunTable(tmp_path / "runs.csv", ("job", "x")).open(resume=False) as table:
        with pytest.raises(RuntimeError, match="stop") as info:
            run_many(jobs, table, workers=2, progress=stop)
        alive = [p for p in multiprocessing.active_children() if p.is_alive()]
        assert info.value is not None and alive == []
