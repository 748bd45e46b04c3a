"""Hold means hold: seeded random stick sequences that end at rest, and how far the tool moves after.

Issue 26, item 1.  A sequence arms the input, then drives the teleop scene (:class:`~app.engine.session.Session`)
through random stick segments with the deadman held, and ends with the stick *still*: centred in
velocity mode, resting at its last deflection in position mode.  From that moment the machine must
come to rest within its braking distance and stay there.  Measured per sequence:

* ``overrun`` [m]: velocity mode, how far the rest point lies from where the joints stop when each
  brakes at its acceleration limit from the moment the stick is centred
  (:meth:`~app.sim.actuators.JointActuators.stopping_point`), as tool positions; position mode, how far
  the rest point lies from the solver's answer for the resting stick (the machine goes there and no
  farther);
* ``drift`` [m]: once at rest, the largest tool displacement over the rest of the hold window;
* ``settle_s`` [s]: from the last stick change to rest (joints below 0.1 % of their speed limits for
  :data:`REST_S`), or
  ``inf`` when the machine never came to rest (a limit cycle).

The worst of ``overrun`` and ``drift`` is the sequence's figure of merit; the property holds when it is
below 1 cm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.engine.session import Session
from app.teleop.devices import InputSample

#: the property's bound on overrun and drift [m] (issue 26: 1 cm)
HOLD_TOLERANCE = 0.01
#: rest: every joint below 0.1 % of its speed limit for this long [s] (not one tick: a reversal crosses zero)
REST_S = 0.1


@dataclass(frozen=True)
class HoldRun:
    """One sequence's outcome (lengths in metres, times in seconds)."""

    seed: int
    overrun: float
    drift: float
    settle_s: float
    travel: float  # tool path length while the stick moved (a sequence that never moved tests nothing)
    ref_step: float = 0.0  # while the stick rests: the largest change of the solver's answer (the joint goal the
    # reference walks to, issue 32 item 5) in one tick, as a fraction of each joint's range (a resting stick's
    # refined answer must stay local)

    @property
    def worst(self) -> float:
        return max(self.overrun, self.drift) if math.isfinite(self.settle_s) else math.inf


def stick_sequence(rng: np.random.Generator, mode: str, segments: int = 3) -> list[tuple[np.ndarray, float]]:
    """Random (stick, seconds) segments: deflections uniform in [−1, 1]³ (some axes centred, some at full
    deflection), 0.05–1.5 s each, some of them brief taps; the last one is the hold: centred in velocity
    mode; in position mode the stick rests, half the time where it was, half the time at a new point."""
    out = []
    for _ in range(segments):
        s = rng.uniform(-1.0, 1.0, 3)
        s[rng.random(3) < 0.25] = 0.0
        full = rng.random(3) < 0.15
        s[full] = np.sign(s[full] + 1e-9)
        length = rng.choice([rng.uniform(0.05, 0.25), rng.uniform(0.25, 1.5)])
        out.append((s, float(length)))
    resting = out[-1][0].copy() if rng.random() < 0.5 else rng.uniform(-1.0, 1.0, 3)
    out.append((np.zeros(3) if mode == "velocity" else resting, -1.0))
    return out


def run_sequence(session, seq, seed: int, rate: float = 1000.0, hold_s: float = 1.0, generations: int | None = None):
    """Drive ``session`` through ``seq`` (from :func:`stick_sequence`) at ``rate`` Hz; a :class:`HoldRun`.

    The solver gets the engine's per-tick budget (40 % of the tick), or with ``generations`` no clock: a GA runs
    that many generations a solve (the same run on any machine, however loaded).  The hold segment runs until the
    joints are at rest, then ``hold_s`` more.  A machine not at rest after crossing its slowest joint's
    whole range, braking twice and 5 s more did not settle.
    """
    dt = 1.0 / rate
    budget = 0.4 * dt
    if generations is not None:
        budget = None
        session.solver.time_budget = None
        if hasattr(session.solver, "max_generations"):
            session.solver.max_generations = generations
    t = 0.0
    robot = session.robot
    brake = np.where(np.isfinite(robot.accel), robot.speed / robot.accel, 0.0)
    settle_limit_s = float(np.max((robot.upper - robot.lower) / robot.speed + 2.0 * brake)) + 5.0
    rest_speed = 1e-3 * robot.speed

    def step(stick, enable=True):
        nonlocal t
        t += dt
        session.feed(InputSample(tuple(float(v) for v in stick), (enable,), "hold-study"), t)
        session.tick(t, dt, solve_budget=budget)

    for enable in (False, True):  # arm: centred with the deadman released, then pressed
        for _ in range(3):
            step((0.0, 0.0, 0.0), enable)
    travel = 0.0
    p_prev = robot.position(session.actuators.q)
    for stick, seconds in seq[:-1]:
        for _ in range(max(1, round(seconds / dt))):
            step(stick)
            p = robot.position(session.actuators.q)
            travel += float(np.linalg.norm(p - p_prev))
            p_prev = p
    stick = seq[-1][0]
    step(stick)  # the stick comes to rest: from here the machine must stop within its braking distance
    if session.mode == "velocity":
        expected = robot.position(session.actuators.stopping_point(dt))
    t0 = t
    settled = math.inf
    span = robot.upper - robot.lower
    q_goal = session.q_goal.copy()
    ref_step = 0.0

    def watch_reference() -> None:
        nonlocal q_goal, ref_step
        ref_step = max(ref_step, float(np.max(np.abs(session.q_goal - q_goal) / span)))
        q_goal = session.q_goal.copy()

    still_since = None  # rest is stillness that lasts REST_S: a joint reversing towards a new answer passes
    while t - t0 < settle_limit_s:  # through zero speed for a tick or two (position mode: 11 m from its answer)
        step(stick)
        watch_reference()
        if np.all(np.abs(session.actuators.qdot) <= rest_speed):
            still_since = t if still_since is None else still_since
            if t - still_since >= REST_S - 0.5 * dt:
                settled = still_since - t0
                break
        else:
            still_since = None
    p_rest = robot.position(session.actuators.q)
    if session.mode == "position":
        expected = robot.position(session.q_ref)
    drift = 0.0
    n_hold = round(hold_s / dt) if math.isfinite(settled) else 0
    for _ in range(n_hold):
        step(stick)
        watch_reference()
        drift = max(drift, float(np.linalg.norm(robot.position(session.actuators.q) - p_rest)))
    if not math.isfinite(settled):
        drift = float(np.linalg.norm(robot.position(session.actuators.q) - p_rest))
    overrun = float(np.linalg.norm(p_rest - expected))
    return HoldRun(seed=seed, overrun=overrun, drift=drift, settle_s=settled, travel=travel, ref_step=ref_step)


def hold_study(
    robot: str,
    solver: str,
    mode: str,
    sequences: int,
    seed: int = 0,
    rate: float = 1000.0,
    progress=None,
    first: int = 0,
    generations: int | None = None,
) -> list[HoldRun]:
    """``sequences`` seeded sequences (numbers ``first`` … ``first + sequences − 1``) on one robot × solver ×
    mode, each on a fresh scene (``generations``: see :func:`run_sequence`)."""
    runs = []
    for k in range(first, first + sequences):
        rng = np.random.default_rng([seed, k])
        ses = Session(robot_name=robot, solver_name=solver, mode=mode, seed=seed + k)
        runs.append(run_sequence(ses, stick_sequence(rng, mode), seed=k, rate=rate, generations=generations))
        if progress is not None:
            progress(k + 1 - first, sequences)
    return runs


CHUNK = 20  # sequences per worker task


def _chunk(task) -> tuple[tuple, list[HoldRun]]:
    case, first, n, seed, rate = task
    return case, hold_study(*case, sequences=n, seed=seed, rate=rate, first=first)


def summarise(case: tuple, runs: list[HoldRun]) -> dict:
    """One case's row: how many sequences held, the largest overrun and drift, the slowest settle."""
    worst = max(runs, key=lambda r: r.worst)
    settled = [r.settle_s for r in runs if math.isfinite(r.settle_s)]
    return {
        "robot": case[0],
        "solver": case[1],
        "mode": case[2],
        "sequences": len(runs),
        "held": sum(r.worst < HOLD_TOLERANCE for r in runs),
        "max_overrun_m": max(r.overrun for r in runs),
        "max_drift_m": max(r.drift for r in runs),
        "max_reference_step": max(r.ref_step for r in runs),
        "worst_m": worst.worst if math.isfinite(worst.worst) else None,  # None: a sequence never came to rest
        "worst_sequence": worst.seed,
        "never_settled": len(runs) - len(settled),
        "max_settle_s": max(settled, default=None),
    }


def bench_hold(
    robots: list[str],
    modes: tuple[str, ...],
    sequences: int,
    seed: int = 0,
    rate: float = 1000.0,
    workers: int = 1,
    progress=None,
    solvers: tuple[str, ...] | None = None,
) -> list[dict]:
    """Every robot × solver (those of ``solvers`` that apply; default all) × mode, ``sequences`` seeded sequences
    each, on ``workers`` processes; one row a case (:func:`summarise`).  ``progress(done, total)`` counts
    sequences."""
    from app.bench.pool import gather
    from app.ik import solvers_for
    from app.models.registry import load_robot

    cases = [
        (r, s, m) for r in robots for s in solvers_for(load_robot(r)) if solvers is None or s in solvers for m in modes
    ]
    tasks = [(c, k, min(CHUNK, sequences - k), seed, rate) for c in cases for k in range(0, sequences, CHUNK)]
    runs = gather(_chunk, tasks, cases, len(cases) * sequences, workers, progress)
    return [summarise(c, runs[c]) for c in cases]
