"""Figures of the campaigns (matplotlib ``Figure`` objects, never ``pyplot``: the user's backend is untouched).

* :func:`error_distribution` -- Monte Carlo: empirical CDF of the max error per controller.
* :func:`error_vs_distance` -- Monte Carlo: max error against ``||theta - theta_0||``, with the
  law's ``rho`` and the certified ``rho_max`` marked, and the robust law's predicted bound.
* :func:`pareto` -- eps sweep: final error against chattering, one curve per rate.
* :func:`stability_map` -- rate sweep: eps x rate cells (clean / chattering / diverged)
  with the safe-rate boundary drawn, one panel per K (a per-joint K titled by its entries).
"""
from __future__ import annotations

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from .studies import gain_label

__all__ = ["error_distribution", "error_vs_distance", "pareto", "stability_map"]


def error_distribution(rows: list[dict], title: str) -> Figure:
    """Fraction of plants whose ``max_j max_t |e_j|`` is at most x, per controller (log x)."""
    fig = Figure(figsize=(8, 4.8), constrained_layout=True)
    ax = fig.subplots()
    for c in sorted({r["controller"] for r in rows}):
        err = np.sort([r["max_error"] for r in rows if r["controller"] == c and r["status"] == "ok"])
        div = sum(1 for r in rows if r["controller"] == c and r["status"] != "ok")
        if err.size:
            frac = np.arange(1, err.size + 1) / (err.size + div)
            ax.step(err, frac, where="post", label=f"{c} ({err.size} runs" + (f", {div} diverged)" if div else ")"))
    ax.set_xscale("log")
    ax.set_ylim(0, 1.02)
    ax.grid(True, which="both", alpha=0.3)
    ax.set_xlabel("max tracking error over the run, max_j max_t |e_j| [rad]")
    ax.set_ylabel("fraction of plants (empirical CDF)")
    ax.set_title(title)
    ax.legend(loc="lower right", fontsize=8)
    return fig


def error_vs_distance(rows: list[dict], radii: dict, title: str) -> Figure:
    """Max error against ||theta - theta_0|| per controller; rho and rho_max as vertical lines."""
    fig = Figure(figsize=(8, 4.8), constrained_layout=True)
    ax = fig.subplots()
    for c in sorted({r["controller"] for r in rows}):
        rs = [r for r in rows if r["controller"] == c and r["status"] == "ok"]
        ax.scatter([r["theta_dist"] for r in rs], [r["max_error"] for r in rs], s=10, alpha=0.7, label=c)
    bounds = [r for r in rows if r["predicted_bound"] is not None and r["covered"]]
    if bounds:
        ax.scatter([r["theta_dist"] for r in bounds], [r["predicted_bound"] for r in bounds], s=12,
                   marker="_", color="k", label=f"predicted bound ({bounds[0]['controller']}, inside the ball)")
    if radii.get("rho") is not None:
        ax.axvline(radii["rho"], color="tab:red", ls="--", lw=1, label=f"rho = {radii['rho']:.4g} (the law's)")
    if radii.get("rho_max") is not None:
        ax.axvline(radii["rho_max"], color="tab:purple", ls=":", lw=1.2,
                   label=f"rho_max = {radii['rho_max']:.4g} (certified, whole box)")
    ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    ax.set_xlabel("||theta - theta_0|| of the plant [SI units of theta]")
    ax.set_ylabel("max_j max_t |e_j| [rad]")
    ax.set_title(title)
    ax.legend(fontsize=7, loc="best")
    return fig


def pareto(summary: list[dict], title: str) -> Figure:
    """Worst final error bound against worst chattering over eps; one curve per rate, points labelled by eps."""
    fig = Figure(figsize=(8, 5), constrained_layout=True)
    ax = fig.subplots()
    for rate in sorted({s["rate_hz"] or 0.0 for s in summary}):
        pts = [s for s in summary if (s["rate_hz"] or 0.0) == rate and s["final_error"] is not None]
        if not pts:
            continue
        x = [s["chattering"] for s in pts]
        y = [s["final_error"] for s in pts]
        ax.loglog(x, y, "o-", label="continuous" if rate == 0.0 else f"sampled {rate / 1000:g} kHz")
        for s, xi, yi in zip(pts, x, y):
            ax.annotate(f"{s['eps']:.3g}", (xi, yi), fontsize=7, textcoords="offset points", xytext=(3, 3))
    ax.grid(True, which="both", alpha=0.3)
    ax.set_xlabel("chattering: total variation of u per second, summed over joints [N m/s]")
    ax.set_ylabel("final error bound max_j max_{t > T-1 s} |e_j| [rad]")
    ax.set_title(title)
    ax.legend(fontsize=8)
    return fig


_CLASSES = ("clean", "chattering", "diverged", "missing")
_COLOURS = ("#4caf50", "#ff9800", "#d32f2f", "#bdbdbd")


def stability_map(maps: dict, title: str) -> Figure:
    """One panel per K: rows eps, columns rate; the safe-rate boundary as a black step line."""
    keys = list(maps)
    fig = Figure(figsize=(5.2 * len(keys) + 1, 4.6), constrained_layout=True)
    axes = np.atleast_1d(fig.subplots(1, len(keys), squeeze=False)[0])
    cmap = ListedColormap(_COLOURS)
    for ax, k in zip(axes, keys):
        m = maps[k]
        grid = np.array([[_CLASSES.index(c) for c in row] for row in m["cells"]])
        ax.imshow(grid, cmap=cmap, vmin=-0.5, vmax=len(_CLASSES) - 0.5, origin="lower", aspect="auto")
        ax.set_xticks(range(len(m["rates"])), [f"{r / 1000:g}" for r in m["rates"]], fontsize=8)
        ax.set_yticks(range(len(m["eps"])), [f"{e:g}" for e in m["eps"]], fontsize=8)
        ax.set_xlabel("controller rate [kHz]")
        ax.set_ylabel("eps")
        xs, ys = [], []
        for i, e in enumerate(m["eps"]):
            s = m["safe_rate"].get(e)
            x = len(m["rates"]) - 0.5 if s is None else m["rates"].index(s) - 0.5
            xs += [x, x]
            ys += [i - 0.5, i + 0.5]
        ax.plot(xs, ys, color="k", lw=2)
        ax.set_title(f"K = {gain_label(k)}", fontsize=9)
    handles = [Patch(color=c, label=n) for n, c in zip(_CLASSES[:3], _COLOURS[:3])]
    handles.append(Patch(facecolor="none", edgecolor="k", label="safe-rate boundary (clean to its right)"))
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=8)
    fig.suptitle(title)
    return fig
