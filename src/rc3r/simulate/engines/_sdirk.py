r"""The SDIRK3 periods' kernel-independent parts (numba): Alexander's table, the friction block of Newton's
matrix, and the step's error control, outside the template :mod:`.compiled` (one compile for every supply;
:func:`rc3r.simulate.engines.compiled._sdirk_period` calls them with the effects' slopes it evaluates).

**The error control at the Coulomb knee** (issue 37; measured in docs/performance.md, "Stiff friction: the
sampled periods"). The embedded order-2 estimate ``e = (q_e, qd_e)`` is filtered by Newton's matrix at the
new state, as RADAU5's (Hairer & Wanner IV.8): ``qd_e <- (I + h g M^-1 D)^-1 qd_e``, ``q_e <- q_e + h g
qd_e``, ``D`` the effects' damping ``-d tau / d qd`` per joint. With ``knee`` set (the default path) two
things change:

* the velocity part is filtered over the **rest of the period** instead of the step: ``qd_e <- (I + tau
  M^-1 D)^-1 qd_e`` with ``tau = max(h g, T - t - h)``. A velocity error committed inside the period in a
  direction the friction damps at rate ``lambda`` is damped by the flow before the controller samples it
  (by ``1 / (1 + lambda tau)``, the backward-Euler bound of ``exp(-lambda tau)``); the last step of a
  period (``tau = h g``) is filtered as before, so the sampled velocity is held to the tolerances. This
  stops the knee's initial layer (the held torque jumps at every sample, a sticking joint's velocity
  relaxes to its new creep value in ~10 us) from cutting the first step of every period to that layer.
* a step is refused when some joint's damping changes by more than :data:`SLOPE_GUARD` times across it
  (:func:`slope_ratio`, on the damping plus :data:`KNEE_FLOOR` times its peak): the embedded estimate is a
  Taylor argument and misjudges a step that jumps
  across the knee (a break-away from sticking, 1e-6 rad off on the Z1 when only the first change is
  made); the guard makes such a step resolve the knee whatever the estimate says.

The first change trusts the flow to damp what a step leaves; SDIRK3 damps it by its own factor per later
step, ``R(-h lambda)`` (within 25 % of ``1 / (1 + g h lambda)`` from h lambda = 30 on), not by the exact
``exp(-lambda tau)``. So the rest-of-period filter may forgive at most :data:`FORGIVE` times the
tolerances: the step's own norm (filtered over the step) must still be under ``FORGIVE``. (A bound, not a
measured necessity: the runs that seemed to show a 0.057 rad/s miss without it were of a version with a
bug, since fixed; the mutation check in docs/testing.md says what the tests see without it.)

Without ``knee`` the control is the one of 2026-12-06 (the step's own filter, no guard): the path the
benchmarks compare with.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from rc3r.simulate.engines._linalg import _lu_factor, _lu_solve

__all__ = ["SG", "TABLE", "BHAT", "NEWTON_MAX", "NEWTON_TOL", "SLOPE_GUARD", "KNEE_FLOOR", "MI_REUSE", "FORGIVE", "factor",
           "error_norm", "slope_ratio"]

_JIT = dict(cache=True, nogil=True, error_model="numpy")

#: Alexander's SDIRK3 (SIAM J. Numer. Anal. 14 (1977); Hairer & Wanner II, IV.6, Table 6.5): L-stable and
#: stiffly accurate, order 3 in 3 implicit stages of diagonal gamma = :data:`SG`; the embedded order-2
#: weights :data:`BHAT` (b^_3 = 0) use the first two stages. Rows: (c_i, a_i1, a_i2, a_i3); the last row is b.
SG = 0.4358665215084590
TABLE = np.array([
    [SG, SG, 0.0, 0.0],
    [(1.0 + SG) / 2.0, (1.0 - SG) / 2.0, SG, 0.0],
    [1.0, -(6.0 * SG * SG - 16.0 * SG + 1.0) / 4.0, (6.0 * SG * SG - 20.0 * SG + 5.0) / 4.0, SG]])
BHAT = np.array([1.0 - (1.0 - 2.0 * SG) / (1.0 - SG), (1.0 - 2.0 * SG) / (1.0 - SG), 0.0])
#: Newton iterations of one stage before the step is rejected and halved.
NEWTON_MAX = 10
#: A stage has converged when Newton's update, in units of the tolerances' scale, is below this (RADAU5's
#: kappa is 0.03-0.1). Measured on the Z1's 500 periods of ``benchmarks/period_methods.py`` with an
#: instrumented copy of the period (not kept): 1e-3 (the value before) 2.28 iterations per stage, 3e-2 2.09,
#: the end states unchanged to 2 digits (2.2e-8 rad).
NEWTON_TOL = 3e-2
#: Largest ratio of a joint's damping (:func:`slope_ratio`) across an accepted step (``knee`` path). 10
#: measured on the Z1 (the same instrumented copy, without :data:`KNEE_FLOOR` and :data:`MI_REUSE`): 3 costs 77.6 right-hand sides per period (q 2.6e-8 rad from the yardstick), 10
#: 68.7 (4.5e-8), 30 the same cost at 5.7e-8 but 1.1e-6 at period_rtol 3e-4; without it 72.0 (1.4e-6).
SLOPE_GUARD = 10.0
#: The guard compares ``d_j(qd) + KNEE_FLOOR d_j(0)`` at the step's ends (``d_j(0)``: the joint's slope at
#: rest, the knee's peak): a pure Coulomb joint's slope outside its knee, ``F_c / v_s sech^2(qd / v_s)``,
#: moves by orders of magnitude while it is negligible, which must not refuse every step there.
KNEE_FLOOR = 0.01
#: Periods one inverse mass matrix of Newton's matrix is kept for (``knee`` path; refreshed, and the step
#: retried, when a stage fails to converge on a kept one). Newton's matrix is an approximation anyway (the
#: rigid body's slopes are left out), and M moves by about |dq| / rad relatively. Measured on 500 periods
#: of ``benchmarks/period_methods.py`` (the instrumented copy): the xArm7's 19.5 right-hand sides per period fall to 14.3 (4
#: periods) and 13.4 (10), the Z1's 69.1 to 64.6 and 63.7, the end states unchanged to 2 digits.
MI_REUSE = 4.0
#: Most the rest-of-period filter may forgive (``knee`` path): a step's error norm filtered over the step
#: alone must stay under this.
FORGIVE = 10.0


@njit(**_JIT)
def factor(Mi, d, hg, N, piv):
    """``N = I + hg Mi diag(d)`` (n, n), LU-factored in place (``Mi`` the inverse mass matrix, ``d`` (n,) the
    damping per joint [N m s/rad], ``hg`` [s]). False if singular."""
    n = d.shape[0]
    for j in range(n):
        s = hg * d[j]
        for i in range(n):
            N[i, j] = Mi[i, j] * s + (1.0 if i == j else 0.0)
    return _lu_factor(N, piv)


@njit(**_JIT)
def error_norm(err, x, xnew, Mi, d, hg, tau, N, piv, col, rtol, atol):
    """The weighted RMS norm of the step's error estimate ``err`` (2n,), filtered in place (module
    docstring): velocities by ``(I + hg Mi diag(d))^-1``, positions plus ``hg`` times that (the norm ``e``);
    when ``tau > hg`` the velocities re-filtered over ``tau`` [s] from the raw estimate (the norm ``e_tau``),
    and the result ``max(e_tau, e / FORGIVE)``. ``d`` (n,): the damping at ``xnew``; ``col`` (n,), ``N``,
    ``piv``: scratch. 1e300 if a matrix is singular."""
    n = d.shape[0]
    for i in range(n):
        col[i] = err[n + i]
    if not factor(Mi, d, hg, N, piv):
        return 1e300
    _lu_solve(N, piv, err[n:2 * n])
    for i in range(n):
        err[i] += hg * err[n + i]
    e = _rms(err, x, xnew, rtol, atol)
    if tau <= hg:
        return e
    if not factor(Mi, d, tau, N, piv):
        return 1e300
    _lu_solve(N, piv, col)
    for i in range(n):
        err[n + i] = col[i]
    return max(_rms(err, x, xnew, rtol, atol), e / FORGIVE)


@njit(**_JIT)
def _rms(err, x, xnew, rtol, atol):
    e = 0.0
    for i in range(err.shape[0]):
        s = err[i] / (atol + rtol * max(abs(x[i]), abs(xnew[i])))
        e += s * s
    return math.sqrt(e / err.shape[0])


@njit(**_JIT)
def slope_ratio(d0, d1):
    """Largest ``max(d0_j, d1_j) / min(d0_j, d1_j)`` over the joints with damping (1 if none): how far a
    step moved a joint along its friction's knee (``d0``, ``d1`` (n,): the damping at the step's ends)."""
    r = 1.0
    for j in range(d0.shape[0]):
        lo, hi = min(d0[j], d1[j]), max(d0[j], d1[j])
        if hi > 0.0:
            r = max(r, hi / lo) if lo > 0.0 else 1e300
    return r
