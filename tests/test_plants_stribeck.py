"""rc3r.plants.stribeck: the worked example of a compiled plant effect added as one file.

Each check compares with an independent source: the formula evaluated by hand (numbers below, not
the module's code), the python engine's trajectory (numpy's torque) against the compiled engine's
(the njit kernel through the generated dispatch), and the analytic Jacobian (the module's
``damping``) against central differences of the engine's right-hand side.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import rc3r
from rc3r.errors import ConfigError
from rc3r.plants import EFFECTS, Plant, Stribeck
from rc3r.plants import stribeck as S

#: F_c, F_s, v_s, F_v per joint; v_eps
FC, FS, VS, FV, VE = [1.0, 0.5, 2.0], [2.0, 0.5, 3.0], [0.1, 0.2, 0.05], [0.5, 0.0, 1.0], 0.01


def _by_hand(qd):
    """tau_f = -((F_c + (F_s - F_c) exp(-(qd/v_s)^2)) tanh(qd/v_eps) + F_v qd), written out per joint."""
    return [-((fc + (fs - fc) * math.exp(-(v / vs) ** 2)) * math.tanh(v / VE) + fv * v)
            for fc, fs, vs, fv, v in zip(FC, FS, VS, FV, qd)]


def test_torque_by_hand():
    """At qd = (0.1, -0.2, 0): joint 1 at its Stribeck speed (exp(-1)), joint 2 without a peak (F_s = F_c),
    joint 3 at rest (no torque). Numbers from the formula by hand: -(1 + e^-1) tanh(10) - 0.05, 0.5 tanh(20), 0."""
    e = Stribeck(FC, FS, VS, FV, v_eps=VE)
    qd = np.array([0.1, -0.2, 0.0])
    want = [-(1.0 + math.exp(-1.0)) * math.tanh(10.0) - 0.05, 0.5 * math.tanh(20.0), 0.0]
    assert want[0] == pytest.approx(-1.4178794354, abs=1e-9)
    np.testing.assert_allclose(_by_hand(qd), want, rtol=1e-15, atol=0)
    np.testing.assert_allclose(e.joint_torque(np.zeros(3), qd), want, rtol=1e-14, atol=1e-15)  # the python engine's
    block = e.LAYOUT.pack(e, 3)
    fx = np.concatenate([[1.0, S.Stribeck.code, 3.0], block])
    for kernel in (S.torque, S.torque.py_func):  # compiled, and its Python text
        got = [kernel(fx, 3, 3, j, qd[j]) for j in range(3)]
        np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-15)


def test_derivative_against_central_differences():
    """``damping`` = -d torque / d qd, at speeds across the peak, the decay (negative damping) and beyond."""
    e = Stribeck(FC, FS, VS, FV, v_eps=VE)
    fx = np.concatenate([[1.0, S.Stribeck.code, 3.0], e.LAYOUT.pack(e, 3)])
    for v in (-0.3, -0.05, -0.004, 0.0, 0.003, 0.02, 0.08, 0.15, 1.0):
        for j in range(3):
            h = 1e-7 * max(1.0, abs(v))
            fd = -(S.torque(fx, 3, 3, j, v + h) - S.torque(fx, 3, 3, j, v - h)) / (2 * h)
            assert S.damping(fx, 3, 3, j, v) == pytest.approx(fd, rel=1e-6, abs=1e-6 * (1 + abs(fd)))
    assert S.damping(fx, 3, 3, 0, 0.1) < 0  # the Stribeck decay: friction falls as the joint speeds up


def test_registered_and_reachable_from_a_config_file(tmp_path):
    """``[plant.stribeck]`` in a run's TOML builds the effect on the true plant (one number per key broadcast)."""
    from rc3r.io import read_config

    assert EFFECTS["stribeck"] is Stribeck and Stribeck.code not in {c.code for c in EFFECTS.values()
                                                                     if c is not Stribeck and c.compiled}
    cfg = tmp_path / "run.toml"
    cfg.write_text('[plant.stribeck]\ncoulomb = 1.0\nstatic = [2.0, 0.5, 3.0]\nv_s = 0.1\nviscous = 0.5\n')
    spec = rc3r.build_run(controller="fbl", duration=0.05, config=read_config(str(cfg)))
    e = spec.true_plant.effect("stribeck")
    assert e.coulomb.tolist() == [1.0] * 3 and e.static.tolist() == [2.0, 0.5, 3.0] and e.v_eps == 0.01
    with pytest.raises(ConfigError, match="unknown key.*v_stat"):
        rc3r.build_run(controller="fbl", config={"plant": {"stribeck": {"v_stat": 1.0}}})


def test_cli_option(tmp_path, capsys):
    """``--stribeck C:S:V:F`` is declared by the effect and reaches the plant of ``rc3r run``; bad text is one line."""
    from rc3r.cli import build_parser
    from rc3r.cli.run import plant_options

    args = build_parser().parse_args(["run", "--stribeck", "1:2:0.1:0.5"])
    opts = plant_options(args)
    assert opts["effects"] == {"stribeck": "1.0:2.0:0.1:0.5"}
    spec = rc3r.build_run(controller="fbl", duration=0.05, **opts)
    e = spec.true_plant.effect("stribeck")
    assert e.static.tolist() == [2.0] * 3 and e.v_s.tolist() == [0.1] * 3 and e.viscous.tolist() == [0.5] * 3
    from rc3r.cli import main

    code = main(["run", "--stribeck", "1:2:x:0", "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "COULOMB:STATIC:V_S:VISCOUS" in err


def _spec(**kw):
    return rc3r.build_run(controller="robust", perturbed=True, duration=0.2,
                          config={"plant": {"stribeck": {"coulomb": FC, "static": FS, "v_s": VS, "viscous": FV,
                                                         "v_eps": 0.05}}}, **kw)


def test_compiled_engine_equals_python_engine():
    """A sampled run (RK4 sub-steps) with Stribeck friction: the compiled engine (njit kernel, generated
    dispatch) and the python engine (numpy) agree to rounding."""
    from dataclasses import replace

    from rc3r.simulate import simulate

    spec = _spec(rate=1000.0)
    opt = replace(spec.options, sampled_method="rk4", nsub=8)
    fast = simulate(spec.true_plant, spec.law, spec.trajectory, replace(opt, engine="fast"))
    slow = simulate(spec.true_plant, spec.law, spec.trajectory, replace(opt, engine="python"))
    assert fast.ok and slow.ok
    assert np.abs(fast.qd).max() > 0.05  # the friction acts (its peak at v_s, joints moving)
    np.testing.assert_allclose(fast.q, slow.q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(fast.u, slow.u, rtol=0, atol=1e-7 * np.abs(slow.u).max())


def test_analytic_jacobian_with_stribeck_equals_central_differences(rng):
    """The closed loop's J and f_t with Stribeck friction (and a clipping torque limit), composed from the
    module's ``damping``, equal central differences of the engine's right-hand side (tests/test_jacobian.py)."""
    from test_jacobian import _analytic, _central, _setup, clipped_friction

    for controller, eps in (("fbl", None), ("robust", 0.5)):
        spec, mod, n, cp, tp, code, kc, fx, x0 = _setup(controller, eps)
        x = x0 + 0.3 * rng.uniform(-1, 1, x0.size)
        x[n:2 * n] = [0.12, -0.04, 0.3]  # across the Stribeck peak and decay
        t = 0.37
        fx = clipped_friction(mod, t, x, kc, fx, code, cp, tp, spec.true_rigid, Stribeck(FC, FS, VS, FV, v_eps=0.05))
        assert S.Stribeck.code in fx[1:1 + 2 * int(fx[0]):2]
        ok, J, Ft = _analytic(mod, t, x, kc, fx, code, cp, tp, n)
        assert ok
        Jc, Ftc = _central(mod, t, x, kc, fx, code, cp, tp, n)
        scale = np.abs(Jc).max()
        assert np.abs(J - Jc).max() <= 1e-6 * scale, np.abs(J - Jc).max() / scale
        assert np.abs(Ft - Ftc).max() <= 1e-6 * max(np.abs(Ftc).max(), 1.0)


def test_stiff_and_packed():
    """It declares itself stiff (shorter explicit steps) and packs by its LAYOUT: coulomb, static, v_s,
    viscous per joint, then v_eps."""
    e = Stribeck(FC, FS, VS, FV, v_eps=VE)
    assert Stribeck.stiff and e.damping().tolist() == pytest.approx([0.5 + 200.0, 50.0, 1.0 + 300.0])
    np.testing.assert_array_equal(Plant(rc3r.load_robot(), [e]).pack(),
                                  [1, 3, 3] + FC + FS + VS + FV + [VE])
