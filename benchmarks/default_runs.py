"""The default robust run on every fixed-base arm of example-robot-data: the issue's "defaults that work".

For each arm, payload range and rate it runs, as a new user would (no gain given, so the gains are
the sampled-data rule's fast form, docs/design.md "Defaults for runs without gains")::

    rc3r run --urdf ARM.urdf [--lock J=V ...] --payload LO:HI --controller robust --rate RATE --perturbed

(10 s, the plant carrying the heaviest payload) and prints one line per run: the verdict and the
worst max|e| over the joints, or the error line of a diverged run. Exit 1 if any run diverged.

    python benchmarks/default_runs.py [--payloads 0:3,0:5] [--rates 500,1000] [--arms ur3,ur5,...]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from design_table import ARMS, ROBOTS  # noqa: E402  (the same arms, URDFs and locked joints)

#: The arms run by default: every fixed-base arm of the table but the SO-101, and the double pendulum.
DEFAULT_ARMS = "ur3,ur5,ur10,panda,z1,kinova,xarm7,double_pendulum"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--payloads", default="0:3,0:5", help="comma-separated LO:HI payload ranges [kg]")
    p.add_argument("--rates", default="500,1000", help="comma-separated controller rates [Hz]")
    p.add_argument("--arms", default=DEFAULT_ARMS, help=f"comma-separated arms of {', '.join(ARMS)}")
    args = p.parse_args(argv)
    rc3r = str(Path(sys.executable).parent / "rc3r")
    bad = 0
    print(f"{'arm':16s} {'payload':8s} {'rate':>6s}  verdict / error")
    with tempfile.TemporaryDirectory() as tmp:
        for arm in args.arms.split(","):
            urdf, lock = ARMS[arm]
            opts = ["--urdf", str(ROBOTS / urdf)] + sum((["--lock", f"{j}={v:g}"] for j, v in lock.items()), [])
            for payload in args.payloads.split(","):
                for rate in args.rates.split(","):
                    out = Path(tmp) / f"{arm}-{payload.replace(':', '-')}-{rate}"
                    cmd = [rc3r, "run", *opts, "--payload", payload, "--controller", "robust", "--rate", rate,
                           "--perturbed", "--out", str(out)]
                    proc = subprocess.run(cmd, capture_output=True, text=True)
                    metrics = out / "metrics.json"
                    if proc.returncode == 0 and metrics.exists():
                        m = json.loads(metrics.read_text())
                        text = f"{m['verdict']}, worst max|e| {max(m['max_abs_error']):.3g} rad"
                    else:
                        bad += 1
                        lines = [ln for ln in proc.stderr.splitlines() if ln.startswith("rc3r: error:")]
                        text = (lines[-1] if lines else proc.stderr.strip()[-200:])[:140]
                    print(f"{arm:16s} {payload:8s} {rate:>6s}  {text}", flush=True)
    print(f"{bad} of the runs diverged or failed" if bad else "every run ended without an error")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
