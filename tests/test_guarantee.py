"""rc3r.controllers.guarantee: the robust laws' ultimate bound, against hand-computed values and
(for the inertia range) Pinocchio's CRBA.

The numbers are chosen so the arithmetic is exact in binary floating point (powers of two,
quarters): equality to 1e-15 relative; a wrong formula (rho eps / 2, max K for min K, no
m_max / m_min factor) is off by a factor of 2 or more.
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from rc3r.controllers import Adaptive, FeedbackLinearization, Robust, RobustPerCoefficient
from rc3r.controllers.guarantee import covers, error_bound, inertia_range, lyapunov_margin

REL = 1e-15


def test_margin_eq6_is_rho_eps_over_4():
    """rho = 4, eps = 0.5 -> mu = 4 * 0.5 / 4 = 0.5."""
    assert lyapunov_margin(Robust(np.zeros(3), rho=4.0, eps=0.5)) == pytest.approx(0.5, rel=REL)


def test_margin_eq7_is_sum_rho_i_eps_i_over_4():
    """rho_i = (1, 2, 3), eps_i = (0.5, 0.25, 0.125) -> (0.5 + 0.5 + 0.375) / 4 = 0.34375."""
    law = RobustPerCoefficient(np.zeros(3), rho_i=[1.0, 2.0, 3.0], eps_i=[0.5, 0.25, 0.125])
    assert lyapunov_margin(law) == pytest.approx(0.34375, rel=REL)


@pytest.mark.parametrize("law", [FeedbackLinearization(np.zeros(3)), Adaptive(np.zeros(3))], ids=["fbl", "adaptive"])
def test_laws_without_a_robust_term_have_no_margin_and_no_ball(law):
    with pytest.raises(ValueError, match="no robust bound"):
        lyapunov_margin(law)
    with pytest.raises(ValueError, match="no robust bound"):
        covers(law, np.zeros(3))


def test_covers_eq6_is_the_closed_ball_of_radius_rho():
    """theta_0 = (1, 1), rho = 5: (4, 5) is at distance |(3, 4)| = 5 (on the sphere: inside),
    (4, 5.001) outside."""
    law = Robust([1.0, 1.0], rho=5.0, eps=0.5)
    assert covers(law, [4.0, 5.0]) and covers(law, [1.0, 1.0])
    assert not covers(law, [4.0, 5.001]) and not covers(law, [-4.0, 1.0 - 1e-3])


def test_covers_eq7_is_the_box_of_half_widths_rho_i():
    """theta_0 = 0, rho_i = (1, 2): (1, -2) is a corner (inside); (1.001, 0) and (0, -2.001) are out.
    The box is not the ball: (1, 2) has norm 2.24 > max rho_i and is still inside."""
    law = RobustPerCoefficient(np.zeros(2), rho_i=[1.0, 2.0], eps_i=0.1)
    assert covers(law, [1.0, -2.0]) and covers(law, [1.0, 2.0])
    assert not covers(law, [1.001, 0.0]) and not covers(law, [0.0, -2.001])


def test_error_bound_by_hand():
    """mu = 4 * 0.5 / 4 = 0.5; min K = 2 (K = (8, 2, 8)); m_max / m_min = 8 / 2 = 4:
    r_bar = sqrt(4 * 0.5 / 2) = 1; |e_j| <= 1 / Lambda_j = (1, 0.5, 0.25) for Lambda = (1, 2, 4)."""
    law = Robust(np.zeros(15), rho=4.0, eps=0.5, K=[8.0, 2.0, 8.0], Lambda=[1.0, 2.0, 4.0])
    np.testing.assert_allclose(error_bound(law, 2.0, 8.0, 3), [1.0, 0.5, 0.25], rtol=REL)


def test_error_bound_scalar_lambda_broadcasts_and_scales_as_sqrt_eps():
    """Quartering eps halves the bound (r_bar ~ sqrt(mu), mu ~ eps)."""
    a = error_bound(Robust(np.zeros(15), rho=4.0, eps=0.5, K=2.0, Lambda=4.0), 1.0, 1.0, 3)
    b = error_bound(Robust(np.zeros(15), rho=4.0, eps=0.125, K=2.0, Lambda=4.0), 1.0, 1.0, 3)
    np.testing.assert_allclose(a, [0.125] * 3, rtol=REL)  # sqrt(1 * 0.5 / 2) / 4 = 0.5 / 4
    np.testing.assert_allclose(b, a / 2, rtol=REL)


@pytest.mark.parametrize("m_min, m_max", [(0.0, 1.0), (-1.0, 1.0), (2.0, 1.0), (1.0, np.inf)])
def test_error_bound_refuses_an_impossible_inertia_range(m_min, m_max):
    with pytest.raises(ValueError, match="m_min <= m_max"):
        error_bound(Robust(np.zeros(15), rho=1.0, eps=0.5), m_min, m_max, 3)


def test_inertia_range_equals_the_eigenvalues_of_pinocchio_crba(arm, pdata, rng):
    """min / max eigenvalue of M(q) over 20 configurations == those of pinocchio.crba (1e-9 relative:
    3x3 symmetric eigenproblems of entries ~1..10 kg m^2)."""
    import rc3r

    Q = rng.uniform(-np.pi, np.pi, (20, 3))
    ev = []
    for q in Q:
        M = np.array(pin.crba(arm.model, pdata, q), copy=True)
        ev.append(np.linalg.eigvalsh(np.triu(M) + np.triu(M, 1).T))
    ev = np.array(ev)
    lo, hi = inertia_range(rc3r.load_robot(), Q)
    assert lo == pytest.approx(ev[:, 0].min(), rel=1e-9) and hi == pytest.approx(ev[:, -1].max(), rel=1e-9)
    assert 0 < lo < hi


def test_inertia_range_of_a_light_robot_below_one():
    """Eigenvalues all below 1 kg m^2 (M = diag(0.2, 0.5) at q = 0, diag(0.1, 0.3) elsewhere):
    the range is (0.1, 0.5), not clipped at an initial value."""
    class Light:
        @staticmethod
        def mass_matrix(q):
            return np.diag([0.2, 0.5]) if not np.any(q) else np.diag([0.1, 0.3])

    assert inertia_range(Light(), np.array([[0.0, 0.0], [1.0, 0.0]])) == (0.1, 0.5)
