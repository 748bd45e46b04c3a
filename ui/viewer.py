"""``bosun view --connect URL``: a standalone viewer of a running engine (the 3D view as its own client,
universal-architecture paper Fig. 1).

It joins as a **viewer**: it sees the scene (3D or 2D view and live plots) but commands nothing —
except STOP, which anyone may send (Space or the STOP button, confirmed by the engine's state).
What it shows follows the engine's description: a teleoperated arm, the crane head or the
Motion-Lab, reusing the main window's views with their controls disabled.
"""

from __future__ import annotations

import time

from PyQt5.QtCore import Qt, QTimer
from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import (
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QPushButton,
    QShortcut,
    QSplitter,
    QVBoxLayout,
    QWidget,
)

from ui.input_guard import WheelGuard
from ui.widgets.labels import ElidedLabel

ESTOP_CONFIRM_S = 0.1


class ViewerWindow(QMainWindow):
    """A viewer of one engine: its scene, who operates it, STOP."""

    def __init__(self, link, use_gl: bool | None = None) -> None:
        super().__init__()
        self.link = link
        self.use_gl = use_gl
        self.kind = ""
        self.content: QWidget | None = None
        self.estop_sent: float | None = None
        self.estops_before = 0
        self.setWindowTitle(f"Bosun viewer: {link.url}")
        central = QWidget()
        lay = QVBoxLayout(central)
        lay.setContentsMargins(4, 4, 4, 4)
        top = QHBoxLayout()
        self.info = QLabel("waiting for the engine's description…")
        self.info.setWordWrap(True)
        top.addWidget(self.info, 1)
        # the banner keeps its room in the top row, shown or not: the view below never moves (issue 26, item 2)
        self.banner = ElidedLabel("")
        self.banner.setAlignment(Qt.AlignCenter)
        pol = self.banner.sizePolicy()
        pol.setRetainSizeWhenHidden(True)
        self.banner.setSizePolicy(pol)
        self.banner.hide()
        top.addWidget(self.banner, 1)
        self.stop = QPushButton("STOP")
        self.stop.setFocusPolicy(Qt.NoFocus)
        self.stop.setMinimumSize(120, 48)
        self.stop.setStyleSheet(
            "QPushButton { background: #c9302c; color: white; font-size: 18pt; font-weight: bold; border-radius: 6px; }"
        )
        self.stop.setToolTip("E-STOP: anyone may stop the machines, also a viewer (Space)")
        self.stop.pressed.connect(self.estop)
        top.addWidget(self.stop)
        lay.addLayout(top)
        self.body = QVBoxLayout()
        lay.addLayout(self.body, 1)
        self.setCentralWidget(central)
        QShortcut(QKeySequence(Qt.Key_Space), self, activated=self.estop)
        QShortcut(QKeySequence("Ctrl+Space"), self, activated=self.estop)  # as in the operator's window
        link.described.connect(self.on_description)
        link.state.connect(self.on_state)
        link.connection.connect(lambda ok, msg: self.info.setText(msg if not ok else self.info.text()))
        if link.description is not None:
            self.on_description(link.description)
        self._timer = QTimer(self)
        self._timer.setInterval(50)
        self._timer.timeout.connect(self._check_estop)
        self._timer.start()
        self.resize(1200, 760)
        # the wheel scrolls; it changes no field without the keyboard (ui/input_guard.py)
        self.wheel_guard = WheelGuard(lambda text: None, self)
        self.wheel_guard.install()

    # ------------------------------------------------------------------ content
    def on_description(self, desc) -> None:
        if desc.kind == self.kind:
            return
        self.kind = desc.kind
        if self.content is not None:
            self.content.setParent(None)
        self.content = self._make(desc)
        self.body.addWidget(self.content, 1)
        # a child added to a window already on screen stays hidden until shown (Qt): seen as an empty viewer
        # when the description came after the window was shown, in a test process that had shown other windows
        self.content.show()

    def _make(self, desc) -> QWidget:
        if desc.kind == "teleop":
            from ui.widgets.plots import LivePlots, UtilisationBars
            from ui.widgets.view3d import make_robot_view

            w = QSplitter()
            left = QWidget()
            ll = QVBoxLayout(left)
            self.view = make_robot_view(use_gl=self.use_gl)
            self.bars = UtilisationBars()
            ll.addWidget(self.view, 3)
            ll.addWidget(self.bars, 1)
            w.addWidget(left)
            self.plots = LivePlots()
            w.addWidget(self.plots)
            self.view.set_description(desc)
            self.plots.set_description(desc)
            self.link.described.connect(self._teleop_description)
            self.link.states.connect(lambda states: [self.plots.add_state(s) for s in states])
            return w
        if desc.kind == "tac":
            from ui.marine_tab import CraneHeadTab

            tab = CraneHeadTab(lambda: self.link, use_gl=self.use_gl)
        else:
            from ui.lab_tab import MotionLabTab

            tab = MotionLabTab(lambda: self.link, use_gl=self.use_gl)
        tab.connect_engine()
        tab._set_enabled(False)  # a viewer commands nothing; the engine would refuse it anyway
        return tab

    def _teleop_description(self, desc) -> None:
        if desc.kind == "teleop":
            self.view.set_description(desc)
            self.plots.set_description(desc)

    def on_state(self, state) -> None:
        e = state.engine
        role = self.link.role
        paused = " · <b>paused</b> (no operator console shows it)" if e.paused else ""
        desc = self.link.description
        title = getattr(desc, "title", "") or ""
        replay = (
            f" · <b>{title[title.index('replay of') :]}</b>" if "replay of" in title else ""
        )  # never taken for live
        self.info.setText(
            f"<b>{state.kind}</b> engine at {self.link.url}{replay} · you: <b>{role}</b> · "
            f"operator: <b>{e.operator or 'none'}</b> · {e.clients} clients{paused}"
        )
        if state.kind == "teleop" and self.kind == "teleop":
            self.view.update_state(state)
            self.bars.update_state(state, self.link.description)
        self._show_banner(state)

    # ------------------------------------------------------------------ STOP
    def estop(self) -> None:
        st = self.link.latest
        self.estops_before = st.engine.estops if st is not None else 0
        self.estop_sent = time.monotonic()
        self.link.send("estop", reason="STOP in a viewer")

    def _check_estop(self) -> None:
        if self.estop_sent is None:
            return
        st = self.link.latest
        if st is not None and st.estop and st.engine.estops > self.estops_before:
            self.estop_sent = None
        elif time.monotonic() - self.estop_sent > ESTOP_CONFIRM_S:
            self.link.send("estop", reason="STOP in a viewer (resent: not confirmed)")
            self.estop_sent = time.monotonic()
        if st is not None:
            self._show_banner(st)

    def _show_banner(self, state) -> None:
        if self.estop_sent is not None and time.monotonic() - self.estop_sent > ESTOP_CONFIRM_S:
            text, color = "E-STOP NOT CONFIRMED: still trying", "#b00000"
        elif state.estop:
            text, color = "E-STOP LATCHED: the operator resets", "#c9302c"
        else:
            text, color = "", ""
        if (text, color) == getattr(self, "_banner_shown", None):
            return
        self._banner_shown = (text, color)
        self.banner.setVisible(bool(text))
        self.banner.setText(text)
        self.banner.setStyleSheet(f"background: {color}; color: white; font-weight: bold; padding: 4px;")

    def closeEvent(self, ev) -> None:
        self._timer.stop()
        self.wheel_guard.remove()
        self.link.close()
        super().closeEvent(ev)


def run_viewer(connect: str, token: str | None = None, curve=None, quit_after: float | None = None) -> int:
    """Open a viewer of the engine at ``connect`` (viewer role)."""
    import sys

    from PyQt5.QtWidgets import QApplication

    from app.errors import BosunError
    from app.net.transport import TransportError
    from ui.app import close_when_asked, has_display, stop_requests
    from ui.link import EngineLink

    if not has_display():
        raise BosunError(
            "no display to open the viewer on (DISPLAY is not set); start it on a desktop or under xvfb-run"
        )
    from ui.glprobe import share_gl_contexts

    share_gl_contexts()  # before the QApplication: every GL view shares shaders
    app = QApplication.instance() or QApplication(sys.argv[:1])
    try:
        link = EngineLink(connect, role="viewer", name="bosun-viewer", token=token, curve=curve)
    except TransportError as err:
        raise BosunError(str(err)) from None
    asked = stop_requests()  # Qt calls Python from here on: a stop is asked for, never raised
    win = ViewerWindow(link)
    close_when_asked(win, asked)
    win.show()
    if quit_after is not None:
        QTimer.singleShot(int(quit_after * 1000), win.close)
    return app.exec_()
