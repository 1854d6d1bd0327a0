"""rc3r.plotting.estimate_figure: the adaptive law's estimate against the plant's theta, and
``rc3r run --controller adaptive`` writing it (estimate.png, metrics.json parameter_estimate)."""
from __future__ import annotations

import json
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from rc3r.cli import main
from rc3r.plotting import estimate_errors, estimate_figure
from rc3r.runspec import build_run, execute


def _fake(t, z):
    """The fields of a SimResult that estimate_figure reads."""
    return SimpleNamespace(t=np.asarray(t, float), z=np.asarray(z, float), mode="continuous",
                           options=SimpleNamespace(rate=None))


def test_estimate_figure_plots_the_norms_of_a_hand_checkable_estimate():
    """theta = (3, 4); theta_hat = (0,0), (3,4), (6,8), (3,0) at t = 0..3: ||theta_hat - theta|| = 5, 0, 5, 4
    and ||theta_hat - theta_0|| = 0, 5, 10, 3 by hand (3-4-5 triangles: exact in floating point);
    relative errors per coefficient (1, 1) at t = 0 and (0, 1) at the end."""
    res = _fake([0, 1, 2, 3], [[0, 0], [3, 4], [6, 8], [3, 0]])
    fig = estimate_figure(res, [3.0, 4.0], caption="c")
    top, bottom = fig.get_axes()
    err, moved = top.get_lines()[:2]
    np.testing.assert_array_equal(err.get_xdata(), [0, 1, 2, 3])
    np.testing.assert_array_equal(err.get_ydata(), [5, 0, 5, 4])
    np.testing.assert_array_equal(moved.get_ydata(), [0, 5, 10, 3])
    heights = [p.get_height() for p in bottom.patches]
    np.testing.assert_array_equal(heights[:2], [1, 1])          # t = 0
    np.testing.assert_array_equal(heights[2:], [1e-16, 1])      # the end: 0 is drawn at the axis floor
    assert bottom.get_yscale() == "log"
    assert "[" in top.get_ylabel() and top.get_xlabel() == "t [s]"


def test_relative_error_of_a_zero_coefficient_is_not_drawn():
    est = estimate_errors(_fake([0, 1], [[1, 1], [2, 2]]), [0.0, 2.0])
    assert np.isnan(est["rel0"][0]) and est["rel0"][1] == 0.5 and est["rel_end"][1] == 0.0


def test_a_law_without_an_estimate_is_refused():
    with pytest.raises(ValueError, match="only the adaptive law"):
        estimate_errors(_fake([0, 1], np.zeros((2, 0))), np.ones(15))


def test_estimate_of_a_real_adaptive_run_and_its_legends_off_the_data():
    """On the paper's perturbed plant the estimate starts at Table 3's theta_0, so the first point is
    ||theta_0 - theta(Table 1)|| = the paper's rho 186.8129 (printed to 4 decimals: 5e-5), and the line
    never rises above it (Lyapunov, below); the plotted
    line equals numpy's norm of res.z - plant.theta computed here (same operation: 1e-12 relative). The
    legends' boxes do not overlap their axes, and the backend is not switched."""
    backend = matplotlib.get_backend()
    spec = build_run(controller="adaptive", perturbed=True, duration=1.0)
    res, _ = execute(spec)
    fig = estimate_figure(res, spec.true_rigid.theta)
    top, bottom = fig.get_axes()
    y = top.get_lines()[0].get_ydata()
    expected = np.sqrt(((res.z - np.asarray(spec.true_rigid.theta)) ** 2).sum(axis=1))
    np.testing.assert_allclose(y, expected, rtol=1e-12)
    assert abs(y[0] - 186.8129) < 5e-5 and y[-1] < y[0]
    # Slotine-Li: V = r^T M r / 2 + ||theta_hat - theta||^2 / (2 Gamma) never increases (scalar Gamma = 10)
    # and r(0) = 0, so the distance never exceeds its start; up to the integrator's rtol 1e-6 (the first
    # stored step is 1.2e-4 = 6.7e-7 relative below it, measured).
    assert np.all(y[1:] <= y[0] * (1 + 1e-6))
    FigureCanvasAgg(fig).draw()
    for ax in (top, bottom):
        box, leg = ax.get_window_extent(), ax.get_legend().get_window_extent()
        assert leg.x0 >= box.x1 or leg.y1 <= box.y0 or leg.x1 <= box.x0 or leg.y0 >= box.y1, "legend on the data"
    assert matplotlib.get_backend() == backend


def test_rc3r_run_adaptive_writes_estimate_png_and_the_numbers(tmp_path, capsys):
    """`rc3r run --controller adaptive --perturbed` writes estimate.png and metrics.json parameter_estimate
    (initial error = the paper's rho, as above); the robust law's run has neither."""
    out = tmp_path / "adaptive"
    assert main(["run", "--controller", "adaptive", "--perturbed", "--duration", "1", "--out", str(out)]) == 0
    assert (out / "estimate.png").stat().st_size > 10_000
    est = json.loads((out / "metrics.json").read_text())["parameter_estimate"]
    assert abs(est["error_initial"] - 186.8129) < 5e-5
    theta_hat, theta = np.array(est["theta_hat_final"]), np.array(est["theta_plant"])
    assert est["error_final"] == pytest.approx(np.linalg.norm(theta_hat - theta), rel=1e-12)
    other = tmp_path / "robust"
    assert main(["run", "--perturbed", "--duration", "0.2", "--out", str(other)]) == 0
    assert not (other / "estimate.png").exists()
    assert "parameter_estimate" not in json.loads((other / "metrics.json").read_text())


# ---- the paper's theory figures: captions and legends (rc3r paper) ------------------------------


def _fake_run(eps=None, n=3, seed=0):
    """The SimResult fields comparison_figure and boundary_layer_figure read; seeded data."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, 21)
    return SimpleNamespace(t=t, q=rng.normal(size=(t.size, n)), e=rng.normal(size=(t.size, n)) * 1e-3,
                           u=rng.normal(size=(t.size, n)), yt_r_norm=np.abs(rng.normal(size=t.size)),
                           controller={"eps": eps} if eps is not None else {}, mode="continuous",
                           options=SimpleNamespace(rate=None))


def _paper_figures(monkeypatch, tmp_path):
    """The figures `rc3r paper` writes from its theory runs, by file name (atomic_savefig captured)."""
    import rc3r.cli.run as cli_run

    saved = {}
    monkeypatch.setattr(cli_run, "atomic_savefig", lambda fig, path, **kw: saved.setdefault(path.name, fig))
    res = {"fbl-ideal": _fake_run(), "robust-ideal": _fake_run(0.5, seed=1), "fbl-perturbed": _fake_run(seed=2),
           "robust-perturbed": _fake_run(0.5, seed=3), "robust-perturbed-eps0.05": _fake_run(0.05, seed=4)}
    cli_run._theory_figures(res, tmp_path, "continuous", "continuous")
    return saved


def test_each_comparison_caption_speaks_of_its_own_case_only(monkeypatch, tmp_path):
    """compare-perturbed's caption says nothing of the ideal case and compare-ideal's nothing of the
    perturbed one (each figure holds only its case's runs); both captions exist (read from fig.texts)."""
    figs = _paper_figures(monkeypatch, tmp_path)
    captions = {name: " ".join(t.get_text() for t in figs[name].texts)
                for name in ("compare-ideal-continuous.png", "compare-perturbed-continuous.png")}
    assert "perturbed" in captions["compare-perturbed-continuous.png"].lower()
    assert "ideal" not in captions["compare-perturbed-continuous.png"].lower()
    assert "ideal" in captions["compare-ideal-continuous.png"].lower()
    assert "perturbed" not in captions["compare-ideal-continuous.png"].lower()


def test_boundary_layer_legend_names_each_run_once(monkeypatch, tmp_path):
    """The boundary-layer figure's legend: one entry per run (||Y^T r||) and one for the dashed eps lines;
    no label repeats the eps value (the old 'eps = 0.5 (boundary layer), eps 0.5'); labels unique. The
    dashed lines sit at the runs' eps (0.5 and 0.05, the runs' controller values)."""
    fig = _paper_figures(monkeypatch, tmp_path)["boundary-layer-continuous.png"]
    labels = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert len(labels) == len(set(labels)) == 3, labels
    for eps in ("0.5", "0.05"):
        assert sum(f"eps {eps}" in lb or f"eps = {eps}" in lb for lb in labels) == 1, labels
    assert sum("dashed" in lb for lb in labels) == 1
    ax = fig.get_axes()[0]
    dashed = sorted(ln.get_ydata()[0] for ln in ax.get_lines() if ln.get_linestyle() == "--")
    assert dashed == [0.05, 0.5]


def test_comparison_legend_labels_are_distinct(monkeypatch, tmp_path):
    """compare-perturbed: FBL, robust eps 0.5 and robust eps 0.05, each once, in the legend."""
    fig = _paper_figures(monkeypatch, tmp_path)["compare-perturbed-continuous.png"]
    labels = [t.get_text() for ax in fig.get_axes() if ax.get_legend() for t in ax.get_legend().get_texts()]
    assert len(labels) == len(set(labels)) == 3, labels
