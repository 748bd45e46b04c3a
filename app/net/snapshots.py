"""Typed engine state of protocol version 3: one snapshot class and one description class per scene.

An engine publishes a :class:`Snapshot` subclass 25–50 times a second (what changes) and answers a
``describe`` request with a :class:`Description` subclass (what is static: the robot file, joint
limits, the workspace box, the lab's geometry …; sent on join and whenever it changes, announced by
``describe_seq`` in every snapshot).  Every snapshot has the same head: ``kind`` names the scene
(``teleop``, ``tac``, ``lab``), ``estop`` is the scene's E-STOP latch, ``flags`` the input pipeline,
``alarms`` the alarm list and ``engine`` the server's bookkeeping (roles, counters, health).

On the wire a snapshot is a msgpack map made by :func:`to_wire`; :func:`snapshot_from_wire` and
:func:`description_from_wire` turn it back into these classes, checking ``kind`` and every field's
type, so a client reads ``state.engine.operator`` instead of ``state["operator"]``.  Fields a newer
engine adds are ignored (adding an optional field keeps the protocol version, docs/protocol.md).

Units: SI, radians; frames as in each field's comment.
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from dataclasses import dataclass, field
from typing import Any, ClassVar

from app.errors import BosunError


class SnapshotError(BosunError):
    """A state or description map that does not fit its class (wrong kind, missing or mistyped field)."""


# ---------------------------------------------------------------------------------------------- shared parts
@dataclass(kw_only=True, slots=True)
class InputFlags:
    """The input pipeline as the engine sees it (app/teleop/pipeline.py)."""

    stale_input: bool = True  # no input for 200 ms: holding
    enabled: bool = False  # armed, deadman held, fresh: the input may move the machine
    armed: bool = False
    deadman: bool = False
    device: bool = False  # an input device is connected
    device_name: str = ""
    profile: str = ""
    input_reason: str = ""  # why the input does not move the machine, one line
    stale_count: int = 0


@dataclass(kw_only=True, slots=True)
class Alarm:
    key: str
    severity: str  # info | warning | critical
    source: str
    text: str
    active: bool
    acked: bool
    t_raised: float
    t_cleared: float | None
    first_out: bool
    count: int = 1
    shelved_until: float | None = None  # wall-clock end of the operator's shelving (None: not shelved)


@dataclass(kw_only=True, slots=True)
class EngineInfo:
    """The server's part of every snapshot: who is connected, counters, loop health."""

    engine_id: str = ""  # a new value each engine start
    estops: int = 0  # estop messages received (a client confirms its STOP by a state counting it)
    operator: str = ""  # name of the operator, "" when the role is free
    operator_silent: float = 0.0  # s since the operator's last message
    clients: int = 0
    viewers: list[str] = field(default_factory=list)  # names of the clients without the operator role
    rejected: int = 0
    dropped: int = 0
    auth_failures: int = 0
    rate: float = 0.0  # loop rate [Hz]
    realtime_factor: float = 1.0
    late_fraction: float = 0.0
    max_tick_ms: float = 0.0  # the longest tick of the last second [ms], from its start to the next tick's
    paused: bool = False  # the scene's time stands still (no client shows it); STOP still works


@dataclass(kw_only=True, slots=True)
class _Kinded:
    """The head of every snapshot and description: ``kind`` names the scene, and a scene's class fills it
    with its ``KIND`` when it is not given."""

    kind: str = ""

    KIND: ClassVar[str] = ""

    def __post_init__(self) -> None:
        if not self.kind:
            self.kind = self.KIND


@dataclass(kw_only=True, slots=True)
class Snapshot(_Kinded):
    """What every scene's state has, in the same place."""

    t: float = 0.0  # engine (simulated) time [s]
    estop: bool = False  # the scene's E-STOP latch
    describe_seq: int = 0  # the description this state belongs to; a client holding an older one asks again
    flags: InputFlags = field(default_factory=InputFlags)
    alarms: list[Alarm] = field(default_factory=list)
    engine: EngineInfo = field(default_factory=EngineInfo)


@dataclass(kw_only=True, slots=True)
class Description(_Kinded):
    """What every scene's static description has."""

    seq: int = 0  # increments whenever the description changes
    title: str = ""  # the scene as shown to a person
    commands: list[str] = field(default_factory=list)  # the scene's command table (protocol message types)


# ---------------------------------------------------------------------------------------------- teleop
@dataclass(kw_only=True, slots=True)
class ScalingState:
    k_p: list[float]  # position gains [m] (eq. 1)
    x_w: list[float]  # workspace offset [m] (eq. 1)
    k_v: list[float]  # velocity gains [m/s] (eq. 7)


@dataclass(kw_only=True, slots=True)
class HazardState:
    """The hazard nearest its stop this tick (issue 32, item 5: app/control/guard.py); none in its zone: kind ""."""

    kind: str = ""  # "", joint limit, singularity, collision
    name: str = ""  # as the operator reads it: "wrist_1 upper limit", "link 2 ↔ link 5", "link 3 ↔ floor"
    value: float | None = None  # clearance [m], σ ratio, or distance to the limit [rad | m]
    share: float | None = None  # share of its zone left: 1 at the zone's edge, 0 at the stop
    slowed: bool = False  # the command was scaled along the hazard's direction this tick
    text: str = ""  # one line: the hazard and its distance


@dataclass(kw_only=True, slots=True)
class StudyState:
    """The engine's IK study (``study_start``): results come once, in a ``study`` message."""

    id: int = 0
    kind: str = ""  # distribution | tracking
    status: str = "idle"  # idle, running, done, cancelled, failed
    done: int = 0
    total: int = 0
    error: str = ""


@dataclass(kw_only=True, slots=True)
class TeleopSnapshot(Snapshot):
    """One teleoperated serial arm (``bosun server``); points in the robot's world frame [m]."""

    KIND: ClassVar[str] = "teleop"
    tick: int = 0
    robot: str = ""
    solver: str = ""
    # the GA's task weighting in force (issue 32, item 4: set_ga_task): per-axis weights, tool axis and its weight
    ga_weights: list[float] = field(default_factory=lambda: [1.0, 1.0, 1.0])
    ga_axis: list[float] | None = None
    ga_axis_weight: float = 0.0
    mode: str = "position"
    frame: str = "world"  # the frame the stick commands in (issue 30, item 1)
    q: list[float] = field(default_factory=list)  # joint positions [rad | m]
    qdot: list[float] = field(default_factory=list)
    q_ref: list[float] = field(default_factory=list)
    tool: list[float] = field(default_factory=list)  # tool point
    target: list[float] = field(default_factory=list)  # the solver's target this tick
    command: list[float] | None = None  # the operator's command point; None while nothing is commanded
    frames: list[list[float]] = field(default_factory=list)  # origins of base, every DH frame and the tool
    signal: list[float] = field(default_factory=list)  # shaped input s in [-1, 1]^3
    solver_error: float | None = None  # [m]
    solver_time: float = 0.0  # [s]
    solver_ok: bool = True
    scaling: ScalingState | None = None
    hazard: HazardState = field(default_factory=HazardState)  # the direction-aware scaling's nearest hazard
    study: StudyState = field(default_factory=StudyState)


@dataclass(kw_only=True, slots=True)
class RobotEntry:
    """A robot the engine can drive, with the solvers that apply to it."""

    name: str
    joints: int
    solvers: list[str]
    description: str = ""


@dataclass(kw_only=True, slots=True)
class TeleopDescription(Description):
    KIND: ClassVar[str] = "teleop"
    robots: list[RobotEntry] = field(default_factory=list)  # the library, only what this engine drives
    robot: str = ""  # the loaded robot's name
    robot_xml: str = ""  # its robot file's text (the client draws and labels from it)
    solvers: list[str] = field(default_factory=list)  # solvers that apply to the loaded robot
    modes: list[str] = field(default_factory=list)
    joint_names: list[str] = field(default_factory=list)
    lower: list[float] = field(default_factory=list)  # joint limits [rad | m]
    upper: list[float] = field(default_factory=list)
    speed: list[float] = field(default_factory=list)  # joint speed limits [rad/s | m/s]
    box: list[list[float]] = field(default_factory=list)  # workspace box [lower, upper] [m]
    studies: list[str] = field(default_factory=list)  # studies the engine runs (``study_start`` kinds)


# ---------------------------------------------------------------------------------------------- crane head
@dataclass(kw_only=True, slots=True)
class SeaState:
    spectrum: str
    hs: float  # [m]
    tp: float  # [s]
    heading_deg: float  # wave heading [deg]: 0 following, 90 beam, 180 head sea
    seq: int = 0  # increments on every new sea


@dataclass(kw_only=True, slots=True)
class TacSample:
    """The crane-head simulation's latest step (TAC paper symbols)."""

    t: float
    eta: list[float]  # vessel pose in {n}: x, y, z [m], φ, θ, ψ [rad]
    beta: list[float]  # crane joints [rad]
    p_ref_t: list[float]  # compensating reference in {t} [m] (eqs. 49-56)
    p_c_t: list[float]  # head TCP in {t} [m]
    alpha_ref: list[float]  # Delta arm references [rad]
    alpha: list[float]  # Delta arm angles [rad]
    u: list[float]  # servo commands
    e_c: float  # compensation error [m] (eq. 61)
    e_s: float  # uncompensated error [m]
    saturated: bool
    p_c_n: list[float]  # TCP in {n} [m]
    p_s_n: list[float]  # the crane tip without compensation in {n} [m]


@dataclass(kw_only=True, slots=True)
class TacScenePoints:
    """Points in {n} for a drawing without the models (2D views, simple viewers) [m]."""

    ship: list[list[float]]  # the ship box's 8 corners
    crane: list[list[float]]  # crane joint origins, base to the head's base
    head: list[list[float]]  # the head's three knees and its TCP
    hook: list[float] = field(default_factory=list)  # the hanging load (issue 30, item 3); empty: none
    deck: list[list[float]] = field(default_factory=list)  # the target platform's deck corners (issue 30, item 5)


@dataclass(kw_only=True, slots=True)
class CraneLoadState:
    """The hanging load on its wire and its landing (issue 30, items 3 and 5) [m]: the crane's (``hook`` in {n}, NED)
    or the Motion-Lab's (``hook`` in the world {g}, z up; ``ahc``: the winch in MOTION_COMP)."""

    hook: list[float]  # the load in {n}
    wire_length: float  # [m]
    wire_speed: float  # [m/s], paying out positive
    swing_deg: float  # the wire's angle from the vertical
    tension_factor: float  # the wire's tension over the load's weight
    ahc: bool  # the winch's heave compensation on
    # the landing (issue 30, item 5): the deck below, when the load is over it
    clearance: float | None = None  # the load's height above the deck [m]; None: not over the deck
    rel_speed: float = 0.0  # the load's speed towards the deck [m/s]
    contact: bool = False  # the load touches the deck
    landed: bool = False  # it has touched down (until lifted clear again)
    rehits: int = 0  # contacts after the first of this landing
    swing_limit_deg: float = 5.0
    slack_factor: float = 0.1  # tension under this × static without the deck carrying the load: slack
    snap_factor: float = 1.5  # tension over this × static: a snap load
    antisway: bool = False  # the load's anti-swing law on (set_crane_antisway)
    antisway_offset: list[float] = field(default_factory=lambda: [0.0, 0.0])  # its offset of the TCP's target [m]
    # the load chart (issue 31, item 4; the crane's): this load in this sea against its SWL = rated capacity / ψ
    payload_t: float = 0.0  # the load's mass [t]
    radius: float | None = None  # the crane's radius [m]
    capacity_t: float | None = None  # the rated capacity there [t]; None: outside the crane's chart (or none)
    psi: float | None = None  # the dynamic factor seen: the wire's peak tension / weight over psi_window s
    psi_window: float = 0.0  # [s] of the window seen so far (up to the watch's window)
    swl_percent: float | None = None  # 100 · payload · ψ / capacity
    rated: bool = False  # the crane has a load chart (its robot file's <rated_capacity>)


@dataclass(kw_only=True, slots=True)
class LiftWindowState:
    """The lift-window indicator (issue 31, item 3): the crane tip's heave (over the target deck when the target
    is a vessel) predicted over the next ``step`` × (len − 1) s from the motion alone, as deviations from its mean
    [m] with σ, and the model's probability that it stays within ±``threshold`` for the next ``length`` s."""

    signal: str  # "heave" (the tip's) or "relative heave" (the tip's over the target deck)
    threshold: float  # [m], the operator's
    length: float  # [s]
    probability_min: float  # open when the probability is at least this
    step: float  # [s] between the points
    mean: list[float] = field(default_factory=list)  # empty while the predictor learns
    sigma: list[float] = field(default_factory=list)
    probability: float | None = None  # None while learning
    open: bool = False
    learning_s: float = 0.0  # seconds until the first fit


@dataclass(kw_only=True, slots=True)
class TacSnapshot(Snapshot):
    """Vessel, offshore crane and Delta crane head (``bosun server --plant tac``)."""

    KIND: ClassVar[str] = "tac"
    holding: bool = False  # after a reset: frozen until a compensation mode is chosen
    sea: SeaState | None = None
    tac_mode: str = "off"
    x_d: float = 0.0  # desired head centre on the head's x axis [m]
    p_d_n: list[float] = field(default_factory=list)  # desired TCP in {n} [m]
    load: CraneLoadState | None = None  # the hanging load (issue 30, item 3)
    hazard: HazardState = field(default_factory=HazardState)  # what the stick's command was scaled for (issue 32)
    target: str = "platform"  # the landing target: the fixed platform or a second vessel's deck (issue 30, item 5)
    frame: str = "world"  # the stick's frame: world, or target (following the target deck)
    target_age: float | None = None  # the second vessel's motion data age [s] (None: a fixed platform)
    target_lost: bool = False  # its data older than the engine's limit: the TCP holds in the world
    delay: float = 0.0  # s: the measurement-to-actuation delay (issue 31: set_tac_delay)
    predict: bool = False  # the motion predicted ``delay`` ahead fed instead of the late measurement
    lift: LiftWindowState | None = None  # the lift-window indicator (issue 31, item 3)
    sample: TacSample | None = None
    scene: TacScenePoints | None = None


@dataclass(kw_only=True, slots=True)
class ShipBox:
    """The vessel drawn as a box in its body frame {b} (x forward, y starboard, z down) [m]."""

    length: float
    beam: float
    deck_z: float
    keel_z: float


@dataclass(kw_only=True, slots=True)
class WaveField:
    """The sea's components: ζ(x, y, t) = Σ a cos(ω t − k (x cos μ + y sin μ) + φ) in {n} (app/marine/waves.py)."""

    amplitude: list[float]  # [m]
    omega: list[float]  # [rad/s]
    k: list[float]  # wave numbers [rad/m]
    heading_rad: list[float]  # each component's direction μ [rad]
    phase: list[float]  # φ [rad]


@dataclass(kw_only=True, slots=True)
class Hull:
    points: list[list[float]]  # workspace hull vertices in the head frame {t} [m]
    faces: list[list[int]]


@dataclass(kw_only=True, slots=True)
class TacDescription(Description):
    KIND: ClassVar[str] = "tac"
    crane_xml: str = ""  # the offshore crane's robot file
    head_xml: str = ""  # the Delta head's robot file
    vessel: str = ""  # the vessel model (name)
    vessels: list[str] = field(default_factory=list)  # the vessels the engine knows by name (set_vessel, issue 17)
    ship: ShipBox | None = None
    alpha_limits: list[float] = field(default_factory=list)  # Delta arm limits [rad]
    hull: Hull | None = None
    sea: SeaState | None = None
    waves: WaveField | None = None
    modes: list[str] = field(default_factory=list)
    spectra: list[str] = field(default_factory=list)


# ---------------------------------------------------------------------------------------------- Motion-Lab
@dataclass(kw_only=True, slots=True)
class PlatformState:
    name: str
    status: str  # settled, neutral, engaged, holding, or a transition
    mode: str
    source: str
    source_info: dict[str, Any]
    eta: list[float]  # pose [m, rad]
    eta_dot: list[float]
    legs: list[float]  # six leg lengths [m]
    leg_clamped: bool
    ramp: float  # 0..1
    motion: MotionStatus | None = None  # the Stewart status word as the Rexroth controller reports it (issue 16)


@dataclass(kw_only=True, slots=True)
class ComauState:
    mode: str  # settled, remote, motion_comp, hold
    q: list[float]  # [rad]
    qd: list[float]  # [rad/s]
    at_limit: list[bool]


@dataclass(kw_only=True, slots=True)
class WinchState:
    mode: str
    length: float  # wire length [m]
    speed: float  # [m/s]
    speed_command: float  # [m/s]


@dataclass(kw_only=True, slots=True)
class PendulumState:
    alpha: float  # swing angles of eqs. (29)-(30) [rad]
    beta: float
    swing: float  # total swing [rad]


@dataclass(kw_only=True, slots=True)
class LabScenePoints:
    """World-frame {g} points of the lab for drawing [m]."""

    platforms: dict[str, dict[str, list[list[float]]]]  # per platform: ``base`` and ``top`` leg ends (6 × 3)
    robot: list[list[float]]  # the Comau's joint origins, base to tool, no point repeated
    tool: list[float]
    payload: list[float]
    work_point: list[float]
    robot_frames: list[list[list[float]]] = field(default_factory=list)  # its frames (SerialRobot.frames), 4 × 4 each


@dataclass(kw_only=True, slots=True)
class PlantLink:
    """The lab's plant backend and, for ``plc``, the link to the TwinCAT PLC (docs/protocol.md)."""

    backend: str = "simulated"  # simulated | plc
    target: str = ""  # the PLC: "AMS_NET_ID:PORT at HOST"
    link: str = "simulated"  # simulated | connecting | ok | stale | invalid | lost
    connected: bool = False  # the ADS connection is up (always true when simulated)
    plc_state: str = ""  # MAIN.eState by name (NORMAL, STOP, …), "" before the first value
    ads_state: int = 0  # the PLC's ADS state (5: RUN), 0 before the first
    plc_error: str = ""  # what the PLC reports wrong (main state, a platform WARNING/ERROR), one line; "" if nothing
    last_error: str = ""  # the link's last error, one line
    reconnects: int = 0  # connections made after the first
    data_age: float = -1.0  # s since the last value from the PLC (-1: none yet)
    stop_written: bool = False  # MAIN.bStop read back TRUE on this connection after Bosun wrote it
    problems: list[str] = field(default_factory=list)  # symbols missing or of another size (never used)
    devices: dict[str, dict[str, Any]] = field(
        default_factory=dict
    )  # per device (em8000, comau, mru1 …) its PLC states
    # issue 27: values refused as they arrived (not finite, or beyond the machine's physical range), one line per
    # symbol with the age of the last valid value, which is held; and why motion commands are refused ("": taken)
    invalid: list[str] = field(default_factory=list)
    motion_refused: str = ""


# issue 16, item 5 (the lab HMI's status feedback, lights, jog and generator): optional fields
@dataclass(kw_only=True, slots=True)
class MotionStatus:
    """A platform's Rexroth motion status word (E_StewartState bits 0–3, E_StewartStatus 4–7, E_StewartOpMode
    24–31; motionlab_plc.json), by name: from the PLC, or made by the simulated plant from its own state."""

    state: str = ""  # TRANSIT, OFF, SETTLED, OIL_HEATING, NEUTRAL, NEUTRAL_FREEZE, ENGAGED, ENGAGED_FREEZE
    status: str = ""  # SYSTEM_OK, WARNING, ERROR
    opmode: str = ""  # MANUAL, NORMAL
    word: int = 0  # the status word itself (txHmi.status)


@dataclass(kw_only=True, slots=True)
class MachineLight:
    """One of the lab HMI's "Machine and Sensor States" lights (em8000, em1500, comau, mru1, mru2, tracker,
    remote)."""

    name: str
    state: str  # active | inactive (a device that should talk and does not) | absent (not connected) | unknown
    detail: str = ""  # one line: where the state comes from


@dataclass(kw_only=True, slots=True)
class ComauJog:
    """The Comau's joint jog (``lab_comau_jog``) as the engine applies it."""

    joint: int = 0  # 1–3 (q1–q3) while jogging, 0 when not
    speed: float = 0.0  # fraction of the profile's joint speed, −1…1
    qd: float = 0.0  # the joint speed commanded [rad/s]
    reason: str = ""  # why the last jog stopped or was refused, one line ("" when none)


@dataclass(kw_only=True, slots=True)
class SineGenerator:
    """The lab HMI's sine generator for one platform: its defaults and field ranges (motionlab_plc.json)."""

    amplitude: list[float]  # default amplitudes [m, rad]; their range is the operational box
    frequency: list[float]  # default frequencies [Hz]
    phase: list[float]  # default phases [rad]
    frequency_range: list[float]  # min, max, step [Hz]
    phase_range: list[float]  # min, max, step [rad]


@dataclass(kw_only=True, slots=True)
class SwingState:
    """The load-swing estimator and anti-swing law (``lab_antisway``, issue 16 item 4; the lab HMI's "Pendel
    Estimator" tab): the EKF's estimate of eqs. (29)-(30), its 1-σ, the law's tool offset."""

    active: bool  # the anti-swing law adds its offset to the Comau's work point
    measurement: str  # what updates the EKF: ``angles`` (a wire-angle sensor) | ``payload`` (the load's position)
    estimate: list[float]  # α, β [rad], α̇, β̇ [rad/s]
    sigma: list[float]  # the estimate's 1-σ from the EKF's covariance, same units
    error: list[float] | None = None  # estimate − true (a simulated lab knows the truth; None on the real one)
    nees: float | None = None  # normalised estimation error squared (χ² with 4 degrees of freedom)
    nis: float = 0.0  # the last update's normalised innovation squared
    offset: list[float] = field(default_factory=lambda: [0.0, 0.0])  # the law's tool offset in {d} x, y [m]
    saturated: bool = False  # the law's output at its acceleration or offset limit
    damping: float = 0.0  # c of eqs. (29)-(30) the estimator assumes [1/s]
    design_length: float = 0.0  # the wire length the LQR was designed at [m] (scheduled over the wire length)
    design_damping: float = 0.0  # the damping c of the LQR's design [1/s] (the lab's 0.1)
    design_step: float = 0.0  # the LQR's sample time [s] (the lab's 5 ms)
    reason: str = ""  # why the law is off or was switched off, one line ("" when none)


@dataclass(kw_only=True, slots=True)
class LabSnapshot(Snapshot):
    """The Norwegian Motion-Laboratory (``bosun server --plant lab``)."""

    KIND: ClassVar[str] = "lab"
    platforms: list[PlatformState] = field(default_factory=list)
    comau: ComauState | None = None
    winch: WinchState | None = None
    pendulum: PendulumState | None = None
    vvmc: bool = False
    delay: float = 0.0  # s: the simulated measurement-to-actuation delay (issue 31: set_lab_delay)
    predict: bool = False  # the motion predicted over that delay is fed instead
    frame: str = "base"  # the stick's frame: base (REMOTE), target or world (VVMC on)
    tool_error_b2: list[float] = field(default_factory=list)  # tool − work point in EM1500's body frame [m]
    payload_height_error: float = 0.0  # [m]
    scene: LabScenePoints | None = None
    plant: PlantLink | None = None  # the plant backend and its link (optional: older engines have none)
    machines: list[MachineLight] = field(default_factory=list)  # the lab HMI's machine and sensor lights (item 5)
    comau_jog: ComauJog | None = None  # the Comau's joint jog (item 5)
    swing: SwingState | None = None  # the load-swing estimator and anti-swing (item 4; None: not available)
    load: CraneLoadState | None = None  # the load on its wire and its landing on EM1500 (issue 30; hook in {g})
    hazard: HazardState = field(default_factory=HazardState)  # the work point's range edge near (issue 32)


@dataclass(kw_only=True, slots=True)
class PlatformInfo:
    name: str
    robot_xml: str  # the platform's robot file
    leg_range: list[float]  # [min, max] leg length [m]
    pose_min: list[float]  # pose box [m, rad]: Table 8, the hard limit
    pose_max: list[float]
    spectrum: dict[str, list[float]] | None = None  # the simulated sea's S(ω): ``omega`` [rad/s], ``s`` [m²s]
    command_min: list[float] | None = None  # the operational box every command is clipped to [m, rad] (issue 16)
    command_max: list[float] | None = None
    settled: list[float] | None = None  # the SETTLED pose (all legs at their minimum length) [m, rad]
    generator: SineGenerator | None = None  # the lab HMI's sine-generator defaults and ranges (issue 16, item 5)


@dataclass(kw_only=True, slots=True)
class WinchInfo:
    min: float  # wire length limits [m]
    max: float
    speed_max: float  # [m/s]


@dataclass(kw_only=True, slots=True)
class LabDescription(Description):
    KIND: ClassVar[str] = "lab"
    lab_xml: str = ""  # the lab layout file
    platforms: list[PlatformInfo] = field(default_factory=list)
    comau_xml: str = ""
    comau_lower: list[float] = field(default_factory=list)  # [rad]
    comau_upper: list[float] = field(default_factory=list)
    comau_speed: list[float] = field(default_factory=list)  # [rad/s]
    comau_profile: str = ""  # the joint-limit profile in force (``lab``, ``datasheet``, …; issue 16)
    comau_profiles: list[str] = field(default_factory=list)  # the profiles the layout offers
    comau_accel: float | None = None  # joint acceleration limit [rad/s²]
    comau_boundary_accel: float | None = None  # A of the velocity bound √(2 A d) at the joint limits [rad/s²]
    winch: WinchInfo | None = None
    sources: list[str] = field(default_factory=list)
    spectra: list[str] = field(default_factory=list)
    backend: str = "simulated"  # the plant backend: simulated | plc
    vessel: str = ""  # the wave simulator's vessel model ("" over the PLC; issue 17, item 2)
    vessels: list[str] = field(default_factory=list)  # the vessels the engine knows by name (set_vessel)
    comau_jog_timeout: float | None = None  # a jog speed not refreshed this long returns to zero [s] (item 5)


SNAPSHOTS: dict[str, type[Snapshot]] = {c.KIND: c for c in (TeleopSnapshot, TacSnapshot, LabSnapshot)}
DESCRIPTIONS: dict[str, type[Description]] = {c.KIND: c for c in (TeleopDescription, TacDescription, LabDescription)}


# ---------------------------------------------------------------------------------------------- wire
def to_wire(obj: Any) -> Any:
    """A dataclass (nested) as plain maps and lists for msgpack; numbers stay numbers."""
    if dataclasses.is_dataclass(obj):
        return {f.name: to_wire(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, list | tuple):
        return [to_wire(v) for v in obj]
    if isinstance(obj, dict):
        return {k: to_wire(v) for k, v in obj.items()}
    return obj


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _convert(tp: Any, value: Any, where: str) -> Any:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None:
            if type(None) in args:
                return None
            raise SnapshotError(f"{where}: missing value")
        options = [a for a in args if a is not type(None)]
        if len(options) == 1:  # X | None: X's own message says what is wrong
            return _convert(options[0], value, where)
        for a in options:
            try:
                return _convert(a, value, where)
            except SnapshotError:
                continue
        raise SnapshotError(f"{where}: {type(value).__name__} does not fit {tp}")
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, dict):
            raise SnapshotError(f"{where}: expected a map, got {type(value).__name__}")
        return _build(tp, value, where)
    if origin is list:
        if not isinstance(value, list | tuple):
            raise SnapshotError(f"{where}: expected a list, got {type(value).__name__}")
        (item,) = typing.get_args(tp) or (Any,)
        return [_convert(item, v, f"{where}[{i}]") for i, v in enumerate(value)]
    if origin is dict:
        if not isinstance(value, dict):
            raise SnapshotError(f"{where}: expected a map, got {type(value).__name__}")
        _, item = typing.get_args(tp) or (str, Any)
        return {k: _convert(item, v, f"{where}.{k}") for k, v in value.items()}
    if tp is Any:
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise SnapshotError(f"{where}: expected a number, got {type(value).__name__}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise SnapshotError(f"{where}: expected an integer, got {type(value).__name__}")
        return value
    if tp is bool or tp is str:
        if not isinstance(value, tp):
            raise SnapshotError(f"{where}: expected {tp.__name__}, got {type(value).__name__}")
        return value
    raise SnapshotError(f"{where}: unsupported type {tp}")  # a bug in this module's classes


def _build(cls: type, data: dict[str, Any], where: str) -> Any:
    hints = _hints(cls)
    kwargs = {}
    for f in dataclasses.fields(cls):
        if f.name in data:
            kwargs[f.name] = _convert(hints[f.name], data[f.name], f"{where}.{f.name}")
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise SnapshotError(f"{where}: missing field {f.name!r}")
    return cls(**kwargs)


def _from_wire(table: dict[str, type], data: Any, what: str) -> Any:
    if not isinstance(data, dict):
        raise SnapshotError(f"{what} is not a map")
    kind = data.get("kind")
    cls = table.get(kind) if isinstance(kind, str) else None
    if cls is None:
        raise SnapshotError(f"{what} of unknown kind {kind!r} (known: {', '.join(table)})")
    return _build(cls, data, kind)


def snapshot_from_wire(data: Any) -> Snapshot:
    """The typed snapshot of a ``state`` message's map; :class:`SnapshotError` if it does not fit."""
    return _from_wire(SNAPSHOTS, data, "state")


def description_from_wire(data: Any) -> Description:
    """The typed description of a ``describe`` message's map; :class:`SnapshotError` if it does not fit."""
    return _from_wire(DESCRIPTIONS, data, "description")
