"""Each control law against an independent NumPy evaluation of its formula, one hand value,
and the refusal of bad gains."""
from __future__ import annotations

import numpy as np
import pytest

from rc3r.controllers import Adaptive, FeedbackLinearization, PDGravity, Robust, RobustPerCoefficient
from rc3r.errors import ParameterError
from rc3r.model import coriolis_matrix, gravity, mass_matrix
from rc3r.params import theta
from rc3r.regressor import slotine_li_regressor

# Tolerance: the compiled kernel and the NumPy path do the same O(100) float operations in a
# different order on magnitudes up to ~1e3 N m -> agreement to ~1e-12 relative; 1e-9 absolute is safe.
ATOL = 1e-9


@pytest.fixture
def state(rng):
    q, qd, qr, qdr, qddr = (rng.uniform(-2, 2, 3) for _ in range(5))
    return q, qd, qr, qdr, qddr


def _slotine(q, qd, qr, qdr, qddr, lam, l2):
    e, ed = q - qr, qd - qdr
    v, a, r = qdr - lam * e, qddr - lam * ed, ed + lam * e
    return slotine_li_regressor(q, qd, v, a, l2=l2), r


def test_fbl_is_computed_torque(table1, state):
    """u = M(q)(qdd_d + Kd (qd_d - qd) + Kp (q_d - q)) + S(q, qd) qd + g(q)."""
    th, l2 = theta(table1), table1.lengths[1]
    q, qd, qr, qdr, qddr = state
    c = FeedbackLinearization(th, Kp=[100, 80, 60], Kd=[10, 20, 30])
    ar = qddr + c.Kd * (qdr - qd) + c.Kp * (qr - q)
    expected = mass_matrix(th, q) @ ar + coriolis_matrix(th, q, qd) @ qd + gravity(th, q, l2=l2)
    np.testing.assert_allclose(c.torque(q, qd, qr, qdr, qddr, l2=l2), expected, rtol=0, atol=ATOL)


@pytest.mark.parametrize("eps", [1e-6, 0.5, 1e6], ids=["outside-layer", "paper-eps", "inside-layer"])
def test_robust_eq6(table1, state, eps):
    """u = Y (theta0 + delta) - K r, delta = -rho Y^T r / max(||Y^T r||, eps) (eq. 3-6), both branches."""
    th, l2 = theta(table1), table1.lengths[1]
    q, qd, qr, qdr, qddr = state
    c = Robust(th * 1.1, K=[100, 90, 80], Lambda=[50, 40, 30], rho=186.8129, eps=eps)
    Y, r = _slotine(q, qd, qr, qdr, qddr, c.Lambda, l2)
    xi = Y.T @ r
    delta = -c.rho * xi / max(np.linalg.norm(xi), eps)
    expected = Y @ (c.theta + delta) - c.K * r
    np.testing.assert_allclose(c.torque(q, qd, qr, qdr, qddr, l2=l2), expected, rtol=0, atol=ATOL * 1e3)


def test_robust_eq7_per_coefficient(table1, state, rng):
    """delta_i = -rho_i xi_i / max(|xi_i|, eps_i) (eq. 7)."""
    th, l2 = theta(table1), table1.lengths[1]
    q, qd, qr, qdr, qddr = state
    rho_i, eps_i = rng.uniform(0, 50, 15), rng.uniform(0.01, 5, 15)
    c = RobustPerCoefficient(th, rho_i=rho_i, eps_i=eps_i)
    Y, r = _slotine(q, qd, qr, qdr, qddr, c.Lambda, l2)
    xi = Y.T @ r
    expected = Y @ (th - rho_i * xi / np.maximum(np.abs(xi), eps_i)) - c.K * r
    np.testing.assert_allclose(c.torque(q, qd, qr, qdr, qddr, l2=l2), expected, rtol=0, atol=ATOL * 1e3)


def test_adaptive_uses_estimate(table1, state, rng):
    """u = Y theta_hat - K r with the controller state theta_hat, not the initial theta."""
    th, l2 = theta(table1), table1.lengths[1]
    q, qd, qr, qdr, qddr = state
    c = Adaptive(th, Gamma=np.full(15, 3.0))
    z = th + rng.normal(size=15)
    Y, r = _slotine(q, qd, qr, qdr, qddr, c.Lambda, l2)
    np.testing.assert_allclose(c.torque(q, qd, qr, qdr, qddr, z, l2=l2), Y @ z - c.K * r, rtol=0, atol=ATOL)
    np.testing.assert_array_equal(c.initial_state(), th)


def test_pd_gravity_hand_value(table1):
    """At q = 0 on the reference: u = g(0) = (0, g0 (theta14 + theta7/l2), g0 theta7/l2)
    = (0, 9.81 * (15 + 12), 9.81 * 12) = (0, 264.87, 117.72) N m for Table 1 (by hand)."""
    c = PDGravity(theta(table1))
    u = c.torque(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), l2=1.0)
    np.testing.assert_allclose(u, [0.0, 264.87, 117.72], rtol=0, atol=1e-12)


def test_robust_on_reference_with_exact_model_is_inverse_dynamics(table1):
    """On the reference (r = 0) the robust term vanishes: u = Y(q, qd, qd, qdd) theta0 (hand identity)."""
    th, l2 = theta(table1), table1.lengths[1]
    q, qd, qdd = np.array([0.3, -0.2, 0.5]), np.array([1.0, 0.0, 1.0]), np.array([0.0, -5.0, 0.0])
    u = Robust(th).torque(q, qd, q, qd, qdd, l2=l2)
    expected = mass_matrix(th, q) @ qdd + coriolis_matrix(th, q, qd) @ qd + gravity(th, q, l2=l2)
    np.testing.assert_allclose(u, expected, rtol=0, atol=ATOL)


@pytest.mark.parametrize("make", [
    lambda th: Robust(th, eps=0.0),
    lambda th: Robust(th, eps=-1.0),
    lambda th: Robust(th, K=[100, 0, 100]),
    lambda th: Robust(th, Lambda=[-1, 1, 1]),
    lambda th: Robust(th, rho=-1.0),
    lambda th: Robust(th, eps=float("nan")),
    lambda th: FeedbackLinearization(th, Kp=0),
    lambda th: Adaptive(th, Gamma=np.zeros(15)),
    lambda th: RobustPerCoefficient(th, eps_i=np.zeros(15)),
    lambda th: FeedbackLinearization(np.full(15, np.inf)),
], ids=["eps0", "eps<0", "K0", "Lambda<0", "rho<0", "eps-nan", "Kp0", "Gamma0", "eps_i0", "theta-inf"])
def test_bad_gains_refused(table1, make):
    """Non-positive gains, eps <= 0, NaN/inf are refused with ParameterError."""
    with pytest.raises(ParameterError):
        make(theta(table1))
