"""rc3r.robots.rr3.model: M, S, g against Pinocchio, their structural properties, and the paper's typos.

Error measure (as in ``rc3r verify-model``, docs/conventions.md):
``max|x - ref| <= TOL * max(1, max|ref|)``. TOL = 1e-9: every entry is a sum of
O(10..100) float64 products of magnitudes <= O(10^3) (theta <= ~50, qd qd <= 25),
so rounding is ~1e-11 relative; a modelling error (wrong sign, missing factor)
shows up at 1e-3..1.
"""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from _helpers import TOL, arm, assert_close, pdata, th  # noqa: E402, F401  (fixtures: the named arms)
from rc3r.robots.rr3 import model as mdl
from rc3r.robots.rr3.params import ArmParams, LinkParams, theta
from rc3r.robots.rr3.urdf import model_from_params  # make_urdf text -> Pinocchio, gravity (0, 0, -g0)

N_STATES = 50

# The identity tests run on every named configuration (tests/_helpers.py): these
# module-scoped arm, th, pdata override conftest's Table 1 fixtures in this module.





def states(rng, n=N_STATES):
    """q uniform in [-pi, pi], qd uniform in [-5, 5], each (n, 3)."""
    return rng.uniform(-math.pi, math.pi, (n, 3)), rng.uniform(-5, 5, (n, 3))


def pin_M(model, data, q):
    M = np.array(pin.crba(model, data, q), copy=True)
    return np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle (at least)





# ---- identities against Pinocchio --------------------------------------------------------


def test_mass_matrix_equals_crba(arm, th, pdata, rng):
    """M(q) == pinocchio.crba(q) (symmetrized) at random states."""
    Q, _ = states(rng)
    for q in Q:
        assert_close(mdl.mass_matrix(th, q), pin_M(arm.model, pdata, q))


def test_coriolis_matrix_equals_pinocchio_coriolis_matrix(arm, th, pdata, rng):
    """S(q, qd) == pinocchio.computeCoriolisMatrix(q, qd) (the Christoffel matrix)."""
    Q, QD = states(rng)
    for q, qd in zip(Q, QD):
        assert_close(mdl.coriolis_matrix(th, q, qd), pin.computeCoriolisMatrix(arm.model, pdata, q, qd))


def test_S_qd_equals_rnea_without_acceleration_minus_gravity(arm, th, pdata, rng):
    """S(q, qd) qd == rnea(q, qd, 0) - g(q), and coriolis_vector == S qd."""
    Q, QD = states(rng)
    for q, qd in zip(Q, QD):
        ref = pin.rnea(arm.model, pdata, q, qd, np.zeros(3)) - pin.computeGeneralizedGravity(arm.model, pdata, q)
        assert_close(mdl.coriolis_matrix(th, q, qd) @ qd, ref)
        assert_close(mdl.coriolis_vector(th, q, qd), ref)


def test_gravity_equals_computeGeneralizedGravity(arm, th, pdata, rng):
    """g(q) == pinocchio.computeGeneralizedGravity(q); g_1 == 0 exactly."""
    Q, _ = states(rng)
    l2, g0 = arm.params.lengths[1], arm.params.g0
    for q in Q:
        g = mdl.gravity(th, q, l2=l2, g0=g0)
        assert_close(g, pin.computeGeneralizedGravity(arm.model, pdata, q))
        assert g[0] == 0.0


def test_default_gravity_is_pinocchios_not_only_rc3rs(rng):
    """With no g0 given, g(q), Y(q, 0, 0, 0) theta and the robot's g equal computeGeneralizedGravity of
    the committed URDF loaded by Pinocchio itself with Pinocchio's own default gravity (not one set from
    rc3r's G0): a wrong gravity constant in rc3r cannot hide behind a reference built from it."""
    import rc3r
    from rc3r.robots.rr3 import regressor as reg
    from rc3r.robots.rr3.urdf import REPO_URDF

    model = pin.buildModelFromUrdf(str(REPO_URDF))
    np.testing.assert_array_equal(model.gravity.linear, pin.Model().gravity.linear)  # Pinocchio's default
    assert model.gravity.linear[2] < -9.8  # and it is the Earth's
    data = model.createData()
    from rc3r.robots.rr3.params import table1
    th1 = theta(table1())
    robot = rc3r.load_robot()
    z = np.zeros(3)
    for q in states(rng, 10)[0]:
        ref = pin.computeGeneralizedGravity(model, data, q)
        assert_close(mdl.gravity(th1, q, l2=1.0), ref)
        assert_close(reg.slotine_li_regressor(q, z, z, z, l2=1.0) @ th1, ref)
        assert_close(robot.gravity(q), ref)


# ---- structural properties ---------------------------------------------------------------


def mdot_pinocchio(model, data, q, qd):
    """dM/dt exactly: column j = (dtau_dq(q, 0, e_j) - dtau_dq(q, 0, 0)) qd (RNEA derivatives)."""
    z = np.zeros(3)
    base = np.array(pin.computeRNEADerivatives(model, data, q, z, z)[0], copy=True)
    out = np.empty((3, 3))
    for j in range(3):
        dq = np.array(pin.computeRNEADerivatives(model, data, q, z, np.eye(3)[j])[0], copy=True)
        out[:, j] = (dq - base) @ qd
    return out


def mdot_finite_difference(model, data, q, qd):
    """dM/dt by a 5-point central difference of crba along q + s qd (step |s qd| = 1e-3)."""
    h = 1e-3 / np.linalg.norm(qd)
    f = lambda s: pin_M(model, data, q + s * qd)  # noqa: E731
    return (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12 * h)


def test_S_plus_S_transpose_equals_Mdot(arm, th, pdata, rng):
    """S + S^T == dM/dt (analytic, from Pinocchio's RNEA derivatives), i.e. Mdot - 2S is skew."""
    Q, QD = states(rng)
    for q, qd in zip(Q, QD):
        S = mdl.coriolis_matrix(th, q, qd)
        Md = mdot_pinocchio(arm.model, pdata, q, qd)
        assert_close(S + S.T, Md)
        N = Md - 2 * S
        x = rng.normal(size=3)
        assert abs(x @ N @ x) <= TOL * max(1.0, np.abs(Md).max()) * (x @ x)


def test_analytic_Mdot_agrees_with_finite_difference_of_crba(arm, pdata, rng):
    """The analytic dM/dt used as reference == 5-point central difference of crba.

    Tolerance 1e-8 relative: truncation ~ (1e-3)^4 |M^(5)| / 30 ~ 1e-11 and
    rounding ~ eps |M| / 1e-3 ~ 1e-11 relative; 1e-8 leaves a wide margin while
    a wrong column/sign would be off by O(1).
    """
    Q, QD = states(rng, 10)
    for q, qd in zip(Q, QD):
        assert_close(mdot_pinocchio(arm.model, pdata, q, qd),
                     mdot_finite_difference(arm.model, pdata, q, qd), tol=1e-8)


def test_mass_matrix_symmetric_positive_definite(th, rng):
    """M(q) == M(q)^T exactly and its smallest eigenvalue > 0 at random q."""
    Q, _ = states(rng, 200)
    M = mdl.mass_matrix(th, Q)
    np.testing.assert_array_equal(M, np.swapaxes(M, 1, 2))
    assert np.linalg.eigvalsh(M)[:, 0].min() > 0


def test_batch_output_equals_per_state_output(th, rng):
    """(N, 3) input gives the stack of the (3,) outputs, bit for bit (same compiled kernel)."""
    Q, QD = states(rng, 7)
    M, S, g = mdl.mass_matrix(th, Q), mdl.coriolis_matrix(th, Q, QD), mdl.gravity(th, Q, l2=1.0)
    for n in range(7):
        np.testing.assert_array_equal(M[n], mdl.mass_matrix(th, Q[n]))
        np.testing.assert_array_equal(S[n], mdl.coriolis_matrix(th, Q[n], QD[n]))
        np.testing.assert_array_equal(g[n], mdl.gravity(th, Q[n], l2=1.0))


def test_shapes(th, rng):
    """Single state: (3, 3) / (3,); batch of N: (N, 3, 3) / (N, 3); bad shapes raise ValueError."""
    Q, QD = states(rng, 4)
    assert mdl.mass_matrix(th, Q[0]).shape == (3, 3)
    assert mdl.coriolis_matrix(th, Q[0], QD[0]).shape == (3, 3)
    assert mdl.gravity(th, Q[0], l2=1.0).shape == (3,)
    assert mdl.mass_matrix(th, Q).shape == (4, 3, 3)
    assert mdl.coriolis_matrix(th, Q, QD).shape == (4, 3, 3)
    assert mdl.coriolis_vector(th, Q, QD).shape == (4, 3)
    assert mdl.gravity(th, Q, l2=1.0).shape == (4, 3)
    with pytest.raises(ValueError):
        mdl.mass_matrix(th, np.zeros(4))
    with pytest.raises(ValueError):
        mdl.mass_matrix(th[:14], Q[0])


# ---- the paper's typos: the printed formula disagrees with Pinocchio, the fixed one agrees ----


def _typo_arm() -> ArmParams:
    """Table 1 with l2 = 0.7, l3 = 0.6 and r_c3 = (0.3, -0.1, 0.2), so that l2 != l2^2 and
    r_cx3 != r_cy3 (on Table 1 itself l2 = 1 hides the first typo)."""
    links = (
        LinkParams(1.0, 10.0, (0.5, -0.5, -0.1), (0.5, 0.5, 0.5, 0.1, 0.1, 0.1)),
        LinkParams(0.7, 10.0, (-0.5, -0.3, 0.4), (0.5, 0.5, 0.5, 0.2, 0.2, 0.2)),
        LinkParams(0.6, 10.0, (0.3, -0.1, 0.2), (0.5, 0.5, 0.5, 0.2, 0.2, 0.2)),
    )
    return ArmParams(links)


def _link_kinetic_energies(model, data, q, qd):
    """T_i = 1/2 v_i . (I_i v_i) for the three bodies (Pinocchio spatial velocity and inertia)."""
    pin.forwardKinematics(model, data, q, qd)
    return np.array([0.5 * data.v[i].vector @ model.inertias[i].matrix() @ data.v[i].vector
                     for i in range(1, 4)])


def paper_T2(p: ArmParams, q, qd):
    """T2 exactly as printed in section 3.1 (no typo found in it)."""
    _, l2, _ = p.lengths
    k = p.links[1]
    m, (x, y, z) = k.mass, k.com
    ixx, iyy, izz, ixy, ixz, iyz = k.inertia
    s2, c2 = math.sin(q[1]), math.cos(q[1])
    X = l2 + x
    d1, d2 = qd[0], qd[1]
    return (0.5 * m * (d1**2 * z**2 + d2**2 * (X**2 + y**2) - 2 * d1 * d2 * z * (y * c2 + X * s2)
                       + d1**2 * (X**2 * c2**2 + y**2 * s2**2 - 2 * X * y * c2 * s2))
            + 0.5 * (d1**2 * (s2**2 * ixx + c2**2 * iyy + 2 * c2 * s2 * ixy)
                     + 2 * d1 * d2 * (ixz * s2 + iyz * c2) + d2**2 * izz))


def paper_T3(p: ArmParams, q, qd, *, fix_l2_squared: bool, fix_rcx3: bool):
    """T3 as printed in section 3.1, optionally with each of its two typos fixed:
    ``l2 qd2^2`` -> ``l2^2 qd2^2`` and ``(l3 + r_cy3) c3`` -> ``(l3 + r_cx3) c3``."""
    _, l2, l3 = p.lengths
    k = p.links[2]
    m, (x, y, z) = k.mass, k.com
    ixx, iyy, izz, ixy, ixz, iyz = k.inertia
    s2, c2 = math.sin(q[1]), math.cos(q[1])
    s3, c3 = math.sin(q[2]), math.cos(q[2])
    s23, c23 = math.sin(q[1] + q[2]), math.cos(q[1] + q[2])
    X = l3 + x
    d1, d2, d23 = qd[0], qd[1], qd[1] + qd[2]
    L = l2**2 if fix_l2_squared else l2
    Z = x if fix_rcx3 else y
    return (0.5 * m * (d1**2 * z**2 + L * d2**2 + d23**2 * (X**2 + y**2)
                       + 2 * d1 * d2 * l2 * z * (s3 * c23 - c3 * s23)
                       - 2 * d1 * d23 * z * (y * c23 + X * s23)
                       + 2 * d2 * d23 * l2 * ((l3 + Z) * c3 - y * s3)
                       + d1**2 * (X * c23 - y * s23 + l2 * c2) ** 2)
            + 0.5 * (d1**2 * (ixx * s23**2 + iyy * c23**2 + 2 * ixy * s23 * c23)
                     + 2 * d1 * d23 * (ixz * s23 + iyz * c23) + d23**2 * izz))


def test_paper_T2_as_printed_matches_pinocchio(rng):
    """The printed T2 is right: 1/2 v2.(I2 v2) from Pinocchio equals it (l2 != 1)."""
    p = _typo_arm()
    model = model_from_params(p)
    data = model.createData()
    Q, QD = states(rng, 20)
    for q, qd in zip(Q, QD):
        assert_close(paper_T2(p, q, qd), _link_kinetic_energies(model, data, q, qd)[1])


def test_paper_T3_typos_l2_squared_and_rcx3(rng):
    """Typos in T3: ``l2 qd2^2`` must be ``l2^2 qd2^2`` and ``(l3 + r_cy3) c3`` must be
    ``(l3 + r_cx3) c3``. Only with both fixes does T3 equal Pinocchio's kinetic energy of link 3."""
    p = _typo_arm()
    model = model_from_params(p)
    data = model.createData()
    Q, QD = states(rng, 20)
    err = {}
    for fix in [(False, False), (True, False), (False, True), (True, True)]:
        err[fix] = max(abs(paper_T3(p, q, qd, fix_l2_squared=fix[0], fix_rcx3=fix[1])
                           - _link_kinetic_energies(model, data, q, qd)[2])
                       for q, qd in zip(Q, QD))
    assert err[(True, True)] < 1e-10
    # each typo alone changes T3 by O(1) J at these speeds
    assert min(err[(False, False)], err[(True, False)], err[(False, True)]) > 1e-2


def test_kinetic_energies_sum_to_half_qd_M_qd(rng):
    """Sum_i T_i (Pinocchio, per body) == 1/2 qd^T M(q) qd (closed form) -- ties T_i to M."""
    p = _typo_arm()
    model = model_from_params(p)
    data = model.createData()
    th = theta(p)
    Q, QD = states(rng, 20)
    for q, qd in zip(Q, QD):
        assert_close(_link_kinetic_energies(model, data, q, qd).sum(), 0.5 * qd @ mdl.mass_matrix(th, q) @ qd)


def test_paper_omega3_last_entry_is_qd2_plus_qd3(rng):
    """omega_3 = (qd1 s23, qd1 c23, qd2 + qd3) in DH frame 3 (printed: qd2 qd3, a typo);
    also omega_2 = (qd1 s2, qd1 c2, qd2) and omega_1 = (0, qd1, 0) as printed."""
    p = _typo_arm()
    model = model_from_params(p)
    data = model.createData()
    Q, QD = states(rng, 20)
    R1 = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], float)  # DH frame 1 -> URDF link 1 (Rot_x(pi/2))
    for q, qd in zip(Q, QD):
        pin.forwardKinematics(model, data, q, qd)
        s2, c2, s23, c23 = math.sin(q[1]), math.cos(q[1]), math.sin(q[1] + q[2]), math.cos(q[1] + q[2])
        # DH frames 2 and 3 have the orientation of URDF links 2 and 3 (alpha2 = alpha3 = 0)
        w3 = np.asarray(data.v[3].angular)
        assert_close(w3, [qd[0] * s23, qd[0] * c23, qd[1] + qd[2]])
        assert abs(w3[2] - qd[1] * qd[2]) > 1e-3  # the printed entry is wrong
        assert_close(np.asarray(data.v[2].angular), [qd[0] * s2, qd[0] * c2, qd[1]])
        assert_close(R1.T @ np.asarray(data.v[1].angular), [0, qd[0], 0])


def paper_m11(p: ArmParams, q, *, fix_s23: bool):
    """m11 in standard parameters as printed; the term ``-2 r_cy3 l2 c2 s2`` -> ``... s23`` if fixed."""
    _, l2, l3 = p.lengths
    (m1, (x1, _, z1)), (m2, (x2, y2, z2)), (m3, (x3, y3, z3)) = ((k.mass, k.com) for k in p.links)
    iyy1 = p.links[0].inertia[1]
    ixx2, iyy2, _, ixy2, _, _ = p.links[1].inertia
    ixx3, iyy3, _, ixy3, _, _ = p.links[2].inertia
    s2, c2 = math.sin(q[1]), math.cos(q[1])
    s23, c23 = math.sin(q[1] + q[2]), math.cos(q[1] + q[2])
    X2, X3 = l2 + x2, l3 + x3
    last = s23 if fix_s23 else s2
    return (m1 * (x1**2 + z1**2) + iyy1 + m2 * z2**2
            + m2 * (X2**2 * c2**2 + y2**2 * s2**2 - 2 * X2 * y2 * c2 * s2)
            + ixx2 * s2**2 + iyy2 * c2**2 + 2 * ixy2 * c2 * s2 + m3 * z3**2
            + m3 * (X3**2 * c23**2 + y3**2 * s23**2 - 2 * X3 * y3 * c23 * s23 + l2**2 * c2**2
                    + 2 * X3 * l2 * c2 * c23 - 2 * y3 * l2 * c2 * last)
            + ixx3 * s23**2 + iyy3 * c23**2 + 2 * ixy3 * s23 * c23)


def test_paper_m11_typo_s2_should_be_s23(arm, pdata, rng):
    """m11: the printed ``-2 r_cy3 l2 c2 s2`` disagrees with crba; ``-2 r_cy3 l2 c2 s23`` agrees."""
    p = arm.params  # Table 1: r_cy3 = 0.2, l2 = 1, so the term is visible
    Q, _ = states(rng, 20)
    ref = np.array([pin_M(arm.model, pdata, q)[0, 0] for q in Q])
    fixed = np.array([paper_m11(p, q, fix_s23=True) for q in Q])
    printed = np.array([paper_m11(p, q, fix_s23=False) for q in Q])
    assert_close(fixed, ref)
    assert np.max(np.abs(printed - ref)) > 1e-2


def test_paper_printed_M_matrix_entries_11_and_33(arm, th, pdata, rng):
    """The printed M matrix has two typos: (1,1) has ``theta5 s2 s2 c3`` for ``theta5 s23 c23``,
    and (3,3) reads ``theta13 + theta6 s3 + theta7 c3`` where the m_ij list (and crba) give
    ``m33 = theta13``. The fixed entries equal crba."""
    Q, _ = states(rng, 20)
    for q in Q:
        s2, c2 = math.sin(q[1]), math.cos(q[1])
        s3, c3 = math.sin(q[2]), math.cos(q[2])
        s23, c23 = math.sin(q[1] + q[2]), math.cos(q[1] + q[2])
        M = pin_M(arm.model, pdata, q)
        rest = (th[0] + th[1] * s2**2 + th[2] * s2 * c2 + th[3] * s23**2
                + 2 * th[5] * c2 * s23 + 2 * th[6] * c2 * c23)
        assert_close(rest + th[4] * s23 * c23, M[0, 0])
        assert_close(th[12], M[2, 2])
    # the printed versions are off by O(1) somewhere on these states
    err11 = max(abs(th[4] * (s2 * s2 * c3 - s23 * c23)) for s2, c3, s23, c23 in (
        (math.sin(q[1]), math.cos(q[2]), math.sin(q[1] + q[2]), math.cos(q[1] + q[2])) for q in Q))
    err33 = max(abs(th[5] * math.sin(q[2]) + th[6] * math.cos(q[2])) for q in Q)
    assert err11 > 1e-2 and err33 > 1e-2  # the fixed entries agree to 1e-9: the typos are visible


@pytest.mark.parametrize("scale", [1.0, 1e-3], ids=["unit", "small"])
def test_solve_spd3_equals_numpy_solve_and_flags_indefinite_matrices(scale, rng):
    """The plant's 3x3 Cholesky solve: x == numpy.linalg.solve(M, b) (1e-12 relative, condition
    numbers < 100) at every scale (a PD matrix of entries ~1e-3 is still PD), and False with x
    untouched when any leading minor is not positive (the engines' "M not positive definite")."""
    from rc3r.robots.rr3.kernels import solve_spd3

    for _ in range(20):
        A = rng.normal(size=(3, 3))
        M = scale * (A @ A.T + 3.0 * np.eye(3))
        b = rng.normal(size=3)
        x = np.empty(3)
        assert solve_spd3(M, b, x) is True
        np.testing.assert_allclose(x, np.linalg.solve(M, b), rtol=1e-12, atol=0)
    for bad in (np.diag([-1.0, 1.0, 1.0]), np.diag([0.0, 1.0, 1.0]), np.diag([1.0, 0.0, 1.0]), np.diag([1.0, 1.0, -1e-9]),
                np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]])):
        x = np.full(3, 7.0)
        assert solve_spd3(scale * bad, np.ones(3), x) is False
        np.testing.assert_array_equal(x, np.full(3, 7.0))
