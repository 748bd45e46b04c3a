"""The interface of a Motion-Lab plant backend.

The scene keeps one model of the lab, a :class:`~app.scenes.lab.MotionLab` (``backend.lab``): its
platforms, robot, winch and load are what the scene draws, publishes and raises alarms on.  The
backend owns the machines behind that model:

* ``simulated`` steps the model: it *is* the plant;
* ``plc`` never steps it: every tick it sets the model to the states the lab's PLC reported (a mirror),
  and turns the scene's commands into writes of the PLC's symbols.

The scene calls the commands (each done, or refused with :class:`BackendError` and one line), calls
:meth:`LabBackend.poll` at the start of every tick (also while paused) and :meth:`LabBackend.step` to
advance, and reads :meth:`LabBackend.link` for its snapshot.  A backend that talks to hardware does so
from its own thread and hands data over through a queue drained in :meth:`LabBackend.poll`; nothing
calls into the engine's loop.
"""

from __future__ import annotations

import abc
import math
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from app.errors import BosunError
from app.net.snapshots import MachineLight, MotionStatus, PlantLink
from app.plc.symbols import GENERATOR_AMPLITUDE, GENERATOR_OMEGA, GENERATOR_PHASE
from app.scenes.lab import MotionLab
from app.sim.stewart import Generator, Platform


class BackendError(BosunError):
    """A command the plant backend refuses (one line); nothing was changed or sent."""


#: the lab HMI's "Machine and Sensor States" lights, in its order (motionlab_plc.json ``hmi_tabs``)
MACHINES = ("em8000", "em1500", "comau", "mru1", "mru2", "tracker", "remote")
#: the lab's remote interface counts as gone after this long without a message (``remote_interface.timeout_ms``)
REMOTE_TIMEOUT = 0.5
#: the lab PLC's sine-generator defaults (``sineAmplitude``, ``sineOmega`` / 2π, ``sinePhase``): amplitude [m, rad],
#: frequency [Hz], phase [rad]; a ``lab_source`` generator without a field takes these
GENERATOR_DEFAULT = (
    list(GENERATOR_AMPLITUDE),
    [w / (2 * math.pi) for w in GENERATOR_OMEGA],
    list(GENERATOR_PHASE),
)


def lab_generator(plat: Platform, fields: dict[str, Any] | None = None) -> Generator:
    """The checked sine generator a ``lab_source`` command's ``fields`` ask of platform ``plat`` (in its
    command box); a field it lacks takes the lab PLC's default (:data:`GENERATOR_DEFAULT`).
    :class:`BackendError` when the generator is refused."""
    p = fields or {}
    try:
        return Generator.make(
            p.get("amplitude", GENERATOR_DEFAULT[0]),
            p.get("frequency", GENERATOR_DEFAULT[1]),
            p.get("phase", GENERATOR_DEFAULT[2]),
            plat.model,
            plat.command_box,
        )
    except BosunError as err:
        raise BackendError(str(err)) from None


class LabBackend(abc.ABC):
    """What the Motion-Lab scene needs from a plant.  Platforms are given by index ``k`` (0: EM8000,
    1: EM1500, the layout's order).

    Parameters
    ----------
    lab : MotionLab   the scene's model of the lab (stepped, or set from measurements)
    """

    NAME: ClassVar[str] = ""

    def __init__(self, lab: MotionLab) -> None:
        self.lab = lab
        self.layout = lab.layout
        self.names = [n for n, _ in lab.layout.platforms]
        #: called after each model step with its dt (the scene's load-swing estimator; a plant that steps no
        #: model of its own, the PLC's, never calls it)
        self.after_step: Callable[[float], None] | None = None

    @property
    def winch_speed_max(self) -> float:
        """The winch speed the operator's slider and stick command at full deflection [m/s]."""
        return float(self.layout.winch["speed"])

    # ------------------------------------------------------------------ commands
    @abc.abstractmethod
    def platform(self, k: int, action: str) -> None:
        """``neutral``, ``settle``, ``engage`` or ``disengage`` (the lab HMI's mode buttons)."""

    @abc.abstractmethod
    def source(self, k: int, source: str, params: dict[str, Any]) -> dict[str, Any]:
        """Choose a platform's motion source with its parameters; returns what the scene shows of it."""

    @abc.abstractmethod
    def remote_pose(self, k: int, eta: Any) -> None:
        """The pose [m, rad] a platform follows in REMOTE."""

    @abc.abstractmethod
    def comau_mode(self, mode: str) -> None: ...

    @abc.abstractmethod
    def winch_mode(self, mode: str) -> None: ...

    @abc.abstractmethod
    def winch_speed(self, speed: float) -> None:
        """LOCAL: the spring-return slider's speed [m/s] (0 when it is let go)."""

    @abc.abstractmethod
    def vvmc(self, on: bool) -> None: ...

    @abc.abstractmethod
    def drive(self, tool_velocity_r: NDArray[np.float64], winch_speed: float) -> None:
        """The operator's stick, every tick: Comau tool velocity in its base frame [m/s] (REMOTE), or the work
        point's in EM1500's frame (MOTION_COMP: REMOTE under VVMC), and the winch speed [m/s] (REMOTE; under
        VVMC it lowers the load relative to EM1500); zeros when the input may not move anything."""

    @abc.abstractmethod
    def estop(self) -> None:
        """Stop every machine (also with the link to the plant down: then as soon as it is back)."""

    @abc.abstractmethod
    def reset(self) -> None:
        """Clear the E-STOP: every machine holds where it stands until commanded anew."""

    def set_vessel_rao(self, table: Any) -> None:
        """The RAO table the wave simulator uses from its next SIMULATION source on (issue 17, item 2)."""
        raise BackendError(
            f"the {self.NAME} lab's wave simulator takes no RAO table (the lab PLC's: w0, lambda, sigma only)"
        )

    def comau_jog(self, qd: NDArray[np.float64]) -> None:
        """The Comau's joint jog: joint speeds [rad/s] (3; one non-zero, or all zero to stop), REMOTE only.
        The scene refreshes it while the operator holds a jog button and zeroes it when the jog goes stale
        (issue 16, item 5).  A plant that cannot take joint speeds refuses a non-zero jog."""
        if np.any(np.asarray(qd) != 0.0):
            raise BackendError(f"Comau joint jog: the {self.NAME} plant takes no joint speeds")

    def acknowledge(self, k: int | None) -> str:
        """Acknowledge the plant's fault (the PLC's error state; ``k``: one platform only); returns what
        was done, one line."""
        raise BackendError(f"no PLC: this engine runs the {self.NAME} lab (bosun server --plant lab --plc …)")

    # ------------------------------------------------------------------ loop and state
    def poll(self, now: float) -> list[tuple[str, str]]:
        """Start of a tick (also while paused): take what came from the plant.  Returns log lines
        ``(level, text)`` and link events ``("link_lost" | "link_up", text)`` (the scene disarms the
        input on both)."""
        return []

    @abc.abstractmethod
    def step(self, dt: float, n: int) -> None:
        """Advance the model by ``n`` steps of ``dt`` seconds (simulated), or nothing (the real lab)."""

    @abc.abstractmethod
    def link(self, now: float) -> PlantLink:
        """The backend and the state of its link, for the snapshot."""

    @abc.abstractmethod
    def motion_status(self, k: int) -> MotionStatus | None:
        """Platform ``k``'s Rexroth status word (state, status, op mode) as the lab's HMI shows it; None when
        nothing is known (issue 16, item 5)."""

    @abc.abstractmethod
    def machines(self, now: float) -> list[MachineLight]:
        """The lab HMI's "Machine and Sensor States" lights: em8000, em1500, comau, mru1, mru2, tracker, remote."""

    def ready(self) -> str:
        """ "" when commands reach the plant now, else why not (one line)."""
        return ""

    def stop_path(self) -> str:
        """ "" when a STOP reaches the plant now, else why not (one line): the E-STOP then latches here only."""
        return self.ready()

    def motion_block(self) -> str:
        """Why commands that could start motion are refused although commands reach the plant (a STOP that
        cannot reach it, invalid data from it: issue 27), one line; "" when they are taken."""
        return ""

    def close(self) -> None:  # noqa: B027 - optional: a simulated plant owns nothing to release
        """Release threads and connections."""
