"""Coverage of rc3r identify's confidence ellipsoid over seeded synthetic logs of the 3R (issue 35).

One motion of the paper's arm (10 s, random Fourier trajectory seed 2, friction 2 N m s/rad and 1 N m)
recorded with new sensor noise and time stamps per seed (rc3r.identify.synthetic defaults), identified
with rc3r's defaults (or ``--covariance white|robust``), 95 %. Prints the share of logs whose true theta
lies inside the reported ellipsoid and the mean of ``d^T Cov^-1 d / p`` (1 for a correct covariance), for
theta and for all unknowns (friction included), overall and by the cut-off and the slow share the
cross-validation chose (``--slow-share S`` gives it).
docs/identification.md, section 5, quotes a run of 100 logs::

    python benchmarks/identify_coverage.py --logs 100                       # in-band (default)
    python benchmarks/identify_coverage.py --logs 100 --covariance white    # before issue 35's fix

About 2 s per log on the development machine.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--logs", type=int, default=100, help="logs (seeds start .. start + logs - 1)")
    ap.add_argument("--start", type=int, default=0, help="first seed")
    ap.add_argument("--covariance", default="in-band", help="identify's covariance model")
    ap.add_argument("--confidence", type=float, default=0.95)
    ap.add_argument("--slow-share", default="auto",
                    help="identify's slow share (auto, the default: chosen by cross-validation; or a number)")
    args = ap.parse_args(argv)

    import rc3r
    from rc3r.identify.excitation import random_fourier
    from rc3r.identify.pipeline import identify
    from rc3r.identify.synthetic import sample_log, simulate_motion

    arm = rc3r.load_robot("rr3")
    motion = simulate_motion(arm, random_fourier(arm, 10.0, seed=2, fill=0.8), 10.0)
    rows = []
    for seed in range(args.start, args.start + args.logs):
        log, truth = sample_log(motion, seed=seed)
        res = identify(arm, log, confidence=args.confidence, consistency=False, physical=False,
                       covariance=args.covariance,
                       slow_share=None if args.slow_share == "auto" else float(args.slow_share))
        xt = np.concatenate([truth["theta"], truth["viscous"], truth["coulomb"], truth["offset"]])
        xt = np.concatenate([xt, np.zeros(res.x.size - xt.size)])  # fitted rotor inertias: the 3R has none
        d = res.x - xt
        m = float(d[:arm.p] @ np.linalg.solve(res.cov_theta, d[:arm.p]))
        rows.append((res.filter["cutoff_hz"], m <= res.ellipsoid["chi2"], m / arm.p,
                     float(d @ np.linalg.solve(res.cov, d)) / d.size, res.filter["slow_share"]))
        print(f"seed {seed}: cut-off {rows[-1][0]:g} Hz, slow share {rows[-1][4]:g}, d^T Cov^-1 d / p = "
              f"{rows[-1][2]:.3f}", file=sys.stderr)
    fc, inside, m2, m2x, share = (np.array(c) for c in zip(*rows))
    print(f"covariance {args.covariance}, {len(rows)} logs (seeds {args.start}-{args.start + len(rows) - 1}): "
          f"coverage of the {100 * args.confidence:g} % ellipsoid {100 * inside.mean():.1f} %, mean d^T Cov^-1 d / p "
          f"{m2.mean():.3f} (theta), {m2x.mean():.3f} (all unknowns, friction included)")
    for f in np.unique(fc):
        k = fc == f
        print(f"  cut-off {f:g} Hz: {k.sum()} logs, coverage {100 * inside[k].mean():.0f} %, mean {m2[k].mean():.2f}")
    for f in np.unique(share):
        k = share == f
        print(f"  slow share {f:g}: {k.sum()} logs, coverage {100 * inside[k].mean():.0f} %, mean {m2[k].mean():.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
