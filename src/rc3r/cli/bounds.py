"""``rc3r bounds``: theta_0 and rho from a box, the paper's method and the certified one side by side."""
from __future__ import annotations

import json
import math

import numpy as np

from ..errors import ParameterError
from ..io import floats as _floats
from ..robots import DEFAULT_ROBOT, robot_class
from ..runspec import resolve_box
from ..uncertainty import certified_bounds, certified_radius, paper_bounds, sampled_rho_detail
from . import EXIT


#: Samples and seed of the lower bound printed by ``rc3r bounds``.
CLI_SAMPLES = 100_000
CLI_SEED = 0


def _first_non_finite(obj, where: str = "") -> str | None:
    """The key path of the first NaN or infinity in a nested dict/list of numbers, or None."""
    if isinstance(obj, float):
        return None if math.isfinite(obj) else where
    items = obj.items() if isinstance(obj, dict) else enumerate(obj) if isinstance(obj, list | tuple) else ()
    for key, value in items:
        found = _first_non_finite(value, f"{where}.{key}" if where else str(key))
        if found is not None:
            return found
    return None


def _compute(robot, box):
    """Both methods and their sampled checks, with numpy's floating-point warnings silenced: a box or
    robot whose numbers overflow gives a one-line refusal (the caller checks every result is finite),
    never ``RuntimeWarning`` lines."""
    try:
        with np.errstate(all="ignore"):
            a = paper_bounds(robot, box)
            b = certified_bounds(robot, box)
            s_b = sampled_rho_detail(robot, box, b.theta0, n=CLI_SAMPLES, seed=CLI_SEED)
            s_a = sampled_rho_detail(robot, box, a.theta0, n=CLI_SAMPLES, seed=CLI_SEED)
            rho_a_box, rho_a_i = certified_radius(b, a.theta0)
    except (np.linalg.LinAlgError, FloatingPointError, OverflowError) as exc:
        raise ParameterError(f"the bounds of box {box.source} on robot {robot.urdf} cannot be computed in double "
                             f"precision ({type(exc).__name__}: {exc}); are its numbers in SI units?") from None
    return a, b, s_a, s_b, rho_a_box, rho_a_i


def _robot(args):
    """The nominal robot: ``--robot`` (default the paper's arm) or ``--urdf`` (the 3R's closed form when
    the URDF is that arm, else any serial arm through Pinocchio), with ``--lock``."""
    from ..errors import UrdfError
    from ..runspec import _nominal

    urdf, name = getattr(args, "urdf", None), getattr(args, "robot", None)
    lock = dict(args.lock) if getattr(args, "lock", None) else None
    if urdf is not None and name is None and not lock:
        try:
            return robot_class(DEFAULT_ROBOT).from_urdf(urdf)
        except UrdfError as exc:
            if "not the 3R arm" not in str(exc):
                raise
    if urdf is None and name is None and not lock:
        return robot_class(DEFAULT_ROBOT).from_urdf(None)
    return _nominal(name, urdf, lock)


def _payload(args, robot) -> int:
    """``rc3r bounds --payload LO:HI [--payload-com X,Y,Z]``: exact theta_0, rho, rho_i of the payload range."""
    from ..uncertainty.payload import payload_bounds

    (lo, hi), com = args.payload, np.zeros(3) if args.payload_com is None else np.asarray(args.payload_com, float)
    with np.errstate(all="ignore"):
        b = payload_bounds(robot, (lo, hi), com)
        rho, rho_i = certified_radius(b, b.theta0)
    out = {"nominal": {"robot": robot.robot_name or robot.name, "urdf": robot.urdf,
                       "locked": dict(robot.locked or {}), "n": robot.n, "p": robot.p,
                       "theta": _floats(robot.theta)},
           "payload": {"mass": [lo, hi], "com": _floats(com)},
           "theta0": _floats(b.theta0), "rho": float(rho), "rho_i": _floats(rho_i),
           "theta_lo": _floats(b.theta_lo), "theta_hi": _floats(b.theta_hi),
           "definition": "exact: theta is affine in the payload mass, so the segment's ends are the ranges; "
                         "theta0 = its centre, rho = sqrt(sum rho_i^2)"}
    bad = _first_non_finite(out)
    if bad is not None:
        raise ParameterError(f"the payload bounds overflow double precision ({bad} is not finite)")
    if getattr(args, "json", False):
        print(json.dumps(out, indent=2, allow_nan=False))
        return EXIT["ok"]
    print(f"nominal robot: {out['nominal']['robot']} ({robot.n} joints, {robot.p} base parameters)")
    print(f"payload: {lo:g}..{hi:g} kg at {tuple(float(c) for c in com)} m in the last joint's frame")
    print(f"rho = {rho:.6g} (exact over the payload range); theta0 and rho_i with --json")
    return EXIT["ok"]


def cmd_bounds(args) -> int:
    """``rc3r bounds [--box FILE] [--urdf PATH] [--json]``: both methods side by side.

    Every number printed is finite: a result that overflowed (NaN, infinity) is refused in one line
    naming it, and the JSON is strict (``allow_nan=False``).
    """
    robot = _robot(args)
    if getattr(args, "payload", None) is not None:
        return _payload(args, robot)
    box = resolve_box(robot, getattr(args, "box", None))
    a, b, s_a, s_b, rho_a_box, rho_a_i = _compute(robot, box)
    out = {
        "nominal": {"urdf": robot.urdf, "theta": _floats(robot.theta)},
        "box": box.to_dict(),
        "paper": a.to_dict(),
        "certified": b.to_dict(),
        "sampled_certified": s_b.to_dict(),
        "sampled_paper": s_a.to_dict(),
        "paper_theta0_certified": {"rho": rho_a_box, "rho_i": _floats(rho_a_i)},
    }
    for key in ("paper", "certified"):
        out[key].pop("box")
    bad = _first_non_finite(out)
    if bad is not None:
        raise ParameterError(f"the bounds of box {box.source} on robot {robot.urdf} overflow double precision "
                             f"({bad} is not finite); are its numbers in SI units?")
    if getattr(args, "json", False):
        print(json.dumps(out, indent=2, allow_nan=False))
        return EXIT["ok"]
    print(f"nominal robot: {robot.urdf}")
    print(f"box: {box.source}")
    print()
    print(f"{'':>9}{'theta(p)':>11}{'(a) theta0':>12}{'(b) lo':>12}{'(b) hi':>12}{'(b) theta0':>12}{'(b) rho_i':>11}")
    for i in range(robot.p):
        print(f"{f'theta_{i + 1}':>9}{b.theta_nominal[i]:11.4f}{a.theta0[i]:12.4f}{b.theta_lo[i]:12.4f}"
              f"{b.theta_hi[i]:12.4f}{b.theta0[i]:12.4f}{b.rho_i[i]:11.4f}")
    print()
    keys = ", ".join(k.capitalize() for k in a.inertia_keys)
    print(f"(a) paper:     theta0 = (theta(p) + theta(p_up))/2, inertia deltas on {keys} only")
    print(f"               rho = ||theta0 - theta(p)|| = {a.rho:.4f}   (covers the nominal robot only)")
    print(f"               over the box: {s_a.rho:.4f} <= max ||theta - theta0(a)|| <= {rho_a_box:.4f}"
          f"   (sampled; certified from (b)'s ranges)")
    print("(b) certified: theta0 = centre of the exact ranges, |theta_i - theta0_i| <= rho_i (attained)")
    print(f"               rho_max = sqrt(sum rho_i^2) = {b.rho:.4f}   (>= ||theta - theta0|| on the whole box)")
    corners = f"all {s_b.n_corners} relevant corners" if s_b.all_corners else f"{s_b.n_corners} random corners"
    print(f"               max over box of ||theta - theta0(b)|| >= {s_b.rho:.4f}   (sampled lower bound: "
          f"seed {s_b.seed}, {s_b.n_uniform} uniform + {corners}, coordinate ascent from {s_b.n_ascent_starts})")
    return EXIT["ok"]
