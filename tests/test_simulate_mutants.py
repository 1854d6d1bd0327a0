"""What the mutation run of the simulation path (tests/mutation/run.py, group ``simulate``) found the
suite did not check: the python engine's sampled integration against the reference integrator, its
controller-state update and stored grid by hand, and the options' and status check's boundaries.

Every test here runs the ``python`` or ``reference`` engine or no engine at all, so it is fast with
``NUMBA_DISABLE_JIT=1`` (how the mutation run executes it).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import rc3r
from rc3r.errors import ParameterError
from rc3r.plants import as_plant
from rc3r.simulate import MAX_ROWS, MAX_SAMPLES, SimOptions, simulate
from rc3r.simulate import status as S


@pytest.fixture(scope="module")
def spec():
    """The perturbed 3R (Table 1 box), the paper's trajectory."""
    return rc3r.build_run(controller="robust", perturbed=True, duration=1.0)


def _ref(traj, t):
    q, qd, qdd = traj.evaluate(t)
    return np.array([q, qd, qdd])


# --- the python engine's sampled loop ---------------------------------------------------------------

@pytest.mark.parametrize("model", ["exact", "box centre"])
def test_python_sampled_rk4_equals_the_reference_integrator(spec, model):
    """FBL (on the plant's theta, or on the box centre's: a tracking error) sampled at 1 kHz: the
    python engine (RK4, nsub = 4 sub-steps of 0.25 ms per period, given so that the test does not
    depend on the default sub-step rule) and the
    reference engine (SciPy DOP853 per period at rtol 1e-11) integrate the same held torques: their
    positions and velocities agree within 1e-10 over 0.2 s (measured 2e-14: RK4's global error is
    O(h^4) at h = 0.25 ms; the stated sampled accuracy of rc3r.simulate is 1e-8 rad), the torques
    within 1e-9 of their maximum. A wrong RK4 weight or stage (an O(h) or O(h^2) method) misses this
    by orders of magnitude. The python engine evaluates the plant exactly 4 x 4 times a period."""
    law = rc3r.make_law("fbl", spec.true_rigid.theta if model == "exact" else spec.law.theta)
    opt = dict(duration=0.2, rate=1000.0, nsub=4)
    py = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(engine="python", **opt))
    ref = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(engine="reference", **opt))
    assert py.ok and ref.ok and py.engine == "python" and ref.engine == "reference"
    np.testing.assert_array_equal(py.t, ref.t)
    np.testing.assert_allclose(py.t, np.arange(201) * 1e-3, rtol=0, atol=1e-15)
    assert np.max(np.abs(py.q - ref.q)) < 1e-10
    assert np.max(np.abs(py.qd - ref.qd)) < 1e-10
    assert np.max(np.abs(py.u - ref.u)) < 1e-9 * np.max(np.abs(ref.u))
    assert py.rhs_evals == 200 * 4 * 4  # 200 periods x 4 sub-steps x 4 stages
    # the trajectory actually moves (the comparison is not of two resting arms)
    assert np.ptp(py.q[:, 0]) > 0.1


def test_python_sampled_first_period_by_hand(spec):
    """One period by hand: the law's torque at the initial state (on the trajectory), held over
    T = 1 ms, integrated by a classical RK4 written here on the plant's forward dynamics (4 steps of
    0.25 ms): the engine's second row equals it to rounding (1e-12)."""
    law = rc3r.make_law("fbl", spec.true_rigid.theta)
    res = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=0.002, rate=1000.0, nsub=4,
                                                                engine="python"))
    n = 3
    q0, qd0, _ = spec.trajectory.evaluate(0.0)
    u0, _, _ = law.torque(spec.true_rigid, q0, qd0, _ref(spec.trajectory, 0.0), law.initial_state())

    plant = as_plant(spec.true_rigid)

    def f(x):
        return np.concatenate([x[n:], plant.forward_dynamics(x[:n], x[n:], u0, delivered=True)])

    x, h = np.concatenate([q0, qd0]), 0.25e-3
    for _ in range(4):
        k1 = f(x); k2 = f(x + h / 2 * k1); k3 = f(x + h / 2 * k2); k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    np.testing.assert_allclose(res.u[0], u0, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(res.q[1], x[:n], rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.qd[1], x[n:], rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.q[0], q0, rtol=0, atol=0)


def test_adaptive_estimate_is_forward_euler_of_its_law(spec):
    """The controller state of a sampled run moves by forward Euler: z_1 = z_0 + T zdot(0), with
    zdot the adaptive law's own update at the first sample (computed here by its Python method), and
    the torque of each sample is the law's at that sample's state and estimate."""
    law = rc3r.make_law("adaptive", spec.law.theta)
    T = 1e-3
    res = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=0.003, rate=1000.0, engine="python"))
    q0, qd0, _ = spec.trajectory.evaluate(0.0)
    z0 = law.initial_state()
    x1 = np.array([res.q[1], res.qd[1]])
    u0, zdot0, _ = law.torque(spec.true_rigid, q0, qd0, _ref(spec.trajectory, 0.0), z0)
    u1, zdot1, _ = law.torque(spec.true_rigid, x1[0], x1[1], _ref(spec.trajectory, T), res.z[1])
    # the torque uses the estimate z (not a slice that runs into qd)
    np.testing.assert_allclose(res.u[0], u0, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.u[1], u1, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.z[0], z0, rtol=0, atol=0)
    np.testing.assert_allclose(res.z[1], z0 + T * np.asarray(zdot0), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(res.z[2], res.z[1] + T * np.asarray(zdot1), rtol=1e-12, atol=1e-15)


def test_sampled_rows_are_decimated_to_the_output_rate_and_tv_counts_every_sample(spec):
    """At 4 kHz with output_rate 1 kHz every 4th sample is stored (t = 0, 1, ..., 10 ms: 11 rows);
    the exact total variation counts all 40 sample-to-sample steps of the applied torque, so it
    equals the sum over a 4 kHz run stored in full (the same samples), and is at least the stored
    grid's total variation (the triangle inequality)."""
    law = rc3r.make_law("fbl", spec.true_rigid.theta)
    dec = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=0.01, rate=4000.0, output_rate=1000.0,
                                                                engine="python"))
    full = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=0.01, rate=4000.0, output_rate=4000.0,
                                                                 engine="python"))
    np.testing.assert_allclose(dec.t, np.arange(11) * 1e-3, rtol=0, atol=1e-15)
    assert full.t.size == 41
    np.testing.assert_allclose(dec.q, full.q[::4], rtol=0, atol=0)
    tv_full = np.abs(np.diff(full.u, axis=0)).sum(axis=0)
    np.testing.assert_allclose(full.tv_exact, tv_full, rtol=1e-12)
    np.testing.assert_allclose(dec.tv_exact, tv_full, rtol=1e-12)
    assert np.all(dec.tv_exact >= np.abs(np.diff(dec.u, axis=0)).sum(axis=0) - 1e-12)


def test_python_continuous_tracks_the_reference(spec):
    """Continuous time, FBL on the exact model: the python engine (Radau at rtol 1e-6, atol 1e-8)
    and the reference (Radau at rtol 1e-11) store the same 1 kHz grid and agree within 2e-6 rad
    (measured 1.6e-7 over 0.3 s: the default tolerances' error, with a factor 10 of margin); the
    tracking error of exact FBL from the trajectory's start stays at the integrator's level
    (measured 3e-12 in the reference; < 1e-9 asserted). The reference's tighter tolerances cost it
    several times the python engine's right-hand-side evaluations (the engines are not swapped)."""
    law = rc3r.make_law("fbl", spec.true_rigid.theta)
    py = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=0.3, engine="python"))
    ref = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=0.3, engine="reference"))
    assert py.ok and ref.ok and py.mode == "continuous"
    np.testing.assert_allclose(py.t, np.linspace(0, 0.3, 301), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(py.t, ref.t)
    assert np.max(np.abs(py.q - ref.q)) < 2e-6
    assert np.max(np.abs(ref.e)) < 1e-9
    assert py.steps > 0 and py.rhs_evals > py.steps and ref.rhs_evals > 3 * py.rhs_evals


# --- options, grid, status --------------------------------------------------------------------------

def test_substeps_by_hand():
    """RK4 sub-steps per period: ceil(T / 0.25 ms) (1 kHz: 4, 3 kHz: ceil(1.33) = 2, 4 kHz: exactly 1,
    100 Hz: 40), nsub when given, 1 in continuous time."""
    assert SimOptions(rate=1000.0).substeps == 4
    assert SimOptions(rate=3000.0).substeps == 2
    assert SimOptions(rate=4000.0).substeps == 1
    assert SimOptions(rate=100.0).substeps == 40
    assert SimOptions(rate=1e5).substeps == 1
    assert SimOptions(rate=1000.0, nsub=7).substeps == 7
    assert SimOptions().substeps == 1
    assert SimOptions().mode == "continuous" and SimOptions(rate=10.0).mode == "sampled"


def test_option_limits_are_inclusive_where_documented():
    """Boundaries of SimOptions: one period equal to the duration is accepted, a longer one refused;
    duration x rate = MAX_SAMPLES accepted, more refused; stored rows = MAX_ROWS accepted, more
    refused; jac_reuse 1 and 1000 accepted, 0 and 1001 refused; nsub 1 accepted, 0 and True refused."""
    SimOptions(duration=1.0, rate=1.0)
    with pytest.raises(ParameterError, match="slower than the duration"):
        SimOptions(duration=1.0, rate=0.999)
    SimOptions(duration=MAX_SAMPLES / 1e6, rate=1e6, output_rate=1.0)
    with pytest.raises(ParameterError, match="controller samples"):
        SimOptions(duration=MAX_SAMPLES / 1e6 * 1.01, rate=1e6, output_rate=1.0)
    SimOptions(duration=MAX_ROWS / 1000.0, output_rate=1000.0)
    with pytest.raises(ParameterError, match="rows"):
        SimOptions(duration=MAX_ROWS / 1000.0 + 1.0, output_rate=1000.0)
    # sampled: the rows are duration x min(rate, output_rate)
    SimOptions(duration=MAX_ROWS / 1000.0, rate=1000.0, output_rate=1e6)
    with pytest.raises(ParameterError, match="rows"):
        SimOptions(duration=MAX_ROWS / 1000.0 + 1.0, rate=1000.0, output_rate=1e6)
    for ok in (1, 1000):
        SimOptions(jac_reuse=ok)
    for bad in (0, 1001, True, 2.0):
        with pytest.raises(ParameterError, match="jac_reuse"):
            SimOptions(jac_reuse=bad)
    SimOptions(rate=10.0, nsub=1)
    for bad in (0, True, 1.5):
        with pytest.raises(ParameterError, match="nsub"):
            SimOptions(rate=10.0, nsub=bad)
    for name in ("duration", "output_rate", "rtol", "atol", "max_steps", "q_max", "qd_max", "u_max"):
        with pytest.raises(ParameterError, match=name):
            SimOptions(**{name: 0.0})
        with pytest.raises(ParameterError, match=name):
            SimOptions(**{name: True})
    with pytest.raises(ParameterError, match="rate"):
        SimOptions(rate=0.0)
    with pytest.raises(ParameterError, match="engine"):
        SimOptions(engine="nope")


def test_status_check_by_hand():
    """status.check on x = (q, qd, z) and u against (q_max, qd_max, u_max) = (1, 2, 3): a value equal
    to its bound is inside it; each bound, a NaN state (also in z), a NaN torque give their codes; the
    first failing joint decides, joint by joint (q before qd before u at one joint)."""
    lim = np.array([1.0, 2.0, 3.0])
    ok_x = np.array([1.0, -1.0, 2.0, -2.0, 5.0])  # n = 2, z = (5,) is not bounded
    u = np.array([3.0, -3.0])
    assert S.check(ok_x, u, lim) == S.OK
    assert S.check(np.array([1.0 + 1e-12, 0, 0, 0, 0.0]), u, lim) == S.QBOUND
    assert S.check(np.array([0, -1.5, 0, 0, 0.0]), u, lim) == S.QBOUND
    assert S.check(np.array([0, 0, 0, -2.0 - 1e-12, 0.0]), u, lim) == S.QDBOUND
    assert S.check(np.array([0, 0, 2.5, 0, 0.0]), u, lim) == S.QDBOUND
    assert S.check(ok_x, np.array([0.0, 3.0 + 1e-12]), lim) == S.UBOUND
    assert S.check(ok_x, np.array([-3.5, 0.0]), lim) == S.UBOUND
    assert S.check(np.array([0, 0, 0, 0, np.nan]), u, lim) == S.NONFINITE
    assert S.check(np.array([0, 0, np.inf, 0, 0.0]), u, lim) == S.NONFINITE
    assert S.check(ok_x, np.array([0.0, np.nan]), lim) == S.NONFINITE
    # joint 1's |u| bound comes before joint 2's |q| bound; joint 1's |qd| before its |u|
    assert S.check(np.array([0, 1.5, 0, 0, 0.0]), np.array([4.0, 0.0]), lim) == S.UBOUND
    assert S.check(np.array([0, 0, 2.5, 0, 0.0]), np.array([4.0, 0.0]), lim) == S.QDBOUND
    assert (S.OK, S.NONFINITE, S.QBOUND, S.QDBOUND, S.UBOUND, S.NOTPD, S.HMIN, S.INTERRUPTED, S.WORK) == \
        tuple(range(9))


def test_divergence_messages_name_the_bound(spec):
    """The message of each stop, by hand: the bound's value and unit for |q|, |qd|, |u|; the time with
    6 significant digits; for the work budget the law's eps (its smallest eps_i for a per-joint law)."""
    from rc3r.simulate import _message

    opt = SimOptions(q_max=2.5, qd_max=30.0, u_max=400.0, max_steps=5e3)
    assert _message(S.OK, 1.0, opt) == "finished at t = 1 s"
    assert _message(S.QBOUND, 0.1234567, opt) == "diverged at t = 0.123457 s: |q| exceeded its bound (2.5 rad)"
    assert _message(S.QDBOUND, 1.0, opt) == "diverged at t = 1 s: |qd| exceeded its bound (30 rad/s)"
    assert _message(S.UBOUND, 2.0, opt) == "diverged at t = 2 s: |u| exceeded its bound (400 N m)"
    assert _message(S.NONFINITE, 3.0, opt) == "diverged at t = 3 s: state became NaN or infinite"
    assert _message(S.INTERRUPTED, 0.5, opt).startswith("interrupted at t = 0.5 s")

    per_coefficient = rc3r.make_law("robust-coeff", np.ones(3), rho_i=np.ones(3), eps_i=[0.3, 0.02, 0.5])
    msg = _message(S.WORK, 0.25, opt, per_coefficient)
    assert msg.startswith("stopped at t = 0.25 s: the integrator needed more than 5000 steps per simulated second")
    assert "eps = 0.02 makes the loop too stiff" in msg
    assert "eps = 0.5 makes" in _message(S.WORK, 0.25, opt, rc3r.make_law("robust", np.ones(3), rho=1.0, eps=0.5))
    assert "(the loop is too stiff;" in _message(S.WORK, 0.25, opt, rc3r.make_law("fbl", np.ones(3)))
    assert "(the loop is too stiff;" in _message(S.WORK, 0.25, opt)


def test_a_run_starts_on_the_trajectory_or_at_the_given_state(spec):
    """x0 omitted: the first row is q_d(0), qd_d(0) of the trajectory and z the law's initial state;
    x0 given: the first row is x0; x0 of the wrong size or not finite is refused in one line."""
    law = rc3r.make_law("adaptive", spec.law.theta)
    opt = SimOptions(duration=0.002, rate=1000.0, engine="python")
    res = simulate(spec.true_rigid, law, spec.trajectory, opt)
    q0, qd0, _ = spec.trajectory.evaluate(0.0)
    np.testing.assert_array_equal(res.q[0], q0)
    np.testing.assert_array_equal(res.qd[0], qd0)
    np.testing.assert_array_equal(res.z[0], law.initial_state())
    x0 = np.r_[q0 + 0.01, qd0 - 0.02]
    res = simulate(spec.true_rigid, law, spec.trajectory, opt, x0=x0)
    np.testing.assert_array_equal(np.r_[res.q[0], res.qd[0]], x0)
    for bad in (np.zeros(5), np.r_[np.zeros(5), np.nan]):
        with pytest.raises(ParameterError, match="initial state must be 6 finite numbers"):
            simulate(spec.true_rigid, law, spec.trajectory, opt, x0=bad)
    assert math.isclose(res.t_end, 0.002) and res.outcome == "finished" and res.message == "finished at t = 0.002 s"


def test_stored_desired_positions_are_the_trajectorys(spec):
    """q_des of a sampled run is the trajectory's position at each stored sample (not its velocity
    or acceleration row), in the python engine as in the reference."""
    law = rc3r.make_law("fbl", spec.true_rigid.theta)
    res = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=0.01, rate=1000.0, engine="python"))
    for i in (0, 3, 10):
        np.testing.assert_allclose(res.q_des[i], spec.trajectory.evaluate(res.t[i])[0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(res.e, res.q - res.q_des, rtol=0, atol=0)


def test_a_trajectory_or_model_of_another_size_is_refused(spec):
    """The parts must have the plant's joint count: a 2-joint trajectory (fewer) or a 4-joint one
    (more) on the 3R is refused in one line, as is a law with another coefficient count."""
    from rc3r.trajectory import Sines

    law = rc3r.make_law("fbl", spec.true_rigid.theta)
    for n in (2, 4):
        traj = Sines((0.0,) * n, tuple((j, 0.1, 1.0, 0.0) for j in range(1, n + 1)))
        with pytest.raises(ParameterError, match=f"trajectory has {n} joints, robot 'nominal' has 3"):
            simulate(spec.true_rigid, law, traj, SimOptions(duration=0.01, engine="python"))
    with pytest.raises(ParameterError, match="coefficients"):
        simulate(spec.true_rigid, rc3r.make_law("fbl", np.zeros(14)), spec.trajectory, SimOptions(duration=0.01))


def test_python_steps_are_scipys_radau_steps(spec):
    """The continuous python engine steps SciPy's Radau itself: its accepted steps equal those of
    solve_ivp(method='Radau') on the same right-hand side and tolerances (len(sol.t) - 1 without
    t_eval), and its right-hand-side count is at least the steps."""
    from scipy.integrate import solve_ivp

    from rc3r.simulate._python import _Loop

    law = rc3r.make_law("fbl", spec.law.theta)
    opt = SimOptions(duration=0.2, engine="python")
    res = simulate(spec.true_rigid, law, spec.trajectory, opt)
    loop = _Loop(as_plant(spec.true_rigid), law, spec.trajectory)
    x0 = np.concatenate([*spec.trajectory.evaluate(0.0)[:2], law.initial_state()])
    sol = solve_ivp(loop.rhs, (0.0, 0.2), x0, method="Radau", rtol=opt.rtol, atol=opt.atol)
    assert sol.success and res.ok
    assert res.steps == len(sol.t) - 1
    assert res.rhs_evals == loop.nrhs
    np.testing.assert_allclose(res.q[-1], sol.y[:3, -1], rtol=0, atol=1e-12)


def test_mujoco_plant_in_the_python_engine_equals_the_pinocchio_plant():
    """A rigid body that integrates itself (MuJoCo's advance) in the python engine: UR5, FBL at
    1 kHz over 0.05 s, equal to the Pinocchio plant's RK4 within 1e-8 rad (the CLI's 1 s comparison
    measured 1e-11); a joint-torque effect (friction) on it is refused in one line, an actuator map
    (a torque limit) is accepted."""
    pytest.importorskip("mujoco")
    kw = dict(robot="ur5", controller="fbl", rate=1000.0, duration=0.05)
    pin_run = rc3r.build_run(**kw)
    mj_run = rc3r.build_run(plant_engine="mujoco", **kw)
    opt = SimOptions(duration=0.05, rate=1000.0, engine="python")
    a = simulate(pin_run.true_plant, pin_run.law, pin_run.trajectory, opt, model=pin_run.true_rigid)
    b = simulate(mj_run.true_plant, mj_run.law, mj_run.trajectory, opt, model=mj_run.true_rigid)
    assert a.ok and b.ok and a.q.shape == b.q.shape == (51, 6)
    assert np.max(np.abs(a.q - b.q)) < 1e-8 and np.max(np.abs(a.qd - b.qd)) < 1e-6
    assert np.ptp(b.q, axis=0).max() > 1e-3  # the arm moves
    fr = rc3r.build_run(plant_engine="mujoco", friction="1:0.5", **kw)
    with pytest.raises(ParameterError, match="joint-torque effects"):
        simulate(fr.true_plant, fr.law, fr.trajectory, opt, model=fr.true_rigid)
    sat = rc3r.build_run(plant_engine="mujoco", torque_limit=1e4, **kw)
    assert simulate(sat.true_plant, sat.law, sat.trajectory, opt, model=sat.true_rigid).ok


@pytest.mark.parametrize("which", ["q", "qd"])
def test_continuous_python_run_stops_where_the_bound_is_crossed(spec, which):
    """Continuous time, exact FBL tracking q_d2 = 2 sin t (|q| bound) or 2 cos t (qd_d2 = -2 sin t,
    |qd| bound), the other joints sin t: |q2| or |qd2| reaches 1.5 at t = asin(0.75) = 0.84806 s.
    The python engine locates the crossing on its step's dense output (brentq, xtol 1e-12): t_end
    within 1e-6 s of it (exact FBL tracks to ~1e-9 rad here), the status names the bound crossed,
    every stored row is inside the bound and the last one within 1 ms of the crossing."""
    from rc3r.trajectory import Sines

    phase = {"q": 0.0, "qd": np.pi / 2}[which]
    traj = Sines((0.0, 0.0, 0.0), ((1, 1.0, 1.0, 0.0), (2, 2.0, 1.0, phase), (3, 1.0, 1.0, 0.0)))
    law = rc3r.make_law("fbl", spec.true_rigid.theta)
    bounds = {"q": dict(q_max=1.5), "qd": dict(qd_max=1.5)}[which]
    res = simulate(spec.true_rigid, law, traj, SimOptions(duration=1.0, engine="python", **bounds))
    unit = {"q": "rad", "qd": "rad/s"}[which]
    assert res.outcome == "diverged" and f"|{which}| exceeded its bound (1.5 {unit})" in res.message
    assert res.t_end == pytest.approx(np.arcsin(0.75), abs=1e-6)
    x = res.q if which == "q" else res.qd
    assert np.max(np.abs(x)) <= 1.5 and res.t[-1] <= res.t_end < res.t[-1] + 1e-3


def test_documented_defaults():
    """SimOptions' defaults as its docstring and docs/control.md state them: 10 s (the paper's),
    continuous, a 1 kHz stored grid, rtol 1e-6 / atol 1e-8, jac_reuse 5, a work budget of 1e6 steps
    per simulated second, bounds 1e3 rad, 1e4 rad/s, 1e7 N m."""
    o = SimOptions()
    assert (o.duration, o.rate, o.output_rate, o.rtol, o.atol, o.nsub, o.engine, o.jac_reuse, o.max_steps) == \
        (10.0, None, 1000.0, 1e-6, 1e-8, None, "auto", 5, 1e6)
    assert (o.q_max, o.qd_max, o.u_max) == (1e3, 1e4, 1e7)


@pytest.mark.parametrize("duration", [0.5, 2.0])
def test_python_budget_scales_with_the_duration(spec, duration):
    """The continuous python engine's budget is 10 max_steps x duration + 1000 right-hand-side
    evaluations (RHS_PER_STEP = 10): with max_steps = 50 and eps = 1e-6 (a loop far too stiff) the
    run stops having made exactly that many, 1250 for 0.5 s and 2000 for 2 s."""
    from rc3r.controllers import Robust

    law = Robust(spec.law.theta, rho=spec.law.rho, eps=1e-6)
    res = simulate(spec.true_rigid, law, spec.trajectory, SimOptions(duration=duration, max_steps=50.0, engine="python"))
    assert res.outcome == "diverged" and "more than 50 steps per simulated second" in res.message
    assert res.rhs_evals == int(10 * 50 * duration) + 1000
    assert res.t_end < duration
