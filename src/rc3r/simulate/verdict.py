r"""The verdict of a run: what a user should conclude from it, beyond "it did not diverge".

One word, the first that applies in this order:

* ``interrupted`` -- stopped by Ctrl-C or SIGTERM (nothing to conclude);
* ``diverged`` -- the run left its bounds or could not be integrated (``SimResult.outcome`` ``diverged``);
* ``limit-violated`` -- a joint left its position or velocity range
  (:class:`~rc3r.plants.limits.JointLimits`; the motion would not be possible on the arm);
* ``saturated`` -- the delivered torque sat at an actuator limit for more than
  :data:`SATURATION_FRACTION` of the stored samples (``saturation_fraction``; the law is
  not acting as designed);
* ``chattering`` -- a sampled run whose torque switches at the sample rate
  (:func:`chattering`);
* ``clean`` -- none of the above.

Separately, ``tolerance_met`` says whether :math:`\max_t |e_j(t)| \le` ``tolerance`` on every
joint (default :data:`TOLERANCE`, ``--tolerance``).

**Chattering** (every sampled run; continuous-time runs cannot chatter: the boundary layer
makes the law continuous). The total variation of a smooth torque is the same on any fine
grid; chattering multiplies it. With :math:`TV_j` the total variation of joint j's torque over
every controller sample (``SimResult.tv_exact``) and :math:`\widetilde{TV}_j` that of the
stored torque smoothed by a centred moving average of :data:`SMOOTH_SAMPLES` stored samples,
joint j chatters when

.. math::

    TV_j > R \max\left(\widetilde{TV}_j,\; T \cdot 1\,\mathrm{s}^{-1} \max_t |u_j(t)|\right),

with :math:`R` = :data:`CHATTER_RATIO` (the sweep's ratio) and T the run's duration: more than
ten times what the smooth part of the torque and one full swing per second explain. A
torque alternating with amplitude A at rate f has :math:`TV \approx 2 A f T`; a sine of
amplitude A at 1 rad/s has :math:`TV \approx 0.64 A T`.
"""
from __future__ import annotations

import numpy as np

__all__ = ["verdict", "chattering", "saturation_fraction", "VERDICTS", "TOLERANCE", "SATURATION_FRACTION",
           "CHATTER_RATIO", "SMOOTH_SAMPLES"]

#: Verdicts, in the order they are tested.
VERDICTS = ("interrupted", "diverged", "limit-violated", "saturated", "chattering", "clean")

#: Default tracking tolerance on ``max |e_j|`` [rad] (0.57 degrees).
TOLERANCE = 0.01

#: A run is ``saturated`` when a torque limit holds for more than this fraction of the stored samples.
SATURATION_FRACTION = 0.05

#: Total variation over what the smooth torque explains that counts as chattering.
CHATTER_RATIO = 10.0

#: Width of the centred moving average that defines the smooth torque [stored samples].
SMOOTH_SAMPLES = 10


def _smooth(u: np.ndarray, w: int) -> np.ndarray:
    if u.shape[0] < w:
        return u
    kernel = np.ones(w) / w
    return np.stack([np.convolve(u[:, j], kernel, mode="valid") for j in range(u.shape[1])], axis=1)


def chattering(res) -> list[bool]:
    """Per joint: does a sampled run's torque chatter (module docstring)? All False for a continuous run."""
    n = res.u.shape[1] if res.u.ndim == 2 else 0
    if res.mode != "sampled" or res.tv_exact is None or res.u.shape[0] < 2:
        return [False] * n
    T = max(float(res.t_end), 1e-12)
    with np.errstate(all="ignore"):
        smooth = _smooth(np.asarray(res.u, dtype=float), SMOOTH_SAMPLES)
        tv_smooth = np.abs(np.diff(smooth, axis=0)).sum(axis=0)
        swing = T * np.abs(res.u).max(axis=0)
        bar = CHATTER_RATIO * np.maximum(tv_smooth, swing)
    return [bool(tv > b and tv > 0) for tv, b in zip(np.asarray(res.tv_exact, dtype=float), bar)]


def saturation_fraction(res, limit) -> float | None:
    """Fraction of stored samples with some ``|u_j| >= limit_j`` (to 1e-12 relative); None without a limit."""
    if limit is None or res.u.size == 0:
        return None
    lim = np.asarray(limit, dtype=float)
    return float(np.mean(np.any(np.abs(res.u) >= lim * (1.0 - 1e-12), axis=1)))


def verdict(res, *, saturation=None, limits=None, tolerance: float = TOLERANCE) -> dict:
    """The verdict of ``res`` and what it rests on.

    Parameters
    ----------
    res : rc3r.simulate.SimResult
    saturation : (n,) torque limits [N m] of the plant, or None
    limits : dict of :func:`rc3r.plants.limits.crossings`, or None
    tolerance : float
        Tracking tolerance on ``max |e_j|`` [rad].

    Returns
    -------
    dict
        ``verdict`` (one of :data:`VERDICTS`), ``tolerance`` [rad], ``tolerance_met`` (bool, or None
        for a run with no rows), ``saturation_fraction``, ``chattering_joints`` (1-based), ``limits``.
    """
    chat = chattering(res)
    sat = saturation_fraction(res, saturation)
    if res.outcome == "interrupted":
        word = "interrupted"
    elif res.outcome != "finished":
        word = "diverged"
    elif limits is not None and limits.get("violated"):
        word = "limit-violated"
    elif sat is not None and sat > SATURATION_FRACTION:
        word = "saturated"
    elif any(chat):
        word = "chattering"
    else:
        word = "clean"
    e = res.e
    met = bool(np.all(np.abs(e).max(axis=0) <= tolerance)) if e.size else None
    return {"verdict": word, "tolerance": float(tolerance), "tolerance_met": met, "saturation_fraction": sat,
            "chattering_joints": [j + 1 for j, c in enumerate(chat) if c], "limits": limits}
