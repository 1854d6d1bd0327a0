r"""The sampled-data rule: gains and boundary layer from the controller rate (docs/design.md).

**The held loop.** For the laws on :math:`r = \dot e + \Lambda e`, the plant
:math:`M\ddot q + C\dot q + g = u` under :math:`u = Y(\theta_0 + \delta) - K r` gives
:math:`M\dot r = -C r - K r + Y(\theta_0 - \theta + \delta)`. Inside the boundary layer
:math:`\delta = -(\rho/\epsilon) Y^T r` (eq. 6; :math:`-\mathrm{diag}(\rho_i/\epsilon_i) Y^T r` for eq. 7),
so the fast part of the loop is :math:`M\dot r = -G r` with :math:`G = K + (\rho/\epsilon) Y Y^T`. A
digital controller computes :math:`G r` from the state d samples ago and holds it for the period T:
per mode of :math:`M^{-1} G` (real, :math:`\lambda \ge 0`: similar to :math:`M^{-1/2} G M^{-1/2}`),
:math:`r_{k+1} = r_k - T\lambda\, r_{k-d}`, whose characteristic polynomial is
:math:`z^{d+1} - z^d + T\lambda`. It is

* stable while :math:`T\lambda <` :func:`stability_limit` :math:`= 2\sin(\pi / (2(2d+1)))`
  (2 without delay, 1 with one sample, 0.618 with two);
* free of oscillation at the sampling rate (its slowest mode real and positive: it neither alternates
  nor rings) while :math:`T\lambda \le` :func:`real_limit` :math:`= d^d/(d+1)^{d+1}` (1, 1/4, 4/27): the
  design target.

Along the reference (:math:`q = q_d`, Y at :math:`(q_d, \dot q_d, \dot q_d, \ddot q_d)`, M of the
controller's model), :math:`\lambda_{\max}(M^{-1}G) \le \lambda_{\max}(M^{-1}K) + (\rho/\epsilon)
\lambda_{\max}(M^{-1}YY^T)` (Weyl), so the loop at period T is stable when

.. math::

    \epsilon \ge \frac{T\,\rho\,L_Y}{c_d - T L_K},\qquad
    L_Y = \max_t \lambda_{\max}(M^{-1} Y Y^T),\quad L_K = \max_t \lambda_{\max}(M^{-1} K).

**The fast form** (:func:`fast_design`, no simulation) asks for more: the loop must still be free
of oscillation at ``rate / margin`` (period :math:`T' = mT`). It takes

* the scheduled K (``coupling="inertia"``, the default): :math:`K(q) = b\,M(q)` (the law's
  ``K_inertia`` = b, its constant K = 0): every mode of the model's :math:`M^{-1}K` is b, so
  :math:`L_K = b` and :math:`b = \min(\mathrm{rate}/20,\; 125,\; a_d / (4 T'))`: K may use a quarter of
  the budget; :math:`\Lambda = \min(b / 2.5, 50)` [1/s]. Spong's proof needs only a uniformly positive
  definite K(q);
* or a constant K (``coupling="diag"``): :math:`K_i = b\,\kappa_i` with
  :math:`\kappa_i = 1/(M^{-1}(q_d(0)))_{ii}` (the inertia joint i moves with the other joints free;
  ``scaling="diag"`` takes :math:`M_{ii}(q_d(0))`, :func:`rc3r.controllers.inertia_scaled_gain`) and
  :math:`b = \min(\mathrm{rate}/20,\; 125,\; a_d / (4 T' L_\kappa))`, whose spread
  :math:`L_\kappa / b` (M's coupling and its variation along the reference: the Kinova's 22.8) holds b
  down; ``"full"`` takes the constant :math:`b\,M(q_d(0))`, ``"auto"`` the constant one with the larger b;
* :math:`\epsilon = T'\rho L_Y / (a_d - T' L_K)` (eq. 7: one :math:`\epsilon_i` for every coefficient with
  :math:`\rho L_Y` replaced by :math:`\max_t\lambda_{\max}(M^{-1} Y\,\mathrm{diag}(\rho_i) Y^T)`);
* the adaptive law's :math:`\Gamma`: Euler's update of :math:`\dot{\hat\theta} = -\Gamma Y^T r` with
  :math:`M\dot r = -K r + Y\tilde\theta` is stable while :math:`T(k^2/4 + \omega^2) < k`; with
  :math:`\omega^2 \le \gamma L_Y` and k in :math:`[k_-, L_K]`, :math:`\gamma = \min(10, (a_d - T' L_K)
  k_- / (T' L_Y))`;
* FBL: :math:`K_p = \Lambda^2`, :math:`K_d = 2\Lambda` (critically damped at the same bandwidth); PD:
  :math:`K_d = 2\Lambda\kappa`, :math:`K_p = \Lambda^2\kappa`, lowered until :math:`T' L_{K_d} \le a_d/4`.

:func:`sampled_gains` is the "defaults that work" of :func:`rc3r.runspec.build_run`: the law's default
gains when :func:`check` passes them, else the fast form's.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError
from ..uncertainty.inertia import ThetaModel  # re-exported: M(q; theta) of the controller's model

__all__ = ["stability_limit", "real_limit", "Spectrum", "spectrum", "ThetaModel", "Design", "fast_design", "check",
           "eps_boundary", "sampled_gains", "DESIGNED_LAWS", "LAMBDA_MAX", "B_FRACTION"]

#: Laws the rule designs (their gains are K, Lambda, eps / eps_i / Gamma, or Kp, Kd).
DESIGNED_LAWS = ("robust", "robust-coeff", "adaptive", "fbl", "pd", "pd-plus")
#: b = min(rate / B_FRACTION, ...) [1/s]: the velocity loop's bandwidth, a twentieth of the rate at most.
B_FRACTION = 20.0
#: Lambda = min(b / B_OVER_LAMBDA, LAMBDA_MAX) [1/s]: the error's mode 2.5x slower than the velocity loop.
B_OVER_LAMBDA = 2.5
LAMBDA_MAX = 50.0
#: b is never above B_MAX [1/s] (the reference moves at ~1 rad/s: faster loops only amplify noise).
B_MAX = B_OVER_LAMBDA * LAMBDA_MAX
#: Share of the sampled-data budget a_d that K (or PD's Kd) may use.
K_SHARE = 0.25
#: The margin of the defaults of sampled runs (:func:`sampled_gains`), ``rc3r design --margin``'s default.
DEFAULT_MARGIN = 2.0
#: The ellipsoid law (eq. 6 over ``||theta - theta_0||_P <= 1``): the defaults of sampled runs design it too.
ELLIPSOID = "robust-ellipsoid"
#: The adaptive law's gain is never above the default's.
GAMMA_MAX = 10.0


def stability_limit(delay: int = 0) -> float:
    """Largest :math:`T\\lambda` for which :math:`z^{d+1} - z^d + T\\lambda` is stable: :math:`2\\sin(\\pi/(2(2d+1)))`."""
    d = _delay(delay)
    return 2.0 * math.sin(math.pi / (2.0 * (2 * d + 1)))


def real_limit(delay: int = 0) -> float:
    """Largest :math:`T\\lambda` for which the slowest roots are real and positive: :math:`d^d / (d+1)^{d+1}`."""
    d = _delay(delay)
    return 1.0 if d == 0 else d ** d / (d + 1) ** (d + 1)


def _delay(delay) -> int:
    if isinstance(delay, bool) or int(delay) != delay or delay < 0:
        raise ParameterError(f"delay must be a whole number of samples >= 0, got {delay!r}")
    return int(delay)


@dataclass(frozen=True, eq=False)
class Spectrum:
    """The controller's model along the reference: what the rule needs, and the samples to reweigh.

    Attributes
    ----------
    t : (N,) sample times [s]
    chol_inv : (N, n, n) inverse Cholesky factors of M(q_d(t)) (M^-1 = L^T L)
    Y : (N, n, p) regressors at (q_d, qd_d, qd_d, qdd_d)
    kappa : (n,) the inertia unit of K [kg m^2] (``scaling``)
    scaling : str
        ``"free"``: 1 / (M^-1(q_d(0)))_ii; ``"diag"``: M_ii(q_d(0)).
    m_min, m_max : float
        Extreme eigenvalues of M over the samples [kg m^2].
    minv_diag_max : (n,) max over the samples of (M^-1)_jj [1/(kg m^2)]
    M0 : (n, n) M(q_d(0)) [kg m^2], the unit of a coupled K (:func:`fast_design`'s ``coupling``)
    """

    t: np.ndarray
    chol_inv: np.ndarray
    Y: np.ndarray
    kappa: np.ndarray
    scaling: str
    m_min: float
    m_max: float
    minv_diag_max: np.ndarray
    M0: np.ndarray | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def n(self) -> int:
        """Joints."""
        return self.Y.shape[1]

    def lam(self, A) -> float:
        """:math:`\\max_t \\lambda_{\\max}(M^{-1} A)` for a symmetric A (n, n), or a diagonal given as (n,)."""
        A = np.asarray(A, dtype=float)
        A = np.diag(A) if A.ndim == 1 else A
        return float(max(np.linalg.eigvalsh(Li @ A @ Li.T)[-1] for Li in self.chol_inv))

    def lam_min(self, A) -> float:
        """:math:`\\min_t \\lambda_{\\min}(M^{-1} A)`."""
        A = np.asarray(A, dtype=float)
        A = np.diag(A) if A.ndim == 1 else A
        return float(min(np.linalg.eigvalsh(Li @ A @ Li.T)[0] for Li in self.chol_inv))

    def lam_yy(self, weights=None) -> float:
        """:math:`\\max_t \\lambda_{\\max}(M^{-1} Y W Y^T)`, W = diag(weights) (p,), a positive definite
        (p, p) matrix (the ellipsoid law's :math:`P^{-1}`), or I."""
        key = None if weights is None else np.asarray(weights, dtype=float).tobytes()
        if key not in self._cache:
            W = None if weights is None else np.asarray(weights, dtype=float)
            w = None if W is None else np.linalg.cholesky(0.5 * (W + W.T)) if W.ndim == 2 else np.sqrt(W)
            vals = []
            for Li, Y in zip(self.chol_inv, self.Y):
                B = Li @ (Y if w is None else Y @ w if w.ndim == 2 else Y * w)
                vals.append(np.linalg.eigvalsh(B @ B.T)[-1])
            self._cache[key] = float(max(vals))
        return self._cache[key]


def spectrum(robot, trajectory, duration: float = 10.0, *, scaling: str = "free", samples: int | None = None
             ) -> Spectrum:
    """Sample the model ``robot`` along ``trajectory`` over [0, duration] (every 0.025 s, 101 to 2001 samples).

    ``robot`` is the controller's model (its M; for a payload the arm without it, the lightest plant when
    the range starts at 0), or a sequence of models of one arm (same kinematics, e.g. the robot's own
    parameters and the controller's theta_0, :class:`ThetaModel`): the samples of every model are
    stacked, so every ``max_t`` of the rule is also a maximum over the models and a design holds on each
    (``kappa`` and ``M0``, the units of a constant K and of PD, are the first model's).
    Raises ParameterError for a mass matrix that is not positive definite.
    """
    if scaling not in ("free", "diag"):
        raise ParameterError(f"scaling must be 'free' or 'diag', got {scaling!r}")
    if not (np.isfinite(duration) and duration > 0):
        raise ParameterError(f"duration must be finite and > 0, got {duration!r}")
    models = list(robot) if isinstance(robot, (list, tuple)) else [robot]
    N = samples or int(np.clip(round(40 * duration) + 1, 101, 2001))
    t = np.linspace(0.0, float(duration), N)
    qd, vd, ad = trajectory.evaluate(t)
    Ys = np.array([models[0].regressor(qd[k], vd[k], vd[k], ad[k]) for k in range(N)])  # kinematics: every model's
    Ls, dmax = [], np.zeros(models[0].n)
    lo, hi = np.inf, 0.0
    for model in models:
        for k in range(N):
            M = model.mass_matrix(qd[k])
            try:
                L = np.linalg.cholesky(M)
            except np.linalg.LinAlgError:
                raise ParameterError(f"the model's mass matrix is not positive definite at t = {t[k]:g} s") from None
            Li = np.linalg.inv(L)  # M^-1 = Li^T Li
            Ls.append(Li)
            ev = np.linalg.eigvalsh(M)
            lo, hi = min(lo, ev[0]), max(hi, ev[-1])
            dmax = np.maximum(dmax, np.sum(Li * Li, axis=0))  # (M^-1)_jj = sum_i Li_ij^2
    M0 = models[0].mass_matrix(qd[0])
    kappa = 1.0 / np.diag(np.linalg.inv(M0)) if scaling == "free" else np.diag(M0).copy()
    k = len(models)
    return Spectrum(np.tile(t, k), np.array(Ls), np.tile(Ys, (k, 1, 1)), kappa, scaling, float(lo), float(hi), dmax,
                    M0.copy())


@dataclass(frozen=True)
class Design:
    """Gains of every designed law for one rate, and the numbers behind them (:func:`fast_design`)."""

    rate: float
    delay: int
    margin: float
    Lambda: float
    bandwidth: float
    K: np.ndarray
    eps: float
    eps_i: float | None
    Gamma: float
    fbl: dict
    pd: dict
    rho: float
    L_Y: float
    L_K: float
    eps_stable: float
    kappa: np.ndarray
    scaling: str
    K_inertia: float = 0.0

    def gains(self, law: str) -> dict:
        """The gains of ``law`` (a key of :data:`DESIGNED_LAWS`) as a config table (plain floats and lists)."""
        sliding = {"K": np.asarray(self.K, dtype=float).tolist(), "Lambda": float(self.Lambda)}
        if self.K_inertia > 0.0:
            sliding["K_inertia"] = float(self.K_inertia)
        if law == "robust":
            return {**sliding, "eps": float(self.eps)}
        if law == "robust-coeff":
            if self.eps_i is None:
                raise ParameterError("this design has no rho_i: no eps_i for robust-coeff")
            return {**sliding, "eps_i": float(self.eps_i)}
        if law == "adaptive":
            return {**sliding, "Gamma": float(self.Gamma)}
        if law == "fbl":
            return dict(self.fbl)
        if law in ("pd", "pd-plus"):  # PD+'s error loop near the reference, M e'' + (C + Kd) e' + Kp e = 0, holds
            # the same Kd mode as PD's: the same gains
            return {k: [float(x) for x in v] for k, v in self.pd.items()}
        raise ParameterError(f"the rule designs {', '.join(DESIGNED_LAWS)}, not {law!r}")

    def describe(self) -> dict:
        """JSON-ready: every field (arrays as lists)."""
        out = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            out[f.name] = v.tolist() if isinstance(v, np.ndarray) else v
        return out


def _check_rate(rate, margin) -> tuple[float, float]:
    if isinstance(rate, bool) or not (isinstance(rate, (int, float)) and np.isfinite(rate) and rate > 0):
        raise ParameterError(f"rate must be a finite number of Hz > 0, got {rate!r}")
    if isinstance(margin, bool) or not (isinstance(margin, (int, float)) and np.isfinite(margin) and margin >= 1):
        raise ParameterError(f"margin must be a finite number >= 1, got {margin!r}")
    return float(rate), float(margin)


def eps_boundary(spec: Spectrum, rate: float, rho: float, K, delay: int = 0, rho_i=None,
                 K_inertia: float = 0.0) -> float:
    """The smallest eps for which the rule's held loop at ``rate`` is stable (inf: K alone is unstable);
    ``K_inertia`` b adds b to every mode of M^-1 K (the scheduled ``b M(q)`` on the spectrum's own M)."""
    T = 1.0 / float(rate)
    K = np.asarray(K, float)
    room = stability_limit(delay) - T * (spec.lam(K if K.ndim == 2 else np.broadcast_to(K, (spec.n,)))
                                         + float(K_inertia))
    ly = float(rho) * spec.lam_yy() if rho_i is None else spec.lam_yy(rho_i)
    return math.inf if room <= 0 else T * ly / room


def fast_design(spec: Spectrum, rate: float, *, rho: float, rho_i=None, delay: int = 0, margin: float = 1.0,
                Lambda: float | None = None, coupling: str = "inertia", b_max: float | None = None) -> Design:
    """The rule's fast form (module docstring): gains of every designed law at ``rate`` [Hz].

    Parameters
    ----------
    spec : Spectrum
        The model along the reference (:func:`spectrum`).
    rate : float
        Controller rate [Hz].
    rho, rho_i : float, (p,) optional
        The robust laws' bounds (eq. 6, eq. 7).
    delay : int
        Samples between a measurement and its torque.
    margin : float
        The design must stay free of oscillation at ``rate / margin`` (>= 1).
    Lambda : float, optional
        Error bandwidth [1/s] (default min(rate / 50, 50)).
    coupling : {"inertia", "diag", "full", "auto"}
        The sliding laws' K: ``"inertia"`` (the default) the scheduled ``K(q) = b M(q)``
        (``K = 0``, ``K_inertia = b``: every mode of M^-1 K is b for the model, so neither M's
        coupling nor its variation along the trajectory caps b); ``"diag"`` the constant ``b kappa``;
        ``"full"`` the constant ``b M(q_d(0))``; ``"auto"`` the constant one of the two with the larger b.
    b_max : float, optional
        A cap on b [1/s] (``rc3r design``: the held loop of K alone on the hardest plant of the bounds).
    """
    rate, margin = _check_rate(rate, margin)
    d = _delay(delay)
    if coupling not in ("inertia", "auto", "diag", "full"):
        raise ParameterError(f"coupling must be 'inertia', 'auto', 'diag' or 'full', got {coupling!r}")
    Tm = margin / rate
    a = real_limit(d)
    cap = min(rate / B_FRACTION, B_MAX, np.inf if b_max is None else float(b_max))
    l_diag = spec.lam(spec.kappa)
    sched = coupling == "inertia"
    full = spec.M0 is not None and (coupling == "full" or coupling == "auto" and spec.lam(spec.M0) < l_diag)
    unit = np.zeros(spec.n) if sched else spec.M0 if full else spec.kappa
    l_kappa = 1.0 if sched else spec.lam(unit) if full else l_diag  # max_t lambda_max(M^-1 unit)
    b = min(cap, K_SHARE * a / (Tm * l_kappa))
    lam = float(Lambda) if Lambda is not None else min(b / B_OVER_LAMBDA, LAMBDA_MAX)
    if not (np.isfinite(lam) and lam > 0):
        raise ParameterError(f"Lambda must be finite and > 0, got {Lambda!r}")
    K = b * unit
    L_K = b * l_kappa
    room = a - Tm * L_K
    L_Y = spec.lam_yy()
    eps = Tm * float(rho) * L_Y / room
    eps_i = None if rho_i is None else Tm * spec.lam_yy(rho_i) / room
    k_min = b if sched else b * spec.lam_min(unit)
    gamma = min(GAMMA_MAX, room * k_min / (Tm * L_Y)) if L_Y > 0 else GAMMA_MAX
    omega = min(lam, K_SHARE * a / (2.0 * Tm))  # FBL: T' Kd = 2 T' omega <= a/4 at most
    fbl = {"Kp": float(omega ** 2), "Kd": float(2.0 * omega)}
    w_pd = min(lam, K_SHARE * a / (2.0 * Tm * l_diag))  # PD's gains stay diagonal
    pd = {"Kp": (w_pd ** 2 * spec.kappa).tolist(), "Kd": (2.0 * w_pd * spec.kappa).tolist()}
    return Design(rate, d, margin, lam, float(b), K, float(eps), None if eps_i is None else float(eps_i),
                  float(gamma), fbl, pd, float(rho), L_Y, float(L_K),
                  eps_boundary(spec, rate, rho, K, d, K_inertia=b if sched else 0.0), np.array(unit, dtype=float),
                  "inertia" if sched else "full" if full else spec.scaling, float(b) if sched else 0.0)


def check(law, spec: Spectrum, rate: float, delay: int = 0, margin: float = 1.0) -> float:
    """The rule's figure of ``law`` at ``rate / margin``: the loop is free of oscillation there when it is <= 1.

    It is :math:`T'\\lambda_{\\max}` of the held loop divided by :func:`real_limit`; for the sliding laws
    also :math:`T'\\Lambda` (the error's own mode) counts. A law the rule does not know gives nan.
    """
    from ..controllers import Adaptive, FeedbackLinearization, PDGravity, PDPlus, Robust, RobustPerCoefficient
    from ..controllers.ellipsoid import RobustEllipsoid

    rate, margin = _check_rate(rate, margin)
    Tm, a, n = margin / rate, real_limit(delay), spec.n

    def vec(x):
        x = np.asarray(x, dtype=float)
        return x if x.ndim == 2 else np.broadcast_to(x, (n,))

    if isinstance(law, (Robust, RobustPerCoefficient, Adaptive)):
        L_K = spec.lam(vec(law.K)) + law.K_inertia  # the scheduled b M(q) on the spectrum's M: + b
        lam = float(np.max(law.Lambda))
        if isinstance(law, Robust):
            fig = Tm * (L_K + law.rho / law.eps * spec.lam_yy())
        elif isinstance(law, RobustPerCoefficient):
            fig = Tm * (L_K + spec.lam_yy(np.asarray(law.rho_i) / np.asarray(law.eps_i)))
        else:
            gmax = float(np.max(law.Gamma))
            fig = Tm * (L_K + gmax * spec.lam_yy() / max(spec.lam_min(vec(law.K)) + law.K_inertia, 1e-300))
        return max(fig, Tm * lam) / a
    if isinstance(law, RobustEllipsoid):  # inside its layer delta = -P^-1 Y^T r / (eps rho_P): G = K + Y P^-1 Y^T / ..
        fig = Tm * (spec.lam(vec(law.K)) + spec.lam_yy(law._Pinv) / (law.eps * law.rho_P))
        return max(fig, Tm * float(np.max(law.Lambda))) / a
    if isinstance(law, FeedbackLinearization):  # e'' + Kd e' + Kp e = 0, per joint: its fastest pole
        kp, kd = vec(law.Kp), vec(law.Kd)
        disc = np.sqrt(np.maximum(kd ** 2 - 4 * kp, 0.0))
        fastest = np.where(kd ** 2 >= 4 * kp, (kd + disc) / 2, np.sqrt(kp))
        return float(Tm * np.max(fastest)) / a
    if isinstance(law, (PDGravity, PDPlus)):  # the held loop M qdd = -Kd qd: T lambda_max(M^-1 Kd)
        return Tm * spec.lam(vec(law.Kd)) / a
    return math.nan


def _ellipsoid_gains(design: Design, spec: Spectrum, law) -> dict:
    """``robust-ellipsoid``'s gains from a fast form with a constant K (the law has no scheduled K): its
    boundary layer makes :math:`T'\\lambda_{\\max}(M^{-1}(K + Y P^{-1} Y^T / (\\epsilon\\rho_P)))` the real
    limit, :math:`\\epsilon = T' L_P / (\\rho_P (a_d - T' L_K))` with :math:`L_P = \\max_t\\lambda_{\\max}(M^{-1}
    Y P^{-1} Y^T)` (``law``: the ellipsoid law with its P, for ``_Pinv`` and ``rho_P``)."""
    Tm = design.margin / design.rate
    room = real_limit(design.delay) - Tm * design.L_K
    eps = Tm * spec.lam_yy(law._Pinv) / (law.rho_P * room)
    return {"K": np.asarray(design.K, dtype=float).tolist(), "Lambda": float(design.Lambda), "eps": float(eps)}


def _models(robot, theta0) -> list:
    """The models whose M the rule's spectrum spans: ``robot``, and its kinematics with ``theta0`` if that differs."""
    if theta0 is None:
        return [robot]
    th = np.asarray(theta0, dtype=float)
    if th.shape != (robot.p,) or np.array_equal(th, np.asarray(robot.theta, dtype=float)):
        return [robot]
    return [robot, ThetaModel(robot, th, "the controller's theta_0")]


#: Fast designs already computed in this process (campaign workers build many runs of one arm).
_CACHE: dict = {}


def sampled_gains(kind: str, robot, trajectory, model: dict, rate: float, *, delay: int = 0,
                  duration: float = 10.0, margin: float = DEFAULT_MARGIN):
    """The gains of ``kind`` for a sampled run without user gains (:func:`rc3r.runspec.build_run`'s hook).

    Returns ``(gains, note)``: the law's defaults (``gains = {}``) when :func:`check` passes them at
    ``rate / margin``, else the fast form's gains for that margin (by default ``rc3r design``'s, 2:
    with margin 1 the unverified eps of eq. 6 diverged on the xArm7 with a 0-3 kg payload at 500 Hz
    and 1 kHz, docs/design.md); ``note`` says which. ``(None, None)`` for a law the
    rule does not design.

    The rule's spectrum is taken over the robot's own parameters *and* the controller's model
    (``robot``'s kinematics with ``model["theta0"]``, :class:`ThetaModel`) when they differ: the held loop
    is stiffest on the lighter of the two along each direction, and either may be the plant (an identified
    arm's theta_0 and its URDF differ by 5-20x in the Panda's wrist, docs/design.md).
    """
    from ..controllers import make_law

    if kind not in DESIGNED_LAWS + (ELLIPSOID,):
        return None, None
    rho, rho_i = model.get("rho"), model.get("rho_i")
    if kind == "robust-coeff" and rho_i is None or kind == ELLIPSOID and model.get("P") is None:
        return None, None
    key = (kind, robot.label, robot.urdf, robot.n, robot.p,
           np.asarray(robot.theta, float).tobytes(), trajectory.pack().tobytes(), float(rate), int(delay),
           float(duration), float(margin), rho, None if rho_i is None else tuple(rho_i),
           tuple(model.get("theta0") or ()))
    if key not in _CACHE:
        skey = key[1:7] + key[9:10] + key[-1:]
        spec = _CACHE.get(skey)
        if spec is None:
            spec = _CACHE[skey] = spectrum(_models(robot, model.get("theta0")), trajectory, duration)
        default = make_law(kind, model["theta0"], rho=rho, rho_i=rho_i, **({"P": model["P"]} if kind == ELLIPSOID
                                                                           else {}))
        fig = check(default, spec, rate, delay, margin)
        if fig <= 1.0:
            _CACHE[key] = ({}, f"default gains (the sampled-data rule passes them at {rate / margin:g} Hz: "
                               f"{fig:.2g} <= 1)")
        else:
            design = fast_design(spec, rate, rho=rho if rho is not None else 0.0, rho_i=rho_i, delay=delay,
                                 margin=margin, coupling="diag" if kind == ELLIPSOID else "inertia")
            gains = _ellipsoid_gains(design, spec, default) if kind == ELLIPSOID else design.gains(kind)
            _CACHE[key] = (gains, f"gains of the sampled-data rule for {rate:g} Hz (the defaults "
                                               f"fail it: {fig:.2g} > 1; rc3r design verifies a design)")
    gains, note = _CACHE[key]
    return dict(gains), note
