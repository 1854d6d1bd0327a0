"""Compare two ``rc3r paper`` summaries: ``python benchmarks/compare_summary.py OLD NEW``.

OLD and NEW are ``summary.json`` files written by ``rc3r paper`` (or a baseline with
``{"scenarios": {name: {metric: [...]}}}``). Every number of ``max_abs_error``,
``rms_error``, ``max_abs_torque`` of every scenario must satisfy
``|new - old| <= rtol |old| + atol`` (defaults 5 % and 1e-7, the refactoring rule);
prints the largest relative change per scenario and exits 1 on a violation.
"""
from __future__ import annotations

import argparse
import json
import sys

METRICS = ("max_abs_error", "rms_error", "max_abs_torque")


def _by_name(doc: dict) -> dict:
    sc = doc["scenarios"]
    if isinstance(sc, dict):
        return sc
    out = {}
    for row in sc:
        key = row["name"] if row.get("rate_hz") is None else f"{row['name']}@{row['rate_hz']:g}Hz"
        out[key] = row
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rtol", type=float, default=0.05)
    ap.add_argument("--atol", type=float, default=1e-7)
    a = ap.parse_args(argv)
    old = _by_name(json.load(open(a.old)))
    new = _by_name(json.load(open(a.new)))
    bad = 0
    for name, o in old.items():
        if name not in new:
            print(f"{name:40s} MISSING in new")
            bad += 1
            continue
        worst = 0.0
        for m in METRICS:
            for x, y in zip(o[m], new[name][m]):
                worst = max(worst, abs(y - x) / max(abs(x), 1e-300))
                if abs(y - x) > a.rtol * abs(x) + a.atol:
                    print(f"{name:40s} {m}: old {x:.6g} new {y:.6g}")
                    bad += 1
        print(f"{name:40s} largest relative change {worst:.2e}")
    print("OK: every number within tolerance" if not bad else f"FAIL: {bad} numbers out of tolerance")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
