"""``rc3r bench`` of two source trees side by side in one run: every ratio and time, and after / before.

Issue 34's bar is that ``rc3r bench``'s ratios are no worse after a change than before, measured side by
side. Each round runs ``rc3r bench --json`` (full, or ``--quick``) in a fresh interpreter on the ``src/`` of
each tree, the trees alternating (before, after, after, before, ...) so that both see the same machine load;
each tree keeps its own ``NUMBA_CACHE_DIR`` and ``RC3R_CACHE_DIR`` across rounds (temporary, removed at the
end), and the first round of each is a warm-up when ``--warm`` is given (its numbers are dropped). Prints, per
leaf of the JSON that is a number (``ops/.../ratio_to_rnea``, ``sims/.../wall_s``, ``targets/.../measured``,
``compile/...``), the median over the rounds of each tree and ``after / before``; ``--only ratio`` keeps the
leaves named like a ratio (``ratio``, ``speedup``, ``x_``), whose numerator and denominator were measured in
the same process and so move together with the machine's load. ``--out FILE`` writes every round's JSON::

    git worktree add --detach ../before <rev>
    python benchmarks/bench_compare.py ../before . --rounds 2 --out /tmp/bench_compare.json
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RUN = "import sys; from rc3r.cli import main; sys.exit(main(['bench', '--json'] + sys.argv[1:]))"
_RATIO = ("ratio", "speedup", "x_default", "/x_")


def leaves(x, path=""):
    """``{path: number}`` of every int or float leaf of a JSON value (bools and strings left out)."""
    out = {}
    if isinstance(x, dict):
        for k, v in x.items():
            out.update(leaves(v, f"{path}/{k}"))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            out.update(leaves(v, f"{path}/{i}"))
    elif isinstance(x, (int, float)) and not isinstance(x, bool):
        out[path] = float(x)
    return out


def run_tree(tree: Path, env: dict, quick: bool) -> dict:
    """One ``rc3r bench --json`` of ``tree``'s ``src/`` in a fresh interpreter; its JSON, plus wall/CPU."""
    e = dict(env, PYTHONPATH=str(tree / "src"))
    t0 = time.perf_counter()
    r0 = os.times()
    p = subprocess.run([sys.executable, "-c", RUN] + (["--quick"] if quick else []), env=e,
                       capture_output=True, text=True, cwd=tree)
    r1 = os.times()
    if p.returncode not in (0, 1) or not p.stdout.strip():
        raise SystemExit(f"error: rc3r bench failed in {tree} (exit {p.returncode}): "
                         f"{(p.stderr.strip().splitlines() or ['no output'])[-1]}")
    d = json.loads(p.stdout)
    d["_process"] = {"wall_s": time.perf_counter() - t0,
                     "cpu_s": (r1.children_user - r0.children_user) + (r1.children_system - r0.children_system)}
    return d


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before", type=Path, help="a checkout of the commit before (git worktree add --detach ...)")
    ap.add_argument("after", type=Path, help="a checkout of the commit after")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--quick", action="store_true", help="rc3r bench --quick (tiny sizes: a smoke run)")
    ap.add_argument("--warm", action="store_true", help="one extra first round per tree, dropped")
    ap.add_argument("--only", choices=("all", "ratio"), default="all")
    ap.add_argument("--out", type=Path, help="write every round's JSON here")
    a = ap.parse_args(argv)
    for t in (a.before, a.after):
        if not (t / "src" / "rc3r").is_dir():
            print(f"error: {t} has no src/rc3r (give two checkouts of rc3r)", file=sys.stderr)
            return 2
    runs = {"before": [], "after": []}
    with tempfile.TemporaryDirectory() as tmp:
        envs = {}
        for k in runs:
            envs[k] = dict(os.environ, NUMBA_CACHE_DIR=f"{tmp}/{k}/numba", RC3R_CACHE_DIR=f"{tmp}/{k}/rc3r")
        trees = {"before": a.before.resolve(), "after": a.after.resolve()}
        order = []
        for r in range(a.rounds + (1 if a.warm else 0)):
            order += [("before", "after"), ("after", "before")][r % 2]
        for i, k in enumerate(order):
            keep = not (a.warm and i < 2)
            print(f"[bench_compare] {time.strftime('%H:%M:%S')} {k} ({trees[k]}){'' if keep else ' warm-up'} "
                  f"load {os.getloadavg()[0]:.1f} ...", file=sys.stderr, flush=True)
            d = run_tree(trees[k], envs[k], a.quick)
            d["_process"]["load_end"] = os.getloadavg()[0]
            if keep:
                runs[k].append(d)
    if a.out:
        a.out.write_text(json.dumps(runs, indent=1))
    lb = [leaves(d) for d in runs["before"]]
    la = [leaves(d) for d in runs["after"]]
    keys = [k for k in lb[0] if all(k in x for x in lb + la)]
    if a.only == "ratio":
        keys = [k for k in keys if any(s in k for s in _RATIO)]
    # settings and the run's own description, not measurements: whole sections, and leaves by their last name
    # (a whole-path substring would also drop targets/<name>/measured with the targets' limit "target")
    sections = ("/settings/", "/machine/")
    names = {"n_states", "repeats", "tol", "states", "target", "duration_s", "max_abs_ref"}
    keys = [k for k in keys if not k.startswith(sections) and k.rsplit("/", 1)[-1] not in names]
    print(f"rc3r bench side by side: before {trees['before']} | after {trees['after']}; "
          f"{len(lb)} round(s) each{' (quick)' if a.quick else ''}; medians; "
          f"loads at the ends {[round(d['_process']['load_end'], 1) for d in runs['before'] + runs['after']]}")
    w = max(len(k) for k in keys)
    print(f"{'leaf':<{w}}  {'before':>12}  {'after':>12}  {'after/before':>12}")
    for k in keys:
        b = statistics.median(x[k] for x in lb)
        f = statistics.median(x[k] for x in la)
        q = f"{f / b:12.3f}" if b else f"{'-':>12}"
        print(f"{k:<{w}}  {b:12.4g}  {f:12.4g}  {q}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
