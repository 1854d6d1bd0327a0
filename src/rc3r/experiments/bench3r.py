r"""``rc3r bench``: closed form vs Pinocchio, simulation wall times, compile time, memory.

Everything is measured side by side in one run, on one machine; nothing is read
from files and nothing is written (except temporary directories of the
subprocess measurements, removed afterwards).

Operations (``ops``)
    Per-state cost of the closed form (:mod:`.regressor`, :mod:`.model`,
    the compiled kernels of :mod:`.kernels`) and of Pinocchio's ``rnea``,
    ``aba``, ``crba`` looped from Python over the *same* random states.
    Each is timed with :func:`time.perf_counter` after a warm-up call (numba
    compilation or cache load), ``repeats`` times; ``median_s``/``min_s`` are per
    state. ``ratio_to_rnea`` = median of the ``pin.rnea loop`` / median of the
    operation, i.e. *how many times faster than pin.rnea from Python* (the
    ``pin.rnea loop`` row is 1). That loop is the ordinary one,
    ``for i in range(N): pin.rnea(model, data, Q[i], QD[i], QDD[i])``; the row
    ``pin.rnea loop (pre-split)`` iterates over lists of 1-D arrays made
    beforehand (no numpy indexing in the timed loop), the cheapest way to call
    Pinocchio per state from Python, and the targets also report the speed-up
    against it. Results of the Pinocchio loops are discarded.

    Pinocchio's own C++ cost cannot be timed from Python. ``pinocchio_cpp_estimate``
    subtracts the cost of the same binding call on an *empty* model (``pin.rnea``
    with nq = 0: same argument conversion, no dynamics) from the cost of ``pin.rnea``
    on one fixed state. Converting 3-vectors costs a little more than 0-vectors,
    so this over-estimates the C++ time (the ratio is a lower bound on the
    speed-up over the C++ code); it is labelled an estimate everywhere.

Correctness (``checks``)
    The benchmark verifies its own results on its states: closed-form torques vs
    ``pin.rnea``, Slotine-Li ``Y(q, qd, v, a) theta`` vs ``crba a + C(q, qd) v + g``,
    ``M`` vs ``crba``, closed-form forward dynamics vs ``aba``. Error measure and
    tolerance are those of :mod:`rc3r.verify`. A failed check makes the command
    return 1; a missed *timing* target does not (it is reported).

Simulations (``sims``)
    :func:`rc3r.experiments.paper3r.scenarios` in continuous time, FBL-perturbed and
    robust-perturbed sampled at 1 kHz (the robust law with the paper's gains
    diverges at 1 kHz; the run stops early, which is reported), and, in the full
    mode only, robust-perturbed for 2 s with the fast and the reference engine
    (Pinocchio ABA + SciPy Radau). ``wall_s`` is :attr:`SimResult.wall_time_s`
    (the integration; metrics excluded) -- median over repeats.

Compile (``compile``), memory (``memory``) and the cold start (``cold_start``), full mode only (:mod:`.bench_startup`)
    Cold start (``NUMBA_CACHE_DIR`` = a fresh empty directory) vs warm start (the
    same directory again), each a fresh interpreter: import, first torque call,
    first continuous and sampled simulation. Peak resident memory of
    ``rc3r paper`` (into a temporary directory) from ``getrusage(RUSAGE_CHILDREN)``
    of a wrapper process that has no other child.

``--quick`` (CI: correctness only): 1 000 states, 1 repeat, 0.5 s simulations, no
reference engine, no subprocesses. Timing targets are still evaluated (simulation
times extrapolated to 10 s) but mean little at that size.
"""
from __future__ import annotations

import datetime as _dt
import os
import platform
import time

import numpy as np
from numba import njit

from .._trig import sincos
from ._report import _REPORT, _progress
from ..robots.rr3 import kernels as K

__all__ = ["run_bench", "TARGETS"]

#: The issue's targets: name -> (limit, comparison, unit, description).
TARGETS = {
    "tau_per_state": (35e-9, "<=", "s", "closed-form tau = Y(q,qd,qdd) theta per state, bulk or in compiled code "
                      "(the speed issue's 35 ns; was 100 ns)"),
    "tau_speedup_vs_rnea": (10.0, ">=", "x", "closed-form tau vs pin.rnea looped from Python"),
    "slotine_li_per_state": (1e-7, "<=", "s", "Slotine-Li Y(q,qd,v,a) per state, bulk or in compiled code"),
    "slotine_li_speedup_vs_rnea": (10.0, ">=", "x", "Slotine-Li Y vs pin.rnea looped from Python"),
    "robust_perturbed_continuous_10s": (0.12, "<=", "s", "robust-perturbed, 10 s, continuous: wall time "
                                        "(the speed issue's 0.12 s; was 1 s)"),
    "paper_five_continuous_10s": (5.0, "<=", "s", "all five paper scenarios, 10 s, continuous: total wall"),
    "fbl_perturbed_sampled_1khz_10s": (0.1, "<=", "s", "FBL-perturbed, 10 s, sampled at 1 kHz: wall time"),
}

_SEED = 20261122
_JIT = dict(cache=True, nogil=True)


# ---- compiled helpers: the library's kernels called from a compiled loop ----------------


@njit(**_JIT)
def _slotine_li_in_loop(th, Q, QD, V, A, l2, g0, out):
    """Y(q, qd, v, a) by the library kernel (scalar arguments, no row views) into one
    reused 3x15; ``out[n] = Y theta`` keeps the result alive and checkable."""
    Y = np.empty((3, 15))
    for n in range(Q.shape[0]):
        K.slotine_li_scalars(Q[n, 1], Q[n, 2], QD[n, 0], QD[n, 1], QD[n, 2], V[n, 0], V[n, 1], V[n, 2],
                             A[n, 0], A[n, 1], A[n, 2], l2, g0, Y)
        for i in range(3):
            acc = 0.0
            for j in range(15):
                acc += Y[i, j] * th[j]
            out[n, i] = acc


@njit(**_JIT)
def _trig_in_loop(Q, out):
    """The closed form's angles through :func:`rc3r._trig.sincos`, one state at a time (range-checked,
    not in SIMD lanes): what one reduction per angle saves on its own."""
    for n in range(Q.shape[0]):
        s2, c2 = sincos(Q[n, 1])
        s3, c3 = sincos(Q[n, 2])
        out[n, 0] = s2 + c2
        out[n, 1] = s3 + c3
        out[n, 2] = (s2 * c3 + c2 * s3) + (c2 * c3 - s2 * s3)


@njit(**_JIT)
def _libm_trig_in_loop(Q, out):
    """The same angles through the per-state path's four libm calls (:func:`.kernels._trig`; numba's
    vector math SVML is off here: the llvmlite wheel is not SVML-patched)."""
    for n in range(Q.shape[0]):
        s2, c2, s3, c3, s23, c23 = K._trig(Q[n, 1], Q[n, 2])
        out[n, 0] = s2 + c2
        out[n, 1] = s3 + c3
        out[n, 2] = s23 + c23


@njit(**_JIT)
def _forward_dynamics_in_loop(th, Q, QD, U, l2, g0, out):
    """qdd = M^-1 (u - S qd - g) by the library kernel (the fast plant); returns #not-PD."""
    w33 = np.empty((3, 3))
    w3 = np.empty(3)
    bad = 0
    for n in range(Q.shape[0]):
        if not K.forward_dynamics_into(th, Q[n], QD[n], U[n], l2, g0, out[n], w33, w3):
            bad += 1
    return bad


# ---- small utilities --------------------------------------------------------------------


def _time(fn, repeats: int) -> tuple[float, float]:
    """(median, min) wall time of ``fn()`` in seconds over ``repeats`` calls (after one warm-up)."""
    fn()
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), float(min(ts))


def _compare(x, ref) -> dict:
    """Error measure of :mod:`rc3r.verify`: max |x - ref|, relative to max(1, max |ref|)."""
    from ..verify import TOL

    x = np.asarray(x, float)
    ref = np.asarray(ref, float)
    err = float(np.max(np.abs(x - ref))) if x.size else 0.0
    scale = float(np.max(np.abs(ref))) if ref.size else 0.0
    rel = err / max(1.0, scale)
    return {"max_abs_err": err, "max_abs_ref": scale, "rel_err": rel, "tol": TOL,
            "states": int(x.shape[0]), "ok": bool(np.isfinite(rel) and rel <= TOL)}


def _machine() -> dict:
    import numba
    import pinocchio as pin
    import scipy

    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    from .. import __version__

    return {
        "date_utc": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "cpu": cpu, "cpu_count": os.cpu_count(), "cpus_usable": usable,
        "platform": platform.platform(), "python": platform.python_version(),
        "numpy": np.__version__, "numba": numba.__version__, "scipy": scipy.__version__,
        "pinocchio": pin.__version__, "rc3r": __version__,
    }


# ---- operations -------------------------------------------------------------------------


def _states(n: int, rng) -> dict:
    """Random joint states: q in [-pi, pi], qd/v in [-5, 5] rad/s, qdd/a in [-20, 20] rad/s^2,
    u in [-200, 200] N m."""
    return {
        "Q": rng.uniform(-np.pi, np.pi, (n, 3)), "QD": rng.uniform(-5, 5, (n, 3)),
        "QDD": rng.uniform(-20, 20, (n, 3)), "V": rng.uniform(-5, 5, (n, 3)),
        "A": rng.uniform(-20, 20, (n, 3)), "U": rng.uniform(-200, 200, (n, 3)),
    }


def bench_ops(n: int, repeats: int) -> tuple[dict, dict, dict]:
    """Time the closed form and Pinocchio on ``n`` states; return (ops, checks, cpp_estimate)."""
    import pinocchio as pin

    from ..robots.rr3 import model as mdl
    from ..robots.rr3 import regressor as reg
    from ..robots.rr3.params import theta as theta_of
    from ..robots.rr3.urdf import load_arm

    arm = load_arm(None)
    m, d = arm.model, arm.model.createData()
    th = theta_of(arm.params)
    l2, g0 = float(arm.params.lengths[1]), float(arm.params.g0)
    S = _states(n, np.random.default_rng(_SEED))
    Q, QD, QDD, V, A, U = (S[k] for k in ("Q", "QD", "QDD", "V", "A", "U"))
    Ql, QDl, QDDl = list(Q), list(QD), list(QDD)
    rnea, aba, crba = pin.rnea, pin.aba, pin.crba

    def rnea_loop():
        for i in range(n):
            rnea(m, d, Q[i], QD[i], QDD[i])

    def rnea_presplit():
        for a, b, c in zip(Ql, QDl, QDDl):
            rnea(m, d, a, b, c)

    def aba_loop():
        for i in range(n):
            aba(m, d, Q[i], QD[i], U[i])

    def crba_loop():
        for i in range(n):
            crba(m, d, Q[i])

    out3 = np.empty((n, 3))
    out3a = np.empty((n, 3))
    out3b = np.empty((n, 3))
    out3c = np.empty((n, 3))
    # (name, fn, what it computes, Pinocchio equivalent)
    specs = [
        ("pin.rnea loop", rnea_loop, "tau = RNEA(q, qd, qdd): for i in range(N): pin.rnea(.., Q[i], ..)",
         "pin.rnea loop"),
        ("pin.rnea loop (pre-split)", rnea_presplit,
         "same over lists of 1-D arrays made beforehand (best case for Pinocchio)", "pin.rnea loop"),
        ("pin.aba loop", aba_loop, "qdd = ABA(q, qd, u), Python loop (indexing as pin.rnea loop)",
         "pin.aba loop"),
        ("pin.crba loop", crba_loop, "M(q) = CRBA(q), Python loop (indexing as pin.rnea loop)", "pin.crba loop"),
        ("inverse_dynamics batch", lambda: reg.inverse_dynamics(th, Q, QD, QDD, l2=l2, g0=g0),
         "tau = Y(q,qd,qdd) theta, rc3r.regressor.inverse_dynamics on (N,3)", "pin.rnea loop"),
        ("inverse_dynamics compiled", lambda: K.inverse_dynamics_batch(th, Q, QD, QDD, l2, g0, out3),
         "same, compiled loop called directly (no wrapper, output preallocated)", "pin.rnea loop"),
        ("sincos scalar compiled", lambda: _trig_in_loop(Q, out3a),
         "the model's angles through 2 rc3r._trig.sincos per state, one state at a time", "pin.rnea loop"),
        ("libm trig compiled", lambda: _libm_trig_in_loop(Q, out3a),
         "the same angles by 4 libm sin/cos per state (the per-state path's kernels._trig)", "pin.rnea loop"),
        ("slotine_li_regressor batch", lambda: reg.slotine_li_regressor(Q, QD, V, A, l2=l2, g0=g0),
         "Y(q,qd,v,a) materialized (N,3,15)", "pin.rnea loop"),
        ("slotine_li compiled", lambda: _slotine_li_in_loop(th, Q, QD, V, A, l2, g0, out3b),
         "Y(q,qd,v,a) into a reused 3x15 inside compiled code, then Y theta", "pin.rnea loop"),
        ("regressor batch", lambda: reg.regressor(Q, QD, QDD, l2=l2, g0=g0),
         "Y(q,qd,qdd) materialized (N,3,15)", "pin.rnea loop"),
        ("mass_matrix batch", lambda: mdl.mass_matrix(th, Q), "M(q) (N,3,3)", "pin.crba loop"),
        ("forward_dynamics compiled", lambda: _forward_dynamics_in_loop(th, Q, QD, U, l2, g0, out3c),
         "qdd = M^-1(u - S qd - g), the fast plant's kernel in a compiled loop", "pin.aba loop"),
    ]
    ops = {}
    for name, fn, what, equiv in specs:
        _progress(f"op {name} (N = {n}, {repeats} repeats) ...")
        med, mn = _time(fn, repeats)
        ops[name] = {"median_s": med / n, "min_s": mn / n, "what": what, "n_states": n,
                     "repeats": repeats, "pin_equivalent": equiv}
    base = ops["pin.rnea loop"]["median_s"]
    for name, o in ops.items():
        o["ratio_to_rnea"] = base / o["median_s"]
        o["ratio_to_pin_equivalent"] = ops[o["pin_equivalent"]]["median_s"] / o["median_s"]

    # ---- correctness on the same states (untimed) ----
    _progress("checking the closed form against Pinocchio on the benchmark's states ...")
    tau_ref = np.array([np.array(rnea(m, d, a, b, c)) for a, b, c in zip(Ql, QDl, QDDl)])
    checks = {
        "inverse_dynamics vs pin.rnea": _compare(reg.inverse_dynamics(th, Q, QD, QDD, l2=l2, g0=g0), tau_ref),
        "inverse_dynamics compiled vs pin.rnea": _compare(out3, tau_ref),
        "regressor @ theta vs pin.rnea": _compare(reg.regressor(Q, QD, QDD, l2=l2, g0=g0) @ th, tau_ref),
    }
    k = min(n, 2000)  # Slotine-Li, M and ABA references need several Pinocchio calls per state
    sl_ref = np.empty((k, 3))
    M_ref = np.empty((k, 3, 3))
    fd_ref = np.empty((k, 3))
    for i in range(k):
        Mi = np.array(crba(m, d, Q[i]))
        Mi = np.triu(Mi) + np.triu(Mi, 1).T  # Pinocchio fills the upper triangle
        C = np.array(pin.computeCoriolisMatrix(m, d, Q[i], QD[i]))
        gv = np.array(pin.computeGeneralizedGravity(m, d, Q[i]))
        sl_ref[i] = Mi @ A[i] + C @ V[i] + gv
        M_ref[i] = Mi
        fd_ref[i] = np.array(aba(m, d, Q[i], QD[i], U[i]))
    checks["slotine_li_regressor @ theta vs crba a + C v + g"] = _compare(
        reg.slotine_li_regressor(Q[:k], QD[:k], V[:k], A[:k], l2=l2, g0=g0) @ th, sl_ref)
    checks["slotine_li compiled vs crba a + C v + g"] = _compare(out3b[:k], sl_ref)
    checks["mass_matrix vs pin.crba"] = _compare(mdl.mass_matrix(th, Q[:k]).reshape(k, 9), M_ref.reshape(k, 9))
    checks["forward_dynamics compiled vs pin.aba"] = _compare(out3c[:k], fd_ref)

    # ---- Pinocchio's C++ cost: an estimate (see the module docstring) ----
    _progress("estimating Pinocchio's C++ cost (binding overhead subtracted) ...")
    from .bench_generic import pin_rnea_cpp_estimate

    t_same, t_empty, t_cpp = pin_rnea_cpp_estimate(m, Q[0], QD[0], QDD[0], max(n, 20000), repeats)
    best_tau = min(ops["inverse_dynamics compiled"]["median_s"], ops["inverse_dynamics batch"]["median_s"])
    cpp = {
        "estimate": True,
        "method": "median per call of pin.rnea on one fixed state minus pin.rnea on an empty model "
                  "(nq = 0: same binding path, no dynamics), both looped from Python",
        "rnea_fixed_state_s": t_same, "rnea_empty_model_s": t_empty, "rnea_cpp_estimate_s": t_cpp,
        "closed_form_tau_s": best_tau,
        "ratio_cpp_estimate_to_closed_form": (t_cpp / best_tau) if best_tau > 0 else None,
        "note": "upper bound on the C++ time (3-vectors cost more to convert than 0-vectors), "
                "so the ratio is a lower bound on the speed-up over Pinocchio's C++",
    }
    return ops, checks, cpp


# ---- simulations ------------------------------------------------------------------------


def _sim_row(spec, res, walls, execute_s) -> dict:
    from ..simulate import file_status

    o = spec.options
    return {
        "wall_s": float(np.median(walls)), "min_wall_s": float(min(walls)), "repeats": len(walls),
        "execute_s": execute_s, "rhs_evals": int(res.rhs_evals), "steps": int(res.steps),
        "rejected_steps": int(res.rejected_steps), "status": file_status(res), "message": res.message,
        "t_end": float(res.t_end), "duration_s": float(o.duration), "mode": o.mode,
        "rate_hz": o.rate, "engine": o.engine,
    }


def _run(spec, repeats: int):
    from ..runspec import execute

    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        res, _m = execute(spec)
        execute_s = time.perf_counter() - t0
        walls.append(res.wall_time_s)
    return _sim_row(spec, res, walls, execute_s)


def bench_sims(duration: float, repeats: int, reference: bool) -> dict:
    from ..runspec import build_run, execute
    from .paper3r import scenarios as paper_scenarios

    # warm-up: compile or load every integrator/law combination used below
    _progress("warming up the simulator (numba compile or cache load) ...")
    for spec in paper_scenarios(duration=0.01) + paper_scenarios(duration=0.01, rate=1000.0):
        execute(spec)
    sims = {}
    specs = paper_scenarios(duration=duration)
    for k, spec in enumerate(specs, 1):
        _progress(f"sim [{k}/{len(specs)}] {spec.name}, continuous, {duration:g} s, {repeats} repeats ...")
        sims[spec.name] = _run(spec, repeats)
    for c in ("fbl", "robust"):
        spec = build_run(controller=c, perturbed=True, eps=0.5 if c == "robust" else None, rate=1000.0,
                         duration=duration, name=f"{c}-perturbed@1kHz")
        _progress(f"sim {spec.name}, sampled 1 kHz, {duration:g} s ...")
        sims[spec.name] = _run(spec, repeats)
    if reference:
        d = 2.0
        for engine in ("fast", "reference"):
            spec = build_run(controller="robust", perturbed=True, eps=0.5, duration=d, engine=engine,
                             name=f"robust-perturbed-{d:g}s-{engine}")
            slow = " (Pinocchio ABA + SciPy Radau, slow)" if engine == "reference" else ""
            _progress(f"sim {spec.name}, continuous, {d:g} s, engine {engine}{slow} ...")
            sims[spec.name] = _run(spec, 1 if engine == "reference" else repeats)
    return sims


# ---- targets ----------------------------------------------------------------------------


def _targets(ops: dict, sims: dict, duration: float) -> dict:
    def entry(name, measured, note=""):
        limit, cmp, unit, desc = TARGETS[name]
        met = bool(measured <= limit) if cmp == "<=" else bool(measured >= limit)
        return {"target": limit, "comparison": cmp, "unit": unit, "measured": float(measured),
                "met": met, "description": desc, "note": note}

    rnea = ops["pin.rnea loop"]["median_s"]
    rnea_best = ops["pin.rnea loop (pre-split)"]["median_s"]
    t = {}
    for key, bulk, comp in (("tau", "inverse_dynamics batch", "inverse_dynamics compiled"),
                            ("slotine_li", "slotine_li_regressor batch", "slotine_li compiled")):
        best = min((bulk, comp), key=lambda k: ops[k]["median_s"])
        tb = ops[best]["median_s"]
        floor = ops["sincos scalar compiled"]["median_s"] if key == "tau" else None
        libm = ops["libm trig compiled"]["median_s"] if key == "tau" else None
        t[f"{key}_per_state"] = entry(f"{key}_per_state", tb, f"best of '{bulk}' and '{comp}': '{best}' (median)"
                                      + (f"; SIMD blocks of sincos_fast; scalar trigonometry alone {floor * 1e9:.3g} ns, by libm "
                                            f"{libm * 1e9:.3g} ns"
                                         if floor else ""))
        t[f"{key}_speedup_vs_rnea"] = entry(
            f"{key}_speedup_vs_rnea", rnea / tb,
            f"pin.rnea loop median / '{best}' median; vs the pre-split loop: {rnea_best / tb:.3g}x")
    scale = 10.0 / duration
    note = "" if duration == 10.0 else f"extrapolated from {duration:g} s runs (x {scale:g}): indicative only"
    t["robust_perturbed_continuous_10s"] = entry("robust_perturbed_continuous_10s",
                                                 sims["robust-perturbed"]["wall_s"] * scale, note)
    five = ("fbl-ideal", "robust-ideal", "fbl-perturbed", "robust-perturbed", "robust-perturbed-eps0.05")
    t["paper_five_continuous_10s"] = entry("paper_five_continuous_10s",
                                           sum(sims[s]["wall_s"] for s in five) * scale,
                                           (note + "; " if note else "") + "sum of the five medians")
    t["fbl_perturbed_sampled_1khz_10s"] = entry("fbl_perturbed_sampled_1khz_10s",
                                                sims["fbl-perturbed@1kHz"]["wall_s"] * scale, note)
    return t


# ---- the whole benchmark ----------------------------------------------------------------


def run_bench(quick: bool = False, progress=None) -> dict:
    """Run everything; return the JSON-ready result (see the module docstring)."""
    _REPORT[0] = progress or (lambda msg: None)
    t_start = time.perf_counter()
    n, repeats = (1000, 1) if quick else (100_000, 7)
    duration, sim_repeats = (0.5, 1) if quick else (10.0, 3)
    out = {"mode": "quick" if quick else "full", "machine": _machine(),
           "settings": {"n_states": n, "repeats": repeats, "sim_duration_s": duration,
                        "sim_repeats": sim_repeats, "seed": _SEED}}
    ops, checks, cpp = bench_ops(n, repeats)
    out["ops"] = ops
    out["checks"] = checks
    out["pinocchio_cpp_estimate"] = cpp
    out["sims"] = bench_sims(duration, sim_repeats, reference=not quick)
    if not quick and "robust-perturbed-2s-reference" in out["sims"]:
        f, r = out["sims"]["robust-perturbed-2s-fast"], out["sims"]["robust-perturbed-2s-reference"]
        out["reference_speedup"] = {"fast_wall_s": f["wall_s"], "reference_wall_s": r["wall_s"],
                                    "speedup": r["wall_s"] / f["wall_s"] if f["wall_s"] > 0 else None}
    out["targets"] = _targets(ops, out["sims"], duration)
    from .bench_methods import bench_integrators
    out["integrators"] = bench_integrators(duration, progress=_progress)
    skip = {"skipped": "quick mode"}
    from .bench_startup import bench_cold_start, bench_compile, bench_memory

    out["compile"] = skip if quick else bench_compile()
    out["memory"] = skip if quick else bench_memory()
    out["cold_start"] = skip if quick else bench_cold_start()
    out["checks_ok"] = all(c["ok"] for c in checks.values())
    out["total_wall_s"] = time.perf_counter() - t_start
    return out


# ---- text output ------------------------------------------------------------------------
