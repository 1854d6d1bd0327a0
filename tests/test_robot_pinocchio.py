"""rc3r.robots.pinocchio: any serial arm through Pinocchio, its Slotine--Li regressor and base parameters.

Tolerances: every identity compares float64 sums of O(10..100) products of magnitudes
<= O(1e3) (torques of the UR5/Panda/3R at |qd|, |a| <= 5), rounding ~1e-13 relative;
the checks use the verify-model measure (``_helpers.assert_close``, 1e-9 relative to
max(1, max|ref|)) unless a tighter bound is stated. "Fails" means an error >= 1e-2
relative, 10^7 times the tolerance.
"""
from __future__ import annotations

import pickle

import numpy as np
import pinocchio as pin
import pytest
from _helpers import assert_close

from rc3r.errors import ConfigError, UrdfError
from rc3r.robots.base_parameters import INDEPENDENCE_TOL, RANK_RTOL, base_parameters
from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir
from rc3r.experiments.bench_generic import bench_regressor
from rc3r.verify import verify_model

REPO_3R = "urdf/rr3.urdf"


@pytest.fixture(scope="module")
def arm3(request):
    return PinocchioRobot.from_urdf(request.config.rootpath / REPO_3R)


@pytest.fixture(scope="module", params=["ur5", "panda", "arm3"])
def robot(request):
    return request.getfixturevalue(request.param)


def _states(rng, n, N=40):
    return rng.uniform(-np.pi, np.pi, (N, n)), *rng.uniform(-5, 5, (3, N, n))


def _pinocchio_sl(model, q, qd, v, a):
    """M a + C(q, qd) v + g from crba (symmetrized), computeCoriolisMatrix, computeGeneralizedGravity."""
    data = model.createData()
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    return M @ a + pin.computeCoriolisMatrix(model, data, q, qd) @ v + pin.computeGeneralizedGravity(model, data, q)


# ---- the facts the regressor is built on ------------------------------------------------------


def test_coriolis_matrix_is_symmetric_bilinear(robot, rng):
    """computeCoriolisMatrix is the Christoffel matrix: C(q, x) y == C(q, y) x for 1-DoF joints."""
    m = robot.model
    d = m.createData()
    for q, x, y, _ in zip(*_states(rng, robot.n, 20)):
        assert_close(pin.computeCoriolisMatrix(m, d, q, x) @ y, pin.computeCoriolisMatrix(m, d, q, y) @ x)


def test_joint_torque_regressor_is_rnea_in_dynamic_parameters(robot, rng):
    """computeJointTorqueRegressor(q, v, a) @ [toDynamicParameters of every body] == rnea(q, v, a)."""
    m = robot.model
    d = m.createData()
    std = robot.standard_parameters()
    for q, v, a, _ in zip(*_states(rng, robot.n, 20)):
        assert_close(pin.computeJointTorqueRegressor(m, d, q, v, a) @ std, pin.rnea(m, d, q, v, a))


def test_slotine_li_identity(robot, rng):
    """Y(q, qd, v, a) theta == M a + C(q, qd) v + g (Pinocchio), for the compiled and the reference
    path, and Y_pi pi == the same in standard parameters."""
    Q, QD, V, A = _states(rng, robot.n)
    ref = np.array([_pinocchio_sl(robot.model, *s) for s in zip(Q, QD, V, A)])
    assert_close(robot.regressor(Q, QD, V, A) @ robot.theta, ref)
    assert_close(robot.regressor_pinocchio(Q, QD, V, A) @ robot.theta, ref)
    assert_close(robot.regressor_pinocchio(Q, QD, V, A, standard=True) @ robot.standard_parameters(), ref)


def test_plain_joint_torque_regressor_is_not_slotine_li(ur5, rng):
    """R(q, qd, a) in place of Y(q, qd, v, a) gives C(q, qd) qd, not C(q, qd) v: the identity fails
    (relative error >= 1e-2) when v != qd, and holds when v == qd."""
    m = ur5.model
    d = m.createData()
    std = ur5.standard_parameters()
    for q, qd, v, a in zip(*_states(rng, ur5.n, 10)):
        ref = _pinocchio_sl(m, q, qd, v, a)
        err = np.abs(pin.computeJointTorqueRegressor(m, d, q, qd, a) @ std - ref).max()
        assert err > 1e-2 * max(1.0, np.abs(ref).max())
        assert_close(pin.computeJointTorqueRegressor(m, d, q, qd, a) @ std, _pinocchio_sl(m, q, qd, qd, a))


def test_compiled_kernel_equals_pinocchio_path(robot, rng):
    """The numba kernel and the two computeJointTorqueRegressor calls agree to 1e-12 relative
    (same arithmetic up to the order of O(100)-term sums)."""
    Q, QD, V, A = _states(rng, robot.n, 200)
    assert robot.kernel is not None
    assert_close(robot.regressor(Q, QD, V, A), robot.regressor_pinocchio(Q, QD, V, A), tol=1e-12)
    assert_close(robot.regressor(Q[0], QD[0], V[0], A[0]), robot.regressor_pinocchio(Q, QD, V, A)[0], tol=1e-12)


@pytest.mark.parametrize("name", ["ur5", "panda", "arm3"])
def test_verify_model_passes(name, request):
    """rc3r.verify.verify_model (M, C, g, Y, skew symmetry, least squares, minimality) passes."""
    report = verify_model(request.getfixturevalue(name), samples=30, seed=3)
    failed = {k: (c.max_rel_err, c.detail) for k, c in report.checks.items() if not c.passed}
    assert report.passed, failed


# ---- base parameters -----------------------------------------------------------------------


@pytest.mark.parametrize("name,n,p", [("ur5", 6, 36), ("panda", 7, 43), ("arm3", 3, 15)])
def test_base_parameter_counts(name, n, p, request):
    """Reference counts: UR5 36, Panda (fingers locked) 43, the paper's 3R 15."""
    robot = request.getfixturevalue(name)
    assert (robot.n, robot.p, robot.theta.shape, len(robot.coefficient_names)) == (n, p, (p,), p)
    assert len(robot.standard_parameter_names) == 10 * robot.nbodies == 10 * n


def test_base_parameters_do_not_depend_on_the_seed(robot):
    """Greedy selection in column order: same count, same columns, same K (1e-9) for seeds 0, 1, 2."""
    ref = base_parameters(robot.model, seed=0)
    for seed in (1, 2):
        other = base_parameters(robot.model, seed=seed)
        assert other.p == ref.p
        np.testing.assert_array_equal(other.independent, ref.independent)
        np.testing.assert_allclose(other.K, ref.K, rtol=0, atol=1e-9 * max(1.0, np.abs(ref.K).max()))


def test_rank_gap_is_wide(robot):
    """The numerical rank is unambiguous: dependent columns' residuals <= 1e-12, independent ones
    >= 1e-3 (INDEPENDENCE_TOL = 1e-7 between), s_p/s_1 >= 1e-3 >> RANK_RTOL >> s_{p+1}/s_1."""
    b = robot.base
    assert b.residuals[b.dependent].max() <= 1e-12 < INDEPENDENCE_TOL < 1e-3 <= b.residuals[b.independent].min()
    s = b.singular_values / b.singular_values[0]
    assert s[b.p - 1] >= 1e-3 > RANK_RTOL > 1e-12 >= (s[b.p] if s.size > b.p else 0.0)


def test_theta_of_standard_is_linear_and_batched(robot, rng):
    """theta_of_standard maps (..., 10 nb) -> (..., p) linearly, and theta == theta_of_standard(std)."""
    std = robot.standard_parameters()
    X = rng.normal(size=(4, 5, std.size))
    th = robot.theta_of_standard(X)
    assert th.shape == (4, 5, robot.p)
    assert_close(th[1, 2], robot.theta_of_standard(X[1, 2]), tol=1e-14)
    assert_close(robot.theta_of_standard(std), robot.theta, tol=0)
    assert_close(robot.theta_of_standard(X[0, 0] + 2 * X[0, 1]), th[0, 0] + 2 * th[0, 1], tol=1e-12)


def test_with_standard_parameters(robot, rng):
    """A perturbed plant: its inertias are the given standard parameters, its theta is
    theta_of_standard of them, and its rnea equals Y theta (same base structure)."""
    std = robot.standard_parameters() * rng.uniform(0.8, 1.2, robot.standard_parameters().size)
    other = robot.with_standard_parameters(std, "perturbed")
    assert other.label == "perturbed" and other.base is robot.base
    assert_close(other.standard_parameters(), std, tol=1e-14)
    assert_close(other.theta, robot.theta_of_standard(std), tol=1e-14)
    Q, QD, _, A = _states(rng, robot.n, 10)
    d = other.model.createData()
    assert_close(other.regressor(Q, QD, QD, A) @ other.theta,
                 np.array([pin.rnea(other.model, d, *s) for s in zip(Q, QD, A)]))


def test_3r_spans_the_closed_form_regressor(arm3, rng):
    """Over the same states, the base regressor of the 3R and the closed-form regressor of
    RR3.from_urdf() (15 columns each) span the same column space (projection residual 1e-10)."""
    from rc3r.robots.rr3 import RR3

    closed = RR3.from_urdf()
    Q, QD, V, A = _states(rng, 3, 100)
    Y1 = arm3.regressor(Q, QD, V, A).reshape(-1, 15)
    Y2 = closed.regressor(Q, QD, V, A).reshape(-1, 15)
    U1, s1, _ = np.linalg.svd(Y1, full_matrices=False)
    U2, s2, _ = np.linalg.svd(Y2, full_matrices=False)
    assert s1[-1] / s1[0] > 1e-6 and s2[-1] / s2[0] > 1e-6  # both of full rank 15
    cosines = np.linalg.svd(U1.T @ U2, compute_uv=False)  # cosines of the principal angles
    assert np.all(np.abs(cosines - 1.0) <= 1e-10)


def test_3r_torque_equals_closed_form(arm3, rng):
    """Y theta (Pinocchio base parameters) == Y_RR3 theta_RR3 (the paper's 15 coefficients), 1e-9."""
    from rc3r.robots.rr3 import RR3

    closed = RR3.from_urdf()
    Q, QD, V, A = _states(rng, 3, 100)
    assert_close(arm3.regressor(Q, QD, V, A) @ arm3.theta, closed.regressor(Q, QD, V, A) @ closed.theta)


# ---- model terms, shapes, loading ------------------------------------------------------------


def test_model_terms_batch_and_plant(ur5, rng):
    """Batched M, C, g, aba have a leading axis N and equal the single-state calls; the plant
    satisfies M qdd + C qd + g == u."""
    Q, QD, _, U = _states(rng, ur5.n, 5)
    M, C, g, qdd = ur5.mass_matrix(Q), ur5.coriolis_matrix(Q, QD), ur5.gravity(Q), ur5.forward_dynamics(Q, QD, U)
    assert (M.shape, C.shape, g.shape, qdd.shape) == ((5, 6, 6), (5, 6, 6), (5, 6), (5, 6))
    assert_close(M[2], ur5.mass_matrix(Q[2]), tol=0)
    assert_close(M, np.swapaxes(M, 1, 2), tol=0)
    assert ur5.regressor(Q, QD, QD, U).shape == (5, 6, 36) and ur5.regressor(Q[0], QD[0], QD[0], U[0]).shape == (6, 36)
    assert_close(np.einsum("nij,nj->ni", M, qdd) + np.einsum("nij,nj->ni", C, QD) + g, U)
    lo, hi = ur5.joint_limits
    assert lo.shape == hi.shape == (6,) and np.all(lo < hi)


def test_named_robots(ur5, panda):
    """named(): files found under the example-robot-data prefix; Panda's fingers locked; describe()
    reports the robot's own name."""
    assert (example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf").is_file()
    assert panda.joint_names == tuple(f"panda_joint{i}" for i in range(1, 8))
    assert panda.locked == {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
    d = ur5.describe()
    assert (d["robot"], d["robot_name"], d["n"], d["p"]) == ("pinocchio", "ur5", 6, 36)
    assert d["urdf"].endswith("ur5_robot.urdf") and "ur5" in repr(ur5)
    with pytest.raises(ConfigError, match="unknown named robot"):
        PinocchioRobot.named("no-such-arm")


def test_pickle_round_trip(ur5, rng):
    """A robot survives pickling (pinocchio Data rebuilt) with the same regressor."""
    Q, QD, V, A = _states(rng, ur5.n, 3)
    other = pickle.loads(pickle.dumps(ur5))
    assert_close(other.regressor(Q, QD, V, A), ur5.regressor(Q, QD, V, A), tol=0)


def test_physical_issues(ur5, arm3):
    """UR5: none; the 3R's Table 1 violates the triangle inequality on links 2 and 3; a negative
    mass and a non-PD inertia are reported per body."""
    assert ur5.physical_issues() == []
    assert [i.split(":")[0] for i in arm3.physical_issues()] == ["body 2 (joint2)", "body 3 (joint3)"]
    std = ur5.standard_parameters().copy()
    std[10] = -1.0
    std[24] = -5.0  # Ixx of body 3
    issues = ur5.with_standard_parameters(std, "bad").physical_issues()
    assert "mass -1 kg <= 0" in issues[0] and "not positive definite" in issues[1]


TOY = """<?xml version="1.0"?>
<robot name="toy">
  <link name="base"/>
  <joint name="spin" type="continuous"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="l1"><inertial><origin xyz="0.1 0.02 0.05" rpy="0.1 0.2 0.3"/><mass value="2"/>
    <inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.03" iyz="0.002" izz="0.04"/></inertial></link>
  <joint name="slide" type="prismatic"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.2 0 0.1" rpy="0.3 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.5" effort="100" velocity="1"/></joint>
  <link name="l2"><inertial><origin xyz="0.05 0.01 -0.02"/><mass value="1.5"/>
    <inertia ixx="0.01" ixy="0" ixz="0.001" iyy="0.02" iyz="0" izz="0.015"/></inertial></link>
  <joint name="tilt" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.1 0.1 0" rpy="0 0.4 0"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-2" upper="2" effort="10" velocity="1"/></joint>
  <link name="l3"><inertial><origin xyz="0.15 0 0.02"/><mass value="0.8"/>
    <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.006"/></inertial></link>
  <joint name="tool_joint" type="fixed"><parent link="l3"/><child link="tool"/><origin xyz="0.3 0 0"/></joint>
  <link name="tool"><inertial><mass value="0.2"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
</robot>
"""


def test_continuous_joint_becomes_revolute(tmp_path, rng):
    """A continuous joint is loaded as revolute (nq = nv = n = 3, limits +-1000 rad) with the same
    dynamics as Pinocchio's (cos, sin) joint: rnea(q) == rnea_continuous((cos q1, sin q1, q2, q3));
    prismatic, unaligned revolute and fixed joints work; verify_model passes."""
    path = tmp_path / "toy.urdf"
    path.write_text(TOY)
    robot = PinocchioRobot.from_urdf(path)
    assert (robot.n, robot.model.nq, robot.continuous, robot.robot_name) == (3, 3, ("spin",), "toy")
    assert robot.joint_limits[0][0] == -1000.0 and robot.joint_limits[1][1] == 0.5
    original = pin.buildModelFromXML(TOY)
    assert (original.nq, original.nv) == (4, 3)
    d, d0 = robot.model.createData(), original.createData()
    for q, qd, qdd, _ in zip(*_states(rng, 3, 20)):
        qc = np.concatenate([[np.cos(q[0]), np.sin(q[0])], q[1:]])
        assert_close(pin.rnea(robot.model, d, q, qd, qdd), pin.rnea(original, d0, qc, qd, qdd))
    assert robot.kernel is not None
    assert verify_model(robot, samples=20, seed=1).passed


def test_helical_joint_uses_the_pinocchio_path(rng):
    """A 1-DoF joint the kernel does not handle (helical) falls back to the reference path, which
    still satisfies the Slotine--Li identity."""
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "rz")
    model.appendBodyToJoint(j1, pin.Inertia(2.0, np.array([0.3, 0.1, 0.0]), np.diag([0.1, 0.2, 0.3])),
                            pin.SE3.Identity())
    j2 = model.addJoint(j1, pin.JointModelHX(0.05), pin.SE3(np.eye(3), np.array([0.4, 0.0, 0.2])), "hx")
    model.appendBodyToJoint(j2, pin.Inertia(1.0, np.array([0.1, 0.2, 0.05]), np.diag([0.02, 0.03, 0.04])),
                            pin.SE3.Identity())
    robot = PinocchioRobot(model, "helix")
    assert robot.kernel is None
    Q, QD, V, A = _states(rng, 2, 10)
    ref = np.array([_pinocchio_sl(model, *s) for s in zip(Q, QD, V, A)])
    assert_close(robot.regressor(Q, QD, V, A) @ robot.theta, ref)


def _urdf_error(tmp_path, text, match, **kw):
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    with pytest.raises(UrdfError, match=match) as info:
        PinocchioRobot.from_urdf(path, **kw)
    assert "\n" not in str(info.value)


def test_refused_urdfs(tmp_path):
    """One-line UrdfError for: a missing file, malformed XML, a non-robot root, a non-numeric
    attribute (urdfdom only warns and drops the element), no masses, a joint
    that is not 1-DoF, a joint moving nothing (singular M), an unlocked mimic joint, an unknown
    locked joint."""
    with pytest.raises(UrdfError, match="not found"):
        PinocchioRobot.from_urdf(tmp_path / "none.urdf")
    _urdf_error(tmp_path, "<robot><link", "malformed URDF")
    _urdf_error(tmp_path, "<model/>", "expected <robot>")
    _urdf_error(tmp_path, TOY.replace('ixx="0.02"', 'ixx="np.float64(0.02)"'), "ixx=.* is not a number")
    _urdf_error(tmp_path, TOY.replace('xyz="0.2 0 0.1"', 'xyz="0.2 0"'), "is not 3 numbers")
    massless = TOY.replace('<mass value="2"/>', '<mass value="0"/>').replace('<mass value="1.5"/>', '<mass value="0"/>')
    massless = massless.replace('<mass value="0.8"/>', '<mass value="0"/>').replace('<mass value="0.2"/>', '<mass value="0"/>')
    _urdf_error(tmp_path, massless, "no inertias")
    _urdf_error(tmp_path, TOY.replace('type="prismatic"', 'type="floating"'), "not 1-DoF")
    last_moves_nothing = TOY.replace('<mass value="0.8"/>', '<mass value="0"/>').replace(
        'ixx="0.004" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.006"', 'ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"')
    last_moves_nothing = last_moves_nothing.replace('<mass value="0.2"/>', '<mass value="0"/>').replace(
        'ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"', 'ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"')
    _urdf_error(tmp_path, last_moves_nothing, "singular")
    panda = (example_robot_data_dir() / "panda_description/urdf/panda.urdf").read_text()
    _urdf_error(tmp_path, panda, "mimics 'panda_finger_joint1'", lock={"panda_finger_joint1": 0.0})
    _urdf_error(tmp_path, TOY, "unknown joint", lock={"elbow": 0.0})


def test_bench_regressor_reports_times(ur5, monkeypatch):
    """bench_regressor times what it says (its ratio is the quotient of the two times it prints) and
    the regressor it timed is right (Y(q, qd, qd, a) theta == pin.rnea to 1e-12 relative, the
    identity, at its own states). A wrong regressor (theta off by 1 % in one column) is caught by the
    same number: the benchmark never reports the speed of a wrong result."""
    out = bench_regressor(ur5, n=50, seed=0, repeat=1)
    assert out["robot"] == "ur5" and out["states"] == 50 and out["p"] == 36
    assert out["ratio"] == pytest.approx(out["regressor_us"] / out["rnea_us"], rel=1e-12)
    assert all(out[k] > 0 for k in ("regressor_us", "regressor_single_us", "rnea_us", "pinocchio_path_us"))
    assert out["max_rel_error_vs_rnea"] < 1e-12
    real = type(ur5).regressor

    def wrong(self, q, qd, v, a):
        Y = real(self, q, qd, v, a).copy()
        Y[..., 3] *= 1.01
        return Y

    monkeypatch.setattr(type(ur5), "regressor", wrong)
    assert bench_regressor(ur5, n=20, seed=0, repeat=1)["max_rel_error_vs_rnea"] > 1e-6


@pytest.mark.parametrize("law", ["fbl", "pd", "robust-rho0"])
def test_generic_3r_gives_the_closed_form_controller_torques(law, rng):
    """On the paper's 3R, the same law on the generic robot (36 -> 15 base parameters, its own theta)
    and on the closed form (the paper's theta) gives the same torque to 1e-9 relative: u = Y theta + w
    does not depend on the parametrization when the law's model is the plant's (for the robust law,
    with rho = 0: its robust term lives in coefficient space and is basis dependent)."""
    from rc3r.controllers import make_law
    from rc3r.robots.pinocchio import PinocchioRobot
    from rc3r.robots.rr3 import RR3
    from rc3r.robots.rr3.urdf import REPO_URDF

    closed, generic = RR3.from_urdf(REPO_URDF), PinocchioRobot.from_urdf(REPO_URDF)
    name, extra = ("robust", {"rho": 0.0}) if law == "robust-rho0" else (law, {})
    a, b = make_law(name, closed.theta, **extra), make_law(name, generic.theta, **extra)
    for _ in range(20):
        q, qd = rng.uniform(-3, 3, 3), rng.uniform(-3, 3, 3)
        ref = rng.uniform(-3, 3, (3, 3))
        ua, _, _ = a.torque(closed, q, qd, ref)
        ub, _, _ = b.torque(generic, q, qd, ref)
        assert np.max(np.abs(ua - ub)) <= 1e-9 * max(1.0, np.max(np.abs(ua)))


def test_identifiability_of_hand_made_regressors():
    """identifiability: singular values by hand. Y = diag(2, 1e-6) stacked twice has s = (2 sqrt 2,
    1e-6 sqrt 2), ratio 5e-7 < 1e-4: one warning naming only the second coefficient (its right singular
    vector is e_2); diag(2, 0.5) has ratio 0.25: no warning."""
    from rc3r.robots.base_parameters import IDENTIFIABILITY_RTOL, identifiability

    ratio, warn = identifiability(np.vstack([np.diag([2.0, 1e-6])] * 2), ("a", "b"))
    assert ratio == pytest.approx(5e-7, rel=1e-12) and ratio < IDENTIFIABILITY_RTOL
    assert len(warn) == 1 and "1 base-parameter direction(s)" in warn[0] and "(mostly b)" in warn[0]
    assert "s2/s1 = 5.0e-07" in warn[0]
    ratio, warn = identifiability(np.diag([2.0, 0.5]), ("a", "b"))
    assert ratio == pytest.approx(0.25, rel=1e-12) and warn == []


def test_default_trajectory_keeps_half_the_urdf_velocity_limit(ur5):
    """The Kinova of example-robot-data limits its joints to 0.628 and 0.838 rad/s: its default sines
    (omega = 1 rad/s) get A_i = 0.5 x v_max,i, so max_t |qd_d,i| = 0.5 v_max,i (sampled every 1 ms over one
    period: equal to 1e-6 relative); the UR5's limits (3.15 rad/s) leave its 0.5 rad amplitude as it was
    (peak speed 0.5 rad/s: A omega)."""
    from rc3r.robots.pinocchio import VELOCITY_SHARE

    kinova = PinocchioRobot.from_urdf(example_robot_data_dir() / "kinova_description/robots/kinova.urdf")
    vmax = np.asarray(kinova.model.velocityLimit, float)
    assert vmax.max() < 1.0
    t = np.arange(0.0, 2 * np.pi, 1e-3)
    for arm, expect in ((kinova, VELOCITY_SHARE * vmax), (ur5, np.full(ur5.n, 0.5))):
        traj = arm.default_trajectory()
        peak = np.abs(np.array([np.asarray(traj.evaluate(s)[1]).ravel() for s in t])).max(axis=0)
        np.testing.assert_allclose(peak, expect, rtol=1e-6)


def test_a_joint_named_like_a_link_can_be_locked(tmp_path):
    """Issue 33 item 1. The SO-100 of example-robot-data has a link and a joint both named
    ``gripper``; locking that joint (Pinocchio's buildReducedModel looks frames up by name) gives
    the same arm as the same URDF with the joint renamed and locked: equal standard parameters,
    joint names and frame names (the link keeps its URDF name, no renaming left behind)."""
    text = (example_robot_data_dir() / "so_arm_description/urdf/so100.urdf").read_text()
    renamed = tmp_path / "renamed.urdf"
    renamed.write_text(text.replace('<joint name="gripper"', '<joint name="gripper_joint"'))
    assert renamed.read_text() != text
    robot = PinocchioRobot.from_urdf(example_robot_data_dir() / "so_arm_description/urdf/so100.urdf",
                                     lock={"gripper": 0.3})
    ref = PinocchioRobot.from_urdf(renamed, lock={"gripper_joint": 0.3})
    assert robot.n == ref.n == 5 and robot.joint_names == ref.joint_names
    np.testing.assert_array_equal(robot.standard_parameters(), ref.standard_parameters())
    names = [f.name for f in robot.model.frames]
    assert names == [f.name if f.name != "gripper_joint" else "gripper" for f in ref.model.frames]
    assert names.count("gripper") == 2


def test_unlocked_mimic_joints_are_refused_with_the_options_that_lock_them(tmp_path):
    """Issue 33 item 2: every unlocked <mimic> joint is named in one line with the command-line
    options that lock it (``--lock J=0``, not Python syntax), and those options are enough."""
    panda = example_robot_data_dir() / "panda_description/urdf/panda.urdf"
    text = panda.read_text().replace('<joint name="panda_finger_joint1" type="prismatic">',
                                     '<joint name="panda_finger_joint1" type="prismatic">'
                                     '<mimic joint="panda_joint7" multiplier="0.0"/>')
    two = tmp_path / "two_mimics.urdf"
    two.write_text(text)
    with pytest.raises(UrdfError) as info:
        PinocchioRobot.from_urdf(two)
    msg = str(info.value)
    assert "\n" not in msg and "lock=" not in msg
    assert msg.endswith("lock them with --lock panda_finger_joint1=0 --lock panda_finger_joint2=0"), msg
    with pytest.raises(UrdfError, match=r"mimics 'panda_finger_joint1': lock it with --lock panda_finger_joint2=0$"):
        PinocchioRobot.from_urdf(panda)
