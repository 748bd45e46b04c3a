"""The input client: reads a local joystick and streams it to a (possibly remote) engine."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from app.net.transport import Client
from app.teleop.devices import PygameJoysticks


def run_joystick_client(
    url: str,
    *,
    token: str | None = None,
    device: str | None = None,
    rate: float = 100.0,
    duration: float | None = None,
    stop: threading.Event | None = None,
    on_event: Callable[[str], None] | None = None,
    name: str = "joystick",
) -> int:
    """Stream joystick samples as ``input`` messages until stopped; returns the number sent.

    A device that disappears is reported once as ``device_lost`` (the engine then holds
    the robot); when one is plugged in again streaming resumes.
    """
    say = on_event or (lambda text: None)
    sticks = PygameJoysticks(select=device)
    client = Client(url, role="operator", name=name, token=token)
    if client.role != "operator":
        client.close()
        raise RuntimeError(client.note or "the engine did not grant the operator role")
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
                if had_device is not False:
                    client.send("device_lost", device=(had_device or "")[:128] if isinstance(had_device, str) else "")
                    say("no joystick: the engine holds the robot")
                had_device = False
            else:
                client.send_input(sample.axes[:16], sample.buttons[:64], sample.device[:128])
                had_device = sample.device
                sent += 1
            time.sleep(max(0.0, period - (time.monotonic() - t0)))
    finally:
        client.close()
        sticks.close()
    return sent
