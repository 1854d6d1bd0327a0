r"""The rule's fast form verified by simulation over the bounds, at the rate and at rate / margin.

:func:`verify_design` takes a run configuration (the arm, its bounds, the plant effects, the
trajectory: what :func:`rc3r.runspec.build_run` reads) and a controller rate, and

1. computes the fast form (:func:`rc3r.design.rule.fast_design`) on the controller's own model (theta_0's M,
   :func:`controller_model`), its bandwidth b capped so that K alone uses at most :data:`K_SET_SHARE` of the
   held loop's limit at rate / margin on the hardest plant of the bounds;
2. runs the robust law with it on the plants of the bounds -- for a payload the lightest and the
   heaviest end and ``n`` seeded random masses, for a box its nominal robot and ``n`` seeded random
   plants (``random:<plant_seed(seed, k)>``, as ``rc3r montecarlo``), for an identification's
   bounds the ellipsoid's centre and ``n`` seeded plants drawn in it
   (:func:`rc3r.uncertainty.ellipsoid.draw_from_ellipsoid`) -- and, for every eps tried, the three hardest
   plants of the bounds for that eps (:mod:`rc3r.design.worst`, searched in this process: linear algebra, no
   draw), beyond the bounds by the URDF's own uncertainty when they trust the URDF (``[plant]
   urdf_uncertainty``) -- at the rate and at rate / margin, as campaign jobs
   (:func:`rc3r.campaign.runner.run_many`: a local pool or a Dask scheduler);
3. starts from the fast form's eps for rate / margin (:func:`start_eps`), or 1.25 x the eps from which the
   held loop at rate / margin is stable on the hardest plants if larger, tightens eps by halves
   while every run is ``clean``, or backs off by doubling while one chatters, saturates, leaves the
   joint limits or diverges (at most ``steps`` times), then bisects the bracket once (geometric
   mean); the smallest clean eps is the design. An eps whose held loop at rate / margin is unstable on a
   searched plant (:func:`_loop`) is not clean and is not simulated;
4. runs the baselines and the other laws on the same plants at the rate: FBL with the rule's
   Kp, Kd, the adaptive law with the rule's Gamma, and eq. (7) with eps_i scaled like eps (the fast
   form's eps_i if that is not clean), at the rate and at rate / margin like eq. 6; the design is
   verified (:attr:`DesignResult.ok`) if eq. 6 or eq. 7 is clean on every plant at both rates, and
   :meth:`DesignResult.recommendation` names the one to run;
5. runs the design at rates below rate / margin (steps of sqrt(2), on the first four plants) to find
   the lowest rate at which it stays clean.
"""
from __future__ import annotations

import copy
import json
import math
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from .rule import fast_design, spectrum
from .worst import Hardest

__all__ = ["RUN_LAWS", "DesignResult", "controller_model", "design_config", "plant_specs", "start_eps", "verify_design", "summarize"]

#: The laws a design runs (the robust law, the baselines, eq. 7): ``rc3r design`` plans one compiled instance
#: for them all (:func:`rc3r.campaign.runner.prepare`); :meth:`_Runner.jobs` refuses another.
RUN_LAWS = ("robust", "robust-coeff", "fbl", "adaptive")


#: Share of the held loop's stability limit at rate / margin that K alone may use on the hardest plant of the
#: bounds (``rc3r design`` lowers the fast form's bandwidth b to it; the rest is the robust term's).
K_SET_SHARE = 0.5

#: Default URDF uncertainty of a design whose bounds trust a URDF (docs/design.md, "URDF uncertainty";
#: :mod:`rc3r.uncertainty.urdf`): every link's pseudo-inertia scaled by 0.1..1.5 along each principal direction,
#: the last link's (the tool or hand) by 0.05..1.5.
URDF_UNCERTAINTY = "0.1..1.5,-1=0.05..1.5"


def design_config(config: dict | None = None, **options) -> dict:
    """The run configuration a design is made for: ``config`` (a ``--config`` table) with the command
    line's ``options`` written into it (``robot``, ``urdf``, ``lock``, ``payload`` (lo, hi), ``payload_com``,
    ``box``, ``bounds``, ``friction``, ``torque_limit``, ``noise``, ``delay``, ``duration``, ``tolerance``,
    ``urdf_uncertainty``: ``[plant] urdf_uncertainty``, a spec of :func:`rc3r.uncertainty.urdf.parse_spec`,
    default :data:`URDF_UNCERTAINTY` for bounds that trust the URDF (a payload range, a ``box`` around its
    values), none for a robot's own stated uncertainty (its ``default_box``: the paper's box of the 3R) and
    for an identification's ``bounds``; ``off`` or 0 disables it).

    Gains are what a design chooses: a config with ``[gains]`` or ``[controller]`` gains is refused.
    """
    cfg = copy.deepcopy(config or {})
    ctrl = cfg.get("controller", {})
    if cfg.get("gains") or (isinstance(ctrl, dict) and set(ctrl) - {"kind"}):
        raise ConfigError("rc3r design chooses the gains: remove [gains] and the gains of [controller] from --config")
    cfg.pop("controller", None)
    cfg.pop("gains", None)
    cfg.pop("design", None)
    given = [k for k in ("payload", "box", "bounds") if options.get(k) is not None]
    if len(given) > 1:
        raise ConfigError(f"give one of --payload, --box, --bounds, not {' and '.join('--' + k for k in given)}")
    if options.get("robot") is not None and options.get("urdf") is not None:
        raise ConfigError("give --robot NAME or --urdf PATH, not both")
    for key in ("robot", "urdf", "box", "bounds", "tolerance"):
        if options.get(key) is not None:
            cfg[key] = options[key] if key in ("tolerance", "robot") else str(options[key])
    for key in ("urdf", "box", "bounds"):  # absolute while designing; design.toml names them portably
        if isinstance(cfg.get(key), str) and not cfg[key].startswith("erd:") and Path(cfg[key]).exists():
            cfg[key] = str(Path(cfg[key]).resolve())
    if options.get("urdf") is not None:
        cfg.pop("robot", None)
    if options.get("lock"):
        cfg["lock"] = {str(k): float(v) for k, v in dict(options["lock"]).items()}
    if options.get("payload") is not None:
        lo, hi = options["payload"]
        cfg["payload"] = {"mass": [float(lo), float(hi)]}
        if options.get("payload_com") is not None:
            cfg["payload"]["com"] = [float(c) for c in options["payload_com"]]
        cfg.pop("box", None)
    plant = dict(cfg.get("plant", {}))
    for key in ("friction", "torque_limit", "noise", "delay"):
        if options.get(key) is not None:
            plant[key] = options[key]
    from ..uncertainty.urdf import parse_spec

    f = options.get("urdf_uncertainty")
    if f is None:
        # the default only where the bounds trust a URDF's values (a payload range, a box around them);
        # a robot's own stated uncertainty (the paper's box of the 3R, section 4) and an identification's
        # bounds already say how wrong the model may be
        trusts_urdf = cfg.get("payload") is not None or cfg.get("box") is not None
        f = plant.get("urdf_uncertainty", URDF_UNCERTAINTY if trusts_urdf else None)
    f = parse_spec(f)
    if cfg.get("bounds") or f is None:  # identified bounds do not trust the URDF
        plant.pop("urdf_uncertainty", None)
    else:
        plant["urdf_uncertainty"] = f
    if plant:
        cfg["plant"] = plant
    sim = dict(cfg.get("simulation", {}))
    if options.get("duration") is not None:
        sim["duration"] = float(options["duration"])
    sim.pop("rate", None)  # the design's rate is given apart
    if sim:
        cfg["simulation"] = sim
    cfg["perturbed"] = True
    return json.loads(json.dumps(cfg))  # plain data, as a Job carries it


def plant_specs(cfg: dict, n: int, seed: int = 0) -> list[tuple[int, str]]:
    """``(job plant id, plant spec)`` of a design's verification (module docstring); -1 names a plant."""
    from ..campaign.jobs import plant_seed

    draws = [(k, f"random:{plant_seed(seed, k)}") for k in range(n)]
    if cfg.get("payload"):
        return [(-1, "lower"), (-1, "upper")] + draws
    if cfg.get("bounds") and not cfg.get("box"):  # the identified ellipsoid: its centre and draws in it
        return [(-1, "centre")] + draws
    return [(-1, "nominal")] + draws


def summarize(rows: list[dict]) -> dict:
    """Counts of verdicts and the worst numbers of a set of ``runs.csv`` rows."""
    if not rows:
        return {"runs": 0, "clean": False, "verdicts": {}}
    n = sum(1 for k in rows[0] if k.startswith("u_max_"))
    u = np.array([[r[f"u_max_{j}"] for j in range(1, n + 1)] for r in rows], dtype=float)
    err = np.array([r["max_error"] for r in rows], dtype=float)
    worst = int(np.nanargmax(err)) if np.any(np.isfinite(err)) else 0
    return {"runs": len(rows), "clean": all(r["verdict"] == "clean" for r in rows),
            "verdicts": dict(Counter(r["verdict"] for r in rows)),
            "worst_error": float(np.nanmax(err)), "worst_plant": rows[worst]["plant_seed"] or rows[worst]["job"],
            "median_error": float(np.nanmedian(err)), "worst_chattering": float(np.nanmax([r["chattering"]
                                                                                           for r in rows])),
            "u_max": np.nanmax(u, axis=0).tolist(), "tolerance_met": all(bool(r["tolerance_met"]) for r in rows)}


@dataclass
class DesignResult:
    """What :func:`verify_design` found (JSON-ready through :meth:`describe`)."""

    config: dict
    rate: float
    margin: float
    design: object
    eps: float | None
    levels: list = field(default_factory=list)
    baselines: dict = field(default_factory=dict)
    low_rates: list = field(default_factory=list)
    plants: list = field(default_factory=list)
    model: dict = field(default_factory=dict)
    spectrum: dict = field(default_factory=dict)
    effort_limit: list | None = None
    eps_i: float | None = None
    search: str = "off"
    eps_needed: float | None = None
    eps_i_needed: float | None = None
    urdf: str | None = None
    b_note: dict | None = None

    @property
    def worst(self) -> dict:
        """Per robust law, the hardest plant searched for its verified (else last tried) gains, with
        ``T_lambda`` (on that plant), ``model_T_lambda`` (the rule's, on the controller's model) and ``limit``."""
        out = {}
        lv = self.chosen or (max(self.levels, key=lambda x: x["eps"]) if self.levels else None)
        if lv and lv.get("worst"):
            out["robust"] = {**lv["worst"], "model_T_lambda": lv.get("model_T_lambda"), "eps": lv["eps"]}
        rc = self.baselines.get("robust-coeff") or {}
        if rc.get("worst"):
            out["robust-coeff"] = {**rc["worst"], "model_T_lambda": rc.get("model_T_lambda"), "eps_i": rc["eps_i"]}
        return out

    @property
    def eq6_ok(self) -> bool:
        """True if a clean eps of eq. 6 was found at the rate and at rate / margin on every plant."""
        return self.eps is not None

    @property
    def ok(self) -> bool:
        """True if a robust law is verified: eq. 6 (:attr:`eq6_ok`) or eq. 7 clean on every plant at the rate
        and at rate / margin (:meth:`recommendation` is not None)."""
        return self.recommendation() is not None

    @property
    def chosen(self) -> dict | None:
        """The level of the chosen eps."""
        return next((lv for lv in self.levels if lv["eps"] == self.eps), None)

    def gains(self) -> dict:
        """``[gains.<law>]`` tables of the design (the fast form's, with the verified eps and eps_i; not verified,
        the largest eps and the last eps_i tried)."""
        out = {law: self.design.gains(law) for law in ("robust", "adaptive", "fbl", "pd")}
        eps = self.eps
        if eps is None and self.levels:  # not verified: the thickest layer tried (as :attr:`worst` reports; the
            eps = max(lv["eps"] for lv in self.levels)  # fast form's may be unstable on a searched plant)
        if eps is not None:
            out["robust"]["eps"] = float(eps)
        if self.design.eps_i is not None:
            out["robust-coeff"] = {**self.design.gains("robust-coeff"), "eps_i": float(self.eps_i or
                                                                                       self.design.eps_i)}
        return out

    def recommendation(self) -> dict | None:
        """The robust law to run: of eq. 6 (``robust``, the chosen eps, if clean at both rates) and eq. 7
        (``robust-coeff``, if clean on every plant at the rate and at rate / margin) the one with the smaller
        worst max|e| at the rate; ``{"law", "worst_error", "fbl_worst_error", "why"}``, or None if neither
        is clean. (eq. 6's boundary layer must be thick enough for the sampled loop; where that leaves
        its robust term too weak, eq. 7's per-coefficient layers often are not: docs/design.md.)"""
        cands = []
        if self.chosen is not None:
            cands.append(("robust", self.chosen["at_rate"].get("worst_error")))
        rc = self.baselines.get("robust-coeff") or {}
        if rc.get("clean") and rc.get("clean_low", True) and rc.get("worst_error") is not None:
            cands.append(("robust-coeff", rc["worst_error"]))
        cands = [(law, e) for law, e in cands if e is not None and np.isfinite(e)]
        if not cands:
            return None
        law, err = min(cands, key=lambda c: c[1])
        other = [f"{ol} {oe:.3g} rad" for ol, oe in cands if ol != law]
        why = (f"clean, worst max|e| {err:.3g} rad" + (f" (against {other[0]})" if other else
               " (the other robust variant was not clean)"))
        return {"law": law, "worst_error": float(err),
                "fbl_worst_error": (self.baselines.get("fbl") or {}).get("worst_error"), "why": why}

    def lowest_clean_rate(self) -> float | None:
        """The lowest rate tested at which eq. 6's design stayed clean (rate / margin at least, if verified)."""
        clean = [r["rate"] for r in self.low_rates if r["clean"]]
        base = [self.rate / self.margin] if self.eq6_ok else []
        return min(clean + base) if clean + base else None

    def describe(self) -> dict:
        """Everything as plain data."""
        return {"rate": self.rate, "margin": self.margin, "eps": self.eps, "eps_i": self.eps_i, "ok": self.ok,
                "eq6_ok": self.eq6_ok,
                "design": self.design.describe(), "levels": self.levels, "baselines": self.baselines,
                "low_rates": self.low_rates, "lowest_clean_rate": self.lowest_clean_rate(),
                "plants": self.plants, "model": self.model, "spectrum": self.spectrum,
                "effort_limit": self.effort_limit, "gains": self.gains(), "config": self.config,
                "recommendation": self.recommendation(), "search": self.search, "worst": self.worst,
                "eps_needed": self.eps_needed, "eps_i_needed": self.eps_i_needed, "urdf": self.urdf,
                "b_note": self.b_note}


def _resolve(cfg: dict, rate: float):
    """The controller's model, trajectory and bounds of the configuration (no simulation)."""
    from ..runspec import build_run

    spec = build_run(controller="robust", config=cfg, rate=rate, eps=1.0)  # eps given: no defaults hook
    rho_i = None
    try:
        rho_i = build_run(controller="robust-coeff", config=cfg, rate=rate, eps=1.0).model["rho_i"]
    except ConfigError:
        pass
    return spec, rho_i


def controller_model(spec):
    """The controller's own model of a resolved run: the arm's kinematics with the law's theta_0
    (:class:`rc3r.design.rule.ThetaModel`); every figure of the rule and of the report is computed on it."""
    from .rule import ThetaModel

    theta0 = spec.model.get("theta0")
    if theta0 is None:
        return ThetaModel(spec.controller_model, spec.controller_model.theta, f"theta of {spec.controller_model.label}")
    src = spec.model.get("theta_source") or "theta_0"
    return ThetaModel(spec.controller_model, theta0, f"the controller's theta_0 ({src})")


def start_eps(design, sp, rate: float, margin: float, rho: float) -> float:
    """Where the search starts: the fast form's eps for rate / margin with the design's K (the loop free of
    oscillation at the lower rate too); the fast form's eps if K alone uses the budget there."""
    from .rule import real_limit

    Tm = margin / float(rate)
    room = real_limit(design.delay) - Tm * design.L_K
    return Tm * rho * sp.lam_yy() / room if room > 0 else design.eps * margin


def _effort(robot):
    try:
        lim = np.array(robot.model.effortLimit, dtype=float)
    except AttributeError:
        return None
    return lim.tolist() if lim.shape == (robot.n,) and np.all(np.isfinite(lim)) and np.all(lim > 0) else None


class _Runner:
    """Runs batches of jobs into one table and keeps their rows."""

    def __init__(self, cfg, table, duration, workers, scheduler, progress):
        self.cfg, self.table, self.duration = cfg, table, duration
        self.workers, self.scheduler, self.progress = workers, scheduler, progress
        self.rows: dict = {}

    def jobs(self, law, gains, eps, rate, plants, tag=""):
        from ..campaign.jobs import Job

        if law not in RUN_LAWS:
            raise RuntimeError(f"a design runs the laws of RUN_LAWS, not {law!r}: add it there")

        cfg = json.dumps({**self.cfg, "gains": {law: gains}}, sort_keys=True)
        return [Job(k, spec, law, eps, float(rate), self.duration, config=cfg, tag=tag) for k, spec in plants]

    def run(self, jobs, what: str) -> list[dict]:
        from ..campaign.runner import run_many

        if self.progress is not None:
            self.progress(what, len(jobs))

        def keep(row):
            self.rows[row["job"]] = row
            if self.progress is not None:
                self.progress(None, 1)

        run_many(jobs, self.table, workers=self.workers, scheduler=self.scheduler, progress=keep)
        return [self.rows[j.id] for j in jobs if j.id in self.rows]


def deciding(rows: list[dict], searched=()) -> dict | None:
    """The plant that decided a rejected level: of the runs that were not clean, the one with the most severe
    verdict (diverged before limit-violated, saturated, chattering), a searched worst plant first among equals,
    then the largest max|e|; ``{"plant", "verdict", "rate", "max_error", "searched"}`` or None if all were clean."""
    from ..simulate.verdict import VERDICTS

    bad = [r for r in rows if r["verdict"] != "clean"]
    if not bad:
        return None

    def name(r):
        return f"random:{r['plant_seed']}" if r.get("plant_seed") not in (None, "") else str(r["job"]).split("/")[0]

    sev = {v: i for i, v in enumerate(VERDICTS)}
    r = min(bad, key=lambda r: (sev.get(r["verdict"], 0), name(r) not in searched,
                                -float(r["max_error"]) if np.isfinite(r["max_error"]) else -np.inf))
    return {"plant": name(r), "verdict": r["verdict"], "rate": r["rate_hz"], "max_error": float(r["max_error"]),
            "searched": name(r) in searched}


def _loop(found: list[dict], margin: float, low: float) -> dict | None:
    """The searched plant whose held loop is unstable at rate / margin (``T lambda_max(M_p^-1 G) >=`` the limit
    at the lower rate), as :func:`deciding` names a plant; None if there is none."""
    bad = [e for e in found if e["T_lambda"] * margin >= e["limit"]]
    if not bad:
        return None
    e = max(bad, key=lambda e: e["T_lambda"])
    return {"plant": e["spec"], "verdict": f"loop gain {e['T_lambda'] * margin:.3g} >= {e['limit']:.3g}",
            "rate": float(low), "max_error": float("nan"), "searched": True, "loop": True}


def verify_design(cfg: dict, rate: float, *, table, margin: float = 2.0, n: int = 50, seed: int = 0,
                  workers: int | None = None, scheduler: str | None = None, steps: int = 3,
                  progress=None, search: bool = True) -> DesignResult:
    """Design and verify the gains for ``rate`` [Hz] (module docstring).

    Parameters
    ----------
    cfg : dict
        The run configuration (:func:`design_config`).
    rate : float
        Controller rate [Hz].
    table : rc3r.campaign.RunTable
        Opened table the verification runs are appended to (``runs.csv``).
    margin : float
        The design must also be clean at ``rate / margin`` (>= 1).
    n : int
        Random plants besides the ends (payload) or the nominal robot (box).
    seed : int
        Seed of the random plants.
    workers, scheduler
        Where the runs go (:func:`rc3r.campaign.runner.run_many`).
    steps : int
        At most this many halvings and doublings of eps.
    progress : callable, optional
        ``progress(what, count)``: a new batch of ``count`` runs (``what`` a label), or ``(None, 1)`` a run done.
    search : bool
        Add the hardest plants of the bounds for each eps tried (:mod:`rc3r.design.worst`) to the plants.
    """
    if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate > 0):
        raise ConfigError(f"--rate must be a finite number of Hz > 0, got {rate!r}")
    if not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 1):
        raise ConfigError(f"--margin must be a finite number >= 1, got {margin!r}")
    spec, rho_i = _resolve(cfg, rate)
    duration = spec.options.duration
    delay = 0 if spec.loop is None else int(spec.loop.delay)
    model = controller_model(spec)
    sp = spectrum(model, spec.trajectory, duration)
    rho = float(spec.model["rho"])
    design = fast_design(sp, rate, rho=rho, rho_i=rho_i, delay=delay)
    hard = Hardest(cfg, spec, sp, rate, delay) if search else None
    b_note = None
    if hard is not None:  # K alone may use half the held loop's budget at rate / margin on the hardest plant
        unit = {"K": design.K / design.bandwidth, "K_inertia": 1.0 if design.K_inertia else 0.0}
        top = hard.plants(unit, rho=0.0, eps=1.0)[0]
        kappa = top["T_lambda"] * rate  # max_t lambda_max(M_p^-1 K / b)
        b_max = K_SET_SHARE * top["limit"] * rate / (margin * kappa)
        if design.bandwidth > b_max:
            b_note = {"b": design.bandwidth, "b_max": b_max, "plant": top["spec"], "kappa": kappa}
            design = fast_design(sp, rate, rho=rho, rho_i=rho_i, delay=delay, b_max=b_max)
    plants = plant_specs(cfg, n, seed)
    res = DesignResult(cfg, float(rate), float(margin), design, None, plants=[s for _, s in plants],
                       model={**{k: spec.model.get(k) for k in ("rho", "theta_source", "rho_source", "box", "nominal")},
                              "controller_model": model.label,
                              "box": spec.model.get("box") or (f"identified bounds {spec.model['bounds_file']}"
                                                               if spec.model.get("bounds_file") else None)},
                       spectrum={"m_min": sp.m_min, "m_max": sp.m_max, "L_Y": sp.lam_yy(), "samples": int(sp.t.size),
                                 "minv_diag_max": sp.minv_diag_max.tolist()},
                       effort_limit=_effort(spec.controller_model))
    run = _Runner(cfg, table, duration, workers, scheduler, progress)
    sliding = {k: v for k, v in design.gains("robust").items() if k in ("K", "Lambda", "K_inertia")}
    low = rate / margin
    res.b_note = b_note
    res.search = hard.kind if hard is not None else "off"
    res.urdf = hard.urdf.describe() if hard is not None and hard.urdf is not None else None

    def with_worst(entries):
        names = {s for _, s in plants}
        return plants + [(-1, e["spec"]) for e in entries if e["spec"] not in names]

    def level(eps):
        found = hard.plants(sliding, rho=rho, eps=eps) if hard is not None else []
        pl = with_worst(found)
        loop = _loop(found, margin, low)
        if loop is not None:  # the held loop is unstable on a searched plant: refused without simulation
            rows, at, lo = [], summarize([]), summarize([])
        else:
            jobs = run.jobs("robust", sliding, eps, rate, pl) + \
                (run.jobs("robust", sliding, eps, low, pl) if margin > 1 else [])
            rows = run.run(jobs, f"robust, eps {eps:.4g}")
            at = summarize([r for r in rows if r["rate_hz"] == float(rate)])
            lo = summarize([r for r in rows if r["rate_hz"] == float(low)]) if margin > 1 else at
        lv = {"eps": float(eps), "factor": float(eps / design.eps), "at_rate": at, "at_low": lo,
              "clean": bool(loop is None and at["clean"] and lo["clean"]), "worst": found[0] if found else None,
              "model_T_lambda": hard.model_gain(sliding, rho=rho, eps=eps) if hard is not None else None,
              "decided_by": loop or deciding(rows, {e["spec"] for e in found}), "plants": len(pl)}
        res.levels.append(lv)
        return lv["clean"]

    eps = start_eps(design, sp, rate, margin, rho)
    if hard is not None:  # no thinner layer than the held loop on the searched plants allows at rate / margin
        hard.plants(sliding, rho=rho, eps=eps)
        need = hard.eps_factor(sliding, low, rho=rho, eps=eps)
        res.eps_needed = float(eps * need) if math.isfinite(need) else float("inf")
        if math.isfinite(need) and need > 1.0:
            eps *= 1.25 * need
    clean, failed = (eps, None) if level(eps) else (None, eps)
    for _ in range(steps):  # halve while clean, double while not, until the boundary is bracketed
        if clean is not None and failed is None:
            eps = clean / 2.0
            if level(eps):
                clean = eps
            else:
                failed = eps
        elif clean is None:
            eps = failed * 2.0
            if level(eps):
                clean = eps
            else:
                failed = eps
        else:
            break
    if clean is not None and failed is not None and failed < clean:  # one geometric bisection of the bracket
        eps = math.sqrt(clean * failed)
        if level(eps):
            clean = eps
    res.eps = clean
    res.levels.sort(key=lambda lv: lv["eps"])
    factor = 1.0 if res.eps is None else res.eps / design.eps
    chosen = res.chosen
    hardest = with_worst([chosen["worst"]] if chosen is not None and chosen.get("worst") else [])
    fbl = run.run(run.jobs("fbl", design.gains("fbl"), None, rate, hardest), "fbl baseline")
    res.baselines["fbl"] = summarize(fbl)
    if design.eps_i is not None:
        sl = dict(sliding)
        tried = [design.eps_i * factor] + ([design.eps_i] if factor != 1.0 else [])
        if hard is not None:  # and no thinner than the held loop on the searched plants allows at rate / margin
            hard.plants(sl, rho_i=rho_i, eps_i=tried[0])
            need = hard.eps_factor(sl, low, rho_i=rho_i, eps_i=tried[0])
            res.eps_i_needed = float(tried[0] * need) if math.isfinite(need) else float("inf")
            if math.isfinite(need) and need > 1.0:
                tried = [tried[0] * 1.25 * need]
        for eps_i in tried:  # verified like eq. 6: every plant (and the hardest) at the rate and at rate / margin
            found = hard.plants(sl, rho_i=rho_i, eps_i=eps_i) if hard is not None else []
            pl = with_worst(found)
            loop = _loop(found, margin, low)
            if loop is not None:
                rows = []
            else:
                jobs = run.jobs("robust-coeff", sl, eps_i, rate, pl) + \
                    (run.jobs("robust-coeff", sl, eps_i, low, pl) if margin > 1 else [])
                rows = run.run(jobs, f"robust-coeff, eps_i {eps_i:.4g}")
            rc = summarize([r for r in rows if r["rate_hz"] == float(rate)])
            rc_low = summarize([r for r in rows if r["rate_hz"] == float(low)]) if margin > 1 else rc
            res.baselines["robust-coeff"] = {
                **rc, "eps_i": float(eps_i), "at_low": rc_low, "clean_low": bool(rc_low["clean"]),
                "worst": found[0] if found else None, "decided_by": loop or deciding(rows, {e["spec"] for e in found}),
                "model_T_lambda": hard.model_gain(sl, rho_i=rho_i, eps_i=eps_i) if hard is not None else None}
            res.eps_i = float(eps_i)
            if rc["clean"] and rc_low["clean"]:
                break
    res.baselines["adaptive"] = summarize(run.run(run.jobs("adaptive", design.gains("adaptive"), None, rate,
                                                           hardest), "adaptive"))
    if res.eps is not None:
        r = low
        for _ in range(4):
            r /= math.sqrt(2.0)
            s = summarize(run.run(run.jobs("robust", sliding, res.eps, r, plants[:4]), f"robust at {r:.4g} Hz"))
            res.low_rates.append({"rate": float(r), "clean": s["clean"], "verdicts": s["verdicts"],
                                  "worst_error": s.get("worst_error")})
            if not s["clean"]:
                break
    return res
