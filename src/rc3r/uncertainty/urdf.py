r"""The URDF's own uncertainty as a physical set of link inertias (``[plant] urdf_uncertainty``).

Bounds that trust a URDF (a payload range, a box around its values) do not cover the URDF's own error;
``rc3r design`` verifies beyond them with this set (docs/design.md, "URDF uncertainty"). Each moving
link's pseudo-inertia (Wensing, Kim & Slotine, RA-L 2017)

.. math:: J = \begin{bmatrix} \Sigma & h \\ h^T & m \end{bmatrix},\quad
          \Sigma = \tfrac12 \mathrm{tr}(\bar I) 1 - \bar I

(mass, first moment, rotational inertia about the link frame; a real rigid body iff :math:`J \succ 0`)
may be any :math:`J'` with :math:`s_{lo} J \preceq J' \preceq s_{hi} J`: with :math:`J = L L^T` (L of J's eigendecomposition),
:math:`J' = L R\,\mathrm{diag}(s)\,R^T L^T`, the link scaled by a factor in :math:`[s_{lo}, s_{hi}]` along
each of four principal directions R of its mass distribution (the whole link scaled by s when all four
are equal). Every plant of the set is physical by construction (:math:`J' \succeq s_{lo} J \succ 0`).

The kinetic energy is linear in each J and monotone in the PSD order (:math:`\tfrac12\mathrm{tr}(V J V^T)`
for the link's 3x4 velocity map V), so :math:`x^T M(q; J') x \ge \sum_i s_{lo,i}\, x^T M_i(q) x` for every
q and x, with equality at ``urdf-lower`` (every link at its lower factor, :math:`J_i' = s_{lo,i} J_i`): that
plant is the lightest of the set in every direction at every posture, so it maximises the held loop's
gain :math:`T\lambda_{\max}(M_p^{-1} G)` for every gain G (the worst corner, exact, no search), and
``urdf-upper`` is the heaviest. (A link whose J is not positive semidefinite -- a table that is no rigid body, like the
paper's 3R -- is scaled as a whole, :math:`J' = sJ`: its spatial inertia stays positive definite, so the bound holds; the
plant is as physical as the table.) ``urdf-scale:<s_1>,...`` scales link i by :math:`s_i`; ``urdf-random:<seed>``
draws R (Haar) and s (log-uniform) per link from ``numpy.random.default_rng(seed)``.

Specs (:func:`parse_spec`): ``off`` (or 0); a fraction F in (0, 1): every link in [1 - F, 1 + F]; or items
``LO..HI`` (every link) and ``K=LO..HI`` (link K, 1-based; -1 the last), comma-separated, later items
overriding earlier ones, with 0 < LO <= 1 <= HI. The default :data:`DEFAULT`, from the identified real
Panda (docs/design.md): every link down to 1/10, the last (the one that carries the tool or hand) to 1/20.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError

__all__ = ["DEFAULT", "URDFSet", "parse_spec", "ranges", "link_masses", "ARM_SPECS"]

#: The default URDF uncertainty (docs/design.md, "URDF uncertainty": the identified real Panda is 9.7 x
#: lighter than its URDF in its lightest direction along the reference; its wrist 5-20 x in some directions).
DEFAULT = "0.1..1.5,-1=0.05..1.5"

#: The arm specs :meth:`URDFSet.plant` accepts.
ARM_SPECS = "urdf-lower, urdf-upper, urdf-scale:<s per link>, urdf-random:<seed>"

_PIN_KEYS = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
_COM_KEYS = ("m", "rcx", "rcy", "rcz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def _range(text: str, where: str) -> tuple[float, float]:
    lo, sep, hi = text.partition("..")
    try:
        a, b = float(lo), float(hi if sep else lo)
    except ValueError:
        raise ConfigError(f"URDF uncertainty {where!r}: expected LO..HI (two numbers)") from None
    if not (np.isfinite(a) and np.isfinite(b) and 0.0 < a <= 1.0 <= b <= 1e3):
        raise ConfigError(f"URDF uncertainty {where!r}: need 0 < LO <= 1 <= HI (the URDF itself inside)")
    return a, b


def parse_spec(value) -> str | None:
    """The canonical text of a URDF-uncertainty spec (module docstring), or None for none (``off``, 0).

    Raises
    ------
    ConfigError
        Not a spec.
    """
    if value is None or value is False:
        return None
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        f = float(value)
        if not (np.isfinite(f) and 0.0 <= f < 1.0):
            raise ConfigError(f"URDF uncertainty must be a fraction in [0, 1) or a spec LO..HI[,K=LO..HI], got {value!r}")
        return None if f == 0.0 else f"{1.0 - f:g}..{1.0 + f:g}"
    text = str(value).strip().replace(" ", "")
    if text.lower() in ("off", "none", "0", "0.0", ""):
        return None
    try:
        return parse_spec(float(text))
    except ValueError:
        pass
    items = []
    for item in text.split(","):
        key, eq, rng = item.rpartition("=")
        if eq:
            try:
                k = int(key)
            except ValueError:
                raise ConfigError(f"URDF uncertainty {item!r}: the link before '=' must be an integer "
                                  "(1-based; -1 the last)") from None
            if k == 0:
                raise ConfigError(f"URDF uncertainty {item!r}: links count from 1 (or from -1, the last)")
        a, b = _range(rng, item)
        items.append((f"{int(key)}=" if eq else "") + f"{a:g}..{b:g}")
    return ",".join(items)


def ranges(spec: str, bodies: int) -> tuple[np.ndarray, np.ndarray]:
    """Per link ``(lo, hi)`` arrays (bodies,) of a canonical spec (:func:`parse_spec`)."""
    lo, hi = np.ones(bodies), np.ones(bodies)
    for item in spec.split(","):
        key, eq, rng = item.rpartition("=")
        a, b = _range(rng, item)
        if not eq:
            lo[:], hi[:] = a, b
            continue
        k = int(key)
        if not -bodies <= k <= bodies:
            raise ConfigError(f"URDF uncertainty {item!r}: the arm has {bodies} moving links")
        j = k - 1 if k > 0 else bodies + k
        lo[j], hi[j] = a, b
    return lo, hi


def _keys(robot) -> tuple:
    from .box import body_keys

    keys = body_keys(robot.standard_parameter_names)
    if keys not in (_PIN_KEYS, _COM_KEYS):
        raise ConfigError(f"URDF uncertainty: standard parameters {keys} are neither Pinocchio's nor the 3R's")
    return keys


def _to_dynamic(block, keys) -> np.ndarray:
    """Pinocchio's dynamic parameters (m, m c, inertia about the link frame) of one body's 10 parameters."""
    b = np.asarray(block, dtype=float)
    if keys == _PIN_KEYS:
        return b.copy()
    m, c = b[0], b[1:4]
    ixx, iyy, izz, ixy, ixz, iyz = b[4:]
    Io = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]) + m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.array([m, *(m * c), Io[0, 0], Io[0, 1], Io[1, 1], Io[0, 2], Io[1, 2], Io[2, 2]])


def _from_dynamic(dyn, keys) -> np.ndarray:
    d = np.asarray(dyn, dtype=float)
    if keys == _PIN_KEYS:
        return d.copy()
    m = d[0]
    c = d[1:4] / m
    Io = np.array([[d[4], d[5], d[7]], [d[5], d[6], d[8]], [d[7], d[8], d[9]]])
    Ic = Io - m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.array([m, *c, Ic[0, 0], Ic[1, 1], Ic[2, 2], Ic[0, 1], Ic[0, 2], Ic[1, 2]])


def _pseudo(dyn) -> np.ndarray:
    import pinocchio as pin

    return np.array(pin.PseudoInertia.FromDynamicParameters(np.asarray(dyn, dtype=float)).toMatrix())


def _dynamic(J) -> np.ndarray:
    import pinocchio as pin

    J = 0.5 * (np.asarray(J, dtype=float) + np.asarray(J, dtype=float).T)
    return np.array(pin.PseudoInertia.FromMatrix(J).toDynamicParameters())


def link_masses(robot) -> np.ndarray:
    """The mass of every moving link, (bodies,)."""
    return np.asarray(robot.standard_parameters(), dtype=float)[0::10].copy()


class URDFSet:
    """The URDF uncertainty of an arm (module docstring): per link ``s_lo J <= J' <= s_hi J``.

    Parameters
    ----------
    robot : Robot
        The arm as its URDF (or the payload's light end) gives it: the J of every link.
    spec : str
        A spec (:func:`parse_spec`; canonicalised here).

    Attributes
    ----------
    lo, hi : ndarray (bodies,)
        The factors of every link.
    spec : str
        The canonical spec.
    """

    def __init__(self, robot, spec):
        text = parse_spec(spec)
        if text is None:
            raise ConfigError("URDF uncertainty: 'off' is no set")
        self.robot, self.spec, self.keys = robot, text, _keys(robot)
        std = np.asarray(robot.standard_parameters(), dtype=float)
        self.bodies = std.size // 10
        self.lo, self.hi = ranges(text, self.bodies)
        self.dyn = [_to_dynamic(std[10 * k:10 * k + 10], self.keys) for k in range(self.bodies)]
        self.J = [_pseudo(d) for d in self.dyn]
        self.used = np.array([bool(np.any(d)) for d in self.dyn])  # a massless body (all zero) stays as it is
        self.V, self.w, self.L = [], [], []  # J = V diag(w) V^T = L L^T
        for k in range(self.bodies):
            w, V = np.linalg.eigh(self.J[k])
            self.V.append(V)
            self.w.append(w)
            self.L.append(V * np.sqrt(np.clip(w, 0.0, None)))
        #: links whose J is not positive semidefinite (a URDF or table that is no rigid body, e.g. the paper's 3R):
        #: scaled as a whole (J' = s J, as physical as the table)
        self.improper = [k + 1 for k in range(self.bodies)
                         if self.used[k] and self.w[k][0] < -1e-12 * max(self.w[k][-1], 1e-300)]

    def describe(self) -> str:
        """One line: the factors per link."""
        parts = []
        for k in range(self.bodies):
            rng = f"{self.lo[k]:g}..{self.hi[k]:g}"
            if parts and parts[-1][1] == rng:
                parts[-1] = (parts[-1][0][:1] + [k + 1], rng)
            else:
                parts.append(([k + 1], rng))
        text = ", ".join((f"link {a[0]}" if len(a) == 1 else f"links {a[0]}-{a[-1]}") + f" x {r}" for a, r in parts)
        bad = (f"; links {', '.join(map(str, self.improper))} are no rigid body in the table (J not positive "
               "semidefinite): scaled as a whole") if self.improper else ""
        return (f"every link's pseudo-inertia J' with s_lo J <= J' <= s_hi J (scaled by a factor in [s_lo, s_hi] "
                f"along each principal direction; physical by construction): {text} (spec '{self.spec}'){bad}")

    def with_pseudo(self, Js, label: str):
        """The arm with the links' pseudo-inertias ``Js`` (bodies of 4x4)."""
        std = np.asarray(self.robot.standard_parameters(), dtype=float).copy()
        for k in np.flatnonzero(self.used):
            std[10 * k:10 * k + 10] = _from_dynamic(_dynamic(Js[k]), self.keys)
        return self.robot.with_standard_parameters(std, label)

    def scaled(self, s, label: str | None = None):
        """Link i's J scaled by ``s[i]`` (each in [lo_i, hi_i]; checked)."""
        s = np.broadcast_to(np.asarray(s, dtype=float), (self.bodies,))
        if not np.all((s >= self.lo * (1 - 1e-12)) & (s <= self.hi * (1 + 1e-12))):
            raise ConfigError(f"urdf-scale: factors {s.tolist()} outside the URDF uncertainty {self.spec!r}")
        return self.with_pseudo([sk * J for sk, J in zip(s, self.J)],
                                label or f"{self.robot.label} scaled " + ",".join(f"{x:g}" for x in s))

    def end(self, which: str):
        """``lower`` (every link at its lower factor: the lightest plant in every direction) or ``upper``."""
        Js = []
        for k in range(self.bodies):
            Js.append((self.lo[k] if which == "lower" else self.hi[k]) * self.J[k])
        return self.with_pseudo(Js, f"{self.robot.label} urdf-{which}")

    def random(self, seed: int):
        """A seeded plant of the set: per link a Haar rotation R of 4 and log-uniform factors."""
        rng = np.random.default_rng(int(seed))
        Js = []
        for k in range(self.bodies):
            Q, Rr = np.linalg.qr(rng.standard_normal((4, 4)))
            Q = Q * np.sign(np.diag(Rr))
            s = np.exp(rng.uniform(np.log(self.lo[k]), np.log(self.hi[k]), 4))
            if k + 1 in self.improper:
                Js.append(s[0] * self.J[k])
            else:
                Js.append(self.L[k] @ Q @ np.diag(s) @ Q.T @ self.L[k].T)
        return self.with_pseudo(Js, f"{self.robot.label} urdf-random:{seed}")

    def plant(self, spec: str):
        """The arm of an arm spec (:data:`ARM_SPECS`)."""
        s = str(spec).strip()
        kind, _, arg = s.partition(":")
        if kind == "urdf-lower" and not arg:
            return self.end("lower")
        if kind == "urdf-upper" and not arg:
            return self.end("upper")
        if kind == "urdf-scale":
            try:
                f = np.array([float(x) for x in arg.split(",")])
            except ValueError:
                f = np.zeros(0)
            if f.size not in (1, self.bodies):
                raise ConfigError(f"bad arm spec {s!r}: urdf-scale needs one factor or one per link ({self.bodies})")
            return self.scaled(f, f"{self.robot.label} {s}")
        if kind == "urdf-random" and arg.isdigit():
            return self.random(int(arg))
        raise ConfigError(f"bad arm spec {s!r}: expected {ARM_SPECS}")
