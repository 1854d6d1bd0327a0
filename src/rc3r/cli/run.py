"""``rc3r run``, ``rc3r paper``: simulations, their files and figures.

Every output file is written atomically (:mod:`rc3r.io`); progress goes to stderr.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path


from ..errors import ConfigError, DivergenceError
from ..io import atomic_savefig, atomic_write_json, atomic_write_text, read_config
from ..robots import DEFAULT_ROBOT, robot_class
from ..simulate._fast import effect_codes, planned, simulator
from ..simulate.metrics import CHATTERING_DEFINITION
from ..provenance import provenance
from ..runspec import build_run, execute
from . import EXIT
from ._output import check_output_path, output_dir


def _progress(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def announce_compile(plant, rate=False, spec=None) -> None:
    """Say so before a first run compiles the robot's simulator (numba, once; measured on the 2-core machine:
    the 3R's continuous integrator 34 s and its sampled one 20 s (``rc3r bench``, 2026-12-05), 87 s of CPU for
    the UR5 chain engine (2026-12-02)); ``spec``: the run (a :class:`rc3r.runspec.RunSpec`), whose law and
    plant effects choose the instance (:meth:`rc3r.simulate._fast.CompiledSimulator.for_run`), else the
    instance of every registered law and effect."""
    eng = simulator(plant)
    which = None if rate is False else ("continuous" if rate is None else "sampled")  # False: both modes
    law, fx = None, None
    if spec is not None and spec.law.code is not None:
        law = spec.law.code
        fx = spec.true_plant.pack() if spec.true_plant is not None else None
    if eng is not None and not eng.is_cached(which, law, fx):
        small = {"continuous": "about 35 s", "sampled": "about 20 s"}.get(which, "about a minute")
        what = small if plant.n <= 3 else "1-2 minutes for a 6-joint arm"
        _progress(f"rc3r: compiling the simulator's kernels (numba): {what}, once; cached on disk afterwards")


#: A sampled run on more default sub-steps per period than this says why (:func:`announce_engine`).
STIFF_NOTE_SUBSTEPS = 16


def own_instance(spec) -> tuple[tuple, tuple]:
    """``(laws, effects)``: the codes of the run's own law and its plant's effects, the plan of ``rc3r run``
    (:func:`rc3r.simulate._fast.plan`): one law per process, so its compiled instance has the one law's
    branch, not the library default's three (``docs/performance.md``, "Compile instances")."""
    fx = spec.true_plant.pack() if spec.true_plant is not None else None
    return ((spec.law.code,) if spec.law.code is not None else ()), effect_codes(fx)


def announce_engine(spec) -> str | None:
    """:func:`announce_compile` if the run will compile its simulator; if ``auto`` takes the python engine
    because the compiled one is not built yet (a short sampled run, :func:`rc3r.simulate.planned_engine`),
    return the note that says so and how to build it (None otherwise).

    The note is informational: the caller prints it after a run that finished, never beside the one
    error line of a run that diverged (``rc3r run``)."""
    from ..simulate import default_substeps, plant_method, planned_engine, stiffness

    plant = spec.true_plant if spec.true_plant is not None else spec.true_rigid
    opt = spec.options
    if opt.rate is not None and opt.nsub is None:
        lam = stiffness(plant)
        nsub = default_substeps(plant, opt.rate, lam)
        method = plant_method(plant, opt, lam)
        if method in ("sdirk", "ros4", "rodas"):
            _progress(f"rc3r: stiff friction (it damps a joint at up to {lam:.3g} 1/s): the plant is advanced by "
                      f"adaptive L-stable {method.upper()} steps per period instead of {nsub} RK4 sub-steps "
                      "([simulation] sampled_method)")
        elif nsub > STIFF_NOTE_SUBSTEPS:
            _progress(f"rc3r: stiff friction (it damps a joint at up to {lam:.3g} 1/s): {nsub} RK4 "
                      f"sub-steps per {1e3 / opt.rate:g} ms period, the run costs about {nsub} times a rigid plant's")
    name, why = planned_engine(plant, spec.law, opt)
    if why is not None:
        from ..simulate.engines.base import COLD_MAX_SUBSTEPS

        return (f"rc3r: python engine: the compiled one is passed over, {why}; a run of over "
                f"{COLD_MAX_SUBSTEPS} sub-steps, --engine fast or RC3R_COLD_START=compile builds it (once)")
    if name == "fast":
        announce_compile(spec.true_rigid, spec.options.rate, spec)
    return None


def _fmt3(x) -> str:
    return " ".join(f"{v:.3g}" for v in x)


def verdict_text(m: dict) -> str:
    """``clean, within 0.01 rad`` / ``chattering (joints 1, 3), tolerance 0.01 rad missed`` ...: the
    first words of a run's summary line."""
    word = verdict_word(m) if "verdict" in m else m.get("status")
    if word == "saturated" and m.get("saturation_fraction") is not None:
        word += f" ({100 * m['saturation_fraction']:.1f} % of samples at a torque limit)"
    met = m.get("tolerance_met")
    if met is not None:
        word += f", {'within' if met else 'outside'} {m['tolerance']:g} rad"
    return word


def plant_options(args) -> dict:
    """The arm and plant keywords of :func:`rc3r.build_run` from the options of :func:`rc3r.cli.plant_args`.

    ``effects`` holds the ``[plant]`` keys the registered effects' options set (:attr:`rc3r.plants.Effect.cli`:
    ``--friction`` -> ``friction``, ``--torque-limit`` -> ``torque_limit``, ...), only those given."""
    from ..plants import registered

    out = {k: getattr(args, k, None) for k in ("urdf", "noise", "delay", "plant_engine", "tolerance", "bounds")}
    locks = getattr(args, "lock", None)
    out["lock"] = dict(locks) if locks else None
    out["effects"] = {o.key: getattr(args, o.dest) for c in registered() for o in c.cli
                      if getattr(args, o.dest, None) is not None}
    return out


def model_friction_config(cfg: dict, args) -> dict:
    """``cfg`` with ``--model-friction`` (if given) as its ``[model] friction``: the option replaces the config's
    value whole (docs/control.md, "Friction with a box or a payload")."""
    value = args.model_friction
    if value is None:
        return cfg
    return dict(cfg, model=dict(cfg.get("model", {}), friction=value))


def describe_model(spec) -> str:
    """What the plant is and what the controller knows of it, for the run's announcement.

    The plant is the true robot (``spec.true_rigid.label``, "the nominal robot" when it is that one);
    the controller's model is theta_0 and rho with the short form of their sources
    (``spec.model``), or the plant's own theta in an ideal run. A perturbed run's perturbation is
    in the controller's model, not in the plant.
    """
    model = spec.model
    plant = f"plant '{spec.true_rigid.label}'"
    if spec.true_rigid.label == model.get("nominal"):
        plant += " (the nominal robot)"
    elif spec.true_rigid.label == "centre" and "bounds" in (model.get("theta_source") or ""):
        plant += " (the identified robot: the bounds' centre)"
    if spec.scenario != "perturbed" and (model.get("theta_source") or "").startswith("theta of the plant"):
        return f"{plant}; controller model = the plant's theta (ideal)" + _effects_text(spec)
    short = lambda src: (src or "").split(":")[0]  # noqa: E731 - the source up to its formula
    out = f"{plant}; controller model ({spec.scenario}): {short(model.get('theta_source'))}"
    if model.get("rho") is not None:
        out += f", rho = {model['rho']:.6g} ({short(model.get('rho_source'))})"
    if model.get("rho_i") is not None:
        out += ", rho_i certified"
    return out + _effects_text(spec)


def _effects_text(spec) -> str:
    """``; plant effects: friction (urdf), saturation (urdf); loop: noise, delay 2`` or ``""``."""
    plant, loop = spec.true_plant, spec.loop
    parts = []
    if plant is not None:
        fx = [f"{e.name} ({e.source})" for e in plant.effects]
        rigid = plant.rigid.name if plant.rigid.advance is not None else None  # a rigid body stepping itself: MuJoCo
        if fx:
            parts.append("plant effects: " + ", ".join(fx))
        if rigid:
            parts.append(f"plant engine {rigid}")
    if loop is not None:
        d = loop.describe()
        bits = [k for k in ("noise_q", "noise_qd", "quantization", "q0_error", "qd0_error") if any(d[k])]
        if d["delay"]:
            bits.append(f"delay {d['delay']} samples")
        if bits:
            parts.append("loop: " + ", ".join(bits) + f" (seed {d['seed']})")
    return "".join("; " + p for p in parts)


def cmd_run(args) -> int:
    """``rc3r run``: one simulation; writes timeseries.csv, run.png, metrics.json into --out.

    A diverged run writes its data up to the divergence, then raises
    :class:`~rc3r.errors.DivergenceError` (exit 3).
    """
    cfg = model_friction_config({} if args.config is None else read_config(args.config), args)
    spec = build_run(robot=args.robot, controller=args.controller, perturbed=args.perturbed, plant=args.plant,
                     eps=args.eps, rate=args.rate, duration=args.duration, engine=args.engine, box=args.box,
                     payload=args.payload, payload_com=args.payload_com, config=cfg, **plant_options(args))
    out = Path(args.out if args.out is not None else Path("out") / "run" / spec.name)
    check_output_path(out)  # before anything is announced or simulated
    if out.is_dir() and any(out.iterdir()) and not args.force:
        raise ConfigError(f"{out} holds an earlier result; give --force to replace it, or another --out")
    fmt = getattr(args, "animate", None)
    if fmt:
        from ..animation import check_animatable, frame_count

        check_animatable(spec.true_rigid, fmt)  # before anything is announced or simulated
    from ..runspec import design_warning

    warning = design_warning(cfg)
    if warning:
        _progress(warning)
    with planned(*own_instance(spec), keep=True):  # its own law only (the smallest instance), if unplanned
        engine_note = announce_engine(spec)  # said after a finished run only: a diverged one prints one error line
        for warning in spec.warnings:
            _progress(f"rc3r: warning: {warning}")
        _progress(f"rc3r run: {spec.name}: {describe_model(spec)}; {spec.options.mode}"
                  f"{'' if spec.options.rate is None else f' at {spec.options.rate:g} Hz'}, "
                  f"{spec.options.duration:g} s, engine {spec.options.engine}"
                  f"{f', then animation.{fmt} ({frame_count(spec.options.duration)} frames)' if fmt else ''} ...")
        anim_interrupted = False
        with output_dir(out) as tmp:  # --out checked and locked before simulating
            res, m = execute(spec)
            estimate = _estimate(spec, res, m)
            if fmt and res.outcome != "interrupted":
                anim_interrupted = not _animate(spec, res, m, tmp / f"animation.{fmt}", out)
            m["provenance"] = provenance(config=cfg, seed=spec.seed)
            res.save(tmp, m, spec.name)
            if estimate is not None:
                atomic_savefig(estimate, tmp / "estimate.png", dpi=110)
        if res.outcome == "interrupted":
            print(f"rc3r: {spec.name} {res.message}: written to {out}/ (metrics.json status 'interrupted')",
                  file=sys.stderr)
            return EXIT["interrupted"]
        if anim_interrupted:
            print(f"rc3r: interrupted while writing the animation: the run is written to {out}/ without it",
                  file=sys.stderr)
            return EXIT["interrupted"]
        if engine_note is not None and res.ok:
            _progress(engine_note)
        print(f"{verdict_text(m)}: {spec.name}: max|e| = {_fmt3(m['max_abs_error'])} rad, "
              f"final bound = {_fmt3(m['final_error_bound'])} rad, chattering = {_fmt3(m['chattering'])} N m/s, "
              f"wall {m['wall_time_s']:.2f} s -> {out}/")
        try:
            res.raise_for_status()
        except DivergenceError as exc:
            rate = "HZ" if spec.options.rate is None else f"{spec.options.rate:g}"
            raise DivergenceError(f"{exc}; data up to then written to {out}/; gains and eps verified for your "
                                  f"controller rate: rc3r design --rate {rate} (docs/design.md)") from None
        return EXIT["ok"]


def _estimate(spec, res, m: dict):
    """The adaptive law's estimate against the plant's theta: ``m["parameter_estimate"]`` and the
    figure (``None`` for the other laws)."""
    from ..controllers import Adaptive

    if not isinstance(spec.law, Adaptive) or res.z.shape[1] != spec.true_rigid.p or res.t.size == 0:
        return None
    from ..plotting import ESTIMATE_UNITS, estimate_errors, estimate_figure

    est = estimate_errors(res, spec.true_rigid.theta)
    m["parameter_estimate"] = {
        "definition": "theta_hat(t) = the adaptive law's state; theta = the plant's coefficients (unknown to the law)",
        "units": ESTIMATE_UNITS,
        "error_initial": float(est["error"][0]), "error_final": float(est["error"][-1]),
        "error_min": float(est["error"].min()), "moved_max": float(est["moved"].max()),
        "theta_hat_final": [float(x) for x in res.z[-1]], "theta_plant": [float(x) for x in spec.true_rigid.theta],
    }
    return estimate_figure(res, spec.true_rigid.theta, f"{spec.name}: adaptive estimate on plant '{spec.true_rigid.label}'",
                           names=spec.true_rigid.coefficient_names if spec.true_rigid.p > 15 else None)


def _animate(spec, res, m: dict, path: Path, out: Path) -> bool:
    """Write the animation into the run directory; False if interrupted (the run is kept without it)."""
    from ..animation import write_animation

    _progress(f"rc3r run: writing the animation {out}/{path.name} ...")
    try:
        frames = write_animation(res, spec.true_rigid, path, title=f"rc3r run {spec.name}")
    except KeyboardInterrupt:
        return False
    m["animation"] = {"file": path.name, "frames": int(frames.t.size), "fps": frames.fps,
                      "end_effector_frame": frames.frame, "t": [float(frames.t[0]), float(frames.t[-1])]}
    return True


def verdict_word(m: dict) -> str:
    """``clean``, ``chattering (joints 1, 2)``, ``saturated`` ...: a run's verdict (:mod:`rc3r.simulate.verdict`)
    with the joints that chatter, as the summary tables print it."""
    word = m["verdict"]
    if word == "chattering" and m.get("chattering_joints"):
        word += f" (joints {', '.join(str(j) for j in m['chattering_joints'])})"
    return word


def _table(rows: list[dict]) -> str:
    head = ("| scenario | mode | verdict | max abs error [rad] | final error bound [rad] | "
            "max abs torque [N m] | chattering [N m/s] | wall [s] |")
    lines = [head, "|" + "---|" * 8]
    for m in rows:
        mode = m["mode"] if m["rate_hz"] is None else f"sampled {m['rate_hz'] / 1000:g} kHz"
        lines.append(f"| {m['name']} | {mode} | {verdict_word(m)} | {_fmt3(m['max_abs_error'])} | "
                     f"{_fmt3(m['final_error_bound'])} | {_fmt3(m['max_abs_torque'])} | "
                     f"{_fmt3(m['chattering'])} | {m['wall_time_s']:.2f} |")
    return "\n".join(lines)


def cmd_paper(args) -> int:
    """``rc3r paper``: the five scenarios, continuous and sampled; figures, summary.md/json."""
    from ..experiments import paper3r as paper  # the paper's experiment, named openly

    with output_dir(args.out) as tmp:
        return _paper(paper, tmp)


#: Caption of the per-joint FBL-against-robust figure, per case: each speaks of its own case only.
COMPARISON_CAPTIONS = {
    "ideal": "Same plant, same trajectory, one axis per joint. Ideal: both laws know the plant's theta, so "
             "FBL's error is the integrator's and the robust term has no model error to remove.",
    "perturbed": "Same plant, same trajectory, one axis per joint. Perturbed: the laws know only theta_0 and "
                 "rho; FBL is left with the model error, the robust term removes it down to the boundary "
                 "layer (a smaller eps: smaller error).",
}


def theory_figures(res: dict, label: str) -> dict:
    """The figures of :func:`_theory_figures` by file stem (``compare-ideal``, ``compare-perturbed``,
    ``boundary-layer``), as :class:`matplotlib.figure.Figure` objects; ``res`` maps scenario names
    (``fbl-ideal``, ``robust-perturbed``, ...) to results, missing ones are left out."""
    from ..plotting import boundary_layer_figure, comparison_figure

    figs = {}
    for case in ("ideal", "perturbed"):
        runs = {f"FBL {case}": res.get(f"fbl-{case}"), f"robust {case}, eps 0.5": res.get(f"robust-{case}")}
        if case == "perturbed":
            runs["robust perturbed, eps 0.05"] = res.get("robust-perturbed-eps0.05")
        runs = {k: v for k, v in runs.items() if v is not None}
        if runs:
            figs[f"compare-{case}"] = comparison_figure(runs, f"FBL vs robust, {case} case, {label}",
                                                        COMPARISON_CAPTIONS[case])
    robust = {f"eps {r.controller.get('eps'):g}": r for n, r in res.items()
              if n.startswith("robust-perturbed") and isinstance(r.controller.get("eps"), (int, float))}
    if robust:
        figs["boundary-layer"] = boundary_layer_figure(
            robust, f"robust law, perturbed case: ||Y^T r|| and the boundary layer, {label}",
            "Below its dashed line a run is inside its boundary layer, where the robust term is the linear "
            "gain (rho/eps) Y Y^T r; the ultimate error bound scales with rho eps.")
    return figs


def _theory_figures(res: dict, out: Path, mode: str, label: str) -> None:
    """FBL against robust per joint (ideal, perturbed) and ||Y^T r|| against eps, saved as PNG."""
    for stem, fig in theory_figures(res, label).items():
        atomic_savefig(fig, out / f"{stem}-{mode}.png", dpi=110)


def _paper(paper, out: Path) -> int:
    from ..plotting import plot_error_comparison

    from ..campaign.runner import plan

    short = paper.scenarios(duration=0.01)
    plan(short[0], [spec.law.name for spec in short])  # one compiled instance for the scenarios' laws
    announce_compile(short[0].true_rigid, spec=short[0])
    t_start = time.perf_counter()
    rows, results = [], {}
    for mode, rate in (("continuous", None), ("sampled", paper.PAPER_SAMPLED_RATE)):
        specs = paper.scenarios(rate=rate)
        for k, spec in enumerate(specs, 1):
            _progress(f"[{mode} {k}/{len(specs)}] {spec.name} ...")
            res, m = execute(spec)
            if res.outcome == "interrupted":
                raise KeyboardInterrupt
            _progress(f"    {verdict_word(m)}; max|e| = {_fmt3(m['max_abs_error'])} rad, wall {m['wall_time_s']:.2f} s")
            sub = out / mode / spec.name
            res.save(sub, m, spec.name)
            rows.append(m)
            results[(mode, spec.name)] = res
        label = mode + ("" if rate is None else f" {rate / 1000:g} kHz")
        plot_error_comparison({n: r for (md, n), r in results.items() if md == mode},
                              out / f"errors-{mode}.png", f"tracking error, {label}")
        _theory_figures({n: r for (md, n), r in results.items() if md == mode}, out, mode, label)
    claims = paper.claims(rows)
    total = time.perf_counter() - t_start
    summary = {"scenarios": rows, "claims": claims, "sampled_rate_hz": paper.PAPER_SAMPLED_RATE,
               "chattering_definition": CHATTERING_DEFINITION, "total_wall_s": total,
               "provenance": provenance()}
    atomic_write_json(out / "summary.json", summary)
    md = ["# rc3r paper: section 4 reproduced", "",
          paper.SUMMARY_INTRO, "",
          _table(rows), "", f"Chattering: {CHATTERING_DEFINITION}.", "", "## The paper's claims on these numbers", ""]
    for c in claims:
        md += [f"- [{'x' if c['holds'] else ' '}] {c['mode']}: {c['claim']} ({c['why']}).",
               f"  {'Holds' if c['holds'] else 'Does not hold'}: {c['explanation']}."]
    md += ["", f"Total wall time {total:.1f} s. Figures: `<mode>/<scenario>/run.png`, `errors-<mode>.png`, "
           "`compare-ideal-<mode>.png` and `compare-perturbed-<mode>.png` (FBL vs robust per joint, errors and "
           "torques), `boundary-layer-<mode>.png` (||Y^T r|| against eps).", ""]
    atomic_write_text(out / "summary.md", "\n".join(md))
    print("\n".join(md))
    return EXIT["ok"]
