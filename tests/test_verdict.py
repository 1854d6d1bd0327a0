"""Verdicts: chattering, saturation and the tracking tolerance against hand-made torque series, and
the done-when of the plant-seam issue on the paper's arm (eps 0.5 at 20 kHz chatters; in continuous
time it is clean)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import rc3r
from rc3r.simulate import verdict as V


def _res(u, rate=1000.0, outcome="finished", e=None):
    """A stand-in SimResult: stored torque u (N, n) at `rate`, total variation over every sample."""
    u = np.asarray(u, dtype=float)
    t = np.arange(u.shape[0]) / rate
    q = np.zeros_like(u) if e is None else np.asarray(e, dtype=float)
    return SimpleNamespace(u=u, t=t, t_end=float(t[-1]), mode="sampled", outcome=outcome,
                           tv_exact=np.abs(np.diff(u, axis=0)).sum(axis=0), e=q)


def test_alternating_torque_chatters_and_a_sine_does_not():
    """u = 300 (-1)^k on joint 1 (TV = 600 per sample, 2 s: 1.2e6 N m against a bar of
    10 x max(smooth TV = 0 (a moving average of 10 samples cancels the alternation), 2 s x 300 N m)
    = 6000) chatters; a 1 rad/s sine of 300 N m (TV ~ 0.64 x 300 x 2 = 382 < 6000) does not. A
    period-3 switch (+300, +300, -600) chatters too."""
    k = np.arange(2001)
    u = np.stack([300.0 * (-1.0) ** k, 300.0 * np.sin(k / 1000.0)], axis=1)
    assert V.chattering(_res(u)) == [True, False]
    p3 = np.tile([300.0, 300.0, -600.0], 700)[:, None]
    assert V.chattering(_res(p3)) == [True]
    out = V.verdict(_res(u))
    assert out["verdict"] == "chattering" and out["chattering_joints"] == [1]


def test_saturation_fraction_by_hand():
    """10 of 100 samples at the limit on some joint: fraction 0.1 > 0.05 -> saturated (when clean otherwise)."""
    u = np.full((100, 2), 5.0)
    u[:10, 1] = -20.0
    res = _res(np.sin(np.arange(100)[:, None] / 50.0) * 0 + u)
    assert V.saturation_fraction(res, [10.0, 20.0]) == pytest.approx(0.1)
    assert V.verdict(res, saturation=[10.0, 20.0])["verdict"] == "saturated"
    assert V.verdict(res, saturation=[10.0, 200.0])["verdict"] == "clean"


def test_order_and_tolerance():
    """diverged beats everything; limit-violated beats saturated; tolerance_met reads max|e|."""
    u = np.full((10, 1), 1.0)
    e = np.full((10, 1), 0.02)
    assert V.verdict(_res(u, outcome="diverged"), saturation=[1.0])["verdict"] == "diverged"
    out = V.verdict(_res(u, e=e), saturation=[1.0], limits={"violated": True})
    assert out["verdict"] == "limit-violated" and out["tolerance_met"] is False
    assert V.verdict(_res(u, e=e), tolerance=0.05)["tolerance_met"] is True


@pytest.mark.parametrize("rate, expect", [(None, "clean"), (20000.0, "chattering")])
def test_paper_robust_law_verdicts(rate, expect):
    """The paper's robust law (eps 0.5, perturbed): continuous time is clean; sampled at 20 kHz
    (rate x eps = 10 kHz, below the measured 40-50 kHz boundary) it chatters without diverging (from
    about 1.2 s on: the first second is clean, measured)."""
    spec = rc3r.build_run(controller="robust", perturbed=True, duration=2.0, rate=rate, eps=0.5)  # given: no rule
    res, m = rc3r.execute(spec)
    assert res.ok and m["verdict"] == expect
    assert m["tolerance_met"] is True  # max|e| < 1e-3 rad either way: chattering is a torque problem


def test_continuous_runs_never_chatter_and_rows_matter():
    """Chattering is a sampled-data verdict: a continuous run with the same torque is clean; a run with
    one stored row, or fewer rows than the smoothing window (10), has no chattering to judge (its
    'smooth' torque is itself); 11 rows of alternation are enough."""
    k = np.arange(2001)
    u = (300.0 * (-1.0) ** k)[:, None]
    res = _res(u)
    res.mode = "continuous"
    assert V.chattering(res) == [False]
    assert V.chattering(_res(u[:1])) == [False]
    assert V.chattering(_res(u[:9])) == [False]
    assert V.chattering(_res(u[:11])) == [True]
