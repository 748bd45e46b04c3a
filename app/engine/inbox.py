"""What the engine's two threads share: per-client rate limits, the inbox from the I/O thread to the loop,
and the loop's tick statistics."""

from __future__ import annotations

import math
import threading
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.teleop.devices import InputSample

RATE_LIMIT = 1000.0  # messages a second per client, sustained; the joystick sends 500 and pings 2
RATE_BURST = 250  # messages a client may send at once
INBOX_LIMIT = 1024  # commands and inputs waiting for the loop; past it, refused ("engine busy")


@dataclass
class LoopStats:
    """Tick timing of the fixed-rate loop, over a ring buffer of recent ticks."""

    period: float
    periods: deque = field(default_factory=lambda: deque(maxlen=200_000))
    work: deque = field(default_factory=lambda: deque(maxlen=200_000))
    latencies: deque = field(default_factory=lambda: deque(maxlen=200_000))
    missed: int = 0
    ticks: int = 0

    def summary(self) -> dict[str, Any]:
        p = np.array(self.periods) if self.periods else np.array([math.nan])
        w = np.array(self.work) if self.work else np.array([math.nan])
        lat = np.array(self.latencies) if self.latencies else np.array([math.nan])

        def pct(a, q):
            return float(np.percentile(a, q)) if np.all(np.isfinite(a)) else None

        return {
            "ticks": self.ticks,
            "period_target_ms": self.period * 1e3,
            "period_p50_ms": pct(p, 50) and pct(p, 50) * 1e3,
            "period_p99_ms": pct(p, 99) and pct(p, 99) * 1e3,
            "period_max_ms": float(np.max(p)) * 1e3 if np.all(np.isfinite(p)) else None,
            "jitter_p99_ms": pct(np.abs(p - self.period), 99) and pct(np.abs(p - self.period), 99) * 1e3,
            "work_p99_ms": pct(w, 99) and pct(w, 99) * 1e3,
            "missed_deadlines": self.missed,
            "latency_p50_ms": pct(lat, 50) and pct(lat, 50) * 1e3,
            "latency_p99_ms": pct(lat, 99) and pct(lat, 99) * 1e3,
            "latency_samples": len(self.latencies),
        }


class RateLimit:
    """Token buckets per client: ``rate`` messages a second, bursts of ``burst``; the excess counted."""

    def __init__(self, rate: float = RATE_LIMIT, burst: int = RATE_BURST, clients: int = 4096) -> None:
        self.rate, self.burst, self.max_clients = rate, float(burst), clients
        self.buckets: dict[bytes, list[float]] = {}  # ident -> [tokens, last refill time]
        self.dropped: dict[bytes, int] = {}
        self.total_dropped = 0

    def allow(self, ident: bytes, now: float) -> bool:
        b = self.buckets.get(ident)
        if b is None:
            if len(self.buckets) >= self.max_clients:  # identities are cheap to invent: forget, never grow
                self.buckets.clear()
                self.dropped.clear()
            b = self.buckets[ident] = [self.burst, now]
        b[0] = min(self.burst, b[0] + (now - b[1]) * self.rate)
        b[1] = now
        if b[0] >= 1.0:
            b[0] -= 1.0
            return True
        self.dropped[ident] = self.dropped.get(ident, 0) + 1
        self.total_dropped += 1
        return False


class Inbox:
    """What the I/O thread hands the loop: E-STOPs apart, then commands and input in arrival order.

    Bounded (``limit`` events; E-STOPs are never refused).  Consecutive inputs of one client with the
    same buttons and device are coalesced to the newest: the loop takes the newest input per client
    each tick, and a button edge (a press, a release, a stop button) always survives."""

    def __init__(self, limit: int = INBOX_LIMIT) -> None:
        self.limit = limit
        self.lock = threading.Lock()
        self.estops: list[tuple[float, int, str]] = []  # (receive time, tick at receipt, source)
        self.events: list[tuple] = []
        self.coalesced = 0
        self.refused = 0
        self.listened = -math.inf  # monotonic time the I/O thread last found the request socket empty

    def estop(self, now: float, tick: int, source: str) -> None:
        with self.lock:
            self.estops.append((now, tick, source))

    def put(self, event: tuple) -> bool:
        with self.lock:
            if len(self.events) >= self.limit:
                self.refused += 1
                return False
            self.events.append(event)
            return True

    def put_input(self, ident: bytes, sample: InputSample, t_send: float | None) -> bool:
        with self.lock:
            last = self.events[-1] if self.events else None
            if (
                last is not None
                and last[0] == "input"
                and last[1] == ident
                and last[2].buttons == sample.buttons
                and last[2].device == sample.device
            ):
                self.events[-1] = ("input", ident, sample, t_send)
                self.coalesced += 1
                return True
            if len(self.events) >= self.limit:
                self.refused += 1
                return False
            self.events.append(("input", ident, sample, t_send))
            return True

    def take(self) -> tuple[list, list]:
        with self.lock:
            estops, self.estops = self.estops, []
            events, self.events = self.events, []
        return estops, events
