r"""Bounds on the 15 dynamic coefficients from a box of standard-parameter uncertainty.

The paper (section 4) assumes each of the 30 standard parameters of the arm lies
in a known interval around its nominal value, ``p + delta`` with
``delta in [lower, upper]`` (a :class:`Box`), and designs the robust law of
eq. (6) from a nominal ``theta_0`` and a radius ``rho`` with
``||theta - theta_0|| <= rho``. Two ways to get them:

(a) :func:`paper_bounds` -- the paper's own numbers. ``theta_0`` is the midpoint
    of ``theta(p)`` and ``theta(p_up)``, where ``p_up`` adds the upper deltas to
    masses and CoM coordinates but, of the inertia entries, only to ``Iyy`` and
    ``Izz`` (that is what reproduces Table 3 exactly; the text says every entry,
    which gives a different table), and ``rho = ||theta_0 - theta(p)||``
    (= 186.8129). This ``rho`` only covers the nominal robot, not the box.

(b) :func:`certified_bounds` -- the exact range ``[lo_i, hi_i]`` of every
    ``theta_i`` over the whole box, ``theta_0`` = its centre, ``rho_i`` = its half
    width (attained), and ``rho_max = sqrt(sum rho_i^2)``, a guaranteed bound on
    ``||theta - theta_0||`` over the box.

Exactness of (b). Every ``theta_i`` has the structure

.. math::

    \theta_i = c_{0i} + \sum_{k=1}^{3} \bigl[ m_k\, h_{ik}(r_k) + c_{ik}\cdot I_k \bigr]

with ``h_ik`` a quadratic polynomial in the CoM ``r_k`` (3 variables) and
``c_ik`` a constant 6-vector. The groups ``m_k``, ``r_k``, ``I_k`` of the three
links are independent coordinates of the box, so the range of ``theta_i`` is the
Minkowski sum of the ranges of the terms. ``range(c . I)`` is exact from the
interval endpoints (linear). ``h_ik`` ranges over an interval ``[hmin, hmax]``
(continuous image of a connected box), and ``m h`` is bilinear on the rectangle
``[m_lo, m_hi] x [hmin, hmax]``, so its extrema are among the four corner
products (for ``m_lo > 0``: ``min = m_lo hmin`` if ``hmin >= 0`` else
``m_hi hmin``). ``hmin``/``hmax`` of a quadratic over a 3-D box are exact by
enumerating its 27 faces (each coordinate at lo, at hi, or free): an extremum
lies in the relative interior of some face, where the gradient of the
restriction vanishes; a nonsingular restricted Hessian gives the unique
stationary point (kept if inside the face), a singular one can be skipped because
the restriction is then constant along a null direction through any interior
extremum, so the same value is reached on a lower-dimensional face, which is
enumerated too. Every candidate is a point of the box, so extra candidates
(saddles) never spoil the result. The decomposition is extracted numerically
from :func:`rc3r.params.theta_from_vector` (no formula is retyped) and checked in
``tests/test_uncertainty.py``; :func:`certified_bounds` also returns, for every
``i``, points of the box at which ``lo_i`` and ``hi_i`` are attained.

See ``docs/bounds.md`` for the TOML box format and a worked example.
"""
from __future__ import annotations

import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from .errors import ConfigError, ParameterError
from .io import read_toml
from .params import INERTIA_KEYS, STD_NAMES, ArmParams, require_simulable, theta, theta_from_vector

__all__ = [
    "PARAM_NAMES",
    "PAPER_INERTIA_KEYS",
    "Box",
    "Bounds",
    "SampledRho",
    "load_box",
    "parse_box",
    "paper_box",
    "paper_upper",
    "paper_bounds",
    "certified_bounds",
    "quadratic_box_extrema",
    "certified_radius",
    "sampled_rho",
    "sampled_rho_detail",
    "perturb",
    "cmd_bounds",
]

#: Names of the 30 standard parameters (``m1, rcx1, ..., Iyz3``), vector order.
PARAM_NAMES = tuple(f"{name}{k}" for k in (1, 2, 3) for name in STD_NAMES)

#: Inertia entries that method (a) perturbs: the ones that reproduce Table 3.
PAPER_INERTIA_KEYS = ("iyy", "izz")

_KEY_INDEX = {name.lower(): j for j, name in enumerate(STD_NAMES)}  # m, rcx, ..., iyz -> 0..9
_GROUPS = {
    "mass": (0,),
    "com": (1, 2, 3),
    "inertia": tuple(range(4, 10)),
}


# --------------------------------------------------------------------------- Box


@dataclass(frozen=True, eq=False)
class Box:
    """Intervals ``[lower_j, upper_j]`` on the deltas of the 30 standard parameters.

    A parameter set ``p`` is perturbed to ``p.to_vector() + delta`` with
    ``lower <= delta <= upper`` componentwise (order :data:`PARAM_NAMES`). The
    arrays are stored read-only.

    Raises
    ------
    ParameterError
        Wrong shapes, non-finite numbers, or ``lower > upper`` somewhere.
    """

    lower: np.ndarray
    upper: np.ndarray
    source: str = field(default="", compare=False)

    def __post_init__(self):
        try:
            lo = np.array(self.lower, dtype=float)
            hi = np.array(self.upper, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError("box deltas must be numbers") from None
        if lo.shape != (30,) or hi.shape != (30,):
            raise ParameterError(
                f"a box needs 30 lower and 30 upper deltas, got shapes {lo.shape} and {hi.shape}"
            )
        for what, arr in (("lower", lo), ("upper", hi)):
            bad = [PARAM_NAMES[j] for j in np.flatnonzero(~np.isfinite(arr))]
            if bad:
                raise ParameterError(f"box {what} delta is not finite for {', '.join(bad)}")
        bad = np.flatnonzero(lo > hi)
        if bad.size:
            j = bad[0]
            raise ParameterError(
                f"box interval of {PARAM_NAMES[j]} is empty: lower {lo[j]:g} > upper {hi[j]:g}"
                + (f" (and {bad.size - 1} more)" if bad.size > 1 else "")
            )
        lo.flags.writeable = False
        hi.flags.writeable = False
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)

    # -- construction ---------------------------------------------------
    @classmethod
    def uniform(cls, mass=(0.0, 0.0), com=(0.0, 0.0), inertia=(0.0, 0.0), source: str = "") -> "Box":
        """The same intervals for every link: ``mass``, every CoM coordinate, every inertia entry."""
        lo = np.zeros(30)
        hi = np.zeros(30)
        for k in range(3):
            for group, iv in (("mass", mass), ("com", com), ("inertia", inertia)):
                for j in _GROUPS[group]:
                    lo[10 * k + j], hi[10 * k + j] = iv
        return cls(lo, hi, source=source)

    @classmethod
    def zero(cls) -> "Box":
        """The degenerate box (every parameter known exactly)."""
        return cls(np.zeros(30), np.zeros(30), source="zero")

    # -- queries -------------------------------------------------------
    @property
    def width(self) -> np.ndarray:
        """``upper - lower``, shape (30,)."""
        return self.upper - self.lower

    @property
    def centre(self) -> np.ndarray:
        """Centre of the box, shape (30,)."""
        return 0.5 * (self.lower + self.upper)

    def __eq__(self, other) -> bool:
        return isinstance(other, Box) and np.array_equal(self.lower, other.lower) and np.array_equal(self.upper, other.upper)

    __hash__ = None

    def check(self, p: ArmParams) -> None:
        """Raise :class:`ParameterError` if ``p`` plus the box allows a mass <= 0."""
        vec = p.to_vector()
        for k in range(3):
            m_lo = vec[10 * k] + self.lower[10 * k]
            if not m_lo > 0:
                raise ParameterError(
                    f"box allows a non-positive mass for link {k + 1}: nominal {vec[10 * k]:g} kg "
                    f"+ lower delta {self.lower[10 * k]:g} kg = {m_lo:g} kg"
                )

    def contains(self, delta, tol: float = 1e-12) -> np.ndarray:
        """Whether each delta (shape (..., 30)) lies in the box (up to ``tol``)."""
        d = np.asarray(delta, dtype=float)
        return np.all((d >= self.lower - tol) & (d <= self.upper + tol), axis=-1)

    def corner(self, bits) -> np.ndarray:
        """Delta of a corner: ``bits[j]`` 0 -> lower, 1 -> upper (30 entries)."""
        b = np.asarray(bits, dtype=bool)
        if b.shape != (30,):
            raise ParameterError(f"a corner needs 30 bits, got shape {b.shape}")
        return np.where(b, self.upper, self.lower)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` deltas uniform in the box, shape (n, 30)."""
        return rng.uniform(self.lower, self.upper, size=(int(n), 30))

    def to_dict(self) -> dict:
        return {
            "source": self.source,
            "names": list(PARAM_NAMES),
            "lower": self.lower.tolist(),
            "upper": self.upper.tolist(),
        }

    def __repr__(self) -> str:
        return f"Box(source={self.source!r}, lower={self.lower.tolist()}, upper={self.upper.tolist()})"


def _interval(value, where: str) -> tuple[float, float]:
    def num(x):
        return isinstance(x, int | float) and not isinstance(x, bool)

    if num(value):
        return float(value), float(value)
    if isinstance(value, list) and len(value) == 2 and all(num(x) for x in value):
        return float(value[0]), float(value[1])
    raise ConfigError(f"{where}: expected [lower, upper] (two numbers), got {value!r}")


def _apply(table: dict, lo: np.ndarray, hi: np.ndarray, links, where: str) -> None:
    """Set the intervals of ``table`` (group keys first, then single keys) on ``links``."""
    groups, singles = {}, {}
    for key, value in table.items():
        name = key.lower()
        if name in _GROUPS:
            groups[name] = value
        elif name in _KEY_INDEX:
            singles[name] = value
        else:
            allowed = ", ".join(list(_GROUPS) + [n.lower() for n in STD_NAMES])
            raise ConfigError(f"{where}: unknown key {key!r} (allowed: {allowed})")
    if "mass" in groups and "m" in singles:
        raise ConfigError(f"{where}: give either 'mass' or 'm', not both")
    for name, value in groups.items():
        a, b = _interval(value, f"{where} {name}")
        for k in links:
            for j in _GROUPS[name]:
                lo[10 * k + j], hi[10 * k + j] = a, b
    for name, value in singles.items():
        a, b = _interval(value, f"{where} {name}")
        for k in links:
            lo[10 * k + _KEY_INDEX[name]], hi[10 * k + _KEY_INDEX[name]] = a, b


def parse_box(data: dict, source: str = "<box>") -> Box:
    """A :class:`Box` from parsed TOML (format in ``docs/bounds.md``).

    ``[delta]`` holds defaults for every link, by kind (``mass``, ``com``,
    ``inertia``) or by parameter (``m``, ``rcx`` ... ``iyz``, case-insensitive;
    single keys win over kinds). ``[[link]]`` tables with ``index = 1..3`` override
    them for one link, with the same keys. Unlisted parameters get ``[0, 0]``.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: expected a TOML table")
    unknown = set(data) - {"delta", "link", "description", "name"}
    if unknown:
        raise ConfigError(f"{source}: unknown top-level key(s) {', '.join(sorted(unknown))} (allowed: delta, link, description)")
    if "delta" not in data and "link" not in data:
        raise ConfigError(f"{source}: missing key 'delta' (and no [[link]] overrides): the box defines no interval")
    lo = np.zeros(30)
    hi = np.zeros(30)
    delta = data.get("delta", {})
    if not isinstance(delta, dict):
        raise ConfigError(f"{source}: 'delta' must be a table ([delta])")
    _apply(delta, lo, hi, range(3), f"{source} [delta]")
    overrides = data.get("link", [])
    if not isinstance(overrides, list) or not all(isinstance(t, dict) for t in overrides):
        raise ConfigError(f"{source}: 'link' must be an array of tables ([[link]])")
    seen = set()
    for n, table in enumerate(overrides, 1):
        idx = table.get("index")
        if idx is None:
            raise ConfigError(f"{source}: [[link]] number {n} lacks 'index' (1, 2 or 3)")
        if isinstance(idx, bool) or not isinstance(idx, int) or not 1 <= idx <= 3:
            raise ConfigError(f"{source}: [[link]] number {n}: index must be 1, 2 or 3, got {idx!r}")
        if idx in seen:
            raise ConfigError(f"{source}: link {idx} is overridden twice")
        seen.add(idx)
        rest = {k: v for k, v in table.items() if k != "index"}
        _apply(rest, lo, hi, (idx - 1,), f"{source} [[link]] index={idx}")
    try:
        return Box(lo, hi, source=source)
    except ParameterError as exc:
        raise ParameterError(f"{source}: {exc}") from None


def load_box(path: str | Path) -> Box:
    """Read a :class:`Box` from a TOML file.

    Raises
    ------
    ConfigError
        Missing file, malformed TOML, unknown or malformed keys.
    ParameterError
        Non-finite numbers or an empty interval (``lower > upper``).
    """
    data = read_toml(path, "box file")
    return parse_box(data, str(path))


def paper_box() -> Box:
    """The box of section 4: ``dm in [0, 10]``, ``dr_c in [0, 1]``, ``dI in [0, 1]`` for every entry.

    Packaged as ``rc3r/data/paper_box.toml``.
    """
    text = resources.files("rc3r").joinpath("data/paper_box.toml").read_text()
    return parse_box(tomllib.loads(text), "rc3r/data/paper_box.toml")


# ------------------------------------------------------------------ perturbations


def _inertia_keys(inertia_keys) -> tuple[str, ...]:
    """Normalise ``"all"``, one key or a sequence of keys to lower-case INERTIA_KEYS names."""
    if isinstance(inertia_keys, str):
        inertia_keys = tuple(INERTIA_KEYS) if inertia_keys.lower() == "all" else (inertia_keys,)
    keys = tuple(str(k).lower() for k in inertia_keys)
    bad = [k for k in keys if k not in INERTIA_KEYS]
    if bad:
        raise ConfigError(f"unknown inertia entries {bad} (allowed: {', '.join(INERTIA_KEYS)} or 'all')")
    return keys


def _inertia_mask(inertia_keys) -> np.ndarray:
    keys = _inertia_keys(inertia_keys)
    mask = np.zeros(30, dtype=bool)
    for k in range(3):
        mask[10 * k : 10 * k + 4] = True  # m, rcx, rcy, rcz
        for key in keys:
            mask[10 * k + 4 + INERTIA_KEYS.index(key)] = True
    return mask


def paper_upper(p: ArmParams, box: Box, inertia_keys=PAPER_INERTIA_KEYS) -> ArmParams:
    """``p_up`` of method (a): upper deltas on masses, CoM and the ``inertia_keys`` entries."""
    delta = np.where(_inertia_mask(inertia_keys), box.upper, 0.0)
    return _shifted(p, delta)


def _unsimulable(p: ArmParams) -> bool:
    try:
        require_simulable(p)
    except ParameterError:
        return True
    return False


def _shifted(p: ArmParams, delta) -> ArmParams:
    return ArmParams.from_vector(p.to_vector() + np.asarray(delta, dtype=float), p.lengths, p.g0, name=p.name)


def perturb(p: ArmParams, box: Box, spec: str, *, simulable: bool = False) -> ArmParams:
    """A parameter set of the box, for plants of simulations.

    ``spec`` is one of

    * ``"nominal"`` -- ``p`` itself;
    * ``"upper"`` / ``"lower"`` -- every delta at its upper / lower end;
    * ``"paper-upper"`` -- ``p_up`` of method (a) (inertia deltas on Iyy, Izz only);
    * ``"corner:<bits>"`` -- 30 characters ``0`` (lower) / ``1`` (upper) in
      :data:`PARAM_NAMES` order (``_`` separators allowed);
    * ``"random:<seed>"`` -- uniform in the box, ``numpy.random.default_rng(seed)``.

    By default the result is only checked for mass > 0: most random draws and many
    corners of the paper's box have a non-positive-definite inertia (e.g.
    ``Ixx2 = 0.5``, ``Ixy2 = 1.2``), see :func:`rc3r.params.physical_issues`.
    With ``simulable=True`` the result must pass
    :func:`rc3r.params.require_simulable` (mass > 0, inertia positive definite;
    the triangle inequality is not required, as for Table 1): ``random:<seed>``
    then redraws from the same generator until it does (uniform on the
    simulable part of the box, at most 10000 draws), other specs raise.

    Raises
    ------
    ConfigError
        Unknown or malformed ``spec``.
    ParameterError
        The box allows a mass <= 0 for ``p``; with ``simulable=True``, a result
        that cannot be simulated.
    """
    out = _perturb(p, box, spec, simulable)
    if simulable:
        try:
            require_simulable(out)
        except ParameterError as exc:
            raise ParameterError(f"perturbation {spec!r} is not simulable: {exc}") from None
    return out


def _perturb(p: ArmParams, box: Box, spec, simulable: bool) -> ArmParams:
    if not isinstance(spec, str):
        raise ConfigError(f"perturbation spec must be a string, got {spec!r}")
    s = spec.strip()
    kind, _, arg = s.partition(":")
    kind = kind.lower()
    if kind == "nominal" and not arg:
        return p
    box.check(p)
    if kind == "upper" and not arg:
        return _shifted(p, box.upper)
    if kind == "lower" and not arg:
        return _shifted(p, box.lower)
    if kind == "paper-upper" and not arg:
        return paper_upper(p, box)
    if kind == "corner":
        bits = arg.replace("_", "")
        if len(bits) != 30 or set(bits) - {"0", "1"}:
            raise ConfigError(
                f"bad perturbation {spec!r}: 'corner:' needs 30 characters 0/1 (lower/upper) in the order "
                f"m1 rcx1 ... Iyz3, got {len(bits)} characters"
            )
        return _shifted(p, box.corner([c == "1" for c in bits]))
    if kind == "random":
        try:
            seed = int(arg)
            if seed < 0:
                raise ValueError
        except ValueError:
            raise ConfigError(f"bad perturbation {spec!r}: 'random:' needs a seed >= 0, e.g. random:0") from None
        rng = np.random.default_rng(seed)
        for _ in range(10_000 if simulable else 1):
            out = _shifted(p, box.sample(rng, 1)[0])
            if not simulable or not _unsimulable(out):
                return out
        raise ParameterError(f"perturbation {spec!r}: no simulable robot in 10000 draws from the box")
    raise ConfigError(
        f"bad perturbation {spec!r}: expected nominal, upper, lower, paper-upper, corner:<30 bits> or random:<seed>"
    )


# ------------------------------------------------------------------------ Bounds


def _floats(x):
    return None if x is None else np.asarray(x, dtype=float).tolist()


@dataclass(frozen=True, eq=False)
class Bounds:
    """``theta_0`` and radius for the robust law, from a box.

    Attributes
    ----------
    method : str
        ``"paper"`` (method (a)) or ``"certified"`` (method (b)).
    theta0 : ndarray (15,)
        Nominal coefficients for the controller.
    rho : float
        Norm bound: method (a) ``||theta_0 - theta(p)||`` (the paper's rho, valid
        for the nominal robot only); method (b) ``sqrt(sum rho_i^2)``, valid over
        the whole box.
    rho_i : ndarray (15,) or None
        Per-coefficient bounds ``|theta_i - theta0_i| <= rho_i`` (eq. 7), method (b).
    theta_lo, theta_hi : ndarray (15,) or None
        Exact range of each coefficient over the box, method (b).
    box : Box
    theta_nominal : ndarray (15,)
        ``theta(p)`` of the nominal robot.
    witness_lo, witness_hi : ndarray (15, 30) or None
        Method (b): standard-parameter vectors in the box at which ``theta_i``
        equals ``theta_lo[i]`` / ``theta_hi[i]`` (proof of attainment).
    inertia_keys : tuple of str or None
        Method (a): the inertia entries ``p_up`` perturbs.
    theta_upper : ndarray (15,) or None
        Method (a): ``theta(p_up)``.
    """

    method: str
    theta0: np.ndarray
    rho: float
    rho_i: np.ndarray | None
    theta_lo: np.ndarray | None
    theta_hi: np.ndarray | None
    box: Box
    theta_nominal: np.ndarray
    witness_lo: np.ndarray | None = None
    witness_hi: np.ndarray | None = None
    inertia_keys: tuple[str, ...] | None = None
    theta_upper: np.ndarray | None = None

    def to_dict(self) -> dict:
        """JSON-ready dict (lists of floats)."""
        d = {
            "method": self.method,
            "theta0": _floats(self.theta0),
            "rho": float(self.rho),
            "rho_i": _floats(self.rho_i),
            "theta_lo": _floats(self.theta_lo),
            "theta_hi": _floats(self.theta_hi),
            "theta_nominal": _floats(self.theta_nominal),
            "box": self.box.to_dict(),
        }
        if self.method == "paper":
            d["inertia_keys"] = list(self.inertia_keys or ())
            d["theta_upper"] = _floats(self.theta_upper)
            d["rho_covers"] = "the nominal robot only: ||theta0 - theta(p)||"
        else:
            d["rho_covers"] = "the whole box: sqrt(sum rho_i^2) >= ||theta - theta0||"
        return d

    def to_json(self, **kwargs) -> str:
        """:meth:`to_dict` as a JSON string."""
        return json.dumps(self.to_dict(), **kwargs)


def paper_bounds(p: ArmParams, box: Box | None = None, inertia_keys=PAPER_INERTIA_KEYS) -> Bounds:
    """Method (a), the paper's: reproduces Table 3 and ``rho = 186.8129`` for Table 1.

    ``theta_0 = (theta(p) + theta(p_up)) / 2`` and ``rho = ||theta_0 - theta(p)||``,
    where ``p_up`` (:func:`paper_upper`) adds the box's upper deltas to every mass
    and CoM coordinate and, of the inertia entries, only to ``inertia_keys``
    (default ``("iyy", "izz")``, which reproduces the published Table 3; the
    paper's text perturbs every entry: pass ``"all"`` for that reading).
    """
    box = paper_box() if box is None else box
    box.check(p)
    keys = _inertia_keys(inertia_keys)
    th = theta(p)
    th_up = theta(paper_upper(p, box, keys))
    th0 = 0.5 * (th + th_up)
    return Bounds(
        method="paper",
        theta0=th0,
        rho=float(np.linalg.norm(th0 - th)),
        rho_i=None,
        theta_lo=None,
        theta_hi=None,
        box=box,
        theta_nominal=th,
        inertia_keys=keys,
        theta_upper=th_up,
    )


# ------------------------------------------------------ method (b): exact ranges


@dataclass(frozen=True)
class _Structure:
    """``theta(v) = const + sum_k m_k (a_k + b_k . r_k + r_k^T Q_k r_k) + C_k I_k``.

    Shapes: const (15,), a (3, 15), b (3, 15, 3), Q (3, 15, 3, 3) symmetric,
    C (3, 15, 6).
    """

    const: np.ndarray
    a: np.ndarray
    b: np.ndarray
    Q: np.ndarray
    C: np.ndarray

    def evaluate(self, std) -> np.ndarray:
        """Reconstructed theta, std shape (..., 30) -> (..., 15)."""
        v = np.asarray(std, dtype=float)
        out = np.broadcast_to(self.const, v.shape[:-1] + (15,)).copy()
        for k in range(3):
            m = v[..., 10 * k]
            r = v[..., 10 * k + 1 : 10 * k + 4]
            inertia = v[..., 10 * k + 4 : 10 * k + 10]
            h = (self.a[k] + np.einsum("ij,...j->...i", self.b[k], r)
                 + np.einsum("...j,ijl,...l->...i", r, self.Q[k], r))
            out += m[..., None] * h + np.einsum("ij,...j->...i", self.C[k], inertia)
        return out


def _structure(lengths) -> _Structure:
    """Extract the decomposition from :func:`theta_from_vector` by exact evaluations.

    ``c_k`` from unit inertia entries (theta is affine in ``I``); ``h_k(r)`` =
    theta(m_k = 1, r_k = r) - theta(0) with every other parameter 0, and the
    quadratic's coefficients from ``r = 0, +-e_j, e_j + e_l`` (exact for a
    quadratic up to rounding). The claim that theta has this form is checked
    in the tests at random points.
    """
    zero = np.zeros(30)
    const = theta_from_vector(zero, lengths)

    def th(v):
        return theta_from_vector(v, lengths) - const

    a = np.zeros((3, 15))
    b = np.zeros((3, 15, 3))
    Q = np.zeros((3, 15, 3, 3))
    C = np.zeros((3, 15, 6))
    eye = np.eye(3)
    for k in range(3):
        for j in range(6):
            v = zero.copy()
            v[10 * k + 4 + j] = 1.0
            C[k, :, j] = th(v)

        def h(r, k=k):
            v = zero.copy()
            v[10 * k] = 1.0
            v[10 * k + 1 : 10 * k + 4] = r
            return th(v)

        a[k] = h(np.zeros(3))
        hp = [h(eye[j]) for j in range(3)]
        hm = [h(-eye[j]) for j in range(3)]
        for j in range(3):
            b[k, :, j] = 0.5 * (hp[j] - hm[j])
            Q[k, :, j, j] = 0.5 * (hp[j] + hm[j]) - a[k]
        for j, l in itertools.combinations(range(3), 2):
            q = 0.5 * (h(eye[j] + eye[l]) - a[k] - b[k, :, j] - b[k, :, l] - Q[k, :, j, j] - Q[k, :, l, l])
            Q[k, :, j, l] = Q[k, :, l, j] = q
    return _Structure(const, a, b, Q, C)


def quadratic_box_extrema(a: float, b, Q, lo, hi):
    """Exact min and max of ``a + b.x + x^T Q x`` (Q symmetric) over the box ``[lo, hi]``.

    Enumerates every face of the box (each coordinate at lo, at hi, or free),
    keeps the stationary point of the restriction when its Hessian is
    nonsingular and the point lies in the face, plus all vertices.

    Returns
    -------
    (hmin, xmin, hmax, xmax)
    """
    b = np.asarray(b, dtype=float)
    Q = np.asarray(Q, dtype=float)
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    n = b.size
    scale = max(1.0, float(np.abs(Q).max(initial=0.0)))

    def f(x):
        return float(a + b @ x + x @ Q @ x)

    best_lo = (math.inf, None)
    best_hi = (-math.inf, None)
    for states in itertools.product((0, 1, 2), repeat=n):  # 0 = lo, 1 = hi, 2 = free
        x = np.where(np.array(states) == 0, lo, hi).astype(float)
        free = [j for j, s in enumerate(states) if s == 2]
        if free:
            fixed = [j for j, s in enumerate(states) if s != 2]
            F = np.ix_(free, free)
            QF = Q[F]
            eig = np.linalg.eigvalsh(QF)
            if np.min(np.abs(eig)) <= 1e-10 * scale:
                continue  # singular: the extremum is also reached on a lower-dimensional face
            rhs = b[free] + 2.0 * Q[np.ix_(free, fixed)] @ x[fixed]
            xf = np.linalg.solve(2.0 * QF, -rhs)
            tol = 1e-12 * (1.0 + np.abs(xf))
            if np.any(xf < lo[free] - tol) or np.any(xf > hi[free] + tol):
                continue
            x[free] = np.clip(xf, lo[free], hi[free])
        val = f(x)
        if val < best_lo[0]:
            best_lo = (val, x.copy())
        if val > best_hi[0]:
            best_hi = (val, x.copy())
    return best_lo[0], best_lo[1], best_hi[0], best_hi[1]


def certified_bounds(p: ArmParams, box: Box | None = None) -> Bounds:
    """Method (b): exact range of every theta_i over the box (see the module docstring).

    Returns a :class:`Bounds` with ``theta_lo``/``theta_hi`` (exact ranges),
    ``theta0`` = their centre, ``rho_i`` = half widths (attained at
    ``witness_lo``/``witness_hi``) and ``rho = sqrt(sum rho_i^2)``, which bounds
    ``||theta - theta0||`` everywhere in the box.

    Raises
    ------
    ParameterError
        The box allows a mass <= 0 for ``p``.
    """
    box = paper_box() if box is None else box
    box.check(p)
    S = _structure(p.lengths)
    nom = p.to_vector()
    lo_v = nom + box.lower
    hi_v = nom + box.upper
    theta_lo = S.const.copy()
    theta_hi = S.const.copy()
    wit_lo = np.zeros((15, 30))
    wit_hi = np.zeros((15, 30))
    for k in range(3):
        sl_r = slice(10 * k + 1, 10 * k + 4)
        sl_i = slice(10 * k + 4, 10 * k + 10)
        m_lo, m_hi = lo_v[10 * k], hi_v[10 * k]
        for i in range(15):
            hmin, rmin, hmax, rmax = quadratic_box_extrema(S.a[k, i], S.b[k, i], S.Q[k, i], lo_v[sl_r], hi_v[sl_r])
            # bilinear m * h on [m_lo, m_hi] x [hmin, hmax]: extrema at corners
            cands = [(m * hv, m, r) for m in (m_lo, m_hi) for hv, r in ((hmin, rmin), (hmax, rmax))]
            vmin, mmin, r_of_min = min(cands, key=lambda c: c[0])
            vmax, mmax, r_of_max = max(cands, key=lambda c: c[0])
            theta_lo[i] += vmin
            theta_hi[i] += vmax
            wit_lo[i, 10 * k], wit_lo[i, sl_r] = mmin, r_of_min
            wit_hi[i, 10 * k], wit_hi[i, sl_r] = mmax, r_of_max
            # linear c . I: each entry at the endpoint that minimises / maximises
            c = S.C[k, i]
            ilo, ihi = lo_v[sl_i], hi_v[sl_i]
            i_min = np.where(c >= 0, ilo, ihi)
            i_max = np.where(c >= 0, ihi, ilo)
            theta_lo[i] += float(c @ i_min)
            theta_hi[i] += float(c @ i_max)
            wit_lo[i, sl_i] = i_min
            wit_hi[i, sl_i] = i_max
    th0 = 0.5 * (theta_lo + theta_hi)
    rho_i = 0.5 * (theta_hi - theta_lo)
    return Bounds(
        method="certified",
        theta0=th0,
        rho=float(np.sqrt(np.sum(rho_i**2))),
        rho_i=rho_i,
        theta_lo=theta_lo,
        theta_hi=theta_hi,
        box=box,
        theta_nominal=theta(p),
        witness_lo=wit_lo,
        witness_hi=wit_hi,
    )


def certified_radius(cert: Bounds, theta0) -> tuple[float, np.ndarray]:
    """Certified radius around any ``theta0`` from the exact ranges of method (b).

    ``rho_i = max(theta0_i - lo_i, hi_i - theta0_i)`` (attained, eq. 7) and
    ``rho = sqrt(sum rho_i^2) >= ||theta - theta0||`` over the box. For the
    centre (``cert.theta0``) this is ``(cert.rho, cert.rho_i)``, the smallest such
    per-coefficient radii; for the paper's Table 3 it says how large ``rho`` must
    be for the paper's ``theta_0`` to cover the whole box.
    """
    if cert.theta_lo is None or cert.theta_hi is None:
        raise ParameterError("certified_radius needs the exact ranges of certified_bounds (method (b))")
    t0 = np.asarray(theta0, dtype=float)
    if t0.shape != (15,) or not np.all(np.isfinite(t0)):
        raise ParameterError(f"theta0 needs 15 finite entries, got {t0.tolist()}")
    rho_i = np.maximum(t0 - cert.theta_lo, cert.theta_hi - t0)
    rho_i = np.maximum(rho_i, 0.0)
    return float(np.sqrt(np.sum(rho_i**2))), rho_i


# ----------------------------------------------------------- sampled lower bound


@dataclass(frozen=True, eq=False)
class SampledRho:
    """A lower bound on ``max over the box of ||theta - theta0||`` and how it was found."""

    rho: float
    seed: int
    n_uniform: int
    n_corners: int
    all_corners: bool
    n_ascent_starts: int
    witness: np.ndarray  # standard-parameter vector (30,) that attains ``rho``

    def to_dict(self) -> dict:
        return {
            "rho": float(self.rho),
            "seed": self.seed,
            "n_uniform": self.n_uniform,
            "n_corners": self.n_corners,
            "all_relevant_corners": self.all_corners,
            "n_ascent_starts": self.n_ascent_starts,
            "witness": _floats(self.witness),
        }


def _relevant(S: _Structure, box: Box) -> np.ndarray:
    """Parameters with a nonzero interval that enter theta at all."""
    rel = np.zeros(30, dtype=bool)
    for k in range(3):
        rel[10 * k] = np.any(S.a[k] != 0) or np.any(S.b[k] != 0) or np.any(S.Q[k] != 0)
        for j in range(3):
            rel[10 * k + 1 + j] = np.any(np.abs(S.b[k, :, j]) > 1e-14) or np.any(np.abs(S.Q[k, :, j, :]) > 1e-14)
        rel[10 * k + 4 : 10 * k + 10] = np.any(np.abs(S.C[k]) > 1e-14, axis=0)
    return rel & (box.width > 0)


def _norms(std, lengths, theta0, chunk: int = 1 << 16) -> np.ndarray:
    out = np.empty(len(std))
    for s in range(0, len(std), chunk):
        out[s : s + chunk] = np.linalg.norm(theta_from_vector(std[s : s + chunk], lengths) - theta0, axis=-1)
    return out


def sampled_rho_detail(p: ArmParams, box: Box, theta0, n: int = 100_000, seed: int = 0,
                       max_corner_bits: int = 20, ascent_starts: int = 8) -> SampledRho:
    """Lower bound on ``max_{box} ||theta - theta0||`` by evaluation at points of the box.

    Candidates: ``n`` uniform samples (``numpy.random.default_rng(seed)``); every
    corner of the parameters that have a nonzero interval and enter theta if
    there are at most ``max_corner_bits`` of them, else ``n`` random such corners;
    then coordinate ascent from the ``ascent_starts`` best candidates, each step
    maximising exactly along one coordinate (theta is at most quadratic in any
    single standard parameter, so ``||theta - theta0||^2`` is a quartic whose
    maximum on the interval is at an endpoint or a root of its cubic derivative).
    Every candidate is a point of the box, so the result is a true lower bound.
    """
    theta0 = np.asarray(theta0, dtype=float)
    if theta0.shape != (15,):
        raise ParameterError(f"theta0 needs 15 entries, got shape {theta0.shape}")
    n = int(n)
    if n < 0:
        raise ParameterError(f"sample count must be >= 0, got {n}")
    box.check(p)
    L = p.lengths
    nom = p.to_vector()
    lo, hi = nom + box.lower, nom + box.upper
    rng = np.random.default_rng(seed)
    S = _structure(L)
    rel = np.flatnonzero(_relevant(S, box))

    pts = [nom[None, :], (nom + box.centre)[None, :], lo[None, :], hi[None, :]]
    if n:
        pts.append(lo + rng.random((n, 30)) * (hi - lo))
    all_corners = rel.size <= max_corner_bits
    if all_corners:
        n_corners = 1 << rel.size
        bits = ((np.arange(n_corners)[:, None] >> np.arange(rel.size)[None, :]) & 1).astype(bool)
    else:
        n_corners = n
        bits = rng.random((n, rel.size)) < 0.5
    corners = np.broadcast_to(lo, (n_corners, 30)).copy()
    corners[:, rel] = np.where(bits, hi[rel], lo[rel])
    pts.append(corners)
    cand = np.concatenate(pts)
    vals = _norms(cand, L, theta0)

    starts = cand[np.argsort(vals)[::-1][: max(0, ascent_starts)]]
    x = starts.copy()
    for _ in range(100):
        before = _norms(x, L, theta0)
        for j in rel:
            x = _coordinate_max(x, j, lo[j], hi[j], L, theta0)
        after = _norms(x, L, theta0)
        if np.all(after - before <= 1e-12 * (1.0 + after)):
            break
    allp = np.concatenate([cand, x]) if len(x) else cand
    allv = np.concatenate([vals, _norms(x, L, theta0)]) if len(x) else vals
    best = int(np.argmax(allv))
    return SampledRho(
        rho=float(allv[best]),
        seed=int(seed),
        n_uniform=n,
        n_corners=int(n_corners),
        all_corners=bool(all_corners),
        n_ascent_starts=int(len(x)),
        witness=allp[best].copy(),
    )


def _coordinate_max(x, j, lo, hi, lengths, theta0):
    """Move coordinate ``j`` of each row of ``x`` to its exact maximiser of ||theta - theta0||."""
    if hi <= lo:
        return x
    ts = np.array([lo, 0.5 * (lo + hi), hi])
    th = []
    for t in ts:
        y = x.copy()
        y[:, j] = t
        th.append(theta_from_vector(y, lengths) - theta0)
    # theta(t) - theta0 = A + B t + C t^2 through the three points (exact for a quadratic)
    V = np.vander(ts, 3, increasing=True)
    coef = np.linalg.solve(V, np.stack(th, axis=1))  # (N, 3, 15): A, B, C
    A, B, Cq = coef[:, 0], coef[:, 1], coef[:, 2]
    out = x.copy()
    for r in range(len(x)):
        # d/dt ||A + B t + C t^2||^2 / 2 = (A + B t + C t^2) . (B + 2 C t)
        d = [2 * Cq[r] @ Cq[r], 3 * B[r] @ Cq[r], B[r] @ B[r] + 2 * A[r] @ Cq[r], A[r] @ B[r]]
        roots = np.roots(d) if np.any(np.abs(d) > 0) else np.array([])
        cands = [lo, hi, x[r, j]] + [float(z.real) for z in roots if abs(z.imag) < 1e-9 and lo <= z.real <= hi]
        Y = np.repeat(x[r : r + 1], len(cands), axis=0)
        Y[:, j] = cands
        vals = np.linalg.norm(theta_from_vector(Y, lengths) - theta0, axis=-1)
        out[r, j] = cands[int(np.argmax(vals))]
    return out


def sampled_rho(p: ArmParams, box: Box, theta0, n: int = 100_000, seed: int = 0) -> float:
    """``sampled_rho_detail(...).rho``: a lower bound on ``max_{box} ||theta - theta0||``."""
    return sampled_rho_detail(p, box, theta0, n=n, seed=seed).rho


# --------------------------------------------------------------------------- CLI

#: Samples and seed of the lower bound printed by ``rc3r bounds``.
CLI_SAMPLES = 100_000
CLI_SEED = 0


def cmd_bounds(args) -> int:
    """``rc3r bounds [--box FILE] [--urdf PATH] [--json]``: both methods side by side."""
    from .urdf import load_arm

    box = paper_box() if getattr(args, "box", None) is None else load_box(args.box)
    loaded = load_arm(getattr(args, "urdf", None))
    p = loaded.params
    a = paper_bounds(p, box)
    b = certified_bounds(p, box)
    s_b = sampled_rho_detail(p, box, b.theta0, n=CLI_SAMPLES, seed=CLI_SEED)
    s_a = sampled_rho_detail(p, box, a.theta0, n=CLI_SAMPLES, seed=CLI_SEED)
    rho_a_box, rho_a_i = certified_radius(b, a.theta0)
    if getattr(args, "json", False):
        out = {
            "nominal": {"urdf": loaded.path, "theta": _floats(theta(p))},
            "box": box.to_dict(),
            "paper": a.to_dict(),
            "certified": b.to_dict(),
            "sampled_certified": s_b.to_dict(),
            "sampled_paper": s_a.to_dict(),
            "paper_theta0_certified": {"rho": rho_a_box, "rho_i": _floats(rho_a_i)},
        }
        for key in ("paper", "certified"):
            out[key].pop("box")
        print(json.dumps(out, indent=2))
        return 0
    print(f"nominal robot: {loaded.path}")
    print(f"box: {box.source}")
    print()
    print(f"{'':>9}{'theta(p)':>11}{'(a) theta0':>12}{'(b) lo':>12}{'(b) hi':>12}{'(b) theta0':>12}{'(b) rho_i':>11}")
    for i in range(15):
        print(f"{f'theta_{i + 1}':>9}{b.theta_nominal[i]:11.4f}{a.theta0[i]:12.4f}{b.theta_lo[i]:12.4f}"
              f"{b.theta_hi[i]:12.4f}{b.theta0[i]:12.4f}{b.rho_i[i]:11.4f}")
    print()
    keys = ", ".join(k.capitalize() for k in a.inertia_keys)
    print(f"(a) paper:     theta0 = (theta(p) + theta(p_up))/2, inertia deltas on {keys} only")
    print(f"               rho = ||theta0 - theta(p)|| = {a.rho:.4f}   (covers the nominal robot only)")
    print(f"               over the box: {s_a.rho:.4f} <= max ||theta - theta0(a)|| <= {rho_a_box:.4f}"
          f"   (sampled; certified from (b)'s ranges)")
    print("(b) certified: theta0 = centre of the exact ranges, |theta_i - theta0_i| <= rho_i (attained)")
    print(f"               rho_max = sqrt(sum rho_i^2) = {b.rho:.4f}   (>= ||theta - theta0|| on the whole box)")
    corners = f"all {s_b.n_corners} relevant corners" if s_b.all_corners else f"{s_b.n_corners} random corners"
    print(f"               max over box of ||theta - theta0(b)|| >= {s_b.rho:.4f}   (sampled lower bound: "
          f"seed {s_b.seed}, {s_b.n_uniform} uniform + {corners}, coordinate ascent from {s_b.n_ascent_starts})")
    return 0
