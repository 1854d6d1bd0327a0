"""What :mod:`rc3r.robots.generated` generates and from what: the functions (:data:`FUNCTIONS`) and a
chain's kinematic constants (:class:`Chain`), read by both the generator and its symbolic recursions
(:mod:`rc3r.robots.generated_sym`). Its text enters the generated kernels' cache key."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FUNCTIONS", "Chain"]

#: The generated functions and their inputs, in this order.
FUNCTIONS = {
    "rnea": ("q", "qd", "qdd"),
    "slotine_li": ("q", "qd", "v", "a"),
    "mass": ("q",),
    "coriolis": ("q", "qd"),
    "gravity": ("q",),
    "aba": ("q", "qd", "tau"),
}


@dataclass(frozen=True)
class Chain:
    """The kinematic constants of a chain of 1-DoF joints (read by :func:`chain_constants`).

    Attributes
    ----------
    parent : numpy.ndarray
        (n,) int: joint index of each joint's parent, -1 for the base.
    revolute : numpy.ndarray
        (n,) bool: revolute (else prismatic).
    R0, p0 : numpy.ndarray
        (n, 3, 3), (n, 3): each joint's fixed placement in its parent's frame [-, m].
    axis : numpy.ndarray
        (n, 3): unit axis in the joint's own frame.
    gravity : numpy.ndarray
        (6,): ``model.gravity`` (linear [m/s^2], angular), in the base frame.
    pi : numpy.ndarray
        (n, 10): standard parameters (Pinocchio's order), about each joint-frame origin.
    """

    parent: np.ndarray
    revolute: np.ndarray
    R0: np.ndarray
    p0: np.ndarray
    axis: np.ndarray
    gravity: np.ndarray
    pi: np.ndarray

    @property
    def n(self) -> int:
        return int(self.parent.size)

    def digest_bytes(self) -> bytes:
        """The float64/int64 bytes of every constant (the cache key's model part)."""
        parts = [self.parent.astype(np.int64), self.revolute.astype(np.int64), self.R0, self.p0, self.axis,
                 self.gravity, self.pi]
        return b"".join(np.ascontiguousarray(x, dtype=np.int64 if x.dtype.kind in "ib" else np.float64).tobytes()
                        for x in parts)
