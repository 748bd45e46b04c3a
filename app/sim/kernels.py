"""Compiled per-step plant updates: the braking bound, the platform motion filter, the joint servos.

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the
interpreted path); the NumPy methods of :class:`~app.sim.actuators.JointActuators` and
:class:`~app.sim.stewart.MotionFilter` remain the reference, tested equal in ``tests/test_kernels.py``.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit

__all__ = ["ENABLED", "actuator_step", "braking_speed", "motion_filter_step"]


@_jit
def braking_speed(d, a, dt):
    """:func:`app.sim.actuators.braking_speed` element by element (same formula, same order)."""
    out = np.empty(d.shape[0])
    for i in range(d.shape[0]):
        di = max(d[i], 0.0)
        if math.isfinite(a[i]):
            h = a[i] * dt
            m = math.floor(max(math.sqrt(0.25 + 2.0 * di / (h * dt)) - 0.5, 0.0))
            out[i] = (di / dt + 0.5 * h * m * (m + 1.0)) / (m + 1.0)
        else:
            out[i] = di / dt
    return out


@_jit
def motion_filter_step(x, v, x_ref, v_ref, use_v_ref, lower, upper, speed, accel, tau, dt, speed_scale):
    """One :meth:`MotionFilter.step`: (x⁺, v⁺, a)."""
    n = x.shape[0]
    up = braking_speed(upper - x, accel, dt)
    down = braking_speed(x - lower, accel, dt)
    x_new, v_new, a_new = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        v_des = (x_ref[i] - x[i]) / max(tau, dt)
        if use_v_ref:
            v_des = v_des + v_ref[i]
        vmax = speed[i] * speed_scale
        hi = min(min(v[i] + accel[i] * dt, vmax), up[i])
        lo = max(max(v[i] - accel[i] * dt, -vmax), -down[i])
        hi = max(hi, lo)  # rounding only
        if not math.isfinite(v_des):
            v_des = 0.0
        vn = min(max(v_des, lo), hi)
        a_new[i] = (vn - v[i]) / dt
        v_new[i] = vn
        x_new[i] = min(max(x[i] + vn * dt, lower[i]), upper[i])
    return x_new, v_new, a_new


@_jit
def actuator_step(q, qdot, q_ref, lower, upper, speed, accel, tau, dt):
    """One :meth:`JointActuators.step`: (q⁺, q̇⁺, q̈)."""
    n = q.shape[0]
    up = braking_speed(upper - q, accel, dt)
    down = braking_speed(q - lower, accel, dt)
    q_new, v_new, a_new = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        r = min(max(q_ref[i], lower[i]), upper[i])
        gap = abs(r - q[i]) / dt
        v_des = min(max((r - q[i]) / tau, -gap), gap)  # never past the reference in one step
        dv = accel[i] * dt
        hi = min(min(qdot[i] + dv, speed[i]), up[i])
        lo = max(max(qdot[i] - dv, -speed[i]), -down[i])
        v = min(max(v_des, lo), max(hi, lo))
        qn = min(max(q[i] + v * dt, lower[i]), upper[i])
        v = (qn - q[i]) / dt
        a_new[i] = (v - qdot[i]) / dt
        q_new[i], v_new[i] = qn, v
    return q_new, v_new, a_new
