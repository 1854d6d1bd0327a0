r"""Generated dynamics kernels: symbolic (CasADi SX), common subexpressions eliminated, compiled C.

For one serial (or tree) arm of 1-DoF revolute/prismatic joints, this module writes the
recursive Newton--Euler algorithm, the composite-rigid-body algorithm and the Slotine--Li
regressor on CasADi ``SX`` symbols from the chain's constants, with the arm's numeric standard
parameters embedded (one arm, one library), eliminates common subexpressions
(``casadi.cse``), generates C with ``casadi.CodeGenerator``, adds a small hand-written wrapper
with batch entry points, compiles it with the system C compiler and loads it with
:mod:`ctypes`. ``pinocchio.casadi`` is not used (the ``pin`` wheel has no CasADi bindings):
the recursions are written here, and ``tests/test_generated.py`` checks them against
Pinocchio's ``rnea``, ``crba``, ``computeCoriolisMatrix``, ``computeGeneralizedGravity``,
``aba`` and the Slotine--Li regressor of :meth:`~rc3r.robots.pinocchio.PinocchioRobot.regressor_pinocchio`.

Conventions (``docs/conventions.md``): SI units; spatial vectors ``(linear, angular)`` as in
Pinocchio; every body's quantities in its own joint frame (Pinocchio's ``LOCAL``); standard
parameters Pinocchio's ``(m, m c, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)`` per body, about the
joint-frame origin in the joint frame. Joint ``j`` (parent ``lambda(j)``, fixed placement
``(R0_j, p0_j)`` in its parent's frame, constant unit axis ``u_j`` in its own frame):

* revolute: ``R_j = R0_j Rot(u_j, q_j)``, ``p_j = p0_j``, motion subspace ``S_j = (0, u_j)``;
* prismatic: ``R_j = R0_j``, ``p_j = p0_j + R0_j u_j q_j``, ``S_j = (u_j, 0)``.

Constants within 1e-14 of 0 or +-1 (``cos(pi/2)`` of a URDF ``rpy``) are snapped to them before
the expressions are built, so that the products they enter vanish from the graph; the change is
below 1e-14 relative and far inside the tests' tolerances.

Functions (all per state; batch entry points loop over N states of row-major ``(N, n)`` arrays):

``rnea(q, qd, qdd) -> tau``
    ``tau = M(q) qdd + C(q, qd) qd + g(q)`` [N m or N], Newton--Euler with gravity.
``slotine_li(q, qd, v, a) -> Y`` (n, p)
    ``Y theta = M(q) a + C(q, qd) v + g(q)`` in the base parameters ``theta`` (``robot.theta``):
    the Jacobian, with respect to symbolic standard parameters, of the polarized Newton--Euler
    torque ``NE_g(q, (qd + v)/2, a/2) - NE_0(q, (qd - v)/2, -a/2)`` (:mod:`rc3r.robots.pinocchio`),
    which is linear in them, so the Jacobian is exact; only the base columns
    (``robot.base.independent``) are made symbolic, the others are zero.
``mass(q) -> M`` (n, n)
    Composite-rigid-body algorithm; symmetric (both triangles filled).
``coriolis(q, qd) -> C`` (n, n)
    The Christoffel matrix, ``C_ij = sum_k Gamma_ijk qd_k``: with ``c(q, x) = C(q, x) x`` the
    Newton--Euler torque without gravity at zero acceleration, ``C(q, qd) = 1/2 dc/dx (q, qd)``
    (``Gamma_ijk`` is symmetric in j, k); ``dM/dt - 2 C`` is skew-symmetric and ``C`` equals
    ``pinocchio.computeCoriolisMatrix``.
``gravity(q) -> g`` (n,)
    Newton--Euler at ``qd = qdd = 0``.
``aba(q, qd, tau) -> qdd`` (n,)
    ``qdd = M(q)^{-1} (tau - rnea(q, qd, 0))``: M by the composite-rigid-body algorithm, the bias
    by Newton--Euler, and a Cholesky factorization ``M = L L^T`` with its two triangular solves
    unrolled into the same generated C (no pivoting: M is positive definite). Chosen over a
    symbolic articulated-body recursion because it reuses the two recursions already checked
    (``mass``, ``rnea``) so the expression graphs share their kinematics after CSE, and for
    the few joints of an arm (n <= 7) the unrolled factorization is a few hundred flops, no more
    than ABA's 6 x 6 articulated inertias cost; a state where M is not positive definite gives NaN.

Cache: a library is kept under ``cache_dir/<key>/`` (default ``$RC3R_CACHE_DIR/kernels`` if that
variable is set, else ``~/.cache/rc3r/kernels``), where ``key`` is a SHA-256 of the chain's
constants and standard parameters (their float64 bytes), the base columns, the function list,
the CasADi version, the compiler (name, ``--version`` first line) and flags, and the text of this
file, of :mod:`.generated_chain` and of :mod:`.generated_sym`. Each entry is built in a temporary directory next to it and moved in by ``os.replace``,
so a concurrent process sees either no entry or a complete one; a cache hit generates and
compiles nothing. Compiler: ``$RC3R_CC``, else ``$CC``, else ``cc``.

Not done yet: the compiled numba engine (:mod:`rc3r.simulate`) does not call these kernels.
"""
from __future__ import annotations

import ctypes
import functools
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from ..errors import ConfigError, ParameterError
from .base import stack_states
from .generated_chain import FUNCTIONS, Chain
from .generated_sym import _functions, _wrapper
from .pinocchio_kernel import local_axis

__all__ = ["GeneratedKernels", "DEFAULT_FLAGS", "default_cache_dir", "chain_constants"]

#: Compiler flags (``-O3`` gave no consistent gain: ``docs/generated.md``).
DEFAULT_FLAGS = ("-O2", "-shared", "-fPIC")

#: Bumped when the layout of a cache entry changes.
_FORMAT = 1
_LIB = "librc3r_gen.so"


def default_cache_dir() -> Path:
    """``$RC3R_CACHE_DIR/kernels`` if that variable is set (non-empty), else ``~/.cache/rc3r/kernels``."""
    base = os.environ.get("RC3R_CACHE_DIR")
    return Path(base) / "kernels" if base else Path.home() / ".cache" / "rc3r" / "kernels"


def chain_constants(model, where: str = "model") -> Chain:
    """The :class:`Chain` of a ``pinocchio.Model`` whose joints are all revolute or prismatic (1-DoF).

    Raises
    ------
    ParameterError
        A joint that is not 1-DoF (``nq == nv == 1``: a URDF ``continuous`` joint has nq = 2, a
        floating base 7), a helical or other joint whose motion is not a pure rotation or
        translation about a constant axis, or non-finite constants.
    """
    import pinocchio as pin

    n = model.njoints - 1
    if n < 1:
        raise ParameterError(f"{where}: no moving joint")
    for j in range(1, model.njoints):
        jm = model.joints[j]
        if jm.nq != 1 or jm.nv != 1:
            raise ParameterError(f"{where}: joint {j} '{model.names[j]}' ({jm.shortname()}) has nq={jm.nq}, "
                                 f"nv={jm.nv}; generated kernels need 1-DoF revolute or prismatic joints")
    data = model.createData()
    pin.computeJointJacobians(model, data, pin.neutral(model))
    parent, revolute = np.empty(n, dtype=np.int64), np.empty(n, dtype=bool)
    R0, p0, axis, pi = np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 10))
    for j in range(n):
        S = local_axis(model, data, j + 1)
        rev = bool(np.linalg.norm(S[3:]) > 0.5)
        if np.linalg.norm(S[:3] if rev else S[3:]) > 1e-12:
            raise ParameterError(f"{where}: joint {j + 1} '{model.names[j + 1]}' ({model.joints[j + 1].shortname()}) "
                                 "is neither a pure rotation nor a pure translation (helical?)")
        placement = model.jointPlacements[j + 1]
        parent[j], revolute[j] = model.parents[j + 1] - 1, rev
        R0[j], p0[j] = placement.rotation, placement.translation
        axis[j] = S[3:] if rev else S[:3]
        pi[j] = model.inertias[j + 1].toDynamicParameters()
    gravity = np.array(model.gravity.vector, dtype=float)
    if not all(np.all(np.isfinite(x)) for x in (R0, p0, axis, pi, gravity)):
        raise ParameterError(f"{where}: non-finite placements, axes, inertias or gravity")
    return Chain(parent, revolute, R0, p0, axis, gravity, pi)


# ---- compiler and cache -------------------------------------------------------------------------


def _compiler(compiler: str | None) -> str:
    return compiler or os.environ.get("RC3R_CC") or os.environ.get("CC") or "cc"


@functools.lru_cache(maxsize=8)
def _compiler_id(compiler: str) -> tuple[str, str]:
    """(absolute path, first line of ``--version``) of the C compiler; ConfigError if it is missing."""
    path = shutil.which(compiler)
    if path is None:
        raise ConfigError(f"C compiler {compiler!r} not found: generated kernels need one "
                          "(install cc/gcc/clang or set RC3R_CC)")
    try:
        out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=60)
        line = (out.stdout or out.stderr).strip().splitlines()
    except (OSError, subprocess.SubprocessError) as exc:
        raise ConfigError(f"C compiler {compiler!r} ({path}) does not run: {type(exc).__name__}") from None
    return path, line[0] if line else ""


def _this_source() -> bytes:
    """The text of this module, of :mod:`.generated_chain` (the functions generated) and of
    :mod:`.generated_sym` (the expressions): all three enter the cache key."""
    here = Path(__file__)
    return b"".join(here.with_name(name).read_bytes() for name in (here.name, "generated_chain.py", "generated_sym.py"))


def cache_key(chain: Chain, columns, names, compiler: str, flags) -> str:
    """SHA-256 (hex) of everything the library depends on (module docstring)."""
    import casadi as cs

    path, version = _compiler_id(compiler)
    h = hashlib.sha256()
    for part in (f"rc3r-generated-{_FORMAT}".encode(), chain.digest_bytes(),
                 np.asarray(columns, dtype=np.int64).tobytes(), ",".join(names).encode(), cs.__version__.encode(),
                 compiler.encode(), path.encode(), version.encode(), "\0".join(flags).encode(), _this_source()):
        h.update(len(part).to_bytes(8, "little"))
        h.update(part)
    return h.hexdigest()


def _compile(cc: str, flags, sources, target: Path, cwd: Path) -> float:
    t0 = time.perf_counter()
    try:
        proc = subprocess.run([cc, *flags, "-o", str(target), *map(str, sources), "-lm"], cwd=cwd,
                              capture_output=True, text=True)
    except OSError as exc:
        raise ConfigError(f"cannot run the C compiler {cc!r}: {exc.strerror or type(exc).__name__}") from None
    if proc.returncode != 0:
        lines = [ln.strip() for ln in (proc.stderr or proc.stdout).splitlines() if ln.strip()]
        first = next((ln for ln in lines if "error" in ln.lower()), lines[0] if lines else "no message")
        raise ConfigError(f"compiling the generated kernels with {cc} failed (exit {proc.returncode}): {first[:300]}")
    return time.perf_counter() - t0


class GeneratedKernels:
    """Compiled C kernels of one arm: ``rnea``, ``slotine_li``, ``mass``, ``coriolis``, ``gravity``, ``aba``.

    Build with :meth:`for_robot` or :meth:`for_model`. Every method takes (n,) or (N, n) float arrays
    (broadcast against each other) and returns the shape of the corresponding
    :class:`~rc3r.robots.pinocchio.PinocchioRobot` method: (n,) / (N, n), (n, n) / (N, n, n), or
    (n, p) / (N, n, p). The batch calls release the GIL (ctypes).

    Attributes
    ----------
    key : str
        SHA-256 of the cache entry (module docstring).
    library_path, source_path : pathlib.Path
        The shared library and the CasADi-generated C file.
    compile_seconds, generate_seconds : float
        Wall time of the compiler and of building + CSE + code generation; 0.0 when loaded from the cache.
    n, p : int
        Joints, base parameters (columns of ``slotine_li``).
    columns : numpy.ndarray
        (p,) the standard-parameter columns of ``slotine_li`` (``robot.base.independent``).
    """

    def __init__(self, directory: Path, key: str, meta: dict, compile_seconds: float, generate_seconds: float):
        self.key = key
        self.directory = Path(directory)
        self.library_path = self.directory / _LIB
        self.source_path = self.directory / meta["source"]
        self.wrapper_path = self.directory / meta["wrapper"]
        self.compile_seconds = float(compile_seconds)
        self.generate_seconds = float(generate_seconds)
        self.meta = meta
        self.n, self.p = int(meta["n"]), int(meta["p"])
        self.columns = np.asarray(meta["columns"], dtype=np.int64)
        self.functions = tuple(meta["functions"])
        self._lib = ctypes.CDLL(str(self.library_path))
        self._fns = {}
        for name in self.functions:
            fn = getattr(self._lib, f"rc3r_gen_{name}_batch")
            fn.restype = None
            fn.argtypes = [ctypes.c_int] + [ctypes.c_void_p] * (len(FUNCTIONS[name]) + 1)
            self._fns[name] = fn

    # ---- construction -----------------------------------------------------------------
    @classmethod
    def for_robot(cls, robot, cache_dir=None, functions=None, compiler: str | None = None,
                  flags=None) -> "GeneratedKernels":
        """The kernels of a :class:`~rc3r.robots.pinocchio.PinocchioRobot` (its model, standard
        parameters and base columns ``robot.base.independent``), from the cache or built.

        Parameters
        ----------
        robot : PinocchioRobot
            A :class:`~rc3r.robots.base.Robot` with base parameters (``robot.base``, not None) and its
            ``pinocchio.Model``.
        cache_dir : path, optional
            Default :func:`default_cache_dir`.
        functions : sequence of str, optional
            A subset of :data:`FUNCTIONS` (default all).
        compiler : str, optional
            C compiler; default ``$RC3R_CC``, ``$CC`` or ``cc``.
        flags : sequence of str, optional
            Compiler flags, default :data:`DEFAULT_FLAGS` (must produce a shared library).

        Raises
        ------
        ParameterError
            Not an arm of 1-DoF revolute/prismatic joints, or base columns out of range.
        ConfigError
            CasADi missing, no C compiler, or the compilation failed (one line each).
        """
        from .base import Robot

        if not isinstance(robot, Robot) or robot.base is None:  # the contract declares base (None: no base columns)
            raise ParameterError(f"{type(robot).__name__} has no pinocchio model and base columns: "
                                 "use a PinocchioRobot (or GeneratedKernels.for_model)")
        return cls.for_model(robot.model, robot.base.independent, cache_dir=cache_dir, functions=functions, compiler=compiler,
                             flags=flags, where=robot.robot_name or "robot")

    @classmethod
    def for_model(cls, model, columns, cache_dir=None, functions=None, compiler: str | None = None,
                  flags=None, where: str = "model") -> "GeneratedKernels":
        """The kernels of a ``pinocchio.Model`` with Slotine--Li ``columns`` (indices among its 10 nb
        standard parameters); see :meth:`for_robot`."""
        try:
            import casadi as cs
        except ImportError:
            raise ConfigError("generated kernels need CasADi: pip install 'casadi>=3.6'") from None
        chain = chain_constants(model, where)
        columns = np.asarray(columns, dtype=np.int64).ravel()
        if columns.size == 0 or columns.min() < 0 or columns.max() >= 10 * chain.n or np.unique(columns).size != columns.size:
            raise ParameterError(f"{where}: base columns must be distinct indices in [0, {10 * chain.n}), "
                                 f"got {columns.size} of them")
        names = tuple(FUNCTIONS) if functions is None else tuple(functions)
        unknown = [f for f in names if f not in FUNCTIONS]
        if unknown or not names:
            raise ParameterError(f"unknown generated function(s) {unknown} (known: {', '.join(FUNCTIONS)})")
        cc = _compiler(compiler)
        flags = tuple(DEFAULT_FLAGS if flags is None else flags)
        key = cache_key(chain, columns, names, cc, flags)
        root = Path(cache_dir) if cache_dir is not None else default_cache_dir()
        final = root / key
        meta = cls._read_meta(final)
        if meta is not None:
            return cls(final, key, meta, 0.0, 0.0)
        try:
            root.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ConfigError(f"cannot create the kernel cache {root}: {exc.strerror or exc}") from None
        t0 = time.perf_counter()
        funcs, shapes = _functions(chain, columns, names)
        gen = cs.CodeGenerator("rc3r_kernels.c", {"with_header": False})
        for f in funcs.values():
            gen.add(f)
        source, wrapper = gen.dump(), _wrapper(funcs)
        generate_seconds = time.perf_counter() - t0
        tmp = Path(tempfile.mkdtemp(prefix=f".{key[:12]}-", dir=root))
        try:
            (tmp / "rc3r_kernels.c").write_text(source)
            (tmp / "rc3r_wrap.c").write_text(wrapper)
            compile_seconds = _compile(cc, flags, ["rc3r_kernels.c", "rc3r_wrap.c"], tmp / _LIB, tmp)
            meta = {"format": _FORMAT, "n": chain.n, "p": int(columns.size), "columns": columns.tolist(),
                    "functions": list(names), "shapes": {k: list(shapes[k]) for k in names},
                    "instructions": {k: int(f.n_instructions()) for k, f in funcs.items()},
                    "casadi": cs.__version__, "compiler": list(_compiler_id(cc)), "flags": list(flags),
                    "source": "rc3r_kernels.c", "wrapper": "rc3r_wrap.c",
                    "generate_seconds": generate_seconds, "compile_seconds": compile_seconds, "where": where}
            (tmp / "meta.json").write_text(json.dumps(meta, indent=1))
            try:
                os.replace(tmp, final)  # atomic; fails if another process put the entry there first
            except OSError:
                other = cls._read_meta(final)
                if other is not None:  # a concurrent build won: use it
                    shutil.rmtree(tmp, ignore_errors=True)
                    return cls(final, key, other, 0.0, 0.0)
                shutil.rmtree(final, ignore_errors=True)  # an incomplete entry (a library deleted by hand)
                try:
                    os.replace(tmp, final)
                except OSError as exc:
                    raise ConfigError(f"cannot move the compiled kernels into the cache {final}: "
                                      f"{exc.strerror or exc}") from None
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return cls(final, key, meta, compile_seconds, generate_seconds)

    @staticmethod
    def _read_meta(directory: Path):
        """The entry's metadata if it is complete (``meta.json`` and the library), else None."""
        try:
            meta = json.loads((directory / "meta.json").read_text())
        except (OSError, ValueError):
            return None
        return meta if meta.get("format") == _FORMAT and (directory / _LIB).is_file() else None

    # ---- evaluation -------------------------------------------------------------------
    def _call(self, name: str, *xs) -> np.ndarray:
        if name not in self._fns:
            raise ConfigError(f"{name} was not generated for this library (functions: {', '.join(self.functions)})")
        single, X = stack_states(self.n, *xs)  # X[k] (N, n): C-contiguous float64
        xs, N = list(X), X.shape[1]
        out_shape = tuple(self.meta["shapes"][name])
        out = np.empty((N,) + out_shape)
        self._fns[name](N, *(x.ctypes.data for x in xs), out.ctypes.data)
        return out[0] if single else out

    def rnea(self, q, qd, qdd) -> np.ndarray:
        """Inverse dynamics ``tau = M(q) qdd + C(q, qd) qd + g(q)`` [N m or N], (n,) or (N, n).

        q [rad or m], qd, qdd: (n,) or (N, n). Equals ``pinocchio.rnea`` (with the model's gravity).
        """
        return self._call("rnea", q, qd, qdd)

    def slotine_li(self, q, qd, v, a) -> np.ndarray:
        """Slotine--Li regressor in the base parameters, (n, p) or (N, n, p).

        Identity: ``slotine_li(q, qd, v, a) @ robot.theta == M(q) a + C(q, qd) v + g(q)``; equals
        ``robot.regressor`` and ``robot.regressor_pinocchio`` (columns ``robot.base.independent``).
        """
        return self._call("slotine_li", q, qd, v, a)

    def mass(self, q) -> np.ndarray:
        """Joint-space inertia M(q), (n, n) or (N, n, n), symmetric positive definite (``pinocchio.crba``)."""
        return self._call("mass", q)

    def coriolis(self, q, qd) -> np.ndarray:
        """Christoffel matrix C(q, qd), (n, n) or (N, n, n): ``C qd`` is the Coriolis/centrifugal torque,
        ``dM/dt - 2 C`` is skew-symmetric (``pinocchio.computeCoriolisMatrix``)."""
        return self._call("coriolis", q, qd)

    def gravity(self, q) -> np.ndarray:
        """Generalized gravity g(q) [N m or N], (n,) or (N, n) (``pinocchio.computeGeneralizedGravity``)."""
        return self._call("gravity", q)

    def aba(self, q, qd, tau) -> np.ndarray:
        """Forward dynamics ``qdd = M(q)^{-1} (tau - C(q, qd) qd - g(q))``, (n,) or (N, n) (``pinocchio.aba``);
        NaN where M is not positive definite."""
        return self._call("aba", q, qd, tau)

    forward_dynamics = aba

    def __repr__(self) -> str:
        return f"<GeneratedKernels n={self.n} p={self.p} key={self.key[:12]} {self.library_path}>"
