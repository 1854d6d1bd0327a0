"""Uncertainty box -> (theta_0, rho): the paper's Table 3 and the certified exact ranges."""
from __future__ import annotations

import json
import textwrap

import numpy as np
import pytest

from rc3r.errors import ConfigError, ParameterError
from rc3r.robots.rr3 import RR3
from rc3r.robots.rr3.paper import paper_box
from rc3r.robots.rr3.params import ArmParams, theta, theta_from_vector
from rc3r.robots.rr3.robot import PARAM_NAMES
from rc3r.uncertainty import (
    Box,
    certified_bounds,
    paper_bounds,
    paper_upper,
    perturb,
    quadratic_box_extrema,
    sampled_rho,
    sampled_rho_detail,
)
from rc3r.uncertainty import load_box as _load_box
from rc3r.uncertainty.bounds import _structure


def load_box(path):
    return _load_box(path, PARAM_NAMES)

TABLE3 = np.array([164.25, -33.9, -19.1, -41.5, -54.8, -13, 28, -9, -34.8, -14.4, -27.4, 116.3, 71.2, 32.5, -5.5])
PAPER_RHO = 186.8129


@pytest.fixture(scope="module")
def cert(table1):
    return certified_bounds(RR3(table1), paper_box())


def _one_line(exc_info):
    msg = str(exc_info.value)
    assert msg and "\n" not in msg, msg
    return msg


# ----------------------------------------------------------------- method (a)


def test_table3_exact(table1):
    b = paper_bounds(RR3(table1), paper_box())
    np.testing.assert_allclose(b.theta0, TABLE3, rtol=0, atol=1e-9)
    assert b.rho == pytest.approx(PAPER_RHO, abs=5e-5)
    assert b.rho == pytest.approx(np.linalg.norm(TABLE3 - theta(table1)), abs=1e-9)
    assert b.inertia_keys == ("iyy", "izz")
    assert b.rho_i is None and b.theta_lo is None


def test_text_reading_all_inertia_entries_gives_another_table(table1):
    """The text perturbs every inertia entry; that does NOT reproduce Table 3 (docs/bounds.md)."""
    b = paper_bounds(RR3(table1), paper_box(), inertia_keys="all")
    differs = np.flatnonzero(np.abs(b.theta0 - TABLE3) > 1e-6)
    # entries that contain Ixx, Ixy, Ixz or Iyz of links 2, 3: theta_2..5, 8..11
    assert (differs + 1).tolist() == [2, 3, 4, 5, 8, 9, 10, 11]
    np.testing.assert_allclose(b.theta0[[1, 2, 3, 4]], [-33.4, -18.1, -41.0, -53.8], atol=1e-9)
    assert abs(b.rho - PAPER_RHO) > 0.1
    assert b.rho == pytest.approx(186.0811, abs=5e-5)


@pytest.mark.parametrize("keys", [("iyy", "Iqq"), ("rcz",), ("m",), "aaa", ""], ids=["typo", "com", "mass", "aaa", "empty"])
def test_paper_inertia_keys_validated(table1, keys):
    """Only inertia entries (ixx .. iyz) or "all": a CoM coordinate or the mass is not an inertia key,
    and no other string means "all"."""
    with pytest.raises(ConfigError, match="unknown inertia entries") as e:
        paper_bounds(RR3(table1), paper_box(), inertia_keys=keys)
    _one_line(e)


# ----------------------------------------------------------------- method (b)


@pytest.mark.parametrize("lengths", [(1.0, 1.0, 1.0), (0.7, 1.3, 0.45)])
def test_structure_decomposition_is_exact(rng, lengths):
    S = _structure(RR3(ArmParams.from_vector(np.ones(30), lengths)))
    v = rng.uniform(-2, 2, size=(500, 30))
    ref = theta_from_vector(v, lengths)
    np.testing.assert_allclose(S.evaluate(v), ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def test_quadratic_box_extrema_exact(rng):
    g = np.linspace(0, 1, 41)
    grid = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    for trial in range(30):
        a = rng.normal()
        b = rng.normal(size=3)
        A = rng.normal(size=(3, 3))
        Q = A + A.T
        if trial % 3 == 1:  # singular Hessian (as in theta: e.g. rcz^2 + (l2 + rcx)^2)
            Q[:, 2] = Q[2, :] = 0.0
        lo = rng.uniform(-1, 0, 3)
        hi = lo + rng.uniform(0.1, 2, 3)
        x = lo + grid * (hi - lo)
        vals = a + x @ b + np.einsum("ni,ij,nj->n", x, Q, x)
        hmin, xmin, hmax, xmax = quadratic_box_extrema(a, b, Q, lo, hi)
        assert hmin <= vals.min() + 1e-12 and hmax >= vals.max() - 1e-12
        for h, xx in ((hmin, xmin), (hmax, xmax)):  # attained inside the box
            assert np.all(xx >= lo) and np.all(xx <= hi)
            assert a + b @ xx + xx @ Q @ xx == pytest.approx(h, abs=1e-12)


def test_certified_ranges_contain_random_box_samples(table1, cert, rng):
    box = cert.box
    v = table1.to_vector() + box.sample(rng, 20000)
    th = theta_from_vector(v, table1.lengths)
    assert np.all(th >= cert.theta_lo - 1e-9) and np.all(th <= cert.theta_hi + 1e-9)
    assert np.all(np.linalg.norm(th - cert.theta0, axis=1) <= cert.rho + 1e-9)


def test_certified_ranges_contain_all_corners_of_a_sub_box(table1, cert, rng):
    """All 2^12 corners over the CoM and masses of links 2, 3 and two inertia entries, rest random."""
    box = cert.box
    idx = np.array([10, 11, 12, 13, 20, 21, 22, 23, 14, 17, 24, 27])
    base = box.sample(rng, 1)[0]
    bits = (np.arange(1 << idx.size)[:, None] >> np.arange(idx.size)) & 1
    d = np.repeat(base[None], len(bits), axis=0)
    d[:, idx] = np.where(bits, box.upper[idx], box.lower[idx])
    th = theta_from_vector(table1.to_vector() + d, table1.lengths)
    assert np.all(th >= cert.theta_lo - 1e-9) and np.all(th <= cert.theta_hi + 1e-9)


def test_certified_ranges_are_attained(table1, cert):
    nom = table1.to_vector()
    for W, target in ((cert.witness_lo, cert.theta_lo), (cert.witness_hi, cert.theta_hi)):
        assert np.all(cert.box.contains(W - nom, tol=1e-12))
        th = theta_from_vector(W, table1.lengths)
        np.testing.assert_allclose(np.diag(th), target, rtol=0, atol=1e-9)
    np.testing.assert_allclose(cert.rho_i, (cert.theta_hi - cert.theta_lo) / 2, atol=1e-12)
    np.testing.assert_allclose(cert.theta0, (cert.theta_hi + cert.theta_lo) / 2, atol=1e-12)
    assert cert.rho == pytest.approx(np.sqrt(np.sum(cert.rho_i**2)), rel=1e-14)


def test_certified_on_another_robot_and_box(rng):
    """Negative deltas, other lengths, per-link intervals: still contained and attained."""
    vec = rng.uniform(0.1, 1.0, 30)
    vec[[0, 10, 20]] = rng.uniform(2, 5, 3)
    p = ArmParams.from_vector(vec, (0.8, 1.2, 0.6))
    lo = -rng.uniform(0, 0.5, 30)
    hi = rng.uniform(0, 0.5, 30)
    box = Box(lo, hi)
    b = certified_bounds(RR3(p), box)
    th = theta_from_vector(vec + box.sample(rng, 5000), p.lengths)
    assert np.all(th >= b.theta_lo - 1e-9) and np.all(th <= b.theta_hi + 1e-9)
    np.testing.assert_allclose(np.diag(theta_from_vector(b.witness_lo, p.lengths)), b.theta_lo, atol=1e-9)
    np.testing.assert_allclose(np.diag(theta_from_vector(b.witness_hi, p.lengths)), b.theta_hi, atol=1e-9)


def test_zero_box_gives_zero_radius(table1):
    b = certified_bounds(RR3(table1), Box.zero(PARAM_NAMES))
    np.testing.assert_allclose(b.rho_i, 0.0, atol=1e-12)
    np.testing.assert_allclose(b.theta0, theta(table1), atol=1e-12)
    assert b.rho <= 1e-12
    assert paper_bounds(RR3(table1), Box.zero(PARAM_NAMES)).rho == 0.0


def test_rho_max_bounds_sampled_rho(table1, cert):
    s = sampled_rho_detail(RR3(table1), cert.box, cert.theta0, n=5000, seed=3)
    assert 0 < s.rho <= cert.rho
    assert np.all(cert.box.contains(s.witness - table1.to_vector()))
    assert np.linalg.norm(theta_from_vector(s.witness, table1.lengths) - cert.theta0) == pytest.approx(s.rho, abs=1e-12)
    assert s.rho >= cert.rho_i.max()  # each rho_i alone is attained
    assert sampled_rho(RR3(table1), cert.box, cert.theta0, n=5000, seed=3) == s.rho  # reproducible


def test_paper_rho_does_not_cover_the_box(table1):
    """The paper's rho is ||theta_0 - theta(p)||: some robot of the box is farther from theta_0."""
    a = paper_bounds(RR3(table1), paper_box())
    s = sampled_rho_detail(RR3(table1), a.box, a.theta0, n=2000, seed=0)
    assert s.rho > a.rho + 1.0


# ------------------------------------------------------------------ box, TOML


def test_paper_box_file():
    box = paper_box()
    assert box == Box.uniform(PARAM_NAMES, mass=(0, 10), com=(0, 1), inertia=(0, 1))
    assert box.upper[PARAM_NAMES.index("Ixy2")] == 1.0  # every inertia entry, as the text says


def test_box_toml_defaults_and_overrides(tmp_path):
    f = tmp_path / "box.toml"
    f.write_text(textwrap.dedent("""
        [delta]
        mass = [0, 2]
        com = [-0.1, 0.1]
        inertia = [0, 0.5]
        rcz = [0, 0]          # a single parameter beats its kind

        [[link]]
        index = 3
        m = [-1, 1]
        Ixy = 0.25            # a number = an exact shift
    """))
    box = load_box(f)
    lo = dict(zip(PARAM_NAMES, box.lower))
    hi = dict(zip(PARAM_NAMES, box.upper))
    assert (lo["m1"], hi["m1"]) == (0, 2) and (lo["m3"], hi["m3"]) == (-1, 1)
    assert (lo["rcx2"], hi["rcx2"]) == (-0.1, 0.1) and (lo["rcz2"], hi["rcz2"]) == (0, 0)
    assert (lo["Ixy3"], hi["Ixy3"]) == (0.25, 0.25) and (lo["Ixy2"], hi["Ixy2"]) == (0, 0.5)
    assert box.source == str(f)


@pytest.mark.parametrize(
    "text, err, needle",
    [
        ("[delta\nmass = [0, 1]", ConfigError, "malformed TOML"),
        ("[delta]\nmas = [0, 1]", ConfigError, "unknown key 'mas'"),
        ("[delta]\nmass = [0, 1, 2]", ConfigError, "expected [lower, upper]"),
        ("[delta]\nmass = ['a', 1]", ConfigError, "expected [lower, upper]"),
        ("title = 'x'", ConfigError, "unknown top-level"),
        ("description = 'x'", ConfigError, "missing key 'delta'"),
        ("[[link]]\nm = [0, 1]", ConfigError, "lacks 'index'"),
        ("[[link]]\nindex = 4\nm = [0, 1]", ConfigError, "index must be one of 1, 2, 3"),
        ("[delta]\nmass = [nan, 1]", ParameterError, "not finite for m1"),
        ("[delta]\ncom = [1, 0]", ParameterError, "rcx1 is empty: lower 1 > upper 0"),
    ],
)
def test_bad_box_files(tmp_path, text, err, needle):
    f = tmp_path / "box.toml"
    f.write_text(text)
    with pytest.raises(err) as e:
        load_box(f)
    assert needle in _one_line(e)


def test_missing_box_file(tmp_path):
    with pytest.raises(ConfigError) as e:
        load_box(tmp_path / "nope.toml")
    assert "not found" in _one_line(e)


def test_bad_box_objects(table1):
    ok = np.zeros(30)
    for lo, hi in ((np.full(30, np.nan), ok), (ok, np.r_[ok[:29], np.inf]), (np.ones(30), ok), (ok[:29], ok[:29])):
        with pytest.raises(ParameterError) as e:
            Box(lo, hi, PARAM_NAMES)
        _one_line(e)
    neg = Box(np.r_[-10.0, np.zeros(29)], np.zeros(30), PARAM_NAMES)  # m1 may reach 0 kg
    for fn in (certified_bounds, paper_bounds):
        with pytest.raises(ParameterError) as e:
            fn(RR3(table1), neg)
        assert "non-positive mass for link 1" in _one_line(e)


# --------------------------------------------------------------- perturbations


def test_perturb_specs(table1):
    box = paper_box()
    nom = table1.to_vector()
    rr = RR3(table1)
    assert perturb(rr, box, "nominal") is rr
    np.testing.assert_array_equal(perturb(rr, box, "upper").standard_parameters(), nom + box.upper)
    np.testing.assert_array_equal(perturb(rr, box, "lower").standard_parameters(), nom + box.lower)
    up = perturb(rr, box, "paper-upper")
    assert up.params == paper_upper(rr, box).params
    np.testing.assert_allclose((theta(table1) + up.theta) / 2, TABLE3, atol=1e-9)
    bits = "1000000000" + "0110000000" + "0000000001"
    c = perturb(rr, box, "corner:" + bits).standard_parameters() - nom
    np.testing.assert_array_equal(np.flatnonzero(c), [0, 11, 12, 29])
    assert perturb(rr, box, "corner:" + "_".join([bits[:10], bits[10:20], bits[20:]])).params == perturb(
        rr, box, "corner:" + bits).params
    r1, r2 = perturb(rr, box, "random:7"), perturb(rr, box, "random:7")
    assert r1.params == r2.params and r1.params != perturb(rr, box, "random:8").params
    assert r1.label == "random:7"
    assert box.contains(r1.standard_parameters() - nom)
    assert r1.params.lengths == table1.lengths and r1.params.g0 == table1.g0


@pytest.mark.parametrize("spec", ["", "uper", "corner:0101", "corner:" + "2" * 30, "random:x", "random:-1",
                                  "upper:1", None])
def test_bad_perturb_spec(table1, spec):
    with pytest.raises(ConfigError) as e:
        perturb(RR3(table1), paper_box(), spec)
    _one_line(e)


# ------------------------------------------------------------------------ CLI


def test_cli_bounds_json(capsys):
    from rc3r.cli import main

    assert main(["bounds", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(out["paper"]["theta0"], TABLE3, atol=1e-9)
    assert out["paper"]["rho"] == pytest.approx(PAPER_RHO, abs=5e-5)
    cert = out["certified"]
    assert len(cert["theta_lo"]) == len(cert["rho_i"]) == 15
    assert out["sampled_certified"]["rho"] <= cert["rho"]
    assert out["box"]["upper"][0] == 10.0


def test_cli_bounds_text_and_errors(capsys, tmp_path):
    from rc3r.cli import main

    assert main(["bounds"]) == 0
    out = capsys.readouterr().out
    assert "186.8129" in out and "rho_max" in out and "theta_15" in out
    bad = tmp_path / "b.toml"
    bad.write_text("[delta]\nmass = [1, 0]\n")
    assert main(["bounds", "--box", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rc3r: error:") and "\n" not in err


def test_certified_radius(table1, cert):
    from rc3r.uncertainty import certified_radius

    rho, rho_i = certified_radius(cert, cert.theta0)
    assert rho == pytest.approx(cert.rho, rel=1e-14)
    np.testing.assert_allclose(rho_i, cert.rho_i, atol=1e-12)
    a = paper_bounds(RR3(table1), paper_box())
    rho_a, _ = certified_radius(cert, a.theta0)
    s = sampled_rho_detail(RR3(table1), cert.box, a.theta0, n=2000, seed=0)
    assert cert.rho <= rho_a and s.rho <= rho_a
    with pytest.raises(ParameterError):
        certified_radius(a, a.theta0)


def test_perturb_simulable(table1):
    """Most random robots of the paper's box have a non-PD inertia; simulable=True redraws."""
    box = paper_box()
    rr = RR3(table1)
    assert any("positive definite" in s for s in perturb(rr, box, "random:0").physical_issues())
    r = perturb(rr, box, "random:0", simulable=True)
    assert not [s for s in r.physical_issues() if "triangle" not in s]
    assert box.contains(r.standard_parameters() - table1.to_vector())
    assert r.params == perturb(rr, box, "random:0", simulable=True).params
    for spec in ("upper", "lower", "paper-upper"):
        perturb(rr, box, spec, simulable=True)
    with pytest.raises(ParameterError) as e:  # Ixx2 = Iyy2 = 0.5 with Ixy2 = 1.2
        perturb(rr, box, "corner:" + "0" * 17 + "1" + "0" * 12, simulable=True)
    assert "not simulable" in _one_line(e)


def test_linear_certified_bounds_of_a_pinocchio_arm(ur5, rng):
    """For a Pinocchio arm theta = c + K std is linear, so the certified ranges are exact interval
    arithmetic: every theta of 2000 random box members lies in [theta_lo, theta_hi] (1e-9 slack for
    rounding of the O(10) kg m^2 sums), both ends are attained at the witnesses, rho_i is the half
    width and theta_0 the centre -- checked with the robot's own base-parameter map, independently
    of how the bounds were formed."""
    names = ur5.standard_parameter_names
    upper = np.zeros(len(names))
    upper[[10 * k for k in range(len(names) // 10)]] = 0.5         # every mass -0.1 .. +0.5 kg
    upper[[10 * k + 1 for k in range(len(names) // 10)]] = 0.05    # every m c_x +0.05 kg m
    box = Box(-0.2 * upper, upper, names)
    b = certified_bounds(ur5, box)
    std = ur5.standard_parameters()
    th = np.array([ur5.theta_of_standard(std + d) for d in box.sample(rng, 2000)])
    slack = 1e-9 * max(1.0, np.abs(b.theta_hi).max())
    assert np.all(th >= b.theta_lo - slack) and np.all(th <= b.theta_hi + slack)
    for i in range(b.theta_lo.size):  # witness row i: the box member where theta_i is extremal
        assert ur5.theta_of_standard(b.witness_lo[i])[i] == pytest.approx(b.theta_lo[i], abs=slack)
        assert ur5.theta_of_standard(b.witness_hi[i])[i] == pytest.approx(b.theta_hi[i], abs=slack)
    np.testing.assert_allclose(b.rho_i, 0.5 * (b.theta_hi - b.theta_lo), rtol=1e-15)
    np.testing.assert_allclose(b.theta0, 0.5 * (b.theta_hi + b.theta_lo), rtol=1e-15)
    assert b.rho == pytest.approx(np.linalg.norm(b.rho_i), rel=1e-12) and b.rho > 0


def test_bounds_are_frozen_and_say_what_rho_covers(table1, cert):
    """Bounds is immutable; its dict says the paper's rho covers the nominal robot only (with the
    inertia keys and theta_upper it used) and the certified rho the whole box."""
    import dataclasses

    paper = paper_bounds(RR3(table1), paper_box())
    with pytest.raises(dataclasses.FrozenInstanceError):
        paper.rho = 1.0
    dp, dc = paper.to_dict(), cert.to_dict()
    assert dp["rho_covers"].startswith("the nominal robot only") and dp["inertia_keys"] == ["iyy", "izz"]
    assert len(dp["theta_upper"]) == 15
    assert dc["rho_covers"].startswith("the whole box") and "theta_upper" not in dc and "inertia_keys" not in dc


@pytest.mark.parametrize("size", [14, 16])
def test_certified_radius_refuses_a_theta0_of_the_wrong_size(cert, size):
    from rc3r.uncertainty import certified_radius

    with pytest.raises(ParameterError, match="theta0 needs 15 finite entries"):
        certified_radius(cert, np.zeros(size))


def test_structure_of_a_robot_with_a_constant_term(rng):
    """The decomposition theta(v) = const + m (a + b.r + r^T Q r) + C I, extracted from evaluations
    only, reproduces a synthetic one-body robot whose theta has a constant term (the 3R's has
    none), for one standard-parameter vector (10,) and for a batch (5, 10)."""
    c0, a0 = rng.normal(size=4), rng.normal(size=4)
    b0, C0 = rng.normal(size=(4, 3)), rng.normal(size=(4, 6))
    A = rng.normal(size=(4, 3, 3))
    Q0 = A + A.transpose(0, 2, 1)

    class Synthetic:
        standard_parameter_names = tuple(f"x{i}" for i in range(10))

        @staticmethod
        def theta_of_standard(v):
            m, r, inertia = v[0], v[1:4], v[4:10]
            return c0 + m * (a0 + b0 @ r + np.einsum("j,ijl,l->i", r, Q0, r)) + C0 @ inertia

    S = _structure(Synthetic())
    V = rng.normal(size=(5, 10))
    want = np.array([Synthetic.theta_of_standard(v) for v in V])
    np.testing.assert_allclose(S.evaluate(V), want, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(S.evaluate(V[2]), want[2], rtol=1e-10, atol=1e-10)
