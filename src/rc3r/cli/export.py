"""``rc3r export``: the controller of a run as C99 source, with its check (:mod:`rc3r.export`).

The run is resolved exactly as ``rc3r run`` resolves it (:func:`rc3r.build_run` with the same
options and config file); the directory ``--out`` is checked before any work and written as a
whole (:mod:`._output`). The parser is built on every command line, so this module imports the
library only inside :func:`cmd_export`.
"""
from __future__ import annotations

import sys
from pathlib import Path


def cmd_export(args) -> int:
    """``rc3r export``: write rc3r_controller.{c,h}, check.c, Makefile, states.csv, torques.csv, export.json."""
    from ..controllers.controller import Controller
    from ..errors import ConfigError
    from ..export.c import check_exportable, regressor_source
    from ..export.harness import FILES, write_export
    from ..provenance import provenance
    from ..io import read_config
    from ..runspec import build_run
    from ._output import check_output_path, output_dir
    from .run import model_friction_config, plant_options

    cfg = model_friction_config(read_config(args.config), args)
    spec = build_run(robot=args.robot, controller=args.controller, rate=args.rate, eps=args.eps, config=cfg,
                     **plant_options(args))
    from ..runspec import design_unverified, design_warning

    warning = design_warning(cfg)
    if warning is not None and not args.force:
        raise ConfigError(f"{args.config} is a design that did NOT verify: export refused (give --force to export "
                          "its unverified gains anyway)")
    if warning is not None:
        print(warning, file=sys.stderr)
    ctrl = Controller.from_run(spec)
    check_exportable(ctrl.law, ctrl.trajectory)  # a law, trajectory or robot without a C port: before any work
    regressor_source(ctrl.model)
    out = Path(args.out)
    check_output_path(out)
    if out.is_dir() and any(out.iterdir()) and not args.force:
        raise ConfigError(f"{out} holds an earlier export; give --force to replace it, or another --out")
    print(f"rc3r export: {spec.name}: recording {args.states} calls of the controller from an rc3r simulation "
          f"({spec.options.mode}{'' if spec.options.rate is None else f' at {spec.options.rate:g} Hz'}) ...",
          file=sys.stderr, flush=True)
    with output_dir(out, own=FILES) as tmp:
        info = write_export(spec, tmp, count=args.states, calls_per_sample=args.calls_per_sample,
                            provenance=provenance(config=cfg, seed=spec.seed),
                            unverified=design_unverified(cfg))
    print(f"wrote {out}/rc3r_controller.c and .h ({info['exported']}), {info['calls']} recorded calls; "
          f"check with: make -C {out} check")
    return 0


def add_parser(sub) -> None:
    """The ``export`` subcommand's options (called by :func:`rc3r.cli.build_parser`)."""
    from ..controllers import LAWS
    from ..export.harness import STATES
    from ..robots import ROBOTS
    from . import _positive, plant_args

    e = sub.add_parser("export", help="the controller of a run as C99 source, with a harness that checks it")
    e.add_argument("--robot", help=f"a registered robot ({', '.join(ROBOTS)}; default: config, else rr3)")
    e.add_argument("--config", required=True, help="TOML of the run: gains, trajectory, plant, bounds, rate "
                                                   "(docs/control.md); the design to export")
    e.add_argument("--controller", choices=tuple(LAWS), help="control law (default: config file, else robust)")
    e.add_argument("--rate", type=_positive(), help="controller rate [Hz] (default: the config's, else continuous)")
    e.add_argument("--eps", type=_positive(), help="boundary layer eps of the robust laws")
    e.add_argument("--out", required=True, help="output directory (written as a whole)")
    e.add_argument("--force", action="store_true", help="replace an earlier export in --out; export a design.toml that did not verify")
    e.add_argument("--states", type=_positive(int), default=STATES,
                   help=f"calls recorded for the check (default {STATES})")
    e.add_argument("--calls-per-sample", type=_positive(int), default=1,
                   help="calls of rc3r_control per controller period in the recording (default 1; more also "
                        "checks the zero-order hold, with seeded perturbed states inside the period)")
    plant_args(e)
