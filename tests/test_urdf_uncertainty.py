"""Issue 36: the URDF's own uncertainty as a physical set of link inertias (rc3r.uncertainty.urdf), its
lightest plant as the design's worst corner, and a planted case where it breaks eq. 6 at the rate."""
from __future__ import annotations

import itertools
import json

import numpy as np
import pinocchio as pin
import pytest

import rc3r
from rc3r.errors import ConfigError
from rc3r.uncertainty.urdf import DEFAULT, URDFSet, parse_spec, ranges


def _pseudo(block):
    return pin.PseudoInertia.FromDynamicParameters(np.asarray(block, dtype=float)).toMatrix()


# ---- the set -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("value, text", [(None, None), (0.0, None), ("off", None), (0.5, "0.5..1.5"),
                                         ("0.25", "0.75..1.25"), (" 0.1..1.5 , -1=0.05..2 ", "0.1..1.5,-1=0.05..2"),
                                         ("0.2..1,3=0.5..3", "0.2..1,3=0.5..3")])
def test_spec_is_canonicalised(value, text):
    assert parse_spec(value) == text


@pytest.mark.parametrize("bad", ["0..1.5", "1.2..1.5", "0.5..0.9", "x", "a=0.5..1.5", "0=0.5..1.5", 1.0, -0.1])
def test_bad_spec_is_refused(bad):
    with pytest.raises(ConfigError):
        parse_spec(bad)


def test_ranges_override_by_link_counting_from_either_end():
    lo, hi = ranges("0.1..1.5,-1=0.05..1.5,2=0.5..2", 6)
    np.testing.assert_allclose(lo, [0.1, 0.5, 0.1, 0.1, 0.1, 0.05])
    np.testing.assert_allclose(hi, [1.5, 2, 1.5, 1.5, 1.5, 1.5])
    with pytest.raises(ConfigError):
        ranges("0.5..1.5,8=0.1..1", 7)


@pytest.mark.parametrize("robot", ["ur5", "panda"])
def test_every_plant_of_the_default_set_is_physical_and_between_its_ends(robot):
    """Seeded draws, both ends, a scaled plant: no physical issue (mass, inertia about the CoM, triangle), and
    per link lo J <= J' <= hi J (Pinocchio's pseudo-inertia of the realised standard parameters: the PSD
    order, checked by eigenvalues); the draws are reproducible from their seed and differ between seeds."""
    arm = rc3r.load_robot(robot)
    u = URDFSet(arm, DEFAULT)
    std0 = arm.standard_parameters()
    plants = [u.plant(f"urdf-random:{s}") for s in range(8)] + [u.plant("urdf-lower"), u.plant("urdf-upper"),
                                                               u.plant("urdf-scale:0.5")]
    for p in plants:
        assert p.physical_issues() == []
        std = p.standard_parameters()
        for k in range(u.bodies):
            J0, J = _pseudo(std0[10 * k:10 * k + 10]), _pseudo(std[10 * k:10 * k + 10])
            scale = np.abs(J0).max()
            assert np.linalg.eigvalsh(J - u.lo[k] * J0)[0] > -1e-9 * scale
            assert np.linalg.eigvalsh(u.hi[k] * J0 - J)[0] > -1e-9 * scale
    np.testing.assert_array_equal(u.plant("urdf-random:3").theta, u.plant("urdf-random:3").theta)
    assert np.max(np.abs(u.plant("urdf-random:3").theta - u.plant("urdf-random:4").theta)) > 1e-3
    np.testing.assert_allclose(u.plant("urdf-lower").standard_parameters()[0::10], u.lo * std0[0::10])
    with pytest.raises(ConfigError):
        u.plant("urdf-scale:0.01")  # outside the set


# ---- its worst corner, against Pinocchio's CRBA --------------------------------------------------------

def _scaled_crba(arm, factors, q):
    """M(q) by pin.crba of the arm's model with link i's inertia scaled by factors[i] (independent of rc3r's
    regressor and of URDFSet)."""
    model = arm.model.copy()
    for i, f in enumerate(factors, start=1):
        model.inertias[i] = pin.Inertia.FromDynamicParameters(f * model.inertias[i].toDynamicParameters())
    data = model.createData()
    M = pin.crba(model, data, np.asarray(q, dtype=float))
    return np.triu(M) + np.triu(M, 1).T


def _ur5_payload(urdf_uncertainty, rate=1000.0, duration=1.0):
    from rc3r.design.rule import fast_design, spectrum
    from rc3r.design.verify import _resolve, controller_model, design_config
    from rc3r.design.worst import Hardest

    cfg = design_config({}, robot="ur5", payload=(0.0, 3.0), duration=duration, urdf_uncertainty=urdf_uncertainty)
    spec, rho_i = _resolve(cfg, rate)
    sp = spectrum(controller_model(spec), spec.trajectory, duration)
    d = fast_design(sp, rate, rho=spec.model["rho"], rho_i=rho_i)
    return cfg, spec, sp, d, Hardest(cfg, spec, sp, rate, 0)


def test_the_lightest_plant_is_the_worst_corner_and_its_figure_is_pinocchios():
    """UR5 + 0..3 kg with the default set, eq. 6 at the fast form's gains: the search's hardest plant is
    'lower+urdf-lower' (every link at its lower factor, no payload) and its T lambda_max(M_p^-1 G) equals the
    figure from pin.crba of the URDF model with each link's inertia scaled by its factor; no vertex of the
    whole-link scalings (2^6, by CRBA) and no seeded draw of the set is harder (the PSD-order argument of
    rc3r.uncertainty.urdf)."""
    from rc3r.design.worst import plant_gain

    cfg, spec, sp, d, hard = _ur5_payload(None)
    sl = {k: v for k, v in d.gains("robust").items() if k in ("K", "Lambda", "K_inertia")}
    found = hard.plants(sl, rho=spec.model["rho"], eps=d.eps)
    top = found[0]
    assert top["spec"] == "lower+urdf-lower"
    G = hard.gains(sl, rho=spec.model["rho"], eps=d.eps)
    q = hard.search.q
    lo, hi = ranges(DEFAULT, 6)

    def crba_gain(factors):
        Ms = np.array([_scaled_crba(spec.controller_model, factors, qk) for qk in q])
        return float(np.max(plant_gain(G, Ms)[0])) / 1000.0

    assert crba_gain(lo) == pytest.approx(top["T_lambda"], rel=1e-8)
    vertices = [crba_gain(np.where(bits, hi, lo)) for bits in itertools.product((0, 1), repeat=6)]
    assert max(vertices) == pytest.approx(top["T_lambda"], rel=1e-8)
    draws = [rc3r.build_run(controller="robust", config=cfg, plant=f"random:{s}", rate=1000.0, eps=1.0).true_rigid
             for s in range(10)]
    assert max(float(np.max(plant_gain(G, hard.search.mass(p.theta))[0])) / 1000.0 for p in draws) < top["T_lambda"]
    light = rc3r.build_run(controller="robust", config=cfg, plant="lower+urdf-lower", rate=1000.0, eps=1.0).true_rigid
    assert float(np.max(plant_gain(G, hard.search.mass(light.theta))[0])) / 1000.0 == pytest.approx(top["T_lambda"])


# ---- the planted case ----------------------------------------------------------------------------------

def _old_box(arm, f=0.5):
    """Last session's URDF uncertainty: +-f |p_j| on every standard parameter (not a physical set)."""
    from rc3r.uncertainty.box import Box

    std = np.abs(arm.standard_parameters())
    return Box(-f * std, f * std, tuple(arm.standard_parameter_names))


def test_a_light_wrist_breaks_eq6_where_the_old_box_passes_and_the_design_refuses_it(tmp_path):
    """UR5 + 0..3 kg at 1 kHz, the fast form's K and Lambda: at eps_p, 1.2 x the smallest eps at which 30 seeded
    plants of last session's +-0.5 |p| box keep T lambda_max(M_p^-1 G) < 2, the default set's lightest plant
    (its wrist link 20 x lighter, the others 10 x: inside the default) is above 2 by Pinocchio's CRBA of the
    scaled model, and a run of it at eps_p is not clean. The design's search finds that plant
    (lower+urdf-lower, same figure) and refuses eps_p; the design with the default set (margin 1, 4 random
    plants, 1 s) refuses every eps whose held loop there is unstable, without simulation, and verifies gains
    whose figure on it (CRBA) is below 2, with clean runs on it."""
    from rc3r.campaign import RunTable, columns, read_rows
    from rc3r.design.verify import _loop, verify_design
    from rc3r.design.worst import plant_gain
    from rc3r.uncertainty.box import perturb

    cfg, spec, sp, d, hard = _ur5_payload(None)
    rho, arm, q = spec.model["rho"], spec.controller_model, hard.search.q
    sl = {k: v for k, v in d.gains("robust").items() if k in ("K", "Lambda", "K_inertia")}
    box = _old_box(arm)
    old_M = [hard.search.mass(perturb(arm, box, f"random:{s}", simulable=True).theta) for s in range(30)]

    def old(eps):
        G = hard.gains(sl, rho=rho, eps=eps)
        return max(float(np.max(plant_gain(G, M)[0])) / 1000.0 for M in old_M)

    lo_e, hi_e = d.eps, d.eps
    while old(hi_e) >= 2.0:
        hi_e *= 2.0
    while old(lo_e) < 2.0 and lo_e > 1e-6:
        lo_e /= 2.0
    for _ in range(40):
        mid = np.sqrt(lo_e * hi_e)
        lo_e, hi_e = (mid, hi_e) if old(mid) >= 2.0 else (lo_e, mid)
    eps_p = 1.2 * hi_e
    lo, _ = ranges(DEFAULT, 6)
    M_light = np.array([_scaled_crba(arm, lo, qk) for qk in q])  # no payload: the range's light end
    G_p = hard.gains(sl, rho=rho, eps=eps_p)
    light_p = float(np.max(plant_gain(G_p, M_light)[0])) / 1000.0
    assert old(eps_p) < 2.0 < light_p
    found = hard.plants(sl, rho=rho, eps=eps_p)
    assert found[0]["spec"] == "lower+urdf-lower" and found[0]["T_lambda"] == pytest.approx(light_p, rel=1e-8)
    refusal = _loop(found, 1.0, 1000.0)
    assert refusal["plant"] == "lower+urdf-lower" and "loop gain" in refusal["verdict"]
    run = rc3r.build_run(controller="robust", config={**cfg, "gains": {"robust": {**sl, "eps": eps_p}}},
                         plant="lower+urdf-lower", rate=1000.0, eps=eps_p)
    assert rc3r.execute(run)[0].verdict != "clean"

    path = tmp_path / "runs.csv"
    with RunTable(path, columns(6)).open(resume=False) as table:
        seen = verify_design(cfg, 1000.0, table=table, margin=1.0, n=4, seed=0, workers=1)
    rows = read_rows(path)
    refused = [lv for lv in seen.levels if lv["worst"]["T_lambda"] >= 2.0]
    assert all(not lv["clean"] and lv["decided_by"]["plant"] == "lower+urdf-lower"
               and "loop gain" in lv["decided_by"]["verdict"] for lv in refused)
    assert not any(r["eps"] == lv["eps"] for lv in refused for r in rows if r["controller"] == "robust")
    assert seen.eps is not None and seen.chosen["worst"]["spec"] == "lower+urdf-lower"
    g_s = seen.gains()["robust"]
    G_s = hard.gains({k: g_s[k] for k in ("K", "Lambda", "K_inertia")}, rho=rho, eps=g_s["eps"])
    assert float(np.max(plant_gain(G_s, M_light)[0])) / 1000.0 < 2.0
    mine = [r for r in rows if r["controller"] == "robust" and r["eps"] == seen.eps
            and r["job"].startswith("lower+urdf-lower")]
    assert mine and all(r["verdict"] == "clean" for r in mine)
    info = json.loads(json.dumps(seen.describe()))
    assert info["worst"]["robust"]["spec"] == "lower+urdf-lower" and info["urdf"].startswith("every link")
