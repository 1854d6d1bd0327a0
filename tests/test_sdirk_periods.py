"""The SDIRK3 periods (``rc3r.simulate.engines._sdirk``, ``compiled._sdirk_period``) on a real arm's friction knee,
each period integrated alone against a tight ROS4 period from the same state (issue 37)."""
from __future__ import annotations

import numpy as np
import pytest

import rc3r
from rc3r.simulate import simulate


@pytest.mark.slow
def test_z1_sdirk_periods_land_on_tight_ros4_periods_across_the_coulomb_knee():
    """The Z1 (its URDF friction: viscous and smooth Coulomb with v_s = 0.01 rad/s on light joints; its effort
    limits), the robust law at 1 kHz with a 0-3 kg payload on the perturbed plant, 0.5 s: every period of the
    run, integrated alone from the run's state under its held torque by the SDIRK3 period with the knee's
    error control at rtol 1e-4, atol 1e-6 (its tuning point; the default is 1e-5, 1e-7), ends within 3e-7 rad
    in q of ROS4 at rtol 1e-10, atol 1e-12 (an independent integrator, near the exact flow). Most periods
    start with a joint inside the knee (|qd| < v_s) and some break away; measured 4.5e-8 rad
    (benchmarks/period_methods.py, docs/performance.md). The bound is the one the knee's slope guard
    (``_sdirk.SLOPE_GUARD``) holds: without it, a step jumping across the knee is judged by a Taylor
    estimate that misses it (1.4e-6 rad measured on an instrumented copy; the mutation check in
    docs/testing.md)."""
    from rc3r.robots.pinocchio import example_robot_data_dir
    from rc3r.simulate._fast import simulator

    spec = rc3r.build_run(urdf=str(example_robot_data_dir() / "z1_description/urdf/z1.urdf"),
                          lock={"jointGripper": 0.0}, controller="robust", payload=(0.0, 3.0), rate=1000.0,
                          duration=0.5, friction="urdf", torque_limit="urdf", perturbed=True)
    P = spec.true_plant
    res = simulate(P, spec.law, spec.trajectory, spec.options)
    assert res.options.sampled_method == "sdirk"
    eng = simulator(P.rigid)
    mod = eng.for_run(int(spec.law.code), P.pack(), "sampled")  # the run's own instance: no second compile
    kc, fx, n = eng.constants(P.rigid), P.pack(), P.n
    n2, wk, fric = 2 * n, mod._make_work(kc), mod._friction(fx, n)
    cp, tp, code = spec.law.pack(n), spec.trajectory.pack(), int(spec.law.code)
    pp = int(cp[0])
    tw = mod._tangent_work(n, pp, 0)
    ref, Y, xi = np.empty((6, n)), np.empty((n, pp)), np.empty(pp)
    v, a, r, tau, ys = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(1)
    V, J, W, piv = np.empty((13, n2)), np.empty((n2, n2)), np.empty((n2, n2)), np.zeros(n2, dtype=np.int64)
    Mi, N, pivn = np.empty((n, n)), np.empty((n, n)), np.zeros(n, dtype=np.int64)
    T = 1.0 / 1000.0
    X0, U = np.concatenate([res.q, res.qd], axis=1)[:-1], res.u[:-1]
    v_s = min(e.v_s for e in P.effects if e.name == "friction")
    assert np.mean(np.abs(X0[:, n:]).min(axis=1) < v_s) > 0.5  # most periods start with a joint in the knee
    ends = {}
    for kind in ("ros4", "sdirk"):
        hs, out = np.array([T, 0.0]), np.empty_like(X0)
        for k in range(len(X0)):
            x = X0[k].copy()
            if kind == "ros4":
                st, _ = mod._stiff_period(x, U[k].copy(), T, hs, kc, wk, fx, fric, code, cp, tp, ref, Y, xi, v, a, r,
                                          tau, ys, V, J, W, piv, 1e-10, 1e-12, 100000, tw)
            else:
                st, _ = mod._sdirk_period(x, U[k].copy(), T, hs, kc, wk, fx, fric, tau, V, Mi, N, pivn, 1e-4, 1e-6,
                                          100000, True)
            assert st == 0
            out[k] = x
        ends[kind] = out
    dq = np.abs(ends["sdirk"][:, :n] - ends["ros4"][:, :n]).max()
    assert dq <= 3e-7, dq
