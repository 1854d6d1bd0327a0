"""The python and the compiled engine side by side: ``python benchmarks/engines.py [--duration 10]``.

The UR5 of example-robot-data carrying an unknown payload (0..5 kg at 0.1 m on the last link;
plant at 5 kg, controller at the box's centre), the robust law with the gains of
``examples/ur5_payload.toml`` (K = 50 diag M(q_d(0)), Lambda = 20, eps = 5), sampled at
1 kHz (RK4, 4 sub-steps of 0.25 ms: 16 forward dynamics and one regressor per control step),
``--duration`` simulated seconds on each engine, in one process. Each engine is warmed first
(numba's compile or cache load is not timed). Printed per engine: wall time
(``SimResult.wall_time_s``) and process CPU time of the run, and the cost of one control step
in units of one ``pinocchio.rnea`` call (a Python loop over the run's own states on the plant's
model, best of 5; CPU time, which the other processes of a shared machine disturb less than
the wall clock); and the largest joint-position difference between the two runs.
"""
from __future__ import annotations

import argparse
import time

import numpy as np


def _spec(duration: float, engine: str):
    import rc3r
    from rc3r.controllers import inertia_scaled_gain

    ur5 = rc3r.load_robot("ur5")
    k = inertia_scaled_gain(ur5, ur5.default_trajectory().evaluate(0.0)[0], 50.0)
    gains = {"robust": {"K": k.tolist(), "Lambda": 20.0, "eps": 5.0}}
    return rc3r.build_run(robot="ur5", controller="robust", perturbed=True, payload=(0.0, 5.0),
                          payload_com=(0, 0, 0.1), rate=1000.0, duration=duration, engine=engine,
                          config={"gains": gains})


def _run(spec):
    import rc3r

    cpu = time.process_time()
    res = rc3r.simulate(spec.true_rigid, spec.law, spec.trajectory, spec.options)
    return res, time.process_time() - cpu


def _rnea_us(model, Q, QD, QDD, repeat: int = 5) -> tuple[float, float]:
    """(wall, cpu) microseconds of one ``pinocchio.rnea`` call, best of ``repeat`` loops over the states."""
    import pinocchio as pin

    data = model.createData()
    walls, cpus = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        for q, qd, a in zip(Q, QD, QDD):
            pin.rnea(model, data, q, qd, a)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return min(walls) / len(Q) * 1e6, min(cpus) / len(Q) * 1e6


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0, help="simulated seconds per engine (default 10)")
    a = ap.parse_args(argv)
    from dataclasses import replace

    rows = {}
    for engine in ("compiled", "python"):
        spec = _spec(a.duration, engine)
        _run(replace(spec, options=replace(spec.options, duration=0.01)))  # warm: compile or cache load
        res, cpu = _run(spec)
        rows[engine] = (res, cpu)
        print(f"{engine:>8}: {res.verdict}, {res.t.size - 1} control steps stored, wall {res.wall_time_s:.3f} s, "
              f"cpu {cpu:.3f} s", flush=True)
    res = rows["compiled"][0]
    idx = np.linspace(0, res.t.size - 1, min(res.t.size, 20000)).astype(int)
    qdd = np.gradient(res.qd, res.t, axis=0)
    rnea_wall, rnea_cpu = _rnea_us(_spec(a.duration, "compiled").true_rigid.model, res.q[idx], res.qd[idx], qdd[idx])
    steps = round(a.duration * 1000.0)
    print(f"pin.rnea: {rnea_wall:.2f} us wall, {rnea_cpu:.2f} us cpu per call")
    print(f"{'engine':>8} {'wall [s]':>9} {'cpu [s]':>8} {'us/step (cpu)':>14} {'rnea/step (cpu)':>16} "
          f"{'rnea/step (wall)':>17}")
    for engine, (r, cpu) in rows.items():
        print(f"{engine:>8} {r.wall_time_s:9.3f} {cpu:8.3f} {cpu / steps * 1e6:14.2f} "
              f"{cpu / steps * 1e6 / rnea_cpu:16.2f} {r.wall_time_s / steps * 1e6 / rnea_wall:17.2f}")
    py = rows["python"][0]
    m = min(py.q.shape[0], res.q.shape[0])
    print(f"speed-up (wall): {py.wall_time_s / res.wall_time_s:.1f}x; "
          f"max |q_compiled - q_python| = {np.abs(py.q[:m] - res.q[:m]).max():.3g} rad over {m} rows")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
