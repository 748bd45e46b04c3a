"""The operator's main window: Teleop, Analysis, Crane head and Motion-Lab over a status area with STOP.

Safety rules the window keeps (docs/safety.md lists each with its test):

* STOP (the button, Space from any tab or dialog, a joystick's stop button) sends ``estop`` to
  every engine; the window says "E-STOP confirmed" only when an engine's state shows it latched,
  and raises the alarm "E-STOP NOT CONFIRMED" (resending every 100 ms) if that takes longer than
  100 ms.  Esc is not STOP (it closes drop-downs).
* No modal dialogs: errors go to a message bar and the log; the file chooser is non-modal.
* While a tab with an on-screen stick is shown, the stick owns the arrow keys, Page Up/Down and
  Shift (enable): they never reach other widgets.  A tab change, focus moving to a text field, or
  the window losing focus releases every key.
* Lost engine: every light says LOST/unknown, plots grey out, and the link reconnects by itself.
* The window opens within the screen (1280×800 at most) and never grows past it.
"""

from __future__ import annotations

import threading
import time
from dataclasses import asdict

import pyqtgraph as pg
from PyQt5.QtCore import QEvent, QSettings, Qt, QTimer
from PyQt5.QtGui import QGuiApplication, QKeySequence
from PyQt5.QtWidgets import (
    QAbstractSpinBox,
    QAction,
    QApplication,
    QDockWidget,
    QFrame,
    QGraphicsOpacityEffect,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QMainWindow,
    QPlainTextEdit,
    QPushButton,
    QScrollArea,
    QShortcut,
    QSizePolicy,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from app.engine.alarms import AlarmList
from ui.analysis_tab import AnalysisTab
from ui.lab_tab import MotionLabTab
from ui.marine_tab import CraneHeadTab
from ui.teleop_tab import TeleopTab
from ui.widgets.status import StatusPanel

ESTOP_CONFIRM_S = 0.1  # the engine's state must show the latch within this, else an alarm
MAX_SIZE = (1280, 800)
MESSAGE_COLORS = {"error": "#7a2421", "info": "#1f4e79"}


class FitTabs(QTabWidget):
    """Tabs whose pages sit in scroll areas, so no page can make the window taller than the screen.

    ``widget``, ``currentWidget`` and ``setCurrentWidget`` speak of the pages, not their scroll areas.
    """

    def __init__(self) -> None:
        super().__init__()
        self.pages: list[QWidget] = []

    def add(self, page: QWidget, label: str) -> None:
        area = QScrollArea()
        area.setWidget(page)
        area.setWidgetResizable(True)
        area.setFrameShape(QFrame.NoFrame)
        self.pages.append(page)
        self.addTab(area, label)

    def widget(self, i: int) -> QWidget | None:
        return self.pages[i] if 0 <= i < len(self.pages) else None

    def currentWidget(self) -> QWidget | None:
        return self.widget(self.currentIndex())

    def setCurrentWidget(self, w: QWidget) -> None:
        self.setCurrentIndex(self.pages.index(w))


class MessageBar(QFrame):
    """A non-blocking error line above the tabs (no modal dialog ever takes STOP away)."""

    def __init__(self) -> None:
        super().__init__()
        lay = QHBoxLayout(self)
        lay.setContentsMargins(8, 2, 4, 2)
        self.text = QLabel("")
        self.text.setWordWrap(True)
        lay.addWidget(self.text, 1)
        close = QPushButton("×")
        close.setFocusPolicy(Qt.NoFocus)
        close.setFixedWidth(28)
        close.setToolTip("dismiss (the message stays in the log)")
        close.clicked.connect(self.hide)
        lay.addWidget(close)
        self.hide()

    def show_message(self, title: str, message: str, level: str = "error") -> None:
        self.setStyleSheet(
            f"MessageBar {{ background: {MESSAGE_COLORS[level]}; border-radius: 4px; }} QLabel {{ color: white; }}"
        )
        first = message.strip().splitlines()[0] if message.strip() else ""
        self.text.setText(f"<b>{title}</b>: {first}")
        self.text.setToolTip(message)
        self.show()


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
        self.dialogs = dialogs  # kept for callers; errors never open a modal dialog
        self.messages: list[tuple[str, str]] = []
        self.settings = settings or QSettings("Bosun", "Bosun HMI")
        self.setWindowTitle("Bosun: universal teleoperation")
        self.tabs = FitTabs()
        self.teleop = TeleopTab(link)
        self.analysis = AnalysisTab(link)
        self.tabs.add(self.teleop, "Teleop")
        self.tabs.add(self.analysis, "Analysis")
        self.crane_head = CraneHeadTab(marine_link_factory, use_gl=use_gl)
        self.tabs.add(self.crane_head, "Crane head")
        self.motion_lab = MotionLabTab(lab_link_factory, use_gl=use_gl)
        self.tabs.add(self.motion_lab, "Motion-Lab")
        self.tabs.currentChanged.connect(self._tab_changed)
        self.banner = QLabel("")
        self.banner.setAlignment(Qt.AlignCenter)
        self.banner.setWordWrap(True)
        self.banner.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)  # text never widens the window
        self.banner.hide()
        self.message_bar = MessageBar()
        central = QWidget()
        cl = QVBoxLayout(central)
        cl.setContentsMargins(2, 2, 2, 2)
        cl.setSpacing(2)
        cl.addWidget(self.banner)
        cl.addWidget(self.message_bar)
        cl.addWidget(self.tabs, 1)
        self.setCentralWidget(central)
        self.status = StatusPanel()
        dock = QDockWidget("Status")
        dock.setObjectName("status-dock")
        dock.setWidget(self.status)
        dock.setFeatures(QDockWidget.DockWidgetMovable | QDockWidget.DockWidgetFloatable)
        self.addDockWidget(Qt.BottomDockWidgetArea, dock)

        self.status.stop_clicked.connect(self.estop)
        self.status.reset_clicked.connect(self.reset)
        self.status.role_clicked.connect(self.toggle_role)
        QShortcut(QKeySequence("Ctrl+1"), self, activated=lambda: self.teleop.set_mode("position"))
        QShortcut(QKeySequence("Ctrl+2"), self, activated=lambda: self.teleop.set_mode("velocity"))
        QShortcut(QKeySequence("F1"), self, activated=self.show_keys)
        menu = self.menuBar().addMenu("&File")
        act = QAction("Open robot XML…", self, triggered=self.teleop.choose_xml)
        act.setShortcut("Ctrl+O")
        menu.addAction(act)
        menu.addAction(QAction("Quit", self, triggered=self.close, shortcut="Ctrl+Q"))
        help_menu = self.menuBar().addMenu("&Help")
        help_menu.addAction(QAction("Keys and STOP…", self, triggered=self.show_keys, shortcut="F1"))

        link.state.connect(self.on_state)
        link.log.connect(self.status.add_log)
        link.connection.connect(lambda ok, msg: self.on_connection(ok, msg, "teleop"))
        link.reply.connect(self.on_reply)
        self.teleop.error.connect(self.show_error)
        self.analysis.error.connect(self.show_error)
        self.teleop.inputs.notice.connect(self.on_input_event)
        self.teleop.inputs.stop_pressed.connect(lambda dev: self.estop(f"stop button of {dev}"))
        self.crane_head.on_link = lambda lk: self._watch_link("crane head", lk)
        self.motion_lab.on_link = lambda lk: self._watch_link("Motion-Lab", lk)
        self.crane_head.notice.connect(self.on_marine_notice)
        self.motion_lab.notice.connect(self.on_marine_notice)
        self.motion_lab.plc_link.connect(lambda state, detail: self.status.lights["plc"].set(state, detail))
        self.status.alarms.ack.connect(self.acknowledge)
        self.gui_alarms = AlarmList("GUI", note=lambda lvl, text: None)
        self.status.lights["engine"].set("ok", "connected")
        self.status.add_log("info", f"connected to the engine at {link.client.url} as {link.role}")
        if link.note:
            self.status.add_log("warning", link.note)
        self._owned_keys: set[int] = set()  # stick keys pressed and not yet released
        self.estop_pending: dict[str, list] = {}  # origin -> [t_sent, t_last_send, (engine_id, estops) at send]
        self.lost: set[str] = set()
        self._confirm = QTimer(self)
        self._confirm.setInterval(10)
        self._confirm.timeout.connect(self._check_estop)
        self._confirm.start()
        self._alarm_timer = QTimer(self)
        self._alarm_timer.setInterval(200)
        self._alarm_timer.timeout.connect(self._refresh_alarms)
        self._alarm_timer.start()
        self.child_engines: list = []  # scene engine processes started by the GUI (the teleop one is ``engine``)
        self._restart_errors: list[str] = []
        self._watchdog = QTimer(self)
        self._watchdog.setInterval(1000)
        self._watchdog.timeout.connect(self.watch_engines)
        self._watchdog.start()
        self.restore()
        self.teleop.inputs.route(link, self.teleop.stick)
        app = QApplication.instance()
        app.installEventFilter(self)
        app.focusChanged.connect(self._focus_changed)
        app.applicationStateChanged.connect(self._app_state)

    # ------------------------------------------------------------------ engines
    def links(self) -> dict[str, object]:
        """Every engine this window talks to now (scene engines once their tab has connected them)."""
        out = {"teleop": self.link}
        if self.crane_head.link is not None:
            out["crane head"] = self.crane_head.link
        if self.motion_lab.link is not None:
            out["Motion-Lab"] = self.motion_lab.link
        return out

    def watch_engines(self) -> None:
        """A child engine process that died is started again on its URL; its link reconnects by itself
        and the new engine starts holding, its input disarmed."""
        if not self.isVisible():
            return
        while self._restart_errors:
            self.show_error("Engine not restarted", self._restart_errors.pop(0))
        for proc in ([self.engine] if self.engine is not None else []) + list(self.child_engines):
            code = proc.exited()
            if code is None or getattr(proc, "restarting", False):
                continue
            self.status.add_log("error", f"the {proc.plant} engine process exited (code {code}): restarting it")
            proc.restarting = True
            # off the GUI thread: STOP and the keyboard stay live while the new process starts
            threading.Thread(target=self._restart, args=(proc,), daemon=True).start()

    def _restart(self, proc) -> None:
        try:
            proc.restart()
        except Exception as err:  # it does not come back: the next watchdog tick tries again
            self._restart_errors.append(str(err))
        finally:
            proc.restarting = False

    # ------------------------------------------------------------------ keyboard
    def _stick_of_current_tab(self):
        page = self.tabs.currentWidget()
        if page is self.teleop:
            return self.teleop.stick
        if page is self.motion_lab:
            return self.motion_lab.stick
        return None

    def release_keys(self) -> None:
        for stick in (self.teleop.stick, self.motion_lab.stick):
            if stick.keys or stick.pad.held or stick.enabled:
                stick.release_all()

    @staticmethod
    def _typing() -> bool:
        w = QApplication.focusWidget()
        if isinstance(w, QPlainTextEdit):
            return not w.isReadOnly()
        return isinstance(w, QLineEdit | QAbstractSpinBox)

    def eventFilter(self, obj, ev) -> bool:
        """Space is STOP everywhere; the stick of the tab on screen owns its keys (see the module doc)."""
        t = ev.type()
        if t in (QEvent.KeyPress, QEvent.KeyRelease):
            key = ev.key()
            if key == Qt.Key_Space:
                if t == QEvent.KeyPress and not ev.isAutoRepeat():
                    self.estop("Space")
                return True  # never reaches a button or dialog
            stick = self._stick_of_current_tab()
            if stick is not None and key in stick.KEYS and self.isActiveWindow() and not self._typing():
                if not ev.isAutoRepeat():
                    stick.key(key, t == QEvent.KeyPress)
                    if t == QEvent.KeyPress:
                        self._owned_keys.add(key)
                if t == QEvent.KeyRelease and not ev.isAutoRepeat():
                    self._owned_keys.discard(key)
                return True  # auto-repeat too: arrows never switch tabs or move a combo box
            if key in self._owned_keys:
                # a key pressed for the stick and still held after a tab change: its auto-repeats and
                # release are swallowed too (they would walk the tab bar and start scene engines)
                if t == QEvent.KeyRelease and not ev.isAutoRepeat():
                    self._owned_keys.discard(key)
                return True
        elif t == QEvent.WindowDeactivate and obj is self:
            self.release_keys()
            self._owned_keys.clear()  # their releases go to another window
        return False

    def _focus_changed(self, old, new) -> None:
        if new is None or self._typing():
            self.release_keys()

    def _app_state(self, state) -> None:
        if state != Qt.ApplicationActive:
            self.release_keys()
            self._owned_keys.clear()

    def _tab_changed(self, i: int) -> None:
        self.release_keys()
        w = self.tabs.widget(i)
        for tab in (self.crane_head, self.motion_lab):
            # a scene no tab shows is paused (its time stands still, STOP still latches); shown, it resumes
            tab.set_shown(w is tab)
            if w is tab:
                tab.connect_engine()
        self._route_input()

    def _watch_link(self, origin: str, link) -> None:
        """A scene link however it was made (first view, the tab's Start button): lost engine, input."""
        link.connection.connect(lambda ok, msg, o=origin: self.on_connection(ok, msg, o))
        self._route_input()

    def _route_input(self) -> None:
        """Input goes to the engine of the tab on screen (none on Analysis)."""
        w = self.tabs.currentWidget()
        if w is self.teleop:
            self.teleop.inputs.route(self.link, self.teleop.stick)
        elif w is self.motion_lab:
            self.teleop.inputs.route(self.motion_lab.link, self.motion_lab.stick)
        elif w is self.crane_head:
            self.teleop.inputs.route(self.crane_head.link, None)
        else:
            self.teleop.inputs.route(None, None)

    def show_keys(self) -> None:
        """The shortcut overlay, in the message area (non-blocking)."""
        self.status.add_log("info", KEYS_HELP.replace("\n", " "))
        self.message_bar.show_message("Keys", KEYS_HELP, level="info")
        self.message_bar.text.setText(KEYS_HTML)

    # ------------------------------------------------------------------ STOP and reset
    def estop(self, why: str = "STOP button") -> None:
        now = time.monotonic()
        for origin, link in self.links().items():
            link.send("estop", reason=why[:200])
            if origin not in self.estop_pending:
                st = getattr(link, "latest", None)
                before = (st.engine.engine_id, st.engine.estops) if st is not None else (None, 0)
                self.estop_pending[origin] = [now, now, before]
        self.status.add_log("error", f"STOP ({why}): E-STOP sent to {', '.join(self.links())}; awaiting confirmation")
        self._update_banner()

    def _latched(self, origin: str) -> bool:
        link = self.links().get(origin)
        st = getattr(link, "latest", None) if link is not None else None
        return st is not None and st.estop

    def _confirms(self, origin: str, before: tuple) -> bool:
        """The engine's newest state shows the latch and counts an estop received after ours was sent
        (or comes from a new engine instance): an older latched state never confirms a new STOP."""
        link = self.links().get(origin)
        st = getattr(link, "latest", None)
        if st is None or not self._latched(origin) or origin in self.lost or not link.connected:
            return False
        engine_id, estops = before
        return st.engine.engine_id != engine_id or st.engine.estops > estops

    def _check_estop(self) -> None:
        now = time.monotonic()
        links = self.links()
        for origin in list(self.estop_pending):
            t_sent, t_last, before = self.estop_pending[origin]
            link = links.get(origin)
            if link is None:
                del self.estop_pending[origin]
                continue
            if self._confirms(origin, before):
                del self.estop_pending[origin]
                self.gui_alarms.set(f"estop_unconfirmed:{origin}", False)
                self.status.add_log("info", f"E-STOP confirmed by the {origin} engine ({1e3 * (now - t_sent):.0f} ms)")
                continue
            if now - t_sent > ESTOP_CONFIRM_S:
                self.gui_alarms.set(
                    f"estop_unconfirmed:{origin}",
                    True,
                    "critical",
                    f"E-STOP NOT CONFIRMED by the {origin} engine: still trying",
                    source=origin,
                )
                if now - t_last >= ESTOP_CONFIRM_S:
                    link.send("estop", reason="STOP (resent: not confirmed)")
                    self.estop_pending[origin][1] = now
        self._update_banner()

    def reset(self) -> None:
        for link in self.links().values():
            link.send("reset")
        self.status.add_log(
            "info", "Reset sent: machines hold where they are; centre the stick and press enable (or choose a mode)"
        )

    def _update_banner(self) -> None:
        latched = [o for o in self.links() if self._latched(o)]
        self.status.show_estop(bool(latched))
        late = [o for o, (t0, *_) in self.estop_pending.items() if time.monotonic() - t0 > ESTOP_CONFIRM_S]
        if late:
            text, color = f"E-STOP NOT CONFIRMED ({', '.join(late)}): the engine did not answer", "#b00000"
        elif latched:
            text, color = f"E-STOP LATCHED ({', '.join(latched)}): machines stopped; Reset to continue", "#c9302c"
        elif self.estop_pending:
            text, color = "STOP sent: awaiting the engine's confirmation", "#c9302c"
        elif self.lost:
            text, color = f"ENGINE LOST ({', '.join(sorted(self.lost))}): reconnecting…", "#b07000"
        else:
            text, color = "", ""
        if (text, color) == getattr(self, "_banner_shown", None):
            return
        self._banner_shown = (text, color)
        self.banner.setVisible(bool(text))
        self.banner.setText(text)
        self.banner.setStyleSheet(
            f"background: {color}; color: white; font-weight: bold; font-size: 14pt; padding: 4px; border-radius: 4px;"
        )

    # ------------------------------------------------------------------ alarms
    def toggle_role(self) -> None:
        """Release the operator role of every engine, or take it where it is free."""
        links = self.links()
        if any(getattr(lk, "role", "") == "operator" for lk in links.values()):
            for lk in links.values():
                if lk.role == "operator":
                    lk.release_operator()
            self.release_keys()
            self.status.add_log("info", f"operator role released on {', '.join(links)}: viewing only")
        else:
            for lk in links.values():
                lk.take_operator()
            self.status.add_log("info", "operator role requested (granted where free; input starts disarmed)")

    def _refresh_roles(self) -> None:
        rows = []
        for origin, lk in self.links().items():
            st = getattr(lk, "latest", None)
            rows.append((origin, getattr(lk, "role", "viewer"), st.engine.operator if st is not None else ""))
        self.status.show_roles(rows)

    def _refresh_alarms(self) -> None:
        self._refresh_roles()
        rows = []
        for origin, link in self.links().items():
            st = getattr(link, "latest", None)
            if origin in self.lost or st is None:
                continue  # its list is unknown while lost; the GUI's "engine lost" alarm stands for it
            rows += [{**asdict(a), "origin": origin} for a in st.alarms]
        rows += [{**a, "origin": "gui"} for a in self.gui_alarms.snapshot()]
        self.status.alarms.set_alarms(rows)

    def acknowledge(self, origin: str, key: str) -> None:
        if origin == "gui":
            self.gui_alarms.ack(key or None)
        else:
            link = self.links().get(origin)
            if link is not None:
                link.send("ack_alarm", **({"key": key} if key else {}))
        self._refresh_alarms()

    # ------------------------------------------------------------------ messages
    def on_marine_notice(self, level: str, text: str) -> None:
        self.status.add_log(level, text)
        if level == "error" and any(w in text for w in ("refused", "not started", "not sent", "engine:")):
            self.show_error("Motion-Lab" if text.startswith("Motion-Lab") else "Crane head", text)

    def show_error(self, title: str, message: str) -> None:
        """Non-blocking: the message bar and the log (STOP stays live)."""
        self.messages.append((title, message))
        self.status.add_log("error", f"{title}: {message}")
        self.message_bar.show_message(title, message)

    # ------------------------------------------------------------------ engine events
    def on_state(self, state) -> None:
        f = state.flags
        if state.estop:
            self.status.lights["plant"].set("error", "E-STOP")
        elif f.enabled and not f.stale_input:
            self.status.lights["plant"].set("ok", "moving" if any(abs(v) > 1e-6 for v in state.qdot) else "ready")
        else:
            self.status.lights["plant"].set("warn", "holding")
        if f.device and not f.stale_input:
            detail = ("" if f.armed else "not armed: ") + f.device_name[:32]
            self.status.lights["input"].set("ok" if f.armed else "warn", detail)
        else:
            self.status.lights["input"].set("warn", "no input")
        rt, late = state.engine.realtime_factor, state.engine.late_fraction
        if rt < 0.95 or late > 0.01:
            self.status.lights["engine"].set("warn", f"slow: {100 * rt:.0f} % real time, {100 * late:.0f} % late")
        elif self.link.connected:
            self.status.lights["engine"].set("ok", "connected")
        choice = (state.robot, state.solver, state.mode)
        if choice != getattr(self, "_choice", None):
            self._choice = choice
            for key, value in zip(("robot", "solver", "mode"), choice, strict=True):
                self.settings.setValue(key, value)

    def on_connection(self, ok: bool, message: str, origin: str = "teleop") -> None:
        self.gui_alarms.set(f"lost:{origin}", not ok, "critical", f"{origin} engine lost: reconnecting", source=origin)
        page = {"teleop": self.teleop, "crane head": self.crane_head, "Motion-Lab": self.motion_lab}[origin]
        grey(page, not ok)
        if ok:
            self.lost.discard(origin)
            self.status.add_log("info", f"{origin}: {message}")
            if origin == "teleop":
                self.status.lights["engine"].set("ok", "connected")
        else:
            self.lost.add(origin)
            if origin == "teleop":
                self.status.set_lost()
            if origin == "Motion-Lab":  # its engine is gone: nothing is known of the PLC link
                self.status.lights["plc"].set("unknown", "unknown")
            self.show_error(
                "Engine connection lost" if origin == "teleop" else f"{origin} engine lost",
                f"{message}. The engine holds its machines when input stops; reconnecting.",
            )
        self._update_banner()

    def on_reply(self, re: str, ok: bool, error: str) -> None:
        if ok and re in ("set_robot", "set_solver", "set_mode", "reset", "estop"):
            self.status.add_log("info", f"{re}: done")
        if not ok and "no longer the operator" in error:  # the engine gave the role away: say it, loudly
            self.gui_alarms.set("role_lost", True, "critical", f"Operator role lost: {error}", source="engine link")
            self.show_error("Operator role lost", error)

    def on_input_event(self, level: str, text: str) -> None:
        self.status.add_log(level, text)
        lost = level == "warning" and "unplugged" in text
        self.gui_alarms.set("device_lost", lost, "warning", text, source="input")
        if level == "warning":
            self.statusBar().showMessage(text, 10_000)

    # ------------------------------------------------------------------ size and settings
    def fit_to_screen(self, first: bool = False) -> None:
        """Never larger than the screen's free area (STOP stays visible); a first opening is at most 1280×800."""
        avail = (self.screen() or QGuiApplication.primaryScreen()).availableGeometry()
        self.setMaximumSize(avail.size())
        w, h = MAX_SIZE if first else (self.width(), self.height())
        self.resize(min(w, avail.width()), min(h, avail.height()))

    def restore(self) -> None:
        geom = self.settings.value("geometry")
        if geom is not None:
            self.restoreGeometry(geom)
        state = self.settings.value("windowState")
        if state is not None:
            self.restoreState(state)
        self.fit_to_screen(first=geom is None)

    def closeEvent(self, ev) -> None:
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("windowState", self.saveState())
        self._watchdog.stop()
        app = QApplication.instance()
        app.removeEventFilter(self)
        self.teleop.stop_logger()
        self.teleop.inputs.timer.stop()
        self.crane_head.close_link()
        self.motion_lab.close_link()
        self.link.close()
        if self.engine is not None:
            self.engine.stop()
        super().closeEvent(ev)


def grey(page: QWidget, on: bool) -> None:
    """Grey a page's 2D plots (pyqtgraph views) while its engine is lost; GL views are left alone."""
    for view in page.findChildren(pg.GraphicsView):
        if on:
            eff = QGraphicsOpacityEffect(view)
            eff.setOpacity(0.3)
            view.setGraphicsEffect(eff)
        else:
            view.setGraphicsEffect(None)


KEYS_HELP = """STOP: Space (any tab, any dialog), the STOP button, or the joystick's stop button. Esc is not STOP.
Reset E-STOP: the Reset button; machines keep holding until you command them anew.
Drive (Teleop and Motion-Lab tabs): hold Shift (or the ENABLE button) as the deadman, then arrows for x/y and
Page Up/Down for z. After a reset, a mode or robot change: stick at neutral, release and press enable again.
Ctrl+1 / Ctrl+2: position / velocity mode. Ctrl+O: open a robot file. F1: this help."""

KEYS_HTML = (
    "<b>STOP</b>: Space (any tab, any dialog) · STOP button · joystick stop button &nbsp;|&nbsp; Esc is <i>not</i> STOP"
    " &nbsp;|&nbsp; <b>Enable</b>: hold Shift or ENABLE &nbsp;|&nbsp; <b>Drive</b>: arrows x/y, PgUp/PgDn z"
    " &nbsp;|&nbsp; after reset / mode / robot change: neutral, then press enable again"
    " &nbsp;|&nbsp; Ctrl+1/2 mode · Ctrl+O robot file · F1 help"
)
