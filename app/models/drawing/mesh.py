"""The mesh, its checks and the primitive solids (cylinder, box, sphere, plate), merged and outlined."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "DECK_COLOR",
    "HEAD_COLOR",
    "HULL_COLOR",
    "JOINT_COLOR",
    "LEG_COLOR",
    "LINK_COLOR",
    "LINK_RADIUS_SHARE",
    "LOAD_COLOR",
    "MOUNT_COLOR",
    "RGBA",
    "ROD_COLOR",
    "SEA_COLOR",
    "SHIP_DECK_COLOR",
    "Mesh",
    "box",
    "convex_hull_2d",
    "cylinder",
    "dedupe",
    "disc",
    "extrusion",
    "homogeneous_rotation",
    "is_closed",
    "merge",
    "outline",
    "plate",
    "signed_volume",
    "sphere",
    "support_polygon",
    "up_rotation",
]

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
