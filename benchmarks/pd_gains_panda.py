"""Why PD+'s fixed default gains diverge on the Panda when sampled, and what the defaults of a sampled run are.

For ``pd`` and ``pd-plus`` at each rate: the held loop's figure ``T lambda_max(M^-1 Kd)`` of the law's
class defaults (Kp 500, Kd 100), the largest over the default reference (``rc3r.design.rule.spectrum`` of the
arm: M along the trajectory, every 0.025 s), which a zero-order hold keeps stable only below 2 (and free of
oscillation below 1: ``rc3r.design.rule.real_limit``); then the gains ``rc3r.build_run`` gives a sampled run
with no gains (the class defaults, or the sampled-data rule's), their figure, and the verdict of that run
(python engine, ``--duration`` s)::

    python benchmarks/pd_gains_panda.py --robot panda --rates 500 1000 --duration 1
"""
from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np


def main(argv=None) -> int:
    import rc3r
    from rc3r.controllers import default_gains
    from rc3r.design.rule import spectrum

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", default="panda")
    ap.add_argument("--rates", type=float, nargs="+", default=[500.0, 1000.0])
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--laws", nargs="+", default=["pd", "pd-plus"])
    args = ap.parse_args(argv)
    first = rc3r.build_run(robot=args.robot, controller="pd", duration=args.duration)
    sp = spectrum(first.controller_model, first.trajectory, 10.0)
    print(f"{args.robot}: max_t lambda_max(M^-1) = {sp.lam(np.ones(first.true_rigid.n)):.4g} 1/kg m^2 "
          f"(M along the default reference, 10 s)")
    print(f"{'law':8s} {'rate':>6s}  {'T lam(M^-1 Kd) defaults':>24s}  {'gains of a sampled run':34s} "
          f"{'T lam':>7s}  verdict")
    for law in args.laws:
        kd0 = np.full(first.true_rigid.n, float(default_gains(law)["Kd"]))
        for rate in args.rates:
            spec = rc3r.build_run(robot=args.robot, controller=law, rate=rate, duration=args.duration)
            kd = np.broadcast_to(np.asarray(spec.law.Kd, dtype=float), (spec.true_rigid.n,))
            source = spec.model.get("gains_source", "class defaults")
            res = rc3r.simulate(spec.true_plant, spec.law, spec.trajectory,
                                replace(spec.options, engine="python"),
                                loop=spec.loop, model=spec.controller_model)
            kd_txt = f"Kd {kd.min():.3g}..{kd.max():.3g}"
            print(f"{law:8s} {rate:6g}  {sp.lam(kd0) / rate:24.3g}  {kd_txt:34s} {sp.lam(kd) / rate:7.3g}  "
                  f"{res.verdict} ({res.outcome}, t_end {res.t_end:.3g} s)  [{source.split(' (')[0]}]")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
