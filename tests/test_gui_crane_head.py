"""Crane-head tab (pytest-qt offscreen) against a real crane-head engine over 127.0.0.1."""

import numpy as np
import pytest

pytest.importorskip("PyQt5")

from app.engine.session import Session
from app.engine.tac_session import TacSession
from app.net.transport import Client, TransportError
from tests.gui_rig import drive_until, main_window
from tests.helpers import GUI_WAIT
from ui.link import EngineLink
from ui.marine_tab import SceneView2D


@pytest.fixture
def engines(serve):
    teleop, _ = serve(Session(robot_name="comau_smart5_3dof"), rate=200, publish_rate=25)
    tac, _ = serve(TacSession(), rate=50, publish_rate=25)
    return teleop, tac


def _window(qtbot, teleop_url, tmp_path, factory):
    win = main_window(teleop_url, tmp_path / "s.ini", marine_link_factory=factory)
    qtbot.addWidget(win)
    return win


@pytest.fixture
def window(qtbot, engines, tmp_path):
    teleop, tac = engines
    made = []

    def factory():
        made.append(EngineLink(tac.url, name="gui-tac"))
        return made[-1]

    win = _window(qtbot, teleop.url, tmp_path, factory)
    win.show()
    yield win, made
    win.close()


def test_tab_starts_its_engine_and_plots_live(qtbot, window):
    win, made = window
    tab = win.crane_head
    assert tab.link is None and not tab.mode.isEnabled()
    win.tabs.setCurrentWidget(tab)  # first show connects
    assert len(made) == 1 and tab.mode.isEnabled()
    qtbot.waitUntil(lambda: tab.hull is not None and tab.ring.i > 20, timeout=GUI_WAIT)
    assert isinstance(tab.scene, SceneView2D)
    assert tab.hull is not None and len(tab.hull.points) > 50
    x, y = tab.c_ec.getData()
    assert len(x) > 20 and np.all(np.isfinite(y))
    _, ys = tab.c_es.getData()
    assert np.max(ys) > 0.05  # the uncompensated TCP moves in the default Hs 3 m sea
    assert "mode <b>tac</b>" in tab.readout.text()
    win.tabs.setCurrentIndex(0)
    win.tabs.setCurrentWidget(tab)
    assert len(made) == 1  # one engine link, not one per visit


def test_sea_and_mode_reach_the_engine(qtbot, window):
    win, _ = window
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None, timeout=GUI_WAIT)
    tab.spectrum.setCurrentText("torsethaugen")
    tab.hs.setValue(2.0)
    tab.tp.setValue(8.0)
    tab.heading.setValue(135)
    tab.apply_sea.click()
    qtbot.waitUntil(lambda: tab.state.sea.spectrum == "torsethaugen", timeout=GUI_WAIT)
    assert tab.state.sea.hs == 2.0 and tab.state.sea.heading_deg == 135.0
    tab.mode.setCurrentText("cooperative")
    tab.mode.activated.emit(tab.mode.currentIndex())  # what the operator's pick in the list emits
    qtbot.waitUntil(lambda: tab.state.tac_mode == "cooperative", timeout=GUI_WAIT)


def test_breaking_sea_is_refused_with_a_message(qtbot, window):
    win, _ = window
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None, timeout=GUI_WAIT)
    tab.hs.setValue(12.0)
    tab.tp.setValue(5.0)
    tab.apply_sea.click()
    qtbot.waitUntil(lambda: any("steeper than a sea" in m for _, m in win.messages), timeout=GUI_WAIT)
    assert tab.state.sea.hs == 3.0  # the engine kept its sea


def test_stop_freezes_the_head_and_reset_holds_until_a_mode_is_chosen(qtbot, window):
    win, _ = window
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and bool(tab.state.sample), timeout=GUI_WAIT)
    win.status.stop.click()
    qtbot.waitUntil(lambda: tab.state.estop, timeout=GUI_WAIT)
    a1 = tab.state.sample.alpha
    qtbot.wait(300)
    assert tab.state.sample.alpha == a1 and "E-STOP latched" in tab.readout.text()
    win.status.reset.click()
    qtbot.waitUntil(lambda: not tab.state.estop, timeout=GUI_WAIT)
    qtbot.wait(500)  # issue 12 item 2: a reset does not restart the compensation by itself
    assert tab.state.sample.alpha == a1 and tab.state.holding and "HOLDING" in tab.readout.text()
    tab.mode.activated.emit(tab.mode.findText("tac"))  # the operator chooses the mode again
    qtbot.waitUntil(lambda: tab.state.sample.alpha != a1, timeout=GUI_WAIT)


def test_engine_that_does_not_start_is_reported(qtbot, engines, tmp_path):
    teleop, _ = engines

    def broken():
        raise RuntimeError("the engine did not start: no such plant")

    win = _window(qtbot, teleop.url, tmp_path, broken)
    win.tabs.setCurrentWidget(win.crane_head)
    assert any("no such plant" in m for _, m in win.messages)
    assert win.crane_head.start.isVisible() or not win.isVisible()
    win.close()


def test_teleop_engine_refuses_crane_head_commands(engines):
    teleop, tac = engines
    for url, mtype, fields, match in (
        (teleop.url, "set_tac_mode", {"mode": "tac"}, "runs the teleop scene, not the scene"),
        (tac.url, "set_robot", {"robot": "scara"}, "runs the crane-head scene, not the scene"),
    ):
        c = Client(url, role="operator", name="t")
        try:
            with pytest.raises(TransportError, match=match):
                c.request(mtype, **fields)
        finally:
            c.close()


# ---------------------------------------------------------------------------- the vessel (issue 17, item 2)
def test_the_tab_names_the_vessel_and_loads_an_rao_file(qtbot, window, engines, tmp_path):
    """The crane-head tab shows the engine's vessel model and offers the vessels it knows by name; a named
    vessel and an RAO file (read here, sent in parts) reach the engine, which then runs that table; a file
    that does not load is said in one line and nothing changes."""
    from app.marine.vessel import load_rao, parametric_rao, rao_to_csv

    win, _ = window
    tac = engines[1]
    ses = tac.session
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.desc is not None and tab.state is not None, timeout=GUI_WAIT)
    items = [tab.vessel.combo.itemText(i) for i in range(tab.vessel.combo.count())]
    assert items == ["supply", "supply-closed-form", "RAO file…"] and tab.vessel.combo.currentText() == "supply"
    assert "boundary elements" in tab.vessel.label.toolTip()
    tab.vessel.combo.setCurrentIndex(1)
    tab.vessel.combo.activated.emit(1)  # the operator's pick
    qtbot.waitUntil(lambda: "supply-closed-form" in tab.vessel.label.toolTip(), timeout=GUI_WAIT)
    assert ses.sim.vessel  # the engine runs on
    # a table large enough to go in several parts (Bosun's CSV, 60 × 72 rows)
    table = parametric_rao(w=np.linspace(0.1, 3.0, 60), headings_deg=np.arange(0, 360, 5))
    path = tmp_path / "big_vessel.csv"
    path.write_text(rao_to_csv(table), encoding="utf-8")
    assert len(path.read_text(encoding="utf-8")) > 3 * 55_000
    assert tab.vessel.send_file(str(path))
    qtbot.waitUntil(lambda: tab.vessel.label.text() == "RAO file big_vessel.csv", timeout=GUI_WAIT)
    assert tab.vessel.combo.currentText() == "RAO file…"
    got = ses.vessel.table
    np.testing.assert_allclose(got.w, table.w) and np.testing.assert_allclose(got.amp, table.amp, rtol=1e-7)
    bad = tmp_path / "bad.csv"
    bad.write_text("w,heading_deg\n1,2\n", encoding="utf-8")
    assert not tab.vessel.send_file(str(bad))
    qtbot.waitUntil(
        lambda: any("RAO file not sent" in m and "missing column" in m for _, m in win.messages), timeout=GUI_WAIT
    )
    assert ses.vessel.table is got
    from tests.conftest import SHARED_DATA

    mss = SHARED_DATA / "supply_mss.mat"
    if mss.is_file():  # the MSS .mat format through the same path
        assert tab.vessel.send_file(str(mss))
        qtbot.waitUntil(lambda: "supply_mss.mat" in tab.vessel.label.text(), timeout=GUI_WAIT)
        np.testing.assert_allclose(ses.vessel.table.amp, load_rao(mss).amp, rtol=1e-7, atol=1e-12)


def test_set_vessel_parts_in_order_or_refused():
    """Issue 17, item 2 (engine): parts out of order are refused and the upload starts anew; a table that does
    not parse is refused with its line; a name the engine does not know is refused; nothing changes."""
    from app.engine.scene import CommandError
    from app.marine.vessel import parametric_rao, rao_to_csv

    ses = TacSession()
    before = ses.sim
    text = rao_to_csv(parametric_rao(w=np.linspace(0.1, 3.0, 30), headings_deg=np.arange(0, 360, 10)))
    a, b = text[: len(text) // 2], text[len(text) // 2 :]
    with pytest.raises(CommandError, match=r"part 1 of 2 \(x.csv\) is not the next"):
        ses.set_vessel(csv=b, part=1, parts=2, label="x.csv")
    ses.set_vessel(csv=a, part=0, parts=3, label="x.csv")
    with pytest.raises(CommandError, match="not the next of the table being sent"):  # a part of another upload
        ses.set_vessel(csv=b, part=1, parts=2, label="x.csv")
    assert ses.sim is before
    ses.set_vessel(csv=a, part=0, parts=2, label="x.csv")
    assert ses.sim is before  # not until the last part
    ses.set_vessel(csv=b, part=1, parts=2, label="x.csv")
    assert ses.sim is not before and ses.describe().vessel == "RAO file x.csv"
    now = ses.sim
    with pytest.raises(CommandError, match=r"y.csv:3: expected 14 fields"):
        ses.set_vessel(csv=a.splitlines()[1] + "\n" + a.splitlines()[2] + "\n1,2\n", label="y.csv")
    with pytest.raises(CommandError, match="unknown vessel 'tanker'"):
        ses.set_vessel(vessel="tanker")
    with pytest.raises(CommandError, match="not both"):
        ses.set_vessel(vessel="supply", csv=a)
    assert ses.sim is now
    ses.set_vessel(vessel="supply")
    assert ses.vessel.table is None and ses.describe().vessel.startswith("supply: ")


def test_the_rao_file_dialog_leaves_stop_live(qtbot, window):
    """Issue 17, item 2 (safety): the vessel's RAO-file chooser is not modal; Ctrl+Space in its file-name field
    (where Space types a space, issue 26 item 10) and Space in its list of files are STOP for the crane-head
    engine, which confirms the stop, and the STOP button works with it open."""
    from PyQt5.QtCore import Qt
    from PyQt5.QtTest import QTest
    from PyQt5.QtWidgets import QApplication, QListView

    win, _ = window
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.desc is not None and tab.state is not None, timeout=GUI_WAIT)
    tab.vessel._chosen(tab.vessel.combo.count() - 1)  # "RAO file…"
    dlg = tab.vessel._dialog
    qtbot.waitUntil(dlg.isVisible, timeout=GUI_WAIT)
    assert not dlg.isModal() and QApplication.activeModalWidget() is None
    QTest.keyClick(dlg.focusWidget() or dlg, Qt.Key_Space, Qt.ControlModifier)
    qtbot.waitUntil(lambda: tab.state.estop, timeout=GUI_WAIT)
    win.reset()
    qtbot.waitUntil(lambda: not tab.state.estop, timeout=GUI_WAIT)
    files = dlg.findChild(QListView, "listView")
    files.setFocus()
    QTest.keyClick(files, Qt.Key_Space)
    qtbot.waitUntil(lambda: tab.state.estop, timeout=GUI_WAIT)
    win.reset()
    qtbot.waitUntil(lambda: not tab.state.estop, timeout=GUI_WAIT)
    win.status.stop.click()
    qtbot.waitUntil(lambda: tab.state.estop, timeout=GUI_WAIT)
    assert dlg.isVisible()
    dlg.close()


def test_the_on_screen_stick_moves_the_tcp_target_through_the_engine(qtbot, window):
    """Issue 30, items 2 and 7: the crane-head tab has the stick; armed (neutral, then Shift held) it moves the
    TCP's target in the world through the engine, and releasing it holds the target."""
    from PyQt5.QtCore import Qt

    win, _ = window
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and len(tab.state.p_d_n) == 3, timeout=GUI_WAIT)
    p0 = np.array(tab.state.p_d_n)
    stick = tab.stick
    assert win._stick_of_current_tab() is stick
    drive_until(
        qtbot,
        stick,
        lambda: tab.state.flags,
        lambda: stick.pad.set_position(1.0, 0.0, True),
        lambda: np.array(tab.state.p_d_n)[0] - p0[0] > 0.1,
    )
    stick.pad.set_position(0.0, 0.0, False)
    stick.key(Qt.Key_Shift, False)
    qtbot.wait(300)
    held = np.array(tab.state.p_d_n)
    qtbot.wait(500)
    np.testing.assert_array_equal(np.array(tab.state.p_d_n), held)


def _choose(combo, text: str) -> None:
    """What the operator's pick of ``text`` in the list emits (the project's convention: the arrow keys are the
    stick's, and an offscreen popup does not take a click)."""
    combo.setCurrentText(text)
    combo.activated.emit(combo.currentIndex())


def test_the_target_and_frame_selectors_reach_the_engine_and_the_refusal_is_shown(qtbot, window):
    """Issue 30, items 1, 5 and 7: the target row's selectors switch the engine to the vessel target (its frame then
    target, its deck drawn moving) and back to the world frame; the stick's title says the frame; a refusal (the
    tool frame is not this scene's) comes back as a message, the selector as before."""
    win, _ = window
    tab = win.crane_head
    notices = []
    tab.notice.connect(lambda level, text: notices.append(text))
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and tab.target.isEnabled(), timeout=GUI_WAIT)
    _choose(tab.mode, "cooperative")  # following a moving deck needs the crane (H107)
    qtbot.waitUntil(lambda: tab.state.tac_mode == "cooperative", timeout=GUI_WAIT)
    _choose(tab.target, "vessel")
    qtbot.waitUntil(lambda: tab.state.target == "vessel" and tab.state.frame == "target", timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: tab.frame.currentText() == "target", timeout=GUI_WAIT)
    assert "over the target deck" in tab.stick_box.title()
    deck0 = np.array(tab.state.scene.deck)
    qtbot.waitUntil(lambda: not np.allclose(np.array(tab.state.scene.deck), deck0), timeout=GUI_WAIT)  # it moves
    _choose(tab.frame, "world")
    qtbot.waitUntil(lambda: tab.state.frame == "world" and "in the world" in tab.stick_box.title(), timeout=GUI_WAIT)
    tab._send("set_frame", frame="tool")  # what no selector offers: the engine's refusal reaches the operator
    qtbot.waitUntil(lambda: any("set_frame refused" in n for n in notices), timeout=GUI_WAIT)
    assert tab.frame.currentText() == "world"


def test_the_delay_and_prediction_reach_the_engine_and_a_refusal_is_shown(qtbot, window):
    """Issue 31, item 2: the mode row's delay and *predict* reach the engine with the compensation off (the snapshot
    then says so); while compensating the engine refuses them with the reason, the operator is told, and the
    controls show what the engine has."""
    win, _ = window
    tab = win.crane_head
    notices = []
    tab.notice.connect(lambda level, text: notices.append(text))
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and tab.delay.isEnabled(), timeout=GUI_WAIT)
    tab.delay.setValue(0.3)
    tab.predict.click()  # in tac: refused
    qtbot.waitUntil(lambda: any("set_tac_delay refused" in n for n in notices), timeout=GUI_WAIT)
    # the refusal's own notice (another, e.g. "input stale" on a loaded machine, may come after it)
    assert "compensation is off" in next(n for n in notices if "set_tac_delay refused" in n)
    qtbot.waitUntil(lambda: not tab.predict.isChecked() and tab.delay.value() == 0.0, timeout=GUI_WAIT)
    _choose(tab.mode, "off")
    qtbot.waitUntil(lambda: tab.state.tac_mode == "off", timeout=GUI_WAIT)
    tab.delay.setValue(0.3)
    tab.predict.click()
    qtbot.waitUntil(lambda: tab.state.delay == 0.3 and tab.state.predict, timeout=GUI_WAIT)
    _choose(tab.mode, "tac")
    qtbot.waitUntil(lambda: tab.state.tac_mode == "tac" and tab.predict.isChecked(), timeout=GUI_WAIT)


def test_the_lift_window_strip_shows_the_prediction_and_the_operator_s_threshold(qtbot, window):
    """Issue 31, item 3: the strip under the plots draws the tip's heave predicted over the next 20 s with its
    band (the predictor starts on the sensor's past: no 150 s wait); the *lift window* threshold reaches the engine;
    a threshold the sea keeps within opens the window (the green span, the verdict), a tight one closes it."""
    win, _ = window
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and tab.state.lift is not None and bool(tab.state.lift.mean),
                    timeout=GUI_WAIT)  # fmt: skip
    qtbot.waitUntil(lambda: tab.lift_mean.getData()[0] is not None and len(tab.lift_mean.getData()[0]) == 41,
                    timeout=GUI_WAIT)  # fmt: skip
    assert tab.lift_mean.getData()[0][-1] == pytest.approx(20.0)
    for threshold, opened in ((8.0, True), (0.1, False)):
        tab.lift_threshold.setValue(threshold)
        tab.lift_threshold.editingFinished.emit()
        qtbot.waitUntil(lambda t=threshold: tab.state.lift.threshold == t, timeout=GUI_WAIT)
        qtbot.waitUntil(lambda o=opened: tab.state.lift.open == o and tab.lift_open.isVisible() == o, timeout=GUI_WAIT)
        assert ("OPEN" in tab.lift_verdict.text()) == opened
        assert tab.lift_lines[0].value() == pytest.approx(threshold)


def test_the_landing_panel_shows_the_load_as_a_share_of_its_swl_as_the_engine_reports_it(qtbot, window):
    """Issue 31, item 4: the crane tab's landing status line carries the engine's "X % of SWL" (this load, its
    dynamic factor seen, the rated capacity at the crane's radius) as "SWL X %", green under 90 %, amber to 100 %,
    red over it;
    its tooltip says what the figure is made of."""
    from ui.widgets.landing import LandingPanel
    from ui.widgets.status import LIGHT

    win, _ = window
    tab = win.crane_head
    win.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.state is not None and tab.state.load is not None
                    and tab.state.load.swl_percent is not None, timeout=GUI_WAIT)  # fmt: skip
    ld = tab.state.load
    qtbot.waitUntil(lambda: "SWL " in tab.landing.status.text(), timeout=GUI_WAIT)
    assert LIGHT["ok"] in tab.landing.status.text()  # 5 t at 29.7 m: about half its SWL
    assert f"rated {ld.capacity_t:g} t" in tab.landing.status.toolTip()
    panel = LandingPanel()
    qtbot.addWidget(panel)
    for pct, look in ((95.0, "warn"), (104.0, "error")):
        panel.show_load(type(ld)(**{**{k: getattr(ld, k) for k in ld.__slots__}, "swl_percent": pct}))
        assert f"SWL {pct:.0f} %" in panel.status.text() and LIGHT[look] in panel.status.text()
