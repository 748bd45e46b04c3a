"""Motion-Lab tab, modelled on the lab's own PyQt5 HMI (Motion-Lab paper §2.9, Figs. 10–11).

One sub-tab per Stewart platform (mode buttons, motion source with the sine generator and the
wave simulator, status fields, position and attitude plots, six actuator-stroke bars), one for
the Comau robot and the winch (modes, joint plots, utilisation bars, wire-length bar and the
spring-return speed slider, VVMC on/off) and one with the 3D scene of the lab and the pendulum
plots.  Everything goes through the lab engine (``bosun server --plant lab``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import Qt, QTimer, pyqtSignal
from PyQt5.QtWidgets import (
    QApplication,
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QProgressBar,
    QPushButton,
    QSizePolicy,
    QSlider,
    QSpinBox,
    QStackedWidget,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from ui.csv_logger import LAB_DURATION_RANGE, LabCsvLogger
from ui.glprobe import gl_available
from ui.scene_tab import SceneEngineMixin
from ui.widgets.columns import scroll_column
from ui.widgets.files import choose_file
from ui.widgets.labels import ElidedLabel
from ui.widgets.machines3d import LazyDraw
from ui.widgets.plots import Ring, axis_label, legend, refit, refit_on_show
from ui.widgets.status import MOVING, SceneLights, StatusLight, lab_plc_light
from ui.widgets.stick import VirtualStick
from ui.widgets.vessel import VesselRow

HISTORY_S = 60.0
SAMPLE_HZ = 25
DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
SOURCES = ("generator", "simulation", "remote", "timeseries")
COMAU_MODES = ("settled", "remote", "motion_comp", "hold")
PLATFORM_COLUMNS = ("t", *DOFS)  # position [m], attitude [deg]
# engine time, Comau q [deg] and q̇ [rad/s], swing α β [rad], tool − work point in {b2} [m], wire length [m]
LAB_COLUMNS = ("t", "q1", "q2", "q3", "qd1", "qd2", "qd3", "alpha", "beta", "err_x", "err_y", "err_z", "wire")
# issue 16, item 4: the swing estimator's estimate α̂ β̂, its error (estimate − true) and 1-σ [deg], the law's offset [mm]
SWING_COLUMNS = ("t", "alpha", "beta", "alpha_hat", "beta_hat", "err_a", "err_b", "sig_a", "sig_b", "off_x", "off_y")
# issue 16, item 5: the lab HMI's "Machine and Sensor States" lights (engine name, shown name) and their colours
MACHINES = (
    ("em8000", "EM8000"),
    ("em1500", "EM1500"),
    ("comau", "Comau"),
    ("mru1", "MRU1"),
    ("mru2", "MRU2"),
    ("tracker", "tracker"),
    ("remote", "remote"),
)
MACHINE_LIGHT = {
    "active": ("ok", "on"),
    "inactive": ("error", "OFF"),
    "absent": ("off", "n/c"),
    "stale": ("warn", "old"),  # issue 27: the PLC sent invalid data for it; the last valid value is held
    "unknown": ("unknown", "?"),
}
MOTION_COLOR = {"SYSTEM_OK": "#3c9", "WARNING": "#fa3", "ERROR": "#e33"}
# a platform's mode as its page shows it; red only for a latched E-STOP (issue 26, item 5)
STATUS_COLOR = {"ENGAGED": "#3c9", "NEUTRAL": "#39f", "SETTLED": "#999", "HOLDING": "#fa3"}
STOP_COLOR = "#e33"
# the Motion-Lab engine's lights on its page (issue 26, item 6): key, shown name, tool tip
LAB_LIGHTS = (
    ("engine", "engine", "the Motion-Lab engine: connection and loop"),
    ("input", "input", "the input that drives a lab machine now: a joint jog, the stick (REMOTE) or none"),
    ("plant", "plant", "the lab's machines as the engine reports them: moving, compensating, holding, at rest, E-STOP"),
    ("plc", "PLC", "the lab's PLC link (bosun server --plant lab --plc): none (simulated plant), ok, lost, error"),
)
# the stick's ENABLE as the engine takes it: (text, style sheet) for enabled, held but refused, armed, not armed
ENABLE_LOOK = {
    "enabled": ("ENABLED", "QPushButton { background: #3c9d3c; color: white; font-weight: bold; }"),
    "refused": (
        "NOT ARMED\n(release)",
        "QPushButton, QPushButton:pressed { background: #e0a020; color: black; font-weight: bold; }",
    ),
    "armed": ("ENABLE\n(armed)", "QPushButton { border: 2px solid #3c9d3c; }"),
    "idle": ("ENABLE\n(hold)", ""),
}
JOG_RESEND_MS = 100  # a held jog button resends its speed this often (the engine stops a jog after 0.3 s)


def _bar(fmt: str = "%p %") -> QProgressBar:
    b = QProgressBar()
    b.setRange(0, 1000)
    b.setFormat(fmt)
    b.setTextVisible(True)
    return b


def _set_bar(bar: QProgressBar, fraction: float, text: str) -> None:
    bar.setValue(int(1000 * min(1.0, max(0.0, fraction))))
    bar.setFormat(text)


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
        self.leg_bars = [_bar() for _ in range(6)]
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
                _set_bar(bar, (L - lo) / (hi - lo), f"leg {k + 1}: {L:.3f} m")
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


class SpringSlider(QSlider):
    """The lab HMI's winch speed control: a value only while the handle is held, zero otherwise.

    No keyboard focus, no wheel, no jumps by clicking the groove: any value not held by the mouse
    springs back to zero at once, so nothing but a held handle commands the winch.
    """

    def __init__(self) -> None:
        super().__init__(Qt.Horizontal)
        self.setRange(-100, 100)
        self.setValue(0)
        self.setFocusPolicy(Qt.NoFocus)
        self.setPageStep(0)
        self.sliderReleased.connect(lambda: self.setValue(0))
        self.valueChanged.connect(self._spring)

    def _spring(self, value: int) -> None:
        if value != 0 and not self.isSliderDown():
            self.setValue(0)

    def wheelEvent(self, ev) -> None:
        ev.ignore()


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


LAB_TIP = (
    "EM8000 and EM1500 (blue decks, grey legs), Comau (orange) on its pedestal, wire and load (red), "
    "work point (green) [m]"
)


class LabScene2D(LazyDraw, QWidget):
    """Without OpenGL: the lab's solids seen from the side (world x – z) and from above (x – y)."""

    kind = "2d"

    def __init__(self) -> None:
        super().__init__()
        from ui.widgets.machines3d import MachineView2D

        views = [
            ("side", "side: world x – z [m]", ((1, 0, 0), (0, 0, 1))),
            ("top", "top: world x – y [m]", ((1, 0, 0), (0, 1, 0))),
        ]
        self.machines = MachineView2D(self, views=views, note="Motion-Lab, 2D views (no OpenGL here)")
        self.machines.setToolTip(LAB_TIP)
        self.plot = self.machines.plots["side"]["plot"]
        self.draw = LabDrawing()
        self._fitted = False
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.machines)

    def set_description(self, desc) -> None:
        self.draw.set_description(desc)

    def update_scene(self, sc) -> None:
        """Draw the engine's scene points (now if shown, else when next shown)."""
        self.submit(sc)

    def draw_now(self, sc) -> None:
        meshes = self.draw.meshes(sc)
        m = self.machines
        m.set_meshes(meshes)
        m.set_line("wire", [sc.tool, sc.payload], (235, 235, 235), 1.5)
        m.set_points("goal", [sc.work_point], (50, 220, 80), "+", 14)
        if not self._fitted:
            m.fit_meshes(meshes)
            self._fitted = True

    def grab_image(self):
        return self.machines.grab_image()


class LabScene3D(LazyDraw, QWidget):
    """The lab in OpenGL: platforms as decks on six legs, the Comau on its pedestal, wire and load."""

    kind = "3d"

    def __init__(self) -> None:
        super().__init__()
        from ui.widgets.machines3d import MachineView3D

        self.machines = MachineView3D(self, tooltip=LAB_TIP)
        self.view = self.machines.view
        self.draw = LabDrawing()
        self._fitted = False
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.machines)

    def set_description(self, desc) -> None:
        self.draw.set_description(desc)

    def update_scene(self, sc) -> None:
        """Draw the engine's scene points (now if shown, else when next shown)."""
        self.submit(sc)

    def draw_now(self, sc) -> None:
        from app.models.drawing import merge

        meshes = self.draw.meshes(sc)
        m = self.machines
        m.set_mesh("lab", merge(meshes))
        m.set_line("wire", [sc.tool, sc.payload], (0.92, 0.92, 0.92, 1), 1.5)
        m.set_points("goal", [sc.work_point], (0.2, 0.85, 0.3, 1), 10)
        if not self._fitted:
            m.fit_meshes(meshes)
            self._fitted = True

    def grab_image(self):
        return self.machines.grab_image()


def make_lab_scene(use_gl: bool | None) -> QWidget:
    if use_gl is None:
        use_gl = gl_available()
    if use_gl:
        try:
            return LabScene3D()
        except Exception:
            pass
    return LabScene2D()


class MotionLabTab(SceneEngineMixin, QWidget):
    """The Motion-Lab HMI; ``link_factory`` makes the link to the lab engine on first view."""

    notice = pyqtSignal(str, str)
    plc_link = pyqtSignal(str, str)  # the plant's link as a status light: state (ok/warn/error/off), detail
    engine_label = "Motion-Lab"

    def __init__(self, link_factory: Callable[[], object] | None = None, use_gl: bool | None = None) -> None:
        super().__init__()
        self.link_factory = link_factory
        self.link = None
        self.use_gl = use_gl
        self.state = None  # the newest LabSnapshot
        self.desc = None  # the engine's LabDescription
        self._t_last = -math.inf
        self.ring = Ring(int(HISTORY_S * SAMPLE_HZ), LAB_COLUMNS)
        self.swing_ring = Ring(int(HISTORY_S * SAMPLE_HZ), SWING_COLUMNS)
        self.tabs = QTabWidget()
        self.platforms = {n: PlatformPanel(n, t) for n, t in (("em8000", "E-Motion 8000"), ("em1500", "E-Motion 1500"))}
        for n, p in self.platforms.items():
            p.command.connect(self._on_panel)
            self.tabs.addTab(p, n.upper())
        self.tabs.addTab(self._control(), "Comau && winch")
        self.tabs.addTab(self._scene_tab(), "Scene && load")
        self.tabs.addTab(self._swing_tab(), "Load swing")
        self.start = ElidedLabel("The Motion-Lab engine starts when this tab is first opened.")
        self.plc_bar = self._plc_bar()
        self.logger: LabCsvLogger | None = None
        self.lights = SceneLights("Motion-Lab", LAB_LIGHTS, padding="1px 6px")  # its engine's lights (issue 26)
        self._enable_look = ""
        lay = QVBoxLayout(self)
        lay.addWidget(self.lights)
        # the engine's start note and the PLC's error live in the room beside the sub-tabs (the tab widget's
        # corner, the tab bar's height whatever it shows): nothing moves when one comes or goes (issue 26,
        # item 2: a page that stays put; as the main window's notices)
        notes = QWidget()
        row = QHBoxLayout(notes)
        row.setContentsMargins(8, 0, 0, 0)
        row.setSpacing(0)
        row.addWidget(self.start, 1)
        row.addWidget(self.plc_bar, 1)
        notes.setFixedHeight(self.tabs.tabBar().sizeHint().height())
        notes.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Fixed)
        self.notes = notes
        self.tabs.setCornerWidget(notes, Qt.TopRightCorner)
        lay.addWidget(self.tabs)
        lay.addWidget(self._status_strip())  # the lab HMI's bottom: machine and sensor states, CSV logger
        self._set_enabled(False)

    # ------------------------------------------------------------------ layout
    def _plc_bar(self) -> QWidget:
        """The PLC's error, as the lab HMI shows it, with Acknowledge; never a modal box (STOP stays live)."""
        bar = QWidget()
        bar.setStyleSheet("background: #5a1f1d; color: white;")
        bar.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
        row = QHBoxLayout(bar)
        row.setContentsMargins(6, 0, 2, 0)
        self.plc_text = ElidedLabel("")  # one line in the row's kept room ("…" and the whole in the tool tip)
        row.addWidget(self.plc_text, 1)
        self.plc_ack = QPushButton("Acknowledge")
        self.plc_ack.setFocusPolicy(Qt.NoFocus)  # Space stays STOP
        self.plc_ack.setToolTip("writes MAIN.bReset; a platform in WARNING/ERROR: its bReset, then SETTLED")
        self.plc_ack.clicked.connect(lambda: self._send("lab_plc_ack"))
        row.addWidget(self.plc_ack)
        bar.hide()
        return bar

    def _show_plant(self, state) -> None:
        """The plant backend's link: the PLC light (:func:`~ui.widgets.status.lab_plc_light`, on this page's
        row and as ``plc_link``) and, while the PLC reports an error, the bar above the tabs."""
        light = lab_plc_light(state)
        self.plc_link.emit(light.look, light.detail)
        pl = getattr(state, "plant", None)
        if pl is None or pl.backend != "plc":
            self.plc_bar.hide()
            return
        show = bool(pl.plc_error) and pl.connected
        if show:
            self.plc_text.setText(f"PLC error: {pl.plc_error}")  # one line: "…" and the whole in its tool tip
            self.plc_ack.setEnabled(not state.estop)  # the E-STOP's reset resets the PLC: acknowledge after it
            self.start.hide()
        self.plc_bar.setVisible(show)

    # ------------------------------------------------------------------ the lab HMI's bottom (issue 16, item 5)
    def _status_strip(self) -> QWidget:
        """Below the sub-tabs, on every one of them: the lab HMI's "Machine and Sensor States" lights and its
        CSV logger (file, duration 1–1200 s, start / stop, progress, sample count)."""
        w = QWidget()
        col = QVBoxLayout(w)
        col.setContentsMargins(0, 0, 0, 0)
        col.setSpacing(2)
        lights = QHBoxLayout()
        lights.addWidget(QLabel("<b>Machine and sensor states</b>"))
        self.machine_lights: dict[str, StatusLight] = {}
        for key, name in MACHINES:
            light = StatusLight(name, "")
            light.setMinimumWidth(90)
            self.machine_lights[key] = light
            lights.addWidget(light, 1)
        col.addLayout(lights)
        row = QHBoxLayout()
        row.addWidget(QLabel("<b>CSV logger</b>"))
        self.log_path = QLineEdit(os.path.join(os.getcwd(), "bosun_lab_log.csv"))
        self.log_path.setToolTip("the file the logger writes (overwritten)")
        row.addWidget(self.log_path, 2)
        browse = QPushButton("…")
        browse.setFocusPolicy(Qt.NoFocus)
        browse.setMaximumWidth(32)
        browse.setToolTip("choose the log file")
        browse.clicked.connect(
            lambda: choose_file(self, "Log file", self.log_path.text(), "CSV (*.csv)", self.log_path.setText, save=True)
        )
        row.addWidget(browse)
        self.log_duration = QSpinBox()
        self.log_duration.setRange(*(int(v) for v in LAB_DURATION_RANGE))  # the lab HMI's 1..1200 s
        self.log_duration.setValue(60)
        self.log_duration.setSuffix(" s")
        self.log_duration.setToolTip("logging duration in engine time (the lab HMI's 1–1200 s)")
        row.addWidget(self.log_duration)
        self.log_button = QPushButton("Start logging")
        self.log_button.setFocusPolicy(Qt.NoFocus)  # Space stays STOP
        self.log_button.setToolTip(
            "write every published lab state (time, both platforms' η, Comau q, wire, swing, VVMC error) to the file; "
            "stops by itself after the duration, when the engine is lost or the tab closes"
        )
        self.log_button.clicked.connect(self.toggle_logger)
        row.addWidget(self.log_button)
        self.log_progress = _bar()
        _set_bar(self.log_progress, 0.0, "not logging")
        row.addWidget(self.log_progress, 2)
        self.log_samples = QLabel("0 samples")
        self.log_samples.setMinimumWidth(90)
        row.addWidget(self.log_samples)
        col.addLayout(row)
        return w

    def _show_machines(self, state) -> None:
        shown = {m.name: m for m in getattr(state, "machines", None) or []}
        for key, light in self.machine_lights.items():
            m = shown.get(key)
            look, word = MACHINE_LIGHT.get(m.state, MACHINE_LIGHT["unknown"]) if m is not None else ("unknown", "?")
            light.set(look, word)
            tip = m.detail if m is not None else "the engine does not report it"
            if light.toolTip() != tip:
                light.setToolTip(tip)

    def toggle_logger(self) -> None:
        if self.logger is None:
            self.start_logger()
        else:
            self.stop_logger("stopped by the operator")

    def start_logger(self) -> None:
        try:
            self.logger = LabCsvLogger(self.log_path.text(), float(self.log_duration.value()))
        except (OSError, ValueError) as err:
            self.notice.emit("error", f"Motion-Lab: CSV logger not started: {err}")
            return
        self.log_button.setText("Stop logging")
        self._show_log(self.logger)
        self.notice.emit("info", f"Motion-Lab: logging to {self.logger.path} for {self.logger.duration:g} s")

    def stop_logger(self, reason: str) -> None:
        """End the log (the file stays complete); says why and how many samples it holds."""
        lg, self.logger = self.logger, None
        if lg is None:
            return
        lg.close(reason)
        self.log_button.setText("Start logging")
        self._show_log(lg)
        self.notice.emit("info", f"Motion-Lab: CSV logger {lg.reason}: {lg.rows} samples in {lg.path.name}")

    def _show_log(self, lg: LabCsvLogger) -> None:
        _set_bar(self.log_progress, lg.progress, f"{lg.elapsed:.1f} / {lg.duration:g} s")
        self.log_samples.setText(f"{lg.rows} samples")

    def log_states(self, states: list) -> None:
        """Every state the engine published (also when the GUI lags) goes to the logger."""
        lg = self.logger
        if lg is None:
            return
        for st in states:
            if not lg.add(st):
                self.stop_logger(lg.reason)
                return
        self._show_log(lg)

    def _connection(self, ok: bool, message: str) -> None:
        if not ok:  # the engine is gone: nothing more to log, nothing known about the machines
            self.stop_logger(f"stopped: engine lost ({message})" if message else "stopped: engine lost")
            self._show_machines(None)
            self.lights.show_lost()

    def _linked(self, make) -> bool:
        done = super()._linked(make)
        if done:
            for signal, slot in (("states", self.log_states), ("connection", self._connection)):
                if hasattr(self.link, signal):
                    getattr(self.link, signal).connect(slot)
        return done

    def close_link(self) -> None:
        self.stop_logger("stopped: the Motion-Lab tab closed")
        self._jog_release()
        super().close_link()

    # ------------------------------------------------------------------ Comau joint jog (issue 16, item 5)
    def _jog_buttons(self, k: int) -> QWidget:
        """Joint ``k``'s (0-2) jog buttons: press and hold to move it, let go to stop."""
        row = QWidget()
        lay = QHBoxLayout(row)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.joint_pos_bars[k], 1)
        for sign, text in ((-1, "−"), (1, "+")):
            b = QPushButton(text)
            b.setFocusPolicy(Qt.NoFocus)  # Space stays STOP; the keyboard stays with the stick
            b.setFixedWidth(34)
            b.setToolTip(
                f"jog q{k + 1} {'down' if sign < 0 else 'up'}: press and hold with enable held (Shift or ENABLE); it "
                "stops when let go, when enable is released, and by itself 0.3 s after the last refresh. REMOTE only: "
                "refused in MOTION_COMP / VVMC, under E-STOP and over the lab's PLC"
            )
            b.pressed.connect(lambda j=k + 1, sg=sign: self._jog_press(j, sg))
            b.released.connect(self._jog_release)
            self.jog_buttons[(k + 1, sign)] = b
            lay.addWidget(b)
        return row

    def _jog_send(self) -> None:
        if self._jogging is not None:
            joint, sign = self._jogging
            self._send("lab_comau_jog", joint=joint, speed=sign * self.jog_speed.value() / 100.0)

    def _jog_press(self, joint: int, sign: int) -> None:
        self._jogging, self._jog_told = (joint, sign), False
        self._jog_send()
        self._jog_timer.start()

    def _jog_resend(self) -> None:
        """While the button is held its speed is refreshed (the engine drops a jog 0.3 s after the last).  A
        button that is no longer on screen (its page or tab left while held, H62) never gets its release: the
        jog ends, as it does when the application loses the focus."""
        b = None if self._jogging is None else self.jog_buttons[self._jogging]
        app = QApplication.instance()
        active = app is None or app.applicationState() == Qt.ApplicationActive or self._headless
        if b is not None and b.isDown() and b.isVisible() and active:
            self._jog_send()
        else:
            if b is not None:
                b.setDown(False)
            self._jog_release()

    def _jog_release(self) -> None:
        self._jog_timer.stop()
        if self._jogging is not None:
            self._send("lab_comau_jog", joint=self._jogging[0], speed=0.0)
            self._jogging = None

    def _show_jog(self, state) -> None:
        c, jog = state.comau, getattr(state, "comau_jog", None)
        can = c.mode == "remote" and not state.vvmc and not state.estop
        for b in self.jog_buttons.values():
            if b.isEnabled() != can and not b.isDown():
                b.setEnabled(can)
        if jog is not None and jog.joint:
            text = f"jogging q{jog.joint} {100 * jog.speed:+.0f} % ({math.degrees(jog.qd):+.1f}°/s)"
        elif not can:
            text = "jog: Comau REMOTE only (not in MOTION_COMP / VVMC, not under E-STOP)"
        elif jog is not None and jog.reason:
            text = f"jog stopped: {jog.reason}"
        else:
            text = "hold enable (Shift or ENABLE), then press and hold a joint's button"
        if text != self.jog_label.text():
            self.jog_label.setText(text)

    def _show_enable(self, state) -> None:
        """The stick's ENABLE shows what the engine made of it (issue 26): green only while the engine says
        the input is enabled (armed, deadman held, fresh), amber while held here but refused (not armed:
        release, centre, press again), outlined while armed, plain otherwise."""
        f = state.flags
        if f.enabled:
            look = "enabled"
        elif self.stick.enabled:
            look = "refused"
        else:
            look = "armed" if f.armed and not state.estop else "idle"
        if look != self._enable_look:
            self._enable_look = look
            text, css = ENABLE_LOOK[look]
            self.stick.enable.setText(text)
            self.stick.enable.setStyleSheet(css)
        tip = f"the engine: {'enabled' if f.enabled else 'armed' if f.armed else 'not armed'}"
        if f.input_reason and not f.enabled:
            tip += f" ({f.input_reason})"
        if self.stick.enable.toolTip() != tip:
            self.stick.enable.setToolTip(tip)

    def _control(self) -> QWidget:
        w = QWidget()
        grid = QGridLayout(w)
        cbox = QGroupBox("Comau SMART-5 NJ 110-3.0")  # a longer title widened the column past its scroll area
        cbox.setToolTip("Comau SMART-5 NJ 110-3.0, 3-DOF with the lab's extension arm")
        cl = QFormLayout(cbox)
        self.comau_mode = QComboBox()
        self.comau_mode.addItems([m.upper() for m in COMAU_MODES])
        self.comau_mode.setToolTip("HOLD: after an E-STOP reset the robot holds until a mode is chosen")
        self.comau_mode.model().item(COMAU_MODES.index("hold")).setEnabled(False)  # shown, not chosen
        self.comau_mode.activated.connect(lambda i: self._send("lab_comau_mode", mode=COMAU_MODES[i]))
        cl.addRow("mode", self.comau_mode)
        self.comau_limits = QLabel("")  # the joint-limit profile in force (issue 16)
        self.comau_limits.setTextFormat(Qt.RichText)
        self.comau_limits.setWordWrap(True)
        cl.addRow(self.comau_limits)
        self.joint_pos_bars = [_bar() for _ in range(3)]
        self.joint_speed_bars = [_bar() for _ in range(3)]
        self.jog_buttons: dict[tuple[int, int], QPushButton] = {}  # (joint 1-3, sign) -> button
        self._jogging: tuple[int, int] | None = None  # the held button
        self._jog_told = False  # a refusal of this press was shown
        # offscreen (tests, screenshots) the application is never "active": the focus rule is for a real display
        self._headless = QApplication.platformName() in ("offscreen", "minimal")
        self._jog_timer = QTimer(self)
        self._jog_timer.setInterval(JOG_RESEND_MS)
        self._jog_timer.timeout.connect(self._jog_resend)
        for k in range(3):
            cl.addRow(f"q{k + 1} position", self._jog_buttons(k))  # with its jog buttons (issue 16, item 5)
            cl.addRow(f"q{k + 1} speed use", self.joint_speed_bars[k])
        self.jog_speed = QSpinBox()
        self.jog_speed.setRange(5, 100)
        self.jog_speed.setValue(25)
        self.jog_speed.setSuffix(" % of the joint speed")
        self.jog_speed.setToolTip("the speed of the − / + jog buttons, a share of the joint-limit profile's speed")
        cl.addRow("jog speed", self.jog_speed)
        self.jog_label = QLabel("–")
        self.jog_label.setWordWrap(True)
        cl.addRow(self.jog_label)
        wbox = QGroupBox("Winch")
        wl = QFormLayout(wbox)
        self.winch_mode = QComboBox()
        self.winch_mode.addItems(["LOCAL", "REMOTE", "MOTION_COMP"])
        self.winch_mode.activated.connect(lambda i: self._send("lab_winch", mode=("local", "remote", "motion_comp")[i]))
        wl.addRow("mode", self.winch_mode)
        self.wire_bar = _bar()
        wl.addRow("wire length", self.wire_bar)
        self.winch_slider = SpringSlider()
        self.winch_slider.valueChanged.connect(self._slider)
        self._slider_timer = QTimer(self)  # the engine zeroes a LOCAL speed not refreshed for 0.3 s
        self._slider_timer.setInterval(100)
        self._slider_timer.timeout.connect(lambda: self._slider(self.winch_slider.value()))
        # the lab HMI's "Velocity Setpoint - max 0.2 m/s": −100…100, u = value/100 · top speed, springs back
        self.winch_slider_label = QLabel("velocity setpoint (springs back)")
        self.winch_slider_label.setWordWrap(True)  # a label as wide as the column cut its right side off
        wl.addRow(self.winch_slider_label)
        wl.addRow(self.winch_slider)
        rbox = QGroupBox("REMOTE drive (Comau tool x, y, z; winch w)")
        rl = QVBoxLayout(rbox)
        self.stick = VirtualStick(aux_axis="w winch")
        self.stick.setToolTip(
            "drives the Comau tool point (REMOTE, 0.25 m/s at full stick) and the winch (REMOTE, slider w); "
            "hold Shift or the ENABLE button (deadman); a joystick works the same way"
        )
        rl.addWidget(self.stick)
        # not a toggle: a click asks the engine for the other state, and the button shows the engine's state
        # only (a checkable button showed the request, also one the engine refused)
        self.vvmc = QPushButton("VVMC OFF")
        self.vvmc.setToolTip(
            "vessel-to-vessel motion compensation: the Comau and winch in MOTION_COMP (the state shown is the "
            "engine's); click to switch it"
        )
        self.vvmc.clicked.connect(lambda: self._send("lab_vvmc", on=not (self.state is not None and self.state.vvmc)))
        self.vvmc.setMinimumHeight(36)
        self.readout = QLabel("–")
        self.readout.setTextFormat(Qt.RichText)
        self.readout.setWordWrap(True)  # wraps rather than widening the column past its scroll area
        left = QVBoxLayout()
        left.addWidget(cbox)
        left.addWidget(wbox)
        left.addWidget(self.vvmc)
        left.addWidget(self.readout)
        left.addStretch(1)
        lw = QWidget()
        lw.setLayout(left)
        self.joint_plot = pg.PlotWidget(title="Comau joints")
        axis_label(self.joint_plot.getPlotItem(), "left", "joint angle", "deg")
        legend(self.joint_plot.getPlotItem(), cols=3)
        self.joint_curves = [
            self.joint_plot.plot(pen=pg.mkPen(c, width=1.5), name=f"q{k + 1}")
            for k, c in enumerate(((230, 90, 80), (90, 200, 90), (90, 140, 240)))
        ]
        self.wire_plot = pg.PlotWidget(title="winch wire")
        axis_label(self.wire_plot.getPlotItem(), "left", "length", "m")
        legend(self.wire_plot.getPlotItem())
        self.wire_curve = self.wire_plot.plot(pen=pg.mkPen((200, 200, 90), width=1.5), name="L_w")
        for p in (self.joint_plot, self.wire_plot):
            p.showGrid(x=True, y=True, alpha=0.3)
            axis_label(p.getPlotItem(), "bottom", "t", "s")
        refit_on_show(w, lambda: self._shown(self.joint_plot, self.wire_plot))
        # the stick beside the wire plot, the joints below: stacked under a 200 px stick, the wire plot was
        # squeezed below its own header in a 1280×800 window
        right = QVBoxLayout()
        rbox.setMaximumHeight(200)
        top = QHBoxLayout()
        top.addWidget(rbox, 2)
        top.addWidget(self.wire_plot, 3)
        right.addLayout(top, 1)
        right.addWidget(self.joint_plot, 1)
        grid.addWidget(scroll_column(lw, max_width=480), 0, 0)  # the controls scroll, the plots keep the height
        grid.addLayout(right, 0, 1)
        grid.setColumnStretch(1, 1)
        return w

    def _scene_tab(self) -> QWidget:
        w = QWidget()
        lay = QHBoxLayout(w)
        self.scene = make_lab_scene(self.use_gl)
        lay.addWidget(self.scene, 3)
        plots = QVBoxLayout()
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
        refit_on_show(w, lambda: self._shown(self.swing_plot, self.err_plot))
        return w

    def _swing_tab(self) -> QWidget:
        """The lab HMI's "Pendel Estimator" tab (issue 16, item 4): anti-swing Activate / Deactivate / Reset,
        the pendulum states (estimate beside the true swing), the error states with the estimator's ±2σ,
        the damping parameter and the law's tool offset."""
        w = QWidget()
        col = QVBoxLayout(w)
        row = QHBoxLayout()
        self.swing_buttons: dict[str, QPushButton] = {}
        for action, tip in (
            ("activate", "add the anti-swing law's offset to the work point the Comau tracks (VVMC on)"),
            ("deactivate", "the law off: its offset returns to zero along the law (the tool back on the work point)"),
            ("reset", "the estimator back to 'no swing' with its initial covariance (law off, tool back)"),
        ):
            b = QPushButton(action.capitalize())
            b.setFocusPolicy(Qt.NoFocus)  # Space stays STOP
            b.setToolTip(tip)
            b.setMinimumHeight(30)
            b.clicked.connect(lambda _=False, a=action: self._send("lab_antisway", action=a))
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
        refit_on_show(w, lambda: self._shown(self.swing_state_plot, self.swing_err_plot, self.swing_off_plot))
        return w

    def _show_swing(self, state) -> None:
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

    def _set_enabled(self, on: bool) -> None:
        for i in range(self.tabs.count()):  # the pages, not the tab widget: its corner (the notes) stays live
            self.tabs.widget(i).setEnabled(on)
        self.start.setVisible(not on and not self.plc_bar.isVisibleTo(self))

    # ------------------------------------------------------------------ engine
    def _engine_failed(self, err: Exception) -> None:
        self.start.setText(f"engine not started: {err}")

    def _on_panel(self, mtype: str, fields: dict) -> None:
        if mtype == "_error":
            self.notice.emit("error", f"Motion-Lab: refused: {fields['text']}")
            return
        self._send(mtype, **fields)

    def _slider(self, value: int) -> None:
        if self.winch_slider.isSliderDown() and not self._slider_timer.isActive():
            self._slider_timer.start()
        elif not self.winch_slider.isSliderDown():
            self._slider_timer.stop()
        if self.desc is not None and self.desc.winch is not None:
            vmax = self.desc.winch.speed_max  # u = value/100 · 0.2 m/s (the lab HMI, motionlab_plc.json)
            self._send("lab_winch", speed=vmax * value / 100.0)

    def on_reply(self, re: str, ok: bool, error: str) -> None:
        if not ok and "no longer the operator" in error:
            self.notice.emit("error", f"Motion-Lab: operator role lost: {error}")
        if not ok and re == "lab_comau_jog":  # resent while held: said once per press
            if self._jog_told:
                return
            self._jog_told = True
        if not ok and (re.startswith("lab_") or re in ("reset", "set_vessel")):
            self.notice.emit("error", f"Motion-Lab: {re} refused: {error}")

    # ------------------------------------------------------------------ state
    def on_description(self, desc) -> None:
        """The lab's static data: platform leg ranges and seas, Comau limits, winch range."""
        if getattr(desc, "kind", None) != "lab":
            return
        self.desc = desc
        for info in desc.platforms:
            if info.name in self.platforms:
                self.platforms[info.name].set_info(info)
        for panel in self.platforms.values():  # the wave simulator's vessel (none over the PLC)
            panel.vessel.setVisible(bool(desc.vessels))
            if desc.vessels:
                panel.vessel.set_engine(desc.vessel, list(desc.vessels))
        self.scene.set_description(desc)
        if desc.winch is not None:
            self.winch_slider_label.setText(f"velocity setpoint, max {desc.winch.speed_max:g} m/s (springs back)")
        if desc.comau_profile:
            lim = ", ".join(
                f"q{k + 1} {math.degrees(a):.0f}…{math.degrees(b):.0f}°"
                for k, (a, b) in enumerate(zip(desc.comau_lower, desc.comau_upper, strict=True))
            )
            law = f", A = {desc.comau_boundary_accel:.3g} rad/s² at the limits" if desc.comau_boundary_accel else ""
            speed = max(desc.comau_speed) if desc.comau_speed else 0.0
            self.comau_limits.setText(
                f"joint limits <b>{desc.comau_profile}</b>: {lim}, {math.degrees(speed):.0f}°/s{law}"
            )

    def on_state(self, state) -> None:
        if getattr(state, "kind", None) != "lab":
            return
        self.state = state
        self.lights.show_state(state)
        self._show_plant(state)
        self._show_machines(state)
        self._show_jog(state)
        self._show_swing(state)
        self._show_enable(state)
        t = state.t
        for p in state.platforms:
            self.platforms[p.name].update_state(p, t, state.estop)
        c, w, d = state.comau, state.winch, self.desc
        if d is not None:
            for k in range(3):
                lo, hi = d.comau_lower[k], d.comau_upper[k]
                _set_bar(self.joint_pos_bars[k], (c.q[k] - lo) / (hi - lo), f"{math.degrees(c.q[k]):.1f}°")
                use = abs(c.qd[k]) / d.comau_speed[k]
                _set_bar(self.joint_speed_bars[k], use, f"{100 * use:.0f} %")
            wi = d.winch
            _set_bar(self.wire_bar, (w.length - wi.min) / (wi.max - wi.min), f"{w.length:.3f} m")
        if c.mode in COMAU_MODES:  # the PLC may report a mode Bosun does not offer (shown in its light)
            self.comau_mode.setCurrentIndex(COMAU_MODES.index(c.mode))
        if w.mode in ("local", "remote", "motion_comp"):
            self.winch_mode.setCurrentIndex(("local", "remote", "motion_comp").index(w.mode))
        free = not state.estop  # the engine refuses every mode, winch and VVMC command until reset
        for widget in (self.comau_mode, self.winch_mode, self.vvmc):
            widget.setEnabled(free)
        self.winch_slider.setEnabled(free and w.mode == "local")
        look = "VVMC ON" if state.vvmc else "VVMC OFF"
        if self.vvmc.text() != look:
            self.vvmc.setText(look)
            self.vvmc.setStyleSheet("QPushButton { background: #2f6f2f; color: white; }" if state.vvmc else "")
        e = 1000 * np.linalg.norm(state.tool_error_b2)
        pend = state.pendulum
        stop = ""
        if state.estop:
            moving = max(map(abs, c.qd), default=0.0) > MOVING or abs(w.speed) > MOVING
            what = "braking" if moving else "stopped"
            stop = f"<b style='color:{STOP_COLOR}'>E-STOP latched: Comau and winch {what}</b><br>"
        self.readout.setText(
            f"{stop}tool − work point {e:.1f} mm &nbsp; swing {math.degrees(pend.swing):.2f}° &nbsp; t {t:.1f} s"
        )
        if t - self._t_last >= 1.0 / SAMPLE_HZ - 1e-9:
            self._t_last = t
            self.ring.push([t, *np.degrees(c.q), *c.qd, pend.alpha, pend.beta, *state.tool_error_b2, w.length])
            sw = getattr(state, "swing", None)
            if sw is not None:
                err = sw.error if sw.error is not None else [math.nan] * 4
                self.swing_ring.push(
                    [t, *np.degrees([pend.alpha, pend.beta, *sw.estimate[:2], *err[:2], *sw.sigma[:2]]),
                     *(1000 * np.asarray(sw.offset[:2]))]
                )  # fmt: skip
            if state.scene is not None:
                self.scene.update_scene(state.scene)
            self._draw()

    def _shown(self, *plots) -> None:
        """A page of the tab on screen again: its plots drawn from the newest data and refitted."""
        self._draw()
        for p in plots:
            refit(p.getPlotItem())

    def _draw(self) -> None:
        for p in self.platforms.values():
            p.draw()
        r = self.ring
        if r.n < 2 or not self.isVisible():
            return
        t = r["t"]
        for k, c in enumerate(self.joint_curves):
            c.setData(t, r[f"q{k + 1}"])
        for c, col in zip(self.swing_curves, ("alpha", "beta"), strict=True):
            c.setData(t, np.degrees(r[col]))
        for c, col in zip(self.err_curves, ("err_x", "err_y", "err_z"), strict=True):
            c.setData(t, 1000 * r[col])
        self.wire_curve.setData(t, r["wire"])
        s = self.swing_ring
        if s.n >= 2:
            ts = s["t"]
            for c, col in zip(self.swing_state_curves, ("alpha", "alpha_hat", "beta", "beta_hat"), strict=True):
                c.setData(ts, s[col])
            self.swing_err_curves[0].setData(ts, s["err_a"])
            self.swing_err_curves[1].setData(ts, s["err_b"])
            two = 2 * np.maximum(s["sig_a"], s["sig_b"])
            self.swing_err_curves[2].setData(ts, two)
            self.swing_err_curves[3].setData(ts, -two)
            for c, col in zip(self.swing_off_curves, ("off_x", "off_y"), strict=True):
                c.setData(ts, s[col])
