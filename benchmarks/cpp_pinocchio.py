#!/usr/bin/env python
"""Pinocchio's own C++ cost of rnea/aba/crba on a URDF arm, measured in C++, vs the generated C kernels.

``rc3r bench`` and ``benchmarks/generated_kernels.py`` can only *estimate* Pinocchio's C++ time
from Python. This script measures it: it writes the arm's ``pinocchio.Model`` (the Python model
itself: joint types, placements, inertias, gravity) to a plain text file, compiles
``benchmarks/cpp/pin_cpp_bench.cpp`` against the Pinocchio that the ``pin`` wheel installed
(headers and ``libpinocchio_default`` in its cmeel prefix), runs it on random states written by
this process, checks its rnea, aba and crba against ``pinocchio`` from Python (exits 1 if the
relative difference exceeds 1e-9), and, in the same run on the same states, times the generated
C kernels of :mod:`rc3r.robots.generated` (``GeneratedKernels.for_robot(robot)``: ``rnea``,
``aba`` = CRBA + Cholesky, ``mass``), one batch call from Python each.

Arms (``--robot``): ``rr3`` (default; ``urdf/rr3.urdf``, ``rc3r.robots.rr3.urdf.REPO_URDF``), the
names of ``PinocchioRobot.named`` (``ur5``, ``panda`` with its fingers locked), or a path to a
URDF of a fixed-base arm. Joints: 1-DoF revolute or prismatic (Pinocchio's ``RX/RY/RZ``,
``PX/PY/PZ``, ``RevoluteUnaligned``, ``PrismaticUnaligned``; URDF ``continuous`` joints are read
as revolute by ``PinocchioRobot.from_urdf``); the C++ model uses the same joint types as the
Python one, so both run the same code path.

States: ``numpy.random.default_rng(--seed)``, q in [-pi, pi], qd and qdd in [-5, 5] (as in
``benchmarks/generated_kernels.py``), aba torques in [-50, 50]. Every time is the median (and min)
over ``--repeats`` passes over the N states after one warm-up pass, divided by N.

Needs a C++17 compiler and the Eigen headers, which the ``pin`` wheel does not ship; searched in
``--eigen DIR`` (the directory that contains ``Eigen/``), ``$EIGEN_INCLUDE_DIR``, the cmeel
prefix, ``/usr/include/eigen3``, ``/usr/local/include/eigen3`` and the casadi wheel's
``casadi/include/eigen3`` (Eigen 3.4.0 in casadi 3.8.2).

Builds (``--build``, default ``both``, library first):

* ``library`` -- calls the precompiled ``libpinocchio_default``
  (``-DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION``, arguments ``Eigen::Ref<const VectorXd>``, the
  instantiated types), i.e. the C++ code the Python bindings run; the script checks with ``nm``
  that ``rnea``, ``aba`` and ``crba`` are undefined in the program (resolved from the library).
  Compiled without ``-march=native``: the library's Eigen alignment must match.
* ``headers`` -- Pinocchio's templates compiled into the program with ``-O3 -march=native``: the
  best case of Pinocchio on this machine.

The program does not depend on the arm (it reads the model file), so each build is compiled once
and kept in ``$RC3R_CACHE_DIR/cpp-bench`` (else ``~/.cache/rc3r/cpp-bench``), keyed by a SHA-256 of
the source, the compiler command and ``--version``; ``--no-cache`` recompiles in a temporary
directory. On the 2-core development machine the library build compiles in ~20 s, the headers
build in ~4 min.

Ends with ``target generated_tau_vs_cpp_rnea: <= 1x: <ratio> -> met|NOT MET``, the ratio being the
generated rnea per state over the fastest measured C++ rnea per state.

Usage: ``python benchmarks/cpp_pinocchio.py [--robot rr3|ur5|panda|PATH] [--build both|library|headers]
[--eigen DIR] [-n N] [--repeats R] [--seed S] [--no-generated] [--no-cache] [--json]``
"""
from __future__ import annotations

import argparse
import datetime
import hashlib
import importlib.util
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "cpp" / "pin_cpp_bench.cpp"
DEFINES = ["-DBOOST_MPL_LIMIT_LIST_SIZE=30", "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30",
           "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS", "-DBOOST_FUSION_INVOKE_MAX_ARITY=12"]
#: Relative tolerance of every cross-check (max |diff| / max(1, max |reference|)).
TOL = 1e-9
#: Pinocchio joint short names -> the type code of pin_cpp_bench.cpp.
JOINT_CODES = {"JointModelRX": "RX", "JointModelRY": "RY", "JointModelRZ": "RZ", "JointModelPX": "PX",
               "JointModelPY": "PY", "JointModelPZ": "PZ", "JointModelRevoluteUnaligned": "RU",
               "JointModelPrismaticUnaligned": "PU"}
BUILDS = ("library", "headers")


def die(msg: str) -> None:
    sys.exit(f"cpp_pinocchio: {msg}")


def cmeel_prefix() -> Path:
    import pinocchio

    for parent in Path(pinocchio.__file__).resolve().parents:
        if parent.name == "cmeel.prefix":
            return parent
    p = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix"
    if p.is_dir():
        return p
    die("cannot find the cmeel prefix of the pin wheel (headers, libpinocchio_default)")


def casadi_eigen() -> Path | None:
    spec = importlib.util.find_spec("casadi")
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(list(spec.submodule_search_locations)[0]) / "include" / "eigen3"


def find_eigen(arg: str | None, prefix: Path) -> Path:
    candidates = [arg, os.environ.get("EIGEN_INCLUDE_DIR"), prefix / "include" / "eigen3", "/usr/include/eigen3",
                  "/usr/local/include/eigen3", casadi_eigen()]
    if arg and not (Path(arg) / "Eigen" / "Core").is_file():
        die(f"--eigen {arg}: no Eigen/Core there")
    for c in candidates:
        if c and (Path(c) / "Eigen" / "Core").is_file():
            return Path(c)
    die("Eigen headers not found (searched $EIGEN_INCLUDE_DIR, the cmeel prefix, /usr/include/eigen3, "
        "/usr/local/include/eigen3, casadi/include/eigen3); pass --eigen DIR (the directory containing Eigen/)")


def load_robot(name: str):
    from rc3r.robots.pinocchio import NAMED, PinocchioRobot

    if name == "rr3":
        from rc3r.robots.rr3.urdf import REPO_URDF

        return PinocchioRobot.from_urdf(REPO_URDF, robot_name="rr3")
    if name in NAMED:
        return PinocchioRobot.named(name)
    if Path(name).suffix.lower() == ".urdf" or Path(name).is_file():
        return PinocchioRobot.from_urdf(name)
    die(f"--robot {name!r}: not rr3, one of {', '.join(NAMED)}, or a URDF file")


def model_text(model) -> tuple[str, list[str]]:
    """``model`` as the text of pin_cpp_bench.cpp (module docstring); also the joint codes."""
    from rc3r.robots.generated import chain_constants

    if model.njoints < 2:
        die("the model has no moving joint")
    chain = chain_constants(model)  # refuses non-1-DoF and helical joints; gives the unit axes
    g = model.gravity
    if np.any(np.asarray(g.angular) != 0):
        die("model.gravity has an angular part; pin_cpp_bench.cpp sets only the linear one")
    lines, codes = [" ".join(repr(float(x)) for x in g.linear)], []
    for j in range(1, model.njoints):
        short = model.joints[j].shortname()
        code = JOINT_CODES.get(short)
        if code is None:
            die(f"joint {j} '{model.names[j]}' is {short}; pin_cpp_bench.cpp handles "
                + ", ".join(JOINT_CODES))
        P, inertia = model.jointPlacements[j], model.inertias[j]
        vals = [*chain.axis[j - 1], *P.rotation.ravel(), *P.translation, inertia.mass, *inertia.lever,
                *inertia.inertia.ravel()]
        lines.append(" ".join([code, str(int(model.parents[j]))] + [repr(float(v)) for v in vals]))
        codes.append(code)
    return "\n".join(lines) + "\n", codes


def compiler_version(cxx: str) -> str:
    p = subprocess.run([cxx, "--version"], capture_output=True, text=True)
    return (p.stdout.splitlines() or ["?"])[0].strip()


def compile_cmd(build: str, eigen: Path, prefix: Path, out: Path, cxx: str) -> list[str]:
    cmd = [cxx, "-std=c++17", "-O3", "-DNDEBUG", *DEFINES, f"-I{prefix / 'include'}",
           f"-I{prefix / 'include' / 'pinocchio' / 'deprecated'}", f"-I{eigen}", str(SOURCE), "-o", str(out),
           f"-Wl,-rpath,{prefix / 'lib'}"]
    if build == "library":
        cmd += ["-DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION", f"-L{prefix / 'lib'}", "-lpinocchio_default"]
    else:
        cmd += ["-march=native"]
    return cmd


def cache_root() -> Path:
    base = os.environ.get("RC3R_CACHE_DIR")
    return Path(base) / "cpp-bench" if base else Path.home() / ".cache" / "rc3r" / "cpp-bench"


def build_program(build: str, eigen: Path, prefix: Path, cxx: str, tmp: Path, use_cache: bool) -> tuple[Path, float, bool]:
    """The compiled program of ``build``: (path, compile seconds, from the cache)."""
    placeholder = Path("@OUT@")
    cmd = compile_cmd(build, eigen, prefix, placeholder, cxx)
    key = hashlib.sha256("\0".join([SOURCE.read_text(), *cmd, compiler_version(cxx)]).encode()).hexdigest()[:24]
    final = (cache_root() / f"{build}-{key}" / "pin_cpp_bench") if use_cache else tmp / f"pin_cpp_bench_{build}"
    if final.is_file() and os.access(final, os.X_OK):
        return final, 0.0, True
    final.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{build}-", dir=final.parent))
    exe = work / "pin_cpp_bench"
    cmd = [str(exe) if c == str(placeholder) else c for c in cmd]
    print(f"cpp_pinocchio: compiling the {build} build (library ~20 s, headers ~4 min) ...", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if p.returncode != 0:
        shutil.rmtree(work, ignore_errors=True)
        errs = [ln for ln in p.stderr.splitlines() if "error" in ln][:5]
        die(f"compilation of the {build} build failed:\n  " + " ".join(cmd) + "\n"
            + "\n".join(errs or p.stderr.splitlines()[-5:]))
    os.replace(exe, final)
    shutil.rmtree(work, ignore_errors=True)
    return final, seconds, False


def library_resolved(exe: Path) -> dict:
    """Whether rnea/aba/crba are undefined symbols of ``exe`` (i.e. taken from libpinocchio_default)."""
    if shutil.which("nm") is None:
        return {}
    p = subprocess.run(["nm", "-C", "-u", str(exe)], capture_output=True, text=True)
    und = [ln for ln in p.stdout.splitlines() if "pinocchio::" in ln]
    return {f: any(f"pinocchio::{f}<" in ln or f"pinocchio::impl::{f}<" in ln for ln in und)
            for f in ("rnea", "aba", "crba")}


def median_per_state(fn, count: int, repeats: int) -> tuple[float, float]:
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times) / count, min(times) / count


def rel_err(x: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    d = float(np.max(np.abs(x - ref)))
    return d, d / max(1.0, float(np.max(np.abs(ref))))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="rr3", help="rr3 (default), ur5, panda or a URDF path")
    ap.add_argument("--build", choices=("both", *BUILDS), default="both")
    ap.add_argument("--eigen", help="directory containing Eigen/ (default: search)")
    ap.add_argument("--cxx", default=os.environ.get("CXX", "c++"))
    ap.add_argument("-n", type=int, default=100_000, help="states (default 100000)")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-generated", action="store_true", help="do not time rc3r.robots.generated")
    ap.add_argument("--no-cache", action="store_true", help="compile into a temporary directory")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if args.n < 1 or args.repeats < 1:
        die("-n and --repeats must be >= 1")
    if shutil.which(args.cxx) is None:
        die(f"C++ compiler {args.cxx!r} not found")
    import pinocchio as pin

    prefix = cmeel_prefix()
    eigen = find_eigen(args.eigen, prefix)
    robot = load_robot(args.robot)
    model = robot.model
    data = model.createData()
    nv, N, R = model.nv, args.n, args.repeats
    if model.nq != nv:
        die(f"nq = {model.nq} != nv = {nv}: only 1-DoF revolute/prismatic joints")
    text, codes = model_text(model)
    rng = np.random.default_rng(args.seed)
    Q = rng.uniform(-np.pi, np.pi, (N, nv))
    QD, QDD = rng.uniform(-5.0, 5.0, (2, N, nv))
    U = rng.uniform(-50.0, 50.0, (N, nv))
    builds = BUILDS if args.build == "both" else (args.build,)

    # Pinocchio from Python: the reference of every check (first m states)
    m = min(N, 1000)
    ref_tau = np.array([pin.rnea(model, data, q, v, a) for q, v, a in zip(Q[:m], QD[:m], QDD[:m])])
    ref_qdd = np.array([pin.aba(model, data, q, v, u) for q, v, u in zip(Q[:m], QD[:m], U[:m])])

    res = {"date": datetime.date.today().isoformat(), "robot": args.robot, "urdf": robot.urdf, "nv": nv,
           "joints": codes, "n_states": N, "repeats": R, "seed": args.seed, "pinocchio": pin.__version__,
           "python": platform.python_version(), "compiler": compiler_version(args.cxx), "eigen": str(eigen),
           "cpp": {}, "checks": {}}
    ok = True
    tau_cpp = None
    with tempfile.TemporaryDirectory(prefix="rc3r-cpp-") as tmp:
        tmp = Path(tmp)
        (tmp / "arm.model").write_text(text)
        with open(tmp / "states.bin", "wb") as f:
            for X in (Q, QD, QDD, U):
                f.write(np.ascontiguousarray(X, dtype=np.float64).tobytes())
        for build in builds:
            exe, compile_s, cached = build_program(build, eigen, prefix, args.cxx, tmp, not args.no_cache)
            print(f"cpp_pinocchio: running the {build} build ...", file=sys.stderr, flush=True)
            out = tmp / f"out_{build}.bin"
            p = subprocess.run([str(exe), str(tmp / "arm.model"), str(tmp / "states.bin"), str(N), str(R), str(out)],
                               capture_output=True, text=True)
            if p.returncode != 0:
                die(f"the C++ benchmark ({build} build) failed (exit {p.returncode}): "
                    f"{(p.stderr or p.stdout).strip()[-2000:]}")
            cpp = json.loads(p.stdout.strip().splitlines()[-1])
            if cpp["nv"] != nv or cpp["njoints"] != model.njoints:
                die(f"the C++ model has nv={cpp['nv']}, njoints={cpp['njoints']}; Python's {nv}, {model.njoints}")
            raw = np.fromfile(out, dtype=np.float64)
            k = cpp["crba_checked"]
            if raw.size != 2 * N * nv + k * nv * nv:
                die(f"{out.name}: {raw.size} doubles, expected {2 * N * nv + k * nv * nv}")
            tau = raw[:N * nv].reshape(N, nv)
            qdd = raw[N * nv:2 * N * nv].reshape(N, nv)
            M = raw[2 * N * nv:].reshape(k, nv, nv)
            ref_M = np.array([np.triu(pin.crba(model, data, q)) for q in Q[:k]])
            checks = {"rnea": rel_err(tau[:m], ref_tau), "aba": rel_err(qdd[:m], ref_qdd),
                      "crba": rel_err(np.triu(M), ref_M)}
            res["checks"][f"cpp_{build}_vs_python"] = {f: {"max_abs": a, "rel": r} for f, (a, r) in checks.items()}
            ok &= all(r <= TOL for _, r in checks.values())
            cpp.update(compile_s=compile_s, cached=cached, program=str(exe),
                       flags=compile_cmd(build, eigen, prefix, Path("pin_cpp_bench"), args.cxx)[1:])
            if build == "library":
                cpp["library_resolved"] = library_resolved(exe)
            res["cpp"][build] = cpp
            if tau_cpp is None:  # the first build's (library's, if run) torques: compared with the generated
                tau_cpp = tau

    gen = None
    if not args.no_generated:
        try:
            from rc3r.robots.generated import GeneratedKernels

            t0 = time.perf_counter()
            kern = GeneratedKernels.for_robot(robot)
            load_s = time.perf_counter() - t0
            g_tau = kern.rnea(Q, QD, QDD)
            gen = {"load_s": load_s, "generate_s": kern.generate_seconds, "compile_s": kern.compile_seconds,
                   "flags": list(kern.meta["flags"])}
            for f, call in (("rnea", lambda: kern.rnea(Q, QD, QDD)), ("aba", lambda: kern.aba(Q, QD, U)),
                            ("crba", lambda: kern.mass(Q))):
                gen[f"{f}_median_s"], gen[f"{f}_min_s"] = median_per_state(call, N, R)
            g_checks = {"rnea_vs_python": rel_err(g_tau[:m], ref_tau),
                        f"rnea_vs_cpp_{builds[0]}_all_states": rel_err(g_tau, tau_cpp),
                        "aba_vs_python": rel_err(kern.aba(Q[:m], QD[:m], U[:m]), ref_qdd)}
            res["checks"]["generated"] = {f: {"max_abs": a, "rel": r} for f, (a, r) in g_checks.items()}
            ok &= all(r <= TOL for _, r in g_checks.values())
        except Exception as exc:  # a missing casadi / C compiler: report, keep the C++ numbers
            gen = {"unavailable": f"{type(exc).__name__}: {exc}"}
    res["generated"] = gen
    best = min(res["cpp"].values(), key=lambda c: c["rnea_median_s"])
    best_name = next(b for b, c in res["cpp"].items() if c is best)
    if gen and "rnea_median_s" in gen:
        ratio = gen["rnea_median_s"] / best["rnea_median_s"]
        res["target_generated_tau_vs_cpp_rnea"] = {"ratio": ratio, "against": best_name, "met": ratio <= 1.0}
    res["checks_ok"] = bool(ok)

    if args.json:
        print(json.dumps(res, indent=2))
    else:
        ns = 1e9
        print(f"# Pinocchio C++ (measured in C++) vs generated kernels, {res['date']}, robot {args.robot} "
              f"(nv={nv}, joints {' '.join(codes)}), {N} states (seed {args.seed}), median (min) of {R} passes "
              f"per state; pin {pin.__version__}, python {res['python']}, {res['compiler']}, Eigen {eigen}")
        for b, c in res["cpp"].items():
            how = "cached" if c["cached"] else f"compiled in {c['compile_s']:.1f} s"
            extra = ""
            if b == "library":
                lr = c.get("library_resolved") or {}
                extra = ("; rnea/aba/crba from libpinocchio_default: "
                         + ("yes" if lr and all(lr.values()) else f"NO {lr}" if lr else "unknown (no nm)"))
                desc = "libpinocchio_default, -O3 (no -march=native)"
            else:
                desc = "templates in the program, -O3 -march=native"
            print(f"C++ {b:8s}: {desc}, {how}{extra}")
        if gen and "rnea_median_s" in gen:
            how = "cached" if gen["compile_s"] == 0 else f"generated {gen['generate_s']:.2f} s + compiled {gen['compile_s']:.2f} s"
            print(f"generated : rc3r.robots.generated, {' '.join(gen['flags'])}, {how}; one batch call per pass "
                  f"from Python (aba = CRBA + Cholesky, crba = mass)")
        elif gen:
            print(f"generated : unavailable ({gen['unavailable']})")
        for name, ch in res["checks"].items():
            print(f"check {name}: " + ", ".join(f"{f} max |diff| {v['max_abs']:.1e} (rel {v['rel']:.1e})"
                                               for f, v in ch.items()))
        print()
        cols = [f"C++ {b}" for b in res["cpp"]] + (["generated"] if gen and "rnea_median_s" in gen else [])
        head = f"{'per state':10s}" + "".join(f"{c:>24s}" for c in cols)
        if "generated" in cols:
            head += "".join(f"{'gen/' + b:>14s}" for b in res["cpp"])
        print(head)
        for f in ("rnea", "aba", "crba"):
            srcs = list(res["cpp"].values()) + ([gen] if "generated" in cols else [])
            line = f"{f:10s}" + "".join(f"{s[f + '_median_s'] * ns:13.1f} ns ({s[f + '_min_s'] * ns:6.1f})"
                                        for s in srcs)
            if "generated" in cols:
                line += "".join(f"{gen[f + '_median_s'] / c[f + '_median_s']:13.2f}x" for c in res["cpp"].values())
            print(line)
        print()
        t = res.get("target_generated_tau_vs_cpp_rnea")
        if t:
            print(f"target generated_tau_vs_cpp_rnea: <= 1x: {t['ratio']:.2f} -> {'met' if t['met'] else 'NOT MET'} "
                  f"(generated rnea / C++ {t['against']} rnea, the fastest C++ build measured)")
        else:
            print("target generated_tau_vs_cpp_rnea: <= 1x: not measured (no generated kernel)")
    if not ok:
        print(f"cpp_pinocchio: CHECK FAILED: a relative difference exceeds {TOL:g} (see the check lines)",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
