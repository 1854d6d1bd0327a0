"""Integrators side by side on the same compiled closed loop (part of ``rc3r bench``).

The compiled engine's continuous-time integrator is a hand-written Rosenbrock method
(:mod:`rc3r.simulate.engines.compiled`, instantiated on the 3R's kernel supply :mod:`rc3r.robots.rr3.engine`).
This section makes it justify itself against library solvers on the *same* compiled
right-hand side (``closed_loop_xdot`` of that instantiation: closed-form plant, law kernel,
trajectory) and the same tolerances (``rtol = 1e-6``, ``atol = 1e-8``):

* ``rosenbrock, J every step`` -- MATLAB's ode23s scheme (``jac_reuse = 1``);
* ``rosenbrock, J kept 5 steps`` -- ode23s with ``jac_reuse = 5``, the default for FBL;
* ``ros4, J every step`` / ``ros4, J kept 5 steps`` -- ``SimOptions(method="ros4")``, Hairer &
  Wanner's order-4 method (a Rosenbrock method, not a W-method: it wants the Jacobian of each step);
* ``rodas, J every step`` -- ``SimOptions(method="rodas")``, Hairer & Wanner's stiffly accurate RODAS,
  steps ending on the output times (the default for the robust laws);
* ``scipy Radau`` / ``scipy BDF`` -- :func:`scipy.integrate.solve_ivp` calling the
  compiled right-hand side (finite-difference Jacobian by SciPy), stored on the same
  1 kHz grid (``t_eval``) with ``max_step`` = 1 ms like the Rosenbrock runs.

Each row: wall time of the integration, right-hand-side evaluations, and the largest
joint-position difference from ``scipy Radau`` at ``rtol = 1e-10`` (the yardstick). ``x_default`` is
the wall time over that of the method the default options take for the law
(:func:`rc3r.simulate.continuous_method`: ode23s with J kept 5 steps for FBL, RODAS for the robust law).
"""
from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["bench_integrators"]


def _scipy(spec, x0, t_out, method: str, rtol: float, atol: float):
    from ..plants import as_plant
    from ..simulate._fast import simulator

    p = spec.true_rigid
    cp, tp, code = spec.law.pack(p.n), spec.trajectory.pack(), int(spec.law.code)
    eng = simulator(p)
    _rhs = eng.instance.closed_loop_xdot
    args = (eng.constants(p), as_plant(p).pack(), code, cp, tp, p.n)
    _rhs(0.0, x0, *args)  # compile / load before timing
    t0 = time.perf_counter()
    sol = solve_ivp(_rhs, (t_out[0], t_out[-1]), x0, method=method, t_eval=t_out, rtol=rtol, atol=atol,
                    max_step=t_out[1] - t_out[0], args=args)
    wall = time.perf_counter() - t0
    return sol.y.T[:, :3], wall, int(sol.nfev), sol.status == 0


def _rosenbrock(spec, jac_reuse: int, method: str = "ode23s"):
    from dataclasses import replace

    from ..simulate import simulate

    opts = replace(spec.options, jac_reuse=jac_reuse, engine="fast", method=method)
    simulate(spec.true_rigid, spec.law, spec.trajectory, replace(opts, duration=0.01))  # warm
    res = simulate(spec.true_rigid, spec.law, spec.trajectory, opts)
    return res.q, res.wall_time_s, res.rhs_evals, res.ok


def bench_integrators(duration: float = 10.0, progress=None) -> dict:
    """Rosenbrock ode23s and ROS4 (J every step / kept 5 steps) and RODAS vs SciPy Radau and BDF on the FBL and
    robust perturbed runs."""
    from ..simulate import _initial_state, continuous_method
    from ..runspec import build_run

    report = progress or (lambda msg: None)
    out = {}
    for ctrl in ("fbl", "robust"):
        spec = build_run(controller=ctrl, perturbed=True, duration=duration)
        x0 = _initial_state(3, spec.law, spec.trajectory, None)
        t_out = np.linspace(0.0, duration, int(round(duration * spec.options.output_rate)) + 1)
        report(f"integrators: {ctrl}-perturbed {duration:g} s, yardstick scipy Radau rtol 1e-10 ...")
        ref_q, ref_wall, _, _ = _scipy(spec, x0, t_out, "Radau", 1e-10, 1e-12)
        rows = {}
        for label, run in (("rosenbrock, J every step", lambda: _rosenbrock(spec, 1)),
                           ("rosenbrock, J kept 5 steps", lambda: _rosenbrock(spec, 5)),
                           ("ros4, J every step", lambda: _rosenbrock(spec, 1, "ros4")),
                           ("ros4, J kept 5 steps", lambda: _rosenbrock(spec, 5, "ros4")),
                           ("rodas, J every step", lambda: _rosenbrock(spec, 1, "rodas")),
                           ("scipy Radau", lambda: _scipy(spec, x0, t_out, "Radau", 1e-6, 1e-8)),
                           ("scipy BDF", lambda: _scipy(spec, x0, t_out, "BDF", 1e-6, 1e-8))):
            report(f"integrators: {ctrl}, {label} ...")
            q, wall, nfev, ok = run()
            m = min(len(q), len(ref_q))
            rows[label] = {"wall_s": wall, "rhs_evals": nfev, "ok": bool(ok),
                           "max_q_diff_rad": float(np.abs(q[:m] - ref_q[:m]).max())}
        default = {"ode23s": "rosenbrock, J kept 5 steps", "rodas": "rodas, J every step"}[
            continuous_method(spec.law, spec.options).method]
        base = rows[default]["wall_s"]
        for r in rows.values():
            r["x_default"] = r["wall_s"] / base if base > 0 else None
        out[f"{ctrl}-perturbed"] = {"duration_s": duration, "yardstick_wall_s": ref_wall, "methods": rows,
                                    "default": default}
    return out
