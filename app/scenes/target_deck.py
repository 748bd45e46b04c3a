"""A second vessel's deck as a landing target (issue 30, item 5): ``bosun sim transfer --target vessel`` and the
crane-head engine's vessel target.

:class:`TargetVessel` is the second vessel: its own RAO table and heading to the waves, in the same sea as the
crane's vessel (the components' directions turned into its frame and their phases moved to its place).  The landing
spot moves with its deck; the target frame keeps level axes (:meth:`TargetVessel.deck`).  :class:`VesselDeck` adds
the deck's footprint (a rectangle on the deck around the landing spot) for the load's contact and the drawing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from app.geometry import euler_zyx_to_matrix
from app.marine.vessel import VesselMotion
from app.marine.vessels import vessel_rao
from app.marine.waves import WaveComponents
from app.models.pendulum import G

__all__ = ["TargetVessel", "VesselDeck"]


@dataclass
class TargetVessel:
    """The second vessel: its RAO table and its heading to the waves, at its place in the same sea."""

    rao_name: str | None
    heading_deg: float
    sea: WaveComponents
    wave_heading_deg: float  # the sea's mean heading relative to the supply vessel (whose frame is the world's)
    place: NDArray[np.float64]  # the landing spot in the world (calm water)

    def __post_init__(self) -> None:
        psi = math.radians(self.wave_heading_deg - self.heading_deg)  # the second vessel's yaw in the world
        self.psi = psi
        self.R_n_b_yaw = euler_zyx_to_matrix(np.array([0.0, 0.0, psi]))  # its calm-water frame in {n}
        # its origin: the landing spot straight above/below it, so the deck point in its frame is (0, 0, z)
        self.origin = np.array([self.place[0], self.place[1], 0.0])
        self.deck_b = np.array([0.0, 0.0, self.place[2]])
        s = self.sea
        k = s.omega**2 / G
        shift = k * (self.origin[0] * np.cos(s.direction) + self.origin[1] * np.sin(s.direction))
        own = WaveComponents(s.omega, s.amplitude, s.phase - shift, s.direction - psi)
        self.motion = VesselMotion(vessel_rao(self.rao_name), own)

    def deck(self, t: float) -> tuple[NDArray, NDArray, NDArray]:
        """The landing spot and the deck's up normal in the world at time t, and the target frame's rotation.

        The target frame moves with the landing spot and keeps level axes, the world's (so the operator's x is the
        same on both targets): a hanging load cannot tilt with a deck, and in the deck's own rolling axes the
        commanded point metres above the deck swept sideways with every roll, which the head followed and the
        load swung from (Hs 3 m, seeds 1–2: compensated/off 34 % and 62 % with the deck's axes, 30 % and 54 % level;
        anti-swing 26 %, 37 % against 15 %, 36 %; the Motion-Lab's VVMC, app.scenes.lab.MotionLab.set_work_frame,
        for the same reason)."""
        eta = self._eta(t)
        R_n_b_own = euler_zyx_to_matrix(eta[3:6])  # its body in its calm-water frame
        R = self.R_n_b_yaw @ R_n_b_own
        d = self.origin + self.R_n_b_yaw @ eta[:3] + R @ self.deck_b
        return d, -R[:, 2], np.eye(3)

    def spot_acceleration(self, t: float) -> NDArray[np.float64]:
        """The landing spot's acceleration in the world at time t [m/s²]: the rigid body's point d̈ = η̈₁₋₃ + ϑ̈ × r
        in linear seakeeping (the RAOs' own small-angle theory: the ω² terms of the rotation are second order),
        r the spot in the vessel's frame, turned by its yaw into the world (what its MRU gives the crane)."""
        return self.spot_accelerations(np.array([t]))[0]

    def spot_accelerations(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """:meth:`spot_acceleration` at the times ``t`` (n,), (n, 3): one evaluation of the sea for all."""
        eta_ddot = self.motion.eta_derivatives(np.asarray(t, dtype=float))[2]
        return (eta_ddot[:, :3] + np.cross(eta_ddot[:, 3:6], self.deck_b)) @ self.R_n_b_yaw.T

    def pose(self, t: float) -> tuple[NDArray, NDArray]:
        """The landing spot in the world and the deck's rotation (its body in the world) at time t.  The last two
        are kept: a load step asks for t and t − dt, the next for t + dt and t again (the vessel's motion is a sum
        over every wave component)."""
        cache = self.__dict__.setdefault("_poses", {})
        if t in cache:
            return cache[t]
        eta = self._eta(t)
        R = self.R_n_b_yaw @ euler_zyx_to_matrix(eta[3:6])
        out = (self.origin + self.R_n_b_yaw @ eta[:3] + R @ self.deck_b, R)
        if len(cache) >= 2:
            cache.pop(next(iter(cache)))
        cache[t] = out
        return out

    def spots(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """The landing spot in the world at the times ``t`` (n,), (n, 3): :meth:`pose`'s point, vectorised."""
        eta = self.motion.state(np.asarray(t, dtype=float)).eta
        R = self.R_n_b_yaw @ euler_zyx_to_matrix(eta[:, 3:6])
        return self.origin + eta[:, :3] @ self.R_n_b_yaw.T + R @ self.deck_b

    def _eta(self, t: float) -> NDArray[np.float64]:
        """The vessel's motion at t (a VesselMotion's, or a sea transition's: anything with eta_derivatives)."""
        at = getattr(self.motion, "at", None)
        if at is not None:
            return at(t)[0]
        return self.motion.eta_derivatives(np.array([t]))[0][0]


@dataclass
class VesselDeck:
    """The second vessel's deck as the load's target: a ``half``-sized rectangle on the deck around the landing
    spot.  :meth:`deck` is the load's deck record (present while the load is over the rectangle), with the deck
    point's velocity from its positions at ``t − dt`` and ``t``."""

    vessel: TargetVessel
    half: tuple[float, float] = (3.0, 3.0)

    def over(self, r: NDArray[np.float64], t: float) -> bool:
        d, R = self.vessel.pose(t)
        p = R.T @ (np.asarray(r, dtype=float) - d)
        return abs(float(p[0])) <= self.half[0] and abs(float(p[1])) <= self.half[1]

    def deck(self, r: NDArray[np.float64], t: float, dt: float) -> tuple:
        """(present, the deck point under the load, the up normal, that point's velocity over the last ``dt``)."""
        d, R = self.vessel.pose(t)
        d0, R0 = self.vessel.pose(t - dt)
        p = R.T @ (np.asarray(r, dtype=float) - d)
        present = abs(float(p[0])) <= self.half[0] and abs(float(p[1])) <= self.half[1]
        m = np.array([p[0], p[1], 0.0])  # the deck's material point under the load
        here = d + R @ m
        return (present, here, -R[:, 2], (here - (d0 + R0 @ m)) / dt)

    def corners(self, t: float) -> list[list[float]]:
        d, R = self.vessel.pose(t)
        hx, hy = self.half
        return [(d + R @ np.array([x, y, 0.0])).tolist() for x, y in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]
