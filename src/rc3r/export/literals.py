"""C99 literals of Python numbers: the one place :mod:`rc3r.export.c` and :mod:`rc3r.export.chain`
write a constant, so both read back the same double."""
from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError

__all__ = ["c_double", "c_array"]


def c_double(x) -> str:
    """The C literal of a finite double: ``repr`` (it always has a ``.`` or an exponent and reads back
    exactly); ParameterError for NaN or an infinity."""
    x = float(x)
    if not math.isfinite(x):
        raise ParameterError(f"cannot export the non-finite constant {x!r}")
    return repr(x)


def c_array(values, fmt=c_double, per_line: int = 4) -> str:
    """``{a, b, ...}`` of ``values`` (flattened), ``per_line`` literals to a line."""
    items = [fmt(v) for v in np.ravel(values)]
    lines = [", ".join(items[i:i + per_line]) for i in range(0, len(items), per_line)]
    return "{\n    " + ",\n    ".join(lines) + "\n}"
