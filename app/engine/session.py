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

from app.engine.alarms import AlarmList
from app.errors import BosunError, one_line, printable
from app.ik import DEFAULT, make_solver
from app.models.registry import allowed_dirs, load_robot, load_robot_text
from app.models.serial import SerialRobot
from app.models.workspace import workspace_box
from app.sim.actuators import JointActuators
from app.teleop.devices import InputSample
from app.teleop.mapping import (
    MODES,
    Scaling,
    default_scaling,
    position_target,
    velocity_command,
)
from app.teleop.pipeline import InputPipeline
from app.teleop.profiles import DeviceProfile

DEFAULT_ROBOT = "comau_smart5_3dof"
DEFAULT_SOLVER = "jacobian"
SINGULARITY_RATIO = 0.01  # σ_min/σ_max of the speed-scaled position Jacobian below this: alarm


class CommandError(BosunError):
    """A command the engine refuses; nothing has changed."""


def _label(ref: str) -> str:
    """The file name a client gave its robot text, as shown in errors."""
    return printable(ref.replace("\\", "/").rsplit("/", 1)[-1], 80) or "<robot text>"


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
    robots_dirs: tuple = ()  # folders set_robot may read besides the library (``--robots-dir``)
    log: deque = field(default_factory=lambda: deque(maxlen=200))

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise CommandError(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        self.estop_latched = False
        self.log_seq = 0
        self.input = InputPipeline(self.stale_timeout, note=self.note)
        self.alarms = AlarmList("teleop", note=self.note)
        self.enabled = False
        self.stale = True
        self.signal = np.zeros(3)
        self.command_point = None  # the operator's command as a point (eq. 1, or eq. 7 integrated)
        self.solver_cost = math.nan
        self.solver_time = 0.0
        self.solver_ok = True
        self.ticks = 0
        self.sim_time = 0.0
        self._armed_prev = False
        self._load(self.robot_name, self.solver_name)

    # ------------------------------------------------------------------ logging
    def note(self, level: str, text: str) -> None:
        self.log_seq += 1
        self.log.append(LogEntry(self.log_seq, time.time(), level, text))

    # ------------------------------------------------------------------ commands
    def _load(self, robot_ref: str, solver_name: str, robot=None) -> None:
        robot = load_robot(robot_ref) if robot is None else robot
        if not isinstance(robot, SerialRobot):
            raise CommandError(f"{robot.name} is a {robot.kind} mechanism; the teleoperation engine drives serial arms")
        solver = make_solver(solver_name, robot, seed=self.seed)
        q0 = 0.5 * (robot.lower + robot.upper)
        old = getattr(self, "robot", None)
        if old is not None and old.joint_names == robot.joint_names and np.all(robot.within_limits(self.actuators.q)):
            q0 = self.actuators.q.copy()  # the same joints reloaded: the arm stays where it stands
        act = JointActuators(robot.lower, robot.upper, robot.speed, robot.accel, self.actuator_tau, q0)
        box = workspace_box(robot)
        # everything built: now switch (a failure above leaves the old robot in place)
        self.robot, self.solver, self.actuators, self.box = robot, solver, act, box
        self.robot_name, self.solver_name = robot.name, solver_name
        self.q_ref = act.q.copy()
        self.target = robot.position(self.q_ref)
        self.scaling = default_scaling(box, self.target)

    def moving(self) -> bool:
        """Whether any joint moves faster than 0.1 % of its speed limit."""
        return bool(np.any(np.abs(self.actuators.qdot) > 1e-3 * self.robot.speed))

    def set_robot(self, robot_ref: str, xml: str | None = None) -> None:
        """Load a robot; on any error the previous robot stays.

        ``robot_ref`` is a library name or a path inside the allowed robot folders (the
        library, ``$BOSUN_ROBOTS_DIR``, :attr:`robots_dirs`); with ``xml`` the client sent the
        file's text and ``robot_ref`` only names it.  Refused while the arm moves.
        """
        if self.estop_latched:
            raise CommandError("E-STOP is latched; reset before changing the robot")
        if self.moving():
            raise CommandError("the robot is moving; release ENABLE and let it come to rest before changing the robot")
        solver = self.solver_name
        try:
            if xml is not None:
                robot = load_robot_text(xml, _label(robot_ref))
            else:
                robot = load_robot(robot_ref, allowed=allowed_dirs(self.robots_dirs))
            if not isinstance(robot, SerialRobot):
                raise CommandError(
                    f"{robot.name} is a {robot.kind} mechanism; the teleoperation engine drives serial arms"
                )
            try:
                make_solver(solver, robot)
            except BosunError as err:
                if "no closed-form solution" not in str(err):
                    raise
                solver = DEFAULT_SOLVER
            self._load(robot_ref, solver, robot)
        except BosunError as err:
            raise CommandError(one_line(str(err), 300)) from None
        self.input.disarm("robot changed")
        self.note("info", f"robot {self.robot_name} loaded ({self.robot.n_joints} joints, solver {solver})")

    def set_solver(self, name: str) -> None:
        try:
            solver = make_solver(name, self.robot, seed=self.seed)
        except BosunError as err:
            raise CommandError(str(err)) from None
        self.solver, self.solver_name = solver, name
        self.input.disarm("solver changed")
        self.note("info", f"solver {name}")

    def set_mode(self, mode: str) -> None:
        if mode not in MODES:
            raise CommandError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
        if mode != self.mode:
            self.mode = mode
            # position mode starts from where the tool is: releasing the stick returns here
            self.scaling = self.scaling.with_origin(self.robot.position(self.actuators.q))
            self.q_ref = self.actuators.q.copy()
            self.command_point = None
            self.input.disarm("mode changed")
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
        self.input.disarm("scaling changed")  # a new k_p, x_w or k_v never moves an armed arm by itself

    def set_profile(self, profile: DeviceProfile | None) -> None:
        """Use this profile for every device (None: pick by device name again)."""
        self.input.set_profile(profile)

    @property
    def profile(self) -> DeviceProfile:
        return self.input.profile

    def operator_changed(self, name: str) -> None:
        """A new operator (or the same one reconnected): its first command must be a fresh one."""
        self.input.disarm(f"operator {name} connected")

    def estop(self, source: str = "operator") -> None:
        """Stop all motion in this tick and latch."""
        self.actuators.stop()
        self.q_ref = self.actuators.q.copy()
        if not self.estop_latched:
            self.note("error", f"E-STOP from {source}")
        self.estop_latched = True

    def reset(self) -> None:
        """Clear a latched E-STOP; the arm holds where it stands until the operator commands anew."""
        if self.estop_latched:
            self.estop_latched = False
            self.q_ref = self.actuators.q.copy()
            self.command_point = None
            if self.mode == "position":
                self.scaling = self.scaling.with_origin(self.robot.position(self.actuators.q))
            self.input.disarm("E-STOP reset")
            self.note("info", "E-STOP reset: holding; centre the stick and press enable to drive")

    # ------------------------------------------------------------------ input
    def feed(self, sample: InputSample | None, now: float, released: bool = False) -> None:
        """The latest reading of the input device (None: no device connected), at engine receive time."""
        self.input.feed(sample, now, released)

    # ------------------------------------------------------------------ control tick
    def _hold(self) -> None:
        self.q_ref = self.actuators.q.copy()

    def tick(self, now: float, dt: float, solve_budget: float | None = None) -> None:
        """One control step of length dt [s] at engine time ``now`` [s]."""
        self.ticks += 1
        self.sim_time += dt
        inp = self.input.step(now)
        if inp.stop:
            self.estop(source=f"the stop button of {self.input.profile.name}")
        if inp.armed and not self._armed_prev and self.mode == "position":
            # position mode starts from where the tool is at every arming: arming at neutral never moves it
            self.scaling = self.scaling.with_origin(self.robot.position(self.q_ref))
        self._armed_prev = inp.armed
        self.stale, self.enabled = inp.stale, inp.enabled and not self.estop_latched
        self.signal = inp.raw_signal[:3].copy()
        if self.estop_latched:
            self.actuators.stop()
            self._hold()
            self.command_point = None
            self._check_alarms(None, dt)
            return
        if inp.mode_toggle:
            self.set_mode("position" if self.mode == "velocity" else "velocity")
            self.enabled = False
        if not self.enabled:
            self._hold()
            self.command_point = None
            self.actuators.step(self.q_ref, dt)
            self._check_alarms(None, dt)
            return
        s = inp.signal[:3]
        q_ref_before = self.q_ref.copy()
        budget = DEFAULT if solve_budget is None else solve_budget
        xdot = None
        if self.mode == "position":
            self.command_point = position_target(s, self.scaling.k_p, self.scaling.x_w)  # eq. (1)
            res = self.solver.solve_position(self.command_point, self.q_ref, time_budget=budget)
            self.q_ref = res.q
            self.target = np.asarray(self.command_point, dtype=float)
        else:
            xdot = velocity_command(s, self.scaling.k_v)  # eq. (2)
            x_ref = self.robot.position(self.q_ref)
            if np.any(xdot != 0.0):
                # the operator's command as a point: eq. (7) integrated from where the reference was
                start = x_ref if self.command_point is None else self.command_point
                self.command_point = start + xdot * dt
                res = self.solver.solve_velocity(self.q_ref, xdot, dt, time_budget=budget)  # eqs. (4), (7), (9)
                self.target = x_ref + xdot * dt  # eq. (7): the solver's target this tick
                self.q_ref = res.q
            else:
                res = None  # released stick: stop and keep the last position
                self.command_point = None
                self.target = x_ref
        if res is not None:
            self.solver_cost, self.solver_time, self.solver_ok = res.error, res.time_s, res.success
        self.actuators.step(self.q_ref, dt)
        self._check_alarms(xdot, dt, q_ref_before)

    # ------------------------------------------------------------------ alarms
    def _check_alarms(self, xdot, dt: float, q_before=None) -> None:
        """Per tick: E-STOP, input, joint limits against the command, speed limiting, singularity.

        ``q_before``: the joint reference before this tick's solve; the reference's tool step is
        compared with the commanded one (velocity mode)."""
        al = self.alarms
        flags = self.input.flags()
        al.set("estop", self.estop_latched, "critical", "E-STOP latched: reset to continue")
        al.set(
            "device_lost",
            self.input.lost,
            "warning",
            "input device lost: holding",
        )
        al.set(
            "stale_input",
            self.input.connected and flags["stale_input"],
            "warning",
            f"stale input (nothing for {self.input.stale_timeout * 1e3:.0f} ms): holding",
        )
        lo, hi = self.robot.lower, self.robot.upper
        tol = 1e-6 * np.maximum(1.0, hi - lo)
        blocked = ""
        limited = False
        if xdot is not None and np.any(xdot != 0.0) and q_before is not None:
            v_cmd = float(np.linalg.norm(xdot))
            step = self.robot.position(self.q_ref) - self.robot.position(q_before)
            progress = float(step @ xdot) / (v_cmd * dt * v_cmd) if v_cmd > 0 else 1.0
            at_lo, at_hi = self.q_ref <= lo + tol, self.q_ref >= hi - tol
            if progress < 0.5 and np.any(at_lo | at_hi):
                k = int(np.flatnonzero(at_lo | at_hi)[0])
                blocked = f"{self.robot.joint_names[k]} at its {'lower' if at_lo[k] else 'upper'} limit"
            limited = not blocked and progress < 0.9
        n = max(1, round(0.1 / dt))  # 100 ms: one alarm per episode, not one per tick
        al.set("joint_limit", bool(blocked), "warning", f"{blocked}: commanded direction blocked", debounce=n)
        al.set("speed_limited", limited, "info", "speed limited: k_v asks for more than the joints allow", debounce=n)
        if self.ticks % 10 == 0:
            ratio = self._sigma_ratio()
            text = f"near a singularity (σ ratio {ratio:.3f})"
            al.set("near_singularity", ratio < SINGULARITY_RATIO, "warning", text)

    def _sigma_ratio(self) -> float:
        """σ_min/σ_max of J·diag(joint speed limits) for the tool position: how evenly the joints, each at
        its own speed, can move the tool in every direction (1: isotropic, 0: a direction is lost)."""
        J = self.robot.jacobian(self.actuators.q)[:3] * self.robot.speed
        sv = np.linalg.svd(J, compute_uv=False)
        return float(sv[min(2, sv.size - 1)] / sv[0]) if sv[0] > 0 else 0.0

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
            "command": None if self.command_point is None else np.asarray(self.command_point, float).tolist(),
            "flags": {**self.input.flags(self.estop_latched), "enabled": self.enabled},
            "alarms": self.alarms.snapshot(),
        }
