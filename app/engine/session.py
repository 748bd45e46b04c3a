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

import functools
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from app.control.guard import GuardReport, HazardGuard
from app.engine.alarms import AlarmList
from app.engine.scene import CommandError, LogEntry, Scene, command
from app.engine.studies import STUDIES, StudyError, StudyRunner
from app.errors import BosunError, error_line, one_line, printable_path
from app.ik import DEFAULT, GaTask, Replayed, make_solver, solvers_for
from app.models.registry import (
    allowed_dirs,
    list_robots,
    load_robot,
    load_robot_file,
    load_robot_text,
    robots_dir,
)
from app.models.serial import SerialRobot
from app.models.workspace import workspace_box
from app.net.snapshots import (
    HazardState,
    RobotEntry,
    ScalingState,
    StudyState,
    TeleopDescription,
    TeleopSnapshot,
)
from app.scenes.teleop_guard import guard_tick
from app.sim.actuators import JointActuators
from app.teleop.devices import InputSample
from app.teleop.mapping import (
    FRAMES,
    MODES,
    Scaling,
    default_scaling,
    in_frame,
    position_target,
    velocity_command,
)
from app.teleop.pipeline import InputPipeline
from app.teleop.profiles import DeviceProfile

DEFAULT_ROBOT = "comau_smart5_3dof"
DEFAULT_SOLVER = "jacobian"
#: the "speed limited" log line at most once in this many seconds of engine time: the state flickers as the arm
#: turns (three lines in one second were seen driving the Panda up from the floor)
SPEED_NOTE_INTERVAL = 10.0
REFINE_STEP = 0.02  # of each joint's range: the largest step a resting stick's refined answer may take
REFINE_TRIES = 50  # solves in a row that find nothing nearer for a resting stick: its point is out of reach


__all__ = ["CommandError", "LogEntry", "Session", "library_entries"]


def _label(ref: str) -> str:
    """The file name a client gave its robot text, as shown in errors."""
    return printable_path(ref.replace("\\", "/").rsplit("/", 1)[-1], 80) or "<robot text>"


@functools.cache
def library_entries(folder: str) -> tuple[RobotEntry, ...]:
    """The library's serial arms with the solvers that apply to each (what this engine can drive);
    ``folder``, the library folder now (``$BOSUN_ROBOTS_DIR``), is the cache key."""
    out = []
    for name in list_robots():
        try:
            robot = load_robot(name)
        except BosunError:
            continue  # a broken library file is reported when it is chosen, not here
        if isinstance(robot, SerialRobot):
            out.append(RobotEntry(name=name, joints=robot.n_joints, solvers=solvers_for(robot)))
    return tuple(out)


@dataclass
class Session(Scene):
    """The engine's model of one manipulator under teleoperation."""

    KIND: ClassVar[str] = "teleop"
    TITLE: ClassVar[str] = "the teleop scene"
    robot_name: str = DEFAULT_ROBOT
    solver_name: str = DEFAULT_SOLVER
    mode: str = "velocity"
    frame: str = "world"  # the frame the stick commands in (issue 30, item 1): world, base or tool
    stale_timeout: float = 0.2
    actuator_tau: float = 0.05
    seed: int = 0
    robots_dirs: tuple = ()  # folders set_robot may read besides the library (``--robots-dir``)
    ga_task: GaTask = field(default_factory=GaTask)  # the GA's task weighting (set_ga_task; the published cost)

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise CommandError(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        self._init_scene()
        self.studies = StudyRunner()
        self.input = InputPipeline(self.stale_timeout, note=self.note)
        self.alarms = AlarmList("Teleop", note=self.note)
        self.enabled = False
        self.stale = True
        self.signal = np.zeros(3)
        self.command_point = None  # the operator's command as a point (eq. 1, or eq. 7 integrated)
        self._position_answered = False  # position mode: the solver reached the resting stick's point
        self._refine_misses = 0  # position mode: solves in a row that found the resting stick's point no nearer
        self._hold_deadline: float | None = None  # engine time by which a holding arm must be at rest
        self._speed_limited = False
        self._speed_noted = -math.inf  # engine time of the last "speed limited" line
        self.solver_cost = math.nan
        self.solver_time = 0.0
        self.solver_ok = True
        self.ticks = 0
        self.sim_time = 0.0
        self._armed_prev = False
        self.dt_last = 0.002  # the last tick's length [s] (the guard's stopping point)
        self.braked = 0  # ticks the safe-braking rule braked the joints (:meth:`_guarded`)
        self.guard_tick = guard_tick  # the guard's tick (a benchmark watches it: app/bench/guard.py)
        self._brake_ref: np.ndarray | None = None  # the safe-braking rule's reference while it brakes
        self._frame_at_arming: np.ndarray | None = None  # position mode: the frame's rotation when armed
        self._load(self.robot_name, self.solver_name)

    # ------------------------------------------------------------------ commands
    def _load(self, robot_ref: str, solver_name: str, robot=None, xml: str | None = None, solver=None) -> None:
        if robot is None or xml is None:  # the file read once, by the reader ``bosun check`` uses
            robot, xml = load_robot_file(robot_ref)
        if not isinstance(robot, SerialRobot):
            raise CommandError(f"{robot.name} is a {robot.kind} mechanism; the teleoperation engine drives serial arms")
        if solver is None:
            solver = self._make_solver(solver_name, robot)
        q0 = 0.5 * (robot.lower + robot.upper)
        old = getattr(self, "robot", None)
        if old is not None and old.joint_names == robot.joint_names and np.all(robot.within_limits(self.actuators.q)):
            q0 = self.actuators.q.copy()  # the same joints reloaded: the arm stays where it stands
        act = JointActuators(robot.lower, robot.upper, robot.speed, robot.accel, self.actuator_tau, q0)
        box = workspace_box(robot)
        guard = HazardGuard.for_robot(robot)
        # everything built: now switch (a failure above leaves the old robot in place)
        self.robot, self.solver, self.actuators, self.box, self.guard = robot, solver, act, box, guard
        self.hazard = self._hazard_at_rest()
        self.robot_name, self.solver_name = robot.name, solver_name
        self.q_ref = act.q.copy()
        self.q_goal = self.q_ref.copy()  # position mode: the solver's answer the reference walks to
        self.target = robot.position(self.q_ref)
        self.scaling = default_scaling(box, self.target)
        self.robot_xml = xml
        self.changed()

    def replay_args(self) -> dict:
        """What builds this scene again for a replay (app/engine/replay.py): its robot and file's text, solver,
        mode."""
        return {"robot": self.robot_name, "robot_xml": self.robot_xml, "solver": self.solver_name, "mode": self.mode}

    def moving(self) -> bool:
        """Whether any joint moves faster than 0.1 % of its speed limit."""
        return bool(np.any(np.abs(self.actuators.qdot) > 1e-3 * self.robot.speed))

    @command
    def set_robot(self, robot: str, xml: str | None = None) -> None:
        """Load a robot; on any error the previous robot stays.

        ``robot`` is a library name or a path inside the allowed robot folders (the
        library, ``$BOSUN_ROBOTS_DIR``, :attr:`robots_dirs`); with ``xml`` the client sent the
        file's text and ``robot`` only names it.  Refused while the arm moves.
        """
        if self.estop_latched:
            raise CommandError("E-STOP is latched; reset before changing the robot")
        if self.moving():
            raise CommandError("the robot is moving; release ENABLE and let it come to rest before changing the robot")
        solver = self.solver_name
        try:
            if xml is not None:
                model = load_robot_text(xml, _label(robot))
            else:
                model, xml = load_robot_file(robot, allowed=self._allowed())
            if not isinstance(model, SerialRobot):
                raise CommandError(
                    f"{model.name} is a {model.kind} mechanism; the teleoperation engine drives serial arms"
                )
            try:
                built = self._make_solver(solver, model)
            except BosunError as err:
                if "no closed-form solution" not in str(err):
                    raise
                solver, built = DEFAULT_SOLVER, None  # the analytic solver does not apply: the default's
            self._load(robot, solver, model, xml, built)
        except OSError as err:  # not str(err): it holds the whole path (the engine's folders), cut at its end
            why = one_line(err.strerror or type(err).__name__, 200)
            raise CommandError(f"{_label(robot)}: cannot read: {why}") from None
        except BosunError as err:
            raise CommandError(error_line(err, 300)) from None
        self.input.disarm("robot changed")
        self.note("info", f"robot {self.robot_name} loaded ({self.robot.n_joints} joints, solver {solver})")

    @command
    def set_solver(self, solver: str) -> None:
        name = solver
        try:
            solver = self._make_solver(name, self.robot)
        except BosunError as err:
            raise CommandError(str(err)) from None
        self.solver, self.solver_name = solver, name
        self.changed()
        self.input.disarm("solver changed")
        self.note("info", f"solver {name}")

    def _make_solver(self, name: str, robot):
        """A solver for ``robot``; the GA family with the operator's task (:meth:`set_ga_task`)."""
        if name.startswith("ga"):
            return make_solver(name, robot, seed=self.seed, task=self.ga_task)
        return make_solver(name, robot, seed=self.seed)

    @command
    def set_ga_task(self, weights: list[float], axis: list[float] | None = None, axis_weight: float | None = None):
        """The GA's task weighting (issue 32, item 4; :class:`app.ik.GaTask`): weights of the normalised position
        error per world axis, and the direction the tool's z should point along with its weight (default 1 with
        an axis).  It shapes the GA's position mapping; a change rebuilds a GA solver and disarms the input (the
        next answer may lie elsewhere, H111)."""
        if axis is None and axis_weight:
            raise CommandError("GA task: a tool-axis weight needs the axis (3 numbers)")
        try:
            task = GaTask(tuple(weights), None if axis is None else tuple(axis),
                          (1.0 if axis_weight is None else axis_weight) if axis is not None else 0.0)  # fmt: skip
        except ValueError as err:
            raise CommandError(str(err)) from None
        if task == self.ga_task:
            return
        self.ga_task = task
        if self.solver_name.startswith("ga"):
            self.solver = self._make_solver(self.solver_name, self.robot)
            self.input.disarm("GA task changed")
        self.changed()
        w = ", ".join(f"{v:g}" for v in task.weights)
        axis_text = (
            ""
            if task.axis is None
            else f"; tool z along ({', '.join(f'{v:.3g}' for v in task.axis)}) × {task.axis_weight:g}"
        )
        self.note("info", f"GA task: weights ({w}){axis_text}")

    @command
    def set_mode(self, mode: str) -> None:
        if mode not in MODES:
            raise CommandError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
        if mode != self.mode:
            self.mode = mode
            # position mode starts from where the tool is: releasing the stick returns here
            self.scaling = self.scaling.with_origin(self.robot.position(self.actuators.q))
            self.q_ref = self.actuators.q.copy()
            self.q_goal = self.q_ref.copy()
            self.command_point = None
            self.input.disarm("mode changed")
            self.note("info", f"mode {mode}")

    @command
    def set_frame(self, frame: str) -> None:
        """The frame the stick commands in (issue 30, item 1): ``world`` (earth-fixed, the papers' mapping),
        ``base`` (the robot's base) or ``tool`` (the tool, as it turns); this scene has no target deck.  Position
        and velocity modes and the scaling act in that frame; a change disarms the input (safety H96)."""
        if frame not in FRAMES:
            raise CommandError(f"frame must be one of {', '.join(FRAMES)}, got {frame!r}")
        if frame == "target":
            raise CommandError(
                "frame target: the teleop scene has no target deck (the crane-head and Motion-Lab scenes have one)"
            )
        if frame != self.frame:
            self.frame = frame
            self.command_point = None
            self.input.disarm("command frame changed")
            self.note("info", f"command frame {frame}")

    def _frame_rotation(self) -> np.ndarray | None:
        """R_w^F of the operator's frame now (None: the world frame, the papers' mapping as it is)."""
        if self.frame == "base":
            return self.robot.T_world_base[:3, :3]
        if self.frame == "tool":
            return self.robot.fk(self.q_ref)[:3, :3]
        return None

    @command
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

    def _allowed(self):
        return allowed_dirs(self.robots_dirs)

    @command
    def study_start(self, study: str, solver: str | None = None, grid: int = 8) -> None:
        """Run an IK study of the loaded robot in a worker process (progress in ``study`` messages)."""
        name = solver or self.solver_name
        if name not in solvers_for(self.robot):
            raise CommandError(
                f"{name} does not apply to {self.robot_name} (solvers: {', '.join(solvers_for(self.robot))})"
            )
        try:
            n = self.studies.start(study, self.robot_xml, self.robot_name, name, grid)
        except StudyError as err:
            raise CommandError(str(err)) from None
        what = f"{grid}³ targets" if study == "distribution" else "a 20 s path"
        self.note("info", f"study {n}: {study} of {self.robot_name} with {name} ({what}) started")

    @command
    def study_cancel(self) -> None:
        if not self.studies.running:
            raise CommandError("no study is running")
        self.studies.cancel()
        self.note("info", "study cancel requested: the targets done so far are kept")

    def close(self) -> None:
        self.studies.close()

    def estop(self, source: str = "operator") -> None:
        """Stop all motion in this tick and latch."""
        self.actuators.stop()
        self.q_ref = self.actuators.q.copy()
        self.q_goal = self.q_ref.copy()
        self._latch(f"E-STOP from {source}")

    def reset(self) -> None:
        """Clear a latched E-STOP; the arm holds where it stands until the operator commands anew."""
        if self.estop_latched:
            self.q_ref = self.actuators.q.copy()
            self.q_goal = self.q_ref.copy()
            self.command_point = None
            if self.mode == "position":
                self.scaling = self.scaling.with_origin(self.robot.position(self.actuators.q))
            self._unlatch("holding; centre the stick and press enable to drive")

    # ------------------------------------------------------------------ input
    def feed(self, sample: InputSample | None, now: float, released: bool = False) -> None:
        """The latest reading of the input device (None: no device connected), at engine receive time."""
        self.input.feed(sample, now, released)

    # ------------------------------------------------------------------ control tick
    def _hold(self, dt: float) -> None:
        """Hold: the reference is where the joints come to rest braking now (issue 26, item 1).

        Nearer (the joints where they are) asks the servo for a stop it cannot make without
        overshooting; farther (the last commanded reference, which leads the joints while they
        accelerate) moves the machine on after the operator stopped commanding."""
        self.q_ref = self.actuators.stopping_point(dt)
        self.q_goal = self.q_ref.copy()
        self.hazard = self._hazard_at_rest()
        self._brake_ref = None

    def _hazard_at_rest(self) -> GuardReport:
        """The hazard nearest its stop among those in their zones where the joints are, with no command: what the
        *hazard* line says while nobody drives (H124: it said "none near" with the Panda's tool 5 mm over the
        floor once the deadman was released, the screen contradicting the machine)."""
        return self.guard.step(self.actuators.q, np.zeros_like(self.actuators.q))[1]

    def _guarded(self, dq: np.ndarray) -> None:
        """Move the reference by the joint step ``dq``, scaled along the directions that bring a hazard nearer, and
        supervised (issue 32, item 5: :func:`app.scenes.teleop_guard.guard_tick`, one compiled call).

        The scaling moves the capsules' stop out by how far the arm can be from its reference (the servo lags it
        and each joint brakes on its own): without that the reference kept its clearance while the lagging,
        acceleration-limited joints cut the corner (the Panda's tool 63 mm into the floor; judged from the
        joints' stopping point instead, 0.2 m).  The safe-braking rule then keeps the reference only if, after this
        tick, the joints can still brake to rest with every capsule clearance at least 2.5 mm (or what braking now
        would leave, if less): else a gentler reference the servo follows in proportion, else the joints brake now.
        By induction the arm can always be stopped clear (at twice the default stick speed the scaling alone let
        the Panda's tool 31 mm into the floor: review of the first runs of ``bosun bench guard``)."""
        q_ref, self.hazard, action = self.guard_tick(self.guard, self.q_ref, dq, self.actuators, self.dt_last)
        if action == 2:  # brake: to the stopping point of the first braking tick, held until the rule lets go
            self.braked += 1
            if self._brake_ref is None:
                self._brake_ref = q_ref
            q_ref = self._brake_ref
        else:
            self._brake_ref = None
        self.q_ref = q_ref

    def _walk_to_goal(self, dt: float) -> None:
        """Position mode: the reference walks to the solver's answer, each joint at its own speed limit, guarded: a
        jump through a hazard is not taken at once.  Each joint's step is clipped on its own (safety H114): scaled
        as a whole to the joint with the farthest to go, a step whose far joint the guard held (an answer behind
        the floor) left the others creeping to their goals ever slower, and the arm never came to rest."""
        reach = self.robot.speed * dt
        self.guard.in_tool_metric(False)  # a joint-space walk: corrected in the joints' metric (H121)
        try:
            self._guarded(np.clip(self.q_goal - self.q_ref, -reach, reach))
        finally:
            self.guard.in_tool_metric(True)

    def take_solver_work(self) -> list[list[int]]:
        """The solver's clock decisions since the last call, one list per solve (:meth:`app.ik.base.Solver.take_work`:
        what a recording keeps so that a replay's GA takes the same generations)."""
        return self.solver.take_work()

    def tick(self, now: float, dt: float, solve_budget: float | Replayed | None = None) -> None:
        """One control step of length dt [s] at engine time ``now`` [s] (``solve_budget``: the solver's time budget
        [s], or a replay's recorded decisions)."""
        self.ticks += 1
        self.sim_time += dt
        self.dt_last = dt
        inp = self.input.step(now)
        if inp.stop:
            self.estop(source=f"the stop button of {self.input.profile.name}")
        if inp.armed and not self._armed_prev and self.mode == "position":
            # position mode starts from where the tool is at every arming: arming at neutral never moves it
            self.scaling = self.scaling.with_origin(self.robot.position(self.q_ref))
            self._frame_at_arming = self._frame_rotation()  # the frame held while armed (a tool frame turns)
        self._armed_prev = inp.armed
        self.stale, self.enabled = inp.stale, inp.enabled and not self.estop_latched
        self.signal = inp.raw_signal[:3].copy()
        if self.estop_latched:
            self.actuators.stop()
            self._hold(dt)
            self.command_point = None
            self._check_alarms(now, None, dt)
            return
        if inp.mode_toggle:
            self.set_mode("position" if self.mode == "velocity" else "velocity")
            self.enabled = False
        if not self.enabled:
            self._hold(dt)
            self.command_point = None
            self.actuators.step(self.q_ref, dt)
            self._check_alarms(now, None, dt)
            return
        s = inp.signal[:3]
        q_ref_before = self.q_ref.copy()
        budget = DEFAULT if solve_budget is None else solve_budget
        xdot = None
        if self.mode == "position":
            if self.frame == "world":
                point = position_target(s, self.scaling.k_p, self.scaling.x_w)  # eq. (1)
            else:  # eq. (1) in the operator's frame, as it was at arming
                point = self.scaling.x_w + in_frame(np.asarray(self.scaling.k_p) * s, self._frame_at_arming)
            res = self._solve_position(point, budget)
            self._walk_to_goal(dt)
            self.command_point = point
            self.target = np.asarray(point, dtype=float)
        else:
            xdot = velocity_command(s, self.scaling.k_v)  # eq. (2), in the operator's frame
            if self.frame != "world":
                xdot = in_frame(xdot, self._frame_rotation())
            x_ref = self.robot.position(self.q_ref)
            if np.any(xdot != 0.0):
                # the operator's command as a point: eq. (7) integrated from where the reference was
                start = x_ref if self.command_point is None else self.command_point
                self.command_point = start + xdot * dt
                res = self.solver.solve_velocity(self.q_ref, xdot, dt, time_budget=budget)  # eqs. (4), (7), (9)
                self.target = x_ref + xdot * dt  # eq. (7): the solver's target this tick
                self._guarded(res.q - self.q_ref)
                self.q_goal = self.q_ref.copy()
            else:
                res = None  # centred stick: brake to the nearest stop and hold there
                if self.command_point is not None:
                    self._hold(dt)
                else:
                    self.hazard = self._hazard_at_rest()
                self.command_point = None
                self.target = self.robot.position(self.q_ref)
        if res is not None:
            self.solver_cost, self.solver_time, self.solver_ok = res.error, res.time_s, res.success
        self.actuators.step(self.q_ref, dt)
        self._check_alarms(now, xdot, dt, q_ref_before)

    def _solve_position(self, point: np.ndarray, budget):
        """Eq. (3) for the stick's point, as a hold where the stick rests (issue 26, item 1).

        A command that has not moved (within 1 µm) is a hold: once answered, the reference stays; while
        unanswered (out of reach, or the budget spent), a new answer is taken only when it brings the tool
        nearer the point by at least a millimetre.  Re-solving a resting stick's point every tick let a
        solver's restarts and a GA's population move the arm with nobody touching the stick."""
        still = self.command_point is not None and float(np.max(np.abs(point - self.command_point))) <= 1e-6
        if not still:
            self._refine_misses = 0
        if still and (self._position_answered or self._refine_misses >= REFINE_TRIES):
            return None  # answered, or nothing nearer found in REFINE_TRIES tries: out of reach, hold
        res = self.solver.solve_position(point, self.q_goal, time_budget=budget)
        if still:
            self._refine_misses += 1
            # a refinement for a resting stick: nearer by a millimetre and a local step only (a GA's or a
            # restart's answer elsewhere in joint space, a little nearer, swung the arm 2.8 rad: review)
            now_error = float(np.linalg.norm(self.robot.position(self.q_goal) - point))
            local = bool(np.all(np.abs(res.q - self.q_goal) <= REFINE_STEP * (self.robot.upper - self.robot.lower)))
            if not (res.error < now_error - 1e-3 and local):
                return res
            self._refine_misses = 0
        self.q_goal = res.q
        self._position_answered = bool(res.success)
        return res

    # ------------------------------------------------------------------ alarms
    def _check_alarms(self, now: float, xdot, dt: float, q_before=None) -> None:
        """Per tick: motion without a command, E-STOP, input, joint limits against the command, an unreached
        position target, singularity (definitions: :mod:`app.engine.alarm_catalog`).

        ``q_before``: the joint reference before this tick's solve; the reference's tool step is
        compared with the commanded one (velocity mode)."""
        al = self.alarms
        al.at(now)
        self._check_unbidden(now, xdot)
        flags = self.input.flags()
        al.set("estop", self.estop_latched, text="E-STOP latched: reset to continue")
        al.set("device_lost", self.input.lost, text="Input device lost: the arm holds")
        al.set(
            "stale_input",
            self.input.connected and flags["stale_input"] and self.input.stale_while_driving,
            text=f"Input stale (nothing for {self.input.stale_timeout * 1e3:.0f} ms): the arm holds",
        )
        lo, hi = self.robot.lower, self.robot.upper
        tol = 1e-6 * np.maximum(1.0, hi - lo)
        blocked = ""
        limited = False
        commanded = xdot is not None and np.any(xdot != 0.0) and q_before is not None
        if commanded:
            v_cmd = float(np.linalg.norm(xdot))
            step = self.robot.position(self.q_ref) - self.robot.position(q_before)
            progress = float(step @ xdot) / (v_cmd * dt * v_cmd) if v_cmd > 0 else 1.0
            at_lo, at_hi = self.q_ref <= lo + tol, self.q_ref >= hi - tol
            hz = self.hazard
            if progress < 0.5 and np.any(at_lo | at_hi):
                k = int(np.flatnonzero(at_lo | at_hi)[0])
                blocked = f"{self.robot.joint_names[k]} at its {'lower' if at_lo[k] else 'upper'} limit"
            elif progress < 0.5 and hz.slowed and hz.kind == "joint limit":  # the guard slows it onto the limit
                joint, side, _ = hz.name.rsplit(" ", 2)
                blocked = f"{joint} near its {side} limit ({hz.distance()} to go)"
            limited = not blocked and progress < 0.9 and not self.hazard.slowed
        al.set("joint_limit", bool(blocked), text=f"{blocked}: the commanded direction is blocked")
        hz = self.hazard
        # a collision's own alarm (a joint limit and a singularity have theirs: joint_limit, near_singularity)
        al.set("hazard_slowed", self.enabled and hz.slowed and hz.kind == "collision", text=f"Slowed near {hz.text()}")
        if limited != self._speed_limited:  # a status, not an alarm: no operator action (rationalisation)
            self._speed_limited = limited
            if limited and now - self._speed_noted >= SPEED_NOTE_INTERVAL:  # a line, not one per flicker
                self._speed_noted = now
                self.note("info", "speed limited: the joints' speed limits slow the tool below the stick's speed")
        reach = self.mode == "position" and self.enabled and self.command_point is not None
        miss = float(np.linalg.norm(self.robot.position(self.q_goal) - self.command_point)) if reach else 0.0
        al.set(
            "target_unreachable",
            reach and not self._position_answered,
            text=f"Target out of reach: the arm stops {miss:.2f} m short of the stick's point",
        )
        if self.ticks % 10 == 0:
            if commanded or (self.mode == "position" and self.enabled):
                ratio = self._sigma_ratio()
                cond = 1.0 / ratio if ratio > 0 else math.inf
                al.set("near_singularity", value=min(cond, 1e12), text=f"Near a singularity (σ ratio {ratio:.3f})")
            else:
                al.set("near_singularity", False)  # an arm at rest near one: nothing to do about it

    def _check_unbidden(self, now: float, xdot) -> None:
        """Motion without a command (issue 26): holding (E-STOP, input not enabled, a centred stick in
        velocity mode), the joints must be at rest within their braking time and a second; else the
        alarm, and the E-STOP latches."""
        holding = self.estop_latched or not self.enabled or (self.mode == "velocity" and not np.any(xdot))
        # simulated time: braking advances by dt a tick whatever the wall clock does (a slow engine, a stall)
        if not holding:
            self._hold_deadline = None
        elif self._hold_deadline is None:
            accel = self.robot.accel
            brake = np.where(np.isfinite(accel) & (accel > 0), np.abs(self.actuators.qdot) / accel, 0.0)
            self._hold_deadline = self.sim_time + float(np.max(brake, initial=0.0)) + 10.0 * self.actuator_tau + 1.0
        late = self._hold_deadline is not None and self.sim_time > self._hold_deadline
        unbidden = holding and late and self.moving()
        self.alarms.set(
            "motion_without_command",
            unbidden,
            text="The arm moves without a command: E-STOP latched",
        )
        if unbidden:
            self.estop(source="the engine (motion without a command)")

    def _sigma_ratio(self) -> float:
        """σ_min/σ_max of J·diag(joint speed limits) for the tool position: how evenly the joints, each at
        its own speed, can move the tool in every direction (1: isotropic, 0: a direction is lost)."""
        J = self.robot.jacobian(self.actuators.q)[:3] * self.robot.speed
        sv = np.linalg.svd(J, compute_uv=False)
        return float(sv[min(2, sv.size - 1)] / sv[0]) if sv[0] > 0 else 0.0

    # ------------------------------------------------------------------ state
    def describe(self) -> TeleopDescription:
        r = self.robot
        return TeleopDescription(
            seq=self.describe_seq,
            title="Teleoperation",
            commands=sorted(kind.TYPE for kind in self.COMMANDS),
            robots=list(library_entries(str(robots_dir()))),
            robot=self.robot_name,
            robot_xml=self.robot_xml,
            solvers=solvers_for(r),
            modes=list(MODES),
            joint_names=list(r.joint_names),
            lower=r.lower.tolist(),
            upper=r.upper.tolist(),
            speed=r.speed.tolist(),
            box=[self.box.lower.tolist(), self.box.upper.tolist()],
            studies=list(STUDIES),
        )

    def snapshot(self) -> TeleopSnapshot:
        q = self.actuators.q
        for msg in self.studies.poll():
            self.events.append(("study", msg))
            if msg["status"] != "running":
                self.note("info" if msg["status"] != "failed" else "warning", _study_line(msg))
        st = self.studies.state
        head = self._head()
        head["flags"].enabled = self.enabled
        hz = self.hazard
        return TeleopSnapshot(
            **head,
            t=self.sim_time,
            tick=self.ticks,
            robot=self.robot_name,
            solver=self.solver_name,
            ga_weights=list(self.ga_task.weights),
            ga_axis=None if self.ga_task.axis is None else list(self.ga_task.axis),
            ga_axis_weight=self.ga_task.axis_weight,
            mode=self.mode,
            frame=self.frame,
            q=q.tolist(),
            qdot=self.actuators.qdot.tolist(),
            q_ref=self.q_ref.tolist(),
            tool=self.robot.position(q).tolist(),
            frames=self.robot.frames(q)[:, :3, 3].tolist(),
            target=np.asarray(self.target, dtype=float).tolist(),
            signal=self.signal.tolist(),
            solver_error=None if not math.isfinite(self.solver_cost) else float(self.solver_cost),
            solver_time=float(self.solver_time),
            solver_ok=bool(self.solver_ok),
            scaling=ScalingState(k_p=list(self.scaling.k_p), x_w=list(self.scaling.x_w), k_v=list(self.scaling.k_v)),
            hazard=HazardState(
                kind=hz.kind,
                name=hz.name,
                value=_finite(hz.value),
                share=_finite(hz.share),
                slowed=hz.slowed,
                text=hz.text(),
            ),
            command=None if self.command_point is None else np.asarray(self.command_point, float).tolist(),
            study=StudyState(**{k: st[k] for k in ("id", "kind", "status", "done", "total", "error")}),
        )


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _study_line(msg: dict) -> str:
    if msg["status"] == "failed":
        return f"study {msg['id']} failed: {msg['error']}"
    return f"study {msg['id']} ({msg['kind']}) {msg['status']}: {msg['done']} of {msg['total']} targets"
