r"""Joint-space tracking laws behind one interface, and their registry.

Every law here is :math:`u = Y(q, \dot q, v, a)\,\theta_{\mathrm{eff}} + w`: it sees
the robot only through the Slotine--Li regressor ``Y`` (shape (n, p)), so one law
serves every robot. With :math:`e = q - q_d`:

* :class:`FeedbackLinearization` (``fbl``) -- computed torque,
  :math:`v = \dot q`, :math:`a = \ddot q_d - K_d \dot e - K_p e`, :math:`w = 0`.
* :class:`Robust` (``robust``) -- Spong's law, eqs. (3)-(6):
  :math:`v = \dot q_d - \Lambda e`, :math:`a = \ddot q_d - \Lambda \dot e`,
  :math:`r = \dot q - v`, :math:`\theta_{\mathrm{eff}} = \theta_0 + \delta`,
  :math:`\delta = -\rho\, Y^T r / \max(\|Y^T r\|, \epsilon)`, :math:`w = -K r`.
* :class:`RobustPerCoefficient` (``robust-coeff``) -- eq. (7):
  :math:`\delta_i = -\rho_i\, \xi_i / \max(|\xi_i|, \epsilon_i)`, :math:`\xi = Y^T r`.
* :class:`Adaptive` (``adaptive``) -- Slotine--Li: :math:`\theta_{\mathrm{eff}} = \hat\theta`,
  :math:`\dot{\hat\theta} = -\Gamma Y^T r` (controller state :math:`\hat\theta`).
* :class:`PDGravity` (``pd``) -- :math:`v = a = 0` (so :math:`Y\theta = g(q)`),
  :math:`w = -K_p e - K_d \dot e`.
* :class:`PDPlus` (``pd-plus``) -- Paden and Panja's PD+: :math:`v = \dot q_d`, :math:`a = \ddot q_d`
  (so :math:`Y\theta_0 = M \ddot q_d + C \dot q_d + g`), :math:`w = -K_p e - K_d \dot e`.

Gains are diagonal: a scalar (same for every joint or coefficient) or a vector
of the right length, strictly positive. Their defaults are the one gain table of
rc3r (the command line uses them too; ``docs/control.md`` says why each value).

**Adding a law** written in Python is one class and one registration::

    @register_law
    class MyLaw(Law):
        name = "my-law"
        def signals(self, q, qd, ref): ...   # -> v, a, r, w   (each (n,))
        def output(self, Y, r, z): ...       # -> theta_eff (p,), zdot (nz,), diagnostic float

It runs with any robot in the generic Python engine (continuous or sampled time;
``examples/custom_law.py``). A **compiled** law is one module: its class, ``LAYOUT``, numba
kernels, their derivatives and its C port (:mod:`rc3r.controllers.base`; the worked example
:mod:`rc3r.controllers.pd_plus`, ``docs/architecture.md``, "Adding a compiled law"). The robots'
fast engines dispatch on its ``code`` (written from :data:`LAWS` when the engine is instantiated,
:mod:`rc3r.simulate.engines._dispatch`); its Python methods call the same kernels, so each law's
arithmetic exists once.
"""
from __future__ import annotations

from .base import (LAWS, Law, Layout, default_gains, inertia_scaled_gain, make_law, packed,  # noqa: F401
                   register_law, _array, _gain_matrix, _is_matrix, _nonnegative, _positive, _scalar, _sized)
from .fbl import FeedbackLinearization
from .robust import Robust
from .robust_coeff import RobustPerCoefficient
from .adaptive import Adaptive
from .pd import PDGravity
from .pd_gains import PDGains  # noqa: F401
from .sliding import Sliding  # noqa: F401
from . import ellipsoid as _ellipsoid  # noqa: E402,F401  (registers robust-ellipsoid: a Python law)
from .pd_plus import PDPlus

__all__ = [
    "Law",
    "Layout",
    "FeedbackLinearization",
    "Robust",
    "RobustPerCoefficient",
    "Adaptive",
    "PDGravity",
    "PDPlus",
    "LAWS",
    "register_law",
    "make_law",
    "default_gains",
    "inertia_scaled_gain",
]
