"""Status area as in the lab's HMI: a light per subsystem, the alarm list, a timestamped log, a big STOP."""

from __future__ import annotations

import time

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QFont
from PyQt5.QtWidgets import (
    QHBoxLayout,
    QLabel,
    QPlainTextEdit,
    QPushButton,
    QSplitter,
    QVBoxLayout,
    QWidget,
)

from ui.widgets.alarms import AlarmPanel
from ui.widgets.labels import ElidedLabel

LIGHT = {"ok": "#3c9d3c", "warn": "#e0a020", "error": "#d9534f", "off": "#666666", "unknown": "#8a8aa0"}


class StatusLight(ElidedLabel):
    """A light: "● name: detail"; a detail too long for its room ends in "…" (whole in the tool tip),
    it never widens the window."""

    def __init__(self, name: str, tooltip: str, parent=None) -> None:
        super().__init__("", parent)
        self.name = name
        self.setToolTip(tooltip)
        self.setMinimumWidth(120)
        self.state = "off"
        self.set("off")

    def set(self, state: str, detail: str = "") -> None:
        if (state, detail) == getattr(self, "_shown", None):
            return  # restyling a label relayouts the window: only on change
        self._shown = (state, detail)
        self.state = state
        self.setText(f"● {self.name}{': ' + detail if detail else ''}")
        self.setStyleSheet(f"color: {LIGHT[state]}; font-weight: bold; padding: 2px 6px;")


class StatusPanel(QWidget):
    stop_clicked = pyqtSignal()
    reset_clicked = pyqtSignal()
    role_clicked = pyqtSignal()  # release the operator role, or take it when free

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(4, 2, 4, 2)
        self.setMaximumHeight(230)  # the machines stay in view on a 800-px screen
        left = QVBoxLayout()
        lights = QHBoxLayout()
        self.lights = {
            "engine": StatusLight("engine", "engine connection and loop"),
            "input": StatusLight("input", "input device: joystick, on-screen stick or keyboard"),
            "plant": StatusLight("plant", "simulated manipulator: moving, holding, E-STOP"),
            "plc": StatusLight(
                "PLC", "the Motion-Lab's PLC link (bosun server --plant lab --plc): simulated, ok, lost, error"
            ),
        }
        for w in self.lights.values():
            lights.addWidget(w, 1)
        left.addLayout(lights)
        split = QSplitter(Qt.Horizontal)
        self.alarms = AlarmPanel()
        split.addWidget(self.alarms)
        self.log_view = QPlainTextEdit()
        self.log_view.setReadOnly(True)
        self.log_view.setMaximumBlockCount(2000)
        self.log_view.setToolTip("event log (UTC time stamps); always scrolled to the newest line")
        self.log_view.setFocusPolicy(Qt.NoFocus)
        split.addWidget(self.log_view)
        split.setSizes([560, 440])
        left.addWidget(split, 1)
        lay.addLayout(left, 1)
        right = QVBoxLayout()
        self.stop = QPushButton("STOP")
        self.stop.setFocusPolicy(Qt.NoFocus)  # never takes the keyboard: Space stays STOP everywhere
        self.stop.setMinimumSize(150, 80)
        f = QFont()
        f.setPointSize(22)
        f.setBold(True)
        self.stop.setFont(f)
        self.stop.setStyleSheet(
            "QPushButton { background: #c9302c; color: white; border-radius: 8px; }"
            "QPushButton:pressed { background: #8b1e1b; }"
        )
        self.stop.setToolTip(
            "E-STOP: stops every machine within one engine tick and latches (Space, from any tab or dialog, "
            "or the joystick's stop button)"
        )
        self.stop.pressed.connect(self.stop_clicked)  # on press: a press that slides off still stops
        right.addWidget(self.stop)
        self.latched = QLabel("")
        self.latched.setStyleSheet("color: #d9534f; font-weight: bold;")
        right.addWidget(self.latched)
        self.reset = QPushButton("Reset E-STOP")
        self.reset.setFocusPolicy(Qt.NoFocus)
        self.reset.setToolTip(
            "clear a latched E-STOP (operator only); every machine keeps holding until you command it anew: "
            "centre the stick and press enable, or choose a mode"
        )
        self.reset.setEnabled(False)
        self.reset.clicked.connect(self.reset_clicked)
        right.addWidget(self.reset)
        self.role = QLabel("role: –")
        self.role.setWordWrap(True)
        self.role.setMaximumWidth(190)
        self.role.setToolTip("who holds the operator role of each engine; viewers see everything and may STOP")
        right.addWidget(self.role)
        self.role_button = QPushButton("Release operator role")
        self.role_button.setFocusPolicy(Qt.NoFocus)
        self.role_button.setToolTip(
            "release: the engines hold and another console may take over; take: become the operator where the "
            "role is free (you start disarmed)"
        )
        self.role_button.clicked.connect(self.role_clicked)
        right.addWidget(self.role_button)
        right.addStretch(1)
        lay.addLayout(right)

    def add_log(self, level: str, text: str) -> None:
        stamp = time.strftime("%H:%M:%S", time.gmtime())
        self.log_view.appendPlainText(f"{stamp}  {level.upper():7s} {text}")
        bar = self.log_view.verticalScrollBar()
        bar.setValue(bar.maximum())  # always the newest entry, also after the operator scrolled up

    def show_estop(self, latched: bool) -> None:
        if latched == getattr(self, "_latched_shown", None):
            return
        self._latched_shown = latched
        self.latched.setText("E-STOP LATCHED" if latched else "")
        self.reset.setEnabled(latched)

    def show_roles(self, rows: list[tuple[str, str, str]]) -> None:
        """``rows``: (engine, this console's role, operator name) per engine."""
        text = "<br>".join(
            f"{origin}: <b>{'you operate' if role == 'operator' else 'viewer'}</b>"
            + ("" if role == "operator" else f" (operator: {op or 'free'})")
            for origin, role, op in rows
        )
        if text != self.role.text():
            self.role.setText(text or "role: –")
        mine = any(role == "operator" for _, role, _ in rows)
        label = "Release operator role" if mine else "Take operator role"
        if self.role_button.text() != label:
            self.role_button.setText(label)
        free = any(role != "operator" and not op for _, role, op in rows)
        self.role_button.setEnabled(mine or free)

    def set_lost(self) -> None:
        """The engine is out of reach: nothing is known about input or plant."""
        self.lights["engine"].set("error", "LOST")
        self.lights["input"].set("unknown", "unknown")
        self.lights["plant"].set("unknown", "unknown")
