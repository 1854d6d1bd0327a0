"""The integration methods' names and codes, written once: the names :class:`rc3r.simulate.SimOptions`
takes and the integer codes the compiled integrators branch on (:mod:`rc3r.simulate.engines.compiled`
imports its codes from here, so the two cannot part).

* continuous time (:attr:`~rc3r.simulate.SimOptions.method`): :data:`METHODS`, codes of
  :func:`~rc3r.simulate.engines.compiled.integrate_continuous`;
* sampled time, how the plant is advanced over a period
  (:attr:`~rc3r.simulate.SimOptions.sampled_method`): :data:`PERIOD_METHODS`, codes of
  :func:`~rc3r.simulate.engines.compiled.integrate_sampled` (its ``stiff`` argument).

numba freezes these codes into the compiled integrators' machine code; this module mentions numba so
that :func:`rc3r._numba_cache.package_hash` covers it (an edited code recompiles, never a stale cache:
``tests/test_numba_cache.py``).
"""
from __future__ import annotations

__all__ = ["ODE23S", "ROS4", "RODAS", "METHODS", "RK4_PERIODS", "ROS4_PERIODS", "RODAS_PERIODS", "SDIRK_PERIODS",
           "PERIOD_METHODS", "SAMPLED_METHODS"]

#: ``method`` codes of the continuous-time integrator: Shampine & Reichelt's ode23s, Hairer & Wanner's
#: ROS4 and RODAS.
ODE23S, ROS4, RODAS = 0, 1, 2

#: The fast engine's continuous-time Rosenbrock methods: name -> code (:data:`ODE23S`, :data:`ROS4`,
#: :data:`RODAS`); :attr:`SimOptions.method` also takes ``"auto"`` (:func:`rc3r.simulate.continuous_method`).
METHODS = {"ros4": ROS4, "ode23s": ODE23S, "rodas": RODAS}

#: ``stiff`` codes of the sampled integrator: RK4 sub-steps, adaptive ROS4, RODAS or SDIRK3 periods.
RK4_PERIODS, ROS4_PERIODS, RODAS_PERIODS, SDIRK_PERIODS = 0, 1, 2, 3

#: :attr:`SimOptions.sampled_method` (resolved) -> the ``stiff`` code of the sampled integrator.
PERIOD_METHODS = {"rk4": RK4_PERIODS, "ros4": ROS4_PERIODS, "rodas": RODAS_PERIODS, "sdirk": SDIRK_PERIODS}

#: Ways of advancing the plant over a sampling period (:attr:`SimOptions.sampled_method`): ``"auto"``
#: (:func:`rc3r.simulate.plant_method`) and every name of :data:`PERIOD_METHODS`.
SAMPLED_METHODS = ("auto",) + tuple(PERIOD_METHODS)
