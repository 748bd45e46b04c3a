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

from app.models.drawing.machines import (
    delta_meshes,
    link_radius,
    load_mesh,
    pedestal,
    serial_links,
    serial_reach,
    serial_robot_meshes,
    stewart_meshes,
    wire,
)
from app.models.drawing.mesh import (
    DECK_COLOR,
    HEAD_COLOR,
    HULL_COLOR,
    JOINT_COLOR,
    LEG_COLOR,
    LINK_COLOR,
    LINK_RADIUS_SHARE,
    LOAD_COLOR,
    MOUNT_COLOR,
    RGBA,
    ROD_COLOR,
    SEA_COLOR,
    SHIP_DECK_COLOR,
    Mesh,
    box,
    convex_hull_2d,
    cylinder,
    dedupe,
    disc,
    extrusion,
    homogeneous_rotation,
    is_closed,
    merge,
    outline,
    plate,
    signed_volume,
    sphere,
    support_polygon,
    up_rotation,
)
from app.models.drawing.scenes import lab_meshes, tac_meshes
from app.models.drawing.sea import (
    WAVE_FIELDS,
    grid_surface,
    hull_mesh,
    sea_profile,
    sea_surface,
    strongest_components,
    wave_elevation,
)

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
    "WAVE_FIELDS",
    "Mesh",
    "box",
    "convex_hull_2d",
    "cylinder",
    "dedupe",
    "delta_meshes",
    "disc",
    "extrusion",
    "grid_surface",
    "homogeneous_rotation",
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
