"""Parameter uncertainty: boxes on standard parameters and the bounds on theta they imply.

* :mod:`~rc3r.uncertainty.box` -- :class:`Box`, box files, plants drawn from a box;
* :mod:`~rc3r.uncertainty.bounds` -- theta_0 and rho: the paper's method (a) and the
  certified exact ranges (b);
* :mod:`~rc3r.uncertainty.sampled` -- a sampled lower bound on the largest distance.

Every function takes the nominal robot (:class:`rc3r.robots.base.Robot`) and works for
any robot of the contract.
"""
from .bounds import (PAPER_INERTIA_KEYS, Bounds, certified_bounds, certified_radius, paper_bounds,
                     paper_upper, quadratic_box_extrema)
from .box import Box, load_box, parse_box, perturb
from .sampled import SampledRho, sampled_rho, sampled_rho_detail

__all__ = ["Box", "load_box", "parse_box", "perturb", "Bounds", "PAPER_INERTIA_KEYS", "paper_upper",
           "paper_bounds", "certified_bounds", "certified_radius", "quadratic_box_extrema", "SampledRho",
           "sampled_rho", "sampled_rho_detail"]
