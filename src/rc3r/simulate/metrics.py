r"""Scalar metrics of a run (the ``metrics.json`` of ``rc3r run``).

Definitions (per joint j, over the stored run of length T):

* ``max_abs_error`` -- :math:`\max_t |e_j(t)|` [rad], :math:`e = q - q_d`.
* ``rms_error`` -- :math:`\sqrt{\tfrac1N \sum_k e_j(t_k)^2}` [rad].
* ``final_error_bound`` -- :math:`\max_{t \ge T - 1\,s} |e_j(t)|` [rad]: the ultimate
  bound the robust law guarantees (shrinks with eps).
* ``max_abs_torque`` -- :math:`\max_t |u_j(t)|` [N m].
* ``chattering`` -- total variation of the torque per second,
  :math:`\tfrac1T \sum_k |u_j(t_{k+1}) - u_j(t_k)|` [N m/s]. In sampled mode the sum
  runs over every controller sample (exact for a zero-order-hold signal); in
  continuous mode over the stored grid (``output_rate``, default 1 kHz). A smooth
  torque of amplitude A at 1 rad/s scores about 0.64 A; chattering adds to it.
* ``verdict``, ``tolerance``, ``tolerance_met``, ``saturation_fraction``,
  ``chattering_joints``, ``limits`` -- :mod:`rc3r.simulate.verdict` (what the run means:
  clean, chattering, saturated, limit-violated, diverged, interrupted), from the plant's
  effects recorded in ``effects`` (and the loop's in ``loop``).
* ``boundary_layer`` -- robust law (eq. 6) only: ``median`` and ``max`` of
  :math:`\|Y^T r\| / \epsilon` over the stored rows after t = 0, and ``outside`` = the
  fraction of them with :math:`\|Y^T r\| > \epsilon` (outside the layer the robust term
  is the unit vector of magnitude rho; inside it the linear gain rho/eps).
"""
from __future__ import annotations

import numpy as np

__all__ = ["run_metrics", "verdict_of", "CHATTERING_DEFINITION"]

CHATTERING_DEFINITION = "total variation of u per second [N m/s] (sampled: every sample; continuous: 1 kHz grid)"


def _tolist(x):
    return [float(v) for v in np.asarray(x).ravel()]


def _layer(res, eps):
    if not isinstance(eps, (int, float)) or isinstance(eps, bool) or res.yt_r_norm.size < 2:
        return None
    x = np.asarray(res.yt_r_norm[1:]) / float(eps)
    return {"median": float(np.median(x)), "max": float(x.max()), "outside": float(np.mean(x > 1.0))}


def verdict_of(res, tolerance=None) -> dict:
    """The verdict of a run with its plant's recorded limits.

    Parameters
    ----------
    res : rc3r.simulate.SimResult
        A run; the plant's torque and joint limits are read from ``res.robot["effects"]``.
    tolerance : float, optional
        Tracking tolerance [rad] (default :data:`~rc3r.simulate.verdict.TOLERANCE`).

    Returns
    -------
    dict
        :func:`rc3r.simulate.verdict.verdict`'s dict (``verdict``, ``tolerance_met``, ...).
    """
    return _verdict(res, tolerance)


def _verdict(res, tolerance) -> dict:
    from .verdict import TOLERANCE, verdict

    effects = {e.get("effect"): e for e in res.robot.get("effects", [])}
    limits = None
    if "limits" in effects:
        from ..plants.limits import JointLimits, crossings

        d = effects["limits"]
        inf = np.inf

        def arr(x, fill):
            return np.array([fill if v is None else v for v in x], dtype=float)

        jl = JointLimits(arr(d["lower"], -inf), arr(d["upper"], inf), arr(d["velocity"], inf))
        limits = crossings(jl, res.t, res.q, res.qd)
    sat = effects.get("saturation", {}).get("limit")
    return verdict(res, saturation=sat, limits=limits, tolerance=TOLERANCE if tolerance is None else tolerance)


def run_metrics(res, seed=None, tolerance=None) -> dict:
    """The metrics of ``res`` as a JSON-ready dict (definitions in the module docstring);
    ``tolerance`` [rad] of the verdict's ``tolerance_met`` (default
    :data:`rc3r.simulate.verdict.TOLERANCE`)."""
    from . import file_status

    e = res.e
    nan = [float("nan")] * res.q.shape[1]
    T = max(res.t_end, 1e-12)
    late = res.t >= res.t[-1] - 1.0 if res.t.size else np.zeros(0, bool)
    if res.tv_exact is not None:
        tv = np.asarray(res.tv_exact) / T
    else:
        tv = np.abs(np.diff(res.u, axis=0)).sum(axis=0) / T if res.u.shape[0] > 1 else np.zeros(res.u.shape[1])
    c = res.controller
    out = {
        "controller": c.get("name"),
        "robot": res.robot.get("robot"),
        "plant": res.plant,
        "mode": res.mode,
        "rate_hz": res.options.rate,
        "engine": res.engine,
        "trajectory": res.trajectory,
        "status": file_status(res),  # how the integration ended, in the files' words; the verdict is below
        "message": res.message,
        "t_end": float(res.t_end),
        "theta_model": _tolist(c.get("theta", [])),
        "rho": c.get("rho", c.get("rho_i")),
        "eps": c.get("eps", c.get("eps_i")),
        "gains": {k: c[k] for k in ("Kp", "Kd", "K", "Lambda", "K_inertia", "Gamma") if k in c},
        "max_abs_error": _tolist(np.abs(e).max(axis=0)) if e.size else nan,
        "rms_error": _tolist(np.sqrt((e ** 2).mean(axis=0))) if e.size else nan,
        "final_error_bound": _tolist(np.abs(e[late]).max(axis=0)) if late.any() else nan,
        "max_abs_torque": _tolist(np.abs(res.u).max(axis=0)) if res.u.size else nan,
        "chattering": _tolist(tv),
        "chattering_definition": CHATTERING_DEFINITION,
        "boundary_layer": _layer(res, c.get("eps")),
        "wall_time_s": float(res.wall_time_s),
        "rhs_evals": res.rhs_evals,
        "steps": res.steps,
        "tolerances": {"rtol": res.options.rtol, "atol": res.options.atol,
                       "method": res.options.method if res.engine == "fast"  # another engine: None
                       else {"python": "scipy Radau", "reference": "scipy Radau"}.get(res.engine)}
        if res.mode == "continuous" else None,
        "seed": seed,
        "effects": res.robot.get("effects", []),
        "loop": res.loop,
    }
    out.update(_verdict(res, tolerance))
    return out
