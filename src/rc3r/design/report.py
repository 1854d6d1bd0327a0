"""What ``rc3r design`` writes: ``design.toml`` (a run configuration), ``design.md``, ``design.json``, the figure.

``design.toml`` is the configuration the design was made for (arm, bounds, plant effects, trajectory)
with ``[gains.<law>]`` for robust, robust-coeff, adaptive, fbl and pd and ``[simulation] rate``:
``rc3r run --config`` and ``rc3r montecarlo --config`` take it as it is.
"""
from __future__ import annotations

from collections import Counter

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
    rec = result.recommendation()
    law = rec["law"] if rec is not None else "robust"
    cfg["controller"] = {"kind": law}
    cfg["simulation"] = sim
    cfg["design"] = design_table(result)
    top = ("Gains and boundary layer for a sampled controller, chosen by rc3r design (docs/design.md).\n"
           f"[controller] kind is the recommended law ({law}{'' if rec else ': NOT verified'}): rc3r run, montecarlo "
           "and export --config design.toml run it;\n--controller robust|robust-coeff|adaptive|fbl|pd runs "
           "another law of [gains]. " + ("[design] verified = true: clean on every plant tried (design.md)."
                                          if cfg["design"]["verified"] else
                                          "[design] verified = false: no robust law was clean (design.md says why)."))
    return to_toml(cfg, top + ("\n" + header if header else ""))


def design_table(result) -> dict:
    """``[design]`` of design.toml: ``verified``, the ``law`` of ``[controller]``, the rate and margin, and
    (when the worst-plant search ran) the worst plant found and its loop gain; ``note`` says why not verified."""
    rec = result.recommendation()
    out = {"verified": bool(result.ok), "law": rec["law"] if rec is not None else "robust",
           "rate": float(result.rate), "margin": float(result.margin)}
    worst = result.worst or {}
    w = worst.get(out["law"])
    if w:
        out["worst_plant"] = str(w["spec"])
        out["loop_gain"] = float(w["T_lambda"])
    if not result.ok:
        out["note"] = failure_line(result)
    return out


def failure_line(result) -> str:
    """One line: why no robust law verified (verdict counts per law, the deciding plant)."""
    parts = []
    lv = [x for x in result.levels if not x["clean"]]
    if lv:
        last = max(lv, key=lambda x: x["eps"])
        dec = last.get("decided_by") or {}
        parts.append(f"eq. 6 at its largest eps tried {last['eps']:.4g}: {_verdicts(last['at_rate'])} at "
                     f"{result.rate:g} Hz" + (f", decided by plant {dec['plant']} ({dec['verdict']} at "
                                              f"{dec['rate']:g} Hz)" if dec else ""))
    rc = result.baselines.get("robust-coeff")
    if rc:
        dec = rc.get("decided_by")
        parts.append(f"eq. 7 at eps_i {rc.get('eps_i', float('nan')):.4g}: {_verdicts(rc)} at {result.rate:g} Hz"
                     + (f", decided by plant {dec['plant']} ({dec['verdict']} at {dec['rate']:g} Hz)" if dec else ""))
    return "; ".join(parts) or "no robust law was clean on every plant"


def next_steps(result) -> list[str]:
    """What to try when no robust law verified, from the verdicts and the hardest plant found."""
    counts = Counter()
    for lv in result.levels:
        for side in ("at_rate", "at_low"):
            counts.update(lv[side].get("verdicts", {}))
    rc = result.baselines.get("robust-coeff") or {}
    counts.update(rc.get("verdicts", {}))
    counts.update((rc.get("at_low") or {}).get("verdicts", {}))
    counts.pop("clean", None)
    out = []
    w = result.worst.get("robust") or result.worst.get("robust-coeff")
    limits = []
    if counts.get("limit-violated"):
        limits.append(f"plants left the joint limits ({counts['limit-violated']} runs): a smaller or slower reference "
                      "([trajectory] in --config) or a smaller payload range")
    if counts.get("limit-violated", 0) >= counts.get("chattering", 0) + counts.get("diverged", 0):
        out += limits  # the most common failure first
        limits = []
    if counts.get("chattering") or counts.get("diverged"):
        if w and w["T_lambda"] > w["limit"]:
            need = result.rate * w["T_lambda"] / w["limit"]
            out.append(f"a higher --rate: the hardest plant ({w['spec']}) has T lambda_max = {w['T_lambda']:.3g} "
                       f"> {w['limit']:.3g} at {result.rate:g} Hz, so about {need:.3g} Hz for the same gains")
        else:
            out.append("a higher --rate (the held loop chattered or diverged)")
        out.append(f"a larger eps ({counts.get('chattering', 0)} runs chattered, {counts.get('diverged', 0)} "
                   "diverged; try it on the deciding plant: rc3r run --config design.toml --plant SPEC --eps E)")
    out += limits
    if counts.get("saturated"):
        out.append("torques reached the limits: a smaller payload range, or the arm's real torque limits")
    out.append("a smaller bounds set (payload range, box) if the real arm is known better; --margin 1 verifies "
               "at the rate only")
    return out


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
              "", f"Every figure of the rule and of the bound below is computed on the controller's own model: "
              f"{result.model.get('controller_model') or 'theta_0'} -- the M the law uses, not the URDF's.",
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
              f"Lambda = {d.Lambda:.4g} 1/s" + _b_note(result) + ";",
              f"* stability boundary of the rule at {result.rate:g} Hz: eps = T rho L_Y / (c_d - T L_K) = "
              f"{d.eps_stable:.4g};",
              f"* fast form (free of oscillation at {result.rate:g} Hz): eps = {d.eps:.4g};",
              f"* verified: **eps = {_f(result.eps, '.4g')}** ({_f(None if result.eps is None else result.eps / d.eps_stable, '.3g')}"
              " x the rule's stability boundary)" + ("" if result.eq6_ok else
                                                     " -- NO eps tried was clean at both rates: see the table"),
              "", "## eps tried (robust law)", "",
              f"| eps | at {result.rate:g} Hz | worst max\\|e\\| [rad] | worst chattering [N m/s] | "
              f"at {result.rate / result.margin:g} Hz | worst max\\|e\\| [rad] | clean | T lambda_max: model / hardest "
              "plant | decided by |", "|---|---|---|---|---|---|---|---|---|"]
    for lv in result.levels:
        a, lo = lv["at_rate"], lv["at_low"]
        w, dec = lv.get("worst") or {}, lv.get("decided_by")
        lines.append(f"| {lv['eps']:.4g} | {_verdicts(a)} | {_f(a.get('worst_error'))} | "
                     f"{_f(a.get('worst_chattering'))} | {_verdicts(lo)} | {_f(lo.get('worst_error'))} | "
                     f"{'yes' if lv['clean'] else 'no'} | {_f(lv.get('model_T_lambda'))} / {_f(w.get('T_lambda'))} | "
                     + ("-" if not dec else f"{_short(dec['plant'])} ({dec['verdict']} at {dec['rate']:g} Hz"
                        f"{', searched' if dec['searched'] else ''})") + " |")
    lines += ["", "## Hardest plants (worst-plant search)", ""]
    if result.search == "off" or not result.worst:
        lines.append("* not searched.")
    for law, w in result.worst.items():
        gain = f"eps = {w['eps']:.4g}" if "eps" in w else f"eps_i = {w['eps_i']:.4g}"
        lines.append(f"* {law} ({gain}) at {result.rate:g} Hz: hardest plant `{w['spec']}` ({w['why']}): "
                     f"T lambda_max(M_p^-1 G) = **{w['T_lambda']:.3g}** against the held loop's limit "
                     f"{w['limit']:.3g} (at t = {w['t']:.3g} s); on the controller's model (the rule's prediction) "
                     f"{_f(w.get('model_T_lambda'))}. Inertia margin: along that direction the plant may be "
                     f"{w['limit'] / w['T_lambda']:.3g} x the hardest plant's inertia "
                     + ("(lighter than it: " if w['limit'] > w['T_lambda'] else "(it must be heavier: ")
                     + f"the rule predicted {_f(None if not w.get('model_T_lambda') else w['limit'] / w['model_T_lambda'])} "
                     "x the model's) before the held loop at the rate loses stability."
                     + _not_clean(result, law, w))
    lines.append("* URDF uncertainty: " + _urdf_line(result))
    if result.search != "off":
        how = ("both ends of the payload range" if result.search == "payload" else
               "the payload's lower end with every link at its lower factor (the lightest plant of the set in every "
               "direction: the exact maximiser of T lambda_max(M_p^-1 G)), the upper end with every link at its "
               "upper factor, and the URDF's own arm at the lower end" if result.search.startswith("payload") else
               "the ellipsoid's points of least inertia along the top directions of M_p^-1 G (closed form), "
               "alternated with the top generalized eigenvector" if result.search == "ellipsoid" else
               "corners of the box lightest along the top directions of M_p^-1 G, alternated with the top "
               "generalized eigenvector" + (", around the arm's lightest plant of the URDF uncertainty, and its "
                                            "heaviest" if "URDF" in result.search else ""))
        lines.append(f"* searched: {result.search} ({how}); the hardest plants join the random ones at every eps "
                     "tried: clean means clean on them too, and an eps whose held loop at rate / margin is unstable on "
                     "one of them (T lambda_max >= the limit) is refused without simulation.")
        for name, key, val in (("eq. 6", "eps", result.eps_needed), ("eq. 7", "eps_i", result.eps_i_needed)):
            if val is not None:
                lines.append(f"* {name}: the held loop on the hardest plants is stable at {result.rate / result.margin:g} "
                             + (f"Hz from {key} = {val:.4g} (the search starts above it)" if np.isfinite(val) else
                                "Hz for no boundary layer: K and b M0 alone reach the limit there (a higher rate, "
                                "a smaller bandwidth, or a smaller URDF uncertainty)") + ".")
    lines += ["", "## The chosen gains (design.toml)", "", "| law | gains |", "|---|---|"]
    for law, table in g.items():
        text = "; ".join(f"{k} = {_vec(v)}" for k, v in table.items())
        lines.append(f"| {law} | {text} |")
    lines += ["", "## Bound, errors, torques", ""]
    fbl = result.baselines.get("fbl", {})
    if ch is not None:
        bound = predicted_bound(result)
        lines += [f"* predicted ultimate bound (Spong, continuous time, the controller's model's inertia {result.spectrum['m_min']:.3g}.."
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
        lines.append("* recommended robust law: none (neither eq. 6 nor eq. 7 was clean on every plant at both rates): "
                     f"{failure_line(result)}. design.toml says `verified = false`.")
        lines += ["", "## Not verified: what to try", ""] + [f"* {x}" for x in next_steps(result)]
    low = result.lowest_clean_rate()
    tried = ", ".join(f"{r['rate']:.4g} Hz {'clean' if r['clean'] else _verdicts(r)}" for r in result.low_rates)
    lines += [f"* lowest rate at which the design stayed clean: {_f(low, '.4g')} Hz"
              + (f" (below {result.rate / result.margin:g} Hz on the first four plants: {tried})" if tried else ""),
              "", "Figure: design.png (worst error and chattering against eps at the rate). Runs: runs.csv.", ""]
    return "\n".join(lines)


def _not_clean(result, law: str, w: dict) -> str:
    """What design.md adds to a law that is not clean over the whole set at the rate: what would make it so."""
    rc = result.baselines.get("robust-coeff") or {}
    clean = result.eq6_ok if law == "robust" else bool(rc.get("clean") and rc.get("clean_low", True))
    if clean:
        return ""
    text = f" **{law} is not clean over the whole set at {result.rate:g} Hz**"
    if w["T_lambda"] >= w["limit"]:
        return text + (f": its held loop on this plant needs about {result.rate * w['T_lambda'] / w['limit']:.3g} Hz "
                       f"with these gains, or a boundary layer about {w['T_lambda'] / w['limit']:.3g} x thicker.")
    return text + ": its loop on the hardest plant is stable, so the failing runs are not the held loop's: see " \
                  "'decided by' and 'Not verified: what to try'."


def _b_note(result) -> str:
    """Why b is below the fast form's (the held loop of K on the hardest plant), or nothing."""
    b = result.b_note
    if not b:
        return ""
    return (f" (b lowered from {b['b']:.4g}: on the hardest plant `{_short(b['plant'])}` max lambda_max(M_p^-1 K / b) = "
            f"{b['kappa']:.3g}, so K alone may use half the held loop's limit at {result.rate / result.margin:g} Hz "
            f"only up to b = {b['b_max']:.4g})")


def _urdf_line(result) -> str:
    """What design.md says of the URDF uncertainty (:mod:`rc3r.uncertainty.urdf`)."""
    from ..uncertainty.urdf import parse_spec

    spec = parse_spec(result.config.get("plant", {}).get("urdf_uncertainty"))
    if spec is None:
        return "none (the plants are the bounds' own; --urdf-uncertainty SPEC adds it)."
    text = result.urdf or f"spec '{spec}'"
    return (f"{text}; beyond the bounds (which trust the URDF): the random plants draw it, the search visits its "
            "lightest and heaviest plants (docs/design.md, 'URDF uncertainty'; --urdf-uncertainty off turns it off).")


def _short(spec: str) -> str:
    return spec if len(spec) <= 24 else spec[:20] + "..."


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
