"""rc3r.simulate.metrics: every metric of ``metrics.json`` against values computed by hand.

The run below is five rows, two joints, written out so each expected number can be checked
with pencil and paper (the arithmetic is in the comments). Tolerance 1e-12 relative: each
number is a handful of float operations on short decimals; a wrong definition (a sum for a
mean, another window, another grid) is off by 10 % or more.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from rc3r.simulate.metrics import CHATTERING_DEFINITION, run_metrics

REL = 1e-12

T = np.array([0.0, 0.5, 1.0, 1.5, 2.0])  # [s], t_end = 2 s
E = np.array([[0.5, 0.0],                # e = q - q_d [rad]; the error at t = 1.0 s (-0.4) is the
              [0.45, -0.1],              # largest of joint 1 in the last second, so a window of
              [-0.4, 0.1],               # t > T - 1 (0.2), T - 0.5 (0.2), t >= 0.5 (0.45) or the
              [0.1, -0.3],               # whole run (0.5) each gives another number than
              [0.2, 0.05]])              # t >= T - 1 (0.4)
U = np.array([[1.0, 0.0],                # u [N m]
              [3.0, 0.0],
              [-2.0, 5.0],
              [-2.0, 5.0],
              [0.0, 5.0]])


def fake_run(*, mode="continuous", tv_exact=None, controller=None, yt_r_norm=None, rate=None):
    """A stand-in for a SimResult with exactly the fields run_metrics reads."""
    q_des = np.full_like(E, 0.25)
    controller = controller or {"name": "robust", "theta": [1.0, 2.0], "rho": 3.0, "eps": 0.5,
                                "K": 100.0, "Lambda": 50.0}
    return SimResult(
        t=T, q=E + q_des, q_des=q_des, u=U, t_end=2.0, tv_exact=tv_exact, controller=controller,
        robot={"robot": "toy"}, loop=None, plant={"name": "nominal"}, mode=mode, engine="python", trajectory={},
        outcome="finished", message="", yt_r_norm=np.array([0.0, 0.1, 0.6, 0.3, 0.9]) if yt_r_norm is None else yt_r_norm,
        wall_time_s=0.25, rhs_evals=7, steps=3,
        options=SimpleNamespace(rate=rate, rtol=1e-6, atol=1e-8))


class SimResult(SimpleNamespace):
    @property
    def e(self):
        return self.q - self.q_des


def test_max_abs_error_is_the_largest_absolute_error_per_joint():
    """max_t |e_j|: joint 1 |0.5| at t = 0, joint 2 |-0.3| at t = 1.5."""
    assert run_metrics(fake_run())["max_abs_error"] == pytest.approx([0.5, 0.3], rel=REL)


def test_rms_error_is_the_root_of_the_mean_square():
    """joint 1: (0.25 + 0.2025 + 0.16 + 0.01 + 0.04) / 5 = 0.1325 -> sqrt 0.364...;
    joint 2: (0 + 0.01 + 0.01 + 0.09 + 0.0025) / 5 = 0.0225 -> 0.15."""
    got = run_metrics(fake_run())["rms_error"]
    assert got == pytest.approx([np.sqrt(0.1325), 0.15], rel=REL)


def test_final_error_bound_is_the_max_over_the_last_second_inclusive():
    """max over t >= t_end - 1 = 1.0 s (rows 1.0, 1.5, 2.0): joint 1 |-0.4|, joint 2 |-0.3|."""
    assert run_metrics(fake_run())["final_error_bound"] == pytest.approx([0.4, 0.3], rel=REL)


def test_max_abs_torque():
    assert run_metrics(fake_run())["max_abs_torque"] == pytest.approx([3.0, 5.0], rel=REL)


def test_chattering_continuous_is_total_variation_of_the_stored_grid_per_second():
    """joint 1: |3-1| + |-2-3| + 0 + |0+2| = 9 N m over 2 s -> 4.5 N m/s; joint 2: 5 -> 2.5."""
    m = run_metrics(fake_run())
    assert m["chattering"] == pytest.approx([4.5, 2.5], rel=REL)
    assert m["chattering_definition"] == CHATTERING_DEFINITION


def test_chattering_sampled_uses_every_controller_sample_not_the_stored_grid():
    """A sampled run reports the engine's total variation over every sample (tv_exact = [10, 4]
    N m over 2 s -> [5, 2] N m/s), not the decimated stored rows (which would give [4.5, 2.5])."""
    m = run_metrics(fake_run(mode="sampled", tv_exact=np.array([10.0, 4.0]), rate=1000.0))
    assert m["chattering"] == pytest.approx([5.0, 2.0], rel=REL)
    assert m["rate_hz"] == 1000.0 and m["tolerances"] is None


def test_boundary_layer_of_the_robust_law():
    """||Y^T r|| / eps after t = 0: [0.1, 0.6, 0.3, 0.9] / 0.5 = [0.2, 1.2, 0.6, 1.8]:
    median (0.6 + 1.2) / 2 = 0.9, max 1.8, outside (> 1) two rows of four."""
    bl = run_metrics(fake_run())["boundary_layer"]
    assert bl == pytest.approx({"median": 0.9, "max": 1.8, "outside": 0.5}, rel=REL)


def test_boundary_layer_edge_is_inside_and_one_row_is_enough():
    """||Y^T r|| == eps is on the layer's edge, inside (eq. 6 uses max(||xi||, eps)): [0.5, 0.25, 1.0] / 0.5
    = [1, 0.5, 2] -> outside 1/3 (one strictly above 1), median 1, max 2. A run with one row after
    t = 0 has its layer; a run with only t = 0 has none."""
    r = fake_run(yt_r_norm=np.array([0.0, 0.5, 0.25, 1.0, 0.0]))
    r.yt_r_norm = r.yt_r_norm[:4]
    bl = run_metrics(r)["boundary_layer"]
    assert bl == pytest.approx({"median": 1.0, "max": 2.0, "outside": 1 / 3}, rel=REL)
    two = fake_run(yt_r_norm=np.array([0.0, 0.75]))
    assert run_metrics(two)["boundary_layer"] == pytest.approx({"median": 1.5, "max": 1.5, "outside": 1.0}, rel=REL)
    assert run_metrics(fake_run(yt_r_norm=np.array([0.0])))["boundary_layer"] is None


def test_short_runs_and_one_joint():
    """A 2-row run of 0.5 s: chattering |u(0.5) - u(0)| / 0.5 = 4 N m/s on joint 1 (not divided by 1 s
    and not dropped); its last-second window is the whole run. A one-joint robot gets its total
    variation too: |3-1| + |-2-3| + 0 + |0+2| = 9 N m over 2 s."""
    r = fake_run()
    r.t, r.q, r.q_des, r.u, r.t_end = T[:2], r.q[:2], r.q_des[:2], U[:2], 0.5
    m = run_metrics(r)
    assert m["chattering"] == pytest.approx([4.0, 0.0], rel=REL)
    assert m["final_error_bound"] == pytest.approx([0.5, 0.1], rel=REL)
    one = fake_run()
    one.q, one.q_des, one.u = one.q[:, :1], one.q_des[:, :1], U[:, :1]
    m1 = run_metrics(one)
    assert m1["chattering"] == pytest.approx([4.5], rel=REL) and m1["max_abs_error"] == pytest.approx([0.5], rel=REL)


def test_boundary_layer_absent_without_a_scalar_eps():
    """FBL (no eps) and eq. 7 (a vector eps_i) have no single layer to report."""
    assert run_metrics(fake_run(controller={"name": "fbl", "theta": [1.0]}))["boundary_layer"] is None
    eq7 = {"name": "robust-coeff", "theta": [1.0, 2.0], "rho_i": [1.0, 2.0], "eps_i": [0.1, 0.2]}
    m = run_metrics(fake_run(controller=eq7))
    assert m["boundary_layer"] is None and m["rho"] == [1.0, 2.0] and m["eps"] == [0.1, 0.2]


def test_descriptive_fields_are_copied_from_the_run():
    m = run_metrics(fake_run(), seed=42)
    assert m["controller"] == "robust" and m["robot"] == "toy" and m["seed"] == 42
    assert m["theta_model"] == [1.0, 2.0] and m["rho"] == 3.0 and m["eps"] == 0.5
    assert m["gains"] == {"K": 100.0, "Lambda": 50.0}
    assert m["t_end"] == 2.0 and m["tolerances"] == {"rtol": 1e-6, "atol": 1e-8, "method": "scipy Radau"}
    assert (m["rhs_evals"], m["steps"], m["wall_time_s"]) == (7, 3, 0.25)


def test_a_run_stopped_at_t0_has_nan_errors_not_a_crash():
    """A run that diverged before its first stored row has no error to report: NaN, not 0."""
    r = fake_run()
    for name in ("t", "yt_r_norm"):
        setattr(r, name, np.zeros(0))
    r.q = r.q_des = np.zeros((0, 2))
    r.u = np.zeros((0, 2))
    m = run_metrics(r)
    for key in ("max_abs_error", "rms_error", "final_error_bound", "max_abs_torque"):
        assert np.isnan(m[key]).all() and len(m[key]) == 2, key
    assert m["chattering"] == [0.0, 0.0] and m["boundary_layer"] is None


def test_a_sampled_run_stopped_at_t0_has_zero_chattering_not_nan():
    """A sampled run that diverged at its first sample (t_end = 0, one row, tv_exact = 0): 0 N m/s."""
    r = fake_run(mode="sampled", tv_exact=np.zeros(2), rate=1000.0)
    r.t, r.q, r.q_des, r.u, r.t_end = T[:1], r.q[:1], r.q_des[:1], U[:1], 0.0
    assert run_metrics(r)["chattering"] == [0.0, 0.0]
