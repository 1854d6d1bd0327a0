"""rc3r.robots.rr3.urdf: the committed URDF, round trips URDF <-> ArmParams, URDFs of other but
kinematically equivalent layouts (hand-written and hypothesis-drawn), and refusals of other robots."""
from __future__ import annotations

import glob
import math
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rc3r.cli import main
from rc3r.errors import UrdfError
from rc3r.robots.rr3 import RR3
from rc3r.robots.rr3.params import ArmParams, LinkParams, theta
from rc3r.robots.rr3.urdf import (
    L3_DEFAULT, REPO_URDF, dh_fixed, load_arm, make_urdf, params_from_model, write_urdf,
)
from rc3r.verify import verify_model

#: Parameters survive URDF text (repr of float64, exact) and Pinocchio's
#: lever/inertia conversion plus our inverse rotation by R_i (a handful of
#: operations on O(1..10) numbers): rounding ~1e-15, so 1e-12 is a safe bound.
ROUND_TRIP_TOL = 1e-12

#: theta (entries up to ~33 kg m^2) of an equivalent layout against the reference:
#: the rpy text of a few rotations (repr, exact) and Pinocchio's compositions of
#: ~10 rigid transforms with O(1..5) m lever arms round at ~1e-15 relative, and
#: theta squares those levers times masses of O(10): ~1e-13 (measured at most
#: 7e-14 over 200 random layouts). 1e-12 keeps a margin of ~10 and is 1e9 times
#: below the effect of any real change of the mechanism.
THETA_TOL = 1e-12

#: Reproducible property tests (as in test_rr3_regressor.py): fixed example
#: sequence, no database on disk, no per-example deadline (Pinocchio warm-up).
PROPERTY = settings(max_examples=40, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow])


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


# ---- visual geometry ------------------------------------------------------------------------


def test_committed_urdf_has_a_visual_model_of_two_cylinders_per_link():
    """Pinocchio reads 6 visual cylinders (housing + shaft per link); at a random q each shaft spans
    its joint's origin to the next joint's origin (the tool for link 3), each housing sits on its joint
    axis: the visuals are where the kinematics are. Placements compose a few rigid transforms of O(1) m:
    rounding ~1e-15, so 1e-12."""
    model, collision, visual = pin.buildModelsFromUrdf(str(REPO_URDF), geometry_types=[
        pin.GeometryType.COLLISION, pin.GeometryType.VISUAL])
    assert visual.ngeoms == 6 and collision.ngeoms == 0
    assert pin.buildGeomFromUrdf(model, str(REPO_URDF), pin.GeometryType.VISUAL).ngeoms == 6
    assert [g.parentJoint for g in visual.geometryObjects] == [1, 1, 2, 2, 3, 3]
    q = np.array([0.3, -1.1, 2.0])
    data, gdata = model.createData(), pin.GeometryData(visual)
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    pin.updateGeometryPlacements(model, data, visual, gdata)
    ends = [data.oMi[1].translation, data.oMi[2].translation, data.oMi[3].translation,
            data.oMf[model.getFrameId("tool")].translation]
    for i in range(3):
        housing, shaft = visual.geometryObjects[2 * i], visual.geometryObjects[2 * i + 1]
        assert isinstance(shaft.geometry, type(housing.geometry)) and type(shaft.geometry).__name__ == "Cylinder"
        assert shaft.geometry.radius == 0.05 and housing.geometry.radius == 0.075  # VISUAL_RADIUS x min(l) = 1 m
        M = gdata.oMg[2 * i + 1]
        h = shaft.geometry.halfLength
        tips = sorted([M.act(np.array([0, 0, -h])), M.act(np.array([0, 0, h]))],
                      key=lambda x: np.linalg.norm(x - ends[i]))
        np.testing.assert_allclose(tips[0], ends[i], atol=1e-12)
        np.testing.assert_allclose(tips[1], ends[i + 1], atol=1e-12)
        axis = data.oMi[i + 1].rotation[:, 2]  # joint i turns about its frame's z
        np.testing.assert_allclose(gdata.oMg[2 * i].translation, ends[i], atol=1e-12)
        np.testing.assert_allclose(abs(gdata.oMg[2 * i].rotation[:, 2] @ axis), 1.0, atol=1e-12)


def test_visual_geometry_does_not_change_the_dynamics(tmp_path, table1):
    """The same URDF without its <visual>/<material> elements gives bit-identical Pinocchio inertias,
    joint placements and the same ArmParams: the visuals are for viewers only."""
    import re

    text = make_urdf(table1)
    bare = re.sub(r"\s*<material name=\"[^\"]*\">.*?</material>", "", text, flags=re.S)
    bare = re.sub(r"\s*<visual.*?</visual>", "", bare, flags=re.S)
    assert "<visual" in text and "<visual" not in bare and "<material" not in bare
    a, b = pin.buildModelFromXML(text), pin.buildModelFromXML(bare)
    for i in range(1, 4):
        np.testing.assert_array_equal(a.inertias[i].toDynamicParameters(), b.inertias[i].toDynamicParameters())
        np.testing.assert_array_equal(a.jointPlacements[i].homogeneous, b.jointPlacements[i].homogeneous)
    assert [f.name for f in a.frames] == [f.name for f in b.frames]
    loaded = load_arm(_write(tmp_path, bare, "bare.urdf")).params
    np.testing.assert_array_equal(load_arm(REPO_URDF).params.to_vector(), loaded.to_vector())


def test_committed_urdf_visuals_load_in_yourdfpy():
    """yourdfpy (what rc3r validates URDFs with, and a viewer) sees two cylinders on each link."""
    import yourdfpy

    robot = yourdfpy.URDF.load(str(REPO_URDF), build_scene_graph=False, load_meshes=False)
    vis = {lk.name: [(v.name, v.geometry.cylinder.radius, v.geometry.cylinder.length) for v in lk.visuals]
           for lk in robot.robot.links}
    assert vis["base_link"] == [] and vis["tool"] == []
    for i in (1, 2, 3):
        assert vis[f"link{i}"] == [(f"link{i}_housing", 0.075, 0.15), (f"link{i}_shaft", 0.05, 1.0)]


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
    """Joint 1 about base x is refused. (The message used to name Pinocchio's joint type,
    JointModelRX; the reader now checks axes in the base frame and names the axis.)"""
    text = make_urdf(table1).replace('<axis xyz="0 0 1" />', '<axis xyz="1 0 0" />', 1)
    with pytest.raises(UrdfError, match=r"joint 1 axis is \(1, 0, 0\) in the base frame, not vertical"):
        load_arm(_write(tmp_path, text))


def test_refuses_wrong_joint2_rpy(tmp_path, table1):
    """Joint 2 origin without its rpy = (pi/2, 0, 0) makes joint 2 vertical. (The message used to
    demand that exact origin; other origins are now accepted when equivalent, so it names the
    geometric difference instead.)"""
    text = make_urdf(table1)
    good = '<origin xyz="0 0 1.0" rpy="1.5707963267948966 0 0" />'
    assert text.count(good) == 1
    text = text.replace(good, '<origin xyz="0 0 1.0" rpy="0 0 0" />')
    with pytest.raises(UrdfError, match=r"joint 2 axis is not perpendicular to joint 1 axis \(angle 0 rad"):
        load_arm(_write(tmp_path, text))


def test_missing_tool_joint_is_accepted_with_default_l3(tmp_path, table1):
    """No tool joint after joint 3: loaded with l3 = L3_DEFAULT. (This test used to assert the
    refusal "no fixed tool joint after joint 3"; l3 only enters theta through X3 = l3 + r_cx3,
    which the inertial origin gives, so the refusal was needless.)"""
    text = _without_tool(make_urdf(table1))
    arm = load_arm(_write(tmp_path, text))
    assert arm.l3_source == "default" and arm.params.lengths[2] == L3_DEFAULT
    np.testing.assert_allclose(theta(arm.params), theta(table1), rtol=0, atol=THETA_TOL)


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


# ---- equivalent layouts: other joint origins, link frames, axes, fixed links --------------


def _without_tool(text: str) -> str:
    """make_urdf text without its tool joint and tool link (link frames at the joints)."""
    return text.split('  <joint name="tool_joint"')[0] + "</robot>\n"


def _origin(M) -> str:
    xyz = " ".join(repr(float(v)) for v in M.translation)
    rpy = " ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(M.rotation))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _inertial(M, mass, i6) -> str:
    ixx, iyy, izz, ixy, ixz, iyz = (repr(float(v)) for v in i6)
    return (f'<inertial>{_origin(M)}<mass value="{mass!r}"/><inertia ixx="{ixx}" ixy="{ixy}" '
            f'ixz="{ixz}" iyy="{iyy}" iyz="{iyz}" izz="{izz}"/></inertial>')


def equivalent_urdf(p: ArmParams, shifts=(0, 0, 0), turns=(0, 0, 0), tilts=((0, 0, 0),) * 3,
                    brackets=(False, False, False), tool=False, base=(0.0, 0.0)) -> str:
    """URDF of the arm ``p`` with the link frames placed differently, same mechanism.

    The frame of link *i* is ``T_{i-1} Trans_z(shifts[i]) Rot_z(turns[i]) G_i`` with
    ``T_{i-1}`` the DH frame on joint *i*'s axis and ``G_i = rpy(tilts[i])`` an
    arbitrary rotation, the ``<axis>`` being ``G_i^T z`` so that the joint still turns
    about DH z_{i-1}: shifted along and turned about the joint axis, axis written in
    a tilted frame. Each joint origin is the relative placement of consecutive
    frames; each ``<inertial>`` puts the CoM of ``p`` with DH axes in its link frame.
    ``brackets[i]``: link *i* carries a fixed child link at an arbitrary placement
    holding half its mass and inertia (same CoM), and joint *i+1* hangs from it.
    ``tool``: a fixed ``tool_joint`` at DH frame 3. ``base``: joint 1's axis is moved
    horizontally to ``(x, y)``.
    """
    T = [pin.SE3(np.eye(3), np.array([base[0], base[1], 0.0]))]
    for i in (1, 2, 3):
        T.append(T[-1] * pin.SE3(*dh_fixed(i, p.lengths)))
    out = ['<robot name="equivalent">', '<link name="base"/>']
    parent, P = "base", pin.SE3.Identity()
    for i in (1, 2, 3):
        G = pin.rpy.rpyToMatrix(*map(float, tilts[i - 1]))
        F = (T[i - 1] * pin.SE3(np.eye(3), np.array([0.0, 0.0, shifts[i - 1]]))
             * pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, float(turns[i - 1])), np.zeros(3)) * pin.SE3(G, np.zeros(3)))
        axis = " ".join(repr(float(v)) for v in G.T @ np.array([0.0, 0.0, 1.0]))
        out.append(f'<joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="l{i}"/>'
                   f'{_origin(P.actInv(F))}<axis xyz="{axis}"/>'
                   '<limit lower="-10" upper="10" effort="1" velocity="1"/></joint>')
        link = p.links[i - 1]
        com = pin.SE3(T[i].rotation, T[i].act(np.array(link.com)))  # DH axes i at the CoM
        k = 0.5 if brackets[i - 1] else 1.0  # halving is exact in binary floating point
        inertia = [k * v for v in link.inertia]
        out.append(f'<link name="l{i}">{_inertial(F.actInv(com), k * link.mass, inertia)}</link>')
        parent, P = f"l{i}", F
        if brackets[i - 1]:
            E = F * pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.7, 1.1), np.array([0.2, -0.4, 0.3]))
            out.append(f'<joint name="bracket{i}" type="fixed"><parent link="l{i}"/><child link="b{i}"/>'
                       f'{_origin(F.actInv(E))}</joint>')
            out.append(f'<link name="b{i}">{_inertial(E.actInv(com), k * link.mass, inertia)}</link>')
            parent, P = f"b{i}", E
    if tool:
        out.append(f'<joint name="tool_joint" type="fixed"><parent link="{parent}"/><child link="tool"/>'
                   f'{_origin(P.actInv(T[3]))}</joint><link name="tool"/>')
    return "\n".join(out + ["</robot>"]) + "\n"


#: The Table 1 arm written by hand another way: joint 1 origin flipped (rpy = (pi, 0, 0))
#: with axis -z (so it turns about base +z), joints 2 and 3 in world-aligned link frames
#: with axis (0, -1, 0), link 2's frame shifted 0.25 m along joint 2's axis, a massless
#: fixed bracket between link 2 and joint 3, no tool joint. Inertial origins carry the DH
#: rotations: link 1 CoM (0.5, 0.1, 0.5) in the base frame is (0.5, -0.1, -0.5) in link
#: 1's flipped frame, with DH axes at rpy (-pi/2, 0, 0) there; links 2 and 3 at
#: rpy (pi/2, 0, 0).
HAND_WRITTEN = """<?xml version="1.0"?>
<robot name="rr3_other_layout">
  <link name="base_link"/>
  <joint name="shoulder_yaw" type="continuous">
    <parent link="base_link"/><child link="upper"/>
    <origin xyz="0 0 0" rpy="3.141592653589793 0 0"/><axis xyz="0 0 -1"/>
  </joint>
  <link name="upper">
    <inertial>
      <origin xyz="0.5 -0.1 -0.5" rpy="-1.5707963267948966 0 0"/><mass value="10"/>
      <inertia ixx="0.5" ixy="0.1" ixz="0.1" iyy="0.5" iyz="0.1" izz="0.5"/>
    </inertial>
  </link>
  <joint name="shoulder_pitch" type="revolute">
    <parent link="upper"/><child link="arm"/>
    <origin xyz="0 0.25 -1" rpy="3.141592653589793 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="-3" upper="3" effort="100" velocity="10"/>
  </joint>
  <link name="arm">
    <inertial>
      <origin xyz="0.5 -0.15 -0.3" rpy="1.5707963267948966 0 0"/><mass value="10"/>
      <inertia ixx="0.5" ixy="0.2" ixz="0.2" iyy="0.5" iyz="0.2" izz="0.5"/>
    </inertial>
  </link>
  <joint name="bracket_mount" type="fixed">
    <parent link="arm"/><child link="bracket"/><origin xyz="0.5 0.25 0" rpy="0 0 0"/>
  </joint>
  <link name="bracket"/>
  <joint name="elbow" type="revolute">
    <parent link="bracket"/><child link="forearm"/>
    <origin xyz="0.5 0 0" rpy="0 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="-3" upper="3" effort="100" velocity="10"/>
  </joint>
  <link name="forearm">
    <inertial>
      <origin xyz="1.2 -0.2 0.2" rpy="1.5707963267948966 0 0"/><mass value="10"/>
      <inertia ixx="0.5" ixy="0.2" ixz="0.2" iyy="0.5" iyz="0.2" izz="0.5"/>
    </inertial>
  </link>
</robot>
"""


def test_committed_urdf_params_unchanged_by_the_equivalence_reader(arm, table1):
    """(a) urdf/rr3.urdf loads to Table 1 with l3 read from its tool joint."""
    _assert_params_close(arm.params, table1)
    assert arm.l3_source == "tool joint 'tool_joint'"


@pytest.mark.parametrize("layout", ["links_at_joints_no_tool", "hand_written"])
def test_equivalent_layout_loads_to_table2_and_passes_verify_model(tmp_path, table1, layout):
    """(b) The Table 1 arm with another layout and no tool joint: theta == Table 2, verify-model passes.

    l3 defaults to 1 m, which happens to be Table 1's l3, so the parameters match too."""
    text = _without_tool(make_urdf(table1)) if layout != "hand_written" else HAND_WRITTEN
    path = _write(tmp_path, text, f"{layout}.urdf")
    arm = load_arm(path)
    assert arm.l3_source == "default"
    np.testing.assert_allclose(theta(arm.params), theta(table1), rtol=0, atol=THETA_TOL)
    np.testing.assert_allclose(theta(arm.params), (33, -11.6, 3.4, -14, -4.4, -2, 12, 1.4, -3.8, -0.2,
                                                   -2.2, 29.2, 15.3, 15, 3), rtol=0, atol=THETA_TOL)
    _assert_params_close(arm.params, table1)
    report = verify_model(RR3.from_urdf(path), samples=200, seed=1)
    assert report.passed, {n: c for n, c in report.checks.items() if not c.passed}


def test_generated_equivalent_layout_with_everything_passes_verify_model(tmp_path):
    """A random physical arm, every link frame shifted, turned and tilted, brackets, base offset."""
    p = random_physical_arm(np.random.default_rng(7))
    text = equivalent_urdf(p, shifts=(0.3, -1.1, 0.7), turns=(2.0, -0.4, 3.0),
                           tilts=((0.1, 0.2, 0.3), (-1.0, 0.5, 2.0), (2.5, -1.2, 0.4)),
                           brackets=(True, True, True), tool=True, base=(0.4, -0.3))
    path = _write(tmp_path, text, "everything.urdf")
    arm = load_arm(path)
    _assert_params_close(arm.params, p)
    report = verify_model(RR3.from_urdf(path), samples=200, seed=2)
    assert report.passed, {n: c for n, c in report.checks.items() if not c.passed}


@st.composite
def placements(draw):
    """Keyword arguments of :func:`equivalent_urdf`: shifts in [-2, 2] m, angles in [-pi, pi]."""
    angle = st.floats(-math.pi, math.pi)
    return dict(
        shifts=[draw(st.floats(-2.0, 2.0)) for _ in range(3)],
        turns=[draw(angle) for _ in range(3)],
        tilts=[[draw(angle) for _ in range(3)] for _ in range(3)],
        brackets=[draw(st.booleans()) for _ in range(3)],
        tool=draw(st.booleans()),
        base=(draw(st.floats(-1.0, 1.0)), draw(st.floats(-1.0, 1.0))),
    )


@PROPERTY
@given(kw=placements(), seed=st.integers(0, 2**32 - 1))
def test_property_rigid_replacements_of_link_frames_keep_theta(tmp_path_factory, kw, seed):
    """(d) Re-placing link frames (shift along / turn about the joint axis, tilt with the
    axis rewritten, brackets, base offset), compensating joint and inertial origins, keeps
    theta; with a tool joint the parameters themselves come back."""
    p = random_physical_arm(np.random.default_rng(seed))
    path = tmp_path_factory.mktemp("prop") / "arm.urdf"
    path.write_text(equivalent_urdf(p, **kw))
    arm = load_arm(path)
    np.testing.assert_allclose(theta(arm.params), theta(p), rtol=0, atol=THETA_TOL)
    if kw["tool"]:
        _assert_params_close(arm.params, p)
    else:
        assert arm.params.lengths[2] == L3_DEFAULT


# ---- l3 ----------------------------------------------------------------------------------


def test_theta_is_independent_of_the_l3_choice(arm, table1):
    """Two choices of l3 give identical theta (l3 enters only through X3 = l3 + r_cx3)."""
    a = params_from_model(arm.model, l3=0.37)
    b = params_from_model(arm.model, l3=2.5)
    assert a.lengths[2] == 0.37 and b.lengths[2] == 2.5
    assert a.links[2].com[0] != b.links[2].com[0]
    np.testing.assert_allclose(theta(a), theta(b), rtol=0, atol=THETA_TOL)
    np.testing.assert_allclose(theta(a), theta(table1), rtol=0, atol=THETA_TOL)


def test_l3_from_a_fixed_frame_on_the_dh_x3_axis(tmp_path, table1):
    """Without a tool_joint, the farthest fixed frame on DH x3 gives l3; one off that axis is ignored."""
    text = make_urdf(table1).replace('name="tool_joint"', 'name="flange"')
    text = text.replace('<origin xyz="1.0 0 0" rpy="0 0 0" />\n  </joint>\n  <link name="tool"',
                        '<origin xyz="0.7 0 0" rpy="0.3 0 0" />\n  </joint>\n  <link name="tool"')
    arm = load_arm(_write(tmp_path, text, "flange.urdf"))
    assert arm.l3_source == "fixed frame 'flange'" and arm.params.lengths[2] == pytest.approx(0.7, abs=1e-15)
    np.testing.assert_allclose(theta(arm.params), theta(table1), rtol=0, atol=THETA_TOL)
    off_axis = text.replace('xyz="0.7 0 0" rpy="0.3 0 0"', 'xyz="0.7 0 0.2" rpy="0 0 0"')
    arm = load_arm(_write(tmp_path, off_axis, "sensor.urdf"))
    assert arm.l3_source == "default"
    np.testing.assert_allclose(theta(arm.params), theta(table1), rtol=0, atol=THETA_TOL)


# ---- refusals of non-equivalent structures ---------------------------------------------------


def _edit(text: str, old: str, new: str, nth: int = 1) -> str:
    """Replace the nth occurrence of old (asserting it exists)."""
    parts = text.split(old)
    assert len(parts) > nth, old
    return old.join(parts[:nth]) + new + old.join(parts[nth:])


J2 = '<origin xyz="0 0 1.0" rpy="1.5707963267948966 0 0" />'
J3 = '<origin xyz="1.0 0 0" rpy="0 0 0" />'  # 1st: joint 3, 2nd: tool joint
AXIS = '<axis xyz="0 0 1" />'
FOURTH = ('<joint name="wrist" type="revolute"><parent link="tool"/><child link="hand"/><axis xyz="0 0 1"/>'
          '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint><link name="hand"/></robot>')
REFUSALS = {
    "not_perpendicular": (J2, '<origin xyz="0 0 1.0" rpy="1.2 0 0" />', 1,
                          r"joint 2 axis is not perpendicular to joint 1 axis \(angle 1\.2 rad"),
    "not_intersecting": (J2, '<origin xyz="0.1 0 1.0" rpy="1.5707963267948966 0 0" />', 1,
                         r"joint 2 axis does not intersect joint 1 axis \(distance 0\.1 m"),
    "l1_not_positive": (J2, '<origin xyz="0 0 -0.5" rpy="1.5707963267948966 0 0" />', 1,
                        r"meets joint 1 axis at height -0\.5 m .*expected l1 > 0"),
    "not_parallel": (J3, '<origin xyz="1.0 0 0" rpy="0.3 0 0" />', 1,
                     r"joint 3 axis is not parallel to joint 2 axis \(angle 0\.3 rad"),
    "l2_zero": (J3, '<origin xyz="0 0 0.5" rpy="0 0 0" />', 1, r"joint 3 axis coincides with joint 2 axis"),
    "d3_nonzero": (J3, '<origin xyz="1.0 0 0.1" rpy="0 0 0" />', 2,
                   r"tool joint 'tool_joint' is 0\.1 m off the arm plane .*DH d3 = 0\.1, expected 0"),
    "tool_rotated": (J3, '<origin xyz="1.0 0 0" rpy="0.2 0 0" />', 2,
                     r"tool joint 'tool_joint' is rotated 0\.2 rad relative to DH frame 3"),
    "joint1_flipped": (AXIS, '<axis xyz="0 0 -1" />', 1, r"joint 1 axis points along -z, a flipped axis"),
    "joint2_flipped": (AXIS, '<axis xyz="0 0 -1" />', 2,
                       r"joint 2 axis is \(0, 1, 0\).*turned 3\.14159 rad about joint 1, .*flipped joint 2"),
    "joint3_flipped": (AXIS, '<axis xyz="0 0 -1" />', 3, r"joint 3 axis is antiparallel to joint 2 axis"),
    "joint1_zero_offset": ('<origin xyz="0 0 0" rpy="0 0 0" />', '<origin xyz="0 0 0" rpy="0 0 0.5" />', 1,
                           r"turned 0\.5 rad about joint 1, a joint 1 zero offset"),
    "joint2_zero_offset": (J3, '<origin xyz="0 1.0 0" rpy="0 0 0" />', 1,
                           r"common normal from joint 2 to joint 3 points along \(0, 0, 1\).*"
                           r"joint 2 zero offset of 1\.5708 rad"),
    "joint3_zero_offset": (J3, '<origin xyz="0 1.0 0" rpy="0 0 0" />', 2,
                           r"tool joint 'tool_joint' is turned 1\.5708 rad about joint 3 .*joint 3 zero offset"),
    "prismatic": ('name="joint3" type="revolute"', 'name="joint3" type="prismatic"', 1,
                  r"'joint3' is prismatic, expected revolute"),
    "four_joints": ("</robot>", FOURTH, 1, r"it has 4 moving joints \(joint1, joint2, joint3, wrist\), expected 3"),
}


@pytest.mark.parametrize("case", sorted(REFUSALS))
def test_refuses_non_equivalent_structure_naming_the_difference(tmp_path, table1, case):
    """(c) Each way of not being the paper's arm is refused with a one-line message naming it."""
    old, new, nth, pattern = REFUSALS[case]
    text = _edit(make_urdf(table1), old, new, nth)
    with pytest.raises(UrdfError, match=pattern) as exc:
        load_arm(_write(tmp_path, text, f"{case}.urdf"))
    assert len(str(exc.value).splitlines()) == 1 and "is not the 3R arm: " in str(exc.value)
