"""Friction and rotor inertia (armature) in the controller's model: :class:`rc3r.robots.actuated.ActuatedRobot`.

Independent sources: Pinocchio with ``model.armature`` set here (``rnea``, ``crba``, ``aba`` include it, as
measured on Pinocchio 4.1) plus the plant's friction law :class:`rc3r.plants.Friction` (its own module, the
law the plants apply) for the model; the python engine (Pinocchio's ABA, SciPy/RK4 in
:mod:`rc3r.simulate._python`) for the compiled engine; a C compiler for the exported regressor.
Tolerances: the 3R's and the UR5's torques are O(10..100) N m, float64 sums of a few hundred terms:
1e-10 of the largest entry leaves four orders above the ~1e-14 measured.
"""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

import rc3r
from rc3r.errors import ConfigError, ParameterError
from rc3r.plants import Friction, Plant
from rc3r.robots import load_robot
from rc3r.robots.actuated import ActuatedRobot

KINDS = ("viscous", "coulomb", "offset", "armature")
V_S = 0.05


def _joint(n, scale=1.0):
    """Joint coefficients in friction_names order: fv, fc, f0, ia per joint."""
    return scale * np.concatenate([np.linspace(0.5, 1.5, n), np.linspace(1.0, 3.0, n), np.linspace(-0.4, 0.4, n),
                                   np.linspace(0.05, 0.3, n)])


def _reference(robot, joint):
    """(pinocchio model with armature, Friction) built here from the rigid body and the coefficients."""
    n = robot.n
    m = robot.model.copy()
    m.armature = joint[3 * n:]
    return m, Friction(joint[:n], joint[n:2 * n], joint[2 * n:3 * n], v_s=V_S)


@pytest.fixture(scope="module", params=["rr3", "ur5"])
def arm(request):
    return load_robot(request.param)


def test_regressor_is_rnea_with_armature_plus_the_plants_friction_law(arm, rng):
    """Y_act(q, qd, qd, qdd) theta_act = pin.rnea(model with armature) - Friction.joint_torque(qd) at random
    states, single and batched (1e-10 of the largest torque)."""
    import pinocchio as pin

    joint = _joint(arm.n)
    act = ActuatedRobot(arm, KINDS, V_S, joint)
    model, fr = _reference(arm, joint)
    data = model.createData()
    Q, QD, QDD = rng.uniform(-2, 2, (3, 5, arm.n))
    ref = np.array([pin.rnea(model, data, q, qd, a) - fr.joint_torque(q, qd) for q, qd, a in zip(Q, QD, QDD)])
    got = act.regressor(Q, QD, QD, QDD) @ act.theta
    assert np.abs(got - ref).max() <= 1e-10 * np.abs(ref).max()
    assert np.abs(act.regressor(Q[0], QD[0], QD[0], QDD[0]) @ act.theta - ref[0]).max() <= 1e-10 * np.abs(ref).max()
    assert act.p == arm.p + 4 * arm.n and act.coefficient_names[arm.p] == "fv1"
    assert act.coefficient_names[-1] == f"ia{arm.n}"


def test_mass_matrix_and_forward_dynamics_are_crba_and_aba_with_armature(arm, rng):
    """M_act = pin.crba with armature (upper triangle mirrored) and the actuated rigid body's forward dynamics =
    pin.aba with armature (no friction: a plant's friction is its Friction effect)."""
    import pinocchio as pin

    joint = _joint(arm.n)
    act = ActuatedRobot(arm, KINDS, V_S, joint)
    model, _ = _reference(arm, joint)
    data = model.createData()
    q, qd, u = rng.uniform(-2, 2, (3, arm.n))
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    assert np.abs(act.mass_matrix(q) - M).max() <= 1e-10 * np.abs(M).max()
    ref = pin.aba(model, data, q, qd, 10 * u)
    assert np.abs(act.forward_dynamics(q, qd, 10 * u) - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())


def test_theta_model_mass_matrix_is_crba_with_armature(arm, rng):
    """The design rule's M(q; theta) from the regressor (ThetaModel: Y(q, 0, 0, e_j) - Y(q, 0, 0, 0)) on the
    actuated model is crba with armature: friction and offset columns cancel in the identity the sampled rule
    uses, the armature stays."""
    import pinocchio as pin

    from rc3r.design.rule import ThetaModel

    joint = _joint(arm.n)
    act = ActuatedRobot(arm, KINDS, V_S, joint)
    model, _ = _reference(arm, joint)
    q = rng.uniform(-2, 2, arm.n)
    M = pin.crba(model, model.createData(), q)
    M = np.triu(M) + np.triu(M, 1).T
    assert np.abs(ThetaModel(act, act.theta).mass_matrix(q) - M).max() <= 1e-10 * np.abs(M).max()


def test_compiled_supply_equals_pinocchio_and_friction_law(arm, rng):
    """The compiled supply (:mod:`rc3r.robots.actuated_supply` over the 3R's closed form, its generated copy
    over the chain's): ``u = w + Y th`` at th = theta_act is rnea with armature + friction; ``xi = Y^T r`` is the
    python regressor's (itself tested above); ``M_th r`` is crba's; the plant's forward dynamics is aba with
    the armature."""
    import importlib

    import pinocchio as pin

    joint = _joint(arm.n)
    act = ActuatedRobot(arm, KINDS, V_S, joint)
    model, fr = _reference(arm, joint)
    data = model.createData()
    module, kc = act.compiled_kernels
    S = importlib.import_module(module)
    wk = S.make_work(kc)
    n, p = arm.n, act.p
    Y = np.zeros((n, p))
    q, qd, a, r, w, tau = rng.uniform(-2, 2, (6, n))
    S.passes_into(kc, q, qd, qd, a, Y, wk)
    u, xi, Mr, qdd = np.zeros(n), np.zeros(p), np.zeros(n), np.zeros(n)
    S.apply_into(kc, Y, act.theta, w, u, wk)
    ref = pin.rnea(model, data, q, qd, a) - fr.joint_torque(q, qd) + w
    assert np.abs(u - ref).max() <= 1e-10 * np.abs(ref).max()
    S.xi_into(kc, Y, r, xi, wk)
    ref_xi = act.regressor(q, qd, qd, a).T @ r
    assert np.abs(xi - ref_xi).max() <= 1e-10 * np.abs(ref_xi).max()
    S.mass_into(kc, q, act.theta, r, Mr, Y, wk)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    assert np.abs(Mr - M @ r).max() <= 1e-10 * np.abs(M @ r).max()
    assert S.forward_dynamics_into(kc, q, qd, 20 * tau, qdd, wk)
    ref = pin.aba(model, data, q, qd, 20 * tau)
    assert np.abs(qdd - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())
    Yf = np.zeros((n, p))
    S.regressor_into(kc, q, qd, qd, a, Yf, wk)
    assert np.abs(Yf - act.regressor(q, qd, qd, a)).max() <= 1e-10 * np.abs(Yf).max()


def test_tangents_are_the_derivatives_of_the_torque(rng):
    """The 3R supply's analytic d(Y th)/d(q, qd, v, a) (inner tangents + joint slopes: fv + fc sech^2 / v_s in
    qd, ia in a) equals central differences of the python regressor (step 1e-6: error ~1e-10 relative)."""
    import importlib

    arm = load_robot("rr3")
    act = ActuatedRobot(arm, KINDS, V_S, _joint(3))
    module, kc = act.compiled_kernels
    S = importlib.import_module(module)
    wk = S.make_work(kc)
    x = rng.uniform(-1, 1, 12)
    D = np.zeros((3, 12))
    assert S.tangents_into(kc, act.theta, x[:3], x[3:6], x[6:9], x[9:], D, wk)
    h, F = 1e-6, np.zeros((3, 12))
    for k in range(12):
        e = np.zeros(12)
        e[k] = h
        tp, tm = (act.regressor(*np.split(x + s * e, 4)) @ act.theta for s in (1, -1))
        F[:, k] = (tp - tm) / (2 * h)
    assert np.abs(D - F).max() <= 1e-7 * np.abs(F).max()


def test_physical_issues_refuse_negative_coefficients_and_unsmoothed_coulomb():
    """fv < 0, fc < 0, ia < 0 and a Coulomb column with v_s = 0 are each named; a negative offset is a bias,
    allowed; an unknown kind is a one-line ConfigError."""
    arm = load_robot("rr3")
    ok = ActuatedRobot(arm, KINDS, V_S, _joint(3))
    assert not [i for i in ok.physical_issues() if "triangle" not in i]
    for k, name in ((0, "viscous"), (3, "coulomb"), (9, "armature")):
        j = _joint(3)
        j[k] = -0.1
        issues = ActuatedRobot(arm, KINDS, V_S, j).physical_issues()
        assert any(name in i for i in issues), issues
    assert any("v_s" in i for i in ActuatedRobot(arm, KINDS, 0.0, _joint(3)).physical_issues())
    with pytest.raises(ParameterError):
        ActuatedRobot(arm, KINDS, V_S, _joint(3)[:5])
    with pytest.raises(ConfigError, match="unknown joint coefficient kind"):
        ActuatedRobot(arm, ("viscous", "stiction"), V_S)


def test_compiled_run_equals_python_engine_3r():
    """A robust law whose model carries friction and armature on a plant with other friction and armature
    (the 3R at 1 kHz, 0.5 s): the compiled engine equals the python engine to 1e-8 rad and 1e-6 N m (measured
    2.8e-17 rad, 1.2e-11 N m)."""
    from dataclasses import replace

    from rc3r.controllers import make_law

    arm = load_robot("rr3")
    plant = ActuatedRobot(arm, KINDS, V_S, _joint(3)).as_plant()
    model = ActuatedRobot(arm, KINDS, V_S, _joint(3, 0.7))
    spec = rc3r.build_run(controller="fbl", rate=1000.0, duration=0.5)
    law = make_law("robust", model.theta, rho=0.5 * np.linalg.norm(model.theta), eps=1.0)
    fast, py = (rc3r.simulate(plant, law, spec.trajectory, replace(spec.options, engine=e), model=model)
                for e in ("fast", "python"))
    assert fast.ok and py.ok and fast.engine == "fast" and py.engine == "python"
    assert np.abs(fast.q - py.q).max() <= 1e-8
    assert np.abs(fast.u - py.u).max() <= 1e-6


@pytest.mark.slow
def test_compiled_run_equals_python_engine_ur5():
    """The same on the UR5 (the chain supply's generated copy; about 150 s of compilation on a cold cache;
    the same comparison with the robust spec's defaults measured 5.6e-17 rad, 8e-14 N m)."""
    from dataclasses import replace

    from rc3r.controllers import make_law

    arm = load_robot("ur5")
    plant = ActuatedRobot(arm, KINDS, V_S, _joint(6)).as_plant()
    model = ActuatedRobot(arm, KINDS, V_S, _joint(6, 0.7))
    spec = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=0.5)
    law = make_law("robust", model.theta, rho=0.5 * np.linalg.norm(model.theta), eps=5.0, K=20.0, Lambda=20.0)
    fast, py = (rc3r.simulate(plant, law, spec.trajectory, replace(spec.options, engine=e), model=model)
                for e in ("fast", "python"))
    assert fast.ok and py.ok and fast.engine == "fast"
    assert np.abs(fast.q - py.q).max() <= 1e-8
    assert np.abs(fast.u - py.u).max() <= 1e-6


# ---- a bounds file with an actuator part (the dict load_bounds returns for format rc3r-bounds/2) -------------

def _bounds(robot, kinds, joint0, rel=0.05, jrel=0.3):
    """The dict of :func:`rc3r.identify.bounds_file.load_bounds` for a /2 file, by hand: an ellipsoid inside the
    box of half-widths ``rel |theta_r| + 1e-3`` and ``jrel |joint0| + 1e-3``, its rigid projection on top."""
    from rc3r.identify.regressors import friction_names

    p = robot.p
    th = np.concatenate([robot.theta, joint0])
    hw = np.concatenate([rel * np.abs(robot.theta), jrel * np.abs(joint0)]) + 1e-3
    P = np.diag(1.0 / (th.size * hw ** 2))
    C = np.linalg.inv(P)
    Pr = np.linalg.inv(C[:p, :p])
    act = {"kinds": list(kinds), "coulomb_velocity": V_S, "rigid_p": p,
           "coefficient_names": tuple(robot.coefficient_names) + friction_names(kinds, robot.n),
           "theta0": th, "P": P, "rho": float(np.sqrt(np.linalg.eigvalsh(C).max())), "rho_i": np.sqrt(np.diag(C))}
    return {"theta0": robot.theta.copy(), "P": Pr, "rho": float(np.sqrt(np.linalg.eigvalsh(C[:p, :p]).max())),
            "rho_i": np.sqrt(np.diag(C))[:p], "source": "hand.toml", "confidence": 0.95, "robot": robot.name,
            "coefficient_names": tuple(robot.coefficient_names), "n": robot.n, "p": p, "actuator": act}


@pytest.fixture
def bounds_file(monkeypatch):
    """``load_bounds`` returning a hand-built /2 dict for the 3R (viscous, Coulomb, offset)."""
    import rc3r.identify.bounds_file as bf

    arm = load_robot("rr3")
    joint0 = np.concatenate([np.full(3, 2.0), np.full(3, 3.0), np.full(3, 0.5)])
    holder = {"bf": _bounds(arm, KINDS[:3], joint0)}
    monkeypatch.setattr(bf, "load_bounds", lambda path, robot=None: holder["bf"])
    return holder


def test_bounds_with_actuator_give_an_actuated_model_and_plants_in_the_full_ellipsoid(bounds_file):
    """``--bounds`` with an actuator part: the controller's model is the ActuatedRobot at the centre (theta_0,
    rho, rho_i over p + 3n coefficients); plant ``random:3`` lies in the full ellipsoid with fv, fc >= 0, and the
    true plant's Friction effect carries exactly its joint coefficients; ``--friction`` with it is refused in one
    line; ``nominal`` is the rigid centre without friction."""
    bd = bounds_file["bf"]
    act = bd["actuator"]
    spec = rc3r.build_run(controller="robust", bounds="hand.toml", plant="random:3", perturbed=True, duration=0.1)
    model, plant = spec.controller_model, spec.true_plant
    assert isinstance(model, ActuatedRobot) and model.p == 24
    np.testing.assert_array_equal(spec.law.theta, act["theta0"])
    assert spec.law.rho == act["rho"]
    rigid = plant.rigid
    d = rigid.theta - act["theta0"]
    assert d @ act["P"] @ d <= 1.0 + 1e-9
    fr = plant.effect("friction")
    np.testing.assert_array_equal(fr.viscous, rigid.coefficients("viscous"))
    np.testing.assert_array_equal(fr.coulomb, rigid.coefficients("coulomb"))
    np.testing.assert_array_equal(fr.offset, rigid.coefficients("offset"))
    assert fr.v_s == V_S and np.all(fr.viscous >= 0) and np.all(fr.coulomb >= 0)
    with pytest.raises(ConfigError, match="drop --friction"):
        rc3r.build_run(controller="robust", bounds="hand.toml", plant="random:3", perturbed=True, friction="1:1")
    nom = rc3r.build_run(controller="robust", bounds="hand.toml", plant="nominal", perturbed=True, duration=0.1)
    assert nom.true_plant.effect("friction") is None and not np.any(nom.true_plant.rigid.joint)


def test_a_plant_without_friction_outside_the_bounds_joint_part_is_said(bounds_file):
    """The nominal plant (joint coefficients 0) against a centre 0 lies outside of (half-widths 5 % of the joint
    coefficients, ``_bounds(jrel=0.05)``: |theta0_j| / sqrt((P^-1)_jj) about 4 for every joint coefficient): the
    run's warnings say so once, naming the coefficient farthest in units of its half-width; with the fixture's
    30 % half-widths (0 inside every one, ratio about 0.7) there is no such warning."""
    nom = rc3r.build_run(controller="robust", bounds="hand.toml", plant="nominal", perturbed=True, duration=0.1)
    assert not [w for w in nom.warnings if "no joint friction" in w], nom.warnings
    arm = load_robot("rr3")
    joint0 = np.concatenate([np.full(3, 2.0), np.full(3, 3.0), np.full(3, 0.5)])
    bd = bounds_file["bf"] = _bounds(arm, KINDS[:3], joint0, jrel=0.05)
    act = bd["actuator"]
    ratio = np.abs(act["theta0"][arm.p:]) / np.sqrt(np.diag(np.linalg.inv(act["P"]))[arm.p:])
    far = act["coefficient_names"][arm.p + int(np.argmax(ratio))]
    spec = rc3r.build_run(controller="robust", bounds="hand.toml", plant="nominal", perturbed=True, duration=0.1)
    said = [w for w in spec.warnings if "no joint friction" in w]
    assert len(said) == 1 and f"{far} = " in said[0] and "--plant centre" in said[0], spec.warnings


@pytest.mark.parametrize("law", ["robust", "fbl"])
def test_friction_in_the_model_tracks_a_friction_plant_better(bounds_file, law):
    """The same plant (plant ``random:3`` of the bounds: rigid body + viscous, Coulomb, offset friction), the
    same law, once with the friction in the model (the bounds' actuator part) and once without (the rigid
    bounds alone): with it, the largest tracking error is below 3/4 of the one without (measured over 2 s on the
    python engine, continuous time: robust 1.26e-4 against 2.31e-4 rad, ratio 0.54; fbl 0.0258 against 0.0504
    rad, ratio 0.51; sampled at 1 kHz with the rule's gains 0.54 and 0.51 too)."""
    bd = bounds_file["bf"]
    spec = rc3r.build_run(controller=law, bounds="hand.toml", plant="random:3", perturbed=True, duration=2.0,
                          engine="python")
    with_f = rc3r.simulate(spec.true_plant, spec.law, spec.trajectory, spec.options, model=spec.controller_model)
    bounds_file["bf"] = {k: v for k, v in bd.items() if k != "actuator"}
    rigid = rc3r.build_run(controller=law, bounds="hand.toml", plant="nominal", perturbed=True, duration=2.0,
                           engine="python")
    same = Plant(spec.true_plant.rigid.rigid, spec.true_plant.effects)  # the same rigid body and friction
    without = rc3r.simulate(same, rigid.law, rigid.trajectory, rigid.options, model=rigid.controller_model)
    assert with_f.ok and without.ok
    e_with, e_without = np.abs(with_f.e).max(), np.abs(without.e).max()
    assert e_with < 0.75 * e_without, (e_with, e_without)


CC = shutil.which("cc")


@pytest.mark.skipif(CC is None, reason="no C compiler (cc)")
@pytest.mark.parametrize("name", ["rr3", "ur5"])
def test_exported_c_regressor_equals_python_and_pinocchio(tmp_path, name):
    """``rc3r export``'s regressor of an actuated model (the 3R's closed form, the UR5's chain, each renamed and
    wrapped by :mod:`rc3r.robots.actuated_c`), built by cc: ``xi = Y^T r`` and ``u = w + Y th`` equal the python
    regressor's at random states and th (1e-12 of the largest entry), and at th = theta_act, v = qd, w = 0, u is
    rnea with armature + the friction law (1e-10)."""
    import pinocchio as pin

    from rc3r.export.c import regressor_source

    arm = load_robot(name)
    joint = _joint(arm.n)
    act = ActuatedRobot(arm, KINDS, V_S, joint)
    n, p = act.n, act.p
    driver = tmp_path / "driver.c"
    driver.write_text(f"#include <math.h>\n#include <stdio.h>\n#define RC3R_N {n}\n#define RC3R_P {p}\n"
                      + regressor_source(act) + r"""
int main(void)
{
    double q[RC3R_N], qd[RC3R_N], v[RC3R_N], a[RC3R_N], r[RC3R_N], w[RC3R_N], th[RC3R_P], xi[RC3R_P], u[RC3R_N];
    rc3r_regressor wk;
    int i;
    for (;;) {
        for (i = 0; i < RC3R_N; ++i)
            if (scanf("%lf %lf %lf %lf %lf %lf", q + i, qd + i, v + i, a + i, r + i, w + i) != 6)
                return 0;
        for (i = 0; i < RC3R_P; ++i)
            if (scanf("%lf", th + i) != 1)
                return 1;
        rc3r_regressor_eval(&wk, q, qd, v, a);
        rc3r_regressor_xi(&wk, r, xi);
        rc3r_regressor_apply(&wk, th, w, u);
        for (i = 0; i < RC3R_P; ++i)
            printf("%.17g ", xi[i]);
        for (i = 0; i < RC3R_N; ++i)
            printf("%.17g ", u[i]);
        printf("\n");
    }
}
""")
    subprocess.run([CC, "-O2", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-o", str(tmp_path / "driver"),
                    str(driver), "-lm"], check=True)
    rng = np.random.default_rng(7)
    N = 20
    X = rng.uniform(-2.0, 2.0, (6, N, n))  # q, qd, v, a, r, w
    TH = rng.uniform(-1.0, 1.0, (N, p))
    X[2, :2], X[5, :2], TH[:2] = X[1, :2], 0.0, act.theta  # two inverse-dynamics rows at the true coefficients
    text = "\n".join(" ".join(repr(float(x)) for x in np.concatenate([X[:, s].T.ravel(), TH[s]])) for s in range(N))
    out = subprocess.run([str(tmp_path / "driver")], input=text, capture_output=True, text=True, check=True).stdout
    res = np.array([[float(x) for x in line.split()] for line in out.splitlines()])
    assert res.shape == (N, p + n)
    Y = act.regressor(X[0], X[1], X[2], X[3])
    xi = np.einsum("sij,si->sj", Y, X[4])
    u = np.einsum("sij,sj->si", Y, TH) + X[5]
    assert np.abs(res[:, :p] - xi).max() <= 1e-12 * np.abs(xi).max()
    assert np.abs(res[:, p:] - u).max() <= 1e-12 * np.abs(u).max()
    model, fr = _reference(arm, joint)
    data = model.createData()
    ref = np.array([pin.rnea(model, data, X[0, s], X[1, s], X[3, s]) - fr.joint_torque(X[0, s], X[1, s])
                    for s in range(2)])
    assert np.abs(res[:2, p:] - ref).max() <= 1e-10 * np.abs(ref).max()


def test_model_friction_config_covers_its_ranges():
    """``[model] friction`` (numbers here; "urdf" reads <dynamics>): the controller's theta_0 ends with the
    intervals' centres (nominal x (0.5 + 1.5) / 2), rho_i with their half-widths (0.5 x nominal), rho is the
    ball around the product hypot(rho of the rigid box, ||half-widths||), computed here by hand; plant
    ``random:3`` draws each coefficient inside its interval (seeded: the same twice) and carries them as its
    Friction effect; bad values are one-line ConfigErrors."""
    fr = {"viscous": 2.0, "coulomb": [1.0, 2.0, 3.0]}
    law = "robust-coeff"
    base = rc3r.build_run(controller=law, config={"perturbed": True}, plant="random:3", duration=0.1)
    spec = rc3r.build_run(controller=law, config={"perturbed": True, "model": {"friction": fr}}, plant="random:3",
                          duration=0.1)
    nom = np.array([2.0, 2.0, 2.0, 1.0, 2.0, 3.0])
    assert isinstance(spec.controller_model, ActuatedRobot) and spec.controller_model.p == 21
    np.testing.assert_array_equal(spec.law.theta[15:], nom)
    np.testing.assert_allclose(spec.model["rho_i"][15:], 0.5 * nom, rtol=1e-15)
    robust = rc3r.build_run(controller="robust", config={"perturbed": True, "model": {"friction": fr}},
                            plant="random:3", duration=0.1)
    rigid = rc3r.build_run(controller="robust", config={"perturbed": True}, plant="random:3", duration=0.1)
    assert robust.model["rho"] == pytest.approx(np.sqrt(rigid.model["rho"] ** 2 + np.sum((0.5 * nom) ** 2)), rel=1e-14)
    joint = spec.true_plant.rigid.joint
    assert np.all(joint >= 0.5 * nom) and np.all(joint <= 1.5 * nom) and np.any(joint != nom)
    np.testing.assert_array_equal(spec.true_plant.effect("friction").viscous, joint[:3])
    np.testing.assert_array_equal(spec.true_plant.rigid.rigid.theta, base.true_rigid.theta)  # the same rigid draw
    again = rc3r.build_run(controller=law, config={"perturbed": True, "model": {"friction": fr}}, plant="random:3")
    np.testing.assert_array_equal(again.true_plant.rigid.joint, joint)
    for bad, msg in (({"viscous": -1.0}, ">= 0"), ({"coulomb": "urdf"}, "no <dynamics friction>"),
                     ({"viscous": 1.0, "range": [1.2, 2.0]}, "range"), ({"viscous": 1.0, "stiction": 1}, "unknown key")):
        with pytest.raises(ConfigError, match=msg):
            rc3r.build_run(controller="robust", config={"perturbed": True, "model": {"friction": bad}})


@pytest.mark.skipif(CC is None or shutil.which("make") is None, reason="no C compiler (cc) or make")
@pytest.mark.parametrize("law", ["robust", "fbl"])
def test_rc3r_export_of_an_actuated_model_passes_make_check(bounds_file, tmp_path, law):
    """``rc3r export`` of a run on bounds with joint coefficients (the 3R, p = 24, plant ``random:3`` with its
    friction, 1 kHz): ``make check`` compares the C controller's torques with rc3r's recorded ones, max abs diff
    <= 1e-9 of max |u| (measured 3.0e-12 N m robust, 1.1e-13 fbl, on |u| ~ 345 N m)."""
    from rc3r.cli import main

    cfg = tmp_path / "run.toml"
    cfg.write_text('bounds = "hand.toml"\nperturbed = true\n[plant]\nspec = "random:3"\n'
                   '[simulation]\nrate = 1000.0\nengine = "python"\n')
    out = tmp_path / law
    assert main(["export", "--config", str(cfg), "--controller", law, "--out", str(out)]) == 0
    proc = subprocess.run(["make", "-s", "-C", str(out), "check"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and proc.stdout.strip().endswith("ok"), proc.stdout + proc.stderr


@pytest.mark.slow  # about 60 s of CPU (a design of its own), 8 min wall on a loaded machine
def test_rc3r_design_with_a_v2_bounds_file_verifies_plants_carrying_its_friction(tmp_path):
    """``rc3r design --bounds FILE`` with an ``rc3r-bounds/2`` file (the 3R's rigid coefficients 1 %, viscous 2,
    Coulomb 3, offset 0.5 N m per joint 30 %; written by ``write_bounds``, read back here with ``tomllib``, not
    ``load_bounds``): the design's ball is the file's full one over rigid **and** joint coefficients (rho 4.4, the
    Coulomb half-widths, against 1.6 of the rigid projection, computed here from P), and its ``centre`` plant is
    the file's theta0 with its friction (distance 0 to theta0 in runs.csv; a rigid plant without friction would
    be ||joint part|| = 6.3 away); every plant drawn lies in the ball (``covered``). 0.2 s runs, 2 draws."""
    import csv
    import json
    from rc3r.io import tomllib  # tomli on Python 3.10

    from rc3r.cli import main
    from rc3r.identify.bounds_file import write_bounds

    arm = load_robot("rr3")
    joint0 = np.concatenate([np.full(3, 2.0), np.full(3, 3.0), np.full(3, 0.5)])
    bd = _bounds(arm, KINDS[:3], joint0, rel=0.01)
    write_bounds(tmp_path / "b.toml", {"confidence": 0.95, "chi2": 1.0, "theta0": bd["theta0"], "P": bd["P"],
                                       "rho": bd["rho"], "rho_i": bd["rho_i"],
                                       "actuator": dict(bd["actuator"], quantile=1.0)}, arm, robot_name="rr3")
    f = tomllib.loads((tmp_path / "b.toml").read_text())
    assert f["format"] == "rc3r-bounds/2" and f["p"] == 24
    C = np.linalg.inv(np.array(f["P"]))
    rho_full, rho_rigid = np.sqrt(np.linalg.eigvalsh(C).max()), np.sqrt(np.linalg.eigvalsh(C[:15, :15]).max())
    assert rho_full > 2 * rho_rigid
    out = tmp_path / "d"
    code = main(["design", "--robot", "rr3", "--bounds", str(tmp_path / "b.toml"), "--rate", "1000", "--n", "2",
                 "--duration", "0.2", "--workers", "1", "--out", str(out)])
    assert code == 0
    model = json.loads((out / "design.json").read_text())["model"]
    assert model["rho"] == pytest.approx(rho_full, rel=1e-12)
    rows = [r for r in csv.DictReader((out / "runs.csv").open()) if r["controller"] == "robust"]
    centre = [r for r in rows if r["plant"] == "-1" and float(r["theta_dist"]) < 1e-9 * np.linalg.norm(f["theta0"])]
    assert centre and len({r["plant_seed"] for r in rows if r["plant_seed"]}) == 2
    assert np.linalg.norm(f["theta0"][15:]) == pytest.approx(6.3, abs=0.01)
    assert all(r["covered"] == "true" and float(r["theta_dist"]) <= rho_full for r in rows)
