"""Device profiles: how a joystick's raw axes and buttons become the universal signal s.

A profile is a TOML file (editable by hand; ``app/teleop/profiles/*.toml`` ship with
Bosun, a user's own can be given by path).  Example::

    name = "Logitech Extreme 3D Pro"
    match = ["Extreme 3D"]          # case-insensitive substrings of the device name
    deadzone = 0.08
    expo = 0.3
    enable_button = 0               # deadman: motion only while held; omit for none
    mode_button = 1                 # optional: toggles position/velocity
    stop_button = 2                 # optional: E-STOP (latches in every engine)

    [axes.x]                        # tool x from raw axis 0
    index = 0
    [axes.y]
    index = 1
    invert = true                   # stick forward gives a negative raw value
    [axes.z]
    index = 2
    [axes.w]                        # optional auxiliary axis (the Motion-Lab winch in REMOTE)
    index = 3

The profile for a device is the first whose ``match`` occurs in its name; unknown devices
get :func:`default_profile`.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from app.errors import BosunError
from app.resources import device_profiles

PROFILE_DIR = device_profiles()  # package data (app/resources.py)
AXES = ("x", "y", "z", "w")


class ProfileError(BosunError):
    """A device profile file that cannot be used."""


@dataclass(frozen=True)
class AxisMap:
    index: int
    invert: bool = False
    scale: float = 1.0


@dataclass(frozen=True)
class DeviceProfile:
    """Mapping of one device model to the signal s = (x, y, z, w) in [−1, 1]⁴ (w: auxiliary axis)."""

    name: str
    match: tuple[str, ...]
    axes: tuple[AxisMap | None, ...]
    deadzone: float = 0.08
    expo: float = 0.0
    enable_button: int | None = None
    mode_button: int | None = None
    path: str | None = None
    stop_button: int | None = None

    def matches(self, device_name: str) -> bool:
        low = device_name.lower()
        return any(m.lower() in low for m in self.match)

    def signal(self, axes: tuple[float, ...]) -> np.ndarray:
        """Raw axes → unshaped s (x, y, z, w): picked, inverted, scaled, clipped to [−1, 1]; missing axes give 0."""
        s = np.zeros(len(AXES))
        for k, a in enumerate(self.axes):
            if a is not None and a.index < len(axes):
                v = float(axes[a.index])
                if np.isfinite(v):
                    s[k] = (-v if a.invert else v) * a.scale
        return np.clip(s, -1.0, 1.0)

    def enabled(self, buttons: tuple[bool, ...]) -> bool:
        """Deadman state: True without an enable button, else whether it is held."""
        if self.enable_button is None:
            return True
        return self.enable_button < len(buttons) and bool(buttons[self.enable_button])


def default_profile(n_axes: int = 3) -> DeviceProfile:
    """For an unknown device: axes 0, 1, 2, 3 as x, y (inverted: forward is +y), z, w; deadman on button 0."""
    axes = tuple(AxisMap(i, invert=(i == 1)) if i < n_axes else None for i in range(len(AXES)))
    return DeviceProfile(name="default", match=(), axes=axes, deadzone=0.1, expo=0.0, enable_button=0)


def _err(path: str, message: str) -> ProfileError:
    return ProfileError(f"{path}: {message}")


def parse_profile(text: str, path: str = "<string>") -> DeviceProfile:
    """Parse a TOML profile; raises :class:`ProfileError` naming the file and the field."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise _err(path, f"TOML syntax error: {err}") from None
    known = {"name", "match", "deadzone", "expo", "enable_button", "mode_button", "stop_button", "axes"}
    unknown = set(data) - known
    if unknown:
        raise _err(path, f"unknown field(s): {', '.join(sorted(unknown))}")
    name = data.get("name")
    if not isinstance(name, str) or not name:
        raise _err(path, "field 'name' must be a non-empty string")
    match = data.get("match", [])
    if not isinstance(match, list) or not all(isinstance(m, str) and m for m in match):
        raise _err(path, "field 'match' must be a list of non-empty strings")

    def number(key: str, lo: float, hi: float, default: float) -> float:
        v = data.get(key, default)
        if isinstance(v, bool) or not isinstance(v, int | float) or not lo <= v <= hi:
            raise _err(path, f"field '{key}' must be a number in [{lo}, {hi}], got {v!r}")
        return float(v)

    def button(key: str) -> int | None:
        v = data.get(key)
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v < 128:
            raise _err(path, f"field '{key}' must be a button index 0..127, got {v!r}")
        return v

    deadzone = number("deadzone", 0.0, 0.95, 0.08)
    expo = number("expo", 0.0, 1.0, 0.0)
    axes_tbl = data.get("axes", {})
    if not isinstance(axes_tbl, dict) or set(axes_tbl) - set(AXES):
        raise _err(
            path, f"[axes] may only have x, y, z, w, got {sorted(axes_tbl) if isinstance(axes_tbl, dict) else axes_tbl}"
        )
    axes: list[AxisMap | None] = []
    for ax in AXES:
        a = axes_tbl.get(ax)
        if a is None:
            axes.append(None)
            continue
        idx = a.get("index")
        if isinstance(idx, bool) or not isinstance(idx, int) or not 0 <= idx < 64:
            raise _err(path, f"axes.{ax}.index must be an axis index 0..63, got {idx!r}")
        inv = a.get("invert", False)
        if not isinstance(inv, bool):
            raise _err(path, f"axes.{ax}.invert must be true or false")
        sc = a.get("scale", 1.0)
        if isinstance(sc, bool) or not isinstance(sc, int | float) or not 0 < sc <= 10:
            raise _err(path, f"axes.{ax}.scale must be a number in (0, 10]")
        axes.append(AxisMap(idx, inv, float(sc)))
    buttons = {k: button(k) for k in ("enable_button", "mode_button", "stop_button")}
    used = [v for v in buttons.values() if v is not None]
    if len(used) != len(set(used)):
        raise _err(path, f"enable_button, mode_button and stop_button must be different buttons, got {buttons}")
    return DeviceProfile(name, tuple(match), tuple(axes), deadzone, expo, path=path, **buttons)


def load_profile(path: str | Path) -> DeviceProfile:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise _err(str(path), f"cannot read profile: {err.strerror or err}") from None
    return parse_profile(text, str(path))


def shipped_profiles() -> list[DeviceProfile]:
    return [load_profile(p) for p in sorted(PROFILE_DIR.glob("*.toml"))]


def profile_for(device_name: str, n_axes: int, profiles: list[DeviceProfile] | None = None) -> DeviceProfile:
    """The first profile matching the device name, else :func:`default_profile`."""
    for prof in profiles if profiles is not None else shipped_profiles():
        if prof.matches(device_name):
            return prof
    return default_profile(n_axes)
