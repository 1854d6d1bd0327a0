"""Figures of an identification: held-out torques, measured and predicted, and their residuals.

Both build :class:`matplotlib.figure.Figure` objects directly (the backend is never switched).
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["torque_figure", "residual_figure"]


def _rows(n: int, title: str) -> tuple:
    fig = Figure(figsize=(11, 1.3 + 1.9 * n), constrained_layout=True)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    fig.suptitle(title)
    return fig, axes


def torque_figure(ident, title: str = "held-out torques: logged and predicted") -> Figure:
    """Per joint, on the held-out part: logged torque, prediction, and the prediction band."""
    h = ident.held_out
    t, tau, pred, band = h["t"], h["tau"], h["pred"], h["band"]
    n = tau.shape[1]
    fig, axes = _rows(n, title)
    for j, ax in enumerate(axes):
        ax.plot(t, tau[:, j], ".", ms=1.5, color="0.55", label="logged")
        ax.fill_between(t, pred[:, j] - band[:, j], pred[:, j] + band[:, j], color="C0", alpha=0.2,
                        label=f"{100 * ident.validation['band_confidence']:g} % band")
        ax.plot(t, pred[:, j], color="C0", lw=1.2, label="predicted")
        ax.set_ylabel(f"tau{j + 1} [N m]")
        ax.text(0.01, 0.95, f"rms {ident.validation['rms'][j]:.3g} N m", transform=ax.transAxes, va="top",
                fontsize=8)
    axes[0].legend(loc="upper right", fontsize=8, ncol=3)
    axes[-1].set_xlabel("t [s]")
    return fig


def residual_figure(ident, title: str = "held-out residuals: logged - predicted") -> Figure:
    """Per joint: the held-out residual over time with the prediction band, and its histogram."""
    h = ident.held_out
    t, r, band = h["t"], h["tau"] - h["pred"], h["band"]
    n = r.shape[1]
    fig = Figure(figsize=(11, 1.3 + 1.9 * n), constrained_layout=True)
    axes = fig.subplots(n, 2, squeeze=False, gridspec_kw={"width_ratios": [4, 1]})
    fig.suptitle(title)
    for j in range(n):
        ax, hx = axes[j]
        ax.plot(t, r[:, j], ".", ms=1.5, color="C3")
        ax.plot(t, band[:, j], color="0.4", lw=0.8)
        ax.plot(t, -band[:, j], color="0.4", lw=0.8)
        ax.axhline(0.0, color="0.7", lw=0.6)
        ax.set_ylabel(f"joint {j + 1} [N m]")
        hx.hist(r[:, j], bins=40, orientation="horizontal", color="C3", alpha=0.7)
        hx.set_yticks([])
        inside = float(np.mean(np.abs(r[:, j]) <= band[:, j]))
        hx.set_title(f"{100 * inside:.1f} % inside", fontsize=8)
    axes[-1, 0].set_xlabel("t [s]")
    return fig
