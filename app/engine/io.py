"""The engine's I/O thread: the protocol side of :class:`~app.engine.server.EngineServer`.

It owns the request socket: it receives, rate-limits (per client, before decoding: a flooding client costs
a receive and a counter), decodes and validates every message, keeps the client book
(:mod:`app.engine.clients`: hello, roles, tokens, the launch secret, lapses) and answers what it can answer
itself.  What the control step must see it hands over in the bounded :class:`~app.engine.inbox.Inbox`.

It runs Python only in the loop's idle time, the *I/O window* (:class:`IOWindow`; the module text of
:mod:`app.engine.server` says why).  Failed authentications are counted and throttled per connection (a
wrong-key handshake per peer address): one client's guessing never holds back another's right key or token.
"""

from __future__ import annotations

import contextlib
import logging
import math
import secrets
import threading
import time
from typing import TYPE_CHECKING, Any

import zmq

from app.engine.clients import clean_name
from app.errors import printable
from app.net.codec import ProtocolError, decode, encode_message
from app.net.messages import OPERATOR_ONLY, Hello, Reply, Welcome
from app.teleop.devices import InputSample

if TYPE_CHECKING:
    from app.engine.server import EngineServer

log = logging.getLogger("bosun.engine")

JOB_MARGIN = 0.001  # s: a job takes no step with less than this (or a quarter period) left in the I/O window


class IOWindow:
    """The loop's idle time, when the I/O thread and a scene's job may run Python (``end``: perf_counter
    time it closes; open until the loop runs)."""

    def __init__(self, stop: threading.Event, dt: float) -> None:
        self.cond = threading.Condition()
        self.end = math.inf
        self.stop = stop
        self.dt = dt

    def open_until(self, until: float) -> None:
        with self.cond:
            self.end = until
            self.cond.notify_all()  # the I/O thread and a job's thread

    def wait_io(self) -> None:
        """Block (interpreter lock free) while the loop is in, or about to start, its tick.

        A window shut for longer than a period and a millisecond means the loop overran or stalls in
        a long command: the I/O thread then carries on (sharing the lock), so E-STOPs still come in."""
        with self.cond:
            while not self.stop.is_set() and (now := time.perf_counter()) >= self.end:
                if now - self.end > self.dt + 0.001:
                    return
                self.cond.wait(0.001)

    def wait_job(self) -> None:
        """A step of a scene's job (:mod:`app.engine.jobs`) waits for the loop's idle time: the I/O window, with
        :data:`JOB_MARGIN` (at most a quarter period) to spare so that a step started in it ends before the
        tick.  Unlike the I/O thread it never carries on while the loop is in a tick, however long: nothing of a
        job is urgent, and a thread that shares the interpreter lock with the loop stretches the loop's tick."""
        margin = min(JOB_MARGIN, 0.25 * self.dt)
        with self.cond:
            while not self.stop.is_set() and time.perf_counter() >= self.end - margin:
                self.cond.wait(0.005)


class EngineIO:
    """Requests in, replies out, the client book kept.  ``srv`` is the engine: its sockets, inbox, book,
    rate limits, authentication throttle, credentials and counters are what this thread works on."""

    def __init__(self, srv: EngineServer) -> None:
        self.srv = srv
        self.backlog = False  # the window closed on waiting messages
        self.error: BaseException | None = None
        self._frame: zmq.Frame | None = None  # the message in hand (its peer address, its key)
        self._unknown_logged: dict[bytes, float] = {}
        self._current_type = "invalid"

    # ------------------------------------------------------------------ answers
    def reply(self, ident: bytes, re: str, ok: bool, error: str = "") -> None:
        answer = Reply(re=re, ok=ok, error=error[:1000] if error else None)
        self.srv.router.send_multipart([ident, encode_message(answer)], zmq.NOBLOCK)

    def reject(self, ident: bytes, reason: str, re: str | None = None) -> None:
        self.srv.rejected += 1
        self.srv._log_limited(f"reject:{reason[:40]}", f"rejected message from {ident[:32]!r}: {reason}", note=False)
        if re is not None:
            self.reply(ident, re, False, reason)

    # ------------------------------------------------------------------ credentials
    def source(self, ident: bytes) -> str:
        """Who a failed token or secret is pinned on: this connection (identity, peer address, CURVE key).

        The address and key come from the message in hand (ZeroMQ's ``Peer-Address`` and ``User-Id``
        properties; the key is the one the ZAP handler admitted)."""
        address = user = ""
        frame = self._frame
        if frame is not None:
            with contextlib.suppress(zmq.ZMQError, AttributeError):
                address = frame.get("Peer-Address")
            if self.srv.curve is not None:
                with contextlib.suppress(zmq.ZMQError, AttributeError):
                    user = frame.get("User-Id")
        where = f" at {printable(address, 64)}" if address else ""
        key = f" with key {user[:8]}…" if user else ""
        return f"client {ident[:32]!r}{where}{key}"

    def credential(self, ident: bytes, given: Any, expected: str | None, what: str) -> str:
        """'' when ``given`` is right (or this engine expects nothing), else why not, in a few words.

        Compared in constant time on UTF-8 bytes (compare_digest refuses non-ASCII str).  Failures are
        throttled per connection (:meth:`source`): past 10 in a second, that connection's further
        tries are refused unexamined for a second; anybody else's are still looked at (issue 27, item 3)."""
        if expected is None:
            return ""
        auth = self.srv.auth
        source = f"{what} {self.source(ident)}"
        if not auth.allowed(source):
            return (
                f"not checked: {auth.burst} wrong {what}s from this client within {auth.window:g} s; "
                "try again in a second"
            )
        given = "" if given is None else str(given)
        if given and secrets.compare_digest(given.encode(), expected.encode()):
            return ""
        if auth.failed(source) == auth.burst:
            self.srv._log_limited(
                f"auth:{source}",
                f"{auth.burst} wrong {what}s within {auth.window:g} s from {source[len(what) + 1 :]}: "
                f"its tries are refused unexamined for {auth.window:g} s ({auth.failures} failures so far)",
            )
        return f"with a wrong {what}" if given else f"without a {what} (this engine needs one)"

    # ------------------------------------------------------------------ messages
    def handle(self, ident: bytes, data: bytes, now: float) -> None:
        """Rate-limit, validate and dispatch one message from a client; nothing a message does escapes.

        Any exception a handler raises (a bug, a value the checks missed) becomes a refusal to that
        client and one rate-limited log line; the engine keeps running and keeps its E-STOP.  A client
        over its budget has the message dropped unread, unless it may be an E-STOP (the word is in it)."""
        limits = self.srv.limits
        if not limits.allow(ident, now) and b"estop" not in data:
            if limits.dropped[ident] % 10_000 == 1:
                self.srv._log_limited(
                    f"flood:{ident[:16]!r}",
                    f"client {ident[:32]!r} over {limits.rate:g} messages/s: excess dropped "
                    f"({limits.dropped[ident]} so far)",
                )
            return
        self._current_type = "invalid"
        try:
            self._handle(ident, data, now)
        except Exception as err:  # the boundary: a message can be refused, never kill or freeze the engine
            self.srv.rejected += 1
            self.srv._log_limited("internal", f"message refused by an internal error: {type(err).__name__}: {err}")
            with contextlib.suppress(Exception):
                self.reply(ident, self._current_type, False, f"refused: internal error ({type(err).__name__})")

    def _estop(self, ident: bytes, source: str, now: float) -> None:
        """Past every queue: the loop applies it first thing in its next tick, then confirms."""
        self.srv.inbox.estop(now, self.srv.stats.ticks, source)
        self.reply(ident, "estop", True)

    def _handle(self, ident: bytes, data: bytes, now: float) -> None:
        srv, book = self.srv, self.srv.book
        try:
            msg = decode(data)
        except ProtocolError as err:
            self.reject(ident, str(err), re="invalid")
            return
        mtype = msg.TYPE
        self._current_type = mtype
        if mtype == "hello":
            self._hello(ident, msg, now)
            return
        client = book.clients.get(ident)
        if client is None:
            if mtype == "estop":  # STOP must never fail: accepted before or without hello
                why = self.credential(ident, msg.token, srv.token, "token")
                if why:
                    self.reject(ident, f"estop {why}", re="estop")
                    return
                self._estop(ident, f"an unregistered client ({msg.reason or 'no reason'})", now)
                return
            srv.rejected += 1
            if now - self._unknown_logged.get(ident, -math.inf) > 5.0:  # a re-hello hint, not a log flood
                if len(self._unknown_logged) > 1000:
                    self._unknown_logged.clear()
                self._unknown_logged[ident] = now
                log.warning("%s from %r before hello: told to say hello", mtype, ident[:32])
            self.reply(ident, mtype, False, f"{mtype} before hello: say hello first (engine restarted?)")
            return
        client.last_seen = now
        if mtype == "bye":
            book.leave(ident)
            return
        if mtype == "ping":
            self.reply(ident, "ping", True)
            return
        if mtype == "describe":
            srv.router.send_multipart([ident, srv._description], zmq.NOBLOCK)
            return
        if mtype == "estop":
            self._estop(ident, client.name, now)
            return
        if mtype == "release_operator":
            book.release(ident)
            self.reply(ident, mtype, True)
            return
        if mtype in OPERATOR_ONLY and ident != book.operator:
            if ident in book.displaced:
                self._refuse_displaced(ident, client, mtype, now)
            elif mtype == "input":
                self.reject(ident, f"input from viewer {client.name}")
            else:
                self.reject(ident, f"{mtype}: only the operator may do this", re=mtype)
            return
        if mtype == "input":
            sample = InputSample(tuple(msg.axes), tuple(msg.buttons), msg.device, now)
            if not srv.inbox.put_input(ident, sample, msg.t_send):
                srv.rejected += 1
            return
        if mtype == "device_lost":
            if not srv.inbox.put(("lost", ident, bool(msg.released), now)):
                srv.rejected += 1
            return
        if not srv.inbox.put(("command", ident, mtype, msg, client.name, now)):
            self.reject(ident, f"{mtype}: engine busy ({srv.inbox.limit} requests waiting); try again", re=mtype)

    def _refuse_displaced(self, ident: bytes, client, mtype: str, now: float) -> None:
        """A former operator's command: an explicit refusal (for input at most once a second)."""
        book = self.srv.book
        why = book.displaced[ident]
        holder = book.holder()
        if mtype == "input":
            if now - client.refused_at < 1.0:
                self.srv.rejected += 1
                return
            client.refused_at = now
        self.reject(
            ident,
            f"{client.name} is no longer the operator: {why}; held by {holder.name if holder else 'nobody'} now. "
            "Say hello as operator to take the role back when it is free",
            re=mtype,
        )

    def _hello(self, ident: bytes, msg: Hello, now: float) -> None:
        srv = self.srv
        why = self.credential(ident, msg.token, srv.token, "token")
        if why:
            self.reject(ident, f"hello {why}", re="hello")
            return
        name = clean_name(msg.name)
        wants = msg.role == "operator"
        why = self.credential(ident, msg.secret, srv.operator_secret, "launch secret") if wants else ""
        if why:
            role, note = srv.book.join(ident, name, False, now)
            note = (
                "the operator role of this engine belongs to the program that started it "
                f"(hello {why}); joined as viewer"
            )
        else:
            role, note = srv.book.join(ident, name, wants, now)
        if role == "operator":  # a new (or reconnected) operator starts disarmed: before any of its input
            srv.inbox.put(("operator", name))
        srv._note("info", f"{name} connected as {role}")
        welcome = Welcome(
            client_id=ident.decode(errors="replace")[:64], role=role, state_url=srv.state_url, note=note or None
        )
        srv.router.send_multipart([ident, encode_message(welcome)], zmq.NOBLOCK)
        srv.router.send_multipart([ident, srv._description], zmq.NOBLOCK)  # the scene's static data

    # ------------------------------------------------------------------ the thread
    def run(self) -> None:
        """The I/O thread: requests in, replies out, the client book kept; Python only in I/O windows."""
        srv = self.srv
        window = srv.window
        poller = zmq.Poller()
        poller.register(srv.router, zmq.POLLIN)
        poller.register(srv._reply_in, zmq.POLLIN)
        next_house = 0.0
        try:
            while not srv._stop.is_set():
                looked = time.monotonic()  # stamped before looking: a hold-up after it cannot pass as silence
                ready = dict(poller.poll(5))
                if srv.router not in ready:
                    srv.inbox.listened = looked  # nothing was waiting then (input age counts)
                window.wait_io()
                if srv._reply_in in ready:
                    for _ in range(1000):
                        try:
                            frames = srv._reply_in.recv_multipart(zmq.NOBLOCK)
                        except zmq.Again:
                            break
                        srv.router.send_multipart(frames, zmq.NOBLOCK)
                if srv.router in ready:
                    for _ in range(2000):
                        if time.perf_counter() >= window.end:
                            # messages still waiting: the loop leaves a share of the next period
                            self.backlog = bool(srv.router.getsockopt(zmq.EVENTS) & zmq.POLLIN)
                            window.wait_io()
                        looked = time.monotonic()
                        try:
                            # as frames: a hello's peer address and CURVE key are read from them (source)
                            parts = srv.router.recv_multipart(zmq.NOBLOCK, copy=False)
                        except zmq.Again:
                            self.backlog = False
                            srv.inbox.listened = looked
                            break
                        now = time.monotonic()
                        frames = [p.bytes for p in parts]
                        if len(frames) != 2:
                            if srv.limits.allow(frames[0] if frames else b"?", now):
                                self.reject(frames[0] if frames else b"?", f"{len(frames)} frames; expected one")
                            continue
                        self._frame = parts[1]
                        self.handle(frames[0], frames[1], now)
                        self._frame = None
                now = time.monotonic()
                if now >= next_house:
                    next_house = now + 0.02
                    srv.book.housekeeping(now)
        except zmq.ZMQError as err:  # sockets closed under us at shutdown: nothing left to serve
            if not srv._stop.is_set():  # not a shutdown: the engine is deaf from now on, so STOP
                self.error = err
                log.error("engine I/O thread stopped: %s", err)
                srv.inbox.estop(time.monotonic(), srv.stats.ticks, f"the engine's I/O thread (ZMQError: {err})")
        except Exception as err:  # a bug here must not leave a silent engine: STOP, say so, end the loop
            self.error = err
            log.exception("engine I/O thread failed")
            srv.inbox.estop(time.monotonic(), srv.stats.ticks, f"the engine's I/O thread ({type(err).__name__})")
