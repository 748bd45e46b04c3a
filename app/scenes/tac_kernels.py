"""The crane-head scene (:mod:`app.scenes.tac`) compiled: the head's servo (PID and DC motors) and one chunk of
the simulation step (TAC paper §8–10).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path).  The references are the same diagram run block by block in NumPy, tested equal on the same seeded
inputs in ``tests/test_tac_kernels.py``: ``HeadServo.run`` (:mod:`app.scenes.tac`) and a whole
:func:`app.scenarios.tac.simulate` in each mode.  The blocks wired here: the head's PID of eq. (57)
(:func:`app.control.tac_kernels.head_pid_block`), its DC motors of eq. (58) (:func:`app.sim.head_kernels.
head_motors_block`) and the cooperative crane law driving the crane's joints (:func:`app.control.tac_kernels.
crane_command`, :func:`app.sim.head_kernels.crane_joints`); the kinematics
they build on (crane pose and IK, Delta IK/FK, head references of eqs. 49–56) are
:mod:`app.models.crane_head_kernels`.

Records (every array C-contiguous float64; ``chain``, ``head``, ``hull`` and ``elbow`` are described in
:mod:`app.models.crane_head_kernels`, ``pid`` in :mod:`app.control.tac_kernels`, ``motors`` in
:mod:`app.sim.head_kernels`; ``crane`` = (law, joints), the records of :class:`app.scenes.tac.CraneServo`):

* the head servo's state (α, ∫α̃, u) (3,) each, in place: the arm angles, the PID's integral and its last input;
* :func:`tac_chunk`'s ``x`` = (crane, servo): crane (β, β̇, β_c of the last step (3,) each, in place; the slew
  angle to unwrap β_c from; whether β_c of the last step is set), servo the head servo's state;
  ``u`` = (η_true, η_meas, ν_meas (n, 6), noisy: whether the measured η differs from the true one);
  ``p`` = (modes, chain, head, hull, elbow, crane, pid, motors), modes = (crane mode, head mode, β_hold,
  α_lock, α_d, β_d, p_d^n, p_d^t, fade), fade = (τ₀, T, release, α_f, β_f, α̇_f): a change of references easing
  in (H108; T ≤ 0: none), τ₀ its time before the chunk's first step; a resumption (``release`` False) from the
  pose α_f, β_f and the arms' rate α̇_f (:func:`resume_start`), a release (compensation switched off) from the
  compensating references.
"""

from __future__ import annotations

import math

import numpy as np

from app.control.tac_kernels import crane_command, head_pid_block
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
from app.sim.head_kernels import crane_joints, head_motors_block

__all__ = [
    "ENABLED",
    "crane_servo",
    "ease_in",
    "head_servo",
    "tac_chunk",
    "warm_up_steps",
]

CRANE_HOLD, CRANE_COOPERATIVE, CRANE_RETURN = 0, 1, 2  # crane modes of tac_chunk
HEAD_LOCK, HEAD_SERVO, HEAD_HOLD = 0, 1, 2  # head modes of tac_chunk


# ----------------------------------------------------------------------------- resumption (H108)
@_jit
def ease_in(tau):
    """The resumption's gain s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ and ds/dτ = 30τ²(1 − τ)² for τ in [0, 1] (a quintic: from
    rest to rest with no step in acceleration either)."""
    t = min(max(tau, 0.0), 1.0)
    return t * t * t * (10.0 + t * (6.0 * t - 15.0)), 30.0 * (t * (1.0 - t)) ** 2


#: s: a resumption that begins while the arms move (a fade interrupted: off chosen and the mode again within
#: RESUME_TIME) starts from them going on at their rate, which dies away over this time (H108)
RESUME_DRIFT = 0.5


@_jit
def resume_start(alpha_f, alpha_f_dot, t, out, out_dot):
    """Where a resumption starts from ``t`` s after it began, into ``out`` and its rate into ``out_dot``: the pose
    α_f going on at its rate α̇_f, which dies away, α_f + α̇_f τ (1 − e^{−t/τ}), τ = :data:`RESUME_DRIFT` (the
    arms' velocity is continuous at the start; from rest, simply α_f)."""
    e = math.exp(-t / RESUME_DRIFT)
    for j in range(3):
        out[j] = alpha_f[j] + alpha_f_dot[j] * RESUME_DRIFT * (1.0 - e)
        out_dot[j] = alpha_f_dot[j] * e


# ----------------------------------------------------------------------------- crane servo
@_jit
def _crane_step(x, u, p, dt, cmd):
    """One step of the crane servo (``CraneServo.run``), in place: the cooperative crane law
    (:func:`app.control.tac_kernels.crane_command`) into ``cmd``, then the crane's joints
    (:func:`app.sim.head_kernels.crane_joints`).  x = (β, β̇); u = (β_d, β_c, β̇_c); p = (law, joints)."""
    beta_d, beta_c, beta_c_dot = u
    law, joints = p
    crane_command((beta_d, beta_c, beta_c_dot, x[0]), law, cmd)
    crane_joints(x, cmd, joints, dt)


@_jit
def crane_servo(x, u, p, dt):
    """``CraneServo.run``: len(β_c) steps of :func:`_crane_step`; u = (β_d (3,), β_c, β̇_c (n, 3)); returns (β,
    β̇) after each step, (n, 3) each, the state x = (β, β̇) in place."""
    beta_d, beta_c, beta_c_dot = u
    n = beta_c.shape[0]
    out_b, out_v, cmd = np.empty((n, 3)), np.empty((n, 3)), np.empty(3)
    for k in range(n):
        _crane_step(x, (beta_d, beta_c[k], beta_c_dot[k]), p, dt, cmd)
        out_b[k], out_v[k] = x
    return out_b, out_v


# ----------------------------------------------------------------------------- head servo
@_jit
def _servo_step(x, u, p, dt):
    """One step of the head servo (``HeadServo.run``), in place: the PID of eq. (57) solved for u with the
    motor rate of eq. (58), then the DC motors of eq. (58) with their speed limit inside the mechanical stops,
    then the PID's integral committed: anti-windup, no integration while the input is limited or the motor
    runs at its speed limit (the motor's flag of this same step).

    x = (α, ∫α̃, u) in place; u = (α_ref, α̇_ref) (3,) each; p = (pid, motors)."""
    alpha, integral, u_head = x
    ref, ref_dot = u
    pid, motors = p
    _, (u_new, trial, limited) = head_pid_block((integral,), (ref, ref_dot, alpha), pid, dt)  # eq. (57)
    _, (_, saturated) = head_motors_block((alpha,), (u_new,), motors, dt)  # eq. (58), ω-limited, α in place
    for j in range(3):
        u_head[j] = u_new[j]
        if not (limited[j] or saturated[j]):
            integral[j] = trial[j]  # anti-windup: integrate only while input and motor are free


@_jit
def head_servo(x, u, p, dt):
    """``HeadServo.run``: len(α_ref) steps of eqs. (57)–(58) (:func:`_servo_step`); u = (α_ref, α̇_ref) (n, 3)
    each; returns (α, u) after each step, (n, 3) each, the state x = (α, ∫α̃, u) in place."""
    ref, ref_dot = u
    n = ref.shape[0]
    out_a, out_u = np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        _servo_step(x, (ref[k], ref_dot[k]), p, dt)
        out_a[k], out_u[k] = x[0], x[2]
    return out_a, out_u


# ----------------------------------------------------------------------------- one chunk
@_jit
def tac_chunk(x, u, p, dt):
    """``TacSimulator.advance`` after the vessel motion, for the n rows of η (true and measured: ``noisy``
    when they differ) and ν (see the module text for the records).

    Crane (crane mode): CRANE_HOLD at β_hold at rest, CRANE_COOPERATIVE following a share of the elbow IK of
    eqs. (42)–(44) that keeps the TCP on p_d^n (slew unwrapped from the hint, the rate from β_c of the last
    step unless it is not set), CRANE_RETURN driving back to β_d of eq. (60).  Head: references of eqs.
    (49)–(56), then (head mode) the PID and DC motors of eqs. (57)–(58) on them (HEAD_SERVO), the same servo
    holding α_lock (HEAD_HOLD: compensation off) or the arms locked at α_lock (HEAD_LOCK: E-STOP); p_c^t by
    eqs. (17)–(25); e_c and e_s of eq. (61).  The crane (β, β̇, β_c of the last step) and head servo (α, ∫α̃,
    u) states are updated in place.
    While a resumption eases in (H108: after an E-STOP, or compensation chosen in ``off``), the servos run on
    their references seen from the pose it starts from, r ← r_f + s (r − r_f) with s of :func:`ease_in`: the
    head's α_ref (and its rate, + ṡ (α_ref − α_f)) or hold, and the crane law's β_d and β_c (β̇_c likewise).
    While a release eases in (compensation switched off: HEAD_HOLD, and CRANE_COOPERATIVE from cooperative),
    they run from the compensating references to the hold: α ← α_ref + s (α_lock − α_ref), β_c ← β_c + s (β_d −
    β_c).
    Returns (β, p_ref^t, p_c^t, α_ref (the one followed), α, u, p_c^n, p_s^n (n, 3), e_c, e_s (n,),
    saturated (n,)).
    """
    (beta, beta_dot, beta_c_prev, beta0_hint, has_prev), servo = x
    eta_true, eta_meas, nu_meas, noisy = u
    modes, chain, head, hull, elbow, crane, pid, motors = p
    crane_mode, head_mode, beta_hold, alpha_lock, alpha_d, beta_d, p_d_n, p_d_t, fade = modes
    r_t0, r_T, release, alpha_f, beta_f, alpha_f_dot = fade
    a_f, a_f_dot = np.empty(3), np.empty(3)
    alpha = servo[0]
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
    target, beta_c, beta_c_dot, zero, cmd = np.empty(3), np.empty(3), np.zeros(3), np.zeros(3), np.empty(3)
    p_tcp, b_d, b_c, b_c_dot, a_ref, a_dot = (
        np.empty(3),
        np.empty(3),
        np.empty(3),
        np.empty(3),
        np.empty(3),
        np.empty(3),
    )
    geometry, tip, work, servo_p = (head, hull), (o, R, v, w), (c, d), (pid, motors)
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
    prev_raw, correction = beta0_hint, 0.0
    hold = alpha_d
    for k in range(n):
        em, et = eta_meas[k], eta_true[k]
        _rot_zyx(em[3], em[4], em[5], R_n_b)  # R_b^n of the measured η
        easing, s, s_dot = False, 1.0, 0.0
        if r_T > 0.0:
            tau = (r_t0 + (k + 1) * dt) / r_T
            if tau < 1.0:
                easing = True
                s, s_dot = ease_in(tau)
                s_dot /= r_T
                if not release:
                    resume_start(alpha_f, alpha_f_dot, r_t0 + (k + 1) * dt, a_f, a_f_dot)
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
            else:
                beta_c[:] = beta_d
                beta_c_dot[:] = 0.0
            if easing and release:  # from the cooperative law's references to β_d
                for j in range(3):
                    b_d[j] = beta_d[j]
                    b_c[j] = beta_c[j] + s * (beta_d[j] - beta_c[j])
                    b_c_dot[j] = (1.0 - s) * beta_c_dot[j] + s_dot * (beta_d[j] - beta_c[j])
                _crane_step((beta, beta_dot), (b_d, b_c, b_c_dot), crane, dt, cmd)
            elif easing:  # the law's references seen from β_f
                for j in range(3):
                    b_d[j] = beta_f[j] + s * (beta_d[j] - beta_f[j])
                    b_c[j] = beta_f[j] + s * (beta_c[j] - beta_f[j])
                    b_c_dot[j] = s * beta_c_dot[j] + s_dot * (beta_c[j] - beta_f[j])
                _crane_step((beta, beta_dot), (b_d, b_c, b_c_dot), crane, dt, cmd)
            elif crane_mode == CRANE_COOPERATIVE:
                _crane_step((beta, beta_dot), (beta_d, beta_c, beta_c_dot), crane, dt, cmd)
            else:
                _crane_step((beta, beta_dot), (beta_d, beta_d, zero), crane, dt, cmd)
            out_beta[k] = beta
            _crane_pose(chain, beta, beta_dot, o, R, v, w)
        # head reference (eqs. 49–56), servo (eqs. 57–58) and forward kinematics (eqs. 17–25)
        out = (o_t_n, R_n_t, p_ref_t[k], p_cmd, v_ref_t, alpha_ref[k], alpha_dot_ref)
        limited = _reference_point(geometry, (em, nu_meas[k], R_n_b), tip, (p_d_n, zero), hold, out, work)
        hold = alpha_ref[k]
        if head_mode == HEAD_LOCK:
            out_alpha[k], out_u[k] = alpha_lock, alpha_lock
        else:
            if head_mode == HEAD_SERVO:
                if easing and not release:  # the reference seen from α_f
                    for j in range(3):
                        a_ref[j] = a_f[j] + s * (alpha_ref[k, j] - a_f[j])
                        a_dot[j] = (1.0 - s) * a_f_dot[j] + s * alpha_dot_ref[j] + s_dot * (alpha_ref[k, j] - a_f[j])
                    alpha_ref[k] = a_ref
                    _servo_step(servo, (a_ref, a_dot), servo_p, dt)
                else:
                    _servo_step(servo, (alpha_ref[k], alpha_dot_ref), servo_p, dt)
                saturated[k] = limited
            elif easing and release:  # HEAD_HOLD, released: from the compensating reference to the hold
                for j in range(3):
                    a_ref[j] = alpha_ref[k, j] + s * (alpha_lock[j] - alpha_ref[k, j])
                    a_dot[j] = (1.0 - s) * alpha_dot_ref[j] + s_dot * (alpha_lock[j] - alpha_ref[k, j])
                _servo_step(servo, (a_ref, a_dot), servo_p, dt)
            elif easing:  # HEAD_HOLD, easing in: the hold seen from α_f
                for j in range(3):
                    a_ref[j] = a_f[j] + s * (alpha_lock[j] - a_f[j])
                    a_dot[j] = (1.0 - s) * a_f_dot[j] + s_dot * (alpha_lock[j] - a_f[j])
                _servo_step(servo, (a_ref, a_dot), servo_p, dt)
            else:  # HEAD_HOLD: the servo holds α_lock
                _servo_step(servo, (alpha_lock, zero), servo_p, dt)
            out_alpha[k], out_u[k] = alpha, servo[2]
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
    """Zero-argument calls that compile (or load) every kernel of this file the crane-head scene calls from
    Python, with the argument types it passes (for :func:`app.warmup.warm_up`)."""
    from app.geometry import rot_x

    z3, o3, eye = np.zeros(3), np.ones(3), np.eye(4)
    chain = (np.stack([z3, z3, o3, o3, z3]), np.stack([np.eye(3), np.zeros((3, 3))]), np.stack([eye, eye]))
    head = (3.25, -0.75, 7.0, rot_x(np.radians([150.0, 270.0, 30.0])), -o3, o3)  # TAC paper Table 4
    hull = (np.array([[1.0, 0.0, 0.0, -1.0]]), z3, 1.0)
    elbow = (3.0, 19.2, 16.0, eye)
    crane = ((-o3, o3, o3, o3, 0.3, 1.0), (-o3, o3, o3))
    servo_p = ((10.0, 60.0, 1.0, 0.2, 1.0, -o3, o3), (0.2, 1.0, -o3, o3, o3))
    rows3, rows6 = np.zeros((2, 3)), np.zeros((2, 6))

    def servo() -> tuple:
        return z3.copy(), z3.copy(), z3.copy()

    def chunk(crane_mode: int, head_mode: int) -> None:
        x = ((z3.copy(), z3.copy(), z3.copy(), 0.0, False), servo())
        modes = (crane_mode, head_mode, z3, z3, z3, z3, o3, o3, (0.0, 0.0, False, z3, z3, z3))
        tac_chunk(x, (rows6, rows6, rows6, False), (modes, chain, head, hull, elbow, crane, *servo_p), 0.01)

    return [
        lambda: crane_servo((z3.copy(), z3.copy()), (z3, rows3, rows3), crane, 0.01),
        lambda: head_servo(servo(), (rows3, rows3), servo_p, 0.01),
        lambda: chunk(CRANE_COOPERATIVE, HEAD_SERVO),
    ]
