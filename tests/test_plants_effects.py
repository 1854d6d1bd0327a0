"""The plant-effect registry: every registered effect is complete in its one module, and the registry
(not a list elsewhere) drives the compiled engine's dispatch, the ``[plant]`` keys and the command line.

For every compiled effect: a LAYOUT of its own fields, a value kernel, a derivative (checked against
central differences of the value kernel), a code with a branch of its own in the generated dispatch;
for every effect: its config keys, accepted by a run configuration, and its CLI options in the parser.
"""
from __future__ import annotations

import numpy as np
import pytest

import rc3r
from rc3r.plants import EFFECTS, PLANT_KEYS, Effect, Friction, Plant, Saturation, registered
from rc3r.simulate.engines import _effects

COMPILED = [c for c in registered() if c.compiled]


def test_the_registry_holds_the_built_in_effects():
    assert {"friction", "saturation", "stribeck", "limits"} <= set(EFFECTS)
    assert [c.name for c in COMPILED][:3] == ["friction", "saturation", "stribeck"]
    codes = [c.code for c in COMPILED]
    assert len(set(codes)) == len(codes) and all(isinstance(c, int) and c > 0 for c in codes)


@pytest.mark.parametrize("cls", COMPILED, ids=lambda c: c.name)
def test_a_compiled_effect_has_layout_kernels_and_role(cls):
    """LAYOUT names fields of the class; value and slope kernels are njit functions of its own module."""
    assert cls.role in ("torque", "actuator")
    assert cls.LAYOUT is not None and set(cls.LAYOUT.names) <= set(cls.__dataclass_fields__)
    for k in (cls.value_kernel, cls.slope_kernel):
        assert hasattr(k, "py_func") and k.py_func.__module__ == cls.__module__


@pytest.mark.parametrize("cls", [c for c in registered() if c.name != "?"], ids=lambda c: c.name)
def test_every_effect_declares_its_config_keys_and_they_are_valid(cls):
    """Every effect has [plant] keys (its name first where it has a table), all of them valid in a run
    configuration (rc3r.study.CONFIG_KEYS reads the registry) and in :data:`PLANT_KEYS`; its CLI options parse."""
    from rc3r.cli import build_parser
    from rc3r.study import CONFIG_KEYS

    assert cls.config_keys and all(k in PLANT_KEYS and k in CONFIG_KEYS["plant"] for k in cls.config_keys)
    assert isinstance(cls.stiff, bool)
    run = build_parser()._subparsers._group_actions[0].choices["run"]
    flags = {s for a in run._actions for s in a.option_strings}
    for opt in cls.cli:
        assert opt.flag in flags and opt.key in cls.config_keys


def _plant(cls, n=3):
    """A plant with one instance of the compiled effect ``cls`` (non-trivial parameters)."""
    arm = rc3r.load_robot()
    make = {"friction": lambda: Friction([0.4, 0.3, 0.2], [2.0, 1.5, 1.0], [0.1, -0.2, 0.0], v_s=0.05),
            "saturation": lambda: Saturation([5.0, 6.0, 7.0])}
    if cls.name in make:
        e = make[cls.name]()
    else:  # an effect of its own: its config keys' first form, as a user would give it
        pytest.skip(f"no sample parameters for {cls.name}") if cls.name != "stribeck" else None
        e = cls([1.0, 0.5, 2.0], [2.0, 0.5, 3.0], [0.1, 0.2, 0.05], [0.5, 0.0, 1.0])
    return Plant(arm, [e]), e


@pytest.mark.parametrize("cls", COMPILED, ids=lambda c: c.name)
def test_pack_writes_the_layout_and_the_kernels_match_the_python_effect(cls):
    """The block at the offset pack records holds each field at its LAYOUT slot; the value kernel equals the
    effect's Python torque (or actuator map), and the slope kernel its central difference."""
    plant, e = _plant(cls)
    fx, n = plant.pack(), 3
    assert fx[0] == 1 and fx[1] == cls.code
    o = int(fx[2])
    for (name, kind), (a, b) in zip(cls.LAYOUT.fields, cls.LAYOUT.slots):
        i = o + a * n + b
        got = fx[i:i + n] if kind == "joint" else fx[i]
        np.testing.assert_array_equal(got, getattr(e, name))
    assert fx.size == o + cls.LAYOUT.size(n)
    value, slope = cls.value_kernel, cls.slope_kernel
    for x in np.linspace(-9.0, 9.0, 37) / (1.0 if cls.role == "actuator" else 30.0):
        xs = np.full(n, x)
        want = e.actuator(xs, None, None) if cls.role == "actuator" else e.joint_torque(None, xs)
        got = [value(fx, o, n, j, x) for j in range(n)]
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-14)
        for j in range(n):
            h = 1e-7 * max(1.0, abs(x))
            d = (value(fx, o, n, j, x + h) - value(fx, o, n, j, x - h)) / (2 * h)
            d = d if cls.role == "actuator" else -d  # a torque's slope is its damping, -d tau / d qd
            if cls.role == "actuator" and np.any(abs(abs(x) - np.asarray(e.limit)) < 2 * h):
                continue  # at the clip's kink
            assert slope(fx, o, n, j, x) == pytest.approx(d, rel=1e-6, abs=1e-6)


def test_the_dispatch_has_one_branch_per_code_and_no_fall_through():
    """The generated dispatch names each registered code once per function and ends in NaN, not another branch."""
    text = _effects.source(EFFECTS)
    for cls in COMPILED:
        assert text.count(f"code == {cls.code}:") == 5  # actuate, has_torque, joint_torque, damping, _passes
    codes = tuple(c.code for c in sorted(COMPILED, key=lambda c: c.code))
    assert text.count("else:") == 5 and f"CODES = {codes!r}" in text
    import ast

    tree = ast.parse(text)  # it is Python: a syntax slip fails here, not in numba
    names = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    assert names >= {"actuate", "has_torque", "joint_torque", "damping", "effect_slopes"}


def test_the_engine_cache_key_counts_the_effect_modules():
    """The dispatch imports each effect's module; those inside the package use numba (so package_hash counts
    them) and instantiate hashes the dispatch text itself."""
    from pathlib import Path

    import rc3r as pkg

    for mod in _effects.kernel_modules(EFFECTS):
        path = Path(pkg.__file__).parent.joinpath(*mod.split(".")[1:]).with_suffix(".py")
        assert b"numba" in path.read_bytes(), mod


def test_an_effect_registered_later_is_reachable_from_a_config_file():
    """A (Python) effect registered after import gets a [plant.<name>] table and the python engine."""
    from dataclasses import dataclass

    from rc3r.plants import register_effect

    @dataclass(frozen=True)
    class Kick(Effect):
        torque: float = 0.0
        name = "kick_test"
        config_keys = ("kick_test",)

        @classmethod
        def from_config(cls, robot, key, value, rng=None):
            return cls(float(value["torque"]))

        def joint_torque(self, q, qd):
            return np.full(3, self.torque)

    register_effect(Kick)
    try:
        spec = rc3r.build_run(controller="fbl", duration=0.05, config={"plant": {"kick_test": {"torque": 0.5}}})
        assert spec.true_plant.effect("kick_test").torque == 0.5 and not spec.true_plant.compiled
    finally:
        del EFFECTS["kick_test"]
    assert "kick_test" not in PLANT_KEYS


def test_old_and_new_spellings_of_saturation():
    """``torque_limit = 50`` (the older key) and ``[plant.saturation] limit = 50`` give the same effect; both at
    once is refused."""
    a = rc3r.build_run(controller="fbl", duration=0.05, config={"plant": {"torque_limit": 50.0}}).true_plant
    b = rc3r.build_run(controller="fbl", duration=0.05, config={"plant": {"saturation": {"limit": 50.0}}}).true_plant
    assert a.effect("saturation").limit.tolist() == b.effect("saturation").limit.tolist() == [50.0] * 3
    with pytest.raises(rc3r.ConfigError, match="both give the saturation effect"):
        rc3r.build_run(controller="fbl", config={"plant": {"torque_limit": 5.0, "saturation": {"limit": 5.0}}})


def test_stiffness_is_declared_by_the_effect():
    """steps.default_substeps reads Effect.stiff: saturation keeps the rigid step, friction shortens it."""
    from rc3r.simulate.steps import EFFECT_SUBSTEP_S, RIGID_SUBSTEP_S, default_substeps

    arm = rc3r.load_robot()
    assert default_substeps(Plant(arm, [Saturation(np.full(3, 50.0))]), 1000.0) == round(1e-3 / RIGID_SUBSTEP_S)
    assert default_substeps(Plant(arm, [Friction(np.full(3, 1e-3))]), 1000.0) == round(1e-3 / EFFECT_SUBSTEP_S)
