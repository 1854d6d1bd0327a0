"""The measurements behind the default gains not given by the paper (docs/control.md, "One gain table").

``python benchmarks/gain_choice.py`` runs, on the paper's perturbed scenario (10 s, continuous time):
the adaptive law with Gamma = 1 and Gamma = 10 (how far the estimate moves, and the tracking
error), and PD + gravity with Kp = 100 and Kp = 500 (Kd = 100).
"""
from __future__ import annotations

import numpy as np

from rc3r.runspec import build_run, execute


def main() -> None:
    for gamma in (1.0, 10.0):
        spec = build_run(controller="adaptive", perturbed=True, config={"controller": {"Gamma": gamma}})
        res, m = execute(spec)
        z0, zT = res.z[0], res.z[-1]
        print(f"adaptive Gamma = {gamma:4g}: {res.message}; ||theta_hat(10) - theta_hat(0)|| / ||theta_hat(0)|| = "
              f"{np.linalg.norm(zT - z0) / np.linalg.norm(z0):.3g}; max|e| = {max(m['max_abs_error']):.3g} rad")
    for kp in (100.0, 500.0):
        spec = build_run(controller="pd", perturbed=True, config={"controller": {"Kp": kp, "Kd": 100.0}})
        res, m = execute(spec)
        print(f"pd Kp = {kp:4g}, Kd = 100: {res.message}; max|e| per joint = "
              + ", ".join(f"{x:.3g}" for x in m["max_abs_error"]) + " rad")


if __name__ == "__main__":
    main()
