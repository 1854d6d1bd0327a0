r"""Resampling, zero-phase low-pass filtering and differentiation of a log ("parallel filtering").

The dynamics ``tau = Phi(q, qd, qdd) x`` hold at every instant, so they hold for any linear
filter ``L`` applied to both sides: ``L[tau] = L[Phi] x``. rc3r fits that filtered equation
(:func:`prepare`):

1. **Resample** ``q`` and ``tau`` (and ``qd`` if logged) onto a uniform grid at the log's
   median time step (:func:`uniform_grid`) by cubic interpolating splines (the time stamps
   jitter; ``filtfilt`` needs a uniform grid).
2. **States**: ``q`` low-passed at ``STATE_FACTOR x f_c`` (zero phase, below; so that the
   parallel filter alone shapes the band: at ``f_c`` the states keep all but 3e-6 of their
   power), then
   differentiated by second-order central differences (``numpy.gradient``):
   ``qd = d q_f / dt`` (or the logged ``qd``, filtered, when it is the less noisy source:
   :func:`velocity_source`), ``qdd = d qd_f / dt``.
3. **Parallel filter** ``L``: Butterworth of order :data:`ORDER` at ``f_c`` run forwards and
   backwards (``scipy.signal.sosfiltfilt``: gain ``1/(1 + (f/f_c)^{2 ORDER})``, no delay,
   odd extension over ``3 f_s / f_c`` samples), applied to ``tau`` and to every regressor
   column. The arm's columns are evaluated on a coarser grid (every ``D``-th sample, rate
   ``f_2 >= COARSE_FACTOR x`` the state cut-off) and filtered there; the friction columns,
   which jump where a velocity changes sign, are filtered at the full rate, then sampled.
4. The first and last :data:`EDGE` ``/ f_c`` seconds are the filters' start-up: unused.
5. Predictions of the **unfiltered** torques (held-out RMS, prediction bands) evaluate the model
   at states low-passed at the cut-off itself (``PREDICT_FACTOR = 1``): ``q`` (and the logged
   ``qd``) zero-phase at ``f_c``, ``qd`` and ``qdd`` by central differences -- the states the fit
   sees through ``L``, and FIGAROH's recipe for its states. (Until issue 35 they were low-passed
   at ``2 f_c``, where ``qdd`` is mostly differentiated noise: 0.81-1.71 N m held out on the Panda
   log instead of 0.32-0.44.)

Why both sides: the torque of a real (or simulated) arm has content the low-passed states
cannot reproduce (a velocity reversal under Coulomb friction kinks the motion). Comparing
``tau`` itself with a model of filtered states leaves that content as a *systematic*
residual, whose size grows as ``f_c`` falls; filtering both sides removes it at any ``f_c``,
and the fit uses the band below ``f_c`` where the motion is. The filtered noise is coloured,
which :mod:`rc3r.identify.estimate` accounts for exactly (:func:`noise_gain`).

The default cut-off, velocity source, weighting and Coulomb smoothing are chosen by blocked
cross-validation on the training part (:mod:`rc3r.identify.selection`) among
:data:`CUTOFFS_HZ` that the log's rate allows (:func:`cutoff_candidates`).

Spectral edges (:func:`choose_cutoff`; recorded for reference, no longer the default)
    For every joint, the power spectra (Welch) of the resampled ``q`` and ``tau`` are
    estimated from their second differences, divided by ``|2 sin(pi f / f_s)|^4``
    (differencing keeps the window's leakage from the large low-frequency peak out of the
    floor). Each spectrum's floor ``N_0`` is its median over :data:`FLOOR_BAND` (a fraction
    of the sampling rate, far above any motion: encoder quantization and sensor noise). The
    joint's **motion edge** is the highest frequency below that band where its *torque*
    spectrum still exceeds both :data:`SIGNAL_OVER_FLOOR` ``x N_0`` and :data:`BELOW_PEAK`
    times its peak (40 dB down: the band that holds the motion's torque, not the weak tail
    of a friction kink or a vibration). The cut-off is :data:`EDGE_FACTOR` times the largest
    edge over the joints, clipped to :data:`CUTOFF_RANGE`. The positions' floor decides
    whether logged velocities are used (:func:`velocity_source`); their edges are recorded.

What it costs: a higher ``f_c`` lets more differentiated encoder noise into ``qdd`` (its share
grows as ``f_c^{5/2}``) and into the regressor, where it is an error in the variables (a
bias the covariance does not see); a lower one discards information (a larger covariance,
never a bias, since both sides are filtered alike) and needs longer edges.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError

__all__ = ["ORDER", "EDGE", "STATE_FACTOR", "PREDICT_FACTOR", "CUTOFFS_HZ", "cutoff_candidates", "Grids",
           "COARSE_FACTOR", "FLOOR_BAND", "SIGNAL_OVER_FLOOR", "BELOW_PEAK", "EDGE_FACTOR",
           "CUTOFF_RANGE", "uniform_grid", "resample", "lowpass", "spectrum_edges", "choose_cutoff",
           "velocity_source", "noise_gain", "effective_dof", "power_response", "residual_density", "Prepared", "prepare"]

#: Butterworth order (``sosfiltfilt`` doubles it).
ORDER = 4

#: Filter start-up excluded at each end: ``EDGE / f_c`` seconds.
EDGE = 3.0

#: The states are low-passed at this multiple of the cut-off (so ``L`` alone shapes the band).
STATE_FACTOR = 5.0

#: Predictions of unfiltered torques (validation, bands) use states low-passed at this multiple of the cut-off
#: (1: the cut-off itself, consistent with the fit; module docstring, step 5).
PREDICT_FACTOR = 1.0

#: Cut-offs [Hz] the cross-validation chooses among (those the log's rate allows: :func:`cutoff_candidates`).
CUTOFFS_HZ = (2.0, 3.0, 5.0, 7.0, 10.0, 15.0, 20.0)

#: The arm's regressor is evaluated at no less than this multiple of the states' cut-off.
COARSE_FACTOR = 10.0

#: Band of the noise floor, as fractions of the sampling rate (100-200 Hz at 1 kHz).
FLOOR_BAND = (0.1, 0.2)

#: A signal reaches up to where its spectrum falls to this multiple of the floor (10 dB).
SIGNAL_OVER_FLOOR = 10.0

#: The motion's band ends where the torque spectrum falls this far below its peak (40 dB).
BELOW_PEAK = 1e-4

#: Cut-off = this times the highest signal edge over the joints (1: both sides are filtered, no bias).
EDGE_FACTOR = 1.0

#: Range [Hz] the data-chosen cut-off is clipped to.
CUTOFF_RANGE = (2.0, 20.0)


def cutoff_candidates(fs: float, candidates=CUTOFFS_HZ) -> tuple:
    """The ``candidates`` [Hz] a log sampled at ``fs`` allows: states' cut-off ``STATE_FACTOR f_c < 0.45 fs``.

    A 1 kHz log allows all of :data:`CUTOFFS_HZ`, a 100 Hz log 2, 3, 5 and 7 Hz.
    """
    return tuple(float(f) for f in candidates if STATE_FACTOR * f < 0.45 * fs)


@dataclass(frozen=True, eq=False)
class Grids:
    """A log resampled once on its uniform grid (``t`` (G,), ``q``, ``qd`` or None, ``tau`` (G, n), ``fs``).

    :meth:`lowpass` remembers its results: the cross-validation prepares one log at many cut-offs
    and velocity sources, which share most of their filtered signals.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray | None
    tau: np.ndarray
    fs: float
    _memo: dict = field(default_factory=dict, repr=False)

    def lowpass(self, name: str, fc: float) -> np.ndarray:
        """:func:`lowpass` of the signal ``name`` (``"q"``, ``"qd"`` or ``"tau"``) at ``fc`` [Hz], remembered."""
        key = (name, float(fc))
        if key not in self._memo:
            self._memo[key] = lowpass(getattr(self, name), self.fs, fc)
        return self._memo[key]

    @classmethod
    def of(cls, log) -> "Grids":
        """Resample ``log`` (:func:`uniform_grid`, :func:`resample`)."""
        grid = uniform_grid(log.t)
        return cls(grid, resample(log.t, log.q, grid), None if log.qd is None else resample(log.t, log.qd, grid),
                   resample(log.t, log.tau, grid), 1.0 / (grid[1] - grid[0]))


def uniform_grid(t, rate: float | None = None) -> np.ndarray:
    """Uniform time grid from ``t[0]`` to at most ``t[-1]`` at ``rate`` [Hz] (default ``1 / median(diff t)``)."""
    t = np.asarray(t, dtype=float)
    dt = float(np.median(np.diff(t))) if rate is None else 1.0 / float(rate)
    return t[0] + dt * np.arange(int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1)


def resample(t, x, grid) -> np.ndarray:
    """``x`` (N, k) sampled at ``t`` evaluated on ``grid`` by a cubic interpolating spline (not-a-knot)."""
    from scipy.interpolate import make_interp_spline

    return make_interp_spline(np.asarray(t, float), np.asarray(x, float), k=3, axis=0)(grid)


def lowpass(x, fs: float, fc: float, order: int = ORDER) -> np.ndarray:
    """Zero-phase Butterworth low-pass of ``x`` (N, ...) along axis 0 (``sosfiltfilt``, odd padding)."""
    from scipy.signal import butter, sosfiltfilt

    if not 0 < fc < 0.5 * fs:
        raise ConfigError(f"filter cut-off {fc:g} Hz must be between 0 and half the sampling rate "
                          f"({0.5 * fs:g} Hz)")
    x = np.asarray(x, dtype=float)
    sos = butter(order, fc, fs=fs, output="sos")
    padlen = int(min(x.shape[0] - 1, np.ceil(3.0 * fs / fc)))
    return sosfiltfilt(sos, x, axis=0, padtype="odd", padlen=padlen)


def noise_gain(fs: float, fc: float, order: int = ORDER) -> float:
    """Variance of :func:`lowpass` of unit white noise at rate ``fs``: ``(2/fs) int_0^{fs/2} |L(f)|^2 df``."""
    top = min(0.5 * fs, 20.0 * fc)  # |L|^2 < 1e-20 beyond
    f = np.linspace(0.0, top, 20001)
    return float(2.0 / fs * np.trapezoid(power_response(f, fs, fc, order), f))


def effective_dof(rows: int, rate: float, fc: float) -> float:
    """Degrees of freedom of a variance estimated from ``rows`` samples at ``rate`` of white noise after :func:`lowpass`.

    Satterthwaite's ``nu = (tr R)^2 / tr(R^2) = N gamma_0^2 / sum_l gamma_l^2`` with ``gamma_l`` the
    filtered noise's autocovariance at the rows' spacing (from ``|L|^2`` by an inverse FFT); about
    ``2 x bandwidth x duration``, not ``N``: the rows are correlated.
    """
    M = 8 * int(rows)
    P = power_response(np.fft.rfftfreq(M, 1.0 / rate), rate, fc)
    gam = np.fft.irfft(P, n=M)
    return float(rows * gam[0] ** 2 / (gam[0] ** 2 + 2.0 * np.sum(gam[1:M // 2] ** 2)))


def power_response(f, fs: float, fc: float, order: int = ORDER) -> np.ndarray:
    """``|L(f)|^2`` of :func:`lowpass` (forwards and backwards: the Butterworth magnitude to the 4th power)."""
    from scipy.signal import butter, sosfreqz

    sos = butter(order, fc, fs=fs, output="sos")
    _, h = sosfreqz(sos, worN=np.asarray(f, dtype=float), fs=fs)
    return np.abs(h) ** 4


def residual_density(t, r, fc: float, fs: float):
    """``f -> |L(f)|^2 S(f)`` (len(f), n): the filtered spectrum of residuals ``r`` (N, n) at stamps ``t``.

    ``S`` is Welch's one-sided spectrum of ``r`` taken as uniformly sampled at its mean rate
    (segments of about 2 s, Hann window), linearly interpolated in frequency.
    """
    from scipy.signal import welch

    r = np.asarray(r, dtype=float)
    rate = (r.shape[0] - 1) / float(t[-1] - t[0])
    nper = int(min(r.shape[0], 2 ** int(np.ceil(np.log2(2.0 * rate)))))
    fw, S = welch(r, fs=rate, nperseg=nper, axis=0, detrend="constant")

    def density(f):
        f = np.asarray(f, dtype=float)
        S_f = np.column_stack([np.interp(f, fw, S[:, j]) for j in range(S.shape[1])])
        return S_f * power_response(f, fs, fc)[:, None]

    return density


def _spectrum(x, fs: float):
    """Welch spectrum of ``x`` (N, k) from its second difference, re-scaled to ``x``'s: (f, S)."""
    from scipy.signal import welch

    d2 = np.diff(np.asarray(x, dtype=float), n=2, axis=0)
    nper = int(min(d2.shape[0], 2 ** int(np.ceil(np.log2(2.0 * fs)))))
    f, S = welch(d2, fs=fs, nperseg=nper, axis=0, detrend="constant")
    keep = f > 0
    return f[keep], S[keep] / np.abs(2.0 * np.sin(np.pi * f[keep] / fs))[:, None] ** 4


def spectrum_edges(x, fs: float, below_peak: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Per column of ``x`` (N, k) on a grid at ``fs``: (signal edge [Hz], floor) (module docstring).

    The edge is the highest frequency below :data:`FLOOR_BAND` where the spectrum exceeds
    :data:`SIGNAL_OVER_FLOOR` times the floor and ``below_peak`` times its peak.
    """
    f, S = _spectrum(x, fs)
    lo, hi = FLOOR_BAND[0] * fs, FLOOR_BAND[1] * fs
    band = (f >= lo) & (f <= hi)
    if band.sum() < 3:
        raise ConfigError(f"log too short to choose a filter from its spectrum (rate {fs:g} Hz); give --filter HZ")
    floor = np.median(S[band], axis=0)
    edges = np.empty(S.shape[1])
    for j in range(S.shape[1]):
        level = max(SIGNAL_OVER_FLOOR * floor[j], below_peak * S[f < lo, j].max(), 1e-300)
        above = np.nonzero((S[:, j] > level) & (f < lo))[0]
        edges[j] = f[above[-1]] if above.size else f[0]
    return edges, floor


def choose_cutoff(q_grid, tau_grid, fs: float) -> dict:
    """The cut-off [Hz] chosen from the spectra of the resampled torques (and positions) (module docstring).

    Returns
    -------
    dict
        ``cutoff_hz``, per joint ``torque_edge_hz``, ``position_edge_hz`` (10 x floor only),
        ``position_floor``, ``torque_floor`` (spectral densities [unit^2/Hz]), ``unclipped_hz``,
        ``clipped``, ``method`` (one sentence).
    """
    eq, fq = spectrum_edges(q_grid, fs)
    et, ft = spectrum_edges(tau_grid, fs, BELOW_PEAK)
    raw = EDGE_FACTOR * float(et.max())
    fc = min(float(np.clip(raw, *CUTOFF_RANGE)), 0.45 * fs / STATE_FACTOR)
    lo, hi = FLOOR_BAND[0] * fs, FLOOR_BAND[1] * fs
    return {"cutoff_hz": fc, "torque_edge_hz": et.tolist(), "position_edge_hz": eq.tolist(),
            "position_floor": fq.tolist(), "torque_floor": ft.tolist(), "unclipped_hz": raw, "clipped": bool(fc != raw),
            "method": (f"{EDGE_FACTOR:g} x the highest frequency (over the joints) where the Welch spectrum of the "
                       f"torque exceeds {SIGNAL_OVER_FLOOR:g} x its floor (median over {lo:.4g}-{hi:.4g} Hz) and "
                       f"{BELOW_PEAK:g} x its peak, clipped to {CUTOFF_RANGE[0]:g}-{CUTOFF_RANGE[1]:g} Hz")}


def velocity_source(q_floor, qd_floor, state_cutoff: float) -> str:
    """``"logged"`` if the logged velocities' noise floor is below that of differentiated positions.

    ``q_floor`` and ``qd_floor`` (n,) are the white-noise densities of ``q`` and of the logged
    ``qd``; differentiating multiplies ``q``'s by ``(2 pi f)^2``, compared at the states' cut-off.
    """
    diff = (2.0 * np.pi * state_cutoff) ** 2 * np.asarray(q_floor, dtype=float)
    return "logged" if np.all(np.asarray(qd_floor, dtype=float) <= diff) else "differentiated"


@dataclass(frozen=True, eq=False)
class Prepared:
    """A log resampled and filtered for the fit (module docstring).

    Attributes
    ----------
    t : ndarray (K,)
        Times of the coarse grid [s].
    q, qd, qdd : ndarray (K, n)
        States filtered at ``state_cutoff_hz``, on the coarse grid.
    tau : ndarray (K, n)
        ``L[tau]`` on the coarse grid.
    friction_qd : ndarray (G, n)
        Velocities on the full grid (for the friction columns).
    predict : tuple of three ndarray (K, n)
        ``q, qd, qdd`` low-passed at ``PREDICT_FACTOR x cutoff_hz`` (the cut-off), for predictions.
    usable : ndarray of bool (K,)
        Outside the filters' start-up.
    fs, fs_coarse : float
        Rates of the full and coarse grids [Hz]; ``step`` = their ratio (an int).
    cutoff_hz, state_cutoff_hz : float
    velocities : str
        ``"logged"`` or ``"differentiated"``.
    tau_raw : ndarray (K, n)
        The unfiltered torques (resampled) on the coarse grid (cross-validation scores).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    friction_qd: np.ndarray
    predict: tuple
    usable: np.ndarray
    fs: float
    fs_coarse: float
    step: int
    cutoff_hz: float
    state_cutoff_hz: float
    velocities: str
    tau_raw: np.ndarray | None = None

    def filter_coarse(self, X) -> np.ndarray:
        """``L`` applied to columns ``X`` (K, ...) on the coarse grid."""
        X = np.asarray(X, dtype=float)
        return lowpass(X.reshape(X.shape[0], -1), self.fs_coarse, self.cutoff_hz).reshape(X.shape)

    def filter_full(self, X) -> np.ndarray:
        """``L`` applied to columns ``X`` (G, ...) on the full grid, then sampled on the coarse grid."""
        X = np.asarray(X, dtype=float)
        return lowpass(X.reshape(X.shape[0], -1), self.fs, self.cutoff_hz)[::self.step].reshape(
            (-1,) + X.shape[1:])

    @property
    def noise_gain(self) -> float:
        """Variance of ``L`` of unit white noise at the full rate (:func:`noise_gain`)."""
        return noise_gain(self.fs, self.cutoff_hz)


def prepare(log, cutoff_hz: float, velocities: str = "auto", floors: dict | None = None,
            grids: Grids | None = None, coarse_factor: float = COARSE_FACTOR) -> Prepared:
    """Resample and filter ``log`` for the fit at cut-off ``cutoff_hz`` (module docstring, steps 1-5).

    ``velocities``: ``"auto"`` (:func:`velocity_source` from ``floors`` = ``{"q": ..., "qd": ...}``,
    else differentiated), ``"logged"`` or ``"differentiated"``. ``grids``: ``Grids.of(log)`` when
    already computed (the cross-validation prepares one log many times). ``coarse_factor``: the
    coarse grid's rate is at least this multiple of the states' cut-off (:data:`COARSE_FACTOR`).
    """
    g = Grids.of(log) if grids is None else grids
    grid, fs = g.t, g.fs
    fsc = STATE_FACTOR * cutoff_hz
    if not fsc < 0.45 * fs:
        raise ConfigError(f"filter cut-off {cutoff_hz:g} Hz is too high for a log sampled at {fs:.4g} Hz "
                          f"(at most {0.45 * fs / STATE_FACTOR:.4g} Hz)")
    if velocities == "auto":
        velocities = ("differentiated" if log.qd is None or not floors
                      else velocity_source(floors["q"], floors["qd"], fsc))
    if velocities == "logged" and log.qd is None:
        raise ConfigError(f"log {log.source} has no velocities (qd1..qdn) to use")
    dt = 1.0 / fs
    qf = g.lowpass("q", fsc)
    qdf = g.lowpass("qd", fsc) if velocities == "logged" else np.gradient(qf, dt, axis=0)
    qddf = np.gradient(qdf, dt, axis=0)
    step = max(1, int(np.floor(fs / (coarse_factor * fsc))))
    fp = PREDICT_FACTOR * cutoff_hz
    qp = g.lowpass("q", fp)
    qdp = g.lowpass("qd", fp) if velocities == "logged" else np.gradient(qp, dt, axis=0)
    predict = (qp[::step], qdp[::step], np.gradient(qdp, dt, axis=0)[::step])
    tau_f = g.lowpass("tau", cutoff_hz)
    tc = grid[::step]
    edge = EDGE / cutoff_hz
    usable = (tc >= grid[0] + edge) & (tc <= grid[-1] - edge)
    if not usable.any():
        raise ConfigError(f"log {log.source} lasts {grid[-1] - grid[0]:.3g} s: too short for a filter at "
                          f"{cutoff_hz:g} Hz, whose start-up takes {edge:.3g} s at each end")
    return Prepared(tc, qf[::step], qdf[::step], qddf[::step], tau_f[::step], qdf, predict, usable, fs, fs / step, step,
                    float(cutoff_hz), float(fsc), velocities, g.tau[::step])
