"""Whole scenes in the display frame (z up): the crane head's and the Motion-Lab's."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from app.geometry import euler_zyx_to_matrix
from app.models.drawing.machines import (
    delta_meshes,
    link_radius,
    load_mesh,
    pedestal,
    serial_links,
    serial_robot_meshes,
    stewart_meshes,
)
from app.models.drawing.mesh import Mesh, box, cylinder, dedupe, homogeneous_rotation, up_rotation
from app.models.drawing.sea import hull_mesh

__all__ = [
    "lab_meshes",
    "tac_meshes",
]


# ---------------------------------------------------------------------------------------------- scenes
def tac_meshes(
    crane_links, crane_frames_b, head_spec, alpha, p_c_t, eta, ship=None, hook=None, deck=None
) -> list[Mesh]:
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
    hook : (3,), optional
        The load's underside in {n} (issue 30, item 3): a 5 t crate standing on it and the wire from the TCP to its
        top are drawn.
    deck : (4, 3), optional
        The target platform's deck corners in {n} (issue 30, item 5): a 1 m thick slab under them.
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
    if hook is not None and len(hook) == 3:
        T_d_t = T_d_b @ F[-1]
        tcp_d = T_d_t[:3, :3] @ np.asarray(p_c_t, dtype=float) + T_d_t[:3, 3]
        hook_d = up_rotation("-z") @ np.asarray(hook, dtype=float)  # {n} (z down) to the display frame (z up)
        top = hook_d + np.array([0.0, 0.0, 1.5])  # the crate's top, where the sling meets the wire
        if np.linalg.norm(top - tcp_d) > 1e-6:
            out.append(cylinder(tcp_d, top, 0.12, 8, color=(0.9, 0.9, 0.9, 1.0), name="wire"))  # seen at 100 m
        crate = hook_d + np.array([0.0, 0.0, 0.75])
        out.append(box(crate, np.eye(3), (2.0, 2.0, 1.5), color=(0.95, 0.75, 0.1, 1.0), name="load"))  # a 5 t crate
    if deck is not None and len(deck) == 4:
        c = np.asarray(deck, dtype=float) @ up_rotation("-z").T
        lo, hi = c.min(axis=0), c.max(axis=0)
        centre = 0.5 * (lo + hi) - np.array([0.0, 0.0, 0.5])
        size = (hi[0] - lo[0], hi[1] - lo[1], 1.0)
        out.append(box(centre, np.eye(3), size, color=(0.35, 0.75, 0.4, 1.0), name="platform"))
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
