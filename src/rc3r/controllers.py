r"""Joint-space tracking controllers behind one interface.

Each controller is a frozen dataclass holding its gains and **its own model**
``theta`` (15,) -- never the plant's. With :math:`e = q - q_d`:

* :class:`FeedbackLinearization` -- computed torque,
  :math:`u = M(q)(\ddot q_d - K_d \dot e - K_p e) + S(q,\dot q)\dot q + g(q)
  = Y(q, \dot q, \dot q, a_r)\,\theta`.
* :class:`Robust` -- Spong's law, eqs. (3)-(6):
  :math:`v = \dot q_d - \Lambda e`, :math:`a = \ddot q_d - \Lambda \dot e`,
  :math:`r = \dot q - v = \dot e + \Lambda e`,
  :math:`u = Y(q,\dot q,v,a)(\theta_0 + \delta) - K r` with
  :math:`\delta = -\rho\, Y^T r / \max(\|Y^T r\|, \epsilon)`.
* :class:`RobustPerCoefficient` -- eq. (7):
  :math:`\delta_i = -\rho_i\, \xi_i / \max(|\xi_i|, \epsilon_i)`, :math:`\xi = Y^T r`.
* :class:`Adaptive` -- Slotine-Li: :math:`u = Y\hat\theta - K r`,
  :math:`\dot{\hat\theta} = -\Gamma Y^T r` (controller state :math:`\hat\theta`).
* :class:`PDGravity` -- :math:`u = -K_p e - K_d \dot e + g(q)`.

Gains are diagonal (3,) vectors, strictly positive. The single implementation of
every law is the compiled :func:`control_into`; :meth:`Controller.torque` calls it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numba import njit

from . import _kernels as K
from .errors import ParameterError
from .params import G0

__all__ = [
    "Controller",
    "FeedbackLinearization",
    "Robust",
    "RobustPerCoefficient",
    "Adaptive",
    "PDGravity",
    "control_into",
]

FBL, ROBUST, ROBUST_COEFF, ADAPTIVE, PD = 0, 1, 2, 3, 4


@njit(cache=True, nogil=True)
def control_into(law, cp, q, qd, z, ref, l2, g0, u, zdot, Y, xi):
    """Control torque ``u`` (3,) and controller-state rate ``zdot`` for law ``law``.

    ``cp`` packs ``theta (15) | gains ...`` (see each dataclass's ``pack``);
    ``ref`` rows are q_d, qd_d, qdd_d; ``Y`` (3, 15) and ``xi`` (15,) are work arrays.
    Returns ``||Y^T r||`` for the robust laws (0 otherwise), for diagnostics.
    """
    th = cp[0:15]
    if law == FBL or law == PD:
        Kp = cp[15:18]
        Kd = cp[18:21]
        if law == FBL:
            ar1 = ref[2, 0] + Kd[0] * (ref[1, 0] - qd[0]) + Kp[0] * (ref[0, 0] - q[0])
            ar2 = ref[2, 1] + Kd[1] * (ref[1, 1] - qd[1]) + Kp[1] * (ref[0, 1] - q[1])
            ar3 = ref[2, 2] + Kd[2] * (ref[1, 2] - qd[2]) + Kp[2] * (ref[0, 2] - q[2])
            K.slotine_li_scalars(q[1], q[2], qd[0], qd[1], qd[2], qd[0], qd[1], qd[2], ar1, ar2, ar3, l2, g0, Y)
            for i in range(3):
                acc = 0.0
                for j in range(15):
                    acc += Y[i, j] * th[j]
                u[i] = acc
        else:
            K.gravity_into(th, q, l2, g0, u)
            for i in range(3):
                u[i] += Kp[i] * (ref[0, i] - q[i]) + Kd[i] * (ref[1, i] - qd[i])
        return 0.0
    Kg = cp[15:18]
    Lam = cp[18:21]
    # v = qd_d - Lambda e, a = qdd_d - Lambda e_dot, r = qd - v = e_dot + Lambda e
    e1 = q[0] - ref[0, 0]; e2 = q[1] - ref[0, 1]; e3 = q[2] - ref[0, 2]
    ed1 = qd[0] - ref[1, 0]; ed2 = qd[1] - ref[1, 1]; ed3 = qd[2] - ref[1, 2]
    r1 = ed1 + Lam[0] * e1; r2 = ed2 + Lam[1] * e2; r3 = ed3 + Lam[2] * e3
    K.slotine_li_scalars(q[1], q[2], qd[0], qd[1], qd[2],
                         ref[1, 0] - Lam[0] * e1, ref[1, 1] - Lam[1] * e2, ref[1, 2] - Lam[2] * e3,
                         ref[2, 0] - Lam[0] * ed1, ref[2, 1] - Lam[1] * ed2, ref[2, 2] - Lam[2] * ed3,
                         l2, g0, Y)
    nrm2 = 0.0
    for j in range(15):
        xi[j] = Y[0, j] * r1 + Y[1, j] * r2 + Y[2, j] * r3
        nrm2 += xi[j] * xi[j]
    nrm = np.sqrt(nrm2)
    # xi <- effective parameter vector used in u = Y theta_eff - K r
    if law == ROBUST:
        rho = cp[21]
        eps = cp[22]
        scale = rho / max(nrm, eps)
        for j in range(15):
            xi[j] = th[j] - scale * xi[j]
    elif law == ROBUST_COEFF:
        for j in range(15):
            xi[j] = th[j] - cp[21 + j] * xi[j] / max(abs(xi[j]), cp[36 + j])
    else:  # ADAPTIVE: theta_hat is the controller state z
        for j in range(15):
            zdot[j] = -cp[21 + j] * xi[j]
            xi[j] = z[j]
    u[0] = -Kg[0] * r1
    u[1] = -Kg[1] * r2
    u[2] = -Kg[2] * r3
    for i in range(3):
        acc = 0.0
        for j in range(15):
            acc += Y[i, j] * xi[j]
        u[i] += acc
    return nrm


def _vec(name, x, n=3) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(x, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must be finite, got {np.asarray(x).tolist()}")
    return arr


def _positive(name, x, n=3) -> np.ndarray:
    arr = _vec(name, x, n)
    if np.any(arr <= 0):
        raise ParameterError(f"{name} must be > 0, got {arr.tolist()}")
    return arr


def _nonnegative(name, x, n) -> np.ndarray:
    arr = _vec(name, x, n)
    if np.any(arr < 0):
        raise ParameterError(f"{name} must be >= 0, got {arr.tolist()}")
    return arr


@runtime_checkable
class Controller(Protocol):
    """What the simulator needs from a controller."""

    name: str
    law: int
    theta: np.ndarray

    def pack(self) -> np.ndarray: ...
    def initial_state(self) -> np.ndarray: ...
    def describe(self) -> dict: ...


@dataclass(frozen=True, eq=False)
class _Base:
    theta: np.ndarray
    name = "?"
    law = -1

    def __post_init__(self):
        object.__setattr__(self, "theta", _vec("theta", self.theta, 15))

    def initial_state(self) -> np.ndarray:
        """Initial controller state (empty except for the adaptive law)."""
        return np.zeros(0)

    def torque(self, q, qd, q_des, qd_des, qdd_des, z=None, *, l2: float, g0: float = G0) -> np.ndarray:
        """Control torque (3,) [N m] at one state, through the compiled law."""
        ref = np.array([q_des, qd_des, qdd_des], dtype=float)
        u = np.empty(3)
        zdot = np.zeros(15)
        zz = np.asarray(z if z is not None else np.zeros(15), dtype=float)
        control_into(self.law, self.pack(), np.asarray(q, float), np.asarray(qd, float), zz, ref,
                     float(l2), float(g0), u, zdot, np.empty((3, 15)), np.empty(15))
        return u

    def describe(self) -> dict:
        out = {"name": self.name}
        for k, v in self.__dict__.items():
            out[k] = v.tolist() if isinstance(v, np.ndarray) else v
        return out


@dataclass(frozen=True, eq=False)
class FeedbackLinearization(_Base):
    """Computed torque with diagonal ``Kp`` [1/s^2] and ``Kd`` [1/s] (paper: 100, 100)."""

    Kp: np.ndarray = field(default_factory=lambda: np.full(3, 100.0))
    Kd: np.ndarray = field(default_factory=lambda: np.full(3, 100.0))
    name = "fbl"
    law = FBL

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "Kp", _positive("Kp", self.Kp))
        object.__setattr__(self, "Kd", _positive("Kd", self.Kd))

    def pack(self) -> np.ndarray:
        return np.concatenate([self.theta, self.Kp, self.Kd])


@dataclass(frozen=True, eq=False)
class PDGravity(FeedbackLinearization):
    """PD plus gravity compensation from the model theta: ``Kp`` [N m/rad], ``Kd`` [N m s/rad]."""

    name = "pd"
    law = PD


@dataclass(frozen=True, eq=False)
class _SlidingBase(_Base):
    """Laws built on r = e_dot + Lambda e: ``K`` [N m s/rad] and ``Lambda`` [1/s], diagonal, > 0."""

    K: np.ndarray = field(default_factory=lambda: np.full(3, 100.0))
    Lambda: np.ndarray = field(default_factory=lambda: np.full(3, 50.0))

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "K", _positive("K", self.K))
        object.__setattr__(self, "Lambda", _positive("Lambda", self.Lambda))


@dataclass(frozen=True, eq=False)
class Robust(_SlidingBase):
    """Spong's robust law, eq. (3)-(6): ``K`` [N m s/rad], ``Lambda`` [1/s], ``rho``, ``eps``.

    Paper: K = 100, Lambda = 50, rho = 186.8129, eps = 0.5 (and 0.05).
    Inside the boundary layer ``||Y^T r|| <= eps`` the law is the high gain
    ``(rho / eps) Y Y^T`` (~1e6 here): stiff; see docs/control.md.
    """

    rho: float = 186.8129
    eps: float = 0.5
    name = "robust"
    law = ROBUST

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "rho", float(_nonnegative("rho", self.rho, 1)[0]))
        object.__setattr__(self, "eps", float(_positive("eps", self.eps, 1)[0]))

    def pack(self) -> np.ndarray:
        return np.concatenate([self.theta, self.K, self.Lambda, [self.rho, self.eps]])


@dataclass(frozen=True, eq=False)
class RobustPerCoefficient(_SlidingBase):
    """Eq. (7): per-coefficient bounds ``rho_i`` (15,) and boundary layers ``eps_i`` (15,)."""

    rho_i: np.ndarray = field(default_factory=lambda: np.zeros(15))
    eps_i: np.ndarray = field(default_factory=lambda: np.full(15, 0.5))
    name = "robust-coeff"
    law = ROBUST_COEFF

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "rho_i", _nonnegative("rho_i", self.rho_i, 15))
        object.__setattr__(self, "eps_i", _positive("eps_i", self.eps_i, 15))

    def pack(self) -> np.ndarray:
        return np.concatenate([self.theta, self.K, self.Lambda, self.rho_i, self.eps_i])


@dataclass(frozen=True, eq=False)
class Adaptive(_SlidingBase):
    """Slotine-Li adaptive law; ``theta`` is the initial estimate, ``Gamma`` (15,) the adaptation gain."""

    Gamma: np.ndarray = field(default_factory=lambda: np.full(15, 1.0))
    name = "adaptive"
    law = ADAPTIVE

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "Gamma", _positive("Gamma", self.Gamma, 15))

    def pack(self) -> np.ndarray:
        return np.concatenate([self.theta, self.K, self.Lambda, self.Gamma])

    def initial_state(self) -> np.ndarray:
        return self.theta.copy()
