r"""The paper's 3R spatial arm as a :class:`~rc3r.robots.base.Robot`.

Closed-form model (:mod:`.model`), regressor (:mod:`.regressor`) and compiled
kernels (:mod:`.kernels`) in the paper's 15 coefficients; the Pinocchio model of
the same parameters (through :mod:`.urdf`) is the ground-truth plant; the compiled
kernel supply of the compiled engine is :mod:`.engine`.
"""
from __future__ import annotations

from functools import cached_property
from pathlib import Path

import numpy as np

from ..base import Robot
from . import model as _model
from . import regressor as _reg
from . import engine as _engine
from .params import PARAM_NAMES, ArmParams, physical_issues, table1, theta, theta_from_vector

__all__ = ["RR3", "COEFFICIENT_NAMES"]  # PARAM_NAMES (imported here too): rc3r.robots.rr3.params

#: Names of the 15 coefficients (paper order, section 3.1.1).
COEFFICIENT_NAMES = tuple(f"theta{i}" for i in range(1, 16))


class RR3(Robot):
    """The 3R arm with one parameter set (paper convention, :class:`ArmParams`).

    Parameters
    ----------
    params : ArmParams
        Link lengths, masses, CoMs and inertias (docs/conventions.md).
    label : str
        Where this parameter set came from.
    model : pinocchio.Model, optional
        Its Pinocchio model (built from ``params`` through the generated URDF if
        omitted); gravity ``(0, 0, -g0)``.
    urdf : str, optional
        The URDF it was read from, if any.
    """

    name = "rr3"
    #: What theta's entries are (``verify-model`` prints it).
    theta_order = "paper order, section 3.1.1"

    @property
    def compiled_kernels(self) -> tuple[str, np.ndarray]:
        """``(module, kc)``: the kernel supply :mod:`.engine` and its constants ``[theta, l2, g0]``."""
        return _engine.ENGINE, _engine.pack(self)

    def __init__(self, params: ArmParams, label: str = "nominal", model=None, urdf: str | None = None):
        self.params = params
        self._label = label
        self._model = model
        self.urdf = urdf

    # ---- construction -----------------------------------------------------------------
    @classmethod
    def nominal(cls) -> "RR3":
        """Table 1 of the paper."""
        return cls(table1(), "nominal")

    @classmethod
    def from_params(cls, params: ArmParams, label: str = "nominal") -> "RR3":
        """A plant of parameters ``params``; ParameterError for a mass <= 0 or a non-PD inertia."""
        robot = cls(params, label)
        robot.require_simulable()
        return robot

    @classmethod
    def from_urdf(cls, path=None, label: str | None = None) -> "RR3":
        """A URDF of this arm (default: the committed ``urdf/rr3.urdf``); UrdfError if it is not."""
        from .urdf import load_arm

        arm = load_arm(path)
        return cls(arm.params, label or arm.path, arm.model, urdf=arm.path)

    @classmethod
    def from_params_file(cls, path, label: str | None = None) -> "RR3":
        """A parameter TOML (format of ``rc3r/robots/rr3/data/rr3.toml``)."""
        from .params import load_params

        return cls(load_params(path), label or str(path))

    @classmethod
    def make_urdf(cls, params_path, out):
        """Write the URDF of a parameter TOML (default Table 1) to ``out``; return its path."""
        from .params import load_params
        from .urdf import write_urdf

        return write_urdf(load_params(params_path) if params_path else table1(), out)

    def mujoco_urdf(self):
        """The URDF MuJoCo simulates for this arm: the physically consistent arm with Table 1's theta
        (``data/rr3_consistent.toml``, docs/model.md; MuJoCo refuses Table 1 itself), written once into
        the user's cache; None unless this is the nominal parameter set (its theta is Table 1's)."""
        import os
        import tempfile

        from .params import theta

        if not np.allclose(self.theta, theta(table1()), rtol=0, atol=1e-12):
            return None
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rc3r"
        try:
            base.mkdir(parents=True, exist_ok=True)
        except OSError:
            base = Path(tempfile.gettempdir())
        import hashlib

        params = Path(__file__).parent / "data" / "rr3_consistent.toml"
        out = base / f"rr3_consistent-{hashlib.sha256(params.read_bytes()).hexdigest()[:12]}.urdf"
        if not out.is_file():
            self.make_urdf(params, out)
        return out

    @classmethod
    def default_box(cls):
        """The paper's box (section 4)."""
        from .paper import paper_box

        return paper_box()

    @classmethod
    def default_trajectory(cls):
        r"""The paper's :math:`q_d = (\sin t, 5\cos t, \sin t)`."""
        from .paper import paper_trajectory

        return paper_trajectory()

    # ---- sizes and parameters ---------------------------------------------------------
    n = 3
    p = 15
    coefficient_names = COEFFICIENT_NAMES
    standard_parameter_names = PARAM_NAMES

    @cached_property
    def theta(self) -> np.ndarray:
        """The 15 coefficients of section 3.1.1 (read-only)."""
        th = theta(self.params)
        th.flags.writeable = False
        return th

    @property
    def label(self) -> str:
        return self._label

    @property
    def model(self):
        if self._model is None:
            from .urdf import model_from_params

            self._model = model_from_params(self.params)
        return self._model

    @property
    def joint_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """The URDF's limits (the generated arm has +-1000 rad: the paper's arm is unlimited)."""
        m = self.model
        return np.array(m.lowerPositionLimit), np.array(m.upperPositionLimit)

    @property
    def l2(self) -> float:
        """DH length a2 [m]: the kinematic constant in the gravity columns of Y."""
        return self.params.lengths[1]

    # ---- dynamics ---------------------------------------------------------------------
    def regressor(self, q, qd, v, a) -> np.ndarray:
        return _reg.slotine_li_regressor(q, qd, v, a, l2=self.l2, g0=self.params.g0)

    def mass_matrix(self, q) -> np.ndarray:
        return _model.mass_matrix(self.theta, q)

    def coriolis_matrix(self, q, qd) -> np.ndarray:
        return _model.coriolis_matrix(self.theta, q, qd)

    def gravity(self, q) -> np.ndarray:
        return _model.gravity(self.theta, q, l2=self.l2, g0=self.params.g0)

    def forward_dynamics(self, q, qd, u) -> np.ndarray:
        """Joint accelerations (3,) by Pinocchio's ABA (the ground-truth plant)."""
        import pinocchio as pin

        data = self._data()
        return np.array(pin.aba(self.model, data, np.asarray(q, float), np.asarray(qd, float),
                                np.asarray(u, float)))

    def forward_dynamics_closed_form(self, q, qd, u) -> np.ndarray:
        """Joint accelerations (3,) from the compiled closed form (the fast engine's plant)."""
        from . import kernels as K

        qdd = np.empty(3)
        ok = K.forward_dynamics_into(np.ascontiguousarray(self.theta), np.asarray(q, float),
                                     np.asarray(qd, float), np.asarray(u, float), self.l2,
                                     self.params.g0, qdd, np.empty((3, 3)), np.empty(3))
        if not ok:
            raise FloatingPointError("closed-form mass matrix is not positive definite")
        return qdd

    def c_regressor_source(self) -> str:
        """The closed-form Slotine--Li regressor as C99 source, for ``rc3r export`` (:mod:`.c_kernels`)."""
        from .c_kernels import c_regressor_source

        return c_regressor_source(self)

    def _data(self):
        if getattr(self, "_pin_data", None) is None:
            self._pin_data = self.model.createData()
        return self._pin_data

    # ---- parameter sets ---------------------------------------------------------------
    def standard_parameters(self) -> np.ndarray:
        return self.params.to_vector()

    def theta_of_standard(self, std) -> np.ndarray:
        return theta_from_vector(std, self.params.lengths)

    def with_standard_parameters(self, std, label: str) -> "RR3":
        p = self.params
        return RR3(ArmParams.from_vector(std, p.lengths, p.g0, name=p.name), label)

    def physical_issues(self) -> list[str]:
        return physical_issues(self.params)

    def describe(self) -> dict:
        out = super().describe()
        if self.urdf:
            out["urdf"] = str(Path(self.urdf))
        return out

    def __getstate__(self):  # pinocchio Data is rebuilt after unpickling
        state = dict(self.__dict__)
        state.pop("_pin_data", None)
        return state
