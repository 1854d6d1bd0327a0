"""How a run is stepped: in sampled mode, how the plant is advanced over a period (RK4 sub-steps, their
length from the plant's stiffness, or implicit periods: :attr:`rc3r.simulate.SimOptions.sampled_method`);
in continuous mode, which Rosenbrock method the fast engine uses (:func:`continuous_method`).

:func:`default_substeps` chooses RK4 sub-steps from the rigid body and its effects (:func:`stiffness`:
the fastest rate at which the effects damp a joint); :func:`plant_method` resolves ``"auto"`` to
adaptive SDIRK3 periods where that stiffness would make RK4 costly; :func:`rc3r.simulate.simulate`
applies both (``_resolve_steps``) and redoes a run on finer steps when it moved too fast for the
longer one (``_too_fast``). Measurements behind each constant are in its comment and in
docs/control.md, "Simulation".
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

#: Longest RK4 sub-step [s] of a sampled run whose plant adds no state-dependent force to the rigid
#: body (no effect, or only torque saturation and limit monitors). Measured 2026-12-02 against the
#: reference engine (DOP853 per period, rtol 1e-11), robust law at 1 kHz over 2 s with a payload: one
#: 1 ms step per period is within 6.5e-13 rad (UR5), 1.6e-11 (Panda), 6.5e-12 (Z1) and 4.6e-12
#: (double pendulum) of it (``tests/test_simulate.py::test_one_rk4_step_per_ms_matches_the_reference``).
RIGID_SUBSTEP_S = 1e-3
#: Longest RK4 sub-step [s] when an effect adds a state-dependent force (friction: its smooth Coulomb
#: term is stiff; strong Coulomb friction needs still smaller steps, docs/control.md "Simulation").
EFFECT_SUBSTEP_S = 2.5e-4
#: Largest ``h lambda`` of a default RK4 sub-step ``h`` against the effects' damping rate ``lambda``
#: (:func:`stiffness`): RK4's factor on ``exp(-h lambda)`` at 1.0 is 0.375 against 0.368 (stable to 2.79).
STIFF_STEP = 1.0


#: Largest joint angle [rad] a default RK4 sub-step may cover (``max |qd| * h``) before a sampled run is
#: redone with :data:`EFFECT_SUBSTEP_S` steps: a run whose motion turns violent (the eq. 7 law with a
#: thin layer at 1 kHz reaches |qd| ~ 1450 rad/s and 1e7 N m on the 3R) needs the finer step (1 ms
#: steps made it diverge; 0.25 ms ones agree with the reference engine, max|e| 1.2683 rad).
MAX_STEP_ANGLE = 0.02

#: Default ``(period_rtol, period_atol)`` of the implicit periods per resolved ``sampled_method``
#: (:attr:`SimOptions.period_rtol` ``None``; ``"rk4"`` gets ROS4's, unused). ROS4 and RODAS 1e-4, 1e-6
#: (docs/control.md). SDIRK3 1e-5, 1e-7 (issue 37, docs/performance.md "The design's worst errors at the
#: periods' tolerance"): at 1e-4 its xArm7 design (n 4, 2 s) moved a worst error 4.0e-6 rad from the same
#: design at 1e-8 (ROS4 at 1e-4: 3.8e-7), on a torque-saturated plant that leaves the joint limits (the
#: loop amplifies the periods' errors there); at 1e-5 4.0e-7 (2e-5: 7.9e-7, 3e-5: 1.1e-6).
PERIOD_TOLERANCES = {"sdirk": (1e-5, 1e-7), "ros4": (1e-4, 1e-6), "rodas": (1e-4, 1e-6)}


def _too_fast(res, opt) -> bool:
    """True if a sampled run on default sub-steps did not finish or moved more than
    :data:`MAX_STEP_ANGLE` per sub-step (then :func:`simulate` redoes it with finer steps)."""
    if res.outcome != "finished":
        return res.outcome != "interrupted"
    h = (1.0 / opt.rate) / opt.substeps
    qd = np.abs(np.asarray(res.qd, dtype=float))
    return bool(qd.size and np.nanmax(qd) * h > MAX_STEP_ANGLE)


def plant_method(plant, options, lam: float | None = None) -> str:
    """The resolved :attr:`SimOptions.sampled_method` of a sampled run on ``plant``: the option itself
    unless ``"auto"``; then ``"sdirk"`` if ``options.nsub`` is None and the effects' damping
    (:func:`stiffness`) limits an RK4 sub-step below :data:`EFFECT_SUBSTEP_S` (``STIFF_STEP / lambda``
    shorter than it), else ``"rk4"``; ``"rk4"`` in continuous mode (unused there). Measured with
    ``benchmarks/stiff_plant.py`` (docs/control.md, "Simulation"): on the xArm7's URDF friction ROS4
    periods make 8.8-19x fewer right-hand sides than RK4 at 1 kHz and 500 Hz, on the Z1's 1.6-3.5x, at
    the same distance from the reference engine; SDIRK3 periods with Newton on the friction cost 2.0x
    (Z1) to 3.2x (xArm7) less per period than ROS4's at the same tolerances, RODAS periods 1.3x and 3.1x
    (``benchmarks/period_methods.py``, docs/performance.md, "Stiff friction: the sampled periods").
    ``lam``: :func:`stiffness` of ``plant`` if already known."""
    if options.sampled_method != "auto":
        return options.sampled_method
    if options.rate is None or options.nsub is not None:
        return "rk4"
    lam = stiffness(plant) if lam is None else lam
    return "sdirk" if lam > 0 and STIFF_STEP / lam < EFFECT_SUBSTEP_S else "rk4"


def continuous_method(law, options):
    """``options`` with :attr:`~rc3r.simulate.SimOptions.method` decided for a continuous run of ``law``: the
    option itself unless ``"auto"``; then ``"rodas"`` if the law has a boundary layer (``law.stiff``: the
    robust laws, whose gain ``rho / eps Y Y^T`` makes the loop stiff), else ``"ode23s"``; unchanged in
    sampled mode. Measured by ``python benchmarks/continuous_methods.py`` (docs/performance.md,
    "Continuous-time methods"): on the 3R's robust runs RODAS makes fewer right-hand sides than ode23s
    and lands closer to the yardstick in q, qd and u (its steps end on the output times and it is stiffly
    accurate, so the stored u is the law's own); on FBL, PD and the adaptive law (not stiff) its
    Jacobian per step costs 3.5-4.1x the right-hand sides of ode23s with a kept Jacobian."""
    if options.rate is not None or options.method != "auto":
        return options
    return replace(options, method="rodas" if law.stiff else "ode23s")


def _resolve_steps(plant, options):
    """``options`` with ``nsub`` (:func:`default_substeps`), ``sampled_method`` (:func:`plant_method`) and the
    period tolerances left at ``None`` (:data:`PERIOD_TOLERANCES` of the method) decided for a sampled run on
    ``plant``; unchanged in continuous mode."""
    if options.rate is None:
        return options
    lam = stiffness(plant)  # once for both decisions
    method = plant_method(plant, options, lam)
    if options.nsub is None:
        options = replace(options, nsub=default_substeps(plant, options.rate, lam))
    rtol, atol = PERIOD_TOLERANCES.get(method, PERIOD_TOLERANCES["ros4"])
    return replace(options, sampled_method=method,
                   period_rtol=rtol if options.period_rtol is None else options.period_rtol,
                   period_atol=atol if options.period_atol is None else options.period_atol)


def default_substeps(plant, rate: float, lam: float | None = None) -> int:
    """RK4 sub-steps per period of a sampled run on ``plant`` at ``rate`` [Hz] when ``SimOptions.nsub``
    is not given: steps of at most :data:`RIGID_SUBSTEP_S` for a rigid body (with saturation or limit
    monitors), :data:`EFFECT_SUBSTEP_S` when an effect that declares itself ``stiff`` (friction) acts, and at most
    :data:`STIFF_STEP` / :func:`stiffness` when the effects' damping is stiffer than that.
    :func:`simulate` redoes a run on the longer step with :data:`EFFECT_SUBSTEP_S` steps when it did
    not end ``ok`` or moved more than :data:`MAX_STEP_ANGLE` per step. ``lam``: :func:`stiffness` of
    ``plant`` if already known."""
    from ..plants import as_plant

    plant = as_plant(plant)
    # an effect declares whether it adds a state-dependent force (Effect.stiff: friction does; saturation acts
    # on the held torque and limits only watch)
    h = RIGID_SUBSTEP_S if not any(e.stiff for e in plant.effects) else EFFECT_SUBSTEP_S
    lam = stiffness(plant) if lam is None else lam
    if lam > 0:
        h = min(h, STIFF_STEP / lam)
    return _steps(rate, h)


def stiffness(plant, q=None) -> float:
    r"""The fastest rate [1/s] at which the plant's effects damp a joint velocity:

    .. math:: \lambda_{\max}\bigl(M(q)^{-1} D\bigr), \qquad D = \operatorname{diag}\Bigl(\sum_e d_e\Bigr),

    ``d_e`` the largest slope of effect ``e``'s torque in ``qd`` (:meth:`rc3r.plants.Effect.damping`;
    friction: ``F_v + F_c / v_s``), ``M`` the rigid body's mass matrix at ``q`` (default: zero). 0 if no
    effect damps. Explicit RK4 is stable on ``-lambda`` for ``h lambda < 2.79``; :func:`default_substeps`
    keeps ``h lambda <= STIFF_STEP``. Example: the xArm7's URDF damping, 10 N m s/rad on a wrist of
    1.4e-4 kg m^2, gives about 7e4 1/s (a 14 us time constant).
    """
    from ..plants import as_plant

    plant = as_plant(plant)
    slopes = [d for d in (e.damping() for e in plant.effects) if d is not None]
    if not slopes:
        return 0.0
    D = np.sum(np.atleast_2d(np.asarray(slopes, dtype=float)), axis=0)
    if not np.any(D > 0):
        return 0.0
    from scipy.linalg import eigh

    rigid = plant.rigid
    M = np.asarray(rigid.mass_matrix(np.zeros(rigid.n) if q is None else np.asarray(q, dtype=float)))
    return float(np.max(eigh(np.diag(D), M, eigvals_only=True)))


def _steps(rate: float, h: float) -> int:
    """RK4 sub-steps of at most ``h`` [s] in one period of ``rate`` [Hz] (at least one)."""
    return max(1, int(np.ceil((1.0 / float(rate)) / h - 1e-9)))


def period_budget(options) -> int:
    """Most implicit steps one sampling period may take (``sampled_method`` ``"sdirk"``, ``"ros4"``, ``"rodas"``):
    ``max_steps`` per simulated second, at least 100."""
    return max(100, int(np.ceil(options.max_steps / float(options.rate))))
