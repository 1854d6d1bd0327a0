"""Tracking with and without friction in the controller's model: ``python benchmarks/actuated_tracking.py``.

The 3R with a hand-built ellipsoid over its 15 coefficients (5 % half-widths) and per-joint viscous 2 N m s/rad,
Coulomb 3 N m (v_s = 0.05 rad/s) and offset 0.5 N m (30 %), built as ``tests/test_actuated.py`` builds it (the dict
``load_bounds`` returns for a bounds file with an actuator part). Plant ``random:3`` of that ellipsoid (rigid body
and friction drawn together). Each law runs 2 s on the python engine, continuous and sampled at 1 kHz (the
sampled-data rule's default gains), once with the ActuatedRobot model of the bounds and once with the rigid
bounds alone on the same plant; printed: max |e| per joint [rad] and the ratio of the largest errors
(docs/control.md, "Friction and armature in the controller's model", quotes it).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import rc3r
import rc3r.identify.bounds_file as bounds_file
from rc3r.plants import Plant
from rc3r.robots import load_robot

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_actuated import KINDS, _bounds  # noqa: E402 - the tests' hand-built bounds


_G = {"float_kind": lambda x: f"{x:.3g}"}


def main() -> None:
    arm = load_robot("rr3")
    bd = _bounds(arm, KINDS[:3], np.concatenate([np.full(3, 2.0), np.full(3, 3.0), np.full(3, 0.5)]))
    rigid_bd = {k: v for k, v in bd.items() if k != "actuator"}
    for law in ("robust", "fbl", "robust-coeff", "adaptive", "pd"):
        for rate in (None, 1000.0):
            kw = dict(controller=law, bounds="hand.toml", perturbed=True, duration=2.0, engine="python", rate=rate)
            bounds_file.load_bounds = lambda path, robot=None: bd
            spec = rc3r.build_run(plant="random:3", **kw)
            w = rc3r.simulate(spec.true_plant, spec.law, spec.trajectory, spec.options, model=spec.controller_model)
            bounds_file.load_bounds = lambda path, robot=None: rigid_bd
            rg = rc3r.build_run(plant="nominal", **kw)
            same = Plant(spec.true_plant.rigid.rigid, spec.true_plant.effects)
            wo = rc3r.simulate(same, rg.law, rg.trajectory, rg.options, model=rg.controller_model)
            ew, eo = np.abs(w.e).max(axis=0), np.abs(wo.e).max(axis=0)
            print(f"{law:13s} {'continuous' if rate is None else '1 kHz':10s} ok={w.ok and wo.ok} "
                  f"with {np.array2string(ew, formatter=_G)} without {np.array2string(eo, formatter=_G)} "
                  f"ratio {ew.max() / eo.max():.3f}")


if __name__ == "__main__":
    main()
