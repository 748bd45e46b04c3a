"""A soak of the Motion-Lab's PLC link against a misbehaving PLC (issue 27, items 1 and 7).

A real :class:`~app.engine.lab_session.LabSession` drives pyads' own ADS test server playing the lab's PLC
(:mod:`app.plc.testplc`), ticked in real time at 50 Hz in this process (the test server delivers its
notifications in-process).  A "PLC program" thread writes plausible machine values every 50 ms (both
platforms gently moving at NEUTRAL, the Comau's joints, the wire).  Phases follow each other in a fixed
cycle, each ``phase_s`` long:

``normal``       a sound PLC
``nan``          NaN, ±inf and out-of-range numbers injected into the polled values (platform poses,
                 references, cylinders, scales, Comau joints and speeds, the wire's utilisation)
``wrong_sizes``  the PLC restarted with ``MAIN.bStop`` declared INT and one more symbol of another size;
                 half-way the operator presses E-STOP (it latches in the engine only), its reset is refused;
                 on the sound PLC that follows, the STOP is written first, then reset
``link_gone``    the PLC stops answering (the server stopped), then comes back
``slow``         every answer 0.05–0.3 s late, and once for 1 s later than the ADS timeout (0.5 s)

A scripted operator tries a command every 0.25 s (seeded): the platforms' modes and sources, the remote
pose, the Comau's and the winch's modes, the winch's slider, the acknowledgement, and the stops.  Checked
throughout: every number in every snapshot (as it goes on the wire) is finite; no command that could start
motion is taken while the engine's link was not ``ok``; every refusal is one line; the PLC incarnations
whose ``MAIN.bStop`` was unusable received no write that could start motion (their own log of writes).
"""

from __future__ import annotations

import math
import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from app.errors import BosunError

PHASES = ("normal", "nan", "normal", "wrong_sizes", "normal", "link_gone", "normal", "slow")
RATE = 50.0  # Hz: the engine's ticks here
COMMAND_EVERY = 0.25  # s
FEED_EVERY = 0.05  # s: the "PLC program" (the lab HMI polls its structs at this rate)
#: writes that cannot start motion: a flag back to FALSE, the winch's spring-return speed to zero, STOP
REST_WRITES = {"bStart": b"\x00", "bReset": b"\x00", "bResetScale": b"\x00", "u": b"\x00\x00\x00\x00", "bStop": b"\x01"}
#: a second symbol of another size in the ``wrong_sizes`` phase (one at random)
WRONG_SIZE = {
    "MAIN.em8000.sineAmplitude": "ARRAY[1..6] OF REAL",
    "MAIN.em1500.uRemote": "ARRAY[1..6] OF LREAL",
    "MAIN.winch.u": "LREAL",
    "MAIN.comau.txHmi": "ARRAY[1..20] OF REAL",
}
#: the operator's commands: (name, fields, could it start motion)
COMMANDS: tuple[tuple[str, dict[str, Any], bool], ...] = (
    ("lab_platform", {"platform": "em8000", "action": "neutral"}, True),
    ("lab_platform", {"platform": "em1500", "action": "neutral"}, True),
    ("lab_platform", {"platform": "em1500", "action": "settle"}, True),
    ("lab_platform", {"platform": "em8000", "action": "engage"}, True),
    ("lab_platform", {"platform": "em8000", "action": "disengage"}, False),
    ("lab_source", {"platform": "em8000", "source": "generator"}, True),
    ("lab_source", {"platform": "em1500", "source": "simulation", "hs": 2.0, "tp": 8.0}, True),
    ("lab_source", {"platform": "em1500", "source": "remote"}, True),
    ("lab_remote_pose", {"platform": "em1500", "eta": [0.0, 0.0, 0.02, 0.0, 0.0, 0.0]}, True),
    ("lab_comau_mode", {"mode": "remote"}, True),
    ("lab_comau_mode", {"mode": "settled"}, False),
    ("lab_winch", {"mode": "local"}, True),
    ("lab_winch", {"speed": 0.1}, True),
    ("lab_winch", {"speed": 0.0}, False),
    ("lab_plc_ack", {}, True),
)


def is_rest_write(name: str, raw: bytes) -> bool:
    """A write to the PLC that cannot start motion (see :data:`REST_WRITES`)."""
    return REST_WRITES.get(name.rsplit(".", 1)[1]) == bytes(raw)


def count_numbers(wire: Any) -> tuple[int, list[str]]:
    """How many numbers a wire form holds, and the paths of those that are not finite."""
    n, bad = 0, []
    stack: list[tuple[str, Any]] = [("", wire)]
    while stack:
        path, v = stack.pop()
        if isinstance(v, dict):
            stack.extend((f"{path}.{k}", x) for k, x in v.items())
        elif isinstance(v, list | tuple):
            stack.extend((f"{path}[{i}]", x) for i, x in enumerate(v))
        elif isinstance(v, float | int | np.floating | np.integer) and not isinstance(v, bool | np.bool_):
            n += 1
            if not math.isfinite(float(v)):
                bad.append(path)
    return n, bad


@dataclass
class SoakReport:
    """What the soak measured; :attr:`ok` when nothing unsafe was seen."""

    seconds: float = 0.0
    phases: int = 0
    snapshots: int = 0
    fields_checked: int = 0
    nonfinite_fields: int = 0
    nonfinite_paths: list[str] = field(default_factory=list)  # the first 20
    injections: dict[str, int] = field(default_factory=dict)
    commands: int = 0
    accepted: int = 0
    refused: int = 0
    refused_by: dict[str, int] = field(default_factory=dict)  # link down, STOP unusable, invalid data, other
    motion_accepted_while_not_ok: list[str] = field(default_factory=list)
    multi_line_refusals: list[str] = field(default_factory=list)
    stop_unusable_connects: int = 0
    motion_writes_while_stop_unusable: list[str] = field(default_factory=list)
    estops: int = 0
    resets_refused: int = 0
    resets_taken_while_stop_unusable: int = 0
    stop_rewritten_after_fix: int = 0  # MAIN.bStop read back TRUE on the sound PLC before the reset
    link_seconds: dict[str, float] = field(default_factory=dict)
    alarms_raised: dict[str, int] = field(default_factory=dict)
    max_tick_s: float = 0.0

    @property
    def ok(self) -> bool:
        return not (
            self.nonfinite_fields
            or self.motion_accepted_while_not_ok
            or self.multi_line_refusals
            or self.motion_writes_while_stop_unusable
            or self.resets_taken_while_stop_unusable
        )

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "ok": self.ok}


def _why(text: str) -> str:
    if "STOP does not reach the PLC" in text:
        return "STOP unusable"
    if "invalid data" in text:
        return "invalid data"
    if "link is lost" in text or "not connected" in text:
        return "link down"
    return "other"


class _Program(threading.Thread):
    """The "PLC program": plausible values every :data:`FEED_EVERY` s into the current server, with
    injections while ``inject`` is set."""

    def __init__(self, rng: np.random.Generator) -> None:
        super().__init__(name="plc-soak-program", daemon=True)
        self.rng = rng
        self.plc: Any = None
        self.inject = False
        self.injected: Counter[str] = Counter()
        self.quit = threading.Event()
        self.lock = threading.Lock()

    def values(self, t: float) -> dict[str, list[float]]:
        s = math.sin(0.5 * t)
        out = {}
        for k, name in enumerate(("em8000", "em1500")):
            eta = [0.02 * s, -0.01 * s, 0.05 * s, 0.01 * s, -0.01 * s, 0.02 * s * (k + 1)]
            out[name] = [4, *eta, *eta, *[0.1 * s] * 6, *[1.0] * 6]  # NEUTRAL, eta, etaRef, cyl, dofScale
        q = [0.3 * s, -0.2 + 0.1 * s, -1.6 + 0.2 * s, 0.0, 0.0, 0.0]
        out["comau"] = [*q, *[0.05 * math.cos(0.5 * t)] * 6, *[-2.0] * 6, *[2.0] * 6]
        out["winch"] = [50.0 + 20.0 * s]
        return out

    def _spoil(self, vals: dict[str, list[float]]) -> None:
        rng = self.rng
        dev = str(rng.choice(["em8000", "em1500", "comau", "winch"]))
        kind = str(rng.choice(["nan", "inf", "-inf", "range"]))
        v = vals[dev]
        if dev == "winch":
            i, far = 0, 150.0 + 100.0 * rng.random()
        elif dev == "comau":
            i = int(rng.integers(0, 12))  # q or u
            far = 3.5 * (1.0 + rng.random()) if i < 6 else 12.0
            i = i if i % 6 < 3 or kind != "range" else i - 3  # ranges hold for the first three joints
        else:
            i = 1 + int(rng.integers(0, 18))  # eta, etaRef, cyl (1: after the status word)
            far = 4.0 + rng.random()
        v[i] = {"nan": math.nan, "inf": math.inf, "-inf": -math.inf, "range": far}[kind]
        self.injected[kind] += 1

    def run(self) -> None:
        t0 = time.monotonic()
        while not self.quit.wait(FEED_EVERY):
            with self.lock:
                plc = self.plc
                if plc is None:
                    continue
                vals = self.values(time.monotonic() - t0)
                if self.inject and self.rng.random() < 0.5:
                    self._spoil(vals)
                for dev in ("em8000", "em1500"):
                    _quiet(plc, f"MAIN.{dev}.txHmi", "<i24f", vals[dev])
                _quiet(plc, "MAIN.comau.txHmi", "<24f", vals["comau"])
                _quiet(plc, "MAIN.winch.lengthUtilization", "<f", vals["winch"])


def _quiet(plc: Any, name: str, fmt: str, values: list[float]) -> None:
    if name in plc.declarations and plc.declarations[name] != "ARRAY[1..20] OF REAL":
        plc.set_quietly(name, fmt, *values)


def _audit(plc: Any, rep: SoakReport) -> None:
    """Every write a PLC whose ``MAIN.bStop`` Bosun could not use received that could start motion."""
    if plc.declarations.get("MAIN.bStop") != "BOOL":
        rep.motion_writes_while_stop_unusable += [
            f"{name} := {raw.hex()}" for _, name, raw in plc.writes if not is_rest_write(name, raw)
        ]


def _new_plc(ip: str, declarations: dict[str, str] | None = None) -> Any:
    from app.plc.testplc import STATE, LabPlc

    plc = LabPlc(ip, declarations)
    for dev in ("em8000", "em1500"):
        plc.set(f"MAIN.{dev}.eState", "<b", STATE["NEUTRAL"])
        plc.set(f"MAIN.{dev}.bActive", "<?", True)
    plc.set("MAIN.comau.bActive", "<?", True)
    plc.set("MAIN.comau.eMode", "<b", 1)  # REMOTE
    plc.set("MAIN.winch.eMode", "<b", 1)  # LOCAL
    plc.start()
    return plc


def run(
    seconds: float = 600.0,
    seed: int = 27,
    phase_s: float = 7.5,
    progress: Callable[[float, float], None] | None = None,
) -> SoakReport:
    """Soak the lab's PLC link for ``seconds`` (real time) in phases of ``phase_s`` (:data:`PHASES`, cycled).

    Needs pyads (the ``plc`` extra).  Returns the :class:`SoakReport`."""
    try:
        import pyads  # noqa: F401 - the test server is pyads'
    except ImportError:
        raise BosunError("bench plc-soak needs pyads: pip install 'bosun[plc]'") from None
    from app.engine.lab_session import LabSession
    from app.engine.scene import CommandError
    from app.net.snapshots import to_wire
    from app.plc.bridge import PlcTarget
    from app.plc.testplc import free_loopback, lab_declarations

    rng = np.random.default_rng(seed)
    rep = SoakReport()
    ip = free_loopback()
    program = _Program(np.random.default_rng(seed + 1))
    plc = _new_plc(ip)
    program.plc = plc
    program.start()
    ses = LabSession(
        plc=PlcTarget.parse(f"{ip}.1.1:851"),
        plc_options={"backoff": (0.2, 1.6), "connect_timeout": 1.0, "ads_timeout": 0.5},
    )
    link_time: Counter[str] = Counter()
    raised: Counter[str] = Counter()
    active: set[str] = set()
    t0 = t_last = time.monotonic()
    phase_i, phase_end = -1, t0
    next_command = t0 + 1.0
    slow_burst: tuple[float, float] | None = None
    want_reset = False

    def swap(declarations: dict[str, str] | None) -> None:
        """The PLC restarted with ``declarations``; the one it replaces checked if its STOP was unusable."""
        nonlocal plc
        with program.lock:
            plc.stop()
            _audit(plc, rep)
            plc = _new_plc(ip, declarations)
            program.plc = plc

    try:
        now = t0
        while now - t0 < seconds:
            now = time.monotonic()
            if now >= phase_end:  # ------------------------------------------------ the next phase
                old = PHASES[phase_i % len(PHASES)] if phase_i >= 0 else ""
                phase_i += 1
                rep.phases += 1
                phase = PHASES[phase_i % len(PHASES)]
                phase_end = now + phase_s
                program.inject = phase == "nan"
                if old == "wrong_sizes":
                    swap(None)
                elif old == "link_gone":
                    with program.lock:
                        plc.start()
                elif old == "slow":
                    plc.delay = 0.0
                if phase == "wrong_sizes":
                    decl = lab_declarations()
                    decl["MAIN.bStop"] = "INT"
                    other = str(rng.choice(sorted(WRONG_SIZE)))
                    decl[other] = WRONG_SIZE[other]
                    swap(decl)
                    rep.stop_unusable_connects += 1
                    rep.injections["wrong_sizes"] = rep.injections.get("wrong_sizes", 0) + 2
                elif phase == "link_gone":
                    with program.lock:
                        plc.stop()
                    rep.injections["link_gone"] = rep.injections.get("link_gone", 0) + 1
                elif phase == "slow":
                    plc.delay = float(rng.uniform(0.05, 0.3))
                    start = now + float(rng.uniform(0.3, 0.5)) * phase_s
                    slow_burst = (start, start + 1.0)
                    rep.injections["slow"] = rep.injections.get("slow", 0) + 1
            if phase_i % len(PHASES) == PHASES.index("slow") and slow_burst is not None:
                if slow_burst[0] <= now < slow_burst[1] and plc.delay < 0.8:
                    plc.delay = 0.8  # beyond the ADS timeout: the link falls
                    rep.injections["slower_than_timeout"] = rep.injections.get("slower_than_timeout", 0) + 1
                elif now >= slow_burst[1] and plc.delay >= 0.8:
                    plc.delay = float(rng.uniform(0.05, 0.3))
                    slow_burst = None
            # ------------------------------------------------------------------ the engine's tick
            t_tick = time.monotonic()
            ses.tick(now, 1.0 / RATE)
            snap = ses.snapshot()
            rep.max_tick_s = max(rep.max_tick_s, time.monotonic() - t_tick)
            n, bad = count_numbers(to_wire(snap))
            rep.snapshots += 1
            rep.fields_checked += n
            rep.nonfinite_fields += len(bad)
            rep.nonfinite_paths += bad[: max(0, 20 - len(rep.nonfinite_paths))]
            link = snap.plant.link if snap.plant is not None else "?"
            link_time[link] += now - t_last  # real time since the last tick, in the link state seen now
            t_last = now
            now_active = {a.key for a in snap.alarms if a.active}
            raised.update(now_active - active)
            active = now_active
            phase = PHASES[phase_i % len(PHASES)]
            stop_named = any(p.startswith("MAIN.bStop:") for p in snap.plant.problems)
            late = now > phase_end - 0.5 * phase_s  # the first half: the operator's commands meet the unusable STOP
            if phase == "wrong_sizes" and late and stop_named and snap.plant.connected and not snap.estop:
                ses.estop("the soak's operator (STOP unusable)")
                rep.estops += 1
                try:
                    ses.reset()
                    rep.resets_taken_while_stop_unusable += 1
                except CommandError:
                    rep.resets_refused += 1
                want_reset = True
            if want_reset and phase != "wrong_sizes" and link == "ok" and not stop_named and snap.plant.stop_written:
                rep.stop_rewritten_after_fix += 1  # the latched STOP reached the sound PLC before the reset
                try:
                    ses.reset()
                    want_reset = False
                except CommandError:
                    rep.resets_refused += 1
            # ------------------------------------------------------------------ the operator
            if now >= next_command:
                next_command = now + COMMAND_EVERY
                name, fields, motion = COMMANDS[int(rng.integers(0, len(COMMANDS)))]
                rep.commands += 1
                try:
                    ses.command(name, **fields)
                    rep.accepted += 1
                    if motion and (link != "ok" or stop_named):
                        rep.motion_accepted_while_not_ok.append(f"{now - t0:.1f} s {name} {fields} (link {link})")
                except CommandError as err:
                    text = str(err)
                    rep.refused += 1
                    rep.refused_by[_why(text)] = rep.refused_by.get(_why(text), 0) + 1
                    if "\n" in text:
                        rep.multi_line_refusals.append(text)
            if progress is not None and int(now - t0) != int(now - t0 - 1.0 / RATE):
                progress(min(int(now - t0), int(seconds)), int(seconds))  # once a second
            time.sleep(max(0.0, 1.0 / RATE - (time.monotonic() - now)))
    finally:
        program.quit.set()
        program.join(timeout=5)
        ses.close()
        with program.lock:
            plc.stop()
            _audit(plc, rep)
    rep.seconds = round(time.monotonic() - t0, 1)
    for kind, n in program.injected.items():
        rep.injections[f"values_{kind}"] = n
    rep.link_seconds = {k: round(v, 1) for k, v in sorted(link_time.items())}
    rep.alarms_raised = dict(sorted(raised.items()))
    return rep
