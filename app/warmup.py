"""Compile (or load from numba's on-disk cache) every kernel before an engine's first tick (H43).

Each kernel file lists calls with the argument types its callers pass (``warm_up_steps``); running
them all here, at set-up and before an engine's loop starts, means no control tick ever waits for a
compile.  This module sits above every floor that holds kernels (models, marine, ik, sim, control).
"""

from __future__ import annotations

import time
from collections.abc import Callable


def warm_up(progress: Callable[[int, int], None] | None = None) -> float:
    """Compile (or load) every kernel now, not in a control tick; seconds taken (0 with ``BOSUN_JIT=0``).

    ``progress(k, n)`` is called after each of the n steps."""
    from app.control import tac_kernels
    from app.ik import ga_kernels
    from app.marine import kernels as marine_kernels
    from app.models import crane_head_kernels, kernels
    from app.sim import kernels as sim_kernels

    t0 = time.perf_counter()
    if not kernels.ENABLED:
        return 0.0
    steps = [
        *kernels.warm_up_steps(),
        *marine_kernels.warm_up_steps(),
        *sim_kernels.warm_up_steps(),
        *ga_kernels.warm_up_steps(),
        *crane_head_kernels.warm_up_steps(),
        *tac_kernels.warm_up_steps(),
    ]
    for k, step in enumerate(steps):
        step()
        if progress is not None:
            progress(k + 1, len(steps))
    return time.perf_counter() - t0
