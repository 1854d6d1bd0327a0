r"""The robot contract: what every robot gives the rest of rc3r.

A :class:`Robot` is a kinematic structure together with one set of dynamic
parameters. The same class serves as the **plant** (the true robot being
simulated) and as the **nominal model** a controller is designed from; a
controller never reads the plant's parameters, it sees the plant only through
the Slotine--Li regressor :math:`Y(q, \dot q, v, a)`, which depends on the
kinematics alone:

.. math::

    Y(q, \dot q, v, a)\,\theta = M(q)\,a + C(q, \dot q)\,v + g(q),

with :math:`C` the Christoffel-symbol factorization (so :math:`\dot M - 2C` is
skew-symmetric) and :math:`\theta` the robot's :attr:`Robot.theta`.

To add a robot, subclass :class:`Robot` and implement (in the style of SciPy's
``OdeSolver``):

Attributes
    ``name`` (str, class attribute: the registry name), ``n`` (joints),
    ``p`` (coefficients), ``theta`` (p,), ``coefficient_names`` (p str),
    ``joint_limits`` ((n,), (n,) [rad]), ``label`` (where this parameter set
    came from), ``model`` (a ``pinocchio.Model`` with the same parameters and
    gravity: the ground truth the tests and ``verify-model`` compare with).
Methods
    :meth:`Robot.regressor` (Slotine--Li Y), :meth:`Robot.mass_matrix`,
    :meth:`Robot.coriolis_matrix`, :meth:`Robot.gravity` (the model terms,
    however the robot computes them), :meth:`Robot.forward_dynamics` (the plant),
    and, for boxes of parameter uncertainty, :meth:`Robot.standard_parameters`,
    :attr:`Robot.standard_parameter_names`, :meth:`Robot.theta_of_standard`,
    :meth:`Robot.with_standard_parameters`, :meth:`Robot.physical_issues`.
Optional
    Declared here with their defaults (None, False or a neutral value), so that a caller reads the
    attribute directly and a robot that has the capability overrides it (no ``getattr`` probes;
    ``tests/test_contracts.py`` counts them):

    * :attr:`Robot.compiled_kernels`: the kernel supply of the compiled engine (see
      :mod:`rc3r.robots.rr3.engine` for the 3R's), from which :func:`rc3r.simulate._fast.simulator`
      builds its simulator; None: the generic Python engine (any law, continuous or sampled time);
    * :attr:`Robot.urdf`, :attr:`Robot.locked`, :attr:`Robot.joint_names`, :attr:`Robot.robot_name`:
      the URDF file of this parameter set, its joints fixed at a value, the joint names in ``q``
      order, the arm's own name; None;
    * :attr:`Robot.base`, :attr:`Robot.kernel`: numerical base parameters of a robot whose theta is
      in them, a serial chain's compiled regressor; None;
    * :attr:`Robot.linear_in_standard_parameters`, :attr:`Robot.model_terms_are_pinocchio`: exact
      bounds by linear programming, M, C, g are Pinocchio's own; False;
    * :attr:`Robot.theta_order`: the order of theta in words (``verify-model``);
    * :attr:`Robot.mujoco_urdf`, :attr:`Robot.c_regressor_source`, :attr:`Robot.with_model`,
      :attr:`Robot.regressor_pinocchio`, :attr:`Robot.advance`: methods a robot may have (the URDF
      MuJoCo compiles, its own C99 regressor, itself on another ``pinocchio.Model``, Pinocchio's own
      regressor, its own integration of a held torque); None where it has not;
    * :meth:`Robot.default_trajectory_warnings`: what the default trajectory could not follow; [].

    A robot is the plant's rigid body too: it implements :class:`rc3r.plants.RigidBody`.

Then register the class in :data:`rc3r.robots.ROBOTS`. Nothing outside a
robot's own package may name it: the control laws, the simulator, the bounds and
the command line use only this contract.

Shapes: states ``q, qd, v, a, u`` are (n,) [rad, rad/s, rad/s, rad/s^2, N m];
batched methods accept (N, n) and return a leading axis N.
"""
from __future__ import annotations

import abc

import numpy as np

from ..plants.rigid import RigidBody

__all__ = ["Robot", "kinematics_differ", "stack_states"]


class Robot(RigidBody):
    """Abstract base of every robot (module docstring: what to implement); a plant's rigid body
    (:class:`~rc3r.plants.RigidBody`) that is also a controller's model."""

    #: Registry name (``rc3r.robots.ROBOTS``).
    name: str = "?"

    # ---- sizes and parameters --------------------------------------------------------

    @property
    @abc.abstractmethod
    def n(self) -> int:
        """Number of joints (size of q)."""

    @property
    @abc.abstractmethod
    def p(self) -> int:
        """Number of dynamic coefficients (size of theta, columns of Y)."""

    @property
    @abc.abstractmethod
    def theta(self) -> np.ndarray:
        """This parameter set's coefficients, shape (p,)."""

    @property
    @abc.abstractmethod
    def coefficient_names(self) -> tuple[str, ...]:
        """Names of the p coefficients, in order."""

    @property
    @abc.abstractmethod
    def label(self) -> str:
        """Where this parameter set came from (``nominal``, ``random:7``, a URDF path ...)."""

    @property
    @abc.abstractmethod
    def joint_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Position limits ``(lower, upper)``, each (n,) [rad]."""

    @property
    @abc.abstractmethod
    def model(self):
        """``pinocchio.Model`` of this robot with the same parameters and gravity."""

    # ---- dynamics ---------------------------------------------------------------------

    @abc.abstractmethod
    def regressor(self, q, qd, v, a) -> np.ndarray:
        r"""Slotine--Li regressor, (n, p) or (N, n, p).

        Identity: ``regressor(q, qd, v, a) @ theta == M(q) a + C(q, qd) v + g(q)``.
        """

    @abc.abstractmethod
    def mass_matrix(self, q) -> np.ndarray:
        """M(q), (n, n) or (N, n, n)."""

    @abc.abstractmethod
    def coriolis_matrix(self, q, qd) -> np.ndarray:
        r"""Christoffel factorization :math:`C(q, \dot q)`, (n, n) or (N, n, n)."""

    @abc.abstractmethod
    def gravity(self, q) -> np.ndarray:
        """g(q), (n,) or (N, n) [N m]."""

    @abc.abstractmethod
    def forward_dynamics(self, q, qd, u) -> np.ndarray:
        r"""Joint accelerations :math:`\ddot q = M^{-1}(u - C\dot q - g)`, (n,) [rad/s^2]."""

    # ---- parameter sets (boxes of uncertainty) ------------------------------------

    @property
    @abc.abstractmethod
    def standard_parameter_names(self) -> tuple[str, ...]:
        """Names of the standard parameters (10 per moving body), in vector order."""

    @abc.abstractmethod
    def standard_parameters(self) -> np.ndarray:
        """This parameter set as standard parameters, (10 * bodies,)."""

    @abc.abstractmethod
    def theta_of_standard(self, std) -> np.ndarray:
        """theta of standard-parameter vectors, (..., 10 * bodies) -> (..., p) (same kinematics)."""

    @abc.abstractmethod
    def with_standard_parameters(self, std, label: str) -> "Robot":
        """The same robot with other standard parameters (a perturbed plant)."""

    @abc.abstractmethod
    def physical_issues(self) -> list[str]:
        """Physical-consistency problems (mass <= 0, inertia not PD, triangle inequality)."""

    def require_simulable(self) -> None:
        """Raise :class:`~rc3r.errors.ParameterError` for a mass <= 0 or a non-PD inertia.

        The triangle inequality is only warned about (the paper's Table 1 violates it).
        """
        from ..errors import ParameterError

        for issue in self.physical_issues():
            if "triangle" not in issue:
                raise ParameterError(issue)

    # ---- optional capabilities (module docstring): read directly, overridden where a robot has one ----

    #: ``(module, kc)``: the compiled engine's kernel supply (a dotted module name, contract
    #: :mod:`rc3r.simulate.engines._template`) and its packed constants, or None (generic Python engine).
    compiled_kernels = None
    #: The URDF file this parameter set was read from, or None.
    urdf: str | None = None
    #: Joints fixed at a value, ``{name: value}`` [rad or m], or None.
    locked: dict | None = None
    #: Joint names in ``q`` order, or None.
    joint_names: tuple | None = None
    #: The arm's own name (a URDF's ``<robot name>``), or None (then :attr:`name` names it).
    robot_name: str | None = None
    #: Numerical base parameters (``BaseParameters``: ``independent`` columns, ``T`` with
    #: ``theta = T @ pi``) of a robot whose theta is in base parameters, or None.
    base = None
    #: A serial chain's compiled Slotine--Li regressor (``ChainKernel``), or None.
    kernel = None
    #: True if theta is linear in the standard parameters (exact bounds by linear programming).
    linear_in_standard_parameters: bool = False
    #: True if M, C and g are Pinocchio's own (``verify-model`` then compares nothing with itself).
    model_terms_are_pinocchio: bool = False
    #: The order of theta, in words (``verify-model``'s report).
    theta_order: str = "the robot's coefficient order (coefficient_names)"
    #: ``mujoco_urdf() -> path or None``: the URDF MuJoCo compiles for this robot (None from the method:
    #: this parameter set is no URDF's); None here: MuJoCo reads :attr:`urdf`.
    mujoco_urdf = None
    #: ``c_regressor_source() -> str``: the robot's own C99 regressor for ``rc3r export``; None here: the
    #: generic chain of :attr:`kernel`.
    c_regressor_source = None
    #: ``with_model(model, label) -> Robot``: the same robot on another ``pinocchio.Model`` (a payload added
    #: by Pinocchio's own sum of inertias); None: not supported.
    with_model = None
    #: ``regressor_pinocchio(q, qd, v, a, standard=False)``: Pinocchio's own regressor; None.
    regressor_pinocchio = None
    def default_trajectory_warnings(self) -> list[str]:
        """What the robot's default trajectory could not follow (degenerate joint limits ...); none here."""
        return []

    def describe(self) -> dict:
        """JSON-ready identification of this robot (name, label, n, p)."""
        return {"robot": self.name, "label": self.label, "n": self.n, "p": self.p}

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r} n={self.n} p={self.p} label={self.label!r}>"


def kinematics_differ(a: Robot, b: Robot, seed: int = 0, rtol: float = 1e-9) -> str | None:
    """Why robots ``a`` and ``b`` do not share their kinematics, or None if they do.

    Same n and p, and the same regressor ``Y(q, qd, v, a)`` at three states drawn from
    ``numpy.random.default_rng(seed)`` (q in [-pi, pi], the rest in [-2, 2]) to ``rtol`` relative
    to the largest entry: Y depends on the kinematics and gravity only, so a plant built from the
    same URDF with other inertias passes, a UR10 plant under a UR5 model does not.
    """
    if a.n != b.n:
        return f"{b.n} joints, the model has {a.n}"
    if a.p != b.p:
        return f"{b.p} base parameters, the model has {a.p}"
    rng = np.random.default_rng(seed)
    for _ in range(3):
        q = rng.uniform(-np.pi, np.pi, a.n)
        qd, v, acc = rng.uniform(-2.0, 2.0, (3, a.n))
        ya, yb = a.regressor(q, qd, v, acc), b.regressor(q, qd, v, acc)
        scale = max(float(np.abs(ya).max()), 1e-12)
        if not np.allclose(ya, yb, rtol=0.0, atol=rtol * scale):
            return (f"its regressor differs from the model's by {float(np.abs(ya - yb).max()):.3g} "
                    f"(relative {float(np.abs(ya - yb).max()) / scale:.2g}) at a random state: another kinematic "
                    "structure or gravity")
    return None


def stack_states(n: int, *xs) -> tuple[bool, np.ndarray]:
    """``(single, X)``: the (n,) or (N, n) arrays ``xs`` (broadcast if their shapes differ) stacked into
    one C-contiguous float64 ``X`` of shape (len(xs), N, n) (N = 1 for (n,) inputs); ``single`` is
    True for (n,) inputs. ValueError for any other shape."""
    xs = [np.asarray(x, dtype=float) for x in xs]
    if any(x.shape != xs[0].shape for x in xs):
        xs = np.broadcast_arrays(*xs)
    shape = xs[0].shape
    if shape[-1:] != (n,) or len(shape) > 2:
        raise ValueError(f"states must have shape ({n},) or (N, {n}), got {shape}")
    X = np.empty((len(xs),) + (shape if len(shape) == 2 else (1, n)))
    for k, x in enumerate(xs):
        X[k] = x
    return len(shape) == 1, X
