"""Parse robot XML text into a :class:`~app.models.spec.RobotSpec`.

The text is checked against ``robots/robot.xsd`` (lxml's XML Schema validator), then
for what XSD 1.0 cannot express: finite numbers, min < max, unique and known joint
names, the mechanism element matching ``type``.  Every failure raises
:class:`~app.errors.RobotXmlError` naming the file, the line and what is wrong.
The format is documented in ``robots/README.md``.
"""

from __future__ import annotations

import codecs
import math
import re
import stat
from functools import lru_cache
from pathlib import Path

import numpy as np
from lxml import etree

from app.errors import RobotXmlError, one_line
from app.geometry import euler_zyx_to_matrix, homogeneous
from app.models.spec import (
    STEWART_DOFS,
    DeltaSpec,
    JointSpec,
    LinkSpec,
    RatedCapacity,
    RobotSpec,
    SerialSpec,
    StewartSpec,
    standard_from_modified,
)
from app.models.urdf import is_urdf
from app.resources import robot_library

SCHEMA_PATH = robot_library() / "robot.xsd"  # package data (app/resources.py)
MAX_FILE_BYTES = 1_000_000

#: At most this many actuated joints in a serial chain (and links in the table).  Past a dozen
#: joints a chain is no manipulator Bosun drives, and the solvers' cost grows with n.
MAX_JOINTS = 12
MAX_LINKS = 24

#: Physical bounds of every number in a robot file, in SI units after conversion (rad, m, s):
#: kind -> (lowest, highest, unit).  Documented in robots/README.md, "Physical bounds".
BOUNDS: dict[str, tuple[float, float, str]] = {
    "length": (-1000.0, 1000.0, "m"),  # DH a and d, offsets, points, prismatic limits
    "size": (1e-3, 1000.0, "m"),  # Delta link lengths, Stewart leg lengths
    "angle": (-40 * math.pi, 40 * math.pi, "rad"),  # DH angles, rpy, revolute limits (±20 turns)
    "speed": (1e-6, 1000.0, "/s"),  # rad/s or m/s
    "accel": (1e-6, 1e5, "/s²"),  # rad/s² or m/s²
    "factor": (-100.0, 100.0, ""),  # coupling ratios
    "time": (1e-4, 1000.0, "s"),  # motor time constant
    "gain": (0.0, 1e6, ""),  # PID gains
    "ratio": (1e-6, 1e6, ""),  # motor gain
    "capacity": (1e-3, 1e5, "t"),  # a crane's rated capacity (in tonnes, as load charts give it)
}

#: seeded joint-space samples at which a serial chain's FK and Jacobian must be finite
N_CHECK_SAMPLES = 64


@lru_cache(maxsize=1)
def _schema() -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(str(SCHEMA_PATH)))


#: byte-order marks, longest first (a UTF-32-LE mark begins like a UTF-16-LE one)
_BOMS = (
    (codecs.BOM_UTF32_LE, "utf-32-le"),
    (codecs.BOM_UTF32_BE, "utf-32-be"),
    (codecs.BOM_UTF8, "utf-8"),
    (codecs.BOM_UTF16_LE, "utf-16-le"),
    (codecs.BOM_UTF16_BE, "utf-16-be"),
)
#: the first bytes of '<?' without a mark (XML 1.0, appendix F)
_NO_BOM = (
    (b"\x00\x00\x00<", "utf-32-be"),
    (b"<\x00\x00\x00", "utf-32-le"),
    (b"\x00<\x00?", "utf-16-be"),
    (b"<\x00?\x00", "utf-16-le"),
)
#: an XML declaration up to its encoding's name (group 4), ASCII in every ASCII-compatible encoding
_DECLARATION = re.compile(r"""\A(<\?xml\s+version\s*=\s*(["'])[^"']*\2\s+encoding\s*=\s*)(["'])([^"']*)\3""")
_ASCII = bytes(range(0x20, 0x7F)) + b"\t\n\r"


def _codec(name: str, path: str) -> str:
    """The Python codec of the encoding an XML declaration names, for a file without a byte-order mark."""
    try:
        info = codecs.lookup(name)
        text = info._is_text_encoding and "escape" not in info.name  # type: ignore[attr-defined]
    except LookupError:
        text = False
    if not text:
        raise RobotXmlError(
            path, 1, f"unknown encoding {_short(name)!r} in the XML declaration; save the file as UTF-8"
        )
    try:  # the declaration was read as ASCII: the encoding must agree with ASCII there
        ascii_compatible = _ASCII.decode(info.name) == _ASCII.decode("ascii")
    except ValueError:  # UnicodeDecodeError among them
        ascii_compatible = False
    if not ascii_compatible:
        raise RobotXmlError(
            path, 1, f"the XML declaration declares {_short(name)} but the file is not in it (no byte-order mark)"
        )
    return info.name


def decode_robot_xml(data: bytes, path: str = "<string>") -> str:
    """The text of a robot file's bytes, decoded as an XML parser does; the one reader of robot files.

    The encoding is the byte-order mark's, else the one the XML declaration names, else UTF-8 (XML 1.0,
    section 4.3.3 and appendix F).  The text comes back without the mark and with the declaration
    saying ``UTF-8``, so whoever encodes it again as UTF-8 (:func:`parse_robot_xml`, a message to a
    client) reads the same document.  ``bosun check``, the engine's ``--robot`` and ``set_robot`` all
    read through here: a file one of them accepts, all do (issue 27, item 9).

    Raises
    ------
    RobotXmlError
        An unknown encoding, a declaration that contradicts the bytes, or bytes that are not in the
        encoding (naming the line and the byte).
    """
    codec = None
    for bom, name in _BOMS:
        if data.startswith(bom):
            codec, data = name, data[len(bom) :]
            break
    else:
        for start, name in _NO_BOM:
            if data.startswith(start):
                codec = name
                break
    if codec is None:  # ASCII-compatible: the declaration, if any, names the encoding
        m = _DECLARATION.match(data[:200].decode("latin-1"))
        codec = _codec(m.group(4), path) if m else "utf-8"
    try:
        text = data.decode(codec)
    except UnicodeDecodeError as err:
        line = data[: err.start].decode(codec, "replace").count("\n") + 1
        shown = "UTF-8" if codec == "utf-8" else codec
        raise RobotXmlError(
            path,
            line,
            f"not valid {shown} (byte 0x{data[err.start]:02x}); save the file as UTF-8 or name its encoding "
            'in the XML declaration (<?xml version="1.0" encoding="ISO-8859-1"?>)',
        ) from None
    return _declared_utf8(text)


def _declared_utf8(text: str) -> str:
    """``text`` without a leading mark, its declaration (if it names an encoding) saying UTF-8."""
    text = text.removeprefix("\ufeff")
    m = _DECLARATION.match(text)
    if m and m.group(4) != "UTF-8":
        text = f"{m.group(1)}{m.group(3)}UTF-8{m.group(3)}{text[m.end() :]}"
    return text


def read_robot_file(path: str | Path, label: str | None = None) -> str:
    """The text of a robot file (:func:`decode_robot_xml`), its size checked before reading.

    ``label`` names the file in errors (default: the path)."""
    path = Path(path)
    label = str(path) if label is None else label
    try:
        info = path.stat()
        if not stat.S_ISREG(info.st_mode):
            raise RobotXmlError(label, None, "not a regular file")
        if info.st_size > MAX_FILE_BYTES:  # checked before reading: a 1 GB file is never read
            raise RobotXmlError(label, None, f"file is {info.st_size} bytes; a robot file is at most {MAX_FILE_BYTES}")
        with path.open("rb") as fh:
            data = fh.read(MAX_FILE_BYTES + 1)
    except OSError as err:
        raise RobotXmlError(label, None, f"cannot read file: {err.strerror or err}") from None
    if len(data) > MAX_FILE_BYTES:  # grew since the stat
        raise RobotXmlError(
            label, None, f"file is over {MAX_FILE_BYTES} bytes; a robot file is at most {MAX_FILE_BYTES}"
        )
    return decode_robot_xml(data, label)


def parse_robot_file(path: str | Path, label: str | None = None) -> RobotSpec:
    """Read (:func:`read_robot_file`) and parse (:func:`parse_robot_xml`) a robot file."""
    label = str(path) if label is None else label
    return parse_robot_xml(read_robot_file(path, label), label)


def _safe_root(text: str | bytes, path: str) -> etree._Element:
    """The document's root, parsed as a robot file is: decoded, no entities, no network, no DOCTYPE, bounded size."""
    if not isinstance(text, str):
        if len(text) > MAX_FILE_BYTES:
            raise RobotXmlError(path, None, f"file is {len(text)} bytes; a robot file is at most {MAX_FILE_BYTES}")
        text = decode_robot_xml(bytes(text), path)
    try:
        data = _declared_utf8(text).encode("utf-8")
    except UnicodeEncodeError as err:  # a lone surrogate: no file holds one
        line = text[: err.start].count("\n") + 1
        raise RobotXmlError(path, line, f"not text: U+{ord(text[err.start]):04X} is no character") from None
    if len(data) > MAX_FILE_BYTES:
        raise RobotXmlError(path, None, f"file is {len(data)} bytes; a robot file is at most {MAX_FILE_BYTES}")
    parser = etree.XMLParser(resolve_entities=False, no_network=True, remove_comments=True, huge_tree=False)
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as err:
        raise RobotXmlError(path, err.lineno, f"XML syntax error: {_strip_location(err.msg)}") from None
    if root.getroottree().docinfo.doctype:
        raise RobotXmlError(path, 1, "a DOCTYPE (DTD, entities) is not allowed in a robot file")
    return root


def urdf_root(text: str | bytes, path: str) -> etree._Element:
    """A URDF document's root, parsed safely (:func:`_safe_root`); a document that is no URDF is refused."""
    root = _safe_root(text, path)
    if not is_urdf(root):
        raise RobotXmlError(path, root.sourceline, "not a URDF (a <robot> with <link> and <joint> elements)")
    return root


def parse_robot_xml(text: str | bytes, path: str = "<string>") -> RobotSpec:
    """Parse and validate robot XML.

    Parameters
    ----------
    text : str or bytes
        The XML document: bytes are decoded by :func:`decode_robot_xml` (mark, declaration, UTF-8);
        a str is text already, whatever encoding its declaration names.
    path : str
        Name used in error messages and stored as ``RobotSpec.path``.

    Returns
    -------
    RobotSpec
        All lengths in metres, all angles in radians.

    Raises
    ------
    RobotXmlError
        For a syntax error, a schema violation or a value that cannot be used.
    """
    root = _safe_root(text, path)
    if is_urdf(root):  # a URDF, wherever a robot file is accepted: its chain as the robot file it makes
        return _from_urdf(root, path)
    schema = _schema()
    try:
        valid = schema.validate(root)
    except etree.Error as err:  # e.g. an entity reference left unresolved in element text
        raise RobotXmlError(path, None, f"schema: cannot validate ({err})") from None
    if not valid:
        first = schema.error_log[0]
        raise RobotXmlError(path, first.line, f"schema: {first.message}")
    try:
        return _Reader(path, root).robot()
    except RobotXmlError:
        raise
    except (ArithmeticError, ValueError, TypeError, IndexError, KeyError) as err:
        # a boundary: a file that slips past the checks is refused with its name, never a traceback
        raise RobotXmlError(path, None, f"cannot be used ({type(err).__name__}: {err})") from None


def _from_urdf(root: etree._Element, path: str) -> RobotSpec:
    """A URDF document's chain (its only tip, from its root link: :mod:`app.models.urdf`) read as the robot file the
    importer writes; a value of it that a robot file refuses is reported against the URDF."""
    from app.models.urdf import robot_xml_from_urdf

    text = robot_xml_from_urdf(root, path)
    try:
        return parse_robot_xml(text, path)
    except RobotXmlError as err:
        raise RobotXmlError(path, None, f"as imported from URDF: {err.message}") from None


#: xs:double as a finite decimal: what the schema and float() both accept (no INF, NaN, '1e', '1.e')
_NUMBER = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")


def parse_number(raw: str) -> float | None:
    """The one number parser of robot files: a finite decimal or None (the caller names the place)."""
    text = raw.strip()
    if not _NUMBER.match(text):
        return None
    value = float(text)
    return value if math.isfinite(value) else None


def _short(raw: str) -> str:
    """A file value quoted in a message: one line, at most 40 characters."""
    return one_line(raw, 40)


def _strip_location(msg: str) -> str:
    # lxml appends ", line N, column M" to syntax messages; the line is reported already.
    head, sep, _ = msg.rpartition(", line ")
    return head if sep else msg


class _Reader:
    """Turns a schema-valid element tree into a spec, converting units."""

    def __init__(self, path: str, root: etree._Element) -> None:
        self.path = path
        self.root = root
        self.angle_scale = math.pi / 180.0 if root.get("angle_unit") == "deg" else 1.0

    # ------------------------------------------------------------------ helpers
    def fail(self, el: etree._Element, message: str) -> RobotXmlError:
        return RobotXmlError(self.path, el.sourceline, message)

    def num(
        self, el: etree._Element, attr: str, default: float | None = None, angle: bool = False, bound: str = ""
    ) -> float:
        """The attribute as a finite number in SI units, inside ``BOUNDS[bound]`` when given."""
        raw = el.get(attr)
        if raw is None:
            if default is None:
                raise self.fail(el, f"<{el.tag}> needs attribute '{attr}'")
            value = default
        else:
            value = parse_number(raw)
            if value is None:
                raise self.fail(el, f"<{el.tag}> attribute '{attr}' is {_short(raw)}; give a finite number")
        value = value * self.angle_scale if angle else value
        if bound:
            self.bounded(el, attr, value, bound, raw, angle)
        return value

    def bounded(
        self, el: etree._Element, attr: str, value: float, bound: str, raw: str | None, angle: bool = False
    ) -> None:
        lo, hi, unit = BOUNDS[bound]
        if bound in ("speed", "accel"):
            unit = ("rad" if angle else "m") + unit
        if not lo <= value <= hi:
            shown = "" if raw is None else f" ({_short(raw)} in the file)"
            unit = f" {unit}" if unit else ""
            raise self.fail(
                el,
                f"<{el.tag}> attribute '{attr}' is {value:.6g}{unit}{shown}; must be within "
                f"[{lo:.6g}, {hi:.6g}]{unit} (the {bound} bound, robots/README.md)",
            )

    def vec3(self, el: etree._Element, attr: str, angle: bool = False) -> np.ndarray:
        raw = el.get(attr, "0 0 0")
        vals = [parse_number(x) for x in raw.split()]
        if len(vals) != 3 or any(v is None for v in vals):
            raise self.fail(el, f"<{el.tag}> attribute '{attr}' needs three finite numbers, got '{_short(raw)}'")
        v = np.array(vals, dtype=float)
        v = v * self.angle_scale if angle else v
        for x in v:
            self.bounded(el, attr, float(x), "angle" if angle else "length", raw)
        return v

    def frame(self, el: etree._Element | None) -> np.ndarray:
        if el is None:
            return np.eye(4)
        return homogeneous(euler_zyx_to_matrix(self.vec3(el, "rpy", angle=True)), self.vec3(el, "xyz"))

    def ordered(self, el: etree._Element, lo: float, hi: float, what: str, strict: bool = True) -> None:
        if lo > hi or (strict and lo == hi):
            raise self.fail(el, f"{what}: min ({lo:g}) must be less than max ({hi:g})")

    def limits(self, el: etree._Element, angular: bool, what: str) -> tuple[float, float, float, float | None]:
        position = "angle" if angular else "length"
        lo = self.num(el, "min", angle=angular, bound=position)
        hi = self.num(el, "max", angle=angular, bound=position)
        # Compare in file units so the message shows the numbers the user wrote.
        self.ordered(el, self.num(el, "min"), self.num(el, "max"), what)
        speed = self.num(el, "speed", angle=angular, bound="speed")
        accel = self.num(el, "accel", angle=angular, bound="accel") if el.get("accel") is not None else None
        return lo, hi, speed, accel

    # ------------------------------------------------------------------ robot
    def robot(self) -> RobotSpec:
        root = self.root
        kind = root.get("type")
        mech = root.find(kind)
        if mech is None:
            other = next(el.tag for el in root if el.tag in ("serial", "delta", "stewart"))
            raise self.fail(root.find(other), f"robot type is '{kind}' but the mechanism element is <{other}>")
        common = dict(
            name=root.get("name"),
            type=kind,
            description=" ".join((root.findtext("description") or "").split()),
            source=" ".join((root.findtext("source") or "").split()),
            assumptions=" ".join((root.findtext("assumptions") or "").split()),
            path=self.path,
            rated_capacity=self.rated_capacity(root.find("rated_capacity")),
        )
        if kind == "serial":
            spec = RobotSpec(**common, serial=self.serial(mech))
        elif kind == "delta":
            spec = RobotSpec(**common, delta=self.delta(mech))
        else:
            spec = RobotSpec(**common, stewart=self.stewart(mech))
        self.check_model(spec, mech)
        return spec

    def rated_capacity(self, el: etree._Element | None) -> RatedCapacity | None:
        """``<rated_capacity source="…">`` with ``<rating radius="m" capacity="t"/>`` rows: radii increasing,
        capacities in tonnes not rising with the radius (a crane's load chart falls outwards)."""
        if el is None:
            return None
        rows = el.findall("rating")
        radius = [self.num(r, "radius", bound="size") for r in rows]
        tonnes = [self.num(r, "capacity", bound="capacity") for r in rows]
        for k in range(1, len(rows)):
            if radius[k] <= radius[k - 1]:
                raise self.fail(
                    rows[k], f"<rating> radius {radius[k]:g} m must be more than the row before's ({radius[k - 1]:g} m)"
                )
            if tonnes[k] > tonnes[k - 1]:
                raise self.fail(
                    rows[k],
                    f"<rating> capacity {tonnes[k]:g} t at {radius[k]:g} m is more than {tonnes[k - 1]:g} t at "
                    f"{radius[k - 1]:g} m: a load chart does not rise outwards",
                )
        source = " ".join((el.get("source") or "").split())
        if not source:
            raise self.fail(el, "<rated_capacity> needs a source: where the ratings come from, or 'assumed' and why")
        return RatedCapacity(np.array(radius), 1000.0 * np.array(tonnes), source)

    # ------------------------------------------------------------------ the model as physics
    def check_model(self, spec: RobotSpec, mech: etree._Element) -> None:
        """Build the kinematic model and check it where the file's numbers cannot show a fault.

        Serial: tool position and Jacobian finite at the mid-range pose, every limit corner of
        the first three joints and seeded samples inside the limits.  Delta: an assembly exists
        at the mid-range arm angles with a finite Jacobian.  Stewart: every leg reaches the
        neutral pose and each pose limit taken alone (the others at 0) within its stroke.
        """
        from app.models.delta import DeltaHead
        from app.models.serial import SerialRobot
        from app.models.stewart import StewartPlatform

        if spec.serial is not None:
            robot = SerialRobot(spec)
            rng = np.random.default_rng(0)
            q = rng.uniform(robot.lower, robot.upper, size=(N_CHECK_SAMPLES, robot.n_joints))
            q[0] = 0.5 * (robot.lower + robot.upper)
            with np.errstate(all="ignore"):
                bad = ~(
                    np.all(np.isfinite(robot.position(q)), axis=-1)
                    & np.all(np.isfinite(robot.jacobian(q)), axis=(-2, -1))
                )
            if bad.any():
                raise self.fail(mech, "the chain's tool position or Jacobian is not finite inside the joint limits")
        elif spec.delta is not None:
            head = DeltaHead(spec)
            alpha = np.full(3, 0.5 * (head.lower[0] + head.upper[0]))
            try:
                with np.errstate(all="ignore"):
                    ok = np.all(np.isfinite(head.fk(alpha))) and np.all(np.isfinite(head.jacobian(alpha)))
            except (ValueError, np.linalg.LinAlgError):
                ok = False
            if not ok:
                raise self.fail(
                    mech, "the Delta head cannot be assembled at mid-range arm angles (check l_k, l_a, l_r, l_p)"
                )
        else:
            self.check_stewart(StewartPlatform(spec), mech)

    def check_stewart(self, platform, mech: etree._Element) -> None:
        legs_el = mech.find("legs")
        poses = [("the neutral pose", np.zeros(6))]
        for i, name in enumerate(STEWART_DOFS):
            for end, value in (("min", platform.pose_min[i]), ("max", platform.pose_max[i])):
                if value != 0.0:
                    eta = np.zeros(6)
                    eta[i] = value
                    poses.append((f"{name} {end}", eta))
        lengths = platform.leg_lengths(np.array([eta for _, eta in poses]))
        lo, hi = platform.leg_min, platform.leg_max
        tol = 1e-9 * max(1.0, hi)
        for (what, _), row in zip(poses, lengths, strict=True):
            k = int(np.argmax(np.maximum(lo - row, row - hi)))
            if not lo - tol <= row[k] <= hi + tol:
                raise self.fail(
                    legs_el,
                    f"leg {k + 1} needs {row[k]:.4g} m at {what}, outside its stroke [{lo:g}, {hi:g}] m; "
                    "every leg must reach the neutral pose and each pose limit alone",
                )

    # ------------------------------------------------------------------ serial
    def serial(self, el: etree._Element) -> SerialSpec:
        links: list[LinkSpec] = []
        joints: list[dict] = []
        link_els = el.findall("link")
        movers = [x for x in link_els if x.get("joint") != "fixed"]
        if len(movers) > MAX_JOINTS:
            raise self.fail(
                movers[MAX_JOINTS], f"{len(movers)} joints; a serial robot has at most {MAX_JOINTS} (robots/README.md)"
            )
        if len(link_els) > MAX_LINKS:
            raise self.fail(
                link_els[MAX_LINKS], f"{len(link_els)} links; a serial robot has at most {MAX_LINKS} (robots/README.md)"
            )
        for i, link_el in enumerate(link_els):
            kind = link_el.get("joint")
            name = link_el.get("name") or str(i + 1)
            dh = link_el.find("dh")
            joint_el = link_el.find("joint")
            variable = {"revolute": "theta", "prismatic": "d"}.get(kind)
            if variable and dh.get(variable) is not None:
                raise self.fail(
                    dh,
                    f"link {name}: a {kind} joint drives '{variable}'; give its constant part as "
                    f"<joint offset=...> instead of <dh {variable}=...>",
                )
            if kind == "fixed" and joint_el is not None:
                raise self.fail(joint_el, f"link {name}: a fixed link has no <joint>")
            if kind != "fixed" and joint_el is None:
                raise self.fail(link_el, f"link {name}: a {kind} link needs a <joint> with limits")
            col = link_el.find("collision")
            radius = None
            if col is not None:
                radius = self.num(col, "radius", bound="size")
            joint_index = None
            if joint_el is not None:
                joint_index = len(joints)
                joints.append(self.joint(joint_el, kind, i))
            links.append(
                LinkSpec(
                    name=name,
                    kind=kind,
                    theta=self.num(dh, "theta", 0.0, angle=True, bound="angle"),
                    d=self.num(dh, "d", 0.0, bound="length"),
                    a=self.num(dh, "a", bound="length"),
                    alpha=self.num(dh, "alpha", angle=True, bound="angle"),
                    joint=joint_index,
                    radius=radius,
                )
            )
        if not joints:
            raise self.fail(el, "a serial robot needs at least one revolute or prismatic link")
        names = [j["name"] for j in joints]
        for j in joints:
            if names.count(j["name"]) > 1:
                raise self.fail(j["element"], f"joint name '{j['name']}' is used more than once")
        joint_specs = []
        for j in joints:
            coupling = []
            for c_el in j["element"].findall("coupling"):
                other = c_el.get("joint")
                if other not in names:
                    raise self.fail(
                        c_el, f"joint {j['name']}: coupling names unknown joint '{other}' (joints: {', '.join(names)})"
                    )
                if other == j["name"]:
                    raise self.fail(c_el, f"joint {j['name']}: coupling to itself; use sign and offset instead")
                coupling.append((names.index(other), self.num(c_el, "factor", bound="factor")))
            del j["element"]
            joint_specs.append(JointSpec(**j, coupling=tuple(coupling)))
        base, written = self.frame(el.find("base")), tuple(links)
        convention = el.get("convention", "standard")
        if convention == "modified":  # the same chain as a standard table (SerialSpec's text)
            links, base = standard_from_modified(written, base)
        return SerialSpec(
            links=tuple(links),
            joints=tuple(joint_specs),
            T_world_base=base,
            T_flange_tool=self.frame(el.find("tool")),
            up=el.get("up", "+z"),
            convention=convention,
            written=written if convention == "modified" else (),
        )

    def joint(self, el: etree._Element, kind: str, link_index: int) -> dict:
        name = el.get("name")
        angular = kind == "revolute"
        lo, hi, speed, accel = self.limits(el.find("limits"), angular, f"joint {name} limits")
        return dict(
            element=el,
            name=name,
            kind=kind,
            link=link_index,
            lower=lo,
            upper=hi,
            speed=speed,
            accel=accel,
            sign=self.num(el, "sign", 1.0),
            offset=self.num(el, "offset", 0.0, angle=angular, bound="angle" if angular else "length"),
        )

    # ------------------------------------------------------------------ delta
    def delta(self, el: etree._Element) -> DeltaSpec:
        arms = el.findall("arm")
        indices = [int(a.get("index")) for a in arms]
        if sorted(indices) != [1, 2, 3]:
            raise self.fail(arms[0], f"delta arms must have index 1, 2 and 3 once each, got {indices}")
        rotations = np.zeros(3)
        for a in arms:
            rotations[int(a.get("index")) - 1] = self.num(a, "rot_x", angle=True, bound="angle")
        lo, hi, speed, accel = self.limits(el.find("limits"), True, "delta arm limits")
        motor = el.find("motor")
        pid = el.find("pid")
        spec = DeltaSpec(
            l_k=self.num(el, "l_k", bound="size"),
            l_a=self.num(el, "l_a", bound="size"),
            l_r=self.num(el, "l_r", bound="size"),
            l_p=self.num(el, "l_p", bound="size"),
            arm_rotations=rotations,
            alpha_min=lo,
            alpha_max=hi,
            speed=speed,
            accel=accel,
            motor_time_constant=self.num(motor, "time_constant", bound="time") if motor is not None else None,
            motor_gain=self.num(motor, "gain", bound="ratio") if motor is not None else None,
            pid=tuple(self.num(pid, k, bound="gain") for k in ("kp", "ki", "kd")) if pid is not None else None,
        )
        if spec.l_r <= abs(spec.l_p - spec.l_k):
            raise self.fail(
                el, f"delta rod l_r ({spec.l_r:g} m) must be longer than |l_p - l_k| ({abs(spec.l_p - spec.l_k):g} m)"
            )
        return spec

    # ------------------------------------------------------------------ stewart
    def stewart(self, el: etree._Element) -> StewartSpec:
        base = np.array([self.vec3(p, "xyz") for p in el.find("base_joints").findall("point")])
        plat = np.array([self.vec3(p, "xyz") for p in el.find("platform_joints").findall("point")])
        legs = el.find("legs")
        leg_min, leg_max = self.num(legs, "min_length", bound="size"), self.num(legs, "max_length", bound="size")
        self.ordered(legs, leg_min, leg_max, "leg length")
        dofs = {}
        for d in el.find("pose_limits").findall("dof"):
            name = d.get("name")
            if name in dofs:
                raise self.fail(d, f"pose limit for '{name}' is given twice")
            angular = name in ("roll", "pitch", "yaw")
            lo, hi, speed, accel = self.limits(d, angular, f"{name} limits")
            if not lo <= 0.0 <= hi:
                raise self.fail(
                    d, f"{name} limits [{self.num(d, 'min'):g}, {self.num(d, 'max'):g}] must contain the neutral pose 0"
                )
            dofs[name] = (lo, hi, speed, accel)
        rows = np.array([dofs[n] for n in STEWART_DOFS], dtype=float)
        return StewartSpec(
            base_joints_n=base,
            platform_joints_b=plat,
            leg_min=leg_min,
            leg_max=leg_max,
            leg_speed=self.num(legs, "speed", bound="speed"),
            leg_accel=self.num(legs, "accel", bound="accel") if legs.get("accel") is not None else None,
            pose_min=rows[:, 0],
            pose_max=rows[:, 1],
            speed_max=rows[:, 2],
            accel_max=rows[:, 3],
        )
