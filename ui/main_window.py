"""The operator's main window: Teleop, Analysis, Crane head and Motion-Lab over a status area with STOP.

Safety rules the window keeps (docs/safety.md lists each with its test):

* STOP (the button, Space from any tab or dialog, Ctrl+Space also in a text field, a joystick's stop
  button) sends ``estop`` to every engine; the window says "E-STOP confirmed" only when an engine's
  state shows it latched, and raises the alarm "E-STOP NOT CONFIRMED" (resending every 100 ms) if
  that takes longer than 100 ms.  Esc is not STOP (it closes drop-downs).  In a text field that has
  the keyboard (a file name, a log path) Space types a space; everywhere else it is STOP.
* No modal dialogs: errors go to the message bar and the log; the file chooser is non-modal.
* The page stays put (ui/notices.py): the banner and the message bar sit beside the tab bar, in room
  of their own, so no control ever moves when one appears or goes; each message is tied to its
  condition and cleared when that is gone.  The wheel changes a set-point only in the field that has
  the keyboard (ui/input_guard.py).
* ENABLE shows the engine's view of the input (enabled, armed, E-STOP) from its snapshots.
* While a tab with an on-screen stick is shown, the stick owns the arrow keys, Page Up/Down and
  Shift (enable): they never reach other widgets.  A tab change, focus moving to a text field, or
  the window losing focus releases every key.
* Lost engine: every light says LOST/unknown, plots grey out, and the link reconnects by itself.
* The window opens within the screen's free area (1280×800 at most), its frame included: the frame's
  top at the free area's top on a first opening, never past its edges.
"""

from __future__ import annotations

import re
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
    QComboBox,
    QDockWidget,
    QFrame,
    QGraphicsOpacityEffect,
    QLineEdit,
    QMainWindow,
    QPlainTextEdit,
    QScrollArea,
    QShortcut,
    QTabWidget,
    QTextEdit,
    QVBoxLayout,
    QWidget,
)

from app.engine.alarms import AlarmList
from ui.analysis_tab import AnalysisTab
from ui.input_guard import WheelGuard
from ui.lab_tab import MotionLabTab
from ui.marine_tab import CraneHeadTab
from ui.notices import KeysOverlay, NoticeStrip
from ui.teleop_tab import TeleopTab
from ui.widgets.status import StatusPanel

ESTOP_CONFIRM_S = 0.1  # the engine's state must show the latch within this, else an alarm
MAX_SIZE = (1280, 800)
FRAME_FIT_MS = (0, 150, 500, 1200, 2500, 5000)  # the window manager frames the window some time after show()
FRAME_FIT_S = 10.0  # moves and resizes this soon after the first show are the window manager's: fitted
# an error from a tab, by its title: (engine, what it refused) keys the message, cleared by that command's success
TITLE_KEYS = {
    "Robot not loaded": "teleop:set_robot",
    "Solver not changed": "teleop:set_solver",
    "Command refused": "teleop:command",
    "Logger not started": "teleop:logger",
}
SCENE_REFUSAL = re.compile(r"^(?P<origin>Motion-Lab|crane head): (?:(?P<re>\w+) )?refused: (?P<error>.*)$", re.S)


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
        # banner and messages in the room beside the tab bar: they never move a control (ui/notices.py)
        self.notices = NoticeStrip(self.tabs)
        self.tabs.setCornerWidget(self.notices, Qt.TopRightCorner)
        self.banner = self.notices.banner
        self.message_bar = self.notices.message_bar
        central = QWidget()
        cl = QVBoxLayout(central)
        cl.setContentsMargins(2, 2, 2, 2)
        cl.setSpacing(2)
        cl.addWidget(self.tabs, 1)
        self.setCentralWidget(central)
        self.keys_overlay = KeysOverlay(central, KEYS_HTML)
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
        menu = self.menuBar().addMenu("&File")
        act = QAction("Open robot file (XML, URDF)…", self, triggered=self.teleop.choose_xml)
        act.setShortcut("Ctrl+O")
        menu.addAction(act)
        menu.addAction(QAction("Quit", self, triggered=self.close, shortcut="Ctrl+Q"))
        help_menu = self.menuBar().addMenu("&Help")
        # F1 only here: a QShortcut for F1 beside it made the key ambiguous, and neither ever fired
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
        self.status.alarms.ack.connect(self.acknowledge)
        self.status.alarms.shelve.connect(self.shelve_alarm)
        # the GUI's own alarms: raised, cleared, shelved and unshelved in the log; their conditions are stated
        # again at every refresh, so delays and shelving run out on time (review of issue 26)
        self.gui_alarms = AlarmList("GUI", note=lambda lvl, text: self.status.add_log(lvl, text))
        self._gui_conditions: dict[str, tuple[bool, str]] = {}
        # the room of "E-STOP LATCHED" under STOP is kept while it is empty (else Reset moves when it shows)
        latched = self.status.latched
        latched.setMinimumHeight(latched.fontMetrics().height() + latched.contentsMargins().top() * 2)
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
        self._look_timer = QTimer(self)  # ENABLE's look and the messages' conditions, from the engines' states
        self._look_timer.setInterval(100)
        self._look_timer.timeout.connect(self._refresh_looks)
        self._look_timer.start()
        self.child_engines: list = []  # scene engine processes started by the GUI (the teleop one is ``engine``)
        self._restart_errors: list[str] = []
        self._watchdog = QTimer(self)
        self._watchdog.setInterval(1000)
        self._watchdog.timeout.connect(self.watch_engines)
        self._watchdog.start()
        self._frame_fitted = False
        self._fit_until = 0.0
        self.restore()
        self.teleop.inputs.route(link, self.teleop.stick)
        app = QApplication.instance()
        app.installEventFilter(self)
        self.wheel_guard = WheelGuard(lambda text: self.status.add_log("info", f"set-point {text}"), self)
        self.wheel_guard.install(app)
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
            err = self._restart_errors.pop(0)
            if err:
                self.show_error("Engine not restarted", err, key="restart")
            else:
                self.notices.clear("restart")
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
        else:
            self._restart_errors.append("")  # back: its "not restarted" message goes
        finally:
            proc.restarting = False

    # ------------------------------------------------------------------ keyboard
    def _stick_of_current_tab(self):
        page = self.tabs.currentWidget()
        if page is self.teleop:
            return self.teleop.stick
        if page is self.motion_lab:
            return self.motion_lab.stick
        if page is self.crane_head:
            return self.crane_head.stick
        return None

    def release_keys(self) -> None:
        for stick in (self.teleop.stick, self.motion_lab.stick, self.crane_head.stick):
            if stick.keys or stick.pad.held or stick.enabled:
                stick.release_all()

    @staticmethod
    def _typing() -> bool:
        w = QApplication.focusWidget()
        if isinstance(w, QPlainTextEdit | QTextEdit):
            return not w.isReadOnly()
        return isinstance(w, QLineEdit | QAbstractSpinBox)

    @staticmethod
    def _text_field(obj) -> bool:
        """``obj``, the receiver of a key event, is a text field that has the keyboard: Space types a space.

        A line edit (not read-only; a spin box's own is a number, not text), an editable text edit or an
        editable combo box.  A key sent to anything else (a button, a list, a spin box, a native GL view,
        a dialog's list of files) is not typed text."""
        if not isinstance(obj, QWidget):
            # a platform key event reaches the window (QWidgetWindow) before its focus widget: look ahead at
            # that widget; a native child window (a GL view) is no text field
            fw = QApplication.focusWidget()
            if fw is None or fw.window().windowHandle() is not obj:
                return False
            obj = fw
        if not obj.hasFocus():
            return False
        if isinstance(obj, QLineEdit):
            return not obj.isReadOnly() and not isinstance(obj.parentWidget(), QAbstractSpinBox)
        if isinstance(obj, QPlainTextEdit | QTextEdit):
            return not obj.isReadOnly()
        return isinstance(obj, QComboBox) and obj.isEditable()

    def eventFilter(self, obj, ev) -> bool:
        """Space is STOP everywhere but in a text field that has the keyboard, Ctrl+Space everywhere; the stick
        of the tab on screen owns its keys (see the module doc)."""
        t = ev.type()
        if t in (QEvent.KeyPress, QEvent.KeyRelease):
            key = ev.key()
            if key == Qt.Key_Space:
                ctrl = bool(ev.modifiers() & Qt.ControlModifier)
                if not ctrl and self._text_field(obj):
                    return False  # typed: a file name may hold a space (Ctrl+Space and STOP still stop)
                if t == QEvent.KeyPress and not ev.isAutoRepeat():
                    self.estop("Ctrl+Space" if ctrl else "Space")
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
        """A scene link however it was made (first view, the tab's Start button): lost engine, input, and the
        messages its commands' refusals left (cleared when the command is taken)."""
        link.connection.connect(lambda ok, msg, o=origin: self.on_connection(ok, msg, o))
        link.reply.connect(lambda re_, ok, _err, o=origin: self.notices.clear(f"{o}:{re_}") if ok else None)
        self._route_input()

    def _route_input(self) -> None:
        """Input goes to the engine of the tab on screen (none on Analysis)."""
        w = self.tabs.currentWidget()
        if w is self.teleop:
            self.teleop.inputs.route(self.link, self.teleop.stick)
        elif w is self.motion_lab:
            self.teleop.inputs.route(self.motion_lab.link, self.motion_lab.stick)
        elif w is self.crane_head:
            self.teleop.inputs.route(self.crane_head.link, self.crane_head.stick)
        else:
            self.teleop.inputs.route(None, None)

    def show_keys(self) -> None:
        """The shortcut overlay (F1 opens and closes it): floats over the top of the pages, non-blocking."""
        if not self.keys_overlay.isVisible():
            self.status.add_log("info", KEYS_HELP.replace("\n", " "))
        self.keys_overlay.toggle(self.tabs.geometry().top() + self.tabs.tabBar().height() + 6)

    def resizeEvent(self, ev) -> None:
        super().resizeEvent(ev)
        if self.keys_overlay.isVisible():
            self.keys_overlay.place(self.tabs.geometry().top() + self.tabs.tabBar().height() + 6)

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
                self._gui_alarm(f"estop_unconfirmed:{origin}", False)
                self.status.add_log("info", f"E-STOP confirmed by the {origin} engine ({1e3 * (now - t_sent):.0f} ms)")
                continue
            if now - t_sent > ESTOP_CONFIRM_S:
                text = f"E-STOP NOT CONFIRMED by the {origin} engine: still trying"
                self._gui_alarm(f"estop_unconfirmed:{origin}", True, text)
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
            text, color = f"E-STOP NOT CONFIRMED ({', '.join(late)}): no answer", "#b00000"
        elif latched:
            text, color = f"E-STOP LATCHED ({', '.join(latched)}): Reset to continue", "#c9302c"
        elif self.estop_pending:
            text, color = "STOP sent: awaiting the engine's confirmation", "#c9302c"
        elif self.lost:
            text, color = f"ENGINE LOST ({', '.join(sorted(self.lost))}): reconnecting…", "#b07000"
        else:
            text, color = "", ""
        self.notices.set_banner(text, color)

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

    def _gui_alarm(self, key: str, active: bool, text: str = "") -> None:
        """State one of the GUI's own alarm conditions (kept, and stated again at every refresh)."""
        last = self._gui_conditions.get(key, (False, ""))
        self._gui_conditions[key] = (active, text or last[1])
        self.gui_alarms.set(key, active, text=text or last[1])

    def _refresh_alarms(self) -> None:
        self.gui_alarms.at(time.monotonic())  # delays and shelving count on the same clock
        for key, (active, text) in list(self._gui_conditions.items()):
            self.gui_alarms.set(key, active, text=text)
        if self.link.role == "operator" and self._gui_conditions.get("role_lost", (False,))[0]:
            self._gui_alarm("role_lost", False)  # the role is back (the message bar's condition too)
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

    def shelve_alarm(self, origin: str, key: str, minutes: float) -> None:
        """Shelve (or, with 0 minutes, unshelve) one alarm in the engine that raised it (ISA-18.2 §12.3)."""
        try:
            if origin == "gui":
                if minutes:
                    self.gui_alarms.shelve(key, 60.0 * minutes, who="the operator")
                else:
                    self.gui_alarms.unshelve(key)
            else:
                link = self.links().get(origin)
                if link is not None:
                    link.send("shelve_alarm", key=key, minutes=float(minutes))
        except ValueError as err:  # not shelvable: said in the log and the message bar, nothing changes
            self.status.add_log("warning", str(err))
            self.show_error("Alarm not shelved", str(err))
        self._refresh_alarms()

    # ------------------------------------------------------------------ messages
    def on_marine_notice(self, level: str, text: str) -> None:
        self.status.add_log(level, text)
        if level == "error" and any(w in text for w in ("refused", "not started", "not sent", "engine:")):
            origin = "Motion-Lab" if text.startswith("Motion-Lab") else "crane head"
            m = SCENE_REFUSAL.match(text)
            if m is not None:  # "<scene>: <command> refused: why": cleared when that command is taken
                key = f"{origin}:{m['re'] or 'refused'}"
            elif "engine:" in text:
                key = f"{origin}:engine"
            else:
                key = f"{origin}:{text.split(':')[1].strip()[:40] if ':' in text else text[:40]}"
            gone = None
            if key.endswith(":engine"):  # the engine did not start or failed: gone once it is linked and up
                tab = self.crane_head if origin == "crane head" else self.motion_lab
                gone = lambda t=tab, o=origin: t.link is not None and o not in self.lost  # noqa: E731
            self.show_error("Motion-Lab" if origin == "Motion-Lab" else "Crane head", text, key=key, gone=gone)

    def show_error(self, title: str, message: str, key: str | None = None, gone=None, origin: str = "") -> None:
        """Non-blocking: the message bar and the log (STOP stays live).

        The message is tied to its condition (issue 26, item 7): ``key`` names it (one message per key:
        a newer replaces it, the command's success clears it); ``gone()`` true clears it.  A refusal
        because the E-STOP is latched goes once the engine that refused it is reset."""
        self.messages.append((title, message))
        self.status.add_log("error", f"{title}: {message}")
        key = key or TITLE_KEYS.get(title) or f"gui:{title}"
        origin = origin or ("teleop" if key.startswith("teleop:") else key.split(":")[0])
        if gone is None and "E-STOP" in message and origin in ("teleop", "crane head", "Motion-Lab"):
            gone = lambda o=origin: self._state_known(o) and not self._latched(o)  # noqa: E731
        self.notices.post(key, title, message, "error", gone)

    def _state_known(self, origin: str) -> bool:
        link = self.links().get(origin)
        return link is not None and getattr(link, "latest", None) is not None and origin not in self.lost

    def _refresh_looks(self) -> None:
        """ENABLE from the engines' newest states; messages whose condition is gone are cleared."""
        for origin, stick in (
            ("teleop", self.teleop.stick),
            ("Motion-Lab", self.motion_lab.stick),
            ("crane head", self.crane_head.stick),
        ):
            link = self.links().get(origin)
            st = getattr(link, "latest", None) if link is not None and origin not in self.lost else None
            stick.show_engine(st if st is not None and hasattr(st, "flags") else None)
        if self.teleop.logger is not None:
            self.notices.clear("teleop:logger")
        self.notices.sweep()

    # ------------------------------------------------------------------ engine events
    def on_state(self, state) -> None:
        if "teleop" not in self.lost and self.link.connected:  # a late state never turns LOST green again
            self.status.show_teleop(state)  # every light from what the engine reports (ui/widgets/status.py)
        choice = (state.robot, state.solver, state.mode)
        if choice != getattr(self, "_choice", None):
            self._choice = choice
            for key, value in zip(("robot", "solver", "mode"), choice, strict=True):
                self.settings.setValue(key, value)

    def on_connection(self, ok: bool, message: str, origin: str = "teleop") -> None:
        self._gui_alarm(f"lost:{origin}", not ok, f"Connection to the {origin} engine lost: reconnecting")
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
            self.show_error(
                "Engine connection lost" if origin == "teleop" else f"{origin} engine lost",
                f"{message}. The engine holds its machines when input stops; reconnecting.",
                key=f"lost:{origin}",
                gone=lambda o=origin: o not in self.lost,  # cleared once the connection is restored
            )
        self.notices.sweep()
        self._update_banner()

    def on_reply(self, re: str, ok: bool, error: str) -> None:
        if ok and re in ("set_robot", "set_solver", "set_mode", "reset", "estop"):
            self.status.add_log("info", f"{re}: done")
        if ok:  # the command was taken: its earlier refusal is history
            self.notices.clear(f"teleop:{re}")
            if re in ("set_mode", "set_scaling"):
                self.notices.clear("teleop:command")
        if not ok and "no longer the operator" in error:  # the engine gave the role away: say it, loudly
            self._gui_alarm("role_lost", True, f"Operator role lost: {error}")
            self.show_error(
                "Operator role lost",
                error,
                key="teleop:role",
                gone=lambda: getattr(self.link, "role", "") == "operator",
            )

    def on_input_event(self, level: str, text: str) -> None:
        self.status.add_log(level, text)
        lost = level == "warning" and "unplugged" in text
        self._gui_alarm("device_lost", lost, f"Input device lost: {text}")
        # the message bar, not a status bar (one created at the first warning shrank the window's pages)
        device = text.removeprefix("joystick ").split(" unplugged")[0].split(" plugged in")[0]
        if lost:
            self.notices.post(f"device:{device}", "Input", text, "warning")
        elif "plugged in" in text:
            self.notices.clear(f"device:{device}")

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
        self._first_open = geom is None
        self.fit_to_screen(first=geom is None)

    def showEvent(self, ev) -> None:
        super().showEvent(ev)
        if not self._frame_fitted:  # once the window manager has framed the window: fit the frame too
            self._frame_fitted = True
            self._fit_until = time.monotonic() + FRAME_FIT_S
            for ms in FRAME_FIT_MS:
                QTimer.singleShot(ms, self.fit_frame)

    def event(self, ev) -> bool:
        # a window manager frames the window when it maps it (a move, a resize, an activation follow): fit then,
        # during the first seconds after the first show (later moves and resizes are the operator's)
        fitting = time.monotonic() < getattr(self, "_fit_until", 0.0)
        if fitting and ev.type() in (QEvent.Move, QEvent.Resize, QEvent.WindowActivate):
            QTimer.singleShot(0, self.fit_frame)
        return super().event(ev)

    def fit_frame(self) -> None:
        """The window's frame (title bar and borders included) inside the screen's free area: the client
        shrinks by the frame's size where needed, and on a first opening the frame's top-left is the free
        area's top-left (issue 26, item 10: a 1280×800 client under a 20-px title bar opened 20 px down
        with its bottom, the status panel's, off an 800-px screen)."""
        if not self.isVisible() or self.windowState() & (Qt.WindowMaximized | Qt.WindowFullScreen):
            return
        if time.monotonic() >= self._fit_until:
            return  # fitted, or long opened: the window's place is the operator's
        avail = (self.screen() or QGuiApplication.primaryScreen()).availableGeometry()
        fg, g = self.frameGeometry(), self.geometry()
        dw, dh = fg.width() - g.width(), fg.height() - g.height()
        w, h = min(g.width(), avail.width() - dw), min(g.height(), avail.height() - dh)
        if (w, h) != (g.width(), g.height()):
            self.resize(w, h)
        fw, fh = w + dw, h + dh
        if self._first_open:
            x, y = avail.x(), avail.y()
        else:
            x = min(max(fg.x(), avail.x()), avail.x() + avail.width() - fw)
            y = min(max(fg.y(), avail.y()), avail.y() + avail.height() - fh)
        if (x, y) != (fg.x(), fg.y()):
            self.move(x, y)
        elif (w, h) == (g.width(), g.height()) and (dw or dh):
            self._fit_until = 0.0  # framed and fitted: from now on the window's place is the operator's

    def closeEvent(self, ev) -> None:
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("windowState", self.saveState())
        self._watchdog.stop()
        app = QApplication.instance()
        app.removeEventFilter(self)
        self.wheel_guard.remove(app)
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


KEYS_HELP = """STOP: Space (any tab, any dialog; in a text field you are typing in, Ctrl+Space), the STOP button,
or the joystick's stop button. Ctrl+Space stops everywhere. Esc is not STOP.
Reset E-STOP: the Reset button; machines keep holding until you command them anew.
Drive (Teleop and Motion-Lab tabs): hold Shift (or the ENABLE button) as the deadman, then arrows for x/y and
Page Up/Down for z. After a reset, a mode or robot change: stick at neutral, release and press enable again.
Mouse wheel: scrolls the page; it changes a field only after you click into it (the change is logged).
Ctrl+1 / Ctrl+2: position / velocity mode. Ctrl+O: open a robot file. F1: this help."""

KEYS_HTML = (
    "<p><b>STOP</b>: <b>Space</b> (any tab, any dialog) · <b>Ctrl+Space</b> (everywhere, also while you type in a"
    " text field, where Space types a space) · the STOP button · the joystick's stop button."
    " Esc is <i>not</i> STOP.</p>"
    "<p><b>Reset E-STOP</b>: the Reset button; machines keep holding until you command them anew.</p>"
    "<p><b>Enable</b>: hold Shift or ENABLE (it shows the engine's view: ENABLED, NOT ARMED, E-STOP)."
    " <b>Drive</b>: arrows x/y, Page Up/Down z. After a reset, a mode or robot change: stick at neutral,"
    " release and press enable again.</p>"
    "<p><b>Mouse wheel</b>: scrolls the page; it changes a field only after you click into it (logged).</p>"
    "<p>Ctrl+1 / Ctrl+2 position / velocity mode · Ctrl+O robot file · F1 this help</p>"
)
