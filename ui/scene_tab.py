"""What the scene tabs (Crane head, Motion-Lab) share: their own engine link, made on first view.

While no tab shows a scene its engine is paused (``pause`` on: its time stands still, STOP still
latches); shown again, it resumes.  The main window says which tabs are on screen
(:meth:`SceneEngineMixin.set_shown`); the tab keeps its engine in that state, also across a
reconnect or an engine restart (each state tells whether the engine is paused).

A factory that can start its engine apart from linking to it (``start_process()`` → URL, then
``link(url)``) has the slow part — a new engine process, about a second — run in a thread, so the
window (and Space = STOP) stays live while the engine starts; a plain callable factory is called
directly.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from PyQt5.QtCore import QObject, pyqtSignal

PAUSE_RESEND_S = 1.0  # an engine whose state disagrees with the wanted pause is told again this often


class _Started(QObject):
    """Carries the result of a background engine start back to the GUI thread."""

    done = pyqtSignal(str, str)  # url, error


class SceneEngineMixin:
    """Connects a tab to its scene engine through ``link_factory`` the first time it is needed.

    The tab provides ``notice`` (signal: level, text), ``on_state``, ``on_description``, ``on_reply``,
    ``_set_enabled``,
    ``_engine_failed(err)`` and the class attribute ``engine_label`` used in messages.
    """

    engine_label = "scene"
    link = None
    link_factory = None
    on_link = None  # called with each new link (the main window watches it: lost engine, STOP)

    _starting = None
    shown = True  # the tab is on screen (set by the main window); hidden, its engine is paused
    _pause_sent = -1e9

    def __init__(self, link_factory: Callable[[], object] | None = None, use_gl: bool | None = None) -> None:
        """Before the first view: no link (``link_factory`` makes it), nothing from the engine yet;
        ``use_gl`` chooses the tab's scene view (None: OpenGL where it works)."""
        super().__init__()  # the tab's widget class, next in its bases
        self.link_factory = link_factory
        self.link = None
        self.use_gl = use_gl
        self.state = None  # the engine's newest snapshot
        self.desc = None  # the engine's description

    def connect_engine(self) -> bool:
        """Link the tab to its engine; False while it is starting in the background or when it failed."""
        if self.link is not None:
            return True
        if self.link_factory is None or self._starting is not None:
            return False
        if hasattr(self.link_factory, "start_process"):
            self._starting = _Started()
            self._starting.done.connect(self._engine_started)
            self.notice.emit("info", f"{self.engine_label} engine starting…")
            bridge, factory = self._starting, self.link_factory

            def run() -> None:
                try:
                    bridge.done.emit(factory.start_process(), "")
                except Exception as err:
                    bridge.done.emit("", str(err) or type(err).__name__)

            threading.Thread(target=run, daemon=True).start()
            return False
        return self._linked(self.link_factory)

    def _engine_started(self, url: str, error: str) -> None:
        self._starting = None
        if error:
            self.notice.emit("error", f"{self.engine_label} engine: {error}")
            self._engine_failed(RuntimeError(error))
            return
        self._linked(lambda: self.link_factory.link(url))

    def _linked(self, make) -> bool:
        try:
            self.link = make()
        except Exception as err:  # the engine did not start: say why, keep the tab usable
            self.notice.emit("error", f"{self.engine_label} engine: {err}")
            self._engine_failed(err)
            return False
        self.link.state.connect(self.on_state)
        self.link.state.connect(self._keep_pause)
        self.link.described.connect(self.on_description)
        if self.link.description is not None:
            self.on_description(self.link.description)
        self.link.reply.connect(self.on_reply)
        self.link.log.connect(lambda lvl, text: self.notice.emit(lvl, f"{self.engine_label}: {text}"))
        self._set_enabled(True)
        self.notice.emit("info", f"{self.engine_label} engine connected")
        if self.on_link is not None:
            self.on_link(self.link)
        if not self.shown:
            self._send_pause()
        return True

    # ------------------------------------------------------------------ pause while hidden
    def set_shown(self, shown: bool) -> None:
        """The tab came on screen (the engine resumes) or left it (the engine pauses)."""
        if shown != self.shown:
            self.shown = shown
            self._send_pause()

    def _send_pause(self) -> None:
        # only the operator may pause (a viewer's pause would be refused); STOP is never held back by it:
        # an ``estop`` goes out ahead of any queued message and a paused engine still latches it
        if self.link is not None and getattr(self.link, "role", "operator") == "operator":
            self.link.send("pause", on=not self.shown)
            self._pause_sent = time.monotonic()

    def _keep_pause(self, state) -> None:
        """The engine's state disagrees with the wanted pause (a restarted engine, a lost message): again."""
        engine = getattr(state, "engine", None)
        if engine is None or engine.paused == (not self.shown):
            return
        if time.monotonic() - self._pause_sent > PAUSE_RESEND_S:
            self._send_pause()

    def _send(self, mtype: str, **fields) -> None:
        if self.link is not None:
            self.link.send(mtype, **fields)

    def estop(self) -> None:
        self._send("estop", reason="STOP in the GUI")

    def reset(self) -> None:
        self._send("reset")

    def close_link(self) -> None:
        if self.link is not None:
            self.link.close()
            self.link = None
