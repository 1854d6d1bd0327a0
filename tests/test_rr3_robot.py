"""rc3r.robots.rr3.robot: RR3 as a Robot; its closed-form plant equals Pinocchio's ABA plant."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rc3r.controllers import FeedbackLinearization
from rc3r.errors import ParameterError
from rc3r.robots.rr3 import RR3
from rc3r.robots.rr3.paper import paper_box, paper_trajectory
from rc3r.uncertainty import paper_bounds, perturb


@pytest.fixture(scope="module")
def plant(table1):
    return RR3.from_params(table1)


def test_forward_dynamics_equals_aba(plant, rng):
    """M^{-1}(u - S qd - g) (closed form) == pinocchio.aba, relative 1e-10 (rounding of a 3x3 solve
    with cond(M) <~ 1e3 on torques ~1e3)."""
    for _ in range(200):
        q, qd, u = rng.uniform(-3, 3, 3), rng.uniform(-5, 5, 3), rng.uniform(-500, 500, 3)
        a_pin = plant.forward_dynamics(q, qd, u)
        a_cf = plant.forward_dynamics_closed_form(q, qd, u)
        np.testing.assert_allclose(a_cf, a_pin, rtol=1e-10, atol=1e-10 * np.abs(a_pin).max())


@pytest.mark.slow
def test_closed_form_plant_follows_pinocchio_over_a_whole_run(plant, table1):
    """Same controller (FBL with theta_0), same integrator (DOP853, rtol 1e-12), 10 s of the paper's
    trajectory: the closed-form plant and the ABA plant stay within 1e-8 rad."""
    th0 = paper_bounds(plant, paper_box()).theta0
    ctrl, tr = FeedbackLinearization(th0), paper_trajectory()

    def rhs(fd):
        def f(t, x):
            u, _, _ = ctrl.torque(plant, x[:3], x[3:], np.array(tr.evaluate(t)))
            return np.concatenate([x[3:], fd(x[:3], x[3:], u)])
        return f

    q0, qd0, _ = tr.evaluate(0.0)
    t_eval = np.linspace(0, 10, 201)
    runs = [solve_ivp(rhs(fd), (0, 10), np.concatenate([q0, qd0]), method="DOP853", rtol=1e-12,
                      atol=1e-12, t_eval=t_eval) for fd in (plant.forward_dynamics, plant.forward_dynamics_closed_form)]
    assert all(r.success for r in runs)
    assert np.abs(runs[0].y[:3] - runs[1].y[:3]).max() < 1e-8


def test_perturbed_plants_differ_and_refuse_nonphysical(table1):
    """'upper' is a different robot; a non-PD inertia is refused with a ParameterError."""
    up = perturb(RR3(table1), paper_box(), "upper")
    assert up.label == "upper"
    assert np.abs(up.theta - RR3.from_params(table1).theta).max() > 1.0
    bad = table1.links[1].__class__(1.0, 10.0, (0, 0, 0), (0.5, 0.5, 0.5, 1.2, 0.0, 0.0))
    with pytest.raises(ParameterError, match="positive definite"):
        RR3.from_params(table1.with_links(links=(table1.links[0], bad, table1.links[2])))
