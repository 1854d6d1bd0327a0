"""Campaign throughput (part of ``rc3r bench``): plant-controller runs per minute, 1 and 2 workers.

The same Monte Carlo jobs (FBL and robust on ``n`` plants of the robot's default box,
continuous time, ``duration`` s each) are run into a temporary table with each worker
count, one after the other in one process; the rate counts the whole of
:func:`~rc3r.campaign.runner.run_many` (pool start, job transfer, rows written and
fsynced). Target: at least 1000 runs of 10 s per minute with 2 workers.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

__all__ = ["bench_throughput", "TARGET_RUNS_PER_MIN"]

#: Runs of 10 s per minute the FBL/robust pair must reach on 2 workers.
TARGET_RUNS_PER_MIN = 1000.0


def bench_throughput(n_plants: int = 100, duration: float = 10.0, workers=(1, 2), seed: int = 0,
                     robot: str | None = None, progress=None, config: dict | None = None) -> dict:
    """Runs per minute of ``fbl,robust`` on ``n_plants`` plants for each worker count (``config``: the
    campaign's configuration, e.g. ``{"payload": {"mass": [0, 3]}, "simulation": {"rate": 1000}}``)."""
    from ..campaign.jobs import columns, run_job
    from ..campaign.runner import RunTable, run_many
    from ..campaign.studies import montecarlo_jobs

    report = progress or (lambda msg: None)
    jobs = montecarlo_jobs(n_plants, seed, ["fbl", "robust"], duration=duration, robot=robot, config=config)
    run_job(montecarlo_jobs(1, seed, ["robust"], duration=0.01, robot=robot, config=config)[0])  # kernels loaded
    # before forking
    n = jobs[0].build().true_rigid.n
    out = {"n_plants": n_plants, "runs": len(jobs), "duration_s": duration, "controllers": ["fbl", "robust"],
           "seed": seed, "robot": robot or "rr3", "config": config or {}, "workers": {}}
    for k in workers:
        report(f"throughput: {len(jobs)} runs of {duration:g} s on {k} worker(s) ...")
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            with RunTable(Path(d) / "runs.csv", columns(n)).open(resume=False) as table:
                written = run_many(jobs, table, workers=k)
            wall = time.perf_counter() - t0
        out["workers"][k] = {"wall_s": wall, "runs": written, "runs_per_min": 60.0 * written / wall}
    rates = {k: v["runs_per_min"] for k, v in out["workers"].items()}
    if 1 in rates and 2 in rates:
        out["speedup_2_vs_1"] = rates[2] / rates[1]
    best = rates.get(2, max(rates.values()))
    out["target"] = {"runs_per_min": TARGET_RUNS_PER_MIN, "measured": best,
                     "met": bool(duration >= 10.0 and best >= TARGET_RUNS_PER_MIN),
                     "note": "" if duration >= 10.0 else f"runs of {duration:g} s, not 10 s: not comparable"}
    return out
