"""rc3r.uncertainty.ellipsoid: plants drawn from an identification's ellipsoid, and the campaigns on them.

The properties: a drawn plant's own dynamics (Pinocchio's RNEA on its model) equal the regressor times
the drawn theta; that theta lies in the ellipsoid (on its boundary for ``boundary:``); the radial law of
``draw_theta`` is the uniform ball's, P(r <= t) = t^p; a consistent arm's plants are real rigid bodies,
and a draw is refused exactly when the consistency SDP finds no consistent parameters; ``montecarlo
--bounds`` runs plants of the file's ellipsoid, not of the box.
"""
from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

import rc3r
from rc3r.cli import main
from rc3r.errors import ConfigError, ParameterError
from rc3r.uncertainty.ellipsoid import draw_from_ellipsoid, draw_theta, ellipsoid_factor, realise_theta


def _box_ellipsoid(arm, rel=0.05, floor=1e-3):
    """An axis-aligned ellipsoid of half-widths rel |theta| + floor about the arm's theta."""
    return np.diag(1.0 / (rel * np.abs(arm.theta) + floor) ** 2)


@pytest.fixture(scope="module", params=["rr3", "ur5", "panda"])
def arm(request):
    return rc3r.load_robot(request.param)


def test_factor_fills_the_ellipsoid(rng):
    """L L^T = P^-1 for a random SPD P (so theta_0 + L u with |u| <= 1 is the ellipsoid); a non-SPD P is refused."""
    A = rng.standard_normal((5, 5))
    P = A @ A.T + 0.1 * np.eye(5)
    L = ellipsoid_factor(P)
    np.testing.assert_allclose(L @ L.T, np.linalg.inv(P), rtol=1e-10, atol=1e-12)
    with pytest.raises(ParameterError, match="not positive definite"):
        ellipsoid_factor(np.diag([1.0, -1.0]))


def test_radial_law_is_the_uniform_balls(rng):
    """r = sqrt(d^T P d) of uniform draws in a p-ellipsoid: P(r <= t) = t^p, so r^p is U(0, 1); a
    Kolmogorov-Smirnov test at 2000 draws (p = 15) with a critical value 1.63/sqrt(n) (alpha = 1 %)."""
    p = 15
    A = rng.standard_normal((p, p))
    P = A @ A.T + np.eye(p)
    theta0 = rng.standard_normal(p)
    d = np.array([draw_theta(theta0, P, rng) - theta0 for _ in range(2000)])
    r = np.sqrt(np.einsum("ki,ij,kj->k", d, P, d))
    u = np.sort(r ** p)
    ks = np.max(np.abs(u - (np.arange(1, u.size + 1) - 0.5) / u.size))
    assert r.max() <= 1.0 + 1e-12 and ks < 1.63 / np.sqrt(u.size)
    b = draw_theta(theta0, P, rng, boundary=True) - theta0
    assert b @ P @ b == pytest.approx(1.0, rel=1e-12)


def test_drawn_plant_dynamics_are_the_regressor_times_the_drawn_theta(arm, rng):
    """Pinocchio's RNEA on the plant's own model == Y(q, qd, qdd) @ theta_drawn at random states
    (relative 1e-9 of |tau|), theta_drawn inside the ellipsoid; the plant is seeded (same spec, same
    parameters) and as physically consistent as the nominal arm (no new issue)."""
    P = _box_ellipsoid(arm)
    plant = draw_from_ellipsoid(arm, arm.theta, P, "random:5")
    again = draw_from_ellipsoid(arm, arm.theta, P, "random:5")
    np.testing.assert_array_equal(plant.standard_parameters(), again.standard_parameters())
    d = plant.theta - arm.theta
    assert d @ P @ d <= 1.0 + 1e-9 and np.linalg.norm(d) > 0
    model = plant.model
    data = model.createData()
    for _ in range(5):
        q, qd, qdd = rng.uniform(-1.5, 1.5, (3, arm.n))
        tau = pin.rnea(model, data, q, qd, qdd)
        pred = np.asarray(arm.regressor(q, qd, qd, qdd)) @ plant.theta
        np.testing.assert_allclose(pred, tau, rtol=0, atol=1e-9 * max(1.0, np.abs(tau).max()))
    assert len(plant.physical_issues()) <= len(arm.physical_issues())


def test_boundary_and_centre(arm):
    """boundary:<seed> lies on the ellipsoid's surface; centre realises theta_0 itself."""
    P = _box_ellipsoid(arm)
    theta0 = arm.theta * 1.01
    b = draw_from_ellipsoid(arm, theta0, P, "boundary:1")
    d = b.theta - theta0
    assert d @ P @ d == pytest.approx(1.0, rel=1e-6)
    c = draw_from_ellipsoid(arm, theta0, P, "centre")
    np.testing.assert_allclose(c.theta, theta0, rtol=1e-9, atol=1e-12)


def test_bad_specs_are_refused():
    arm = rc3r.load_robot("rr3")
    P = _box_ellipsoid(arm)
    for spec, kind, needle in (("upper", ConfigError, "expected nominal"), ("random:-1", ConfigError, "seed >= 0"),
                               ("random:x", ConfigError, "seed >= 0")):
        with pytest.raises(kind, match=needle):
            draw_from_ellipsoid(arm, arm.theta, P, spec)
    far = arm.theta.copy()
    far[:] = -1e3 * np.abs(far).max()  # negative inertias everywhere: no robot near the 3R has them
    with pytest.raises(ParameterError):
        draw_from_ellipsoid(arm, far, np.eye(arm.p) * 1e12, "centre")


def test_refused_draws_are_exactly_the_physically_inconsistent_ones():
    """On the UR5 (consistent URDF) with 5 % half-widths: realise_theta succeeds on a draw iff the
    consistency SDP (cvxpy, an independent method) finds consistent parameters at distance ~0 from it
    (1e-6 in the identity metric: the SDP's accuracy), over 12 seeded draws; prints the fraction."""
    pytest.importorskip("cvxpy")
    from rc3r.identify.consistency import check_consistency

    arm = rc3r.load_robot("ur5")
    P = _box_ellipsoid(arm)
    rng = np.random.default_rng(0)
    agree, ok = 0, 0
    for _ in range(12):
        th = draw_theta(arm.theta, P, rng)
        try:
            realise_theta(arm, th)
            realised = True
        except ParameterError:
            realised = False
        d = check_consistency(arm, th, np.eye(arm.p), 1.0)["mahalanobis"]
        agree += realised == (d < 1e-6)
        ok += realised
    print(f"UR5, 5 % ellipsoid: {ok} of 12 draws realisable; realise_theta and the SDP agree on {agree} of 12")
    assert agree == 12 and 0 < ok < 12


@pytest.fixture(scope="module")
def bounds_3r(tmp_path_factory):
    """A bounds.toml of the 3R: theta_0 = the nominal theta, a 3 % ellipsoid (written with rc3r's writer)."""
    from rc3r.identify.bounds_file import load_bounds, write_bounds

    arm = rc3r.load_robot("rr3")
    P = _box_ellipsoid(arm, rel=0.03)
    L = ellipsoid_factor(P)
    rho = float(np.linalg.norm(L, 2))
    rho_i = np.sqrt(np.diag(np.linalg.inv(P)))
    path = tmp_path_factory.mktemp("b") / "bounds.toml"
    write_bounds(path, {"theta0": arm.theta, "P": P, "rho": rho, "rho_i": rho_i, "confidence": 0.95, "chi2": 1.0},
                 arm, robot_name="rr3")
    load_bounds(path, robot=arm)
    return path, arm, P


def test_montecarlo_on_bounds_draws_plants_in_the_ellipsoid(bounds_3r, tmp_path):
    """montecarlo --bounds: every plant's distance ||theta - theta_0|| (runs.csv, theta_dist) is inside the
    file's ball rho and is not the nominal plant's (0); the robust law tracks them all (0 diverged)."""
    from rc3r.campaign import read_rows

    path, arm, P = bounds_3r
    out = tmp_path / "mc"
    assert main(["montecarlo", "--bounds", str(path), "--n", "4", "--duration", "0.5", "--controllers",
                 "robust", "--workers", "1", "--out", str(out)]) == 0
    rows = read_rows(out / "runs.csv")
    rho = json.loads((out / "summary.json").read_text())["radii"]["rho"]
    dist = [r["theta_dist"] for r in rows]
    assert len(rows) == 4 and all(0 < x <= rho * (1 + 1e-9) for x in dist) and len(set(dist)) == 4
    assert all(r["status"] == "ok" for r in rows)


def test_design_on_bounds_verifies_on_the_centre_and_draws_and_names_the_file_portably(bounds_3r, tmp_path,
                                                                                      monkeypatch):
    """design --bounds (relative path, from another directory): its runs are the ellipsoid's centre and N
    draws (theta_dist 0 for the centre to 1e-9 rho, > 0 and <= rho for the draws), and design.toml names the
    bounds file relative to itself (issue 33: a design survives a moved project), so montecarlo --config
    design.toml runs from any directory."""
    import os

    from rc3r.campaign import read_rows
    from rc3r.io import read_toml

    path, arm, P = bounds_3r
    monkeypatch.chdir(path.parent)
    out = tmp_path / "d"
    main(["design", "--robot", "rr3", "--bounds", path.name, "--rate", "1000", "--margin", "1", "--n", "2",
          "--duration", "0.3", "--workers", "1", "--out", str(out)])
    cfg = read_toml(out / "design.toml", "design")
    assert cfg["bounds"] == os.path.relpath(path.resolve(), out.resolve())
    rows = [r for r in read_rows(out / "runs.csv") if r["controller"] == "robust"]
    rho = rows[0]["rho"]
    centre = [r["theta_dist"] for r in rows if r["job"].startswith("centre/")]
    drawn = [r["theta_dist"] for r in rows if r["plant"] >= 0]
    assert centre and max(centre) <= 1e-9 * rho
    assert drawn and all(0 < d <= rho * (1 + 1e-9) for d in drawn)
    monkeypatch.chdir(tmp_path)
    assert main(["montecarlo", "--config", str(out / "design.toml"), "--n", "1", "--duration", "0.2",
                 "--controllers", "robust", "--workers", "1", "--out", str(tmp_path / "mc")]) == 0
