"""URDF of the 3R arm: written from :class:`~rc3r.params.ArmParams`, read back into them.

Writing (:func:`make_urdf`): URDF link frame *i* is DH frame *i-1* turned by ``q_i``
about z; DH frame *i* is reached by ``A_i = Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)
= (R_i, p_i)`` (:func:`dh_fixed`). Joint *i+1* has ``<origin>`` = ``A_i`` in link *i*,
a fixed ``tool_joint`` at ``A_3`` carries ``l3``, and the ``<inertial>`` of link *i*
has ``xyz = p_i + R_i r_ci``, ``rpy = rpy(R_i)``: inertia entries of DH frame *i*.
Each link also has two ``<visual>`` cylinders for viewers (Pinocchio, yourdfpy), a housing
and a shaft (:data:`VISUAL_RADIUS`); they do not enter the dynamics.

Reading (:func:`load_arm`) accepts any URDF **kinematically equivalent** to the DH
table, whatever its joint origins, link frames, ``<axis>`` vectors and fixed links.
From the joint axes in the base frame at ``q = 0`` (:func:`dh_structure`) it
requires: joint 1 about base ``+z`` (gravity ``-z``); joint 2 perpendicular to it,
meeting it at height ``l1 > 0`` above the base origin (``alpha1 = pi/2, a1 = 0``);
joint 3 parallel to joint 2, ``l2 > 0`` away (``alpha2 = 0, a2 = l2``). A horizontal
offset of axis 1 is accepted (DH frame 0 is the base frame moved onto it; under
uniform gravity no torque depends on it). For parallel axes ``d2``, ``d3`` are
conventions: frame 2 is the foot of the common normal through frame 1, frame 3 in
that plane. The Pinocchio model is the plant the closed forms are checked against,
so its joint variables must be the paper's: **axis sign flips and zero offsets are
refused, not absorbed**, naming them. At ``q = 0`` joint 1 must turn about ``+z``,
joint 2's axis be ``(0, -1, 0)`` (else a joint 1 zero offset or a flipped joint 2),
the common normal from joint 2 to joint 3 point along base ``+x`` (else a joint 2
zero offset), joint 3 turn like joint 2. Only a tool frame fixes q3's zero.

**l3** (DH ``a3``) comes from a fixed frame after joint 3: the fixed joint named
``tool_joint`` if any (it must then *be* DH frame 3: on DH x3, ``d3 = 0``,
unrotated, else the file is refused); else the farthest fixed frame on the DH x3
axis; else ``l3 = 1 m`` (:data:`L3_DEFAULT`). The choice is immaterial: theta (so
M, S, g, every result) sees ``l3`` only through ``X3 = l3 + r_cx3``, and ``r_cx3``
is measured from the chosen frame 3, so ``X3`` (the CoM's distance from joint 3's
axis along x3) is the same for every ``l3``.

Inertias (Pinocchio's ``model.inertias`` in joint frames, fixed children lumped in)
are moved into the reconstructed DH frames (:func:`params_from_model`), never read
in the URDF's link frames. ``continuous`` joints are loaded as ``revolute``.
"""
from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import UrdfError
from ...io import atomic_write_text, native_stderr, number_problem, require_file
from .params import G0, ArmParams, LinkParams, require_simulable

__all__ = [
    "dh_fixed", "make_urdf", "write_urdf", "load_arm", "LoadedArm", "default_urdf_path", "REPO_URDF",
    "model_from_params", "params_from_model", "dh_structure", "DHStructure", "PLACEMENT_TOL",
    "L3_DEFAULT", "TOOL_JOINT", "VISUAL_RADIUS", "VISUAL_MATERIALS",
]

#: DH table of the paper: (alpha_i, uses_d) -- d_i = l_i for joint 1, a_i = l_i otherwise.
_ALPHA = (math.pi / 2, 0.0, 0.0)

#: Where the committed URDF lives in a source checkout.
REPO_URDF = Path(__file__).resolve().parents[4] / "urdf" / "rr3.urdf"

#: Tolerance [m, rad] of the structure checks. The URDF's Pinocchio model is the
#: plant and the reference of ``rc3r verify-model`` (closed form within 1e-9
#: relative, :data:`rc3r.verify.TOL`); a structural deviation eps changes M, S, g by
#: O(eps) relative, so a looser tolerance would accept arms failing verify-model.
#: Rounding of URDF decimals and of a few rigid-transform compositions on O(1..10) m
#: is ~1e-15: 1e-9 admits any sane rounding (rpy with 12 digits) and nothing else.
PLACEMENT_TOL = 1e-9

#: l3 [m] used when the URDF has no fixed frame on the DH x3 axis (module
#: docstring); any l3 > 0 gives the same theta (only X3 = l3 + r_cx3 enters).
L3_DEFAULT = 1.0

#: Visual geometry only: radius of the link cylinders / the shortest link (joint housings 1.5 times
#: it, 3 times it long), and colours (URDF ``rgba``) of links and housings.
VISUAL_RADIUS = 0.05
VISUAL_MATERIALS = {"rc3r_link": "0.35 0.55 0.8 1", "rc3r_joint": "0.25 0.25 0.25 1"}

#: Name of the fixed joint :func:`make_urdf` writes at DH frame 3; when a URDF has
#: one, it must be DH frame 3 (it fixes l3, d3 = 0, alpha3 = 0 and q3's zero).
TOOL_JOINT = "tool_joint"


def _snap(x: float) -> float:
    """Round cos/sin of multiples of pi/2 to exact 0/+-1 (keeps the URDF text clean)."""
    for v in (0.0, 1.0, -1.0):
        if abs(x - v) < 1e-15:
            return v
    return x


def _rot_x(alpha: float) -> np.ndarray:
    c, s = _snap(math.cos(alpha)), _snap(math.sin(alpha))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def dh_fixed(i: int, lengths) -> tuple[np.ndarray, np.ndarray]:
    """Fixed part ``(R_i, p_i)`` of the DH transform of joint ``i`` (1-based).

    ``A_i = Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)`` maps DH frame *i*
    coordinates into URDF link-*i* coordinates: ``x_link = R_i x_DH + p_i``.
    Joint 1: ``d = l1``, ``alpha = pi/2``; joints 2, 3: ``a = l_i``, ``alpha = 0``.
    """
    l = float(lengths[i - 1])
    p = np.array([0.0, 0.0, l]) if i == 1 else np.array([l, 0.0, 0.0])
    return _rot_x(_ALPHA[i - 1]), p


def _num(x: float) -> str:
    x = float(x)
    return "0" if x == 0.0 else repr(x)


def _vec(v) -> str:
    return " ".join(_num(x) for x in v)


def _rpy(R: np.ndarray) -> tuple[float, float, float]:
    """URDF roll-pitch-yaw of a rotation matrix (R = Rz(y) Ry(p) Rx(r))."""
    pitch = math.asin(-max(-1.0, min(1.0, R[2, 0])))
    roll = math.atan2(R[2, 1], R[2, 2])
    yaw = math.atan2(R[1, 0], R[0, 0])
    return roll, pitch, yaw


def make_urdf(p: ArmParams) -> str:
    """URDF text of the arm ``p`` (deterministic: same parameters, same bytes).

    Raises
    ------
    ParameterError
        A link with mass <= 0 or a non-positive-definite inertia (no URDF tool
        accepts those); the triangle inequality is not enforced (Table 1 fails it).
    """
    require_simulable(p)
    robot = ET.Element("robot", name=p.name)
    robot.append(ET.Comment(" Generated by rc3r.urdf.make_urdf; do not edit: change the TOML and run "
                            "`rc3r make-urdf`. Units SI; DH table and frames in docs/conventions.md. "))
    for name, rgba in VISUAL_MATERIALS.items():
        ET.SubElement(ET.SubElement(robot, "material", name=name), "color", rgba=rgba)
    ET.SubElement(robot, "link", name="base_link")
    parent = "base_link"
    radius = VISUAL_RADIUS * min(p.lengths)
    joint_origin = (np.zeros(3), (0.0, 0.0, 0.0))
    for i, link in enumerate(p.links, 1):
        j = ET.SubElement(robot, "joint", name=f"joint{i}", type="revolute")
        ET.SubElement(j, "parent", link=parent)
        ET.SubElement(j, "child", link=f"link{i}")
        ET.SubElement(j, "origin", xyz=_vec(joint_origin[0]), rpy=_vec(joint_origin[1]))
        ET.SubElement(j, "axis", xyz="0 0 1")
        # Limits are required by urdfdom for revolute joints; they do not enter dynamics.
        ET.SubElement(j, "limit", lower=_num(-1e3), upper=_num(1e3), effort=_num(1e6), velocity=_num(1e3))
        R, pos = dh_fixed(i, p.lengths)
        lk = ET.SubElement(robot, "link", name=f"link{i}")
        inertial = ET.SubElement(lk, "inertial")
        ET.SubElement(inertial, "origin", xyz=_vec(pos + R @ np.array(link.com)), rpy=_vec(_rpy(R)))
        ET.SubElement(inertial, "mass", value=_num(link.mass))
        ixx, iyy, izz, ixy, ixz, iyz = link.inertia
        ET.SubElement(inertial, "inertia", ixx=_num(ixx), ixy=_num(ixy), ixz=_num(ixz), iyy=_num(iyy),
                      iyz=_num(iyz), izz=_num(izz))
        _visuals(lk, i, pos, radius)
        joint_origin = (pos, _rpy(R))
        parent = f"link{i}"
    tool = ET.SubElement(robot, "joint", name=TOOL_JOINT, type="fixed")
    ET.SubElement(tool, "parent", link="link3")
    ET.SubElement(tool, "child", link="tool")
    ET.SubElement(tool, "origin", xyz=_vec(joint_origin[0]), rpy=_vec(joint_origin[1]))
    ET.SubElement(robot, "link", name="tool")
    ET.indent(robot, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"


def _visuals(link: ET.Element, i: int, pos: np.ndarray, radius: float) -> None:
    """Link ``i``'s visual cylinders: a housing on joint ``i``'s axis, a shaft to ``pos`` (the next joint
    or the tool; a cylinder lies along its z, turned onto x for links 2, 3). No effect on the dynamics."""
    for part, xyz, rpy, r, length, material in (
            ("housing", "0 0 0", "0 0 0", 1.5 * radius, 3 * radius, "rc3r_joint"),
            ("shaft", _vec(pos / 2), "0 0 0" if i == 1 else _vec((0.0, math.pi / 2, 0.0)), radius,
             float(np.linalg.norm(pos)), "rc3r_link")):
        v = ET.SubElement(link, "visual", name=f"link{i}_{part}")
        ET.SubElement(v, "origin", xyz=xyz, rpy=rpy)
        ET.SubElement(ET.SubElement(v, "geometry"), "cylinder", radius=_num(round(r, 12)),
                      length=_num(round(length, 12)))
        ET.SubElement(v, "material", name=material)


def write_urdf(p: ArmParams, path: str | Path) -> Path:
    """Write :func:`make_urdf` ``(p)`` to ``path`` atomically (temp file + rename)."""
    return atomic_write_text(path, make_urdf(p))


@dataclass(frozen=True)
class LoadedArm:
    """A URDF checked to be the 3R arm.

    Attributes
    ----------
    params : ArmParams
        Its parameters in the paper's convention (CoM, inertia in DH frame *i*).
    model : pinocchio.Model
        Pinocchio model, nq = nv = 3, gravity ``(0, 0, -g0)``.
    path : str
        Where it was read from.
    l3_source : str
        Where ``l3`` came from (:attr:`DHStructure.l3_source`).
    """

    params: ArmParams
    model: object
    path: str
    l3_source: str = "given"


def default_urdf_path() -> Path:
    """The committed ``urdf/rr3.urdf`` of a source checkout.

    Outside a checkout (a wheel install) the Table 1 URDF is generated into
    ``$XDG_CACHE_HOME/rc3r/rr3.urdf`` (byte-identical, see ``tests/test_urdf.py``).
    """
    if REPO_URDF.is_file():
        return REPO_URDF
    from .params import table1

    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "rc3r" / "rr3.urdf"
    if not cache.is_file():
        write_urdf(table1(), cache)
    return cache


def _parse(path: Path) -> ET.Element:
    require_file(path, "URDF", UrdfError)  # not found, not a file, a name too long ...
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise UrdfError(f"malformed URDF {path}: {exc}") from None
    except OSError as exc:  # unreadable (permission denied, an I/O error)
        raise UrdfError(f"cannot read URDF {path}: {exc.strerror or exc}") from None
    if root.tag != "robot":
        raise UrdfError(f"malformed URDF {path}: root element is <{root.tag}>, not <robot>")
    _check_numbers(root, path)
    # yourdfpy validates the URDF schema (links, joints, references) beyond XML syntax.
    import yourdfpy

    try:
        yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False,
                           build_collision_scene_graph=False, load_collision_meshes=False)
    except Exception as exc:  # yourdfpy raises many types; all mean "not a usable URDF"
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise UrdfError(f"malformed URDF {path}: {msg}") from None
    return root


_MOVING = {"revolute", "continuous", "prismatic", "floating", "planar"}


#: Numeric attributes of a URDF that rc3r reads: (element tag, attributes).
_NUMERIC = {
    "origin": ("xyz", "rpy"),
    "axis": ("xyz",),
    "mass": ("value",),
    "inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
}


#: Elements whose every numeric attribute must be present.
_REQUIRED = ("mass", "inertia")


def _check_numbers(root: ET.Element, path: Path) -> None:
    """Every number rc3r reads must parse, be finite (urdfdom drops a NaN) and within ``MAX_MAGNITUDE``."""
    for parent in root.iter():
        owner = parent.get("name")
        for el in parent:
            for attr in _NUMERIC.get(el.tag, ()):
                text = el.get(attr)
                where = f"{parent.tag} '{owner}'" if owner else parent.tag
                if text is None:
                    if el.tag in _REQUIRED:  # urdfdom would read a missing inertia entry as 0
                        raise UrdfError(f"malformed URDF {path}: {where} <{el.tag}> has no {attr}=\"...\"")
                    continue
                why = number_problem(text)
                if why:
                    raise UrdfError(f"malformed URDF {path}: {where} <{el.tag} {attr}=\"{text}\"> is {why}")


def _normalize(root: ET.Element, path: Path) -> str:
    """Check the joint types; turn ``continuous`` into ``revolute`` for Pinocchio."""
    joints = root.findall("joint")
    moving = [j for j in joints if j.get("type") in _MOVING]
    names = [j.get("name") for j in moving]
    if len(moving) != 3:
        raise UrdfError(
            f"{path} is not the 3R arm: it has {len(moving)} moving joints ({', '.join(names) or 'none'}), expected 3"
        )
    for j in moving:
        kind = j.get("type")
        if kind not in ("revolute", "continuous"):
            raise UrdfError(f"{path} is not the 3R arm: joint '{j.get('name')}' is {kind}, expected revolute")
        if kind == "continuous":
            j.set("type", "revolute")
            if j.find("limit") is None:
                ET.SubElement(j, "limit", lower="-1e3", upper="1e3", effort="1e6", velocity="1e3")
    return ET.tostring(root, encoding="unicode")


@dataclass(frozen=True)
class DHStructure:
    """DH frames of an arm found equivalent to the paper's (:func:`dh_structure`).

    Attributes
    ----------
    lengths : tuple of 3 float
        ``(l1, l2, l3)`` [m].
    frames : tuple of 4 pinocchio.SE3
        DH frames 0..3 in the URDF base frame at ``q = 0``.
    l3_source : str
        ``"tool joint '<name>'"``, ``"fixed frame '<name>'"``, ``"default"`` or ``"given"``.
    """

    lengths: tuple[float, float, float]
    frames: tuple
    l3_source: str


def _fmt(v) -> str:
    """Short text of a vector; rounding residue (< 1e-12) printed as 0."""
    return "(" + ", ".join(f"{x:.6g}" for x in np.round(np.asarray(v, dtype=float), 12) + 0.0) + ")"


def _axis_lines(model, data, refuse) -> list[tuple[np.ndarray, np.ndarray]]:
    """Unit axis ``u`` and the point ``P`` nearest the base origin of joints 1..3 at q = 0.

    Column ``j`` of the world-frame joint Jacobian is the joint's unit twist
    ``(v, w)`` at the base origin; for a rotation about the line ``P + s u``,
    ``w = |w| u`` and ``v = P x w``, so ``P = u x v / |w|``.
    """
    import pinocchio as pin

    pin.computeJointJacobians(model, data, pin.neutral(model))
    lines = []
    for j in range(1, 4):
        col = np.asarray(data.J[:, model.joints[j].idx_v], dtype=float)
        w = np.linalg.norm(col[3:])
        if w <= PLACEMENT_TOL:
            refuse(f"joint {j} ('{model.names[j]}') does not rotate; expected a revolute joint")
        u = col[3:] / w
        lines.append((u, np.cross(u, col[:3]) / w))
    return lines


def dh_structure(model, l3: float | None = None, where: str = "the model") -> DHStructure:
    """Check that a Pinocchio model is the paper's arm up to frame placement; find its DH frames.

    Parameters
    ----------
    model : pinocchio.Model
        Three 1-DoF revolute joints in series (from a URDF; fixed joints merged).
    l3 : float, optional
        Use this ``l3`` [m] instead of the module's rule (a tool joint, a fixed frame
        on the DH x3 axis, else :data:`L3_DEFAULT`); ArmParams refuses ``l3 <= 0``.
    where : str
        What the model is, for messages (the URDF path).

    Raises
    ------
    UrdfError
        One line naming the first difference from the DH table (module docstring),
        checked to :data:`PLACEMENT_TOL`.
    """
    import pinocchio as pin

    def refuse(what: str):
        raise UrdfError(f"{where} is not the 3R arm: {what}")

    tol, ex, ez = PLACEMENT_TOL, np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    if model.nq != 3 or model.nv != 3 or model.njoints != 4:
        refuse(f"nq = {model.nq}, nv = {model.nv}, expected 3")
    if list(model.parents) != [0, 0, 1, 2]:
        refuse("the three joints do not form a serial chain")
    data = model.createData()
    (u1, p1), (u2, p2), (u3, p3) = _axis_lines(model, data, refuse)
    if np.linalg.norm(np.cross(u1, ez)) > tol:
        refuse(f"joint 1 axis is {_fmt(u1)} in the base frame, not vertical; expected base z (gravity -z)")
    if u1[2] < 0:
        refuse("joint 1 axis points along -z, a flipped axis (q1 would be minus the paper's q1); expected +z")
    if abs(u1 @ u2) > tol:
        angle = math.acos(np.clip(u1 @ u2, -1, 1))
        refuse(f"joint 2 axis is not perpendicular to joint 1 axis (angle {angle:.6g} rad, expected pi/2: DH alpha1)")
    # Closest points o1 (on axis 1) and c2 (on axis 2) of the two (perpendicular) lines.
    w0, b = p1 - p2, u1 @ u2
    o1 = p1 + (b * (u2 @ w0) - u1 @ w0) / (1.0 - b * b) * u1
    c2 = p2 + (u2 @ w0 - b * (u1 @ w0)) / (1.0 - b * b) * u2
    dist = float(np.linalg.norm(o1 - c2))
    if dist > tol:
        refuse(f"joint 2 axis does not intersect joint 1 axis (distance {dist:.6g} m, expected 0: DH a1)")
    l1 = float(o1[2])
    if l1 <= tol:
        refuse(f"joint 2 axis meets joint 1 axis at height {l1:.6g} m above the base origin, expected l1 > 0 (d1)")
    e2 = np.array([0.0, -1.0, 0.0])  # z1 = Rot_x(pi/2) z0 when x1 = base x
    phi1 = math.atan2(np.cross(e2, u2) @ ez, e2 @ u2)
    if abs(phi1) > tol:
        refuse(f"at q = 0 joint 2 axis is {_fmt(u2)}, not (0, -1, 0) as the DH table needs (alpha1 = pi/2, "
               f"x1 = base x): turned {phi1:.6g} rad about joint 1, a joint 1 zero offset or a flipped joint 2 axis")
    s23 = min(1.0, float(np.linalg.norm(np.cross(u2, u3))))
    if s23 > tol:
        refuse(f"joint 3 axis is not parallel to joint 2 axis (angle {math.asin(s23):.6g} rad, expected 0: alpha2)")
    if u2 @ u3 < 0:
        refuse("joint 3 axis is antiparallel to joint 2 axis, a flipped axis (q3 would be minus the paper's q3)")
    normal = (p3 - o1) - ((p3 - o1) @ u2) * u2
    l2 = float(np.linalg.norm(normal))
    if l2 <= tol:
        refuse("joint 3 axis coincides with joint 2 axis; expected them l2 > 0 apart (DH a2)")
    phi2 = math.atan2(np.cross(ex, normal) @ u2, ex @ normal)
    if abs(phi2) > tol:
        refuse(f"at q = 0 the common normal from joint 2 to joint 3 points along {_fmt(normal / l2)}, not base x: "
               f"a joint 2 zero offset of {phi2:.6g} rad (DH theta2 = q2)")

    frames = [pin.SE3(np.eye(3), np.array([o1[0], o1[1], 0.0]))]  # DH frame 0: base moved onto axis 1
    for i in (1, 2):
        frames.append(frames[-1] * pin.SE3(*dh_fixed(i, (l1, l2, 1.0))))
    found, source = _read_l3(model, data, frames[2], refuse)
    lengths = (l1, l2, found) if l3 is None else (l1, l2, float(l3))
    frames.append(frames[2] * pin.SE3(*dh_fixed(3, lengths)))
    return DHStructure(lengths, tuple(frames), source if l3 is None else "given")


def _read_l3(model, data, frame2, refuse) -> tuple[float, str]:
    """``(l3, source)`` from the fixed frames after joint 3 (module docstring rule)."""
    import pinocchio as pin

    tol, on_ray = PLACEMENT_TOL, []
    for f in model.frames:
        if f.parentJoint != 3 or f.type != pin.FrameType.FIXED_JOINT:
            continue
        M = frame2.actInv(data.oMi[3] * f.placement)  # in DH frame 2 = DH frame 3 at q3 = 0, l3 = 0
        x, y, z = (float(c) for c in M.translation)
        if f.name == TOOL_JOINT:
            what = f"tool joint '{f.name}'"
            if abs(z) > tol:
                refuse(f"{what} is {z:.6g} m off the arm plane along joint 3's axis (DH d3 = {z:.6g}, expected 0)")
            if math.hypot(x, y) <= tol:
                refuse(f"{what} lies on joint 3's axis; expected it at l3 > 0 along DH x3 (DH a3)")
            angle = math.atan2(y, x)
            if abs(angle) > tol:
                refuse(f"at q = 0 {what} is turned {angle:.6g} rad about joint 3 from the DH x2 axis: "
                       "a joint 3 zero offset (DH theta3 = q3)")
            turn = float(np.linalg.norm(pin.log3(M.rotation)))
            if turn > tol:
                refuse(f"{what} is rotated {turn:.6g} rad relative to DH frame 3 (expected alpha3 = 0, x3 on link 3)")
            return x, what
        if abs(y) <= tol and abs(z) <= tol and x > tol:
            on_ray.append((x, f.name))
    if on_ray:
        x, name = max(on_ray)
        return x, f"fixed frame '{name}'"
    return L3_DEFAULT, "default"


def params_from_model(model, l3: float | None = None, g0: float = G0, name: str = "rr3",
                      where: str = "the model") -> ArmParams:
    """Paper-convention parameters from a Pinocchio model of the arm (any frame placement).

    Checks the structure (:func:`dh_structure`, which also fixes ``l3``), then moves
    each body's CoM ``c`` and inertia ``I_J`` about it from joint frame *i* into DH
    frame *i*: with ``X = T_i^-1 oMi[i]`` at ``q = 0`` (constant: both frames ride on
    link *i*), ``r_ci = X c`` and ``I_i = R_X I_J R_X^T``.

    Raises
    ------
    UrdfError
        The model is not the arm (:func:`dh_structure`).
    """
    return _dh_params(model, dh_structure(model, l3=l3, where=where), g0, name)


def _dh_params(model, dh: DHStructure, g0: float, name: str) -> ArmParams:
    import pinocchio as pin

    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    links = []
    for i in range(1, 4):
        Y = model.inertias[i]
        X = dh.frames[i].actInv(data.oMi[i])
        R = np.asarray(X.rotation)
        com = R @ np.asarray(Y.lever) + np.asarray(X.translation)
        I = R @ np.asarray(Y.inertia) @ R.T
        links.append(LinkParams(dh.lengths[i - 1], float(Y.mass), com,
                                (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])))
    return ArmParams(tuple(links), g0=g0, name=name)


def load_arm(path: str | Path | None = None, g0: float = G0) -> LoadedArm:
    """Load a URDF, check that it is the 3R arm, and read its parameters.

    Parameters
    ----------
    path : path-like, optional
        URDF file; default :func:`default_urdf_path`.
    g0 : float
        Gravity magnitude [m/s^2]; the model's gravity is set to ``(0, 0, -g0)``.

    Raises
    ------
    UrdfError
        Missing or malformed file, or a robot that is not kinematically this arm
        (the one-line message names what differs; module docstring).
    """
    import pinocchio as pin

    path = Path(path) if path is not None else default_urdf_path()
    root = _parse(path)
    xml = _normalize(root, path)
    try:  # urdfdom prints its reason on fd 2: caught, and folded into the one line
        with native_stderr() as cpp:
            model = pin.buildModelFromXML(xml)
    except Exception as exc:  # Pinocchio raises std::invalid_argument etc. as generic errors
        raise UrdfError(cpp.folded(f"malformed URDF {path}", f"Pinocchio: {str(exc).splitlines()[0]}")) from None
    model.gravity.linear = np.array([0.0, 0.0, -float(g0)])
    dh = dh_structure(model, where=str(path))
    params = _dh_params(model, dh, g0, root.get("name", "rr3"))
    return LoadedArm(params=params, model=model, path=str(path), l3_source=dh.l3_source)


def model_from_params(p: ArmParams):
    """Pinocchio model of the arm ``p`` (through :func:`make_urdf`), gravity ``(0, 0, -g0)``."""
    import pinocchio as pin

    with native_stderr():
        model = pin.buildModelFromXML(make_urdf(p))
    model.gravity.linear = np.array([0.0, 0.0, -float(p.g0)])
    return model
