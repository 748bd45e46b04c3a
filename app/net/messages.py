"""The Bosun protocol, version 3: message types and their fields (see docs/protocol.md).

Version 2 (typed state): every snapshot has ``kind`` and the E-STOP latch at ``estop`` (version 1
nested it under ``flags`` for the teleop scene); static data (robot file, limits, joint names,
the workspace box, the lab's geometry) moved from the state into the ``description`` a client asks
for with ``describe``; server fields moved under ``engine``.  The classes are in
:mod:`app.net.snapshots`.

Every message is a msgpack map with ``v`` (protocol version), ``type`` and the fields
below.  A field spec is (kind, required, limit):

* ``str``: UTF-8 text of at most ``limit`` characters;
* ``int``: integer in [0, limit];
* ``float``: finite number with |x| ≤ limit;
* ``bool``;
* ``floats``: list of at most ``limit`` finite numbers; ``unit_floats``: same, each in [−1, 1];
* ``bools``: list of at most ``limit`` booleans;
* ``vec3``: three finite numbers with |x| ≤ limit;
* ``enum``: one of the strings in ``limit``;
* ``map``: a map (state snapshots from the engine; not accepted from clients).

Typed (issue 29, item 5): every message is a frozen dataclass here, one per message type, its fields
declared with their spec (:func:`spec`).  :func:`app.net.codec.decode` validates a message once and hands
out an instance of its class; a sender builds the instance (an unknown or missing field fails at the
sender); an engine scene's command table is keyed by the class (:mod:`app.engine.scene`).  The schema dicts
below (``CLIENT_MESSAGES``, ``ENGINE_MESSAGES``) are derived from the classes, for the validator and the
protocol page.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

PROTOCOL_VERSION = 3
MAX_MESSAGE_BYTES = 65_536  # a client's message
MAX_ENGINE_MESSAGE_BYTES = 16 * 2**20  # an engine's (a study's result, a description with robot files)
MAX_ROBOT_TEXT = 60_000  # robot XML sent by a client in set_robot (larger files go in a robot folder)

ROLES = ("operator", "viewer")
MODES = ("position", "velocity")


# ------------------------------------------------------------------ the message classes
def spec(kind: str, limit: Any = None, *, optional: bool = False) -> Any:
    """A field of a message: its ``kind`` and ``limit`` (see the module text); an optional field defaults to None
    (absent on the wire)."""
    return dataclasses.field(default=None if optional else dataclasses.MISSING, metadata={"kind": kind, "limit": limit})


@dataclass(frozen=True, kw_only=True)
class Message:
    """A protocol message: ``TYPE`` on the wire, and its fields."""

    TYPE: ClassVar[str] = ""

    @classmethod
    def schema(cls) -> dict[str, tuple]:
        """The fields as (kind, required, limit), in declaration order (the validator's schema)."""
        return {
            f.name: (f.metadata["kind"], f.default is dataclasses.MISSING, f.metadata["limit"])
            for f in dataclasses.fields(cls)
        }

    def fields(self) -> dict[str, Any]:
        """The fields that are set (an optional field left out is absent, as on the wire)."""
        return {f.name: v for f in dataclasses.fields(self) if (v := getattr(self, f.name)) is not None}


#: message type -> class, client to engine, and engine to client
CLIENT: dict[str, type[Message]] = {}
ENGINE: dict[str, type[Message]] = {}
#: the scene commands: the server hands them to the scene's command table
SCENE_COMMANDS: dict[str, type[Message]] = {}


def client_message(cls: type[Message]) -> type[Message]:
    CLIENT[cls.TYPE] = cls
    return cls


def scene_command(cls: type[Message]) -> type[Message]:
    SCENE_COMMANDS[cls.TYPE] = cls
    return client_message(cls)


def engine_message(cls: type[Message]) -> type[Message]:
    ENGINE[cls.TYPE] = cls
    return cls


# ------------------------------------------------------------------ client -> engine
@client_message
@dataclass(frozen=True, kw_only=True)
class Hello(Message):
    TYPE: ClassVar[str] = "hello"
    role: str = spec("enum", ROLES)
    name: str = spec("str", 64)
    token: str | None = spec("str", 256, optional=True)
    secret: str | None = spec("str", 256, optional=True)


@client_message
@dataclass(frozen=True, kw_only=True)
class Bye(Message):
    TYPE: ClassVar[str] = "bye"


@client_message
@dataclass(frozen=True, kw_only=True)
class Ping(Message):
    TYPE: ClassVar[str] = "ping"
    seq: int | None = spec("int", 2**62, optional=True)


@client_message
@dataclass(frozen=True, kw_only=True)
class Input(Message):
    TYPE: ClassVar[str] = "input"
    seq: int = spec("int", 2**62)
    t_send: float | None = spec("float", 1e12, optional=True)
    axes: list[float] = spec("unit_floats", 16)
    buttons: list[bool] = spec("bools", 64)
    device: str = spec("str", 128)


@client_message
@dataclass(frozen=True, kw_only=True)
class DeviceLost(Message):
    TYPE: ClassVar[str] = "device_lost"
    device: str | None = spec("str", 128, optional=True)
    released: bool | None = spec("bool", optional=True)


@scene_command
@dataclass(frozen=True, kw_only=True)
class SetRobot(Message):
    TYPE: ClassVar[str] = "set_robot"
    robot: str = spec("str", 1024)
    xml: str | None = spec("str", 60_000, optional=True)


@scene_command
@dataclass(frozen=True, kw_only=True)
class SetSolver(Message):
    TYPE: ClassVar[str] = "set_solver"
    solver: str = spec("str", 64)


@scene_command
@dataclass(frozen=True, kw_only=True)
class SetMode(Message):
    TYPE: ClassVar[str] = "set_mode"
    mode: str = spec("enum", MODES)


@scene_command
@dataclass(frozen=True, kw_only=True)
class SetScaling(Message):
    TYPE: ClassVar[str] = "set_scaling"
    k_p: list[float] | None = spec("vec3", 1e4, optional=True)
    x_w: list[float] | None = spec("vec3", 1e5, optional=True)
    k_v: list[float] | None = spec("vec3", 1000.0, optional=True)


@client_message
@dataclass(frozen=True, kw_only=True)
class Estop(Message):
    TYPE: ClassVar[str] = "estop"
    reason: str | None = spec("str", 256, optional=True)
    token: str | None = spec("str", 256, optional=True)


@client_message
@dataclass(frozen=True, kw_only=True)
class AckAlarm(Message):
    TYPE: ClassVar[str] = "ack_alarm"
    key: str | None = spec("str", 64, optional=True)


# shelve one alarm for ``minutes`` (ISA-18.2 §12.3; at most 60, default 10; 0 unshelves it now)
@client_message
@dataclass(frozen=True, kw_only=True)
class ShelveAlarm(Message):
    TYPE: ClassVar[str] = "shelve_alarm"
    key: str = spec("str", 64)
    minutes: float | None = spec("float", 60.0, optional=True)


@client_message
@dataclass(frozen=True, kw_only=True)
class Reset(Message):
    TYPE: ClassVar[str] = "reset"


@client_message
@dataclass(frozen=True, kw_only=True)
class ReleaseOperator(Message):
    TYPE: ClassVar[str] = "release_operator"


@client_message
@dataclass(frozen=True, kw_only=True)
class Describe(Message):
    TYPE: ClassVar[str] = "describe"


@client_message
@dataclass(frozen=True, kw_only=True)
class Pause(Message):
    TYPE: ClassVar[str] = "pause"
    on: bool = spec("bool")


# teleop scene: IK studies in a worker process the engine owns
@scene_command
@dataclass(frozen=True, kw_only=True)
class StudyStart(Message):
    TYPE: ClassVar[str] = "study_start"
    study: str = spec("enum", ("distribution", "tracking"))
    solver: str | None = spec("str", 64, optional=True)
    grid: int | None = spec("int", 40, optional=True)


@scene_command
@dataclass(frozen=True, kw_only=True)
class StudyCancel(Message):
    TYPE: ClassVar[str] = "study_cancel"


# crane-head scene (``bosun server --plant tac``)
# the crane-head scene's vessel (issue 17, item 2): a name (``bosun vessel list``) or an RAO table in Bosun's CSV,
# sent in parts of ≤ 60 000 characters (``part`` 0 … ``parts`` − 1, in order; a part 0 starts anew)
@scene_command
@dataclass(frozen=True, kw_only=True)
class SetVessel(Message):
    TYPE: ClassVar[str] = "set_vessel"
    vessel: str | None = spec("str", 64, optional=True)
    csv: str | None = spec("str", 60_000, optional=True)
    part: int | None = spec("int", 63, optional=True)
    parts: int | None = spec("int", 64, optional=True)
    label: str | None = spec("str", 256, optional=True)


@scene_command
@dataclass(frozen=True, kw_only=True)
class SetSea(Message):
    TYPE: ClassVar[str] = "set_sea"
    spectrum: str = spec("enum", ("jonswap", "pm", "torsethaugen"))
    hs: float = spec("float", 30.0)
    tp: float = spec("float", 40.0)
    heading: float = spec("float", 720.0)


@scene_command
@dataclass(frozen=True, kw_only=True)
class SetTacMode(Message):
    TYPE: ClassVar[str] = "set_tac_mode"
    mode: str = spec("enum", ("off", "tac", "cooperative"))


# Motion-Lab (``bosun server --plant lab``)
@scene_command
@dataclass(frozen=True, kw_only=True)
class LabPlatform(Message):
    TYPE: ClassVar[str] = "lab_platform"
    platform: str = spec("str", 32)
    action: str = spec("enum", ("neutral", "settle", "engage", "disengage"))


@scene_command
@dataclass(frozen=True, kw_only=True)
class LabSource(Message):
    TYPE: ClassVar[str] = "lab_source"
    platform: str = spec("str", 32)
    source: str = spec("enum", ("simulation", "generator", "remote", "timeseries"))
    amplitude: list[float] | None = spec("floats", 6, optional=True)
    frequency: list[float] | None = spec("floats", 6, optional=True)
    phase: list[float] | None = spec("floats", 6, optional=True)
    spectrum: str | None = spec("enum", ("jonswap", "pm", "torsethaugen"), optional=True)
    hs: float | None = spec("float", 30.0, optional=True)
    tp: float | None = spec("float", 40.0, optional=True)
    heading: float | None = spec("float", 720.0, optional=True)
    seed: int | None = spec("int", 2**31, optional=True)
    scale: list[float] | None = spec("floats", 6, optional=True)
    csv: str | None = spec("str", 60_000, optional=True)
    name: str | None = spec("str", 256, optional=True)


@scene_command
@dataclass(frozen=True, kw_only=True)
class LabRemotePose(Message):
    TYPE: ClassVar[str] = "lab_remote_pose"
    platform: str = spec("str", 32)
    eta: list[float] = spec("floats", 6)


@scene_command
@dataclass(frozen=True, kw_only=True)
class LabComauMode(Message):
    TYPE: ClassVar[str] = "lab_comau_mode"
    mode: str = spec("enum", ("settled", "remote", "motion_comp"))


@scene_command
@dataclass(frozen=True, kw_only=True)
class LabWinch(Message):
    TYPE: ClassVar[str] = "lab_winch"
    mode: str | None = spec("enum", ("local", "remote", "motion_comp"), optional=True)
    speed: float | None = spec("float", 10.0, optional=True)


@scene_command
@dataclass(frozen=True, kw_only=True)
class LabVvmc(Message):
    TYPE: ClassVar[str] = "lab_vvmc"
    on: bool = spec("bool")


# the real lab's PLC (``--plc``): acknowledge its error as the lab HMI does (``platform``: only that one)
@scene_command
@dataclass(frozen=True, kw_only=True)
class LabPlcAck(Message):
    TYPE: ClassVar[str] = "lab_plc_ack"
    platform: str | None = spec("str", 32, optional=True)


# the Comau's joint jog (issue 16, item 5): ``joint`` 1–3 (q1–q3), ``speed`` a fraction of the profile's
# joint speed; resent while held, zero when let go (a speed not refreshed for 0.3 s returns to zero)
@scene_command
@dataclass(frozen=True, kw_only=True)
class LabComauJog(Message):
    TYPE: ClassVar[str] = "lab_comau_jog"
    joint: int = spec("int", 3)
    speed: float = spec("float", 1.0)


# the load-swing estimator and anti-swing law (issue 16, item 4; the lab HMI's "Pendel Estimator" buttons)
@scene_command
@dataclass(frozen=True, kw_only=True)
class LabAntisway(Message):
    TYPE: ClassVar[str] = "lab_antisway"
    action: str = spec("enum", ("activate", "deactivate", "reset"))


# ------------------------------------------------------------------ engine -> client
@engine_message
@dataclass(frozen=True, kw_only=True)
class Welcome(Message):
    TYPE: ClassVar[str] = "welcome"
    client_id: str = spec("str", 64)
    role: str = spec("enum", ROLES)
    state_url: str = spec("str", 1024)
    note: str | None = spec("str", 256, optional=True)


@engine_message
@dataclass(frozen=True, kw_only=True)
class Reply(Message):
    TYPE: ClassVar[str] = "reply"
    re: str = spec("str", 32)
    ok: bool = spec("bool")
    error: str | None = spec("str", 1024, optional=True)


@engine_message
@dataclass(frozen=True, kw_only=True)
class State(Message):
    TYPE: ClassVar[str] = "state"
    state: dict[str, Any] = spec("map")


@engine_message
@dataclass(frozen=True, kw_only=True)
class Description(Message):
    TYPE: ClassVar[str] = "description"
    description: dict[str, Any] = spec("map")


@engine_message
@dataclass(frozen=True, kw_only=True)
class Study(Message):
    TYPE: ClassVar[str] = "study"
    study: dict[str, Any] = spec("map")


@engine_message
@dataclass(frozen=True, kw_only=True)
class Log(Message):
    TYPE: ClassVar[str] = "log"
    level: str = spec("enum", ("info", "warning", "error"))
    text: str = spec("str", 1024)
    t: float = spec("float", 1e12)


CLIENT_MESSAGES: dict[str, dict[str, tuple]] = {t: c.schema() for t, c in CLIENT.items()}
ENGINE_MESSAGES: dict[str, dict[str, tuple]] = {t: c.schema() for t, c in ENGINE.items()}
SCENE_MESSAGES = frozenset(SCENE_COMMANDS)

#: messages only the operator may send (a viewer gets an error reply); E-STOP is anyone's
OPERATOR_ONLY = frozenset({"input", "device_lost", "reset", "ack_alarm", "shelve_alarm", "pause"} | SCENE_MESSAGES)
