"""First-run compile time of the 3R's compiled simulator, two source trees side by side in one run.

Issue 34's bar: the first run with an empty cache (``NUMBA_CACHE_DIR`` and ``RC3R_CACHE_DIR`` new and
empty) of the 3R's continuous simulator is no slower after a refactor than before. Each measurement is a
fresh interpreter running ``rc3r run --robot rr3 --perturbed --controller robust --engine fast --duration 1``
under ``RC3R_COLD_START=compile`` (compile now, no fallback engine) on the ``src/`` of a tree; the trees
alternate, ``--repeat`` times each, so that both see the same machine load. Prints wall and user CPU per
run and the ratio of the medians (after / before)::

    git worktree add --detach /tmp/before <rev>
    python benchmarks/first_compile.py /tmp/before /path/to/repo --repeat 2
"""
from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RUN = ("import sys; from rc3r.cli import main; sys.exit(main(['run', '--robot', 'rr3', '--perturbed', "
       "'--controller', 'robust', '--engine', 'fast', '--duration', '1', '--out', sys.argv[1]]))")
PAPER = "import sys; from rc3r.cli import main; sys.exit(main(['paper', '--out', sys.argv[1]]))"
#: ``rc3r bench``'s compile script (each tree's own): a robust continuous then an fbl sampled run in one
#: process, no plan (the library default: compile once per process, docs/performance.md "Compile instances").
STARTUP = "from rc3r.experiments.bench_startup import _COMPILE_SCRIPT as s; exec(s)"
COMMANDS = {"run": RUN, "paper": PAPER, "startup": STARTUP}


def once(tree: Path, command: str = "run") -> tuple[float, float]:
    """(wall s, user CPU s) of one cold first run on ``tree``'s sources."""
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, PYTHONPATH=str(tree / "src"), NUMBA_CACHE_DIR=f"{tmp}/nc",
                   RC3R_CACHE_DIR=f"{tmp}/rc", RC3R_COLD_START="compile")
        before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
        t0 = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", COMMANDS[command], f"{tmp}/out"], env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if done.returncode != 0:
            raise SystemExit(f"first_compile: the run on {tree} failed: {done.stderr.strip().splitlines()[-1:]}")
        if command == "startup":  # its stages, as rc3r bench's compile row prints them
            print(f"       {done.stdout.strip().splitlines()[-1]}", flush=True)
        return wall, resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("before", type=Path, help="the tree before the change (its src/ is imported)")
    ap.add_argument("after", type=Path, help="the tree after the change")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--command", choices=sorted(COMMANDS), default="run",
                    help="run: one continuous robust run of the 3R (default); paper: rc3r paper; "
                         "startup: rc3r bench's compile script (robust continuous, then fbl sampled)")
    args = ap.parse_args(argv)
    got: dict = {"before": [], "after": []}
    for _ in range(args.repeat):
        for label in ("before", "after"):
            wall, cpu = once(getattr(args, label).resolve(), args.command)
            got[label].append((wall, cpu))
            print(f"{label:6s} wall {wall:6.1f} s  user CPU {cpu:6.1f} s", flush=True)
    load = os.getloadavg()[0]
    med = {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in got.items()}
    print(f"median wall {med['before'][0]:.1f} -> {med['after'][0]:.1f} s ({med['after'][0] / med['before'][0]:.2f}x), "
          f"user CPU {med['before'][1]:.1f} -> {med['after'][1]:.1f} s ({med['after'][1] / med['before'][1]:.2f}x); "
          f"load average {load:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
