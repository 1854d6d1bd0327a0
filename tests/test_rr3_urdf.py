"""rc3r.robots.rr3.urdf: the committed URDF, round trips URDF <-> ArmParams, and refusals of other robots."""
from __future__ import annotations

import glob
import sys
from pathlib import Path

import numpy as np
import pytest

from rc3r.cli import main
from rc3r.errors import UrdfError
from rc3r.robots.rr3.params import ArmParams, LinkParams
from rc3r.robots.rr3.urdf import REPO_URDF, load_arm, make_urdf, write_urdf

#: Parameters survive URDF text (repr of float64, exact) and Pinocchio's
#: lever/inertia conversion plus our inverse rotation by R_i (a handful of
#: operations on O(1..10) numbers): rounding ~1e-15, so 1e-12 is a safe bound.
ROUND_TRIP_TOL = 1e-12


def random_physical_arm(rng, name="rand") -> ArmParams:
    """A physically consistent arm: lengths in [0.2, 2] m, masses in [0.1, 20] kg,
    CoM in [-1, 1]^3 m, inertia R diag(I) R^T with principal moments
    I = (dy + dz, dx + dz, dx + dy), d in [0.01, 1] (triangle inequality holds
    strictly) and a random rotation R."""
    links = []
    for _ in range(3):
        d = rng.uniform(0.01, 1.0, 3)
        moments = np.array([d[1] + d[2], d[0] + d[2], d[0] + d[1]])
        R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        inertia = R @ np.diag(moments) @ R.T
        links.append(LinkParams(
            rng.uniform(0.2, 2.0), rng.uniform(0.1, 20.0), rng.uniform(-1, 1, 3),
            (inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]),
        ))
    return ArmParams(tuple(links), name=name)


def _assert_params_close(a: ArmParams, b: ArmParams, tol=ROUND_TRIP_TOL):
    np.testing.assert_allclose(a.to_vector(), b.to_vector(), rtol=0, atol=tol)
    np.testing.assert_allclose(a.lengths, b.lengths, rtol=0, atol=tol)
    assert a.g0 == b.g0


def _ur5_path():
    hits = glob.glob(f"{sys.prefix}/**/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf",
                     recursive=True)
    return hits[0] if hits else None


# ---- the committed file ------------------------------------------------------------------


def test_committed_urdf_is_make_urdf_of_table1_byte_for_byte(table1):
    """urdf/rr3.urdf == make_urdf(table1()) exactly (regenerate with `rc3r make-urdf`)."""
    assert REPO_URDF.read_text() == make_urdf(table1)


def test_make_urdf_is_deterministic(table1):
    assert make_urdf(table1) == make_urdf(table1)


def test_committed_urdf_loads_in_pinocchio_with_nq_3():
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(REPO_URDF))
    assert (model.nq, model.nv, model.njoints) == (3, 3, 4)


def test_committed_urdf_loads_in_yourdfpy():
    import yourdfpy

    robot = yourdfpy.URDF.load(str(REPO_URDF), build_scene_graph=False, load_meshes=False)
    assert [j.name for j in robot.robot.joints] == ["joint1", "joint2", "joint3", "tool_joint"]
    assert [j.type for j in robot.robot.joints] == ["revolute"] * 3 + ["fixed"]


def test_load_arm_params_round_trip_table1(arm, table1):
    """load_arm(rr3.urdf).params == Table 1 (CoM and inertia back in DH frame i)."""
    _assert_params_close(arm.params, table1)
    assert arm.model.nq == 3
    np.testing.assert_array_equal(arm.model.gravity.linear, (0, 0, -9.81))


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
def test_load_arm_params_round_trip_random_physical_arms(tmp_path, seed):
    """ArmParams -> URDF -> load_arm -> ArmParams is the identity for random physical arms."""
    p = random_physical_arm(np.random.default_rng(seed))
    path = write_urdf(p, tmp_path / "r.urdf")
    _assert_params_close(load_arm(path).params, p)


def test_load_arm_g0_sets_model_gravity(tmp_path, table1):
    arm = load_arm(REPO_URDF, g0=3.5)
    np.testing.assert_array_equal(arm.model.gravity.linear, (0, 0, -3.5))
    assert arm.params.g0 == 3.5


def test_continuous_joints_are_accepted_with_nq_3(tmp_path, table1):
    """`continuous` joints (Pinocchio: nq = 2 each) are loaded as revolute: nq == 3, same params."""
    text = make_urdf(table1).replace('type="revolute"', 'type="continuous"')
    assert text.count('type="continuous"') == 3
    path = tmp_path / "cont.urdf"
    path.write_text(text)
    arm = load_arm(path)
    assert arm.model.nq == 3
    _assert_params_close(arm.params, table1)


# ---- refusals -----------------------------------------------------------------------------


def _write(tmp_path, text, name="bad.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_refuses_missing_file(tmp_path):
    with pytest.raises(UrdfError, match="not found"):
        load_arm(tmp_path / "missing.urdf")


def test_refuses_malformed_xml(tmp_path, table1):
    with pytest.raises(UrdfError, match="malformed URDF"):
        load_arm(_write(tmp_path, make_urdf(table1)[:200]))


def test_refuses_non_robot_root(tmp_path):
    with pytest.raises(UrdfError, match="root element is <model>, not <robot>"):
        load_arm(_write(tmp_path, '<?xml version="1.0"?>\n<model name="x"/>\n'))


def test_refuses_ur5_with_six_moving_joints():
    path = _ur5_path()
    if path is None:
        pytest.skip("example-robot-data UR5 URDF not installed")
    with pytest.raises(UrdfError, match="6 moving joints"):
        load_arm(path)


def test_refuses_prismatic_joint(tmp_path, table1):
    text = make_urdf(table1).replace('name="joint2" type="revolute"', 'name="joint2" type="prismatic"')
    with pytest.raises(UrdfError, match="'joint2' is prismatic"):
        load_arm(_write(tmp_path, text))


def test_refuses_joint_axis_along_x(tmp_path, table1):
    text = make_urdf(table1).replace('<axis xyz="0 0 1" />', '<axis xyz="1 0 0" />', 1)
    with pytest.raises(UrdfError, match=r"joint 1 .*JointModelRX.*about \+z"):
        load_arm(_write(tmp_path, text))


def test_refuses_wrong_joint2_rpy(tmp_path, table1):
    text = make_urdf(table1)
    good = '<origin xyz="0 0 1.0" rpy="1.5707963267948966 0 0" />'
    assert text.count(good) == 1
    text = text.replace(good, '<origin xyz="0 0 1.0" rpy="0 0 0" />')
    with pytest.raises(UrdfError, match=r"joint 2 origin .*rpy=\(pi/2, 0, 0\)"):
        load_arm(_write(tmp_path, text))


def test_refuses_missing_tool_joint(tmp_path, table1):
    text = make_urdf(table1).split('  <joint name="tool_joint"')[0] + "</robot>\n"
    with pytest.raises(UrdfError, match="no fixed tool joint"):
        load_arm(_write(tmp_path, text))


@pytest.mark.parametrize("kind", ["missing", "malformed", "prismatic"])
def test_cli_verify_model_bad_urdf_exit_2_one_line(tmp_path, table1, capsys, kind):
    """`rc3r verify-model --urdf BAD` returns 2 and prints exactly one line on stderr, nothing on stdout."""
    if kind == "missing":
        bad = tmp_path / "missing.urdf"
    elif kind == "malformed":
        bad = _write(tmp_path, "<robot")
    else:
        bad = _write(tmp_path, make_urdf(table1).replace('type="revolute"', 'type="prismatic"', 1))
    assert main(["verify-model", "--urdf", str(bad)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert len(err.splitlines()) == 1 and err.startswith("rc3r: error: ")


@pytest.mark.parametrize("bad", ['<mass value="nan" />', '<mass value="inf" />', '<mass value="ten" />'])
def test_non_finite_numbers_refused(tmp_path, bad):
    """A NaN/inf/non-numeric mass is refused by rc3r (urdfdom would drop the inertial silently)."""
    text = (Path(REPO_URDF).read_text()).replace('<mass value="10.0" />', bad, 1)
    f = tmp_path / "bad.urdf"
    f.write_text(text)
    with pytest.raises(UrdfError, match="not a finite number"):
        load_arm(f)
