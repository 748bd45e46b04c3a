"""Issue 15 item 5: the standalone viewer (``bosun view``) and the operator role in the GUI."""

from __future__ import annotations

import pytest

pytest.importorskip("PyQt5")

from PyQt5.QtCore import QSettings

from app.engine.session import Session
from app.engine.tac_session import TacSession
from app.net.transport import Client, TransportError
from tests.helpers import GUI_WAIT
from ui.link import EngineLink
from ui.main_window import MainWindow
from ui.viewer import ViewerWindow


@pytest.fixture
def teleop_engine(serve):
    return serve(Session(), rate=200, publish_rate=25)[0]


@pytest.fixture
def tac_engine(serve):
    return serve(TacSession(), rate=50, publish_rate=25)[0]


def test_viewer_shows_the_arm_commands_nothing_and_can_stop(qtbot, teleop_engine):
    operator = Client(teleop_engine.url, role="operator", name="console")
    link = EngineLink(teleop_engine.url, role="viewer", name="bosun-viewer")
    win = ViewerWindow(link, use_gl=False)
    qtbot.addWidget(win)
    win.show()
    try:
        qtbot.waitUntil(lambda: win.kind == "teleop" and link.latest is not None, timeout=GUI_WAIT)
        assert link.role == "viewer"
        qtbot.waitUntil(lambda: "operator: <b>console</b>" in win.info.text(), timeout=GUI_WAIT)
        qtbot.waitUntil(lambda: win.plots.ring is not None and win.plots.ring.n > 5, timeout=GUI_WAIT)
        paths = win.view.plots["top"]["paths"]  # the 2D fallback draws the arm's solids
        assert sum(p.isVisible() and not p.path().isEmpty() for p in paths) >= len(link.latest.frames) - 1
        # a viewer's command is refused by the engine; its STOP is not
        viewer2 = Client(teleop_engine.url, role="viewer", name="v2")
        try:
            with pytest.raises(TransportError, match="only the operator"):
                viewer2.request("set_solver", solver="ga")
        finally:
            viewer2.close()
        win.estop()
        qtbot.waitUntil(lambda: link.latest.estop and win.estop_sent is None, timeout=GUI_WAIT)
        assert "E-STOP LATCHED" in win.banner.text()
    finally:
        win.close()
        operator.close()


def test_viewer_of_the_crane_head_has_its_controls_disabled(qtbot, tac_engine):
    link = EngineLink(tac_engine.url, role="viewer", name="bosun-viewer")
    win = ViewerWindow(link, use_gl=False)
    qtbot.addWidget(win)
    win.show()
    try:
        qtbot.waitUntil(lambda: win.kind == "tac", timeout=GUI_WAIT)
        tab = win.content
        qtbot.waitUntil(lambda: tab.ring.i > 10, timeout=GUI_WAIT)  # live plots from the engine's stream
        assert not tab.mode.isEnabled()
        assert tab.hull is not None  # static data came in the description
    finally:
        win.close()


def test_gui_shows_releases_and_takes_the_operator_role(qtbot, teleop_engine, tmp_path):
    link = EngineLink(teleop_engine.url)
    win = MainWindow(link, settings=QSettings(str(tmp_path / "s.ini"), QSettings.IniFormat), dialogs=False)
    qtbot.addWidget(win)
    win.show()
    try:
        qtbot.waitUntil(lambda: "you operate" in win.status.role.text(), timeout=GUI_WAIT)
        assert win.status.role_button.text() == "Release operator role"
        win.status.role_button.click()
        qtbot.waitUntil(lambda: link.role == "viewer", timeout=GUI_WAIT)
        qtbot.waitUntil(lambda: "operator: free" in win.status.role.text(), timeout=GUI_WAIT)
        # another console takes the free role; this GUI shows who holds it and cannot take it
        other = Client(teleop_engine.url, role="operator", name="other-console")
        try:
            assert other.role == "operator"
            qtbot.waitUntil(lambda: "operator: other-console" in win.status.role.text(), timeout=GUI_WAIT)
            assert not win.status.role_button.isEnabled()
        finally:
            other.close()  # bye frees the role
        qtbot.waitUntil(lambda: win.status.role_button.isEnabled(), timeout=GUI_WAIT)
        assert win.status.role_button.text() == "Take operator role"
        win.status.role_button.click()
        qtbot.waitUntil(lambda: link.role == "operator", timeout=GUI_WAIT)
        qtbot.waitUntil(lambda: "you operate" in win.status.role.text(), timeout=GUI_WAIT)
        assert not link.latest.flags.armed  # a new operator starts disarmed
    finally:
        win.close()
