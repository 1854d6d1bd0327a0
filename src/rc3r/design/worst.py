r"""The hardest plants of the bounds for a law's gains at a rate (``rc3r design``'s worst-plant search).

Inside its boundary layer a sliding law acts on r with the gain :math:`G = K + b M_0(q) + Y W Y^T`
(:math:`W = (\rho/\epsilon) I` for eq. 6, :math:`\mathrm{diag}(\rho_i/\epsilon_i)` for eq. 7, :math:`M_0` the
controller's own M); on a plant of mass matrix :math:`M_p` the held loop at period T is stable while
:math:`T\lambda_{\max}(M_p^{-1} G) <` :func:`rc3r.design.rule.stability_limit` (2 without delay). Random
draws seldom visit the corner of the bounds where :math:`M_p` is lightest along G's top direction; this
module searches for it:

* for a fixed direction x at a reference sample, :math:`x^T M(q;\theta) x` is linear in theta, so its
  minimiser over a box of standard parameters is a corner (each parameter at the end that lowers it,
  by the sign of its gradient); over a payload range (M increasing in the mass) it is the lightest end;
* :func:`search_box` alternates: the top generalized eigenvector of :math:`(G, M_p)` over the reference
  samples gives the direction, the corner that minimises the inertia along it gives the next plant;
  it keeps the plant with the largest :math:`T\lambda_{\max}` and, beside it, the corners of the top
  directions of the nominal plant (the smallest inertia in the directions that matter). A corner that
  cannot be simulated (mass <= 0, inertia not positive definite) is pulled toward the nominal robot
  (``corner:<bits>@<s>``, s = 1, 0.75, 0.5, 0.25) until it can.

Every figure is exact on the realised plant (its own theta); the linear model is only used to pick
the corner. No random draw is made: the search is deterministic.
"""
from __future__ import annotations

import numpy as np

from .rule import ThetaModel, stability_limit

#: Seeded boundary draws (``boundary:0`` ...) the ellipsoid's search keeps beside its closed-form points.
BOUNDARY_DRAWS = 24

__all__ = ["loop_gains", "plant_gain", "search_box", "search_ellipsoid", "Search", "Hardest", "BOUNDARY_DRAWS"]


class Search:
    """The reference samples and the kinematics a search needs, computed once per design.

    Parameters
    ----------
    nominal : Robot
        The arm (the kinematics; the plants are built from it).
    spectrum : rc3r.design.rule.Spectrum
        The controller's model along the reference (its samples, regressors and M).
    trajectory : Trajectory
        The reference.
    """

    def __init__(self, nominal, spectrum, trajectory):
        self.nominal, self.sp = nominal, spectrum
        qd, _, _ = trajectory.evaluate(spectrum.t)
        self.q = np.asarray(qd, dtype=float)
        kin = ThetaModel(nominal, nominal.theta)
        self.dM = np.array([kin.dM(q) for q in self.q])  # (N, n, n, p)
        L = np.linalg.inv(spectrum.chol_inv)  # M0 = (Li^T Li)^-1 = L L^T
        self.M0 = L @ np.transpose(L, (0, 2, 1))

    def mass(self, theta) -> np.ndarray:
        """M(q_d(t); theta) at every sample, (N, n, n)."""
        M = self.dM @ np.asarray(theta, dtype=float)
        return 0.5 * (M + np.transpose(M, (0, 2, 1)))


def loop_gains(search: Search, gains: dict, *, rho=None, eps=None, rho_i=None, eps_i=None) -> np.ndarray:
    """G(t) of a sliding law along the reference: ``K + K_inertia M0 + Y W Y^T``.

    Parameters
    ----------
    search : Search
        The reference samples (regressors, the controller's M0).
    gains : dict
        The law's ``K`` (scalar, (n,) or (n, n)) and ``K_inertia`` (b of the scheduled ``b M0(q)``).
    rho, eps : float, optional
        Eq. 6: ``W = (rho / eps) I``.
    rho_i, eps_i : (p,) or float, optional
        Eq. 7: ``W = diag(rho_i / eps_i)`` (used when ``eps_i`` is given).

    Returns
    -------
    ndarray, (N, n, n)
        Symmetric G at every sample.
    """
    sp = search.sp
    n = sp.n
    K = np.asarray(gains.get("K", 0.0), dtype=float)
    K = np.diag(np.broadcast_to(K, (n,))) if K.ndim < 2 else K
    if eps_i is not None:
        w = np.asarray(rho_i, dtype=float) / np.asarray(eps_i, dtype=float)
    else:
        w = np.full(sp.Y.shape[2], float(rho) / float(eps))
    YW = sp.Y * w
    G = K + float(gains.get("K_inertia", 0.0)) * search.M0 + YW @ np.transpose(sp.Y, (0, 2, 1))
    return 0.5 * (G + np.transpose(G, (0, 2, 1)))


def plant_gain(G, Mp):
    r"""The held loop's top mode on a plant, sample by sample.

    Parameters
    ----------
    G, Mp : ndarray, (N, n, n)
        The law's gain and the plant's mass matrix along the reference.

    Returns
    -------
    lam : ndarray, (N,)
        :math:`\lambda_{\max}(M_p^{-1} G)` (inf where M_p is not positive definite).
    X : ndarray, (N, n)
        The top generalized eigenvectors of (G, M_p) (zero where M_p is not positive definite).
    """
    N, n, _ = G.shape
    lam = np.full(N, np.inf)
    X = np.zeros((N, n))
    for k in range(N):
        try:
            L = np.linalg.cholesky(Mp[k])
        except np.linalg.LinAlgError:
            continue
        Li = np.linalg.inv(L)
        w, V = np.linalg.eigh(Li @ G[k] @ Li.T)
        lam[k] = w[-1]
        X[k] = Li.T @ V[:, -1]
    return lam, X


def _simulable(robot) -> bool:
    from ..errors import ParameterError

    try:
        robot.require_simulable()
    except ParameterError:
        return False
    return True


def _jacobian(robot, std) -> np.ndarray:
    """d theta / d standard parameters at ``std`` (p, 10 bodies), central differences."""
    std = np.asarray(std, dtype=float)
    J = np.zeros((robot.p, std.size))
    for k in range(std.size):
        h = 1e-6 * max(1.0, abs(std[k]))
        e = np.zeros(std.size)
        e[k] = h
        J[:, k] = (robot.theta_of_standard(std + e) - robot.theta_of_standard(std - e)) / (2 * h)
    return J


def search_box(search: Search, box, G, rate: float, *, delay: int = 0, directions: int = 3,
               rounds: int = 6) -> list[dict]:
    """The hardest plants of a box of standard parameters for the gain G (module docstring).

    Parameters
    ----------
    search : Search
        The reference samples; ``search.nominal`` is the robot the box's deltas are added to.
    box : rc3r.uncertainty.box.Box
        The deltas of the standard parameters.
    G : ndarray, (N, n, n)
        The law's gain along the reference (:func:`loop_gains`).
    rate : float
        Controller rate [Hz].
    delay : int
        Samples of delay (the limit is :func:`rc3r.design.rule.stability_limit`).
    directions : int
        Top directions of the nominal plant whose lightest corners are kept.
    rounds : int
        At most this many alternations of direction and corner.

    Returns
    -------
    list of dict
        Most demanding first, each ``{"spec": "corner:<bits>[@s]", "T_lambda": float, "t": float,
        "limit": stability_limit(delay), "why": str}``; ``T_lambda`` is :math:`T\\max_t\\lambda_{\\max}(M_p^{-1}G)`
        on the realised plant. Duplicates removed.
    """
    from ..uncertainty.box import perturb

    nominal = search.nominal
    T = 1.0 / float(rate)
    std0 = nominal.standard_parameters()
    J = _jacobian(nominal, std0)
    limit = stability_limit(delay)
    found: dict[str, dict] = {}

    products = np.array([str(nm).startswith(("Ixy", "Ixz", "Iyz")) for nm in box.names])
    bodies = box.size // 10

    def realise(bits):
        """The plant of corner ``bits`` (1 upper, 0 lower, None nominal) made simulable: the delta of each body
        that is not (mass <= 0, inertia about its CoM not positive definite) halved until it is (at most 8
        times), first with every parameter at its corner, then with the products of inertia left nominal."""
        import re

        text = "".join("n" if b is None else "1" if b else "0" for b in bits)
        texts = [text]
        if products.any():
            texts.append("".join("n" if p else c for c, p in zip(text, products)))
        for txt in texts:
            scales = np.ones(bodies)
            for _ in range(9):
                suffix = "" if np.all(scales == 1.0) else "@" + ",".join(f"{x:g}" for x in scales)
                spec = f"corner:{txt}{suffix}"
                try:
                    plant = perturb(nominal, box, spec)
                    issues = [i for i in plant.physical_issues() if "triangle" not in i]
                except Exception as exc:  # noqa: BLE001 -- a mass <= 0: the message names no body
                    plant, issues = None, [str(exc)]
                if not issues:
                    Mp = search.mass(plant.theta)
                    if np.all(np.linalg.eigvalsh(Mp)[:, 0] > 0):
                        return spec, Mp
                    scales = scales * 0.5
                    continue
                bad = {int(m) - 1 for i in issues for m in re.findall(r"(?:body|link) (\d+)", i)}
                bad = {b for b in bad if 0 <= b < bodies}
                if bad:
                    scales[sorted(bad)] *= 0.5
                else:
                    scales = scales * 0.5
        return None, None

    def corner_for(x, k):
        """The corner (1 upper, 0 lower, None nominal per standard parameter) of least x^T M(q_k) x: the signs
        of the gradient first (exact where theta is linear in the standard parameters), then coordinate
        passes on the exact x^T M x (theta need not be linear in them: the 3R's centres of mass)."""
        g = np.einsum("i,ijp,j->p", x, search.dM[k], x)  # d(x^T M x)/d theta at sample k
        c = g @ J  # ... per standard parameter
        tiny = 1e-9 * max(float(np.max(np.abs(c))), 1e-300)
        bits = [None if abs(v) <= tiny else bool(v < 0) for v in c]

        def delta(b):
            return np.array([0.0 if v is None else (box.upper[j] if v else box.lower[j]) for j, v in enumerate(b)])

        def f(b):
            return float(g @ nominal.theta_of_standard(std0 + delta(b)))

        best = f(bits)
        for _ in range(2):
            changed = False
            for j in range(len(bits)):
                for v in (None, False, True):
                    if v is bits[j]:
                        continue
                    trial = bits[:j] + [v] + bits[j + 1:]
                    val = f(trial)
                    if val < best - 1e-12 * abs(best):
                        bits, best, changed = trial, val, True
            if not changed:
                break
        return bits

    def keep(spec, Mp, why):
        lam, X = plant_gain(G, Mp)
        k = int(np.argmax(lam))
        entry = {"spec": spec, "T_lambda": float(T * lam[k]), "t": float(search.sp.t[k]), "limit": float(limit),
                 "why": why}
        if spec not in found or found[spec]["T_lambda"] < entry["T_lambda"]:
            found[spec] = entry
        return lam, X

    lam0, X0 = keep("nominal", search.mass(nominal.theta), "the nominal robot (where the search starts)")
    # the smallest inertia in the top directions of the nominal plant (distinct samples, largest gains first)
    order = np.argsort(-lam0)
    picked = []
    for k in order:
        if len(picked) >= directions:
            break
        if all(abs(int(k) - j) > max(1, lam0.size // 20) for j in picked):
            picked.append(int(k))
    for i, k in enumerate(picked):
        spec, Mp = realise(corner_for(X0[k], k))
        if spec is not None:
            keep(spec, Mp, f"lightest along the nominal plant's {'top' if i == 0 else f'#{i + 1}'} direction "
                           f"of M^-1 G (t = {search.sp.t[k]:.3g} s)")
    # alternate: the top direction on the current plant, then the corner lightest along it
    lam, X = lam0, X0
    best = -np.inf
    for _ in range(rounds):
        k = int(np.argmax(lam))
        spec, Mp = realise(corner_for(X[k], k))
        if spec is None:
            break
        lam, X = keep(spec, Mp, "largest T lambda_max(M_p^-1 G) found (alternating direction and corner)")
        top = float(np.max(lam))
        if top <= best * (1 + 1e-9):
            break
        best = top
    out = sorted(found.values(), key=lambda e: -e["T_lambda"])
    if out and not out[0]["why"].startswith("largest"):  # the maximiser is named as such whichever route found it
        out[0] = {**out[0], "why": "largest T lambda_max(M_p^-1 G) found: " + out[0]["why"]}
    return out


def search_ellipsoid(search: Search, realise, G, rate: float, *, delay: int = 0, directions: int = 3,
                     rounds: int = 4, shrink=(1.0, 0.75, 0.5, 0.35, 0.25, 0.15, 0.1), pool=()) -> list[dict]:
    """The hardest plants of an identified ellipsoid for the gain G (module docstring): over the ellipsoid
    :math:`x^T M(q;\\theta) x` is smallest at :math:`\\theta_0 - P^{-1}g/\\sqrt{g^T P^{-1} g}`
    (``lightest:<q>:<x>``, :func:`rc3r.uncertainty.ellipsoid.lightest_theta`); alternated with the top
    generalized eigenvector of (G, M_p) like :func:`search_box`.

    ``realise(spec)`` builds the plant of a spec (the centre: ``"centre"``) or raises; a point no simulable
    robot realises is moved toward theta_0 (``:<s>``, s in ``shrink``). ``pool``: ``(spec, M_p (N, n, n))`` of
    plants already realised on the ellipsoid's boundary (seeded ``boundary:<seed>`` draws, each realisable:
    where the closed form is not, the hardest of them stands in). Returns what :func:`search_box` does.
    """
    T = 1.0 / float(rate)
    limit = stability_limit(delay)
    found: dict[str, dict] = {}

    def fmt(v):
        return ",".join(f"{float(a):.12g}" for a in v)

    def keep(spec, plant, why):
        lam, X = plant_gain(G, search.mass(plant.theta))
        k = int(np.argmax(lam))
        found[spec] = {"spec": spec, "T_lambda": float(T * lam[k]), "t": float(search.sp.t[k]),
                       "limit": float(limit), "why": why}
        return lam, X

    def lightest(x, k, why):
        for s in shrink:
            spec = f"lightest:{fmt(search.q[k])}:{fmt(x)}" + ("" if s == 1.0 else f":{s:g}")
            try:
                plant = realise(spec)
            except Exception:  # noqa: BLE001 -- not realisable there: closer to theta_0
                continue
            return keep(spec, plant, why)
        return None

    for spec, Mp in pool:
        lam, _ = plant_gain(G, Mp)
        k = int(np.argmax(lam))
        found[spec] = {"spec": spec, "T_lambda": float(T * lam[k]), "t": float(search.sp.t[k]),
                       "limit": float(limit), "why": "the hardest of the seeded boundary draws"}
    if pool:  # only the hardest draw stays
        top = max((found[s] for s, _ in pool), key=lambda e: e["T_lambda"])
        for spec, _ in pool:
            if spec != top["spec"]:
                found.pop(spec)
    lam0, X0 = keep("centre", realise("centre"), "the centre theta_0 (where the search starts)")
    picked = []
    for k in np.argsort(-lam0):
        if len(picked) >= directions:
            break
        if all(abs(int(k) - j) > max(1, lam0.size // 20) for j in picked):
            picked.append(int(k))
    for i, k in enumerate(picked):
        lightest(X0[k], k, f"lightest along the centre's {'top' if i == 0 else f'#{i + 1}'} direction of M^-1 G "
                           f"(t = {search.sp.t[k]:.3g} s)")
    lam, X = lam0, X0
    best = -np.inf
    for _ in range(rounds):
        k = int(np.argmax(lam))
        got = lightest(X[k], k, "largest T lambda_max(M_p^-1 G) found (alternating direction and lightest point)")
        if got is None:
            break
        lam, X = got
        if float(np.max(lam)) <= best * (1 + 1e-9):
            break
        best = float(np.max(lam))
    out = sorted(found.values(), key=lambda e: -e["T_lambda"])
    if out and not out[0]["why"].startswith("largest"):
        out[0] = {**out[0], "why": "largest T lambda_max(M_p^-1 G) found: " + out[0]["why"]}
    return out


class Hardest:
    """The worst-plant search of a design (:mod:`rc3r.design.worst`) on its bounds: a box of standard
    parameters (searched corner by corner), a payload range (its two ends, exact), an identified ellipsoid
    (its lightest points along the worst directions, closed form); with the URDF's own uncertainty
    (:mod:`rc3r.uncertainty.urdf`) the arm at its lightest plant ``urdf-lower`` (exact: the lightest of the
    set in every direction) and its heaviest ``urdf-upper``, the box's corners searched around the lightest."""

    def __init__(self, cfg, spec, sp, rate, delay):
        from ..uncertainty.urdf import URDFSet, parse_spec

        self.rate, self.delay = float(rate), int(delay)
        self.search = Search(spec.controller_model, sp, spec.trajectory)
        self.kind, self.box, self.ends, self.suffix = "off", None, {}, ""
        self.masses: dict = {}  # spec -> M_p (N, n, n) of the plants the last search returned
        self._found: list = []
        u = parse_spec(cfg.get("plant", {}).get("urdf_uncertainty"))
        self.urdf = URDFSet(spec.controller_model, u) if u is not None else None
        if cfg.get("payload"):
            from ..plant_sets import _payload, _payload_plant

            pay = _payload(cfg["payload"]["mass"], cfg["payload"].get("com"))
            self.kind = "payload"
            ends = ("lower", "upper") if self.urdf is None else ("lower+urdf-lower", "upper+urdf-upper", "lower")
            self.ends = {e: _payload_plant(spec.controller_model, pay, e, self.urdf).theta for e in ends}
            if self.urdf is not None:
                self.kind = "payload + URDF uncertainty"
        elif cfg.get("bounds"):  # the identified ellipsoid: its lightest points along the worst directions
            from ..identify.bounds_file import load_bounds
            from ..plant_sets import _bounds_plant

            from ..plant_sets import _actuated_bounds_plant
            from ..robots.actuated import ActuatedRobot

            model = spec.controller_model  # with a file's joint coefficients: friction and armature (ActuatedRobot)
            rigid = model.rigid if isinstance(model, ActuatedRobot) else model
            bf = load_bounds(cfg["bounds"], robot=rigid)
            draw = _actuated_bounds_plant if isinstance(model, ActuatedRobot) and bf.get("actuator") else _bounds_plant
            self.kind = "ellipsoid"
            self.realise = lambda s: draw(rigid, bf, s)  # the plants a run of the bounds draws
            self.pool = [(f"boundary:{k}", self.search.mass(self.realise(f"boundary:{k}").theta))
                         for k in range(BOUNDARY_DRAWS)]  # seeded, realisable: the closed form's stand-ins
        else:
            from ..plant_sets import resolve_box

            self.kind, self.box = "box", resolve_box(spec.controller_model, cfg.get("box"))
            if self.urdf is not None:  # the box's corners around the arm's lightest plant
                self.kind, self.suffix = "box + URDF uncertainty", "+urdf-lower"
                self.search = Search(self.urdf.end("lower"), sp, spec.trajectory)
                self.upper = self.search.mass(self.urdf.end("upper").theta)

    def gains(self, sliding, **w):
        return loop_gains(self.search, sliding, **w)

    def model_gain(self, sliding, **w) -> float:
        """T max_t lambda_max(M_0^-1 G): the rule's own figure on the controller's model."""
        return float(np.max(plant_gain(self.gains(sliding, **w), self.search.M0)[0]) / self.rate)

    def _entry(self, spec, Mp, G, why):
        lam, _ = plant_gain(G, Mp)
        k = int(np.argmax(lam))
        self.masses[spec] = Mp
        return {"spec": spec, "T_lambda": float(lam[k] / self.rate), "t": float(self.search.sp.t[k]),
                "limit": stability_limit(self.delay), "why": why}

    def plants(self, sliding, **w) -> list[dict]:
        """The hardest plants for the law's gains (most demanding first; at most 3, and the heaviest arm)."""
        G = self.gains(sliding, **w)
        self.masses = {}
        if self.kind == "ellipsoid":  # M_p realised on demand (eps_factor): the closed form's points cost a fit
            self._found = search_ellipsoid(self.search, self.realise, G, self.rate, delay=self.delay, pool=self.pool)[:3]
            return self._found
        if self.box is not None:
            found = search_box(self.search, self.box, G, self.rate, delay=self.delay)[:3]
            if self.suffix:  # corners of the box around the arm's lightest plant, and the heaviest arm
                found = [{**e, "spec": e["spec"] + self.suffix} for e in found]
            for e in found:
                self.masses[e["spec"]] = self._mass_of(e["spec"])
            if self.suffix:
                found.append(self._entry("nominal+urdf-upper", self.upper, G, "the arm's heaviest plant of the "
                                         "URDF uncertainty (every link at its upper factor)"))
            return sorted(found, key=lambda e: -e["T_lambda"])
        why = {"lower": "the payload's lower end (M grows with the mass: the lightest in every direction)",
               "upper": "the payload's upper end (the heaviest)",
               "lower+urdf-lower": "the lightest plant of the set in every direction (exact maximiser): the payload's "
                                   "lower end, every link at its lower factor of the URDF uncertainty",
               "upper+urdf-upper": "the heaviest plant: the payload's upper end, every link at its upper factor"}
        if self.urdf is not None:
            why["lower"] = "the URDF's own arm at the payload's lower end (the bounds' lightest plant)"
        out = [self._entry(end, self.search.mass(theta), G, why[end]) for end, theta in self.ends.items()]
        return sorted(out, key=lambda e: -e["T_lambda"])

    def _mass_of(self, spec):
        from ..uncertainty.box import perturb

        box_spec, _, arm = spec.partition("+")
        base = self.search.nominal if not arm else self.urdf.plant(arm)
        plant = base if box_spec == "nominal" else perturb(base, self.box, box_spec)
        return self.search.mass(plant.theta)

    def eps_factor(self, sliding, rate: float, **w) -> float:
        """The smallest factor f on the law's boundary layers (eps or eps_i) for which the held loop at ``rate``
        is stable on every plant the last :meth:`plants` returned (``T lambda_max(M_p^-1 G) <`` the limit);
        inf if no boundary layer is thick enough (K and b M0 alone reach the limit: a higher rate is needed)."""
        if not self.masses and self.kind == "ellipsoid":
            self.masses = {e["spec"]: self.search.mass(self.realise(e["spec"]).theta) for e in self._found}
        if not self.masses:
            return 1.0
        G = self.gains(sliding, **w)
        G0 = self.gains({**sliding}, rho=0.0, eps=1.0)  # K + b M0: the robust term's layer infinitely thick
        R = G - G0
        limit, T = stability_limit(self.delay), 1.0 / float(rate)

        def top(f):
            return max(T * float(np.max(plant_gain(G0 + R / f, Mp)[0])) for Mp in self.masses.values())

        if top(1e12) >= limit:
            return float("inf")
        lo, hi = 1e-6, 1.0
        while top(hi) >= limit:
            lo, hi = hi, hi * 2.0
        for _ in range(50):
            mid = np.sqrt(lo * hi)
            lo, hi = (mid, hi) if top(mid) >= limit else (lo, mid)
            if hi / lo < 1.001:
                break
        return float(hi)
