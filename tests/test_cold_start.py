"""The cold start (speed issue): a short sampled run whose compiled integrator is not built yet runs on
the python engine and compiles nothing; longer runs, continuous runs and ``RC3R_COLD_START=compile``
compile; campaigns build the integrator once first (:func:`rc3r.campaign.runner.prepare`).

The suite itself runs with ``RC3R_COLD_START=compile`` (tests/conftest.py); the tests here that need
the default policy set it themselves, or start a fresh interpreter with an empty numba cache.
"""
from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rc3r
from rc3r import _numba_cache
from rc3r.campaign.runner import prepare
from rc3r.simulate import planned_engine
from rc3r.simulate._fast import CompiledSimulator
from rc3r.simulate.engines.base import COLD_MAX_SUBSTEPS

_COLD_CMD = ["run", "--robot", "ur5", "--controller", "fbl", "--rate", "1000", "--duration", "0.2"]


def _import_file(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_ready_is_false_before_the_first_compile_and_true_after(tmp_path, monkeypatch):
    """ready(f): False for a cache=True function never compiled (empty cache), True once compiled in
    this process; ready_or_python gives the plain function while cold, the dispatcher after."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("RC3R_COLD_START", "python")
    src = tmp_path / "coldmod.py"
    src.write_text("from numba import njit\n\n@njit(cache=True)\ndef twice(x):\n    return 2.0 * x\n")
    mod = _import_file(src, "rc3r_test_coldmod")
    assert not _numba_cache.ready(mod.twice)
    f = _numba_cache.ready_or_python(mod.twice)
    assert f is mod.twice.py_func and f(1.5) == 3.0  # interpreted: nothing compiled
    assert not mod.twice.overloads
    assert mod.twice(1.5) == 3.0  # compiles
    assert _numba_cache.ready(mod.twice)
    assert _numba_cache.ready_or_python(mod.twice) is mod.twice


def test_compile_policy_keeps_the_dispatcher(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    src = tmp_path / "coldmod2.py"
    src.write_text("from numba import njit\n\n@njit(cache=True)\ndef thrice(x):\n    return 3.0 * x\n")
    mod = _import_file(src, "rc3r_test_coldmod2")
    monkeypatch.setenv("RC3R_COLD_START", "compile")
    assert _numba_cache.cold_start_policy() == "compile"
    assert _numba_cache.ready_or_python(mod.thrice) is mod.thrice
    monkeypatch.setenv("RC3R_COLD_START", "anything else")
    assert _numba_cache.cold_start_policy() == "python"


@pytest.fixture
def cold(monkeypatch):
    """The default policy, and every compiled integrator reported not built (numba's cache cold)."""
    monkeypatch.setenv("RC3R_COLD_START", "python")
    monkeypatch.setattr(CompiledSimulator, "is_cached", lambda self, which=None, law=None, fx=None: False)


@pytest.mark.parametrize("robot", ["ur5", "rr3"])
def test_short_sampled_run_passes_a_cold_engine_over(cold, robot):
    spec = rc3r.build_run(robot=robot, controller="fbl", rate=1000.0, duration=1.0)
    name, why = planned_engine(spec.true_rigid, spec.law, spec.options)
    assert name == "python" and "not built yet" in why


def test_limit_of_the_cold_rule(cold):
    """At the limit (COLD_MAX_SUBSTEPS sub-steps, one per 1 ms period) python; one period more, fast."""
    at = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=COLD_MAX_SUBSTEPS / 1000.0)
    assert planned_engine(at.true_rigid, at.law, at.options)[0] == "python"
    past = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=COLD_MAX_SUBSTEPS / 1000.0 + 0.001)
    assert planned_engine(past.true_rigid, past.law, past.options) == ("fast", None)


def test_continuous_named_and_compile_policy_runs_compile(cold, monkeypatch):
    cont = rc3r.build_run(robot="rr3", controller="robust", perturbed=True, duration=1.0)
    assert planned_engine(cont.true_rigid, cont.law, cont.options) == ("fast", None)
    named = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=1.0, engine="fast")
    assert planned_engine(named.true_rigid, named.law, named.options) == ("fast", None)
    monkeypatch.setenv("RC3R_COLD_START", "compile")
    short = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=1.0)
    assert planned_engine(short.true_rigid, short.law, short.options) == ("fast", None)


def test_cold_python_run_equals_the_compiled_one(cold):
    """The run a cold start takes (python engine, RK4 on the same 1 ms step, interpreted kernels) gives
    the compiled engine's trajectory: both are RK4 on the same grid, so they agree to rounding
    (tests/test_simulate.py: 6.5e-13 rad over 2 s on the UR5); 1e-9 rad leaves room for 0.5 s."""
    spec = rc3r.build_run(robot="ur5", controller="robust", payload=(0.0, 3.0), perturbed=True, rate=1000.0,
                          duration=0.5)
    res_py = rc3r.simulate(spec.true_plant or spec.true_rigid, spec.law, spec.trajectory, spec.options,
                           loop=spec.loop, model=spec.controller_model)
    assert res_py.engine == "python"
    from dataclasses import replace

    res_fast = rc3r.simulate(spec.true_plant or spec.true_rigid, spec.law, spec.trajectory,
                             replace(spec.options, engine="fast"), loop=spec.loop, model=spec.controller_model)
    assert res_fast.engine == "fast" and res_py.outcome == res_fast.outcome == "finished"
    assert np.max(np.abs(res_py.q - res_fast.q)) < 1e-9


def test_prepare_builds_a_cold_integrator_and_leaves_a_warm_one(monkeypatch):
    monkeypatch.setenv("RC3R_COLD_START", "python")
    spec = rc3r.build_run(robot="rr3", controller="fbl", rate=1000.0, duration=1.0)
    from dataclasses import replace

    rc3r.simulate(spec.true_rigid, spec.law, spec.trajectory, replace(spec.options, engine="fast"))  # now warm
    assert planned_engine(spec.true_rigid, spec.law, spec.options) == ("fast", None)
    assert prepare(spec) is False  # warm: nothing to do
    calls = []
    monkeypatch.setattr(CompiledSimulator, "is_cached", lambda self, which=None, law=None, fx=None: bool(calls))
    real = CompiledSimulator.sampled

    def sampled(self, *args, **kwargs):
        calls.append(os.environ.get("RC3R_COLD_START"))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(CompiledSimulator, "sampled", sampled)
    assert prepare(spec) is True
    assert calls and calls[0] == "compile"  # ran the compiled integrator, under the compile policy
    assert os.environ["RC3R_COLD_START"] == "python"  # and put the policy back


def test_fresh_process_with_an_empty_cache_compiles_nothing(tmp_path):
    """``rc3r run --robot ur5 --controller fbl --rate 1000 --duration 0.2`` in a fresh interpreter with an
    empty NUMBA_CACHE_DIR: exit 0, the python engine, says so, and numba wrote no compiled code (no
    .nbc file: nothing was compiled); its errors equal the compiled engine's run in this process."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_") and k != "RC3R_COLD_START"}
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "numba")
    env["MPLBACKEND"] = "Agg"
    code = "import sys; from rc3r.cli import entry; sys.argv = ['rc3r'] + sys.argv[1:]; entry()"
    out = tmp_path / "out"
    p = subprocess.run([sys.executable, "-c", code, *_COLD_CMD, "--out", str(out)], capture_output=True,
                       text=True, env=env, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    assert "python engine" in p.stderr
    m = json.loads((out / "metrics.json").read_text())
    assert m["engine"] == "python" and m["status"] == "ok"
    compiled = list((tmp_path / "numba").rglob("*.nbc")) if (tmp_path / "numba").exists() else []
    assert compiled == []
    spec = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=0.2, engine="fast")
    res = rc3r.simulate(spec.true_rigid, spec.law, spec.trajectory, spec.options)
    e_fast = np.max(np.abs(res.e), axis=0)
    np.testing.assert_allclose(m["max_abs_error"], e_fast, rtol=1e-6, atol=1e-12)


def test_run_says_when_stiff_friction_multiplies_the_sub_steps(capsys):
    """The line rc3r run prints before a sampled run on a stiff friction: the damping rate and the
    sub-step count (64 for the UR5 with --friction 0.5:10 at 1 kHz: ceil(T lambda), lambda from
    rc3r.simulate.stiffness). By default (``sampled_method = "auto"``) such a plant is advanced by SDIRK
    periods and the line says so (``"ros4"``: ROS4 periods); with ``sampled_method = "rk4"`` it says the sub-steps multiply the
    cost. A rigid plant prints no such line."""
    import dataclasses

    from rc3r.cli.run import announce_engine
    from rc3r.simulate import default_substeps, stiffness

    stiff = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=0.1, friction=(0.5, 10.0))
    n = default_substeps(stiff.true_plant, 1000.0)
    announce_engine(stiff)
    err = capsys.readouterr().err
    assert n > 16 and f"adaptive L-stable SDIRK steps per period instead of {n} RK4 sub-steps" in err
    announce_engine(dataclasses.replace(stiff, options=dataclasses.replace(stiff.options, sampled_method="ros4")))
    assert f"adaptive L-stable ROS4 steps per period instead of {n} RK4 sub-steps" in capsys.readouterr().err
    assert f"{stiffness(stiff.true_plant):.3g} 1/s" in err
    announce_engine(dataclasses.replace(stiff, options=dataclasses.replace(stiff.options, sampled_method="rk4")))
    err = capsys.readouterr().err
    assert f"{n} RK4 sub-steps per 1 ms period" in err and "ROS4" not in err and "SDIRK" not in err
    assert f"{stiffness(stiff.true_plant):.3g} 1/s" in err
    rigid = rc3r.build_run(robot="ur5", controller="fbl", rate=1000.0, duration=0.1)
    announce_engine(rigid)
    assert "stiff friction" not in capsys.readouterr().err
