"""rc3r.uncertainty.payload: a payload of uncertain mass moves theta along a segment; exact bounds.

Tolerances: theta entries are O(1..10) sums of O(10) float64 products, rounding ~1e-15
relative; "exact" is checked to 1e-12 relative to max(1, max|theta|) (``assert_close``
with tol=1e-12); the model comparisons (rnea) use the verify-model 1e-9.
"""
from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from _helpers import assert_close

from rc3r.errors import ParameterError
from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir
from rc3r.uncertainty.payload import (payload_bounds, payload_parameters, point_mass_parameters,
                                      with_payload)

MASS = (0.5, 3.0)
COM = (0.01, -0.02, 0.12)
INERTIA = np.array([[0.004, 0.0005, 0.0], [0.0005, 0.005, 0.0002], [0.0, 0.0002, 0.003]])
EXACT = 1e-12


def test_payload_parameters_are_pinocchio_inertias():
    """m w(c) + (0, iota(I_c)) == pinocchio.Inertia(m, c, I_c).toDynamicParameters() (w: unit point mass)."""
    c = np.array(COM)
    assert_close(point_mass_parameters(c), pin.Inertia(1.0, c, np.zeros((3, 3))).toDynamicParameters(), tol=EXACT)
    assert_close(payload_parameters(2.5, c, INERTIA), pin.Inertia(2.5, c, INERTIA).toDynamicParameters(), tol=EXACT)
    urdf_order = (INERTIA[0, 0], INERTIA[1, 1], INERTIA[2, 2], INERTIA[0, 1], INERTIA[0, 2], INERTIA[1, 2])
    assert_close(payload_parameters(2.5, c, urdf_order), payload_parameters(2.5, c, INERTIA), tol=0)


@pytest.mark.parametrize("name", ["ur5", "panda"])
@pytest.mark.parametrize("inertia", [None, INERTIA])
def test_bounds_are_exact_on_the_segment(name, inertia, request):
    """theta(with_payload(m)) for m in [lo, hi] lies in [theta_lo, theta_hi], within rho_i of theta0
    and within rho in norm; the ends of the interval attain theta_lo/theta_hi, rho_i and rho."""
    robot = request.getfixturevalue(name)
    b = payload_bounds(robot, MASS, COM, inertia)
    scale = max(1.0, np.abs(b.theta_hi).max())
    thetas = np.array([with_payload(robot, m, COM, inertia).theta for m in np.linspace(*MASS, 9)])
    assert np.all(thetas >= b.theta_lo - EXACT * scale) and np.all(thetas <= b.theta_hi + EXACT * scale)
    assert np.all(np.abs(thetas - b.theta0) <= b.rho_i + EXACT * scale)
    assert np.all(np.linalg.norm(thetas - b.theta0, axis=1) <= b.rho + EXACT * scale)
    ends = thetas[[0, -1]]
    assert_close(np.minimum(*ends), b.theta_lo, tol=EXACT)
    assert_close(np.maximum(*ends), b.theta_hi, tol=EXACT)
    assert_close(np.abs(ends[1] - b.theta0), b.rho_i, tol=EXACT)
    assert_close(np.linalg.norm(ends - b.theta0, axis=1), [b.rho, b.rho], tol=EXACT)
    assert_close(b.theta_nominal, robot.theta, tol=0)
    assert b.method == "payload" and json.loads(b.to_json())["rho"] == pytest.approx(b.rho)


def test_witnesses_attain_the_ranges(ur5):
    """theta_i(witness_lo[i]) == theta_lo[i] and theta_i(witness_hi[i]) == theta_hi[i]; the box
    (bounding box of the segment) contains both ends' deltas and is zero off the last body."""
    b = payload_bounds(ur5, MASS, COM, INERTIA)
    i = np.arange(ur5.p)
    assert_close(ur5.theta_of_standard(b.witness_lo)[i, i], b.theta_lo, tol=EXACT)
    assert_close(ur5.theta_of_standard(b.witness_hi)[i, i], b.theta_hi, tol=EXACT)
    std = ur5.standard_parameters()
    assert np.all(b.box.contains(b.witness_lo - std)) and np.all(b.box.contains(b.witness_hi - std))
    assert not np.any(b.box.lower[:-10]) and not np.any(b.box.upper[:-10])
    assert (b.box.lower[-10], b.box.upper[-10]) == MASS


def _ur5_with_payload_link(tmp_path, mass, parent, xyz, inertia):
    """The UR5 URDF with a payload link fixed to ``parent`` at ``xyz`` (Pinocchio merges it)."""
    text = (example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf").read_text()
    I = np.asarray(inertia).tolist()
    xyz = [float(x) for x in xyz]
    extra = (f'<joint name="payload_joint" type="fixed"><parent link="{parent}"/><child link="payload"/>'
             f'<origin xyz="{xyz[0]!r} {xyz[1]!r} {xyz[2]!r}" rpy="0 0 0"/></joint>'
             f'<link name="payload"><inertial><origin xyz="0 0 0"/><mass value="{mass!r}"/>'
             f'<inertia ixx="{I[0][0]!r}" ixy="{I[0][1]!r}" ixz="{I[0][2]!r}" iyy="{I[1][1]!r}" '
             f'iyz="{I[1][2]!r}" izz="{I[2][2]!r}"/></inertial></link></robot>')
    path = tmp_path / "ur5_payload.urdf"
    path.write_text(text.replace("</robot>", extra))
    return PinocchioRobot.from_urdf(path)


@pytest.mark.parametrize("frame,parent", [(None, "wrist_3_link"), ("tool0", "tool0")])
def test_with_payload_equals_urdf_with_a_payload_link(tmp_path, ur5, rng, frame, parent):
    """with_payload (pinocchio.Inertia sum on the last joint) == the URDF with a fixed payload link
    (Pinocchio's parser merges it): same rnea at random states (1e-9), same theta (1e-12); also
    with the CoM given in the tool frame ``tool0`` (rotated and offset from the joint frame)."""
    m = 2.2
    plant = with_payload(ur5, m, COM, INERTIA, frame=frame)
    ref = _ur5_with_payload_link(tmp_path, m, parent, COM, INERTIA)
    d, dr = plant.model.createData(), ref.model.createData()
    for _ in range(20):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, 6), rng.uniform(-5, 5, 6), rng.uniform(-5, 5, 6)
        assert_close(pin.rnea(plant.model, d, q, qd, qdd), pin.rnea(ref.model, dr, q, qd, qdd))
    assert_close(plant.theta, ref.theta, tol=EXACT)
    assert_close(payload_bounds(ur5, (m, m), COM, INERTIA, frame=frame).theta0, ref.theta, tol=EXACT)


def test_with_payload_equals_append_body_to_joint(ur5, rng):
    """with_payload == model.appendBodyToJoint(last, Inertia(m, 0, I_c), SE3(1, c)) (rnea, 1e-9)."""
    model = ur5.model.copy()
    model.appendBodyToJoint(model.njoints - 1, pin.Inertia(1.7, np.zeros(3), INERTIA), pin.SE3(np.eye(3), np.array(COM)))
    plant = with_payload(ur5, 1.7, COM, INERTIA)
    d, dr = plant.model.createData(), model.createData()
    for _ in range(20):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, 6), rng.uniform(-5, 5, 6), rng.uniform(-5, 5, 6)
        assert_close(pin.rnea(plant.model, d, q, qd, qdd), pin.rnea(model, dr, q, qd, qdd))


def test_payload_plant_regressor_identity(ur5, rng):
    """The plant with a payload keeps the kinematics: Y theta(payload) == its Pinocchio rnea."""
    plant = with_payload(ur5, 3.0, COM)
    assert plant.base is ur5.base and plant.kernel is ur5.kernel
    q, qd, qdd = rng.uniform(-np.pi, np.pi, (3, 6)), rng.uniform(-5, 5, (3, 6)), rng.uniform(-5, 5, (3, 6))
    d = plant.model.createData()
    assert_close(plant.regressor(q, qd, qd, qdd) @ plant.theta,
                 np.array([pin.rnea(plant.model, d, *s) for s in zip(q, qd, qdd)]))


def test_bad_payloads(ur5):
    """One-line ParameterError: negative or reversed mass interval, bad CoM, a frame not on the last
    joint, a robot whose standard parameters are not Pinocchio's."""
    from rc3r.robots.rr3 import RR3

    for kwargs, match in [
        (dict(mass=(-1.0, 1.0), com=COM), "0 <= lower <= upper"),
        (dict(mass=(2.0, 1.0), com=COM), "0 <= lower <= upper"),
        (dict(mass=(0.0, 1.0), com=(1.0, 2.0)), "CoM"),
        (dict(mass=(0.0, 1.0), com=COM, frame="shoulder_link"), "not attached to the last joint"),
        (dict(mass=(0.0, 1.0), com=COM, frame="nowhere"), "no frame"),
    ]:
        with pytest.raises(ParameterError, match=match) as info:
            payload_bounds(ur5, **kwargs)
        assert "\n" not in str(info.value)
    with pytest.raises(ParameterError, match="Pinocchio's standard parameters"):
        payload_bounds(RR3.nominal(), (0.0, 1.0), COM)
