"""Engine alarms, managed as ANSI/ISA-18.2 describes: rationalised, delayed against chatter, shelvable.

Each engine scene keeps one :class:`AlarmList`.  Every control tick it states each condition
(``set(key, active)``, or ``set(key, value=…)`` for an analog one); an alarm is *raised* when its
condition has held for the definition's on-delay, *cleared* when it has been gone for the off-delay
(analog alarms clear only below ``limit − deadband``), and stays in the list until it is both cleared
and acknowledged (the ISA-18.2 life cycle: an alarm that came and went unseen still asks to be
acknowledged).  Priority, delays and deadbands come from the rationalisation table
(:mod:`app.engine.alarm_catalog`), never from the call site.

*First-out*: the first **trip** alarm (one that stops or holds the machine) raised while no other trip
alarm was active; in a cascade (E-STOP, then inputs going stale and machines reporting limits) it
names the cause.  Warnings that stop nothing never take the mark.

*Shelving* (ISA-18.2 §12.3): the operator may shelve a shelvable alarm for a limited time
(:data:`~app.engine.alarm_catalog.SHELVE_MAX_S`); it stays tracked but does not annunciate, and it
returns by itself when the time is up.  Both are log lines.

Published in every snapshot as ``alarms``: a list of dicts (see :meth:`AlarmList.snapshot`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict

from app.engine.alarm_catalog import SHELVE_MAX_S, AlarmDef, definition
from app.net.snapshots import Alarm  # one alarm record: the engine's list holds what the wire carries

SEVERITIES = ("info", "warning", "critical")


class AlarmList:
    """The alarms of one engine.

    Parameters
    ----------
    source : str
        Source shown with each alarm: the engine, as the operator names it ("Teleop", "Crane head",
        "Motion-Lab", "GUI").
    note : callable(level, text), optional
        Receives a log line when an alarm is raised, cleared, shelved or unshelved.
    clock : callable, optional
        Wall-clock seconds for the time stamps; default: the engine's tick (:meth:`at`) on the wall clock — the
        wall time at start plus the monotonic time since, so the stamps follow the ticks (a replay of a recorded
        session, given the same :attr:`wall_offset`, stamps its alarms alike), ``time.time`` before the first tick.
    """

    def __init__(self, source: str, note: Callable[[str, str], None] | None = None, clock=None) -> None:
        self.source = source
        self._note = note or (lambda level, text: None)
        #: wall-clock minus monotonic seconds, fixed at start: a tick's wall time is wall_offset + its time
        self.wall_offset = time.time() - time.monotonic()
        self._clock = clock or self._tick_wall
        self.items: dict[str, Alarm] = {}
        self._since: dict[str, tuple[bool, float]] = {}  # key -> (condition, engine time it became so)
        self._now: float | None = None
        self._shelf_end: dict[str, float] = {}  # key -> engine time its shelving ends
        self.raised = 0  # alarms raised since start (the rate benchmarks count them)

    # ------------------------------------------------------------------ time
    def _tick_wall(self) -> float:
        return time.time() if self._now is None else self.wall_offset + self._now

    def at(self, now: float) -> None:
        """The engine's (monotonic) time of this tick: on- and off-delays count in it, and shelving ends."""
        self._now = now
        self._expire_shelving()

    def _time(self) -> float:
        return time.monotonic() if self._now is None else self._now

    # ------------------------------------------------------------------ conditions
    def set(
        self,
        key: str,
        active: bool | None = None,
        severity: str | None = None,
        text: str = "",
        source: str | None = None,
        *,
        value: float | None = None,
    ) -> None:
        """State a condition; raises, updates or clears the alarm ``key``.

        ``value``: an analog alarm's measure (``active`` then follows from the definition's limit and
        deadband).  ``severity`` is taken only for a key the rationalisation table does not know (it
        should know every key: a test holds it so).
        """
        d = definition(key)
        a = self.items.get(key)
        is_on = a is not None and a.active
        if value is not None and d is not None and d.analog:
            v = float(value)
            active = math.isfinite(v) and (v > d.limit if not is_on else v > d.limit - d.deadband)
        active = bool(active)
        if severity is None or d is not None:
            severity = d.priority if d is not None else "warning"
        if severity not in SEVERITIES:
            raise ValueError(f"severity must be one of {SEVERITIES}, got {severity!r}")
        if not self._delayed(key, active, is_on, d):
            if is_on and text and text != a.text and (active or (d is not None and d.analog)):
                # still active during its off-delay: an analog alarm's live figure goes on; a condition that is
                # no longer true keeps the words it was raised with (its present text describes nothing:
                # "…: the commanded direction is blocked" with no joint named)
                a.text = text
            return
        if active:
            self._raise(key, d, severity, text, source)
        elif is_on:
            a.active, a.t_cleared = False, self._clock()
            self._note("info", f"alarm cleared, {a.source}: {a.text}")
            self._drop_done()

    def _delayed(self, key: str, active: bool, is_on: bool, d: AlarmDef | None) -> bool:
        """Whether a change of the condition has lasted its delay (True: act on it now)."""
        now = self._time()
        last, since = self._since.get(key, (active, now))
        if last != active:
            since = now
        self._since[key] = (active, since)
        if active == is_on:
            return active  # no change: an active alarm may still take a new text
        delay = 0.0 if d is None else (d.on_delay if active else d.off_delay)
        return now - since >= delay - 1e-9

    def _raise(self, key: str, d: AlarmDef | None, severity: str, text: str, source: str | None) -> None:
        a = self.items.get(key)
        if a is not None and a.active:
            if text and text != a.text:
                a.text = text  # a live figure (e.g. % of time saturated)
            return
        trip = d is not None and d.trip
        # the first trip of a cascade; a shelved alarm (still tracked) takes no part
        first = trip and not any(x.active and x.shelved_until is None and _is_trip(x.key) for x in self.items.values())
        text = text or (d.title if d is not None else key)
        if a is None:
            a = Alarm(
                key=key, severity=severity, source=source or self.source, text=text, active=True, acked=False,
                t_raised=self._clock(), t_cleared=None, first_out=first,
            )  # fmt: skip
            self.items[key] = a
        else:  # raised again before it was acknowledged: one entry, counted
            a.active, a.acked, a.t_cleared, a.first_out = True, False, None, first
            a.t_raised, a.count = self._clock(), a.count + 1
            a.severity, a.text = severity, text
        self.raised += 1
        if a.shelved_until is None:
            self._note("error" if severity == "critical" else "warning", f"ALARM {a.source}: {a.text}")

    # ------------------------------------------------------------------ operator actions
    def ack(self, key: str | None = None) -> int:
        """Acknowledge one alarm (by key) or all (None); returns how many were newly acknowledged."""
        n = 0
        for a in self.items.values():
            if (key is None or a.key == key) and not a.acked:
                a.acked = True
                n += 1
        self._drop_done()
        return n

    def shelve(self, key: str, seconds: float, who: str = "the operator") -> str:
        """Shelve ``key`` for ``seconds`` (≤ SHELVE_MAX_S); returns the log line.  Raises ValueError for an
        alarm that is not shown, not shelvable, or a time out of range."""
        d = definition(key)
        if d is None or not d.shelvable:
            raise ValueError(f"{d.title if d else key}: this alarm may not be shelved")
        a = self.items.get(key)
        if a is None:
            raise ValueError(f"no alarm {key!r} to shelve")
        if not (math.isfinite(seconds) and 0 < seconds <= SHELVE_MAX_S):
            raise ValueError(f"shelving time must be between 0 and {SHELVE_MAX_S / 60:g} minutes, got {seconds:g} s")
        a.shelved_until = self._clock() + seconds
        self._shelf_end[key] = self._time() + seconds
        line = f"alarm shelved by {who} for {seconds / 60:g} min, {a.source}: {a.text}"
        self._note("warning", line)
        return line

    def unshelve(self, key: str, why: str = "by the operator") -> None:
        a = self.items.get(key)
        if a is None or a.shelved_until is None:
            return
        a.shelved_until = None
        self._shelf_end.pop(key, None)
        self._note("warning", f"alarm unshelved {why}, {a.source}: {a.text}" + (" (active)" if a.active else ""))
        self._drop_done()

    def _expire_shelving(self) -> None:
        if not self._shelf_end:
            return
        now = self._time()
        for key in [k for k, t in self._shelf_end.items() if now >= t]:
            self.unshelve(key, "when its time was up")

    def _drop_done(self) -> None:
        for k in [k for k, a in self.items.items() if a.acked and not a.active and a.shelved_until is None]:
            del self.items[k]

    # ------------------------------------------------------------------ reading
    def active(self, key: str) -> bool:
        a = self.items.get(key)
        return a is not None and a.active

    def annunciating(self) -> list[Alarm]:
        """Active, not shelved: what the operator must see now."""
        return [a for a in self.items.values() if a.active and a.shelved_until is None]

    def snapshot(self) -> list[dict]:
        """Alarms still to be shown: active, shelved, or cleared but not acknowledged; newest first."""
        return [asdict(a) for a in sorted(self.items.values(), key=lambda a: -a.t_raised)]


def _is_trip(key: str) -> bool:
    d = definition(key)
    return d is not None and d.trip
