r"""The kernel supply of the compiled engine: what a robot hands to :mod:`.compiled`, as stubs.

:mod:`rc3r.simulate.engines.compiled` is written once, against the seven functions below. It is
never compiled as it stands: :mod:`rc3r.simulate._fast` writes a copy of its source per kernel
supply with this module's import line replaced by the supply's module (numba caches a module
on disk like any file, but not a function that receives another jitted function). A robot
names its supply by :attr:`~rc3r.robots.base.Robot.compiled_kernels`, ``(module, kc)``:

``module`` : str
    Dotted name of an importable module defining, with ``numba.njit``, the seven functions
    of this one with the same signatures (``rc3r.robots.rr3.engine`` for the paper's arm,
    ``rc3r.robots.pinocchio_supply`` for any serial chain).
``kc`` : ndarray (float64, 1-d)
    The rigid body's constants packed for those functions (the 3R: theta, l2, g0; a chain:
    its kinematic constants and the standard parameters). They receive it unchanged.

The supply is the **plant's** model; the law evaluates the same regressor (the model's
kinematics equal the plant's, :func:`rc3r.simulate.simulate` checks them), at the model's theta.
``q``, ``qd``, ``v``, ``a``, ``tau``, ``qdd`` are (n,) arrays, ``Y`` is (n, p); nothing may be
allocated per call in the hot path. The law needs ``Y`` only through ``xi = Y^T r`` and
``u = w + Y theta``: the control step calls :func:`passes_into` once, then :func:`xi_into` (the
laws that use it) and :func:`apply_into`; a supply may fill ``Y`` there and contract it (the 3R)
or compute both contractions without forming it (a chain, O(n)). :func:`regressor_into` serves
the rest (the python engine, tests): scratch space comes from :func:`make_work`, called once per
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


@njit(**_JIT)
def passes_into(kc, q, qd, v, a, Y, wk):
    """Prepare :func:`xi_into` and :func:`apply_into` at the state ``(q, qd, v, a)`` (may fill ``Y``)."""
    Y[:, :] = np.nan


@njit(**_JIT)
def xi_into(kc, Y, r, xi, wk):
    """Fill ``xi`` (p,) with ``Y^T r`` at the state of the last :func:`passes_into`."""
    xi[:] = np.nan


@njit(**_JIT)
def apply_into(kc, Y, th, w, u, wk):
    """Fill ``u`` (n,) with ``w + Y th`` at the state of the last :func:`passes_into`."""
    u[:] = np.nan


@njit(**_JIT)
def mass_into(kc, q, th, r, out, Y, wk):
    """Fill ``out`` (n,) with ``M_th(q) r`` (the mass matrix of the parameters ``th``), called after
    :func:`passes_into` at the same ``q`` (whose kinematics a supply may reuse)."""
    out[:] = np.nan


# ---- optional: analytic derivatives (the second import line of :mod:`.compiled`) ----------------
# A supply that defines both functions below gets the analytic closed-loop Jacobian of
# :mod:`rc3r.simulate.engines._jacobian`; one that does not keeps these stubs, and the engine
# differentiates its right-hand side numerically (forward differences), as before.


@njit(**_JIT)
def tangents_into(kc, th, q, qd, v, a, D, wk):
    """``D`` (n, 4n) = d(Y(q, qd, v, a) th)/d(q, qd, v, a) at fixed ``th`` (p,), any ``th`` (the engine also
    calls it at directions that are not parameter sets). False: no analytic derivatives."""
    return False


@njit(**_JIT)
def plant_tangents_into(kc, q, qd, qdd, D, wk):
    """``D`` (n, 4n) as :func:`tangents_into` at the plant's own parameters and ``(v, a) = (qd, qdd)``:
    columns 0..2n-1 and 2n..3n-1 give d(M(q) qdd + C(q, qd) qd + g(q))/d(q, qd), columns 3n.. give
    M(q). False: no analytic derivatives."""
    return False
