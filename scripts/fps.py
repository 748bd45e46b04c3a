"""Frame rate of the operator window: the teleop tab's frames per second with the 3D view, the 2D view or none.

    python scripts/fps.py                      # starts its own Xvfb at 1600×1000 (software OpenGL, Mesa)
    python scripts/fps.py --view 2d --json     # the same window with the 2D fallback view

One *frame* is one redraw of the teleop tab's live plots (``LivePlots.frames_drawn``, a 30/s timer
that also refreshes the machine view and the bars); when the window's paint work does not fit in the
33 ms the timer asks for, frames are late and the rate drops below 30.  ``gl_paints`` counts the
OpenGL view's own paints over the same time, so a view that stopped drawing is seen.  The arm
moves all the time (the on-screen stick sweeps in a circle with ENABLE held), the engine runs in this
process's thread at 500 Hz and publishes at 50 Hz, as in the GUI tests.

Prints one line per run (or JSON with ``--json``): fps, GL paints per second, and the machine.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _xvfb(size: str) -> subprocess.Popen | None:
    """A private Xvfb display when none is set; None if this process already has one."""
    if os.environ.get("DISPLAY"):
        return None
    exe = shutil.which("Xvfb")
    if exe is None:
        raise SystemExit("fps: no DISPLAY and no Xvfb on PATH (apt install xvfb)")
    for n in range(90, 140):
        if not Path(f"/tmp/.X11-unix/X{n}").exists() and not Path(f"/tmp/.X{n}-lock").exists():
            break
    proc = subprocess.Popen([exe, f":{n}", "-screen", "0", f"{size}x24", "-nolisten", "tcp"], stderr=subprocess.DEVNULL)
    for _ in range(100):
        if Path(f"/tmp/.X11-unix/X{n}").exists():
            break
        time.sleep(0.05)
    os.environ["DISPLAY"] = f":{n}"
    return proc


def measure(view: str, width: int, height: int, seconds: float, warmup: float) -> dict:
    os.environ["QT_QPA_PLATFORM"] = "xcb"
    if view != "gl":
        os.environ["BOSUN_NO_GL"] = "1"
    import threading

    from PyQt5.QtCore import QSettings, Qt
    from PyQt5.QtWidgets import QApplication

    from ui.glprobe import share_gl_contexts

    share_gl_contexts()
    app = QApplication.instance() or QApplication(sys.argv[:1])

    from app.engine.server import EngineServer
    from app.engine.session import Session
    from ui.link import EngineLink
    from ui.main_window import MainWindow

    srv = EngineServer(Session(robot_name="comau_smart5_3dof"), bind="tcp://127.0.0.1:0", rate=500, publish_rate=50)
    th = threading.Thread(target=srv.run, kwargs={"duration": seconds + warmup + 60}, daemon=True)
    th.start()
    settings = QSettings(str(Path("/tmp") / f"bosun-fps-{os.getpid()}.ini"), QSettings.IniFormat)
    win = MainWindow(EngineLink(srv.url), settings=settings, dialogs=False)
    win.show()
    win.setGeometry(0, 0, width, height)
    tab = win.teleop
    if view == "none":
        tab.view.hide()

    def pump(s: float) -> None:
        end = time.monotonic() + s
        while time.monotonic() < end:
            app.processEvents()
            time.sleep(0.001)

    deadline = time.monotonic() + 30
    while tab.state is None and time.monotonic() < deadline:
        pump(0.05)
    if tab.state is None:
        raise SystemExit("fps: the engine sent no state in 30 s")
    stick = tab.stick
    stick.release_all()
    pump(0.2)
    stick.key(Qt.Key_Shift, True)  # the arming gesture: centred, then ENABLE held
    gl_view = getattr(tab.view, "machines", None)
    paints = [0]
    if gl_view is not None and view == "gl":
        inner = gl_view.view
        orig = inner.paintGL

        def counted(*a, **k):
            paints[0] += 1
            return orig(*a, **k)

        inner.paintGL = counted

    def sweep(t: float) -> None:
        stick.pad.set_position(0.8 * math.cos(0.6 * t), 0.8 * math.sin(0.6 * t), True)

    t0 = time.monotonic()
    end = t0 + warmup
    while time.monotonic() < end:
        sweep(time.monotonic() - t0)
        pump(0.02)
    f0, p0, m0 = tab.plots.frames_drawn, paints[0], time.monotonic()
    end = m0 + seconds
    while time.monotonic() < end:
        sweep(time.monotonic() - t0)
        pump(0.02)
    dt = time.monotonic() - m0
    frames, gl_paints = tab.plots.frames_drawn - f0, paints[0] - p0
    moved = tab.state is not None and tab.state.flags.enabled
    stick.pad.set_position(0.0, 0.0, False)
    stick.key(Qt.Key_Shift, False)
    pump(0.2)
    renderer = ""
    if gl_view is not None and view == "gl":
        from OpenGL import GL

        gl_view.view.makeCurrent()
        renderer = (GL.glGetString(GL.GL_RENDERER) or b"").decode(errors="replace")
        gl_view.view.doneCurrent()
    win.close()
    srv.stop()
    th.join(timeout=5)
    srv.close()

    return {
        "view": view,
        "view_class": type(tab.view).__name__,
        "size": f"{width}x{height}",
        "fps": round(frames / dt, 1),
        "gl_paints_per_s": round(gl_paints / dt, 1) if view == "gl" else None,
        "enabled": bool(moved),
        "seconds": round(dt, 1),
        "renderer": renderer,
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, {platform.system()}",
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--view", choices=("gl", "2d", "none"), default="gl")
    ap.add_argument("--size", default="1600x1000", help="window size WxH (the Xvfb screen gets the same)")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--warmup", type=float, default=3.0)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        print(f"fps: --size: expected WxH such as 1600x1000, got {args.size!r}", file=sys.stderr)
        return 2
    xvfb = _xvfb(f"{width}x{height}")
    result = measure(args.view, width, height, args.seconds, args.warmup)
    if args.json:
        print(json.dumps(result))
    else:
        gl = f", GL view {result['gl_paints_per_s']} paints/s" if result["gl_paints_per_s"] is not None else ""
        r = result
        print(f"{r['view']} ({r['view_class']}) at {r['size']}: {r['fps']} fps{gl}; {r['renderer']}")
    sys.stdout.flush()
    if xvfb is not None:  # Qt still holds the display: leave without its teardown (an X I/O error otherwise)
        xvfb.terminate()
        os._exit(0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
