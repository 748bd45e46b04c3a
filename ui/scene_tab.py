"""What the scene tabs (Crane head, Motion-Lab) share: their own engine link, made on first view."""

from __future__ import annotations


class SceneEngineMixin:
    """Connects a tab to its scene engine through ``link_factory`` the first time it is needed.

    The tab provides ``notice`` (signal: level, text), ``on_state``, ``on_reply``, ``_set_enabled``,
    ``_engine_failed(err)`` and the class attribute ``engine_label`` used in messages.
    """

    engine_label = "scene"
    link = None
    link_factory = None
    on_link = None  # called with each new link (the main window watches it: lost engine, STOP)

    def connect_engine(self) -> bool:
        if self.link is not None:
            return True
        if self.link_factory is None:
            return False
        try:
            self.link = self.link_factory()
        except Exception as err:  # the engine did not start: say why, keep the tab usable
            self.notice.emit("error", f"{self.engine_label} engine: {err}")
            self._engine_failed(err)
            return False
        self.link.state.connect(self.on_state)
        self.link.reply.connect(self.on_reply)
        self.link.log.connect(lambda lvl, text: self.notice.emit(lvl, f"{self.engine_label}: {text}"))
        self._set_enabled(True)
        self.notice.emit("info", f"{self.engine_label} engine connected")
        if self.on_link is not None:
            self.on_link(self.link)
        return True

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
