"""A recorded session run again (issue 32, item 6): ``bosun replay FILE.mcap [--check]``.

The recording (:mod:`app.engine.record`) holds, in the order the loop applied them, every command, E-STOP and
input sample, then each control tick with what the loop gave the scene (its clock, Δt, the input receiver's
listening time, the solver's budget), the state it published, and the loop's health alarms after it.  The replay
builds the scene as the recording's ``/session`` says, applies the same messages through the loop's own command
path (:func:`app.engine.server.apply_command`), steps it with the same ticks and sets the same health alarms;
``check`` compares every published state with the recording, field by field (numbers to ``tolerance``,
relative to their size above 1; what times the machine, not the scene, left out: :data:`MEASURED`).

What a replay cannot reproduce is refused or reported, never hidden: a command whose work ran off the loop
(a ``Deferred``: the crane head's new sea, a study) returns its result on a later tick that the machine's speed
chose, so a recording that holds one is refused in one line; a solver with a time budget (the GA, a Jacobian
that ran out of its budget) takes its decisions from the clock (whether its time is up, how many generations
still fit), so the recording keeps them (each ``/tick``'s ``work``) and the replay gives the
solver those instead of the clock (:class:`app.ik.Replayed`): the same generations on any machine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from app.engine.jobs import Deferred
from app.engine.scene import CommandError
from app.engine.server import apply_command, apply_health
from app.errors import BosunError
from app.ik import Replayed
from app.net.codec import build
from app.net.recording import RecordingError, read_recording
from app.net.snapshots import to_wire
from app.teleop.devices import InputSample

__all__ = ["MEASURED", "ReplayError", "ReplayReport", "Replayer", "replay"]

#: a state's fields that time the machine, not the scene: the server's bookkeeping and the solver's wall time
MEASURED = frozenset({"engine", "solver_time"})


class ReplayError(BosunError):
    """A recording that cannot be replayed (one line)."""


@dataclass
class ReplayReport:
    """What a replay did: ticks stepped, states compared and how many differed, the first difference."""

    path: str
    kind: str
    ticks: int = 0
    states: int = 0
    differing: int = 0
    first: str = ""  # "tick N, field: recorded R, replayed P"
    commands: int = 0
    inputs: int = 0
    estops: int = 0
    largest: float = 0.0  # the largest numeric difference found [the field's unit]
    notes: list[str] = field(default_factory=list)

    @property
    def equal(self) -> bool:
        return self.differing == 0

    def to_dict(self) -> dict:
        return {"path": self.path, "kind": self.kind, "ticks": self.ticks, "states": self.states,
                "differing": self.differing, "first": self.first, "commands": self.commands, "inputs": self.inputs,
                "estops": self.estops, "largest_difference": self.largest, "equal": self.equal}  # fmt: skip


def _messages(path: Path):
    try:
        yield from read_recording(path)
    except RecordingError as err:
        raise ReplayError(str(err)) from None


def _scene(kind: str, scene: dict, seed: int):
    if kind == "teleop":
        from app.engine.session import Session
        from app.models.registry import list_robots, resolve

        name = scene.get("robot", "")
        xml = scene.get("robot_xml", "")
        if name not in list_robots() or resolve(name).read_text(encoding="utf-8") != xml:
            raise ReplayError(
                f"the recording's robot '{name}' is not the library's file of that name: replay takes library robots"
            )
        return Session(robot_name=name, solver_name=scene.get("solver", "jacobian"), mode=scene.get("mode", "velocity"),
                       seed=seed)  # fmt: skip
    if kind == "tac":
        from app.engine.tac_session import TacSession

        return TacSession()
    if kind == "lab":
        if scene.get("plc"):
            raise ReplayError("the recording drove the real Motion-Lab through its PLC: a replay cannot")
        from app.engine.lab_session import LabSession

        return LabSession(comau_profile=scene.get("comau_profile"))  # None (an older recording): the layout's
    raise ReplayError(f"the recording's engine kind '{kind}' has no replay")


def _compare(recorded: Any, replayed: Any, where: str, tol: float, out: list) -> None:
    """Differences between two wire values (first few kept in ``out`` as (where, recorded, replayed, size))."""
    if isinstance(recorded, dict) and isinstance(replayed, dict):
        for k in recorded.keys() | replayed.keys():
            if where == "" and k in MEASURED:  # the machine's timings, not the scene's state
                continue
            _compare(recorded.get(k), replayed.get(k), f"{where}.{k}" if where else k, tol, out)
        return
    if isinstance(recorded, list) and isinstance(replayed, list):
        if len(recorded) != len(replayed):
            out.append((where, f"{len(recorded)} items", f"{len(replayed)} items", math.inf))
            return
        for i, (a, b) in enumerate(zip(recorded, replayed, strict=True)):
            _compare(a, b, f"{where}[{i}]", tol, out)
        return
    if isinstance(replayed, float) and not math.isfinite(replayed):
        replayed = None  # written as null
    num = (int, float)
    if isinstance(recorded, num) and isinstance(replayed, num) and not isinstance(recorded, bool):
        d = abs(float(recorded) - float(replayed))
        if d > tol * max(1.0, abs(float(recorded))):
            out.append((where, recorded, replayed, d))
        return
    if recorded != replayed:
        out.append((where, recorded, replayed, math.inf))


class Replayer:
    """A recording stepped one control tick at a time (:meth:`advance`): the replayed scene is :attr:`session`,
    the comparison so far :attr:`report`.  :func:`replay` runs it to the end; ``bosun replay --serve`` steps it
    in an engine loop that viewers watch (:func:`serve`)."""

    def __init__(self, path: str | Path, *, check: bool = True, tolerance: float = 1e-12) -> None:
        self.path = Path(path)
        self.check, self.tolerance = check, tolerance
        self._it = _messages(self.path)
        try:
            topic, head = next(self._it)
        except StopIteration:
            raise ReplayError(f"{self.path}: an empty recording") from None
        if topic != "/session":
            raise ReplayError(f"{self.path}: not a Bosun recording (it starts with '{topic}', not '/session')")
        self.head = head
        kind = head.get("kind", "")
        scene = head.get("scene") or {}
        self.session = _scene(kind, scene, int(head.get("seed", 0)))
        alarms = getattr(self.session, "alarms", None)
        if alarms is not None and scene.get("alarm_wall_offset") is not None:
            alarms.wall_offset = float(scene["alarm_wall_offset"])  # the alarms stamped on the recording's clock
        self.report = ReplayReport(str(self.path), kind)
        self.rate = float(head.get("rate_hz", 50.0))
        self.publish_rate = float(head.get("publish_rate_hz", self.rate))
        self._pending: tuple[str, Any] | None = None
        self.done = False
        self._tick = self.session.tick  # the scene's own step (``serve`` puts the replay's in its place)

    def _next(self) -> tuple[str, Any] | None:
        if self._pending is not None:
            msg, self._pending = self._pending, None
            return msg
        return next(self._it, None)

    def advance(self) -> bool:
        """Apply the recording up to and through its next control tick (with the state published and the health
        alarms set after it); False at the end of the recording."""
        if self.done:
            return False
        ticked = False
        topic = "/session"
        try:
            while True:
                msg = self._next()
                if msg is None:
                    self.done = True
                    return ticked
                topic, m = msg
                if ticked and topic not in ("/state", "/health", "/description"):
                    self._pending = msg  # the next tick's
                    return True
                self._apply(topic, m)
                ticked = ticked or topic == "/tick"
        except (KeyError, TypeError) as err:  # a message of another shape: another version wrote it
            raise ReplayError(
                f"{self.path}: a {topic} message lacks {err}: written by Bosun {self.head.get('version', '?')} in "
                "another format"
            ) from None

    def _apply(self, topic: str, m: dict) -> None:
        session, report = self.session, self.report
        if topic == "/command":
            report.commands += 1
            _command(session, m, report)
        elif topic == "/estop":
            report.estops += 1
            session.estop(source=m["source"])
        elif topic == "/input":
            report.inputs += 1
            if m["lost"]:
                session.feed(None, m["t"], released=m["released"])
            else:
                session.feed(InputSample(tuple(m["axes"]), tuple(m["buttons"]), m["device"], m["t"]), m["t"])
        elif topic == "/tick":
            inp = getattr(session, "input", None)
            if inp is not None and m.get("listened") is not None:
                inp.listened = m["listened"]
            budget = m["solve_budget"]
            if m.get("work"):  # the solver's clock decisions in the tick (none: it read no clock)
                budget = Replayed(float(budget), tuple(tuple(int(v) for v in d) for d in m["work"]))
            self._tick(m["now"], m["dt"], solve_budget=budget)
            report.ticks += 1
        elif topic == "/state":
            report.states += 1
            if self.check:
                snap = to_wire(session.snapshot())
                diffs: list = []
                _compare(m, snap, "", self.tolerance, diffs)
                if diffs:
                    report.differing += 1
                    finite = [d[3] for d in diffs if math.isfinite(d[3])]
                    report.largest = max([report.largest, *finite])
                    if not report.first:
                        w, a, b, _ = diffs[0]
                        report.first = f"tick {report.ticks}, {w}: recorded {a!r}, replayed {b!r}"
        elif topic == "/health":
            alarms = getattr(session, "alarms", None)
            if alarms is not None:
                apply_health(alarms, m["now"], [tuple(a) for a in m["alarms"]])

    def close(self) -> None:
        closer = getattr(self.session, "close", None)
        if closer is not None:
            closer()


def replay(path: str | Path, *, check: bool = True, tolerance: float = 1e-12, progress=None) -> ReplayReport:
    """Run the recording at ``path`` again (module text); with ``check`` compare every published state."""
    r = Replayer(path, check=check, tolerance=tolerance)
    try:
        while r.advance():
            if progress is not None and r.report.ticks % 500 == 0:
                progress(r.report.ticks)
            r.session.events.clear()  # published with the states, as the server does
    finally:
        r.close()
    return r.report


def _command(session, m: dict, report: ReplayReport) -> None:
    mtype, fields, by = m["type"], m.get("fields") or {}, m.get("by", "")
    if mtype == "note":
        session.note(fields["level"], fields["text"])
        return
    if mtype == "operator_changed":
        changed = getattr(session, "operator_changed", None)
        if changed is not None:
            changed(fields["name"])
        return
    ok, error = True, ""
    try:
        if m.get("deferred"):
            raise ReplayError(
                f"the recording holds '{mtype}', whose work ran off the loop: its result came on a tick the machine's "
                "speed chose, which a replay cannot place"
            )
        done = apply_command(session, mtype, build(mtype, **fields), by)
        if isinstance(done, Deferred):  # a scene on its own does its work in the command; never deferred here
            raise ReplayError(f"'{mtype}' deferred its work in the replay: not replayable")
    except ReplayError:
        raise
    except (CommandError, BosunError) as err:
        session.note("warning", f"{mtype} refused: {err}")
        ok, error = False, str(err)
    if ok != m.get("ok", True) and not report.first:
        report.first = f"tick {report.ticks}, command {mtype}: recorded {'done' if m.get('ok') else 'refused'}, " \
                       f"replayed {'done' if ok else 'refused: ' + error}"  # fmt: skip
        report.differing += 1


class ReplayScene:
    """A recording played back in an engine loop (``bosun replay --serve``): each control tick steps the
    :class:`Replayer` by one recorded tick, so viewers (``bosun view``, the GUI) watch the session as it ran, in
    real time.  Everything else is the replayed scene's (attribute access passes through), except what would
    change the recording's course: live input is ignored, commands are refused in one line, ``pause`` stands the
    playback still, and STOP freezes it where it is with the scene's E-STOP latched (a replay's STOP ends it)."""

    def __init__(self, replayer: Replayer) -> None:
        self._replayer = replayer
        self._stopped = False
        self._paused = False
        replayer.session.note("info", f"a replay of {replayer.path.name}: nothing here drives a machine")

    def describe(self) -> Any:
        """The scene's description, its title saying that this is a replay (a viewer never takes it for live)."""
        d = self._replayer.session.describe()
        d.title = f"{d.title} — replay of {self._replayer.path.name}"
        return d

    def __getattr__(self, name: str) -> Any:
        return getattr(self._replayer.session, name)

    @property
    def paused(self) -> bool:
        return self._paused

    @property
    def finished(self) -> bool:
        return self._replayer.done

    def tick(self, now: float, dt: float, solve_budget: float | None = None) -> None:
        if not (self._stopped or self._paused):
            self._replayer.advance()

    def feed(self, sample, now: float, released: bool = False) -> None:
        """Live input plays no part in a replay."""

    def operator_changed(self, name: str) -> None:
        """A replay has no operator to disarm."""

    def pause(self, on: bool) -> None:
        self._paused = bool(on)

    def estop(self, source: str = "operator") -> None:
        self._stopped = True
        self._replayer.session.estop(source=source)

    def reset(self) -> None:
        raise CommandError("this engine replays a recording: its STOP ends the replay (run it again)")

    def run(self, msg) -> Any:
        raise CommandError(f"{msg.TYPE}: this engine replays a recording; commands are refused")

    def command(self, mtype: str, **fields: Any) -> Any:
        raise CommandError(f"{mtype}: this engine replays a recording; commands are refused")
