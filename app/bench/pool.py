"""Seeded benchmark work shared out over processes (``bosun bench guard``, ``bosun bench hold``)."""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable

__all__ = ["gather"]


def gather(
    work: Callable[[tuple], tuple[Hashable, list]],
    tasks: list[tuple],
    keys: Iterable[Hashable],
    total: int,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
) -> dict[Hashable, list]:
    """Every task through ``work`` (a module-level function: ``task`` → (key, results)), in this process or on
    ``workers`` spawned ones, in the tasks' order; the results gathered per key.  ``progress(done, total)`` after
    each task, ``done`` counting results."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    out: dict[Hashable, list] = {k: [] for k in keys}
    done = 0

    def take(key: Hashable, part: list) -> None:
        nonlocal done
        out[key] += part
        done += len(part)
        if progress is not None:
            progress(done, total)

    if workers <= 1:
        for task in tasks:
            take(*work(task))
    else:
        with ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn")) as pool:
            for key, part in pool.map(work, tasks):
                take(key, part)
    return out
