r"""The identification regressor: the arm's base regressor and per-joint friction columns.

The logged torque of joint ``j`` is modelled as

.. math::

    \tau_j = \bigl[Y(q, \dot q, \dot q, \ddot q)\,\theta\bigr]_j
             + f_{v,j}\,\dot q_j + f_{c,j}\,\tanh(\dot q_j / v_s) + f_{0,j},

with ``Y`` the robot's regressor in its own coefficients (:meth:`Robot.regressor` with
``v = qd``, ``a = qdd``: the inverse-dynamics regressor), viscous ``f_v`` [N m s/rad],
Coulomb ``f_c`` [N m] and a constant offset ``f_0`` [N m] (a torque sensor's bias or a
static load the model lacks). Each friction kind adds one column per joint, nonzero
only in that joint's row. :data:`FRICTION_KINDS` lists them in the order their columns
follow ``theta``: for every kind, joints 1..n.

The Coulomb law is smooth: ``tanh(qd / v_s)`` with a smoothing velocity ``v_s`` [rad/s] (``v_s = 0``
is ``sign(qd)``). ``sign`` flips with every zero crossing of velocity noise while a joint rests or
reverses, putting a full ``+-f_c`` square wave into the regressor that the torque does not show;
``tanh`` keeps the law's ``+-f_c`` plateaus away from rest and lets noise-level velocities give
noise-level friction. ``rc3r identify`` chooses ``v_s`` by cross-validation
(:mod:`rc3r.identify.selection`) and records it (``friction_law`` in identified.json,
``coulomb_velocity`` in bounds.toml's ``[identification]``) so that models and plants use the same
law (:func:`coulomb`).

A geared joint's rotor inertia ``I_a`` (Pinocchio's ``armature``) adds the column ``qdd_j``
(:data:`JOINT_KINDS`' ``armature``). Where the rigid regressor already holds that column (joint 1 about
the gravity axis: its rotor inertia and the link's ``ZZ`` are one coefficient) it is merged, not fitted
(:func:`merged_columns`, :func:`kept_columns`).
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError

__all__ = ["FRICTION_KINDS", "JOINT_KINDS", "ARMATURE_CHOICES", "coulomb", "COULOMB_LAW", "parse_friction",
           "friction_names", "friction_columns", "joint_columns", "identification_regressor", "merged_columns",
           "kept_columns", "MERGE_RTOL"]

#: Friction kinds and the prefix of their coefficient names.
FRICTION_KINDS = {"viscous": "fv", "coulomb": "fc", "offset": "f0"}

#: Every per-joint column kind, friction and the rotor inertia (``armature`` [kg m^2], Pinocchio's
#: ``model.armature``: the column is the joint's acceleration ``a_j``), and the prefix of their names.
#: Columns of several kinds follow ``theta`` in this order: for every kind, joints 1..n.
JOINT_KINDS = {**FRICTION_KINDS, "armature": "ia"}

#: ``rc3r identify --armature``: chosen by cross-validation (``auto``, the default), always or never fitted.
ARMATURE_CHOICES = ("auto", "on", "off")

#: An armature column whose distance to the span of the rigid regressor is below this share of its norm
#: (over random states) is merged into the rigid coefficients (:func:`merged_columns`).
MERGE_RTOL = 1e-8

#: The Coulomb law, as recorded in identified.json and bounds.toml.
COULOMB_LAW = "f_c tanh(qd / v_s) (sign(qd) when v_s = 0)"


def coulomb(qd, v_s: float = 0.0) -> np.ndarray:
    """The Coulomb column ``tanh(qd / v_s)`` (``sign(qd)`` for ``v_s = 0``) of velocities ``qd`` [rad/s]."""
    qd = np.asarray(qd, dtype=float)
    if v_s < 0:
        raise ConfigError(f"Coulomb smoothing velocity must be >= 0, got {v_s:g}")
    return np.sign(qd) if v_s == 0 else np.tanh(qd / float(v_s))


def parse_friction(text, table=FRICTION_KINDS, what: str = "friction kind") -> tuple[str, ...]:
    """``"viscous,coulomb"`` (or a sequence) -> ``("viscous", "coulomb")`` in ``table``'s order
    (:data:`FRICTION_KINDS`, or :data:`JOINT_KINDS` for the controller's joint coefficients).

    ``""`` or ``"none"`` give no columns; an unknown kind is a one-line ConfigError naming it as ``what``.
    """
    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text)]
    items = [s for s in items if s and s != "none"]
    bad = [s for s in items if s not in table]
    if bad:
        raise ConfigError(f"unknown {what}(s) {', '.join(bad)} (choose from {', '.join(table)})")
    return tuple(k for k in table if k in items)


def random_states(robot, states: int | None, seed: int):
    """``(Q, QD, QDD, Y)``: ``states`` (default ``max(20, 4 p)``) random states of ``robot``
    (``numpy.random.default_rng(seed)``; ``q`` in [-pi, pi], ``qd``, ``qdd`` in [-3, 3]), each (states, n), and
    the inverse-dynamics regressor ``Y(q, qd, qd, qdd)`` stacked to (states n, p)."""
    n, p = robot.n, robot.p
    states = int(states or max(20, 4 * p))
    rng = np.random.default_rng(seed)
    Q = rng.uniform(-np.pi, np.pi, (states, n))
    QD, QDD = rng.uniform(-3.0, 3.0, (2, states, n))
    return Q, QD, QDD, np.asarray(robot.regressor(Q, QD, QD, QDD), dtype=float).reshape(-1, p)


def friction_names(kinds, n: int) -> tuple[str, ...]:
    """``("fv1", ..., "fvn", "fc1", ..., "ia1", ...)`` for the kinds given (:data:`JOINT_KINDS`)."""
    return tuple(f"{JOINT_KINDS[k]}{j}" for k in kinds for j in range(1, n + 1))


def friction_columns(qd, kinds, v_s: float = 0.0) -> np.ndarray:
    """Friction regressor (N, n, n * len(kinds)) of velocities ``qd`` (N, n); Coulomb by :func:`coulomb`."""
    qd = np.atleast_2d(np.asarray(qd, dtype=float))
    N, n = qd.shape
    out = np.zeros((N, n, n * len(kinds)))
    idx = np.arange(n)
    for k, kind in enumerate(kinds):
        val = qd if kind == "viscous" else coulomb(qd, v_s) if kind == "coulomb" else np.ones_like(qd)
        out[:, idx, k * n + idx] = val
    return out


def joint_columns(qd, a, kinds, v_s: float = 0.0) -> np.ndarray:
    """Per-joint columns (N, n, n * len(kinds)) of velocities ``qd`` and accelerations ``a`` (N, n).

    ``kinds`` in :data:`JOINT_KINDS` order; ``viscous``: ``qd_j``, ``coulomb``: :func:`coulomb`,
    ``offset``: 1, ``armature``: ``a_j`` (the Slotine--Li reference acceleration in a control law,
    ``qdd`` in identification). Each column is nonzero only in its joint's row.
    """
    qd = np.atleast_2d(np.asarray(qd, dtype=float))
    a = np.atleast_2d(np.asarray(a, dtype=float))
    N, n = qd.shape
    out = np.zeros((N, n, n * len(kinds)))
    idx = np.arange(n)
    for k, kind in enumerate(kinds):
        if kind not in JOINT_KINDS:
            raise ConfigError(f"unknown joint column kind {kind!r} (choose from {', '.join(JOINT_KINDS)})")
        val = (qd if kind == "viscous" else coulomb(qd, v_s) if kind == "coulomb"
               else a if kind == "armature" else np.ones_like(qd))
        out[:, idx, k * n + idx] = val
    return out


def identification_regressor(robot, q, qd, qdd, kinds, v_s: float = 0.0, columns=None) -> np.ndarray:
    """``[Y(q, qd, qd, qdd) | joint columns]``, shape (N, n, p + n len(kinds)); ``v_s``: :func:`coulomb`.

    ``kinds`` in :data:`JOINT_KINDS` order (:func:`joint_columns`, the armature column is ``qdd``);
    ``columns``: only these joint columns (indices into the ``n len(kinds)`` of :func:`joint_columns`,
    :func:`kept_columns`), shape (N, n, p + len(columns)).
    """
    q, qd, qdd = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, qd, qdd))
    Y = np.asarray(robot.regressor(q, qd, qd, qdd), dtype=float)
    if Y.ndim == 2:
        Y = Y[None]
    F = joint_columns(qd, qdd, kinds, v_s)
    return np.concatenate([Y, F if columns is None else F[:, :, np.asarray(columns, dtype=int)]], axis=2)


def merged_columns(robot, seed: int = 0, states: int | None = None, rtol: float = MERGE_RTOL) -> dict:
    """The armature columns in the span of the rigid regressor: ``{joint j (0-based): coefficient index}``.

    The column of joint ``j``'s rotor inertia is ``qdd_j`` in its own row. When the rigid regressor ``Y``
    already holds it (joint 1 about the gravity axis: ``tau_1 = ZZ_1 qdd_1 + ...``, nothing else in the
    other rows) the two cannot be told apart by any log: the rotor inertia *merges* with that rigid
    coefficient (the one with the largest weight in the column's expansion is named). Tested on
    ``states`` random states (``numpy.random.default_rng(seed)``, ``q`` in [-pi, pi], ``qd``, ``qdd`` in
    [-3, 3]): a column whose least-squares distance to the span of ``Y`` is at most ``rtol`` of its norm.
    """
    n = robot.n
    Q, QD, QDD, Y = random_states(robot, states, seed)
    scale = np.linalg.norm(Y, axis=0)
    scale[scale == 0] = 1.0
    out = {}
    for j in range(n):
        c = np.zeros(QDD.shape)
        c[:, j] = QDD[:, j]
        c = c.ravel()
        coef = np.linalg.lstsq(Y / scale, c, rcond=None)[0]
        if np.linalg.norm(c - (Y / scale) @ coef) <= rtol * np.linalg.norm(c):
            out[j] = int(np.argmax(np.abs(coef / scale)))
    return out


def kept_columns(kinds, n: int, merged=()) -> np.ndarray:
    """Indices into :func:`joint_columns`' ``n len(kinds)`` columns of those fitted: all but the armature
    columns of the joints in ``merged`` (0-based; :func:`merged_columns`)."""
    kinds = tuple(kinds)
    drop = {kinds.index("armature") * n + j for j in merged} if "armature" in kinds else set()
    return np.array([c for c in range(n * len(kinds)) if c not in drop], dtype=int)
