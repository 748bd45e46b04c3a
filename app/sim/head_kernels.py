"""Compiled plant of the crane head: the crane's three joints and the Delta head's three DC motors (TAC paper
eq. 58).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path).  The NumPy references are :mod:`app.sim.head` (:data:`~app.sim.head.CRANE_JOINTS`,
:data:`~app.sim.head.HEAD_MOTORS`), tested equal on the same seeded inputs in ``tests/test_blocks.py``; the
scene that wires them with their controllers (:mod:`app.control.tac_kernels`: the cooperative crane law, the
PID of eq. 57) is :mod:`app.scenes.tac_kernels`.

The blocks take records, (x, u, p, dt), and update their state arrays in place (see :mod:`app.sim.kernels`).
The crane's joints: ``x`` = (β, β̇) (3,) each [rad, rad/s], in place; ``u`` = (β̇_cmd,) (3,); ``p`` = (β_min,
β_max, β̈_max) (3,) each; ``y`` = (β, β̇).  The head's motors:

* ``x`` = (α,): the arm angles (3,) [rad], in place;
* ``u`` = (u,): the motors' inputs (3,) [rad] (K_DC u is the angle each motor settles at);
* ``p`` = (T_DC, K_DC, α_min, α_max, ω_max): eq. (58)'s time constant [s] and gain, the mechanical stops (3,)
  [rad] and the arms' speed limit (3,) [rad/s] (the motors saturate in speed);
* ``y`` = (α, saturated): the angles after the step and which motor ran at its speed limit (3,) bool.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit

__all__ = ["ENABLED", "crane_joints", "crane_joints_block", "head_motors_block", "warm_up_steps"]


@_jit
def crane_joints(x, cmd, p, dt):
    """:data:`app.sim.head.CRANE_JOINTS`' step on x = (β, β̇) in place: each joint's rate follows β̇_cmd within
    its acceleration limit, its angle stays inside [β_min, β_max]."""
    beta, beta_dot = x
    lower, upper, accel = p
    for j in range(beta.shape[0]):
        dv = accel[j] * dt
        beta_dot[j] = beta_dot[j] + min(max(cmd[j] - beta_dot[j], -dv), dv)
        beta[j] = min(max(beta[j] + beta_dot[j] * dt, lower[j]), upper[j])


@_jit
def crane_joints_block(x, u, p, dt):
    """The crane's joints as a block (:data:`app.sim.head.CRANE_JOINTS`), in place; returns (x', y), y = (β, β̇)."""
    crane_joints(x, u[0], p, dt)
    return x, x


@_jit
def _motor_step(alpha, u, a_m, b_m, t_dc, k_dc, w_max, dt):
    """``app.sim.head.motor_step``: one zero-order-hold step of the DC motor of eq. (58) whose speed
    saturates at ±w_max (at w_max while |K_DC u − α| > T_DC w_max, then eq. 58's exponential); (α⁺, saturated)."""
    d = k_dc * u - alpha
    band = t_dc * w_max
    if -band <= d <= band:
        return a_m * alpha + b_m * u, False  # eq. (58), zero-order hold
    s = 1.0 if d > 0.0 else -1.0
    t_fast = (abs(d) - band) / w_max
    if t_fast >= dt:
        return alpha + s * w_max * dt, True
    return k_dc * u - s * band * math.exp(-(dt - t_fast) / t_dc), True


@_jit
def head_motors_block(x, u, p, dt):
    """The head's DC motors as a block (:data:`app.sim.head.HEAD_MOTORS`), in place: eq. (58) discretised
    exactly (a = e^{−dt/T_DC}, b = (1 − a) K_DC) with each motor's speed limit, then the mechanical stops
    [α_min, α_max].  Returns (x', y) with y = (α, saturated) (see the module text)."""
    alpha = x[0]
    u_in = u[0]
    t_dc, k_dc, lo, hi, w_max = p
    a_m = math.exp(-dt / t_dc)
    b_m = (1.0 - a_m) * k_dc
    saturated = np.zeros(3, dtype=np.bool_)
    for j in range(3):
        a_new, fast = _motor_step(alpha[j], u_in[j], a_m, b_m, t_dc, k_dc, w_max[j], dt)
        saturated[j] = fast
        alpha[j] = lo[j] if a_new < lo[j] else hi[j] if a_new > hi[j] else a_new  # mechanical stops
    return (alpha,), (alpha, saturated)


# ----------------------------------------------------------------------------- warm-up
def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) the blocks with the argument types their callers pass (for
    :func:`app.warmup.warm_up`)."""
    z3, o3 = np.zeros(3), np.ones(3)
    return [
        lambda: head_motors_block((z3.copy(),), (o3,), (0.2, 1.0, -o3, o3, o3), 0.01),
        lambda: crane_joints_block((z3.copy(), z3.copy()), (o3,), (-o3, o3, o3), 0.01),
    ]
