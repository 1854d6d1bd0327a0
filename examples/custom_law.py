"""A control law of your own, written in plain Python, on the paper's arm.

The law: Spong's robust law with a smooth saturation instead of the boundary layer,

    theta_eff = theta_0 - rho * tanh(xi / eps),   xi = Y^T r   (per coefficient),
    u         = Y(q, qd, v, a) theta_eff - K r,

one class and one registration. It has no compiled kernel, so it runs in the generic
Python engine, here as a 1 kHz digital controller (sampled mode) on the perturbed plant,
next to the built-in eq. (7) law with the same bounds. Run: ``python examples/custom_law.py``.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

import rc3r
from rc3r.controllers import Law, register_law


@register_law
@dataclass(frozen=True, eq=False)
class TanhRobust(Law):
    """Per-coefficient robust law with a tanh saturation; gains K [N m s/rad], Lambda [1/s]."""

    K: float = 100.0
    Lambda: float = 50.0
    rho_i: float | np.ndarray = 0.0
    eps: float = 50.0
    name = "tanh-robust"
    model_inputs = ("rho_i",)

    def signals(self, q, qd, ref):
        e, ed = q - ref[0], qd - ref[1]
        r = ed + self.Lambda * e
        return ref[1] - self.Lambda * e, ref[2] - self.Lambda * ed, r, -self.K * r

    def output(self, Y, r, z):
        xi = Y.T @ r
        return self.theta - self.rho_i * np.tanh(xi / self.eps), np.zeros(0), float(np.linalg.norm(xi))


def main(duration: float = 2.0) -> dict:
    # the run specification gives the plant, theta_0 and the certified rho_i of the paper's box
    spec = rc3r.build_run(controller="robust-coeff", perturbed=True, rate=1000.0, duration=duration,
                          config={"model": {"theta": "certified"}})
    law = rc3r.make_law("tanh-robust", spec.model["theta0"], rho_i=spec.model["rho_i"])
    opts = rc3r.SimOptions(duration=duration, rate=1000.0)
    mine = rc3r.simulate(spec.plant, law, spec.trajectory, opts)
    eq7 = rc3r.simulate(spec.plant, spec.law, spec.trajectory, opts)
    out = {}
    for res in (mine, eq7):
        out[res.controller["name"]] = float(np.abs(res.e).max())
        print(f"{res.controller['name']:>13} on '{res.plant}' ({res.engine} engine, {res.mode} "
              f"{res.options.rate:g} Hz, {duration:g} s): {res.message}, max|e| = {np.abs(res.e).max():.3g} rad")
    return out


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 2.0)
