"""rc3r.animation and ``rc3r run --animate``: the GIF is written (atomically, the expected number of
frames), what it draws is Pinocchio's forward kinematics (and the 3R's DH formula), the UR5 animates
too, and bad requests get one line and exit 2."""
from __future__ import annotations

import json
from types import SimpleNamespace

import matplotlib
import numpy as np
import pinocchio as pin
import pytest
from PIL import Image

import rc3r
from rc3r import animation
from rc3r.animation import animation_figure, arm_frames, check_animatable, end_effector_frame, frame_count
from rc3r.cli import main
from rc3r.errors import ConfigError

#: Positions [m] from Pinocchio's compositions of 4-8 rigid transforms of O(1) m against the same
#: computation or the DH formula: rounding ~1e-15, so 1e-12.
POS_TOL = 1e-12


def _result(t, q, q_des):
    """The fields of a SimResult that the animation reads."""
    return SimpleNamespace(t=np.asarray(t, float), q=np.asarray(q, float), q_des=np.asarray(q_des, float))


def _fk_tool(model, q, frame_name):
    """Independent FK: framesForwardKinematics (all frames) rather than the module's
    forwardKinematics + updateFramePlacement of one frame."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, float))
    return np.array(data.oMf[model.getFrameId(frame_name)].translation)


def _dh_tool(q, l=(1.0, 1.0, 1.0)):
    """End of link 3 of the paper's DH table (docs/conventions.md), by hand."""
    q1, q2, q3 = q
    reach = l[1] * np.cos(q2) + l[2] * np.cos(q2 + q3)
    return np.array([np.cos(q1) * reach, np.sin(q1) * reach, l[0] + l[1] * np.sin(q2) + l[2] * np.sin(q2 + q3)])


def test_frame_count_is_25_per_second_at_most_250():
    assert frame_count(10.0) == 250 and frame_count(2.0) == 50
    assert frame_count(100.0) == 250 and frame_count(0.001) == 2


def test_the_3r_end_effector_is_the_tool_and_the_drawn_arm_is_its_forward_kinematics():
    """At two instants the drawn arm (solid) ends at the tool frame placed by framesForwardKinematics and
    by the DH formula, the ghost at those of q_d; the drawn trail ends at the drawn end effector."""
    arm = rc3r.load_robot()
    model = arm.model
    assert model.frames[end_effector_frame(model)].name == "tool"
    t = np.linspace(0.0, 2.0, 2001)
    q = np.column_stack([np.sin(t), 5 * np.cos(t), np.sin(t)])
    q_des = q + 0.1
    frames = arm_frames(_result(t, q, q_des), arm)
    assert frames.t.size == 50 and frames.t[0] == 0.0 and frames.t[-1] == 2.0
    fig, update = animation_figure(frames)
    art = fig.rc3r_artists
    for i in (7, 42):
        update(i)
        row = frames.rows[i]
        actual = np.column_stack(art["actual"].get_data_3d())
        ghost = np.column_stack(art["desired"].get_data_3d())
        np.testing.assert_allclose(actual[-1], _fk_tool(model, q[row], "tool"), atol=POS_TOL)
        np.testing.assert_allclose(actual[-1], _dh_tool(q[row]), atol=POS_TOL)
        np.testing.assert_allclose(ghost[-1], _dh_tool(q_des[row]), atol=POS_TOL)
        np.testing.assert_allclose(actual[2], (0, 0, 1), atol=POS_TOL)  # joint 2 at height l1
        trail = np.column_stack(art["ee_path"].get_data_3d())
        np.testing.assert_array_equal(trail[-1], actual[-1])
        assert abs(t[row] - 2.0 * i / 49) <= 0.5e-3  # nearest stored row of the evenly spaced instant


def test_the_ur5_animates_from_its_own_model(ur5):
    """A generic robot: the end effector is the UR5's farthest frame on its last joint, and the drawn arm
    is its FK (joint origins and that frame) at two instants."""
    model = ur5.model
    name = model.frames[end_effector_frame(model)].name
    t = np.linspace(0.0, 1.0, 101)
    q = 0.3 * np.sin(np.outer(t, np.arange(1, 7)))
    frames = arm_frames(_result(t, q, q), ur5)
    fig, update = animation_figure(frames)
    for i in (3, 20):
        update(i)
        drawn = np.column_stack(fig.rc3r_artists["actual"].get_data_3d())
        row = frames.rows[i]
        np.testing.assert_allclose(drawn[-1], _fk_tool(model, q[row], name), atol=POS_TOL)
        data = model.createData()
        pin.forwardKinematics(model, data, q[row])
        np.testing.assert_allclose(drawn[1:-1], [data.oMi[j].translation for j in range(1, model.njoints)],
                                   atol=POS_TOL)
    assert drawn.shape == (model.njoints + 1, 3)


@pytest.mark.slow
def test_rc3r_run_animate_writes_a_gif_of_25_frames_per_second(tmp_path, capsys):
    """2 s of the robust law: animation.gif has 50 frames of 40 ms (PIL counts them), metrics.json says
    so, the announce line names the animation, no temporary file is left, the backend is untouched."""
    backend = matplotlib.get_backend()
    out = tmp_path / "run"
    assert main(["run", "--perturbed", "--duration", "2", "--animate", "--out", str(out)]) == 0
    with Image.open(out / "animation.gif") as im:
        assert im.n_frames == 50 and im.info["duration"] == 40
    m = json.loads((out / "metrics.json").read_text())
    assert m["animation"] == {"file": "animation.gif", "frames": 50, "fps": 25.0, "end_effector_frame": "tool",
                              "t": [0.0, 2.0]}
    err = capsys.readouterr().err
    assert "then animation.gif (50 frames)" in err and "writing the animation" in err
    assert sorted(p.name for p in out.iterdir()) == ["animation.gif", "metrics.json", "run.png", "timeseries.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    assert matplotlib.get_backend() == backend


@pytest.mark.slow
def test_rc3r_run_animate_a_generic_robot(tmp_path):
    """The UR5 (python engine) animates as well: 0.4 s, 10 frames."""
    out = tmp_path / "ur5"
    assert main(["run", "--robot", "ur5", "--controller", "fbl", "--duration", "0.4", "--animate",
                 "--out", str(out)]) == 0
    with Image.open(out / "animation.gif") as im:
        assert im.n_frames == 10


def test_interrupted_animation_keeps_the_run_without_it(tmp_path, monkeypatch, capsys):
    """Ctrl-C at the 10th frame: exit 130, the run's files are in --out, no animation and no temporary
    file (rc3r.io.atomic_path removed the one the writer had opened)."""
    real = animation.animation_figure

    def figure(*args, **kwargs):
        fig, update = real(*args, **kwargs)

        def interrupted(i):
            if i == 10:
                raise KeyboardInterrupt
            update(i)

        return fig, interrupted

    monkeypatch.setattr(animation, "animation_figure", figure)
    out = tmp_path / "run"
    assert main(["run", "--perturbed", "--duration", "0.8", "--animate", "--out", str(out)]) == 130
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "run.png", "timeseries.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    assert "animation" not in json.loads((out / "metrics.json").read_text())
    assert "interrupted while writing the animation" in capsys.readouterr().err


def test_mp4_without_ffmpeg_is_refused_before_simulating(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(animation.shutil, "which", lambda name: None)
    out = tmp_path / "run"
    assert main(["run", "--animate", "mp4", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "rc3r: error: --animate mp4 needs ffmpeg on the PATH (not found); --animate alone writes a GIF"
    assert not out.exists()


def test_unknown_format_is_one_line_exit_2(tmp_path, capsys):
    assert main(["run", "--animate", "avi", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rc3r: error: argument --animate: invalid choice: 'avi'")


def test_a_robot_without_a_pinocchio_model_is_refused():
    with pytest.raises(ConfigError, match="has no Pinocchio model"):
        check_animatable(SimpleNamespace(model=None, label="mine", n=2))
