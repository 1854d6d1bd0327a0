#!/usr/bin/env python
"""Generated C kernels (rc3r.robots.generated) vs Pinocchio from Python and the numba regressor.

Per-state median times, in one process on the same random states (q in [-pi, pi], qd, v, a in
[-5, 5], ``numpy.random.default_rng(seed)``), every timing the median of ``--repeats`` runs after
one warm-up call (``time.perf_counter``):

* generated ``rnea`` and ``slotine_li`` on the whole batch (one ctypes call each);
* ``pin.rnea`` looped from Python over the states;
* ``robot.regressor`` (the numba kernel of :mod:`rc3r.robots.pinocchio_kernel`) on the batch, with
  ``RC3R_COLD_START=compile`` (set here unless given) so that it is the compiled kernel and not the
  cold-start fallback to Pinocchio's regressor; its warm-up call compiles it if numba's cache is cold;
* Pinocchio's C++ ``rnea`` estimated as ``rnea`` looped on one fixed state minus ``rnea`` looped on
  an empty model (nq = 0: the same binding path, no dynamics), as ``rc3r bench`` does: an upper
  bound on the C++ time, so the ratio printed against it is conservative for the generated code.

The kernels are built into a fresh temporary cache (``--cache-dir`` to keep them), so the
generate and compile seconds are those of a cold build; ``--o3`` builds a second library with
``-O3`` and times it too. Ends with ``target generated_tau_vs_cpp_rnea: <= 1x: <ratio> -> met|NOT MET``
(generated rnea per state / estimated C++ pin.rnea per state).

Usage: ``python benchmarks/generated_kernels.py [--robot ur5|panda|rr3] [-n 100000] [--repeats 7] [--o3]``
"""
from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def robot_of(name: str):
    from rc3r.robots.pinocchio import PinocchioRobot

    if name == "rr3":
        return PinocchioRobot.from_urdf(REPO / "urdf" / "rr3.urdf")
    return PinocchioRobot.named(name)


def fmt(s: float) -> str:
    return f"{s * 1e9:10.0f} ns" if s < 1e-5 else f"{s * 1e6:10.2f} us"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="ur5", choices=("ur5", "panda", "rr3"))
    ap.add_argument("-n", type=int, default=100_000, help="states (default 100000)")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--o3", action="store_true", help="also build and time an -O3 library")
    ap.add_argument("--cache-dir", help="kernel cache (default: a temporary directory, removed afterwards)")
    args = ap.parse_args(argv)
    os.environ.setdefault("RC3R_COLD_START", "compile")  # robot.regressor: the numba kernel, not the fallback

    import casadi
    import pinocchio as pin

    from rc3r.robots.generated import DEFAULT_FLAGS, GeneratedKernels
    from rc3r.experiments.bench_generic import median_per_state, pin_rnea_cpp_estimate

    robot = robot_of(args.robot)
    n, N, R = robot.n, args.n, args.repeats
    rng = np.random.default_rng(args.seed)
    Q = rng.uniform(-np.pi, np.pi, (N, n))
    QD, V, A = rng.uniform(-5.0, 5.0, (3, N, n))
    model = robot.model
    data = model.createData()

    with tempfile.TemporaryDirectory(prefix="rc3r-gen-bench-") as tmp:
        cache = Path(args.cache_dir) if args.cache_dir else Path(tmp)
        builds = [("-O2", GeneratedKernels.for_robot(robot, cache_dir=cache))]
        if args.o3:
            flags = tuple("-O3" if f == "-O2" else f for f in DEFAULT_FLAGS)
            builds.append(("-O3", GeneratedKernels.for_robot(robot, cache_dir=cache, flags=flags)))
        k = builds[0][1]

        # what is timed computes the right thing (first 1000 states)
        m = min(N, 1000)
        ref = np.array([pin.rnea(model, data, q, qd, a) for q, qd, a in zip(Q[:m], QD[:m], A[:m])])
        err_tau = float(np.max(np.abs(k.rnea(Q[:m], QD[:m], A[:m]) - ref)) / max(1.0, np.abs(ref).max()))
        Yg, Yn = k.slotine_li(Q[:m], QD[:m], V[:m], A[:m]), robot.regressor(Q[:m], QD[:m], V[:m], A[:m])
        err_Y = float(np.max(np.abs(Yg - Yn)) / max(1.0, np.abs(Yn).max()))

        t = {}
        for label, kk in builds:
            t[f"generated rnea {label}"] = median_per_state(lambda kk=kk: kk.rnea(Q, QD, A), N, R)
            t[f"generated slotine_li {label}"] = median_per_state(lambda kk=kk: kk.slotine_li(Q, QD, V, A), N, R)
        t["pin.rnea loop"] = median_per_state(
            lambda: [pin.rnea(model, data, q, qd, a) for q, qd, a in zip(Q, QD, A)], N, R)
        assert robot.kernel is not None and robot.kernel.ready(), "robot.regressor would not be the numba kernel"
        t["robot.regressor (numba)"] = median_per_state(lambda: robot.regressor(Q, QD, V, A), N, R)

        # Pinocchio's C++ rnea: fixed state minus the empty model, both looped from Python
        t_fixed, t_empty, t_cpp = pin_rnea_cpp_estimate(model, Q[0], QD[0], A[0], max(N, 20000), R)

        print(f"# generated kernels benchmark, {datetime.date.today().isoformat()}, robot {args.robot} "
              f"(n={n}, p={robot.p}), {N} states, median of {R}; python {platform.python_version()}, "
              f"casadi {casadi.__version__}, pin {pin.__version__}, {k.meta['compiler'][1]}")
        for label, kk in builds:
            src = kk.source_path.stat().st_size / 1e6
            print(f"build {label}: generate {kk.generate_seconds:.2f} s, compile {kk.compile_seconds:.2f} s "
                  f"({' '.join(kk.meta['flags'])}; {src:.2f} MB of C; instructions "
                  + ", ".join(f"{f} {c}" for f, c in kk.meta["instructions"].items()) + ")")
        print(f"check: generated rnea vs pin.rnea max rel err {err_tau:.1e}; "
              f"generated slotine_li vs robot.regressor {err_Y:.1e} (first {m} states)")
        print()
        print(f"{'per state':32s} {'time':>13s}  {'vs pin.rnea loop':>17s}")
        base = t["pin.rnea loop"]
        for name, s in t.items():
            print(f"{name:32s} {fmt(s)}  {base / s:16.2f}x")
        print()
        print(f"{'tau: generated rnea':32s} {fmt(t['generated rnea -O2'])}")
        print(f"{'tau: pin.rnea loop':32s} {fmt(base)}   generated is {base / t['generated rnea -O2']:.1f}x faster")
        print(f"{'Y: generated slotine_li':32s} {fmt(t['generated slotine_li -O2'])}")
        print(f"{'Y: robot.regressor (numba)':32s} {fmt(t['robot.regressor (numba)'])}   generated is "
              f"{t['robot.regressor (numba)'] / t['generated slotine_li -O2']:.2f}x faster")
        print(f"pin.rnea C++ estimate: fixed state {fmt(t_fixed).strip()} - empty model {fmt(t_empty).strip()} "
              f"= {fmt(t_cpp).strip()}")
        ratio = t["generated rnea -O2"] / t_cpp if t_cpp > 0 else float("inf")
        print(f"target generated_tau_vs_cpp_rnea: <= 1x: {ratio:.2f} -> {'met' if ratio <= 1.0 else 'NOT MET'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
