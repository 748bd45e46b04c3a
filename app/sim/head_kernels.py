"""Compiled plant of the crane head: the Delta head's three DC motors (TAC paper eq. 58).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path).  The NumPy reference is :mod:`app.sim.head` (:data:`~app.sim.head.HEAD_MOTORS`), tested equal on the
same seeded inputs in ``tests/test_blocks.py``; the scene that wires these motors with their PID
(:func:`app.control.tac_kernels.head_pid_block`, eq. 57) is :mod:`app.scenes.tac_kernels`.

The block takes records, (x, u, p, dt), and updates its state array in place (see :mod:`app.sim.kernels`):

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

__all__ = ["ENABLED", "head_motors_block", "warm_up_steps"]


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
    """A zero-argument call that compiles (or loads) :func:`head_motors_block` with the argument types its
    callers pass (for :func:`app.warmup.warm_up`)."""
    z3, o3 = np.zeros(3), np.ones(3)
    return [lambda: head_motors_block((z3.copy(),), (o3,), (0.2, 1.0, -o3, o3, o3), 0.01)]
