"""The Motion-Lab's "Comau & winch" page: the robot's and the winch's modes, the joints with their jog
buttons, the winch's spring-return speed slider, the REMOTE stick, VVMC on/off and their plots."""

from __future__ import annotations

import html
import math
from collections.abc import Callable

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import Qt, QTimer
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
    QPushButton,
    QSlider,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from ui.lab.common import COMAU_MODES, ENABLE_LOOK, JOG_RESEND_MS, STOP_COLOR, progress_bar, set_bar
from ui.widgets.columns import scroll_column
from ui.widgets.landing import LandingPanel
from ui.widgets.plots import axis_label, legend, refit, refit_on_show
from ui.widgets.status import MOVING
from ui.widgets.stick import VirtualStick

WINCH_MODES = ("local", "remote", "motion_comp")
#: the stick's group title, by VVMC (issue 30, item 4: REMOTE under VVMC moves the work point on EM1500)
DRIVE_TITLES = {
    False: "REMOTE drive (Comau tool x, y, z; winch w)",
    True: "VVMC drive (work point on EM1500 x, y, z; w lowers the load to the deck)",
    "world": "VVMC drive, world frame (the tool held still in the lab: x, y, z; w the load)",
}


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


class ComauWinchPage(QWidget):
    """``send(type, **fields)`` sends a command to the lab engine; ``on_shown()`` draws the newest data."""

    def __init__(self, send: Callable[..., None], on_shown: Callable[[], None]) -> None:
        super().__init__()
        self._send = send
        self.state = None  # the newest LabSnapshot
        self.desc = None  # the engine's LabDescription
        self._enable_look = ""
        grid = QGridLayout(self)
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
        self.joint_pos_bars = [progress_bar() for _ in range(3)]
        self.joint_speed_bars = [progress_bar() for _ in range(3)]
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
        self.winch_mode.activated.connect(lambda i: self._send("lab_winch", mode=WINCH_MODES[i]))
        wl.addRow("mode", self.winch_mode)
        self.wire_bar = progress_bar()
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
        rbox = self.drive_box = QGroupBox(DRIVE_TITLES[False])
        rl = QHBoxLayout(rbox)
        self.stick = VirtualStick(aux_axis="w winch")
        self.stick.setToolTip(
            "drives the Comau tool point (REMOTE, 0.25 m/s at full stick) and the winch (REMOTE, slider w); with VVMC "
            "on it moves the work point on EM1500 (x, y along the deck, z up) while VVMC holds the tool on it, and w "
            "lowers the load relative to the EM1500 deck; hold Shift or the ENABLE button (deadman); a joystick works "
            "the same way"
        )
        rl.addWidget(self.stick)
        # the landing on EM1500's deck beside the stick (issue 30, items 5 and 7; the simulated lab reports it)
        self.landing = LandingPanel(deck="EM1500", fast=0.1, ahc=("winch MOTION_COMP", "winch not compensating"))
        rl.addWidget(self.landing, 1)
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
        # the frame VVMC holds the tool in (issue 30, item 1): EM1500's deck (target, the paper's) or the lab's world
        self.frame = QComboBox()
        self.frame.addItems(["target", "world"])
        self.frame.setToolTip(
            "with VVMC on: target holds the tool on the work point on EM1500 (the paper's VVMC), world holds it still "
            "in the lab (only EM8000's motion compensated); the stick moves the point in that frame; a change "
            "disarms the stick"
        )
        self.frame.activated.connect(lambda i: self._send("set_frame", frame=self.frame.itemText(i)))
        vrow = QHBoxLayout()
        vrow.setContentsMargins(0, 0, 0, 0)
        vrow.addWidget(self.vvmc, 2)
        vrow.addWidget(QLabel("frame"))
        vrow.addWidget(self.frame, 1)
        left.addLayout(vrow)
        # the simulated lab's measurement-to-actuation delay and its prediction (issue 31, item 2): set with VVMC off
        self.delay = QDoubleSpinBox(decimals=2, minimum=0.0, maximum=2.0, singleStep=0.1, value=0.0, suffix=" s")
        self.delay.setToolTip(
            "the delay with which the Comau's and winch's laws see both platforms (simulated lab only; set with "
            "VVMC off)"
        )
        self.predict = QCheckBox("predict")
        self.predict.setToolTip(
            "feed the platforms' motion predicted the delay ahead (an online AR model; it fits 150 s after the "
            "delay is set)"
        )
        self.delay.editingFinished.connect(self._send_delay)
        self.predict.clicked.connect(lambda _on: self._send_delay())
        drow = QHBoxLayout()
        drow.setContentsMargins(0, 0, 0, 0)
        drow.addWidget(QLabel("delay"))
        drow.addWidget(self.delay, 1)
        drow.addWidget(self.predict, 1)
        left.addLayout(drow)
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

        def shown() -> None:
            on_shown()
            for p in (self.joint_plot, self.wire_plot):
                refit(p.getPlotItem())

        refit_on_show(self, shown)
        # the stick beside the wire plot, the joints below: stacked under a 200 px stick, the wire plot was
        # squeezed below its own header in a 1280×800 window
        right = QVBoxLayout()
        rbox.setMaximumHeight(200)
        top = QHBoxLayout()
        top.addWidget(rbox, 3)
        top.addWidget(self.wire_plot, 2)
        right.addLayout(top, 1)
        right.addWidget(self.joint_plot, 1)
        grid.addWidget(scroll_column(lw, max_width=480), 0, 0)  # the controls scroll, the plots keep the height
        grid.addLayout(right, 0, 1)
        grid.setColumnStretch(1, 1)

    # ------------------------------------------------------------------ Comau joint jog (issue 16, item 5)
    def _send_delay(self) -> None:
        self._send("set_lab_delay", delay=float(self.delay.value()), predict=bool(self.predict.isChecked()))

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
            b.released.connect(self.jog_release)
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
            self.jog_release()

    def jog_release(self) -> None:
        """The held jog ends: its speed zero to the engine (nothing when no jog is held)."""
        self._jog_timer.stop()
        if self._jogging is not None:
            self._send("lab_comau_jog", joint=self._jogging[0], speed=0.0)
            self._jogging = None

    def jog_refused(self) -> bool:
        """A refusal of the held jog: True the first time for this press (say it), False after (resent)."""
        told, self._jog_told = self._jog_told, True
        return not told

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

    def _slider(self, value: int) -> None:
        if self.winch_slider.isSliderDown() and not self._slider_timer.isActive():
            self._slider_timer.start()
        elif not self.winch_slider.isSliderDown():
            self._slider_timer.stop()
        if self.desc is not None and self.desc.winch is not None:
            vmax = self.desc.winch.speed_max  # u = value/100 · 0.2 m/s (the lab HMI, motionlab_plc.json)
            self._send("lab_winch", speed=vmax * value / 100.0)

    # ------------------------------------------------------------------ the engine's data
    def set_description(self, desc) -> None:
        """The winch's top speed and the Comau's joint-limit profile."""
        self.desc = desc
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

    def show_state(self, state) -> None:
        """Bars, modes, jog, ENABLE, VVMC and the readout as the engine reports them."""
        self.state = state
        self.landing.show_load(getattr(state, "load", None))
        self._show_jog(state)
        self._show_enable(state)
        c, w, d = state.comau, state.winch, self.desc
        if d is not None:
            for k in range(3):
                lo, hi = d.comau_lower[k], d.comau_upper[k]
                set_bar(self.joint_pos_bars[k], (c.q[k] - lo) / (hi - lo), f"{math.degrees(c.q[k]):.1f}°")
                use = abs(c.qd[k]) / d.comau_speed[k]
                set_bar(self.joint_speed_bars[k], use, f"{100 * use:.0f} %")
            wi = d.winch
            set_bar(self.wire_bar, (w.length - wi.min) / (wi.max - wi.min), f"{w.length:.3f} m")
        if c.mode in COMAU_MODES:  # the PLC may report a mode Bosun does not offer (shown in its light)
            self.comau_mode.setCurrentIndex(COMAU_MODES.index(c.mode))
        if w.mode in WINCH_MODES:
            self.winch_mode.setCurrentIndex(WINCH_MODES.index(w.mode))
        free = not state.estop  # the engine refuses every mode, winch and VVMC command until reset
        for widget in (self.comau_mode, self.winch_mode, self.vvmc):
            widget.setEnabled(free)
        self.winch_slider.setEnabled(free and w.mode == "local")
        look = "VVMC ON" if state.vvmc else "VVMC OFF"
        title = DRIVE_TITLES["world" if state.vvmc and getattr(state, "frame", "") == "world" else bool(state.vvmc)]
        if self.drive_box.title() != title:
            self.drive_box.setTitle(title)
        self.frame.setEnabled(free and bool(state.vvmc))
        simulated = getattr(getattr(state, "plant", None), "backend", "simulated") != "plc"
        for widget in (self.delay, self.predict):  # set with VVMC off, on the simulated lab (the engine refuses else)
            widget.setEnabled(free and simulated and not state.vvmc)
        delay, predict = float(getattr(state, "delay", 0.0)), bool(getattr(state, "predict", False))
        if not self.delay.hasFocus() and abs(self.delay.value() - delay) > 1e-9:
            self.delay.setValue(delay)  # what the engine has (a refusal leaves it)
        if self.predict.isChecked() != predict:
            self.predict.setChecked(predict)
        frame = getattr(state, "frame", "base")
        if frame in ("target", "world") and self.frame.currentText() != frame and not self.frame.view().isVisible():
            self.frame.setCurrentText(frame)  # the engine's (a VVMC starts in target)
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
        hz = getattr(state, "hazard", None)  # the work point's range edge near (issue 32, item 5)
        near = ""
        if hz is not None and hz.text:
            color = "#b06000" if hz.slowed else "inherit"
            near = f"<br><span style='color:{color}'>{html.escape(hz.text)}{' — slowing' if hz.slowed else ''}</span>"
        self.readout.setText(
            f"{stop}tool − work point {e:.1f} mm &nbsp; swing {math.degrees(pend.swing):.2f}° &nbsp; t {state.t:.1f} s"
            f"{near}"
        )

    def draw(self, ring) -> None:
        """The joint and wire plots from the lab's ring of samples (``ring.n`` ≥ 2)."""
        t = ring["t"]
        for k, c in enumerate(self.joint_curves):
            c.setData(t, ring[f"q{k + 1}"])
        self.wire_curve.setData(t, ring["wire"])
