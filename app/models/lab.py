"""Lab layout files (``robots/labs/*.xml``): which robots stand where, with the calibrated frames.

A layout names two Stewart platforms, the serial crane mounted on the first, the winch, the
payload and the work point VVMC keeps the tool at.  Frames are given as position + unit
quaternion [w x y z], as in the lab's calibration file.  Errors name the file and the line.

What belongs to the lab's installation rather than to a machine lives here too: each platform's
*operational box* (``<command_box>``, the lab PLC's ``etaRefMin/Max``: the command limit of every
motion source, inside the machine's Table 8 hard limits) and the crane's joint-limit *profiles*
(``<joint_limits name=…>``: the lab's own program limits next to the robot file's data sheet,
``datasheet``, always available; ``<crane limits=…>`` names the default).  Angles in degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from lxml import etree
from numpy.typing import ArrayLike, NDArray

from app.errors import RobotXmlError
from app.geometry import homogeneous, is_rotation_matrix
from app.resources import robot_library

LABS_DIR = robot_library() / "labs"  # package data (app/resources.py)


def quat_to_matrix(q: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix of a unit quaternion [w, x, y, z] (Hamilton convention)."""
    w, x, y, z = np.asarray(q, dtype=float)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


DATASHEET = "datasheet"  # the crane robot file's own limits (Motion-Lab Table 6), always a profile


@dataclass(frozen=True, eq=False)
class JointLimitProfile:
    """Joint limits of the lab's crane for one use (SI: rad, rad/s, rad/s²).

    ``lower``/``upper``/``speed`` are ``None`` in the ``datasheet`` profile (the robot file's limits);
    ``boundary_accel`` is A of the velocity-boundary law |q̇| ≤ √(2 A d) near a limit (``None``: the
    joint acceleration limit, as the motion filter always brakes).
    """

    name: str
    lower: NDArray[np.float64] | None = None
    upper: NDArray[np.float64] | None = None
    speed: NDArray[np.float64] | None = None
    boundary_accel: float | None = None
    source: str = ""


@dataclass(frozen=True, eq=False)
class LabLayout:
    """A parsed lab layout.  Transforms are 4×4, named ``T_<to>_<from>`` (the papers' H_from^to).

    Attributes
    ----------
    platforms : tuple of (name, robot file name)   the main vessel first
    T_world_n1, T_world_n2 : H^g_n1, H^g_n2 (neutral frames of the two platforms in the world)
    crane_robot : str   robot file of the crane on platform 1
    T_b1_r : H^b1_r (crane base in platform 1's body frame)
    crane_accel : float   joint acceleration limit [rad/s²]
    park_q : ndarray (3,)   crane park configuration [rad]
    winch : dict   min_length, max_length, start_length [m], speed [m/s], accel [m/s²]
    payload_mass : float [kg];  payload_damping : float [1/s]
    work_point_b2 : ndarray (3,)   the tool's place in platform 2's body frame [m]
    command_boxes : tuple of 2 × (min, max) or None   operational pose box of each platform [m, rad]
        (None: the platform's Table 8 box)
    crane_profiles : dict name → JointLimitProfile   ``datasheet`` and the file's ``<joint_limits>``
    crane_profile : str   the default profile (``<crane limits=…>``; ``datasheet`` when absent)
    """

    name: str
    source: str
    path: str
    platforms: tuple[tuple[str, str], tuple[str, str]]
    T_world_n1: NDArray[np.float64]
    T_world_n2: NDArray[np.float64]
    crane_robot: str
    T_b1_r: NDArray[np.float64]
    crane_accel: float
    park_q: NDArray[np.float64]
    winch: dict
    payload_mass: float
    payload_damping: float
    work_point_b2: NDArray[np.float64]
    command_boxes: tuple[tuple[NDArray[np.float64], NDArray[np.float64]] | None, ...] = (None, None)
    crane_profiles: dict[str, JointLimitProfile] | None = None
    crane_profile: str = DATASHEET

    def profile(self, name: str | None = None) -> JointLimitProfile:
        """The crane's joint-limit profile ``name`` (default: the layout's); RobotXmlError if unknown."""
        profiles = self.crane_profiles or {DATASHEET: JointLimitProfile(DATASHEET)}
        key = self.crane_profile if name is None else name
        if key not in profiles:
            raise RobotXmlError(
                self.path, None, f"unknown crane joint-limit profile {key!r} (this layout has {', '.join(profiles)})"
            )
        return profiles[key]


def resolve_lab(name_or_path: str = "motionlab") -> Path:
    p = Path(name_or_path)
    if p.suffix == ".xml":
        if not p.is_file():
            raise RobotXmlError(str(p), None, "lab layout file not found")
        return p
    path = LABS_DIR / f"{name_or_path}.xml"
    if not path.is_file():
        names = ", ".join(sorted(x.stem for x in LABS_DIR.glob("*.xml")))
        raise RobotXmlError(name_or_path, None, f"unknown lab layout (available: {names})")
    return path


def load_lab(name_or_path: str = "motionlab") -> LabLayout:
    path = resolve_lab(name_or_path)
    return parse_lab_xml(path.read_bytes(), str(path))


def parse_lab_xml(text: str | bytes, path: str = "<string>") -> LabLayout:
    """Parse a lab layout; raises :class:`RobotXmlError` (file:line: what is wrong)."""
    if isinstance(text, str):
        text = text.encode()
    try:
        root = etree.fromstring(text, etree.XMLParser(resolve_entities=False, no_network=True))
    except etree.XMLSyntaxError as err:
        raise RobotXmlError(path, err.lineno, f"not well-formed XML: {err.msg}") from None

    def fail(el, msg):
        return RobotXmlError(path, el.sourceline, msg)

    def need(parent, tag):
        el = parent.find(tag)
        if el is None:
            raise fail(parent, f"<{parent.tag}> needs a <{tag}> element")
        return el

    def nums(el, attr, n, default=None):
        raw = el.get(attr)
        if raw is None:
            if default is not None:
                return np.asarray(default, dtype=float)
            raise fail(el, f"<{el.tag}> needs attribute '{attr}'")
        try:
            v = np.array([float(x) for x in raw.split()])
        except ValueError:
            raise fail(el, f"<{el.tag}> attribute '{attr}' must be numbers, got '{raw}'") from None
        if v.size != n or not np.all(np.isfinite(v)):
            raise fail(el, f"<{el.tag}> attribute '{attr}' needs {n} finite number{'s' * (n > 1)}, got '{raw}'")
        return v

    def positive(el, attr, default=None):
        v = float(nums(el, attr, 1, None if default is None else [default])[0])
        if not v > 0:
            raise fail(el, f"<{el.tag}> attribute '{attr}' must be positive, got {v:g}")
        return v

    def frame(el):
        f = need(el, "frame")
        q = nums(f, "quat", 4)
        norm = float(np.linalg.norm(q))
        if abs(norm - 1.0) > 1e-6:
            raise fail(f, f"<frame> quat must be a unit quaternion (norm {norm:.6g})")
        R = quat_to_matrix(q / norm)
        assert is_rotation_matrix(R, 1e-9)
        return homogeneous(R, nums(f, "pos", 3))

    if root.tag != "lab":
        raise fail(root, f"root element must be <lab>, got <{root.tag}>")
    plats = root.findall("platform")
    if len(plats) != 2:
        raise fail(root, f"a lab needs exactly two <platform> elements, got {len(plats)}")
    names = []
    for p in plats:
        if not p.get("name") or not p.get("robot"):
            raise fail(p, "<platform> needs attributes 'name' and 'robot'")
        names.append((p.get("name"), p.get("robot")))
    crane = need(root, "crane")
    if crane.get("on") != names[0][0]:
        raise fail(crane, f"<crane on='{crane.get('on')}'>: the crane must stand on the first platform '{names[0][0]}'")
    park = need(crane, "park")
    winch_el = need(root, "winch")
    winch = {k: positive(winch_el, k) for k in ("min_length", "max_length", "start_length", "speed", "accel")}
    if not winch["min_length"] < winch["max_length"]:
        raise fail(winch_el, "<winch> min_length must be below max_length")
    if not winch["min_length"] <= winch["start_length"] <= winch["max_length"]:
        raise fail(winch_el, "<winch> start_length must lie between min_length and max_length")
    payload = need(root, "payload")
    damping = float(nums(payload, "damping", 1, [0.0])[0])
    if damping < 0:
        raise fail(payload, "<payload> damping must not be negative")
    wp = need(root, "work_point")
    if wp.get("on") != names[1][0]:
        raise fail(wp, f"<work_point on=...> must name the second platform '{names[1][0]}'")
    boxes = []
    for p in plats:
        box = p.find("command_box")
        if box is None:
            boxes.append(None)
            continue
        lo, hi = nums(box, "min", 6), nums(box, "max", 6)
        if not (np.all(lo < 0.0) and np.all(hi > 0.0)):
            raise fail(box, "<command_box> must contain the neutral pose: every min < 0 < every max")
        scale = np.array([1.0, 1.0, 1.0, math.pi / 180, math.pi / 180, math.pi / 180])  # m, m, m, deg → rad
        boxes.append((lo * scale, hi * scale))
    profiles = {DATASHEET: JointLimitProfile(DATASHEET, source="the crane robot file (Motion-Lab Table 6)")}
    crane_accel = math.radians(positive(crane, "accel"))
    for el in crane.findall("joint_limits"):
        name = el.get("name", "")
        if not name or name in profiles:
            raise fail(el, f"<joint_limits> needs a unique name other than '{DATASHEET}', got '{name}'")
        lo, hi = np.radians(nums(el, "min", 3)), np.radians(nums(el, "max", 3))
        if not np.all(lo < hi):
            raise fail(el, "<joint_limits> every min must be below its max")
        speed = np.radians(nums(el, "speed", 3))
        if not np.all(speed > 0):
            raise fail(el, "<joint_limits> speeds must be positive")
        a_b = math.radians(positive(el, "boundary_accel"))
        if a_b > crane_accel * (1 + 1e-12):
            # braking at A must be possible with the joints' acceleration limit (the filter's invariant)
            raise fail(el, "<joint_limits> boundary_accel must not exceed the crane's accel")
        src = el.find("source")
        profiles[name] = JointLimitProfile(
            name, lo, hi, speed, a_b, " ".join((src.text or "").split()) if src is not None else ""
        )
    default = crane.get("limits", DATASHEET)
    if default not in profiles:
        raise fail(crane, f"<crane limits='{default}'> names no profile (this layout has {', '.join(profiles)})")
    src = root.find("source")
    return LabLayout(
        name=root.get("name", Path(path).stem),
        source=" ".join((src.text or "").split()) if src is not None else "",
        path=path,
        platforms=(names[0], names[1]),
        T_world_n1=frame(plats[0]),
        T_world_n2=frame(plats[1]),
        crane_robot=crane.get("robot", ""),
        T_b1_r=frame(crane),
        crane_accel=crane_accel,
        park_q=np.radians(nums(park, "q", 3)),
        winch=winch,
        payload_mass=positive(payload, "mass"),
        payload_damping=damping,
        work_point_b2=nums(wp, "xyz", 3),
        command_boxes=(boxes[0], boxes[1]),
        crane_profiles=profiles,
        crane_profile=default,
    )
