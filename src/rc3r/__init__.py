"""rc3r: robust tracking control of a 3R spatial arm from bounds on its dynamic coefficients.

Modules (one concept each): :mod:`rc3r.params` (link parameters, theta),
:mod:`rc3r.urdf` (URDF in/out), :mod:`rc3r.model` (closed-form M, S, g),
:mod:`rc3r.regressor` (Y), :mod:`rc3r.verify` (cross-checks against Pinocchio).
Conventions: ``docs/conventions.md``.
"""
__version__ = "0.1.0"
