"""Engine alarms: conditions an operator must notice, with raise / clear / acknowledge and first-out.

Each engine scene keeps one :class:`AlarmList`.  Every control tick it states each condition
(``set(key, active, ...)``); an alarm is *raised* when its condition becomes true, *cleared*
when it becomes false, and stays in the list until it is both cleared and acknowledged (the
usual ISA-18.2 life cycle: an alarm that came and went unseen still asks to be acknowledged).
The first alarm raised while no other was active is marked *first-out*: in a cascade (E-STOP,
then every machine at rest reporting its limits) it names the cause.

Published in every snapshot as ``alarms``: a list of dicts (see :meth:`AlarmList.snapshot`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

SEVERITIES = ("info", "warning", "critical")


@dataclass
class Alarm:
    key: str
    severity: str
    source: str
    text: str
    active: bool
    acked: bool
    t_raised: float
    t_cleared: float | None
    first_out: bool
    count: int = 1


class AlarmList:
    """The alarms of one engine.

    Parameters
    ----------
    source : str
        Default source shown with each alarm (e.g. "teleop", "crane head", "Motion-Lab").
    note : callable(level, text), optional
        Receives a log line when an alarm is raised or cleared.
    clock : callable, optional
        Wall-clock seconds for the time stamps (default ``time.time``).
    """

    def __init__(self, source: str, note: Callable[[str, str], None] | None = None, clock=time.time) -> None:
        self.source = source
        self._note = note or (lambda level, text: None)
        self._clock = clock
        self.items: dict[str, Alarm] = {}
        self._streak: dict[str, tuple[bool, int]] = {}

    def set(
        self,
        key: str,
        active: bool,
        severity: str = "warning",
        text: str = "",
        source: str | None = None,
        debounce: int = 1,
    ) -> None:
        """State a condition; raises, updates or clears the alarm ``key``.

        ``debounce``: the condition must hold (or be gone) on this many consecutive calls before the
        alarm is raised (or cleared), so a condition that flickers tick by tick is one alarm, not many.
        """
        if severity not in SEVERITIES:
            raise ValueError(f"severity must be one of {SEVERITIES}, got {severity!r}")
        if debounce > 1:
            last, n = self._streak.get(key, (active, 0))
            n = n + 1 if last == active else 1
            self._streak[key] = (active, n)
            current = self.items.get(key)
            if n < debounce and (current is not None and current.active) != active:
                return
        a = self.items.get(key)
        if active:
            if a is None or not a.active:
                first = not any(x.active for x in self.items.values())
                if a is None:
                    a = Alarm(key, severity, source or self.source, text, True, False, self._clock(), None, first)
                    self.items[key] = a
                else:  # raised again before it was acknowledged: one entry, counted
                    a.active, a.acked, a.t_cleared, a.first_out = True, False, None, first
                    a.t_raised, a.count = self._clock(), a.count + 1
                    a.severity, a.text = severity, text or a.text
                self._note("error" if severity == "critical" else "warning", f"ALARM {a.source}: {a.text}")
            elif text and text != a.text:
                a.text = text  # a live figure (e.g. % of time saturated)
        elif a is not None and a.active:
            a.active, a.t_cleared = False, self._clock()
            self._note("info", f"alarm cleared {a.source}: {a.text}")
            self._drop_done()

    def ack(self, key: str | None = None) -> int:
        """Acknowledge one alarm (by key) or all (None); returns how many were newly acknowledged."""
        n = 0
        for a in self.items.values():
            if (key is None or a.key == key) and not a.acked:
                a.acked = True
                n += 1
        self._drop_done()
        return n

    def _drop_done(self) -> None:
        for k in [k for k, a in self.items.items() if a.acked and not a.active]:
            del self.items[k]

    def active(self, key: str) -> bool:
        a = self.items.get(key)
        return a is not None and a.active

    def snapshot(self) -> list[dict]:
        """Alarms still to be shown: active, or cleared but not acknowledged; newest first."""
        return [asdict(a) for a in sorted(self.items.values(), key=lambda a: -a.t_raised)]
