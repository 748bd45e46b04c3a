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
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, dataclass_transform

PROTOCOL_VERSION = 3
MAX_MESSAGE_BYTES = 65_536  # a client's message
MAX_ENGINE_MESSAGE_BYTES = 16 * 2**20  # an engine's (a study's result, a description with robot files)
MAX_ROBOT_TEXT = 60_000  # robot XML sent by a client in set_robot (larger files go in a robot folder)

ROLES = ("operator", "viewer")
MODES = ("position", "velocity")
#: the frames the operator may command in (issue 30, item 1): the world (earth-fixed: the mapping of the papers),
#: the robot's base, its tool, and a target (a moving deck: the EM1500, a second vessel; scenes that have one)
FRAMES = ("world", "base", "tool", "target")


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


def _message(wire_type: str, *books: dict[str, type[Message]]) -> Callable[[type], type[Message]]:
    """Make a class a message: a frozen, keyword-only dataclass with ``TYPE`` = ``wire_type``, entered in ``books``."""

    def declare(cls: type) -> type[Message]:
        cls.TYPE = wire_type
        made = dataclass(frozen=True, kw_only=True)(cls)
        for book in books:
            book[wire_type] = made
        return made

    return declare


@dataclass_transform(frozen_default=True, kw_only_default=True, field_specifiers=(spec,))
def client_message(wire_type: str) -> Callable[[type], type[Message]]:
    """A message a client sends (the server's own: hello, input, STOP, alarms …)."""
    return _message(wire_type, CLIENT)


@dataclass_transform(frozen_default=True, kw_only_default=True, field_specifiers=(spec,))
def scene_command(wire_type: str) -> Callable[[type], type[Message]]:
    """A message a client sends that the server hands to the scene's command table."""
    return _message(wire_type, CLIENT, SCENE_COMMANDS)


@dataclass_transform(frozen_default=True, kw_only_default=True, field_specifiers=(spec,))
def engine_message(wire_type: str) -> Callable[[type], type[Message]]:
    """A message an engine sends."""
    return _message(wire_type, ENGINE)


# ------------------------------------------------------------------ client -> engine
@client_message("hello")
class Hello(Message):
    """Join an engine as ``operator`` or ``viewer`` (``token``/``secret``: a remote engine's access)."""

    role: str = spec("enum", ROLES)
    name: str = spec("str", 64)
    token: str | None = spec("str", 256, optional=True)
    secret: str | None = spec("str", 256, optional=True)


@client_message("bye")
class Bye(Message):
    """Leave: the engine forgets this client (an operator's role is free again)."""


@client_message("ping")
class Ping(Message):
    """Ask for a reply, to measure the round trip and keep the role."""

    seq: int | None = spec("int", 2**62, optional=True)


@client_message("input")
class Input(Message):
    """The operator's device: axes in [−1, 1] and buttons, numbered by ``seq``."""

    seq: int = spec("int", 2**62)
    t_send: float | None = spec("float", 1e12, optional=True)
    axes: list[float] = spec("unit_floats", 16)
    buttons: list[bool] = spec("bools", 64)
    device: str = spec("str", 128)


@client_message("device_lost")
class DeviceLost(Message):
    """The device is gone (unplugged, focus lost, a key release lost): the engine halts."""

    device: str | None = spec("str", 128, optional=True)
    released: bool | None = spec("bool", optional=True)


@scene_command("set_robot")
class SetRobot(Message):
    """Load a robot by name, path, or the XML sent with it."""

    robot: str = spec("str", 1024)
    xml: str | None = spec("str", 60_000, optional=True)


@scene_command("set_solver")
class SetSolver(Message):
    """Choose the IK solver by name (``bosun robots solvers``)."""

    solver: str = spec("str", 64)


@scene_command("set_ga_task")
class SetGaTask(Message):
    """The GA's task weighting (issue 32, item 4): the normalised position error's weight per world axis, and
    optionally the direction the tool's z should point along with that term's weight (default 1).  The published
    cost is weights 1, 1, 1 and no axis.  A change disarms the input."""

    weights: list[float] = spec("vec3", 100.0)
    axis: list[float] | None = spec("vec3", 1.0e3, optional=True)
    axis_weight: float | None = spec("float", 100.0, optional=True)


@scene_command("set_mode")
class SetMode(Message):
    """Choose the position or the velocity workspace."""

    mode: str = spec("enum", MODES)


@scene_command("set_frame")
class SetFrame(Message):
    """Choose the frame the stick commands in (issue 30, item 1): world (earth-fixed), base, tool, or target (a
    moving deck, in the scenes that have one).  A change disarms the input."""

    frame: str = spec("enum", FRAMES)


@scene_command("set_scaling")
class SetScaling(Message):
    """The workspaces' scaling: position gain, workspace half-size, velocity gain (each x, y, z)."""

    k_p: list[float] | None = spec("vec3", 1e4, optional=True)
    x_w: list[float] | None = spec("vec3", 1e5, optional=True)
    k_v: list[float] | None = spec("vec3", 1000.0, optional=True)


@client_message("estop")
class Estop(Message):
    """STOP: anyone's, always; ``token`` lets a remote engine check it."""

    reason: str | None = spec("str", 256, optional=True)
    token: str | None = spec("str", 256, optional=True)


@client_message("ack_alarm")
class AckAlarm(Message):
    """Acknowledge one alarm (``key``) or all."""

    key: str | None = spec("str", 64, optional=True)


@client_message("shelve_alarm")
class ShelveAlarm(Message):
    """Shelve one alarm for ``minutes`` (ISA-18.2 §12.3; at most 60, default 10; 0 unshelves it now)."""

    key: str = spec("str", 64)
    minutes: float | None = spec("float", 60.0, optional=True)


@client_message("reset")
class Reset(Message):
    """Clear the E-STOP latch; nothing moves until a fresh operator command."""


@client_message("release_operator")
class ReleaseOperator(Message):
    """Give up the operator role."""


@client_message("describe")
class Describe(Message):
    """Ask for the engine's description (robot files, limits, geometry)."""


@client_message("pause")
class Pause(Message):
    """Pause or resume the simulation clock."""

    on: bool = spec("bool")


# ------------------------------------------------------------------ teleop scene
@scene_command("study_start")
class StudyStart(Message):
    """Teleop scene: start an IK study in a worker process the engine owns."""

    study: str = spec("enum", ("distribution", "tracking"))
    solver: str | None = spec("str", 64, optional=True)
    grid: int | None = spec("int", 40, optional=True)


@scene_command("study_cancel")
class StudyCancel(Message):
    """Teleop scene: cancel the running IK study."""


# ------------------------------------------------------------------ crane-head scene (``bosun server --plant tac``)
@scene_command("set_vessel")
class SetVessel(Message):
    """Crane-head scene: the vessel (issue 17, item 2), a name (``bosun vessel list``) or an RAO table in
    Bosun's CSV, sent in parts of ≤ 60 000 characters (``part`` 0 … ``parts`` − 1, in order; a part 0 starts
    anew)."""

    vessel: str | None = spec("str", 64, optional=True)
    csv: str | None = spec("str", 60_000, optional=True)
    part: int | None = spec("int", 63, optional=True)
    parts: int | None = spec("int", 64, optional=True)
    label: str | None = spec("str", 256, optional=True)


@scene_command("set_sea")
class SetSea(Message):
    """Crane-head scene: the sea state (spectrum, Hs, Tp, heading in degrees)."""

    spectrum: str = spec("enum", ("jonswap", "pm", "torsethaugen"))
    hs: float = spec("float", 30.0)
    tp: float = spec("float", 40.0)
    heading: float = spec("float", 720.0)


@scene_command("set_tac_mode")
class SetTacMode(Message):
    """Crane-head scene: no compensation, TAC, or cooperative crane and head."""

    mode: str = spec("enum", ("off", "tac", "cooperative"))


@scene_command("set_crane_antisway")
class SetCraneAntisway(Message):
    """Crane-head scene (issue 30): the load's swing estimator and anti-swing law on (an offset of the TCP's target
    against the swing) or off (the offset returns to zero along the law)."""

    on: bool = spec("bool")


@scene_command("set_lift_window")
class SetLiftWindow(Message):
    """Crane-head scene (issue 31): the lift window's threshold [m] — a window is open while the tip's heave (over
    the target deck with a vessel target) is predicted to stay within ± this of its mean for 10 s."""

    threshold: float = spec("float", 10.0)


@scene_command("set_lab_delay")
class SetLabDelay(Message):
    """Motion-Lab scene, simulated (issue 31): the delay [s] with which the Comau's and winch's laws see the
    platforms' motion, and whether the motion predicted that far ahead is fed instead."""

    delay: float = spec("float", 2.0)
    predict: bool = spec("bool")


@scene_command("set_tac_delay")
class SetTacDelay(Message):
    """Crane-head scene (issue 31): the measurement-to-actuation delay [s] (the controller sees the MRU this late),
    and whether the motion predicted that far ahead from the MRU is fed instead."""

    delay: float = spec("float", 2.0)
    predict: bool = spec("bool")


@scene_command("set_crane_target")
class SetCraneTarget(Message):
    """Crane-head scene (issue 30): the deck the load is landed on, the fixed platform or a second vessel's."""

    target: str = spec("enum", ("platform", "vessel"))


@scene_command("tac_target_link")
class TacTargetLink(Message):
    """Crane-head scene (issue 30): the second vessel's motion link up or down (simulated: training and tests)."""

    up: bool = spec("bool")


# ------------------------------------------------------------------ Motion-Lab (``bosun server --plant lab``)
@scene_command("lab_platform")
class LabPlatform(Message):
    """Motion-Lab (``bosun server --plant lab``): move a Stewart platform to neutral, settle, engage or disengage it."""

    platform: str = spec("str", 32)
    action: str = spec("enum", ("neutral", "settle", "engage", "disengage"))


@scene_command("lab_source")
class LabSource(Message):
    """Motion-Lab: a platform's motion source (simulation, generator, remote, time series) and its settings."""

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


@scene_command("lab_remote_pose")
class LabRemotePose(Message):
    """Motion-Lab: a platform's pose in REMOTE (η: x, y, z, φ, θ, ψ)."""

    platform: str = spec("str", 32)
    eta: list[float] = spec("floats", 6)


@scene_command("lab_comau_mode")
class LabComauMode(Message):
    """Motion-Lab: the Comau's mode."""

    mode: str = spec("enum", ("settled", "remote", "motion_comp"))


@scene_command("lab_winch")
class LabWinch(Message):
    """Motion-Lab: the winch's mode and jog speed."""

    mode: str | None = spec("enum", ("local", "remote", "motion_comp"), optional=True)
    speed: float | None = spec("float", 10.0, optional=True)


@scene_command("lab_vvmc")
class LabVvmc(Message):
    """Motion-Lab: vessel-to-vessel motion compensation on or off."""

    on: bool = spec("bool")


@scene_command("lab_plc_ack")
class LabPlcAck(Message):
    """The real lab's PLC (``--plc``): acknowledge its error as the lab HMI does (``platform``: only that
    one)."""

    platform: str | None = spec("str", 32, optional=True)


@scene_command("lab_comau_jog")
class LabComauJog(Message):
    """The Comau's joint jog (issue 16, item 5): ``joint`` 1–3 (q1–q3), ``speed`` a fraction of the
    profile's joint speed; resent while held, zero when let go (a speed not refreshed for 0.3 s returns to
    zero)."""

    joint: int = spec("int", 3)
    speed: float = spec("float", 1.0)


@scene_command("lab_antisway")
class LabAntisway(Message):
    """The load-swing estimator and anti-swing law (issue 16, item 4; the lab HMI's "Pendel Estimator"
    buttons)."""

    action: str = spec("enum", ("activate", "deactivate", "reset"))


# ------------------------------------------------------------------ engine -> client
@engine_message("welcome")
class Welcome(Message):
    """The engine's answer to ``hello``: this client's id, its role, and where the state is published."""

    client_id: str = spec("str", 64)
    role: str = spec("enum", ROLES)
    state_url: str = spec("str", 1024)
    note: str | None = spec("str", 256, optional=True)


@engine_message("reply")
class Reply(Message):
    """The engine's answer to a command (``re``): done, or refused with the reason."""

    re: str = spec("str", 32)
    ok: bool = spec("bool")
    error: str | None = spec("str", 1024, optional=True)


@engine_message("state")
class State(Message):
    """A state snapshot (:mod:`app.net.snapshots`)."""

    state: dict[str, Any] = spec("map")


@engine_message("description")
class Description(Message):
    """The engine's static description, the answer to ``describe``."""

    description: dict[str, Any] = spec("map")


@engine_message("study")
class Study(Message):
    """An IK study's progress or result."""

    study: dict[str, Any] = spec("map")


@engine_message("log")
class Log(Message):
    """A line for the operator's log."""

    level: str = spec("enum", ("info", "warning", "error"))
    text: str = spec("str", 1024)
    t: float = spec("float", 1e12)


CLIENT_MESSAGES: dict[str, dict[str, tuple]] = {t: c.schema() for t, c in CLIENT.items()}
ENGINE_MESSAGES: dict[str, dict[str, tuple]] = {t: c.schema() for t, c in ENGINE.items()}
SCENE_MESSAGES = frozenset(SCENE_COMMANDS)

#: messages only the operator may send (a viewer gets an error reply); E-STOP is anyone's
OPERATOR_ONLY = frozenset({"input", "device_lost", "reset", "ack_alarm", "shelve_alarm", "pause"} | SCENE_MESSAGES)
