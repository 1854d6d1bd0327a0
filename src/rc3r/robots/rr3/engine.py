"""Compiled closed-loop simulation (numba): closed-form plant + controller + integrator.

State ``x = (q, qd, z)``: joint positions [rad], velocities [rad/s] and the
controller state ``z`` (the adaptive law's theta estimate; empty otherwise).

* :func:`integrate_continuous` -- the controller inside the integrator (continuous
  time). The robust law's boundary layer makes the loop stiff (gain ``rho/eps Y Y^T``
  ~ 1e6), so the integrator is the L-stable Rosenbrock pair of Shampine & Reichelt,
  "The MATLAB ODE Suite", SIAM J. Sci. Comput. 18 (1997) (MATLAB's ode23s): order 2
  step, order 3 error estimate, Jacobian by forward differences, kept for
  ``jac_reuse`` accepted steps (refreshed after a rejection; 1 = every step as ode23s).
  Steps are not clipped to the output times: the stored rows are the cubic Hermite
  interpolant of the two ends of the step that contains them (third order, like the step).
* :func:`integrate_sampled` -- a digital controller: u computed at t_k = k T and
  held (zero-order hold); the plant is integrated over each period by classical RK4
  with ``nsub`` sub-steps; the controller state is updated by forward Euler.

The control law enters through the generic compiled kernels of
:mod:`rc3r.controllers._kernels` (selected by its integer code); the regressor, the
plant and the integrators are this robot's. Status codes: :mod:`rc3r.simulate.status`.
:class:`FastEngine` is what :attr:`RR3.fast_engine` hands to :func:`rc3r.simulate.simulate`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...controllers._kernels import apply_regressor, law_output, law_signals
from ...plants._kernels import actuate, apply_effects, measure
from ...simulate.status import HMIN, NOTPD, OK, WORK, check
from ...trajectory import reference_into
from . import kernels as K

_JIT = dict(cache=True, nogil=True, error_model="numpy")


@njit(**dict(_JIT, inline="always"))
def control(law, cp, q, qd, z, ref, l2, g0, u, zdot, Y, th_eff, v, a, r, w):
    """u (3,) and zdot of a registered law (code ``law``) on the 3R regressor; returns ||Y^T r||."""
    law_signals(law, cp, q, qd, ref, v, a, r, w)
    K.slotine_li_scalars(q[1], q[2], qd[0], qd[1], qd[2], v[0], v[1], v[2], a[0], a[1], a[2], l2, g0, Y)
    yn = law_output(law, cp, Y, r, z, th_eff, zdot)
    apply_regressor(Y, th_eff, w, u)
    return yn


@njit(**_JIT)
def closed_loop_rhs(t, x, thp, fx, law, cp, tp, l2, g0, xdot, u, ref, Y, xi, w33, w3, v, a, r, w, ys):
    """xdot = f(t, x); fills ``u`` with the delivered torque (the law's, through the plant's actuator
    effects ``fx``) and ``ys[0] = ||Y^T r||``. Returns False if the plant M is not PD."""
    reference_into(tp, t, ref)
    ys[0] = control(law, cp, x[0:3], x[3:6], x[6:], ref, l2, g0, u, xdot[6:], Y, xi, v, a, r, w)
    actuate(fx, u, u)
    apply_effects(fx, x[3:6], u, w)  # w (the law's additive term) is free again: the joint torque
    for i in range(3):
        xdot[i] = x[3 + i]
    return K.forward_dynamics_into(thp, x[0:3], x[3:6], w, l2, g0, xdot[3:6], w33, w3)


@njit(**_JIT)
def _lu_factor(A, piv):
    """In-place LU with partial pivoting (small dense n x n)."""
    n = A.shape[0]
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                p = i
        piv[k] = p
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        if A[k, k] == 0.0:
            return False
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            A[i, k] *= inv
            f = A[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    return True


@njit(**_JIT)
def _lu_solve(LU, piv, b):
    n = LU.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        acc = b[i]
        for j in range(i):
            acc -= LU[i, j] * b[j]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= LU[i, j] * b[j]
        b[i] = acc / LU[i, i]


@njit(**_JIT)
def _jacobian(t, x, F0, thp, fx, law, cp, tp, l2, g0, J, Ft, Fp, u, ref, Y, xi, w33, w3, v, a, r, w, ys):
    """J = df/dx and Ft = df/dt at (t, x) by forward differences (F0 = f(t, x))."""
    n = x.shape[0]
    sqeps = math.sqrt(2.220446049250313e-16)
    for j in range(n):
        dx = sqeps * max(abs(x[j]), 1e-3)
        xj = x[j]
        x[j] = xj + dx
        closed_loop_rhs(t, x, thp, fx, law, cp, tp, l2, g0, Fp, u, ref, Y, xi, w33, w3, v, a, r, w, ys)
        x[j] = xj
        for i in range(n):
            J[i, j] = (Fp[i] - F0[i]) / dx
    dt = sqeps * max(abs(t), 1.0)
    closed_loop_rhs(t + dt, x, thp, fx, law, cp, tp, l2, g0, Fp, u, ref, Y, xi, w33, w3, v, a, r, w, ys)
    for i in range(n):
        Ft[i] = (Fp[i] - F0[i]) / dt
    return n + 1


@njit(**_JIT)
def integrate_continuous(x0, t_out, thp, fx, law, cp, tp, l2, g0, rtol, atol, h0, hmax, lim,
                         X, U, R, ynorm, jac_reuse, max_steps):
    """Integrate from ``t_out[0]``; store x, u, q_d rows at every ``t_out``.

    At most ``max_steps`` steps (accepted and rejected) are taken in this call; past that it
    returns :data:`~rc3r.simulate.status.WORK` where it stands (a too stiff loop, e.g. a
    boundary layer eps so thin that the step size collapses without reaching underflow), so a
    call's wall time stays bounded and the caller regains control.

    The Jacobian is recomputed every ``jac_reuse`` accepted steps and after any
    rejected step taken with an older one (``jac_reuse = 1``: every step, as ode23s).
    Returns ``(status, n_stored, n_rhs, n_steps, n_rejected, t_end)``.
    ``ynorm[k]`` receives ``||Y^T r||`` at output k (robust laws).
    """
    n = x0.shape[0]
    d = 1.0 / (2.0 + math.sqrt(2.0))
    e32 = 6.0 + math.sqrt(2.0)
    x = x0.copy()
    xnew = np.empty(n)
    F0 = np.empty(n); F1 = np.empty(n); F2 = np.empty(n); Ft = np.empty(n); Fp = np.empty(n)
    k1 = np.empty(n); k2 = np.empty(n); k3 = np.empty(n); tmp = np.empty(n)
    J = np.empty((n, n)); W = np.empty((n, n)); piv = np.zeros(n, dtype=np.int64)
    u = np.empty(3); ref = np.empty((3, 3)); Y = np.empty((3, 15)); xi = np.empty(15)
    w33 = np.empty((3, 3)); w3 = np.empty(3)
    v = np.empty(3); a = np.empty(3); r = np.empty(3); w = np.empty(3)
    ys = np.empty(1); u0 = np.empty(3)
    nrhs = 0; nsteps = 0; nrej = 0
    t = t_out[0]
    ok = closed_loop_rhs(t, x, thp, fx, law, cp, tp, l2, g0, F0, u, ref, Y, xi, w33, w3, v, a, r, w, ys)
    nrhs += 1
    X[0] = x; U[0] = u; R[0] = ref[0]
    ynorm[0] = ys[0]
    u0[:] = u
    ys0 = ys[0]
    if not ok:
        return NOTPD, 1, nrhs, nsteps, nrej, t
    st = check(x, u, lim)
    if st != OK:
        return st, 1, nrhs, nsteps, nrej, t
    h = h0
    jac_age = jac_reuse  # accepted steps since the Jacobian was computed
    t_final = t_out[t_out.shape[0] - 1]
    k = 1  # next output row
    while k < t_out.shape[0]:
        h = min(h, hmax)
        last = False
        if t + h >= t_final - 1e-12 * max(1.0, abs(t_final)):
            h = t_final - t
            last = True
        if jac_age >= jac_reuse:
            nrhs += _jacobian(t, x, F0, thp, fx, law, cp, tp, l2, g0, J, Ft, Fp, u, ref, Y, xi, w33, w3, v, a, r, w, ys)
            jac_age = 0
        while True:
            if nsteps + nrej >= max_steps:
                return WORK, k, nrhs, nsteps, nrej, t
            hd = h * d
            for i in range(n):
                for j in range(n):
                    W[i, j] = -hd * J[i, j]
                W[i, i] += 1.0
            if not _lu_factor(W, piv):
                return HMIN, k, nrhs, nsteps, nrej, t
            for i in range(n):
                k1[i] = F0[i] + hd * Ft[i]
            _lu_solve(W, piv, k1)
            for i in range(n):
                tmp[i] = x[i] + 0.5 * h * k1[i]
            ok1 = closed_loop_rhs(t + 0.5 * h, tmp, thp, fx, law, cp, tp, l2, g0, F1, u, ref, Y, xi, w33, w3,
                                  v, a, r, w, ys)
            for i in range(n):
                k2[i] = F1[i] - k1[i]
            _lu_solve(W, piv, k2)
            for i in range(n):
                k2[i] += k1[i]
                xnew[i] = x[i] + h * k2[i]
            ok2 = closed_loop_rhs(t + h, xnew, thp, fx, law, cp, tp, l2, g0, F2, u, ref, Y, xi, w33, w3, v, a, r, w, ys)
            nrhs += 2
            for i in range(n):
                k3[i] = F2[i] - e32 * (k2[i] - F1[i]) - 2.0 * (k1[i] - F0[i]) + hd * Ft[i]
            _lu_solve(W, piv, k3)
            err = 0.0  # RMS norm of the scaled error estimate (Hairer & Wanner; SciPy's solve_ivp)
            for i in range(n):
                sc = atol + rtol * max(abs(x[i]), abs(xnew[i]))
                ei = h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]) / sc
                err += ei * ei
            err = math.sqrt(err / n)
            if not (err <= 1e300):  # NaN or overflow
                err = 1e300
            if ok1 and ok2 and err <= 1.0:
                break
            nrej += 1
            last = False
            if jac_age > 0:  # rejected with an old Jacobian: refresh it first
                nrhs += _jacobian(t, x, F0, thp, fx, law, cp, tp, l2, g0, J, Ft, Fp, u, ref, Y, xi, w33, w3,
                                  v, a, r, w, ys)
                jac_age = 0
            h = h * max(0.1, 0.8 * (1.0 / max(err, 1e-300)) ** (1.0 / 3.0)) if err < 1e300 else 0.1 * h
            if h < 1e-14 * max(1.0, abs(t)):
                return HMIN, k, nrhs, nsteps, nrej, t
        nsteps += 1
        jac_age += 1
        t_new = t_final if last else t + h
        st = check(xnew, u, lim)
        if st != OK:
            for i in range(n):
                x[i] = xnew[i]
            return st, k, nrhs, nsteps, nrej, t_new
        # outputs inside (t, t_new]: the state by cubic Hermite on (x, F0) and (xnew, F2), third order
        # like the step; u and ||Y^T r|| linearly between their values on the integrated states (evaluating
        # the stiff boundary-layer law on an interpolated state would add noise of gain x interpolation error)
        while k < t_out.shape[0] and (t_out[k] <= t_new or (last and k == t_out.shape[0] - 1)):
            s_ = (t_out[k] - t) / h
            if k == t_out.shape[0] - 1 and last:
                s_ = 1.0
            h00 = (1.0 + 2.0 * s_) * (1.0 - s_) * (1.0 - s_)
            h10 = s_ * (1.0 - s_) * (1.0 - s_)
            h01 = s_ * s_ * (3.0 - 2.0 * s_)
            h11 = s_ * s_ * (s_ - 1.0)
            for i in range(n):
                tmp[i] = h00 * x[i] + h * h10 * F0[i] + h01 * xnew[i] + h * h11 * F2[i]
            X[k] = tmp
            for i in range(3):
                U[k, i] = (1.0 - s_) * u0[i] + s_ * u[i]
            ynorm[k] = (1.0 - s_) * ys0 + s_ * ys[0]
            reference_into(tp, t_out[k], ref)
            R[k] = ref[0]
            k += 1
        u0[:] = u
        ys0 = ys[0]
        t = t_new
        for i in range(n):
            x[i] = xnew[i]
            F0[i] = F2[i]
        fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.8 * (1.0 / err) ** (1.0 / 3.0)))
        h = h * fac
    return OK, t_out.shape[0], nrhs, nsteps, nrej, t


@njit(**_JIT)
def _plant_rhs(x, u, thp, fx, l2, g0, xdot, w33, w3, tau):
    """Plant only, under the delivered torque ``u``: the joint torque adds the friction of ``fx``."""
    apply_effects(fx, x[3:6], u, tau)
    for i in range(3):
        xdot[i] = x[3 + i]
    return K.forward_dynamics_into(thp, x[0:3], x[3:6], tau, l2, g0, xdot[3:6], w33, w3)


@njit(**_JIT)
def integrate_sampled(x0, s0, Ts, nsamples, dec, nsub, thp, fx, law, cp, tp, l2, g0, lim,
                      X, U, R, ynorm, tv, noise, quant, ubuf):
    """Zero-order-hold loop: ``nsamples`` periods of ``Ts`` from sample ``s0`` (t = (s0 + s) Ts, exact
    whatever the chunking); store every ``dec``-th sample.

    The controller sees the measurement of :func:`rc3r.plants._kernels.measure` (``noise`` rows by
    global sample index, ``quant`` encoder steps); its torque goes through the delay line ``ubuf``
    (d + 1, 3) (persistent across chunks: sample k writes row k mod (d + 1) and the plant gets the
    command of sample k - d, or of sample 0 while k < d) and the actuator effects of ``fx``.
    The stored ``U`` is the delivered torque; the |u| bound is checked on the command.
    ``tv`` (3,) accumulates the total variation of the delivered torque over all samples.
    Returns ``(status, n_stored, n_rhs, n_samples_done, t_end)``.
    """
    n = x0.shape[0]
    x = x0.copy()
    zdot = np.zeros(max(n - 6, 0))
    u = np.empty(3); uprev = np.empty(3)
    ref = np.empty((3, 3)); Y = np.empty((3, 15)); xi = np.empty(15)
    w33 = np.empty((3, 3)); w3 = np.empty(3)
    v = np.empty(3); a = np.empty(3); r = np.empty(3); w = np.empty(3)
    k1 = np.empty(6); k2 = np.empty(6); k3 = np.empty(6); k4 = np.empty(6); xs = np.empty(6)
    qm = np.empty(3); qdm = np.empty(3); ua = np.empty(3); tau = np.empty(3)
    nd = ubuf.shape[0]  # delay + 1
    h = Ts / nsub
    nrhs = 0
    stored = 0
    for s in range(nsamples + 1):
        kk = s0 + s
        t = kk * Ts
        reference_into(tp, t, ref)
        measure(x, kk, noise, quant, qm, qdm)
        yn = control(law, cp, qm, qdm, x[6:], ref, l2, g0, u, zdot, Y, xi, v, a, r, w)
        for i in range(3):
            ubuf[kk % nd, i] = u[i]
        row = (kk - nd + 1) % nd if kk >= nd - 1 else 0
        for i in range(3):
            ua[i] = ubuf[row, i]
        actuate(fx, ua, ua)
        if s > 0:
            for i in range(3):
                tv[i] += abs(ua[i] - uprev[i])
        for i in range(3):
            uprev[i] = ua[i]
        st = check(x, u, lim)
        if s % dec == 0 or st != OK:
            X[stored] = x; U[stored] = ua; R[stored] = ref[0]; ynorm[stored] = yn
            stored += 1
        if st != OK:
            return st, stored, nrhs, s, t
        if s == nsamples:
            break
        for sub in range(nsub):
            ok = _plant_rhs(x, ua, thp, fx, l2, g0, k1, w33, w3, tau)
            for i in range(6):
                xs[i] = x[i] + 0.5 * h * k1[i]
            ok &= _plant_rhs(xs, ua, thp, fx, l2, g0, k2, w33, w3, tau)
            for i in range(6):
                xs[i] = x[i] + 0.5 * h * k2[i]
            ok &= _plant_rhs(xs, ua, thp, fx, l2, g0, k3, w33, w3, tau)
            for i in range(6):
                xs[i] = x[i] + h * k3[i]
            ok &= _plant_rhs(xs, ua, thp, fx, l2, g0, k4, w33, w3, tau)
            nrhs += 4
            if not ok:
                return NOTPD, stored, nrhs, s, t
            for i in range(6):
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        for i in range(n - 6):  # controller state: forward Euler, as a digital controller
            x[6 + i] += Ts * zdot[i]
    return OK, stored, nrhs, nsamples, (s0 + nsamples) * Ts


class FastEngine:
    """The 3R's compiled simulator behind the interface :mod:`rc3r.simulate` expects.

    ``continuous(...)`` returns ``(status, n_stored, n_rhs, n_steps, n_rejected, t_end)``;
    ``sampled(..., s0, ...)`` (s0: first sample index) returns
    ``(status, n_stored, n_rhs, n_samples_done, t_end)``; both fill
    the output arrays ``X`` (state), ``U`` (torque), ``R`` (q_d), ``yn`` (||Y^T r||).
    """

    n = 3
    p = 15

    @staticmethod
    def is_cached() -> bool:
        """True if numba's disk cache holds both integrators (no compilation on first use).

        Reads numba's cache index paths (an internal of numba 0.5x-0.6x); if they cannot be
        read, answers True (no announcement rather than a wrong one).
        """
        import os

        try:
            return all(os.path.exists(f._cache._cache_file._index_path)
                       for f in (integrate_continuous, integrate_sampled))
        except AttributeError:
            return True

    @staticmethod
    def continuous(rigid, fx, code, cp, tp, x0, t_out, rtol, atol, h0, hmax, lim, X, U, R, yn, jac_reuse,
                   max_steps):
        l2, g0 = rigid.params.lengths[1], rigid.params.g0
        return integrate_continuous(x0, t_out, rigid.theta, fx, code, cp, tp, l2, g0, rtol, atol, h0, hmax,
                                    lim, X, U, R, yn, jac_reuse, max_steps)

    @staticmethod
    def sampled(rigid, fx, code, cp, tp, x0, s0, Ts, nsamples, dec, nsub, lim, X, U, R, yn, tv, noise, quant,
                ubuf):
        l2, g0 = rigid.params.lengths[1], rigid.params.g0
        return integrate_sampled(x0, s0, Ts, nsamples, dec, nsub, rigid.theta, fx, code, cp, tp, l2, g0, lim,
                                 X, U, R, yn, tv, noise, quant, ubuf)
