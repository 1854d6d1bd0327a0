"""One run of a campaign as data (:class:`Job`), and its execution on a worker (:func:`run_job`).

A job is a handful of strings and numbers: it pickles cheaply for a process pool
or a Dask worker, and the worker rebuilds the run with :func:`rc3r.runspec.build_run`
(the same path as ``rc3r run``). Its :attr:`Job.id` names the row it produces, so a
resumed campaign skips what is done without duplicating a row.
"""
from __future__ import annotations

import json
import os
import socket
from dataclasses import dataclass

import numpy as np

__all__ = ["Job", "plant_seed", "run_job", "columns", "ROW_KEYS", "TIMING_KEYS"]


def plant_seed(seed: int, plant: int) -> int:
    """The seed of plant ``plant`` of a campaign seeded ``seed``: ``SeedSequence([seed, plant])``,
    63 bits (independent streams for every plant, the same on every machine)."""
    return int(np.random.SeedSequence([int(seed), int(plant)]).generate_state(1, np.uint64)[0] >> np.uint64(1))


@dataclass(frozen=True)
class Job:
    """One plant-controller run.

    Attributes
    ----------
    plant : int
        Plant id in the campaign (>= 0), or -1 for a named plant (``spec``).
    spec : str
        Plant spec for :func:`rc3r.runspec.build_run` (``random:<seed>``, ``nominal`` ...).
    controller : str
        A registered law.
    eps : float or None
        Boundary layer of the robust laws (None: the config's or the law's default).
    rate : float or None
        Controller rate [Hz]; None = continuous time (also when the config has a
        ``[simulation] rate``: a job is exactly what its :attr:`id` says).
    duration : float or None
        Simulated time [s] (None: config, else 10).
    robot, box : str or None
        Robot name and box TOML path (None: the config's, else the defaults).
    config : str
        The run configuration as JSON (``"{}"``: none).
    tag : str
        Distinguishes jobs that differ only in ``config`` (e.g. ``K=50.0``); part of :attr:`id`.
    """

    plant: int
    spec: str
    controller: str
    eps: float | None = None
    rate: float | None = None
    duration: float | None = None
    robot: str | None = None
    box: str | None = None
    config: str = "{}"
    tag: str = ""

    @property
    def id(self) -> str:
        """Row key: plant, controller, eps, rate, tag (e.g. ``p0007/robust/eps=default/continuous``)."""
        who = f"p{self.plant:04d}" if self.plant >= 0 else self.spec
        eps = "eps=default" if self.eps is None else f"eps={self.eps!r}"
        rate = "continuous" if self.rate is None else f"rate={self.rate!r}"
        return f"{who}/{self.controller}/{eps}/{rate}" + (f"/{self.tag}" if self.tag else "")

    def build(self):
        """The :class:`rc3r.runspec.RunSpec` of this job (``rate`` None runs in continuous time)."""
        from ..runspec import build_run

        return build_run(robot=self.robot, controller=self.controller, perturbed=True, plant=self.spec,
                         eps=self.eps, rate=0.0 if self.rate is None else self.rate,  # 0: continuous
                         duration=self.duration, box=self.box,
                         config=json.loads(self.config), name=self.id)


#: Columns of ``runs.csv`` before the per-joint ones (docs/robustness.md defines each).
ROW_KEYS = ("job", "plant", "plant_seed", "controller", "eps", "rate_hz", "theta_dist", "rho", "covered",
            "status", "t_end", "max_error", "final_error", "rms_error", "max_torque", "chattering",
            "predicted_bound", "exceeds_bound", "verdict", "tolerance_met", "saturation_fraction")
#: Per-joint columns (suffix ``_<j>``, j = 1..n).
JOINT_KEYS = ("e_max", "e_final", "e_rms", "u_max", "tv")
#: Columns of ``timing.csv`` (not deterministic, so not in ``runs.csv``).
TIMING_KEYS = ("job", "wall_time_s", "steps", "rhs_evals", "worker")


def columns(n: int) -> tuple[str, ...]:
    """All columns of ``runs.csv`` for an n-joint robot."""
    return ROW_KEYS + tuple(f"{k}_{j}" for k in JOINT_KEYS for j in range(1, n + 1))


def _bound(spec, res):
    """(covered, predicted per-joint bound or None) of a robust law in continuous time."""
    from ..controllers.guarantee import covers, error_bound, inertia_range, lyapunov_margin

    try:
        lyapunov_margin(spec.law)
    except ValueError:
        return None, None
    covered = covers(spec.law, spec.true_rigid.theta)
    if res.mode != "continuous" or res.q.shape[0] == 0:
        return covered, None
    step = max(1, res.q.shape[0] // 200)
    m_lo, m_hi = inertia_range(spec.true_rigid, res.q[::step])
    return covered, error_bound(spec.law, m_lo, m_hi, res.n)


def run_job(job: Job) -> tuple[dict, dict]:
    """Simulate ``job``; return its ``runs.csv`` row and its ``timing.csv`` row.

    A diverged run is a row with ``status = "diverged"`` (its metrics up to then);
    bad input raises :class:`rc3r.errors.Rc3rError` as ``rc3r run`` would; an
    interrupted run raises ``KeyboardInterrupt`` (never a row: a resumed campaign runs it).
    """
    from ..simulate import file_status
    from ..runspec import execute

    spec = job.build()
    res, m = execute(spec)
    if res.outcome == "interrupted":
        raise KeyboardInterrupt(res.message)
    e_max = np.asarray(m["max_abs_error"])
    covered, bound = _bound(spec, res)
    th0 = np.asarray(spec.model["theta0"], dtype=float)
    law_eps = res.controller.get("eps")
    eps = job.eps if job.eps is not None else (float(law_eps) if isinstance(law_eps, (int, float)) else None)
    row = {
        "job": job.id, "plant": job.plant, "plant_seed": spec.seed if job.spec.startswith("random:") else None,
        "controller": job.controller, "eps": eps,
        "rate_hz": None if spec.options.rate is None else float(spec.options.rate),  # as simulated
        "theta_dist": float(np.linalg.norm(spec.true_rigid.theta - th0)), "rho": spec.model.get("rho"),
        "covered": covered, "status": file_status(res), "t_end": res.t_end,
        "max_error": float(e_max.max()), "final_error": float(np.max(m["final_error_bound"])),
        "rms_error": float(np.max(m["rms_error"])), "max_torque": float(np.max(m["max_abs_torque"])),
        "chattering": float(np.sum(m["chattering"])),
        "predicted_bound": None if bound is None else float(bound.max()),
        "exceeds_bound": None if bound is None or not covered else bool(np.any(e_max > bound)),
        "verdict": m["verdict"], "tolerance_met": m["tolerance_met"], "saturation_fraction": m["saturation_fraction"],
    }
    for key, name in zip(JOINT_KEYS, ("max_abs_error", "final_error_bound", "rms_error", "max_abs_torque",
                                      "chattering")):
        for j, v in enumerate(m[name], 1):
            row[f"{key}_{j}"] = float(v)
    timing = {"job": job.id, "wall_time_s": m["wall_time_s"], "steps": m["steps"], "rhs_evals": m["rhs_evals"],
              "worker": f"{socket.gethostname()}:{os.getpid()}"}
    return row, timing
