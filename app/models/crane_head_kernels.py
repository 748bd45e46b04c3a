"""Compiled kinematics of the offshore crane carrying the Delta head (TAC paper §3–8).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path).  The NumPy methods stay the reference, tested equal on the same seeded inputs in
``tests/test_tac_kernels.py``: ``DeltaHead.ik`` and ``fk`` (:mod:`app.models.delta`, eqs. 8–25) and
``CraneHead.crane_ik_tcp`` and ``head_reference`` (:mod:`app.models.crane_head`, eqs. 42–56).  The
crane law and the head's PID built on these are :mod:`app.control.tac_kernels`, the crane's joints and the
head's motors :mod:`app.sim.head_kernels`, the whole simulation step :mod:`app.scenes.tac_kernels`.

Every array argument is C-contiguous float64 (another layout would make numba compile a second
specialisation in an engine tick); the constants come in tuples built once by the models:

* ``chain``: the crane's ``SerialRobot.kernel_record``, the robot record of :mod:`app.models.kernels`
  (dh (5, L): θ₀, d₀, a, cos α, sin α; M (2, L, n): M_θ, M_d; T (2, 4, 4): T_world_base, T_flange_tool;
  eq. 39);
* ``head``: ``DeltaHead.kernel_args`` (l_a, a = l_p − l_k, l_r, R_{t_i}^t (3, 3, 3), α_min, α_max);
* ``hull``: the workspace's facet equations (m, 4) (n·p + b ≤ 0 inside, |n| = 1), centre p_d^t and the
  radius of the largest ball about it inside the hull (its depth, §6);
* ``elbow``: (L0, L1, L2 + x_d, T_world_1⁻¹ (4, 4)) of eqs. (42)–(44) carrying the TCP (§8).
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _chain, _jit, matmul_into

__all__ = [
    "ENABLED",
    "c_array",
    "crane_ik_tcp",
    "delta_fk",
    "delta_ik",
    "head_reference",
    "warm_up_steps",
]

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
    theta0, d0, a, ca, sa, M_theta, M_d, T_base, T_tool = _chain(chain)
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
def _reference_point(geometry, vessel, tip, desired, hold, out, work):
    """Head references of TAC paper eqs. (49)–(56) at one instant (``CraneHead.head_reference``; the exact
    eqs. 53–54 of :mod:`app.models.crane_head`), into the output rows.  Records: ``geometry`` (head, hull);
    ``vessel`` (η, ν (6,), R_b^n of η, named R_n_b); ``tip`` (o_t^b, R_t^b, v_t^b, ω_t^b) of the jib tip (eqs.
    41, 45); ``desired`` (p_d^n, ṗ_d^n); ``hold``: the reference kept where the inverse kinematics has no
    solution; ``out`` (o_t^n, R_t^n, p_ref^t, p_cmd^t, v_ref^t, α_ref, α̇_ref), written; ``work`` (c, d) (3, 3)
    scratch.  Returns True when limited (saturated, held or clipped)."""
    head, hull = geometry
    eta, nu, R_n_b = vessel
    o_t_b, R_b_t, v_t_b, w_t_b = tip
    p_d, p_d_dot = desired
    o_t_n, R_n_t, p_ref_t, p_cmd, v_ref_t, alpha_ref, alpha_dot_ref = out
    c, d = work
    p_ref_n, p_ref_n_dot, q = np.empty(3), np.empty(3), np.empty(3)
    for r in range(3):
        o_t_n[r] = (R_n_b[r, 0] * o_t_b[0] + R_n_b[r, 1] * o_t_b[1] + R_n_b[r, 2] * o_t_b[2]) + eta[r]  # eq. (49)
        p_ref_n[r] = p_d[r] - o_t_n[r]
    matmul_into(R_n_b, R_b_t, R_n_t)  # R_t^n = R_b^n R_t^b
    for r in range(3):
        p_ref_t[r] = R_n_t[0, r] * p_ref_n[0] + R_n_t[1, r] * p_ref_n[1] + R_n_t[2, r] * p_ref_n[2]  # eq. (50)
    # eqs. (52)–(55): ṗ_ref^n = ṗ_d^n − R_b^n (ω_b × o_t^b + v_t^b) − R_b^n ν₁
    w0, w1, w2 = nu[3], nu[4], nu[5]
    q[0] = (w1 * o_t_b[2] - w2 * o_t_b[1]) + v_t_b[0]
    q[1] = (w2 * o_t_b[0] - w0 * o_t_b[2]) + v_t_b[1]
    q[2] = (w0 * o_t_b[1] - w1 * o_t_b[0]) + v_t_b[2]
    for r in range(3):
        rq = R_n_b[r, 0] * q[0] + R_n_b[r, 1] * q[1] + R_n_b[r, 2] * q[2]
        rv = R_n_b[r, 0] * nu[0] + R_n_b[r, 1] * nu[1] + R_n_b[r, 2] * nu[2]
        p_ref_n_dot[r] = p_d_dot[r] - rq - rv
    # Ṙ_n^t p_ref^n = −(R_t^b)ᵀ [(ω_t^b + ω_b) × ((R_b^n)ᵀ p_ref^n)]
    s0, s1, s2 = w_t_b[0] + w0, w_t_b[1] + w1, w_t_b[2] + w2
    m0 = R_n_b[0, 0] * p_ref_n[0] + R_n_b[1, 0] * p_ref_n[1] + R_n_b[2, 0] * p_ref_n[2]
    m1 = R_n_b[0, 1] * p_ref_n[0] + R_n_b[1, 1] * p_ref_n[1] + R_n_b[2, 1] * p_ref_n[2]
    m2 = R_n_b[0, 2] * p_ref_n[0] + R_n_b[1, 2] * p_ref_n[1] + R_n_b[2, 2] * p_ref_n[2]
    x0, x1, x2 = s1 * m2 - s2 * m1, s2 * m0 - s0 * m2, s0 * m1 - s1 * m0
    for r in range(3):
        rdot = -(R_b_t[0, r] * x0 + R_b_t[1, r] * x1 + R_b_t[2, r] * x2)
        v_ref_t[r] = rdot + (R_n_t[0, r] * p_ref_n_dot[0] + R_n_t[1, r] * p_ref_n_dot[1] + R_n_t[2, r] * p_ref_n_dot[2])
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
def head_reference(system, vessel, crane, desired, hold):
    """``CraneHead.head_reference`` (eqs. 49–56) for ``system`` (chain, head, hull), ``vessel`` (η, ν) (n, 6)
    each, ``crane`` (β, β̇) and ``desired`` (p_d^n, ṗ_d^n) (n, 3) each, ``hold`` (3,) the reference kept where
    the inverse kinematics has no solution: (o_t^n, R_t^n (n, 3, 3), p_ref^t, p_cmd^t, v_ref^t, α_ref, α̇_ref,
    limited (n,))."""
    chain, head, hull = system
    eta, nu = vessel
    beta, beta_dot = crane
    p_d, p_d_dot = desired
    n = eta.shape[0]
    o_t_n, R_n_t = np.empty((n, 3)), np.empty((n, 3, 3))
    p_ref_t, p_cmd, v_ref_t = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    alpha_ref, alpha_dot_ref = np.empty((n, 3)), np.empty((n, 3))
    limited = np.empty(n, dtype=np.bool_)
    o, R, v, w = np.empty(3), np.empty((3, 3)), np.empty(3), np.empty(3)
    R_n_b, c, d = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    for k in range(n):
        _crane_pose(chain, beta[k], beta_dot[k], o, R, v, w)
        _rot_zyx(eta[k, 3], eta[k, 4], eta[k, 5], R_n_b)  # R_b^n, Fossen eq. (2.18)
        out = (o_t_n[k], R_n_t[k], p_ref_t[k], p_cmd[k], v_ref_t[k], alpha_ref[k], alpha_dot_ref[k])
        vessel_k = (eta[k], nu[k], R_n_b)
        limited[k] = _reference_point((head, hull), vessel_k, (o, R, v, w), (p_d[k], p_d_dot[k]), hold, out, (c, d))
        hold = alpha_ref[k]
    return o_t_n, R_n_t, p_ref_t, p_cmd, v_ref_t, alpha_ref, alpha_dot_ref, limited


# ----------------------------------------------------------------------------- warm-up
def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel of this file the crane and head models
    call from Python, with the argument types they pass (for :func:`app.warmup.warm_up`)."""
    from app.geometry import rot_x

    z3, o3, eye = np.zeros(3), np.ones(3), np.eye(4)
    chain = (np.stack([z3, z3, o3, o3, z3]), np.stack([np.eye(3), np.zeros((3, 3))]), np.stack([eye, eye]))
    head = (3.25, -0.75, 7.0, rot_x(np.radians([150.0, 270.0, 30.0])), -o3, o3)  # TAC paper Table 4
    hull = (np.array([[1.0, 0.0, 0.0, -1.0]]), z3, 1.0)
    elbow = (3.0, 19.2, 16.0, eye)
    rows3, rows6 = np.zeros((2, 3)), np.zeros((2, 6))
    points = np.array([[6.5, 0.0, 0.0], [6.0, 0.5, 0.0]])  # inside the head's workspace
    return [
        lambda: delta_ik(head, points),
        lambda: delta_fk(head, rows3),
        lambda: crane_ik_tcp(elbow, rows3, 0.0),
        lambda: head_reference((chain, head, hull), (rows6, rows6), (rows3, rows3), (rows3, rows3), z3),
    ]
