r"""Closed-loop simulation: :func:`simulate` returns a :class:`SimResult`, no hidden state.

Two **modes** (the result says which):

* ``continuous`` -- the controller is evaluated inside the integrator, as in the
  paper's simulation (an idealized, infinitely fast controller).
* ``sampled`` -- a digital controller at ``rate`` Hz: u is computed at t_k = k/rate
  and held (zero-order hold) while the plant moves.

Three **engines**:

* ``fast`` -- the compiled simulator built from the robot's kernels (:attr:`Robot.compiled_kernels`; the paper's
  arm has one: closed-form plant on the plant's theta; for continuous mode Rosenbrock
  steps of at most 1 ms, RODAS for the robust laws (steps ending on the output grid) and
  ode23s for the others (stored rows interpolated inside the steps), :attr:`SimOptions.method`;
  RK4 with ``nsub`` sub-steps per period for sampled mode, see
  :mod:`rc3r.robots.rr3.engine`). Needs a law with a compiled kernel.
* ``python`` -- any robot, any law (also a user's law written in Python): the
  robot's own forward dynamics (Pinocchio ABA), SciPy ``Radau`` at ``rtol``/``atol``
  (continuous) or RK4 with ``nsub`` sub-steps (sampled).
* ``reference`` -- the ``python`` engine at tight tolerances: ``Radau`` with
  ``rtol = 1e-11`` (continuous) or ``DOP853`` per period (sampled). Slow; what the
  fast engine is tested against (``tests/test_simulate.py``).

``auto`` (default) picks ``fast`` when the robot has a compiled simulator and the
law a compiled kernel, else ``python``; the result records the engine used.

Stated accuracy (fast engine, defaults ``rtol = 1e-6``, ``atol = 1e-8``), against the
reference engine (Radau, ``rtol = 1e-11``) on the paper's trajectory over 10 s: joint
positions within 3e-6 rad, tracking error within 0.1 % of its maximum, torques within
1 % of max ``|u|``, for every controller (measured 2026-11-22: worst 2.8e-6 rad (PD),
2.7e-4 and 7.5e-3 (eq. 7); checked over 1.5 s by ``tests/test_simulate.py``). Sampled
mode: positions within 1e-8 rad of the reference.

A run that leaves its bounds (NaN, ``|q| > q_max``, ``|qd| > qd_max``,
``|u| > u_max``, M not positive definite) stops there; the result keeps the data up
to then, its ``outcome``/``message`` say when and why, and
:meth:`SimResult.raise_for_status` raises :class:`~rc3r.errors.DivergenceError`.

What a run means is its **verdict** (:attr:`SimResult.verdict`, :mod:`rc3r.simulate.verdict`): ``clean``,
``chattering``, ``saturated``, ``limit-violated``, ``diverged`` (or ``interrupted``), the word ``rc3r run``,
``rc3r paper``, the campaigns and ``metrics.json`` print. :attr:`SimResult.outcome` is only how the
integration ended (``finished``, ``diverged``, ``interrupted``: a chattering run has finished);
``SimResult.status`` (``"ok"`` for any finished run) is its deprecated alias in the old words, which the
files keep in their ``status`` field (:func:`file_status`) for their existing readers.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from ..errors import DivergenceError, ParameterError
from . import status as S
from .engines.base import engine_names as _engine_names
from .methods import METHODS, SAMPLED_METHODS
from .steps import (EFFECT_SUBSTEP_S, MAX_STEP_ANGLE, RIGID_SUBSTEP_S, STIFF_STEP, _resolve_steps, _steps,  # noqa: F401
                    _too_fast, continuous_method, default_substeps, period_budget, plant_method, stiffness)

__all__ = ["SimOptions", "SimResult", "simulate", "ENGINES", "METHODS", "planned_engine", "default_substeps",
           "stiffness", "plant_method", "SAMPLED_METHODS", "continuous_method", "file_status"]

#: Engines accepted by :class:`SimOptions`: ``"auto"`` and every name and alias of the engine registry
#: (:mod:`rc3r.simulate.engines`; a live view: ``"auto", "fast", "compiled", "python", "reference"`` and
#: any engine registered later).
ENGINES = _engine_names()

#: Largest stored time series (rows): each row holds ~(3 n + nz + 2) doubles, so 5e6 rows of the
#: 3R are ~0.6 GB. A longer run must lower ``output_rate``.
MAX_ROWS = 5_000_000

#: :data:`METHODS` (continuous-time Rosenbrock methods: name -> the compiled integrator's code) and
#: :data:`SAMPLED_METHODS` (ways of advancing the plant over a period) are :mod:`.methods`'.

#: Most controller samples of a sampled run (1e9 samples take hours even compiled).
MAX_SAMPLES = 1_000_000_000


def _real(name, x) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{name} must be a number, got {x!r}")
    return float(x)


@dataclass(frozen=True)
class SimOptions:
    """Simulation settings.

    Attributes
    ----------
    duration : float
        Simulated time [s] (paper: 10).
    rate : float or None
        Controller rate [Hz] for sampled mode; ``None`` = continuous time.
    output_rate : float
        Rate of the stored time series [Hz] (continuous mode; sampled mode stores
        every sample up to this rate, decimating above it).
    rtol, atol : float
        Integrator tolerances (continuous mode), mixed relative/absolute per state.
    period_rtol, period_atol : float or None
        Tolerances of the implicit periods (``sampled_method`` ``"sdirk"``, ``"ros4"``, ``"rodas"``); ``None``
        (default): the resolved method's own, :data:`rc3r.simulate.steps.PERIOD_TOLERANCES` (measured there),
        which :func:`simulate` returns: SDIRK3 1e-5, 1e-7 (issue 37's 1e-6 rad on a design's worst errors),
        ROS4 and RODAS 1e-4, 1e-6 (docs/control.md, "Stiff friction: implicit periods").
    nsub : int or None
        RK4 sub-steps per sampling period (sampled mode); default: chosen by :func:`simulate`
        from the plant (:func:`default_substeps`: steps of at most 1 ms for a rigid body, 0.25 ms
        with friction); :attr:`substeps` alone, without a plant, is the conservative
        ``ceil(T / 0.25 ms)``.
    sampled_method : {"auto", "rk4", "sdirk", "ros4", "rodas"}
        How the plant is advanced over a sampling period under the held torque (sampled mode).
        ``"rk4"``: :attr:`nsub` classical RK4 sub-steps. ``"sdirk"``, ``"ros4"``, ``"rodas"``: adaptive
        L-stable steps at ``period_rtol``, ``period_atol``, for plants whose friction damps a light joint
        faster than RK4 can follow (the xArm7's URDF damping: 738 sub-steps per 2 ms period). Fast engine:
        ``"sdirk"`` Alexander's SDIRK3 with Newton's method on the friction (its slope at every iterate,
        M^-1 once per period), ``"ros4"`` and ``"rodas"`` Rosenbrock steps with a forward-difference
        Jacobian per step; python engine: SciPy's Radau for all three, the reference path. ``"auto"``
        (default): ``"sdirk"`` when ``nsub`` is not given and :func:`stiffness` limits the RK4 step below
        :data:`EFFECT_SUBSTEP_S`, else ``"rk4"`` (:func:`plant_method`).
    engine : {"auto", "fast", "python", "reference"}
    jac_reuse : int
        Fast engine, continuous mode: accepted Rosenbrock steps one finite-difference Jacobian is kept
        for (refreshed at once after a step rejected with an older one). 1 = every step (MATLAB's
        ode23s). The default 5 makes the FBL runs about 2x faster and the robust runs 1.0-1.3x, at the
        same accuracy against a tight SciPy Radau solution (``rc3r bench``, docs/performance.md).
    method : {"auto", "ode23s", "ros4", "rodas"}
        Fast engine, continuous mode: the Rosenbrock method (:data:`METHODS`). ``"ode23s"``:
        Shampine & Reichelt's order-2 pair (MATLAB's ode23s); ``"ros4"``: Hairer & Wanner's L-stable
        order-4 method with an order-3 error estimate (give it ``jac_reuse = 1``: it is not a
        W-method); ``"rodas"``: Hairer & Wanner's stiffly accurate order-4 RODAS, a Jacobian every
        step (``jac_reuse`` ignored), steps ending on the output times. ``"auto"`` (default):
        ``"rodas"`` for a law with a boundary layer (``Law.stiff``: the robust laws), ``"ode23s"``
        otherwise (:func:`continuous_method`, which states the measurements). The python and
        reference engines use SciPy and ignore it.
    max_steps : float
        Work budget of continuous mode: integrator steps (accepted and rejected) per
        simulated second. The fast engine checks it inside the compiled loop (per 0.5 s
        chunk), the python engine as ``10 max_steps`` right-hand-side evaluations per
        second. Past it the run stops with status ``diverged`` and a message naming the
        law's eps: a loop that stiff (e.g. eps = 1e-6) would otherwise run for hours. The
        default 1e6 is 40x the most any run of docs/control.md takes (the paper's robust
        law needs 8.4e3 steps per second at eps = 0.5 and 2.6e4 at eps = 0.001).
    q_max, qd_max, u_max : float
        Divergence bounds [rad], [rad/s], [N m].
    """

    duration: float = 10.0
    rate: float | None = None
    output_rate: float = 1000.0
    rtol: float = 1e-6
    atol: float = 1e-8
    period_rtol: float | None = None
    period_atol: float | None = None
    nsub: int | None = None
    sampled_method: str = "auto"
    engine: str = "auto"
    jac_reuse: int = 5
    method: str = "auto"
    max_steps: float = 1e6
    q_max: float = 1e3
    qd_max: float = 1e4
    u_max: float = 1e7

    def __post_init__(self):
        for name in ("duration", "output_rate", "rtol", "atol", "period_rtol", "period_atol", "max_steps", "q_max",
                     "qd_max", "u_max"):
            if getattr(self, name) is None and name.startswith("period_"):
                continue  # the method's own (steps.PERIOD_TOLERANCES)
            x = _real(name, getattr(self, name))
            if not (np.isfinite(x) and x > 0):
                raise ParameterError(f"{name} must be finite and > 0, got {getattr(self, name)}")
        if self.rate is not None:
            r = _real("rate", self.rate)
            if not (np.isfinite(r) and r > 0):
                raise ParameterError(f"rate must be finite and > 0, got {self.rate}")
            if self.duration * r > MAX_SAMPLES:
                raise ParameterError(f"duration {self.duration:g} s at rate {r:g} Hz is {self.duration * r:.3g} "
                                     f"controller samples (at most {MAX_SAMPLES:.0e})")
            if 1.0 / r > self.duration:
                raise ParameterError(f"rate {r:g} Hz is slower than the duration {self.duration:g} s: "
                                     "not one control period would be simulated")
        if self.nsub is not None and (isinstance(self.nsub, bool) or not isinstance(self.nsub, (int, np.integer))
                                      or self.nsub < 1):
            raise ParameterError(f"nsub must be an integer >= 1, got {self.nsub!r}")
        if isinstance(self.jac_reuse, bool) or not isinstance(self.jac_reuse, (int, np.integer)) \
                or not 1 <= self.jac_reuse <= 1000:
            raise ParameterError(f"jac_reuse must be an integer in [1, 1000], got {self.jac_reuse!r}")
        if not isinstance(self.method, str) or (self.method not in METHODS and self.method != "auto"):
            raise ParameterError(f"method must be one of auto, {', '.join(METHODS)}, got {self.method!r}")
        if not isinstance(self.sampled_method, str) or self.sampled_method not in SAMPLED_METHODS:
            raise ParameterError(f"sampled_method must be one of {', '.join(SAMPLED_METHODS)}, "
                                 f"got {self.sampled_method!r}")
        if not isinstance(self.engine, str) or self.engine not in ENGINES:
            raise ParameterError(f"engine must be one of {', '.join(ENGINES)}, got {self.engine!r}")
        rows = self.duration * (self.output_rate if self.rate is None else min(self.rate, self.output_rate))
        if rows > MAX_ROWS:
            raise ParameterError(f"duration {self.duration:g} s would store {rows:.3g} rows (at most {MAX_ROWS:.0e}): "
                                 "lower output_rate or the duration")

    @property
    def substeps(self) -> int:
        """RK4 sub-steps per sampling period."""
        if self.nsub is not None:
            return int(self.nsub)
        return _steps(self.rate, EFFECT_SUBSTEP_S) if self.rate else 1

    @property
    def mode(self) -> str:
        """``"continuous"`` or ``"sampled"``."""
        return "continuous" if self.rate is None else "sampled"


@dataclass(frozen=True, eq=False)
class SimResult:
    """Time series and diagnostics of one run.

    Arrays: ``t`` (N,) [s]; ``q``, ``qd``, ``q_des``, ``u`` (N, n) [rad, rad/s, rad,
    N m]; ``z`` (N, nz) controller state; ``yt_r_norm`` (N,) = ``||Y^T r||``.
    ``e = q - q_des``. :attr:`verdict` is what the run means (clean, chattering, saturated,
    limit-violated, diverged, interrupted); ``outcome`` how the integration ended
    (``"finished"``, ``"diverged"``, ``"interrupted"``); ``status`` is deprecated (module docstring).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    q_des: np.ndarray
    u: np.ndarray
    z: np.ndarray
    yt_r_norm: np.ndarray
    outcome: str
    message: str
    t_end: float
    mode: str
    engine: str
    options: SimOptions
    plant: str
    controller: dict
    trajectory: str
    rhs_evals: int
    steps: int
    rejected_steps: int
    wall_time_s: float
    tv_exact: np.ndarray | None = field(default=None)
    robot: dict = field(default_factory=dict)
    loop: dict | None = field(default=None)

    @property
    def e(self) -> np.ndarray:
        """Tracking error q - q_d (N, n) [rad]."""
        return self.q - self.q_des

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.q.shape[1]

    @property
    def ok(self) -> bool:
        """True if the integration reached the end (``outcome == "finished"``; see :attr:`verdict`)."""
        return self.outcome == "finished"

    @property
    def status(self) -> str:
        """Deprecated since 2026-12-06: :attr:`outcome` in its old words (``"ok"`` for a finished run, also a
        chattering or saturated one). Read :attr:`verdict` for what the run means, :attr:`outcome` for
        how the integration ended."""
        import warnings

        warnings.warn("SimResult.status is deprecated: read SimResult.verdict (clean, chattering, saturated, "
                      "limit-violated, diverged, interrupted) or SimResult.outcome (finished, diverged, "
                      "interrupted)", DeprecationWarning, stacklevel=2)
        return file_status(self)

    @cached_property
    def verdict(self) -> str:
        """What the run means, the word every command prints: ``clean``, ``chattering``, ``saturated``,
        ``limit-violated``, ``diverged`` or ``interrupted`` (:func:`rc3r.simulate.verdict.verdict`, with
        the plant's torque and joint limits recorded in :attr:`robot`; ``metrics.json``'s ``verdict``)."""
        from .metrics import verdict_of

        return verdict_of(self)["verdict"]

    def to_pandas(self):
        """The time series as a ``pandas.DataFrame`` indexed by t (columns: :mod:`.export`)."""
        from .export import to_pandas

        return to_pandas(self)

    def plot(self, title: str | None = None):
        """Errors and torques per joint; returns a ``matplotlib.figure.Figure`` (backend untouched)."""
        from ..plotting import run_figure

        return run_figure(self, title or self.controller.get("name", "run"))

    def save(self, directory, metrics: dict | None = None, title: str | None = None):
        """Write ``timeseries.csv``, ``run.png``, ``metrics.json`` into ``directory`` (what ``rc3r run`` writes)."""
        from .export import save

        return save(self, directory, metrics, title)

    def raise_for_status(self) -> "SimResult":
        """Return self if the run finished; raise :class:`DivergenceError` (with ``.result``) if it
        diverged, ``KeyboardInterrupt`` if it was interrupted."""
        if self.outcome == "interrupted":
            raise KeyboardInterrupt(self.message)
        if not self.ok:
            exc = DivergenceError(self.message)
            exc.result = self
            raise exc
        return self


#: :attr:`SimResult.outcome` -> the ``status`` word of ``metrics.json``, ``runs.csv`` and ``SimResult.status``.
_FILE_STATUS = {"finished": "ok"}


def file_status(res) -> str:
    """The ``status`` field of ``metrics.json`` and ``runs.csv``.

    Parameters
    ----------
    res : SimResult
        A run.

    Returns
    -------
    str
        ``res.outcome`` in the words those files have always used (``"ok"`` for ``"finished"``,
        ``"diverged"``, ``"interrupted"``), kept for their readers (``rc3r montecarlo --resume`` reads
        older rows). What a run means is its verdict (:attr:`SimResult.verdict`).
    """
    return _FILE_STATUS.get(res.outcome, res.outcome)


def _limits(opt: SimOptions) -> np.ndarray:
    return np.array([opt.q_max, opt.qd_max, opt.u_max])


def _initial_state(n: int, law, trajectory, x0) -> np.ndarray:
    z0 = law.initial_state()
    if x0 is None:
        q0, qd0, _ = trajectory.evaluate(0.0)  # start on the trajectory
        x0 = np.concatenate([q0, qd0])
    x0 = np.asarray(x0, dtype=float)
    if x0.shape != (2 * n,) or not np.all(np.isfinite(x0)):
        raise ParameterError(f"initial state must be {2 * n} finite numbers (q, qd), got {x0.tolist()}")
    return np.concatenate([x0, z0])


def _message(status: int, t_end: float, opt: SimOptions, law=None) -> str:
    if status == S.OK:
        return f"finished at t = {t_end:.6g} s"
    if status == S.INTERRUPTED:
        return f"interrupted at t = {t_end:.6g} s (Ctrl-C or SIGTERM); the data up to then is kept"
    if status == S.WORK and opt.rate is not None:
        return (f"stopped at t = {t_end:.6g} s: a {opt.sampled_method.upper()} period of the plant needed more than "
                f"{period_budget(opt)} steps (a stiff plant: raise [simulation] max_steps, or sampled_method = \"rk4\")")
    if status == S.WORK:
        gains = law.describe() if law is not None else {}  # every field: eps of a boundary layer, or eps_i
        eps = gains.get("eps")
        if eps is None and gains.get("eps_i") is not None:
            eps = float(np.min(gains["eps_i"]))
        why = (f"the boundary layer eps = {eps:g} makes the loop too stiff: raise eps, or simulate the "
               "controller sampled (--rate)" if eps is not None else "the loop is too stiff")
        return (f"stopped at t = {t_end:.6g} s: the integrator needed more than {opt.max_steps:g} steps per "
                f"simulated second ({why}; or raise [simulation] max_steps)")
    bound = {S.QBOUND: f" ({opt.q_max:g} rad)", S.QDBOUND: f" ({opt.qd_max:g} rad/s)",
             S.UBOUND: f" ({opt.u_max:g} N m)"}.get(status, "")
    return f"diverged at t = {t_end:.6g} s: {S.STATUS_TEXT[status]}{bound}"


def _engine(plant, law, opt: SimOptions) -> str:
    """The registered engine's canonical name for ``opt.engine`` (:func:`rc3r.simulate.engines.choose`)."""
    from .engines import choose

    return choose(opt.engine, plant, law, opt)


def planned_engine(plant, law, options: SimOptions) -> tuple[str, str | None]:
    """The engine :func:`simulate` will run ``law`` on ``plant`` with, and why ``"auto"`` passed over an
    available compiled engine (its integrator not built yet and the run short:
    :meth:`rc3r.simulate.engines.Engine.cold`), else None.

    Example: ``planned_engine(spec.true_plant, spec.law, spec.options)`` -> ``("fast", None)`` once the
    arm's compiled integrator is in numba's cache.
    """
    from ..plants import as_plant
    from .engines import ENGINES

    plant = as_plant(plant)
    options = continuous_method(law, _resolve_steps(plant, options))
    name = _engine(plant, law, options)
    why = None
    if options.engine == "auto":
        passed = [e for e in {id(e): e for e in ENGINES.values()}.values()
                  if e.auto_priority is not None and e.name != name and e.unavailable(plant, law) is None
                  and e.cold(plant, law, options) is not None]
        why = passed[0].cold(plant, law, options) if passed else None
    return name, why


def _check_structure(plant, model, law, trajectory, loop, opt) -> None:
    """The run's parts fit together: sizes, the model's kinematics = the plant's, loop effects sampled."""
    from ..robots.base import Robot, kinematics_differ

    if trajectory.n != plant.n:
        raise ParameterError(f"trajectory has {trajectory.n} joints, robot '{plant.label}' has {plant.n}")
    if model.n != plant.n:
        raise ParameterError(f"the controller's model has {model.n} joints, the plant '{plant.label}' has {plant.n}")
    if law.p != model.p:
        raise ParameterError(f"law {law.name!r} has {law.p} coefficients, robot '{model.label}' has {model.p}")
    if model is not plant.rigid and isinstance(plant.rigid, Robot):  # MuJoCo's rigid body has no regressor
        why = kinematics_differ(model, plant.rigid)
        if why:
            raise ParameterError(f"the plant '{plant.label}' is not the model's arm: {why}")
    if plant.rigid.advance is not None and any(not e.monitor and type(e).joint_torque is not
                                               type(e).__mro__[-2].joint_torque for e in plant.effects):
        raise ParameterError("joint-torque effects (friction) are not applied inside a rigid body that integrates "
                             "itself (MuJoCo): use the Pinocchio plant engine for friction")
    if loop is not None:
        if loop.n != plant.n:
            raise ParameterError(f"loop effects are sized for {loop.n} joints, the plant has {plant.n}")
        if loop.active and opt.rate is None:
            raise ParameterError("sensor noise, quantization and delay act on a sampled controller: give a rate "
                                 "(--rate HZ)")


def simulate(plant, law, trajectory, options: SimOptions = SimOptions(), x0=None, loop=None,
             model=None) -> SimResult:
    """Simulate control law ``law`` on ``plant`` tracking ``trajectory``.

    Parameters
    ----------
    plant : rc3r.plants.Plant or rc3r.robots.base.Robot
        The true system: a rigid body and its effects (friction, saturation, limits); a bare
        robot is the rigid plant. The law never reads its parameters. Of a run specification, its
        ``true_plant`` (``true_rigid`` is the rigid body alone: no effects); ``rc3r.execute(spec)`` runs it whole.
    law : rc3r.controllers.Law
        Any registered or user-defined law, with its own model theta (p,).
    trajectory : rc3r.trajectory.Trajectory
        With ``trajectory.n == plant.n``.
    options : SimOptions
    x0 : array_like (2 n,), optional
        Initial (q, qd); default: on the trajectory at t = 0 (the paper's
        "matching conditions"), plus the loop's initial error.
    loop : rc3r.plants.LoopEffects, optional
        Sensor noise, quantization, delay (sampled mode only) and initial error.
    model : rc3r.robots.base.Robot, optional
        The robot whose regressor the law evaluates (default the plant's rigid body). Its
        kinematics must be the plant's (checked at three seeded states).

    Returns
    -------
    SimResult
        With ``outcome == "finished"`` or the divergence message (``verdict``: what the run means);
        never raises for a diverging run (call :meth:`SimResult.raise_for_status` for that).
        ``wall_time_s`` never includes numba's compilation: the first fast run of a
        process first runs two output periods, untimed.

    Examples
    --------
    The paper's robust law on the perturbed 3R, 0.5 s of continuous time:

    >>> import rc3r
    >>> spec = rc3r.build_run(controller="robust", perturbed=True, duration=0.5)
    >>> res = rc3r.simulate(spec.true_plant, spec.law, spec.trajectory, spec.options)
    >>> res.verdict, res.outcome, res.engine, res.q.shape
    ('clean', 'finished', 'fast', (501, 3))
    >>> bool(abs(res.e).max() < 1e-3)
    True
    """
    from ..plants import as_plant

    plant = as_plant(plant)
    model = plant.rigid if model is None else model
    auto_step = options.rate is not None and options.nsub is None
    options = continuous_method(law, _resolve_steps(plant, options))
    _check_structure(plant, model, law, trajectory, loop, options)
    if x0 is None and loop is not None:
        x0 = loop.x0(*trajectory.evaluate(0.0)[:2])
    x0 = _initial_state(plant.n, law, trajectory, x0)
    engine = _engine(plant, law, options)
    from .engines import get_engine

    eng = get_engine(engine)
    run = eng.run
    if eng.compiled:
        _warm_up(run, plant, law, trajectory, replace(options, engine=engine), x0)
    S.raise_if_stopped()  # a signal during numba's compilation may have been swallowed there
    t0 = time.perf_counter()
    out = run(plant, law, trajectory, replace(options, engine=engine), x0, loop, model)
    careful = _steps(options.rate, EFFECT_SUBSTEP_S) if auto_step else 0
    rk4 = options.sampled_method == "rk4"
    if auto_step and rk4 and options.nsub < careful and _too_fast(out, options):  # violent motion: redo the step
        options = replace(options, nsub=careful)
        S.raise_if_stopped()
        out = run(plant, law, trajectory, replace(options, engine=engine), x0, loop, model)
    wall = time.perf_counter() - t0
    return replace(out, wall_time_s=wall, loop=None if loop is None else loop.describe())


_WARMED: set = set()


def _warm_up(run, plant, law, trajectory, opt: SimOptions, x0) -> None:
    """Run two output periods once per compiled integrator and process, untimed, so that numba's
    compilation (or cache load) is never booked as a simulation's wall time."""
    from ._fast import simulator

    key = (opt.engine, simulator(plant.rigid), opt.mode)  # one compiled integrator
    if key in _WARMED:
        return
    short = 2.0 / (opt.output_rate if opt.rate is None else min(opt.rate, opt.output_rate))
    if opt.rate is not None:
        short = max(short, 2.0 / opt.rate)
    run(plant, law, trajectory, replace(opt, duration=min(short, opt.duration)), x0)
    _WARMED.add(key)


def _result(plant, law, trajectory, opt, t, X, U, R, yn, status, t_end, nrhs, nsteps, nrej, tv=None):
    n = plant.n
    return SimResult(
        t=t, q=X[:, 0:n].copy(), qd=X[:, n:2 * n].copy(), q_des=R.copy(), u=U.copy(), z=X[:, 2 * n:].copy(),
        yt_r_norm=yn.copy(), outcome={S.OK: "finished", S.INTERRUPTED: "interrupted"}.get(status, "diverged"),
        message=_message(status, t_end, opt, law), t_end=float(t_end), mode=opt.mode, engine=opt.engine,
        options=opt, plant=plant.label, controller=law.describe(),
        trajectory=trajectory.describe(), rhs_evals=int(nrhs), steps=int(nsteps),
        rejected_steps=int(nrej), wall_time_s=0.0, tv_exact=tv, robot=plant.describe(),
    )


def _sample_grid(opt: SimOptions):
    Ts = 1.0 / opt.rate
    nsamples = int(round(opt.duration * opt.rate))
    dec = max(1, int(round(opt.rate / opt.output_rate)))
    return Ts, nsamples, dec
