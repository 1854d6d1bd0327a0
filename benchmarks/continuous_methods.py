"""The fast engine's continuous-time methods on the 3R, side by side: ``python benchmarks/continuous_methods.py``.

For each law of the paper's comparison (and the adaptive, PD and eq. 7 laws), 10 s of the perturbed
scenario (``--duration``), default tolerances (rtol 1e-6, atol 1e-8), with each Rosenbrock method of
``SimOptions.method``: ode23s with its Jacobian kept 5 steps (the default before RODAS), ROS4 and RODAS
with a Jacobian every step. Each row: steps, rejected steps, right-hand sides, wall time (best of
``--repeats``), and the largest distance from a yardstick in q [rad], qd [rad/s] and u (relative to
max|u|). The yardstick is ROS4 at rtol 1e-10, atol 1e-12 (its steps are ~100x shorter, so its linearly
interpolated u is exact to ~1e-8 of max|u|); its q is checked against SciPy's Radau at rtol 1e-10 on the
same compiled right-hand side (a different method), printed as ``yardstick vs Radau``. ``auto`` says
which method the default (``SimOptions(method="auto")``, :func:`rc3r.simulate.continuous_method`) takes.
The table of docs/performance.md ("Continuous-time methods") comes from this script.

``--rtol R --atol A``: every method at those tolerances instead (the yardstick stays). ``--arms ur5,panda``:
instead of the 3R table, the robust law on each named arm with a 0-3 kg payload (its default box and
gains), ``--duration`` of continuous time, ode23s against RODAS: right-hand sides, wall and max|e|.
"""
from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

CASES = (("fbl", False, None), ("robust", False, 0.5), ("fbl", True, None), ("robust", True, 0.5),
         ("robust", True, 0.05), ("robust-coeff", True, None), ("adaptive", True, None), ("pd", True, None))
METHODS = (("ode23s", 5), ("ros4", 1), ("rodas", 1))


def main() -> None:
    from scipy.integrate import solve_ivp

    from rc3r.plants import as_plant
    from rc3r.simulate import _initial_state, continuous_method, simulate
    from rc3r.simulate._fast import simulator
    from rc3r.runspec import build_run

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--rtol", type=float, default=None)
    ap.add_argument("--atol", type=float, default=None)
    ap.add_argument("--arms", default=None)
    args = ap.parse_args()
    if args.arms:
        for arm in args.arms.split(","):
            spec = build_run(robot=arm, payload=(0.0, 3.0), controller="robust", duration=args.duration)
            for method in ("ode23s", "rodas"):
                r = simulate(spec.true_rigid, spec.law, spec.trajectory, replace(spec.options, method=method))
                print(f"{arm:8s} robust, 0-3 kg, {args.duration:g} s continuous, {method:6s} {r.engine:6s} {r.verdict:8s} "
                      f"steps {r.steps:7d} rhs {r.rhs_evals:8d} wall {r.wall_time_s:6.2f} s max|e| {np.abs(r.e).max():.4g} rad",
                      flush=True)
        return
    tol = "rtol 1e-6, atol 1e-8" if args.rtol is None else f"rtol {args.rtol:g}, atol {args.atol or 1e-8:g}"
    print(f"3R, perturbed unless 'ideal', {args.duration:g} s continuous, {tol}; wall best of "
          f"{args.repeats}; distances from ROS4 at rtol 1e-10 (du: / max|u|)")
    print(f"{'run':24s} {'method':6s} {'auto':4s} {'steps':>7s} {'rejected':>8s} {'rhs':>8s} {'wall':>8s} "
          f"{'dq':>8s} {'dqd':>8s} {'du':>8s}")
    for law, pert, eps in CASES:
        spec = build_run(controller=law, perturbed=pert, eps=eps, duration=args.duration)
        opts = replace(spec.options, engine="fast")
        if args.rtol is not None:
            opts = replace(opts, rtol=args.rtol, atol=args.atol if args.atol is not None else opts.atol)
        name = f"{law}{'' if eps is None else f'-eps{eps:g}'}-{'perturbed' if pert else 'ideal'}"
        ref = simulate(spec.true_rigid, spec.law, spec.trajectory,
                       replace(opts, method="ros4", jac_reuse=1, rtol=1e-10, atol=1e-12, max_steps=1e8))
        umax = np.abs(ref.u).max()
        p = spec.true_rigid
        x0 = _initial_state(p.n, spec.law, spec.trajectory, None)
        rhs = simulator(p).instance.closed_loop_xdot
        rargs = (simulator(p).constants(p), as_plant(p).pack(), int(spec.law.code), spec.law.pack(p.n),
                 spec.trajectory.pack(), p.n)
        sol = solve_ivp(rhs, (0.0, args.duration), x0, method="Radau", t_eval=ref.t, rtol=1e-10, atol=1e-12,
                        max_step=1e-3, args=rargs)
        chosen = continuous_method(spec.law, opts).method
        for method, jr in METHODS:
            o = replace(opts, method=method, jac_reuse=jr)
            runs = [simulate(spec.true_rigid, spec.law, spec.trajectory, o) for _ in range(args.repeats)]
            r = min(runs, key=lambda x: x.wall_time_s)
            m = min(len(r.t), len(ref.t))
            dq = np.abs(r.q[:m] - ref.q[:m]).max()
            dqd = np.abs(r.qd[:m] - ref.qd[:m]).max()
            du = np.abs(r.u[:m] - ref.u[:m]).max() / umax
            print(f"{name:24s} {method:6s} {'<-' if method == chosen else '':4s} {r.steps:7d} {r.rejected_steps:8d} "
                  f"{r.rhs_evals:8d} {r.wall_time_s * 1e3:5.0f} ms {dq:8.1e} {dqd:8.1e} {du:8.1e}"
                  + ("" if r.ok else f"  {r.verdict}"), flush=True)
        print(f"{name:24s} yardstick vs Radau (rtol 1e-10): dq {np.abs(sol.y[:p.n].T - ref.q).max():.1e}", flush=True)


if __name__ == "__main__":
    main()
