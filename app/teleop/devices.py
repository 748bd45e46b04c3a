"""Input sources: any joystick through pygame (hot-plug aware), and a manual source.

Every source returns an :class:`InputSample` (raw axes, buttons, device name, time) or
None when no device is connected.  The engine maps samples through a device profile.
"""

from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass, field

from app.errors import require


@dataclass(frozen=True)
class InputSample:
    """One reading of an input device.

    Attributes
    ----------
    axes : tuple of float
        Raw axes in [−1, 1].
    buttons : tuple of bool
    device : str
        Device name (profiles match on it).
    t : float
        ``time.monotonic()`` of the reading [s].
    """

    axes: tuple[float, ...]
    buttons: tuple[bool, ...]
    device: str
    t: float = field(default_factory=time.monotonic)


@dataclass(frozen=True)
class DeviceEvent:
    kind: str  # "added" | "removed"
    device: str
    t: float


class PygameJoysticks:
    """All joysticks SDL sees, through pygame; follows devices being plugged in and out.

    Parameters
    ----------
    select : str or None
        Use the first device whose name contains this (case-insensitive); default the
        first device.

    Notes
    -----
    SDL delivers joystick events through its event queue, which needs a video driver;
    without a display the dummy driver is used (set before pygame is initialised).
    """

    def __init__(self, select: str | None = None) -> None:
        if "DISPLAY" not in os.environ and "WAYLAND_DISPLAY" not in os.environ:
            os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        # SDL would take SIGINT/SIGTERM for its own quit event: the process must stay stoppable by them
        os.environ.setdefault("SDL_NO_SIGNAL_HANDLERS", "1")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        pygame = require("pygame", "joystick", "joystick input")

        self._pg = pygame
        if not pygame.display.get_init():
            pygame.display.init()
        pygame.joystick.init()
        self.select = select
        self._open: dict[int, object] = {}  # instance id -> Joystick
        self.events: list[DeviceEvent] = []
        for i in range(pygame.joystick.get_count()):
            self._add(i, announce=False)

    def _add(self, device_index: int, announce: bool = True) -> None:
        js = self._pg.joystick.Joystick(device_index)
        self._open[js.get_instance_id()] = js
        if announce:
            self.events.append(DeviceEvent("added", js.get_name(), time.monotonic()))

    def devices(self) -> list[str]:
        return [js.get_name() for js in self._open.values()]

    def active(self):
        for js in self._open.values():
            if self.select is None or self.select.lower() in js.get_name().lower():
                return js
        return None

    def poll(self) -> InputSample | None:
        """Process SDL events (hot-plug) and read the selected device; None when none is connected."""
        pg = self._pg
        for ev in pg.event.get((pg.JOYDEVICEADDED, pg.JOYDEVICEREMOVED)):
            if ev.type == pg.JOYDEVICEADDED:
                self._add(ev.device_index)
            else:
                js = self._open.pop(ev.instance_id, None)
                name = js.get_name() if js is not None else f"joystick {ev.instance_id}"
                self.events.append(DeviceEvent("removed", name, time.monotonic()))
        pg.event.pump()
        js = self.active()
        if js is None:
            return None
        axes = tuple(float(js.get_axis(i)) for i in range(js.get_numaxes()))
        buttons = tuple(bool(js.get_button(i)) for i in range(js.get_numbuttons()))
        return InputSample(axes, buttons, js.get_name())

    def buttons_of_all(self) -> list[tuple[str, tuple[bool, ...]]]:
        """(name, buttons) of every open device, after :meth:`poll` (a stop button works on any of them)."""
        return [
            (js.get_name(), tuple(bool(js.get_button(i)) for i in range(js.get_numbuttons())))
            for js in self._open.values()
        ]

    def take_events(self) -> list[DeviceEvent]:
        ev, self.events = self.events, []
        return ev

    def close(self) -> None:
        self._open.clear()


class ManualInput:
    """A source set programmatically: the GUI's keyboard and on-screen stick, scripts, tests.

    Thread-safe; ``set`` stamps the sample with the current time, so a source that is not
    updated goes stale like a silent device.
    """

    def __init__(self, name: str = "manual", n_axes: int = 3, n_buttons: int = 4) -> None:
        self.name = name
        self._lock = threading.Lock()
        self._sample: InputSample | None = InputSample((0.0,) * n_axes, (False,) * n_buttons, name)

    def set(self, axes, buttons=None) -> None:
        with self._lock:
            prev = self._sample
            b = tuple(bool(v) for v in buttons) if buttons is not None else (prev.buttons if prev else ())
            self._sample = InputSample(tuple(float(v) for v in axes), b, self.name)

    def disconnect(self) -> None:
        with self._lock:
            self._sample = None

    def poll(self) -> InputSample | None:
        with self._lock:
            return self._sample
