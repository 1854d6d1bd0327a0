"""What one ROS4 period of a stiff plant costs: ``python benchmarks/stiff_period_probe.py xarm7 500``.

Runs 0.1 s of the robust law on the arm (example-robot-data URDF, its friction and effort limits, a
0-3 kg payload) at the rate, then re-integrates each recorded period alone with the compiled
``_stiff_period`` (the held torque of the run) and prints the right-hand sides per period
(median, min, max) at three tolerances, and with the first step reset to T or to 1 us each period.
A period costs 1 + (2n + 3) per step (a Jacobian and three stages), so 255 on the 7-joint xArm7 is
15 steps. Measured 2026-12-03 (xArm7, 500 Hz): median 255 at rtol 1e-6, 35 at 1e-4, 800 at 1e-8,
and 257 / 256 with the first step reset: the steps are set by accuracy, not by the start-up.
"""
import sys, numpy as np
from dataclasses import replace
import rc3r
from rc3r.simulate import simulate
from rc3r.simulate._fast import simulator
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent)); import design_table as D  # noqa: E402
arm, rate = sys.argv[1], float(sys.argv[2])
urdf, lock = D.ARMS[arm]
spec = rc3r.build_run(urdf=str(D.ROBOTS / urdf), lock=lock or None, controller="robust", payload=(0.0, 3.0), rate=rate,
                      duration=0.1, friction="urdf", torque_limit="urdf", perturbed=True)
P = spec.true_plant
res = simulate(P, spec.law, spec.trajectory, spec.options)
rigid = P.rigid; eng = simulator(rigid); mod = eng.instance
kc = eng.constants(rigid); fx = P.pack(); wk = mod._make_work(kc); n = P.n; n2 = 2 * n
fric = mod._friction(fx, n)
cp, tp, code = spec.law.pack(n), spec.trajectory.pack(), int(spec.law.code)
p = int(cp[0])
ref = np.empty((6, n)); Y = np.empty((n, p)); xi = np.empty(p); v = np.empty(n); a = np.empty(n); r = np.empty(n)
tau = np.empty(n); ys = np.empty(1); V = np.empty((11, n2)); J = np.empty((n2, n2)); W = np.empty((n2, n2))
piv = np.zeros(n2, dtype=np.int64)
tw = mod._tangent_work(n, p, 0)  # the plant-only Jacobian is numerical: unused (the argument since the analytic one)
Ts = 1 / rate
for rtol, atol in ((1e-6, 1e-8), (1e-4, 1e-6), (1e-8, 1e-10)):
    nfs = []
    hs = np.full(1, Ts)
    for k in range(len(res.t) - 1):
        x = np.concatenate([res.q[k], res.qd[k]])
        st, nf = mod._stiff_period(x, res.u[k].copy(), Ts, hs, kc, wk, fx, fric, code, cp, tp, ref, Y, xi, v, a, r, tau, ys,
                                   V, J, W, piv, rtol, atol, 100000, tw)
        nfs.append(nf)
    nfs = np.array(nfs)
    print(rtol, atol, "nf per period: median", np.median(nfs), "min", nfs.min(), "max", nfs.max(), "hs", hs[0])
# fresh hs=Ts each period vs tiny
for h0 in (Ts, 1e-6):
    nfs = []
    for k in range(len(res.t) - 1):
        hs = np.full(1, h0)
        x = np.concatenate([res.q[k], res.qd[k]])
        st, nf = mod._stiff_period(x, res.u[k].copy(), Ts, hs, kc, wk, fx, fric, code, cp, tp, ref, Y, xi, v, a, r, tau, ys,
                                   V, J, W, piv, 1e-6, 1e-8, 100000, tw)
        nfs.append(nf)
    print("h0", h0, "median nf", np.median(nfs))
