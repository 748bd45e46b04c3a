"""The alarm rationalisation: every alarm Bosun can raise, why, what follows, and what the operator does.

ANSI/ISA-18.2-2016 §10 (rationalisation) and EEMUA 191 (3rd ed., 2013) ask that every alarm be
justified before it is configured: a cause, a consequence of not acting, an operator action, a
priority from that consequence and the time to respond, and a setting against chatter.  A condition
that asks for no action is not an alarm: it is a status or a diagnostic (``speed limited``, ``holding:
select a mode`` and the engine's timing were alarms before issue 26 and are not now).

This table is the single source: the engines take priority, delays, deadbands and texts' meaning
from it (:class:`app.engine.alarms.AlarmList`), ``bosun alarms`` prints it, and ``docs/alarms.md`` is
generated from it (a test keeps the page equal to the table).

Priorities (severity on the wire): ``critical`` — act now, the machine is stopped or may hurt
someone; ``warning`` — act within minutes, the task suffers.  Keys with a ``:`` carry a part after it
(``leg_limit:em8000``, ``lost:teleop``) and share the definition of the part before it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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


CATALOG: tuple[AlarmDef, ...] = (
    AlarmDef(
        key="estop",
        title="E-STOP latched",
        sources=("teleop", "tac", "lab"),
        priority="critical",
        cause="STOP was pressed (button, Space, Ctrl+Space, a joystick's stop button, a viewer), or the engine "
        "stopped itself after a fault it names in the log",
        consequence="every machine of the engine is stopped and held; nothing moves until reset",
        action="find out why it was stopped; when the area is safe, press Reset E-STOP, then choose a mode or "
        "centre the stick and press ENABLE",
        trip=True,
        shelvable=False,
    ),
    AlarmDef(
        key="motion_without_command",
        title="Machine moves without a command",
        sources=("teleop",),
        priority="critical",
        cause="a joint kept moving with no enabled operator command (E-STOP, enable released, a centred stick in "
        "velocity mode) for longer than its braking time and a second of simulated time (a fault in the control "
        "law, a solver or the plant)",
        consequence="the engine latches E-STOP at once",
        action="keep clear of the machine; note what was on the screen; reset only once the cause is known",
        trip=True,
        shelvable=False,
    ),
    AlarmDef(
        key="device_lost",
        title="Input device lost",
        sources=("teleop", "lab", "gui"),
        priority="warning",
        cause="the joystick or input client that was driving stopped sending or was unplugged",
        consequence="the machine holds where it is; the input is disarmed",
        action="reconnect the device, centre the stick, press ENABLE to drive again",
        trip=True,
        shelvable=False,
        off_delay=1.0,
    ),
    AlarmDef(
        key="stale_input",
        title="Input stale",
        sources=("teleop", "lab"),
        priority="warning",
        cause="the input device driving the machine (armed) sent nothing for 200 ms (a frozen client, a congested "
        "link); a device nobody drives with going quiet is no alarm",
        consequence="the machine holds where it is; the input is disarmed",
        action="check the input client and the network; centre the stick and press ENABLE to drive again",
        trip=True,
        shelvable=False,
        off_delay=1.0,
    ),
    AlarmDef(
        key="engine_slow",
        title="Engine too slow for control",
        sources=("teleop", "tac", "lab"),
        priority="warning",
        cause="the engine's control loop ran below 90 % of real time for 5 s, or the input went stale while it "
        "lagged (the computer is overloaded)",
        consequence="control ticks come late; motion is jerky and the machine holds when input goes stale",
        action="stop studies and other programs on this computer; if it persists, stop the machine",
        off_delay=5.0,
    ),
    AlarmDef(
        key="loop_stall",
        title="Control loop stalled",
        sources=("teleop", "tac", "lab"),
        priority="warning",
        cause="one control tick took longer than 10 periods and 0.1 s (the engine's process was held up: the "
        "computer overloaded or swapping, or work that should run beside the loop ran in it); the log names the "
        "tick's length",
        consequence="for that long nothing was controlled: the machine went on with its last command and a STOP "
        "took effect only after the tick; if it recurs, the machine cannot be stopped promptly",
        action="check that the machine is where it should be; stop studies and other programs on this computer; "
        "if it recurs, stop the machine and report it with the log",
        off_delay=30.0,
    ),
    AlarmDef(
        key="joint_limit",
        title="Joint at its limit",
        sources=("teleop",),
        priority="warning",
        cause="the operator commands a direction that a joint at its limit blocks",
        consequence="the tool does not move in that direction",
        action="command another direction, or change mode to move the arm into another configuration",
        on_delay=0.3,
        off_delay=1.0,
    ),
    AlarmDef(
        key="near_singularity",
        title="Near a singularity",
        sources=("teleop",),
        priority="warning",
        cause="the commanded motion runs where the arm can hardly move the tool in some direction "
        "(σ_min/σ_max of the speed-scaled Jacobian below 0.01)",
        consequence="motion in that direction slows or stops while joints turn fast",
        action="steer away from the stretched or folded pose; use the other mode to reposition",
        on_delay=0.5,
        off_delay=1.0,
        limit=100.0,
        deadband=50.0,
        unit="σ_max/σ_min",
    ),
    AlarmDef(
        key="target_unreachable",
        title="Target out of reach",
        sources=("teleop",),
        priority="warning",
        cause="position mode: the stick's point lies outside the arm's reach (or no joints reaching it were found "
        "within the tick's time)",
        consequence="the arm stops at the nearest point it reached, not at the stick's point",
        action="bring the stick back towards the centre, or lower k_p or move the workspace origin",
        on_delay=0.5,
        off_delay=0.5,
    ),
    AlarmDef(
        key="saturation",
        title="Crane head saturated",
        sources=("tac",),
        priority="warning",
        cause="the Delta head hit its arm limits in more than 5 % of the last 10 s: the sea moves the crane tip "
        "more than the head can cancel",
        consequence="the tool point moves with the vessel; the compensation error grows",
        action="hold the lift and wait for calmer sea, or change heading to reduce the motion",
        on_delay=2.0,
        off_delay=60.0,  # a sea state, not an event: between wave groups the share falls to 0 and rises again
        limit=5.0,
        deadband=4.0,
        unit="% of time",
    ),
    AlarmDef(
        key="winch_end_stop",
        title="Winch at an end stop",
        sources=("lab",),
        priority="warning",
        cause="the winch is driven into its upper or lower end stop",
        consequence="the wire stops; heave compensation by the winch is lost in that direction",
        action="drive the winch the other way, or move the Comau to bring the load back into the winch's range",
        on_delay=0.3,
        off_delay=1.0,
    ),
    AlarmDef(
        key="leg_limit",
        title="Platform leg at its stroke",
        sources=("lab",),
        priority="warning",
        cause="the platform's target lies beyond an actuator's stroke and is scaled back",
        consequence="the platform does not follow its motion fully (compensation or wave replay is incomplete)",
        action="lower the generator amplitudes or the sea state, or stop the platform",
        on_delay=0.5,
        off_delay=2.0,
    ),
    AlarmDef(
        key="payload_below_deck",
        title="Load below the EM1500 deck",
        sources=("lab",),
        priority="critical",
        cause="the hanging load is inside EM1500's footprint and below its top plate",
        consequence="the load strikes the platform deck",
        action="hoist the winch or move the Comau away until the load is clear",
        shelvable=False,
    ),
    AlarmDef(
        key="load_swing",
        title="Load swinging",
        sources=("lab",),
        priority="warning",
        cause="the hanging load swings more than 5° from the vertical (amplitude of the pendulum)",
        consequence="the load may strike people, the platform or the other vessel's deck; landing is unsafe",
        action="stop moving the load; switch on anti-swing (Load swing page) or wait for the swing to decay",
        on_delay=1.0,
        off_delay=2.0,
        limit=5.0,
        deadband=1.0,
        unit="°",
    ),
    AlarmDef(
        key="plc_link",
        title="PLC link down",
        sources=("lab",),
        priority="critical",
        cause="the ADS link to the lab's PLC is lost or not yet up",
        consequence="Bosun neither sees nor commands the real machines; STOP is latched here and written on "
        "reconnect; the lab's own safety chain still acts",
        action="use the lab's hardware emergency stop if anything moves; check the network and the PLC",
        trip=True,
        shelvable=False,
    ),
    AlarmDef(
        key="plc_stale",
        title="PLC data old",
        sources=("lab",),
        priority="warning",
        cause="the PLC's state arrives late (more than 0.5 s old)",
        consequence="the screen shows the last known state; commands wait",
        action="check the network load and the PLC's task cycle",
        off_delay=1.0,
    ),
    AlarmDef(
        key="plc_error",
        title="PLC reports an error",
        sources=("lab",),
        priority="critical",
        cause="the PLC's own logic reports an error (its text is shown)",
        consequence="the PLC has stopped the machines it names",
        action="read the error; fix the cause; acknowledge it on the Motion-Lab page (lab_plc_ack)",
        trip=True,
        shelvable=False,
    ),
    AlarmDef(
        key="plc_symbols",
        title="PLC symbols unusable",
        sources=("lab",),
        priority="warning",
        cause="PLC variables are declared otherwise than Bosun expects (type or size)",
        consequence="Bosun never reads or writes them; the commands that need them are refused",
        action="compare the PLC project with Bosun's symbol table (docs) and correct the project",
    ),
    AlarmDef(
        key="plc_invalid",
        title="PLC data invalid",
        sources=("lab",),
        priority="critical",
        cause="the PLC sent a number that is not finite (NaN, inf) or lies beyond the machine's physical range "
        "(a platform pose beyond its stroke, a Comau joint beyond its limit, the wire beyond its soft ends, each "
        "with a margin): a failed sensor or encoder, a PLC project of another layout or scaling",
        consequence="Bosun holds the last valid value (shown stale) and refuses every command that could start "
        "motion; what the machine really does is not known here",
        action="use the lab's hardware emergency stop if anything may move; check the named signal on the PLC; "
        "the alarm clears once the signal is valid for 1 s",
        trip=True,
        shelvable=False,
    ),
    AlarmDef(
        key="lost",
        title="Engine connection lost",
        sources=("gui",),
        priority="critical",
        cause="no state from an engine for 1 s (the engine stopped, hangs, or the link is down)",
        consequence="the screen no longer shows that machine; commands cannot reach it (STOP is still sent)",
        action="press STOP if anything may move; wait for the reconnection; check the engine process",
        trip=True,
        shelvable=False,
    ),
    AlarmDef(
        key="estop_unconfirmed",
        title="E-STOP not confirmed",
        sources=("gui",),
        priority="critical",
        cause="the engine's state did not show the stop within 100 ms of STOP (it is resent every 100 ms)",
        consequence="the machine may still be moving",
        action="use the hardware emergency stop; keep pressing STOP",
        trip=True,
        shelvable=False,
    ),
    AlarmDef(
        key="role_lost",
        title="Operator role lost",
        sources=("gui",),
        priority="critical",
        cause="another client took the operator role, or this GUI fell silent past the lapse time",
        consequence="this GUI's commands (not STOP) are refused; someone else may drive",
        action="find out who holds the role; take it back (Take operator) only when agreed",
        shelvable=False,
    ),
)

BY_KEY: dict[str, AlarmDef] = {a.key: a for a in CATALOG}

#: shelving (ISA-18.2 §12.3): at most this long, then the alarm returns by itself
SHELVE_MAX_S = 3600.0
SHELVE_DEFAULT_S = 600.0


def definition(key: str) -> AlarmDef | None:
    """The rationalised definition of ``key`` (its part before any ``:``), or None."""
    return BY_KEY.get(key.split(":", 1)[0])


def reference_markdown() -> str:
    """docs/alarms.md: the alarm reference, generated from :data:`CATALOG`."""
    lines = [
        "# Alarm reference",
        "",
        "Generated from `app/engine/alarm_catalog.py` by `bosun alarms --markdown`; do not edit by hand.",
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
    for a in CATALOG:
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
