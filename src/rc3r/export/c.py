r"""The controller of a run as C99 source: ``rc3r_controller.h`` and ``rc3r_controller.c``.

:func:`controller_sources` writes the :class:`rc3r.Controller` of a run -- its reference trajectory
(:func:`rc3r.trajectory.reference_into`), the model's Slotine--Li regressor, the law
(its module's ``c_source``: the arithmetic of its kernels, in the same order) with theta_0, rho, rho_i
and the gains, the law's state, the zero-order hold at the run's rate and the delay line -- as one
C99 translation unit that needs nothing but libm. Every number is a literal, ``repr`` of the float:
the shortest decimal (at most 17 significant digits) that reads back to the same double.

The C function ``rc3r_control(t, q, qd, s, u)`` behaves as :meth:`rc3r.Controller.step`, call for
call: sampled at ``rate`` it computes a torque at the first call at or after ``t_k = k T``
(``k = floor(t / T + 1e-9)``) from that call's state and the reference at ``t_k``, after a forward
Euler step of the law's state over one period, pushes it into the delay line and returns the
delayed command until ``t_{k+1}``; without a rate every call computes a torque and the state is
integrated by forward Euler between calls. A call earlier than the last sample (or the last call,
continuous) sets ``s->error = 1`` and returns the torque held, where ``Controller.step`` raises.

**The regressor contract.** The robot's part is C source (from ``model.c_regressor_source()``, or
for an arm of :class:`~rc3r.robots.pinocchio_kernel.ChainKernel` the generic chain of
:mod:`rc3r.export.chain`) placed after ``RC3R_N``, ``RC3R_P`` and ``<math.h>``. It defines a type
``rc3r_regressor`` (the work of one state) and three ``static inline`` functions::

    void rc3r_regressor_eval(rc3r_regressor *wk, const double *q, const double *qd,
                             const double *v, const double *a);            /* Y(q, qd, v, a) */
    void rc3r_regressor_xi(const rc3r_regressor *wk, const double *r, double *xi);   /* Y^T r */
    void rc3r_regressor_apply(const rc3r_regressor *wk, const double *th,
                              const double *w, double *u);                  /* w + Y th */

with ``Y`` the robot's ``regressor(q, qd, v, a)`` (n, p): how the three are computed is the robot's
business (the chain never forms Y).
"""
from __future__ import annotations

import numpy as np

from ..controllers import LAWS, Law
from ..errors import ConfigError
from ..trajectory import Trajectory
from .literals import c_array, c_double

__all__ = ["c_double", "c_array", "regressor_source", "controller_sources", "check_exportable", "law_codes"]


def law_codes() -> dict[int, str]:
    """Code -> name of the registered laws with a C port: every compiled law (its module's ``c_source``)."""
    return {cls.code: cls.name for cls in LAWS.values() if cls.code is not None}


def regressor_source(model) -> str:
    """The C source of ``model``'s regressor (module docstring, the regressor contract).

    ``model.c_regressor_source()`` if the robot class has one (the 3R's closed form), else the
    generic chain of :mod:`rc3r.export.chain` for a model with a supported ``ChainKernel``; for an
    :class:`~rc3r.robots.actuated.ActuatedRobot` its rigid body's, wrapped by :mod:`rc3r.robots.actuated_c`.

    Raises
    ------
    ConfigError
        A robot with neither (a helical joint, a robot class without a C regressor).
    """
    from ..robots.actuated import ActuatedRobot

    if isinstance(model, ActuatedRobot):  # the rigid body's C, renamed, plus the joint columns
        from ..robots.actuated_c import c_regressor_source

        return c_regressor_source(model, regressor_source(model.rigid))
    if model.c_regressor_source is not None:  # declared by every robot (rc3r.robots.base.Robot)
        return model.c_regressor_source()
    from .chain import chain_source

    if model.kernel is not None and model.kernel.supported and model.base is not None:
        return chain_source(model.kernel, np.ascontiguousarray(model.base.independent, dtype=np.int64))
    raise ConfigError(f"robot {model.label!r} has no C regressor (a class with "
                      "c_regressor_source(), or a serial arm of revolute/prismatic joints through Pinocchio)")


def check_exportable(law, trajectory) -> None:
    """ConfigError unless ``law`` is a built-in law with a C port and ``trajectory`` a packed kind."""
    cls = type(law)
    same = all(getattr(cls, m) is getattr(Law, m) for m in ("signals", "output", "torque"))
    codes = law_codes()
    if law.code not in codes or law.kernels is None or not same:
        raise ConfigError(f"controller {law.name!r} has no C port (exportable: {', '.join(codes.values())})")
    tp = trajectory.pack()
    if type(trajectory).evaluate is not Trajectory.evaluate or tp[0] not in (0.0, 1.0):
        raise ConfigError(f"trajectory {trajectory.describe()!r} has no C port (sines, quintic)")


def _constant(name: str, dims: str, value, comment: str) -> str:
    """One ``static const double`` of a law's C port: a number (``dims`` empty), a vector or an (n, n) matrix."""
    if not dims:
        text = c_double(float(value))
    elif np.ndim(value) == 2:
        text = "{" + ", ".join(c_array(row) for row in np.asarray(value)) + "}"
    else:
        text = c_array(np.asarray(value))
    return f"static const double {name}{dims} = {text};" + (f"  /* {comment} */" if comment else "")


def _law_parts(law, n: int) -> tuple[str, str, str, str, str]:
    """(constants, signals body, output body, coupling, schedule) of the law in C: its module's ``c_source``
    (:mod:`rc3r.controllers.base`), whose numbers come from ``law.pack(n)`` through the law's LAYOUT
    (coupling: the off-diagonal part of a matrix K, after the per-joint loop; schedule: the
    ``-K_inertia M(q) r`` of a scheduled K, before the regressor's evaluation; empty otherwise)."""
    part = law.kernels.c_source(law, n)
    consts = [_constant(*c) for c in part["constants"]]
    z0 = np.asarray(law.initial_state(), dtype=float)
    if z0.size:
        consts += [_constant("rc3r_z0", "[RC3R_NZ]", z0, "theta_0: the initial estimate")]
    return "\n".join(consts), part["signals"], part["output"], part.get("coupling", ""), part.get("schedule", "")


def _reference_source(trajectory) -> str:
    """``rc3r_reference(t, ref)`` of the packed trajectory (:func:`rc3r.trajectory.reference_into`)."""
    tp = np.asarray(trajectory.pack(), dtype=float)
    head = f"static const double rc3r_tp[{tp.size}] = {c_array(tp)};\n\n"
    if tp[0] == 0.0:  # sines: [0, K, c (n), per joint K x (A, w, phi)]
        return head + f"""static void rc3r_reference(double t, double ref[3][RC3R_N])
{{
    const int K = {int(tp[1])};
    int i, k;
    for (i = 0; i < RC3R_N; ++i) {{
        double q = rc3r_tp[2 + i], qd = 0.0, qdd = 0.0;
        const int base = 2 + RC3R_N + i * K * 3;
        for (k = 0; k < K; ++k) {{
            const double A = rc3r_tp[base + 3 * k];
            const double w = rc3r_tp[base + 3 * k + 1];
            const double ph = rc3r_tp[base + 3 * k + 2];
            const double s = sin(w * t + ph);
            const double c = cos(w * t + ph);
            q += A * s;
            qd += A * w * c;
            qdd -= A * w * w * s;
        }}
        ref[0][i] = q;
        ref[1][i] = qd;
        ref[2][i] = qdd;
    }}
}}"""
    return head + f"""static void rc3r_reference(double t, double ref[3][RC3R_N])
{{
    const int nseg = {int(tp[1])};
    double t0 = 0.0, T, tau, s, ds, dds;
    int k, i, a, seg = -1;
    for (k = 0; k < nseg; ++k) {{
        if (t < t0 + rc3r_tp[2 + k]) {{
            seg = k;
            break;
        }}
        t0 += rc3r_tp[2 + k];
    }}
    if (seg < 0) {{  /* past the end: hold the last waypoint */
        const int wp = 2 + nseg + RC3R_N * nseg;
        for (i = 0; i < RC3R_N; ++i) {{
            ref[0][i] = rc3r_tp[wp + i];
            ref[1][i] = 0.0;
            ref[2][i] = 0.0;
        }}
        return;
    }}
    T = rc3r_tp[2 + seg];
    tau = (t - t0) / T;
    tau = tau > 0.0 ? tau : 0.0;
    s = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
    ds = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau) / T;
    dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (T * T);
    a = 2 + nseg + RC3R_N * seg;
    for (i = 0; i < RC3R_N; ++i) {{
        const double d = rc3r_tp[a + RC3R_N + i] - rc3r_tp[a + i];
        ref[0][i] = rc3r_tp[a + i] + d * s;
        ref[1][i] = d * ds;
        ref[2][i] = d * dds;
    }}
}}"""


_HEADER = """/* rc3r_controller.h -- @TITLE@
 *
 * u = rc3r_control(t, q, qd, &s): the torque [N m] to apply from time t [s] on, given the measured
 * joint positions q and velocities qd (RC3R_N each). Behaves as rc3r.Controller.step of the same
 * run, call for call (docs/export.md). Not thread-safe per state; one rc3r_state per controller.
 */
#ifndef RC3R_CONTROLLER_H
#define RC3R_CONTROLLER_H

#ifdef __cplusplus
extern "C" {
#endif

#define RC3R_N @N@       /* joints */
#define RC3R_P @P@       /* coefficients of theta */
#define RC3R_NZ @NZ@      /* controller state (the adaptive estimate) */
#define RC3R_DELAY @DELAY@   /* samples between a measurement and its torque */
#define RC3R_SAMPLED @SAMPLED@  /* 1: zero-order hold at RC3R_RATE; 0: a torque at every call */
#define RC3R_RATE @RATE@  /* controller rate [Hz] (0.0: continuous) */

typedef struct {
    double z[RC3R_NZ > 0 ? RC3R_NZ : 1];     /* the law's state */
    double zdot[RC3R_NZ > 0 ? RC3R_NZ : 1];  /* its rate at the last torque */
    double u[RC3R_N];                        /* the torque now applied */
    double line[RC3R_DELAY + 1][RC3R_N];     /* delay line: the last RC3R_DELAY + 1 commands */
    int line_count, line_start;
    long long k;                             /* last sample computed (-1: none yet) */
    double t_last;                           /* continuous: time of the last call */
    int started;                             /* continuous: a call has been made */
    double diagnostic;                       /* ||Y^T r|| at the last torque */
    int error;                               /* 1 after a call earlier than the last one */
} rc3r_state;

/* The state at t = 0: the law's initial state, an empty hold and delay line. */
void rc3r_init(rc3r_state *s);

/* Writes u (RC3R_N); q, qd (RC3R_N) are the measured state at time t; calls in non-decreasing t. */
void rc3r_control(double t, const double *q, const double *qd, rc3r_state *s, double *u);

#ifdef __cplusplus
}
#endif

#endif /* RC3R_CONTROLLER_H */
"""

_SOURCE = """/* rc3r_controller.c -- @TITLE@
 * Self-contained C99; needs only libm. Generated: edit the run, not this file.
 */
#include <math.h>
#include <string.h>

#include "rc3r_controller.h"

/* ---- the reference trajectory (rc3r.trajectory.reference_into) ---- */
@REFERENCE@

/* ---- the model's regressor ---- */
@REGRESSOR@

/* ---- the law (rc3r.controllers): @LAW@ ---- */
@CONSTANTS@

static void rc3r_law_signals(const double *q, const double *qd, double ref[3][RC3R_N],
                             double *v, double *a, double *r, double *w)
{
    int i;
    for (i = 0; i < RC3R_N; ++i) {
@SIGNALS@
    }
@COUPLING@}

/* theta_eff into th (RC3R_P), the state's rate into zdot; returns ||Y^T r|| */
static double rc3r_law_output(const rc3r_regressor *wk, const double *r, const double *z,
                              double *th, double *zdot)
{
@OUTPUT@
}

/* u = Y(q, qd, v, a) theta_eff + w at time t, with the law's state z */
static double rc3r_torque(double t, const double *q, const double *qd, const double *z,
                          double *u, double *zdot)
{
    double ref[3][RC3R_N], v[RC3R_N], a[RC3R_N], r[RC3R_N], w[RC3R_N], th[RC3R_P], diag;
    rc3r_regressor wk;
    rc3r_reference(t, ref);
    rc3r_law_signals(q, qd, ref, v, a, r, w);
@SCHEDULE@    rc3r_regressor_eval(&wk, q, qd, v, a);
    diag = rc3r_law_output(&wk, r, z, th, zdot);
    rc3r_regressor_apply(&wk, th, w, u);
    return diag;
}

/* ---- rc3r.Controller: zero-order hold, delay line, the law's state ---- */
void rc3r_init(rc3r_state *s)
{
    memset(s, 0, sizeof *s);
#if RC3R_NZ > 0
    memcpy(s->z, rc3r_z0, sizeof rc3r_z0);
#endif
    s->k = -1;
}

void rc3r_control(double t, const double *q, const double *qd, rc3r_state *s, double *u)
{
    int i;
#if RC3R_SAMPLED
    const double T = @PERIOD@;  /* 1 / RC3R_RATE [s] */
    const long long k = (long long)floor(t / T + 1e-9);
    if (k < s->k) {
        s->error = 1;  /* rc3r.Controller.step raises: called before its last sample */
    } else if (k > s->k) {
        double *cmd;
        int j;
        if (s->k >= 0) {  /* forward Euler over one period, as the simulator */
            for (j = 0; j < RC3R_NZ; ++j)
                s->z[j] = s->z[j] + T * s->zdot[j];
        }
        if (s->line_count < RC3R_DELAY + 1) {
            cmd = s->line[(s->line_start + s->line_count) % (RC3R_DELAY + 1)];
            s->line_count += 1;
        } else {  /* the oldest command leaves the line */
            cmd = s->line[s->line_start];
            s->line_start = (s->line_start + 1) % (RC3R_DELAY + 1);
        }
        s->diagnostic = rc3r_torque((double)k * T, q, qd, s->z, cmd, s->zdot);
        for (i = 0; i < RC3R_N; ++i)
            s->u[i] = s->line[s->line_start][i];
        s->k = k;
    }
#else
    if (s->started && t < s->t_last) {
        s->error = 1;  /* rc3r.Controller.step raises: called before its last call */
    } else {
        int j;
        if (s->started) {
            const double dt = t - s->t_last;
            for (j = 0; j < RC3R_NZ; ++j)
                s->z[j] = s->z[j] + dt * s->zdot[j];
        }
        s->diagnostic = rc3r_torque(t, q, qd, s->z, s->u, s->zdot);
        s->t_last = t;
        s->started = 1;
    }
#endif
    for (i = 0; i < RC3R_N; ++i)
        u[i] = s->u[i];
}
"""


def controller_sources(ctrl, title: str) -> tuple[str, str]:
    """``(header, source)``: ``rc3r_controller.h`` and ``rc3r_controller.c`` of a :class:`rc3r.Controller`.

    Parameters
    ----------
    ctrl : rc3r.Controller
        Its law, model (the regressor), trajectory, rate and delay are written out.
    title : str
        One line naming what was exported (the first comment line of both files).

    Raises
    ------
    ConfigError
        A law, trajectory or robot without a C port (:func:`check_exportable`, :func:`regressor_source`).
    """
    law, model, traj = ctrl.law, ctrl.model, ctrl.trajectory
    check_exportable(law, traj)
    n, p = model.n, law.p
    consts, signals, output, coupling, schedule = _law_parts(law, n)
    sampled = ctrl.rate is not None
    title = " ".join(str(title).replace("*/", "* /").split())
    fields = {"@TITLE@": title, "@N@": str(n), "@P@": str(p), "@NZ@": str(law.initial_state().size),
              "@DELAY@": str(ctrl.delay), "@SAMPLED@": str(int(sampled)),
              "@RATE@": c_double(ctrl.rate) if sampled else "0.0"}
    header = _HEADER
    for key, value in fields.items():
        header = header.replace(key, value)
    parts = {"@TITLE@": title, "@REFERENCE@": _reference_source(traj), "@REGRESSOR@": regressor_source(model).strip(),
             "@LAW@": law.name, "@CONSTANTS@": consts, "@SIGNALS@": signals, "@COUPLING@": coupling, "@SCHEDULE@": schedule, "@OUTPUT@": output,
             "@PERIOD@": c_double(1.0 / ctrl.rate) if sampled else "0.0"}
    source = _SOURCE
    for key, value in parts.items():
        source = source.replace(key, value)
    return header, source
