"""A physically consistent 3R with the same 15 coefficients as Table 1: ``python benchmarks/consistent_3r.py``.

Table 1's links 2 and 3 violate the triangle inequality (principal moments 0.3, 0.3, 0.9 kg m^2),
so MuJoCo refuses them. theta is linear in the *barycentric* parameters of each link (mass ``m``,
first moment ``h = m c`` and inertia ``I_O`` about the origin of DH frame *i*), so every arm with
Table 1's theta is ``beta = beta_T1 + N z`` with ``N`` a basis of the null space of the stacked map
(theta map; held coordinates). The search:

1. holds Table 1's lengths, all three masses and the whole of link 1 (already consistent);
   ``N`` then has 3 columns;
2. the margin of a link is the smallest eigenvalue ``sigma_min`` [kg m^2] of its second moment of
   mass about the CoM, ``Sigma_c = tr(I_c)/2 * 1 - I_c`` (eigenvalues ``(I_b + I_c - I_a)/2``: half
   the slack of the triangle inequality; ``Sigma_c`` is PD iff the pseudo-inertia matrix is PD iff
   the link is physically consistent). SLSQP maximises ``min(sigma_min(link 2), sigma_min(link 3))``
   over ``z`` from seeded starts: ``t_max``;
3. SLSQP minimises the Euclidean distance of the 30 standard parameters (CoM [m], inertia
   [kg m^2]; masses and lengths unchanged) to Table 1 subject to ``sigma_min >= t_max / 2`` on
   links 2 and 3, from the same seeded starts (the first is Table 1 itself);
4. rounding: ``rcz2``, ``rcz3`` and ``Iyy3`` go to the 1e-3 grid (of the 8 grid neighbours of the
   SLSQP point, the nearest to Table 1 that keeps the margin); the other inertia entries of links
   2 and 3 are solved from theta (linear in them at fixed masses and CoMs) and rounded to 1e-10,
   which leaves the exact decimal solution; theta is then checked to 1e-12.

``--out FILE`` writes the parameter file (``src/rc3r/robots/rr3/data/rr3_consistent.toml`` is this
script's output with seed 0, ``tests/test_plant_mujoco.py`` checks that it reproduces it).
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from scipy.linalg import null_space
from scipy.optimize import minimize

from rc3r.robots.rr3.params import STD_NAMES, inertia_matrix, table1, theta_from_vector

#: Indices (in the 30-vector, ``STD_NAMES`` order per link) of the coordinates rounded to 1e-3.
FREE = (13, 23, 25)  # rcz2, rcz3, Iyy3
#: Inertia entries of links 2 and 3 solved from theta after rounding (every one except Iyy3).
SOLVED = tuple(range(14, 20)) + (24, 26, 27, 28, 29)


def barycentric(std) -> np.ndarray:
    """(30,) standard parameters -> (30,) ``(m, m c, I_O)`` per link, about the DH frame origin."""
    s = np.asarray(std, float).reshape(3, 10)
    out = np.empty((3, 10))
    for k, (m, c, i6) in enumerate((row[0], row[1:4], row[4:]) for row in s):
        io = inertia_matrix(i6) + m * (c @ c * np.eye(3) - np.outer(c, c))
        out[k] = [m, *(m * c), io[0, 0], io[1, 1], io[2, 2], io[0, 1], io[0, 2], io[1, 2]]
    return out.ravel()


def standard(bary) -> np.ndarray:
    """Inverse of :func:`barycentric`."""
    b = np.asarray(bary, float).reshape(3, 10)
    out = np.empty((3, 10))
    for k, (m, h, i6) in enumerate((row[0], row[1:4], row[4:]) for row in b):
        c = h / m
        ic = inertia_matrix(i6) - m * (c @ c * np.eye(3) - np.outer(c, c))
        out[k] = [m, *c, ic[0, 0], ic[1, 1], ic[2, 2], ic[0, 1], ic[0, 2], ic[1, 2]]
    return out.ravel()


def sigma_min(std) -> np.ndarray:
    """(3,) smallest eigenvalue of each link's ``Sigma_c = tr(I_c)/2 - I_c`` [kg m^2]."""
    s = np.asarray(std, float).reshape(3, 10)
    out = []
    for row in s:
        ic = inertia_matrix(row[4:])
        out.append(np.linalg.eigvalsh(0.5 * np.trace(ic) * np.eye(3) - ic)[0])
    return np.array(out)


def theta_matrix(std0, lengths) -> np.ndarray:
    """(15, 30) ``A`` with ``theta = A beta`` (columns by differences; linearity checked)."""
    b0 = barycentric(std0)
    f = lambda b: theta_from_vector(standard(b), lengths)  # noqa: E731
    A = np.column_stack([f(b0 + e) - f(b0) for e in np.eye(30)])
    rng = np.random.default_rng(12345)
    for b in (b0, b0 + rng.normal(scale=0.3, size=30)):
        err = np.abs(A @ b - f(b)).max()
        assert err < 1e-11, f"theta is not linear in the barycentric parameters ({err:.2g})"
    return A


def _best(fun, cons, n, starts, rng):
    best = None
    for k in range(starts):
        z0 = np.zeros(n) if k == 0 else rng.normal(scale=0.3, size=n)
        r = minimize(fun, z0, method="SLSQP", constraints=cons, options={"maxiter": 500, "ftol": 1e-15})
        ok = r.success and all(np.all(c["fun"](r.x) >= -1e-9) for c in cons)
        if ok and (best is None or r.fun < best.fun):
            best = r
    if best is None:
        raise RuntimeError("SLSQP found no feasible point from any start")
    return best


def search(seed: int = 0, starts: int = 8, hold_link1: bool = True) -> dict:
    """Run the search; return the rounded parameters and what was measured (module docstring).

    Returns
    -------
    dict
        ``std`` (30,) rounded standard parameters; ``std_slsqp`` (30,) before rounding;
        ``t_max`` and ``target`` [kg m^2]; ``sigma_min`` (3,) [kg m^2] after rounding;
        ``distance`` and ``distance_slsqp`` (to Table 1); ``theta_err`` max |theta - Table 2|;
        ``null_dim``; ``seconds``.
    """
    t0 = time.perf_counter()
    p = table1()
    s0, lengths = p.to_vector(), p.lengths
    theta0 = theta_from_vector(s0, lengths)
    A = theta_matrix(s0, lengths)
    held = list(range(10)) if hold_link1 else [0]
    held += [10, 20]
    E = np.eye(30)[held]
    N = null_space(np.vstack([A, E]))
    b0 = barycentric(s0)
    moving = [1, 2] if hold_link1 else [0, 1, 2]
    std_of = lambda z: standard(b0 + N @ z)  # noqa: E731
    rng = np.random.default_rng(seed)

    # 1. the largest margin links 2 and 3 can have
    n = N.shape[1]
    cons = [{"type": "ineq", "fun": lambda x: sigma_min(std_of(x[:-1]))[moving] - x[-1]}]
    r = _best(lambda x: -x[-1], cons, n + 1, starts, rng)
    t_max = -r.fun
    target = 0.5 * t_max

    # 2. nearest arm to Table 1 with margin t_max / 2
    cons = [{"type": "ineq", "fun": lambda z: sigma_min(std_of(z))[moving] - target}]
    r = _best(lambda z: np.sum((std_of(z) - s0) ** 2), cons, n, starts, rng)
    s_opt = std_of(r.x)
    out = {"std_slsqp": s_opt, "distance_slsqp": float(np.linalg.norm(s_opt - s0)), "t_max": float(t_max),
           "target": float(target), "null_dim": n}
    if hold_link1:
        out["std"] = _round(s_opt, s0, lengths, theta0, target, moving)
    else:
        out["std"] = s_opt
    s = out["std"]
    out.update(sigma_min=sigma_min(s), distance=float(np.linalg.norm(s - s0)),
               theta_err=float(np.abs(theta_from_vector(s, lengths) - theta0).max()),
               seconds=time.perf_counter() - t0)
    return out


def _round(s_opt, s0, lengths, theta0, target, moving) -> np.ndarray:
    """Table 1 where the search left it; FREE on the 1e-3 grid, the nearest to Table 1 of the 2^3
    grid neighbours of the SLSQP point that keeps ``sigma_min >= target``; SOLVED from theta."""
    changed = np.flatnonzero(np.abs(s_opt - s0) > 1e-9)
    assert set(changed) <= set(FREE) | set(SOLVED), f"unexpected coordinates moved: {changed}"
    best = None
    for corner in np.ndindex(*(2,) * len(FREE)):
        s = s0.copy()
        s[list(FREE)] = (np.floor(s_opt[list(FREE)] * 1e3) + corner) / 1e3
        s = _solve_inertia(s, lengths, theta0)
        if np.all(sigma_min(s)[moving] >= target):
            d = np.linalg.norm(s - s0)
            if best is None or d < best[0]:
                best = (d, s)
    if best is None:
        raise RuntimeError("no grid neighbour of the SLSQP point keeps the margin")
    return best[1]


def _solve_inertia(s, lengths, theta0) -> np.ndarray:
    """``s`` with its SOLVED entries making theta equal ``theta0`` (linear in them), to 1e-10."""
    s = s.copy()
    solved = list(SOLVED)
    s[solved] = 0.0
    r0 = theta_from_vector(s, lengths)
    J = np.column_stack([theta_from_vector(s + np.eye(30)[j], lengths) - r0 for j in solved])
    u, *_ = np.linalg.lstsq(J, theta0 - r0, rcond=None)
    s[solved] = np.round(u, 10)
    return s


def to_toml(std, lengths, g0: float, result: dict) -> str:
    """The parameter file (format of ``rc3r/robots/rr3/data/rr3.toml``)."""
    s = np.asarray(std).reshape(3, 10)
    lines = [
        "# A physically consistent 3R arm with exactly the coefficients theta of Table 1 (Table 2).",
        "#",
        "# Written by benchmarks/consistent_3r.py (seed 0); docs/model.md, section",
        "# 'A physically consistent arm with Table 1's theta'. Same lengths and masses as Table 1,",
        "# link 1 unchanged; links 2 and 3 differ in the CoM height rcz and the inertia about the CoM.",
        f"# Margin: smallest eigenvalue of tr(I_c)/2 - I_c (half the triangle-inequality slack) >= "
        f"{result['sigma_min'].min():.4g} kg m^2 on every link.",
        "# Conventions as rr3.toml (docs/conventions.md): SI units; `com` [m] and `inertia`",
        "# [kg m^2, about the CoM] in DH frame i (distal end of link i); matrix entries.",
        "",
        'name = "rr3_consistent"',
        f"g0 = {g0!r}          # [m/s^2]",
    ]
    for k, row in enumerate(s):
        inertia = ", ".join(f"{key.lower()} = {float(v)!r}" for key, v in zip(STD_NAMES[4:], row[4:]))
        lines += ["", f"[[link]]           # link {k + 1}", f"length = {float(lengths[k])!r}",
                  f"mass = {float(row[0])!r}", f"com = [{', '.join(repr(float(v)) for v in row[1:4])}]",
                  f"inertia = {{ {inertia} }}"]
    return "\n".join(lines) + "\n"


def _principal(row) -> np.ndarray:
    return np.linalg.eigvalsh(inertia_matrix(row[4:]))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, help="write the parameter file here")
    args = ap.parse_args(argv)
    p = table1()
    res = search(seed=args.seed)
    s0 = p.to_vector()
    print(f"null space dimension {res['null_dim']} (lengths, masses, link 1 held)")
    print(f"largest margin of links 2 and 3: t_max = {res['t_max']:.6g} kg m^2; target t_max/2 = "
          f"{res['target']:.6g}")
    print(f"distance to Table 1: SLSQP {res['distance_slsqp']:.6g}, rounded {res['distance']:.6g}")
    print(f"max |theta - Table 2| = {res['theta_err']:.3g}; search took {res['seconds']:.2f} s")
    for k, row in enumerate(res["std"].reshape(3, 10)):
        moved = [f"{STD_NAMES[j]}{k + 1}: {s0[10 * k + j]:g} -> {row[j]:.10g}" for j in range(10)
                 if row[j] != s0[10 * k + j]]
        print(f"link {k + 1}: principal moments {np.round(_principal(row), 6)} kg m^2, sigma_min "
              f"{res['sigma_min'][k]:.6g}; {', '.join(moved) or 'unchanged'}")
    free = search(seed=args.seed, hold_link1=False)
    print(f"for comparison, link 1 free too (null dim {free['null_dim']}): distance "
          f"{free['distance_slsqp']:.6g}, sigma_min {np.round(free['sigma_min'], 6)}")
    if args.out:
        args.out.write_text(to_toml(res["std"], p.lengths, p.g0, res))
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
