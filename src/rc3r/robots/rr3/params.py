r"""Link parameters of the 3R arm in the paper's convention, and the coefficients theta.

Conventions are fixed once in ``docs/conventions.md``: SI units; the CoM
``com`` [m] and the inertia about the CoM ``inertia`` [kg m^2] of link *i* are
expressed in DH frame *i*, which sits at the **distal** end of link *i*;
inertia entries are matrix entries (URDF ``ixy`` convention).

The 15 dynamic coefficients are those of section 3.1.1 of the paper; with
:math:`X_2 = l_2 + r_{cx2}` and :math:`X_3 = l_3 + r_{cx3}`

.. math::

    \theta_1 &= m_1(r_{cx1}^2 + r_{cz1}^2) + I_{yy1} + m_2 r_{cz2}^2 + m_2 X_2^2
               + I_{yy2} + m_3 r_{cz3}^2 + m_3 X_3^2 + I_{yy3} + m_3 l_2^2 \\
    \theta_2 &= -m_2 X_2^2 + m_2 r_{cy2}^2 - I_{yy2} + I_{xx2} - m_3 l_2^2 \\
    \theta_3 &= -2 m_2 r_{cy2} X_2 + 2 I_{xy2} \\
    \theta_4 &= m_3 r_{cy3}^2 - m_3 X_3^2 + I_{xx3} - I_{yy3} \\
    \theta_5 &= -2 m_3 r_{cy3} X_3 + 2 I_{xy3} \\
    \theta_6 &= -m_3 r_{cy3} l_2, \quad \theta_7 = m_3 X_3 l_2 \\
    \theta_8 &= -m_2 r_{cy2} r_{cz2} + I_{yz2} \\
    \theta_9 &= -m_2 X_2 r_{cz2} + I_{xz2} - m_3 r_{cz3} l_2 \\
    \theta_{10} &= -m_3 r_{cy3} r_{cz3} + I_{yz3}, \quad
    \theta_{11} = -m_3 X_3 r_{cz3} + I_{xz3} \\
    \theta_{12} &= m_2(r_{cy2}^2 + X_2^2) + I_{zz2} + m_3(l_2^2 + r_{cy3}^2 + X_3^2) + I_{zz3} \\
    \theta_{13} &= m_3(X_3^2 + r_{cy3}^2) + I_{zz3}, \quad
    \theta_{14} = m_2 X_2 + m_3 l_2, \quad \theta_{15} = -m_2 r_{cy2}

Table 1 gives exactly Table 2 (``tests/test_params.py``).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

import numpy as np

from ...errors import ConfigError, ParameterError
from ...io import MAX_MAGNITUDE, read_toml, too_large, tomllib

__all__ = [
    "G0",
    "INERTIA_KEYS",
    "STD_NAMES",
    "PARAM_NAMES",
    "LinkParams",
    "ArmParams",
    "table1",
    "load_params",
    "theta",
    "theta_from_vector",
    "physical_issues",
    "inertia_matrix",
]

#: Standard gravity used by the paper [m/s^2].
G0 = 9.81

#: Order of the six inertia entries everywhere in rc3r.
INERTIA_KEYS = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")

#: Names of the 10 standard parameters of one link, in vector order.
STD_NAMES = ("m", "rcx", "rcy", "rcz") + tuple(k.capitalize() for k in INERTIA_KEYS)

#: Names of the 30 standard parameters (``m1, rcx1, ..., Iyz3``), vector order.
PARAM_NAMES = tuple(f"{name}{k}" for k in (1, 2, 3) for name in STD_NAMES)


def inertia_matrix(i6) -> np.ndarray:
    """3x3 inertia matrix from ``(ixx, iyy, izz, ixy, ixz, iyz)`` (matrix entries)."""
    ixx, iyy, izz, ixy, ixz, iyz = (float(x) for x in i6)
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def _finite(name: str, values) -> None:
    arr = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} is not finite: {np.asarray(values).tolist()}")


@dataclass(frozen=True)
class LinkParams:
    """Parameters of one link, paper convention.

    Attributes
    ----------
    length : float
        DH length of the link [m]: ``l1 = d1``, ``l2 = a2``, ``l3 = a3``.
    mass : float
        Mass [kg].
    com : tuple of 3 float
        Centre of mass [m] in DH frame *i* (distal end of link *i*).
    inertia : tuple of 6 float
        Inertia about the CoM [kg m^2] in DH frame *i* axes, as
        ``(ixx, iyy, izz, ixy, ixz, iyz)`` matrix entries.
    """

    length: float
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]

    def __post_init__(self):
        object.__setattr__(self, "length", float(self.length))
        object.__setattr__(self, "mass", float(self.mass))
        object.__setattr__(self, "com", tuple(float(x) for x in self.com))
        object.__setattr__(self, "inertia", tuple(float(x) for x in self.inertia))
        if len(self.com) != 3:
            raise ParameterError(f"com needs 3 entries, got {len(self.com)}")
        if len(self.inertia) != 6:
            raise ParameterError(f"inertia needs 6 entries, got {len(self.inertia)}")
        _finite("length", self.length)
        _finite("mass", self.mass)
        _finite("com", self.com)
        _finite("inertia", self.inertia)

    @property
    def inertia_matrix(self) -> np.ndarray:
        """Inertia about the CoM as a symmetric (3, 3) array [kg m^2], DH frame *i*."""
        return inertia_matrix(self.inertia)

    def to_vector(self) -> np.ndarray:
        """The 10 standard parameters ``(m, rcx, rcy, rcz, Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``."""
        return np.array((self.mass, *self.com, *self.inertia))


@dataclass(frozen=True)
class ArmParams:
    """Parameters of the whole 3R arm.

    Attributes
    ----------
    links : tuple of 3 LinkParams
    g0 : float
        Gravity magnitude [m/s^2]; gravity is ``(0, 0, -g0)`` in the base frame.
    name : str
        Robot name (URDF ``<robot name>``).
    """

    links: tuple[LinkParams, LinkParams, LinkParams]
    g0: float = G0
    name: str = "rr3"
    source: str = field(default="", compare=False)

    def __post_init__(self):
        object.__setattr__(self, "links", tuple(self.links))
        if len(self.links) != 3:
            raise ParameterError(f"the arm has 3 links, got {len(self.links)}")
        _finite("g0", self.g0)
        for i, link in enumerate(self.links, 1):
            if link.length <= 0:
                raise ParameterError(f"link {i} length must be > 0, got {link.length}")

    @property
    def lengths(self) -> tuple[float, float, float]:
        """``(l1, l2, l3)`` [m]."""
        return tuple(link.length for link in self.links)

    def to_vector(self) -> np.ndarray:
        """The 30 standard parameters, link by link (:data:`STD_NAMES` order)."""
        return np.concatenate([link.to_vector() for link in self.links])

    @classmethod
    def from_vector(cls, vec, lengths, g0: float = G0, name: str = "rr3") -> "ArmParams":
        """Inverse of :meth:`to_vector` (30 numbers, plus the three lengths)."""
        vec = np.asarray(vec, dtype=float)
        if vec.shape != (30,):
            raise ParameterError(f"expected 30 standard parameters, got shape {vec.shape}")
        links = tuple(
            LinkParams(lengths[k], vec[10 * k], vec[10 * k + 1 : 10 * k + 4], vec[10 * k + 4 : 10 * k + 10])
            for k in range(3)
        )
        return cls(links, g0=g0, name=name)

    def with_links(self, **changes) -> "ArmParams":
        """Copy with fields replaced (``dataclasses.replace``)."""
        return replace(self, **changes)


#: Keys of a parameter file: top level, a ``[[link]]`` table (an inertia table has INERTIA_KEYS).
TOP_KEYS = ("name", "g0", "link")
LINK_KEYS = ("length", "mass", "com", "inertia")


def _known(table, allowed, where: str, source: str) -> None:
    """Refuse a key of ``table`` not in ``allowed`` (a typo would otherwise be ignored)."""
    if not isinstance(table, dict):
        raise ConfigError(f"{source}: {where} must be a table, got {table!r}")
    unknown = [key for key in table if key not in allowed]
    if unknown:
        raise ConfigError(f"{source}: unknown key {unknown[0]!r} in {where} (allowed: {', '.join(allowed)})")


def _magnitudes(arm: "ArmParams", source: str) -> "ArmParams":
    """``arm``, if no number of it is beyond :data:`rc3r.io.MAX_MAGNITUDE` (refused at the file's
    edge: 1e300 would overflow theta and the URDF's model)."""
    for k, link in enumerate(arm.links, 1):
        for what, values in (("length", [link.length]), ("mass", [link.mass]), ("com", link.com),
                             ("inertia", link.inertia), ("g0", [arm.g0])):
            big = [x for x in values if too_large(x)]
            if big:
                where = "g0" if what == "g0" else f"link {k} {what}"
                raise ParameterError(f"{source}: {where} {big[0]:g} is beyond {MAX_MAGNITUDE:g} in magnitude "
                                     "(SI units)")
    return arm


def _params_from_mapping(data: dict, source: str) -> ArmParams:
    _known(data, TOP_KEYS, "the top level", source)
    if not isinstance(data.get("name", "rr3"), str):
        raise ConfigError(f"{source}: name must be a string, got {data['name']!r}")
    try:
        links = []
        for k, entry in enumerate(data["link"], 1):
            _known(entry, LINK_KEYS, f"link {k}", source)
            inertia = entry["inertia"]
            if isinstance(inertia, dict):
                _known(inertia, INERTIA_KEYS, f"link {k} inertia", source)
                missing = [key for key in INERTIA_KEYS if key not in inertia]
                if missing:
                    raise ConfigError(f"{source}: link {k} inertia lacks {', '.join(missing)}")
                inertia = [inertia[key] for key in INERTIA_KEYS]
            links.append(LinkParams(entry["length"], entry["mass"], entry["com"], inertia))
        arm = ArmParams(tuple(links), g0=data.get("g0", G0), name=data.get("name", "rr3"), source=source)
        return _magnitudes(arm, source)
    except KeyError as exc:
        raise ConfigError(f"{source}: missing key {exc.args[0]!r}") from None
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ConfigError | ParameterError):
            raise
        raise ConfigError(f"{source}: {exc}") from None


def load_params(path: str | Path) -> ArmParams:
    """Read link parameters from a TOML file (format of ``rc3r/data/rr3.toml``).

    Raises
    ------
    ConfigError
        Missing file, malformed TOML or missing keys.
    ParameterError
        Non-finite numbers or non-positive lengths.
    """
    return _params_from_mapping(read_toml(path, "parameter file"), str(path))


def table1() -> ArmParams:
    """The robot of Table 1 of the paper (packaged ``rc3r/robots/rr3/data/rr3.toml``)."""
    text = resources.files(__package__).joinpath("data/rr3.toml").read_text()
    return _params_from_mapping(tomllib.loads(text), "rc3r/robots/rr3/data/rr3.toml")


def theta_from_vector(std, lengths) -> np.ndarray:
    """Coefficients theta from standard parameters, broadcasting over leading axes.

    Parameters
    ----------
    std : array_like, shape (..., 30)
        Standard parameters in :meth:`ArmParams.to_vector` order.
    lengths : array_like, shape (3,)
        ``(l1, l2, l3)`` [m] (``l1`` does not enter theta).

    Returns
    -------
    ndarray, shape (..., 15)
        theta in the paper's order (section 3.1.1; units in docs/conventions.md).
    """
    p = np.asarray(std, dtype=float)
    _, l2, l3 = (float(x) for x in lengths)
    m1, x1, _y1, z1, _ixx1, iyy1 = (p[..., i] for i in range(6))
    m2, x2, y2, z2, ixx2, iyy2, izz2, ixy2, ixz2, iyz2 = (p[..., 10 + i] for i in range(10))
    m3, x3, y3, z3, ixx3, iyy3, izz3, ixy3, ixz3, iyz3 = (p[..., 20 + i] for i in range(10))
    X2 = l2 + x2
    X3 = l3 + x3
    th = [
        m1 * (x1**2 + z1**2) + iyy1 + m2 * z2**2 + m2 * X2**2 + iyy2
        + m3 * z3**2 + m3 * X3**2 + iyy3 + m3 * l2**2,
        -m2 * X2**2 + m2 * y2**2 - iyy2 + ixx2 - m3 * l2**2,
        -2 * m2 * y2 * X2 + 2 * ixy2,
        m3 * y3**2 - m3 * X3**2 + ixx3 - iyy3,
        -2 * m3 * y3 * X3 + 2 * ixy3,
        -m3 * y3 * l2,
        m3 * X3 * l2,
        -m2 * y2 * z2 + iyz2,
        -m2 * X2 * z2 + ixz2 - m3 * z3 * l2,
        -m3 * y3 * z3 + iyz3,
        -m3 * X3 * z3 + ixz3,
        m2 * (y2**2 + X2**2) + izz2 + m3 * (l2**2 + y3**2 + X3**2) + izz3,
        m3 * (X3**2 + y3**2) + izz3,
        m2 * X2 + m3 * l2,
        -m2 * y2,
    ]
    return np.stack(np.broadcast_arrays(*th), axis=-1)


def theta(p: ArmParams) -> np.ndarray:
    """The 15 dynamic coefficients of ``p`` (section 3.1.1), shape (15,)."""
    return theta_from_vector(p.to_vector(), p.lengths)


def physical_issues(p: ArmParams, tol: float = 1e-12) -> list[str]:
    """Physical-consistency problems of each link, as readable sentences.

    Checks mass > 0, inertia about the CoM positive definite, and the triangle
    inequality of its principal moments (``I_a <= I_b + I_c``), which every real
    rigid body satisfies. An empty list means every link is physically consistent.
    """
    issues = []
    for i, link in enumerate(p.links, 1):
        if link.mass <= 0:
            issues.append(f"link {i}: mass {link.mass:g} kg is not positive")
        eig = np.linalg.eigvalsh(link.inertia_matrix)
        if eig[0] <= tol * max(1.0, abs(eig[-1])):
            issues.append(f"link {i}: inertia is not positive definite (eigenvalues {_fmt(eig)} kg m^2)")
        elif eig[2] > eig[0] + eig[1] + tol * eig[2]:
            issues.append(
                f"link {i}: principal moments {_fmt(eig)} kg m^2 violate the triangle inequality "
                f"({eig[2]:.4g} > {eig[0]:.4g} + {eig[1]:.4g}): no real rigid body has this inertia"
            )
    return issues


def _fmt(x) -> str:
    return "(" + ", ".join(f"{v:.4g}" for v in x) + ")"


def require_simulable(p: ArmParams) -> None:
    """Raise :class:`ParameterError` if a link has mass <= 0 or a non-PD inertia.

    The triangle inequality is not enforced: Table 1 violates it for links 2 and 3
    and the paper simulates it anyway (a warning, see :func:`physical_issues`).
    """
    for issue in physical_issues(p):
        if "triangle" not in issue:
            raise ParameterError(issue)
