"""The design benchmark (for ``rc3r bench``): wall time of a default ``rc3r design`` of a 6-DoF arm.

:func:`bench_design` runs ``rc3r design --robot ur5 --payload 0:3 --rate 1000`` (full: the defaults,
``--n 50`` random plants and 10 s runs, on every core; quick: 1 random plant and 0.5 s runs) into a
temporary directory through :func:`rc3r.cli.main`, and reports its wall time against the goal
(:data:`GOAL_S`, 2 minutes on a 2-core machine), the runs it made (the rows of its ``runs.csv``) and
runs per second. The kernels are compiled (or loaded from numba's cache) by a short run before the
clock starts. :func:`render` is its text table.
"""
from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import tempfile
import time
from pathlib import Path

__all__ = ["bench_design", "render", "GOAL_S"]

#: Wall time a default design of a 6-DoF arm should stay under [s].
GOAL_S = 120.0


def _usable_cpus() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def bench_design(main, quick: bool = False, progress=None, workers: int | None = None) -> dict:
    """Time a default ``rc3r design`` of the UR5 with a 0-3 kg payload at 1 kHz (module docstring).

    Parameters
    ----------
    main : callable
        The command line's entry point, ``main(argv) -> exit code`` (:func:`rc3r.cli.main`, handed over by
        ``rc3r bench``: the experiments sit below the command line and never import it).
    quick : bool
        1 random plant and 0.5 s runs instead of the defaults (50 plants, 10 s).
    progress : callable, optional
        ``progress(message)`` before each step.
    workers : int, optional
        ``--workers`` of the design (default: the command's, all cores).

    Returns
    -------
    dict
        ``command``, ``exit`` (the command's exit code), ``wall_s``, ``runs``, ``runs_per_s``,
        ``simulated_s`` (runs x duration), ``goal_s``, ``ratio_to_goal`` (wall / goal), ``met``,
        ``eps``, ``n``, ``duration_s``, ``rate_hz``, ``workers``, ``cpus``, ``quick``.
    """
    report = progress or (lambda msg: None)
    n, duration, rate = (1, 0.5, 1000.0) if quick else (50, 10.0, 1000.0)
    base = ["design", "--robot", "ur5", "--payload", "0:3", "--rate", f"{rate:g}"]
    if workers is not None:
        base += ["--workers", str(int(workers))]
    argv = base + (["--n", str(n), "--duration", f"{duration:g}"] if quick else [])
    report("design benchmark: loading the kernels (the same design at 1 plant, 0.02 s) ...")
    with tempfile.TemporaryDirectory() as d, contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(io.StringIO()):  # its plan and compiled instance are the timed design's
        main(base + ["--n", "1", "--duration", "0.02", "--out", str(Path(d) / "warm")])
    report(f"design benchmark: rc3r {' '.join(argv)} ...")
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "design"
        sink = io.StringIO()
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            code = main(argv + ["--out", str(out)])
        wall = time.perf_counter() - t0
        runs, eps = 0, None
        if (out / "runs.csv").exists():
            with open(out / "runs.csv", newline="") as fh:
                runs = sum(1 for _ in csv.DictReader(fh))
        if (out / "design.json").exists():
            eps = json.loads((out / "design.json").read_text()).get("eps")
    return {"command": "rc3r " + " ".join(argv) + " --out DIR", "exit": int(code), "wall_s": wall, "runs": runs,
            "runs_per_s": runs / wall if wall > 0 else None, "simulated_s": runs * duration, "goal_s": GOAL_S,
            "ratio_to_goal": wall / GOAL_S, "met": bool(code == 0 and wall <= GOAL_S), "eps": eps, "n": n,
            "duration_s": duration, "rate_hz": rate, "workers": workers, "cpus": _usable_cpus(), "quick": quick,
            "output_tail": sink.getvalue().strip().splitlines()[-1:] if sink.getvalue().strip() else []}


def render(result: dict) -> str:
    """A text table of :func:`bench_design`'s result."""
    r = result
    goal = "met" if r["met"] else "NOT MET"
    if r["quick"]:
        goal += " (quick: not the goal's size)"
    rows = [("command", r["command"]),
            ("size", f"{r['n']} random plants + the payload's 2 ends, {r['duration_s']:g} s runs at "
                     f"{r['rate_hz']:g} Hz (quick)" if r["quick"] else
                     f"{r['n']} random plants + the payload's 2 ends, {r['duration_s']:g} s runs at {r['rate_hz']:g} Hz"),
            ("workers / usable CPUs", f"{r['workers'] or 'all'} / {r['cpus']}"),
            ("exit", f"{r['exit']} ({'clean design' if r['exit'] == 0 else 'not clean / error'}; eps {r['eps']})"),
            ("runs", str(r["runs"])),
            ("wall", f"{r['wall_s']:.1f} s"),
            ("runs per second", "-" if r["runs_per_s"] is None else f"{r['runs_per_s']:.3g}"),
            ("goal", f"{r['goal_s']:g} s: wall / goal = {r['ratio_to_goal']:.3g} -> {goal}")]
    w = max(len(k) for k, _ in rows)
    return "\n".join(["Design benchmark (rc3r design, UR5, payload 0-3 kg, 1 kHz)"] +
                     [f"  {k.ljust(w)}  {v}" for k, v in rows])
