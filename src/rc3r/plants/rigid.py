r"""The rigid-body contract of a plant: :class:`RigidBody`, what :attr:`rc3r.plants.Plant.rigid` provides.

Two kinds implement it:

* a :class:`~rc3r.robots.base.Robot` (the closed form, Pinocchio's ABA): a rigid body that is also a
  model, with ``p``, ``theta`` and the Slotine--Li regressor, and possibly a compiled kernel supply
  (:attr:`~rc3r.robots.base.Robot.compiled_kernels`);
* :class:`~rc3r.plants.mujoco.MujocoRigidBody`: MuJoCo's dynamics of a URDF, no coefficients
  (``p`` and ``theta`` are None: MuJoCo reads the masses from the file), no regressor, and an
  :meth:`advance` that integrates a held torque itself (its own RK4 at a fine step).

What every rigid body provides
    ``n`` (joints), ``label`` (where its parameters came from), ``name`` (a registry or engine name),
    :meth:`RigidBody.forward_dynamics` (:math:`\ddot q` under a joint torque),
    :meth:`RigidBody.mass_matrix`, :meth:`RigidBody.describe`.
Declared with their defaults (read directly, never probed)
    ``p`` and ``theta`` (None: no coefficients), ``advance`` (None: the engine integrates
    :meth:`forward_dynamics`; else ``advance(q, qd, u, T) -> (q, qd)`` under the torque ``u`` held
    for ``T`` seconds: the sampled ``python`` engine then calls it, and joint-torque effects such as
    friction are refused), ``compiled_kernels`` (None: no compiled simulator).

A controller's model must be a :class:`~rc3r.robots.base.Robot` (it needs the regressor); the plant's
rigid body need only be a :class:`RigidBody`.
"""
from __future__ import annotations

import abc

import numpy as np

__all__ = ["RigidBody"]


class RigidBody(abc.ABC):
    """Abstract base of a plant's rigid body (module docstring: what to implement, what is optional)."""

    #: A registry or engine name.
    name: str = "?"
    #: Number of coefficients, or None for a rigid body without them (MuJoCo).
    p = None
    #: The true coefficients (p,), or None for a rigid body without them (MuJoCo).
    theta = None
    #: ``advance(q, qd, u, T) -> (q, qd)``: the rigid body integrates a held torque itself; None: it does not.
    advance = None
    #: ``(module, kc)`` of the compiled engine's kernel supply, or None (no compiled simulator).
    compiled_kernels = None

    @property
    @abc.abstractmethod
    def n(self) -> int:
        """Number of joints (size of q)."""

    @property
    @abc.abstractmethod
    def label(self) -> str:
        """Where this rigid body's parameters came from (a URDF path, ``nominal``, ``random:7`` ...)."""

    @abc.abstractmethod
    def forward_dynamics(self, q, qd, u) -> np.ndarray:
        r"""Joint accelerations :math:`\ddot q` (n,) [rad/s^2] under the joint torque ``u`` (n,) [N m]."""

    @abc.abstractmethod
    def mass_matrix(self, q) -> np.ndarray:
        """M(q), (n, n)."""

    @abc.abstractmethod
    def describe(self) -> dict:
        """JSON-ready identification (``metrics.json``)."""
