"""Engine session for the Motion-Lab (``bosun server --plant lab``): the lab HMI's commands.

Each tick advances :class:`~app.scenes.lab.MotionLab` in steps of 0.01 s.  Commands (protocol
messages, see docs/protocol.md): ``lab_platform`` (neutral / settle / engage / disengage),
``lab_source`` (simulation, generator, remote, timeseries with their parameters), ``lab_remote_pose``,
``lab_comau_mode``, ``lab_winch`` (mode and / or spring-return speed), ``lab_vvmc`` (on/off),
``set_lab_delay`` (the simulated lab's measurement-to-actuation delay and its prediction, issue 31), plus
``estop`` / ``reset``.  Input (a joystick or the GUI's stick, through the one
:class:`~app.teleop.pipeline.InputPipeline`: profile, deadzone, deadman, arming, stale halt) drives the
Comau tool point in REMOTE (s_x, s_y, s_z; 0.25 m/s at full stick, in the robot base frame) and the
winch in REMOTE (s_w, up to its speed limit).  After an E-STOP reset every machine holds where it
stands until the operator commands it anew.

The machines are driven through a plant backend (:mod:`app.plant`): ``simulated`` steps the
:class:`~app.scenes.lab.MotionLab`, ``plc`` (``--plc AMS_NET_ID``) drives the real lab through its
TwinCAT PLC and keeps the same model set to what the PLC reports; the scene does not know which.
``lab_plc_ack`` acknowledges a PLC error as the lab's HMI does.

The lab HMI's parity (issue 16, item 5): ``lab_comau_jog`` jogs one Comau joint in REMOTE (the operator's
input armed, refreshed within :data:`JOG_TIMEOUT`, else it returns to zero), each platform's Rexroth status
word, the "Machine and Sensor States" lights and the sine generator's defaults and ranges, for both
backends alike.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from app.control.lab import ComauGuard
from app.engine.alarms import AlarmList
from app.engine.jobs import Deferred
from app.engine.scene import CommandError, Scene, command
from app.engine.vessel_upload import TableText, VesselChoice
from app.errors import BosunError
from app.marine.vessel import RAOTable
from app.marine.vessels import VESSELS
from app.marine.waves import SPECTRA
from app.marine.waves import spectrum as sea_spectrum
from app.models.lab import load_lab, resolve_lab
from app.models.registry import resolve
from app.models.stewart import StewartPlatform
from app.models.xml import read_robot_file
from app.net.snapshots import (
    ComauJog,
    ComauState,
    CraneLoadState,
    HazardState,
    LabDescription,
    LabScenePoints,
    LabSnapshot,
    PendulumState,
    PlatformInfo,
    PlatformState,
    SineGenerator,
    SwingState,
    WinchInfo,
    WinchState,
)
from app.plant.base import GENERATOR_DEFAULT, LabBackend
from app.plant.simulated import SimulatedLab
from app.plc.symbols import GENERATOR_FREQUENCY_HZ, GENERATOR_PHASE_DEG
from app.scenarios.swing import SwingControl
from app.scenarios.vvmc import LateView
from app.scenes.crane_load import SNAP_FACTOR, LandingWatch
from app.scenes.lab import REMOTE_TOOL_SPEED, WORK_SHIFT_MAX, MotionLab
from app.scenes.lab_load import LabLoad
from app.teleop.pipeline import InputPipeline

STEP = 0.01
LOCAL_SPEED_TIMEOUT = 0.3  # s: a LOCAL winch speed not refreshed this long returns to zero
JOG_TIMEOUT = 0.3  # s: a Comau jog speed not refreshed this long returns to zero (issue 16, item 5)


SOURCES = ("simulation", "generator", "remote", "timeseries")


@dataclass
class LabSession(Scene):
    """The Motion-Lab scene.  ``comau_profile`` names the Comau's joint-limit profile (``lab``: the
    lab program's limits and velocity-boundary law, ``datasheet``: Table 6); ``None`` takes the
    layout's default (``<crane limits=…>``, ``lab`` for motionlab.xml).  Chosen at start: a profile
    never changes under a moving arm.  ``plc``: an :class:`app.plc.bridge.PlcTarget` to drive the real
    lab's PLC (``plc_options``: the bridge's timeouts); ``None`` simulates."""

    lab_name: str = "motionlab"
    comau_profile: str | None = None
    plc: Any = None
    plc_options: dict[str, Any] = field(default_factory=dict)

    KIND: ClassVar[str] = "lab"
    TITLE: ClassVar[str] = "the Motion-Lab"

    def __post_init__(self) -> None:
        self._init_scene()
        self.robot_name, self.solver_name, self.mode = "motionlab", "analytic", "lab"
        self.layout = load_lab(self.lab_name)
        self.lab = MotionLab(self.layout, at_work=True, comau_profile=self.comau_profile)
        self.plant: LabBackend
        if self.plc is None:
            self.plant = SimulatedLab(self.lab)
        else:
            from app.plant.plc import PlcLab

            self.plant = PlcLab(self.lab, self.plc, **self.plc_options)
        self.names = [n for n, _ in self.layout.platforms]
        self._carry = 0.0
        self.input = InputPipeline(note=self.note, axes=4)
        self.alarms = AlarmList("Motion-Lab", note=self.note)
        self._local_speed_time = -np.inf
        self.sources: list[dict[str, Any]] = [{"source": "generator"} for _ in self.names]
        self.spectra: list[tuple[str, float, float] | None] = [None for _ in self.names]  # the last simulated sea
        self.vvmc = False
        self.delay, self.predict = 0.0, False  # the simulated measurement-to-actuation delay (set_lab_delay)
        self.vessel = VesselChoice()  # the wave simulator's vessel (set_vessel, issue 17)
        self._jog: tuple[int, float, float] | None = None  # Comau jog: joint (1-3), speed fraction, time received
        self._jog_reason = ""
        # the load-swing estimator and anti-swing law (issue 16, item 4): on the simulated lab, stepped with it
        self.swing: SwingControl | None = None
        self._swing_reason = ""
        # the load on its elastic wire, landing on EM1500's deck (issue 30, item 5): on the simulated lab, whose
        # pendulum then reports that load's wire (app/scenes/lab_load.py); the real lab's load is the lab's own
        self.load: LabLoad | None = None
        self.watch = LandingWatch(relift=True)
        self._landing_events = [False] * 4  # slack, snap, re-hit, sideways since the last alarm check
        if self.plc is None:
            self.load = LabLoad(self.lab)
            self.swing = SwingControl(self.lab, np.random.default_rng(16_4), active=False)
            self.plant.after_step = self._after_step
        if self.plc is None:
            self.note("info", f"Motion-Lab: {', '.join(self.names)} SETTLED, Comau REMOTE, winch LOCAL")
        else:
            self.note("info", f"Motion-Lab on its PLC at {self.plc}: connecting; the machines as the PLC reports them")

    def replay_args(self) -> dict:
        """What builds this scene again for a replay (app/engine/replay.py): whether it drove the real lab, and the
        Comau's joint-limit profile."""
        return {"plc": self.plc is not None, "comau_profile": self.lab.profile.name}

    def _platform(self, name: str) -> int:
        if name not in self.names:
            raise CommandError(f"unknown platform {name!r} (this lab has {', '.join(self.names)})")
        return self.names.index(name)

    def _guard(self) -> None:
        if self.estop_latched:
            raise CommandError("E-STOP is latched; reset first")

    # ------------------------------------------------------------------ commands
    def _plant(self, fn, *args) -> Any:
        """A command to the plant backend; its refusal becomes the command's (nothing changed)."""
        try:
            return fn(*args)
        except BosunError as err:
            raise CommandError(str(err)) from None

    @command
    def lab_platform(self, platform: str, action: str) -> None:
        self._guard()
        k = self._platform(platform)
        self._plant(self.plant.platform, k, action)
        self.note("info", f"{platform}: {action.upper()}")

    @command
    def lab_source(self, platform: str, source: str, **p: Any) -> None:
        k = self._platform(platform)
        info = self._plant(self.plant.source, k, source, p)
        self.sources[k] = {"source": source, **info}
        if source == "simulation":
            self.spectra[k] = (p.get("spectrum", "jonswap"), float(info["hs"]), float(info["tp"]))
        self.changed()
        self.note("info", f"{platform}: motion source {source.upper()}")

    @command
    def set_vessel(
        self, vessel: str | None = None, csv: str | None = None, part: int = 0, parts: int = 1, label: str = ""
    ) -> Deferred | None:
        """The wave simulator's vessel (issue 17, item 2): by name or an RAO table sent in parts; it makes the
        platforms' seas from the next SIMULATION source on (a platform's source changes only out of ENGAGED).
        Under a server a whole table is parsed off the control loop and taken at a tick boundary (issue 27,
        item 2; :class:`~app.engine.jobs.Deferred`, the reply follows); a later vessel supersedes it."""
        if self.plc is not None:
            self._plant(self.plant.set_vessel_rao, None)  # refused with the reason
        got = self.vessel.take(vessel, csv, part, parts, label)
        if got is False:
            return None
        if isinstance(got, TableText):
            if self.jobs.background:
                return self.jobs.start(f"set_vessel {got.where}", got.parse, lambda table: self._use_table(got, table))
            self._use_table(got, got.parse())
            return None
        self.jobs.supersede(f"set_vessel {self.vessel.label}")  # a pending table would undo this choice
        self._vessel_taken()
        return None

    def _use_table(self, text: TableText, table: RAOTable) -> None:
        """A parsed table is the wave simulator's vessel (at a tick boundary when parsed off the loop)."""
        self.vessel.use(table, text)
        self._vessel_taken()

    def _vessel_taken(self) -> None:
        self._plant(self.plant.set_vessel_rao, self.vessel.rao())
        self.changed()
        self.note("info", f"wave simulator vessel: {self.vessel.label} (from the next SIMULATION source on)")

    @command
    def set_lab_delay(self, delay: float, predict: bool = False) -> None:
        """The measurement-to-actuation delay (issue 31, item 2): the Comau's and the winch's laws see both platforms'
        motion ``delay`` s late, or with ``predict`` the motion predicted that far ahead from those late samples
        (:class:`app.scenarios.vvmc.LateView`: an AR model that fits first 150 s after the delay is set, having no
        past before, and is blended in over PREDICT_BLEND).  Simulated lab only (the real lab's delay is its own);
        set while VVMC is off (the laws' input would jump under the machine; VVMC then engages from where the tool
        is, H106)."""
        delay = float(delay)
        if not (math.isfinite(delay) and 0.0 <= delay <= 2.0):
            raise CommandError(f"delay must be in [0, 2] s, got {delay}")
        if self.plc is not None:
            raise CommandError("a delay is simulated on the simulated lab only: the real lab's is its own")
        if self.vvmc:
            raise CommandError("the delay is set while VVMC is off: turn VVMC off first, then on again")
        views = None
        if delay > 0.0 or predict:
            views = tuple(LateView(None, delay, STEP, bool(predict)) for _ in self.names)
        self.lab.set_sensors(views)
        self.delay, self.predict = delay, bool(predict) and views is not None
        more = ", the motion predicted that far ahead (fitted 150 s from now)" if self.predict else ""
        self.note("info", f"delay {delay:g} s{more}")

    @command
    def lab_remote_pose(self, platform: str, eta: list[float]) -> None:
        k = self._platform(platform)
        self._plant(self.plant.remote_pose, k, eta)

    @command
    def lab_comau_mode(self, mode: str) -> None:
        self._guard()
        if mode == "remote":
            self.input.disarm("Comau REMOTE selected")
        self._plant(self.plant.comau_mode, mode)
        if mode != "motion_comp":
            self._swing_off(f"Comau {mode.upper()}")
        self.note("info", f"Comau: {mode.upper()}")

    @command
    def lab_winch(self, mode: str | None = None, speed: float | None = None) -> None:
        self._guard()
        if mode is not None:
            if mode == "remote":
                self.input.disarm("winch REMOTE selected")
            self._plant(self.plant.winch_mode, mode)
            self.note("info", f"winch: {mode.upper()}")
        if speed is not None:
            if self.lab.winch.mode != "local":
                raise CommandError("the speed slider drives the winch in LOCAL mode only")
            lim = self.plant.winch_speed_max
            self._plant(self.plant.winch_speed, float(np.clip(speed, -lim, lim)))
            self._local_speed_time = time.monotonic()  # the GUI resends while the slider is held

    @command
    def set_frame(self, frame: str) -> None:
        """The frame the stick commands in (issue 30, item 1).  REMOTE: the Comau's ``base``.  Under VVMC: ``target``
        (EM1500's deck: VVMC holds the tool on the work point on it, the paper's) or ``world`` (the lab's world: the
        tool held still there, only EM8000's motion compensated; the winch holds the load's height there).  Another
        is refused with the reason; a change disarms the input (H96) and keeps the work point where it is."""
        if self.plc is not None and frame == "world":
            raise CommandError("frame world: the real lab's VVMC is its PLC's program, which holds EM1500's frame")
        allowed = ("target", "world") if self.vvmc else ("base",)
        if frame not in allowed:
            now = "VVMC on: target or world" if self.vvmc else "REMOTE: base (turn VVMC on for target or world)"
            raise CommandError(f"frame {frame}: the lab's stick commands in the frame of its mode, now {now}")
        if frame == self._frame():
            return
        self.input.disarm("command frame changed")
        self.lab.set_work_frame("world" if frame == "world" else "deck")
        self.note("info", f"frame: {frame}")

    def _frame(self) -> str:
        if not self.vvmc:
            return "base"
        return "world" if self.lab.work_frame == "world" else "target"

    @command
    def lab_vvmc(self, on: bool) -> None:
        self._guard()
        self.input.disarm("VVMC switched")  # off puts the Comau in REMOTE: a held stick must not drive it
        self.lab.set_work_frame("deck")  # a VVMC starts in the target frame, EM1500's (the paper's)
        self._plant(self.plant.vvmc, on)
        self.vvmc = on
        if not on:
            self._swing_off("VVMC off")  # at once, not at the next step (an off and on in one tick)
        self.note("info", f"VVMC {'ON: Comau and winch MOTION_COMP' if on else 'OFF: Comau REMOTE, winch LOCAL'}")

    @command
    def lab_plc_ack(self, platform: str | None = None) -> None:
        """Acknowledge the PLC's error as the lab HMI does (``MAIN.bReset``; a platform in WARNING or ERROR:
        its ``bReset``, then ``eModeCmd`` := SETTLED).  Refused while the E-STOP is latched: its reset
        resets the PLC, an acknowledgement must not undo a STOP."""
        self._guard()
        k = None if platform is None else self._platform(platform)
        self.note("info", self._plant(self.plant.acknowledge, k))

    # ------------------------------------------------------------------ Comau joint jog (issue 16, item 5)
    @command
    def lab_comau_jog(self, joint: int, speed: float) -> None:
        """Jog joint ``joint`` (1–3) at ``speed`` (−1…1) × the profile's joint speed, resent while the operator
        holds it; 0 stops any jog and is always taken.  Refused while the E-STOP is latched, unless the Comau is
        in REMOTE (never in MOTION_COMP / VVMC, SETTLED or HOLD), while the operator's input is not armed and
        fresh (enable held: the stick's rules), and where the plant takes no joint speeds (the lab's PLC).
        The joint filter keeps the profile's limits and velocity-boundary law.  A jog not refreshed within
        :data:`JOG_TIMEOUT`, or whose input stops being enabled, returns to zero (:meth:`_apply_input`)."""
        if joint not in (1, 2, 3):
            raise CommandError(f"Comau jog: joint must be 1, 2 or 3 (q1-q3), got {joint}")
        speed = float(np.clip(speed, -1.0, 1.0))
        if speed == 0.0:
            self._stop_jog("")
            return
        self._guard()
        lab = self.lab
        if self.vvmc or lab.comau_mode != "remote":
            vvmc = " with VVMC on" if self.vvmc else ""
            raise CommandError(f"Comau jog needs REMOTE (the Comau is {lab.comau_mode.upper()}{vvmc})")
        if not (self.input.armed and self.input.last.enabled):
            why = self.input.last.reason or "not armed"
            raise CommandError(f"Comau jog refused: the input is not armed ({why}); centre the stick, hold enable")
        qd = np.zeros(3)
        qd[joint - 1] = speed * float(lab.joints.speed[joint - 1])
        self._plant(self.plant.comau_jog, qd)
        if self._jog is None or self._jog[0] != joint or (self._jog[1] > 0) != (speed > 0):
            self.note("info", f"Comau jog q{joint} {100 * speed:+.0f} %")
        self._jog = (joint, speed, time.monotonic())
        self._jog_reason = ""

    def _stop_jog(self, reason: str) -> None:
        """End the jog (the plant's joint speeds to zero); ``reason`` why, "" when the operator let go."""
        if self._jog is not None:
            self.plant.comau_jog(np.zeros(3))  # a stop is never refused
            if reason:
                self.note("warning", f"Comau jog q{self._jog[0]} stopped: {reason}")
            self._jog = None
        self._jog_reason = reason

    # ------------------------------------------------------------------ load swing (issue 16, item 4)
    @command
    def lab_antisway(self, action: str) -> None:
        """The lab HMI's "Pendel Estimator" buttons: ``activate`` adds the anti-swing law's offset to the work
        point the Comau tracks (VVMC on, no E-STOP), ``deactivate`` brings the offset back to zero along the
        law (always taken), ``reset`` puts the estimator back to "no swing" (only with the law off and its
        offset back at zero: a reset must not make the tool jump)."""
        sw = self.swing
        if sw is None:
            name = self.plant.NAME
            raise CommandError(f"anti-swing: the {name} plant has none here (the lab runs its estimator in the PLC)")
        if action == "deactivate":
            if sw.active:
                self.note("info", "anti-swing OFF: the tool returns to the work point")
            sw.active, self._swing_reason = False, "deactivated"
            return
        self._guard()
        if action == "activate":
            if not self.vvmc or self.lab.comau_mode != "motion_comp":
                raise CommandError("anti-swing acts on the compensated work point: turn VVMC on first")
            if not sw.active:
                self.note("info", "anti-swing ON: the law's offset is added to the Comau's work point")
            sw.active, self._swing_reason = True, ""
        elif action == "reset":
            if sw.active or float(np.max(np.abs(sw.law.p))) > 1e-3 or float(np.max(np.abs(sw.law.v))) > 1e-3:
                raise CommandError("anti-swing reset: deactivate first and let the tool return to the work point")
            sw.reset()
            self.note("info", "swing estimator reset (no swing, initial covariance)")
        else:
            raise CommandError(f"anti-swing: action must be activate, deactivate or reset, got {action!r}")

    def _swing_off(self, reason: str) -> None:
        """The law off (its offset returns to zero along the law) when what it needs is gone."""
        if self.swing is not None and self.swing.active:
            self.swing.active = False
            self._swing_reason = reason
            self.note("warning", f"anti-swing OFF: {reason}")

    def _after_step(self, dt: float) -> None:
        """After each plant step: the load on its wire and the landing, then the swing estimator and law."""
        ld, watch = self.load, self.watch
        if ld is not None:
            ld.step(dt)
            watch.step(ld, ld.deck_v, ld.n_up)
            ev = self._landing_events
            for i, now in enumerate((watch.slack, watch.snap, watch.rehit, watch.sideways)):
                ev[i] = ev[i] or now
        self._swing_step(dt)

    def _swing_step(self, dt: float) -> None:
        """The estimator sees the step, the law sets the next step's offset; it rests (its offset returning to zero)
        while the load is on the deck or the wire slack, where the wire's angle is no swing."""
        sw = self.swing
        if sw is None:
            return
        if sw.active and (self.estop_latched or not self.vvmc or self.lab.comau_mode != "motion_comp"):
            self._swing_off("E-STOP" if self.estop_latched else "VVMC off")
        sw.step(dt, in_play=not (self.watch.touched or self.watch.slack))

    def _swing_state(self) -> SwingState | None:
        sw = self.swing
        if sw is None:
            return None
        ekf, truth = sw.ekf, sw.truth()
        return SwingState(
            active=sw.active,
            measurement=sw.measurement,
            estimate=ekf.x.tolist(),
            sigma=ekf.sigma().tolist(),
            error=(ekf.x - truth).tolist(),
            nees=float(ekf.nees(truth)),
            nis=float(getattr(ekf, "nis", 0.0)),
            offset=sw.law.p.tolist(),
            saturated=bool(sw.law.saturated),
            damping=float(ekf.c),
            design_length=float(sw.design.L),
            design_damping=float(sw.design.c),
            design_step=float(sw.design.Ts),
            reason=self._swing_reason,
        )

    def estop(self, source: str = "operator") -> None:
        if self._latch(f"E-STOP from {source}: platforms, robot and winch braking to rest"):
            why = self.plant.stop_path()
            if why and self.plant.ready():
                self.note("error", f"E-STOP latched here, not yet on the plant ({why}): written as soon as it is back")
            elif why:  # the link is up, but STOP cannot reach the PLC (issue 27, item 1)
                self.note("error", f"E-STOP latched here only: {why}; use the lab's hardware emergency stop")
        self.vvmc = False
        self.plant.estop()
        self._jog = None  # the plant dropped it with the stop
        self._swing_off("E-STOP")

    def reset(self) -> None:
        if self.estop_latched:
            why = self.plant.ready()
            if why:
                raise CommandError(f"reset refused: {why}; the E-STOP stays latched")
            self._plant(self.plant.reset)
            held = ", ".join(f"{n} {p.status.upper()}" for n, p in zip(self.names, self.lab.platforms, strict=True))
            self._unlatch(f"every machine holds where it stands ({held}, Comau HOLD, winch LOCAL)")

    # ------------------------------------------------------------------ loop
    def _apply_input(self, now: float) -> None:
        block = self.plant.motion_block()
        if block:  # nothing may start motion: the input stays disarmed until the cause is gone (issue 27)
            self.input.disarm(f"motion refused: {block}")
        inp = self.input.step(now)
        if inp.stop:
            self.estop(source=f"the stop button of {self.input.profile.name}")
        s = inp.signal if inp.enabled and not self.estop_latched else np.zeros(4)
        if self._jog is not None:  # the jog's stale halt: the stick's rules (issue 16, item 5)
            if not inp.enabled:
                self._stop_jog(f"input not enabled ({inp.reason})")
            elif self.lab.comau_mode != "remote":
                self._stop_jog(f"the Comau left REMOTE ({self.lab.comau_mode.upper()})")
            elif time.monotonic() - self._jog[2] > JOG_TIMEOUT:
                self._stop_jog(f"not refreshed for {JOG_TIMEOUT:g} s")
        tool = np.zeros(3) if self._jog is not None else REMOTE_TOOL_SPEED * s[:3]  # a jog moves one joint only
        self.plant.drive(tool, self.plant.winch_speed_max * s[3])  # REMOTE modes only
        if self.lab.winch.mode == "local" and time.monotonic() - self._local_speed_time > LOCAL_SPEED_TIMEOUT:
            self.plant.winch_speed(0.0)  # the spring-return slider is not being held (or the GUI is gone)

    def _check_alarms(self, now: float) -> None:
        al, lab = self.alarms, self.lab
        al.at(now)
        al.set("estop", self.estop_latched, text="E-STOP latched: reset to continue")
        fl = self.input.flags()
        # the stick drives in REMOTE and, under VVMC, the work point and the load relative to EM1500 (issue 30)
        remote = lab.comau_mode in ("remote", "motion_comp") or lab.winch.mode in ("remote", "motion_comp")
        al.set("device_lost", remote and self.input.lost, text="Input device lost: Comau and winch hold")
        stale = remote and fl["device"] and fl["stale_input"] and self.input.stale_while_driving
        al.set("stale_input", stale, text="Input stale: Comau and winch hold")
        w = self.layout.winch
        wire = lab.winch.length
        top = wire <= w["min_length"] + 1e-3
        bottom = wire >= w["max_length"] - 1e-3
        push = float(getattr(lab.winch, "speed_command", 0.0))
        driven = lab.winch.mode == "motion_comp" or (top and push < 0.0) or (bottom and push > 0.0)
        al.set(
            "winch_end_stop",
            (top or bottom) and driven,  # at rest at a stop nobody drives into, it is only where the wire is
            text=f"Winch driven into its {'upper' if top else 'lower'} end stop (wire {wire:.2f} m)",
        )
        for k, name in enumerate(self.names):
            al.set(
                f"leg_limit:{name}",
                lab.platforms[k].leg_clamped,
                text=f"{name}: target beyond an actuator stroke, scaled back (leg limit)",
            )
        pushed = bool(np.any(np.asarray(lab.tool_velocity_cmd) != 0.0))
        limited = lab.comau_mode == "motion_comp" and pushed and bool(getattr(lab, "work_shift_limited", False))
        al.set("work_point_limit", limited, text="Work point at the Comau's reach: it stops there")
        al.set("payload_below_deck", self._payload_below_deck(), text="Load below the EM1500 deck")
        hz = self._hazard()
        al.set("hazard_slowed", hz.slowed and hz.kind == "collision", text=f"Slowed near {hz.text}")
        slack, snap, rehit, sideways = self._landing_events  # the landing on EM1500 (issue 30, item 5)
        self._landing_events = [False] * 4
        al.set("slack_wire", slack, text="Slack wire: the load is not on the deck and the wire does not carry it")
        al.set("snap_load", snap, text=f"Snap load: the wire pulled over {SNAP_FACTOR:g}× the load's weight")
        contacts = self.watch.contacts - 1
        al.set("rehit", rehit, text=f"Re-hit: the load struck EM1500's deck again ({contacts} since touchdown)")
        al.set("sideways_contact", sideways, text="The load touched EM1500's deck while sliding sideways")
        amp = self._swing_amplitude()
        al.set(
            "load_model_lost",
            self.lab.load_model_lost,
            text="The load's swing left its model (level with the tool point): Comau and winch stopped",
        )
        al.set("load_swing", value=math.degrees(amp), text=f"Load swinging {math.degrees(amp):.1f}° from the vertical")
        self._check_link()

    def _swing_amplitude(self) -> float:
        """The load's swing amplitude [rad]: the angle from the vertical at which its swing energy (relative
        to the tool, eqs. 26–27) would be all potential, acos(1 − E/(g L)).  Unlike the angle itself it
        does not pass through zero twice a period, so an alarm on it does not chatter."""
        pend = getattr(self.lab, "pendulum", None)
        if pend is None:
            return 0.0
        L = max(self.lab.winch.length, 1e-3)
        e = pend.energy(L) / (pend.g * L)
        return math.acos(max(-1.0, min(1.0, 1.0 - e)))

    def _check_link(self) -> None:
        """Alarms of the plant's link (the plc backend): lost or stale link, the PLC's error, unusable symbols."""
        link = self.plant.link(time.monotonic())
        al = self.alarms
        down = link.link in ("connecting", "lost")
        stop = "; STOP latched here, written on reconnect" if self.estop_latched else ""
        al.set("plc_link", down, text=f"PLC link {link.link.upper()}: {link.last_error or 'no answer yet'}{stop}")
        al.set("plc_stale", link.link == "stale", text=f"PLC data {link.data_age:.1f} s old: holding the last")
        ack = "; motion refused" if link.motion_refused.startswith("STOP") else " (acknowledge: lab_plc_ack)"
        al.set("plc_error", bool(link.plc_error), text=f"PLC error: {link.plc_error}{ack}")
        al.set("plc_symbols", bool(link.problems), text=f"{len(link.problems)} PLC symbol(s) not usable")
        more = f" (+{len(link.invalid) - 1} more)" if len(link.invalid) > 1 else ""
        al.set(
            "plc_invalid",
            bool(link.invalid),
            text=f"PLC data invalid: {link.invalid[0] if link.invalid else ''}{more}; motion refused",
        )

    #: how far below EM1500's top plate the load may be before it is "below the deck": the simulated load resting
    #: on the deck sinks about a millimetre into it (app/scenes/lab_load.py), which is a landing, not a strike
    BELOW_DECK = 0.01

    def _payload_below_deck(self) -> bool:
        """The load inside EM1500's footprint and below its top plate (z-down body frame: z > 0) by more than a
        landed load sinks into it (:attr:`BELOW_DECK`; the real lab's pendulum-borne load: by anything)."""
        lab = self.lab
        H = lab.platform_pose(1)
        p = lab.p_p_g() if self.load is None else self.load.position_g()
        p_b2 = H[:3, :3].T @ (p - H[:3, 3])
        radius = float(np.max(np.linalg.norm(lab.models[1].b_b[:, :2], axis=1)))
        depth = 0.0 if self.load is None else self.BELOW_DECK
        return bool(np.hypot(p_b2[0], p_b2[1]) <= radius and p_b2[2] > depth)

    def _load_state(self) -> CraneLoadState | None:
        """The load and its landing on EM1500's deck (None on the PLC backend: the real load has no such model)."""
        ld = self.load
        if ld is None:
            return None
        e, ell = ld.wire()
        return CraneLoadState(
            hook=np.round(ld.position_g(), 4).tolist(),
            wire_length=round(ld.length, 4),
            wire_speed=round(float(self.lab.winch.speed), 4),
            swing_deg=round(math.degrees(math.acos(max(-1.0, min(1.0, float(e[2]) / ell)))), 3),
            tension_factor=round(ld.tension / ld.static_tension(), 4),
            ahc=self.lab.winch.mode == "motion_comp",
            clearance=round(ld.gap, 4) if math.isfinite(ld.gap) else None,
            **self.watch.report(),
            antisway=bool(self.swing is not None and self.swing.active),
        )

    def tick(self, now: float, dt: float, solve_budget: float | None = None) -> None:
        for kind, text in self.plant.poll(now):  # the real plant's data and link events, also while paused
            if kind in ("link_lost", "link_up"):
                self.input.disarm("PLC link lost" if kind == "link_lost" else "PLC link back")
                self.note("error" if kind == "link_lost" else "info", text)
            else:
                self.note(kind, text)
        if self.paused:  # time stands still; the stop button still latches
            if self.input.step(now).stop:
                self.estop(source=f"the stop button of {self.input.profile.name}")
            return
        self._carry += dt
        n = int(self._carry / STEP + 1e-9)
        if n <= 0:
            return
        self._carry -= n * STEP
        self._apply_input(now)
        self.plant.step(STEP, min(n, 50))  # never more than 0.5 s of catch-up in one tick
        if self.lab.load_model_lost and not self.estop_latched:  # the lab stopped itself (H118): latched here too
            self.estop(source="the load's model: its swing passed level with the tool point")
        self._check_alarms(now)

    def close(self) -> None:
        """The plant backend's thread and connection (the PLC's)."""
        self.plant.close()

    # ------------------------------------------------------------------ state
    def _scene(self) -> LabScenePoints:
        """Points in the world {g} for drawing: leg ends of both platforms, robot joints, tool, load."""
        lab = self.lab
        plats: dict[str, dict[str, list[list[float]]]] = {}
        for k, name in enumerate(self.names):
            model = lab.models[k]
            T_n = self.layout.T_world_n1 if k == 0 else self.layout.T_world_n2
            H = T_n @ StewartPlatform.pose_matrix(lab.platforms[k].eta)
            base = model.a_n @ T_n[:3, :3].T + T_n[:3, 3]
            top = model.b_b @ H[:3, :3].T + H[:3, 3]
            plats[name] = {"base": np.round(base, 4).tolist(), "top": np.round(top, 4).tolist()}
        H1 = lab.platform_pose(0) @ self.layout.T_b1_r
        F = H1 @ lab.robot.frames(lab.joints.x)  # {g}; frame 0 is the robot base {r}
        pts = F[:, :3, 3]
        pts = pts[np.r_[True, np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9]]  # a repeat drew a stray bar
        return LabScenePoints(
            platforms=plats,
            robot=np.round(pts, 4).tolist(),
            tool=np.round(lab.p_t_g, 4).tolist(),
            payload=np.round(lab.p_p_g(), 4).tolist(),
            work_point=np.round(lab.last.p_w_g, 4).tolist(),
            robot_frames=np.round(F, 6).tolist(),
        )

    def describe(self) -> LabDescription:
        lab, w = self.lab, self.layout.winch
        plats = []
        for k, (name, robot_file) in enumerate(self.layout.platforms):
            m = lab.models[k]
            spec = None
            if self.spectra[k] is not None:
                kind, hs, tp = self.spectra[k]
                omega = np.linspace(0.1, 3.0, 300)
                spec = {"omega": omega.tolist(), "s": sea_spectrum(kind, omega, hs, tp).tolist()}
            plats.append(
                PlatformInfo(
                    name=name,
                    robot_xml=read_robot_file(resolve(robot_file)),
                    leg_range=[m.leg_min, m.leg_max],
                    pose_min=m.pose_min.tolist(),
                    pose_max=m.pose_max.tolist(),
                    spectrum=spec,
                    command_min=lab.platforms[k].command_min.tolist(),
                    command_max=lab.platforms[k].command_max.tolist(),
                    settled=lab.platforms[k].settled_pose.tolist(),
                    generator=SineGenerator(  # the lab HMI's (motionlab_plc.json), issue 16, item 5
                        amplitude=list(GENERATOR_DEFAULT[0]),
                        frequency=list(GENERATOR_DEFAULT[1]),
                        phase=list(GENERATOR_DEFAULT[2]),
                        frequency_range=list(GENERATOR_FREQUENCY_HZ),
                        phase_range=[float(np.radians(v)) for v in GENERATOR_PHASE_DEG],
                    ),
                )
            )
        return LabDescription(
            seq=self.describe_seq,
            title="Motion-Lab",
            commands=sorted(kind.TYPE for kind in self.COMMANDS),
            lab_xml=resolve_lab(self.lab_name).read_text(encoding="utf-8"),
            platforms=plats,
            comau_xml=read_robot_file(resolve(self.layout.crane_robot)),
            comau_lower=lab.joints.lower.tolist(),  # the profile in force
            comau_upper=lab.joints.upper.tolist(),
            comau_speed=lab.joints.speed.tolist(),
            comau_profile=lab.profile.name,
            comau_profiles=list(self.layout.crane_profiles or [lab.profile.name]),
            comau_accel=float(lab.joints.accel[0]),
            comau_boundary_accel=float(lab.joints.brake[0]),
            winch=WinchInfo(min=w["min_length"], max=w["max_length"], speed_max=self.plant.winch_speed_max),
            sources=list(SOURCES),
            spectra=list(SPECTRA),
            backend=self.plant.NAME,
            comau_jog_timeout=JOG_TIMEOUT,
            vessel=self.vessel.label if self.plc is None else "",
            vessels=list(VESSELS) if self.plc is None else [],
        )

    def snapshot(self) -> LabSnapshot:
        lab = self.lab
        s = lab.last
        plats = []
        for k, name in enumerate(self.names):
            p, m = lab.platforms[k], lab.models[k]
            plats.append(
                PlatformState(
                    name=name,
                    status=p.status,
                    mode=p.mode,
                    source=p.source_name,
                    source_info=self.sources[k],
                    eta=np.round(p.eta, 6).tolist(),
                    eta_dot=np.round(p.eta_dot, 6).tolist(),
                    legs=np.round(m.leg_lengths(p.eta), 5).tolist(),
                    leg_clamped=bool(p.leg_clamped),
                    ramp=float(p.gain),
                    motion=self.plant.motion_status(k),
                )
            )
        return LabSnapshot(
            **self._head(),
            t=lab.t,
            platforms=plats,
            comau=ComauState(mode=lab.comau_mode, q=s.q.tolist(), qd=s.qd.tolist(), at_limit=lab.at_limit[:3].tolist()),
            winch=WinchState(
                mode=lab.winch.mode, length=float(s.L_w), speed=float(s.L_w_dot), speed_command=lab.winch.speed_command
            ),
            pendulum=PendulumState(alpha=float(s.swing[0]), beta=float(s.swing[1]), swing=float(lab.pendulum.swing)),
            vvmc=self.vvmc,
            delay=self.delay,
            predict=self.predict,
            frame=self._frame(),
            tool_error_b2=s.e_t_b2.tolist(),
            payload_height_error=float(s.payload_height_error),
            scene=self._scene(),
            plant=self.plant.link(time.monotonic()),
            machines=self.plant.machines(time.monotonic()),
            comau_jog=self._jog_state(),
            swing=self._swing_state(),
            load=self._load_state(),
            hazard=self._hazard(),
        )

    def _hazard(self) -> HazardState:
        """The hazard nearest its stop (issue 32, item 5): the Comau's arm near a platform's deck or its pedestal
        (:class:`app.control.lab.ComauGuard`, ahead of anything else), else the work point's range edge the
        operator's shift was last scaled for, if near."""
        rep = self.lab.guard_report
        if rep[0] >= 0 and self.plc is None:  # the simulated lab (on the real one the PLC moves the Comau)
            text = ComauGuard.text(rep)
            return HazardState(kind="collision", name=text.split(":")[0], value=float(rep[2]), share=float(rep[3]),
                               slowed=bool(rep[4]), text=text)  # fmt: skip
        hz = self.lab.work_hazard
        if hz is None or self.lab.comau_mode != "motion_comp":
            return HazardState()
        axis, gap, slowed = hz
        name = f"work point range {'xyz'[axis]}"
        share = gap / (0.25 * float(WORK_SHIFT_MAX[axis]))
        return HazardState(kind="workspace", name=name, value=gap, share=share, slowed=slowed,
                           text=f"{name}: {gap:.2f} m to its edge")  # fmt: skip

    def _jog_state(self) -> ComauJog:
        j = self._jog
        if j is None:
            return ComauJog(reason=self._jog_reason)
        return ComauJog(joint=j[0], speed=j[1], qd=j[1] * float(self.lab.joints.speed[j[0] - 1]))
