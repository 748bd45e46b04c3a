"""From a universal input signal to a tool-point target (Sanfilippo et al. §III-A).

Pure functions on arrays, no state.  The input device sends a vector s with no
semantics, each component in [−1, 1]; it is shaped (deadzone, expo) and then read as

* position mode, eq. (1):  x_ds = k_p ⊙ s + x_w     (x_w: the shifted workspace origin)
* velocity mode, eq. (2):  ẋ_ds = k_v ⊙ s,  and the target x_t = x_a + ẋ_ds Δt (eq. 7).

Released stick (s = 0): position mode returns to x_w (the tool's starting point), velocity
mode commands zero speed and holds, as the paper describes.  Defaults come from the
robot's workspace box, so any robot defined in XML can be driven with no tuning.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.net.messages import FRAMES  # noqa: F401  (the frames, as the wire names them)

MODES = ("position", "velocity")


def apply_deadzone(s: ArrayLike, deadzone: float) -> NDArray[np.float64]:
    """Zero inside |s| ≤ deadzone, rescaled outside so the output still spans [−1, 1] continuously.

    f(s) = sign(s) (|s| − d) / (1 − d) for |s| > d, else 0.
    """
    s = np.clip(np.asarray(s, dtype=float), -1.0, 1.0)
    if not 0.0 <= deadzone < 1.0:
        raise ValueError(f"deadzone must be in [0, 1), got {deadzone}")
    mag = np.maximum(np.abs(s) - deadzone, 0.0) / (1.0 - deadzone)
    return np.sign(s) * mag


def apply_expo(s: ArrayLike, expo: float) -> NDArray[np.float64]:
    """Expo curve (1 − e) s + e s³: finer control near the centre, full output at ±1; e in [0, 1]."""
    if not 0.0 <= expo <= 1.0:
        raise ValueError(f"expo must be in [0, 1], got {expo}")
    s = np.asarray(s, dtype=float)
    return (1.0 - expo) * s + expo * s**3


def shape_input(s: ArrayLike, deadzone: float = 0.0, expo: float = 0.0) -> NDArray[np.float64]:
    """Deadzone then expo; non-finite components become 0 (a broken axis commands nothing)."""
    s = np.nan_to_num(np.asarray(s, dtype=float), nan=0.0, posinf=0.0, neginf=0.0)
    return apply_expo(apply_deadzone(s, deadzone), expo)


def position_target(s: ArrayLike, k_p: ArrayLike, x_w: ArrayLike) -> NDArray[np.float64]:
    """Eq. (1): x_ds = k_p s + x_w [m]; k_p [m per unit deflection], scalar or per axis."""
    return np.asarray(k_p, dtype=float) * np.asarray(s, dtype=float) + np.asarray(x_w, dtype=float)


def velocity_command(s: ArrayLike, k_v: ArrayLike) -> NDArray[np.float64]:
    """Eq. (2): ẋ_ds = k_v s [m/s]; k_v [m/s per unit deflection], scalar or per axis."""
    return np.asarray(k_v, dtype=float) * np.asarray(s, dtype=float)


def in_frame(v: ArrayLike, R_world_frame: NDArray[np.float64] | None) -> NDArray[np.float64]:
    """A command ``v`` given in the operator's frame, in the world: R_w^F v (None: the world frame itself, ``v``
    as it is).  Eqs. (1) and (2) then hold in that frame: x_ds = x_w + R (k_p ⊙ s) and ẋ_ds = R (k_v ⊙ s)."""
    v = np.asarray(v, dtype=float)
    return v if R_world_frame is None else np.asarray(R_world_frame, dtype=float) @ v


def velocity_target(x_a: ArrayLike, xdot_ds: ArrayLike, dt: float) -> NDArray[np.float64]:
    """Eq. (7): x_t = x_a + ẋ_ds Δt [m]."""
    return np.asarray(x_a, dtype=float) + np.asarray(xdot_ds, dtype=float) * dt


@dataclass(frozen=True)
class Scaling:
    """Workspace scaling of one robot: k_p [m], x_w [m], k_v [m/s], each per axis (x, y, z)."""

    k_p: tuple[float, float, float]
    x_w: tuple[float, float, float]
    k_v: tuple[float, float, float]

    def with_origin(self, x_w: ArrayLike) -> Scaling:
        return replace(self, x_w=tuple(float(v) for v in np.asarray(x_w, dtype=float)))

    def validate(self) -> Scaling:
        for name in ("k_p", "x_w", "k_v"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be 3 finite numbers, got {getattr(self, name)!r}")
        if np.any(np.asarray(self.k_p) < 0) or np.any(np.asarray(self.k_v) < 0):
            raise ValueError("k_p and k_v must not be negative")
        return self


def default_scaling(box, start: ArrayLike, position_fraction: float = 0.25, speed_fraction: float = 0.05) -> Scaling:
    """Defaults from the workspace box: full deflection moves ±25 % of the box's smallest side in
    position mode, and 5 % of the box diagonal per second in velocity mode; x_w is the start point.

    The same fraction on every axis keeps the input isotropic (a diagonal stick is a
    diagonal tool motion) whatever the box's aspect ratio.
    """
    k_p = position_fraction * float(np.min(box.extent))
    k_v = speed_fraction * box.diagonal
    return Scaling((k_p,) * 3, tuple(float(v) for v in np.asarray(start, dtype=float)), (k_v,) * 3).validate()
