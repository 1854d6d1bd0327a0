"""Compiled helpers of the plant and the loop, generic over n: the slot arithmetic of an effect's
:class:`~rc3r.plants.base.Layout` (:func:`at`) and the loop's measurement of
:class:`rc3r.plants.loop.LoopEffects` (:func:`measure`).

Each compiled effect's own kernels live in its module (:mod:`rc3r.plants.friction`,
:mod:`rc3r.plants.saturation`, ...); the engines reach them through the dispatch generated from
:data:`rc3r.plants.EFFECTS` (:mod:`rc3r.simulate.engines._effects`).
"""
from __future__ import annotations

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True, error_model="numpy")
#: Options of an effect's kernels: inlined into the generated dispatch (one copy, in it).
KERNEL_JIT = dict(_JIT, inline="always")


@njit(**KERNEL_JIT)
def at(slot, o, n):
    """Index in ``fx`` of the field ``slot = (a, b)`` (:attr:`Layout.slots`) of the block at ``o``, n joints."""
    return o + slot[0] * n + slot[1]


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
