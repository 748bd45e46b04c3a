"""Make docs/screenshots/*.png by running the real app (engine process + GUI) under Xvfb.

    xvfb-run -s "-screen 0 1280x800x24" .venv/bin/python scripts/screenshots.py

Drives the on-screen stick for a few seconds (the arming gesture first: stick centred, then enable
held with Shift) so the plots and the view have something to show.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from PyQt5.QtCore import QSettings
from PyQt5.QtWidgets import QApplication

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ui.engine_process import EngineProcess  # noqa: E402
from ui.link import EngineLink  # noqa: E402
from ui.main_window import MainWindow  # noqa: E402
from ui.widgets.glwindow import grab_window  # noqa: E402

OUT = ROOT / "docs" / "screenshots"


def pump(app: QApplication, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents()
        time.sleep(0.005)


def main() -> int:
    from ui.glprobe import share_gl_contexts

    share_gl_contexts()  # before the QApplication: every GL view shares shaders
    app = QApplication(sys.argv[:1])
    settings = QSettings(str(OUT / "screenshots.ini"), QSettings.IniFormat)
    engine = EngineProcess(robot="knuckle_boom_crane", solver="jacobian", mode="velocity")
    link = EngineLink(engine.url, secret=engine.secret)
    tac_engines = []

    def marine_link():
        tac_engines.append(EngineProcess(plant="tac"))
        return EngineLink(tac_engines[-1].url, name="screenshots-tac", secret=tac_engines[-1].secret)

    def lab_link():
        tac_engines.append(EngineProcess(plant="lab"))
        return EngineLink(tac_engines[-1].url, name="screenshots-lab", secret=tac_engines[-1].secret)

    win = MainWindow(
        link,
        engine=engine,
        settings=settings,
        dialogs=False,
        marine_link_factory=marine_link,
        lab_link_factory=lab_link,
    )
    win.show()  # the window sizes itself to the screen (at most 1280 × 800)
    pump(app, 1.5)
    OUT.mkdir(parents=True, exist_ok=True)
    only_lab = "--lab-only" in sys.argv
    if not only_lab:
        other_tabs(app, win)
    motion_lab(app, win)
    win.close()
    for e in tac_engines:
        e.stop()
    (OUT / "screenshots.ini").unlink(missing_ok=True)
    return 0


def motion_lab(app: QApplication, win: MainWindow) -> None:
    """Both platforms raised and engaged (EM8000 waves, EM1500 a sine), VVMC on."""
    lab = win.motion_lab
    win.tabs.setCurrentWidget(lab)
    pump(app, 1.0)
    lab.status.log_path.setText("/home/operator/lab runs/bosun_lab_log.csv")  # not this checkout's path
    for p in lab.platforms.values():
        p.buttons["neutral"].click()
    pump(app, 12.0)
    em8000, em1500 = lab.platforms["em8000"], lab.platforms["em1500"]
    em8000.source.setCurrentIndex(1)
    em8000.sim_hs.setValue(2.5)
    em8000.apply.click()
    em1500.source.setCurrentIndex(0)
    for i, (a, f) in enumerate(((0.0, 0.1), (0.05, 0.12), (0.12, 0.1), (3.0, 0.08), (2.0, 0.11), (0.0, 0.1))):
        em1500.gen[i][0].setValue(a)
        em1500.gen[i][1].setValue(f)
    em1500.apply.click()
    pump(app, 1.0)
    em8000.buttons["engage"].click()
    em1500.buttons["engage"].click()
    pump(app, 3.0)
    lab.comau.vvmc.click()
    pump(app, 30.0)
    lab.tabs.setCurrentIndex(0)
    pump(app, 0.5)
    grab_window(win).save(str(OUT / "lab_platform.png"))
    lab.tabs.setCurrentIndex(2)
    pump(app, 0.5)
    grab_window(win).save(str(OUT / "lab_control.png"))
    lab.tabs.setCurrentIndex(3)
    pump(app, 1.0)
    grab_window(win).save(str(OUT / "lab_scene.png"))
    print(f"Motion-Lab scene view: {lab.scene.kind}")


def other_tabs(app: QApplication, win: MainWindow) -> None:
    from PyQt5.QtCore import Qt

    stick = win.teleop.stick
    stick.release_all()
    pump(app, 0.3)
    stick.key(Qt.Key_Shift, True)  # enable, pressed with the stick at neutral: the engine arms
    pump(app, 0.3)
    for x, y, z, secs in ((0.8, 0.0, 0.0, 2.0), (0.0, 0.8, 0.4, 2.0), (-0.6, -0.5, -0.5, 2.0)):
        stick.pad.set_position(x, y, True)
        stick.z.setValue(int(100 * z))
        pump(app, secs)
    stick.pad.set_position(0.0, 0.0, False)
    stick.z.setValue(0)
    stick.key(Qt.Key_Shift, False)
    pump(app, 0.8)
    grab_window(win).save(str(OUT / "teleop.png"))
    win.status.stop.click()
    pump(app, 0.6)
    grab_window(win).save(str(OUT / "estop.png"))
    win.status.reset.click()
    win.tabs.setCurrentWidget(win.analysis)
    win.analysis.grid.setValue(6)
    win.analysis.solver.setCurrentText("jacobian")
    win.analysis.start("distribution")
    deadline = time.monotonic() + 300
    while win.analysis.running and time.monotonic() < deadline:  # the study runs in the engine
        pump(app, 0.2)
    pump(app, 0.5)
    grab_window(win).save(str(OUT / "analysis.png"))
    win.tabs.setCurrentWidget(win.crane_head)
    pump(app, 10.0)  # the crane-head scene: Hs 3 m beam sea, head compensating
    tab = win.crane_head
    tab.mode.setCurrentText("cooperative")
    tab.mode.activated.emit(tab.mode.currentIndex())  # the crane joins in: the TCP may go 5 m
    pump(app, 2.0)
    hook = tab.stick
    hook.release_all()
    pump(app, 0.3)
    hook.key(Qt.Key_Shift, True)  # armed
    pump(app, 0.3)
    hook.pad.set_position(0.3, 0.0, True)  # the load forward over the platform, gently (issue 30, item 5)
    pump(app, 40.0)
    hook.pad.set_position(0.0, 0.0, True)
    hook.w.setValue(30)  # lowered towards the deck
    pump(app, 5.0)
    hook.w.setValue(0)
    pump(app, 2.0)
    hook.release_all()
    pump(app, 1.0)
    grab_window(win).save(str(OUT / "crane_head.png"))
    print(f"view: {win.teleop.view.kind}; plots redrawn {win.teleop.plots.frames_drawn} times")
    print(f"crane-head scene view: {win.crane_head.scene.kind}")


if __name__ == "__main__":
    raise SystemExit(main())
