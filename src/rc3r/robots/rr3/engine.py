"""The 3R's kernel supply for the compiled engine (:mod:`rc3r.simulate.engines.compiled`).

The closed-form regressor and forward dynamics of :mod:`.kernels` behind the supply contract
of :mod:`rc3r.simulate.engines._template`, on the packed constants
``kc = [theta (15), l2, g0]`` (:func:`pack`). The generic integrators are instantiated on this
module (:attr:`RR3.compiled_kernels`); their arithmetic on the 3R is the one the 3R's own
integrators had (the same kernels called in the same order).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...controllers._kernels import apply_regressor, regressor_transpose
from . import kernels as K

__all__ = ["make_work", "regressor_into", "forward_dynamics_into", "passes_into", "xi_into", "apply_into",
           "mass_into", "pack", "ENGINE"]

_JIT = dict(cache=True, nogil=True, error_model="numpy")


def pack(robot) -> np.ndarray:
    """``kc = [theta (15), l2, g0]`` of a :class:`RR3`."""
    return np.concatenate([np.asarray(robot.theta, dtype=float), [robot.params.lengths[1], robot.params.g0]])


@njit(**_JIT)
def make_work(kc):
    """The 3x3 and 3-vector scratch of :func:`.kernels.forward_dynamics_into`."""
    return np.empty((3, 3)), np.empty(3)


@njit(**dict(_JIT, inline="always"))
def regressor_into(kc, q, qd, v, a, Y, wk):
    """Y (3, 15) of :func:`.kernels.slotine_li_scalars`."""
    K.slotine_li_scalars(q[1], q[2], qd[0], qd[1], qd[2], v[0], v[1], v[2], a[0], a[1], a[2], kc[15], kc[16], Y)


@njit(**dict(_JIT, inline="always"))
def forward_dynamics_into(kc, q, qd, tau, qdd, wk):
    """qdd of the closed form (theta = kc[:15]); False if M is not PD."""
    return K.forward_dynamics_into(kc, q, qd, tau, kc[15], kc[16], qdd, wk[0], wk[1])



@njit(**dict(_JIT, inline="always"))
def passes_into(kc, q, qd, v, a, Y, wk):
    """Y (3, 15) itself (:func:`regressor_into`): the closed form is cheaper formed than contracted."""
    regressor_into(kc, q, qd, v, a, Y, wk)


@njit(**dict(_JIT, inline="always"))
def xi_into(kc, Y, r, xi, wk):
    """xi = Y^T r on the formed Y."""
    regressor_transpose(Y, r, xi)


@njit(**dict(_JIT, inline="always"))
def apply_into(kc, Y, th, w, u, wk):
    """u = w + Y th on the formed Y."""
    apply_regressor(Y, th, w, u)



@njit(**dict(_JIT, inline="always"))
def mass_into(kc, q, th, r, out, Y, wk):
    """out = M_th(q) r of the closed form (section 3.1; ``wk[0]`` holds M)."""
    K.mass_matrix_into(th, q, wk[0])
    for i in range(3):
        out[i] = wk[0][i, 0] * r[0] + wk[0][i, 1] * r[1] + wk[0][i, 2] * r[2]


#: This module's dotted name, what :attr:`RR3.compiled_kernels` hands to the engine.
ENGINE = __name__
