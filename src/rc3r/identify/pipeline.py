r"""The identification pipeline: from a log to theta, friction, covariance, validation and bounds.

:func:`identify` runs, in order:

1. the split: the first ``1 - F`` of the log's duration trains, the last ``F`` is held out (the
   filters run over the whole log once; their start-up at both ends is unused);
2. the settings: cut-off, velocity source (logged or differentiated), weighting (ordinary or
   per-joint noise), Coulomb smoothing velocity and rotor inertias (armature), each given or chosen by blocked
   cross-validation on the training part only (:func:`rc3r.identify.selection.select`; the
   scores behind the choice are kept in ``selection``);
3. resampling and parallel filtering (:func:`~rc3r.identify.filtering.prepare`), the regressor
   ``[Y | friction]`` (:mod:`rc3r.identify.regressors`) low-passed like the torques;
4. the excitation check, the least squares and the covariance (:mod:`rc3r.identify.estimate`),
   the confidence ellipsoid of theta and the ball and box containing it;
5. held-out validation at the logged time stamps: the model evaluated at the states low-passed at
   the cut-off (``q`` and logged ``qd`` zero-phase at ``f_c``, derivatives by central
   differences: consistent with the fit), RMS of ``tau - Phi x`` per joint against the torques
   **as logged** (``rms``), and of ``L[tau] - L[Phi] x`` against the low-passed ones
   (``rms_filtered``), the fraction of logged torques inside the prediction band at the
   confidence level, and the RMS of the robot's own (URDF) coefficients without friction
   (``rms_nominal``) for comparison;
6. the **physically consistent estimate** (:mod:`rc3r.identify.physical`, default): least squares
   in the log-Cholesky chart of every link's pseudo-inertia, pulled toward the URDF's inertias by
   the log-det divergence, its Laplace covariance and ellipsoid (what ``bounds.toml`` carries), and
   its held-out validation like the unconstrained estimate's;
7. the consistency SDP of the unconstrained estimate (:mod:`rc3r.identify.consistency`, cvxpy), if asked.

Evaluating another coefficient vector exactly like the fit's: :meth:`Identification.held_out_rms`
(``x`` of the same unknowns, e.g. the physically consistent estimate) uses the stored held-out
regressor ``held_out["rows"]`` (N, n, m: the rows of step 5 at the held-out logged stamps) and
the logged torques ``held_out["tau"]`` (N, n); ``held_out_rms(res.x) == validation["rms"]``.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ConfigError
from . import estimate as _est
from . import filtering as _flt
from . import selection as _sel
from .regressors import ARMATURE_CHOICES, COULOMB_LAW, FRICTION_KINDS, friction_names, kept_columns, merged_columns

__all__ = ["Identification", "identify", "MAX_RAW_STAMPS", "COVARIANCES"]

#: The covariance models of :func:`identify` (the first is the default).
COVARIANCES = ("in-band", "white", "robust")

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
    selection: dict | None = None
    friction_law: dict = field(default_factory=dict)
    physical: dict | None = None
    physical_fit: object = field(default=None, repr=False)
    columns: tuple | None = None
    armature: dict | None = None
    confidence: float = 0.95
    dof: float | None = None

    @property
    def joint_columns(self) -> np.ndarray:
        """Indices (m - p,) of the fitted joint columns among the ``n len(friction_kinds)`` of
        :func:`~rc3r.identify.regressors.joint_columns` (all of them unless an armature column merged)."""
        n = self.sigma.size
        return np.arange(n * len(self.friction_kinds)) if self.columns is None else np.asarray(self.columns, int)

    def _full(self, v, fill: float = 0.0) -> np.ndarray:
        """The fitted joint coefficients (m - p,) spread over all ``n len(friction_kinds)`` (``fill`` elsewhere)."""
        out = np.full(self.sigma.size * len(self.friction_kinds), fill)
        out[self.joint_columns] = v
        return out

    def held_out_rms(self, x=None) -> np.ndarray:
        """Held-out RMS per joint (n,) [N m] of coefficients ``x`` (m,) against the logged torques.

        Evaluated exactly as ``validation["rms"]`` (module docstring, step 5) from the stored
        ``held_out["rows"]`` and ``held_out["tau"]``; ``x`` defaults to the fit's.
        """
        x = self.x if x is None else np.asarray(x, dtype=float)
        if x.shape != self.x.shape:
            raise ConfigError(f"x has shape {x.shape}, the identification's unknowns {self.x.shape}")
        r = self.held_out["tau"] - self.held_out["rows"] @ x
        return np.sqrt(np.mean(r ** 2, axis=0))

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
        full = self._full(self.x[self.p:])
        return {k: full[i * n:(i + 1) * n] for i, k in enumerate(self.friction_kinds)}

    def bounds(self, which: str = "auto") -> dict:
        """``theta0, rho, rho_i, P, confidence, chi2`` of the confidence ellipsoid (and ``physical``).

        ``which``: ``"physical"`` the consistent estimate's (centre ``T pi*``, Laplace covariance; its
        link parameters in ``physical``: ``standard_parameters``, ``log_cholesky``, ``log_cholesky_cov``),
        ``"unconstrained"`` the least-squares estimate's, ``"auto"`` the first when it was fitted.
        """
        if which == "unconstrained" or (which == "auto" and self.physical_fit is None):
            return {"theta0": self.theta, **self.ellipsoid, "actuator": self.actuator_bounds(self.x)}
        if self.physical_fit is None:
            raise ConfigError("no physically consistent fit (identify(..., physical=False))")
        f = self.physical_fit
        ph = self.physical
        return {"theta0": f.theta, **ph["_ellipsoid"], "actuator": self.actuator_bounds(f.x),
                "physical": {"standard_parameters": f.standard, "log_cholesky": f.eta,
                             "log_cholesky_cov": f.cov_eta, "gamma": f.gamma,
                             "draws_inside": ph["draws_inside"]["share"],
                             "masses": f.masses}}

    def actuator_bounds(self, x) -> dict:
        """The ellipsoid over the rigid **and** joint coefficients about ``x`` (m,) (``rc3r-bounds/2``).

        Shaped by the fit's covariance over all m unknowns at the fit's confidence (quantile over m
        dimensions), then spread over every joint column of ``friction_kinds``: a merged armature column
        (not fitted) has centre 0 and, for a full-rank ellipsoid, an independent half-width equal to the
        ``rho_i`` of the rigid coefficient it merged with (a slice through the ellipsoid at 0 is the fitted
        one: the true coefficients, written with their rotor inertia in that rigid coefficient, are inside it
        exactly when they were). Returns ``kinds``, ``coulomb_velocity``, ``rigid_p``, ``coefficient_names``,
        ``theta0`` (p + m_all,), ``P``, ``rho``, ``rho_i``, ``quantile``, ``merged`` (names).
        """
        p, n = self.p, self.sigma.size
        ell = _est.ellipsoid(self.cov, self.confidence, dof=self.dof)
        all_names = friction_names(self.friction_kinds, n)
        names_c = list(self.coefficient_names) + [all_names[c] for c in self.joint_columns]
        merged = dict((self.armature or {}).get("merged") or {}) if "armature" in self.friction_kinds else {}
        a0 = p + self.friction_kinds.index("armature") * n if merged else 0
        pairs = {a0 + int(name[2:]) - 1: names_c.index(rigid) for name, rigid in merged.items()}
        full = _est.spread_ellipsoid(ell["P"], np.concatenate([np.arange(p), p + self.joint_columns]),
                                     p + n * len(self.friction_kinds), pairs)
        x = np.asarray(x, dtype=float)
        return {"kinds": list(self.friction_kinds),
                "coulomb_velocity": float(self.friction_law.get("coulomb_velocity", 0.0)),
                "rigid_p": int(p), "coefficient_names": list(self.coefficient_names) + list(all_names),
                "theta0": np.concatenate([x[:p], self._full(x[p:])]), **full, "quantile": float(ell["chi2"]),
                "merged": merged}

    def to_dict(self) -> dict:
        """JSON-ready: every field of ``identified.json`` except provenance."""
        all_names = friction_names(self.friction_kinds, self.sigma.size)
        names = tuple(self.coefficient_names) + tuple(all_names[c] for c in self.joint_columns)
        se = np.sqrt(np.diag(self.cov))
        se_j = self._full(se[self.p:], np.nan)
        n = self.sigma.size
        ell = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.ellipsoid.items() if k != "P"}
        return {
            "robot": self.robot,
            "theta": self.theta.tolist(),
            "theta_std": se[:self.p].tolist(),
            "coefficient_names": list(self.coefficient_names),
            "friction": {k: v.tolist() for k, v in self.friction().items()},
            "friction_std": {k: [None if not np.isfinite(v) else float(v) for v in se_j[i * n:(i + 1) * n]]
                             for i, k in enumerate(self.friction_kinds)},
            "armature": self.armature,
            "unknowns": list(names),
            "covariance": self.cov.tolist(),
            "noise": {"sigma": self.sigma.tolist(), "sigma_raw": self.sigma_raw.tolist(),
                      "meaning": "sigma: white torque noise per logged sample [N m] estimated from the filtered "
                                 "residuals over the pass band (sets the white covariance and the consistent fit's "
                                 "metric; the default in-band covariance uses regressor.covariance.in_band_sigma); "
                                 "sigma_raw: RMS of the unfiltered training "
                                 "residual (sets the prediction band)"},
            "ellipsoid": ell,
            "filter": self.filter,
            "validation": self.validation,
            "regressor": self.regressor,
            "log": self.log,
            "consistency": self.consistency,
            "friction_law": self.friction_law,
            "selection": self.selection,
            "physical": None if self.physical is None else
            {k: v for k, v in self.physical.items() if not k.startswith("_")},
        }


def _raw_rows(robot, prep, t, kinds, predict: bool = False, v_s: float = 0.0, columns=None) -> np.ndarray:
    """Unfiltered regressor ``[Y | joint columns]`` (N, n, m) at stamps ``t`` from the fit's (or prediction) states."""
    from .regressors import identification_regressor

    states = prep.predict if predict else (prep.q, prep.qd, prep.qdd)
    at = [np.column_stack([np.interp(t, prep.t, X[:, j]) for j in range(X.shape[1])]) for X in states]
    return identification_regressor(robot, *at, kinds, v_s, columns)


def _filtered_rows(robot, prep, kinds, v_s: float = 0.0, columns=None) -> np.ndarray:
    """``L[Y | joint columns]`` (K, n, m) on the coarse grid (:func:`rc3r.identify.selection.filtered_rows`)."""
    return _sel.filtered_rows(robot, prep, kinds, v_s, columns=columns)


def identify(robot, log, friction=("viscous", "coulomb", "offset"), cutoff_hz: float | None = None,
             test_fraction: float = 0.2, confidence: float = 0.95, velocities: str = "auto",
             consistency: bool = True, covariance: str = "in-band", seed: int = 0, weighting: str = "auto",
             coulomb_velocity: float | None = None, folds: int = _sel.FOLDS,
             physical: bool = True, armature: str = "auto", slow_share: float | None = None) -> Identification:
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
        The parallel filter's cut-off; default chosen by cross-validation among
        :func:`~rc3r.identify.filtering.cutoff_candidates`.
    test_fraction : float
        Held-out fraction F of the log's duration, ``0 < F < 1``.
    confidence : float
        Level of the ellipsoid and of the prediction band.
    velocities : str
        ``"auto"`` (cross-validated between logged and differentiated when ``qd`` is logged,
        else differentiated), ``"logged"`` or ``"differentiated"``.
    consistency : bool
        Run the physical-consistency SDP (needs cvxpy).
    covariance : str
        ``"in-band"`` (default): the sandwich with each joint's noise level measured, corrected for what
        the fit absorbed, over the band that holds the estimate's information
        (:func:`~rc3r.identify.estimate.in_band_covariance`; F quantile with that band's degrees of freedom);
        ``"white"``: from the whole pass band's residual level (:func:`~rc3r.identify.estimate.weighted_least_squares`);
        ``"robust"``: the smallest covariance that dominates it and the spectral (Whittle) one
        (:func:`~rc3r.identify.estimate.dominating`), for logs with coloured low-frequency residuals.
    seed : int
        Seed of the random states of the standard-parameter map (robots without Pinocchio base
        parameters) and of the draws that measure the physical ellipsoid's share of physical draws.
    weighting : str
        ``"auto"`` (cross-validated), ``"ordinary"`` or ``"per-joint"``.
    coulomb_velocity : float, optional
        The Coulomb smoothing velocity ``v_s`` [rad/s] (0: ``sign``); default cross-validated among
        :data:`~rc3r.identify.selection.COULOMB_VELOCITIES`.
    folds : int
        Blocks of the cross-validation.
    armature : str
        A rotor inertia per joint (the column ``qdd_j``): ``"auto"`` (cross-validated), ``"on"``, ``"off"``;
        a joint whose column the rigid regressor already holds is merged, not fitted
        (:func:`~rc3r.identify.regressors.merged_columns`).
    physical : bool
        Fit the physically consistent estimate (:func:`rc3r.identify.physical.fit_physical`; SciPy only).
    slow_share : float, optional
        A joint's rows slower than this x its RMS speed (reversals, rests: :func:`~rc3r.identify.estimate.slow_rows`)
        are left out of the fit; 0 keeps every row; default: chosen among
        :data:`~rc3r.identify.selection.SLOW_SHARES` at the chosen settings (:func:`~rc3r.identify.selection.select`).
    """
    kinds = tuple(k for k in FRICTION_KINDS if k in tuple(friction))
    if armature not in ARMATURE_CHOICES:
        raise ConfigError(f"armature must be {', '.join(ARMATURE_CHOICES)}, got {armature!r}")
    if log.n != robot.n:
        raise ConfigError(f"log has {log.n} joints, robot '{robot.label}' has {robot.n}")
    if not 0.0 < test_fraction < 1.0:
        raise ConfigError(f"test fraction must be between 0 and 1 (exclusive), got {test_fraction}")
    if not 0.0 < confidence < 1.0:
        raise ConfigError(f"confidence must be between 0 and 1 (exclusive), got {confidence}")
    if covariance not in COVARIANCES:
        raise ConfigError(f"covariance must be one of {', '.join(COVARIANCES)}, got {covariance!r}")
    if weighting != "auto" and weighting not in _est.WEIGHTINGS:
        raise ConfigError(f"weighting must be auto, {', '.join(_est.WEIGHTINGS)}, got {weighting!r}")
    if velocities not in ("auto", "logged", "differentiated"):
        raise ConfigError(f"velocities must be auto, logged or differentiated, got {velocities!r}")
    if velocities == "logged" and log.qd is None:
        raise ConfigError(f"log {log.source} has no velocities (qd1..qdn) to use")
    if coulomb_velocity is not None and not coulomb_velocity >= 0:
        raise ConfigError(f"Coulomb smoothing velocity must be >= 0, got {coulomb_velocity:g}")
    grids = _flt.Grids.of(log)
    grid, fs = grids.t, grids.fs
    if grid.size < 4 * 3.0 * fs / _flt.CUTOFF_RANGE[1]:
        raise ConfigError(f"log {log.source} lasts {grid[-1] - grid[0]:.3g} s: too short to identify from")
    t0, t1 = float(log.t[0]), float(log.t[-1])
    t_split = t0 + (1.0 - test_fraction) * (t1 - t0)
    if cutoff_hz is None:
        cutoffs = _flt.cutoff_candidates(fs)
        if not cutoffs:
            raise ConfigError(f"log {log.source} is sampled at {fs:.4g} Hz: too slow for any cut-off of "
                              f"{', '.join(f'{f:g}' for f in _flt.CUTOFFS_HZ)} Hz; give --filter HZ "
                              f"(at most {0.45 * fs / _flt.STATE_FACTOR:.3g} Hz)")
    else:
        cutoffs = (float(cutoff_hz),)
    vels = (("logged", "differentiated") if log.qd is not None else ("differentiated",)) \
        if velocities == "auto" else (velocities,)
    weights = _est.WEIGHTINGS if weighting == "auto" else (weighting,)
    v_cands = _sel.COULOMB_VELOCITIES if coulomb_velocity is None else (float(coulomb_velocity),)
    if "coulomb" not in kinds:
        v_cands = (0.0 if coulomb_velocity is None else float(coulomb_velocity),)
    merged = merged_columns(robot, seed) if armature != "off" else {}
    arm_opts = {"auto": (False, True), "on": (True,), "off": (False,)}[armature]
    if len(merged) == robot.n:
        arm_opts = (False,)  # every rotor inertia merges with a rigid coefficient: nothing to fit
    sel = None
    shares = _sel.SLOW_SHARES if slow_share is None else (float(slow_share),)
    if max(len(cutoffs), len(vels), len(weights), len(v_cands), len(arm_opts), len(shares)) > 1:
        sel = _sel.select(robot, log, kinds, t_split, cutoffs, vels, weights, v_cands, grids=grids, folds=folds,
                          armature=arm_opts, merged=tuple(merged), slow_share=shares)
        c = sel["chosen"]
        fc, vel, wgt, v_s, arm, slow_share = (c[k] for k in ("cutoff_hz", "velocities", "weighting",
                                                             "coulomb_velocity", "armature", "slow_share"))
    else:
        fc, vel, wgt, v_s, arm, slow_share = cutoffs[0], vels[0], weights[0], v_cands[0], arm_opts[0], shares[0]
    chosen = "given (--filter)" if cutoff_hz is not None else "cross-validation"
    prep = _flt.prepare(log, fc, vel, grids=grids)
    train = prep.usable & (prep.t <= t_split)
    test = prep.usable & (prep.t > t_split)
    keep = _est.slow_rows(prep.qd, train, slow_share)[train]  # (rows of train, n): 0 at reversals and rests
    if not test.any():
        raise ConfigError(f"no held-out samples: the last {test_fraction:g} of the log lies in the filter's "
                          f"start-up ({_flt.EDGE / fc:.3g} s); give a longer log or a larger --test-fraction")
    arm_note = None
    partner = {j: robot.coefficient_names[k] for j, k in merged.items()}
    while True:
        kinds_all = kinds + (("armature",) if arm else ())
        cols = kept_columns(kinds_all, robot.n, tuple(merged) if arm else ())
        A = _filtered_rows(robot, prep, kinds_all, v_s, cols)
        all_names = friction_names(kinds_all, robot.n)
        names = tuple(robot.coefficient_names) + tuple(all_names[c] for c in cols)
        if arm:  # rotor inertias nearly confounded with a rigid coefficient on this log: merged, not fitted
            ia = [robot.p + i for i, c in enumerate(cols) if all_names[c].startswith("ia")]
            weak = _est.weak_columns(A[train] * keep[:, :, None], ia)
            if weak:
                partner |= {int(names[k][2:]) - 1: names[w] for k, w in weak.items()}
                merged = dict(merged) | {int(names[k][2:]) - 1: w for k, w in weak.items()}
                cols = kept_columns(kinds_all, robot.n, tuple(merged))
                A = _filtered_rows(robot, prep, kinds_all, v_s, cols)
                names = tuple(robot.coefficient_names) + tuple(all_names[c] for c in cols)
        try:
            _est.check_excitation(A[train] * keep[:, :, None], names, prep.q[train])
            break
        except ConfigError as exc:
            if not (arm and armature == "auto"):
                raise
            arm, arm_note = False, f"chosen by cross-validation, dropped: {exc}"
    arm_info = {"fitted": bool(arm), "option": armature,
                "chosen": arm_note or ("cross-validation" if len(arm_opts) > 1 and sel is not None else
                                       f"given (--armature {armature})"),
                "merged": {f"ia{j + 1}": partner[j] for j in sorted(merged)},
                "meaning": "a rotor inertia per joint (Pinocchio's armature [kg m^2], column qdd_j in joint j's row); "
                           "merged: joints whose column the rigid regressor already holds (over random states), not "
                           "fitted: their rotor inertia is part of the named rigid coefficient; or, on this log, "
                           "nearly confounded with the named coefficient (column-scaled condition number above "
                           "estimate.ARMATURE_COND)"}
    A_tr, y_tr, kept = A[train] * keep[:, :, None], prep.tau[train] * keep, keep.mean(axis=0)
    fit = _est.weighted_least_squares(A_tr, y_tr, gain=prep.noise_gain, step=prep.step, weighting=wgt, kept=kept)
    # the unfiltered residual at the training stamps (evenly thinned): its spectrum sets the covariance
    edge = _flt.EDGE / fc
    ok = (log.t >= t0 + edge) & (log.t <= grid[-1] - edge)
    tr_idx = np.nonzero(ok & (log.t <= t_split))[0]
    tr_idx = tr_idx[np.unique(np.linspace(0, tr_idx.size - 1, min(tr_idx.size, MAX_RAW_STAMPS)).astype(int))]
    raw_res = log.tau[tr_idx] - _raw_rows(robot, prep, log.t[tr_idx], kinds_all, v_s=v_s, columns=cols) @ fit.x
    sigma_raw = np.sqrt(np.mean((log.tau[tr_idx]
                                 - _raw_rows(robot, prep, log.t[tr_idx], kinds_all, True, v_s, cols) @ fit.x)
                                ** 2, axis=0))
    density = _flt.residual_density(log.t[tr_idx], raw_res, fc, prep.fs)
    parts = {"white": fit.cov, "spectral": _est.spectral_covariance(A_tr, fit.weights, prep.fs_coarse, density)}
    inband = _est.in_band_covariance(A_tr, fit.weights, y_tr - A_tr @ fit.x, prep.fs_coarse, prep.fs, fc, kept=kept)
    parts["in-band"] = inband["cov"]
    nu = robot.n * _flt.effective_dof(int(fit.rows), prep.fs_coarse, fc) - len(names)
    if covariance == "robust":
        fit = replace(fit, cov=_est.dominating(parts["white"], parts["spectral"]))
    elif covariance == "in-band":
        fit, nu = replace(fit, cov=inband["cov"]), inband["dof"]
    p = robot.p
    ell = _est.ellipsoid(fit.cov[:p, :p], confidence, dof=max(nu, 1.5))
    te_idx = np.nonzero(ok & (log.t > t_split))[0]
    if te_idx.size == 0:
        raise ConfigError("no held-out time stamps outside the filter's start-up; give a longer log")
    R_te = _raw_rows(robot, prep, log.t[te_idx], kinds_all, True, v_s, cols)
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
        "band_confidence": float(confidence), "meaning": "rms: held-out torques as logged minus the model at the "
        "states low-passed at the cut-off (q and logged qd zero-phase at f_c, derivatives by central differences), at "
        "the logged stamps [N m]; rms_filtered: the same after the parallel low-pass; rms_nominal: the robot's own "
        "coefficients, no friction; inside_band: fraction of held-out logged torques within the prediction band"}
    filt = {"cutoff_hz": fc, "chosen": chosen, "order": _flt.ORDER, "kind": "Butterworth, zero phase (sosfiltfilt)",
            "state_cutoff_hz": prep.state_cutoff_hz, "predict_cutoff_hz": _flt.PREDICT_FACTOR * fc, "edge_s": edge,
            "rate_hz": fs, "coarse_rate_hz": prep.fs_coarse, "velocities": prep.velocities,
            "velocities_chosen": "cross-validation" if len(vels) > 1 else
            ("given (--velocities)" if velocities != "auto" else "not logged"),
            "weighting": wgt, "weighting_chosen": "cross-validation" if len(weights) > 1 else "given (--weighting)",
            "slow_share": float(slow_share), "rows_kept": kept.tolist(), "slow_share_chosen": "cross-validation"
            if len(shares) > 1 else "given (--slow-share)"}
    law = {"coulomb": COULOMB_LAW, "coulomb_velocity": float(v_s),
           "chosen": "cross-validation" if len(v_cands) > 1 else
           ("given (--coulomb-velocity)" if coulomb_velocity is not None else "no Coulomb term")}
    lam = np.linalg.eigvals(np.linalg.solve(parts["white"], parts["spectral"])).real
    lam_ib = np.linalg.eigvals(np.linalg.solve(parts["white"], parts["in-band"])).real
    reg = {"rows": int(fit.rows), "unknowns": len(names), "condition_number": fit.cond,
           "covariance": {"method": covariance, "spectral_over_white": [float(lam.min()), float(lam.max())],
                          "in_band_over_white": [float(lam_ib.min()), float(lam_ib.max())],
                          "in_band_hz": inband["band_hz"], "information_share": _est.INFO_SHARE,
                          "in_band_sigma": inband["sigma"].tolist(), "in_band_dof": float(inband["dof"]),
                          "meaning": "spectral_over_white, in_band_over_white: ranges of the generalized eigenvalues "
                                     "of the spectral (Whittle) and the in-band covariance against the white one; "
                                     "in_band_hz: the band holding information_share of the estimate's information, "
                                     "where in_band_sigma (white-equivalent noise per logged sample) is measured"}}
    cons = None
    if consistency:
        from .consistency import check_consistency

        cons = check_consistency(robot, fit.x[:p], fit.cov[:p, :p], ell["chi2"], seed=seed)
    held = {"t": log.t[te_idx], "tau": tau_te, "pred": pred, "band": half, "covariances": parts, "rows": R_te}
    phys = pfit = None
    if physical:
        from .physical import RULE_STAMPS

        rule = tr_idx[np.unique(np.linspace(0, tr_idx.size - 1, min(tr_idx.size, RULE_STAMPS)).astype(int))]
        phys, pfit = _physical(robot, fit, parts["white"], kinds_all,
                               _raw_rows(robot, prep, log.t[rule], kinds_all, True, v_s, cols),
                               log.tau[rule], A[test], prep.tau[test], R_te, tau_te, confidence, max(nu, 1.5),
                               sigma_raw, seed, cols)
    return Identification(robot.describe() | {"coefficient_names": list(robot.coefficient_names)},
                          tuple(robot.coefficient_names), kinds_all, fit.x, fit.cov, p, fit.sigma, sigma_raw, ell,
                          filt, validation, reg, log.describe(), cons, held, sel, law, phys, pfit,
                          tuple(int(c) for c in cols), arm_info, confidence, max(nu, 1.5))


def _physical(robot, fit, metric, kinds, R_tr, tau_tr, A_te, y_te, R_te, tau_te, confidence, dof, sigma_raw, seed,
              cols):
    """The consistent fit, its ellipsoid, held-out validation and share of physical draws inside (JSON-ready)."""
    import time

    from .consistency import standard_map
    from .physical import (GAMMAS, INSIDE_DRAWS, MAHALANOBIS_SLACK, PRIOR_FLOOR, REALISE_DRAWS, covariance_factor,
                           draws_inside, fit_physical, realise_log_cholesky, standard_of)

    t0 = time.perf_counter()
    # the white covariance is the projection's metric (it weighs the data against the prior; the reported
    # covariance, fit.cov, shapes the ellipsoid below)
    pf = fit_physical(robot, fit.x, metric, R_tr, tau_tr, kinds, seed=seed, columns=cols)
    elapsed = time.perf_counter() - t0
    p = robot.p
    # the bounds' ellipsoid: centred at the consistent estimate, shaped by the data's covariance (the
    # unconstrained estimate's): the prior moves the centre into the consistent set, it does not shrink
    # the uncertainty (a URDF's inertias can be wrong: docs/identification.md)
    ell = _est.ellipsoid(fit.cov[:p, :p], confidence, dof=dof)
    T = standard_map(robot, seed)
    share = draws_inside(pf, T, ell["P"], np.random.default_rng(seed))
    # what a campaign draws (rc3r.uncertainty.ellipsoid.draw_from_ellipsoid): theta uniform in the ellipsoid,
    # realised in the log-Cholesky chart from the consistent estimate's parameters
    rng = np.random.default_rng(seed)
    S = covariance_factor(pf.cov_eta)
    t1 = time.perf_counter()
    realised = reached = 0
    for _ in range(REALISE_DRAWS):
        th = _est.draw_theta(pf.theta, ell["P"], rng)
        eta = realise_log_cholesky(T, th, pf.eta, S, best=True)
        dd = T @ standard_of(eta) - pf.theta
        realised += bool(np.linalg.norm(T @ standard_of(eta) - th) <= 1e-10 * np.linalg.norm(th))
        reached += bool(dd @ ell["P"] @ dd <= 1.0 + 1e-9)
    t_realise = (time.perf_counter() - t1) / REALISE_DRAWS
    pred = R_te @ pf.x
    half = _est.Fit(pf.x, pf.cov, fit.sigma, fit.rows, fit.cond, fit.weights).band(R_te, sigma_raw, confidence)
    nb = pf.standard.size // 10
    from ..conventions import STD_KEYS
    from .consistency import model_standard_parameters

    pi0 = model_standard_parameters(robot.model)
    links = [{k: float(v) for k, v in zip(STD_KEYS, pf.standard[10 * b:10 * b + 10])} for b in range(nb)]
    se = np.sqrt(np.diag(pf.cov))
    n = robot.n

    def spread(v, fill):
        out = np.full(n * len(kinds), fill)
        out[np.asarray(cols, dtype=int)] = v
        return out
    out = {
        "theta": pf.theta.tolist(), "theta_std": se[:p].tolist(),
        "friction": {k: spread(pf.x[p:], 0.0)[i * n:(i + 1) * n].tolist() for i, k in enumerate(kinds)},
        "friction_std": {k: [None if not np.isfinite(v) else float(v)
                             for v in spread(se[p:], np.nan)[i * n:(i + 1) * n]]
                         for i, k in enumerate(kinds)},
        "links": links, "log_cholesky": pf.eta.tolist(),
        "masses": pf.masses.tolist(), "urdf_masses": pi0[0::10].tolist(),
        "mass_ratio": (pf.masses / np.maximum(pi0[0::10], 1e-300)).tolist(),
        "min_pseudo_inertia_eigenvalues": pf.info["min_eigenvalues"],
        "divergence_per_link": pf.info["divergence_per_body"],
        "gamma": pf.gamma,
        "gamma_rule": f"of {', '.join(f'{g:g}' for g in GAMMAS)} (each fitted, warm-started), the largest whose "
                      "Mahalanobis distance to the unconstrained estimate exceeds the smallest gamma's by at most "
                      f"{MAHALANOBIS_SLACK:g}",
        "gamma_path": pf.path, "prior_repaired_links": pf.info["repaired"], "prior_floor": PRIOR_FLOOR,
        "validation": {"rms": np.sqrt(np.mean((tau_te - pred) ** 2, axis=0)).tolist(),
                       "rms_filtered": np.sqrt(np.mean((y_te - A_te @ pf.x) ** 2, axis=0)).tolist(),
                       "rms_train": np.sqrt(np.mean((tau_tr - R_tr @ pf.x) ** 2, axis=0)).tolist(),
                       "inside_band": float(np.mean(np.abs(tau_te - pred) <= half))},
        "ellipsoid": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in ell.items() if k != "P"},
        "draws_inside": {"share": share, "draws": INSIDE_DRAWS, "seed": int(seed),
                         "realised": realised / REALISE_DRAWS, "realise_draws": REALISE_DRAWS,
                         "plants_inside": reached / REALISE_DRAWS,
                         "seconds_per_realised_draw": t_realise,
                         "meaning": "share: of log-Cholesky draws eta ~ N(eta*, Cov(eta)) (all physical), those whose "
                                    "theta lies inside this ellipsoid; realised: of theta uniform in the ellipsoid, "
                                    "those realised by physical link parameters (log-Cholesky Gauss-Newton from the "
                                    "consistent estimate's), as run, montecarlo and design draw plants; "
                                    "plants_inside: of those draws, the ones whose realised (or nearest reached) "
                                    "physical coefficients lie in the ellipsoid (usable plants)"},
        "covariance": pf.cov.tolist(), "seconds": elapsed,
        "method": "min (x - x_ls)^T Cov^-1 (x - x_ls) + gamma sum_k d(J_k || J0_k) over the log-Cholesky parameters "
                  "of every link (scipy least_squares); d the log-det divergence from the URDF's pseudo-inertia; "
                  "covariance by the Laplace approximation (docs/identification.md)",
        "_ellipsoid": ell,
    }
    return out, pf
