"""The hazard guard's tick compiled (:mod:`app.control.guard`): capsule clearances, the σ ratio, the joint limits,
their gradients and the direction-aware scaling of one joint step, in one call.

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` runs the same code interpreted).

Geometry: a capsule is a segment (two points) and a radius; the clearance of two capsules is the distance of their
segments less both radii (Ericson, *Real-Time Collision Detection*, 2005, §5.1.9, closest points of two segments),
of a capsule and a plane n·x = h the nearer end's height above it less the radius.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit, fma, frames, jacobian_from_frames

__all__ = ["ENABLED", "guard_step", "hazard_values", "warm_up_steps"]

# hazard kinds (the rows of hazard_values): the order the report names them in
LIMIT, SINGULAR, PAIR, PLANE = 0, 1, 2, 3


@_jit
def _segment_closest(p1, q1, p2, q2):
    """Distance [m] between the segments p1–q1 and p2–q2 and the closest points' parameters (s on the first, t on
    the second, in [0, 1]) (Ericson §5.1.9; degenerate segments are points)."""
    d1x, d1y, d1z = q1[0] - p1[0], q1[1] - p1[1], q1[2] - p1[2]
    d2x, d2y, d2z = q2[0] - p2[0], q2[1] - p2[1], q2[2] - p2[2]
    rx, ry, rz = p1[0] - p2[0], p1[1] - p2[1], p1[2] - p2[2]
    # the dot products rounded as BLAS ddot (d1 @ d1 before): the same numbers without 3 arrays and 5 calls
    a = fma(d1z, d1z, fma(d1y, d1y, d1x * d1x))
    e = fma(d2z, d2z, fma(d2y, d2y, d2x * d2x))
    f = fma(d2z, rz, fma(d2y, ry, d2x * rx))
    eps = 1e-18
    if a <= eps and e <= eps:
        s = 0.0
        t = 0.0
    elif a <= eps:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = fma(d1z, rz, fma(d1y, ry, d1x * rx))
        if e <= eps:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = fma(d1z, d2z, fma(d1y, d2y, d1x * d2x))
            den = a * e - b * b
            s = min(max((b * f - c * e) / den, 0.0), 1.0) if den > eps * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    dx = (p1[0] + d1x * s) - (p2[0] + d2x * t)
    dy = (p1[1] + d1y * s) - (p2[1] + d2y * t)
    dz = (p1[2] + d1z * s) - (p2[2] + d2z * t)
    return math.sqrt(dx * dx + dy * dy + dz * dz), s, t


@_jit
def _segment_distance(p1, q1, p2, q2):
    """Distance [m] between the segments p1–q1 and p2–q2."""
    return _segment_closest(p1, q1, p2, q2)[0]


@_jit
def _point_rate(F, chain, link, part, s, p, u, g):
    """Add u·∂p/∂q to ``g`` (n,): p a point of a capsule of ``link`` (``part`` and its parameter ``s`` as in
    :func:`_capsule_points`), u a direction (scaled as wanted), chain (M_θ, M_d, speeds).  ∂p/∂θ_l = z_l × (p − o_l)
    and ∂p/∂d_l = z_l for every link l before the capsule's (TAC paper eq. 47's columns at p), the capsule's own
    link's θ about its own axis, its d moving the d part's point by s (its far end by 1) and the a part whole; then
    through M_θ, M_d to q."""
    M_theta, M_d = chain[0], chain[1]
    L = M_theta.shape[0]
    n = M_theta.shape[1]
    last = min(link, L - 1)
    for l in range(last + 1):
        z = F[l, :3, 2]
        o = F[l, :3, 3]
        rx, ry, rz = p[0] - o[0], p[1] - o[1], p[2] - o[2]
        # u · (z × r) and u · z
        rot = u[0] * (z[1] * rz - z[2] * ry) + u[1] * (z[2] * rx - z[0] * rz) + u[2] * (z[0] * ry - z[1] * rx)
        lin = u[0] * z[0] + u[1] * z[1] + u[2] * z[2]
        if l == link and part == 0:
            lin *= s
        for j in range(n):
            mt = M_theta[l, j]
            md = M_d[l, j]
            if mt != 0.0 or md != 0.0:
                g[j] += rot * mt + lin * md


@_jit
def _cross(a, b):
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


@_jit
def _ratio_bound_sq(J):
    """A lower bound on (σ_min/σ_max)² of J (3, n): 4 det(J Jᵀ)/tr(J Jᵀ)³, 0 for J = 0."""
    m00 = m01 = m02 = m11 = m12 = m22 = 0.0
    for j in range(J.shape[1]):
        x, y, z = J[0, j], J[1, j], J[2, j]
        m00 += x * x
        m01 += x * y
        m02 += x * z
        m11 += y * y
        m12 += y * z
        m22 += z * z
    tr = m00 + m11 + m22
    if not tr > 0.0:
        return 0.0
    det = m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02)
    return 4.0 * det / (tr * tr * tr)


@_jit
def _sigma_grad(F, M_theta, M_d, speed, kink, zone, g):
    """σ_min/σ_max of J_v·diag(speed) (:func:`_sigma_ratio`) and its gradient in q into ``g`` (n,), in closed
    form: dσ_i = u_iᵀ (∂J/∂q_j) diag(speed) v_i (the derivative of a simple singular value), the columns'
    derivatives from the chain (a column c_l = z_l × (p − o_l) of θ_l, z_l of d_l: ∂/∂θ_k is z_k × c_l for k ≤ l
    and z_l × c_k(θ) for k > l; ∂/∂d_k is z_l × z_k for k > l, else 0), then through M_θ, M_d.  Where σ_min is
    below ``kink`` × σ_max (a singularity: |x|-like, no gradient) the gradient is zero.  Where the ratio is at or
    above ``zone`` the gradient is not wanted and left zero; where a bound proves it so (:func:`_ratio_bound_sq`,
    most ticks) no SVD is taken either and ``zone`` itself is returned: only a ratio under ``zone`` is exact."""
    L = M_theta.shape[0]
    n = M_theta.shape[1]
    for j in range(n):
        g[j] = 0.0
    if n < 3:
        return 0.0
    p = F[F.shape[0] - 1, :3, 3]
    ct = np.empty((L, 3))
    zz = np.empty((L, 3))
    for l in range(L):
        z = F[l, :3, 2]
        o = F[l, :3, 3]
        rx, ry, rz = p[0] - o[0], p[1] - o[1], p[2] - o[2]
        ct[l, 0], ct[l, 1], ct[l, 2] = z[1] * rz - z[2] * ry, z[2] * rx - z[0] * rz, z[0] * ry - z[1] * rx
        zz[l, 0], zz[l, 1], zz[l, 2] = z[0], z[1], z[2]
    J = np.zeros((3, n))
    for l in range(L):
        for j in range(n):
            mt = M_theta[l, j]
            md = M_d[l, j]
            if mt != 0.0 or md != 0.0:
                for r in range(3):
                    J[r, j] += (ct[l, r] * mt + zz[l, r] * md) * speed[j]
    # out of the zone for certain, without the SVD: with λ the eigenvalues of J Jᵀ (the σ²), λ_max ≤ tr and
    # λ_min ≥ 4 det/tr² (λ₁λ₂ ≤ (tr/2)²), so (σ_min/σ_max)² ≥ 4 det/tr³; 1 % spare for det's rounding
    if _ratio_bound_sq(J) >= 1.01 * zone * zone:
        return zone
    U, S, Vh = np.linalg.svd(J)
    if S[0] <= 0.0:
        return 0.0
    ratio = S[2] / S[0]
    if S[2] <= kink * S[0] or ratio >= zone:
        return ratio
    for which in (0, 2):
        u = U[:, which]
        wv = np.empty(n)
        for j in range(n):
            wv[j] = speed[j] * Vh[which, j]
        a = np.zeros(L)
        b = np.zeros(L)
        for l in range(L):
            for j in range(n):
                a[l] += M_theta[l, j] * wv[j]
                b[l] += M_d[l, j] * wv[j]
        # D(θ_k), D(d_k): u · ∂J_DH/∂var_k weighted by a, b
        Dt = np.zeros(L)
        Dd = np.zeros(L)
        for k in range(L):
            zk = zz[k]
            for l in range(L):
                if k <= l:
                    # ∂c_l(θ)/∂θ_k = z_k × c_l(θ); ∂c_l(d)/∂θ_k = z_k × z_l
                    c = ct[l]
                    x0, x1, x2 = _cross(zk, c)
                    y0, y1, y2 = _cross(zk, zz[l])
                    Dt[k] += (u[0] * x0 + u[1] * x1 + u[2] * x2) * a[l] + (u[0] * y0 + u[1] * y1 + u[2] * y2) * b[l]
                else:
                    # ∂c_l(θ)/∂θ_k = z_l × c_k(θ); ∂c_l(θ)/∂d_k = z_l × z_k
                    x0, x1, x2 = _cross(zz[l], ct[k])
                    Dt[k] += (u[0] * x0 + u[1] * x1 + u[2] * x2) * a[l]
                    y0, y1, y2 = _cross(zz[l], zk)
                    Dd[k] += (u[0] * y0 + u[1] * y1 + u[2] * y2) * a[l]
        sign = -ratio / S[0] if which == 0 else 1.0 / S[0]  # d(σ3/σ1) = dσ3/σ1 − σ3 dσ1/σ1²
        for k in range(L):
            for j in range(n):
                g[j] += sign * (Dt[k] * M_theta[k, j] + Dd[k] * M_d[k, j])
    return ratio


@_jit
def _plane_clearance(a, b, radius, plane):
    """Clearance [m] of the capsule a–b (radius) above the plane ``plane`` = (n_x, n_y, n_z, h), n·x = h."""
    ha = plane[0] * a[0] + plane[1] * a[1] + plane[2] * a[2] - plane[3]
    hb = plane[0] * b[0] + plane[1] * b[1] + plane[2] * b[2] - plane[3]
    return min(ha, hb) - radius


@_jit
def _capsule_points(F, caps, out):
    """The capsules' end points into ``out`` (C, 2, 3) from the chain's frames F (K, 4, 4) (``SerialRobot.frames``).

    ``caps`` (C, 2) int: the link (its frames F[i] → F[i + 1]; the last, K − 2, is flange → tool) and the part:
    0 the DH link's d part (o_i to the bend o_i + z_i (z_i·(o_{i+1} − o_i))), 1 its a part (the bend to o_{i+1}),
    2 the whole link (o_i to o_{i+1}) — as :func:`app.models.drawing.machines.serial_links` draws it."""
    for c in range(caps.shape[0]):
        i = caps[c, 0]
        part = caps[c, 1]
        o0 = F[i, :3, 3]
        o1 = F[i + 1, :3, 3]
        z = F[i, :3, 2]
        along = z[0] * (o1[0] - o0[0]) + z[1] * (o1[1] - o0[1]) + z[2] * (o1[2] - o0[2])
        for k in range(3):
            bend = o0[k] + z[k] * along
            if part == 0:
                out[c, 0, k] = o0[k]
                out[c, 1, k] = bend
            elif part == 1:
                out[c, 0, k] = bend
                out[c, 1, k] = o1[k]
            else:
                out[c, 0, k] = o0[k]
                out[c, 1, k] = o1[k]


@_jit
def _sigma_ratio(F, M_theta, M_d, speed):
    """σ_min/σ_max of J_v·diag(speed), J_v the tool point's position Jacobian from the frames F (eq. 47 of the TAC
    paper through M_θ, M_d as :func:`app.models.kernels.jacobian_from_frames`): 1 isotropic, 0 a direction lost.
    The SVD, not the eigenvalues of J Jᵀ in closed form: those lose σ_min to cancellation near a singularity
    (a gradient of the wrong sign at σ ratio 2·10⁻⁵, youBot; review)."""
    L = M_theta.shape[0]
    n = M_theta.shape[1]
    p = F[F.shape[0] - 1, :3, 3]
    Jq = np.zeros((3, n))
    for i in range(L):
        z = F[i, :3, 2]
        o = F[i, :3, 3]
        rx, ry, rz = p[0] - o[0], p[1] - o[1], p[2] - o[2]
        cx, cy, cz = z[1] * rz - z[2] * ry, z[2] * rx - z[0] * rz, z[0] * ry - z[1] * rx
        for j in range(n):
            mt = M_theta[i, j]
            md = M_d[i, j]
            if mt != 0.0 or md != 0.0:
                Jq[0, j] += cx * mt + z[0] * md
                Jq[1, j] += cy * mt + z[1] * md
                Jq[2, j] += cz * mt + z[2] * md
    for j in range(n):
        for r in range(3):
            Jq[r, j] *= speed[j]
    if n < 3:
        return 0.0
    sv = np.linalg.svd(Jq)[1]  # singular values, largest first (accurate to rounding of the largest)
    if sv[0] <= 0.0:
        return 0.0
    return sv[2] / sv[0]


@_jit
def _clearances(robot, model, q, pts, out, at):
    """Every pair's capsule clearance, then every floor clearance [m], at q into ``out`` from index ``at``."""
    caps, radii, pairs, plane, plane_caps = model
    F = frames(robot, q)
    _capsule_points(F, caps, pts)
    P = pairs.shape[0]
    for k in range(P):
        a = pairs[k, 0]
        b = pairs[k, 1]
        out[at + k] = _segment_distance(pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1]) - radii[a] - radii[b]
    for k in range(plane_caps.shape[0]):
        c = plane_caps[k]
        out[at + P + k] = _plane_clearance(pts[c, 0], pts[c, 1], radii[c], plane)


@_jit
def hazard_values(robot, chain, model, q, pts, out):
    """The clearances of every geometric hazard and the σ ratio at q into ``out`` (1 + P + Pl,): out[0] the σ
    ratio, then each pair's capsule clearance [m], then each plane capsule's clearance above ``plane`` [m].

    robot: the chain's record (``SerialRobot.kernel_record``); chain: (M_θ, M_d, joint speeds); model: the
    capsules (C, 2) and their radii (C,), the capsule pairs checked (P, 2), the floor (4,) and the capsules checked
    against it (Pl,) (:meth:`app.control.guard.HazardGuard.record`); pts (C, 2, 3) scratch."""
    M_theta, M_d, speed = chain
    caps, radii, pairs, plane, plane_caps = model
    F = frames(robot, q)
    out[0] = _sigma_ratio(F, M_theta, M_d, speed)
    _capsule_points(F, caps, pts)
    P = pairs.shape[0]
    for k in range(P):
        a = pairs[k, 0]
        b = pairs[k, 1]
        out[1 + k] = _segment_distance(pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1]) - radii[a] - radii[b]
    for k in range(plane_caps.shape[0]):
        c = plane_caps[k]
        out[1 + P + k] = _plane_clearance(pts[c, 0], pts[c, 1], radii[c], plane)


@_jit
def _active(robot, chain, model, limits, q, settings, G, rows):
    """The hazards in their zones at q: each one's gradient in q into a row of ``G`` (n + m, n) and its value,
    zone, stop, kind and index into ``rows``; returns how many.  Joint limits: ±1 on the joint.  The σ ratio:
    :func:`_sigma_grad`.  A capsule pair: the rate of its closest points apart along the line between them
    (:func:`_point_rate`); a capsule over the floor: its lower end's rate along the floor's normal."""
    caps, radii, pairs, plane, plane_caps = model
    M_theta, M_d, speed = chain
    lo, hi = limits[0], limits[1]
    n = q.shape[0]
    P = pairs.shape[0]
    Pl = plane_caps.shape[0]
    C = caps.shape[0]
    F = frames(robot, q)
    pts = np.empty((C, 2, 3))
    _capsule_points(F, caps, pts)
    lim_zone, lim_stop = settings[0], settings[1]
    sig_zone, sig_stop = settings[2], settings[3]
    cap_zone, cap_stop = settings[4] + settings[8], settings[5] + settings[8]  # shifted by the servo's margin
    kink = settings[6]
    val, zone, stop, kind, index = rows
    na = 0
    for j in range(n):
        span = hi[j] - lo[j]
        zj, sj = lim_zone * span, lim_stop * span
        dlo = q[j] - lo[j]
        dhi = hi[j] - q[j]
        if dlo < zj:
            G[na, j] = 1.0
            val[na], zone[na], stop[na], kind[na], index[na] = dlo, zj, sj, LIMIT, j
            na += 1
        if dhi < zj:
            G[na, j] = -1.0
            val[na], zone[na], stop[na], kind[na], index[na] = dhi, zj, sj, LIMIT, n + j
            na += 1
    # the σ ratio and its gradient (closed form), in its zone
    g = np.zeros(n)
    sigma = _sigma_grad(F, M_theta, M_d, speed, kink, sig_zone, g)
    if sigma < sig_zone:
        G[na, :] = g
        val[na], zone[na], stop[na], kind[na], index[na] = sigma, sig_zone, sig_stop, SINGULAR, 0
        na += 1
    # the capsule pairs and the floor, in their zones: the gradient of a clearance is the rate of its closest
    # points apart along the line between them (of the lower end above the floor, along its normal)
    u = np.empty(3)
    for k in range(P):
        a = pairs[k, 0]
        b = pairs[k, 1]
        dist, sa, tb = _segment_closest(pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1])
        clear = dist - radii[a] - radii[b]
        if clear >= cap_zone:
            continue
        pa = pts[a, 0] + sa * (pts[a, 1] - pts[a, 0])
        pb = pts[b, 0] + tb * (pts[b, 1] - pts[b, 0])
        if dist > 1e-12:
            for r in range(3):
                u[r] = (pa[r] - pb[r]) / dist
            _point_rate(F, chain, caps[a, 0], caps[a, 1], sa, pa, u, G[na])
            _point_rate(F, chain, caps[b, 0], caps[b, 1], tb, pb, -u, G[na])
        val[na], zone[na], stop[na], kind[na], index[na] = clear, cap_zone, cap_stop, PAIR, k
        na += 1
    for r in range(3):
        u[r] = plane[r]
    for k in range(Pl):
        c = plane_caps[k]
        ha = plane[0] * pts[c, 0, 0] + plane[1] * pts[c, 0, 1] + plane[2] * pts[c, 0, 2]
        hb = plane[0] * pts[c, 1, 0] + plane[1] * pts[c, 1, 1] + plane[2] * pts[c, 1, 2]
        clear = min(ha, hb) - plane[3] - radii[c]
        if clear >= cap_zone:
            continue
        end = 0 if ha <= hb else 1
        _point_rate(F, chain, caps[c, 0], caps[c, 1], float(end), pts[c, end], u, G[na])
        val[na], zone[na], stop[na], kind[na], index[na] = clear, cap_zone, cap_stop, PLANE, k
        na += 1
    for i in range(na):  # a gradient at rounding's level (a distance the step cannot change) is none at all
        gg = 0.0
        for j in range(n):
            gg += G[i, j] * G[i, j]
        if gg < 1e-24:
            for j in range(n):
                G[i, j] = 0.0
    return na


@_jit
def _solve_small(A, b, x):
    """x = A⁻¹b for a small dense A (k × k), Gaussian elimination with partial pivoting; False where A is singular
    to rounding (a pivot under 10⁻¹⁰ of A's largest entry)."""
    k = A.shape[0]
    M = A.copy()
    y = b.copy()
    big = 0.0
    for a in range(k):
        for c in range(k):
            big = max(big, abs(M[a, c]))
    if not big > 0.0:
        return False
    for c in range(k):
        p = c
        for a in range(c + 1, k):
            if abs(M[a, c]) > abs(M[p, c]):
                p = a
        if abs(M[p, c]) < 1e-10 * big:
            return False
        if p != c:
            for e in range(k):
                M[c, e], M[p, e] = M[p, e], M[c, e]
            y[c], y[p] = y[p], y[c]
        for a in range(c + 1, k):
            f = M[a, c] / M[c, c]
            for e in range(c, k):
                M[a, e] -= f * M[c, e]
            y[a] -= f * y[c]
    for c in range(k - 1, -1, -1):
        acc = y[c]
        for e in range(c + 1, k):
            acc -= M[c, e] * x[e]
        x[c] = acc / M[c, c]
    return True


@_jit
def _least_change(G, H, dq, rules, out, slowed):
    """The step nearest ``dq`` in the tool's metric W whose every hazard's rate meets what it is due (its bound, or
    its push where one is due): min ½(x − dq)ᵀW(x − dq) with g_iᵀx ≥ w_i, exactly.  x = dq + Σ λ_i W⁻¹g_i, λ ≥ 0
    solving the linear complementarity problem of M = G W⁻¹ Gᵀ (rows H = W⁻¹g_i), by Murty's least-index
    principal pivoting (finite for a positive definite M: K. G. Murty, *Linear Complementarity, Linear and
    Nonlinear Programming*, 1988).  Into ``out`` and ``slowed`` (a bound that took a λ > 0); False, nothing
    written, where M is singular on the way (dependent gradients) or the pivoting does not end: the caller then
    projects in passes."""
    bound, push, norm2 = rules
    na = H.shape[0]
    n = dq.shape[0]
    M = np.zeros((na, na))
    r0 = np.zeros(na)
    want = np.zeros(na)
    for i in range(na):
        for j in range(n):
            r0[i] += G[i, j] * dq[j]
        want[i] = push[i] if push[i] > 0.0 else bound[i]
        for c in range(na):
            t = 0.0
            for j in range(n):
                t += G[i, j] * H[c, j]
            M[i, c] = t
    active = np.zeros(na, np.bool_)
    lam = np.zeros(na)
    for _ in range(4 * na + 8):
        k = 0
        for i in range(na):
            k += active[i]
        idx = np.empty(k, np.int64)
        k = 0
        for i in range(na):
            if active[i]:
                idx[k] = i
                k += 1
        A = np.empty((k, k))
        b = np.empty(k)
        x = np.empty(k)
        for a in range(k):
            b[a] = want[idx[a]] - r0[idx[a]]
            for c in range(k):
                A[a, c] = M[idx[a], idx[c]]
        if k > 0 and not _solve_small(A, b, x):
            return False
        for i in range(na):
            lam[i] = 0.0
        for a in range(k):
            lam[idx[a]] = x[a]
        pick = -1
        for i in range(na):
            if norm2[i] <= 0.0:
                continue  # no gradient (rounding's level): nothing the step can change
            if active[i]:
                if lam[i] < 0.0:
                    pick = i
                    break
            else:
                s = r0[i] - want[i]
                for c in range(na):
                    s += M[i, c] * lam[c]
                if s < -1e-15:
                    pick = i
                    break
        if pick < 0:
            for i in range(na):
                if lam[i] > 0.0:
                    for j in range(n):
                        out[j] += lam[i] * H[i, j]
                    if r0[i] < bound[i] - 1e-15:
                        slowed[i] = True
            return True
        active[pick] = not active[pick]
    return False


@_jit
def _tool_metric(J, G, na, H, hg):
    """The corrections of :func:`guard_step` in the metric W = JᵀJ + λI (J the tool point's position Jacobian,
    λ = 10⁻³ tr(JᵀJ)): into row i of ``H`` the direction W⁻¹g_i, into ``hg[i]`` g_iᵀW⁻¹g_i (Cholesky of W, n × n)."""
    n = J.shape[1]
    W = np.zeros((n, n))
    tr = 0.0
    for a in range(n):
        for b in range(a + 1):
            w = J[0, a] * J[0, b] + J[1, a] * J[1, b] + J[2, a] * J[2, b]
            W[a, b] = w
            W[b, a] = w
        tr += W[a, a]
    lam = 1e-3 * tr + 1e-12
    for a in range(n):
        W[a, a] += lam
    Lc = np.zeros((n, n))  # W = Lc Lcᵀ
    for a in range(n):
        for b in range(a + 1):
            acc = W[a, b]
            for k in range(b):
                acc -= Lc[a, k] * Lc[b, k]
            if a == b:
                Lc[a, a] = math.sqrt(max(acc, 1e-300))
            else:
                Lc[a, b] = acc / Lc[b, b]
    y = np.empty(n)
    for i in range(na):
        for a in range(n):  # Lc y = g
            acc = G[i, a]
            for k in range(a):
                acc -= Lc[a, k] * y[k]
            y[a] = acc / Lc[a, a]
        for a in range(n - 1, -1, -1):  # Lcᵀ h = y
            acc = y[a]
            for k in range(a + 1, n):
                acc -= Lc[k, a] * H[i, k]
            H[i, a] = acc / Lc[a, a]
        t = 0.0
        for a in range(n):
            t += G[i, a] * H[i, a]
        hg[i] = t


@_jit
def guard_step(robot, chain, model, limits, q, dq, settings, report):
    """One joint step ``dq`` (n,) from q (robot, chain, model: as :func:`hazard_values`; limits: the joints' lower
    and upper limits), scaled along the directions that bring a hazard nearer; returns the
    scaled step (velocity damper: Faverjon & Tournassoud 1987; Kanoun, Lamiraux & Wieber 2011, eq. 10).

    For each hazard i with clearance d_i inside its zone (d_i < zone_i) and gradient g_i = ∂d_i/∂q, the step's
    rate r_i = g_i·dq is left as it is when r_i ≥ 0 (the step opens the clearance or keeps it) and bounded when
    r_i < 0 by

        r_i ≥ −min(s_i |r_i⁰|, κ (d_i − stop_i)),   s_i = clamp((d_i − stop_i)/(zone_i − stop_i), 0, 1),

    (r_i⁰ the unscaled step's rate): the approach slows linearly through the zone and, κ = ½, never crosses the
    stop distance (to first order).  The rate is corrected where that changes the tool's motion least: the step
    moves by c W⁻¹g_i, c = (b_i − r_i)/(g_iᵀW⁻¹g_i), the least change in the metric W = JᵀJ + λI (J the tool
    point's position Jacobian, λ = 10⁻³ tr JᵀJ: :func:`_tool_metric`) — the damper as a constraint on the task's
    least-squares step, as Kanoun et al. pose it — solved exactly for all the hazards in their zones at once
    (:func:`_least_change`), else in a few passes over them; if a bound still fails,
    the whole step is scaled down to meet every bound (dq = 0 meets them all: every bound is ≤ 0), and so it is if
    a joint would need longer at its speed limit than the command did.  Corrected in the joints' own metric
    (dq − (r_i − b_i) g_i/|g_i|², before 2026-11-30) what was left of the command went elsewhere: pushed straight
    down onto the floor, the Comau's tool slid 1.1 m sideways; the SCARA, pushed along +x near its singularity,
    went 0.47 m along −x (safety H121).  With settings[10] = 0 (the position mode's walk to a joint goal, whose
    tool motion is no command: :meth:`app.control.guard.HazardGuard.in_tool_metric`) the step is corrected in the
    joints' metric, in passes, as before.

    Inside the capsules' own stop (settings[5], where only a braking overshoot puts a capsule: the safe-braking
    rule's clearance is half of it) the bound turns positive, as Kanoun et al.'s eq. 10 does for d < d_s: a
    non-zero step gains a rate r_i ≥ min(½(stop − d_i), ⅕ |g_i||dq|) along g_i, motion away from the hazard at most
    a fifth of the command's own, never a slowing (not reported as one, and not enforced by the last scaling).
    A zero step stays zero: a centred stick holds.  Without it a tool caught at the safe-braking clearance slid
    along the floor at 8–13 % of the stick's speed (the braking path of a tangential step dips below that
    clearance, so the rule took gentler references): the Panda in ``bosun bench guard``.

    settings (11,): zone and stop of the joint limits [share of each joint's range], of the σ ratio, of the
    capsule clearances [m]; the σ ratio below which σ_min has no gradient (a kink: :func:`_sigma_grad`); passes;
    a margin [m] added to the capsules' zone and stop (how far the arm may be from ``q``:
    :meth:`app.control.guard.HazardGuard.margin`); the safe-braking clearance
    (:func:`app.scenes.teleop_kernels.guard_tick`); the metric (1 the tool's, 0 the joints').

    report (6,) out: of the hazards that slowed the step (if none, of all in their zones) the one with the least
    of its zone left — its kind (:data:`LIMIT`, :data:`SINGULAR`, :data:`PAIR`, :data:`PLANE`; −1 none in its
    zone), its index (a joint limit: the joint for its lower, n + the joint for its upper), its value (clearance
    [m], σ ratio, or distance to the limit [rad or m]), its zone's share left ((d − stop)/(zone − stop)) — whether
    the step was slowed (1.0), and |dq_out|/|dq| (1 for a zero step)."""
    n = q.shape[0]
    m = 1 + model[2].shape[0] + model[4].shape[0]
    G = np.zeros((n + m, n))
    val = np.zeros(n + m)
    zone = np.zeros(n + m)
    stop = np.zeros(n + m)
    kind = np.zeros(n + m, np.int64)
    index = np.zeros(n + m, np.int64)
    na = _active(robot, chain, model, limits, q, settings, G, (val, zone, stop, kind, index))
    passes = int(settings[7])
    out = dq.copy()
    bound = np.zeros(na)  # the damper's bounds (≤ 0): a step slowed to meet one is reported as slowed
    push = np.zeros(na)  # the recovery's (≥ 0): motion added away from a hazard, never a slowing
    slowed = np.zeros(na, np.bool_)
    norm2 = np.zeros(na)  # |g|² of each row
    dq_norm = 0.0
    for j in range(n):
        dq_norm += dq[j] * dq[j]
    dq_norm = math.sqrt(dq_norm)
    for i in range(na):
        r0 = 0.0
        gg = 0.0
        for j in range(n):
            r0 += G[i, j] * dq[j]
            gg += G[i, j] * G[i, j]
        norm2[i] = gg
        if r0 < 0.0:
            s = min(max((val[i] - stop[i]) / (zone[i] - stop[i]), 0.0), 1.0)
            bound[i] = -min(s * -r0, 0.5 * max(val[i] - stop[i], 0.0))
        else:
            bound[i] = 0.0  # not approaching: never slowed, and no correction may turn it into an approach
        if (kind[i] == PAIR or kind[i] == PLANE) and val[i] < settings[5] and dq_norm > 0.0:
            # inside the capsules' own stop (a braking overshoot put it there): the damper's bound turns positive
            # (Kanoun et al. eq. 10 with d < d_s), the command carries the clearance back out — at most a fifth of
            # the command's own rate along the gradient, and only while the operator commands motion
            push[i] = min(0.5 * (settings[5] - val[i]), 0.2 * math.sqrt(gg) * dq_norm)
    H = np.zeros((na, n))  # each hazard's correction direction W⁻¹g_i (in the tool's metric) and g_iᵀW⁻¹g_i
    hg = np.zeros(na)
    due = False  # a rate short of what it is due: only then the metric and the correction (most ticks: none)
    for i in range(na):
        r = 0.0
        for j in range(n):
            r += G[i, j] * dq[j]
        if norm2[i] > 0.0 and r < (push[i] if push[i] > 0.0 else bound[i]) - 1e-15:
            due = True
    tool = settings[10] > 0.5
    if due and tool:
        J = jacobian_from_frames(frames(robot, q), chain[0], chain[1])
        _tool_metric(J, G, na, H, hg)
        if _least_change(G, H, dq, (bound, push, norm2), out, slowed):
            passes = 0  # solved exactly: no passes
    elif due:  # the joints' metric (a walk to a joint goal): W = I, in passes as before H121
        for i in range(na):
            hg[i] = norm2[i]
            for j in range(n):
                H[i, j] = G[i, j]
    else:
        passes = 0  # nothing to correct
    for _ in range(passes):
        changed = False
        for i in range(na):
            r = 0.0
            for j in range(n):
                r += G[i, j] * out[j]
            want = push[i] if push[i] > 0.0 else bound[i]  # a push only where one is due (bounds are ≤ 0)
            if r < want - 1e-15 and norm2[i] > 0.0 and hg[i] > 0.0:
                c = (want - r) / hg[i]
                for j in range(n):
                    out[j] += c * H[i, j]
                if r < bound[i] - 1e-15:
                    slowed[i] = True
                changed = True
        if not changed:
            break
    alpha = 1.0
    for i in range(na):
        r = 0.0
        for j in range(n):
            r += G[i, j] * out[j]
        if r < bound[i] - 1e-12:
            slowed[i] = True
            alpha = min(alpha, bound[i] / r) if r < 0.0 else 0.0
    # the corrections may speed a joint that compensates: the step takes no longer at the joints' speed limits than
    # the command did (scaled as a whole, every bound still met: they are ≤ 0)
    speed = chain[2]
    t0 = 0.0
    t1 = 0.0
    for j in range(n):
        if speed[j] > 0.0:
            t0 = max(t0, abs(dq[j]) / speed[j])
            t1 = max(t1, abs(out[j]) / speed[j])
    if tool and t1 > t0 > 0.0:
        alpha = min(alpha, t0 / t1)
    if alpha < 1.0:
        for j in range(n):
            out[j] *= max(alpha, 0.0)
    # the report: of the hazards that slowed the step (else of all in their zones), the one with the least zone left
    best = -1
    best_share = math.inf
    any_slowed = False
    for i in range(na):
        any_slowed = any_slowed or slowed[i]
    for i in range(na):
        share = (val[i] - stop[i]) / (zone[i] - stop[i])
        if (slowed[i] or not any_slowed) and share < best_share:
            best_share = share
            best = i
    n0 = 0.0
    n1 = 0.0
    for j in range(n):
        n0 += dq[j] * dq[j]
        n1 += out[j] * out[j]
    report[0] = -1.0 if best < 0 else float(kind[best])
    report[1] = -1.0 if best < 0 else float(index[best])
    report[2] = math.nan if best < 0 else val[best]
    report[3] = math.nan if best < 0 else best_share
    report[4] = 1.0 if any_slowed else 0.0
    report[5] = math.sqrt(n1 / n0) if n0 > 0.0 else 1.0
    return out


def warm_up_records() -> tuple:
    """The records of a three-link chain, as :class:`app.control.guard.HazardGuard` builds them (robot, chain,
    capsule model, joint limits, settings, q, dq): the warm-up calls' arguments here and in
    :mod:`app.scenes.teleop_kernels`."""
    L = n = 3
    dh = np.stack([np.zeros(L), np.zeros(L), np.ones(L), np.ones(L), np.zeros(L)])
    robot = (dh, np.stack([np.eye(L, n), np.zeros((L, n))]), np.stack([np.eye(4), np.eye(4)]))
    chain = (np.eye(L, n), np.zeros((L, n)), np.ones(n))
    caps = np.array([[0, 1], [2, 1]], dtype=np.int64)
    model = (caps, np.full(2, 0.1), np.array([[0, 1]], dtype=np.int64), np.array([0.0, 0.0, 1.0, -1.0]),
             np.array([1], dtype=np.int64))  # fmt: skip
    limits = (-np.ones(n), np.ones(n))
    settings = np.array([0.05, 0.0, 0.04, 0.01, 0.1, 0.005, 1e-6, 4.0, 0.0, 0.0025, 1.0])
    return robot, chain, model, limits, settings, np.full(n, 0.3), np.full(n, 1e-3)


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) this file's kernels with the argument types
    :class:`app.control.guard.HazardGuard` passes (for :func:`app.warmup.warm_up`): a three-link chain."""
    robot, chain, model, limits, settings, q, dq = warm_up_records()
    return [
        lambda: hazard_values(robot, chain, model, q, np.zeros((2, 2, 3)), np.zeros(3)),
        lambda: guard_step(robot, chain, model, limits, q, dq, settings, np.zeros(6)),
    ]
