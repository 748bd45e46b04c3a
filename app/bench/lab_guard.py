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
* ``slowed`` ticks and the least clearance reached.

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
                        moved, ends = [], []
                        for cmd in (asked, got):
                            x = (q.copy(), qd.copy(), np.zeros(3))
                            motion_filter_update(x, cmd[1:], limits, DT)
                            moved.append(float(np.linalg.norm(x[0] - q)))
                            ends.append(x[0])
                        kept = moved[1] / moved[0] if moved[0] > 0.0 else 1.0
                        min_open = min(min_open, kept)
                        if kept < 0.9:
                            opening_slow += 1
                            opening_slow_closing += bool(np.any(clear(world, ends[0])[inzone] < vals[inzone]))
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
        opening_slow_closing=opening_slow_closing,
    )  # fmt: skip


def _chunk(task) -> tuple[str, list[LabGuardRun]]:
    first, n = task
    return "motionlab", [run_stream(k) for k in range(first, first + n)]


def summarise(runs: list[LabGuardRun]) -> dict:
    from app.bench.guard import totals

    near = {k: sum(r.near[k] for r in runs) for k in runs[0].near} if runs else {}
    return {"scene": "motionlab (Comau REMOTE, data-sheet limits)", **totals(runs), "nearest_in_zone_ticks": near,
            "opening_slow_closing_ticks": sum(r.opening_slow_closing for r in runs),
            "load_nearest_ticks": sum(r.load_near for r in runs),
            "load_least_clearance_m": min((r.load_least for r in runs), default=math.inf),
            "streams_load_model_lost": sum(r.load_model_lost for r in runs)}  # fmt: skip


def bench_lab_guard(streams: int, workers: int = 1, progress=None) -> dict:
    """``streams`` seeded streams on ``workers`` processes, summarised (:func:`summarise`)."""
    from app.bench.pool import gather

    chunk = 10
    tasks = [(k, min(chunk, streams - k)) for k in range(0, streams, chunk)]
    runs = gather(_chunk, tasks, ["motionlab"], streams, workers, progress)
    return summarise(runs["motionlab"])
