r"""Weighted least squares with per-joint noise, the parameter covariance, the confidence ellipsoid.

Model: ``y_tj = A_tj x + e_tj`` for rows ``t`` and joints ``j``, where ``A`` and ``y`` are the
low-passed regressor and torques of :mod:`rc3r.identify.filtering` (``L[Phi]`` and ``L[tau]``
on the coarse grid) and ``e_tj = L[w_j]`` is white sensor noise ``w_j`` of standard
deviation ``sigma_j`` (per sample at the log's rate; drives and sensors differ per joint)
after the same filter.

Estimate (:func:`weighted_least_squares`)
    ``weighting="per-joint"``: ordinary least squares first; then ``sigma_j`` from the residuals
    and least squares again with weights ``1/sigma_j``; twice. ``weighting="ordinary"``: ordinary
    least squares only (``sigma_j`` still from its residuals, for the covariance). Which one
    ``rc3r identify`` uses is chosen by cross-validation (:mod:`rc3r.identify.selection`): per-joint
    weights are the Gauss--Markov choice when the residual is sensor noise, but they also shrink the
    pull of the joints whose residual is mostly model error. Solved by the normal equations of the
    column-scaled weighted matrix (condition number at most :data:`COND_MAX`, checked first) with
    one step of iterative refinement.

Noise and covariance
    The filtered noise is coloured, and what survives the filter need not be white either
    (differentiated encoder noise in the regressor grows as ``f^4``; unmodelled dynamics sit at
    low frequencies). The covariance is the sandwich

    .. math::  \mathrm{Cov}(\hat x) = H^{-1} B H^{-1}, \qquad H = Z^T Z, \qquad
               B = \mathrm{Var}(Z^T e) = \frac{1}{M}\sum_k \sum_j \hat Z_j(\omega_k)^* \hat Z_j(\omega_k)^T\,
               s_j(\omega_k),

    ``Z`` the rows weighted by ``w_j``, ``\hat Z_j`` their discrete Fourier transform over the
    rows of joint ``j`` (zero-padded to ``M = 2N``), and ``s_j = w_j^2 |L|^2 S_j f_2 / 2`` the
    spectral density of the rows' noise: ``|L(f)|^2`` the filter's power response and ``S_j`` the
    one-sided power spectrum [N^2 m^2/Hz] of the **unfiltered** residual (Welch, at the logged
    stamps), ``f_2`` the rows' rate (Whittle's approximation; exact when the noise's correlation
    dies out within ``N`` rows). For white noise ``S_j = 2 sigma_j^2 / f_s`` this is
    ``(1/D) (L Z)^T (L Z)`` (Parseval), and without filtering the Gauss--Markov
    ``(A^T W A)^{-1}``; for ordinary least squares (``w_j = 1``) the white-noise sandwich is
    ``H^{-1} (sum_j sigma_j^2 Z_j^T Z_j) H^{-1} / D``. ``sigma_j`` reported is the white-equivalent level
    from the filtered
    residual: ``||r_j||^2 = sigma_j^2 (N G - m/(n D))`` with ``G`` the filter's noise gain
    (:func:`rc3r.identify.filtering.noise_gain`) and ``D`` the coarse grid's step.

In-band covariance (:func:`in_band_covariance`, ``rc3r identify``'s default)
    The same sandwich with ``s_j = c_j |L|^2``: one level per joint, measured over the band that holds
    :data:`INFO_SHARE` of the estimate's information, by moments that count what the fit absorbed
    there. The filtered residual's spectrum rises toward ``f_c`` (errors in the variables), the
    regressor's information lies well below it: the whole band's level (above) overstates the noise
    that moves the estimate (docs/identification.md, section 2.5).

Confidence ellipsoid (:func:`ellipsoid`)
    ``x`` is approximately normal, so the dynamic coefficients ``theta`` (the first ``p``
    unknowns) satisfy ``(theta - theta_hat)^T Cov_theta^{-1} (theta - theta_hat) <= chi2_p(C)``
    with probability ``C``: the ellipsoid ``||theta - theta_0||_P <= 1`` with
    ``P = Cov_theta^{-1} / chi2_p(C)``. The smallest ball about ``theta_0`` containing it has
    ``rho = sqrt(lambda_max(P^{-1}))``, the smallest box ``rho_i = sqrt((P^{-1})_ii)``: the
    robust laws' bounds (eqs. 6 and 7) hold with the same probability.

Excitation (:func:`check_excitation`): a joint that does not move, or a regressor whose
column-scaled condition number exceeds :data:`COND_MAX` (rank-deficient: the trajectory does
not excite some combination of coefficients), is refused in one line naming the worst
combination.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError, ParameterError

__all__ = ["COND_MAX", "MOTION_MIN", "WEIGHTINGS", "Fit", "ellipsoid_factor", "draw_theta",
           "check_excitation", "weak_columns", "ARMATURE_COND", "spread_ellipsoid",
           "weighted_least_squares", "spectral_covariance", "INFO_SHARE", "in_band_covariance",
           "dominating", "ellipsoid", "SLOW_SHARE", "SLOW_KEEP_MIN", "slow_rows"]

#: Largest condition number of the column-scaled regressor that still counts as full rank.
COND_MAX = 1e6

#: The least-squares weightings (:func:`weighted_least_squares`).
WEIGHTINGS = ("ordinary", "per-joint")

#: The in-band covariance measures the noise level over the band holding this share of the estimate's
#: information (:func:`in_band_covariance`).
INFO_SHARE = 0.99

#: A rotor-inertia column that leaves the column-scaled regressor's condition number above this is not fitted
#: (:func:`weak_columns`): it is nearly confounded with a rigid coefficient on this log (its variance would be
#: about ``cond^2`` times a well-determined column's).
ARMATURE_COND = 1e4

#: A joint whose filtered position range is below this [rad or m] does not move.
MOTION_MIN = 1e-2

#: A joint's rows where its filtered speed is below this share of its RMS speed over the training rows are left
#: out of the fit (:func:`slow_rows`): at reversals and rests a Coulomb joint sticks and its friction is any value
#: in ``[-f_c, f_c]``, which no smooth law of ``qd`` models. A sinusoidal joint spends 4.5 % of its time there.
SLOW_SHARE = 0.1

#: A joint that would keep less than this share of its training rows keeps them all (a joint that mostly rests).
SLOW_KEEP_MIN = 0.5


@dataclass(frozen=True, eq=False)
class Fit:
    """A weighted least-squares fit.

    Attributes
    ----------
    x : ndarray (m,)
        The estimate.
    cov : ndarray (m, m)
        Its covariance (module docstring).
    sigma : ndarray (n,)
        Per-joint standard deviation of the white noise before the filter (per sample of the log).
    rows : int
        Rows N used.
    cond : float
        Condition number of the column-scaled weighted regressor.
    weights : ndarray (n,)
        The per-joint weights of the last least squares.
    """

    x: np.ndarray
    cov: np.ndarray
    sigma: np.ndarray
    rows: int
    cond: float
    weights: np.ndarray

    def predict(self, A) -> np.ndarray:
        """``A x``: (N, n) from (N, n, m)."""
        return np.asarray(A) @ self.x

    def band(self, A, sigma, confidence: float) -> np.ndarray:
        """Half-width (N, n) of the two-sided prediction interval at ``confidence`` for new samples.

        ``z sqrt(sigma_j^2 + a^T Cov a)`` with ``z`` the normal quantile and ``sigma`` (n,) the
        noise of one new sample (a new torque carries the noise, the prediction the estimate's
        uncertainty).
        """
        from scipy.stats import norm

        A = np.asarray(A, dtype=float)
        var = np.einsum("tjk,kl,tjl->tj", A, self.cov, A) + np.asarray(sigma, dtype=float) ** 2
        return float(norm.ppf(0.5 + 0.5 * confidence)) * np.sqrt(var)


def check_excitation(A, names, q) -> None:
    """ConfigError unless every joint moves and the regressor (N, n, m) has full numerical rank.

    ``q`` (N, n) are the filtered positions; ``names`` the m unknowns.
    """
    span = np.ptp(q, axis=0)
    still = np.nonzero(span < MOTION_MIN)[0]
    if still.size:
        raise ConfigError("unexciting trajectory: joint(s) " + ", ".join(str(j + 1) for j in still)
                          + f" do not move (position range {', '.join(f'{span[j]:.3g}' for j in still)}, "
                          f"less than {MOTION_MIN:g}): the regressor is rank-deficient")
    M = np.asarray(A, dtype=float).reshape(-1, A.shape[-1])
    norms = np.linalg.norm(M, axis=0)
    zero = np.nonzero(norms == 0.0)[0]
    if zero.size:
        raise ConfigError(f"unexciting trajectory: the regressor's column(s) {', '.join(names[k] for k in zero)} "
                          "are zero (rank-deficient)")
    Mn = M / norms
    lam, vec = np.linalg.eigh(Mn.T @ Mn)  # squared singular values of the column-scaled regressor
    cond = float(np.sqrt(lam[-1] / lam[0])) if lam[0] > 0 else np.inf
    if cond > COND_MAX:
        v = vec[:, 0]
        top = np.argsort(-np.abs(v))[:3]
        combo = " ".join(f"{'+' if v[k] >= 0 else '-'} {abs(v[k]):.2f} {names[k]}" for k in top)
        raise ConfigError(f"unexciting trajectory: the regressor is rank-deficient (column-scaled condition "
                          f"number {cond:.3g} > {COND_MAX:.0e}); the log does not determine {combo.lstrip('+ ')}")


def weak_columns(A, candidates, cond_max: float = None) -> dict:
    """Columns among ``candidates`` to leave out until the column-scaled regressor (N, n, m) is conditioned.

    While the condition number exceeds ``cond_max`` (default :data:`ARMATURE_COND`), the candidate with
    the largest weight in the weakest direction (the smallest singular value's right vector) is left out,
    if that weight is at least 0.1 (else the ill-conditioning is not the candidates'). Returns
    ``{column: the other column with the largest weight in that direction}`` (what it is confounded with).
    """
    cond_max = ARMATURE_COND if cond_max is None else float(cond_max)
    M = np.asarray(A, dtype=float).reshape(-1, A.shape[-1])
    norms = np.linalg.norm(M, axis=0)
    norms[norms == 0] = 1.0
    Mn = M / norms
    G = Mn.T @ Mn
    keep = list(range(M.shape[1]))
    out = {}
    while True:
        lam, vec = np.linalg.eigh(G[np.ix_(keep, keep)])
        if lam[0] > 0 and np.sqrt(lam[-1] / lam[0]) <= cond_max:
            return out
        v = np.abs(vec[:, 0])
        cand = [i for i, c in enumerate(keep) if c in candidates]
        if not cand:
            return out
        i = max(cand, key=lambda i: v[i])
        if v[i] < 0.1:
            return out
        others = [k for k in range(len(keep)) if k != i]
        out[keep[i]] = keep[max(others, key=lambda k: v[k])]
        keep.pop(i)


def slow_rows(qd, rows, share: float = SLOW_SHARE) -> np.ndarray:
    """Per-joint weights (K, n) of 0 or 1: 0 where joint ``j``'s speed is below ``share`` x its RMS over ``rows``.

    Parameters
    ----------
    qd : ndarray (K, n)
        Filtered joint velocities [rad/s or m/s] of the rows.
    rows : ndarray of bool (K,)
        The rows whose RMS speed sets the threshold (the training part).
    share : float
        :data:`SLOW_SHARE`; 0 keeps every row. A joint that would keep less than :data:`SLOW_KEEP_MIN` of
        ``rows`` keeps every row.

    Returns
    -------
    ndarray (K, n)
        1.0 for a row of a joint the fit uses, 0.0 for one it leaves out (the row ``j`` of ``A`` and ``y``
        is multiplied by it).
    """
    if not (np.isfinite(share) and 0.0 <= share < 1.0):
        raise ConfigError(f"slow share must be in [0, 1) (a share of a joint's RMS speed), got {share:g}")
    qd = np.abs(np.asarray(qd, dtype=float))
    keep = np.ones(qd.shape)
    if share <= 0:
        return keep
    rms = np.sqrt(np.mean(qd[rows] ** 2, axis=0))
    slow = qd < share * rms[None, :]
    use = np.mean(~slow[rows], axis=0) >= SLOW_KEEP_MIN
    keep[:, use] = np.where(slow[:, use], 0.0, 1.0)
    return keep


def _lstsq(A, y, w):
    """Weighted least squares of (N, n, m) A, (N, n) y with per-joint weights w (n,): (x, H^{-1}, scale, cond).

    Normal equations of the column-scaled matrix (its condition number is at most
    :data:`COND_MAX`, checked before) with one step of iterative refinement; ``H^{-1}`` is of the
    scaled columns.
    """
    Aw = (A * w[None, :, None]).reshape(-1, A.shape[-1])
    yw = (y * w[None, :]).ravel()
    scale = np.linalg.norm(Aw, axis=0)
    scale[scale == 0] = 1.0
    As = Aw / scale
    H = As.T @ As
    Hinv = np.linalg.inv(H)
    xs = Hinv @ (As.T @ yw)
    xs = xs + Hinv @ (As.T @ (yw - As @ xs))
    lam = np.linalg.eigvalsh(H)
    return xs / scale, Hinv, scale, float(np.sqrt(lam[-1] / max(lam[0], 1e-300)))


def weighted_least_squares(A, y, gain: float = 1.0, step: int = 1, iterations: int = 2,
                           weighting: str = "per-joint", kept=None) -> Fit:
    """Fit ``y`` (N, n) by ``A`` (N, n, m) (module docstring: weights, noise).

    The covariance is the white-noise one, ``(sigma^2 / D)``-scaled ``H^{-1}`` (per-joint weights) or
    the sandwich (ordinary); replace it with :func:`spectral_covariance` when the residual's spectrum
    is known.

    Parameters
    ----------
    A, y : ndarray
        Filtered regressor rows and torques.
    gain : float
        ``G``, the variance of the filter's output for unit white input (1: no filter).
    step : int
        ``D``, samples of the log per row.
    iterations : int
        Re-weightings after the ordinary fit (``weighting="per-joint"`` only).
    weighting : str
        ``"per-joint"`` (weights ``1/sigma_j``) or ``"ordinary"`` (all 1), :data:`WEIGHTINGS`.
    kept : ndarray (n,), optional
        Share of each joint's rows that are not zeroed (:func:`slow_rows`): ``sigma_j`` counts only those.
    """
    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    N, n, m = A.shape
    kept = np.ones(n) if kept is None else np.asarray(kept, dtype=float)
    if weighting not in WEIGHTINGS:
        raise ConfigError(f"weighting must be one of {', '.join(WEIGHTINGS)}, got {weighting!r}")
    if N * n <= m:
        raise ConfigError(f"too few samples: {N} rows x {n} joints for {m} unknowns")
    dof = kept * N * gain - m / (n * step)
    if np.any(dof <= 0):
        raise ConfigError(f"too few samples: {N} rows for {m} unknowns after filtering")
    w = np.ones(n)
    for _ in range(iterations + 1 if weighting == "per-joint" else 0):
        x, Hinv, scale, cond = _lstsq(A, y, w)
        e = y - A @ x
        sigma = np.sqrt(np.sum(e ** 2, axis=0) / dof)
        sigma = np.maximum(sigma, 1e-12 * max(1.0, float(np.abs(y).max())))
        w = 1.0 / sigma
    x, Hinv, scale, cond = _lstsq(A, y, w)
    e = y - A @ x
    sigma = np.sqrt(np.sum(e ** 2, axis=0) / dof)
    if weighting == "per-joint":
        cov = Hinv / np.outer(scale, scale) / step  # white-noise approximation (L ~ I on the band)
    else:
        As = A / scale
        B = sum(sigma[j] ** 2 * (As[:, j, :].T @ As[:, j, :]) for j in range(n))
        cov = Hinv @ B @ Hinv / np.outer(scale, scale) / step
    return Fit(x, 0.5 * (cov + cov.T), sigma, N, cond, w)


def spectral_covariance(A, w, rate: float, density) -> np.ndarray:
    r"""The sandwich covariance of a fit with weights ``w`` (n,) for rows ``A`` (N, n, m) at ``rate`` [Hz].

    ``density(f)`` -> (len(f), n): the rows' noise spectral density *before weighting*, one-sided
    [unit^2/Hz], filter included (``|L(f)|^2 S_j(f)``). Module docstring: Whittle's formula.
    """
    A = np.asarray(A, dtype=float)
    N, n, m = A.shape
    Z = A * np.asarray(w, dtype=float)[None, :, None]
    scale = np.linalg.norm(Z.reshape(-1, m), axis=0)
    scale[scale == 0] = 1.0
    Z = Z / scale
    H = np.einsum("tjk,tjl->kl", Z, Z)
    M = 2 * N
    f = np.fft.rfftfreq(M, d=1.0 / rate)
    dens = np.asarray(density(f), dtype=float) * (rate / 2.0) * np.asarray(w, dtype=float) ** 2  # (len(f), n)
    weight = np.full(f.size, 2.0)  # rfft: every bin but 0 and Nyquist stands for two
    weight[0] = 1.0
    if M % 2 == 0:
        weight[-1] = 1.0
    B = np.zeros((m, m))
    for j in range(n):
        F = np.fft.rfft(Z[:, j, :], n=M, axis=0)  # (len(f), m)
        Fw = F * (weight * dens[:, j])[:, None]
        B += np.real(F.conj().T @ Fw)
    B /= M
    Hinv = np.linalg.inv(H)
    cov = Hinv @ B @ Hinv / np.outer(scale, scale)
    return 0.5 * (cov + cov.T)


def in_band_covariance(A, w, e, rate: float, fs: float, fc: float, share: float = INFO_SHARE, kept=None) -> dict:
    r"""The sandwich covariance with each joint's noise level measured where the estimate's information is.

    The filtered residual's spectrum is not flat inside the pass band: errors in the variables
    (differentiated encoder steps in ``qdd``, Coulomb columns flipping with velocity noise) grow toward
    ``f_c``, while the regressor's rows ``Z`` (weights ``w`` (n,), rows ``A`` (N, n, m) at ``rate`` [Hz],
    residual ``e`` (N, n)) hold their energy well below it. A flat level averaged over the whole band
    (:func:`weighted_least_squares`) then overstates the noise that moves the estimate. Here:

    * the band ``[0, f_top]`` holds ``share`` of the estimate's information
      ``I(f) = |L(f)|^2 sum_j tr(H^{-1} \hat Z_j(f)^* \hat Z_j(f))``;
    * each joint's level ``c_j`` (white-equivalent, filtered like the rows: density ``c_j |L|^2``) is the
      method-of-moments solution of ``E[Q_j] = Q_j``, ``Q_j`` the residual's power in the band, whose
      expectation under the model ``E[r r^T] = (I - Z H^{-1} Z^T) S (I - Z H^{-1} Z^T)`` counts what the fit
      absorbed there (in the band the fit absorbs a large share of the residual: the uncorrected level
      is too small);
    * ``Cov = H^{-1} (sum_j c_j G_j) H^{-1}`` with ``G_j`` the Whittle form of :func:`spectral_covariance`.

    Returns ``cov`` (m, m), ``sigma`` (n,) (white-equivalent per-sample level at ``fs`` [unit]),
    ``band_hz`` (``f_top``) and ``dof`` (``2 f_top T`` per joint minus the information absorbed: the
    F quantile's ``nu``). ``kept`` (n,): the share of each joint's rows that are not zeroed
    (:func:`slow_rows`); the noise of joint ``j`` is present on that share of the rows only.
    """
    from .filtering import power_response

    A = np.asarray(A, dtype=float)
    N, n, m = A.shape
    kept = np.ones(n) if kept is None else np.asarray(kept, dtype=float)
    w = np.asarray(w, dtype=float)
    Z = A * w[None, :, None]
    r = np.asarray(e, dtype=float) * w[None, :]
    scale = np.linalg.norm(Z.reshape(-1, m), axis=0)
    scale[scale == 0] = 1.0
    Z = Z / scale
    Hi = np.linalg.inv(np.einsum("tjk,tjl->kl", Z, Z))
    M = 2 * N
    f = np.fft.rfftfreq(M, d=1.0 / rate)
    wt = np.full(f.size, 2.0)
    wt[0] = 1.0
    if M % 2 == 0:
        wt[-1] = 1.0
    L2 = power_response(f, fs, fc) * (rate / 2.0)  # per-row variance density of filtered noise of level 1
    F = [np.fft.rfft(Z[:, j, :], n=M, axis=0) for j in range(n)]
    R = np.abs(np.fft.rfft(r, n=M, axis=0)) ** 2

    def gram(j, g):
        return np.real(F[j].conj().T @ (F[j] * (wt * g)[:, None])) / M

    info = L2 * wt * sum(np.einsum("kl,fk,fl->f", Hi, F[j].conj(), F[j]).real for j in range(n))
    top = float(f[min(int(np.searchsorted(np.cumsum(info) / info.sum(), share)), f.size - 1)])
    b = f <= top
    G = [gram(j, L2) for j in range(n)]
    X, q, absorbed = np.zeros((n, n)), np.zeros(n), 0.0
    for j in range(n):
        Gb = gram(j, b.astype(float))
        X[j, j] += kept[j] * (N / M) * np.sum(wt[b] * L2[b]) - 2.0 * np.trace(Hi @ gram(j, b * L2))
        HGH = Hi @ Gb @ Hi
        X[j] += [np.sum(HGH * G[i]) for i in range(n)]
        q[j] = np.sum(wt[b] * R[b, j]) / M
        absorbed += float(np.trace(Hi @ Gb))
    c = np.linalg.solve(X, q)
    c = np.maximum(c, 1e-24 * max(1.0, float(np.max(np.abs(c)))))
    cov = Hi @ sum(c[i] * G[i] for i in range(n)) @ Hi / np.outer(scale, scale)
    return {"cov": 0.5 * (cov + cov.T), "sigma": np.sqrt(c * fs / 2.0) / w, "band_hz": top,
            "dof": float(np.sum(kept)) * 2.0 * top * N / rate - absorbed}


def dominating(C1, C2) -> np.ndarray:
    """The smallest covariance along the common eigendirections of ``C1`` and ``C2`` that is >= both.

    With ``C1 = L L^T`` and ``L^{-1} C2 L^{-T} = U diag(l) U^T``: ``L U diag(max(1, l)) U^T L^T``.
    Its ellipsoid contains both ellipsoids.
    """
    L = np.linalg.cholesky(C1)
    Li = np.linalg.inv(L)
    lam, U = np.linalg.eigh(Li @ C2 @ Li.T)
    C = L @ (U * np.maximum(lam, 1.0)) @ U.T @ L.T
    return 0.5 * (C + C.T)


def ellipsoid(cov_theta, confidence: float, dof: float | None = None) -> dict:
    r"""The confidence ellipsoid of ``theta`` with covariance ``cov_theta`` (p, p) at ``confidence``.

    The quantile is ``chi2_p(C)`` for a known covariance, or ``p F_{p, nu}(C)`` when the noise
    level behind it was estimated with ``nu = dof`` degrees of freedom (the Wald statistic with an
    estimated variance; it tends to ``chi2_p`` as ``nu`` grows).

    Returns
    -------
    dict
        ``P`` (p, p) with ``(theta - theta_0)^T P (theta - theta_0) <= 1``, ``chi2`` (the
        quantile), ``quantile`` (which), ``dof``, ``rho`` (radius of the smallest ball about
        theta_0 containing the ellipsoid), ``rho_i`` (p,) (half-widths of the smallest box),
        ``confidence``.
    """
    from scipy.stats import chi2, f

    if not 0.0 < confidence < 1.0:
        raise ConfigError(f"confidence must be between 0 and 1 (exclusive), got {confidence}")
    cov_theta = np.asarray(cov_theta, dtype=float)
    p = cov_theta.shape[0]
    if dof is None or not np.isfinite(dof):
        q, which = float(chi2.ppf(confidence, p)), "chi2_p(C)"
    else:
        if dof <= 1:
            raise ConfigError(f"too few effective samples for a confidence region ({dof:.3g} degrees of freedom)")
        q, which = float(p * f.ppf(confidence, p, dof)), "p F(C; p, nu)"
    Pinv = q * cov_theta
    P = np.linalg.inv(Pinv)
    P = 0.5 * (P + P.T)
    return {"P": P, "chi2": q, "quantile": which, "dof": None if dof is None else float(dof),
            "rho": float(np.sqrt(np.linalg.eigvalsh(Pinv)[-1])), "rho_i": np.sqrt(np.diag(Pinv)),
            "confidence": float(confidence)}


def spread_ellipsoid(P, keep, size: int, pairs: dict) -> dict:
    """An ellipsoid ``P`` (k, k) over coordinates ``keep`` (k,) of ``size``, spread over all of them.

    A coordinate not kept gets an independent half-width: that of the kept coordinate ``pairs[i]`` names
    (an index into ``keep``), for each ``i`` in ``pairs`` (the slice through the result at 0 along them is
    ``P``). Returns ``P`` (size, size), ``rho``, ``rho_i`` (size,). Every coordinate must be kept or paired.
    """
    Pinv_c = np.linalg.inv(np.asarray(P, dtype=float))
    Pinv = np.zeros((size, size))
    Pinv[np.ix_(keep, keep)] = Pinv_c
    for i, k in pairs.items():
        Pinv[i, i] = Pinv_c[k, k]
    Pinv = 0.5 * (Pinv + Pinv.T)
    P_full = np.linalg.inv(Pinv)
    return {"P": 0.5 * (P_full + P_full.T), "rho": float(np.sqrt(np.linalg.eigvalsh(Pinv)[-1])),
            "rho_i": np.sqrt(np.diag(Pinv))}


def ellipsoid_factor(P) -> np.ndarray:
    r"""``L`` (p, p) with :math:`L L^T = P^{-1}`: :math:`\theta_0 + L u`, :math:`\|u\| \le 1`, fills the ellipsoid.

    Raises
    ------
    ParameterError
        ``P`` is not symmetric positive definite.
    """
    P = np.asarray(P, dtype=float)
    if P.ndim != 2 or P.shape[0] != P.shape[1] or not np.all(np.isfinite(P)):
        raise ParameterError(f"ellipsoid matrix P must be a finite square matrix, got shape {P.shape}")
    w, V = np.linalg.eigh(0.5 * (P + P.T))
    if w[0] <= 0:
        raise ParameterError(f"ellipsoid matrix P is not positive definite (smallest eigenvalue {w[0]:.3g})")
    return V / np.sqrt(w)


def draw_theta(theta0, P, rng: np.random.Generator, boundary: bool = False) -> np.ndarray:
    r"""One :math:`\theta` uniform in the ellipsoid (or on its boundary), (p,).

    :math:`u = g\,r^{1/p}/\|g\|` with :math:`g \sim N(0, I_p)`, :math:`r \sim U(0, 1)` (``r = 1`` on
    the boundary) is uniform in the unit ball; :math:`\theta = \theta_0 + L u`.
    """
    theta0 = np.asarray(theta0, dtype=float)
    L = ellipsoid_factor(P)
    p = theta0.size
    g = rng.standard_normal(p)
    r = 1.0 if boundary else rng.uniform() ** (1.0 / p)
    return theta0 + L @ (g * (r / np.linalg.norm(g)))
