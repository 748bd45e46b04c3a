"""One Stewart platform's page (EM8000, EM1500): mode buttons, motion source, status, plots, legs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QStackedWidget,
    QVBoxLayout,
    QWidget,
)

from ui.lab.common import (
    DOFS,
    HISTORY_S,
    MOTION_COLOR,
    PLATFORM_COLUMNS,
    SAMPLE_HZ,
    SOURCES,
    STATUS_COLOR,
    STOP_COLOR,
    progress_bar,
    set_bar,
)
from ui.widgets.columns import scroll_column
from ui.widgets.files import choose_file
from ui.widgets.plots import Ring, axis_label, legend, refit, refit_on_show
from ui.widgets.status import MOVING
from ui.widgets.vessel import VesselRow


class PlatformPanel(QWidget):
    """Controls and displays of one Stewart platform."""

    command = pyqtSignal(str, dict)  # message type, fields

    def __init__(self, name: str, title: str) -> None:
        super().__init__()
        self.name = name
        self.ring = Ring(int(HISTORY_S * SAMPLE_HZ), PLATFORM_COLUMNS)
        self._t_last = -math.inf
        self.info = None  # PlatformInfo from the engine's description
        self.limits: tuple[np.ndarray, np.ndarray] | None = None
        self.csv_text: str | None = None
        self.csv_name = ""

        modes = QGroupBox(f"{title}: mode")
        ml = QGridLayout(modes)
        self.buttons = {}
        for i, (action, label) in enumerate(
            (("neutral", "NEUTRAL"), ("settle", "SETTLE"), ("engage", "ENGAGE"), ("disengage", "DISENGAGE"))
        ):
            b = QPushButton(label)
            b.clicked.connect(
                lambda _=False, a=action: self.command.emit("lab_platform", {"platform": name, "action": a})
            )
            self.buttons[action] = b
            ml.addWidget(b, 0, i)
        self.status = QLabel("–")
        self.status.setTextFormat(Qt.RichText)
        self.status.setWordWrap(True)  # a long source line (Hs, Tp, six scales) wraps, never cut at the edge
        ml.addWidget(self.status, 1, 0, 1, 4)
        self.box_label = QLabel("")  # the operational box every command is clipped to (issue 16)
        self.box_label.setWordWrap(True)
        self.box_label.setToolTip(
            "Every motion source (generator, simulation, remote pose, time series) is clipped to the lab's "
            "operational box before the motion filter (the lab PLC's etaRefMin/Max); Table 8 stays the hard limit."
        )
        ml.addWidget(self.box_label, 2, 0, 1, 4)
        self.motion_label = QLabel("Rexroth status: –")  # the Stewart status word (issue 16, item 5)
        self.motion_label.setTextFormat(Qt.RichText)
        self.motion_label.setWordWrap(True)
        self.motion_label.setToolTip(
            "the platform controller's motion status word as the lab HMI shows it: operation state "
            "(E_StewartState, bits 0-3), system status (E_StewartStatus, 4-7) and operation mode (E_StewartOpMode, "
            "24-31); from the PLC, or made by the simulation from its own state (app/plant/simulated.py)"
        )
        ml.addWidget(self.motion_label, 3, 0, 1, 4)
        self._generator_defaults_shown = False

        src = QGroupBox("Motion source")
        sl = QVBoxLayout(src)
        row = QHBoxLayout()
        self.source = QComboBox()
        self.source.addItems([s.upper() for s in SOURCES])
        self.apply = QPushButton("Apply source")
        self.apply.clicked.connect(self.send_source)
        row.addWidget(self.source)
        row.addWidget(self.apply)
        sl.addLayout(row)
        self.stack = QStackedWidget()
        self.stack.addWidget(self._generator())
        self.stack.addWidget(self._simulator())
        self.stack.addWidget(self._remote())
        self.stack.addWidget(self._timeseries())
        self.source.currentIndexChanged.connect(self.stack.setCurrentIndex)
        sl.addWidget(self.stack)

        legs = QGroupBox("Actuator strokes")
        ll = QVBoxLayout(legs)
        self.leg_bars = [progress_bar() for _ in range(6)]
        for b in self.leg_bars:
            ll.addWidget(b)

        self.pos_plot = pg.PlotWidget(title="position (platform frame, z down)")
        self.att_plot = pg.PlotWidget(title="attitude")
        axis_label(self.pos_plot.getPlotItem(), "left", "position", "m")
        axis_label(self.att_plot.getPlotItem(), "left", "angle", "deg")
        colors = ((230, 90, 80), (90, 200, 90), (90, 140, 240))
        for p in (self.pos_plot, self.att_plot):
            legend(p.getPlotItem(), cols=3)
            p.showGrid(x=True, y=True, alpha=0.3)
            p.setDownsampling(auto=True)
            p.setClipToView(True)
            axis_label(p.getPlotItem(), "bottom", "t", "s")
        self.pos_curves = [
            self.pos_plot.plot(pen=pg.mkPen(c, width=1.5), name=n) for c, n in zip(colors, DOFS[:3], strict=True)
        ]
        self.att_curves = [
            self.att_plot.plot(pen=pg.mkPen(c, width=1.5), name=n) for c, n in zip(colors, DOFS[3:], strict=True)
        ]

        left = QVBoxLayout()
        left.addWidget(modes)
        left.addWidget(src)
        left.addWidget(legs)
        left.addStretch(1)
        right = QVBoxLayout()
        right.addWidget(self.pos_plot)
        right.addWidget(self.att_plot)
        lay = QHBoxLayout(self)
        lw = QWidget()
        lw.setLayout(left)
        lay.addWidget(scroll_column(lw, max_width=520))  # the controls scroll, the plots keep the height
        lay.addLayout(right, 1)
        refit_on_show(self, self._shown)

    def _shown(self) -> None:
        self.draw()
        for p in (self.pos_plot, self.att_plot):
            refit(p.getPlotItem())
        refit(self.spec_plot.getPlotItem())

    # ------------------------------------------------------------------ source editors
    def _generator(self) -> QWidget:
        w = QWidget()
        g = QGridLayout(w)
        for j, h in enumerate(("DOF", "amplitude", "frequency [Hz]", "phase [deg]")):
            g.addWidget(QLabel(f"<b>{h}</b>"), 0, j)
        self.gen = []
        for i, dof in enumerate(DOFS):
            amp = QDoubleSpinBox()
            amp.setRange(0.0, 40.0 if i >= 3 else 1.4)
            amp.setDecimals(3)
            amp.setSingleStep(0.01 if i < 3 else 0.5)
            amp.setSuffix(" °" if i >= 3 else " m")
            f = QDoubleSpinBox()  # the lab HMI's ranges (motionlab_plc.json); the engine's description sets them
            f.setRange(0.01, 1.0)
            f.setDecimals(3)
            f.setValue(0.1)
            f.setSingleStep(0.02)
            ph = QDoubleSpinBox()
            ph.setRange(-180, 180)
            ph.setSingleStep(10)
            g.addWidget(QLabel(dof), i + 1, 0)
            for j, box in enumerate((amp, f, ph)):
                g.addWidget(box, i + 1, j + 1)
            self.gen.append((amp, f, ph))
        g.setRowStretch(len(DOFS) + 1, 1)  # the rows stay under their header; spare height goes below
        return w

    def _simulator(self) -> QWidget:
        w = QWidget()
        lay = QHBoxLayout(w)
        form = QFormLayout()
        self.sim_spectrum = QComboBox()
        self.sim_spectrum.addItems(["jonswap", "pm", "torsethaugen"])
        self.sim_hs = QDoubleSpinBox()
        self.sim_hs.setRange(0.1, 15)
        self.sim_hs.setValue(2.0)
        self.sim_hs.setSuffix(" m")
        self.sim_tp = QDoubleSpinBox()
        self.sim_tp.setRange(2, 25)
        self.sim_tp.setValue(8.0)
        self.sim_tp.setSuffix(" s")
        self.sim_heading = QDoubleSpinBox()
        self.sim_heading.setRange(0, 359)
        self.sim_heading.setValue(150.0 if self.name == "em8000" else 90.0)
        self.sim_heading.setSuffix(" °")
        form.addRow("spectrum", self.sim_spectrum)
        form.addRow("Hs", self.sim_hs)
        form.addRow("Tp", self.sim_tp)
        form.addRow("wave heading", self.sim_heading)
        # the wave simulator's vessel (issue 17, item 2): one for the scene, shown in both platforms' panels
        self.vessel = VesselRow(lambda **f: self.command.emit("set_vessel", f))
        self.vessel.error.connect(lambda text: self.command.emit("_error", {"text": f"RAO file not sent: {text}"}))
        form.addRow("vessel", self.vessel)
        self.auto_scale = QCheckBox("auto scale (fit to the limits)")
        self.auto_scale.setChecked(True)
        form.addRow(self.auto_scale)
        self.scales = []
        for dof in DOFS:
            s = QDoubleSpinBox()
            s.setRange(0.0, 10.0)
            s.setDecimals(2)
            s.setValue(1.0)
            s.setEnabled(False)
            form.addRow(f"scale {dof}", s)
            self.scales.append(s)
        self.auto_scale.toggled.connect(lambda on: [s.setEnabled(not on) for s in self.scales])
        lay.addLayout(form)
        self.spec_plot = pg.PlotWidget(title="wave spectrum")
        axis_label(self.spec_plot.getPlotItem(), "bottom", "ω", "rad/s")
        axis_label(self.spec_plot.getPlotItem(), "left", "S(ω)", "m²s")
        legend(self.spec_plot.getPlotItem())
        self.spec_curve = self.spec_plot.plot(
            pen=pg.mkPen((80, 160, 240), width=2), fillLevel=0, brush=(80, 160, 240, 60), name="S(ω) of the sea"
        )
        self.spec_plot.setMinimumWidth(200)
        lay.addWidget(self.spec_plot)
        return w

    def _remote(self) -> QWidget:
        w = QWidget()
        form = QFormLayout(w)
        self.remote = []
        for i, dof in enumerate(DOFS):
            s = QDoubleSpinBox()
            s.setRange(-40 if i >= 3 else -1.4, 40 if i >= 3 else 1.4)
            s.setDecimals(3)
            s.setSingleStep(0.01 if i < 3 else 0.5)
            s.setSuffix(" °" if i >= 3 else " m")
            form.addRow(dof, s)
            self.remote.append(s)
        b = QPushButton("Send pose")
        b.clicked.connect(self.send_remote_pose)
        form.addRow(b)
        form.addRow(QLabel("A client may also send lab_remote_pose messages (docs/protocol.md)."))
        return w

    def _timeseries(self) -> QWidget:
        w = QWidget()
        lay = QVBoxLayout(w)
        b = QPushButton("Load CSV…")
        b.clicked.connect(self.choose_csv)
        self.csv_label = QLabel("columns t, x, y, z, phi, theta, psi (s, m, deg)")
        self.csv_label.setWordWrap(True)
        lay.addWidget(b)
        lay.addWidget(self.csv_label)
        lay.addStretch(1)
        return w

    def choose_csv(self) -> None:
        choose_file(self, "6-DOF time series", "", "CSV (*.csv);;all files (*)", self.load_csv)

    def load_csv(self, path: str) -> None:
        try:
            self.csv_text = Path(path).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as err:
            self.command.emit("_error", {"text": f"cannot read {path}: {err}"})
            return
        self.csv_name = Path(path).name
        self.csv_label.setText(f"{self.csv_name}: {len(self.csv_text.splitlines()) - 1} rows (checked by the engine)")

    # ------------------------------------------------------------------ send
    def send_source(self) -> None:
        src = SOURCES[self.source.currentIndex()]
        fields: dict = {"platform": self.name, "source": src}
        if src == "generator":
            amp = [a.value() if i < 3 else math.radians(a.value()) for i, (a, _, _) in enumerate(self.gen)]
            fields.update(
                amplitude=amp,
                frequency=[f.value() for _, f, _ in self.gen],
                phase=[math.radians(p.value()) for _, _, p in self.gen],
            )
        elif src == "simulation":
            fields.update(
                spectrum=self.sim_spectrum.currentText(),
                hs=float(self.sim_hs.value()),
                tp=float(self.sim_tp.value()),
                heading=float(self.sim_heading.value()),
            )
            if not self.auto_scale.isChecked():
                fields["scale"] = [float(s.value()) for s in self.scales]
        elif src == "timeseries":
            if self.csv_text is None:
                self.command.emit("_error", {"text": "load a CSV file first"})
                return
            fields.update(csv=self.csv_text, name=self.csv_name)
        self.command.emit("lab_source", fields)

    def send_remote_pose(self) -> None:
        eta = [s.value() if i < 3 else math.radians(s.value()) for i, s in enumerate(self.remote)]
        self.command.emit("lab_remote_pose", {"platform": self.name, "eta": eta})

    # ------------------------------------------------------------------ state
    def set_info(self, info) -> None:
        """The platform's static data from the engine's description (leg range, pose boxes, its sea).

        The generator amplitudes range over the smaller side of the operational box and the remote pose
        fields over the box (as on the lab HMI, whose amplitude fields range over etaRefMin…etaRefMax)."""
        self.info = info
        if info.spectrum is not None:
            self.spec_curve.setData(info.spectrum["omega"], info.spectrum["s"])
        lo = info.command_min if info.command_min is not None else info.pose_min
        hi = info.command_max if info.command_max is not None else info.pose_max
        if len(lo) == 6 and len(hi) == 6:
            shown = [
                (v, w) if i < 3 else (math.degrees(v), math.degrees(w))
                for i, (v, w) in enumerate(zip(lo, hi, strict=True))
            ]
            for (amp, _, _), box, (a, b) in zip(self.gen, self.remote, shown, strict=True):
                amp.setRange(0.0, min(-a, b))
                box.setRange(a, b)
            parts = [
                f"{d} {a:+.3g}…{b:+.3g} {'m' if i < 3 else '°'}"
                for i, (d, (a, b)) in enumerate(zip(DOFS, shown, strict=True))
            ]
            self.box_label.setText("operational box (command limit): " + ", ".join(parts))
        self._set_generator(getattr(info, "generator", None))

    def _set_generator(self, g) -> None:
        """The lab HMI's sine generator (issue 16, item 5): frequency and phase ranges and steps always, the
        defaults once (an operator's values stay when the description changes)."""
        if g is None:
            return
        f_lo, f_hi, f_step = g.frequency_range
        p_lo, p_hi, p_step = (math.degrees(v) for v in g.phase_range)
        for _, f, ph in self.gen:
            f.setRange(f_lo, f_hi)
            f.setSingleStep(f_step)
            ph.setRange(p_lo, p_hi)
            ph.setSingleStep(p_step)
        if not self._generator_defaults_shown:
            self._generator_defaults_shown = True
            for i, (amp, f, ph) in enumerate(self.gen):
                to_shown = math.degrees if i >= 3 else float
                amp.setValue(to_shown(g.amplitude[i]))
                f.setValue(g.frequency[i])
                ph.setValue(math.degrees(g.phase[i]))

    def update_state(self, p, t: float, estop: bool = False) -> None:
        """The platform as the engine reports it; ``estop``: the lab's E-STOP is latched (the engine refuses
        every mode command until reset, the platform brakes to rest and holds)."""
        info = p.source_info
        extra = ""
        if p.source == "simulation" and "hs" in info:
            extra = f" (Hs {info['hs']:g} m, Tp {info['tp']:g} s, scale {', '.join(f'{v:.2f}' for v in info['scale'])})"
        self.status.setText(
            f"{_platform_status(p, estop)} &nbsp; source <b>{p.source.upper()}</b>{extra}"
            f" &nbsp; ramp {100 * p.ramp:.0f} %"
            + (" &nbsp; <b style='color:#f80'>LEG LIMIT</b>" if p.leg_clamped else "")
        )
        self._show_motion(getattr(p, "motion", None))
        engaged = p.mode == "engaged"
        ok = not estop
        self.buttons["neutral"].setEnabled(ok and p.status in ("settled", "holding"))
        self.buttons["settle"].setEnabled(ok and p.status in ("neutral", "holding"))
        self.buttons["engage"].setEnabled(ok and p.status == "neutral")
        self.buttons["disengage"].setEnabled(ok and engaged and p.status != "disengaging")
        self.apply.setEnabled(not engaged)  # the engine takes a source out of ENGAGED, also under an E-STOP
        if self.info is not None:
            lo, hi = self.info.leg_range
            for k, (bar, L) in enumerate(zip(self.leg_bars, p.legs, strict=True)):
                set_bar(bar, (L - lo) / (hi - lo), f"leg {k + 1}: {L:.3f} m")
        if t - self._t_last >= 1.0 / SAMPLE_HZ - 1e-9:
            self._t_last = t
            eta = np.asarray(p.eta)
            self.ring.push([t, *eta[:3], *np.degrees(eta[3:])])

    def _show_motion(self, m) -> None:
        """The Rexroth status word: operation state, system status, operation mode (as the lab HMI)."""
        if m is None:
            text = "Rexroth status: –"
        else:
            color = MOTION_COLOR.get(m.status, "#e33")
            text = (
                f"Rexroth: state <b>{m.state or '–'}</b> &nbsp; status <b style='color:{color}'>{m.status or '–'}</b>"
                f" &nbsp; op mode <b>{m.opmode or '–'}</b> &nbsp; (0x{m.word:08X})"
            )
        if text != self.motion_label.text():
            self.motion_label.setText(text)

    def draw(self) -> None:
        r = self.ring
        if r.n < 2 or not self.isVisible():  # a hidden panel draws when shown again (_shown)
            return
        t = r["t"]
        for dof, c in zip(DOFS[:3], self.pos_curves, strict=True):
            c.setData(t, r[dof])
        for dof, c in zip(DOFS[3:], self.att_curves, strict=True):
            c.setData(t, r[dof])


def _platform_status(p, estop: bool) -> str:
    """A platform's mode in its colour; under a latched E-STOP in the stop colour with what it does (braking or
    stopped, from its speed): never a green ENGAGED while it is stopped."""
    status = p.status.upper()
    if estop:
        moving = max(map(abs, p.eta_dot), default=0.0) > MOVING
        return f"<b style='color:{STOP_COLOR}'>{status} — E-STOP latched: {'braking' if moving else 'stopped'}</b>"
    text = f"<b style='color:{STATUS_COLOR.get(status, '#fa3')}'>{status}</b>"
    return text + (" (choose NEUTRAL or SETTLE)" if p.status == "holding" else "")
