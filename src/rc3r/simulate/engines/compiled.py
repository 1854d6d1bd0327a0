r"""The compiled engine's integrators, written once for any n and p (numba): a template. State
``x = (q, qd, z)``: positions [rad], velocities [rad/s], the controller state (the adaptive law's estimate).

* :func:`integrate_continuous` -- the controller inside the integrator (continuous time). The robust
  law's boundary layer makes the loop stiff (gain ``rho/eps Y Y^T`` ~ 1e6), so the integrators are
  L-stable Rosenbrock methods (``SimOptions.method``): ode23s (Shampine & Reichelt, SIAM J. Sci. Comput.
  18 (1997); order 2, a W-method, so its Jacobian may be kept ``jac_reuse`` steps), ROS4 and RODAS
  (Hairer & Wanner; order 4, RODAS stiffly accurate, ending its steps on the outputs). The Jacobian is
  analytic where the kernel supply has derivatives (:func:`_tangent_jacobian`), else by forward
  differences (:func:`_jacobian`). Other stored rows are cubic Hermite interpolants.
* :func:`integrate_sampled` -- a digital controller: u computed at t_k = k T and held; the plant is
  integrated over each period by RK4 with ``nsub`` sub-steps, or for a stiff plant (friction on a light
  joint) by adaptive SDIRK3 steps with Newton on the friction (:func:`_sdirk_period`, the default), RODAS
  steps (:func:`_rodas_period`) or ROS4 steps (:func:`_stiff_period`) on the plant alone; the controller
  state by forward Euler.

Plant effects (``fx`` of :meth:`rc3r.plants.Plant.pack`) act through the dispatch written from
:data:`rc3r.plants.EFFECTS` (:mod:`._effects`, line ``# effect dispatch``), the law through the one written
from the law registry (:mod:`._dispatch`, line ``# law dispatch``), the loop's noise and quantization by
:mod:`rc3r.plants._kernels`. The robot enters only through its **kernel supply** (:mod:`._template`) on
its constants ``kc``; n is ``U.shape[1]``, p is ``cp[0]``. Never run as it stands:
:func:`rc3r.simulate._fast.instantiate` writes a copy per supply, ``# kernel supply`` lines naming its
module, dispatches in place of their lines (numba caches a module on disk, not a function that receives
another jitted function), so every import here is absolute. Status codes: :mod:`rc3r.simulate.status`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from rc3r.plants._kernels import measure
from rc3r.simulate.engines._effects import CODES as EFFECT_CODES, actuate, damping as _damping, effect_slopes as _effect_slopes, has_torque as _friction, joint_torque as _joint_torque  # noqa: F401 - effect dispatch
from rc3r.simulate.engines._template import apply_into as _apply, forward_dynamics_into as _fd, make_work as _make_work, mass_into as _mass, passes_into as _passes, xi_into as _xi  # kernel supply
from rc3r.simulate.engines._template import plant_tangents_into as _ptangents, tangents_into as _tangents  # kernel supply (optional)
from rc3r.simulate.engines._dispatch import LAW_CODES, inertia_gain, law_directions, law_jacobian, law_signals, law_slopes, law_theta, uses_xi  # law dispatch
from rc3r.simulate.engines._jacobian import work as _tangent_work
from rc3r.simulate.engines._linalg import _lu_factor, _lu_solve
from rc3r.simulate.engines._sdirk import BHAT as _SDIRK3_BHAT, NEWTON_MAX as _NEWTON_MAX, NEWTON_TOL as _NEWTON_TOL, SG as _SG, SLOPE_GUARD as _SLOPE_GUARD, KNEE_FLOOR as _KNEE_FLOOR, MI_REUSE as _MI_REUSE, TABLE as _SDIRK3, error_norm as _error_norm, factor as _factor, slope_ratio as _slope_ratio  # noqa: E501
from rc3r.simulate.engines._tableaux import RODAS as _RODAS, ROS4 as _ROS4
from rc3r.simulate.methods import ODE23S, RK4_PERIODS, RODAS, RODAS_PERIODS, ROS4, ROS4_PERIODS  # one source
from rc3r.simulate.status import HMIN, NOTPD, OK, WORK, check
from rc3r.trajectory import reference_into, reference_jerk_into

_JIT = dict(cache=True, nogil=True, error_model="numpy")
_ON = np.ones(1, dtype=np.bool_)  # flags pass as _ON[0], a bool (a literal True would compile a second copy)


@njit(**dict(_JIT, inline="always"))
def control(law, cp, q, qd, z, ref, kc, wk, u, zdot, Y, th_eff, v, a, r, w):
    """u (n,) and zdot of a registered law (code ``law``) on the supply's regressor; returns ||Y^T r||.

    ``u = w + Y th_eff`` and ``xi = Y^T r`` through the supply's contractions (``Y`` is scratch).
    A scheduled K (``K_inertia`` b > 0) subtracts ``b M(q) r`` from w (the law's theta, on the
    kinematics of the same pass). ``ref`` (6, n): rows q_d, qd_d, qdd_d, then scratch."""
    law_signals(law, cp, q, qd, ref, v, a, r, w)
    _passes(kc, q, qd, v, a, Y, wk)
    b = inertia_gain(law, cp, q.shape[0])
    if b > 0.0:
        m1 = ref[3]
        _mass(kc, q, cp[1:1 + int(cp[0])], r, m1, Y, wk)
        for i in range(q.shape[0]):
            w[i] -= b * m1[i]
    if uses_xi(law):
        _xi(kc, Y, r, th_eff, wk)
    yn = law_theta(law, cp, q.shape[0], z, th_eff, zdot)
    _apply(kc, Y, th_eff, w, u, wk)
    return yn


@njit(**_JIT)
def closed_loop_rhs(t, x, kc, wk, fx, fric, law, cp, tp, xdot, u, ref, Y, xi, v, a, r, w, ys, fresh=True):
    """xdot = f(t, x); fills ``u`` with the delivered torque (the law's, through the plant's actuator
    effects ``fx``; ``fric = _friction(fx, n)``) and ``ys[0] = ||Y^T r||``. Returns False if the plant M
    is not PD. ``fresh = False``: ``ref`` rows 0-2 already hold the reference at this t (not recomputed)."""
    n = u.shape[0]
    if fresh:
        reference_into(tp, t, ref)
    ys[0] = control(law, cp, x[0:n], x[n:2 * n], x[2 * n:], ref, kc, wk, u, xdot[2 * n:], Y, xi, v, a, r, w)
    actuate(fx, u, u)
    _joint_torque(fx, fric, x[n:2 * n], u, w)  # w (the law's additive term) is free again: the joint torque
    for i in range(n):
        xdot[i] = x[n + i]
    return _fd(kc, x[0:n], x[n:2 * n], w, xdot[n:2 * n], wk)


@njit(**dict(_JIT, inline="always"))
def _f(plant_only, t, x, kc, wk, fx, fric, law, cp, tp, xdot, u, ref, Y, xi, v, a, r, w, ys, fresh=True):
    """:func:`closed_loop_rhs` (``fresh`` as there), or if ``plant_only`` the plant alone (:func:`_plant_rhs`,
    x = (q, qd)) under the held torque ``u`` (read, not written; ``w`` is scratch). False if M is not PD."""
    if plant_only:
        return _plant_rhs(x, u, kc, wk, fx, fric, xdot, w)
    return closed_loop_rhs(t, x, kc, wk, fx, fric, law, cp, tp, xdot, u, ref, Y, xi, v, a, r, w, ys, fresh)


@njit(**_JIT)
def _jacobian(t, x, F0, kc, wk, fx, fric, law, cp, tp, J, Ft, Fp, u, ref, Y, xi, v, a, r, w, ys, tw, plant_only=False,
              warm=False):
    """J = df/dx and Ft = df/dt at (t, x) (F0 = f(t, x); ``plant_only``: f of :func:`_f`, autonomous, so
    Ft = 0): by :func:`_tangent_jacobian` if it can (``tw``: :func:`._jacobian.work`), else by forward
    differences. Returns the evaluations of f made (0 for the analytic one). ``warm``: the last evaluation of
    f was :func:`closed_loop_rhs` at this (t, x), so ``Y``, ``xi``, ``v``, ``a``, ``r`` and the delivered ``u`` hold
    its values (the law is not evaluated again)."""
    if not plant_only and _tangent_jacobian(t, x, kc, wk, fx, law, cp, tp, J, Ft, F0, u, ref, Y, xi, v, a, r, w, tw,
                                            warm):
        return 0
    n = x.shape[0]
    sqeps = math.sqrt(2.220446049250313e-16)
    for j in range(n):
        dx = sqeps * max(abs(x[j]), 1e-3)
        xj = x[j]
        x[j] = xj + dx
        _f(plant_only, t, x, kc, wk, fx, fric, law, cp, tp, Fp, u, ref, Y, xi, v, a, r, w, ys, j == 0)
        x[j] = xj
        for i in range(n):
            J[i, j] = (Fp[i] - F0[i]) / dx
    if plant_only:
        Ft[:] = 0.0
        return n
    dt = sqeps * max(abs(t), 1.0)
    closed_loop_rhs(t + dt, x, kc, wk, fx, fric, law, cp, tp, Fp, u, ref, Y, xi, v, a, r, w, ys, _ON[0])
    for i in range(n):
        Ft[i] = (Fp[i] - F0[i]) / dt
    return n + 1


@njit(**_JIT)
def _tangent_jacobian(t, x, kc, wk, fx, law, cp, tp, J, Ft, F0, u, ref, Y, th, v, a, r, w, tw, warm=False):
    """J and Ft at (t, x) by the chain rule (:mod:`._jacobian`) on the supply's ``tangents_into`` and
    ``plant_tangents_into`` (such a supply forms ``Y`` in ``passes_into``); False (nothing usable written) if
    it has none or the law schedules K by M(q). ``u`` .. ``w``: scratch, as in :func:`control`. d(Y^T r) enters
    only as ``b^T d(Y^T r) = r^T d(Y b)``: one more ``tangents_into`` per b (n + 1 robust, p adaptive)."""
    n = u.shape[0]
    D, Dp, G, Wx, jerk = tw[0], tw[1], tw[3], tw[4], tw[7]
    if inertia_gain(law, cp, n) > 0.0:
        return False
    q, qd = x[0:n], x[n:2 * n]
    reference_into(tp, t, ref)
    reference_jerk_into(tp, t, jerk)
    if not warm:  # f at (t, x), ref already at t, leaves the law's values in the scratch (u delivered, as warm)
        closed_loop_rhs(t, x, kc, wk, fx, _friction(fx, n), law, cp, tp, Ft, u, ref, Y, th, v, a, r, w, tw[14], not _ON[0])
    if not (_tangents(kc, th, q, qd, v, a, D, wk) and _ptangents(kc, q, qd, F0[n:2 * n], Dp, wk)):
        return False
    law_slopes(law, cp, n, ref, jerk, G, Wx)
    rows = law_directions(law, cp, Y, r, tw)  # the directions b whose r^T d(Y b)/dz the law needs (tw[8])
    for i in range(rows):
        _tangents(kc, tw[8][i], q, qd, v, a, tw[13][i], wk)
    _effect_slopes(fx, u, qd, tw[15])  # the plant effects' slopes at the delivered u and qd
    return law_jacobian(law, cp, tw[15], x, Y, r, rows, tw, J, Ft)


@njit(**_JIT)
def _rosenbrock_stages(T, t, x, h, F0, Ft, J, W, piv, kc, wk, fx, fric, law, cp, tp, F1, F2, u, ref, Y, xi, v, a, r,
                       w, ys, K, tmp, xnew, rtol, atol, plant_only=False):
    """One step of the Rosenbrock method of table ``T`` (:mod:`._tableaux`: ROS4, RODAS) from (t, x) of size h
    (F0 = f(t, x), J, Ft at (t, x); ``K`` (>= s, n) scratch): fills ``xnew`` and, if the step is acceptable,
    ``F2 = f(t + h, xnew)`` (``u``, ``ys`` there). Returns ``(status, err, n_f)``: status 0, 1 if the plant's M
    was not PD at a stage or at xnew, 2 if G is singular; err the scaled RMS error estimate (as
    :func:`integrate_continuous`'s); n_f the evaluations of f made. ``plant_only``: f is the plant alone under
    the held ``u`` (:func:`_f`; sampled mode's stiff plants)."""
    n = x.shape[0]
    s = T.shape[0] - 2
    hg = 1.0 / (h * T[0, 1])
    for i in range(n):
        for j in range(n):
            W[i, j] = -J[i, j]
        W[i, i] += hg
    if not _lu_factor(W, piv):
        return 2, 1e300, 0
    ok, nf, at = True, 0, -1.0  # at: the stage time (in h) the reference in ref was last computed for
    F1[:] = F0
    for st in range(s):
        if T[st, 2] != 0.0:
            for i in range(n):
                acc = x[i]
                for j in range(st):
                    acc += T[st, 3 + j] * K[j, i]
                tmp[i] = acc
            ok &= _f(plant_only, t + T[st, 0] * h, tmp, kc, wk, fx, fric, law, cp, tp, F1, u, ref, Y, xi, v, a, r,
                     w, ys, T[st, 0] != at)
            nf += 1
            at = T[st, 0]
        for i in range(n):
            acc = 0.0
            for j in range(st):
                acc += T[st, 3 + s + j] * K[j, i]
            K[st, i] = F1[i] + acc / h + h * T[st, 1] * Ft[i]
        _lu_solve(W, piv, K[st])
    err = 0.0
    for i in range(n):
        xn, ei = x[i], 0.0
        for j in range(s):
            xn += T[s, j] * K[j, i]
            ei += T[s + 1, j] * K[j, i]
        xnew[i] = xn
        ei /= atol + rtol * max(abs(x[i]), abs(xn))
        err += ei * ei
    err = math.sqrt(err / n)
    if not ok:
        return 1, err, nf
    if err <= 1.0:  # f at the new state: the next step's F0, the outputs' u
        if not _f(plant_only, t + h, xnew, kc, wk, fx, fric, law, cp, tp, F2, u, ref, Y, xi, v, a, r, w, ys,
                  at != 1.0):
            return 1, err, nf + 1
        return 0, err, nf + 1
    return 0, err, nf


@njit(**_JIT)
def _ode23s_stages(t, x, h, F0, Ft, J, W, piv, kc, wk, fx, fric, law, cp, tp, F1, F2, u, ref, Y, xi, v, a, r, w, ys,
                   k1, k2, k3, tmp, xnew, rtol, atol):
    """One ode23s step (Shampine & Reichelt 1997; a W-method of order 2, so a kept J keeps the order)
    from (t, x) of size h (F0 = f(t, x), J, Ft at (t, x)): fills ``xnew`` and ``F2 = f(t + h, xnew)``
    (``u``, ``ys`` there). Returns ``(status, err, n_f)`` as :func:`_rosenbrock_stages`: status 0, 1 if the
    plant's M was not PD at the midpoint or at xnew, 2 if W is singular; err the scaled RMS estimate."""
    n = x.shape[0]
    d = 1.0 / (2.0 + math.sqrt(2.0))
    e32 = 6.0 + math.sqrt(2.0)
    hd = h * d
    for i in range(n):
        for j in range(n):
            W[i, j] = -hd * J[i, j]
        W[i, i] += 1.0
    if not _lu_factor(W, piv):
        return 2, 1e300, 0
    for i in range(n):
        k1[i] = F0[i] + hd * Ft[i]
    _lu_solve(W, piv, k1)
    for i in range(n):
        tmp[i] = x[i] + 0.5 * h * k1[i]
    ok1 = closed_loop_rhs(t + 0.5 * h, tmp, kc, wk, fx, fric, law, cp, tp, F1, u, ref, Y, xi, v, a, r, w, ys, _ON[0])
    for i in range(n):
        k2[i] = F1[i] - k1[i]
    _lu_solve(W, piv, k2)
    for i in range(n):
        k2[i] += k1[i]
        xnew[i] = x[i] + h * k2[i]
    ok2 = closed_loop_rhs(t + h, xnew, kc, wk, fx, fric, law, cp, tp, F2, u, ref, Y, xi, v, a, r, w, ys, _ON[0])
    for i in range(n):
        k3[i] = F2[i] - e32 * (k2[i] - F1[i]) - 2.0 * (k1[i] - F0[i]) + hd * Ft[i]
    _lu_solve(W, piv, k3)
    err = 0.0  # RMS norm of the scaled error estimate (Hairer & Wanner; SciPy's solve_ivp)
    for i in range(n):
        sc = atol + rtol * max(abs(x[i]), abs(xnew[i]))
        ei = h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]) / sc
        err += ei * ei
    err = math.sqrt(err / n)
    if not (ok1 and ok2):
        return 1, err, 2
    return 0, err, 2


@njit(**_JIT)
def integrate_continuous(x0, t_out, kc, fx, law, cp, tp, rtol, atol, h0, hmax, lim,
                         X, U, R, ynorm, jac_reuse, max_steps, method):
    """Integrate from ``t_out[0]``; store x, u, q_d rows at every ``t_out`` (n joints: ``U.shape[1]``).

    At most ``max_steps`` steps (accepted and rejected) are taken in this call; past that it
    returns :data:`~rc3r.simulate.status.WORK` where it stands (a too stiff loop, e.g. a
    boundary layer eps so thin that the step size collapses without reaching underflow), so a
    call's wall time stays bounded and the caller regains control.

    The Jacobian is recomputed every ``jac_reuse`` accepted steps and after any
    rejected step taken with an older one (``jac_reuse = 1``: every step, as ode23s).
    ``method``: :data:`ODE23S` (order 2, error estimate of order 3: :func:`_ode23s_stages`) or
    :data:`ROS4` or :data:`RODAS` (order 4, embedded order 3: :func:`_rosenbrock_stages`); all evaluate f at
    the new state before accepting it. RODAS takes a Jacobian every step (``jac_reuse`` is ignored) and ends
    its steps on the output times, so the stored rows are its own step ends (stiffly accurate: u there is
    the law's on the integrated state, not interpolated).
    Returns ``(status, n_stored, n_rhs, n_steps, n_rejected, t_end)``.
    ``ynorm[k]`` receives ``||Y^T r||`` at output k (robust laws).
    """
    n = x0.shape[0]
    x = x0.copy()
    xnew = np.empty(n)
    F0 = np.empty(n); F1 = np.empty(n); F2 = np.empty(n); Ft = np.empty(n); Fp = np.empty(n)
    k1 = np.empty(n); k2 = np.empty(n); k3 = np.empty(n); K = np.empty((6, n)); tmp = np.empty(n)
    q_err = 3.0 if method == ODE23S else 4.0  # the error estimate's order + 1: exponent of the step control
    tab = _RODAS if method == RODAS else _ROS4
    if method == RODAS:
        jac_reuse = 1
    J = np.empty((n, n)); W = np.empty((n, n)); piv = np.zeros(n, dtype=np.int64)
    nj = U.shape[1]
    p = int(cp[0])
    wk = _make_work(kc)
    tw = _tangent_work(nj, p, n - 2 * nj)
    fric = _friction(fx, nj)
    u = np.empty(nj); ref = np.empty((6, nj)); Y = np.empty((nj, p)); xi = np.empty(p)
    v = np.empty(nj); a = np.empty(nj); r = np.empty(nj); w = np.empty(nj)
    ys = np.empty(1); u0 = np.empty(nj)
    nrhs = 0; nsteps = 0; nrej = 0
    t = t_out[0]
    ok = closed_loop_rhs(t, x, kc, wk, fx, fric, law, cp, tp, F0, u, ref, Y, xi, v, a, r, w, ys, _ON[0])
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
        h_try = h
        land = method == RODAS and t + 1.001 * h >= t_out[k]  # RODAS ends its steps on the outputs
        if land:
            h = t_out[k] - t
        last = False
        if t + h >= t_final - 1e-12 * max(1.0, abs(t_final)):
            h = t_final - t
            last = True
        if jac_age >= jac_reuse:
            nrhs += _jacobian(t, x, F0, kc, wk, fx, fric, law, cp, tp, J, Ft, Fp, u, ref, Y, xi, v, a, r, w, ys, tw,
                              not _ON[0], _ON[0])  # warm: the last f was at (t, x) (first, or the step's end)
            jac_age = 0
        while True:
            if nsteps + nrej >= max_steps:
                return WORK, k, nrhs, nsteps, nrej, t
            if method != ODE23S:
                st_, err, nf = _rosenbrock_stages(tab, t, x, h, F0, Ft, J, W, piv, kc, wk, fx, fric, law, cp, tp, F1,
                                                  F2, u, ref, Y, xi, v, a, r, w, ys, K, tmp, xnew, rtol, atol)
            else:
                st_, err, nf = _ode23s_stages(t, x, h, F0, Ft, J, W, piv, kc, wk, fx, fric, law, cp, tp, F1, F2, u,
                                              ref, Y, xi, v, a, r, w, ys, k1, k2, k3, tmp, xnew, rtol, atol)
            nrhs += nf
            if st_ == 2:  # W singular
                return HMIN, k, nrhs, nsteps, nrej, t
            if not (err <= 1e300):  # NaN or overflow
                err = 1e300
            if st_ == 0 and err <= 1.0:
                break
            nrej += 1
            last = land = False
            if jac_age > 0:  # rejected with an old Jacobian: refresh it first
                nrhs += _jacobian(t, x, F0, kc, wk, fx, fric, law, cp, tp, J, Ft, Fp, u, ref, Y, xi, v, a, r, w,
                                  ys, tw, not _ON[0], not _ON[0])
                jac_age = 0
            h = h * max(0.1, 0.8 * (1.0 / max(err, 1e-300)) ** (1.0 / q_err)) if err < 1e300 else 0.1 * h
            if h < 1e-14 * max(1.0, abs(t)):
                return HMIN, k, nrhs, nsteps, nrej, t
        nsteps += 1
        jac_age += 1
        t_new = t_final if last else (t_out[k] if land else t + h)
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
            for i in range(nj):
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
        fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.8 * (1.0 / err) ** (1.0 / q_err)))
        h = max(h * fac, h_try) if land else h * fac  # a step cut to an output does not shrink the next
    return OK, t_out.shape[0], nrhs, nsteps, nrej, t


@njit(**dict(_JIT, inline="always"))
def _plant_rhs(x, u, kc, wk, fx, fric, xdot, tau):
    """Plant only, under the delivered torque ``u``: the joint torque adds the friction of ``fx``."""
    n = u.shape[0]
    _joint_torque(fx, fric, x[n:2 * n], u, tau)
    for i in range(n):
        xdot[i] = x[n + i]
    return _fd(kc, x[0:n], x[n:2 * n], tau, xdot[n:2 * n], wk)


@njit(**_JIT)
def _stiff_period(x, ua, Ts, hs, kc, wk, fx, fric, law, cp, tp, ref, Y, xi, v, a, r, tau, ys, V, J, W, piv,
                  rtol, atol, budget, tw):
    """Advance the plant ``x = (q, qd)`` (2n,) in place over one period ``Ts`` under the held torque ``ua`` by
    adaptive ROS4 steps (:func:`_rosenbrock_stages` on the plant alone, a forward-difference Jacobian per step,
    error control as :func:`integrate_continuous`'s): L-stable, so a friction that damps a light joint in
    microseconds costs no more steps than the motion needs. ``hs[0]``: the step to try, carried from
    period to period. ``V`` (11, 2n), ``J``, ``W`` (2n, 2n), ``piv``: scratch. At most ``budget`` steps.
    Returns ``(status, n_f)``."""
    F0, F1, F2, Ft, Fp = V[0], V[1], V[2], V[3], V[4]
    K, tmp, xnew = V[5:9], V[9], V[10]
    if not _plant_rhs(x, ua, kc, wk, fx, fric, F0, tau):
        return NOTPD, 1
    nf, steps, t, err = 1, 0, 0.0, 0.0
    while t < Ts * (1.0 - 1e-12):
        h = min(hs[0], Ts - t)
        cut = h < hs[0]
        nf += _jacobian(t, x, F0, kc, wk, fx, fric, law, cp, tp, J, Ft, Fp, ua, ref, Y, xi, v, a, r, tau, ys, tw,
                        _ON[0], not _ON[0])
        while True:
            steps += 1
            if steps > budget:
                return WORK, nf
            st_, err, m = _rosenbrock_stages(_ROS4, t, x, h, F0, Ft, J, W, piv, kc, wk, fx, fric, law, cp, tp, F1, F2,
                                             ua, ref, Y, xi, v, a, r, tau, ys, K, tmp, xnew, rtol, atol, True)
            nf += m
            if st_ == 2:
                return HMIN, nf
            if not (err <= 1e300):
                err = 1e300
            if st_ == 0 and err <= 1.0:
                break
            cut = False
            h = h * max(0.1, 0.8 * (1.0 / max(err, 1e-300)) ** 0.25) if err < 1e300 else 0.1 * h
            if h < 1e-14 * Ts:
                return HMIN, nf
        t = Ts if cut else t + h
        for i in range(x.shape[0]):
            x[i] = xnew[i]
            F0[i] = F2[i]
        hn = h * (5.0 if err == 0.0 else min(5.0, max(0.2, 0.8 * (1.0 / err) ** 0.25)))
        hs[0] = max(hs[0], hn) if cut else hn
    return OK, nf


@njit(**dict(_JIT, inline="always"))
def _slopes(fx, qd, d, floor):
    """``d`` (n,): the effects' damping ``-d tau / d qd`` per joint at ``qd``, plus ``floor`` times that at 0."""
    for j in range(qd.shape[0]):
        d[j] = _damping(fx, qd.shape[0], j, qd[j]) + (floor * _damping(fx, qd.shape[0], j, 0.0) if floor else 0.0)


@njit(**dict(_JIT, inline="always"))
def _inverse_mass(x, ua, kc, wk, fx, fric, f, tau, col, Mi):
    """``Mi`` = M(q)^-1 at ``x``: column j is fd(tau(x) + e_j) - ``f`` (f at x; fd affine in tau). False if not PD."""
    n = Mi.shape[0]
    _joint_torque(fx, fric, x[n:2 * n], ua, tau)
    for j in range(n):
        s_ = max(1.0, abs(tau[j]))
        tau[j] += s_
        ok = _fd(kc, x[0:n], x[n:2 * n], tau, col, wk)
        tau[j] -= s_
        if not ok:
            return False
        for i in range(n):
            Mi[i, j] = (col[i] - f[n + i]) / s_
    return True


@njit(**_JIT)
def _sdirk_period(x, ua, Ts, hs, kc, wk, fx, fric, tau, V, Mi, N, piv, rtol, atol, budget, knee=True):
    """Advance the plant ``x = (q, qd)`` (2n,) in place over one period ``Ts`` under the held torque ``ua`` by
    adaptive steps of Alexander's SDIRK3 (:data:`._sdirk.TABLE`), each stage solved by Newton's method on the
    friction: Newton's matrix is ``[[I, -h g I], [0, I + h g M0^-1 phi'(qd)]]``, ``phi'`` the friction's slope
    at the iterate (the smooth Coulomb knee is solved, not linearized), ``M0^-1`` the inverse mass matrix at
    the period's start (:func:`_inverse_mass`, n forward dynamics; kept :data:`._sdirk.MI_REUSE` periods with
    ``knee`` if ``hs`` has a second entry); the rigid body's own slopes are left out (they slow the iteration
    by ~ (h g)^2 |dqdd/dq|, not by the damping). A period costs ``n + 1`` right-hand sides plus one per Newton
    iteration, whatever the friction's stiffness. A stage has converged when Newton's update is below
    :data:`._sdirk.NEWTON_TOL` (1e-3 without ``knee``) of the tolerances' scale (never under 1e-12 (1 + |x|)),
    rejected after :data:`._sdirk.NEWTON_MAX` iterations. The embedded estimate is filtered by Newton's matrix
    (:func:`._sdirk.error_norm`); ``knee`` (the default) filters its velocities over the rest of the
    period (forgiving at most :data:`._sdirk.FORGIVE` times the step's own) and refuses a step across the
    friction's knee: :mod:`._sdirk`.
    ``hs[0]``: the step to try, carried between periods (``hs[1]``: the periods left on ``Mi``). ``V`` (12,
    2n), ``Mi``, ``N`` (n, n), ``piv`` (n,): scratch. At most ``budget`` steps. Returns ``(status, n_f)``."""
    n2 = x.shape[0]
    n = n2 // 2
    F0, Y, base, Fs, err, xnew = V[0], V[1], V[2], V[3:6], V[6], V[7]
    col, d0, d1 = V[8][0:n], V[10][0:n], V[11][0:n]
    if not _plant_rhs(x, ua, kc, wk, fx, fric, F0, tau):
        return NOTPD, 1
    nf, steps, t = 1, 0, 0.0
    g = _SG
    ntol = _NEWTON_TOL if knee else 1e-3
    fresh = not knee or hs.shape[0] < 2 or hs[1] <= 0.0  # M0^-1 kept _MI_REUSE periods (hs[1]: periods left)
    if fresh and not _inverse_mass(x, ua, kc, wk, fx, fric, F0, tau, col, Mi):
        return NOTPD, nf
    nf += n if fresh else 0
    if hs.shape[0] > 1:
        hs[1] = (_MI_REUSE if fresh else hs[1]) - 1.0
    while t < Ts * (1.0 - 1e-12):
        h = min(hs[0], Ts - t)
        cut = h < hs[0]
        while True:
            steps += 1
            if steps > budget:
                return WORK, nf
            hg = h * g
            good = True
            for st in range(3):
                for i in range(n2):
                    acc = x[i]
                    for j in range(st):
                        acc += h * _SDIRK3[st, 1 + j] * Fs[j, i]
                    base[i] = acc
                    Y[i] = acc + hg * (F0[i] if st == 0 else Fs[st - 1, i])  # the last slope as the guess
                conv = False
                for it in range(_NEWTON_MAX):
                    if not _plant_rhs(Y, ua, kc, wk, fx, fric, xnew, tau):
                        good = False
                        break
                    nf += 1
                    _slopes(fx, Y[n:n2], d1, 0.0)
                    if not _factor(Mi, d1, hg, N, piv):
                        good = False
                        break
                    for i in range(n):  # residual R = Y - base - hg f(Y); dqd = -N^-1 R_qd, dq = -R_q + hg dqd
                        col[i] = -(Y[n + i] - base[n + i] - hg * xnew[n + i])
                    _lu_solve(N, piv, col)
                    dn = 0.0
                    for i in range(n):
                        dq = -(Y[i] - base[i] - hg * xnew[i]) + hg * col[i]
                        Y[i] += dq
                        Y[n + i] += col[i]
                        a0 = dq / (atol + rtol * abs(Y[i]) + 1e-12 * (1.0 + abs(Y[i])))  # never below rounding
                        a1 = col[i] / (atol + rtol * abs(Y[n + i]) + 1e-12 * (1.0 + abs(Y[n + i])))
                        dn += a0 * a0 + a1 * a1
                    if math.sqrt(dn / n2) <= ntol:
                        conv = True
                        break
                if not (good and conv):
                    good = False
                    break
                for i in range(n2):  # the stage's slope from the solved equation (exact at convergence)
                    Fs[st, i] = (Y[i] - base[i]) / hg
            if not good and not fresh:  # a kept M0^-1 may be what failed: refresh it here, retry the step
                fresh = _plant_rhs(x, ua, kc, wk, fx, fric, err, tau) and _inverse_mass(x, ua, kc, wk, fx, fric, err,
                                                                                         tau, col, Mi)
                nf += n + 1
                if not fresh:
                    return NOTPD, nf
                steps -= 1
                continue
            e = 1e300
            if good:
                for i in range(n2):
                    xnew[i] = Y[i]  # stiffly accurate: the solution is the last stage
                    acc = 0.0
                    for j in range(3):
                        acc += (_SDIRK3[2, 1 + j] - _SDIRK3_BHAT[j]) * Fs[j, i]
                    err[i] = h * acc
                _slopes(fx, xnew[n:n2], d1, 0.0)
                e = _error_norm(err, x, xnew, Mi, d1, hg, max(hg, Ts - t - h) if knee else hg, N, piv, col, rtol, atol)
                if knee and e <= 1.0:
                    _slopes(fx, x[n:n2], d0, _KNEE_FLOOR)
                    _slopes(fx, xnew[n:n2], d1, _KNEE_FLOOR)
                    if _slope_ratio(d0, d1) > _SLOPE_GUARD:
                        e = 2.0  # across the knee: halve the step (the estimate misjudges it)
            if not (e <= 1e300):
                e = 1e300
            if e <= 1.0:
                break
            cut = False
            h = h * max(0.1, 0.8 * (1.0 / max(e, 1e-300)) ** (1.0 / 3.0)) if e < 1e300 else 0.5 * h
            if h < 1e-14 * Ts:
                return HMIN, nf
        t = Ts if cut else t + h
        for i in range(n2):
            x[i] = xnew[i]
            F0[i] = Fs[2, i]  # the last stage's slope: f at the new state, to the Newton tolerance
        hn = h * (5.0 if e == 0.0 else min(5.0, max(0.2, 0.8 * (1.0 / e) ** (1.0 / 3.0))))
        hs[0] = max(hs[0], hn) if cut else hn
    return OK, nf


#: Accepted RODAS steps of a period one forward-difference Jacobian is kept for (:func:`_rodas_period`).
PERIOD_JAC_REUSE = 1


@njit(**_JIT)
def _rodas_period(x, ua, Ts, hs, kc, wk, fx, fric, law, cp, tp, ref, Y, xi, v, a, r, tau, ys, V, J, W, piv,
                  rtol, atol, budget, tw, jac_reuse):
    """Advance the plant ``x = (q, qd)`` (2n,) in place over one period ``Ts`` under the held torque ``ua`` by
    adaptive RODAS steps (:func:`_rosenbrock_stages` on the plant alone, table ``RODAS``): L-stable and stiffly
    accurate, with an error estimate that is itself stiffly accurate (it vanishes on a damped transient, where
    ROS4's counts it as error), so the steps are set by the motion, not by how fast the friction damps a joint.
    A forward-difference Jacobian is kept ``jac_reuse`` accepted steps and refreshed after a step rejected with
    an older one (as :func:`integrate_continuous`); ``hs[0]``: the step to try, carried from period to period.
    ``V`` (13, 2n), ``J``, ``W`` (2n, 2n), ``piv``: scratch. At most ``budget`` steps. Returns ``(status, n_f)``."""
    F0, F1, F2, Ft, Fp = V[0], V[1], V[2], V[3], V[4]
    K, tmp, xnew = V[5:11], V[11], V[12]
    if not _plant_rhs(x, ua, kc, wk, fx, fric, F0, tau):
        return NOTPD, 1
    nf, steps, t, err = 1, 0, 0.0, 0.0
    age = jac_reuse
    while t < Ts * (1.0 - 1e-12):
        h = min(hs[0], Ts - t)
        cut = h < hs[0]
        if age >= jac_reuse:
            nf += _jacobian(t, x, F0, kc, wk, fx, fric, law, cp, tp, J, Ft, Fp, ua, ref, Y, xi, v, a, r, tau, ys, tw,
                            _ON[0], not _ON[0])
            age = 0
        while True:
            steps += 1
            if steps > budget:
                return WORK, nf
            st_, err, m = _rosenbrock_stages(_RODAS, t, x, h, F0, Ft, J, W, piv, kc, wk, fx, fric, law, cp, tp, F1,
                                             F2, ua, ref, Y, xi, v, a, r, tau, ys, K, tmp, xnew, rtol, atol, True)
            nf += m
            if st_ == 2:
                return HMIN, nf
            if not (err <= 1e300):
                err = 1e300
            if st_ == 0 and err <= 1.0:
                break
            cut = False
            if age > 0:
                nf += _jacobian(t, x, F0, kc, wk, fx, fric, law, cp, tp, J, Ft, Fp, ua, ref, Y, xi, v, a, r, tau, ys,
                                tw, _ON[0], not _ON[0])
                age = 0
            h = h * max(0.1, 0.8 * (1.0 / max(err, 1e-300)) ** 0.25) if err < 1e300 else 0.1 * h
            if h < 1e-14 * Ts:
                return HMIN, nf
        age += 1
        t = Ts if cut else t + h
        for i in range(x.shape[0]):
            x[i] = xnew[i]
            F0[i] = F2[i]
        hn = h * (5.0 if err == 0.0 else min(5.0, max(0.2, 0.8 * (1.0 / err) ** 0.25)))
        hs[0] = max(hs[0], hn) if cut else hn
    return OK, nf


@njit(**_JIT)
def integrate_sampled(x0, s0, Ts, nsamples, dec, nsub, kc, fx, law, cp, tp, lim,
                      X, U, R, ynorm, tv, noise, quant, ubuf, stiff, rtol, atol, budget):
    """Zero-order-hold loop: ``nsamples`` periods of ``Ts`` from sample ``s0`` (t = (s0 + s) Ts, exact
    whatever the chunking); store every ``dec``-th sample.

    The controller sees the measurement of :func:`rc3r.plants._kernels.measure` (``noise`` rows by
    global sample index, ``quant`` encoder steps); its torque goes through the delay line ``ubuf``
    (d + 1, n) (persistent across chunks: sample k writes row k mod (d + 1) and the plant gets the
    command of sample k - d, or of sample 0 while k < d) and the actuator effects of ``fx``.
    The stored ``U`` is the delivered torque; the |u| bound is checked on the command.
    ``tv`` (n,) accumulates the total variation of the delivered torque over all samples.
    The plant is advanced over a period by ``nsub`` RK4 sub-steps (``stiff`` = :data:`RK4_PERIODS`), or by
    :func:`_stiff_period` (:data:`ROS4_PERIODS`) or :func:`_rodas_period` (:data:`RODAS_PERIODS`) at the
    tolerances ``rtol``, ``atol``, at most ``budget`` steps per period.
    Returns ``(status, n_stored, n_rhs, n_samples_done, t_end)``.
    """
    n = x0.shape[0]
    nj = U.shape[1]
    n2 = 2 * nj
    p = int(cp[0])
    wk = _make_work(kc)
    tw = _tangent_work(nj, p, 0)  # the plant-only Jacobian is numerical: unused
    fric = _friction(fx, nj)
    x = x0.copy()
    zdot = np.zeros(max(n - n2, 0))
    u = np.empty(nj); uprev = np.empty(nj)
    ref = np.empty((6, nj)); Y = np.empty((nj, p)); xi = np.empty(p)
    v = np.empty(nj); a = np.empty(nj); r = np.empty(nj); w = np.empty(nj)
    k1 = np.empty(n2); k2 = np.empty(n2); k3 = np.empty(n2); k4 = np.empty(n2); xs = np.empty(n2)
    qm = np.empty(nj); qdm = np.empty(nj); ua = np.empty(nj); tau = np.empty(nj)
    nd = ubuf.shape[0]  # delay + 1
    h = Ts / nsub
    V = np.empty((13, n2)); J = np.empty((n2, n2)); W = np.empty((n2, n2)); piv = np.zeros(n2, dtype=np.int64)
    hs = np.array([Ts, 0.0]); ys = np.empty(1)  # the step to try; periods left on the SDIRK3's M0^-1
    Mi = np.empty((nj, nj)); Nw = np.empty((nj, nj)); pivn = np.zeros(nj, dtype=np.int64)
    xp = x[0:n2]  # the plant's part of x, advanced in place
    nrhs = 0
    stored = 0
    for s in range(nsamples + 1):
        kk = s0 + s
        t = kk * Ts
        reference_into(tp, t, ref)
        measure(x, kk, noise, quant, qm, qdm)
        yn = control(law, cp, qm, qdm, x[n2:], ref, kc, wk, u, zdot, Y, xi, v, a, r, w)
        for i in range(nj):
            ubuf[kk % nd, i] = u[i]
        row = (kk - nd + 1) % nd if kk >= nd - 1 else 0
        for i in range(nj):
            ua[i] = ubuf[row, i]
        actuate(fx, ua, ua)
        if s > 0:
            for i in range(nj):
                tv[i] += abs(ua[i] - uprev[i])
        for i in range(nj):
            uprev[i] = ua[i]
        st = check(x, u, lim)
        if s % dec == 0 or st != OK:
            X[stored] = x; U[stored] = ua; R[stored] = ref[0]; ynorm[stored] = yn
            stored += 1
        if st != OK:
            return st, stored, nrhs, s, t
        if s == nsamples:
            break
        if stiff != RK4_PERIODS:
            if stiff == ROS4_PERIODS:
                st, m = _stiff_period(xp, ua, Ts, hs, kc, wk, fx, fric, law, cp, tp, ref, Y, xi, v, a, r, tau, ys, V,
                                      J, W, piv, rtol, atol, budget, tw)
            elif stiff == RODAS_PERIODS:
                st, m = _rodas_period(xp, ua, Ts, hs, kc, wk, fx, fric, law, cp, tp, ref, Y, xi, v, a, r, tau, ys, V,
                                      J, W, piv, rtol, atol, budget, tw, PERIOD_JAC_REUSE)
            else:
                st, m = _sdirk_period(xp, ua, Ts, hs, kc, wk, fx, fric, tau, V, Mi, Nw, pivn, rtol, atol, budget,
                                      _ON[0])
            nrhs += m
            if st != OK:
                return st, stored, nrhs, s, t
        for sub in range(0 if stiff != RK4_PERIODS else nsub):
            ok = _plant_rhs(x, ua, kc, wk, fx, fric, k1, tau)
            for i in range(n2):
                xs[i] = x[i] + 0.5 * h * k1[i]
            ok &= _plant_rhs(xs, ua, kc, wk, fx, fric, k2, tau)
            for i in range(n2):
                xs[i] = x[i] + 0.5 * h * k2[i]
            ok &= _plant_rhs(xs, ua, kc, wk, fx, fric, k3, tau)
            for i in range(n2):
                xs[i] = x[i] + h * k3[i]
            ok &= _plant_rhs(xs, ua, kc, wk, fx, fric, k4, tau)
            nrhs += 4
            if not ok:
                return NOTPD, stored, nrhs, s, t
            for i in range(n2):
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        for i in range(n - n2):  # controller state: forward Euler, as a digital controller
            x[n2 + i] += Ts * zdot[i]
    return OK, stored, nrhs, nsamples, (s0 + nsamples) * Ts


@njit(**_JIT)
def closed_loop_xdot(t, x, kc, fx, law, cp, tp, n):
    """xdot (new array) of the closed loop at (t, x), for library solvers (``rc3r bench``'s integrators);
    NaN where the plant's M is not positive definite."""
    p = int(cp[0])
    wk = _make_work(kc)
    fric = _friction(fx, n)
    xdot = np.empty(x.shape[0])
    u = np.empty(n); ref = np.empty((6, n)); Y = np.empty((n, p)); xi = np.empty(p)
    v = np.empty(n); a = np.empty(n); r = np.empty(n); w = np.empty(n); ys = np.empty(1)
    if not closed_loop_rhs(t, x, kc, wk, fx, fric, law, cp, tp, xdot, u, ref, Y, xi, v, a, r, w, ys, _ON[0]):
        xdot[:] = np.nan
    return xdot
