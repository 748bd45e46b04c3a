"""The ADS bridge: one pyads connection to the lab's TwinCAT PLC, in its own thread.

The engine never waits on the PLC and the bridge never calls into the engine: everything the bridge
reads or learns goes into :attr:`AdsBridge.updates` (a :class:`queue.Queue` of the typed updates below)
which the engine drains in its tick; the engine hands writes to the bridge with :meth:`AdsBridge.write`
(a queue too).  All pyads calls happen in the bridge thread; pyads' notification callbacks (its own
thread) only decode and put on the queue.

Link watchdog
-------------
* **Connect** with a TCP probe bounded by ``connect_timeout`` (the ADS library's own connect has no
  timeout), then ``read_state`` under the ADS timeout; every symbol of the table is looked up and its
  size checked (:func:`app.plc.symbols.check_size`): a symbol missing or of another size is reported
  and never read or written.
* **Lost**: any failed read or write (each bounded by the ADS timeout) ends the connection: the
  notifications are deleted, the handles released and the port closed (in that order: closing a port
  that still holds a notification on a dead link crashes the ADS library), and
  :class:`LinkDown` is posted.  Writes waiting in the queue are **dropped** (:class:`Dropped`), never
  sent after the gap; a write older than ``max_command_age`` is dropped too.
* **Reconnect** with exponential backoff (``backoff``: first and longest wait).  On every connect the
  bridge first writes ``MAIN.bStop := TRUE`` if the engine's STOP is latched (:meth:`set_stop`) and reads
  it back (:class:`StopConfirmed`), then returns the momentary inputs to rest (``bReset`` flags FALSE, the
  winch's spring-return speed ``u`` := 0), reads every notified symbol once and subscribes again.
"""

from __future__ import annotations

import contextlib
import ctypes
import queue
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from app.errors import BosunError, one_line
from app.plc.symbols import ADS_TCP_PORT, AMS_PORT, Symbol, check_size, lab_symbols


class PlcTargetError(BosunError):
    """An AMS address the user gave that cannot be used."""


@dataclass(frozen=True)
class PlcTarget:
    """Where the PLC is: AMS Net ID and port, the host to reach it (default: the Net ID's first four
    numbers) and, optionally, this machine's own AMS Net ID (the PLC needs a route back to it)."""

    net_id: str
    port: int = AMS_PORT
    host: str = ""
    local_net_id: str = ""

    @classmethod
    def parse(cls, text: str, host: str | None = None, local_net_id: str | None = None) -> PlcTarget:
        """``AMS_NET_ID[:PORT]`` as given to ``--plc`` (e.g. ``192.168.90.150.1.1:851``)."""
        net, _, port_text = text.strip().partition(":")
        _check_net_id(net, "--plc")
        try:
            port = int(port_text) if port_text else AMS_PORT
        except ValueError:
            raise PlcTargetError(f"--plc {text}: the port after ':' must be a number (e.g. 851)") from None
        if not 1 <= port <= 65535:
            raise PlcTargetError(f"--plc {text}: port {port} is out of range 1..65535")
        if local_net_id:
            _check_net_id(local_net_id, "--plc-local-id")
        return cls(net, port, host or ".".join(net.split(".")[:4]), local_net_id or "")

    def __str__(self) -> str:
        return f"{self.net_id}:{self.port} at {self.host}"


def _check_net_id(net: str, flag: str) -> None:
    parts = net.split(".")
    if len(parts) != 6 or not all(p.isdigit() and 0 <= int(p) <= 255 for p in parts):
        raise PlcTargetError(
            f"{flag} {net}: an AMS Net ID is six numbers 0..255 separated by dots (e.g. 192.168.90.150.1.1)"
        )


# ----------------------------------------------------------------------------- updates (bridge → engine)
@dataclass(frozen=True)
class LinkUp:
    t: float  # time.monotonic() of the event
    reconnects: int  # connections made before this one
    ads_state: int  # the PLC's ADS state (5: RUN)
    problems: tuple[str, ...] = ()  # symbols missing or of another size (never used), one line each
    unusable: tuple[str, ...] = ()  # their names
    notes: tuple[str, ...] = ()  # enumeration widths taken from the PLC


@dataclass(frozen=True)
class LinkDown:
    t: float
    error: str  # one line
    was_up: bool  # False: a connect attempt failed


@dataclass(frozen=True)
class Value:
    t: float
    name: str
    value: Any  # decoded (bool, int, float, list, dict)
    how: str  # notify | poll | read (after connect and every ``refresh``)


@dataclass(frozen=True)
class WriteFailed:
    t: float
    name: str
    error: str


@dataclass(frozen=True)
class Dropped:
    t: float
    names: tuple[str, ...]
    reason: str


@dataclass(frozen=True)
class StopConfirmed:
    t: float
    value: bool  # MAIN.bStop as read back after writing it


@dataclass(frozen=True)
class AdsState:
    t: float
    ads_state: int  # 5 RUN, 6 STOP, 15 CONFIG …


Update = LinkUp | LinkDown | Value | WriteFailed | Dropped | StopConfirmed | AdsState


@dataclass
class _Write:
    name: str
    value: Any
    t: float
    pulse: float = 0.0  # > 0: write FALSE again after this many seconds


@dataclass
class BridgeStats:
    """Counters of the bridge thread (read by tests and the log)."""

    connects: int = 0
    reads: int = 0
    writes: int = 0
    notifications: int = 0
    dropped_updates: int = 0
    attempts: list[float] = field(default_factory=list)  # clock times of the last 100 connect attempts
    written: list[tuple[str, Any]] = field(default_factory=list)  # the last 64 writes (name, value)


ADS_RUN = 5
STOP = "MAIN.bStop"


class AdsBridge:
    """A pyads connection to one PLC in its own thread.

    Parameters
    ----------
    target : PlcTarget
    symbols : dict          the symbol table (default :func:`app.plc.symbols.lab_symbols`)
    connect_timeout : float s: TCP connect probe
    ads_timeout : float     s: every ADS request (read, write, state)
    backoff : (float, float)  s: first and longest wait between connect attempts (doubling)
    refresh : float         s: notified symbols are also read this often (a lost notification cannot
                            leave a stale state) and the PLC's ADS state checked
    max_command_age : float s: a write older than this when its turn comes is dropped
    ads : module or None    pyads (injected by tests); imported when the thread starts
    """

    def __init__(
        self,
        target: PlcTarget,
        symbols: dict[str, Symbol] | None = None,
        *,
        connect_timeout: float = 2.0,
        ads_timeout: float = 0.5,
        backoff: tuple[float, float] = (0.25, 5.0),
        refresh: float = 1.0,
        max_command_age: float = 0.5,
        ads: Any = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.target = target
        self.symbols = dict(symbols or lab_symbols())
        self.connect_timeout, self.ads_timeout = float(connect_timeout), float(ads_timeout)
        self.backoff, self.refresh, self.max_command_age = backoff, float(refresh), float(max_command_age)
        self.clock = clock
        self.updates: queue.Queue[Update] = queue.Queue(maxsize=20_000)
        self.stats = BridgeStats()
        self._ads = ads
        self._writes: queue.Queue[_Write] = queue.Queue()
        self._stop_latched = threading.Event()
        self._stop_now = threading.Event()
        self._quit = threading.Event()
        self._wake = threading.Event()
        self._thread: threading.Thread | None = None
        self._plc: Any = None
        self._usable: dict[str, Symbol] = {}
        self._handles: dict[str, int] = {}
        self._notes: list[tuple[int, int]] = []
        self._by_address: dict[tuple[int, int], Symbol] = {}  # notified symbols by index group and offset
        self._addresses: dict[str, tuple[int, int]] = {}
        self._pulses: list[tuple[float, str]] = []
        self.connected = False

    # ------------------------------------------------------------------ engine side (any thread)
    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="bosun-plc-ads", daemon=True)
        self._thread.start()

    def write(self, name: str, value: Any, pulse: float = 0.0) -> None:
        """Queue a write by name (never blocks).  ``pulse`` > 0: a momentary flag, FALSE again after that long."""
        if name not in self.symbols:
            raise KeyError(name)
        self._writes.put(_Write(name, value, self.clock(), pulse))
        self._wake.set()

    def set_stop(self, latched: bool) -> None:
        """The engine's STOP latch: while set, ``MAIN.bStop := TRUE`` is written at once and on every reconnect."""
        if latched:
            self._stop_latched.set()
            self._stop_now.set()
        else:
            self._stop_latched.clear()
        self._wake.set()

    def close(self, timeout: float = 5.0) -> None:
        """Stop the thread (it closes the connection); waits at most ``timeout`` seconds."""
        self._quit.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)

    @property
    def alive(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    # ------------------------------------------------------------------ bridge thread
    def _post(self, update: Update) -> None:
        try:
            self.updates.put_nowait(update)
        except queue.Full:  # the engine stopped draining: values are dropped, the link events too
            self.stats.dropped_updates += 1

    def _run(self) -> None:
        if self._ads is None:
            import pyads

            self._ads = pyads
            quiet_ads_library()
        delay = self.backoff[0]
        was_up = False
        while not self._quit.is_set():
            self.stats.attempts.append(self.clock())
            del self.stats.attempts[:-100]
            try:
                self._connect()
            except Exception as err:
                self._teardown()
                self._drop_writes("the PLC link is down")
                self._post(LinkDown(self.clock(), _describe(err), False))
                self._quit.wait(delay)
                delay = min(2.0 * delay, self.backoff[1])
                continue
            delay = self.backoff[0]
            was_up = True
            try:
                self._serve()
            except Exception as err:
                self._post(LinkDown(self.clock(), _describe(err), was_up))
                self._quit.wait(self.backoff[0])  # a first short wait: the link may be back at once
            finally:
                self.connected = False
                self._teardown()
                self._drop_writes("the PLC link was lost before they were written")
        self._teardown()

    def _connect(self) -> None:
        ads, t = self._ads, self.target
        with socket.create_connection((t.host, ADS_TCP_PORT), timeout=self.connect_timeout):
            pass  # the router answers: the ADS library's own (unbounded) connect will not hang
        if t.local_net_id:
            ads.set_local_address(t.local_net_id)
        plc = ads.Connection(t.net_id, t.port, t.host)
        plc.open()
        self._plc = plc
        plc.set_timeout(int(1000 * self.ads_timeout))
        ads_state, _ = plc.read_state()
        problems, notes = self._check_symbols()
        self.stats.connects += 1
        if self._stop_latched.is_set():  # first of all: the latched STOP
            self._write_stop()
        for name in list(self._usable):  # momentary inputs back at rest; nothing else is written
            if name.endswith(".bReset") or name.endswith(".bResetScale"):
                self._raw_write(name, False)
        if "MAIN.winch.u" in self._usable:
            self._raw_write("MAIN.winch.u", 0.0)
        self._pulses.clear()
        self._drop_writes("written before the link came back")  # queued during the connect: not replayed
        for sym in self._usable.values():
            if sym.access in ("notify", "poll"):
                self._handles[sym.name] = plc.get_handle(sym.name)
        for sym in self._usable.values():
            if sym.access == "notify":
                self._read(sym, "read")
                self._subscribe(sym)
        self.connected = True
        unusable = tuple(n for n in self.symbols if n not in self._usable)
        self._post(
            LinkUp(self.clock(), self.stats.connects - 1, int(ads_state), tuple(problems), unusable, tuple(notes))
        )

    def _check_symbols(self) -> tuple[list[str], list[str]]:
        from pyads.pyads_ex import adsGetSymbolInfo  # the lookup AdsSymbol uses: size and declared type

        self._usable.clear()
        self._addresses.clear()
        problems, notes = [], []
        plc = self._plc
        for name, sym in self.symbols.items():
            try:
                info = adsGetSymbolInfo(plc._port, plc._adr, name)
            except self._ads.ADSError as err:
                if not 0x700 <= (getattr(err, "err_code", None) or 0) < 0x740:  # not the device's answer: the link
                    raise
                problems.append(f"{name}: not on the PLC ({one_line(str(err), 80)})")  # e.g. 0x710 symbol not found
                continue
            use, note = check_size(sym, int(info.size), str(info.symbol_type))
            if use is None:
                problems.append(note)
                continue
            if note:
                notes.append(note)
            self._usable[name] = use
            address = (int(info.iGroup), int(info.iOffs))
            self._addresses[name] = address
            if sym.access == "notify":
                self._by_address[address] = use
        return problems, notes

    def _subscribe(self, sym: Symbol) -> None:
        ads = self._ads
        attr = ads.NotificationAttrib(sym.size)
        address = self._addresses[sym.name]
        handles = self._plc.add_device_notification(address, attr, self._on_notification)
        self._notes.append(handles)

    def _on_notification(self, notification: Any, data: Any) -> None:
        """pyads' callback (the ADS library's thread): decode and queue, nothing else."""
        try:
            sym = self._by_address.get(tuple(data))
            if sym is None:
                return
            head = notification.contents
            n = min(int(head.cbSampleSize), sym.size)
            offset = type(head).data.offset
            raw = bytes((ctypes.c_ubyte * n).from_address(ctypes.addressof(head) + offset))
            self.stats.notifications += 1
            self._post(Value(self.clock(), sym.name, sym.decode(raw), "notify"))
        except Exception:  # a callback must never raise into the ADS library
            return

    def _read(self, sym: Symbol, how: str) -> None:
        ctype = ctypes.c_ubyte * sym.size
        handle = self._handles.get(sym.name)
        raw = self._plc.read_by_name("" if handle else sym.name, ctype, return_ctypes=True, handle=handle)
        self.stats.reads += 1
        self._post(Value(self.clock(), sym.name, sym.decode(bytes(raw)), how))

    def _raw_write(self, name: str, value: Any) -> None:
        sym = self._usable[name]
        raw = sym.encode(value)
        self._plc.write_by_name(name, raw, ctypes.c_ubyte * len(raw))
        self.stats.writes += 1
        self.stats.written.append((name, value))
        del self.stats.written[:-64]

    def _write_stop(self) -> None:
        if STOP not in self._usable:
            self._post(WriteFailed(self.clock(), STOP, "MAIN.bStop is not usable on this PLC"))
            return
        self._raw_write(STOP, True)
        back = self._usable[STOP].decode(bytes(self._plc.read_by_name(STOP, ctypes.c_ubyte * 1, return_ctypes=True)))
        self._post(StopConfirmed(self.clock(), bool(back)))

    def _drop_writes(self, reason: str) -> None:
        names = []
        while True:
            try:
                names.append(self._writes.get_nowait().name)
            except queue.Empty:
                break
        if names:
            self._post(Dropped(self.clock(), tuple(names), reason))

    def _serve(self) -> None:
        """Connected: STOP first, then writes in order, due pulses, polls and the refresh, until an error."""
        now = self.clock()
        due = {s.name: now for s in self._usable.values() if s.access == "poll"}
        next_refresh = now + self.refresh
        while not self._quit.is_set():
            if self._stop_now.is_set():
                self._stop_now.clear()
                if self._stop_latched.is_set():
                    self._write_stop()
            self._do_writes()
            now = self.clock()
            for t_due, name in [p for p in self._pulses if p[0] <= now]:
                self._pulses.remove((t_due, name))
                self._raw_write(name, False)
            for name, t_due in due.items():
                if t_due <= now:
                    sym = self._usable[name]
                    self._read(sym, "poll")
                    due[name] = max(t_due + sym.period, now)  # no burst of reads to catch up
            if now >= next_refresh:
                next_refresh = now + self.refresh
                state, _ = self._plc.read_state()
                self._post(AdsState(now, int(state)))
                for sym in self._usable.values():
                    if sym.access == "notify":
                        self._read(sym, "read")
            wake = min([*due.values(), next_refresh, *(p[0] for p in self._pulses)])
            self._wake.wait(max(0.0, min(wake - self.clock(), 0.05)))
            self._wake.clear()

    def _do_writes(self) -> None:
        while not self._stop_now.is_set():  # a STOP that comes in between goes first
            try:
                w = self._writes.get_nowait()
            except queue.Empty:
                return
            now = self.clock()
            if now - w.t > self.max_command_age:
                self._post(Dropped(now, (w.name,), f"older than {self.max_command_age:g} s when its turn came"))
                continue
            if w.name not in self._usable:
                self._post(WriteFailed(now, w.name, f"{w.name} is not usable on this PLC (see the link's problems)"))
                continue
            self._raw_write(w.name, w.value)
            if w.pulse > 0:
                self._pulses.append((now + w.pulse, w.name))

    def _teardown(self) -> None:
        """Notifications first, then handles, then the port (never the port with notifications left)."""
        plc, self._plc = self._plc, None
        self.connected = False
        if plc is None:
            return
        for handles in self._notes:
            with contextlib.suppress(Exception):
                plc.del_device_notification(*handles)
        self._notes.clear()
        for handle in self._handles.values():
            with contextlib.suppress(Exception):
                plc.release_handle(handle)
        self._handles.clear()
        self._by_address.clear()
        self._addresses.clear()
        with contextlib.suppress(Exception):
            plc.close()


def quiet_ads_library() -> None:
    """Silence the ADS library's own log on stderr (Linux: Beckhoff's AdsLib prints a line for every failed
    frame, hundreds while a link is down); the bridge reports the link's state itself, one line per change."""
    with contextlib.suppress(Exception):
        from pyads import pyads_ex

        ctypes.c_int.in_dll(pyads_ex._adsDLL, "_ZN6Logger8logLevelE").value = 4  # above error: nothing


def _describe(err: BaseException) -> str:
    """One line for a link error: timeouts and refusals in words."""
    if isinstance(err, socket.timeout | TimeoutError):
        return "no answer from the PLC's router (connect timeout)"
    if isinstance(err, ConnectionRefusedError):
        return "connection refused: no ADS router at that address"
    if isinstance(err, OSError) and not hasattr(err, "err_code"):
        return one_line(f"network: {err.strerror or err}", 200)
    code = getattr(err, "err_code", None)
    if code == 1861:
        return "the PLC did not answer within the ADS timeout"
    return one_line(f"{type(err).__name__}: {err}", 200)


__all__ = [
    "STOP",
    "AdsBridge",
    "AdsState",
    "Dropped",
    "LinkDown",
    "LinkUp",
    "PlcTarget",
    "PlcTargetError",
    "StopConfirmed",
    "Update",
    "Value",
    "WriteFailed",
]
