"""Figures (PNG, matplotlib Agg backend), written atomically."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .io import atomic_savefig  # noqa: E402

__all__ = ["plot_run", "plot_error_comparison", "plot_tradeoff"]


def plot_run(res, path: str | Path, title: str) -> Path:
    """Joint errors (left) and torques (right), one row per joint, as the paper's figures 3-7."""
    fig, axes = plt.subplots(3, 2, figsize=(11, 7), sharex=True, constrained_layout=True)
    for j in range(3):
        axes[j, 0].plot(res.t, res.e[:, j], lw=0.9)
        axes[j, 0].set_ylabel(f"e{j + 1} [rad]")
        axes[j, 0].ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
        axes[j, 1].plot(res.t, res.u[:, j], lw=0.7, color="tab:red")
        axes[j, 1].set_ylabel(f"u{j + 1} [N m]")
        for ax in axes[j]:
            ax.grid(alpha=0.3)
    axes[2, 0].set_xlabel("t [s]")
    axes[2, 1].set_xlabel("t [s]")
    axes[0, 0].set_title("tracking error q - q_d")
    axes[0, 1].set_title("joint torque u")
    status = "" if res.ok else f"  [{res.message}]"
    fig.suptitle(f"{title} ({res.mode}{'' if res.options.rate is None else f' {res.options.rate:g} Hz'}){status}")
    path = atomic_savefig(fig, path, dpi=110)
    plt.close(fig)
    return path


def _finish(fig, ax, path, title, xlabel, ylabel) -> Path:
    """Label, grid, legend; save atomically; close."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    path = atomic_savefig(fig, path, dpi=110)
    plt.close(fig)
    return path


def plot_error_comparison(runs: dict, path: str | Path, title: str) -> Path:
    """max_j |e_j(t)| of several runs on a log scale."""
    fig, ax = plt.subplots(figsize=(9, 4.5), constrained_layout=True)
    for name, res in runs.items():
        ax.semilogy(res.t, np.maximum(np.abs(res.e).max(axis=1), 1e-16), lw=0.9, label=name)
    return _finish(fig, ax, path, title, "t [s]", "max_j |e_j| [rad]")


def plot_tradeoff(rows: list[dict], path: str | Path, title: str) -> Path:
    """Final error bound vs chattering, one curve per mode, points labelled by eps."""
    fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    for mode in sorted({r["mode_label"] for r in rows}):
        pts = [r for r in rows if r["mode_label"] == mode and r["status"] == "ok"]
        if not pts:
            continue
        x = [sum(r["chattering"]) for r in pts]
        y = [max(r["final_error_bound"]) for r in pts]
        ax.loglog(x, y, "o-", label=mode)
        for r, xi, yi in zip(pts, x, y):
            ax.annotate(f"{r['eps']:.3g}", (xi, yi), fontsize=7, textcoords="offset points", xytext=(3, 3))
    return _finish(fig, ax, path, title,
                   "chattering: total variation of u per second, summed over joints [N m/s]",
                   "final error bound max_j max_{t>T-1} |e_j| [rad]")
