"""Orders and names every layer shares, defined once at the bottom of the package (docs/conventions.md).

:data:`STD_KEYS` is Pinocchio's order of a body's 10 standard parameters: the robots write their
standard parameters in it (:mod:`rc3r.robots.base_parameters`), the payload bounds read it
(:mod:`rc3r.uncertainty.payload`), the identification's consistency check states it
(:mod:`rc3r.identify.consistency`).
"""
from __future__ import annotations

__all__ = ["STD_KEYS"]

#: Pinocchio's 10 standard parameters of a body, about the joint-frame origin, in the
#: joint frame (``pinocchio.Inertia.toDynamicParameters`` order): mass [kg], first
#: moments m c [kg m], inertia entries [kg m^2].
STD_KEYS = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
