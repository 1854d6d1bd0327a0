"""``rc3r bench``'s generic-robot section: the Slotine--Li regressor of a URDF arm against one
``pinocchio.rnea`` call, and 10 s runs of the UR5 and the Panda with a payload at 1 kHz.

Targets (the any-URDF issue): the UR5 regressor within 6x one ``pin.rnea`` call measured in the
same run; the 10 s robust run in under 2 s on this 2-core machine. The speed issue's: the UR5's and
the Panda's robust run within 6 ``pin.rnea`` calls (each measured in the same run) per control
step. All are reported, never asserted (tests do not assert wall-clock times).
"""
from __future__ import annotations

import math
import statistics
import time

import numpy as np

__all__ = ["bench_generic", "bench_regressor", "median_per_state", "pin_rnea_cpp_estimate", "GENERIC_TARGETS"]

#: name -> (limit, comparison, unit, description), as ``rc3r.experiments.bench3r.TARGETS``.
GENERIC_TARGETS = {
    "ur5_regressor_vs_rnea": (6.0, "<=", "x", "UR5 Slotine-Li Y per state (batch) / one pin.rnea call"),
    "ur5_payload_robust_1khz_10s": (2.0, "<=", "s", "UR5 + payload, robust law, 10 s at 1 kHz: wall time"),
    "ur5_payload_robust_rnea_per_step": (6.0, "<=", "rnea", "UR5 + payload, robust, 1 kHz: integration wall per "
                                                            "control step / one pin.rnea call (the speed issue)"),
    "panda_payload_robust_rnea_per_step": (6.0, "<=", "rnea", "Panda + payload, robust, 1 kHz: integration wall "
                                                              "per control step / one pin.rnea call"),
}


def bench_generic(quick: bool = False, progress=None) -> dict:
    """Measure the generic-robot targets; returns ``{"regressor": {...}, "runs": {...}, "targets": {...}}``."""
    from ..simulate import file_status
    from ..runspec import build_run, execute
    from ..robots import load_robot

    say = progress or (lambda msg: None)
    out = {"regressor": {}, "runs": {}}
    for name in ("ur5", "panda"):
        say(f"generic: {name} Slotine-Li regressor vs pin.rnea ...")
        robot = load_robot(name)
        z = [[0.1] * robot.n] * 2
        robot.regressor(z, z, z, z)  # warm-up: numba compile or cache load is not timed
        out["regressor"][name] = bench_regressor(robot, n=200 if quick else 2000, repeat=1 if quick else 3)
    duration = 0.5 if quick else 10.0
    from ..controllers import inertia_scaled_gain

    ur5 = load_robot("ur5")  # the gains of examples/ur5_payload.toml: K = 50 diag M(q_d(0)), Lambda 20, eps 5
    k = inertia_scaled_gain(ur5, ur5.default_trajectory().evaluate(0.0)[0], 50.0)
    gains = {"robust": {"K": k.tolist(), "Lambda": 20.0, "eps": 5.0}}
    cases = [("ur5", law, {"gains": gains}) for law in ("fbl", "robust")] + [("panda", "robust", {})]
    for name, law, cfg in cases:  # the Panda: the rule's default gains for its bounds and rate
        spec = build_run(robot=name, controller=law, perturbed=True, payload=(0.0, 5.0 if name == "ur5" else 3.0),
                         payload_com=(0, 0, 0.1), rate=1000.0, duration=duration, config=cfg)
        res, m = execute(build_run(robot=name, controller=law, perturbed=True, payload=(0.0, 1.0), rate=1000.0,
                                   duration=0.01, config=cfg))  # warm-up: kernels compiled or loaded, not timed
        say(f"generic: {name} + payload, {law}, {duration:g} s at 1 kHz ({res.engine} engine) ...")
        t0 = time.perf_counter()
        res, m = execute(spec)
        steps = int(round(duration * 1000.0))
        rnea_s = out["regressor"][name]["rnea_us"] * 1e-6

        out["runs"][f"{name}-payload-{law}@1kHz"] = {
            "wall_s": res.wall_time_s, "execute_s": time.perf_counter() - t0, "duration_s": duration,
            "engine": res.engine, "status": file_status(res), "max_abs_error": max(m["max_abs_error"]),
            "per_step_s": res.wall_time_s / steps, "rnea_per_step": res.wall_time_s / steps / rnea_s}
    scale = 10.0 / duration
    runs = out["runs"]
    measured = {"ur5_regressor_vs_rnea": out["regressor"]["ur5"]["ratio"],
                "ur5_payload_robust_1khz_10s": runs["ur5-payload-robust@1kHz"]["wall_s"] * scale,
                "ur5_payload_robust_rnea_per_step": runs["ur5-payload-robust@1kHz"]["rnea_per_step"],
                "panda_payload_robust_rnea_per_step": runs["panda-payload-robust@1kHz"]["rnea_per_step"]}
    out["targets"] = {}
    for key, (limit, op, unit, what) in GENERIC_TARGETS.items():
        x = measured[key]
        out["targets"][key] = {"limit": limit, "op": op, "unit": unit, "description": what, "measured": x,
                               "met": bool(x <= limit), "extrapolated": bool(quick and unit in ("s", "rnea"))}
    return out


def bench_regressor(robot, n: int = 2000, seed: int = 0, repeat: int = 3) -> dict:
    """Per-state time of ``robot.regressor`` on a batch of ``n`` states vs one ``pinocchio.rnea`` call.

    States from ``numpy.random.default_rng(seed)`` (q in [-pi, pi], qd, v, a in [-5, 5]).
    Every timing is the best of ``repeat`` runs (``time.perf_counter``) in the same
    process; ``rnea`` is called in a Python loop on ``robot.model``.

    Returns
    -------
    dict
        ``robot``, ``n`` (joints), ``p``, ``states``; per state [microseconds]:
        ``regressor_us`` (one call on the whole batch), ``regressor_single_us`` (one
        call per state), ``rnea_us``, and for a :class:`PinocchioRobot` the reference
        path ``pinocchio_path_us`` (:meth:`PinocchioRobot.regressor_pinocchio`);
        ``ratio`` = ``regressor_us / rnea_us``; ``max_rel_error_vs_rnea``: the benchmarked
        regressor checked, ``max |Y(q, qd, qd, a) theta - rnea(q, qd, a)| / max |rnea|`` over the states.
    """
    import pinocchio as pin

    rng = np.random.default_rng(seed)
    Q = rng.uniform(-math.pi, math.pi, (n, robot.n))
    QD, V, A = rng.uniform(-5.0, 5.0, (3, n, robot.n))
    model = robot.model
    data = model.createData()

    def best(fn) -> float:
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t0)
        return min(times) / n * 1e6

    def loop(fn):
        return lambda: [fn(*x) for x in zip(Q, QD, V, A)]

    out = {"robot": robot.robot_name or robot.name, "n": robot.n, "p": robot.p, "states": n,
           "regressor_us": best(lambda: robot.regressor(Q, QD, V, A)),
           "regressor_single_us": best(loop(robot.regressor)),
           "rnea_us": best(loop(lambda q, qd, v, a: pin.rnea(model, data, q, qd, a)))}
    if robot.regressor_pinocchio is not None:
        out["pinocchio_path_us"] = best(lambda: robot.regressor_pinocchio(Q, QD, V, A))
    out["ratio"] = out["regressor_us"] / out["rnea_us"]
    # what was timed computes the right thing: Y(q, qd, qd, a) theta = rnea(q, qd, a) at every state
    tau = np.einsum("knp,p->kn", robot.regressor(Q, QD, QD, A), robot.theta)
    ref = np.array([pin.rnea(model, data, q, qd, a) for q, qd, a in zip(Q, QD, A)])
    out["max_rel_error_vs_rnea"] = float(np.abs(tau - ref).max() / max(np.abs(ref).max(), 1e-300))
    return out


def median_per_state(fn, count: int, repeats: int) -> float:
    """Median over ``repeats`` runs of ``fn()`` [s], divided by ``count``; one warm-up run first."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times) / count


def pin_rnea_cpp_estimate(model, q, qd, qdd, reps: int, repeats: int) -> tuple[float, float, float]:
    """Pinocchio's C++ ``rnea`` per call [s], estimated from Python: ``(t_fixed, t_empty, t_cpp)`` with
    ``t_fixed`` = ``pin.rnea(model, ...)`` looped ``reps`` times on the one state ``(q, qd, qdd)``,
    ``t_empty`` = the same binding call on an empty model (nq = 0: no dynamics), both medians of
    ``repeats`` (:func:`median_per_state`), and ``t_cpp = max(t_fixed - t_empty, 0)``: an upper bound
    of the C++ work (``benchmarks/cpp_pinocchio.py`` measures it in C++)."""
    import pinocchio as pin

    data, m0 = model.createData(), pin.Model()
    d0, z = m0.createData(), np.zeros(0)
    q0, qd0, a0 = (np.array(x, dtype=float) for x in (q, qd, qdd))
    t_fixed = median_per_state(lambda: [pin.rnea(model, data, q0, qd0, a0) for _ in range(reps)], reps, repeats)
    t_empty = median_per_state(lambda: [pin.rnea(m0, d0, z, z, z) for _ in range(reps)], reps, repeats)
    return t_fixed, t_empty, max(t_fixed - t_empty, 0.0)
