"""Joint actuators of a simulated manipulator: first order, within every XML limit."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


class JointActuators:
    """Per-joint first-order servo: q̇_des = (q_ref − q)/τ, then limited.

    Each step the desired speed is clipped to the speed limit, to the braking speed that
    still stops before the nearest position limit with the acceleration limit, and to the
    change the acceleration limit allows in one step.  The position is therefore never
    driven past a limit, and speed and acceleration stay within theirs (up to rounding).
    E-STOP (:meth:`stop`) zeroes the speed at once: a stop takes priority over the
    acceleration limit.

    Parameters
    ----------
    lower, upper, speed : array_like, shape (n,)
        Position and speed limits [rad or m, rad/s or m/s].
    accel : array_like, shape (n,)
        Acceleration limits; ``inf`` for none.
    tau : float
        Time constant of the position loop [s]; default 0.05.
    q0 : array_like, optional
        Initial position (default mid-range); clipped into the limits.
    """

    def __init__(
        self,
        lower: ArrayLike,
        upper: ArrayLike,
        speed: ArrayLike,
        accel: ArrayLike,
        tau: float = 0.05,
        q0: ArrayLike | None = None,
    ) -> None:
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.speed = np.asarray(speed, dtype=float)
        self.accel = np.asarray(accel, dtype=float)
        if not tau > 0:
            raise ValueError("tau must be positive")
        self.tau = tau
        q = 0.5 * (self.lower + self.upper) if q0 is None else np.asarray(q0, dtype=float)
        self.q = np.clip(q, self.lower, self.upper)
        self.qdot = np.zeros_like(self.q)
        self.qddot = np.zeros_like(self.q)

    def _braking_speed(self, distance: NDArray[np.float64], dt: float) -> NDArray[np.float64]:
        """Largest speed from which decelerating at the limit, step by step, stops within ``distance``.

        Discrete stop distance from v: v·dt·(k+1)/2 with k = v/(a·dt) steps ⇒
        v = −a·dt/2 + sqrt((a·dt/2)² + 2·a·d).
        """
        a = self.accel
        d = np.maximum(distance, 0.0)
        finite = np.isfinite(a)
        half = np.where(finite, a, 0.0) * dt / 2.0
        v = -half + np.sqrt(half**2 + 2.0 * np.where(finite, a, 0.0) * d)
        return np.where(finite, v, d / dt)

    def step(self, q_ref: ArrayLike, dt: float) -> NDArray[np.float64]:
        """Advance by dt toward q_ref; returns the new position."""
        q_ref = np.clip(np.asarray(q_ref, dtype=float), self.lower, self.upper)
        v = (q_ref - self.q) / self.tau
        v = np.clip(v, -self.speed, self.speed)
        v = np.minimum(v, self._braking_speed(self.upper - self.q, dt))
        v = np.maximum(v, -self._braking_speed(self.q - self.lower, dt))
        # never overshoot the reference within one step
        v = np.clip(v, -np.abs(q_ref - self.q) / dt, np.abs(q_ref - self.q) / dt)
        dv = np.clip(v - self.qdot, -self.accel * dt, self.accel * dt)
        v = self.qdot + dv
        q_new = np.clip(self.q + v * dt, self.lower, self.upper)
        v = (q_new - self.q) / dt
        self.qddot = (v - self.qdot) / dt
        self.q, self.qdot = q_new, v
        return self.q

    def stop(self) -> None:
        """E-STOP: speed zero now."""
        self.qddot = np.zeros_like(self.q)
        self.qdot = np.zeros_like(self.q)

    def reset(self, q: ArrayLike) -> None:
        self.q = np.clip(np.asarray(q, dtype=float), self.lower, self.upper)
        self.qdot = np.zeros_like(self.q)
        self.qddot = np.zeros_like(self.q)
