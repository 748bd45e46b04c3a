"""The Motion-Lab HMI's bottom, below every page (issue 16, item 5): its "Machine and Sensor States" lights
and its CSV logger (file, duration 1–1200 s, start / stop, progress, sample count)."""

from __future__ import annotations

import os

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QHBoxLayout, QLabel, QLineEdit, QPushButton, QSpinBox, QVBoxLayout, QWidget

from ui.csv_logger import LAB_DURATION_RANGE, LabCsvLogger
from ui.lab.common import MACHINE_LIGHT, MACHINES, progress_bar, set_bar
from ui.widgets.files import choose_file
from ui.widgets.status import StatusLight


class StatusStrip(QWidget):
    """The machine and sensor lights as the engine reports them, and the logger of every published state."""

    notice = pyqtSignal(str, str)  # level, text

    def __init__(self) -> None:
        super().__init__()
        self.logger: LabCsvLogger | None = None
        col = QVBoxLayout(self)
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
        self.log_progress = progress_bar()
        set_bar(self.log_progress, 0.0, "not logging")
        row.addWidget(self.log_progress, 2)
        self.log_samples = QLabel("0 samples")
        self.log_samples.setMinimumWidth(90)
        row.addWidget(self.log_samples)
        col.addLayout(row)

    def show_machines(self, state) -> None:
        """Each machine's light as the engine reports it; '?' for one it does not (or no engine)."""
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
        set_bar(self.log_progress, lg.progress, f"{lg.elapsed:.1f} / {lg.duration:g} s")
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
