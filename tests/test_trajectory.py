"""Trajectories: derivatives consistent with the positions, the paper's reference, quintic ends."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rc3r.errors import ConfigError
from rc3r.robots.rr3.paper import paper_trajectory
from rc3r.trajectory import Quintic, Sines, trajectory_from_config

TRAJS = {
    "paper": paper_trajectory(),
    "sines": Sines((0.1, -0.2, 0.3), ((1, 0.5, 2.0, 0.1), (1, 0.2, 5.0, 1.0), (3, 1.0, 0.5, -0.3))),
    "quintic": Quintic(((0, 0, 0), (1, -1, 0.5), (0.2, 0.3, 0.4)), (1.5, 2.0)),
}


@pytest.mark.parametrize("name", TRAJS)
def test_derivatives_are_consistent(name):
    """qd_d = d q_d/dt and qdd_d = d qd_d/dt (central differences, h = 1e-5: error ~h^2 * |q'''| ~ 1e-8)."""
    tr = TRAJS[name]
    h = 1e-5
    for t in np.linspace(0.05, 4.0, 23):
        qm, qdm, _ = tr.evaluate(t - h)
        qp, qdp, _ = tr.evaluate(t + h)
        _, qd, qdd = tr.evaluate(t)
        np.testing.assert_allclose((qp - qm) / (2 * h), qd, atol=1e-6)
        np.testing.assert_allclose((qdp - qdm) / (2 * h), qdd, atol=1e-5)


@pytest.mark.parametrize("name", TRAJS)
def test_jerk_is_the_derivative_of_the_acceleration(name):
    """reference_jerk_into = d qdd_d/dt (central differences, h = 1e-5: error ~h^2 |q^(5)| <= ~1e-7 here), inside
    the quintic's segments and past its end (held: 0); the analytic Jacobian's time column uses it."""
    from rc3r.trajectory import reference_jerk_into

    tr = TRAJS[name]
    tp = tr.pack()
    h = 1e-5
    for t in list(np.linspace(0.05, 3.4, 23)) + [4.0]:
        jerk = np.empty(tr.n)
        reference_jerk_into(tp, t, jerk)
        dq = (tr.evaluate(t + h)[2] - tr.evaluate(t - h)[2]) / (2 * h)
        np.testing.assert_allclose(jerk, dq, atol=1e-5)
    assert name != "quintic" or not np.any(jerk)  # t = 4.0 is past the quintic's 3.5 s


def test_paper_trajectory_values():
    """q_d = (sin t, 5 cos t, sin t), qd_d = (cos t, -5 sin t, cos t) (section 3.3)."""
    for t in (0.0, 0.7, 3.0):
        q, qd, qdd = paper_trajectory().evaluate(t)
        np.testing.assert_allclose(q, [math.sin(t), 5 * math.cos(t), math.sin(t)], atol=1e-14)
        np.testing.assert_allclose(qd, [math.cos(t), -5 * math.sin(t), math.cos(t)], atol=1e-14)
        np.testing.assert_allclose(qdd, -q, atol=1e-14)


def test_quintic_rest_to_rest():
    """Waypoints reached at rest; the last one is held."""
    tr = TRAJS["quintic"]
    for t, wp in ((0.0, (0, 0, 0)), (1.5, (1, -1, 0.5)), (3.5, (0.2, 0.3, 0.4)), (10.0, (0.2, 0.3, 0.4))):
        q, qd, qdd = tr.evaluate(t)
        np.testing.assert_allclose(q, wp, atol=1e-12)
        np.testing.assert_allclose(qd, 0, atol=1e-12)
        np.testing.assert_allclose(qdd, 0, atol=1e-9)


def test_vector_time():
    q, qd, qdd = paper_trajectory().evaluate(np.linspace(0, 1, 5))
    assert q.shape == qd.shape == qdd.shape == (5, 3)


@pytest.mark.parametrize("cfg", [
    {"kind": "spline"},
    {"kind": "sines"},
    {"kind": "sines", "terms": [[4, 1, 1, 0]]},
    {"kind": "sines", "terms": [[1, float("nan"), 1, 0]]},
    {"kind": "quintic", "waypoints": [[0, 0, 0]], "durations": []},
    {"kind": "quintic", "waypoints": [[0, 0, 0], [1, 1, 1]], "durations": [0.0]},
])
def test_bad_trajectory_configs(cfg):
    with pytest.raises(ConfigError):
        trajectory_from_config(cfg, paper_trajectory())


def test_sines_with_any_number_of_joints():
    """A 6-joint sine trajectory: q_d(t) = c + A sin(w t + phi) evaluated per joint, hand values."""
    tr = Sines((0.0,) * 5 + (0.25,), ((6, 2.0, 3.0, 0.5), (2, 1.0, 1.0, 0.0)))
    q, qd, qdd = tr.evaluate(0.7)
    assert q.shape == (6,)
    assert q[5] == pytest.approx(0.25 + 2.0 * np.sin(3.0 * 0.7 + 0.5), abs=1e-15)
    assert qd[5] == pytest.approx(6.0 * np.cos(3.0 * 0.7 + 0.5), abs=1e-14)
    assert qdd[1] == pytest.approx(-np.sin(0.7), abs=1e-15)
    assert q[0] == 0.0 and q[3] == 0.0


def test_quintic_with_two_joints_reaches_its_waypoints():
    """Rest-to-rest: q_d(T) = waypoint, qd_d(T) = 0, and the midpoint is halfway (s(1/2) = 1/2)."""
    tr = Quintic(((0.0, 1.0), (2.0, -1.0)), (2.0,))
    q, qd, _ = tr.evaluate(2.0)
    np.testing.assert_allclose(q, [2.0, -1.0], atol=1e-14)
    np.testing.assert_allclose(qd, 0.0, atol=1e-14)
    np.testing.assert_allclose(tr.evaluate(1.0)[0], [1.0, 0.0], atol=1e-14)
