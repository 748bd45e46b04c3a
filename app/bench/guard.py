"""Direction-aware scaling under random sticks (issue 32, item 5's acceptance): seeded random stick streams drive
the teleop scene (:class:`~app.engine.session.Session`) into its hazards, and every tick is checked.

Per stream, at the actual joints (the actuators', not the reference):

* ``penetration`` [m]: the deepest capsule overlap (minus the least clearance when it is negative; 0 otherwise)
  over every pair and floor the guard checks (:class:`~app.control.guard.HazardGuard`);
* ``limit_excess``: the farthest any joint went past a limit [rad or m];
* ``opening`` ticks: a step whose direction opens (or keeps) every hazard in its zone — the σ ratio, every
  clearance and every joint's distance to its limit no smaller 10⁻⁷ rad along it than where it starts, measured
  by the hazards' own values, not the guard's gradients — and, of them, the least ratio of the arm's motion in the
  tick (the servo's step from where the joints are) with the guarded reference to its motion with the reference as
  asked (``min_opening_speed``: 1 means never slowed; the acceptance asks ≥ 0.9; an opening tick the safe-braking
  rule braked counts as 0);
* ``slowed`` ticks, ``braked`` ticks (the safe-braking rule, :func:`~app.scenes.teleop_guard.guard_tick`),
  and the least clearance reached;
* over the slowed ticks, the tool travel the solver's steps asked for (at the reference) and the guarded steps'
  tool motion across each step's direction (``slowed_across``): what the guard leaves of a command should go where
  it was asked, not elsewhere.

Streams: 6 to 12 segments of 0.2–1 s, each stick deflection uniform in [−1, 1]³ with a third of the axes at full
deflection, velocity mode, the Jacobian solver, at the rate given, the workspace scaling's default speed (or a
multiple of it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from app.engine.session import Session
from app.scenes import teleop_guard
from app.sim.actuators import JOINT_ACTUATORS
from app.teleop.devices import InputSample

DIRECTION_STEP = 1e-7  # [rad | m]: a command's direction is judged by the hazards' change over this step along it
SPEED = 1.0  # the stick's speed as a multiple of the workspace scaling's default k_v


@dataclass(frozen=True)
class GuardRun:
    seed: int
    ticks: int
    penetration: float  # [m], ≥ 0
    least_clearance: float  # [m] (inf: nothing checked)
    limit_excess: float  # [rad | m], ≥ 0
    opening: int  # ticks whose unscaled step opened every hazard in its zone (at least one in its zone)
    min_opening_speed: float  # the least tool step ratio (scaled/unscaled) over those ticks (1: never slowed)
    slowed: int  # ticks the guard scaled the step
    braked: int = 0  # ticks the safe-braking rule braked the joints (scenes.teleop_guard)
    opening_braked: int = 0  # of the opening ticks, those it braked (counted as speed 0 kept)
    opening_slow: int = 0  # of the opening ticks, those kept under 90 % of their speed (braked ones included)
    opening_slow_closing: int = 0  # of those, the ticks whose arm, with the command as asked, closed on a hazard
    slowed_travel: float = 0.0  # [m] the tool's travel the solver's steps asked for in the slowed ticks
    slowed_across: float = 0.0  # [m] the guarded steps' tool motion across those steps' directions


class _Watch:
    """Stands in for the session's guard: passes every call on, and measures each tick's step."""

    def __init__(self, guard, settings) -> None:
        self.guard = guard
        self.s = settings
        self.opening = 0
        self.min_opening_speed = 1.0
        self.slowed = 0
        self.opening_braked = 0
        self.opening_slow = 0  # opening ticks kept under 90 % of their speed
        self.opening_slow_closing = 0  # … whose arm, with the command as asked, would have closed on a hazard
        self.slowed_travel = 0.0  # the reference's tool travel asked in the slowed ticks [m]
        self.slowed_across = 0.0  # … and the guarded reference's tool motion across it [m]

    def __getattr__(self, name):
        return getattr(self.guard, name)

    def _in_zone(self, q, v, margin) -> tuple[np.ndarray, np.ndarray]:
        r = self.guard.robot
        span = r.upper - r.lower
        lim = np.minimum(q - r.lower, r.upper - q)
        zones = np.concatenate(([self.s.sigma_zone], np.full(v.size - 1, self.s.clear_zone + margin)))
        return lim < self.s.limit_zone * span, v < zones

    def _across(self, q_ref, dq, new) -> None:
        """A slowed tick: the tool travel the solver's step asked for, and the guarded step's motion across its
        direction (the guard may take from the command only along it: what it leaves must not go elsewhere)."""
        r = self.guard.robot
        p0 = r.position(q_ref)
        asked = r.position(np.clip(q_ref + dq, r.lower, r.upper)) - p0
        travel = float(np.linalg.norm(asked))
        if travel > 1e-12:
            u = asked / travel
            got = r.position(new) - p0
            self.slowed_travel += travel
            self.slowed_across += float(np.linalg.norm(got - (got @ u) * u))

    def tick(self, guard, q_ref, dq, act, dt):
        q_ref = np.array(q_ref, dtype=float)
        margin = self.guard.margin(q_ref, act.stopping_point(dt))
        new, rep, action = teleop_guard.guard_tick(guard, q_ref, dq, act, dt)
        if rep.slowed:
            self.slowed += 1
            self._across(q_ref, dq, new)
        if not np.any(dq):
            return new, rep, action
        r = self.guard.robot
        e = DIRECTION_STEP / float(np.max(np.abs(dq)))  # the command's direction: a step of 1e-7 along it
        v0, v1 = self.guard.values(q_ref), self.guard.values(q_ref + e * dq)
        lim_zone, geo_zone = self._in_zone(q_ref, v0, margin)
        if lim_zone.any() or geo_zone.any():
            lim0 = np.minimum(q_ref - r.lower, r.upper - q_ref)
            lim1 = np.minimum(q_ref + e * dq - r.lower, r.upper - (q_ref + e * dq))
            opens = np.all(lim1[lim_zone] >= lim0[lim_zone]) and np.all(v1[geo_zone] >= v0[geo_zone])
            if opens:
                self.opening += 1
                # the arm's motion this tick (the servo's step from where it is) with the command as asked and as
                # guarded: the speed it moves at, not the reference's (a reference the servo cannot follow is no
                # faster; the safe-braking rule's gentler reference is the one it follows in proportion)
                x = (act.q, act.qdot, act.qddot)
                full = np.clip(q_ref + dq, r.lower, r.upper)
                (q_full, _, _), _ = JOINT_ACTUATORS.step(x, (full,), act.params, dt, act.use_kernels)
                (q_new, _, _), _ = JOINT_ACTUATORS.step(
                    x, (np.ascontiguousarray(new),), act.params, dt, act.use_kernels
                )
                p0 = r.position(act.q)
                want = float(np.linalg.norm(r.position(q_full) - p0))
                got = float(np.linalg.norm(r.position(q_new) - p0))
                slow = action == 2 or (want > 1e-12 and got < 0.9 * want)
                if action == 2:
                    self.opening_braked += 1
                    self.min_opening_speed = 0.0
                elif want > 1e-12:
                    self.min_opening_speed = min(self.min_opening_speed, got / want)
                if slow:
                    self.opening_slow += 1
                    # the command opens at the reference, but the arm lags it: its servo step as asked would still
                    # close a clearance in its zone (the reference's lead points at the hazard)
                    a0, a1 = self.guard.values(act.q), self.guard.values(q_full)
                    self.opening_slow_closing += bool(np.any((a1 < a0)[1:] & (a0 < self.s.clear_zone + margin)[1:]))
        return new, rep, action


def stick_stream(
    rng: np.random.Generator, shortest: float = 0.2, longest: float = 1.0
) -> list[tuple[np.ndarray, float]]:
    """6–12 random (stick, seconds) segments of ``shortest``–``longest`` s (see the module's text)."""
    out = []
    for _ in range(int(rng.integers(6, 13))):
        s = rng.uniform(-1.0, 1.0, 3)
        full = rng.random(3) < 1 / 3
        s[full] = np.sign(s[full] + 1e-9)
        out.append((s, float(rng.uniform(shortest, longest))))
    return out


def run_stream(robot: str, seed: int, rate: float = 250.0, speed: float | None = None) -> GuardRun:
    """One seeded stream on a fresh teleop scene of ``robot``."""
    rng = np.random.default_rng([seed, 32])
    ses = Session(robot_name=robot, solver_name="jacobian", mode="velocity", seed=seed)
    factor = SPEED if speed is None else speed
    ses.scaling = replace(ses.scaling, k_v=tuple(factor * float(v) for v in ses.scaling.k_v))
    guard = ses.guard
    watch = _Watch(guard, guard.settings)
    ses.guard_tick = watch.tick
    r = ses.robot
    dt = 1.0 / rate
    t = 0.0
    ticks = 0
    least = math.inf
    excess = 0.0

    def step(stick, enable=True):
        nonlocal t, ticks, least, excess
        t += dt
        ses.feed(InputSample(tuple(float(v) for v in stick), (enable,), "guard-bench"), t)
        ses.tick(t, dt, solve_budget=0.4 * dt)
        ticks += 1
        q = ses.actuators.q
        least = min(least, guard.min_clearance(q))
        excess = max(excess, float(np.max(np.maximum(r.lower - q, q - r.upper))))

    for enable in (False, True):
        for _ in range(3):
            step((0.0, 0.0, 0.0), enable)
    for stick, seconds in stick_stream(rng):
        for _ in range(max(1, round(seconds / dt))):
            step(stick)
    for _ in range(round(0.5 / dt)):  # centred: the arm brakes and holds
        step((0.0, 0.0, 0.0))
    return GuardRun(
        seed=seed, ticks=ticks, penetration=max(0.0, -least) if math.isfinite(least) else 0.0,
        least_clearance=least, limit_excess=max(excess, 0.0), opening=watch.opening,
        min_opening_speed=watch.min_opening_speed, slowed=watch.slowed, braked=ses.braked,
        opening_braked=watch.opening_braked, opening_slow=watch.opening_slow,
        opening_slow_closing=watch.opening_slow_closing, slowed_travel=watch.slowed_travel,
        slowed_across=watch.slowed_across,
    )  # fmt: skip


def _chunk(task) -> tuple[str, list[GuardRun]]:
    robot, first, n, rate, speed = task
    return robot, [run_stream(robot, k, rate, speed) for k in range(first, first + n)]


def totals(runs: list) -> dict:
    """The figures every scene's guard streams report (runs with ticks, penetration, least_clearance, limit_excess,
    opening, min_opening_speed, opening_slow, slowed)."""
    return {
        "streams": len(runs),
        "ticks": sum(r.ticks for r in runs),
        "max_penetration_m": max(r.penetration for r in runs),
        "least_clearance_m": min(r.least_clearance for r in runs),
        "max_limit_excess": max(r.limit_excess for r in runs),
        "opening_ticks": sum(r.opening for r in runs),
        "min_opening_speed": min(r.min_opening_speed for r in runs),
        "opening_slow_ticks": sum(r.opening_slow for r in runs),
        "slowed_ticks": sum(r.slowed for r in runs),
        "streams_slowed": sum(r.slowed > 0 for r in runs),
    }


def summarise(robot: str, runs: list[GuardRun]) -> dict:
    return {
        "robot": robot,
        **totals(runs),
        "braked_ticks": sum(r.braked for r in runs),
        "opening_braked_ticks": sum(r.opening_braked for r in runs),
        "opening_slow_closing_ticks": sum(r.opening_slow_closing for r in runs),
        "slowed_travel_m": sum(r.slowed_travel for r in runs),
        "slowed_across_m": sum(r.slowed_across for r in runs),
    }


def bench_guard(
    robots: list[str], streams: int, rate: float = 250.0, workers: int = 1, progress=None, speed: float = 1.0
) -> list[dict]:
    """``streams`` seeded streams per robot on ``workers`` processes; one row a robot (:func:`summarise`)."""
    from app.bench.pool import gather

    chunk = 10
    tasks = [(r, k, min(chunk, streams - k), rate, speed) for r in robots for k in range(0, streams, chunk)]
    runs = gather(_chunk, tasks, robots, len(robots) * streams, workers, progress)
    return [summarise(r, runs[r]) for r in robots]
