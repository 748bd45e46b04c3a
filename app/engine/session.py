"""Engine session: the state of one teleoperated manipulator and its control tick.

One tick (:meth:`Session.tick`) reads the latest input, shapes it through the device
profile, maps it to a target (eqs. 1, 2, 7), calls the selected solver within the tick's
time budget, and moves the simulated joints through their actuators (speed and
acceleration limits).  Safety rules live here, independent of timing and network:

* no input for ``stale_timeout`` (200 ms), a disconnected device, or the deadman released:
  the reference is set to where the joints are, so the robot brakes to a stop and holds;
* E-STOP: joint speeds are zeroed in the same tick and the state latches until
  :meth:`reset`; while latched nothing moves whatever the input says;
* a failed command (bad robot file, unknown solver) leaves everything as it was.

Qt-free and clock-free: the caller passes ``now``, so tests run deterministically.
"""

from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.errors import BosunError
from app.ik import DEFAULT, make_solver
from app.models.registry import load_robot
from app.models.serial import SerialRobot
from app.models.workspace import workspace_box
from app.sim.actuators import JointActuators
from app.teleop.devices import InputSample
from app.teleop.mapping import (
    MODES,
    Scaling,
    default_scaling,
    position_target,
    shape_input,
    velocity_command,
)
from app.teleop.profiles import DeviceProfile, default_profile, profile_for

DEFAULT_ROBOT = "comau_smart5_3dof"
DEFAULT_SOLVER = "jacobian"


class CommandError(BosunError):
    """A command the engine refuses; nothing has changed."""


@dataclass
class LogEntry:
    seq: int
    t: float
    level: str
    text: str


@dataclass
class Session:
    """The engine's model of one manipulator under teleoperation."""

    robot_name: str = DEFAULT_ROBOT
    solver_name: str = DEFAULT_SOLVER
    mode: str = "velocity"
    stale_timeout: float = 0.2
    actuator_tau: float = 0.05
    seed: int = 0
    log: deque = field(default_factory=lambda: deque(maxlen=200))

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise CommandError(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        self.estop_latched = False
        self.log_seq = 0
        self.profile: DeviceProfile = default_profile()
        self.profile_locked = False
        self.sample: InputSample | None = None
        self.sample_time = -math.inf
        self.device_connected = False
        self.enabled = False
        self.stale = True
        self.signal = np.zeros(3)
        self.solver_cost = math.nan
        self.solver_time = 0.0
        self.solver_ok = True
        self.ticks = 0
        self.sim_time = 0.0
        self._mode_button_prev = False
        self._load(self.robot_name, self.solver_name)

    # ------------------------------------------------------------------ logging
    def note(self, level: str, text: str) -> None:
        self.log_seq += 1
        self.log.append(LogEntry(self.log_seq, time.time(), level, text))

    # ------------------------------------------------------------------ commands
    def _load(self, robot_ref: str, solver_name: str) -> None:
        robot = load_robot(robot_ref)
        if not isinstance(robot, SerialRobot):
            raise CommandError(f"{robot.name} is a {robot.kind} mechanism; the teleoperation engine drives serial arms")
        solver = make_solver(solver_name, robot, seed=self.seed)
        q0 = 0.5 * (robot.lower + robot.upper)
        act = JointActuators(robot.lower, robot.upper, robot.speed, robot.accel, self.actuator_tau, q0)
        box = workspace_box(robot)
        # everything built: now switch (a failure above leaves the old robot in place)
        self.robot, self.solver, self.actuators, self.box = robot, solver, act, box
        self.robot_name, self.solver_name = robot.name, solver_name
        self.q_ref = act.q.copy()
        self.target = robot.position(self.q_ref)
        self.scaling = default_scaling(box, self.target)

    def set_robot(self, robot_ref: str) -> None:
        """Load a robot by library name or path; on any error the previous robot stays."""
        if self.estop_latched:
            raise CommandError("E-STOP is latched; reset before changing the robot")
        solver = self.solver_name
        try:
            robot = load_robot(robot_ref)
            if not isinstance(robot, SerialRobot):
                raise CommandError(
                    f"{robot.name} is a {robot.kind} mechanism; the teleoperation engine drives serial arms"
                )
            make_solver(solver, robot)
        except BosunError as err:
            if "no closed-form solution" in str(err):
                solver = DEFAULT_SOLVER
            else:
                raise CommandError(str(err)) from None
        self._load(robot_ref, solver)
        self.note("info", f"robot {self.robot_name} loaded ({self.robot.n_joints} joints, solver {solver})")

    def set_solver(self, name: str) -> None:
        try:
            solver = make_solver(name, self.robot, seed=self.seed)
        except BosunError as err:
            raise CommandError(str(err)) from None
        self.solver, self.solver_name = solver, name
        self.note("info", f"solver {name}")

    def set_mode(self, mode: str) -> None:
        if mode not in MODES:
            raise CommandError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
        if mode != self.mode:
            self.mode = mode
            # position mode starts from where the tool is: releasing the stick returns here
            self.scaling = self.scaling.with_origin(self.robot.position(self.actuators.q))
            self.q_ref = self.actuators.q.copy()
            self.note("info", f"mode {mode}")

    def set_scaling(self, k_p=None, x_w=None, k_v=None) -> None:
        new = Scaling(
            tuple(np.broadcast_to(np.asarray(k_p, dtype=float), 3)) if k_p is not None else self.scaling.k_p,
            tuple(np.asarray(x_w, dtype=float)) if x_w is not None else self.scaling.x_w,
            tuple(np.broadcast_to(np.asarray(k_v, dtype=float), 3)) if k_v is not None else self.scaling.k_v,
        )
        try:
            self.scaling = new.validate()
        except ValueError as err:
            raise CommandError(str(err)) from None

    def set_profile(self, profile: DeviceProfile | None) -> None:
        """Use this profile for every device (None: pick by device name again)."""
        self.profile_locked = profile is not None
        if profile is not None:
            self.profile = profile

    def estop(self, source: str = "operator") -> None:
        """Stop all motion in this tick and latch."""
        self.actuators.stop()
        self.q_ref = self.actuators.q.copy()
        if not self.estop_latched:
            self.note("error", f"E-STOP from {source}")
        self.estop_latched = True

    def reset(self) -> None:
        if self.estop_latched:
            self.estop_latched = False
            self.q_ref = self.actuators.q.copy()
            if self.mode == "position":
                self.scaling = self.scaling.with_origin(self.robot.position(self.actuators.q))
            self.note("info", "E-STOP reset")

    # ------------------------------------------------------------------ input
    def feed(self, sample: InputSample | None, now: float) -> None:
        """The latest reading of the input device (None: no device connected)."""
        if sample is None:
            if self.device_connected:
                self.note("warning", "input device disconnected: holding")
            self.device_connected = False
            self.sample = None
            return
        if not self.device_connected:
            self.note("info", f"input device {sample.device}")
            if not self.profile_locked:
                self.profile = profile_for(sample.device, len(sample.axes))
        self.device_connected = True
        self.sample, self.sample_time = sample, now

    # ------------------------------------------------------------------ control tick
    def _hold(self) -> None:
        self.q_ref = self.actuators.q.copy()

    def tick(self, now: float, dt: float, solve_budget: float | None = None) -> None:
        """One control step of length dt [s] at engine time ``now`` [s]."""
        self.ticks += 1
        self.sim_time += dt
        sample = self.sample
        self.stale = sample is None or (now - self.sample_time) > self.stale_timeout
        if self.estop_latched:
            self.actuators.stop()
            self._hold()
            self.enabled = False
            return
        if self.stale:
            self.enabled = False
            self._hold()
            self.actuators.step(self.q_ref, dt)
            return
        prof = self.profile
        mode_button = (
            prof.mode_button is not None and prof.mode_button < len(sample.buttons) and sample.buttons[prof.mode_button]
        )
        if mode_button and not self._mode_button_prev:
            self.set_mode("position" if self.mode == "velocity" else "velocity")
        self._mode_button_prev = bool(mode_button)
        self.enabled = prof.enabled(sample.buttons)
        self.signal = shape_input(prof.signal(sample.axes), prof.deadzone, prof.expo)
        if not self.enabled:
            self._hold()
            self.actuators.step(self.q_ref, dt)
            return
        budget = DEFAULT if solve_budget is None else solve_budget
        if self.mode == "position":
            self.target = position_target(self.signal, self.scaling.k_p, self.scaling.x_w)  # eq. (1)
            res = self.solver.solve_position(self.target, self.q_ref, time_budget=budget)
            self.q_ref = res.q
        else:
            xdot = velocity_command(self.signal, self.scaling.k_v)  # eq. (2)
            if np.any(xdot != 0.0):
                res = self.solver.solve_velocity(self.q_ref, xdot, dt, time_budget=budget)  # eqs. (4), (7), (9)
                self.q_ref = res.q
            else:
                res = None  # released stick: stop and keep the last position
            self.target = self.robot.position(self.q_ref)
        if res is not None:
            self.solver_cost, self.solver_time, self.solver_ok = res.error, res.time_s, res.success
        self.actuators.step(self.q_ref, dt)

    # ------------------------------------------------------------------ state
    def snapshot(self) -> dict[str, Any]:
        q = self.actuators.q
        return {
            "t": self.sim_time,
            "tick": self.ticks,
            "robot": self.robot_name,
            "solver": self.solver_name,
            "mode": self.mode,
            "joint_names": list(self.robot.joint_names),
            "q": q.tolist(),
            "qdot": self.actuators.qdot.tolist(),
            "q_ref": self.q_ref.tolist(),
            "lower": self.robot.lower.tolist(),
            "upper": self.robot.upper.tolist(),
            "tool": self.robot.position(q).tolist(),
            "frames": self.robot.frames(q)[:, :3, 3].tolist(),
            "target": np.asarray(self.target, dtype=float).tolist(),
            "signal": self.signal.tolist(),
            "solver_error": None if not math.isfinite(self.solver_cost) else float(self.solver_cost),
            "solver_time": float(self.solver_time),
            "solver_ok": bool(self.solver_ok),
            "scaling": {"k_p": list(self.scaling.k_p), "x_w": list(self.scaling.x_w), "k_v": list(self.scaling.k_v)},
            "box": [self.box.lower.tolist(), self.box.upper.tolist()],
            "flags": {
                "estop": self.estop_latched,
                "stale_input": self.stale,
                "enabled": self.enabled,
                "device": self.device_connected,
                "device_name": self.sample.device if self.sample is not None else "",
                "profile": self.profile.name,
            },
        }
