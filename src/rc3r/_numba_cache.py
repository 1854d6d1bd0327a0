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
(about 20 s) once. It relies on numba's ``CacheImpl._locator_classes`` (numba 0.59-0.68);
if that is missing, nothing is installed and numba's own behaviour stays.
"""
from __future__ import annotations

import functools
import hashlib
from pathlib import Path

__all__ = ["package_hash", "install", "PACKAGE_DIR"]

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
