"""``rc3r bench``: the benchmark's tables (or one JSON object) and its exit code."""
from __future__ import annotations

import json
import os
import sys

import numpy as np

from ..robots import DEFAULT_ROBOT, robot_class
from . import EXIT


def _si(x: float | None) -> str:
    """Seconds with a readable unit."""
    if x is None or not np.isfinite(x):
        return "-"
    a = abs(x)
    for unit, f in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9)):
        if a >= f or unit == "ns":
            return f"{x / f:.3g} {unit}"
    return f"{x:g} s"


def _table(head: list[str], rows: list[list[str]], right: set[int] = frozenset()) -> str:
    w = [max(len(str(r[i])) for r in [head] + rows) for i in range(len(head))]

    def fmt(r):
        return "  ".join(str(c).rjust(w[i]) if i in right else str(c).ljust(w[i]) for i, c in enumerate(r)).rstrip()

    return "\n".join([fmt(head), "  ".join("-" * x for x in w)] + [fmt(r) for r in rows])


def render_text(r: dict) -> str:
    mc = r["machine"]
    st = r["settings"]
    lines = [f"rc3r bench ({r['mode']}) -- {mc['date_utc']}, {mc['cpu']}, {mc['cpus_usable']} usable CPU(s); "
             f"python {mc['python']}, numpy {mc['numpy']}, numba {mc['numba']}, pinocchio {mc['pinocchio']}", ""]
    lines.append(f"Operations: time per state over N = {st['n_states']} random states, {st['repeats']} repeat(s) "
                 "after a warm-up; 'x rnea' = pin.rnea-loop median / median (times faster).")
    rows = [[k, _si(o["median_s"]), _si(o["min_s"]), f"{o['ratio_to_rnea']:.3g}",
             "-" if k.startswith("pin.") else
             f"{o['ratio_to_pin_equivalent']:.3g} vs {o['pin_equivalent'].split()[0]}"]
            for k, o in r["ops"].items()]
    lines += [_table(["operation", "median/state", "min/state", "x rnea", "x pin equivalent"], rows, {1, 2, 3}), ""]
    cpp = r["pinocchio_cpp_estimate"]
    lines.append(f"Pinocchio C++ cost (ESTIMATE: pin.rnea on a fixed state {_si(cpp['rnea_fixed_state_s'])} minus "
                 f"on an empty model {_si(cpp['rnea_empty_model_s'])}): rnea ~ {_si(cpp['rnea_cpp_estimate_s'])}"
                 f" per call; closed-form tau {_si(cpp['closed_form_tau_s'])} -> ~"
                 f"{cpp['ratio_cpp_estimate_to_closed_form']:.3g}x faster than Pinocchio's C++ (lower bound).")
    lines.append("")
    lines.append("Correctness on the benchmark's states (error measure of rc3r.verify):")
    rows = [[k, str(c["states"]), f"{c['max_abs_err']:.3g}", f"{c['rel_err']:.3g}", "ok" if c["ok"] else "FAIL"]
            for k, c in r["checks"].items()]
    lines += [_table(["check", "states", "max abs err", "rel err", ""], rows, {1, 2, 3}), ""]
    lines.append(f"Simulations (wall = integration only, median of {st['sim_repeats']} run(s); "
                 "execute = simulate + metrics, last run):")
    rows = []
    for k, s in r["sims"].items():
        mode = s["mode"] if s["rate_hz"] is None else f"sampled {s['rate_hz'] / 1000:g} kHz"
        rows.append([k, mode, s["engine"], f"{s['duration_s']:g} s", _si(s["wall_s"]), _si(s["execute_s"]),
                     str(s["rhs_evals"]), s["message"]])
    lines += [_table(["scenario", "mode", "engine", "duration", "wall", "execute", "rhs evals", "status"],
                     rows, {3, 4, 5, 6}), ""]
    if "reference_speedup" in r:
        rs = r["reference_speedup"]
        lines += [f"Fast engine vs reference (Pinocchio ABA + SciPy Radau), robust-perturbed 2 s: "
                  f"{_si(rs['fast_wall_s'])} vs {_si(rs['reference_wall_s'])} -> {rs['speedup']:.3g}x", ""]
    lines.append("Targets:")
    rows = []
    for k, t in r["targets"].items():
        fmt = _si if t["unit"] == "s" else (lambda x: f"{x:.3g}x")
        rows.append([k, f"{t['comparison']} {fmt(t['target'])}", fmt(t["measured"]),
                     "met" if t["met"] else "NOT MET", t["note"]])
    lines += [_table(["target", "limit", "measured", "", "note"], rows, {2}), ""]
    c = r["compile"]
    if "skipped" in c:
        lines.append(f"Compile (numba first call): skipped ({c['skipped']}).")
    else:
        lines.append("Compile (numba first call), fresh interpreter each; cold = empty NUMBA_CACHE_DIR, "
                     "warm = same dir again:")
        rows = []
        for label in ("cold", "warm"):
            x = c.get(label, {})
            if "error" in x:
                rows.append([label, "error: " + x["error"], "", "", "", ""])
                continue
            rows.append([label, _si(x.get("import_s")), _si(x.get("first_inverse_dynamics_s")),
                         _si(x.get("first_continuous_sim_s")), _si(x.get("first_sampled_sim_s")),
                         _si(x.get("process_wall_s"))])
        lines += [_table(["start", "import", "1st inverse_dynamics", "1st continuous sim", "1st sampled sim",
                          "process total"], rows, {1, 2, 3, 4, 5})]
        if "saved_by_cache_s" in c:
            lines.append(f"cache saves {_si(c['saved_by_cache_s'])} per fresh process "
                         f"(cache size {c.get('cache_bytes', 0) / 2 ** 20:.2f} MiB)")
    lines.append("")
    mem = r["memory"]
    if "skipped" in mem:
        lines.append(f"Peak memory of `rc3r paper`: skipped ({mem['skipped']}).")
    elif "error" in mem:
        lines.append(f"Peak memory of `rc3r paper`: error: {mem['error']}")
    else:
        lines.append(f"Peak memory of `rc3r paper`: {mem['peak_rss_mib']:.0f} MiB resident "
                     f"(wall {_si(mem['wall_s'])}, exit {mem['returncode']}).")
    cs = r.get("cold_start", {"skipped": "not run"})
    if "skipped" in cs:
        lines.append(f"Cold start: skipped ({cs['skipped']}).")
    else:
        lines.append(f"Cold start: `{cs['command']}`, a fresh interpreter, empty numba cache (cold), then the "
                     "same cache again (warm), process wall:")
        rows = [[label, _si(cs[label]["wall_s"]), str(cs[label].get("engine")), str(cs[label]["returncode"]),
                 cs[label].get("error", "")] for label in ("cold", "warm") if label in cs]
        lines += [_table(["start", "wall", "engine", "exit", ""], rows, {1}),
                  f"target cold_start_ur5_fbl_1s: <= {_si(cs['target_s'])}: {_si(cs.get('cold', {}).get('wall_s'))} "
                  f"-> {'met' if cs['met'] else 'NOT MET'}"]
    if "integrators" in r:
        lines += ["", _render_integrators(r["integrators"])]
    if "generic" in r:
        lines += ["", _render_generic(r["generic"])]
    if "throughput" in r:
        lines += ["", _render_throughput(r["throughput"])]
    if "throughput_ur5" in r:
        lines += ["", _render_throughput(r["throughput_ur5"])]
    if "generated" in r:
        lines += ["", _render_generated(r["generated"])]
    if "design" in r:
        from ..experiments.bench_design import render as render_design

        lines += ["", render_design(r["design"])]
    lines.append("")
    lines.append(f"Correctness: {'all checks pass' if r['checks_ok'] else 'SOME CHECKS FAIL'}. "
                 f"Benchmark wall time {_si(r['total_wall_s'])}.")
    return "\n".join(lines)


def _render_generated(g: dict) -> str:
    """Generated tau (CasADi -> C) against pin.rnea, per state."""
    if "skipped" in g:
        return f"Generated kernels: skipped ({g['skipped']})."
    build = ("from the disk cache" if g["compile_s"] == 0 else
             f"generated {g['generate_s']:.2f} s + compiled {g['compile_s']:.2f} s")
    rows = [["generated rnea (C, one batch call)", _si(g["generated_rnea_s"]),
             f"{g['pin_rnea_loop_s'] / g['generated_rnea_s']:.3g}x"],
            ["pin.rnea loop (Python)", _si(g["pin_rnea_loop_s"]), "1x"],
            ["pin.rnea C++ (ESTIMATE: fixed state - empty model)", _si(g["cpp_rnea_estimate_s"]),
             f"{g['pin_rnea_loop_s'] / g['cpp_rnea_estimate_s']:.3g}x" if g["cpp_rnea_estimate_s"] > 0 else "-"]]
    t = g["target"]
    return "\n".join([
        f"Generated kernels (rc3r.robots.generated, {g['robot']}, {build}): per state over {g['states']} states, "
        f"median of {g['repeats']}; check vs pin.rnea max rel err {g['check']['max_rel_err']:.1e} "
        f"({'ok' if g['check']['ok'] else 'FAILED'}):",
        _table(["kernel", "per state", "x pin.rnea loop"], rows, {1, 2}),
        f"target generated_tau_vs_cpp_rnea: <= {t['limit']:g}x: {t['ratio']:.3g}x -> {'met' if t['met'] else 'NOT MET'} "
        "(benchmarks/cpp_pinocchio.py --robot ur5 measures the C++ side in C++)"])


def _render_integrators(g: dict) -> str:
    """Rosenbrock vs SciPy on the same compiled right-hand side."""
    lines = ["Integrators on the same compiled closed loop (rtol 1e-6, atol 1e-8; 'q diff' = max |q - q_yardstick|, "
             "yardstick SciPy Radau rtol 1e-10; 'vs default' = wall over that of the method the run's default options take):"]
    rows = []
    for run, x in g.items():
        for label, m in x["methods"].items():
            rows.append([run, label, _si(m["wall_s"]), f"{m['x_default']:.3g}x", str(m["rhs_evals"]),
                         f"{m['max_q_diff_rad']:.2g}", "ok" if m["ok"] else "FAILED"])
    return "\n".join(lines + [_table(["run", "method", "wall", "vs default", "rhs evals", "q diff [rad]", ""],
                                     rows, {2, 3, 4, 5})])


def _render_throughput(t: dict) -> str:
    """Campaign runs per minute with 1 and 2 workers."""
    rows = [[str(k), str(v["runs"]), _si(v["wall_s"]), f"{v['runs_per_min']:.0f}"] for k, v in t["workers"].items()]
    tg = t["target"]
    tail = [f"2 vs 1 worker(s): {t['speedup_2_vs_1']:.2f}x" if "speedup_2_vs_1" in t else "",
            f"target >= {tg['runs_per_min']:.0f} runs/min of 10 s: {tg['measured']:.0f} -> "
            f"{'met' if tg['met'] else 'NOT MET'} {tg['note']}".rstrip()]
    arm = t.get("robot", "rr3") + (" with a payload at 1 kHz" if t.get("config") else "")
    return "\n".join([f"Campaign throughput ({arm}): rc3r montecarlo jobs, {'/'.join(t['controllers'])} on "
                      f"{t['n_plants']} "
                      f"plants, {t['duration_s']:g} s each (pool start and fsynced rows included):",
                      _table(["workers", "runs", "wall", "runs/min"], rows, {1, 2, 3})] + [x for x in tail if x])


def _render_generic(g: dict) -> str:
    """The generic-robot section: regressor vs rnea per robot, the UR5 payload runs, targets."""
    lines = ["Generic URDF arms (PinocchioRobot), Slotine-Li Y per state vs one pin.rnea call, same run:", ""]
    rows = [[name, str(x["n"]), str(x["p"]), _si(x["regressor_us"] * 1e-6), _si(x["regressor_single_us"] * 1e-6),
             _si(x.get("pinocchio_path_us", float("nan")) * 1e-6), _si(x["rnea_us"] * 1e-6), f"{x['ratio']:.2f}x"]
            for name, x in g["regressor"].items()]
    lines += [_table(["robot", "n", "p", "Y (batch)", "Y (one call/state)", "Y (2 Pinocchio calls)", "pin.rnea",
                      "Y batch / rnea"], rows, {1, 2, 3, 4, 5, 6, 7}), ""]
    rows = [[k, v["engine"], v["status"], f"{v['duration_s']:g} s", _si(v["wall_s"]), _si(v.get("per_step_s")),
             f"{v.get('rnea_per_step', float('nan')):.3g}", f"{v['max_abs_error']:.3g}"] for k, v in g["runs"].items()]
    lines += [_table(["run", "engine", "status", "simulated", "wall", "per step", "pin.rnea / step", "max|e| [rad]"],
                     rows, {3, 4, 5, 6, 7}), ""]
    for key, t in g["targets"].items():
        val = f"{t['measured']:.3g} {t['unit']}" + (" (extrapolated to 10 s)" if t["extrapolated"] else "")
        lines.append(f"target {key}: {t['op']} {t['limit']:g} {t['unit']}: {val} -> "
                     f"{'met' if t['met'] else 'NOT MET'}")
    return "\n".join(lines)


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if np.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def _progress(msg: str) -> None:
    print(f"[bench] {msg}", file=sys.stderr, flush=True)


def cmd_bench(args) -> int:
    """``rc3r bench [--json] [--quick]``: print the tables (or one JSON object); 1 if a check fails."""
    quick = bool(getattr(args, "quick", False))
    os.environ["RC3R_COLD_START"] = "compile"  # the benchmark times compiled code (its cold-start row unsets it)
    from ..experiments.bench3r import run_bench

    r = run_bench(quick=quick, progress=_progress)
    from ..experiments.bench_generic import bench_generic

    r["generic"] = bench_generic(quick=quick, progress=_progress)
    from ..experiments.bench_campaign import bench_throughput

    r["throughput"] = bench_throughput(n_plants=2 if quick else 100, duration=0.5 if quick else 10.0,
                                       progress=_progress)
    r["throughput_ur5"] = bench_throughput(n_plants=2 if quick else 100, duration=0.5 if quick else 10.0,
                                           robot="ur5", progress=_progress,
                                           config={"payload": {"mass": [0.0, 3.0]}, "simulation": {"rate": 1000.0}})
    from ..experiments.bench_generated import bench_generated

    r["generated"] = bench_generated("ur5", quick=quick, progress=_progress)
    if "check" in r["generated"]:
        r["checks_ok"] = r["checks_ok"] and r["generated"]["check"]["ok"]
    from ..experiments.bench_design import bench_design
    from . import main

    r["design"] = bench_design(main, quick=quick, progress=_progress)
    if getattr(args, "json", False):
        print(json.dumps(_jsonable(r), indent=2))
    else:
        print(render_text(r))
    if not r["checks_ok"]:
        print("rc3r: error: the closed form disagrees with Pinocchio on the benchmark's states", file=sys.stderr)
        return EXIT["check_failed"]
    return EXIT["ok"]
