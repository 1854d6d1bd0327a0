"""``rc3r design``: gains and eps for a controller rate, verified over the bounds (docs/design.md).

Writes into ``--out`` (as a whole, :mod:`rc3r.cli._output`): ``design.toml`` (a configuration for
``rc3r run``, ``montecarlo`` and ``export --config``: ``[controller] kind`` the recommended law, ``[gains.<law>]``
every law's gains, ``[design] verified``), ``design.md``, ``design.json``, ``design.png`` and ``runs.csv``
(every verification run, the rows of ``rc3r montecarlo``).
Exit 0 when a robust law (eq. 6 or eq. 7) was clean at the rate and at rate / margin on every plant (the random
ones and the searched hardest ones), 1 when none was (the files are written with the fast form's gains,
``verified = false``, and the command says why and what to try), 2 on bad input (nothing written).
"""
from __future__ import annotations

import shlex
import sys
import time

import numpy as np

from ..errors import ConfigError
from ..io import atomic_savefig, atomic_write_json, atomic_write_text
from ..provenance import provenance
from . import EXIT
from ._output import check_output_path, output_dir

#: Most controller samples (duration x rate) of one verification run: a design runs every plant at several
#: eps and two rates, so a rate a single run may still take (``rc3r.simulate.MAX_SAMPLES``, 1e9) would keep
#: it busy for days; 1e6 is 10 s at 100 kHz (``rc3r design --rate 1e9`` did not return).
DESIGN_MAX_SAMPLES = 1_000_000

#: What ``rc3r design`` writes in its directory (replaced by a rerun; other entries are kept).
DESIGN_ENTRIES = ("design.toml", "design.md", "design.json", "design.png", "runs.csv")


def add_parser(sub) -> None:
    """The ``design`` subcommand's options (called by :func:`rc3r.cli.build_parser`)."""
    from ..robots import ROBOTS
    from . import _interval, _positive, _vector3, plant_args

    d = sub.add_parser("design", help="gains and eps for a controller rate, verified over the bounds")
    d.add_argument("--robot", help=f"a registered robot ({', '.join(ROBOTS)}; default: config, else rr3)")
    d.add_argument("--payload", type=_interval, metavar="LO:HI",
                   help="unknown payload mass on the last link [kg]: verified on both ends and --n random masses")
    d.add_argument("--payload-com", type=_vector3, metavar="X,Y,Z",
                   help="payload CoM in the last joint's frame [m] (default 0,0,0)")
    d.add_argument("--box", help="box TOML: verified on the nominal robot and --n random plants of the box")
    d.add_argument("--bounds", metavar="FILE", help="bounds.toml of rc3r identify (verified on the nominal robot)")
    d.add_argument("--rate", type=_positive(), required=True, help="controller rate [Hz]")
    d.add_argument("--urdf-uncertainty", type=_urdf_spec, metavar="SPEC",
                   help="the URDF's own error, verified beyond a payload range or a box: every link's pseudo-inertia "
                        "scaled by LO..HI along each principal direction, K=LO..HI for link K (-1 the last), "
                        "comma-separated; a fraction F is 1-F..1+F (default '0.1..1.5,-1=0.05..1.5'; off: none; "
                        "never with --bounds; docs/design.md, 'URDF uncertainty')")
    d.add_argument("--config", help="TOML with the trajectory, plant effects, bounds (no gains: they are designed)")
    d.add_argument("--margin", type=_margin, default=2.0,
                   help="the design must also be clean at rate / MARGIN (default 2; 1: at the rate only)")
    d.add_argument("--n", type=_positive(int, allow_zero=True), default=50,
                   help="random plants besides the payload's ends or the nominal robot (default 50)")
    d.add_argument("--seed", type=_positive(int, allow_zero=True), default=0, help="seed of the random plants")
    d.add_argument("--duration", type=_positive(), help="simulated time per run [s] (default: config, else 10)")
    d.add_argument("--workers", type=_positive(int), help="local worker processes (default: all cores)")
    d.add_argument("--scheduler", help="address of a Dask scheduler (tcp://HOST:PORT) instead of local workers")
    d.add_argument("--out", required=True, help="output directory (written as a whole)")
    d.add_argument("--force", action="store_true", help="replace an earlier design in --out")
    plant_args(d)


def _clean(res, law: str) -> bool:
    """Whether a robust law of a design result was clean at the rate and at rate / margin."""
    if law == "robust":
        return res.eq6_ok
    rc = res.baselines.get("robust-coeff") or {}
    return bool(rc.get("clean") and rc.get("clean_low", True))


def _urdf_spec(text):
    import argparse

    from ..uncertainty.urdf import parse_spec

    try:
        return parse_spec(text) or "off"
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _margin(text):
    import argparse
    import math

    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (math.isfinite(x) and x >= 1):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 1, got {text}")
    return x


class _Bar:
    """A tqdm bar whose total grows with each batch of runs."""

    def __init__(self):
        from tqdm import tqdm

        self.bar = tqdm(total=0, desc="design", unit="run", file=sys.stderr, dynamic_ncols=True, disable=None,
                        mininterval=0.5)

    def __call__(self, what, count):
        if what is not None:
            self.bar.total += count
            self.bar.set_description(what)
            self.bar.refresh()
        else:
            self.bar.update(count)

    def close(self):
        self.bar.close()


def cmd_design(args) -> int:
    """``rc3r design``: the rule, the verification, the files (module docstring)."""
    from ..campaign import RunTable, columns
    from ..design.report import design_figure, design_markdown, design_toml, failure_line, next_steps
    from ..design.verify import RUN_LAWS, design_config, verify_design
    from ..campaign.runner import plan, prepare
    from ..io import read_config
    from ..runspec import build_run
    from .run import announce_compile, model_friction_config, plant_options

    if args.scheduler is not None and args.workers is not None:
        raise ConfigError("give --workers or --scheduler, not both")
    if args.payload_com is not None and args.payload is None:
        raise ConfigError("--payload-com needs --payload LO:HI")
    cfg = model_friction_config({} if args.config is None else read_config(args.config), args)
    opts = plant_options(args)
    cfg = design_config(cfg, robot=args.robot, urdf=opts["urdf"], lock=opts["lock"], payload=args.payload,
                        payload_com=args.payload_com, box=args.box, bounds=args.bounds,
                        friction=opts["effects"].pop("friction", None),
                        torque_limit=opts["effects"].pop("torque_limit", None), noise=opts["noise"], delay=opts["delay"],
                        duration=args.duration, tolerance=opts["tolerance"], urdf_uncertainty=args.urdf_uncertainty)
    if opts["effects"]:  # the other registered effects' options
        cfg.setdefault("plant", {}).update(opts["effects"])
    if opts.get("plant_engine"):
        cfg.setdefault("plant", {})["engine"] = opts["plant_engine"]
    first = build_run(controller="robust", config=cfg, rate=args.rate, eps=1.0)  # bad input refused here
    samples = first.options.duration * float(args.rate)
    if samples > DESIGN_MAX_SAMPLES:
        raise ConfigError(f"--rate {args.rate:g} Hz over {first.options.duration:g} s is {samples:.3g} controller "
                          f"samples per verification run; rc3r design allows {DESIGN_MAX_SAMPLES:.0e} (lower "
                          f"--rate or --duration: at most {DESIGN_MAX_SAMPLES / first.options.duration:.3g} Hz "
                          f"over {first.options.duration:g} s)")
    out = check_output_path(args.out)
    if out.is_dir() and any(out.iterdir()) and not args.force:
        raise ConfigError(f"{out} holds an earlier result; give --force to replace it, or another --out")
    command = "rc3r " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:2] == ["design"] else ""
    where = args.scheduler or f"{args.workers or 'all'} local worker(s)"
    from ..robots.actuated import ActuatedRobot

    model = first.controller_model  # an identified arm (friction, armature): named by its rigid body
    arm = (model.rigid if isinstance(model, ActuatedRobot) else model).label
    print(f"rc3r design: {first.true_rigid.n}-joint arm '{arm}', {args.rate:g} Hz (margin "
          f"{args.margin:g}), {args.n} random plants, {first.options.duration:g} s each, on {where} -> {out}/",
          file=sys.stderr)
    plan(first, RUN_LAWS)  # one compiled instance for the design's laws
    announce_compile(first.true_rigid, float(args.rate), first)
    prepare(first)  # compile once here: the jobs alone are short enough to pass a cold engine over
    t0 = time.perf_counter()
    with output_dir(out, own=DESIGN_ENTRIES) as tmp:
        bar = _Bar()
        try:
            with RunTable(tmp / "runs.csv", columns(first.true_rigid.n)).open(resume=False) as table:
                res = verify_design(cfg, float(args.rate), table=table, margin=args.margin, n=args.n,
                                    seed=args.seed, workers=args.workers, scheduler=args.scheduler, progress=bar)
        finally:
            bar.close()
        wall = time.perf_counter() - t0
        info = res.describe()
        info.update({"wall_s": wall, "command": command, "provenance": provenance(config=cfg, seed=args.seed)})
        atomic_write_text(tmp / "design.toml", design_toml(res, f"made by: {command}" if command else "",
                                                           base=out.resolve()))
        atomic_write_text(tmp / "design.md", design_markdown(res, command))
        atomic_write_json(tmp / "design.json", info)
        atomic_savefig(design_figure(res), tmp / "design.png", dpi=110)
    g = res.gains()["robust"]
    fbl = res.baselines.get("fbl", {}).get("worst_error")
    ch = res.chosen
    last = ch or (max(res.levels, key=lambda x: x["eps"]) if res.levels else None)
    worst = None if last is None else last["at_rate"].get("worst_error")
    word = "clean" if res.eq6_ok else ("NOT clean (eq. 6; eq. 7 is)" if res.ok else "NOT clean")
    low = res.lowest_clean_rate()
    def num(x, fmt=".3g"):
        return "-" if x is None else format(x, fmt)

    kk = np.asarray(g["K"], dtype=float)
    ks = ", ".join(format(k, ".3g") for k in (np.diag(kk) if kk.ndim == 2 else kk)) + \
        ("; diagonal of b M(q_d(0))" if kk.ndim == 2 else "") + \
        (f"] + {g['K_inertia']:.4g} M(q) [scheduled" if g.get("K_inertia") else "")
    print(f"{word}: eps = {g['eps']:.4g} (rule: {res.design.eps:.4g}, stability boundary {res.design.eps_stable:.4g}), "
          f"Lambda = {g['Lambda']:.4g}, K = [{ks}]; worst max|e| {num(worst)} rad{'' if ch else ' (largest eps tried)'} (FBL {num(fbl)}); lowest clean "
          f"rate {num(low, '.4g')} Hz; {len(res.levels)} eps tried, wall {wall:.1f} s -> {out}/")
    rec = res.recommendation()
    if rec is not None:
        print(f"recommended robust law: {rec['law']} ({rec['why']}; FBL {num(rec['fbl_worst_error'])} rad)")
    for law, w in res.worst.items():
        print(f"hardest plant for {law}: {w['spec'][:48]}{'...' if len(w['spec']) > 48 else ''}: T lambda_max = "
              f"{w['T_lambda']:.3g} (limit {w['limit']:.3g}; the rule's on the controller's model "
              f"{num(w.get('model_T_lambda'))})" + ("" if w['T_lambda'] <= w['limit'] else
                                                    "; above the limit, which holds for the law inside its boundary "
                                                    "layer, yet the runs on it were clean" if _clean(res, law) else
                                                    f"; above the limit: {law} is not clean over the set at this rate"))
    if not res.ok:
        print(f"rc3r design: NOT verified: neither eq. 6 (no eps tried was clean) nor eq. 7 was clean on every plant "
              f"at {args.rate:g} and {args.rate / args.margin:g} Hz: {failure_line(res)}", file=sys.stderr)
        print("rc3r design: to try: " + "; ".join(next_steps(res)) + f". {out}/design.toml says verified = false "
              "(run, montecarlo and export warn; export refuses it without --force)", file=sys.stderr)
        return EXIT["check_failed"]
    return EXIT["ok"]
