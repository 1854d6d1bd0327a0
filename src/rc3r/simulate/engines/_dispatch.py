r"""The compiled engine's dispatch over the registered laws, written from :data:`rc3r.controllers.LAWS`.

The integrators of :mod:`.compiled` call a law through seven functions of its integer ``code``. They are
not written by hand: :func:`law_source` writes them from the registry when :func:`rc3r.simulate._fast.instantiate`
instantiates the engine on a kernel supply, one branch per compiled law of the instance (the run's, or a
command's planned set; its module's kernels,
:mod:`rc3r.controllers.base`) and none that falls through: a code no law has raises. The text replaces the
line of :mod:`.compiled` marked ``# law dispatch`` (:data:`MARKER`); the instantiation's cache key counts
that text, the package's numba modules (:func:`rc3r._numba_cache.package_hash`) and the source of any law
module outside the package (:func:`law_files`), so a new or edited law compiles afresh. The stubs below
keep the template importable as it stands; they raise if ever compiled and called.

=====================  ===========================================================================
``law_signals``        the law's ``signals``: v, a, r, w                              (value, inlined)
``inertia_gain``       its ``inertia_gain``: the scheduled K's b                       (value, inlined)
``uses_xi``            its ``USES_XI``: whether ``law_theta`` reads xi = Y^T r          (value, inlined)
``law_theta``          its ``theta``: theta_eff, zdot, ||xi||                          (value, inlined)
``law_slopes``         its ``slopes``: G, W_x                               (derivative, inlined)
``law_directions``     its ``directions``: the b of ``b^T d(Y^T r)``          (derivative)
``law_jacobian``       :func:`._jacobian.signal_columns`, its ``theta_columns`` and ``state_gain``, then
                       :func:`._jacobian.finish`: J and f_t                  (derivative)
=====================  ===========================================================================
"""
from __future__ import annotations

import sys

from numba import njit

from ..._numba_cache import _inside

__all__ = ["MARKER", "LAW_CODES", "DEFAULT_COMPANIONS", "default_laws", "law_source", "law_files", "compiled_laws",
           "signature"]

#: The line of :mod:`.compiled` that each instantiation replaces with :func:`law_source`.
MARKER = ("from rc3r.simulate.engines._dispatch import LAW_CODES, inertia_gain, law_directions, law_jacobian, "
          "law_signals, law_slopes, law_theta, uses_xi  # law dispatch")

#: The law codes this dispatch has a branch for (none in the stubs; an instance's are its laws').
LAW_CODES = ()

_JIT = dict(cache=True, nogil=True)


def compiled_laws(laws=None) -> list:
    """The registered law classes with a compiled kernel (``code`` not None), by code."""
    if laws is None:
        from ...controllers import LAWS as laws
    return sorted((cls for cls in laws.values() if cls.code is not None), key=lambda cls: cls.code)


#: The laws a run's default instance has beside its own (names): the paper's pair, FBL and Spong's robust law,
#: which every comparison of rc3r starts from (``rc3r paper``, the examples, design's and the campaigns' lists).
DEFAULT_COMPANIONS = ("fbl", "robust")


def default_laws(law: int) -> tuple[int, ...]:
    """Codes of the default instance's laws for a run of the law of code ``law`` without a plan: it and
    :data:`DEFAULT_COMPANIONS`, sorted. Every law branch is code numba compiles into each integrator (about
    1 s of CPU per law and integrator on the 3R), so the default is small; a script running a law outside it
    compiles a second instance (``docs/performance.md``, "Compile instances")."""
    from ...controllers import LAWS

    extra = {LAWS[name].code for name in DEFAULT_COMPANIONS if name in LAWS and LAWS[name].code is not None}
    return tuple(sorted({int(law)} | {int(c) for c in extra}))


def signature(laws=None) -> tuple:
    """``((code, name, module), ...)`` of the compiled laws: what the dispatch is written from."""
    return tuple((cls.code, cls.name, cls.__module__) for cls in compiled_laws(laws))


def law_files(laws=None) -> list[str]:
    """Source files of the compiled laws' modules outside the package (their bytes count in the cache key)."""
    out = []
    for cls in compiled_laws(laws):
        f = getattr(sys.modules.get(cls.__module__), "__file__", None)
        if f and not _inside(f) and f not in out:
            out.append(f)
    return out


def law_source(laws=None) -> str:
    """The Python source that replaces :data:`MARKER` in :mod:`.compiled`: the seven dispatch functions.

    Parameters
    ----------
    laws : dict, optional
        name -> law class (default :data:`rc3r.controllers.LAWS`); its compiled laws get one branch each
        (laws whose kernel is one function share a branch naming each code), an unknown code raises.

    Returns
    -------
    str
        Module-level source: the law modules' imports and the seven ``@njit`` functions (module docstring).
    """
    laws = compiled_laws(laws)
    if not laws:
        raise ValueError("no compiled law is registered")
    imports = [f"import {cls.__module__} as _law_{int(cls.code)}  # {cls.name}" for cls in laws]

    def branch(head, args_of, ret, kernel=None):
        """``if code == c: ...`` per law; laws whose ``kernel`` (a name, or names) is the same function(s) (the
        sliding laws' signals) share one branch that names each of their codes (one inlined copy, not three)."""
        groups: dict = {}
        for cls in laws:
            mod = sys.modules[cls.__module__]
            names = kernel if isinstance(kernel, tuple) else (kernel,)
            key = tuple(id(getattr(mod, k)) for k in names) if kernel else (id(cls),)
            groups.setdefault(key, []).append(cls)
        lines = [head]
        for k, group in enumerate(groups.values()):
            test = " or ".join(f"code == {int(c.code)}" for c in group)
            lines.append(f"    {'if' if k == 0 else 'elif'} {test}:  # {', '.join(c.name for c in group)}")
            lines.extend(f"        {line}" for line in args_of(f"_law_{int(group[0].code)}", group[0]))
        codes = ", ".join(str(int(c.code)) for c in laws)
        lines += ["    else:", f"        raise ValueError(\"law code not registered (registered: {codes})\")"]
        return "\n".join(lines) + ("\n    return " + ret if ret else "")

    parts = [
        "# ---- the law dispatch: written by rc3r.simulate.engines._dispatch from rc3r.controllers.LAWS ----",
        *imports,
        f"LAW_CODES = {tuple(int(c.code) for c in laws)!r}",
        "from rc3r.simulate.engines._jacobian import finish as _finish, signal_columns as _signal_columns",
        "_LAW_INLINE = dict(cache=True, nogil=True, inline=\"always\")",
        "_LAW_JIT = dict(cache=True, nogil=True, error_model=\"numpy\")",
        "",
        "",
        "@njit(**_LAW_INLINE)\n" + branch(
            "def law_signals(code, cp, q, qd, ref, v, a, r, w):",
            lambda a, c: [f"{a}.signals(cp, q, qd, ref, v, a, r, w)"], "", "signals"),
        "",
        "",
        "@njit(**_LAW_INLINE)\n" + branch(
            "def inertia_gain(code, cp, n):",
            lambda a, c: [f"return {a}.inertia_gain(cp, n)"], "", "inertia_gain"),
        "",
        "",
        "@njit(**_LAW_INLINE)\n" + branch(
            "def uses_xi(code):",
            lambda a, c: [f"return {bool(sys.modules[c.__module__].USES_XI)}"], "", "USES_XI"),
        "",
        "",
        "@njit(**_LAW_INLINE)\n" + branch(
            "def law_theta(code, cp, n, z, th_eff, zdot):",
            lambda a, c: [f"return {a}.theta(cp, n, z, th_eff, zdot)"], "", "theta"),
        "",
        "",
        "@njit(**_LAW_INLINE)\n" + branch(
            "def law_slopes(code, cp, n, ref, jerk, G, Wx):",
            lambda a, c: [f"{a}.slopes(cp, n, ref, jerk, G, Wx)"], "", "slopes"),
        "",
        "",
        "@njit(**_LAW_JIT)\n" + branch(
            "def law_directions(code, cp, Y, r, tw):\n    TB, xs, om, bt = tw[8], tw[9], tw[10], tw[14]",
            lambda a, c: [f"return {a}.directions(cp, Y, r, xs, TB, om, bt)"], "", "directions"),
        "",
        "",
        "@njit(**_LAW_JIT)\n" + branch(
            "def law_jacobian(code, cp, es, x, Y, r, rows, tw, J, Ft):\n"
            "    Ux, Xi, xs, bt = tw[5], tw[6], tw[9], tw[14]\n"
            "    n = Y.shape[0]\n"
            "    _signal_columns(Y, r, rows, tw)",
            lambda a, c: [f"{a}.theta_columns(cp, Y, rows, Ux, Xi, xs, bt)", f"gam = {a}.state_gain(cp, n)"],
            "_finish(es, x, tw[1], Ux, Xi, gam, J, Ft, tw[11], tw[12])", ("theta_columns", "state_gain")),
        "# ---- end of the law dispatch ----",
    ]
    return "\n".join(parts)


# ---- stubs: the template (:mod:`.compiled`) as it stands imports these; an instantiation replaces them ----


@njit(**_JIT)
def law_signals(code, cp, q, qd, ref, v, a, r, w):
    """Stub (never instantiated): raises."""
    raise RuntimeError("the law dispatch is written at instantiation (rc3r.simulate._fast.instantiate)")


@njit(**_JIT)
def inertia_gain(code, cp, n):
    """Stub (never instantiated): raises."""
    raise RuntimeError("the law dispatch is written at instantiation (rc3r.simulate._fast.instantiate)")


@njit(**_JIT)
def uses_xi(code):
    """Stub (never instantiated): raises."""
    raise RuntimeError("the law dispatch is written at instantiation (rc3r.simulate._fast.instantiate)")


@njit(**_JIT)
def law_theta(code, cp, n, z, th_eff, zdot):
    """Stub (never instantiated): raises."""
    raise RuntimeError("the law dispatch is written at instantiation (rc3r.simulate._fast.instantiate)")


@njit(**_JIT)
def law_slopes(code, cp, n, ref, jerk, G, Wx):
    """Stub (never instantiated): raises."""
    raise RuntimeError("the law dispatch is written at instantiation (rc3r.simulate._fast.instantiate)")


@njit(**_JIT)
def law_directions(code, cp, Y, r, tw):
    """Stub (never instantiated): raises."""
    raise RuntimeError("the law dispatch is written at instantiation (rc3r.simulate._fast.instantiate)")


@njit(**_JIT)
def law_jacobian(code, cp, es, x, Y, r, rows, tw, J, Ft):
    """Stub (never instantiated): raises."""
    raise RuntimeError("the law dispatch is written at instantiation (rc3r.simulate._fast.instantiate)")
