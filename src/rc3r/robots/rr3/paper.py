r"""The paper's data of its 3R arm (section 4): box, gains, trajectory, sampled rate. The experiment
(scenarios, claims) is :mod:`rc3r.experiments.paper3r`, above the library.

Scenario reading that reproduces the paper (docs/control.md):

* **ideal** -- the controller's model theta is the plant's own theta;
* **perturbed** -- the plant is the Table 1 robot and the controllers use the
  paper's ``theta_0`` (Table 3) and ``rho = 186.8129`` (method (a) of
  :mod:`rc3r.uncertainty.bounds` on :func:`paper_box`);
* trajectory :math:`q_d = (\sin t, 5\cos t, \sin t)`, start on it, 10 s.
"""
from __future__ import annotations

import math
from importlib import resources

from ...io import tomllib
from ...trajectory import Sines
from ...uncertainty.box import Box, parse_box
from .params import PARAM_NAMES

__all__ = ["paper_box", "paper_trajectory", "PAPER_GAINS", "PAPER_SAMPLED_RATE"]

#: Gains of section 4 (FBL: Kp = Kd = 100; robust: K = 100, Lambda = 50, eps = 0.5).
PAPER_GAINS = {
    "fbl": {"Kp": 100.0, "Kd": 100.0},
    "robust": {"K": 100.0, "Lambda": 50.0, "eps": 0.5},
}

#: Controller rate [Hz] of the paper's scenarios in sampled mode: the lowest of
#: 1, 2, 5, 10, 20, 50, 100 kHz at which the eps = 0.5 robust law runs the whole 10 s
#: without chattering (measured 2026-11-22: 1-2 kHz diverge, 5-50 kHz chatter;
#: docs/control.md). At this rate eps = 0.05 still chatters: the trade-off of section 4.
PAPER_SAMPLED_RATE = 100_000.0

def paper_box() -> Box:
    """The box of section 4: ``dm in [0, 10]``, ``dr_c in [0, 1]``, ``dI in [0, 1]`` for every entry.

    Packaged as ``rc3r/robots/rr3/data/paper_box.toml``.
    """
    text = resources.files(__package__).joinpath("data/paper_box.toml").read_text()
    return parse_box(tomllib.loads(text), PARAM_NAMES, "rc3r/robots/rr3/data/paper_box.toml")


def paper_trajectory() -> Sines:
    r"""The paper's :math:`q_d(t) = (\sin t,\ 5\cos t,\ \sin t)` (section 3.3)."""
    return Sines((0.0, 0.0, 0.0), ((1, 1.0, 1.0, 0.0), (2, 5.0, 1.0, math.pi / 2), (3, 1.0, 1.0, 0.0)))
