"""Compiled per-step plant updates: the braking bound, the motion filter, the joint servos and the Motion-Lab.

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the
interpreted path).  The NumPy methods stay the reference, tested equal on the same seeded inputs:
:class:`~app.sim.actuators.JointActuators` and :class:`~app.sim.stewart.MotionFilter` in
``tests/test_kernels.py``; the Stewart kinematics (:class:`~app.models.stewart.StewartPlatform`), the
Comau on its platform, the pendulum and a whole :class:`~app.sim.motionlab.MotionLab` step in
``tests/test_sim_kernels.py``.

The Motion-Lab step (:func:`lab_step`) is one call doing what ``MotionLab.step`` does after the
platforms: body rates, the Comau's control and servo, the tool point, the winch, the load and the
sample.  Its state arrays are updated in place (allocating and returning them costs more than the
arithmetic).  Every array argument is C-contiguous float64 (bool for ``at_limit``): another layout
would make numba compile a second specialisation in a control tick.  Helpers take whole arrays or
scalars, never slices, so each keeps the single signature it gets from its callers (and flags as
``np.bool_``: a literal ``True`` in a call would compile another).

:func:`lab_step` links :func:`app.models.kernels.comau_candidates` (eqs. 7–20) into its cached machine
code, and numba's cache does not notice edits in another file: after changing that function, touch
this file (or delete ``app/sim/__pycache__/kernels.*.nb?``).
"""

from __future__ import annotations

import math

import numpy as np

from app.models import kernels as model_kernels
from app.models.kernels import ENABLED, _jit

__all__ = [
    "ENABLED",
    "actuator_block",
    "actuator_step",
    "approach_speed",
    "braking_speed",
    "clamp_to_legs",
    "comau_ik",
    "comau_tool",
    "command_clip",
    "follow_clamped",
    "lab_step",
    "leg_lengths",
    "lstsq3",
    "motion_filter_step",
    "motion_filter_update",
    "pendulum_block",
    "pendulum_step",
    "pose_in",
    "rotation_xyz",
    "stewart_rates",
    "tool_on_platform",
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
def motion_filter_update(x, v, a, x_ref, v_ref, use_v_ref, lower, upper, speed, accel, brake, tau, dt, speed_scale):
    """One :meth:`MotionFilter.step` in place: x, v, a become x⁺, v⁺, a (x_ref may be x itself); ``brake``
    (≤ accel) is the deceleration of the velocity bound at the position limits."""
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
def motion_filter_step(x, v, x_ref, v_ref, use_v_ref, lower, upper, speed, accel, brake, tau, dt, speed_scale):
    """One :meth:`MotionFilter.step`: (x⁺, v⁺, a), new arrays."""
    x_new, v_new, a_new = x.copy(), v.copy(), np.empty(x.shape[0])
    motion_filter_update(
        x_new, v_new, a_new, x_ref, v_ref, use_v_ref, lower, upper, speed, accel, brake, tau, dt, speed_scale
    )  # fmt: skip
    return x_new, v_new, a_new


@_jit
def actuator_step(q, qdot, q_ref, lower, upper, speed, accel, tau, dt):
    """One :meth:`JointActuators.step`: (q⁺, q̇⁺, q̈)."""
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
    return q_new, v_new, a_new


@_jit
def actuator_block(x, u, p, dt):
    """The joint actuators as a block (:data:`app.sim.actuators.JOINT_ACTUATORS`): state (q, q̇, q̈), input
    (q_ref,), parameters (lower, upper, speed, accel, τ); returns (x', y) with y = (q,)."""
    q, qdot, _ = x
    q_new, v_new, a_new = actuator_step(q, qdot, u[0], p[0], p[1], p[2], p[3], p[4], dt)
    return (q_new, v_new, a_new), (q_new,)


# ============================================================================= Motion-Lab
# ----------------------------------------------------------------------------- small algebra
@_jit
def _matmul(A, B):
    """A @ B for square C-contiguous matrices (3×3 or 4×4), a new array."""
    C = np.empty((A.shape[0], A.shape[0]))
    model_kernels.matmul_into(A, B, C)
    return C


@_jit
def _mv(A, x0, x1, x2):
    """A @ (x0, x1, x2) for the upper-left 3×3 block of A (3×3 or 4×4)."""
    out = np.empty(3)
    for i in range(3):
        out[i] = A[i, 0] * x0 + A[i, 1] * x1 + A[i, 2] * x2
    return out


@_jit
def _mtv(A, x0, x1, x2):
    """A[:3, :3]ᵀ @ (x0, x1, x2)."""
    out = np.empty(3)
    for i in range(3):
        out[i] = A[0, i] * x0 + A[1, i] * x1 + A[2, i] * x2
    return out


@_jit
def _skew(x, y, z):
    """S(v) of Motion-Lab eq. (46): S(v) w = v × w."""
    S = np.zeros((3, 3))
    S[0, 1], S[0, 2] = -z, y
    S[1, 0], S[1, 2] = z, -x
    S[2, 0], S[2, 1] = -y, x
    return S


@_jit
def _remainder(x, y):
    """IEEE remainder x − n y, n the nearest integer to x / y (ties to even): CPython's ``math.remainder``."""
    if math.isfinite(x) and math.isfinite(y):
        if y == 0.0:
            return math.nan
        absx, absy = abs(x), abs(y)
        m = np.fmod(absx, absy)
        c = absy - m
        if m < c:
            r = m
        elif m > c:
            r = -c
        else:  # half way: the even multiple
            r = m - 2.0 * np.fmod(0.5 * (absx - m), absy)
        return math.copysign(1.0, x) * r
    if math.isnan(x):
        return x
    if math.isnan(y):
        return y
    if math.isinf(x):
        return math.nan
    return x


@_jit
def lstsq3(J, b):
    """``np.linalg.lstsq(J, b, rcond=1e-6)[0]`` for a 3×3 J (eq. 21: q̇ = J⁺ ṗ).

    s_min/s_max ≥ |det J| / ‖J‖_F³ (s_max ≤ ‖J‖_F, s_min = |det J| / (s_max s_mid)): above 1e-3, far
    from the cut-off, the least-squares solution is J⁻¹ b, solved here by Gaussian elimination with
    partial pivoting (a tenth of LAPACK's cost); otherwise LAPACK's SVD solver, as NumPy's.
    """
    det = (
        J[0, 0] * (J[1, 1] * J[2, 2] - J[1, 2] * J[2, 1])
        - J[0, 1] * (J[1, 0] * J[2, 2] - J[1, 2] * J[2, 0])
        + J[0, 2] * (J[1, 0] * J[2, 1] - J[1, 1] * J[2, 0])
    )
    fro2 = 0.0
    for i in range(3):
        for j in range(3):
            fro2 += J[i, j] * J[i, j]
    if not abs(det) > 1e-3 * fro2 * math.sqrt(fro2):
        return np.linalg.lstsq(J, b, rcond=1e-6)[0]
    A, x = J.copy(), b.copy()
    for k in range(3):
        p = k
        for i in range(k + 1, 3):
            if abs(A[i, k]) > abs(A[p, k]):
                p = i
        if p != k:
            for j in range(3):
                A[k, j], A[p, j] = A[p, j], A[k, j]
            x[k], x[p] = x[p], x[k]
        for i in range(k + 1, 3):
            f = A[i, k] / A[k, k]
            for j in range(k, 3):
                A[i, j] -= f * A[k, j]
            x[i] -= f * x[k]
    for k in range(2, -1, -1):
        s = x[k]
        for j in range(k + 1, 3):
            s -= A[k, j] * x[j]
        x[k] = s / A[k, k]
    return x


# ----------------------------------------------------------------------------- Stewart platform
@_jit
def rotation_xyz(phi, theta, psi):
    """R_b^n = R_x(φ) R_y(θ) R_z(ψ), Motion-Lab eq. (33) in the order eq. (44) implies (3, 3).

    The product written out, (R_x R_y) first and then R_z, as the reference multiplies them."""
    cf, sf = math.cos(phi), math.sin(phi)
    ct, st = math.cos(theta), math.sin(theta)
    cp, sp = math.cos(psi), math.sin(psi)
    M = np.empty((3, 3))  # R_x R_y
    M[0, 0], M[0, 1], M[0, 2] = ct, 0.0, st
    M[1, 0], M[1, 1], M[1, 2] = sf * st, cf, -sf * ct
    M[2, 0], M[2, 1], M[2, 2] = -cf * st, sf, cf * ct
    R = np.empty((3, 3))
    for i in range(3):
        R[i, 0] = M[i, 0] * cp + M[i, 1] * sp
        R[i, 1] = M[i, 0] * -sp + M[i, 1] * cp
        R[i, 2] = M[i, 2]
    return R


@_jit
def _pose(eta):
    """H_b^n of eq. (38) (4, 4)."""
    H = np.zeros((4, 4))
    R = rotation_xyz(eta[3], eta[4], eta[5])
    for i in range(3):
        for j in range(3):
            H[i, j] = R[i, j]
        H[i, 3] = eta[i]
    H[3, 3] = 1.0
    return H


@_jit
def pose_in(T, eta):
    """T @ H_b^n(η) (4, 4): a platform body in the world, eq. (39) with eq. (38)."""
    return _matmul(T, _pose(eta))


@_jit
def leg_lengths(a_n, b_b, eta):
    """The six leg lengths |p + R b_k − a_k| of pose η, eqs. (31)–(38) (inverse kinematics) (6,)."""
    R = rotation_xyz(eta[3], eta[4], eta[5])
    out = np.empty(a_n.shape[0])
    for k in range(a_n.shape[0]):
        ss = 0.0
        for i in range(3):
            li = (eta[i] + (R[i, 0] * b_b[k, 0] + R[i, 1] * b_b[k, 1] + R[i, 2] * b_b[k, 2])) - a_n[k, i]
            ss += li * li
        out[k] = math.sqrt(ss)
    return out


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
def follow_clamped(a_n, b_b, lo, hi, gain, eta_s, v_s, x, v, a, lower, upper, speed, accel, tau, dt):
    """An engaged platform's step in place (``Platform.step``): the source pose η_s times the ramp gain,
    clipped to the command box (the filter's limits while engaged, :func:`command_clip`), scaled back
    into the leg strokes (:func:`clamp_to_legs`, eqs. 31–38), then the motion filter with the feed-forward
    gain·η̇_s.  Returns whether the pose was scaled back."""
    eta_c, v_c = command_clip(gain * eta_s, gain * v_s, lower, upper)
    target, clamped = clamp_to_legs(a_n, b_b, eta_c, lo, hi)
    on = np.bool_(True)  # a plain bool: a literal True would compile a second specialisation
    motion_filter_update(x, v, a, target, v_c, on, lower, upper, speed, accel, accel, tau, dt, 1.0)
    return clamped


@_jit
def stewart_rates(eta, eta_dot, eta_ddot):
    """R, Ṙ, R̈ of a platform body (3, 3) each: R of eq. (33); ω = T(δ)⁻¹ δ̇ (eq. 45),
    ω̇ = T⁻¹(δ̈ − Ṫ ω) (eq. 50, Ṫ of eq. 49); Ṙ = R S(ω) (eq. 47), R̈ = R S(ω)² + R S(ω̇) (eq. 51)."""
    th, psi = eta[4], eta[5]
    ct, st, cp, sp = math.cos(th), math.sin(th), math.cos(psi), math.sin(psi)
    Ti = np.zeros((3, 3))  # T(δ)⁻¹
    Ti[0, 0], Ti[0, 1] = ct * cp, sp
    Ti[1, 0], Ti[1, 1] = -ct * sp, cp
    Ti[2, 0], Ti[2, 2] = st, 1.0
    dth, dpsi = eta_dot[4], eta_dot[5]
    tt, sec = st / ct, 1.0 / ct
    Td = np.zeros((3, 3))  # d/dt T(δ) of eq. (44)
    Td[0, 0] = cp * sec * tt * dth - sp * sec * dpsi
    Td[0, 1] = -sp * sec * tt * dth - cp * sec * dpsi
    Td[1, 0] = cp * dpsi
    Td[1, 1] = -sp * dpsi
    Td[2, 0] = -cp * (sec * sec) * dth + tt * sp * dpsi
    Td[2, 1] = sp * (sec * sec) * dth + tt * cp * dpsi
    w = _mv(Ti, eta_dot[3], eta_dot[4], eta_dot[5])
    Tw = _mv(Td, w[0], w[1], w[2])
    wd = _mv(Ti, eta_ddot[3] - Tw[0], eta_ddot[4] - Tw[1], eta_ddot[5] - Tw[2])
    R = rotation_xyz(eta[3], eta[4], eta[5])
    Sw, Swd = _skew(w[0], w[1], w[2]), _skew(wd[0], wd[1], wd[2])
    Rd = _matmul(R, Sw)
    Rdd = _matmul(Rd, Sw) + _matmul(R, Swd)  # Ṙ = R S(ω), R̈ = Ṙ S(ω) + R S(ω̇)
    return R, Rd, Rdd


# ----------------------------------------------------------------------------- Comau
@_jit
def comau_tool(cm, q, qd, qdd):
    """Tool point of the Comau in its base {r}: p (eq. 3), ṗ = J q̇ (eqs. 4–5), p̈ = J̇ q̇ + J q̈ (eq. 6);
    ``cm`` = (a1, d1, a2, a3, L).  Returns (p, ṗ, p̈, J)."""
    a1, d1, a2, a3, L = cm[0], cm[1], cm[2], cm[3], cm[4]
    s1, c1 = math.sin(q[0]), math.cos(q[0])
    s2, c2 = math.sin(q[1]), math.cos(q[1])
    s3, c3 = math.sin(q[2]), math.cos(q[2])
    u = a1 - L * s3 - a3 * c3 + a2 * s2  # radial reach
    z = d1 + L * c3 + a2 * c2 - a3 * s3
    p = np.empty(3)
    p[0], p[1], p[2] = c1 * u, -s1 * u, z
    u2, u3 = a2 * c2, -L * c3 + a3 * s3
    z2, z3 = -a2 * s2, -L * s3 - a3 * c3
    J = np.empty((3, 3))
    J[0, 0], J[0, 1], J[0, 2] = -s1 * u, c1 * u2, c1 * u3
    J[1, 0], J[1, 1], J[1, 2] = -c1 * u, -s1 * u2, -s1 * u3
    J[2, 0], J[2, 1], J[2, 2] = 0.0, z2, z3
    e1, e2, e3 = qd[0], qd[1], qd[2]
    ud = u2 * e2 + u3 * e3
    udd = -a2 * s2 * (e2 * e2) + (L * s3 + a3 * c3) * (e3 * e3)
    zdd = -a2 * c2 * (e2 * e2) + (-L * c3 + a3 * s3) * (e3 * e3)
    jx = -c1 * (e1 * e1) * u - 2 * s1 * e1 * ud + c1 * udd
    jy = s1 * (e1 * e1) * u - 2 * c1 * e1 * ud - s1 * udd
    v = _mv(J, e1, e2, e3)
    Jqdd = _mv(J, qdd[0], qdd[1], qdd[2])
    a = np.empty(3)
    a[0], a[1], a[2] = jx + Jqdd[0], jy + Jqdd[1], zdd + Jqdd[2]
    return p, v, a, J


@_jit
def tool_on_platform(cm, T_b1_r, eta, eta_dot, eta_ddot, R, Rd, Rdd, q, qd, qdd):
    """Tool point in the platform's neutral frame {n1}: eqs. (54), (56), (57) with R, Ṙ, R̈ of
    eqs. (33), (47), (51) (see :func:`app.sim.motionlab.tool_on_platform`): (p, ṗ, p̈)."""
    p_tr, v_tr, a_tr, _ = comau_tool(cm, q, qd, qdd)
    arm = _mv(T_b1_r, p_tr[0], p_tr[1], p_tr[2])
    for i in range(3):
        arm[i] = T_b1_r[i, 3] + arm[i]
    Rv = _mv(T_b1_r, v_tr[0], v_tr[1], v_tr[2])
    Ra = _mv(T_b1_r, a_tr[0], a_tr[1], a_tr[2])
    R_arm = _mv(R, arm[0], arm[1], arm[2])
    Rd_arm = _mv(Rd, arm[0], arm[1], arm[2])
    Rdd_arm = _mv(Rdd, arm[0], arm[1], arm[2])
    R_Rv, Rd_Rv, R_Ra = _mv(R, Rv[0], Rv[1], Rv[2]), _mv(Rd, Rv[0], Rv[1], Rv[2]), _mv(R, Ra[0], Ra[1], Ra[2])
    p, v, a = np.empty(3), np.empty(3), np.empty(3)
    for i in range(3):
        p[i] = eta[i] + R_arm[i]
        v[i] = eta_dot[i] + Rd_arm[i] + R_Rv[i]
        a[i] = eta_ddot[i] + Rdd_arm[i] + 2.0 * Rd_Rv[i] + R_Ra[i]
    return p, v, a


@_jit
def comau_ik(cm, T_base, p_tr, q_near, signs, lower, upper):
    """``MotionLab._ik``: the exact candidate of eqs. (7)–(20) inside the joint limits nearest q_near,
    q1 wrapped to within half a turn of it: (q, found)."""
    Q, exact = model_kernels.comau_candidates((cm[0], cm[1], cm[2], cm[3], cm[4], T_base), p_tr, q_near[0], signs)
    best = q_near.copy()
    best_d = np.inf
    found = False
    for k in range(Q.shape[0]):
        q = Q[k].copy()
        q[0] = q_near[0] + _remainder(q[0] - q_near[0], 2 * math.pi)
        if not exact[k]:
            continue
        inside = True
        for i in range(3):
            if not (q[i] >= lower[i] - 1e-9 and q[i] <= upper[i] + 1e-9):
                inside = False
        if not inside:
            continue
        d = 0.0
        for i in range(3):
            d += (q[i] - q_near[i]) * (q[i] - q_near[i])
        if d < best_d:
            best, best_d, found = q, d, True
    return best, found


# ----------------------------------------------------------------------------- pendulum
@_jit
def _pendulum_derivative(a, b, ad, bd, ax, ay, az, L, Ld, c, g):
    """Eqs. (29)–(30) / (60)–(61) with the z̈ sign of a z-down frame and damping −c φ̇
    (:meth:`app.sim.motionlab.Pendulum.derivative`)."""
    sa, ca, sb, cb = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
    add = (ax * ca + ay * sa * sb + az * sa * cb - g * sa * cb - 2 * Ld * ad - L * bd * bd * sa * ca) / L - c * ad
    ca_safe = ca if abs(ca) > 1e-6 else math.copysign(1e-6, ca)
    bdd = (-ay * cb + az * sb - g * sb - 2 * Ld * bd * ca + 2 * L * ad * bd * sa) / (L * ca_safe) - c * bd
    return ad, bd, add, bdd


@_jit
def pendulum_step(alpha, beta, alpha_dot, beta_dot, dt, ax, ay, az, L, Ld, c, g):
    """One RK4 step of the load (eqs. 29–30 / 60–61, :meth:`Pendulum.step`), tool acceleration
    (ax, ay, az) in {d} held, wire length L + Ld·s: (α, β, α̇, β̇)."""
    x0, x1, x2, x3 = alpha, beta, alpha_dot, beta_dot
    h = 0.5 * dt
    k10, k11, k12, k13 = _pendulum_derivative(x0, x1, x2, x3, ax, ay, az, L, Ld, c, g)
    Lh = L + h * Ld
    k20, k21, k22, k23 = _pendulum_derivative(
        x0 + h * k10, x1 + h * k11, x2 + h * k12, x3 + h * k13, ax, ay, az, Lh, Ld, c, g
    )  # fmt: skip
    k30, k31, k32, k33 = _pendulum_derivative(
        x0 + h * k20, x1 + h * k21, x2 + h * k22, x3 + h * k23, ax, ay, az, Lh, Ld, c, g
    )  # fmt: skip
    k40, k41, k42, k43 = _pendulum_derivative(
        x0 + dt * k30, x1 + dt * k31, x2 + dt * k32, x3 + dt * k33, ax, ay, az, L + dt * Ld, Ld, c, g
    )  # fmt: skip
    f = dt / 6.0
    return (
        x0 + f * (k10 + 2 * k20 + 2 * k30 + k40),
        x1 + f * (k11 + 2 * k21 + 2 * k31 + k41),
        x2 + f * (k12 + 2 * k22 + 2 * k32 + k42),
        x3 + f * (k13 + 2 * k23 + 2 * k33 + k43),
    )


@_jit
def pendulum_block(x, u, p, dt):
    """The load as a block (:data:`app.sim.motionlab.PENDULUM`): state (α, β, α̇, β̇), inputs (a_t^d (3,) in {d},
    L, L̇), parameters (c, g); y = (α, β)."""
    a_t = u[0]
    a, b, ad, bd = pendulum_step(x[0], x[1], x[2], x[3], dt, a_t[0], a_t[1], a_t[2], u[1], u[2], p[0], p[1])
    return (a, b, ad, bd), (a, b)


# ----------------------------------------------------------------------------- the lab
@_jit
def lab_step(
    x1, v1, a1, x2, v2, a2, rates,
    cx1, cv1, ca1, cx2, cv2, ca2, measured, off_p, off_v,
    cm, T_base, signs, T_g_n1, T_g_n2, T_n1_n2, T_b1_r, w_b2, park_q,
    q, qd, qdd, q_lo, q_hi, q_speed, q_accel, q_brake, q_tau, comau_mode, v_cmd,
    wl, wv, wa, w_lo, w_hi, w_speed, w_accel, w_tau, track, speed_cmd,
    target, has_target, alpha, beta, alpha_dot, beta_dot, damping, g,
    a_n1, b_b1, a_n2, b_b2,
    p_t_n1, p_t_g, v_t_g, a_t_g, at_limit, e_b2, p_w_g, p_p_g, legs1, legs2,
    dt,
):  # fmt: skip
    """One :meth:`MotionLab.step` after the platforms, in place (the reference is the NumPy methods).

    Platforms: η, η̇, η̈ of EM8000 (x1, v1, a1) and EM1500 (x2, v2, a2); ``rates`` (2, 3, 3, 3) receives
    R, Ṙ, R̈ of both bodies (eqs. 33, 47, 51).  The controllers (the Comau's MOTION_COMP and the winch's
    height tracking) see the platforms as measured, (cx1, cv1, ca1) and (cx2, cv2, ca2), when
    ``measured`` (else the true states); the plant, the load and the scores always use the true ones.
    ``off_p``, ``off_v``: an offset (position, velocity in {n1}) added to the work point the Comau
    tracks in MOTION_COMP (the anti-swing law's).  Comau (``cm`` = a1, d1, a2, a3, L; joint filter q, q̇, q̈
    and limits, ``q_brake`` the deceleration A of the velocity bound at the joint limits): ``comau_mode``
    0 settled (to ``park_q`` at a quarter speed), 1 remote (q̇ = J⁺ v_cmd, eq. 21), 2 motion_comp (the
    work point w_b2 fixed in {b2} through eqs. 54–56 inverted, IK of eqs. 7–20, feed-forward
    q̇ = J⁺ ṗ_t^r of eq. 21), 3 brake (HOLD or E-STOP).  Tool point p, ṗ, p̈ in {n1} (eqs. 54, 56, 57)
    and in {g} (eq. 55).  Winch (filter wl, wv, wa and limits): ``track`` keeps the load's height
    relative to EM1500 at ``target`` (in {b2}; captured now unless ``has_target``), else the speed
    command.  Load: RK4 of eqs. (29)–(30) / (60)–(61) with p̈_t^g of eq. (57).  Sample: e_b2 (tool
    minus work point in {b2}), the work point and the load (eq. 58) in {g}, the legs of both platforms.

    Returns (has_target, α, β, α̇, β̇, payload height error).
    """
    on, off = np.bool_(True), np.bool_(False)  # plain bools: literals would compile more specialisations
    # body rates of both platforms (eqs. 33, 45, 47, 50, 51)
    R1, Rd1, Rdd1 = stewart_rates(x1, v1, a1)
    R2b, Rd2, Rdd2 = stewart_rates(x2, v2, a2)
    for i in range(3):
        for j in range(3):
            rates[0, 0, i, j], rates[0, 1, i, j], rates[0, 2, i, j] = R1[i, j], Rd1[i, j], Rdd1[i, j]
            rates[1, 0, i, j], rates[1, 1, i, j], rates[1, 2, i, j] = R2b[i, j], Rd2[i, j], Rdd2[i, j]
    # ... and as the controllers see them
    if measured:
        cR1, cRd1, _ = stewart_rates(cx1, cv1, ca1)
        cR2, cRd2, _ = stewart_rates(cx2, cv2, ca2)
    else:
        cx1, cv1, cx2, cv2 = x1, v1, x2, v2
        cR1, cRd1, cR2, cRd2 = R1, Rd1, R2b, Rd2

    # ---- the Comau
    if comau_mode == 3:  # brake at the acceleration limits to rest, then stay
        for i in range(3):
            dv = min(max(-qd[i], -q_accel[i] * dt), q_accel[i] * dt)
            vn = qd[i] + dv
            qdd[i] = (vn - qd[i]) / dt
            qd[i] = vn
            q[i] = min(max(q[i] + vn * dt, q_lo[i]), q_hi[i])
    else:
        if comau_mode == 0:
            motion_filter_update(
                q, qd, qdd, park_q, park_q, off, q_lo, q_hi, q_speed, q_accel, q_brake, q_tau, dt, 0.25
            )
        elif comau_mode == 1:
            J = comau_tool(cm, q, qd, qdd)[3]
            rate = lstsq3(J, v_cmd)  # eq. (21)
            q_ref = q + rate * dt
            motion_filter_update(q, qd, qdd, q_ref, rate, on, q_lo, q_hi, q_speed, q_accel, q_brake, q_tau, dt, 1.0)
        else:  # inverse kinematic control with feed-forward of both platforms
            # the work point fixed in {b2} (plus the offset), in {n1} (eq. 39 through {g}), as measured
            w = _mv(cR2, w_b2[0], w_b2[1], w_b2[2])
            Rdw = _mv(cRd2, w_b2[0], w_b2[1], w_b2[2])
            pw = _mv(T_n1_n2, cx2[0] + w[0], cx2[1] + w[1], cx2[2] + w[2])
            vw = _mv(T_n1_n2, cv2[0] + Rdw[0], cv2[1] + Rdw[1], cv2[2] + Rdw[2])
            for i in range(3):
                pw[i] = T_n1_n2[i, 3] + pw[i] + off_p[i]
                vw[i] = vw[i] + off_v[i]
            # eqs. (54), (56) inverted for the tool point in {r}
            b = _mtv(cR1, pw[0] - cx1[0], pw[1] - cx1[1], pw[2] - cx1[2])
            p_tr = _mtv(T_b1_r, b[0] - T_b1_r[0, 3], b[1] - T_b1_r[1, 3], b[2] - T_b1_r[2, 3])
            arm = _mv(T_b1_r, p_tr[0], p_tr[1], p_tr[2])
            for i in range(3):
                arm[i] = T_b1_r[i, 3] + arm[i]
            Rd_arm = _mv(cRd1, arm[0], arm[1], arm[2])
            c = _mtv(cR1, vw[0] - cv1[0] - Rd_arm[0], vw[1] - cv1[1] - Rd_arm[1], vw[2] - cv1[2] - Rd_arm[2])
            v_tr = _mtv(T_b1_r, c[0], c[1], c[2])
            q_d, found = comau_ik(cm, T_base, p_tr, q, signs, q_lo, q_hi)
            if not found:  # out of reach: hold, limits intact
                q_d = q.copy()
            J = comau_tool(cm, q_d, qd, qdd)[3]
            rate = lstsq3(J, v_tr)  # eq. (21)
            motion_filter_update(q, qd, qdd, q_d, rate, on, q_lo, q_hi, q_speed, q_accel, q_brake, q_tau, dt, 1.0)
        for i in range(3):
            at_limit[i] = q[i] <= q_lo[i] + 1e-6 or q[i] >= q_hi[i] - 1e-6 or abs(qd[i]) >= q_speed[i] * (1 - 1e-3)

    # ---- the tool point (eqs. 54–57)
    p, v, a = tool_on_platform(cm, T_b1_r, x1, v1, a1, R1, Rd1, Rdd1, q, qd, qdd)
    pg, vg, ag = _mv(T_g_n1, p[0], p[1], p[2]), _mv(T_g_n1, v[0], v[1], v[2]), _mv(T_g_n1, a[0], a[1], a[2])
    for i in range(3):
        p_t_n1[i] = p[i]
        p_t_g[i] = pg[i] + T_g_n1[i, 3]  # eq. (55)
        v_t_g[i] = vg[i]
        a_t_g[i] = ag[i]

    # ---- the winch (its height tracking sees EM1500 as measured)
    H2 = pose_in(T_g_n2, x2)  # H^g_b2, eq. (39)
    cH2 = pose_in(T_g_n2, cx2) if measured else H2
    ref, ref_v = np.empty(1), np.empty(1)
    if track:
        if not has_target:  # keep the load where it is now, relative to EM1500
            sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
            L0 = wl[0]
            pp0 = p_t_g[0] + L0 * -sa - cH2[0, 3]
            pp1 = p_t_g[1] - L0 * (ca * sb) - cH2[1, 3]
            pp2 = p_t_g[2] - L0 * (ca * cb) - cH2[2, 3]
            t = _mtv(cH2, pp0, pp1, pp2)
            for i in range(3):
                target[i] = t[i]
            has_target = True
        tg = _mv(cH2, target[0], target[1], target[2])
        Rdt = _mv(cRd2, target[0], target[1], target[2])
        vtg = _mv(T_g_n2, cv2[0] + Rdt[0], cv2[1] + Rdt[1], cv2[2] + Rdt[2])
        # heights along gravity: the load hangs L_w below the tool (small swing)
        ref[0] = p_t_g[2] - (tg[2] + cH2[2, 3])
        ref_v[0] = v_t_g[2] - vtg[2]
    else:
        s = min(max(speed_cmd, -w_speed[0]), w_speed[0])
        ref[0] = wl[0] + s * dt
        ref_v[0] = s
    motion_filter_update(wl, wv, wa, ref, ref_v, on, w_lo, w_hi, w_speed, w_accel, w_accel, w_tau, dt, 1.0)
    at_limit[3] = wl[0] <= w_lo[0] + 1e-6 or wl[0] >= w_hi[0] - 1e-6 or abs(wv[0]) >= w_speed[0] * (1 - 1e-3)

    # ---- the load (eqs. 29–30 / 60–61 with p̈_t^g of eq. 57, in {d}: (x, −y, −z))
    alpha, beta, alpha_dot, beta_dot = pendulum_step(
        alpha, beta, alpha_dot, beta_dot, dt, a_t_g[0], -a_t_g[1], -a_t_g[2], wl[0], wv[0], damping, g
    )  # fmt: skip

    # ---- the sample
    sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
    L0 = wl[0]
    p_p_g[0] = p_t_g[0] + L0 * -sa  # eq. (58)
    p_p_g[1] = p_t_g[1] - L0 * (ca * sb)
    p_p_g[2] = p_t_g[2] - L0 * (ca * cb)
    e = _mtv(H2, p_t_g[0] - H2[0, 3], p_t_g[1] - H2[1, 3], p_t_g[2] - H2[2, 3])
    wg = _mv(H2, w_b2[0], w_b2[1], w_b2[2])
    for i in range(3):
        e_b2[i] = e[i] - w_b2[i]
        p_w_g[i] = wg[i] + H2[i, 3]
    h_err = 0.0
    if has_target:
        tg = _mv(H2, target[0], target[1], target[2])
        h_err = p_p_g[2] - (tg[2] + H2[2, 3])
    l1, l2 = leg_lengths(a_n1, b_b1, x1), leg_lengths(a_n2, b_b2, x2)
    for k in range(6):
        legs1[k], legs2[k] = l1[k], l2[k]
    return has_target, alpha, beta, alpha_dot, beta_dot, h_err


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel the plants call from Python, with the
    argument types they pass (for :func:`app.warmup.warm_up`)."""
    o3, o6, z3, z6 = np.ones(3), np.ones(6), np.zeros(3), np.zeros(6)
    eye = np.eye(4)
    a_n, b_b = np.ones((6, 3)), np.full((6, 3), 0.5)
    cm = np.array([0.35, 0.83, 1.16, 0.25, 2.269])  # any numbers compile; these are Tables 3/7 (L = 2.269 m)
    signs = np.array([1.0, -1.0])

    def vec(n: int, value: float = 0.0) -> np.ndarray:
        return np.full(n, value)

    def lab() -> None:
        lab_step(
            z6, z6, z6, z6, z6, z6, np.zeros((2, 3, 3, 3)), z6, z6, z6, z6, z6, z6, True, z3, z3,
            cm, eye, signs, eye, eye, eye, eye, o3, z3,
            vec(3), vec(3), vec(3), vec(3, -3.0), vec(3, 3.0), o3, o3, o3, 0.05, 2, z3,
            vec(1, 1.0), vec(1), vec(1), vec(1, 0.3), vec(1, 2.5), vec(1, 0.5), vec(1, 1.5), 0.05, True, 0.0,
            vec(3), False, 0.0, 0.0, 0.0, 0.0, 0.1, 9.81, a_n, b_b, a_n, b_b,
            vec(3), vec(3), vec(3), vec(3), np.zeros(4, dtype=np.bool_), vec(3), vec(3), vec(3), vec(6), vec(6), 0.01,
        )  # fmt: skip

    return [
        lambda: motion_filter_step(o6, o6, o6, o6, True, -o6, o6, o6, o6, o6, 0.1, 0.01, 1.0),
        lambda: actuator_step(o6, o6, o6, -o6, o6, o6, o6, 0.05, 0.002),
        lambda: actuator_block((o6, o6, o6), (o6,), (-o6, o6, o6, o6, 0.05), 0.002),
        lambda: motion_filter_update(vec(3), vec(3), vec(3), o3, o3, True, -o3, o3, o3, o3, o3, 0.1, 0.01, 1.0),
        lambda: clamp_to_legs(a_n, b_b, z6, 0.5, 1.5),
        lambda: follow_clamped(a_n, b_b, 0.5, 1.5, 1.0, z6, z6, vec(6), vec(6), vec(6), -o6, o6, o6, o6, 0.1, 0.01),
        lambda: command_clip(z6, z6, -o6, o6),
        lambda: pendulum_step(0.1, 0.0, 0.0, 0.0, 0.01, 0.0, 0.0, 0.0, 1.0, 0.0, 0.1, 9.81),
        lambda: pendulum_block((0.1, 0.0, 0.0, 0.0), (z3, 1.0, 0.0), (0.1, 9.81), 0.01),
        lambda: pose_in(eye, z6),
        lab,
    ]
