"""Joint actuators of a simulated manipulator: first order, within every XML limit."""

from __future__ import annotations

from dataclasses import InitVar, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.models.block import Block
from app.sim import kernels as sim_kernels


def braking_speed(distance: ArrayLike, accel: ArrayLike, dt: float) -> NDArray[np.float64]:
    """Largest speed from which braking at ``accel``, step by step, stops within ``distance``.

    Exact for the discrete steps: braking from v moves dt·Σ_{i=0..m} (v − i·a·dt) with
    m = ⌊v/(a dt)⌋ (the last, partial step included), a continuous increasing function of v that is
    linear in v for each m, so v = (d/dt + a dt m(m+1)/2)/(m+1) on the piece where
    m·a·dt ≤ v ≤ (m+1)·a·dt, i.e. for the largest m with dt·a dt·m(m+1)/2 ≤ d.  The continuous
    formula −a dt/2 + √((a dt/2)² + 2 a d) is only an estimate of it, and braking onto a limit from
    it needed up to 12.5 % more than the acceleration limit (issue 13).  With no acceleration limit
    (inf) the answer is d/dt.
    """
    a = np.asarray(accel, dtype=float)
    d = np.maximum(np.asarray(distance, dtype=float), 0.0)
    finite = np.isfinite(a)
    h = np.where(finite, a, 1.0) * dt
    # m: the largest whole number of full braking steps, dt·h·m(m+1)/2 ≤ d; S(v) = d on its piece
    m = np.floor(np.maximum(np.sqrt(0.25 + 2.0 * d / (h * dt)) - 0.5, 0.0))
    v = (d / dt + 0.5 * h * m * (m + 1.0)) / (m + 1.0)
    return np.where(finite, v, d / dt)


def braking_distance(speed: ArrayLike, accel: ArrayLike, dt: float) -> NDArray[np.float64]:
    """Distance an axis moving at ``speed`` covers while braking at ``accel``, step by step, from the next
    step on: dt·Σ_{i=1..m} (|v| − i·a·dt), m = ⌊|v|/(a·dt)⌋ (signed as the speed; 0 with no acceleration
    limit).  The stopping point q + braking_distance(q̇) is where a hold can keep the axis: a nearer
    reference cannot be reached without overshooting it, a farther one moves the axis after the command
    to stop."""
    v = np.asarray(speed, dtype=float)
    a = np.asarray(accel, dtype=float)
    finite = np.isfinite(a) & (a > 0)
    h = np.where(finite, a, 1.0) * dt
    s = np.abs(v)
    m = np.floor(s / h)
    d = dt * (m * s - 0.5 * h * m * (m + 1.0))
    return np.where(finite, np.sign(v) * np.maximum(d, 0.0), 0.0)


def approach_speed(e: ArrayLike, v_brake: ArrayLike, tau: float) -> NDArray[np.float64]:
    """A servo's speed towards a reference ``e`` ahead [rad or m]: e/τ, bounded by ``v_brake``, the speed
    from which the axis still stops at the reference (:func:`braking_speed` of |e|).

    The proportional law alone asks for speeds an acceleration-limited axis cannot brake from, overshoots,
    and answers its overshoot the same way: a bang-bang oscillation that keeps its energy (issue 26,
    item 1).  With the bound, the approach is time-optimal near the reference and ends there.
    """
    e = np.asarray(e, dtype=float)
    return np.clip(e / tau, -np.asarray(v_brake, dtype=float), v_brake)


def _actuators_reference(x, u, p, dt):
    """The NumPy reference of :data:`JOINT_ACTUATORS` (the kernel: ``app.sim.kernels.actuator_block``)."""
    q, qdot, _ = x
    lower, upper, speed, accel, tau = p
    q_ref = np.clip(np.asarray(u[0], dtype=float), lower, upper)
    e = q_ref - q
    gap = np.abs(e) / dt
    v_des = np.clip(approach_speed(e, braking_speed(np.abs(e), accel, dt), tau), -gap, gap)
    # the admissible speeds: acceleration, speed and exact braking towards each limit (as MotionFilter)
    dv = accel * dt
    hi = np.minimum(np.minimum(qdot + dv, speed), braking_speed(upper - q, accel, dt))
    lo = np.maximum(np.maximum(qdot - dv, -speed), -braking_speed(q - lower, accel, dt))
    v = np.clip(v_des, lo, np.maximum(hi, lo))  # hi < lo only by rounding
    q_new = np.clip(q + v * dt, lower, upper)
    v = (q_new - q) / dt
    return (q_new, v, (v - qdot) / dt), (q_new,)


#: the joint actuators of a simulated arm as a block (app.models.block): the teleop scene's plant
JOINT_ACTUATORS = Block(
    "joint actuators",
    state=("q", "qdot", "qddot"),
    inputs=("q_ref",),
    outputs=("q",),
    params=("lower", "upper", "speed", "accel", "tau"),
    reference=_actuators_reference,
    kernel=sim_kernels.actuator_block,
)


@dataclass(eq=False)
class LimitedAxes:
    """Axes within per-axis limits, as the plants' servos and filters hold them: position limits ``lower``,
    ``upper`` [rad or m] (the object's own copies: a filter may narrow them in place), speed and
    acceleration limits ``speed``, ``accel`` (``inf``: none) and the time constant ``tau`` [s] of the loop
    that tracks a reference; every array C-contiguous float64 (a compiled step has one signature and
    never compiles in a control tick).  ``use_kernels``: step compiled (default when numba is there)."""

    lower: ArrayLike
    upper: ArrayLike
    speed: ArrayLike
    accel: ArrayLike
    tau: float

    def __post_init__(self) -> None:
        self.lower = np.array(self.lower, dtype=float, order="C")
        self.upper = np.array(self.upper, dtype=float, order="C")
        self.speed = np.ascontiguousarray(self.speed, dtype=float)
        self.accel = np.ascontiguousarray(self.accel, dtype=float)
        self.tau = float(self.tau)
        self.use_kernels = sim_kernels.ENABLED

    def rest_state(self, x: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """A state at rest at ``x``: (position clipped into the limits, zero speed, zero acceleration)."""
        x = np.clip(np.asarray(x, dtype=float), self.lower, self.upper)
        return x, np.zeros_like(x), np.zeros_like(x)


@dataclass(eq=False)
class JointActuators(LimitedAxes):
    """Per-joint servo: q̇_des = (q_ref − q)/τ, bounded by the braking speed towards q_ref
    (:func:`approach_speed`), then limited.

    Each step the desired speed is clipped to the intersection of the speed limit, the change
    the acceleration limit allows in one step and the exact discrete braking speed towards each
    position limit (:func:`braking_speed`, the bound :class:`~app.sim.stewart.MotionFilter` uses).
    The position is therefore never driven past a limit, and speed and acceleration stay within
    theirs (up to rounding).
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

    tau: float = 0.05
    q0: InitVar[ArrayLike | None] = None

    def __post_init__(self, q0: ArrayLike | None) -> None:
        super().__post_init__()
        if not self.tau > 0:
            raise ValueError("tau must be positive")
        self.q, self.qdot, self.qddot = self.rest_state(0.5 * (self.lower + self.upper) if q0 is None else q0)
        # the block's parameter record (lower, upper, speed, accel, τ): fixed, so made once, not every tick
        self.params = (self.lower, self.upper, self.speed, self.accel, self.tau)

    def step(self, q_ref: ArrayLike, dt: float) -> NDArray[np.float64]:
        """Advance by dt toward q_ref (one step of :data:`JOINT_ACTUATORS`, compiled unless ``use_kernels`` is
        False); returns the new position."""
        x = (self.q, self.qdot, self.qddot)
        u = (np.ascontiguousarray(q_ref, dtype=float),)
        (self.q, self.qdot, self.qddot), _ = JOINT_ACTUATORS.step(x, u, self.params, float(dt), self.use_kernels)
        return self.q

    def stopping_point(self, dt: float) -> NDArray[np.float64]:
        """Where the joints come to rest braking at their acceleration limits from now (within the limits)."""
        return np.clip(self.q + braking_distance(self.qdot, self.accel, dt), self.lower, self.upper)

    def stop(self) -> None:
        """E-STOP: speed zero now."""
        self.qddot = np.zeros_like(self.q)
        self.qdot = np.zeros_like(self.q)

    def reset(self, q: ArrayLike) -> None:
        self.q, self.qdot, self.qddot = self.rest_state(q)
