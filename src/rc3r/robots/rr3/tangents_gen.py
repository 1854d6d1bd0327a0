r"""Writes :mod:`.tangents` (the 3R's analytic derivatives) with SymPy: ``python -m rc3r.robots.rr3.tangents_gen``.

The expressions are not transcribed: the closed-form Slotine--Li regressor of :mod:`.kernels`
(:func:`~.kernels.slotine_li_scalars`, its pure-Python body) is run on SymPy symbols, with its
trigonometry ``_trig`` swapped for a symbolic one for the duration of the call, so the
derivatives are those of the very function the simulator evaluates. With
``z = (q_1, q_2, q_3, qd_1, qd_2, qd_3, v_1, v_2, v_3, a_1, a_2, a_3)`` (12 columns):

* ``torque_tangent``: :math:`D = \partial (Y(q, \dot q, v, a)\,\theta) / \partial z`, (3, 12), for
  any ``theta`` (its columns 9-11 are :math:`M_\theta(q)`). The engine needs the derivative of
  :math:`Y^T r` only contracted with a vector ``b``, which is this one at ``theta = b``:
  :math:`b^T \partial(Y^T r)/\partial z = r^T \partial(Y b)/\partial z`.

SymPy differentiates; ``sympy.cse`` removes common subexpressions; the sines of ``q_2``, ``q_3`` and
``q_2 + q_3`` are then named ``s2, c2, s3, c3, s23, c23`` and computed by the kernels' own
:func:`~.kernels._trig`. SymPy is needed only to regenerate
(the ``codegen`` extra); ``tests/test_rr3_tangents.py`` checks that the committed module is what
this script writes, and the derivatives against Pinocchio's ``computeRNEADerivatives`` and
central differences.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

TARGET = Path(__file__).with_name("tangents.py")

_HEADER = '''r"""Analytic derivatives of the 3R's closed form, for the compiled engine's Jacobian. GENERATED.

Written by :mod:`.tangents_gen` (SymPy) from :func:`.kernels.slotine_li_scalars`: do not edit,
regenerate (``python -m rc3r.robots.rr3.tangents_gen``). Columns ``z = (q (3), qd (3), v (3), a (3))``;
q1 does not enter (its column is zero).

* :func:`torque_tangent` -- ``D`` (3, 12) = d(Y(q, qd, v, a) theta)/dz, any ``theta`` (15,).

Checked against Pinocchio's ``computeRNEADerivatives`` and central differences in
``tests/test_rr3_tangents.py``.
"""
from __future__ import annotations

from numba import njit

from .kernels import _trig

_JIT = dict(cache=True, nogil=True, error_model="numpy")
'''


def _symbolic():
    import sympy as sp

    from . import kernels as K

    q2, q3 = sp.symbols("q2 q3")
    qd = sp.symbols("qd1 qd2 qd3")
    v = sp.symbols("v1 v2 v3")
    a = sp.symbols("a1 a2 a3")
    l2, g0 = sp.symbols("l2 g0")
    th = sp.IndexedBase("th")
    S2, C2, S3, C3, S23, C23 = sp.symbols("s2 c2 s3 c3 s23 c23")

    def trig(x2, x3):
        return sp.sin(x2), sp.cos(x2), sp.sin(x3), sp.cos(x3), sp.sin(x2 + x3), sp.cos(x2 + x3)

    Y = np.empty((3, 15), dtype=object)
    saved = K._trig
    K._trig = trig
    try:
        K.slotine_li_scalars.py_func(q2, q3, *qd, *v, *a, l2, g0, Y)
    finally:
        K._trig = saved
    z = [sp.Symbol("q1"), q2, q3, *qd, *v, *a]
    name = {sp.sin(q2 + q3): S23, sp.cos(q2 + q3): C23, sp.sin(q2): S2, sp.cos(q2): C2, sp.sin(q3): S3,
            sp.cos(q3): C3}
    tau = [sum(Y[i, k] * th[k] for k in range(15)) for i in range(3)]
    D = [[sp.diff(tau[i], zj).subs(name) for zj in z] for i in range(3)]
    return D


def _body(rows, out: str) -> list[str]:
    import sympy as sp

    flat = [e for row in rows for e in row]
    subs, red = sp.cse(flat, symbols=sp.numbered_symbols("t"), optimizations="basic")
    lines = [f"    {s} = {sp.pycode(e)}" for s, e in subs]
    ncol = len(rows[0])
    if any(e == 0 for e in red):
        lines.append(f"    {out}[:, :] = 0.0")
    for k, e in enumerate(red):
        if e != 0:
            lines.append(f"    {out}[{k // ncol}, {k % ncol}] = {sp.pycode(e)}")
    return lines


def source() -> str:
    """The text of :mod:`.tangents`."""
    D = _symbolic()
    trig = ["    s2, c2, s3, c3, s23, c23 = _trig(q2, q3)"]
    args = "q2, q3, qd1, qd2, qd3, v1, v2, v3, a1, a2, a3"
    text = _HEADER + "\n\n@njit(**_JIT)\n"
    text += f"def torque_tangent(th, {args}, l2, g0, D):\n"
    text += '    """D (3, 12) = d(Y theta)/d(q, qd, v, a) at the state; ``th`` (15,)."""\n'
    text += "\n".join(trig + _body(D, "D")) + "\n"
    return text


def main() -> None:
    TARGET.write_text(source())


if __name__ == "__main__":
    main()
