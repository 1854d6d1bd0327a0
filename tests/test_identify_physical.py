"""The physically consistent estimate of rc3r identify and the physical uncertainty set.

Properties checked:

* on synthetic logs of a known physical arm (example-robot-data's double pendulum, viscous and Coulomb
  friction; rc3r's own simulator, noise levels of :mod:`rc3r.identify.synthetic`), the consistent fit is
  a rigid body per link -- checked independently by the eigenvalues of the pseudo-inertias that
  *Pinocchio* builds from the fitted standard parameters --, its held-out RMS is within 5 % of the
  unconstrained fit's on every joint, its masses are near the truth, and its coefficients are exactly
  ``T pi`` of its link parameters (the bounds' centre is realisable by construction);
* every draw of the Laplace posterior in the log-Cholesky chart is physical, and every plant drawn from
  a bounds file with a ``[physical]`` table is a rigid body whose coefficients lie in the ellipsoid;
* over 100 seeded logs the true coefficients lie in the reported ellipsoid at least about as often as
  stated (slow);
* run, design and montecarlo refuse, in one line and with exit code 2, a bounds file whose mass matrix
  is not positive definite along the reference, naming the joint and the smallest eigenvalue (computed
  here independently by Pinocchio's CRBA);
* on the real Panda log (``<repo>/../shared/data/panda_gaz``, GPL-3, never copied here; or
  ``RC3R_SHARED_DATA``; skipped without it): consistent, masses within 3x of the URDF's, held-out RMS
  under the targets of issue 35 (the defaults, the last 30 % held out).
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import rc3r
from rc3r.cli import main
from rc3r.errors import ParameterError
from rc3r.identify.bounds_file import load_bounds, write_bounds
from rc3r.identify.consistency import standard_map
from rc3r.identify.excitation import Limits, random_fourier
from rc3r.identify.physical import draw_standard
from rc3r.identify.pipeline import identify
from rc3r.identify.synthetic import Friction, sample_log, simulate_motion
from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir
from rc3r.uncertainty.ellipsoid import draw_from_ellipsoid

from _helpers import shared_panda_log

PENDULUM = "double_pendulum_description/urdf/double_pendulum.urdf"


def _pin_min_eigenvalues(standard) -> np.ndarray:
    """Smallest eigenvalue of every link's pseudo-inertia as Pinocchio builds it (independent of rc3r's)."""
    std = np.asarray(standard, dtype=float)
    return np.array([np.linalg.eigvalsh(pin.Inertia.FromDynamicParameters(std[k:k + 10]).toPseudoInertia()
                                        .toMatrix())[0] for k in range(0, std.size, 10)])


@pytest.fixture(scope="module")
def pendulum():
    return PinocchioRobot.from_urdf(example_robot_data_dir() / PENDULUM)


@pytest.fixture(scope="module")
def pendulum_motion(pendulum):
    """10 s of the double pendulum on a random Fourier trajectory, friction 0.05 N m s/rad and 0.02 N m."""
    lim = Limits(np.full(2, -np.pi), np.full(2, np.pi), np.full(2, 3.0), np.full(2, 10.0))
    return simulate_motion(pendulum, random_fourier(pendulum, 10.0, seed=2, fill=0.8, limits=lim), 10.0,
                           Friction((0.05, 0.05), (0.02, 0.02)))


@pytest.fixture(scope="module")
def pendulum_result(pendulum, pendulum_motion):
    log, truth = sample_log(pendulum_motion, seed=0)
    return identify(pendulum, log, consistency=False), truth


def test_consistent_fit_is_physical_accurate_and_near_the_true_masses(pendulum, pendulum_result):
    """Pinocchio's pseudo-inertias of the fit are positive definite; held-out RMS within 5 % of the
    unconstrained fit's on every joint; masses within 5 % of the truth; viscous and Coulomb >= 0."""
    res, truth = pendulum_result
    pf = res.physical_fit
    assert np.all(_pin_min_eigenvalues(pf.standard) > 0)
    ols = np.asarray(res.validation["rms"])
    phys = np.asarray(res.physical["validation"]["rms"])
    assert np.all(phys <= 1.05 * ols), (phys, ols)
    assert np.allclose(res.held_out_rms(pf.x), phys) and np.allclose(res.held_out_rms(res.x), ols)
    true_masses = pendulum.standard_parameters()[0::10]
    assert np.allclose(pf.masses, true_masses, rtol=0.05), (pf.masses, true_masses)
    fr = res.physical["friction"]
    assert min(fr["viscous"]) >= 0 and min(fr["coulomb"]) >= 0


def test_bounds_centre_is_the_consistent_estimate_realised_by_its_links(pendulum, pendulum_result):
    """theta0 of the bounds is T pi of the link parameters it carries (to rounding), not the unconstrained
    estimate; the ellipsoid is the data's covariance about it."""
    res, _ = pendulum_result
    b = res.bounds()
    T = standard_map(pendulum)
    assert np.allclose(T @ b["physical"]["standard_parameters"], b["theta0"], rtol=0, atol=1e-12)
    assert not np.allclose(b["theta0"], res.theta)
    assert np.allclose(b["P"], res.ellipsoid["P"])


def test_draws_are_physical_and_plants_lie_in_the_ellipsoid(tmp_path, pendulum, pendulum_result):
    """200 Laplace draws of the log-Cholesky parameters: every link positive definite (Pinocchio). Plants
    of a written-and-read bounds file (random:0..4, boundary:0, centre): rigid bodies (Pinocchio) with
    coefficients inside the ellipsoid, the centre's exactly theta0."""
    res, _ = pendulum_result
    draws = draw_standard(res.physical_fit, np.random.default_rng(0), 200)
    assert all(np.all(_pin_min_eigenvalues(d) > 0) for d in draws)
    path = write_bounds(tmp_path / "bounds.toml", res.bounds(), pendulum, urdf=str(example_robot_data_dir() / PENDULUM))
    bf = load_bounds(path, robot=pendulum)
    assert bf["physical"] is not None
    for spec in ("random:0", "random:1", "random:2", "random:3", "random:4", "boundary:0", "centre"):
        plant = draw_from_ellipsoid(pendulum, bf["theta0"], bf["P"], spec, physical=bf["physical"])
        assert np.all(_pin_min_eigenvalues(plant.standard_parameters()) > 0), spec
        d = plant.theta - bf["theta0"]
        assert d @ bf["P"] @ d <= 1.0 + 1e-9, spec
        if spec == "centre":
            assert np.allclose(plant.theta, bf["theta0"], rtol=1e-10, atol=1e-14)


def test_malformed_physical_table_is_refused(tmp_path, pendulum, pendulum_result):
    """A [physical] covariance that is not symmetric is refused in one line."""
    res, _ = pendulum_result
    b = res.bounds()
    C = np.array(b["physical"]["log_cholesky_cov"])
    C[0, 1] += 1.0
    b["physical"] = dict(b["physical"], log_cholesky_cov=C)
    path = write_bounds(tmp_path / "bad.toml", b, pendulum, urdf=str(example_robot_data_dir() / PENDULUM))
    with pytest.raises(ParameterError, match="log_cholesky_cov is not symmetric"):
        load_bounds(path, robot=pendulum)


@pytest.mark.slow
def test_true_theta_is_inside_the_physical_ellipsoid_at_about_the_stated_confidence(pendulum, pendulum_motion):
    """100 seeded logs (seeds 0-99, new noise and stamps each), defaults: the true theta lies in the bounds'
    ellipsoid (about the consistent estimate) in at least 88 % of them (95 % stated; a prior equal to the
    truth pulls the centre toward it, so coverage may exceed 95 %: 99 % measured, mean
    ``d^T Cov^-1 d / p`` 0.36), and every fit is physical. The same covariance about the unconstrained
    estimate, which no prior pulls, is calibrated on this second arm too: coverage within [0.88, 0.99]
    (95 +- 2.2 % binomial standard deviation: -3.2 and +1.8 sigma) and the mean within [0.7, 1.3]
    (measured 2026-12-06: 94 %, 0.997; the white covariance 94 %, 0.981: this arm's residual is flat).
    bounds.toml's ellipsoid over theta **and** the friction and offsets (rc3r-bounds/2; the plant's Coulomb
    law is ``sign``, the fit's ``tanh``) contains the truth in at least 88 % of the logs too."""
    inside, inside_u, m2_u, inside_all = [], [], [], []
    for seed in range(100):
        log, truth = sample_log(pendulum_motion, seed=seed)
        res = identify(pendulum, log, consistency=False, seed=seed)
        b = res.bounds()
        d = b["theta0"] - truth["theta"]
        inside.append(d @ b["P"] @ d <= 1.0)
        a = b["actuator"]  # bounds.toml's ellipsoid over theta and the joint coefficients (rc3r-bounds/2)
        true_joint = {"viscous": truth["viscous"], "coulomb": truth["coulomb"], "offset": truth["offset"],
                      "armature": np.zeros(pendulum.n)}
        d_all = a["theta0"] - np.concatenate([truth["theta"]] + [true_joint[k] for k in a["kinds"]])
        inside_all.append(d_all @ a["P"] @ d_all <= 1.0)
        du = res.theta - truth["theta"]
        m = float(du @ np.linalg.solve(res.cov_theta, du))
        inside_u.append(m <= res.ellipsoid["chi2"])
        m2_u.append(m / du.size)
        assert np.all(_pin_min_eigenvalues(res.physical_fit.standard) > 0)
    coverage = float(np.mean(inside))
    print(f"\ncoverage of the 95 % physical ellipsoid over 100 logs: {100 * coverage:.1f} %; unconstrained "
          f"{100 * np.mean(inside_u):.1f} %, mean d^T Cov^-1 d / p {np.mean(m2_u):.3f}; bounds.toml's ellipsoid over "
          f"theta and friction (rc3r-bounds/2) {100 * np.mean(inside_all):.1f} %")
    assert coverage >= 0.88
    assert np.mean(inside_all) >= 0.88
    assert 0.88 <= np.mean(inside_u) <= 0.99
    assert 0.7 <= np.mean(m2_u) <= 1.3


@pytest.mark.slow
def test_a_wrong_urdf_prior_does_not_drag_the_estimate_out_of_its_ellipsoid(pendulum, pendulum_motion):
    """The prior taken from a pendulum whose every standard parameter is 1.5x the truth, 50 seeded logs:
    the truth still lies in the bounds' ellipsoid in at least 88 % of them (the gamma rule lets the prior
    move the estimate by at most one standard deviation beyond what consistency forces). Mutant: choosing
    the largest gamma (1e4) gives 17 % over 30 logs."""
    wrong = pendulum.with_standard_parameters(pendulum.standard_parameters() * 1.5, "wrong prior")
    inside = []
    for seed in range(50):
        log, truth = sample_log(pendulum_motion, seed=seed)
        b = identify(wrong, log, consistency=False, seed=seed).bounds()
        d = b["theta0"] - truth["theta"]
        inside.append(d @ b["P"] @ d <= 1.0)
    coverage = float(np.mean(inside))
    print(f"\ncoverage with a prior 1.5x the truth over 50 logs: {100 * coverage:.1f} %")
    assert coverage >= 0.88


@pytest.fixture(scope="module")
def indefinite_ur5(tmp_path_factory):
    """A UR5 bounds file whose theta0 is T pi of the URDF's links with link 6's Ixx, Iyy, Izz set to -0.05 kg m^2
    (no rigid body), and the smallest eigenvalue of M along the default reference by Pinocchio's CRBA."""
    ur5 = rc3r.load_robot("ur5")
    pi = ur5.standard_parameters().copy()
    pi[[54, 56, 59]] = -0.05  # Ixx, Iyy, Izz of link 6
    theta0 = ur5.theta_of_standard(pi)
    P = np.eye(ur5.p) * 1e6
    rho_i = np.sqrt(np.diag(np.linalg.inv(P)))
    path = tmp_path_factory.mktemp("ind") / "bounds.toml"
    write_bounds(path, {"theta0": theta0, "P": P, "rho": float(rho_i.max()), "rho_i": rho_i, "confidence": 0.95,
                        "chi2": 1.0}, ur5, robot_name="ur5")
    model = ur5.model.copy()
    model.inertias[6] = pin.Inertia.FromDynamicParameters(pi[50:60])
    data = model.createData()
    t = np.linspace(0.0, 10.0, 200)
    Q = ur5.default_trajectory().evaluate(t)[0]
    low = min(np.linalg.eigvalsh(pin.crba(model, data, q))[0] for q in Q)
    return path, low


@pytest.mark.parametrize("command", [
    ["run", "--robot", "ur5", "--controller", "robust-coeff", "--rate", "1000"],
    ["montecarlo", "--robot", "ur5", "--n", "2", "--workers", "1"],
    ["design", "--robot", "ur5", "--rate", "1000", "--n", "2", "--workers", "1"],
])
def test_indefinite_mass_matrix_is_refused_in_one_line(indefinite_ur5, tmp_path, capsys, command):
    """run, montecarlo and design on the indefinite file: exit 2, one line naming joint 6 and the smallest
    eigenvalue (Pinocchio's, to the printed 3 digits)."""
    path, low = indefinite_ur5
    assert low < 0
    rc = main(command + ["--bounds", str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert rc == 2, err
    assert len(err.splitlines()) == 1, err
    assert "not positive definite" in err and "joint 6" in err and f"{low:.3g}" in err, (err, low)


#: Issue 35's targets for the consistent estimate's held-out RMS [N m] on the real Panda log.
PANDA_RMS_TARGETS = (0.33, 0.44, 0.29, 0.46, 0.12, 0.13, 0.07)


@pytest.mark.slow  # the real log: a whole identify with cross-validation
@pytest.mark.skipif(shared_panda_log() is None,
                    reason="the real Panda log (GPL-3) is absent: <repo>/../shared/data/panda_gaz or RC3R_SHARED_DATA")
def test_real_panda_log_gives_a_consistent_plausible_accurate_estimate():
    """The defaults (settings by cross-validation), last 30 % held out, the estimate bounds.toml carries
    evaluated exactly as validation.rms (held_out_rms): Pinocchio's pseudo-inertias PD, every link mass within 3x of the URDF's, held-out
    RMS under the targets, and M of the bounds' centre positive definite along the default reference."""
    from rc3r.identify.log import load_log
    from rc3r.uncertainty.ellipsoid import require_positive_mass_matrix

    panda = rc3r.load_robot("panda")
    res = identify(panda, load_log(shared_panda_log(), n=7), test_fraction=0.3, consistency=False)
    pf = res.physical_fit
    assert np.all(_pin_min_eigenvalues(pf.standard) > 0)
    ratio = pf.masses / panda.standard_parameters()[0::10]
    assert np.all((ratio >= 1 / 3) & (ratio <= 3)), ratio
    rms = res.held_out_rms(pf.x)
    assert np.all(rms <= np.asarray(PANDA_RMS_TARGETS)), rms
    assert require_positive_mass_matrix(panda, res.bounds()["theta0"], panda.default_trajectory(), 10.0, "x") > 0


def test_indefinite_model_theta_of_a_config_is_refused(tmp_path, capsys):
    """A config's [model] theta list whose mass matrix is not positive definite (the UR5's theta negated:
    M = -M_nominal; the FBL law takes it) is refused by run in one line, exit 2, naming the smallest eigenvalue."""
    ur5 = rc3r.load_robot("ur5")
    cfg = tmp_path / "c.toml"
    cfg.write_text('robot = "ur5"\n[model]\ntheta = [' + ", ".join(repr(float(-x)) for x in ur5.theta)
                   + "]\n")
    rc = main(["run", "--config", str(cfg), "--controller", "fbl", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "model theta of the config" in err and "not positive definite" in err and "smallest eigenvalue -" in err


def test_no_physical_bounds_are_the_unconstrained_estimate(pendulum_result):
    """bounds("unconstrained") is the least-squares centre and ellipsoid, without link parameters."""
    res, _ = pendulum_result
    b = res.bounds("unconstrained")
    np.testing.assert_array_equal(b["theta0"], res.theta)
    assert "physical" not in b
