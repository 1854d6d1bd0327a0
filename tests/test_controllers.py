"""Each control law against an independent NumPy evaluation of its formula, one hand value,
and the refusal of bad gains."""
from __future__ import annotations

import numpy as np
import pytest

from rc3r.controllers import (LAWS, Adaptive, FeedbackLinearization, Law, PDGravity, Robust,
                              RobustPerCoefficient, default_gains, make_law, register_law)
from rc3r.errors import ParameterError
from rc3r.robots.rr3 import RR3
from rc3r.robots.rr3.model import coriolis_matrix, gravity, mass_matrix
from rc3r.robots.rr3.params import theta
from rc3r.robots.rr3.regressor import slotine_li_regressor

# Tolerance: the compiled kernel and the NumPy path do the same O(100) float operations in a
# different order on magnitudes up to ~1e3 N m -> agreement to ~1e-12 relative; 1e-9 absolute is safe.
ATOL = 1e-9


@pytest.fixture
def state(rng):
    q, qd, qr, qdr, qddr = (rng.uniform(-2, 2, 3) for _ in range(5))
    return q, qd, qr, qdr, qddr


def _u(c, table1, q, qd, qr, qdr, qddr, z=None):
    """The law's torque on the 3R (its Python path, which calls the compiled kernel)."""
    u, _, _ = c.torque(RR3(table1), q, qd, np.array([qr, qdr, qddr]), z)
    return u


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
    np.testing.assert_allclose(_u(c, table1, q, qd, qr, qdr, qddr), expected, rtol=0, atol=ATOL)


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
    np.testing.assert_allclose(_u(c, table1, q, qd, qr, qdr, qddr), expected, rtol=0, atol=ATOL * 1e3)


def test_robust_eq7_per_coefficient(table1, state, rng):
    """delta_i = -rho_i xi_i / max(|xi_i|, eps_i) (eq. 7)."""
    th, l2 = theta(table1), table1.lengths[1]
    q, qd, qr, qdr, qddr = state
    rho_i, eps_i = rng.uniform(0, 50, 15), rng.uniform(0.01, 5, 15)
    c = RobustPerCoefficient(th, rho_i=rho_i, eps_i=eps_i)
    Y, r = _slotine(q, qd, qr, qdr, qddr, c.Lambda, l2)
    xi = Y.T @ r
    expected = Y @ (th - rho_i * xi / np.maximum(np.abs(xi), eps_i)) - c.K * r
    np.testing.assert_allclose(_u(c, table1, q, qd, qr, qdr, qddr), expected, rtol=0, atol=ATOL * 1e3)


def test_adaptive_uses_estimate(table1, state, rng):
    """u = Y theta_hat - K r with the controller state theta_hat, not the initial theta."""
    th, l2 = theta(table1), table1.lengths[1]
    q, qd, qr, qdr, qddr = state
    c = Adaptive(th, Gamma=np.full(15, 3.0))
    z = th + rng.normal(size=15)
    Y, r = _slotine(q, qd, qr, qdr, qddr, c.Lambda, l2)
    np.testing.assert_allclose(_u(c, table1, q, qd, qr, qdr, qddr, z), Y @ z - c.K * r, rtol=0, atol=ATOL)
    np.testing.assert_array_equal(c.initial_state(), th)


def test_pd_gravity_hand_value(table1):
    """At q = 0 on the reference: u = g(0) = (0, g0 (theta14 + theta7/l2), g0 theta7/l2)
    = (0, 9.81 * (15 + 12), 9.81 * 12) = (0, 264.87, 117.72) N m for Table 1 (by hand)."""
    c = PDGravity(theta(table1))
    u = _u(c, table1, *(np.zeros(3) for _ in range(5)))
    np.testing.assert_allclose(u, [0.0, 264.87, 117.72], rtol=0, atol=1e-12)


def test_robust_on_reference_with_exact_model_is_inverse_dynamics(table1):
    """On the reference (r = 0) the robust term vanishes: u = Y(q, qd, qd, qdd) theta0 (hand identity)."""
    th, l2 = theta(table1), table1.lengths[1]
    q, qd, qdd = np.array([0.3, -0.2, 0.5]), np.array([1.0, 0.0, 1.0]), np.array([0.0, -5.0, 0.0])
    u = _u(Robust(th), table1, q, qd, q, qd, qdd)
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


class _ToyRobot:
    """A 2-joint, 4-coefficient stand-in: the laws see a robot only through ``regressor``."""

    n, p = 2, 4

    @staticmethod
    def regressor(q, qd, v, a):
        return np.array([[a[0], qd[0] * v[1], np.sin(q[0]), 0.0],
                         [0.0, a[1], np.cos(q[1]), v[0]]])


@pytest.mark.parametrize("eps", [1e-6, 1e6], ids=["outside-layer", "inside-layer"])
def test_robust_is_generic_over_n_and_p(rng, eps):
    """Eq. (6) on a 2-joint, 4-coefficient regressor: u = Y (theta0 - rho xi / max(|xi|, eps)) - K r."""
    robot = _ToyRobot()
    th = rng.uniform(-2, 2, 4)
    c = Robust(th, K=[3.0, 4.0], Lambda=7.0, rho=2.5, eps=eps)
    q, qd, qr, qdr, qddr = (rng.uniform(-1, 1, 2) for _ in range(5))
    e, ed = q - qr, qd - qdr
    v, a, r = qdr - 7.0 * e, qddr - 7.0 * ed, ed + 7.0 * e
    Y = robot.regressor(q, qd, v, a)
    xi = Y.T @ r
    expected = Y @ (th - 2.5 * xi / max(np.linalg.norm(xi), eps)) - np.array([3.0, 4.0]) * r
    u, zdot, diag = c.torque(robot, q, qd, np.array([qr, qdr, qddr]))
    np.testing.assert_allclose(u, expected, rtol=0, atol=1e-12)
    assert zdot.size == 0 and diag == pytest.approx(np.linalg.norm(xi), rel=1e-14)


def test_adaptive_rate_is_minus_gamma_yt_r(rng):
    """d theta_hat/dt = -Gamma Y^T r, elementwise Gamma (p,), on the toy robot."""
    robot = _ToyRobot()
    gamma = np.array([1.0, 2.0, 3.0, 4.0])
    c = Adaptive(np.zeros(4), Gamma=gamma, Lambda=2.0)
    q, qd, qr, qdr, qddr = (rng.uniform(-1, 1, 2) for _ in range(5))
    z = rng.uniform(-1, 1, 4)
    e, ed = q - qr, qd - qdr
    Y = robot.regressor(q, qd, qdr - 2.0 * e, qddr - 2.0 * ed)
    _, zdot, _ = c.torque(robot, q, qd, np.array([qr, qdr, qddr]), z)
    np.testing.assert_allclose(zdot, -gamma * (Y.T @ (ed + 2.0 * e)), rtol=0, atol=1e-13)


def test_gains_of_the_wrong_size_are_refused():
    """A 3-vector gain on a 2-joint robot is an error, not a silent broadcast."""
    c = FeedbackLinearization(np.ones(4), Kp=[1.0, 2.0, 3.0])
    with pytest.raises(ParameterError, match="entries"):
        c.torque(_ToyRobot(), np.zeros(2), np.zeros(2), np.zeros((3, 2)))


def test_registry_holds_the_five_laws_and_one_gain_table():
    """Every built-in law is registered; the command line's defaults are the classes' defaults."""
    assert set(LAWS) >= {"fbl", "robust", "robust-coeff", "adaptive", "pd"}
    assert default_gains("pd") == {"Kp": 500.0, "Kd": 100.0}
    assert default_gains("adaptive") == {"K": 100.0, "Lambda": 50.0, "K_inertia": 0.0, "Gamma": 10.0}
    assert default_gains("robust") == {"K": 100.0, "Lambda": 50.0, "K_inertia": 0.0, "eps": 0.5}
    assert PDGravity(np.ones(15)).Kp == 500.0 and Adaptive(np.ones(15)).Gamma[0] == 10.0


def test_make_law_passes_bounds_only_to_laws_that_use_them_and_refuses_unknown_gains():
    th = np.ones(15)
    assert make_law("robust", th, rho=3.0, rho_i=np.ones(15)).rho == 3.0
    assert not hasattr(make_law("fbl", th, rho=3.0), "rho")
    with pytest.raises(ParameterError, match="no gain Kpp"):
        make_law("fbl", th, Kpp=1.0)
    with pytest.raises(ParameterError, match="unknown controller"):
        make_law("nope", th)


def test_a_law_in_plain_python_registers_and_runs():
    """One class + one registration: a saturated-PD law written in Python is usable by name."""
    from dataclasses import dataclass

    @register_law
    @dataclass(frozen=True, eq=False)
    class SatPD(Law):
        umax: float = 1.0
        name = "test-sat-pd"

        def signals(self, q, qd, ref):
            n = len(q)
            w = np.clip(10.0 * (ref[0] - q), -self.umax, self.umax)
            return np.zeros(n), np.zeros(n), np.zeros(n), w

        def output(self, Y, r, z):
            return self.theta, np.zeros(0), 0.0

    try:
        law = make_law("test-sat-pd", np.zeros(4), umax=0.5)
        u, _, _ = law.torque(_ToyRobot(), np.zeros(2), np.zeros(2), np.array([[1.0, -0.01], [0, 0], [0, 0]]))
        np.testing.assert_allclose(u, [0.5, -0.1], atol=1e-15)
        with pytest.raises(ParameterError, match="no compiled kernel"):
            law.pack(2)
    finally:
        LAWS.pop("test-sat-pd", None)


# ---- signals of every law, gain shapes, inertia-scaled gains --------------------------------


@pytest.mark.parametrize("name", ["fbl", "pd", "robust", "robust-coeff", "adaptive"])
def test_signals_of_every_law_against_their_formulas(name, rng):
    """(v, a, r, w) on the toy robot with a moving reference, per law, against the module docstring:
    FBL v = qd, a = qdd_d - Kd e_dot - Kp e, r = w = 0; PD v = a = r = 0, w = -Kp e - Kd e_dot;
    sliding laws v = qd_d - Lambda e, a = qdd_d - Lambda e_dot, r = e_dot + Lambda e, w = -K r.
    Gains differ per joint so a swapped index shows."""
    gains = {"fbl": dict(Kp=[3.0, 5.0], Kd=[7.0, 11.0]), "pd": dict(Kp=[3.0, 5.0], Kd=[7.0, 11.0]),
             "robust": dict(K=[3.0, 5.0], Lambda=[7.0, 11.0]),
             "robust-coeff": dict(K=[3.0, 5.0], Lambda=[7.0, 11.0]),
             "adaptive": dict(K=[3.0, 5.0], Lambda=[7.0, 11.0])}[name]
    law = make_law(name, np.ones(4), rho=1.0, rho_i=np.ones(4), **gains)
    q, qd = rng.uniform(-1, 1, (2, 2))
    ref = rng.uniform(-1, 1, (3, 2))
    e, ed = q - ref[0], qd - ref[1]
    v, a, r, w = law.signals(q, qd, ref)
    z = np.zeros(2)
    if name == "fbl":
        want = (qd, ref[2] - np.array([7.0, 11.0]) * ed - np.array([3.0, 5.0]) * e, z, z)
    elif name == "pd":
        want = (z, z, z, -np.array([3.0, 5.0]) * e - np.array([7.0, 11.0]) * ed)
    else:
        lam, k = np.array([7.0, 11.0]), np.array([3.0, 5.0])
        want = (ref[1] - lam * e, ref[2] - lam * ed, ed + lam * e, -k * (ed + lam * e))
    for got, exp, label in zip((v, a, r, w), want, "varw"):
        np.testing.assert_allclose(got, exp, rtol=0, atol=1e-14, err_msg=label)


@pytest.mark.parametrize("K", [[1.0, 2.0], [1.0, 2.0, 3.0, 4.0]], ids=["short", "long"])
def test_a_gain_vector_of_the_wrong_length_is_refused_naming_the_sizes(K):
    """A 2- or 4-vector K for a 3-joint robot: refused (never truncated or padded)."""
    with pytest.raises(ParameterError, match=f"K has {len(K)} entries, the robot needs 3"):
        Robust(np.ones(15), K=K).pack(3)


@pytest.mark.parametrize("K, message", [
    (np.ones((3, 3)), "K as a matrix must be positive definite"),  # symmetric, rank 1
    (np.ones((2, 3)), r"K as a matrix must be square, got shape \(2, 3\)"),
    ([[2.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]], "K as a matrix must be symmetric"),
    ([[1.0, 0.0], [0.0, np.inf]], "K must be finite"),
    ([1.0, [2.0, 3.0]], "K must be numbers"),          # ragged: numpy's ValueError, reworded
    ([1.0, None, 2.0], "K must be finite"),            # None -> nan
    ({"a": 1}, "K must be numbers"),                   # numpy's TypeError, reworded
], ids=["singular-matrix", "non-square", "non-symmetric", "inf-matrix", "ragged", "none", "dict"])
def test_malformed_gains_are_refused_with_one_line(K, message):
    with pytest.raises(ParameterError, match=message):
        Robust(np.ones(15), K=K)


def test_theta_must_be_a_non_empty_vector_and_one_coefficient_is_fine():
    with pytest.raises(ParameterError, match="non-empty vector"):
        FeedbackLinearization(np.zeros(0))
    with pytest.raises(ParameterError, match="theta must be a number or a vector"):
        FeedbackLinearization(np.zeros((2, 2)))
    with pytest.raises(ParameterError, match="non-empty vector"):
        FeedbackLinearization(2.0)  # a scalar is not a coefficient vector
    assert FeedbackLinearization([2.0]).p == 1


@pytest.mark.parametrize("p", [3, 5])
def test_a_regressor_of_the_wrong_width_is_refused(p):
    """A law with p coefficients on a robot whose Y is (2, 4): a one-line ParameterError, either way."""
    with pytest.raises(ParameterError, match=r"has %d coefficients, the robot's regressor is \(2, 4\)" % p):
        Robust(np.ones(p)).torque(_ToyRobot(), np.zeros(2), np.zeros(2), np.zeros((3, 2)))


def test_laws_compare_by_identity_and_hash():
    """Laws hold arrays, so they compare by identity (two equal-looking laws are distinct objects)
    and can be set members or dict keys (the engines cache per law)."""
    a, b = Robust(np.ones(15)), Robust(np.ones(15))
    assert a == a and a != b and len({a, b, a}) == 2
    for law in (RobustPerCoefficient(np.ones(15)), Adaptive(np.ones(15)), PDGravity(np.ones(15)),
                FeedbackLinearization(np.ones(15))):
        assert {law: 1}[law] == 1


def test_robust_coeff_default_bounds_are_zero():
    """Without rho_i, eq. 7 has no robust term (rho_i = 0): it is the nominal Slotine-Li law."""
    law = RobustPerCoefficient(np.ones(15))
    np.testing.assert_array_equal(np.broadcast_to(law.rho_i, (15,)), np.zeros(15))


def test_inertia_scaled_gain_is_bandwidth_times_pinocchio_diag_M(arm, rng):
    """K_i = b M_ii(q) with M from pinocchio.crba of the committed URDF (1e-9 relative)."""
    import pinocchio as pin

    from rc3r.controllers import inertia_scaled_gain

    q = rng.uniform(-np.pi, np.pi, 3)
    M = np.array(pin.crba(arm.model, arm.model.createData(), q), copy=True)
    np.testing.assert_allclose(inertia_scaled_gain(RR3(arm.params), q, 40.0), 40.0 * np.diag(M), rtol=1e-9)
    for bad in (0.0, -5.0, float("inf"), float("nan")):
        with pytest.raises(ParameterError, match="bandwidth"):
            inertia_scaled_gain(RR3(arm.params), q, bad)


def test_describe_is_json_ready_with_every_field():
    """describe(): the registry name and every field, arrays as lists (json.dumps works)."""
    import json

    d = RobustPerCoefficient(np.array([1.0, 2.0]), rho_i=[0.5, 0.25], eps_i=0.1).describe()
    assert d["name"] == "robust-coeff" and d["theta"] == [1.0, 2.0] and d["rho_i"] == [0.5, 0.25]
    assert isinstance(d["K"], (float, list)) and json.loads(json.dumps(d)) == d


def test_default_gains_of_eq7_and_diagnostic_of_fbl(table1):
    """eq. 7's default eps_i is 0.5 per coefficient (docs/control.md's gain table); FBL and PD have
    no sliding variable, so their diagnostic ||Y^T r|| is 0."""
    law = RobustPerCoefficient(np.ones(15))
    np.testing.assert_array_equal(np.broadcast_to(law.eps_i, (15,)), np.full(15, 0.5))
    for c in (FeedbackLinearization(theta(table1)), PDGravity(theta(table1))):
        _, _, diag = c.torque(RR3(table1), np.full(3, 0.1), np.full(3, 0.2), np.ones((3, 3)))
        assert diag == 0.0


def test_register_law_refuses_what_is_not_a_law():
    class NotALaw:
        name = "not-a-law"

    for bad in (NotALaw, 5, Law):
        with pytest.raises(TypeError, match="Law subclass with a name"):
            register_law(bad)


def test_apply_regressor_is_w_plus_Y_theta():
    """The compiled engines' last step, u = w + Y theta_eff, by hand: Y = [[1, 2], [3, 4]],
    theta = (10, 100), w = (0.5, -0.5) -> u = (210.5, 429.5)."""
    from rc3r.controllers._kernels import apply_regressor

    u = np.empty(2)
    apply_regressor(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([10.0, 100.0]), np.array([0.5, -0.5]), u)
    np.testing.assert_array_equal(u, [210.5, 429.5])


def test_default_gains_are_the_documented_table():
    """docs/control.md's gain table, by hand: FBL Kp = Kd = 100; the sliding laws K = 100,
    Lambda = 50; robust eps = 0.5 and rho = 0 (no bound given: no robust term); eq. 7 eps_i = 0.5;
    adaptive Gamma = 10; PD Kp = 500, Kd = 100."""
    th = np.ones(15)
    want = {FeedbackLinearization: dict(Kp=100.0, Kd=100.0), PDGravity: dict(Kp=500.0, Kd=100.0),
            Robust: dict(K=100.0, Lambda=50.0, eps=0.5, rho=0.0),
            RobustPerCoefficient: dict(K=100.0, Lambda=50.0, eps_i=0.5, rho_i=0.0),
            Adaptive: dict(K=100.0, Lambda=50.0, Gamma=10.0)}
    for cls, gains in want.items():
        law = cls(th)
        for k, v in gains.items():
            assert np.all(np.asarray(getattr(law, k)) == v), (cls.__name__, k)


def test_robust_scalars_refuse_vectors_and_make_law_takes_bounds_by_keyword():
    with pytest.raises(ParameterError, match="rho must be one number"):
        Robust(np.ones(15), rho=[1.0, 2.0])
    with pytest.raises(ParameterError, match="eps must be one number"):
        Robust(np.ones(15), eps=[0.5, 0.5])
    with pytest.raises(TypeError):
        make_law("robust", np.ones(15), 5.0)  # rho only by keyword: a positional number is an error


def test_boolean_arrays_are_not_gains():
    with pytest.raises(ParameterError, match="K must be numbers"):
        Robust(np.ones(15), K=np.array([True, True, True]))
    with pytest.raises(ParameterError, match="K must be numbers"):
        Robust(np.ones(15), K=[100.0, True, 100.0])


def test_packed_gains_are_read_only():
    """A law is frozen, and so is its cached packed vector: a kernel cannot change the law's gains."""
    cp = Robust(np.ones(15)).pack(3)
    with pytest.raises(ValueError):
        cp[0] = 2.0


def test_eq7_each_coefficient_uses_its_own_eps(rng):
    """Eq. 7 on the toy robot with eps_i spanning 1e-3..1e3, so some coefficients sit inside
    their layer (linear) and others outside (saturated); a wrong eps index changes the torque."""
    robot = _ToyRobot()
    th = rng.uniform(-2, 2, 4)
    rho_i, eps_i = np.array([1.0, 2.0, 3.0, 4.0]), np.array([1e-3, 1e3, 1e-2, 1e2])
    c = RobustPerCoefficient(th, rho_i=rho_i, eps_i=eps_i, K=2.0, Lambda=3.0)
    q, qd, qr, qdr, qddr = (rng.uniform(-1, 1, 2) for _ in range(5))
    e, ed = q - qr, qd - qdr
    r = ed + 3.0 * e
    Y = robot.regressor(q, qd, qdr - 3.0 * e, qddr - 3.0 * ed)
    xi = Y.T @ r
    inside = np.abs(xi) < eps_i
    assert inside.any() and (~inside).any()
    u, _, _ = c.torque(robot, q, qd, np.array([qr, qdr, qddr]))
    np.testing.assert_allclose(u, Y @ (th - rho_i * xi / np.maximum(np.abs(xi), eps_i)) - 2.0 * r, rtol=0, atol=1e-12)


def test_inertia_scaled_gain_default_bandwidth_and_small_bandwidths():
    """Default b = 50 1/s (docs/generic.md); any b > 0 is accepted, also below 1."""
    from rc3r.controllers import inertia_scaled_gain

    class Unit:
        @staticmethod
        def mass_matrix(q):
            return np.diag([1.0, 2.0])

    np.testing.assert_array_equal(inertia_scaled_gain(Unit(), np.zeros(2)), [50.0, 100.0])
    np.testing.assert_array_equal(inertia_scaled_gain(Unit(), np.zeros(2), 0.5), [0.5, 1.0])


@pytest.mark.parametrize("name", ["robust", "robust-coeff", "adaptive"])
def test_a_matrix_k_gives_w_equal_minus_k_r(name, rng):
    """A symmetric positive definite K (6 x 6) on the UR5: the law's torque equals Y theta_eff - K r with Y
    from Pinocchio's own regressor (``regressor_pinocchio``) and theta_eff computed here from its formula,
    to 1e-10 relative (the compiled kernels pack K's diagonal, a flag and its off-diagonal part)."""
    import rc3r
    from rc3r.controllers import make_law

    arm = rc3r.load_robot("ur5")
    A = rng.standard_normal((6, 6))
    Kf = A @ A.T + 6.0 * np.eye(6)
    th = np.asarray(arm.theta, float)
    gains = {"robust": dict(rho=3.0, eps=5.0), "robust-coeff": dict(rho_i=np.full(arm.p, 0.2), eps_i=0.5),
             "adaptive": dict(Gamma=1.0)}[name]
    law = make_law(name, th, K=Kf, Lambda=20.0, **gains)
    diag = make_law(name, th, K=np.diag(Kf), Lambda=20.0, **gains)
    lay = law.layout()
    assert lay.slice(law.pack(6), "K_matrix", 6)[0] == 1.0 and lay.slice(diag.pack(6), "K_matrix", 6)[0] == 0.0
    assert np.array_equal(lay.slice(law.pack(6), "K_offdiag", 6).reshape(6, 6), Kf - np.diag(np.diag(Kf)))
    for _ in range(5):
        q, qd = rng.uniform(-1, 1, (2, 6))
        ref = rng.uniform(-1, 1, (3, 6))
        u, zdot, _ = law.torque(arm, q, qd, ref)
        e, ed = q - ref[0], qd - ref[1]
        r = ed + 20.0 * e
        Y = arm.regressor_pinocchio(q, qd, ref[1] - 20.0 * e, ref[2] - 20.0 * ed)
        xi = Y.T @ r
        if name == "robust":
            th_eff = th - 3.0 * xi / max(np.linalg.norm(xi), 5.0)
        elif name == "robust-coeff":
            th_eff = th - 0.2 * xi / np.maximum(np.abs(xi), 0.5)
        else:
            th_eff = th
            np.testing.assert_allclose(zdot, -xi, rtol=1e-10, atol=1e-12)
        want = Y @ th_eff - Kf @ r
        assert np.abs(u - want).max() <= 1e-10 * np.abs(want).max()
    assert law.k_min() == pytest.approx(np.linalg.eigvalsh(Kf)[0], rel=1e-12)


@pytest.mark.parametrize("K", [0.0, 5.0], ids=["scheduled-only", "plus-diagonal"])
def test_a_scheduled_k_subtracts_b_m_of_q_times_r(K, rng):
    """``K_inertia`` b: w = -(K + b M(q)) r with M from pin.crba at the measured q (the law's theta is the
    UR5's own, so its mass matrix is Pinocchio's): the torque equals Y theta_eff - (K + b M(q)) r to 1e-10 relative;
    K = 0 is allowed with b > 0 (b M is positive definite), K < 0 is not; k_min adds b m_min."""
    import pinocchio as pin

    import rc3r
    from rc3r.controllers import make_law

    arm = rc3r.load_robot("ur5")
    th = np.asarray(arm.theta, float)
    law = make_law("robust", th, rho=3.0, K=K, Lambda=10.0, eps=5.0, K_inertia=25.0)
    data = arm.model.createData()
    for _ in range(5):
        q, qd = rng.uniform(-1, 1, (2, 6))
        ref = rng.uniform(-1, 1, (3, 6))
        u, _, _ = law.torque(arm, q, qd, ref)
        e, ed = q - ref[0], qd - ref[1]
        r = ed + 10.0 * e
        Y = arm.regressor_pinocchio(q, qd, ref[1] - 10.0 * e, ref[2] - 10.0 * ed)
        xi = Y.T @ r
        M = pin.crba(arm.model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        want = Y @ (th - 3.0 * xi / max(np.linalg.norm(xi), 5.0)) - K * r - 25.0 * M @ r
        assert np.abs(u - want).max() <= 1e-10 * np.abs(want).max()
    assert law.k_min(0.2) == pytest.approx(K + 25.0 * 0.2)
    with pytest.raises(ParameterError, match="K must be >= 0"):
        make_law("robust", th, K=-1.0, K_inertia=25.0)
    with pytest.raises(ParameterError, match="K_inertia must be >= 0"):
        make_law("robust", th, K_inertia=-1.0)


def test_the_robust_laws_share_one_xi_norm_and_it_stays_plain_python():
    """rc3r.controllers.sliding.xi_norm is ||xi[:p]|| (3-4-12: 5 for p = 2, 13 for p = 3, by hand; a random
    vector against numpy.linalg.norm to 1e-15 relative); both robust laws' theta return it, and called
    from Python (a cold start's py_func) they compile nothing: the value kernels stay leaves."""
    from rc3r.controllers import robust, robust_coeff
    from rc3r.controllers.sliding import xi_norm

    v = np.array([3.0, 4.0, 12.0])
    assert xi_norm(v, 2) == 5.0 and xi_norm(v, 3) == 13.0
    xi = np.random.default_rng(7).normal(size=15)
    assert abs(xi_norm(xi, 15) - np.linalg.norm(xi)) <= 1e-15 * np.linalg.norm(xi)
    for mod, law in ((robust, Robust(np.ones(15))), (robust_coeff, RobustPerCoefficient(np.ones(15), rho_i=np.ones(15)))):
        th = xi.copy()
        assert mod.theta.py_func(law.pack(3), 3, None, th, None) == xi_norm(xi, 15)
    assert type(xi_norm).__name__ == "function"  # not a numba dispatcher
