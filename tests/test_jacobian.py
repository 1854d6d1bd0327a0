"""rc3r.simulate.engines._jacobian: the closed loop's analytic Jacobian against central differences.

The compiled engine's Rosenbrock steps take ``J = df/dx`` and ``f_t = df/dt`` of the closed loop.
On a supply with analytic derivatives (the 3R) they are composed by the chain rule
(:func:`_tangent_jacobian`); here they are compared with central differences of the engine's own
right-hand side ``closed_loop_rhs`` (which the simulation tests check against Pinocchio and SciPy),
for every compiled law, inside and outside the robust layer, with friction and with a torque limit
that clips one joint. Tolerance: the entries reach ~1e6 (``rho/eps Y Y^T``); a central difference
with relative step 1e-7 has truncation ~h^2 f''' and rounding ~1e-16 |f| / h, together below 1e-6
of max|J| here (measured 1e-9 to 4e-9), so 1e-6 relative to max|J|.
"""
from __future__ import annotations

import numpy as np
import pytest

import rc3r
from rc3r.plants import Friction, Plant, Saturation, as_plant
from rc3r.simulate import _initial_state
from rc3r.simulate._fast import simulator
from rc3r.simulate.engines._jacobian import work


def _setup(controller, eps=None, **kw):
    spec = rc3r.build_run(controller=controller, perturbed=True, eps=eps, duration=1.0, **kw)
    p = spec.true_rigid
    eng = simulator(as_plant(p).rigid)
    mod = eng.instance
    n = p.n
    cp, tp, code = spec.law.pack(n), spec.trajectory.pack(), int(spec.law.code)
    kc, fx = eng.constants(as_plant(p).rigid), as_plant(p).pack()
    x0 = _initial_state(n, spec.law, spec.trajectory, None)
    return spec, mod, n, cp, tp, code, kc, fx, x0


def _scratch(n, p):
    return (np.empty(n), np.empty((6, n)), np.empty((n, p)), np.empty(p), np.empty(n), np.empty(n), np.empty(n),
            np.empty(n), np.empty(1))


def _f(mod, t, x, kc, fx, code, cp, tp, n):
    p = int(cp[0])
    F = np.empty(x.size)
    u, ref, Y, xi, v, a, r, w, ys = _scratch(n, p)
    fric = mod._friction(fx, n)
    ok = mod.closed_loop_rhs(t, x, kc, mod._make_work(kc), fx, fric, code, cp, tp, F, u, ref, Y, xi, v, a, r, w, ys, True)
    assert ok
    return F, u, ys[0], Y.T @ r


def _analytic(mod, t, x, kc, fx, code, cp, tp, n):
    p = int(cp[0])
    F0 = _f(mod, t, x, kc, fx, code, cp, tp, n)[0]
    J, Ft = np.empty((x.size, x.size)), np.empty(x.size)
    u, ref, Y, xi, v, a, r, w, _ys = _scratch(n, p)
    ok = mod._tangent_jacobian(t, x, kc, mod._make_work(kc), fx, code, cp, tp, J, Ft, F0, u, ref, Y, xi, v, a, r, w,
                               work(n, p, x.size - 2 * n))
    return ok, J, Ft


def _central(mod, t, x, kc, fx, code, cp, tp, n):
    N = x.size
    J, Ft = np.empty((N, N)), np.empty(N)
    for j in range(N):
        h = 1e-7 * max(1.0, abs(x[j]))
        xp, xm = x.copy(), x.copy()
        xp[j] += h
        xm[j] -= h
        J[:, j] = (_f(mod, t, xp, kc, fx, code, cp, tp, n)[0] - _f(mod, t, xm, kc, fx, code, cp, tp, n)[0]) / (2 * h)
    h = 1e-7
    Ft[:] = (_f(mod, t + h, x, kc, fx, code, cp, tp, n)[0] - _f(mod, t - h, x, kc, fx, code, cp, tp, n)[0]) / (2 * h)
    return J, Ft


def clipped_friction(mod, t, x, kc, fx, code, cp, tp, rigid, friction):
    """``fx`` of the plant ``rigid`` with ``friction`` and a torque limit that clips joint 1 at (t, x), not the others."""
    n = rigid.n
    u = _f(mod, t, x, kc, fx, code, cp, tp, n)[1]
    lim = 2.0 * np.abs(u) + 1.0
    lim[0] = 0.5 * abs(u[0])  # joint 1 saturated, the others not
    return Plant(rigid, [friction, Saturation(lim)]).pack()


CASES = {  # name: (controller, eps, state offset from the reference's initial state)
    "fbl": ("fbl", None, 0.3),
    "pd": ("pd", None, 0.3),
    "robust-outside-layer": ("robust", 0.5, 0.3),
    "robust-inside-layer": ("robust", 1e5, 0.3),
    "robust-coeff": ("robust-coeff", None, 0.3),
    "robust-coeff-wide-layers": ("robust-coeff", 300.0, 0.3),
    "adaptive": ("adaptive", None, 0.3),
}


@pytest.mark.parametrize("plant", ["rigid", "friction-and-clip"])
@pytest.mark.parametrize("case", list(CASES))
def test_analytic_jacobian_equals_central_differences(case, plant, rng):
    """J = df/dx and f_t = df/dt of the closed loop, composed analytically, equal central differences."""
    controller, eps, off = CASES[case]
    spec, mod, n, cp, tp, code, kc, fx, x0 = _setup(controller, eps)
    x = x0 + off * rng.uniform(-1, 1, x0.size)
    t = 0.37
    if plant == "friction-and-clip":
        fx = clipped_friction(mod, t, x, kc, fx, code, cp, tp, spec.true_rigid, Friction([0.4, 0.3, 0.2], [2.0, 1.5, 1.0],
                                                                                     v_s=0.05))
    ok, J, Ft = _analytic(mod, t, x, kc, fx, code, cp, tp, n)
    assert ok
    Jc, Ftc = _central(mod, t, x, kc, fx, code, cp, tp, n)
    scale = np.abs(Jc).max()
    assert np.abs(J - Jc).max() <= 1e-6 * scale, np.abs(J - Jc).max() / scale
    assert np.abs(Ft - Ftc).max() <= 1e-6 * max(np.abs(Ftc).max(), 1.0)
    if case in ("robust-outside-layer", "robust-inside-layer"):  # the state is in the layer the case names
        ynorm = _f(mod, t, x, kc, fx, code, cp, tp, n)[2]
        assert (ynorm < eps) == (case == "robust-inside-layer")
    if case == "robust-coeff-wide-layers":  # some coefficients inside their layer, some outside
        xi = np.abs(_f(mod, t, x, kc, fx, code, cp, tp, n)[3])
        assert np.any(xi <= eps) and np.any(xi > eps), xi


@pytest.mark.slow
def test_a_scheduled_gain_falls_back_to_differences():
    """K_inertia > 0 (w -= b M(q) r) is not composed: the analytic Jacobian declines, the engine differences."""
    spec, mod, n, cp, tp, code, kc, fx, x0 = _setup("robust")
    cp = cp.copy()
    cp[spec.law.layout().offset("K_inertia", n, int(cp[0]))] = 2.0
    ok, _J, _Ft = _analytic(mod, 0.1, x0 + 0.1, kc, fx, code, cp, tp, n)
    assert not ok


def test_a_supply_without_tangents_falls_back_to_differences():
    """The Pinocchio chain's supply defines no tangents_into: its instantiation keeps the template's stubs."""
    from rc3r.simulate._fast import TANGENT_MARKER, instantiate

    mod = instantiate("rc3r.robots.pinocchio_supply")
    assert mod._tangents.__module__ == "rc3r.simulate.engines._template"
    assert instantiate("rc3r.robots.rr3.engine")._tangents.__module__ == "rc3r.robots.rr3.engine"
    assert "# kernel supply (optional)" in TANGENT_MARKER


@pytest.mark.parametrize("case", ["robust-outside-layer", "robust-inside-layer", "adaptive", "fbl"])
def test_warm_jacobian_equals_cold(case, rng):
    """warm=True (the integrator's call right after f at the same (t, x): the law is not evaluated again, its
    values are read from the scratch f left, u being the delivered torque) gives the cold call's J and f_t
    bit for bit, with a clipped joint."""
    controller, eps, off = CASES[case]
    spec, mod, n, cp, tp, code, kc, fx, x0 = _setup(controller, eps)
    x = x0 + off * rng.uniform(-1, 1, x0.size)
    t, p, N = 0.37, int(cp[0]), x0.size
    u0 = _f(mod, t, x, kc, fx, code, cp, tp, n)[1]
    lim = 2.0 * np.abs(u0) + 1.0
    lim[0] = 0.5 * abs(u0[0])
    fx = Plant(spec.true_rigid, [Saturation(lim)]).pack()
    ok, J, Ft = _analytic(mod, t, x, kc, fx, code, cp, tp, n)
    wk = mod._make_work(kc)
    S = _scratch(n, p)
    F0 = np.empty(N)
    assert mod.closed_loop_rhs(t, x, kc, wk, fx, False, code, cp, tp, F0, *S, True)
    Jw, Ftw = np.full((N, N), np.nan), np.full(N, np.nan)
    assert mod._tangent_jacobian(t, x, kc, wk, fx, code, cp, tp, Jw, Ftw, F0, *S[:8], work(n, p, N - 2 * n), True)
    assert ok and np.array_equal(J, Jw) and np.array_equal(Ft, Ftw)
