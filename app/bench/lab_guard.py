"""The Comau's guard under random sticks in the Motion-Lab (issue 32, item 5's acceptance for the lab scene):
seeded random stick streams drive the lab's Comau in REMOTE into EM8000's deck, its pedestal and EM1500's deck,
and every 5 ms step is checked.

Each stream:

* the Comau on the robot file's (data sheet) joint limits, where it reaches both decks and its pedestal (the
  lab's own program limits keep it 0.4 m above its base: nothing to guard there);
* both platforms held still at a random pose inside their command boxes, uniform per degree of freedom;
* the arm starting at a random configuration with every clearance outside the guard's zone;
* 6–12 segments; half of them for 0.5–3 s a stick deflection uniform in [−1, 1]³ with a third of the axes at
  full deflection, the other half for 2–8 s a full stick aimed, as the segment starts, from the tool point at a
  random point of a random obstacle (:func:`aimed_stick`: random sticks alone seldom reach them); as the lab
  engine maps a stick: the tool's velocity in {r}, REMOTE_TOOL_SPEED at full stick;
* in half the segments, the winch in REMOTE paying out or hauling in at a speed uniform in ±its 0.2 m/s (from its
  1.8 m of wire, within its 0.3–4 m);
* then the stick centred and the winch still for 1 s.

A stream whose load swings past its model (level with the tool point: H118) stops the lab there, as the engine
does; ``load_model_lost`` counts them.

The load hangs from the tool point on the winch's wire, and swings as the arm moves it.

Measured at the actual joints (the drives', after each step) against the true platforms, the load where it hangs:

* ``penetration`` [m]: the deepest capsule overlap with an obstacle (minus the least clearance when negative), the
  wire's and the load's among them (``load_least``: theirs alone; ``load_near``: steps the guard's nearest hazard
  in its zone was the wire or the load's swing envelope);
* ``limit_excess``: the farthest a joint went past its limit [rad];
* ``opening`` ticks: the law's command opens (or keeps) every clearance in the guard's zone, judged by the
  clearances' own values over a 10⁻⁷ rad step along what the drives can do of it (a joint at its limit stays),
  not the guard's gradients; and of them the least ratio of
  one drive step with the guarded command to one with the command as the law gave it (1: never slowed; the
  acceptance asks ≥ 0.9); of the steps kept under 90 %, those whose drive step with the command as the law gave
  it would itself close a clearance in the zone (``opening_slow_closing``: the command opens, but the drives,
  still carrying the arm's last motion or each ramping at its own limit, would move it nearer the hazard this
  step);
* the opening steps kept under 90 %, split by why (each on the true clearances along the plant's own drive model,
  :func:`app.sim.kernels.motion_filter_update`, not the guard's first order): ``opening_slow_ahead``, those whose
  drives, following the command as asked for as long as the guard's outcome check looks ahead and then braked to
  rest, take a clearance in the zone below the stop distance (less the guard's 2 mm slack) and below where it is —
  a joint braking into its limit while the others close the gap, the drives' ramps leaving the command's
  direction; of the rest, ``opening_slow_carried``, those whose arm, braked to rest now, is carried into the zone of
  a hazard outside it that the command closes on (the guard counts an approach's braking distance, as the teleop
  bench's zone counts the servo's lag);
* ``slowed`` ticks and the least clearance reached; over the steps the guard slowed, the tool's travel in the
  drive step as asked and the guarded drive step's tool motion across its direction (``slowed_across``, as the
  teleop bench's *across*, H121).

The platforms stand still because the guard never moves the arm by itself (nothing moves without the operator's
command): a platform that drives its deck into a resting arm is the platforms' command boxes' to prevent, not the
arm's guard — the stream measures what the guard can answer for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.control import lab_kernels as ck
from app.models.lab import load_lab
from app.models.lab_kernels import comau_tool, lstsq3
from app.scenes.lab import REMOTE_TOOL_SPEED, MotionLab
from app.sim.kernels import motion_filter_update

DIRECTION_STEP = 1e-7  # [rad]: a command's direction is judged by the clearances' change over this step along it
DT = 0.005  # [s]: the lab PLC's cycle
ROLLOUT_REST = 400  # steps: the longest a braked path is followed to rest (2 s)


@dataclass(frozen=True)
class LabGuardRun:
    seed: int
    ticks: int
    penetration: float  # [m], ≥ 0
    least_clearance: float  # [m]
    limit_excess: float  # [rad], ≥ 0
    opening: int  # ticks whose command opened every clearance in the zone (at least one in it)
    min_opening_speed: float  # the least drive-step ratio (guarded/as asked) over them (1: never slowed)
    opening_slow: int  # of them, those kept under 90 %
    slowed: int  # ticks the guard slowed the command
    near: dict  # obstacle → ticks with it the nearest in the zone
    load_near: int = 0  # of those, ticks the wire or the load (its swing's envelope) was the nearest
    load_least: float = math.inf  # [m]: the least clearance of the wire and the load (where it hangs)
    load_model_lost: bool = False  # the swing left its model and the lab stopped itself (H118)
    opening_slow_closing: int = 0  # of the opening steps kept under 90 %, those whose drive step as asked closed one
    opening_slow_ahead: int = 0  # … those whose drives as asked would pass below the stop distance (this step or on)
    opening_slow_carried: int = 0  # … of the rest, those whose arm its own motion carries into another hazard's zone
    slowed_travel: float = 0.0  # [m]: the tool's travel the drive steps as asked would make in the slowed steps
    slowed_across: float = 0.0  # [m]: … and the guarded drive steps' tool motion across their direction


def stick_stream(rng: np.random.Generator) -> list[tuple[np.ndarray | None, float]]:
    """6–12 (stick, seconds) segments: random sticks for 0.5–3 s, or (None) one aimed when its segment starts, for
    2–8 s (see the module's text)."""
    out: list[tuple[np.ndarray | None, float]] = []
    for _ in range(int(rng.integers(6, 13))):
        s = rng.uniform(-1.0, 1.0, 3)
        full = rng.random(3) < 1 / 3
        s[full] = np.sign(s[full] + 1e-9)
        aimed = rng.random() < 0.5
        out.append((None if aimed else s, float(rng.uniform(2.0, 8.0) if aimed else rng.uniform(0.5, 3.0))))
    return out


def aimed_stick(rng: np.random.Generator, lab: MotionLab, world: tuple, tool: np.ndarray) -> np.ndarray:
    """A full stick from the tool point towards a random point of a random obstacle (in {r}): EM8000's deck within
    3 m of the pedestal's foot, the pedestal's axis, or EM1500's deck; a little off line (±0.2 per axis)."""
    deck1, ped, _, deck2, _ = world
    which = int(rng.integers(3))
    if which == 1:
        target = ped[0] + (ped[1] - ped[0]) * rng.uniform()
    else:
        n = deck1[:3] if which == 0 else deck2[3:6]
        centre = ped[0] if which == 0 else deck2[:3]
        radius = 3.0 if which == 0 else deck2[6]
        e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        r, a = radius * math.sqrt(rng.uniform()), rng.uniform(0.0, 2 * math.pi)
        target = centre + r * (math.cos(a) * e1 + math.sin(a) * e2)
    d = target - tool + rng.uniform(-0.2, 0.2, 3) * np.linalg.norm(target - tool)
    return d / max(float(np.abs(d).max()), 1e-9)


class _Clearances:
    """The guard's clearances at a configuration (:func:`app.control.lab_kernels.guard_hazards`)."""

    def __init__(self, lab: MotionLab) -> None:
        self.cm, self.radii = lab._comau, lab.guard.radii
        self.G, self.val = np.zeros((ck.ROWS, 3)), np.zeros(ck.ROWS)
        self.kind, self.cap = np.zeros(ck.ROWS, np.int64), np.zeros(ck.ROWS, np.int64)

    def __call__(self, world, q) -> np.ndarray:
        ck.guard_hazards(self.cm, self.radii, world, np.ascontiguousarray(q), self.G, self.val, self.kind, self.cap)
        return self.val.copy()


def actual(world: tuple) -> tuple:
    """The guard's world with the load where it is (the guard's own takes the sphere its swing can reach)."""
    hang = world[4].copy()
    hang[3:6], hang[6] = hang[0:3], 0.0
    return (*world[:4], hang)


def _drive_step(arm: tuple, command: tuple, limits: tuple) -> np.ndarray:
    """The joints after one drive step (:func:`app.sim.kernels.motion_filter_update`) from ``arm`` = (q, q̇) with
    the Comau law's ``command`` (brake, q_ref, q̇_ref, use q̇_ref, speed scale)."""
    x = (arm[0].copy(), arm[1].copy(), np.zeros(3))
    motion_filter_update(x, command[1:], limits, DT)
    return x[0]


def _across(cm, q, asked: np.ndarray, got: np.ndarray) -> tuple[float, float]:
    """The tool's travel in the drive step as asked (joints moved by ``asked``), and the guarded step's (``got``)
    tool motion across that travel's direction [m] (as :mod:`app.bench.guard` measures the teleop arms)."""
    z3 = np.zeros(3)
    p0 = comau_tool(cm, q, z3, z3)[0]
    d_asked = comau_tool(cm, q + asked, z3, z3)[0] - p0
    travel = float(np.linalg.norm(d_asked))
    if travel <= 1e-12:
        return 0.0, 0.0
    u = d_asked / travel
    d_got = comau_tool(cm, q + got, z3, z3)[0] - p0
    return travel, float(np.linalg.norm(d_got - (d_got @ u) * u))


def _path_lowest(clear, world, arm: tuple, command, limits: tuple, hold: int) -> np.ndarray:
    """Each clearance's least value where the drives take the arm from ``arm`` = (q, q̇): ``hold`` steps following
    ``command(q)`` (the law's command at the joints q), then braked to rest at their limits (the command q_ref = q,
    no rate: :func:`app.sim.kernels.motion_filter_update` decelerates each joint at its own limit)."""
    x = (arm[0].copy(), arm[1].copy(), np.zeros(3))
    lowest = clear(world, x[0])
    z3 = np.zeros(3)
    for k in range(hold + ROLLOUT_REST):
        rest = k >= hold
        if rest and not np.any(x[1]):
            break
        cmd = (x[0].copy(), z3, np.bool_(False), 1.0) if rest else command(x[0])[1:]
        motion_filter_update(x, cmd, limits, DT)
        lowest = np.minimum(lowest, clear(world, x[0]))
    return lowest


def _closes_ahead(clear, world, arm: tuple, asked: tuple, guard_p: tuple, inzone: np.ndarray) -> bool:
    """Whether the drives, following the command as asked (its joint rate, held) for as long as the guard's outcome
    check looks ahead (until they have it, and as long again as they would take to stop from it at κ of their
    acceleration), then braked to rest, take a clearance in the zone below the stop distance (less the guard's
    2 mm slack) and below where it is: the true clearances along the drives' own path, not the guard's first order."""
    q, qd = arm
    _, _, limits, settings = guard_p
    accel, kappa, stop = limits[3], float(settings[2]), float(settings[1])
    rate = asked[2]
    reach = np.abs(rate - qd) / (accel * DT) + np.abs(rate) / (kappa * accel * DT)  # the guard's horizon [steps]
    hold = int(min(np.max(np.ceil(reach)), ck.ROLLOUT))

    def command(qq):
        return (np.bool_(False), qq + rate * DT, rate, np.bool_(True), 1.0)

    now = clear(world, q)
    lowest = _path_lowest(clear, world, arm, command, limits, hold)
    return bool(np.any(inzone & (lowest < stop - ck.BRAKE_SLACK) & (lowest < now)))


def _carried_in(clear, world, arm: tuple, v0: np.ndarray, guard_p: tuple) -> bool:
    """Whether the arm's own motion, braked to rest now, carries it into the zone of a hazard outside it that the
    command's direction ``v0`` closes (the guard counts an approach's braking distance; the opening test above looks
    only at the hazards already in the zone)."""
    zone = float(guard_p[3][0])
    now = clear(world, arm[0])
    lowest = _path_lowest(clear, world, arm, None, guard_p[2], 0)
    ahead = clear(world, arm[0] + DIRECTION_STEP * v0 / max(float(np.linalg.norm(v0)), 1e-300))
    return bool(np.any((now >= zone) & (lowest < zone) & (ahead < now)))


def run_stream(seed: int, lab_name: str = "motionlab") -> LabGuardRun:
    """One seeded stream on a fresh Motion-Lab (see the module's text)."""
    rng = np.random.default_rng([seed, 3205])
    lab = MotionLab(load_lab(lab_name), comau_profile="datasheet")
    for p in lab.platforms:  # held still at a random pose inside its command box
        lo, hi = p.command_box
        p.place_at_neutral()
        p.filter.reset(rng.uniform(lo, hi))
        p.estop()
    lab.set_comau_mode("remote")
    clear = _Clearances(lab)
    f = lab.joints
    lo, hi = f.lower, f.upper
    world = lab.guard_world()
    zone = lab.guard.zone
    for _ in range(10_000):  # a start with every clearance outside the zone
        q = rng.uniform(lo, hi)
        if clear(world, q).min() > zone:
            break
    f.reset(q)
    lab.refresh()
    cm = lab._comau
    guard_p = (cm, lab._guard_p[0], f.limits(), lab._guard_p[5])
    limits = f.limits()
    ticks = opening = slowed = opening_slow = opening_slow_closing = load_near = 0
    opening_slow_ahead = opening_slow_carried = 0
    slowed_travel = slowed_across = 0.0
    load_least = math.inf
    least, excess, min_open = math.inf, 0.0, 1.0
    near = {"EM8000 deck": 0, "pedestal": 0, "EM1500 deck": 0}
    names = tuple(near)
    segments = stick_stream(rng) + [(np.zeros(3), 1.0)]
    winch = [float(rng.uniform(-1.0, 1.0)) if rng.random() < 0.5 else 0.0 for _ in segments[:-1]] + [0.0]
    lab.set_winch_mode("remote")
    for (stick, seconds), pay_out in zip(segments, winch, strict=True):
        lab.winch.speed_command = pay_out * lab.winch.spec["speed"]
        if stick is None:
            stick = aimed_stick(rng, lab, world, comau_tool(cm, f.x, np.zeros(3), np.zeros(3))[0])
        v_cmd = np.ascontiguousarray(REMOTE_TOOL_SPEED * stick)
        for _ in range(max(1, round(seconds / DT))):
            world = lab.guard_world()  # the platforms stand still; the load hangs where it swings
            q, qd = f.x.copy(), f.v.copy()
            # the law's command and the guard's answer, as lab_step will make them this step
            rate = lstsq3(comau_tool(cm, q, np.zeros(3), np.zeros(3))[3], v_cmd)
            asked = (np.bool_(False), q + rate * DT, rate, np.bool_(True), 1.0)
            _, (got, report) = ck.comau_guard((), (asked, q, qd, world), guard_p, DT)
            vals = clear(world, q)
            inzone = vals < zone
            ends = None
            if report[4]:  # slowed: the drive steps as asked and as guarded; the second's tool motion across the first
                ends = [_drive_step((q, qd), cmd, limits) for cmd in (asked, got)]
                travel, across = _across(cm, q, ends[0] - q, ends[1] - q)
                slowed_travel += travel
                slowed_across += across
            if inzone.any():
                near[names[int(report[0])]] += 1
                load_near += int(report[1]) >= ck.WIRE
                up, down = np.maximum(f.upper - q, 0.0), np.maximum(q - f.lower, 0.0)  # the drives' reach this step
                hi_v = np.minimum(f.speed, np.minimum(np.sqrt(2.0 * f.brake * up), up / DT))
                lo_v = -np.minimum(f.speed, np.minimum(np.sqrt(2.0 * f.brake * down), down / DT))
                v0 = np.clip((asked[1] - q) / max(f.tau, DT) + rate, lo_v, hi_v)
                norm = float(np.linalg.norm(v0))
                if norm > 0.0:
                    ahead = clear(world, q + DIRECTION_STEP * v0 / norm)
                    if np.all(ahead[inzone] >= vals[inzone] - 1e-15):
                        opening += 1
                        if ends is None:
                            ends = [_drive_step((q, qd), asked, limits)] * 2
                        moved = [float(np.linalg.norm(e - q)) for e in ends]
                        kept = moved[1] / moved[0] if moved[0] > 0.0 else 1.0
                        min_open = min(min_open, kept)
                        if kept < 0.9:
                            opening_slow += 1
                            step_closes = bool(np.any(clear(world, ends[0])[inzone] < vals[inzone]))
                            opening_slow_closing += step_closes
                            ahead_closes = step_closes or _closes_ahead(clear, world, (q, qd), asked, guard_p, inzone)
                            opening_slow_ahead += ahead_closes
                            opening_slow_carried += not ahead_closes and _carried_in(clear, world, (q, qd), v0, guard_p)
            lab.tool_velocity_cmd = v_cmd
            lab.step(DT)
            slowed += bool(lab.guard_report[4])
            ticks += 1
            q = f.x
            now = clear(actual(lab.guard_world()), q)
            least = min(least, float(now.min()))
            load_least = min(load_least, float(now[ck.ROWS - 4 :].min()))
            excess = max(excess, float(np.max(np.maximum(lo - q, q - hi))))
    return LabGuardRun(
        seed=seed, ticks=ticks, penetration=max(0.0, -least), least_clearance=least, limit_excess=max(excess, 0.0),
        opening=opening, min_opening_speed=min_open, opening_slow=opening_slow, slowed=slowed, near=near,
        load_near=load_near, load_least=load_least, load_model_lost=bool(lab.load_model_lost),
        opening_slow_closing=opening_slow_closing, opening_slow_ahead=opening_slow_ahead,
        opening_slow_carried=opening_slow_carried, slowed_travel=slowed_travel, slowed_across=slowed_across,
    )  # fmt: skip


def _chunk(task) -> tuple[str, list[LabGuardRun]]:
    first, n = task
    return "motionlab", [run_stream(k) for k in range(first, first + n)]


def summarise(runs: list[LabGuardRun]) -> dict:
    from app.bench.guard import totals

    near = {k: sum(r.near[k] for r in runs) for k in runs[0].near} if runs else {}
    return {"scene": "motionlab (Comau REMOTE, data-sheet limits)", **totals(runs), "nearest_in_zone_ticks": near,
            "opening_slow_closing_ticks": sum(r.opening_slow_closing for r in runs),
            "opening_slow_ahead_ticks": sum(r.opening_slow_ahead for r in runs),
            "opening_slow_carried_ticks": sum(r.opening_slow_carried for r in runs),
            "slowed_travel_m": sum(r.slowed_travel for r in runs),
            "slowed_across_m": sum(r.slowed_across for r in runs),
            "load_nearest_ticks": sum(r.load_near for r in runs),
            "load_least_clearance_m": min((r.load_least for r in runs), default=math.inf),
            "streams_load_model_lost": sum(r.load_model_lost for r in runs),
            # which streams to take apart: the load or the arm past 1 mm; slow opening steps by why
            "seeds_penetrating": [r.seed for r in runs if r.penetration > 1e-3],
            "seeds_opening_slow_ahead": [r.seed for r in runs if r.opening_slow_ahead],
            "seeds_opening_slow_carried": [r.seed for r in runs if r.opening_slow_carried],
            "seeds_opening_slow_unexplained": [
                r.seed for r in runs if r.opening_slow > r.opening_slow_ahead + r.opening_slow_carried]}  # fmt: skip


def bench_lab_guard(streams: int, workers: int = 1, progress=None) -> dict:
    """``streams`` seeded streams on ``workers`` processes, summarised (:func:`summarise`)."""
    from app.bench.pool import gather

    chunk = 10
    tasks = [(k, min(chunk, streams - k)) for k in range(0, streams, chunk)]
    runs = gather(_chunk, tasks, ["motionlab"], streams, workers, progress)
    return summarise(runs["motionlab"])
