"""Serial chains, Stewart platforms, the Delta head and the lab's parts as solids."""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import ArrayLike

from app.geometry import rot_x
from app.models.drawing.mesh import (
    DECK_COLOR,
    HEAD_COLOR,
    JOINT_COLOR,
    LEG_COLOR,
    LINK_COLOR,
    LINK_RADIUS_SHARE,
    LOAD_COLOR,
    MOUNT_COLOR,
    RGBA,
    ROD_COLOR,
    Mesh,
    _check_points,
    _unit,
    box,
    cylinder,
    dedupe,
    disc,
    plate,
    sphere,
)

__all__ = [
    "delta_meshes",
    "link_radius",
    "load_mesh",
    "pedestal",
    "serial_links",
    "serial_reach",
    "serial_robot_meshes",
    "stewart_meshes",
    "wire",
]


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
