r"""Rosenbrock tableaux of the compiled engine's continuous and stiff-period steps (plain constants; the
compiled integrators of :mod:`.compiled` read them as compile-time arrays, which numba freezes into the
cached machine code: this file mentions numba so that it counts in :func:`rc3r._numba_cache.package_hash`,
the cache key, and an edited table is recompiled, not served stale).

Each table is the transformed form of Hairer & Wanner, *Solving Ordinary Differential Equations II*
(2nd ed., Springer 1996), sec. IV.7, as KPP's Rosenbrock integrators tabulate it:

.. math:: G k_i = f\Bigl(t + \alpha_i h,\; x + \sum_{j<i} a_{ij} k_j\Bigr) + \sum_{j<i} \frac{c_{ij}}{h} k_j
          + h \gamma_i f_t, \qquad G = \frac{I}{h \gamma_1} - J,

``x_new = x + sum_i m_i k_i``, error estimate ``sum_i e_i k_i``.
"""
from __future__ import annotations

import numpy as np

__all__ = ["ROS4", "RODAS"]

# Layout: row i < s holds alpha_i, gamma_i, new_i (0: the stage reuses the f before it, F0 for stage 1),
# a_i1..a_is, c_i1..c_is; row s holds m, row s + 1 holds e (zero-padded).
#
# ROS4: Hairer & Wanner's L-stable order-4 method in 4 stages (stage 4 reuses stage 3's f); its embedded
# order-3 solution is not L-stable (0.55 at z = -1e6: tests/test_engines.py).
ROS4 = np.array([
    [0.0, 0.5728200000000000, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.145640000000000, -1.769193891319233, 1.0, 2.0, 0.0, 0.0, 0.0, -7.137615036412310, 0.0, 0.0, 0.0],
    [0.6552168638155900, 0.7592633437920482, 1.0, 1.867943637803922, 0.2344449711399156, 0.0, 0.0,
     2.580708087951457, 0.6515950076447975, 0.0, 0.0],
    [0.6552168638155900, -0.1049021087100450, 0.0, 0.0, 0.0, 0.0, 0.0,
     -2.137148994382534, -0.3214669691237626, -0.6949742501781779, 0.0],
    [2.255570073418735, 0.2870493262186792, 0.4353179431840180, 1.093502252409163] + [0.0] * 7,
    [-0.2815431932141155, -0.07276199124938920, -0.1082196201495311, -1.093502252409163] + [0.0] * 7])

# RODAS: Hairer & Wanner's rodas.f (METH = 1), order 4 in 6 stages with an order-3 estimate; stiffly accurate
# (x_new is stage 6's argument plus k_6, the estimate is k_6), so both stability functions vanish at -inf.
_A5 = [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950]
RODAS = np.array([
    [0.0, 0.25, 0.0] + [0.0] * 12,
    [0.386, -0.1043, 1.0, 1.544] + [0.0] * 5 + [-5.6688] + [0.0] * 5,
    [0.21, 0.1035, 1.0, 0.9466785280815826, 0.2557011698983284] + [0.0] * 4
    + [-2.430093356833875, -0.2063599157091915] + [0.0] * 4,
    [0.63, -0.3620000000000023e-01, 1.0, 3.314825187068521, 2.896124015972201, 0.9986419139977817] + [0.0] * 3
    + [-0.1073529058151375, -9.594562251023355, -20.47028614809616] + [0.0] * 3,
    [1.0, 0.0, 1.0] + _A5 + [0.0] * 2 + [7.496443313967647, -10.24680431464352, -33.99990352819905,
                                         11.70890893206160, 0.0, 0.0],
    [1.0, 0.0, 1.0] + _A5 + [1.0, 0.0] + [8.083246795921522, -7.981132988064893, -31.52159432874371,
                                          16.31930543123136, -6.058818238834054, 0.0],
    _A5 + [1.0, 1.0] + [0.0] * 9,
    [0.0] * 5 + [1.0] + [0.0] * 9])
