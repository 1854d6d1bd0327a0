"""rc3r.robots.rr3.params: Table 1 -> Table 2, theta broadcasting, physical checks, TOML loading."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rc3r.errors import ConfigError, ParameterError
from rc3r.robots.rr3.params import (
    STD_NAMES,
    ArmParams,
    LinkParams,
    load_params,
    physical_issues,
    theta,
    theta_from_vector,
)

#: Table 2 of the paper (theta of the Table 1 robot), printed with at most 3 digits.
TABLE2 = (33, -11.6, 3.4, -14, -4.4, -2, 12, 1.4, -3.8, -0.2, -2.2, 29.2, 15.3, 15, 3)

VALID_TOML = """
name = "test"
g0 = 9.81
[[link]]
length = 1.0
mass = 1.0
com = [0.1, 0.0, 0.0]
inertia = { ixx = 0.1, iyy = 0.1, izz = 0.1, ixy = 0.0, ixz = 0.0, iyz = 0.0 }
[[link]]
length = 0.5
mass = 2.0
com = [0.0, 0.1, 0.0]
inertia = [0.2, 0.2, 0.2, 0.0, 0.0, 0.0]
[[link]]
length = 0.7
mass = 3.0
com = [0.0, 0.0, 0.1]
inertia = { ixx = 0.3, iyy = 0.3, izz = 0.3, ixy = 0.0, ixz = 0.0, iyz = 0.0 }
"""


def test_theta_of_table1_equals_table2(table1):
    """theta(Table 1) == Table 2 (section 3.1.1 formulas).

    Tolerance 1e-12: each entry is a sum of a few products of decimal numbers
    below 10; float64 rounding is ~1e-14.
    """
    np.testing.assert_allclose(theta(table1), TABLE2, rtol=0, atol=1e-12)


def test_theta_from_vector_broadcasts_over_batch(table1, rng):
    """theta_from_vector(std (..., 30)) == stack of theta_from_vector of each row (exact)."""
    base = table1.to_vector()
    batch = base + rng.uniform(-0.1, 0.1, size=(4, 5, 30))
    out = theta_from_vector(batch, table1.lengths)
    assert out.shape == (4, 5, 15)
    for idx in np.ndindex(4, 5):
        np.testing.assert_array_equal(out[idx], theta_from_vector(batch[idx], table1.lengths))


def test_theta_does_not_depend_on_l1(table1):
    """theta(std, (l1, l2, l3)) == theta(std, (l1', l2, l3)): the base height enters neither M nor g."""
    v = table1.to_vector()
    np.testing.assert_array_equal(theta_from_vector(v, (1.0, 1.0, 1.0)),
                                  theta_from_vector(v, (7.0, 1.0, 1.0)))


def test_physical_issues_flags_triangle_inequality_of_links_2_and_3(table1):
    """Table 1: I_2, I_3 have eigenvalues (0.3, 0.3, 0.9), 0.9 > 0.3 + 0.3; I_1 is fine."""
    issues = physical_issues(table1)
    assert len(issues) == 2
    assert issues[0].startswith("link 2") and "triangle" in issues[0]
    assert issues[1].startswith("link 3") and "triangle" in issues[1]
    assert not any(i.startswith("link 1") for i in issues)
    np.testing.assert_allclose(np.linalg.eigvalsh(table1.links[1].inertia_matrix), (0.3, 0.3, 0.9),
                               atol=1e-12)


def test_physical_issues_flags_negative_mass_and_non_pd_inertia(table1):
    """mass <= 0 and a non-positive-definite inertia each produce one issue for that link."""
    links = list(table1.links)
    links[0] = LinkParams(1.0, -1.0, (0, 0, 0), (1, 1, 1, 0, 0, 0))
    links[1] = LinkParams(1.0, 1.0, (0, 0, 0), (1, 1, -1, 0, 0, 0))
    issues = physical_issues(ArmParams(tuple(links)))
    assert any(i.startswith("link 1") and "mass" in i for i in issues)
    assert any(i.startswith("link 2") and "positive definite" in i for i in issues)


def test_physically_consistent_arm_has_no_issues():
    """A uniform-ish body (diag inertia, all moments equal) is consistent: no issue."""
    link = LinkParams(1.0, 2.0, (0.1, 0.2, 0.3), (0.2, 0.2, 0.2, 0.0, 0.0, 0.0))
    assert physical_issues(ArmParams((link, link, link))) == []


@pytest.mark.parametrize("field", ["length", "mass", "com", "inertia"])
def test_nan_in_link_params_raises_parameter_error(field):
    """A NaN anywhere in a link is refused at construction (ParameterError)."""
    kwargs = dict(length=1.0, mass=1.0, com=(0, 0, 0), inertia=(1, 1, 1, 0, 0, 0))
    kwargs[field] = {"length": np.nan, "mass": np.nan, "com": (0, np.nan, 0),
                     "inertia": (1, 1, np.nan, 0, 0, 0)}[field]
    with pytest.raises(ParameterError):
        LinkParams(**kwargs)


def test_nan_g0_raises_parameter_error(table1):
    with pytest.raises(ParameterError):
        ArmParams(table1.links, g0=float("nan"))


def test_load_params_reads_valid_toml(tmp_path):
    """Both inertia forms (table of keys, list in INERTIA_KEYS order) load."""
    path = tmp_path / "p.toml"
    path.write_text(VALID_TOML)
    p = load_params(path)
    assert p.name == "test" and p.lengths == (1.0, 0.5, 0.7)
    assert p.links[1].inertia == (0.2, 0.2, 0.2, 0.0, 0.0, 0.0)


def test_load_params_missing_file_raises_config_error(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_params(tmp_path / "nope.toml")


def test_load_params_malformed_toml_raises_config_error(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[[link]\nmass = = 1\n")
    with pytest.raises(ConfigError, match="malformed TOML"):
        load_params(path)


@pytest.mark.parametrize("key", ["mass", "com", "length", "izz"])
def test_load_params_missing_key_raises_config_error(tmp_path, key):
    """Dropping any required key gives a ConfigError naming it."""
    lines = VALID_TOML.splitlines()
    if key == "izz":
        text = VALID_TOML.replace(", izz = 0.1", "", 1)
    else:
        drop = next(i for i, line in enumerate(lines) if line.startswith(f"{key} ="))
        text = "\n".join(lines[:drop] + lines[drop + 1:])
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=key):
        load_params(path)


def test_arm_params_vector_round_trip(table1, rng):
    """from_vector(to_vector(p)) == p, also for random numbers; STD_NAMES names 10 per link."""
    assert len(STD_NAMES) == 10 and len(table1.to_vector()) == 30
    assert ArmParams.from_vector(table1.to_vector(), table1.lengths) == table1
    v = rng.uniform(-1, 1, 30)
    p = ArmParams.from_vector(v, (0.3, 0.4, 0.5), g0=3.0, name="x")
    np.testing.assert_array_equal(p.to_vector(), v)
    assert p.lengths == (0.3, 0.4, 0.5) and p.g0 == 3.0 and p.name == "x"


@pytest.mark.parametrize("shape", [(29,), (31,), (3, 10)])
def test_from_vector_wrong_shape_raises_parameter_error(shape):
    """from_vector needs exactly 30 numbers (10 per link): fewer, more or a matrix is an error."""
    with pytest.raises(ParameterError):
        ArmParams.from_vector(np.zeros(shape), (1, 1, 1))


def test_parameters_are_immutable(table1):
    """ArmParams and LinkParams are frozen: theta and the URDF computed from them cannot go stale."""
    import dataclasses

    with pytest.raises(dataclasses.FrozenInstanceError):
        table1.links[0].mass = 2.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        table1.g0 = 1.0


@pytest.mark.parametrize("field, value", [("com", (0.1, 0.2)), ("com", (0.1, 0.2, 0.3, 0.4)),
                                          ("inertia", (1.0,) * 5), ("inertia", (1.0,) * 7)])
def test_link_vectors_of_the_wrong_length_are_refused(field, value):
    """A CoM needs 3 numbers and an inertia 6: fewer or more is an error, never truncated."""
    kw = dict(length=1.0, mass=1.0, com=(0.0, 0.0, 0.0), inertia=(1.0, 1.0, 1.0, 0.0, 0.0, 0.0))
    kw[field] = value
    with pytest.raises(ParameterError):
        LinkParams(**kw)


@pytest.mark.parametrize("mass", [0.0, -0.5])
def test_zero_or_slightly_negative_mass_is_an_issue_of_that_link(mass):
    """On an otherwise consistent arm (tests/_helpers.py's "unequal"), the one issue is link 3's mass."""
    from _helpers import named_arm

    links = list(named_arm("unequal").params.links)
    links[2] = LinkParams(1.0, mass, (0, 0, 0), (1, 1, 1, 0, 0, 0))
    issues = physical_issues(ArmParams(tuple(links)))
    assert len(issues) == 1 and issues[0].startswith("link 3: mass")


def test_inertia_singular_relative_to_its_size_is_an_issue():
    """Principal moments (1e-9, 1e3, 1e3) kg m^2: positive, but 1e-12 of the largest -- numerically
    singular (the test is relative to the largest moment, not to 1 kg m^2)."""
    from _helpers import named_arm

    links = list(named_arm("unequal").params.links)
    links[1] = LinkParams(1.0, 1.0, (0, 0, 0), (1e-9, 1e3, 1e3, 0, 0, 0))
    issues = physical_issues(ArmParams(tuple(links)))
    assert len(issues) == 1 and issues[0].startswith("link 2: inertia is not positive definite")


@pytest.mark.parametrize("length", [0.0, -1.0])
def test_non_positive_link_length_is_refused_naming_the_link(table1, length):
    links = list(table1.links)
    links[1] = LinkParams(length, 1.0, (0, 0, 0), (1, 1, 1, 0, 0, 0))
    with pytest.raises(ParameterError, match="link 2 length must be > 0"):
        ArmParams(tuple(links))


def test_a_bad_link_in_a_parameter_file_is_named(tmp_path):
    """The parameter file's links are numbered from 1 in messages (the second [[link]] is link 2)."""
    src = (Path(__file__).resolve().parents[1] / "src/rc3r/robots/rr3/data/rr3.toml").read_text()
    parts = src.split("[[link]]")
    parts[2] = parts[2].replace(", iyz = 0.2 }", " }", 1)
    f = tmp_path / "p.toml"
    f.write_text("[[link]]".join(parts))
    with pytest.raises(ConfigError, match="link 2 inertia lacks iyz"):
        load_params(f)


def test_near_singular_inertia_is_judged_against_its_largest_moment():
    """Principal moments (1e-10, 1, 1e3) kg m^2: the smallest is 1e-13 of the largest, so the inertia
    is numerically singular ("not positive definite"), whatever the middle moment."""
    from _helpers import named_arm

    links = list(named_arm("unequal").params.links)
    links[0] = LinkParams(1.0, 1.0, (0, 0, 0), (1e-10, 1.0, 1e3, 0, 0, 0))
    issues = physical_issues(ArmParams(tuple(links)))
    assert len(issues) == 1 and issues[0].startswith("link 1: inertia is not positive definite")
