"""The held loop's gain of a design's laws on another plant: T lambda_max(M_p^-1 G) along the reference.

``python benchmarks/design_loop_gain.py DESIGN.toml BOUNDS.toml`` evaluates the gains of a design
(``rc3r design``'s design.toml; eq. 6 ``robust`` and eq. 7 ``robust-coeff``) with M_p the mass matrix of
the centre of an identification's bounds.toml (``rc3r identify``'s physically consistent estimate of the
real arm), beside the figure on the design's own controller model, on the hardest plant of the design's
own URDF uncertainty ([plant] urdf_uncertainty, rc3r.uncertainty.urdf: its lightest plant), and the worst
of the 2^n plants whose links are the URDF's (payload at its light end) scaled by s or 1 (s = 0.5, 0.3,
0.2, 0.1). The held loop of period T is stable
while the figure is below 2 (docs/design.md, "Hardest plants"). Used in docs/design.md ("What the URDF
uncertainty does not cover") with the Panda log of Gaz et al. (RA-L 2019).
"""
from __future__ import annotations

import itertools
import sys

import numpy as np

from rc3r.design.rule import spectrum
from rc3r.design.verify import _resolve, controller_model
from rc3r.design.worst import Hardest, plant_gain
from rc3r.identify.bounds_file import load_bounds
from rc3r.io import read_config


def main(design_path: str, bounds_path: str) -> None:
    cfg = read_config(design_path)
    rate = float(cfg["simulation"]["rate"])
    spec, rho_i = _resolve(cfg, rate)
    hard = Hardest(cfg, spec, controller_model_spectrum(spec), rate, 0)
    m_other = hard.search.mass(load_bounds(bounds_path, robot=spec.controller_model)["theta0"])
    gains = {}
    for law in ("robust", "robust-coeff"):
        g = dict(cfg["gains"][law])
        sl = {k: g[k] for k in ("K", "Lambda", "K_inertia") if k in g}
        gains[law] = (hard.gains(sl, rho=spec.model["rho"], eps=g["eps"]) if law == "robust"
                      else hard.gains(sl, rho_i=rho_i, eps_i=g["eps_i"]))
        found = hard.plants(sl, rho=spec.model["rho"], eps=g["eps"]) if law == "robust" else \
            hard.plants(sl, rho_i=rho_i, eps_i=g["eps_i"])
        print(f"{law}: T lambda_max on the controller's model {np.max(plant_gain(gains[law], hard.search.M0)[0]) / rate:.3f}, "
              f"on the bounds' centre {np.max(plant_gain(gains[law], m_other)[0]) / rate:.3f}, on the design's hardest "
              f"plant {found[0]['spec']} {found[0]['T_lambda']:.3f} (limit 2; K = {g['K']}, b = {g.get('K_inertia', 0)}, "
              f"{'eps' if law == 'robust' else 'eps_i'} = {g.get('eps', g.get('eps_i'))})")
    if not cfg.get("payload"):
        return
    from rc3r.plant_sets import _payload, _payload_plant

    lower = _payload_plant(spec.controller_model, _payload(cfg["payload"]["mass"], cfg["payload"].get("com")), "lower")
    pi0 = lower.standard_parameters().copy()
    for s in (0.5, 0.3, 0.2, 0.1):
        worst = 0.0
        for bits in itertools.product((s, 1.0), repeat=len(pi0) // 10):
            pi = pi0 * np.repeat(bits, 10)
            worst = max(worst, np.max(plant_gain(gains["robust"], hard.search.mass(
                lower.with_standard_parameters(pi, "scaled").theta))[0]) / rate)
        print(f"robust: links scaled by {s} or 1 ({2 ** (len(pi0) // 10)} plants): worst T lambda_max {worst:.3f}")


def controller_model_spectrum(spec):
    return spectrum(controller_model(spec), spec.trajectory, 10.0)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__.split("\n\n")[1])
    main(sys.argv[1], sys.argv[2])
