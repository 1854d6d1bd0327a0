"""Robustness campaigns: many runs as data, on all local cores or a Dask cluster.

* :mod:`.jobs` -- :class:`Job` (one plant-controller run, a few strings and numbers)
  and :func:`run_job` (its ``runs.csv`` row);
* :mod:`.runner` -- :class:`RunTable` (an append-only CSV, resumable) and
  :func:`run_many` (local process pool or ``dask.distributed``);
* :mod:`.studies` -- the Monte Carlo over the box, the eps sweep and the sample-rate
  map: their jobs and summaries;
* :mod:`.figures` -- their figures; :mod:`.bench` -- their throughput (``rc3r bench``).

The command line is :mod:`rc3r.cli.study` (``rc3r montecarlo``, ``rc3r sweep eps``,
``rc3r sweep rate``); ``docs/robustness.md`` has what they found.
"""
from .jobs import Job, columns, plant_seed, run_job
from .runner import RunTable, read_rows, run_many, sorted_rows
from .studies import (CHATTER_RATIO, classify, eps_jobs, eps_summary, model_radii, montecarlo_jobs,
                      montecarlo_summary, rate_jobs, rate_map)

__all__ = ["Job", "columns", "plant_seed", "run_job", "RunTable", "read_rows", "run_many", "sorted_rows",
           "CHATTER_RATIO", "classify", "eps_jobs", "eps_summary", "model_radii", "montecarlo_jobs",
           "montecarlo_summary", "rate_jobs", "rate_map"]
