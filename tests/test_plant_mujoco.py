"""MuJoCo as a second plant engine (``rc3r.plants.mujoco``) and the physically consistent 3R.

Independent sources: Pinocchio (``crba``, ``rnea``, ``aba``, ``buildReducedModel``) for the
dynamics; the paper's Table 2 typed in here for theta; MuJoCo's own URDF importer for what it
refuses. Errors are measured as in ``rc3r verify-model``: ``max|x - ref| / max(1, max|ref|)``.
"""
from __future__ import annotations

import importlib.util
import pickle
from pathlib import Path

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

import pinocchio as pin  # noqa: E402

from rc3r.errors import ParameterError, UrdfError  # noqa: E402
from rc3r.plants.mujoco import MujocoRigidBody  # noqa: E402
from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir  # noqa: E402
from rc3r.robots.rr3.params import load_params, theta  # noqa: E402
from rc3r.robots.rr3.regressor import regressor  # noqa: E402
from rc3r.robots.rr3.robot import RR3  # noqa: E402
from rc3r.robots.rr3.urdf import load_arm  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
CONSISTENT_TOML = REPO / "src" / "rc3r" / "robots" / "rr3" / "data" / "rr3_consistent.toml"
CONSISTENT_URDF = REPO / "urdf" / "rr3_consistent.urdf"
TABLE1_URDF = REPO / "urdf" / "rr3.urdf"
#: Table 2 of the paper, typed from the paper (not computed by rc3r).
TABLE2 = np.array([33, -11.6, 3.4, -14, -4.4, -2, 12, 1.4, -3.8, -0.2, -2.2, 29.2, 15.3, 15, 3], float)
#: Dynamics tolerance: MuJoCo and Pinocchio are different float64 algorithms (CRB/RNE with
#: MuJoCo's diagonalised body inertias vs Pinocchio's spatial algebra); with MuJoCo 4 they agree
#: to ~1e-13 relative (measured 2e-15 .. 5e-13): 1e-9 as in verify-model. MuJoCo 3.x stops its
#: 3x3 eigensolver (body inertia -> principal axes) at ~1e-7 relative: measured 1.4e-7 kg m^2 on
#: the 3R's link 2 and 4e-7 relative on the dynamics (3.1.6, 3.2.0, 3.3.0), hence 1e-6 there.
TOL = 1e-9 if int(mujoco.__version__.split(".")[0]) >= 4 else 1e-6
LOCK_PANDA = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}


def _rel(x, ref) -> float:
    return float(np.max(np.abs(np.asarray(x) - ref)) / max(1.0, float(np.max(np.abs(ref)))))


def _states(n, count, seed, qmax=np.pi):
    rng = np.random.default_rng(seed)
    return [(rng.uniform(-qmax, qmax, n), rng.uniform(-5, 5, n), rng.uniform(-5, 5, n)) for _ in range(count)]


def _full(M):
    return np.triu(M) + np.triu(M, 1).T


def _erd(rel: str) -> Path:
    return example_robot_data_dir() / rel


# ---- the physically consistent 3R --------------------------------------------------------
def test_consistent_parameters_have_table2_theta_from_the_toml_and_from_the_urdf():
    """theta of the shipped parameter file, and of its URDF as read back, is Table 2 to 1e-12."""
    assert np.max(np.abs(theta(load_params(CONSISTENT_TOML)) - TABLE2)) <= 1e-12
    assert np.max(np.abs(theta(load_arm(CONSISTENT_URDF).params) - TABLE2)) <= 1e-12


def test_consistent_urdf_has_the_dynamics_of_table1_in_pinocchio():
    """Same theta, so the same dynamics: Pinocchio's rnea and crba on the consistent URDF equal
    those on Table 1's URDF, and the closed-form Y(q, qd, qdd) Table2 equals its rnea."""
    mc, mt = load_arm(CONSISTENT_URDF).model, load_arm(TABLE1_URDF).model
    dc, dt = mc.createData(), mt.createData()
    err_rnea = err_crba = err_y = 0.0
    for q, qd, qdd in _states(3, 200, seed=3):
        tau = pin.rnea(mc, dc, q, qd, qdd)
        err_rnea = max(err_rnea, _rel(tau, pin.rnea(mt, dt, q, qd, qdd)))
        err_crba = max(err_crba, _rel(_full(pin.crba(mc, dc, q)), _full(pin.crba(mt, dt, q))))
        err_y = max(err_y, _rel(regressor(q, qd, qdd, l2=1.0, g0=9.81) @ TABLE2, tau))
    assert max(err_rnea, err_crba, err_y) <= 1e-12, (err_rnea, err_crba, err_y)


def test_the_links_differ_from_table1_so_the_equality_above_is_not_trivial():
    """Links 2 and 3 do differ (up to 0.38 kg m^2 in Ixz), masses and lengths do not."""
    std_c, std_t = load_params(CONSISTENT_TOML).to_vector(), RR3.nominal().standard_parameters()
    diff = np.abs(std_c - std_t).reshape(3, 10)
    assert diff[0].max() == 0 and diff[:, 0].max() == 0
    assert diff[1].max() > 0.2 and diff[2].max() > 0.2
    assert load_params(CONSISTENT_TOML).lengths == RR3.nominal().params.lengths


def test_consistent_arm_is_physically_consistent_with_margin():
    """physical_issues() is empty (it is not for Table 1), and every link's principal moments
    satisfy the triangle inequality with slack >= 0.05 kg m^2 (twice the 0.025 target)."""
    robot = RR3.from_params_file(CONSISTENT_TOML)
    assert robot.physical_issues() == []
    assert len(RR3.nominal().physical_issues()) == 2
    for link in robot.params.links:
        assert link.mass > 0
        a, b, c = np.linalg.eigvalsh(link.inertia_matrix)
        assert a > 0 and a + b - c >= 0.05, (a, b, c)


def test_mujoco_itself_refuses_table1_and_compiles_the_consistent_urdf():
    """MuJoCo's own URDF importer (no rc3r edits) refuses Table 1 for link 2's triangle inequality."""
    with pytest.raises(ValueError, match=r"A \+ B >= C") as info:
        mujoco.MjModel.from_xml_path(str(TABLE1_URDF))
    assert "link2" in str(info.value)
    assert mujoco.MjModel.from_xml_path(str(CONSISTENT_URDF)).nv == 3


def test_plant_refuses_table1_in_one_line_and_loads_the_consistent_arm():
    with pytest.raises(UrdfError) as info:
        MujocoRigidBody.from_urdf(TABLE1_URDF)
    msg = str(info.value)
    assert "\n" not in msg and "A + B >= C" in msg and "link2" in msg and str(TABLE1_URDF) in msg
    plant = MujocoRigidBody.from_urdf(CONSISTENT_URDF)
    assert plant.n == 3 and plant.joint_names == ("joint1", "joint2", "joint3")


def _benchmark_module():
    spec = importlib.util.spec_from_file_location("consistent_3r", REPO / "benchmarks" / "consistent_3r.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_search_reproduces_the_shipped_parameter_file():
    """benchmarks/consistent_3r.py with seed 0 writes the committed TOML byte for byte; seed 1
    finds the same rounded arm (the optimum does not depend on the starts)."""
    bench = _benchmark_module()
    params = load_params(CONSISTENT_TOML)
    res = bench.search(seed=0)
    assert bench.to_toml(res["std"], params.lengths, params.g0, res) == CONSISTENT_TOML.read_text()
    assert res["t_max"] == pytest.approx(0.05, abs=1e-9)  # the xy-block bound of links 2 and 3
    assert res["sigma_min"].min() >= res["target"] == pytest.approx(0.025, abs=1e-9)
    assert np.array_equal(bench.search(seed=1, starts=3)["std"], res["std"])


# ---- MuJoCo against Pinocchio ---------------------------------------------------------------
def _pair(name):
    """(MuJoCo plant, Pinocchio model of the same URDF) for each robot of the comparison."""
    if name == "ur5":
        path = _erd("ur_description/urdf/ur5_robot.urdf")
        return MujocoRigidBody.from_urdf(path), PinocchioRobot.from_urdf(path).model
    if name == "panda":
        path = _erd("panda_description/urdf/panda.urdf")
        return MujocoRigidBody.from_urdf(path, locked=LOCK_PANDA), PinocchioRobot.named("panda").model
    return MujocoRigidBody.from_urdf(CONSISTENT_URDF), load_arm(CONSISTENT_URDF).model


@pytest.mark.parametrize("name", ["ur5", "rr3_consistent", "panda"])
def test_mass_matrix_bias_and_forward_dynamics_equal_pinocchio(name):
    """mj_fullM = crba, qfrc_bias = rnea(q, qd, 0), qacc = aba at 50 seeded states, 1e-9 relative.
    The Panda has damping 0.003 and limits of +-1.76 rad in its URDF: q in [-pi, pi] and aba
    without damping check that both are off."""
    plant, model = _pair(name)
    data = model.createData()
    assert plant.joint_names == tuple(model.names[1:])
    err = {"M": 0.0, "bias": 0.0, "qdd": 0.0}
    for q, qd, u in _states(plant.n, 50, seed=11):
        err["M"] = max(err["M"], _rel(plant.mass_matrix(q), _full(pin.crba(model, data, q))))
        err["bias"] = max(err["bias"], _rel(plant.bias_forces(q, qd), pin.rnea(model, data, q, qd, 0 * q)))
        err["qdd"] = max(err["qdd"], _rel(plant.forward_dynamics(q, qd, 20 * u), pin.aba(model, data, q, qd, 20 * u)))
    assert max(err.values()) <= TOL, err


def test_locked_joints_equal_pinocchio_reduced_model():
    """UR5 with the elbow locked at -1.2 rad and wrist 3 at 0.7 rad (the value folded into the
    joint origin) equals pinocchio.buildReducedModel at the same values."""
    path = _erd("ur_description/urdf/ur5_robot.urdf")
    lock = {"elbow_joint": -1.2, "wrist_3_joint": 0.7}
    plant = MujocoRigidBody.from_urdf(path, locked=lock)
    full = pin.buildModelFromUrdf(str(path))
    q_ref = pin.neutral(full)
    ids = [full.getJointId(j) for j in lock]
    for jid, value in zip(ids, lock.values()):
        q_ref[full.idx_qs[jid]] = value
    model = pin.buildReducedModel(full, ids, q_ref)
    data = model.createData()
    assert plant.joint_names == tuple(model.names[1:]) and plant.n == 4
    err = 0.0
    for q, qd, u in _states(4, 30, seed=5):
        err = max(err, _rel(plant.mass_matrix(q), _full(pin.crba(model, data, q))),
                  _rel(plant.bias_forces(q, qd), pin.rnea(model, data, q, qd, 0 * q)))
    assert err <= TOL
    unlocked = MujocoRigidBody.from_urdf(path, locked={"elbow_joint": 0.0, "wrist_3_joint": 0.0})
    q = _states(4, 1, seed=5)[0][0]
    assert _rel(unlocked.bias_forces(q, 0 * q), plant.bias_forces(q, 0 * q)) > 1e-3  # the value matters


def test_a_rotated_inertial_frame_is_read_right(tmp_path):
    """A link whose <inertial> has rpy = (0.3, -0.5, 1.1) and a full inertia: M equals Pinocchio's.
    MuJoCo < 4 drops that rotation (its issue 3559: 0.25 kg m^2 off); the plant hands MuJoCo the
    inertia rotated into the link frame, which every version reads right."""
    urdf = tmp_path / "rotated.urdf"
    urdf.write_text("""<robot name="rot"><link name="base"/>
      <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0 0 0" rpy="0 0 0"/>
        <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <link name="a"><inertial><origin xyz="0.3 0.1 0" rpy="0 0 0"/><mass value="2"/>
        <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.5 0 0" rpy="1.5707963267948966 0 0"/>
        <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <link name="b"><inertial><origin xyz="0.2 -0.1 0.05" rpy="0.3 -0.5 1.1"/><mass value="1.5"/>
        <inertia ixx="0.4" iyy="0.7" izz="0.9" ixy="0.05" ixz="-0.03" iyz="0.02"/></inertial></link></robot>""")
    plant = MujocoRigidBody.from_urdf(urdf)
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    err = max(_rel(plant.mass_matrix(q), _full(pin.crba(model, data, q))) for q, _, _ in _states(2, 20, seed=1))
    assert err <= TOL


def _rk4_pinocchio(model, q, qd, u, T, steps):
    data, h = model.createData(), T / steps

    def f(x):
        return np.concatenate([x[model.nv:], pin.aba(model, data, x[:model.nv], x[model.nv:], u)])

    x = np.concatenate([q, qd])
    for _ in range(steps):
        k1 = f(x)
        k2 = f(x + h / 2 * k1)
        k3 = f(x + h / 2 * k2)
        k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x[:model.nv], x[model.nv:]


@pytest.mark.parametrize("name", ["rr3_consistent", "ur5"])
def test_advance_10ms_equals_rk4_of_pinocchio_aba(name):
    """advance over 10 ms (100 RK4 steps of 0.1 ms) under a constant torque equals RK4 of
    Pinocchio's ABA at 1e-5 s steps to 1e-8 rad. RK4's global error is O(h^4): at these
    accelerations (up to ~1e2 rad/s^2) both are ~1e-12 from the exact flow; the state moves
    by more than 1e-3 rad, so the comparison is not of two resting arms."""
    plant, model = _pair(name)
    q, qd, u = _states(plant.n, 1, seed=7)[0]
    u = 10 * u
    q1, qd1 = plant.advance(q, qd, u, 10e-3)
    q_ref, qd_ref = _rk4_pinocchio(model, q, qd, u, 10e-3, 1000)
    assert np.max(np.abs(q1 - q_ref)) <= 1e-8
    assert np.max(np.abs(qd1 - qd_ref)) <= 1e-6  # rad/s: qdd ~ 1e2 times the same relative error
    assert np.max(np.abs(q1 - q)) > 1e-3


def test_advance_steps_divide_the_period_and_stay_below_max_step():
    plant = MujocoRigidBody.from_urdf(CONSISTENT_URDF)
    assert plant.steps(1e-3) == (10, pytest.approx(1e-4, rel=1e-15))
    assert plant.steps(2.5e-4) == (3, pytest.approx(2.5e-4 / 3, rel=1e-15))
    assert plant.steps(1e-5) == (1, 1e-5)
    for T in (0.0, -1e-3, float("nan"), float("inf")):
        with pytest.raises(ParameterError, match="positive"):
            plant.steps(T)


def test_advance_over_two_halves_equals_one_period_with_the_same_steps():
    """A ZOH period split in two advances of 0.5 ms (5 steps each) is the same RK4 sequence as
    one advance of 1 ms (10 steps): equal to rounding."""
    plant = MujocoRigidBody.from_urdf(CONSISTENT_URDF)
    q, qd, u = _states(3, 1, seed=2)[0]
    qa, qda = plant.advance(*plant.advance(q, qd, u, 5e-4), u, 5e-4)
    qb, qdb = plant.advance(q, qd, u, 1e-3)
    assert np.max(np.abs(qa - qb)) <= 1e-13 and np.max(np.abs(qda - qdb)) <= 1e-11


@pytest.mark.parametrize("u, q0", [(1e300, 0.0), (1e12, 0.0), (0.0, float("nan"))])
def test_advance_raises_instead_of_mujoco_resetting_the_state(u, q0, tmp_path, monkeypatch):
    """A huge torque (or a NaN start) makes MuJoCo's state checks fire: by default it would reset
    the state to qpos0 and go on, and write MUJOCO_LOG.TXT into the working directory."""
    monkeypatch.chdir(tmp_path)
    plant = MujocoRigidBody.from_urdf(CONSISTENT_URDF)
    with pytest.raises(FloatingPointError, match="non-finite or huge"):
        plant.advance(np.full(3, q0), np.zeros(3), np.full(3, u), 1e-3)
    if hasattr(mujoco.mjtDisableBit, "mjDSBL_AUTORESET"):
        assert list(tmp_path.iterdir()) == []
    q, qd = plant.advance(np.zeros(3), np.zeros(3), np.zeros(3), 1e-3)  # usable again afterwards
    assert np.all(np.isfinite(q)) and q[1] != 0.0  # gravity moves joint 2


def test_joint_order_can_be_chosen():
    """joint_names permutes q, qd, u and M consistently."""
    a = MujocoRigidBody.from_urdf(CONSISTENT_URDF)
    b = MujocoRigidBody.from_urdf(CONSISTENT_URDF, joint_names=("joint3", "joint1", "joint2"))
    perm = [2, 0, 1]
    q, qd, u = _states(3, 1, seed=4)[0]
    assert np.allclose(b.mass_matrix(q[perm]), a.mass_matrix(q)[np.ix_(perm, perm)], rtol=0, atol=1e-14)
    assert np.allclose(b.forward_dynamics(q[perm], qd[perm], u[perm]), a.forward_dynamics(q, qd, u)[perm],
                       rtol=0, atol=1e-12)
    with pytest.raises(UrdfError, match="each of the 3 joints once"):
        MujocoRigidBody.from_urdf(CONSISTENT_URDF, joint_names=("joint1", "joint1", "joint2"))


def test_plant_pickles():
    """A plant survives pickling (process pools): same model settings, same results."""
    plant = _pair("panda")[0]
    copy = pickle.loads(pickle.dumps(plant))
    q, qd, u = _states(7, 1, seed=9)[0]
    assert np.array_equal(copy.forward_dynamics(q, qd, u), plant.forward_dynamics(q, qd, u))
    assert np.array_equal(copy.advance(q, qd, u, 1e-3)[0], plant.advance(q, qd, u, 1e-3)[0])


@pytest.mark.parametrize("kwargs, match", [
    ({"path": "/nonexistent/robot.urdf"}, "cannot read URDF"),
    ({"path": "PANDA"}, "mimics 'panda_finger_joint1': lock it"),
    ({"path": "PANDA", "locked": {"panda_finger_joint1": 0.0, "nope": 1.0}}, "unknown joint"),
    ({"path": "PANDA", "locked": {**LOCK_PANDA, "panda_joint8": 0.0}}, "not 1-DoF"),
    ({"path": "BAD_XML"}, "malformed URDF"),
])
def test_bad_urdfs_are_one_line_urdf_errors(kwargs, match, tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'></robot>")
    path = {"PANDA": _erd("panda_description/urdf/panda.urdf"), "BAD_XML": bad}.get(kwargs["path"], kwargs["path"])
    with pytest.raises(UrdfError, match=match) as info:
        MujocoRigidBody.from_urdf(path, locked=kwargs.get("locked"))
    assert "\n" not in str(info.value)


def test_missing_mujoco_is_a_one_line_config_error(monkeypatch):
    import sys

    from rc3r.errors import ConfigError

    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco raises ImportError
    with pytest.raises(ConfigError, match=r"MuJoCo is not installed: pip install 'rc3r\[mujoco\]'"):
        MujocoRigidBody.from_urdf(CONSISTENT_URDF)


def test_wrong_shapes_are_parameter_errors():
    plant = MujocoRigidBody.from_urdf(CONSISTENT_URDF)
    with pytest.raises(ParameterError, match=r"q must have shape \(3,\)"):
        plant.forward_dynamics(np.zeros(2), np.zeros(3), np.zeros(3))
    with pytest.raises(ParameterError, match=r"u must have shape \(3,\)"):
        plant.advance(np.zeros(3), np.zeros(3), np.zeros((3, 1)), 1e-3)


def test_gravity_is_minus_g0_along_base_z():
    """g0 = 3.7: the bias at rest equals Pinocchio's gravity torque with gravity (0, 0, -3.7)."""
    path = _erd("ur_description/urdf/ur5_robot.urdf")
    plant = MujocoRigidBody.from_urdf(path, g0=3.7)
    model = PinocchioRobot.from_urdf(path, gravity=(0, 0, -3.7)).model
    data = model.createData()
    q = _states(6, 1, seed=8)[0][0]
    g = pin.computeGeneralizedGravity(model, data, q)
    assert _rel(plant.bias_forces(q, 0 * q), g) <= TOL and np.max(np.abs(g)) > 1.0
