"""Command line: ``rc3r <command> [options]``.

``main(argv) -> int`` is the whole program (tested in-process); ``entry`` is the
console script. This package is the only place that parses arguments, prints and
chooses exit codes; each command group has its module (:mod:`.model`,
:mod:`.bounds`, :mod:`.run`, :mod:`.bench`), which calls the library.

Exit codes (:data:`EXIT`): 0 success; 1 a check failed (``verify-model`` found the
model wrong, ``bench`` found a wrong result); 2 bad input (one line
``rc3r: error: ...``, never a traceback); 3 a simulation diverged (its data up to
then is written); 70 an internal error (a bug: one line, ``RC3R_DEBUG=1`` for the
traceback); 75 a campaign lost its workers (``--resume`` continues); 130 interrupted.
"""
from __future__ import annotations

import argparse
import importlib
import math
import os
import signal
import sys
import threading

from ..controllers import LAWS
from ..errors import Rc3rError
from ..robots import ROBOTS
from ..simulate import ENGINES

__all__ = ["main", "entry", "build_parser", "EXIT"]

#: Exit codes of every command.
EXIT = {"ok": 0, "check_failed": 1, "bad_input": 2, "diverged": 3, "internal_error": 70, "workers_lost": 75,
        "interrupted": 130}


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line (no usage dump)."""

    def error(self, message):  # noqa: D401 - argparse API
        raise _UsageError(f"{message} (see `{self.prog} --help`)")


class _UsageError(Exception):
    pass


def _positive(kind=float, allow_zero=False):
    def conv(text):
        try:
            x = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if isinstance(x, float) and not math.isfinite(x):
            raise argparse.ArgumentTypeError(f"must be finite, got {text}")
        if x < 0 or (x == 0 and not allow_zero):
            raise argparse.ArgumentTypeError(f"must be {'>= 0' if allow_zero else '> 0'}, got {text}")
        return x

    conv.__name__ = kind.__name__
    return conv


def _interval(text):
    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LO:HI, got {text!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo <= hi):
        raise argparse.ArgumentTypeError(f"expected finite 0 <= LO <= HI, got {text!r}")
    return lo, hi


def _vector3(text):
    try:
        v = tuple(float(x) for x in text.split(","))
    except ValueError:
        v = ()
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise argparse.ArgumentTypeError(f"expected X,Y,Z (three finite numbers), got {text!r}")
    return v


def _lock(text):
    name, sep, value = text.partition("=")
    try:
        v = float(value)
    except ValueError:
        v = float("nan")
    if not sep or not name or not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected JOINT=VALUE (a joint name and a finite number), got {text!r}")
    return name, v


def urdf_path(text):
    """``--urdf``: a path, or ``erd:REL`` for a file of example-robot-data (its path, resolved here)."""
    from ..urdf_names import resolve_erd

    return str(resolve_erd(text))


def _noise(text):
    from ..plants.base import nonnegative_numbers

    try:
        return nonnegative_numbers(text, "SIGMA_Q:SIGMA_QD")
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _effect_type(option):
    """argparse's ``type`` for a plant effect's :class:`~rc3r.plants.base.Option`: its parse, a ValueError
    turned into argparse's one-line error."""
    def parse(text):
        try:
            return option.parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = option.dest  # argparse names a failed type by it
    return parse


def _model_friction(text):
    """``--model-friction``: ``urdf``, or ``KEY=VALUE[;KEY=VALUE...]`` with VALUE ``urdf`` or numbers
    ``a[,b,...]``: the value of ``[model] friction`` (a table), checked by :func:`rc3r.build_run`."""
    if text.strip() == "urdf":
        return "urdf"
    out = {}
    for part in (x.strip() for x in text.split(";") if x.strip()):
        key, sep, value = (x.strip() for x in part.partition("="))
        try:
            nums = [float(v) for v in value.split(",")] if value != "urdf" else None
        except ValueError:
            nums = []
        if not sep or not key or nums == [] or key in out:
            raise argparse.ArgumentTypeError(f"expected urdf or KEY=VALUE[;KEY=VALUE...] (VALUE urdf or numbers "
                                             f"a,b,...; each KEY once), got {text!r}")
        out[key] = "urdf" if nums is None else (nums[0] if len(nums) == 1 and key != "range" else nums)
    if not out:
        raise argparse.ArgumentTypeError(f"expected urdf or KEY=VALUE[;KEY=VALUE...], got {text!r}")
    return out


def plant_args(p, robot_help: bool = True) -> None:
    """The arm and plant options of run, montecarlo and sweep (docs/control.md, "Plants")."""
    if robot_help:
        p.add_argument("--urdf", type=urdf_path,
                       help="the arm from a URDF (any serial arm through Pinocchio; with --robot rr3 the "
                            "3R's closed form)")
        p.add_argument("--lock", type=_lock, action="append", metavar="JOINT=VALUE",
                       help="fix a joint of the URDF at VALUE (repeatable; fingers, mimic joints)")
    from ..plants import registered

    for cls in registered():  # every registered effect's own options (rc3r.plants.base.Effect.cli)
        for opt in cls.cli:
            p.add_argument(opt.flag, dest=opt.dest, type=_effect_type(opt), metavar=opt.metavar, help=opt.help)
    p.add_argument("--noise", type=_noise, metavar="SIGMA_Q:SIGMA_QD",
                   help="sensor noise std on q [rad] and qd [rad/s] (sampled runs; seeded by the run's seed)")
    p.add_argument("--delay", type=_positive(int, allow_zero=True), metavar="SAMPLES",
                   help="samples between a measurement and its torque (sampled runs)")
    p.add_argument("--plant-engine", choices=("pinocchio", "mujoco"),
                   help="rigid body of the plant: Pinocchio (default) or MuJoCo (extra 'mujoco'; the URDF's own "
                        "parameters; for the 3R the consistent arm with Table 1's theta)")
    p.add_argument("--tolerance", type=_positive(), help="tracking tolerance on max|e_j| [rad] of the verdict "
                                                         "(default 0.01)")
    p.add_argument("--model-friction", type=_model_friction, metavar="urdf|KEY=VALUE;...",
                   help="joint friction in the controller's model with a range, for box and payload bounds: "
                        "[model] friction of --config, which this replaces (docs/control.md); e.g. urdf, or "
                        "'viscous=urdf;coulomb=1,2,3;v_s=0.05;range=0.5,1.5'")


def _controllers(text):
    names = [c.strip() for c in text.split(",") if c.strip()]
    bad = [c for c in names if c not in LAWS]
    if not names or bad:
        raise argparse.ArgumentTypeError(f"unknown controller(s) {', '.join(bad) or '(none)'}; "
                                         f"choose from {', '.join(LAWS)}")
    return ",".join(dict.fromkeys(names))


def _campaign_args(p, out: str, plants: bool = False) -> None:
    """Options every campaign shares."""
    if plants:
        p.add_argument("--n", type=_positive(int, allow_zero=True), default=0,
                       help="plants drawn from the box (default 0: the nominal plant, the paper's perturbed case)")
        p.add_argument("--seed", type=_positive(int, allow_zero=True), default=0, help="seed of the plants")
    p.add_argument("--duration", type=_positive(), help="simulated time per run [s] (default 10)")
    p.add_argument("--robot", help=f"a registered robot ({', '.join(ROBOTS)}; default rr3)")
    p.add_argument("--box", help="box TOML (default: the robot's box)")
    p.add_argument("--bounds", metavar="FILE", help="bounds.toml of rc3r identify: the controllers' theta_0, rho, "
                                                    "rho_i, P, and the plants drawn in its ellipsoid")
    p.add_argument("--config", help="TOML with gains, trajectory, bounds (docs/control.md)")
    p.add_argument("--out", default=out, help=f"output directory (default {out})")
    p.add_argument("--workers", type=_positive(int), help="local worker processes (default: all cores)")
    p.add_argument("--scheduler", help="address of a Dask scheduler (tcp://HOST:PORT) instead of local workers")
    p.add_argument("--resume", action="store_true", help="continue the campaign in --out, skipping finished runs")
    p.add_argument("--payload", type=_interval, metavar="LO:HI",
                   help="unknown payload mass on the last link [kg]: plants carry masses of the range, the "
                        "controllers get its exact bounds")
    p.add_argument("--payload-com", type=_vector3, metavar="X,Y,Z",
                   help="payload CoM in the last joint's frame [m] (default 0,0,0)")
    plant_args(p)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="rc3r", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"rc3r {__import__('rc3r').__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    v = sub.add_parser("verify-model", help="cross-check a robot's model and regressor against Pinocchio")
    v.add_argument("--robot", help=f"a registered robot ({', '.join(ROBOTS)}; default rr3, the paper's arm)")
    v.add_argument("--urdf", type=urdf_path,
                   help="a URDF: of the paper's 3R structure (closed form), or with --robot any, or "
                        "with --generic any serial arm through Pinocchio")
    v.add_argument("--generic", action="store_true", help="check --urdf as a generic Pinocchio arm")
    v.add_argument("--lock", type=_lock, action="append", metavar="JOINT=VALUE",
                   help="fix a joint of the URDF at VALUE (repeatable; fingers, mimic joints; implies --generic)")
    v.add_argument("--samples", type=_positive(int), default=1000, help="random states (default 1000)")
    v.add_argument("--seed", type=_positive(int, allow_zero=True), default=0, help="RNG seed (default 0)")
    v.add_argument("--json", action="store_true", help="one JSON object on stdout")

    u = sub.add_parser("make-urdf", help="write the URDF of a parameter file (TOML)")
    u.add_argument("--params", help="parameter TOML (default: Table 1, rc3r/data/rr3.toml)")
    u.add_argument("--out", default="urdf/rr3.urdf", help="output path (default urdf/rr3.urdf)")

    b = sub.add_parser("bounds", help="theta_0 and rho from an uncertainty box")
    b.add_argument("--box", help="box TOML (default: the paper's box)")
    b.add_argument("--urdf", type=urdf_path,
                   help="nominal robot URDF (default: urdf/rr3.urdf; any serial arm through Pinocchio)")
    b.add_argument("--robot", help=f"a registered robot ({', '.join(ROBOTS)}) instead of --urdf")
    b.add_argument("--lock", type=_lock, action="append", metavar="JOINT=VALUE",
                   help="fix a joint of the URDF at VALUE (repeatable)")
    b.add_argument("--payload", type=_interval, metavar="LO:HI",
                   help="bounds of an unknown payload mass on the last link [kg] instead of a box")
    b.add_argument("--payload-com", type=_vector3, metavar="X,Y,Z",
                   help="payload CoM in the last joint's frame [m] (default 0,0,0)")
    b.add_argument("--json", action="store_true", help="one JSON object on stdout")

    r = sub.add_parser("run", help="simulate one controller on one plant")
    r.add_argument("--controller", choices=tuple(LAWS), help="control law (default: config file, else robust)")
    r.add_argument("--perturbed", action="store_true",
                   help="the controller's model is theta_0 and rho of the box, not the plant's theta (the "
                        "plant stays the one --plant names, default nominal = Table 1); default: ideal, the "
                        "controller knows the plant's theta; implied by --payload")
    r.add_argument("--plant", help="plant: nominal (Table 1), upper, lower, paper-upper, "
                                  "corner:<30 bits>, random:<seed> (of the box), or a URDF path")
    r.add_argument("--box", help="box TOML: the plant's box and the controller's bounds (default: the paper's box)")
    r.add_argument("--bounds", metavar="FILE", help="bounds.toml of rc3r identify: the controller's theta_0, rho, "
                                                   "rho_i and ellipsoid (the plant: the file's centre, the "
                                                   "identified robot; or --plant: nominal, random:<seed>, "
                                                   "boundary:<seed>)")
    r.add_argument("--robot", help=f"a registered robot ({', '.join(ROBOTS)}; default: config, else rr3)")
    r.add_argument("--payload", type=_interval, metavar="LO:HI",
                   help="unknown payload mass on the last link [kg]: the plant carries HI (see --plant); the "
                        "controller does not know it: theta_0 and rho are the exact bounds of LO..HI (the run "
                        "is perturbed; [model] theta = \"plant\" in --config gives it the loaded plant's theta)")
    r.add_argument("--payload-com", type=_vector3, metavar="X,Y,Z",
                   help="payload CoM in the last joint's frame [m] (default 0,0,0)")
    r.add_argument("--eps", type=_positive(), help="boundary layer eps of the robust laws")
    r.add_argument("--rate", type=_positive(), help="sampled-data controller at this rate [Hz] "
                                                    "(default: continuous time)")
    r.add_argument("--duration", type=_positive(), help="simulated time [s] (default 10)")
    r.add_argument("--config", help="TOML with gains, trajectory, plant, bounds (docs/control.md)")
    r.add_argument("--engine", choices=ENGINES, help="simulator (default auto: fast when compiled, else python)")
    r.add_argument("--out", help="output directory (default out/run/<name>, e.g. out/run/robust-perturbed)")
    r.add_argument("--force", action="store_true", help="replace an earlier result in --out")
    plant_args(r)
    r.add_argument("--animate", nargs="?", const="gif", choices=("gif", "mp4"),
                   help="also write animation.gif (or .mp4, needs ffmpeg): the arm tracking its trajectory")

    pa = sub.add_parser("paper", help="the five scenarios of section 4, figures and summary")
    pa.add_argument("--out", default="out/paper", help="output directory (default out/paper)")

    mc = sub.add_parser("montecarlo", help="every controller on N plants drawn from the box")
    mc.add_argument("--n", type=_positive(int), default=200, help="plants (default 200)")
    mc.add_argument("--seed", type=_positive(int, allow_zero=True), default=0, help="campaign seed (default 0)")
    mc.add_argument("--controllers", type=_controllers,
                    help=f"comma-separated laws ({', '.join(LAWS)}; default: the config's [controller] kind "
                         "(a design.toml's recommended law) and fbl, else fbl,robust)")
    mc.add_argument("--eps", type=_positive(), help="boundary layer eps of the robust laws")
    mc.add_argument("--rate", type=_positive(), help="sampled-data controller rate [Hz] (default: continuous)")
    _campaign_args(mc, "out/montecarlo")

    sw = sub.add_parser("sweep", help="eps trade-off (sweep eps) or sample-rate stability map (sweep rate)")
    swsub = sw.add_subparsers(dest="what", required=True, parser_class=_Parser)
    se = swsub.add_parser("eps", help="final error bound vs chattering over eps; Pareto plot")
    se.add_argument("--eps", type=_positive(), nargs="+", default=[0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0],
                    help="eps values (default 0.01 ... 2)")
    se.add_argument("--rates", type=_positive(), nargs="*", default=[100000.0],
                    help="sampled rates [Hz] besides continuous time (default 100000)")
    _campaign_args(se, "out/sweep-eps", plants=True)
    sr = swsub.add_parser("rate", help="stable / chattering / clean over eps x rate (x K); stability map")
    sr.add_argument("--eps", type=_positive(), nargs="+", default=[0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0],
                    help="eps values (default 0.05 ... 10)")
    sr.add_argument("--rates", type=_positive(), nargs="+",
                    default=[500.0, 1000.0, 2000.0, 5000.0, 10000.0, 20000.0, 50000.0, 100000.0],
                    help="controller rates [Hz] (default 0.5 ... 100 kHz)")
    sr.add_argument("--K", type=_positive(), nargs="+", help="robust gains K to compare (default: the law's)")
    _campaign_args(sr, "out/sweep-rate", plants=True)

    be = sub.add_parser("bench", help="closed form vs Pinocchio and simulation timings")
    be.add_argument("--json", action="store_true", help="one JSON object on stdout")
    be.add_argument("--quick", action="store_true", help="tiny sizes (CI: correctness only)")
    importlib.import_module(".identify", __package__).add_parsers(sub, _positive, _lock, urdf_path)  # identify, excite
    importlib.import_module(".export", __package__).add_parser(sub)  # export
    importlib.import_module(".design", __package__).add_parser(sub)  # design
    return p


#: command -> (module, function); modules are imported only when their command runs.
_COMMANDS = {
    "verify-model": ("model", "cmd_verify_model"),
    "make-urdf": ("model", "cmd_make_urdf"),
    "bounds": ("bounds", "cmd_bounds"),
    "run": ("run", "cmd_run"),
    "paper": ("run", "cmd_paper"),
    "montecarlo": ("study", "cmd_montecarlo"),
    "sweep": ("study", "cmd_sweep"),
    "bench": ("bench", "cmd_bench"),
    "identify": ("identify", "cmd_identify"),
    "excite": ("identify", "cmd_excite"),
    "export": ("export", "cmd_export"),
    "design": ("design", "cmd_design"),
}


def _dispatch(args) -> int:
    module, func = _COMMANDS[args.command]  # argparse restricts the choices
    return getattr(importlib.import_module(f".{module}", __package__), func)(args)


def _interrupt(signum, frame):
    from ..simulate.status import STOP

    STOP.set()  # survives a KeyboardInterrupt lost inside numba's compiler (rc3r.simulate.status)
    raise KeyboardInterrupt("SIGTERM" if signum == signal.SIGTERM else "SIGINT")


def main(argv=None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); return the exit code.

    SIGTERM is handled as Ctrl-C (``KeyboardInterrupt``) while the command runs; both also set
    :data:`rc3r.simulate.status.STOP`, which the engines check, so a signal lost inside numba's
    compiler still ends the run.
    """
    os.environ.setdefault("MPLBACKEND", "Agg")
    from ..simulate.status import STOP

    old = None
    STOP.clear()
    if threading.current_thread() is threading.main_thread():
        old = (signal.signal(signal.SIGTERM, _interrupt), signal.signal(signal.SIGINT, _interrupt))
    try:
        args = build_parser().parse_args(argv)
        return int(_dispatch(args) or 0)
    except _UsageError as exc:
        print(f"rc3r: error: {exc}", file=sys.stderr)
        return EXIT["bad_input"]
    except Rc3rError as exc:
        print(f"rc3r: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("rc3r: interrupted; the output directory was left as it was before this run", file=sys.stderr)
        return EXIT["interrupted"]
    except Exception as exc:  # a bug: still one line, with a way to get the traceback
        if os.environ.get("RC3R_DEBUG"):
            raise
        print(f"rc3r: internal error: {type(exc).__name__}: {exc} (set RC3R_DEBUG=1 for a traceback)",
              file=sys.stderr)
        return EXIT["internal_error"]
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old[0])
            signal.signal(signal.SIGINT, old[1])


def entry() -> None:  # console script
    sys.exit(main())
