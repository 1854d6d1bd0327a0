"""The ``fast`` engine: a robot's compiled simulator (:attr:`Robot.fast_engine`) driven by packed arrays.

The compiled integrators run in chunks of :data:`CHUNK_S` simulated seconds: between two
chunks control is back in Python, so Ctrl-C or SIGTERM (which the command line turns into
``KeyboardInterrupt``) stops a long run within one chunk's wall time (about 0.1 s for the
paper's robust law), and the result keeps every chunk finished before it
(``status = "interrupted"``). A chunk is also bounded in work: at most
``SimOptions.max_steps`` integrator steps per simulated second (status ``WORK``, a
"diverged" run whose message names the law's eps), so a loop too stiff to integrate
stops within seconds instead of running for hours.
"""
from __future__ import annotations

import numpy as np

from . import _limits, _result, _sample_grid
from . import status as S

#: Simulated seconds per compiled call.
CHUNK_S = 0.5

#: Largest continuous-time step [s]; the stored rows are interpolated inside the steps.
HMAX = 0.001


def run(plant, law, trajectory, opt, x0, loop=None, model=None):
    """Simulate on the rigid body's compiled simulator; ``plant`` is a :class:`~rc3r.plants.Plant` whose
    effects are compiled ones (packed by :meth:`~rc3r.plants.Plant.pack`), ``loop`` the sampled loop's
    effects (or None). ``model`` is ignored: the compiled regressor is the rigid body's, whose
    kinematics :func:`rc3r.simulate.simulate` checked equal to the model's."""
    rigid = plant.rigid
    eng = rigid.fast_engine
    n = plant.n
    fx = plant.pack()
    cp, tp, code = law.pack(n), trajectory.pack(), int(law.code)
    lim = _limits(opt)
    size = x0.size
    if opt.rate is None:
        nout = int(round(opt.duration * opt.output_rate)) + 1
        t_out = np.linspace(0.0, opt.duration, nout)
        X = np.zeros((nout, size)); U = np.zeros((nout, n)); R = np.zeros((nout, n)); yn = np.zeros(nout)
        X[0] = x0
        hmax = HMAX
        per = max(1, int(round(CHUNK_S * opt.output_rate)))
        start, stored, st, t_end, counts = 0, 0, S.OK, 0.0, np.zeros(3, dtype=np.int64)
        try:
            while True:
                end = min(start + per, nout - 1)
                budget = max(1000, int(np.ceil(opt.max_steps * (t_out[end] - t_out[start]))))
                st_k, m, nrhs, nsteps, nrej, t_k = eng.continuous(
                    rigid, fx, code, cp, tp, X[start].copy(), t_out[start:end + 1], opt.rtol, opt.atol, 1e-5, hmax,
                    lim, X[start:end + 1], U[start:end + 1], R[start:end + 1], yn[start:end + 1], opt.jac_reuse,
                    budget)
                counts += (nrhs, nsteps, nrej)
                stored, st, t_end = start + m, st_k, t_k
                if st != S.OK or end == nout - 1:
                    break
                start = end
        except KeyboardInterrupt:
            st = S.INTERRUPTED
        m = stored
        return _result(plant, law, trajectory, opt, t_out[:m], X[:m], U[:m], R[:m], yn[:m],
                       st, t_end, *counts)
    Ts, nsamples, dec = _sample_grid(opt)
    nout = nsamples // dec + 2
    X = np.zeros((nout, size)); U = np.zeros((nout, n)); R = np.zeros((nout, n)); yn = np.zeros(nout)
    X[0] = x0
    tv = np.zeros(n)
    noise = loop.noise(nsamples) if loop is not None else np.zeros((0, 2 * n))
    quant = loop.quantization if loop is not None else np.zeros(n)
    ubuf = np.zeros(((loop.delay if loop is not None else 0) + 1, n))  # the delay line, across chunks
    per = max(1, int(round(CHUNK_S * opt.rate)) // dec) * dec  # samples per call, a multiple of dec
    s0, row, stored, st, t_end, nrhs_all, done = 0, 0, 0, S.OK, 0.0, 0, 0
    try:
        while True:
            k = min(per, nsamples - s0)
            st_k, m, nrhs, ndone, t_k = eng.sampled(
                rigid, fx, code, cp, tp, X[row].copy(), s0, Ts, k, dec, opt.substeps, lim,
                X[row:], U[row:], R[row:], yn[row:], tv, noise, quant, ubuf)
            nrhs_all += nrhs
            stored, st, t_end, done = row + m, st_k, t_k, s0 + ndone
            if st != S.OK or s0 + k >= nsamples:
                break
            s0 += k
            row = stored - 1  # the chunk's last sample is the next chunk's first
    except KeyboardInterrupt:
        st = S.INTERRUPTED
    m = stored
    t = np.arange(m) * dec * Ts
    if st not in (S.OK, S.INTERRUPTED) and m > 0:
        t[-1] = t_end
    return _result(plant, law, trajectory, opt, t, X[:m], U[:m], R[:m], yn[:m],
                   st, t_end, nrhs_all, done, 0, tv=tv)
