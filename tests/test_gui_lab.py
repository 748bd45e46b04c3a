"""Motion-Lab tab (pytest-qt offscreen) against a real lab engine over 127.0.0.1."""

import threading

import numpy as np
import pytest

pytest.importorskip("PyQt5")
from PyQt5.QtCore import QSettings

from app.engine.lab_session import LabSession
from app.engine.server import EngineServer
from app.engine.session import Session
from tests.helpers import GUI_WAIT
from ui.lab_tab import LabScene2D
from ui.link import EngineLink
from ui.main_window import MainWindow


def _serve(session, rate):
    srv = EngineServer(session, bind="tcp://127.0.0.1:0", rate=rate, publish_rate=min(rate, 25))
    th = threading.Thread(target=srv.run, kwargs={"duration": 120.0}, daemon=True)
    th.start()
    return srv, th


@pytest.fixture
def window(qtbot, tmp_path):
    teleop, lab = _serve(Session(robot_name="comau_smart5_3dof"), 200), _serve(LabSession(), 50)
    made = []

    def factory():
        made.append(EngineLink(lab[0].url, name="gui-lab"))
        return made[-1]

    win = MainWindow(
        EngineLink(teleop[0].url),
        settings=QSettings(str(tmp_path / "s.ini"), QSettings.IniFormat),
        dialogs=False,
        lab_link_factory=factory,
        use_gl=False,
    )
    qtbot.addWidget(win)
    win.show()
    yield win, made
    win.close()
    for srv, th in (teleop, lab):
        srv.stop()
        th.join(timeout=5)
        srv.close()


def test_lab_tab_runs_platforms_through_the_engine(qtbot, window):
    win, made = window
    tab = win.motion_lab
    assert tab.link is None and not tab.tabs.isEnabled()
    win.tabs.setCurrentWidget(tab)
    assert len(made) == 1 and tab.tabs.isEnabled()
    qtbot.waitUntil(lambda: tab.state is not None, timeout=GUI_WAIT)
    assert isinstance(tab.scene, LabScene2D)
    em1500 = tab.platforms["em1500"]
    assert "SETTLED" in em1500.status.text() and not em1500.buttons["engage"].isEnabled()
    em1500.buttons["neutral"].click()
    qtbot.waitUntil(
        lambda: "NEUTRAL" in em1500.status.text() and em1500.buttons["engage"].isEnabled(), timeout=GUI_WAIT
    )
    # sine generator: 0.1 m heave at 0.5 Hz
    em1500.source.setCurrentIndex(0)
    em1500.gen[2][0].setValue(0.1)
    em1500.gen[2][1].setValue(0.5)
    em1500.apply.click()
    qtbot.waitUntil(lambda: tab.state.platforms[1].source == "generator", timeout=GUI_WAIT)
    em1500.buttons["engage"].click()
    qtbot.waitUntil(lambda: "ENGAGED" in em1500.status.text() and not em1500.apply.isEnabled(), timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: em1500.ring.i > 30, timeout=GUI_WAIT)
    qtbot.wait(2500)
    z = em1500.ring.view()[:, 3]
    assert np.nanmax(np.abs(z)) > 0.02  # it heaves
    assert all(0 <= b.value() <= 1000 for b in em1500.leg_bars)
    # VVMC on: Comau and winch in MOTION_COMP, reported back by the engine
    tab.vvmc.click()
    qtbot.waitUntil(lambda: tab.state.vvmc and tab.state.comau.mode == "motion_comp", timeout=GUI_WAIT)
    assert tab.comau_mode.currentText() == "MOTION_COMP" and tab.winch_mode.currentText() == "MOTION_COMP"
    # the robot first travels to the work point (EM8000 is still SETTLED, 0.9 m low), then holds it
    qtbot.waitUntil(lambda: np.linalg.norm(tab.state.tool_error_b2) < 0.01, timeout=GUI_WAIT)
    # STOP: everything brakes to rest and commands are refused until reset
    win.estop()
    qtbot.waitUntil(lambda: tab.state.estop, timeout=GUI_WAIT)
    qtbot.wait(1500)
    assert np.abs(tab.state.platforms[1].eta_dot).max() < 1e-9
    win.reset()
    qtbot.waitUntil(lambda: not tab.state.estop, timeout=GUI_WAIT)


def test_bad_time_series_is_refused_with_a_dialog(qtbot, window, tmp_path):
    win, _ = window
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None, timeout=GUI_WAIT)
    bad = tmp_path / "waves.csv"
    bad.write_text("t,x,y,z,phi,theta,psi\n0,0,0,0,0,0,0\n1,0,0,0,0,0,0\n0.5,0,0,0,0,0,0\n")
    p = tab.platforms["em8000"]
    p.source.setCurrentIndex(3)
    p.load_csv(str(bad))
    p.apply.click()
    qtbot.waitUntil(lambda: any("does not increase" in m for _, m in win.messages), timeout=GUI_WAIT)
    title, msg = next((t, m) for t, m in win.messages if "does not increase" in m)
    assert title == "Motion-Lab" and "waves.csv:4" in msg
    assert tab.state.platforms[0].source == "generator"  # nothing changed


def test_platform_status_line_wraps_instead_of_being_cut(qtbot):
    """In a 1280×800 window the EM8000's status ("ENGAGED source SIMULATION (Hs 2.5 m, Tp 8 s, scale 1.00, …")
    ran past the mode box's edge and was cut.  It wraps: every word is inside the label."""
    from types import SimpleNamespace

    from PyQt5.QtCore import QRect, Qt

    from ui.lab_tab import PlatformPanel

    panel = PlatformPanel("em8000", "E-Motion 8000")
    qtbot.addWidget(panel)
    panel.resize(1280, 480)
    panel.show()
    qtbot.waitExposed(panel)
    p = SimpleNamespace(
        status="engaged", mode="engaged", source="simulation", ramp=1.0, leg_clamped=True, legs=[2.0] * 6,
        eta=[0.0] * 6, source_info={"hs": 2.5, "tp": 8.0, "scale": [1.0, 1.0, 0.85, 1.0, 1.0, 0.6]},
    )  # fmt: skip
    panel.update_state(p, 1.0)
    qtbot.wait(200)
    label = panel.status
    assert "LEG LIMIT" in label.text()
    doc_text = label.text()
    from PyQt5.QtGui import QTextDocument

    doc = QTextDocument()
    doc.setHtml(doc_text)
    plain = doc.toPlainText()
    rect = label.contentsRect()
    need = label.fontMetrics().boundingRect(QRect(0, 0, rect.width(), 10_000), int(Qt.TextWordWrap), plain)
    assert need.width() <= rect.width() and need.height() <= rect.height() + 2, (need, rect)
    assert label.visibleRegion().boundingRect().width() >= rect.width() - 1  # the label itself is not cut either


def test_winch_slider_is_the_labs_and_the_operational_box_is_shown(qtbot, window):
    """Issue 16: the winch slider is the lab HMI's, an integer −100…100 mapped to u = value/100 · 0.2 m/s,
    back to 0 on release; each platform shows its operational box and its generator and remote fields
    range over it; the Comau's joint-limit profile is named."""
    win, _ = window
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and tab.desc is not None, timeout=GUI_WAIT)
    assert "max 0.2 m/s" in tab.winch_slider_label.text()
    assert (tab.winch_slider.minimum(), tab.winch_slider.maximum()) == (-100, 100)
    tab.winch_slider.setSliderDown(True)
    tab.winch_slider.setValue(50)
    qtbot.waitUntil(lambda: abs(tab.state.winch.speed_command - 0.1) < 1e-9, timeout=GUI_WAIT)
    tab.winch_slider.setSliderDown(False)
    tab.winch_slider.sliderReleased.emit()
    assert tab.winch_slider.value() == 0
    qtbot.waitUntil(lambda: tab.state.winch.speed_command == 0.0, timeout=GUI_WAIT)
    em8000 = tab.platforms["em8000"]
    assert "heave -0.6…+0.6 m" in em8000.box_label.text() and "yaw -10…+10 °" in em8000.box_label.text()
    assert em8000.gen[2][0].maximum() == pytest.approx(0.6) and em8000.remote[5].maximum() == pytest.approx(10.0)
    assert "lab" in tab.comau_limits.text() and "q2 -30…30°" in tab.comau_limits.text()
