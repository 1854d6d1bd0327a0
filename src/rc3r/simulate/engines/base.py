r"""The engine contract and the engine registry: what :func:`rc3r.simulate.simulate` runs a loop with.

An **engine** integrates one closed loop (plant, law, trajectory, loop effects) and returns a
:class:`~rc3r.simulate.SimResult`. :data:`ENGINES` maps names to engines; the
option ``SimOptions.engine`` (``--engine``) picks one by name or alias, ``"auto"`` the available
engine of lowest :attr:`Engine.auto_priority`. The built-in ones:

========== ========= ===================================================================
name       aliases   what
========== ========= ===================================================================
``fast``   compiled  the compiled engine (:mod:`.compiled`, driven by
                     :mod:`rc3r.simulate._fast`) on the robot's kernel supply
``python``           :mod:`rc3r.simulate._python`: any robot, law and effect
``reference``        the python engine at tight tolerances
========== ========= ===================================================================

**To add an engine** (in the style of SciPy's ``OdeSolver``): subclass :class:`Engine`, set

* :attr:`~Engine.name` (and :attr:`~Engine.aliases`), the strings ``SimOptions.engine`` accepts;
* :attr:`~Engine.auto_priority` -- None if ``"auto"`` must never pick it, else its rank
  (``fast`` is 0, ``python`` 10);
* :attr:`~Engine.compiled` -- True if its first call in a process compiles or loads machine
  code: :func:`~rc3r.simulate.simulate` then runs two output periods untimed first, so that
  ``wall_time_s`` is the simulation's only;

implement

* :meth:`~Engine.unavailable` ``(plant, law) -> str | None`` -- why this engine cannot run
  that plant and law (one clause, quoted in the error), or None;
* :meth:`~Engine.run` ``(plant, law, trajectory, options, x0, loop, model) -> SimResult`` --
  ``plant`` a :class:`~rc3r.plants.Plant`, ``x0`` the full initial state ``(q, qd, z)``,
  ``options.engine`` already this engine's name; every stop (divergence, budget, interruption)
  is a status of the result, never an exception (``rc3r.simulate._result`` builds one);

and register an instance: ``register_engine(MyEngine())``. The status codes are
:mod:`rc3r.simulate.status`; ``tests/test_engines.py`` shows the comparisons a new engine
should pass (against the ``python`` engine sampled, against ``reference`` continuous).
"""
from __future__ import annotations

from collections.abc import Sequence

from ...errors import ParameterError

__all__ = ["Engine", "ENGINES", "register_engine", "get_engine", "choose", "engine_names"]


class Engine:
    """Base of every engine (module docstring: what to implement)."""

    name = "?"
    aliases: tuple = ()
    auto_priority: int | None = None
    compiled = False

    def unavailable(self, plant, law) -> str | None:
        """Why this engine cannot simulate ``law`` on ``plant``, or None if it can."""
        return None

    def cold(self, plant, law, options) -> str | None:
        """Why ``"auto"`` should pass this engine over for a run of ``options`` although it is available
        (its first use would cost more than the run: compilation), or None. Named engines ignore it."""
        return None

    def run(self, plant, law, trajectory, options, x0, loop=None, model=None):
        """Simulate; returns a :class:`~rc3r.simulate.SimResult`."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"<Engine {self.name!r}>"


#: name -> engine (aliases included); :func:`register_engine` adds to it.
ENGINES: dict[str, Engine] = {}


def register_engine(engine: Engine) -> Engine:
    """Make ``engine`` (an :class:`Engine` instance) available by its name and aliases."""
    if not isinstance(engine, Engine) or engine.name in ("?", "", "auto"):
        raise TypeError("register_engine needs an Engine instance with a name other than 'auto'")
    for key in (engine.name, *engine.aliases):
        ENGINES[key] = engine
    return engine


def get_engine(name: str) -> Engine:
    """The engine registered as ``name`` (a name or an alias)."""
    try:
        return ENGINES[name]
    except KeyError:
        raise ParameterError(f"unknown engine {name!r} (known: {', '.join(engine_names())})") from None


class _Names(Sequence):
    """``("auto", every registered name and alias)``, read from the registry at each use."""

    def __getitem__(self, i):
        return ("auto", *ENGINES)[i]

    def __len__(self) -> int:
        return 1 + len(ENGINES)

    def __repr__(self) -> str:
        return repr(tuple(self))


def engine_names() -> Sequence:
    """The strings ``SimOptions.engine`` accepts (a live view of the registry)."""
    return _Names()


def choose(name: str, plant, law, options=None) -> str:
    """The canonical name of the engine ``name`` (``"auto"``: the available one of lowest
    :attr:`Engine.auto_priority` that is not :meth:`~Engine.cold` for ``options``) for ``law`` on
    ``plant``; ParameterError if it cannot run them."""
    if name == "auto":
        ranked = sorted({id(e): e for e in ENGINES.values() if e.auto_priority is not None}.values(),
                        key=lambda e: e.auto_priority)
        for eng in ranked:
            if eng.unavailable(plant, law) is None and (options is None or eng.cold(plant, law, options) is None):
                return eng.name
        raise ParameterError("no engine can simulate this plant and law")
    eng = get_engine(name)
    why = eng.unavailable(plant, law)
    if why is not None:
        raise ParameterError(f"engine '{name}' is not available: {why} (use engine 'python')")
    return eng.name


#: Sampled runs of at most this many RK4 sub-steps (20 s at 1 kHz on one step per period) run on the
#: python engine while the compiled integrator is cold (:meth:`CompiledEngine.cold`). ``rc3r bench``'s
#: cold-start row, 2026-12-02: a 1 s UR5 run (1000 sub-steps) took 3.93 s end to end, imports and
#: figure included, so 20000 stay well below the 1-2 minutes of CPU numba takes to compile a 6-joint
#: arm's integrator.
COLD_MAX_SUBSTEPS = 20000


class CompiledEngine(Engine):
    """``fast``: the compiled integrators of :mod:`.compiled` on the rigid body's kernel supply
    (:attr:`~rc3r.robots.base.Robot.compiled_kernels`), with the plant's compiled effects."""

    name = "fast"
    aliases = ("compiled",)
    auto_priority = 0
    compiled = True

    def unavailable(self, plant, law):
        rigid = plant.rigid
        if rigid.compiled_kernels is None:  # declared by every rigid body (rc3r.plants.RigidBody)
            return f"robot {rigid.name!r} has no compiled simulator"
        if law.code is None:
            return f"law {law.name!r} has no compiled kernel"
        if not plant.compiled:
            return ("the plant has an effect the compiled engine does not apply: "
                    + ", ".join(e.name for e in plant.effects if not (e.compiled or e.monitor)))
        return None

    def cold(self, plant, law, options):
        """A sampled run of at most :data:`COLD_MAX_SUBSTEPS` RK4 sub-steps whose integrator is neither
        compiled in this process nor in numba's disk cache: the python engine finishes it sooner than
        numba compiles (a 6-joint arm: 1-2 minutes of CPU), unless ``RC3R_COLD_START=compile``
        (:func:`rc3r._numba_cache.cold_start_policy`). Continuous runs always compile (their stiff
        laws take the python engine's SciPy Radau longer than the compilation)."""
        from ..._numba_cache import cold_start_policy
        from .._fast import simulator

        if options.rate is None or cold_start_policy() == "compile":
            return None
        steps = round(options.duration * options.rate) * options.substeps
        sim = simulator(plant.rigid)
        if steps > COLD_MAX_SUBSTEPS or sim is None or sim.is_cached("sampled", law.code, plant.pack()):
            return None
        return (f"its compiled integrator is not built yet and {steps} RK4 sub-steps take the python engine "
                "less time than compiling it")

    def run(self, plant, law, trajectory, options, x0, loop=None, model=None):
        from .._fast import run

        return run(plant, law, trajectory, options, x0, loop, model)


class PythonEngine(Engine):
    """``python``: :mod:`rc3r.simulate._python` (SciPy Radau, or RK4 per period)."""

    name = "python"
    auto_priority = 10

    def run(self, plant, law, trajectory, options, x0, loop=None, model=None):
        from .._python import run

        return run(plant, law, trajectory, options, x0, loop, model)


class ReferenceEngine(PythonEngine):
    """``reference``: the python engine at ``rtol = 1e-11`` (Radau; DOP853 per period)."""

    name = "reference"
    auto_priority = None


for _engine in (CompiledEngine(), PythonEngine(), ReferenceEngine()):
    register_engine(_engine)
del _engine
