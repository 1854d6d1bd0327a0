"""The chain's kernel supply (rc3r.robots.pinocchio_supply): the law's two contractions of the Slotine--Li
regressor, xi = Y^T r and u = w + Y theta, computed without forming Y, against Pinocchio's own regressor
(``regressor_pinocchio``: two calls of computeJointTorqueRegressor, an independent implementation), on a
6-DoF arm, a 7-DoF arm and a tree with a prismatic joint; and the 3R's supply against its closed form."""
from __future__ import annotations

import numpy as np
import pytest
from numba import njit

import rc3r


@njit
def _contract(passes, xi_into, apply_into, make_work, kc, q, qd, v, a, r, th, w, Y, xi, u):
    wk = make_work(kc)
    passes(kc, q, qd, v, a, Y, wk)
    xi_into(kc, Y, r, xi, wk)
    apply_into(kc, Y, th, w, u, wk)


def _panda_with_finger():
    from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir

    return PinocchioRobot.from_urdf(example_robot_data_dir() / "panda_description/urdf/panda.urdf",
                                    lock={"panda_finger_joint2": 0.0})


@pytest.fixture(scope="module", params=["ur5", "panda", "panda+finger"])
def arm(request):
    return _panda_with_finger() if request.param == "panda+finger" else rc3r.load_robot(request.param)


def test_contractions_equal_pinocchio_regressor(arm, rng):
    """``xi_into == Y^T r`` and ``apply_into == w + Y theta`` with Y from Pinocchio at 20 seeded states of
    the supply's own ``passes_into``, to 1e-12 of the largest entry (a few hundred operations per entry in
    double on both sides; measured ~1e-15). The finger arm is a tree with a prismatic joint (8 joints)."""
    from rc3r.robots import pinocchio_supply as PS

    module, kc = arm.compiled_kernels
    assert module == PS.__name__
    n, p = arm.n, arm.p
    for _ in range(20):
        q, qd, v, a, r, w = rng.uniform(-2.0, 2.0, (6, n))
        th = rng.uniform(-1.0, 1.0, p)
        Y, xi, u = np.empty((n, p)), np.empty(p), np.empty(n)
        _contract(PS.passes_into, PS.xi_into, PS.apply_into, PS.make_work, kc, q, qd, v, a, r, th, w, Y, xi, u)
        ref = arm.regressor_pinocchio(q, qd, v, a)
        assert np.abs(xi - ref.T @ r).max() <= 1e-12 * np.abs(ref.T @ r).max()
        assert np.abs(u - (ref @ th + w)).max() <= 1e-12 * np.abs(ref @ th + w).max()


def test_contraction_at_theta_is_inverse_dynamics(rng):
    """With theta the arm's own base parameters, ``apply_into`` at ``v = qd`` is Pinocchio's rnea(q, qd, a)
    (``Y(q, qd, qd, a) theta = M a + C qd + g``), 1e-10 relative (the base-parameter map adds rounding)."""
    import pinocchio as pin

    from rc3r.robots import pinocchio_supply as PS

    arm = rc3r.load_robot("ur5")
    module, kc = arm.compiled_kernels
    data = arm.model.createData()
    for _ in range(10):
        q, qd, a = rng.uniform(-2.0, 2.0, (3, arm.n))
        Y, xi, u = np.empty((arm.n, arm.p)), np.empty(arm.p), np.empty(arm.n)
        _contract(PS.passes_into, PS.xi_into, PS.apply_into, PS.make_work, kc, q, qd, qd, a, np.zeros(arm.n),
                  np.asarray(arm.theta, float), np.zeros(arm.n), Y, xi, u)
        tau = pin.rnea(arm.model, data, q, qd, a)
        assert np.abs(u - tau).max() <= 1e-10 * np.abs(tau).max()
        assert np.all(xi == 0.0)  # r = 0


def test_rr3_supply_contracts_its_closed_form(rng):
    """The 3R's supply fills Y with its closed form (checked against Pinocchio in test_rr3_regressor) and
    contracts it: xi == Y^T r, u == w + Y theta to rounding (1e-13 relative)."""
    from rc3r.robots.rr3 import engine as E

    arm = rc3r.load_robot("rr3")
    module, kc = arm.compiled_kernels
    assert module == E.__name__
    for _ in range(10):
        q, qd, v, a, r, w = rng.uniform(-2.0, 2.0, (6, 3))
        th = rng.uniform(-1.0, 1.0, 15)
        Y, xi, u = np.empty((3, 15)), np.empty(15), np.empty(3)
        _contract(E.passes_into, E.xi_into, E.apply_into, E.make_work, kc, q, qd, v, a, r, th, w, Y, xi, u)
        ref = arm.regressor(q, qd, v, a)
        assert np.abs(Y - ref).max() <= 1e-13 * np.abs(ref).max()
        assert np.abs(xi - ref.T @ r).max() <= 1e-13 * np.abs(ref.T @ r).max()
        assert np.abs(u - (ref @ th + w)).max() <= 1e-13 * np.abs(ref @ th + w).max()


@njit
def _mass(passes, mass_into, make_work, kc, q, th, r, Y, out):
    wk = make_work(kc)
    passes(kc, q, np.zeros_like(q), np.zeros_like(q), np.zeros_like(q), Y, wk)
    mass_into(kc, q, th, r, out, Y, wk)


def test_mass_into_is_pinocchio_crba_times_r(arm, rng):
    """``mass_into`` (one acceleration pass on the kinematics of ``passes_into``) with theta the arm's own
    base parameters equals pin.crba(q) r (symmetrized) to 1e-11 relative; the 3R's closed form against
    pin.crba of its Table 1 URDF too."""
    import pinocchio as pin

    from rc3r.robots import pinocchio_supply as PS
    from rc3r.robots.rr3 import engine as E

    for robot, sup in ((arm, PS), (rc3r.load_robot("rr3"), E)):
        _, kc = robot.compiled_kernels
        model = robot.model
        for _ in range(5):
            q, r = rng.uniform(-2.0, 2.0, (2, robot.n))
            out, Y = np.empty(robot.n), np.empty((robot.n, robot.p))
            _mass(sup.passes_into, sup.mass_into, sup.make_work, kc, q, np.asarray(robot.theta, float), r, Y, out)
            M = pin.crba(model, model.createData(), q)
            M = np.triu(M) + np.triu(M, 1).T
            assert np.abs(out - M @ r).max() <= 1e-11 * np.abs(M @ r).max()
