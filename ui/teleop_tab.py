"""Teleop tab: robot, solver, mode and scaling; input devices; 3D view; live plots; CSV logger."""

from __future__ import annotations

import os

from PyQt5.QtCore import QObject, Qt, QTimer, pyqtSignal
from PyQt5.QtWidgets import (
    QButtonGroup,
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QFrame,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QProgressBar,
    QPushButton,
    QRadioButton,
    QScrollArea,
    QSplitter,
    QVBoxLayout,
    QWidget,
)

from app.net.messages import MAX_ROBOT_TEXT
from ui.csv_logger import SIGNALS, StateCsvLogger
from ui.widgets.fields import EngineFields
from ui.widgets.files import choose_file
from ui.widgets.labels import ElidedLabel
from ui.widgets.plots import LivePlots, UtilisationBars
from ui.widgets.stick import VirtualStick
from ui.widgets.view3d import make_robot_view

MANUAL = "on-screen stick / keyboard"


#: the GA tasks the teleop tab offers (issue 32, item 4): name → (weights per world axis, tool axis or None);
#: the protocol's set_ga_task takes any numbers
GA_TASKS: dict[str, tuple[list[float], list[float] | None]] = {
    "published cost": ([1.0, 1.0, 1.0], None),
    "height first (z × 4)": ([1.0, 1.0, 4.0], None),
    "plan first (x, y × 4)": ([4.0, 4.0, 1.0], None),
    "tool pointing down": ([1.0, 1.0, 1.0], [0.0, 0.0, -1.0]),
    "tool down, height first": ([1.0, 1.0, 4.0], [0.0, 0.0, -1.0]),
}


class InputManager(QObject):
    """Polls the chosen input at 100 Hz and hands it to the engine of the tab on screen.

    Sources: any joystick pygame sees (hot-plug) or the on-screen stick and keyboard of that tab.
    The main window sets ``link`` (the engine that receives input, or None) and ``stick`` (the
    on-screen stick of the tab on screen, or None).  The link's own thread re-sends the sample at a
    fixed rate, so a busy GUI does not starve the engine of input.  A joystick's stop button (from
    its profile) emits ``stop_pressed`` whatever tab is shown.
    """

    sample = pyqtSignal(tuple, tuple, str)  # axes, buttons, device (for the live display)
    devices_changed = pyqtSignal(list)
    notice = pyqtSignal(str, str)  # level, text (not "event": that would shadow QObject.event)
    stop_pressed = pyqtSignal(str)  # device name

    def __init__(self, link, parent=None) -> None:
        super().__init__(parent)
        self.link = link
        self.stick = None
        self.choice = MANUAL
        self._stop_prev: dict[str, bool] = {}
        self._profiles: dict = {}
        try:
            from app.teleop.devices import PygameJoysticks

            self.sticks = PygameJoysticks()
        except Exception as err:
            self.sticks = None
            self.notice.emit("warning", f"joysticks unavailable: {err}")
        self.known: list[str] = []
        self.timer = QTimer(self)
        self.timer.setInterval(10)
        self.timer.timeout.connect(self.poll)
        self.timer.start()

    def route(self, link, stick) -> None:
        """Input now goes to ``link`` (None: nowhere), the on-screen source is ``stick``."""
        if link is not self.link and self.link is not None:
            self.link.clear_input(self.choice[:128], released=True)  # the engine left behind holds at once
        self.link, self.stick = link, stick

    def _check_stops(self) -> None:
        """The stop button of every connected joystick (from its profile) stops every engine, selected or not."""
        from app.teleop.profiles import profile_for

        for name, buttons in self.sticks.buttons_of_all():
            if name not in self._profiles:
                self._profiles[name] = profile_for(name, 0)
            b = self._profiles[name].stop_button
            pressed = b is not None and b < len(buttons) and buttons[b]
            if pressed and not self._stop_prev.get(name, False):
                self.stop_pressed.emit(name)
            self._stop_prev[name] = pressed

    def poll(self) -> None:
        joy = None
        if self.sticks is not None:
            self.sticks.select = None if self.choice == MANUAL else self.choice
            joy = self.sticks.poll()
            self._check_stops()
            for ev in self.sticks.take_events():
                level = "warning" if ev.kind == "removed" else "info"
                text = f"joystick {ev.device} {'unplugged: the robot holds' if ev.kind == 'removed' else 'plugged in'}"
                self.notice.emit(level, text)
                if ev.kind == "removed" and ev.device == self.choice and self.link is not None:
                    self.link.clear_input(ev.device[:128], released=False)
            names = self.sticks.devices()
            if names != self.known:
                self.known = names
                self.devices_changed.emit(names)
        if self.choice != MANUAL:
            if joy is not None:
                if self.link is not None:
                    self.link.send_input(joy.axes[:16], joy.buttons[:64], joy.device[:128])
                self.sample.emit(joy.axes, joy.buttons, joy.device)
            return
        if self.stick is None or self.link is None:
            return
        x, y, z, w, enabled = self.stick.values()
        # the default profile reads axes (0, 1 inverted, 2, 3) and button 0 as the deadman
        axes, buttons = (x, -y, z, w), (enabled,)
        self.link.send_input(axes, buttons, MANUAL)
        self.sample.emit(axes, buttons, MANUAL)


class TeleopTab(QWidget):
    error = pyqtSignal(str, str)  # title, message for a dialog

    def __init__(self, link, parent=None) -> None:
        super().__init__(parent)
        self.link = link
        self.logger: StateCsvLogger | None = None
        self.state = None  # the newest TeleopSnapshot
        self.desc = None  # the engine's TeleopDescription (robot library, solvers, limits, box)
        self._syncing = False
        outer = QHBoxLayout(self)
        split = QSplitter()
        outer.addWidget(split)

        # ---------------------------------------------------------- controls
        controls = QWidget()

        cl = QVBoxLayout(controls)
        area = QScrollArea()  # only the controls scroll; the 3D view and plots keep the full height
        area.setWidget(controls)
        area.setWidgetResizable(True)
        area.setFrameShape(QFrame.NoFrame)
        area.setHorizontalScrollBarPolicy(Qt.ScrollBarAlwaysOff)
        split.addWidget(area)

        g = QGroupBox("Manipulator")
        f = QFormLayout(g)
        self.robot = QComboBox()
        self.robot.setToolTip("robots the engine can drive (its library); loading one moves nothing")
        self.robot.activated.connect(lambda _i: self.choose_robot(self.robot.currentText()))
        self.opened: dict[str, tuple[str, str]] = {}  # robot name -> (file name, text) of files opened by path
        row = QHBoxLayout()
        row.addWidget(self.robot, 1)
        self.open_xml = QPushButton("Open…")
        self.open_xml.setToolTip(
            "load any robot file (XML: a DH table and limits) or a URDF; an invalid file keeps the current robot"
        )
        self.open_xml.clicked.connect(self.choose_xml)
        row.addWidget(self.open_xml)
        f.addRow("robot", row)
        self.solver = QComboBox()
        self.solver.setToolTip(
            "IK solvers that apply to this robot: ga (the paper's genetic algorithm), ga-restart (the same, re-seeded "
            "when it stalls), jacobian (damped least squares), analytic (closed form, Comau-type arms)"
        )
        self.solver.activated.connect(lambda _i: self.link.send("set_solver", solver=self.solver.currentText()))
        f.addRow("solver", self.solver)
        self.ga_task = QComboBox()
        self.ga_task.addItems(list(GA_TASKS))
        self.ga_task.setToolTip(
            "the GA's task (issue 32): weights of its position cost per axis and a tool-axis term; 'published "
            "cost' is the paper's. It shapes the GA's position mode; a change disarms the stick (centre it and "
            "hold enable again). Other solvers keep it for when a GA is chosen."
        )
        self.ga_task.activated.connect(lambda _i: self.send_ga_task(self.ga_task.currentText()))
        f.addRow("GA task", self.ga_task)
        mode_row = QHBoxLayout()
        self.mode_group = QButtonGroup(self)
        self.mode_pos = QRadioButton("position")
        self.mode_pos.setToolTip("position mode (Ctrl+1): x = k_p·s + x_w; releasing the stick returns to x_w")
        self.mode_vel = QRadioButton("velocity")
        self.mode_vel.setToolTip("velocity mode (Ctrl+2): ẋ = k_v·s; releasing the stick stops and holds")
        for b in (self.mode_pos, self.mode_vel):
            self.mode_group.addButton(b)
            mode_row.addWidget(b)
        self.mode_pos.clicked.connect(lambda: self.set_mode("position"))
        self.mode_vel.clicked.connect(lambda: self.set_mode("velocity"))
        f.addRow("mode", mode_row)
        self.frame = QComboBox()
        self.frame.addItems(["world", "base", "tool"])  # this scene has no target deck
        self.frame.setToolTip(
            "the frame the stick commands in (issue 30): world (earth-fixed, the papers' mapping), base (the robot's "
            "base) or tool (the tool, as it turns); position and velocity modes and the scaling act in it; a "
            "change disarms the stick (centre it and hold enable again)"
        )
        self.frame.activated.connect(lambda _i: self.link.send("set_frame", frame=self.frame.currentText()))
        f.addRow("frame", self.frame)
        self.hazard = ElidedLabel("–")  # one line: the nearest hazard and its distance (issue 32, item 5)
        self.hazard.setToolTip(
            "the hazard nearest its stop while you drive: a collision (the arm's capsules, the floor), a singularity "
            "or a joint limit, and its distance; amber while it slows the command (only the part of it that "
            "approaches the hazard: moving away is never slowed)"
        )
        f.addRow("hazard", self.hazard)
        cl.addWidget(g)

        g = QGroupBox("Input")
        il = QVBoxLayout(g)
        self.device = QComboBox()
        self.device.addItem(MANUAL)
        self.device.setToolTip(
            "input device: a joystick (hot-plug) or the on-screen stick and keyboard "
            "(hold Shift to enable; arrows: x/y, Page Up/Down: z)"
        )
        il.addWidget(self.device)
        self.axes_bars = []
        axes_row = QHBoxLayout()
        for k in range(6):
            b = QProgressBar()
            b.setRange(-1000, 1000)
            b.setTextVisible(False)
            b.setMaximumHeight(10)
            b.setMinimumWidth(20)
            b.setToolTip(f"raw axis {k} of the input device, in [−1, 1]")
            self.axes_bars.append(b)
            axes_row.addWidget(b)
        il.addLayout(axes_row)
        self.buttons_label = ElidedLabel("buttons: –")  # a long device name ends in "…", whole in the tool tip
        self.buttons_label.setToolTip("buttons held on the input device")
        il.addWidget(self.buttons_label)
        self.stick = VirtualStick()
        il.addWidget(self.stick)
        cl.addWidget(g)

        g = QGroupBox("Workspace scaling (eqs. 1–2)")
        grid = QGridLayout(g)
        self.k_p = self._spin(0.0, 1e4, 3, "k_p: tool displacement per full stick deflection [m]")
        self.k_v = self._spin(0.0, 1e3, 3, "k_v: tool speed per full stick deflection [m/s]")
        self.x_w = [self._spin(-1e5, 1e5, 3, f"x_w {a}: origin of the virtual workspace [m]") for a in "xyz"]
        # a label column on the left, the x, y, z columns headed; k_p and k_v take the x column
        for k, a in enumerate("xyz"):
            head = QLabel(a)
            head.setAlignment(Qt.AlignCenter)
            grid.addWidget(head, 0, 1 + k)
        for row, (text, tip, widgets) in enumerate(
            (
                ("x_w [m]", "origin of the virtual workspace (eq. 1)", self.x_w),
                ("k_p [m]", "position gain: displacement per full deflection (eq. 1)", [self.k_p]),
                ("k_v [m/s]", "velocity gain: speed per full deflection (eq. 2)", [self.k_v]),
            ),
            start=1,
        ):
            label = QLabel(text)
            label.setToolTip(tip)
            label.setAlignment(Qt.AlignRight | Qt.AlignVCenter)
            grid.addWidget(label, row, 0)
            for k, w in enumerate(widgets):
                grid.addWidget(w, row, 1 + k)
        self.scaling_fields = EngineFields(self)
        for w in (*self.x_w, self.k_p, self.k_v):
            w.setMinimumWidth(70)
            self.scaling_fields.add(w)
        for k in range(3):
            grid.setColumnStretch(1 + k, 1)
        self.apply_scaling = QPushButton("Apply")
        self.apply_scaling.setToolTip("send k_p, x_w and k_v to the engine (Esc in a field reverts it)")
        self.apply_scaling.clicked.connect(self.send_scaling)
        grid.addWidget(self.apply_scaling, 3, 2, 1, 2)
        self.scaling_note = ElidedLabel("")  # one line, its room kept while empty: the logger below never moves
        self.scaling_note.setFixedHeight(self.scaling_note.fontMetrics().height() + 4)
        self.scaling_note.setStyleSheet("color: #b08000;")
        grid.addWidget(self.scaling_note, 4, 0, 1, 4)
        self.scaling_fields.dirty_changed.connect(
            lambda on: self.scaling_note.setText("edited (yellow): Apply sends, Esc reverts" if on else "")
        )
        cl.addWidget(g)

        g = QGroupBox("CSV logger")
        lg = QFormLayout(g)
        path_row = QHBoxLayout()
        self.log_path = QLineEdit(os.path.join(os.getcwd(), "bosun_log.csv"))
        self.log_path.setToolTip("file the logger writes (overwritten)")
        browse = QPushButton("…")
        browse.setToolTip("choose the log file")
        browse.clicked.connect(self._browse_log)
        path_row.addWidget(self.log_path, 1)
        path_row.addWidget(browse)
        lg.addRow("file", path_row)
        self.log_duration = self._spin(0.0, 86400.0, 1, "logging duration [s] of engine time; 0 = until stopped")
        self.log_duration.setValue(60.0)
        lg.addRow("duration [s]", self.log_duration)
        sig_row = QGridLayout()
        self.log_signals = {}
        for k, name in enumerate(SIGNALS):
            cb = QCheckBox(name)
            cb.setChecked(name in ("q", "tool", "target"))
            cb.setToolTip(f"log '{name}' columns")
            self.log_signals[name] = cb
            sig_row.addWidget(cb, k // 3, k % 3)  # three a row: the column stays narrow enough to show whole
        lg.addRow("signals", sig_row)
        self.log_button = QPushButton("Start logging")
        self.log_button.setToolTip("start or stop writing engine states to the CSV file")
        self.log_button.clicked.connect(self.toggle_logger)
        self.log_rows = QLabel("")
        lg.addRow(self.log_button, self.log_rows)
        cl.addWidget(g)
        cl.addStretch(1)

        # ---------------------------------------------------------- view and plots
        middle = QWidget()
        ml = QVBoxLayout(middle)
        self.view = make_robot_view()
        ml.addWidget(self.view, 3)
        self.bars = UtilisationBars()
        ml.addWidget(self.bars, 1)
        split.addWidget(middle)
        self.plots = LivePlots()
        split.addWidget(self.plots)
        for combo in (self.robot, self.solver, self.ga_task, self.device):  # long names must not widen the column
            combo.setSizeAdjustPolicy(QComboBox.AdjustToMinimumContentsLengthWithIcon)
            combo.setMinimumContentsLength(14)
        # the column is as wide as its widest control needs (nothing cut at its right edge) plus the scroll bar
        bar = area.verticalScrollBar().sizeHint().width()
        area.setMinimumWidth(controls.minimumSizeHint().width() + bar + 4)
        split.setSizes([area.minimumWidth(), 400, 460])

        self.inputs = InputManager(link, self)
        self.inputs.stick = self.stick
        self.inputs.sample.connect(self.show_sample)
        self.inputs.devices_changed.connect(self._devices)
        self.device.activated.connect(lambda _i: setattr(self.inputs, "choice", self.device.currentText()))
        self._dirty = False
        link.state.connect(self.on_state)
        link.described.connect(self.on_description)
        link.states.connect(self.log_states)
        link.reply.connect(self.on_reply)
        self.plots.frame.connect(self.refresh)
        if link.description is not None:
            self.on_description(link.description)

    @staticmethod
    def _spin(lo: float, hi: float, decimals: int, tip: str) -> QDoubleSpinBox:
        s = QDoubleSpinBox()
        s.setRange(lo, hi)
        s.setDecimals(decimals)
        s.setToolTip(tip)
        return s

    # ------------------------------------------------------------------ commands
    def choose_xml(self) -> None:
        """A non-modal file chooser: STOP and the rest of the window stay live while it is open."""
        self.file_dialog = choose_file(
            self, "Open robot file", os.getcwd(), "Robot files (*.xml *.urdf)", self.load_robot_file
        )

    def load_robot_file(self, path: str) -> None:
        """Send the chosen file's text: the engine reads no path outside its robot folders."""
        from app.errors import RobotXmlError
        from app.models.xml import decode_robot_xml

        name = os.path.basename(path)
        try:
            size = os.path.getsize(path)
            if size > MAX_ROBOT_TEXT:
                raise ValueError(f"{size} bytes; files over {MAX_ROBOT_TEXT} bytes go in a robot folder")
            with open(path, "rb") as fh:
                data = fh.read(MAX_ROBOT_TEXT + 1)
            text = decode_robot_xml(data, name)  # as the engine reads a file: mark, declaration, UTF-8
        except RobotXmlError as err:
            self.error.emit("Robot not loaded", str(err))
            return
        except (OSError, ValueError) as err:
            self.error.emit("Robot not loaded", f"{name}: {getattr(err, 'strerror', None) or err}")
            return
        self.link.send("set_robot", robot=name, xml=text)
        self._pending_file = (name, text)

    def choose_robot(self, name: str) -> None:
        """A library robot by name; a file opened earlier by its text again (the engine has no path to it)."""
        if self.desc is not None and name == self.desc.robot:
            return
        if name in self.opened:
            file_name, text = self.opened[name]
            self.link.send("set_robot", robot=file_name, xml=text)
        else:
            self.link.send("set_robot", robot=name)

    def _sync_ga_task(self, state) -> None:
        """The GA task combo shows the engine's task: its preset, or a custom line (another client's numbers)."""
        weights = [float(v) for v in getattr(state, "ga_weights", [1.0, 1.0, 1.0])]
        axis = getattr(state, "ga_axis", None)
        axis_weight = float(getattr(state, "ga_axis_weight", 0.0))
        name = next(
            (n for n, (w, a) in GA_TASKS.items()
             if w == weights and a == (None if axis is None else [round(v, 9) for v in axis])
             and axis_weight == (0.0 if a is None else 1.0)),
            None,
        )  # fmt: skip
        if name is None:
            axis_text = "" if axis is None else f", axis ({', '.join(f'{v:.2g}' for v in axis)}) × {axis_weight:g}"
            name = f"custom: weights ({', '.join(f'{v:g}' for v in weights)}){axis_text}"
            if self.ga_task.findText(name) < 0:
                self.ga_task.addItem(name)
        if self.ga_task.currentText() != name and not self.ga_task.view().isVisible():
            self.ga_task.setCurrentText(name)
        ga = str(state.solver).startswith("ga")
        if self.ga_task.isEnabled() != ga:
            self.ga_task.setEnabled(ga)

    def set_mode(self, mode: str) -> None:
        self.link.send("set_mode", mode=mode)

    def send_scaling(self) -> None:
        k_p, k_v = self.k_p.value(), self.k_v.value()
        self.link.send("set_scaling", k_p=[k_p] * 3, k_v=[k_v] * 3, x_w=[s.value() for s in self.x_w])

    def send_ga_task(self, name: str) -> None:
        preset = GA_TASKS.get(name)
        if preset is None:  # a task set by another client: shown, not re-sent
            return
        weights, axis = preset
        self.link.send("set_ga_task", weights=weights, **({} if axis is None else {"axis": axis}))

    def on_reply(self, re: str, ok: bool, error: str) -> None:
        if not ok and re in ("set_robot", "set_solver", "set_ga_task", "set_mode", "set_frame", "set_scaling",
                             "invalid"):  # fmt: skip
            what = {"set_robot": "Robot not loaded", "set_solver": "Solver not changed",
                    "set_ga_task": "GA task not changed"}.get(re, "Command refused")  # fmt: skip
            self.error.emit(what, error)

    # ------------------------------------------------------------------ display
    def _devices(self, names: list) -> None:
        current = self.device.currentText()
        self.device.clear()
        self.device.addItems([MANUAL, *names])
        if current in names:
            self.device.setCurrentText(current)
        elif current != MANUAL:
            self.inputs.choice = MANUAL

    def show_sample(self, axes: tuple, buttons: tuple, device: str) -> None:
        for k, b in enumerate(self.axes_bars):
            b.setValue(int(1000 * axes[k]) if k < len(axes) else 0)
        held = [str(i) for i, v in enumerate(buttons) if v]
        self.buttons_label.setText(f"buttons: {' '.join(held) if held else '–'}   ({device})")

    def on_description(self, desc) -> None:
        """The engine's robot library, the solvers that apply to its robot, joint limits and box."""
        if getattr(desc, "kind", None) != "teleop":
            return
        self.desc = desc
        pending = getattr(self, "_pending_file", None)
        if pending is not None and desc.robot_xml == pending[1]:
            self.opened[desc.robot] = pending  # the file's robot as the engine named it
            self._pending_file = None
        names = [r.name for r in desc.robots]
        names += [n for n in self.opened if n not in names]
        if desc.robot not in names:
            names.append(desc.robot)  # a robot opened by path: shown, chosen again by its name
        _set_items(self.robot, names, desc.robot)
        _set_items(self.solver, desc.solvers, self.state.solver if self.state is not None else None)
        self.plots.set_description(desc)
        self.view.set_description(desc)
        self._dirty = True

    def on_state(self, state) -> None:
        """The newest state; widgets are refreshed from it once per plot frame."""
        self.state = state
        self._dirty = True

    def log_states(self, states: list) -> None:
        """Every snapshot the engine published goes to the plots' buffer and the CSV logger, also when the
        GUI lags behind the stream."""
        for st in states:
            self.plots.add_state(st)
            if self.logger is not None and not self.logger.add(st):
                self.stop_logger()

    def refresh(self) -> None:
        """Once per frame (30/s): view, bars and controls from the newest state."""
        if not self._dirty or self.state is None:
            return
        self._dirty = False
        state = self.state
        self.view.update_state(state)
        self.bars.update_state(state, self.desc)
        if self.logger is not None:
            self.log_rows.setText(f"{self.logger.rows} rows")
        self._sync_controls(state)

    def _sync_controls(self, state) -> None:
        """Controls follow the engine, touched only where they differ (each change relayouts)."""
        if self.robot.currentText() != state.robot:
            if self.robot.findText(state.robot) < 0:
                self.robot.addItem(state.robot)
            self.robot.setCurrentText(state.robot)
        if self.solver.currentText() != state.solver:
            if self.solver.findText(state.solver) < 0:
                self.solver.addItem(state.solver)
            self.solver.setCurrentText(state.solver)
        self._sync_ga_task(state)
        button = self.mode_pos if state.mode == "position" else self.mode_vel
        if not button.isChecked():
            button.setChecked(True)
        frame = getattr(state, "frame", "world")
        if self.frame.currentText() != frame and not self.frame.view().isVisible():  # the engine's frame
            self.frame.setCurrentText(frame)
        hz = getattr(state, "hazard", None)
        slowing = hz is not None and hz.slowed
        text = (hz.text if hz is not None and hz.text else "none near") + (" — slowing" if slowing else "")
        if self.hazard.text() != text:
            self.hazard.setText(text)
            self.hazard.setStyleSheet("color: #b06000; font-weight: bold;" if slowing else "")
        sc = state.scaling
        if sc is None:
            return
        # an edit the operator has not applied stays (highlighted) until Apply or Esc
        for w, v in ((self.k_p, sc.k_p[0]), (self.k_v, sc.k_v[0]), *zip(self.x_w, sc.x_w, strict=True)):
            self.scaling_fields.engine_value(w, v)

    # ------------------------------------------------------------------ logger
    def _browse_log(self) -> None:
        choose_file(self, "Log file", self.log_path.text(), "CSV (*.csv)", self.log_path.setText, save=True)

    def toggle_logger(self) -> None:
        if self.logger is None:
            self.start_logger()
        else:
            self.stop_logger()

    def start_logger(self) -> None:
        signals = [n for n, cb in self.log_signals.items() if cb.isChecked()]
        duration = self.log_duration.value() or None
        try:
            names = self.desc.joint_names if self.desc is not None else None
            self.logger = StateCsvLogger(self.log_path.text(), signals, duration, names)
        except (OSError, ValueError) as err:
            self.error.emit("Logger not started", str(err))
            return
        self.log_button.setText("Stop logging")
        self.log_rows.setText("0 rows")

    def stop_logger(self) -> None:
        if self.logger is not None:
            self.logger.close()
            self.log_rows.setText(f"{self.logger.rows} rows written to {os.path.basename(self.log_path.text())}")
            self.logger = None
        self.log_button.setText("Start logging")


def _set_items(combo: QComboBox, items: list[str], current: str | None) -> None:
    """Replace a combo box's items (only when they differ: a change relayouts), keeping ``current`` chosen."""
    if [combo.itemText(i) for i in range(combo.count())] != list(items):
        combo.blockSignals(True)
        combo.clear()
        combo.addItems(list(items))
        combo.blockSignals(False)
    if current is not None and combo.findText(current) >= 0 and combo.currentText() != current:
        combo.setCurrentText(current)
