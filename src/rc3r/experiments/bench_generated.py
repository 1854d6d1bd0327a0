"""The generated kernels in ``rc3r bench``: generated tau per state against ``pin.rnea``, side by side.

One process, the same seeded random states (q in [-pi, pi], qd, qdd in [-5, 5]), every time the
median of ``repeats`` passes after a warm-up:

* the generated ``rnea`` of :mod:`rc3r.robots.generated` on the batch (one ctypes call);
* ``pin.rnea`` looped from Python;
* Pinocchio's C++ ``rnea``, estimated as ``pin.rnea`` looped on one fixed state minus on an empty
  model (the same binding path, no dynamics): an upper bound of the C++ time, so the ratio against
  it is on the safe side of the target; ``benchmarks/cpp_pinocchio.py --robot ur5`` measures it in C++.

Target (the speed issue): generated tau for the UR5 at most the cost of one ``pin.rnea`` call
measured from C++ (ratio <= 1). The check compares the generated torques with ``pin.rnea`` (1e-10
relative to ``max(1, |tau|)``). Skipped, with the reason, without CasADi or a C compiler.
"""
from __future__ import annotations

import numpy as np

__all__ = ["bench_generated", "TARGET_RATIO"]

#: Generated tau per state / Pinocchio's C++ rnea per call, at most.
TARGET_RATIO = 1.0


def bench_generated(robot: str = "ur5", quick: bool = False, seed: int = 0, progress=None) -> dict:
    """Per-state seconds of the generated rnea, a ``pin.rnea`` loop and the C++ estimate; the check and
    the target (module docstring). ``{"skipped": reason}`` without CasADi or a C compiler."""
    report = progress or (lambda msg: None)
    from ..errors import Rc3rError

    try:
        import casadi  # noqa: F401
    except ImportError:
        return {"skipped": "casadi is not installed"}
    import pinocchio as pin

    from ..robots.generated import GeneratedKernels
    from ..robots.pinocchio import PinocchioRobot
    from .bench_generic import median_per_state, pin_rnea_cpp_estimate

    arm = PinocchioRobot.named(robot)
    report(f"generated kernels: {robot} (CasADi -> C; built once, cached on disk) ...")
    try:
        k = GeneratedKernels.for_robot(arm)
    except Rc3rError as exc:
        return {"skipped": str(exc)}
    N, R = (1000, 3) if quick else (100_000, 7)
    rng = np.random.default_rng(seed)
    Q = rng.uniform(-np.pi, np.pi, (N, arm.n))
    QD, A = rng.uniform(-5.0, 5.0, (2, N, arm.n))
    model, data = arm.model, arm.model.createData()
    m = min(N, 1000)
    ref = np.array([pin.rnea(model, data, q, qd, a) for q, qd, a in zip(Q[:m], QD[:m], A[:m])])
    err = float(np.max(np.abs(k.rnea(Q[:m], QD[:m], A[:m]) - ref) / np.maximum(1.0, np.abs(ref))))
    t_gen = median_per_state(lambda: k.rnea(Q, QD, A), N, R)
    t_loop = median_per_state(lambda: [pin.rnea(model, data, q, qd, a) for q, qd, a in zip(Q, QD, A)], N, R)
    t_fixed, t_empty, t_cpp = pin_rnea_cpp_estimate(model, Q[0], QD[0], A[0], max(N, 20_000), R)
    ratio = t_gen / t_cpp if t_cpp > 0 else float("inf")
    return {"robot": robot, "n": arm.n, "states": N, "repeats": R, "seed": seed,
            "generate_s": k.generate_seconds, "compile_s": k.compile_seconds,
            "generated_rnea_s": t_gen, "pin_rnea_loop_s": t_loop, "pin_rnea_fixed_s": t_fixed,
            "pin_empty_s": t_empty, "cpp_rnea_estimate_s": t_cpp,
            "check": {"max_rel_err": err, "ok": bool(err <= 1e-10)},
            "target": {"ratio": ratio, "limit": TARGET_RATIO, "met": bool(ratio <= TARGET_RATIO)}}
