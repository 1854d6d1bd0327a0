r"""Law ``adaptive``: Slotine--Li's adaptive law, one module (:mod:`.base`).

On the sliding variable (:mod:`.sliding`): :math:`\theta_{\mathrm{eff}} = \hat\theta`, the controller
state, with :math:`\dot{\hat\theta} = -\Gamma\, Y^T r` and :math:`\hat\theta(0) = \theta`; :math:`w = -K r`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ._kernels import regressor_transpose
from .base import Layout, _positive, _sized, at, packed, register_law
from .sliding import C_XI_HEAD, Sliding, c_parts, inertia_gain, signals, slopes  # noqa: F401

__all__ = ["Adaptive", "LAYOUT"]

_INLINE = dict(cache=True, nogil=True, inline="always")
_DERIV = dict(_INLINE, error_model="numpy")


@dataclass(frozen=True, eq=False)
class Adaptive(Sliding):
    """Slotine--Li adaptive law; ``theta`` is the initial estimate, ``Gamma`` the adaptation gain.

    Packed as :data:`LAYOUT`.
    """

    Gamma: float | np.ndarray = packed(10.0, ("Gamma", "p"))
    name = "adaptive"
    code = 3

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "Gamma", _sized("Gamma", _positive("Gamma", self.Gamma), self.p))

    def initial_state(self) -> np.ndarray:
        return self.theta.copy()


#: The sliding prefix (:data:`rc3r.controllers.sliding.PREFIX`), then ``Gamma`` (p).
LAYOUT = Layout.of(Adaptive)
_GAMMA = LAYOUT.index("Gamma")
USES_XI = True


@njit(**_INLINE)
def theta(cp, n, z, th_eff, zdot):
    """theta_eff (p,) = theta_hat = z, the state; from ``th_eff`` = xi its rate ``zdot = -Gamma xi``;
    returns ||xi||."""
    p = int(cp[0])
    nrm2 = 0.0
    for j in range(p):
        nrm2 += th_eff[j] * th_eff[j]
    nrm = math.sqrt(nrm2)
    g = at(_GAMMA, n, p)
    for j in range(p):
        zdot[j] = -cp[g + j] * th_eff[j]
        th_eff[j] = z[j]
    return nrm


@njit(**_DERIV)
def directions(cp, Y, r, xs, TB, om, bt):
    """``xs`` = xi = Y^T r and the unit vectors (the p rows of d xi) in ``TB``; returns p."""
    p = Y.shape[1]
    regressor_transpose(Y, r, xs)
    for i in range(p):
        for k in range(p):
            TB[i, k] = 1.0 if k == i else 0.0
    return p


@njit(**_DERIV)
def theta_columns(cp, Y, rows, Ux, Xi, xs, bt):
    """``u = w + Y z``: the columns of z in ``Ux`` (n, 2n + 1 + p) are Y."""
    n, p = Y.shape
    m = 2 * n + 1
    for i in range(n):
        for k in range(p):
            Ux[i, m + k] = Y[i, k]


@njit(**_DERIV)
def state_gain(cp, n):
    """Gamma (p,): ``dz/dt = -Gamma xi``."""
    p = int(cp[0])
    g = at(_GAMMA, n, p)
    return cp[g:g + p]


_C_OUTPUT = C_XI_HEAD + """    for (j = 0; j < RC3R_P; ++j) {
        zdot[j] = -rc3r_Gamma[j] * th[j];
        th[j] = z[j];
    }
    return nrm;"""


def c_source(law, n: int) -> dict:
    """The law in C (:func:`rc3r.export.c.controller_sources`): ``rc3r_Gamma``; the state starts at theta."""
    own = [("rc3r_Gamma", "[RC3R_P]", law.layout().slice(law.pack(n), "Gamma", n), "")]
    return c_parts(law, n, own, _C_OUTPUT, theta0=False)


register_law(Adaptive)
