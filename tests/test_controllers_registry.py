"""The law contract (rc3r.controllers.base): every compiled law is one module with its LAYOUT, kernels,
derivatives and C; a law missing one is refused; the engine's dispatch is written from the registry with
one branch per code and none that falls through; docs/architecture.md's worked example is registered."""
from __future__ import annotations

import ast
import re
import sys
import types
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import pytest

from rc3r.controllers import LAWS, Law
from rc3r.controllers.base import DERIVATIVE_KERNELS, VALUE_KERNELS, Layout, packed, register_law
from rc3r.controllers.sliding import PREFIX, Sliding
from rc3r.simulate.engines import _dispatch

REPO = Path(__file__).resolve().parents[1]
COMPILED = [cls for cls in LAWS.values() if cls.code is not None]


@pytest.mark.parametrize("cls", COMPILED, ids=[c.name for c in COMPILED])
def test_every_compiled_law_holds_layout_kernels_derivatives_and_c(cls):
    mod = sys.modules[cls.__module__]
    assert cls.kernels is mod and mod.LAYOUT == Layout.of(cls) == cls.layout()
    assert isinstance(mod.USES_XI, bool)
    for name in VALUE_KERNELS + DERIVATIVE_KERNELS:
        assert callable(getattr(getattr(mod, name), "py_func", None)), f"{cls.name}: {name} is no numba kernel"
    law = cls(np.linspace(1.0, 2.0, 15))
    part = mod.c_source(law, 3)
    assert {"constants", "signals", "output"} <= set(part) and part["signals"].strip() and part["output"].strip()
    if issubclass(cls, Sliding):  # one signals kernel for every sliding law: their prefix is one layout
        assert mod.LAYOUT.entries[:len(PREFIX.entries)] == PREFIX.entries


@pytest.mark.parametrize("cls", COMPILED, ids=[c.name for c in COMPILED])
def test_layout_reads_back_every_packed_field(cls):
    """Each field packed with a distinct value is found at its LAYOUT offset (n = 3, p = 5): a layout
    written twice, or an offset off by one, fails here."""
    n, p = 3, 5
    vals = {}
    for k, f in enumerate(fields(cls)):
        entries = f.metadata.get("pack", ())
        if entries and entries[0][1] in ("n", "p"):
            vals[f.name] = 10.0 * (k + 1) + np.arange(n if entries[0][1] == "n" else p)
        elif entries:
            vals[f.name] = 10.0 * (k + 1) + 0.5
    law = cls(np.arange(1.0, p + 1.0), **vals)
    cp = law.pack(n)
    lay = cls.layout()
    assert cp.size == lay.size(n, p) and np.array_equal(lay.slice(cp, "theta", n), law.theta)
    for name, value in vals.items():
        got = lay.slice(cp, name, n)
        assert np.array_equal(got, np.atleast_1d(value)), (name, got, value)


def _module(name, **attrs):
    mod = types.ModuleType(name)
    mod.__dict__.update(attrs)
    sys.modules[name] = mod
    return mod


def _law_in(modname, code=97):
    @dataclass(frozen=True, eq=False)
    class Half(Law):
        K: float = packed(1.0, ("K", "n"))
        name = "test-half-law"

    Half.code = code
    Half.__module__ = modname
    return Half


@pytest.mark.parametrize("missing", ["LAYOUT", "signals", "theta", "slopes", "directions", "state_gain", "c_source"])
def test_a_compiled_law_missing_a_part_is_refused(missing):
    """register_law refuses a compiled law whose module lacks its LAYOUT, a value kernel, a derivative or its C."""
    from rc3r.controllers import pd_plus

    modname = f"_rc3r_test_half_{missing}"
    cls = _law_in(modname)
    parts = {k: getattr(pd_plus, k) for k in ("USES_XI", *VALUE_KERNELS, *DERIVATIVE_KERNELS, "c_source")}
    parts["LAYOUT"] = Layout.of(cls)
    del parts[missing]
    _module(modname, **parts)
    try:
        with pytest.raises(TypeError, match=missing):
            register_law(cls)
        assert cls.name not in LAWS
    finally:
        sys.modules.pop(modname, None)


def test_a_wrong_layout_a_plain_function_or_a_taken_code_is_refused():
    from rc3r.controllers import pd_plus

    modname = "_rc3r_test_half_wrong"
    cls = _law_in(modname)
    parts = {k: getattr(pd_plus, k) for k in ("USES_XI", *VALUE_KERNELS, *DERIVATIVE_KERNELS, "c_source")}
    try:
        _module(modname, **parts, LAYOUT=Layout((("p", "1"), ("theta", "p"))))  # not its fields' layout
        with pytest.raises(TypeError, match="not the layout of its fields"):
            register_law(cls)
        _module(modname, **dict(parts, signals=pd_plus.signals.py_func), LAYOUT=Layout.of(cls))
        with pytest.raises(TypeError, match="numba kernels"):
            register_law(cls)
        _module(modname, **parts, LAYOUT=Layout.of(cls))
        with pytest.raises(TypeError, match="code 1 is law 'robust'"):
            register_law(_law_in(modname, code=1))
    finally:
        sys.modules.pop(modname, None)
    assert "test-half-law" not in LAWS


def test_the_dispatch_has_one_branch_per_code_and_none_that_falls_through():
    """Every generated function is an if/elif chain over the registered codes whose last ``else`` raises;
    each code is tested exactly once per function; an unregistered code raises (checked on py_func)."""
    src = _dispatch.law_source()
    tree = ast.parse(src)
    codes = sorted(cls.code for cls in COMPILED)
    funcs = [f for f in tree.body if isinstance(f, ast.FunctionDef)]
    assert sorted(f.name for f in funcs) == sorted(["law_signals", "inertia_gain", "uses_xi", "law_theta",
                                                     "law_slopes", "law_directions", "law_jacobian"])
    for f in funcs:
        chain = next(s for s in f.body if isinstance(s, ast.If))
        seen = []
        while isinstance(chain, ast.If):
            seen += [c.value for c in ast.walk(chain.test) if isinstance(c, ast.Constant)]
            last, chain = chain, (chain.orelse[0] if len(chain.orelse) == 1 and isinstance(chain.orelse[0], ast.If)
                                  else chain.orelse)
        assert sorted(seen) == codes, (f.name, seen)
        assert len(chain) == 1 and isinstance(chain[0], ast.Raise), f"{f.name} falls through"
    ns = {}
    exec(compile("from numba import njit\n" + src.replace("cache=True", "cache=False"), "<dispatch>", "exec"), ns)
    with pytest.raises(ValueError, match="not registered"):
        ns["inertia_gain"].py_func(max(codes) + 1, np.zeros(3), 1)


def test_architecture_doc_worked_example_is_one_registered_module():
    """docs/architecture.md's "Adding a compiled law" names its file; it exists, is one module, and its law
    is registered, compiled and exportable."""
    text = (REPO / "docs" / "architecture.md").read_text()
    section = text[text.index("## Adding a compiled law"):]
    section = section[:section.index("\n## ", 1)]
    path = re.search(r"`(src/rc3r/controllers/\w+\.py)`", section).group(1)
    file = REPO / path
    assert file.exists()
    modname = "rc3r." + path[len("src/rc3r/"):-3].replace("/", ".")
    laws = [cls for cls in LAWS.values() if cls.__module__ == modname]
    assert len(laws) == 1 and laws[0].code is not None and laws[0].name in section
    assert f'kind = "{laws[0].name}"' in section and f"--controller {laws[0].name}" in section
