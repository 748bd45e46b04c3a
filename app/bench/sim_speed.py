"""How fast the engine plants run unthrottled: simulated seconds per wall-clock second.

:func:`engine_speed` ticks a fresh engine session (``lab``: :class:`~app.engine.lab_session.LabSession`,
``tac``: :class:`~app.engine.tac_session.TacSession`) back to back, as the engine loop would at its
default rate (50 Hz for both plants) with no sleep between ticks, and compares the simulated time to
the wall time.  The kernels are compiled (or loaded from the cache) and the session built before
the clock starts.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from app.errors import BosunError

KINDS = ("lab", "tac")
PREDICT_DELAY = 0.2  # s: the delay of the predict case (issue 31's acceptance)
DEFAULT_DT = 0.02  # s: the engine's default tick for the lab and crane-head plants (50 Hz)


class SimSpeedError(BosunError):
    """A speed measurement that cannot run (one line)."""


def _session(kind: str, motion: bool) -> Any:
    if kind == "tac":
        from app.engine.tac_session import TacSession

        return TacSession()
    from app.engine.lab_session import STEP, LabSession

    s = LabSession()
    if motion:  # both platforms raised, then playing their vessels in waves, VVMC on
        for name in s.names:
            s.lab_platform(name, "neutral")
        for _ in range(round(60.0 / STEP)):
            if all(p.status == "neutral" for p in s.lab.platforms):
                break
            s.lab.step(STEP)
        else:
            raise SimSpeedError("the platforms did not reach NEUTRAL within 60 s")
        for name in s.names:
            s.lab_source(name, "simulation")
            s.lab_platform(name, "engage")
        s.lab_vvmc(True)
    return s


def engine_speed(
    kind: str, seconds: float = 10.0, dt: float = DEFAULT_DT, motion: bool = False, predict: bool = False
) -> dict[str, Any]:
    """Tick a ``kind`` session (``lab`` or ``tac``) for ``seconds`` of simulated time in ticks of ``dt``.

    ``motion`` (lab only): both platforms engaged in waves with VVMC on, instead of the session as it
    starts (platforms settled, Comau REMOTE, winch LOCAL).  ``predict`` (tac only): a 0.2 s measurement delay with
    the motion predictor fed forward (issue 31), and the predictor's own time in each tick (``predictor_ms``: p50,
    p99, max; the refit every 10 s is the max).  Returns the simulated and wall seconds, the tick count and
    ``speed_x_realtime`` (simulated / wall).
    """
    if kind not in KINDS:
        raise SimSpeedError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if not (seconds > 0 and dt > 0):
        raise SimSpeedError(f"seconds and dt must be positive, got {seconds:g} and {dt:g}")
    if motion and kind != "lab":
        raise SimSpeedError("motion applies to the lab plant only")
    if predict and kind != "tac":
        raise SimSpeedError("predict applies to the crane-head plant only")
    from app.models import kernels
    from app.warmup import warm_up

    compile_s = warm_up()
    session = _session(kind, motion)
    cost: list[float] = []
    if predict:
        mode = session.mode if session.mode != "off" else "tac"
        session.set_tac_mode("off")
        session.set_tac_delay(PREDICT_DELAY, predict=True)
        session.set_tac_mode(mode)
        foresee = session.sim._foresee

        def timed(meas):
            t_in = time.perf_counter()
            out = foresee(meas)
            cost[-1] += time.perf_counter() - t_in
            return out

        session.sim._foresee = timed
    n = max(1, round(seconds / dt))
    t = 0.0
    t0 = time.perf_counter()
    for _ in range(n):
        t += dt
        cost.append(0.0)
        session.tick(t, dt)
    wall = time.perf_counter() - t0
    extra: dict[str, Any] = {}
    if predict:
        c = np.array(cost[1:]) * 1e3  # the first tick runs the predictor over the sensor's past (its start)
        extra["predictor_ms"] = {
            "p50": float(np.percentile(c, 50)),
            "p99": float(np.percentile(c, 99)),
            "max": float(c.max()),
        }
    return {
        "kind": kind,
        "motion": motion,
        "predict": predict,
        **extra,
        "dt": dt,
        "ticks": n,
        "simulated_s": n * dt,
        "wall_s": wall,
        "speed_x_realtime": n * dt / wall,
        "kernels": kernels.ENABLED,
        "warm_up_s": compile_s,
    }
