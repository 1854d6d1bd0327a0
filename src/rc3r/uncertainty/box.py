r"""Boxes of standard-parameter uncertainty, their files, and plants drawn from them.

A robot's standard parameters are 10 per moving body, in the order the robot
states (:attr:`rc3r.robots.base.Robot.standard_parameter_names`): the mass, three
centre-of-mass (or first-moment) entries, six inertia entries. A :class:`Box`
holds intervals ``[lower_j, upper_j]`` on the **deltas** of these parameters:
a robot of the box has ``nominal + delta`` with ``lower <= delta <= upper``.

Box files (TOML, ``docs/bounds.md``)::

    [delta]                 # every body, by kind (mass, com, inertia) or by key
    mass = [0, 10]
    com = [0, 1]
    inertia = [0, 1]
    [[link]]                # one body, same keys
    index = 3
    m = [0, 5]
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError, ParameterError
from ..io import MAX_MAGNITUDE, read_toml

__all__ = ["Box", "parse_box", "load_box", "body_keys", "perturb", "shifted", "paper_upper", "PAPER_INERTIA_KEYS",
           "PERTURBATIONS"]

#: Positions of the kinds inside the 10 parameters of one body.
GROUPS = {"mass": (0,), "com": (1, 2, 3), "inertia": tuple(range(4, 10))}

#: The perturbation specs :func:`perturb` accepts.
PERTURBATIONS = "nominal, upper, lower, paper-upper, corner:<bits>, random:<seed>"


def body_keys(names) -> tuple[str, ...]:
    """The 10 per-body keys of full names ``("m1", "rcx1", ...)``: the body number stripped."""
    keys = []
    for name in list(names)[:10]:
        m = re.fullmatch(r"(.*?)(\d+)", name)
        keys.append((m.group(1) if m else name))
    return tuple(keys)


@dataclass(frozen=True, eq=False)
class Box:
    """Intervals ``[lower_j, upper_j]`` on the deltas of a robot's standard parameters.

    Attributes
    ----------
    lower, upper : ndarray (10 * bodies,)
        Read-only.
    names : tuple of str
        Parameter names in vector order (the robot's ``standard_parameter_names``).
    source : str
        Where the box came from (file path, ``"zero"`` ...).

    Raises
    ------
    ParameterError
        Wrong shapes, non-finite numbers or beyond :data:`rc3r.io.MAX_MAGNITUDE`, or
        ``lower > upper`` somewhere.
    """

    lower: np.ndarray
    upper: np.ndarray
    names: tuple = ()
    source: str = field(default="", compare=False)

    def __post_init__(self):
        try:
            lo = np.array(self.lower, dtype=float)
            hi = np.array(self.upper, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError("box deltas must be numbers") from None
        if lo.ndim != 1 or lo.shape != hi.shape or lo.size == 0 or lo.size % 10:
            raise ParameterError(f"a box needs 10 lower and 10 upper deltas per body, got shapes "
                                 f"{lo.shape} and {hi.shape}")
        names = tuple(self.names) or tuple(f"p{j}" for j in range(lo.size))
        if len(names) != lo.size:
            raise ParameterError(f"box has {lo.size} deltas but {len(names)} names")
        for what, arr in (("lower", lo), ("upper", hi)):
            bad = [names[j] for j in np.flatnonzero(~np.isfinite(arr))]
            if bad:
                raise ParameterError(f"box {what} delta is not finite for {', '.join(bad)}")
            big = np.flatnonzero(~(np.abs(arr) <= MAX_MAGNITUDE))
            if big.size:  # 1e300 would overflow the bounds' squares (theta is quadratic in the parameters)
                raise ParameterError(f"box {what} delta of {names[big[0]]} is {arr[big[0]]:g}, beyond "
                                     f"{MAX_MAGNITUDE:g} in magnitude (SI units)")
        bad = np.flatnonzero(lo > hi)
        if bad.size:
            j = bad[0]
            raise ParameterError(
                f"box interval of {names[j]} is empty: lower {lo[j]:g} > upper {hi[j]:g}"
                + (f" (and {bad.size - 1} more)" if bad.size > 1 else "")
            )
        lo.flags.writeable = False
        hi.flags.writeable = False
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "names", names)

    # -- construction ---------------------------------------------------
    @classmethod
    def uniform(cls, names, mass=(0.0, 0.0), com=(0.0, 0.0), inertia=(0.0, 0.0), source: str = "") -> "Box":
        """The same intervals for every body: ``mass``, every CoM entry, every inertia entry."""
        size = len(names)
        lo = np.zeros(size)
        hi = np.zeros(size)
        for k in range(size // 10):
            for group, iv in (("mass", mass), ("com", com), ("inertia", inertia)):
                for j in GROUPS[group]:
                    lo[10 * k + j], hi[10 * k + j] = iv
        return cls(lo, hi, names, source=source)

    @classmethod
    def zero(cls, names) -> "Box":
        """The degenerate box (every parameter known exactly)."""
        return cls(np.zeros(len(names)), np.zeros(len(names)), names, source="zero")

    # -- queries -------------------------------------------------------
    @property
    def size(self) -> int:
        """Number of standard parameters (10 per body)."""
        return self.lower.size

    @property
    def bodies(self) -> int:
        """Number of bodies."""
        return self.lower.size // 10

    @property
    def width(self) -> np.ndarray:
        """``upper - lower``."""
        return self.upper - self.lower

    @property
    def centre(self) -> np.ndarray:
        """Centre of the box."""
        return 0.5 * (self.lower + self.upper)

    def __eq__(self, other) -> bool:
        return (isinstance(other, Box) and np.array_equal(self.lower, other.lower)
                and np.array_equal(self.upper, other.upper))

    __hash__ = None

    def check(self, robot) -> None:
        """Raise :class:`ParameterError` if ``robot`` plus the box allows a mass <= 0 (or sizes differ)."""
        vec = robot.standard_parameters()
        if vec.size != self.size:
            raise ParameterError(f"box {self.source or ''} has {self.size} parameters, robot "
                                 f"'{robot.label}' has {vec.size}")
        for k in range(self.bodies):
            m_lo = vec[10 * k] + self.lower[10 * k]
            if not m_lo > 0:
                raise ParameterError(
                    f"box allows a non-positive mass for link {k + 1}: nominal {vec[10 * k]:g} kg "
                    f"+ lower delta {self.lower[10 * k]:g} kg = {m_lo:g} kg"
                )

    def contains(self, delta, tol: float = 1e-12) -> np.ndarray:
        """Whether each delta (shape (..., size)) lies in the box (up to ``tol``)."""
        d = np.asarray(delta, dtype=float)
        return np.all((d >= self.lower - tol) & (d <= self.upper + tol), axis=-1)

    def corner(self, bits) -> np.ndarray:
        """Delta of a corner: ``bits[j]`` 0 -> lower, 1 -> upper (``size`` entries)."""
        b = np.asarray(bits, dtype=bool)
        if b.shape != (self.size,):
            raise ParameterError(f"a corner needs {self.size} bits, got shape {b.shape}")
        return np.where(b, self.upper, self.lower)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` deltas uniform in the box, shape (n, size)."""
        return rng.uniform(self.lower, self.upper, size=(int(n), self.size))

    def to_dict(self) -> dict:
        return {"source": self.source, "names": list(self.names), "lower": self.lower.tolist(),
                "upper": self.upper.tolist()}

    def __repr__(self) -> str:
        return f"Box(source={self.source!r}, lower={self.lower.tolist()}, upper={self.upper.tolist()})"


# ---------------------------------------------------------------------------- files


def _interval(value, where: str) -> tuple[float, float]:
    def num(x):
        return isinstance(x, int | float) and not isinstance(x, bool)

    if num(value):
        return float(value), float(value)
    if isinstance(value, list) and len(value) == 2 and all(num(x) for x in value):
        return float(value[0]), float(value[1])
    raise ConfigError(f"{where}: expected [lower, upper] (two numbers), got {value!r}")


def _apply(table: dict, lo, hi, bodies, keys, where: str) -> None:
    """Set the intervals of ``table`` (group keys first, then single keys) on ``bodies``."""
    index = {k.lower(): j for j, k in enumerate(keys)}
    groups, singles = {}, {}
    for key, value in table.items():
        name = key.lower()
        if name in GROUPS:
            groups[name] = value
        elif name in index:
            singles[name] = value
        else:
            allowed = ", ".join(list(GROUPS) + [k.lower() for k in keys])
            raise ConfigError(f"{where}: unknown key {key!r} (allowed: {allowed})")
    mass_key = keys[0].lower()
    if "mass" in groups and mass_key in singles:
        raise ConfigError(f"{where}: give either 'mass' or '{mass_key}', not both")
    for name, value in groups.items():
        a, b = _interval(value, f"{where} {name}")
        for k in bodies:
            for j in GROUPS[name]:
                lo[10 * k + j], hi[10 * k + j] = a, b
    for name, value in singles.items():
        a, b = _interval(value, f"{where} {name}")
        for k in bodies:
            lo[10 * k + index[name]], hi[10 * k + index[name]] = a, b


def parse_box(data: dict, names, source: str = "<box>") -> Box:
    """A :class:`Box` from parsed TOML (format in ``docs/bounds.md``) for parameters ``names``.

    ``[delta]`` holds defaults for every body, by kind (``mass``, ``com``,
    ``inertia``) or by parameter key (``body_keys(names)``, case-insensitive;
    single keys win over kinds). ``[[link]]`` tables with ``index = 1..bodies``
    override them for one body, with the same keys. Unlisted parameters get ``[0, 0]``.
    """
    names = tuple(names)
    nb = len(names) // 10
    keys = body_keys(names)
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: expected a TOML table")
    unknown = set(data) - {"delta", "link", "description", "name"}
    if unknown:
        raise ConfigError(f"{source}: unknown top-level key(s) {', '.join(sorted(unknown))} "
                          "(allowed: delta, link, description)")
    if "delta" not in data and "link" not in data:
        raise ConfigError(f"{source}: missing key 'delta' (and no [[link]] overrides): the box defines no interval")
    lo = np.zeros(len(names))
    hi = np.zeros(len(names))
    delta = data.get("delta", {})
    if not isinstance(delta, dict):
        raise ConfigError(f"{source}: 'delta' must be a table ([delta])")
    _apply(delta, lo, hi, range(nb), keys, f"{source} [delta]")
    overrides = data.get("link", [])
    if not isinstance(overrides, list) or not all(isinstance(t, dict) for t in overrides):
        raise ConfigError(f"{source}: 'link' must be an array of tables ([[link]])")
    seen = set()
    valid = ", ".join(str(i) for i in range(1, nb + 1))
    for n, table in enumerate(overrides, 1):
        idx = table.get("index")
        if idx is None:
            raise ConfigError(f"{source}: [[link]] number {n} lacks 'index' ({valid})")
        if isinstance(idx, bool) or not isinstance(idx, int) or not 1 <= idx <= nb:
            raise ConfigError(f"{source}: [[link]] number {n}: index must be one of {valid}, got {idx!r}")
        if idx in seen:
            raise ConfigError(f"{source}: link {idx} is overridden twice")
        seen.add(idx)
        rest = {k: v for k, v in table.items() if k != "index"}
        _apply(rest, lo, hi, (idx - 1,), keys, f"{source} [[link]] index={idx}")
    try:
        return Box(lo, hi, names, source=source)
    except ParameterError as exc:
        raise ParameterError(f"{source}: {exc}") from None


def load_box(path: str | Path, names) -> Box:
    """Read a :class:`Box` for parameters ``names`` from a TOML file.

    Raises
    ------
    ConfigError
        Missing file, malformed TOML, unknown or malformed keys.
    ParameterError
        Non-finite numbers or an empty interval (``lower > upper``).
    """
    return parse_box(read_toml(path, "box file"), names, str(path))


# ---------------------------------------------------------------------- perturbations


def shifted(robot, delta, label: str):
    """``robot`` with standard parameters ``nominal + delta``."""
    return robot.with_standard_parameters(robot.standard_parameters() + np.asarray(delta, dtype=float), label)


def _unsimulable(robot) -> bool:
    try:
        robot.require_simulable()
    except ParameterError:
        return True
    return False


#: Inertia entries that method (a) perturbs: the ones that reproduce Table 3.
PAPER_INERTIA_KEYS = ("iyy", "izz")


def _inertia_keys(robot, inertia_keys) -> tuple[str, ...]:
    """Normalise ``"all"``, one key or a sequence of keys to lower-case inertia keys of ``robot``."""
    allowed = tuple(k.lower() for k in body_keys(robot.standard_parameter_names)[4:10])
    if isinstance(inertia_keys, str):
        inertia_keys = allowed if inertia_keys.lower() == "all" else (inertia_keys,)
    keys = tuple(str(k).lower() for k in inertia_keys)
    bad = [k for k in keys if k not in allowed]
    if bad:
        raise ConfigError(f"unknown inertia entries {bad} (allowed: {', '.join(allowed)} or 'all')")
    return keys


def _inertia_mask(robot, keys) -> np.ndarray:
    per_body = [k.lower() for k in body_keys(robot.standard_parameter_names)]
    size = len(robot.standard_parameter_names)
    mask = np.zeros(size, dtype=bool)
    for k in range(size // 10):
        mask[10 * k : 10 * k + 4] = True  # mass and CoM
        for j in range(4, 10):
            mask[10 * k + j] = per_body[j] in keys
    return mask


def paper_upper(robot, box: Box, inertia_keys=PAPER_INERTIA_KEYS):
    """``p_up`` of method (a) (:func:`rc3r.uncertainty.bounds.paper_bounds`): upper deltas on masses, CoM
    and the ``inertia_keys`` entries.

    Parameters
    ----------
    robot : Robot
        The nominal robot.
    box : Box
        The box on its standard parameters.
    inertia_keys : str or sequence of str
        The inertia entries perturbed (lower-case, ``"all"`` for the six).

    Returns
    -------
    Robot
        ``robot`` shifted by the box's upper deltas on those entries, labelled ``"paper-upper"``.
    """
    keys = _inertia_keys(robot, inertia_keys)
    return shifted(robot, np.where(_inertia_mask(robot, keys), box.upper, 0.0), "paper-upper")


def perturb(robot, box: Box, spec: str, *, simulable: bool = False):
    """A robot of the box, for plants of simulations.

    ``spec`` is one of

    * ``"nominal"`` -- ``robot`` itself;
    * ``"upper"`` / ``"lower"`` -- every delta at its upper / lower end;
    * ``"paper-upper"`` -- ``p_up`` of the paper's method (:func:`paper_upper`);
    * ``"corner:<bits>"`` -- ``box.size`` characters ``0`` (lower) / ``1`` (upper) / ``n`` (nominal)
      in parameter order (``_`` separators allowed); ``"corner:<bits>@<s>"`` the corner's delta times
      s in [0, 1] (a corner pulled toward the nominal robot: ``rc3r design``'s worst-plant search), or
      ``@<s_1>,...,<s_B>`` one s per body;
    * ``"random:<seed>"`` -- uniform in the box, ``numpy.random.default_rng(seed)``.

    By default the result is only checked for mass > 0: many draws of a box have
    a non-positive-definite inertia. With ``simulable=True`` the result must pass
    :meth:`~rc3r.robots.base.Robot.require_simulable`: ``random:<seed>`` then
    redraws from the same generator until it does (uniform on the simulable part
    of the box, at most 10000 draws), other specs raise.

    Raises
    ------
    ConfigError
        Unknown or malformed ``spec``.
    ParameterError
        The box allows a mass <= 0; with ``simulable=True``, a result that cannot
        be simulated.
    """
    out = _perturb(robot, box, spec, simulable)
    if simulable:
        try:
            out.require_simulable()
        except ParameterError as exc:
            raise ParameterError(f"perturbation {spec!r} is not simulable: {exc}") from None
    return out


def spec_seed(spec: str, kind: str, arg: str, what: str) -> int:
    """The seed ``arg`` of a plant spec ``kind:arg`` (``random:7``): an integer >= 0, else one
    ConfigError ``"<what> '<spec>': '<kind>:' needs a seed >= 0, e.g. <kind>:0"``."""
    try:
        seed = int(arg)
        if seed < 0:
            raise ValueError
    except ValueError:
        raise ConfigError(f"{what} {spec!r}: '{kind}:' needs a seed >= 0, e.g. {kind}:0") from None
    return seed


def _perturb(robot, box: Box, spec, simulable: bool):
    if not isinstance(spec, str):
        raise ConfigError(f"perturbation spec must be a string, got {spec!r}")
    s = spec.strip()
    kind, _, arg = s.partition(":")
    kind = kind.lower()
    if kind == "nominal" and not arg:
        return robot
    box.check(robot)
    if kind == "upper" and not arg:
        return shifted(robot, box.upper, s)
    if kind == "lower" and not arg:
        return shifted(robot, box.lower, s)
    if kind == "paper-upper" and not arg:
        return paper_upper(robot, box)
    if kind == "corner":
        bits, at, frac = arg.replace("_", "").partition("@")
        if len(bits) != box.size or set(bits) - {"0", "1", "n"}:
            raise ConfigError(
                f"bad perturbation {spec!r}: 'corner:' needs {box.size} characters 0/1/n (lower/upper/nominal) in the "
                f"order {box.names[0]} ... {box.names[-1]}, got {len(bits)} characters"
            )
        try:
            scale = np.array([float(x) for x in frac.split(",")]) if at else np.ones(1)
        except ValueError:
            scale = np.array([np.nan])
        if scale.size not in (1, box.size // 10) or not np.all((scale >= 0.0) & (scale <= 1.0)):
            raise ConfigError(f"bad perturbation {spec!r}: 'corner:<bits>@<s>' needs 0 <= s <= 1 (the corner's "
                              f"delta times s), one s or one per body ({box.size // 10})")
        scale = np.repeat(scale, 10) if scale.size > 1 else scale[0]
        delta = np.where([c == "n" for c in bits], 0.0, box.corner([c == "1" for c in bits]))
        return shifted(robot, scale * delta, s)
    if kind == "random":
        rng = np.random.default_rng(spec_seed(spec, kind, arg, "bad perturbation"))
        for _ in range(10_000 if simulable else 1):
            out = shifted(robot, box.sample(rng, 1)[0], s)
            if not simulable or not _unsimulable(out):
                return out
        raise ParameterError(f"perturbation {spec!r}: no simulable robot in 10000 draws from the box")
    raise ConfigError(f"bad perturbation {spec!r}: expected {PERTURBATIONS}")
