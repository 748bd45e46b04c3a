"""URDF import (issue 32, item 1): a serial chain of a URDF robot as a Bosun robot file.

The URDF is read by yourdfpy (the ``urdf`` extra); Bosun's XML stays the native format.  A chain from a base link
(default: the tree's root) to a tip link (default: its only leaf) becomes a standard DH table with a base and a
tool transform, by the classic construction on the joint axes at q = 0 (Spong, Hutchinson & Vidyasagar, *Robot
Modeling and Control*, §3.3; the same frames a hand-written table has):

* frame 0 on the first joint's axis (z₀ along it), its x from the base link's x;
* frame i (i < n) on joint i + 1's axis, x_i along the common normal from z_{i−1} to z_i (through the last origin
  when the axes are parallel, along z_{i−1} × z_i when they meet), and its link's θ_i, d_i, a_i, α_i read off;
* frame n is frame n − 1 moved by the last joint alone, and the tool transform carries it to the tip link.

Each joint's axis is its z with the URDF's direction (sign +1) and its q = 0 is the URDF's (the θ or d of its row
at q = 0 is the joint's offset), so joint values mean what they mean in the URDF.  Revolute, continuous (given
±2π: Bosun's joints have limits), prismatic and fixed joints are taken with their limits; ``<mimic>``, floating
and planar joints on the chain, a link with two parents (a closed loop) and a joint without a velocity limit are
refused in one line naming the element and its line.  Meshes are not read: Bosun draws the links as solids sized
from the joint origins.
"""

from __future__ import annotations

import io
import logging
import math
from dataclasses import dataclass

import numpy as np
from lxml import etree
from numpy.typing import NDArray

from app.errors import RobotXmlError

__all__ = ["CONTINUOUS_RANGE", "UrdfChain", "is_urdf", "robot_xml_from_urdf", "urdf_chain"]

#: the range given to a continuous joint (rad): Bosun's joints have limits
CONTINUOUS_RANGE = 2.0 * math.pi
_EPS = 1e-9  # m or rad: axes closer than this are parallel, normals shorter than this are none


def is_urdf(root: etree._Element) -> bool:
    """A URDF document (root ``<robot>`` with ``<joint>`` or ``<link>`` children and no Bosun ``type``)."""
    return (
        root.tag == "robot"
        and root.get("type") is None
        and (root.find("joint") is not None or root.find("link") is not None)
    )


@dataclass(frozen=True)
class ChainJoint:
    """One movable joint of the chain at q = 0: its name, kind, the axis line in the base link's frame (a point
    and a unit direction) and its limits (SI)."""

    name: str
    kind: str  # revolute or prismatic
    point: NDArray[np.float64]
    axis: NDArray[np.float64]
    lower: float
    upper: float
    speed: float
    line: int | None


@dataclass(frozen=True)
class UrdfChain:
    """The chain from ``base`` to ``tip``: its movable joints at q = 0 and the tip's pose in the base link."""

    robot: str
    base: str
    tip: str
    joints: tuple[ChainJoint, ...]
    T_base_tip: NDArray[np.float64]


def _lines(root: etree._Element) -> dict[tuple[str, str], int]:
    return {(el.tag, el.get("name", "")): el.sourceline for el in root if el.tag in ("joint", "link")}


def urdf_chain(root: etree._Element, label: str, base: str | None = None, tip: str | None = None) -> UrdfChain:
    """The serial chain of a URDF document (parsed safely by the caller: no DTD) from ``base`` to ``tip``."""
    lines = _lines(root)
    try:
        import yourdfpy
    except ImportError:  # pragma: no cover - the urdf extra, installed by scripts/setup.sh
        raise RobotXmlError(label, None, "reading a URDF needs the urdf extra (pip install 'bosun[urdf]')") from None

    def fail(what: tuple[str, str] | None, message: str) -> RobotXmlError:
        return RobotXmlError(label, lines.get(what) if what else None, message)

    logging.getLogger("yourdfpy").setLevel(logging.CRITICAL)  # its own error log would print tracebacks' worth
    try:
        model = yourdfpy.URDF.load(
            io.BytesIO(etree.tostring(root)), build_scene_graph=False, load_meshes=False, load_collision_meshes=False
        )
    except Exception as err:
        raise fail(None, f"URDF cannot be read ({type(err).__name__}: {err})") from None
    robot = model.robot
    joints = list(robot.joints)
    links = {lk.name for lk in robot.links}
    by_child: dict[str, object] = {}
    children: dict[str, list] = {}
    for j in joints:
        where = ("joint", j.name)
        if j.parent not in links or j.child not in links:
            missing = j.parent if j.parent not in links else j.child
            raise fail(where, f"joint '{j.name}': link '{missing}' is not defined")
        if j.child in by_child:
            raise fail(where, f"joint '{j.name}': link '{j.child}' is already the child of joint "
                              f"'{by_child[j.child].name}': a closed loop (a serial chain has none)")  # fmt: skip
        by_child[j.child] = j
        children.setdefault(j.parent, []).append(j)
    roots = sorted(links - set(by_child))
    if len(roots) != 1:
        raise fail(
            None, f"URDF has {len(roots)} root links ({', '.join(roots) or 'none'}): the links must form one tree"
        )
    base = roots[0] if base is None else base
    if base not in links:
        raise fail(None, f"base link '{base}' is not in the URDF (links: {', '.join(sorted(links))})")
    if tip is None:
        leaves = sorted(lk for lk in links if lk not in children and _descends(lk, base, by_child))
        if len(leaves) != 1:
            raise fail(None, f"the URDF branches below '{base}' into {len(leaves)} tips ({', '.join(leaves)}): "
                             "give the tip link (--tip)")  # fmt: skip
        tip = leaves[0]
    if tip not in links:
        raise fail(None, f"tip link '{tip}' is not in the URDF (links: {', '.join(sorted(links))})")
    path = []
    link = tip
    while link != base:
        j = by_child.get(link)
        if j is None:
            raise fail(None, f"tip link '{tip}' does not hang below base link '{base}'")
        path.append(j)
        link = j.parent
    path.reverse()
    T = np.eye(4)
    out: list[ChainJoint] = []
    for j in path:
        where = ("joint", j.name)
        if j.type in ("floating", "planar"):
            raise fail(where, f"joint '{j.name}': type '{j.type}' is not supported (a serial chain's joints are "
                              "revolute, continuous, prismatic or fixed)")  # fmt: skip
        if j.type not in ("revolute", "continuous", "prismatic", "fixed"):
            raise fail(where, f"joint '{j.name}': unknown type '{j.type}'")
        if j.mimic is not None:
            raise fail(where, f"joint '{j.name}': <mimic> is not supported (each joint is driven on its own)")
        origin = np.eye(4) if j.origin is None else np.asarray(j.origin, dtype=float)
        T = T @ origin
        if j.type == "fixed":
            continue
        axis = np.array([1.0, 0.0, 0.0]) if j.axis is None else np.asarray(j.axis, dtype=float)
        norm = float(np.linalg.norm(axis))
        if not (math.isfinite(norm) and norm > _EPS):
            raise fail(where, f"joint '{j.name}': its axis {axis.tolist()} has no direction")
        lim = j.limit
        if j.type == "continuous":
            lower, upper = -CONTINUOUS_RANGE, CONTINUOUS_RANGE
        else:
            if lim is None or lim.lower is None or lim.upper is None:
                raise fail(where, f"joint '{j.name}': a {j.type} joint needs <limit lower= upper=>")
            lower, upper = float(lim.lower), float(lim.upper)
            if not lower < upper:
                raise fail(where, f"joint '{j.name}': limit lower ({lower:g}) must be less than upper ({upper:g})")
        speed = None if lim is None or lim.velocity is None else float(lim.velocity)
        if speed is None or not speed > 0:
            raise fail(where, f"joint '{j.name}': no positive <limit velocity=>; Bosun needs each joint's speed limit")
        out.append(
            ChainJoint(
                name=j.name, kind="prismatic" if j.type == "prismatic" else "revolute", point=T[:3, 3].copy(),
                axis=T[:3, :3] @ (axis / norm), lower=lower, upper=upper, speed=speed, line=lines.get(where),
            )
        )  # fmt: skip
    if not out:
        raise fail(None, f"no revolute, continuous or prismatic joint between '{base}' and '{tip}'")
    return UrdfChain(robot=robot.name or "robot", base=base, tip=tip, joints=tuple(out), T_base_tip=T)


def _descends(link: str, base: str, by_child: dict) -> bool:
    while link != base:
        j = by_child.get(link)
        if j is None:
            return False
        link = j.parent
    return True


def _unit(v: NDArray[np.float64]) -> NDArray[np.float64]:
    return v / float(np.linalg.norm(v))


def _angle(a: NDArray, b: NDArray, about: NDArray) -> float:
    """The angle from unit vector a to unit vector b about the unit axis ``about`` (both ⊥ to it)."""
    return math.atan2(float(np.cross(a, b) @ about), float(a @ b))


@dataclass(frozen=True)
class DhRow:
    theta: float
    d: float
    a: float
    alpha: float


def dh_table(chain: UrdfChain) -> tuple[NDArray[np.float64], list[DhRow], NDArray[np.float64]]:
    """The standard DH table of the chain at q = 0 (module text): T_base_0 (frame 0 in the base link), the rows
    (θ and d at q = 0: the joints' offsets), and T_n_tip (the tip in frame n)."""
    J = chain.joints
    z = J[0].axis
    o = J[0].point
    ref = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = _unit(ref - (ref @ z) * z)  # the base link's x on the first axis's plane
    x0 = x
    rows: list[DhRow] = []
    for k, nxt in enumerate(J[1:]):
        zn, p = nxt.axis, nxt.point
        c = np.cross(z, zn)
        if float(np.linalg.norm(c)) > _EPS:  # skew or meeting: the common normal's feet on both lines
            w = p - o
            b = float(z @ zn)
            denom = 1.0 - b * b
            s = (float(w @ z) - b * float(w @ zn)) / denom
            t = (b * float(w @ z) - float(w @ zn)) / denom
            foot, on = o + s * z, p + t * zn
            gap = on - foot
            if float(np.linalg.norm(gap)) > _EPS:
                xn = _unit(gap)
            else:  # the axes meet: x either way along z_{i−1} × z_i, the one nearer the last x (θ offset small)
                xn = _unit(c) if float(_unit(c) @ x) >= 0.0 else -_unit(c)
        else:  # parallel: the normal through the last origin
            foot = o
            on = p + float((o - p) @ zn) * zn
            gap = on - foot
            xn = _unit(gap) if float(np.linalg.norm(gap)) > _EPS else x
        if k == 0:  # frame 0's x is free: along frame 1's, so the first joint's θ at q = 0 is 0
            x = x0 = xn
        d = float((foot - o) @ z)
        a = float((on - foot) @ xn)
        rows.append(DhRow(theta=_angle(x, xn, z), d=d, a=a, alpha=_angle(z, zn, xn)))
        z, o, x = zn, on, xn
    rows.append(DhRow(theta=0.0, d=0.0, a=0.0, alpha=0.0))  # frame n: frame n − 1 moved by the last joint
    T0 = np.eye(4)
    z0 = J[0].axis
    T0[:3, 0], T0[:3, 1], T0[:3, 2], T0[:3, 3] = x0, np.cross(z0, x0), z0, J[0].point
    rows = [DhRow(*(0.0 if abs(v) < 1e-14 else v for v in (r.theta, r.d, r.a, r.alpha))) for r in rows]
    Tn = np.eye(4)
    Tn[:3, 0], Tn[:3, 1], Tn[:3, 2], Tn[:3, 3] = x, np.cross(z, x), z, o
    return T0, rows, np.linalg.solve(Tn, chain.T_base_tip)


def _rpy(R: NDArray[np.float64]) -> tuple[float, float, float]:
    """Roll, pitch, yaw of R = Rz(yaw) Ry(pitch) Rx(roll) (the robot file's ``rpy``), the pitch by atan2 (the
    arcsin of :func:`app.geometry.matrix_to_euler_zyx` loses ~1e-8 rad near ±90°, where imported tools often are:
    the import must keep the chain to 1e-12)."""
    pitch = math.atan2(-float(R[2, 0]), math.hypot(float(R[0, 0]), float(R[1, 0])))
    if math.hypot(float(R[0, 0]), float(R[1, 0])) > 1e-12:
        return math.atan2(float(R[2, 1]), float(R[2, 2])), pitch, math.atan2(float(R[1, 0]), float(R[0, 0]))
    return math.atan2(-float(R[1, 2]), float(R[1, 1])), pitch, 0.0  # gimbal lock: yaw taken as 0


def _frame(tag: str, T: NDArray[np.float64]) -> str:
    xyz = " ".join(repr(0.0 if abs(v) < 1e-14 else float(v)) for v in T[:3, 3])
    rpy = " ".join(repr(0.0 if abs(v) < 1e-14 else float(v)) for v in _rpy(T[:3, :3]))
    return f'    <{tag} xyz="{xyz}" rpy="{rpy}"/>\n'


def _esc(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def _identifier(text: str) -> str:
    out = "".join(ch if ch.isalnum() or ch == "_" else "_" for ch in text) or "robot"
    return out if out[0].isalpha() else f"r_{out}"


def robot_xml_from_chain(chain: UrdfChain, name: str, source: str) -> str:
    """The Bosun robot file (XML text) of a URDF chain."""
    T0, rows, Tt = dh_table(chain)
    links = []
    for k, (j, row) in enumerate(zip(chain.joints, rows, strict=True)):
        if j.kind == "revolute":
            dh = f'<dh d="{row.d!r}" a="{row.a!r}" alpha="{row.alpha!r}"/>'
            offset = row.theta
        else:
            dh = f'<dh theta="{row.theta!r}" a="{row.a!r}" alpha="{row.alpha!r}"/>'
            offset = row.d
        lim = f'<limits min="{j.lower!r}" max="{j.upper!r}" speed="{j.speed!r}"/>'
        links.append(
            f'    <link name="{k + 1}" joint="{j.kind}">\n      {dh}\n'
            f'      <joint name="{_esc(_identifier(j.name))}" offset="{offset!r}">{lim}</joint>\n    </link>\n'
        )
    continuous = CONTINUOUS_RANGE
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<robot name="{_esc(name)}" type="serial" angle_unit="rad" length_unit="m">\n'
        f"  <description>{_esc(chain.robot)} from its URDF, the chain from link '{_esc(chain.base)}' to link "
        f"'{_esc(chain.tip)}' ({len(chain.joints)} joints), imported by bosun import urdf.</description>\n"
        f"  <source>{_esc(source)}</source>\n"
        "  <assumptions>The DH frames are the importer's (the common normals of the joint axes at q = 0); joint "
        "names, directions, zeros and limits are the URDF's; a continuous joint is given "
        f"±{continuous:.6g} rad. The links are drawn as solids sized from the joint origins (meshes are not "
        "read).</assumptions>\n"
        "  <serial>\n" + _frame("base", T0) + "".join(links) + _frame("tool", Tt) + "  </serial>\n</robot>\n"
    )


def robot_xml_from_urdf(
    root: etree._Element, label: str, base: str | None = None, tip: str | None = None, name: str | None = None
) -> str:
    """A URDF document (parsed, :func:`is_urdf`) as Bosun robot XML text; ``name`` default: the URDF's robot name
    made an identifier."""
    chain = urdf_chain(root, label, base, tip)
    return robot_xml_from_chain(chain, name or _identifier(chain.robot), f"URDF file {label}, robot '{chain.robot}'")
