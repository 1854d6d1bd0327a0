"""Figures (PNG), written atomically.

Figures are built as :class:`matplotlib.figure.Figure` objects, not through
``pyplot``: importing this module never changes the user's backend (a notebook
keeps its inline plots) and nothing is left open in pyplot's figure manager.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from .io import atomic_savefig

__all__ = ["run_figure", "plot_run", "plot_error_comparison"]


def plot_run(res, path: str | Path, title: str) -> Path:
    """:func:`run_figure` saved as PNG (atomically)."""
    return atomic_savefig(run_figure(res, title), path, dpi=110)


def run_figure(res, title: str) -> Figure:
    """Joint errors (left) and torques (right), one row per joint, as the paper's figures 3-7."""
    n = res.q.shape[1]
    fig = Figure(figsize=(11, 1.2 + 1.95 * n), constrained_layout=True)
    axes = np.atleast_2d(fig.subplots(n, 2, sharex=True))
    for j in range(n):
        axes[j, 0].plot(res.t, res.e[:, j], lw=0.9)
        axes[j, 0].set_ylabel(f"e{j + 1} [rad]")
        axes[j, 0].ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
        axes[j, 1].plot(res.t, res.u[:, j], lw=0.7, color="tab:red")
        axes[j, 1].set_ylabel(f"u{j + 1} [N m]")
        for ax in axes[j]:
            ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("t [s]")
    axes[-1, 1].set_xlabel("t [s]")
    axes[0, 0].set_title("tracking error q - q_d")
    axes[0, 1].set_title("joint torque u")
    status = "" if res.ok else f"  [{res.message}]"
    fig.suptitle(f"{title} ({res.mode}{'' if res.options.rate is None else f' {res.options.rate:g} Hz'}){status}")
    return fig


def _finish(fig, ax, path, title, xlabel, ylabel) -> Path:
    """Label, grid, legend; save atomically; close."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return atomic_savefig(fig, path, dpi=110)


def plot_error_comparison(runs: dict, path: str | Path, title: str) -> Path:
    """max_j |e_j(t)| of several runs on a log scale."""
    fig = Figure(figsize=(9, 4.5), constrained_layout=True)
    ax = fig.subplots()
    for name, res in runs.items():
        ax.semilogy(res.t, np.maximum(np.abs(res.e).max(axis=1), 1e-16), lw=0.9, label=name)
    return _finish(fig, ax, path, title, "t [s]", "max_j |e_j| [rad]")
