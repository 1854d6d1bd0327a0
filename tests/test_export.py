"""``rc3r export``: the C controller against rc3r's own, and the C regressor against Pinocchio.

* ``make check`` of an export (the C torques at 1000 recorded calls against ``rc3r.Controller``'s)
  passes with ``max_abs_diff <= 1e-9`` N m for the UR5 carrying an unknown payload (FBL with a
  delay of one sample, robust, adaptive) and the 3R (robust, robust-coeff with two calls per
  period, PD), all at 1 kHz; the bound is the brief's: torques of tens to hundreds of N m agree to
  ~1e-13 (double rounding, a few hundred operations), so 1e-9 leaves four orders of margin;
* the harness can fail: a torque off by 1e-6 of max|u|, a controller without its delay line, one
  that recomputes inside the period (no zero-order hold), and one that skips the adaptive state's
  Euler step are each caught;
* the generic chain regressor in C equals Pinocchio's own regressor (computeJointTorqueRegressor,
  an independent source) on a tree with a prismatic joint (the Panda with a free finger);
* every generated source compiles with ``-std=c99 -Wall -Wextra -Werror -pedantic``;
* bad input is one line ``rc3r: error: ...``, exit 2, nothing written.

The tests that compile need ``cc`` and ``make`` and are skipped without them. The recordings use
the python engine (the runs' plant is the same; it needs no compilation of a simulator).
"""
from __future__ import annotations

import json
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import rc3r
from rc3r.cli import main
from rc3r.controllers import LAWS, Law, inertia_scaled_gain

CC = shutil.which("cc")
MAKE = shutil.which("make")
needs_cc = pytest.mark.skipif(CC is None or MAKE is None, reason="no C compiler (cc) or make")

#: The brief's bound on max |u_C - u_rc3r| [N m].
BOUND = 1e-9


def _toml(table: dict, prefix: str = "") -> str:
    """A small TOML writer for the configs below (scalars, lists, nested tables)."""
    plain = {k: v for k, v in table.items() if not isinstance(v, dict)}
    lines = [f"[{prefix}]"] if prefix and plain else []
    for k, v in plain.items():
        lines.append(f"{k} = {json.dumps(v)}")
    for k, v in table.items():
        if isinstance(v, dict):
            lines.append(_toml(v, f"{prefix}.{k}" if prefix else k))
    return "\n".join(lines)


def _config(robot: str) -> dict:
    """A 1 kHz design for each arm: the UR5 with a payload of 0..3 kg unknown to the controller
    (inertia-scaled K, docs/generic.md), the 3R perturbed with eps = 50 (clean at 1 kHz)."""
    if robot == "ur5-sched":  # K(q) = 25 M(q) (rc3r design's default)
        cfg = _config("ur5")
        cfg["gains"]["robust"] = {"K": 0.0, "K_inertia": 25.0, "Lambda": 10.0, "eps": 5.0}
        return cfg
    if robot == "ur5-fullK":  # K = 50 M(q_d(0)), the full matrix (rc3r design's coupled K)
        ur5 = rc3r.load_robot("ur5")
        M0 = ur5.mass_matrix(ur5.default_trajectory().evaluate(0.0)[0])
        cfg = _config("ur5")
        cfg["gains"]["robust"]["K"] = (50.0 * 0.5 * (M0 + M0.T)).tolist()
        return cfg
    if robot == "ur5":
        ur5 = rc3r.load_robot("ur5")
        k = [round(float(x), 4) for x in inertia_scaled_gain(ur5, ur5.default_trajectory().evaluate(0.0)[0], 50.0)]
        return {"robot": "ur5", "payload": {"mass": [0.0, 3.0]},
                "gains": {"robust": {"K": k, "Lambda": 20.0, "eps": 5.0},
                          "adaptive": {"K": k, "Lambda": 20.0, "Gamma": 1.0}},
                "simulation": {"rate": 1000.0, "engine": "python"}}
    if robot == "rr3-sched":
        return {"perturbed": True, "gains": {"adaptive": {"K": 1.0, "K_inertia": 20.0, "Lambda": 10.0, "Gamma": 1.0}},
                "simulation": {"rate": 1000.0, "engine": "python"}}
    return {"perturbed": True, "gains": {"robust": {"eps": 50.0}, "robust-coeff": {"eps_i": 50.0}},
            "simulation": {"rate": 1000.0, "engine": "python"}}


def _export(tmp_path, robot, law, *extra) -> Path:
    cfg = tmp_path / f"{robot}.toml"
    cfg.write_text(_toml(_config(robot)))
    out = tmp_path / f"{robot}-{law}"
    assert main(["export", "--config", str(cfg), "--controller", law, "--out", str(out), *extra]) == 0
    return out


def _check(directory) -> tuple[int, dict, str]:
    """``make -C directory check``: (exit code, the printed numbers, stdout)."""
    proc = subprocess.run([MAKE, "-s", "-C", str(directory), "check"], capture_output=True, text=True, timeout=300)
    numbers = {k: float(v) for k, v in re.findall(r"^(\w+) = ([-+0-9.eE]+|nan|inf)", proc.stdout, flags=re.M)}
    return proc.returncode, numbers, proc.stdout


#: (robot, law, extra options): the brief's six cases.
CASES = [("ur5", "fbl", ("--delay", "1")), ("ur5", "robust", ()), ("ur5", "adaptive", ()),
         ("rr3", "robust", ()), ("rr3", "robust-coeff", ("--calls-per-sample", "2")), ("rr3", "pd", ()),
         ("ur5-fullK", "robust", ()), ("ur5-sched", "robust", ()), ("rr3-sched", "adaptive", ())]


@pytest.fixture(scope="module")
def exports(tmp_path_factory):
    """Every case exported once (the module's tests share them; copies are mutated)."""
    base = tmp_path_factory.mktemp("exports")
    return {(robot, law): _export(base, robot, law, *extra) for robot, law, extra in CASES}


@needs_cc
@pytest.mark.parametrize("robot,law", [c[:2] for c in CASES], ids=[f"{r}-{law}" for r, law, _ in CASES])
def test_make_check_matches_rc3r(exports, robot, law):
    out = exports[(robot, law)]
    info = json.loads((out / "export.json").read_text())
    assert info["calls"] == 1000 and info["rate"] == 1000.0
    u = np.loadtxt(out / "torques.csv", delimiter=",", skiprows=1)
    t = np.loadtxt(out / "states.csv", delimiter=",", skiprows=1)[:, 0]
    assert np.all(np.isfinite(u)) and 1.0 < np.abs(u).max() < 1e4  # a working design, not a diverged one
    assert np.ptp(u, axis=0).min() > 0.0  # every joint's torque moves
    per = info["calls_per_sample"]
    np.testing.assert_allclose(t[::per], np.arange(1000 // per) / 1000.0, rtol=0, atol=1e-12)  # the samples
    code, numbers, stdout = _check(out)
    assert code == 0, stdout
    assert numbers["calls"] == 1000 and numbers["max_abs_diff"] <= BOUND, stdout
    assert numbers["ns_per_call"] > 0.0


def _mutated(exports, key, tmp_path, file, old, new) -> Path:
    """A copy of an export with ``old`` replaced by ``new`` (once) in ``file``."""
    out = tmp_path / "mutant"
    shutil.copytree(exports[key], out)
    for stale in ("rc3r_check", "rc3r_controller.o"):
        (out / stale).unlink(missing_ok=True)
    text = (out / file).read_text()
    assert text.count(old) == 1, (file, old)
    (out / file).write_text(text.replace(old, new))
    return out


@needs_cc
@pytest.mark.parametrize("key,file,old,new", [
    (("rr3", "pd"), "torques.csv", None, None),  # one torque off by 1e-6 max|u|
    (("ur5", "fbl"), "rc3r_controller.h", "#define RC3R_DELAY 1 ", "#define RC3R_DELAY 0 "),  # no delay line
    (("rr3", "robust-coeff"), "rc3r_controller.c", "} else if (k > s->k) {", "} else if (k >= s->k) {"),  # no hold
    (("ur5", "adaptive"), "rc3r_controller.c", "s->z[j] = s->z[j] + T * s->zdot[j];", "s->z[j] = s->z[j];"),
], ids=["torque", "delay", "hold", "adaptive-state"])
def test_check_catches_a_wrong_controller(exports, tmp_path, key, file, old, new):
    if old is None:
        lines = (exports[key] / file).read_text().splitlines()
        row = [float(x) for x in lines[500].split(",")]
        scale = max(abs(float(x)) for ln in lines[1:] for x in ln.split(","))
        row[1] += 1e-6 * scale
        old, new = lines[500], ",".join(repr(x) for x in row)
    out = _mutated(exports, key, tmp_path, file, old, new)
    code, numbers, stdout = _check(out)
    assert code != 0 and "FAILED" in stdout, stdout  # make exits 2 when the harness exits 1
    assert numbers["max_rel_diff"] > 1e-9


@needs_cc
def test_chain_regressor_in_c_equals_pinocchio(tmp_path):
    """The exported chain's xi = Y^T r and u = w + Y theta against Pinocchio's regressor
    (``regressor_pinocchio``: computeJointTorqueRegressor) on the Panda with its first finger free:
    8 joints, a tree (the finger hangs off the hand beside nothing else) and a prismatic joint."""
    from rc3r.export.chain import chain_source
    from rc3r.robots.pinocchio import PinocchioRobot, example_robot_data_dir

    robot = PinocchioRobot.from_urdf(example_robot_data_dir() / "panda_description/urdf/panda.urdf",
                                     lock={"panda_finger_joint2": 0.0})
    n, p = robot.n, robot.p
    assert n == 8 and not robot.kernel.ints[7, 1]  # the finger: prismatic
    driver = tmp_path / "driver.c"
    driver.write_text(f"#include <math.h>\n#include <stdio.h>\n#include <string.h>\n#define RC3R_N {n}\n#define RC3R_P {p}\n"
                      + chain_source(robot.kernel, robot._columns) + r"""
int main(void)
{
    double q[RC3R_N], qd[RC3R_N], v[RC3R_N], a[RC3R_N], r[RC3R_N], w[RC3R_N], th[RC3R_P], xi[RC3R_P], u[RC3R_N];
    rc3r_regressor wk;
    int i;
    for (;;) {
        for (i = 0; i < RC3R_N; ++i)
            if (scanf("%lf %lf %lf %lf %lf %lf", q + i, qd + i, v + i, a + i, r + i, w + i) != 6)
                return 0;
        for (i = 0; i < RC3R_P; ++i)
            if (scanf("%lf", th + i) != 1)
                return 1;
        rc3r_regressor_eval(&wk, q, qd, v, a);
        rc3r_regressor_xi(&wk, r, xi);
        rc3r_regressor_apply(&wk, th, w, u);
        for (i = 0; i < RC3R_P; ++i)
            printf("%.17g ", xi[i]);
        for (i = 0; i < RC3R_N; ++i)
            printf("%.17g ", u[i]);
        printf("\n");
    }
}
""")
    subprocess.run([CC, "-O2", "-std=c99", "-o", str(tmp_path / "driver"), str(driver), "-lm"], check=True)
    rng = np.random.default_rng(7)
    N = 40
    X = rng.uniform(-2.0, 2.0, (6, N, n))  # q, qd, v, a, r, w
    TH = rng.uniform(-1.0, 1.0, (N, p))
    text = "\n".join(" ".join(repr(float(x)) for x in np.concatenate([X[:, s].T.ravel(), TH[s]])) for s in range(N))
    out = subprocess.run([str(tmp_path / "driver")], input=text, capture_output=True, text=True, check=True).stdout
    res = np.array([[float(x) for x in line.split()] for line in out.splitlines()])
    Y = robot.regressor_pinocchio(X[0], X[1], X[2], X[3])
    xi = np.einsum("sij,si->sj", Y, X[4])
    u = np.einsum("sij,sj->si", Y, TH) + X[5]
    assert res.shape == (N, p + n)
    # a few hundred operations per entry, both sides in double: 1e-12 of the largest entry (7e-16 measured)
    assert np.abs(res[:, :p] - xi).max() <= 1e-12 * np.abs(xi).max()
    assert np.abs(res[:, p:] - u).max() <= 1e-12 * np.abs(u).max()


def _specs():
    """Specs of every law on both arms, sampled and continuous, and a quintic trajectory."""
    for robot in ("rr3", "ur5"):
        cfg = _config(robot)
        for law in ("fbl", "robust", "robust-coeff", "adaptive", "pd"):
            for rate in (1000.0, 0.0):
                yield f"{robot}-{law}-{'sampled' if rate else 'continuous'}", \
                    rc3r.build_run(controller=law, config={**cfg, "simulation": {"rate": rate}}, delay=2 if rate else None)
    quintic = {"kind": "quintic", "waypoints": [[0.0, 0.1, 0.2], [0.5, -0.3, 0.1], [0.2, 0.2, 0.2]],
               "durations": [1.0, 0.5]}
    yield "rr3-robust-quintic", rc3r.build_run(controller="robust", config={**_config("rr3"), "trajectory": quintic})


@needs_cc
def test_generated_sources_compile_without_warnings(tmp_path):
    from rc3r.export.c import controller_sources
    from rc3r.export.harness import _CHECK_C, TOLERANCE

    flags = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2"]
    (tmp_path / "check.c").write_text(_CHECK_C.replace("@TOL@", repr(TOLERANCE)))
    for name, spec in _specs():
        header, source = controller_sources(rc3r.Controller.from_run(spec), name)
        (tmp_path / "rc3r_controller.h").write_text(header)
        (tmp_path / "rc3r_controller.c").write_text(source)
        for unit in ("rc3r_controller.c", "check.c"):
            proc = subprocess.run([CC, *flags, "-c", unit, "-o", "/dev/null"], cwd=tmp_path, capture_output=True,
                                  text=True)
            assert proc.returncode == 0, f"{name} {unit}: {proc.stderr}"


def test_literals_read_back_exactly():
    """Every constant of the law is written as repr: the C source holds theta_0 digit for digit."""
    from rc3r.export.c import c_double, controller_sources

    spec = rc3r.build_run(controller="robust-coeff", config=_config("rr3"))
    _, source = controller_sources(rc3r.Controller.from_run(spec), "x")
    block = re.search(r"rc3r_theta0\[RC3R_P\] = \{(.*?)\}", source, flags=re.S).group(1)
    values = [float(x) for x in block.replace("\n", " ").split(",")]
    assert values == spec.law.theta.tolist()  # exact equality: repr reads back to the same double
    assert c_double(0.1) == "0.1" and float(c_double(1 / 3)) == 1 / 3
    with pytest.raises(rc3r.ParameterError):
        c_double(float("nan"))


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rc3r: error: "), err
    return err[0]


def test_bad_inputs_are_one_line_and_write_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["export", "--out", str(out)]) == 2
    assert "--config" in _one_error_line(capsys)
    assert main(["export", "--config", str(tmp_path / "missing.toml"), "--out", str(out)]) == 2
    assert "missing.toml" in _one_error_line(capsys)
    cfg = tmp_path / "rr3.toml"
    cfg.write_text(_toml(_config("rr3")))

    @dataclass(frozen=True, eq=False)
    class PythonLaw(Law):  # a law written in Python: no compiled kernel, no C port
        K: float = 10.0
        name = "python-pd-test"

        def signals(self, q, qd, ref):
            n = len(q)
            return np.zeros(n), np.zeros(n), np.zeros(n), -self.K * (np.asarray(q) - ref[0])

        def output(self, Y, r, z):
            return self.theta.copy(), np.zeros(0), 0.0

    LAWS[PythonLaw.name] = PythonLaw
    try:
        assert main(["export", "--config", str(cfg), "--controller", PythonLaw.name, "--out", str(out)]) == 2
        assert "has no C port" in _one_error_line(capsys)
    finally:
        del LAWS[PythonLaw.name]
    assert not out.exists()


def test_an_earlier_export_is_kept_without_force(tmp_path, capsys):
    cfg = tmp_path / "rr3.toml"
    cfg.write_text(_toml(_config("rr3")))
    out = tmp_path / "out"
    args = ["export", "--config", str(cfg), "--controller", "pd", "--out", str(out), "--states", "20"]
    assert main(args) == 0
    before = (out / "rc3r_controller.c").read_text()
    (out / "notes.txt").write_text("mine")
    capsys.readouterr()
    assert main(args[:4] + ["fbl"] + args[5:]) == 2
    assert "--force" in _one_error_line(capsys)
    assert (out / "rc3r_controller.c").read_text() == before
    assert main(args[:4] + ["fbl"] + args[5:] + ["--force"]) == 0
    assert "fbl on" in (out / "rc3r_controller.c").read_text() and (out / "notes.txt").read_text() == "mine"
