"""Drive a plant rc3r does not simulate with ``rc3r.Controller.step`` at 1 kHz, and compare with
``rc3r run`` of the same specification.

The plant is MuJoCo when it is installed (``pip install 'rc3r[mujoco]'``: its own RK4 at 0.1 ms
steps, on the same URDF), else a plain Pinocchio ABA + RK4 loop written here (4 steps of 0.25 ms
per control period, as rc3r's sampled simulator). Usage::

    python examples/external_loop.py [--robot ur5] [--controller adaptive] [--duration 2]

It prints the largest joint-position difference between the external loop and ``rc3r.execute``.
"""
from __future__ import annotations

import argparse

import numpy as np

import rc3r


def pinocchio_plant(robot):
    """``advance(q, qd, u, T)``: RK4 of Pinocchio's ABA under a held torque, 4 steps per period."""
    import pinocchio as pin

    model, data = robot.model, robot.model.createData()

    def f(x, u):
        n = model.nv
        return np.concatenate([x[n:], pin.aba(model, data, x[:n], x[n:], u)])

    def advance(q, qd, u, T, nsub=4):
        x, h = np.concatenate([q, qd]), T / nsub
        for _ in range(nsub):
            k1 = f(x, u); k2 = f(x + 0.5 * h * k1, u); k3 = f(x + 0.5 * h * k2, u); k4 = f(x + h * k3, u)
            x = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        return x[:model.nv], x[model.nv:]

    return advance


def external_run(spec, engine: str):
    """Joint positions (N, n) of the external loop at the controller's samples."""
    ctrl = rc3r.Controller.from_run(spec)
    rigid = spec.true_rigid
    if engine == "mujoco":
        from rc3r.plants.mujoco import MujocoRigidBody

        advance = MujocoRigidBody.from_urdf(rigid.urdf, locked=rigid.locked or None).advance
    else:
        advance = pinocchio_plant(rigid)
    T = 1.0 / spec.options.rate
    q, qd, _ = spec.trajectory.evaluate(0.0)
    rows = [q]
    for k in range(int(round(spec.options.duration * spec.options.rate))):
        u = ctrl.step(k * T, q, qd)
        q, qd = advance(q, qd, u, T)
        rows.append(q)
    return np.array(rows)


def main(argv=None) -> float:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="ur5")
    ap.add_argument("--controller", default="fbl")
    ap.add_argument("--duration", type=float, default=2.0)
    ap.add_argument("--engine", choices=("auto", "mujoco", "pinocchio"), default="auto")
    args = ap.parse_args(argv)
    engine = args.engine
    if engine == "auto":
        try:
            import mujoco  # noqa: F401
            engine = "mujoco"
        except ImportError:
            engine = "pinocchio"
    spec = rc3r.build_run(robot=args.robot, controller=args.controller, rate=1000.0, duration=args.duration)
    res, m = rc3r.execute(spec)
    q_ext = external_run(spec, engine)
    diff = float(np.abs(q_ext[: len(res.q)] - res.q).max())
    print(f"{args.robot} {args.controller} at 1 kHz, {args.duration:g} s: external loop ({engine}) vs rc3r run: "
          f"max |q_ext - q_rc3r| = {diff:.3g} rad (rc3r verdict {m['verdict']}, max|e| = {max(m['max_abs_error']):.3g} rad)")
    return diff


if __name__ == "__main__":
    main()
