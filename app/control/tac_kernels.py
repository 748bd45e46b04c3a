"""Compiled per-step loops of the crane-head simulation (TAC paper §3–8 and §10).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path).  The NumPy methods stay the reference, tested equal on the same seeded inputs in
``tests/test_tac_kernels.py``: ``DeltaHead.ik`` and ``fk`` (:mod:`app.models.delta`),
``CraneHead.crane_ik_tcp`` and ``head_reference``, ``HeadServo.run`` and ``CraneServo.run``
(:mod:`app.control.tac`), and a whole :func:`app.sim.tac.simulate` in each mode.

:func:`tac_chunk` is one call doing what ``TacSimulator.advance`` does after the vessel motion: the
crane joints, the head references, the PID and DC motors, the head's forward kinematics and the
errors of eq. (61), step by step.  Servo states are updated in place.  Every array argument is
C-contiguous float64 (another layout would make numba compile a second specialisation in an engine
tick); the constants come in tuples built once by the models:

* ``chain``: the crane's ``SerialRobot.kernel_args`` (θ₀, d₀, a, cos α, sin α, M_θ, M_d, T_world_base,
  T_flange_tool; eq. 39);
* ``head``: ``DeltaHead.kernel_args`` (l_a, a = l_p − l_k, l_r, R_{t_i}^t (3, 3, 3), α_min, α_max);
* ``hull``: the workspace's facet equations (m, 4) (n·p + b ≤ 0 inside, |n| = 1), centre p_d^t and the
  radius of the largest ball about it inside the hull (its depth, §6);
* ``elbow``: (L0, L1, L2 + x_d, T_world_1⁻¹ (4, 4)) of eqs. (42)–(44) carrying the TCP (§8);
* ``pid``: (K_p, K_i, K_d, T_DC, K_DC, u_min, u_max, α_min, α_max) of eqs. (57)–(58);
* ``crane``: (β_min, β_max, β̇_max, β̈_max, share, k_p) of the cooperative crane servo.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit, matmul_into

__all__ = [
    "ENABLED",
    "c_array",
    "crane_ik_tcp",
    "crane_servo",
    "delta_fk",
    "delta_ik",
    "head_reference",
    "head_servo",
    "tac_chunk",
    "warm_up_steps",
]

CRANE_HOLD, CRANE_COOPERATIVE, CRANE_RETURN = 0, 1, 2  # crane modes of tac_chunk
HEAD_LOCK, HEAD_SERVO = 0, 1  # head modes of tac_chunk
COLLINEAR, NO_ASSEMBLY = 1, 2  # forward kinematics failures


def c_array(x) -> np.ndarray:
    """x as a writable C-contiguous float64 array, copied only when needed: the one array type the kernels
    are compiled for (a read-only or strided array, e.g. from ``np.broadcast_to``, would be another)."""
    a = np.ascontiguousarray(x, dtype=np.float64)
    return a if a.flags.writeable else a.copy()


# ----------------------------------------------------------------------------- small algebra
@_jit
def _rot_zyx(phi, theta, psi, R):
    """R_b^n = Rz(ψ) Ry(θ) Rx(φ) into R (Fossen 2011 eq. 2.18; TAC paper eq. 37, see app.geometry)."""
    cf, sf = math.cos(phi), math.sin(phi)
    ct, st = math.cos(theta), math.sin(theta)
    cp, sp = math.cos(psi), math.sin(psi)
    R[0, 0], R[0, 1], R[0, 2] = cp * ct, -sp * cf + cp * st * sf, sp * sf + cp * st * cf
    R[1, 0], R[1, 1], R[1, 2] = sp * ct, cp * cf + sp * st * sf, -cp * sf + sp * st * cf
    R[2, 0], R[2, 1], R[2, 2] = -st, ct * sf, ct * cf


@_jit
def _to_n(R, eta, o, M, p, out):
    """out = R (o + M p) + η₁: a point p of a frame at o, M in {b}, expressed in {n} (``CraneHead.tcp_n``)."""
    q0 = o[0] + (M[0, 0] * p[0] + M[0, 1] * p[1] + M[0, 2] * p[2])
    q1 = o[1] + (M[1, 0] * p[0] + M[1, 1] * p[1] + M[1, 2] * p[2])
    q2 = o[2] + (M[2, 0] * p[0] + M[2, 1] * p[1] + M[2, 2] * p[2])
    for r in range(3):
        out[r] = R[r, 0] * q0 + R[r, 1] * q1 + R[r, 2] * q2 + eta[r]


# ----------------------------------------------------------------------------- crane
@_jit
def _crane_pose(chain, beta, beta_dot, o, R, v, w):
    """o_t^b, R_t^b of the jib tip (eqs. 39–41) and its twist v_t^b, ω_t^b = J(β) β̇ (eqs. 45–48), in place."""
    theta0, d0, a, ca, sa, M_theta, M_d, T_base, T_tool = chain
    L, n = M_theta.shape
    T, C = T_base.copy(), np.empty((4, 4))
    A = np.zeros((4, 4))
    A[3, 3] = 1.0
    z, org = np.empty((L, 3)), np.empty((L, 3))
    for i in range(L):
        s_theta, s_d = 0.0, 0.0
        for j in range(n):
            s_theta += M_theta[i, j] * beta[j]
            s_d += M_d[i, j] * beta[j]
        theta, d = theta0[i] + s_theta, d0[i] + s_d
        for r in range(3):
            z[i, r], org[i, r] = T[r, 2], T[r, 3]
        ct, st = math.cos(theta), math.sin(theta)
        A[0, 0], A[0, 1], A[0, 2], A[0, 3] = ct, -st * ca[i], st * sa[i], a[i] * ct
        A[1, 0], A[1, 1], A[1, 2], A[1, 3] = st, ct * ca[i], -ct * sa[i], a[i] * st
        A[2, 0], A[2, 1], A[2, 2], A[2, 3] = 0.0, sa[i], ca[i], d
        matmul_into(T, A, C)
        T, C = C, T
    matmul_into(T, T_tool, C)
    for r in range(3):
        o[r] = C[r, 3]
        for c in range(3):
            R[r, c] = C[r, c]
    # J = J_θ M_θ + J_d M_d, columns [z_i × (o − o_i); z_i] and [z_i; 0] (eq. 47), then ξ = J β̇
    J = np.zeros((6, n))
    for j in range(n):
        for i in range(L):
            mt = M_theta[i, j]
            r0, r1, r2 = o[0] - org[i, 0], o[1] - org[i, 1], o[2] - org[i, 2]
            J[0, j] += (z[i, 1] * r2 - z[i, 2] * r1) * mt
            J[1, j] += (z[i, 2] * r0 - z[i, 0] * r2) * mt
            J[2, j] += (z[i, 0] * r1 - z[i, 1] * r0) * mt
            for r in range(3):
                J[3 + r, j] += z[i, r] * mt
        for i in range(L):
            for r in range(3):
                J[r, j] += z[i, r] * M_d[i, j]
    for r in range(3):
        sv, sw = 0.0, 0.0
        for j in range(n):
            sv += J[r, j] * beta_dot[j]
            sw += J[3 + r, j] * beta_dot[j]
        v[r], w[r] = sv, sw


@_jit
def _elbow_ik(elbow, p0, p1, p2, out):
    """TAC paper eqs. (42)–(44) with L2 + x_d, elbow up: out = (atan2(y, x) before unwrapping, β1, β2)."""
    L0, L1, L2, T1 = elbow
    x = (T1[0, 0] * p0 + T1[0, 1] * p1 + T1[0, 2] * p2) + T1[0, 3]  # eq. (42)
    y = (T1[1, 0] * p0 + T1[1, 1] * p1 + T1[1, 2] * p2) + T1[1, 3]
    z = (T1[2, 0] * p0 + T1[2, 1] * p1 + T1[2, 2] * p2) + T1[2, 3]
    r = math.hypot(x, y)
    out[0] = math.atan2(y, x)  # eq. (43)
    delta = (x**2 + y**2 + (z - L0) ** 2 - L1**2 - L2**2) / (2 * L1 * L2)  # eq. (44)
    delta = min(max(delta, -1.0), 1.0)
    beta2 = math.atan2(-math.sqrt(1.0 - delta**2), delta)  # elbow up: the negative root
    out[1] = math.atan2(z - L0, r) - math.atan2(L2 * math.sin(beta2), L1 + L2 * math.cos(beta2))
    out[2] = beta2


@_jit
def _unwrap(prev, raw, correction):
    """One step of ``np.unwrap``: the running 2π correction after the sample ``raw`` following ``prev``."""
    dd = raw - prev
    ddmod = (dd + math.pi) % (2 * math.pi) - math.pi
    if ddmod == -math.pi and dd > 0:
        ddmod = math.pi
    return correction + (0.0 if abs(dd) < math.pi else ddmod - dd)


@_jit
def crane_ik_tcp(elbow, P, beta0_hint):
    """β placing the TCP at each row of P in {b}: eqs. (42)–(44) with L2 + x_d (§8), elbow up, the slew
    angle unwrapped from ``beta0_hint`` (``CraneHead.crane_ik_tcp``)."""
    n = P.shape[0]
    out = np.empty((n, 3))
    prev, correction = beta0_hint, 0.0
    for k in range(n):
        _elbow_ik(elbow, P[k, 0], P[k, 1], P[k, 2], out[k])
        raw = out[k, 0]
        correction = _unwrap(prev, raw, correction)
        prev = raw
        out[k, 0] = raw + correction
    return out


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


# ----------------------------------------------------------------------------- Delta head
@_jit
def _delta_ik_arm(head, i, px, py, pz):
    """Arm i of TAC paper eqs. (8)–(16) (``DeltaHead.ik``): (α_i knees out, reachable)."""
    l_a, a, l_r, R = head[0], head[1], head[2], head[3]
    x = R[i, 0, 0] * px + R[i, 1, 0] * py + R[i, 2, 0] * pz  # p in {t_i}: R^T p, eq. (2)
    y = R[i, 0, 1] * px + R[i, 1, 1] * py + R[i, 2, 1] * pz
    z = R[i, 0, 2] * px + R[i, 1, 2] * py + R[i, 2, 2] * pz
    E = 2.0 * l_a * (y - a)
    F = -2.0 * l_a * x
    G = x**2 + (y - a) ** 2 + z**2 + l_a**2 - l_r**2
    H = math.hypot(E, F)
    ratio = -G / H if H > 1e-12 else math.inf
    phi = math.atan2(F, E)
    delta = math.acos(min(max(ratio, -1.0), 1.0))
    r1 = (phi - delta + math.pi) % (2 * math.pi) - math.pi
    r2 = (phi + delta + math.pi) % (2 * math.pi) - math.pi
    return (r1 if abs(r1) <= abs(r2) else r2), abs(ratio) <= 1.0


@_jit
def delta_ik(head, P):
    """``DeltaHead.ik`` for rows of P (n, 3): α, reachable and within the limits (1e-12), each (n, 3) (eqs. 8–16)."""
    lower, upper = head[4], head[5]
    n = P.shape[0]
    alpha = np.empty((n, 3))
    reachable = np.empty((n, 3), dtype=np.bool_)
    within = np.empty((n, 3), dtype=np.bool_)
    for k in range(n):
        for i in range(3):
            al, ok = _delta_ik_arm(head, i, P[k, 0], P[k, 1], P[k, 2])
            alpha[k, i], reachable[k, i] = al, ok
            within[k, i] = ok and al >= lower[i] - 1e-12 and al <= upper[i] + 1e-12
    return alpha, reachable, within


@_jit
def _knees(head, alpha, c, d):
    """Knee points c_i^t (eq. 4) and their rates d_i^t = ∂c_i/∂α_i (eq. 28) into rows of c and d."""
    l_a, a, R = head[0], head[1], head[3]
    for i in range(3):
        s, co = math.sin(alpha[i]), math.cos(alpha[i])
        u0, u1 = l_a * s, a - l_a * co
        e0, e1 = l_a * co, l_a * s
        for j in range(3):
            c[i, j] = R[i, j, 0] * u0 + R[i, j, 1] * u1
            d[i, j] = R[i, j, 0] * e0 + R[i, j, 1] * e1


@_jit
def _cross(u, v, out):
    out[0] = u[1] * v[2] - u[2] * v[1]
    out[1] = u[2] * v[0] - u[0] * v[2]
    out[2] = u[0] * v[1] - u[1] * v[0]


@_jit
def _delta_fk_point(head, c, p):
    """TCP p_c^t from the knees c (3, 3): eqs. (17)–(25) by trilateration, the solution above the base
    (``DeltaHead.fk``).  Returns 0, or COLLINEAR / NO_ASSEMBLY (p untouched)."""
    l_r = head[2]
    u, v, nrm = c[1] - c[0], c[2] - c[0], np.empty(3)
    _cross(u, v, nrm)
    nn = nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]
    if nn < 1e-18:
        return COLLINEAR
    s1 = c[0, 0] * c[0, 0] + c[0, 1] * c[0, 1] + c[0, 2] * c[0, 2]
    b2 = 0.5 * ((c[1, 0] * c[1, 0] + c[1, 1] * c[1, 1] + c[1, 2] * c[1, 2]) - s1)
    b3 = 0.5 * ((c[2, 0] * c[2, 0] + c[2, 1] * c[2, 1] + c[2, 2] * c[2, 2]) - s1)
    vn, nu_ = np.empty(3), np.empty(3)
    _cross(v, nrm, vn)
    _cross(nrm, u, nu_)
    root_nn = math.sqrt(nn)
    p0, w, unit = np.empty(3), np.empty(3), np.empty(3)
    for r in range(3):
        p0[r] = (b2 * vn[r] + b3 * nu_[r]) / nn
        w[r] = p0[r] - c[0, r]
        unit[r] = nrm[r] / root_nn
    bq = w[0] * unit[0] + w[1] * unit[1] + w[2] * unit[2]
    cq = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) - l_r**2
    disc = bq**2 - cq
    if disc < -1e-9:
        return NO_ASSEMBLY
    root = math.sqrt(max(disc, 0.0))
    t1, t2 = -bq + root, -bq - root
    t = t1 if p0[0] + t1 * unit[0] >= p0[0] + t2 * unit[0] else t2
    for r in range(3):
        p[r] = p0[r] + t * unit[r]
    return 0


@_jit
def _raise_fk(status):
    if status == COLLINEAR:
        raise ValueError("knee points are collinear: forward kinematics undefined")
    if status == NO_ASSEMBLY:
        raise ValueError("the rods cannot meet for these arm angles")


@_jit
def delta_fk(head, alpha):
    """``DeltaHead.fk`` for rows of α (n, 3): p_c^t (n, 3) (eqs. 17–25); ValueError where no assembly exists."""
    n = alpha.shape[0]
    out = np.empty((n, 3))
    c, d = np.empty((3, 3)), np.empty((3, 3))
    for k in range(n):
        _knees(head, alpha[k], c, d)
        _raise_fk(_delta_fk_point(head, c, out[k]))
    return out


@_jit
def _saturate(hull, p, out):
    """p inside the workspace hull (depth ≥ −1e-9), or the hull point on the segment from the centre to p
    (§6, §8; ``DeltaWorkspace.saturate_many``).  Returns True when saturated.

    A point well inside the ball of the hull's depth at the centre is inside every facet: no facet test."""
    eq, centre, radius = hull
    d0, d1, d2 = p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]
    if radius > 1e-6 and d0 * d0 + d1 * d1 + d2 * d2 < (radius - 1e-6) ** 2:
        out[0], out[1], out[2] = p[0], p[1], p[2]
        return False
    m = eq.shape[0]
    worst = -math.inf
    for j in range(m):
        worst = max(worst, (eq[j, 0] * p[0] + eq[j, 1] * p[1] + eq[j, 2] * p[2]) + eq[j, 3])
    if -worst >= -1e-9:
        out[0], out[1], out[2] = p[0], p[1], p[2]
        return False
    t_min = math.inf
    for j in range(m):
        num = -((eq[j, 0] * centre[0] + eq[j, 1] * centre[1] + eq[j, 2] * centre[2]) + eq[j, 3])
        den = d0 * eq[j, 0] + d1 * eq[j, 1] + d2 * eq[j, 2]
        t_min = min(t_min, num / den if den > 1e-15 else math.inf)
    t_exit = min(max(t_min, 0.0), 1.0)
    out[0], out[1], out[2] = centre[0] + t_exit * d0, centre[1] + t_exit * d1, centre[2] + t_exit * d2
    return True


# ----------------------------------------------------------------------------- references
@_jit
def _reference_point(
    head, hull, eta, nu, o_t_b, R_t_b, v_t_b, w_t_b, p_d, p_d_dot, hold, R_b_n, o_t_n, R_t_n, p_ref_t, p_cmd,
    v_ref_t, alpha_ref, alpha_dot_ref, c, d,
):  # fmt: skip
    """Head references of TAC paper eqs. (49)–(56) at one instant (``CraneHead.head_reference``; the exact
    eqs. 53–54 of :mod:`app.control.tac`), into the output rows; R_b_n is that of η.  ``hold``: the
    reference kept where the inverse kinematics has no solution.  Returns True when limited (saturated,
    held or clipped)."""
    p_ref_n, p_ref_n_dot, q = np.empty(3), np.empty(3), np.empty(3)
    for r in range(3):
        o_t_n[r] = (R_b_n[r, 0] * o_t_b[0] + R_b_n[r, 1] * o_t_b[1] + R_b_n[r, 2] * o_t_b[2]) + eta[r]  # eq. (49)
        p_ref_n[r] = p_d[r] - o_t_n[r]
    matmul_into(R_b_n, R_t_b, R_t_n)
    for r in range(3):
        p_ref_t[r] = R_t_n[0, r] * p_ref_n[0] + R_t_n[1, r] * p_ref_n[1] + R_t_n[2, r] * p_ref_n[2]  # eq. (50)
    # eqs. (52)–(55): ṗ_ref^n = ṗ_d^n − R_b^n (ω_b × o_t^b + v_t^b) − R_b^n ν₁
    w0, w1, w2 = nu[3], nu[4], nu[5]
    q[0] = (w1 * o_t_b[2] - w2 * o_t_b[1]) + v_t_b[0]
    q[1] = (w2 * o_t_b[0] - w0 * o_t_b[2]) + v_t_b[1]
    q[2] = (w0 * o_t_b[1] - w1 * o_t_b[0]) + v_t_b[2]
    for r in range(3):
        rq = R_b_n[r, 0] * q[0] + R_b_n[r, 1] * q[1] + R_b_n[r, 2] * q[2]
        rv = R_b_n[r, 0] * nu[0] + R_b_n[r, 1] * nu[1] + R_b_n[r, 2] * nu[2]
        p_ref_n_dot[r] = p_d_dot[r] - rq - rv
    # Ṙ_n^t p_ref^n = −(R_t^b)ᵀ [(ω_t^b + ω_b) × ((R_b^n)ᵀ p_ref^n)]
    s0, s1, s2 = w_t_b[0] + w0, w_t_b[1] + w1, w_t_b[2] + w2
    m0 = R_b_n[0, 0] * p_ref_n[0] + R_b_n[1, 0] * p_ref_n[1] + R_b_n[2, 0] * p_ref_n[2]
    m1 = R_b_n[0, 1] * p_ref_n[0] + R_b_n[1, 1] * p_ref_n[1] + R_b_n[2, 1] * p_ref_n[2]
    m2 = R_b_n[0, 2] * p_ref_n[0] + R_b_n[1, 2] * p_ref_n[1] + R_b_n[2, 2] * p_ref_n[2]
    x0, x1, x2 = s1 * m2 - s2 * m1, s2 * m0 - s0 * m2, s0 * m1 - s1 * m0
    for r in range(3):
        rdot = -(R_t_b[0, r] * x0 + R_t_b[1, r] * x1 + R_t_b[2, r] * x2)
        v_ref_t[r] = rdot + (R_t_n[0, r] * p_ref_n_dot[0] + R_t_n[1, r] * p_ref_n_dot[1] + R_t_n[2, r] * p_ref_n_dot[2])
    # workspace check and saturation onto the hull (§6, §8), then eq. (51)
    saturated = _saturate(hull, p_ref_t, p_cmd)
    lower, upper = head[4], head[5]
    reachable, within = True, True
    for i in range(3):
        al, ok = _delta_ik_arm(head, i, p_cmd[0], p_cmd[1], p_cmd[2])
        reachable = reachable and ok
        within = within and ok and al >= lower[i] - 1e-12 and al <= upper[i] + 1e-12
        alpha_ref[i] = min(max(al, lower[i]), upper[i])
    bad = not reachable
    clipped = not within and not bad
    if bad:
        alpha_ref[0], alpha_ref[1], alpha_ref[2] = hold[0], hold[1], hold[2]
    limited = saturated or bad or clipped
    # eq. (56) as α̇ = B⁻¹ A v_ref (eq. 32); no feed-forward while limited
    if limited:
        alpha_dot_ref[0], alpha_dot_ref[1], alpha_dot_ref[2] = 0.0, 0.0, 0.0
    else:
        _knees(head, alpha_ref, c, d)
        for i in range(3):
            e0, e1, e2 = p_cmd[0] - c[i, 0], p_cmd[1] - c[i, 1], p_cmd[2] - c[i, 2]
            num = e0 * v_ref_t[0] + e1 * v_ref_t[1] + e2 * v_ref_t[2]
            alpha_dot_ref[i] = num / (e0 * d[i, 0] + e1 * d[i, 1] + e2 * d[i, 2])
    return limited


@_jit
def head_reference(chain, head, hull, eta, nu, beta, beta_dot, p_d, p_d_dot, hold):
    """``CraneHead.head_reference`` (eqs. 49–56) for rows of η, ν (n, 6), β, β̇, p_d^n, ṗ_d^n (n, 3):
    (o_t^n, R_t^n (n, 3, 3), p_ref^t, p_cmd^t, v_ref^t, α_ref, α̇_ref, limited (n,))."""
    n = eta.shape[0]
    o_t_n, R_t_n = np.empty((n, 3)), np.empty((n, 3, 3))
    p_ref_t, p_cmd, v_ref_t = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    alpha_ref, alpha_dot_ref = np.empty((n, 3)), np.empty((n, 3))
    limited = np.empty(n, dtype=np.bool_)
    o, R, v, w = np.empty(3), np.empty((3, 3)), np.empty(3), np.empty(3)
    R_b_n, c, d = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    for k in range(n):
        _crane_pose(chain, beta[k], beta_dot[k], o, R, v, w)
        _rot_zyx(eta[k, 3], eta[k, 4], eta[k, 5], R_b_n)
        limited[k] = _reference_point(
            head, hull, eta[k], nu[k], o, R, v, w, p_d[k], p_d_dot[k], hold, R_b_n, o_t_n[k], R_t_n[k], p_ref_t[k],
            p_cmd[k], v_ref_t[k], alpha_ref[k], alpha_dot_ref[k], c, d,
        )  # fmt: skip
        hold = alpha_ref[k]
    return o_t_n, R_t_n, p_ref_t, p_cmd, v_ref_t, alpha_ref, alpha_dot_ref, limited


# ----------------------------------------------------------------------------- head servo
@_jit
def _servo_step(pid, a_m, b_m, dt, ref, ref_dot, alpha, integral, u):
    """PID of eq. (57) solved for u with the motor rate of eq. (58), anti-windup, then the DC motor
    α⁺ = a α + b u (eq. 58, zero-order hold) inside the mechanical stops (``HeadServo.run``); in place."""
    kp, ki, kd, t_dc, k_dc, u_lo, u_hi, lo, hi = pid
    implicit = 1.0 + kd * k_dc / t_dc
    inv_t = 1.0 / t_dc
    for j in range(3):
        err = ref[j] - alpha[j]
        trial = integral[j] + err * dt
        u_new = (kp * err + ki * trial + kd * (ref_dot[j] + alpha[j] * inv_t)) / implicit  # eq. (57)
        if u_new < u_lo[j]:
            u_new = u_lo[j]
        elif u_new > u_hi[j]:
            u_new = u_hi[j]
        else:
            integral[j] = trial  # anti-windup: integrate only while the input is free
        u[j] = u_new
        a_new = a_m * alpha[j] + b_m * u_new  # eq. (58), zero-order hold
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
    Head: references of eqs. (49)–(56), then (``head_mode``) the PID and DC motors of eqs. (57)–(58) or
    locked at ``alpha_lock``; p_c^t by eqs. (17)–(25); e_c and e_s of eq. (61).  The crane (β, β̇, β_c
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
    R_b_n, R_n, R_t_n, c, d = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
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
        _rot_zyx(em[3], em[4], em[5], R_b_n)
        # crane
        if crane_mode == CRANE_HOLD:
            out_beta[k] = beta_hold
        else:
            if crane_mode == CRANE_COOPERATIVE:
                g0, g1, g2 = p_d_n[0] - em[0], p_d_n[1] - em[1], p_d_n[2] - em[2]
                for r in range(3):  # p_d^n in {b}
                    target[r] = R_b_n[0, r] * g0 + R_b_n[1, r] * g1 + R_b_n[2, r] * g2
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
            head, hull, em, nu_meas[k], o, R, v, w, p_d_n, zero, hold, R_b_n, o_t_n, R_t_n, p_ref_t[k], p_cmd,
            v_ref_t, alpha_ref[k], alpha_dot_ref, c, d,
        )  # fmt: skip
        hold = alpha_ref[k]
        if head_mode == HEAD_SERVO:
            _servo_step(pid, a_m, b_m, dt, alpha_ref[k], alpha_dot_ref, alpha, integral, u)
            out_alpha[k], out_u[k] = alpha, u
            saturated[k] = limited
            _knees(head, alpha, c, d)
            _raise_fk(_delta_fk_point(head, c, p_tcp))
        else:
            out_alpha[k], out_u[k] = alpha_lock, alpha_lock
        p_c_t[k] = p_tcp
        # eq. (61): e_c = |p_d^n − p_c^n|, e_s = |p_d^n − p_s^n|
        if noisy:
            _rot_zyx(et[3], et[4], et[5], R_n)
        else:
            R_n[:] = R_b_n
        _to_n(R_n, et, o, R, p_tcp, p_c_n[k])
        _to_n(R_n, et, o_s, eye, zero, p_s_n[k])
        sc, ss = 0.0, 0.0
        for r in range(3):
            sc += (p_d_n[r] - p_c_n[k, r]) ** 2
            ss += (p_d_n[r] - p_s_n[k, r]) ** 2
        e_c[k], e_s[k] = math.sqrt(sc), math.sqrt(ss)
    return out_beta, p_ref_t, p_c_t, alpha_ref, out_alpha, out_u, p_c_n, p_s_n, e_c, e_s, saturated


# ----------------------------------------------------------------------------- warm-up
def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel the crane-head models call from Python,
    with the argument types they pass (for :func:`app.models.kernels.warm_up`)."""
    from app.geometry import rot_x

    z3, o3, eye = np.zeros(3), np.ones(3), np.eye(4)
    chain = (z3, z3, o3, o3, z3, np.eye(3), np.zeros((3, 3)), eye, eye)
    head = (3.25, -0.75, 7.0, rot_x(np.radians([150.0, 270.0, 30.0])), -o3, o3)  # TAC paper Table 4
    hull = (np.array([[1.0, 0.0, 0.0, -1.0]]), z3, 1.0)
    elbow = (3.0, 19.2, 16.0, eye)
    crane = (-o3, o3, o3, o3, 0.3, 1.0)
    pid = (10.0, 60.0, 1.0, 0.2, 1.0, -o3, o3, -o3, o3)
    rows3, rows6 = np.zeros((2, 3)), np.zeros((2, 6))
    points = np.array([[6.5, 0.0, 0.0], [6.0, 0.5, 0.0]])  # inside the head's workspace

    def chunk(crane_mode: int, head_mode: int) -> None:
        tac_chunk(
            rows6, rows6, rows6, False, 0.01, crane_mode, head_mode, z3, z3, z3, z3, o3, o3, chain, head, hull, elbow,
            crane, pid, z3.copy(), z3.copy(), z3.copy(), 0.0, False, z3.copy(), z3.copy(), z3.copy(),
        )  # fmt: skip

    return [
        lambda: delta_ik(head, points),
        lambda: delta_fk(head, rows3),
        lambda: crane_ik_tcp(elbow, rows3, 0.0),
        lambda: head_reference(chain, head, hull, rows6, rows6, rows3, rows3, rows3, rows3, z3),
        lambda: head_servo(pid, 0.01, rows3, rows3, z3.copy(), z3.copy(), z3.copy()),
        lambda: crane_servo(crane, z3, rows3, rows3, 0.01, z3.copy(), z3.copy()),
        lambda: chunk(CRANE_COOPERATIVE, HEAD_SERVO),
    ]
