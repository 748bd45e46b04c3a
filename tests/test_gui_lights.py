"""Lights and pages that tell the truth (issue 26, items 5-6; docs/safety.md H71-H74): the main window
(pytest-qt offscreen) against real teleop, crane-head and Motion-Lab engines over 127.0.0.1, checked in
what an operator sees: the lights shown on screen, the platform page's words and colours, the buttons the
engine would refuse."""

import pytest

pytest.importorskip("PyQt5")
from PyQt5.QtCore import Qt

from app.engine.lab_session import LabSession
from app.engine.session import Session
from tests.gui_rig import color_px, main_window, scene_engines
from tests.helpers import GUI_WAIT
from ui.widgets.status import LIGHT, StatusLight


@pytest.fixture
def window(qtbot, tmp_path, serve):
    """The main window with its three engines; the lab's platforms start at rest at NEUTRAL (a scenario's
    start, as app/scenarios/vvmc.py places them: no 0.9 m raise to wait for)."""
    lab = LabSession()
    for p in lab.lab.platforms:
        p.place_at_neutral()
    teleop, _ = serve(Session(robot_name="comau_smart5_3dof"), rate=100, publish_rate=25, duration=180.0)
    win = main_window(teleop.url, tmp_path / "s.ini", **scene_engines(serve, 180.0, lab))
    qtbot.addWidget(win)
    win.resize(1280, 800)
    win.show()
    yield win
    win.close()


def shown_lights(win) -> list[str]:
    """The text of every status light an operator sees now (machine lights included)."""
    return [w.text() for w in win.findChildren(StatusLight) if w.isVisible()]


def _has(win, prefix: str) -> bool:
    return any(t.startswith(prefix) for t in shown_lights(win))


def _open_lab(qtbot, win):
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and tab.desc is not None, timeout=GUI_WAIT)
    return tab


def test_item5_estop_on_a_platform_page_shows_the_latched_stop_not_a_green_engaged(qtbot, window):
    """Item 5: during an E-STOP the EM8000 page showed a green ENGAGED with DISENGAGE enabled.  It shows
    the latched stop in the stop colour (braking, then stopped) and every command the engine refuses until
    reset is disabled; the reset leaves it HOLDING (amber) with NEUTRAL and SETTLE offered."""
    win = window
    tab = _open_lab(qtbot, win)
    em8000 = tab.platforms["em8000"]
    tab.tabs.setCurrentIndex(0)
    qtbot.waitUntil(lambda: em8000.buttons["engage"].isEnabled(), timeout=GUI_WAIT)
    em8000.buttons["engage"].click()
    qtbot.waitUntil(lambda: tab.state.platforms[0].status == "engaged", timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: em8000.buttons["disengage"].isEnabled(), timeout=GUI_WAIT)
    green = "#3c9"
    assert "ENGAGED" in em8000.status.text() and color_px(em8000.status, green) > 20
    win.estop("Space")
    qtbot.waitUntil(lambda: tab.state.estop, timeout=GUI_WAIT)  # the engine confirmed the stop
    qtbot.waitUntil(lambda: not any(tab.state.platforms[0].eta_dot), timeout=GUI_WAIT)  # at rest
    qtbot.wait(300)  # the page has shown a few of these states
    assert "ENGAGED — E-STOP latched: stopped" in em8000.status.text()
    assert color_px(em8000.status, green) == 0 and color_px(em8000.status, "#e33") > 20  # no green on the page's status
    assert not any(b.isEnabled() for b in em8000.buttons.values())  # DISENGAGE too: the engine refuses it
    for widget in (tab.comau.comau_mode, tab.comau.winch_mode, tab.comau.vvmc, tab.comau.winch_slider):
        assert not widget.isEnabled()
    assert _has(win, "● plant: E-STOP")
    win.reset()
    qtbot.waitUntil(lambda: not tab.state.estop and "HOLDING" in em8000.status.text(), timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: em8000.buttons["neutral"].isEnabled(), timeout=GUI_WAIT)
    assert em8000.buttons["settle"].isEnabled() and not em8000.buttons["disengage"].isEnabled()
    assert color_px(em8000.status, "#e33") == 0 and color_px(em8000.status, "#fa3") > 20  # holding is not a stop
    assert _has(win, "● plant: holding: EM8000")


def test_item6_lab_lights_compensating_jog_and_enable_from_the_engine(qtbot, window):
    """Item 6: with both platforms engaged and VVMC on no light says "plant: holding" (the Motion-Lab's
    plant light says compensating); a running joint jog is the input ("input: jog q1"), not "no input";
    the stick's ENABLE turns green only once the engine enabled the input, and says so when it refuses."""
    win = window
    tab = _open_lab(qtbot, win)
    for panel in tab.platforms.values():
        qtbot.waitUntil(lambda p=panel: p.buttons["engage"].isEnabled(), timeout=GUI_WAIT)
        panel.buttons["engage"].click()
    qtbot.waitUntil(lambda: all(p.mode == "engaged" for p in tab.state.platforms), timeout=GUI_WAIT)
    tab.comau.vvmc.click()
    qtbot.waitUntil(lambda: tab.state.vvmc and tab.state.comau.mode == "motion_comp", timeout=GUI_WAIT)
    qtbot.wait(300)  # the window has shown a few of these states
    assert not any("plant: holding" in t for t in shown_lights(win)), shown_lights(win)
    assert _has(win, "● plant: compensating")
    assert tab.lights.lights["plant"].state == "ok"
    assert "EM8000 engag" in tab.lights.lights["plant"].text() and "EM1500 engag" in tab.lights.lights["plant"].text()
    assert not _has(win, "● input: not used (Comau MOTION_COMP")  # under VVMC the stick moves the work point
    # VVMC off: the Comau in REMOTE takes the stick and the jog
    tab.comau.vvmc.click()
    qtbot.waitUntil(lambda: not tab.state.vvmc and tab.state.comau.mode == "remote", timeout=GUI_WAIT)
    tab.tabs.setCurrentIndex(2)
    enable = tab.stick.enable
    tab.stick.key(Qt.Key_Right, True)  # the stick deflected: enable pressed now is refused (arming needs neutral)
    qtbot.mousePress(enable, Qt.LeftButton)
    qtbot.waitUntil(lambda: enable.text().startswith("NOT ARMED"), timeout=GUI_WAIT)
    # the engine has seen the enable held (deadman) and refused it: the light says so (before that state came,
    # the input was idle: enable released)
    qtbot.waitUntil(lambda: tab.state.flags.deadman and _has(win, "● input: not armed"), timeout=GUI_WAIT)
    assert not tab.state.flags.enabled and color_px(enable, LIGHT["ok"]) == 0
    qtbot.mouseRelease(enable, Qt.LeftButton)
    tab.stick.key(Qt.Key_Right, False)
    # the engine sees the enable released at neutral before the new press (arming takes a fresh press)
    qtbot.waitUntil(lambda: not tab.state.flags.deadman, timeout=GUI_WAIT)
    tab.stick.key(Qt.Key_Shift, True)
    qtbot.waitUntil(lambda: tab.state.flags.enabled and enable.text().startswith("ENABLED"), timeout=GUI_WAIT)
    assert color_px(enable, LIGHT["ok"]) > 50 and _has(win, "● input: enabled")
    plus = tab.comau.jog_buttons[(1, 1)]
    qtbot.mousePress(plus, Qt.LeftButton)
    qtbot.waitUntil(lambda: tab.state.comau_jog.joint == 1, timeout=GUI_WAIT)
    qtbot.wait(300)
    assert not any(t.endswith("input: no input") for t in shown_lights(win) if "teleop" not in t)
    assert _has(win, "● input: jog q1 +25 %")
    qtbot.waitUntil(lambda: "Comau jog q1" in tab.lights.lights["plant"].text(), timeout=GUI_WAIT)
    qtbot.mouseRelease(plus, Qt.LeftButton)
    tab.stick.key(Qt.Key_Shift, False)
    qtbot.waitUntil(
        lambda: tab.state.comau_jog.joint == 0 and not enable.text().startswith("ENABLED"), timeout=GUI_WAIT
    )


def test_item6_crane_head_tab_lights_compensating_no_plc_estop_and_holding(qtbot, window):
    """Item 6: on the crane-head tab no light says "PLC: simulated" (it has no PLC; the lab's was opened
    first) nor "plant: holding" while the head compensates; STOP turns its plant light red and greys the mode
    the engine refuses; after the reset it is "holding" until a mode is chosen, then compensating again."""
    win = window
    _open_lab(qtbot, win)
    qtbot.waitUntil(lambda: _has(win, "● PLC: "), timeout=GUI_WAIT)  # the lab's PLC light is set
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and tab.state.sample is not None, timeout=GUI_WAIT)
    assert tab.state.tac_mode == "tac" and not tab.state.holding and not tab.state.estop  # the head compensates
    qtbot.wait(300)  # the window has shown a few of these states
    lights = shown_lights(win)
    assert not any("PLC" in t for t in lights), lights
    assert not any("plant: holding" in t for t in lights), lights
    assert _has(win, "● plant: compensating: head (tac)")
    # the tab's stick is routed to the crane head: its light follows the stick (issue 30, item 2), never "not used"
    assert any(t.startswith("● input: ") and "not used" not in t and "on-screen stick" in t for t in lights), lights
    assert "simulated plant" in tab.lights.title.text() and tab.mode.isEnabled()
    win.estop("Space")
    qtbot.waitUntil(lambda: tab.state.estop and _has(win, "● plant: E-STOP: head and crane stopped"), timeout=GUI_WAIT)
    assert tab.lights.lights["plant"].state == "error" and not tab.mode.isEnabled()
    win.reset()
    qtbot.waitUntil(lambda: _has(win, "● plant: holding: choose a compensation mode"), timeout=GUI_WAIT)
    assert tab.mode.isEnabled()
    tab.mode.activated.emit(tab.mode.findText("tac"))
    qtbot.waitUntil(lambda: _has(win, "● plant: compensating: head (tac)"), timeout=GUI_WAIT)
