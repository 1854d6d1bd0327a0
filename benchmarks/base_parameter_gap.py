"""How clear the numerical rank of the base parameters is: ``python benchmarks/base_parameter_gap.py``.

For the UR5, the Panda (fingers locked) and the paper's 3R through ``PinocchioRobot``, with seeds
0, 1, 2: the number of base parameters, whether the chosen columns are the same for every seed,
the largest greedy residual of a dependent column and the smallest of an independent one
(``rc3r.robots.base_parameters``; docs/generic.md quotes these).
"""
from __future__ import annotations

from pathlib import Path

from rc3r.robots.base_parameters import base_parameters
from rc3r.robots.pinocchio import PinocchioRobot

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    robots = {"ur5": PinocchioRobot.named("ur5"), "panda": PinocchioRobot.named("panda"),
              "rr3": PinocchioRobot.from_urdf(REPO / "urdf" / "rr3.urdf")}
    for name, robot in robots.items():
        bases = [base_parameters(robot.model, seed) for seed in (0, 1, 2)]
        same = all(list(b.independent) == list(bases[0].independent) for b in bases)
        dep = max(float(b.residuals[b.dependent].max()) for b in bases)
        ind = min(float(b.residuals[b.independent].min()) for b in bases)
        print(f"{name:6s} base parameters {bases[0].p:3d}  same set for seeds 0-2: {same}  "
              f"max dependent residual {dep:.2g}  min independent residual {ind:.2g}")


if __name__ == "__main__":
    main()
