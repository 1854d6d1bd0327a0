"""Mutation testing of rc3r's core modules with cosmic-ray: how many deliberately broken
versions of the code does the test suite notice?

Usage (from the repository root, after ``pip install -e ".[test,mutation]"``)::

    python tests/mutation/run.py                 # every group, ~1 h on 2 cores
    python tests/mutation/run.py metrics bounds  # some groups
    python tests/mutation/run.py --jobs 1        # one group at a time
    python tests/mutation/run.py simulate --retest   # the last session's survivors, current tests
    python tests/mutation/run.py campaigns --skip-tests tests/test_campaign_mutants.py  # without a file

For each group (a set of modules and the tests that cover them, :data:`GROUPS`) it copies
``src/``, ``tests/``, ``urdf/`` and ``pyproject.toml`` into ``out/mutation/<group>/``
(the checkout is never mutated, so an interrupted run cannot leave a broken source file
behind), writes a cosmic-ray config there, and runs ``cosmic-ray init``, the operator
filter (:data:`EXCLUDED_OPERATORS`), the ``# pragma: no mutate`` filter, ``cosmic-ray
baseline`` (the unmutated code must pass) and ``cosmic-ray exec``. The tests run with
``NUMBA_DISABLE_JIT=1``: the compiled kernels then execute as the plain Python they are
written in, so a mutant costs a test run (seconds) instead of a numba compilation
(~20 s), and the mutated source is exactly what runs.

Score = killed / (killed + survived); a timeout counts as killed (cosmic-ray's rule; the
mutant made the tests hang). ``out/mutation/summary.json`` holds the counts per group and
every survivor (file, line, operator, the mutated line), ``out/mutation/survivors.md``
the same for reading. ``docs/testing.md`` reports the score and which survivors were
judged equivalent (no test can tell them from the original, e.g. a changed tolerance
factor ``1 + 1e-12``).
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import json
import os
import shutil
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

from rc3r.io import atomic_write_json, atomic_write_text

REPO = Path(__file__).resolve().parents[2]
PY = sys.executable
BIN = Path(PY).parent

#: group -> (modules to mutate, pytest node ids that cover them). Each group's tests are the
#: ones written against an independent source for those modules (Pinocchio, hand values).
GROUPS = {
    "model": (
        ["src/rc3r/robots/rr3/kernels.py", "src/rc3r/robots/rr3/model.py", "src/rc3r/robots/rr3/regressor.py",
         "src/rc3r/robots/rr3/params.py"],
        ["tests/test_rr3_regressor.py::test_Y_theta_equals_rnea", "tests/test_rr3_model.py",
         "tests/test_rr3_regressor.py", "tests/test_rr3_params.py",
         "tests/test_rr3_robot.py::test_forward_dynamics_equals_aba"],
    ),
    "controllers": (
        ["src/rc3r/controllers/base.py", "src/rc3r/controllers/_kernels.py", "src/rc3r/controllers/fbl.py",
         "src/rc3r/controllers/pd.py", "src/rc3r/controllers/pd_gains.py", "src/rc3r/controllers/sliding.py",
         "src/rc3r/controllers/robust.py", "src/rc3r/controllers/robust_coeff.py",
         "src/rc3r/controllers/adaptive.py", "src/rc3r/controllers/guarantee.py"],
        ["tests/test_controllers.py", "tests/test_guarantee.py"],
    ),
    "metrics": (
        ["src/rc3r/simulate/metrics.py"],
        ["tests/test_metrics.py"],
    ),
    "bounds": (
        ["src/rc3r/uncertainty/bounds.py"],
        ["tests/test_uncertainty.py", "tests/test_payload.py"],
    ),
    # the simulators' verdicts and the plant effects: the by-hand tests (no long simulation runs
    # with NUMBA_DISABLE_JIT=1) and the python engine's loop effects against recomputed torques
    "plants": (
        ["src/rc3r/simulate/verdict.py", "src/rc3r/plants/base.py", "src/rc3r/plants/friction.py",
         "src/rc3r/plants/saturation.py", "src/rc3r/plants/limits.py", "src/rc3r/plants/loop.py"],
        ["tests/test_verdict.py::test_alternating_torque_chatters_and_a_sine_does_not",
         "tests/test_verdict.py::test_saturation_fraction_by_hand", "tests/test_verdict.py::test_order_and_tolerance",
         "tests/test_plants.py::test_friction_torque_by_hand", "tests/test_plants.py::test_saturation_and_plant_torque_by_hand",
         "tests/test_plants.py::test_effects_from_the_urdf_text", "tests/test_plants.py::test_friction_ranges_drawn_per_plant_and_seeded",
         "tests/test_plants.py::test_noise_is_seeded", "tests/test_plants.py::test_limit_crossings_by_hand",
         "tests/test_plants.py::test_urdf_without_friction_is_refused_in_one_line",
         "tests/test_plants.py::test_loop_effects_against_recomputed_torques[python]",
         "tests/test_plants.py::test_initial_error_and_continuous_refusal"],
    ),
    # the simulation path in Python: the options, the loop, the python/reference engines, the status
    # check and the engine registry, against the tests that run them (python/reference engines,
    # by-hand bounds and stops; with NUMBA_DISABLE_JIT=1 the compiled engine is left out: its kernels
    # are compared with the reference engine by tests/test_simulate.py and tests/test_engines.py)
    "simulate": (
        ["src/rc3r/simulate/__init__.py", "src/rc3r/simulate/_python.py", "src/rc3r/simulate/status.py",
         "src/rc3r/simulate/engines/base.py"],
        ["tests/test_simulate_mutants.py", "tests/test_simulate_faults.py::test_python_engine_budget",
         "tests/test_simulate_faults.py::test_nan_torque_is_a_divergence_not_an_exception",
         "tests/test_simulate_faults.py::test_run_stops_at_the_first_sample_past_its_bound",
         "tests/test_simulate_faults.py::test_step_underflow_exit_fires_at_its_threshold",
         "tests/test_simulate_faults.py::test_a_signal_lost_inside_numba_still_stops_the_run",
         "tests/test_simulate.py::test_bad_options", "tests/test_simulate.py::test_bad_initial_state",
         "tests/test_simulate.py::test_continuous_divergence_detected",
         "tests/test_simulate.py::test_quintic_trajectory_from_rest",
         "tests/test_engines.py::test_engine_names_aliases_and_registry",
         "tests/test_plants.py::test_loop_effects_against_recomputed_torques[python]",
         "tests/test_plants.py::test_initial_error_and_continuous_refusal"],
    ),
    # the campaigns: jobs and their rows, the append-only table and its recovery, the local pool's
    # worker set-up, the classification and maps; not the Dask paths (a cluster per mutant) nor the
    # @pytest.mark.slow interrupt tests. test_a_row_is_the_run_of_its_recorded_seed is the one that
    # simulates (two 0.5 s runs and one `rc3r run`, ~15 s with NUMBA_DISABLE_JIT=1)
    "campaigns": (
        ["src/rc3r/campaign/runner.py", "src/rc3r/campaign/jobs.py", "src/rc3r/campaign/studies.py"],
        ["tests/test_campaign_mutants.py", "tests/test_campaign.py::test_plant_seeds_are_fixed_distinct_and_63_bit",
         "tests/test_campaign.py::test_job_ids_are_unique_per_plant_controller_eps_rate_and_tag",
         "tests/test_campaign.py::test_table_appends_whole_lines_and_resume_cuts_a_torn_line",
         "tests/test_campaign.py::test_table_refuses_to_mix_campaigns", "tests/test_campaign.py::test_classify",
         "tests/test_campaign.py::test_rate_map_worst_class_and_safe_rate_by_hand",
         "tests/test_campaign.py::test_rate_map_takes_a_per_joint_K",
         "tests/test_campaign.py::test_error_bound_by_hand",
         "tests/test_campaign.py::test_a_continuous_job_runs_in_continuous_time_whatever_the_config_says",
         "tests/test_campaign_faults.py::test_a_short_row_ending_in_a_newline_is_dropped_and_run_again",
         "tests/test_campaign_faults.py::test_a_worker_asks_the_kernel_for_sigkill_at_its_parents_death",
         "tests/test_campaign_faults.py::test_a_worker_exits_within_the_poll_period_when_its_parent_dies_without_prctl",
         "tests/test_campaign.py::test_a_row_is_the_run_of_its_recorded_seed"],
    ),
}

#: Fraction of each group's mutants that a default run tests (a seeded sample, the rest are
#: marked "not sampled"): a full run of the model group (~1,400 mutants at ~4 s on a shared
#: 2-core machine) takes hours; a uniform sample estimates the same score with a binomial
#: standard error (printed). ``--sample 1`` tests every mutant.
SAMPLE = {"model": 0.2, "controllers": 1.0, "metrics": 1.0, "bounds": 0.3, "plants": 0.4, "simulate": 0.12,
          "campaigns": 0.08}

#: Mutants that a review of the suite found it did not notice (issue: "tests that fail when the
#: code is wrong"), applied by hand with ``--named``: each must make its group's tests fail.
#: (group, what, file, original text, mutated text)
NAMED = [
    ("controllers", "adaptive law ignores Gamma", "src/rc3r/controllers/adaptive.py",
     "zdot[j] = -cp[g + j] * th_eff[j]", "zdot[j] = -th_eff[j]"),
    ("metrics", "rms computed as a root sum of squares", "src/rc3r/simulate/metrics.py",
     "np.sqrt((e ** 2).mean(axis=0))", "np.sqrt((e ** 2).sum(axis=0))"),
    ("metrics", "chattering on the decimated stored grid in sampled mode", "src/rc3r/simulate/metrics.py",
     "if res.tv_exact is not None:", "if False:"),
    ("metrics", "final-error window of the last 0.5 s", "src/rc3r/simulate/metrics.py",
     "res.t >= res.t[-1] - 1.0", "res.t >= res.t[-1] - 0.5"),
    ("metrics", "final-error window open at its start", "src/rc3r/simulate/metrics.py",
     "res.t >= res.t[-1] - 1.0", "res.t > res.t[-1] - 1.0"),
    ("model", "gravity constant 9.8 instead of 9.81", "src/rc3r/robots/rr3/params.py",
     "G0 = 9.81", "G0 = 9.8"),
    ("model", "gravity term drops l2", "src/rc3r/robots/rr3/kernels.py",
     "th[5] * s23) / l2", "th[5] * s23)"),
    ("controllers", "robust law uses min(||xi||, eps)", "src/rc3r/controllers/robust.py",
     "scale = cp[at(_RHO, n, p)] / max(nrm, cp[at(_EPS, n, p)])", "scale = cp[at(_RHO, n, p)] / min(nrm, cp[at(_EPS, n, p)])"),
    ("bounds", "paper rho as the largest coefficient deviation, not the norm", "src/rc3r/uncertainty/bounds.py",
     "rho=float(np.linalg.norm(th0 - th)),", "rho=float(np.max(np.abs(th0 - th))),"),
]

#: Operators left out, and why: bitwise/shift/modulo/floor-division replacements of float
#: arithmetic only raise TypeError (caught by any test that runs the line, they inflate the
#: score); removing a decorator removes ``@njit`` (equivalent with NUMBA_DISABLE_JIT) or
#: ``@dataclass`` (caught at import); the variable inserter/replacer draw at random (not
#: reproducible). What stays: + <-> -, * <-> /, + -> *, ** -> *, every comparison swap,
#: unary operators, numbers (+1 / -1), True/False, and/or, ``not`` added to conditions,
#: loops that run zero times, break/continue, exception types.
EXCLUDED_OPERATORS = [
    r"core/ReplaceBinaryOperator_\w+_(FloorDiv|Mod|RShift|LShift|BitOr|BitAnd|BitXor)$",
    r"core/ReplaceBinaryOperator_(FloorDiv|Mod|RShift|LShift|BitOr|BitAnd|BitXor)_\w+$",
    r"core/ReplaceBinaryOperator_(Add_Div|Add_Pow|Sub_Mul|Sub_Div|Sub_Pow|Mul_Sub|Mul_Pow|Div_Add|Div_Sub|Div_Pow|Pow_Add|Pow_Sub|Pow_Div)$",
    r"core/RemoveDecorator",
    r"core/VariableInserter",
    r"core/VariableReplacer",
]

TIMEOUT_S = 120.0


#: Test files or node ids left out of every group's test command by ``--skip-tests`` (e.g. a
#: first pass of the suite as it was before a group's ``test_*_mutants.py`` was written).
SKIP_TESTS: set = set()


def _tests(group: str) -> list[str]:
    return [t for t in GROUPS[group][1] if t not in SKIP_TESTS and t.split("::")[0] not in SKIP_TESTS]


def _config(group: str) -> str:
    modules, _ = GROUPS[group]
    tests = _tests(group)
    mods = ", ".join(f'"{m}"' for m in modules)
    excl = ", ".join(f"'{e}'" for e in EXCLUDED_OPERATORS)
    cmd = f"{PY} -m pytest -x -q -p no:cacheprovider " + " ".join(tests)
    return (f'[cosmic-ray]\nmodule-path = [{mods}]\ntimeout = {TIMEOUT_S}\nexcluded-modules = []\n'
            f'test-command = "{cmd}"\n\n[cosmic-ray.distributor]\nname = "local"\n\n'
            f'[cosmic-ray.filters.operators-filter]\nexclude-operators = [{excl}]\n')


def _copy_tree(dest: Path) -> None:
    if dest.exists():
        shutil.rmtree(dest)
    dest.mkdir(parents=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc", ".hypothesis")
    for name in ("src", "tests", "urdf"):
        shutil.copytree(REPO / name, dest / name, ignore=ignore)
    shutil.copy2(REPO / "pyproject.toml", dest / "pyproject.toml")


def _env(work: Path) -> dict:
    """The tests' environment: the copy's sources, kernels as plain Python, no display, fixed hashing."""
    return dict(os.environ, NUMBA_DISABLE_JIT="1", PYTHONPATH=str(work / "src"), MPLBACKEND="Agg",
                PYTHONHASHSEED="0")


def _run(cmd, cwd, env, log):
    with open(log, "a") as fh:
        fh.write(f"$ {' '.join(map(str, cmd))}\n")
        fh.flush()
        p = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, stdout=fh, stderr=subprocess.STDOUT)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd[:2]))} failed (exit {p.returncode}); see {log}")


NOT_SAMPLED = "not sampled"


def _sample(db: Path, fraction: float, seed: int) -> int:
    """Keep a seeded uniform sample of ``fraction`` of the pending mutants; mark the rest skipped."""
    import random

    from cosmic_ray.work_db import use_db
    from cosmic_ray.work_item import WorkerOutcome, WorkResult

    with use_db(str(db)) as wdb:
        ids = sorted(item.job_id for item in wdb.pending_work_items)
        keep = set(random.Random(seed).sample(ids, round(fraction * len(ids)))) if fraction < 1 else set(ids)
        for job in ids:
            if job not in keep:
                wdb.set_result(job, WorkResult(output=NOT_SAMPLED, worker_outcome=WorkerOutcome.SKIPPED))
    return len(keep)


def run_named(root: Path) -> list[dict]:
    """Apply each of :data:`NAMED` to a fresh copy and run its group's tests: each must fail."""
    out = []
    for group, what, path, old, new in NAMED:
        work = root / "named"
        _copy_tree(work)
        text = (work / path).read_text()
        if old not in text:
            raise RuntimeError(f"named mutant {what!r}: {old!r} not found in {path}")
        (work / path).write_text(text.replace(old, new, 1))
        p = subprocess.run([PY, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *GROUPS[group][1]],
                           cwd=work, env=_env(work), capture_output=True, text=True)
        failed = [ln.split(" ")[1] for ln in p.stdout.splitlines() if ln.startswith("FAILED ")]
        out.append({"group": group, "mutant": what, "file": path, "killed": p.returncode != 0,
                    "by": failed[0] if failed else None})
        print(f"{'killed  ' if p.returncode else 'SURVIVED'} {what}  ({failed[0] if failed else '-'})", flush=True)
    return out


def _line(path: Path, lineno: int) -> str:
    try:
        return path.read_text().splitlines()[lineno - 1].strip()
    except (OSError, IndexError):
        return "?"


def run_group(group: str, root: Path, fraction: float, seed: int) -> dict:
    work = root / group
    _copy_tree(work)
    (work / "cosmic-ray.toml").write_text(_config(group))
    env = _env(work)
    log = work / "cosmic-ray.log"
    t0 = time.perf_counter()
    db = work / "session.sqlite"
    _run([BIN / "cosmic-ray", "init", "cosmic-ray.toml", db.name], work, env, log)
    _run([BIN / "cr-filter-operators", db.name, "cosmic-ray.toml"], work, env, log)
    _run([BIN / "cr-filter-pragma", db.name], work, env, log)
    _sample(db, fraction, seed)
    _run([BIN / "cosmic-ray", "baseline", "cosmic-ray.toml"], work, env, log)
    _run([BIN / "cosmic-ray", "exec", "cosmic-ray.toml", db.name], work, env, log)
    return {**_results(group, db, fraction, seed), "wall_s": round(time.perf_counter() - t0, 1), "retested": None}


def _results(group: str, db: Path, fraction: float, seed: int) -> dict:
    counts = {"killed": 0, "survived": 0, "incompetent": 0, "skipped": 0, "not_sampled": 0}
    survivors = []
    con = sqlite3.connect(db)
    rows = con.execute(
        "SELECT m.module_path, m.operator_name, m.occurrence, m.start_pos_row, "
        "r.worker_outcome, r.test_outcome, r.diff, r.output "
        "FROM mutation_specs m JOIN work_results r ON m.job_id = r.job_id").fetchall()
    con.close()
    for module, op, occ, row, worker, test, diff, output in rows:
        worker, test = str(worker).lower(), str(test).lower()  # enum names or values
        if worker == "skipped":
            counts["not_sampled" if output == NOT_SAMPLED else "skipped"] += 1
        elif worker in ("normal", "abnormal") and test in ("killed", "survived"):
            counts[test] += 1
            if test == "survived":
                survivors.append({"module": module, "line": row, "operator": op, "occurrence": occ,
                                  "source": _line(db.parent / module, row), "diff": diff})
        else:
            counts["incompetent"] += 1
    tested = counts["killed"] + counts["survived"]
    score = counts["killed"] / tested if tested else float("nan")
    return {"group": group, "modules": GROUPS[group][0], "tests": _tests(group), **counts,
            "sample_fraction": fraction, "seed": seed, "score": score,
            "score_stderr": (score * (1 - score) / tested) ** 0.5 if tested else float("nan"),
            "survivors": sorted(survivors, key=lambda s: (s["module"], s["line"]))}


def _same_tree(a: Path, b: Path) -> bool:
    """True if the .py files under a and b are byte for byte the same."""
    fa = {p.relative_to(a): p for p in a.rglob("*.py")}
    fb = {p.relative_to(b): p for p in b.rglob("*.py")}
    return fa.keys() == fb.keys() and all(fa[k].read_bytes() == fb[k].read_bytes() for k in fa)


def retest_group(group: str, root: Path) -> dict:
    """Run a finished session's survivors again against the current tests: after tests were added for
    what survived. The mutants stay those of the session's copy of the source; the current tests must
    pass on that copy unmutated (``cosmic-ray baseline``), else the re-test stops. The test command is
    rebuilt from :data:`GROUPS`, so test files added to a group since are run too."""
    work = root / group
    db = work / "session.sqlite"
    if not db.exists():
        raise RuntimeError(f"no session for {group} in {root}")
    # The mutants are of the session's copy of the source (work/src), which stays as it was; if the
    # checkout's source moved on since, the current tests must still pass on that copy (the baseline
    # below) for the re-test to mean anything, and the result says the source differs.
    source_changed = not _same_tree(REPO / "src", work / "src")
    if source_changed:
        print(f"{group}: the checkout's source differs from the session's copy; re-testing the session's "
              "mutants (of the copy) after a baseline of the current tests on the copy", flush=True)
    shutil.rmtree(work / "tests")
    shutil.copytree(REPO / "tests", work / "tests", ignore=shutil.ignore_patterns("__pycache__", ".hypothesis"))
    (work / "cosmic-ray.toml").write_text(_config(group))  # the group's tests as GROUPS lists them now
    prev = json.loads((root / "summary.json").read_text())
    old = next(r for r in prev["groups"] if r["group"] == group)
    t0 = time.perf_counter()
    # before the survivors' results are cleared, so that a failing baseline leaves the session as it was
    _run([BIN / "cosmic-ray", "baseline", "cosmic-ray.toml"], work, _env(work), work / "cosmic-ray.log")
    con = sqlite3.connect(db)
    n = con.execute("SELECT count(*) FROM work_results WHERE lower(test_outcome) = 'survived'").fetchone()[0]
    con.execute("DELETE FROM work_results WHERE lower(test_outcome) = 'survived'")
    con.commit()
    con.close()
    _run([BIN / "cosmic-ray", "exec", "cosmic-ray.toml", db.name], work, _env(work), work / "cosmic-ray.log")
    new = _results(group, db, old["sample_fraction"], old["seed"])
    return {**new, "wall_s": old["wall_s"], "retested": {"survivors": n, "killed_now": n - new["survived"],
                                                           "wall_s": round(time.perf_counter() - t0, 1),
                                                           "source_changed": source_changed}}


def _write(root: Path, results: list[dict]) -> None:
    killed = sum(r["killed"] for r in results)
    survived = sum(r["survived"] for r in results)
    summary = {"groups": results, "killed": killed, "survived": survived,
               "score": killed / (killed + survived) if killed + survived else float("nan"),
               "excluded_operators": EXCLUDED_OPERATORS, "python": sys.version.split()[0],
               "command": " ".join([Path(sys.argv[0]).name] + sys.argv[1:])}
    atomic_write_json(root / "summary.json", summary)
    lines = [f"# Mutation testing: {killed} killed, {survived} survived, score {summary['score']:.1%}", ""]
    for r in results:
        lines += [f"## {r['group']}: {r['killed']} killed, {r['survived']} survived, "
                  f"{r['incompetent']} incompetent, {r['skipped']} filtered, {r['not_sampled']} not sampled "
                  f"(seed {r['seed']}); score {r['score']:.1%} +- {r['score_stderr']:.1%} "
                  f"({r['wall_s']:.0f} s)"
                  + (f"; {r['retested']['survivors']} survivors re-tested with the current tests, "
                     f"{r['retested']['killed_now']} now killed" if r.get("retested") else ""), ""]
        lines += [f"- `{s['module']}:{s['line']}` {s['operator'].split('/')[-1]} #{s['occurrence']}: `{s['source']}`"
                  for s in r["survivors"]]
        lines.append("")
    atomic_write_text(root / "survivors.md", "\n".join(lines))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("groups", nargs="*", choices=[[]] + list(GROUPS), help="default: all")
    ap.add_argument("--jobs", type=int, default=2, help="groups run side by side (default 2)")
    ap.add_argument("--out", type=Path, default=REPO / "out" / "mutation")
    ap.add_argument("--sample", type=float, default=None,
                    help="fraction of each group's mutants to test (default: SAMPLE per group)")
    ap.add_argument("--seed", type=int, default=20261123, help="seed of the sample (recorded)")
    ap.add_argument("--named", action="store_true", help="only apply the NAMED mutants (a minute)")
    ap.add_argument("--retest", action="store_true",
                    help="re-run the survivors of the sessions in --out against the current tests")
    ap.add_argument("--skip-tests", nargs="+", default=[], metavar="TEST",
                    help="leave these test files or node ids out of the groups' test commands (recorded)")
    a = ap.parse_args(argv)
    SKIP_TESTS.update(a.skip_tests)
    a.out.mkdir(parents=True, exist_ok=True)
    if a.named:
        named = run_named(a.out)
        atomic_write_json(a.out / "named.json", named)
        return 0 if all(n["killed"] for n in named) else 1
    if a.retest:  # the groups not re-tested keep their results
        prev = {r["group"]: r for r in json.loads((a.out / "summary.json").read_text())["groups"]}
        todo = a.groups or list(prev)
        results = [r for g, r in prev.items() if g not in todo]
        fn = retest_group
    else:
        todo = a.groups or list(GROUPS)
        results = []

        def fn(g, out):
            return run_group(g, out, SAMPLE[g] if a.sample is None else a.sample, a.seed)

    with cf.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        futures = {pool.submit(fn, g, a.out): g for g in todo}
        for fut in cf.as_completed(futures):
            r = fut.result()
            print(f"{r['group']}: {r['killed']} killed, {r['survived']} survived, score {r['score']:.1%} "
                  f"+- {r['score_stderr']:.1%} (sample {r['sample_fraction']:g} of the mutants) "
                  f"({r['wall_s']:.0f} s)", flush=True)
            results.append(r)
    results.sort(key=lambda r: list(GROUPS).index(r["group"]))
    _write(a.out, results)
    total = sum(r["killed"] for r in results) + sum(r["survived"] for r in results)
    print(f"total: {sum(r['killed'] for r in results)} of {total} mutants killed; "
          f"survivors in {a.out / 'survivors.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
