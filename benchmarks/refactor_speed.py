"""Speed of the current tree against the pre-refactoring commit, side by side in one run.

    git worktree add /tmp/rc3r-aec101b aec101b
    python benchmarks/refactor_speed.py /tmp/rc3r-aec101b

Alternates fresh interpreters of the old tree (its own numba cache) and the current one, ``--rounds``
times: the five paper scenarios in continuous time (sum of wall times, median of 5) and the
closed-form kernels per state (tau and Slotine-Li Y on 1e5 states, median of 7). Prints each
measurement and the new/old ratios of the medians. Used for the robot-contract issue's "speed within
10 %" (docs/performance.md).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

_OLD = r"""
import sys, json, time, numpy as np
sys.path.insert(0, sys.argv[1] + "/src")
import rc3r.scenarios as S, rc3r._kernels as K
specs = S.paper_scenarios()
run = S.execute
"""
_NEW = r"""
import sys, json, time, numpy as np
from rc3r.experiments.paper3r import scenarios
from rc3r.robots.rr3 import kernels as K
from rc3r.runspec import execute as run
specs = scenarios()
"""
_BODY = r"""
for s in specs: run(s)
five = float(np.median([sum(run(s)[0].wall_time_s for s in specs) for _ in range(5)]))
rng = np.random.default_rng(0); N = 100000
Q, QD, QDD = (rng.uniform(-3, 3, (N, 3)) for _ in range(3)); th = rng.uniform(-5, 5, 15)
out = np.empty((N, 3)); Y = np.empty((N, 3, 15))
K.inverse_dynamics_batch(th, Q, QD, QDD, 1.0, 9.81, out); K.slotine_li_batch(Q, QD, QD, QDD, 1.0, 9.81, Y)
tau, sl = [], []
for _ in range(7):
    t = time.perf_counter(); K.inverse_dynamics_batch(th, Q, QD, QDD, 1.0, 9.81, out); tau.append((time.perf_counter() - t) / N)
    t = time.perf_counter(); K.slotine_li_batch(Q, QD, QD, QDD, 1.0, 9.81, Y); sl.append((time.perf_counter() - t) / N)
print(json.dumps({"five_continuous_s": five, "tau_per_state_s": float(np.median(tau)),
                  "slotine_li_per_state_s": float(np.median(sl))}))
"""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old_tree", help="a checkout of the old commit (git worktree add ...)")
    ap.add_argument("--rounds", type=int, default=2)
    a = ap.parse_args(argv)
    rows = {"old": [], "new": []}
    with tempfile.TemporaryDirectory() as cache:
        for r in range(a.rounds):
            for which, script in (("old", _OLD + _BODY), ("new", _NEW + _BODY)):
                env = dict(os.environ)
                if which == "old":
                    env["NUMBA_CACHE_DIR"] = cache
                p = subprocess.run([sys.executable, "-c", script, a.old_tree], capture_output=True, text=True,
                                   env=env, check=True)
                rows[which].append(json.loads(p.stdout.strip().splitlines()[-1]))
                print(f"round {r + 1} {which}: {rows[which][-1]}", flush=True)
    for key in rows["old"][0]:
        o = np.median([x[key] for x in rows["old"]])
        n = np.median([x[key] for x in rows["new"]])
        print(f"{key:24s} old {o:.4g}  new {n:.4g}  new/old {n / o:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
