"""The manipulator seen in 3D (pyqtgraph.opengl) or, without OpenGL, in top and side views.

Both views take the engine's state snapshot: ``frames`` (joint origins), ``target``,
``tool`` and the workspace ``box``.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PyQt5.QtWidgets import QHBoxLayout, QLabel, QVBoxLayout, QWidget

from ui.glprobe import gl_available

LINK_COLOR = (0.85, 0.55, 0.15, 1.0)
TARGET_COLOR = (0.2, 0.8, 0.2, 1.0)
TOOL_COLOR = (0.9, 0.2, 0.2, 1.0)


def _box_edges(lo, hi) -> np.ndarray:
    """The 12 edges of an axis-aligned box as 24 points (pairs)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    pairs = [(0, 1), (0, 2), (0, 4), (1, 3), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 6), (5, 7), (6, 7)]
    return np.array([c[i] for p in pairs for i in p])


class RobotView3D(QWidget):
    """OpenGL view: links as a thick polyline, joints as dots, target, tool point, workspace box."""

    kind = "3d"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        import pyqtgraph.opengl as gl

        self.gl = gl
        self.view = gl.GLViewWidget()
        self.view.setBackgroundColor((20, 24, 30))
        self.view.setToolTip("3D view: drag to orbit, wheel to zoom. Links (orange), target (green), tool (red) [m]")
        grid = gl.GLGridItem()
        grid.setColor((90, 90, 90, 120))
        self.view.addItem(grid)
        self.grid = grid
        self.links = gl.GLLinePlotItem(pos=np.zeros((2, 3)), color=LINK_COLOR, width=5, antialias=True)
        self.joints = gl.GLScatterPlotItem(pos=np.zeros((1, 3)), color=(0.9, 0.9, 0.9, 1), size=9)
        self.target = gl.GLScatterPlotItem(pos=np.zeros((1, 3)), color=TARGET_COLOR, size=14)
        self.tool = gl.GLScatterPlotItem(pos=np.zeros((1, 3)), color=TOOL_COLOR, size=11)
        self.box = gl.GLLinePlotItem(pos=np.zeros((2, 3)), color=(0.5, 0.6, 0.9, 0.5), width=1, mode="lines")
        for it in (self.box, self.links, self.joints, self.target, self.tool):
            self.view.addItem(it)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.view)
        self._box_key = None
        self.desc = None

    def set_description(self, desc) -> None:
        """The engine's robot and workspace box (its ``description``)."""
        self.desc = desc

    def update_state(self, state) -> None:
        frames = np.asarray(state.frames, dtype=float)
        self.links.setData(pos=frames)
        self.joints.setData(pos=frames[:-1])
        self.target.setData(pos=np.asarray([state.target], dtype=float))
        self.tool.setData(pos=np.asarray([state.tool], dtype=float))
        if self.desc is None or not self.desc.box:
            return
        key = (self.desc.robot, tuple(map(tuple, self.desc.box)))
        if key != self._box_key:
            lo, hi = np.asarray(self.desc.box[0]), np.asarray(self.desc.box[1])
            self.box.setData(pos=_box_edges(lo, hi))
            size = float(np.max(hi - lo))
            self.grid.setSize(size * 1.5, size * 1.5)
            self.grid.setSpacing(size / 10, size / 10)
            c = 0.5 * (lo + hi)
            self.view.setCameraPosition(pos=pg.Vector(*c), distance=1.8 * size, elevation=25, azimuth=-60)
            self._box_key = key

    def grab_image(self):
        return self.view.grabFramebuffer()


class RobotView2D(QWidget):
    """Fallback without OpenGL: top (x–y) and side (x–z) projections."""

    kind = "2d"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setToolTip("No OpenGL here: top (x–y) and side (x–z) views [m]. Links orange, target green, tool red")
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        note = QLabel("2D views (no OpenGL context available)")
        note.setStyleSheet("color: #888")
        lay.addWidget(note)
        row = QHBoxLayout()
        lay.addLayout(row)
        self.plots = {}
        for key, (a, b), title in (("top", (0, 1), "top: x–y [m]"), ("side", (0, 2), "side: x–z [m]")):
            pw = pg.PlotWidget(title=title)
            pw.setAspectLocked(True)
            pw.showGrid(x=True, y=True, alpha=0.3)
            box = pw.plot(pen=pg.mkPen((120, 140, 220), width=1, style=pg.QtCore.Qt.DashLine))
            links = pw.plot(
                pen=pg.mkPen((220, 140, 40), width=4), symbol="o", symbolSize=6, symbolBrush=(230, 230, 230)
            )
            target = pw.plot(pen=None, symbol="o", symbolSize=12, symbolBrush=(50, 200, 50))
            tool = pw.plot(pen=None, symbol="x", symbolSize=12, symbolPen=pg.mkPen((230, 50, 50), width=2))
            pw.disableAutoRange()  # fitted to the workspace box once per robot: axes stay cached
            self.plots[key] = (pw, (a, b), box, links, target, tool)
            row.addWidget(pw)
        self._box_key = None
        self.desc = None

    def set_description(self, desc) -> None:
        """The engine's robot and workspace box (its ``description``)."""
        self.desc = desc

    def update_state(self, state) -> None:
        frames = np.asarray(state.frames, dtype=float)
        box_ = self.desc.box if self.desc is not None and self.desc.box else [state.tool, state.tool]
        lo, hi = np.asarray(box_[0]), np.asarray(box_[1])
        new_box = (state.robot, tuple(lo), tuple(hi))
        for pw, (a, b), box, links, target, tool in self.plots.values():
            links.setData(frames[:, a], frames[:, b])
            target.setData([state.target[a]], [state.target[b]])
            tool.setData([state.tool[a]], [state.tool[b]])
            if new_box != self._box_key and self.desc is not None:
                box.setData([lo[a], hi[a], hi[a], lo[a], lo[a]], [lo[b], lo[b], hi[b], hi[b], lo[b]])
                pw.setRange(xRange=(lo[a], hi[a]), yRange=(lo[b], hi[b]), padding=0.05)
        self._box_key = new_box

    def grab_image(self):
        return self.grab().toImage()


def make_robot_view(parent: QWidget | None = None, use_gl: bool | None = None) -> QWidget:
    """The 3D view when OpenGL works here, else the 2D fallback (never a crash)."""
    if use_gl is None:
        use_gl = gl_available()
    if use_gl:
        try:
            return RobotView3D(parent)
        except Exception:
            pass
    return RobotView2D(parent)
