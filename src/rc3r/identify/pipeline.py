r"""The identification pipeline: from a log to theta, friction, covariance, validation and bounds.

:func:`identify` runs, in order:

1. the cut-off: given, or chosen from the log's spectra (:func:`rc3r.identify.filtering.choose_cutoff`),
   and the velocity source (logged or differentiated, :func:`~rc3r.identify.filtering.velocity_source`);
2. resampling and parallel filtering (:func:`~rc3r.identify.filtering.prepare`), the regressor
   ``[Y | friction]`` (:mod:`rc3r.identify.regressors`) low-passed like the torques;
3. the split: the first ``1 - F`` of the log's duration trains, the last ``F`` is held out (the
   filters run over the whole log once; their start-up at both ends is unused);
4. the excitation check, weighted least squares with per-joint noise and the covariance
   (:mod:`rc3r.identify.estimate`), the confidence ellipsoid of theta and the ball and box
   containing it;
5. held-out validation at the logged time stamps: RMS of ``tau - Phi x`` per joint against the
   logged torques (``rms``) and of ``L[tau] - L[Phi] x`` against the low-passed ones
   (``rms_filtered``), the fraction of logged torques inside the prediction band at the
   confidence level, and the RMS of the robot's own (URDF) coefficients without friction
   (``rms_nominal``) for comparison;
6. physical consistency (:mod:`rc3r.identify.consistency`), if asked.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ConfigError
from . import estimate as _est
from . import filtering as _flt
from .regressors import FRICTION_KINDS, friction_names

__all__ = ["Identification", "identify", "MAX_RAW_STAMPS"]

#: At most this many training time stamps (evenly spread) estimate the raw residual's noise.
MAX_RAW_STAMPS = 20000


@dataclass(frozen=True, eq=False)
class Identification:
    """The result of :func:`identify` (``to_dict`` is ``identified.json`` without provenance)."""

    robot: dict
    coefficient_names: tuple
    friction_kinds: tuple
    x: np.ndarray
    cov: np.ndarray
    p: int
    sigma: np.ndarray
    sigma_raw: np.ndarray
    ellipsoid: dict
    filter: dict
    validation: dict
    regressor: dict
    log: dict
    consistency: dict | None
    held_out: dict = field(repr=False)

    @property
    def theta(self) -> np.ndarray:
        """The dynamic coefficients (p,)."""
        return self.x[:self.p]

    @property
    def cov_theta(self) -> np.ndarray:
        """Their covariance (p, p)."""
        return self.cov[:self.p, :self.p]

    def friction(self) -> dict:
        """``{kind: (n,) coefficients}`` for the identified friction kinds."""
        n = self.sigma.size
        return {k: self.x[self.p + i * n: self.p + (i + 1) * n] for i, k in enumerate(self.friction_kinds)}

    def bounds(self) -> dict:
        """``theta0, rho, rho_i, P, confidence, chi2`` of the confidence ellipsoid."""
        return {"theta0": self.theta, **self.ellipsoid}

    def to_dict(self) -> dict:
        """JSON-ready: every field of ``identified.json`` except provenance."""
        names = tuple(self.coefficient_names) + friction_names(self.friction_kinds, self.sigma.size)
        se = np.sqrt(np.diag(self.cov))
        ell = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.ellipsoid.items() if k != "P"}
        return {
            "robot": self.robot,
            "theta": self.theta.tolist(),
            "theta_std": se[:self.p].tolist(),
            "coefficient_names": list(self.coefficient_names),
            "friction": {k: v.tolist() for k, v in self.friction().items()},
            "friction_std": {k: se[self.p + i * self.sigma.size: self.p + (i + 1) * self.sigma.size].tolist()
                             for i, k in enumerate(self.friction_kinds)},
            "unknowns": list(names),
            "covariance": self.cov.tolist(),
            "noise": {"sigma": self.sigma.tolist(), "sigma_raw": self.sigma_raw.tolist(),
                      "meaning": "sigma: white torque noise per logged sample [N m] estimated from the filtered "
                                 "residuals (sets the covariance); sigma_raw: RMS of the unfiltered training "
                                 "residual (sets the prediction band)"},
            "ellipsoid": ell,
            "filter": self.filter,
            "validation": self.validation,
            "regressor": self.regressor,
            "log": self.log,
            "consistency": self.consistency,
        }


def _raw_rows(robot, prep, t, kinds, predict: bool = False) -> np.ndarray:
    """Unfiltered regressor ``[Y | friction]`` (N, n, m) at stamps ``t`` from the fit's (or prediction) states."""
    from .regressors import identification_regressor

    states = prep.predict if predict else (prep.q, prep.qd, prep.qdd)
    at = [np.column_stack([np.interp(t, prep.t, X[:, j]) for j in range(X.shape[1])]) for X in states]
    return identification_regressor(robot, *at, kinds)


def _filtered_rows(robot, prep, kinds) -> np.ndarray:
    """``L[Y | friction]`` (K, n, m) on the coarse grid (friction filtered at the full rate)."""
    Y = np.asarray(robot.regressor(prep.q, prep.qd, prep.qd, prep.qdd), dtype=float)
    LY = prep.filter_coarse(Y)
    n = prep.q.shape[1]
    qd = prep.friction_qd
    cols = {"viscous": qd, "coulomb": np.sign(qd), "offset": np.ones_like(qd)}
    LF = np.zeros((LY.shape[0], n, n * len(kinds)))
    idx = np.arange(n)
    for k, kind in enumerate(kinds):
        LF[:, idx, k * n + idx] = prep.filter_full(cols[kind])[:LY.shape[0]]
    return np.concatenate([LY, LF], axis=2)


def identify(robot, log, friction=("viscous", "coulomb", "offset"), cutoff_hz: float | None = None,
             test_fraction: float = 0.2, confidence: float = 0.95, velocities: str = "auto",
             consistency: bool = True, covariance: str = "white", seed: int = 0) -> Identification:
    """Identify ``robot``'s coefficients, friction and their covariance from ``log`` (module docstring).

    Parameters
    ----------
    robot : Robot
        The arm's kinematics (and its nominal coefficients, for ``rms_nominal``).
    log : rc3r.identify.log.Log
        With ``log.n == robot.n``.
    friction : sequence of str
        Kinds of :data:`~rc3r.identify.regressors.FRICTION_KINDS`.
    cutoff_hz : float, optional
        The parallel filter's cut-off; default chosen from the data.
    test_fraction : float
        Held-out fraction F of the log's duration, ``0 < F < 1``.
    confidence : float
        Level of the ellipsoid and of the prediction band.
    velocities : str
        ``"auto"``, ``"logged"`` or ``"differentiated"``.
    consistency : bool
        Run the physical-consistency SDP (needs cvxpy).
    covariance : str
        ``"white"``: from the in-band residual level (:func:`~rc3r.identify.estimate.weighted_least_squares`);
        ``"robust"``: the smallest covariance that dominates it and the spectral (Whittle) one
        (:func:`~rc3r.identify.estimate.dominating`), for logs with coloured low-frequency residuals.
    seed : int
        Seed of the random states of the consistency check's standard-parameter map.
    """
    kinds = tuple(k for k in FRICTION_KINDS if k in tuple(friction))
    if log.n != robot.n:
        raise ConfigError(f"log has {log.n} joints, robot '{robot.label}' has {robot.n}")
    if not 0.0 < test_fraction < 1.0:
        raise ConfigError(f"test fraction must be between 0 and 1 (exclusive), got {test_fraction}")
    if not 0.0 < confidence < 1.0:
        raise ConfigError(f"confidence must be between 0 and 1 (exclusive), got {confidence}")
    grid = _flt.uniform_grid(log.t)
    fs = 1.0 / (grid[1] - grid[0])
    if grid.size < 4 * 3.0 * fs / _flt.CUTOFF_RANGE[1]:
        raise ConfigError(f"log {log.source} lasts {grid[-1] - grid[0]:.3g} s: too short to identify from")
    q_grid = _flt.resample(log.t, log.q, grid)
    choice = _flt.choose_cutoff(q_grid, _flt.resample(log.t, log.tau, grid), fs)
    floors = {"q": choice["position_floor"]}
    if log.qd is not None:
        floors["qd"] = _flt.spectrum_edges(_flt.resample(log.t, log.qd, grid), fs)[1].tolist()
    if cutoff_hz is None:
        fc, chosen = choice["cutoff_hz"], "from the data"
    else:
        fc, chosen = float(cutoff_hz), "given (--filter)"
    prep = _flt.prepare(log, fc, velocities, floors)
    A = _filtered_rows(robot, prep, kinds)
    t0, t1 = float(log.t[0]), float(log.t[-1])
    t_split = t0 + (1.0 - test_fraction) * (t1 - t0)
    train = prep.usable & (prep.t <= t_split)
    test = prep.usable & (prep.t > t_split)
    if not test.any():
        raise ConfigError(f"no held-out samples: the last {test_fraction:g} of the log lies in the filter's "
                          f"start-up ({_flt.EDGE / fc:.3g} s); give a longer log or a larger --test-fraction")
    names = tuple(robot.coefficient_names) + friction_names(kinds, robot.n)
    _est.check_excitation(A[train], names, prep.q[train])
    fit = _est.weighted_least_squares(A[train], prep.tau[train], gain=prep.noise_gain, step=prep.step)
    # the unfiltered residual at the training stamps (evenly thinned): its spectrum sets the covariance
    edge = _flt.EDGE / fc
    ok = (log.t >= t0 + edge) & (log.t <= grid[-1] - edge)
    tr_idx = np.nonzero(ok & (log.t <= t_split))[0]
    tr_idx = tr_idx[np.unique(np.linspace(0, tr_idx.size - 1, min(tr_idx.size, MAX_RAW_STAMPS)).astype(int))]
    raw_res = log.tau[tr_idx] - _raw_rows(robot, prep, log.t[tr_idx], kinds) @ fit.x
    sigma_raw = np.sqrt(np.mean((log.tau[tr_idx] - _raw_rows(robot, prep, log.t[tr_idx], kinds, True) @ fit.x) ** 2,
                                axis=0))
    density = _flt.residual_density(log.t[tr_idx], raw_res, fc, prep.fs)
    parts = {"white": fit.cov, "spectral": _est.spectral_covariance(A[train], fit.weights, prep.fs_coarse, density)}
    if covariance == "robust":
        fit = replace(fit, cov=_est.dominating(parts["white"], parts["spectral"]))
    elif covariance != "white":
        raise ConfigError(f"covariance must be 'white' or 'robust', got {covariance!r}")
    p = robot.p
    nu = robot.n * _flt.effective_dof(int(fit.rows), prep.fs_coarse, fc) - len(names)
    ell = _est.ellipsoid(fit.cov[:p, :p], confidence, dof=max(nu, 1.5))
    te_idx = np.nonzero(ok & (log.t > t_split))[0]
    if te_idx.size == 0:
        raise ConfigError("no held-out time stamps outside the filter's start-up; give a longer log")
    R_te = _raw_rows(robot, prep, log.t[te_idx], kinds, True)
    pred = R_te @ fit.x
    tau_te = log.tau[te_idx]
    half = fit.band(R_te, sigma_raw, confidence)
    inside = np.abs(tau_te - pred) <= half
    nominal = R_te[:, :, :p] @ np.asarray(robot.theta, dtype=float)
    validation = {
        "test_fraction": float(test_fraction), "split_time_s": t_split, "samples": int(te_idx.size),
        "rms": np.sqrt(np.mean((tau_te - pred) ** 2, axis=0)).tolist(),
        "rms_filtered": np.sqrt(np.mean((prep.tau[test] - A[test] @ fit.x) ** 2, axis=0)).tolist(),
        "rms_nominal": np.sqrt(np.mean((tau_te - nominal) ** 2, axis=0)).tolist(),
        "inside_band": float(inside.mean()), "inside_band_per_joint": inside.mean(axis=0).tolist(),
        "band_confidence": float(confidence),
        "meaning": "rms: held-out logged torques minus the model at the filtered states [N m]; rms_filtered: "
                   "the same after the parallel low-pass; rms_nominal: the robot's own coefficients, no "
                   "friction; inside_band: fraction of held-out logged torques within the prediction band",
    }
    filt = {"cutoff_hz": fc, "chosen": chosen, "order": _flt.ORDER, "kind": "Butterworth, zero phase (sosfiltfilt)",
            "state_cutoff_hz": prep.state_cutoff_hz, "edge_s": edge, "rate_hz": fs, "coarse_rate_hz": prep.fs_coarse,
            "velocities": prep.velocities, "data_choice": choice}
    lam = np.linalg.eigvals(np.linalg.solve(parts["white"], parts["spectral"])).real
    reg = {"rows": int(fit.rows), "unknowns": len(names), "condition_number": fit.cond,
           "covariance": {"method": covariance, "spectral_over_white": [float(lam.min()), float(lam.max())],
                          "meaning": "range of the generalized eigenvalues of the spectral (Whittle) covariance "
                                     "against the white one"}}
    cons = None
    if consistency:
        from .consistency import check_consistency

        cons = check_consistency(robot, fit.x[:p], fit.cov[:p, :p], ell["chi2"], seed=seed)
    held = {"t": log.t[te_idx], "tau": tau_te, "pred": pred, "band": half, "covariances": parts}
    return Identification(robot.describe() | {"coefficient_names": list(robot.coefficient_names)},
                          tuple(robot.coefficient_names), kinds, fit.x, fit.cov, p, fit.sigma, sigma_raw, ell,
                          filt, validation, reg, log.describe(), cons, held)
