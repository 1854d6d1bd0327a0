"""Print the tables of docs/robustness.md from campaign directories.

Usage::

    python benchmarks/robustness_tables.py out/sweep-rate out/montecarlo out/montecarlo-1khz

Any argument may be a ``rc3r sweep rate`` directory (stability.json) or a
``rc3r montecarlo`` directory (summary.json); each gets its table, and the sweep its
chattering-ratio gap and late divergences.
"""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np

from rc3r.campaign import CHATTER_RATIO, read_rows


def _g(x):
    return "-" if x is None else f"{x:.3g}"


def sweep_rate(d: Path) -> None:
    st = json.loads((d / "stability.json").read_text())
    rows = read_rows(d / "runs.csv")
    print(f"### {d}: lowest clean rate (every tested rate above it clean too)\n")
    maps = st["maps"]
    keys = list(maps)
    print("| eps | " + " | ".join(f"K = {k}" for k in keys) + " | final error at that rate, K = " + keys[-1] + " |")
    print("|---|" + "---|" * len(keys) + "---|")
    last = maps[keys[-1]]
    for e in last["eps"]:
        cells = []
        for k in keys:
            s = maps[k]["safe_rate"].get(str(e))
            cells.append("never (up to 100 kHz)" if s is None else f"{s / 1000:g} kHz")
        s = last["safe_rate"].get(str(e))
        tag = "" if keys[-1] == "default" else f"/K={float(keys[-1])!r}"
        job = f"nominal/robust/eps={float(e)!r}/rate={s!r}{tag}" if s is not None else None
        fe = next((r["final_error"] for r in rows if r["job"] == job), None)
        print(f"| {e:g} | " + " | ".join(cells) + f" | {_g(fe)} rad |")
    by = {r["job"]: r for r in rows}
    ratios = sorted(r["chattering"] / by[re.sub(r"/rate=[^/]+", "/continuous", j)]["chattering"]
                    for j, r in by.items() if "/rate=" in j and r["status"] == "ok")
    below = [x for x in ratios if x <= CHATTER_RATIO]
    above = [x for x in ratios if x > CHATTER_RATIO]
    print(f"\nchattering ratio (sampled / continuous total variation) over {len(ratios)} finished sampled runs: "
          f"largest below the threshold {max(below, default=float('nan')):.3g}, smallest above "
          f"{min(above, default=float('nan')):.3g}")
    div = [r for r in rows if r["status"] != "ok"]
    late = [r for r in div if r["t_end"] > 1.0]
    print(f"{len(div)} diverged runs, {len(late)} of them after t = 1 s, the latest at t = "
          f"{max((r['t_end'] for r in div), default=float('nan')):.4g} s\n")


def montecarlo(d: Path) -> None:
    s = json.loads((d / "summary.json").read_text())
    req = s["request"]
    print(f"### {d}: n = {req['n']}, seed {req['seed']}, rate {req['rate'] or 'continuous'}, "
          f"eps {req['eps'] or 'default'}\n")
    print("| controller | runs | diverged | median max|e| | p95 | worst | inside ball | bound exceeded | "
          "median predicted bound | median chattering |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for c, x in s["summary"].items():
        exc = "-" if x["bound_exceeded"] is None else f"{x['bound_exceeded']} of {x['bound_checked']}"
        print(f"| {c} | {x['runs']} | {x['diverged']} | {_g(x['max_error_median'])} | {_g(x['max_error_p95'])} | "
              f"{_g(x['max_error_max'])} | {'-' if x['inside_ball'] is None else x['inside_ball']} | {exc} | "
              f"{_g(x['predicted_bound_median'])} | {_g(x['chattering_median'])} |")
    r = s["radii"]
    rows = [x for x in read_rows(d / "runs.csv") if x["predicted_bound"] is not None]
    dist = [x["theta_dist"] for x in read_rows(d / "runs.csv")]
    print(f"\nrho = {r['rho']:.6g} ({r['rho_source']}); certified rho_max = {r['rho_max']:.6g}; "
          f"||theta - theta_0|| from {min(dist):.4g} to {max(dist):.4g}")
    if rows:
        ratio = np.array([x["max_error"] / x["predicted_bound"] for x in rows])
        print(f"max error / predicted bound: largest {ratio.max():.3g}, median {np.median(ratio):.3g}")
    print()


def main(argv) -> int:
    for a in argv:
        d = Path(a)
        if (d / "stability.json").exists():
            sweep_rate(d)
        elif (d / "summary.json").exists():
            montecarlo(d)
        else:
            print(f"{d}: neither a sweep-rate nor a montecarlo directory", file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
