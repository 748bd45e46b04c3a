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

from app.models.drawing import machines, mesh, scenes, sea
from app.models.drawing.machines import *  # noqa: F403 - each module's __all__ is its public part
from app.models.drawing.mesh import *  # noqa: F403
from app.models.drawing.scenes import *  # noqa: F403
from app.models.drawing.sea import *  # noqa: F403

__all__ = [*mesh.__all__, *machines.__all__, *sea.__all__, *scenes.__all__]
