"""The operator's main window: Teleop and Analysis tabs over a status area with STOP."""

from __future__ import annotations

from PyQt5.QtCore import QEvent, QSettings, Qt
from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import (
    QAbstractSpinBox,
    QAction,
    QApplication,
    QComboBox,
    QDockWidget,
    QLineEdit,
    QMainWindow,
    QMessageBox,
    QPlainTextEdit,
    QShortcut,
    QTabWidget,
)

from ui.analysis_tab import AnalysisTab
from ui.lab_tab import MotionLabTab
from ui.marine_tab import CraneHeadTab
from ui.teleop_tab import TeleopTab
from ui.widgets.status import StatusPanel


class MainWindow(QMainWindow):
    def __init__(
        self,
        link,
        engine=None,
        settings: QSettings | None = None,
        dialogs: bool = True,
        marine_link_factory=None,
        use_gl: bool | None = None,
        lab_link_factory=None,
    ) -> None:
        super().__init__()
        self.link = link
        self.engine = engine
        self.dialogs = dialogs  # tests record messages instead of blocking on modal dialogs
        self.messages: list[tuple[str, str]] = []
        self.settings = settings or QSettings("Bosun", "Bosun HMI")
        self.setWindowTitle("Bosun: universal teleoperation")
        self.tabs = QTabWidget()
        self.teleop = TeleopTab(link)
        self.analysis = AnalysisTab()
        self.tabs.addTab(self.teleop, "Teleop")
        self.tabs.addTab(self.analysis, "Analysis")
        self.crane_head = CraneHeadTab(marine_link_factory, use_gl=use_gl)
        self.tabs.addTab(self.crane_head, "Crane head")
        self.motion_lab = MotionLabTab(lab_link_factory, use_gl=use_gl)
        self.tabs.addTab(self.motion_lab, "Motion-Lab")
        # the scene engines start the first time their tab is shown
        self.tabs.currentChanged.connect(self._scene_tab_shown)
        self.setCentralWidget(self.tabs)
        self.status = StatusPanel()
        dock = QDockWidget("Status")
        dock.setObjectName("status-dock")
        dock.setWidget(self.status)
        dock.setFeatures(QDockWidget.DockWidgetMovable | QDockWidget.DockWidgetFloatable)
        self.addDockWidget(Qt.BottomDockWidgetArea, dock)

        self.status.stop_clicked.connect(self.estop)
        self.status.reset_clicked.connect(self.reset)
        for key in (Qt.Key_Space, Qt.Key_Escape):
            sc = QShortcut(QKeySequence(key), self)
            sc.setContext(Qt.ApplicationShortcut)
            sc.activated.connect(self.estop)
        QShortcut(QKeySequence("Ctrl+1"), self, activated=lambda: self.teleop.set_mode("position"))
        QShortcut(QKeySequence("Ctrl+2"), self, activated=lambda: self.teleop.set_mode("velocity"))
        menu = self.menuBar().addMenu("&File")
        act = QAction("Open robot XML…", self, triggered=self.teleop.choose_xml)
        act.setShortcut("Ctrl+O")
        menu.addAction(act)
        menu.addAction(QAction("Quit", self, triggered=self.close, shortcut="Ctrl+Q"))

        link.state.connect(self.on_state)
        link.log.connect(self.status.add_log)
        link.connection.connect(self.on_connection)
        link.reply.connect(self.on_reply)
        self.teleop.error.connect(self.show_error)
        self.analysis.error.connect(self.show_error)
        self.teleop.inputs.notice.connect(self.on_input_event)
        self.crane_head.notice.connect(self.on_marine_notice)
        self.motion_lab.notice.connect(self.on_marine_notice)
        self.status.lights["engine"].set("ok", "connected")
        self.status.add_log("info", f"connected to the engine at {link.client.url} as {link.role}")
        if link.note:
            self.status.add_log("warning", link.note)
        self.restore()
        QApplication.instance().installEventFilter(self)

    # ------------------------------------------------------------------ keyboard teleoperation
    def eventFilter(self, obj, ev) -> bool:
        """Arrows and Page Up/Down drive the stick while the Teleop tab is shown (not while typing)."""
        if ev.type() in (QEvent.KeyPress, QEvent.KeyRelease) and self.tabs.currentWidget() is self.teleop:
            focus = QApplication.focusWidget()
            typing = isinstance(focus, QLineEdit | QAbstractSpinBox | QPlainTextEdit | QComboBox)
            if not typing and not ev.isAutoRepeat() and self.isActiveWindow():
                return self.teleop.stick.key(ev.key(), ev.type() == QEvent.KeyPress)
        return False

    def _scene_tab_shown(self, i: int) -> None:
        w = self.tabs.widget(i)
        if w is self.crane_head:
            self.crane_head.connect_engine()
        elif w is self.motion_lab:
            self.motion_lab.connect_engine()

    # ------------------------------------------------------------------ actions
    def estop(self) -> None:
        self.link.send("estop", reason="STOP button")
        self.crane_head.estop()
        self.motion_lab.estop()
        self.status.add_log("error", "STOP pressed: E-STOP sent")

    def reset(self) -> None:
        self.link.send("reset")
        self.crane_head.reset()
        self.motion_lab.reset()

    def on_marine_notice(self, level: str, text: str) -> None:
        self.status.add_log(level, text)
        if level == "error" and ("refused" in text or "not started" in text or "engine:" in text):
            self.show_error("Motion-Lab" if text.startswith("Motion-Lab") else "Crane head", text)

    def show_error(self, title: str, message: str) -> None:
        self.messages.append((title, message))
        self.status.add_log("error", f"{title}: {message}")
        if self.dialogs:
            QMessageBox.critical(self, title, message)

    # ------------------------------------------------------------------ engine events
    def on_state(self, state: dict) -> None:
        f = state["flags"]
        self.status.show_estop(f["estop"])
        if f["estop"]:
            self.status.lights["plant"].set("error", "E-STOP")
        elif f["enabled"] and not f["stale_input"]:
            self.status.lights["plant"].set("ok", "moving" if any(abs(v) > 1e-6 for v in state["qdot"]) else "ready")
        else:
            self.status.lights["plant"].set("warn", "holding")
        if f["device"] and not f["stale_input"]:
            self.status.lights["input"].set("ok", f["device_name"][:24])
        else:
            self.status.lights["input"].set("warn", "no input")
        choice = (state["robot"], state["solver"], state["mode"])
        if choice != getattr(self, "_choice", None):
            self._choice = choice
            self.analysis.set_robot(state["robot"])
            for key, value in zip(("robot", "solver", "mode"), choice, strict=True):
                self.settings.setValue(key, value)

    def on_connection(self, ok: bool, message: str) -> None:
        self.status.lights["engine"].set("ok" if ok else "error", "connected" if ok else "LOST")
        if ok:
            self.status.add_log("info", message)
        else:
            self.show_error("Engine connection lost", message + ". The engine holds the robot when input stops.")

    def on_reply(self, re: str, ok: bool, error: str) -> None:
        if ok and re in ("set_robot", "set_solver", "set_mode", "reset", "estop"):
            self.status.add_log("info", f"{re}: done")

    def on_input_event(self, level: str, text: str) -> None:
        self.status.add_log(level, text)
        if level == "warning":
            self.statusBar().showMessage(text, 10_000)

    # ------------------------------------------------------------------ settings
    def restore(self) -> None:
        geom = self.settings.value("geometry")
        if geom is not None:
            self.restoreGeometry(geom)
        state = self.settings.value("windowState")
        if state is not None:
            self.restoreState(state)

    def closeEvent(self, ev) -> None:
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("windowState", self.saveState())
        self.teleop.stop_logger()
        self.crane_head.close_link()
        self.motion_lab.close_link()
        self.link.close()
        if self.engine is not None:
            self.engine.stop()
        super().closeEvent(ev)
