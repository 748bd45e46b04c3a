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
that ran out of its budget) may take another number of steps on another run, and the first state that differs
is reported with its tick and field.
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
from app.net.codec import build
from app.net.recording import RecordingError, read_recording
from app.net.snapshots import to_wire
from app.teleop.devices import InputSample

__all__ = ["MEASURED", "ReplayError", "ReplayReport", "replay"]

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

        return LabSession()
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


def replay(path: str | Path, *, check: bool = True, tolerance: float = 1e-12, progress=None) -> ReplayReport:
    """Run the recording at ``path`` again (module text); with ``check`` compare every published state."""
    path = Path(path)
    it = _messages(path)
    try:
        topic, head = next(it)
    except StopIteration:
        raise ReplayError(f"{path}: an empty recording") from None
    if topic != "/session":
        raise ReplayError(f"{path}: not a Bosun recording (it starts with '{topic}', not '/session')")
    kind = head.get("kind", "")
    scene = head.get("scene") or {}
    session = _scene(kind, scene, int(head.get("seed", 0)))
    alarms = getattr(session, "alarms", None)
    if alarms is not None and scene.get("alarm_wall_offset") is not None:
        alarms.wall_offset = float(scene["alarm_wall_offset"])  # the alarms stamped on the recording's wall clock
    report = ReplayReport(str(path), kind)
    inp = getattr(session, "input", None)
    topic = "/session"
    try:
        for topic, m in it:
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
                    sample = InputSample(tuple(m["axes"]), tuple(m["buttons"]), m["device"], m["t"])
                    session.feed(sample, m["t"])
            elif topic == "/tick":
                if inp is not None and m.get("listened") is not None:
                    inp.listened = m["listened"]
                session.tick(m["now"], m["dt"], solve_budget=m["solve_budget"])
                report.ticks += 1
                if progress is not None and report.ticks % 500 == 0:
                    progress(report.ticks)
            elif topic == "/state":
                snap = to_wire(session.snapshot())
                session.events.clear()  # published with the state, as the server does
                report.states += 1
                if check:
                    diffs: list = []
                    _compare(m, snap, "", tolerance, diffs)
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
    except (KeyError, TypeError) as err:  # a message of another shape: another version wrote it
        raise ReplayError(
            f"{path}: a {topic} message lacks {err}: written by Bosun {head.get('version', '?')} in another format"
        ) from None
    finally:
        closer = getattr(session, "close", None)
        if closer is not None:
            closer()
    return report


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
