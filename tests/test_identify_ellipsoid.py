"""The robust-ellipsoid law against the ball law (robust, eq. 6) on the same bounds.

* a ball ``P = I / rho^2`` reproduces the robust law's torques (same K, Lambda, eps), inside and outside
  the boundary layer;
* for an ellipsoid inside the ball about the same centre (the ball ``rho = rho_P`` that bounds.toml
  writes), the robust correction is never larger, ``||delta_E|| <= ||delta_B||``, nor its power
  ``|xi^T delta|``, nor its stiffness inside the layer (the largest eigenvalue of the gain on r);
* the Lyapunov claims: the worst case of ``xi^T Delta`` over the ellipsoid is ``s = ||P^{-1/2} xi||``
  (against 20000 sampled boundary points), and ``xi^T (delta - Delta) <= eps rho_P / 4``;
* in closed loop on the 3R whose theta is inside the ellipsoid, the tracking error stays below the
  law's ultimate bound, which is below the ball's.
"""
from __future__ import annotations

import numpy as np
import pytest

import rc3r
from rc3r.controllers import make_law
from rc3r.controllers.ellipsoid import covers, error_bound, lyapunov_margin
from rc3r.errors import ParameterError


@pytest.fixture(scope="module")
def arm():
    return rc3r.load_robot("rr3")


def _ellipsoid(p, seed=0, spread=1e-3, top=4.0):
    """A random ellipsoid: axes from top * spread**u (u uniform), random orientation; returns P."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(p, p)))
    axes = top * spread ** rng.uniform(0, 1, p)
    axes[0] = top
    return Q @ np.diag(1.0 / axes ** 2) @ Q.T


def _states(arm, seed, count=40):
    """Random (q, qd, ref): half with ref close to the state (small r: inside the boundary layer)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(count):
        q, qd = rng.uniform(-2, 2, (2, arm.n))
        scale = 1e-6 if k % 2 else 1.0
        ref = np.vstack([q + scale * rng.normal(size=arm.n), qd + scale * rng.normal(size=arm.n),
                         rng.normal(size=arm.n)])
        out.append((q, qd, ref))
    return out


def _delta(law, arm, q, qd, ref):
    v, a, r, _ = law.signals(q, qd, ref)
    Y = arm.regressor(q, qd, v, a)
    th, _, diag = law.output(Y, r, None)
    return th - law.theta, Y.T @ r, diag


def test_a_ball_reproduces_the_robust_law(arm):
    """P = I / rho^2 with the same gains and eps: u equal to 1e-12 of its size at 40 states, 20 of them
    inside the boundary layer (||xi|| < eps) and 20 outside; the diagnostic is rho ||xi||."""
    th0, rho, eps = np.asarray(arm.theta) + 3.0, 40.0, 0.5
    ball = make_law("robust", th0, rho=rho, eps=eps, K=80.0, Lambda=30.0)
    ell = make_law("robust-ellipsoid", th0, P=np.eye(arm.p) / rho ** 2, eps=eps, K=80.0, Lambda=30.0)
    sides = set()
    for q, qd, ref in _states(arm, 1):
        ub, _, db = ball.torque(arm, q, qd, ref)
        ue, _, de = ell.torque(arm, q, qd, ref)
        assert np.abs(ue - ub).max() <= 1e-12 * max(1.0, np.abs(ub).max())
        assert de == pytest.approx(rho * db, rel=1e-12)
        sides.add(db < eps)
    assert sides == {True, False}


def test_an_ellipsoid_inside_the_ball_gives_a_smaller_robust_term(arm):
    """rho = rho_P: at 40 states the ellipsoid's correction, its power along r, and (inside the layer) its
    stiffness are at most the ball's (to 1e-12); with axes down to 1e-3 of the largest they are much
    smaller on average (mean ||delta_E|| / ||delta_B|| < 0.5)."""
    P = _ellipsoid(arm.p)
    th0, eps = np.asarray(arm.theta), 0.5
    ell = make_law("robust-ellipsoid", th0, P=P, eps=eps)
    ball = make_law("robust", th0, rho=ell.rho_P, eps=eps)
    ratios = []
    Pinv = np.linalg.inv(P)
    for q, qd, ref in _states(arm, 2):
        dE, xi, s = _delta(ell, arm, q, qd, ref)
        dB, _, nx = _delta(ball, arm, q, qd, ref)
        assert np.linalg.norm(dE) <= np.linalg.norm(dB) * (1 + 1e-12)
        assert abs(xi @ dE) <= abs(xi @ dB) * (1 + 1e-12)
        ratios.append(np.linalg.norm(dE) / np.linalg.norm(dB))
        if s < eps * ell.rho_P:  # inside the layer: u = ... - Y G Y^T r with these gains G
            v, a, _, _ = ell.signals(q, qd, ref)
            Y = arm.regressor(q, qd, v, a)
            gE = np.linalg.eigvalsh(Y @ Pinv @ Y.T / (eps * ell.rho_P))[-1]
            gB = np.linalg.eigvalsh(ball.rho * Y @ Y.T / eps)[-1]
            assert gE <= gB * (1 + 1e-12)
    assert np.mean(ratios) < 0.5


def test_worst_case_and_lyapunov_margin(arm):
    """max over the ellipsoid of xi^T Delta is s: 20000 random boundary points never exceed it and
    Delta* = P^{-1} xi / s is on the boundary and attains it; xi^T (delta - Delta) <= eps rho_P / 4 for
    every sampled Delta and for Delta*."""
    P = _ellipsoid(arm.p, seed=3, spread=0.1)
    law = make_law("robust-ellipsoid", np.zeros(arm.p), P=P, eps=0.5)
    mu = lyapunov_margin(law)
    assert mu == pytest.approx(0.5 * law.rho_P / 4)
    rng = np.random.default_rng(4)
    L = np.linalg.cholesky(np.linalg.inv(P))  # Delta = L u, |u| = 1: the boundary
    U = rng.normal(size=(20000, arm.p))
    D = (U / np.linalg.norm(U, axis=1, keepdims=True)) @ L.T
    for scale in (1e-4, 1e-2, 1.0, 10.0):  # inside and outside the layer
        xi = scale * rng.normal(size=arm.p)
        delta, _, s = law.output(np.eye(arm.p), xi, None)
        delta = delta - law.theta
        star = np.linalg.solve(P, xi) / s
        assert star @ P @ star == pytest.approx(1.0, rel=1e-10) and xi @ star == pytest.approx(s, rel=1e-10)
        worst = np.append(D @ xi, xi @ star)
        assert worst.max() <= s * (1 + 1e-10)
        assert np.all(xi @ delta - worst <= mu * (1 + 1e-12))


def test_closed_loop_stays_under_the_ultimate_bound(arm):
    """The plant is the 3R; the law's centre is off by Delta with Delta^T P Delta = 0.64 (inside). 1 s of
    the paper's trajectory in the python engine (continuous time): max|e_j| <= the law's bound, which is
    below the ball's (mu = eps rho_P / 4 against eps rho / 4 with rho = rho_P here, and a smaller ball
    bound still if rho is any ball containing the ellipsoid)."""
    from rc3r.controllers import guarantee

    P = _ellipsoid(arm.p, seed=5, spread=1e-2, top=2.0)
    Delta = np.linalg.cholesky(np.linalg.inv(P)) @ np.full(arm.p, 0.8 / np.sqrt(arm.p))
    th0 = np.asarray(arm.theta) - Delta
    law = make_law("robust-ellipsoid", th0, P=P, eps=0.5)
    assert covers(law, arm.theta) and Delta @ P @ Delta == pytest.approx(0.64)
    traj = arm.default_trajectory()
    res = rc3r.simulate(arm, law, traj, rc3r.SimOptions(duration=1.0, engine="python"))
    assert res.outcome == "finished", res.message
    m_lo, m_hi = guarantee.inertia_range(arm, res.q)
    bound = error_bound(law, m_lo, m_hi, arm.n)
    ball = make_law("robust", th0, rho=law.rho_P * 1.5, eps=0.5)
    assert np.all(np.abs(res.q - res.q_des).max(axis=0) <= bound)
    assert np.all(bound < guarantee.error_bound(ball, m_lo, m_hi, arm.n))


def test_bad_ellipsoids_are_refused(arm):
    p = arm.p
    for P, match in ((None, "needs the ellipsoid P"), (np.eye(p - 1), "15 x 15"),
                     (np.triu(np.ones((p, p))), "symmetric"), (-np.eye(p), "positive definite"),
                     (np.full((p, p), np.nan), "finite")):
        with pytest.raises(ParameterError, match=match):
            make_law("robust-ellipsoid", arm.theta, P=P)
