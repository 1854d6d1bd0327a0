"""A :class:`~rc3r.simulate.SimResult` as a table, a CSV file, a figure, a run directory.

Columns (``n`` joints): ``t`` [s], ``q1..qn`` [rad], ``qd1..qdn`` [rad/s], ``qdes1..qdesn``
[rad], ``e1..en = q - q_des`` [rad], ``u1..un`` [N m], ``ytr_norm`` = ``||Y^T r||`` (robust
laws; 0 otherwise). The same columns in :func:`to_pandas`, :func:`write_csv` and the
``timeseries.csv`` of ``rc3r run``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..io import atomic_path, atomic_write_json

__all__ = ["columns", "table", "to_pandas", "write_csv", "save"]


def columns(n: int) -> list[str]:
    """Column names for ``n`` joints."""
    return (["t"] + [f"{k}{j}" for k in ("q", "qd", "qdes", "e", "u") for j in range(1, n + 1)]
            + ["ytr_norm"])


def table(res) -> np.ndarray:
    """The time series as one (N, 5 n + 2) array in :func:`columns` order."""
    return np.column_stack([res.t, res.q, res.qd, res.q_des, res.e, res.u, res.yt_r_norm])


def to_pandas(res):
    """A ``pandas.DataFrame`` indexed by ``t`` [s]; pandas is an optional dependency."""
    try:
        import pandas as pd
    except ImportError:
        raise ConfigError("SimResult.to_pandas needs pandas: pip install 'rc3r[pandas]' (or pandas)") from None
    df = pd.DataFrame(table(res), columns=columns(res.n))
    return df.set_index("t")


def write_csv(res, path) -> Path:
    """Write the time series as CSV (atomically)."""
    with atomic_path(path) as tmp:
        np.savetxt(tmp, table(res), delimiter=",", header=",".join(columns(res.n)), comments="", fmt="%.10g")
    return Path(path)


def save(res, directory, metrics: dict | None = None, title: str | None = None) -> Path:
    """Write what ``rc3r run`` writes: ``timeseries.csv``, ``run.png``, ``metrics.json``.

    ``metrics`` defaults to :func:`rc3r.simulate.metrics.run_metrics` of ``res``. Each file is
    written atomically; the directory is created if needed.
    """
    from ..plotting import plot_run
    from .metrics import run_metrics

    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    write_csv(res, d / "timeseries.csv")
    plot_run(res, d / "run.png", title or res.controller.get("name", "run"))
    atomic_write_json(d / "metrics.json", metrics if metrics is not None else run_metrics(res))
    return d
