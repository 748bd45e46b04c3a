"""Compiled controllers of the crane-head compensation (TAC paper §8): the cooperative crane servo and the
head's joint PID (eq. 57).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path).  The NumPy code stays the reference, tested equal on the same seeded inputs: ``CraneServo.run``
(:mod:`app.control.tac`) in ``tests/test_tac_kernels.py``, the PID block :data:`app.control.tac.HEAD_PID` in
``tests/test_blocks.py``.  The plant the PID drives, the DC motors of eq. (58), is :mod:`app.sim.head_kernels`;
the scene that wires them with the crane, the head references and the head's kinematics (and the whole
simulation step, ``tac_chunk``) is :mod:`app.scenes.tac_kernels`.  Every array argument is C-contiguous
float64, and

* ``crane``: (β_min, β_max, β̇_max, β̈_max, share, k_p) of the cooperative crane servo;
* the PID's parameters: (K_p, K_i, K_d, T_DC, K_DC, u_min, u_max) of eqs. (57)–(58).
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit

__all__ = [
    "ENABLED",
    "crane_servo",
    "head_pid_block",
    "warm_up_steps",
]


# ----------------------------------------------------------------------------- crane servo
@_jit
def _crane_step(crane, beta_d, beta_c, beta_c_dot, dt, beta, beta_dot):
    """One step of the cooperative crane (``CraneServo``): β̇_cmd = s β̇_c + k_p (β_d + s (β_c − β_d) − β),
    limited in speed, braking distance and acceleration; β, β̇ in place (they carry the crane terms of
    eqs. 45–48 into the head reference)."""
    lower, upper, speed, accel, share, k_p = crane
    for j in range(beta.shape[0]):
        target = beta_d[j] + share * (beta_c[j] - beta_d[j])
        cmd = share * beta_c_dot[j] + k_p * (target - beta[j])
        cmd = min(max(cmd, -speed[j]), speed[j])
        room_hi = math.sqrt(2 * accel[j] * max(upper[j] - beta[j], 0.0))
        room_lo = -math.sqrt(2 * accel[j] * max(beta[j] - lower[j], 0.0))
        cmd = min(max(cmd, room_lo), room_hi)
        dv = accel[j] * dt
        beta_dot[j] = beta_dot[j] + min(max(cmd - beta_dot[j], -dv), dv)
        beta[j] = min(max(beta[j] + beta_dot[j] * dt, lower[j]), upper[j])


@_jit
def crane_servo(crane, beta_d, beta_c, beta_c_dot, dt, beta, beta_dot):
    """``CraneServo.run``: the crane following β_c (n, 3) with rates β̇_c; (β, β̇) after each step, state in place."""
    n = beta_c.shape[0]
    out_b, out_v = np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        _crane_step(crane, beta_d, beta_c[k], beta_c_dot[k], dt, beta, beta_dot)
        out_b[k], out_v[k] = beta, beta_dot
    return out_b, out_v


# ----------------------------------------------------------------------------- head PID
@_jit
def head_pid_block(x, u, p, dt):
    """The head's joint PID as a block (:data:`app.control.tac.HEAD_PID`): eq. (57) solved for u with the motor
    rate of eq. (58), the input limited to [u_min, u_max].

    State (∫α̃,) (3,); inputs (α_ref, α̇_ref, α) (3,) each; parameters (K_p, K_i, K_d, T_DC, K_DC, u_min, u_max).
    Returns (x', y) with x' = x (not changed here) and y = (u, trial, limited), new arrays: the input, the
    integral with this step's error and whether the input was limited.  The integral is committed by the
    composition right after the motor step, integral = trial unless limited or the motor ran at its speed
    limit (anti-windup: it needs the motor's flag of the same step; ``app.scenes.tac_kernels._servo_step``)."""
    integral = x[0]
    ref, ref_dot, alpha = u
    kp, ki, kd, t_dc, k_dc, u_lo, u_hi = p
    implicit = 1.0 + kd * k_dc / t_dc
    inv_t = 1.0 / t_dc
    u_out, trial = np.empty(3), np.empty(3)
    limited = np.empty(3, dtype=np.bool_)
    for j in range(3):
        err = ref[j] - alpha[j]
        trial[j] = integral[j] + err * dt
        u_new = (kp * err + ki * trial[j] + kd * (ref_dot[j] + alpha[j] * inv_t)) / implicit  # eq. (57)
        limited[j] = True
        if u_new < u_lo[j]:
            u_new = u_lo[j]
        elif u_new > u_hi[j]:
            u_new = u_hi[j]
        else:
            limited[j] = False
        u_out[j] = u_new
    return x, (u_out, trial, limited)


# ----------------------------------------------------------------------------- warm-up
def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel of this file the crane-head controllers
    call from Python, with the argument types they pass (for :func:`app.warmup.warm_up`)."""
    z3, o3 = np.zeros(3), np.ones(3)
    crane = (-o3, o3, o3, o3, 0.3, 1.0)
    pid = (10.0, 60.0, 1.0, 0.2, 1.0, -o3, o3)
    rows3 = np.zeros((2, 3))
    return [
        lambda: crane_servo(crane, z3, rows3, rows3, 0.01, z3.copy(), z3.copy()),
        lambda: head_pid_block((z3.copy(),), (z3, z3, z3), pid, 0.01),
    ]
