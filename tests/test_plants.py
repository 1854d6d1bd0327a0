"""The plant seam: effects against hand values and the URDF's own text, the compiled engine against the
python engine with every effect, the loop effects against recomputed controller torques, and the
model/plant structure check."""
from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import rc3r
from rc3r.errors import ConfigError, ParameterError
from rc3r.plants import Friction, JointLimits, LoopEffects, Plant, Saturation, build_effects, crossings
from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir
from rc3r.simulate import SimOptions, simulate


@pytest.fixture(scope="module")
def spec():
    return rc3r.build_run(controller="robust", perturbed=True, duration=1.0)


def test_friction_torque_by_hand():
    """tau_f = -(Fv qd + Fc tanh(qd / v_s) + offset), joint by joint."""
    f = Friction([1.0, 2.0], [0.5, 0.0], [0.1, -0.2], v_s=0.1)
    qd = np.array([0.3, -1.0])
    expect = [-(1.0 * 0.3 + 0.5 * np.tanh(3.0) + 0.1), -(2.0 * -1.0 + 0.0 + -0.2)]
    np.testing.assert_allclose(f.joint_torque(None, qd), expect, rtol=1e-15)


def test_saturation_and_plant_torque_by_hand():
    """The command is clipped, then friction is added: 80 -> 50 - 2*1 = 48; -80 -> -50 - 2*1."""
    arm = rc3r.load_robot()
    plant = Plant(arm, [Friction(np.full(3, 2.0)), Saturation(np.full(3, 50.0))])
    tau = plant.joint_torque(np.zeros(3), np.ones(3), np.array([80.0, -80.0, 10.0]))
    np.testing.assert_allclose(tau, [48.0, -52.0, 8.0])
    qdd = plant.forward_dynamics(np.zeros(3), np.ones(3), np.array([80.0, -80.0, 10.0]))
    np.testing.assert_allclose(qdd, arm.forward_dynamics(np.zeros(3), np.ones(3), tau), rtol=1e-14)


def _urdf_joint_values(path, names, tag, attr):
    root = ET.parse(path).getroot()
    out = []
    for name in names:
        j = root.find(f"joint[@name='{name}']")
        el = j.find(tag)
        out.append(float(el.get(attr, 0.0)) if el is not None else 0.0)
    return np.array(out)


@pytest.mark.parametrize("urdf", ["z1_description/urdf/z1.urdf", "xarm_description/urdf/xarm7.urdf"])
def test_effects_from_the_urdf_text(urdf):
    """Friction and torque limits read through Pinocchio equal the URDF's own <dynamics> and <limit>
    attributes, read here with ElementTree (an independent parser)."""
    path = example_robot_data_dir() / urdf
    robot = PinocchioRobot.from_urdf(path, lock={"jointGripper": 0.0} if "z1" in urdf else None)
    names = robot.joint_names
    f, s = Friction.from_model(robot), Saturation.from_model(robot)
    np.testing.assert_array_equal(f.viscous, _urdf_joint_values(path, names, "dynamics", "damping"))
    np.testing.assert_array_equal(f.coulomb, _urdf_joint_values(path, names, "dynamics", "friction"))
    np.testing.assert_array_equal(s.limit, _urdf_joint_values(path, names, "limit", "effort"))
    assert f.source == s.source == "urdf"


def test_urdf_without_friction_is_refused_in_one_line():
    with pytest.raises(ConfigError, match="no <dynamics damping friction>"):
        Friction.from_model(rc3r.load_robot("ur5"))


def test_friction_ranges_drawn_per_plant_and_seeded():
    """A range {lo, hi} is drawn per joint from the plant's generator: the same seed gives the same
    plant, another seed another one, every draw inside the range."""
    arm = rc3r.load_robot()
    spec = {"viscous": {"lo": 1.0, "hi": 2.0}, "coulomb": 0.5}
    a, = build_effects(arm, friction=spec, rng=np.random.default_rng(5))
    b, = build_effects(arm, friction=spec, rng=np.random.default_rng(5))
    c, = build_effects(arm, friction=spec, rng=np.random.default_rng(6))
    np.testing.assert_array_equal(a.viscous, b.viscous)
    assert not np.array_equal(a.viscous, c.viscous)
    assert np.all((a.viscous >= 1.0) & (a.viscous <= 2.0)) and np.all(a.coulomb == 0.5)
    with pytest.raises(ConfigError, match="lo <= hi|lo = a"):
        build_effects(arm, friction={"viscous": {"lo": 2.0, "hi": 1.0}})


@pytest.mark.parametrize("rate", [None, 1000.0])
def test_compiled_engine_applies_effects_like_the_python_engine(spec, rate):
    """Friction and saturation in the 3R's compiled engine (packed fields) equal the python engine
    (Plant.forward_dynamics on Pinocchio's ABA): 1e-6 rad continuous (both at rtol 1e-6 against
    different integrators), 1e-8 rad sampled (same RK4, different arithmetic of the plant: the
    sampled accuracy the simulate module states). The
    delivered torque never exceeds the limit."""
    plant = Plant(spec.true_rigid, build_effects(spec.true_rigid, friction="2:1", torque_limit=150.0))
    opt = SimOptions(duration=0.5, rate=rate)
    fast = simulate(plant, spec.law, spec.trajectory, opt)
    py = simulate(plant, spec.law, spec.trajectory, SimOptions(duration=0.5, rate=rate, engine="python"))
    assert fast.engine == "fast" and py.engine == "python" and fast.ok and py.ok
    np.testing.assert_allclose(fast.q, py.q, atol=1e-6 if rate is None else 1e-8, rtol=0)
    assert np.abs(fast.u).max() <= 150.0 * (1 + 1e-12)  # stored rows interpolate between step ends
    assert np.abs(fast.u).max() == pytest.approx(150.0)
    rigid = simulate(spec.true_rigid, spec.law, spec.trajectory, opt)  # at 1 kHz the rigid run diverges
    m = min(len(rigid.q), len(fast.q))
    assert not rigid.ok or np.abs(rigid.q[:m] - fast.q[:m]).max() > 1e-3  # the effects act


def _ref(traj, t):
    q, qd, qdd = traj.evaluate(t)
    return np.array([q, qd, qdd])


@pytest.mark.parametrize("engine", ["fast", "python"])
def test_loop_effects_against_recomputed_torques(spec, engine):
    """Sample k's delivered torque is the law's torque at the measurement of sample k - d: the state
    plus noise row k - d (LoopEffects.noise, seeded), q quantized. Recomputed here from the stored
    true states with the law's own Python method."""
    law = rc3r.make_law("fbl", spec.true_rigid.theta)
    loop = LoopEffects(3, noise_q=1e-3, noise_qd=1e-2, quantization=1e-3, delay=2, seed=11)
    res = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=0.05, rate=1000.0, engine=engine),
                   loop=loop)
    noise = loop.noise(50)
    assert res.ok and res.loop["seed"] == 11
    for k in (0, 1, 2, 10, 37):
        src = max(k - 2, 0)
        qm = np.round((res.q[src] + noise[src, :3]) / 1e-3) * 1e-3
        qdm = res.qd[src] + noise[src, 3:]
        u, _, _ = law.torque(spec.true_rigid, qm, qdm, _ref(spec.trajectory, src * 1e-3))
        np.testing.assert_allclose(res.u[k], u, rtol=1e-9, atol=1e-9)


def test_initial_error_and_continuous_refusal(spec):
    loop = LoopEffects(3, q0_error=[0.01, 0.0, -0.02])
    res = simulate(spec.true_rigid, spec.law, spec.trajectory, SimOptions(duration=0.01), loop=loop)
    np.testing.assert_allclose(res.q[0] - spec.trajectory.evaluate(0.0)[0], [0.01, 0.0, -0.02], atol=1e-15)
    with pytest.raises(ParameterError, match="sampled controller"):
        simulate(spec.true_rigid, spec.law, spec.trajectory, SimOptions(duration=0.01),
                 loop=LoopEffects(3, noise_q=1e-3))


def test_noise_is_seeded():
    a, b = LoopEffects(2, noise_q=0.1, seed=3), LoopEffects(2, noise_q=0.1, seed=4)
    np.testing.assert_array_equal(a.noise(10), LoopEffects(2, noise_q=0.1, seed=3).noise(10))
    assert not np.array_equal(a.noise(10), b.noise(10))
    assert np.all(a.noise(10)[:, 2:] == 0.0)  # no velocity noise asked


def test_plant_of_another_arm_is_refused():
    """A UR10 plant under the UR5 model (same n = 6, p = 36) differs in its regressor: refused in one
    line; the UR5 with other inertias (a payload) passes."""
    from rc3r.uncertainty.payload import with_payload

    ur5 = rc3r.load_robot("ur5")
    ur10 = PinocchioRobot.from_urdf(example_robot_data_dir() / "ur_description/urdf/ur10_robot.urdf")
    traj = ur5.default_trajectory()
    law = rc3r.make_law("fbl", ur5.theta)
    with pytest.raises(ParameterError, match="not the model's arm"):
        simulate(ur10, law, traj, SimOptions(duration=0.01, rate=1000.0), model=ur5)
    heavy = with_payload(ur5, 3.0, np.zeros(3), label="ur5 + 3 kg")
    assert simulate(heavy, law, traj, SimOptions(duration=0.01, rate=1000.0), model=ur5).ok


def test_limit_crossings_by_hand():
    lim = JointLimits([-1.0, -np.inf], [1.0, np.inf], [np.inf, 2.0])
    t = np.array([0.0, 0.1, 0.2, 0.3])
    q = np.array([[0.0, 0.0], [0.5, 9.0], [1.2, 0.0], [0.0, 0.0]])
    qd = np.array([[0.0, 0.0], [0.0, 1.0], [0.0, 2.5], [0.0, 0.0]])
    out = crossings(lim, t, q, qd)
    assert out == {"position": [0.2, None], "velocity": [None, 0.2], "violated": True}


def test_pack_layout_by_hand():
    """The compiled engines' effects: ``[m, code, offset, ...]`` then each effect's block in the order of its
    LAYOUT (friction: viscous, coulomb, offset per joint, v_s; saturation: the limit per joint); a rigid plant,
    or one whose friction is zero, is ``[0]`` (its arithmetic is then the rigid body's)."""
    arm = rc3r.load_robot()
    np.testing.assert_array_equal(Plant(arm).pack(), [0.0])
    np.testing.assert_array_equal(Plant(arm, [Friction(np.zeros(3))]).pack(), [0.0])
    plant = Plant(arm, [Friction([1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0], v_s=0.5),
                        Saturation([10.0, 20.0, 30.0])])
    np.testing.assert_array_equal(plant.pack(), [2, 1, 5, 2, 15, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0.5, 10, 20, 30])
    assert plant.effect("saturation").limit.tolist() == [10.0, 20.0, 30.0] and plant.effect("nope") is None


def test_effect_construction_rules():
    """Scalars broadcast, sizes are checked against the arm, effects are frozen (a plant is data)."""
    import dataclasses

    f = Friction(coulomb=[1.0, 2.0, 3.0], offset=0.5)
    assert f.n == 3 and f.viscous.tolist() == [0.0] * 3 and f.offset.tolist() == [0.5] * 3
    with pytest.raises(dataclasses.FrozenInstanceError):
        f.v_s = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        JointLimits([0.0], [1.0], [1.0]).lower = 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        LoopEffects(1).delay = 3
    with pytest.raises(ConfigError, match="sized for 2 joints"):
        Plant(rc3r.load_robot(), [Friction([1.0, 2.0])])
    with pytest.raises(ConfigError, match="given twice"):
        Plant(rc3r.load_robot(), [Saturation([1.0] * 3), Saturation([2.0] * 3)])
    drawn = Friction.draw({"viscous": {"lo": 1.0, "hi": 1.0}}, 3, np.random.default_rng(0))
    assert drawn.coulomb.tolist() == [0.0] * 3 and drawn.offset.tolist() == [0.0] * 3
    assert drawn.viscous.tolist() == [1.0] * 3


@pytest.mark.parametrize("lo, hi, vel", [([1.0], [0.0], [1.0]), ([0.0], [1.0], [0.0]), ([0.0], [np.nan], [1.0])])
def test_bad_joint_limits_are_refused(lo, hi, vel):
    with pytest.raises(ConfigError, match="joint limits"):
        JointLimits(lo, hi, vel)


def test_limits_without_a_range_are_unbounded():
    """The double pendulum's URDF says lower = upper = 0: no range, so no crossing is ever reported."""
    robot = PinocchioRobot.from_urdf(example_robot_data_dir() / "double_pendulum_description/urdf/double_pendulum.urdf")
    lim = JointLimits.from_model(robot)
    assert lim.lower.tolist() == [-np.inf, -np.inf] and lim.upper.tolist() == [np.inf, np.inf]
    assert np.all(lim.velocity > 0)
    q = np.array([[5.0, -5.0]])
    assert crossings(lim, np.zeros(1), q, np.zeros((1, 2)))["violated"] is False


@pytest.mark.parametrize("kwargs", [dict(delay=-1), dict(delay=1001), dict(delay=1.5), dict(delay=True),
                                    dict(seed=-1), dict(noise_q=-1.0), dict(noise_q=[1.0, 2.0])])
def test_bad_loop_effects_are_refused(kwargs):
    with pytest.raises(ConfigError):
        LoopEffects(3, **kwargs)
    assert LoopEffects(3, delay=1000).delay == 1000
