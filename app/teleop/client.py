"""The input client: reads a local joystick and streams it to a (possibly remote) engine."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from app.net.link import EngineConnection, connect
from app.net.security import ClientCurve
from app.teleop.devices import PygameJoysticks

LOST_AFTER = 1.0  # s without a state: the engine is lost (the connection says hello again by itself)
FIND_DEVICE = 1.0  # s to wait for SDL to list a joystick at start-up


class NoDeviceError(RuntimeError):
    """No joystick at start-up: nothing to stream."""


class RoleLostError(RuntimeError):
    """The engine says this client is no longer its operator."""


def run_joystick_client(
    url: str,
    *,
    token: str | None = None,
    curve: ClientCurve | None = None,
    device: str | None = None,
    rate: float = 100.0,
    duration: float | None = None,
    stop: threading.Event | None = None,
    on_event: Callable[[str], None] | None = None,
    name: str = "joystick",
) -> int:
    """Stream joystick samples as ``input`` messages until stopped; returns the number sent.

    With no joystick at start-up it raises :class:`NoDeviceError` before taking the operator
    role.  A device that disappears later is reported once as ``device_lost`` (the engine then
    holds the robot); the client keeps its role with keep-alive pings until one is plugged in
    again.  When the engine refuses input because the role has gone to someone else it raises
    :class:`RoleLostError` with the engine's reason.
    """
    say = on_event or (lambda text: None)
    sticks = PygameJoysticks(select=device)
    deadline = time.monotonic() + FIND_DEVICE
    while sticks.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    if sticks.poll() is None:
        sticks.close()
        which = f" matching '{device}'" if device else ""
        raise NoDeviceError(f"no joystick{which} found; plug one in (or try --virtual)")
    conn = connect(url, role="operator", name=name, token=token, curve=curve, lost_after=LOST_AFTER)
    if conn.role != "operator":
        conn.stop()
        conn.join(timeout=2)
        conn.client.close()
        sticks.close()
        raise RuntimeError(conn.client.note or "the engine did not grant the operator role")
    stop = stop or threading.Event()
    period = 1.0 / rate
    end = time.monotonic() + duration if duration is not None else float("inf")
    sent, had_device = 0, None
    try:
        while not stop.is_set() and time.monotonic() < end:
            t0 = time.monotonic()
            sample = sticks.poll()
            for ev in sticks.take_events():
                say(f"{ev.device} {ev.kind}")
            if sample is None:
                if had_device is not False:  # once: the engine holds; the connection's pings keep the role
                    conn.clear_input(had_device if isinstance(had_device, str) else "", released=False)
                    say("no joystick: the engine holds the robot; waiting for one (the role is kept)")
                had_device = False
            else:
                conn.set_input(sample.axes[:16], sample.buttons[:64], sample.device[:128])
                had_device = sample.device
                sent += 1
            _check_events(conn, say)
            time.sleep(max(0.0, period - (time.monotonic() - t0)))
    finally:
        conn.stop()
        conn.join(timeout=2)
        if not conn.is_alive():  # never close sockets a running thread still uses
            conn.client.close()
        sticks.close()
    return sent


def _check_events(conn: EngineConnection, say: Callable[[str], None]) -> None:
    """Raise RoleLostError on the engine's refusal of our input; say when the engine is lost or back."""
    while conn.events:
        ev = conn.events.popleft()
        if ev[0] == "reply" and not ev[2] and ev[1] in ("input", "device_lost"):
            raise RoleLostError(ev[3] or "the engine refused our input")
        if ev[0] == "conn":
            say(ev[2])
