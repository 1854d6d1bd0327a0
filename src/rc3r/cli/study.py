"""``rc3r montecarlo``, ``rc3r sweep eps``, ``rc3r sweep rate``: campaigns of many runs.

The output directory grows while the campaign runs: ``runs.csv`` (one row per finished
job, the metrics of ``rc3r run``), ``timing.csv`` (wall times, workers), ``campaign.json``
(what was asked, seeds, bounds, provenance), and at the end the summary and the figures
(each written atomically). An interrupted campaign keeps every finished row; the same
command with ``--resume`` runs only the rest. A lock refuses a second writer.

A campaign whose workers die (a local worker killed, a Dask cluster without workers for
``RC3R_DASK_GRACE`` seconds, default 60) stops with one line and exit code 75
(:class:`rc3r.errors.WorkerLostError`); its rows stay, and ``--resume`` continues.
"""
from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

from ..campaign import (RunTable, columns, eps_jobs, eps_summary, model_radii, montecarlo_jobs,
                        montecarlo_summary, rate_jobs, rate_map, read_rows, run_many, sorted_rows)
from ..campaign.jobs import TIMING_KEYS
from ..campaign.runner import DASK_GRACE_S
from ..campaign.studies import gain_label
from ..errors import ConfigError, WorkerLostError
from ..io import atomic_savefig, atomic_write_json, atomic_write_text
from ..provenance import provenance
from . import EXIT
from ._output import check_output_path, locked
from ..campaign.runner import plan, prepare
from .run import announce_compile


def _progress_bar(total: int, done: int, what: str):
    from tqdm import tqdm

    return tqdm(total=total, initial=done, desc=what, unit="run", file=sys.stderr, dynamic_ncols=True,
                disable=None, mininterval=0.5)


def _dask_grace() -> float:
    """Seconds a Dask cluster may have no worker while runs wait: ``RC3R_DASK_GRACE``, else the default."""
    text = os.environ.get("RC3R_DASK_GRACE", "").strip()
    if not text:
        return DASK_GRACE_S
    try:
        grace = float(text)
    except ValueError:
        grace = float("nan")
    if not grace > 0 or grace == float("inf"):
        raise ConfigError(f"RC3R_DASK_GRACE={text!r}: must be a number of seconds > 0")
    return grace


def _campaign(args, kind: str, jobs, request: dict, finish) -> int:
    """Shared driver: check --out, lock, campaign.json, run the jobs, then ``finish(out, rows, meta)``."""
    out = check_output_path(args.out)
    if not jobs:
        raise ConfigError("nothing to run: the campaign has no jobs")
    if args.scheduler is not None and args.workers is not None:
        raise ConfigError("give --workers or --scheduler, not both")
    grace = _dask_grace()
    first = jobs[0].build()  # bad input (box, robot, gains, config) refused here, before any worker starts
    n = first.true_rigid.n
    with locked(out):
        meta_path = out / "campaign.json"
        request = dict(request, kind=kind, jobs=len(jobs))
        if meta_path.exists():
            try:
                old = json.loads(meta_path.read_text()).get("request")
            except (OSError, ValueError):
                old = None
            if not args.resume:
                raise ConfigError(f"{out} already holds a campaign: give --resume to continue it, or another --out")
            if old != json.loads(json.dumps(request)):
                raise ConfigError(f"{out} holds a different campaign ({old}); --resume needs the same options")
        elif (out / "runs.csv").exists():
            raise ConfigError(f"{out} has runs.csv but no campaign.json; cannot tell what it was")
        out.mkdir(exist_ok=True)
        meta = {"request": request, "provenance": provenance(), "radii": None}
        if kind == "montecarlo":
            meta["radii"] = model_radii(jobs[0])
        if not meta_path.exists():
            atomic_write_json(meta_path, meta)
        with RunTable(out / "runs.csv", columns(n)).open(resume=True) as table, \
                RunTable(out / "timing.csv", TIMING_KEYS).open(resume=True) as timing:
            done = sum(1 for j in jobs if j.id in table.done)
            where = args.scheduler or f"{args.workers or os.cpu_count()} local worker(s)"
            if table.dropped:
                print(f"rc3r {kind}: {table.dropped} incomplete row(s) of {out}/runs.csv dropped; they run again",
                      file=sys.stderr)
            print(f"rc3r {kind}: {len(jobs)} runs, {done} already done, on {where} -> {out}/", file=sys.stderr)
            plan(first, [j.controller for j in jobs])  # one compiled instance for the campaign's laws
            announce_compile(first.true_rigid, first.options.rate, first)
            prepare(first)  # compile once here: the jobs alone are short enough to pass a cold engine over
            bar = _progress_bar(len(jobs), done, kind)
            t0 = time.perf_counter()
            try:
                written = run_many(jobs, table, timing, workers=args.workers, scheduler=args.scheduler,
                                   progress=lambda row: bar.update(1), worker_grace=grace)
            except WorkerLostError as exc:
                bar.close()
                raise WorkerLostError(f"{exc}; {len(table.done)} of {len(jobs)} runs are in {out}/runs.csv; the same "
                                      "command with --resume runs the rest") from None
            except KeyboardInterrupt:
                bar.close()
                print(f"rc3r: interrupted; {len(table.done)} of {len(jobs)} runs are in {out}/runs.csv; the same "
                      "command with --resume runs the rest", file=sys.stderr)
                return EXIT["interrupted"]
            bar.close()
            wall = time.perf_counter() - t0
        rows = sorted_rows(read_rows(out / "runs.csv"), jobs)
        print(f"{written} runs in {wall:.1f} s ({60 * written / max(wall, 1e-9):.0f} runs/min); "
              f"{len(rows)} of {len(jobs)} in the table", file=sys.stderr)
        return finish(out, rows, meta)


def _map_key(k) -> str:
    """Key of a rate map in stability.json: ``default``, ``50.0``, or a per-joint K as a JSON list."""
    return json.dumps(list(k)) if isinstance(k, tuple) else str(k)


def _g(x) -> str:
    return "-" if x is None else f"{x:.3g}"


def _config(args) -> dict:
    """The campaign's configuration: --config, then the arm and plant options of the command line on top
    (every job gets them through its configuration: docs/control.md, "Plants")."""
    from ..io import read_config
    from .run import model_friction_config, plant_options

    cfg = model_friction_config({} if args.config is None else read_config(args.config), args)

    opts = plant_options(args)
    for key in ("urdf", "tolerance"):
        if opts.get(key) is not None:
            cfg[key] = opts[key]
    if getattr(args, "bounds", None) is not None:
        cfg["bounds"] = str(args.bounds)
    if opts.get("lock"):
        cfg["lock"] = opts["lock"]
    if getattr(args, "payload", None) is not None:
        cfg["payload"] = {"mass": list(args.payload)}
        if getattr(args, "payload_com", None) is not None:
            cfg["payload"]["com"] = list(args.payload_com)
    plant = dict(cfg.get("plant", {}))
    plant.update(opts["effects"])  # the registered effects' options, by their [plant] keys
    for key, name in (("noise", "noise"), ("delay", "delay"), ("plant_engine", "engine")):
        if opts.get(key) is not None:
            plant[name] = opts[key]
    if plant:
        cfg["plant"] = plant
    return cfg


def cmd_montecarlo(args) -> int:
    """``rc3r montecarlo``: every controller on N plants drawn from the box."""
    from ..campaign.figures import error_distribution, error_vs_distance

    from ..runspec import design_warning

    cfg = _config(args)
    if args.controllers is None:  # a design.toml's recommended law, and FBL beside it
        kind = cfg.get("controller", {}).get("kind") if isinstance(cfg.get("controller"), dict) else None
        args.controllers = ",".join(dict.fromkeys([kind, "fbl"])) if kind else "fbl,robust"
    controllers = [c.strip() for c in args.controllers.split(",") if c.strip()]
    if design_warning(cfg):
        print(design_warning(cfg), file=sys.stderr)
    jobs = montecarlo_jobs(args.n, args.seed, controllers, eps=args.eps, rate=args.rate, duration=args.duration,
                           robot=args.robot, box=args.box, config=cfg)
    request = {"n": args.n, "seed": args.seed, "controllers": controllers, "eps": args.eps, "rate": args.rate,
               "duration": args.duration, "robot": args.robot, "box": args.box, "config": cfg}

    def finish(out: Path, rows, meta) -> int:
        summary = montecarlo_summary(rows)
        atomic_write_json(out / "summary.json", {"summary": summary, "radii": meta["radii"],
                                                  "request": meta["request"], "provenance": provenance()})
        where = f"the ellipsoid of {cfg['bounds']}" if cfg.get('bounds') else "the box"
        title = f"{len({r['plant'] for r in rows})} plants of {where}, seed {args.seed}"
        atomic_savefig(error_distribution(rows, f"max error per controller: {title}"), out / "error_cdf.png")
        atomic_savefig(error_vs_distance(rows, meta["radii"] or {}, f"max error vs ||theta - theta_0||: {title}"),
                       out / "error_vs_distance.png")
        lines = ["| controller | runs | clean | chattering | saturated | limit-violated | diverged | "
                 "median max|e| [rad] | p95 | max | inside ball | bound exceeded |",
                 "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for c, s in summary.items():
            exceeded = "-" if s["bound_exceeded"] is None else f"{s['bound_exceeded']} of {s['bound_checked']}"
            inside = "-" if s["inside_ball"] is None else str(s["inside_ball"])
            v = s["verdicts"]
            lines.append(f"| {c} | {s['runs']} | {v['clean']} | {v['chattering']} | {v['saturated']} | "
                         f"{v['limit-violated']} | {v['diverged']} | {_g(s['max_error_median'])} | "
                         f"{_g(s['max_error_p95'])} | {_g(s['max_error_max'])} | {inside} | {exceeded} |")
        atomic_write_text(out / "summary.md", "\n".join(lines) + "\n")
        print("\n".join(lines))
        return EXIT["ok"]

    return _campaign(args, "montecarlo", jobs, request, finish)


def cmd_sweep(args) -> int:
    """``rc3r sweep eps`` / ``rc3r sweep rate``."""
    from ..campaign.figures import pareto, stability_map

    cfg = _config(args)
    eps_values = args.eps
    if args.what == "eps":
        rates = (None,) + tuple(args.rates or ())
        jobs = eps_jobs(eps_values, rates, n_plants=args.n, seed=args.seed, duration=args.duration,
                        robot=args.robot, box=args.box, config=cfg)
    else:
        jobs = rate_jobs(eps_values, args.rates, tuple(args.K or (None,)), n_plants=args.n, seed=args.seed,
                         duration=args.duration, robot=args.robot, box=args.box, config=cfg)
    request = {"what": args.what, "eps": eps_values, "rates": args.rates, "K": getattr(args, "K", None),
               "n": args.n, "seed": args.seed, "duration": args.duration, "robot": args.robot, "box": args.box,
               "config": cfg}

    def finish(out: Path, rows, meta) -> int:
        if args.what == "eps":
            summary = eps_summary(rows)
            atomic_write_json(out / "sweep.json", {"summary": summary, "request": meta["request"],
                                                    "provenance": provenance()})
            atomic_savefig(pareto(summary, "robust law: final error bound vs chattering over eps"),
                           out / "pareto.png")
            for s in summary:
                mode = "continuous" if s["rate_hz"] is None else f"{s['rate_hz']:g} Hz"
                fe = ("diverged" if s["final_error"] is None else
                      f"final bound {s['final_error']:.3g} rad, chattering {s['chattering']:.4g} N m/s")
                print(f"{mode:>12} eps = {s['eps']:<8g} {fe}")
        else:
            maps = rate_map(rows, jobs)
            atomic_write_json(out / "stability.json", {
                "maps": {_map_key(k): {"K": list(k) if isinstance(k, tuple) else None if k == "default" else k,
                                       **m, "safe_rate": {str(e): r for e, r in m["safe_rate"].items()}}
                         for k, m in maps.items()},
                "request": meta["request"], "provenance": provenance()})
            atomic_savefig(stability_map(maps, "sampled-data robust law over the full duration"),
                           out / "stability_map.png")
            for k, m in maps.items():
                for e in m["eps"]:
                    s = m["safe_rate"][e]
                    print(f"K = {gain_label(k)}: eps = {e:g}: clean from {'never' if s is None else f'{s:g} Hz'}")
        return EXIT["ok"]

    return _campaign(args, f"sweep-{args.what}", jobs, request, finish)
