"""Motion-Lab tab (pytest-qt offscreen) against a real lab engine over 127.0.0.1."""

import numpy as np
import pytest

pytest.importorskip("PyQt5")

from app.engine.lab_session import LabSession
from app.engine.session import Session
from tests.gui_rig import color_px, main_window
from tests.helpers import GUI_WAIT
from ui.lab.scene import LabScene2D
from ui.link import EngineLink


@pytest.fixture
def window(qtbot, tmp_path, serve):
    teleop, _ = serve(Session(robot_name="comau_smart5_3dof"), rate=200, publish_rate=25)
    lab, _ = serve(LabSession(), rate=50, publish_rate=25)
    made = []

    def factory():
        made.append(EngineLink(lab.url, name="gui-lab"))
        return made[-1]

    win = main_window(teleop.url, tmp_path / "s.ini", lab_link_factory=factory)
    qtbot.addWidget(win)
    win.show()
    yield win, made
    win.close()


@pytest.fixture
def lab_alone(qtbot, serve):
    """A Motion-Lab tab of its own against a lab engine in this process: (session, server, thread, tab, notices)."""
    from ui.lab_tab import MotionLabTab

    ses = LabSession()
    srv, th = serve(ses, rate=50, publish_rate=25)
    notices: list[str] = []
    tab = MotionLabTab(link_factory=lambda: EngineLink(srv.url, name="gui-lab"), use_gl=False)
    qtbot.addWidget(tab)
    tab.notice.connect(lambda lvl, text: notices.append(text))
    tab.resize(1200, 800)
    tab.show()
    assert tab.connect_engine()
    qtbot.waitUntil(lambda: tab.state is not None, timeout=GUI_WAIT)
    yield ses, srv, th, tab, notices
    tab.close_link()


def test_lab_tab_runs_platforms_through_the_engine(qtbot, window):
    win, made = window
    tab = win.motion_lab
    assert tab.link is None and not tab.tabs.currentWidget().isEnabled()  # its pages wait for the engine
    win.tabs.setCurrentWidget(tab)
    assert len(made) == 1 and tab.tabs.currentWidget().isEnabled()
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
    tab.comau.vvmc.click()
    qtbot.waitUntil(lambda: tab.state.vvmc and tab.state.comau.mode == "motion_comp", timeout=GUI_WAIT)
    assert tab.comau.comau_mode.currentText() == "MOTION_COMP" and tab.comau.winch_mode.currentText() == "MOTION_COMP"
    assert tab.comau.drive_box.title().startswith("VVMC drive (work point on EM1500")  # issue 30, item 4
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
    bad.write_text("t,x,y,z,phi,theta,psi\n0,0,0,0,0,0,0\n1,0,0,0,0,0,0\n0.5,0,0,0,0,0,0\n", encoding="utf-8")
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

    from ui.lab.platform import PlatformPanel

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
    assert "max 0.2 m/s" in tab.comau.winch_slider_label.text()
    assert (tab.comau.winch_slider.minimum(), tab.comau.winch_slider.maximum()) == (-100, 100)
    tab.comau.winch_slider.setSliderDown(True)
    tab.comau.winch_slider.setValue(50)
    qtbot.waitUntil(lambda: abs(tab.state.winch.speed_command - 0.1) < 1e-9, timeout=GUI_WAIT)
    tab.comau.winch_slider.setSliderDown(False)
    tab.comau.winch_slider.sliderReleased.emit()
    assert tab.comau.winch_slider.value() == 0
    qtbot.waitUntil(lambda: tab.state.winch.speed_command == 0.0, timeout=GUI_WAIT)
    em8000 = tab.platforms["em8000"]
    assert "heave -0.6…+0.6 m" in em8000.box_label.text() and "yaw -10…+10 °" in em8000.box_label.text()
    assert em8000.gen[2][0].maximum() == pytest.approx(0.6) and em8000.remote[5].maximum() == pytest.approx(10.0)
    assert "lab" in tab.comau.comau_limits.text() and "q2 -30…30°" in tab.comau.comau_limits.text()


# ---------------------------------------------------------------------------- the lab HMI's parity (issue 16, item 5)
def test_status_word_lights_and_generator_defaults_as_the_lab_hmi(qtbot, window):
    """Item 5: each platform shows its Rexroth status (operation state, system status, operation mode) and
    follows it (SETTLED → TRANSIT while raising); the machine and sensor lights are green where the model
    runs and grey for the tracker and the remote interface (in the screen's pixels); the sine generator's
    fields start at the lab's defaults with its ranges and steps."""
    from ui.widgets.status import LIGHT

    win, _ = window
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and tab.desc is not None, timeout=GUI_WAIT)
    em8000 = tab.platforms["em8000"]
    qtbot.waitUntil(lambda: "SETTLED" in em8000.motion_label.text(), timeout=GUI_WAIT)
    text = em8000.motion_label.text()
    assert "SYSTEM_OK" in text and "op mode <b>NORMAL</b>" in text and "0x01000002" in text
    lights = tab.status.machine_lights
    qtbot.waitUntil(lambda: lights["em8000"].state == "ok", timeout=GUI_WAIT)
    green, grey = (tuple(int(LIGHT[k][i : i + 2], 16) for i in (1, 3, 5)) for k in ("ok", "off"))
    for name in ("em8000", "em1500", "comau", "mru1", "mru2"):
        assert lights[name].state == "ok" and color_px(lights[name], green) > 30, name
    for name in ("tracker", "remote"):
        assert lights[name].state == "off" and color_px(lights[name], grey, 12) > 30, name
        assert color_px(lights[name], green) == 0 and "not connected" in lights[name].toolTip()
    # the generator as the lab's HMI: 0.2 m heave, 2° roll and pitch at 0.1 Hz; 0.01-1 Hz step 0.02, ±180° step 10
    values = [(a.value(), f.value(), p.value()) for a, f, p in em8000.gen]
    assert [v[0] for v in values] == pytest.approx([0, 0, 0.2, 2.0, 2.0, 0], abs=1e-9)
    assert [v[1] for v in values] == pytest.approx([0.1] * 6, abs=1e-3) and [v[2] for v in values] == [0.0] * 6
    _, f, ph = em8000.gen[0]
    assert (f.minimum(), f.maximum(), f.singleStep()) == pytest.approx((0.01, 1.0, 0.02))
    assert (ph.minimum(), ph.maximum(), ph.singleStep()) == pytest.approx((-180, 180, 10))
    em8000.buttons["neutral"].click()
    qtbot.waitUntil(lambda: "TRANSIT" in em8000.motion_label.text(), timeout=GUI_WAIT)


def test_comau_joint_jog_from_the_gui_holds_enable_and_stops_on_release(qtbot, window):
    """Item 5: with enable held (Shift), a held jog button moves its joint only and letting go stops it;
    without enable the engine refuses the jog and says so once per press, nothing moves."""
    from PyQt5.QtCore import Qt

    win, _ = window
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    tab.tabs.setCurrentIndex(2)
    qtbot.waitUntil(lambda: tab.state is not None and tab.state.comau.mode == "remote", timeout=GUI_WAIT)
    qtbot.wait(300)  # the stick seen at neutral with enable released
    q0 = np.array(tab.state.comau.q)
    plus = tab.comau.jog_buttons[(2, 1)]
    qtbot.mousePress(plus, Qt.LeftButton)  # not armed: refused, said once, nothing moves
    qtbot.waitUntil(lambda: any("lab_comau_jog refused" in m for _, m in win.messages), timeout=GUI_WAIT)
    qtbot.wait(600)  # five more refreshes, each refused
    qtbot.mouseRelease(plus, Qt.LeftButton)
    refused = [m for _, m in win.messages if "lab_comau_jog refused" in m]
    assert len(refused) == 1 and "not armed" in refused[0]
    assert np.allclose(tab.state.comau.q, q0, atol=1e-9)
    tab.stick.key(Qt.Key_Shift, True)  # enable held: the input arms
    qtbot.waitUntil(lambda: tab.state.flags.armed, timeout=GUI_WAIT)
    qtbot.mousePress(plus, Qt.LeftButton)
    qtbot.waitUntil(
        lambda: tab.state.comau_jog.joint == 2 and "jogging q2 +25 %" in tab.comau.jog_label.text(), timeout=GUI_WAIT
    )
    qtbot.waitUntil(lambda: tab.state.comau.q[1] - q0[1] > np.radians(2.0), timeout=GUI_WAIT)
    qtbot.mouseRelease(plus, Qt.LeftButton)
    qtbot.waitUntil(lambda: tab.state.comau_jog.joint == 0 and tab.state.comau.qd == [0, 0, 0], timeout=GUI_WAIT)
    q = np.array(tab.state.comau.q)
    assert np.allclose(q[[0, 2]], q0[[0, 2]], atol=1e-9)  # q1 and q3 never moved
    qtbot.wait(500)
    assert tab.state.comau.q == pytest.approx(q.tolist(), abs=1e-12)  # and q2 stays where it was let go
    tab.stick.key(Qt.Key_Shift, False)


def test_lab_csv_logger_writes_every_state_for_its_duration(qtbot, window, tmp_path):
    """Item 5: the lab HMI's CSV logger: a file, a duration, progress and a sample count; every published
    state (25 a second) for the duration, then it stops by itself."""
    import csv

    from ui.csv_logger import LAB_LOG_COLUMNS

    win, _ = window
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None, timeout=GUI_WAIT)
    path = tmp_path / "lab.csv"
    tab.status.log_path.setText(str(path))
    tab.status.log_duration.setValue(2)
    assert (tab.status.log_duration.minimum(), tab.status.log_duration.maximum()) == (1, 1200)
    tab.status.log_button.click()
    assert tab.status.logger is not None and tab.status.log_button.text() == "Stop logging"
    qtbot.waitUntil(lambda: tab.status.logger is None, timeout=GUI_WAIT)
    rows = list(csv.reader(path.open(encoding="utf-8", newline="")))
    assert tuple(rows[0]) == LAB_LOG_COLUMNS and len(rows) - 1 == 51  # 0 … 2 s every 0.04 s
    t = np.array([float(r[0]) for r in rows[1:]])
    assert t[-1] == pytest.approx(2.0) and np.allclose(np.diff(t), 0.04, atol=1e-6)  # none lost
    assert tab.status.log_progress.value() == 1000 and tab.status.log_samples.text() == "51 samples"
    assert tab.status.log_button.text() == "Start logging"
    assert "CSV logger duration reached: 51 samples in lab.csv" in win.status.log_view.toPlainText()


def test_lab_csv_logger_stops_cleanly_when_the_engine_goes(qtbot, tmp_path, lab_alone):
    """Item 5: an engine that goes away ends the log with a complete file and says so; so does closing."""
    _, srv, th, tab, notices = lab_alone
    path = tmp_path / "lost.csv"
    tab.status.log_path.setText(str(path))
    tab.status.log_duration.setValue(600)
    tab.status.start_logger()
    qtbot.waitUntil(lambda: tab.status.logger is not None and tab.status.logger.rows > 10, timeout=GUI_WAIT)
    srv.stop()
    th.join(timeout=5)
    srv.close()
    qtbot.waitUntil(lambda: tab.status.logger is None, timeout=GUI_WAIT)
    assert any("engine lost" in n for n in notices)
    assert all(light.state == "unknown" for light in tab.status.machine_lights.values())  # nothing known any more
    lines = path.read_text(encoding="utf-8").splitlines()
    assert len(lines) > 11 and all(len(line.split(",")) == len(lines[0].split(",")) for line in lines)


def test_load_swing_tab_activates_anti_swing_and_shows_estimate_beside_the_true_swing(qtbot, lab_alone):
    """Issue 16, item 4 (the lab HMI's "Pendel Estimator" tab): Activate is refused-by-design without VVMC
    (disabled, and the engine's refusal shown if sent); with VVMC on, a 4° swing given to the load, Reset
    then Activate: the swing is damped below 0.5°, the estimate curve follows the true one and the error
    plot carries the ±2σ band; Deactivate turns it off."""
    import math

    ses, _, _, tab, notices = lab_alone
    tab.tabs.setCurrentIndex(tab.tabs.count() - 1)
    assert tab.tabs.tabText(tab.tabs.currentIndex()) == "Load swing"
    qtbot.waitUntil(lambda: tab.state is not None and tab.state.swing is not None, timeout=GUI_WAIT)
    buttons = tab.swing.swing_buttons
    assert not buttons["activate"].isEnabled() and "needs VVMC on" in tab.swing.swing_label.text()
    buttons["activate"].setEnabled(True)  # sent anyway: the engine refuses, the GUI says why
    buttons["activate"].click()
    qtbot.waitUntil(lambda: any("turn VVMC on first" in n for n in notices), timeout=GUI_WAIT)
    tab.comau.vvmc.click()
    qtbot.waitUntil(lambda: tab.state.vvmc and buttons["activate"].isEnabled(), timeout=GUI_WAIT)
    qtbot.wait(1500)  # the Comau settles on the work point
    kick, tick = [], ses.tick

    def kicked_tick(*args, **kw):  # the kick lands between two steps, in the engine's own thread
        if kick:
            kick.pop()
            ses.load.kick(math.radians(4.0), 0.0)  # the load on its wire (app/scenes/lab_load.py)
        return tick(*args, **kw)

    ses.tick = kicked_tick
    kick.append(True)
    qtbot.waitUntil(lambda: math.degrees(tab.state.pendulum.swing) > 3.0, timeout=GUI_WAIT)
    buttons["reset"].click()
    buttons["activate"].click()
    qtbot.waitUntil(lambda: tab.state.swing.active and "ACTIVE" in tab.swing.swing_label.text(), timeout=GUI_WAIT)
    t_active = tab.state.t
    qtbot.waitUntil(lambda: math.degrees(tab.state.pendulum.swing) < 0.5, timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: tab.state.t > t_active + 3.0, timeout=GUI_WAIT)
    ts, true = tab.swing.swing_state_curves[0].getData()
    est = tab.swing.swing_state_curves[1].getData()[1]
    assert np.nanmax(true) > 3.0  # the swing was seen …
    late = ts > t_active + 1.0  # … and, a second after its reset, the estimate follows it
    assert late.sum() >= 10 and np.nanmax(np.abs(est[late] - true[late])) < 0.5
    band = tab.swing.swing_err_curves[2].getData()[1]
    assert np.all(band[late] > 0) and np.all(tab.swing.swing_err_curves[3].getData()[1][late] < 0)
    assert np.nanmax(np.abs(tab.swing.swing_off_curves[0].getData()[1])) > 5.0  # the law moved the tool [mm]
    buttons["deactivate"].click()
    qtbot.waitUntil(lambda: not tab.state.swing.active and buttons["activate"].isEnabled(), timeout=GUI_WAIT)


def test_platform_panels_show_and_choose_the_wave_simulators_vessel(qtbot, window):
    """Issue 17, item 2: both platforms' wave-simulator pages name the engine's vessel and choose another."""
    win, _ = window
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.desc is not None, timeout=GUI_WAIT)
    em8000, em1500 = tab.platforms["em8000"].vessel, tab.platforms["em1500"].vessel
    assert "supply: " in em8000.label.toolTip() and em1500.combo.currentText() == "supply"
    em8000.combo.setCurrentIndex(1)
    em8000.combo.activated.emit(1)
    qtbot.waitUntil(lambda: "supply-closed-form" in em1500.label.toolTip(), timeout=GUI_WAIT)  # one for the scene
    qtbot.waitUntil(
        lambda: "wave simulator vessel: supply-closed-form" in win.status.log_view.toPlainText(), timeout=GUI_WAIT
    )


def test_a_held_jog_stops_when_its_page_or_the_tab_is_left(qtbot, window):
    """Safety (H62): a jog button held while the operator switches to another Motion-Lab page, or to another
    tab, never gets its release; the GUI stops resending the jog and the engine halts the joint."""
    from PyQt5.QtCore import Qt

    win, _ = window
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    tab.tabs.setCurrentIndex(2)
    qtbot.waitUntil(lambda: tab.state is not None and tab.state.comau.mode == "remote", timeout=GUI_WAIT)
    qtbot.wait(300)
    for leave in (lambda: tab.tabs.setCurrentIndex(3), lambda: win.tabs.setCurrentIndex(0)):
        win.tabs.setCurrentWidget(tab)
        tab.tabs.setCurrentIndex(2)
        tab.stick.key(Qt.Key_Shift, False)  # the stick let its keys go when its page was left: enable anew
        qtbot.wait(300)
        tab.stick.key(Qt.Key_Shift, True)
        qtbot.waitUntil(lambda: tab.state.flags.armed, timeout=GUI_WAIT)
        plus = tab.comau.jog_buttons[(1, 1)]
        qtbot.mousePress(plus, Qt.LeftButton)
        qtbot.waitUntil(lambda: tab.state.comau_jog.joint == 1, timeout=GUI_WAIT)
        leave()  # no release reaches the button
        qtbot.waitUntil(lambda: tab.comau._jogging is None, timeout=GUI_WAIT)  # the GUI stopped resending
        win.tabs.setCurrentWidget(tab)
        qtbot.waitUntil(lambda: tab.state.comau_jog.joint == 0 and tab.state.comau.qd == [0, 0, 0], timeout=GUI_WAIT)
    tab.stick.key(Qt.Key_Shift, False)


def test_the_lab_s_delay_and_prediction_reach_the_engine_and_are_held_under_vvmc(qtbot, lab_alone):
    """Issue 31, item 2 (the lab's engine): the Comau page's delay and *predict* reach the engine with VVMC off (the
    snapshot then says so); with VVMC on they are disabled and show what the engine has; a refusal (sent anyway) is
    told to the operator."""
    ses, _, _, tab, notices = lab_alone
    page = tab.comau
    tab.tabs.setCurrentWidget(page)
    qtbot.waitUntil(lambda: page.delay.isEnabled(), timeout=GUI_WAIT)
    page.delay.setValue(0.3)
    page.predict.click()
    qtbot.waitUntil(lambda: tab.state.delay == 0.3 and tab.state.predict, timeout=GUI_WAIT)
    assert ses.delay == 0.3 and ses.predict
    page.vvmc.click()
    qtbot.waitUntil(lambda: tab.state.vvmc and not page.delay.isEnabled(), timeout=GUI_WAIT)
    tab._send("set_lab_delay", delay=0.0, predict=False)  # what the disabled controls would not send
    qtbot.waitUntil(lambda: any("set_lab_delay refused" in n for n in notices), timeout=GUI_WAIT)
    # the refusal's own notice (another, e.g. "input stale" on a loaded machine, may come after it)
    assert "while VVMC is off" in next(n for n in notices if "set_lab_delay refused" in n)
    assert page.delay.value() == 0.3 and page.predict.isChecked() and ses.delay == 0.3


def test_the_comau_page_names_the_platform_it_slows_for(qtbot, serve, tmp_path):
    """Issue 32, item 5 (H115) as the operator sees it: the lab engine on the Comau's data-sheet limits, the stick
    held down (Shift and Page Down) on the Comau & winch page: the readout names the extension arm and EM8000's
    deck with its clearance, amber while it slows, and the alarm list has "Slowed near"; released, the arm holds
    clear of the deck."""
    from PyQt5.QtCore import Qt

    teleop, _ = serve(Session(robot_name="comau_smart5_3dof"), rate=200, publish_rate=25)
    ses = LabSession(comau_profile="datasheet")
    lab, _ = serve(ses, rate=50, publish_rate=25)
    win = main_window(teleop.url, tmp_path / "s.ini", lab_link_factory=lambda: EngineLink(lab.url, name="gui-lab"))
    qtbot.addWidget(win)
    win.resize(1280, 900)
    win.show()
    tab = win.motion_lab
    win.tabs.setCurrentWidget(tab)
    tab.tabs.setCurrentIndex(2)
    qtbot.waitUntil(lambda: tab.state is not None and tab.state.comau.mode == "remote", timeout=GUI_WAIT)
    qtbot.wait(300)  # the stick seen at neutral with enable released
    tab.stick.key(Qt.Key_Shift, True)
    qtbot.waitUntil(lambda: tab.state.flags.armed, timeout=GUI_WAIT)
    tab.stick.key(Qt.Key_PageDown, True)
    qtbot.waitUntil(lambda: tab.state.hazard.slowed, timeout=60_000)
    qtbot.waitUntil(lambda: "slowing" in tab.comau.readout.text(), timeout=GUI_WAIT)
    text = tab.comau.readout.text()
    assert "extension arm ↔ EM8000 deck: clearance" in text and "#b06000" in text, text
    qtbot.waitUntil(lambda: any(a.key == "hazard_slowed" and a.active for a in tab.state.alarms), timeout=GUI_WAIT)
    tab.comau.readout.grab().save(str(tmp_path / "lab_guard.png"))
    tab.stick.key(Qt.Key_PageDown, False)
    tab.stick.key(Qt.Key_Shift, False)
    qtbot.wait(1500)
    assert ses.lab.guard_report[0] < 0 or ses.lab.guard_report[2] >= ses.lab.guard.stop - 1e-3
    win.close()
