"""The paper's 3R spatial arm: everything that names it lives in this package.

* :mod:`.params` -- link parameters (paper convention), theta (section 3.1.1), Table 1;
* :mod:`.kernels` -- compiled closed-form M, S, g, Y (numba);
* :mod:`.model`, :mod:`.regressor` -- NumPy-facing closed forms;
* :mod:`.urdf` -- URDF writer/reader with the DH structure checks;
* :mod:`.robot` -- :class:`RR3`, the :class:`~rc3r.robots.base.Robot` implementation;
* :mod:`.engine` -- the kernel supply of the compiled closed-loop simulator;
* :mod:`.paper` -- the paper's box, gains, trajectory, five scenarios and claims.
"""
from .robot import RR3

__all__ = ["RR3"]
