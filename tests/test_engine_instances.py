"""Which compiled instance a run takes (rc3r.simulate._fast.for_run, plan, instantiate): the law(s) and plant
effects a run uses, never every registered one (each branch is code numba compiles into every integrator),
and the arithmetic of a run is the same whichever instance runs it.

The codes expected are written here by hand from the law and effect modules (robust 1, fbl 0, adaptive 3;
friction 1, saturation 2), not read back from the function under test. The suite's own plan (conftest: one
instance of everything) is lifted in each test (``planned()`` with no law)."""
from __future__ import annotations

import ast

import numpy as np
import pytest

import rc3r
from rc3r.errors import ParameterError
from rc3r.plants import Friction, Plant, Saturation
from rc3r.simulate import SimOptions, _fast, simulate

ROBUST, FBL, ADAPTIVE = 1, 0, 3
FRICTION, SATURATION = 1, 2
RR3 = "rc3r.robots.rr3.engine"


@pytest.fixture
def no_plan():
    """Lift the suite's plan (conftest) and forget the instances this process imported, for one test."""
    saved = dict(_fast._INSTANCES)
    _fast._INSTANCES.clear()
    with _fast.planned():
        yield
    _fast._INSTANCES.clear()
    _fast._INSTANCES.update(saved)


def _branches(mod, name: str) -> list[int]:
    """The codes tested by the if/elif chain of function ``name`` in the instance's source file."""
    tree = ast.parse(open(mod.__file__).read())
    fn = next(f for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == name)
    return sorted(c.value for c in ast.walk(fn) if isinstance(c, ast.Compare)
                  for c in c.comparators if isinstance(c, ast.Constant))


def test_a_run_instance_has_a_branch_for_its_law_and_effects_only(no_plan):
    """A robust run on a rigid plant: the instance's law dispatch tests code 1 only (no fbl, adaptive,
    pd, pd-plus branch) and has no effect branch; with friction and saturation the effect dispatch
    tests exactly codes 1 and 2 (its source file read by ast, an independent reading of the text)."""
    eng = _fast.CompiledSimulator(RR3)
    rigid = eng.for_run(ROBUST, np.array([0.0]))
    assert rigid.LAW_CODES == (ROBUST,) and rigid.EFFECT_CODES == ()
    assert _branches(rigid, "law_signals") == [ROBUST] and _branches(rigid, "law_jacobian") == [ROBUST]
    arm = rc3r.load_robot()
    fx = Plant(arm, [Friction(viscous=np.full(3, 0.3)), Saturation(limit=np.full(3, 80.0))]).pack()
    both = eng.for_run(ROBUST, fx)
    assert both.EFFECT_CODES == (FRICTION, SATURATION)
    effects = __import__("sys").modules[both.actuate.py_func.__module__]
    assert _branches(effects, "damping") == [FRICTION, SATURATION]
    assert both is not rigid and both.__file__ != rigid.__file__


def test_one_file_per_choice_written_once_in_the_package_versions_folder(no_plan, tmp_path, monkeypatch):
    """Two choices of laws are two files side by side in one folder (the package version's: pruning one
    choice never removes another); asking again for a choice imports the same module, its file untouched."""
    eng = _fast.CompiledSimulator(RR3)
    a = eng.for_run(ROBUST)
    b = eng.for_run(FBL)
    assert a is not b and a.__file__ != b.__file__
    assert _fast.Path(a.__file__).parent == _fast.Path(b.__file__).parent
    stamp = _fast.Path(a.__file__).stat().st_mtime_ns
    _fast._INSTANCES.clear()  # a new process: instantiate writes (or finds) the file again
    again = _fast.instantiate(RR3, (ROBUST,), ())
    assert again.__file__ == a.__file__ and _fast.Path(a.__file__).stat().st_mtime_ns == stamp


def test_a_plan_gives_its_laws_one_instance(no_plan):
    """Under a plan of fbl, robust and adaptive (a command that runs several laws), each of those laws'
    runs takes the one instance of all three; a law outside the plan takes its own; a plant with an
    effect outside the plan too."""
    eng = _fast.CompiledSimulator(RR3)
    with _fast.planned([FBL, ROBUST, ADAPTIVE], [FRICTION]):
        inst = eng.for_run(FBL)
        assert inst.LAW_CODES == (FBL, ROBUST, ADAPTIVE) and inst.EFFECT_CODES == (FRICTION,)
        assert eng.for_run(ROBUST) is inst and eng.for_run(ADAPTIVE, np.array([1.0, FRICTION, 3.0])) is inst
        pd = eng.for_run(4)
        assert pd.LAW_CODES == (4,)
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


def test_a_run_gives_the_same_numbers_on_its_own_instance_and_on_everything(no_plan):
    """The 3R's robust run (continuous, 0.05 s, friction) on its own instance (one law, one effect) and on the
    instance of every law and effect: the same arithmetic, so the same bits (numba compiles without
    fast-math: no reassociation whatever the surrounding code)."""
    spec = rc3r.build_run(robot="rr3", controller="robust", perturbed=True, duration=0.05)
    plant = Plant(spec.true_rigid, [Friction(viscous=np.full(3, 0.5))])
    opt = SimOptions(duration=0.05, engine="fast")
    own = simulate(plant, spec.law, spec.trajectory, opt)
    assert _fast.simulator(spec.true_rigid).for_run(ROBUST, plant.pack()).LAW_CODES == (ROBUST,)
    _fast._INSTANCES.clear()
    _fast.simulator(spec.true_rigid).instance  # the only one imported now: it covers the run
    assert len(_fast.simulator(spec.true_rigid).for_run(ROBUST, plant.pack()).LAW_CODES) >= 5
    every = simulate(plant, spec.law, spec.trajectory, opt)
    assert own.ok and every.ok
    assert np.array_equal(own.q, every.q) and np.array_equal(own.qd, every.qd) and np.array_equal(own.u, every.u)
