"""ZeroMQ transport: endpoints and the client side of the protocol.

The engine binds two sockets: a ROUTER for requests and input (``--bind URL``) and a PUB
for the state stream, whose address it tells each client in ``welcome``.  A client
connects a DEALER to the request URL and a SUB to the state URL, so one machine or
several is only a matter of URL: ``ipc:///tmp/bosun``, ``tcp://127.0.0.1:5555``,
``tcp://host:5555``.
"""

from __future__ import annotations

import contextlib
import ipaddress
import time
import uuid
from collections.abc import Iterator
from typing import Any
from urllib.parse import urlsplit

import zmq

from app.errors import BosunError
from app.net.codec import ProtocolError, build, decode_engine, encode, encode_message
from app.net.messages import PROTOCOL_VERSION, Reply, State
from app.net.messages import Description as DescriptionMessage
from app.net.security import ClientCurve
from app.net.snapshots import Description, Snapshot, SnapshotError, description_from_wire, snapshot_from_wire

DEFAULT_URL = "tcp://127.0.0.1:5555"


class TransportError(BosunError):
    """A URL that cannot be used, or an engine that does not answer."""


def check_url(url: str) -> str:
    """Accept tcp://HOST:PORT (PORT may be 0 for any free port) and ipc://PATH."""
    parts = urlsplit(url)
    if parts.scheme == "ipc":
        if not (parts.netloc or parts.path):
            raise TransportError(f"ipc URL needs a path: {url}")
        return url
    if parts.scheme != "tcp":
        raise TransportError(f"URL must start with tcp:// or ipc://, got {url!r}")
    try:
        port = parts.port
    except ValueError:
        port = None
    if not parts.hostname or port is None:
        raise TransportError(f"tcp URL needs a host and a port, e.g. tcp://127.0.0.1:5555; got {url!r}")
    return url


def is_local(url: str) -> bool:
    """True for ipc:// and loopback tcp addresses (127.0.0.0/8, ::1, localhost)."""
    parts = urlsplit(url)
    if parts.scheme == "ipc":
        return True
    host = parts.hostname or ""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def state_url_for(bind_url: str) -> str:
    """Where the PUB socket binds: ipc://PATH.state, or the same tcp host on any free port."""
    parts = urlsplit(bind_url)
    if parts.scheme == "ipc":
        return bind_url + ".state"
    return f"tcp://{parts.hostname if ':' not in (parts.hostname or '') else '[' + parts.hostname + ']'}:0"


def client_view_of(state_endpoint: str, request_url: str) -> str:
    """The state URL as a client should dial it: the engine's port, the host the client used."""
    st, req = urlsplit(state_endpoint), urlsplit(request_url)
    if st.scheme != "tcp" or req.scheme != "tcp":
        return state_endpoint
    return f"tcp://{req.netloc.rsplit(':', 1)[0]}:{st.port}"


def _auth_refusal(monitor: zmq.Socket | None) -> int:
    """The ZAP status code (400) with which the engine refused this client's key, 0 if it did not."""
    from zmq.utils.monitor import recv_monitor_message

    status = 0
    while monitor is not None:
        try:
            event = recv_monitor_message(monitor, zmq.NOBLOCK)
        except (zmq.Again, zmq.ZMQError):
            break
        if event["event"] == zmq.EVENT_HANDSHAKE_FAILED_AUTH:
            status = int(event["value"]) or 400
        elif event["event"] == zmq.EVENT_HANDSHAKE_SUCCEEDED:
            status = 0
    return status


def _engine_messages(sock: zmq.Socket, timeout: float) -> Iterator[Any]:
    """The engine's messages as they arrive on ``sock`` until ``timeout`` seconds have passed (the caller
    stops early by leaving the loop); what does not decode is skipped."""
    deadline = time.monotonic() + timeout
    while (left := deadline - time.monotonic()) > 0:
        if not sock.poll(int(left * 1000) + 1):
            continue
        try:
            msg = decode_engine(sock.recv())
        except ProtocolError:
            continue
        yield msg


class Client:
    """A protocol client: request/reply and input on a DEALER, state on a SUB.

    Parameters
    ----------
    url : str
        The engine's request URL.
    role : {"operator", "viewer"}
    name : str
        Shown in the engine's log.
    token : str, optional
        Shared token of an engine that asks for one (loopback testing).
    secret : str, optional
        The launch secret of an engine this program started (the operator role needs it).
    curve : ClientCurve, optional
        CURVE keys for an engine bound to a non-local address (encrypted, authenticated).
    timeout : float
        Seconds to wait for ``welcome`` and for replies.
    """

    def __init__(
        self,
        url: str,
        role: str = "viewer",
        name: str = "client",
        token: str | None = None,
        timeout: float = 3.0,
        context: zmq.Context | None = None,
        secret: str | None = None,
        curve: ClientCurve | None = None,
    ) -> None:
        self.url = check_url(url)
        self.curve = curve
        self.ctx = context or zmq.Context.instance()
        self.timeout = timeout
        self.dealer = self.ctx.socket(zmq.DEALER)
        self.dealer.setsockopt(zmq.LINGER, 0)
        self.dealer.setsockopt(zmq.IDENTITY, f"{name}-{uuid.uuid4().hex[:8]}".encode())
        monitor = None
        if curve is not None:
            curve.apply(self.dealer)
            # the handshake's outcome: a refused key is then told apart from an engine that is not there
            monitor = self.dealer.get_monitor_socket(zmq.EVENT_HANDSHAKE_FAILED_AUTH | zmq.EVENT_HANDSHAKE_SUCCEEDED)
        self.dealer.connect(self.url)
        self.sub: zmq.Socket | None = None
        self.role = None
        self.seq = 0
        hello: dict[str, Any] = {"role": role, "name": name}
        if token is not None:
            hello["token"] = token
        if secret is not None:
            hello["secret"] = secret
        self.hello_fields = hello  # what a reconnecting link says again
        self.description: Description | None = None
        try:
            # a DEALER without a pipe to the engine refuses a non-blocking send (zmq.Again): the pipe can be gone
            # already when a CURVE handshake was refused at once; wait for one as for the welcome
            try:
                if not self.dealer.poll(int(1000 * timeout), zmq.POLLOUT):
                    raise zmq.Again()
                self.send("hello", **hello)
            except zmq.Again:
                raise TransportError(f"no answer from the engine at {self.url} within {timeout:g} s") from None
            welcome = self._wait_for(("welcome", "reply"))
        except TransportError as err:
            refused = _auth_refusal(monitor)
            self.close()
            if refused:
                raise TransportError(
                    f"the engine at {self.url} refused this client's CURVE key (ZAP status {refused}): "
                    "is its public key in the engine's allowed folder?"
                ) from None
            if curve is not None:
                raise TransportError(
                    f"{err} (CURVE: is this client's public key in the engine's allowed folder, "
                    "and is the engine's public key the right one?)"
                ) from None
            raise
        finally:
            if monitor is not None:
                with contextlib.suppress(zmq.ZMQError):
                    self.dealer.disable_monitor()
                monitor.close(0)
        if isinstance(welcome, Reply):
            self.close()
            raise TransportError(f"engine refused the connection: {welcome.error or 'no reason given'}")
        self.role = welcome.role
        self.client_id = welcome.client_id
        self.note = welcome.note or ""
        self.state_url = client_view_of(welcome.state_url, self.url)
        self.sub = self.ctx.socket(zmq.SUB)
        self.sub.setsockopt(zmq.LINGER, 0)
        self.sub.setsockopt(zmq.CONFLATE, 0)
        self.sub.setsockopt(zmq.SUBSCRIBE, b"")
        if curve is not None:
            curve.apply(self.sub)
        self.sub.connect(self.state_url)

    # ------------------------------------------------------------------ sending
    def send(self, mtype: str, **fields: Any) -> None:
        """Send a client message, built as its class first (a misspelt or missing field is a TypeError here)."""
        self.dealer.send(encode_message(build(mtype, **fields)), zmq.NOBLOCK)

    def send_unchecked(self, mtype: str, **fields: Any) -> None:
        """Send a message as given, unchecked: for probing an engine with what no client should send (the
        hostile tests, the fuzzers); the engine validates it and refuses what is wrong."""
        self.dealer.send(encode(mtype, **fields), zmq.NOBLOCK)

    def send_input(self, axes, buttons, device: str) -> None:
        self.seq += 1
        self.send(
            "input",
            seq=self.seq,
            t_send=time.monotonic(),
            axes=[float(a) for a in axes],
            buttons=[bool(b) for b in buttons],
            device=device,
        )

    def request(self, mtype: str, **fields: Any) -> Reply:
        """Send a command and wait for its reply; raises TransportError when refused or silent."""
        self.send(mtype, **fields)
        reply = self._wait_for(("reply",), re=mtype)
        if not reply.ok:
            raise TransportError(reply.error or f"{mtype} refused")
        return reply

    def describe(self) -> Description:
        """Ask for the scene's description and wait for it."""
        self.send("describe")
        msg = self._wait_for(("description",))
        try:
            return description_from_wire(msg.description)
        except SnapshotError as err:
            raise TransportError(f"the engine's description does not fit protocol {PROTOCOL_VERSION}: {err}") from None

    # ------------------------------------------------------------------ receiving
    def _wait_for(self, types: tuple[str, ...], re: str | None = None) -> Any:
        for msg in _engine_messages(self.dealer, self.timeout):
            if isinstance(msg, DescriptionMessage):  # sent after welcome and on request: keep the newest
                with contextlib.suppress(SnapshotError):
                    self.description = description_from_wire(msg.description)
            if msg.TYPE in types and (re is None or getattr(msg, "re", None) == re):
                return msg
        raise TransportError(f"no answer from the engine at {self.url} within {self.timeout:g} s")

    def recv_state(self, timeout: float = 1.0) -> Snapshot | None:
        """The next state message's typed snapshot (None on timeout); other messages are skipped."""
        for msg in _engine_messages(self.sub, timeout):
            if isinstance(msg, State):
                try:
                    return snapshot_from_wire(msg.state)
                except SnapshotError:
                    continue
        return None

    def latest_state(self, timeout: float = 1.0) -> Snapshot | None:
        """Drain the stream and return the newest snapshot (waits up to timeout for one)."""
        newest = self.recv_state(timeout)
        while newest is not None and self.sub.poll(0):
            nxt = self.recv_state(0.001)
            if nxt is None:
                break
            newest = nxt
        return newest

    def close(self) -> None:
        with contextlib.suppress(zmq.ZMQError):
            self.send("bye")
        for s in (self.dealer, self.sub):
            if s is not None:
                s.close(0)
