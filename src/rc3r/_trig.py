"""sin x and cos x from one argument reduction, compiled (numba): the closed form's trigonometry.

The 3R's closed-form model needs sin and cos of q2 and q3 in every state; libm computes each on its own (two argument reductions per angle, about 11 ns per
call on the development machine: 44 of the 55 ns of the 3R's tau on 2026-12-02, ``rc3r bench``'s
"libm trig" row). :func:`sincos` returns both from one reduction:

.. math::

    x = k \\frac{\\pi}{2} + y, \\quad |y| \\lesssim \\frac{\\pi}{4}, \\qquad
    (\\sin x, \\cos x) = \\text{rotate}_k(\\sin y, \\cos y),

with ``k = round(2 x / pi)``, ``y`` by Cody and Waite's reduction on a three-part ``pi / 2`` (33 +
33 + 53 bits: ``k p_1`` and ``k p_2`` are exact for ``|k| < 2^20``) and ``sin y``, ``cos y`` by
the minimax polynomials of fdlibm's ``__kernel_sin`` and ``__kernel_cos`` (FreeBSD msun
``k_sin.c``, ``k_cos.c``, ``e_rem_pio2.c``: same coefficients; error below one ulp on
``|y| <= pi / 4``). Outside ``|x| < 10^5`` (a joint angle never is; NaN and infinity included) it
calls libm. The batch tau (:func:`rc3r.robots.rr3.kernels.inverse_dynamics_batch`) uses it; the
per-state path of the simulators and the trajectory keep libm (the chattering eps = 0.05 runs
amplify a last-bit difference of a sine into a different torque peak, and the cold start runs the
trajectory interpreted, where a call of this compiled function would compile it). :func:`sincos_fast` is the same without that test and without a branch, for loops
over many states that LLVM runs in SIMD lanes (the caller checks the range first:
:func:`rc3r.robots.rr3.kernels.inverse_dynamics_batch`). Measured error against libm:
``tests/test_trig.py`` (at most 2 ulp of max(1, |result|)).
No library supplies this to numba here: its vector math (SVML) is absent from the llvmlite wheel.
"""
from __future__ import annotations

import math

from numba import njit

__all__ = ["sincos", "sincos_fast", "FAST_LIMIT"]

#: |x| below which the reduction is used (above it, libm): ``k < 2^20`` keeps ``k p_1`` exact.
FAST_LIMIT = 1.0e5

_INVPIO2 = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e+00  # first 33 bits of pi/2
_PIO2_2 = 6.07710050630396597660e-11  # next 33 bits
_PIO2_2T = 2.02226624879595063154e-21  # pi/2 - _PIO2_1 - _PIO2_2

_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10

_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11


@njit(cache=True, nogil=True, fastmath=False)
def sincos_fast(x):
    """(sin x, cos x) for ``|x| < FAST_LIMIT`` (finite), branch-free; outside that range the result is
    undefined (the caller checks: :func:`sincos`).

    Parameters
    ----------
    x : float
        Angle [rad], ``|x| < FAST_LIMIT``.

    Returns
    -------
    (float, float)
        ``sin x`` and ``cos x``, each within 2 ulp of max(1, |value|) of libm's.
    """
    fk = math.floor(x * _INVPIO2 + 0.5)
    y = ((x - fk * _PIO2_1) - fk * _PIO2_2) - fk * _PIO2_2T
    z = y * y
    # fdlibm __kernel_sin (iy = 0): y + y^3 (S1 + z (S2 + ... ))
    r = _S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))
    s = y + z * y * (_S1 + z * r)
    # FreeBSD __kernel_cos (y_tail = 0): 1 - z/2 + z^2 (C1 + ...), the 1 - z/2 part compensated
    w = z * z
    rc = z * (_C1 + z * (_C2 + z * _C3)) + w * w * (_C4 + z * (_C5 + z * _C6))
    hz = 0.5 * z
    one_m = 1.0 - hz
    c = one_m + (((1.0 - one_m) - hz) + z * rc)
    k = int(fk) & 3  # quadrant; selects and exact sign flips, no branch (random angles mispredict)
    odd = (k & 1) == 1
    sx = c if odd else s
    cx = s if odd else c
    return (1.0 - float(k & 2)) * sx, (1.0 - float((k + 1) & 2)) * cx


@njit(cache=True, nogil=True, fastmath=False)
def sincos(x):
    """(sin x, cos x) of a float ``x`` [rad], each within 2 ulp of max(1, |value|) of libm's.

    Parameters
    ----------
    x : float
        Angle [rad]; any value (``|x| >= FAST_LIMIT``, NaN and infinity go to libm).

    Returns
    -------
    (float, float)
        ``sin x`` and ``cos x``.

    Examples
    --------
    >>> from rc3r._trig import sincos
    >>> s, c = sincos(1.0)
    >>> abs(s - 0.8414709848078965) < 1e-15 and abs(c - 0.5403023058681398) < 1e-15
    True
    """
    if not abs(x) < FAST_LIMIT:
        return math.sin(x), math.cos(x)
    return sincos_fast(x)
