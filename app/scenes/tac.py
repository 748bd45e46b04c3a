"""The crane-head scene (TAC paper §8–10): the head's joint PID (eq. 57) driving its DC motors (eq. 58), with the
cooperative crane and the head references (eqs. 49–56), wired as one diagram (issue 29).

Plants (:mod:`app.sim.head`): the crane's joints, :data:`~app.sim.head.CRANE_JOINTS`, and the DC motors,
:data:`~app.sim.head.HEAD_MOTORS`.  Controllers (:mod:`app.control.tac`): the cooperative crane law,
:data:`~app.control.tac.CRANE_LAW`, and the PID, :data:`~app.control.tac.HEAD_PID`.  The crane servo, law then
joints, is :class:`CraneServo`; the head servo, PID then motors then the integral committed (anti-windup on the
motor's flag of the same step), is :class:`HeadServo`; the whole simulation step after the vessel motion is
compiled in one call (:func:`app.scenes.tac_kernels.tac_chunk`, driven by :class:`app.scenarios.tac.TacSimulator`)
or run block by block in NumPy (the reference), tested equal in ``tests/test_tac_kernels.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.control.tac import CRANE_LAW, HEAD_PID, PidGains
from app.models.crane_head_kernels import c_array
from app.scenes import tac_kernels
from app.sim.head import CRANE_JOINTS, HEAD_MOTORS

__all__ = ["CraneServo", "HeadServo", "PidGains"]


@dataclass
class HeadServo:
    """PID (eq. 57, :data:`~app.control.tac.HEAD_PID`) + first-order DC motors (eq. 58,
    :data:`~app.sim.head.HEAD_MOTORS`) on the three arm angles, the motors saturating in speed.

    The D term uses the motor rate α̇ = (K_DC u − α)/T_DC of eq. (58) with the input being
    computed, so eq. (57) is solved for u:  u (1 + K_d K_DC/T_DC) = K_p α̃ + K_i ∫α̃ + K_d (α̇_ref
    + α/T_DC).  (Using the previous step's input instead puts a factor −K_d K_DC/T_DC = −5 on
    u_{k−1}: a discrete loop that oscillates and diverges.)  The input is limited to the joint range widened
    by ``u_margin``; the motor's speed is limited to ``speed`` (ω_max, the head file's arm speed;
    :func:`app.sim.head.motor_step`), so no arm ever turns faster than its file allows, whatever the reference
    does (a far reference after a mode change or an E-STOP is approached at ω_max).  Anti-windup: the
    integrator stops while the input is limited or the motor runs at its speed limit (the PID's trial integral
    is committed after the motor step, which gives the motor's flag).  The arm angles never leave
    [α_min, α_max] (mechanical stops).

    A (re)start is bumpless: the integrator is set so that K_i ∫α̃ = u = (α + T_DC α̇)/K_DC, the input that
    keeps the motor of eq. (58) moving as it is; with zero error and α̇_ref = α̇ the solved eq. (57) gives
    that u again, so a servo started on its reference follows it without a kick.
    """

    gains: PidGains
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    alpha: NDArray[np.float64]
    speed: ArrayLike | None = None  # ω_max per arm [rad/s]; None: unlimited (eq. 58 alone)
    u_margin: float = math.radians(10.0)
    use_kernels: bool = field(default=tac_kernels.ENABLED, repr=False)  # False: the NumPy reference

    def __post_init__(self) -> None:
        w = np.full(3, np.inf) if self.speed is None else np.broadcast_to(np.asarray(self.speed, dtype=float), (3,))
        if np.any(~(w > 0)):
            raise ValueError(f"arm speed limits must be positive, got {w.tolist()}")
        self.speed = np.array(w, dtype=float)
        self.reset(self.alpha)

    def kernel_args(self) -> tuple:
        """(pid, motors): the parameter records of :data:`~app.control.tac.HEAD_PID` (K_p, K_i, K_d, T_DC, K_DC,
        u_min, u_max) and :data:`~app.sim.head.HEAD_MOTORS` (T_DC, K_DC, α_min, α_max, ω_max), C-contiguous
        float64 (the ``p`` of :func:`app.scenes.tac_kernels.head_servo`)."""
        g = self.gains
        u_lo, u_hi = (self.lower - self.u_margin) / g.k_dc, (self.upper + self.u_margin) / g.k_dc
        t_dc, k_dc = float(g.t_dc), float(g.k_dc)
        pid = (float(g.kp), float(g.ki), float(g.kd), t_dc, k_dc, c_array(u_lo), c_array(u_hi))
        motors = (t_dc, k_dc, c_array(self.lower), c_array(self.upper), c_array(self.speed))
        return pid, motors

    def reset(self, alpha: ArrayLike, alpha_dot: ArrayLike | None = None) -> None:
        """Start at α (and arm rates α̇, default at rest), bumpless (see the class docstring)."""
        g = self.gains
        self.alpha = np.array(alpha, dtype=float)
        rate = (
            np.zeros(3) if alpha_dot is None else np.clip(np.asarray(alpha_dot, dtype=float), -self.speed, self.speed)
        )
        u_lo, u_hi = (self.lower - self.u_margin) / g.k_dc, (self.upper + self.u_margin) / g.k_dc
        self.u = np.clip((self.alpha + g.t_dc * rate) / g.k_dc, u_lo, u_hi)
        self.integral = self.u / g.ki if g.ki != 0 else np.zeros(3)

    def run(
        self, alpha_ref: NDArray[np.float64], alpha_dot_ref: NDArray[np.float64], dt: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Advance len(alpha_ref) steps; returns α (after each step) and u, each (n, 3)."""
        params = self.kernel_args()
        if self.use_kernels:
            x = tuple(np.array(v, dtype=float) for v in (self.alpha, self.integral, self.u))  # fresh: in place
            out = tac_kernels.head_servo(x, (c_array(alpha_ref), c_array(alpha_dot_ref)), params, float(dt))
            self.alpha, self.integral, self.u = x
            return out
        # the reference: the diagram block by block, PID → motors → the integral committed
        pid_p, motor_p = params
        n = alpha_ref.shape[0]
        out_a, out_u = np.empty((n, 3)), np.empty((n, 3))
        alpha, integral, u = (np.array(v, dtype=float) for v in (self.alpha, self.integral, self.u))
        for k in range(n):
            _, (u, trial, limited) = HEAD_PID.reference((integral,), (alpha_ref[k], alpha_dot_ref[k], alpha), pid_p, dt)
            (alpha,), (_, saturated) = HEAD_MOTORS.reference((alpha,), (u,), motor_p, dt)
            integral = np.where(limited | saturated, integral, trial)  # anti-windup: only while input and motor free
            out_a[k], out_u[k] = alpha, u
        self.alpha, self.integral, self.u = alpha, integral, u
        return out_a, out_u


@dataclass
class CraneServo:
    """The crane's joints in cooperative mode: the law :data:`~app.control.tac.CRANE_LAW` (β̇_cmd from the
    share of β_c, its rate and a proportional correction, within speed and braking limits) driving the joints
    :data:`~app.sim.head.CRANE_JOINTS` (rate drives, acceleration-limited, inside their limits)."""

    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    speed: NDArray[np.float64]
    accel: NDArray[np.float64]
    beta: NDArray[np.float64]
    share: float = 1.0
    k_p: float = 1.0
    use_kernels: bool = field(default=tac_kernels.ENABLED, repr=False)  # False: the NumPy reference

    def __post_init__(self) -> None:
        self.beta = np.array(self.beta, dtype=float)
        self.beta_dot = np.zeros(3)

    def kernel_args(self) -> tuple:
        """(law, joints): the parameter records of :data:`~app.control.tac.CRANE_LAW` (β_min, β_max, β̇_max,
        β̈_max, share, k_p) and :data:`~app.sim.head.CRANE_JOINTS` (β_min, β_max, β̈_max), C-contiguous float64
        (the ``crane`` of :mod:`app.scenes.tac_kernels`)."""
        lower, upper, speed, accel = (c_array(x) for x in (self.lower, self.upper, self.speed, self.accel))
        return (lower, upper, speed, accel, float(self.share), float(self.k_p)), (lower, upper, accel)

    def run(
        self, beta_d: NDArray[np.float64], beta_c: NDArray[np.float64], beta_c_dot: NDArray[np.float64], dt: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Advance len(beta_c) steps towards β_d + share (β_c − β_d); returns β and β̇ after each step, each (n, 3)."""
        params = self.kernel_args()
        if self.use_kernels:
            x = (np.array(self.beta, dtype=float), np.array(self.beta_dot, dtype=float))  # fresh: in place
            u = tuple(c_array(v) for v in (beta_d, beta_c, beta_c_dot))
            out = tac_kernels.crane_servo(x, u, params, float(dt))
            self.beta, self.beta_dot = x
            return out
        # the reference: the diagram block by block, law → joints
        law_p, joints_p = params
        n = beta_c.shape[0]
        out_b, out_v = np.empty((n, 3)), np.empty((n, 3))
        x = (self.beta, self.beta_dot)
        for k in range(n):
            _, cmd = CRANE_LAW.reference((), (beta_d, beta_c[k], beta_c_dot[k], x[0]), law_p, dt)
            x, _ = CRANE_JOINTS.reference(x, cmd, joints_p, dt)
            out_b[k], out_v[k] = x
        self.beta, self.beta_dot = x
        return out_b, out_v
