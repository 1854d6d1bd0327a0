"""The symbolic half of :mod:`rc3r.robots.generated`: the recursions on CasADi ``SX`` and the C batch wrapper.

:class:`_Sym` writes the Newton--Euler and composite-rigid-body recursions, the polarized Slotine--Li
regressor and the CRBA + Cholesky forward dynamics of one chain (:class:`rc3r.robots.generated.Chain`)
on ``SX`` symbols; :func:`_functions` makes the CSE'd CasADi Functions, :func:`_wrapper` the C batch
entry points. Conventions, identities and tests: :mod:`rc3r.robots.generated` (which hashes this
file's text into its cache key too).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .generated_chain import Chain

__all__ = []

#: Constants within this of 0 or +-1 are snapped to them (:func:`_snap`).
_SNAP = 1e-14


def _snap(x: np.ndarray) -> np.ndarray:
    """Entries within 1e-14 of 0, 1 or -1 set to it."""
    x = np.array(x, dtype=float)
    for v in (0.0, 1.0, -1.0):
        x[np.abs(x - v) < _SNAP] = v
    return x


# ---- the symbolic recursions --------------------------------------------------------------------


class _Sym:
    """The SX recursions of one chain (numeric constants snapped, :func:`_snap`)."""

    def __init__(self, chain: Chain):
        import casadi as cs

        self.cs = cs
        self.ch = chain
        self.n = chain.n
        self.R0 = [_snap(r) for r in chain.R0]
        self.p0 = [_snap(p) for p in chain.p0]
        self.u = [_snap(u) for u in chain.axis]
        self.grav = _snap(chain.gravity)

    # small vector helpers on SX columns
    def _v(self, x):
        return self.cs.SX(self.cs.DM(np.asarray(x, dtype=float).reshape(-1, 1)))

    def _rot(self, j, q):
        """Rot(u_j, q) (3, 3) SX; a signed coordinate axis written directly (no 1 - (1 - c) terms)."""
        cs = self.cs
        u = self.u[j]
        c, s = cs.cos(q), cs.sin(q)
        k = int(np.argmax(np.abs(u)))
        if abs(u[k]) == 1.0 and np.count_nonzero(u) == 1:
            s = s if u[k] > 0 else -s
            R = cs.SX.eye(3)
            a, b = [(1, 2), (2, 0), (0, 1)][k]
            R[a, a], R[b, b], R[a, b], R[b, a] = c, c, -s, s
            return R
        K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
        return c * cs.SX.eye(3) + s * cs.SX(cs.DM(K)) + (1 - c) * cs.SX(cs.DM(np.outer(u, u)))

    def kinematics(self, q):
        """``(R_j, p_j)``: joint j's frame in its parent's, SX (3, 3) and (3, 1)."""
        cs = self.cs
        out = []
        for j in range(self.n):
            R0 = cs.SX(cs.DM(self.R0[j]))
            if self.ch.revolute[j]:
                out.append((cs.mtimes(R0, self._rot(j, q[j])), self._v(self.p0[j])))
            else:
                out.append((R0, self._v(self.p0[j]) + cs.mtimes(R0, self._v(self.u[j])) * q[j]))
        return out

    def _S(self, j):
        """(lin, ang) of the motion subspace of joint j in its frame, SX (3, 1) each."""
        u, z = self._v(self.u[j]), self._v(np.zeros(3))
        return (z, u) if self.ch.revolute[j] else (u, z)

    def _to_child(self, R, p, v, w):
        """A motion (v, w) at the parent's origin in its axes -> at the child's origin in its axes."""
        cs = self.cs
        return cs.mtimes(R.T, v + cs.cross(w, p)), cs.mtimes(R.T, w)

    def _to_parent(self, R, p, f, m):
        """A force (f, m) about the child's origin in its axes -> about the parent's in its axes."""
        cs = self.cs
        fp = cs.mtimes(R, f)
        return fp, cs.mtimes(R, m) + cs.cross(p, fp)

    @staticmethod
    def _inertia_apply(cs, pi, v, w):
        """``I (v, w) = (m v - h x w, h x v + I_O w)`` for ``pi = (m, h, xx, xy, yy, xz, yz, zz)``."""
        m, h = pi[0], cs.vertcat(*pi[1:4])
        xx, xy, yy, xz, yz, zz = pi[4:10]
        Iw = cs.vertcat(xx * w[0] + xy * w[1] + xz * w[2], xy * w[0] + yy * w[1] + yz * w[2],
                        xz * w[0] + yz * w[1] + zz * w[2])
        return m * v - cs.cross(h, w), cs.cross(h, v) + Iw

    def body_forces(self, kin, x, b, pi, gravity: bool):
        """Per body the Newton--Euler force ``I A + V x* (I V)`` at joint velocities x, accelerations b."""
        cs = self.cs
        V, A, F = [None] * self.n, [None] * self.n, [None] * self.n
        for j in range(self.n):
            R, p = kin[j]
            lam = int(self.ch.parent[j])
            if lam < 0:
                z = self._v(np.zeros(3))
                vp, wp = z, z
                g = -self.grav if gravity else np.zeros(6)
                ap, alp = self._v(g[:3]), self._v(g[3:])
            else:
                (vp, wp), (ap, alp) = V[lam], A[lam]
            v, w = self._to_child(R, p, vp, wp)
            a, al = self._to_child(R, p, ap, alp)
            Sl, Sa = self._S(j)
            xl, xa = Sl * x[j], Sa * x[j]
            v, w = v + xl, w + xa
            a = a + Sl * b[j] + cs.cross(w, xl) + cs.cross(v, xa)
            al = al + Sa * b[j] + cs.cross(w, xa)
            V[j], A[j] = (v, w), (a, al)
            fa, na = self._inertia_apply(cs, pi[j], a, al)
            fv, nv = self._inertia_apply(cs, pi[j], v, w)
            F[j] = (fa + cs.cross(w, fv), na + cs.cross(w, nv) + cs.cross(v, fv))
        return F

    def backward(self, kin, F):
        """Joint torques ``tau_j = S_j . f_j`` with the forces of the subtree carried to each joint."""
        cs = self.cs
        F = list(F)
        tau = [None] * self.n
        for j in range(self.n - 1, -1, -1):
            f, m = F[j]
            Sl, Sa = self._S(j)
            tau[j] = cs.dot(Sl, f) + cs.dot(Sa, m)
            lam = int(self.ch.parent[j])
            if lam >= 0:
                R, p = kin[j]
                fp, mp = self._to_parent(R, p, f, m)
                F[lam] = (F[lam][0] + fp, F[lam][1] + mp)
        return cs.vertcat(*tau)

    def numeric_pi(self):
        return [[float(x) for x in row] for row in self.ch.pi]

    def rnea(self, q, x, b, pi=None, gravity=True):
        kin = self.kinematics(q)
        return self.backward(kin, self.body_forces(kin, x, b, pi or self.numeric_pi(), gravity))

    def slotine_li(self, q, qd, v, a, columns):
        """``Y`` (n, p): d/d theta of the polarized Newton--Euler torque (module docstring)."""
        cs = self.cs
        th = cs.SX.sym("theta", len(columns))
        pi = [[0.0] * 10 for _ in range(self.n)]
        for k, c in enumerate(columns):
            pi[int(c) // 10][int(c) % 10] = th[k]
        kin = self.kinematics(q)
        F1 = self.body_forces(kin, 0.5 * (qd + v), 0.5 * a, pi, True)
        F2 = self.body_forces(kin, 0.5 * (qd - v), -0.5 * a, pi, False)
        tau = self.backward(kin, [(f1 - f2, m1 - m2) for (f1, m1), (f2, m2) in zip(F1, F2)])
        return cs.jacobian(tau, th)

    def _spatial_inertia(self, pi):
        """6 x 6 (lin, ang) spatial inertia of ``pi`` (numeric): [[m 1, -[h]x], [[h]x, I_O]]."""
        m, h = pi[0], np.asarray(pi[1:4])
        xx, xy, yy, xz, yz, zz = pi[4:10]
        H = np.array([[0, -h[2], h[1]], [h[2], 0, -h[0]], [-h[1], h[0], 0]])
        return np.block([[m * np.eye(3), -H], [H, np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])]])

    def mass(self, q):
        """M (n, n) by the composite-rigid-body algorithm in the joint frames."""
        cs = self.cs
        kin = self.kinematics(q)
        n = self.n
        Ic = [cs.SX(cs.DM(self._spatial_inertia(self.ch.pi[j]))) for j in range(n)]
        X = []
        for R, p in kin:  # parent motion -> child motion, (lin, ang)
            P = cs.skew(p)
            X.append(cs.blockcat([[R.T, -cs.mtimes(R.T, P)], [cs.SX(3, 3), R.T]]))
        for j in range(n - 1, -1, -1):
            lam = int(self.ch.parent[j])
            if lam >= 0:
                Ic[lam] = Ic[lam] + cs.mtimes([X[j].T, Ic[j], X[j]])
        M = cs.SX(n, n)
        for j in range(n):
            Sj = cs.vertcat(*self._S(j))
            F = cs.mtimes(Ic[j], Sj)
            M[j, j] = cs.dot(Sj, F)
            i = j
            while int(self.ch.parent[i]) >= 0:
                F = cs.mtimes(X[i].T, F)
                i = int(self.ch.parent[i])
                M[i, j] = cs.dot(cs.vertcat(*self._S(i)), F)
                M[j, i] = M[i, j]
        return M

    def coriolis(self, q, qd):
        """The Christoffel C (n, n): half the Jacobian of ``C(q, qd) qd`` with respect to qd."""
        c = self.rnea(q, qd, self.cs.SX.zeros(self.n), gravity=False)
        return 0.5 * self.cs.jacobian(c, qd)

    def aba(self, q, qd, tau):
        """``M^{-1} (tau - rnea(q, qd, 0))`` by an unrolled Cholesky factorization."""
        cs = self.cs
        n = self.n
        M = self.mass(q)
        rhs = tau - self.rnea(q, qd, cs.SX.zeros(n))
        L = [[None] * n for _ in range(n)]
        for j in range(n):
            d = M[j, j]
            for k in range(j):
                d = d - L[j][k] * L[j][k]
            L[j][j] = cs.sqrt(d)
            for i in range(j + 1, n):
                s = M[i, j]
                for k in range(j):
                    s = s - L[i][k] * L[j][k]
                L[i][j] = s / L[j][j]
        y = [None] * n
        for i in range(n):
            s = rhs[i]
            for k in range(i):
                s = s - L[i][k] * y[k]
            y[i] = s / L[i][i]
        x = [None] * n
        for i in range(n - 1, -1, -1):
            s = y[i]
            for k in range(i + 1, n):
                s = s - L[k][i] * x[k]
            x[i] = s / L[i][i]
        return cs.vertcat(*x)


def _functions(chain: Chain, columns, names):
    """The CasADi Functions ``rc3r_k_<name>`` (CSE'd, dense outputs laid out row-major) and
    their output shapes."""
    import casadi as cs

    from .generated_chain import FUNCTIONS

    sym = _Sym(chain)
    n = chain.n
    ins = {k: cs.SX.sym(k, n) for k in ("q", "qd", "qdd", "v", "a", "tau")}
    build = {
        "rnea": lambda: sym.rnea(ins["q"], ins["qd"], ins["qdd"]),
        "slotine_li": lambda: sym.slotine_li(ins["q"], ins["qd"], ins["v"], ins["a"], columns).T,
        "mass": lambda: sym.mass(ins["q"]),
        "coriolis": lambda: sym.coriolis(ins["q"], ins["qd"]).T,
        "gravity": lambda: sym.rnea(ins["q"], cs.SX.zeros(n), cs.SX.zeros(n)),
        "aba": lambda: sym.aba(ins["q"], ins["qd"], ins["tau"]),
    }
    shapes = {"rnea": (n,), "slotine_li": (n, len(columns)), "mass": (n, n), "coriolis": (n, n),
              "gravity": (n,), "aba": (n,)}
    out = {}
    for name in names:
        expr = cs.cse(cs.densify(build[name]()))  # transposed where needed: column-major = row-major of the result
        out[name] = cs.Function(f"rc3r_k_{name}", [ins[k] for k in FUNCTIONS[name]], [cs.vec(expr)])
    return out, shapes


def _wrapper(funcs) -> str:
    """The hand-written batch entry points ``void rc3r_gen_<name>_batch(int N, const double *in0, ..., double *out)``."""
    parts = ["/* rc3r generated kernels: batch entry points (rc3r.robots.generated) */",
             "#include <stdlib.h>", "#include <math.h>", "typedef long long int casadi_int;", ""]
    for name, f in funcs.items():
        nin, nout = f.n_in(), f.nnz_out(0)
        sizes = [f.size1_in(i) for i in range(nin)]
        parts.append(f"int rc3r_k_{name}(const double** arg, double** res, casadi_int* iw, double* w, int mem);")
        args = ", ".join(f"const double *in{i}" for i in range(nin))
        sz_w, sz_iw = max(int(f.sz_w()), 1), max(int(f.sz_iw()), 1)
        sets = "\n".join(f"        arg[{i}] = in{i} + (size_t)s * {sizes[i]};" for i in range(nin))
        parts.append(f"""void rc3r_gen_{name}_batch(int N, {args}, double *out) {{
    const double *arg[{max(int(f.sz_arg()), nin)}] = {{0}};
    double *res[{max(int(f.sz_res()), 1)}] = {{0}};
    double *w = (double *)malloc(sizeof(double) * {sz_w});
    casadi_int *iw = (casadi_int *)malloc(sizeof(casadi_int) * {sz_iw});
    if (!w || !iw) {{
        for (long k = 0; k < (long)N * {nout}; k++) out[k] = NAN;
        free(w); free(iw); return;
    }}
    for (int s = 0; s < N; s++) {{
{sets}
        res[0] = out + (size_t)s * {nout};
        rc3r_k_{name}(arg, res, iw, w, 0);
    }}
    free(w); free(iw);
}}
""")
    return "\n".join(parts)
