"""Shape handling shared by the public closed-form functions."""
from __future__ import annotations

import numpy as np


def as_states(*arrays):
    """Broadcast (3,) or (N, 3) inputs to contiguous float (N, 3) arrays.

    Returns the arrays and whether the input was a single state (so the caller
    drops the batch axis again).
    """
    arrs = [np.asarray(a, dtype=float) for a in arrays]
    for a in arrs:
        if a.ndim not in (1, 2) or a.shape[-1] != 3:
            raise ValueError(f"expected shape (3,) or (N, 3), got {a.shape}")
    single = all(a.ndim == 1 for a in arrs)
    arrs = np.broadcast_arrays(*[np.atleast_2d(a) for a in arrs])
    return [np.ascontiguousarray(a) for a in arrs], single


def as_theta(theta) -> np.ndarray:
    th = np.ascontiguousarray(theta, dtype=float)
    if th.shape != (15,):
        raise ValueError(f"theta must have shape (15,), got {th.shape}")
    return th
