"""Which compiled instance a run takes (rc3r.simulate._fast.for_run, plan, instantiate, loaded): compile once
per process where one will do. Without a plan the first run on a plant's effects takes its law, FBL and robust,
a run of a law it lacks every registered law (at most two instances per plant, never one per law); a plan (``rc3r run``: its own law) gives the
planned laws' instance; an imported instance that covers a run serves it. The arithmetic of a run is the
same whichever instance runs it.

The codes expected are written here by hand from the law and effect modules (fbl 0, robust 1, robust-coeff 2,
adaptive 3, pd 4, pd-plus 5; friction 1, saturation 2), not read back from the function under test. The
suite's own plan (conftest: one instance of everything) is lifted in each test (``planned()`` with no law)."""
from __future__ import annotations

import ast

import numpy as np
import pytest

import rc3r
from rc3r.errors import ParameterError
from rc3r.plants import Friction, Plant, Saturation
from rc3r.simulate import SimOptions, _fast, simulate

ROBUST, FBL, ADAPTIVE = 1, 0, 3
EVERY_LAW = (0, 1, 2, 3, 4, 5)
FRICTION, SATURATION = 1, 2
RR3 = "rc3r.robots.rr3.engine"


@pytest.fixture
def no_plan_warm():
    """Lift the suite's plan (conftest) and forget the instances this process imported, for one test."""
    saved = dict(_fast._INSTANCES)
    _fast._INSTANCES.clear()
    with _fast.planned():
        yield
    _fast._INSTANCES.clear()
    _fast._INSTANCES.update(saved)


@pytest.fixture
def no_plan(no_plan_warm, monkeypatch, tmp_path):
    """:func:`no_plan_warm` and an empty folder of instances (``$NUMBA_CACHE_DIR/rc3r_engines`` read by
    ``_fast._roots``): no instance is on disk, whatever earlier runs compiled."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))


def _branches(mod, name: str) -> list[int]:
    """The codes tested by the if/elif chain of function ``name`` in the instance's source file."""
    tree = ast.parse(open(mod.__file__).read())
    fn = next(f for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == name)
    return sorted(c.value for c in ast.walk(fn) if isinstance(c, ast.Compare)
                  for c in c.comparators if isinstance(c, ast.Constant))


def test_a_planned_run_instance_has_a_branch_for_its_law_and_effects_only(no_plan):
    """A robust run on a rigid plant under the plan of its own law (what ``rc3r run`` makes): the instance's
    law dispatch tests code 1 only (no fbl, adaptive, pd, pd-plus branch) and has no effect branch; with
    friction and saturation the effect dispatch tests exactly codes 1 and 2 (its source file read by ast,
    an independent reading of the text)."""
    eng = _fast.CompiledSimulator(RR3)
    with _fast.planned([ROBUST], []):
        rigid = eng.for_run(ROBUST, np.array([0.0]))
    assert rigid.LAW_CODES == (ROBUST,) and rigid.EFFECT_CODES == ()
    assert _branches(rigid, "law_signals") == [ROBUST] and _branches(rigid, "law_jacobian") == [ROBUST]
    arm = rc3r.load_robot()
    fx = Plant(arm, [Friction(viscous=np.full(3, 0.3)), Saturation(limit=np.full(3, 80.0))]).pack()
    with _fast.planned([ROBUST], [FRICTION, SATURATION]):
        both = eng.for_run(ROBUST, fx)
    assert both.EFFECT_CODES == (FRICTION, SATURATION)
    effects = __import__("sys").modules[both.actuate.py_func.__module__]
    assert _branches(effects, "damping") == [FRICTION, SATURATION]
    assert both is not rigid and both.__file__ != rigid.__file__


def test_without_a_plan_a_process_compiles_at_most_two_instances_per_plant(no_plan):
    """With no plan, an fbl run then a robust run on a rigid plant take one instance (``loaded`` counts one):
    the run's law and the paper's pair, FBL and robust (its dispatch's tested codes, read by ast: 0 and 1
    only). An adaptive run, which it lacks, takes a second instance of every registered law and no effect,
    which a pd run then reuses (two instances, never one per law). On a plant with friction the same: a
    robust-coeff run takes it, FBL and robust on friction, an adaptive run then every law on friction."""
    eng = _fast.CompiledSimulator(RR3)
    first = eng.for_run(FBL, np.array([0.0]))
    assert eng.for_run(ROBUST) is first and _fast.loaded(RR3) == (first,)
    assert first.LAW_CODES == (FBL, ROBUST) and first.EFFECT_CODES == ()
    assert _branches(first, "law_signals") == [FBL, ROBUST]
    every = eng.for_run(ADAPTIVE)
    assert every.LAW_CODES == EVERY_LAW and every.EFFECT_CODES == ()
    assert _branches(every, "law_signals") == list(EVERY_LAW)
    assert eng.for_run(4) is every and _fast.loaded(RR3) == (first, every)
    fx = Plant(rc3r.load_robot(), [Friction(viscous=np.full(3, 0.3))]).pack()
    rough = eng.for_run(2, fx)
    assert rough.EFFECT_CODES == (FRICTION,) and rough.LAW_CODES == (FBL, ROBUST, 2)
    rough_every = eng.for_run(ADAPTIVE, fx)
    assert rough_every.EFFECT_CODES == (FRICTION,) and rough_every.LAW_CODES == EVERY_LAW
    assert eng.for_run(5, fx) is rough_every and len(_fast.loaded(RR3)) == 4


def test_a_loaded_superset_is_preferred_to_compiling_a_subset(no_plan):
    """Under a plan of the robust law alone, a robust run still takes the instance of robust and fbl already
    imported (a covering instance costs nothing to load again; compiling the subset would be a second
    compile in the process)."""
    eng = _fast.CompiledSimulator(RR3)
    pair = eng.for_run(ROBUST)  # without a plan: robust and fbl
    with _fast.planned([ROBUST], []):
        assert eng.for_run(ROBUST) is pair
    assert _fast.loaded(RR3) == (pair,) and pair.LAW_CODES == (FBL, ROBUST)


def test_a_choice_compiled_on_disk_is_loaded_instead_of_compiling_the_plan(no_plan, monkeypatch):
    """Step 2 of the rule: under the plan of the robust law alone (``rc3r run``), a continuous robust run
    takes the instance of every law on its effects (none) if an earlier process left it on disk with its
    continuous integrator in numba's cache (loading compiles nothing), not a new robust-only compile; if that
    integrator is not cached, the plan's own instance. numba's answer is replaced by a stub that says
    "cached" for the default instance's module only (so no compile is needed here)."""
    from rc3r import _numba_cache

    default = _fast.instantiate(RR3, None, ())  # an earlier process wrote it ...
    name = default.__name__
    _fast._INSTANCES.clear()  # ... and this is a new one
    cached = {"continuous": True}
    monkeypatch.setattr(_numba_cache, "ready", lambda f: f.py_func.__module__ == name
                        and cached.get(f.__name__.removeprefix("integrate_"), False))
    eng = _fast.CompiledSimulator(RR3)
    with _fast.planned([ROBUST], []):
        got = eng.for_run(ROBUST, None, "continuous")
        assert got.__name__ == name and got.LAW_CODES == EVERY_LAW and _fast.loaded(RR3) == (got,)
        _fast._INSTANCES.clear()
        own = eng.for_run(ROBUST, None, "sampled")  # its sampled integrator is not cached: compile the plan
        assert own.LAW_CODES == (ROBUST,) and _fast.loaded(RR3) == (own,)


def test_one_file_per_choice_written_once_in_the_package_versions_folder(no_plan, tmp_path, monkeypatch):
    """Two choices of laws are two files side by side in one folder (the package version's: pruning one
    choice never removes another); asking again for a choice imports the same module, its file untouched."""
    a = _fast.instantiate(RR3, (ROBUST,), ())
    b = _fast.instantiate(RR3, (FBL,), ())
    assert a is not b and a.__file__ != b.__file__
    assert _fast.Path(a.__file__).parent == _fast.Path(b.__file__).parent
    stamp = _fast.Path(a.__file__).stat().st_mtime_ns
    _fast._INSTANCES.clear()  # a new process: instantiate writes (or finds) the file again
    again = _fast.instantiate(RR3, (ROBUST,), ())
    assert again.__file__ == a.__file__ and _fast.Path(a.__file__).stat().st_mtime_ns == stamp


def test_a_plan_gives_its_laws_one_instance(no_plan):
    """Under a plan of fbl, robust and adaptive (a command that runs several laws), each of those laws'
    runs takes the one instance of all three; a law outside the plan takes the small default (it, FBL and
    robust on the run's effects, here none)."""
    eng = _fast.CompiledSimulator(RR3)
    with _fast.planned([FBL, ROBUST, ADAPTIVE], [FRICTION]):
        inst = eng.for_run(FBL)
        assert inst.LAW_CODES == (FBL, ROBUST, ADAPTIVE) and inst.EFFECT_CODES == (FRICTION,)
        assert eng.for_run(ROBUST) is inst and eng.for_run(ADAPTIVE, np.array([1.0, FRICTION, 3.0])) is inst
        pd = eng.for_run(4)
        assert pd.LAW_CODES == (FBL, ROBUST, 4) and pd.EFFECT_CODES == ()
    assert _fast._PLAN == []  # lifted after the block


def test_an_imported_instance_that_covers_a_run_is_reused(no_plan):
    """An instance already imported in this process with a branch for the run's law and effects serves it
    (no second compile): after the instance of every law, a robust run takes it."""
    eng = _fast.CompiledSimulator(RR3)
    every = eng.instance
    assert set(every.LAW_CODES) >= {FBL, ROBUST, ADAPTIVE, 4, 5}
    assert eng.for_run(ROBUST) is every


def test_an_unregistered_code_is_refused(no_plan):
    """A law or effect code no registered class has: one ParameterError naming it."""
    with pytest.raises(ParameterError, match=r"no compiled law has code\(s\) \[99\]"):
        _fast.instantiate(RR3, (99,), ())
    with pytest.raises(ParameterError, match=r"no compiled effect has code\(s\) \[42\]"):
        _fast.instantiate(RR3, (ROBUST,), (42,))


def test_a_run_gives_the_same_numbers_on_its_own_instance_and_on_everything(no_plan_warm):
    """The 3R's robust run (continuous, 0.05 s, friction) on its own instance (one law, one effect) and on the
    instance of every law and effect: the same arithmetic, so the same bits (numba compiles without
    fast-math: no reassociation whatever the surrounding code)."""
    spec = rc3r.build_run(robot="rr3", controller="robust", perturbed=True, duration=0.05)
    plant = Plant(spec.true_rigid, [Friction(viscous=np.full(3, 0.5))])
    opt = SimOptions(duration=0.05, engine="fast")
    _fast.instantiate(RR3, (ROBUST,), (FRICTION,))  # the only one imported: it covers the run
    own = simulate(plant, spec.law, spec.trajectory, opt)
    assert _fast.simulator(spec.true_rigid).for_run(ROBUST, plant.pack()).LAW_CODES == (ROBUST,)
    _fast._INSTANCES.clear()
    _fast.simulator(spec.true_rigid).instance  # the only one imported now: it covers the run
    assert len(_fast.simulator(spec.true_rigid).for_run(ROBUST, plant.pack()).LAW_CODES) >= 5
    every = simulate(plant, spec.law, spec.trajectory, opt)
    assert own.ok and every.ok
    assert np.array_equal(own.q, every.q) and np.array_equal(own.qd, every.qd) and np.array_equal(own.u, every.u)


def _plan_seen_by_rc3r_run(monkeypatch, tmp_path, *argv) -> tuple:
    """The plan and the imported instances of the 3R's supply when ``rc3r run`` reaches its simulation
    (its ``execute`` replaced by a probe that records them and stops the command with an error)."""
    import rc3r.cli.run as cli_run
    from rc3r.cli import main
    from rc3r.errors import ConfigError

    seen = []

    def probe(spec):
        seen.append((list(_fast._PLAN), _fast.loaded(RR3)))
        raise ConfigError("probe: stop before simulating")

    monkeypatch.setattr(cli_run, "execute", probe)
    assert main(["run", "--robot", "rr3", "--perturbed", "--engine", "fast", "--duration", "0.01",
                 "--out", str(tmp_path / "out"), *argv]) != 0
    assert len(seen) == 1
    return seen[0]


def test_rc3r_run_plans_its_own_law_only(no_plan, monkeypatch, tmp_path):
    """``rc3r run --controller fbl --friction ...`` in a process with no plan: its run is planned on the fbl
    law (code 0) and the friction effect (code 1) alone, the one instance imported has exactly those
    branches (the smallest compile: the first-run time of issue 34), and the plan is lifted afterwards."""
    plan, inst = _plan_seen_by_rc3r_run(monkeypatch, tmp_path, "--controller", "fbl", "--friction", "0.2:0.1")
    assert plan == [((FBL,), (FRICTION,))]
    assert len(inst) == 1 and inst[0].LAW_CODES == (FBL,) and inst[0].EFFECT_CODES == (FRICTION,)
    assert _fast._PLAN == []


def test_rc3r_run_keeps_a_plan_made_before_it(no_plan, monkeypatch, tmp_path):
    """A process that planned already (a script or a test suite running several commands) keeps its plan
    through ``rc3r run``: the robust run takes the planned instance of fbl and robust."""
    with _fast.planned([FBL, ROBUST], []):
        plan, inst = _plan_seen_by_rc3r_run(monkeypatch, tmp_path, "--controller", "robust")
        assert plan == [((FBL, ROBUST), ())] and [m.LAW_CODES for m in inst] == [(FBL, ROBUST)]
