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

from app.errors import BosunError

KINDS = ("lab", "tac")
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


def engine_speed(kind: str, seconds: float = 10.0, dt: float = DEFAULT_DT, motion: bool = False) -> dict[str, Any]:
    """Tick a ``kind`` session (``lab`` or ``tac``) for ``seconds`` of simulated time in ticks of ``dt``.

    ``motion`` (lab only): both platforms engaged in waves with VVMC on, instead of the session as it
    starts (platforms settled, Comau REMOTE, winch LOCAL).  Returns the simulated and wall seconds,
    the tick count and ``speed_x_realtime`` (simulated / wall).
    """
    if kind not in KINDS:
        raise SimSpeedError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if not (seconds > 0 and dt > 0):
        raise SimSpeedError(f"seconds and dt must be positive, got {seconds:g} and {dt:g}")
    if motion and kind != "lab":
        raise SimSpeedError("motion applies to the lab plant only")
    from app.models import kernels
    from app.warmup import warm_up

    compile_s = warm_up()
    session = _session(kind, motion)
    n = max(1, round(seconds / dt))
    t = 0.0
    t0 = time.perf_counter()
    for _ in range(n):
        t += dt
        session.tick(t, dt)
    wall = time.perf_counter() - t0
    return {
        "kind": kind,
        "motion": motion,
        "dt": dt,
        "ticks": n,
        "simulated_s": n * dt,
        "wall_s": wall,
        "speed_x_realtime": n * dt / wall,
        "kernels": kernels.ENABLED,
        "warm_up_s": compile_s,
    }
