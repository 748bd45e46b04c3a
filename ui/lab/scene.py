"""The Motion-Lab's scene page: the lab's solids (platforms, Comau, wire and load) beside the load's swing
and the tool point's error (eqs. 29–30)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyqtgraph as pg
from PyQt5.QtWidgets import QCheckBox, QHBoxLayout, QVBoxLayout, QWidget

from ui.widgets.plots import axis_label, legend, refit, refit_on_show
from ui.widgets.scene_view import DrawnScene, make_view

LAB_TIP = (
    "EM8000 and EM1500 (blue decks, grey legs), Comau (orange) on its pedestal, wire and load (red), "
    "work point (green) [m]"
)


class LabDrawing:
    """The lab's solids from the engine's description (robot file, leg ranges) and scene points."""

    def __init__(self) -> None:
        self.links = None  # the Comau's DH table
        self.leg_min: dict[str, float] = {}

    def set_description(self, desc) -> None:
        from app.models.xml import parse_robot_xml

        self.leg_min = {p.name: float(p.leg_range[0]) for p in desc.platforms if p.leg_range}
        try:
            spec = parse_robot_xml(desc.comau_xml, "comau") if desc.comau_xml else None
        except Exception:  # drawn from the joint origins instead
            spec = None
        self.links = spec.serial.links if spec is not None and spec.serial is not None else None

    def meshes(self, sc) -> list:
        from app.models.drawing import lab_meshes

        plats = []
        for name, p in sc.platforms.items():
            base, top = np.asarray(p["base"], dtype=float), np.asarray(p["top"], dtype=float)
            leg_min = self.leg_min.get(name, 0.8 * float(np.min(np.linalg.norm(top - base, axis=1))))
            plats.append((name, base, top, leg_min))
        frames = np.asarray(sc.robot_frames, dtype=float)
        if self.links is not None and frames.shape == (len(self.links) + 2, 4, 4):
            return lab_meshes(plats, self.links, frames, sc.payload)
        return lab_meshes(plats, None, np.asarray(sc.robot, dtype=float), sc.payload)


def _machines_2d(parent: QWidget) -> QWidget:
    from ui.widgets.machines3d import MachineView2D

    views = [
        ("side", "side: world x – z [m]", ((1, 0, 0), (0, 0, 1))),
        ("top", "top: world x – y [m]", ((1, 0, 0), (0, 1, 0))),
    ]
    m = MachineView2D(parent, views=views, note="Motion-Lab, 2D views (no OpenGL here)")
    m.setToolTip(LAB_TIP)
    return m


def _machines_3d(parent: QWidget) -> QWidget:
    from ui.widgets.machines3d import MachineView3D

    return MachineView3D(parent, tooltip=LAB_TIP)


class LabScene2D(DrawnScene):
    """Without OpenGL: the lab's solids seen from the side (world x – z) and from above (x – y)."""

    kind = "2d"

    def __init__(self) -> None:
        super().__init__(_machines_2d, LabDrawing())
        self.plot = self.machines.plots["side"]["plot"]

    def draw_now(self, sc) -> None:
        meshes = self.draw.meshes(sc)
        m = self.machines
        m.set_meshes(meshes)
        m.set_line("wire", [sc.tool, sc.payload], (235, 235, 235), 1.5)
        m.set_points("goal", [sc.work_point], (50, 220, 80), "+", 14)
        self.fit_once(lambda: m.fit_meshes(meshes))


class LabScene3D(DrawnScene):
    """The lab in OpenGL: platforms as decks on six legs, the Comau on its pedestal, wire and load."""

    kind = "3d"

    def __init__(self) -> None:
        super().__init__(_machines_3d, LabDrawing())
        self.view = self.machines.view
        self.ride = False  # the camera rides with EM1500's deck, the target (issue 30, item 7)

    def set_ride(self, on: bool) -> None:
        self.ride = bool(on)
        if not on:
            self.machines.set_preset(self.machines.preset)

    def draw_now(self, sc) -> None:
        from app.models.drawing import merge

        meshes = self.draw.meshes(sc)
        m = self.machines
        top = (getattr(sc, "platforms", None) or {}).get("em1500", {}).get("top")
        if self.ride and top:
            m.follow(np.mean(np.asarray(top, dtype=float), axis=0))
        m.set_mesh("lab", merge(meshes))
        m.set_line("wire", [sc.tool, sc.payload], (0.92, 0.92, 0.92, 1), 1.5)
        m.set_points("goal", [sc.work_point], (0.2, 0.85, 0.3, 1), 10)
        self.fit_once(lambda: m.fit_meshes(meshes))


def make_lab_scene(use_gl: bool | None) -> QWidget:
    return make_view(LabScene3D, LabScene2D, use_gl)


class ScenePage(QWidget):
    """The "Scene & load" page: the lab drawn (3D, or 2D without OpenGL) beside two plots, the load's swing
    angles and the tool point's offset from the work point in EM1500's frame."""

    def __init__(self, use_gl: bool | None, on_shown: Callable[[], None]) -> None:
        super().__init__()
        lay = QHBoxLayout(self)
        self.scene = make_lab_scene(use_gl)
        lay.addWidget(self.scene, 3)
        plots = QVBoxLayout()
        self.ride = QCheckBox("camera rides EM1500's deck")
        self.ride.setToolTip("the 3D camera looks at EM1500's deck wherever it moves (the target deck)")
        self.ride.toggled.connect(lambda on: getattr(self.scene, "set_ride", lambda _on: None)(on))
        self.ride.setEnabled(hasattr(self.scene, "set_ride"))  # the 2D views are fixed to the lab
        plots.addWidget(self.ride)
        self.swing_plot = pg.PlotWidget(title="load swing (eqs. 29–30)")
        axis_label(self.swing_plot.getPlotItem(), "left", "swing angle", "deg")
        legend(self.swing_plot.getPlotItem(), cols=2)
        self.swing_curves = [
            self.swing_plot.plot(pen=pg.mkPen(c, width=1.5), name=n)
            for c, n in (((230, 90, 80), "φα"), ((90, 140, 240), "φβ"))
        ]
        self.err_plot = pg.PlotWidget(title="tool point − work point in EM1500's frame")
        axis_label(self.err_plot.getPlotItem(), "left", "offset", "mm")
        legend(self.err_plot.getPlotItem(), cols=3)
        self.err_curves = [
            self.err_plot.plot(pen=pg.mkPen(c, width=1.5), name=n)
            for c, n in (((230, 90, 80), "x"), ((90, 200, 90), "y"), ((90, 140, 240), "z"))
        ]
        for p in (self.swing_plot, self.err_plot):
            p.showGrid(x=True, y=True, alpha=0.3)
            axis_label(p.getPlotItem(), "bottom", "t", "s")
            plots.addWidget(p)
        lay.addLayout(plots, 2)

        def shown() -> None:
            on_shown()
            for p in (self.swing_plot, self.err_plot):
                refit(p.getPlotItem())

        refit_on_show(self, shown)

    def draw(self, ring) -> None:
        """The plots from the lab's ring of samples (``ring.n`` ≥ 2)."""
        t = ring["t"]
        for c, col in zip(self.swing_curves, ("alpha", "beta"), strict=True):
            c.setData(t, np.degrees(ring[col]))
        for c, col in zip(self.err_curves, ("err_x", "err_y", "err_z"), strict=True):
            c.setData(t, 1000 * ring[col])
