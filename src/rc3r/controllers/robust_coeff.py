r"""Law ``robust-coeff``: Spong's law with per-coefficient bounds, eq. (7), one module (:mod:`.base`).

On the sliding variable (:mod:`.sliding`): :math:`\delta_i = -\rho_i\, \xi_i / \max(|\xi_i|, \epsilon_i)`,
:math:`\xi = Y^T r`, :math:`\theta_{\mathrm{eff}} = \theta_0 + \delta`, :math:`w = -K r`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ._kernels import regressor_transpose
from .base import Layout, _nonnegative, _positive, _sized, at, packed, register_law
from .sliding import (C_XI_HEAD, Sliding, c_parts, inertia_gain, signals, slopes,  # noqa: F401
                      xi_directions, xi_norm)
from .sliding import no_state_gain as state_gain, xi_theta_columns as theta_columns  # noqa: F401

__all__ = ["RobustPerCoefficient", "LAYOUT"]

_INLINE = dict(cache=True, nogil=True, inline="always")
_DERIV = dict(_INLINE, error_model="numpy")


@dataclass(frozen=True, eq=False)
class RobustPerCoefficient(Sliding):
    """Eq. (7): per-coefficient bounds ``rho_i`` (p,) and boundary layers ``eps_i``. Packed as :data:`LAYOUT`."""

    rho_i: float | np.ndarray = packed(0.0, ("rho_i", "p"))
    eps_i: float | np.ndarray = packed(0.5, ("eps_i", "p"))
    name = "robust-coeff"
    code = 2
    model_inputs = ("rho_i",)
    stiff = True

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "rho_i", _sized("rho_i", _nonnegative("rho_i", self.rho_i), self.p))
        object.__setattr__(self, "eps_i", _sized("eps_i", _positive("eps_i", self.eps_i), self.p))


#: The sliding prefix (:data:`rc3r.controllers.sliding.PREFIX`), then ``rho_i`` (p), ``eps_i`` (p).
LAYOUT = Layout.of(RobustPerCoefficient)
_THETA, _RHO, _EPS = LAYOUT.index("theta"), LAYOUT.index("rho_i"), LAYOUT.index("eps_i")
USES_XI = True


@njit(**_INLINE)
def theta(cp, n, z, th_eff, zdot):
    """Eq. (7): theta_eff_i = theta_0i - rho_i xi_i / max(|xi_i|, eps_i) from ``th_eff`` = xi; returns ||xi||."""
    p = int(cp[0])
    nrm = xi_norm(th_eff, p)
    t0, ro, eo = at(_THETA, n, p), at(_RHO, n, p), at(_EPS, n, p)
    for j in range(p):
        th_eff[j] = cp[t0 + j] - cp[ro + j] * th_eff[j] / max(abs(th_eff[j]), cp[eo + j])
    return nrm


@njit(**_DERIV)
def weights(cp, n, xi, om):
    """``d theta_eff = diag(om) d xi``: ``om_k = -rho_k / eps_k`` inside coefficient k's layer
    ``|xi_k| <= eps_k``, 0 outside (there theta_k = theta_0k - rho_k sign(xi_k)); returns beta = 0."""
    p = xi.shape[0]
    ro, eo = at(_RHO, n, p), at(_EPS, n, p)
    for k in range(p):
        om[k] = -cp[ro + k] / cp[eo + k] if abs(xi[k]) <= cp[eo + k] else 0.0
    return 0.0


@njit(**_DERIV)
def directions(cp, Y, r, xs, TB, om, bt):
    """``xs`` = xi = Y^T r, ``om`` (:func:`weights`) and the directions of
    :func:`rc3r.controllers.sliding.xi_directions` in ``TB``; returns their count."""
    regressor_transpose(Y, r, xs)
    bt[0] = weights(cp, Y.shape[0], xs, om)
    return xi_directions(Y, om, xs, TB)


_C_OUTPUT = C_XI_HEAD + """    (void)z; (void)zdot;
    for (j = 0; j < RC3R_P; ++j) {
        const double x = fabs(th[j]);
        th[j] = rc3r_theta0[j] - rc3r_rho_i[j] * th[j] / (rc3r_eps_i[j] > x ? rc3r_eps_i[j] : x);
    }
    return nrm;"""


def c_source(law, n: int) -> dict:
    """The law in C (:func:`rc3r.export.c.controller_sources`): eq. (7) with ``rc3r_rho_i``, ``rc3r_eps_i``."""
    cp, lay = law.pack(n), law.layout()
    own = [("rc3r_rho_i", "[RC3R_P]", lay.slice(cp, "rho_i", n), ""),
           ("rc3r_eps_i", "[RC3R_P]", lay.slice(cp, "eps_i", n), "")]
    return c_parts(law, n, own, _C_OUTPUT)


register_law(RobustPerCoefficient)
