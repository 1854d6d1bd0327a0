"""The arms table of docs/design.md: ``rc3r design`` then ``rc3r montecarlo`` for every fixed-base arm.

For each arm and each rate it runs (as subprocesses, so each has its own process and wall time)::

    rc3r design --urdf ARM.urdf [--lock J=V ...] --payload 0:3 --rate RATE --n N --duration D \
        --seed SEED --workers W --out OUT/ARM-RATE/design
    rc3r montecarlo --config OUT/ARM-RATE/design/design.toml --n N --duration D --seed SEED \
        --controllers LAW,fbl --workers W --out OUT/ARM-RATE/mc

where LAW is the robust law the design recommends (``recommendation`` in design.json: eq. 6
``robust`` or eq. 7 ``robust-coeff``, whichever was clean on every plant with the smaller worst
error; ``robust`` if neither), or the one ``--mc-law`` names,

and writes ``OUT/design_table.md`` (one row per arm and rate) and ``OUT/design_table.json`` (every
number, the commands, the seed). ``--effects`` adds ``--friction urdf --torque-limit urdf`` to both
commands (for the arms whose URDF has friction and effort limits).

Reduced size (docs/design.md)::

    python benchmarks/design_table.py --out out/design_table --n 10 --duration 5 --rates 500,1000,2000 --workers 1

Full size (the issue's acceptance): ``--n 50 --duration 10``. A rerun into the same ``--out`` skips the
arm-rate pairs already in its ``design_table.json``; ``--merge DIR ...`` writes one table of several
earlier ``--out`` directories (docs/design.md's table: 2026-12-02, ``--n 6 --duration 3``, seed 0).
"""
from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROBOTS = Path(sys.prefix) / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages" / \
    "cmeel.prefix" / "share" / "example-robot-data" / "robots"

#: name -> (URDF under ROBOTS, locked joints): the fixed-base arms of example-robot-data.
ARMS = {
    "ur3": ("ur_description/urdf/ur3_robot.urdf", {}),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", {}),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", {}),
    "panda": ("panda_description/urdf/panda.urdf", {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}),
    "z1": ("z1_description/urdf/z1.urdf", {"jointGripper": 0.0}),
    "kinova": ("kinova_description/robots/kinova.urdf", {}),
    "xarm7": ("xarm_description/urdf/xarm7.urdf", {}),
    "so101": ("so_arm_description/urdf/so101.urdf", {"gripper": 0.0}),
    "double_pendulum": ("double_pendulum_description/urdf/double_pendulum.urdf", {}),
}
DEFAULT_ARMS = "ur5,ur10,panda,z1,kinova,xarm7"


def _rc3r() -> list[str]:
    """The ``rc3r`` console script of this interpreter's environment."""
    return [str(Path(sys.executable).parent / "rc3r")]


def _run(cmd: list[str], log: Path) -> tuple[int, float]:
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        rc = subprocess.run(cmd, stdout=fh, stderr=subprocess.STDOUT).returncode
    return rc, time.perf_counter() - t0


def _rows(path: Path) -> list[dict]:
    if not path.exists():
        return []
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _summary(rows: list[dict], limit) -> dict:
    """Verdict counts, worst max|e|, torque peaks (and peak / limit) of runs.csv rows."""
    if not rows:
        return {"runs": 0}
    n = sum(1 for k in rows[0] if k.startswith("u_max_"))
    err = np.array([float(r["max_error"]) if r["max_error"] not in ("", "nan") else np.nan for r in rows])
    u = np.array([[float(r[f"u_max_{j}"]) if r[f"u_max_{j}"] != "" else np.nan for j in range(1, n + 1)]
                  for r in rows])
    verdicts: dict = {}
    for r in rows:
        verdicts[r["verdict"]] = verdicts.get(r["verdict"], 0) + 1
    out = {"runs": len(rows), "verdicts": verdicts,
           "worst_error": float(np.nanmax(err)) if np.any(np.isfinite(err)) else None,
           "u_peak": np.nanmax(u, axis=0).tolist() if np.any(np.isfinite(u)) else None}
    if limit and out["u_peak"] is not None:
        out["u_over_limit"] = float(np.nanmax(np.asarray(out["u_peak"]) / np.asarray(limit)))
    return out


def one(arm: str, rate: float, args, base: Path) -> dict:
    urdf, lock = ARMS[arm]
    where = base / f"{arm}-{rate:g}"
    where.mkdir(parents=True, exist_ok=True)
    arm_opts = ["--urdf", str(ROBOTS / urdf)] + sum((["--lock", f"{j}={v:g}"] for j, v in lock.items()), [])
    effects = ["--friction", "urdf", "--torque-limit", "urdf"] if args.effects else []
    common = ["--n", str(args.n), "--duration", str(args.duration), "--seed", str(args.seed),
              "--workers", str(args.workers)]
    design_cmd = _rc3r() + ["design"] + arm_opts + ["--payload", "0:3", "--rate", f"{rate:g}"] + effects + \
        common + ["--out", str(where / "design"), "--force"]
    rc_d, wall_d = _run(design_cmd, where / "design.log")
    row = {"arm": arm, "rate": rate, "design_cmd": design_cmd, "design_exit": rc_d, "design_wall_s": wall_d}
    info_path = where / "design" / "design.json"
    if not info_path.exists():
        row["error"] = (where / "design.log").read_text()[-2000:]
        return row
    info = json.loads(info_path.read_text())
    row.update(_design_fields(info))
    limit = info.get("effort_limit")
    # the robust law the design recommends (eq. 6 or eq. 7, design.json), or eq. 6 if it recommends none
    law = args.mc_law if args.mc_law != "recommended" else (info.get("recommendation") or {}).get("law") or "robust"
    mc_cmd = _rc3r() + ["montecarlo", "--config", str(info_path.with_name("design.toml")),
                        "--controllers", f"{law},fbl"] + effects + common + ["--out", str(where / "mc")]
    rc_m, wall_m = _run(mc_cmd, where / "mc.log")
    rows = _rows(where / "mc" / "runs.csv")
    row.update({"mc_cmd": mc_cmd, "mc_exit": rc_m, "mc_wall_s": wall_m, "robust_law": law,
                "mc": {key: _summary([r for r in rows if r["controller"] == name], limit)
                       for key, name in (("robust", law), ("fbl", "fbl"))}})
    return row


def _design_fields(info: dict) -> dict:
    """The numbers of a ``design.json`` the table reports."""
    g = info["gains"]["robust"]
    ch = next((lv for lv in info["levels"] if lv["eps"] == info["eps"]), None)
    base = info.get("baselines", {})
    return {"ok": info["ok"], "K": g["K"], "K_inertia": g.get("K_inertia"), "Lambda": g["Lambda"], "eps": g["eps"],
            "eps_rule": info["design"]["eps"], "eps_stable": info["design"]["eps_stable"],
            "fbl_gains": info["gains"]["fbl"], "effort_limit": info.get("effort_limit"),
            "design_worst_error": None if ch is None else ch["at_rate"]["worst_error"],
            "design_fbl_worst_error": base.get("fbl", {}).get("worst_error"),
            "design_baselines": {law: {k: s.get(k) for k in ("verdicts", "worst_error", "eps_i")}
                                 for law, s in base.items()},
            "bandwidth": info["design"]["bandwidth"], "L_K_over_b": info["design"]["L_K"] / info["design"]["bandwidth"],
            "rho": info["design"]["rho"], "L_Y": info["design"]["L_Y"],
            "lowest_clean_rate": info.get("lowest_clean_rate"), "eps_tried": len(info["levels"]),
            "design_wall_s_inside": info.get("wall_s")}


def _krange(K, b=None) -> str:
    """``min..max`` of K's diagonal, ``(full)`` if K is a matrix; ``b M(q)`` for a scheduled K."""
    if b:
        return f"{b:.3g} M(q)"
    k = np.asarray(K, dtype=float)
    d = np.diag(k) if k.ndim == 2 else k
    return f"{d.min():.3g}..{d.max():.3g}" + (" (full)" if k.ndim == 2 else "")


def _f(x, fmt=".3g") -> str:
    return "-" if x is None else format(x, fmt)


def _v(s: dict | None) -> str:
    if not s or not s.get("verdicts"):
        return "-"
    return ", ".join(f"{v} {k}" for k, v in sorted(s["verdicts"].items()))


def _effects(r: dict) -> bool:
    return "--friction" in (r.get("design_cmd") or [])


def _rc(r: dict) -> str:
    rc = r.get("design_baselines", {}).get("robust-coeff")
    return "-" if not rc else f"{_f(rc.get('worst_error'))} ({_v(rc)})"


def _refresh(rows: list[dict]) -> list[dict]:
    """Re-read each row's design.json (the path after --out in its command)."""
    for r in rows:
        cmd = r.get("design_cmd") or []
        if "--out" in cmd:
            path = Path(cmd[cmd.index("--out") + 1]) / "design.json"
            if path.exists():
                r.update(_design_fields(json.loads(path.read_text())))
    return rows


def markdown(rows: list[dict]) -> str:
    lines = ["| arm | rate [Hz] | b [1/s] (L_K / b) | K [N m s/rad] | Lambda [1/s] | eps | design clean | robust law "
             "(montecarlo) | worst max\\|e\\| robust [rad] | FBL (design) | FBL (montecarlo) | robust / FBL | torque peak / limit | "
             "verdicts robust | verdicts FBL | robust-coeff (design) | wall s (design + mc) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "K" not in r:
            lines.append(f"| {r['arm']} | {r['rate']:g} | design failed (exit {r['design_exit']}) | | | | | | | | | | | | | | "
                         f"{r['design_wall_s']:.0f} |")
            continue
        rob, fbl = r.get("mc", {}).get("robust", {}), r.get("mc", {}).get("fbl", {})
        ratio = (rob["worst_error"] / fbl["worst_error"]) if rob.get("worst_error") and fbl.get("worst_error") else None
        lines.append(
            f"| {r['arm']}{' + URDF friction, limits' if _effects(r) else ''} | {r['rate']:g} | {_f(r.get('bandwidth'))} ({_f(r.get('L_K_over_b'), '.3g')}) | {_krange(r['K'], r.get('K_inertia'))} | {r['Lambda']:.3g} | {r['eps']:.3g} | "
            f"{'yes' if r['ok'] else 'NO'} | {r.get('robust_law', 'robust')} | {_f(rob.get('worst_error'))} | {_f(r.get('design_fbl_worst_error'))} | "
            f"{_f(fbl.get('worst_error'))} | {_f(ratio, '.2g')} | {_f(rob.get('u_over_limit'), '.2g')} | {_v(rob)} | "
            f"{_v(fbl)} | {_rc(r)} | {r['design_wall_s']:.0f} + {r.get('mc_wall_s', 0):.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--n", type=int, default=10, help="random plants per design and per montecarlo (default 10)")
    p.add_argument("--duration", type=float, default=5.0, help="simulated time per run [s] (default 5)")
    p.add_argument("--rates", default="500,1000,2000", help="comma-separated controller rates [Hz]")
    p.add_argument("--arms", default=DEFAULT_ARMS, help=f"comma-separated arms of {', '.join(ARMS)}")
    p.add_argument("--workers", type=int, default=1, help="worker processes of each command (default 1)")
    p.add_argument("--seed", type=int, default=0, help="seed of the design's and the montecarlo's plants")
    p.add_argument("--effects", action="store_true", help="add --friction urdf --torque-limit urdf")
    p.add_argument("--mc-law", default="recommended", choices=("recommended", "robust", "robust-coeff"),
                   help="the robust law of the montecarlo (default: the one the design recommends)")
    p.add_argument("--merge", nargs="+", metavar="DIR",
                   help="write one table of the rows of these earlier --out directories into --out, and stop")
    args = p.parse_args(argv)
    if args.merge:
        rows, metas = [], []
        for d in args.merge:
            data = json.loads((Path(d) / "design_table.json").read_text())
            rows += _refresh(data["rows"])
            metas.append({"dir": d, **data["meta"]})
        order = list(ARMS)
        rows.sort(key=lambda r: (_effects(r), order.index(r["arm"]) if r["arm"] in order else 99, r["rate"]))
        base = Path(args.out)
        base.mkdir(parents=True, exist_ok=True)
        (base / "design_table.json").write_text(json.dumps({"meta": metas, "rows": rows}, indent=1, default=str))
        (base / "design_table.md").write_text(markdown(rows))
        print(markdown(rows))
        return 0
    arms = [a.strip() for a in args.arms.split(",") if a.strip()]
    bad = [a for a in arms if a not in ARMS]
    if bad:
        p.error(f"unknown arm(s) {', '.join(bad)}; known: {', '.join(ARMS)}")
    rates = [float(r) for r in args.rates.split(",") if r.strip()]
    base = Path(args.out)
    base.mkdir(parents=True, exist_ok=True)
    out_json = base / "design_table.json"
    done = json.loads(out_json.read_text())["rows"] if out_json.exists() else []
    have = {(r["arm"], r["rate"]) for r in done}
    rows = list(done)
    t0 = time.perf_counter()
    for rate in rates:  # rate-major: every arm at the first rate before the next rate
        for arm in arms:
            if (arm, rate) in have:
                print(f"{arm} at {rate:g} Hz: in {out_json} already", flush=True)
                continue
            print(f"[{time.strftime('%H:%M:%S')}] {arm} at {rate:g} Hz ...", flush=True)
            r = one(arm, rate, args, base)
            rows.append(r)
            rob = r.get("mc", {}).get("robust", {})
            fbl = r.get("mc", {}).get("fbl", {})
            print(f"    design exit {r['design_exit']} ({r['design_wall_s']:.0f} s), eps {_f(r.get('eps'))}; "
                  f"montecarlo robust {_v(rob)} worst {_f(rob.get('worst_error'))}, fbl {_v(fbl)} worst "
                  f"{_f(fbl.get('worst_error'))}; torque/limit {_f(rob.get('u_over_limit'), '.2g')}", flush=True)
            meta = {"n": args.n, "duration": args.duration, "seed": args.seed, "workers": args.workers,
                    "effects": args.effects, "payload": [0.0, 3.0], "argv": sys.argv}
            from rc3r.provenance import provenance

            out_json.write_text(json.dumps({"meta": meta, "provenance": provenance(seed=args.seed), "rows": rows},
                                           indent=1, default=str))
            (base / "design_table.md").write_text(markdown(rows))
    print(f"done in {time.perf_counter() - t0:.0f} s -> {base}/design_table.md, design_table.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
