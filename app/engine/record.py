"""An engine session on record (issue 32, item 6): MCAP files that Foxglove and PlotJuggler open.

``bosun server --record FILE.mcap`` (any plant) writes, as the loop runs, with the ``mcap`` library and JSON
messages, each channel with a JSON schema made from the protocol's own dataclasses (so a viewer names and plots
every field):

* ``/session`` (once): the engine's kind, its rate and publication rate, seed, version and command line;
* ``/description``: the scene's description, at the start and whenever it changes;
* ``/tick``: every control tick, after its inputs, commands and control step, before its state: the loop's clock,
  Δt, the input receiver's listening time, the solver's budget and the solver's clock decisions in it (what a
  replay steps with: a GA or a Jacobian that ran out of time takes the same steps again);
* ``/health``: the loop's own health alarms after each tick (measured on the machine: a replay sets them);
* ``/input``: every input sample fed to the scene (axes, buttons, device, its time; a lost device as
  ``device_lost``), in the order the loop applied it;
* ``/command``: every command the loop applied (its type and fields, who sent it, and whether it was refused);
* ``/estop``: every E-STOP applied (its source);
* ``/state``: every published snapshot, as the clients get it.

Message times (log and publish) are the loop's own time from the start of the recording (tick × Δt) in
nanoseconds.  The recorder costs nothing when off (the server holds None), and what it writes is checked by
``tests/test_record.py`` through the ``mcap`` reader; :mod:`app.engine.replay` runs a recording again.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import types
import typing
from pathlib import Path
from typing import Any

from app import __version__
from app.errors import BosunError

__all__ = ["RecordError", "SessionRecorder", "json_schema"]


class RecordError(BosunError):
    """A recording that cannot be written (one line)."""


def json_schema(cls: type, title: str | None = None) -> dict:
    """A JSON schema (draft 2020-12) of a protocol dataclass: numbers, integers, strings, booleans, arrays and
    nested objects named as the fields are (what Foxglove's and PlotJuggler's JSON decoders need to list the
    fields)."""
    hints = typing.get_type_hints(cls)
    props = {f.name: _type_schema(hints[f.name]) for f in dataclasses.fields(cls)}
    out = {"type": "object", "properties": props}
    if title:
        out = {"$schema": "https://json-schema.org/draft/2020-12/schema", "title": title, **out}
    return out


def _type_schema(tp: Any) -> dict:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        options = [a for a in typing.get_args(tp) if a is not type(None)]
        inner = _type_schema(options[0]) if len(options) == 1 else {}
        return {"anyOf": [inner, {"type": "null"}]} if inner else {}
    if origin in (list, tuple):
        args = [a for a in typing.get_args(tp) if a is not Ellipsis]
        return {"type": "array", "items": _type_schema(args[0]) if args else {}}
    if origin is dict:
        return {"type": "object"}
    if tp is bool:
        return {"type": "boolean"}
    if tp is int:
        return {"type": "integer"}
    if tp is float:
        return {"type": "number"}
    if tp is str:
        return {"type": "string"}
    if dataclasses.is_dataclass(tp):
        return json_schema(tp)
    return {}


@dataclasses.dataclass
class _Tick:
    tick: int
    now: float
    dt: float
    listened: float | None
    solve_budget: float
    work: list[list[int]]


@dataclasses.dataclass
class _Health:
    tick: int
    now: float
    alarms: list[list]


@dataclasses.dataclass
class _Input:
    t: float
    axes: list[float] | None
    buttons: list[bool] | None
    device: str
    released: bool | None
    lost: bool


@dataclasses.dataclass
class _Command:
    tick: int
    type: str
    fields: dict
    by: str
    ok: bool
    error: str
    deferred: bool


@dataclasses.dataclass
class _Estop:
    tick: int
    source: str


@dataclasses.dataclass
class _Session:
    kind: str
    rate_hz: float
    publish_rate_hz: float
    seed: int
    version: str
    argv: list[str]
    scene: dict


def _clean(obj: Any) -> Any:
    """JSON has no NaN or infinity: they are written as null (a viewer shows a gap)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_clean(v) for v in obj]
    return obj


class SessionRecorder:
    """Writes one engine session to an MCAP file (module text); :meth:`close` finishes the file."""

    def __init__(self, path: str | Path, snapshot_cls: type, description_cls: type) -> None:
        try:
            from mcap.writer import Writer
        except ImportError:  # pragma: no cover - mcap is a core dependency
            raise RecordError("recording needs the mcap package (pip install mcap)") from None
        self.path = Path(path)
        if self.path.suffix != ".mcap":
            raise RecordError(f"{path}: a recording's file name ends in .mcap")
        try:
            self._file = open(self.path, "wb")  # noqa: SIM115 - closed in close()
        except OSError as err:
            raise RecordError(f"{path}: cannot write: {err.strerror or err}") from None
        self._writer = Writer(self._file)
        self._writer.start(profile="", library=f"bosun {__version__}")
        self._channels: dict[str, int] = {}
        for topic, cls, name in (
            ("/session", _Session, "bosun.Session"),
            ("/description", description_cls, f"bosun.{description_cls.__name__}"),
            ("/tick", _Tick, "bosun.Tick"),
            ("/input", _Input, "bosun.Input"),
            ("/command", _Command, "bosun.Command"),
            ("/estop", _Estop, "bosun.Estop"),
            ("/health", _Health, "bosun.Health"),
            ("/state", snapshot_cls, f"bosun.{snapshot_cls.__name__}"),
        ):
            schema = json.dumps(json_schema(cls, name)).encode("utf-8")
            sid = self._writer.register_schema(name=name, encoding="jsonschema", data=schema)
            self._channels[topic] = self._writer.register_channel(topic=topic, message_encoding="json", schema_id=sid)
        self._seq: dict[str, int] = dict.fromkeys(self._channels, 0)
        self.t = 0.0
        self.tick = 0
        self.messages = 0
        self.closed = False

    def _write(self, topic: str, payload: Any, t: float | None = None) -> None:
        if self.closed:
            return
        ns = round(1e9 * max(0.0, self.t if t is None else t))
        data = json.dumps(_clean(payload), separators=(",", ":"), allow_nan=False).encode("utf-8")
        self._seq[topic] += 1
        self._writer.add_message(self._channels[topic], log_time=ns, data=data, publish_time=ns,
                                 sequence=self._seq[topic])  # fmt: skip
        self.messages += 1

    # ------------------------------------------------------------------ what the loop reports
    def session(self, kind: str, rate: float, publish_rate: float, seed: int, scene: dict) -> None:
        """The session's start: the engine's kind, rates and seed, and what builds its scene again (``scene``:
        the teleop scene's robot, its file's text, solver, mode and frame; the others' defaults)."""
        rec = _Session(kind, rate, publish_rate, int(seed), __version__, list(sys.argv), scene)
        self._write("/session", dataclasses.asdict(rec), 0.0)

    def description(self, wire: dict) -> None:
        self._write("/description", wire)

    def on_tick(
        self, tick: int, now: float, dt: float, listened: float | None, budget: float, work: list[list[int]]
    ) -> None:
        """A control tick just run, after the inputs and commands it took and before the state it published: its
        number, the loop's clock ``now`` (monotonic), Δt, the input receiver's last listening time, the solver's
        budget, and the solver's clock decisions in it (``work``, one list per solve: whether its time was up, how
        many GA generations fitted; a replay takes them instead of reading the clock, :class:`app.ik.Replayed`) —
        what a replay gives the scene."""
        self.tick = tick
        self.t = tick * dt  # the messages' time: the loop's own, from the recording's start
        self._write("/tick", {"tick": tick, "now": now, "dt": dt, "listened": listened, "solve_budget": budget,
                              "work": work})  # fmt: skip

    def on_health(self, now: float, health: list) -> None:
        """The loop's health alarms after a tick (``loop_stall``, ``engine_slow``): measured, not replayable."""
        self._write(
            "/health", {"tick": self.tick, "now": now, "alarms": [[k, bool(on), text] for k, on, text in health]}
        )

    def on_input(self, sample, t: float, released: bool | None = None) -> None:
        if sample is None:
            payload = {"t": t, "axes": None, "buttons": None, "device": "", "released": released, "lost": True}
        else:
            payload = {"t": sample.t if sample.t is not None else t, "axes": list(sample.axes),
                       "buttons": list(sample.buttons), "device": sample.device, "released": released,
                       "lost": False}  # fmt: skip
        self._write("/input", payload)

    def on_command(self, mtype: str, fields: dict, by: str, ok: bool, error: str = "", deferred: bool = False) -> None:
        """A command the loop applied: its refusal, or ``deferred`` when its work went off the loop (its result
        came on a later tick: a replay refuses such a recording)."""
        self._write("/command", {"tick": self.tick, "type": mtype, "fields": fields, "by": by, "ok": ok,
                                 "error": error, "deferred": deferred})  # fmt: skip

    def on_estop(self, source: str) -> None:
        self._write("/estop", {"tick": self.tick, "source": source})

    def on_state(self, wire: dict) -> None:
        self._write("/state", wire)

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        try:
            self._writer.finish()
        finally:
            self._file.close()
