"""rc3r: robust tracking control of manipulators from bounds on their dynamic coefficients.

Public API (everything a script or notebook needs)::

    import rc3r
    arm = rc3r.load_robot("rr3")                       # the paper's arm, Table 1
    law = rc3r.make_law("robust", theta0, rho=rho)     # any registered law
    res = rc3r.simulate(plant, law, arm.default_trajectory())

Module map (one concept each; ``docs/architecture.md`` has the same map):

==============================  ===============================================================
``rc3r.robots.base``            the robot contract (:class:`Robot`): n, p, theta, Y(q, qd, v, a)
``rc3r.robots``                 registry of robots (:func:`load_robot`, :data:`ROBOTS`)
``rc3r.robots.rr3``             the paper's 3R arm: params, closed-form kernels, model,
                                regressor, URDF, compiled engine, the paper's study, bench
``rc3r.controllers``            control laws u = Y theta_eff + w, registry (:func:`make_law`)
``rc3r.controllers._kernels``   compiled kernels of the built-in laws (generic over n, p)
``rc3r.trajectory``             desired trajectories (sines, quintic), compiled evaluation
``rc3r.uncertainty``            boxes (``box``), theta_0/rho (``bounds``), lower bound (``sampled``)
``rc3r.simulate``               :func:`simulate`, options, result; engines ``_fast``, ``_python``;
                                ``metrics``; ``status``
``rc3r.study``                  a run as data (:class:`RunSpec`), :func:`build_run`, :func:`execute`
``rc3r.verify``                 checks of a robot against Pinocchio
``rc3r.plotting``               figures (no backend switch)
``rc3r.io``                     atomic file output, TOML reading
``rc3r.errors``                 exception types (one-line errors on the command line)
``rc3r.cli``                    the command line: the only place that parses, prints, exits
==============================  ===============================================================

Conventions (units, frames, gravity, parameter orders): ``docs/conventions.md``.
"""
__version__ = "0.2.0"

from .controllers import LAWS, Law, make_law, register_law
from .errors import ConfigError, DivergenceError, ParameterError, Rc3rError, UrdfError
from .robots import ROBOTS, Robot, load_robot
from .simulate import SimOptions, SimResult, simulate
from .study import RunSpec, build_run, execute

__all__ = [
    "__version__",
    "Robot", "ROBOTS", "load_robot",
    "Law", "LAWS", "make_law", "register_law",
    "SimOptions", "SimResult", "simulate",
    "RunSpec", "build_run", "execute",
    "Rc3rError", "ConfigError", "ParameterError", "UrdfError", "DivergenceError",
]
