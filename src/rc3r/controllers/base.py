r"""The law contract: :class:`Law`, its packed layout (:class:`Layout`), the registry :data:`LAWS`.

A law is one module (:mod:`rc3r.controllers.robust` and its siblings) that holds five things:

* the class, a frozen dataclass whose gain fields say how they are packed (:func:`packed`);
* ``LAYOUT``, the named offsets of its packed vector ``cp = [p, theta (p), gains ...]``, derived from
  those fields (:meth:`Layout.of`) and written nowhere else: the kernels, the analytic Jacobian and
  the C port read an entry's index from it (:func:`at`, :meth:`Layout.slice`);
* its value kernels (numba, each a leaf that calls no other jitted function, so that its
  ``py_func`` runs without compiling anything): :data:`VALUE_KERNELS`;
* the derivatives the compiled engine's analytic Jacobian needs (:data:`DERIVATIVE_KERNELS`);
* ``c_source(law, n)``, its part of ``rc3r export``'s C (:func:`rc3r.export.c.controller_sources`).

:func:`register_law` refuses a compiled law (``code`` not None) whose module lacks one of them; a
law written in Python only (``code = None``, :mod:`rc3r.controllers.ellipsoid`) needs none. The
compiled engine's dispatch over the codes is written from :data:`LAWS` when the engine is
instantiated (:mod:`rc3r.simulate.engines._dispatch`), one branch per registered code.
"""
from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass

import numpy as np
from numba.extending import register_jitable

from ..errors import ParameterError
from .._numba_cache import ready_or_python
from ._kernels import regressor_transpose

__all__ = ["Law", "Layout", "packed", "at", "LAWS", "register_law", "make_law", "default_gains",
           "inertia_scaled_gain", "VALUE_KERNELS", "DERIVATIVE_KERNELS"]

#: The value kernels of a compiled law's module (numba, inlined into the engine):
#: ``signals(cp, q, qd, ref, v, a, r, w)`` fills the regressor arguments v, a, the sliding variable r and
#: the additive torque w, each (n,), from the state and ``ref`` (rows q_d, qd_d, qdd_d);
#: ``theta(cp, n, z, th_eff, zdot)`` turns ``th_eff`` = xi = Y^T r (if ``USES_XI``) into theta_eff (p,),
#: fills the state's rate ``zdot`` and returns ||xi|| (0 for a law without xi);
#: ``inertia_gain(cp, n)`` the scheduled ``K_inertia`` b [1/s] (0: none; the engine subtracts b M(q) r).
VALUE_KERNELS = ("signals", "theta", "inertia_gain")

#: The derivative kernels (:mod:`rc3r.simulate.engines._jacobian` composes them):
#: ``slopes(cp, n, ref, jerk, G, Wx)`` the slopes of v, a, r in (q_j, qd_j, t) and dw/d(q, qd, t);
#: ``directions(cp, Y, r, tw)`` the directions b whose ``b^T d(Y^T r)`` theta_eff needs, their count;
#: ``theta_columns(cp, Y, rows, tw)`` adds ``Y d theta_eff`` to du/d(q, qd, t, z);
#: ``state_gain(cp, n)`` the gains of ``dz/dt = -gain * xi`` (empty for a law without state).
DERIVATIVE_KERNELS = ("slopes", "directions", "theta_columns", "state_gain")

#: Sizes of a packed entry: one number, one per joint, one per coefficient, an (n, n) matrix (last only).
_SIZES = {"1": (1, 0, 0, 0), "n": (0, 1, 0, 0), "p": (0, 0, 1, 0), "nn": (0, 0, 0, 1)}


def _array(name, x) -> np.ndarray:
    """``x`` as a float array of at most one dimension (the length is checked when n or p is known)."""
    items = x if isinstance(x, (list, tuple)) else [x]
    if any(isinstance(v, (bool, np.bool_, str)) for v in items) or \
            (isinstance(x, np.ndarray) and x.dtype.kind in "bUS"):  # True is not a gain of 1
        raise ParameterError(f"{name} must be numbers, got {x!r}")
    try:
        arr = np.array(x, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be numbers, got {x!r}") from None
    if arr.ndim > 1:
        raise ParameterError(f"{name} must be a number or a vector, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def _is_matrix(x) -> bool:
    """True for a 2-D array or a list of rows."""
    return bool(isinstance(x, (list, tuple)) and x and isinstance(x[0], (list, tuple, np.ndarray))
                or isinstance(x, np.ndarray) and x.ndim == 2)


def _gain_matrix(name, x) -> np.ndarray:
    """A sliding law's ``K``: a number or a vector > 0 (diagonal), or a symmetric positive definite (n, n)
    matrix (Spong's proof holds for any constant positive definite K; the design rule's
    ``coupling = "full"`` makes ``K = b M(q_d(0))``)."""
    if _is_matrix(x):
        try:
            arr = np.array(x, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"{name} must be numbers, got {x!r}") from None
        if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or arr.dtype.kind != "f":
            raise ParameterError(f"{name} as a matrix must be square, got shape {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ParameterError(f"{name} must be finite, got {arr.tolist()}")
        if not np.allclose(arr, arr.T, rtol=1e-12, atol=1e-12 * np.abs(arr).max()):
            raise ParameterError(f"{name} as a matrix must be symmetric")
        arr = 0.5 * (arr + arr.T)
        try:
            np.linalg.cholesky(arr)
        except np.linalg.LinAlgError:
            raise ParameterError(f"{name} as a matrix must be positive definite") from None
        return arr
    return _positive(name, x)


def _positive(name, x) -> np.ndarray:
    arr = _array(name, x)
    if np.any(arr <= 0):
        raise ParameterError(f"{name} must be > 0, got {arr.tolist()}")
    return arr


def _nonnegative(name, x) -> np.ndarray:
    arr = _array(name, x)
    if np.any(arr < 0):
        raise ParameterError(f"{name} must be >= 0, got {arr.tolist()}")
    return arr


def _sized(name, arr, size) -> np.ndarray:
    """Broadcast a scalar or check a vector against ``size`` (joints or coefficients)."""
    arr = np.asarray(arr, dtype=float)
    if arr.ndim == 0:
        return np.full(size, float(arr))
    if arr.size != size:
        raise ParameterError(f"{name} has {arr.size} entries, the robot needs {size}")
    return arr.copy()


def _scalar(name, arr) -> float:
    if arr.ndim != 0:
        raise ParameterError(f"{name} must be one number, got {arr.tolist()}")
    return float(arr)




@register_jitable
def at(ix, n, p):
    """The offset in ``cp`` of a packed entry.

    Plain Python when called from Python (a law kernel's ``py_func``), compiled into a kernel that calls it.

    Parameters
    ----------
    ix : tuple of 4 int
        The entry's :meth:`Layout.index` ``(c0, cn, cp, cnn)``.
    n, p : int
        Joints and coefficients.

    Returns
    -------
    int
        ``c0 + cn n + cp p + cnn n^2``, an index into ``cp``.
    """
    return ix[0] + ix[1] * n + ix[2] * p + ix[3] * n * n


def packed(default, *entries: tuple[str, str]):
    """A dataclass field of a law whose value the compiled kernels read from the packed vector.

    Parameters
    ----------
    default : float or array_like
        The field's default (the one gain table, :func:`default_gains`).
    *entries : (str, str)
        ``(name, size)`` of the entries it packs into, in order; size ``"1"`` (one number), ``"n"`` (per
        joint), ``"p"`` (per coefficient) or ``"nn"`` (an n x n matrix, row-major). :meth:`Layout.of` lists
        them; ``Law._packed`` gives their values.

    Returns
    -------
    dataclasses.Field
    """
    for name, size in entries:
        if size not in _SIZES:
            raise ValueError(f"packed entry {name!r}: size must be one of {', '.join(_SIZES)}, got {size!r}")
    return dataclasses.field(default=default, metadata={"pack": tuple(entries)})


@dataclass(frozen=True)
class Layout:
    """The named entries of a law's packed vector ``cp`` (:meth:`Law.pack`), in order.

    ``entries`` ``((name, size), ...)``: ``p`` (one number) and ``theta`` (p) first, then the law's
    packed fields (:func:`packed`) in field order. An entry's offset is linear in ``(1, n, p, n * n)``
    (:meth:`index`), so a numba kernel reads it with :func:`at` from a module-level tuple.
    """

    entries: tuple

    @classmethod
    def of(cls, law_cls) -> "Layout":
        """The layout of a law class, from its fields' ``pack`` metadata (:func:`packed`)."""
        entries = [("p", "1"), ("theta", "p")]
        for f in dataclasses.fields(law_cls):
            entries.extend(f.metadata.get("pack", ()))
        return cls(tuple(entries))

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.entries)

    def index(self, name: str) -> tuple[int, int, int, int]:
        """Coefficients ``(c0, cn, cp, cnn)`` of the offset ``c0 + cn n + cp p + cnn n^2`` of entry ``name``
        (a module-level constant a kernel hands to :func:`at`); KeyError if there is none."""
        acc = [0, 0, 0, 0]
        for entry, size in self.entries:
            if entry == name:
                return tuple(acc)
            acc = [a + b for a, b in zip(acc, _SIZES[size])]
        raise KeyError(f"no packed entry {name!r} (entries: {', '.join(self.names)})")

    def offset(self, name: str, n: int, p: int) -> int:
        """Offset [index into cp] of entry ``name`` for n joints and p coefficients."""
        return at(self.index(name), n, p)

    def size(self, n: int, p: int) -> int:
        """Length of the packed vector."""
        return sum(at(_SIZES[s], n, p) for _, s in self.entries)

    def slice(self, cp, name: str, n: int) -> np.ndarray:
        """Entry ``name`` of a packed vector.

        Parameters
        ----------
        cp : (size,) ndarray
            A law's :meth:`Law.pack` (p is ``cp[0]``).
        name : str
            An entry of this layout.
        n : int
            Joints.

        Returns
        -------
        ndarray
            A view, shape (1,), (n,), (p,) or (n * n,) by the entry's size.
        """
        p = int(cp[0])
        size = dict(self.entries)[name]
        o = self.offset(name, n, p)
        return cp[o:o + at(_SIZES[size], n, p)]

    def __str__(self) -> str:
        return "[" + ", ".join(name if size == "1" else f"{name} ({size})" for name, size in self.entries) + "]"


@dataclass(frozen=True, eq=False)
class Law:
    """Base of every control law: its own model ``theta`` (p,) and gains.

    Subclasses set ``name`` (registry key), ``code`` (compiled kernel, or None
    for a Python-only law), ``model_inputs`` (which bounds the law needs besides
    theta: ``"rho"``, ``"rho_i"``). A compiled law's arithmetic is its module's kernels
    (module docstring); a Python-only law overrides :meth:`signals` and :meth:`output`.
    ``n`` (joints) is fixed when the law meets a robot (:meth:`pack`, :meth:`torque`):
    scalar gains broadcast to it.
    """

    theta: np.ndarray
    name = "?"
    code = None
    model_inputs = ()
    #: True for a law with a boundary layer (a gain ``rho / eps``): continuous runs use RODAS
    #: (:func:`rc3r.simulate.continuous_method`).
    stiff = False
    #: The scheduled inertia gain b of ``K(q) = K + b M(q)`` (0: none; the sliding laws make it a field).
    K_inertia = 0.0
    #: The module holding the law's kernels, LAYOUT and C port (set by :func:`register_law`).
    kernels = None

    def __post_init__(self):
        th = _array("theta", self.theta)
        if th.ndim != 1 or th.size == 0:
            raise ParameterError(f"theta must be a non-empty vector, got shape {th.shape}")
        object.__setattr__(self, "theta", th)

    @property
    def p(self) -> int:
        """Number of coefficients of the law's model."""
        return self.theta.size

    # ---- the law ----------------------------------------------------------------------
    def initial_state(self) -> np.ndarray:
        """Initial controller state z (empty except for laws with dynamics)."""
        return np.zeros(0)

    def _module(self):
        if self.code is None or self.kernels is None:
            raise ParameterError(f"law {self.name!r} has no compiled kernel")
        return self.kernels

    def signals(self, q, qd, ref):
        """``(v, a, r, w)``, each (n,): regressor arguments, sliding variable, additive torque.

        ``ref`` (3, n) holds the rows q_d, qd_d, qdd_d.
        """
        n = len(q)
        v, a, r, w = (np.empty(n) for _ in range(4))
        ready_or_python(self._module().signals)(self.pack(n), np.asarray(q, float), np.asarray(qd, float),
                                                np.asarray(ref, float), v, a, r, w)
        return v, a, r, w

    def output(self, Y, r, z):
        """``(theta_eff (p,), zdot, diagnostic)`` from the regressor Y (n, p) and r (n,)."""
        mod = self._module()
        Y = np.ascontiguousarray(Y, dtype=float)
        th_eff = np.empty(self.p)
        zdot = np.zeros(self.initial_state().size)
        zz = np.asarray(z if z is not None else self.initial_state(), dtype=float)
        if mod.USES_XI:
            ready_or_python(regressor_transpose)(Y, np.asarray(r, float), th_eff)  # xi, in th_eff
        diag = ready_or_python(mod.theta)(self.pack(Y.shape[0]), Y.shape[0], zz, th_eff, zdot)
        return th_eff, zdot, float(diag)

    def torque(self, robot, q, qd, ref, z=None):
        """Control torque at one state: ``(u (n,), zdot, diagnostic)``.

        ``u = robot.regressor(q, qd, v, a) @ theta_eff + w``: the robot enters only
        through its regressor (kinematics), never through its parameters.
        """
        q = np.asarray(q, dtype=float)
        qd = np.asarray(qd, dtype=float)
        v, a, r, w = self.signals(q, qd, ref)
        Y = robot.regressor(q, qd, v, a)
        if Y.shape != (q.size, self.p):
            raise ParameterError(f"law {self.name!r} has {self.p} coefficients, the robot's regressor "
                                 f"is {Y.shape}")
        b = float(self.K_inertia)
        if b > 0.0:  # K(q) = K + b M(q): M(q) r = Y(q, 0, 0, r) theta - Y(q, 0, 0, 0) theta (the law's theta)
            zero = np.zeros(q.size)
            w = w - b * ((robot.regressor(q, zero, zero, r) - robot.regressor(q, zero, zero, zero)) @ self.theta)
        th_eff, zdot, diag = self.output(Y, r, z)
        return Y @ th_eff + w, zdot, diag

    # ---- packing for compiled kernels ---------------------------------------------
    @classmethod
    def layout(cls) -> Layout:
        """The class's :class:`Layout` (from its fields)."""
        return Layout.of(cls)

    def _packed(self, name: str, size: str, n: int) -> np.ndarray:
        """The values of entry ``name`` for n joints (a field of that name, broadcast to its size)."""
        value = getattr(self, name)
        if size == "1":
            return np.array([float(value)])
        return _sized(name, value, n if size == "n" else self.p)

    def pack(self, n: int) -> np.ndarray:
        """``cp``, laid out as the law's :class:`Layout` (``[p, theta, gains ...]``), for n joints; cached per n.

        A law is frozen, so its packed vector for a given n never changes; the cache saves the
        concatenation on every control step of the Python engine.
        """
        if self.code is None:
            raise ParameterError(f"law {self.name!r} has no compiled kernel")
        cache = self.__dict__.setdefault("_packed_cache", {})
        if n not in cache:
            lay = self.layout()
            cp = np.concatenate([[float(self.p)], self.theta,
                                 *(self._packed(name, size, n) for name, size in lay.entries[2:])])
            if cp.size != lay.size(n, self.p):  # pragma: no cover - a _packed override of the wrong size
                raise RuntimeError(f"law {self.name!r} packed {cp.size} numbers, its layout {lay} has "
                                   f"{lay.size(n, self.p)}")
            cp.flags.writeable = False
            cache[n] = cp
        return cache[n]

    def describe(self) -> dict:
        """JSON-ready dict: name and every field (arrays as lists)."""
        out = {"name": self.name}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            out[f.name] = v.tolist() if isinstance(v, np.ndarray) else v
        return out


#: name -> law class. :func:`register_law` adds to it.
LAWS: dict[str, type[Law]] = {}


def _check_compiled(cls) -> None:
    """TypeError unless the module of the compiled law ``cls`` holds its LAYOUT, kernels and C port."""
    mod = sys.modules.get(cls.__module__)
    code = cls.code
    if isinstance(code, bool) or not isinstance(code, int) or code < 0:
        raise TypeError(f"law {cls.name!r}: code must be an integer >= 0, got {code!r}")
    for other in LAWS.values():
        if other.code == code and other.name != cls.name:
            raise TypeError(f"law {cls.name!r}: code {code} is law {other.name!r}'s")
    missing = [k for k in ("LAYOUT", "USES_XI", *VALUE_KERNELS, *DERIVATIVE_KERNELS, "c_source")
               if not hasattr(mod, k)]
    if missing:
        raise TypeError(f"compiled law {cls.name!r}: its module {cls.__module__} lacks {', '.join(missing)} "
                        "(rc3r.controllers.base)")
    if mod.LAYOUT != Layout.of(cls):
        raise TypeError(f"compiled law {cls.name!r}: {cls.__module__}.LAYOUT {mod.LAYOUT} is not the layout of "
                        f"its fields {Layout.of(cls)}")
    plain = [k for k in (*VALUE_KERNELS, *DERIVATIVE_KERNELS) if not hasattr(getattr(mod, k), "py_func")]
    if plain or not callable(mod.c_source):
        raise TypeError(f"compiled law {cls.name!r}: {', '.join(plain) or 'c_source'} must be "
                        f"{'numba kernels' if plain else 'callable'}")


def register_law(cls: type[Law]) -> type[Law]:
    """Make ``cls`` available as ``make_law(cls.name, ...)``, ``--controller`` and ``[controller] kind``.

    A compiled law (``code`` not None) is registered after its module has defined its LAYOUT,
    kernels and ``c_source`` (call it at the module's end); the compiled engine's dispatch and
    ``rc3r export`` then reach it. Usable as a class decorator for a Python-only law.

    Parameters
    ----------
    cls : type
        A :class:`Law` subclass with a ``name``.

    Returns
    -------
    type
        ``cls`` (its ``kernels`` set to its module if compiled).

    Raises
    ------
    TypeError
        Not a named Law subclass; a compiled law whose module lacks LAYOUT, ``USES_XI``, a value or
        derivative kernel (numba) or ``c_source``, whose LAYOUT is not its fields', or whose code is
        another law's.
    """
    if not (isinstance(cls, type) and issubclass(cls, Law)) or cls.name in ("?", ""):
        raise TypeError("register_law needs a Law subclass with a name")
    if cls.code is not None:
        _check_compiled(cls)
        cls.kernels = sys.modules[cls.__module__]
    LAWS[cls.name] = cls
    return cls


#: Fields of every law that are not gains.
_MODEL_FIELDS = {"theta", "rho", "rho_i"}


def default_gains(name: str) -> dict:
    """The default gains of law ``name`` (the class's field defaults): the one gain table."""
    cls = _law_class(name)
    return {f.name: f.default for f in dataclasses.fields(cls)
            if f.name not in _MODEL_FIELDS and f.default is not dataclasses.MISSING}


def _law_class(name: str) -> type[Law]:
    try:
        return LAWS[name]
    except KeyError:
        raise ParameterError(f"unknown controller {name!r} ({', '.join(LAWS)})") from None


def make_law(name: str, theta, *, rho=None, rho_i=None, **gains) -> Law:
    """Build the registered law ``name`` from its model and gains.

    ``rho`` / ``rho_i`` are passed only to laws that use them (``model_inputs``),
    so a caller may always supply both. Unknown gain names are refused.
    """
    cls = _law_class(name)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(gains) - names)
    if unknown:
        raise ParameterError(f"controller {name!r} has no gain {', '.join(unknown)} "
                             f"(gains: {', '.join(sorted(names - _MODEL_FIELDS))})")
    kwargs = dict(gains)
    for key, value in (("rho", rho), ("rho_i", rho_i)):
        if key in names and key not in kwargs and value is not None:
            kwargs[key] = value
    return cls(theta, **kwargs)


def inertia_scaled_gain(robot, q, bandwidth: float = 50.0) -> np.ndarray:
    """Diagonal gain ``bandwidth * diag M(q)`` [N m s/rad], shape (n,).

    With ``K_i = b M_ii`` every joint's velocity loop ``M qdd = -K r`` has the same bandwidth
    ``b`` [1/s]; a sampled loop at period T needs ``b T < 2``. The paper's K = 100 on every
    joint suits its 3R (10 kg links) but not an arm with a light wrist (docs/generic.md).
    """
    if not (np.isfinite(bandwidth) and bandwidth > 0):
        raise ParameterError(f"bandwidth must be finite and > 0, got {bandwidth}")
    return float(bandwidth) * np.diag(robot.mass_matrix(np.asarray(q, dtype=float)))
