"""The GUI's only way to the engine: a protocol client polled by a QTimer, as Qt signals."""

from __future__ import annotations

import contextlib
import time
from typing import Any

import zmq
from PyQt5.QtCore import QObject, QTimer, pyqtSignal

from app.net.codec import ProtocolError, decode_engine
from app.net.transport import Client, TransportError


class EngineLink(QObject):
    """Connects as operator (or viewer) and turns the engine's stream into signals.

    Signals
    -------
    state(dict)            every state snapshot
    log(str, str)          level, text of engine log lines
    reply(str, bool, str)  request type, ok, error text
    connection(bool, str)  engine reachable or lost, with a message
    """

    state = pyqtSignal(dict)
    log = pyqtSignal(str, str)
    reply = pyqtSignal(str, bool, str)
    connection = pyqtSignal(bool, str)

    def __init__(
        self,
        url: str,
        role: str = "operator",
        name: str = "bosun-gui",
        token: str | None = None,
        lost_after: float = 1.5,
        parent: QObject | None = None,
    ) -> None:
        super().__init__(parent)
        self.client = Client(url, role=role, name=name, token=token)
        self.role = self.client.role
        self.note = self.client.note
        self.lost_after = lost_after
        self.last_state_time = time.monotonic()
        self.connected = True
        self.latest: dict[str, Any] | None = None
        self._timer = QTimer(self)
        self._timer.setInterval(10)
        self._timer.timeout.connect(self.poll)
        self._timer.start()
        self._ping = QTimer(self)
        self._ping.setInterval(500)  # keeps the operator role alive while the stick is idle
        self._ping.timeout.connect(lambda: self.send("ping"))
        self._ping.start()

    # ------------------------------------------------------------------ sending
    def send(self, mtype: str, **fields: Any) -> None:
        try:
            self.client.send(mtype, **fields)
        except zmq.ZMQError as err:
            self.connection.emit(False, f"cannot send to the engine: {err}")

    def send_input(self, axes, buttons, device: str) -> None:
        with contextlib.suppress(zmq.ZMQError):
            self.client.send_input(axes, buttons, device)

    # ------------------------------------------------------------------ receiving
    def poll(self) -> None:
        newest = None
        for sock in (self.client.sub, self.client.dealer):
            for _ in range(500):
                try:
                    data = sock.recv(zmq.NOBLOCK)
                except zmq.Again:
                    break
                try:
                    msg = decode_engine(data)
                except ProtocolError:
                    continue
                if msg["type"] == "state":
                    newest = msg["state"]
                elif msg["type"] == "log":
                    self.log.emit(msg["level"], msg["text"])
                elif msg["type"] == "reply" and msg["re"] != "ping":
                    self.reply.emit(msg["re"], msg["ok"], msg.get("error", ""))
        now = time.monotonic()
        if newest is not None:
            self.last_state_time = now
            self.latest = newest
            if not self.connected:
                self.connected = True
                self.connection.emit(True, "engine connection restored")
            self.state.emit(newest)
        elif self.connected and now - self.last_state_time > self.lost_after:
            self.connected = False
            self.connection.emit(False, f"lost the engine connection (no state for {self.lost_after:g} s)")

    def close(self) -> None:
        self._timer.stop()
        self._ping.stop()
        self.client.close()


__all__ = ["EngineLink", "TransportError"]
