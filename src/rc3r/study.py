r"""Runs as data: from a configuration (TOML + keyword options) to a :class:`RunSpec`, and its execution.

**One source of truth.** A run has one nominal robot and one box. The plant is
drawn from them (``nominal``, ``upper``, ``random:<seed>`` ... or an explicit URDF),
and the controller's ``theta_0``, ``rho`` and ``rho_i`` are computed from the
*same* nominal robot and the *same* box:

* ``theta = "paper"`` -- method (a) (:func:`rc3r.uncertainty.paper_bounds`):
  midpoint of theta(nominal) and theta(p_up); the default for perturbed runs;
* ``theta = "certified"`` -- centre of the exact ranges over the box;
* ``theta = "plant"`` -- the plant's own theta (ideal scenarios);
* ``rho = "paper"`` (method (a)), ``"certified"`` (covers the whole box around the
  chosen theta_0), or a number; ``rho_i`` is always the certified per-coefficient
  radius around theta_0.

:class:`RunSpec` records what the controller got and where it came from
(``spec.model``); :func:`execute` copies it into the metrics. The command line
(:mod:`rc3r.cli`) builds specs with :func:`build_run`; the paper's scenarios are
:func:`rc3r.robots.rr3.paper.scenarios`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .controllers import LAWS, make_law
from .errors import ConfigError, ParameterError
from .robots import DEFAULT_ROBOT, robot_class
from .simulate import SimOptions, SimResult, simulate
from .simulate.metrics import run_metrics
from .trajectory import trajectory_from_config
from .uncertainty import certified_bounds, certified_radius, load_box, paper_bounds, perturb

__all__ = ["RunSpec", "build_run", "execute", "resolve_box", "CONFIG_KEYS"]


@dataclass(frozen=True)
class RunSpec:
    """Everything one run needs, resolved: plant, law, trajectory, options, provenance.

    ``model`` records the controller's theta_0, rho, rho_i and their sources
    (``theta_source``, ``rho_source``, ``box``, ``nominal``).
    """

    name: str
    plant: object
    law: object
    trajectory: object
    options: SimOptions
    seed: int
    scenario: str
    model: dict = field(default_factory=dict)


#: Keys a run configuration may hold, per table (docs/control.md).
CONFIG_KEYS = {
    "": ("robot", "seed", "perturbed", "box", "plant", "model", "controller", "trajectory", "simulation"),
    "plant": ("spec", "urdf", "box"),
    "model": ("theta", "rho"),
    "trajectory": ("kind", "offset", "terms", "waypoints", "durations"),
    "simulation": ("duration", "rate", "output_rate", "rtol", "atol", "nsub", "engine", "q_max", "qd_max", "u_max"),
}


def _check_keys(table, allowed, where: str) -> dict:
    """Refuse a non-table or an unknown key, naming the nearest valid one."""
    import difflib

    if not isinstance(table, dict):
        raise ConfigError(f"config: {where or 'the file'} must be a table, got {table!r}")
    for key in table:
        if key not in allowed:
            near = difflib.get_close_matches(str(key), allowed, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else f" (valid: {', '.join(allowed)})"
            raise ConfigError(f"config: unknown key {key!r}{' in [' + where + ']' if where else ''}{hint}")
    return table


def _check_config(cfg: dict, kind_override=None) -> None:
    _check_keys(cfg, CONFIG_KEYS[""], "")
    for table in ("plant", "model", "trajectory", "simulation"):
        if table in cfg:
            _check_keys(cfg[table], CONFIG_KEYS[table], table)
    if "controller" in cfg:
        ctrl = _check_keys(cfg["controller"], tuple(cfg["controller"]) if isinstance(cfg["controller"], dict)
                           else (), "controller")
        kind = ctrl.get("kind", "robust")
        if not isinstance(kind, str) or kind not in LAWS:
            raise ConfigError(f"config: [controller] kind must be one of {', '.join(LAWS)}, got {kind!r}")
        kind = kind_override or kind
        if kind not in LAWS:
            raise ConfigError(f"config: [controller] kind must be one of {', '.join(LAWS)}, got {kind!r}")
        names = [f for f in LAWS[kind].__dataclass_fields__ if f not in ("theta", "rho", "rho_i")]
        if "eps_i" in names:
            names.append("eps")
        _check_keys(ctrl, ["kind"] + names, "controller")
    seed = cfg.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise ConfigError(f"config: seed must be an integer in [0, 2^63), got {seed!r}")
    if not isinstance(cfg.get("perturbed", False), bool):
        raise ConfigError(f"config: perturbed must be true or false, got {cfg['perturbed']!r}")
    for key, where in (("robot", cfg), ("box", cfg), ("spec", cfg.get("plant", {})), ("urdf", cfg.get("plant", {})),
                       ("box", cfg.get("plant", {}))):
        if key in where and not isinstance(where[key], str):
            raise ConfigError(f"config: {key} must be a string, got {where[key]!r}")


def _floats(x):
    return None if x is None else [float(v) for v in np.asarray(x, dtype=float).ravel()]


def resolve_box(cls, nominal, box_path=None):
    """The box of a run: ``box_path`` (TOML) if given, else the robot's default box."""
    if box_path is not None:
        return load_box(box_path, nominal.standard_parameter_names)
    box = cls.default_box()
    if box is None:
        raise ConfigError(f"robot {cls.name!r} has no default box: give one (--box FILE)")
    return box


def _plant(cls, nominal, box, spec: str, seed: int):
    if spec.endswith(".urdf") or Path(spec).suffix == ".urdf":
        plant = cls.from_urdf(spec)
    else:
        # random draws are redrawn (same seeded stream) until the robot is physical
        plant = perturb(nominal, box, spec, simulable=spec.startswith("random"))
    plant.require_simulable()
    return plant


class _Bounds:
    """The bounds of one nominal robot and box, each computed at most once."""

    def __init__(self, nominal, box):
        self.nominal, self.box = nominal, box
        self._paper = self._cert = None

    @property
    def paper(self):
        if self._paper is None:
            self._paper = paper_bounds(self.nominal, self.box)
        return self._paper

    @property
    def cert(self):
        if self._cert is None:
            self._cert = certified_bounds(self.nominal, self.box)
        return self._cert


def _model(law_cls, plant, bounds: _Bounds, perturbed: bool, cfg: dict) -> dict:
    """The controller's model and where it came from."""
    which = cfg.get("theta", "paper" if perturbed else "plant")
    p = plant.p
    if isinstance(which, list):
        th = np.asarray(which, dtype=float)
        if th.shape != (p,) or not np.all(np.isfinite(th)):
            raise ConfigError(f"model theta must be {p} finite numbers, got {which}")
        src = "theta from config"
    elif which == "plant":
        th, src = plant.theta, "theta of the plant (ideal)"
    elif which == "paper":
        th, src = bounds.paper.theta0, "theta_0 by the paper's method (a): (theta(nominal) + theta(p_up)) / 2"
    elif which == "certified":
        th, src = bounds.cert.theta0, "theta_0 = centre of the exact ranges over the box"
    else:
        raise ConfigError(f"model theta must be 'plant', 'paper', 'certified' or {p} numbers, got {which!r}")
    rho_cfg = cfg.get("rho", "paper")
    rho_i = None
    if "rho_i" in getattr(law_cls, "model_inputs", ()):
        _, rho_i = certified_radius(bounds.cert, th)
    if rho_cfg == "paper":
        rho, rho_src = bounds.paper.rho, "paper's method (a): ||theta_0(a) - theta(nominal)||"
    elif rho_cfg == "certified":
        rho, _ = certified_radius(bounds.cert, th)
        rho_src = "certified: sqrt(sum rho_i^2) of the exact ranges around theta_0"
    else:
        try:
            rho = float(rho_cfg)
        except (TypeError, ValueError):
            raise ConfigError(f"rho must be 'paper', 'certified' or a number, got {rho_cfg!r}") from None
        rho_src = "rho from config"
    return {
        "theta0": _floats(th), "rho": float(rho), "rho_i": _floats(rho_i),
        "theta_source": src, "rho_source": rho_src,
        "rho_i_source": "certified per-coefficient radius around theta_0" if rho_i is not None else None,
        "box": bounds.box.source, "nominal": bounds.nominal.label,
    }


def _law(kind: str, model: dict, cfg: dict, eps_override):
    gains = {k: v for k, v in cfg.items() if k != "kind"}
    names = {f for f in LAWS[kind].__dataclass_fields__}
    if eps_override is not None:
        gains["eps"] = eps_override
    if "eps" in gains and "eps" not in names and "eps_i" in names:  # eq. (7): one eps for every coefficient
        gains.setdefault("eps_i", gains.pop("eps"))
    try:
        return make_law(kind, model["theta0"], rho=model["rho"], rho_i=model["rho_i"], **gains)
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ConfigError(f"controller {kind}: {exc}") from None


def build_run(*, robot: str | None = None, controller: str | None = None, perturbed: bool = False,
              plant: str | None = None, eps: float | None = None, rate: float | None = None,
              duration: float | None = None, engine: str | None = None, box: str | None = None,
              config: dict | None = None, name: str | None = None) -> RunSpec:
    """Resolve a run from keyword options (command line) over a config dict (TOML).

    Keyword options win over the config; both over the defaults (the robot's
    nominal parameters, default box and trajectory; the laws' default gains; 10 s).
    Config keys: ``robot``, ``seed``, ``perturbed``, ``box``, ``[plant]`` (``spec``,
    ``urdf``, legacy ``box``), ``[model]`` (``theta``, ``rho``), ``[controller]``
    (``kind`` and gains), ``[trajectory]``, ``[simulation]`` (docs/control.md).
    """
    cfg = config or {}
    _check_config(cfg, controller)
    seed = int(cfg.get("seed", 0))
    cls = robot_class(robot or cfg.get("robot", DEFAULT_ROBOT))
    ctrl_cfg = dict(cfg.get("controller", {}))
    kind = controller or ctrl_cfg.get("kind", "robust")
    if kind not in LAWS:
        raise ConfigError(f"unknown controller {kind!r} ({', '.join(LAWS)})")
    perturbed = perturbed or bool(cfg.get("perturbed", False))
    plant_cfg = dict(cfg.get("plant", {}))
    nominal = cls.nominal()
    the_box = resolve_box(cls, nominal, box or cfg.get("box") or plant_cfg.get("box"))
    spec = plant or plant_cfg.get("spec", "nominal")
    if "urdf" in plant_cfg and spec == "nominal":
        spec = str(plant_cfg["urdf"])
    if spec == "random":
        spec = f"random:{seed}"
    if isinstance(spec, str) and spec.startswith("random:"):
        try:
            seed = int(spec.partition(":")[2])  # the seed that actually drew the plant is recorded
        except ValueError:
            pass  # perturb() refuses the spec with its own message
    the_plant = _plant(cls, nominal, the_box, spec, seed)
    model = _model(LAWS[kind], the_plant, _Bounds(nominal, the_box), perturbed, dict(cfg.get("model", {})))
    law = _law(kind, model, ctrl_cfg, eps)
    traj = trajectory_from_config(dict(cfg.get("trajectory", {})), cls.default_trajectory())
    if traj.n != the_plant.n:
        raise ConfigError(f"trajectory has {traj.n} joints, robot {cls.name!r} has {the_plant.n}")
    sim = dict(cfg.get("simulation", {}))
    if rate is not None:
        sim["rate"] = rate
    if sim.get("rate") in (0, 0.0):
        sim["rate"] = None
    if duration is not None:
        sim["duration"] = duration
    if engine is not None:
        sim["engine"] = engine
    try:
        opts = SimOptions(**sim)
    except TypeError as exc:
        raise ConfigError(f"[simulation]: {exc}") from None
    scenario = "perturbed" if perturbed else "ideal"
    return RunSpec(name or f"{kind}-{scenario}", the_plant, law, traj, opts, seed, scenario, model)


def execute(spec: RunSpec) -> tuple[SimResult, dict]:
    """Simulate a resolved run; return the result and its metrics (with the model's provenance)."""
    res = simulate(spec.plant, spec.law, spec.trajectory, spec.options)
    m = run_metrics(res, seed=spec.seed)
    m.update({"name": spec.name, "scenario": spec.scenario, "model": spec.model})
    return res, m
