"""The interface every engine scene (teleop arm, crane head, Motion-Lab) offers the server.

The server owns sockets and time; a scene owns its machines.  A scene has

* ``describe()``: its static data (a :class:`~app.net.snapshots.Description`), sent on join and
  whenever it changes (``describe_seq`` increments, :meth:`changed`);
* a **command table** ``COMMANDS``: a scene command's class (:data:`app.net.messages.SCENE_COMMANDS`) → the
  method that runs it (the scene's methods marked ``@command``, named as their message), called by
  :meth:`Scene.run` with the typed message's fields as keywords; a command of another scene is refused, and
  nothing is looked up by a string from the wire;
* ``tick(now, dt, solve_budget)``, ``snapshot()`` (a typed :class:`~app.net.snapshots.Snapshot`),
  ``estop(source)``, ``reset()``, ``pause(on)``;
* one log (``note``), one input pipeline (``input``) and one alarm list (``alarms``);
* ``events``: messages the scene wants published besides its state (study progress and results);
* ``jobs``: heavy command work off the control loop (:mod:`app.engine.jobs`): under a server, a command
  that starts one returns a :class:`~app.engine.jobs.Deferred` and its reply follows when the result has
  been swapped in at a tick boundary (or refused).
"""

from __future__ import annotations

import abc
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from app.engine.jobs import Jobs
from app.errors import BosunError
from app.net.messages import SCENE_COMMANDS, Message
from app.net.snapshots import Alarm, Description, InputFlags, Snapshot


class CommandError(BosunError):
    """A command the engine refuses; nothing has changed."""


@dataclass
class LogEntry:
    seq: int
    t: float
    level: str
    text: str


def command(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Marks a scene method as the handler of the scene command of its name (a class of
    :data:`app.net.messages.SCENE_COMMANDS`): the scene's ``COMMANDS`` table is made of them.  A name that is
    no scene command is a TypeError when the class is made."""
    if fn.__name__ not in SCENE_COMMANDS:
        raise TypeError(f"@command {fn.__name__}: no scene command of that name in app.net.messages")
    fn.command_type = SCENE_COMMANDS[fn.__name__]
    return fn


class Scene(abc.ABC):
    """Base of the engine's scenes; subclasses are dataclasses that call :meth:`_init_scene`."""

    KIND: ClassVar[str] = ""
    TITLE: ClassVar[str] = ""
    #: scene command class -> the method that runs it (fields as keywords); built from the ``@command``
    #: methods of the class and its bases
    COMMANDS: ClassVar[dict[type[Message], Callable[..., Any]]] = {}

    def __init_subclass__(cls, **kw: Any) -> None:
        super().__init_subclass__(**kw)
        own = vars(cls)  # an override of an inherited command runs, marked again or not
        table = {kind: own.get(kind.TYPE, fn) for kind, fn in cls.COMMANDS.items()}
        for fn in own.values():
            mtype = getattr(fn, "command_type", None)
            if mtype is not None:
                table[mtype] = fn
        cls.COMMANDS = table

    def _init_scene(self) -> None:
        self.log: deque = deque(maxlen=200)
        self.log_seq = 0
        self.estop_latched = False
        self.describe_seq = 1
        self.paused = False
        self.events: deque = deque(maxlen=256)  # (message type, fields) to publish
        self.jobs = Jobs()  # work off the loop; the server sets its pace (a scene on its own works in the command)

    # ------------------------------------------------------------------ log
    def note(self, level: str, text: str) -> None:
        self.log_seq += 1
        self.log.append(LogEntry(self.log_seq, time.time(), level, text))

    def _latch(self, text: str) -> bool:
        """Latch the E-STOP; the first STOP of a latch says ``text`` in the log.  True for that first one."""
        first = not self.estop_latched
        if first:
            self.note("error", text)
        self.estop_latched = True
        return first

    def _unlatch(self, text: str) -> None:
        """Clear the E-STOP latch once the scene holds its machines: the input is disarmed, so nothing moves
        until the operator commands anew; ``text`` says how the scene holds."""
        self.estop_latched = False
        self.input.disarm("E-STOP reset")
        self.note("info", f"E-STOP reset: {text}")

    def changed(self) -> None:
        """The description changed: clients are told by ``describe_seq`` and ask for it again."""
        self.describe_seq += 1

    # ------------------------------------------------------------------ commands
    def run(self, msg: Message) -> Any:
        """Run a typed scene command (validated once, when it was decoded) from the table; :class:`CommandError`
        for one of another scene.  Returns what the command returns: a :class:`~app.engine.jobs.Deferred` when
        its work went off the loop."""
        handler = self.COMMANDS.get(type(msg))
        if handler is None:
            raise CommandError(f"{msg.TYPE}: this engine runs {self.TITLE}, not the scene of that command")
        return handler(self, **msg.fields())

    def command(self, mtype: str, **fields: Any) -> Any:
        """:meth:`run` for a command built in this process (by type and fields: studies, benches, tests)."""
        kind = SCENE_COMMANDS.get(mtype)
        if kind is None:
            raise CommandError(f"{mtype}: no such scene command")
        return self.run(kind(**fields))

    def pause(self, on: bool) -> None:
        """Stand time still (no client shows this scene) or let it run again.  Pausing and resuming
        disarm the input: nothing moves on return until the operator commands anew."""
        if on != self.paused:
            self.paused = on
            self.input.disarm("scene paused" if on else "scene resumed")
            self.note("info", "paused: no client shows this scene" if on else "resumed")

    def operator_changed(self, name: str) -> None:
        """A new operator (or the same one reconnected): its first command must be a fresh one."""
        self.input.disarm(f"operator {name} connected")

    def feed(self, sample, now: float, released: bool = False) -> None:
        """The latest reading of the input device (None: no device connected), at engine receive time."""
        self.input.feed(sample, now, released)

    def _head(self) -> dict[str, Any]:
        """The fields every snapshot shares (``engine`` is filled in by the server)."""
        return {
            "estop": self.estop_latched,
            "describe_seq": self.describe_seq,
            "flags": InputFlags(**self.input.flags(self.estop_latched)),
            "alarms": [Alarm(**a) for a in self.alarms.snapshot()],
        }

    # ------------------------------------------------------------------ the scene's own
    @abc.abstractmethod
    def describe(self) -> Description: ...

    @abc.abstractmethod
    def snapshot(self) -> Snapshot: ...

    @abc.abstractmethod
    def tick(self, now: float, dt: float, solve_budget: float | None = None) -> None: ...

    @abc.abstractmethod
    def estop(self, source: str = "operator") -> None: ...

    @abc.abstractmethod
    def reset(self) -> None: ...

    def close(self) -> None:  # noqa: B027 - optional: most scenes own nothing to release
        """Release what the scene owns (worker processes)."""
