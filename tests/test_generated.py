"""Generated C kernels (rc3r.robots.generated) against Pinocchio, an independent implementation.

Tolerances: every kernel is a few thousand double-precision operations on quantities of
order one (rad, rad/s, kg, m), so its rounding error is ~1e-13 of the largest term; the
comparisons are relative to ``max(1, |reference|)`` (the 1 keeps a near-zero entry from asking
for more than absolute 1e-10) at 1e-10, orders of magnitude above the ~5e-16 that
``benchmarks/generated_kernels.py`` prints for rnea and slotine_li (``docs/generated.md``) yet far
below any modelling error (a wrong sign, axis or parameter is O(1)). ``aba`` solves with M, whose
condition number multiplies the rounding error of both sides (the generated code and ``pin.aba``
factor it differently); it gets 1e-9.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

cs = pytest.importorskip("casadi")
pin = pytest.importorskip("pinocchio")
if shutil.which(os.environ.get("RC3R_CC") or os.environ.get("CC") or "cc") is None:
    pytest.skip("no C compiler (cc) to build the generated kernels", allow_module_level=True)

from rc3r.errors import ConfigError, ParameterError  # noqa: E402
from rc3r.robots.generated import FUNCTIONS, GeneratedKernels, chain_constants  # noqa: E402
from rc3r.robots.pinocchio import PinocchioRobot  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
RR3_URDF = REPO / "urdf" / "rr3.urdf"
STATES = 50
TOL = 1e-10


def _robot(name):
    return PinocchioRobot.from_urdf(RR3_URDF) if name == "rr3" else PinocchioRobot.named(name)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("kernels")


@pytest.fixture(scope="module", params=["ur5", "panda", "rr3"])
def built(request, cache):
    """(robot, kernels) of each arm, built once per module into the module's cache."""
    robot = _robot(request.param)
    return robot, GeneratedKernels.for_robot(robot, cache_dir=cache)


def _states(rng, n, k=4):
    q = rng.uniform(-np.pi, np.pi, (STATES, n))
    return (q, *rng.uniform(-5.0, 5.0, (k - 1, STATES, n)))


def _rel(x, ref):
    """max over states of |x - ref| / max(1, |ref|) (max norms per state)."""
    x, ref = np.asarray(x).reshape(STATES, -1), np.asarray(ref).reshape(STATES, -1)
    return float(np.max(np.abs(x - ref).max(axis=1) / np.maximum(1.0, np.abs(ref).max(axis=1))))


def _pin(robot):
    return robot.model, robot.model.createData()


def test_rnea_equals_pinocchio(built, rng):
    robot, k = built
    Q, QD, QDD = _states(rng, robot.n, 3)
    m, d = _pin(robot)
    ref = np.array([pin.rnea(m, d, q, qd, a) for q, qd, a in zip(Q, QD, QDD)])
    assert _rel(k.rnea(Q, QD, QDD), ref) < TOL
    assert k.rnea(Q[0], QD[0], QDD[0]).shape == (robot.n,)
    np.testing.assert_allclose(k.rnea(Q[0], QD[0], QDD[0]), ref[0], rtol=0, atol=TOL * max(1, np.abs(ref[0]).max()))


def test_mass_coriolis_gravity_equal_pinocchio(built, rng):
    robot, k = built
    Q, QD = _states(rng, robot.n, 2)
    m, d = _pin(robot)
    M_ref = np.array([np.array(pin.crba(m, d, q)) for q in Q])
    M_ref = np.triu(M_ref) + np.swapaxes(np.triu(M_ref, 1), -1, -2)  # crba fills the upper triangle
    C_ref = np.array([np.array(pin.computeCoriolisMatrix(m, d, q, qd)) for q, qd in zip(Q, QD)])
    g_ref = np.array([pin.computeGeneralizedGravity(m, d, q) for q in Q])
    M, C, g = k.mass(Q), k.coriolis(Q, QD), k.gravity(Q)
    assert M.shape == C.shape == (STATES, robot.n, robot.n) and g.shape == (STATES, robot.n)
    assert _rel(M, M_ref) < TOL
    assert _rel(C, C_ref) < TOL
    assert _rel(g, g_ref) < TOL
    assert k.mass(Q[0]).shape == k.coriolis(Q[0], QD[0]).shape == (robot.n, robot.n)


def test_coriolis_skew_property(built, rng):
    """dM/dt - 2 C is skew-symmetric (dM/dt by central differences along qd: error ~h^2 ~1e-10)."""
    robot, k = built
    Q, QD = _states(rng, robot.n, 2)
    h = 1e-5
    dM = (k.mass(Q + h * QD) - k.mass(Q - h * QD)) / (2 * h)
    N = dM - 2 * k.coriolis(Q, QD)
    assert np.abs(N + np.swapaxes(N, 1, 2)).max() < 1e-6 * max(1.0, np.abs(dM).max())


def test_aba_equals_pinocchio(built, rng):
    robot, k = built
    Q, QD, TAU = _states(rng, robot.n, 3)
    TAU = TAU * 10.0
    m, d = _pin(robot)
    ref = np.array([pin.aba(m, d, q, qd, u) for q, qd, u in zip(Q, QD, TAU)])
    assert _rel(k.aba(Q, QD, TAU), ref) < 1e-9
    # and inverts rnea
    assert _rel(k.rnea(Q, QD, k.aba(Q, QD, TAU)), TAU) < 1e-9


def test_slotine_li_identity_and_reference(built, rng):
    robot, k = built
    Q, QD, V, A = _states(rng, robot.n)
    m, d = _pin(robot)
    ref = []
    for q, qd, v, a in zip(Q, QD, V, A):
        M = np.array(pin.crba(m, d, q))
        M = np.triu(M) + np.triu(M, 1).T
        ref.append(M @ a + np.array(pin.computeCoriolisMatrix(m, d, q, qd)) @ v
                   + pin.computeGeneralizedGravity(m, d, q))
    Y = k.slotine_li(Q, QD, V, A)
    assert Y.shape == (STATES, robot.n, robot.p) and k.p == robot.p
    assert _rel(Y @ np.asarray(robot.theta), np.array(ref)) < TOL
    assert _rel(Y, robot.regressor_pinocchio(Q, QD, V, A)) < TOL
    assert k.slotine_li(Q[0], QD[0], V[0], A[0]).shape == (robot.n, robot.p)


def test_cache_hit_compiles_nothing(built, cache):
    robot, k = built
    again = GeneratedKernels.for_robot(robot, cache_dir=cache)
    assert again.compile_seconds == 0.0 and again.generate_seconds == 0.0
    assert again.library_path == k.library_path and again.key == k.key
    assert k.library_path.is_file() and k.source_path.is_file()
    assert json.loads((k.library_path.parent / "meta.json").read_text())["functions"] == list(FUNCTIONS)
    assert not [p for p in cache.iterdir() if p.name.startswith(".")]  # no temporary directory left


def test_fresh_process_compiles_nothing(cache):
    robot = _robot("rr3")
    first = GeneratedKernels.for_robot(robot, cache_dir=cache)
    code = ("import sys; from rc3r.robots.pinocchio import PinocchioRobot; "
            "from rc3r.robots.generated import GeneratedKernels; "
            "k = GeneratedKernels.for_robot(PinocchioRobot.from_urdf(sys.argv[1]), cache_dir=sys.argv[2]); "
            "print(k.compile_seconds, k.generate_seconds, k.library_path)")
    out = subprocess.run([sys.executable, "-c", code, str(RR3_URDF), str(cache)], capture_output=True, text=True,
                         check=True, timeout=300).stdout.split()
    assert out == ["0.0", "0.0", str(first.library_path)]


def test_changed_standard_parameter_changes_key(tmp_path, rng):
    robot = _robot("rr3")
    std = robot.standard_parameters().copy()
    std[10:20] *= 1.5  # the second body 1.5 x heavier (mass, first moments, inertia)
    other = robot.with_standard_parameters(std, "heavier link 2")
    a = GeneratedKernels.for_robot(robot, cache_dir=tmp_path, functions=["gravity"])
    b = GeneratedKernels.for_robot(other, cache_dir=tmp_path, functions=["gravity"])
    assert a.key != b.key and a.library_path != b.library_path and b.compile_seconds > 0
    Q = _states(rng, 3, 1)[0]
    assert _rel(b.gravity(Q), other.gravity(Q)) < TOL
    assert _rel(a.gravity(Q), other.gravity(Q)) > 1e-3  # the parameters are embedded
    with pytest.raises(ConfigError, match="rnea was not generated"):
        a.rnea(Q, Q, Q)


def _one_line(exc):
    msg = str(exc.value)
    assert "\n" not in msg and "Traceback" not in msg
    return msg


def test_missing_compiler_is_one_line_error(tmp_path, monkeypatch):
    monkeypatch.setenv("RC3R_CC", "rc3r-no-such-compiler")
    with pytest.raises(ConfigError, match="C compiler 'rc3r-no-such-compiler' not found") as exc:
        GeneratedKernels.for_robot(_robot("rr3"), cache_dir=tmp_path, functions=["gravity"])
    _one_line(exc)
    assert not list(tmp_path.iterdir())


def test_compile_failure_is_one_line_error(tmp_path):
    with pytest.raises(ConfigError, match="compiling the generated kernels with .* failed") as exc:
        GeneratedKernels.for_robot(_robot("rr3"), cache_dir=tmp_path, functions=["gravity"],
                                   flags=["-shared", "-fPIC", "--rc3r-no-such-flag"])
    _one_line(exc)
    assert not list(tmp_path.iterdir())  # the temporary build directory is removed


def test_bad_robot_is_one_line_error(tmp_path):
    model = pin.Model()
    jid = model.addJoint(0, pin.JointModelRUBZ(), pin.SE3.Identity(), "wheel")  # continuous: nq = 2
    model.appendBodyToJoint(jid, pin.Inertia.FromSphere(1.0, 0.1), pin.SE3.Identity())
    with pytest.raises(ParameterError, match="'wheel'.*nq=2") as exc:
        GeneratedKernels.for_model(model, [0], cache_dir=tmp_path)
    _one_line(exc)
    with pytest.raises(ParameterError, match="no pinocchio model") as exc:
        GeneratedKernels.for_robot(object(), cache_dir=tmp_path)
    _one_line(exc)
    with pytest.raises(ParameterError, match="base columns"):
        GeneratedKernels.for_model(_robot("rr3").model, [0, 30], cache_dir=tmp_path)
    with pytest.raises(ParameterError, match="unknown generated function"):
        GeneratedKernels.for_robot(_robot("rr3"), cache_dir=tmp_path, functions=["crba"])


def test_chain_constants_read_the_model():
    robot = _robot("ur5")
    ch = chain_constants(robot.model)
    assert ch.n == 6 and ch.revolute.all() and list(ch.parent) == [-1, 0, 1, 2, 3, 4]
    np.testing.assert_array_equal(ch.pi.ravel(), robot.standard_parameters())


def test_default_cache_dir(monkeypatch, tmp_path):
    from rc3r.robots.generated import default_cache_dir

    monkeypatch.setenv("RC3R_CACHE_DIR", str(tmp_path))
    assert default_cache_dir() == tmp_path / "kernels"
    monkeypatch.delenv("RC3R_CACHE_DIR")
    assert default_cache_dir() == Path.home() / ".cache" / "rc3r" / "kernels"
