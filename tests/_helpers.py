"""Assertions shared by the test modules (tests/ is on sys.path under pytest's default import mode)."""
from __future__ import annotations

import numpy as np

#: Relative tolerance of the model identities: float64 rounding of O(100) products of
#: magnitudes <= O(1e3) gives ~1e-13 relative; 1e-9 leaves four orders of margin and still
#: fails any wrong term (the smallest coefficient, |theta_10| = 0.2, times O(1) trig).
TOL = 1e-9


def assert_close(x, ref, tol=TOL):
    """max|x - ref| <= tol * max(1, max|ref|) (the verify-model relative error)."""
    x, ref = np.asarray(x, float), np.asarray(ref, float)
    assert x.shape == ref.shape
    err = np.max(np.abs(x - ref))
    scale = max(1.0, float(np.max(np.abs(ref))))
    assert err <= tol * scale, f"max abs err {err:.3e} > {tol:.0e} * {scale:.3g}"
