r"""Plants drawn from an ellipsoid of coefficients (the bounds of ``rc3r identify``).

An identification gives the controller :math:`\theta_0` and the confidence ellipsoid
:math:`\mathcal E = \{\theta : (\theta - \theta_0)^T P (\theta - \theta_0) \le 1\}`
(``bounds.toml``, :mod:`rc3r.identify.bounds_file`). A campaign on those bounds needs *plants*
whose coefficients lie in :math:`\mathcal E`: robots, i.e. standard parameters
:math:`\pi` (10 per body, the robot's own order) with :math:`\theta(\pi) = \theta` that a simulator can run.

:func:`draw_from_ellipsoid` draws :math:`\theta` uniformly in :math:`\mathcal E`
(``random:<seed>``: :math:`\theta = \theta_0 + L\,u`, :math:`L L^T = P^{-1}`, :math:`u` uniform in
the unit ball), on its boundary (``boundary:<seed>``, :math:`\|u\| = 1`) or at its centre
(``centre``), then realises it by a robot near the nominal one (:func:`realise_theta`): the
smallest relative change, by minimum-norm Gauss-Newton steps from the nominal robot, of

* for a Pinocchio arm whose bodies are all physically consistent, the Cholesky factors of the
  bodies' pseudo-inertias, :math:`J_k(\pi) = L_k L_k^T` (Wensing, Kim, Slotine, RA-L 2018): every
  plant drawn is then a real rigid body (mass > 0, inertia positive definite, triangle inequality);
* otherwise (the paper's 3R, whose Table 1 violates the triangle inequality) the standard
  parameters themselves: with :math:`\theta = T\pi` one step gives
  :math:`\pi = \pi_{nom} + D\,(T D)^{+}\,(\theta - T\pi_{nom})`, :math:`D = \mathrm{diag}(s)`,
  :math:`s_k = \max(|\pi_{nom,k}|, 10^{-3} \max_j |\pi_{nom,j}|)`, the minimiser of
  :math:`\|D^{-1}(\pi - \pi_{nom})\|_2` subject to :math:`T\pi = \theta`.

The coefficients outside :math:`\theta` (its null space) stay near the nominal robot's. A draw
that no such robot realises (a confidence ellipsoid can reach beyond the physically consistent
coefficients: on the UR5 with 5 % half-widths, about half the draws; the SDP of
:func:`rc3r.identify.consistency.check_consistency` agrees that they are out of reach:
``tests/test_ellipsoid_plants.py``), or whose
robot cannot be simulated (:meth:`~rc3r.robots.base.Robot.require_simulable`), is redrawn from the
same seeded stream, at most :data:`MAX_DRAWS` times: ``random:<seed>`` is uniform on the
realisable part of :math:`\mathcal E`.

**Physical draws** (an identification's ``[physical]`` table: the consistent estimate's link parameters
and the Laplace covariance of their log-Cholesky parameters, :mod:`rc3r.identify.physical`). The centre
is the consistent estimate's own robot (``theta_0 = T pi*`` exactly); a draw ``theta`` is realised in the
**log-Cholesky chart** of the pseudo-inertias (Rucker, Wensing 2022) from the centre's parameters, by
minimum-norm Gauss-Newton steps in the Laplace metric
(:func:`rc3r.identify.physical.realise_log_cholesky`): every iterate, hence every plant, is a real rigid
body, and its coefficients are ``T pi`` of its link parameters. A draw outside the consistent set is
replaced by the nearest physical coefficients the steps reach, if they lie in the ellipsoid (else it
is redrawn as above): plants are uniform on the realisable part of the ellipsoid, plus points of the
consistent set's boundary region for the draws beyond it.

Before a run, a model ``theta`` (a bounds file's centre, a config's list) must give a positive definite
mass matrix along the run's reference (:func:`require_positive_mass_matrix`): else the run is refused
in one line naming the direction and the smallest eigenvalue.

This is not the physical-consistency projection of :func:`rc3r.identify.consistency.check_consistency`
(a semidefinite program, cvxpy): that one projects an estimate; this one draws plants, and needs no solver.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError, ParameterError
from ..identify.estimate import draw_theta, ellipsoid_factor  # re-exported: the ellipsoid's own numerics

__all__ = ["MAX_DRAWS", "ELLIPSOID_SPECS", "MASS_SAMPLES", "ellipsoid_factor", "draw_theta", "realise_theta",
           "draw_from_ellipsoid", "lightest_theta", "realise_toward", "PULL", "mass_matrix_of",
           "require_positive_mass_matrix"]

#: Reference samples at which a model's mass matrix is checked positive definite.
MASS_SAMPLES = 200

#: Redraws of ``random:<seed>`` / ``boundary:<seed>`` before a non-simulable ellipsoid is refused.
MAX_DRAWS = 200

#: The plant specs :func:`draw_from_ellipsoid` understands (besides ``nominal``).
ELLIPSOID_SPECS = "centre, random:<seed>, boundary:<seed>, lightest:<q>:<x>[:<s>]"


#: Standard-parameter names of one body in Pinocchio's order (``toDynamicParameters``), body 1.
_PIN_ORDER = ("m1", "mcx1", "mcy1", "mcz1", "Ixx1", "Ixy1", "Iyy1", "Ixz1", "Iyz1", "Izz1")
_TRIL = np.tril_indices(4)


def _pseudo(block) -> np.ndarray:
    from ..identify.consistency import pseudo_inertia

    return pseudo_inertia(block)


def _from_pseudo(J) -> np.ndarray:
    """Pinocchio's 10 parameters of pseudo-inertias ``J`` (..., 4, 4) (inverse of ``pseudo_inertia``:
    I = tr(S) 1 - S), (..., 10)."""
    S, h, m = J[..., :3, :3], J[..., :3, 3], J[..., 3, 3]
    I = np.trace(S, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - S
    return np.concatenate([m[..., None], h, np.stack([I[..., 0, 0], I[..., 0, 1], I[..., 1, 1], I[..., 0, 2],
                                                      I[..., 1, 2], I[..., 2, 2]], axis=-1)], axis=-1)


def _cholesky_chart(robot):
    """``(xi_0, pi(xi))``: every body's pseudo-inertia as ``L L^T`` (``L`` lower triangular, 10 numbers), so
    that every ``xi`` is a physically consistent robot (Wensing et al. 2018); None when the robot's
    parameters are not in Pinocchio's order or a body of the nominal robot is not strictly consistent."""
    if tuple(robot.standard_parameter_names[:10]) != _PIN_ORDER:
        return None
    pi0 = np.asarray(robot.standard_parameters(), dtype=float)
    nb = pi0.size // 10
    xi0 = []
    for k in range(nb):
        try:
            xi0.append(np.linalg.cholesky(_pseudo(pi0[10 * k:10 * k + 10]))[_TRIL])
        except np.linalg.LinAlgError:
            return None

    def pi_of(xi):
        xi = np.asarray(xi, dtype=float)
        L = np.zeros(xi.shape[:-1] + (nb, 4, 4))
        L[..., _TRIL[0], _TRIL[1]] = xi.reshape(xi.shape[:-1] + (nb, 10))
        return _from_pseudo(L @ np.swapaxes(L, -1, -2)).reshape(xi.shape[:-1] + (10 * nb,))

    return np.concatenate(xi0), pi_of


def realise_theta(robot, theta, label: str | None = None, iterations: int = 30):
    r"""A robot near ``robot`` whose coefficients are ``theta``, as physically consistent as ``robot``.

    Gauss-Newton with minimum-norm steps on the under-determined :math:`\theta(\pi(\xi)) = \theta^*`,
    :math:`\xi \leftarrow \xi + D (J D)^+ (\theta^* - \theta)`, :math:`J = \partial\theta/\partial\xi`,
    :math:`D` the magnitudes of the nominal :math:`\xi` (floored at 1e-3 of the largest), from the nominal
    robot. The chart :math:`\xi`:

    * a Pinocchio arm whose every body is strictly physically consistent: :math:`\xi` the Cholesky
      factors of the bodies' pseudo-inertias, :math:`J_k = L_k L_k^T` (every :math:`\xi` is a real rigid
      body: mass > 0, inertia positive definite, triangle inequality);
    * otherwise (the 3R of Table 1, which violates the triangle inequality): the standard parameters
      themselves (:math:`\theta` linear in them: one step is the minimum-norm solution of the module
      docstring; the 3R's :meth:`~rc3r.robots.base.Robot.theta_of_standard` is quadratic in its own
      parameters and takes a few steps).

    Parameters
    ----------
    robot : Robot
        The nominal robot (its kinematics and standard parameters).
    theta : array_like, (p,)
        The coefficients to realise.
    iterations : int
        At most this many steps.

    Returns
    -------
    Robot
        ``robot.with_standard_parameters(pi)``, not yet checked for simulability.

    Raises
    ------
    ParameterError
        ``theta`` is not reached to 1e-10 (relative) in ``iterations`` steps.
    """
    theta = np.asarray(theta, dtype=float)
    chart = _cholesky_chart(robot)
    if chart is None:
        xi = np.asarray(robot.standard_parameters(), dtype=float).copy()

        def pi_of(x):
            return x
    else:
        xi, pi_of = chart
    s = np.maximum(np.abs(xi), 1e-3 * max(float(np.abs(xi).max()), 1e-300))
    E = np.diag(s)

    def f(x):
        return np.asarray(robot.theta_of_standard(pi_of(x)), dtype=float)

    scale = max(float(np.linalg.norm(theta)), 1e-300)
    r = theta - f(xi)
    miss = float(np.linalg.norm(r)) / scale
    for _ in range(int(iterations)):
        if miss <= 1e-10:
            break
        J = ((f(xi + E) - f(xi - E)) / 2.0).T  # d theta / d z: both charts are at most quadratic, so exact
        step = s * (np.linalg.pinv(J, rcond=1e-12) @ r)
        for _ in range(30):  # backtracking: the chart is quadratic, a full step can overshoot
            r_new = theta - f(xi + step)
            m_new = float(np.linalg.norm(r_new)) / scale
            if m_new < miss:
                break
            step = step / 2.0
        else:
            break
        xi, r, miss = xi + step, r_new, m_new
    if not miss <= 1e-10:
        raise ParameterError(f"coefficients not realisable by robot '{robot.label}' (relative misfit {miss:.2g})")
    return robot.with_standard_parameters(pi_of(xi), label or "ellipsoid")


def _physical_chart(robot, theta0, physical, source):
    """``(T, eta*, S, pi*)`` of a bounds file's ``[physical]`` table, or None when the robot's standard
    parameters are not Pinocchio's (the 3R)."""
    if physical is None or tuple(robot.standard_parameter_names[:10]) != _PIN_ORDER:
        return None
    from ..identify.consistency import standard_map
    from ..identify.physical import covariance_factor, standard_of

    T = standard_map(robot)
    eta = np.asarray(physical["log_cholesky"], dtype=float)
    pi = standard_of(eta)
    theta0 = np.asarray(theta0, dtype=float)
    if np.linalg.norm(T @ pi - theta0) > 1e-8 * max(np.linalg.norm(theta0), 1e-300):
        raise ParameterError(f"{source}: its link parameters [physical] do not give its theta0 "
                             f"(relative misfit {np.linalg.norm(T @ pi - theta0) / np.linalg.norm(theta0):.2g})")
    return T, eta, covariance_factor(np.asarray(physical["log_cholesky_cov"], dtype=float)), pi


def draw_from_ellipsoid(robot, theta0, P, spec: str, *, source: str = "the bounds", physical: dict | None = None):
    """A plant of the ellipsoid: ``centre``, ``random:<seed>`` or ``boundary:<seed>`` (module docstring).

    Parameters
    ----------
    robot : Robot
        The nominal robot.
    theta0, P : ndarray, (p,), (p, p)
        The ellipsoid ``(theta - theta0)^T P (theta - theta0) <= 1``.
    spec : str
        The plant spec.
    source : str
        Named in the error messages (e.g. the bounds file).
    physical : dict, optional
        A bounds file's ``[physical]`` table (``log_cholesky``, ``log_cholesky_cov``): draws are realised in
        the log-Cholesky chart from the consistent estimate (module docstring).

    Returns
    -------
    Robot
        A simulable robot labelled ``spec`` whose ``theta`` lies in the ellipsoid.

    Raises
    ------
    ConfigError
        An unknown or malformed spec.
    ParameterError
        No robot near the nominal one realises a draw in :data:`MAX_DRAWS` (or the centre).

    Examples
    --------
    >>> import numpy as np
    >>> from rc3r.robots import load_robot
    >>> arm = load_robot("rr3")
    >>> P = np.diag(1.0 / (0.05 * np.abs(arm.theta) + 1e-3) ** 2)
    >>> plant = draw_from_ellipsoid(arm, arm.theta, P, "random:3")
    >>> d = plant.theta - arm.theta
    >>> bool(d @ P @ d <= 1.0 + 1e-9)
    True
    """
    kind, _, arg = str(spec).strip().partition(":")
    kind = kind.lower()
    chart = _physical_chart(robot, theta0, physical, source)
    if chart is not None:
        return _draw_physical(robot, theta0, P, spec, kind, arg, chart, source)
    if kind in ("centre", "center") and not arg:
        try:
            plant = realise_theta(robot, theta0, label="centre")
            plant.require_simulable()
        except ParameterError as exc:
            raise ParameterError(f"the centre theta_0 of {source} has no simulable plant near robot "
                                 f"'{robot.label}': {exc}") from None
        return plant
    if kind == "lightest":
        theta = lightest_theta(robot, theta0, P, arg, spec)
        try:
            plant = realise_theta(robot, theta, label=spec)
            plant.require_simulable()
        except ParameterError as exc:
            raise ParameterError(f"plant {spec!r}: no simulable robot near '{robot.label}' realises it: {exc}") from None
        return plant
    if kind not in ("random", "boundary"):
        raise ConfigError(f"bad plant {spec!r} with bounds from {source}: expected nominal, {ELLIPSOID_SPECS}")
    from .box import spec_seed

    rng = np.random.default_rng(spec_seed(spec, kind, arg, "bad plant"))
    for _ in range(MAX_DRAWS):
        theta = draw_theta(theta0, P, rng, boundary=kind == "boundary")
        try:
            plant = realise_theta(robot, theta, label=spec)
            plant.require_simulable()
            return plant
        except ParameterError:
            continue
    raise ParameterError(f"plant {spec!r}: no robot near '{robot.label}' realises any of {MAX_DRAWS} draws from the "
                         f"ellipsoid of {source} (is it the bounds of this arm?)")


def lightest_theta(robot, theta0, P, arg: str, spec: str = "") -> np.ndarray:
    r"""The coefficients of ``lightest:<q>:<x>[:<s>]``: the point of the ellipsoid where the inertia along the
    direction x at the configuration q, :math:`x^T M(q;\theta) x` (linear in theta: :math:`g^T\theta`), is
    smallest, :math:`\theta_0 - P^{-1} g / \sqrt{g^T P^{-1} g}`, moved s of the way from theta_0 (default 1).
    q and x are n comma-separated numbers each (``rc3r design``'s worst-plant search writes them)."""
    from .inertia import ThetaModel

    parts = arg.split(":")
    try:
        q = np.array([float(v) for v in parts[0].split(",")])
        x = np.array([float(v) for v in parts[1].split(",")])
        s = float(parts[2]) if len(parts) > 2 else 1.0
    except (IndexError, ValueError):
        q = x = np.zeros(0)
        s = float("nan")
    if q.shape != (robot.n,) or x.shape != (robot.n,) or len(parts) > 3 or not (0.0 <= s <= 1.0) \
            or not np.all(np.isfinite(np.concatenate([q, x]))):
        raise ConfigError(f"bad plant {spec!r}: 'lightest:<q>:<x>[:<s>]' needs {robot.n} numbers for q and for x "
                          "(comma-separated) and 0 <= s <= 1")
    g = np.einsum("i,ijp,j->p", x, ThetaModel(robot, robot.theta).dM(q), x)
    Pinv_g = np.linalg.solve(np.asarray(P, dtype=float), g)
    norm = float(np.sqrt(max(g @ Pinv_g, 0.0)))
    theta0 = np.asarray(theta0, dtype=float)
    return theta0 if norm == 0.0 else theta0 - s * Pinv_g / norm


#: Fractions of the way from theta_0 to a ``lightest:`` point tried in turn until the nearest physical link
#: parameters lie in the ellipsoid (:func:`realise_toward`).
PULL = (1.0, 0.75, 0.5, 0.25)


def _realised(robot, theta, theta0, P, chart, spec):
    """The plant of the physical link parameters nearest ``theta`` (the chart's Gauss-Newton), or None when
    they leave the ellipsoid ``(P, theta0)`` or cannot be simulated."""
    from ..identify.physical import realise_log_cholesky, standard_of

    T, eta0, S, _ = chart
    pi = standard_of(realise_log_cholesky(T, theta, eta0, S, best=True))
    d = T @ pi - theta0
    if not d @ P @ d <= 1.0 + 1e-9:
        return None
    try:
        plant = robot.with_standard_parameters(pi, spec)
        plant.require_simulable()
        return plant
    except ParameterError:
        return None


def realise_toward(robot, theta0, P, target, *, physical, source: str = "the bounds", spec: str = ""):
    """``(plant, f)``: the plant of the physical link parameters nearest ``theta0 + f (target - theta0)`` for the
    first ``f`` of :data:`PULL` where they lie in the ellipsoid and simulate (the log-Cholesky chart of the
    bounds' ``[physical]`` table: every such plant is a rigid body), as ``rc3r design``'s worst-plant search
    needs for a ``lightest:`` point; None when the bounds have no link parameters for ``robot`` (the 3R);
    ParameterError when no ``f`` gives one."""
    chart = _physical_chart(robot, theta0, physical, source)
    if chart is None:
        return None
    return _pulled(robot, np.asarray(theta0, dtype=float), np.asarray(P, dtype=float),
                   np.asarray(target, dtype=float), chart, spec, source)


def _pulled(robot, theta0, P, target, chart, spec, source):
    """:func:`realise_toward` on a chart: ``(plant, f)`` or ParameterError."""
    for f in PULL:
        plant = _realised(robot, theta0 + f * (target - theta0), theta0, P, chart, spec)
        if plant is not None:
            return plant, f
    raise ParameterError(f"plant {spec!r}: no physical link parameters inside the ellipsoid of {source} realise it")


def _draw_physical(robot, theta0, P, spec, kind, arg, chart, source):
    """:func:`draw_from_ellipsoid` with link parameters realised in the log-Cholesky chart (module docstring)."""
    pi0 = chart[3]
    if kind in ("centre", "center") and not arg:
        plant = robot.with_standard_parameters(pi0, "centre")
        try:
            plant.require_simulable()
        except ParameterError as exc:
            raise ParameterError(f"the centre theta_0 of {source} is not simulable: {exc}") from None
        return plant
    P = np.asarray(P, dtype=float)
    theta0 = np.asarray(theta0, dtype=float)
    if kind == "lightest":  # rc3r design's worst plant: the nearest physical point, pulled inside if need be
        return _pulled(robot, theta0, P, lightest_theta(robot, theta0, P, arg, spec), chart, spec, source)[0]
    if kind not in ("random", "boundary"):
        raise ConfigError(f"bad plant {spec!r} with bounds from {source}: expected nominal, {ELLIPSOID_SPECS}")
    from .box import spec_seed

    rng = np.random.default_rng(spec_seed(spec, kind, arg, "bad plant"))
    for _ in range(MAX_DRAWS):
        plant = _realised(robot, draw_theta(theta0, P, rng, boundary=kind == "boundary"), theta0, P, chart, spec)
        if plant is not None:  # the nearest physical coefficients reached lie in the ellipsoid and simulate
            return plant
    raise ParameterError(f"plant {spec!r}: no physical link parameters realise any of {MAX_DRAWS} draws from the "
                         f"ellipsoid of {source}")


def mass_matrix_of(robot, theta, Q) -> np.ndarray:
    """``M(q)`` (K, n, n) of coefficients ``theta`` (p,) at positions ``Q`` (K, n): :class:`~rc3r.uncertainty.
    inertia.ThetaModel`'s (column i is ``Y(q, 0, 0, e_i) theta - Y(q, 0, 0, 0) theta``), symmetrised."""
    from .inertia import ThetaModel

    model = ThetaModel(robot, theta)
    return np.stack([model.mass_matrix(q) for q in np.atleast_2d(np.asarray(Q, dtype=float))])


def require_positive_mass_matrix(robot, theta, trajectory, duration: float, source: str) -> float:
    """ParameterError (one line) unless ``M(q)`` of ``theta`` is positive definite at :data:`MASS_SAMPLES`
    points of ``trajectory`` over ``[0, duration]``; returns the smallest eigenvalue.

    The message names the smallest eigenvalue, the time and the direction: ``joint j`` when the
    eigenvector is mostly one joint (|v_j| >= 0.9), else its largest components.
    """
    t = np.linspace(0.0, float(duration), MASS_SAMPLES)
    Q = np.asarray(trajectory.evaluate(t)[0], dtype=float)
    lam, V = np.linalg.eigh(mass_matrix_of(robot, theta, Q))
    k = int(np.argmin(lam[:, 0]))
    low = float(lam[k, 0])
    if not low > 0.0:
        v = V[k][:, 0]
        v = v * np.sign(v[np.argmax(np.abs(v))])
        j = int(np.argmax(np.abs(v)))
        if abs(v[j]) >= 0.9:
            where = f"joint {j + 1}"
        else:
            top = np.argsort(-np.abs(v))[:3]
            where = "eigenvector " + " ".join(f"{v[i]:+.2f} q{i + 1}" for i in top)
        raise ParameterError(f"{source}: its mass matrix is not positive definite along the reference: smallest "
                             f"eigenvalue {low:.3g} along {where} at t = {t[k]:.3g} s (not a rigid body; "
                             "identify with the physically consistent fit)")
    return low
