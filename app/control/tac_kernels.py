"""Compiled controllers of the crane-head compensation (TAC paper §8): the cooperative crane law and the
head's joint PID (eq. 57).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path).  The NumPy code stays the reference, tested equal on the same seeded inputs in ``tests/test_blocks.py``:
the blocks :data:`app.control.tac.CRANE_LAW` and :data:`app.control.tac.HEAD_PID`.  The plants they drive, the
crane's joints and the head's DC motors of eq. (58), are :mod:`app.sim.head_kernels`; the scene that wires them
with the head references and the head's kinematics (and the whole simulation step, ``tac_chunk``) is
:mod:`app.scenes.tac_kernels`.  Every array argument is C-contiguous
float64, and

* the crane law's parameters: (β_min, β_max, β̇_max, β̈_max, share, k_p) of the cooperative crane;
* the PID's parameters: (K_p, K_i, K_d, T_DC, K_DC, u_min, u_max) of eqs. (57)–(58).
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit

__all__ = [
    "ENABLED",
    "crane_command",
    "crane_law_block",
    "head_pid_block",
    "warm_up_steps",
]


# ----------------------------------------------------------------------------- cooperative crane law
@_jit
def crane_command(u, p, cmd):
    """:data:`app.control.tac.CRANE_LAW`'s output into ``cmd`` (3,): β̇_cmd = s β̇_c + k_p (β_d + s (β_c − β_d) − β),
    limited to each joint's speed and to the speed it can still brake from before its position limits."""
    beta_d, beta_c, beta_c_dot, beta = u
    lower, upper, speed, accel, share, k_p = p
    for j in range(beta.shape[0]):
        target = beta_d[j] + share * (beta_c[j] - beta_d[j])
        c = share * beta_c_dot[j] + k_p * (target - beta[j])
        c = min(max(c, -speed[j]), speed[j])
        room_hi = math.sqrt(2 * accel[j] * max(upper[j] - beta[j], 0.0))
        room_lo = -math.sqrt(2 * accel[j] * max(beta[j] - lower[j], 0.0))
        cmd[j] = min(max(c, room_lo), room_hi)


@_jit
def crane_law_block(x, u, p, dt):
    """The cooperative crane law as a block (:data:`app.control.tac.CRANE_LAW`): no state; u = (β_d, β_c, β̇_c,
    β) (3,) each; p = (β_min, β_max, β̇_max, β̈_max, share, k_p); y = (β̇_cmd,), a new array."""
    cmd = np.empty(u[3].shape[0])
    crane_command(u, p, cmd)
    return x, (cmd,)


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
    return [
        lambda: crane_law_block((), (z3, z3, z3, z3), crane, 0.01),
        lambda: head_pid_block((z3.copy(),), (z3, z3, z3), pid, 0.01),
    ]
