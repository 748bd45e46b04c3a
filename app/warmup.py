"""Compile (or load from numba's on-disk cache) every kernel before an engine's first tick (H43).

Each kernel file lists calls with the argument types its callers pass (``warm_up_steps``); running
them all here, at set-up and before an engine's loop starts, means no control tick ever waits for a
compile.  This module sits above every floor that holds kernels (models, marine, ik, sim, control).

Set-up compiles on every core (``workers``): each kernel file's steps in one process, the files shared
out by their compile time, then this process loads them all from the cache.  A kernel that calls another
file's kernel compiles the callee into its own code and adds no signature, and no cache entry, to the
callee's dispatcher: each cache entry is written by one process only (tests/test_kernels.py checks it).
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable

#: the kernel files, with their share of a cold compile's time on the 2-core VM (s, 2026-11-28: the
#: proportions are what count; a file that calls another file's kernels compiles them into its own code, so
#: the sim and GA files weigh more in a process of their own), used to share them out between processes.
#: Measured from cold: all in one process 97 s; models + crane head + marine beside GA + sim + TAC 48 s and
#: 61 s (62.5 s wall); TAC then moved beside the model files.
KERNEL_MODULES = {
    "app.models.kernels": 30.0,
    "app.marine.kernels": 2.0,
    "app.models.lab_kernels": 4.0,
    "app.sim.kernels": 9.0,
    "app.control.lab_kernels": 6.0,
    "app.scenes.lab_kernels": 10.0,
    "app.ik.ga_kernels": 25.0,
    "app.models.crane_head_kernels": 12.0,
    "app.control.tac_kernels": 2.0,
    "app.sim.head_kernels": 1.0,
    "app.scenes.tac_kernels": 8.0,
    "app.control.antisway_kernels": 20.0,
    "app.control.guard_kernels": 3.0,
    "app.scenes.teleop_kernels": 2.0,
    "app.control.predict_kernels": 1.0,  # 2026-11-29: 50 s cold beside two busy processes; about 20 s alone
    "app.scenes.lab_transfer_kernels": 23.0,  # 2026-11-30: 23 s cold alone (the lab's step compiled into its own)
    "app.scenes.crane_transfer_kernels": 8.0,  # 2026-11-30
}


def _steps(modules) -> list[Callable[[], object]]:
    return [step for name in modules for step in importlib.import_module(name).warm_up_steps()]


def _compile(modules: list[str]) -> float:
    """One worker's share: run the steps of ``modules`` (numba writes each kernel's cache); seconds taken."""
    t0 = time.perf_counter()
    for step in _steps(modules):
        step()
    return time.perf_counter() - t0


def shares(workers: int) -> list[list[str]]:
    """The kernel files shared out among ``workers`` processes, longest first to the least loaded."""
    load = [0.0] * workers
    out: list[list[str]] = [[] for _ in range(workers)]
    for name, seconds in sorted(KERNEL_MODULES.items(), key=lambda kv: -kv[1]):
        k = load.index(min(load))
        out[k].append(name)
        load[k] += seconds
    return [s for s in out if s]


def cold(modules) -> list[str]:
    """The kernel files among ``modules`` with a kernel numba has no fresh cache entry for (a cache it
    would compile), by numba's own index (an unreadable index counts as cold).  Only the kernels Python
    calls count (public names, the ones ``warm_up_steps`` call): a private helper is compiled into its
    callers and has a cache entry of its own only if something once called it directly (a test), so its
    missing index said "cold" after every clearing of stale caches, whatever warm_up had just compiled."""
    import numba

    out = []
    for name in modules:
        module = importlib.import_module(name)
        for f in vars(module).values():
            if isinstance(f, numba.core.registry.CPUDispatcher) and f.__module__ == name and f.__name__[0] != "_":
                try:
                    if not f._cache._cache_file._load_index():  # {} when missing or stale (source changed)
                        out.append(name)
                        break
                except Exception:  # numba's private layout changed: compile as if cold
                    out.append(name)
                    break
    return out


def warm_up(progress: Callable[[int, int], None] | None = None, workers: int = 1) -> float:
    """Compile (or load) every kernel now, not in a control tick; seconds taken (0 with ``BOSUN_JIT=0``).

    ``workers`` > 1 compiles in that many processes first (set-up: a cold cache on several cores); this
    process then loads what they cached.  ``progress(k, n)`` is called after each of the n steps here."""
    from app.models import kernels

    t0 = time.perf_counter()
    if not kernels.ENABLED:
        return 0.0
    kernels.clear_stale()
    if workers > 1 and len(cold(KERNEL_MODULES)) > 1:  # a warm cache loads faster here than processes start
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        parts = shares(workers)
        with ProcessPoolExecutor(len(parts), mp_context=mp.get_context("spawn")) as pool:
            list(pool.map(_compile, parts))
    steps = _steps(KERNEL_MODULES)
    for k, step in enumerate(steps):
        step()
        if progress is not None:
            progress(k + 1, len(steps))
    return time.perf_counter() - t0
