"""The ``fast`` (``compiled``) engine's driver: one instantiation of :mod:`.engines.compiled` per kernel
supply, run in chunks.

**Instantiation.** A robot names its kernel supply by :attr:`~rc3r.robots.base.Robot.compiled_kernels`
``(module, kc)`` (contract: :mod:`.engines._template`). :func:`instantiate` writes the source of
:mod:`.engines.compiled` with its one ``# kernel supply`` import line naming that module and its
``# law dispatch`` line replaced by the dispatch over a choice of laws (:mod:`.engines._dispatch`), beside
the dispatch over a choice of plant effects (:mod:`.engines._effects`).

**Compile once per process.** Every branch is code numba compiles into every integrator, so a choice is
what its process runs (:meth:`CompiledSimulator.for_run`; ``docs/performance.md``, "Compile instances"):
a run takes an instance imported already that covers its law and effects (:func:`loaded`; a superset is
fine), else one whose integrator numba's disk cache holds, else compiles its process's :func:`plan` (``rc3r
run`` plans its own law; ``rc3r paper``, design and campaigns their laws) or the default on exactly the run's
plant effects: the run's law, FBL and robust (:func:`.engines._dispatch.default_laws`) first, every
registered law the second (at most two compiles per supply and effects in a process without a plan).
Each choice is one file, named by a hash of its text (and, for a supply or a law or effect module outside
rc3r, their sources), in a folder keyed by :func:`rc3r._numba_cache.package_hash`, written atomically
and only once (the first writer wins, so numba's stamp, the file's time and size, stays valid), and
imported: numba caches its functions on disk like any module's. Any edit of a numba module of the
package makes a new folder, hence a fresh compile.
The directory is ``$NUMBA_CACHE_DIR/rc3r_engines`` if that is set, else the user's cache
(``$XDG_CACHE_HOME`` or ``~/.cache``)``/rc3r/engines``, else the temporary directory (never
inside the package: :func:`rc3r._numba_cache.package_hash` reads every module there);
instantiations of other package versions older than a day are removed. :class:`CompiledSimulator` is the
instantiation of one supply behind the calls :func:`run` makes; :func:`simulator` builds it, once per supply,
from what a robot declares (the robot itself knows no simulator).

**Chunks.** The compiled integrators run in chunks of :data:`CHUNK_S` simulated seconds: between two
chunks control is back in Python, so Ctrl-C or SIGTERM (which the command line turns into
``KeyboardInterrupt``) stops a long run within one chunk's wall time (about 0.1 s for the paper's robust
law), and the result keeps every chunk finished before it (``status = "interrupted"``). A chunk is also
bounded in work: at most ``SimOptions.max_steps`` integrator steps per simulated second (status ``WORK``,
a "diverged" run whose message names the law's eps), so a loop too stiff to integrate stops within
seconds instead of running for hours.
"""
from __future__ import annotations

import contextlib
import hashlib
import importlib
import importlib.util
import os
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

from .. import _numba_cache
from ..errors import ParameterError
from . import _limits, _result, _sample_grid
from .methods import METHODS, PERIOD_METHODS
from . import status as S
from .engines import _dispatch
from .steps import continuous_method, period_budget

__all__ = ["CompiledSimulator", "simulator", "instantiate", "plan", "planned", "loaded", "effect_codes", "run", "CHUNK_S", "HMAX"]

#: Simulated seconds per compiled call.
CHUNK_S = 0.5

#: Largest continuous-time step [s]; the stored rows are interpolated inside the steps.
HMAX = 0.001

#: The line of :mod:`.engines.compiled` that each instantiation replaces.
MARKER = ("from rc3r.simulate.engines._template import apply_into as _apply, forward_dynamics_into as _fd, "
          "make_work as _make_work, mass_into as _mass, passes_into as _passes, xi_into as _xi  # kernel supply")

#: The optional line: a supply with analytic derivatives (``tangents_into``, ``plant_tangents_into``) names
#: itself there too, one without keeps the stubs of :mod:`.engines._template` (numerical Jacobian).
TANGENT_MARKER = ("from rc3r.simulate.engines._template import plant_tangents_into as _ptangents, "
                  "tangents_into as _tangents  # kernel supply (optional)")
_TANGENTS = ("tangents_into", "plant_tangents_into")

#: Age [s] past which an instantiation of another package version is removed.
STALE_S = 86400.0

_INTEGRATORS = {"continuous": ("integrate_continuous",), "sampled": ("integrate_sampled",),  # a run's kind
                None: ("integrate_continuous", "integrate_sampled")}

_SUPPLY = ("make_work", "regressor_into", "forward_dynamics_into", "passes_into", "xi_into", "apply_into",
           "mass_into")
_DOTTED = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*\Z")
_INSTANCES: dict = {}


def _roots():
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        yield Path(env) / "rc3r_engines"
        return
    yield Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rc3r" / "engines"
    yield Path(tempfile.gettempdir()) / f"rc3r-engines-{os.getuid() if hasattr(os, 'getuid') else 0}"


def _prune(root: Path, keep: str) -> None:
    """Remove the instantiations of other package versions not touched for :data:`STALE_S` (each
    edit of a numba module makes a new one; a day-old one belongs to no running process)."""
    import shutil
    import time

    try:
        for d in root.iterdir():
            if d.is_dir() and d.name != keep and time.time() - d.stat().st_mtime > STALE_S:
                shutil.rmtree(d, ignore_errors=True)
    except OSError:
        pass


def _write_once(path: Path, text: str) -> None:
    """``path`` holds ``text``: written through a temporary file and a hard link (never replaced if
    it already holds it, so its time stamp stays the one numba's cache was stamped with)."""
    try:
        if path.read_text() == text:
            return
        exists = True
    except (OSError, UnicodeDecodeError):
        exists = False
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    tmp.write_text(text)
    try:
        if exists:
            os.replace(tmp, path)
        else:
            try:
                os.link(tmp, path)
            except FileExistsError:  # another process wrote it first: its file stands
                pass
    finally:
        tmp.unlink(missing_ok=True)


def _chosen(registry: list, codes, what: str) -> list:
    """The classes of ``registry`` (by code) whose ``code`` is in ``codes`` (None: all of them); ParameterError
    naming a code no class of it has."""
    if codes is None:
        return list(registry)
    want = sorted({int(c) for c in codes})
    known = {int(c.code) for c in registry}
    unknown = [c for c in want if c not in known]
    if unknown:
        raise ParameterError(f"no compiled {what} has code(s) {unknown} (registered: {sorted(known)})")
    return [c for c in registry if int(c.code) in want]


def instantiate(module: str, laws=None, effects=None, *, only_ready=None):
    """The compiled integrators (:mod:`.engines.compiled`) instantiated on the kernel supply ``module``
    (a dotted module name), for the compiled laws of codes ``laws`` (the law dispatch :mod:`.engines._dispatch`
    writes into it) and the plant effects of codes ``effects`` (the dispatch :func:`.engines._effects.source`
    writes beside it), imported once per process and choice; ParameterError if it is no supply or a code is
    not registered.

    Parameters
    ----------
    module : str
        Dotted name of the kernel supply (:mod:`.engines._template`).
    laws, effects : iterable of int, optional
        Codes of registered compiled laws (:data:`rc3r.controllers.LAWS`) and effects
        (:data:`rc3r.plants.EFFECTS`) the instance has a branch for; None (default): every registered one
        (which instance a run takes: :meth:`CompiledSimulator.for_run`).
    only_ready : tuple of str, optional
        Integrator names (``"integrate_continuous"``, ...): the instance only if imported, or on disk with
        those integrators in numba's disk cache (:func:`rc3r._numba_cache.ready`), else None (nothing written).

    Returns
    -------
    module or None
        The instantiated module (its integrators, ``LAW_CODES`` and ``EFFECT_CODES``).
    """
    from ..plants import EFFECTS
    from .engines import _effects

    law_classes = _chosen(_dispatch.compiled_laws(), laws, "law")
    effect_classes = _chosen(list(_effects.compiled_effects(EFFECTS)), effects, "effect")
    if not law_classes:
        raise ParameterError("an instance of the compiled engine needs at least one law")
    law_reg = {cls.name: cls for cls in law_classes}
    effect_reg = {cls.name: cls for cls in effect_classes}
    sig = _dispatch.signature(law_reg)
    codes = tuple((c.code, c.name, c.value_kernel, c.slope_kernel) for c in effect_classes)
    if (module, sig, codes) in _INSTANCES:
        return _INSTANCES[(module, sig, codes)]
    if not isinstance(module, str) or not _DOTTED.match(module):
        raise ParameterError(f"kernel supply must be a dotted module name, got {module!r}")
    try:
        supply = importlib.import_module(module)
    except ImportError as exc:
        raise ParameterError(f"kernel supply {module!r} cannot be imported: {exc}") from None
    missing = [f for f in _SUPPLY if not hasattr(supply, f)]
    if missing:
        raise ParameterError(f"kernel supply {module!r} lacks {', '.join(missing)} (rc3r.simulate.engines._template)")
    template = (Path(__file__).resolve().parent / "engines" / "compiled.py").read_text()
    if template.count(MARKER) != 1 or template.count(TANGENT_MARKER) != 1 or template.count(_dispatch.MARKER) != 1:
        raise RuntimeError("rc3r.simulate.engines.compiled lost a kernel-supply or law-dispatch line")
    source = template.replace(MARKER, MARKER.replace("rc3r.simulate.engines._template", module))
    source = source.replace(_dispatch.MARKER, _dispatch.law_source(law_reg))
    if all(hasattr(supply, f) for f in _TANGENTS):
        source = source.replace(TANGENT_MARKER, TANGENT_MARKER.replace("rc3r.simulate.engines._template", module))
    if source.count(_effects.MARKER) != 1 or source.count("from rc3r.simulate.engines._effects import") != 1:
        raise RuntimeError("rc3r.simulate.engines.compiled lost an effect-dispatch line")
    dispatch = _effects.source(effect_reg)
    version = hashlib.sha256(f"{_numba_cache.package_hash()}\0{module}\0".encode())
    h = version.copy()
    h.update(source.encode() + b"\0" + dispatch.encode())
    # every module the instantiated text imports counts: the supply, the laws' and the effects' kernel
    # modules (inside the package, package_hash covers those that use numba; outside, their own source)
    for name_ in (module,) + _effects.kernel_modules(effect_reg):
        file_ = getattr(sys.modules.get(name_) or importlib.import_module(name_), "__file__", None)
        if file_ and not _numba_cache._inside(file_):
            h.update(Path(file_).read_bytes())
    for law_file in _dispatch.law_files(law_reg):  # a registered law's module outside the package
        h.update(Path(law_file).read_bytes())
    key, folder = h.hexdigest()[:16], version.hexdigest()[:16]  # one folder per package version and supply
    stem = module.replace(".", "_")
    effects_name = f"_rc3r_effects_{key}"
    source = source.replace(_effects.MARKER, _effects.MARKER.replace("rc3r.simulate.engines._effects", effects_name))
    if only_ready is not None:
        return _ready_on_disk((module, sig, codes), folder, f"{stem}_{key}", effects_name, only_ready)
    errors = []
    for root in _roots():
        path = root / folder / f"{stem}_{key}.py"
        try:
            _write_once(path.with_name(f"{effects_name}.py"), dispatch)
            _write_once(path, source)
            _prune(root, folder)
            break
        except OSError as exc:
            errors.append(f"{root}: {exc.strerror or exc}")
    else:
        raise ParameterError("cannot write the compiled engine's source: " + "; ".join(errors))
    if effects_name not in sys.modules:
        _load(effects_name, path.with_name(f"{effects_name}.py"))
    mod = _load(f"_rc3r_engine_{stem}_{key}", path)
    _INSTANCES[(module, sig, codes)] = mod
    return mod


def _ready_on_disk(ckey: tuple, folder: str, name: str, effects_name: str, which: tuple):
    """The instance ``ckey`` (files ``name``, ``effects_name`` in ``folder`` of a root) if numba's disk cache
    holds its integrators ``which`` (kept then as :func:`instantiate`'s), else None (imported, not kept)."""
    from .._numba_cache import ready

    for root in _roots():
        path = root / folder / f"{name}.py"
        if path.is_file() and path.with_name(f"{effects_name}.py").is_file():
            break
    else:
        return None
    try:
        if effects_name not in sys.modules:
            _load(effects_name, path.with_name(f"{effects_name}.py"))
        mod = _load(f"_rc3r_engine_{name}", path)
        if not all(ready(getattr(mod, f)) for f in which):
            return None
    except Exception:  # noqa: BLE001 - a damaged or half-written file from another process: compile instead
        return None
    _INSTANCES[ckey] = mod
    return mod


def _load(name: str, path: Path):
    """Import the file ``path`` as the module ``name`` (registered in ``sys.modules`` first), once."""
    if getattr(sys.modules.get(name), "__file__", None) == str(path):
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


class CompiledSimulator:
    """The compiled integrators instantiated on the kernel supply ``module`` (:func:`simulator` of a robot).

    ``continuous(rigid, ...)`` returns ``(status, n_stored, n_rhs, n_steps, n_rejected, t_end)``;
    ``sampled(rigid, ..., s0, ...)`` (s0: first sample index) returns
    ``(status, n_stored, n_rhs, n_samples_done, t_end)``; both fill the output arrays ``X``
    (state), ``U`` (torque), ``R`` (q_d), ``yn`` (||Y^T r||), on the constants of
    ``rigid.compiled_kernels``.
    """

    def __init__(self, module: str):
        self.module = module

    def __eq__(self, other):
        return isinstance(other, CompiledSimulator) and other.module == self.module

    def __hash__(self):
        return hash(("CompiledSimulator", self.module))

    def __repr__(self) -> str:
        return f"CompiledSimulator({self.module!r})"

    @property
    def instance(self):
        """The instantiated module on every registered law and effect (:func:`instantiate`)."""
        return instantiate(self.module)

    def for_run(self, law: int, fx=None, which: str | None = None):
        """The instance a run of the law of code ``law`` on a plant of packed effects ``fx`` (:meth:`~rc3r.plants.
        Plant.pack`; None: none) in the ``which`` integrator (``"continuous"``, ``"sampled"``; None: both) takes:
        (1) an instance imported already with a branch for the law and each effect (a superset is fine);
        (2) else the first on disk with that integrator in numba's cache (loading compiles nothing) of: the
        :func:`plan` if it covers the run, every law on the run's effects, the small default
        (:func:`.engines._dispatch.default_laws`) on them, every law on every effect; (3) else compiled: the
        plan, else the small default, or every law if an instance on those effects is imported already (the
        process runs a law the small one lacks) (``docs/performance.md``, "Compile instances").
        """
        from ..plants import EFFECTS
        from .engines import _effects

        codes = effect_codes(fx)
        laws = {c.code: (c.code, c.name, c.__module__) for c in _dispatch.compiled_laws()}
        effects = {c.code: (c.code, c.name, c.value_kernel, c.slope_kernel)
                   for c in _effects.compiled_effects(EFFECTS)}
        if int(law) not in laws or any(c not in effects for c in codes):
            return instantiate(self.module, (int(law),), codes)  # ParameterError naming the code
        need_l, need_e = {laws[int(law)]}, {effects[c] for c in codes}
        for (module, sig, ecodes), mod in _INSTANCES.items():
            if module == self.module and need_l <= set(sig) and need_e <= set(ecodes):
                return mod
        plan_laws, plan_effects = _PLAN[0] if _PLAN else ((), ())
        small, every = (_dispatch.default_laws(law), codes), (None, codes)
        choices = [every, small, (None, None)]
        if int(law) in plan_laws and set(codes) <= set(plan_effects):
            choices.insert(0, (plan_laws, plan_effects))
        funcs = _INTEGRATORS.get(which, _INTEGRATORS[None])
        for laws_, effects_ in choices:
            mod = instantiate(self.module, laws_, effects_, only_ready=funcs)
            if mod is not None:
                return mod
        if choices[0] is not every:  # the plan
            return instantiate(self.module, *choices[0])
        again = any(m == self.module and set(e) == need_e for (m, _, e) in _INSTANCES)
        return instantiate(self.module, *(every if again else small))

    def constants(self, rigid) -> np.ndarray:
        """The packed constants ``kc`` of ``rigid`` (its ``compiled_kernels`` must name this supply)."""
        module, kc = rigid.compiled_kernels
        if module != self.module:
            raise ParameterError(f"robot {rigid.name!r} supplies kernels {module!r}, its engine runs {self.module!r}")
        return np.ascontiguousarray(kc, dtype=np.float64)

    def is_cached(self, which: str | None = None, law: int | None = None, fx=None) -> bool:
        """True if the integrators of this supply a run needs are compiled in this process or held
        valid by numba's disk cache (no compilation on first use, :func:`rc3r._numba_cache.ready`):
        ``which`` ``"sampled"``, ``"continuous"``, or None for both; ``law`` and ``fx`` as in :meth:`for_run`
        (None: the instance of every registered law and effect).

        Reads numba's cache index (an internal of numba 0.59-0.68); if it cannot be read, answers
        True (no announcement and no cold-start fallback rather than a wrong one).
        """
        from .._numba_cache import ready

        try:
            mod = self.instance if law is None else self.for_run(law, fx, which)
            funcs = {"sampled": (mod.integrate_sampled,), "continuous": (mod.integrate_continuous,)}.get(
                which, (mod.integrate_continuous, mod.integrate_sampled))
        except (AttributeError, ParameterError):
            return True
        return all(ready(f) for f in funcs)

    def continuous(self, rigid, fx, code, cp, tp, x0, t_out, rtol, atol, h0, hmax, lim, X, U, R, yn, jac_reuse,
                   max_steps, kc=None, method=0):
        """``kc``: :meth:`constants` of ``rigid`` if already packed (a run packs them once for all its chunks);
        ``method``: a code of :data:`rc3r.simulate.METHODS` (default 0, ode23s)."""
        kc = self.constants(rigid) if kc is None else kc
        return self.for_run(code, fx, "continuous").integrate_continuous(x0, t_out, kc, fx, code, cp, tp, rtol, atol, h0,
                                                  hmax, lim, X, U, R, yn, jac_reuse, max_steps, int(method))

    def sampled(self, rigid, fx, code, cp, tp, x0, s0, Ts, nsamples, dec, nsub, lim, X, U, R, yn, tv, noise, quant,
                ubuf, kc=None, stiff=0, rtol=1e-6, atol=1e-8, budget=1000):
        """``stiff``: a code of :data:`PERIOD_METHODS` (``SimOptions.sampled_method``): 0 advances the plant by
        ``nsub`` RK4 sub-steps, 1 by adaptive ROS4 steps and 2 by adaptive RODAS steps (``rtol``, ``atol``, at
        most ``budget`` per period)."""
        kc = self.constants(rigid) if kc is None else kc
        return self.for_run(code, fx, "sampled").integrate_sampled(x0, s0, Ts, nsamples, dec, nsub, kc, fx, code, cp,
                                               tp, lim, X, U, R, yn, tv, noise, quant, ubuf, int(stiff),
                                               float(rtol), float(atol), int(budget))


_PLAN: list = []

def plan(laws=(), effects=()) -> tuple:
    """From now on in this process (and in the worker processes it forks), a run of one of the compiled laws
    of codes ``laws`` on a plant whose effects are among the codes ``effects`` takes the one instance of all
    of them (:meth:`CompiledSimulator.for_run`): a command that runs several laws (``rc3r paper``, a design, a
    campaign) compiles each integrator once, not once per law. Returns the plan it replaces (``()``: none).

    Parameters
    ----------
    laws, effects : iterable of int
        Codes of registered compiled laws and plant effects (a law with no compiled kernel, code None, is
        skipped); ParameterError at the first run if one is not registered. Both empty: no plan.
    """
    before = _PLAN[0] if _PLAN else ()
    law_codes = tuple(sorted({int(c) for c in laws if c is not None}))
    _PLAN[:] = [(law_codes, tuple(sorted({int(c) for c in effects})))] if law_codes else []
    return before


@contextlib.contextmanager
def planned(laws=(), effects=(), keep: bool = False):
    """:func:`plan` within a ``with`` block; the plan before it is restored after. ``keep``: a plan already
    made in this process stands (the caller's, e.g. a test suite's or a script's that runs several commands
    in one process); ``rc3r run`` plans its own law so."""
    if keep and _PLAN:
        yield
        return
    before = plan(laws, effects)
    try:
        yield
    finally:
        _PLAN[:] = [before] if before else []


def loaded(module: str | None = None) -> tuple:
    """The compiled instances imported in this process (in import order), of the kernel supply ``module``
    (None: every supply), each compiled or loaded once: the count behind :meth:`CompiledSimulator.for_run`."""
    return tuple(mod for (m, _, _), mod in _INSTANCES.items() if module is None or m == module)


def effect_codes(fx) -> tuple[int, ...]:
    """The effect codes of packed effects ``fx`` (:meth:`rc3r.plants.Plant.pack`), sorted, once each; () for None."""
    if fx is None:
        return ()
    m = int(fx[0])
    return tuple(sorted({int(c) for c in np.asarray(fx)[1:1 + 2 * m:2]}))


#: One :class:`CompiledSimulator` per supply module, shared by every robot that declares it.
_SIMULATORS: dict[str, CompiledSimulator] = {}


def simulator(rigid) -> CompiledSimulator | None:
    """The compiled simulator of a rigid body, built from the kernels it declares.

    Parameters
    ----------
    rigid : rc3r.plants.RigidBody
        A robot (or any rigid body): its declared ``compiled_kernels``, ``(module, kc)``
        (:attr:`rc3r.robots.base.Robot.compiled_kernels`), or None.

    Returns
    -------
    CompiledSimulator or None
        The one instance for that supply module (the same object for every robot that declares it),
        or None if ``rigid`` declares no compiled kernels (the generic Python engine runs it).
    """
    declared = rigid.compiled_kernels
    if declared is None:
        return None
    module = declared[0]
    if module not in _SIMULATORS:
        _SIMULATORS[module] = CompiledSimulator(module)
    return _SIMULATORS[module]


def run(plant, law, trajectory, opt, x0, loop=None, model=None):
    """Simulate on the rigid body's compiled simulator; ``plant`` is a :class:`~rc3r.plants.Plant` whose
    effects are compiled ones (packed by :meth:`~rc3r.plants.Plant.pack`), ``loop`` the sampled loop's
    effects (or None). ``model`` is ignored: the compiled regressor is the rigid body's, whose
    kinematics :func:`rc3r.simulate.simulate` checked equal to the model's."""
    rigid = plant.rigid
    eng = simulator(rigid)
    n = plant.n
    fx = plant.pack()
    which = "continuous" if opt.rate is None else "sampled"
    stale = [e.name for e in plant.packed() if e.code not in eng.for_run(law.code, fx, which).EFFECT_CODES]
    if stale:  # cannot happen through instantiate (keyed on the registry); a guard for a hand-made instance
        raise ParameterError(f"the compiled engine has no branch for plant effect(s) {', '.join(stale)}")
    kc = eng.constants(rigid)  # once per run (packing the UR5's took 0.4 ms per chunk)
    cp, tp, code = law.pack(n), trajectory.pack(), int(law.code)
    lim = _limits(opt)
    size = x0.size
    if opt.rate is None:
        nout = int(round(opt.duration * opt.output_rate)) + 1
        t_out = np.linspace(0.0, opt.duration, nout)
        X = np.zeros((nout, size)); U = np.zeros((nout, n)); R = np.zeros((nout, n)); yn = np.zeros(nout)
        X[0] = x0
        hmax = HMAX
        per = max(1, int(round(CHUNK_S * opt.output_rate)))
        start, stored, st, t_end, counts = 0, 0, S.OK, 0.0, np.zeros(3, dtype=np.int64)
        method = METHODS[continuous_method(law, opt).method]  # once per run, not per chunk
        h0 = 1e-5  # the first step; a later chunk starts at its predecessor's mean step, not from 1e-5 again
        try:
            while True:
                end = min(start + per, nout - 1)
                budget = max(1000, int(np.ceil(opt.max_steps * (t_out[end] - t_out[start]))))
                st_k, m, nrhs, nsteps, nrej, t_k = eng.continuous(
                    rigid, fx, code, cp, tp, X[start].copy(), t_out[start:end + 1], opt.rtol, opt.atol, h0, hmax,
                    lim, X[start:end + 1], U[start:end + 1], R[start:end + 1], yn[start:end + 1], opt.jac_reuse,
                    budget, kc=kc, method=method)
                counts += (nrhs, nsteps, nrej)
                stored, st, t_end = start + m, st_k, t_k
                if st != S.OK or end == nout - 1:
                    break
                h0 = min(hmax, max(1e-5, (t_k - t_out[start]) / max(int(nsteps), 1)))
                start = end
        except KeyboardInterrupt:
            st = S.INTERRUPTED
        m = stored
        return _result(plant, law, trajectory, opt, t_out[:m], X[:m], U[:m], R[:m], yn[:m],
                       st, t_end, *counts)
    Ts, nsamples, dec = _sample_grid(opt)
    nout = nsamples // dec + 2
    X = np.zeros((nout, size)); U = np.zeros((nout, n)); R = np.zeros((nout, n)); yn = np.zeros(nout)
    X[0] = x0
    tv = np.zeros(n)
    noise = loop.noise(nsamples) if loop is not None else np.zeros((0, 2 * n))
    quant = loop.quantization if loop is not None else np.zeros(n)
    ubuf = np.zeros(((loop.delay if loop is not None else 0) + 1, n))  # the delay line, across chunks
    per = max(1, int(round(CHUNK_S * opt.rate)) // dec) * dec  # samples per call, a multiple of dec
    stiff = PERIOD_METHODS[opt.sampled_method]
    budget = period_budget(opt)
    s0, row, stored, st, t_end, nrhs_all, done = 0, 0, 0, S.OK, 0.0, 0, 0
    try:
        while True:
            k = min(per, nsamples - s0)
            st_k, m, nrhs, ndone, t_k = eng.sampled(
                rigid, fx, code, cp, tp, X[row].copy(), s0, Ts, k, dec, opt.substeps, lim,
                X[row:], U[row:], R[row:], yn[row:], tv, noise, quant, ubuf, kc=kc, stiff=stiff,
                rtol=opt.period_rtol, atol=opt.period_atol, budget=budget)
            nrhs_all += nrhs
            stored, st, t_end, done = row + m, st_k, t_k, s0 + ndone
            if st != S.OK or s0 + k >= nsamples:
                break
            s0 += k
            row = stored - 1  # the chunk's last sample is the next chunk's first
    except KeyboardInterrupt:
        st = S.INTERRUPTED
    m = stored
    t = np.arange(m) * dec * Ts
    if st not in (S.OK, S.INTERRUPTED) and m > 0:
        t[-1] = t_end
    return _result(plant, law, trajectory, opt, t, X[:m], U[:m], R[:m], yn[:m],
                   st, t_end, nrhs_all, done, 0, tv=tv)
