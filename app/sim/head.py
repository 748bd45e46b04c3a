"""The crane head's plant: the crane's three joints and the Delta head's three DC motors (TAC paper eq. 58,
Table 4: T_DC 0.2 s, K_DC 1).

The crane's joints (slew, boom, jib) are rate drives, :data:`CRANE_JOINTS`: each joint's rate follows the
commanded rate within its acceleration limit, its angle stays inside its limits.  The law that commands them
in cooperative mode is :data:`app.control.tac.CRANE_LAW`.

Each arm is driven by a DC motor modelled as α/u = K_DC/(T_DC s + 1) (eq. 58), discretised exactly (zero-order
hold), its speed saturating at the head file's arm speed (90°/s for ``robots/tac_delta_head.xml``), its angle
kept inside the mechanical stops [α_min, α_max].  The motors are a block (:mod:`app.models.block`),
:data:`HEAD_MOTORS`, with its compiled kernel (:func:`app.sim.head_kernels.head_motors_block`) and its NumPy
reference here, tested equal in ``tests/test_blocks.py``.  The PID that drives them (eq. 57) is
:data:`app.control.tac.HEAD_PID`; the scene that wires the two (and the crane, the references and the head's
kinematics) is :mod:`app.scenes.tac`.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.block import Block
from app.sim import head_kernels

__all__ = ["CRANE_JOINTS", "HEAD_MOTORS", "motor_step"]


def _crane_joints_reference(x, u, p, dt):
    """The NumPy reference of :data:`CRANE_JOINTS` (the kernel: ``app.sim.head_kernels.crane_joints_block``)."""
    beta, beta_dot = x
    lower, upper, accel = p
    dv = accel * dt
    beta_dot = beta_dot + np.clip(u[0] - beta_dot, -dv, dv)
    beta = np.minimum(np.maximum(beta + beta_dot * dt, lower), upper)
    return (beta, beta_dot), (beta, beta_dot)


#: the crane's three joints as a block (app.models.block): rate drives, acceleration-limited, inside the limits
CRANE_JOINTS = Block(
    "crane joints",
    state=("beta", "beta_dot"),
    inputs=("beta_dot_cmd",),
    outputs=("beta", "beta_dot"),
    params=("lower", "upper", "accel"),
    reference=_crane_joints_reference,
    kernel=head_kernels.crane_joints_block,
)


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


def _motors_reference(x, u, p, dt):
    """The NumPy reference of :data:`HEAD_MOTORS` (the kernel: ``app.sim.head_kernels.head_motors_block``):
    :func:`motor_step` per arm (eq. 58 with the speed limit), then the mechanical stops."""
    t_dc, k_dc, lower, upper, speed = p
    a = math.exp(-dt / t_dc)
    b = (1.0 - a) * k_dc
    # plain floats per arm: three arms, so Python scalars beat small numpy arrays here
    alpha, u_in = np.asarray(x[0], dtype=float).tolist(), np.asarray(u[0], dtype=float).tolist()
    lo, hi, w_max = (np.asarray(v, dtype=float).tolist() for v in (lower, upper, speed))
    out, saturated = [0.0, 0.0, 0.0], [False, False, False]
    for j in range(3):
        a_new, saturated[j] = motor_step(alpha[j], u_in[j], a, b, t_dc, k_dc, w_max[j], dt)
        out[j] = lo[j] if a_new < lo[j] else hi[j] if a_new > hi[j] else a_new  # mechanical stops
    alpha_new = np.array(out)
    return (alpha_new,), (alpha_new, np.array(saturated))


#: the Delta head's three DC motors as a block (app.models.block): the plant of eq. (58), speed-limited
HEAD_MOTORS = Block(
    "head DC motors",
    state=("alpha",),
    inputs=("u",),
    outputs=("alpha", "saturated"),
    params=("t_dc", "k_dc", "lower", "upper", "speed"),
    reference=_motors_reference,
    kernel=head_kernels.head_motors_block,
)
