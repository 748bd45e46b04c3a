"""Views that draw machines from :mod:`app.models.drawing` meshes: a 3D OpenGL view and its 2D fallback.

:class:`MachineView3D` wraps a pyqtgraph 3D view (a native OpenGL window in a container,
:mod:`ui.widgets.glwindow`) holding named mesh, line and point items, updated in place every frame
(``setMeshData``: one upload per named mesh), with camera presets (iso, top, side, front, reset) and a
floor grid and axes whose scale is printed ("grid 1 m").

:class:`MachineView2D` draws the same meshes without OpenGL: each solid's silhouette (the convex outline
of its projected vertices, :func:`app.models.drawing.support_polygon`) as a filled polygon in side (x–z)
and top (x–y) projections, far solids first, and polylines without repeated points (a repeated
point drew a stray bar across the plot).
"""

from __future__ import annotations

import math

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import QPointF, Qt
from PyQt5.QtGui import QBrush, QColor, QPainterPath, QPen, QPolygonF
from PyQt5.QtWidgets import QGraphicsPathItem, QHBoxLayout, QLabel, QToolButton, QVBoxLayout, QWidget

from app.models.drawing import Mesh, dedupe, support_polygon
from ui.widgets.labels import ElidedLabel

#: camera presets: elevation, azimuth [deg] (pyqtgraph's orbit camera; z is up)
PRESETS = {"iso": (25.0, -60.0), "top": (90.0, -90.0), "side": (0.0, -90.0), "front": (0.0, 0.0)}

SHADER = "bosun_lit"
_VERTEX = """
uniform mat4 u_mvp;
uniform mat3 u_normal;
attribute vec4 a_position;
attribute vec3 a_normal;
attribute vec4 a_color;
varying vec4 v_color;
varying vec3 v_normal;
void main() {
    v_normal = normalize(u_normal * a_normal);
    v_color = a_color;
    gl_Position = u_mvp * a_position;
}
"""
_FRAGMENT = """
#ifdef GL_ES
precision mediump float;
#endif
varying vec4 v_color;
varying vec3 v_normal;
void main() {
    // a key light over the viewer's right shoulder and a weak head light, in eye coordinates
    vec3 n = normalize(v_normal);
    float key = max(dot(n, normalize(vec3(0.4, 0.6, 0.7))), 0.0);
    float head = abs(n.z);
    vec3 rgb = v_color.rgb * (0.30 + 0.55 * key + 0.20 * head);
    gl_FragColor = vec4(min(rgb, vec3(1.0)), v_color.a);
}
"""


def machine_shader() -> str:
    """The name of the mesh shader (registered with pyqtgraph on first use): diffuse light from the front."""
    from pyqtgraph.opengl import shaders

    if SHADER not in shaders.ShaderProgram.names:
        shaders.ShaderProgram(SHADER, [shaders.VertexShader(_VERTEX), shaders.FragmentShader(_FRAGMENT)])
    return SHADER


def nice_step(span: float, parts: float = 8.0) -> float:
    """A 1-2-5 step near span/parts [m] (grid spacing)."""
    raw = max(float(span) / parts, 1e-6)
    mag = 10.0 ** math.floor(math.log10(raw))
    for f in (1.0, 2.0, 5.0, 10.0):
        if raw <= f * mag * 1.0001:
            return f * mag
    return 10.0 * mag


def polyline_2d(uv, tol: float = 1e-9) -> np.ndarray:
    """Projected polyline pieces (separated by NaN rows) without repeated points and without pieces
    that are a single point; pieces stay separated by one NaN row, none at the ends.  (K, 2)."""
    uv = np.asarray(uv, dtype=float).reshape(-1, 2)
    pieces, run = [], []
    for row in uv:
        if np.isnan(row).any():
            pieces.append(run)
            run = []
        elif not run or np.hypot(*(row - run[-1])) > tol:
            run.append(row)
    pieces.append(run)
    out: list[np.ndarray] = []
    for run in (r for r in pieces if len(r) >= 2):
        if out:
            out.append(np.full((1, 2), np.nan))
        out.append(np.array(run))
    return np.concatenate(out) if out else np.zeros((0, 2))


def _bounds(meshes: list[Mesh]) -> tuple[np.ndarray, np.ndarray]:
    pts = np.concatenate([m.vertices for m in meshes if len(m.vertices)]) if meshes else np.zeros((1, 3))
    return pts.min(axis=0), pts.max(axis=0)


class LazyDraw:
    """Mixin for a view that draws only while it is shown (a hidden tab costs nothing): :meth:`submit` keeps
    the newest arguments and calls ``draw_now(*args)`` at once when visible, else when next shown."""

    _pending: tuple | None = None

    def submit(self, *args) -> None:
        self._pending = args
        if self.isVisible():
            self._flush()

    def _flush(self) -> None:
        args, self._pending = self._pending, None
        if args is not None:
            self.draw_now(*args)

    def showEvent(self, ev) -> None:
        super().showEvent(ev)
        self._flush()


class MachineView3D(QWidget):
    """An OpenGL view of named meshes, lines and points, with camera presets and a scaled grid.

    Parameters
    ----------
    background : RGB tuple
    tooltip : str
        What the colours mean, shown on hover.
    """

    def __init__(self, parent: QWidget | None = None, background=(18, 26, 38), tooltip: str = "") -> None:
        super().__init__(parent)
        import pyqtgraph.opengl as gl

        from ui.widgets.glwindow import gl_view

        self.gl = gl
        # a native GL window in a container: the rest of the window stays off OpenGL (ui/widgets/glwindow.py)
        self.view, self.box = gl_view(self, tooltip + ". Drag to orbit, wheel to zoom" if tooltip else "")
        self.view.setBackgroundColor(background)
        self.grid = gl.GLGridItem()
        self.grid.setColor((110, 110, 120, 110))
        self.axes = gl.GLAxisItem()
        self.view.addItem(self.grid)
        self.view.addItem(self.axes)
        self.items: dict[str, object] = {}
        self.center = np.zeros(3)
        self.distance = 10.0
        self.step = 1.0
        self.preset = "iso"

        bar = QHBoxLayout()
        bar.setContentsMargins(4, 2, 4, 2)
        # ends in "…" where the buttons need the room (it was cut under them, and its width was the view's
        # minimum: a 600 px wide 3D view in a 1280 px window)
        self.scale = ElidedLabel("", min_chars=10)
        self.scale.setStyleSheet("color: #aaa")
        self.scale.setToolTip("floor grid spacing; axes at the origin: x blue, y yellow, z green (z is up)")
        bar.addWidget(self.scale, 1)
        self.buttons = {}
        for key, text in (
            ("iso", "Iso"),
            ("top", "Top"),
            ("side", "Side"),
            ("front", "Front"),
            ("reset", "Reset view"),
        ):
            b = QToolButton()
            b.setText(text)
            b.setToolTip("fit the machines and look from the default corner" if key == "reset" else f"{text} view")
            b.clicked.connect(lambda _=False, k=key: self.reset_view() if k == "reset" else self.set_preset(k))
            bar.addWidget(b)
            self.buttons[key] = b
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addLayout(bar)
        lay.addWidget(self.box, 1)
        self._extent: tuple[np.ndarray, np.ndarray] | None = None

    # ------------------------------------------------------------------ items
    def set_mesh(self, name: str, mesh: Mesh | None, translucent: bool = False) -> None:
        """Show (or update) the named mesh; ``None`` or an empty mesh hides it."""
        item = self.items.get(name)
        if mesh is None or len(mesh.faces) == 0:
            if item is not None:
                item.setVisible(False)
            return
        verts = np.ascontiguousarray(mesh.vertices, dtype=np.float32)
        colors = np.ascontiguousarray(mesh.colors(), dtype=np.float32)
        if item is None:
            item = self.gl.GLMeshItem(
                vertexes=verts,
                faces=mesh.faces,
                faceColors=colors,
                smooth=False,
                shader=machine_shader(),
                glOptions="translucent" if translucent else "opaque",
            )
            self.view.addItem(item)
            self.items[name] = item
        else:
            item.setMeshData(vertexes=verts, faces=mesh.faces, faceColors=colors)
            item.setVisible(True)

    def set_line(self, name: str, pts, color=(1, 1, 1, 1), width: float = 2.0, mode: str = "line_strip") -> None:
        """A polyline (``mode="lines"``: segment pairs) in scene coordinates [m]."""
        pts = np.asarray(pts, dtype=float).reshape(-1, 3)
        if mode == "line_strip":
            pts = dedupe(pts)
        item = self.items.get(name)
        if item is None:
            item = self.gl.GLLinePlotItem(pos=pts, color=color, width=width, antialias=True, mode=mode)
            self.view.addItem(item)
            self.items[name] = item
        else:
            item.setData(pos=pts, color=color, width=width)
        item.setVisible(len(pts) >= 2)

    def set_points(self, name: str, pts, color=(1, 1, 1, 1), size: float = 10.0, gl_options: str = "additive") -> None:
        """Round points of ``size`` px; ``gl_options="opaque"``: depth-tested, nearer points cover farther ones
        (and a point drawn later at the same place shows only where it is larger: a ring)."""
        pts = np.asarray(pts, dtype=float).reshape(-1, 3)
        item = self.items.get(name)
        if item is None:
            item = self.gl.GLScatterPlotItem(pos=pts, color=color, size=size, glOptions=gl_options)
            self.view.addItem(item)
            self.items[name] = item
        else:
            item.setData(pos=pts, color=color, size=size)

    # ------------------------------------------------------------------ camera and scale
    def set_extent(self, lo, hi, floor: float | None = None, fit: bool = True) -> None:
        """The region the machines occupy [m]: sizes the grid (at ``floor``, default the lowest z) and the
        axes, and (``fit``) points the camera at it from the current preset."""
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        self._extent = (lo, hi)
        size = float(max(np.max(hi - lo), 1e-3))
        self.step = nice_step(size)
        n = math.ceil(1.5 * size / self.step)
        self.grid.setSize(n * self.step, n * self.step)
        self.grid.setSpacing(self.step, self.step)
        c = 0.5 * (lo + hi)
        z0 = lo[2] if floor is None else floor
        self.grid.resetTransform()
        self.grid.translate(round(c[0] / self.step) * self.step, round(c[1] / self.step) * self.step, z0)
        self.axes.setSize(self.step, self.step, self.step)
        unit = "m" if self.step >= 1 else "cm" if self.step >= 0.01 else "mm"
        value = self.step if unit == "m" else self.step * (100 if unit == "cm" else 1000)
        self.scale.setText(f"grid {value:g} {unit} · axes {value:g} {unit}: x blue, y yellow, z green (up)")
        if fit:
            self.center = c
            self.set_preset(self.preset)

    def fit_distance(self, elevation: float | None = None, azimuth: float | None = None) -> float:
        """The camera distance at which the fitted region's eight corners are all in view, looking from
        ``elevation``, ``azimuth`` [deg] (default: the camera's) at the centre.  pyqtgraph's field of view is
        horizontal: a distance from the size alone cut the machines at the top and bottom of a wide, low
        view (the lab's EM1500 in a 1280×800 window) and the sides of a square one (the error scatter's box)."""
        if self._extent is None:
            return self.distance
        opts = self.view.opts
        e = math.radians(opts["elevation"] if elevation is None else elevation)
        a = math.radians(opts["azimuth"] if azimuth is None else azimuth)
        f = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])  # centre → camera
        r = np.array([-math.sin(a), math.cos(a), 0.0])
        u = np.cross(f, r)
        w, h = max(1, self.box.width()), max(1, self.box.height())
        th = math.tan(0.5 * math.radians(opts.get("fov", 60.0)))  # horizontal half-angle
        tv = th * h / w
        lo, hi = self._extent
        v = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) - self.center
        z_c, x_c, y_c = v @ f, np.abs(v @ r), np.abs(v @ u)
        margin = 1.08
        d = np.max(np.maximum(z_c + margin * x_c / th, z_c + margin * y_c / tv))
        return float(max(d, 1.2 * np.max(z_c) + 1e-3, 1e-3))

    def resizeEvent(self, ev) -> None:
        super().resizeEvent(ev)
        from PyQt5.QtCore import QTimer

        QTimer.singleShot(0, self._refit_distance)  # once the view has its new size

    def _refit_distance(self) -> None:
        """A resized view keeps the machines whole, unless the operator has zoomed (then the zoom stays)."""
        if self._extent is None or abs(self.view.opts["distance"] - self.distance) > 1e-6 * self.distance:
            return
        self.distance = self.fit_distance()
        self.view.setCameraPosition(distance=self.distance)

    def fit_meshes(self, meshes: list[Mesh], floor: float | None = None) -> None:
        """:meth:`set_extent` on the meshes' bounding box."""
        lo, hi = _bounds(meshes)
        self.set_extent(lo, hi, floor)

    def set_preset(self, key: str) -> None:
        """Look from a preset direction (``PRESETS``) at the fitted centre and distance."""
        elevation, azimuth = PRESETS[key]
        self.preset = key
        self.distance = self.fit_distance(elevation, azimuth)
        self.view.setCameraPosition(
            pos=pg.Vector(*self.center), distance=self.distance, elevation=elevation, azimuth=azimuth
        )

    def follow(self, point) -> None:
        """Keep the camera looking at ``point`` (a moving deck it rides with), at its distance and angles."""
        self.view.opts["center"] = pg.Vector(*(float(v) for v in point))
        self.view.update()

    def reset_view(self) -> None:
        self.preset = "iso"
        if self._extent is not None:
            self.set_extent(*self._extent, fit=True)
        else:
            self.set_preset("iso")

    # ------------------------------------------------------------------ pictures
    def project(self, pts) -> np.ndarray:
        """Widget pixel coordinates (column, row) of scene points (K, 3), through the view's camera."""
        pts = np.asarray(pts, dtype=float).reshape(-1, 3)
        w, h = self.view.width(), self.view.height()
        region = (0, 0, w, h)
        m = self.view.projectionMatrix(region, region) * self.view.viewMatrix()
        M = np.array(m.data(), dtype=float).reshape(4, 4).T  # QMatrix4x4.data() is column-major
        hom = np.c_[pts, np.ones(len(pts))] @ M.T
        ndc = hom[:, :3] / hom[:, 3:4]
        return np.column_stack([(ndc[:, 0] + 1) * 0.5 * w, (1 - ndc[:, 1]) * 0.5 * h])

    def grab_image(self):
        return self.view.render_image()


class MachineView2D(QWidget):
    """Without OpenGL: the meshes' silhouettes in two projections (side x–z and top x–y by default).

    Parameters
    ----------
    views : list of (key, title, P)
        P (2, 3): the plot's horizontal and vertical axes as directions in the scene; the viewer
        looks along −(P[0] × P[1]) (side: from −y, top: from +z), and nearer solids cover farther ones.
    note : str
        A line above the plots.
    """

    SIDE = ("side", "side: x–z [m]", ((1, 0, 0), (0, 0, 1)))
    TOP = ("top", "top: x–y [m]", ((1, 0, 0), (0, 1, 0)))

    def __init__(self, parent: QWidget | None = None, views=None, note: str = "", vertical: bool = False) -> None:
        super().__init__(parent)
        views = views if views is not None else [self.SIDE, self.TOP]
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        if note:
            label = QLabel(note)
            label.setStyleSheet("color: #888")
            lay.addWidget(label)
        row = QVBoxLayout() if vertical else QHBoxLayout()  # vertical: one above the other (a narrow column)
        lay.addLayout(row, 1)
        self.plots: dict[str, dict] = {}
        for key, title, P in views:
            pw = pg.PlotWidget(title=title)
            pw.setAspectLocked(True)
            pw.showGrid(x=True, y=True, alpha=0.3)
            pw.disableAutoRange()
            P = np.asarray(P, dtype=float)
            self.plots[key] = {"plot": pw, "P": P, "depth": np.cross(P[0], P[1]), "paths": [], "curves": {}}
            row.addWidget(pw)

    def set_meshes(self, meshes: list[Mesh]) -> None:
        """Every mesh's silhouette as a filled polygon, far ones first.  Neighbours in that order with one
        colour share a path item (their outlines unite: winding fill); items are reused frame to frame."""
        meshes = [m for m in meshes if len(m.vertices)]
        centres = np.array([m.vertices.mean(axis=0) for m in meshes]).reshape(-1, 3)
        colors = [
            tuple(m.face_colors[0]) if m.face_colors is not None and len(m.face_colors) else m.color for m in meshes
        ]
        for v in self.plots.values():
            order = np.argsort(centres @ v["depth"], kind="stable")
            groups: list[tuple[tuple, QPainterPath]] = []
            for k in order:
                poly = support_polygon(meshes[k].vertices @ v["P"].T)
                if len(poly) < 2:
                    continue
                if not groups or groups[-1][0] != colors[k]:
                    path = QPainterPath()
                    path.setFillRule(Qt.WindingFill)
                    groups.append((colors[k], path))
                path = groups[-1][1]
                path.addPolygon(QPolygonF([QPointF(x, y) for x, y in poly.tolist()]))
                path.closeSubpath()
            paths: list[QGraphicsPathItem] = v["paths"]
            while len(paths) < len(groups):
                item = QGraphicsPathItem()
                item.setZValue(-1)
                item.color = None
                v["plot"].addItem(item)
                paths.append(item)
            for item, (rgba, path) in zip(paths, groups, strict=False):
                item.setPath(path)
                if item.color != rgba:  # pens and brushes only when the colour changes
                    color = QColor.fromRgbF(*np.clip(rgba, 0, 1))
                    edge = QPen(color.darker(160))
                    edge.setCosmetic(True)
                    edge.setWidthF(1.0)
                    edge.setJoinStyle(Qt.MiterJoin)
                    item.setPen(edge)
                    item.setBrush(QBrush(color))
                    item.color = rgba
                item.setVisible(True)
            for item in paths[len(groups) :]:
                item.setVisible(False)

    def set_line(
        self, name: str, pts, color=(220, 220, 220), width: float = 1.0, only: str | None = None, fill=None
    ) -> None:
        """A polyline in scene coordinates (K, 3) [m]; NaN rows break it.  In each projection repeated
        points are dropped, and pieces that shrink to a point (a vertical wire seen from above) vanish:
        pyqtgraph draws a zero-length segment as a bar across the plot.  ``only``: in that view alone;
        ``fill``: an RGBA (0–255) brush filling below the line (the sea over a hull's underwater part)."""
        pts = np.asarray(pts, dtype=float).reshape(-1, 3)
        for key, v in self.plots.items():
            if only is not None and key != only:
                continue
            curve = v["curves"].get(name)
            if curve is None:
                curve = v["plot"].plot(pen=pg.mkPen(color, width=width))
                if fill is not None:
                    curve.setFillLevel(-1e5)
                    curve.setBrush(pg.mkBrush(fill))
                v["curves"][name] = curve
            uv = polyline_2d(pts @ v["P"].T, tol=1e-6 * max(1.0, float(np.nanmax(np.abs(pts), initial=1.0))))
            curve.setData(uv[:, 0], uv[:, 1], connect="finite")

    def set_points(self, name: str, pts, color=(50, 220, 80), symbol: str = "o", size: float = 10.0) -> None:
        pts = np.asarray(pts, dtype=float).reshape(-1, 3)
        for v in self.plots.values():
            curve = v["curves"].get(name)
            if curve is None:
                curve = v["plot"].plot(pen=None, symbol=symbol, symbolSize=size, symbolBrush=color, symbolPen=color)
                v["curves"][name] = curve
            uv = pts @ v["P"].T
            curve.setData(uv[:, 0], uv[:, 1])

    def set_extent(self, lo, hi) -> None:
        """Fit every plot to the box [lo, hi] [m] (once per scene: the axes stay cached)."""
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        for v in self.plots.values():
            uv = corners @ v["P"].T
            v["plot"].setRange(xRange=(uv[:, 0].min(), uv[:, 0].max()), yRange=(uv[:, 1].min(), uv[:, 1].max()),
                               padding=0.06)  # fmt: skip

    def fit_meshes(self, meshes: list[Mesh]) -> None:
        self.set_extent(*_bounds(meshes))

    def grab_image(self):
        return self.grab().toImage()
