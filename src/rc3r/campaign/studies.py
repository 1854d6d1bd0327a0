r"""The three campaigns: Monte Carlo over the box, the eps sweep, the sample-rate map.

Each is a list of :class:`~rc3r.campaign.jobs.Job` (built here) run by
:func:`~rc3r.campaign.runner.run_many`, and a summary of the finished rows.

* :func:`montecarlo_jobs` -- N plants drawn uniformly from the simulable part of the
  box (plant k from ``random:<plant_seed(seed, k)>``), every controller on every plant,
  at ``--rate`` or else the config's ``[simulation] rate`` (its jobs and rows say which);
  :func:`montecarlo_summary` per controller: counts, quantiles of the max error, the
  fraction of plants inside the law's ball and how often a robust law's error exceeded
  its predicted bound (:mod:`rc3r.controllers.guarantee`).
* :func:`eps_jobs` / :func:`eps_summary` -- the robust law over eps, continuous and at
  given rates: final error bound against chattering.
* :func:`rate_jobs` / :func:`rate_map` -- the robust law over eps x rate x K, sampled
  over the full duration, each cell classified (:func:`classify`) against the
  continuous-time run of the same eps and K (a scalar K, a per-joint K as a tuple,
  or the config's/law's default; :func:`gain_label` names it):

  - ``diverged`` -- the run left its bounds (:mod:`rc3r.simulate.status`);
  - ``chattering`` -- it finished, but the torque's total variation per second is more
    than :data:`CHATTER_RATIO` times the continuous-time run's (a smooth torque has
    the same total variation on any fine grid; chattering multiplies it);
  - ``clean`` -- otherwise.
"""
from __future__ import annotations

import json
import math

import numpy as np

from ..errors import ConfigError
from ..simulate.verdict import VERDICTS
from .jobs import Job, plant_seed

__all__ = ["montecarlo_jobs", "montecarlo_summary", "eps_jobs", "eps_summary", "rate_jobs", "rate_map",
           "classify", "CHATTER_RATIO", "model_radii", "config_rate", "gain_label"]

#: A sampled run chatters when its total variation of u per second exceeds this multiple
#: of the continuous-time run's (docs/robustness.md).
CHATTER_RATIO = 10.0


def _cfg(config) -> str:
    return json.dumps(config or {}, sort_keys=True)


def config_rate(config) -> float | None:
    """The controller rate [Hz] of a config's ``[simulation] rate`` (None: absent or 0, continuous time).

    Raises
    ------
    rc3r.errors.ConfigError
        If the rate is not a non-negative finite number.
    """
    sim = (config or {}).get("simulation", {})
    rate = sim.get("rate") if isinstance(sim, dict) else None
    if rate is None:
        return None
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not math.isfinite(rate) or rate < 0:
        raise ConfigError(f"[simulation] rate = {rate!r}: must be a rate in Hz (> 0), or 0 for continuous time")
    return float(rate) or None


def montecarlo_jobs(n: int, seed: int, controllers, *, eps=None, rate=None, duration=None, robot=None,
                    box=None, config=None) -> list[Job]:
    """Every controller on plants 0..n-1 of the box (plant k: ``random:<plant_seed(seed, k)>``);
    ``eps`` goes to the laws that have one (robust, robust-coeff). ``rate`` None takes the
    config's ``[simulation] rate`` (:func:`config_rate`), so each job names the rate it runs at."""
    from ..controllers import LAWS

    cfg_rate = config_rate(config)
    rate = cfg_rate if rate is None else float(rate)
    cfg = _cfg(config)
    has_eps = {c: any(f in LAWS[c].__dataclass_fields__ for f in ("eps", "eps_i")) for c in controllers}
    return [Job(k, f"random:{plant_seed(seed, k)}", c, eps if has_eps[c] else None, rate, duration, robot, box, cfg)
            for k in range(n) for c in controllers]


def model_radii(job: Job) -> dict:
    """theta_0 and the radii of a campaign's model: ``rho`` (the run's, e.g. the paper's method (a))
    and ``rho_max`` (certified: the smallest rho around the same theta_0 that covers the whole box)."""
    from ..runspec import build_run

    cfg = json.loads(job.config)
    kw = dict(robot=job.robot, controller="robust", perturbed=True, plant="nominal", box=job.box,
              duration=job.duration)
    run = build_run(config=cfg, **kw).model
    cert_cfg = dict(cfg, model=dict(cfg.get("model", {}), rho="certified"))
    cert = build_run(config=cert_cfg, **kw).model
    return {"theta0": run["theta0"], "rho": run["rho"], "rho_source": run["rho_source"], "rho_max": cert["rho"],
            "box": run["box"]}


def _q(x, p):
    return float(np.quantile(x, p)) if len(x) else None


def montecarlo_summary(rows: list[dict]) -> dict:
    """Per controller: runs, ok, diverged, every verdict's count (``verdicts``: clean, chattering, saturated,
    limit-violated, diverged, interrupted), max error quantiles, and the bound check (robust laws)."""
    from ..simulate.verdict import VERDICTS

    out = {}
    for c in sorted({r["controller"] for r in rows}):
        rs = [r for r in rows if r["controller"] == c]
        ok = [r for r in rs if r["status"] == "ok"]
        err = np.array([r["max_error"] for r in ok])
        cov = [r for r in rs if r["covered"]]
        checked = [r for r in cov if r["exceeds_bound"] is not None]
        verdicts = {v: sum(1 for r in rs if r.get("verdict") == v) for v in reversed(VERDICTS)}
        verdicts["diverged"] += sum(1 for r in rs if not r.get("verdict") and r["status"] != "ok")
        out[c] = {
            "runs": len(rs), "ok": len(ok), "diverged": len(rs) - len(ok), "verdicts": verdicts,
            "max_error_median": _q(err, 0.5), "max_error_p95": _q(err, 0.95),
            "max_error_max": float(err.max()) if err.size else None,
            "final_error_median": _q([r["final_error"] for r in ok], 0.5),
            "chattering_median": _q([r["chattering"] for r in ok], 0.5),
            "inside_ball": len(cov) if rs[0]["covered"] is not None else None,
            "bound_checked": len(checked) if checked else None,
            "bound_exceeded": sum(bool(r["exceeds_bound"]) for r in checked) if checked else None,
            "predicted_bound_median": _q([r["predicted_bound"] for r in checked], 0.5) if checked else None,
        }
    return out


def eps_jobs(eps_values, rates=(None,), *, n_plants: int = 0, seed: int = 0, duration=None, robot=None,
             box=None, config=None, controller: str = "robust", tag: str = "") -> list[Job]:
    """The robust law over ``eps_values`` at each rate (None = continuous), on the nominal plant
    (the paper's perturbed scenario) or on ``n_plants`` plants of the box. A config's
    ``[simulation] rate`` is checked but not used: these rates are the sweep's."""
    config_rate(config)
    cfg = _cfg(config)
    plants = [(-1, "nominal")] if n_plants == 0 else [(k, f"random:{plant_seed(seed, k)}") for k in range(n_plants)]
    return [Job(k, spec, controller, float(e), r, duration, robot, box, cfg, tag)
            for k, spec in plants for r in rates for e in eps_values]


def eps_summary(rows: list[dict]) -> list[dict]:
    """Per (rate, eps): worst final error, worst chattering and the statuses over the plants."""
    out = []
    keys = sorted({(r["rate_hz"] or 0.0, r["eps"]) for r in rows})
    for rate, eps in keys:
        rs = [r for r in rows if (r["rate_hz"] or 0.0) == rate and r["eps"] == eps]
        ok = [r for r in rs if r["status"] == "ok"]
        out.append({"rate_hz": rate or None, "eps": eps, "runs": len(rs), "diverged": len(rs) - len(ok),
                    "final_error": max((r["final_error"] for r in ok), default=None),
                    "max_error": max((r["max_error"] for r in ok), default=None),
                    "chattering": max((r["chattering"] for r in ok), default=None)})
    return out


def rate_jobs(eps_values, rates, k_values=(None,), *, n_plants: int = 0, seed: int = 0, duration=None,
              robot=None, box=None, config=None) -> list[Job]:
    """eps x (continuous, rates...) x K on the nominal plant (or ``n_plants`` plants of the box)."""
    jobs = []
    for k in k_values:
        cfg = dict(config or {})
        if k is not None:
            gains = dict(cfg.get("gains", {}))
            gains["robust"] = dict(gains.get("robust", {}), K=float(k))
            cfg["gains"] = gains
        jobs += eps_jobs(eps_values, (None,) + tuple(rates), n_plants=n_plants, seed=seed, duration=duration,
                         robot=robot, box=box, config=cfg, tag="" if k is None else f"K={float(k)!r}")
    return jobs


def classify(row: dict, reference: dict | None) -> str:
    """``diverged``, ``chattering`` or ``clean`` (module docstring); ``reference`` is the
    continuous-time row of the same plant, eps and K."""
    if row["status"] != "ok":
        return "diverged"
    if reference is None or reference["status"] != "ok":
        return "clean"
    return "chattering" if row["chattering"] > CHATTER_RATIO * reference["chattering"] else "clean"


def _gain(job: Job):
    """The robust law's K of a job's config: None, a float, or a per-joint tuple of floats (hashable)."""
    k = json.loads(job.config).get("gains", {}).get("robust", {}).get("K")
    if isinstance(k, (list, tuple)):
        return tuple(float(x) for x in k)
    return None if k is None else float(k)


def gain_label(k) -> str:
    """Short text of a rate map's key: ``default``, ``50`` or ``[151, 192, 41.9]`` (3 digits)."""
    if k is None or k == "default":
        return "default"
    if isinstance(k, (list, tuple)):
        return "[" + ", ".join(f"{x:.3g}" for x in k) + "]"
    return f"{k:g}"


def rate_map(rows: list[dict], jobs: list[Job]) -> dict:
    """``{K: {"eps": [...], "rates": [...], "cells": [[class per rate] per eps], "safe_rate": {eps: Hz}}}``.

    K is ``"default"`` (the law's), a float, or a tuple of floats (a per-joint K, from
    the config's ``[gains.robust] K = [...]``). A cell is the worst class over the plants (diverged > chattering > clean);
    ``safe_rate[eps]`` is the lowest rate from which every higher rate is clean (None if none is).
    """
    by_id = {r["job"]: r for r in rows}
    order = {"clean": 0, "chattering": 1, "diverged": 2}
    maps = {}
    for job in jobs:
        if job.rate is None or job.id not in by_id:
            continue
        ref_id = Job(job.plant, job.spec, job.controller, job.eps, None, job.duration, job.robot, job.box,
                     job.config, job.tag).id
        cls = classify(by_id[job.id], by_id.get(ref_id))
        m = maps.setdefault(_gain(job), {})
        key = (job.eps, job.rate)
        if order[cls] >= order.get(m.get(key, "clean"), 0):
            m[key] = cls
    out = {}
    for k, m in maps.items():
        eps = sorted({e for e, _ in m})
        rates = sorted({r for _, r in m})
        cells = [[m.get((e, r), "missing") for r in rates] for e in eps]
        safe = {}
        for e, row in zip(eps, cells):
            s = None
            for r, c in zip(reversed(rates), reversed(row)):
                if c != "clean":
                    break
                s = r
            safe[e] = s
        out["default" if k is None else k] = {"eps": eps, "rates": rates, "cells": cells, "safe_rate": safe}
    return out
