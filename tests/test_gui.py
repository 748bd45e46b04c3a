"""Operator HMI with pytest-qt (offscreen), talking to a real engine over 127.0.0.1."""

import csv
import os
import shutil
import subprocess
import sys
import threading
import time
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("PyQt5")
from PyQt5.QtCore import QSettings

from app.engine.server import EngineServer
from app.engine.session import Session
from app.net.snapshots import InputFlags, TeleopSnapshot
from tests.gui_rig import drive_until
from tests.helpers import GUI_WAIT
from ui.csv_logger import StateCsvLogger
from ui.glprobe import gl_available
from ui.link import EngineLink
from ui.main_window import MainWindow
from ui.widgets.view3d import RobotView2D, make_robot_view


@pytest.fixture
def engine():
    srv = EngineServer(Session(robot_name="comau_smart5_3dof"), bind="tcp://127.0.0.1:0", rate=500, publish_rate=50)
    th = threading.Thread(target=srv.run, kwargs={"duration": 120.0}, daemon=True)
    th.start()
    yield srv
    srv.stop()
    th.join(timeout=5)
    srv.close()


@pytest.fixture
def window(qtbot, engine, tmp_path):
    link = EngineLink(engine.url)
    win = MainWindow(link, settings=QSettings(str(tmp_path / "s.ini"), QSettings.IniFormat), dialogs=False)
    qtbot.addWidget(win)
    win.show()
    qtbot.waitUntil(lambda: win.teleop.state is not None, timeout=GUI_WAIT)
    yield win
    win.close()


def test_fallback_2d_view_when_gl_is_unavailable(qtbot):
    assert os.environ["QT_QPA_PLATFORM"] == "offscreen"
    assert not gl_available()
    view = make_robot_view()
    qtbot.addWidget(view)
    assert isinstance(view, RobotView2D)


def test_choosing_a_robot_loads_it_in_engine_and_view(qtbot, window):
    combo = window.teleop.robot
    combo.setCurrentText("scara")
    combo.activated.emit(combo.currentIndex())
    qtbot.waitUntil(lambda: window.teleop.state.robot == "scara", timeout=GUI_WAIT)
    qtbot.wait(100)
    view = window.teleop.view
    qtbot.waitUntil(lambda: view.draw.model is not None and view.draw.model.name == "scara", timeout=GUI_WAIT)
    shown = [p for p in view.plots["top"]["paths"] if p.isVisible() and not p.path().isEmpty()]
    assert len(shown) >= 4 + 2  # scara drawn from its file: base plate, 4 links, joint housings, tool
    assert len(window.teleop.bars.bars) == 4


def test_mode_and_solver_reach_the_engine(qtbot, window):
    window.teleop.mode_pos.click()
    qtbot.waitUntil(lambda: window.teleop.state.mode == "position", timeout=GUI_WAIT)
    solver = window.teleop.solver
    solver.setCurrentText("ga")
    solver.activated.emit(solver.currentIndex())
    qtbot.waitUntil(lambda: window.teleop.state.solver == "ga", timeout=GUI_WAIT)
    frame = window.teleop.frame  # issue 30, item 1: the frame selector shows the engine's frame
    frame.setCurrentText("tool")
    frame.activated.emit(frame.currentIndex())
    qtbot.waitUntil(lambda: window.teleop.state.frame == "tool", timeout=GUI_WAIT)
    assert frame.findText("target") < 0  # the teleop scene has no target deck: not offered


def test_virtual_stick_moves_the_plotted_tool_point(qtbot, window):
    plots = window.teleop.plots
    qtbot.waitUntil(lambda: plots.ring is not None and plots.ring.n > 5, timeout=GUI_WAIT)
    x0 = plots.ring.view()[-1, 7]
    stick = window.teleop.stick
    drive_until(
        qtbot,
        stick,
        lambda: window.teleop.state.flags,
        lambda: stick.pad.set_position(1.0, 0.0, True),
        lambda: plots.ring.view()[-1, 7] - x0 > 0.05,
    )
    window.teleop.stick.pad.set_position(0.0, 0.0, False)
    assert plots.frames_drawn > 0


def test_keyboard_drives_the_stick(qtbot, window):
    from PyQt5.QtCore import Qt

    got = []
    window.teleop.stick.changed.connect(lambda *a: got.append(a))
    assert window.teleop.stick.key(Qt.Key_Up, True)
    assert got[-1] == (0.0, 1.0, 0.0, 0.0, False)  # deflection alone does not enable
    window.teleop.stick.key(Qt.Key_Up, False)
    assert got[-1] == (0.0, 0.0, 0.0, 0.0, False)
    window.teleop.stick.key(Qt.Key_Shift, True)  # Shift is the enable (deadman), apart from deflection
    assert got[-1] == (0.0, 0.0, 0.0, 0.0, True)
    window.teleop.stick.key(Qt.Key_Shift, False)
    assert got[-1] == (0.0, 0.0, 0.0, 0.0, False)


def test_stop_latches_and_reset_clears(qtbot, window):
    window.status.stop.click()
    qtbot.waitUntil(lambda: window.teleop.state.estop, timeout=GUI_WAIT)
    assert window.status.latched.text() == "E-STOP LATCHED" and window.status.reset.isEnabled()
    assert window.status.lights["plant"].state == "error"
    window.status.reset.click()
    qtbot.waitUntil(lambda: not window.teleop.state.estop, timeout=GUI_WAIT)
    assert window.status.latched.text() == ""


def test_invalid_xml_gives_error_and_keeps_robot(qtbot, window, tmp_path):
    bad = tmp_path / "broken_arm.xml"
    bad.write_text('<robot name="x" type="serial" angle_unit="deg"><description/></robot>', encoding="utf-8")
    window.teleop.load_robot_file(str(bad))
    qtbot.waitUntil(lambda: len(window.messages) > 0, timeout=GUI_WAIT)
    title, message = window.messages[-1]
    assert title == "Robot not loaded" and "broken_arm.xml:1: schema" in message
    qtbot.wait(200)
    assert window.teleop.state.robot == "comau_smart5_3dof"


def test_open_xml_reads_a_utf16_or_latin1_file_as_the_engine_does(qtbot, window, tmp_path):
    """Issue 27, item 9: Open XML read the file as UTF-8 ("Robot not loaded: 'utf-8' codec can't decode")."""
    from app.models.registry import resolve

    text = resolve("scara").read_text(encoding="utf-8")
    text = text.replace('name="scara"', 'name="utf16_arm"', 1).replace('encoding="UTF-8"', 'encoding="UTF-16"', 1)
    path = tmp_path / "utf16_arm.xml"
    path.write_bytes(text.encode("utf-16"))  # with a byte-order mark
    window.teleop.load_robot_file(str(path))
    qtbot.waitUntil(lambda: window.teleop.state.robot == "utf16_arm", timeout=GUI_WAIT)
    bad = tmp_path / "latin_arm.xml"
    bad.write_bytes(b'<?xml version="1.0" encoding="UTF-8"?>\n<robot name="caf\xe9"/>')  # says UTF-8, is Latin-1
    window.teleop.load_robot_file(str(bad))
    qtbot.waitUntil(lambda: len(window.messages) > 0, timeout=GUI_WAIT)
    assert window.messages[-1][0] == "Robot not loaded"
    assert window.messages[-1][1].startswith("latin_arm.xml:2: not valid UTF-8 (byte 0xe9)")
    assert window.teleop.state.robot == "utf16_arm"


def test_open_robot_file_takes_a_urdf(qtbot, window, tmp_path):
    """Issue 32, item 1: a URDF opened in the GUI is driven as the robot file it makes (the engine reads its text);
    a URDF the importer refuses gives the one-line message and keeps the robot."""
    pytest.importorskip("yourdfpy", reason="yourdfpy (bosun[urdf])")
    from app.resources import robot_library

    window.teleop.load_robot_file(str(robot_library() / "urdf" / "ur5.urdf"))
    qtbot.waitUntil(lambda: window.teleop.state.robot == "ur5", timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: len(window.teleop.state.q) == 6, timeout=GUI_WAIT)
    bad = tmp_path / "loop.urdf"
    bad.write_text(
        '<robot name="loop">\n<link name="a"/><link name="b"/>\n'
        '<joint name="ab" type="floating"><parent link="a"/><child link="b"/></joint>\n</robot>\n',
        encoding="utf-8",
    )
    window.teleop.load_robot_file(str(bad))
    qtbot.waitUntil(lambda: len(window.messages) > 0, timeout=GUI_WAIT)
    title, message = window.messages[-1]
    assert title == "Robot not loaded" and message.startswith("loop.urdf:3: joint 'ab': type 'floating'"), message
    assert window.teleop.state.robot == "ur5"


def test_the_ga_task_row_sends_and_shows_the_engine_s_task(qtbot, window):
    """Issue 32, item 4 (H111): the GA task chosen in the teleop tab reaches the engine and the row shows the
    engine's task (another client's numbers as a custom line); it is greyed out while a non-GA solver drives."""
    tab = window.teleop
    qtbot.waitUntil(lambda: tab.state is not None and tab.solver.findText("ga-restart") >= 0, timeout=GUI_WAIT)
    tab.solver.setCurrentText("ga-restart")
    tab.solver.activated.emit(tab.solver.currentIndex())
    qtbot.waitUntil(lambda: tab.state.solver == "ga-restart" and tab.ga_task.isEnabled(), timeout=GUI_WAIT)
    assert tab.ga_task.currentText() == "published cost"
    tab.ga_task.setCurrentText("tool down, height first")
    tab.ga_task.activated.emit(tab.ga_task.currentIndex())
    qtbot.waitUntil(lambda: tab.state.ga_weights == [1.0, 1.0, 4.0] and tab.state.ga_axis == [0.0, 0.0, -1.0],
                    timeout=GUI_WAIT)  # fmt: skip
    tab.link.send("set_ga_task", weights=[2.0, 1.0, 1.0])  # another client's task
    qtbot.waitUntil(lambda: tab.ga_task.currentText() == "custom: weights (2, 1, 1)", timeout=GUI_WAIT)
    tab.solver.setCurrentText("jacobian")
    tab.solver.activated.emit(tab.solver.currentIndex())
    qtbot.waitUntil(lambda: tab.state.solver == "jacobian" and not tab.ga_task.isEnabled(), timeout=GUI_WAIT)
    assert tab.state.ga_weights == [2.0, 1.0, 1.0]  # kept for the GA


def test_the_teleop_page_names_the_nearest_hazard_and_shows_when_it_slows(qtbot, window):
    """Issue 32, item 5: the hazard and its distance on the page, amber while it slows the command."""
    from app.net.snapshots import HazardState

    tab = window.teleop
    qtbot.waitUntil(lambda: tab.state is not None, timeout=GUI_WAIT)
    assert tab.hazard.text() in ("none near", "–") or "clearance" in tab.hazard.text() or "σ" in tab.hazard.text()
    near = HazardState(kind="collision", name="link 2 ↔ floor", value=0.034, share=0.3, slowed=True,
                       text="link 2 ↔ floor: clearance 34 mm")  # fmt: skip
    tab._sync_controls(replace(tab.state, hazard=near))
    assert tab.hazard.text() == "link 2 ↔ floor: clearance 34 mm — slowing"
    assert "b06000" in tab.hazard.styleSheet()
    tab._sync_controls(replace(tab.state, hazard=HazardState()))
    assert tab.hazard.text() == "none near" and tab.hazard.styleSheet() == ""


def test_the_crane_and_lab_pages_name_the_range_edge_near():
    """Issue 32, item 5: the crane-head page's readout (and the lab's, the same way) names the edge of the TCP
    target's range the stick is slowed for, and its distance."""
    from types import SimpleNamespace

    from app.net.snapshots import HazardState
    from ui.marine_tab import CraneHeadTab

    near = HazardState(kind="workspace", name="tac range x", value=0.12, share=0.3, slowed=True,
                       text="tac range x: 0.12 m to its edge")  # fmt: skip
    line = CraneHeadTab._hazard_line(SimpleNamespace(hazard=near))
    assert "tac range x: 0.12 m to its edge — slowing" in line and "#b06000" in line
    assert CraneHeadTab._hazard_line(SimpleNamespace(hazard=HazardState())) == ""


def test_csv_logger_in_the_gui(qtbot, window, tmp_path):
    path = tmp_path / "log.csv"
    window.teleop.log_path.setText(str(path))
    window.teleop.log_duration.setValue(0.0)  # until stopped
    window.teleop.start_logger()
    qtbot.waitUntil(lambda: window.teleop.logger is not None and window.teleop.logger.rows >= 10, timeout=GUI_WAIT)
    window.teleop.stop_logger()
    with open(path, encoding="utf-8") as f:
        rows = list(csv.reader(f))
    assert rows[0][:4] == ["t", "q_q1", "q_q2", "q_q3"] and len(rows) >= 11


def test_csv_logger_rows_and_closed_mid_run(tmp_path):
    state = TeleopSnapshot(
        q=[0.1, 0.2],
        qdot=[0, 0],
        tool=[1, 2, 3],
        target=[1, 2, 3],
        signal=[0, 0, 0],
        solver_error=None,
        solver_time=0.001,
        flags=InputFlags(stale_input=False, enabled=True),
    )
    names = ["a", "b"]  # from the engine's description
    log = StateCsvLogger(tmp_path / "a.csv", ["q", "tool", "solver"], duration=0.1, joint_names=names)
    written = 0
    for k in range(20):
        if log.add(replace(state, t=k * 0.02)):
            written += 1
    assert written == 6 and log.done  # t = 0 .. 0.10 s, then the duration ended the file
    with open(tmp_path / "a.csv", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    assert len(rows) == 7 and rows[0] == [
        "t",
        "q_a",
        "q_b",
        "tool_x",
        "tool_y",
        "tool_z",
        "solver_error",
        "solver_time",
    ]
    # a logger abandoned mid-run (no close) has flushed every row written so far
    log2 = StateCsvLogger(tmp_path / "b.csv", ["q"], joint_names=names)
    for k in range(5):
        log2.add(replace(state, t=k * 0.02))
    with open(tmp_path / "b.csv", encoding="utf-8") as f:
        assert len(list(csv.reader(f))) == 6
    with pytest.raises(ValueError, match="unknown or no signals"):
        StateCsvLogger(tmp_path / "c.csv", ["nope"])


def test_lost_engine_connection_is_reported(qtbot, engine, tmp_path):
    link = EngineLink(engine.url, lost_after=0.5)
    win = MainWindow(link, settings=QSettings(str(tmp_path / "s.ini"), QSettings.IniFormat), dialogs=False)
    qtbot.addWidget(win)
    qtbot.waitUntil(lambda: win.teleop.state is not None, timeout=GUI_WAIT)
    engine.stop()
    qtbot.waitUntil(lambda: any(t == "Engine connection lost" for t, _ in win.messages), timeout=GUI_WAIT)
    # the light follows at the status area's next refresh (a loaded CI run read it between the two)
    qtbot.waitUntil(lambda: win.status.lights["engine"].state == "error", timeout=GUI_WAIT)
    win.close()


def test_unplugged_joystick_is_reported(qtbot, window):
    from app.teleop.virtual import VirtualJoystick

    vj = VirtualJoystick(n_axes=4, n_buttons=8)
    try:
        qtbot.waitUntil(lambda: window.teleop.device.count() == 2, timeout=GUI_WAIT)
        window.teleop.device.setCurrentIndex(1)
        window.teleop.device.activated.emit(1)
        vj.set_button(0, True)
        qtbot.waitUntil(lambda: window.teleop.state.flags.device_name != "on-screen stick / keyboard", timeout=GUI_WAIT)
    finally:
        vj.detach()
    qtbot.waitUntil(lambda: "unplugged" in window.status.log_view.toPlainText(), timeout=GUI_WAIT)
    # the GUI falls back to the on-screen stick, which nobody holds: the deadman is off and the robot holds
    qtbot.waitUntil(lambda: window.teleop.inputs.choice == "on-screen stick / keyboard", timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: not window.teleop.state.flags.enabled, timeout=GUI_WAIT)
    qtbot.wait(300)
    p = np.array(window.teleop.state.tool)
    qtbot.wait(300)
    np.testing.assert_allclose(window.teleop.state.tool, p, atol=1e-6)


# ------------------------------------------------------------------ OpenGL under Xvfb
GL_SCRIPT = r"""
import sys, numpy as np
from PyQt5.QtWidgets import QApplication
app = QApplication(sys.argv[:1])
from ui.glprobe import gl_available
if not gl_available():
    sys.exit(77)
from ui.widgets.view3d import RobotView3D, make_robot_view
from app.engine.session import Session
from app.net.snapshots import InputFlags, TeleopSnapshot
view = make_robot_view()
assert isinstance(view, RobotView3D), type(view)
view.resize(400, 300); view.show(); app.processEvents()
view.update_state(Session(robot_name="offshore_crane").snapshot()); app.processEvents()
img = view.view.renderToArray((400, 300))
lit = (img[..., :3].max(axis=2) > 100).mean()
print("lit fraction", lit)
sys.exit(0 if 0.001 < lit < 0.9 else 1)
"""


@pytest.mark.gl
def test_gl_view_renders_under_xvfb(tmp_path):
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed")
    display = ":93"
    xvfb = subprocess.Popen(
        ["Xvfb", display, "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        time.sleep(1.0)
        env = {**os.environ, "DISPLAY": display, "QT_QPA_PLATFORM": "xcb"}
        res = subprocess.run(
            [sys.executable, "-c", GL_SCRIPT], env=env, capture_output=True, text=True, timeout=120, cwd=str(tmp_path)
        )
    finally:
        xvfb.terminate()
        xvfb.wait(timeout=10)
    if res.returncode == 77:
        pytest.skip("no OpenGL context under Xvfb here")
    assert res.returncode == 0, res.stdout + res.stderr
    assert "lit fraction" in res.stdout


def test_arrow_keys_drive_the_tool(qtbot, window):
    from PyQt5.QtCore import Qt

    window.activateWindow()
    window.tabs.setFocus()
    plots = window.teleop.plots
    qtbot.waitUntil(lambda: plots.ring is not None and plots.ring.n > 5, timeout=GUI_WAIT)
    y0 = window.teleop.state.tool[1]
    qtbot.wait(150)  # neutral and released first
    qtbot.keyPress(window.tabs, Qt.Key_Shift)
    qtbot.waitUntil(lambda: window.teleop.state.flags.armed, timeout=GUI_WAIT)
    qtbot.keyPress(window.tabs, Qt.Key_Up)
    qtbot.waitUntil(lambda: window.teleop.state.tool[1] - y0 > 0.05, timeout=GUI_WAIT)
    qtbot.keyRelease(window.tabs, Qt.Key_Up)
    qtbot.keyRelease(window.tabs, Qt.Key_Shift)
    qtbot.waitUntil(lambda: not window.teleop.state.flags.enabled, timeout=GUI_WAIT)


def test_picker_lists_only_what_the_engine_drives(qtbot, window):
    """The robot combo comes from the engine's description: serial arms only, each with its solvers."""
    qtbot.waitUntil(lambda: window.teleop.robot.count() > 0, timeout=GUI_WAIT)
    names = {window.teleop.robot.itemText(i) for i in range(window.teleop.robot.count())}
    assert {"scara", "comau_smart5_3dof", "offshore_crane"} <= names
    assert not names & {"em8000", "em1500", "tac_delta_head"}  # a Stewart platform and the Delta head are refused
    solvers = {window.teleop.solver.itemText(i) for i in range(window.teleop.solver.count())}
    assert solvers == {"ga", "ga-restart", "jacobian", "analytic"}  # the Comau 3-DOF has a closed form
    window.teleop.robot.setCurrentText("scara")
    window.teleop.robot.activated.emit(window.teleop.robot.currentIndex())
    qtbot.waitUntil(lambda: window.teleop.desc is not None and window.teleop.desc.robot == "scara", timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: window.teleop.solver.findText("analytic") < 0, timeout=GUI_WAIT)  # no closed form


def test_custom_robot_opened_by_path_works_in_analysis(qtbot, window, tmp_path):
    """Issue 15: open a robot XML by path, then Analysis: the study runs in the engine on that robot."""
    from app.models.registry import resolve

    text = resolve("scara").read_text(encoding="utf-8").replace('name="scara"', 'name="custom_arm"', 1)
    path = tmp_path / "custom_arm.xml"
    path.write_text(text, encoding="utf-8")
    window.teleop.load_robot_file(str(path))
    qtbot.waitUntil(lambda: window.teleop.state.robot == "custom_arm", timeout=GUI_WAIT)
    tab = window.analysis
    window.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: "custom_arm" in tab.robot_label.text(), timeout=GUI_WAIT)
    assert window.teleop.robot.currentText() == "custom_arm"
    tab.grid.setValue(3)
    tab.solver.setCurrentText("jacobian")
    tab.start("distribution")
    qtbot.waitUntil(lambda: tab.result is not None, timeout=120_000)
    assert tab.result.robot == "custom_arm" and len(tab.result.error) == 27
    assert tab.progress.value() == tab.progress.maximum() == 27
    assert "custom_arm / jacobian: 27 targets" in tab.summary.text()
    assert tab.colorbar is not None and tab.export_csv.isEnabled()
    assert not any(t == "Analysis failed" for t, _ in window.messages)
    # another robot, then the custom one chosen again in the combo: the GUI sends its text again
    combo = window.teleop.robot
    for name in ("scara", "custom_arm"):
        combo.setCurrentText(name)
        combo.activated.emit(combo.currentIndex())
        qtbot.waitUntil(lambda n=name: window.teleop.state.robot == n, timeout=GUI_WAIT)
    tab.start("tracking")
    qtbot.waitUntil(lambda: hasattr(tab.result, "t"), timeout=120_000)
    assert tab.result.robot == "custom_arm"
    assert not any("not loaded" in t for t, _ in window.messages)
