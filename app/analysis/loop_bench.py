"""Engine loop benchmark: tick timing and input-to-command latency with real sockets.

The engine runs in its own process, as it does in use; this process hosts one viewer and
one input client sending at 500 Hz over tcp://127.0.0.1.
"""

from __future__ import annotations

import multiprocessing as mp
import threading
import time
from typing import Any

import numpy as np

from app.net.transport import Client


def _engine_process(rate: float, seconds: float, robot: str, solver: str, urls: Any, results: Any) -> None:
    from app.engine.server import EngineServer
    from app.engine.session import Session

    session = Session(robot_name=robot, solver_name=solver, mode="velocity")
    server = EngineServer(session, bind="tcp://127.0.0.1:0", rate=rate, publish_rate=50.0)
    urls.put(server.url)
    try:
        server.run(duration=seconds)
    finally:
        server.close()
        results.put(server.stats.summary())


def bench_loop(
    rate: float = 500.0, seconds: float = 30.0, robot: str = "comau_smart5_3dof", solver: str = "jacobian"
) -> dict[str, Any]:
    """Run the engine at ``rate`` for ``seconds`` with one viewer and one operator sending at 500 Hz.

    The operator sends a slowly varying stick (deadman held) so the solver works every
    tick; latency runs from the client's send time (the system-wide monotonic clock) to
    the end of the engine tick that turned the sample into a joint command.
    """
    ctx = mp.get_context("spawn")
    urls, results = ctx.Queue(), ctx.Queue()
    proc = ctx.Process(target=_engine_process, args=(rate, seconds + 1.0, robot, solver, urls, results), daemon=True)
    proc.start()
    try:
        url = urls.get(timeout=60)
        viewer = Client(url, role="viewer", name="bench-viewer")
        operator = Client(url, role="operator", name="bench-input")
        states = 0
        stop = threading.Event()

        def watch() -> None:
            nonlocal states
            while not stop.is_set():
                if viewer.recv_state(0.2) is not None:
                    states += 1

        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
        t0 = time.monotonic()
        k = 0
        while (now := time.monotonic()) - t0 < seconds:
            phase = 2 * np.pi * 0.1 * (now - t0)
            operator.send_input([0.5 * np.sin(phase), 0.5 * np.cos(phase), 0.2 * np.sin(2 * phase)], [True], "bench")
            k += 1
            time.sleep(max(0.0, t0 + k * 0.002 - time.monotonic()))
        elapsed = time.monotonic() - t0
        stop.set()
        watcher.join(timeout=2)
        viewer.close()
        operator.close()
        loop = results.get(timeout=30)
    finally:
        proc.join(timeout=10)
        if proc.is_alive():
            proc.terminate()
    return {
        "benchmark": "loop",
        "rate_hz": rate,
        "seconds": seconds,
        "robot": robot,
        "solver": solver,
        "loop": loop,
        "viewer_states": states,
        "viewer_rate_hz": states / elapsed,
        "inputs_sent": k,
    }
