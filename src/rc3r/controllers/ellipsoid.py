r"""Spong's robust law for an ellipsoidal bound ``||theta - theta_0||_P <= 1`` (law ``robust-ellipsoid``).

Identification (``rc3r identify``) gives the coefficients' confidence **ellipsoid**
``(theta - theta_0)^T P (theta - theta_0) <= 1``, which is smaller than any ball containing it.
With ``xi = Y^T r`` and ``Delta = theta - theta_0``, the uncertain term of ``dV/dt`` is
``xi^T (delta - Delta)``, and its worst case over the ellipsoid is

.. math::

    \max_{\Delta^T P \Delta \le 1} \xi^T \Delta = \|P^{-1/2}\xi\| =: s, \quad
    \text{attained at } \Delta^* = P^{-1}\xi / s .

So the law takes (``docs/identification.md`` derives it)

.. math::

    \theta_{\mathrm{eff}} = \theta_0 + \delta, \qquad
    \delta = -\frac{P^{-1}\xi}{\max(s,\ \epsilon\rho_P)}, \qquad
    \rho_P = \sqrt{\lambda_{\max}(P^{-1})}, \qquad u = Y\theta_{\mathrm{eff}} - K r,

with ``v, a, r`` as in Spong's law (``r = e_dot + Lambda e``). Outside the boundary layer
``xi^T delta = -s`` cancels the worst case; inside it ``xi^T delta = -s^2/(eps rho_P)``, so
``xi^T(delta - Delta) <= s - s^2/(eps rho_P) <= eps rho_P / 4``: the margin is
``mu = eps rho_P / 4`` and the ultimate bound is that of
:mod:`rc3r.controllers.guarantee` with this ``mu`` (:func:`error_bound`). The layer is scaled by
``rho_P`` (the radius of the smallest ball about ``theta_0`` containing the ellipsoid) so that
``eps`` means what it means for the ball law: with ``P = I / rho^2`` the law **is** eq. (6)
(``robust``) with the same ``eps``, torque for torque. For an ellipsoid inside a ball of radius
``rho`` about the same centre, ``||delta|| <= rho min(1, ||xi|| / eps)``, the ball law's
``||delta||``, and its margin is smaller.

It is written in Python (no compiled kernel), so it runs in the ``python`` engine.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from .base import Law, _positive, _scalar, _sized, register_law

__all__ = ["RobustEllipsoid", "lyapunov_margin", "error_bound", "covers"]


@register_law
@dataclass(frozen=True, eq=False)
class RobustEllipsoid(Law):
    """Spong's robust term for ``||theta - theta_0||_P <= 1`` (module docstring).

    Parameters
    ----------
    theta : (p,) array_like
        ``theta_0``, the ellipsoid's centre.
    P : (p, p) array_like
        Symmetric positive definite shape matrix (``bounds.toml``'s ``P``).
    K : float or (n,)
        Gain on ``r`` [N m s/rad].
    Lambda : float or (n,)
        ``r = e_dot + Lambda e`` [1/s].
    eps : float
        Boundary layer, in units of ``rho_P ||xi||`` (the ball law's ``eps`` for a ball).
    """

    P: np.ndarray | None = None
    K: float | np.ndarray = 100.0
    Lambda: float | np.ndarray = 50.0
    eps: float = 0.5
    name = "robust-ellipsoid"
    model_inputs = ("P",)
    stiff = True

    def __post_init__(self):
        super().__post_init__()
        if self.P is None:
            raise ParameterError("robust-ellipsoid needs the ellipsoid P (p x p; bounds.toml of rc3r identify)")
        try:
            P = np.array(self.P, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError("P must be a p x p matrix of numbers") from None
        if P.shape != (self.p, self.p) or not np.all(np.isfinite(P)):
            raise ParameterError(f"P must be a finite {self.p} x {self.p} matrix, got shape {P.shape}")
        if not np.allclose(P, P.T, rtol=1e-10, atol=1e-14 * np.abs(P).max()):
            raise ParameterError("P must be symmetric")
        try:
            Lc = np.linalg.cholesky(0.5 * (P + P.T))
        except np.linalg.LinAlgError:
            raise ParameterError("P must be positive definite") from None
        Li = np.linalg.inv(Lc)
        Pinv = Li.T @ Li
        P.flags.writeable = False
        Pinv.flags.writeable = False
        object.__setattr__(self, "P", P)
        object.__setattr__(self, "_Pinv", 0.5 * (Pinv + Pinv.T))
        object.__setattr__(self, "rho_P", float(np.sqrt(np.linalg.eigvalsh(Pinv)[-1])))
        object.__setattr__(self, "K", _positive("K", self.K))
        object.__setattr__(self, "Lambda", _positive("Lambda", self.Lambda))
        object.__setattr__(self, "eps", _scalar("eps", _positive("eps", self.eps)))

    def signals(self, q, qd, ref):
        """``v = qd_d - Lambda e``, ``a = qdd_d - Lambda e_dot``, ``r = e_dot + Lambda e``, ``w = -K r``."""
        q, qd, ref = np.asarray(q, float), np.asarray(qd, float), np.asarray(ref, float)
        n = q.size
        lam, K = _sized("Lambda", self.Lambda, n), _sized("K", self.K, n)
        e, ed = q - ref[0], qd - ref[1]
        r = ed + lam * e
        return ref[1] - lam * e, ref[2] - lam * ed, r, -K * r

    def output(self, Y, r, z):
        """``theta_eff = theta_0 - P^{-1} xi / max(s, eps rho_P)``; the diagnostic is ``s = ||P^{-1/2} xi||``."""
        xi = np.asarray(Y, dtype=float).T @ np.asarray(r, dtype=float)
        Pxi = self._Pinv @ xi
        s = float(np.sqrt(max(float(xi @ Pxi), 0.0)))
        return self.theta - Pxi / max(s, self.eps * self.rho_P), np.zeros(0), s

    def describe(self) -> dict:
        """Name, theta, gains and P (lists), and ``rho_P``."""
        out = super().describe()
        out["rho_P"] = self.rho_P
        return out


def lyapunov_margin(law: RobustEllipsoid) -> float:
    r"""The margin ``mu = eps rho_P / 4`` of the law's robust term (module docstring)."""
    return float(law.eps) * float(law.rho_P) / 4.0


def covers(law: RobustEllipsoid, theta) -> bool:
    """True if ``theta`` (p,) is inside the law's ellipsoid: ``(theta - theta_0)^T P (theta - theta_0) <= 1``."""
    d = np.asarray(theta, dtype=float) - law.theta
    return bool(d @ law.P @ d <= 1.0 + 1e-12)


def error_bound(law: RobustEllipsoid, m_min: float, m_max: float, n: int) -> np.ndarray:
    r"""Per-joint bound (n,) [rad] on ``|e_j(t)|`` from matching initial conditions, for plants it covers.

    ``sqrt((m_+/m_-) mu / lambda_min(K)) / Lambda_j`` with ``mu`` of :func:`lyapunov_margin`
    (the argument of :func:`rc3r.controllers.guarantee.error_bound`).
    """
    if not (0 < m_min <= m_max and np.isfinite(m_max)):
        raise ValueError(f"need 0 < m_min <= m_max (finite), got {m_min}, {m_max}")
    lam = np.broadcast_to(np.asarray(law.Lambda, dtype=float), (n,))
    return np.sqrt(m_max / m_min * lyapunov_margin(law) / float(np.min(law.K))) / lam
