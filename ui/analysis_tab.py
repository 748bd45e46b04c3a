"""Analysis tab: error distribution (Fig. 5) and trajectory tracking (Fig. 4) off the GUI thread."""

from __future__ import annotations

import os

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import QThread, pyqtSignal
from PyQt5.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QLabel,
    QProgressBar,
    QPushButton,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from app.analysis.ik_studies import error_distribution, track
from app.errors import BosunError
from app.ik import solver_names
from app.models.registry import load_robot
from ui.glprobe import gl_available
from ui.widgets.files import choose_file


class StudyWorker(QThread):
    """Runs one study in a thread; progress and result come back as signals."""

    progress = pyqtSignal(int, int)
    finished_ok = pyqtSignal(object)
    failed = pyqtSignal(str)

    def __init__(self, kind: str, robot_ref: str, solver: str, grid: int, parent=None) -> None:
        super().__init__(parent)
        self.kind, self.robot_ref, self.solver, self.grid = kind, robot_ref, solver, grid
        self._cancel = False

    def cancel(self) -> None:
        self._cancel = True

    def run(self) -> None:
        try:
            robot = load_robot(self.robot_ref)
            hooks = {"progress": lambda d, t: self.progress.emit(d, t), "cancelled": lambda: self._cancel}
            if self.kind == "distribution":
                result = error_distribution(robot, self.solver, self.grid, **hooks)
            else:
                result = track(robot, self.solver, **hooks)
        except (BosunError, ValueError) as err:
            self.failed.emit(str(err))
            return
        self.finished_ok.emit(result)


class AnalysisTab(QWidget):
    error = pyqtSignal(str, str)

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.robot_ref = "comau_smart5_3dof"
        self.worker: StudyWorker | None = None
        self.result = None
        self.scatter3d = None
        lay = QVBoxLayout(self)
        row = QHBoxLayout()
        self.robot_label = QLabel()
        row.addWidget(self.robot_label)
        self.solver = QComboBox()
        self.solver.addItems(solver_names())
        self.solver.setToolTip("solver to study")
        row.addWidget(QLabel("solver"))
        row.addWidget(self.solver)
        self.grid = QSpinBox()
        self.grid.setRange(2, 20)
        self.grid.setValue(8)
        self.grid.setToolTip("targets per axis of the workspace box (8 → 512 targets, as in the paper)")
        row.addWidget(QLabel("grid"))
        row.addWidget(self.grid)
        self.run_dist = QPushButton("Error distribution")
        self.run_dist.setToolTip("solve the grid³ equally spaced targets of the workspace box (paper Fig. 5)")
        self.run_dist.clicked.connect(lambda: self.start("distribution"))
        self.run_track = QPushButton("Trajectory tracking")
        self.run_track.setToolTip("follow a 20 s path through the workspace, X/Y/Z target vs reached (Fig. 4)")
        self.run_track.clicked.connect(lambda: self.start("tracking"))
        self.cancel = QPushButton("Cancel")
        self.cancel.setEnabled(False)
        self.cancel.setToolTip("stop the running study (the targets done so far are kept)")
        self.cancel.clicked.connect(lambda: self.worker and self.worker.cancel())
        for b in (self.run_dist, self.run_track, self.cancel):
            row.addWidget(b)
        self.progress = QProgressBar()
        self.progress.setToolTip("targets solved")
        row.addWidget(self.progress, 1)
        self.export_csv = QPushButton("Export CSV")
        self.export_csv.setToolTip("write the study's rows to a CSV file")
        self.export_csv.clicked.connect(self.save_csv)
        self.export_png = QPushButton("Export PNG")
        self.export_png.setToolTip("save the plots as a PNG picture")
        self.export_png.clicked.connect(self.save_png)
        for b in (self.export_csv, self.export_png):
            b.setEnabled(False)
            row.addWidget(b)
        lay.addLayout(row)
        self.summary = QLabel("")
        lay.addWidget(self.summary)
        self.glw = pg.GraphicsLayoutWidget()
        lay.addWidget(self.glw, 1)
        self.set_robot(self.robot_ref)

    def set_robot(self, robot_ref: str) -> None:
        self.robot_ref = robot_ref
        self.robot_label.setText(f"robot: {robot_ref}")

    def start(self, kind: str) -> None:
        if self.worker is not None:
            return
        self.worker = StudyWorker(kind, self.robot_ref, self.solver.currentText(), self.grid.value(), self)
        self.worker.progress.connect(lambda d, t: (self.progress.setMaximum(t), self.progress.setValue(d)))
        self.worker.finished_ok.connect(self.show_result)
        self.worker.failed.connect(lambda msg: self.error.emit("Analysis failed", msg))
        self.worker.finished.connect(self._done)
        for b in (self.run_dist, self.run_track):
            b.setEnabled(False)
        self.cancel.setEnabled(True)
        self.progress.setValue(0)
        self.worker.start()

    def _done(self) -> None:
        self.worker = None
        for b in (self.run_dist, self.run_track):
            b.setEnabled(True)
        self.cancel.setEnabled(False)

    def show_result(self, result) -> None:
        self.result = result
        self.glw.clear()
        s = result.summary()
        if hasattr(result, "grid"):
            self.summary.setText(
                f"{s['robot']} / {s['solver']}: {s['targets']} targets, {s['reachable']} reachable, "
                f"{s['success']} solved; median error {s['error_m']['median']:.3g} m"
                + ("" if s["complete"] else "  (cancelled)")
            )
            err = np.log10(np.maximum(result.error, 1e-9))
            lo, hi = float(err.min()), float(max(err.max(), err.min() + 1e-9))
            cmap = pg.colormap.get("viridis")
            self._show_3d_scatter(result.targets, cmap.map((err - lo) / (hi - lo), mode="float"))
            order = np.argsort(-err)  # large errors first, so the small ones are drawn on top
            brushes = [pg.mkBrush(cmap.map((e - lo) / (hi - lo), mode="qcolor")) for e in err[order]]
            for col, (a, b, name) in enumerate(
                ((0, 1, "top x–y [m]"), (0, 2, "side x–z [m]"), (1, 2, "front y–z [m]"))
            ):
                p = self.glw.addPlot(row=0, col=col, title=f"{name}, colour log10 error")
                p.addItem(
                    pg.ScatterPlotItem(
                        result.targets[order, a], result.targets[order, b], brush=brushes, size=7, pen=None
                    )
                )
                p.setAspectLocked(True)
        else:
            self.summary.setText(
                f"{s['robot']} / {s['solver']}: rms error {s['rms_error_m']:.3g} m, "
                f"max {s['max_error_m']:.3g} m over {s['samples']} targets"
            )
            for k, name in enumerate("XYZ"):
                p = self.glw.addPlot(row=k, col=0, title=f"{name} [m]: target (grey) vs reached (orange)")
                p.plot(result.t, result.target[:, k], pen=pg.mkPen((170, 170, 170), width=3))
                p.plot(result.t, result.reached[:, k], pen=pg.mkPen((240, 150, 40), width=1.5))
                p.setLabel("bottom", "t", "s")
        for b in (self.export_csv, self.export_png):
            b.setEnabled(True)

    def _show_3d_scatter(self, points: np.ndarray, colors: np.ndarray) -> None:
        """The paper's 3D scatter coloured by error, where OpenGL is available (the projections always)."""
        if not gl_available():
            return
        import pyqtgraph.opengl as gl

        if self.scatter3d is None:
            self.scatter3d = gl.GLViewWidget()
            self.scatter3d.setToolTip("targets coloured by log10 error (viridis: dark small, yellow large) [m]")
            self.scatter3d.setMinimumHeight(280)
            self.layout().insertWidget(2, self.scatter3d, 1)
        from ui.widgets.view3d import _box_edges

        self.scatter3d.clear()
        lo, hi = points.min(axis=0), points.max(axis=0)
        self.scatter3d.addItem(gl.GLLinePlotItem(pos=_box_edges(lo, hi), color=(0.5, 0.6, 0.9, 0.6), mode="lines"))
        self.scatter3d.addItem(gl.GLScatterPlotItem(pos=points, color=colors, size=8))
        size = float(np.max(hi - lo))
        self.scatter3d.setCameraPosition(
            pos=pg.Vector(*(0.5 * (lo + hi))), distance=5.0 * size, elevation=22, azimuth=-60
        )

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
