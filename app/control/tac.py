"""Controllers of the crane-head compensation (TAC paper §8, eq. 57) and the cooperative crane.

Joint control: PID on α (eq. 57, Table 4: K_p 10, K_i 60, K_d 1) as a block (:mod:`app.models.block`),
:data:`HEAD_PID`, driving the DC motors of eq. (58) (α/u = K_DC/(T_DC s + 1), T_DC 0.2 s, K_DC 1), which are the
plant :data:`app.sim.head.HEAD_MOTORS`.  The references they follow (eqs. 49–56) come from
:class:`app.models.crane_head.CraneHead`; the scene that wires PID, motors, crane and references is
:mod:`app.scenes.tac` (its :class:`~app.scenes.tac.HeadServo` holds the PID and the motors).

The PID block and the crane servo run compiled (:mod:`app.control.tac_kernels`) unless ``use_kernels`` is
False; the NumPy code here is their reference.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from app.control import tac_kernels
from app.models.block import Block
from app.models.crane_head_kernels import c_array

__all__ = ["HEAD_PID", "CraneServo", "PidGains"]


@dataclass(frozen=True)
class PidGains:
    """Joint PID and DC-motor constants (TAC paper Table 4)."""

    kp: float = 10.0
    ki: float = 60.0
    kd: float = 1.0
    t_dc: float = 0.2  # [s]
    k_dc: float = 1.0


# ----------------------------------------------------------------------------- joint PID
def _pid_reference(x, u, p, dt):
    """The NumPy reference of :data:`HEAD_PID` (the kernel: ``app.control.tac_kernels.head_pid_block``)."""
    kp, ki, kd, t_dc, k_dc, u_lo, u_hi = p
    implicit = 1.0 + kd * k_dc / t_dc
    inv_t = 1.0 / t_dc
    # plain floats per joint: three joints, so Python scalars beat small numpy arrays here
    integral = np.asarray(x[0], dtype=float).tolist()
    ref, ref_dot, alpha, ulo, uhi = (np.asarray(v, dtype=float).tolist() for v in (*u, u_lo, u_hi))
    u_out, trial, limited = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [True, True, True]
    for j in range(3):
        err = ref[j] - alpha[j]
        trial[j] = integral[j] + err * dt
        u_new = (kp * err + ki * trial[j] + kd * (ref_dot[j] + alpha[j] * inv_t)) / implicit  # eq. (57)
        if u_new < ulo[j]:
            u_new = ulo[j]
        elif u_new > uhi[j]:
            u_new = uhi[j]
        else:
            limited[j] = False
        u_out[j] = u_new
    return x, (np.array(u_out), np.array(trial), np.array(limited))


#: the head's joint PID as a block (app.models.block): eq. (57) solved for u with the motor rate of eq. (58).
#: The D term uses the motor rate α̇ = (K_DC u − α)/T_DC with the input being computed, so eq. (57) is solved
#: for u:  u (1 + K_d K_DC/T_DC) = K_p α̃ + K_i ∫α̃ + K_d (α̇_ref + α/T_DC).  (Using the previous step's input
#: instead puts a factor −K_d K_DC/T_DC = −5 on u_{k−1}: a discrete loop that oscillates and diverges.)  The
#: input is limited to [u_min, u_max].  Its state, the integral, is not changed by the step: its output
#: ``trial`` (the integral with this step's error) is committed by the scene right after the motor step,
#: unless ``limited`` or the motor ran at its speed limit (anti-windup, which needs the motor's
#: ``saturated`` flag of the same step: :meth:`app.scenes.tac.HeadServo.run`).
HEAD_PID = Block(
    "head joint PID",
    state=("integral",),
    inputs=("alpha_ref", "alpha_dot_ref", "alpha"),
    outputs=("u", "trial", "limited"),
    params=("kp", "ki", "kd", "t_dc", "k_dc", "u_min", "u_max"),
    reference=_pid_reference,
    kernel=tac_kernels.head_pid_block,
)


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
