"""Why a resting arm's held-out torque carries a static error: ``python benchmarks/identify_slow_rows.py [--seed S]``.

The geared UR5 stand-in of ``benchmarks/identify_arms.py`` (24 s of motion, 6 s at rest, 2 kHz, no logged
velocities; the last 30 % held out) identified at given settings (differentiated velocities, ``v_s`` 0.003 rad/s,
no rotor inertias) at 2 and 15 Hz, every row (``--slow-share 0``) and without each joint's rows slower than 0.1
x its RMS speed (``--slow-share 0.1``, :func:`rc3r.identify.estimate.slow_rows`). Printed per joint: the held-out
RMS [N m], the mean residual over the rest (after its first 0.5 s) [N m] (a static error: the gravity and offset
terms at the resting posture), and the identified offsets against the log's true sensor offsets.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def main(argv=None) -> int:
    import identify_arms as ia
    from threadpoolctl import threadpool_limits

    from rc3r.identify.pipeline import identify

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0, help="seed of the stand-in's trajectory and log (default 0)")
    args = ap.parse_args(argv)
    spec = ia.ARMS["ur5-geared"]
    robot, _, log = ia.make_log("ur5-geared", spec, args.seed)
    t_rest = log.t[-1] - spec["rest"]
    print(f"ur5-geared stand-in, seed {args.seed}; true offsets {' '.join(f'{x:g}' for x in spec['offset'])} N m")
    for fc in (2.0, 15.0):
        for share in (0.0, 0.1):
            with threadpool_limits(limits=1, user_api="blas"):
                res = identify(robot, log, cutoff_hz=fc, velocities="differentiated", weighting="per-joint",
                               coulomb_velocity=0.003, armature="off", test_fraction=0.3, physical=False,
                               consistency=False, slow_share=share)
            t = res.held_out["t"]
            r = res.held_out["tau"] - res.held_out["pred"]
            rest = t > t_rest + 0.5
            print(f"{fc:g} Hz, slow share {share:g} (rows kept {' '.join(f'{k:.2f}' for k in res.filter['rows_kept'])})")
            print("  held-out RMS  " + " ".join(f"{x:7.3f}" for x in res.validation["rms"]))
            print("  rest mean     " + " ".join(f"{x:7.3f}" for x in r[rest].mean(axis=0)))
            print("  offsets       " + " ".join(f"{x:7.3f}" for x in res.friction()["offset"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
