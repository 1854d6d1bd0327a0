"""rc3r._trig: sincos against libm, and the 3R's SIMD-blocked tau against Pinocchio.

Tolerances: fdlibm's kernels err by less than one ulp on |y| <= pi/4 and the three-part
reduction adds about ulp(y), so each value is within 2 ulp of max(1, |value|) of libm's
(libm itself is within 1 ulp of the truth); a wrong coefficient of the polynomials (the
smallest, S6 ~ 1.6e-10 times y^13 at y = pi/4, ~7e-12) or of pi/2 is off by far more.
"""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from rc3r._trig import FAST_LIMIT, sincos, sincos_fast
from rc3r.robots.rr3 import kernels as K

ULP1 = np.spacing(1.0)


@njit(cache=False)
def _both(X, S, C, fast):
    for i in range(X.shape[0]):
        if fast:
            S[i], C[i] = sincos_fast(X[i])
        else:
            S[i], C[i] = sincos(X[i])


def _run(X, fast=False):
    S = np.empty_like(X); C = np.empty_like(X)
    _both(X, S, C, fast)
    return S, C


def _ulps(got, ref):
    return np.abs(got - ref) / np.spacing(np.maximum(1.0, np.abs(ref)))


def _angles(rng):
    k = np.arange(-4000, 4001)
    return np.concatenate([
        rng.uniform(-10.0, 10.0, 200_000),                      # joint angles
        rng.uniform(-FAST_LIMIT, FAST_LIMIT, 50_000),            # the whole reduced range
        k * (np.pi / 2), np.nextafter(k * (np.pi / 2), np.inf),  # the quadrant boundaries, where y ~ 0
        k * (np.pi / 4) + 1e-9, (k + 0.5) * (np.pi / 2),         # |y| ~ pi/4, the polynomials' edge
        [0.0, -0.0, 5e-324, -1e-300, FAST_LIMIT * (1 - 1e-16)]])


@pytest.mark.parametrize("fast", [False, True], ids=["sincos", "sincos_fast"])
def test_sin_and_cos_within_two_ulp_of_libm(rng, fast):
    """sincos(x) == (sin x, cos x) of libm within 2 ulp of max(1, |value|), |x| < FAST_LIMIT."""
    X = _angles(rng)
    S, C = _run(X, fast)
    assert _ulps(S, np.sin(X)).max() <= 2.0
    assert _ulps(C, np.cos(X)).max() <= 2.0


def test_sine_relative_error_near_its_zeros(rng):
    """Near the zeros of sin (x ~ k pi, k < 2^10) the reduction keeps relative accuracy: 4 eps where |sin x| > 1e-12."""
    k = rng.integers(-1000, 1000, 5000)
    X = k * np.pi + rng.uniform(-1e-3, 1e-3, k.size)
    S, _ = _run(X)
    ref = np.sin(X)
    keep = np.abs(ref) > 1e-12
    assert (np.abs(S - ref)[keep] / np.abs(ref[keep])).max() <= 4 * ULP1


@pytest.mark.parametrize("x", [FAST_LIMIT, -FAST_LIMIT, 1e6, -3.7e12, 1e300, np.inf, -np.inf, np.nan])
def test_outside_the_reduced_range_is_libm(x):
    """|x| >= FAST_LIMIT, infinities and NaN: sincos(x) is libm's (sin x, cos x) exactly (NaN for inf, NaN)."""
    S, C = _run(np.array([x]))
    with np.errstate(invalid="ignore"):
        np.testing.assert_array_equal(S, np.sin([x]))
        np.testing.assert_array_equal(C, np.cos([x]))


@settings(max_examples=200, deadline=None, derandomize=True, database=None)
@given(st.floats(-FAST_LIMIT, FAST_LIMIT, allow_nan=False, exclude_max=True, exclude_min=True))
def test_pythagoras_and_odd_even_symmetry(x):
    """sin^2 x + cos^2 x == 1 (4 ulp), sin(-x) == -sin x and cos(-x) == cos x exactly (the reduction is odd)."""
    S, C = _run(np.array([x, -x]))
    assert abs(S[0] ** 2 + C[0] ** 2 - 1.0) <= 4 * ULP1
    assert S[1] == -S[0] and C[1] == C[0]


def test_blocked_tau_equals_rnea_on_both_paths(arm, rng):
    """inverse_dynamics_batch == pin.rnea (TOL 1e-9 relative) on 2 BLOCK + 5 states, one block with an angle
    beyond FAST_LIMIT (per-state libm path) and one with a NaN angle (its state NaN, every other state exact)."""
    from rc3r.robots.rr3.params import theta

    th = theta(arm.params)
    N = 2 * K.BLOCK + 5
    Q = rng.uniform(-np.pi, np.pi, (N, 3)); QD = rng.uniform(-5, 5, (N, 3)); QDD = rng.uniform(-5, 5, (N, 3))
    Q[3, 1] = 2.0 * FAST_LIMIT + 0.3           # block 0: the per-state path
    Q[K.BLOCK + 7, 2] = np.nan                  # block 1: NaN
    out = np.empty((N, 3))
    K.inverse_dynamics_batch(th, Q, QD, QDD, arm.params.lengths[1], arm.params.g0, out)
    data = arm.model.createData()
    ref = np.array([pin.rnea(arm.model, data, q, qd, qdd) for q, qd, qdd in zip(Q, QD, QDD)])
    bad = K.BLOCK + 7
    assert np.isnan(out[bad]).any()
    keep = np.arange(N) != bad
    err = np.abs(out[keep] - ref[keep]).max()
    assert err <= 1e-9 * max(1.0, np.abs(ref[keep]).max()), err
