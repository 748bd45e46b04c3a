"""Joint control of the crane-head compensation (TAC paper §8, eqs. 57–58) and the cooperative crane.

Joint control: PID on α (eq. 57, Table 4: K_p 10, K_i 60, K_d 1) driving DC motors modelled as
α/u = K_DC/(T_DC s + 1) (eq. 58, T_DC 0.2 s, K_DC 1), discretised exactly (zero-order hold), their speed
saturating at the head file's arm speed (90°/s for ``robots/tac_delta_head.xml``).  The
references they follow (eqs. 49–56) come from :class:`app.models.crane_head.CraneHead`.

Both servos run compiled (:mod:`app.control.tac_kernels`) unless ``use_kernels`` is False; the NumPy
code here is their reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.control import tac_kernels
from app.models.crane_head_kernels import c_array


@dataclass(frozen=True)
class PidGains:
    """Joint PID and DC-motor constants (TAC paper Table 4)."""

    kp: float = 10.0
    ki: float = 60.0
    kd: float = 1.0
    t_dc: float = 0.2  # [s]
    k_dc: float = 1.0


# ----------------------------------------------------------------------------- joint servo
def motor_step(
    alpha: float, u: float, a: float, b: float, t_dc: float, k_dc: float, w_max: float, dt: float
) -> tuple[float, bool]:
    """One zero-order-hold step of the DC motor of eq. (58) whose speed saturates at ±``w_max``.

    Eq. (58) in the time domain is α̇ = (K_DC u − α)/T_DC; a real motor's speed saturates (its back-EMF
    reaches the supply), so here α̇ = sat((K_DC u − α)/T_DC, ±ω_max), solved exactly over the step with u
    held: while |K_DC u − α| > T_DC ω_max the arm turns at ω_max, then it follows the exponential of eq.
    (58).  Unsaturated the step is eq. (58)'s exact discretisation α⁺ = a α + b u (a = e^{−dt/T_DC},
    b = (1 − a) K_DC).  Either way |α⁺ − α| ≤ ω_max dt.  Returns (α⁺, whether the speed saturated).
    """
    d = k_dc * u - alpha  # T_DC α̇ of eq. (58)
    band = t_dc * w_max
    if -band <= d <= band:
        return a * alpha + b * u, False  # eq. (58), zero-order hold
    s = 1.0 if d > 0.0 else -1.0
    t_fast = (abs(d) - band) / w_max  # time at the speed limit
    if t_fast >= dt:
        return alpha + s * w_max * dt, True
    return k_dc * u - s * band * math.exp(-(dt - t_fast) / t_dc), True


@dataclass
class HeadServo:
    """PID (eq. 57) + first-order DC motors (eq. 58) on the three arm angles, the motors saturating in speed.

    The D term uses the motor rate α̇ = (K_DC u − α)/T_DC of eq. (58) with the input being
    computed, so eq. (57) is solved for u:  u (1 + K_d K_DC/T_DC) = K_p α̃ + K_i ∫α̃ + K_d (α̇_ref
    + α/T_DC).  (Using the previous step's input instead puts a factor −K_d K_DC/T_DC = −5 on
    u_{k−1}: a discrete loop that oscillates and diverges.)  The input is limited to the joint range widened
    by ``u_margin``; the motor's speed is limited to ``speed`` (ω_max, the head file's arm speed;
    :func:`motor_step`), so no arm ever turns faster than its file allows, whatever the reference does
    (a far reference after a mode change or an E-STOP is approached at ω_max).  Anti-windup: the integrator
    stops while the input is limited or the motor runs at its speed limit.  The arm angles never leave
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
        """(K_p, K_i, K_d, T_DC, K_DC, u_min, u_max, α_min, α_max, ω_max): ``pid`` of :mod:`app.control.tac_kernels`."""
        g = self.gains
        u_lo, u_hi = (self.lower - self.u_margin) / g.k_dc, (self.upper + self.u_margin) / g.k_dc
        bounds = (u_lo, u_hi, self.lower, self.upper, self.speed)
        return (float(g.kp), float(g.ki), float(g.kd), float(g.t_dc), float(g.k_dc)) + tuple(c_array(x) for x in bounds)

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
        if self.use_kernels:
            alpha, integral, u = (np.array(x, dtype=float) for x in (self.alpha, self.integral, self.u))
            ref, ref_dot = c_array(alpha_ref), c_array(alpha_dot_ref)
            out = tac_kernels.head_servo(self.kernel_args(), float(dt), ref, ref_dot, alpha, integral, u)
            self.alpha, self.integral, self.u = alpha, integral, u
            return out
        g = self.gains
        a = math.exp(-dt / g.t_dc)
        b = (1.0 - a) * g.k_dc
        u_lo, u_hi = (self.lower - self.u_margin) / g.k_dc, (self.upper + self.u_margin) / g.k_dc
        lo, hi = self.lower, self.upper
        n = alpha_ref.shape[0]
        out_a = np.empty((n, 3))
        out_u = np.empty((n, 3))
        implicit = 1.0 + g.kd * g.k_dc / g.t_dc
        kp, ki, kd, t_dc, k_dc, inv_t = g.kp, g.ki, g.kd, g.t_dc, g.k_dc, 1.0 / g.t_dc
        # plain floats per joint: three joints, so Python scalars beat small numpy arrays here
        ref, ref_dot = alpha_ref.tolist(), alpha_dot_ref.tolist()
        alpha, integral, u = self.alpha.tolist(), self.integral.tolist(), self.u.tolist()
        ulo, uhi, lo_, hi_, w_max = u_lo.tolist(), u_hi.tolist(), lo.tolist(), hi.tolist(), self.speed.tolist()
        for k in range(n):
            rk, rdk = ref[k], ref_dot[k]
            for j in range(3):
                err = rk[j] - alpha[j]
                trial = integral[j] + err * dt
                u_new = (kp * err + ki * trial + kd * (rdk[j] + alpha[j] * inv_t)) / implicit  # eq. (57)
                limited = True
                if u_new < ulo[j]:
                    u_new = ulo[j]
                elif u_new > uhi[j]:
                    u_new = uhi[j]
                else:
                    limited = False
                u[j] = u_new
                a_new, fast = motor_step(alpha[j], u_new, a, b, t_dc, k_dc, w_max[j], dt)  # eq. (58), ω-limited
                if not (limited or fast):
                    integral[j] = trial  # anti-windup: integrate only while input and motor are free
                alpha[j] = lo_[j] if a_new < lo_[j] else hi_[j] if a_new > hi_[j] else a_new
            out_a[k] = alpha
            out_u[k] = u
        alpha, integral, u = np.array(alpha), np.array(integral), np.array(u)
        self.alpha, self.integral, self.u = alpha, integral, u
        return out_a, out_u


# ----------------------------------------------------------------------------- cooperative crane
@dataclass
class CraneServo:
    """Crane joints in cooperative mode: they take the slow, large part of the compensation.

    The crane follows a share ``share`` of the full-compensation configuration β_c (the elbow
    IK with L2 + x_d that keeps the TCP on p_d^n, §8) around the nominal β_d, with the target's
    rate as feed-forward and a proportional correction ``k_p`` [1/s]:

        β̇_cmd = s β̇_c + k_p (β_d + s (β_c − β_d) − β),

    limited to each joint's speed and acceleration and kept inside its position limits.  The head
    takes the rest, through the crane terms of eqs. (49)–(54).
    """

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
        """(β_min, β_max, β̇_max, β̈_max, share, k_p): the ``crane`` of :mod:`app.control.tac_kernels`."""
        limits = (self.lower, self.upper, self.speed, self.accel)
        return tuple(c_array(x) for x in limits) + (float(self.share), float(self.k_p))

    def run(
        self, beta_d: NDArray[np.float64], beta_c: NDArray[np.float64], beta_c_dot: NDArray[np.float64], dt: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Advance len(beta_c) steps; returns β and β̇ after each step, each (n, 3)."""
        if self.use_kernels:
            beta, beta_dot = np.array(self.beta, dtype=float), np.array(self.beta_dot, dtype=float)
            args = (c_array(x) for x in (beta_d, beta_c, beta_c_dot))
            out = tac_kernels.crane_servo(self.kernel_args(), *args, float(dt), beta, beta_dot)
            self.beta, self.beta_dot = beta, beta_dot
            return out
        n = beta_c.shape[0]
        out_b = np.empty((n, 3))
        out_v = np.empty((n, 3))
        s, kp = self.share, self.k_p
        beta, bdot = self.beta, self.beta_dot
        dv = self.accel * dt
        for k in range(n):
            target = beta_d + s * (beta_c[k] - beta_d)
            cmd = s * beta_c_dot[k] + kp * (target - beta)
            cmd = np.minimum(np.maximum(cmd, -self.speed), self.speed)
            # braking distance: never run into a position limit faster than the deceleration allows
            room_hi = np.sqrt(2 * self.accel * np.maximum(self.upper - beta, 0.0))
            room_lo = -np.sqrt(2 * self.accel * np.maximum(beta - self.lower, 0.0))
            cmd = np.minimum(np.maximum(cmd, room_lo), room_hi)
            bdot = bdot + np.clip(cmd - bdot, -dv, dv)
            beta = np.minimum(np.maximum(beta + bdot * dt, self.lower), self.upper)
            out_b[k] = beta
            out_v[k] = bdot
        self.beta, self.beta_dot = beta, bdot
        return out_b, out_v
