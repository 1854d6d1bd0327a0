r"""Law ``robust``: Spong's robust law, eqs. (3)-(6), one module (:mod:`.base`).

On the sliding variable (:mod:`.sliding`): :math:`\theta_{\mathrm{eff}} = \theta_0 + \delta`,
:math:`\delta = -\rho\, \xi / \max(\|\xi\|, \epsilon)` with :math:`\xi = Y^T r`, :math:`w = -K r`.
Inside the boundary layer :math:`\|\xi\| \le \epsilon` the law is the high gain
:math:`(\rho/\epsilon)\, Y Y^T`: stiff (docs/control.md).
"""
from __future__ import annotations

from dataclasses import dataclass

from numba import njit

from ._kernels import regressor_transpose
from .base import Layout, _nonnegative, _positive, _scalar, at, packed, register_law
from .sliding import (C_XI_HEAD, Sliding, c_parts, inertia_gain, signals, slopes,  # noqa: F401
                      xi_directions, xi_norm)
from .sliding import no_state_gain as state_gain, xi_theta_columns as theta_columns  # noqa: F401

__all__ = ["Robust", "LAYOUT"]

_INLINE = dict(cache=True, nogil=True, inline="always")
_DERIV = dict(_INLINE, error_model="numpy")


@dataclass(frozen=True, eq=False)
class Robust(Sliding):
    """Spong's robust law, eq. (3)-(6), with bound ``rho`` and boundary layer ``eps``.

    Inside the boundary layer ``||Y^T r|| <= eps`` the law is the high gain
    ``(rho / eps) Y Y^T``: stiff (docs/control.md). Packed as :data:`LAYOUT`.
    """

    rho: float = packed(0.0, ("rho", "1"))
    eps: float = packed(0.5, ("eps", "1"))
    name = "robust"
    code = 1
    model_inputs = ("rho",)
    stiff = True

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "rho", _scalar("rho", _nonnegative("rho", self.rho)))
        object.__setattr__(self, "eps", _scalar("eps", _positive("eps", self.eps)))


#: The sliding prefix (:data:`rc3r.controllers.sliding.PREFIX`), then ``rho``, ``eps``.
LAYOUT = Layout.of(Robust)
_THETA, _RHO, _EPS = LAYOUT.index("theta"), LAYOUT.index("rho"), LAYOUT.index("eps")
USES_XI = True


@njit(**_INLINE)
def theta(cp, n, z, th_eff, zdot):
    """Eq. (6): theta_eff (p,) = theta_0 - rho xi / max(||xi||, eps) from ``th_eff`` = xi; returns ||xi||."""
    p = int(cp[0])
    nrm = xi_norm(th_eff, p)
    t0 = at(_THETA, n, p)
    scale = cp[at(_RHO, n, p)] / max(nrm, cp[at(_EPS, n, p)])
    for j in range(p):
        th_eff[j] = cp[t0 + j] - scale * th_eff[j]
    return nrm


@njit(**_DERIV)
def weights(cp, n, xi, om):
    r"""``d theta_eff = diag(om) d xi + beta xi (xi^T d xi)``: ``om`` (p,) = -rho / max(||xi||, eps); returns
    beta = rho / ||xi||^3 outside the layer, 0 inside."""
    p = xi.shape[0]
    nrm = xi_norm(xi, p)
    rho, eps = cp[at(_RHO, n, p)], cp[at(_EPS, n, p)]
    o = -rho / max(nrm, eps)
    for k in range(p):
        om[k] = o
    return rho / (nrm * nrm * nrm) if nrm > eps else 0.0


@njit(**_DERIV)
def directions(cp, Y, r, xs, TB, om, bt):
    """``xs`` = xi = Y^T r, ``om`` and ``bt[0]`` = beta (:func:`weights`), and the directions of
    :func:`rc3r.controllers.sliding.xi_directions` in ``TB``; returns their count."""
    regressor_transpose(Y, r, xs)
    bt[0] = weights(cp, Y.shape[0], xs, om)
    return xi_directions(Y, om, xs, TB)


_C_OUTPUT = C_XI_HEAD + """    {
        const double scale = rc3r_rho / (rc3r_eps > nrm ? rc3r_eps : nrm);
        (void)z; (void)zdot;
        for (j = 0; j < RC3R_P; ++j)
            th[j] = rc3r_theta0[j] - scale * th[j];
    }
    return nrm;"""


def c_source(law, n: int) -> dict:
    """The law in C (:func:`rc3r.export.c.controller_sources`): eq. (6) with ``rc3r_rho``, ``rc3r_eps``."""
    cp, lay = law.pack(n), law.layout()
    own = [("rc3r_rho", "", float(lay.slice(cp, "rho", n)[0]), ""),
           ("rc3r_eps", "", float(lay.slice(cp, "eps", n)[0]), "")]
    return c_parts(law, n, own, _C_OUTPUT)


register_law(Robust)
