"""``rc3r design`` on the arms with URDF friction, before (ROS4 periods) and after (SDIRK3 periods), side by side.

Issue 37's acceptance command, per arm, once per period method in one run (the method set by a config's
``[simulation] sampled_method``, everything else the command's)::

    rc3r design --urdf ARM.urdf [--lock J=V] --payload 0:3 --rate 1000 --friction urdf --torque-limit urdf \\
        --n N --duration D --seed 0 --workers W --out OUT/ARM-METHOD --config OUT/METHOD.toml

    python benchmarks/friction_design.py --arms xarm7,z1 --n 4 --duration 2 --workers 2 --out /tmp/fd
    python benchmarks/friction_design.py --n 50 --duration 10 --workers 2 --out FD50   # the issue's size

Prints one row per arm and method: wall time, the CPU time the design used (its process and its workers,
from ``resource.getrusage``: on a shared machine the wall time grows with the load, the CPU time hardly;
on an idle one wall ~ CPU / workers plus start-up), the wall's ratio to the first method's, the design's verdict
(``ok``, the recommended law and its worst error, the layer eps), and the largest difference of any worst
error in ``design.json`` from the first method's (every ``worst_error`` leaf, paired by path; in brackets
those of the comparison laws under ``baselines``, FBL and the adaptive law) and whether every
verdict count, ``ok`` and recommendation are identical. Run the methods' commands one after the other
(never concurrently), so the two share the machine's load.
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import resource
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


def _config(method: str) -> str:
    """The ``[simulation]`` config of a ``--methods`` entry ``NAME`` or ``NAME@RTOL/ATOL``; below rtol 1e-6 (a
    reference design) ``max_steps`` 1e9 too, so that no period runs out of steps (the default budget stops
    the xArm7's first period at rtol 1e-8)."""
    name, _, tol = method.partition("@")
    text = f'[simulation]\nsampled_method = "{name}"\n'
    if tol:
        rtol, atol = (float(x) for x in tol.split("/"))
        text += f"period_rtol = {rtol!r}\nperiod_atol = {atol!r}\n" + ("max_steps = 1e9\n" if rtol < 1e-6 else "")
    return text


def run_errors(where: Path) -> dict:
    """``{(job, plant): (max_error [rad], verdict, t_end [s])}`` of a design's ``runs.csv``."""
    with open(where / "runs.csv", newline="") as f:
        return {(r["job"], r["plant"]): (float(r["max_error"]), r["verdict"], r["t_end"]) for r in csv.DictReader(f)}


def compare_runs(a: dict, b: dict) -> tuple[float, float, int]:
    """Largest |difference| of the runs' ``max_error`` [rad] between two designs' :func:`run_errors`, over the
    runs clean in both and over the others (limit-violated, saturated, ...), and how many verdicts differ
    (runs that end at different times are counted there, their errors not compared)."""
    clean, other, nv = 0.0, 0.0, 0
    for k, (ea, va, ta) in a.items():
        if k not in b:
            continue
        eb, vb, tb = b[k]
        nv += va != vb or ta != tb
        if ta != tb:
            continue
        if va == vb == "clean":
            clean = max(clean, abs(ea - eb))
        else:
            other = max(other, abs(ea - eb))
    return clean, other, nv


def timed_run(cmd: list) -> tuple[float, float, subprocess.CompletedProcess]:
    """Run ``cmd`` to its end; its wall time [s], the CPU time [s] it used (user + system of the process and
    of every descendant it waited for, e.g. a design's worker processes: the growth of
    ``resource.getrusage(RUSAGE_CHILDREN)`` of this process across the run) and the finished process. On a
    machine the run has to itself, wall ~ CPU / workers plus the serial start-up; on a shared one wall grows
    with the load and CPU does not (much)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), proc


def _read_times(where: Path) -> tuple[float, float]:
    """Wall and CPU time [s] of a design kept under ``where`` (``--reuse``); CPU NaN if not recorded."""
    wall = float((where / "bench_wall.txt").read_text())
    cpu = where / "bench_cpu.txt"
    return wall, float(cpu.read_text()) if cpu.exists() else float("nan")


def _cpu(cpu: float) -> str:
    return "-" if cpu != cpu else f"{cpu:.1f}"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--arms", default="xarm7,z1")
    p.add_argument("--rate", type=float, default=1000.0)
    p.add_argument("--n", type=int, default=4)
    p.add_argument("--duration", type=float, default=2.0)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--methods", default="ros4,sdirk",
                   help="sampled methods, each NAME or NAME@RTOL/ATOL (the period tolerances); the first is the baseline")
    p.add_argument("--ref", default=None, help="also compare every method's runs with this one's (a --methods entry, "
                                               "e.g. a tight-tolerance design), printed after each arm")
    p.add_argument("--out", required=True)
    p.add_argument("--reuse", action="store_true",
                   help="a method whose design (and its bench_wall.txt) is already under --out is read, not rerun")
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    methods = args.methods.split(",")
    print(f"# friction designs, {time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime())} UTC, rate {args.rate:g} Hz, "
          f"n {args.n}, duration {args.duration:g} s, workers {args.workers}, load {os.getloadavg()[0]:.2f}")
    print("| arm | sampled method | wall [s] | CPU [s] | wall ratio | design ok, law, eps | max\\|d worst error\\| [rad] "
          "(baselines) "
          "| verdicts identical | load at end |")
    print("|---|---|---|---|---|---|---|---|---|")
    for arm in args.arms.split(","):
        urdf, lock = D.ARMS[arm]
        first, done = None, {}
        for m in methods:
            cfg = out / f"{m.replace('/', '_')}.toml"
            cfg.write_text(_config(m))
            where = out / f"{arm}-{m.replace('/', '_')}"
            cmd = D._rc3r() + ["design", "--urdf", str(D.ROBOTS / urdf)] + \
                sum((["--lock", f"{j}={v:g}"] for j, v in lock.items()), []) + \
                ["--payload", "0:3", "--rate", f"{args.rate:g}", "--friction", "urdf", "--torque-limit", "urdf",
                 "--n", str(args.n), "--duration", f"{args.duration:g}", "--seed", str(args.seed),
                 "--workers", str(args.workers), "--config", str(cfg), "--out", str(where), "--force"]
            path = where / "design.json"
            if args.reuse and path.exists() and (where / "bench_wall.txt").exists():
                wall, cpu = _read_times(where)
            else:
                wall, cpu, proc = timed_run(cmd)
                (out / f"{arm}-{m.replace('/', '_')}.log").write_text(" ".join(cmd) + "\n" + proc.stdout + proc.stderr)
                if path.exists():
                    (where / "bench_wall.txt").write_text(f"{wall!r}\n")
                    (where / "bench_cpu.txt").write_text(f"{cpu!r}\n")
            if not path.exists():
                print(f"| {arm} | {m} | {wall:.1f} | {cpu:.1f} | | failed (exit {proc.returncode}, {where}.log) | | | |")
                continue
            info = json.loads(path.read_text())
            done[m] = where
            rec = info.get("recommendation") or {}
            we, eps = rec.get("worst_error"), info.get("eps")
            head = (f"{info.get('ok')}, {rec.get('law')} {'-' if we is None else f'{we:.6g}'} rad, "
                    f"eps {'-' if eps is None else f'{eps:.4g}'}")
            if first is None:
                first = (wall, info)
                print(f"| {arm} | {m} | {wall:.1f} | {_cpu(cpu)} | 1 | {head} | (baseline) | | {os.getloadavg()[0]:.2f} |",
                      flush=True)
                continue
            worst, base, same, diffs = compare(first[1], info)
            print(f"| {arm} | {m} | {wall:.1f} | {_cpu(cpu)} | {wall / first[0]:.3g} | {head} | {worst:.3g} ({base:.3g}) | "
                  f"{'yes' if same else 'NO: ' + str(diffs[:3])} | {os.getloadavg()[0]:.2f} |", flush=True)
        if args.ref in done:
            print(f"# {arm}: worst errors against {args.ref}: " + ", ".join(
                f"{m} {compare(json.loads((done[args.ref] / 'design.json').read_text()), json.loads((w / 'design.json').read_text()))[0]:.3g}"
                for m, w in done.items() if m != args.ref))
            ref = run_errors(done[args.ref])
            for m, where in done.items():
                if m != args.ref:
                    c, o, nv = compare_runs(ref, run_errors(where))
                    print(f"# {arm}: {m} against {args.ref}, per run max|d max_error|: clean runs {c:.3g} rad, "
                          f"other runs {o:.3g} rad; verdicts differing {nv}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
