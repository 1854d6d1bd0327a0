"""Where the 3R's robust continuous run spends its time: ``python benchmarks/rr3_rhs_cost.py``.

The compiled engine's right-hand side of the paper's robust-perturbed loop, and its parts, each
called 10^6 times from a compiled loop (no Python in between; best of 3): the whole
``closed_loop_rhs``, the law (``control``: regressor, Y^T r, the eq. 6 term, Y theta), the plant's
forward dynamics, the reference trajectory; one closed-loop Jacobian, analytic (the 3R's generated
tangents, ``_tangent_jacobian``) and by forward differences (the fallback of ``_jacobian``, 7
right-hand sides). Then the 10 s run with each Rosenbrock method and
Jacobian policy (RODAS, the robust laws' default, always with a Jacobian per step): steps, rejected
steps, right-hand sides, wall time (``SimResult``). The numbers of docs/performance.md ("Not met")
come from this script.
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from numba import njit


def main() -> None:
    from rc3r.plants import as_plant
    from rc3r.simulate import _initial_state, simulate
    from rc3r.simulate._fast import simulator
    from rc3r.runspec import build_run
    from rc3r.trajectory import reference_into

    spec = build_run(controller="robust", perturbed=True, duration=10.0)
    p = spec.true_rigid
    eng = simulator(p)
    mod = eng.instance
    cp, tp, code = spec.law.pack(p.n), spec.trajectory.pack(), int(spec.law.code)
    kc, fx = eng.constants(p), as_plant(p).pack()
    x0 = _initial_state(3, spec.law, spec.trajectory, None)
    ctl, fd, mk, rhs, fr = mod.control, mod._fd, mod._make_work, mod.closed_loop_rhs, mod._friction

    @njit
    def loop_rhs(N, x, kc, fx, law, cp, tp, n):
        p_ = int(cp[0]); wk = mk(kc); fric = fr(fx, n)
        xdot = np.empty(x.shape[0]); u = np.empty(n); ref = np.empty((6, n)); Y = np.empty((n, p_))
        xi = np.empty(p_); v = np.empty(n); a = np.empty(n); r = np.empty(n); w = np.empty(n); ys = np.empty(1)
        s = 0.0
        for k in range(N):
            rhs(k * 1e-6, x, kc, wk, fx, fric, law, cp, tp, xdot, u, ref, Y, xi, v, a, r, w, ys, True)
            s += xdot[3]
        return s

    @njit
    def loop_law(N, x, kc, fx, law, cp, tp, n):
        p_ = int(cp[0]); wk = mk(kc)
        xdot = np.empty(x.shape[0]); u = np.empty(n); ref = np.empty((6, n)); Y = np.empty((n, p_))
        xi = np.empty(p_); v = np.empty(n); a = np.empty(n); r = np.empty(n); w = np.empty(n)
        reference_into(tp, 0.1, ref)
        q = x[0:n]; qd = x[n:2 * n]; z = x[2 * n:]; zd = xdot[2 * n:]
        s = 0.0
        for k in range(N):
            s += ctl(law, cp, q, qd, z, ref, kc, wk, u, zd, Y, xi, v, a, r, w)
        return s

    @njit
    def loop_plant(N, x, kc, fx, law, cp, tp, n):
        wk = mk(kc); tau = np.ones(n); qdd = np.empty(n); s = 0.0
        q = x[0:n]; qd = x[n:2 * n]
        for k in range(N):
            fd(kc, q, qd, tau, qdd, wk)
            s += qdd[0]
        return s

    @njit
    def loop_reference(N, x, kc, fx, law, cp, tp, n):
        ref = np.empty((6, n)); s = 0.0
        for k in range(N):
            reference_into(tp, k * 1e-6, ref)
            s += ref[0, 1]
        return s

    from rc3r.simulate.engines._jacobian import work

    tj = mod._tangent_jacobian

    @njit
    def loop_jacobian(N, x, kc, fx, law, cp, tp, n, analytic):
        p_ = int(cp[0]); wk = mk(kc); m = x.shape[0]
        u = np.empty(n); ref = np.empty((6, n)); Y = np.empty((n, p_)); xi = np.empty(p_); v = np.empty(n)
        a = np.empty(n); r = np.empty(n); w = np.empty(n); ys = np.empty(1)
        F0 = np.empty(m); Fp = np.empty(m); J = np.empty((m, m)); Ft = np.empty(m); tw = work(n, p_, m - 2 * n)
        s = 0.0
        for k in range(N):
            t = 0.3 + k * 1e-9
            rhs(t, x, kc, wk, fx, False, law, cp, tp, F0, u, ref, Y, xi, v, a, r, w, ys, True)
            if analytic:
                tj(t, x, kc, wk, fx, law, cp, tp, J, Ft, F0, u, ref, Y, xi, v, a, r, w, tw, True)
            else:  # the forward differences of _jacobian (plant_only=False, no tangents tried)
                sq = 1.4901161193847656e-08
                for j in range(m):
                    dx = sq * max(abs(x[j]), 1e-3)
                    xj = x[j]
                    x[j] = xj + dx
                    rhs(t, x, kc, wk, fx, False, law, cp, tp, Fp, u, ref, Y, xi, v, a, r, w, ys, j == 0)
                    x[j] = xj
                    for i in range(m):
                        J[i, j] = (Fp[i] - F0[i]) / dx
                rhs(t + sq, x, kc, wk, fx, False, law, cp, tp, Fp, u, ref, Y, xi, v, a, r, w, ys, True)
                for i in range(m):
                    Ft[i] = (Fp[i] - F0[i]) / sq
            s += J[4, 1]
        return s

    N = 1_000_000
    args = (x0, kc, fx, code, cp, tp, 3)
    x1 = x0 + 0.1
    print("closed-loop Jacobian at one state, per call (compiled loop of 2e5, each after one right-hand side "
          "at that state, which is subtracted; best of 3):")
    costs = {}
    for name, an in (("analytic (tangents)", True), ("forward differences", False)):
        loop_jacobian(10, x1, kc, fx, code, cp, tp, 3, an)
        costs[name] = min(_timed(loop_jacobian, 200_000, (x1, kc, fx, code, cp, tp, 3, an)) for _ in range(3))
    base = min(_timed(loop_rhs, 200_000, (x1,) + args[1:]) for _ in range(3))
    for name, c in costs.items():
        print(f"  {name:24s} {(c - base) / 200_000 * 1e9:7.1f} ns")
    print("right-hand side of the 3R's robust-perturbed loop, per call (compiled loop of 1e6, best of 3):")
    for name, f in (("closed_loop_rhs", loop_rhs), ("law (control)", loop_law),
                    ("plant forward dynamics", loop_plant), ("reference trajectory", loop_reference)):
        f(10, *args)
        best = min(_timed(f, N, args) for _ in range(3))
        print(f"  {name:24s} {best / N * 1e9:7.1f} ns")
    opts = replace(spec.options, engine="fast")
    simulate(spec.true_rigid, spec.law, spec.trajectory, replace(opts, duration=0.01, method="ros4"))
    simulate(spec.true_rigid, spec.law, spec.trajectory, replace(opts, duration=0.01))
    print("\n10 s robust-perturbed, rtol 1e-6, atol 1e-8 (best of 3 walls):")
    print(f"  {'method':8s} {'J kept':>6s} {'steps':>7s} {'rejected':>8s} {'rhs':>7s} {'rhs/step':>8s} {'wall':>8s}")
    for method, jr in (("ode23s", 1), ("ode23s", 5), ("ros4", 1), ("ros4", 5), ("rodas", 1)):
        runs = [simulate(spec.true_rigid, spec.law, spec.trajectory, replace(opts, method=method, jac_reuse=jr))
                for _ in range(3)]
        r = min(runs, key=lambda x: x.wall_time_s)
        tries = r.steps + r.rejected_steps
        print(f"  {method:8s} {jr:6d} {r.steps:7d} {r.rejected_steps:8d} {r.rhs_evals:7d} "
              f"{r.rhs_evals / tries:8.2f} {r.wall_time_s * 1e3:6.0f} ms")
    reps = 9
    walls = sorted(simulate(spec.true_rigid, spec.law, spec.trajectory, opts).wall_time_s * 1e3 for _ in range(reps))
    print(f"\nthe default (auto: rodas), simulate() {reps} times: walls {', '.join(f'{w:.0f}' for w in walls)} ms; "
          f"median {walls[reps // 2]:.0f} ms")
    from rc3r.simulate import _limits
    from rc3r.simulate.engines.compiled import ODE23S, RODAS

    t_out = np.linspace(0.0, 10.0, 10001)
    print("one compiled integrate_continuous call over the 10 s (no 0.5 s chunks), best of 3:")
    for name, m in (("rodas", RODAS), ("ode23s", ODE23S)):
        X = np.zeros((t_out.size, 6)); U = np.zeros((t_out.size, 3)); R = np.zeros((t_out.size, 3))
        yn = np.zeros(t_out.size)
        best, out = 1e9, None
        for _ in range(3):
            t0 = time.perf_counter()
            out = mod.integrate_continuous(x0.copy(), t_out, kc, fx, code, cp, tp, opts.rtol, opts.atol, 1e-5, 1e-3,
                                           _limits(opts), X, U, R, yn, 5, 10 ** 7, m)
            best = min(best, time.perf_counter() - t0)
        print(f"  {name:8s} {out[3]:7d} steps {out[2]:7d} rhs {best * 1e3:6.1f} ms = {best / out[3] * 1e6:5.2f} us/step")


def _timed(f, N, args) -> float:
    t0 = time.perf_counter()
    f(N, *args)
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
