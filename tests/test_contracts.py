"""Declared contracts instead of probes (issue 34, deliverable 4).

* No ``getattr``/``hasattr`` probes on the capabilities of robots, rigid bodies, plants, effects, laws and run
  specifications anywhere in ``src/rc3r`` (the command line included): each capability is declared with a
  default in its contract (:class:`rc3r.robots.base.Robot`, :class:`rc3r.plants.RigidBody`,
  :class:`rc3r.plants.Effect`, :class:`rc3r.controllers.Law`, :class:`rc3r.runspec.RunSpec`) and read directly.
  Every ``getattr``/``hasattr`` left is listed in :data:`ALLOWED` with why it is no probe of ours; a new one
  fails :func:`test_no_new_getattr_probes` (and an entry whose call is gone fails too, so the list stays true).
* Every capability name the probes read (:data:`CAPABILITIES`) is declared on its contract.
* ``RunSpec``'s former field names are deprecated read-only aliases; ``rc3r.study`` is a deprecated re-export
  of ``rc3r.runspec``.
"""
from __future__ import annotations

import ast
import warnings
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "rc3r"

#: Capabilities that were probed before (issue 34 counted 48 probes outside cli/), by contract.
CAPABILITIES = {
    "rc3r.robots.base.Robot": ("compiled_kernels", "urdf", "locked", "joint_names", "robot_name", "base", "kernel",
                               "linear_in_standard_parameters", "model_terms_are_pinocchio", "theta_order",
                               "mujoco_urdf", "c_regressor_source", "with_model", "regressor_pinocchio", "advance",
                               "default_trajectory_warnings", "model", "label", "describe", "name"),
    "rc3r.plants.rigid.RigidBody": ("name", "p", "theta", "advance", "compiled_kernels", "n", "label",
                                    "forward_dynamics", "mass_matrix", "describe"),
    "rc3r.plants.base.Effect": ("name", "n", "source", "damping", "compiled", "monitor"),
    "rc3r.plants.base.Plant": ("effects", "rigid"),
    "rc3r.controllers.Law": ("stiff", "model_inputs", "K_inertia", "code", "describe"),
    "rc3r.runspec.RunSpec": ("loop", "true_plant", "true_rigid", "controller_model", "plant", "robot_model"),
}

ARGPARSE = "an argparse namespace: sub-commands define different options"

#: ``(module under src/rc3r, attribute or "<dynamic>")``: why this getattr/hasattr is no capability probe.
ALLOWED = {
    ("identify/excitation.py", "velocityLimit"): "a pinocchio.Model field (Pinocchio's own object, older builds lack it)",
    ("identify/filtering.py", "<dynamic>"): "a memoised signal of the log itself, by name",
    ("campaign/runner.py", "_processes"): "concurrent.futures' pool internals (the worker processes to name)",
    ("campaign/runner.py", "asyncio_loop"): "a Dask client's event loop (tornado's attribute)",
    ("campaign/runner.py", "_rc3r"): "our own marker on an asyncio exception handler",
    ("campaign/runner.py", "close"): "a stream that may not be closable (file-like duck typing of the standard library)",
    ("simulate/__init__.py", "<dynamic>"): "SimOptions validating its own fields by name",
    ("simulate/_fast.py", "getuid"): "os.getuid is POSIX-only",
    ("simulate/_fast.py", "<dynamic>"): "a kernel supply is a user module: its functions are checked by name",
    ("simulate/_fast.py", "__file__"): "a kernel supply is a user module (a namespace package has no file)",
    ("design/rule.py", "<dynamic>"): "a gain table's dataclass fields by name",
    ("controllers/base.py", "<dynamic>"): "Law.describe and the packed layout: the law's own dataclass fields by name",
    ("controllers/base.py", "py_func"): "numba dispatcher internals (is a law's kernel compiled?)",
    ("plants/base.py", "<dynamic>"): "Plant.pack: an effect's own LAYOUT fields by name",
    ("plants/base.py", "__dataclass_fields__"): "an effect class's dataclass fields (its LAYOUT is derived from them)",
    ("plants/base.py", "py_func"): "numba dispatcher internals (is an effect's kernel compiled?)",
    ("plants/stribeck.py", "<dynamic>"): "Stribeck validating its own fields by name",
    ("simulate/engines/_dispatch.py", "__file__"): "a registered law's module may be a user module (its source "
                                                   "joins the cache key)",
    ("simulate/engines/_dispatch.py", "<dynamic>"): "a registered law's kernel module by name",
    ("simulate/engines/_effects.py", "py_func"): "numba dispatcher internals (an effect's kernel must be njit)",
    ("simulate/engines/_effects.py", "<dynamic>"): "a registered effect's kernel, looked up in its module by name",
    ("export/c.py", "<dynamic>"): "a law class's methods compared with Law's (is the law a built-in one?)",
    ("study.py", "<dynamic>"): "the deprecated module rc3r.study forwarding a name to rc3r.runspec",
    ("_numba_cache.py", "_cache"): "numba dispatcher internals",
    ("_numba_cache.py", "_cache_file"): "numba dispatcher internals",
    ("_numba_cache.py", "overloads"): "numba dispatcher internals",
    ("_numba_cache.py", "py_func"): "numba dispatcher internals (a plain function has none)",
    ("plants/loop.py", "<dynamic>"): "LoopEffects validating its own fields by name",
    ("plants/friction.py", "<dynamic>"): "Friction validating its own fields by name",
    ("plants/mujoco.py", "mjDSBL_AUTORESET"): "a MuJoCo enum member that exists from 3.2 on",
    ("plants/mujoco.py", "qM"): "MuJoCo 3 and 4 differ in mj_fullM's arguments",
    ("robots/pinocchio.py", "_pin_datas"): "the robot's own lazily built work data",
    ("robots/pinocchio.py", "<dynamic>"): "a pinocchio function by name",
    ("robots/__init__.py", "<dynamic>"): "a registered robot class, imported by its dotted name",
    ("robots/generated.py", "<dynamic>"): "a compiled library's function by name",
    ("robots/actuated.py", "<dynamic>"): "an inner kernel supply is a user module: its optional derivatives by name",
    ("robots/actuated.py", "__file__"): "an inner kernel supply is a user module (its source joins the cache key)",
    ("robots/rr3/robot.py", "_pin_data"): "the robot's own lazily built work data",
    ("cli/__init__.py", "<dynamic>"): "a sub-command's function, imported by name",
    ("cli/model.py", "lock"): ARGPARSE,
    ("cli/bench.py", "quick"): ARGPARSE,
    ("cli/bench.py", "json"): ARGPARSE,
    ("cli/study.py", "bounds"): ARGPARSE,
    ("cli/study.py", "payload"): ARGPARSE,
    ("cli/study.py", "payload_com"): ARGPARSE,
    ("cli/study.py", "K"): ARGPARSE,
    ("cli/bounds.py", "urdf"): ARGPARSE,
    ("cli/bounds.py", "robot"): ARGPARSE,
    ("cli/bounds.py", "lock"): ARGPARSE,
    ("cli/bounds.py", "json"): ARGPARSE,
    ("cli/bounds.py", "payload"): ARGPARSE,
    ("cli/bounds.py", "box"): ARGPARSE,
    ("cli/run.py", "<dynamic>"): ARGPARSE,
    ("cli/run.py", "lock"): ARGPARSE,
    ("cli/run.py", "animate"): ARGPARSE,
    ("cli/identify.py", "tolist"): "a JSON value that may be an array",
}


def probes(src: Path = SRC) -> dict[tuple[str, str], list[int]]:
    """``{(module, attribute or "<dynamic>"): [lines]}`` of every getattr/hasattr call under ``src``."""
    out: dict[tuple[str, str], list[int]] = {}
    for path in sorted(src.rglob("*.py")):
        rel = path.relative_to(src).as_posix()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id in ("getattr", "hasattr") and len(node.args) >= 2):
                arg = node.args[1]
                name = arg.value if isinstance(arg, ast.Constant) and isinstance(arg.value, str) else "<dynamic>"
                out.setdefault((rel, name), []).append(node.lineno)
    return out


def test_no_new_getattr_probes():
    """Every getattr/hasattr of the package is an ALLOWED one: none probes a capability of a robot, rigid body,
    plant, effect, law or run spec (issue 34 counted 48 outside cli/; 0 after it). What remains (2026-12-06: 35
    calls outside cli/, 19 in it) reads the standard library's, numba's, MuJoCo's, Pinocchio's, Dask's or a user
    module's attributes, an object's own fields by name, or the command line's argparse options."""
    found = probes()
    new = {f"{m}:{lines[0]}: {a}" for (m, a), lines in found.items() if (m, a) not in ALLOWED}
    assert not new, ("capability probes: declare the attribute with a default in its contract and read it directly "
                     f"(or, for no capability of ours, add it to ALLOWED with the reason): {sorted(new)}")
    gone = sorted(k for k in ALLOWED if k not in found)
    assert not gone, f"ALLOWED lists calls that are gone (remove them): {gone}"
    names = {a for names in CAPABILITIES.values() for a in names}
    on_objects = {a for m, a in ALLOWED if ALLOWED[m, a] != ARGPARSE}  # --urdf is an option, Robot.urdf a capability
    assert not names & on_objects, f"a capability of a contract is allowed as a probe: {sorted(names & on_objects)}"


@pytest.mark.parametrize("contract", sorted(CAPABILITIES))
def test_capabilities_are_declared(contract):
    """Each capability is an attribute of its contract class (a default or an abstract member), so that callers
    read it without a probe."""
    import importlib

    module, _, name = contract.rpartition(".")
    cls = getattr(importlib.import_module(module), name)
    fields = set(getattr(cls, "__dataclass_fields__", {}))
    missing = [a for a in CAPABILITIES[contract] if not (hasattr(cls, a) or a in fields)]
    if contract.endswith("Plant"):  # instance attributes set by Plant.__init__
        import rc3r

        plant = rc3r.Plant(rc3r.load_robot())
        missing = [a for a in missing if not hasattr(plant, a)]
    assert not missing, f"{contract} does not declare {missing}"


def test_robot_defaults_are_neutral_and_the_robots_override_them():
    """Robot's declared defaults: None for the optional methods and objects, False for the flags; the 3R has its
    own C regressor, MuJoCo URDF and compiled kernels, and no URDF, lock or base parameters."""
    from rc3r.robots.base import Robot
    from rc3r.robots.rr3 import RR3

    for a in ("urdf", "locked", "joint_names", "robot_name", "base", "kernel", "mujoco_urdf", "c_regressor_source",
              "with_model", "regressor_pinocchio", "advance", "compiled_kernels"):
        assert getattr(Robot, a) is None, a
    assert Robot.linear_in_standard_parameters is False and Robot.model_terms_are_pinocchio is False
    arm = RR3.nominal()
    assert callable(arm.c_regressor_source) and callable(arm.mujoco_urdf) and arm.compiled_kernels is not None
    assert arm.urdf is None and arm.locked is None and arm.base is None and arm.advance is None
    assert arm.default_trajectory_warnings() == []


def test_mujoco_rigid_body_implements_the_contract():
    """MujocoRigidBody is a RigidBody with n, label, name and advance, and declares that it has no coefficients,
    regressor or compiled kernels (p, theta, compiled_kernels None), so the simulator reads them directly."""
    pytest.importorskip("mujoco")
    from rc3r.plants import Plant, RigidBody
    from rc3r.plants.mujoco import MujocoRigidBody
    from rc3r.robots.base import Robot
    from rc3r.robots.rr3 import RR3

    rigid = MujocoRigidBody.from_urdf(RR3.nominal().mujoco_urdf())
    assert isinstance(rigid, RigidBody) and not isinstance(rigid, Robot)
    assert rigid.n == 3 and rigid.name == "mujoco" and rigid.advance is not None
    assert rigid.p is None and rigid.theta is None and rigid.compiled_kernels is None
    plant = Plant(rigid)
    assert plant.p is None and plant.theta is None and plant.n == 3
    assert isinstance(RR3.nominal(), RigidBody) and RR3.nominal().advance is None


def test_runspec_fields_and_deprecated_aliases():
    """RunSpec names its robots for what they are; ``plant`` and ``robot_model`` are read-only aliases of
    ``true_rigid`` and ``controller_model`` that warn, the plant one (a FutureWarning, shown by default) saying
    that it is the rigid body without the effects and the loop."""
    import dataclasses

    import rc3r

    spec = rc3r.build_run(controller="fbl", perturbed=True, rate=1000.0, duration=0.01, friction="1:0.5",
                          noise="1e-6:1e-5")
    assert isinstance(spec.true_plant, rc3r.Plant) and spec.true_plant.rigid is spec.true_rigid
    assert spec.true_plant.effects and spec.loop is not None
    assert isinstance(spec.controller_model, rc3r.Robot) and spec.controller_model.label == "nominal"
    with pytest.warns(FutureWarning, match="true_rigid.*WITHOUT the plant's effects and loop"):  # shown by default
        assert spec.plant is spec.true_rigid
    with pytest.warns(DeprecationWarning, match="controller_model"):
        assert spec.robot_model is spec.controller_model
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.plant = None
    assert {f.name for f in dataclasses.fields(spec)} >= {"true_rigid", "true_plant", "controller_model", "loop"}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the library itself reads the new names only
        rc3r.Controller.from_run(spec)
        rc3r.execute(dataclasses.replace(spec, options=dataclasses.replace(spec.options, engine="python")))


def test_study_is_a_deprecated_re_export_of_runspec():
    """``import rc3r.study`` warns and gives rc3r.runspec's objects, its private helpers too."""
    import importlib
    import sys

    import rc3r.runspec as runspec

    sys.modules.pop("rc3r.study", None)
    with pytest.warns(DeprecationWarning, match="rc3r.runspec"):
        study = importlib.import_module("rc3r.study")
    assert study.build_run is runspec.build_run and study.RunSpec is runspec.RunSpec
    assert study._nominal is runspec._nominal and study.CONFIG_KEYS is runspec.CONFIG_KEYS
