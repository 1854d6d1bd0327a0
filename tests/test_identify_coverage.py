"""Coverage of the reported confidence ellipsoid, measured over 100 seeded synthetic logs of the 3R.

One motion of the paper's arm (10 s, a random Fourier trajectory; friction 2 N m s/rad and 1 N m on
every joint) is recorded 100 times with new sensor noise and new time stamps (seeds 0-99; torque noise
0.2 N m, offset 0.3 N m, velocity noise 0.01 rad/s, 16-bit encoder, 0.7-9 ms intervals): an experiment
repeated 100 times. Each log is identified at a 2 Hz cut-off with differentiated velocities, per-joint
weights and ``sign`` Coulomb friction (what the spectral rule chose before issue 35: 2-2.4 Hz on these
logs), white covariance, 95 %; the true theta must lie inside its ellipsoid in about 95 % of them.

Why not the cross-validated defaults: they choose 2-5 Hz on these logs, and at 3-5 Hz the filtered
residual holds in-band model misfit (differentiated 16-bit encoder steps) besides the sensor noise, so
the white ``sigma_j`` is 2-5 times the 0.2 N m noise and the ellipsoid is conservative: 100 % coverage,
mean ``d^T Cov^-1 d / p = 0.462`` over the same 100 logs (2026-12-06, commit ec3582b). The calibration this test checks is that
of the covariance model where its assumption (the filtered residual is the noise) holds.
"""
from __future__ import annotations

import numpy as np
import pytest

import rc3r
from rc3r.identify.excitation import random_fourier
from rc3r.identify.pipeline import identify
from rc3r.identify.synthetic import sample_log, simulate_motion

LOGS = 100
CONFIDENCE = 0.95


@pytest.mark.slow
def test_true_theta_is_inside_the_ellipsoid_at_the_stated_confidence():
    """Coverage over 100 logs within [0.88, 0.99]: a calibrated 95 % region gives 95 +- 2.2 % (binomial
    standard deviation), so 0.88 is 3.2 sigma below and 0.99 is 1.8 sigma above (a region twice too large
    in its quadratic form would cover ~100 %); and the mean of the normalized squared distance
    ``d^T Cov^{-1} d / p`` within [0.7, 1.3] (its mean is 1 for a correct covariance; the standard
    deviation of a 100-log mean is 0.04)."""
    arm = rc3r.load_robot("rr3")
    motion = simulate_motion(arm, random_fourier(arm, 10.0, seed=2, fill=0.8), 10.0)
    inside, m2, cutoffs = [], [], []
    for seed in range(LOGS):
        log, truth = sample_log(motion, seed=seed)
        res = identify(arm, log, confidence=CONFIDENCE, consistency=False, cutoff_hz=2.0,
                       velocities="differentiated", weighting="per-joint", coulomb_velocity=0.0, physical=False)
        d = res.theta - truth["theta"]
        m = float(d @ np.linalg.solve(res.cov_theta, d))
        m2.append(m / arm.p)
        inside.append(m <= res.ellipsoid["chi2"])
        cutoffs.append(res.filter["cutoff_hz"])
    coverage = float(np.mean(inside))
    print(f"\ncoverage of the {100 * CONFIDENCE:g} % ellipsoid over {LOGS} logs: {100 * coverage:.1f} % "
          f"(mean d^T Cov^-1 d / p = {np.mean(m2):.3f}; cut-off {min(cutoffs):.3g}-{max(cutoffs):.3g} Hz)")
    assert 0.88 <= coverage <= 0.99
    assert 0.7 <= np.mean(m2) <= 1.3
