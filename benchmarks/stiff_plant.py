"""How a sampled run advances a stiff plant: RK4 sub-steps against adaptive ROS4 per period, side by side.

For each arm (example-robot-data URDF, its ``<dynamics damping friction>`` as the plant's friction, its
effort limits as saturation, a 0-3 kg payload, the robust law on its default gains) and rate, one
sampled run per ``SimOptions.sampled_method`` on the compiled engine, and the python engine at
reference tolerances (DOP853 per period, rtol 1e-11) unless ``--no-reference``. Prints, per run,
right-hand sides, wall time, max|e| and the largest difference of q from the reference run, and what
``sampled_method = "auto"`` picks (:func:`rc3r.simulate.plant_method`)::

    python benchmarks/stiff_plant.py --arms xarm7,z1 --rates 500,1000 --duration 0.3 [--rtol 1e-4 --atol 1e-6]

The robust law's boundary layer is a high-gain loop, so two accurate integrations of the plant part by
up to 1e-4 rad over a fraction of a second (it amplifies any last-digit difference): read the q
difference against the run's own max|e|, not against the tolerances.
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import design_table as D  # noqa: E402  (the arms and their locked joints)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--arms", default="xarm7,z1")
    p.add_argument("--rates", default="500,1000")
    p.add_argument("--duration", type=float, default=0.3)
    p.add_argument("--no-reference", action="store_true")
    p.add_argument("--rtol", type=float, default=None, help="the ROS4 periods' rtol (default: SimOptions')")
    p.add_argument("--atol", type=float, default=None, help="the ROS4 periods' atol (default: SimOptions')")
    args = p.parse_args(argv)
    import rc3r
    from rc3r.simulate import plant_method, simulate, stiffness

    print(f"# stiff plants, {time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime())} UTC, duration {args.duration:g} s, "
          f"ROS4 rtol {args.rtol or 'default'}, atol {args.atol or 'default'}")
    print("| arm | rate [Hz] | lambda [1/s] | auto | method | RK4 nsub | rhs | wall [s] | max\\|e\\| [rad] "
          "| max\\|q - q_ref\\| [rad] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for arm in args.arms.split(","):
        urdf, lock = D.ARMS[arm]
        for rate in (float(r) for r in args.rates.split(",")):
            spec = rc3r.build_run(urdf=str(D.ROBOTS / urdf), lock=lock or None, controller="robust",
                                  payload=(0.0, 3.0), rate=rate, duration=args.duration, friction="urdf",
                                  torque_limit="urdf", perturbed=True)
            plant, o = spec.true_plant, spec.options
            auto = plant_method(plant, o)
            lam = f"{stiffness(plant):.3g}"
            tol = {k: v for k, v in (("rtol", args.rtol), ("atol", args.atol)) if v is not None}
            runs = [(m, simulate(plant, spec.law, spec.trajectory,
                                 replace(o, sampled_method=m, engine="fast",
                                         **({f"period_{k}": v for k, v in tol.items()} if m == "ros4" else {}))))
                    for m in ("rk4", "ros4")]
            ref = None if args.no_reference else simulate(plant, spec.law, spec.trajectory,
                                                          replace(o, engine="reference"))
            if ref is not None:
                runs.append(("reference", ref))
            for m, r in runs:
                diff = "" if ref is None or r is ref or len(r.q) != len(ref.q) else f"{np.abs(r.q - ref.q).max():.3g}"
                print(f"| {arm} | {rate:g} | {lam} | {auto} | {m} ({r.verdict}) | {r.options.nsub} | {r.rhs_evals} "
                      f"| {r.wall_time_s:.3f} | {np.abs(r.e).max():.4g} | {diff} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
