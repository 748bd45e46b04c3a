"""Solid drawings of the machines as triangle meshes: pure NumPy geometry, no Qt.

Every function returns :class:`Mesh` objects (vertices (N, 3) [m], faces (M, 3) vertex indices,
RGBA colour) in the frame its arguments are given in; the scene builders at the end
(:func:`serial_robot_meshes`, :func:`tac_meshes`, :func:`lab_meshes`) return them in a **display
frame with z up**, so every machine is drawn the right way up whatever its own frames are: a
serial chain's world axis that points up comes from its robot file (``<serial up="-z">``, see
:func:`up_rotation`), the crane-head scene's NED frame {n} is turned half a turn about x
(x north, y west, z up), the lab's world {g} is z-up already.

Solids (cylinders, boxes, spheres, plates, the hull) are closed: every edge is shared by exactly
two faces, in opposite directions, and the faces are ordered counter-clockwise seen from outside
(:func:`is_closed`).  :func:`merge` packs many meshes into one vertex and one face array with a
colour per face, so a view uploads one mesh per frame.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.geometry import euler_zyx_to_matrix, rot_x

RGBA = tuple[float, float, float, float]

LINK_COLOR: RGBA = (0.90, 0.55, 0.15, 1.0)  # orange: the links of a serial arm or crane
JOINT_COLOR: RGBA = (0.30, 0.32, 0.36, 1.0)  # dark grey: joint housings, motors
MOUNT_COLOR: RGBA = (0.55, 0.57, 0.60, 1.0)  # grey: fixed mounts, pedestals, base plates
DECK_COLOR: RGBA = (0.35, 0.60, 0.95, 1.0)  # blue: Stewart platform decks
LEG_COLOR: RGBA = (0.78, 0.80, 0.84, 1.0)  # light grey: Stewart legs
ROD_COLOR: RGBA = (0.92, 0.92, 0.95, 1.0)  # Stewart leg rods, Delta forearms
HEAD_COLOR: RGBA = (0.30, 0.85, 0.90, 1.0)  # cyan: the Delta crane head
LOAD_COLOR: RGBA = (0.95, 0.25, 0.20, 1.0)  # red: the load, the tool point
HULL_COLOR: RGBA = (0.62, 0.16, 0.14, 1.0)  # a supply vessel's red hull
SHIP_DECK_COLOR: RGBA = (0.70, 0.70, 0.68, 1.0)
SEA_COLOR: RGBA = (0.15, 0.38, 0.62, 0.75)

#: a serial link's radius as a share of the chain's reach (sum of |a| and |d| from the first joint on)
LINK_RADIUS_SHARE = 0.03


@dataclass(eq=False)
class Mesh:
    """A triangle mesh.

    Attributes
    ----------
    vertices : ndarray, shape (N, 3)
        Vertex positions [m], in the frame the producing function states.
    faces : ndarray of int, shape (M, 3)
        Vertex indices of each triangle, counter-clockwise seen from outside.
    color : tuple of 4 float
        RGBA in [0, 1], used for every face unless ``face_colors`` is given.
    face_colors : ndarray, shape (M, 4), optional
        A colour per face (what :func:`merge` makes).
    name : str
        What the mesh shows ("link 2", "em8000 deck" …), for views and tests.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int32]
    color: RGBA = LINK_COLOR
    face_colors: NDArray[np.float64] | None = None
    name: str = ""

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices, dtype=float).reshape(-1, 3)
        self.faces = np.asarray(self.faces, dtype=np.int32).reshape(-1, 3)

    def colors(self) -> NDArray[np.float64]:
        """The colour of every face, shape (M, 4)."""
        if self.face_colors is not None:
            return np.asarray(self.face_colors, dtype=float)
        return np.tile(np.asarray(self.color, dtype=float), (len(self.faces), 1))

    def transformed(self, T: ArrayLike) -> Mesh:
        """The mesh moved by a homogeneous transform T (4, 4) or a rotation (3, 3)."""
        T = np.asarray(T, dtype=float)
        R, t = (T[:3, :3], T[:3, 3]) if T.shape == (4, 4) else (T, np.zeros(3))
        return Mesh(self.vertices @ R.T + t, self.faces.copy(), self.color, self.face_colors, self.name)


# ---------------------------------------------------------------------------------------------- checks
def is_closed(mesh: Mesh) -> bool:
    """True when every directed edge appears once and its reverse once (a closed, oriented surface)."""
    f = mesh.faces
    if len(f) == 0:
        return False
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    fwd = {tuple(e) for e in edges.tolist()}
    if len(fwd) != len(edges):
        return False  # an edge used twice in the same direction
    return all((b, a) in fwd for a, b in fwd)


def signed_volume(mesh: Mesh) -> float:
    """Volume enclosed by a closed mesh [m³]; positive when the faces point outwards."""
    v = mesh.vertices[mesh.faces]
    return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)


# ---------------------------------------------------------------------------------------------- primitives
def _unit(v: ArrayLike) -> NDArray[np.float64]:
    v = np.asarray(v, dtype=float)
    n = float(np.linalg.norm(v))
    if not n > 1e-12:
        raise ValueError("a direction of zero length")
    return v / n


def _cross(a, b) -> NDArray[np.float64]:
    """a × b of two 3-vectors (np.cross costs ten times more on one pair)."""
    a0, a1, a2 = (float(x) for x in a)
    b0, b1, b2 = (float(x) for x in b)
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def _perpendicular(axis: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two unit vectors u, w with (u, w, axis) a right-handed orthonormal triad."""
    helper = (1.0, 0.0, 0.0) if abs(axis[0]) < 0.9 else (0.0, 1.0, 0.0)
    u = _unit(_cross(axis, helper))
    return u, _cross(axis, u)


def _check_points(*pts: NDArray[np.float64]) -> None:
    for p in pts:
        if not np.all(np.isfinite(p)):
            raise ValueError("a point of a drawing is not finite")


def _fan(center: int, ring: NDArray[np.int32], reverse: bool) -> NDArray[np.int32]:
    """Triangles (center, ring[k], ring[k+1]) around a closed ring (reversed: the other side)."""
    nxt = np.roll(ring, -1)
    c = np.full_like(ring, center)
    return np.stack([c, nxt, ring] if reverse else [c, ring, nxt], axis=1)


def _band(lower: NDArray[np.int32], upper: NDArray[np.int32]) -> NDArray[np.int32]:
    """Quads between two closed rings of equal length, two triangles each, facing out for CCW rings."""
    lo1, up1 = np.roll(lower, -1), np.roll(upper, -1)
    return np.concatenate([np.stack([lower, lo1, up1], axis=1), np.stack([lower, up1, upper], axis=1)])


def extrusion(bottom: ArrayLike, top: ArrayLike, color: RGBA = MOUNT_COLOR, name: str = "") -> Mesh:
    """A closed solid between two rings of points (a loft): sides, and a fan over each end.

    Parameters
    ----------
    bottom, top : array_like, shape (K, 3)
        Rings of corresponding points [m], each convex and counter-clockwise seen from the ``top``
        side (looking from top towards bottom).
    """
    bottom, top = np.asarray(bottom, dtype=float), np.asarray(top, dtype=float)
    _check_points(bottom, top)
    k = len(bottom)
    if k < 3 or top.shape != bottom.shape:
        raise ValueError("an extrusion needs two rings of the same length, at least 3 points")
    verts = np.vstack([bottom, top, bottom.mean(axis=0), top.mean(axis=0)])
    return Mesh(verts, _extrusion_faces(k), color, name=name)


@lru_cache(maxsize=64)
def _extrusion_faces(k: int) -> NDArray[np.int32]:
    """Faces of :func:`extrusion` for rings of k points (the same for every extrusion of that size; read-only)."""
    lo, hi = np.arange(k, dtype=np.int32), np.arange(k, 2 * k, dtype=np.int32)
    faces = np.concatenate([_band(lo, hi), _fan(2 * k, lo, reverse=True), _fan(2 * k + 1, hi, reverse=False)])
    faces.setflags(write=False)
    return faces


def cylinder(
    p0: ArrayLike, p1: ArrayLike, radius: float, n: int = 12, color: RGBA = LINK_COLOR, name: str = ""
) -> Mesh:
    """A closed cylinder with its axis from p0 to p1.

    Parameters
    ----------
    p0, p1 : array_like, shape (3,)
        Centres of the end faces [m]; they must differ.
    radius : float
        [m], positive.
    n : int
        Sides of the prism that approximates it (at least 3).

    Returns
    -------
    Mesh
        2n + 2 vertices, 4n faces, in the frame of p0 and p1.
    """
    p0, p1 = np.asarray(p0, dtype=float), np.asarray(p1, dtype=float)
    _check_points(p0, p1)
    if not radius > 0 or n < 3:
        raise ValueError("a cylinder needs a positive radius and at least 3 sides")
    axis = _unit(p1 - p0)
    u, w = _perpendicular(axis)
    ang = 2 * np.pi * np.arange(n) / n
    ring = radius * (np.outer(np.cos(ang), u) + np.outer(np.sin(ang), w))
    return extrusion(p0 + ring, p1 + ring, color, name)


def disc(center: ArrayLike, normal: ArrayLike, radius: float, thickness: float, n: int = 24, **kw) -> Mesh:
    """A flat cylinder whose top face lies at ``center``, extending ``thickness`` [m] against ``normal``."""
    c, nrm = np.asarray(center, dtype=float), _unit(normal)
    return cylinder(c - thickness * nrm, c, radius, n, **kw)


def box(center: ArrayLike, R: ArrayLike, size: ArrayLike, color: RGBA = LOAD_COLOR, name: str = "") -> Mesh:
    """A closed box.

    Parameters
    ----------
    center : array_like, shape (3,)
        [m].
    R : array_like, shape (3, 3)
        Orientation: column i is the direction of the box's edge i.
    size : array_like, shape (3,)
        Edge lengths [m], positive.
    """
    c, R, s = np.asarray(center, dtype=float), np.asarray(R, dtype=float), np.asarray(size, dtype=float)
    _check_points(c, R, s)
    if np.any(s <= 0):
        raise ValueError("a box needs positive edge lengths")
    h = 0.5 * s
    ring = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float) * h[:2]
    local_lo = np.column_stack([ring, np.full(4, -h[2])])
    local_hi = np.column_stack([ring, np.full(4, h[2])])
    return extrusion(local_lo @ R.T + c, local_hi @ R.T + c, color, name)


def sphere(center: ArrayLike, radius: float, n: int = 12, color: RGBA = LOAD_COLOR, name: str = "") -> Mesh:
    """A closed UV sphere of ``n`` meridians and n/2 parallels bands [m]."""
    c = np.asarray(center, dtype=float)
    _check_points(c)
    if not radius > 0 or n < 4:
        raise ValueError("a sphere needs a positive radius and at least 4 meridians")
    rings = max(2, n // 2)
    theta = np.pi * np.arange(1, rings) / rings  # polar angles of the parallels
    phi = 2 * np.pi * np.arange(n) / n
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    ring_pts = np.stack([st * np.cos(phi), st * np.sin(phi), np.broadcast_to(ct, (rings - 1, n))], axis=-1)
    verts = np.vstack([[[0, 0, 1]], ring_pts.reshape(-1, 3), [[0, 0, -1]]]) * radius + c
    return Mesh(verts, _sphere_faces(n), color, name=name)


@lru_cache(maxsize=16)
def _sphere_faces(n: int) -> NDArray[np.int32]:
    rings = max(2, n // 2)
    idx = (1 + np.arange((rings - 1) * n, dtype=np.int32)).reshape(rings - 1, n)
    south = (rings - 1) * n + 1
    faces = [_fan(0, idx[0], reverse=False)]  # rings run from the north pole down
    for k in range(rings - 2):
        faces.append(_band(idx[k + 1], idx[k]))
    faces.append(_fan(south, idx[-1], reverse=True))
    out = np.concatenate(faces)
    out.setflags(write=False)
    return out


def plate(
    points: ArrayLike,
    normal: ArrayLike,
    thickness: float,
    margin: float = 0.0,
    color: RGBA = DECK_COLOR,
    name: str = "",
) -> Mesh:
    """A convex slab through points in a plane: its top face holds the points, ``thickness`` below it.

    Parameters
    ----------
    points : array_like, shape (K, 3)
        Points near one plane [m] (e.g. a Stewart platform's six joints), K ≥ 3; the plate is their
        convex hull in that plane.
    normal : array_like, shape (3,)
        The side of the top face; the slab extends from the points' plane against it.
    thickness : float
        [m], positive.
    margin : float
        Every corner pushed this far outwards from the centroid, in the plane [m].
    """
    pts = np.asarray(points, dtype=float)
    _check_points(pts)
    nrm = _unit(normal)
    c = pts.mean(axis=0)
    c = c + nrm * float(np.mean((pts - c) @ nrm))
    u, w = _perpendicular(nrm)
    uv = convex_hull_2d(np.column_stack([(pts - c) @ u, (pts - c) @ w]))  # CCW seen from the normal's side
    if len(uv) < 3 or not thickness > 0:
        raise ValueError("a plate needs points around its centroid and a positive thickness")
    centre = uv.mean(axis=0)
    r = np.linalg.norm(uv - centre, axis=1)
    uv = centre + (uv - centre) * ((r + margin) / np.maximum(r, 1e-12))[:, None]
    top = c + np.outer(uv[:, 0], u) + np.outer(uv[:, 1], w)
    return extrusion(top - thickness * nrm, top, color, name)


def merge(meshes: list[Mesh], name: str = "") -> Mesh:
    """One mesh of many: vertices stacked, face indices shifted, a colour per face.

    Returns
    -------
    Mesh
        ``face_colors`` (M, 4) set; an empty mesh (0 vertices) for an empty list.
    """
    meshes = [m for m in meshes if len(m.faces)]
    if not meshes:
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32), face_colors=np.zeros((0, 4)), name=name)
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets, strict=True)])
    return Mesh(
        np.concatenate([m.vertices for m in meshes]),
        faces,
        meshes[0].color,
        face_colors=np.concatenate([m.colors() for m in meshes]),
        name=name,
    )


def dedupe(points: ArrayLike, tol: float = 1e-9) -> NDArray[np.float64]:
    """A polyline without consecutive repeated points (a repeat draws a stray bar in pyqtgraph); (K, 3)."""
    p = np.asarray(points, dtype=float)
    if len(p) < 2:
        return p.copy()
    keep = np.r_[True, np.linalg.norm(np.diff(p, axis=0), axis=1) > tol]
    return p[keep]


def outline(mesh: Mesh, axes: tuple[int, int] = (0, 2)) -> NDArray[np.float64]:
    """Silhouette of a convex mesh projected on two axes: its convex hull, counter-clockwise.

    The first point is not repeated at the end (a caller closes the polygon itself).

    Parameters
    ----------
    mesh : Mesh
    axes : (int, int) or array_like, shape (2, 3)
        Coordinates kept: (0, 2) the x–z side view, (0, 1) the x–y top view; or a projection
        whose rows are the picture's horizontal and vertical directions in the mesh's frame.

    Returns
    -------
    ndarray, shape (K, 2)
        K ≥ 1; K ≤ 2 when the projection is a point or a segment.
    """
    P = np.asarray(axes, dtype=float)
    uv = mesh.vertices @ P.T if P.shape == (2, 3) else mesh.vertices[:, [int(a) for a in axes]]
    return convex_hull_2d(uv)


def convex_hull_2d(points: ArrayLike) -> NDArray[np.float64]:
    """Convex hull of 2D points, counter-clockwise, first point not repeated (Andrew's monotone chain).

    Returns (K, 2); K ≤ 2 for points that are one point or on one line.
    """
    p = np.round(np.asarray(points, dtype=float).reshape(-1, 2), 9)
    p = p[np.lexsort((p[:, 1], p[:, 0]))].tolist()  # sorted by x, then y; Python floats: a fast loop
    if len(p) <= 2 or p[0] == p[-1]:
        return np.array(p[:1] if p and p[0] == p[-1] else p).reshape(-1, 2)

    def half(points):
        hull: list[list[float]] = []
        for q in points:
            while len(hull) >= 2:
                (ax, ay), (bx, by) = hull[-2], hull[-1]
                if (bx - ax) * (q[1] - ay) - (by - ay) * (q[0] - ax) > 1e-12:
                    break
                hull.pop()
            hull.append(q)
        return hull

    lower, upper = half(p), half(p[::-1])
    return np.array(lower[:-1] + upper[:-1]).reshape(-1, 2)


@lru_cache(maxsize=8)
def _directions(k: int) -> NDArray[np.float64]:
    a = 2 * np.pi * np.arange(k) / k
    return np.stack([np.cos(a), np.sin(a)])


def support_polygon(uv: ArrayLike, k: int = 32) -> NDArray[np.float64]:
    """The points of uv (N, 2) farthest out in k evenly spaced directions, counter-clockwise, none repeated.

    A convex polygon inside the convex hull that has every hull corner whose outer angle exceeds 2π/k: the
    silhouette of a drawn solid at a fraction of :func:`convex_hull_2d`'s cost (one matrix product).
    """
    uv = np.asarray(uv, dtype=float).reshape(-1, 2)
    if len(uv) == 0:
        return uv
    idx = np.argmax(uv @ _directions(k), axis=0)  # in direction order: counter-clockwise
    idx = idx[np.concatenate([[True], idx[1:] != idx[:-1]])]
    if len(idx) > 1 and idx[0] == idx[-1]:
        idx = idx[:-1]
    return uv[idx]


# ---------------------------------------------------------------------------------------------- frames
def up_rotation(up: str = "+z") -> NDArray[np.float64]:
    """R_display_world: the rotation that turns a world whose ``up`` axis points up into a z-up frame.

    "-z" (a z-down frame such as NED or a vessel's {b}) is half a turn about x: x stays, y and z
    change sign (x north, y west, z up for NED).
    """
    table = {
        "+z": np.eye(3),
        "-z": np.diag([1.0, -1.0, -1.0]),
        "+x": np.array([[0.0, 0, -1], [0, 1, 0], [1, 0, 0]]),  # x → z
        "-x": np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]]),
        "+y": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),  # y → z
        "-y": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),
    }
    if up not in table:
        raise ValueError(f"up must be one of {', '.join(table)}, got {up!r}")
    return table[up]


def homogeneous_rotation(R: ArrayLike) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, :3] = R
    return T


# ---------------------------------------------------------------------------------------------- serial chains
def serial_reach(links) -> float:
    """Σ (|a| + |d|) of a DH table from its first moving link on [m] (leading fixed links are mounts)."""
    first = next((i for i, link in enumerate(links) if link.kind != "fixed"), 0)
    return float(sum(abs(link.a) + abs(link.d) for link in links[first:]))


def link_radius(links) -> float:
    """The drawn radius of a chain's links [m]: :data:`LINK_RADIUS_SHARE` of its reach."""
    return max(1e-3, LINK_RADIUS_SHARE * serial_reach(links))


def serial_links(
    frames_world: ArrayLike,
    radius: float,
    kinds: list[str] | None = None,
    taper: float = 0.6,
    n: int = 12,
) -> list[Mesh]:
    """The links of a serial chain as cylinders between its frames.

    Parameters
    ----------
    frames_world : array_like, shape (K, 4, 4) or (K, 3)
        The chain's frames (base, every DH frame, tool; ``SerialRobot.frames``) or only their
        origins [m], in the frame the meshes are wanted in.  With full frames a DH link with both
        d and a is drawn as it is built, an L: d along z_{i-1}, then a along x_i.  Repeated
        origins are skipped.
    radius : float
        Radius of the first link [m]; the last one is ``taper`` times it.
    kinds : list of str, optional
        Each link's joint kind ("revolute", "prismatic", "fixed"); links before the first moving
        one are mounts, drawn thinner in grey.

    Returns
    -------
    list of Mesh
        Cylinders (``name`` "link i" or "mount i") and a sphere at every bend.
    """
    F = np.asarray(frames_world, dtype=float)
    full = F.ndim == 3
    origins = F[:, :3, 3] if full else F.reshape(-1, 3)
    _check_points(origins)
    n_links = len(origins) - 1
    first = 0
    if kinds is not None:
        first = next((i for i, k in enumerate(kinds) if k != "fixed"), 0)
    out: list[Mesh] = []
    for i in range(n_links):
        mount = i < first
        share = i / max(1, n_links - 1)
        r = radius * (1.0 - (1.0 - taper) * share) * (0.45 if mount else 1.0)
        color = MOUNT_COLOR if mount else LINK_COLOR
        label = f"{'mount' if mount else 'link'} {i + 1}"
        o0, o1 = origins[i], origins[i + 1]
        pts = [o0]
        if full:
            z0 = F[i, :3, 2]
            bend = o0 + z0 * float((o1 - o0) @ z0)
            pts.append(bend)
        pts.append(o1)
        pts = dedupe(np.array(pts), tol=1e-6)
        for a, b in itertools.pairwise(pts):
            out.append(cylinder(a, b, r, n, color, label))
        for bend in pts[1:-1]:
            out.append(sphere(bend, r, n, color, f"{label} bend"))
    return out


def serial_robot_meshes(
    links,
    frames_world: ArrayLike,
    radius: float | None = None,
    n: int = 12,
) -> list[Mesh]:
    """A serial robot drawn as it is: base plate, links, joint housings and the tool point.

    Parameters
    ----------
    links : sequence of LinkSpec
        The DH table (``SerialSpec.links``): joint kinds and the reach that sizes the drawing.
    frames_world : array_like, shape (len(links) + 2, 4, 4)
        ``SerialRobot.frames(q)``, moved into the frame wanted (e.g. ``T_display_world @ F``).
    radius : float, optional
        First link radius [m]; default :func:`link_radius`.

    Returns
    -------
    list of Mesh
        Named "base", "link i", "mount i", "joint i", "tool".
    """
    F = np.asarray(frames_world, dtype=float)
    if F.shape != (len(links) + 2, 4, 4):
        raise ValueError(f"{len(links)} links need {len(links) + 2} frames, got shape {F.shape}")
    r = link_radius(links) if radius is None else radius
    kinds = [link.kind for link in links]
    out = serial_links(F, r, kinds, n=n)
    first = next((i for i, k in enumerate(kinds) if k != "fixed"), 0)
    o, z = F[first, :3, 3], F[first, :3, 2]
    out.append(disc(o + 0.6 * r * z, z, 2.0 * r, 0.6 * r, n=2 * n, color=MOUNT_COLOR, name="base"))  # on its floor
    n_links = len(links)
    for i, kind in enumerate(kinds):
        if kind == "fixed":
            continue
        ri = r * (1.0 - 0.4 * i / max(1, n_links - 1))
        o, z = F[i, :3, 3], F[i, :3, 2]
        h = 1.3 * ri if kind == "revolute" else 0.8 * ri
        rr = 1.3 * ri if kind == "revolute" else 1.5 * ri
        if i == first:  # the first joint sits on the base plate: its housing rises from it
            out.append(cylinder(o, o + 2 * h * z, rr, n, JOINT_COLOR, f"joint {i + 1}"))
        else:
            out.append(cylinder(o - h * z, o + h * z, rr, n, JOINT_COLOR, f"joint {i + 1}"))
    out.append(sphere(F[-1, :3, 3], 0.6 * r, n, LOAD_COLOR, "tool"))
    return out


# ---------------------------------------------------------------------------------------------- parallel machines
def stewart_meshes(
    base_pts: ArrayLike,
    top_pts: ArrayLike,
    leg_radius: float | None = None,
    plate_thickness: float | None = None,
    body_length: float | None = None,
    name: str = "stewart",
    n: int = 12,
    deck_extra: ArrayLike | None = None,
) -> list[Mesh]:
    """A Stewart platform: base plate, top deck and six legs (cylinder body and rod).

    Parameters
    ----------
    base_pts, top_pts : array_like, shape (6, 3)
        Lower and upper leg joints [m], in the frame the meshes are wanted in; leg k joins
        ``base_pts[k]`` to ``top_pts[k]``.
    leg_radius, plate_thickness : float, optional
        [m]; default 4 % and 8 % of the deck's joint-circle radius.
    body_length : float, optional
        Length of each leg's cylinder body from the base joint [m]; the rod runs from its end to the
        top joint.  Default: half the shortest leg.
    deck_extra : array_like, shape (K, 3), optional
        More points the deck must cover (a pedestal's footprint) [m].

    Returns
    -------
    list of Mesh
        "<name> base", "<name> deck" (top face in the plane of the top joints, the slab on the
        base's side), "<name> leg k", "<name> rod k", "<name> joint".
    """
    a, b = np.asarray(base_pts, dtype=float), np.asarray(top_pts, dtype=float)
    _check_points(a, b)
    if a.shape != (6, 3) or b.shape != (6, 3):
        raise ValueError("a Stewart platform has six base and six top joints")
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    span = float(np.max(np.linalg.norm(b - cb, axis=1)))
    r = 0.04 * span if leg_radius is None else leg_radius
    t = 0.08 * span if plate_thickness is None else plate_thickness
    legs = b - a
    lengths = np.linalg.norm(legs, axis=1)
    body = 0.5 * float(lengths.min()) if body_length is None else body_length

    def plane_normal(pts, away_from):
        _, _, vt = np.linalg.svd(pts - pts.mean(axis=0))
        nrm = vt[-1]
        return nrm if nrm @ (pts.mean(axis=0) - away_from) > 0 else -nrm

    n_top = plane_normal(b, ca)
    n_base = plane_normal(a, cb)  # points away from the deck: the base slab lies below its joints
    deck_pts = b
    if deck_extra is not None and len(deck_extra):
        extra = np.asarray(deck_extra, dtype=float).reshape(-1, 3)
        deck_pts = np.vstack([b, extra - np.outer((extra - cb) @ n_top, n_top)])  # into the joint plane
    out = [  # the base slab's top face at the base joints, extending away from the deck
        plate(a, -n_base, t, margin=0.35 * span, color=MOUNT_COLOR, name=f"{name} base"),
        plate(deck_pts, n_top, t, margin=0.3 * span, color=DECK_COLOR, name=f"{name} deck"),
    ]
    for k in range(6):
        d = legs[k] / lengths[k]
        mid = a[k] + min(body, 0.95 * lengths[k]) * d
        out.append(cylinder(a[k], mid, r, n, LEG_COLOR, f"{name} leg {k + 1}"))
        out.append(cylinder(mid - 0.05 * lengths[k] * d, b[k], 0.55 * r, n, ROD_COLOR, f"{name} rod {k + 1}"))
    for p in np.vstack([a, b]):
        out.append(sphere(p, 1.5 * r, 8, JOINT_COLOR, f"{name} joint"))
    return out


def delta_meshes(
    spec,
    alpha: ArrayLike,
    p_t: ArrayLike,
    T: ArrayLike | None = None,
    n: int = 12,
) -> list[Mesh]:
    """A Delta mechanism as built (TAC paper Fig. 1): base plate, three arms, parallelogram forearms,
    travelling plate.

    In the head frame {t} (x from the base plate towards the travelling plate) arm i turns in the
    plane of {t_i} = R_x(rot_i) {t} (eq. 1): its shoulder is at R_i [0, −l_k, 0], its elbow at
    R_i [l_a sin α_i, −l_k − l_a cos α_i, 0] (eq. 4 without the l_p shift), and its two parallel
    rods of length l_r reach the plate at p + R_i [0, −l_p, 0] ± w R_i e_z.

    Parameters
    ----------
    spec : DeltaSpec
        l_k, l_a, l_r, l_p [m], arm_rotations (3,) [rad].
    alpha : array_like, shape (3,)
        Arm angles [rad].
    p_t : array_like, shape (3,)
        Travelling-plate centre (the TCP) in {t} [m], e.g. ``DeltaHead.fk(alpha)``.
    T : array_like, shape (4, 4), optional
        Pose of {t} in the frame the meshes are wanted in (default identity).
    """
    alpha, p = np.asarray(alpha, dtype=float), np.asarray(p_t, dtype=float)
    _check_points(alpha, p)
    T = np.eye(4) if T is None else np.asarray(T, dtype=float)
    l_k, l_a, l_r, l_p = spec.l_k, spec.l_a, spec.l_r, spec.l_p
    R = rot_x(np.asarray(spec.arm_rotations, dtype=float))  # (3, 3, 3)
    x = np.array([1.0, 0.0, 0.0])
    ra = 0.06 * l_a  # arm radius
    rr = 0.012 * l_r  # rod radius
    w = 0.12 * l_a  # half the parallelogram's width
    out = [
        disc(np.zeros(3), x, 1.25 * l_k, 0.12 * l_k, n=2 * n, color=JOINT_COLOR, name="head base"),
        disc(p + 0.08 * l_p * x, x, 1.1 * l_p, 0.16 * l_p, n=2 * n, color=HEAD_COLOR, name="head plate"),
        sphere(p, 0.25 * l_p, n, LOAD_COLOR, "head tcp"),
    ]
    for i in range(3):
        Ri = R[i]
        zi = Ri[:, 2]
        shoulder = Ri @ [0.0, -l_k, 0.0]
        elbow = Ri @ [l_a * math.sin(alpha[i]), -l_k - l_a * math.cos(alpha[i]), 0.0]
        att = p + Ri @ [0.0, -l_p, 0.0]
        out.append(cylinder(shoulder - 1.6 * ra * zi, shoulder + 1.6 * ra * zi, 1.4 * ra, n, JOINT_COLOR,
                            f"head motor {i + 1}"))  # fmt: skip
        out.append(cylinder(shoulder, elbow, ra, n, HEAD_COLOR, f"head arm {i + 1}"))
        out.append(cylinder(elbow - 1.1 * w * zi, elbow + 1.1 * w * zi, 0.6 * ra, n, HEAD_COLOR, f"head elbow {i + 1}"))
        for s in (-1.0, 1.0):
            out.append(cylinder(elbow + s * w * zi, att + s * w * zi, rr, 8, ROD_COLOR, f"head rod {i + 1}"))
    return [m.transformed(T) for m in out]


# ---------------------------------------------------------------------------------------------- lab parts
def pedestal(
    T_world_base: ArrayLike,
    deck_point: ArrayLike,
    deck_normal: ArrayLike,
    radius: float,
    name: str = "pedestal",
) -> list[Mesh]:
    """A column from a deck up to a robot's base, and a foot flange on the deck.

    Parameters
    ----------
    T_world_base : array_like, shape (4, 4)
        The robot base frame; the column ends at its origin.
    deck_point, deck_normal : array_like, shape (3,)
        A point of the deck's top plane and its upward normal.
    radius : float
        Column radius [m].

    Returns
    -------
    list of Mesh
        The column (``name``), from the base origin's foot on the deck plane (along the deck
        normal) to the base origin, and the flange ("<name> foot").
    """
    T = np.asarray(T_world_base, dtype=float)
    top, p0, nrm = T[:3, 3], np.asarray(deck_point, dtype=float), _unit(deck_normal)
    foot = top - float((top - p0) @ nrm) * nrm
    return [
        cylinder(foot, top, radius, 20, MOUNT_COLOR, name),
        disc(foot + 0.12 * radius * nrm, nrm, 1.5 * radius, 0.12 * radius, n=20, color=JOINT_COLOR,
             name=f"{name} foot"),
    ]  # fmt: skip


def load_mesh(center: ArrayLike, size: float, color: RGBA = LOAD_COLOR) -> Mesh:
    """The hanging load: a cube of edge ``size`` [m] centred on the point mass, axes of the frame."""
    return box(center, np.eye(3), (size, size, size), color, "load")


def wire(p_top: ArrayLike, p_bottom: ArrayLike, radius: float) -> list[Mesh]:
    """The winch wire from the tool point to the load as a thin cylinder (none when they meet)."""
    a, b = np.asarray(p_top, dtype=float), np.asarray(p_bottom, dtype=float)
    if np.linalg.norm(b - a) < 1e-6:
        return []
    return [cylinder(a, b, radius, 6, ROD_COLOR, "wire")]


# ---------------------------------------------------------------------------------------------- vessel and sea
def hull_mesh(length: float, beam: float, deck_z: float, keel_z: float, n: int = 12) -> Mesh:
    """A ship hull in its body frame {b} (x forward, y starboard, z down, origin at CO) [m].

    Parallel sides over the aft 65 % of the length, a rounded bow (half-beam √(1 − s²) over the
    fore part), a flat deck at ``deck_z`` and a narrower flat bottom at ``keel_z`` that starts a
    little forward of the transom and ends short of the stem (a raked bow).  Deck faces are grey,
    the rest red.  Needs keel_z > deck_z (the deck above the keel in a z-down frame).
    """
    if not (length > 0 and beam > 0 and keel_z > deck_z):
        raise ValueError("a hull needs a positive length and beam and its keel below its deck (z down)")
    s = np.concatenate([[0.0, 0.3, 0.65], 0.65 + 0.35 * np.sin(0.5 * np.pi * np.arange(1, n + 1) / n)])

    def half_beam(s):
        f = np.ones_like(s)
        fore = s > 0.65
        f[fore] = np.sqrt(np.clip(1 - ((s[fore] - 0.65) / 0.35) ** 2, 0, 1))
        return f

    f = half_beam(s)

    def ring(x0, x1, hb, z):
        x = x0 + (x1 - x0) * s
        side = np.column_stack([x, hb * f, np.full_like(x, z)])  # starboard, stern to bow
        port = side[-2::-1] * [1, -1, 1]  # bow excluded, back to the stern
        return np.vstack([side, port[:-1] if f[0] == 0 else port])

    deck = ring(-length / 2, length / 2, beam / 2, deck_z)
    keel = ring(-0.47 * length, 0.38 * length, 0.8 * beam / 2, keel_z)
    # seen from the deck side (−z in {b}) the starboard-first ring runs clockwise: swap for the loft
    m = extrusion(keel, deck, HULL_COLOR, "hull")
    if signed_volume(m) < 0:
        m = Mesh(m.vertices, m.faces[:, ::-1], HULL_COLOR, name="hull")
    colors = m.colors()
    k = len(deck)
    top_fan = np.all(m.faces >= k, axis=1) & np.any(m.faces == 2 * k + 1, axis=1)
    colors[top_fan] = SHIP_DECK_COLOR
    m.face_colors = colors
    return m


def wave_elevation(
    amplitude: ArrayLike,
    omega: ArrayLike,
    k: ArrayLike,
    heading: ArrayLike,
    phase: ArrayLike,
    t: float,
    x: ArrayLike,
    y: ArrayLike,
) -> NDArray[np.float64]:
    """ζ(x, y, t) = Σ a cos(ω t − k (x cos μ + y sin μ) + φ) (app/marine/waves.py), ζ up [m].

    x, y : arrays of one shape (north, east in {n}) [m]; returns that shape.
    """
    a = np.asarray(amplitude, dtype=float)
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    kx = np.asarray(k, dtype=float) * np.cos(heading)
    ky = np.asarray(k, dtype=float) * np.sin(heading)
    arg = np.asarray(omega) * t + np.asarray(phase) - (x[..., None] * kx + y[..., None] * ky)
    return np.cos(arg) @ a


def strongest_components(amplitude: ArrayLike, share: float = 0.99) -> NDArray[np.intp]:
    """Indices of the fewest wave components whose a²/2 add up to ``share`` of the variance."""
    a2 = np.asarray(amplitude, dtype=float) ** 2
    if a2.size == 0:
        return np.zeros(0, dtype=np.intp)
    order = np.argsort(a2)[::-1]
    cum = np.cumsum(a2[order])
    n = int(np.searchsorted(cum, share * cum[-1])) + 1
    return np.sort(order[:n])


#: a ``WaveField``'s arrays, in :func:`wave_elevation`'s order
WAVE_FIELDS = ("amplitude", "omega", "k", "heading_rad", "phase")


def sea_profile(waves, t: float, p0: ArrayLike, p1: ArrayLike, n: int = 80, share: float = 0.99) -> NDArray[np.float64]:
    """The sea surface along the segment p0 → p1 (north, east in {n}) as points (n, 3) in the display frame
    (x north, y west, z up) [m]."""
    s = np.linspace(0.0, 1.0, n)[:, None]
    ne = np.asarray(p0, dtype=float) + s * (np.asarray(p1, dtype=float) - np.asarray(p0, dtype=float))
    keep = strongest_components(waves.amplitude, share)
    parts = (np.asarray(getattr(waves, f), dtype=float)[keep] for f in WAVE_FIELDS)
    zeta = wave_elevation(*parts, t, ne[:, 0], ne[:, 1])
    return np.column_stack([ne[:, 0], -ne[:, 1], zeta])


def grid_surface(x: ArrayLike, y: ArrayLike, z: ArrayLike, color: RGBA = SEA_COLOR, name: str = "sea") -> Mesh:
    """A height field as triangles: vertices (x[j], y[i], z[i, j]), two faces per cell, facing +z.

    x : (nx,), y : (ny,), z : (ny, nx) [m].  Open (a surface, not a solid).
    """
    x, y, z = np.asarray(x, dtype=float), np.asarray(y, dtype=float), np.asarray(z, dtype=float)
    ny, nx = z.shape
    X, Y = np.meshgrid(x, y)
    verts = np.column_stack([X.ravel(), Y.ravel(), z.ravel()])
    idx = np.arange(nx * ny, dtype=np.int32).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return Mesh(verts, faces, color, name=name)


def sea_surface(
    waves, t: float, center: ArrayLike = (0.0, 0.0), size: float = 200.0, n: int = 41, share: float = 0.99
) -> Mesh:
    """The sea around a point as a grid in the display frame (x north, y west, z up) [m].

    Parameters
    ----------
    waves : object with amplitude, omega, k, heading_rad, phase (a ``WaveField``)
        Components in {n}.
    t : float
        Time of the sea record [s].
    center : (2,)
        North, east of the grid centre in {n} [m] (the vessel).
    size : float
        Edge of the square grid [m]; ``n`` × ``n`` vertices.
    share : float
        Only the strongest components that carry this share of the variance are summed (a picture,
        not a measurement: a 200-component sea costs a frame's time otherwise).
    """
    c = np.asarray(center, dtype=float)
    north = c[0] + np.linspace(-size / 2, size / 2, n)
    east = c[1] + np.linspace(-size / 2, size / 2, n)
    N, E = np.meshgrid(north, east)  # rows: east, columns: north
    keep = strongest_components(waves.amplitude, share)
    parts = (np.asarray(getattr(waves, f), dtype=float)[keep] for f in WAVE_FIELDS)
    zeta = wave_elevation(*parts, t, N, E)
    # display: y = −east; flip the rows so y increases along them
    return grid_surface(north, -east[::-1], zeta[::-1])


# ---------------------------------------------------------------------------------------------- scenes
def tac_meshes(crane_links, crane_frames_b, head_spec, alpha, p_c_t, eta, ship=None) -> list[Mesh]:
    """The crane-head scene in the display frame (x north, y west, z up) [m].

    Parameters
    ----------
    crane_links : sequence of LinkSpec
        The offshore crane's DH table (frame 0 is the vessel's {b}).
    crane_frames_b : ndarray, shape (L + 2, 4, 4)
        ``SerialRobot.frames(beta)``, in {b}; the last one is the head's frame {t}.
    head_spec : DeltaSpec
    alpha : (3,), p_c_t : (3,)
        Head arm angles [rad] and TCP in {t} [m].
    eta : (6,)
        Vessel pose in {n}: north, east, down [m], roll, pitch, yaw [rad] (Fossen zyx).
    ship : object with length, beam, deck_z, keel_z, optional
        The hull's box in {b} (a ``ShipBox``); no hull when None.
    """
    eta = np.asarray(eta, dtype=float)
    T_n_b = np.eye(4)
    T_n_b[:3, :3] = euler_zyx_to_matrix(eta[3:6])
    T_n_b[:3, 3] = eta[:3]
    T_d_b = homogeneous_rotation(up_rotation("-z")) @ T_n_b
    F = np.asarray(crane_frames_b, dtype=float)
    out: list[Mesh] = []
    if ship is not None:
        out.append(hull_mesh(ship.length, ship.beam, ship.deck_z, ship.keel_z).transformed(T_d_b))
    # the crane from its base on deck on: the fixed links before it are inside the hull
    crane = serial_robot_meshes(crane_links, np.einsum("ij,kjl->kil", T_d_b, F))
    if ship is not None:
        crane = [m for m in crane if not m.name.startswith("mount")]
    out += [m for m in crane if m.name != "tool"]
    out += delta_meshes(head_spec, alpha, p_c_t, T_d_b @ F[-1])
    return out


def lab_meshes(
    platforms: list[tuple[str, ArrayLike, ArrayLike, float]],
    comau_links,
    comau_frames_g: ArrayLike,
    payload: ArrayLike,
    load_size: float = 0.12,
) -> list[Mesh]:
    """The Motion-Lab in its world frame {g} (z up) [m]: platforms, the robot on its pedestal, the load.

    Parameters
    ----------
    platforms : list of (name, base_pts (6, 3), top_pts (6, 3), leg_min [m])
        The Stewart platforms' leg ends in {g}; the first carries the robot.
    comau_links : sequence of LinkSpec, or None
        The robot's DH table; None draws straight links between frame origins.
    comau_frames_g : array_like, shape (L + 2, 4, 4), or (K, 3) origins when ``comau_links`` is None
        The robot's frames in {g} (``H^g_b1 H^b1_r SerialRobot.frames(q)``); frame 0 is its base.
    payload : (3,)
        The load's centre (the point mass) in {g}.
    load_size : float
        Edge of the load cube [m].

    Returns
    -------
    list of Mesh
        :func:`stewart_meshes` of each platform, the pedestal from the first platform's deck to the
        robot base (:func:`pedestal`), the robot (:func:`serial_robot_meshes` without its tool
        marker) and the load.  The winch wire is a line (tool point to ``payload``) the views draw.
    """
    F = np.asarray(comau_frames_g, dtype=float)
    if comau_links is not None:
        r = link_radius(comau_links)
        robot = [m for m in serial_robot_meshes(comau_links, F, r) if m.name != "tool"]
        T_base = F[0]
    else:
        origins = dedupe(F.reshape(-1, 3))
        r = max(1e-3, 0.03 * float(np.sum(np.linalg.norm(np.diff(origins, axis=0), axis=1))))
        robot = serial_links(origins, r)
        T_base = np.eye(4)
        T_base[:3, 3] = origins[0]
    out: list[Mesh] = []
    for k, (name, base, top, leg_min) in enumerate(platforms):
        extra, column = None, []
        if k == 0:  # the first platform carries the robot: on a pedestal when its base stands above the deck
            top = np.asarray(top, dtype=float)
            c = top.mean(axis=0)
            _, _, vt = np.linalg.svd(top - c)
            nrm = vt[-1] if vt[-1] @ (T_base[:3, 3] - c) > 0 else -vt[-1]
            if float((T_base[:3, 3] - c) @ nrm) > 1e-3:
                column = pedestal(T_base, c, nrm, 1.6 * r)
                extra = column[1].vertices  # the deck reaches under the pedestal's foot
        out += stewart_meshes(base, top, body_length=0.5 * leg_min, name=name, deck_extra=extra)
        out += column
    out += robot
    out.append(load_mesh(payload, load_size))
    return out


__all__ = [
    "Mesh",
    "box",
    "convex_hull_2d",
    "cylinder",
    "dedupe",
    "delta_meshes",
    "disc",
    "extrusion",
    "grid_surface",
    "hull_mesh",
    "is_closed",
    "lab_meshes",
    "link_radius",
    "load_mesh",
    "merge",
    "outline",
    "pedestal",
    "plate",
    "sea_profile",
    "sea_surface",
    "serial_links",
    "serial_reach",
    "serial_robot_meshes",
    "signed_volume",
    "sphere",
    "stewart_meshes",
    "strongest_components",
    "support_polygon",
    "tac_meshes",
    "up_rotation",
    "wave_elevation",
    "wire",
]
