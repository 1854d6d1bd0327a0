"""Monte Carlo over the paper's box from Python: FBL and the robust law on N random plants.

The same campaign as ``rc3r montecarlo --n N``, through the library: jobs from
:func:`rc3r.campaign.montecarlo_jobs`, run on local worker processes by
:func:`rc3r.campaign.run_many` into a resumable CSV, summarized per controller, and the
figure of max error against ``||theta - theta_0||`` with the law's rho and the certified
rho_max marked. Every plant is seeded (plant k of seed S: ``random:<plant_seed(S, k)>``).

Run: ``python examples/montecarlo.py [N] [duration] [--out=DIR]`` (default 20 plants, 10 s,
``out/example-montecarlo``); run it again with the same arguments and it resumes.
"""
from __future__ import annotations

import sys
from pathlib import Path

from rc3r.campaign import (RunTable, columns, model_radii, montecarlo_jobs, montecarlo_summary, read_rows,
                           run_many)
from rc3r.campaign.figures import error_vs_distance
from rc3r.io import atomic_savefig


def main(n: int = 20, duration: float = 10.0, out: str = "out/example-montecarlo") -> dict:
    jobs = montecarlo_jobs(n, seed=0, controllers=["fbl", "robust"], duration=duration)
    d = Path(out)
    d.mkdir(parents=True, exist_ok=True)
    with RunTable(d / "runs.csv", columns(3)).open(resume=True) as table:
        new = run_many(jobs, table, workers=2)
    rows = read_rows(d / "runs.csv")
    summary = montecarlo_summary(rows)
    for law, s in summary.items():
        checked = "" if s["bound_checked"] is None else \
            f"; error above the predicted bound on {s['bound_exceeded']} of {s['bound_checked']} plants"
        print(f"{law:>6}: {s['runs']} runs ({new} new), {s['diverged']} diverged, median max|e| = "
              f"{s['max_error_median']:.3g} rad, worst {s['max_error_max']:.3g} rad{checked}")
    radii = model_radii(jobs[0])
    atomic_savefig(error_vs_distance(rows, radii, f"{n} plants of the paper's box"), d / "error_vs_distance.png")
    print(f"rho = {radii['rho']:.4g}, certified rho_max = {radii['rho_max']:.4g}; figure: {d}/error_vs_distance.png")
    return summary


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--out=")]
    outs = [a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--out=")]
    main(int(args[0]) if args else 20, float(args[1]) if len(args) > 1 else 10.0,
         outs[0] if outs else "out/example-montecarlo")
