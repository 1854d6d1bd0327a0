"""rc3r identify on synthetic logs of known arms: the truth recovered, held-out torques at the noise level,
the filter chosen by cross-validation, bad logs refused in one line, identified.json and bounds.toml.

The logs are made by rc3r's own simulator of the arm (:mod:`rc3r.identify.synthetic`: Pinocchio ABA with
viscous and Coulomb friction, computed-torque tracking) at stated levels: torque noise 0.2 N m (white),
torque sensor offset 0.3 N m, velocity noise 0.01 rad/s, a 16-bit encoder (2 pi / 65536 rad),
intervals U(0.7, 1.3) ms with 0.5 % late samples after U(2, 9) ms; every draw seeded.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import rc3r
from rc3r.cli import main
from rc3r.errors import ConfigError, ParameterError
from rc3r.identify.bounds_file import load_bounds
from rc3r.identify.excitation import random_fourier
from rc3r.identify.log import Log, load_log, save_log
from rc3r.identify.pipeline import identify
from rc3r.identify.synthetic import Friction, SensorNoise, sample_log, simulate_motion

NOISE = SensorNoise()  # the stated levels (module docstring)


@pytest.fixture(scope="module")
def arm():
    return rc3r.load_robot("rr3")


@pytest.fixture(scope="module")
def motion(arm):
    """10 s of the paper's 3R on a random Fourier trajectory (5 harmonics of 0.1 Hz, at rest at both ends)."""
    return simulate_motion(arm, random_fourier(arm, 10.0, seed=2, fill=0.8), 10.0)


@pytest.fixture(scope="module")
def result(arm, motion):
    log, truth = sample_log(motion, seed=0, noise=NOISE)
    return identify(arm, log), truth, log


def _truth_vector(truth):
    return np.concatenate([truth["theta"], truth["viscous"], truth["coulomb"], truth["offset"]])


def test_true_theta_and_friction_are_recovered(result):
    """Every unknown (15 coefficients, then viscous, Coulomb and offset per joint) is within 4 of its
    reported standard deviations of the truth (a 4-sigma miss has probability 6e-5 per unknown), and the
    coefficients are within 0.5 % of the largest one: the estimate is unbiased to the noise's level."""
    res, truth, _ = result
    x_true = _truth_vector(truth)
    se = np.sqrt(np.diag(res.cov))
    z = (res.x - x_true) / se
    assert np.all(np.abs(z) <= 4.0), np.round(z, 2)
    assert np.abs(res.theta - truth["theta"]).max() <= 5e-3 * np.abs(truth["theta"]).max()
    assert res.friction()["offset"] == pytest.approx(np.full(3, 0.3), abs=4 * se[-3:].max())


def test_held_out_rms_approaches_the_noise_level(arm, motion):
    """The held-out RMS against the logged torques is the sensor noise (0.2 or 0.6 N m) up to the model's
    small misfit (at most +35 %, and never below it: the noise is in every logged sample); the low-passed
    torques are predicted 2.5x better still (at the cross-validated 5 Hz; 5x at the 2.4 Hz the spectra chose
    before issue 35: less noise passes, and the model's misfit remains), and the fraction inside the 95 % band
    is 95 % +- 4 %."""
    for sigma in (0.2, 0.6):
        log, _ = sample_log(motion, seed=1, noise=SensorNoise(torque_std=sigma))
        v = identify(arm, log, consistency=False).validation
        rms = np.asarray(v["rms"])
        assert np.all(rms >= 0.9 * sigma) and np.all(rms <= 1.35 * sigma), (sigma, rms)
        assert np.all(np.asarray(v["rms_filtered"]) <= rms / 2.5)
        assert abs(v["inside_band"] - 0.95) <= 0.04


def test_the_robots_own_coefficients_without_friction_predict_worse(result):
    """rms_nominal (the URDF's coefficients, which here are the truth, but no friction model) is larger than
    the identified model's by at least 5x: the log's friction (2 N m s/rad, 1 N m) and offset are in it."""
    res, _, _ = result
    assert np.all(np.asarray(res.validation["rms_nominal"]) >= 5 * np.asarray(res.validation["rms"]))


def test_ur5_is_identified_and_physically_consistent():
    """The UR5 (36 base parameters + 18 friction): every unknown within 4.5 sigma of the truth, the true
    theta inside the 95 % ellipsoid, the physically consistent estimate is (Pinocchio's pseudo-inertias PD)
    with held-out RMS within 5 % of the unconstrained one's and masses within 25 % of the truth, and the
    consistency SDP finds the nearest physically consistent coefficients inside the ellipsoid too (the true
    arm is consistent).

    At the settings the spectra chose before issue 35 (their cut-off, differentiated velocities, per-joint
    weights, sign friction; d^T Cov^-1 d = 52.3 against the quantile 52.9 with the in-band covariance).
    With the cross-validated defaults (3 Hz, v_s = 0.003 rad/s) the true theta is inside too with the
    in-band covariance (50.9 against 54.5; the white one put it just outside, 57.8 against 53.2; 2026-12-06),
    but the consistent fit's 0.19 kg wrist comes out 37 % heavy there, beyond this test's 25 %. Every row
    fitted (``slow_share=0``, as before issue 35's slow rows): at these settings the default's cross-validation
    leaves the slow rows out (share 0.1) and the true theta falls outside (81.3 against 52.8; 2026-12-06,
    docs/identification.md 2.3)."""
    from rc3r.identify import filtering as F

    ur5 = rc3r.load_robot("ur5")
    fr = Friction((2.0, 2.0, 2.0, 0.5, 0.5, 0.5), (1.0, 1.0, 1.0, 0.2, 0.2, 0.2))
    mo = simulate_motion(ur5, random_fourier(ur5, 10.0, seed=3, fill=0.9), 10.0, fr)
    log, truth = sample_log(mo, seed=0)
    g = F.Grids.of(log)
    spectral = F.choose_cutoff(g.q, g.tau, g.fs)["cutoff_hz"]
    res = identify(ur5, log, cutoff_hz=spectral, velocities="differentiated", weighting="per-joint",
                   coulomb_velocity=0.0, slow_share=0.0)
    z = (res.x - _truth_vector(truth)) / np.sqrt(np.diag(res.cov))
    assert np.all(np.abs(z) <= 4.5), np.round(z, 2)
    d = res.theta - truth["theta"]
    assert d @ np.linalg.solve(res.cov_theta, d) <= res.ellipsoid["chi2"]
    # the physically consistent estimate (default): rigid links by Pinocchio's own pseudo-inertias, held-out
    # RMS within 5 % of the unconstrained fit's, masses within 25 % of the truth (measured: 0-7 % for links
    # 1-5, 20 % for the 0.19 kg wrist, which the data barely see)
    import pinocchio as pin

    pf = res.physical_fit
    assert all(np.linalg.eigvalsh(pin.Inertia.FromDynamicParameters(pf.standard[k:k + 10]).toPseudoInertia()
                                  .toMatrix())[0] > 0 for k in range(0, pf.standard.size, 10))
    assert np.all(res.held_out_rms(pf.x) <= 1.05 * np.asarray(res.validation["rms"]))
    print("\nUR5 masses: consistent", np.round(pf.masses, 3), "true", np.round(ur5.standard_parameters()[0::10], 3),
          "rms ratio", np.round(res.held_out_rms(pf.x) / np.asarray(res.validation["rms"]), 4))
    assert np.allclose(pf.masses, ur5.standard_parameters()[0::10], rtol=0.25)  # measured: at most 20 % (the wrist)
    c = res.consistency
    pytest.importorskip("cvxpy")  # the consistency SDP (extra 'identify')
    assert c["checked"] and c["nominal_consistent"] and c["within_ellipsoid"]
    assert min(c["min_eigenvalues"]) >= -1e-6  # the projection's pseudo-inertias are PSD


def test_cutoff_is_chosen_from_the_torque_spectrum():
    """Hand-made signals: tau has sines up to f_top (1, 3, 6 Hz; 20 dB apart from the strongest) on
    0.2 N m noise, q a sine on quantization. The chosen cut-off is the top sine's frequency to within the
    Hann window's main lobe (two Welch bins of 0.49 Hz) and rises with it."""
    from rc3r.identify import filtering as F

    fs, t = 1000.0, np.arange(0.0, 20.0, 1e-3)
    rng = np.random.default_rng(0)
    q = np.round(np.sin(2 * np.pi * 0.3 * t) / 1e-4)[:, None] * 1e-4
    chosen = []
    for top in (1.0, 3.0, 6.0):
        tau = 50 * np.sin(2 * np.pi * 0.3 * t) + 5 * np.sin(2 * np.pi * top * t) + rng.normal(0, 0.2, t.size)
        c = F.choose_cutoff(q, tau[:, None], fs)
        chosen.append(c["cutoff_hz"])
        assert abs(c["torque_edge_hz"][0] - top) <= 2 * fs / 2048 + 1e-9
    assert chosen[0] == pytest.approx(F.CUTOFF_RANGE[0])  # 1 Hz is clipped to the 2 Hz floor
    assert chosen[0] < chosen[1] < chosen[2]


def test_given_filter_is_used_and_recorded(arm, result):
    _, _, log = result
    res = identify(arm, log, cutoff_hz=3.0, consistency=False)
    assert res.filter["cutoff_hz"] == 3.0 and res.filter["chosen"] == "given (--filter)"
    assert result[0].filter["chosen"] == "cross-validation" and "blocked" in result[0].selection["method"]


def test_velocities_auto_prefers_the_less_noisy_source():
    """With 0.01 rad/s of velocity noise the differentiated 16-bit positions are far less noisy below the
    states' cut-off (density (2 pi f)^2 x 1.5e-12 vs 2e-7 rad^2/s^2/Hz): 'differentiated'; a noise-free
    logged velocity wins: 'logged'."""
    from rc3r.identify.filtering import velocity_source

    assert velocity_source([1.5e-12], [2e-7], 15.0) == "differentiated"
    assert velocity_source([1.5e-12], [1e-12], 15.0) == "logged"


# ---- the command line -------------------------------------------------------------------------------

def _write(path, log):
    save_log(log, path)
    return str(path)


def test_cli_writes_identified_json_and_bounds_toml(tmp_path, result, capsys):
    """identified.json has theta, friction, covariance, validation (rms, rms_filtered, inside_band),
    consistency, physical, filter, provenance; bounds.toml loads back (validated, fitting the arm) with
    exactly the physically consistent estimate's centre and ellipsoid and its link parameters; the figures exist; a rerun without --force is refused and leaves them intact."""
    res, _, log = result
    path = _write(tmp_path / "log.csv", log)
    out = tmp_path / "id"
    assert main(["identify", path, "--robot", "rr3", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "held-out rms" in captured.out and "bounds of the physically consistent estimate at 95 %" in captured.out
    assert "physically consistent fit (gamma" in captured.out and "link masses [kg]" in captured.out
    data = json.loads((out / "identified.json").read_text())
    for key in ("theta", "friction", "covariance", "validation", "consistency", "physical", "filter", "provenance"):
        assert key in data
    assert len(data["validation"]["rms"]) == 3 and len(data["validation"]["rms_filtered"]) == 3
    assert np.allclose(data["theta"], res.theta, rtol=0, atol=1e-9 * np.abs(res.theta).max())
    b = load_bounds(out / "bounds.toml", robot=rc3r.load_robot("rr3"))
    assert b["robot"] == "rr3" and (b["n"], b["p"]) == (3, 15)
    np.testing.assert_array_equal(b["theta0"], np.asarray(data["physical"]["theta"]))
    np.testing.assert_array_equal(b["physical"]["log_cholesky"], np.asarray(data["physical"]["log_cholesky"]))
    # rc3r-bounds/2: the rigid bounds are the projection of the ellipsoid over theta and friction (a quantile over
    # all 24 unknowns): they contain the 15-dimensional ellipsoid at the same confidence
    assert b["format"] == "rc3r-bounds/2" and b["actuator"]["rigid_p"] == 15 and b["confidence"] == 0.95
    assert b["rho"] >= data["physical"]["ellipsoid"]["rho"]
    np.testing.assert_array_equal(b["actuator"]["theta0"][:15], b["theta0"])
    for name in ("torque.png", "residuals.png"):
        assert (out / name).stat().st_size > 10_000
    before = (out / "bounds.toml").read_bytes()
    assert main(["identify", path, "--robot", "rr3", "--out", str(out)]) == 2
    assert "earlier result" in capsys.readouterr().err
    assert (out / "bounds.toml").read_bytes() == before


def _one_line_error(capsys, argv, match):
    assert main(argv) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.startswith("rc3r: error: ") and cap.err.count("\n") == 1, cap.err
    assert match in cap.err, cap.err


def test_bad_logs_are_refused_in_one_line(tmp_path, result, capsys):
    """NaN, time going back, too few samples, a header with another number of joints, a ragged row, a field
    that is not a number, an unknown column, and an unexciting trajectory (a joint that never moves; an arm
    at rest): exit 2, one line on stderr, nothing on stdout, no output directory."""
    _, _, log = result
    bad = {}
    q = log.q.copy()
    q[500, 1] = np.nan
    bad["nan"] = (Log(log.t, q, log.tau), "q2 is nan at sample 501")
    t = log.t.copy()
    t[700] = t[698]
    bad["time"] = (Log(t, log.q, log.tau), "time does not increase at sample 701")
    bad["short"] = (Log(log.t[:50], log.q[:50], log.tau[:50]), "50 samples, at least 100")
    bad["joints"] = (Log(log.t, log.q[:, :2], log.tau[:, :2]), "has 2 joints")
    still = log.q.copy()
    still[:, 2] = 0.25
    bad["still"] = (Log(log.t, still, log.tau), "joint(s) 3 do not move")
    rest = np.tile(log.q[0], (log.samples, 1))
    bad["rest"] = (Log(log.t, rest, log.tau), "do not move")
    for name, (lg, match) in bad.items():
        path = _write(tmp_path / f"{name}.csv", lg)
        _one_line_error(capsys, ["identify", path, "--robot", "rr3", "--out", str(tmp_path / f"out-{name}")], match)
        assert not (tmp_path / f"out-{name}").exists()
    good = (tmp_path / "good.csv")
    _write(good, log)
    lines = good.read_text().splitlines()
    for name, text, match in (("ragged", lines[:10] + [lines[10].rsplit(",", 1)[0]] + lines[11:], "row 11 has 9 fields, the header has 10"),
                              ("word", lines[:5] + ["x" + lines[5][1:]] + lines[6:], "is not a number"),
                              ("column", [lines[0].replace("tau3", "tau4")] + lines[1:], "tau columns must be")):
        p = tmp_path / f"{name}.csv"
        p.write_text("\n".join(text) + "\n")
        _one_line_error(capsys, ["identify", str(p), "--robot", "rr3", "--out", str(tmp_path / "o")], match)
    _one_line_error(capsys, ["identify", str(tmp_path / "missing.csv"), "--robot", "rr3", "--out",
                             str(tmp_path / "o")], "log not found")
    _one_line_error(capsys, ["identify", str(good), "--robot", "rr3", "--friction", "stiction", "--out",
                             str(tmp_path / "o")], "unknown friction kind")


def test_csv_and_npz_logs_read_the_same(tmp_path, result):
    """A log written as CSV (17 significant digits) and as NPZ reads back to the same arrays (CSV to the
    last bit of a 17-digit decimal), with logged velocities kept; the digest differs by format."""
    _, _, log = result
    lg = Log(log.t[:300], log.q[:300], log.tau[:300], log.q[:300] * 0.5)
    a = load_log(_write(tmp_path / "l.csv", lg), n=3)
    b = load_log(_write(tmp_path / "l.npz", lg), n=3)
    for x, y in ((a.t, b.t), (a.q, b.q), (a.qd, b.qd), (a.tau, b.tau)):
        np.testing.assert_array_equal(x, y)
    assert a.sha256 != b.sha256 and len(a.sha256) == 64
    with pytest.raises(ConfigError, match="has 3 joints"):
        load_log(tmp_path / "l.npz", n=6)


# ---- bounds.toml --------------------------------------------------------------------------------------

def test_load_bounds_refuses_inconsistent_files(tmp_path, result):
    """A missing key, an unknown key, P not positive definite, a rho that does not contain the ellipsoid,
    and bounds of another arm are refused with one-line errors naming the problem."""
    from rc3r.identify.bounds_file import write_bounds

    res, _, _ = result
    arm = rc3r.load_robot("rr3")
    path = tmp_path / "b.toml"
    write_bounds(path, dict(res.bounds(), actuator=None), arm, robot_name="rr3")  # rc3r-bounds/1
    good = load_bounds(path, robot=arm)
    np.testing.assert_array_equal(good["P"], res.ellipsoid["P"])  # repr floats round-trip exactly
    text = path.read_text()

    def refused(new_text, exc, match):
        p = tmp_path / "bad.toml"
        p.write_text(new_text)
        with pytest.raises(exc, match=match):
            load_bounds(p, robot=arm)

    refused(text.replace("\nrho = ", "\nrhoo = "), ConfigError, "unknown key")
    refused("\n".join(line for line in text.splitlines() if not line.startswith("theta0")), ConfigError,
            "missing key 'theta0'")
    refused(text.replace(f"rho = {res.ellipsoid['rho']!r}", f"rho = {0.5 * res.ellipsoid['rho']!r}"),
            ParameterError, "does not contain the ellipsoid")
    P = np.array(res.ellipsoid["P"])
    P[0, 0] = -1.0
    refused(text.replace("P = " + text.split("P = ")[1].splitlines()[0], "P = " + json.dumps(P.tolist())),
            ParameterError, "not positive definite")
    with pytest.raises(ParameterError, match="n = 3, p = 15"):
        load_bounds(path, robot=rc3r.load_robot("ur5"))
    with pytest.raises(ConfigError, match="not found"):
        load_bounds(tmp_path / "none.toml")


def test_rank_deficient_regressor_names_the_undetermined_combination():
    """Two columns that move together (here column 2 = 3 x column 1, plus 1e-9 of noise) leave their
    combination undetermined: the column-scaled condition number (~1e9) exceeds 1e6 and the message
    names the two columns; a well-excited regressor passes."""
    from rc3r.identify.estimate import check_excitation

    rng = np.random.default_rng(0)
    A = rng.normal(size=(500, 2, 4))
    q = np.column_stack([np.linspace(0, 1, 500)] * 2)
    check_excitation(A, ("a", "b", "c", "d"), q)
    A[:, :, 1] = 3 * A[:, :, 0] + 1e-9 * rng.normal(size=(500, 2))
    with pytest.raises(ConfigError, match=r"rank-deficient \(column-scaled condition number .*\b[ab]\b.*\b[ab]\b"):
        check_excitation(A, ("a", "b", "c", "d"), q)


def test_robust_covariance_dominates_both_estimates():
    """dominating(C1, C2) - C1 and dominating(C1, C2) - C2 are positive semidefinite (to rounding), and it
    equals C1 when C2 <= C1 (nothing to add)."""
    from rc3r.identify.estimate import dominating

    rng = np.random.default_rng(1)
    X, Y = rng.normal(size=(2, 6, 6))
    C1, C2 = X @ X.T + 0.1 * np.eye(6), Y @ Y.T + 0.1 * np.eye(6)
    C = dominating(C1, C2)
    for Ck in (C1, C2):
        assert np.linalg.eigvalsh(C - Ck)[0] >= -1e-10 * np.abs(C).max()
    np.testing.assert_allclose(dominating(C1, 0.5 * C1), C1, rtol=1e-10, atol=1e-12)
