"""A real SDL joystick without hardware: SDL's virtual joystick, through pygame's own SDL.

pygame ships SDL 2 (``pygame.libs/libSDL2-2*.so*``); loading that library with ctypes
gives the same SDL instance pygame uses, so a device attached here is seen by
``pygame.joystick`` exactly like a USB joystick (added/removed events included).  Used by
the tests and by ``bosun joystick --virtual`` demonstrations.
"""

from __future__ import annotations

import ctypes
import glob
import os

SDL_JOYSTICK_TYPE_GAMECONTROLLER = 1


def _sdl() -> ctypes.CDLL:
    from app.errors import require

    pygame = require("pygame", "joystick", "the virtual joystick")

    libs = sorted(glob.glob(os.path.join(os.path.dirname(pygame.__file__), "..", "pygame.libs", "libSDL2-2*.so*")))
    if not libs:
        raise RuntimeError("pygame's bundled SDL2 library was not found (pygame.libs/libSDL2-2*.so*)")
    sdl = ctypes.CDLL(libs[0])
    sdl.SDL_JoystickAttachVirtual.restype = ctypes.c_int
    sdl.SDL_JoystickAttachVirtual.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int]
    sdl.SDL_JoystickOpen.restype = ctypes.c_void_p
    sdl.SDL_JoystickOpen.argtypes = [ctypes.c_int]
    sdl.SDL_JoystickClose.argtypes = [ctypes.c_void_p]
    sdl.SDL_JoystickSetVirtualAxis.restype = ctypes.c_int
    sdl.SDL_JoystickSetVirtualAxis.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int16]
    sdl.SDL_JoystickSetVirtualButton.restype = ctypes.c_int
    sdl.SDL_JoystickSetVirtualButton.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint8]
    sdl.SDL_JoystickDetachVirtual.restype = ctypes.c_int
    sdl.SDL_JoystickDetachVirtual.argtypes = [ctypes.c_int]
    sdl.SDL_JoystickUpdate.restype = None
    return sdl


class VirtualJoystick:
    """Attach a virtual joystick; set its axes in [−1, 1] and its buttons; detach to unplug it."""

    def __init__(self, n_axes: int = 4, n_buttons: int = 8) -> None:
        self.sdl = _sdl()
        self.n_axes, self.n_buttons = n_axes, n_buttons
        self.index = self.sdl.SDL_JoystickAttachVirtual(SDL_JOYSTICK_TYPE_GAMECONTROLLER, n_axes, n_buttons, 0)
        if self.index < 0:
            raise RuntimeError("SDL refused to attach a virtual joystick (is the joystick subsystem initialised?)")
        self.handle = self.sdl.SDL_JoystickOpen(self.index)
        if not self.handle:
            raise RuntimeError("SDL could not open the virtual joystick")

    def set_axis(self, axis: int, value: float) -> None:
        raw = round(max(-1.0, min(1.0, value)) * 32767)
        self.sdl.SDL_JoystickSetVirtualAxis(self.handle, axis, raw)

    def set_button(self, button: int, pressed: bool) -> None:
        self.sdl.SDL_JoystickSetVirtualButton(self.handle, button, 1 if pressed else 0)

    def update(self) -> None:
        self.sdl.SDL_JoystickUpdate()

    def detach(self) -> None:
        if self.handle:
            self.sdl.SDL_JoystickClose(self.handle)
            self.handle = None
            self.sdl.SDL_JoystickDetachVirtual(self.index)
