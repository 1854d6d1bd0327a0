"""rc3r: robust tracking control of manipulators from bounds on their dynamic coefficients.

Public API (everything a script or notebook needs)::

    import rc3r
    spec = rc3r.build_run(controller="robust", perturbed=True)   # the paper's perturbed scenario
    res, metrics = rc3r.execute(spec)   # the whole run: its plant with the effects, loop, controller's model
    res = rc3r.simulate(spec.true_plant, spec.law, spec.trajectory)  # the same plant, by hand
    arm = rc3r.load_robot()                                     # the nominal robot (Table 1)
    law = rc3r.make_law("fbl", arm.theta)                       # any registered law

Module map (one concept each; ``docs/architecture.md`` has the same map with more words):

=====================================  ==============================================================
``rc3r``                               this public API
``rc3r.robots``                        registry of robots: :func:`load_robot`, :data:`ROBOTS`
``rc3r.robots.base``                   the robot contract :class:`Robot`: n, p, theta, Y(q, qd, v, a)
``rc3r.robots.rr3``                    the paper's 3R arm (everything that names it)
``rc3r.robots.rr3.params``             link parameters (paper convention), theta, Table 1
``rc3r.robots.rr3.kernels``            compiled closed-form M, S, g, Y (numba)
``rc3r.robots.rr3._batch``             shape handling of the closed-form functions
``rc3r.robots.rr3.model``              closed-form M, S, g
``rc3r.robots.rr3.regressor``          closed-form Slotine--Li and inverse-dynamics regressors
``rc3r.robots.rr3.urdf``               URDF writer and reader with the DH structure checks
``rc3r.robots.rr3.tangents``           d(Y theta)/d(q, qd, v, a) of the closed form, generated (numba)
``rc3r.robots.rr3.tangents_gen``       writes that module with SymPy from the closed form
``rc3r.robots.rr3.robot``              :class:`RR3`, the contract's implementation
``rc3r.robots.rr3.engine``             the 3R's kernel supply of the compiled engine
``rc3r.robots.rr3.paper``              the paper's box, gains, trajectory, sampled rate (the robot's data)
``rc3r.robots.rr3.c_kernels``          the closed-form Slotine--Li regressor as C99 source (``rc3r export``)
``rc3r.robots.pinocchio``              :class:`PinocchioRobot`: any URDF arm (UR5, Panda) in base parameters
``rc3r.robots.base_parameters``        numerical base parameters of a Pinocchio model
``rc3r.robots.pinocchio_kernel``       compiled Slotine--Li regressor of a serial chain
``rc3r.robots.pinocchio_supply``       a chain's kernel supply of the compiled engine (Y^T r, Y theta in O(n))
``rc3r.robots.actuated``               ActuatedRobot: any robot plus per-joint friction and armature coefficients
``rc3r.robots.actuated_supply``        its compiled kernel supply, a template over the rigid body's supply
``rc3r.robots.actuated_c``             its C99 regressor for rc3r export (the rigid body's plus the joint columns)
``rc3r.urdf_names``                    URDF files by name: example-robot-data's directory, ``erd:`` names, --lock advice
``rc3r.robots.generated``              generated C kernels of any arm (CasADi SX -> C, cached on disk)
``rc3r.robots.generated_chain``        what is generated (``FUNCTIONS``) and from what (a chain's constants)
``rc3r.robots.generated_sym``          their symbolic recursions and the C batch wrapper
``rc3r.controllers``                   control laws u = Y theta_eff + w and their registry
``rc3r.controllers.base``              the law contract: :class:`Law`, its packed ``Layout``, ``LAWS``, ``register_law``
``rc3r.controllers._kernels``          the compiled contractions every law shares: Y^T r, Y theta + w
``rc3r.controllers.pd_gains``          Kp, Kd and the kernels of a law with theta_eff = theta_0 and no state
``rc3r.controllers.fbl``               law ``fbl``: computed torque (class, LAYOUT, kernels, derivatives, C)
``rc3r.controllers.pd``                law ``pd``: PD plus gravity compensation (one module, as ``fbl``)
``rc3r.controllers.sliding``           what the laws on r = e_dot + Lambda e share: class, kernels, C parts
``rc3r.controllers.robust``            law ``robust``: Spong's eq. (6) (one module, as ``fbl``)
``rc3r.controllers.robust_coeff``      law ``robust-coeff``: eq. (7), per-coefficient bounds (one module)
``rc3r.controllers.adaptive``          law ``adaptive``: Slotine--Li's estimate as the law's state (one module)
``rc3r.controllers.pd_plus``           law ``pd-plus``: Paden--Panja's PD+, the worked example of a compiled law
``rc3r.controllers.controller``        :class:`Controller`: ``u = step(t, q, qd)`` for loops rc3r does not run
``rc3r.controllers.sampled``           the sampled loop in Python: hold, delay line, Euler step of z (engine and Controller)
``rc3r.controllers.guarantee``         the robust laws' ultimate bound on ``|e_j|`` (Spong's UUB made explicit)
``rc3r.controllers.ellipsoid``         law ``robust-ellipsoid``: Spong's term for ||theta - theta_0||_P <= 1
``rc3r.trajectory``                    desired trajectories (sines, quintic), compiled evaluation
``rc3r._trig``                         sin and cos from one argument reduction (compiled; the closed form's)
``rc3r.uncertainty``                   parameter uncertainty (re-exports the three below)
``rc3r.uncertainty.box``               boxes on standard parameters, box files, perturbed plants
``rc3r.uncertainty.bounds``            theta_0 and rho: the paper's method, certified exact ranges
``rc3r.uncertainty.payload``           exact bounds for an unknown payload on the last link
``rc3r.uncertainty.sampled``           sampled lower bound on max ||theta - theta_0||
``rc3r.uncertainty.inertia``           M(q; theta) of a coefficient vector, linear in theta (ThetaModel)
``rc3r.uncertainty.ellipsoid``         plants drawn in an identification's ellipsoid (centre, random, boundary)
``rc3r.uncertainty.urdf``              the URDF's own error: link pseudo-inertias scaled per direction (physical set)
``rc3r.identify``                      identification from logs: bounds for the robust laws (docs/identification.md)
``rc3r.identify.log``                  logs (CSV, NPZ): loading and validation
``rc3r.identify.filtering``            resampling, zero-phase (parallel) low-pass, differentiation, cut-off candidates
``rc3r.identify.selection``            cut-off, velocity source, weighting, Coulomb smoothing by blocked cross-validation
``rc3r.identify.regressors``           identification regressor: the arm's Y and per-joint friction columns
``rc3r.identify.estimate``             weighted least squares, per-joint noise, covariance, confidence ellipsoid
``rc3r.identify.consistency``          physical consistency: SDP on the pseudo-inertia matrices (cvxpy)
``rc3r.identify.physical``             the physically consistent estimate: log-Cholesky least squares, log-det prior
``rc3r.identify.excitation``           exciting trajectories: Fourier series, condition number minimised
``rc3r.identify.bounds_file``          ``bounds.toml``: written by identify, read by :func:`load_bounds`
``rc3r.identify.synthetic``            synthetic logs of a known arm at stated noise levels
``rc3r.identify.pipeline``             :func:`identify`: log to theta, friction, covariance, validation, bounds
``rc3r.identify.figures``              held-out torques and residuals of an identification
``rc3r.plants``                        the true system: :class:`Plant` = rigid body + effects, loop effects
``rc3r.plants.base``                   the plant contract, :class:`Effect`, :class:`Layout`, the effect registry
``rc3r.plants.friction``               viscous, smooth Coulomb and offset joint friction: class, layout, kernels, config
``rc3r.plants.saturation``             actuator torque limits (URDF effort or config): class, layout, kernels
``rc3r.plants.stribeck``               Stribeck friction, the worked example of a compiled effect in one file
``rc3r.plants.limits``                 joint position/velocity limits, reported when crossed (a monitor)
``rc3r.plants.loop``                   sensor noise, quantization, delay, initial error of a sampled loop
``rc3r.plants._kernels``               an effect layout's slot arithmetic and the loop's measurement (numba)
``rc3r.plants.rigid``                  the rigid-body contract :class:`RigidBody` (a Robot, or MuJoCo's)
``rc3r.plants.mujoco``                 MuJoCo as the plant's rigid body (optional extra)
``rc3r.simulate``                      :func:`simulate`, :class:`SimOptions`, :class:`SimResult`
``rc3r.simulate._fast``                the compiled engine's driver: one instantiation per kernel supply
``rc3r.simulate.engines``              engines: the contract and registry, the compiled integrators
``rc3r.simulate.engines.base``         the engine contract, the registry (``ENGINES``), the built-in engines
``rc3r.simulate.engines.compiled``     Rosenbrock (ode23s, ROS4, RODAS) and ZOH (RK4, RODAS or ROS4 periods) integrators, any n, p (numba)
``rc3r.simulate.engines._template``    the kernel supply contract, as stubs
``rc3r.simulate.engines._effects``     the plant-effect dispatch, generated from ``EFFECTS`` per instantiation
``rc3r.simulate.engines._linalg``      dense LU of the compiled integrators (kernel-independent)
``rc3r.simulate.engines._jacobian``    the closed loop's analytic Jacobian by the chain rule (kernel-independent)
``rc3r.simulate.engines._dispatch``    the engine's dispatch over the laws, written from ``LAWS`` at instantiation
``rc3r.simulate.engines._tableaux``    the ROS4 and RODAS tables of those integrators (plain constants)
``rc3r.simulate.engines._sdirk``       the SDIRK3 periods' table, Newton matrix and knee error control (kernel-independent)
``rc3r.simulate._python``              the ``python`` and ``reference`` engines (any robot, any law)
``rc3r.simulate.metrics``              scalar metrics of a run
``rc3r.simulate.verdict``              what a run means: clean, chattering, saturated, limit-violated, diverged
``rc3r.simulate.status``               status codes and the compiled bound check
``rc3r.simulate.methods``              the integration methods' names and codes, written once (SimOptions and the template)
``rc3r.simulate.steps``                how a sampled run advances the plant: RK4 sub-steps, implicit periods
``rc3r.simulate.export``               a result as a table, CSV, figure, run directory
``rc3r.runspec``                       a run as data: :class:`RunSpec`, :func:`build_run`, :func:`execute`
``rc3r.study``                         the former name of ``rc3r.runspec`` (a deprecated re-export)
``rc3r.plant_sets``                    the plants of a run's bounds (payload, box, URDF uncertainty, ellipsoid)
``rc3r.export``                        ``rc3r export``: a run's controller as self-contained C99, with a checking harness
``rc3r.export.c``                      the C controller: trajectory, law, state, zero-order hold, delay line
``rc3r.export.literals``               C99 literals of doubles and arrays (shared by the controller and the chain)
``rc3r.export.chain``                  a serial chain's Slotine--Li regressor in C (port of the compiled kernel)
``rc3r.export.harness``                recorded states, rc3r's torques, ``check.c`` and the ``Makefile``
``rc3r.design``                        ``rc3r design``: gains and eps for a controller rate, verified over the bounds
``rc3r.design.rule``                   the sampled-data rule and its fast form (the defaults of sampled runs)
``rc3r.design.verify``                 the fast form verified over the bounds at the rate and rate / margin (campaign runner)
``rc3r.design.worst``                  the worst-plant search: the bounds' plants of largest held-loop gain T lambda_max(M_p^-1 G)
``rc3r.design.report``                 ``design.toml``, ``design.md``, the figure
``rc3r.campaign``                      many runs: Monte Carlo over the box, eps sweep, rate map
``rc3r.campaign.jobs``                 :class:`Job` (one run, picklable) and :func:`run_job` (its row)
``rc3r.campaign.runner``               resumable row-by-row table, local process pool or Dask
``rc3r.campaign.studies``              the campaigns' jobs, summaries, chattering classification
``rc3r.campaign.figures``              the campaigns' figures
``rc3r.experiments``                   above the library: studies of named robots, benchmarks
``rc3r.experiments.paper3r``           the paper's section 4 on its 3R: five scenarios, claims (``rc3r paper``)
``rc3r.experiments.bench3r``           ``rc3r bench``: closed form vs Pinocchio, simulation timings
``rc3r.experiments.bench_startup``     ``rc3r bench``'s fresh-process rows: compile, cold start, memory
``rc3r.experiments.bench_methods``     Rosenbrock vs SciPy Radau/BDF on the same compiled loop
``rc3r.experiments.bench_generic``     ``rc3r bench``'s generic-robot section (UR5, Panda)
``rc3r.experiments.bench_generated``   ``rc3r bench``'s generated-kernel section (UR5 tau vs pin.rnea)
``rc3r.experiments.bench_campaign``    campaign throughput with 1 and 2 workers (``rc3r bench``)
``rc3r.experiments.bench_design``      wall time of a default design (``rc3r bench``)
``rc3r.experiments._report``           where the benchmarks' progress messages go
``rc3r.verify``                        checks of a robot against Pinocchio
``rc3r.plotting``                      figures (never switches the matplotlib backend)
``rc3r.animation``                     the arm tracking its trajectory in 3D (Pinocchio FK), as a GIF
``rc3r.io``                            atomic file output (user's umask), TOML reading, a config's file names
``rc3r.provenance``                    versions, git commit, command line of an output
``rc3r.errors``                        exception types (one-line errors on the command line)
``rc3r.conventions``                   orders every layer shares (Pinocchio's standard parameters, ``STD_KEYS``)
``rc3r._numba_cache``                  numba's disk cache keyed on the package's content (no stale kernels)
``rc3r.cli``                           the command line: the only place that parses, prints, exits
``rc3r.cli.model``                     ``verify-model``, ``make-urdf``
``rc3r.cli.bounds``                    ``bounds``
``rc3r.cli.run``                       ``run``, ``paper``
``rc3r.cli.study``                     ``montecarlo``, ``sweep eps``, ``sweep rate``
``rc3r.cli.bench``                     ``bench``
``rc3r.cli.export``                    ``export``
``rc3r.cli.identify``                  ``identify``, ``excite``
``rc3r.cli.design``                    ``design``
``rc3r.cli._output``                   output directories written as a whole, locked
=====================================  ==============================================================

Conventions (units, frames, gravity, parameter orders): ``docs/conventions.md``.
"""
__version__ = "0.2.0"

from . import _numba_cache

_numba_cache.install()  # before any compiled kernel is defined: caches keyed on the package's content

from .controllers import LAWS, Law, make_law, register_law
from .controllers.controller import Controller
from .plants import LoopEffects, Plant
from .errors import ConfigError, DivergenceError, ParameterError, Rc3rError, UrdfError
from .robots import ROBOTS, Robot, load_robot
from .simulate import SimOptions, SimResult, simulate
from .runspec import RunSpec, build_run, execute

__all__ = [
    "__version__",
    "Robot", "ROBOTS", "load_robot",
    "Law", "LAWS", "make_law", "register_law", "Controller",
    "Plant", "LoopEffects",
    "SimOptions", "SimResult", "simulate",
    "RunSpec", "build_run", "execute",
    "Rc3rError", "ConfigError", "ParameterError", "UrdfError", "DivergenceError",
]
