"""An animation of a run: the arm tracking its trajectory, in 3D, from Pinocchio's forward kinematics.

:func:`arm_frames` computes what is drawn, :func:`animation_figure` draws one frame of it, and
:func:`write_animation` writes them all (``rc3r run --animate``). The arm is the polyline through
the base origin, every joint origin and the end-effector frame (:func:`end_effector_frame`),
placed by ``pinocchio.forwardKinematics`` / ``updateFramePlacement`` on the robot's own model
(:attr:`rc3r.robots.base.Robot.model`; every robot of the contract has one, and the plant has the
nominal robot's kinematics). Drawn per frame: the actual arm ``q(t)`` (solid), the desired
configuration ``q_d(t)`` (ghosted, dashed), the end-effector path so far (red) and the whole
desired end-effector path (dotted).

Cost: the stored rows (1 kHz) are subsampled to ``fps`` frames per simulated second (default
25), at most ``max_frames`` (default 250: a 10 s run gives 250 frames). A GIF is written with
matplotlib's ``PillowWriter``; an MP4 only with ``FFMpegWriter`` when ``ffmpeg`` is on the PATH.
The file goes through :func:`rc3r.io.atomic_path` (a temporary file renamed into place), and
the figure is a :class:`matplotlib.figure.Figure`: the user's backend is never switched.
"""
from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ConfigError
from .io import atomic_path

__all__ = ["ArmFrames", "FORMATS", "end_effector_frame", "arm_points", "arm_frames", "animation_figure",
           "write_animation", "check_animatable", "frame_count"]

#: Animation formats: suffix -> what writes it.
FORMATS = {"gif": "matplotlib PillowWriter (pillow)", "mp4": "matplotlib FFMpegWriter (needs ffmpeg on the PATH)"}

#: Default frames per second of simulated time, and most frames of one animation.
FPS, MAX_FRAMES = 25.0, 250

#: Most points of the drawn end-effector paths (the stored rows are strided down to this).
PATH_POINTS = 2000


def check_animatable(robot, fmt: str = "gif") -> None:
    """Refuse (one-line :class:`ConfigError`) a robot without a Pinocchio model of its n joints, an
    unknown format, or MP4 without ffmpeg; called before anything is simulated."""
    if fmt not in FORMATS:
        raise ConfigError(f"--animate {fmt}: unknown format (choose {' or '.join(FORMATS)})")
    if fmt == "mp4" and shutil.which("ffmpeg") is None:
        raise ConfigError("--animate mp4 needs ffmpeg on the PATH (not found); --animate alone writes a GIF")
    import pinocchio as pin

    model = robot.model
    if not isinstance(model, pin.Model):
        raise ConfigError(f"cannot animate robot '{robot.label}': it has no Pinocchio model "
                          "(the robot contract's `model`)")
    if model.nq != robot.n:
        raise ConfigError(f"cannot animate robot '{robot.label}': its Pinocchio model has nq = {model.nq}, "
                          f"the run has n = {robot.n} joint angles")


def end_effector_frame(model) -> int:
    """Id of the frame drawn as the end effector: of the frames on the last joint, the farthest
    from the joint's origin (a tool frame: ``tool`` of the 3R, ``tool0``/``ee_link`` of the UR5);
    the last joint's own frame if none is farther."""
    import pinocchio as pin

    last = model.njoints - 1  # the joint's own frame: a link may carry the joint's name (the SO-100's gripper)
    best, key = model.getFrameId(model.names[last], pin.FrameType.JOINT), (0.0, False)
    kinds = (pin.FrameType.BODY, pin.FrameType.FIXED_JOINT, pin.FrameType.OP_FRAME)
    for fid, f in enumerate(model.frames):
        if f.parentJoint == last and f.type in kinds:
            k = (round(float(np.linalg.norm(f.placement.translation)), 12), f.type == pin.FrameType.BODY)
            if k > key:  # farther; at the same place a body frame ('tool') before its joint ('tool_joint')
                best, key = fid, k
    return best


def arm_points(model, data, q, frame: int) -> np.ndarray:
    """(njoints + 1, 3) [m]: the base origin, each joint's origin and the end-effector frame's
    origin in the world frame at ``q`` (``forwardKinematics`` + ``updateFramePlacement``)."""
    import pinocchio as pin

    pin.forwardKinematics(model, data, np.asarray(q, dtype=float))
    pin.updateFramePlacement(model, data, frame)
    pts = [data.oMi[j].translation for j in range(model.njoints)] + [data.oMf[frame].translation]
    return np.array(pts, dtype=float)


def frame_count(duration: float, fps: float = FPS, max_frames: int = MAX_FRAMES) -> int:
    """Frames of an animation of ``duration`` simulated seconds: ``round(duration fps)``, at least 2,
    at most ``max_frames``."""
    return int(min(max_frames, max(2, round(float(duration) * fps))))


@dataclass(frozen=True)
class ArmFrames:
    """What an animation draws (positions [m] in the robot's world frame).

    ``t`` (F,) [s] and ``rows`` (F,) the stored rows shown; ``actual``, ``desired`` (F, k, 3) the arm's
    polyline (:func:`arm_points`) at ``q`` and ``q_des``; ``ee_t`` (P,) [s], ``ee_actual``, ``ee_desired``
    (P, 3) the end-effector paths on (at most :data:`PATH_POINTS`) stored rows; ``frame`` the
    end-effector frame's name; ``fps`` the playback rate [frames/s]; ``error`` (F,) ``max_j |e_j|`` [rad].
    """

    t: np.ndarray
    rows: np.ndarray
    actual: np.ndarray
    desired: np.ndarray
    ee_t: np.ndarray
    ee_actual: np.ndarray
    ee_desired: np.ndarray
    error: np.ndarray
    frame: str
    fps: float
    robot: str


def arm_frames(res, robot, fps: float = FPS, max_frames: int = MAX_FRAMES) -> ArmFrames:
    """Forward kinematics of the rows of ``res`` an animation shows (:func:`frame_count` of them, evenly
    spaced in time from the first to the last finite row, each the nearest stored row)."""
    model = robot.model
    data = model.createData()
    fid = end_effector_frame(model)
    finite = np.flatnonzero(np.all(np.isfinite(res.q), axis=1) & np.all(np.isfinite(res.q_des), axis=1))
    if finite.size == 0:
        raise ConfigError("nothing to animate: the run has no finite state")
    t = np.asarray(res.t, dtype=float)[finite]
    want = np.linspace(t[0], t[-1], frame_count(t[-1] - t[0], fps, max_frames))
    k = np.clip(np.searchsorted(t, want), 0, t.size - 1)
    k = np.where((k > 0) & (np.abs(t[np.maximum(k - 1, 0)] - want) <= np.abs(t[k] - want)), k - 1, k)
    rows = finite[np.unique(k)]
    path = finite[:: max(1, -(-finite.size // PATH_POINTS))]
    if path[-1] != finite[-1]:
        path = np.append(path, finite[-1])

    def fk(Q):
        return np.array([arm_points(model, data, q, fid) for q in Q])

    return ArmFrames(
        t=np.asarray(res.t, dtype=float)[rows], rows=rows, actual=fk(res.q[rows]), desired=fk(res.q_des[rows]),
        ee_t=np.asarray(res.t, dtype=float)[path], ee_actual=fk(res.q[path])[:, -1],
        ee_desired=fk(res.q_des[path])[:, -1], error=np.abs(res.q[rows] - res.q_des[rows]).max(axis=1),
        frame=str(model.frames[fid].name), fps=float(fps), robot=_robot_name(robot))


def _robot_name(robot) -> str:
    """``ur5 (ur5_robot.urdf)``, ``rr3 (nominal)``: the registry name and the label (a path shortened)."""
    name = robot.describe().get("robot", "robot")
    label = str(robot.label)
    label = Path(label).name if "/" in label else label
    return f"{name} ({label})" if label and label != name else str(name)


def animation_figure(frames: ArmFrames, title: str = ""):
    """A :class:`~matplotlib.figure.Figure` and ``update(i)`` drawing frame ``i`` of ``frames``.

    Artists (for tests): ``fig.rc3r_artists`` = dict of the 3D lines ``actual``, ``desired``,
    ``ee_path`` (actual end-effector path up to frame i), ``ee_desired`` (the whole desired path),
    and the ``clock`` text.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.2, 5.6))
    ax = fig.add_axes((0.0, 0.1, 0.68, 0.8), projection="3d")
    pts = np.concatenate([frames.actual.reshape(-1, 3), frames.desired.reshape(-1, 3), frames.ee_actual,
                          frames.ee_desired])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 1e-3) * 1.05
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))  # equal ranges and aspect: true proportions
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.view_init(elev=22, azim=-60)
    (ee_desired,) = ax.plot(*frames.ee_desired.T, ls=":", lw=1.0, color="0.45",
                            label="desired end-effector path")
    (desired,) = ax.plot([], [], [], ls="--", lw=3.0, color="0.55", alpha=0.45, marker="o", ms=4,
                         label="desired configuration q_d(t) (ghost)")
    (ee_path,) = ax.plot([], [], [], lw=1.4, color="C3", label=f"end-effector path ('{frames.frame}')")
    (actual,) = ax.plot([], [], [], lw=4.0, color="C0", marker="o", ms=5, mfc="k", mec="k",
                        label="arm q(t) (joint origins, end effector)")
    fig.legend(handles=[actual, desired, ee_path, ee_desired], loc="upper left", bbox_to_anchor=(0.66, 0.86),
               fontsize=7, frameon=False)  # beside the 3D axes, off the data
    clock = fig.text(0.68, 0.3, "", fontsize=9, family="monospace", va="top")
    fig.suptitle(f"{title + ': ' if title else ''}{frames.robot} tracking its trajectory", fontsize=10)
    fig.text(0.01, 0.015, "Pinocchio forward kinematics of q(t) (solid) and q_d(t) (ghost); playback "
             f"{frames.fps:g} frames/s, one frame every {np.diff(frames.t).mean() if frames.t.size > 1 else 0:.3g} "
             "s of simulated time.", fontsize=7, ha="left", va="bottom")
    fig.rc3r_artists = {"actual": actual, "desired": desired, "ee_path": ee_path, "ee_desired": ee_desired,
                        "clock": clock}

    def update(i: int) -> None:
        actual.set_data_3d(*frames.actual[i].T)
        desired.set_data_3d(*frames.desired[i].T)
        upto = frames.ee_t <= frames.t[i] + 1e-12
        trail = np.vstack([frames.ee_actual[upto], frames.actual[i, -1]])  # ends at the drawn end effector
        ee_path.set_data_3d(*trail.T)
        clock.set_text(f"t = {frames.t[i]:6.2f} s\nmax_j |e_j| = {frames.error[i]:.2e} rad")

    update(0)
    return fig, update


def _blit_writer(fig, dynamic):
    """A ``PillowWriter`` whose frames are the static background (drawn once) plus the ``dynamic``
    artists: the axes, ticks, legend and captions are not redrawn for every frame (4-5x faster)."""
    from matplotlib.animation import PillowWriter
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    canvas = FigureCanvasAgg(fig)  # this figure's canvas only; the user's backend is untouched
    for a in dynamic:
        a.set_animated(True)  # left out of the full draw
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)

    def grab() -> Image.Image:
        canvas.restore_region(background)
        for a in dynamic:
            fig.draw_artist(a)
        return Image.frombuffer("RGBA", canvas.get_width_height(), bytes(canvas.buffer_rgba()), "raw",
                                "RGBA", 0, 1).convert("RGB")

    class BlitPillowWriter(PillowWriter):
        """Frames mapped onto one palette (Pillow would compute one per frame by median cut:
        35 ms a frame, 3/4 of the whole cost); ``palette_from`` is an image with every colour."""

        palette = None

        def grab_frame(self, **savefig_kwargs):
            im = grab()
            if self.palette is None:
                self.palette = im.quantize(colors=128, method=Image.Quantize.MEDIANCUT)
            self._frames.append(im.quantize(palette=self.palette, dither=Image.Dither.NONE))

        def set_palette(self) -> None:
            """Take the palette from the frame drawn now (call it on a frame that shows every colour)."""
            self.palette = grab().quantize(colors=128, method=Image.Quantize.MEDIANCUT)

    return BlitPillowWriter


def write_animation(res, robot, path, fps: float = FPS, max_frames: int = MAX_FRAMES, title: str = "",
                    dpi: int = 80) -> ArmFrames:
    """Write the animation of ``res`` on ``robot`` to ``path`` (``.gif``, or ``.mp4`` with ffmpeg),
    atomically; return what was drawn (:class:`ArmFrames`)."""
    from matplotlib.animation import FFMpegWriter

    path = Path(path)
    fmt = path.suffix.lower().lstrip(".")
    check_animatable(robot, fmt)
    frames = arm_frames(res, robot, fps, max_frames)
    fig, update = animation_figure(frames, title)
    fig.set_dpi(dpi)
    if fmt == "gif":
        art = fig.rc3r_artists
        writer = _blit_writer(fig, [art[k] for k in ("ee_path", "actual", "desired", "clock")])(fps=fps)  # ghost on top
    else:
        writer = FFMpegWriter(fps=fps)  # full redraw per frame (matplotlib's own path)
    with atomic_path(path) as tmp:
        with writer.saving(fig, str(tmp), dpi=dpi):
            if fmt == "gif":
                update(frames.t.size - 1)  # the last frame: the whole path drawn, every colour present
                writer.set_palette()
            for i in range(frames.t.size):
                update(i)
                writer.grab_frame()
    return frames
