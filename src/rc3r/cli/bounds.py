"""``rc3r bounds``: theta_0 and rho from a box, the paper's method and the certified one side by side."""
from __future__ import annotations

import json

from ..io import floats as _floats
from ..robots import DEFAULT_ROBOT, robot_class
from ..study import resolve_box
from ..uncertainty import certified_bounds, certified_radius, paper_bounds, sampled_rho_detail
from . import EXIT


#: Samples and seed of the lower bound printed by ``rc3r bounds``.
CLI_SAMPLES = 100_000
CLI_SEED = 0


def cmd_bounds(args) -> int:
    """``rc3r bounds [--box FILE] [--urdf PATH] [--json]``: both methods side by side."""
    robot = robot_class(DEFAULT_ROBOT).from_urdf(getattr(args, "urdf", None))
    box = resolve_box(robot, getattr(args, "box", None))
    a = paper_bounds(robot, box)
    b = certified_bounds(robot, box)
    s_b = sampled_rho_detail(robot, box, b.theta0, n=CLI_SAMPLES, seed=CLI_SEED)
    s_a = sampled_rho_detail(robot, box, a.theta0, n=CLI_SAMPLES, seed=CLI_SEED)
    rho_a_box, rho_a_i = certified_radius(b, a.theta0)
    if getattr(args, "json", False):
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
        print(json.dumps(out, indent=2))
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
