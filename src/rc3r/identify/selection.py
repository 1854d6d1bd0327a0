r"""The identification's settings chosen by blocked cross-validation on the training part of a log.

What is chosen (:func:`select`), among what the log allows:

* the cut-off ``f_c`` of the parallel filter, among :data:`~rc3r.identify.filtering.CUTOFFS_HZ`
  below the log's rate (:func:`~rc3r.identify.filtering.cutoff_candidates`: 2-20 Hz at 1 kHz,
  2-7 Hz at 100 Hz);
* the velocity source, logged ``qd`` or differentiated ``q`` (both only when ``qd`` is logged: a log
  whose velocities lag its positions, e.g. a 100 Hz log of a filtered velocity estimate, scores
  worse with them and gets the differentiated ones);
* the weighting of the least squares, ordinary or per-joint noise
  (:data:`~rc3r.identify.estimate.WEIGHTINGS`);
* the Coulomb smoothing velocity ``v_s`` of ``tanh(qd / v_s)`` among :data:`COULOMB_VELOCITIES`
  (:func:`~rc3r.identify.regressors.coulomb`; 0 is ``sign``);
* whether a rotor inertia per joint (armature, the column ``qdd_j``) is fitted: kept only when it lowers
  the best score by more than :data:`ARMATURE_GAIN` (joints whose column the rigid regressor holds are
  never fitted: ``merged``);
* whether each joint's slow rows (reversals, rests: :func:`~rc3r.identify.estimate.slow_rows`) are fitted, among
  :data:`SLOW_SHARES`: where a Coulomb joint sticks its friction is anything in ``[-f_c, f_c]``, no function of
  ``qd``, and those rows pull the static terms (offsets, gravity) off. Decided last, at the settings chosen with
  every row fitted: both fits predict the same rows, each joint's split into the same two regimes (slower than
  the largest share x its RMS speed, and the others), and the lower ``regime_score`` (each joint's RMS the
  geometric mean of its two regimes' RMS; one regime's share of the rows does not decide) wins. One setting
  changes between the two, so the comparison measures the rows left out and nothing else.

How a setting is scored. The training part (the log's first ``1 - F``, outside the filters'
start-up) is cut into :data:`FOLDS` contiguous blocks of equal duration. For every block, the
model is fitted exactly as :func:`rc3r.identify.pipeline.identify` fits it (the parallel-filtered
rows ``L[Phi] x = L[tau]``, the same weighting) on the other blocks, leaving out a guard of
``GUARD / f_c`` seconds on each side of the block (the zero-phase filter's reach: without it the
fitted ``L[tau]`` would carry the block's own noise), and predicts the block's **logged**
(unfiltered, resampled) torques at the states low-passed at ``f_c``: the held-out prediction of
:mod:`rc3r.identify.pipeline`, on training data. The score of a setting is the geometric mean
over the joints of the per-joint RMS pooled over the blocks [N m] (every joint counts alike,
whatever its torque scale); the lowest wins (:data:`RULE`).

The search scores every cut-off x velocity source x ``v_s`` x weighting, with the rotor inertias when they
are a candidate (the larger model), then every weighting without them at the chosen settings. The lowest
geometric mean wins (:data:`RULE`). Two stages (:data:`TWO_STAGE`: the cut-off and source at ``v_s =``
:data:`COULOMB_START`, then ``v_s``) are kept as an option: on logs with a large ``sign`` Coulomb law the best
cut-off depends on ``v_s`` (the stand-in arms of docs/identification.md 2.12 at seed 1: 1.4-1.9 x the best
plain fit with two stages, 1.06 with every combination). The worst per-joint ratio rule is kept as an option
too (measured worse on the geared UR5 stand-in at seed 0).
The cross-validation's coarse grid is coarser than the final fit's
(:data:`CV_COARSE_FACTOR`), and its rows are thinned to a rate of at least :data:`CV_RATE_FACTOR`
``x f_c``. Every fold's fit solves the normal equations from per-joint Gram matrices summed over
segments (computed once per setting), so the folds and weightings cost little beyond building the
regressor once per cut-off and source. The fold's fit is the final fit's estimator (checked against
:func:`~rc3r.identify.estimate.weighted_least_squares` in the tests), but the final fit's rows are
on its own, finer grid: the scores rank settings, the held-out ``validation.rms`` is the measure.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from . import filtering as _flt
from .estimate import SLOW_SHARE, WEIGHTINGS, slow_rows
from .regressors import coulomb, identification_regressor, joint_columns, kept_columns

__all__ = ["FOLDS", "GUARD", "COULOMB_VELOCITIES", "COULOMB_START", "CV_RATE_FACTOR", "CV_COARSE_FACTOR",
           "ARMATURE_GAIN",
           "filtered_rows",
           "predict_rows", "cv_scores", "select"]

#: Contiguous blocks of the training part.
FOLDS = 5

#: Coulomb smoothing velocities ``v_s`` [rad/s] the cross-validation chooses among (0: ``sign(qd)``).
COULOMB_VELOCITIES = (0.0, 0.003, 0.01, 0.03, 0.1)

#: ``v_s`` [rad/s] of the first stage (cut-off, velocity source, weighting).
COULOMB_START = 0.01

#: The cross-validation's rows are thinned to a rate of at least this multiple of the cut-off (the filtered rows'
#: products, whose sums are the Gram matrices, hold nothing above ``2 f_c``: sampled at ``10 f_c`` their sums are
#: the full grid's to the filter's stop-band level).
CV_RATE_FACTOR = 10.0

#: The cross-validation's coarse grid runs at no less than this multiple of the states' cut-off ``5 f_c``
#: (the final fit: :data:`~rc3r.identify.filtering.COARSE_FACTOR`, 10): the arm's regressor, evaluated there
#: and low-passed at ``f_c``, aliases only content from above ``19 f_c`` into the band, where the states'
#: filter has removed all but 2e-5 of it.
CV_COARSE_FACTOR = 4.0

#: Guard [in units of ``1 / f_c`` s] left out of a block's fit on each side of the block. The zero-phase
#: Butterworth's impulse response decays as ``exp(-2 pi sin(pi / 8) f_c t)`` = ``exp(-2.4 f_c t)``: 2.7 % of its
#: peak after ``1.5 / f_c``. (``3 / f_c``, the start-up :data:`~rc3r.identify.filtering.EDGE`, starved the
#: folds' fits at 2 Hz on a 10 s log: scores 4x the held-out RMS, 2 Hz never chosen.)
GUARD = 1.5

#: The model with a rotor inertia per joint is chosen only when its score is lower by more than this share
#: (the simpler model wins ties: on arms without rotor inertia the two score within noise, 1e-3 on the 3R).
ARMATURE_GAIN = 0.01

#: How the scored settings are ranked: ``"worst-ratio"`` (default): the lowest worst ratio over the joints of a
#: setting's RMS to that joint's best RMS over every setting scored (ties: the geometric mean); or
#: ``"geometric-mean"``: the lowest geometric mean over the joints.
RULE = "geometric-mean"

#: Search cut-off x source at one ``v_s`` first, then ``v_s`` (True), or every combination (False, the default).
TWO_STAGE = False

#: How a joint's RMS pools its slow rows (:func:`~rc3r.identify.estimate.slow_rows`) and the others:
#: ``"balanced"``, the geometric mean of the two regimes' RMS; ``"pooled"``, one RMS over all; ``"fast"``, the
#: others only.
SLOW_SCORE = "balanced"

#: The slow-row shares (:func:`~rc3r.identify.estimate.slow_rows`) the cross-validation chooses among when none is
#: given: every row, or each joint's rows slower than :data:`~rc3r.identify.estimate.SLOW_SHARE` x its RMS speed
#: left out of the fit.
SLOW_SHARES = (0.0, SLOW_SHARE)

#: Re-weightings of the per-joint weighted fit (as :func:`~rc3r.identify.estimate.weighted_least_squares`).
ITERATIONS = 2


def filtered_rows(robot, prep, kinds, v_s: float = 0.0, arm_rows=None, memo: dict | None = None,
                  columns=None) -> np.ndarray:
    """``L[Y | joint columns]`` (K, n, m) on the coarse grid (friction filtered at the full rate).

    ``kinds`` in :data:`~rc3r.identify.regressors.JOINT_KINDS` order (the armature column, ``qdd``, is
    filtered on the coarse grid like ``Y``); ``columns``: only these joint columns
    (:func:`~rc3r.identify.regressors.kept_columns`). ``arm_rows``: ``L[Y]`` (K, n, p) when already
    computed (only the friction columns depend on ``v_s``); ``memo``: a dict that keeps the filtered
    viscous, offset and armature columns between calls on the same ``prep``.
    """
    LY = prep.filter_coarse(robot.regressor(prep.q, prep.qd, prep.qd, prep.qdd)) if arm_rows is None else arm_rows
    n = prep.q.shape[1]
    qd = prep.friction_qd
    LF = np.zeros((LY.shape[0], n, n * len(kinds)))
    idx = np.arange(n)
    memo = {} if memo is None else memo
    for k, kind in enumerate(kinds):
        if kind == "coulomb":
            col = prep.filter_full(coulomb(qd, v_s))
        else:
            if kind not in memo:
                memo[kind] = (prep.filter_coarse(prep.qdd) if kind == "armature" else
                              prep.filter_full(qd if kind == "viscous" else np.ones_like(qd)))
            col = memo[kind]
        LF[:, idx, k * n + idx] = col[:LY.shape[0]]
    if columns is not None:
        LF = LF[:, :, np.asarray(columns, dtype=int)]
    return np.concatenate([np.asarray(LY, dtype=float), LF], axis=2)


def predict_rows(robot, prep, kinds, v_s: float = 0.0, columns=None) -> np.ndarray:
    """``[Y | joint columns]`` (K, n, m) on the coarse grid at the prediction states (low-passed at the cut-off)."""
    return identification_regressor(robot, *prep.predict, kinds, v_s, columns)


def _solve(G, b, w) -> np.ndarray:
    """``argmin sum_j w_j^2 ||y_j - A_j x||^2`` from per-joint Gram ``G`` (n, m, m) and ``b`` (n, m)."""
    w2 = np.asarray(w, dtype=float) ** 2
    H = np.einsum("j,jkl->kl", w2, G)
    r = w2 @ b
    d = np.sqrt(np.diag(H))
    d[d == 0] = 1.0
    try:
        return np.linalg.solve(H / np.outer(d, d), r / d) / d
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(H / np.outer(d, d), r / d, rcond=None)[0] / d


def _fit(G, b, yy, weighting: str, count=None) -> np.ndarray:
    """The fit of :func:`~rc3r.identify.estimate.weighted_least_squares` from per-joint sums (``count`` (n,):
    each joint's rows used, whose residual sets its weight)."""
    n = G.shape[0]
    w = np.ones(n)
    x = _solve(G, b, w)
    count = np.ones(n) if count is None else np.maximum(np.asarray(count, dtype=float), 1.0)
    if weighting == "per-joint":
        for _ in range(ITERATIONS + 1):
            rss = yy - 2.0 * np.einsum("jk,k->j", b, x) + np.einsum("k,jkl,l->j", x, G, x)
            sig = np.sqrt(np.maximum(rss, 1e-300) / count)
            w = 1.0 / np.maximum(sig, 1e-12 * max(1.0, float(sig.max())))
            x = _solve(G, b, w)
    return x


def cv_scores(A, y, P, tau, t, train, fc: float, weightings=WEIGHTINGS, folds: int = FOLDS, slow=None,
              how: str | None = None) -> dict:
    """Blocked cross-validation RMS per joint of a fit of ``y ~ A x`` predicting ``tau`` by ``P x`` (module docstring).

    Parameters
    ----------
    A, P : ndarray (K, n, m)
        The fit's filtered rows and the prediction rows on one grid of times ``t`` (K,).
    y, tau : ndarray (K, n)
        The filtered torques and the logged (unfiltered) ones there.
    train : ndarray of bool (K,)
        The rows that may be used (training part, outside the filters' start-up).
    fc : float
        The cut-off [Hz]: a guard of ``GUARD / fc`` s about each block is left out of its fit.
    weightings : sequence of str
        Scored alike on the same folds.
    folds : int
        Contiguous blocks.
    slow : ndarray of bool (K, n), optional
        Rows of each joint in the slow regime (reversals, rests: :func:`~rc3r.identify.estimate.slow_rows`):
        a joint's RMS is then the geometric mean of its RMS over its slow rows and over the others (each
        regime counts alike, whatever its share of the training part).
    how : str or tuple of str, optional
        How the regimes pool (as :data:`SLOW_SCORE`, its default); a tuple: ``{weighting: (rms, ...)}``, one (n,)
        per entry.

    Returns
    -------
    dict
        ``{weighting: (n,) RMS [N m]}`` (``inf`` when a fold leaves too few rows to fit).
    """
    how = SLOW_SCORE if how is None else how
    idx = np.nonzero(train)[0]
    K, n, m = A.shape
    tt = t[idx]
    edges = np.linspace(tt[0], tt[-1], folds + 1)
    guard = GUARD / fc
    cuts = np.unique(np.clip(np.concatenate([edges, edges - guard, edges + guard]), tt[0], tt[-1]))
    S = cuts.size - 1
    bounds = np.searchsorted(tt, cuts[1:-1], side="right")  # rows are in time order: segments are slices
    starts, stops = np.concatenate([[0], bounds]), np.concatenate([bounds, [tt.size]])
    G = np.zeros((S, n, m, m))
    bb = np.zeros((S, n, m))
    yy = np.zeros((S, n))
    used = np.zeros((S, n))  # a joint's rows used in each segment (rows zeroed by slow_rows are not)
    count = stops - starts
    At = np.ascontiguousarray(np.moveaxis(A[idx], 1, 0))  # (n, N, m): one contiguous block per joint
    yt = np.ascontiguousarray(y[idx].T)
    for j in range(n):
        nz = np.nonzero(np.any(At[j] != 0.0, axis=0))[0]  # a joint's row: most columns are zero
        Aj = np.ascontiguousarray(At[j][:, nz])
        for s in range(S):
            a, b = starts[s], stops[s]
            if b > a:
                G[s, j][np.ix_(nz, nz)] = Aj[a:b].T @ Aj[a:b]
                bb[s, j, nz] = Aj[a:b].T @ yt[j, a:b]
                yy[s, j] = yt[j, a:b] @ yt[j, a:b]
                used[s, j] = np.count_nonzero(np.any(Aj[a:b] != 0.0, axis=1))
    mid = 0.5 * (cuts[:-1] + cuts[1:])
    fold_of = np.clip(np.searchsorted(edges, tt, side="right") - 1, 0, folds - 1)
    del At
    slow = np.zeros((K, n), dtype=bool) if slow is None else np.asarray(slow, dtype=bool)
    sse = {w: np.zeros((2, n)) for w in weightings}  # [fast, slow] regimes
    rows = np.zeros((2, n))
    for i in range(folds):
        use = (mid < edges[i] - guard) | (mid > edges[i + 1] + guard)
        if count[use].sum() * n <= 2 * m:
            return {w: ((np.full(n, np.inf),) * len(how) if isinstance(how, tuple) else np.full(n, np.inf))
                    for w in weightings}
        val = idx[fold_of == i]
        sv = slow[val]
        rows += np.stack([np.sum(~sv, axis=0), np.sum(sv, axis=0)])
        for w in weightings:
            x = _fit(G[use].sum(axis=0), bb[use].sum(axis=0), yy[use].sum(axis=0), w, used[use].sum(axis=0))
            e2 = (tau[val] - P[val] @ x) ** 2
            sse[w] += np.stack([np.sum(e2 * ~sv, axis=0), np.sum(e2 * sv, axis=0)])
    if isinstance(how, tuple):
        return {w: tuple(_pool(sse[w], rows, h) for h in how) for w in weightings}
    return {w: _pool(sse[w], rows, how) for w in weightings}


def _pool(sse, rows, how: str) -> np.ndarray:
    """Per-joint RMS (n,) from the squared errors and row counts (2, n) of the fast and slow regimes."""
    pooled = np.sqrt(sse.sum(axis=0) / rows.sum(axis=0))
    if how == "pooled":
        return pooled
    if how == "fast":
        return np.where(rows[0] > 0, np.sqrt(sse[0] / np.maximum(rows[0], 1)), pooled)
    both = np.all(rows > 0, axis=0)  # joints with rows in both regimes: geometric mean of the two
    return np.where(both, np.sqrt(np.sqrt(sse[0] / np.maximum(rows[0], 1) * sse[1] / np.maximum(rows[1], 1))), pooled)


def _score(rms) -> float:
    """Geometric mean over joints of the per-joint RMS [N m]."""
    rms = np.asarray(rms, dtype=float)
    return float(np.exp(np.mean(np.log(np.maximum(rms, 1e-300))))) if np.all(np.isfinite(rms)) else float("inf")


def select(robot, log, kinds, t_split: float, cutoffs, velocities, weightings, coulomb_velocities,
           grids=None, folds: int = FOLDS, armature=(False,), merged=(), slow_share=0.0) -> dict:
    """Choose cut-off, velocity source, weighting, Coulomb smoothing and armature by cross-validation.

    Parameters
    ----------
    robot, log :
        As :func:`rc3r.identify.pipeline.identify`.
    kinds : tuple of str
        Friction kinds (``v_s`` is only searched when ``"coulomb"`` is among them).
    t_split : float
        End of the training part [s].
    cutoffs, velocities, weightings, coulomb_velocities : sequence
        The candidates (one each: given, not searched).
    grids : rc3r.identify.filtering.Grids, optional
        The log resampled once.
    folds : int
        Contiguous blocks of the training part.
    armature : sequence of bool
        Fit a rotor inertia per joint (``True``), or not; with both, stages 1 and 2 fit it and stage 3
        scores the model without it at the chosen settings (module docstring).
    merged : sequence of int
        Joints (0-based) whose armature column is in the rigid regressor's span (not fitted:
        :func:`~rc3r.identify.regressors.merged_columns`).
    slow_share : float or sequence of float
        The folds' fits leave out a joint's rows slower than this x its RMS speed, as the final fit does
        (:func:`~rc3r.identify.estimate.slow_rows`; 0: none); the blocks' predictions cover every row, scored
        per regime (:data:`SLOW_SCORE`). Several: each is a candidate, every one scored on the same rows split
        into the same regimes (those of the largest share), so their scores compare.

    Returns
    -------
    dict
        ``chosen`` (``cutoff_hz``, ``velocities``, ``weighting``, ``coulomb_velocity``, ``armature``,
        ``slow_share``, ``score``, and ``regime_score`` with several shares), ``stage1_coulomb_velocity`` (``v_s``
        of stage 1, None when one stage), ``candidates``
        (every setting scored: its settings, ``rms`` per joint and ``score``, in order), ``folds``,
        ``best_score``, ``method`` (one paragraph), ``score`` (its meaning).
    """
    g = _flt.Grids.of(log) if grids is None else grids
    vs = tuple(coulomb_velocities) if "coulomb" in kinds else (0.0,)
    v0 = COULOMB_START if COULOMB_START in vs else vs[len(vs) // 2]
    arm_opts = tuple(dict.fromkeys(bool(a) for a in armature))
    arm0 = arm_opts[-1]
    shares = tuple(dict.fromkeys(float(x) for x in np.atleast_1d(slow_share)))
    split = max(shares)  # the regimes every candidate is scored on (0: one regime, every row pooled)
    n = robot.n
    rows = []
    cache = {}

    def run(fc, vel, v_s, weights, arm, share_list=shares[:1]):
        prep, LY, PY, th, memo = cache[(fc, vel)]
        ks = tuple(kinds) + (("armature",) if arm else ())
        cols = kept_columns(ks, n, merged)
        A = filtered_rows(robot, prep, ks, v_s, arm_rows=LY, memo=memo, columns=cols)[th]
        qp, qdp, qddp = (X[th] for X in prep.predict)
        P = np.concatenate([PY, joint_columns(qdp, qddp, ks, v_s)[:, :, cols]], axis=2)
        train = (prep.usable & (prep.t <= t_split))[th]
        regimes = slow_rows(prep.qd[th], train, split) == 0
        out = []
        for share in share_list:
            keep = slow_rows(prep.qd[th], train, share)
            res = cv_scores(A * keep[:, :, None], prep.tau[th] * keep, P, prep.tau_raw[th], prep.t[th], train, fc,
                            weights, folds, slow=regimes, how=("pooled" if share == 0 else SLOW_SCORE, "balanced"))
            for w in weights:
                own = res[w][0]
                row = {"cutoff_hz": float(fc), "velocities": vel, "weighting": w, "coulomb_velocity": float(v_s),
                       "armature": bool(arm), "slow_share": share, "rms": [float(r) for r in own],
                       "score": _score(own)}
                if len(shares) > 1:
                    row |= {"regime_rms": [float(r) for r in res[w][1]], "regime_score": _score(res[w][1])}
                rows.append(row)
                out.append(row)
        return out

    multi = TWO_STAGE and len(vs) > 1 and (len(cutoffs) > 1 or len(velocities) > 1)

    def pick(cands):
        """The candidate of the rule (:data:`RULE`) among ``cands``, each judged against every row scored."""
        ok = [r for r in cands if np.isfinite(r["score"])]
        if not ok:
            return None
        if RULE == "geometric-mean":
            return min(ok, key=lambda r: r["score"])
        ref = np.min([r["rms"] for r in rows if np.isfinite(r["score"]) and r["slow_share"] == ok[0]["slow_share"]],
                     axis=0)
        return min(ok, key=lambda r: (round(float(np.max(np.asarray(r["rms"]) / ref)), 12), r["score"]))

    for vel in velocities:
        for fc in cutoffs:
            prep = _flt.prepare(log, fc, vel, grids=g, coarse_factor=CV_COARSE_FACTOR)
            LY = prep.filter_coarse(robot.regressor(prep.q, prep.qd, prep.qd, prep.qdd))
            th = slice(None, None, max(1, int(np.floor(prep.fs_coarse / (CV_RATE_FACTOR * fc)))))
            qp, qdp, qddp = (X[th] for X in prep.predict)
            PY = np.asarray(robot.regressor(qp, qdp, qdp, qddp), dtype=float)
            cache[(fc, vel)] = (prep, LY, PY, th, {})
            for v_s in (vs if not multi else (v0,)):
                run(fc, vel, v_s, weightings, arm0)
    top = pick(rows)
    if top is None:
        raise ConfigError(f"log {log.source}: too short to cross-validate the filter ({folds} blocks of the "
                          "training part); give a longer log or --filter, --velocities, --weighting")
    fc, vel = top["cutoff_hz"], top["velocities"]
    cache = {(fc, vel): cache[(fc, vel)]}
    if multi:
        for v_s in vs:
            if v_s != v0:
                run(fc, vel, v_s, weightings, arm0)
        top = pick([r for r in rows if r["cutoff_hz"] == fc and r["velocities"] == vel])
    for arm in arm_opts:
        if arm != arm0:
            other = min(run(fc, vel, top["coulomb_velocity"], weightings, arm), key=lambda r: r["score"])
            with_arm, without = (other, top) if arm else (top, other)
            top = with_arm if with_arm["score"] < (1.0 - ARMATURE_GAIN) * without["score"] else without
    best = top
    if len(shares) > 1:  # the other shares at the chosen settings, all on the same rows in the same two regimes
        same = run(fc, vel, top["coulomb_velocity"], (top["weighting"],), top["armature"], shares[1:])
        best = min([top] + same, key=lambda r: r["regime_score"])
    chosen = {k: best[k] for k in ("cutoff_hz", "velocities", "weighting", "coulomb_velocity", "armature",
                                   "slow_share", "score")}
    if len(shares) > 1:
        chosen["regime_score"] = best["regime_score"]
    lo = min(float(r["score"]) for r in rows if r["slow_share"] == best["slow_share"])
    stages = ("stage 1: every cut-off x velocity source x weighting at v_s = "
              f"{v0:g} rad/s, stage 2: every v_s x weighting at the chosen cut-off and source" if multi
              else "every candidate setting") + (
        "; chosen: the lowest worst ratio over the joints of the setting's RMS to the joint's best over every "
        "setting (ties: geometric mean)" if RULE == "worst-ratio" else "; chosen: the lowest geometric mean")
    if len(arm_opts) > 1:
        stages += (f" (with{'' if arm0 else 'out'} a rotor inertia per joint), then every weighting "
                   f"with{'out' if arm0 else ''} it at the chosen settings; the rotor inertias are kept only "
                   f"when they lower the best score by more than {100 * ARMATURE_GAIN:g} %")
    if len(shares) > 1:
        stages += (f"; every row fitted (slow share {shares[0]:g}), then at the chosen settings the fit without each "
                   "joint's rows slower than " + ", ".join(f"{x:g}" for x in shares[1:]) + " x its RMS speed; of "
                   "these the lowest regime_score: each joint's RMS the geometric mean of its RMS over its rows "
                   f"slower than {split:g} x its RMS speed and over the others (the same rows for every share)")
    return {"chosen": chosen, "candidates": rows, "folds": int(folds), "best_score": lo,
            "stage1_coulomb_velocity": float(v0) if multi else None, "rule": RULE,
            "method": (f"blocked cross-validation on the training part: {folds} contiguous blocks; each block's "
                       "logged torques predicted (states low-passed at the cut-off) by the parallel-filtered fit "
                       f"on the other blocks, less a guard of {GUARD:g} / f_c s at each side of the block; "
                       + stages),
            "score": "geometric mean over joints of the per-joint held-out RMS pooled over the blocks [N m]; "
                     "the choice follows rule"}
