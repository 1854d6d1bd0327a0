r"""Bounds on a robot's dynamic coefficients theta from a box of standard-parameter uncertainty.

The paper (section 4) assumes each standard parameter of the robot lies
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
``c_ik`` a constant 6-vector. The groups ``m_k``, ``r_k``, ``I_k`` of the
bodies are independent coordinates of the box, so the range of ``theta_i`` is the
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
from the robot's :meth:`~rc3r.robots.base.Robot.theta_of_standard` (no formula is retyped) and checked in
``tests/test_uncertainty.py``; :func:`certified_bounds` also returns, for every
``i``, points of the box at which ``lo_i`` and ``hi_i`` are attained.

See ``docs/bounds.md`` for the TOML box format and a worked example.
"""
from __future__ import annotations

import itertools
import json
import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..io import floats as _floats
from .box import PAPER_INERTIA_KEYS, Box, _inertia_keys, paper_upper

__all__ = [
    "Bounds",
    "paper_bounds",
    "certified_bounds",
    "certified_radius",
    "quadratic_box_extrema",
]

# ------------------------------------------------------------------------ Bounds


@dataclass(frozen=True, eq=False)
class Bounds:
    """``theta_0`` and radius for the robust law, from a box.

    Attributes
    ----------
    method : str
        ``"paper"`` (method (a)) or ``"certified"`` (method (b)).
    theta0 : ndarray (p,)
        Nominal coefficients for the controller.
    rho : float
        Norm bound: method (a) ``||theta_0 - theta(p)||`` (the paper's rho, valid
        for the nominal robot only); method (b) ``sqrt(sum rho_i^2)``, valid over
        the whole box.
    rho_i : ndarray (p,) or None
        Per-coefficient bounds ``|theta_i - theta0_i| <= rho_i`` (eq. 7), method (b).
    theta_lo, theta_hi : ndarray (p,) or None
        Exact range of each coefficient over the box, method (b).
    box : Box
    theta_nominal : ndarray (p,)
        theta of the nominal robot.
    witness_lo, witness_hi : ndarray (p, 10 * bodies) or None
        Method (b): standard-parameter vectors in the box at which ``theta_i``
        equals ``theta_lo[i]`` / ``theta_hi[i]`` (proof of attainment).
    inertia_keys : tuple of str or None
        Method (a): the inertia entries ``p_up`` perturbs.
    theta_upper : ndarray (p,) or None
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


def paper_bounds(robot, box: Box, inertia_keys=PAPER_INERTIA_KEYS) -> Bounds:
    """Method (a), the paper's: reproduces Table 3 and ``rho = 186.8129`` for Table 1.

    ``theta_0 = (theta(p) + theta(p_up)) / 2`` and ``rho = ||theta_0 - theta(p)||``,
    where ``p_up`` (:func:`~rc3r.uncertainty.box.paper_upper`) adds the box's upper deltas to every mass
    and CoM coordinate and, of the inertia entries, only to ``inertia_keys``
    (default ``("iyy", "izz")``, which reproduces the published Table 3; the
    paper's text perturbs every entry: pass ``"all"`` for that reading).
    """
    box.check(robot)
    keys = _inertia_keys(robot, inertia_keys)
    th = robot.theta
    th_up = paper_upper(robot, box, keys).theta
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

    Shapes (nb bodies, p coefficients): const (p,), a (nb, p), b (nb, p, 3),
    Q (nb, p, 3, 3) symmetric, C (nb, p, 6).
    """

    const: np.ndarray
    a: np.ndarray
    b: np.ndarray
    Q: np.ndarray
    C: np.ndarray

    def evaluate(self, std) -> np.ndarray:
        """Reconstructed theta, std shape (..., 10 nb) -> (..., p)."""
        v = np.asarray(std, dtype=float)
        out = np.broadcast_to(self.const, v.shape[:-1] + self.const.shape).copy()
        for k in range(self.a.shape[0]):
            m = v[..., 10 * k]
            r = v[..., 10 * k + 1 : 10 * k + 4]
            inertia = v[..., 10 * k + 4 : 10 * k + 10]
            h = (self.a[k] + np.einsum("ij,...j->...i", self.b[k], r)
                 + np.einsum("...j,ijl,...l->...i", r, self.Q[k], r))
            out += m[..., None] * h + np.einsum("ij,...j->...i", self.C[k], inertia)
        return out


def _structure(robot) -> _Structure:
    """Extract the decomposition from ``robot.theta_of_standard`` by exact evaluations.

    ``c_k`` from unit inertia entries (theta is affine in ``I``); ``h_k(r)`` =
    theta(m_k = 1, r_k = r) - theta(0) with every other parameter 0, and the
    quadratic's coefficients from ``r = 0, +-e_j, e_j + e_l`` (exact for a
    quadratic up to rounding). The claim that theta has this form is checked
    in the tests at random points.
    """
    size = len(robot.standard_parameter_names)
    nb = size // 10
    zero = np.zeros(size)
    const = robot.theta_of_standard(zero)
    p = const.size

    def th(v):
        return robot.theta_of_standard(v) - const

    a = np.zeros((nb, p))
    b = np.zeros((nb, p, 3))
    Q = np.zeros((nb, p, 3, 3))
    C = np.zeros((nb, p, 6))
    eye = np.eye(3)
    for k in range(nb):
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


def certified_bounds(robot, box: Box) -> Bounds:
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
    box.check(robot)
    if robot.linear_in_standard_parameters:
        return _linear_bounds(robot, box)
    S = _structure(robot)
    nom = robot.standard_parameters()
    nb, p = S.a.shape
    lo_v = nom + box.lower
    hi_v = nom + box.upper
    theta_lo = S.const.copy()
    theta_hi = S.const.copy()
    wit_lo = np.zeros((p, nom.size))
    wit_hi = np.zeros((p, nom.size))
    for k in range(nb):
        sl_r = slice(10 * k + 1, 10 * k + 4)
        sl_i = slice(10 * k + 4, 10 * k + 10)
        m_lo, m_hi = lo_v[10 * k], hi_v[10 * k]
        for i in range(p):
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
        theta_nominal=robot.theta,
        witness_lo=wit_lo,
        witness_hi=wit_hi,
    )


def _linear_bounds(robot, box: Box) -> Bounds:
    """Exact ranges when theta = c + K std is linear (a Pinocchio robot's base parameters).

    Each theta_i is extremal at the corner where every parameter sits at the end its
    coefficient's sign asks for (interval arithmetic is exact for one linear form).
    """
    nom = robot.standard_parameters()
    c = robot.theta_of_standard(np.zeros(nom.size))
    K = np.stack([robot.theta_of_standard(np.eye(nom.size)[j]) - c for j in range(nom.size)], axis=1)
    lo_v, hi_v = nom + box.lower, nom + box.upper
    wit_lo = np.where(K >= 0, lo_v, hi_v)
    wit_hi = np.where(K >= 0, hi_v, lo_v)
    theta_lo = c + np.einsum("ij,ij->i", K, wit_lo)
    theta_hi = c + np.einsum("ij,ij->i", K, wit_hi)
    rho_i = 0.5 * (theta_hi - theta_lo)
    return Bounds(method="certified", theta0=0.5 * (theta_lo + theta_hi), rho=float(np.sqrt(np.sum(rho_i**2))),
                  rho_i=rho_i, theta_lo=theta_lo, theta_hi=theta_hi, box=box, theta_nominal=robot.theta,
                  witness_lo=wit_lo, witness_hi=wit_hi)


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
    if t0.shape != cert.theta_lo.shape or not np.all(np.isfinite(t0)):
        raise ParameterError(f"theta0 needs {cert.theta_lo.size} finite entries, got {t0.tolist()}")
    rho_i = np.maximum(t0 - cert.theta_lo, cert.theta_hi - t0)
    rho_i = np.maximum(rho_i, 0.0)
    return float(np.sqrt(np.sum(rho_i**2))), rho_i

