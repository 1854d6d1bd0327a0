#!/usr/bin/env python
"""Pinocchio's own C++ cost of rnea/aba/crba on the rc3r arm, vs the closed form (optional).

``rc3r bench`` can only *estimate* Pinocchio's C++ time from Python. This script
measures it: it writes the arm (from ``rc3r.urdf.load_arm``) to a plain text file,
compiles ``benchmarks/cpp/pin_cpp_bench.cpp`` against the Pinocchio that the
``pin`` wheel installed (headers and ``libpinocchio_default`` in its cmeel prefix),
runs it, checks its torque against ``pinocchio.rnea`` from Python, and times the
closed form on the same number of states in this process.

Needs a C++17 compiler and the Eigen headers, which the ``pin`` wheel does not
ship: pass ``--eigen DIR`` (the directory that contains ``Eigen/``), e.g. after
``apt-get install libeigen3-dev`` (``/usr/include/eigen3``, found automatically)
or ``pip download cmeel-eigen --no-deps`` and unzipping the wheel
(``<dir>/cmeel.prefix/include/eigen3``). Compiling takes 1-2 minutes.

Two builds (``--build``):

* ``library`` (default) -- calls the precompiled ``libpinocchio_default``
  (``PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION``), i.e. the C++ code the Python
  bindings run. Compiled without ``-march=native``: the library's Eigen alignment
  must match (with AVX flags the program aborts with ``boost::bad_get``).
* ``headers`` -- Pinocchio's templates compiled into the program with
  ``-O3 -march=native``: the best case of Pinocchio on this machine.

Usage: ``python benchmarks/cpp_pinocchio.py [--eigen DIR] [--build library|headers] [-n N] [--repeats R] [--json]``
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
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


def cmeel_prefix() -> Path:
    import pinocchio

    for parent in Path(pinocchio.__file__).resolve().parents:
        if parent.name == "cmeel.prefix":
            return parent
    p = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix"
    if p.is_dir():
        return p
    sys.exit("cpp_pinocchio: cannot find the cmeel prefix of the pin wheel (headers, libpinocchio_default)")


def find_eigen(arg: str | None, prefix: Path) -> Path:
    candidates = [arg, os.environ.get("EIGEN_INCLUDE_DIR"), prefix / "include" / "eigen3", "/usr/include/eigen3",
                  "/usr/local/include/eigen3"]
    for c in candidates:
        if c and (Path(c) / "Eigen" / "Core").is_file():
            return Path(c)
    sys.exit("cpp_pinocchio: Eigen headers not found; pass --eigen DIR (the directory containing Eigen/), "
             "e.g. after `apt-get install libeigen3-dev`")


def write_model(path: Path):
    """The arm as text for pin_cpp_bench.cpp; returns the loaded arm."""
    from rc3r.urdf import load_arm

    arm = load_arm(None)
    m = arm.model
    lines = [repr(float(-m.gravity.linear[2]))]
    for j in range(1, m.njoints):
        if m.joints[j].shortname() != "JointModelRZ":
            sys.exit(f"cpp_pinocchio: joint {j} is {m.joints[j].shortname()}, the C++ side assumes JointModelRZ")
        P, inertia = m.jointPlacements[j], m.inertias[j]
        vals = [*P.rotation.ravel(), *P.translation, inertia.mass, *inertia.lever, *inertia.inertia.ravel()]
        lines.append(" ".join([str(m.parents[j])] + [repr(float(v)) for v in vals]))
    path.write_text("\n".join(lines) + "\n")
    return arm


def compile_bench(build: str, eigen: Path, prefix: Path, out: Path, cxx: str) -> float:
    cmd = [cxx, "-std=c++17", "-O3", "-DNDEBUG", *DEFINES, f"-I{prefix / 'include'}",
           f"-I{prefix / 'include' / 'pinocchio' / 'deprecated'}", f"-I{eigen}", str(SOURCE), "-o", str(out),
           f"-Wl,-rpath,{prefix / 'lib'}"]
    if build == "library":
        cmd += ["-DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION", f"-L{prefix / 'lib'}", "-lpinocchio_default"]
    else:
        cmd += ["-march=native"]
    print(f"cpp_pinocchio: compiling ({build} build, 1-2 min) ...", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        errs = [ln for ln in p.stderr.splitlines() if "error" in ln][:5]
        sys.exit("cpp_pinocchio: compilation failed:\n" + "\n".join(errs or p.stderr.splitlines()[-5:]))
    return time.perf_counter() - t0


def closed_form_times(arm, n: int, repeats: int) -> dict:
    """Per-state time of the closed form on n states (same draws as rc3r bench)."""
    from rc3r import _kernels as K
    from rc3r import bench
    from rc3r.params import theta

    th = theta(arm.params)
    l2, g0 = float(arm.params.lengths[1]), float(arm.params.g0)
    S = bench._states(n, np.random.default_rng(bench._SEED))
    out = np.empty((n, 3))
    med, mn = bench._time(lambda: K.inverse_dynamics_batch(th, S["Q"], S["QD"], S["QDD"], l2, g0, out), repeats)
    w = np.empty((n, 3))
    med_fd, mn_fd = bench._time(lambda: bench._forward_dynamics_in_loop(th, S["Q"], S["QD"], S["U"], l2, g0, w),
                                repeats)
    return {"tau_median_s": med / n, "tau_min_s": mn / n, "fd_median_s": med_fd / n, "fd_min_s": mn_fd / n}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--eigen", help="directory containing Eigen/ (default: search)")
    ap.add_argument("--build", choices=("library", "headers"), default="library")
    ap.add_argument("--cxx", default=os.environ.get("CXX", "c++"))
    ap.add_argument("-n", type=int, default=100_000, help="states (default 100000)")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if shutil.which(args.cxx) is None:
        sys.exit(f"cpp_pinocchio: C++ compiler {args.cxx!r} not found")
    import pinocchio as pin

    prefix = cmeel_prefix()
    eigen = find_eigen(args.eigen, prefix)
    with tempfile.TemporaryDirectory(prefix="rc3r-cpp-") as tmp:
        tmp = Path(tmp)
        arm = write_model(tmp / "rr3.model")
        compile_s = compile_bench(args.build, eigen, prefix, tmp / "pin_cpp_bench", args.cxx)
        print("cpp_pinocchio: running ...", file=sys.stderr, flush=True)
        p = subprocess.run([str(tmp / "pin_cpp_bench"), str(tmp / "rr3.model"), str(args.n), str(args.repeats)],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"cpp_pinocchio: the C++ benchmark failed: {p.stderr.strip()}")
        cpp = json.loads(p.stdout.strip().splitlines()[-1])
    tau_py = np.array(pin.rnea(arm.model, arm.model.createData(), np.array([0.3, -0.7, 1.1]),
                               np.array([0.5, -1.5, 2.0]), np.array([-3.0, 4.0, 1.0])))
    err = float(np.max(np.abs(np.array(cpp["tau_check"]) - tau_py)))
    cf = closed_form_times(arm, args.n, args.repeats)
    res = {"build": args.build, "compile_s": compile_s, "pinocchio": pin.__version__, "cpp": cpp,
           "tau_check_max_abs_err_vs_python": err, "closed_form": cf,
           "ratio_cpp_rnea_to_closed_form_tau": cpp["rnea_median_s"] / cf["tau_median_s"],
           "ratio_cpp_aba_to_closed_form_fd": cpp["aba_median_s"] / cf["fd_median_s"]}
    if args.json:
        print(json.dumps(res, indent=2))
    else:
        ns = 1e9
        print(f"Pinocchio {pin.__version__} C++ ({args.build} build), N = {args.n}, {args.repeats} repeats, "
              f"median (min) per call:")
        print(f"  rnea {cpp['rnea_median_s'] * ns:7.1f} ns ({cpp['rnea_min_s'] * ns:.1f})   "
              f"closed-form tau {cf['tau_median_s'] * ns:6.1f} ns ({cf['tau_min_s'] * ns:.1f})   "
              f"ratio {res['ratio_cpp_rnea_to_closed_form_tau']:.2f}x")
        print(f"  aba  {cpp['aba_median_s'] * ns:7.1f} ns ({cpp['aba_min_s'] * ns:.1f})   "
              f"closed-form qdd {cf['fd_median_s'] * ns:6.1f} ns ({cf['fd_min_s'] * ns:.1f})   "
              f"ratio {res['ratio_cpp_aba_to_closed_form_fd']:.2f}x")
        print(f"  crba {cpp['crba_median_s'] * ns:7.1f} ns ({cpp['crba_min_s'] * ns:.1f})")
        print(f"  C++ tau vs pinocchio.rnea from Python at a fixed state: max |diff| = {err:.2e}")
    return 0 if err < 1e-9 else 1


if __name__ == "__main__":
    sys.exit(main())
