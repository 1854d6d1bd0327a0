"""``rc3r design`` on the arms with URDF friction, before (ROS4 periods) and after (RODAS periods), side by side.

Issue 37's acceptance command, per arm, once per period method in one run (the method set by a config's
``[simulation] sampled_method``, everything else the command's)::

    rc3r design --urdf ARM.urdf [--lock J=V] --payload 0:3 --rate 1000 --friction urdf --torque-limit urdf \\
        --n N --duration D --seed 0 --workers W --out OUT/ARM-METHOD --config OUT/METHOD.toml

    python benchmarks/friction_design.py --arms xarm7,z1 --n 4 --duration 2 --workers 2 --out /tmp/fd
    python benchmarks/friction_design.py --n 50 --duration 10 --workers 2 --out FD50   # the issue's size

Prints one row per arm and method: wall time, its ratio to the first method's, the design's verdict
(``ok``, the recommended law and its worst error, the layer eps), and the largest difference of any worst
error in ``design.json`` from the first method's (every ``worst_error`` leaf, paired by path; in brackets
those of the comparison laws under ``baselines``, FBL and the adaptive law) and whether every
verdict count, ``ok`` and recommendation are identical. Run the methods' commands one after the other
(never concurrently), so the two share the machine's load.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import design_table as D  # noqa: E402

_SAME = ("ok", "recommendation", "verdict", "verdicts", "eps", "status", "lowest_clean_rate")


def _leaves(x, path=()):
    """(path, value) of every leaf of a JSON value."""
    if isinstance(x, dict):
        for k, v in x.items():
            yield from _leaves(v, path + (str(k),))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from _leaves(v, path + (str(i),))
    else:
        yield path, x


def compare(a: dict, b: dict) -> tuple[float, float, bool, list]:
    """Largest |difference| of the ``worst_error`` leaves of two design.json, outside and inside
    ``baselines`` (the comparison laws: FBL, the adaptive law), whether every verdict-like leaf
    (:data:`_SAME` keys, anywhere) is equal, and the differing ones."""
    la, lb = dict(_leaves(a)), dict(_leaves(b))
    worst, base, same, diffs = 0.0, 0.0, True, []
    for p, v in la.items():
        if p not in lb:
            continue
        w = lb[p]
        if any("worst_error" in k for k in p) and isinstance(v, (int, float)) and isinstance(w, (int, float)):
            if p[0] == "baselines":
                base = max(base, abs(float(v) - float(w)))
            else:
                worst = max(worst, abs(float(v) - float(w)))
        elif any(k in _SAME for k in p) and v != w and "wall" not in "/".join(p):
            same = False
            diffs.append(("/".join(p), v, w))
    return worst, base, same, diffs


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--arms", default="xarm7,z1")
    p.add_argument("--rate", type=float, default=1000.0)
    p.add_argument("--n", type=int, default=4)
    p.add_argument("--duration", type=float, default=2.0)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--methods", default="ros4,sdirk", help="sampled methods; the first is the baseline")
    p.add_argument("--out", required=True)
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    methods = args.methods.split(",")
    print(f"# friction designs, {time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime())} UTC, rate {args.rate:g} Hz, "
          f"n {args.n}, duration {args.duration:g} s, workers {args.workers}, load {os.getloadavg()[0]:.2f}")
    print("| arm | sampled method | wall [s] | wall ratio | design ok, law, eps | max\\|d worst error\\| [rad] "
          "(baselines) "
          "| verdicts identical | load at end |")
    print("|---|---|---|---|---|---|---|---|")
    for arm in args.arms.split(","):
        urdf, lock = D.ARMS[arm]
        first = None
        for m in methods:
            cfg = out / f"{m}.toml"
            cfg.write_text(f'[simulation]\nsampled_method = "{m}"\n')
            where = out / f"{arm}-{m}"
            cmd = D._rc3r() + ["design", "--urdf", str(D.ROBOTS / urdf)] + \
                sum((["--lock", f"{j}={v:g}"] for j, v in lock.items()), []) + \
                ["--payload", "0:3", "--rate", f"{args.rate:g}", "--friction", "urdf", "--torque-limit", "urdf",
                 "--n", str(args.n), "--duration", f"{args.duration:g}", "--seed", str(args.seed),
                 "--workers", str(args.workers), "--config", str(cfg), "--out", str(where), "--force"]
            t0 = time.perf_counter()
            proc = subprocess.run(cmd, capture_output=True, text=True)
            wall = time.perf_counter() - t0
            (out / f"{arm}-{m}.log").write_text(" ".join(cmd) + "\n" + proc.stdout + proc.stderr)
            path = where / "design.json"
            if not path.exists():
                print(f"| {arm} | {m} | {wall:.1f} | | failed (exit {proc.returncode}, {out / f'{arm}-{m}.log'}) | | | |")
                continue
            info = json.loads(path.read_text())
            rec = info.get("recommendation") or {}
            we, eps = rec.get("worst_error"), info.get("eps")
            head = (f"{info.get('ok')}, {rec.get('law')} {'-' if we is None else f'{we:.6g}'} rad, "
                    f"eps {'-' if eps is None else f'{eps:.4g}'}")
            if first is None:
                first = (wall, info)
                print(f"| {arm} | {m} | {wall:.1f} | 1 | {head} | (baseline) | | {os.getloadavg()[0]:.2f} |",
                      flush=True)
                continue
            worst, base, same, diffs = compare(first[1], info)
            print(f"| {arm} | {m} | {wall:.1f} | {wall / first[0]:.3g} | {head} | {worst:.3g} ({base:.3g}) | "
                  f"{'yes' if same else 'NO: ' + str(diffs[:3])} | {os.getloadavg()[0]:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
