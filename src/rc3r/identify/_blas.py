"""One BLAS thread for a block of code: :func:`blas_threads`.

The identification's matrix products are narrow (20-70 columns, thousands of rows). OpenBLAS
splits them over threads that spin while waiting; on a shared machine whose cores are busy that
costs more than it gains: ``rc3r identify`` on the 21 s Panda log took 49 s with two BLAS threads
and 25 s with one (2 cores at a load of 8, 2026-12-06). :func:`blas_threads` sets the thread count
of the OpenBLAS libraries NumPy and SciPy have already loaded (their wheels' ``*.libs``
directories), and restores it afterwards; where none is found (another BLAS, another layout) it
does nothing.
"""
from __future__ import annotations

import contextlib
import ctypes
import os
from pathlib import Path

__all__ = ["blas_threads"]

#: (get, set) symbol pairs of OpenBLAS builds: scipy-openblas 64-bit and 32-bit interfaces, plain OpenBLAS.
_SYMBOLS = (("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
            ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
            ("openblas_get_num_threads", "openblas_set_num_threads"))


def _loaded_openblas() -> list:
    """``(get, set)`` functions of every OpenBLAS already loaded from NumPy's or SciPy's wheel."""
    import numpy

    found = []
    site = Path(numpy.__file__).resolve().parents[1]
    for sub in ("numpy.libs", "scipy.libs"):
        for path in sorted((site / sub).glob("*openblas*.so*")):
            try:
                lib = ctypes.CDLL(str(path), mode=getattr(os, "RTLD_NOLOAD", 0) | ctypes.RTLD_LOCAL)
            except OSError:
                continue  # not loaded (RTLD_NOLOAD) or not loadable: leave it alone
            for get, set_ in _SYMBOLS:
                if hasattr(lib, get) and hasattr(lib, set_):
                    g, s = getattr(lib, get), getattr(lib, set_)
                    g.restype, s.argtypes = ctypes.c_int, [ctypes.c_int]
                    found.append((g, s))
                    break
    return found


@contextlib.contextmanager
def blas_threads(n: int = 1):
    """Run the ``with`` block with ``n`` OpenBLAS threads, then restore the previous counts (module docstring)."""
    libs = _loaded_openblas()
    saved = [g() for g, _ in libs]
    try:
        for _, s in libs:
            s(int(n))
        yield len(libs)
    finally:
        for (_, s), k in zip(libs, saved):
            s(int(k))
