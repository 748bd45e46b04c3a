"""The one protocol client of an engine that keeps itself connected: the GUI's link (``ui/link.py``), the
viewer's and the joystick client's (``app/teleop/client.py``) all use it.  Qt-free.

Its sockets live in their own thread, because the program using it (a GUI painting plots and 3D views, a
loop polling a joystick) can stall on a busy machine, and input, STOP and keep-alives must not stall with
it.  The thread

* sends queued commands at once, an ``estop`` before anything else;
* re-sends the latest input sample at a fixed rate (50 Hz) for as long as its user keeps refreshing it (the
  user's own heartbeat: one frozen for more than ``INPUT_HOLD`` lets the input go stale, so the engine
  holds);
* detects a lost engine (no state for ``lost_after`` s) and reconnects by itself: it says ``hello`` again,
  asking for the same role, and follows the state socket to its new address, also when the engine was
  restarted on the same URL (an engine that answers "before hello" is greeted at once);
* pings twice a second (keeps the operator role).
"""

from __future__ import annotations

import collections
import contextlib
import threading
import time
from collections.abc import Callable
from typing import Any

import zmq

from app.net.codec import ProtocolError, build, decode_engine, encode_message
from app.net.messages import Description as DescriptionMessage
from app.net.messages import Log, Reply, State, Study, Welcome
from app.net.snapshots import Description, Snapshot, SnapshotError, description_from_wire, snapshot_from_wire
from app.net.transport import Client, client_view_of

INPUT_RATE = 50.0  # Hz: input re-sent at this rate while its user keeps it fresh
INPUT_HOLD = 0.25  # s: the user must refresh the input this often, or it is no longer sent (a frozen GUI stops)
DESCRIBE_RETRY = 0.5  # s: a state announcing a newer description than ours asks for it at most this often


class EngineConnection(threading.Thread):
    """Owns the client's sockets (handed over after the first, blocking hello) in its own thread.

    Other threads call :meth:`queue`, :meth:`set_input` and :meth:`clear_input` (thread-safe) and read
    ``events`` (a deque: ``("log", level, text)``, ``("reply", re, ok, error)``, ``("conn", ok, text)``,
    ``("welcome", role, note)``, ``("description", desc)``, ``("study", fields)``), ``latest``, ``state_seq``
    and ``history`` (under ``lock``).  :func:`connect` makes one."""

    def __init__(self, client: Client, role: str, name: str, token: str | None, lost_after: float) -> None:
        super().__init__(daemon=True, name=f"engine-link-{name}")
        self.client = client
        self.role_wanted, self.name, self.token = role, name, token
        self.lost_after = lost_after
        self.lock = threading.RLock()
        self.outbox: collections.deque = collections.deque()
        self.estop_queued = 0
        self.estop_reason = ""
        self.input: tuple | None = None  # (axes, buttons, device, t_set)
        self.device_lost: tuple[str, bool] | None = None  # (device, released deliberately)
        self.latest: Snapshot | None = None
        self.description: Description | None = client.description
        self._last_describe = 0.0
        self.state_seq = 0
        self.history: collections.deque = collections.deque(maxlen=3000)  # every state, for loggers (60 s at 50/s)
        self.events: collections.deque = collections.deque(maxlen=2000)  # ("log"|"reply"|"conn"|"welcome", ...)
        self.connected = True
        self.role = client.role
        self.stop_flag = threading.Event()
        self._last_state = time.monotonic()
        self._last_ping = 0.0
        self._last_input = 0.0
        self._last_hello = 0.0
        self._sent_input_key = None
        self.hello_wanted = False  # the GUI asked for a role again (take the operator role)

    # ------------------------------------------------------------------ called from the GUI thread
    def queue(self, mtype: str, fields: dict[str, Any]) -> None:
        with self.lock:
            if mtype == "estop":
                # STOP goes out first, and a reset the operator gave before it but not yet sent is dropped:
                # a Reset click followed by STOP must end stopped, whatever order one worker pass sends them in
                self.outbox = collections.deque(m for m in self.outbox if m[0] != "reset")
                self.estop_queued += 1
                self.estop_reason = fields.get("reason", "")
            else:
                self.outbox.append((mtype, fields))

    def set_input(self, axes, buttons, device: str) -> None:
        with self.lock:
            self.input = (tuple(axes), tuple(bool(b) for b in buttons), device, time.monotonic())
            self.device_lost = None

    def clear_input(self, device: str, released: bool) -> None:
        """No input from this GUI for this engine any more: ``released`` (the operator left its tab)
        or the device is gone."""
        with self.lock:
            self.input = None
            self.device_lost = (device, released)

    # ------------------------------------------------------------------ the thread
    def _send(self, mtype: str, **fields: Any) -> bool:
        try:
            msg = build(mtype, **fields)
        except TypeError as err:  # a sender's bug: said, not sent, and the link goes on
            self.events.append(("log", "error", f"{mtype} not sent: {err}"[:300]))
            return False
        try:
            self.client.dealer.send(encode_message(msg), zmq.NOBLOCK)
            return True
        except (zmq.ZMQError, ProtocolError):
            return False

    def _hello(self, now: float) -> None:
        self._last_hello = now
        self._send("hello", **dict(self.client.hello_fields, role=self.role_wanted))

    def _welcome(self, msg: Welcome) -> None:
        self.role = msg.role
        url = client_view_of(msg.state_url, self.client.url)
        if url != self.client.state_url:
            with contextlib.suppress(zmq.ZMQError):
                self.client.sub.disconnect(self.client.state_url)
            self.client.sub.connect(url)
            self.client.state_url = url
        self.events.append(("welcome", self.role, msg.note or ""))

    def _flush(self, now: float) -> None:
        with self.lock:
            n_estop, reason = self.estop_queued, self.estop_reason
            self.estop_queued = 0
            out = list(self.outbox)
            self.outbox.clear()
            inp, lost = self.input, self.device_lost
            self.device_lost = None
        for _ in range(min(n_estop, 1)):
            fields: dict[str, Any] = {"reason": reason[:256]}
            if self.token is not None:
                fields["token"] = self.token
            self._send("estop", **fields)
        for mtype, fields in out:
            self._send(mtype, **fields)
        if lost is not None:
            self._send("device_lost", device=lost[0][:128], released=lost[1])
            self._sent_input_key = None
        if self.hello_wanted:
            self.hello_wanted = False
            self._hello(now)
        operator = self.role == "operator"  # a viewer's input would only be refused (and counted)
        if inp is not None and operator and now - inp[3] <= INPUT_HOLD and self.connected:  # never replayed
            key = inp[:3]
            if key != self._sent_input_key or now - self._last_input >= 1.0 / INPUT_RATE:
                self.client.seq += 1
                ok = self._send(
                    "input",
                    seq=self.client.seq,
                    t_send=time.monotonic(),
                    axes=[float(a) for a in inp[0][:16]],
                    buttons=list(inp[1][:64]),
                    device=inp[2][:128],
                )
                if ok:
                    self._last_input, self._sent_input_key = now, key
        if now - self._last_ping >= 0.5:
            self._last_ping = now
            self._send("ping")

    def _typed(self, from_wire: Callable[[Any], Any], data: Any, what: str) -> Any:
        """``data`` as its typed class by ``from_wire``, or None (said in the log) when it does not fit the
        protocol: one bad message is skipped, the link goes on."""
        try:
            return from_wire(data)
        except SnapshotError as err:
            self.events.append(("log", "error", f"engine {what} not understood: {err}"[:300]))
            return None

    def _receive(self, now: float) -> None:
        for sock in (self.client.sub, self.client.dealer):
            for _ in range(500):
                try:
                    data = sock.recv(zmq.NOBLOCK)
                except zmq.Again:
                    break
                except zmq.ZMQError:
                    return
                try:
                    msg = decode_engine(data)
                except ProtocolError:
                    continue
                if isinstance(msg, State):
                    snap = self._typed(snapshot_from_wire, msg.state, "state")
                    if snap is None:
                        continue
                    with self.lock:
                        self.latest = snap
                        self.state_seq += 1
                        self.history.append(snap)
                    self._last_state = now
                    d = self.description
                    if (d is None or d.seq != snap.describe_seq) and now - self._last_describe > DESCRIBE_RETRY:
                        self._last_describe = now
                        self._send("describe")
                elif isinstance(msg, DescriptionMessage):
                    desc = self._typed(description_from_wire, msg.description, "description")
                    if desc is None:
                        continue
                    if (
                        self.description is None
                        or desc.seq != self.description.seq
                        or desc.kind != self.description.kind
                    ):
                        self.description = desc
                        self.events.append(("description", desc))
                elif isinstance(msg, Study):
                    self.events.append(("study", msg.study))
                elif isinstance(msg, Log):
                    self.events.append(("log", msg.level, msg.text))
                elif isinstance(msg, Welcome):
                    self._welcome(msg)
                elif isinstance(msg, Reply):
                    err = msg.error or ""
                    if not msg.ok and "before hello" in err:
                        if now - self._last_hello > 0.2:  # the engine restarted under us: greet it
                            self._hello(now)
                        continue
                    if msg.re != "ping":
                        self.events.append(("reply", msg.re, msg.ok, err))

    def run(self) -> None:
        poller = zmq.Poller()
        poller.register(self.client.sub, zmq.POLLIN)
        poller.register(self.client.dealer, zmq.POLLIN)
        while not self.stop_flag.is_set():
            now = time.monotonic()
            try:
                self._flush(now)
                self._receive(now)
            except zmq.ZMQError:
                pass
            except Exception as err:  # a bug here must not silently stop the link: say it, go on
                self.events.append(("log", "error", f"engine link: {type(err).__name__}: {err}"))
            silent = now - self._last_state
            if self.connected and silent > self.lost_after:
                self.connected = False
                self.events.append(("conn", False, f"lost the engine connection (no state for {self.lost_after:g} s)"))
            elif not self.connected and silent < self.lost_after:
                self.connected = True
                self.events.append(("conn", True, "engine connection restored"))
            if not self.connected and now - self._last_hello > 0.5:
                self._hello(now)  # reconnect: a restarted engine needs a new hello, the same one keeps us
            with contextlib.suppress(zmq.ZMQError):
                poller.poll(5)

    def stop(self) -> None:
        self.stop_flag.set()


def connect(
    url: str,
    role: str = "operator",
    name: str = "bosun",
    token: str | None = None,
    lost_after: float = 1.0,
    secret: str | None = None,
    curve=None,
) -> EngineConnection:
    """Say hello to the engine at ``url`` (raises :class:`~app.net.transport.TransportError`: no engine) and
    start the connection's thread."""
    client = Client(url, role=role, name=name, token=token, secret=secret, curve=curve)
    conn = EngineConnection(client, role, name, token, lost_after)
    conn.start()
    return conn
