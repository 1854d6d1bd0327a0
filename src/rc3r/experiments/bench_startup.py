"""The fresh-process rows of ``rc3r bench`` (full mode): compilation, the cold start, peak memory.

Each starts a new interpreter (``subprocess``), so that what it measures is what a user's first
command pays:

* :func:`bench_compile` -- cold (``NUMBA_CACHE_DIR`` a fresh empty directory) vs warm (the same
  directory again): import, first torque call, first continuous and first sampled simulation of
  the 3R, under ``RC3R_COLD_START=compile`` (inherited from ``rc3r bench``);
* :func:`bench_cold_start` -- the speed issue's cold start, ``rc3r run --robot ur5 --controller fbl
  --rate 1000 --duration 1`` with an empty numba cache and the default policy, end to end;
* :func:`bench_memory` -- peak resident memory of ``rc3r paper``.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ._report import _progress

__all__ = ["bench_compile", "bench_cold_start", "bench_memory", "COLD_START_COMMAND", "COLD_START_TARGET_S"]


# ---- subprocess measurements ------------------------------------------------------------

_COMPILE_SCRIPT = r"""
import json, sys, time
t0 = time.perf_counter()
import numpy as np
import rc3r.robots.rr3.regressor as reg, rc3r.runspec as S
t1 = time.perf_counter()
z = np.zeros((4, 3))
reg.inverse_dynamics(np.ones(15), z, z, z, l2=0.5)
t2 = time.perf_counter()
res, _ = S.execute(S.build_run(controller="robust", perturbed=True, eps=0.5, duration=0.1))
t3 = time.perf_counter()
res2, _ = S.execute(S.build_run(controller="fbl", perturbed=True, rate=1000.0, duration=0.1))
t4 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "first_inverse_dynamics_s": t2 - t1,
                  "first_continuous_sim_s": t3 - t2, "first_sampled_sim_s": t4 - t3,
                  "ok": bool(res.ok and res2.ok)}))
"""


def _clean_env(**extra) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(extra)
    env.setdefault("MPLBACKEND", "Agg")
    return env


def bench_compile() -> dict:
    """Cold (empty NUMBA_CACHE_DIR) vs warm (same dir) start, each a fresh interpreter."""
    out = {"script": "import rc3r.robots.rr3.regressor, rc3r.runspec; inverse_dynamics on 4 states; "
                     "robust-perturbed 0.1 s continuous; fbl-perturbed 0.1 s sampled 1 kHz"}
    cache = tempfile.mkdtemp(prefix="rc3r-numba-cache-")
    try:
        for label in ("cold", "warm"):
            _progress(f"compile: {label} start in a subprocess (NUMBA_CACHE_DIR = {cache}) ...")
            t0 = time.perf_counter()
            p = subprocess.run([sys.executable, "-c", _COMPILE_SCRIPT], capture_output=True, text=True,
                               env=_clean_env(NUMBA_CACHE_DIR=cache), timeout=900)
            wall = time.perf_counter() - t0
            if p.returncode != 0:
                out[label] = {"error": (p.stderr.strip().splitlines() or ["failed"])[-1]}
                continue
            r = json.loads(p.stdout.strip().splitlines()[-1])
            r["process_wall_s"] = wall
            out[label] = r
        size = sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(cache) for f in fs)
        out["cache_bytes"] = size
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    if "process_wall_s" in out.get("cold", {}) and "process_wall_s" in out.get("warm", {}):
        out["saved_by_cache_s"] = out["cold"]["process_wall_s"] - out["warm"]["process_wall_s"]
    return out


#: The speed issue's cold start: this ``rc3r`` command line, in a fresh interpreter, empty numba cache.
COLD_START_COMMAND = ("run", "--robot", "ur5", "--controller", "fbl", "--rate", "1000", "--duration", "1")
#: Its target [s], end to end (imports, arm, simulation, files, figure; the install not counted).
COLD_START_TARGET_S = 5.0


def bench_cold_start() -> dict:
    """``rc3r run --robot ur5 --controller fbl --rate 1000 --duration 1`` (:data:`COLD_START_COMMAND`) as a
    fresh process with an empty numba cache (``NUMBA_CACHE_DIR`` a new directory, ``RC3R_COLD_START``
    unset: the default policy), then again on the same cache: process wall time [s], the engine
    the run used (its metrics.json), exit code."""
    cache = tempfile.mkdtemp(prefix="rc3r-cold-start-")
    code = "import sys; from rc3r.cli import entry; sys.argv = ['rc3r'] + sys.argv[1:]; entry()"
    out = {"command": "rc3r " + " ".join(COLD_START_COMMAND), "target_s": COLD_START_TARGET_S}
    try:
        for label in ("cold", "warm"):
            dest = os.path.join(cache, f"out-{label}")
            _progress(f"cold start: {label} `{out['command']}` in a fresh interpreter ...")
            env = _clean_env(NUMBA_CACHE_DIR=os.path.join(cache, "numba"))
            env.pop("RC3R_COLD_START", None)
            t0 = time.perf_counter()
            p = subprocess.run([sys.executable, "-c", code, *COLD_START_COMMAND, "--out", dest],
                               capture_output=True, text=True, env=env, timeout=900)
            row = {"wall_s": time.perf_counter() - t0, "returncode": p.returncode}
            try:
                row["engine"] = json.loads(Path(dest, "metrics.json").read_text())["engine"]
            except (OSError, ValueError, KeyError):
                row["engine"] = None
                row["error"] = (p.stderr.strip().splitlines() or ["no metrics.json"])[-1]
            out[label] = row
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    cold = out.get("cold", {})
    out["met"] = bool(cold.get("returncode") == 0 and cold.get("wall_s", 1e9) <= COLD_START_TARGET_S)
    return out


_MEMORY_WRAPPER = r"""
import json, resource, subprocess, sys, time
t0 = time.perf_counter()
p = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
wall = time.perf_counter() - t0
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"returncode": p.returncode, "ru_maxrss": ru.ru_maxrss, "wall_s": wall,
                  "stderr_tail": p.stderr.strip().splitlines()[-1:] }))
"""


def bench_memory() -> dict:
    """Peak RSS of ``rc3r paper --out <tmp>``, measured by a wrapper whose only child it is."""
    tmp = tempfile.mkdtemp(prefix="rc3r-bench-paper-")
    try:
        cmd = [sys.executable, "-c", "import sys; from rc3r.cli import main; sys.exit(main(sys.argv[1:]))",
               "paper", "--out", tmp]
        _progress("memory: `rc3r paper` in a subprocess (about 15 s) ...")
        p = subprocess.run([sys.executable, "-c", _MEMORY_WRAPPER, *cmd], capture_output=True, text=True,
                           env=_clean_env(), timeout=1800)
        if p.returncode != 0:
            return {"command": "rc3r paper --out <tmpdir>", "error": (p.stderr.strip().splitlines() or ["?"])[-1]}
        r = json.loads(p.stdout.strip().splitlines()[-1])
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    # Linux reports kilobytes, macOS bytes
    scale = 1 if sys.platform == "darwin" else 1024
    return {"command": "rc3r paper --out <tmpdir>", "peak_rss_bytes": int(r["ru_maxrss"]) * scale,
            "peak_rss_mib": int(r["ru_maxrss"]) * scale / 2 ** 20, "wall_s": r["wall_s"],
            "returncode": r["returncode"], "method": "resource.getrusage(RUSAGE_CHILDREN).ru_maxrss "
            "of a wrapper process whose only child is the command"}
