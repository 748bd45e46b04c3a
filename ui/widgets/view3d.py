"""The teleoperated manipulator drawn as it is built: in 3D (pyqtgraph.opengl) or, without OpenGL, in
top and side projections.

``set_description`` takes the engine's :class:`~app.net.snapshots.TeleopDescription`: its robot file
(``robot_xml``) is parsed with the app's parser, so the links are drawn from the DH table (an L where a
link has both d and a, a radius scaled from the reach, joint housings, base plate) and the right way up
(``<serial up="-z">`` for a chain in a z-down frame such as the offshore crane's vessel frame).
``update_state`` takes a :class:`~app.net.snapshots.TeleopSnapshot`: joint positions ``q`` (the frames
are computed from the same model the engine uses), ``target``, ``tool`` and the workspace ``box``.
Without a usable description the links are drawn between the snapshot's frame origins.
"""

from __future__ import annotations

import numpy as np
from PyQt5.QtWidgets import QWidget

from app.models.drawing import (
    LOAD_COLOR,
    Mesh,
    link_radius,
    merge,
    serial_links,
    serial_robot_meshes,
    up_rotation,
)
from ui.widgets.machines3d import MachineView2D, MachineView3D
from ui.widgets.scene_view import DrawnScene, make_view

LINK_COLOR = (0.85, 0.55, 0.15, 1.0)
TARGET_COLOR = (0.2, 0.8, 0.2, 1.0)
TOOL_COLOR = LOAD_COLOR
TOOLTIP = "Links (orange), joints (dark grey), base (grey), target (green), tool (red), workspace box (blue) [m]"


def _box_edges(lo, hi) -> np.ndarray:
    """The 12 edges of an axis-aligned box as 24 points (pairs)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    pairs = [(0, 1), (0, 2), (0, 4), (1, 3), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 6), (5, 7), (6, 7)]
    return np.array([c[i] for p in pairs for i in p])


class RobotDrawing:
    """What both views draw, from a description and a state: meshes, points and the box in a z-up frame."""

    def __init__(self) -> None:
        self.desc = None
        self.model = None  # SerialRobot of the described robot, or None
        self.R_up = np.eye(3)  # R_display_world

    def set_description(self, desc) -> None:
        self.desc = desc
        self.model, self.R_up = None, np.eye(3)
        xml = getattr(desc, "robot_xml", "") if desc is not None else ""
        if not xml:
            return
        from app.models.serial import SerialRobot
        from app.models.xml import parse_robot_xml

        try:
            spec = parse_robot_xml(xml, desc.robot or "robot")
        except Exception:  # the engine checked the file; a client that cannot read it still draws the origins
            return
        if spec.serial is not None:
            self.model = SerialRobot(spec)
            self.R_up = up_rotation(spec.serial.up)

    def meshes(self, state) -> list[Mesh]:
        """The arm in the display frame (z up)."""
        m = self.model
        if m is not None and state.robot == m.name and len(state.q) == m.n_joints:
            T = np.eye(4)
            T[:3, :3] = self.R_up
            F = np.einsum("ij,kjl->kil", T, m.frames(np.asarray(state.q, dtype=float)))
            return serial_robot_meshes(m.links, F)
        origins = self.up(state.frames)
        if len(origins) < 2:
            return []
        reach = float(np.sum(np.linalg.norm(np.diff(origins, axis=0), axis=1)))
        return serial_links(origins, max(1e-3, 0.03 * reach))

    def up(self, pts) -> np.ndarray:
        return np.asarray(pts, dtype=float).reshape(-1, 3) @ self.R_up.T

    def box(self, state):
        """The workspace box (lo, hi) in the display frame, or None."""
        d = self.desc
        if d is None or not d.box or getattr(d, "robot", state.robot) != state.robot:
            return None
        corners = self.up(_box_edges(d.box[0], d.box[1]))
        return corners.min(axis=0), corners.max(axis=0)

    def radius(self) -> float:
        return link_radius(self.model.links) if self.model is not None else 0.05


class _RobotView(DrawnScene):
    """What both views of the arm share: the engine's robot file and workspace box, a camera (or axes) fitted
    again when the robot or its box changes."""

    def __init__(self, make_machines, parent: QWidget | None = None) -> None:
        super().__init__(make_machines, RobotDrawing(), parent)
        self._fit_key = None
        self.desc = None

    def set_description(self, desc) -> None:
        """The engine's robot file and workspace box (its ``description``)."""
        self.desc = desc
        super().set_description(desc)
        self._fit_key = None

    def update_state(self, state) -> None:
        """Draw a TeleopSnapshot (now if shown, else when next shown)."""
        self.submit(state)


class RobotView3D(_RobotView):
    """OpenGL view: the arm as solids (one mesh), target, tool point, workspace box, scaled grid."""

    kind = "3d"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(lambda w: MachineView3D(w, background=(20, 24, 30), tooltip=TOOLTIP), parent)
        self.view = self.machines.view

    def draw_now(self, state) -> None:
        d = self.draw
        meshes = d.meshes(state)
        self.machines.set_mesh("robot", merge(meshes))
        self.machines.set_points("target", d.up([state.target]) if state.target else np.zeros((0, 3)),
                                 TARGET_COLOR, 14)  # fmt: skip
        self.machines.set_points("tool", d.up([state.tool]) if state.tool else np.zeros((0, 3)), TOOL_COLOR, 11)
        box = d.box(state)
        if box is not None:
            self.machines.set_line("box", _box_edges(*box), (0.5, 0.6, 0.9, 0.5), 1, mode="lines")
        key = (state.robot, None if box is None else tuple(np.round(np.r_[box[0], box[1]], 6)))
        if key != self._fit_key and meshes:  # the camera on the arm (its workspace box may be far larger)
            pts = np.concatenate([m.vertices for m in meshes])
            base_z = float(np.min(np.concatenate([m.vertices[:, 2] for m in meshes if m.name == "base"] or [[0.0]])))
            self.machines.set_extent(pts.min(axis=0), pts.max(axis=0), floor=base_z)
            self._fit_key = key


def _machines_2d(parent: QWidget) -> QWidget:
    m = MachineView2D(
        parent,
        views=[("top", "top: x–y [m]", ((1, 0, 0), (0, 1, 0))), ("side", "side: x–z [m]", ((1, 0, 0), (0, 0, 1)))],
        note="2D views (no OpenGL context available)",
    )
    m.setToolTip("No OpenGL here: top (x–y) and side (x–z) views [m]. " + TOOLTIP)
    return m


class RobotView2D(_RobotView):
    """Fallback without OpenGL: the arm's solids in top (x–y) and side (x–z) projections."""

    kind = "2d"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(_machines_2d, parent)
        self.plots = self.machines.plots

    def draw_now(self, state) -> None:
        d = self.draw
        meshes = d.meshes(state)
        m2 = self.machines
        m2.set_meshes(meshes)
        box = d.box(state)
        if box is not None:
            lo, hi = box
            edges = _box_edges(lo, hi).reshape(-1, 2, 3)
            segs = np.concatenate([np.vstack([e, [[np.nan] * 3]]) for e in edges])
            m2.set_line("box", segs, (120, 140, 220), 1)
        if state.target:
            m2.set_points("target", d.up([state.target]), (50, 200, 50), "o", 12)
        if state.tool:
            m2.set_points("tool", d.up([state.tool]), (230, 50, 50), "x", 12)
        key = (state.robot, None if box is None else tuple(np.round(np.r_[box[0], box[1]], 6)))
        if key != self._fit_key and meshes:
            pts = np.concatenate([m.vertices for m in meshes] + ([np.array(box)] if box is not None else []))
            m2.set_extent(pts.min(axis=0), pts.max(axis=0))
            self._fit_key = key

    def grab_image(self):
        return self.grab().toImage()


def make_robot_view(parent: QWidget | None = None, use_gl: bool | None = None) -> QWidget:
    """The 3D view when OpenGL works here, else the 2D fallback (never a crash)."""
    return make_view(lambda: RobotView3D(parent), lambda: RobotView2D(parent), use_gl)
