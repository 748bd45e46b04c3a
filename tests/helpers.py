"""Small helpers shared by tests."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

#: the source tree is here (lint and layout checks); the core job (scripts/core_job.sh) tests an
#: installed wheel from a copy of tests/ without app/ and ui/
needs_source = pytest.mark.skipif(not (ROOT / "app").is_dir(), reason="needs the checkout's app/ (source checks)")
#: pygame (the ``joystick`` extra) is installed; the core job has none
needs_pygame = pytest.mark.skipif(importlib.util.find_spec("pygame") is None, reason="pygame (bosun[joystick])")
#: PyQt5 (the ``gui`` extra) is installed
needs_qt = pytest.mark.skipif(importlib.util.find_spec("PyQt5") is None, reason="PyQt5 (bosun[gui])")


def random_q(robot, rng: np.random.Generator, n: int) -> np.ndarray:
    """n configurations drawn uniformly inside the joint limits, shape (n, dof)."""
    return rng.uniform(robot.lower, robot.upper, size=(n, robot.n_joints))


# every GUI test waits this long for a condition before failing (busy 2-core CI: issue 14, item 5)
GUI_WAIT = 30_000  # ms


def wait_for(client, predicate, timeout: float = 8.0) -> dict:
    """The first state snapshot (from a protocol Client) that satisfies predicate, within timeout [s]."""
    import time

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        st_ = client.recv_state(0.5)
        if st_ is not None and predicate(st_):
            return st_
    raise AssertionError("state never satisfied the condition")


def arm(client, n_axes: int = 3) -> None:
    """Stick centred with the deadman released, then pressed: the engine arms the input."""
    import time

    for pressed in (False, True):
        for _ in range(5):
            client.send_input([0.0] * n_axes, [pressed], "stick")
            time.sleep(0.005)


def arm_and_hold(client, axes, state_of, flag: str, sends: int = 40) -> dict:
    """Arm, then send ``axes`` with the deadman held until ``state_of()`` shows ``flags[flag]``.

    A starved test thread on a busy machine can let its own input go stale (the engine disarms);
    then it arms again, up to five times.  Returns the last state (the caller asserts on it)."""
    import time

    state = None
    for _attempt in range(5):
        arm(client, len(axes))
        for _ in range(sends):
            client.send_input(list(axes), [True], "stick")
            time.sleep(0.005)
        state = state_of()
        if getattr(state.flags, flag):
            break
    return state


def start_engine(session, rate: float = 200, publish_rate: float | None = None, duration: float = 120.0, **server_kw):
    """An engine for ``session`` on 127.0.0.1 (a free port), run in a daemon thread for at most ``duration`` [s];
    it publishes its state at ``publish_rate`` [Hz], by default min(rate, 50).  Returns (server, thread); stop
    it with :func:`stop_engine`."""
    import threading

    from app.engine.server import EngineServer

    publish_rate = min(rate, 50) if publish_rate is None else publish_rate
    srv = EngineServer(session, bind="tcp://127.0.0.1:0", rate=rate, publish_rate=publish_rate, **server_kw)
    th = threading.Thread(target=srv.run, kwargs={"duration": duration}, daemon=True)
    th.start()
    return srv, th


def stop_engine(srv, th) -> None:
    """Stop an engine from :func:`start_engine`, wait for its thread (5 s at most) and close its sockets."""
    srv.stop()
    th.join(timeout=5)
    srv.close()


def reported_url(proc, lines: int) -> str:
    """The request address that a ``bosun server`` process prints ("requests on tcp://…,"), read from its
    first ``lines`` lines of standard output (a text pipe)."""
    import re

    for _ in range(lines):
        m = re.search(r"requests on (tcp://\S+),", proc.stdout.readline())
        if m:
            return m.group(1)
    raise AssertionError("server did not report its address")


def process_running(pid: int) -> bool:
    """True while the process exists and is not a zombie (Linux /proc)."""
    try:
        with open(f"/proc/{pid}/status", encoding="utf-8") as f:
            return "\nState:\tZ" not in f.read()
    except FileNotFoundError:
        return False
