"""The GUI's only way to an engine: :class:`~app.net.link.EngineConnection` (the Qt-free, reconnecting
protocol client whose sockets live in their own thread) turned into Qt signals.

The GUI thread reads what arrived through a QTimer and gets Qt signals; it never touches a socket.
"""

from __future__ import annotations

from typing import Any

from PyQt5.QtCore import QObject, QTimer, pyqtSignal

from app.net.link import connect
from app.net.snapshots import Description, Snapshot
from app.net.transport import Client, TransportError


class EngineLink(QObject):
    """Connects as operator (or viewer) and turns the engine's stream into signals.

    Signals
    -------
    state(Snapshot)        the newest typed state snapshot (at most once per GUI poll: displays)
    states(list)           every snapshot received since the last poll, oldest first (loggers: none is lost
                           when the GUI is slow)
    described(Description) the scene's static data: on join and whenever the engine changes it
    study(dict)            an IK study's progress (``status``, ``done``, ``total``; ``result`` in the last)
    log(str, str)          level, text of engine log lines
    reply(str, bool, str)  request type, ok, error text
    connection(bool, str)  engine reachable or lost, with a message
    role_changed(str, str) the role this link holds now (operator | viewer) and the engine's note
    """

    state = pyqtSignal(object)
    states = pyqtSignal(list)
    described = pyqtSignal(object)
    study = pyqtSignal(dict)
    role_changed = pyqtSignal(str, str)
    log = pyqtSignal(str, str)
    reply = pyqtSignal(str, bool, str)
    connection = pyqtSignal(bool, str)

    def __init__(self, url: str, *, name: str = "bosun-gui", parent: QObject | None = None, **options: Any) -> None:
        """``options`` are :func:`app.net.link.connect`'s: ``role`` (operator unless given), ``token``,
        ``lost_after``, ``secret``, ``curve``."""
        super().__init__(parent)
        self._worker = connect(url, name=name, **options)  # raises TransportError: no engine
        self.client: Client = self._worker.client
        self.url = url
        self.role = self.client.role
        self.note = self.client.note
        self.lost_after = self._worker.lost_after
        self.latest: Snapshot | None = None
        self.description: Description | None = self.client.description
        self._seen_seq = 0
        self._dead_reported = False
        self._timer = QTimer(self)
        self._timer.setInterval(10)
        self._timer.timeout.connect(self.poll)
        self._timer.start()

    @property
    def connected(self) -> bool:
        return self._worker.connected and self._worker.is_alive()

    # ------------------------------------------------------------------ sending (thread-safe queues)
    def send(self, mtype: str, **fields: Any) -> None:
        self._worker.queue(mtype, fields)

    def send_input(self, axes, buttons, device: str) -> None:
        self._worker.set_input(axes, buttons, device)

    def clear_input(self, device: str = "", released: bool = True) -> None:
        self._worker.clear_input(device, released)

    def release_operator(self) -> None:
        """Give the operator role up (the engine holds and disarms); reconnecting keeps the viewer role."""
        w = self._worker
        with w.lock:
            w.role_wanted = "viewer"
        w.queue("release_operator", {})

    def take_operator(self) -> None:
        """Ask for the operator role again (granted when it is free; a new operator starts disarmed)."""
        w = self._worker
        with w.lock:
            w.role_wanted = "operator"
            w.hello_wanted = True

    # ------------------------------------------------------------------ receiving (GUI thread)
    def poll(self) -> None:
        w = self._worker
        if not w.is_alive() and not self._dead_reported:
            self._dead_reported = True
            self.connection.emit(False, "the engine link's thread stopped")
        while w.events:
            ev = w.events.popleft()
            if ev[0] == "log":
                self.log.emit(ev[1], ev[2])
            elif ev[0] == "reply":
                if ev[1] == "release_operator" and ev[2]:
                    w.role = self.role = "viewer"
                    self.role_changed.emit("viewer", "operator role released")
                self.reply.emit(ev[1], ev[2], ev[3])
            elif ev[0] == "conn":
                self.connection.emit(ev[1], ev[2])
            elif ev[0] == "description":
                self.description = ev[1]
                self.described.emit(ev[1])
            elif ev[0] == "study":
                self.study.emit(ev[1])
            elif ev[0] == "welcome":
                changed = ev[1] != self.role
                self.role, self.note = ev[1], ev[2]
                if ev[1] != "operator" and w.role_wanted == "operator":
                    self.log.emit("warning", f"joined as {ev[1]}: {ev[2]}")
                if changed or ev[2]:
                    self.role_changed.emit(self.role, self.note)
        with w.lock:
            seq, newest = w.state_seq, w.latest
            batch = list(w.history)
            w.history.clear()
        if batch:
            self.states.emit(batch)
        if seq != self._seen_seq and newest is not None:
            self._seen_seq = seq
            self.latest = newest
            self.state.emit(newest)

    def close(self) -> None:
        self._timer.stop()
        self._worker.stop()
        self._worker.join(timeout=2)
        if not self._worker.is_alive():  # never close sockets a running thread still uses
            self.client.close()


__all__ = ["EngineLink", "TransportError"]
