r"""The plants of a run's bounds: a payload range, an uncertainty box (around a URDF too), an
identification's ellipsoid; the plant spec a run names (``nominal``, ``upper``, ``random:<seed>``,
``centre``, ``lightest:...`` ...) drawn from them.

:func:`rc3r.runspec.build_run` resolves a run's bounds into a :class:`_Bounds` and asks :func:`_plant`
for the plant; ``rc3r design``'s verification draws the same plants (:mod:`rc3r.design.verify`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import ConfigError
from .uncertainty import certified_bounds, load_box, paper_bounds, perturb

__all__ = ["resolve_box"]


def _payload(mass, com):
    """``((lo, hi), com)`` from a mass interval [kg] and a CoM (3,) [m], or None; validated."""
    if mass is None:
        if com is not None:
            raise ConfigError("a payload CoM was given without a payload mass interval")
        return None
    try:
        lo, hi = (float(x) for x in mass)
        c = np.zeros(3) if com is None else np.asarray(com, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"payload mass must be [lo, hi] kg and com 3 numbers, got {mass!r}, {com!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo <= hi) or c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ConfigError(f"payload mass must satisfy 0 <= lo <= hi (finite) and com be 3 finite numbers, "
                          f"got {mass!r}, {com!r}")
    return (lo, hi), c


def resolve_box(nominal, box_path=None):
    """The box of a run: ``box_path`` (TOML) if given, else the robot's default box."""
    if box_path is not None:
        return load_box(box_path, nominal.standard_parameter_names)
    box = nominal.default_box()
    if box is None:
        raise ConfigError(f"robot {nominal.robot_name or nominal.name!r} has no default box: "
                          "give --box FILE or --payload LO:HI")
    return box


class _Bounds:
    """The uncertainty of one run (a box, or a payload) and its bounds, each computed at most once."""

    def __init__(self, nominal, box_path=None, payload=None):
        self.nominal, self.box_path, self.payload = nominal, box_path, payload
        self.urdf_uncertainty = None  # [plant] urdf_uncertainty (a spec): the plants' arm beyond the bounds
        self._box = self._paper = self._cert = self._pay = None

    @property
    def box(self):
        if self._box is None:
            self._box = resolve_box(self.nominal, self.box_path)
        return self._box

    @property
    def paper(self):
        if self.payload is not None:
            return self.pay
        if self._paper is None:
            self._paper = paper_bounds(self.nominal, self.box)
        return self._paper

    @property
    def cert(self):
        if self.payload is not None:
            return self.pay
        if self._cert is None:
            self._cert = certified_bounds(self.nominal, self.box)
        return self._cert

    @property
    def pay(self):
        if self._pay is None:
            from .uncertainty.payload import payload_bounds

            mass, com = self.payload
            self._pay = payload_bounds(self.nominal, mass, com)
        return self._pay

    def source(self) -> str:
        if self.payload is not None:
            (lo, hi), com = self.payload
            return f"payload of {lo:g}..{hi:g} kg at {tuple(float(c) for c in com)} m in the last joint frame"
        return self.box.source


def _urdf_set(nominal, bounds: _Bounds):
    """The URDF's own uncertainty of the plants (``[plant] urdf_uncertainty``,
    :class:`rc3r.uncertainty.urdf.URDFSet` of ``nominal``), or None."""
    from .uncertainty.urdf import URDFSet, parse_spec

    spec = parse_spec(bounds.urdf_uncertainty)
    return None if spec is None else URDFSet(nominal, spec)


def _arm_seed(seed: int) -> int:
    """The seed of the arm drawn in the URDF uncertainty beside plant ``random:<seed>``."""
    return int(np.random.SeedSequence([int(seed), 36]).generate_state(1, np.uint64)[0] >> np.uint64(1))


def _plant(nominal, bounds: _Bounds, spec: str, seed: int):
    if spec.endswith(".urdf") or Path(spec).suffix == ".urdf":
        lock = nominal.locked
        plant = type(nominal).from_urdf(spec, lock=lock) if lock else type(nominal).from_urdf(spec)
    elif bounds.payload is not None:
        plant = _payload_plant(nominal, bounds.payload, spec, _urdf_set(nominal, bounds))
    elif spec == "nominal":
        plant = nominal
    else:
        # random draws are redrawn (same seeded stream) until the robot is physical
        uset = _urdf_set(nominal, bounds)
        spec, plus, arm = spec.partition("+")
        if plus and uset is None:
            raise ConfigError(f"plant {spec}+{arm}: '+' needs [plant] urdf_uncertainty")
        if uset is not None:  # the plants' arm goes beyond the URDF by its own error (the model keeps the box)
            kind, _, arg = spec.partition(":")
            if plus:
                nominal = uset.plant(arm)
            elif kind == "random" and arg.isdigit():
                nominal = uset.random(_arm_seed(int(arg)))
        plant = nominal if spec == "nominal" else perturb(nominal, bounds.box, spec,
                                                          simulable=spec.startswith("random"))
    plant.require_simulable()
    return plant


def _drawn(spec) -> bool:
    """True for a plant spec drawn from an ellipsoid of bounds (``centre``, ``random:``, ``boundary:``)."""
    kind = str(spec).strip().partition(":")[0].lower()
    return kind in ("centre", "center", "random", "boundary", "lightest")


def _bounds_plant(nominal, bf: dict, spec: str):
    """A plant drawn from the ellipsoid of an identification's ``bounds.toml`` (``bf``, read by
    :func:`rc3r.identify.bounds_file.load_bounds`; :func:`rc3r.uncertainty.ellipsoid.draw_from_ellipsoid`)."""
    from .uncertainty.ellipsoid import draw_from_ellipsoid

    return draw_from_ellipsoid(nominal, bf["theta0"], bf["P"], spec, source=f"bounds file {bf['source']}",
                               physical=bf.get("physical"))


def _payload_plant(nominal, payload, spec: str, uset=None):
    """The plant carrying a payload: ``upper`` (default, also for ``nominal``) the heaviest,
    ``lower`` the lightest, ``random:<seed>`` a seeded uniform mass, ``mass:<kg>`` a given one.

    With the URDF's own uncertainty ``uset`` (a :class:`rc3r.uncertainty.urdf.URDFSet`, ``[plant]
    urdf_uncertainty``) ``random:<seed>`` also draws the arm in it (``urdf-random:<s>``, s from
    ``SeedSequence([seed, 36])``), and ``<payload spec>+<arm spec>`` (``lower+urdf-lower`` ...) puts the arm
    where the arm spec says (``rc3r design``'s search)."""
    from .uncertainty.payload import with_payload

    (lo, hi), com = payload
    spec, plus, arm = spec.partition("+")
    if plus and uset is None:
        raise ConfigError(f"plant {spec}+{arm!r}: '+' needs [plant] urdf_uncertainty")
    kind, _, arg = spec.partition(":")
    if uset is not None:
        if plus:
            nominal = uset.plant(arm)
        elif kind == "random" and arg.isdigit():
            nominal = uset.random(_arm_seed(int(arg)))
    if kind in ("nominal", "upper") and not arg:
        m = hi
    elif kind == "lower" and not arg:
        m = lo
    elif kind == "random" and arg.isdigit():
        m = float(np.random.default_rng(int(arg)).uniform(lo, hi))
    elif kind == "mass":
        try:
            m = float(arg)
        except ValueError:
            m = float("nan")
        if not lo <= m <= hi:
            raise ConfigError(f"plant {spec!r}: the payload mass must be a number in [{lo:g}, {hi:g}] kg")
    else:
        raise ConfigError(f"bad plant {spec!r} with a payload: expected upper, lower, random:<seed>, mass:<kg>")
    return with_payload(nominal, m, com, label=f"{nominal.label} + payload {m:g} kg")


def actuated_model(nominal, act: dict, label: str = "nominal"):
    """The controller's :class:`~rc3r.robots.actuated.ActuatedRobot` of a bounds file's ``actuator`` part (``bf
    ["actuator"]`` of :func:`rc3r.identify.bounds_file.load_bounds`): ``nominal`` with the joint coefficients of its
    centre ``theta0[p:]``."""
    from .robots.actuated import ActuatedRobot

    theta0 = np.asarray(act["theta0"], dtype=float)
    if int(act.get("rigid_p", nominal.p)) != nominal.p or theta0.size <= nominal.p:
        raise ConfigError(f"the actuator part of the bounds has {theta0.size} coefficients over {act.get('rigid_p')} "
                          f"rigid ones; robot '{nominal.label}' has {nominal.p}")
    return ActuatedRobot(nominal, act["kinds"], float(act["coulomb_velocity"]), theta0[nominal.p:], label=label)


def _joint_issue(model, joint) -> str | None:
    """Why ``joint`` coefficients are no plant's (negative viscous, Coulomb or armature), or None."""
    issues = [i for i in model.with_joint(joint).physical_issues() if i.startswith("negative")]
    return issues[0] if issues else None


def _actuated_bounds_plant(nominal, bf: dict, spec: str):
    """A plant drawn from the ellipsoid over rigid **and** joint coefficients (``bf["actuator"]``): an
    :class:`~rc3r.robots.actuated.ActuatedRobot` (its armature in the rigid body; its friction becomes the plant's
    Friction effect, :func:`with_joint_friction`). ``centre``: the rigid centre (as :func:`_bounds_plant`) and the
    joint centre; ``random:<s>``/``boundary:<s>``: the rigid body drawn as without joint coefficients (:func:`_bounds_plant`:
    physical by construction), then the joint part uniformly in (on the boundary of) the full ellipsoid's
    slice at that rigid part (seed ``SeedSequence([s, 35])``), its viscous, Coulomb and armature
    coefficients clipped at 0 (:func:`_clip_joint`; a rejection of draws with any of them negative found
    none in 200 on a real Panda's bounds: 28 joint coefficients, seven armatures centred at 0);
    ``lightest:...``: the full ellipsoid's lightest point, its rigid part realised as a ``lightest:`` plant of
    :func:`_bounds_plant` (physical link parameters inside the ellipsoid, the point pulled toward theta_0 by
    the first fraction of :data:`~rc3r.uncertainty.ellipsoid.PULL` that allows it), its joint part pulled by the
    same fraction and clipped at 0 where negative."""
    from .errors import ParameterError
    from .uncertainty.box import spec_seed
    from .uncertainty.ellipsoid import lightest_theta, realise_theta, realise_toward

    act, p = bf["actuator"], nominal.p
    model = actuated_model(nominal, act)
    theta0, P = np.asarray(act["theta0"], dtype=float), np.asarray(act["P"], dtype=float)
    source = f"bounds file {bf['source']}"
    kind, _, arg = str(spec).strip().partition(":")
    kind = kind.lower()
    if kind in ("centre", "center") and not arg:
        why = _joint_issue(model, theta0[p:])
        if why:
            raise ParameterError(f"the centre of {source} is no plant: {why}")
        return model.with_rigid(_bounds_plant(nominal, bf, spec), "centre")
    if kind == "lightest":  # the rigid part as without joint coefficients: in the physical chart, pulled inside
        theta = lightest_theta(model, theta0, P, arg, spec)
        got = realise_toward(nominal, bf["theta0"], bf["P"], theta[:p], physical=bf.get("physical"), source=source,
                             spec=spec)  # the projection's ellipsoid holds the rigid part of a point of the full one
        if got is None:  # no link parameters in the file (the 3R): the robot nearest the URDF's
            try:
                rigid = realise_theta(nominal, theta[:p], label=spec)
                rigid.require_simulable()
            except ParameterError as exc:
                raise ParameterError(f"plant {spec!r}: no simulable robot near '{nominal.label}' realises it: "
                                     f"{exc}") from None
            got = (rigid, 1.0)
        rigid, f = got
        joint = _clip_joint(model, theta0[p:] + f * (theta[p:] - theta0[p:]), nominal.n)  # pulled as the rigid part
        return model.with_rigid(rigid, spec).with_joint(joint, spec)
    if kind not in ("random", "boundary"):
        from .uncertainty.ellipsoid import ELLIPSOID_SPECS

        raise ConfigError(f"bad plant {spec!r} with bounds from {source}: expected nominal, {ELLIPSOID_SPECS}")
    rigid = _bounds_plant(nominal, bf, spec)  # the rigid body as without joint coefficients: physical chart
    d_r = np.asarray(rigid.theta, dtype=float) - theta0[:p]
    Pjj, Pjr = P[p:, p:], P[p:, :p]
    centre = theta0[p:] - np.linalg.solve(Pjj, Pjr @ d_r)  # the full ellipsoid's slice at the drawn rigid part
    r2 = max(0.0, 1.0 - float(d_r @ (P[:p, :p] - Pjr.T @ np.linalg.solve(Pjj, Pjr)) @ d_r))
    rng = np.random.default_rng(np.random.SeedSequence([spec_seed(spec, kind, arg, "bad plant"), 35]))
    u = rng.standard_normal(centre.size)
    u /= np.linalg.norm(u)
    if kind == "random":
        u *= rng.uniform() ** (1.0 / u.size)  # uniform in the unit ball
    joint = centre + np.sqrt(r2) * np.linalg.solve(np.linalg.cholesky(Pjj).T, u)
    joint = _clip_joint(model, joint, nominal.n)
    return model.with_rigid(rigid, spec).with_joint(joint, spec)


def _clip_joint(model, joint, n: int):
    """``joint`` with its viscous, Coulomb and armature coefficients clipped at 0 (the chart in which every
    draw is physical; offsets keep their sign)."""
    joint = np.array(joint, dtype=float)
    for k in ("viscous", "coulomb", "armature"):
        if k in model.kinds:
            i = model.kinds.index(k)
            joint[i * n:(i + 1) * n] = np.maximum(joint[i * n:(i + 1) * n], 0.0)
    return joint


def with_joint_friction(true_plant, rigid):
    """``true_plant`` (a :class:`~rc3r.plants.Plant` on the rigid body ``rigid``) with the Friction effect of
    ``rigid``'s joint coefficients (an :class:`~rc3r.robots.actuated.ActuatedRobot`); ConfigError if the plant
    already has a friction effect (``--friction``, ``[plant] friction``: the bounds' plants carry their own)."""
    from .plants import Plant

    own = rigid.as_plant().effects
    if not own:
        return true_plant
    if true_plant.effect("friction") is not None:
        raise ConfigError("the plant drawn from the bounds carries its identified friction: drop --friction / "
                          "[plant] friction")
    return Plant(true_plant.rigid, own + tuple(true_plant.effects), label=true_plant._label)


#: ``[model] friction``'s default relative range of every joint coefficient (its nominal times lo..hi).
FRICTION_RANGE = (0.5, 1.5)
_MODEL_FRICTION_KEYS = ("viscous", "coulomb", "offset", "armature", "v_s", "range")


def _model_friction_values(nominal, cfg):
    """``(kinds, v_s, joint0 (n m,), (lo, hi))`` of a ``[model] friction`` value (``"urdf"`` or a table)."""
    from .robots.actuated import parse_kinds

    if cfg == "urdf":
        cfg = {"viscous": "urdf", "coulomb": "urdf"}
    if not isinstance(cfg, dict):
        raise ConfigError(f"[model] friction must be \"urdf\" or a table ({', '.join(_MODEL_FRICTION_KEYS)}), got {cfg!r}")
    unknown = sorted(set(cfg) - set(_MODEL_FRICTION_KEYS))
    if unknown:
        raise ConfigError(f"[model.friction]: unknown key(s) {', '.join(unknown)} (valid: {', '.join(_MODEL_FRICTION_KEYS)})")
    kinds = parse_kinds([k for k in ("viscous", "coulomb", "offset", "armature") if k in cfg])
    if not kinds:
        raise ConfigError("[model.friction] names no coefficient (viscous, coulomb, offset, armature)")
    n, vals = nominal.n, []
    for k in kinds:
        v = cfg[k]
        if v == "urdf" and k in ("viscous", "coulomb"):
            v = np.array(nominal.model.damping if k == "viscous" else nominal.model.friction, dtype=float)
            if v.size != n or not np.any(v):
                raise ConfigError(f"[model.friction] {k} = \"urdf\": robot '{nominal.label}' has no <dynamics "
                                  f"{'damping' if k == 'viscous' else 'friction'}> (give numbers)")
        try:
            v = np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy()
        except (TypeError, ValueError):
            raise ConfigError(f"[model.friction] {k} must be \"urdf\" (viscous, coulomb), one number or {n}, "
                              f"got {cfg[k]!r}") from None
        if not np.all(np.isfinite(v)) or (k != "offset" and np.any(v < 0)):
            raise ConfigError(f"[model.friction] {k} must be finite{' and >= 0' if k != 'offset' else ''}, got {v.tolist()}")
        vals.append(v)
    rng_ = cfg.get("range", FRICTION_RANGE)
    try:
        lo, hi = (float(x) for x in rng_)
    except (TypeError, ValueError):
        lo = hi = float("nan")
    if not (0.0 <= lo <= 1.0 <= hi < np.inf):
        raise ConfigError(f"[model.friction] range must be [lo, hi] with 0 <= lo <= 1 <= hi, got {rng_!r}")
    v_s = float(cfg.get("v_s", 0.05))
    if not (np.isfinite(v_s) and v_s > 0):
        raise ConfigError(f"[model.friction] v_s must be > 0 [rad/s], got {cfg.get('v_s')!r}")
    return kinds, v_s, np.concatenate(vals), (lo, hi)


def with_model_friction(nominal, the_plant, model: dict, cfg, spec: str, perturbed: bool):
    """``(model_robot, plant, model)`` with the joint coefficients of ``[model] friction`` (docs/control.md):
    each coefficient lies in ``[lo, hi]`` times its nominal value (the URDF's ``<dynamics damping friction>`` or
    the table's numbers; ``range``, default :data:`FRICTION_RANGE`), so theta_0's joint part is the centre of
    those intervals, rho_i their half-widths and rho = sqrt(rho_r^2 + sum rho_i,joint^2) (the ball around the
    product of the rigid set and the intervals). The plant carries the nominal values, or for ``random:<seed>``
    a uniform draw in the intervals (generator ``SeedSequence([seed, 35])``); an ideal run's model is the plant."""
    from .robots.actuated import ActuatedRobot

    kinds, v_s, j0, (lo, hi) = _model_friction_values(nominal, cfg)
    a, b = np.minimum(lo * j0, hi * j0), np.maximum(lo * j0, hi * j0)
    kind, _, arg = str(spec).partition(":")
    joint = j0
    if kind == "random" and arg.isdigit():
        joint = np.random.default_rng(np.random.SeedSequence([int(arg), 35])).uniform(a, b)
    plant = ActuatedRobot(the_plant, kinds, v_s, joint, label=the_plant.label)
    centre, half = 0.5 * (a + b), 0.5 * (b - a)
    th_j = centre if perturbed else joint
    out = dict(model, theta0=list(model["theta0"]) + th_j.tolist(),
               friction_source=f"{', '.join(kinds)} in {lo:g}..{hi:g} x nominal, v_s = {v_s:g} rad/s")
    if model.get("rho") is not None:
        out["rho"] = float(np.hypot(model["rho"], np.linalg.norm(half)))
    if model.get("rho_i") is not None:
        out["rho_i"] = list(model["rho_i"]) + half.tolist()
    if model.get("P") is not None:
        raise ConfigError("[model] friction with an ellipsoid P: use a bounds file with an actuator part")
    return ActuatedRobot(nominal, kinds, v_s, th_j, label=nominal.label), plant, out
