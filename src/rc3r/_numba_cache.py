"""numba's on-disk cache of rc3r's compiled kernels, keyed on the content of the package.

numba stamps a cached function with the modification time and size of the one file that
defines it, so an edit of another module it calls (``rc3r.simulate.status.check`` inside
the 3R's integrators, a law kernel, the trajectory) leaves the cache "valid" and the old
code runs: a user who upgrades rc3r, or a mutation run, can execute stale machine code.

:func:`install` puts three cache locators in front of numba's own, for functions defined
in this package only. They keep numba's locations (``__pycache__`` beside the source, else
``NUMBA_CACHE_DIR`` or the user-wide cache) and add to each function's source stamp
:func:`package_hash`: a SHA-256 of every module of the package that uses numba. Any edit
of any such module then invalidates every cached rc3r kernel, and numba recompiles them
(about a minute for the 3R) once. It relies on numba's ``CacheImpl._locator_classes`` (numba 0.59-0.68);
if that is missing, nothing is installed and numba's own behaviour stays.
"""
from __future__ import annotations

import functools
import hashlib
from pathlib import Path

__all__ = ["package_hash", "install", "PACKAGE_DIR", "ready", "cold_start_policy", "ready_or_python"]

#: The directory of the installed ``rc3r`` package.
PACKAGE_DIR = Path(__file__).resolve().parent


def package_hash(root: str | None = None) -> str:
    """SHA-256 (hex) of the relative path and bytes of every ``.py`` file under ``root``
    (default: this package, computed once per process) whose text mentions ``numba``, in sorted
    order."""
    return _hash(Path(root)) if root is not None else _package_hash()


@functools.lru_cache(maxsize=1)
def _package_hash() -> str:
    return _hash(PACKAGE_DIR)


def _hash(base: Path) -> str:
    h = hashlib.sha256()
    for path in sorted(base.rglob("*.py")):
        data = path.read_bytes()
        if b"numba" in data:
            h.update(str(path.relative_to(base)).encode() + b"\0" + data + b"\0")
    return h.hexdigest()


def _inside(py_file) -> bool:
    try:
        return Path(py_file).resolve().is_relative_to(PACKAGE_DIR)
    except (OSError, ValueError):
        return False


class _PackageStamp:
    """Mixin: a locator for this package's files whose source stamp includes :func:`package_hash`."""

    @classmethod
    def from_function(cls, py_func, py_file):
        if not _inside(py_file):
            return None
        return super().from_function(py_func, py_file)

    def get_source_stamp(self):
        return (super().get_source_stamp(), package_hash())


_INSTALLED: list = []


def install() -> bool:
    """Put the package-stamped locators first in numba's list (once); True if installed."""
    if _INSTALLED:
        return True
    try:
        from numba.core import caching
        classes = caching.CacheImpl._locator_classes
        bases = (caching.UserProvidedCacheLocator, caching.InTreeCacheLocator, caching.UserWideCacheLocator)
    except (ImportError, AttributeError):
        return False
    ours = [type(f"Rc3r{b.__name__}", (_PackageStamp, b), {}) for b in bases]
    classes[0:0] = ours
    _INSTALLED.extend(ours)
    return True


def _index_valid(dispatcher) -> bool:
    """True if numba's disk cache holds a valid entry (this source stamp, this numba) for ``dispatcher``."""
    cache = getattr(dispatcher, "_cache", None)
    cache_file = getattr(cache, "_cache_file", None)
    if cache_file is None:  # cache=False, or numba's internals moved: cannot tell
        return True
    try:
        return bool(cache_file._load_index())
    except Exception:  # noqa: BLE001 - an internal of numba; unreadable means "cannot tell"
        return True


_DISK: dict = {}


def ready(dispatcher) -> bool:
    """True if a call of the numba ``dispatcher`` compiles nothing: it has a compiled overload in this
    process, or numba's disk cache holds a valid one (read once per process and dispatcher).

    Reads numba's cache index (``_cache._cache_file._load_index``, numba 0.59-0.68); if that cannot
    be read, answers True (behave as without this check).
    """
    if getattr(dispatcher, "overloads", None):
        return True
    key = id(dispatcher)
    if key not in _DISK:
        _DISK[key] = _index_valid(dispatcher)
    return _DISK[key]


def cold_start_policy() -> str:
    """``"python"`` (default) or ``"compile"``: the environment variable ``RC3R_COLD_START``.

    ``python``: a short run whose compiled kernels are not built yet runs on code that needs no
    compilation (Pinocchio and plain Python), so a fresh install's first run takes seconds instead
    of the one-off numba compilation (1-2 minutes of CPU for a 6-joint arm); ``compile``: build
    them (what campaigns do before their jobs: :func:`rc3r.campaign.runner.prepare`).
    """
    import os

    value = os.environ.get("RC3R_COLD_START", "python").strip().lower()
    return "compile" if value == "compile" else "python"


def ready_or_python(dispatcher):
    """``dispatcher`` if calling it compiles nothing (:func:`ready`) or the policy is ``compile``, else its
    plain-Python function (``dispatcher.py_func``: the same arithmetic, interpreted)."""
    if cold_start_policy() == "compile" or ready(dispatcher):
        return dispatcher
    return getattr(dispatcher, "py_func", dispatcher)
