"""Compiled joint servos and simulation step of the crane-head compensation (TAC paper §8–10).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path).  The NumPy methods stay the reference, tested equal on the same seeded inputs in
``tests/test_tac_kernels.py``: ``HeadServo.run`` and ``CraneServo.run`` (:mod:`app.control.tac`), and a
whole :func:`app.scenarios.tac.simulate` in each mode.  The kinematics they build on (crane pose and
IK, Delta IK/FK, head references) are :mod:`app.models.crane_head_kernels`.

:func:`tac_chunk` is one call doing what ``TacSimulator.advance`` does after the vessel motion: the
crane joints, the head references, the PID and DC motors, the head's forward kinematics and the
errors of eq. (61), step by step.  Servo states are updated in place.  Every array argument is
C-contiguous float64; ``chain``, ``head``, ``hull`` and ``elbow`` are described in
:mod:`app.models.crane_head_kernels`, and

* ``pid``: (K_p, K_i, K_d, T_DC, K_DC, u_min, u_max, α_min, α_max, ω_max) of eqs. (57)–(58), ω_max the
  arms' speed limit (the motors saturate in speed);
* ``crane``: (β_min, β_max, β̇_max, β̈_max, share, k_p) of the cooperative crane servo.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.crane_head_kernels import (
    _crane_pose,
    _delta_fk_point,
    _elbow_ik,
    _knees,
    _raise_fk,
    _reference_point,
    _rot_zyx,
    _to_n,
    _unwrap,
)
from app.models.kernels import ENABLED, _jit

__all__ = [
    "ENABLED",
    "crane_servo",
    "head_servo",
    "tac_chunk",
    "warm_up_steps",
]

CRANE_HOLD, CRANE_COOPERATIVE, CRANE_RETURN = 0, 1, 2  # crane modes of tac_chunk
HEAD_LOCK, HEAD_SERVO, HEAD_HOLD = 0, 1, 2  # head modes of tac_chunk


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


# ----------------------------------------------------------------------------- head servo
@_jit
def _motor_step(alpha, u, a_m, b_m, t_dc, k_dc, w_max, dt):
    """``app.control.tac.motor_step``: one zero-order-hold step of the DC motor of eq. (58) whose speed
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
def _servo_step(pid, a_m, b_m, dt, ref, ref_dot, alpha, integral, u):
    """PID of eq. (57) solved for u with the motor rate of eq. (58), then the DC motor of eq. (58) with its
    speed limit inside the mechanical stops; anti-windup: no integration while the input is limited or the
    motor runs at its speed limit (``HeadServo.run``); in place."""
    kp, ki, kd, t_dc, k_dc, u_lo, u_hi, lo, hi, w_max = pid
    implicit = 1.0 + kd * k_dc / t_dc
    inv_t = 1.0 / t_dc
    for j in range(3):
        err = ref[j] - alpha[j]
        trial = integral[j] + err * dt
        u_new = (kp * err + ki * trial + kd * (ref_dot[j] + alpha[j] * inv_t)) / implicit  # eq. (57)
        limited = True
        if u_new < u_lo[j]:
            u_new = u_lo[j]
        elif u_new > u_hi[j]:
            u_new = u_hi[j]
        else:
            limited = False
        u[j] = u_new
        a_new, fast = _motor_step(alpha[j], u_new, a_m, b_m, t_dc, k_dc, w_max[j], dt)
        if not (limited or fast):
            integral[j] = trial  # anti-windup: integrate only while input and motor are free
        alpha[j] = lo[j] if a_new < lo[j] else hi[j] if a_new > hi[j] else a_new


@_jit
def head_servo(pid, dt, ref, ref_dot, alpha, integral, u):
    """``HeadServo.run``: len(ref) steps of eqs. (57)–(58); (α, u) after each step, state in place."""
    a_m = math.exp(-dt / pid[3])
    b_m = (1.0 - a_m) * pid[4]
    n = ref.shape[0]
    out_a, out_u = np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        _servo_step(pid, a_m, b_m, dt, ref[k], ref_dot[k], alpha, integral, u)
        out_a[k], out_u[k] = alpha, u
    return out_a, out_u


# ----------------------------------------------------------------------------- one chunk
@_jit
def tac_chunk(
    eta_true, eta_meas, nu_meas, noisy, dt, crane_mode, head_mode, beta_hold, alpha_lock, alpha_d, beta_d, p_d_n,
    p_d_t, chain, head, hull, elbow, crane, pid, beta, beta_dot, beta_c_prev, beta0_hint, has_prev, alpha, integral,
    u,
):  # fmt: skip
    """``TacSimulator.advance`` after the vessel motion, for the n rows of η (true and measured: ``noisy``
    when they differ) and ν.

    Crane (``crane_mode``): CRANE_HOLD at ``beta_hold`` at rest, CRANE_COOPERATIVE following a share of
    the elbow IK of eqs. (42)–(44) that keeps the TCP on p_d^n (slew unwrapped from ``beta0_hint``, the
    rate from ``beta_c_prev`` unless ``has_prev`` is False), CRANE_RETURN driving back to β_d of eq. (60).
    Head: references of eqs. (49)–(56), then (``head_mode``) the PID and DC motors of eqs. (57)–(58) on them
    (HEAD_SERVO), the same servo holding ``alpha_lock`` (HEAD_HOLD: compensation off) or the arms locked at
    ``alpha_lock`` (HEAD_LOCK: E-STOP); p_c^t by eqs. (17)–(25); e_c and e_s of eq. (61).  The crane (β, β̇, β_c
    of the last step) and head servo (α, ∫α̃, u) states are updated in place.
    Returns (β, p_ref^t, p_c^t, α_ref, α, u, p_c^n, p_s^n (n, 3), e_c, e_s (n,), saturated (n,)).
    """
    n = eta_true.shape[0]
    out_beta, p_ref_t, p_c_t = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    alpha_ref, out_alpha, out_u = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    p_c_n, p_s_n = np.empty((n, 3)), np.empty((n, 3))
    e_c, e_s = np.empty(n), np.empty(n)
    saturated = np.zeros(n, dtype=np.bool_)
    o, R, v, w = np.empty(3), np.empty((3, 3)), np.empty(3), np.empty(3)
    R_n_b, R_n_b_true, R_n_t = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    c, d = np.empty((3, 3)), np.empty((3, 3))
    o_t_n, p_cmd, v_ref_t, alpha_dot_ref = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    target, beta_c, beta_c_dot, zero = np.empty(3), np.empty(3), np.zeros(3), np.zeros(3)
    p_tcp = np.empty(3)
    # the uncompensated TCP in {b}: crane at β_d, head locked at p_d^t
    o_s, R_s = np.empty(3), np.empty((3, 3))
    _crane_pose(chain, beta_d, zero, o_s, R_s, v, w)
    for r in range(3):
        o_s[r] = o_s[r] + (R_s[r, 0] * p_d_t[0] + R_s[r, 1] * p_d_t[1] + R_s[r, 2] * p_d_t[2])
    eye = np.eye(3)
    if crane_mode == CRANE_HOLD:
        _crane_pose(chain, beta_hold, zero, o, R, v, w)
    if head_mode == HEAD_LOCK:
        _knees(head, alpha_lock, c, d)
        _raise_fk(_delta_fk_point(head, c, p_tcp))
    a_m = math.exp(-dt / pid[3])
    b_m = (1.0 - a_m) * pid[4]
    prev_raw, correction = beta0_hint, 0.0
    hold = alpha_d
    for k in range(n):
        em, et = eta_meas[k], eta_true[k]
        _rot_zyx(em[3], em[4], em[5], R_n_b)  # R_b^n of the measured η
        # crane
        if crane_mode == CRANE_HOLD:
            out_beta[k] = beta_hold
        else:
            if crane_mode == CRANE_COOPERATIVE:
                g0, g1, g2 = p_d_n[0] - em[0], p_d_n[1] - em[1], p_d_n[2] - em[2]
                for r in range(3):  # p_d^n in {b}
                    target[r] = R_n_b[0, r] * g0 + R_n_b[1, r] * g1 + R_n_b[2, r] * g2
                _elbow_ik(elbow, target[0], target[1], target[2], beta_c)
                raw = beta_c[0]
                correction = _unwrap(prev_raw, raw, correction)
                prev_raw = raw
                beta_c[0] = raw + correction
                if k == 0 and not has_prev:
                    beta_c_prev[:] = beta_c
                for j in range(3):
                    beta_c_dot[j] = (beta_c[j] - beta_c_prev[j]) / dt
                beta_c_prev[:] = beta_c
                _crane_step(crane, beta_d, beta_c, beta_c_dot, dt, beta, beta_dot)
            else:
                _crane_step(crane, beta_d, beta_d, zero, dt, beta, beta_dot)
            out_beta[k] = beta
            _crane_pose(chain, beta, beta_dot, o, R, v, w)
        # head reference, servo and forward kinematics
        limited = _reference_point(
            head, hull, em, nu_meas[k], o, R, v, w, p_d_n, zero, hold, R_n_b, o_t_n, R_n_t, p_ref_t[k], p_cmd,
            v_ref_t, alpha_ref[k], alpha_dot_ref, c, d,
        )  # fmt: skip
        hold = alpha_ref[k]
        if head_mode == HEAD_LOCK:
            out_alpha[k], out_u[k] = alpha_lock, alpha_lock
        else:
            if head_mode == HEAD_SERVO:
                _servo_step(pid, a_m, b_m, dt, alpha_ref[k], alpha_dot_ref, alpha, integral, u)
                saturated[k] = limited
            else:  # HEAD_HOLD: the servo holds α_lock
                _servo_step(pid, a_m, b_m, dt, alpha_lock, zero, alpha, integral, u)
            out_alpha[k], out_u[k] = alpha, u
            _knees(head, alpha, c, d)
            _raise_fk(_delta_fk_point(head, c, p_tcp))
        p_c_t[k] = p_tcp
        # eq. (61): e_c = |p_d^n − p_c^n|, e_s = |p_d^n − p_s^n|
        if noisy:
            _rot_zyx(et[3], et[4], et[5], R_n_b_true)  # R_b^n of the true η
        else:
            R_n_b_true[:] = R_n_b
        _to_n(R_n_b_true, et, o, R, p_tcp, p_c_n[k])
        _to_n(R_n_b_true, et, o_s, eye, zero, p_s_n[k])
        sc, ss = 0.0, 0.0
        for r in range(3):
            sc += (p_d_n[r] - p_c_n[k, r]) ** 2
            ss += (p_d_n[r] - p_s_n[k, r]) ** 2
        e_c[k], e_s[k] = math.sqrt(sc), math.sqrt(ss)
    return out_beta, p_ref_t, p_c_t, alpha_ref, out_alpha, out_u, p_c_n, p_s_n, e_c, e_s, saturated


# ----------------------------------------------------------------------------- warm-up
def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel of this file the crane-head servos and
    simulation call from Python, with the argument types they pass (for :func:`app.warmup.warm_up`)."""
    from app.geometry import rot_x

    z3, o3, eye = np.zeros(3), np.ones(3), np.eye(4)
    chain = (z3, z3, o3, o3, z3, np.eye(3), np.zeros((3, 3)), eye, eye)
    head = (3.25, -0.75, 7.0, rot_x(np.radians([150.0, 270.0, 30.0])), -o3, o3)  # TAC paper Table 4
    hull = (np.array([[1.0, 0.0, 0.0, -1.0]]), z3, 1.0)
    elbow = (3.0, 19.2, 16.0, eye)
    crane = (-o3, o3, o3, o3, 0.3, 1.0)
    pid = (10.0, 60.0, 1.0, 0.2, 1.0, -o3, o3, -o3, o3, o3)
    rows3, rows6 = np.zeros((2, 3)), np.zeros((2, 6))

    def chunk(crane_mode: int, head_mode: int) -> None:
        tac_chunk(
            rows6, rows6, rows6, False, 0.01, crane_mode, head_mode, z3, z3, z3, z3, o3, o3, chain, head, hull, elbow,
            crane, pid, z3.copy(), z3.copy(), z3.copy(), 0.0, False, z3.copy(), z3.copy(), z3.copy(),
        )  # fmt: skip

    return [
        lambda: head_servo(pid, 0.01, rows3, rows3, z3.copy(), z3.copy(), z3.copy()),
        lambda: crane_servo(crane, z3, rows3, rows3, 0.01, z3.copy(), z3.copy()),
        lambda: chunk(CRANE_COOPERATIVE, HEAD_SERVO),
    ]
