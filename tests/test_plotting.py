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
from rc3r.study import build_run, execute


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
    fig = estimate_figure(res, spec.plant.theta)
    top, bottom = fig.get_axes()
    y = top.get_lines()[0].get_ydata()
    expected = np.sqrt(((res.z - np.asarray(spec.plant.theta)) ** 2).sum(axis=1))
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
