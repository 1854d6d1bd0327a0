"""Dense LU with partial pivoting for the compiled integrators' small (2n + m) systems (numba).

Kernel-independent, so outside the template :mod:`.compiled` (one compile for every supply).
``_lu_factor(A, piv)`` factors ``A`` in place (False on an exact zero pivot); ``_lu_solve(LU,
piv, b)`` overwrites ``b`` with ``A^-1 b``. Checked against :func:`numpy.linalg.solve` in
``tests/test_engines.py``.
"""
from __future__ import annotations

from numba import njit

__all__ = ["_lu_factor", "_lu_solve"]

_JIT = dict(cache=True, nogil=True, error_model="numpy")


@njit(**_JIT)
def _lu_factor(A, piv):
    """In-place LU with partial pivoting (small dense n x n)."""
    n = A.shape[0]
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                p = i
        piv[k] = p
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        if A[k, k] == 0.0:
            return False
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            A[i, k] *= inv
            f = A[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    return True


@njit(**_JIT)
def _lu_solve(LU, piv, b):
    n = LU.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        acc = b[i]
        for j in range(i):
            acc -= LU[i, j] * b[j]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= LU[i, j] * b[j]
        b[i] = acc / LU[i, i]
