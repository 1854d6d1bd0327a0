"""Compiled plant and loop effects, generic over n: the fields of :meth:`rc3r.plants.base.Plant.pack`
and of :class:`rc3r.plants.loop.LoopEffects`, applied by every compiled engine.

``fx = [viscous (n), coulomb (n), offset (n), v_s, u_max (n)]``: with no effect (zeros and
``inf``) :func:`apply_effects` returns ``u`` bit for bit, so a rigid plant's arithmetic is the
one it always was.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True, error_model="numpy")


@njit(**_JIT)
def actuate(fx, u, out):
    """The delivered torque: ``u`` clipped to ``|u_j| <= u_max_j``."""
    n = u.shape[0]
    base = 3 * n + 1
    for j in range(n):
        lim = fx[base + j]
        x = u[j]
        out[j] = lim if x > lim else (-lim if x < -lim else x)


@njit(**_JIT)
def apply_effects(fx, qd, ua, tau):
    """Joint torque ``tau = ua - (F_v qd + F_c tanh(qd / v_s) + offset)`` for the delivered torque ``ua``."""
    n = ua.shape[0]
    vs = fx[3 * n]
    for j in range(n):
        tau[j] = ua[j] - (fx[j] * qd[j] + fx[n + j] * math.tanh(qd[j] / vs) + fx[2 * n + j])


@njit(**_JIT)
def measure(x, k, noise, quant, qm, qdm):
    """The controller's measurement at sample ``k`` (:mod:`rc3r.plants.loop`): noise row k (if any),
    then ``q`` quantized to ``quant`` (0: none)."""
    n = qm.shape[0]
    noisy = noise.shape[0] > 0
    for j in range(n):
        qm[j] = x[j] + (noise[k, j] if noisy else 0.0)
        qdm[j] = x[n + j] + (noise[k, n + j] if noisy else 0.0)
        if quant[j] > 0.0:
            qm[j] = quant[j] * np.rint(qm[j] / quant[j])


@njit(**_JIT)
def has_friction(fx, n):
    """True if ``fx`` has a joint torque (viscous, Coulomb or offset friction) on some joint."""
    for j in range(3 * n):
        if fx[j] != 0.0:
            return True
    return False


@njit(**dict(_JIT, inline="always"))
def joint_torque(fx, fric, qd, ua, tau):
    """``tau`` = the joint torque for the delivered ``ua``: :func:`~rc3r.plants._kernels.apply_effects`
    if ``fric`` (:func:`has_friction`), else ``ua`` itself (what apply_effects returns then, ``ua - 0``, without its tanh calls)."""
    if fric:
        apply_effects(fx, qd, ua, tau)
    else:
        for j in range(ua.shape[0]):
            tau[j] = ua[j]
