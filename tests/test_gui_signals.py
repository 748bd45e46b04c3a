"""SIGTERM/SIGINT close the GUI also when they arrive while Qt is calling Python (H53).

Qt calls Python for resize and paint events; an exception raised there by a signal handler is printed
and lost.  The GUI therefore only records a stop in its handlers (:func:`ui.app.stop_requests`) and a
timer closes the window (:func:`ui.app.close_when_asked`)."""

import os
import signal
import sys

import pytest

pytest.importorskip("PyQt5")
from PyQt5.QtWidgets import QMainWindow, QWidget

from tests.helpers import GUI_WAIT
from ui.app import close_when_asked, stop_requests

pytestmark = pytest.mark.gui


class _SignalledWhileResized(QWidget):
    """Sends ``sig`` to this process from inside a Qt virtual (its resize handler)."""

    def __init__(self, sig=signal.SIGTERM) -> None:
        super().__init__()
        self.sig = sig

    def resizeEvent(self, ev) -> None:
        os.kill(os.getpid(), self.sig)
        for _ in range(1000):  # bytecodes: Python runs the handler inside this Qt call
            pass
        super().resizeEvent(ev)


@pytest.fixture
def restore_handlers():
    saved = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGINT)}
    yield
    for s, h in saved.items():
        signal.signal(s, h)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_stop_signalled_inside_a_qt_call_closes_the_window(qtbot, restore_handlers, sig):
    asked = stop_requests()
    win = QMainWindow()
    qtbot.addWidget(win)
    inner = _SignalledWhileResized(sig)
    win.setCentralWidget(inner)
    close_when_asked(win, asked)
    win.show()
    win.resize(640, 480)  # the signal arrives inside Qt's resize handling
    qtbot.waitUntil(lambda: bool(asked), timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: not win.isVisible(), timeout=GUI_WAIT)
    assert asked[0] == {signal.SIGTERM: "SIGTERM", signal.SIGINT: "SIGINT"}[sig]
    # the timer closed it once and stopped: one that kept calling close() fired while the window was destroyed
    from PyQt5.QtCore import QTimer

    assert [t.isActive() for t in win.findChildren(QTimer) if t.interval() == 100] == [False]


def test_the_old_way_loses_the_stop(qtbot, restore_handlers):
    """Why the handler must not raise: the KeyboardInterrupt it raises inside a Qt call never reaches
    the code around the event loop (this is what left the GUI running after SIGTERM)."""
    caught = []

    def raising(*_):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, raising)
    hooked = []
    old_hook = sys.excepthook
    sys.excepthook = lambda *a: hooked.append(a[0])
    try:
        win = _SignalledWhileResized()
        qtbot.addWidget(win)
        try:
            win.show()
            win.resize(300, 200)
            qtbot.wait(200)
        except KeyboardInterrupt:
            caught.append(True)
    finally:
        sys.excepthook = old_hook
    assert not caught and KeyboardInterrupt in hooked and win.isVisible()


def test_an_interrupt_while_an_engine_starts_stops_that_engine(monkeypatch):
    """H89: SIGTERM (as KeyboardInterrupt) reached the GUI while it waited for its engine's "requests on"
    line; the caller had no EngineProcess yet to stop, so the engine ran on until its own start-up ended
    (both ``test_sigterm_closes_the_gui_and_its_engine`` cases failed beside a CPU hog, 2026-11-28).  The
    engine here never starts (a process that only sleeps): the interrupt must leave it stopped."""
    import contextlib
    import subprocess
    import threading

    from app.errors import raise_interrupt
    from tests.helpers import process_running
    from ui import engine_process

    started = []
    real_popen = subprocess.Popen

    def sleeper(cmd, **kw):
        started.append(real_popen([sys.executable, "-c", "import time; time.sleep(120)"], **kw))
        return started[-1]

    monkeypatch.setattr(engine_process.subprocess, "Popen", sleeper)
    previous = signal.signal(signal.SIGUSR2, raise_interrupt)
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGUSR2))
    try:
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            engine_process.EngineProcess(timeout=60.0)
    finally:
        timer.cancel()
        signal.signal(signal.SIGUSR2, previous)
    assert len(started) == 1
    proc = started[0]
    try:
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(timeout=10)
        assert not process_running(proc.pid), "the engine being started was left running"
    finally:
        if proc.poll() is None:
            proc.kill()
