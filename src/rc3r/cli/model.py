"""``rc3r verify-model`` and ``rc3r make-urdf``: the model checks and the URDF generator."""
from __future__ import annotations

import json
import math

import numpy as np

from ..errors import ConfigError, ParameterError, UrdfError
from ..io import file_target_problem
from ..robots import DEFAULT_ROBOT, load_robot, load_urdf_robot, robot_class
from ..verify import IDENTIFIABILITY_RTOL, VerifyReport, verify_model
from . import EXIT


def _finite_or_none(x: float):
    return float(x) if math.isfinite(x) else None


def report_to_dict(report: VerifyReport) -> dict:
    """The ``--json`` object: urdf, theta, checks, warnings, pass (+ tol, samples, seed).

    Non-finite errors become ``null`` so the output is strict JSON.
    """
    return {
        "urdf": report.urdf,
        "theta": list(report.theta),
        "checks": {
            name: {
                "max_abs_err": _finite_or_none(c.max_abs_err),
                "max_rel_err": _finite_or_none(c.max_rel_err),
                "tol": c.tol,
                "pass": c.passed,
                **({"detail": c.detail} if c.detail else {}),
            }
            for name, c in report.checks.items()
        },
        "warnings": list(report.warnings),
        "notes": list(report.notes),
        "theta_order": report.theta_order,
        "identifiability": {"s_min_over_s1": _finite_or_none(report.identifiability),
                            "warn_below": IDENTIFIABILITY_RTOL},
        "pass": report.passed,
        "samples": report.samples,
        "seed": report.seed,
    }


def render_text(report: VerifyReport) -> str:
    """Human-readable report: aligned table, theta, warnings, overall PASS/FAIL."""
    w = max(len("check"), *(len(n) for n in report.checks))
    lines = [
        f"rc3r verify-model: {report.urdf}",
        f"{report.samples} random states (seed {report.seed}); "
        "rel err = max|x - ref| / max(1, max|ref|)",
        "",
        f"{'check':<{w}}  {'max abs err':>11}  {'max rel err':>11}  {'tol':>7}  result",
    ]
    for name, c in report.checks.items():
        lines.append(f"{name:<{w}}  {c.max_abs_err:11.3e}  {c.max_rel_err:11.3e}  {c.tol:7.0e}  "
                     f"{'PASS' if c.passed else 'FAIL'}")
    for name, c in report.checks.items():
        if c.detail:
            lines.append(f"  {name}: {c.detail}")
    lines += [f"  note: {note}" for note in report.notes]
    lines += ["", f"theta ({report.theta_order or 'the robot order'}):"]
    for k in range(0, len(report.theta), 5):
        lines.append("  " + "  ".join(f"th{k + j + 1:<2d} = {x:10.6g}"
                                      for j, x in enumerate(report.theta[k:k + 5])))
    lines.append("")
    if report.warnings:
        lines.append("warnings (do not fail the run):")
        lines += [f"  - {wrn}" for wrn in report.warnings]
    else:
        lines.append("warnings: none (every link is physically consistent, every base parameter identifiable)")
    failed = [n for n, c in report.checks.items() if not c.passed]
    lines.append("")
    lines.append("PASS: every check passed" if report.passed
                 else f"FAIL: {len(failed)} check(s) failed: {', '.join(failed)}")
    return "\n".join(lines)


#: Largest |standard parameter| verify-model accepts: beyond it the identities Y theta = tau
#: cannot be checked in double precision (a 1e300 inertia overflows the products).
MAX_PARAMETER = 1e12


def _require_checkable(robot, urdf) -> None:
    """A non-physical robot is bad input (exit 2), not a failed check: mass <= 0, an inertia that is
    not positive definite, or parameters too large to check."""
    where = f"URDF {urdf}" if urdf else f"robot {robot.label!r}"
    try:
        robot.require_simulable()
    except ParameterError as exc:
        raise ParameterError(f"{where} is not a physical robot: {exc}") from None
    std = np.asarray(robot.standard_parameters(), dtype=float)
    big = np.flatnonzero(~(np.abs(std) <= MAX_PARAMETER))
    if big.size:
        name = robot.standard_parameter_names[big[0]]
        raise ParameterError(f"{where}: parameter {name} = {std[big[0]]:g} is beyond {MAX_PARAMETER:g} "
                             "(SI units): not a robot the model can be checked on")


#: Most random states ``verify-model --samples`` takes: the checks hold every state's regressors at
#: once. Measured for the Panda (7 joints, 43 coefficients): 10^4 states 6.0 s and 350 MB peak,
#: 2 x 10^4 10.9 s and 445 MB, so about 1.2 GB and a minute at this many (10^11 would be ~1 PB).
MAX_SAMPLES = 100_000


def cmd_verify_model(args) -> int:
    """Print the report (text or one JSON object); exit 0 iff every check passes, else 1."""
    if args.samples > MAX_SAMPLES:
        raise ConfigError(f"--samples {args.samples} is more than {MAX_SAMPLES} (the checks hold every state "
                          "in memory at once); give fewer")
    lock = dict(args.lock) if getattr(args, "lock", None) else None
    if args.generic or (lock and not args.robot):  # locked joints: an arm read through Pinocchio
        if not args.urdf:
            raise ConfigError(f"{'--generic' if args.generic else '--lock'} needs --urdf PATH")
        robot = load_urdf_robot(args.urdf, lock=lock)
    elif lock:
        from ..runspec import _nominal

        robot = _nominal(args.robot, args.urdf, lock)
    elif args.robot:
        robot = load_robot(args.robot, urdf=args.urdf)
    else:
        try:
            robot = robot_class(DEFAULT_ROBOT).from_urdf(args.urdf)
        except UrdfError as exc:  # another arm: say how to check it
            raise UrdfError(f"{exc} (any serial arm: rc3r verify-model --generic --urdf {args.urdf})") from None
    _require_checkable(robot, args.urdf)
    report = verify_model(robot, samples=args.samples, seed=args.seed)
    if args.json:
        out = report_to_dict(report)
        out["robot"] = robot.describe()
        out["base_parameters"] = robot.p
        print(json.dumps(out, allow_nan=False))
    else:
        print(render_text(report))
    return EXIT["ok"] if report.passed else EXIT["check_failed"]


def cmd_make_urdf(args) -> int:
    """Write the URDF of a parameter TOML (default: the robot's nominal parameters).

    ``--out`` must be a new name or a regular file (never a directory, ``/``, ``''``, a device or
    a symbolic link: :func:`rc3r.io.file_target_problem`), checked before the parameters are read.
    """
    problem = file_target_problem(args.out)
    if problem:
        raise ConfigError(f"--out {args.out!r} {problem}")
    out = robot_class(DEFAULT_ROBOT).make_urdf(args.params, args.out)
    print(f"wrote {out}")
    return EXIT["ok"]
