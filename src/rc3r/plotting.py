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

__all__ = ["run_figure", "plot_run", "plot_error_comparison", "comparison_figure", "boundary_layer_figure"]


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


def _caption(fig: Figure, caption: str) -> None:
    """A caption line under the axes, with room kept for it by the layout engine."""
    if caption:
        fig.get_layout_engine().set(rect=(0, 0.06, 1, 0.94))
        fig.text(0.01, 0.005, caption, fontsize=8, ha="left", va="bottom", wrap=True)


def comparison_figure(runs: dict, title: str, caption: str = "") -> Figure:
    """Per joint, the runs' |e_j| (left, log scale) and u_j (right) on one axis each.

    ``runs`` maps a label (e.g. ``"FBL"``, ``"robust eps 0.5"``) to a :class:`SimResult`; every
    run shares the joint's axis, so the laws compare at a glance (the paper has one figure per run).
    """
    first = next(iter(runs.values()))
    n = first.q.shape[1]
    fig = Figure(figsize=(11, 1.6 + 2.0 * n), constrained_layout=True)
    axes = np.atleast_2d(fig.subplots(n, 2, sharex=True))
    for label, res in runs.items():
        for j in range(n):
            axes[j, 0].semilogy(res.t[1:], np.maximum(np.abs(res.e[1:, j]), 1e-12), lw=0.8, label=label)
            axes[j, 1].plot(res.t, res.u[:, j], lw=0.7, label=label)
    for j in range(n):
        axes[j, 0].set_ylabel(f"|e{j + 1}| [rad]")
        axes[j, 1].set_ylabel(f"u{j + 1} [N m]")
        for ax in axes[j]:
            ax.grid(alpha=0.3, which="both")
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    axes[0, 0].set_title("tracking error |q_j - q_d,j| (log)")
    axes[0, 1].set_title("joint torque u_j")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    axes[0, 1].legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)  # off the data
    fig.suptitle(title)
    _caption(fig, caption)
    return fig


def boundary_layer_figure(runs: dict, title: str, caption: str = "") -> Figure:
    """||Y^T r|| over time against each robust run's boundary-layer threshold eps (log scale).

    Inside the layer (||Y^T r|| <= eps) the robust term is the linear high gain
    (rho / eps) Y Y^T r; outside it, the unit-vector term of magnitude rho. ``runs`` maps a
    label to a robust-law :class:`SimResult` (its ``controller`` holds ``eps``).
    """
    fig = Figure(figsize=(12, 4.6), constrained_layout=True)
    ax = fig.subplots()
    for k, (label, res) in enumerate(runs.items()):
        colour = f"C{k}"
        ax.semilogy(res.t[1:], np.maximum(res.yt_r_norm[1:], 1e-12), lw=0.8, color=colour,
                    label=f"||Y^T r||, {label}")
        eps = res.controller.get("eps")
        if isinstance(eps, (int, float)):
            ax.axhline(eps, color=colour, ls="--", lw=1.0, label=f"eps = {eps:g} (boundary layer), {label}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("||Y^T r|| (mixed units: each coefficient of theta paired with r [rad/s])", fontsize=8)
    ax.grid(alpha=0.3, which="both")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside right upper", fontsize=8)  # off the data
    ax.set_title(title)
    _caption(fig, caption)
    return fig
