"""Bounds from an uncertainty box of your own, then the robust law built on them.

The box (TOML, the format of ``rc3r bounds --box FILE``, docs/bounds.md) puts intervals on the
deltas added to the nominal standard parameters; here a payload-like one, tighter than the
paper's: masses +0..2 kg, CoM +0..0.1 m, inertia entries +0..0.1 kg m^2, and link 3 carrying up
to 5 kg. From it, ``rc3r.uncertainty`` gives theta_0 and rho by the paper's method (a), which covers
the nominal robot only, and by the certified exact ranges (b), whose rho_max covers every robot
of the box. The robust law gets the certified theta_0 and rho_max; the plant is a random robot of
the box; ``rc3r.controllers.guarantee`` predicts the ultimate bound on |e_j|, and the run stays
under it.

Run: ``python examples/custom_box.py [BOX.toml] [--duration=T]`` (default: the box below, written
into a new temporary directory; 5 s).
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

import rc3r
from rc3r.controllers.guarantee import covers, error_bound, inertia_range
from rc3r.uncertainty import certified_bounds, load_box, paper_bounds

BOX = """description = "example: +0..2 kg, +0..0.1 m, +0..0.1 kg m^2 on every link; link 3 +0..5 kg"
[delta]
mass = [0.0, 2.0]
com = [0.0, 0.1]
inertia = [0.0, 0.1]
[[link]]
index = 3
m = [0.0, 5.0]
"""


def main(box_path: str | None = None, duration: float = 5.0, plant: str = "random:3") -> dict:
    if box_path is None:
        box_path = Path(tempfile.mkdtemp(prefix="rc3r-example-")) / "box.toml"
        box_path.write_text(BOX)
    nominal = rc3r.load_robot()
    box = load_box(box_path, nominal.standard_parameter_names)
    a, b = paper_bounds(nominal, box), certified_bounds(nominal, box)
    print(f"box: {box_path}")
    print(f"(a) paper's method: rho = {a.rho:.6g} (covers the nominal robot only)")
    print(f"(b) certified:      rho_max = {b.rho:.6g} (covers every robot of the box; rho_i from "
          f"{b.rho_i.min():.3g} to {b.rho_i.max():.3g})")

    config = {"model": {"theta": "certified", "rho": "certified"}}
    spec = rc3r.build_run(controller="robust", perturbed=True, box=str(box_path), plant=plant, duration=duration,
                          config=config)
    res, m = rc3r.execute(spec)
    res.raise_for_status()
    inside = covers(spec.law, spec.true_rigid.theta)
    m_lo, m_hi = inertia_range(spec.true_rigid, res.q)  # the plant's M(q) over the whole motion
    bound = error_bound(spec.law, m_lo, m_hi, spec.true_rigid.n)
    err = np.array(m["max_abs_error"])
    print(f"robust law on plant '{spec.true_rigid.label}' (||theta - theta_0|| = "
          f"{np.linalg.norm(spec.true_rigid.theta - spec.law.theta):.4g} <= rho = {spec.law.rho:.6g}: {inside}), "
          f"{duration:g} s: {res.verdict if res.ok else res.message}")
    print(f"max|e|          = {' '.join(f'{x:.3g}' for x in err)} rad")
    print(f"predicted bound = {' '.join(f'{x:.3g}' for x in bound)} rad (Spong's UUB, M eigenvalues in "
          f"[{m_lo:.3g}, {m_hi:.3g}] kg m^2)")
    return {"rho_paper": a.rho, "rho_certified": b.rho, "max_abs_error": err, "bound": bound, "covered": inside}


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--duration=")]
    dur = [float(a.split("=", 1)[1]) for a in sys.argv[1:] if a.startswith("--duration=")]
    try:
        main(args[0] if args else None, dur[0] if dur else 5.0)
    except rc3r.Rc3rError as exc:  # a missing or malformed box file: one line, no traceback
        sys.exit(f"custom_box.py: error: {exc}")
