"""The one compiled engine (rc3r.simulate.engines): instantiated per kernel supply, it runs the 3R's closed
form and any Pinocchio chain. Each property is checked against an independent source: the chain's compiled
forward dynamics against pinocchio.aba, the compiled engine against the python engine (Pinocchio ABA + the
same RK4, written separately in rc3r.simulate._python) sampled, and against the reference engine (Radau at
rtol 1e-11) continuous; effects against the python engine's Python effects."""
from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numba import njit

import rc3r
from rc3r.errors import ParameterError
from rc3r.plants import Friction, LoopEffects, Plant, Saturation
from rc3r.simulate import ENGINES, SimOptions, simulate

SRC = Path(__file__).resolve().parents[1] / "src"


@pytest.fixture(scope="module")
def ur5():
    return rc3r.load_robot("ur5")


@pytest.fixture(scope="module")
def panda():
    return rc3r.load_robot("panda")


def _states(robot, rng, N):
    q = rng.uniform(-np.pi, np.pi, (N, robot.n))
    qd, tau = rng.uniform(-3.0, 3.0, (N, robot.n)), rng.uniform(-40.0, 40.0, (N, robot.n))
    return q, qd, tau


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_chain_forward_dynamics_equals_aba(name, rng):
    """The chain's compiled forward dynamics (world-frame Newton--Euler + CRBA + Cholesky) equals
    pinocchio.aba at 200 seeded random states to 1e-10 relative to max |qdd| per state (measured 3.5e-15 on
    UR5 and 7.5e-14 on Panda: the gap is only rounding, two different algorithms)."""
    import pinocchio as pin

    robot = rc3r.load_robot(name)
    q, qd, tau = _states(robot, rng, 200)
    got = robot.kernel.forward_dynamics(np.array([q, qd, tau]), robot.standard_parameters())
    data = robot.model.createData()
    ref = np.array([pin.aba(robot.model, data, *x) for x in zip(q, qd, tau)])
    assert np.all(np.abs(got - ref) <= 1e-10 * np.abs(ref).max(axis=1, keepdims=True))


@njit
def _supply_calls(fd, reg, make_work, kc, q, qd, v, a, tau, Y, qdd):
    wk = make_work(kc)
    reg(kc, q, qd, v, a, Y, wk)
    return fd(kc, q, qd, tau, qdd, wk)


@pytest.mark.slow
def test_chain_supply_entry_points_equal_the_robot(ur5, rng):
    """The supply's regressor_into (base-parameter columns) equals Pinocchio's two-regressor reference path
    (1e-12 relative), and forward_dynamics_into on a payload plant's constants equals that plant's
    pinocchio.aba (1e-10): the engine sees the plant through these two functions only."""
    from rc3r.robots import pinocchio_supply as PK
    from rc3r.simulate import _fast
    from rc3r.uncertainty.payload import with_payload

    plant = with_payload(ur5, 3.0, (0.0, 0.0, 0.1))
    module, kc = plant.compiled_kernels
    assert module == PK.__name__ and _fast.simulator(plant).module == module
    for _ in range(5):
        q, qd, tau = (x[0] for x in _states(plant, rng, 1))
        v, a = rng.uniform(-3.0, 3.0, (2, plant.n))
        Y, qdd = np.empty((plant.n, plant.p)), np.empty(plant.n)
        ok = _supply_calls(PK.forward_dynamics_into, PK.regressor_into, PK.make_work, kc, q, qd, v, a, tau, Y, qdd)
        ref_y = plant.regressor_pinocchio(q, qd, v, a)
        assert ok and np.abs(Y - ref_y).max() <= 1e-12 * np.abs(ref_y).max()
        ref = plant.forward_dynamics(q, qd, tau)
        assert np.abs(qdd - ref).max() <= 1e-10 * np.abs(ref).max()


def _ur5_spec(controller, engine, duration=1.0, **kw):
    from rc3r.controllers import inertia_scaled_gain

    robot = rc3r.load_robot("ur5")
    k = inertia_scaled_gain(robot, robot.default_trajectory().evaluate(0.0)[0], 50.0)
    gains = {"robust": {"K": k.tolist(), "Lambda": 20.0, "eps": 5.0}}  # examples/ur5_payload.toml
    return rc3r.build_run(robot="ur5", controller=controller, rate=1000.0, duration=duration, engine=engine,
                          config={"gains": gains}, **kw)


@pytest.mark.parametrize("controller, payload", [("fbl", False), ("fbl", True), ("robust", True)])
def test_ur5_sampled_compiled_equals_python(controller, payload):
    """UR5 (with and without an unknown 0..5 kg payload: plant at 5 kg) at 1 kHz for 1 s: the compiled engine
    equals the python engine (pin.aba + its own RK4, 4 sub-steps) to 1e-8 rad, and its torques to 1e-6 N m
    (measured ~1e-16 rad: the same arithmetic up to rounding)."""
    kw = dict(perturbed=True, payload=(0.0, 5.0), payload_com=(0, 0, 0.1)) if payload else {}
    fast = rc3r.execute(_ur5_spec(controller, "compiled", **kw))[0]
    py = rc3r.execute(_ur5_spec(controller, "python", **kw))[0]
    assert fast.ok and py.ok and fast.engine == "fast" and py.engine == "python"
    assert fast.t.size == py.t.size == 1001
    assert np.abs(fast.q - py.q).max() <= 1e-8
    assert np.abs(fast.u - py.u).max() <= 1e-6
    np.testing.assert_allclose(fast.tv_exact, py.tv_exact, rtol=1e-8)


def test_ur5_continuous_compiled_matches_reference():
    """UR5 FBL in continuous time (0.3 s, perturbed by a 5 kg payload): the compiled Rosenbrock against the
    reference engine (Radau rtol 1e-11 on pin.aba) within the 3R's stated accuracy: |q| to 3e-6 rad,
    e to 0.1 % of max |e|, u to 1 % of max |u|."""
    kw = dict(perturbed=True, payload=(0.0, 5.0), payload_com=(0, 0, 0.1))
    spec = _ur5_spec("fbl", "compiled", duration=0.3, **kw)
    spec = replace(spec, options=replace(spec.options, rate=None))
    fast = simulate(spec.true_rigid, spec.law, spec.trajectory, spec.options)
    ref = simulate(spec.true_rigid, spec.law, spec.trajectory, replace(spec.options, engine="reference"))
    assert fast.ok and ref.ok and fast.engine == "fast"
    np.testing.assert_array_equal(fast.t, ref.t)
    assert np.abs(fast.q - ref.q).max() <= 3e-6
    assert np.abs(fast.e - ref.e).max() <= 1e-3 * np.abs(ref.e).max()
    assert np.abs(fast.u - ref.u).max() <= 0.01 * np.abs(ref.u).max()


def _effects_run(robot, spec_kw, engine, limit):
    n = robot.n
    plant = Plant(robot, [Friction(viscous=np.full(n, 0.8), coulomb=np.full(n, 0.5), offset=np.full(n, 0.05),
                                   v_s=0.05), Saturation(limit=np.full(n, limit))])
    loop = LoopEffects(n, noise_q=1e-4, noise_qd=1e-3, quantization=2 * np.pi / 2**16, delay=2, seed=11,
                       q0_error=0.01)
    spec = rc3r.build_run(rate=1000.0, duration=0.5, **spec_kw)
    return simulate(plant, spec.law, spec.trajectory, replace(spec.options, engine=engine), loop=loop,
                    model=robot)


@pytest.mark.parametrize("robot_name, limit", [("rr3", 60.0), ("ur5", 30.0)])
def test_plant_and_loop_effects_compiled_equal_python(robot_name, limit):
    """Friction (viscous, tanh Coulomb, offset), saturation, sensor noise, encoder quantization, a 2-sample
    delay and an initial error: the compiled engine (fields fx, compiled measure and delay line) equals the
    python engine (the effects' Python methods) to 1e-8 rad, on the 3R and on the UR5; the saturation is
    active (some |u| at the limit) and friction changes the run (vs no friction) by far more than 1e-8."""
    robot = rc3r.load_robot(robot_name)
    kw = dict(robot=robot_name, controller="fbl")
    fast, py = _effects_run(robot, kw, "fast", limit), _effects_run(robot, kw, "python", limit)
    assert fast.ok and py.ok
    assert np.abs(fast.q - py.q).max() <= 1e-8
    assert np.abs(fast.u - py.u).max() <= 1e-6
    assert np.isclose(np.abs(fast.u).max(), limit)
    spec = rc3r.build_run(rate=1000.0, duration=0.5, **kw)
    bare = simulate(Plant(robot, [Saturation(limit=np.full(robot.n, limit))]), spec.law, spec.trajectory,
                    spec.options, loop=LoopEffects(robot.n, noise_q=1e-4, noise_qd=1e-3, quantization=2 * np.pi / 2**16,
                                                   delay=2, seed=11, q0_error=0.01))
    assert np.abs(bare.q - fast.q).max() > 1e-5


def test_engine_names_aliases_and_registry():
    """'compiled' is an alias of 'fast' (the result records 'fast'); a registered engine is accepted by
    SimOptions and run by simulate; an unknown name is refused; a robot without kernels names why."""
    from rc3r.simulate import engines as E

    assert {"auto", "fast", "compiled", "python", "reference"} <= set(ENGINES)
    spec = rc3r.build_run(controller="fbl", duration=0.02, engine="compiled")
    assert simulate(spec.true_rigid, spec.law, spec.trajectory, spec.options).engine == "fast"

    class Echo(E.Engine):
        name = "echo-test"

        def run(self, plant, law, trajectory, options, x0, loop=None, model=None):
            from rc3r.simulate._python import run

            return run(plant, law, trajectory, replace(options, engine="python"), x0, loop, model)

    E.register_engine(Echo())
    try:
        opt = SimOptions(duration=0.02, rate=1000.0, engine="echo-test")
        assert simulate(spec.true_rigid, spec.law, spec.trajectory, opt).ok
    finally:
        E.ENGINES.pop("echo-test")
    with pytest.raises(ParameterError, match="engine must be one of"):
        SimOptions(engine="echo-test")

    class NoKernels(type(rc3r.load_robot())):
        compiled_kernels = None

    arm = NoKernels.nominal()
    with pytest.raises(ParameterError, match="has no compiled simulator"):
        simulate(arm, spec.law, spec.trajectory, SimOptions(duration=0.02, engine="fast"))


def test_bad_kernel_supply_is_refused():
    """A supply that is no module, or lacks a kernel, is one ParameterError naming what is missing."""
    from rc3r.simulate._fast import instantiate

    with pytest.raises(ParameterError, match="dotted module name"):
        instantiate("not a module; import os")
    with pytest.raises(ParameterError, match="lacks make_work, regressor_into, forward_dynamics_into, passes_into, xi_into, apply_into"):
        instantiate("rc3r.errors")


_PROBE = r"""
import os, sys, time
import rc3r
from rc3r.simulate import _fast
spec = rc3r.build_run(robot=sys.argv[1], controller="fbl", duration=0.002, rate=1000.0)
t0 = time.perf_counter()
res = rc3r.simulate(spec.true_rigid, spec.law, spec.trajectory, spec.options)
sim = _fast.simulator(spec.true_rigid).instance
print("FILE", sim.__file__, os.stat(sim.__file__).st_mtime_ns, res.outcome, res.engine,
      "%.1f" % (time.perf_counter() - t0))
"""


@pytest.mark.slow
def test_instantiation_is_written_once_and_cached(tmp_path):
    """In a fresh NUMBA_CACHE_DIR the first process writes the instantiated module under it and compiles;
    a second process finds the same file (not rewritten: same mtime, so numba's stamp holds) and loads the
    compiled code from the cache (measured: UR5 about 60 s cold on 2 busy cores, 2-5 s warm)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_DISABLE_JIT", None)

    def probe():
        out = subprocess.run([sys.executable, "-c", _PROBE, "ur5"], env=env, capture_output=True, text=True,
                             timeout=900)
        assert out.returncode == 0, out.stderr
        return [ln for ln in out.stdout.splitlines() if ln.startswith("FILE")][0].split()

    first, second = probe(), probe()
    assert first[1].startswith(str(tmp_path / "rc3r_engines")) and first[3:5] == ["finished", "fast"]
    assert first[1:3] == second[1:3]
    assert float(second[5]) < float(first[5])


def test_is_cached_looks_only_at_the_integrator_the_run_needs(tmp_path, monkeypatch, capsys):
    """A sampled-only history (the sampled integrator's numba index holds an entry valid for this source,
    the continuous one's none): is_cached("sampled") is True, is_cached("continuous") and is_cached()
    False, and the command line's compile announcement is silent for a sampled run and speaks for a
    continuous one."""
    from types import SimpleNamespace

    from rc3r.cli.run import announce_compile
    from rc3r.simulate import _fast

    def disp(index):
        return SimpleNamespace(overloads={}, _cache=SimpleNamespace(
            _cache_file=SimpleNamespace(_load_index=lambda: dict(index))))

    fake = SimpleNamespace(integrate_sampled=disp({("sig",): "entry"}), integrate_continuous=disp({}))
    monkeypatch.setattr(_fast, "instantiate", lambda module: fake)
    eng = _fast.CompiledSimulator("x")
    assert eng.is_cached("sampled") and not eng.is_cached("continuous") and not eng.is_cached()
    plant = SimpleNamespace(compiled_kernels=("x", None), n=6)
    announce_compile(plant, 1000.0)
    assert capsys.readouterr().err == ""
    announce_compile(plant, None)
    assert "compiling the simulator's kernels" in capsys.readouterr().err


@pytest.mark.parametrize("law", ["robust", "adaptive"])
def test_scheduled_k_compiled_equals_python(law):
    """The scheduled K(q) = b M(q) (``K_inertia``, rc3r design's default) on the UR5 with a 0..5 kg
    payload (plant at 5 kg) at 1 kHz for 1 s: the compiled engine (M(q) r from one acceleration pass on
    the kinematics of the chain supply's regressor pass) equals the python engine (two Pinocchio-path
    regressors) to 1e-8 rad and 1e-6 N m."""
    gains = {"robust": {"K": 0.0, "K_inertia": 25.0, "Lambda": 10.0, "eps": 5.0},
             "adaptive": {"K": 0.5, "K_inertia": 25.0, "Lambda": 10.0, "Gamma": 1.0}}
    kw = dict(perturbed=True, payload=(0.0, 5.0), payload_com=(0, 0, 0.1))
    runs = [rc3r.execute(rc3r.build_run(robot="ur5", controller=law, rate=1000.0, duration=1.0, engine=engine,
                                        config={"gains": gains}, **kw))[0] for engine in ("compiled", "python")]
    fast, py = runs
    assert fast.ok and py.ok and fast.engine == "fast" and py.engine == "python"
    assert np.abs(fast.q - py.q).max() <= 1e-8
    assert np.abs(fast.u - py.u).max() <= 1e-6
    assert np.abs(fast.e).max() < 0.05  # the scheduled loop tracks (0.0118 rad measured)


@pytest.mark.parametrize("n", [1, 3, 6, 12])
def test_lu_solve_equals_numpy_solve(n, rng):
    """_lu_factor + _lu_solve (partial pivoting) == numpy.linalg.solve to 1e-12 relative on random
    (well-conditioned: A = I * n + R) and row-permuted systems; an exact zero pivot column is refused."""
    from rc3r.simulate.engines._linalg import _lu_factor, _lu_solve

    for A in (np.eye(n) * n + rng.standard_normal((n, n)), rng.standard_normal((n, n))[rng.permutation(n)]):
        b = rng.standard_normal(n)
        LU, piv, x = A.copy(), np.zeros(n, dtype=np.int64), b.copy()
        assert _lu_factor(LU, piv)
        _lu_solve(LU, piv, x)
        ref = np.linalg.solve(A, b)
        assert np.abs(x - ref).max() <= 1e-12 * np.linalg.cond(A) * max(1.0, np.abs(ref).max())
    Z = rng.standard_normal((n, n)); Z[:, 0] = 0.0
    assert not _lu_factor(Z, np.zeros(n, dtype=np.int64))


_ONE_JOINT = """<?xml version="1.0"?>
<robot name="spinner">
  <link name="base"/>
  <link name="rotor">
    <inertial><origin xyz="0 0 0"/><mass value="0.5"/>
      <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
  </link>
  <joint name="spin" type="revolute"><parent link="base"/><child link="rotor"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="50" velocity="20"/><dynamics damping="10" friction="0"/></joint>
</robot>
"""


@pytest.mark.parametrize("engine, method", [("fast", "auto"), ("fast", "ros4"), ("python", "auto")])
def test_stiff_viscous_plant_period_map_is_the_exponential(engine, method, tmp_path):
    """A rotor about the gravity axis (M = I = 1e-4 kg m^2, no gravity torque) with its URDF's viscous
    damping F = 10 N m s/rad: a time constant I / F = 10 us, 200 times shorter than a 2 ms period, where
    RK4 at the 0.25 ms friction step would blow up (h F / I = 25 > 2.79). ``sampled_method = "auto"``
    takes the implicit path (SDIRK3 compiled, Radau in python; ``"ros4"``: the ROS4 periods), and every
    period is the exact solution of I qdd = u - F qd under the held u:
    qd(T) = u/F + (qd0 - u/F) exp(-F T / I), q(T) = q0 + (u/F) T + (qd0 - u/F)(1 - exp(-F T / I)) I / F.
    At period_rtol 1e-4, period_atol 1e-6 (every method's default until SDIRK3's became 1e-5, 1e-7: the
    bounds hold on either) measured: qd within 1.1e-8 rad/s (fast, ROS4), 5.5e-8 (fast, SDIRK3) and
    4.3e-10 (python), q within 1.1e-13 and 4.3e-15 rad. Bounds: qd 1e-7 (a tenth of ROS4's period_atol), q 1e-9, far below a wrong step (a period integrated over 1 % less time is off by
    3.2e-8 rad in q; checked by hand, docs/testing.md)."""
    from rc3r.simulate import plant_method

    path = tmp_path / "spinner.urdf"
    path.write_text(_ONE_JOINT)
    spec = rc3r.build_run(urdf=str(path), controller="fbl", rate=500.0, duration=0.2, friction="urdf",
                          engine=engine)
    opt = replace(spec.options, sampled_method=method)
    assert plant_method(spec.true_plant, opt) == ("sdirk" if method == "auto" else method)
    res = simulate(spec.true_plant, spec.law, spec.trajectory, opt, x0=[0.1, 5.0])  # decays in 10 us
    assert res.ok and res.engine == engine and len(res.t) == 101
    I, F, T = 1e-4, 10.0, 1.0 / 500.0
    q0, qd0, u = res.q[:-1, 0], res.qd[:-1, 0], res.u[:-1, 0]
    decay = np.exp(-F * T / I)
    qd1 = u / F + (qd0 - u / F) * decay
    q1 = q0 + u / F * T + (qd0 - u / F) * (1.0 - decay) * I / F
    assert abs(qd1[0] - 5.0) > 4.0  # the first period's decay is tested, not a resting rotor
    assert np.abs(res.qd[1:, 0] - qd1).max() <= 1e-7
    assert np.abs(res.q[1:, 0] - q1).max() <= 1e-9


@pytest.mark.parametrize("method", ["sdirk", "ros4"])
def test_stiff_period_work_budget_stops_the_run_with_its_cause(method, tmp_path):
    """An SDIRK3 or ROS4 period that needs more steps than its budget (max(100, max_steps T); here period_rtol
    1e-14 on the 10 us rotor, max_steps 1/s) ends the run as ``diverged`` with a one-line message naming the
    method, the period's budget and the two ways out, and keeps the rows before it; it does not hang."""
    path = tmp_path / "spinner.urdf"
    path.write_text(_ONE_JOINT)
    spec = rc3r.build_run(urdf=str(path), controller="fbl", rate=500.0, duration=0.2, friction="urdf",
                          engine="fast")
    opt = replace(spec.options, period_rtol=1e-14, period_atol=1e-16, max_steps=1.0, sampled_method=method)
    res = simulate(spec.true_plant, spec.law, spec.trajectory, opt, x0=[0.1, 5.0])
    assert res.outcome == "diverged" and len(res.t) >= 1
    assert f"a {method.upper()} period of the plant needed more than 100 steps" in res.message
    assert "max_steps" in res.message and 'sampled_method = "rk4"' in res.message and "\n" not in res.message


def test_sdirk_period_cost_does_not_grow_with_the_damping(tmp_path):
    """The SDIRK3 periods' cost is set by the motion, not by how fast the friction damps the joint: the
    rotor of :data:`_ONE_JOINT` with its viscous damping F = 10, 1e3 and 1e5 N m s/rad (time constants
    I / F = 10 us, 0.1 us, 1 ns; lambda = F / I from 1e5 to 1e9 1/s) under the same FBL run at 500 Hz
    costs no more right-hand sides per period at F = 1e3 and 1e5 than at F = 10 (measured 15.4, 8.1 and 6.0:
    Newton's matrix carries the friction's slope, so a stiffer damping converges no slower, and the
    stiffly accurate stages annihilate the transient), and every period still lands on the closed form of
    :func:`test_stiff_viscous_plant_period_map_is_the_exponential` (q within 1e-9 rad; measured 5.5e-13,
    7.2e-11, 7.2e-15)."""
    counts = []
    for F in (10.0, 1e3, 1e5):
        path = tmp_path / f"spinner{F:g}.urdf"
        path.write_text(_ONE_JOINT.replace('damping="10"', f'damping="{F:g}"'))
        spec = rc3r.build_run(urdf=str(path), controller="fbl", rate=500.0, duration=0.2, friction="urdf",
                              engine="fast")
        res = simulate(spec.true_plant, spec.law, spec.trajectory, spec.options, x0=[0.1, 5.0])
        assert res.ok and res.options.sampled_method == "sdirk"
        I, T = 1e-4, 1.0 / 500.0
        q0, qd0, u = res.q[:-1, 0], res.qd[:-1, 0], res.u[:-1, 0]
        decay = np.exp(-F * T / I)
        q1 = q0 + u / F * T + (qd0 - u / F) * (1.0 - decay) * I / F
        assert np.abs(res.q[1:, 0] - q1).max() <= 1e-9
        counts.append(res.rhs_evals / (len(res.t) - 1))
    assert max(counts[1:]) <= counts[0], counts


def _coulomb_time(v, u, F, s, inertia):
    """The closed form ``t(v)`` (up to a constant) of ``I dv/dt = u - F tanh(v / s)`` under a held ``u`` (|u| != F):
    ``dt = I dv / (u - F tanh(v/s))``; with ``w = exp(2 v / s)``, ``u - F tanh = ((u - F) w + (u + F)) / (w + 1)``,
    and partial fractions give ``t = I (v / (u + F) + s F / (u^2 - F^2) ln|(u - F) w + (u + F)|)`` (checked by
    differentiating by hand; the log's argument keeps its sign along a path, it vanishes only at the sticking
    speed ``s atanh(u / F)``, which the flow approaches but never crosses). Written without overflow for
    large |v| / s."""
    x = v / s
    big = x > 0
    g = np.where(big, (u - F) + (u + F) * np.exp(-2.0 * np.abs(x)), (u - F) * np.exp(-2.0 * np.abs(x)) + (u + F))
    log_g = np.log(np.abs(g)) + np.where(big, 2.0 * x, 0.0)
    return inertia * (v / (u + F) + s * F / (u * u - F * F) * log_g)


def _coulomb_period(qd0, u, F, s, inertia, T):
    """The exact end speed of a period ``T`` of ``I dv/dt = u - F tanh(v / s)`` from ``qd0`` under ``u``
    (arrays): the root of ``t(v) - t(qd0) = T`` (:func:`_coulomb_time`) on the path from ``qd0``, by bisection
    to rounding. The path moves the way ``u - F tanh(qd0 / s)`` points, by at most ``(|u| + F) T / I``, and
    never past the sticking speed ``s atanh(u / F)`` when |u| < F; along it ``t`` grows from ``t(qd0)``."""
    up = u - F * np.tanh(qd0 / s) > 0
    end = qd0 + np.where(up, u + F, u - F) * T / inertia
    stick = np.abs(u) < F
    veq = s * np.arctanh(np.clip(u / F, -1 + 1e-16, 1 - 1e-16))
    end = np.where(stick & up, np.minimum(end, veq), np.where(stick & ~up, np.maximum(end, veq), end))
    t0 = _coulomb_time(qd0, u, F, s, inertia)
    lo, hi = np.zeros_like(qd0), np.ones_like(qd0)
    with np.errstate(divide="ignore"):
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            late = _coulomb_time(qd0 + mid * (end - qd0), u, F, s, inertia) - t0 >= T
            hi, lo = np.where(late, mid, hi), np.where(late, lo, mid)
    return qd0 + 0.5 * (lo + hi) * (end - qd0)


def test_coulomb_rotor_periods_satisfy_the_closed_form(tmp_path):
    """A rotor (I = 1e-4 kg m^2, no gravity torque) with only the smooth Coulomb friction of its URDF
    (F_c = 5e-3 N m, v_s = 0.01 rad/s: slope F_c / v_s = 0.5 N m s/rad at the knee, lambda = 5e3 1/s, so
    ``"auto"`` takes the SDIRK3 periods with the knee's error control), under a 2 s FBL run at 500 Hz that
    starts at 5 rad/s and then sticks and slips along the reference: every period's end speed equals the
    closed form's (:func:`_coulomb_period`, the root of ``t(qd1) - t(qd0) = T``) within 1e-5 rad/s. Bound:
    the knee's control forgives a step's velocity error up to ``_sdirk.FORGIVE`` = 10 times the tolerances
    (period_atol 1e-6 rad/s) when the rest of the period damps it, so 10 period_atol; measured 2.4e-6
    (the control before it, ``knee=False``, lands as far: the next test); a period integrated over
    1 % less time ends 1e-2 rad/s off. The run must stick and slip: some periods start inside the knee
    (|qd| < v_s), some hold a torque above F_c."""
    path = tmp_path / "coulomb.urdf"
    path.write_text(_ONE_JOINT.replace('damping="10" friction="0"', 'damping="0" friction="0.005"'))
    spec = rc3r.build_run(urdf=str(path), controller="fbl", rate=500.0, duration=2.0, friction="urdf",
                          engine="fast")
    res = simulate(spec.true_plant, spec.law, spec.trajectory, spec.options, x0=[0.1, 5.0])
    assert res.ok and res.options.sampled_method == "sdirk"
    qd0, u = res.qd[:-1, 0], res.u[:-1, 0]
    assert np.sum(np.abs(qd0) < 0.01) > 100 and np.sum(np.abs(u) > 0.005) > 50
    want = _coulomb_period(qd0, u, 0.005, 0.01, 1e-4, 1.0 / 500.0)
    assert np.abs(res.qd[1:, 0] - want).max() <= 1e-5, np.abs(res.qd[1:, 0] - want).max()


def test_sdirk_knee_control_costs_less_than_the_step_filter_on_the_coulomb_rotor(tmp_path):
    """The knee's error control (``_sdirk_period(..., knee=True)``, the default) against the control before
    it (``knee=False``) on every period of the sticking and slipping Coulomb rotor of
    :func:`test_coulomb_rotor_periods_satisfy_the_closed_form`, each period integrated alone from the run's
    state under its held torque: fewer right-hand sides in all (bound 0.8 of the old count; measured 14 846
    against 23 988, 0.62), and every end speed still within 1e-5 rad/s of the closed form
    (:func:`_coulomb_period`; measured 2.37e-6 rad/s, the old control 2.37e-6 too)."""
    from rc3r.simulate._fast import simulator

    path = tmp_path / "coulomb.urdf"
    path.write_text(_ONE_JOINT.replace('damping="10" friction="0"', 'damping="0" friction="0.005"'))
    spec = rc3r.build_run(urdf=str(path), controller="fbl", rate=500.0, duration=2.0, friction="urdf",
                          engine="fast")
    P = spec.true_plant
    res = simulate(P, spec.law, spec.trajectory, spec.options, x0=[0.1, 5.0])
    eng = simulator(P.rigid)
    mod = eng.instance
    kc, fx = eng.constants(P.rigid), P.pack()
    wk, fric, T = mod._make_work(kc), mod._friction(fx, 1), 1.0 / 500.0
    cost, ends = {}, {}
    for knee in (True, False):
        hs, V = np.array([T, 0.0]), np.empty((13, 2))
        Mi, N, piv, tau = np.empty((1, 1)), np.empty((1, 1)), np.zeros(1, dtype=np.int64), np.empty(1)
        cost[knee], ends[knee] = 0, []
        for k in range(len(res.t) - 1):
            x = np.array([res.q[k, 0], res.qd[k, 0]])
            st, nf = mod._sdirk_period(x, res.u[k].copy(), T, hs, kc, wk, fx, fric, tau, V, Mi, N, piv, 1e-4, 1e-6,
                                       10000, knee)
            assert st == 0
            cost[knee] += nf
            ends[knee].append(x[1])
    want = _coulomb_period(res.qd[:-1, 0], res.u[:-1, 0], 0.005, 0.01, 1e-4, T)
    assert np.abs(np.array(ends[True]) - want).max() <= 1e-5
    assert cost[True] <= 0.8 * cost[False], cost


def test_one_joint_arm_regressors_equal_rnea(tmp_path, rng):
    """A one-joint arm (Pinocchio returns its joint Jacobian and its torque regressor as vectors, not
    (6, 1) and (1, 10) matrices): both regressors of the robot, the compiled kernel's and the
    two-computeJointTorqueRegressor reference, times theta equal pin.rnea = I qdd for a rotor about
    the gravity axis (I = 1e-4 kg m^2, no gravity torque). Relative 1e-12: a handful of flops."""
    import pinocchio as pin

    path = tmp_path / "spinner.urdf"
    path.write_text(_ONE_JOINT)
    from rc3r.robots import load_urdf_robot

    robot = load_urdf_robot(path)
    assert robot.n == 1 and robot.p == 1
    q, qd, a = rng.uniform(-3, 3, (3, 20, 1))
    for Y in (robot.regressor(q, qd, qd, a), robot.regressor_pinocchio(q, qd, qd, a)):
        assert Y.shape == (20, 1, 1)
        tau = Y @ robot.theta
        want = np.array([pin.rnea(robot.model, robot.model.createData(), qi, qdi, ai) for qi, qdi, ai in zip(q, qd, a)])
        np.testing.assert_allclose(tau, want, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(tau[:, 0], 1e-4 * a[:, 0], rtol=1e-12)


def _dahlquist_step(T, z):
    """One step of h = 1 of the Rosenbrock table ``T`` (rc3r.simulate.engines._tableaux layout) on
    Dahlquist's y' = z y, y(0) = 1, written out from the transformed form (Hairer & Wanner IV.7):
    (1 / gamma_1 - z) k_i = z (1 + sum_j a_ij k_j) + sum_j c_ij k_j. Returns (R(z), estimate e(z))."""
    s = T.shape[0] - 2
    k, f = [], z
    for i in range(s):
        if T[i, 2]:
            f = z * (1 + sum(T[i, 3 + j] * k[j] for j in range(i)))
        k.append((f + sum(T[i, 3 + s + j] * k[j] for j in range(i))) / (1.0 / T[0, 1] - z))
    return 1 + sum(T[s, j] * k[j] for j in range(s)), sum(T[s + 1, j] * k[j] for j in range(s))


def test_ros4_is_l_stable_and_its_estimate_is_not():
    """The compiled ROS4's table on Dahlquist's equation (:func:`_dahlquist_step`): R(z) -> 0 as z -> -inf
    (L-stable; -1.7e-5 at z = -1e6), R(-0.01) = exp(-0.01) to order 4 (error ~ z^5 / 120 ~ 1e-12 here), and
    the embedded solution R(z) - e(z) tends to 0.55, not 0: the error estimate counts a damped transient as
    error (docs/control.md: why the ROS4 periods' tolerances are 1e-4 / 1e-6)."""
    from rc3r.simulate.engines._tableaux import ROS4

    R, e = _dahlquist_step(ROS4, -1e6)
    assert abs(R) < 1e-4 and 0.5 < abs(R - e) < 0.6
    R, e = _dahlquist_step(ROS4, -0.01)
    assert abs(R - np.exp(-0.01)) < 1e-11 and abs(e) < 1e-8


def test_rodas_is_stiffly_accurate_with_its_estimate():
    """The compiled RODAS table (Hairer & Wanner's rodas.f) on Dahlquist's equation: the solution and the
    embedded one both vanish as z -> -inf (|R|, |R - e| < 1e-6 at z = -1e8, where they are O(1/z): 8.8e-8
    and 4.4e-8; stiffly accurate, unlike ROS4's estimate above), R(-0.01) = exp(-0.01) to order 4 (error
    7e-14, bound 1e-11) with an estimate below 1e-8, and R(-1) within 1e-3 of exp(-1) (3.0e-4; ROS4's is
    3.3e-3). A mistyped coefficient moves one of these by orders of magnitude."""
    from rc3r.simulate.engines._tableaux import RODAS

    R, e = _dahlquist_step(RODAS, -1e8)
    assert abs(R) < 1e-6 and abs(R - e) < 1e-6
    R, e = _dahlquist_step(RODAS, -0.01)
    assert abs(R - np.exp(-0.01)) < 1e-11 and abs(e) < 1e-8
    R, _ = _dahlquist_step(RODAS, -1.0)
    assert abs(R - np.exp(-1.0)) < 1e-3
