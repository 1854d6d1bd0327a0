r"""``bounds.toml``: the identified bounds a robust controller is designed from.

Written by ``rc3r identify`` (:func:`write_bounds`), read by :func:`load_bounds`. Keys:

=====================  ===============================================================
``format``             ``"rc3r-bounds/2"`` (written), or ``"rc3r-bounds/1"`` (still read)
``robot``              registry name of the arm (``"ur5"``, ``"rr3"``), or absent
``urdf``               the URDF it was identified with, or absent (one of the two is given)
``lock``               joints locked in that URDF (table name -> value), optional
``n``, ``p``           joints and coefficients (/2: the rigid ones and the joint ones)
``coefficient_names``  the p coefficients, in order (the robot's ``coefficient_names``; /2: then
                       :func:`~rc3r.identify.regressors.friction_names` of ``[actuator].kinds``)
``confidence``         level C of the ellipsoid
``quantile``           the quantile q it used (``chi2_p(C)`` or ``p F_{p,nu}(C)``)
``seed``               the seed of the identification
``theta0``             (p,) the estimate
``P``                  (p, p) the ellipsoid ``(theta - theta0)^T P (theta - theta0) <= 1``
``rho``                radius of the smallest ball about theta0 containing it (eq. 6's bound)
``rho_i``              (p,) half-widths of the smallest box containing it (eq. 7's bounds)
``[actuator]``         /2 only: ``kinds`` (joint-column kinds, :data:`~rc3r.identify.regressors.JOINT_KINDS`
                       order), ``coulomb_velocity`` (``v_s`` [rad/s] of ``tanh(qd / v_s)``),
                       ``rigid_p`` (the robot's p: the first ``rigid_p`` coefficients are rigid),
                       ``merged`` (optional: armature names -> the rigid coefficient holding them)
``[physical]``         optional: the link parameters of the centre (the physically consistent
                       estimate, :mod:`rc3r.identify.physical`): ``standard_parameters`` (10 nb,),
                       ``log_cholesky`` (10 nb,) and ``log_cholesky_cov`` (10 nb, 10 nb), the
                       Laplace covariance plants are drawn with; ``gamma``, ``masses``,
                       ``draws_inside`` (for the record)
``[identification]``   log, digest, filter, noise (for the record)
``[provenance]``       versions, git commit, command line, time
=====================  ===============================================================

In a /2 file ``theta0``, ``P``, ``rho``, ``rho_i`` are over all ``p`` coefficients, rigid and joint
(:meth:`rc3r.identify.pipeline.Identification.actuator_bounds`). :func:`load_bounds` returns, as for a /1
file, the rigid coefficients' bounds (the projection of the ellipsoid onto them: ``P_r = ((P^-1)_rr)^-1``,
its ball and box), so callers that know only the rigid model read either format unchanged, and the whole
ellipsoid under ``"actuator"``.

Every refusal of :func:`load_bounds` is one :class:`~rc3r.errors.ConfigError` (a missing or
malformed file, a missing or mistyped key, wrong lengths) or
:class:`~rc3r.errors.ParameterError` (non-finite numbers, ``P`` not symmetric positive
definite, ``rho`` or ``rho_i`` that do not contain the ellipsoid, a robot of other sizes or
coefficients).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..errors import ConfigError, ParameterError

__all__ = ["FORMAT", "FORMAT_V1", "write_bounds", "load_bounds", "to_toml"]

#: The format written (joint coefficients included); :data:`FORMAT_V1` (rigid only) is still read.
FORMAT = "rc3r-bounds/2"
FORMAT_V1 = "rc3r-bounds/1"

#: Relative slack of the containment checks (ball and box around the ellipsoid).
CONTAIN_RTOL = 1e-9


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        x = float(v)
        if not math.isfinite(x):
            raise ParameterError(f"cannot write a non-finite number ({x}) to a bounds file")
        return repr(x)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v if x is not None) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {_value(x)}" for k, x in v.items() if x is not None) + "}"
    return json.dumps(str(v))


def to_toml(data: dict, header: str = "") -> str:
    """A small TOML writer: scalars, strings, (nested) lists first, then sub-tables; ``None`` omitted."""
    lines = [f"# {line}" for line in header.splitlines()]

    def emit(prefix, table):
        scalars = {k: v for k, v in table.items() if v is not None and not isinstance(v, dict)}
        subs = {k: v for k, v in table.items() if isinstance(v, dict)}
        if prefix:
            lines.append(f"\n[{prefix}]")
        for k, v in scalars.items():
            lines.append(f"{json.dumps(str(k)) if not str(k).isidentifier() else k} = {_value(v)}")
        for k, v in subs.items():
            emit(f"{prefix}.{k}" if prefix else str(k), v)

    emit("", data)
    return "\n".join(lines) + "\n"


def write_bounds(path, bounds: dict, robot, *, robot_name: str | None = None, urdf: str | None = None,
                 lock: dict | None = None, seed: int = 0, identification: dict | None = None,
                 provenance: dict | None = None) -> Path:
    """Write ``bounds`` (``theta0, P, rho, rho_i, confidence, chi2``) of ``robot`` to ``path`` atomically.

    With ``bounds["actuator"]`` (:meth:`~rc3r.identify.pipeline.Identification.actuator_bounds`: joint
    columns identified) the file is ``rc3r-bounds/2`` over rigid and joint coefficients, else /1.
    """
    from ..io import atomic_write_text

    act = bounds.get("actuator")
    if act is not None and not act.get("kinds"):
        act = None
    src = bounds if act is None else act
    names = list(robot.coefficient_names) if act is None else list(act["coefficient_names"])
    data = {"format": FORMAT_V1 if act is None else FORMAT, "robot": robot_name,
            "urdf": None if urdf is None else str(urdf), "n": int(robot.n), "p": len(names),
            "coefficient_names": names, "confidence": float(bounds["confidence"]),
            "quantile": float(src["quantile"] if act is not None else bounds["chi2"]), "seed": int(seed),
            "theta0": np.asarray(src["theta0"], float), "rho": float(src["rho"]),
            "rho_i": np.asarray(src["rho_i"], float), "P": np.asarray(src["P"], float)}
    if act is not None:
        data["actuator"] = {"kinds": list(act["kinds"]), "coulomb_velocity": float(act["coulomb_velocity"]),
                            "rigid_p": int(act["rigid_p"]), "merged": dict(act.get("merged") or {}) or None}
    if lock:
        data["lock"] = {str(k): float(v) for k, v in lock.items()}
    if bounds.get("physical") is not None:
        data["physical"] = {k: (np.asarray(v, float) if isinstance(v, (list, tuple, np.ndarray)) else v)
                            for k, v in bounds["physical"].items()}
    if identification:
        data["identification"] = identification
    if provenance:
        data["provenance"] = provenance
    header = ("Bounds on the dynamic coefficients identified from a log (rc3r identify).\n"
              "(theta - theta0)^T P (theta - theta0) <= 1 at the confidence level; ||theta - theta0|| <= rho;\n"
              "|theta_i - theta0_i| <= rho_i. Read with rc3r.identify.bounds_file.load_bounds.")
    return atomic_write_text(path, to_toml(data, header))


def _numbers(path, key, value, shape) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"bounds file {path}: {key} must be numbers") from None
    if arr.shape != shape:
        raise ConfigError(f"bounds file {path}: {key} has shape {arr.shape}, expected {shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"bounds file {path}: {key} has non-finite entries")
    return arr


def _physical(path, table, robot):
    """The validated ``[physical]`` table (ndarrays) or None."""
    if table is None:
        return None
    if not isinstance(table, dict):
        raise ConfigError(f"bounds file {path}: physical must be a table")
    for key in ("standard_parameters", "log_cholesky", "log_cholesky_cov"):
        if key not in table:
            raise ConfigError(f"bounds file {path}: [physical] lacks {key!r}")
    k = len(table["log_cholesky"]) if isinstance(table["log_cholesky"], list) else -1
    if k <= 0 or k % 10:
        raise ConfigError(f"bounds file {path}: [physical] log_cholesky must be 10 numbers per link")
    if robot is not None and k != len(robot.standard_parameter_names):
        raise ParameterError(f"bounds file {path}: [physical] has {k // 10} links, robot '{robot.label}' has "
                             f"{len(robot.standard_parameter_names) // 10}")
    out = dict(table)
    out["log_cholesky"] = _numbers(path, "physical.log_cholesky", table["log_cholesky"], (k,))
    out["standard_parameters"] = _numbers(path, "physical.standard_parameters", table["standard_parameters"], (k,))
    C = _numbers(path, "physical.log_cholesky_cov", table["log_cholesky_cov"], (k, k))
    if not np.allclose(C, C.T, rtol=1e-9, atol=1e-12 * max(np.abs(C).max(), 1e-300)):
        raise ParameterError(f"bounds file {path}: physical.log_cholesky_cov is not symmetric")
    if np.linalg.eigvalsh(0.5 * (C + C.T))[0] < -1e-9 * max(np.abs(C).max(), 1e-300):
        raise ParameterError(f"bounds file {path}: physical.log_cholesky_cov is not positive semidefinite")
    out["log_cholesky_cov"] = C
    for v in (out["log_cholesky"], out["standard_parameters"], C):
        v.flags.writeable = False
    return out


def _actuator(path, table, n: int, names) -> dict:
    """The validated ``[actuator]`` table of a /2 file: ``kinds``, ``coulomb_velocity``, ``rigid_p``, ``merged``."""
    from .regressors import JOINT_KINDS, friction_names

    if not isinstance(table, dict):
        raise ConfigError(f"bounds file {path}: format {FORMAT!r} needs an [actuator] table")
    unknown = sorted(set(table) - {"kinds", "coulomb_velocity", "rigid_p", "merged"})
    if unknown:
        raise ConfigError(f"bounds file {path}: unknown key(s) in [actuator]: {', '.join(unknown)}")
    kinds = table.get("kinds")
    if not (isinstance(kinds, list) and kinds and all(isinstance(k, str) for k in kinds)):
        raise ConfigError(f"bounds file {path}: [actuator] kinds must be a non-empty list of strings")
    bad = [k for k in kinds if k not in JOINT_KINDS]
    if bad or len(set(kinds)) != len(kinds) or list(kinds) != [k for k in JOINT_KINDS if k in kinds]:
        raise ConfigError(f"bounds file {path}: [actuator] kinds {kinds} must be distinct, in the order "
                          f"{', '.join(JOINT_KINDS)}")
    v_s = table.get("coulomb_velocity", 0.0)
    if isinstance(v_s, bool) or not isinstance(v_s, (int, float)) or not (math.isfinite(v_s) and v_s >= 0):
        raise ConfigError(f"bounds file {path}: [actuator] coulomb_velocity must be a number >= 0, got {v_s!r}")
    rp = table.get("rigid_p")
    if isinstance(rp, bool) or not isinstance(rp, int) or rp <= 0:
        raise ConfigError(f"bounds file {path}: [actuator] rigid_p must be a positive integer, got {rp!r}")
    want = tuple(friction_names(kinds, n))
    if rp + len(want) != len(names) or tuple(names[rp:]) != want:
        raise ConfigError(f"bounds file {path}: coefficient_names must be the {rp} rigid coefficients then "
                          f"{', '.join(want)} ([actuator] kinds), got {len(names)} names")
    merged = table.get("merged", {})
    if not isinstance(merged, dict) or not all(isinstance(v, str) for v in merged.values()):
        raise ConfigError(f"bounds file {path}: [actuator] merged must be a table of name = \"coefficient\"")
    return {"kinds": list(kinds), "coulomb_velocity": float(v_s), "rigid_p": rp, "merged": dict(merged)}


def load_bounds(path, robot=None) -> dict:
    """Read and validate a ``bounds.toml`` (module docstring); optionally check it fits ``robot``.

    Returns
    -------
    dict
        ``theta0`` (p,), ``rho`` (float), ``rho_i`` (p,), ``P`` (p, p) (ndarrays, read-only),
        ``n``, ``p``, ``robot`` (str or None), ``urdf`` (str or None), ``lock`` (dict),
        ``coefficient_names`` (tuple), ``confidence``, ``quantile``, ``seed``, ``format``,
        ``source`` (the path), ``identification``, ``provenance`` (dicts, possibly empty),
        ``physical`` (the validated ``[physical]`` table, or None). For a /2 file these are the rigid
        coefficients' (``p`` the robot's; ``theta0``, ``P``, ``rho``, ``rho_i`` the projection of the
        ellipsoid onto them) and ``actuator`` is ``{"kinds", "coulomb_velocity", "rigid_p",
        "coefficient_names" (all), "theta0" (p + m,), "P" (p + m, p + m), "rho", "rho_i" (p + m,),
        "merged" (dict)}``; for a /1 file ``actuator`` is None.
    """
    from ..io import read_toml

    data = read_toml(path, "bounds file")
    fmt = data.get("format")
    if fmt not in (FORMAT, FORMAT_V1):
        raise ConfigError(f"bounds file {path}: format must be {FORMAT!r} or {FORMAT_V1!r}, got {fmt!r}")
    known = {"format", "robot", "urdf", "lock", "n", "p", "coefficient_names", "confidence", "quantile", "seed",
             "theta0", "rho", "rho_i", "P", "identification", "provenance", "physical"} | (
        {"actuator"} if fmt == FORMAT else set())
    unknown = sorted(set(data) - known)
    if unknown:
        raise ConfigError(f"bounds file {path}: unknown key(s) {', '.join(unknown)}")
    for key in ("n", "p", "theta0", "rho", "rho_i", "P", "coefficient_names", "confidence"):
        if key not in data:
            raise ConfigError(f"bounds file {path}: missing key {key!r}")
    n, p = data["n"], data["p"]
    if not (isinstance(n, int) and isinstance(p, int) and n > 0 and p > 0) or isinstance(n, bool) or isinstance(p, bool):
        raise ConfigError(f"bounds file {path}: n and p must be positive integers, got {n!r}, {p!r}")
    robot_name, urdf = data.get("robot"), data.get("urdf")
    if robot_name is None and urdf is None:
        raise ConfigError(f"bounds file {path}: names no robot (give robot = NAME or urdf = PATH)")
    for key, v in (("robot", robot_name), ("urdf", urdf)):
        if v is not None and not isinstance(v, str):
            raise ConfigError(f"bounds file {path}: {key} must be a string, got {v!r}")
    lock = data.get("lock", {})
    if not isinstance(lock, dict) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                             for v in lock.values()):
        raise ConfigError(f"bounds file {path}: lock must be a table of joint = value")
    names = data["coefficient_names"]
    if not (isinstance(names, list) and len(names) == p and all(isinstance(s, str) for s in names)):
        raise ConfigError(f"bounds file {path}: coefficient_names must be {p} strings")
    conf = data["confidence"]
    if isinstance(conf, bool) or not isinstance(conf, (int, float)) or not 0.0 < conf < 1.0:
        raise ConfigError(f"bounds file {path}: confidence must be a number between 0 and 1, got {conf!r}")
    theta0 = _numbers(path, "theta0", data["theta0"], (p,))
    rho_i = _numbers(path, "rho_i", data["rho_i"], (p,))
    P = _numbers(path, "P", data["P"], (p, p))
    rho = _numbers(path, "rho", data["rho"], ())
    if rho < 0 or np.any(rho_i < 0):
        raise ParameterError(f"bounds file {path}: rho and rho_i must be >= 0")
    if not np.allclose(P, P.T, rtol=1e-9, atol=1e-12 * np.abs(P).max()):
        raise ParameterError(f"bounds file {path}: P is not symmetric")
    try:
        np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        raise ParameterError(f"bounds file {path}: P is not positive definite (not an ellipsoid)") from None
    Pinv = np.linalg.inv(P)
    if rho < np.sqrt(np.linalg.eigvalsh(Pinv)[-1]) * (1 - CONTAIN_RTOL):
        raise ParameterError(f"bounds file {path}: rho = {float(rho):.6g} does not contain the ellipsoid P "
                             f"(its largest semi-axis is {np.sqrt(np.linalg.eigvalsh(Pinv)[-1]):.6g})")
    short = np.nonzero(rho_i < np.sqrt(np.diag(Pinv)) * (1 - CONTAIN_RTOL))[0]
    if short.size:
        raise ParameterError(f"bounds file {path}: rho_i of {names[short[0]]} does not contain the ellipsoid P")
    act = _actuator(path, data.get("actuator"), n, names) if fmt == FORMAT else None
    if act is not None:
        rp = act["rigid_p"]
        act |= {"coefficient_names": list(names), "theta0": theta0, "P": P, "rho": float(rho), "rho_i": rho_i}
        Pinv_r = Pinv[:rp, :rp]
        P_r = np.linalg.inv(0.5 * (Pinv_r + Pinv_r.T))
        theta0, P, rho_i = theta0[:rp].copy(), 0.5 * (P_r + P_r.T), rho_i[:rp].copy()
        rho = np.sqrt(np.linalg.eigvalsh(Pinv_r)[-1])
        p, names = rp, names[:rp]
    if robot is not None:
        if (robot.n, robot.p) != (n, p):
            raise ParameterError(f"bounds file {path} is for an arm with n = {n}, p = {p}; robot "
                                 f"'{robot.label}' has n = {robot.n}, p = {robot.p}")
        if tuple(robot.coefficient_names) != tuple(names):
            k = next(i for i, (a, b) in enumerate(zip(robot.coefficient_names, names)) if a != b)
            raise ParameterError(f"bounds file {path}: coefficient {k + 1} is {names[k]!r}, robot "
                                 f"'{robot.label}' calls it {robot.coefficient_names[k]!r} (another arm?)")
    physical = _physical(path, data.get("physical"), robot)
    out = {"theta0": theta0, "rho": float(rho), "rho_i": rho_i, "P": P, "physical": physical, "actuator": act}
    for arr in (theta0, rho_i, P) + ((act["theta0"], act["P"], act["rho_i"]) if act else ()):
        arr.flags.writeable = False
    seed = data.get("seed", 0)
    return out | {"n": n, "p": p, "robot": robot_name, "urdf": urdf, "lock": dict(lock),
                  "coefficient_names": tuple(names), "confidence": float(conf),
                  "quantile": float(data.get("quantile", float("nan"))), "seed": int(seed) if isinstance(seed, int) else 0,
                  "format": fmt, "source": str(path), "identification": dict(data.get("identification", {})),
                  "provenance": dict(data.get("provenance", {}))}
