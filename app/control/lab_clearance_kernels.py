"""The Comau's clearances in the Motion-Lab, compiled (issue 32, item 5): its capsules (the upper arm, forearm and
extension arm of eq. 3, the winch's wire and the hanging load) against EM8000's deck and the body under it, the
robot's pedestal and column, and EM1500's deck, with their gradients in the joints — what
:func:`app.control.lab_kernels.comau_guard` and ``winch_guard`` bound.  The NumPy reference is
:func:`app.control.lab.guard_hazards_reference`, tested equal in ``tests/test_lab_guard.py``.
"""

from __future__ import annotations

import math

import numpy as np

from app.control.guard_kernels import _segment_closest
from app.models.kernels import _jit
from app.models.lab_kernels import mtv

__all__ = ["arm_points", "guard_hazards", "swing_hang"]

#: the guard's obstacles (the report's kind): EM8000's deck under the robot, the robot's pedestal and column,
#: EM1500's deck; and the report's −1: none in its zone
DECK1, PEDESTAL, DECK2 = 0, 1, 2
GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)
GOLDEN_STEPS = 30  # the search's bracket shrinks to 0.618³⁰ = 5·10⁻⁷ of the segment: a micrometre on the extension arm
#: the wire's search: as long a segment, whose nearest point to the disc is often on the rim's curve, where a
#: micrometre off moves the gradient by 10⁻⁵ (the bracket 0.618⁴⁰ = 4·10⁻⁹ of the wire)
WIRE_GOLDEN_STEPS = 40
FAR = 1.5  # [m]: a disc row this far (by a lower bound; ten zones) takes the bound, not the search


@_jit
def arm_points(cm, q, P, J):
    """The Comau's shoulder, elbow, wrist and tool point in {r} into ``P`` (4, 3), and their Jacobians ∂p/∂q into
    ``J`` (4, 3, 3).  In the arm's plane (radial u, height z) eq. (3) is a sum of the links' own vectors —
    shoulder (a1, d1), upper arm a2 (s2, c2), forearm a3 (−c3, −s3), extension L (−s3, c3) — and a point is
    (c1 u, −s1 u, z): the tool's row is eq. (3)'s p_t^r and its Jacobian eq. (5)'s."""
    a1, d1, a2, a3, L = cm[0], cm[1], cm[2], cm[3], cm[4]
    s1, c1 = math.sin(q[0]), math.cos(q[0])
    s2, c2 = math.sin(q[1]), math.cos(q[1])
    s3, c3 = math.sin(q[2]), math.cos(q[2])
    u = (a1, a1 + a2 * s2, a1 + a2 * s2 - a3 * c3, a1 + a2 * s2 - a3 * c3 - L * s3)
    z = (d1, d1 + a2 * c2, d1 + a2 * c2 - a3 * s3, d1 + a2 * c2 - a3 * s3 + L * c3)
    u2 = (0.0, a2 * c2, a2 * c2, a2 * c2)
    z2 = (0.0, -a2 * s2, -a2 * s2, -a2 * s2)
    u3 = (0.0, 0.0, a3 * s3, a3 * s3 - L * c3)
    z3 = (0.0, 0.0, -a3 * c3, -a3 * c3 - L * s3)
    for k in range(4):
        P[k, 0], P[k, 1], P[k, 2] = c1 * u[k], -s1 * u[k], z[k]
        J[k, 0, 0], J[k, 1, 0], J[k, 2, 0] = -s1 * u[k], -c1 * u[k], 0.0
        J[k, 0, 1], J[k, 1, 1], J[k, 2, 1] = c1 * u2[k], -s1 * u2[k], z2[k]
        J[k, 0, 2], J[k, 1, 2], J[k, 2, 2] = c1 * u3[k], -s1 * u3[k], z3[k]


@_jit
def _disc_gap(x, c, n, R):
    """Clearance of the point x from the disc (centre c, unit normal n, radius R) and the unit direction from the
    disc's nearest point to x: over the disc the signed height (negative: through it) along n, beyond its rim the
    distance to the rim."""
    h = n[0] * (x[0] - c[0]) + n[1] * (x[1] - c[1]) + n[2] * (x[2] - c[2])
    w0, w1, w2 = x[0] - c[0] - h * n[0], x[1] - c[1] - h * n[1], x[2] - c[2] - h * n[2]
    rho = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    if rho <= R:
        return h, n[0], n[1], n[2]
    k = (rho - R) / rho
    e0, e1, e2 = w0 * k + h * n[0], w1 * k + h * n[1], w2 * k + h * n[2]
    d = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    if d <= 0.0:
        return 0.0, n[0], n[1], n[2]
    return d, e0 / d, e1 / d, e2 / d


@_jit
def _solid_gap(x, c, n, R):
    """Clearance of the point x from the solid cylinder under the disc (centre c, unit up normal n, radius R: a
    platform's deck and the body below it) and the unit direction away from it: above the disc its height, beyond
    its rim and above it the distance to the rim, beside the cylinder the distance to its wall; inside it, less
    the nearer of the way out through the top and through the wall (negative)."""
    h = n[0] * (x[0] - c[0]) + n[1] * (x[1] - c[1]) + n[2] * (x[2] - c[2])
    w0, w1, w2 = x[0] - c[0] - h * n[0], x[1] - c[1] - h * n[1], x[2] - c[2] - h * n[2]
    rho = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    if h >= 0.0 or (rho <= R and -h <= R - rho):
        return _disc_gap(x, c, n, R)  # above it, or inside nearer the top: the disc's own clearance
    if rho <= 0.0:
        return h, n[0], n[1], n[2]
    return rho - R, w0 / rho, w1 / rho, w2 / rho  # beside it, or inside nearer the wall


@_jit
def _gap(solid, x, c, n, R):
    return _solid_gap(x, c, n, R) if solid else _disc_gap(x, c, n, R)


@_jit
def _segment_disc(a, b, c, n, R, steps, solid):
    """The least clearance of the segment a–b from the disc (:func:`_disc_gap`) and where on it (s in [0, 1]):
    the ends and a golden-section search of ``steps`` steps between them (the distance to a convex set is convex
    along a line); ``solid``: from the cylinder under the disc (:func:`_solid_gap`)."""
    x = np.empty(3)
    lo, hi = 0.0, 1.0
    for _ in range(steps):
        m1 = hi - GOLDEN * (hi - lo)
        m2 = lo + GOLDEN * (hi - lo)
        for i in range(3):
            x[i] = a[i] + (b[i] - a[i]) * m1
        f1 = _gap(solid, x, c, n, R)[0]
        for i in range(3):
            x[i] = a[i] + (b[i] - a[i]) * m2
        f2 = _gap(solid, x, c, n, R)[0]
        if f1 <= f2:
            hi = m2
        else:
            lo = m1
    best_s, best = 0.0, _gap(solid, a, c, n, R)[0]
    for s in (1.0, 0.5 * (lo + hi)):
        for i in range(3):
            x[i] = a[i] + (b[i] - a[i]) * s
        f = _gap(solid, x, c, n, R)[0]
        if f < best:
            best_s, best = s, f
    for i in range(3):
        x[i] = a[i] + (b[i] - a[i]) * best_s
    d, e0, e1, e2 = _gap(solid, x, c, n, R)
    return d, best_s, e0, e1, e2


@_jit
def _grad(J, k, s, e0, e1, e2, g):
    """g = eᵀ ∂p/∂q at the point s of capsule k (between arm points k and k + 1: a point at a fixed share of a rigid
    segment moves as the share of its ends)."""
    for j in range(3):
        ja0 = J[k, 0, j] + s * (J[k + 1, 0, j] - J[k, 0, j])
        ja1 = J[k, 1, j] + s * (J[k + 1, 1, j] - J[k, 1, j])
        ja2 = J[k, 2, j] + s * (J[k + 1, 2, j] - J[k, 2, j])
        g[j] = e0 * ja0 + e1 * ja1 + e2 * ja2


#: the guard's capsules beyond the arm's three (the report's capsule): the winch's wire from the tool point to the
#: load, and the load (a sphere at the wire's end)
WIRE, LOAD = 3, 4
#: the guard's rows: for each arm capsule and obstacle the nearest point and each end (a capsule sweeping round can
#: close on an obstacle at its far end while its nearest point still recedes): EM8000's deck 3 × 2 (its ends), the
#: pedestal 2 × 3, EM1500's deck 3 × 3; then the wire's nearest point and the load's, each to EM8000's deck and to
#: the pedestal (2 × 2: the wire's ends are the tool point, the arm's, and the load)
ROWS = 25


@_jit
def _away(J, k, s, a, b, o, dist, g):
    """``g`` (a row of G): the gradient of |p − o| at the point p at s of capsule k (a–b), o fixed (zero if p = o)."""
    if dist > 1e-12:
        _grad(J, k, s, (a[0] + (b[0] - a[0]) * s - o[0]) / dist, (a[1] + (b[1] - a[1]) * s - o[1]) / dist,
              (a[2] + (b[2] - a[2]) * s - o[2]) / dist, g)  # fmt: skip
    else:
        g[0], g[1], g[2] = 0.0, 0.0, 0.0


@_jit
def guard_hazards(cm, radii, world, q, G, val, kind, cap):
    """The Comau's clearances [m] from its obstacles at q and their gradients ∂d/∂q (rows of ``G`` (:data:`ROWS`,
    3)), with each one's obstacle (:data:`DECK1`, :data:`PEDESTAL`, :data:`DECK2`) and capsule (0 upper arm,
    1 forearm, 2 extension arm: arm points k to k + 1 of :func:`arm_points`); returns how many (:data:`ROWS`).
    For each capsule and obstacle: the nearest point's clearance and each end's (EM8000's deck, a plane: the ends'
    only, one of them the nearest); EM1500's deck, when a lower bound (the segment's distance to its centre less
    its radius) puts it :data:`FAR` away, takes that bound for its nearest point.

    ``world`` = (deck1 (8,): EM8000's deck n·x = h in {r}, then its centre (3,) and radius; pedestal (2, 3): its
    axis from the deck to the column's top, and its radius (1,); deck2 (7,): EM1500's deck centre, up normal and
    radius in {r}; hang (10,): the wire from the tool point to the load, the centre of the load's swing envelope
    from the tool point, and the envelope's radius, in {r}, then the arm's tool velocity it was taken with
    (:func:`swing_hang`, :func:`app.scenes.lab_kernels.guard_world`)).  The
    capsules' ``radii`` (5,): the arm's three, the wire's and the load's.  The upper arm is joined to the column at
    the shoulder: its pedestal pair is not checked.

    The wire and the load (:data:`WIRE`, :data:`LOAD`, after the arm's rows) are checked against EM8000 (its deck
    and the body under it, a solid cylinder of the deck's radius, :func:`_solid_gap`: the load hangs beside it and
    below its deck's plane over EM1500, where it lands) and the pedestal; not against EM1500's deck, which the load
    is there to land on (its landing is the load's watch's: :mod:`app.scenes.crane_load`).  The wire is where it
    hangs now; the load is the sphere round every point its swing can reach however the arm stops (a swinging
    load is no joint's to brake: the arm is kept from bringing where it can reach near an obstacle).  Both move
    with the tool point (its Jacobian: a step of the arm carries the hanging load with it)."""
    deck1, ped, ped_r, deck2, hang = world
    P = np.empty((5, 3))
    J = np.empty((5, 3, 3))
    arm_points(cm, q, P, J)
    for i in range(3):
        P[4, i] = P[3, i] + hang[i]
        for j in range(3):
            J[4, i, j] = J[3, i, j]
    c2 = deck2[0:3]
    n2 = deck2[3:6]
    o = np.empty(3)
    m = 0
    for k in range(3):
        a, b, r = P[k], P[k + 1], radii[k]
        # EM8000's deck: a plane, each end's height
        for s in (0.0, 1.0):
            e = a if s == 0.0 else b
            val[m], kind[m], cap[m] = deck1[0] * e[0] + deck1[1] * e[1] + deck1[2] * e[2] - deck1[3] - r, DECK1, k
            _grad(J, k, s, deck1[0], deck1[1], deck1[2], G[m])
            m += 1
        # the pedestal and column: the segments' nearest points, then each end's nearest point on the pedestal
        if k > 0:
            for which in range(3):
                if which == 0:
                    dist, s, t = _segment_closest(a, b, ped[0], ped[1])
                else:
                    s = 0.0 if which == 1 else 1.0
                    e = a if which == 1 else b
                    dist, _, t = _segment_closest(e, e, ped[0], ped[1])
                for i in range(3):
                    o[i] = ped[0, i] + (ped[1, i] - ped[0, i]) * t
                val[m], kind[m], cap[m] = dist - r - ped_r[0], PEDESTAL, k
                _away(J, k, s, a, b, o, dist, G[m])
                m += 1
        # EM1500's deck: a disc; the segment's nearest point, then each end
        for which in range(3):
            if which == 0:
                # a lower bound first: the segment's distance to the disc's centre less its radius
                lb, s, _ = _segment_closest(a, b, c2, c2)
                if lb - deck2[6] - r > FAR:  # far: the bound (and its direction) stand for the clearance
                    val[m], kind[m], cap[m] = lb - deck2[6] - r, DECK2, k
                    _away(J, k, s, a, b, c2, lb, G[m])
                    m += 1
                    continue
                d, s, e0, e1, e2 = _segment_disc(a, b, c2, n2, deck2[6], GOLDEN_STEPS, False)
            else:
                s = 0.0 if which == 1 else 1.0
                d, e0, e1, e2 = _disc_gap(a if which == 1 else b, c2, n2, deck2[6])
            val[m], kind[m], cap[m] = d - r, DECK2, k
            _grad(J, k, s, e0, e1, e2, G[m])
            m += 1
    # the wire (tool point to load) and the load: EM8000's deck as a disc, then the pedestal
    a, b = P[3], P[4]
    c1, n1, R1 = deck1[4:7], deck1[0:3], deck1[7]
    d, s, e0, e1, e2 = _segment_disc(a, b, c1, n1, R1, WIRE_GOLDEN_STEPS, True)  # (no far bound: a solid's
    val[m], kind[m], cap[m] = d - radii[WIRE], DECK1, WIRE  # inside can be far from its deck's centre)
    _grad(J, WIRE, s, e0, e1, e2, G[m])
    m += 1
    env = np.empty(3)  # the load's swing envelope: a sphere round where its swing can take it
    for i in range(3):
        env[i] = a[i] + hang[3 + i]
    d, e0, e1, e2 = _solid_gap(env, c1, n1, R1)
    val[m], kind[m], cap[m] = d - radii[LOAD] - hang[6], DECK1, LOAD
    _grad(J, WIRE, 0.0, e0, e1, e2, G[m])
    m += 1
    for which in range(2):  # the wire's nearest point to the pedestal, then the load's envelope's
        if which == 0:
            dist, s, t = _segment_closest(a, b, ped[0], ped[1])
            r = radii[WIRE]
            for i in range(3):
                o[i] = ped[0, i] + (ped[1, i] - ped[0, i]) * t
            _away(J, WIRE, s, a, b, o, dist, G[m])
        else:
            dist, _, t = _segment_closest(env, env, ped[0], ped[1])
            r = radii[LOAD] + hang[6]
            for i in range(3):
                o[i] = ped[0, i] + (ped[1, i] - ped[0, i]) * t
            _away(J, WIRE, 0.0, env, env, o, dist, G[m])
        val[m], kind[m], cap[m] = dist - r - ped_r[0], PEDESTAL, WIRE + which
        m += 1
    return m


@_jit
def swing_hang(frames, swing, v_arm):
    """The hanging load in the Comau's base {r} for :func:`guard_hazards` (its ``hang`` (10,)): the wire from the
    tool point to the load, eq. (58)'s L·(−sα, −cα sβ, −cα cβ) in {g}; the centre of its swing's envelope from the
    tool point and the envelope's radius; and ``v_arm``, the tool point's velocity from the arm's joints in {r}
    (J q̇, eq. 5), which it was taken with.  ``frames`` = (T_g_n1, R1, T_b1_r): {g} into {r} through EM8000's body
    as the controller sees it; ``swing`` = (α, β, α̇, β̇, L, g).

    The envelope holds the load however the arm stops (H122).  The swing's own energy relative to the tool point
    is e_r = g L (1 − cα cβ) + ½ |u|², u = L ẇ, |u|² = L² (α̇² + cα² β̇²) (eqs. 26–27).  Were the arm stopped now
    the load would keep its velocity: relative to the tool it would be u + v (v the wire-normal part of v_arm; the
    wire takes the part along it), whose energy depends on where the swing is in its period.  Whatever that
    phase, |(√(2 g L (1 − cα cβ)), u + v)| ≤ |(√(2 g L (1 − cα cβ)), u)| + |v|, so the envelope takes
    e = ½ (√(2 e_r) + |v|)²: braking the arm hands the swing what it takes from v and never grows e, and a swing
    the arm pumps by speeding up grows it as it happens.  The load then reaches θ from the vertical with
    1 − cos θ = e/(g L); the cap it can reach lies in the sphere round L cos θ below the tool point of radius
    L sin θ (1 − cos θ ≤ sin θ up to 90°; beyond, round the tool point, of radius L; a swing that is not finite,
    the same: the load may be anywhere its wire reaches)."""
    T_g_n1, R1, T_b1_r = frames
    alpha, beta, alpha_dot, beta_dot, L, g = swing
    known = math.isfinite(alpha + beta + alpha_dot + beta_dot + v_arm[0] + v_arm[1] + v_arm[2])
    if not known:  # anywhere within L of the tool point
        alpha = beta = alpha_dot = beta_dot = 0.0
    sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
    hang = np.empty(10)
    wn = mtv(T_g_n1, -L * sa, -L * ca * sb, -L * ca * cb)
    wb = mtv(R1, wn[0], wn[1], wn[2])
    wr = mtv(T_b1_r, wb[0], wb[1], wb[2])
    # 1 − cα cβ = 2 sin²(α/2) + 2 cα sin²(β/2): without the cancellation near the vertical; |u|² = L² |ẇ|²
    tilt = 2.0 * (math.sin(0.5 * alpha) ** 2 + ca * math.sin(0.5 * beta) ** 2)
    e = g * L * tilt + 0.5 * L * L * (alpha_dot * alpha_dot + ca * ca * beta_dot * beta_dot)  # e_r
    along = (v_arm[0] * wr[0] + v_arm[1] * wr[1] + v_arm[2] * wr[2]) / (L * L) if L > 0.0 else 0.0
    m0, m1, m2 = v_arm[0] - along * wr[0], v_arm[1] - along * wr[1], v_arm[2] - along * wr[2]  # v
    e = 0.5 * (math.sqrt(2.0 * e) + math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)) ** 2
    eps = e / (g * L) if L > 0.0 else 0.0  # 1 − cos θ (the radius from it: 1 − k² loses it where it is small)
    k = 1.0 - eps if known else -1.0
    depth, radius = (L * k, L * math.sqrt(max(0.0, eps * (2.0 - eps)))) if k > 0.0 else (0.0, L)
    zn = mtv(T_g_n1, 0.0, 0.0, 1.0)  # up
    zb = mtv(R1, zn[0], zn[1], zn[2])
    zr = mtv(T_b1_r, zb[0], zb[1], zb[2])
    for i in range(3):
        hang[i], hang[3 + i], hang[7 + i] = wr[i], -depth * zr[i], v_arm[i]
    hang[6] = radius
    return hang
