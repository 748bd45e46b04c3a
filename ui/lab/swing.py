"""The Motion-Lab's "Load swing" page: the lab HMI's "Pendel Estimator" tab (issue 16, item 4)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QGridLayout, QHBoxLayout, QLabel, QPushButton, QSizePolicy, QVBoxLayout, QWidget

from ui.widgets.buttons import button
from ui.widgets.plots import axis_label, legend, refit, refit_on_show


class SwingPage(QWidget):
    """Anti-swing Activate / Deactivate / Reset, the pendulum states (estimate beside the true swing), the
    error states with the estimator's ±2σ, the damping parameter and the law's tool offset.  ``send(type,
    **fields)`` sends a command to the lab engine; ``on_shown()`` draws the newest data."""

    def __init__(self, send: Callable[..., None], on_shown: Callable[[], None]) -> None:
        super().__init__()
        col = QVBoxLayout(self)
        row = QHBoxLayout()
        self.swing_buttons: dict[str, QPushButton] = {}
        for action, tip in (
            ("activate", "add the anti-swing law's offset to the work point the Comau tracks (VVMC on)"),
            ("deactivate", "the law off: its offset returns to zero along the law (the tool back on the work point)"),
            ("reset", "the estimator back to 'no swing' with its initial covariance (law off, tool back)"),
        ):
            b = button(action.capitalize(), tip, keyboard=False)
            b.clicked.connect(lambda _=False, a=action: send("lab_antisway", action=a))
            b.setMinimumHeight(30)
            self.swing_buttons[action] = b
            row.addWidget(b)
        self.swing_label = QLabel("–")
        self.swing_label.setTextFormat(Qt.RichText)
        self.swing_label.setWordWrap(True)
        row.addWidget(self.swing_label, 1)
        col.addLayout(row)
        red, blue, grey = (230, 90, 80), (90, 140, 240), (150, 150, 150)
        self.swing_state_plot = pg.PlotWidget(title="pendulum states: estimate (dashed) and true swing")
        axis_label(self.swing_state_plot.getPlotItem(), "left", "angle", "deg")
        legend(self.swing_state_plot.getPlotItem(), cols=4)
        self.swing_state_curves = [
            self.swing_state_plot.plot(pen=pg.mkPen(c, width=1.5, style=st), name=n)
            for c, st, n in (
                (red, Qt.SolidLine, "φα"),
                (red, Qt.DashLine, "φα estimate"),
                (blue, Qt.SolidLine, "φβ"),
                (blue, Qt.DashLine, "φβ estimate"),
            )
        ]
        self.swing_err_plot = pg.PlotWidget(title="error states: estimate − true, with the estimator's ±2σ")
        axis_label(self.swing_err_plot.getPlotItem(), "left", "error", "deg")
        legend(self.swing_err_plot.getPlotItem(), cols=3)
        self.swing_err_curves = [
            self.swing_err_plot.plot(pen=pg.mkPen(c, width=w_, style=st), name=n)
            for c, w_, st, n in (
                (red, 1.5, Qt.SolidLine, "α error"),
                (blue, 1.5, Qt.SolidLine, "β error"),
                (grey, 1.0, Qt.DotLine, "±2σ"),
                (grey, 1.0, Qt.DotLine, None),
            )
        ]
        self.swing_off_plot = pg.PlotWidget(title="anti-swing tool offset from the work point (in {d})")
        axis_label(self.swing_off_plot.getPlotItem(), "left", "offset", "mm")
        legend(self.swing_off_plot.getPlotItem(), cols=2)
        self.swing_off_curves = [
            self.swing_off_plot.plot(pen=pg.mkPen(c, width=1.5), name=n) for c, n in ((red, "x"), ((90, 200, 90), "y"))
        ]
        grid = QGridLayout()  # two plots over each other beside the third: the page fits a 1280 × 800 screen
        plots = (self.swing_state_plot, self.swing_err_plot, self.swing_off_plot)
        for p, (r, c, rows) in zip(plots, ((0, 0, 1), (1, 0, 1), (0, 1, 2)), strict=True):
            p.showGrid(x=True, y=True, alpha=0.3)
            axis_label(p.getPlotItem(), "bottom", "t", "s")
            p.setMinimumHeight(120)
            # a plot's size hint (pyqtgraph's 640 × 480) would make the page, and with it every Motion-Lab page,
            # taller than the window: the plots take the height there is, at least their minimum
            p.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Ignored)
            grid.addWidget(p, r, c, rows, 1)
        grid.setColumnStretch(0, 3)
        grid.setColumnStretch(1, 2)
        col.addLayout(grid, 1)

        def shown() -> None:
            on_shown()
            for p in plots:
                refit(p.getPlotItem())

        refit_on_show(self, shown)

    def show_state(self, state) -> None:
        """The buttons the estimator's state allows and its one-line status."""
        sw = getattr(state, "swing", None)
        if sw is None:
            for b in self.swing_buttons.values():
                b.setEnabled(False)
            text = "the load-swing estimator runs on the simulated lab (the real lab's runs in its PLC)"
        else:
            ok = state.vvmc and not state.estop
            self.swing_buttons["activate"].setEnabled(ok and not sw.active)
            self.swing_buttons["deactivate"].setEnabled(sw.active)
            off = 1000 * float(np.max(np.abs(sw.offset)))
            self.swing_buttons["reset"].setEnabled(not sw.active and off < 1.0 and not state.estop)
            if sw.active:
                status = "<b style='color:#3c9'>anti-swing ACTIVE</b>"
            elif not state.vvmc:
                status = "anti-swing off <span style='color:#888'>(needs VVMC on)</span>"
            else:
                status = "anti-swing off"
            if sw.reason and not sw.active:
                status += f" &nbsp; last: {sw.reason}"
            sat = " &nbsp; <b style='color:#f80'>AT ITS LIMIT</b>" if sw.saturated else ""
            nees = f" &nbsp; NEES {sw.nees:.1f}" if sw.nees is not None else ""
            text = (
                f"{status} &nbsp; estimator: {sw.measurement}, damping c = {sw.damping:g} /s &nbsp; LQR designed at "
                f"L = {sw.design_length:g} m, c = {sw.design_damping:g} /s, "
                f"T<sub>s</sub> = {1000 * sw.design_step:g} ms (scheduled over L){nees} &nbsp; offset {off:.1f} mm{sat}"
            )
        if text != self.swing_label.text():
            self.swing_label.setText(text)

    def draw(self, ring) -> None:
        """The plots from the swing ring (nothing before two samples)."""
        if ring.n < 2:
            return
        ts = ring["t"]
        for c, col in zip(self.swing_state_curves, ("alpha", "alpha_hat", "beta", "beta_hat"), strict=True):
            c.setData(ts, ring[col])
        self.swing_err_curves[0].setData(ts, ring["err_a"])
        self.swing_err_curves[1].setData(ts, ring["err_b"])
        two = 2 * np.maximum(ring["sig_a"], ring["sig_b"])
        self.swing_err_curves[2].setData(ts, two)
        self.swing_err_curves[3].setData(ts, -two)
        for c, col in zip(self.swing_off_curves, ("off_x", "off_y"), strict=True):
            c.setData(ts, ring[col])
