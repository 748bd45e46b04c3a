"""Make docs/screenshots/*.png by running the real app (engine process + GUI) under Xvfb.

    xvfb-run -s "-screen 0 1600x1000x24" .venv/bin/python scripts/screenshots.py

Drives the on-screen stick for a few seconds so the plots and the view have something to show.
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

OUT = ROOT / "docs" / "screenshots"


def pump(app: QApplication, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents()
        time.sleep(0.005)


def main() -> int:
    app = QApplication(sys.argv[:1])
    settings = QSettings(str(OUT / "screenshots.ini"), QSettings.IniFormat)
    engine = EngineProcess(robot="knuckle_boom_crane", solver="jacobian", mode="velocity")
    link = EngineLink(engine.url)
    tac_engines = []

    def marine_link():
        tac_engines.append(EngineProcess(plant="tac"))
        return EngineLink(tac_engines[-1].url, name="screenshots-tac")

    win = MainWindow(link, engine=engine, settings=settings, dialogs=False, marine_link_factory=marine_link)
    win.resize(1600, 1000)
    win.show()
    pump(app, 1.5)
    stick = win.teleop.stick
    for x, y, z, secs in ((0.8, 0.0, 0.0, 2.0), (0.0, 0.8, 0.4, 2.0), (-0.6, -0.5, -0.5, 2.0)):
        stick.pad.set_position(x, y, True)
        stick.z.setValue(int(100 * z))
        pump(app, secs)
    stick.pad.set_position(0.0, 0.0, False)
    stick.z.setValue(0)
    pump(app, 0.8)
    OUT.mkdir(parents=True, exist_ok=True)
    win.grab().save(str(OUT / "teleop.png"))
    win.status.stop.click()
    pump(app, 0.6)
    win.grab().save(str(OUT / "estop.png"))
    win.status.reset.click()
    win.tabs.setCurrentWidget(win.analysis)
    win.analysis.grid.setValue(6)
    win.analysis.solver.setCurrentText("jacobian")
    win.analysis.start("distribution")
    while win.analysis.worker is not None:
        pump(app, 0.2)
    pump(app, 0.5)
    win.grab().save(str(OUT / "analysis.png"))
    win.tabs.setCurrentWidget(win.crane_head)
    pump(app, 25.0)  # the crane-head scene: Hs 3 m beam sea, head compensating
    win.grab().save(str(OUT / "crane_head.png"))
    print(f"view: {win.teleop.view.kind}; plots redrawn {win.teleop.plots.frames_drawn} times")
    print(f"crane-head scene view: {win.crane_head.scene.kind}")
    win.close()
    for e in tac_engines:
        e.stop()
    (OUT / "screenshots.ini").unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
