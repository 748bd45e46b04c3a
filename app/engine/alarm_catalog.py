"""The alarm rationalisation: every alarm Bosun can raise, why, what follows, and what the operator does.

ANSI/ISA-18.2-2016 §10 (rationalisation) and EEMUA 191 (3rd ed., 2013) ask that every alarm be
justified before it is configured: a cause, a consequence of not acting, an operator action, a
priority from that consequence and the time to respond, and a setting against chatter.  A condition
that asks for no action is not an alarm: it is a status or a diagnostic (``speed limited``, ``holding:
select a mode`` and the engine's timing were alarms before issue 26 and are not now).

The table, ``alarms.toml`` beside this module (the master alarm database: data, not code), is the
single source: the engines take priority, delays, deadbands and texts' meaning from it
(:class:`app.engine.alarms.AlarmList`), ``bosun alarms`` prints it, and ``docs/alarms.md`` is generated
from it (a test keeps the page equal to the table).

Priorities (severity on the wire): ``critical`` — act now, the machine is stopped or may hurt
someone; ``warning`` — act within minutes, the task suffers.  Keys with a ``:`` carry a part after it
(``leg_limit:em8000``, ``lost:teleop``) and share the definition of the part before it.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

#: the engines (alarm sources) by scene kind, as the operator reads them
SOURCES = {"teleop": "Teleop", "tac": "Crane head", "lab": "Motion-Lab", "gui": "GUI"}


@dataclass(frozen=True)
class AlarmDef:
    """One rationalised alarm.

    Attributes
    ----------
    key : str
        The key the engine sets (the part before any ``:``).
    title : str
        Plain-language name, as shown in the alarm list.
    sources : tuple of str
        Scene kinds that raise it (``teleop``, ``tac``, ``lab``, ``gui``).
    priority : str
        ``critical`` or ``warning``.
    cause, consequence, action : str
        Why it comes, what happens if nobody acts, what the operator does.
    trip : bool
        The alarm stops or holds the machine: only trip alarms compete for first-out.
    shelvable : bool
        The operator may shelve it for a limited time (never a trip or a critical alarm: a test holds it).
    on_delay, off_delay : float
        Seconds the condition must hold before raising, and be gone before clearing (chatter).
    limit, deadband : float
        Analog alarms: raised when the value exceeds ``limit``, cleared when it falls below
        ``limit − deadband`` (``nan``: a boolean condition).
    unit : str
        Unit of ``limit`` in the reference.
    """

    key: str
    title: str
    sources: tuple[str, ...]
    priority: str
    cause: str
    consequence: str
    action: str
    trip: bool = False
    shelvable: bool = True
    on_delay: float = 0.0
    off_delay: float = 0.0
    limit: float = math.nan
    deadband: float = 0.0
    unit: str = ""

    @property
    def analog(self) -> bool:
        return math.isfinite(self.limit)


#: the master alarm database, beside this module (package data)
CATALOG_FILE = Path(__file__).with_name("alarms.toml")
_PRIORITIES = ("critical", "warning")


@functools.cache
def catalog() -> tuple[AlarmDef, ...]:
    """Every rationalised alarm, in the reference's order, read once from :data:`CATALOG_FILE`.

    Raises
    ------
    ValueError
        The file names an unknown field, misses a required one, repeats a key, or gives an unknown priority or
        source: one line that names the file, the alarm and what is wrong.
    """
    with CATALOG_FILE.open("rb") as f:
        entries = tomllib.load(f).get("alarm", [])
    known = {f.name for f in dataclasses.fields(AlarmDef)}
    alarms: dict[str, AlarmDef] = {}
    for i, entry in enumerate(entries):
        where = f"{CATALOG_FILE.name}: alarm {i + 1} ({entry.get('key', '?')})"
        if unknown := sorted(set(entry) - known):
            raise ValueError(f"{where}: unknown field(s) {', '.join(unknown)}")
        try:
            alarm = AlarmDef(**{**entry, "sources": tuple(entry.get("sources", ()))})
        except TypeError as exc:
            raise ValueError(f"{where}: {exc}") from None
        if alarm.key in alarms:
            raise ValueError(f"{where}: the key is defined twice")
        if alarm.priority not in _PRIORITIES:
            raise ValueError(f"{where}: priority {alarm.priority!r} is not one of {', '.join(_PRIORITIES)}")
        if bad := [s for s in alarm.sources if s not in SOURCES]:
            raise ValueError(f"{where}: unknown source(s) {', '.join(bad)}")
        alarms[alarm.key] = alarm
    return tuple(alarms.values())


@functools.cache
def _by_key() -> dict[str, AlarmDef]:
    return {a.key: a for a in catalog()}


#: shelving (ISA-18.2 §12.3): at most this long, then the alarm returns by itself
SHELVE_MAX_S = 3600.0
SHELVE_DEFAULT_S = 600.0


def definition(key: str) -> AlarmDef | None:
    """The rationalised definition of ``key`` (its part before any ``:``), or None."""
    return _by_key().get(key.split(":", 1)[0])


def reference_markdown() -> str:
    """docs/alarms.md: the alarm reference, generated from the catalogue (:func:`catalog`)."""
    lines = [
        "# Alarm reference",
        "",
        "Generated from `app/engine/alarms.toml` by `bosun alarms --markdown`; do not edit by hand.",
        "",
        "Every alarm Bosun raises, rationalised as ANSI/ISA-18.2 and EEMUA 191 ask: its cause, the",
        "consequence of not acting, the operator's action, its priority and source, and its settings",
        "against chatter (on- and off-delays, deadbands).  **critical**: act now — the machine is stopped",
        "or may hurt someone; **warning**: act within minutes — the task suffers.  *Trip* alarms stop or",
        "hold the machine and alone compete for the first-out mark (the cause of a cascade).  A shelvable",
        f"alarm may be shelved for up to {SHELVE_MAX_S / 60:.0f} minutes (default {SHELVE_DEFAULT_S / 60:.0f}); "
        "shelving and its end are logged.",
        "",
        "Not alarms (no operator action): *speed limited* (a log line), *holding: select a mode* (the",
        "status light), and the engine's timing (the engine light's tool tip) unless control suffers.",
        "",
        "| alarm | key | priority | source | cause | consequence | operator action | settings |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for a in catalog():
        settings = []
        if a.analog:
            settings.append(f"raise > {a.limit:g} {a.unit}, clear < {a.limit - a.deadband:g} {a.unit}")
        if a.on_delay:
            settings.append(f"on-delay {a.on_delay:g} s")
        if a.off_delay:
            settings.append(f"off-delay {a.off_delay:g} s")
        settings.append("trip" if a.trip else "")
        settings.append("shelvable" if a.shelvable else "not shelvable")
        src = ", ".join(SOURCES[s] for s in a.sources)
        cells = (a.title, f"`{a.key}`", a.priority, src, a.cause, a.consequence, a.action,
                 "; ".join(s for s in settings if s))  # fmt: skip
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines) + "\n"
