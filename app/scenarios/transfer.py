"""The compensated lift (issue 30, item 6): an operator moves a load from the supply vessel's crane onto a deck
while the machine cancels the sea (and, in ``antisway``, the swing) — ``bosun sim transfer``.

The crane scene's blocks, wired per step of ``dt`` (0.01 s):

* the vessel, crane and Delta head (:class:`~app.scenarios.tac.TacSimulator`), cooperative: the operator's
  horizontal move sets the crane's nominal configuration β_d (the crane's inverse kinematics of eqs. 42–44 at the
  commanded point in calm water) and the TCP's target p_d^n (the hook's commanded point in the target frame, seen in
  the world now); the crane and head share the compensation around it (§8);
* the winch and the load (:class:`~app.scenes.crane_load.CraneLoad`): the winch's heave compensation holds the
  hook's commanded height (the operator's lift and lowering, and, for a vessel target, the deck's heave), the load
  hangs on its elastic wire (:data:`app.sim.load.LOAD`) and lands on the deck;
* in ``antisway`` the lab's estimator and LQR (:data:`app.control.antisway.SWING_CONTROL`), reused: the TCP's
  measured acceleration and the wire's measured angles in, an offset of the TCP's target out.

``off`` is the same operator without compensation: the crane follows the operator's move in the vessel's frame
(β_d as above, the head held at p_d^t), so the TCP rides the vessel, and the winch pays out only what the operator
commands.

The target deck is a plane: a fixed platform (horizontal, still) or a second vessel's deck (its own RAO table and
heading in the same sea: the components' directions turned into its frame and their phases moved to its place,
:class:`TargetVessel`).  The target frame moves with the deck's landing spot (its origin) and keeps level axes, the
world's (:meth:`TargetVessel.deck` says why).

The scripted operator (:class:`ScriptedOperator`), the reference: hold 10 s, lift 1 m at the lowering speed, move
10 m along x of the target frame at 0.5 m/s with 0.25 m/s² ramps, wait 10 s (the residual swing is measured
there), lower at 0.2 m/s until the load touches the deck, pay out 0.5 m of slack and hold 10 s.  The deck is 2 m
below the load's starting height.  ``--operator FILE`` replays a recorded stick instead (:class:`StickFile`).
"""

from __future__ import annotations

import copy
import csv
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from app.errors import BosunError
from app.marine.waves import SPECTRA
from app.models import kernels as model_kernels
from app.models.pendulum import G
from app.scenarios.tac import TacScenario, TacSimulator
from app.scenes import crane_transfer_kernels as ck
from app.scenes import lab_transfer_kernels as lt
from app.scenes.crane_load import (
    NOISE,
    SIDEWAYS_SPEED,
    SLACK_FACTOR,
    SNAP_FACTOR,
    CraneLoad,
    CraneSwingControl,
    LandingWatch,
)  # fmt: skip
from app.scenes.load_lead import CRANE_LEAD_MAX, LoadLead
from app.scenes.target_deck import TargetVessel

__all__ = [
    "MODES", "SLACK_FACTOR", "SNAP_FACTOR", "TARGETS", "ScriptedOperator", "StickFile", "TransferError",
    "TransferScenario", "landing_statistics", "landings", "simulate",
]  # fmt: skip

MODES = ("off", "compensated", "antisway")
TARGETS = ("platform", "vessel")
SCENES = ("crane", "lab")
LAB_MOVE_MAX = 1.0  # m: the Comau's reach across EM1500 (app.scenarios.lab_transfer)
#: the Motion-Lab's transfer (issue 30, item 6, "lab: 1 m … 0.05 m/s"): sim vvmc's sea and vessels (EM8000's at 150°,
#: EM1500's at 90°), the PLC's 5 ms step, a 0.2 m lift, 1 m across at 0.1 m/s (0.1 m/s² ramps), lowered at 0.05 m/s
LAB_DEFAULTS = {
    "hs": 2.0, "tp": 8.0, "heading": 150.0, "target": "em1500", "target_heading": 90.0, "dt": 0.005, "lift": 0.2,
    "move": 1.0, "move_speed": 0.1, "move_accel": 0.1, "lower_speed": 0.05, "slack": 0.05,
}  # fmt: skip
TCP_SPEED = 0.5  # m/s at full stick, horizontally (app.engine.tac_session: the crane-head scene's)
WINCH_SPEED = 1.0  # m/s at full stick on w
CHUNK = 2  # steps the crane and head advance with the TCP's target held (the crane-head engine's 50 Hz tick)
T_MAX = 1800.0  # s: a run ends by then whatever the operator does
#: the load lead (:class:`app.scenes.load_lead.LoadLead`): at most CRANE_LEAD_MAX, faded in over the first
#: LEAD_FADE s (the quintic of H108)
LEAD_FADE = 5.0
LEAD_BLOCK = 1000  # steps of the deck's accelerations evaluated at once
LEVEL = np.eye(3)  # the target frame's axes: the world's (app.scenes.target_deck.TargetVessel.deck)


class TransferError(BosunError):
    """A bad transfer setting or stick file (names it)."""


@dataclass(frozen=True)
class TransferScenario:
    """One transfer: the sea, the vessels, the target and the mode; angles in degrees at this edge."""

    scene: str = "crane"  # or "lab" (the Motion-Lab: build it with for_scene, whose defaults are the lab's)
    hs: float = 3.0
    tp: float = 9.0
    heading: float = 90.0  # wave heading relative to the supply vessel [deg]
    spectrum: str = "jonswap"
    seed: int = 1
    rao: str | None = None  # the supply vessel (None: the default vessel)
    target: str = "platform"
    target_rao: str | None = None  # the second vessel (None: the same vessel as the crane's)
    target_heading: float = 60.0  # wave heading relative to the second vessel [deg]
    mode: str = "compensated"
    dt: float = 0.01
    n_freq: int = 200
    operator: str = "scripted"  # or a stick file (CSV: t, x, y, z, w)
    lift: float = 1.0  # m
    move: float = 10.0  # m along x of the target frame
    move_speed: float = 0.5  # m/s
    move_accel: float = 0.25  # m/s²
    lower_speed: float = 0.2  # m/s
    deck_drop: float = 2.0  # the deck this far below the load's starting height [m]
    slack: float = 0.5  # paid out after touchdown [m]
    wait: float = 10.0  # s before the lift, after the move, and after the set-down
    sensor_noise: bool = True  # the anti-swing sees the TCP's acceleration and the wire's angles with noise
    lead: bool = True  # compensation leads the target's motion so the hanging load follows it (the load lead)

    @classmethod
    def for_scene(cls, scene: str = "crane", **values) -> TransferScenario:
        """A scenario of ``scene`` (crane or lab) with that scene's defaults (:data:`LAB_DEFAULTS` for the lab)
        under ``values``; None values take the default."""
        if scene not in SCENES:
            raise TransferError(f"scene must be one of {', '.join(SCENES)}, got {scene!r}")
        given = {k: v for k, v in values.items() if v is not None}
        return cls(scene=scene, **{**(LAB_DEFAULTS if scene == "lab" else {}), **given})

    def __post_init__(self) -> None:
        lab = self.scene == "lab"
        targets = ("em1500",) if lab else TARGETS
        checks = [
            (self.scene in SCENES, f"scene must be one of {', '.join(SCENES)}, got {self.scene!r}"),
            (self.mode in MODES, f"mode must be one of {', '.join(MODES)}, got {self.mode!r}"),
            (
                self.target in targets,
                f"{self.scene}: the target must be one of {', '.join(targets)}, "
                f"got {self.target!r}" + (" (the lab lands on EM1500's deck)" if lab else ""),
            ),
            (self.spectrum in SPECTRA, f"spectrum must be one of {', '.join(SPECTRA)}, got {self.spectrum!r}"),
            (math.isfinite(self.hs) and 0 < self.hs <= 15, f"hs must be in (0, 15] m, got {self.hs}"),
            (math.isfinite(self.tp) and 2 <= self.tp <= 30, f"tp must be in [2, 30] s, got {self.tp}"),
            (math.isfinite(self.heading) and math.isfinite(self.target_heading), "headings must be numbers"),
            (math.isfinite(self.dt) and 0 < self.dt <= 0.02, f"dt must be in (0, 0.02] s, got {self.dt}"),
            (0 < self.move_speed <= 1.5, f"move speed must be in (0, 1.5] m/s, got {self.move_speed}"),
            (0 < self.move_accel <= 2, f"move accel (--move-accel) must be in (0, 2] m/s², got {self.move_accel:g}"),
            (0 < self.lower_speed <= 1.0, f"lowering speed must be in (0, 1] m/s, got {self.lower_speed}"),
            (0 <= self.move <= 10.0, f"move must be in [0, 10] m (the cooperative range), got {self.move}"),
            (0 <= self.lift <= 3.0 and 0.5 <= self.deck_drop <= 10.0, "lift in [0, 3] m, deck drop in [0.5, 10] m"),
        ]
        if lab:  # the Motion-Lab's reach: the Comau's tool speed in REMOTE, the winch's speed, the reachable move
            checks += [
                (self.move <= LAB_MOVE_MAX, f"lab: move must be in [0, {LAB_MOVE_MAX:g}] m, got {self.move}"),
                (self.move_speed <= 0.25, f"lab: move speed at most 0.25 m/s (the Comau's), got {self.move_speed}"),
                (self.lower_speed <= 0.2, f"lab: lowering speed at most 0.2 m/s (the winch's), got {self.lower_speed}"),
                (self.lift <= 0.5, f"lab: lift at most 0.5 m, got {self.lift}"),
                (self.dt <= 0.01, f"lab: dt at most 0.01 s, got {self.dt}"),
            ]
        for ok, msg in checks:
            if not ok:
                raise TransferError(msg)

    def to_dict(self) -> dict:
        return asdict(self)


# ----------------------------------------------------------------------------- operators
@dataclass
class ScriptedOperator:
    """The reference operator (module text).  :meth:`command` gives the hook's commanded velocity in the target
    frame (NED axes: z down) and the phase, from the time and whether the load has touched down."""

    sc: TransferScenario
    axis: int = 0  # the move's axis in the target frame (the crane's x; the lab's y of EM1500's frame)
    phase: str = "wait"
    _t_phase: float = 0.0
    _moved: float = 0.0
    _v: float = 0.0
    _paid: float = 0.0
    done: bool = False
    move_end: float | None = None

    def command(self, t: float, dt: float, touched: bool) -> NDArray[np.float64]:
        sc, v = self.sc, np.zeros(3)
        if self.phase == "wait" and t - self._t_phase >= sc.wait:
            self._next("lift", t)
        if self.phase == "lift" and not self._pay(v, -1.0, sc.lift, dt):
            self._next("move", t)
        if self.phase == "move":
            left = sc.move - self._moved
            brake = self._v * self._v / (2 * sc.move_accel)
            a = -sc.move_accel if left <= brake + 1e-9 else sc.move_accel
            self._v = min(max(self._v + a * dt, 0.0), sc.move_speed)
            if left <= 1e-9 or (self._v == 0.0 and a < 0):
                self._v = 0.0
                self.move_end = t
                self._next("settle", t)
            else:
                step = min(self._v * dt, left)
                self._moved += step
                v[self.axis] = step / dt
        if self.phase == "settle" and t - self._t_phase >= sc.wait:
            self._next("lower", t)
        if self.phase == "lower":
            if touched:
                self._paid = 0.0
                self._next("set_down", t)
            else:
                v[2] = sc.lower_speed
        if self.phase == "set_down" and not self._pay(v, 1.0, sc.slack, dt):
            self._next("hold", t)
        if self.phase == "hold" and t - self._t_phase >= sc.wait:
            self.done = True
        return v

    def _next(self, phase: str, t: float) -> None:
        self.phase, self._t_phase = phase, t

    def _pay(self, v: NDArray[np.float64], sign: float, total: float, dt: float) -> bool:
        """The winch's step of a lift (``sign`` −1, up) or a set-down (+1) of ``total`` metres at the lowering speed
        into ``v``; False once the whole distance is paid."""
        if self._paid >= total - 1e-9:
            return False
        step = min(self.sc.lower_speed * dt, total - self._paid)
        self._paid += step
        v[2] = sign * step / dt
        return True


@dataclass
class StickFile:
    """A recorded stick replayed (``--operator FILE``): a CSV with a header ``t,x,y,z,w`` (s, and the profile's
    axes in [−1, 1]: x, y horizontal, z up, w the winch, paying out positive), sampled at any rate and held
    between samples.  x and y move the hook at up to 0.5 m/s in the target frame, z and w raise it and lower it
    (at up to 0.5 and 1 m/s: the crane-head scene's stick).  The run lasts the file's time."""

    t: NDArray[np.float64]
    axes: NDArray[np.float64]
    speeds: tuple[float, float, float] = (TCP_SPEED, TCP_SPEED, WINCH_SPEED)  # m/s at full stick: x and y, z, w
    phase: str = "replay"
    done: bool = False
    move_end: float | None = None

    @classmethod
    def read(cls, path: str | Path, speeds: tuple[float, float, float] | None = None) -> StickFile:
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as err:
            raise TransferError(f"{path}: cannot read the stick file ({err})") from None
        rows = list(csv.reader(text.splitlines()))
        if not rows or [c.strip().lower() for c in rows[0]] != ["t", "x", "y", "z", "w"]:
            raise TransferError(f"{path}, line 1: the header must be t,x,y,z,w")
        t, axes = [], []
        for i, row in enumerate(rows[1:], start=2):
            if not row or not any(c.strip() for c in row):
                continue
            if len(row) != 5:
                raise TransferError(f"{path}, line {i}: 5 fields expected (t,x,y,z,w), got {len(row)}")
            try:
                vals = [float(c) for c in row]
            except ValueError:
                raise TransferError(f"{path}, line {i}: not a number in {','.join(row)!r}") from None
            if not all(math.isfinite(v) for v in vals):
                raise TransferError(f"{path}, line {i}: a value is not finite")
            if any(abs(v) > 1.0 for v in vals[1:]):
                raise TransferError(f"{path}, line {i}: stick axes must be within [-1, 1]")
            if t and vals[0] <= t[-1]:
                raise TransferError(f"{path}, line {i}: t must increase ({vals[0]:g} after {t[-1]:g})")
            t.append(vals[0])
            axes.append(vals[1:])
        if len(t) < 2:
            raise TransferError(f"{path}: at least two samples are needed")
        return cls(np.array(t), np.array(axes), *(() if speeds is None else (tuple(speeds),)))

    def command(self, t: float, dt: float, touched: bool) -> NDArray[np.float64]:
        if t >= self.t[-1]:
            self.done = True
            return np.zeros(3)
        k = max(0, int(np.searchsorted(self.t, t, side="right")) - 1)
        x, y, z, w = self.axes[k]
        v_xy, v_z, v_w = self.speeds
        return np.array([v_xy * x, v_xy * y, -v_z * z + v_w * w])


# ----------------------------------------------------------------------------- the run
@dataclass
class TransferResult:
    scenario: TransferScenario
    columns: list[str]
    rows: NDArray[np.float64]
    phases: list[str]
    summary: dict = field(default_factory=dict)


COLUMNS = (
    "t", "cmd_x", "cmd_y", "cmd_z", "load_x", "load_y", "load_z", "error_m", "tcp_n_x", "tcp_n_y", "tcp_n_z",
    "deck_n_x", "deck_n_y", "deck_n_z", "gap_m", "rel_speed_mps", "swing_deg", "tension_factor", "contact_kN",
    "wire_m", "antisway_x", "antisway_y",
)  # fmt: skip


def simulate(sc: TransferScenario, progress=None, cancel=None, compiled: bool = True) -> TransferResult:
    """One transfer (module text); ``progress(t, t_max)`` now and then, ``cancel()`` True stops it.

    The crane and head advance :data:`CHUNK` steps at a time with the TCP's target held (the crane-head engine's
    50 Hz tick); the operator, the winch, the load, the deck and the anti-swing law step every ``dt``, each chunk's
    steps in one compiled call (:class:`_CraneSteps`) where the load is in the steady state it covers and numba is
    there, else through the objects (``compiled`` False: always, the reference)."""
    if sc.scene == "lab":
        from app.scenarios.lab_transfer import simulate_lab

        return simulate_lab(sc, progress, cancel, compiled=None if compiled else False)
    operator = StickFile.read(sc.operator) if sc.operator != "scripted" else ScriptedOperator(sc)
    tac = TacScenario(
        hs=sc.hs, tp=sc.tp, heading=sc.heading, spectrum=sc.spectrum, seed=sc.seed, rao=sc.rao, dt=sc.dt,
        n_freq=sc.n_freq, mode="off" if sc.mode == "off" else "cooperative", duration=T_MAX + 1.0,
    )  # fmt: skip
    sim = TacSimulator(tac)
    sim.lookahead = 500
    system = sim.system
    load = CraneLoad()
    load.ahc = sc.mode != "off"
    dt = sc.dt
    p0 = sim.p_d_n0.copy()  # the TCP in calm water; the load hangs below it
    start = load.hook(p0)  # where the load starts, in the world (calm water)
    landing = start + np.array([sc.move, 0.0, sc.deck_drop])
    vessel2 = None
    if sc.target == "vessel":
        vessel2 = TargetVessel(sc.target_rao, sc.target_heading, sim.vessel.sea, sc.heading, landing)
    up, eye = np.array([0.0, 0.0, -1.0]), np.eye(3)
    d, n_up, R_deck = (landing, up, eye) if vessel2 is None else vessel2.deck(0.0)
    cmd = R_deck.T @ (start - d)  # the hook's commanded point in the target frame (origin: the landing spot)
    rng = np.random.default_rng(sc.seed + 30_000)
    swing = CraneSwingControl(load, dt, rng, noise=sc.sensor_noise) if sc.mode == "antisway" else None
    offset = np.zeros(3)
    # the load lead (app.scenes.load_lead): compensating, the TCP leads a vessel target's spot; anti-swing, the
    # operator's move too
    lead = None
    if sc.lead and (sc.mode == "antisway" or (sc.mode == "compensated" and vessel2 is not None)):
        lead = LoadLead(dt, CRANE_LEAD_MAX, LEAD_FADE, shape=sc.mode == "antisway")
    lead_tcp, lead_ref, v_prev, zero = np.zeros(3), None, np.zeros(3), np.zeros(3)
    acc: list | None = None  # the deck spot's accelerations ahead: [t of the first, (LEAD_BLOCK, 3), next index]
    beta_hint, calm_prev = float(sim.beta_d[0]), None
    rows, phases = [], []
    watch = LandingWatch()
    slack_n = snap_n = sideways_n = 0
    fast = _CraneSteps(sc, load, watch, swing, lead, vessel2) if compiled and model_kernels.ENABLED else None
    t = 0.0
    d_prev = d
    while not operator.done and t < T_MAX:
        if cancel is not None and cancel():
            break
        # the crane follows the operator's move in calm water (β_d); compensating, the TCP's target is the hook's
        # commanded point in the world now (plus the anti-swing offset) at the TCP's height
        calm_n = landing + cmd  # the commanded point in calm water (the operator's x and y are the world's there)
        if calm_prev is None or calm_n[0] != calm_prev[0] or calm_n[1] != calm_prev[1]:
            sim.beta_d = system.crane_ik_tcp(np.array([[calm_n[0], calm_n[1], p0[2]]]), beta_hint)[0]
            beta_hint, calm_prev = float(sim.beta_d[0]), calm_n
        if sc.mode != "off":
            hook_cmd_n = d + R_deck @ cmd
            hook_cmd_n = hook_cmd_n + lead_tcp  # the load lead (zero without one)
            sim.p_d_n = np.array([hook_cmd_n[0] + offset[0], hook_cmd_n[1] + offset[1], p0[2]])
        c = sim.advance(CHUNK)
        tcps = c.p_s_n if sc.mode == "off" else c.p_c_n
        i0 = 0
        if fast is not None and fast.steady(R_deck):  # the chunk's steps compiled (app/scenes/crane_transfer_kernels)
            loop = {"cmd": cmd, "t": t, "d": d, "n_up": n_up, "d_prev": d_prev, "lead_tcp": lead_tcp,
                    "lead_ref": lead_ref, "v_prev": v_prev, "offset": offset, "acc": acc,
                    "counts": [slack_n, snap_n, sideways_n]}  # fmt: skip
            i0 = fast.chunk(tcps, operator, R_deck, loop, rows, phases)
            cmd, t, d, n_up, d_prev = loop["cmd"], loop["t"], loop["d"], loop["n_up"], loop["d_prev"]
            lead_tcp, lead_ref, v_prev = loop["lead_tcp"], loop["lead_ref"], loop["v_prev"]
            offset, acc = loop["offset"], loop["acc"]
            slack_n, snap_n, sideways_n = loop["counts"]
            if operator.done:
                i0 = len(tcps)
        for tcp in tcps[i0:]:
            v_cmd = operator.command(t, dt, watch.touched)
            cmd = cmd + v_cmd * dt
            t = t + dt
            if vessel2 is not None:  # the target deck at the step's end, and its velocity over the step
                d, n_up, R_deck = vessel2.deck(t)
            deck_v = (d - d_prev) / dt
            d_prev = d
            if lead is not None:  # the deck's spot and the operator's commanded point accelerate
                a_cmd = ((v_cmd[0] - v_prev[0]) / dt, (v_cmd[1] - v_prev[1]) / dt, 0.0)  # the target frame's
                a_spot = zero
                if vessel2 is not None:  # the deck's accelerations a block of steps at a time (one sea evaluation)
                    a_cmd = R_deck @ np.array(a_cmd)  # in the world
                    if acc is None or acc[2] >= acc[1].shape[0]:
                        acc = [t, vessel2.spot_accelerations(t + dt * np.arange(LEAD_BLOCK)), 0]
                    a_spot = acc[1][acc[2]]
                    acc[2] += 1
                lead_tcp, lead_ref = lead.step(a_spot, a_cmd, load.length)
                v_prev = v_cmd
            # the winch: compensating, it holds the hook's commanded height (its rate: the operator's and the
            # deck's); off, it pays out what the operator asks
            load.speed_command = float(v_cmd[2]) if sc.mode == "off" else float((R_deck @ v_cmd)[2] + deck_v[2])
            load.deck = (True, d, n_up, deck_v)
            load.step(tcp, dt)
            r = load.state[0]
            watch.step(load, deck_v, n_up)
            touched, rel_speed, ratio = watch.touched, watch.rel_speed, load.tension / load.static_tension()
            slack_n, snap_n, sideways_n = slack_n + watch.slack, snap_n + watch.snap, sideways_n + watch.sideways
            e = r - tcp
            ell = math.sqrt(float(e @ e))
            swing_deg = math.degrees(math.acos(min(1.0, max(-1.0, e[2] / ell))))
            if swing is not None:  # on the deck, or slack, the wire's angle is no swing
                offset = swing.step(e, ell, not touched and not watch.slack, lead_ref)
            load_t = r - d if vessel2 is None else R_deck.T @ (r - d)
            err = load_t - cmd
            row = (
                t, *cmd, *load_t, math.sqrt(float(err @ err)), *tcp, *d, load.gap, rel_speed, swing_deg, ratio,
                load.contact_force / 1e3, load.length, offset[0], offset[1],
            )  # fmt: skip
            rows.append(row)
            phases.append(operator.phase)
            if operator.done:
                break
        if progress is not None and len(rows) % 500 < CHUNK:
            progress(t, T_MAX)
    data = np.array(rows, dtype=float) if rows else np.zeros((0, len(COLUMNS)))
    res = TransferResult(sc, list(COLUMNS), data, phases)
    res.summary = summarise(res, operator, watch.touch_speed, watch.contacts, slack_n, snap_n, sideways_n)
    if swing is not None:
        res.summary["estimator_resets"] = swing.resets
    return res


class _CraneSteps:
    """A chunk's steps of :func:`simulate` in one call of :func:`app.scenes.crane_transfer_kernels.crane_steps`:
    the operator's commands, the target deck, its spot's accelerations and the sensors' noise worked out ahead; the
    objects (load, watch, swing law, lead, operator) left as the objects' own steps would leave them
    (tests/test_transfer.py runs both ways)."""

    def __init__(self, sc, load, watch, swing, lead, vessel2) -> None:
        self.sc, self.load, self.watch, self.swing, self.lead, self.vessel2 = sc, load, watch, swing, lead, vessel2
        self.P0 = swing._fresh()[0][1].copy() if swing is not None else np.eye(4)
        self.no_swing = ck.warm_up_records()[1] if swing is None else None

    def steady(self, R_deck) -> bool:
        """Whether the state is one :func:`crane_steps` covers: the load hanging with three TCP samples, heave
        compensation on or off (not fading, no E-STOP), one landing (no relift), the target's axes level."""
        load, dt = self.load, self.sc.dt
        fade, g_last = load._ahc
        want = 1.0 if load.ahc and not load.stopped else 0.0
        return (
            load.use_kernels is not False and load.state is not None and len(load._tcp) == 3 and not load.stopped
            and fade is None and want == g_last and not self.watch.relift
            and (self.lead is None or self.lead.dt == dt) and (self.swing is None or self.swing.dt == dt)
            and bool(np.array_equal(R_deck, LEVEL))
        )  # fmt: skip

    def _spot(self, acc, t: float):
        """The deck spot's acceleration at this step, from the block ahead (refilled as :func:`simulate` does)."""
        if acc is None or acc[2] >= acc[1].shape[0]:
            acc = [t, self.vessel2.spot_accelerations(t + self.sc.dt * np.arange(LEAD_BLOCK)), 0]
        a = acc[1][acc[2]]
        acc[2] += 1
        return acc, a

    def _noise(self, k: int) -> list:
        sw, out = self.swing, []
        for _ in range(k):
            if not sw._noise:  # as CraneSwingControl.step draws it
                sw._noise = list(sw.rng.normal(0.0, 1.0, (1000, 5)) * NOISE) if sw.noise else [np.zeros(5)] * 1000
            out.append(sw._noise.pop())
        return out

    def chunk(self, tcps, operator, R_deck, loop: dict, rows: list, phases: list) -> int:
        """The chunk's steps compiled (fewer if the load touched down: the operator sees it); the loop's values in
        ``loop`` updated; the number taken."""
        watch, swing, lead, vessel2, dt = self.watch, self.swing, self.lead, self.vessel2, self.sc.dt
        ahead, touched, t = copy.copy(operator), watch.touched, loop["t"]
        V, ph, D, N, A = [], [], [], [], []
        acc = None if loop["acc"] is None else list(loop["acc"])
        d, n_up = loop["d"], loop["n_up"]
        for _ in range(len(tcps)):
            V.append(ahead.command(t, dt, touched))
            ph.append(ahead.phase)
            t = t + dt
            if vessel2 is not None:
                d, n_up, _ = vessel2.deck(t)
                if lead is not None:
                    acc, a = self._spot(acc, t)
                    A.append(a)
            D.append(d)
            N.append(n_up)
            if ahead.done:
                break
        k = len(V)
        W = self._noise(k) if swing is not None else []
        f = np.ascontiguousarray
        given = (
            f(V, dtype=float), f(tcps[:k], dtype=float), f(D, dtype=float), f(N, dtype=float),
            f(A, dtype=float) if A else np.zeros((k, 3)), f(W, dtype=float) if W else np.zeros((k, 5)),
        )  # fmt: skip
        records, s = self._records(R_deck, loop)
        out = np.empty((k, len(COLUMNS)))
        taken = ck.crane_steps(*records, given, out, s)
        self._write_back(s, records, loop, given, taken)
        if taken == k:
            operator.__dict__.update(ahead.__dict__)
            loop["acc"] = acc
        else:  # the operator and the spot's block again up to where the steps stopped
            again, t, acc = copy.copy(operator), loop["t0"], loop["acc"]
            for _ in range(taken):
                again.command(t, dt, touched)
                t = t + dt
                if vessel2 is not None and lead is not None:
                    acc, _ = self._spot(acc, t)
            operator.__dict__.update(again.__dict__)
            loop["acc"] = acc
            for w in W[taken:][::-1]:
                swing._noise.append(w)
        rows.extend(out[:taken])
        phases.extend(ph[:taken])
        return taken

    def _records(self, R_deck, loop: dict) -> tuple[tuple, np.ndarray]:
        sc, load, watch, swing, lead = self.sc, self.load, self.watch, self.swing, self.lead
        r, v = load.state
        load_rec = (
            r, v, load.drum, load._drum_p, load._load_p, np.array(load._tcp, dtype=float),
            np.array(load.tcp_v, dtype=float), np.array(load.tcp_a, dtype=float), np.zeros(3),
            np.array(loop["d_prev"], dtype=float),
        )  # fmt: skip
        if swing is not None:
            x = swing.x
            swing_rec = (*x[:7], swing.record, self.P0)
        else:
            swing_rec = self.no_swing
        ref = loop["lead_ref"]
        lead_rec = (
            np.array(loop["lead_tcp"], dtype=float),
            (np.zeros(3), np.zeros(3)) if ref is None else tuple(np.array(a, dtype=float) for a in ref),
            np.array(loop["v_prev"], dtype=float),
        )  # fmt: skip
        flags = (
            sc.mode == "off", self.vessel2 is not None, lead is not None, lead is not None and lead.shape,
            swing is not None, swing is not None and swing.active,
        )  # fmt: skip
        lead_p = (float(sc.dt), float(lead.cap), float(lead.fade), float(lead.tau), float(G), bool(lead.shape)) if (
            lead is not None) else (float(sc.dt), 1.0, 1.0, 1.0, float(G), False)  # fmt: skip
        consts = (float(SLACK_FACTOR), float(SNAP_FACTOR), float(SIDEWAYS_SPEED), float(load.static_tension()))
        run = (
            flags, np.array(loop["cmd"], dtype=float), np.ascontiguousarray(R_deck, dtype=float), float(sc.dt),
            lead_p, consts, float(load.spec.speed), np.array(loop["offset"], dtype=float),
        )  # fmt: skip
        s = np.zeros(lt.S)
        L = lt  # the slots
        s[L.S_T], s[L.S_WINCH_SPEED] = loop["t"], load.speed_command
        if lead is not None:
            (x2, y2), (x1, y1) = lead._f
            s[L.S_LEAD_T], s[L.S_LEAD_A : L.S_LEAD_A + 3] = lead.t, lead._a_cmd
            s[L.S_LEAD_F : L.S_LEAD_F + 4] = x2, y2, x1, y1
        s[L.S_TENSION], s[L.S_CONTACT_FORCE], s[L.S_GAP] = load.tension, load.contact_force, load.gap
        s[L.S_TOUCHED] = watch.touched
        s[L.S_TOUCH_SPEED] = math.nan if watch.touch_speed is None else watch.touch_speed
        s[L.S_CONTACTS], s[L.S_REL_SPEED], s[L.S_IN_CONTACT] = watch.contacts, watch.rel_speed, watch.in_contact
        s[L.S_REHIT], s[L.S_SLACK] = watch.rehit, watch.slack
        s[L.S_SNAP], s[L.S_SIDEWAYS] = watch.snap, watch.sideways
        s[L.S_SLACK_N : L.S_SLACK_N + 3] = loop["counts"]
        if swing is not None:
            s[L.S_L_PREV], s[L.S_RESETS] = swing.x[7], swing.resets
        s[L.S_Z_TARGET], s[L.S_HAS_Z], s[L.S_L_RIDE] = load.law
        s[L.S_TRACK] = load._ahc[1] == 1.0
        loop["t0"] = loop["t"]
        return (load_rec, swing_rec, lead_rec, run), s

    def _write_back(self, s, records, loop: dict, given, taken: int) -> None:
        load, watch, swing, lead = self.load, self.watch, self.swing, self.lead
        load_rec, swing_rec, lead_rec, run = records
        L = lt
        if not taken:
            return
        loop["t"] = float(s[L.S_T])
        loop["cmd"], loop["offset"] = run[1].copy(), run[7].copy()
        loop["d"], loop["n_up"] = given[2][taken - 1].copy(), given[3][taken - 1].copy()
        loop["d_prev"] = load_rec[9].copy()
        loop["counts"] = [int(v) for v in s[L.S_SLACK_N : L.S_SLACK_N + 3]]
        load.speed_command = float(s[L.S_WINCH_SPEED])
        hist = load_rec[5]
        load._tcp = [hist[0].copy(), hist[1].copy(), hist[2].copy()]
        load.tcp_v, load.tcp_a = load_rec[6].copy(), load_rec[7].copy()
        load.deck = (True, loop["d"], loop["n_up"], load_rec[8].copy())
        load.tension, load.contact_force, load.gap = (float(v) for v in s[L.S_TENSION : L.S_GAP + 1])
        load.law = (float(s[L.S_Z_TARGET]), bool(s[L.S_HAS_Z]), float(s[L.S_L_RIDE]))
        watch.touched = bool(s[L.S_TOUCHED])
        watch.touch_speed = None if math.isnan(s[L.S_TOUCH_SPEED]) else float(s[L.S_TOUCH_SPEED])
        watch.contacts, watch.rel_speed = int(s[L.S_CONTACTS]), float(s[L.S_REL_SPEED])
        watch.in_contact, watch.rehit, watch.slack = bool(s[L.S_IN_CONTACT]), bool(s[L.S_REHIT]), bool(s[L.S_SLACK])
        watch.snap, watch.sideways = bool(s[L.S_SNAP]), bool(s[L.S_SIDEWAYS])
        if lead is not None:
            x2, y2, x1, y1 = (float(v) for v in s[L.S_LEAD_F : L.S_LEAD_F + 4])
            lead.t, lead._f = float(s[L.S_LEAD_T]), ((x2, y2), (x1, y1))
            lead._a_cmd = tuple(float(v) for v in s[L.S_LEAD_A : L.S_LEAD_A + 3])
            loop["lead_tcp"] = lead_rec[0].copy()
            loop["lead_ref"] = (lead_rec[1][0].copy(), lead_rec[1][1].copy())
            loop["v_prev"] = given[0][taken - 1].copy()
        if swing is not None:
            swing.x = (*swing_rec[:7], float(s[L.S_L_PREV]))
            swing.resets = int(s[L.S_RESETS])
            swing.offset = run[7].copy()


def summarise(res: TransferResult, operator, touch_speed, contacts, slack_n, snap_n, sideways_n) -> dict:
    """The figures of issue 30, item 6."""
    sc, d = res.scenario, res.rows
    col = {name: d[:, i] for i, name in enumerate(res.columns)} if d.size else {}
    ph = np.array(res.phases)
    dt = sc.dt
    out: dict = {"scenario": sc.to_dict()}
    if not d.size:
        return out
    moving = np.isin(ph, ["lift", "move", "settle", "lower"]) if isinstance(operator, ScriptedOperator) else None
    path = col["error_m"][moving] if moving is not None and moving.any() else col["error_m"]
    before_touch = ~np.isin(ph, ["set_down", "hold"])
    residual = None
    if operator.move_end is not None:
        win = (col["t"] > operator.move_end) & (col["t"] <= operator.move_end + sc.wait)
        residual = float(np.sqrt(np.mean(col["swing_deg"][win] ** 2))) if win.any() else None
    out.update(
        {
            "path_rms_error_m": float(np.sqrt(np.mean(path**2))),
            "touchdown_relative_speed_mps": touch_speed,
            "commanded_lowering_speed_mps": sc.lower_speed if isinstance(operator, ScriptedOperator) else None,
            "rehits": max(0, contacts - 1),
            "peak_swing_deg": float(np.max(col["swing_deg"][before_touch])) if before_touch.any() else None,
            "residual_swing_deg": residual,
            "peak_tension_factor": float(np.max(col["tension_factor"])),
            "duration_s": float(col["t"][-1]),
            "alarms": {
                "slack_wire_s": slack_n * dt,
                "snap_load_s": snap_n * dt,
                "rehit": max(0, contacts - 1),
                "sideways_contact_s": sideways_n * dt,
            },
        }
    )
    return out


def landings(sc: TransferScenario, n: int, progress=None, cancel=None) -> dict:
    """``n`` seeded landings (seeds ``sc.seed`` … ``sc.seed + n − 1``): the touchdown speed's error against the
    commanded lowering speed (95th percentile) and the share of landings without a re-hit."""
    runs = []
    for k in range(n):
        if cancel is not None and cancel():
            break
        s = simulate(replace(sc, seed=sc.seed + k)).summary
        runs.append({key: s.get(key) for key in ("touchdown_relative_speed_mps", "rehits", "path_rms_error_m")})
        if progress is not None:
            progress(k + 1, n)
    return {**landing_statistics(runs, sc.lower_speed), "runs": runs}


def landing_statistics(runs: list[dict], lower_speed: float) -> dict:
    """Of runs' summaries: their number, the 95th percentile of the touchdown speed's error against the commanded
    lowering speed, and the share that touched down without a re-hit (a run that never touched down is not)."""
    touched = [r for r in runs if r.get("touchdown_relative_speed_mps") is not None]
    errors = [abs(r["touchdown_relative_speed_mps"] - lower_speed) for r in touched]
    clean = sum(r.get("rehits", 1) == 0 for r in touched)
    return {
        "n": len(runs),
        "touchdown_speed_error_p95_mps": float(np.percentile(errors, 95)) if errors else None,
        "rehit_free_share": clean / len(runs) if runs else None,
    }
