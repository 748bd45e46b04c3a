"""The crane head's range guard under random sticks (issue 32, item 5's acceptance for the crane-head scene): seeded
stick streams drive the TCP's target through the crane-head engine (:class:`~app.engine.tac_session.TacSession`,
its input pipeline and its 50 Hz tick) against the edges of its mode's range, and every tick is checked.

Each stream: the scene in ``tac`` (the Delta head's range alone) or ``cooperative`` (the crane's with it) by turns,
Hs 1 m beam; armed, then 6–12 segments of 0.5–3 s, each stick deflection uniform in [−1, 1]³ with a third of the
axes at full deflection (the default profile's shaping keeps them), then centred for 0.5 s.

Per tick, from the TCP target's offset before and after it (what the stick moved; the sea moves the TCP, not its
target) and the stick's step as the engine shaped it (its profile, deadzone and speed) before the range guard:

* ``excess`` [m]: how far the offset went past its range on any axis (the range's face is the "collision");
* ``opening`` ticks: the stick's step has no outward component on an axis in the outer quarter (the zone) and at
  least one axis is in it — and of them the least ratio of the target's step to the stick's (1: never slowed; the
  acceptance asks ≥ 0.9);
* ``slowed`` ticks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.bench.guard import stick_stream
from app.engine.tac_session import TacSession
from app.scenarios.tac import TacScenario
from app.teleop.devices import InputSample

DT = 0.02  # [s]: the crane-head engine's 50 Hz
ZONE = 0.25  # the share of each axis's range where its outward part is slowed (app.control.guard.scale_in_box)


@dataclass(frozen=True)
class CraneGuardRun:
    seed: int
    mode: str
    ticks: int
    excess: float  # [m], ≥ 0
    opening: int
    min_opening_speed: float
    opening_slow: int
    slowed: int


def _sample(s, enable: bool = True) -> InputSample:
    return InputSample((float(s[0]), -float(s[1]), float(s[2]), 0.0), (enable, False), "guard-bench")


def run_stream(seed: int) -> CraneGuardRun:
    """One seeded stream on a fresh crane-head engine (see the module's text)."""
    rng = np.random.default_rng([seed, 3252])
    mode = ("tac", "cooperative")[seed % 2]
    ses = TacSession(scenario=TacScenario(duration=1e5, hs=1.0, mode=mode))
    t = 0.0

    def tick(s, enable=True) -> None:
        nonlocal t
        t += DT
        ses.feed(_sample(s, enable), t)
        ses.tick(t, DT)

    asked: list[np.ndarray] = []  # the stick's step of this tick as the engine shaped it, before the range guard
    scaled = ses._scaled

    def watch(dp: np.ndarray) -> np.ndarray:
        asked.append(np.array(dp, dtype=float))
        return scaled(dp)

    ses._scaled = watch
    for enable in (False, True):
        for _ in range(5):
            tick(np.zeros(3), enable)
    limit = np.asarray(ses.target_range[mode], dtype=float)
    ticks = opening = slowed = opening_slow = 0
    excess, min_open = 0.0, 1.0
    segments = stick_stream(rng, 0.5, 3.0) + [(np.zeros(3), 0.5)]
    for s, seconds in segments:
        for _ in range(max(1, round(seconds / DT))):
            off0 = np.array(ses.sim.p_d_n) - ses.sim.p_d_n0
            asked.clear()
            tick(s)
            off1 = np.array(ses.sim.p_d_n) - ses.sim.p_d_n0
            ticks += 1
            excess = max(excess, float(np.max(np.abs(off1) - limit)))
            if not asked:
                continue  # nothing asked (centred, or the shaped stick inside its deadzone)
            want = asked[0]
            got = off1 - off0
            norm = float(np.linalg.norm(want))
            if norm == 0.0:
                continue
            if float(np.linalg.norm(got)) < norm - 1e-12:
                slowed += 1
            gap = limit - np.abs(off0)
            zone = gap < ZONE * limit
            outward = (want * off0 > 0.0) & (np.abs(want) > 1e-15)
            if zone.any() and not np.any(outward & zone):
                opening += 1
                kept = float(np.linalg.norm(got)) / norm
                min_open = min(min_open, kept)
                opening_slow += kept < 0.9
    return CraneGuardRun(seed, mode, ticks, max(excess, 0.0), opening, min_open, opening_slow, slowed)


def _chunk(task) -> tuple[str, list[CraneGuardRun]]:
    first, n = task
    return "crane", [run_stream(k) for k in range(first, first + n)]


def summarise(runs: list[CraneGuardRun]) -> dict:
    return {
        "scene": "crane head (tac and cooperative by turns, Hs 1 m beam)",
        "streams": len(runs),
        "ticks": sum(r.ticks for r in runs),
        "max_excess_m": max(r.excess for r in runs),
        "opening_ticks": sum(r.opening for r in runs),
        "min_opening_speed": min(r.min_opening_speed for r in runs),
        "opening_slow_ticks": sum(r.opening_slow for r in runs),
        "slowed_ticks": sum(r.slowed for r in runs),
        "streams_slowed": sum(r.slowed > 0 for r in runs),
    }


def bench_crane_guard(streams: int, workers: int = 1, progress=None) -> dict:
    """``streams`` seeded streams on ``workers`` processes, summarised (:func:`summarise`)."""
    from app.bench.pool import gather

    chunk = 10
    tasks = [(k, min(chunk, streams - k)) for k in range(0, streams, chunk)]
    return summarise(gather(_chunk, tasks, ["crane"], streams, workers, progress)["crane"])
