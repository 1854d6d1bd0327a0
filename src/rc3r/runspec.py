r"""Runs as data: from a configuration (TOML + keyword options) to a :class:`RunSpec`, and its execution.

**One source of truth.** A run has one nominal robot and one box. The plant is
drawn from them (``nominal``, ``upper``, ``random:<seed>`` ... or an explicit URDF),
and the controller's ``theta_0``, ``rho`` and ``rho_i`` are computed from the
*same* nominal robot and the *same* box:

* ``theta = "paper"`` -- method (a) (:func:`rc3r.uncertainty.paper_bounds`):
  midpoint of theta(nominal) and theta(p_up); the default for perturbed runs;
* ``theta = "certified"`` -- centre of the exact ranges over the box;
* ``theta = "plant"`` -- the plant's own theta (ideal scenarios);
* a payload (``payload=(lo, hi)``, ``[payload] mass``) is *unknown* to the controller: the
  run is perturbed whatever ``perturbed`` says, theta_0 is the middle of the exact payload
  segment and rho its radius, while the plant carries the stated mass (``upper``: hi by
  default); ``theta = "plant"`` in ``[model]`` is the explicit exception (ideal knowledge of
  the loaded plant);
* ``rho = "paper"`` (method (a)), ``"certified"`` (covers the whole box around the
  chosen theta_0), or a number; ``rho_i`` is always the certified per-coefficient
  radius around theta_0.

:class:`RunSpec` records what the controller got and where it came from
(``spec.model``); :func:`execute` copies it into the metrics. (This module was ``rc3r.study``; that name is a
deprecated re-export.) The command line
(:mod:`rc3r.cli`) builds specs with :func:`build_run`; the paper's scenarios are
:func:`rc3r.experiments.paper3r.scenarios`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .controllers import LAWS, make_law
from .errors import ConfigError, ParameterError
from .io import floats as _floats
from .plants import PLANT_KEYS
from .robots import DEFAULT_ROBOT, load_robot
from .simulate import SimOptions, SimResult, simulate
from .simulate.metrics import run_metrics
from .trajectory import trajectory_from_config
from .uncertainty import certified_radius
from .plant_sets import (_actuated_bounds_plant, _Bounds, _bounds_plant, _drawn, _payload, _plant, actuated_model,
                         resolve_box, with_joint_friction, with_model_friction)

__all__ = ["RunSpec", "build_run", "design_warning", "execute", "resolve_box", "CONFIG_KEYS"]


@dataclass(frozen=True)
class RunSpec:
    """Everything one run needs, resolved: the robots, law, trajectory, options, provenance.

    Three robots, named for what they are:

    * ``controller_model`` -- the controller's model (a :class:`~rc3r.robots.base.Robot`, the nominal
      arm): the law evaluates its regressor, never the plant's parameters;
    * ``true_rigid`` -- the true rigid body (a :class:`~rc3r.robots.base.Robot`: the nominal, drawn,
      payload or URDF arm), without effects;
    * ``true_plant`` -- the plant the run simulates (a :class:`~rc3r.plants.Plant`: ``true_rigid``, or
      MuJoCo's rigid body of it, with its effects: friction, saturation, limits).

    ``loop`` holds the sampled loop's effects (noise, quantization, delay) or None. Simulate the whole
    run with :func:`execute` (or ``rc3r.simulate(spec.true_plant, spec.law, spec.trajectory,
    spec.options, loop=spec.loop, model=spec.controller_model)``). ``model`` records the controller's
    theta_0, rho, rho_i and their sources (``theta_source``, ``rho_source``, ``box``, ``nominal``);
    ``warnings`` what the user should know about defaults taken for them (e.g. a default trajectory that
    could not follow degenerate joint limits), copied into the metrics by :func:`execute`.

    ``plant`` and ``robot_model``, the former names of ``true_rigid`` and ``controller_model``, are
    deprecated read-only aliases. ``spec.plant`` is the rigid body *without* the effects and the loop
    (``rc3r.simulate(spec.plant, ...)`` does not simulate the run), so it warns with a
    :class:`FutureWarning`, which Python shows by default; ``robot_model`` with a :class:`DeprecationWarning`.
    """

    name: str
    true_rigid: object
    law: object
    trajectory: object
    options: SimOptions
    seed: int
    scenario: str
    model: dict = field(default_factory=dict)
    warnings: tuple = ()
    true_plant: object = None
    loop: object = None
    controller_model: object = None
    tolerance: float | None = None

    @property
    def plant(self):
        """Deprecated: :attr:`true_rigid` (the true rigid body, without its effects and loop)."""
        _deprecated("plant", "true_rigid (the true rigid body, WITHOUT the plant's effects and loop: simulate "
                    "spec.true_plant with loop=spec.loop and model=spec.controller_model, or rc3r.execute(spec))",
                    FutureWarning)  # shown by default: a run simulated on it silently drops the effects
        return self.true_rigid

    @property
    def robot_model(self):
        """Deprecated: :attr:`controller_model` (the controller's model)."""
        _deprecated("robot_model", "controller_model")
        return self.controller_model


def _deprecated(old: str, new: str, category=DeprecationWarning) -> None:
    import warnings

    warnings.warn(f"RunSpec.{old} is deprecated: use RunSpec.{new}", category, stacklevel=3)


#: Keys a run configuration may hold, per table (docs/control.md).
CONFIG_KEYS = {
    "": ("robot", "urdf", "lock", "bounds", "seed", "perturbed", "box", "payload", "plant", "model", "controller", "gains",
         "trajectory", "simulation", "tolerance", "design"),
    "payload": ("mass", "com"),
    "design": ("verified", "law", "rate", "margin", "worst_plant", "loop_gain", "note"),
    "plant": ("spec", "urdf", "box", "urdf_uncertainty") + PLANT_KEYS,  # the effects' keys, live
    "model": ("theta", "rho", "friction"),
    "trajectory": ("kind", "offset", "terms", "waypoints", "durations"),
    "simulation": ("duration", "rate", "output_rate", "rtol", "atol", "period_rtol", "period_atol", "nsub",
                   "sampled_method", "engine", "jac_reuse", "method", "max_steps", "q_max", "qd_max", "u_max"),
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


def design_warning(cfg: dict | None) -> str | None:
    """One line for a configuration written by ``rc3r design`` whose design did not verify
    (``[design] verified = false``), else None. ``rc3r run``, ``montecarlo`` and ``export`` print it."""
    note = design_unverified(cfg)
    if note is None:
        return None
    return (f"rc3r: warning: this design.toml did NOT verify ({note}); its gains are unverified: "
            "see its design.md and docs/design.md, 'When the design is not clean'")


def design_unverified(cfg: dict | None) -> str | None:
    """Why a configuration written by ``rc3r design`` is not verified (its ``[design] note``), or None."""
    d = (cfg or {}).get("design")
    if not isinstance(d, dict) or d.get("verified", True) is not False:
        return None
    return str(d.get("note") or "no robust law was clean on every plant")


def _check_config(cfg: dict, kind_override=None) -> None:
    _check_keys(cfg, CONFIG_KEYS[""], "")
    for table in ("plant", "model", "trajectory", "simulation", "payload", "design"):
        if table in cfg:
            _check_keys(cfg[table], CONFIG_KEYS[table], table)
    if "controller" in cfg:
        ctrl = cfg["controller"]
        if not isinstance(ctrl, dict):
            raise ConfigError(f"config: controller must be a table, got {ctrl!r}")
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
    gains = _check_keys(cfg.get("gains", {}), tuple(LAWS), "gains")
    for law, table in gains.items():
        names = [f for f in LAWS[law].__dataclass_fields__ if f not in ("theta", "rho", "rho_i")]
        _check_keys(table, names + (["eps"] if "eps_i" in names else []), f"gains.{law}")
    if "verified" in cfg.get("design", {}) and not isinstance(cfg["design"]["verified"], bool):
        raise ConfigError(f"config: [design] verified must be true or false, got {cfg['design']['verified']!r}")
    seed = cfg.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise ConfigError(f"config: seed must be an integer in [0, 2^63), got {seed!r}")
    if not isinstance(cfg.get("perturbed", False), bool):
        raise ConfigError(f"config: perturbed must be true or false, got {cfg['perturbed']!r}")
    lock = cfg.get("lock", {})
    if not isinstance(lock, dict) or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in lock.values()):
        raise ConfigError(f"config: lock must be a table of joint = value [rad or m], got {lock!r}")
    for key, where in (("robot", cfg), ("urdf", cfg), ("bounds", cfg), ("box", cfg), ("spec", cfg.get("plant", {})),
                       ("urdf", cfg.get("plant", {})),
                       ("box", cfg.get("plant", {}))):
        if key in where and not isinstance(where[key], str):
            raise ConfigError(f"config: {key} must be a string, got {where[key]!r}")



def _model(law_cls, plant, bounds: _Bounds, perturbed: bool, cfg: dict) -> dict:
    """The controller's model and where it came from (bounds only when the law needs them)."""
    which = cfg.get("theta", "paper" if perturbed else "plant")
    p = plant.p
    pay = bounds.payload is not None
    if isinstance(which, list):
        th = np.asarray(which, dtype=float)
        if th.shape != (p,) or not np.all(np.isfinite(th)):
            raise ConfigError(f"model theta must be {p} finite numbers, got {which}")
        src = "theta from config"
    elif which == "plant":
        th, src = plant.theta, "theta of the plant (ideal)"
    elif pay and which in ("paper", "certified", "payload"):
        th, src = bounds.pay.theta0, "theta_0 = centre of the exact payload segment"
    elif which == "paper":
        th, src = bounds.paper.theta0, "theta_0 by the paper's method (a): (theta(nominal) + theta(p_up)) / 2"
    elif which == "certified":
        th, src = bounds.cert.theta0, "theta_0 = centre of the exact ranges over the box"
    else:
        raise ConfigError(f"model theta must be 'plant', 'paper', 'certified' or {p} numbers, got {which!r}")
    inputs = law_cls.model_inputs
    rho = rho_i = rho_src = None
    if "rho_i" in inputs:
        _, rho_i = certified_radius(bounds.cert, th)
    if "rho" in inputs:
        rho_cfg = cfg.get("rho", "paper")
        if pay and rho_cfg in ("paper", "certified", "payload"):
            rho, _ = certified_radius(bounds.pay, th)
            rho_src = "payload: exact, sqrt(sum rho_i^2) over the payload segment around theta_0"
        elif rho_cfg == "paper":
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
    needs_bounds = which in ("paper", "certified", "payload") or rho is not None or rho_i is not None
    return {
        "theta0": _floats(th), "rho": None if rho is None else float(rho), "rho_i": _floats(rho_i),
        "theta_source": src, "rho_source": rho_src,
        "rho_i_source": "certified per-coefficient radius around theta_0" if rho_i is not None else None,
        "box": bounds.source() if needs_bounds else None, "nominal": bounds.nominal.label,
    }


def _file_model(law_cls, bf: dict, nominal) -> dict:
    """The controller's model from an identification's ``bounds.toml`` (``bf``, read by
    :func:`rc3r.identify.bounds_file.load_bounds`, checked against the nominal robot's n, p and
    coefficient names)."""
    path = bf["source"]
    inputs = law_cls.model_inputs
    src = f"identified bounds {path} (confidence {bf.get('confidence')})"
    return {
        "theta0": _floats(bf["theta0"]), "rho": float(bf["rho"]) if "rho" in inputs else None,
        "rho_i": _floats(bf["rho_i"]) if "rho_i" in inputs else None,
        "P": np.asarray(bf["P"]).tolist() if "P" in inputs else None,
        "theta_source": f"theta_0 of {src}", "rho_source": f"ball containing the ellipsoid of {src}",
        "rho_i_source": "box containing the ellipsoid" if "rho_i" in inputs else None,
        "box": None, "nominal": nominal.label, "bounds_file": str(path),
    }


def _law(kind: str, model: dict, cfg: dict, eps_override, table: dict | None = None):
    gains = dict(table or {})  # [gains.<law>] of the config, then [controller] wins
    gains.update({k: v for k, v in cfg.items() if k != "kind"})
    names = {f for f in LAWS[kind].__dataclass_fields__}
    if eps_override is not None:
        gains["eps"] = eps_override
    if "eps" in gains and "eps" not in names and "eps_i" in names:  # eq. (7): one eps for every coefficient
        gains.setdefault("eps_i", gains.pop("eps"))
    try:
        if "P" in names and model.get("P") is not None:
            gains.setdefault("P", np.asarray(model["P"], dtype=float))
        return make_law(kind, model["theta0"], rho=model["rho"], rho_i=model["rho_i"], **gains)
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ConfigError(f"controller {kind}: {exc}") from None


def build_run(*, robot: str | None = None, controller: str | None = None, perturbed: bool = False,
              plant: str | None = None, eps: float | None = None, rate: float | None = None,
              duration: float | None = None, engine: str | None = None, box: str | None = None,
              payload=None, payload_com=None, config: dict | None = None, name: str | None = None,
              urdf=None, lock: dict | None = None, friction=None, torque_limit=None, noise=None, delay=None,
              plant_engine: str | None = None, tolerance: float | None = None, plant_rng=None,
              bounds: str | None = None, effects: dict | None = None) -> RunSpec:
    """Resolve a run from keyword options (command line) over a config dict (TOML).

    Keyword options win over the config; both over the defaults (the robot's
    nominal parameters, default box and trajectory; the laws' default gains; 10 s).
    Config keys: ``robot``, ``seed``, ``perturbed``, ``box``, ``[plant]`` (``spec``,
    ``urdf``, legacy ``box``), ``[model]`` (``theta``, ``rho``), ``[controller]``
    (``kind`` and gains), ``[trajectory]``, ``[simulation]`` (docs/control.md).
    A payload makes the run perturbed unless ``[model] theta = "plant"`` (module docstring).
    ``urdf`` (and ``lock``, ``{joint: value}``) read the nominal robot from a URDF (any serial arm
    through Pinocchio unless ``robot`` names a closed-form one). ``friction``, ``torque_limit``,
    ``noise``, ``delay``, ``plant_engine`` and the ``[plant]`` table's effect keys build the true
    plant and its loop (:func:`rc3r.plants.resolve`); ``effects`` (``[plant]`` keys of registered effects,
    e.g. the command line's, :func:`rc3r.cli.run.plant_options`) win over the table's; ``tolerance`` [rad] is
    the verdict's. ``bounds`` (or config ``bounds``) is a ``bounds.toml`` of ``rc3r identify``: the controller's
    theta_0, rho, rho_i and ellipsoid P come from it (:func:`_file_model`); the plant is by default the file's
    centre when it has link parameters (``[physical]``: the identified robot), else the nominal robot; or a URDF,
    ``nominal``, or drawn from the ellipsoid (``random:<seed>``, ``boundary:<seed>``:
    :func:`rc3r.uncertainty.ellipsoid.draw_from_ellipsoid`).
    """
    cfg = config or {}
    _check_config(cfg, controller)
    tolerance = _tolerance(tolerance if tolerance is not None else cfg.get("tolerance"))
    seed = int(cfg.get("seed", 0))
    lock = lock if lock is not None else ({k: float(v) for k, v in cfg["lock"].items()} if cfg.get("lock") else None)
    nominal = _nominal(robot or cfg.get("robot"), urdf if urdf is not None else cfg.get("urdf"), lock)
    ctrl_cfg = dict(cfg.get("controller", {}))
    kind = controller or ctrl_cfg.get("kind", "robust")
    if kind not in LAWS:
        raise ConfigError(f"unknown controller {kind!r} ({', '.join(LAWS)})")
    perturbed = perturbed or bool(cfg.get("perturbed", False))
    plant_cfg = dict(cfg.get("plant", {}))
    pay_cfg = dict(cfg.get("payload", {}))
    payload = _payload(payload if payload is not None else pay_cfg.get("mass"),
                       payload_com if payload_com is not None else pay_cfg.get("com"))
    model_cfg = dict(cfg.get("model", {}))
    if payload is not None and model_cfg.get("theta") != "plant":
        perturbed = True  # a payload range is unknown to the controller: it gets theta_0 and rho of the range
    box_bounds = _Bounds(nominal, box or cfg.get("box") or plant_cfg.get("box"), payload)
    from .uncertainty.urdf import parse_spec as _urdf_spec

    box_bounds.urdf_uncertainty = _urdf_spec(plant_cfg.get("urdf_uncertainty"))  # checked; None: none
    spec = plant or plant_cfg.get("spec", "nominal")
    default_plant = plant is None and not {"spec", "urdf"} & set(plant_cfg)  # no plant named (see the bounds below)
    if "urdf" in plant_cfg and spec == "nominal":
        spec = str(plant_cfg["urdf"])
    if spec == "random":
        spec = f"random:{seed}"
    if isinstance(spec, str) and spec.startswith("random:"):
        try:
            seed = int(spec.partition(":")[2])  # the seed that actually drew the plant is recorded
        except ValueError:
            pass  # perturb() refuses the spec with its own message
    bounds_path = bounds if bounds is not None else cfg.get("bounds")
    file_model = bounds_path is not None and model_cfg.get("theta") != "plant"
    if bounds_path is not None and (file_model or _drawn(spec)):
        from .identify.bounds_file import load_bounds

        bounds_file = load_bounds(bounds_path, robot=nominal)  # read once: for the plant and for the model
        if default_plant and file_model and bounds_file.get("physical") is not None:
            spec = "centre"  # the identified robot the bounds are about, not the URDF's (docs/control.md)
        _check_bounds_robot(bounds_file, robot or cfg.get("robot"),
                            urdf if urdf is not None else cfg.get("urdf"))
        if file_model:  # before any plant is drawn from it: a centre that is no rigid body is refused first
            dur = duration if duration is not None else dict(cfg.get("simulation", {})).get("duration")
            _check_model_mass(nominal, {"theta0": bounds_file["theta0"]},
                              trajectory_from_config(dict(cfg.get("trajectory", {})), nominal.default_trajectory()),
                              dur, bounds_path, None)
    act = bounds_file.get("actuator") if bounds_path is not None and (file_model or _drawn(spec)) else None
    model_robot = actuated_model(nominal, act) if act else nominal  # friction, armature: docs/control.md
    the_plant = ((_actuated_bounds_plant if act else _bounds_plant)(nominal, bounds_file, spec)
                 if bounds_path is not None and _drawn(spec) else _plant(nominal, box_bounds, spec, seed))
    joint_note = None
    if act and the_plant.p != model_robot.p:  # a plant of the rigid body alone: no joint coefficients
        the_plant = model_robot.with_rigid(the_plant).with_joint(None)
        joint_note = _joint_outside(act)
    if bounds_path is not None:
        perturbed = file_model
        model = _file_model(LAWS[kind], dict(bounds_file, **(act or {})), nominal) if perturbed else \
            _model(LAWS[kind], the_plant, box_bounds, False, model_cfg)
    else:
        model = _model(LAWS[kind], the_plant, box_bounds, perturbed, model_cfg)
    if model_cfg.get("friction") is not None:  # joint coefficients with a range (docs/control.md)
        if act:
            raise ConfigError("[model] friction and a bounds file with joint coefficients: give one")
        model_robot, the_plant, model = with_model_friction(nominal, the_plant, model, model_cfg["friction"], spec,
                                                            perturbed)
        act = True
    traj_cfg = dict(cfg.get("trajectory", {}))
    traj = trajectory_from_config(traj_cfg, nominal.default_trajectory())
    warnings = [] if joint_note is None else [joint_note]
    if traj_cfg.get("kind", "paper") in ("paper", "default"):  # the robot's default trajectory is used
        warnings += nominal.default_trajectory_warnings()
    if traj.n != the_plant.n:
        raise ConfigError(f"trajectory has {traj.n} joints, robot '{nominal.label}' has {the_plant.n}")
    sim = dict(cfg.get("simulation", {}))
    if bounds_path is None:  # a bounds file's centre was checked when it was read
        _check_model_mass(model_robot, model, traj, duration if duration is not None else sim.get("duration"), None,
                          model_cfg.get("theta"))
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
    from .plants import resolve

    if plant_rng is None:  # uncertain plant effects (friction ranges) are drawn with the plant's own seed
        plant_rng = np.random.default_rng(seed)
    given = dict(effects or {}, **{k: v for k, v in (("friction", friction), ("torque_limit", torque_limit))
                                   if v is not None})
    true_plant, loop, _ = resolve(the_plant, plant_cfg, seed=seed, rng=plant_rng, noise=noise, delay=delay,
                                  plant_engine=plant_engine, **given)
    if act:
        true_plant = with_joint_friction(true_plant, the_plant)
    if loop is not None and loop.active and opts.rate is None:
        raise ConfigError("sensor noise, quantization and delay act on a sampled controller: give a rate (--rate HZ)")
    table = dict(cfg.get("gains", {}).get(kind, {}))
    if opts.rate is not None and eps is None and not table and set(ctrl_cfg) <= {"kind"}:
        # defaults that work: no gain given for a sampled run -> the sampled-data rule's (docs/design.md)
        from .design.rule import sampled_gains

        table, note = sampled_gains(kind, model_robot, traj, model, opts.rate, duration=opts.duration,
                                    delay=0 if loop is None else int(loop.delay))
        if note is not None:
            model = {**model, "gains_source": note}
    law = _law(kind, model, ctrl_cfg, eps, table or {})
    return RunSpec(name or f"{kind}-{scenario}", the_plant, law, traj, opts, seed, scenario, model, tuple(warnings),
                   true_plant, loop, model_robot, tolerance)


def _tolerance(tol) -> float | None:
    """The verdict's tracking tolerance [rad]: None, or a finite number > 0 (ParameterError otherwise)."""
    if tol is not None and (isinstance(tol, bool) or not isinstance(tol, (int, float, np.integer, np.floating))):
        raise ParameterError(f"tolerance must be a number of rad, got {tol!r}")
    if tol is not None and not (np.isfinite(tol) and tol > 0):
        raise ParameterError(f"tolerance must be finite and > 0 rad, got {tol!r}")
    return None if tol is None else float(tol)


def _joint_outside(act: dict) -> str | None:
    """A warning when a plant without joint friction lies outside a bounds file's joint coefficients.

    The plant (the rigid body alone) has every joint coefficient 0; ``act`` is ``load_bounds``'s
    ``"actuator"`` part. Returns None when 0 is inside every joint coefficient's half-width ``rho_i``.
    """
    p = int(act["rigid_p"])
    th, ri = np.asarray(act["theta0"], float)[p:], np.asarray(act["rho_i"], float)[p:]
    k = int(np.argmax(ratio := np.abs(th) / np.maximum(ri, 1e-300)))
    if ratio[k] <= 1.0:
        return None
    name = list(act["coefficient_names"])[p + k]
    return (f"the plant has no joint friction but the bounds' centre has: {name} = {th[k]:.3g} is {ratio[k]:.3g} "
            f"rho_i from 0, so the law compensates friction this plant lacks (--plant centre runs the identified arm)")


def _check_bounds_robot(bf: dict, robot: str | None, urdf) -> None:
    """A ``bounds.toml`` names the robot it was identified on (``robot = NAME``): a run of another registered
    robot is refused, naming both (their sizes and coefficient names may agree, the coefficients do not).
    A file of a URDF arm, or a run from a URDF, is checked by sizes and names only (load_bounds)."""
    named = bf.get("robot")
    if named is None or (urdf is not None and robot is None):
        return
    ours = robot or DEFAULT_ROBOT
    if named != ours:
        raise ConfigError(f"bounds file {bf['source']} was identified on robot '{named}', the run's robot is "
                          f"'{ours}': identify '{ours}' (rc3r identify --robot {ours}) or run --robot {named}")


def _check_model_mass(nominal, model: dict, traj, duration, bounds_path, theta_cfg) -> None:
    """Refuse (one line) a model theta from a bounds file or a config list whose mass matrix is not positive
    definite along the reference (:func:`rc3r.uncertainty.ellipsoid.require_positive_mass_matrix`)."""
    if bounds_path is not None:
        source = f"bounds file {bounds_path}"
    elif isinstance(theta_cfg, list):
        source = "model theta of the config"
    else:
        return
    from .uncertainty.ellipsoid import require_positive_mass_matrix

    require_positive_mass_matrix(nominal, model["theta0"], traj, float(duration if duration is not None else 10.0),
                                 source)


def _nominal(robot: str | None, urdf=None, lock: dict | None = None):
    """The controller's model: the registered ``robot`` (default the paper's arm), or read from ``urdf``
    (a closed-form robot's own reader when ``robot`` names one, else any serial arm through Pinocchio),
    with the joints of ``lock`` fixed."""
    from .robots import robot_class

    if urdf is None:
        if not lock:
            return _robot_cached(("robot", robot or DEFAULT_ROBOT), lambda: load_robot(robot or DEFAULT_ROBOT))
        from .robots.pinocchio import NAMED, PinocchioRobot

        if (robot or DEFAULT_ROBOT) not in NAMED:
            raise ConfigError(f"--lock needs an arm read through Pinocchio (--urdf PATH or one of {', '.join(NAMED)})")
        return PinocchioRobot.named(robot, lock={**NAMED[robot][1], **lock})
    cls = robot_class(robot) if robot else None
    if cls is not None and cls.name == robot and not lock:  # a closed-form robot's own URDF reader
        return cls.from_urdf(urdf)
    return _urdf_robot_cached(urdf, lock)


#: Robots already read in this process (:func:`_robot_cached`).
_ROBOT_CACHE: dict = {}


def _robot_cached(key, make):
    """``make()``, once per ``key`` in a process: the controller's model of a registered robot or a URDF arm.

    Reading a Pinocchio arm computes its base parameters (a least-squares fit and an SVD: about 4 s for
    the UR5, ten times its 2 s simulation at 1 kHz), and a campaign worker builds every job of a design
    or a Monte Carlo from the same arm. A run does not change the robot (plants are new objects), so the
    cached one is returned.
    """
    if key not in _ROBOT_CACHE:
        _ROBOT_CACHE[key] = make()
    return _ROBOT_CACHE[key]


def _urdf_robot_cached(urdf, lock: dict | None = None):
    """:func:`rc3r.robots.load_urdf_robot` through :func:`_robot_cached`, keyed by the file (its real path,
    mtime and size: a file changed on disk is read again) and the locked joints."""
    import os

    from .robots import load_urdf_robot
    from .urdf_names import resolve_erd

    urdf = resolve_erd(urdf)  # erd:REL -> the file of example-robot-data
    try:
        st = os.stat(urdf)
        key = ("urdf", os.path.realpath(urdf), st.st_mtime_ns, st.st_size, tuple(sorted((lock or {}).items())))
    except (OSError, TypeError, ValueError):
        return load_urdf_robot(urdf, lock=lock)  # the reader gives the error
    return _robot_cached(key, lambda: load_urdf_robot(urdf, lock=lock))


def execute(spec: RunSpec) -> tuple[SimResult, dict]:
    """Simulate a resolved run (its plant with the effects, its loop, the controller's model); return the
    result and its metrics (with the model's provenance)."""
    res = simulate(spec.true_plant if spec.true_plant is not None else spec.true_rigid, spec.law, spec.trajectory,
                   spec.options, loop=spec.loop, model=spec.controller_model)
    m = run_metrics(res, seed=spec.seed, tolerance=spec.tolerance)
    m.update({"name": spec.name, "scenario": spec.scenario, "model": spec.model})
    if spec.warnings:
        m["warnings"] = list(spec.warnings)
    return res, m
