"""The engine process: a fixed-rate loop around a :class:`Session`, served over ZeroMQ.

Two threads.  The **I/O thread** (:mod:`app.engine.io`) owns the request socket: it receives,
rate-limits (per client, before decoding: a flooding client costs a receive and a counter), decodes and
validates every message, keeps the client book (:mod:`app.engine.clients`: hello, roles, tokens, the
launch secret, lapses) and answers what it can answer itself.  What the control step must see it hands
over in a bounded inbox (:mod:`app.engine.inbox`): E-STOPs in a list of their own that the loop empties
first in every tick (no queue, no rate limit, no bound delays them), then commands and input in arrival
order, consecutive inputs of a client with the same buttons coalesced to the newest (button edges are
kept, so no press is lost).
The **loop** runs the control tick at a fixed rate: E-STOPs, inbox, ``session.tick``, publish
every ``publish_every`` ticks, then sleep to the next deadline (sleep, then a short spin for
sub-millisecond accuracy).

Both threads share one interpreter lock.  A thread busy in Python holds it for up to the switch
interval (5 ms) when the other wakes, so the I/O thread works only in the loop's idle time: the
loop opens an *I/O window* after each tick that closes ``IO_MARGIN`` before its next deadline,
and the I/O thread finishes the message in hand and waits once the window has closed (it still
receives nothing while waiting; ZeroMQ buffers).  An E-STOP therefore reaches the control step
within two ticks under any traffic.  If the loop stalls (a long command) the I/O thread carries on
after ``2 periods + 10 ms``.

Roles: the first client asking for ``operator`` gets it (where a launch secret is set, only a
client presenting it); others are viewers.  The role lapses only after ``operator_timeout`` (5 s)
without any message from its holder, with a warning to every client at ``lapse_warning`` (2 s);
the displaced holder is then told so in a refusal of what it sends.  E-STOP is accepted from
every client, also one that has not said ``hello`` (an engine restarted under a client must still
stop); where a token is set the ``estop`` must carry it.  A non-local bind needs CURVE keys
(:mod:`app.net.security`).  Failed authentications are counted and throttled per connection (a
wrong-key handshake per peer address): one client's guessing never holds back another's right key
or token.  Once a second the loop checks itself (a diagnostic in every snapshot: real-time factor, late
ticks, the longest tick); below 90 % of real time for 5 s, or input gone stale while it lagged, raises the
``engine_slow`` alarm, and a tick longer than :data:`STALL_PERIODS` periods (at least :data:`STALL_MIN_S`)
the ``loop_stall`` alarm.

Heavy command work (a megabyte RAO table's parse and the scene rebuilt on it) never runs in a tick (issue 27,
item 2): the scene's :mod:`jobs <app.engine.jobs>` do it in a thread paced by the I/O window (it works only
while the loop sleeps), the loop swaps the result in at the start of a tick, after that tick's E-STOPs and
commands, and the command's reply goes out then.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import secrets
import sys
import threading
import time
from collections import deque
from typing import Any

import zmq

from app.engine.alarm_catalog import SHELVE_DEFAULT_S
from app.engine.clients import ClientBook
from app.engine.inbox import RATE_BURST, RATE_LIMIT, Inbox, LoopStats, RateLimit
from app.engine.io import EngineIO, IOWindow
from app.engine.jobs import Deferred
from app.engine.scene import CommandError, Scene
from app.errors import BosunError
from app.net.codec import encode_message
from app.net.messages import ENGINE, SCENE_MESSAGES, Description, Log, Message, Reply, State
from app.net.security import AuthThrottle, CurveAuthenticator, ServerCurve
from app.net.snapshots import EngineInfo, to_wire
from app.net.transport import TransportError, check_url, is_local, state_url_for

log = logging.getLogger("bosun.engine")


# the loop sleeps until SPIN before its deadline and spins the rest (sleep overshoots by ~0.1 ms);
# the I/O window shuts IO_MARGIN before the deadline, so the I/O thread waits (lock free) by then
SPIN = 0.0002
IO_MARGIN = 0.0003
IO_SHARE = 0.1  # of a period the I/O thread is given when messages wait, even after a long tick
RT_REST = 0.1  # of a period a real-time loop (--realtime) always sleeps, even after a tick that overran (H119)
DEFAULT_RATE = 1000.0  # Hz, the teleop engine's control loop
SLOW_FACTOR = 0.9  # of real time: below it for SLOW_FOR seconds in a row, control suffers (alarm engine_slow)
SLOW_FOR = 5
STALL_PERIODS = 10  # a tick longer than this many periods (and STALL_MIN_S) raises loop_stall (issue 27, item 2)
STALL_MIN_S = 0.1  # s: at 1 kHz ten periods are 10 ms, a scheduler's hiccup on a busy computer, not a stall


def apply_health(alarms, now: float, health: list[tuple[str, bool, str]]) -> None:
    """The loop's health alarms (``loop_stall``, ``engine_slow``: key, raised, text) set at ``now``."""
    alarms.at(now)
    for key, on, text in health:
        alarms.set(key, on, text=text)


def apply_command(session: Scene, mtype: str, msg: Message, name: str) -> Any:
    """A client's command applied to the scene, as the loop applies it (and a replay again, app/engine/replay.py):
    what the scene command returns (a :class:`Deferred` when its work went off the loop); refusals raise
    :class:`CommandError` or :class:`BosunError`."""
    if mtype == "reset":
        session.reset()
    elif mtype == "ack_alarm":
        alarms = getattr(session, "alarms", None)
        n = alarms.ack(msg.key or None) if alarms is not None else 0
        session.note("info", f"{name} acknowledged {n} alarm{'s' if n != 1 else ''}")
    elif mtype == "shelve_alarm":
        minutes = float(SHELVE_DEFAULT_S / 60 if msg.minutes is None else msg.minutes)
        try:
            if minutes == 0:
                session.alarms.unshelve(msg.key, f"by {name}")
            else:
                session.alarms.shelve(msg.key, 60.0 * minutes, who=name)
        except ValueError as err:
            raise CommandError(str(err)) from None
    elif mtype == "pause":
        session.pause(bool(msg.on))
    elif mtype in SCENE_MESSAGES:
        return session.run(msg)
    return None


class EngineServer:
    """Serve a session over ZeroMQ at a fixed rate.

    Parameters
    ----------
    session : Session
    bind : str
        Request URL (tcp://HOST:PORT with PORT 0 for any free port, or ipc://PATH).
    rate : float
        Control rate [Hz], 1..1000 (default 1000: issue 14's targets hold, README benchmarks).
    publish_rate : float
        State messages per second (default 50).
    token : str, optional
        Shared secret; required when ``bind`` is not a loopback or ipc address.
    rate_limit, rate_burst : float, int
        Per-client message budget (default 1000 a second, bursts of 250); the excess is dropped
        unread and counted (``dropped`` in the state), except messages that may be an E-STOP.
    """

    def __init__(
        self,
        session: Scene,
        bind: str = "tcp://127.0.0.1:5555",
        rate: float = DEFAULT_RATE,
        publish_rate: float = 50.0,
        token: str | None = None,
        operator_timeout: float = 5.0,
        context: zmq.Context | None = None,
        client_timeout: float = 60.0,
        curve: ServerCurve | None = None,
        operator_secret: str | None = None,
        lapse_warning: float = 2.0,
        rate_limit: float = RATE_LIMIT,
        rate_burst: int = RATE_BURST,
        realtime: int = 0,
    ) -> None:
        check_url(bind)
        if not 0 <= realtime <= 99:
            raise TransportError(f"real-time priority must be between 1 and 99 (0: none), got {realtime}")
        if not 1.0 <= rate <= 1000.0:
            raise TransportError(f"rate must be between 1 and 1000 Hz, got {rate:g}")
        if not 0.1 <= publish_rate <= rate:
            raise TransportError(f"publish rate must be between 0.1 Hz and the loop rate, got {publish_rate:g}")
        if not is_local(bind) and curve is None:
            raise TransportError(
                f"binding to the non-local address {bind} needs CURVE keys (--curve-secret, --curve-clients; "
                "see 'bosun keys' and the README, remote operation)"
            )
        self.session = session
        self.realtime = realtime  # the loop thread's SCHED_FIFO priority asked for (0: the normal scheduler)
        self.realtime_active = False  # whether it was granted (:meth:`_enter_realtime`)
        self.rests = 0  # ticks after which a real-time loop rested though its next deadline had come (H119)
        self.rate = rate
        self.dt = 1.0 / rate
        self.publish_every = max(1, round(rate / publish_rate))
        self.recorder = None  # a SessionRecorder (app/engine/record.py) while the session is on record
        self._replies: list[tuple[bool, str]] | None = None  # a recorded command's replies
        self.token = token
        self.operator_secret = operator_secret
        self.auth = AuthThrottle()
        self.limits = RateLimit(rate_limit, rate_burst)
        self.inbox = Inbox()
        self.book = ClientBook(self._note, operator_timeout, lapse_warning, client_timeout)
        self.ctx = context or zmq.Context.instance()
        self.router = self.ctx.socket(zmq.ROUTER)
        self.router.setsockopt(zmq.LINGER, 0)
        self.router.setsockopt(zmq.ROUTER_MANDATORY, 0)
        self.router.setsockopt(zmq.MAXMSGSIZE, 1 << 20)
        self.pub = self.ctx.socket(zmq.PUB)
        self.pub.setsockopt(zmq.LINGER, 0)
        self.pub.setsockopt(zmq.SNDHWM, 1000)
        # the loop's replies to commands go to the I/O thread (the only user of the request socket)
        inproc = f"inproc://bosun-replies-{id(self):x}-{secrets.token_hex(4)}"
        self._reply_in = self.ctx.socket(zmq.PULL)
        self._reply_in.setsockopt(zmq.LINGER, 0)
        self._reply_in.bind(inproc)
        self._reply_out = self.ctx.socket(zmq.PUSH)
        self._reply_out.setsockopt(zmq.LINGER, 0)
        self._reply_out.setsockopt(zmq.SNDHWM, 10_000)
        self._reply_out.connect(inproc)
        self.authenticator = None
        if curve is not None:
            self.authenticator = CurveAuthenticator(self.ctx, curve.clients_dir, self.auth)
            self.authenticator.start()
            curve.apply(self.router)
            curve.apply(self.pub)
        self.curve = curve
        try:
            self.router.bind(bind)
            self.pub.bind(state_url_for(bind))
        except zmq.ZMQError as err:
            self.close()
            raise TransportError(f"cannot bind {bind}: {err}") from None
        self.url = self.router.getsockopt(zmq.LAST_ENDPOINT).decode()
        self.state_url = self.pub.getsockopt(zmq.LAST_ENDPOINT).decode()
        self.rejected = 0
        self.stats = LoopStats(self.dt)
        self.estop_ticks: deque = deque(maxlen=10_000)  # ticks from an E-STOP's receipt to the tick that applied it
        self._stop = threading.Event()
        self._pending_latency: float | None = None
        self._log_sent = 0
        self._limited: dict[str, float] = {}
        self.engine_id = secrets.token_hex(4)  # a new value each start: clients tell a restarted engine apart
        self.estops = 0  # estop messages received: clients confirm a STOP by a state counting theirs
        self._second = (time.monotonic(), 0, 0)  # (start, ticks, missed) of the current health window
        self.realtime_factor = 1.0
        self.late_fraction = 0.0
        self.max_tick = 0.0  # s: the longest tick of the last health window (start to the next tick's start)
        self._longest = 0.0  # the longest tick of the health window in progress
        self._deferred: dict[int, tuple[bytes, str]] = {}  # a Deferred command's ticket -> (client, message type)
        self._slow_seconds = 0.0  # seconds in a row below SLOW_FACTOR of real time
        self._stale_seen = 0  # the session's stale-input count at the last health check
        # the I/O window: the I/O thread runs Python only while the loop sleeps (see the module text)
        self.window = IOWindow(self._stop, self.dt)
        self.io = EngineIO(self)
        self._io_thread: threading.Thread | None = None
        self.io_deferred = 0  # ticks started late to give the I/O thread its share
        jobs = getattr(session, "jobs", None)
        if jobs is not None:  # heavy command work off the loop, in the loop's idle time (issue 27, item 2)
            jobs.pace = self.window.wait_job
        self._described = -1  # describe_seq of the cached description
        self._description = b""  # the encoded ``description`` (read by the I/O thread, written by the loop)
        self._refresh_description()

    # ------------------------------------------------------------------ shared by both threads
    @property
    def clients(self) -> dict:
        """The client book's entries by identity (the I/O thread's; the loop only reads them)."""
        return self.book.clients

    @property
    def operator(self) -> bytes | None:
        return self.book.operator

    @operator.setter
    def operator(self, ident: bytes | None) -> None:
        self.book.operator = ident

    def _note(self, level: str, text: str) -> None:
        """A session log line from the I/O thread (the loop writes it: the session is the loop's)."""
        self.inbox.put(("note", level, text))

    def _log_limited(self, key: str, text: str, every: float = 5.0, note: bool = True) -> None:
        """One log line per ``key`` and ``every`` seconds (neither thread ever floods the log)."""
        now = time.monotonic()
        if now - self._limited.get(key, -math.inf) >= every:
            if len(self._limited) > 1000:
                self._limited.clear()
            self._limited[key] = now
            log.warning("%s", text)
            if note:
                self._note("warning", text[:1000])

    # ------------------------------------------------------------------ loop: applying what came in
    def _send_reply(self, ident: bytes, re: str, ok: bool, error: str = "") -> None:
        """A reply from the loop, through the I/O thread."""
        if self._replies is not None:
            self._replies.append((ok, error or ""))
        answer = Reply(re=re, ok=ok, error=error[:1000] if error else None)
        with contextlib.suppress(zmq.ZMQError):
            self._reply_out.send_multipart([ident, encode_message(answer)], zmq.NOBLOCK)

    def _apply_inbox(self) -> None:
        """E-STOPs first; then commands and input in arrival order.  An E-STOP that came after a
        command in this batch is applied again after it (a ``reset`` sent before a STOP cannot undo it)."""
        estops, events = self.inbox.take()
        rec = self.recorder
        for _, tick, source in estops:
            self.session.estop(source=source)
            if rec is not None:
                rec.on_estop(source)
            self.estops += 1
            self.estop_ticks.append(self.stats.ticks - tick + 1)  # 1: the first tick after its receipt
        for event in events:
            kind = event[0]
            if kind == "input":
                _, ident, sample, t_send = event
                if ident != self.operator:  # the role moved on after it came in
                    continue
                self.session.feed(sample, sample.t)
                if rec is not None:
                    rec.on_input(sample, sample.t)
                if t_send is not None:
                    self._pending_latency = t_send
            elif kind == "lost":
                _, ident, released, t = event
                if ident == self.operator:
                    self.session.feed(None, t, released=released)
                    if rec is not None:
                        rec.on_input(None, t, released)
            elif kind == "note":
                self.session.note(event[1], event[2])
                if rec is not None:
                    rec.on_command("note", {"level": event[1], "text": event[2]}, "", True)
            elif kind == "operator":
                changed = getattr(self.session, "operator_changed", None)
                if changed is not None:
                    changed(event[1])
                if rec is not None:
                    rec.on_command("operator_changed", {"name": event[1]}, event[1], True)
            elif kind == "command":
                _, ident, mtype, msg, name, t = event
                self._command(ident, mtype, msg, name)
                for t_recv, _, source in estops:
                    if t_recv > t:
                        self.session.estop(source=source)
                        if rec is not None:
                            rec.on_estop(source)

    def _command(self, ident: bytes, mtype: str, msg: Message, name: str) -> None:
        rec = self.recorder
        if rec is None:
            self._apply_command(ident, mtype, msg, name)
            return
        self._replies = []  # the reply this command gets, for the record
        try:
            self._apply_command(ident, mtype, msg, name)
        finally:
            replies, self._replies = self._replies, None
        ok, error = replies[-1] if replies else (True, "")  # a deferred command: applied, its reply comes later
        rec.on_command(mtype, to_wire(msg.fields()), name, ok, error, deferred=not replies)

    def _apply_command(self, ident: bytes, mtype: str, msg: Message, name: str) -> None:
        try:
            if ident != self.operator:
                raise CommandError(f"{mtype}: {name} is no longer the operator")
            done = apply_command(self.session, mtype, msg, name)
            if isinstance(done, Deferred):  # its work runs off the loop: the reply when it is swapped in
                self._deferred[done.ticket] = (ident, mtype)
                return
        except (CommandError, BosunError) as err:
            self.session.note("warning", f"{mtype} refused: {err}")
            self._send_reply(ident, mtype, False, str(err))
            return
        except Exception as err:  # a bug in a handler: refused, logged, the loop goes on
            self._log_limited("internal", f"{mtype} refused by an internal error: {type(err).__name__}: {err}")
            self._send_reply(ident, mtype, False, f"refused: internal error ({type(err).__name__})")
            return
        self._refresh_description()  # a client that asks ``describe`` after this reply sees the change
        self._send_reply(ident, mtype, True)

    def _jobs(self) -> None:
        """At the start of a tick (after its E-STOPs and commands): a job's result swapped in, and the replies of
        deferred commands (done, refused, or superseded) sent."""
        jobs = getattr(self.session, "jobs", None)
        if jobs is None:
            return
        jobs.poll()
        while jobs.answers:
            ticket, error = jobs.answers.popleft()
            ident, mtype = self._deferred.pop(ticket, (b"", "job"))
            if error:
                self.session.note("warning", f"{mtype} refused: {error}")
            else:
                self._refresh_description()  # a client that asks ``describe`` after this reply sees the change
            if ident:
                self._send_reply(ident, mtype, not error, error)

    def _refresh_description(self) -> None:
        """Encode the scene's description when it changed (the I/O thread answers ``describe`` with it)."""
        seq = self.session.describe_seq
        if seq != self._described:
            wire = to_wire(self.session.describe())
            self._description = encode_message(Description(description=wire))
            self._described = seq
            if self.recorder is not None:
                self.recorder.description(wire)
            if self._io_thread is not None:  # announced to every subscriber; late joiners ask for it
                with contextlib.suppress(zmq.ZMQError):
                    self.pub.send(self._description, zmq.NOBLOCK)

    def publish(self) -> None:
        self._refresh_description()
        snap = self.session.snapshot()
        op = self.clients.get(self.operator) if self.operator else None
        snap.engine = EngineInfo(
            engine_id=self.engine_id,
            estops=self.estops,
            operator=op.name if op else "",
            operator_silent=round(time.monotonic() - op.last_seen, 3) if op else 0.0,
            clients=len(self.clients),
            viewers=[c.name for i, c in list(self.clients.items()) if i != self.operator][:32],
            rejected=self.rejected,
            dropped=self.limits.total_dropped,
            auth_failures=self.auth.failures,
            rate=self.rate,
            realtime_factor=self.realtime_factor,
            late_fraction=self.late_fraction,
            max_tick_ms=round(1e3 * self.max_tick, 1),
            paused=self.session.paused,
        )
        wire = to_wire(snap)
        if self.recorder is not None:
            self.recorder.on_state(wire)
        self.pub.send(encode_message(State(state=wire)), zmq.NOBLOCK)
        while self.session.events:
            mtype, fields = self.session.events.popleft()
            with contextlib.suppress(zmq.ZMQError):
                self.pub.send(encode_message(ENGINE[mtype](**{mtype: fields})), zmq.NOBLOCK)
        for e in self.session.log:
            if e.seq > self._log_sent:
                self.pub.send(encode_message(Log(level=e.level, text=e.text[:1000], t=e.t)), zmq.NOBLOCK)
                self._log_sent = e.seq

    # ------------------------------------------------------------------ loop
    def _health(self, now: float) -> None:
        """Once a second: real-time factor and late ticks of the last second (a diagnostic, shown in the
        engine light's tool tip); the ``engine_slow`` alarm only when control suffers (issue 26): below
        :data:`SLOW_FACTOR` of real time for :data:`SLOW_FOR` seconds in a row, or a second in which the
        input went stale while the loop lagged.  The longest tick of the second (``max_tick``: from a tick's
        start to the next's; a 0.6 s tick is one late tick of fifty in ``late_fraction``) beside them, and the
        ``loop_stall`` alarm when it exceeded :data:`STALL_PERIODS` periods and :data:`STALL_MIN_S` (issue 27,
        item 2)."""
        start, ticks0, missed0 = self._second
        if now - start < 1.0:
            return
        ticks, missed = self.stats.ticks - ticks0, self.stats.missed - missed0
        self.realtime_factor = ticks * self.dt / (now - start)
        self.late_fraction = missed / max(1, ticks)
        self.max_tick, self._longest = self._longest, 0.0  # one long tick counts once in late_fraction: here whole
        self._second = (now, self.stats.ticks, self.stats.missed)
        lagging = self.realtime_factor < SLOW_FACTOR
        self._slow_seconds = self._slow_seconds + (now - start) if lagging else 0.0  # a 5 s stall is 5 s
        inp = getattr(self.session, "input", None)
        stale_count = getattr(inp, "stale_count", 0)
        went_stale = stale_count > self._stale_seen and (lagging or self.late_fraction > 0.05)
        self._stale_seen = stale_count
        alarms = getattr(self.session, "alarms", None)
        if alarms is None:
            return
        alarms.at(now)
        stalled = self.max_tick > max(STALL_PERIODS * self.dt, STALL_MIN_S)
        suffering = self._slow_seconds >= SLOW_FOR or went_stale
        health = [
            (
                "loop_stall",
                stalled,
                f"{alarms.source} control loop stalled: a tick took {1e3 * self.max_tick:.0f} ms "
                f"({self.max_tick / self.dt:.0f} periods)"
                if stalled
                else "",  # cleared after its off-delay; the text keeps the stall's figure
            ),
            (
                "engine_slow",
                suffering or (alarms.active("engine_slow") and lagging),
                f"{alarms.source} engine too slow: {100 * self.realtime_factor:.0f} % of real time"
                + (", input went stale" if went_stale else f" for {self._slow_seconds:.0f} s"),
            ),
        ]
        apply_health(alarms, now, health)
        if self.recorder is not None:  # the loop's own health, which a replay cannot measure: on record
            self.recorder.on_health(now, health)

    def step(self, now: float) -> None:
        """One tick: E-STOPs, inbox, a job's result swapped in, control, latency bookkeeping, publication."""
        self._apply_inbox()
        self._jobs()
        inp = getattr(self.session, "input", None)
        if inp is not None:
            inp.listened = self.inbox.listened  # input ages on the receiver's clock (issue 26, item 9)
        budget = 0.4 * self.dt
        work = getattr(self.session, "take_solver_work", None) if self.recorder is not None else None
        if work is not None:
            work()  # what solved before this tick is not this tick's
        listened = getattr(inp, "listened", None)
        try:
            self.session.tick(now, self.dt, solve_budget=budget)
        except Exception as err:  # a failing control step stops the machines and says so; the loop goes on
            with contextlib.suppress(Exception):
                self.session.estop(source=f"the engine itself ({type(err).__name__} in the control step)")
            self._log_limited("tick", f"control step failed: {type(err).__name__}: {err}; E-STOP latched")
        if self.recorder is not None:  # after the tick's inputs, commands and control step, before its state
            self.recorder.on_tick(self.stats.ticks, now, self.dt, listened, budget, work() if work is not None else [])
        if self._pending_latency is not None:
            self.stats.latencies.append(time.monotonic() - self._pending_latency)
            self._pending_latency = None
        if self.stats.ticks % self.publish_every == 0:
            self.publish()

    def run(self, duration: float | None = None) -> LoopStats:
        """Run until :meth:`stop` (or for ``duration`` seconds); the I/O thread lives as long."""
        self._stop.clear()
        if sys.getswitchinterval() > 0.0005:  # a thread wanting the lock waits at most this long (5 ms default)
            sys.setswitchinterval(0.0005)
        self._io_thread = threading.Thread(target=self.io.run, name="bosun-engine-io", daemon=True)
        self._io_thread.start()
        restore = self._enter_realtime()
        next_t = time.perf_counter()
        end = math.inf if duration is None else next_t + duration
        self._second = (time.monotonic(), self.stats.ticks, self.stats.missed)  # health counts from the loop's start
        last_start = None
        try:
            while not self._stop.is_set() and next_t < end:
                start = time.perf_counter()
                if last_start is not None:
                    self.stats.periods.append(start - last_start)
                    self._longest = max(self._longest, start - last_start)
                last_start = start
                now = time.monotonic()
                self.step(now)
                self.stats.ticks += 1
                self._health(now)
                done = time.perf_counter()
                self.stats.work.append(done - start)
                next_t += self.dt
                if done > next_t:
                    self.stats.missed += 1
                    next_t = done  # do not try to catch up with a burst of ticks
                shut = next_t - IO_MARGIN
                if self.io.backlog and shut < done + IO_SHARE * self.dt:
                    # messages wait and this period leaves them no room: the next tick starts late
                    # (a missed deadline) rather than leave an E-STOP unread behind them
                    shut = done + IO_SHARE * self.dt
                    next_t = shut + IO_MARGIN
                    self.stats.missed += 1
                    self.io_deferred += 1
                self.window.open_until(shut)
                remaining = next_t - time.perf_counter()
                if restore is not None and remaining < RT_REST * self.dt + SPIN:
                    # on SCHED_FIFO a loop that never sleeps keeps its core from every normal program, the GUI's
                    # STOP among them (H119): it rests anyway, and the next tick starts late (a missed deadline)
                    time.sleep(RT_REST * self.dt)
                    self.rests += 1
                    next_t = max(next_t, time.perf_counter())
                    remaining = 0.0
                if remaining > SPIN:
                    time.sleep(remaining - SPIN)
                while time.perf_counter() < next_t:
                    pass
        finally:
            self._stop.set()
            self.window.open_until(math.inf)
            if restore is not None:
                self._leave_realtime(restore)
            self._io_thread.join(timeout=5)
        return self.stats

    def _enter_realtime(self) -> tuple[int, Any] | None:
        """Put the loop's thread (this one; the I/O thread, started before, keeps the normal scheduler) on
        SCHED_FIFO at ``realtime`` if asked, as ros2_control's controller manager does for its loop (priority 50,
        on any kernel): programs on the normal scheduler (clients, viewers, the GUI) no longer preempt a tick.
        Not granted (no CAP_SYS_NICE, no rtprio limit, not Linux), or refused on a machine whose process may use
        one CPU only (the loop would share it with the GUI, whose STOP must never wait on it: H119): one warning,
        and the loop runs as before.  Returns what :meth:`_leave_realtime` restores (None: nothing changed)."""
        if not self.realtime:
            return None
        if hasattr(os, "sched_getaffinity") and len(os.sched_getaffinity(0)) < 2:
            log.warning("real-time priority %d not taken: this process may use one CPU only, which the GUI "
                        "needs too (H119); the loop runs on the normal scheduler", self.realtime)  # fmt: skip
            return None
        try:
            before = (os.sched_getscheduler(0), os.sched_getparam(0))
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(self.realtime))
        except (AttributeError, OSError) as exc:
            log.warning("real-time priority %d not granted (%s): the loop runs on the normal scheduler",
                        self.realtime, getattr(exc, "strerror", None) or exc)  # fmt: skip
            return None
        self.realtime_active = True
        log.info("control loop on SCHED_FIFO, priority %d", self.realtime)
        return before

    def _leave_realtime(self, before: tuple[int, Any]) -> None:
        """The thread's scheduler as it was before :meth:`run` (a caller's thread is not left real-time)."""
        with contextlib.suppress(OSError):
            os.sched_setscheduler(0, *before)

    def record(self, path: str, seed: int = 0) -> None:
        """Put the session on record in the MCAP file ``path`` (:mod:`app.engine.record`) from the next tick."""
        from app.engine.record import SessionRecorder

        rec = SessionRecorder(path, type(self.session.snapshot()), type(self.session.describe()))
        scene = getattr(self.session, "replay_args", dict)()
        alarms = getattr(self.session, "alarms", None)
        if alarms is not None:  # its time stamps follow the ticks from this offset (app/engine/alarms.py)
            scene["alarm_wall_offset"] = alarms.wall_offset
        rec.session(getattr(self.session, "KIND", ""), self.rate, self.rate / self.publish_every, seed, scene)
        rec.description(to_wire(self.session.describe()))
        self.recorder = rec

    def stop(self) -> None:
        self._stop.set()

    def close(self) -> None:
        if hasattr(self, "_stop"):
            self._stop.set()
        rec = getattr(self, "recorder", None)
        if rec is not None:
            rec.close()  # the file finished: its summary and index written
        jobs = getattr(getattr(self, "session", None), "jobs", None)
        if jobs is not None:
            jobs.close()  # a pending job's thread stops at its next step
        closer = getattr(getattr(self, "session", None), "close", None)
        if closer is not None:
            closer()  # the scene's worker processes
        io = getattr(self, "_io_thread", None)
        if io is not None and io.is_alive():
            io.join(timeout=5)
        for s in ("router", "pub", "_reply_in", "_reply_out"):
            sock = getattr(self, s, None)
            if sock is not None:
                sock.close(0)
        if getattr(self, "authenticator", None) is not None:
            self.authenticator.stop()
            self.authenticator = None
