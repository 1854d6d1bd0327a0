#!/usr/bin/env python
"""Proposed faster closed-form kernels, measured against the current ones (not library code).

``rc3r bench`` measures tau = Y(q, qd, qdd) theta at ~100 ns per state with
``_kernels.inverse_dynamics_batch``, which fills the 3x15 Slotine-Li regressor
(45 stores after zeroing) and multiplies it by theta, from row views ``Q[n]``
(each view costs a few ns in numba) and with six libm calls per state.
The kernel below computes ``M(q) qdd + S(q, qd) qd + g(q)`` directly from the same
formulas as ``_kernels.mass_matrix_into``/``coriolis_into``/``gravity_into``:
four libm calls (``sin(q2 + q3)``, ``cos(q2 + q3)`` by the addition theorem),
scalar arguments (no views), no Y. It is checked here against ``pinocchio.rnea``
on the same states and timed side by side with the current kernel.

The same two changes (scalar arguments, four libm calls, and every entry of Y
written exactly once instead of zeroing all 45 first) applied to the Slotine-Li
regressor are ``slotine_li_scalars`` below, timed against
``_kernels.slotine_li_batch`` and the compiled loop of ``rc3r bench``.

Usage: ``python benchmarks/proposal_kernels.py [-n N] [--repeats R]``
"""
from __future__ import annotations

import argparse
import math
import sys

import numpy as np
from numba import njit


@njit(cache=False, nogil=True, inline="always")
def tau_scalars(th, q2, q3, qd1, qd2, qd3, a1, a2, a3, l2, g0, out, n):
    """out[n] = M(q) a + S(q, qd) qd + g(q) for one state given as scalars (q1 does not enter)."""
    s2 = math.sin(q2); c2 = math.cos(q2)
    s3 = math.sin(q3); c3 = math.cos(q3)
    s23 = s2 * c3 + c2 * s3; c23 = c2 * c3 - s2 * s3
    m13 = th[9] * c23 + th[10] * s23
    m11 = (th[0] + th[1] * s2 * s2 + th[2] * s2 * c2 + th[3] * s23 * s23 + th[4] * s23 * c23
           + 2.0 * th[5] * c2 * s23 + 2.0 * th[6] * c2 * c23)
    m12 = th[7] * c2 + th[8] * s2 + m13
    m22 = th[11] + 2.0 * th[5] * s3 + 2.0 * th[6] * c3
    m23 = th[12] + th[5] * s3 + th[6] * c3
    # B = (1/2) dm11/dq3, A = (1/2) dm11/dq2 (= B + the q2-only terms), E = dm13/dq3, D = dm12/dq2, F = dm23/dq3
    B = (th[3] * c23 * s23 + 0.5 * th[4] * (c23 * c23 - s23 * s23) + th[5] * c2 * c23 - th[6] * c2 * s23)
    A = th[1] * c2 * s2 + 0.5 * th[2] * (c2 * c2 - s2 * s2) + B - th[5] * s2 * s23 - th[6] * s2 * c23
    E = -th[9] * s23 + th[10] * c23
    D = -th[7] * s2 + th[8] * c2 + E
    F = th[5] * c3 - th[6] * s3
    # S qd with S of _kernels.coriolis_into, expanded
    c1 = (2.0 * qd2 * A + 2.0 * qd3 * B) * qd1 + (D * qd2 + 2.0 * E * qd3) * qd2 + E * qd3 * qd3
    cc2 = -A * qd1 * qd1 + F * qd3 * (2.0 * qd2 + qd3)
    cc3 = -B * qd1 * qd1 - F * qd2 * qd2
    g3 = g0 * (th[6] * c23 + th[5] * s23) / l2
    g2 = g0 * (th[13] * c2 + th[14] * s2) + g3
    out[n, 0] = m11 * a1 + m12 * a2 + m13 * a3 + c1
    out[n, 1] = m12 * a1 + m22 * a2 + m23 * a3 + cc2 + g2
    out[n, 2] = m13 * a1 + m23 * a2 + th[12] * a3 + cc3 + g3


@njit(cache=False, nogil=True)
def inverse_dynamics_batch_fused(th, Q, QD, QDD, l2, g0, out):
    for n in range(Q.shape[0]):
        tau_scalars(th, Q[n, 1], Q[n, 2], QD[n, 0], QD[n, 1], QD[n, 2], QDD[n, 0], QDD[n, 1], QDD[n, 2],
                    l2, g0, out, n)


@njit(cache=False, nogil=True, inline="always")
def slotine_li_scalars(q2, q3, qd1, qd2, qd3, v1, v2, v3, a1, a2, a3, l2, g0, Y):
    """_kernels.slotine_li_into with scalar arguments, four libm calls, each entry written once."""
    s2 = math.sin(q2); c2 = math.cos(q2); s3 = math.sin(q3); c3 = math.cos(q3)
    s23 = s2 * c3 + c2 * s3; c23 = c2 * c3 - s2 * s3
    P12 = v1 * qd2 + qd1 * v2; P13 = v1 * qd3 + qd1 * v3; W = qd3 * v2 + (qd2 + qd3) * v3
    w11 = qd1 * v1; w22 = qd2 * v2
    cs2 = c2 * s2; d2 = 0.5 * (c2 * c2 - s2 * s2); cs23 = c23 * s23; d23 = 0.5 * (c23 * c23 - s23 * s23)
    k6 = c2 * c23 - s2 * s23; k7 = s2 * c23 + c2 * s23; gl = g0 / l2; a23 = a2 + a3
    Y[0, 0] = a1
    Y[0, 1] = a1 * s2 * s2 + P12 * cs2
    Y[0, 2] = a1 * cs2 + P12 * d2
    Y[0, 3] = a1 * s23 * s23 + (P12 + P13) * cs23
    Y[0, 4] = a1 * cs23 + (P12 + P13) * d23
    Y[0, 5] = 2.0 * a1 * c2 * s23 + P12 * k6 + P13 * c2 * c23
    Y[0, 6] = 2.0 * a1 * c2 * c23 - P12 * k7 - P13 * c2 * s23
    Y[0, 7] = a2 * c2 - w22 * s2
    Y[0, 8] = a2 * s2 + w22 * c2
    Y[0, 9] = a23 * c23 - (w22 + W) * s23
    Y[0, 10] = a23 * s23 + (w22 + W) * c23
    Y[0, 11] = 0.0; Y[0, 12] = 0.0; Y[0, 13] = 0.0; Y[0, 14] = 0.0
    Y[1, 0] = 0.0
    Y[1, 1] = -w11 * cs2
    Y[1, 2] = -w11 * d2
    Y[1, 3] = -w11 * cs23
    Y[1, 4] = -w11 * d23
    Y[1, 5] = (2.0 * a2 + a3) * s3 - w11 * k6 + W * c3 + gl * s23
    Y[1, 6] = (2.0 * a2 + a3) * c3 + w11 * k7 - W * s3 + gl * c23
    Y[1, 7] = a1 * c2; Y[1, 8] = a1 * s2; Y[1, 9] = a1 * c23; Y[1, 10] = a1 * s23
    Y[1, 11] = a2; Y[1, 12] = a3; Y[1, 13] = g0 * c2; Y[1, 14] = g0 * s2
    Y[2, 0] = 0.0; Y[2, 1] = 0.0; Y[2, 2] = 0.0
    Y[2, 3] = -w11 * cs23
    Y[2, 4] = -w11 * d23
    Y[2, 5] = a2 * s3 - w11 * c2 * c23 - w22 * c3 + gl * s23
    Y[2, 6] = a2 * c3 + w11 * c2 * s23 + w22 * s3 + gl * c23
    Y[2, 7] = 0.0; Y[2, 8] = 0.0
    Y[2, 9] = a1 * c23; Y[2, 10] = a1 * s23
    Y[2, 11] = 0.0; Y[2, 12] = a23; Y[2, 13] = 0.0; Y[2, 14] = 0.0

@njit(cache=False, nogil=True)
def slotine_li_in_loop_scalar(th, Q, QD, V, A, l2, g0, out):
    Y = np.empty((3, 15))
    for n in range(Q.shape[0]):
        slotine_li_scalars(Q[n,1], Q[n,2], QD[n,0], QD[n,1], QD[n,2], V[n,0], V[n,1], V[n,2], A[n,0], A[n,1], A[n,2], l2, g0, Y)
        for i in range(3):
            acc = 0.0
            for j in range(15):
                acc += Y[i, j] * th[j]
            out[n, i] = acc
@njit(cache=False, nogil=True)
def slotine_li_batch_scalar(Q, QD, V, A, l2, g0, out):
    for n in range(Q.shape[0]):
        slotine_li_scalars(Q[n,1], Q[n,2], QD[n,0], QD[n,1], QD[n,2], V[n,0], V[n,1], V[n,2], A[n,0], A[n,1], A[n,2], l2, g0, out[n])


def main(argv=None) -> int:
    import pinocchio as pin

    from rc3r import _kernels as K
    from rc3r import bench
    from rc3r.params import theta
    from rc3r.urdf import load_arm

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=100_000)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    arm = load_arm(None)
    th = theta(arm.params)
    l2, g0 = float(arm.params.lengths[1]), float(arm.params.g0)
    S = bench._states(args.n, np.random.default_rng(bench._SEED))
    Q, QD, QDD = S["Q"], S["QD"], S["QDD"]
    o_cur, o_new = np.empty((args.n, 3)), np.empty((args.n, 3))
    m, d = arm.model, arm.model.createData()
    ref = np.array([pin.rnea(m, d, Q[i], QD[i], QDD[i]) for i in range(args.n)])
    rows = []
    for _ in range(2):  # interleaved twice: the machine's noise shows in the spread
        rows.append(("current _kernels.inverse_dynamics_batch",
                     bench._time(lambda: K.inverse_dynamics_batch(th, Q, QD, QDD, l2, g0, o_cur), args.repeats)))
        rows.append(("proposed fused scalar kernel",
                     bench._time(lambda: inverse_dynamics_batch_fused(th, Q, QD, QDD, l2, g0, o_new),
                                 args.repeats)))
    V, A = S["V"], S["A"]
    y_cur, y_new = np.empty((args.n, 3, 15)), np.empty((args.n, 3, 15))
    s_cur, s_new = np.empty((args.n, 3)), np.empty((args.n, 3))
    for _ in range(2):
        rows.append(("current _kernels.slotine_li_batch",
                     bench._time(lambda: K.slotine_li_batch(Q, QD, V, A, l2, g0, y_cur), args.repeats)))
        rows.append(("proposed slotine_li_batch (scalars)",
                     bench._time(lambda: slotine_li_batch_scalar(Q, QD, V, A, l2, g0, y_new), args.repeats)))
        rows.append(("current Y in compiled loop + Y theta",
                     bench._time(lambda: bench._slotine_li_in_loop(th, Q, QD, V, A, l2, g0, s_cur), args.repeats)))
        rows.append(("proposed Y in compiled loop + Y theta",
                     bench._time(lambda: slotine_li_in_loop_scalar(th, Q, QD, V, A, l2, g0, s_new), args.repeats)))
    for name, (med, mn) in rows:
        print(f"{name:42s} {med / args.n * 1e9:7.1f} ns/state (min {mn / args.n * 1e9:.1f})")
    e_cur, e_new = np.abs(o_cur - ref).max(), np.abs(o_new - ref).max()
    print(f"max |tau - pin.rnea| over {args.n} states: current {e_cur:.2e}, proposed {e_new:.2e} "
          f"(max |tau| {np.abs(ref).max():.3g})")
    e_y = np.abs(y_cur - y_new).max()
    print(f"max |Y_proposed - Y_current| = {e_y:.2e}, max |Y theta| difference = {np.abs(s_cur - s_new).max():.2e}")
    ok = e_new <= 1e-9 * max(1.0, np.abs(ref).max()) and e_y <= 1e-9 * max(1.0, np.abs(y_cur).max())
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
