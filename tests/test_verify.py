"""rc3r.verify / `rc3r verify-model`: passes on correct models, fails on wrong ones, output formats."""
from __future__ import annotations

import json

import numpy as np
import pytest

import rc3r.cli.model as cli_model
import rc3r.verify as verify
from rc3r.robots.rr3 import RR3
from rc3r.robots.rr3 import regressor as reg
from rc3r.cli import main
from rc3r.robots.rr3.params import ArmParams, LinkParams, theta, theta_from_vector
from rc3r.robots.rr3.urdf import REPO_URDF, load_arm, write_urdf

#: Checks that need no reference model, run for every robot.
COMMON = {
    "Sqd_vs_rnea", "Y_theta_vs_rnea", "Ysl_theta_vs_pinocchio", "skew_symmetry", "skew_symmetry_fd",
    "energy_identity", "theta_least_squares", "minimality",
}
#: The closed-form arm: its own M, C, g against Pinocchio.
CHECKS = COMMON | {"M_vs_crba", "S_vs_coriolis_matrix", "g_vs_gravity"}
#: A robot computed by Pinocchio: M, C, g rebuilt from its regressor instead of Pinocchio against itself.
GENERIC_CHECKS = COMMON | {"M_from_regressor_vs_crba", "C_from_regressor_vs_coriolis", "g_from_regressor_vs_gravity"}

#: Measured errors are ~1e-15 relative (rounding; 1e-12 for the finite-difference skew check);
#: 1e-9 is the documented pass threshold (verify.TOL, verify.FD_TOL), asserted here explicitly so a
#: looser one is caught. The energy identity carries the integrator's error (measured 2e-11): 1e-8.
MAX_REL = 1e-9
BOUND = {"energy_identity": 1e-8}


def _other_arms():
    """Two physically consistent arms unlike Table 1 (other lengths, masses, CoMs, inertias)."""
    a = ArmParams((
        LinkParams(0.4, 3.0, (0.05, -0.2, 0.01), (0.2, 0.25, 0.3, 0.01, -0.02, 0.03)),
        LinkParams(1.7, 8.0, (-0.8, 0.1, -0.05), (0.1, 0.9, 0.85, 0.02, 0.0, -0.01)),
        LinkParams(0.9, 1.5, (-0.3, 0.05, 0.2), (0.05, 0.2, 0.22, -0.01, 0.01, 0.0)),
    ), name="other_a")
    b = ArmParams((
        LinkParams(1.2, 15.0, (0.0, 0.3, 0.0), (1.0, 1.0, 1.0, 0.0, 0.0, 0.0)),
        LinkParams(0.3, 0.5, (-0.1, -0.1, 0.1), (0.01, 0.012, 0.015, 0.001, 0.002, 0.0)),
        LinkParams(2.0, 19.0, (-1.0, 0.4, -0.6), (2.0, 3.0, 4.0, 0.5, -0.3, 0.2)),
    ), name="other_b")
    return a, b


@pytest.fixture(scope="module")
def table1_report():
    return verify.verify_model(RR3.from_urdf(REPO_URDF))


def test_committed_urdf_passes_every_check(table1_report):
    """verify_model(urdf/rr3.urdf) (1000 states): every check passes with rel err <= 1e-9."""
    r = table1_report
    assert set(r.checks) == CHECKS
    for name, c in r.checks.items():
        assert c.passed, name
        assert c.max_rel_err <= BOUND.get(name, MAX_REL), (name, c.max_rel_err)
    assert r.passed
    np.testing.assert_allclose(r.theta, (33, -11.6, 3.4, -14, -4.4, -2, 12, 1.4, -3.8, -0.2, -2.2,
                                         29.2, 15.3, 15, 3), atol=1e-12)


def test_committed_urdf_warns_about_links_2_and_3(table1_report):
    """Table 1 inertias of links 2, 3 violate the triangle inequality: two warnings, run still passes."""
    w = table1_report.warnings
    assert len(w) == 2
    assert w[0].startswith("link 2") and "triangle" in w[0]
    assert w[1].startswith("link 3") and "triangle" in w[1]
    assert table1_report.passed


@pytest.mark.parametrize("which", [0, 1])
def test_generated_robots_pass(tmp_path, which):
    """Any URDF of this structure passes: two generated arms (write_urdf) with other parameters."""
    p = _other_arms()[which]
    path = write_urdf(p, tmp_path / f"{p.name}.urdf")
    r = verify.verify_model(RR3.from_urdf(path), samples=200, seed=3)
    assert r.passed, {n: c for n, c in r.checks.items() if not c.passed}
    assert all(c.max_rel_err <= BOUND.get(n, MAX_REL) for n, c in r.checks.items())
    assert r.warnings == ()  # physically consistent
    np.testing.assert_allclose(r.theta, theta(p), rtol=0, atol=1e-12)


def test_json_output_parses_with_required_keys(capsys):
    """`rc3r verify-model --json --samples 50`: one JSON object, required keys, exit 0."""
    assert main(["verify-model", "--json", "--samples", "50"]) == 0
    out, err = capsys.readouterr()
    obj = json.loads(out)  # exactly one JSON document (json.loads rejects trailing data)
    assert {"urdf", "theta", "checks", "warnings", "pass"} <= set(obj)
    assert obj["pass"] is True and len(obj["theta"]) == 15 and len(obj["warnings"]) == 2
    assert set(obj["checks"]) == CHECKS
    for c in obj["checks"].values():
        assert {"max_abs_err", "max_rel_err", "pass"} <= set(c)
        assert c["pass"] is True
    assert obj["samples"] == 50 and obj["seed"] == 0


def test_text_output_table_and_exit_code(capsys):
    """Human output: one table row per check with PASS, theta, warnings, final PASS line."""
    assert main(["verify-model", "--samples", "20", "--seed", "4"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    for name in CHECKS:
        row = next(line for line in lines if line.startswith(name + " "))
        assert row.rstrip().endswith("PASS")
    assert "th15" in out and "triangle inequality" in out
    assert lines[-1].startswith("PASS")


def test_same_seed_same_report():
    """Reproducible: the same seed gives identical errors."""
    a = verify.verify_model(RR3.from_urdf(REPO_URDF), samples=30, seed=7)
    b = verify.verify_model(RR3.from_urdf(REPO_URDF), samples=30, seed=7)
    assert a.checks == b.checks


# ---- the checks can fail -------------------------------------------------------------------


def test_compare_error_measure():
    """rel = max|x - r| / max(1, max|r|): absolute below unit scale, relative above it."""
    c = verify.compare([1.0, 2.0 + 1e-3], [1.0, 2.0])
    assert c.max_abs_err == pytest.approx(1e-3) and c.max_rel_err == pytest.approx(5e-4)
    assert not c.passed
    small = verify.compare([1e-3], [0.0])
    assert small.max_rel_err == pytest.approx(1e-3)
    assert verify.compare([1e6 + 1e-4], [1e6]).passed  # 1e-10 relative
    with pytest.raises(ValueError):
        verify.compare(np.zeros(3), np.zeros(4))


def test_compare_fails_on_nan():
    c = verify.compare([np.nan], [0.0])
    assert not c.passed


def test_wrong_theta_fails_the_checks(monkeypatch, capsys):
    """theta computed with a wrong l3 (1.1 instead of 1) makes the run FAIL and exit 1.

    Patching ``RR3.theta`` feeds the closed form a theta of the wrong robot while Pinocchio
    uses the URDF.
    """
    def wrong_theta(p):
        l1, l2, l3 = p.lengths
        return theta_from_vector(p.to_vector(), (l1, l2, l3 + 0.1))

    monkeypatch.setattr(RR3, "theta", property(lambda self: wrong_theta(self.params)))
    r = verify.verify_model(RR3.from_urdf(REPO_URDF), samples=50)
    assert not r.passed
    for name in ("M_vs_crba", "Y_theta_vs_rnea", "Ysl_theta_vs_pinocchio", "theta_least_squares",
                 "g_vs_gravity", "skew_symmetry", "energy_identity"):
        assert not r.checks[name].passed, name
        assert r.checks[name].max_rel_err > 1e-3
    assert r.checks["minimality"].passed  # independent of theta
    assert main(["verify-model", "--samples", "20"]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out.splitlines()[-1]


def test_perturbed_theta_fails_comparison_with_rnea(arm, rng):
    """Y theta' vs rnea fails for theta' = theta + 1e-6 in one entry (detects tiny errors)."""
    import pinocchio as pin

    th = theta(arm.params)
    st = verify.sample_states(20, seed=1)
    l2 = arm.params.lengths[1]
    Y = reg.regressor(st["q"], st["qd"], st["qdd"], l2=l2)
    data = arm.model.createData()
    ref = np.array([pin.rnea(arm.model, data, st["q"][n], st["qd"][n], st["qdd"][n]) for n in range(20)])
    assert verify.compare(Y @ th, ref).passed
    bad = th.copy()
    bad[int(rng.integers(15))] += 1e-6
    assert not verify.compare(Y @ bad, ref).passed


def test_minimality_fails_for_rank_deficient_regressor(arm):
    """Dropping one theta column (rank 14) fails the minimality check."""
    st = verify.sample_states(50, seed=2)
    Y = reg.regressor(st["q"], st["qd"], st["qdd"], l2=arm.params.lengths[1]).reshape(-1, 15)
    assert verify.check_minimality(arm.model, Y, st).passed
    Yd = Y.copy()
    Yd[:, 4] = 0.0
    c = verify.check_minimality(arm.model, Yd, st)
    assert not c.passed and "rank(Y) = 14" in c.detail


def test_json_is_strict_even_with_nan():
    """Non-finite errors are written as null, and the overall pass is false."""
    bad = verify.Check(float("nan"), float("nan"), 1e-9, False)
    rep = verify.VerifyReport(urdf="x", theta=(0.0,) * 15, checks={"M_vs_crba": bad}, passed=False)
    text = json.dumps(cli_model.report_to_dict(rep), allow_nan=False)
    obj = json.loads(text)
    assert obj["checks"]["M_vs_crba"]["max_rel_err"] is None and obj["pass"] is False
    assert "FAIL" in cli_model.render_text(rep).splitlines()[-1]


def test_load_arm_default_is_committed_urdf():
    """verify-model without --urdf uses urdf/rr3.urdf in a checkout."""
    assert load_arm().path == str(REPO_URDF)


def test_few_samples_still_identify_theta():
    """--samples 1: the identification checks (lstsq, minimality) still stack 200 states and pass."""
    r = verify.verify_model(RR3.from_urdf(REPO_URDF), samples=1)
    assert r.passed
    assert "200 states" in r.checks["minimality"].detail


# ---- a robot computed by Pinocchio: no check of Pinocchio against itself --------------------------

SO101 = "so_arm_description/urdf/so101.urdf"


@pytest.fixture(scope="module")
def ur5_report(ur5):
    return verify.verify_model(ur5, samples=40, seed=1)


def test_pinocchio_robot_skips_the_tautologies_and_says_why(ur5_report):
    """For the UR5 (M, C, g = crba, computeCoriolisMatrix, computeGeneralizedGravity) the three checks that
    compared Pinocchio with itself (error exactly 0 on main) are gone, a note says why, and M, C, g rebuilt
    from the compiled regressor agree with Pinocchio to rounding but not bitwise (two computations: a max
    abs error of exactly 0 over 40 states x 36 entries would mean the same numbers were compared)."""
    r = ur5_report
    assert set(r.checks) == GENERIC_CHECKS and r.passed
    assert len(r.notes) == 1 and "compare Pinocchio with itself" in r.notes[0]
    for name in ("M_from_regressor_vs_crba", "C_from_regressor_vs_coriolis", "g_from_regressor_vs_gravity"):
        assert 0.0 < r.checks[name].max_rel_err <= MAX_REL, (name, r.checks[name])
    assert r.theta_order.startswith("base parameters, in the order of rc3r.robots.base_parameters")


def test_the_3r_keeps_its_closed_form_checks_and_gets_the_new_ones(table1_report):
    """The closed-form arm is compared with Pinocchio directly (M, S, g are its own formulas), plus the
    energy identity (measured 2.4e-12) and the finite-difference skew symmetry (measured 2.6e-9)."""
    assert set(table1_report.checks) == CHECKS and table1_report.notes == ()
    assert table1_report.checks["energy_identity"].max_rel_err <= verify.ENERGY_TOL
    assert table1_report.checks["skew_symmetry_fd"].max_rel_err <= verify.FD_TOL
    assert table1_report.theta_order == "paper order, section 3.1.1"


def _add_to_torque(robot, delta):
    """robot.regressor changed so that Y theta gains delta(q, qd, v, a) (shape (..., n)) and nothing else:
    Y' = Y + delta theta^T / (theta . theta)."""
    orig, th = robot.regressor, np.asarray(robot.theta, dtype=float)

    def wrong(q, qd, v, a):
        return orig(q, qd, v, a) + np.asarray(delta(q, qd, v, a))[..., :, None] * th / (th @ th)
    return wrong


#: A wrong term each: (what is patched, how, the check it must fail, the rebuilt checks that must pass).
#: 1 % of a term is >= 1e-3 relative in every case, 10^6 times TOL.
MUTANTS = {
    "M a in Y": ("regressor", lambda r: _add_to_torque(r, lambda q, qd, v, a: 0.01 * np.einsum(
        "...ij,...j->...i", r.mass_matrix(q), a)), "M_from_regressor_vs_crba"),
    "C v in Y": ("regressor", lambda r: _add_to_torque(r, lambda q, qd, v, a: 0.01 * np.einsum(
        "...ij,...j->...i", r.coriolis_matrix(q, qd), v)), "C_from_regressor_vs_coriolis"),
    "g in Y": ("regressor", lambda r: _add_to_torque(r, lambda q, qd, v, a: 0.01 * r.gravity(q)),
               "g_from_regressor_vs_gravity"),
    "g x 1.01": ("gravity", lambda r: (lambda q, f=r.gravity: 1.01 * f(q)), "energy_identity"),
    "M x 1.01": ("mass_matrix", lambda r: (lambda q, f=r.mass_matrix: 1.01 * f(q)), "energy_identity"),
    "C x 1.01": ("coriolis_matrix", lambda r: (lambda q, qd, f=r.coriolis_matrix: 1.01 * f(q, qd)),
                 "skew_symmetry_fd"),
    "M + q-dependent": ("mass_matrix", lambda r: (lambda q, f=r.mass_matrix: f(q) + 0.01 * np.cos(
        np.asarray(q)[..., :1, None]) * np.eye(r.n)), "skew_symmetry_fd"),
}


@pytest.mark.parametrize("mutant", MUTANTS)
def test_a_wrong_term_fails_its_check(ur5, monkeypatch, mutant):
    """Each new check can fail: a deliberately wrong term (patched on the robot) fails the check that
    covers it with an error >= 1e-3 relative; the rebuilt terms that do not contain it still pass (so the
    checks localize the error)."""
    attr, make, check = MUTANTS[mutant]
    monkeypatch.setattr(ur5, attr, make(ur5))
    r = verify.verify_model(ur5, samples=20, seed=2)
    assert not r.passed and not r.checks[check].passed and r.checks[check].max_rel_err > 1e-3, r.checks[check]
    rebuilt = {"M a in Y": "M_from_regressor_vs_crba", "C v in Y": "C_from_regressor_vs_coriolis",
               "g in Y": "g_from_regressor_vs_gravity"}
    if mutant in rebuilt:
        for other in set(rebuilt.values()) - {check}:
            assert r.checks[other].passed, other


def test_generic_text_and_json_name_the_base_parameters(capsys):
    """`verify-model --robot ur5`: theta is labelled as base parameters (not 'paper order'), the note is
    printed, and --json carries notes, theta_order and the identifiability ratio."""
    assert main(["verify-model", "--robot", "ur5", "--samples", "20"]) == 0
    out = capsys.readouterr().out
    assert "theta (base parameters, in the order of rc3r.robots.base_parameters" in out
    assert "paper order" not in out and "note: M_vs_crba, S_vs_coriolis_matrix and g_vs_gravity are not run" in out
    assert main(["verify-model", "--robot", "ur5", "--samples", "20", "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert set(obj["checks"]) == GENERIC_CHECKS and len(obj["notes"]) == 1
    assert obj["identifiability"]["warn_below"] == verify.IDENTIFIABILITY_RTOL
    assert obj["identifiability"]["s_min_over_s1"] > 1e-2  # UR5: 0.034 measured
    assert not any("barely identifiable" in w for w in obj["warnings"])


def test_a_urdf_that_is_not_the_3r_names_generic(capsys):
    """Without --generic a UR5 URDF is refused in one line that says how to check it."""
    from rc3r.robots.pinocchio import NAMED, example_robot_data_dir

    path = example_robot_data_dir() / NAMED["ur5"][0]
    assert main(["verify-model", "--urdf", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not the 3R arm" in err and f"--generic --urdf {path}" in err


def test_barely_identifiable_base_parameters_are_a_warning(capsys):
    """SO-101 (example-robot-data): its stacked regressor's s_p/s_1 is 2.7e-7 < IDENTIFIABILITY_RTOL, so
    verify-model warns (text and JSON) but passes. The ratio equals the one of Pinocchio's own joint-torque
    regressor restricted to the kept columns at the same 200 states (the base regressor is that restriction:
    an independent computation of the same matrix, 1e-6 relative for an SVD ratio of 1e-7)."""
    import pinocchio as pin

    from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir

    path = example_robot_data_dir() / SO101
    assert main(["verify-model", "--generic", "--urdf", str(path), "--samples", "20", "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    warn = [w for w in obj["warnings"] if "barely identifiable" in w]
    assert obj["pass"] and len(warn) == 1 and "mcx1" in warn[0] and "mcy1" in warn[0]
    robot = PinocchioRobot.from_urdf(path)
    st = verify.sample_states(verify.MINIMALITY_STATES, 0, robot.n)
    data = robot.model.createData()
    W = np.vstack([pin.computeJointTorqueRegressor(robot.model, data, q, qd, qdd)[:, robot.base.independent]
                   for q, qd, qdd in zip(st["q"], st["qd"], st["qdd"])])
    s = np.linalg.svd(W, compute_uv=False)
    assert obj["identifiability"]["s_min_over_s1"] == pytest.approx(s[-1] / s[0], rel=1e-6)
    assert s[-1] / s[0] < verify.IDENTIFIABILITY_RTOL
    assert main(["verify-model", "--generic", "--urdf", str(path), "--samples", "20"]) == 0
    out = capsys.readouterr().out
    assert "barely identifiable" in out and "warnings (do not fail the run)" in out
