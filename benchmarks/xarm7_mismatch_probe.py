#!/usr/bin/env python
"""Where the default robust law fails on the xArm7: plants of the payload interval vs the model's own.

The xArm7 (example-robot-data) with a 0-3 kg payload, the robust law (eq. 6) and FBL with the gains and eps
of the sampled-data rule's fast form (no user gains: ``rc3r.build_run``'s default for a sampled run),
3 s at 500 Hz and 1 kHz, on the plants ``lower`` (0 kg), ``mass:0.75``, ``mass:1.5`` (the model's
theta_0: the interval's centre) and ``upper`` (3 kg). Prints one line per run: rate, plant, status,
message, max|e| [rad] (clean runs), eps. docs/design.md quotes its output (issue: rc3r design).

Usage: ``python benchmarks/xarm7_mismatch_probe.py [--duration 3]``
"""
from __future__ import annotations

import argparse
import os

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--controllers", default="robust,fbl")
    args = ap.parse_args(argv)
    os.environ.setdefault("RC3R_COLD_START", "compile")
    import rc3r
    from rc3r.robots.pinocchio import example_robot_data_dir

    urdf = str(example_robot_data_dir() / "xarm_description/urdf/xarm7.urdf")
    for ctl in args.controllers.split(","):
        for rate in (1000.0, 500.0):
            for plant in ("lower", "mass:0.75", "mass:1.5", "upper"):
                spec = rc3r.build_run(urdf=urdf, controller=ctl, rate=rate, duration=args.duration,
                                      payload=(0.0, 3.0), plant=plant)
                res = rc3r.simulate(spec.true_plant or spec.true_rigid, spec.law, spec.trajectory, spec.options)
                err = f"{float(np.abs(res.e).max()):.3g}" if res.ok else "-"
                eps = getattr(spec.law, "eps", None)
                print(f"{ctl:6s} {rate:g} Hz  {plant:10s} {res.verdict:14s} max|e| {err:>9s} rad  "
                      f"eps {'-' if eps is None else f'{eps:.4g}'}  {res.message}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
