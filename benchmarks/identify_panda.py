"""rc3r identify on a real Panda log beside a plain least-squares baseline: ``python benchmarks/identify_panda.py``.

The log (Gaz et al., RA-L 2019; GPL-3, not in this repository) is looked for as
``$RC3R_SHARED_DATA/panda_gaz/exciting_traj_1.npz`` or ``shared/data/panda_gaz/`` beside the repository
(or beside its parent or grandparent directory: a git worktree); without
it the script says so and exits 0.

It prints, per joint, the held-out RMS [N m] of the prediction against the torques as logged (train
on the first 70 % of the log's duration, test on the last 30 %) of:

* ``rc3r identify LOG --robot panda --test-fraction 0.3`` with its defaults (run as a command; its
  wall time is printed too), read from its identified.json;
* a plain ordinary least squares at 5, 10 and 20 Hz, and at 100 Hz (FIGAROH's default cut-off),
  computed here, independently of rc3r's identification code (Pinocchio + NumPy + SciPy only; rc3r
  is used to locate example-robot-data's Panda URDF and nothing else). The recipe (FIGAROH's, with its cut-off as a parameter): the log
  linearly interpolated onto a uniform 1 kHz grid; the training and test parts filtered separately
  by a 4th-order Butterworth run forwards and backwards (``scipy.signal.filtfilt``) at the cut-off
  on ``q``, the logged ``qd`` and ``tau``; ``qdd`` by central differences of the filtered ``qd``;
  0.2 s trimmed at each end of each filtered part; the base regressor from
  ``pinocchio.computeJointTorqueRegressor`` (finger joints locked at 0) restricted to a base column
  set chosen by QR with column pivoting on 400 random states (seed 0); per joint viscous ``qd``,
  Coulomb ``sign(qd)`` and offset columns; OLS on the filtered torques of the training part; the
  prediction at the test part's filtered states, linearly interpolated to its logged time stamps,
  against the logged torques there.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FINGERS = ("panda_finger_joint1", "panda_finger_joint2")
RATE = 1000.0
TRIM = 0.2
TEST_FRACTION = 0.3


def shared_log() -> Path | None:
    """The log's NPZ, or None when the shared data are absent."""
    roots = [Path(os.environ["RC3R_SHARED_DATA"])] if os.environ.get("RC3R_SHARED_DATA") else []
    roots += [up / "shared" / "data" for up in REPO.parents[:3]]  # ../shared/data, also from a worktree
    for root in roots:
        path = root / "panda_gaz" / "exciting_traj_1.npz"
        if path.is_file():
            return path
    return None


def panda_model():
    """Pinocchio model of example-robot-data's Panda with the finger joints locked at 0."""
    import pinocchio as pin

    from rc3r.robots.pinocchio import example_robot_data_dir  # only to find the URDF file

    full = pin.buildModelFromUrdf(str(example_robot_data_dir() / "panda_description" / "urdf" / "panda.urdf"))
    lock = [full.getJointId(name) for name in FINGERS]
    return pin.buildReducedModel(full, lock, pin.neutral(full))


def torque_regressor(model, q, qd, qdd) -> np.ndarray:
    """``computeJointTorqueRegressor`` at every row: (N, n, 10 n)."""
    import pinocchio as pin

    data = model.createData()
    return np.stack([np.array(pin.computeJointTorqueRegressor(model, data, a, b, c)) for a, b, c in zip(q, qd, qdd)])


def base_columns(model, seed: int = 0, samples: int = 400) -> np.ndarray:
    """Indices of a base column set: QR with column pivoting of the regressor at random states."""
    from scipy.linalg import qr

    rng = np.random.default_rng(seed)
    n = model.nq
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    q = rng.uniform(lo, hi, (samples, n))
    W = torque_regressor(model, q, rng.uniform(-2, 2, (samples, n)), rng.uniform(-10, 10, (samples, n)))
    W = W.reshape(-1, W.shape[-1])
    _, R, piv = qr(W, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    rank = int(np.sum(d > 1e-8 * d[0]))
    return np.sort(piv[:rank])


def _part(t, q, qd, tau, lo, hi, fc):
    """One part of the log on the uniform grid, filtered at ``fc`` and trimmed: (grid, q, qd, qdd, tau_f)."""
    from scipy.signal import butter, filtfilt

    grid = np.arange(lo, hi, 1.0 / RATE)
    on = lambda X: np.column_stack([np.interp(grid, t, X[:, j]) for j in range(X.shape[1])])  # noqa: E731
    b, a = butter(4, fc, fs=RATE)
    qf, qdf, tauf = (filtfilt(b, a, on(X), axis=0) for X in (q, qd, tau))
    qddf = np.gradient(qdf, 1.0 / RATE, axis=0)
    keep = (grid >= lo + TRIM) & (grid <= hi - TRIM)
    return grid[keep], qf[keep], qdf[keep], qddf[keep], tauf[keep]


def _rows(model, cols, q, qd, qdd) -> np.ndarray:
    """``[W_base | viscous, Coulomb sign, offset per joint]`` (N, n, b + 3 n)."""
    W = torque_regressor(model, q, qd, qdd)[:, :, cols]
    N, n = qd.shape
    F = np.zeros((N, n, 3 * n))
    idx = np.arange(n)
    for k, col in enumerate((qd, np.sign(qd), np.ones_like(qd))):
        F[:, idx, k * n + idx] = col
    return np.concatenate([W, F], axis=2)


def plain_ols(path: Path, fc: float, model, cols) -> np.ndarray:
    """Held-out RMS per joint of the OLS recipe (module docstring) at cut-off ``fc``."""
    d = np.load(path)
    t, q, qd, tau = d["t"], d["q"], d["qd"], d["tau"]
    split = t[0] + (1.0 - TEST_FRACTION) * (t[-1] - t[0])
    _, q1, qd1, qdd1, tau1 = _part(t, q, qd, tau, t[0], split, fc)
    A = _rows(model, cols, q1, qd1, qdd1)
    x = np.linalg.lstsq(A.reshape(-1, A.shape[-1]), tau1.ravel(), rcond=None)[0]
    g2, q2, qd2, qdd2, _ = _part(t, q, qd, tau, split, t[-1], fc)
    pred = _rows(model, cols, q2, qd2, qdd2) @ x
    stamps = (t >= g2[0]) & (t <= g2[-1])
    pred_t = np.column_stack([np.interp(t[stamps], g2, pred[:, j]) for j in range(pred.shape[1])])
    return np.sqrt(np.mean((tau[stamps] - pred_t) ** 2, axis=0))


def run_rc3r(path: Path) -> tuple[np.ndarray, dict, float]:
    """``rc3r identify`` with its defaults: (held-out RMS, identified.json, wall time [s])."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "ID"
        cmd = [sys.executable, "-c", "import sys; from rc3r.cli import main; sys.exit(main(sys.argv[1:]))",
               "identify", str(path), "--robot", "panda",
               "--test-fraction", str(TEST_FRACTION), "--out", str(out)]
        start = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - start
        data = json.loads((out / "identified.json").read_text())
    return np.asarray(data["validation"]["rms"]), data, wall


def main() -> int:
    path = shared_log()
    if path is None:
        print("benchmarks/identify_panda.py: the shared Panda log (../shared/data/panda_gaz or $RC3R_SHARED_DATA) "
              "is absent; nothing to measure")
        return 0
    model = panda_model()
    cols = base_columns(model)
    rms, data, wall = run_rc3r(path)
    f, law = data["filter"], data["friction_law"]
    rows = [(f"rc3r identify (defaults: {f['cutoff_hz']:g} Hz, {f['velocities']} qd, {f['weighting']}, "
             f"v_s {law['coulomb_velocity']:g})", rms)]
    for fc in (5.0, 10.0, 20.0, 100.0):
        rows.append((f"plain OLS at {fc:g} Hz ({cols.size} base columns + {3 * model.nq} friction)",
                     plain_ols(path, fc, model, cols)))
    print(f"log: {path} ({TEST_FRACTION:g} held out); held-out RMS vs logged torque [N m], joints 1..{model.nq}")
    width = max(len(name) for name, _ in rows)
    print(f"| {'method':<{width}} | " + " | ".join(f"j{j + 1:<4}" for j in range(model.nq)) + " |")
    print(f"|{'-' * (width + 2)}|" + "|".join("-" * 7 for _ in range(model.nq)) + "|")
    for name, r in rows:
        print(f"| {name:<{width}} | " + " | ".join(f"{x:.3f}" for x in r) + " |")
    best = np.min([r for _, r in rows[1:4]], axis=0)
    print("rc3r / best plain OLS (5, 10, 20 Hz) per joint: " + " ".join(f"{x:.2f}" for x in rms / best))
    print(f"rc3r identify wall time: {wall:.1f} s (including Python start-up, the consistency SDP and figures)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
