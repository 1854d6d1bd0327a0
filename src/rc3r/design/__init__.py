"""``rc3r design``: gains and boundary layer for a controller rate, verified over the bounds (docs/design.md).

* :mod:`rc3r.design.rule` -- the sampled-data rule and its fast form (no simulation);
* :mod:`rc3r.design.verify` -- the fast form checked by simulation over the bounds at the rate and at
  rate / margin, eps tightened while every run stays clean;
* :mod:`rc3r.design.worst` -- the hardest plants of the bounds for a law's gains at the rate;
* :mod:`rc3r.design.report` -- ``design.toml``, ``design.md`` and the figure.
"""
from .rule import Design, Spectrum, check, eps_boundary, fast_design, real_limit, sampled_gains, spectrum, \
    stability_limit

__all__ = ["Design", "Spectrum", "check", "eps_boundary", "fast_design", "real_limit", "sampled_gains", "spectrum",
           "stability_limit"]
