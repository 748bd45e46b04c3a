"""The GUI tests' rig: the operator window against engines, an image's pixels, and scripts on an X screen.

Two kinds of GUI test share it:

* pytest-qt tests (offscreen) build the window with :func:`main_window` against engines from the ``serve``
  fixture (tests/conftest.py);
* tests of what an X server shows (Xvfb + Mesa OpenGL, real X input) run a script in a process of its own
  with :func:`run_under_xvfb`; the script imports its event loop helpers from here (:func:`gl_app`,
  :func:`pump`, :func:`wait`, :func:`screen_rgb`, :func:`open_window`) and prints one ``RESULT {json}`` line.

Qt is imported inside the functions: importing this module needs neither PyQt5 nor a display.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def image_rgb(image) -> np.ndarray:
    """A QImage as an (h, w, 3) uint8 array."""
    from PyQt5.QtGui import QImage

    img = image.convertToFormat(QImage.Format_RGB888)
    w, h = img.width(), img.height()
    ptr = img.constBits()
    ptr.setsize(img.bytesPerLine() * h)
    return np.frombuffer(ptr, np.uint8).reshape(h, img.bytesPerLine())[:, : 3 * w].reshape(h, w, 3).copy()


def color_px(widget, color, tol: int = 40) -> int:
    """Pixels of ``widget`` (as it paints) within ``tol`` in every channel of ``color``: (r, g, b), or a
    style sheet's ``#rrggbb`` or ``#rgb``."""
    if isinstance(color, str):
        h = color.lstrip("#")
        h = "".join(c * 2 for c in h) if len(h) == 3 else h
        color = [int(h[i : i + 2], 16) for i in (0, 2, 4)]
    a = image_rgb(widget.grab().toImage()).astype(int)
    return int((np.abs(a - np.array(color)).max(axis=2) <= tol).sum())


# ---------------------------------------------------------------------------------------------- the window
def arm_stick(qtbot, stick, flags) -> None:
    """The operator's arming gesture on an on-screen stick: neutral and released, then hold Shift, until the
    engine's ``flags()`` say armed."""
    from PyQt5.QtCore import Qt

    from tests.helpers import GUI_WAIT

    stick.release_all()
    qtbot.wait(150)
    stick.key(Qt.Key_Shift, True)
    try:
        qtbot.waitUntil(lambda: flags().armed, timeout=GUI_WAIT)
    except Exception:
        raise AssertionError(f"not armed: engine flags {flags()}, GUI stick {stick.values()}") from None


def drive_until(qtbot, stick, flags, deflect, until) -> None:
    """Arm ``stick``, call ``deflect()`` (keys or pad), and wait until ``until()``.

    The engine disarms when no input reaches it for 200 ms (stale halt) and when the GUI's link, finding it
    silent for 0.5 s, connects anew; a CI runner at load 4 on two cores starved a test that long (CI,
    2026-11-29: the engine disarmed, the held key kept the stick off centre, and the wait ran out; an engine
    stopped for 0.6 s gives the same).  A disarm is the safe answer, so the operator's is taken: centre, arm
    again, deflect again, up to five times.  Any other way of not getting there fails."""
    from tests.helpers import GUI_WAIT

    reasons = []
    for _attempt in range(5):
        arm_stick(qtbot, stick, flags)
        deflect()
        try:
            qtbot.waitUntil(lambda: until() or not flags().armed, timeout=GUI_WAIT)
        except Exception:
            raise AssertionError(f"not driven: engine flags {flags()}, GUI stick {stick.values()}") from None
        if until():
            return
        reasons.append(flags().input_reason)
    raise AssertionError(f"disarmed five times before getting there: {reasons}")


def main_window(teleop_url: str, settings_path, use_gl: bool | None = False, **kw):
    """The operator window on the teleop engine at ``teleop_url``, its remembered choices in the INI file
    ``settings_path``, errors shown without dialogs, the 2D views unless ``use_gl`` is None (GL where there
    is) or True.  The other keywords go to MainWindow (the scene tabs' link factories: :func:`scene_link`)."""
    from PyQt5.QtCore import QSettings

    from ui.link import EngineLink
    from ui.main_window import MainWindow

    settings = QSettings(str(settings_path), QSettings.IniFormat)
    return MainWindow(EngineLink(teleop_url), settings=settings, dialogs=False, use_gl=use_gl, **kw)


def scene_link(srv, kind: str):
    """A link factory for a scene tab (``kind`` "tac" or "lab"): each call links to the engine ``srv``."""
    from ui.link import EngineLink

    return lambda: EngineLink(srv.url, name=f"gui-{kind}")


def scene_engines(start, duration: float = 120.0, lab_session=None) -> dict:
    """A crane-head and a Motion-Lab engine (``lab_session``, a fresh LabSession by default), each at 50 Hz
    publishing 25 Hz for at most ``duration`` [s], started by ``start`` (the ``serve`` fixture, or
    tests.helpers.start_engine in a script); returns the MainWindow keywords that link the tabs to them."""
    from app.engine.lab_session import LabSession
    from app.engine.tac_session import TacSession

    tac, _ = start(TacSession(), rate=50, publish_rate=25, duration=duration)
    lab, _ = start(lab_session or LabSession(), rate=50, publish_rate=25, duration=duration)
    return {"marine_link_factory": scene_link(tac, "tac"), "lab_link_factory": scene_link(lab, "lab")}


# ------------------------------------------------------------------------------- scripts on an X screen
@contextmanager
def xvfb(screen: str = "1280x1024"):
    """An Xvfb server (``screen`` W×H, 24-bit colour, no TCP) for the with-block; yields its display number,
    '' when it did not start.  Xvfb picks a free number and writes it once it is ready (-displayfd)."""
    r_fd, w_fd = os.pipe()
    proc = subprocess.Popen(
        ["Xvfb", "-displayfd", str(w_fd), "-screen", "0", f"{screen}x24", "-nolisten", "tcp"],
        pass_fds=(w_fd,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(w_fd)
    try:
        with os.fdopen(r_fd) as fh:
            number = fh.readline().strip()
        yield number
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def run_under_xvfb(script: str, tmp_path, screen: str = "1280x1024", timeout: float = 180) -> dict:
    """Run ``script`` (Python source) on an Xvfb screen with Qt's X plugin, as a process of its own with the
    checkout first on the path and ``tmp_path / "img"`` as its argument (a prefix for pictures it saves);
    returns the JSON of its ``RESULT`` line.  Skips without Xvfb, or when the script exits with 77 (no
    OpenGL context there: :func:`gl_app`)."""
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed")
    with xvfb(screen) as number:
        if not number:
            pytest.skip("Xvfb did not start")
        env = {**os.environ, "DISPLAY": f":{number}", "QT_QPA_PLATFORM": "xcb", "PYTHONPATH": str(ROOT)}
        res = subprocess.run(
            [sys.executable, "-c", script, str(tmp_path / "img")],
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=ROOT,
        )
    if res.returncode == 77:
        pytest.skip("no OpenGL context under Xvfb here")
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    line = next(x for x in res.stdout.splitlines() if x.startswith("RESULT "))
    return json.loads(line[len("RESULT ") :])


def gl_app():
    """A script's QApplication with the GL views' contexts shared; the script exits 77 (skipped) when this
    X server gives no OpenGL context."""
    from PyQt5.QtWidgets import QApplication

    from ui.glprobe import gl_available, share_gl_contexts

    share_gl_contexts()  # before the application object exists
    app = QApplication(sys.argv[:1])
    if not gl_available():
        sys.exit(77)
    return app


def pump(s: float) -> None:
    """Process the application's events for ``s`` seconds."""
    from PyQt5.QtWidgets import QApplication

    app = QApplication.instance()
    end = time.monotonic() + s
    while time.monotonic() < end:
        app.processEvents()
        time.sleep(0.005)


def wait(pred, s: float = 60.0) -> bool:
    """Process events until ``pred()`` holds (True) or ``s`` seconds have gone (False)."""
    end = time.monotonic() + s
    while time.monotonic() < end:
        if pred():
            return True
        pump(0.05)
    return False


def screen_rgb() -> np.ndarray:
    """What the X screen shows, as an (h, w, 3) uint8 array."""
    from PyQt5.QtGui import QGuiApplication

    return image_rgb(QGuiApplication.primaryScreen().grabWindow(0).toImage())


def open_window(teleop_url: str, use_gl: bool | None = None, **kw):
    """A script's operator window (:func:`main_window`; settings in a throw-away file, GL views where there
    is OpenGL unless ``use_gl`` says), shown, raised and made active (Xvfb has no window manager to do it),
    once the teleop engine's first state has come."""
    win = main_window(teleop_url, tempfile.mktemp(suffix=".ini"), use_gl=use_gl, **kw)
    win.show()
    win.raise_()
    win.activateWindow()
    assert wait(lambda: win.teleop.state is not None), "no state"
    return win
