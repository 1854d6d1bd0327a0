"""What one sampling period of a stiff plant costs and how far it lands, per method, side by side.

``python benchmarks/period_methods.py --arms xarm7,z1 --rate 1000 --duration 0.5``

Runs the robust law on the arm (example-robot-data URDF, its friction and effort limits, a 0-3 kg payload,
the perturbed plant) with the default sampled method, then re-integrates every recorded period alone from
the run's state under its held torque, with each compiled period method, and with ROS4 at rtol 1e-10,
atol 1e-12 as the yardstick (``sdirk``: SDIRK3 periods with the knee's error control, the default; ``sdirk0``: the
same periods with the error control before it, :mod:`rc3r.simulate.engines._sdirk`). Prints per method: right-hand sides per period (mean, max), wall time per
period (all periods in one timed loop), and the largest distance of the period's end state from the
yardstick's (q [rad], qd [rad/s]). The yardstick is a local one (each period starts from the same state),
so the numbers are the methods' own errors, not the closed loop's amplification of them.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import design_table as D  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--arms", default="xarm7,z1")
    p.add_argument("--rate", type=float, default=1000.0)
    p.add_argument("--duration", type=float, default=0.5)
    p.add_argument("--closed-loop", action="store_true", help="also whole runs against ROS4 at rtol 1e-10")
    p.add_argument("--scale", type=float, default=1.0, help="multiply the URDF friction by this")
    p.add_argument("--coulomb", type=float, default=1.0, help="multiply the Coulomb term by this (0: viscous only)")
    args = p.parse_args(argv)
    import rc3r
    from rc3r.plants import Friction
    from rc3r.simulate import simulate
    from rc3r.simulate._fast import simulator

    print(f"# period methods, {time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime())} UTC, rate {args.rate:g} Hz, "
          f"duration {args.duration:g} s, friction x{args.scale:g}, Coulomb x{args.coulomb:g}")
    print("| arm | method | rhs/period mean | max | us/period | max\\|q - q_y\\| | max\\|qd - qd_y\\| |")
    print("|---|---|---|---|---|---|---|")
    for arm in args.arms.split(","):
        urdf, lock = D.ARMS[arm]
        spec = rc3r.build_run(urdf=str(D.ROBOTS / urdf), lock=lock or None, controller="robust", payload=(0.0, 3.0),
                              rate=args.rate, duration=args.duration, friction="urdf", torque_limit="urdf",
                              perturbed=True)
        P = spec.true_plant
        if args.scale != 1.0 or args.coulomb != 1.0:
            from rc3r.plants import Plant
            eff = tuple(Friction(e.viscous * args.scale, e.coulomb * args.scale * args.coulomb, e.offset, e.v_s)
                        if e.name == "friction" else e for e in P.effects)
            P = Plant(P.rigid, eff, label=P.label)
        res = simulate(P, spec.law, spec.trajectory, spec.options)
        eng = simulator(P.rigid)
        mod = eng.instance
        kc = eng.constants(P.rigid); fx = P.pack(); wk = mod._make_work(kc); n = P.n; n2 = 2 * n
        fric = mod._friction(fx, n)
        cp, tp, code = spec.law.pack(n), spec.trajectory.pack(), int(spec.law.code)
        pp = int(cp[0])
        tw = mod._tangent_work(n, pp, 0)
        ref = np.empty((6, n)); Y = np.empty((n, pp)); xi = np.empty(pp); v = np.empty(n); a = np.empty(n)
        r = np.empty(n); tau = np.empty(n); ys = np.empty(1); V = np.empty((13, n2)); J = np.empty((n2, n2))
        W = np.empty((n2, n2)); piv = np.zeros(n2, dtype=np.int64)
        Mi = np.empty((n, n)); Nw = np.empty((n, n)); pivn = np.zeros(n, dtype=np.int64)
        Ts = 1.0 / args.rate
        X0 = np.concatenate([res.q, res.qd], axis=1)[:-1]
        Uh = res.u[:-1]

        def sweep(kind, rtol, atol, reuse=1):
            hs = np.array([Ts, 0.0])  # the step to try, the periods left on SDIRK3's M^-1 (as the engine)
            out = np.empty_like(X0); nfs = np.empty(len(X0), dtype=np.int64)
            t0 = time.perf_counter()
            for k in range(len(X0)):
                x = X0[k].copy()
                if kind == "ros4":
                    st, nf = mod._stiff_period(x, Uh[k].copy(), Ts, hs, kc, wk, fx, fric, code, cp, tp, ref, Y, xi, v,
                                               a, r, tau, ys, V, J, W, piv, rtol, atol, 100000, tw)
                elif kind in ("sdirk", "sdirk0"):  # sdirk0: the error control before issue 37's knee work
                    st, nf = mod._sdirk_period(x, Uh[k].copy(), Ts, hs, kc, wk, fx, fric, tau, V, Mi, Nw, pivn, rtol,
                                               atol, 100000, kind == "sdirk")
                else:
                    st, nf = mod._rodas_period(x, Uh[k].copy(), Ts, hs, kc, wk, fx, fric, code, cp, tp, ref, Y, xi, v,
                                               a, r, tau, ys, V, J, W, piv, rtol, atol, 100000, tw, reuse)
                assert st == 0, (kind, st)
                out[k] = x; nfs[k] = nf
            return out, nfs, (time.perf_counter() - t0) / len(X0) * 1e6

        for kind in ("ros4", "rodas", "sdirk", "sdirk0"):  # compile
            sweep(kind, 1e-4, 1e-6)
        yard, _, _ = sweep("ros4", 1e-10, 1e-12)
        rows = [("ros4 1e-4/1e-6", "ros4", 1e-4, 1e-6, 1), ("rodas 1e-4/1e-6", "rodas", 1e-4, 1e-6, 1),
                ("rodas 1e-6/1e-8", "rodas", 1e-6, 1e-8, 1)]
        rows += [(f"{k} {rt:g}/{at:g}", k, rt, at, 1) for k in ("sdirk0", "sdirk")
                 for rt, at in ((1e-4, 1e-6), (3e-4, 3e-6), (1e-6, 1e-8))]
        for name, kind, rt, at, reuse in rows:
            out, nfs, us = sweep(kind, rt, at, reuse)
            dq = np.abs(out[:, :n] - yard[:, :n]).max(); dqd = np.abs(out[:, n:] - yard[:, n:]).max()
            print(f"| {arm} | {name} | {nfs.mean():.1f} | {nfs.max()} | {us:.1f} | {dq:.2g} | {dqd:.2g} |",
                  flush=True)
        if args.closed_loop:
            from dataclasses import replace
            o = spec.options
            tight = simulate(P, spec.law, spec.trajectory, replace(o, sampled_method="ros4", period_rtol=1e-10,
                                                                    period_atol=1e-12, max_steps=1e12))
            for m in ("ros4", "rodas", "sdirk"):
                r_ = simulate(P, spec.law, spec.trajectory, replace(o, sampled_method=m))
                print(f"| {arm} | closed loop {m} (default tol) vs ros4 1e-10/1e-12 | rhs {r_.rhs_evals} against "
                      f"{tight.rhs_evals} | wall {r_.wall_time_s:.3f} s against {tight.wall_time_s:.3f} | "
                      f"max\\|q - q_t\\| {np.abs(r_.q - tight.q).max():.2g} | max\\|e\\| {np.abs(r_.e).max():.6g} "
                      f"against {np.abs(tight.e).max():.6g}, {r_.status}/{tight.status} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
