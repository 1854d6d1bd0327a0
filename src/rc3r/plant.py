r"""Plants: the robot being controlled, as a Pinocchio model (ground truth).

A :class:`Plant` holds the arm's parameters and its Pinocchio model; forward
dynamics is Pinocchio's ABA, :math:`\ddot q = M^{-1}(u - c - g)`.
:meth:`Plant.forward_dynamics_closed_form` is the compiled closed form on the
plant's own theta, which the fast simulator uses; ``tests/test_plant.py`` shows it
equals ABA at random states and follows the ABA plant over a whole run.
Perturbed plants come from :func:`rc3r.uncertainty.perturb` (box corners, seeded
random draws) or from any URDF of this arm.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _kernels as K
from .params import ArmParams, require_simulable, theta

__all__ = ["Plant"]


@dataclass(frozen=True, eq=False)
class Plant:
    """A simulated robot.

    Attributes
    ----------
    params : ArmParams
        Its parameters (paper convention).
    model : pinocchio.Model
        Pinocchio model, nq = 3, gravity (0, 0, -g0).
    label : str
        Where it came from (``nominal``, ``upper``, ``random:7``, a URDF path ...).
    """

    params: ArmParams
    model: object
    label: str = "nominal"

    @classmethod
    def from_params(cls, p: ArmParams, label: str = "nominal") -> "Plant":
        """Plant of parameters ``p``; ParameterError if a mass <= 0 or an inertia is not PD."""
        from .urdf import model_from_params

        require_simulable(p)
        return cls(p, model_from_params(p), label)

    @classmethod
    def from_urdf(cls, path, label: str | None = None) -> "Plant":
        """Plant of a URDF of this arm (UrdfError if it is not this arm)."""
        from .urdf import load_arm

        arm = load_arm(path)
        require_simulable(arm.params)
        return cls(arm.params, arm.model, label or str(path))

    @property
    def theta(self) -> np.ndarray:
        """The plant's true coefficients (15,) -- for the fast simulator and ideal scenarios."""
        return theta(self.params)

    def forward_dynamics(self, q, qd, u) -> np.ndarray:
        """Joint accelerations (3,) [rad/s^2] by Pinocchio's ABA."""
        import pinocchio as pin

        data = self.model.createData()
        return np.array(pin.aba(self.model, data, np.asarray(q, float), np.asarray(qd, float),
                                np.asarray(u, float)))

    def forward_dynamics_closed_form(self, q, qd, u) -> np.ndarray:
        """Joint accelerations (3,) from the closed form on :attr:`theta` (compiled)."""
        qdd = np.empty(3)
        ok = K.forward_dynamics_into(self.theta, np.asarray(q, float), np.asarray(qd, float),
                                     np.asarray(u, float), self.params.lengths[1], self.params.g0,
                                     qdd, np.empty((3, 3)), np.empty(3))
        if not ok:
            raise FloatingPointError("closed-form mass matrix is not positive definite")
        return qdd
