"""The measurements of docs/export.md: ``rc3r export`` then ``make -C DIR check`` for six 1 kHz designs.

``python benchmarks/export_check.py [--out DIR]`` writes the designs of ``tests/test_export.py``
(the UR5 carrying an unknown payload of 0..3 kg with inertia-scaled gains, FBL with a delay of one
sample, robust, adaptive; the 3R perturbed with eps = 50, robust, robust-coeff with two calls per
period, PD) as TOML files, runs the two commands for each in subprocesses, exactly as a user
would, and prints one Markdown row per design: calls, max|u|, max_abs_diff, max_rel_diff and
ns_per_call as ``make check`` printed them. ``ns_per_call`` is CPU time per call of
``rc3r_control`` compiled with ``cc -O2 -std=c99`` (the Makefile's flags); for scale the script
ends with the time of one ``pin.rnea`` call on the UR5 from Python, measured in the same run.
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import rc3r
from rc3r.controllers import inertia_scaled_gain

CASES = [("ur5", "fbl", ["--delay", "1"]), ("ur5", "robust", []), ("ur5", "adaptive", []),
         ("rr3", "robust", []), ("rr3", "robust-coeff", ["--calls-per-sample", "2"]), ("rr3", "pd", [])]


def configs() -> dict[str, str]:
    """TOML text of each arm's design (the same as tests/test_export.py's)."""
    ur5 = rc3r.load_robot("ur5")
    k = [round(float(x), 4) for x in inertia_scaled_gain(ur5, ur5.default_trajectory().evaluate(0.0)[0], 50.0)]
    sim = '[simulation]\nrate = 1000.0\nengine = "python"\n'
    return {
        "ur5": (f'robot = "ur5"\n[payload]\nmass = [0.0, 3.0]\n[gains.robust]\nK = {json.dumps(k)}\nLambda = 20.0\n'
                f'eps = 5.0\n[gains.adaptive]\nK = {json.dumps(k)}\nLambda = 20.0\nGamma = 1.0\n' + sim),
        "rr3": 'perturbed = true\n[gains.robust]\neps = 50.0\n[gains.robust-coeff]\neps_i = 50.0\n' + sim,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="where the exports go (default: a temporary directory)")
    args = ap.parse_args(argv)
    base = Path(args.out or tempfile.mkdtemp(prefix="rc3r-export-"))
    base.mkdir(parents=True, exist_ok=True)
    rc3r_exe = Path(sys.executable).with_name("rc3r")
    for robot, text in configs().items():
        (base / f"{robot}.toml").write_text(text)
    print("| arm | law | options | calls | max\\|u\\| [N m] | max_abs_diff [N m] | max_rel_diff | ns_per_call |")
    print("|---|---|---|---|---|---|---|---|")
    failed = 0
    for robot, law, extra in CASES:
        out = base / f"{robot}-{law}"
        subprocess.run([str(rc3r_exe), "export", "--config", str(base / f"{robot}.toml"), "--controller", law,
                        "--out", str(out), "--force", *extra], check=True, stdout=subprocess.DEVNULL)
        proc = subprocess.run(["make", "-s", "-C", str(out), "check"], capture_output=True, text=True)
        failed += proc.returncode != 0
        v = dict(re.findall(r"^(\w+) = (\S+)", proc.stdout, flags=re.M))
        print(f"| {robot} | {law} | {' '.join(extra) or '-'} | {v.get('calls')} | {v.get('max_abs_u')} | "
              f"{v.get('max_abs_diff')} | {v.get('max_rel_diff')} | {v.get('ns_per_call')} |")
    print(f"\nfor scale, in the same run: pin.rnea on the UR5 through Python {rnea_us():.2f} us per call (best of 5 x 20000)")
    return 1 if failed else 0


def rnea_us() -> float:
    """Best of five loops of 20000 ``pin.rnea`` calls on the UR5 from Python [us per call]."""
    import time

    import numpy as np
    import pinocchio as pin

    model = rc3r.load_robot("ur5").model
    data = model.createData()
    q = np.full(model.nv, 0.3)
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(20000):
            pin.rnea(model, data, q, q, q)
        best = min(best, (time.perf_counter() - t0) / 20000 * 1e6)
    return best


if __name__ == "__main__":
    sys.exit(main())
