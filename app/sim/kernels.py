"""Compiled plants: the braking bound, the motion filter, the joint actuators, the Stewart platforms'
command path, the Comau's drives, the winch drum and the load (pendulum).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the
interpreted path).  The NumPy methods stay the reference, tested equal on the same seeded inputs:
:class:`~app.sim.actuators.JointActuators` and :class:`~app.sim.stewart.MotionFilter` in
``tests/test_kernels.py``; the platforms, the drives, the drum, the pendulum and a whole Motion-Lab step
(:func:`app.scenes.lab_kernels.lab_step`, which wires these plants with the controllers of
:mod:`app.control.lab_kernels`) in ``tests/test_sim_kernels.py`` and ``tests/test_blocks.py``.

Blocks (:mod:`app.models.block`) take records, (x, u, p, dt), and update their state arrays in place
(allocating and returning them costs more than the arithmetic).  Every array is C-contiguous float64
(bool for ``at_limit``): another layout would make numba compile a second specialisation in a control
tick; flags are ``np.bool_`` (a literal ``True`` in a call would compile another).  The kinematics they
build on are :mod:`app.models.lab_kernels`.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit
from app.models.lab_kernels import leg_lengths, pose_in, stewart_rates
from app.models.pendulum_kernels import pendulum_step

__all__ = [
    "ENABLED",
    "actuator_block",
    "approach_speed",
    "braking_speed",
    "clamp_to_legs",
    "command_clip",
    "drives_block",
    "drum_block",
    "follow_clamped",
    "leg_lengths",
    "load_block",
    "motion_filter_update",
    "pendulum_block",
    "pendulum_step",
    "pose_in",
    "stewart_rates",
]


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
def approach_speed(e, v_brake, tau):
    """The servo's speed towards a reference ``e`` ahead: e/τ, but never above ``v_brake``, the speed from
    which the joint can still stop at the reference (:func:`braking_speed` of |e|).

    A proportional law alone asks for |e|/τ, far more than an acceleration-limited joint can brake from
    (τ = 50 ms against a crane's seconds of braking): it overshoots, and the overshoot is answered the same
    way, a bang-bang oscillation that keeps its energy, x'' = −a·sign(x) (issue 26, item 1: a centred
    stick moved the crane back and forth for seconds).  Bounded by the braking speed it is the
    time-optimal approach of a bang-bang servo near the reference ("square-root" law), and stops there.
    """
    p = e / tau
    if p > v_brake:
        return v_brake
    if p < -v_brake:
        return -v_brake
    return p


@_jit
def motion_filter_update(state, ref, limits, dt):
    """One :meth:`MotionFilter.step` in place.

    ``state`` = (x, v, a) become (x⁺, v⁺, a); ``ref`` = (x_ref, v_ref, use_v_ref, speed_scale) (x_ref may be
    x itself; v_ref is the feed-forward, used if use_v_ref); ``limits`` = (lower, upper, speed, accel, brake, τ),
    ``brake`` (≤ accel) the deceleration of the velocity bound at the position limits."""
    x, v, a = state
    x_ref, v_ref, use_v_ref, speed_scale = ref
    lower, upper, speed, accel, brake, tau = limits
    n = x.shape[0]
    up = braking_speed(upper - x, brake, dt)
    down = braking_speed(x - lower, brake, dt)
    gap = np.empty(n)
    for i in range(n):
        gap[i] = abs(x_ref[i] - x[i])
    toward = braking_speed(gap, accel, dt)
    for i in range(n):
        v_des = approach_speed(x_ref[i] - x[i], toward[i], max(tau, dt))
        if use_v_ref:
            v_des = v_des + v_ref[i]
        vmax = speed[i] * speed_scale
        hi = min(min(v[i] + accel[i] * dt, vmax), up[i])
        lo = max(max(v[i] - accel[i] * dt, -vmax), -down[i])
        hi = max(hi, lo)  # rounding only
        if not math.isfinite(v_des):
            v_des = 0.0
        vn = min(max(v_des, lo), hi)
        a[i] = (vn - v[i]) / dt
        v[i] = vn
        x[i] = min(max(x[i] + vn * dt, lower[i]), upper[i])


@_jit
def actuator_block(x, u, p, dt):
    """The joint actuators as a block (:data:`app.sim.actuators.JOINT_ACTUATORS`), one
    :meth:`JointActuators.step`: state (q, q̇, q̈), input (q_ref,), parameters (lower, upper, speed, accel, τ);
    returns (x', y) with y = (q,), new arrays."""
    q, qdot, _ = x
    q_ref = u[0]
    lower, upper, speed, accel, tau = p
    n = q.shape[0]
    up = braking_speed(upper - q, accel, dt)
    down = braking_speed(q - lower, accel, dt)
    e = np.empty(n)
    for i in range(n):
        e[i] = min(max(q_ref[i], lower[i]), upper[i]) - q[i]
    toward = braking_speed(np.abs(e), accel, dt)
    q_new, v_new, a_new = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        gap = abs(e[i]) / dt
        v_des = min(max(approach_speed(e[i], toward[i], tau), -gap), gap)  # never past the reference in one step
        dv = accel[i] * dt
        hi = min(min(qdot[i] + dv, speed[i]), up[i])
        lo = max(max(qdot[i] - dv, -speed[i]), -down[i])
        v = min(max(v_des, lo), max(hi, lo))
        qn = min(max(q[i] + v * dt, lower[i]), upper[i])
        v = (qn - q[i]) / dt
        a_new[i] = (v - qdot[i]) / dt
        q_new[i], v_new[i] = qn, v
    return (q_new, v_new, a_new), (q_new,)


# ============================================================================= Motion-Lab
@_jit
def _legs_inside(a_n, b_b, eta, lo, hi):
    L = leg_lengths(a_n, b_b, eta)
    inside = True
    for k in range(L.shape[0]):
        if not (lo <= L[k] and hi >= L[k]):
            inside = False
    return inside


@_jit
def clamp_to_legs(a_n, b_b, eta, lo, hi):
    """``Platform._clamp_to_legs``: η scaled toward neutral (bisection, 20 halvings) until every leg of
    eqs. (31)–(38) lies in [lo, hi]: (η', clamped)."""
    if _legs_inside(a_n, b_b, eta, lo, hi):
        return eta.copy(), False
    a, b = 0.0, 1.0
    for _ in range(20):
        c = 0.5 * (a + b)
        if _legs_inside(a_n, b_b, c * eta, lo, hi):
            a = c
        else:
            b = c
    return a * eta, True


@_jit
def command_clip(eta, v, lower, upper):
    """The lab PLC's etaRef = LIMIT(etaRefMin, u, etaRefMax) (FB_StewartInterface): η clipped to the
    command box, and its feed-forward rate zeroed in each clipped DOF; new arrays (η', η̇')."""
    n = eta.shape[0]
    e, r = np.empty(n), np.empty(n)
    for i in range(n):
        e[i] = min(max(eta[i], lower[i]), upper[i])
        r[i] = v[i] if e[i] == eta[i] else 0.0
    return e, r


@_jit
def follow_clamped(legs, source, state, limits, dt):
    """An engaged platform's step in place (``Platform.step``): the source pose η_s times the ramp gain,
    clipped to the command box (the filter's limits while engaged, :func:`command_clip`), scaled back
    into the leg strokes (:func:`clamp_to_legs`, eqs. 31–38), then the motion filter with the feed-forward
    gain·η̇_s.  ``legs`` = (a_n, b_b, stroke min, stroke max), ``source`` = (gain, η_s, η̇_s), ``state`` =
    (x, v, a) of the filter, ``limits`` = (lower, upper, speed, accel, τ).  Returns whether the pose was
    scaled back."""
    a_n, b_b, lo, hi = legs
    gain, eta_s, v_s = source
    lower, upper, speed, accel, tau = limits
    eta_c, v_c = command_clip(gain * eta_s, gain * v_s, lower, upper)
    target, clamped = clamp_to_legs(a_n, b_b, eta_c, lo, hi)
    on = np.bool_(True)  # a plain bool: a literal True would compile a second specialisation
    motion_filter_update(state, (target, v_c, on, 1.0), (lower, upper, speed, accel, accel, tau), dt)
    return clamped


# ----------------------------------------------------------------------------- pendulum
@_jit
def pendulum_block(x, u, p, dt):
    """The load as a block (:data:`app.sim.motionlab.PENDULUM`): state (α, β, α̇, β̇), inputs (a_t^d (3,) in {d},
    L, L̇), parameters (c, g); y = (α, β)."""
    a_t = u[0]
    a, b, ad, bd = pendulum_step(x, (a_t[0], a_t[1], a_t[2]), u[1], u[2], p[0], p[1], dt)
    return (a, b, ad, bd), (a, b, ad, bd)


# ----------------------------------------------------------------------------- the lab's drives
@_jit
def drives_block(x, u, p, dt):
    """The Comau's joint drives (:data:`app.sim.motionlab.COMAU_DRIVES`), in place: state (q, q̇, q̈,
    at_limit), input the joint command (brake, q_ref, q̇_ref, use q̇_ref, speed scale) of
    :data:`app.control.lab.COMAU_LAW`, parameters (lower, upper, speed, accel, brake deceleration, τ).

    ``brake``: to rest at the acceleration limits, then stay (HOLD, E-STOP); else the motion filter toward
    the reference, and ``at_limit[0:3]`` says which joints are at a position or speed limit.  y = (q,)."""
    q, qd, qdd, at_limit = x
    brake, q_ref, v_ref, use_v, scale = u
    q_lo, q_hi, q_speed, q_accel, _, _ = p
    if brake:
        for i in range(3):
            dv = min(max(-qd[i], -q_accel[i] * dt), q_accel[i] * dt)
            vn = qd[i] + dv
            qdd[i] = (vn - qd[i]) / dt
            qd[i] = vn
            q[i] = min(max(q[i] + vn * dt, q_lo[i]), q_hi[i])
    else:
        motion_filter_update((q, qd, qdd), (q_ref, v_ref, use_v, scale), p, dt)
        for i in range(3):
            at_limit[i] = q[i] <= q_lo[i] + 1e-6 or q[i] >= q_hi[i] - 1e-6 or abs(qd[i]) >= q_speed[i] * (1 - 1e-3)
    return (q, qd, qdd, at_limit), (q, qd)


@_jit
def drum_block(x, u, p, dt):
    """The winch drum (:data:`app.sim.motionlab.WINCH_DRUM`), in place: state (L_w, L̇_w, L̈_w (1,) each,
    at_limit), input the length reference (L_ref, L̇_ref (1,) each) of :data:`app.control.lab.WINCH_LAW`,
    parameters (lower, upper, speed, accel, τ (1,) each but τ); ``at_limit[3]`` says whether the wire is at a
    length or speed limit.  y = (L_w, L̇_w)."""
    wl, wv, wa, at_limit = x
    ref, ref_v = u
    w_lo, w_hi, w_speed, w_accel, w_tau = p
    on = np.bool_(True)
    motion_filter_update((wl, wv, wa), (ref, ref_v, on, 1.0), (w_lo, w_hi, w_speed, w_accel, w_accel, w_tau), dt)
    at_limit[3] = wl[0] <= w_lo[0] + 1e-6 or wl[0] >= w_hi[0] - 1e-6 or abs(wv[0]) >= w_speed[0] * (1 - 1e-3)
    return (wl, wv, wa, at_limit), (wl, wv)


@_jit
def _load_forces(r, v, wire, deck, p):
    """:func:`app.sim.load._forces` on scalars: the load's acceleration (3 floats), the tension, the deck's
    normal force and the gap; ``wire`` = (s, ṡ, L, L̇), ``deck`` = (present, d, n̂, v_d)."""
    s, sd, L, Ld = wire
    present, d, n, vd = deck
    m, ea, zeta_w, c_a, k_c, zeta_c, mu, v_s, g = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]
    e0, e1, e2 = r[0] - s[0], r[1] - s[1], r[2] - s[2]
    ell = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    u0, u1, u2 = e0 / ell, e1 / ell, e2 / ell
    k = ea / L
    stretch = ell - L
    T = 0.0
    if stretch > 0.0:
        rate = u0 * (v[0] - sd[0]) + u1 * (v[1] - sd[1]) + u2 * (v[2] - sd[2])
        T = max(0.0, k * stretch + 2.0 * zeta_w * math.sqrt(k * m) * (rate - Ld))
    f0 = -T * u0 - m * c_a * v[0]
    f1 = -T * u1 - m * c_a * v[1]
    f2 = -T * u2 - m * c_a * v[2] + m * g
    Fn, gap = 0.0, math.inf
    if present:
        gap = n[0] * (r[0] - d[0]) + n[1] * (r[1] - d[1]) + n[2] * (r[2] - d[2])
        if gap < 0.0:
            q0, q1, q2 = v[0] - vd[0], v[1] - vd[1], v[2] - vd[2]
            rel_n = n[0] * q0 + n[1] * q1 + n[2] * q2
            Fn = max(0.0, k_c * (-gap) + 2.0 * zeta_c * math.sqrt(k_c * m) * (-rel_n))
            t0, t1, t2 = q0 - n[0] * rel_n, q1 - n[1] * rel_n, q2 - n[2] * rel_n
            w = mu * Fn / math.sqrt(t0 * t0 + t1 * t1 + t2 * t2 + v_s * v_s)
            f0 = f0 + Fn * n[0] - w * t0
            f1 = f1 + Fn * n[1] - w * t1
            f2 = f2 + Fn * n[2] - w * t2
    return f0 / m, f1 / m, f2 / m, T, Fn, gap


@_jit
def load_block(x, u, p, dt):
    """:data:`app.sim.load.LOAD` (its NumPy reference: ``app.sim.load._load_reference``): state (r, v) (3,) each,
    updated in place; inputs (s₀, s₁, L₀, L₁, deck = (present, d, n̂, v_d)); parameters the LoadSpec record.
    y = (tension, contact force, gap) at the step's end."""
    r, v = x
    s0, s1, L0, L1, deck = u
    present, d0, n, vd = deck
    n_sub = p[9]
    h = dt / n_sub
    sd = (s1 - s0) / dt
    Ld = (L1 - L0) / dt
    pf = np.array([p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]])
    s = np.empty(3)
    d = np.empty(3)
    rk = np.empty(3)
    vk = np.empty(3)
    a = np.empty((4, 3))
    vs = np.empty((4, 3))
    for i in range(n_sub):
        tau0 = i * h
        for stage in range(4):
            if stage == 0:
                tau, c = tau0, 0.0
            elif stage == 3:
                tau, c = tau0 + h, h
            else:
                tau, c = tau0 + 0.5 * h, 0.5 * h
            for j in range(3):
                if stage == 0:
                    rk[j], vk[j] = r[j], v[j]
                else:
                    rk[j] = r[j] + c * vs[stage - 1, j]
                    vk[j] = v[j] + c * a[stage - 1, j]
                s[j] = s0[j] + sd[j] * tau
                d[j] = d0[j] + vd[j] * tau
                vs[stage, j] = vk[j]
            a0, a1, a2, _, _, _ = _load_forces(rk, vk, (s, sd, L0 + Ld * tau, Ld), (present, d, n, vd), pf)
            a[stage, 0], a[stage, 1], a[stage, 2] = a0, a1, a2
        for j in range(3):
            r[j] = r[j] + (h / 6.0) * (vs[0, j] + 2.0 * vs[1, j] + 2.0 * vs[2, j] + vs[3, j])
            v[j] = v[j] + (h / 6.0) * (a[0, j] + 2.0 * a[1, j] + 2.0 * a[2, j] + a[3, j])
    for j in range(3):
        d[j] = d0[j] + vd[j] * dt
    _, _, _, T, Fn, gap = _load_forces(r, v, (s1, sd, L1, Ld), (present, d, n, vd), pf)
    return (r, v), (T, Fn, gap)


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel the plants call from Python, with the
    argument types they pass (for :func:`app.warmup.warm_up`)."""
    o3, o6, z3, z6 = np.ones(3), np.ones(6), np.zeros(3), np.zeros(6)
    a_n, b_b = np.ones((6, 3)), np.full((6, 3), 0.5)
    on = np.bool_(True)

    def vec(n: int, value: float = 0.0) -> np.ndarray:
        return np.full(n, value)

    return [
        lambda: actuator_block((o6, o6, o6), (o6,), (-o6, o6, o6, o6, 0.05), 0.002),
        lambda: motion_filter_update((vec(3), vec(3), vec(3)), (o3, o3, on, 1.0), (-o3, o3, o3, o3, o3, 0.1), 0.01),
        lambda: clamp_to_legs(a_n, b_b, z6, 0.5, 1.5),
        lambda: follow_clamped(
            (a_n, b_b, 0.5, 1.5), (1.0, z6, z6), (vec(6), vec(6), vec(6)), (-o6, o6, o6, o6, 0.1), 0.01
        ),
        lambda: command_clip(z6, z6, -o6, o6),
        lambda: pendulum_block((0.1, 0.0, 0.0, 0.0), (z3, 1.0, 0.0), (0.1, 9.81), 0.01),
        # the crane's winch drum, stepped from Python by app.scenes.crane_load (issue 30; the lab's is in lab_step)
        lambda: drum_block(
            (vec(1, 10.0), vec(1), vec(1), np.zeros(4, dtype=np.bool_)),
            (vec(1, 10.0), vec(1)),
            (vec(1, 3.0), vec(1, 40.0), vec(1, 1.5), vec(1, 2.0), 0.05),
            0.01,
        ),
        # the crane's load on its wire (issue 30), stepped from Python by app.scenes.crane_load
        lambda: load_block(
            (vec(3), vec(3)),
            (vec(3, -10.0), vec(3, -10.0), 10.0, 10.0, (on, vec(3), np.array([0.0, 0.0, -1.0]), vec(3))),
            (5000.0, 5.0e7, 0.05, 0.02, 2.0e7, 1.0, 0.3, 0.01, 9.81, 10),
            0.01,
        ),
    ]
