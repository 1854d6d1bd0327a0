"""``rc3r identify`` (coefficients, friction and bounds from a log) and ``rc3r excite`` (a trajectory to log).

Library: :mod:`rc3r.identify`; guide: ``docs/identification.md``.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import ConfigError
from ..robots import ROBOTS
from . import EXIT

__all__ = ["add_parsers", "cmd_identify", "cmd_excite", "OWN_ENTRIES"]

#: What ``rc3r identify`` writes in --out (a rerun replaces these; other files are kept).
OWN_ENTRIES = ("identified.json", "bounds.toml", "torque.png", "residuals.png")


def _fraction(text):
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0.0 < x < 1.0:
        raise argparse.ArgumentTypeError(f"must be between 0 and 1 (exclusive), got {text}")
    return x


def _kinds(text):
    from ..identify.regressors import parse_friction

    try:
        return parse_friction(text)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _arm_args(p, positive, lock, urdf=str) -> None:
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--robot", help=f"a registered robot ({', '.join(ROBOTS)})")
    g.add_argument("--urdf", type=urdf, help="the arm's URDF (any serial arm through Pinocchio)")
    p.add_argument("--lock", type=lock, action="append", metavar="JOINT=VALUE",
                   help="fix a joint of the URDF at VALUE (repeatable)")
    p.add_argument("--seed", type=positive(int, allow_zero=True), default=0, help="RNG seed (default 0)")


def add_parsers(sub, positive, lock, urdf=str) -> None:
    """Add ``identify`` and ``excite`` to the subparsers ``sub`` (``positive``, ``lock``, ``urdf``: the CLI's
    converters)."""
    i = sub.add_parser("identify", help="coefficients, friction, covariance and bounds.toml from a log")
    i.add_argument("log", metavar="LOG", help="CSV (t, q1..qn, [qd1..qdn,] tau1..taun) or NPZ (t, q, [qd,] tau)")
    _arm_args(i, positive, lock, urdf)
    i.add_argument("--friction", type=_kinds, default=("viscous", "coulomb", "offset"), metavar="KINDS",
                   help="friction columns per joint: comma-separated viscous, coulomb, offset, or none "
                        "(default all three)")
    i.add_argument("--filter", type=positive(), metavar="HZ",
                   help="cut-off of the zero-phase low-pass [Hz] (default: chosen by cross-validation on the "
                        "training part among 2, 3, 5, 7, 10, 15, 20 Hz below the log's rate)")
    i.add_argument("--test-fraction", type=_fraction, default=0.2, metavar="F",
                   help="last fraction of the log held out for validation (default 0.2)")
    i.add_argument("--confidence", type=_fraction, default=0.95, metavar="C",
                   help="confidence level of the ellipsoid and the prediction band (default 0.95)")
    i.add_argument("--covariance", choices=("in-band", "white", "robust"), default="in-band",
                   help="in-band (default): the noise level measured where the estimate's information lies "
                        "(corrected for what the fit absorbed); white: the whole pass band's level; robust: "
                        "white, also dominating the spectral (Whittle) covariance")
    i.add_argument("--velocities", choices=("auto", "logged", "differentiated"), default="auto",
                   help="logged qd or differentiated q (default auto: chosen by cross-validation when qd is logged)")
    i.add_argument("--weighting", choices=("auto", "ordinary", "per-joint"), default="auto",
                   help="least squares: ordinary or weighted by per-joint noise (default auto: by cross-validation)")
    i.add_argument("--coulomb-velocity", type=positive(float, allow_zero=True), metavar="RAD_S",
                   help="smoothing velocity v_s of the Coulomb law f_c tanh(qd / v_s), 0 for sign(qd) "
                        "(default: chosen by cross-validation among 0, 0.003, 0.01, 0.03, 0.1)")
    i.add_argument("--armature", choices=("auto", "on", "off"), default="auto",
                   help="a rotor inertia per joint (Pinocchio's armature, column qdd_j): auto (default: chosen by "
                        "cross-validation), on or off; a joint whose column the rigid model already holds (joint 1 "
                        "about the gravity axis) is merged into that coefficient, said in identified.json")
    i.add_argument("--slow-share", type=positive(float, allow_zero=True), default=None, metavar="S",
                   help="leave a joint's rows slower than S x its RMS speed (reversals, rests: stuck Coulomb "
                        "friction) out of the fit; 0 keeps every row (default: 0 or 0.1, chosen by cross-validation "
                        "with every row scored in two regimes, slow and fast; docs/identification.md 2.3)")
    i.add_argument("--no-consistency", action="store_true",
                   help="skip the consistency SDP of the unconstrained estimate (cvxpy)")
    i.add_argument("--no-physical", action="store_true",
                   help="skip the physically consistent fit: bounds.toml then carries the unconstrained least-squares "
                        "estimate (which may not be a rigid body)")
    i.add_argument("--out", required=True, help="output directory (identified.json, bounds.toml, figures)")
    i.add_argument("--force", action="store_true", help="replace an earlier result in --out")

    e = sub.add_parser("excite", help="an exciting trajectory (Fourier series, condition number minimised)")
    _arm_args(e, positive, lock, urdf)
    e.add_argument("--duration", type=positive(), required=True, metavar="T", help="period and length [s]")
    e.add_argument("--harmonics", type=positive(int), default=5, help="harmonics per joint (default 5)")
    e.add_argument("--max-velocity", type=positive(), metavar="RAD_S",
                   help="velocity bound [rad/s] (default min(2, 0.8 x the URDF's))")
    e.add_argument("--max-acceleration", type=positive(), metavar="RAD_S2", help="acceleration bound (default 10)")
    e.add_argument("--rate", type=positive(), default=1000.0, help="samples per second of the CSV (default 1000)")
    e.add_argument("--starts", type=positive(int), default=1, help="random starts of the optimiser (default 1)")
    e.add_argument("--synthetic-log", metavar="LOG",
                   help="also simulate the arm tracking the trajectory (friction, sensor noise, quantized encoders, "
                        "jittered stamps; docs/identification.md) and write the log an experiment would record")
    e.add_argument("--out", required=True, metavar="TRAJ.CSV",
                   help="the trajectory (t, q, qd, qdd); its coefficients go to the .json beside it")
    e.add_argument("--force", action="store_true",
                   help="replace an earlier trajectory, its .json, or the synthetic log and its .truth.json")


def _robot(args):
    from ..runspec import _nominal

    lock = dict(args.lock) if args.lock else None
    return _nominal(args.robot, args.urdf, lock)


def _note(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _fmt(xs, digits: int = 3) -> str:
    return " ".join(f"{x:.{digits}g}" for x in xs)


def cmd_identify(args) -> int:
    """``rc3r identify LOG``: writes identified.json, bounds.toml, torque.png, residuals.png into --out."""
    from threadpoolctl import threadpool_limits

    from ..identify.bounds_file import write_bounds
    from ..identify.figures import residual_figure, torque_figure
    from ..identify.log import load_log
    from ..identify.pipeline import identify
    from ..io import atomic_savefig, atomic_write_json
    from ..provenance import provenance
    from ._output import check_output_path, output_dir

    out = Path(args.out)
    check_output_path(out)
    if out.is_dir() and any(out.iterdir()) and not args.force:
        raise ConfigError(f"{out} holds an earlier result; give --force to replace it, or another --out")
    robot = _robot(args)
    log = load_log(args.log, n=robot.n)  # no progress line: a refused log must leave one line on stderr
    # Narrow matrices (20-70 columns): spinning BLAS threads cost more than they gain on a busy machine
    # (the Panda log: 49 s with two OpenBLAS threads, 25 s with one, 2 cores at a load of 8, 2026-12-06).
    with threadpool_limits(limits=1, user_api="blas"):
        res = identify(robot, log, friction=args.friction, cutoff_hz=args.filter, test_fraction=args.test_fraction,
                       confidence=args.confidence, velocities=args.velocities,
                       consistency=not args.no_consistency, covariance=args.covariance, seed=args.seed,
                       weighting=args.weighting, coulomb_velocity=args.coulomb_velocity,
                       physical=not args.no_physical, armature=args.armature, slow_share=args.slow_share)
    prov = provenance(seed=args.seed)
    data = res.to_dict() | {"provenance": prov}
    lock = dict(args.lock) if args.lock else {}
    bounds = res.bounds()
    ident = {"log": str(Path(args.log).resolve()), "log_sha256": log.sha256, "cutoff_hz": res.filter["cutoff_hz"],
             "filter_chosen": res.filter["chosen"], "sigma": res.sigma.tolist(), "friction": list(res.friction_kinds),
             "covariance": args.covariance, "quantile": bounds["quantile"],
             "velocities": res.filter["velocities"], "weighting": res.filter["weighting"],
             "slow_share": res.filter["slow_share"],
             "armature": bool((res.armature or {}).get("fitted")),
             "coulomb_law": res.friction_law["coulomb"], "coulomb_velocity": res.friction_law["coulomb_velocity"],
             "estimate": "physically consistent (log-Cholesky, log-det prior)" if "physical" in bounds else
             "unconstrained least squares (--no-physical)"}
    flat_prov = {"rc3r": prov["versions"]["rc3r"], "created": prov["created"], "command": " ".join(prov["command"]),
                 "git_commit": (prov.get("git") or {}).get("commit"), "git_dirty": (prov.get("git") or {}).get("dirty")}
    with output_dir(out, own=OWN_ENTRIES) as tmp:
        atomic_write_json(tmp / "identified.json", data)
        write_bounds(tmp / "bounds.toml", bounds, robot, robot_name=args.robot,
                     urdf=None if args.urdf is None else str(Path(args.urdf).resolve()), lock=lock, seed=args.seed,
                     identification=ident, provenance=flat_prov)
        atomic_savefig(torque_figure(res), tmp / "torque.png", dpi=110)
        atomic_savefig(residual_figure(res), tmp / "residuals.png", dpi=110)
    v, f = res.validation, res.filter
    nfr = sum(k != "armature" for k in res.friction_kinds) * robot.n
    arm = res.armature or {}
    n_arm = res.joint_columns.size - nfr
    merged = ", ".join(f"{a} merged with {b}" for a, b in (arm.get("merged") or {}).items())
    arm_text = (f" + {n_arm} rotor inertias" + (f" ({merged})" if merged else "")) if arm.get("fitted") else ""
    print(f"identified {robot.p} coefficients + {nfr} friction terms{arm_text} of "
          f"{robot.robot_name or robot.name} from {log.samples} samples over {log.t[-1] - log.t[0]:.4g} s")
    sel = res.selection
    if sel is not None:
        c, rows = sel["chosen"], sel["candidates"]
        print(f"cross-validation on the training part ({sel['folds']} blocks, {len(rows)} settings; score = geometric "
              "mean over joints of the held-out RMS vs logged torque [N m], best weighting per cell):")
        v0 = sel["stage1_coulomb_velocity"]
        first = [r for r in rows if v0 is None or r["coulomb_velocity"] == v0]
        cuts = list(dict.fromkeys(r["cutoff_hz"] for r in first))
        print(f"  {'cut-off [Hz]':>16}" + "".join(f"{fc:>8g}" for fc in cuts))
        for vel in dict.fromkeys(r["velocities"] for r in first):
            cell = [min((r["score"] for r in first if r["velocities"] == vel and r["cutoff_hz"] == fc), default=None)
                    for fc in cuts]
            print(f"  {vel:>16}" + "".join(f"{x:>8.4f}" if x is not None else f"{'-':>8}" for x in cell))
        a0 = rows[0].get("armature", False)
        for w in dict.fromkeys(r["weighting"] for r in rows):
            alt = [r for r in rows if r["cutoff_hz"] == c["cutoff_hz"] and r["velocities"] == c["velocities"]
                   and r["weighting"] == w and r.get("armature", False) == a0
                   and r.get("slow_share") == rows[0].get("slow_share")]
            print(f"  {w:>9} at {c['cutoff_hz']:g} Hz, {c['velocities']}, by v_s [rad/s]: "
                  + ", ".join(f"{r['coulomb_velocity']:g} {r['score']:.4f}" for r in sorted(
                      alt, key=lambda r: r["coulomb_velocity"])))
        arms = {r["armature"]: min(x["score"] for x in rows if x.get("armature") == r["armature"] and
                                   x["cutoff_hz"] == c["cutoff_hz"] and x["velocities"] == c["velocities"] and
                                   x["coulomb_velocity"] == c["coulomb_velocity"])
                for r in rows if "armature" in r}
        if len(arms) > 1:
            print(f"  rotor inertia per joint at the chosen settings: with {arms[True]:.4f}, without {arms[False]:.4f} "
                  f"-> {'with' if c['armature'] else 'without'}")
        same = {r["slow_share"]: r["regime_score"] for r in rows if "regime_score" in r and all(
            r[k] == c[k] for k in ("cutoff_hz", "velocities", "weighting", "coulomb_velocity", "armature"))}
        if len(same) > 1:
            print("  slow rows at the chosen settings (regime score, the same rows: slow and fast apart): "
                  + ", ".join(f"share {k:g} {v:.4f}" for k, v in same.items())
                  + f" -> {c['slow_share']:g}" + (f" (each joint's rows slower than {c['slow_share']:g} x its RMS "
                                                   "speed left out of the fit)" if c["slow_share"] else " (every row)"))
    law = res.friction_law
    print(f"filter: {f['cutoff_hz']:.3g} Hz ({f['chosen']}), velocities {f['velocities']}, weighting "
          f"{f['weighting']}, Coulomb tanh(qd / {law['coulomb_velocity']:g} rad/s); "
          f"{res.regressor['rows']} rows, condition number {res.regressor['condition_number']:.3g}")
    print(f"held-out rms [N m]: {_fmt(v['rms'])} (logged), {_fmt(v['rms_filtered'])} (low-passed), "
          f"{_fmt(v['rms_nominal'])} (the robot's own coefficients)")
    ph = res.physical
    if ph is not None:
        pv = ph["validation"]
        print(f"physically consistent fit (gamma {ph['gamma']:g}): held-out rms {_fmt(pv['rms'])} (logged), "
              f"{_fmt(pv['rms_filtered'])} (low-passed); smallest pseudo-inertia eigenvalue "
              f"{min(ph['min_pseudo_inertia_eigenvalues']):.3g}")
        print(f"link masses [kg]: {_fmt(ph['masses'])} (the URDF's {_fmt(ph['urdf_masses'])})")
        di = ph["draws_inside"]
        print(f"physical draws: {100 * di['share']:.1f} % of {di['draws']} Gaussian log-Cholesky draws inside the "
              f"ellipsoid; of {di['realise_draws']} uniform draws, {100 * di['realised']:.0f} % realised exactly by "
              f"physical links, {100 * di['plants_inside']:.0f} % give a physical plant inside (seed {di['seed']})")
    print(f"inside the {100 * v['band_confidence']:g} % prediction band: {100 * v['inside_band']:.1f} % of "
          f"{v['samples']} held-out samples x {robot.n} joints")
    c = res.consistency
    if c is None:
        print("consistency SDP of the unconstrained estimate: not run (--no-consistency)")
    elif not c.get("checked"):
        print(f"consistency SDP of the unconstrained estimate: not run ({c['reason']})")
    else:
        print("consistency SDP of the unconstrained estimate: " + ("it is realised by consistent standard parameters"
                                          if c["consistent"] else
                                          f"the nearest consistent coefficients are {c['mahalanobis']:.3g} standard "
                                          f"deviations away ({'inside' if c['within_ellipsoid'] else 'outside'} "
                                          "the ellipsoid)"))
    which = "physically consistent" if "physical" in bounds else "unconstrained"
    import numpy as np

    act = bounds.get("actuator")
    if act is not None and act["kinds"]:  # rc3r-bounds/2: what a reader of the rigid coefficients gets
        rp = act["rigid_p"]
        Pinv = np.linalg.inv(act["P"])[:rp, :rp]
        rho, rho_i = float(np.sqrt(np.linalg.eigvalsh(0.5 * (Pinv + Pinv.T))[-1])), act["rho_i"][:rp]
        where = (f" over the {rp} rigid coefficients (projected from the ellipsoid over them and the "
                 f"{len(act['theta0']) - rp} joint coefficients: rho = {act['rho']:.4g})")
    else:
        rho, rho_i, where = bounds["rho"], bounds["rho_i"], ""
    print(f"bounds of the {which} estimate at {100 * bounds['confidence']:g} %{where}: rho = {rho:.4g}, "
          f"max rho_i = {max(rho_i):.4g} -> {out}/bounds.toml, identified.json, torque.png, residuals.png")
    return EXIT["ok"]


def _excite_targets(out: Path, log_path: Path | None, force: bool) -> None:
    """Refuse, before any work, to overwrite: an existing trajectory, its .json, synthetic log or its
    .truth.json without ``force``; and, even with it, two outputs on one file (``--synthetic-log`` equal to
    ``--out`` would replace the trajectory just written)."""
    import os

    targets = {"--out": out, "its coefficients (.json beside --out)": out.with_suffix(".json")}
    if log_path is not None:
        targets |= {"--synthetic-log": log_path,
                    "the synthetic log's truth (.truth.json beside it)": log_path.with_suffix(".truth.json")}
    seen: dict = {}
    for what, path in targets.items():
        key = os.path.realpath(path)
        if key in seen:
            raise ConfigError(f"{what} {path} is the same file as {seen[key][0]} {seen[key][1]}: give another name")
        seen[key] = (what, path)
    for what, path in targets.items():
        if path.is_dir():
            raise ConfigError(f"{what} {path} is a directory")
        if (path.exists() or path.is_symlink()) and not force:
            raise ConfigError(f"{what} {path} exists; give --force to replace it, or another name")


def cmd_excite(args) -> int:
    """``rc3r excite``: writes the trajectory CSV and its coefficients (.json beside it); optionally a log."""
    import json

    import numpy as np

    from ..identify.excitation import check_length, excite, limits_of
    from ..identify.log import save_log
    from ..io import atomic_write_text
    from ..provenance import provenance

    out = Path(args.out)
    if out.suffix.lower() != ".csv":
        raise ConfigError(f"--out {out} must name a .csv file")
    if out.is_dir():
        raise ConfigError(f"--out {out} is a directory; give a .csv file")
    log_path = None if args.synthetic_log is None else Path(args.synthetic_log)
    if log_path is not None and log_path.suffix.lower() not in (".csv", ".npz"):
        raise ConfigError(f"--synthetic-log {log_path} must name a .csv or .npz file")
    _excite_targets(out, log_path, args.force)
    check_length(args.duration, args.rate)
    robot = _robot(args)
    lim = limits_of(robot, args.max_velocity, args.max_acceleration)
    _note(f"rc3r excite: {args.harmonics} harmonics per joint over {args.duration:g} s for "
          f"{robot.robot_name or robot.name}, "
          f"seed {args.seed} (SLSQP, {args.starts} start(s)) ...")
    ex = excite(robot, args.duration, seed=args.seed, harmonics=args.harmonics, limits=lim, starts=args.starts,
                check_rate=args.rate)
    t = np.arange(0.0, args.duration + 0.5 / args.rate, 1.0 / args.rate)
    q, qd, qdd = ex.trajectory.evaluate(t)
    n = robot.n
    names = ["t"] + [f"{k}{j}" for k in ("q", "qd", "qdd") for j in range(1, n + 1)]
    table = np.column_stack([t, q, qd, qdd])
    atomic_write_text(out, ",".join(names) + "\n" + "\n".join(",".join(f"{x:.12g}" for x in row) for row in table)
                      + "\n")
    terms = [[int(j), float(A), float(w), float(ph)] for j, A, w, ph in ex.trajectory.terms]
    meta = ex.describe() | {"config": {"trajectory": {"kind": "sines", "offset": list(ex.trajectory.offset),
                                                      "terms": terms}},
                            "provenance": provenance(seed=args.seed)}
    atomic_write_text(out.with_suffix(".json"), json.dumps(meta, indent=2) + "\n")
    base = ex.baseline_condition
    versus = (f"{base:.4g} ({base / ex.condition:.3g}x worse)" if np.isfinite(base) and np.isfinite(ex.condition)
              else f"{base:.4g}" if np.isfinite(base) else "rank-deficient (infinite)")
    print(f"regressor condition number: {ex.condition:.4g} (column-scaled [Y | viscous, coulomb, offset]); "
          f"the robot's default sine trajectory over the same {args.duration:g} s: {versus}")
    print(f"trajectory: {out} ({t.size} samples at {args.rate:g} Hz), coefficients: {out.with_suffix('.json')}")
    if log_path is not None:
        from ..identify.synthetic import synthetic_log

        _note("rc3r excite: simulating the arm tracking it (friction, sensor noise, encoder, jittered stamps) ...")
        log, truth = synthetic_log(robot, ex.trajectory, args.duration, seed=args.seed)
        save_log(log, log_path)
        truth_path = log_path.with_suffix(".truth.json")
        atomic_write_text(truth_path, json.dumps({k: (v.tolist() if hasattr(v, "tolist") else v)
                                                  for k, v in truth.items()}, indent=2) + "\n")
        print(f"synthetic log: {log_path} ({log.samples} samples), its true coefficients: {truth_path}")
    return EXIT["ok"]
