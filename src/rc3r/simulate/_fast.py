"""The ``fast`` engine: a robot's compiled simulator (:attr:`Robot.fast_engine`) driven by packed arrays."""
from __future__ import annotations

import numpy as np

from . import _limits, _result, _sample_grid
from . import status as S


def run(plant, law, trajectory, opt, x0):
    eng = plant.fast_engine
    n = plant.n
    cp, tp, code = law.pack(n), trajectory.pack(), int(law.code)
    lim = _limits(opt)
    size = x0.size
    if opt.rate is None:
        nout = int(round(opt.duration * opt.output_rate)) + 1
        t_out = np.linspace(0.0, opt.duration, nout)
        X = np.zeros((nout, size)); U = np.zeros((nout, n)); R = np.zeros((nout, n)); yn = np.zeros(nout)
        hmax = 1.0 / opt.output_rate
        st, m, nrhs, nsteps, nrej, t_end = eng.continuous(
            plant, code, cp, tp, x0, t_out, opt.rtol, opt.atol, 1e-5, hmax, lim, X, U, R, yn)
        return _result(plant, law, trajectory, opt, t_out[:m], X[:m], U[:m], R[:m], yn[:m],
                       st, t_end, nrhs, nsteps, nrej)
    Ts, nsamples, dec = _sample_grid(opt)
    nout = nsamples // dec + 2
    X = np.zeros((nout, size)); U = np.zeros((nout, n)); R = np.zeros((nout, n)); yn = np.zeros(nout)
    tv = np.zeros(n)
    st, m, nrhs, ndone, t_end = eng.sampled(
        plant, code, cp, tp, x0, 0.0, Ts, nsamples, dec, opt.substeps, lim, X, U, R, yn, tv)
    t = np.arange(m) * dec * Ts
    if st != S.OK and m > 0:
        t[-1] = t_end
    return _result(plant, law, trajectory, opt, t, X[:m], U[:m], R[:m], yn[:m],
                   st, t_end, nrhs, ndone, 0, tv=tv)
