"""Live plots fed by engine states: ring buffers, redrawn by a timer (not per sample)."""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import QTimer, pyqtSignal
from PyQt5.QtWidgets import QGridLayout, QLabel, QProgressBar, QVBoxLayout, QWidget

COLORS = [(230, 90, 70), (80, 180, 90), (80, 140, 230), (220, 180, 60), (170, 100, 210), (70, 200, 200)]


class Ring:
    """Fixed-size ring buffer of rows; ``view()`` returns them oldest first."""

    def __init__(self, size: int, width: int) -> None:
        self.data = np.full((size, width), np.nan)
        self.n = 0
        self.i = 0

    def push(self, row) -> None:
        self.data[self.i] = row
        self.i = (self.i + 1) % len(self.data)
        self.n = min(self.n + 1, len(self.data))

    def view(self) -> np.ndarray:
        if self.n < len(self.data):
            return self.data[: self.n]
        return np.roll(self.data, -self.i, axis=0)


class LivePlots(QWidget):
    """X/Y/Z: the operator's command, the solver's target and the reached point; joints with limit
    bands; solver error and time."""

    frame = pyqtSignal()  # emitted after each redraw: other views refresh at the same frame rate

    def __init__(self, seconds: float = 20.0, rate: float = 50.0, fps: float = 30.0, parent=None) -> None:
        super().__init__(parent)
        self.size = int(seconds * rate)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        self.glw = pg.GraphicsLayoutWidget()
        lay.addWidget(self.glw)
        self.p_xyz = self.glw.addPlot(row=0, col=0, title="tool x, y, z [m]")
        self.p_q = self.glw.addPlot(row=1, col=0, title="joints [rad, m] (limits shaded)")
        self.p_s = self.glw.addPlot(row=2, col=0, title="solver error [m] (red), time [ms] (blue)")
        for p in (self.p_xyz, self.p_q, self.p_s):
            p.showGrid(x=True, y=True, alpha=0.25)
            p.setClipToView(True)
            p.setDownsampling(auto=True, mode="peak")
            p.setLabel("bottom", "time before now", "s")
            # a fixed time axis (−window … 0): its ticks are painted once and cached, where a
            # scrolling axis would re-render its text every frame (the main paint cost)
            p.setXRange(-seconds, 0.0, padding=0.0)
            p.disableAutoRange()  # y is re-fitted about once a second in redraw(), for the same reason
        self.p_xyz.setToolTip(
            "tool position in the robot's world frame [m]. Thick dotted: the operator's command (eq. 1 in position "
            "mode; eq. 7 integrated in velocity mode, from the reference when the stick was deflected; absent while "
            "nothing is commanded). Dashed: the solver's target this tick. Solid: the reached tool point."
        )
        self.p_q.setToolTip("joint values [rad or m] with their limits as bands")
        self.p_s.setToolTip("last solve: position error [m] and solve time [ms]")
        self.p_xyz.addLegend(offset=(5, 5), colCount=5)
        grey = (170, 170, 170)
        for label, style, width in (("command", pg.QtCore.Qt.DotLine, 4), ("solver target", pg.QtCore.Qt.DashLine, 1)):
            self.p_xyz.plot([], [], pen=pg.mkPen(grey, width=width, style=style), name=label)  # legend keys
        self.cur_xyz = []
        for k, name in enumerate("xyz"):
            c = COLORS[k]
            self.cur_xyz.append(
                (
                    self.p_xyz.plot(pen=pg.mkPen(c, width=4, style=pg.QtCore.Qt.DotLine), connect="finite"),
                    self.p_xyz.plot(pen=pg.mkPen(c, width=1, style=pg.QtCore.Qt.DashLine)),
                    self.p_xyz.plot(pen=pg.mkPen(c, width=2), name=name),
                )
            )
        self.cur_q: list = []
        self.bands: list = []
        self.cur_err = self.p_s.plot(pen=pg.mkPen((230, 80, 80), width=1.5))
        self.cur_time = self.p_s.plot(pen=pg.mkPen((80, 140, 230), width=1.5))
        self.ring = None
        self.robot = None
        self.desc = None
        self.timer = QTimer(self)
        self.timer.setInterval(int(1000 / fps))
        self.timer.timeout.connect(self.redraw)
        self.timer.start()
        self.frames_drawn = 0

    @staticmethod
    def _fit_y(plot, values: np.ndarray) -> None:
        v = values[np.isfinite(values)]
        if v.size:
            lo, hi = float(v.min()), float(v.max())
            pad = 0.08 * max(hi - lo, 1e-6)
            plot.setYRange(lo - pad, hi + pad, padding=0.0)

    def set_description(self, desc) -> None:
        """Joint names and limits of the engine's robot (its ``description``)."""
        self.desc = desc
        if self.ring is not None:
            self._reset(self.ring.data.shape[1] - 12, self.robot)

    def _reset(self, n: int, robot: str) -> None:
        self.ring = Ring(self.size, 1 + 9 + n + 2)
        self.robot = robot
        desc = self.desc if self.desc is not None and len(self.desc.joint_names) == n else None
        for c in self.cur_q:
            self.p_q.removeItem(c)
        for b in self.bands:
            self.p_q.removeItem(b)
        self.cur_q, self.bands = [], []
        for j in range(n):
            c = COLORS[j % len(COLORS)]
            if desc is not None:
                lo, hi = desc.lower[j], desc.upper[j]
                band = pg.LinearRegionItem(
                    (lo, hi), orientation="horizontal", movable=False, brush=pg.mkBrush(*c, 18), pen=pg.mkPen(*c, 60)
                )
                self.p_q.addItem(band)
                self.bands.append(band)
            name = desc.joint_names[j] if desc is not None else f"q{j + 1}"
            self.cur_q.append(self.p_q.plot(pen=pg.mkPen(c, width=2), name=name))

    def add_state(self, state) -> None:
        if self.ring is None or state.robot != self.robot or len(state.q) != self.ring.data.shape[1] - 12:
            self._reset(len(state.q), state.robot)
        err = state.solver_error
        command = state.command or (np.nan, np.nan, np.nan)
        self.ring.push(
            [
                state.t,
                *command,
                *state.target,
                *state.tool,
                *state.q,
                np.nan if err is None else err,
                1e3 * state.solver_time,
            ]
        )

    def redraw(self) -> None:
        if self.ring is None or self.ring.n == 0 or not self.isVisible():
            return
        d = self.ring.view()
        t = d[:, 0] - d[-1, 0]
        for k, (c_command, c_target, c_tool) in enumerate(self.cur_xyz):
            c_command.setData(t, d[:, 1 + k], connect="finite")
            c_target.setData(t, d[:, 4 + k])
            c_tool.setData(t, d[:, 7 + k])
        for j, c in enumerate(self.cur_q):
            c.setData(t, d[:, 10 + j])
        self.cur_err.setData(t, d[:, -2])
        self.cur_time.setData(t, d[:, -1])
        if self.frames_drawn % 30 == 0:
            self._fit_y(self.p_xyz, d[:, 1:10])
            self._fit_y(self.p_q, d[:, 10:-2])
            self._fit_y(self.p_s, d[:, -2:])
        self.frames_drawn += 1
        self.frame.emit()


class UtilisationBars(QWidget):
    """(q − q_min)/(q_max − q_min) per joint as bars."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.grid = QGridLayout(self)
        self.grid.setContentsMargins(4, 4, 4, 4)
        self.bars: list[QProgressBar] = []
        self.names: tuple = ()

    def update_state(self, state, desc) -> None:
        """Joint positions of a teleop snapshot against the limits of the engine's description."""
        if desc is None or len(desc.joint_names) != len(state.q):
            return
        names = tuple(desc.joint_names)
        if names != self.names:
            while self.grid.count():
                w = self.grid.takeAt(0).widget()
                if w is not None:
                    w.deleteLater()
            self.bars = []
            for j, n in enumerate(names):
                self.grid.addWidget(QLabel(n), j, 0)
                bar = QProgressBar()
                bar.setRange(0, 1000)
                bar.setTextVisible(True)
                bar.setToolTip(f"{n}: utilisation of the joint range, (q − q_min)/(q_max − q_min) [%]")
                self.grid.addWidget(bar, j, 1)
                self.bars.append(bar)
            self.names = names
            self.near = [None] * len(names)
        for j, bar in enumerate(self.bars):
            lo, hi, q = desc.lower[j], desc.upper[j], state.q[j]
            u = (q - lo) / (hi - lo) if hi > lo else 0.0
            value = round(1000 * min(max(u, 0.0), 1.0))
            if value != bar.value():
                bar.setValue(value)
                bar.setFormat(f"{100 * u:.0f} %")
            near = u < 0.05 or u > 0.95
            if near != self.near[j]:  # a style change relayouts: only when crossing the 5 % margin
                self.near[j] = near
                bar.setStyleSheet("QProgressBar::chunk { background: %s; }" % ("#d9534f" if near else "#5cb85c"))
