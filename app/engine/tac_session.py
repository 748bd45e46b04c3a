"""Engine session for the crane-head compensation scene (vessel, crane, Delta head).

Served by the same :class:`~app.engine.server.EngineServer` as the teleop session
(``bosun server --plant tac``), usually at 50 Hz: each tick advances the simulation by the tick's
time in steps of ``dt`` (0.01 s).  Commands: ``set_sea`` (spectrum, Hs, Tp, heading: a new sea that the
vessel's motion fades into over two peak periods while scene time runs on), ``set_vessel`` (likewise),
``set_tac_mode`` (off / tac / cooperative, switched live), ``estop`` (the head and crane freeze where they
are; latched until ``reset``).  After a reset they stay frozen until the operator
selects a mode again.  Input runs through the one :class:`~app.teleop.pipeline.InputPipeline` (a
profile's stop button latches the E-STOP here too); in ``tac`` and ``cooperative`` the armed stick moves the
TCP's target in the world (issue 30, item 2: :meth:`TacSession._drive`).  Teleop commands (robot, solver,
mode, frame) are refused with a clear message.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from app.control.guard import scale_in_box
from app.control.predict import LiftWindow
from app.engine.alarms import AlarmList
from app.engine.jobs import Deferred
from app.engine.scene import CommandError, Scene, command
from app.engine.vessel_upload import TableText, VesselChoice
from app.errors import BosunError
from app.geometry import euler_zyx_to_matrix
from app.marine.vessel import RAOTable
from app.marine.vessels import VESSELS
from app.marine.waves import SPECTRA
from app.models.registry import load_spec, resolve
from app.models.xml import read_robot_file
from app.net.snapshots import (
    CraneLoadState,
    HazardState,
    Hull,
    LiftWindowState,
    SeaState,
    ShipBox,
    TacDescription,
    TacSample,
    TacScenePoints,
    TacSnapshot,
    WaveField,
)
from app.scenarios.tac import MODES, RESUME_TIME, SEA_BLEND_PERIODS, SeaTransition, TacChunk, TacScenario, TacSimulator
from app.scenes.crane_load import (
    SNAP_FACTOR,
    CraneLoad,
    CraneSwingControl,
    LandingWatch,
    LoadChartWatch,
    Platform,
)
from app.scenes.load_lead import CRANE_LEAD_MAX, LoadLead
from app.scenes.target_deck import TargetVessel, VesselDeck
from app.teleop.pipeline import InputPipeline

SATURATION_WINDOW = 1000  # simulation steps (10 s at 0.01 s) over which the saturated share is counted

# the operator's stick (issue 30, item 2): x, y horizontal and z up (the profile's axes), in {n} (NED: z down)
STICK_TO_NED = np.diag([1.0, 1.0, -1.0])
TCP_SPEED = 0.5  # m/s at full stick (assumed: half the head's reach a second, 90°/s arms)
WINCH_SPEED = 1.0  # m/s at full stick on the w axis (the winch's own limit is higher: app/scenes/crane_load.py)
#: issue 32, item 5: the target slows through the outer quarter of its range; it is "at its range" (the alarm)
#: where an axis asked outward keeps under this share of its step
LIMITED_SHARE = 0.2
#: how far the stick may move the TCP's target from its calm-water point, per axis of {n} [m] (assumed): the head
#: alone (tac) within a quarter of its workspace's smallest extent; with the crane (cooperative) within the crane's
#: working range around the point of eq. (60)
TARGET_RANGE_COOPERATIVE = np.array([5.0, 5.0, 3.0])

# drawing only: the supply vessel's box (Lpp, B; deck at the crane base 3 m above CO, keel at T = 6 m)
SHIP_LENGTH, SHIP_BEAM, SHIP_DECK_Z, SHIP_KEEL_Z = 82.8, 19.2, -3.0, 6.0


#: the target platform (issue 30, item 5), from the load's calm-water point: 4 m forward, its deck 2 m below the
#: load, 6 m × 6 m (assumed; beyond the head's reach alone, within the cooperative crane's)
PLATFORM_OFFSET = np.array([4.0, 0.0, 2.0])
PLATFORM_HALF = (3.0, 3.0)
UP = np.array([0.0, 0.0, -1.0])
#: the crane's targets (issue 30, item 5): the fixed platform, or a second vessel's deck at the platform's place (the
#: default vessel's RAOs, the waves at TARGET_HEADING to it: ``sim transfer --target vessel``'s default)
TARGETS = ("platform", "vessel")
TARGET_HEADING = 60.0
#: the second vessel's motion data older than this is lost (issue 30, item 8; assumed: 25 samples of a 50 Hz link)
TARGET_STALE = 0.5
#: following a deck or the vessel eases in over this long (H107; assumed: a few of the wire's and servo's times)
FOLLOW_RAMP = 4.0
#: H107: following the vessel or a vessel target needs the crane: the head alone (tac) reaches a quarter of its
#: workspace while the point moves metres; it saturated and snatched the load (5.5× its weight, slack between)
FOLLOW_NEEDS_CRANE = (
    "following a moving deck needs the crane and head together (cooperative): the head alone reaches ±0.5 m, the "
    "deck moves metres"
)
#: the frames the crane-head scene's stick commands in: the world, the vessel's (base: riding with its deck, its
#: heading's axes) or the target deck's (following it, level axes)
FRAMES = ("world", "base", "target")


@dataclass
class TacSession(Scene):
    scenario: TacScenario = field(default_factory=lambda: TacScenario(duration=1e5))
    platform: Platform | None = None  # None: the default platform (PLATFORM_OFFSET from the load)

    KIND: ClassVar[str] = "tac"
    TITLE: ClassVar[str] = "the crane-head scene"

    def __post_init__(self) -> None:
        self._init_scene()
        self.robot_name, self.solver_name, self.mode = "tac", "-", self.scenario.mode
        self.vessel = VesselChoice(self.scenario.rao)  # set_vessel (issue 17, item 2)
        self.sim = TacSimulator(self.scenario, rao=self.vessel.rao(self.scenario.roll_damping))
        self.system = self.sim.system
        self._carry = 0.0
        self.holding = False  # after an E-STOP reset: frozen until a mode is commanded
        self.input = InputPipeline(note=self.note, axes=4)  # x, y, z: the TCP; w: the winch (issue 30)
        self.load = CraneLoad()  # the wire, winch and hanging load under the TCP (issue 30, item 3)
        if self.platform is None:
            centre = self.load.hook(self.sim.p_d_n0) + PLATFORM_OFFSET
            self.platform = Platform(tuple(float(v) for v in centre), PLATFORM_HALF)
        self.watch = LandingWatch(relift=True)  # the landing on it (issue 30, item 5)
        # this load in this sea against its SWL (issue 31, item 4): the crane file's rated capacity, ψ seen live
        self.chart = LoadChartWatch(load_spec(self.scenario.crane).rated_capacity)
        self._chart = self.chart.report(self.load.load_spec.mass, self.system.radius(self.sim.beta_d), 0.0)
        # the target: the platform or a second vessel's deck; the stick's frame; the second vessel's motion link
        self.target, self.frame = "platform", "world"
        self.vessel_deck: VesselDeck | None = None
        self.target_link = True  # tac_target_link: the second vessel's motion data arriving (simulated)
        self._target_seen: float | None = None  # engine time of its last data
        self.target_lost = False
        # following a deck (or the vessel): where the point was when it began, what has been applied, for how long
        self._follow: dict | None = None
        self._follow_gain = (0.0, 0.0, 0.0)  # (s, ṡ, D_z) of the ramp, for the winch's heave rate
        self._lead: LoadLead | None = None  # the load lead on a vessel target, and the anti-swing's reference
        self._lead_ref: tuple | None = None
        # the lift-window indicator (issue 31, item 3): the tip's heave (over a vessel target's deck) predicted
        self.lift = LiftWindow(self.scenario.dt)
        self._now = 0.0
        self._p_b: np.ndarray | None = None  # base frame: the followed point in the vessel's body frame {b}
        # the load's anti-swing (the lab's estimator and law, reused): off until the operator switches it on
        self.swing = CraneSwingControl(self.load, self.scenario.dt, np.random.default_rng(30), active=False)
        self.antisway = False
        self._offset = np.zeros(3)  # the anti-swing offset applied to the TCP's target
        self.alarms = AlarmList("Crane head", note=self.note)
        self._saturated = deque(maxlen=SATURATION_WINDOW)
        self.last: dict[str, Any] = {}
        self.sea_seq = 0
        self._publish_count = 0
        pts = self.system.workspace.points
        self.target_range = {
            "tac": np.full(3, 0.25 * float(np.min(pts.max(axis=0) - pts.min(axis=0)))),
            "cooperative": TARGET_RANGE_COOPERATIVE,
        }
        self.target_limited = False
        self.hazard = HazardState()  # the range edge nearest the target: scaled for a command, or at rest (H124)
        hull = self.system.workspace.hull
        self._hull = {
            "points": np.round(hull.points[hull.vertices], 4).tolist(),
            "index": {int(v): i for i, v in enumerate(hull.vertices)},
        }
        self._hull["faces"] = [[self._hull["index"][int(v)] for v in s] for s in hull.simplices]
        del self._hull["index"]
        self.note("info", f"crane-head scene: Hs {self.scenario.hs:g} m, Tp {self.scenario.tp:g} s, mode {self.mode}")

    # ------------------------------------------------------------------ commands
    @command
    def set_sea(self, spectrum: str, hs: float, tp: float, heading: float) -> None:
        try:
            sc = replace(self.scenario, spectrum=spectrum, hs=hs, tp=tp, heading=heading, seed=self.scenario.seed + 1)
        except BosunError as err:
            raise CommandError(str(err)) from None
        self.scenario = sc
        self._rebuild()
        self.note("info", f"sea: {spectrum} Hs {hs:g} m, Tp {tp:g} s, heading {heading:g}°")

    def _rebuild(self, built: TacSimulator | None = None) -> None:
        """A new simulator for the scenario and vessel that continues the running one (docs/safety.md H65):
        scene time runs on, the machine continues where it is, and the vessel's motion fades from the old
        sea or vessel into the new over two peak periods, so the head's reference never jumps
        (:meth:`~app.scenarios.tac.TacSimulator.continue_from`).  ``built``: that simulator, made off the loop
        for this scenario and vessel (:meth:`set_vessel`)."""
        old = self.sim
        new = built or TacSimulator(self.scenario, self.system, rao=self.vessel.rao(self.scenario.roll_damping))
        blend = SEA_BLEND_PERIODS * max(old.scenario.tp, self.scenario.tp)
        new.continue_from(old, blend)
        self.sim = new
        if self.vessel_deck is not None:  # the second vessel in the new sea, faded into as the crane's vessel is
            was = self.vessel_deck.vessel.motion
            self.vessel_deck = self._vessel_deck()
            self.vessel_deck.vessel.motion = SeaTransition(was, self.vessel_deck.vessel.motion, self._t(), blend)
            self.vessel_deck.vessel.__dict__.pop("_poses", None)  # poses of the motion just replaced
        self.sea_seq += 1
        self.changed()

    @command
    def set_vessel(
        self, vessel: str | None = None, csv: str | None = None, part: int = 0, parts: int = 1, label: str = ""
    ) -> Deferred | None:
        """The vessel by name (``supply``, ``supply-closed-form``) or an RAO table in Bosun's CSV, sent in
        ``parts`` parts (issue 17, item 2).  A table that does not parse is refused with its file, line and
        field; nothing changes until the last part has arrived and parsed.

        Under a server a whole table is parsed, and the simulator built on it, off the control loop (issue 27,
        item 2): this returns a :class:`~app.engine.jobs.Deferred`, the new simulator takes over at a tick
        boundary (:meth:`_vessel_built`) and the reply follows.  A later vessel (a name or another table)
        supersedes it; a STOP or reset meanwhile stands (the swap touches neither)."""
        got = self.vessel.take(vessel, csv, part, parts, label)
        if got is False:
            return None
        if isinstance(got, TableText):
            if self.jobs.background:
                scenario, system = self.scenario, self.system

                def work(step) -> tuple[RAOTable, TacScenario, TacSimulator]:
                    table = got.parse(step)
                    step()
                    return table, scenario, TacSimulator(scenario, system, rao=table)

                return self.jobs.start(f"set_vessel {got.where}", work, lambda r: self._vessel_built(got, *r))
            self.vessel.use(got.parse(), got)
        self.jobs.supersede(f"set_vessel {self.vessel.label}")  # a pending table would undo this choice
        self._rebuild()
        self._vessel_note()

    def _vessel_built(self, text: TableText, table: RAOTable, scenario: TacScenario, built: TacSimulator) -> None:
        """At a tick boundary: the table parsed and the simulator built off the loop take over.  Built for the
        scenario of its command: a mode switched since is the running one's (the machine's states carry over in
        any case); a sea changed since (``set_sea``, a new sea record) makes it stale: rebuilt here on the
        parsed table, as ``set_sea`` does (milliseconds; the parse was the long part)."""
        before = (self.vessel.name, self.vessel.table, self.vessel.label)
        self.vessel.use(table, text)
        try:
            if replace(scenario, mode=self.scenario.mode) != self.scenario:
                built = None
            elif built.scenario.mode != self.scenario.mode:
                built.set_mode(self.scenario.mode)
            self._rebuild(built)
        except Exception:  # refused (the job's reply): the scene keeps the vessel it runs
            self.vessel.name, self.vessel.table, self.vessel.label = before
            raise
        self._vessel_note()

    def _vessel_note(self) -> None:
        t = self.sim.vessel_rao
        self.note("info", f"vessel: {self.vessel.label} ({t.w.size} frequencies × {t.headings.size} headings)")

    @command
    def set_tac_mode(self, mode: str) -> None:
        if mode not in MODES:
            raise CommandError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
        if self.estop_latched:
            raise CommandError("E-STOP is latched; reset first")
        if mode == "off" and self.mode != "off" and self._over_target():
            # H100: off, the hook rides the vessel into the deck (or lifts a landed load and drops it), and the crane
            # drives back to its nominal configuration, dragging the load across the deck
            raise CommandError(
                f"compensation stays on while the load {self._where()}: lift it clear and move it off the deck first"
            )
        if mode != "cooperative" and self._moving_frame(self.frame):
            raise CommandError(f"mode {mode}: the {self.frame} frame follows a moving point; {FOLLOW_NEEDS_CRANE} "
                               "(choose the world frame first)")  # fmt: skip
        fades = self.holding or (mode == "off") != (self.mode == "off")  # H108: the new references fade in
        self.sim.set_mode(mode)
        self.scenario = self.sim.scenario
        if mode != self.mode:
            self.input.disarm("compensation mode changed")  # a held stick must not move the TCP in the new mode
        self.mode = mode
        self.holding = False
        self.note("info", f"compensation mode: {mode}" + (f" (fading in over {RESUME_TIME:g} s)" if fades else ""))

    @command
    def set_crane_antisway(self, on: bool) -> None:
        """The load's anti-swing law on or off (issue 30, item 3): on, it adds an offset against the swing to the
        TCP's target while the head (and crane) compensate; off, the offset returns to zero along the law."""
        self.antisway = bool(on)
        self.note("info", f"load anti-swing {'on' if on else 'off'}")

    @command
    def set_tac_delay(self, delay: float, predict: bool = False) -> None:
        """The measurement-to-actuation delay (issue 31, item 2): the controller sees the MRU's η, ν ``delay`` s late,
        or with ``predict`` the motion predicted that far ahead from them (the predictor starts on the sensor's last
        300 s).  The delay is the equipment's: it is set while the compensation is off (the references would
        change at once under a compensating head and crane; switched on again, they fade in from where the machine
        is, H108)."""
        delay = float(delay)
        if not (math.isfinite(delay) and 0.0 <= delay <= 2.0):
            raise CommandError(f"delay must be in [0, 2] s, got {delay}")
        if self.mode != "off":
            raise CommandError("the delay is set while the compensation is off: choose off first, then the mode again")
        sim = self.sim
        sim.scenario = replace(sim.scenario, delay=delay, predict=bool(predict))
        self.scenario = sim.scenario
        if not predict:
            sim._foresight = None  # a later prediction starts again on the sensor's past
        self.note("info", f"delay {delay:g} s" + (", the motion predicted that far ahead" if predict else ""))

    @command
    def set_frame(self, frame: str) -> None:
        """The frame the stick commands in (issue 30, item 1): ``world`` (a centred stick holds the TCP still in the
        world), ``base`` (it holds the TCP over a point of the crane's own vessel, riding its surge, sway and heave:
        a load picked up from its deck; the stick moves along the vessel's heading) or ``target`` (over the target
        deck's spot, following its surge, sway and heave with level axes; the fixed platform's is the world's).
        The heave is the winch's in both.  The head's (tool) frame is refused with the reason.  A change disarms
        the input (H96)."""
        if frame not in FRAMES:
            raise CommandError(
                f"frame {frame}: the crane-head scene commands in the world, base (the vessel's) or target deck's "
                "frame (the head's frame is not in this scene)"
            )
        if self._moving_frame(frame) and self.mode != "cooperative":
            raise CommandError(f"frame {frame}: {FOLLOW_NEEDS_CRANE}")
        if frame != self.frame:
            self.input.disarm("command frame changed")
            self._follow, self._p_b = None, None  # following starts from where the deck is now: nothing jumps
        self.frame = frame
        self.note("info", f"frame: {frame}" + (" (the fixed platform: the world's)" if self._fixed(frame) else ""))

    def _moving_frame(self, frame: str) -> bool:
        """Whether ``frame`` makes the TCP follow a moving point (the vessel's, or a vessel target's deck)."""
        return frame == "base" or (frame == "target" and self.target == "vessel")

    def _fixed(self, frame: str) -> bool:
        return frame == "target" and self.target == "platform"

    @command
    def set_crane_target(self, target: str) -> None:
        """The deck the load is landed on (issue 30, item 5): the fixed ``platform`` or a second ``vessel``'s deck at
        the platform's place in the same sea.  Not while the load is over the present target's deck (hanging or
        landed).  The vessel target selects the target frame (the TCP follows its deck); the input is disarmed."""
        if target not in TARGETS:
            raise CommandError(f"target must be one of {', '.join(TARGETS)}, got {target!r}")
        if target == self.target:
            return
        if self._over_target():
            raise CommandError(f"the target stays while the load {self._where()}: lift it clear and move it off first")
        self.target = target
        self.vessel_deck = self._vessel_deck() if target == "vessel" else None
        self.lift = LiftWindow(self.scenario.dt, self.lift.threshold)  # another signal: learnt afresh
        self._target_seen, self.target_lost, self._follow = None, False, None
        self.watch = LandingWatch(relift=True)
        self.input.disarm("landing target changed")
        self.frame = "target" if target == "vessel" and self.mode == "cooperative" else "world"
        self._follow, self._p_b = None, None
        more = (
            ""
            if self.frame == "target" or target == "platform"
            else " (to follow its deck: cooperative, then frame target)"
        )
        self.note("info", f"target: {target}; frame: {self.frame}{more}")

    @command
    def tac_target_link(self, up: bool) -> None:
        """The second vessel's motion link up or down (simulated: training, and the "target lost" hazard's test).
        Down, its data age; past :data:`TARGET_STALE` the target is lost (alarm ``target_lost``)."""
        if self.target != "vessel":
            raise CommandError("the target link is the second vessel's: select target vessel first")
        self.target_link = bool(up)
        self.note("warning" if not up else "info", f"second vessel's motion link {'up' if up else 'down'}")

    @command
    def set_lift_window(self, threshold: float) -> None:
        """The lift window's threshold (issue 31, item 3): a window is open while the tip's heave — over the target
        deck with a vessel target — is predicted, with the model's probability 0.95 or more, to stay within
        ± ``threshold`` m of its mean for the next 10 s.  The prediction goes on (only the verdict changes)."""
        threshold = float(threshold)
        if not (math.isfinite(threshold) and 0.05 <= threshold <= 10.0):
            raise CommandError(f"lift window threshold must be in [0.05, 10] m, got {threshold}")
        self.lift.threshold = threshold
        self.note("info", f"lift window: the heave within ±{threshold:g} m for {self.lift.length:g} s")

    def _feed_lift(self, c: TacChunk) -> None:
        """The lift window's signal over the chunk: the crane tip riding the vessel (its heave as the MRU gives it,
        the sensor's noise aside), less the target deck's with a vessel target."""
        if not c.t.size:
            return
        if not self.lift.primed:  # its sensor has run all along: the predictor starts on the last 300 s
            self._prime_lift(c)
        z = c.p_s_n[:, 2]
        if self.vessel_deck is not None:
            z = z - self.vessel_deck.vessel.spots(c.t)[:, 2]
        self.lift.feed(-z)  # NED: up positive, as the strip shows it

    def _prime_lift(self, c: TacChunk) -> None:
        """The lift window's signal over the 300 s before this chunk: the vessel's motion then (the sea's) carrying
        the crane tip where it is on the vessel now (its nominal configuration), less the target deck's."""
        w = self.lift
        sp = w.predictor.spec
        th = c.t[0] - np.arange(round(sp.window / sp.dt), 0, -1) * sp.dt
        th = th[th >= 0.0] if isinstance(self.sim.vessel, SeaTransition) else th
        eta0 = c.eta[0]
        r_b = euler_zyx_to_matrix(eta0[3:6]).T @ (c.p_s_n[0] - eta0[:3])  # the tip in the vessel's frame
        eta = self.sim.vessel.state(th).eta
        z = eta[:, 2] + np.einsum("nj,j->n", euler_zyx_to_matrix(eta[:, 3:6])[:, 2, :], r_b)
        if self.vessel_deck is not None:
            z = z - self.vessel_deck.vessel.spots(th)[:, 2]
        w.prime(-z)

    def _lift_state(self) -> LiftWindowState:
        w = self.lift
        ready = w.mean is not None
        return LiftWindowState(
            signal="relative heave" if self.vessel_deck is not None else "heave",
            threshold=w.threshold, length=w.length, probability_min=w.probability_min, step=w.STEP,
            mean=w.mean.tolist() if ready else [], sigma=w.sigma.tolist() if ready else [],
            probability=float(w.probability) if ready else None, open=w.open, learning_s=w.learning_s,
        )  # fmt: skip

    def _vessel_deck(self) -> VesselDeck:
        vessel = TargetVessel(
            None, TARGET_HEADING, self.sim.vessel.sea, self.scenario.heading, np.array(self.platform.centre)
        )
        return VesselDeck(vessel, PLATFORM_HALF)

    def _t(self) -> float:
        return self.sim.k * self.scenario.dt

    def _over_target(self) -> bool:
        hook = self.load.hook(self.sim.p_d_n)
        if self.vessel_deck is not None:
            return self.vessel_deck.over(hook, self._t())
        return self.platform.over(hook)

    def _where(self) -> str:
        hook = self.load.hook(self.sim.p_d_n)
        deck = "the platform" if self.vessel_deck is None else "the target vessel's deck"
        if self.watch.in_contact:
            return f"rests on {deck}"
        z = self.platform.centre[2] if self.vessel_deck is None else self.vessel_deck.vessel.pose(self._t())[0][2]
        return f"hangs {float(z - hook[2]):.1f} m over {deck}"  # NED: the deck is below, at a larger z

    def estop(self, source: str = "operator") -> None:
        self._latch(f"E-STOP from {source}: head and crane stopped")

    def reset(self) -> None:
        """Clear a latched E-STOP; head and crane stay frozen until the operator selects a mode."""
        if self.estop_latched:
            self.holding = True
            self._unlatch("head and crane hold; select a compensation mode to resume")

    # ------------------------------------------------------------------ loop
    def tick(self, now: float, dt: float, solve_budget: float | None = None) -> None:
        if self.paused:  # time stands still; the stop button still latches
            if self.input.step(now).stop:
                self.estop(source=f"the stop button of {self.input.profile.name}")
            return
        self._carry += dt
        n = int(self._carry / self.scenario.dt + 1e-9)
        if n <= 0:
            return
        self._carry -= n * self.scenario.dt
        inp = self.input.step(now)
        if inp.stop:
            self.estop(source=f"the stop button of {self.input.profile.name}")
        frozen = self.estop_latched or self.holding
        self._drive(inp, frozen, n * self.scenario.dt)
        following = self._follow_target(now, frozen, n * self.scenario.dt)
        riding = self._follow_base(frozen, n * self.scenario.dt) if self.frame == "base" else False
        gain, gain_rate, lag_z = self._follow_gain
        # the anti-swing offset of the last step onto the TCP's target (held over the tick, as the stick's move)
        offset = self.swing.offset
        self.sim.p_d_n = self.sim.p_d_n + (offset - self._offset)
        self._offset = offset.copy()
        self.swing.active = self.antisway and self.mode != "off" and not frozen
        chunks = []
        while n > 0:  # every step of the tick, also across the end of a sea record
            if self.sim.done:  # a long session: a fresh sea record that continues this one (H65)
                self.set_sea(self.scenario.spectrum, self.scenario.hs, self.scenario.tp, self.scenario.heading)
            chunks.append(self.sim.advance(n, frozen=frozen))
            n -= chunks[-1].t.size
        c = chunks[0] if len(chunks) == 1 else TacChunk.concat(chunks)
        ld, watch, events = self.load, self.watch, [False] * 4
        step, base, zero = self.scenario.dt, ld.speed_command, np.zeros(3)
        ride_z = self._base_point(np.asarray(self.last["eta"]))[2] if riding else 0.0
        peak = 0.0  # the wire's peak tension over the tick (the load chart's ψ)
        for k, (p, tk) in enumerate(zip(c.p_c_n, c.t, strict=True)):  # the load: one step per simulation step
            if riding:  # the base frame: the winch holds the hook's height over the vessel's point (its heave rate)
                z = self._base_point(c.eta[k])[2]
                ld.speed_command = base + gain * (z - ride_z) / step + gain_rate * lag_z
                ride_z = z
            if self.vessel_deck is not None:  # the second vessel's deck under the load, and its velocity
                ld.deck = self.vessel_deck.deck(ld.hook(p), float(tk), step)
                deck_v, n_up = ld.deck[3], ld.deck[2]
                # following its deck, the winch's heave compensation holds the hook's height over it (its heave rate)
                if not riding:
                    ld.speed_command = base + (gain * float(deck_v[2]) + gain_rate * lag_z if following else 0.0)
            else:
                ld.deck = self.platform.deck(ld.hook(p))
                deck_v, n_up = zero, UP
            ld.step(p, step)
            peak = max(peak, ld.tension)
            watch.step(ld, deck_v, n_up)
            e = ld.state[0] - p
            self.swing.step(e, float(np.sqrt(e @ e)), not watch.touched and not watch.slack, self._lead_ref)
            for i, ev in enumerate((watch.slack, watch.snap, watch.rehit, watch.sideways)):
                events[i] = events[i] or ev
        self._feed_lift(c)
        self.chart.step(now, peak / ld.static_tension())
        # the radius of the TCP where the head holds it (its arms' offset and the anti-swing's in it), not the nominal
        radius = self.system.radius(c.beta[-1], c.p_c_t[-1])
        chart = self.chart.report(ld.load_spec.mass, radius, now)
        self._chart = chart
        self._saturated.extend(c.saturated.tolist())
        share = sum(self._saturated) / max(1, len(self._saturated))
        al = self.alarms
        al.at(now)
        al.set("estop", self.estop_latched, text="E-STOP latched: reset to continue")
        driving = self.mode in ("tac", "cooperative")  # the stick moves the TCP's target (issue 30, item 2)
        fl = self.input.flags()
        al.set("device_lost", driving and self.input.lost, text="Input device lost: the TCP's target holds")
        stale = driving and fl["device"] and fl["stale_input"] and self.input.stale_while_driving
        al.set("stale_input", stale, text="Input stale: the TCP's target holds")
        al.set("target_limit", self.target_limited, text=f"TCP target at its {self.mode} range: it stops there")
        al.set(
            "target_lost",
            self.target_lost,
            text=f"Target vessel's motion data {self._target_age():.1f} s old: the TCP and the winch hold in the "
            "world, not over its deck; lift the load clear",
        )
        slack, snap, rehit, sideways = events  # the landing (issue 30, item 5)
        al.set("slack_wire", slack, text="Slack wire: the load is not on the deck and the wire does not carry it")
        al.set("snap_load", snap, text=f"Snap load: the wire pulled over {SNAP_FACTOR:g}× the load's weight")
        al.set("rehit", rehit, text=f"Re-hit: the load struck the deck again ({watch.contacts - 1} since touchdown)")
        al.set("sideways_contact", sideways, text="The load touched the deck while sliding sideways")
        pct, beyond = chart["swl_percent"], self.chart.beyond(radius)
        if beyond:  # past the chart's last rating: no SWL there, which is no reason to stay quiet
            last = float(self.chart.rating.radius[-1])
            text = f"Overload: the load is at {radius:.1f} m, beyond the crane's rated chart ({last:g} m): not rated"
        elif pct is not None:
            text = f"Overload: the load with the sea's dynamic factor ψ {chart['psi']:.2f} is {pct:.0f} % of its SWL "
            text += f"at {radius:.1f} m"
        else:
            text = "Overload: the load's share of its SWL is not known yet"
        al.set("overload", beyond or (pct is not None and pct >= 100.0), text=text)
        al.set(  # holding after a reset is a status (the plant light), not an alarm: nothing is wrong
            "saturation",
            value=0.0 if frozen else 100.0 * share,
            text=f"Crane head saturated {100 * share:.0f} % of the last {SATURATION_WINDOW * self.scenario.dt:g} s",
        )
        if c.t.size:
            self.last = {
                "t": float(c.t[-1]),
                "eta": c.eta[-1].tolist(),
                "beta": c.beta[-1].tolist(),
                "p_ref_t": c.p_ref_t[-1].tolist(),
                "p_c_t": c.p_c_t[-1].tolist(),
                "alpha_ref": c.alpha_ref[-1].tolist(),
                "alpha": c.alpha[-1].tolist(),
                "u": c.u[-1].tolist(),
                "e_c": float(c.e_c[-1]),
                "e_s": float(c.e_s[-1]),
                "saturated": bool(c.saturated.any()),
                "p_c_n": c.p_c_n[-1].tolist(),
                "p_s_n": c.p_s_n[-1].tolist(),
            }

    def _target_age(self) -> float:
        return 0.0 if self._target_seen is None else max(0.0, self._now - self._target_seen)

    def _follow_target(self, now: float, frozen: bool, dt: float) -> bool:
        """The target frame on a vessel target (issue 30, items 1 and 5): the TCP's target follows the deck spot's
        surge and sway (the winch its heave, in the load's step), from where the deck was when following began,
        so nothing jumps.  Its motion data older than :data:`TARGET_STALE` lose the target (H105): the TCP and
        the winch hold in the world, the input is disarmed, and following starts afresh when the data are back.
        Returns whether the deck is followed this tick."""
        self._now = now
        if self.vessel_deck is None:
            self.target_lost = False
            return False
        if self.target_link or self._target_seen is None:
            self._target_seen = now
        lost = self._target_age() > TARGET_STALE
        if lost != self.target_lost:
            self.target_lost = lost
            self._follow = None
            self.input.disarm("target vessel's data lost" if lost else "target vessel's data back")
            self.note("error" if lost else "info", "target vessel lost: holding in the world" if lost else
                      "target vessel's data back: following its deck from where it is now")  # fmt: skip
        if self.frame != "target":  # the base frame follows its own point (_follow_base)
            return False
        following = not lost and self.mode != "off" and not frozen
        return self._follow_point(following, lambda: self.vessel_deck.vessel.pose(self._t())[0], dt, self._lead_step)

    def _lead_step(self, dt: float) -> np.ndarray:
        """The load lead on the vessel target (:class:`app.scenes.load_lead.LoadLead`): the TCP leads the deck's
        spot by L/(g − z̈)·ẍ so the load below moves with the deck, not behind and beyond it; eased in with the
        following (its ramp), capped at CRANE_LEAD_MAX.  The anti-swing gets the plan as its reference."""
        if self._lead is None:
            self._lead = LoadLead(dt, CRANE_LEAD_MAX, 1e-9)
        t = self._t()
        f, ref = self._lead.step(self.vessel_deck.vessel.spot_acceleration(t), np.zeros(3), self.load.length, dt)
        self._lead_ref = ref
        return f

    def _base_point(self, eta: np.ndarray) -> np.ndarray:
        """The base frame's followed point in {n} for the vessel at η (its body point ``_p_b``)."""
        return eta[:3] + euler_zyx_to_matrix(eta[3:6]) @ self._p_b

    def _follow_base(self, frozen: bool, dt: float) -> bool:
        """The base frame (issue 30, item 1): the TCP's target rides a point of the crane's own vessel (the TCP's
        target when following began, in the vessel's body frame), its surge and sway here, its heave the winch's."""
        following = self.frame == "base" and self.mode != "off" and not frozen and bool(self.last)
        if following and self._p_b is None:
            eta = np.asarray(self.last["eta"])
            self._p_b = euler_zyx_to_matrix(eta[3:6]).T @ (self.sim.p_d_n - eta[:3])
        elif not following:
            self._p_b = None
        return self._follow_point(following, lambda: self._base_point(np.asarray(self.last["eta"])), dt)

    def _follow_point(self, following: bool, point, dt: float, lead=None) -> bool:
        """Move the TCP's target with the followed point's horizontal displacement D since following began, eased
        in: A = s(τ) D, s = 3τ² − 2τ³, τ = t / FOLLOW_RAMP (the TCP starts from rest and ends on the point with no
        lag: a step to the deck's velocity rang the load's wire from 0.63 to 1.43× its weight); within the mode's
        range (its alarm).  The winch's heave rate is eased the same way (``_follow_gain``: s, ṡ and D_z)."""
        if not following:
            self._follow, self._follow_gain = None, (0.0, 0.0, 0.0)
            self._lead, self._lead_ref = None, None
            return False
        spot = np.asarray(point(), dtype=float)
        f = self._follow
        if f is None:
            f = self._follow = {"spot0": spot.copy(), "applied": np.zeros(3), "t": 0.0}
        else:
            f["t"] += dt
        tau = min(1.0, f["t"] / FOLLOW_RAMP)
        s, s_dot = tau * tau * (3.0 - 2.0 * tau), 6.0 * tau * (1.0 - tau) / FOLLOW_RAMP
        D = spot - f["spot0"]
        A = s * D
        if lead is not None:  # the load lead (the vessel target): eased in with the following
            f_lead = lead(dt)
            A[:2] += s * f_lead[:2]
            self._lead_ref = (s * self._lead_ref[0], s * self._lead_ref[1])
        dp = A - f["applied"]
        dp[2] = 0.0  # the heave is the winch's
        f["applied"] = A
        if (dp[0] or dp[1]) and self.sim.move_target(dp, self.target_range[self.mode]):
            self.target_limited = True
        self._follow_gain = (s, s_dot, float(D[2]))
        return True

    def _drive(self, inp, frozen: bool, dt: float) -> None:
        """The stick moves the TCP's target in the world (issue 30, item 2) while the head (tac) or the crane and
        head (cooperative) compensate: a centred stick holds the TCP still in the world, a deflection moves it
        there on top of the compensation.  Only when armed and enabled (deadman, fresh), never frozen or in
        ``off``; the target's offset stays within the mode's range (:meth:`TacSimulator.move_target`)."""
        self.target_limited = False
        self.hazard = self._range_hazard(None)  # where the target stands; a command's own replaces it (_scaled)
        # the winch: heave compensation while the head compensates; the stick's w pays out (positive) or hauls in
        drive = not frozen and inp.enabled and not self.estop_latched
        self.load.ahc, self.load.stopped = self.mode != "off" and not frozen, self.estop_latched
        self.load.speed_command = WINCH_SPEED * float(inp.signal[3]) if drive and len(inp.signal) > 3 else 0.0
        if frozen or self.mode == "off" or not inp.enabled or self.estop_latched:
            return
        s = np.asarray(inp.signal[:3], dtype=float)
        if not np.any(s):
            return
        dp = STICK_TO_NED @ (TCP_SPEED * s) * dt
        if self.frame == "base" and self.last:  # along the vessel's heading; the followed point moves with it
            eta = np.asarray(self.last["eta"])
            dp = euler_zyx_to_matrix(np.array([0.0, 0.0, eta[5]])) @ dp
        dp = self._scaled(dp)
        if self.frame == "base" and self.last:
            before = self.sim.p_d_n.copy()
            self.target_limited |= self.sim.move_target(dp, self.target_range[self.mode])
            if self._p_b is not None:
                self._p_b = self._p_b + euler_zyx_to_matrix(eta[3:6]).T @ (self.sim.p_d_n - before)
            return
        self.target_limited |= self.sim.move_target(dp, self.target_range[self.mode])

    def _scaled(self, dp: np.ndarray) -> np.ndarray:
        """The stick's step of the TCP's target ``dp`` [m, {n}] scaled along the directions that bring the edge of
        the mode's range nearer (issue 32, item 5: the head's reach alone, the crane's with it): each axis's outward
        part through the outer quarter of the range (:func:`~app.control.guard.scale_in_box`); inward and along an
        edge never.  A load coming down onto a deck is a landing, not a collision: it is not slowed here (its
        speed, re-hits and slack are the landing watch's)."""
        limit = self.target_range[self.mode]
        out, axis, gap = scale_in_box(dp, self.sim.p_d_n - self.sim.p_d_n0, limit)
        # at its range: an axis asked outward keeps under a fifth of its step (within 8 cm of the head's edge)
        held = np.abs(out) < LIMITED_SHARE * np.abs(dp)
        self.target_limited = self.target_limited or bool(np.any(held))
        self.hazard = self._range_hazard((axis, gap, bool(np.any(np.abs(out) < np.abs(dp) - 1e-15))))
        return out

    def _range_hazard(self, scaled: tuple[int, float, bool] | None) -> HazardState:
        """The edge of the mode's range nearest the TCP's target, if in its zone (the outer quarter): ``scaled`` the
        stick's step's (axis, gap [m], slowed), or None where nothing is commanded — then the edge the target
        stands nearest, not slowing (H124: the line said "none near" at rest, whatever the target's offset)."""
        if self.mode not in self.target_range:
            return HazardState()
        limit = self.target_range[self.mode]
        if scaled is None:
            _, axis, gap = scale_in_box(np.zeros(3), self.sim.p_d_n - self.sim.p_d_n0, limit)
            scaled = (axis, gap, False)
        axis, gap, slowed = scaled
        if axis < 0:
            return HazardState()
        name = f"{self.mode} range {'xyz'[axis]}"
        return HazardState(
            kind="workspace", name=name, value=gap, share=gap / (0.25 * float(limit[axis])), slowed=slowed,
            text=f"{name}: {gap:.2f} m to its edge",
        )  # fmt: skip

    def _load_state(self) -> CraneLoadState:
        ld = self.load
        return CraneLoadState(
            hook=np.round(ld.hook(np.asarray(self.last["p_c_n"])), 4).tolist(),
            wire_length=round(ld.length, 4),
            wire_speed=round(ld.length_rate, 4),
            swing_deg=round(float(np.degrees(ld.swing_angle())), 3),
            tension_factor=round(float(ld.tension / ld.static_tension()), 4),
            ahc=bool(ld.ahc),
            clearance=round(float(ld.gap), 4) if bool(ld.deck[0]) else None,
            **self.watch.report(),
            antisway=self.antisway,
            antisway_offset=np.round(self._offset[:2], 4).tolist(),
            **self._chart,
        )

    def _scene(self) -> TacScenePoints:
        """Points in {n} for drawing: ship box corners, crane polyline, head knees, TCP, desired point."""
        eta = np.asarray(self.last["eta"])
        R_n_b = euler_zyx_to_matrix(eta[3:6])  # R_b^n
        o = eta[:3]
        beta = np.asarray(self.last["beta"])
        F = self.system.crane.frames(beta)
        crane_b = F[:, :3, 3]
        o_t_b, R_b_t = F[-1, :3, 3], F[-1, :3, :3]
        alpha = np.asarray(self.last["alpha"])
        knees_t = self.system.head.knees(alpha)
        p_c_t = np.asarray(self.last["p_c_t"])
        head_b = o_t_b + (np.vstack([knees_t, p_c_t]) @ R_b_t.T)
        hl, hb = SHIP_LENGTH / 2, SHIP_BEAM / 2
        ship_b = np.array([[x, y, z] for x in (-hl, hl) for y in (-hb, hb) for z in (SHIP_DECK_Z, SHIP_KEEL_Z)])

        def to_n(p):
            return np.round(p @ R_n_b.T + o, 4).tolist()

        hook = self.load.hook(np.asarray(self.last["p_c_n"])).tolist()
        deck = self.platform.corners() if self.vessel_deck is None else self.vessel_deck.corners(self._t())
        return TacScenePoints(ship=to_n(ship_b), crane=to_n(crane_b), head=to_n(head_b), hook=hook, deck=deck)

    def describe(self) -> TacDescription:
        sc = self.scenario
        sea = self.sim.vessel.sea
        return TacDescription(
            seq=self.describe_seq,
            title="Crane head",
            commands=sorted(kind.TYPE for kind in self.COMMANDS),
            crane_xml=read_robot_file(resolve(sc.crane)),
            head_xml=read_robot_file(resolve(sc.head)),
            vessel=self.vessel.label,
            vessels=list(VESSELS),
            ship=ShipBox(length=SHIP_LENGTH, beam=SHIP_BEAM, deck_z=SHIP_DECK_Z, keel_z=SHIP_KEEL_Z),
            alpha_limits=[float(self.system.head.lower[0]), float(self.system.head.upper[0])],
            hull=Hull(points=self._hull["points"], faces=self._hull["faces"]),
            sea=self._sea(),
            waves=WaveField(
                amplitude=sea.amplitude.tolist(),
                omega=sea.omega.tolist(),
                k=sea.wavenumber.tolist(),
                heading_rad=sea.direction.tolist(),
                phase=sea.phase.tolist(),
            ),
            modes=list(MODES),
            spectra=list(SPECTRA),
        )

    def _sea(self) -> SeaState:
        sc = self.scenario
        return SeaState(spectrum=sc.spectrum, hs=sc.hs, tp=sc.tp, heading_deg=sc.heading, seq=self.sea_seq)

    def snapshot(self) -> TacSnapshot:
        return TacSnapshot(
            **self._head(),
            t=float(self.last["t"]) if self.last else 0.0,
            holding=self.holding,
            sea=self._sea(),
            tac_mode=self.scenario.mode,
            x_d=self.system.x_d,
            p_d_n=self.sim.p_d_n.tolist(),
            load=self._load_state() if self.last else None,
            hazard=self.hazard,
            target=self.target,
            frame=self.frame,
            target_age=round(self._target_age(), 3) if self.vessel_deck is not None else None,
            target_lost=self.target_lost,
            delay=self.scenario.delay,
            predict=self.scenario.predict,
            lift=self._lift_state(),
            sample=TacSample(**self.last) if self.last else None,
            scene=self._scene() if self.last else None,
        )
