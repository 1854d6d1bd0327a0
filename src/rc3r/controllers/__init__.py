r"""Joint-space tracking laws behind one interface, and their registry.

Every law here is :math:`u = Y(q, \dot q, v, a)\,\theta_{\mathrm{eff}} + w`: it sees
the robot only through the Slotine--Li regressor ``Y`` (shape (n, p)), so one law
serves every robot. With :math:`e = q - q_d`:

* :class:`FeedbackLinearization` (``fbl``) -- computed torque,
  :math:`v = \dot q`, :math:`a = \ddot q_d - K_d \dot e - K_p e`, :math:`w = 0`.
* :class:`Robust` (``robust``) -- Spong's law, eqs. (3)-(6):
  :math:`v = \dot q_d - \Lambda e`, :math:`a = \ddot q_d - \Lambda \dot e`,
  :math:`r = \dot q - v`, :math:`\theta_{\mathrm{eff}} = \theta_0 + \delta`,
  :math:`\delta = -\rho\, Y^T r / \max(\|Y^T r\|, \epsilon)`, :math:`w = -K r`.
* :class:`RobustPerCoefficient` (``robust-coeff``) -- eq. (7):
  :math:`\delta_i = -\rho_i\, \xi_i / \max(|\xi_i|, \epsilon_i)`, :math:`\xi = Y^T r`.
* :class:`Adaptive` (``adaptive``) -- Slotine--Li: :math:`\theta_{\mathrm{eff}} = \hat\theta`,
  :math:`\dot{\hat\theta} = -\Gamma Y^T r` (controller state :math:`\hat\theta`).
* :class:`PDGravity` (``pd``) -- :math:`v = a = 0` (so :math:`Y\theta = g(q)`),
  :math:`w = -K_p e - K_d \dot e`.

Gains are diagonal: a scalar (same for every joint or coefficient) or a vector
of the right length, strictly positive. Their defaults are the one gain table of
rc3r (the command line uses them too; ``docs/control.md`` says why each value).

**Adding a law** is one class and one registration::

    @register_law
    class MyLaw(Law):
        name = "my-law"
        def signals(self, q, qd, ref): ...   # -> v, a, r, w   (each (n,))
        def output(self, Y, r, z): ...       # -> theta_eff (p,), zdot (nz,), diagnostic float

A law written in Python runs with any robot in the generic Python engine
(continuous or sampled time; ``examples/custom_law.py``). The built-in laws also
have a compiled kernel (:mod:`rc3r.controllers._kernels`, selected by ``code``),
which the robots' fast engines call; their Python methods call that same kernel,
so each law's arithmetic exists once.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from .._numba_cache import ready_or_python
from . import _kernels as _K

__all__ = [
    "Law",
    "FeedbackLinearization",
    "Robust",
    "RobustPerCoefficient",
    "Adaptive",
    "PDGravity",
    "LAWS",
    "register_law",
    "make_law",
    "default_gains",
    "inertia_scaled_gain",
]


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


@dataclass(frozen=True, eq=False)
class Law:
    """Base of every control law: its own model ``theta`` (p,) and gains.

    Subclasses set ``name`` (registry key), ``code`` (compiled kernel, or None
    for a Python-only law), ``model_inputs`` (which bounds the law needs besides
    theta: ``"rho"``, ``"rho_i"``) and implement :meth:`signals` and
    :meth:`output`. ``n`` (joints) is fixed when the law meets a robot
    (:meth:`pack`, :meth:`torque`): scalar gains broadcast to it.
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

    def signals(self, q, qd, ref):
        """``(v, a, r, w)``, each (n,): regressor arguments, sliding variable, additive torque.

        ``ref`` (3, n) holds the rows q_d, qd_d, qdd_d.
        """
        n = len(q)
        v, a, r, w = (np.empty(n) for _ in range(4))
        ready_or_python(_K.law_signals)(self.code, self.pack(n), np.asarray(q, float), np.asarray(qd, float),
                       np.asarray(ref, float), v, a, r, w)
        return v, a, r, w

    def output(self, Y, r, z):
        """``(theta_eff (p,), zdot, diagnostic)`` from the regressor Y (n, p) and r (n,)."""
        Y = np.ascontiguousarray(Y, dtype=float)
        th_eff = np.empty(self.p)
        zdot = np.zeros(self.initial_state().size)
        zz = np.asarray(z if z is not None else self.initial_state(), dtype=float)
        if _K.uses_xi.py_func(self.code):
            ready_or_python(_K.regressor_transpose)(Y, np.asarray(r, float), th_eff)  # xi, in th_eff
        diag = ready_or_python(_K.law_theta)(self.code, self.pack(Y.shape[0]), Y.shape[0], zz, th_eff, zdot)
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
    def _gain_vectors(self, n: int) -> list[np.ndarray]:  # pragma: no cover - per law
        raise NotImplementedError

    def _tail(self, n: int) -> list[np.ndarray]:
        """Entries packed after the law's own (a sliding law's off-diagonal K); none by default."""
        return []

    def pack(self, n: int) -> np.ndarray:
        """``[p, theta, gains ...]`` for :mod:`rc3r.controllers._kernels` (n joints); cached per n.

        A law is frozen, so its packed vector for a given n never changes; the cache saves the
        concatenation on every control step of the Python engine.
        """
        if self.code is None:
            raise ParameterError(f"law {self.name!r} has no compiled kernel")
        cache = self.__dict__.setdefault("_packed", {})
        if n not in cache:
            cp = np.concatenate([[float(self.p)], self.theta, *self._gain_vectors(n), *self._tail(n)])
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


@dataclass(frozen=True, eq=False)
class _PD(Law):
    """Laws with diagonal ``Kp`` and ``Kd`` (> 0). Layout of :meth:`pack`: ``[p, theta, Kp (n), Kd (n)]``."""

    Kp: float | np.ndarray = 100.0
    Kd: float | np.ndarray = 100.0

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "Kp", _positive("Kp", self.Kp))
        object.__setattr__(self, "Kd", _positive("Kd", self.Kd))

    def _gain_vectors(self, n):
        return [_sized("Kp", self.Kp, n), _sized("Kd", self.Kd, n)]


@dataclass(frozen=True, eq=False)
class FeedbackLinearization(_PD):
    """Computed torque with diagonal ``Kp`` [1/s^2] and ``Kd`` [1/s] (the paper's 100, 100)."""

    name = "fbl"
    code = _K.FBL


@dataclass(frozen=True, eq=False)
class PDGravity(_PD):
    """PD plus gravity compensation from the model theta: ``Kp`` [N m/rad], ``Kd`` [N m s/rad]."""

    Kp: float | np.ndarray = 500.0
    name = "pd"
    code = _K.PD


@dataclass(frozen=True, eq=False)
class _Sliding(Law):
    r"""Laws on r = e_dot + Lambda e: ``K`` [N m s/rad] (a number or a vector > 0: diagonal; or a symmetric
    positive definite (n, n) matrix), ``Lambda`` [1/s] (diagonal, > 0) and ``K_inertia`` b [1/s] (>= 0):

    .. math:: w = -\bigl(K + b\,M_{\theta}(q)\bigr)\, r,

    ``M_theta`` the mass matrix of the law's own theta at the measured q (the compiled engine computes
    :math:`M r` on the kinematics of the law's regressor pass; the Python path as
    :math:`Y(q, 0, 0, r)\theta - Y(q, 0, 0, 0)\theta`). Spong's proof needs only :math:`K(q) \succeq k I`
    uniformly, which a positive definite M gives (K = 0 is allowed with b > 0); the scheduled part puts
    every mode of :math:`M^{-1}K` at b for the model, where a constant K spreads them by M's coupling
    and its variation over the configurations (docs/design.md). The packed vector ends with
    ``[b, has_matrix, K's off-diagonal part (n * n, row-major) if K is a matrix]``
    (:meth:`pack`, :func:`rc3r.controllers._kernels.law_signals`).
    """

    K: float | np.ndarray = 100.0
    Lambda: float | np.ndarray = 50.0
    K_inertia: float = 0.0

    def __post_init__(self):
        super().__post_init__()
        b = _scalar("K_inertia", _nonnegative("K_inertia", self.K_inertia))
        object.__setattr__(self, "K_inertia", b)
        if b > 0.0 and not _is_matrix(self.K):  # b M(q) is positive definite: K >= 0 is enough
            object.__setattr__(self, "K", _nonnegative("K", self.K))
        else:
            object.__setattr__(self, "K", _gain_matrix("K", self.K))
        object.__setattr__(self, "Lambda", _positive("Lambda", self.Lambda))

    def _gain_vectors(self, n):
        if self.K.ndim == 2:
            if self.K.shape[0] != n:
                raise ParameterError(f"K is {self.K.shape[0]} x {self.K.shape[1]}, the robot needs {n} x {n}")
            return [np.diag(self.K).copy(), _sized("Lambda", self.Lambda, n)]
        return [_sized("K", self.K, n), _sized("Lambda", self.Lambda, n)]

    def _tail(self, n):
        """``[K_inertia, 1 if K is a matrix else 0, K's off-diagonal part (n * n, if a matrix)]``, packed last."""
        if self.K.ndim != 2:
            return [np.array([self.K_inertia, 0.0])]
        return [np.array([self.K_inertia, 1.0]), (self.K - np.diag(np.diag(self.K))).ravel()]

    def k_min(self, m_min: float = 0.0) -> float:
        """The smallest eigenvalue of ``K + K_inertia M(q)`` [N m s/rad] given ``lambda_min(M) >= m_min``
        [kg m^2]: of K (its smallest entry if diagonal) plus ``K_inertia m_min``."""
        k = float(np.linalg.eigvalsh(self.K)[0] if self.K.ndim == 2 else np.min(self.K))
        return k + self.K_inertia * float(m_min)


@dataclass(frozen=True, eq=False)
class Robust(_Sliding):
    """Spong's robust law, eq. (3)-(6), with bound ``rho`` and boundary layer ``eps``.

    Inside the boundary layer ``||Y^T r|| <= eps`` the law is the high gain
    ``(rho / eps) Y Y^T``: stiff (docs/control.md). Layout of :meth:`pack`:
    ``[p, theta, K (n), Lambda (n), rho, eps]`` and the sliding laws' tail (:class:`_Sliding`).
    """

    rho: float = 0.0
    eps: float = 0.5
    name = "robust"
    code = _K.ROBUST
    model_inputs = ("rho",)
    stiff = True

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "rho", _scalar("rho", _nonnegative("rho", self.rho)))
        object.__setattr__(self, "eps", _scalar("eps", _positive("eps", self.eps)))

    def _gain_vectors(self, n):
        return super()._gain_vectors(n) + [np.array([self.rho, self.eps])]


def _scalar(name, arr) -> float:
    if arr.ndim != 0:
        raise ParameterError(f"{name} must be one number, got {arr.tolist()}")
    return float(arr)


@dataclass(frozen=True, eq=False)
class RobustPerCoefficient(_Sliding):
    """Eq. (7): per-coefficient bounds ``rho_i`` (p,) and boundary layers ``eps_i``.

    Layout of :meth:`pack`: ``[p, theta, K (n), Lambda (n), rho_i (p), eps_i (p)]`` and the sliding laws' tail.
    """

    rho_i: float | np.ndarray = 0.0
    eps_i: float | np.ndarray = 0.5
    name = "robust-coeff"
    code = _K.ROBUST_COEFF
    model_inputs = ("rho_i",)
    stiff = True

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "rho_i", _sized("rho_i", _nonnegative("rho_i", self.rho_i), self.p))
        object.__setattr__(self, "eps_i", _sized("eps_i", _positive("eps_i", self.eps_i), self.p))

    def _gain_vectors(self, n):
        return super()._gain_vectors(n) + [self.rho_i, self.eps_i]


@dataclass(frozen=True, eq=False)
class Adaptive(_Sliding):
    """Slotine--Li adaptive law; ``theta`` is the initial estimate, ``Gamma`` the adaptation gain.

    Layout of :meth:`pack`: ``[p, theta, K (n), Lambda (n), Gamma (p)]`` and the sliding laws' tail.
    """

    Gamma: float | np.ndarray = 10.0
    name = "adaptive"
    code = _K.ADAPTIVE

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "Gamma", _sized("Gamma", _positive("Gamma", self.Gamma), self.p))

    def _gain_vectors(self, n):
        return super()._gain_vectors(n) + [self.Gamma]

    def initial_state(self) -> np.ndarray:
        return self.theta.copy()


#: name -> law class. :func:`register_law` adds to it.
LAWS: dict[str, type[Law]] = {}


def register_law(cls: type[Law]) -> type[Law]:
    """Class decorator: make ``cls`` available as ``make_law(cls.name, ...)`` and ``--controller``."""
    if not (isinstance(cls, type) and issubclass(cls, Law)) or cls.name in ("?", ""):
        raise TypeError("register_law needs a Law subclass with a name")
    LAWS[cls.name] = cls
    return cls


for _cls in (FeedbackLinearization, Robust, RobustPerCoefficient, Adaptive, PDGravity):
    register_law(_cls)


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


from . import ellipsoid as _ellipsoid  # noqa: E402,F401  (registers robust-ellipsoid: a Python law)
