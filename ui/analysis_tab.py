"""Analysis tab: error distribution (Fig. 5) and trajectory tracking (Fig. 4), run by the engine.

The tab is a protocol client like the rest of the window: ``study_start`` asks the teleop engine to
run the study of *its* robot (also one opened by path) in a worker process it owns; progress and the
result arrive as ``study`` messages.  The robot and the solvers that apply come from the engine's
description.
"""

from __future__ import annotations

import os

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QLabel,
    QProgressBar,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from app.analysis.ik_studies import study_from_wire
from ui.glprobe import gl_available
from ui.widgets.buttons import button
from ui.widgets.files import choose_file
from ui.widgets.plots import LEGEND_TEXT, axis_label, legend

UNREACHABLE_PEN = (230, 60, 60)


class AnalysisTab(QWidget):
    error = pyqtSignal(str, str)

    def __init__(self, link=None, parent=None) -> None:
        super().__init__(parent)
        self.link = link
        self.robot_ref = ""
        self.running = False
        self.study_id = 0
        self.result = None
        self.scatter3d = None  # the 3D scatter's GL view (self.scatter holds it, camera buttons and scale)
        self.scatter = None
        self.colorbar = None
        self.projections: list = []
        lay = QVBoxLayout(self)
        row = QHBoxLayout()
        self.robot_label = QLabel()
        self.robot_label.setToolTip("the teleop engine's robot: the study runs on it, in the engine")
        row.addWidget(self.robot_label)
        self.solver = QComboBox()
        self.solver.setToolTip("solver to study (those that apply to this robot)")
        row.addWidget(QLabel("solver"))
        row.addWidget(self.solver)
        self.grid = QSpinBox()
        self.grid.setRange(2, 20)
        self.grid.setValue(8)
        self.grid.setToolTip("targets per axis of the workspace box (8 → 512 targets, as in the paper)")
        row.addWidget(QLabel("grid"))
        row.addWidget(self.grid)
        self.run_dist = button(
            "Error distribution",
            "solve the grid³ equally spaced targets of the workspace box (paper Fig. 5)",
            lambda: self.start("distribution"),
        )
        self.run_track = button(
            "Trajectory tracking",
            "follow a 20 s path through the workspace, X/Y/Z target vs reached (Fig. 4)",
            lambda: self.start("tracking"),
        )
        self.cancel = button(
            "Cancel",
            "stop the running study (the targets done so far are kept)",
            lambda: self.link is not None and self.link.send("study_cancel"),
        )
        self.cancel.setEnabled(False)
        for b in (self.run_dist, self.run_track, self.cancel):
            row.addWidget(b)
        self.progress = QProgressBar()
        self.progress.setToolTip("targets solved")
        self.progress.setFormat("%v / %m targets")
        row.addWidget(self.progress, 1)
        self.export_csv = button("Export CSV", "write the study's rows to a CSV file", self.save_csv)
        self.export_png = button("Export PNG", "save the plots as a PNG picture", self.save_png)
        for b in (self.export_csv, self.export_png):
            b.setEnabled(False)
            row.addWidget(b)
        lay.addLayout(row)
        self.summary = QLabel("")
        lay.addWidget(self.summary)
        # the results: the 3D scatter (where OpenGL works) beside the 2D plots, both the page's full height
        self.body = QHBoxLayout()
        self.body.setContentsMargins(0, 0, 0, 0)
        self.glw = pg.GraphicsLayoutWidget()
        self.glw.setMinimumHeight(200)  # three projections with axes, legends and the colour scale
        self.body.addWidget(self.glw, 3)
        lay.addLayout(self.body, 1)
        self.desc = None
        if link is not None:
            link.described.connect(self.on_description)
            link.study.connect(self.on_study)
            link.reply.connect(self.on_reply)
            if link.description is not None:
                self.on_description(link.description)

    def on_description(self, desc) -> None:
        if getattr(desc, "kind", None) != "teleop":
            return
        self.desc = desc
        self.robot_ref = desc.robot
        self.robot_label.setText(f"robot: {desc.robot}")
        current = self.solver.currentText()
        if [self.solver.itemText(i) for i in range(self.solver.count())] != desc.solvers:
            self.solver.clear()
            self.solver.addItems(desc.solvers)
            if current in desc.solvers:
                self.solver.setCurrentText(current)

    def set_robot(self, robot_ref: str) -> None:
        self.robot_ref = robot_ref
        self.robot_label.setText(f"robot: {robot_ref}")

    def start(self, kind: str) -> None:
        if self.running or self.link is None:
            return
        self.link.send("study_start", study=kind, solver=self.solver.currentText(), grid=self.grid.value())
        self._set_running(True)
        self.progress.setRange(0, 0)  # busy until the first progress message
        self.summary.setText(f"{kind} of {self.robot_ref}: starting in the engine…")

    def _set_running(self, on: bool) -> None:
        self.running = on
        for b in (self.run_dist, self.run_track):
            b.setEnabled(not on)
        self.cancel.setEnabled(on)

    def on_reply(self, re: str, ok: bool, error: str) -> None:
        if re in ("study_start", "study_cancel") and not ok:
            self.error.emit("Analysis", error)
            if re == "study_start":
                self._set_running(False)
                self.progress.setRange(0, 1)
                self.summary.setText("")

    def on_study(self, msg: dict) -> None:
        status = msg.get("status")
        self.study_id = msg.get("id", self.study_id)
        if msg.get("total"):
            self.progress.setRange(0, int(msg["total"]))
            self.progress.setValue(int(msg.get("done", 0)))
        if status == "running":
            self._set_running(True)
            self.summary.setText(f"{msg.get('kind')} of {self.robot_ref}: {msg.get('done')} of {msg.get('total')}")
            return
        self._set_running(False)
        if status == "failed":
            self.progress.setRange(0, 1)
            self.summary.setText(f"study failed: {msg.get('error', '')}")
            self.error.emit("Analysis failed", msg.get("error", "the study failed"))
            return
        if "result" in msg:
            try:
                result = study_from_wire(msg["result"])
            except (KeyError, TypeError, ValueError) as err:
                self.error.emit("Analysis failed", f"the engine's result is not understood: {err}")
                return
            self.show_result(result)

    def show_result(self, result) -> None:
        self.result = result
        self.glw.clear()
        self.colorbar = None
        s = result.summary()
        if hasattr(result, "grid"):
            self.summary.setText(
                f"{s['robot']} / {s['solver']}: {s['targets']} targets, {s['reachable']} reachable, "
                f"{s['success']} solved; median error {s['error_m']['median']:.3g} m"
                + ("" if s["complete"] else "  (cancelled)")
            )
            self._show_distribution(result)
        else:
            self.summary.setText(
                f"{s['robot']} / {s['solver']}: rms error {s['rms_error_m']:.3g} m, "
                f"max {s['max_error_m']:.3g} m over {s['samples']} targets"
            )
            if self.scatter is not None:  # the 3D scatter belongs to a distribution study
                self.scatter.setVisible(False)
            self._show_tracking(result)
        for b in (self.export_csv, self.export_png):
            b.setEnabled(True)

    def _show_tracking(self, result) -> None:
        """X, Y and Z: the target (wide grey) and the reached point, on one time axis."""
        plots = []
        for k, name in enumerate("xyz"):
            p = self.glw.addPlot(row=k, col=0)
            axis_label(p, "left", name, "m")
            p.showGrid(x=True, y=True, alpha=0.25)
            p.getAxis("left").setWidth(58)
            legend(p, cols=2, title=f"tool {name}")
            p.plot(result.t, result.target[:, k], pen=pg.mkPen((170, 170, 170), width=3), name="target")
            p.plot(result.t, result.reached[:, k], pen=pg.mkPen((240, 150, 40), width=1.5), name="reached")
            p.setMinimumHeight(60)
            plots.append(p)
        axis_label(plots[-1], "bottom", "t", "s")
        for p in plots[:-1]:
            p.setXLink(plots[-1])
            p.getAxis("bottom").setStyle(showValues=False)

    def _show_distribution(self, result) -> None:
        """Top, side and front projections coloured by log10 error with a colour scale, fitted to the workspace
        box at equal scale; unreachable targets ringed red; the 3D scatter beside them."""
        if len(result.error) == 0:
            return
        err = np.log10(np.maximum(result.error, 1e-9))
        lo, hi = float(err.min()), float(max(err.max(), err.min() + 1e-9))
        cmap = pg.colormap.get("viridis")
        bad = ~result.reachable
        self._show_3d_scatter(result, cmap.map((err - lo) / (hi - lo), mode="float"), bad)
        order = np.argsort(-err)  # large errors first, so the small ones are drawn on top
        brushes = [pg.mkBrush(cmap.map((e - lo) / (hi - lo), mode="qcolor")) for e in err[order]]
        box_lo = np.minimum(np.asarray(result.box_lower, dtype=float), result.targets.min(axis=0))
        box_hi = np.maximum(np.asarray(result.box_upper, dtype=float), result.targets.max(axis=0))
        self.projections = []
        # one legend above the three projections (a legend in each would be wider than its plot)
        key = pg.LegendItem(colCount=2, frame=False, labelTextSize="9pt", labelTextColor=LEGEND_TEXT)
        self.glw.addItem(key, row=0, col=0, colspan=4)
        self.key = key
        for col, (a, b, name) in enumerate(((0, 1, "top"), (0, 2, "side"), (1, 2, "front"))):
            p = self.glw.addPlot(row=1, col=col)
            p.setTitle(f"{name}: {'xyz'[a]}–{'xyz'[b]}", size="9pt")
            axis_label(p, "bottom", "xyz"[a], "m")
            axis_label(p, "left", "xyz"[b], "m")
            for side in ("bottom", "left"):
                p.getAxis(side).enableAutoSIPrefix(False)  # metres on every axis, as the colour scale
            p.showGrid(x=True, y=True, alpha=0.25)
            p.vb.setFlag(p.vb.GraphicsItemFlag.ItemClipsChildrenToShape, True)  # no mark spills into a neighbour
            dots = pg.ScatterPlotItem(
                result.targets[order, a], result.targets[order, b], brush=brushes, size=7, pen=None
            )
            p.addItem(dots)
            rings = None
            if bad.any():
                rings = pg.ScatterPlotItem(
                    result.targets[bad, a],
                    result.targets[bad, b],
                    brush=None,
                    pen=pg.mkPen(UNREACHABLE_PEN, width=1.5),
                    size=12,
                )
                p.addItem(rings)
            if col == 0:  # the key's dot in the scale's middle colour (the dots' own brush is per target)
                sample = pg.ScatterPlotItem(size=9, pen=None, brush=pg.mkBrush(cmap.map(0.5, mode="qcolor")))
                key.addItem(sample, "target, coloured by its error (scale at the right)")
                if rings is not None:
                    key.addItem(rings, f"red ring: not reachable ({int(bad.sum())} of {len(bad)})")
            # the workspace box at one scale on both axes: nothing squashed, no empty hundreds of metres
            p.setAspectLocked(True)
            p.setRange(xRange=(box_lo[a], box_hi[a]), yRange=(box_lo[b], box_hi[b]), padding=0.06)
            p.disableAutoRange()
            p.setMinimumWidth(120)
            self.projections.append(p)
        bar = pg.ColorBarItem(values=(lo, hi), colorMap=cmap, interactive=False, label="log10 error [m]")
        bar.setToolTip("the targets' colour in every view: log10 of the position error [m]")
        self.glw.addItem(bar, row=1, col=3)
        self.colorbar = bar

    def _show_3d_scatter(self, result, colors: np.ndarray, bad: np.ndarray) -> None:
        """The paper's 3D scatter coloured by error (the projections' colour scale), unreachable targets ringed
        red, the workspace box, a floor grid and axes with their scale, camera presets; the right way up."""
        if not gl_available():
            return
        from ui.widgets.view3d import RobotDrawing, _box_edges

        if self.scatter is None:
            from ui.widgets.machines3d import MachineView3D

            tip = (
                "targets coloured by log10 error (the colour scale on the right), red ring: not reachable, "
                "workspace box (blue) [m]"
            )
            self.scatter = MachineView3D(self, background=(0, 0, 0), tooltip=tip)  # a native GL window
            self.scatter.box.setMinimumSize(160, 160)
            self.scatter3d = self.scatter.view
            self.body.insertWidget(0, self.scatter, 2)
        self.scatter.setVisible(True)
        draw = RobotDrawing()  # a robot in a z-down frame is shown z up, as in the teleop view
        if self.desc is not None and getattr(self.desc, "robot", None) == result.robot:
            draw.set_description(self.desc)
        pts = draw.up(result.targets)
        box = draw.up(_box_edges(result.box_lower, result.box_upper))
        m = self.scatter
        m.set_line("box", box, (0.5, 0.6, 0.9, 0.6), 1, mode="lines")
        # drawn first and opaque: the larger red discs of the unreachable targets behind them show as rings
        m.set_points("targets", pts, colors, 8, gl_options="opaque")
        m.set_points("unreachable", pts[bad] if bad.any() else np.zeros((0, 3)), (0.9, 0.24, 0.24, 1), 14,
                     gl_options="opaque")  # fmt: skip
        lo, hi = np.minimum(box.min(axis=0), pts.min(axis=0)), np.maximum(box.max(axis=0), pts.max(axis=0))
        m.preset = "iso"
        m.set_extent(lo, hi, floor=float(lo[2]))

    def save_csv(self, path: str | None = None) -> None:
        if self.result is None:
            return
        if not path:
            choose_file(self, "Export CSV", os.path.join(os.getcwd(), "study.csv"), "CSV (*.csv)", self.save_csv, True)
            return
        try:
            self.result.write_csv(path)
        except OSError as err:
            self.error.emit("Export failed", str(err))

    def save_png(self, path: str | None = None) -> None:
        if not path:
            choose_file(self, "Export PNG", os.path.join(os.getcwd(), "study.png"), "PNG (*.png)", self.save_png, True)
            return
        if not self.glw.grab().save(path, "PNG"):
            self.error.emit("Export failed", f"could not write {path}")
