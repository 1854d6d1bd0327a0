"""Status codes of a simulation run, shared by every engine, and the compiled bound check.

0 ok, 1 non-finite state, 2 |q| bound, 3 |qd| bound, 4 |u| bound, 5 mass matrix not
positive definite, 6 step size underflow, 7 interrupted (SIGINT/SIGTERM; not a divergence),
8 work budget exhausted (the continuous-time integrator took more than
``SimOptions.max_steps`` steps per simulated second: the loop is too stiff to integrate).
"""
from __future__ import annotations

import math
import threading

from numba import njit

OK, NONFINITE, QBOUND, QDBOUND, UBOUND, NOTPD, HMIN, INTERRUPTED, WORK = 0, 1, 2, 3, 4, 5, 6, 7, 8

STATUS_TEXT = {
    OK: "ok",
    NONFINITE: "state became NaN or infinite",
    QBOUND: "|q| exceeded its bound",
    QDBOUND: "|qd| exceeded its bound",
    UBOUND: "|u| exceeded its bound",
    NOTPD: "plant mass matrix not positive definite",
    HMIN: "integrator step size underflow",
    INTERRUPTED: "interrupted (Ctrl-C or SIGTERM)",
    WORK: "integrator work budget exhausted",
}


#: Set by the command line's SIGINT/SIGTERM handler, cleared when a command starts. A
#: ``KeyboardInterrupt`` raised while numba compiles or loads a kernel can be lost inside numba;
#: the flag is not, and the engines check it (:func:`raise_if_stopped`) after compiling and
#: between chunks, so a signal always ends the run.
STOP = threading.Event()


def raise_if_stopped() -> None:
    """Raise ``KeyboardInterrupt`` if a stop was requested (:data:`STOP`)."""
    if STOP.is_set():
        raise KeyboardInterrupt("stop requested (SIGINT or SIGTERM)")


@njit(cache=True, nogil=True)
def check(x, u, lim):
    """Status of state ``x = (q, qd, z)`` and torque ``u`` (n,) against ``lim = (q_max, qd_max, u_max)``."""
    n = u.shape[0]
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return NONFINITE
    for i in range(n):
        if abs(x[i]) > lim[0]:
            return QBOUND
        if abs(x[n + i]) > lim[1]:
            return QDBOUND
        if not math.isfinite(u[i]):
            return NONFINITE
        if abs(u[i]) > lim[2]:
            return UBOUND
    return OK
