r"""Exact bounds on theta for a payload of uncertain mass on the last link.

A payload is a rigid body of mass ``m`` [kg] in ``[m_lo, m_hi]`` with its centre of
mass at a known point ``c`` [m] of the last joint's frame and, optionally, a known
inertia ``I_c`` [kg m^2] about its CoM (default zero: a point mass). It adds to the
last body's standard parameters (Pinocchio's order about the joint origin,
:data:`rc3r.conventions.STD_KEYS`)

.. math::

    \delta\pi(m) = m\,w(c) + (0, 0, 0, 0, \iota(I_c)), \qquad
    w(c) = \bigl(1,\; c,\; \iota(|c|^2 \mathbf 1 - c c^T)\bigr),

with ``iota(I) = (Ixx, Ixy, Iyy, Ixz, Iyz, Izz)`` (parallel-axis theorem: the
inertia about the joint origin of a unit point mass at ``c``). theta is linear in the
standard parameters, ``theta = B pi`` (the robot's
:meth:`~rc3r.robots.base.Robot.theta_of_standard`), so the payload moves theta
along a **segment**

.. math::

    \theta(m) = \theta_{nom} + B(0, \iota(I_c)) + m\, B w, \qquad m \in [m_lo, m_hi],

and every bound of :class:`~rc3r.uncertainty.bounds.Bounds` is exact and attained at
an end of the segment: ``theta0 = theta(m_mid)``, ``rho = (m_hi - m_lo)/2 ||B w||``,
``rho_i = (m_hi - m_lo)/2 |B w|_i``, ``[theta_lo_i, theta_hi_i]`` the range of
``theta_i(m)``. ``theta_nominal`` is theta of the robot without payload.

The ``box`` field of the result is the bounding box of the segment in standard
parameters: the last body's 10 deltas each range over ``[min, max]`` of
``delta pi(m_lo)`` and ``delta pi(m_hi)``, all other deltas are zero. It contains the
segment but is larger (its deltas are coupled through ``m``); the bounds are
computed from the segment, not from the box.

The robot must use Pinocchio's standard parameters (names ``m, mcx, ..., Izz`` with
body numbers, as :class:`~rc3r.robots.pinocchio.PinocchioRobot`), the last body
being the last 10 of them.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..conventions import STD_KEYS
from .bounds import Bounds
from .box import Box, body_keys

__all__ = ["inertia_entries", "point_mass_parameters", "payload_parameters", "payload_bounds", "with_payload"]


def inertia_entries(I) -> np.ndarray:
    """``(Ixx, Ixy, Iyy, Ixz, Iyz, Izz)`` of a symmetric (3, 3) matrix (Pinocchio's order)."""
    I = np.asarray(I, dtype=float)
    return np.array([I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]])


def point_mass_parameters(com) -> np.ndarray:
    """``w(c)`` (10,): standard parameters of a unit point mass at ``c`` (3,) [m] about the origin."""
    c = np.asarray(com, dtype=float)
    return np.concatenate([[1.0], c, inertia_entries(c @ c * np.eye(3) - np.outer(c, c))])


def _inertia_matrix(inertia) -> np.ndarray:
    """(3, 3) from None (zero), a (3, 3) matrix or 6 entries ``(ixx, iyy, izz, ixy, ixz, iyz)`` (URDF order)."""
    if inertia is None:
        return np.zeros((3, 3))
    I = np.asarray(inertia, dtype=float)
    if I.shape == (6,):
        xx, yy, zz, xy, xz, yz = I
        I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    if I.shape != (3, 3) or not np.all(np.isfinite(I)) or not np.allclose(I, I.T, rtol=0, atol=1e-12 * abs(I).max()):
        raise ParameterError(f"payload inertia must be a symmetric 3x3 matrix or 6 entries, got {np.shape(inertia)}")
    return I


def payload_parameters(mass: float, com, inertia=None) -> np.ndarray:
    """Standard parameters (10,) of a payload: ``m w(c) + (0, 0, 0, 0, iota(I_c))``."""
    return mass * point_mass_parameters(com) + np.concatenate([np.zeros(4), inertia_entries(_inertia_matrix(inertia))])


def _check(robot, mass, com, inertia, frame):
    """Validate; return ``(m_lo, m_hi, c, I_c)`` with ``c, I_c`` in the last joint's frame."""
    keys = tuple(k.lower() for k in body_keys(robot.standard_parameter_names))
    if keys != tuple(k.lower() for k in STD_KEYS):
        raise ParameterError(f"payload bounds need Pinocchio's standard parameters ({', '.join(STD_KEYS)}); "
                             f"robot '{robot.name}' has {', '.join(keys)}")
    try:
        lo, hi = (float(x) for x in (mass if np.ndim(mass) else (mass, mass)))
    except (TypeError, ValueError):
        raise ParameterError(f"payload mass must be a number or (lower, upper) [kg], got {mass!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 <= lo <= hi):
        raise ParameterError(f"payload mass interval must satisfy 0 <= lower <= upper, got [{lo:g}, {hi:g}] kg")
    c = np.asarray(com, dtype=float)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ParameterError(f"payload CoM must be 3 finite numbers [m], got {com!r}")
    I = _inertia_matrix(inertia)
    if frame is not None:
        model = robot.model
        if not model.existFrame(frame):
            raise ParameterError(f"robot has no frame {frame!r}")
        f = model.frames[model.getFrameId(frame)]
        if f.parentJoint != model.njoints - 1:
            raise ParameterError(f"frame {frame!r} is not attached to the last joint '{model.names[model.njoints - 1]}'")
        R, p = np.array(f.placement.rotation), np.array(f.placement.translation)
        c, I = R @ c + p, R @ I @ R.T
    return lo, hi, c, I


def payload_bounds(robot, mass, com, inertia=None, frame: str | None = None) -> Bounds:
    r"""Exact theta_0, rho, rho_i and ranges for a payload of mass in ``mass`` at ``com``.

    Parameters
    ----------
    robot : Robot
        Nominal robot (without payload), Pinocchio standard parameters.
    mass : float or (float, float)
        Payload mass interval ``(m_lo, m_hi)`` [kg], ``0 <= m_lo <= m_hi``.
    com : (3,) array_like
        Payload CoM [m] in the last joint's frame (or in ``frame``).
    inertia : (3, 3) or (6,) array_like, optional
        Payload inertia about its CoM [kg m^2] (6 entries in URDF order
        ``ixx, iyy, izz, ixy, ixz, iyz``); default zero (point mass).
    frame : str, optional
        A Pinocchio frame of ``robot.model`` attached to the last joint (e.g. a
        tool frame) in which ``com`` and ``inertia`` are given.

    Returns
    -------
    Bounds
        ``method="payload"``, fields as in the module docstring; ``witness_lo`` /
        ``witness_hi`` (p, 10 nb) are the standard parameters (nominal plus
        payload of mass ``m_lo`` or ``m_hi``) at which each ``theta_i`` attains
        ``theta_lo[i]`` / ``theta_hi[i]``.
    """
    lo, hi, c, I = _check(robot, mass, com, inertia, frame)
    std = np.asarray(robot.standard_parameters(), dtype=float)
    size = std.size
    ends = np.zeros((2, size))
    ends[0, -10:] = payload_parameters(lo, c, I)
    ends[1, -10:] = payload_parameters(hi, c, I)
    th_ends = robot.theta_of_standard(std + ends)  # (2, p): theta(m_lo), theta(m_hi)
    half = 0.5 * (hi - lo) * np.abs(robot.theta_of_standard(np.concatenate([np.zeros(size - 10),
                                                                             point_mass_parameters(c)])))
    lo_at_hi = th_ends[1] < th_ends[0]
    box = Box(ends.min(axis=0), ends.max(axis=0), robot.standard_parameter_names,
              source=f"payload m in [{lo:g}, {hi:g}] kg at c = {c.tolist()} m")
    return Bounds(
        method="payload",
        theta0=0.5 * (th_ends[0] + th_ends[1]),
        rho=float(np.linalg.norm(half)),
        rho_i=half,
        theta_lo=th_ends.min(axis=0),
        theta_hi=th_ends.max(axis=0),
        box=box,
        theta_nominal=np.asarray(robot.theta, dtype=float),
        witness_lo=std + ends[np.where(lo_at_hi, 1, 0)],
        witness_hi=std + ends[np.where(lo_at_hi, 0, 1)],
    )


def with_payload(robot, mass: float, com, inertia=None, frame: str | None = None, label: str | None = None):
    """``robot`` carrying a payload of ``mass`` [kg] at ``com`` [m] (last joint's frame, or ``frame``).

    For a robot with ``with_model`` (:class:`~rc3r.robots.pinocchio.PinocchioRobot`)
    the last joint's ``pinocchio.Inertia`` gets ``pinocchio.Inertia(mass, com, I_c)``
    added (Pinocchio's own sum of rigid bodies); otherwise the payload's standard
    parameters are added to the last body's (:meth:`Robot.with_standard_parameters`).
    """
    lo, _, c, I = _check(robot, mass, com, inertia, frame)
    label = label or f"{robot.label}+payload({lo:g} kg)"
    if robot.with_model is not None:
        import pinocchio as pin

        model = robot.model.copy()
        last = model.njoints - 1
        model.inertias[last] = model.inertias[last] + pin.Inertia(lo, c, I)
        return robot.with_model(model, label)
    std = np.asarray(robot.standard_parameters(), dtype=float).copy()
    std[-10:] += payload_parameters(lo, c, I)
    return robot.with_standard_parameters(std, label)
