"""rc3r identify's defaults on stand-ins for other arms' real logs: ``python benchmarks/identify_arms.py [--seed S]``.

Issue 35 asks that identify's defaults land within 15 % of the best plain least-squares fit of rc3r's model
class on every joint of two real arms' logs kept back from this repository (100 Hz to 5 kHz, with and
without logged velocities, one geared with a high ratio and resting at the end), and that
``rc3r design --bounds`` accept each result. The logs are not here; this script makes synthetic stand-ins
that have what those logs have, and measures both.

The stand-ins (:data:`ARMS`; every draw seeded, the seed printed): an example-robot-data arm with joint
friction (viscous, Coulomb ``sign(qd)``, and a torque-sensor offset per joint) and **rotor inertias**
(Pinocchio's ``armature``, reflected through the gear: up to 0.8 kg m^2 on the proximal joints) tracks a
random Fourier trajectory (:func:`rc3r.identify.excitation.random_fourier`) under computed torque
(:func:`rc3r.identify.synthetic.simulate_motion`, the plant's model with the armature), then, for the
geared arm, **rests** at its last position (held by gravity); the log is sampled with jittered stamps,
quantized encoders and torque noise (:func:`rc3r.identify.synthetic.sample_log`):

* ``ur5-geared``: the UR5, rotor inertias 0.8 0.8 0.4 0.05 0.05 0.05 kg m^2 (its links' own inertia about
  the joint axes is 0.03-2 kg m^2), 24 s of motion then 6 s at rest, **2 kHz without logged velocities**;
* ``xarm7-100hz``: the xArm7 (URDF), rotor inertias 0.3 0.3 0.15 0.15 0.05 0.05 0.02 kg m^2, 30 s, **100 Hz
  with logged velocities 15 ms late** (a drive's filtered estimate: 1.5 samples).

The identification model is the rigid URDF arm (without the armature): what rc3r is given.

For each: ``rc3r identify LOG (--robot | --urdf) --test-fraction 0.3`` with its defaults (run as a command),
its held-out RMS per joint (``validation.rms`` of identified.json, the unconstrained estimate, and
``physical.validation.rms``, bounds.toml's) beside the **best plain least-squares fit** of rc3r's model
class, computed here: :func:`rc3r.identify.pipeline.identify` with every setting given (ordinary least
squares, no cross-validation, no consistent fit) over every cut-off the log's rate allows x velocity source
(logged, differentiated) x Coulomb law (``sign``, ``tanh(qd / v_s)`` at 0.003 and 0.01 rad/s) x rotor inertia
(off, on): the **best fit** (the setting with the lowest geometric mean of the held-out RMS over the joints)
and, stricter, each joint's own minimum over all those settings (a minimum over 28-84 noisy held-out
figures: biased low).
Then ``rc3r design (--robot | --urdf) --bounds ID/bounds.toml --rate 1000 --n 2 --duration 0.5``: accepted
(exit 0) or its one-line refusal; with ``--run LAWS``, ``rc3r run`` of each law at 1 kHz on the bounds with its
defaults (plant: the identified arm, the bounds' centre), its summary line.

The plain fits are most of the cost (42 fits of the 2 kHz UR5, 84 of the xArm7: 4-6 minutes per seed on the
shared two-core machine); ``--plain-cache FILE`` keeps them by arm and seed (they depend on the seeded log and
the plain grid only) so that a change to identify's defaults is measured again in about a minute per seed.
"""
from __future__ import annotations

import argparse
import itertools
import json
import subprocess
import sys
import tempfile
import time
import types
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
TEST_FRACTION = 0.3
#: Coulomb smoothing velocities [rad/s] of the plain fits (0: sign).
PLAIN_VS = (0.0, 0.003, 0.01)
CLI = [sys.executable, "-c", "import sys; from rc3r.cli import main; sys.exit(main(sys.argv[1:]))"]

#: name -> (robot or urdf, rotor inertias [kg m^2], viscous [N m s/rad], Coulomb [N m], offsets [N m],
#: torque noise [N m], motion [s], rest [s], period [s], logged velocities, velocity lag [s], trajectory seed)
ARMS = {
    "ur5-geared": dict(robot="ur5", armature=(0.8, 0.8, 0.4, 0.05, 0.05, 0.05), viscous=(6, 6, 3, 1, 1, 1),
                       coulomb=(8, 8, 4, 1.5, 1.5, 1.5), offset=(0.8, -0.5, 0.4, 0.2, -0.1, 0.1),
                       torque_std=(0.4, 0.4, 0.3, 0.1, 0.1, 0.1), motion=24.0, rest=6.0, period=5e-4,
                       velocities=False, lag=0.0),
    "xarm7-100hz": dict(urdf="xarm_description/urdf/xarm7.urdf", armature=(0.3, 0.3, 0.15, 0.15, 0.05, 0.05, 0.02),
                        viscous=(3, 3, 2, 2, 0.8, 0.8, 0.5), coulomb=(4, 4, 3, 3, 1, 1, 0.6),
                        offset=(0.3, -0.4, 0.2, 0.2, -0.1, 0.05, 0.05), torque_std=(0.3, 0.3, 0.2, 0.2, 0.1, 0.1, 0.05),
                        motion=30.0, rest=0.0, period=1e-2, velocities=True, lag=0.015),
}


def arm_of(spec):
    """``(robot, cli_args)``: the rigid identification model and how the command line names it."""
    import rc3r
    from rc3r.robots.pinocchio import example_robot_data_dir

    if "robot" in spec:
        return rc3r.load_robot(spec["robot"]), ["--robot", spec["robot"]]
    path = str(example_robot_data_dir() / spec["urdf"])
    from rc3r.robots import load_urdf_robot

    return load_urdf_robot(path), ["--urdf", path]


def plant_of(robot, armature):
    """A copy of ``robot``'s Pinocchio model with rotor inertias: what :func:`simulate_motion` integrates."""
    import pinocchio as pin

    model = pin.Model(robot.model)
    model.armature = np.asarray(armature, dtype=float)
    return types.SimpleNamespace(model=model, n=robot.n, theta=robot.theta, label=robot.label + "+armature")


def resting(motion, plant, seconds: float):
    """``motion`` then ``seconds`` at rest at its last position, held by the gravity torque."""
    import pinocchio as pin

    from rc3r.identify.synthetic import Motion

    if seconds <= 0:
        return motion
    dt = motion.t[1] - motion.t[0]
    K = int(round(seconds / dt))
    q_end = motion.q[-1]
    g = np.array(pin.rnea(plant.model, plant.model.createData(), q_end, np.zeros(plant.n), np.zeros(plant.n)))
    zeros = np.zeros((K, plant.n))
    return Motion(np.concatenate([motion.t, motion.t[-1] + dt * np.arange(1, K + 1)]),
                  np.vstack([motion.q, np.tile(q_end, (K, 1))]), np.vstack([motion.qd, zeros]),
                  np.vstack([motion.qdd, zeros]), np.vstack([motion.u, np.tile(g, (K, 1))]), motion.theta,
                  motion.viscous, motion.coulomb, motion.label, motion.max_tracking_error)


def make_log(name, spec, seed):
    """The stand-in log of arm ``name`` (module docstring) and the rigid robot and its CLI arguments."""
    from rc3r.identify.excitation import random_fourier
    from rc3r.identify.synthetic import Friction, SensorNoise, sample_log, simulate_motion

    robot, args = arm_of(spec)
    plant = plant_of(robot, spec["armature"])
    traj = random_fourier(robot, spec["motion"], seed=seed, fill=0.8)
    motion = simulate_motion(plant, traj, spec["motion"], Friction(spec["viscous"], spec["coulomb"]))
    motion = resting(motion, plant, spec["rest"])
    P = spec["period"]
    noise = SensorNoise(torque_std=tuple(spec["torque_std"]), torque_offset=tuple(spec["offset"]), velocity_std=0.005,
                        encoder_counts=2 ** 18, period=P, gap=(2 * P, 9 * P), velocity_lag=spec["lag"])
    log, truth = sample_log(motion, seed=seed, noise=noise, log_velocities=spec["velocities"])
    return robot, args, log


def best_plain(robot, log):
    """Plain OLS over every setting (module docstring): the best fit's held-out RMS (n,) (lowest geometric mean
    over the joints) and its setting, and per joint the lowest over all settings (n,) and theirs."""
    from threadpoolctl import threadpool_limits

    from rc3r.identify.filtering import Grids, cutoff_candidates
    from rc3r.identify.pipeline import identify

    fs = Grids.of(log).fs
    vels = ("logged", "differentiated") if log.qd is not None else ("differentiated",)
    best, how = np.full(robot.n, np.inf), [None] * robot.n
    one, one_how = None, None
    for fc, vel, v_s, arm in itertools.product(cutoff_candidates(fs), vels, PLAIN_VS, ("off", "on")):
        with threadpool_limits(limits=1, user_api="blas"):
            res = identify(robot, log, cutoff_hz=fc, velocities=vel, weighting="ordinary", coulomb_velocity=v_s,
                           armature=arm, test_fraction=TEST_FRACTION, physical=False, consistency=False,
                           slow_share=0.0)
        rms = np.asarray(res.validation["rms"])
        label = f"{fc:g} Hz {vel[:4]} v_s={v_s:g} ia={arm}"
        for j in np.nonzero(rms < best)[0]:
            best[j], how[j] = rms[j], label
        if one is None or np.exp(np.mean(np.log(rms))) < np.exp(np.mean(np.log(one))):
            one, one_how = rms, label
    return one, one_how, best, how


def cached_plain(path, key, robot, log):
    """:func:`best_plain`, read from the JSON file ``path`` under ``key`` when there, else computed and stored."""
    store = json.loads(Path(path).read_text()) if path and Path(path).exists() else {}
    if key not in store:
        one, one_how, best, how = best_plain(robot, log)
        store[key] = {"best_fit": one.tolist(), "best_fit_setting": one_how, "joint_min": best.tolist(),
                      "joint_min_setting": how}
        if path:
            Path(path).write_text(json.dumps(store, indent=1))
    e = store[key]
    return np.asarray(e["best_fit"]), e["best_fit_setting"], np.asarray(e["joint_min"]), e["joint_min_setting"]


def run_cli(args, log_path, out, arm_args, extra=()):
    """``rc3r identify`` with defaults (and ``extra`` options); ``rc3r design --bounds``: (identified.json, wall s,
    design verdict)."""
    t0 = time.perf_counter()
    subprocess.run(CLI + ["identify", str(log_path), *arm_args, "--test-fraction", str(TEST_FRACTION), *extra,
                          "--out", str(out)], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    data = json.loads((out / "identified.json").read_text())
    if args.skip_design:
        return data, wall, "not run (--skip-design)"
    d = subprocess.run(CLI + ["design", *arm_args, "--bounds", str(out / "bounds.toml"), "--rate", "1000", "--n",
                              str(args.design_n), "--duration", str(args.design_duration), "--out",
                              str(out / "design")], capture_output=True, text=True)
    verdict = "accepted" if d.returncode == 0 else f"refused (exit {d.returncode}): {d.stderr.strip()[-300:]}"
    return data, wall, verdict


def run_laws(args, out, arm_args) -> list[str]:
    """``rc3r run (--robot | --urdf) --bounds OUT/bounds.toml --controller LAW --rate 1000`` for each law of
    ``--run`` (default plant: the bounds' centre, the identified arm with its friction): its summary line."""
    lines = []
    for law in filter(None, args.run.split(",")):
        r = subprocess.run(CLI + ["run", *arm_args, "--bounds", str(out / "bounds.toml"), "--controller", law,
                                  "--rate", "1000", "--out", str(out / f"run-{law}")], capture_output=True, text=True)
        last = ((r.stdout.strip() or r.stderr.strip()).splitlines() or ["(no output)"])[-1]  # the verdict line
        lines.append(f"rc3r run --controller {law} --rate 1000 (exit {r.returncode}): {last[:400]}")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0, help="seed of the trajectories and the logs (default 0)")
    ap.add_argument("--arms", default=",".join(ARMS), help="comma-separated subset of " + ", ".join(ARMS))
    ap.add_argument("--design-n", type=int, default=2, help="rc3r design --n (default 2)")
    ap.add_argument("--design-duration", type=float, default=0.5, help="rc3r design --duration (default 0.5)")
    ap.add_argument("--skip-design", action="store_true", help="do not run rc3r design")
    ap.add_argument("--slow-share", default="auto",
                    help="comma-separated values of identify's --slow-share to measure; auto: the option not given "
                         "(identify's default, chosen by cross-validation; default auto)")
    ap.add_argument("--run", default="", metavar="LAWS",
                    help="comma-separated laws to run at 1 kHz on each result's bounds with rc3r run's defaults "
                         "(its plant: the identified arm; e.g. robust-coeff; default: none)")
    ap.add_argument("--plain-cache", metavar="JSON",
                    help="keep the best plain fits (the costly part: 42-84 fits per arm) in this file, keyed by arm "
                         "and seed, and reuse them from it (they depend on the log and the plain grid only)")
    args = ap.parse_args(argv)
    from rc3r.identify.log import save_log

    print(f"seed {args.seed}; test fraction {TEST_FRACTION}; held-out RMS per joint [N m] against the logged torques")
    worst, worst_j = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.arms.split(","):
            spec = ARMS[name]
            robot, arm_args, log = make_log(name, spec, args.seed)
            path = Path(tmp) / f"{name}.npz"
            save_log(log, path)
            one, one_how, best, how = cached_plain(args.plain_cache, f"{name}:{args.seed}", robot, log)
            for share in args.slow_share.split(","):
                extra = () if share == "auto" else ("--slow-share", f"{float(share):g}")
                data, wall, verdict = run_cli(args, path, Path(tmp) / f"{name}-{share}", arm_args, extra)
                rms = np.asarray(data["validation"]["rms"])
                prms = np.asarray((data.get("physical") or {}).get("validation", {}).get("rms", rms))
                sel = data["filter"]
                arm = data.get("armature") or {}
                slow = (f", slow share {sel['slow_share']:g} ({sel['slow_share_chosen']})"
                        if "slow_share_chosen" in sel else "")
                print(f"\n{name}: {log.samples} samples at {1 / spec['period']:g} Hz, velocities "
                      f"{'logged, ' + format(spec['lag'] * 1e3, 'g') + ' ms late' if spec['velocities'] else 'not logged'}"
                      f"{', at rest for the last ' + format(spec['rest'], 'g') + ' s' if spec['rest'] else ''}; "
                      f"identify{' '.join(('',) + extra)} {wall:.0f} s: "
                      f"{sel['cutoff_hz']:g} Hz, {sel['velocities']}, {sel['weighting']}, "
                      f"v_s {data['friction_law']['coulomb_velocity']:g}, rotor inertias "
                      f"{'fitted' if arm.get('fitted') else 'not fitted'}{slow}"
                      + (" (merged: " + ", ".join(f"{a}->{b}" for a, b in arm["merged"].items()) + ")"
                         if arm.get("merged") else ""))
                print(f"  best plain OLS fit (lowest geometric mean): {one_how}")
                print(f"  {'joint':>5} {'default':>8} {'bounds':>8} {'best fit':>8} {'ratio':>6} {'joint min':>9} "
                      f"{'ratio':>6}  setting of the joint's min")
                for j in range(robot.n):
                    r, r_j = max(rms[j], prms[j]) / one[j], max(rms[j], prms[j]) / best[j]
                    worst[share], worst_j[share] = max(worst.get(share, 0.0), r), max(worst_j.get(share, 0.0), r_j)
                    print(f"  {j + 1:>5} {rms[j]:>8.4f} {prms[j]:>8.4f} {one[j]:>8.4f} {r:>6.3f} {best[j]:>9.4f} "
                          f"{r_j:>6.3f}  {how[j]}")
                if arm.get("fitted"):
                    print("  rotor inertias [kg m^2]: " + " ".join(f"{x:.3g}" for x in data["physical"]["friction"]
                                                                  ["armature"]) + " (true " +
                          " ".join(f"{x:g}" for x in spec["armature"]) + ")")
                print(f"  rc3r design --bounds: {verdict}")
                for line in run_laws(args, Path(tmp) / f"{name}-{share}", arm_args):
                    print(f"  {line}")
    for share in worst:
        print(f"\n--slow-share {share}: worst ratio, any joint, of the default's or the bounds' estimate's RMS: to the "
              f"best plain OLS fit {worst[share]:.3f} ({'within' if worst[share] <= 1.15 else 'beyond'} 15 %); to the "
              f"joint's own minimum over every setting {worst_j[share]:.3f} "
              f"({'within' if worst_j[share] <= 1.15 else 'beyond'} 15 %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
