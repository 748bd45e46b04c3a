"""Make docs/screenshots/lab_load_swing.png: the Motion-Lab's Load swing sub-tab (issue 16, item 4) against a
lab engine in this process (so the load can be kicked): VVMC on at 1.5 s, a 4° / 1.5° swing given to the load
at 4 s (applied at the start of an engine tick, then the estimator's Reset), anti-swing activated at 6 s,
grabbed at 16 s.  Run under a display (Xvfb): ``DISPLAY=:78 .venv/bin/python scripts/screenshot_load_swing.py``."""

from __future__ import annotations

import math
import sys
import threading
from pathlib import Path

from PyQt5.QtCore import QTimer
from PyQt5.QtWidgets import QApplication

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.engine.lab_session import LabSession  # noqa: E402
from app.engine.server import EngineServer  # noqa: E402
from ui.lab_tab import MotionLabTab  # noqa: E402
from ui.link import EngineLink  # noqa: E402

OUT = ROOT / "docs" / "screenshots" / "lab_load_swing.png"


def main() -> int:
    app = QApplication(sys.argv[:1])
    ses = LabSession()
    srv = EngineServer(ses, bind="tcp://127.0.0.1:0", rate=50, publish_rate=25)
    threading.Thread(target=srv.run, kwargs={"duration": 60.0}, daemon=True).start()
    kicks: list[tuple[float, float]] = []
    tick = ses.tick

    def kicked_tick(*args, **kw):  # the kick lands between two steps, in the engine's thread
        if kicks:
            a, b = kicks.pop()
            pd = ses.lab.pendulum
            pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot = math.radians(a), math.radians(b), 0.0, 0.0
            ses.lab_antisway("reset")
        return tick(*args, **kw)

    ses.tick = kicked_tick
    tab = MotionLabTab(link_factory=lambda: EngineLink(srv.url, name="screenshot-lab"), use_gl=False)
    tab.resize(1400, 900)
    tab.show()
    tab.connect_engine()
    tab.tabs.setCurrentIndex(tab.tabs.count() - 1)

    def grab() -> None:
        tab.grab().save(str(OUT))
        print(f"wrote {OUT.relative_to(ROOT)}")
        tab.close_link()
        app.quit()

    QTimer.singleShot(1500, tab.comau.vvmc.click)
    QTimer.singleShot(4000, lambda: kicks.append((4.0, 1.5)))
    QTimer.singleShot(6000, tab.swing.swing_buttons["activate"].click)
    QTimer.singleShot(16000, grab)
    app.exec_()
    srv.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
