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

__all__ = ["run_figure", "plot_run", "plot_error_comparison", "comparison_figure", "boundary_layer_figure",
           "estimate_errors", "estimate_figure", "ESTIMATE_UNITS"]


def plot_run(res, path: str | Path, title: str) -> Path:
    """:func:`run_figure` saved as PNG (atomically)."""
    return atomic_savefig(run_figure(res, title), path, dpi=110)


def run_figure(res, title: str) -> Figure:
    """Joint errors (left) and torques (right), one row per joint, as the paper's figures 3-7."""
    n = res.q.shape[1]
    height = 1.2 + 1.95 * n
    fig = Figure(figsize=(11, height))  # a fixed layout: the layout engine costs seconds for a 6-joint arm
    fig.subplots_adjust(left=0.08, right=0.985, wspace=0.22, hspace=0.12, bottom=0.55 / height,
                        top=1.0 - 0.75 / height)
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
    """``max_j |e_j(t)|`` of several runs on a log scale."""
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
    """Per joint, the runs' ``|e_j|`` (left, log scale) and u_j (right) on one axis each.

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
    label to a robust-law :class:`SimResult` (its ``controller`` holds ``eps``). The legend has
    one entry per run (its ``||Y^T r||``) and one entry for every dashed line (the eps of the run of
    the same colour), so a label that names eps is not repeated.
    """
    from matplotlib.lines import Line2D

    fig = Figure(figsize=(12, 4.6), constrained_layout=True)
    ax = fig.subplots()
    dashed = False
    for k, (label, res) in enumerate(runs.items()):
        colour = f"C{k}"
        ax.semilogy(res.t[1:], np.maximum(res.yt_r_norm[1:], 1e-12), lw=0.8, color=colour,
                    label=f"||Y^T r||, {label}")
        eps = res.controller.get("eps")
        if isinstance(eps, (int, float)):
            ax.axhline(eps, color=colour, ls="--", lw=1.0, label="_boundary layer")  # "_": not in the legend
            dashed = True
    ax.set_xlabel("t [s]")
    ax.set_ylabel("||Y^T r|| (mixed units: each coefficient of theta paired with r [rad/s])", fontsize=8)
    ax.grid(alpha=0.3, which="both")
    handles, labels = ax.get_legend_handles_labels()
    if dashed:
        handles.append(Line2D([], [], color="0.3", ls="--", lw=1.0))
        labels.append("dashed: ||Y^T r|| = eps of the run of the same colour (its boundary layer)")
    fig.legend(handles, labels, loc="outside right upper", fontsize=8)  # off the data
    ax.set_title(title)
    _caption(fig, caption)
    return fig


#: Units of ``||theta_hat - theta||``: theta mixes kg m^2 (moments), kg m (first moments) and, for
#: base parameters of a URDF arm, kg; the norm is taken over the SI numbers, as rho is.
ESTIMATE_UNITS = "SI: kg m^2 and kg m entries, as rho"


def estimate_errors(res, theta) -> dict:
    """The adaptive law's estimate ``theta_hat(t) = res.z`` against the plant's ``theta`` (p,).

    Returns ``t`` (N,) [s], ``error`` = ``||theta_hat(t) - theta||`` (N,), ``moved`` =
    ``||theta_hat(t) - theta_hat(0)||`` (N,) (theta_hat(0) = the law's theta_0), and ``rel0``, ``rel_end``
    (p,) = ``|theta_hat_i - theta_i| / |theta_i|`` at the first and last stored rows (NaN where
    theta_i = 0 to within 1e-12 ||theta||). ``ValueError`` if ``res`` holds no p-vector estimate.
    """
    theta = np.asarray(theta, dtype=float).ravel()
    z = np.asarray(res.z, dtype=float)
    if z.ndim != 2 or z.shape[1] != theta.size or z.shape[0] == 0:
        raise ValueError(f"the run's controller state has shape {z.shape}, not (N, {theta.size}): "
                         "only the adaptive law carries a parameter estimate")
    d = z - theta
    scale = np.abs(theta)
    ok = scale > 1e-12 * max(np.linalg.norm(theta), 1e-300)
    rel = np.full((2, theta.size), np.nan)
    rel[:, ok] = np.abs(d[[0, -1]][:, ok]) / scale[ok]
    return {"t": np.asarray(res.t, dtype=float), "error": np.linalg.norm(d, axis=1),
            "moved": np.linalg.norm(z - z[0], axis=1), "rel0": rel[0], "rel_end": rel[1]}


def estimate_figure(res, theta, title: str = "adaptive law: parameter estimate", caption: str | None = None,
                    names=None) -> Figure:
    """The adaptive law's estimate against the plant's theta: norms over time (top), per coefficient (bottom).

    Top: ``||theta_hat(t) - theta||`` (line 0) and ``||theta_hat(t) - theta_0||`` (line 1) [:data:`ESTIMATE_UNITS`]
    against t [s]. Bottom: ``|theta_hat_i - theta_i| / |theta_i|`` at t = 0 and at the end (bars, log
    scale). Legends sit outside the axes. ``theta`` is the *plant's* coefficient vector (the law
    never sees it: ``RunSpec.true_rigid.theta``); ``names`` labels the coefficients (default theta_1 ...).
    Data: :func:`estimate_errors`.
    """
    est = estimate_errors(res, theta)
    p = est["rel0"].size
    names = list(names) if names is not None else [f"theta_{i + 1}" for i in range(p)]
    fig = Figure(figsize=(12, 7.2), constrained_layout=True)
    top, bottom = fig.subplots(2, 1, gridspec_kw={"height_ratios": [1.1, 1.0]})
    top.plot(est["t"], est["error"], lw=1.2, color="C0", label="||theta_hat(t) - theta||: distance to the plant")
    top.plot(est["t"], est["moved"], lw=1.0, color="C1", ls="--",
             label="||theta_hat(t) - theta_0||: how far the estimate moved")
    top.set_xlabel("t [s]")
    top.set_ylabel(f"norm [{ESTIMATE_UNITS}]", fontsize=8)
    top.set_ylim(bottom=0)
    top.grid(alpha=0.3)
    top.set_title(f"{title} ({res.mode}{'' if res.options.rate is None else f' {res.options.rate:g} Hz'})")
    top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)  # off the data
    x = np.arange(p)
    tiny = 1e-16  # a bar of exactly 0 has no place on a log axis
    bottom.bar(x - 0.2, np.maximum(est["rel0"], tiny), width=0.4, color="C7", label=f"t = {est['t'][0]:g} s (theta_0)")
    bottom.bar(x + 0.2, np.maximum(est["rel_end"], tiny), width=0.4, color="C0", label=f"t = {est['t'][-1]:g} s")
    bottom.set_yscale("log")
    bottom.set_xticks(x, names, rotation=90 if p > 20 else 45, fontsize=7 if p > 20 else 8)
    bottom.set_ylabel("|theta_hat_i - theta_i| / |theta_i|", fontsize=8)
    bottom.grid(alpha=0.3, which="both", axis="y")
    bottom.set_title("relative error per coefficient (no bar where theta_i = 0)", fontsize=9)
    bottom.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    if caption is None:
        e0, e1, mv = est["error"][0], est["error"][-1], est["moved"].max()
        caption = (f"The estimate moves (up to {mv:.3g} from theta_0) while the distance to the plant's theta goes "
                   f"from {e0:.4g} to {e1:.4g}: Slotine-Li adaptation guarantees tracking, not convergence of "
                   "theta_hat to theta (that needs a persistently exciting trajectory).")
    _caption(fig, caption)
    return fig
