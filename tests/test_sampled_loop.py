"""The sampled loop (zero-order hold, delay line, sensor noise, the Euler step of the law's state) is written
once for Python (:class:`rc3r.controllers.sampled.SampledLoop`) and once compiled
(:func:`rc3r.simulate.engines.compiled.integrate_sampled`): the ``python`` engine, the ``fast`` engine and
:meth:`rc3r.Controller.step` driven by an outside loop give the same run on the same plant, law, noise seed and
delay.

Tolerances. ``Controller.step`` and the ``python`` engine share the loop and the test drives the plant with the
engine's own RK4 on the same :meth:`rc3r.plants.Plant.forward_dynamics`: the same arithmetic, so equal to the
last bit (measured 0.0 in q, u and z on 2026-12-06; bound 1e-12). The compiled engine evaluates the 3R's closed
form in numba, whose rounding differs from Python's in the last digits, over 300 samples of a loop that feeds
them back: measured max |dq| 2.8e-17 (adaptive) and 1.5e-14 rad (robust), |du| / max|u| 9.0e-15 and 3.8e-14,
|dz| 1.4e-14 (adaptive; its estimates are O(100)). Bounds 1e-10 rad, 1e-10 of max |u| and 1e-9 in z: four
orders above what rounding gives, five below the sensor noise (1e-5 rad), so a noise sample taken at another
index, a delay of one sample more or less or a state stepped at another time fails them by far.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import rc3r
from rc3r.plants import LoopEffects
from rc3r.simulate import simulate

RATE, DURATION = 1000.0, 0.3


def _outside_loop(spec, loop, nsub):
    """q, u (the delivered torque) and z of ``Controller.step`` driving ``spec.true_plant`` through RK4 with
    ``nsub`` sub-steps per period, the measurement of ``loop`` (its noise, its delay in the controller)."""
    plant, n = spec.true_plant, spec.true_plant.n
    ctrl = rc3r.Controller(spec.law, spec.controller_model, spec.trajectory, rate=RATE, delay=loop.delay)
    T = 1.0 / RATE
    h = T / nsub
    N = int(round(DURATION * RATE))
    noise = loop.noise(N)
    x = loop.x0(*spec.trajectory.evaluate(0.0)[:2])

    def f(x, u):
        return np.concatenate([x[n:], plant.forward_dynamics(x[:n], x[n:], u, delivered=True)])

    Q, U, Z = [], [], []
    for k in range(N + 1):
        u = plant.applied_torque(x[:n], x[n:], ctrl.step(k * T, *loop.measure(x, k, noise)))
        Q.append(x[:n].copy()), U.append(u), Z.append(ctrl.z.copy())
        if k == N:
            break
        for _ in range(nsub):
            k1 = f(x, u)
            k2 = f(x + 0.5 * h * k1, u)
            k3 = f(x + 0.5 * h * k2, u)
            k4 = f(x + h * k3, u)
            x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return np.array(Q), np.array(U), np.array(Z).reshape(N + 1, -1)


@pytest.mark.parametrize("controller", ["adaptive", "robust"])
def test_python_engine_compiled_engine_and_controller_step_agree(controller):
    spec = rc3r.build_run(controller=controller, perturbed=True, rate=RATE, duration=DURATION)
    loop = LoopEffects(spec.true_plant.n, noise_q=1e-5, noise_qd=1e-4, delay=1, seed=7)
    runs = {e: simulate(spec.true_plant, spec.law, spec.trajectory, replace(spec.options, engine=e), loop=loop,
                        model=spec.controller_model) for e in ("python", "fast")}
    py, fast = runs["python"], runs["fast"]
    assert py.engine == "python" and fast.engine == "fast"
    assert py.verdict == fast.verdict == "clean" and py.q.shape == fast.q.shape == (301, 3)
    q, u, z = _outside_loop(spec, loop, py.options.nsub)
    assert np.abs(q - py.q).max() <= 1e-12 and np.abs(u - py.u).max() <= 1e-12 * np.abs(py.u).max()
    assert z.shape == py.z.shape and (z.size == 0 or np.abs(z - py.z).max() <= 1e-12 * np.abs(py.z).max())
    assert fast.options.nsub == py.options.nsub
    assert np.abs(fast.q - py.q).max() <= 1e-10
    assert np.abs(fast.u - py.u).max() <= 1e-10 * np.abs(py.u).max()
    assert py.z.size == 0 or np.abs(fast.z - py.z).max() <= 1e-9
    # the loop effects matter here: without the noise and the delay the run is another one
    plain = simulate(spec.true_plant, spec.law, spec.trajectory, replace(spec.options, engine="python"),
                     x0=loop.x0(*spec.trajectory.evaluate(0.0)[:2]), model=spec.controller_model)
    assert np.abs(plain.u - py.u).max() > 1e3 * 1e-10 * np.abs(py.u).max()


def test_the_loop_holds_delays_and_steps_the_state_by_forward_euler():
    """SampledLoop alone, on a torque whose command is its sample time and whose zdot is 1: with delay 2 the
    held command is u_0 at samples 0, 1, 2 and u_{k-2} after; z_k = z_0 + k T (forward Euler, first step at
    sample 1); Controller.z reads and sets the same state."""
    from rc3r.controllers.sampled import SampledLoop

    class Law:
        def initial_state(self):
            return np.array([1.0])

    T = 0.25
    loop = SampledLoop(Law(), T, delay=2)

    def torque(t, q, qd, z):
        return np.array([t]), np.array([1.0]), float(z[0])

    held = [float(loop.sample(k, torque, None, None)[0]) for k in range(6)]
    assert held == [0.0, 0.0, 0.0, T, 2 * T, 3 * T]
    assert loop.z.tolist() == [1.0 + 5 * T] and loop.diagnostic == 1.0 + 5 * T and loop.command.tolist() == [5 * T]
    loop.reset()
    assert loop.k == -1 and loop.u is None and loop.z.tolist() == [1.0]
    spec = rc3r.build_run(controller="adaptive", rate=RATE, duration=0.01)
    ctrl = rc3r.Controller.from_run(spec)
    ctrl.z = np.full(ctrl.z.size, 2.0)
    assert ctrl._loop.z.tolist() == [2.0] * spec.law.p
