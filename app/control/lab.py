"""The Motion-Lab's controllers as blocks (:mod:`app.models.block`): the Comau's modes and the winch's heave
compensation (Motion-Lab paper §§4–6).

* :data:`COMAU_LAW`: SETTLED (to the park joints at a quarter speed), REMOTE (the operator's tool velocity
  through q̇ = J⁺ ṗ, eq. 21) and MOTION_COMP (VVMC: the work point fixed on EM1500, eqs. 54–56 inverted for the
  tool point in the robot base, the analytic IK of eqs. 7–20 and the feed-forward q̇ = J⁺ ṗ_t^r of eq. 21),
  or BRAKE (HOLD, E-STOP).  Its output is the joint command of the drives (:data:`app.sim.motionlab.COMAU_DRIVES`).
* :data:`COMAU_GUARD`: the law's joint command scaled along the directions that bring the Comau's links nearer
  an obstacle — EM8000's deck under it, its pedestal and column, EM1500's deck (issue 32, item 5; the obstacles
  and capsules are :class:`ComauGuard`'s).
* :data:`WINCH_LAW`: active heave compensation, the wire length that keeps the load's height fixed relative
  to EM1500 (with the relative vertical speed as feed-forward), or the operator's speed; its output is the
  length reference of the drum (:data:`app.sim.motionlab.WINCH_DRUM`).

The functions here are the NumPy references of the compiled :mod:`app.control.lab_kernels`, on the same
records (tested equal in ``tests/test_blocks.py``).  A controller sees the platforms as its sensor reports
them: ``view`` = (η1, η̇1, R1, Ṙ1, η2, η̇2, R2, Ṙ2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from app.control import lab_kernels
from app.control.lab_kernels import BRAKE, MOTION_COMP, REMOTE, SETTLED
from app.models.block import Block
from app.models.closed_form import ComauArm
from app.models.comau import ComauKinematics, nearest_ik

__all__ = ["BRAKE", "COMAU_GUARD", "COMAU_LAW", "MOTION_COMP", "REMOTE", "SETTLED", "WINCH_LAW", "ComauGuard"]


def _comau_reference(x, u, p, dt):
    """The NumPy reference of :func:`app.control.lab_kernels.comau_law`."""
    mode, q, v_cmd, offset, view = u
    cm, T_base, _, T_n1_n2, T_b1_r, w_b2, park_q, lower, upper = p
    if mode == BRAKE:
        return x, (True, q, q, False, 1.0)
    if mode == SETTLED:
        return x, (False, park_q, park_q, False, 0.25)
    comau = ComauKinematics(*(float(c) for c in cm))
    if mode == REMOTE:
        rate = np.linalg.lstsq(comau.jacobian(q), v_cmd, rcond=1e-6)[0]  # eq. (21)
        return x, (False, q + rate * dt, rate, True, 1.0)
    assert mode == MOTION_COMP
    eta1, eta_dot1, R1, Rd1, eta2, eta_dot2, R2, Rd2 = view
    off_p, off_v, d, dd = offset
    # the work point fixed in {b2} and shifted there by the operator, in {n1} (eq. 39 through {g}), plus the offset
    R12 = T_n1_n2[:3, :3]
    w = w_b2 + d
    p_n1 = T_n1_n2[:3, 3] + R12 @ (eta2[:3] + R2 @ w) + off_p
    v_n1 = R12 @ (eta_dot2[:3] + Rd2 @ w + R2 @ dd) + off_v
    # eqs. (54), (56) inverted for the tool point in {r}
    R_r, p_r = T_b1_r[:3, :3], T_b1_r[:3, 3]
    p_tr = R_r.T @ (R1.T @ (p_n1 - eta1[:3]) - p_r)
    arm = p_r + R_r @ p_tr
    v_tr = R_r.T @ (R1.T @ (v_n1 - eta_dot1[:3] - Rd1 @ arm))
    q_d = nearest_ik(ComauArm(*(float(c) for c in cm), T_base), p_tr, q, lower, upper, use_kernels=False)
    if q_d is None:  # out of reach: hold, limits intact
        q_d = q.copy()
    rate = np.linalg.lstsq(comau.jacobian(q_d), v_tr, rcond=1e-6)[0]  # eq. (21)
    return x, (False, q_d, rate, True, 1.0)


#: the Comau's controller: its joint command from the mode, the operator's tool velocity and the platforms
COMAU_LAW = Block(
    "Comau law (REMOTE / MOTION_COMP)",
    state=(),
    inputs=("mode", "q", "v_cmd", "offset", "view"),
    outputs=("brake", "q_ref", "q_dot_ref", "use_q_dot_ref", "speed_scale"),
    params=("cm", "T_base", "signs", "T_n1_n2", "T_b1_r", "w_b2", "park_q", "lower", "upper"),
    reference=_comau_reference,
    kernel=lab_kernels.comau_law,
)


# ---------------------------------------------------------------------------------------------- the Comau's guard
CAPSULES = ("upper arm", "forearm", "extension arm", "wire", "load")
#: the wire's radius [m]: the lab winch's 3 mm steel wire rope (:mod:`app.scenes.lab_load`'s assumed value)
WIRE_RADIUS = 0.0015
#: the load's radius [m]: the sphere round the cube of 0.12 m edge the lab's drawing gives the payload
#: (:func:`app.models.drawing.scenes.lab_meshes`' ``load_size``), 0.06·√3
LOAD_RADIUS = 0.06 * math.sqrt(3.0)
OBSTACLES = ("EM8000 deck", "pedestal", "EM1500 deck")


@dataclass(frozen=True, eq=False)
class ComauGuard:
    """The Comau's capsules and its obstacles in its base {r} (z up), for :data:`COMAU_GUARD`.

    Capsules: the upper arm (shoulder–elbow), the forearm (elbow–wrist) and the extension arm (wrist–tool point),
    with the radii the lab's drawing gives them (:func:`app.models.drawing.machines.link_radius`, tapered along the
    chain as :class:`app.control.guard.HazardGuard`'s; a link's ``<collision radius>`` where the file gives one);
    then the winch's wire from the tool point to the load (:data:`WIRE_RADIUS`) and the load (:data:`LOAD_RADIUS`).
    Obstacles: EM8000's deck (the plane z = 0 of {b1}, under the robot: for the arm its edge is not modelled, so
    beyond it the deck's plane still counts; for the wire and the load, which hang beyond it and below its plane
    over EM1500, the solid under the disc of its upper joints' radius, or out past the pedestal that stands on it
    where that is further: the lab's data give no size of the deck itself), the pedestal from that deck to the
    robot's column top (0, 0, d1) with the drawing's pedestal radius, and EM1500's deck (a disc of its upper
    joints' radius, as the load lands on it: :mod:`app.scenes.lab_load`; the arm's only).  Zone and stop [m]
    (0.15, 0.02: the arm's lag at its 30°/s is ~0.1 m of extension-arm travel over the drives' 0.05 s and their
    braking), the braking share κ of the braking bound.  ``deck1`` = (n, h, centre, radius): the plane n·x = h
    and the disc on it."""

    radii: NDArray[np.float64]
    deck1: NDArray[np.float64]
    pedestal: NDArray[np.float64]
    pedestal_radius: float
    deck2_radius: float
    zone: float = 0.15
    stop: float = 0.02
    braking: float = 0.5

    @classmethod
    def for_lab(cls, robot, cm: NDArray[np.float64], T_b1_r: NDArray[np.float64], models: tuple) -> ComauGuard:
        """The lab's guard; ``models``: EM8000's and EM1500's (their decks' radii: their upper joints')."""
        deck_radii = [float(np.max(np.linalg.norm(m.b_b[:, :2], axis=1))) for m in models]
        from app.models.drawing.machines import link_radius  # the drawing's sizes (no Qt: pure geometry)

        links = robot.links
        r0 = link_radius(links)
        drawn = [r0 * (1.0 - 0.4 * k / max(1, len(links) - 1)) for k in (1, 2)] + [0.6 * r0]
        radii = [
            float(links[i].radius) if getattr(links[i], "radius", None) is not None else drawn[k]
            for k, i in enumerate((1, 2, 3))
        ] + [WIRE_RADIUS, LOAD_RADIUS]
        R_r, p_r = T_b1_r[:3, :3], T_b1_r[:3, 3]
        up = R_r.T @ np.array([0.0, 0.0, -1.0])  # {b1} is z down
        h = float(p_r[2])  # n·x = h for the deck's points (−R_rᵀ p_r among them): n·(−R_rᵀ p_r) = p_r[2]
        foot = h * up  # the deck's point under the robot's base
        pedestal = np.array([foot, [0.0, 0.0, float(cm[1])]])
        # EM8000's deck: round {b1}'s origin, out to its upper joints or past the pedestal standing on it
        centre = -R_r.T @ p_r
        reach = float(np.linalg.norm((foot - centre) - ((foot - centre) @ up) * up)) + 1.6 * r0
        deck1 = np.array([*up, h, *centre, max(float(deck_radii[0]), reach)])
        return cls(np.array(radii), deck1, pedestal, 1.6 * r0, float(deck_radii[1]))

    def record(self) -> tuple:
        """The guard's parameters as :func:`app.scenes.lab_kernels.lab_step` takes them."""
        f64 = lambda a: np.ascontiguousarray(a, dtype=float)  # noqa: E731
        return (
            f64(self.radii), f64(self.deck1), f64(self.pedestal), f64([self.pedestal_radius]),
            f64([self.deck2_radius]), f64([self.zone, self.stop, self.braking]),
        )  # fmt: skip

    @staticmethod
    def text(report: NDArray[np.float64]) -> str:
        """The report's hazard as the operator reads it ("" none): "extension arm ↔ EM1500 deck: 83 mm"."""
        kind = int(report[0])
        if kind < 0:
            return ""
        return f"{CAPSULES[int(report[1])]} ↔ {OBSTACLES[kind]}: clearance {float(report[2]) * 1e3:.0f} mm"


def _arm_points(cm, q):
    """Shoulder, elbow, wrist and tool point in {r} and their Jacobians (the reference of
    :func:`app.control.lab_kernels.arm_points`; the tool's are eqs. 3 and 5)."""
    a1, d1, a2, a3, L = (float(c) for c in cm)
    s1, c1, s2, c2, s3, c3 = np.sin(q[0]), np.cos(q[0]), np.sin(q[1]), np.cos(q[1]), np.sin(q[2]), np.cos(q[2])
    links_u = np.array([a1, a2 * s2, -a3 * c3, -L * s3])  # each link's own radial and height parts
    links_z = np.array([d1, a2 * c2, -a3 * s3, L * c3])
    u, z = np.cumsum(links_u), np.cumsum(links_z)
    du = np.array([[0, 0], [a2 * c2, 0], [a2 * c2, a3 * s3], [a2 * c2, a3 * s3 - L * c3]])
    dz = np.array([[0, 0], [-a2 * s2, 0], [-a2 * s2, -a3 * c3], [-a2 * s2, -a3 * c3 - L * s3]])
    P = np.stack([c1 * u, -s1 * u, z], axis=1)
    J = np.zeros((4, 3, 3))
    J[:, :, 0] = np.stack([-s1 * u, -c1 * u, np.zeros(4)], axis=1)
    J[:, :, 1] = np.stack([c1 * du[:, 0], -s1 * du[:, 0], dz[:, 0]], axis=1)
    J[:, :, 2] = np.stack([c1 * du[:, 1], -s1 * du[:, 1], dz[:, 1]], axis=1)
    return P, J


def _disc_gap(x, c, n, R):
    h = float(n @ (x - c))
    w = x - c - h * n
    rho = float(np.linalg.norm(w))
    if rho <= R:
        return h, n
    e = w * ((rho - R) / rho) + h * n
    d = float(np.linalg.norm(e))
    return (0.0, n) if d <= 0.0 else (d, e / d)


def _solid_gap(x, c, n, R):
    """The reference of :func:`app.control.lab_kernels._solid_gap` (the solid cylinder under the disc)."""
    h = float(n @ (x - c))
    w = x - c - h * n
    rho = float(np.linalg.norm(w))
    if h >= 0.0 or (rho <= R and -h <= R - rho):
        return _disc_gap(x, c, n, R)
    return (h, n) if rho <= 0.0 else (rho - R, w / rho)


def _segment_disc(a, b, c, n, R, steps=lab_kernels.GOLDEN_STEPS, gap=_disc_gap):
    """As the kernel: a golden-section search for the least clearance (``gap``) on a–b, then the ends."""
    golden = 0.5 * (math.sqrt(5.0) - 1.0)
    lo, hi = 0.0, 1.0
    for _ in range(steps):
        m1, m2 = hi - golden * (hi - lo), lo + golden * (hi - lo)
        if gap(a + (b - a) * m1, c, n, R)[0] <= gap(a + (b - a) * m2, c, n, R)[0]:
            hi = m2
        else:
            lo = m1
    best_s, best = 0.0, gap(a, c, n, R)[0]
    for s in (1.0, 0.5 * (lo + hi)):
        f = gap(a + (b - a) * s, c, n, R)[0]
        if f < best:
            best_s, best = s, f
    d, e = gap(a + (b - a) * best_s, c, n, R)
    return d, best_s, e


def _segments_closest(p1, q1, p2, q2):
    """Closest points of two segments (Ericson §5.1.9), by the guard's kernel (no second copy of it)."""
    from app.control.guard_kernels import _segment_closest

    return _segment_closest(p1, q1, p2, q2)


def guard_hazards_reference(cm, radii, world, q):
    """The reference of :func:`app.control.lab_kernels.guard_hazards`: (G (m, 3), values, obstacles, capsules), for
    each capsule and obstacle the nearest point's row and each end's, in the kernel's order."""
    deck1, ped, ped_r, deck2, hang = world
    P, J = _arm_points(cm, q)
    P, J = np.vstack([P, P[3] + hang[:3]]), np.concatenate([J, J[3:4]])  # the load, moving with the tool point
    rows = []

    def away(k, s, p, o, dist):
        Jk = J[k] + s * (J[k + 1] - J[k])  # a point at a fixed share of a rigid segment moves as the share of its ends
        return (p - o) / dist @ Jk if dist > 1e-12 else np.zeros(3)

    for k in range(3):
        a, b, r = P[k], P[k + 1], radii[k]
        Jk = lambda s, k=k: J[k] + s * (J[k + 1] - J[k])  # noqa: E731
        for s, e in ((0.0, a), (1.0, b)):
            rows.append((deck1[:3] @ Jk(s), float(deck1[:3] @ e - deck1[3]) - r, 0, k))
        if k > 0:
            for which in range(3):
                if which == 0:
                    dist, s, t = _segments_closest(a, b, ped[0], ped[1])
                else:
                    s, e = (0.0, a) if which == 1 else (1.0, b)
                    dist, _, t = _segments_closest(e, e, ped[0], ped[1])
                o = ped[0] + (ped[1] - ped[0]) * t
                rows.append((away(k, s, a + (b - a) * s, o, dist), dist - r - ped_r[0], 1, k))
        for which in range(3):
            if which == 0:
                lb, s, _ = _segments_closest(a, b, deck2[0:3], deck2[0:3])
                if lb - deck2[6] - r > lab_kernels.FAR:  # far: the kernel's lower bound
                    d, e = lb - deck2[6], (a + (b - a) * s - deck2[0:3]) / lb
                else:
                    d, s, e = _segment_disc(a, b, deck2[0:3], deck2[3:6], deck2[6])
            else:
                s = 0.0 if which == 1 else 1.0
                d, e = _disc_gap(a if which == 1 else b, deck2[0:3], deck2[3:6], deck2[6])
            rows.append((e @ Jk(s), d - r, 2, k))
    # the wire and the load's swing envelope (the kernel's text): EM8000 as the solid under its deck, then the
    # pedestal; both move with the tool point
    a, b, Jt = P[3], P[4], J[3]
    c1, n1, R1 = deck1[4:7], deck1[0:3], deck1[7]
    r_w, r_l = radii[lab_kernels.WIRE], radii[lab_kernels.LOAD] + hang[6]
    env = a + hang[3:6]
    d, s, e = _segment_disc(a, b, c1, n1, R1, lab_kernels.WIRE_GOLDEN_STEPS, _solid_gap)
    rows.append((e @ Jt, d - r_w, 0, lab_kernels.WIRE))
    d, e = _solid_gap(env, c1, n1, R1)
    rows.append((e @ Jt, d - r_l, 0, lab_kernels.LOAD))
    for which, (p1, p2), r in ((0, (a, b), r_w), (1, (env, env), r_l)):
        dist, s, t = _segments_closest(p1, p2, ped[0], ped[1])
        o, p = ped[0] + (ped[1] - ped[0]) * t, p1 + (p2 - p1) * s
        rows.append(((p - o) / dist @ Jt if dist > 1e-12 else np.zeros(3), dist - r - ped_r[0], 1, 3 + which))
    G = np.array([r[0] for r in rows])
    return G, np.array([r[1] for r in rows]), np.array([r[2] for r in rows]), np.array([r[3] for r in rows])


def _correct(g, bound, out, lo_v, hi_v):
    """The reference of :func:`app.control.lab_kernels._correct` (an active set over the joints' bounds)."""
    out, free = out.copy(), np.ones(3, dtype=bool)
    for _ in range(3):
        r, gg = float(g @ out), float(np.sum(g[free] ** 2))
        if r >= bound - 1e-15 or gg <= 1e-24:
            break
        t = np.where(free, out + (bound - r) / gg * g, out)
        over, under = free & (t > hi_v), free & (t < lo_v)
        out = np.where(over, hi_v, np.where(under, lo_v, t))
        if not (over | under).any():
            break
        free &= ~(over | under)
    return out


def _least(rate):
    """The least part of a clearance's ``rate`` a joint must carry to count as closing or opening it (the kernel's)."""
    return np.maximum(lab_kernels.CONTRIBUTES, lab_kernels.CONTRIBUTES_SHARE * np.abs(rate))[..., None]


def _outcome_reference(model, plant, rows, settings, out):
    """The reference of :func:`app.control.lab_kernels._outcome`: which hazards the command ``out`` would close."""
    cm, radii, world = model
    q, qd, (lower, upper, _, accel, limit_brake, _), dt = plant
    G, clear, active = rows
    _, stop, kappa = settings
    reach = np.abs(out - qd) / (accel * dt) + np.abs(out) / (kappa * accel * dt)  # the kernel's horizon
    steps = int(min(np.max(np.ceil(reach - 1e-9), initial=0.0), lab_kernels.ROLLOUT))
    closing = np.zeros(len(clear), dtype=bool)
    for i in np.flatnonzero(active):
        v, qr, d, g = qd.copy(), q.copy(), float(clear[i]), G[i].copy()
        lowest, floor = d, min(stop - lab_kernels.BRAKE_SLACK, float(clear[i]))
        for k in range(steps):
            v = v + np.clip(out - v, -accel * dt, accel * dt)
            up = np.sqrt(2.0 * limit_brake * np.maximum(upper - qr, 0.0))
            v = np.clip(v, -np.sqrt(2.0 * limit_brake * np.maximum(qr - lower, 0.0)), up)
            qr = qr + v * dt
            if k % lab_kernels.RESAMPLE == lab_kernels.RESAMPLE - 1:
                Gr, vr, _, _ = guard_hazards_reference(cm, radii, world, qr)
                d, g = float(vr[i]), Gr[i]
            else:
                d += float(g @ v) * dt
                if d < floor <= lowest:  # the first order passes the floor: the true clearance there decides
                    Gr, vr, _, _ = guard_hazards_reference(cm, radii, world, qr)
                    d, g = float(vr[i]), Gr[i]
            lowest = min(lowest, d)
            if lowest < floor:
                break
        now = float(g @ v)
        if now < 0.0:
            Am = kappa * float(np.where(g * v < -_least(now)[0], np.abs(g) * accel, 0.0).sum())
            lowest = min(lowest, d - now * now / (2.0 * Am)) if Am > 0.0 else -math.inf
        closing[i] = lowest < floor
    return closing


def _guard_reference(x, u, p, dt):
    """The NumPy reference of :func:`app.control.lab_kernels.comau_guard`."""
    command, q, qd, world = u
    cm, radii, (lower, upper, speed, accel, limit_brake, tau), (zone, stop, kappa) = p
    brake, q_ref, v_ref, use_v, scale = command
    report = np.array([-1.0, -1.0, math.nan, math.nan, 0.0])
    if brake:
        return x, (command, report)
    G, val, kind, cap = guard_hazards_reference(cm, radii, world, q)
    clear = val.copy()
    up, down = np.maximum(upper - q, 0.0), np.maximum(q - lower, 0.0)
    hi_v = np.minimum(speed * scale, np.minimum(np.sqrt(2.0 * limit_brake * up), up / dt))
    lo_v = -np.minimum(speed * scale, np.minimum(np.sqrt(2.0 * limit_brake * down), down / dt))
    v0 = np.clip((q_ref - q) / max(tau, dt) + (v_ref if use_v else 0.0), lo_v, hi_v)  # what the drives can do
    gg = np.einsum("ij,ij->i", G, G)
    A = kappa * float(np.min(accel)) * np.sqrt(gg)
    C = G * qd  # each joint's part of each clearance's rate
    T = np.where(C < 0.0, np.abs(qd) / accel, 0.0).max(axis=1)  # the joints closing it stop in T at the latest
    room_j = np.where(qd > 0.0, upper - q, q - lower)
    now = np.where((C > 0.0) & (room_j < np.abs(qd) * T[:, None]), 0.0, C).sum(axis=1)  # an opening joint at its limit
    Am = kappa * np.where(-_least(now) > C, np.abs(G) * accel, 0.0).sum(axis=1)  # the joints closing each gap
    moving = (now < 0.0) & (Am > 0.0)
    val = np.where(moving, val - now * now / (2.0 * np.where(moving, Am, 1.0)), val)
    r0 = G @ v0
    room = np.maximum(val - stop, 0.0)
    active = val < zone
    share = np.clip(room / (zone - stop), 0.0, 1.0)
    brake_rate = np.sqrt(2.0 * A * room)
    bound = np.where(r0 < 0.0, -np.minimum(share * -r0, np.minimum(room / (2.0 * dt), brake_rate)), 0.0)
    bound = np.where(gg <= 1e-24, -np.inf, bound)
    check = active & np.isfinite(bound)
    out, slowed = v0.copy(), np.zeros(len(val), dtype=bool)
    violated = check & (G @ v0 < bound - 1e-15)
    if violated.any():  # the next step's speeds planned within what the drives reach in it (the kernel's text)
        r_hi = np.maximum(np.minimum(hi_v, qd + accel * dt), lo_v)
        r_lo = np.minimum(np.maximum(lo_v, qd - accel * dt), r_hi)
        out = np.clip(v0, r_lo, r_hi)
        for _ in range(4):
            changed = False
            for i in np.flatnonzero(check):
                if float(G[i] @ out) < bound[i] - 1e-15:
                    out = _correct(G[i], bound[i], out, r_lo, r_hi)
                    changed = True
            if not changed:
                break
        slowed = violated.copy()
    # the safe-braking check on the command's outcome (the kernel's text)
    plant = (q, qd, (lower, upper, speed, accel, limit_brake, tau), dt)
    closing = _outcome_reference((cm, radii, world), plant, (G, clear, active), (zone, stop, kappa), out)
    hold, keep = np.zeros(3, dtype=bool), np.zeros(3, dtype=bool)
    for i in np.flatnonzero(closing):
        least = float(_least(G[i] @ qd)[0])
        for j in range(3):
            now_j, cmd_j = G[i, j] * qd[j], G[i, j] * out[j]
            if now_j < -least and out[j] * qd[j] > 0.0:
                hold[j] = True
            elif now_j > least and out[j] * qd[j] < qd[j] * qd[j]:
                keep[j] = True  # one that opens the gap keeps its speed, unless it closes another
            elif -least <= now_j <= least and cmd_j < -least:
                hold[j] = True  # still, and the command would start it closing
            else:
                continue
            slowed[i] = active[i] = True
    out = np.where(hold, 0.0, np.where(keep, np.clip(qd, lo_v, hi_v), out))
    pick = active & (slowed if slowed.any() else True)
    if pick.any():
        left = np.where(pick, (val - stop) / (zone - stop), np.inf)
        i = int(np.argmin(left))
        report[:4] = kind[i], cap[i], clear[i], left[i]
    if not slowed.any():
        return x, (command, report)
    report[4] = 1.0
    return x, ((brake, q.copy(), out, True, scale), report)


def swing_hang_reference(frames, swing, v_arm) -> NDArray[np.float64]:
    """The reference of :func:`app.control.lab_kernels.swing_hang`: the wire, the centre from the tool point and
    the radius of the envelope that holds the load however the arm stops, in {r}, then the arm's ``v_arm``."""
    T_g_n1, R1, T_b1_r = frames
    alpha, beta, alpha_dot, beta_dot, L, g = swing
    v_arm = np.asarray(v_arm, dtype=float)
    known = math.isfinite(alpha + beta + alpha_dot + beta_dot + float(v_arm.sum()))
    if not known:  # anywhere within L of the tool point
        alpha = beta = alpha_dot = beta_dot = 0.0
    sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
    to_r = T_b1_r[:3, :3].T @ R1.T @ T_g_n1[:3, :3].T  # {g} axes into {r}
    w = to_r @ np.array([-sa, -ca * sb, -ca * cb])  # the wire's unit vector
    u = L * math.hypot(alpha_dot, ca * beta_dot)  # |L ẇ|: the load's speed relative to the tool point (⟂ w)
    tilt = 2.0 * (math.sin(0.5 * alpha) ** 2 + ca * math.sin(0.5 * beta) ** 2)  # 1 − cα cβ
    e = g * L * tilt + 0.5 * u * u  # the swing's own energy
    v = v_arm - (v_arm @ w) * w  # the arm's tool velocity normal to the wire
    e = 0.5 * (math.sqrt(2.0 * e) + float(np.linalg.norm(v))) ** 2  # however the arm stops
    eps = e / (g * L) if L > 0.0 else 0.0  # 1 − cos θ
    k = 1.0 - eps if known else -1.0
    depth, radius = (L * k, L * math.sqrt(max(0.0, eps * (2.0 - eps)))) if k > 0.0 else (0.0, L)
    return np.array([*(L * w), *(-depth * (to_r @ [0.0, 0.0, 1.0])), radius, *v_arm])


def guard_world_reference(guard_p, frames, e1, R1, e2, R2, swing, v_arm) -> tuple:
    """The reference of :func:`app.scenes.lab_kernels.guard_world`: EM1500's deck where the controller sees it,
    through {n1} (eq. 39) and EM8000's body (eq. 54 inverted), and the hanging load (:func:`swing_hang_reference`,
    with the arm's tool velocity ``v_arm`` in {r}) turned into {r} the same way."""
    _, deck1, ped, ped_r, deck_r, _ = guard_p
    T_g_n1, T12, Tr = frames
    c_n1 = T12[:3, 3] + T12[:3, :3] @ e2[:3]
    n_n1 = T12[:3, :3] @ (R2 @ np.array([0.0, 0.0, -1.0]))
    c = Tr[:3, :3].T @ (R1.T @ (c_n1 - e1[:3]) - Tr[:3, 3])
    n = Tr[:3, :3].T @ (R1.T @ n_n1)
    return deck1, ped, ped_r, np.array([*c, *n, deck_r[0]]), swing_hang_reference((T_g_n1, R1, Tr), swing, v_arm)


def _winch_guard_reference(x, u, p, dt):
    """The NumPy reference of :func:`app.control.lab_kernels.winch_guard`."""
    (ref, ref_v), (wl, wv), (q, va), world, frames, swing = u
    cm, radii, (_, _, w_speed, w_accel, w_tau), (zone, stop, kappa) = p
    report = np.array([-1.0, -1.0, math.nan, math.nan, 0.0])
    L = float(wl[0])
    v0 = float(np.clip((ref[0] - L) / max(w_tau, dt) + ref_v[0], -w_speed[0], w_speed[0]))
    if v0 == 0.0:
        return x, ((ref, ref_v), report)
    G, val, kind, cap = guard_hazards_reference(cm, radii, world, q)
    rows = range(len(val) - 4, len(val))  # the wire's and the load's
    if not any(val[i] < zone for i in rows):
        return x, ((ref, ref_v), report)
    alpha, beta, alpha_dot, beta_dot, g = swing
    longer = (alpha, beta, alpha_dot, beta_dot, L + lab_kernels.PAYOUT_STEP, g)
    hang = swing_hang_reference(frames, longer, world[4][7:10])  # the arm's tool velocity the world's
    val2 = guard_hazards_reference(cm, radii, (*world[:4], hang), q)[1]
    v, best, best_share = v0, -1, math.inf
    for i in rows:
        c = (val2[i] - val[i]) / lab_kernels.PAYOUT_STEP
        if c * v0 >= 0.0 or c == 0.0:
            continue
        A = kappa * float(w_accel[0]) * abs(c)
        own = c * float(wv[0])
        d = val[i] - (own * own / (2.0 * A) if own < 0.0 else 0.0)
        if d >= zone:
            continue
        ra = float(G[i] @ va)
        r0 = ra + c * v0
        room = max(d - stop, 0.0)
        share = min(max(room / (zone - stop), 0.0), 1.0)
        bound = -min(share * max(-r0, 0.0), min(room / (2.0 * dt), math.sqrt(2.0 * A * room)))
        if r0 >= bound - 1e-15:
            continue
        allowed = (bound - ra) / c
        allowed = max(0.0, min(v0, allowed)) if v0 > 0.0 else min(0.0, max(v0, allowed))
        v = allowed if abs(allowed) < abs(v) else v
        if (d - stop) / (zone - stop) < best_share:
            best, best_share = i, (d - stop) / (zone - stop)
    if best < 0:
        return x, ((ref, ref_v), report)
    report[:] = kind[best], cap[best], val[best], best_share, 1.0
    return x, ((np.array([L]), np.array([v])), report)


#: the winch's guard between its law and its drum: the pay-out slowed along the wire's and the load's approaches
WINCH_GUARD = Block(
    "winch guard (the wire and the load against EM8000 and the pedestal)",
    state=(),
    inputs=("wire_ref", "wire", "arm", "world", "frames", "swing"),
    outputs=("wire_ref", "report"),
    params=("cm", "radii", "drum", "settings"),
    reference=_winch_guard_reference,
    kernel=lab_kernels.winch_guard,
)


#: the Comau's guard between its law and its drives: the command slowed along the approaches to an obstacle
COMAU_GUARD = Block(
    "Comau guard (capsules against the platforms)",
    state=(),
    inputs=("command", "q", "q_dot", "world"),
    outputs=("command", "report"),
    params=("cm", "radii", "drives", "settings"),
    reference=_guard_reference,
    kernel=lab_kernels.comau_guard,
)


def _winch_reference(x, u, p, dt):
    """The NumPy reference of :func:`app.control.lab_kernels.winch_law`."""
    target, has_target = x
    track, speed_cmd, wl, (alpha, beta), (p_t_g, v_t_g), (H2, Rd2, eta_dot2) = u
    T_g_n2, w_speed = p
    if not track:
        v = float(np.clip(speed_cmd, -w_speed[0], w_speed[0]))
        return x, (wl + v * dt, np.array([v]))
    R2, o2 = H2[:3, :3], H2[:3, 3]
    if not has_target:  # keep the load where it is now, relative to EM1500 (eq. 58 for the load)
        sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
        p_p_g = p_t_g + np.diag([1.0, -1.0, -1.0]) @ (float(wl[0]) * np.array([-sa, ca * sb, ca * cb]))
        target, has_target = R2.T @ (p_p_g - o2), True
    s = float(np.clip(speed_cmd, -w_speed[0], w_speed[0]))  # paying out lowers the load relative to the deck
    target = target.copy()
    target[2] = target[2] + s * dt  # along {b2}'s z, which points down (the platforms' frames)
    target_g = R2 @ target + o2
    v_target_g = T_g_n2[:3, :3] @ (eta_dot2[:3] + Rd2 @ target) + s * R2[:, 2]
    # heights along gravity: the load hangs L_w below the tool (small swing)
    return (target, has_target), (np.array([p_t_g[2] - target_g[2]]), np.array([v_t_g[2] - v_target_g[2]]))


#: the winch's controller: active heave compensation relative to EM1500, or the operator's speed
WINCH_LAW = Block(
    "winch law (heave compensation)",
    state=("target_b2", "has_target"),
    inputs=("track", "speed_cmd", "L_w", "swing", "tool", "view2"),
    outputs=("L_ref", "L_dot_ref"),
    params=("T_g_n2", "speed"),
    reference=_winch_reference,
    kernel=lab_kernels.winch_law,
)
