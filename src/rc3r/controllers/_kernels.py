r"""Compiled helpers every law and kernel supply shares, generic over n joints and p coefficients.

A law ``u = Y(q, \dot q, v, a)\,\theta_{\mathrm{eff}} + w`` is computed in stages around the robot's
regressor: the law's ``signals`` kernel (v, a, r, w); the caller's ``Y``; :func:`regressor_transpose`
(``xi = Y^T r``, for a law with ``USES_XI``); the law's ``theta`` kernel; :func:`apply_regressor`
(``u = Y th_eff + w``). The laws' own kernels live in their modules (:mod:`rc3r.controllers.base`
says which); only the two contractions are here. Only ``xi = Y^T r`` and ``Y th_eff`` enter: a robot's
kernel supply may compute both without forming ``Y`` (:mod:`rc3r.robots.pinocchio_supply`, O(n)).
Each is a leaf (it calls no other jitted function), so its ``py_func`` runs without compiling
anything (the cold start, :func:`rc3r._numba_cache.ready_or_python`).
"""
from __future__ import annotations

from numba import njit

_JIT = dict(cache=True, nogil=True)

#: Inlined into the caller at numba IR level: a robot's compiled simulator calls these once or
#: more per right-hand side, and a separate call with a dozen array arguments costs more than
#: the law's arithmetic (measured: 1.47x on the 10 s robust run without inlining).
_INLINE = dict(_JIT, inline="always")


@njit(**_INLINE)
def regressor_transpose(Y, r, xi):
    """xi (p,) = Y^T r, from Y (n, p) and r (n,)."""
    n, p = Y.shape
    for j in range(p):
        acc = 0.0
        for i in range(n):
            acc += Y[i, j] * r[i]
        xi[j] = acc


@njit(**_INLINE)
def apply_regressor(Y, th_eff, w, u):
    """u = w + Y th_eff, shape (n,), from Y (n, p), th_eff (p,) and w (n,)."""
    n, p = Y.shape
    for i in range(n):
        acc = 0.0
        for j in range(p):
            acc += Y[i, j] * th_eff[j]
        u[i] = w[i] + acc
