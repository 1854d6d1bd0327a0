r"""What the robust laws guarantee: the ultimate bound on the tracking error.

For the laws on :math:`r = \dot e + \Lambda e` with :math:`u = Y(\theta_0 + \delta) - K r`
(eqs. (3)-(7)), the plant :math:`M \ddot q + C \dot q + g = Y \theta` gives
:math:`M \dot r + C r + K r = Y (\theta_0 - \theta + \delta)`. With
:math:`V = \tfrac12 r^T M r` and :math:`\dot M - 2C` skew-symmetric,

.. math::

    \dot V = -r^T K r + \xi^T (\theta_0 - \theta + \delta), \qquad \xi = Y^T r .

If :math:`\|\theta - \theta_0\| \le \rho` (eq. 6), the last term is at most
:math:`\rho\|\xi\| - \rho\|\xi\|^2/\epsilon \le \rho\epsilon/4` inside the boundary
layer and at most 0 outside it; for eq. (7) with :math:`|\theta_i - \theta_{0,i}| \le \rho_i`
it is at most :math:`\sum_i \rho_i \epsilon_i / 4`. Call that margin :math:`\mu`. Then
:math:`\dot V < 0` whenever :math:`\lambda_{\min}(K)\|r\|^2 > \mu`, so with
:math:`m_- \le \lambda(M(q)) \le m_+` along the motion and :math:`r(0) = 0` (the
paper's matching initial conditions),

.. math::

    \|r(t)\| \le \bar r = \sqrt{\frac{m_+}{m_-}\,\frac{\mu}{\lambda_{\min}(K)}}
    \quad\text{and}\quad |e_j(t)| \le \bar r / \Lambda_j \quad \text{for all } t \ge 0,

since :math:`\dot e_j = -\Lambda_j e_j + r_j` with :math:`e_j(0) = 0`. This is Spong's
uniform ultimate boundedness (Spong, "On the robust control of robot manipulators",
IEEE TAC 37(11), 1992) made explicit; it holds in continuous time only, and only for
plants inside the ball the law was built on. ``docs/robustness.md`` compares it with
the Monte Carlo runs.
"""
from __future__ import annotations

import numpy as np

from . import Law, Robust, RobustPerCoefficient

__all__ = ["covers", "error_bound", "inertia_range", "lyapunov_margin"]


def lyapunov_margin(law: Law) -> float:
    r"""The margin :math:`\mu` [N m rad/s] of the law's robust term: :math:`\rho\epsilon/4`
    (eq. 6) or :math:`\sum_i \rho_i\epsilon_i/4` (eq. 7). ``ValueError`` for other laws."""
    if isinstance(law, Robust):
        return float(law.rho) * float(law.eps) / 4.0
    if isinstance(law, RobustPerCoefficient):
        return float(np.sum(np.asarray(law.rho_i) * np.asarray(law.eps_i))) / 4.0
    raise ValueError(f"law {law.name!r} has no robust bound (only robust and robust-coeff do)")


def covers(law: Law, theta) -> bool:
    r"""True if the plant's ``theta`` (p,) is inside the set the law was designed for:
    :math:`\|\theta - \theta_0\| \le \rho` (eq. 6) or every :math:`|\theta_i - \theta_{0,i}| \le \rho_i` (eq. 7)."""
    d = np.asarray(theta, dtype=float) - np.asarray(law.theta, dtype=float)
    if isinstance(law, Robust):
        return bool(np.linalg.norm(d) <= float(law.rho) * (1 + 1e-12))
    if isinstance(law, RobustPerCoefficient):
        return bool(np.all(np.abs(d) <= np.asarray(law.rho_i) * (1 + 1e-12)))
    raise ValueError(f"law {law.name!r} has no robust bound (only robust and robust-coeff do)")


def inertia_range(robot, q) -> tuple[float, float]:
    """Smallest and largest eigenvalue [kg m^2] of ``robot.mass_matrix`` over the rows of ``q`` (N, n)."""
    lo, hi = np.inf, 0.0
    for qk in np.atleast_2d(np.asarray(q, dtype=float)):
        ev = np.linalg.eigvalsh(robot.mass_matrix(qk))
        lo, hi = min(lo, ev[0]), max(hi, ev[-1])
    return float(lo), float(hi)


def error_bound(law: Law, m_min: float, m_max: float, n: int) -> np.ndarray:
    r"""Per-joint bound (n,) [rad] on :math:`|e_j(t)|` for all t, from matching initial conditions.

    Parameters
    ----------
    law : Robust or RobustPerCoefficient
    m_min, m_max : float
        Bounds on the eigenvalues of the plant's M(q) over the motion [kg m^2]
        (:func:`inertia_range`).
    n : int
        Number of joints.

    Returns
    -------
    ndarray (n,)
        :math:`\sqrt{(m_+/m_-)\,\mu/\lambda_{\min}(K)} / \Lambda_j` (with a scheduled K,
        :math:`\lambda_{\min}(K) + b\,m_-`: ``law.k_min(m_min)``, m_min taken for the law's own M too); valid when
        :func:`covers` holds for the plant.

    Examples
    --------
    The paper's eps = 0.5, rho = 186.8129, K = 100, Lambda = 50, with M's eigenvalues in [1, 4]:

    >>> from rc3r.controllers import Robust
    >>> law = Robust(theta=[0.0] * 15, rho=186.8129, K=100.0, Lambda=50.0, eps=0.5)
    >>> round(float(error_bound(law, 1.0, 4.0, 3)[0]), 5)   # sqrt(4 * 23.35 / 100) / 50
    0.01933
    """
    if not (0 < m_min <= m_max and np.isfinite(m_max)):
        raise ValueError(f"need 0 < m_min <= m_max (finite), got {m_min}, {m_max}")
    mu = lyapunov_margin(law)
    k_min = law.k_min(m_min)  # K + K_inertia M(q) >= (lambda_min(K) + K_inertia m_min) I
    lam = np.broadcast_to(np.asarray(law.Lambda, dtype=float), (n,))
    return np.sqrt(m_max / m_min * mu / k_min) / lam
