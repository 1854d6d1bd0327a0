"""What ``rc3r design`` writes: ``design.toml`` (a run configuration), ``design.md``, ``design.json``, the figure.

``design.toml`` is the configuration the design was made for (arm, bounds, plant effects, trajectory)
with ``[gains.<law>]`` for robust, robust-coeff, adaptive, fbl and pd and ``[simulation] rate``:
``rc3r run --config`` and ``rc3r montecarlo --config`` take it as it is.
"""
from __future__ import annotations

import numpy as np

__all__ = ["design_toml", "design_markdown", "design_figure", "predicted_bound"]


def design_toml(result, header: str = "", base=None) -> str:
    """The text of ``design.toml`` for a :class:`rc3r.design.verify.DesignResult`.

    Parameters
    ----------
    result : DesignResult
        The design.
    header : str
        More comment lines for the top (the command that made it).
    base : path-like, optional
        The directory ``design.toml`` is written to: the files the design names are then written
        portably (:func:`rc3r.io.portable_config`: a URDF of example-robot-data as
        ``erd:REL``, any other file relative to ``base``); without it, as the config has them.

    Returns
    -------
    str
        The TOML text.
    """
    from ..identify.bounds_file import to_toml
    from ..io import portable_config

    config = result.config if base is None else portable_config(result.config, base)
    cfg = {k: v for k, v in config.items() if k not in ("gains", "simulation")}
    sim = dict(config.get("simulation", {}))
    sim["rate"] = float(result.rate)
    cfg["gains"] = result.gains()
    cfg["simulation"] = sim
    top = ("Gains and boundary layer for a sampled controller, chosen by rc3r design (docs/design.md).\n"
           "rc3r run --config design.toml [--controller robust|robust-coeff|adaptive|fbl|pd]; "
           "rc3r montecarlo --config design.toml")
    return to_toml(cfg, top + ("\n" + header if header else ""))


def predicted_bound(result) -> np.ndarray:
    """Spong's ultimate bound per joint (:func:`rc3r.controllers.guarantee.error_bound`) of the chosen robust
    law, with the model's inertia range along the reference (continuous time; plants inside the ball)."""
    from ..controllers import make_law
    from ..controllers.guarantee import error_bound

    g = result.gains()["robust"]
    n = len(g["K"])
    law = make_law("robust", np.zeros(1), rho=result.model["rho"], **g)
    return error_bound(law, result.spectrum["m_min"], result.spectrum["m_max"], n)


def _f(x, fmt=".3g") -> str:
    return "-" if x is None else format(x, fmt)


def _verdicts(s: dict) -> str:
    return ", ".join(f"{v} {k}" for k, v in sorted(s.get("verdicts", {}).items())) or "-"


def design_markdown(result, command: str = "") -> str:
    """``design.md``: the rule, the chosen numbers, bound vs measured error, torques vs limits, lowest rate."""
    d, g = result.design, result.gains()
    ch = result.chosen
    lines = ["# rc3r design", ""]
    if command:
        lines += [f"`{command}`", ""]
    lines += [f"Arm: {result.model.get('nominal')}; bounds: {result.model.get('box') or '-'} "
              f"(rho = {result.model['rho']:.6g}); controller rate {result.rate:g} Hz, margin {result.margin:g} "
              f"(also verified at {result.rate / result.margin:g} Hz); delay {d.delay} samples; "
              f"{len(result.plants)} plants: {', '.join(result.plants[:4])}{' ...' if len(result.plants) > 4 else ''}.",
              "", "## The rule", "",
              "Inside the boundary layer the closed loop is M r' = -(K + (rho/eps) Y Y^T) r + ...; a zero-order hold of "
              "period T (and a delay of d samples) keeps a mode lambda of M^-1 (K + (rho/eps) Y Y^T) stable while "
              f"T lambda < {2 * np.sin(np.pi / (2 * (2 * d.delay + 1))):.4g} and free of oscillation while "
              f"T lambda <= {_real(d.delay):.4g}. Along the reference "
              f"L_Y = max lambda_max(M^-1 Y Y^T) = {d.L_Y:.4g} (rho L_Y / eps is a rate [1/s]), "
              f"L_K = max lambda_max(M^-1 K) = {d.L_K:.4g} 1/s, so:", "",
              f"* velocity-loop bandwidth b = {d.bandwidth:.4g} 1/s ("
              + ("K(q) = b M(q), scheduled: every mode of the model's M^-1 K is b"
                 if d.scaling == "inertia" else "K = b M(q_d(0)), the full matrix"
                 if d.scaling == "full" else "K_i = b / (M^-1(q_d(0)))_ii") + "), "
              f"Lambda = {d.Lambda:.4g} 1/s;",
              f"* stability boundary of the rule at {result.rate:g} Hz: eps = T rho L_Y / (c_d - T L_K) = "
              f"{d.eps_stable:.4g};",
              f"* fast form (free of oscillation at {result.rate:g} Hz): eps = {d.eps:.4g};",
              f"* verified: **eps = {_f(result.eps, '.4g')}** ({_f(None if result.eps is None else result.eps / d.eps_stable, '.3g')}"
              " x the rule's stability boundary)" + ("" if result.eq6_ok else
                                                     " -- NO eps tried was clean at both rates: see the table"),
              "", "## eps tried (robust law)", "",
              f"| eps | at {result.rate:g} Hz | worst max\\|e\\| [rad] | worst chattering [N m/s] | "
              f"at {result.rate / result.margin:g} Hz | worst max\\|e\\| [rad] | clean |", "|---|---|---|---|---|---|---|"]
    for lv in result.levels:
        a, lo = lv["at_rate"], lv["at_low"]
        lines.append(f"| {lv['eps']:.4g} | {_verdicts(a)} | {_f(a.get('worst_error'))} | "
                     f"{_f(a.get('worst_chattering'))} | {_verdicts(lo)} | {_f(lo.get('worst_error'))} | "
                     f"{'yes' if lv['clean'] else 'no'} |")
    lines += ["", "## The chosen gains (design.toml)", "", "| law | gains |", "|---|---|"]
    for law, table in g.items():
        text = "; ".join(f"{k} = {_vec(v)}" for k, v in table.items())
        lines.append(f"| {law} | {text} |")
    lines += ["", "## Bound, errors, torques", ""]
    fbl = result.baselines.get("fbl", {})
    if ch is not None:
        bound = predicted_bound(result)
        lines += [f"* predicted ultimate bound (Spong, continuous time, model inertia {result.spectrum['m_min']:.3g}.."
                  f"{result.spectrum['m_max']:.3g} kg m^2): max_j {bound.max():.3g} rad; worst measured max|e| "
                  f"{ch['at_rate']['worst_error']:.3g} rad at {result.rate:g} Hz "
                  f"({ch['at_rate']['worst_error'] / bound.max():.3g} of the bound).",
                  f"* FBL (Kp = {g['fbl']['Kp']:.4g}, Kd = {g['fbl']['Kd']:.4g}) on the same plants: worst max|e| "
                  f"{_f(fbl.get('worst_error'))} rad ({_verdicts(fbl)}); robust/FBL = "
                  f"{ch['at_rate']['worst_error'] / fbl['worst_error']:.3g}." if fbl.get("worst_error") else "* FBL: -"]
        u = np.maximum(ch["at_rate"]["u_max"], ch["at_low"]["u_max"])
        lim = result.effort_limit
        peaks = ", ".join(f"{x:.3g}" + (f"/{lim[j]:g}" if lim else "") for j, x in enumerate(u))
        lines.append(f"* torque peaks per joint [N m]{' / URDF effort limits' if lim else ''}: {peaks}"
                     + (f"; largest ratio {np.max(u / np.asarray(lim)):.3g}" if lim else "") + ".")
    for law in ("robust-coeff", "adaptive"):
        s = result.baselines.get(law)
        if s:
            low = s.get("at_low")
            lines.append(f"* {law} at {result.rate:g} Hz (gains above): {_verdicts(s)}, "
                         f"worst max|e| {_f(s.get('worst_error'))} rad"
                         + (f"; at {result.rate / result.margin:g} Hz: {_verdicts(low)}, worst max|e| "
                            f"{_f(low.get('worst_error'))} rad." if low else " (at the rate only)."))
    rec = result.recommendation()
    if rec is not None:
        f = rec["fbl_worst_error"]
        lines.append(f"* **recommended robust law: {rec['law']}** ({'eq. 7' if rec['law'] == 'robust-coeff' else 'eq. 6'}):"
                     f" {rec['why']}; FBL {_f(f)} rad. Run it: `rc3r montecarlo --config design.toml "
                     f"--controllers {rec['law']},fbl`.")
    else:
        lines.append("* recommended robust law: none (neither eq. 6 nor eq. 7 was clean on every plant at both rates).")
    low = result.lowest_clean_rate()
    tried = ", ".join(f"{r['rate']:.4g} Hz {'clean' if r['clean'] else _verdicts(r)}" for r in result.low_rates)
    lines += [f"* lowest rate at which the design stayed clean: {_f(low, '.4g')} Hz"
              + (f" (below {result.rate / result.margin:g} Hz on the first four plants: {tried})" if tried else ""),
              "", "Figure: design.png (worst error and chattering against eps at the rate). Runs: runs.csv.", ""]
    return "\n".join(lines)


def _real(d: int) -> float:
    from .rule import real_limit

    return real_limit(d)


def _vec(v) -> str:
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_vec(x) for x in v) + "]"
    return f"{v:.4g}"


def design_figure(result):
    """Worst max|e| and worst chattering against eps at the rate; the chosen eps and the rule's stability
    boundary marked (a :class:`matplotlib.figure.Figure`)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.5, 4.2))
    ax = fig.add_subplot(111)
    lv = result.levels
    eps = np.array([x["eps"] for x in lv])
    err = np.array([x["at_rate"].get("worst_error", np.nan) for x in lv], dtype=float)
    chat = np.array([x["at_rate"].get("worst_chattering", np.nan) for x in lv], dtype=float)
    clean = np.array([x["clean"] for x in lv])
    ax.plot(eps, err, "-", color="C0", lw=1)
    ax.scatter(eps[clean], err[clean], color="C2", zorder=3, label="clean at both rates")
    ax.scatter(eps[~clean], err[~clean], color="C3", marker="x", zorder=3, label="not clean")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("eps")
    ax.set_ylabel(f"worst max|e| at {result.rate:g} Hz [rad]", color="C0")
    ax2 = ax.twinx()
    ax2.plot(eps, chat, "s--", color="C1", ms=4, lw=1)
    ax2.set_yscale("log")
    ax2.set_ylabel("worst chattering [N m/s]", color="C1")
    ax.axvline(result.design.eps_stable, color="k", ls=":", label="rule's stability boundary")
    if result.eps is not None:
        ax.axvline(result.eps, color="C2", ls="-", alpha=0.6, label=f"chosen eps = {result.eps:.3g}")
    fbl = result.baselines.get("fbl", {}).get("worst_error")
    if fbl:
        ax.axhline(fbl, color="C4", ls="-.", label=f"FBL worst max|e| = {fbl:.3g}")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(f"rc3r design: robust law at {result.rate:g} Hz over {len(result.plants)} plants", fontsize=10)
    fig.tight_layout()
    return fig
