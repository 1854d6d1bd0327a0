r"""The kernel supply of the compiled engine: what a robot hands to :mod:`.compiled`, as stubs.

:mod:`rc3r.simulate.engines.compiled` is written once, against the three functions below. It is
never compiled as it stands: :mod:`rc3r.simulate._fast` writes a copy of its source per kernel
supply with this module's import line replaced by the supply's module (numba caches a module
on disk like any file, but not a function that receives another jitted function). A robot
names its supply by :attr:`~rc3r.robots.base.Robot.compiled_kernels`, ``(module, kc)``:

``module`` : str
    Dotted name of an importable module defining, with ``numba.njit``, the three functions
    of this one with the same signatures (``rc3r.robots.rr3.engine`` for the paper's arm,
    ``rc3r.robots.pinocchio_kernel`` for any serial chain).
``kc`` : ndarray (float64, 1-d)
    The rigid body's constants packed for those functions (the 3R: theta, l2, g0; a chain:
    its kinematic constants and the standard parameters). They receive it unchanged.

The supply is the **plant's** model; the law evaluates the same regressor (the model's
kinematics equal the plant's, :func:`rc3r.simulate.simulate` checks them), at the model's theta.
``q``, ``qd``, ``v``, ``a``, ``tau``, ``qdd`` are (n,) arrays, ``Y`` is (n, p); nothing may be
allocated per call in the hot path: scratch space comes from :func:`make_work`, called once per
integrator call. The stubs here fill NaN and report failure (an uninstantiated engine stops at
its first step with "mass matrix not positive definite").
"""
from __future__ import annotations

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True)


@njit(**_JIT)
def make_work(kc):
    """Scratch arrays for the two kernels below (any numba value: typically a tuple of arrays)."""
    return (np.empty(1),)


@njit(**_JIT)
def regressor_into(kc, q, qd, v, a, Y, wk):
    """Fill ``Y`` (n, p) with the Slotine--Li regressor: ``Y theta = M(q) a + C(q, qd) v + g(q)``."""
    Y[:, :] = np.nan


@njit(**_JIT)
def forward_dynamics_into(kc, q, qd, tau, qdd, wk):
    """Fill ``qdd = M(q)^{-1} (tau - C(q, qd) qd - g(q))``; return False if M(q) is not positive definite."""
    qdd[:] = np.nan
    return False
