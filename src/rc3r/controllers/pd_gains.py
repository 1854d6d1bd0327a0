r"""What computed torque (:mod:`.fbl`), PD plus gravity (:mod:`.pd`) and PD+ (:mod:`.pd_plus`) share.

:class:`PDGains`, diagonal ``Kp`` and ``Kd`` packed ``[p, theta, Kp (n), Kd (n)]``, and the kernels of a
law whose :math:`\theta_{\mathrm{eff}}` is the model's :math:`\theta_0` and that has no state:
:func:`theta`, :func:`inertia_gain`, :func:`directions`, :func:`theta_columns`, :func:`state_gain` and the
C of its output (:data:`C_FIXED_OUTPUT`). Those laws' modules import them: each law is still one
module (:mod:`.base`), holding them by name.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .base import Law, Layout, _positive, at, packed

__all__ = ["PDGains", "theta", "inertia_gain", "directions", "theta_columns", "state_gain", "c_constants",
           "C_FIXED_OUTPUT"]

_INLINE = dict(cache=True, nogil=True, inline="always")
_DERIV = dict(_INLINE, error_model="numpy")


@dataclass(frozen=True, eq=False)
class PDGains(Law):
    """Laws with diagonal ``Kp`` and ``Kd`` (> 0), packed ``[p, theta, Kp (n), Kd (n)]``."""

    Kp: float | np.ndarray = packed(100.0, ("Kp", "n"))
    Kd: float | np.ndarray = packed(100.0, ("Kd", "n"))

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "Kp", _positive("Kp", self.Kp))
        object.__setattr__(self, "Kd", _positive("Kd", self.Kd))


_THETA = Layout.of(PDGains).index("theta")

@njit(**_INLINE)
def theta(cp, n, z, th_eff, zdot):
    """theta_eff (p,) = theta_0 (the model's); no state; returns 0 (no xi)."""
    p = int(cp[0])
    t0 = at(_THETA, n, p)
    for j in range(p):
        th_eff[j] = cp[t0 + j]
    return 0.0


@njit(**_INLINE)
def inertia_gain(cp, n):
    """No scheduled gain: 0."""
    return 0.0


@njit(**_DERIV)
def directions(cp, Y, r, xs, TB, om, bt):
    """theta_eff does not depend on xi: no directions (0)."""
    return 0


@njit(**_DERIV)
def theta_columns(cp, Y, rows, Ux, Xi, xs, bt):
    """theta_eff is constant: nothing to add to du/dx."""
    return


@njit(**_DERIV)
def state_gain(cp, n):
    """No controller state: an empty gain."""
    return cp[0:0]


def c_constants(law, n: int) -> list:
    """``rc3r_theta0``, ``rc3r_Kp``, ``rc3r_Kd``: ``(C name, dimensions, values, comment)``."""
    cp = law.pack(n)
    lay = law.layout()
    return [("rc3r_theta0", "[RC3R_P]", lay.slice(cp, "theta", n), ""),
            ("rc3r_Kp", "[RC3R_N]", lay.slice(cp, "Kp", n), ""),
            ("rc3r_Kd", "[RC3R_N]", lay.slice(cp, "Kd", n), "")]


#: The C output of a law with theta_eff = theta_0 and no state (:func:`theta`).
C_FIXED_OUTPUT = """    int j;
    (void)wk; (void)r; (void)z; (void)zdot;
    for (j = 0; j < RC3R_P; ++j)
        th[j] = rc3r_theta0[j];
    return 0.0;"""


