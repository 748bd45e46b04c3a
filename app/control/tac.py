"""Controllers of the crane-head compensation (TAC paper §8, eq. 57) and the cooperative crane's law.

Joint control: PID on α (eq. 57, Table 4: K_p 10, K_i 60, K_d 1) as a block (:mod:`app.models.block`),
:data:`HEAD_PID`, driving the DC motors of eq. (58) (α/u = K_DC/(T_DC s + 1), T_DC 0.2 s, K_DC 1), which are the
plant :data:`app.sim.head.HEAD_MOTORS`.  The references they follow (eqs. 49–56) come from
:class:`app.models.crane_head.CraneHead`; the scene that wires PID, motors, crane and references is
:mod:`app.scenes.tac` (its :class:`~app.scenes.tac.HeadServo` holds the PID and the motors, its
:class:`~app.scenes.tac.CraneServo` the crane law, :data:`CRANE_LAW`, and the crane's joints).

The blocks run compiled (:mod:`app.control.tac_kernels`) unless kernels are off; the NumPy code here is their
reference.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.control import tac_kernels
from app.models.block import Block

__all__ = ["CRANE_AHC", "CRANE_LAW", "HEAD_PID", "PidGains"]


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
def _crane_law_reference(x, u, p, dt):
    """The NumPy reference of :data:`CRANE_LAW` (the kernel: ``app.control.tac_kernels.crane_law_block``)."""
    beta_d, beta_c, beta_c_dot, beta = u
    lower, upper, speed, accel, share, k_p = p
    target = beta_d + share * (beta_c - beta_d)
    cmd = share * beta_c_dot + k_p * (target - beta)
    cmd = np.minimum(np.maximum(cmd, -speed), speed)
    # braking distance: never run into a position limit faster than the deceleration allows
    room_hi = np.sqrt(2 * accel * np.maximum(upper - beta, 0.0))
    room_lo = -np.sqrt(2 * accel * np.maximum(beta - lower, 0.0))
    return x, (np.minimum(np.maximum(cmd, room_lo), room_hi),)


#: the crane's joints in cooperative mode, as a block (app.models.block): they take the slow, large part of the
#: compensation.  The crane follows a share ``share`` of the full-compensation configuration β_c (the elbow IK
#: with L2 + x_d that keeps the TCP on p_d^n, §8) around the nominal β_d, with the target's rate as
#: feed-forward and a proportional correction ``k_p`` [1/s]:
#:
#:     β̇_cmd = s β̇_c + k_p (β_d + s (β_c − β_d) − β),
#:
#: limited to each joint's speed and to the speed from which it still brakes before its position limits.  The
#: joints that follow it are the plant :data:`app.sim.head.CRANE_JOINTS`; the head takes the rest of the
#: compensation, through the crane terms of eqs. (49)–(54).
CRANE_LAW = Block(
    "cooperative crane law",
    state=(),
    inputs=("beta_d", "beta_c", "beta_c_dot", "beta"),
    outputs=("beta_dot_cmd",),
    params=("lower", "upper", "speed", "accel", "share", "k_p"),
    reference=_crane_law_reference,
    kernel=tac_kernels.crane_law_block,
)


# ----------------------------------------------------------------------------- the crane's winch (issue 30, item 3)
def _crane_ahc_reference(x, u, p, dt):
    """The NumPy reference of :data:`CRANE_AHC` (no kernel yet: one call per step from Python)."""
    (z_target, has_target, L_ride) = x
    track, speed_cmd, L, (z_tcp, z_tcp_dot), (g, g_dot) = u
    (speed,) = p
    s = min(max(float(speed_cmd), -speed), speed)
    if not track:  # the operator's speed pays out (positive) or hauls in; a later AHC holds the hook where it is then
        return (z_target, False, L_ride), (L + s * dt, s)
    if not has_target:  # hold the hook where it hangs now, in the world
        z_target, has_target, L_ride = z_tcp + L, True, L
    z_target = z_target + s * dt  # paying out lowers the hook in the world (NED: z down)
    if g >= 1.0:
        return (z_target, has_target, L_ride), (z_target - z_tcp, s - z_tcp_dot)
    L_ride = L_ride + s * dt  # easing in (H108): from riding the TCP (L_ride) to held in the world
    d = z_target - z_tcp - L_ride
    return (z_target, has_target, L_ride), (L_ride + g * d, s - g * z_tcp_dot + g_dot * d)


#: the crane winch's active heave compensation (the field's standard: the wire paid out and hauled in against
#: the suspension point's heave so the hook keeps its height in the world, e.g. Küchler et al., "Active
#: control for an offshore crane using prediction of the vessel's motion", IEEE/ASME Trans. Mechatronics 16(2),
#: 2011), in {n} (NED, z down):
#:
#:     L_ref = z_h* − z_tcp,   L̇_ref = ż_h* − ż_tcp,   ż_h* = the operator's winch speed,
#:
#: the hook L below the TCP (small swing; the wire's angle is the anti-swing law's).  Off (``track`` False) the
#: operator's speed drives the drum.  Switched on or off under a hanging load it fades (H108: at once, the drum's
#: step from riding the TCP's heave to holding the hook rang the wire to 1.44× the load's weight): with the gain g
#: of the input ``ease`` = (g, ġ) going from 0 to 1 (or 1 to 0), L_ref = L_r + g (z_h* − z_tcp − L_r) and its
#: rate, L_r the length riding the TCP (the length when tracking began or the fade out did, plus the operator's
#: payout).  The drum that follows is
#: the plant :data:`app.sim.motionlab.WINCH_DRUM`.
CRANE_AHC = Block(
    "crane winch law (active heave compensation)",
    state=("z_target", "has_target", "L_ride"),
    inputs=("track", "speed_cmd", "L", "tcp_z", "ease"),
    outputs=("L_ref", "L_dot_ref"),
    params=("speed",),
    reference=_crane_ahc_reference,
)
