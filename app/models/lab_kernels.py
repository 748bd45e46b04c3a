"""Compiled kinematics of the Motion-Lab (Motion-Lab paper): the Stewart platforms' poses, legs and body
rates (eqs. 31–51), the Comau's tool point, Jacobian and IK (eqs. 3–21) and the tool point on its moving
platform (eqs. 54–57).

Pure geometry, shared by the plants (:mod:`app.sim.kernels`: the platforms, the drives, the tool-point
sensor) and the controllers (:mod:`app.control.lab_kernels`: MOTION_COMP, the winch's heave
compensation), so neither imports the other.  Same scheme as :mod:`app.models.kernels` (numba, cached
on disk, ``BOSUN_JIT=0`` for the interpreted path); the NumPy references are
:class:`~app.models.stewart.StewartPlatform`, :class:`~app.models.comau.ComauKinematics` and
:func:`app.models.comau.tool_on_platform`, tested equal in ``tests/test_sim_kernels.py``.

:func:`comau_ik` links :func:`app.models.kernels.comau_candidates` (eqs. 7–20) into its cached machine
code, and numba's cache does not notice edits in another file: after changing that function, touch
this file (or delete ``app/models/__pycache__/lab_kernels.*.nb?``).
"""

from __future__ import annotations

import math

import numpy as np

from app.models import kernels as model_kernels
from app.models.kernels import _jit

__all__ = [
    "comau_ik",
    "comau_tool",
    "leg_lengths",
    "lstsq3",
    "mtv",
    "mv",
    "pose_in",
    "rotation_xyz",
    "stewart_rates",
    "tool_on_platform",
]


# ----------------------------------------------------------------------------- small algebra
@_jit
def _matmul(A, B):
    """A @ B for square C-contiguous matrices (3×3 or 4×4), a new array."""
    C = np.empty((A.shape[0], A.shape[0]))
    model_kernels.matmul_into(A, B, C)
    return C


@_jit
def mv(A, x0, x1, x2):
    """A @ (x0, x1, x2) for the upper-left 3×3 block of A (3×3 or 4×4)."""
    out = np.empty(3)
    for i in range(3):
        out[i] = A[i, 0] * x0 + A[i, 1] * x1 + A[i, 2] * x2
    return out


@_jit
def mtv(A, x0, x1, x2):
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
    w = mv(Ti, eta_dot[3], eta_dot[4], eta_dot[5])
    Tw = mv(Td, w[0], w[1], w[2])
    wd = mv(Ti, eta_ddot[3] - Tw[0], eta_ddot[4] - Tw[1], eta_ddot[5] - Tw[2])
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
    v = mv(J, e1, e2, e3)
    Jqdd = mv(J, qdd[0], qdd[1], qdd[2])
    a = np.empty(3)
    a[0], a[1], a[2] = jx + Jqdd[0], jy + Jqdd[1], zdd + Jqdd[2]
    return p, v, a, J


@_jit
def tool_on_platform(cm, T_b1_r, platform, rates, joints):
    """Tool point in the platform's neutral frame {n1}: eqs. (54), (56), (57) (the reference is
    :func:`app.models.comau.tool_on_platform`): (p, ṗ, p̈).

    ``platform`` = (η, η̇, η̈) of EM8000, ``rates`` = (R, Ṙ, R̈) of its body (eqs. 33, 47, 51), ``joints`` =
    (q, q̇, q̈) of the Comau, ``cm`` = (a1, d1, a2, a3, L), ``T_b1_r`` the robot base in the body frame."""
    eta, eta_dot, eta_ddot = platform
    R, Rd, Rdd = rates
    q, qd, qdd = joints
    p_tr, v_tr, a_tr, _ = comau_tool(cm, q, qd, qdd)
    arm = mv(T_b1_r, p_tr[0], p_tr[1], p_tr[2])
    for i in range(3):
        arm[i] = T_b1_r[i, 3] + arm[i]
    Rv = mv(T_b1_r, v_tr[0], v_tr[1], v_tr[2])
    Ra = mv(T_b1_r, a_tr[0], a_tr[1], a_tr[2])
    R_arm = mv(R, arm[0], arm[1], arm[2])
    Rd_arm = mv(Rd, arm[0], arm[1], arm[2])
    Rdd_arm = mv(Rdd, arm[0], arm[1], arm[2])
    R_Rv, Rd_Rv, R_Ra = mv(R, Rv[0], Rv[1], Rv[2]), mv(Rd, Rv[0], Rv[1], Rv[2]), mv(R, Ra[0], Ra[1], Ra[2])
    p, v, a = np.empty(3), np.empty(3), np.empty(3)
    for i in range(3):
        p[i] = eta[i] + R_arm[i]
        v[i] = eta_dot[i] + Rd_arm[i] + R_Rv[i]
        a[i] = eta_ddot[i] + Rdd_arm[i] + 2.0 * Rd_Rv[i] + R_Ra[i]
    return p, v, a


@_jit
def comau_ik(cm, T_base, p_tr, q_near, signs, lower, upper):
    """``app.models.comau.nearest_ik``: the exact candidate of eqs. (7)–(20) inside the joint limits nearest q_near,
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


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) the kernels of this file Python calls, with the argument
    types it passes (for :func:`app.warmup.warm_up`)."""
    z6, eye = np.zeros(6), np.eye(4)
    a_n, b_b = np.ones((6, 3)), np.full((6, 3), 0.5)
    return [
        lambda: pose_in(eye, z6),
        lambda: leg_lengths(a_n, b_b, z6),
    ]
