"""Compiled controllers of the Motion-Lab: the Comau's modes (REMOTE, MOTION_COMP) and the winch's heave
compensation, as blocks (:mod:`app.models.block`).  Their NumPy references are :mod:`app.control.lab`, tested
equal in ``tests/test_blocks.py``; the scene wiring them to the plants is :mod:`app.scenes.lab_kernels`.

A controller sees the platforms through ``view`` = (η1, η̇1, R1, Ṙ1, η2, η̇2, R2, Ṙ2): EM8000's and EM1500's
poses, rates and body rotations (eqs. 33, 47) as measured (an MRU or a tracker) or true.
"""

from __future__ import annotations

import math

import numpy as np

from app.control.lab_clearance_kernels import (  # noqa: F401 (the guard's geometry, named here as before)
    DECK1,
    DECK2,
    FAR,
    GOLDEN_STEPS,
    LOAD,
    PEDESTAL,
    ROWS,
    WIRE,
    WIRE_GOLDEN_STEPS,
    arm_points,
    guard_hazards,
    swing_hang,
)
from app.models.kernels import _jit
from app.models.lab_kernels import comau_ik, comau_tool, lstsq3, mtv, mv

__all__ = ["arm_points", "comau_guard", "comau_law", "guard_hazards", "swing_hang", "winch_guard", "winch_law"]

SETTLED, REMOTE, MOTION_COMP, BRAKE = 0, 1, 2, 3  # the Comau's modes in comau_law (HOLD and E-STOP brake alike)


@_jit
def comau_law(x, u, p, dt):
    """The Comau's joint command (:data:`app.control.lab.COMAU_LAW`); no state.

    Inputs (mode, q, v_cmd, offset, view): ``mode`` SETTLED (to the park configuration at a quarter speed),
    REMOTE (q̇ = J⁺ v_cmd, eq. 21, v_cmd the tool velocity in {r}), MOTION_COMP (the work point fixed in {b2},
    shifted by the operator's d (its rate ḋ) in {b2}, plus the anti-swing offset, through eqs. 54–56 inverted, IK
    of eqs. 7–20, feed-forward q̇ = J⁺ ṗ_t^r of eq. 21; ``offset`` = (p, ṗ in {n1}, d, ḋ in {b2})) or BRAKE;
    ``q`` the joints.  Parameters (cm, T_base, signs, T_n1_n2, T_b1_r,
    w_b2, park_q, lower, upper): the arm (a1, d1, a2, a3, L), its base, the IK's elbow branches, {n2} in
    {n1}, {r} in {b1}, the work point in {b2}, the park joints and the joint limits in force.

    y = (brake, q_ref, q̇_ref, use q̇_ref, speed scale): the command of the drives
    (:func:`app.sim.kernels.drives_block`)."""
    mode, q, v_cmd, offset, view = u
    cm, T_base, signs, T_n1_n2, T_b1_r, w_b2, park_q, q_lo, q_hi = p
    on, off = np.bool_(True), np.bool_(False)
    zero = np.zeros(3)
    if mode == BRAKE:
        return x, (on, q, q, off, 1.0)
    if mode == SETTLED:
        return x, (off, park_q, park_q, off, 0.25)
    if mode == REMOTE:
        J = comau_tool(cm, q, zero, zero)[3]
        rate = lstsq3(J, v_cmd)  # eq. (21)
        return x, (off, q + rate * dt, rate, on, 1.0)
    # MOTION_COMP: inverse kinematic control with feed-forward of both platforms, as the controller sees them
    cx1, cv1, cR1, cRd1, cx2, cv2, cR2, cRd2 = view
    off_p, off_v, d, dd = offset
    # the work point fixed in {b2} and shifted there by the operator (plus the offset), in {n1} (eq. 39 via {g})
    w0, w1, w2 = w_b2[0] + d[0], w_b2[1] + d[1], w_b2[2] + d[2]
    w = mv(cR2, w0, w1, w2)
    Rdw = mv(cRd2, w0, w1, w2)
    Rdd = mv(cR2, dd[0], dd[1], dd[2])
    pw = mv(T_n1_n2, cx2[0] + w[0], cx2[1] + w[1], cx2[2] + w[2])
    vw = mv(T_n1_n2, cv2[0] + Rdw[0] + Rdd[0], cv2[1] + Rdw[1] + Rdd[1], cv2[2] + Rdw[2] + Rdd[2])
    for i in range(3):
        pw[i] = T_n1_n2[i, 3] + pw[i] + off_p[i]
        vw[i] = vw[i] + off_v[i]
    # eqs. (54), (56) inverted for the tool point in {r}
    b = mtv(cR1, pw[0] - cx1[0], pw[1] - cx1[1], pw[2] - cx1[2])
    p_tr = mtv(T_b1_r, b[0] - T_b1_r[0, 3], b[1] - T_b1_r[1, 3], b[2] - T_b1_r[2, 3])
    arm = mv(T_b1_r, p_tr[0], p_tr[1], p_tr[2])
    for i in range(3):
        arm[i] = T_b1_r[i, 3] + arm[i]
    Rd_arm = mv(cRd1, arm[0], arm[1], arm[2])
    c = mtv(cR1, vw[0] - cv1[0] - Rd_arm[0], vw[1] - cv1[1] - Rd_arm[1], vw[2] - cv1[2] - Rd_arm[2])
    v_tr = mtv(T_b1_r, c[0], c[1], c[2])
    q_d, found = comau_ik(cm, T_base, p_tr, q, signs, q_lo, q_hi)
    if not found:  # out of reach: hold, limits intact
        q_d = q.copy()
    J = comau_tool(cm, q_d, zero, zero)[3]
    rate = lstsq3(J, v_tr)  # eq. (21)
    return x, (off, q_d, rate, on, 1.0)


@_jit
def winch_law(x, u, p, dt):
    """The winch's length reference (:data:`app.control.lab.WINCH_LAW`): active heave compensation or the
    operator's speed.

    State (target, has_target): the load's height target, a point fixed in {b2} (captured where the load is
    when tracking starts), in place.  Inputs (track, speed_cmd, L_w, swing, tool, view2): ``track`` keeps the
    load's height relative to EM1500 at the target (heights along gravity, the load L_w below the tool: small
    swing), the speed command [m/s] lowering the target along {b2}'s z, down (winch REMOTE under VVMC), else
    the speed command pays out; L_w (1,) the wire; swing (α, β); tool (p_t^g, ṗ_t^g) (eqs. 55–56);
    view2 (H^g_b2, Ṙ2, η̇2) of EM1500 as the controller sees it (eq. 39).  Parameters (T_g_n2, speed (1,)).
    y = (L_ref, L̇_ref), (1,) each: the drum's reference."""
    target, has_target = x
    track, speed_cmd, wl, swing, tool, view2 = u
    T_g_n2, w_speed = p
    cH2, cRd2, cv2 = view2
    p_t_g, v_t_g = tool
    ref, ref_v = np.empty(1), np.empty(1)
    if track:
        if not has_target:  # keep the load where it is now, relative to EM1500
            alpha, beta = swing
            sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
            L0 = wl[0]
            pp0 = p_t_g[0] + L0 * -sa - cH2[0, 3]
            pp1 = p_t_g[1] - L0 * (ca * sb) - cH2[1, 3]
            pp2 = p_t_g[2] - L0 * (ca * cb) - cH2[2, 3]
            t = mtv(cH2, pp0, pp1, pp2)
            for i in range(3):
                target[i] = t[i]
            has_target = True
        s = min(max(speed_cmd, -w_speed[0]), w_speed[0])  # paying out lowers the load relative to the deck:
        target[2] = target[2] + s * dt  # along {b2}'s z, which points down (the platforms' frames)
        tg = mv(cH2, target[0], target[1], target[2])
        Rdt = mv(cRd2, target[0], target[1], target[2])
        vtg = mv(T_g_n2, cv2[0] + Rdt[0], cv2[1] + Rdt[1], cv2[2] + Rdt[2])
        for i in range(3):
            vtg[i] = vtg[i] + s * cH2[i, 2]
        ref[0] = p_t_g[2] - (tg[2] + cH2[2, 3])
        ref_v[0] = v_t_g[2] - vtg[2]
    else:
        s = min(max(speed_cmd, -w_speed[0]), w_speed[0])
        ref[0] = wl[0] + s * dt
        ref_v[0] = s
    return (target, has_target), (ref, ref_v)


# ---------------------------------------------------------------------------------------------- the Comau's guard
CONTRIBUTES = 1e-6  # [m/s]: the least part of a clearance's rate a joint must carry to count as closing or opening it
BRAKE_SLACK = 0.002  # [m]: how far below the stop distance the check lets braking end before it brakes (at the stop,
#: an opening command's first step may still close by a fraction of a millimetre: that is not worth braking it for)
ROLLOUT = 400  # steps: the longest the check follows the drives to the command (2 s at the lab's 5 ms)
RESAMPLE = 20  # steps: the check takes the clearance anew where the arm has got to (0.1 s; first order between,
#: and anew wherever the first order passes below the floor: a dip the first order makes up is not held for)
CONTRIBUTES_SHARE = 0.05  # … and the least share of the rate (a joint that barely moves a gap is not braked for it)


@_jit
def _correct(g, bound, out, lo_v, hi_v):
    """``out`` moved along ``g`` until g·out reaches ``bound``, each joint within [lo_v, hi_v]: a joint that reaches
    its bound keeps it and the rest of the correction goes to the others (an active set; none left: as far as they
    went)."""
    free = np.ones(3, np.bool_)
    for _ in range(3):
        r = g[0] * out[0] + g[1] * out[1] + g[2] * out[2]
        gg = 0.0
        for j in range(3):
            if free[j]:
                gg += g[j] * g[j]
        if r >= bound - 1e-15 or gg <= 1e-24:
            return
        c = (bound - r) / gg
        clamped = False
        for j in range(3):
            if not free[j]:
                continue
            t = out[j] + c * g[j]
            if t > hi_v[j]:
                out[j], free[j], clamped = hi_v[j], False, True
            elif t < lo_v[j]:
                out[j], free[j], clamped = lo_v[j], False, True
            else:
                out[j] = t
        if not clamped:
            return


@_jit
def _outcome(model, plant, rows, settings, out, closing):
    """Step 3 of :func:`comau_guard`: ``closing[i]`` for each hazard in its zone where the drives, following the
    rate ``out`` until they have it and as long again as they would take to stop from it, pass below the stop
    distance (:data:`BRAKE_SLACK` under it, and under the clearance now) or are left closing faster than they could
    then brake short of it.  model (cm, radii, world); plant (q, q̇, drives, dt); rows (G, clearances now, in the
    zone, how many); settings (zone, stop, κ)."""
    cm, radii, world = model
    q, qd, drives, dt = plant
    G, clear, active, m = rows
    lower, upper, _, accel, limit_brake, _ = drives
    stop, kappa = settings[1], settings[2]
    steps = 0  # until the drives have the command, and long enough after to have stopped from it (κ)
    for j in range(3):
        reach = abs(out[j] - qd[j]) / (accel[j] * dt)
        steps = max(steps, int(math.ceil(reach + abs(out[j]) / (kappa * accel[j] * dt) - 1e-9)))  # noqa: RUF046
    steps = min(steps, ROLLOUT)
    any_active = False
    for i in range(m):
        any_active = any_active or active[i]
    if not any_active:
        return
    v = qd.copy()  # one path of the drives for every hazard in its zone: what differs is each one's clearance
    qr = q.copy()
    g = G.copy()
    d = clear.copy()
    lowest = clear.copy()
    kt = np.empty(ROWS, np.int64)
    ct = np.empty(ROWS, np.int64)
    g2, d2 = np.empty((ROWS, 3)), np.empty(ROWS)
    floor = np.empty(ROWS)  # what a clearance must not pass below: the stop distance (less the slack) and where it is
    for i in range(m):
        floor[i] = min(stop - BRAKE_SLACK, clear[i])
    for k in range(steps):
        for j in range(3):  # the drives: toward the command at the acceleration limit, braking at the joint limits
            vj = v[j] + min(max(out[j] - v[j], -accel[j] * dt), accel[j] * dt)
            up = math.sqrt(2.0 * limit_brake[j] * max(upper[j] - qr[j], 0.0))
            down = math.sqrt(2.0 * limit_brake[j] * max(qr[j] - lower[j], 0.0))
            v[j] = min(max(vj, -down), up)
            qr[j] += v[j] * dt
        if k % RESAMPLE == RESAMPLE - 1:  # the clearances and their gradients where the arm has got to
            guard_hazards(cm, radii, world, qr, g, d, kt, ct)
        else:
            dips = False
            for i in range(m):
                if active[i]:
                    d[i] += (g[i, 0] * v[0] + g[i, 1] * v[1] + g[i, 2] * v[2]) * dt
                    dips = dips or (d[i] < floor[i] <= lowest[i])
            if dips:  # the first order has a clearance pass its floor here: that one taken anew where the arm is
                guard_hazards(cm, radii, world, qr, g2, d2, kt, ct)
                for i in range(m):
                    if active[i] and d[i] < floor[i] <= lowest[i]:
                        d[i] = d2[i]
                        g[i, 0], g[i, 1], g[i, 2] = g2[i, 0], g2[i, 1], g2[i, 2]
        done = True
        for i in range(m):
            lowest[i] = min(lowest[i], d[i])
            done = done and (not active[i] or lowest[i] < floor[i])
        if done:
            break  # every clearance in its zone has passed its floor: the rest of the path changes nothing
    for i in range(m):
        if not active[i]:
            continue  # outside its zone, braking from its approach included
        now = g[i, 0] * v[0] + g[i, 1] * v[1] + g[i, 2] * v[2]
        low = lowest[i]
        if now < 0.0:
            Am = 0.0
            least = max(CONTRIBUTES, CONTRIBUTES_SHARE * -now)
            for j in range(3):
                if g[i, j] * v[j] < -least:
                    Am += kappa * abs(g[i, j]) * accel[j]
            low = min(low, d[i] - now * now / (2.0 * Am)) if Am > 0.0 else -math.inf
        closing[i] = low < floor[i]


@_jit
def comau_guard(x, u, p, dt):
    """The Comau's joint command scaled along the directions that bring it nearer an obstacle (issue 32, item 5:
    :mod:`app.control.guard`'s velocity damper, Faverjon & Tournassoud 1987; Kanoun, Lamiraux & Wieber 2011 eq. 10,
    with the braking bound of Flacco, De Luca & Khatib 2015 eq. 13 that the lab's own program puts on its joint
    limits); no state.

    Inputs (command, q, q̇, world): the law's command (brake, q_ref, q̇_ref, use q̇_ref, speed scale), the joints and
    their rates, the obstacles in {r} (:func:`guard_hazards`).  Parameters (cm, radii, drives (lower, upper, speed,
    accel, the limits' braking b, τ: the drives' own), settings (zone, stop, braking share κ)).  The drives would
    move at v = (q_ref − q)/τ (+ q̇_ref), within speed × scale and the braking to each joint's limit
    (:func:`app.sim.kernels.motion_filter_update`): the rate judged and corrected is that one (a joint at its
    limit does not move, whatever the command asks of it).

    1. Each clearance d is first taken as what braking from the arm's own approach g·q̇ < 0 would leave,
       d − (g·q̇)²/(2A'), A' = κ Σ |g_j| a_j over the joints that close it (each braking at its limit a_j, κ a
       margin; a joint that opens it but reaches its own limit before those could stop is left out of g·q̇): an
       arm already closing fast is slowed sooner.
    2. For each hazard in its zone (d < zone) whose rate g·v is an approach (< 0) the rate is bounded by

           g·v ≥ −min(s |g·v⁰|, (d − stop)/(2 dt), √(2 A (d − stop))),   s = (d − stop)/(zone − stop),

       A = κ a_min |g| (the approach's deceleration when the joints change along g, as the correction does).  A
       command that breaks a bound is corrected along g only, as the next step's speeds: each joint within what the
       drives reach in one step (a_j dt of its speed now) and within its limit's braking (√(2 b (q_max − q)),
       Flacco et al. eq. 13: a joint at its limit cannot open a gap), the part a joint cannot take going to the
       others (:func:`_correct`), a few passes over the hazards; where those speeds cannot meet a bound, as near
       as they allow (the drives' hardest braking along g).
    3. The command's outcome is checked, each clearance in its zone (to first order, taken anew every
       :data:`RESAMPLE` steps where the arm has got to, and wherever the first order has it pass below what it
       must not: only the true clearance there counts), until the drives have the command and as long again as
       they would take to stop from it: where the drives, following
       the rate until they have it (each joint's speed changing by a_j dt a step, braking to its limit as the
       drives' velocity bound does: a joint that opens a gap stops at its limit), would pass below the stop
       distance (:data:`BRAKE_SLACK` under it), or leave the arm closing faster than it could then brake short of
       it (with A'), the joints that close that gap are commanded to rest (the drives brake them at their limits;
       a joint the command already turns back keeps its command), a joint at rest that the command would start
       closing it stays, and the joints that open it keep their speed, as A' assumes (slowing them would close it
       too) — unless they close another gap the check acts for: then they rest (a joint opening a swinging load's
       envelope must not carry the arm into the deck).

    A rate that opens every hazard, with the arm not closing on one too fast, or a BRAKE is returned as it came,
    bit for bit; a slowed one as a pure rate (q_ref = q, q̇_ref = v).

    y = (command, report (5,): of the hazards that slowed it (else of all in their zones) the one with the least of
    its zone left — obstacle (−1: none in its zone), capsule, its clearance as it is [m], share of its zone left
    (of the braking-adjusted clearance), slowed (1.0))."""
    command, q, qd, world = u
    cm, radii, drives, settings = p
    brake, q_ref, v_ref, use_v, scale = command
    lower, upper, speed, accel, limit_brake, tau = drives
    zone, stop, kappa = settings[0], settings[1], settings[2]
    report = np.empty(5)
    report[0], report[1], report[2], report[3], report[4] = -1.0, -1.0, math.nan, math.nan, 0.0
    if brake:
        return x, (command, report)
    G = np.zeros((ROWS, 3))
    val = np.zeros(ROWS)
    kind = np.zeros(ROWS, np.int64)
    cap = np.zeros(ROWS, np.int64)
    m = guard_hazards(cm, radii, world, q, G, val, kind, cap)
    clear = val.copy()
    v0 = np.empty(3)
    t = max(tau, dt)
    a_min = min(accel[0], min(accel[1], accel[2]))
    hi_v, lo_v = np.empty(3), np.empty(3)  # the speeds the drives allow, up and down (near a limit, its braking)
    for j in range(3):
        lim = speed[j] * scale
        up, down = max(upper[j] - q[j], 0.0), max(q[j] - lower[j], 0.0)
        hi_v[j] = min(lim, min(math.sqrt(2.0 * limit_brake[j] * up), up / dt))
        lo_v[j] = -min(lim, min(math.sqrt(2.0 * limit_brake[j] * down), down / dt))
        v = (q_ref[j] - q[j]) / t + (v_ref[j] if use_v else 0.0)
        v0[j] = min(max(v, lo_v[j]), hi_v[j])  # what the drives can do: a joint at its limit stays there
    active = np.zeros(ROWS, np.bool_)
    bound = np.zeros(ROWS)
    slowed = np.zeros(ROWS, np.bool_)  # the command closed on it too fast, or the braking check acted for it
    closing = np.zeros(ROWS, np.bool_)
    for i in range(m):
        gg = G[i, 0] * G[i, 0] + G[i, 1] * G[i, 1] + G[i, 2] * G[i, 2]
        A = kappa * a_min * math.sqrt(gg)  # the approach's deceleration when the joints change along g, a margin
        # the arm's own approach (its momentum), less what a joint opening it gives if that joint reaches its limit
        # before the joints closing it could stop
        T = 0.0
        for j in range(3):
            if G[i, j] * qd[j] < 0.0:
                T = max(T, abs(qd[j]) / accel[j])
        now = 0.0
        for j in range(3):
            c = G[i, j] * qd[j]
            if c > 0.0 and (upper[j] - q[j] if qd[j] > 0.0 else q[j] - lower[j]) < abs(qd[j]) * T:
                c = 0.0
            now += c
        if now < 0.0:
            Am = 0.0  # braking the joints that close it, each at its limit, with the margin
            least = max(CONTRIBUTES, CONTRIBUTES_SHARE * -now)
            for j in range(3):
                if G[i, j] * qd[j] < -least:
                    Am += kappa * abs(G[i, j]) * accel[j]
            if Am > 0.0:
                val[i] -= now * now / (2.0 * Am)  # what braking from it now would leave
        if val[i] >= zone:
            continue
        active[i] = True
        r0 = G[i, 0] * v0[0] + G[i, 1] * v0[1] + G[i, 2] * v0[2]
        room = max(val[i] - stop, 0.0)
        if gg <= 1e-24:
            bound[i] = -math.inf  # no gradient (a distance no joint changes): nothing to scale
        elif r0 < 0.0:
            s = min(max(room / (zone - stop), 0.0), 1.0)
            bound[i] = -min(s * -r0, min(room / (2.0 * dt), math.sqrt(2.0 * A * room)))
        else:
            bound[i] = 0.0  # not approaching: never slowed, and no correction may turn it into an approach
        slowed[i] = r0 < bound[i] - 1e-15
    out = v0.copy()
    violated = False
    for i in range(m):
        violated = violated or slowed[i]
    if violated:
        # the correction plans the next step's speeds: each joint within a_j dt of its speed now (what the drives
        # reach in one step) and within its limits' reach; the bounds met there, or as near as those allow
        r_lo, r_hi = np.empty(3), np.empty(3)
        for j in range(3):
            r_hi[j] = max(min(hi_v[j], qd[j] + accel[j] * dt), lo_v[j])
            r_lo[j] = min(max(lo_v[j], qd[j] - accel[j] * dt), r_hi[j])
            out[j] = min(max(v0[j], r_lo[j]), r_hi[j])
        for _ in range(4):
            changed = False
            for i in range(m):
                if not active[i] or bound[i] == -math.inf:
                    continue
                r = G[i, 0] * out[0] + G[i, 1] * out[1] + G[i, 2] * out[2]
                if r < bound[i] - 1e-15:
                    _correct(G[i], bound[i], out, r_lo, r_hi)
                    changed = True
            if not changed:
                break
    # 3. the safe-braking check on the command's outcome (the text's third step)
    rows = (G, clear, active, m)
    plant = (q, qd, drives, dt)
    _outcome((cm, radii, world), plant, rows, settings, out, closing)
    hold = np.zeros(3, np.bool_)  # a joint that closes a gap the check acts for: to rest
    keep = np.zeros(3, np.bool_)  # one that opens one: keeps its speed, unless it closes another
    for i in range(m):
        if not closing[i]:
            continue
        least = max(CONTRIBUTES, CONTRIBUTES_SHARE * abs(G[i, 0] * qd[0] + G[i, 1] * qd[1] + G[i, 2] * qd[2]))
        for j in range(3):
            now_j, cmd_j = G[i, j] * qd[j], G[i, j] * out[j]
            if now_j < -least:  # closing it: to rest, unless the command already turns it back
                if out[j] * qd[j] <= 0.0:
                    continue
                hold[j] = True
            elif now_j > least:  # opening it: keeps its speed (to its limit)
                if out[j] * qd[j] >= qd[j] * qd[j]:
                    continue
                keep[j] = True
            elif cmd_j < -least:  # still, and the command would start it closing: it stays
                hold[j] = True
            else:
                continue
            slowed[i] = True
            active[i] = True
    for j in range(3):
        if hold[j]:
            out[j] = 0.0
        elif keep[j]:
            out[j] = min(max(qd[j], lo_v[j]), hi_v[j])
    any_slowed = False
    for i in range(m):
        any_slowed = any_slowed or slowed[i]
    best, best_share = -1, math.inf
    for i in range(m):
        if not active[i] or (any_slowed and not slowed[i]):
            continue
        share = (val[i] - stop) / (zone - stop)
        if share < best_share:
            best, best_share = i, share
    if best >= 0:
        report[0], report[1], report[2], report[3] = float(kind[best]), float(cap[best]), clear[best], best_share
    if not any_slowed:
        return x, (command, report)
    report[4] = 1.0
    return x, ((brake, q.copy(), out, np.bool_(True), scale), report)


#: [m]: the step of the wire's length over which the winch's guard takes each clearance's change with it
PAYOUT_STEP = 1e-4


@_jit
def winch_guard(x, u, p, dt):
    """The winch's pay-out slowed along the approaches of the wire and the load to an obstacle (issue 32, item 5):
    a velocity damper in one dimension, the wire's length, beside :func:`comau_guard`'s in the joints; no state.

    Inputs (wire_ref (L_ref, L̇_ref) of :func:`winch_law`, wire (L, L̇), arm (q, q̇: the joints after their drives'
    step), world (:func:`guard_hazards`'), frames and swing of :func:`swing_hang` (α, β, α̇, β̇, g: the length is
    the wire's, the arm's tool velocity the world's)).  Parameters (cm, radii, the drum's (lower, upper, speed,
    accel, τ), settings (zone, stop, κ)).  The drum would pay out at v = (L_ref − L)/τ + L̇_ref (within its speed).

    For the wire's and the load's rows in their zone, with c = ∂d/∂L (over :data:`PAYOUT_STEP` of wire: the wire
    end and the swing's envelope follow it) and the arm's rate r_a = g·q̇ (as its guard left it): where the
    pay-out closes the clearance (c v < 0), the total rate r = r_a + c v is bounded as the arm's guard bounds its
    own, r ≥ −min(s |r⁰|, (d − stop)/(2 dt), √(2 A (d − stop))), A = κ a_w |c| (the drum's braking along it), d
    taken less what braking the drum's own approach now would leave; the pay-out alone gives way, down to rest —
    never reversed (nothing moves that the operator did not ask for).  A pay-out that opens every such clearance
    or is not in a zone is returned as it came, bit for bit; a slowed one as a pure rate (L_ref = L, L̇_ref = v).

    y = (wire_ref, report (5,): as :func:`comau_guard`'s, of the row that slowed it most)."""
    (ref, ref_v), (wl, wv), (q, va), world, frames, swing = u
    cm, radii, drum, settings = p
    report = np.empty(5)
    report[0], report[1], report[2], report[3], report[4] = -1.0, -1.0, math.nan, math.nan, 0.0
    _, _, w_speed, w_accel, w_tau = drum
    zone, stop, kappa = settings[0], settings[1], settings[2]
    L = wl[0]
    v0 = min(max((ref[0] - L) / max(w_tau, dt) + ref_v[0], -w_speed[0]), w_speed[0])
    if v0 == 0.0:
        return x, ((ref, ref_v), report)
    G = np.zeros((ROWS, 3))
    val = np.zeros(ROWS)
    kind = np.zeros(ROWS, np.int64)
    cap = np.zeros(ROWS, np.int64)
    m = guard_hazards(cm, radii, world, q, G, val, kind, cap)
    first = m - 4  # the wire's and the load's rows
    near = False
    for i in range(first, m):
        near = near or val[i] < zone
    if not near:
        return x, ((ref, ref_v), report)
    alpha, beta, alpha_dot, beta_dot, g = swing
    longer = (world[0], world[1], world[2], world[3],
              swing_hang(frames, (alpha, beta, alpha_dot, beta_dot, L + PAYOUT_STEP, g), world[4][7:10]))  # fmt: skip
    G2 = np.zeros((ROWS, 3))
    val2 = np.zeros(ROWS)
    guard_hazards(cm, radii, longer, q, G2, val2, kind, cap)
    v = v0
    best, best_share = -1, math.inf
    for i in range(first, m):
        c = (val2[i] - val[i]) / PAYOUT_STEP
        if c * v0 >= 0.0 or c == 0.0:
            continue  # the pay-out does not close it
        d = val[i]
        own = c * wv[0]
        A = kappa * w_accel[0] * abs(c)
        if own < 0.0:
            d -= own * own / (2.0 * A)  # what braking the drum's own approach now would leave
        if d >= zone:
            continue
        ra = G[i, 0] * va[0] + G[i, 1] * va[1] + G[i, 2] * va[2]
        r0 = ra + c * v0
        room = max(d - stop, 0.0)
        share = min(max(room / (zone - stop), 0.0), 1.0)
        bound = -min(share * max(-r0, 0.0), min(room / (2.0 * dt), math.sqrt(2.0 * A * room)))
        if r0 >= bound - 1e-15:
            continue
        allowed = (bound - ra) / c  # the pay-out that meets the bound with the arm as it is
        allowed = max(0.0, min(v0, allowed)) if v0 > 0.0 else min(0.0, max(v0, allowed))
        if abs(allowed) < abs(v):
            v = allowed
        left = (d - stop) / (zone - stop)
        if left < best_share:
            best, best_share = i, left
    if best < 0:
        return x, ((ref, ref_v), report)
    report[0], report[1], report[2], report[3] = float(kind[best]), float(cap[best]), val[best], best_share
    report[4] = 1.0
    out_ref, out_v = np.empty(1), np.empty(1)
    out_ref[0], out_v[0] = L, v
    return x, ((out_ref, out_v), report)


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) the laws as their blocks call them from Python (for
    :func:`app.warmup.warm_up`; the lab's step compiles them into its own code)."""
    z3, z6, o3, eye3, eye4 = np.zeros(3), np.zeros(6), np.ones(3), np.eye(3), np.eye(4)
    cm = np.array([0.35, 0.83, 1.16, 0.25, 2.269])  # any numbers compile; these are Tables 3/7 (L = 2.269 m)
    view = (z6, z6, eye3, eye3, z6, z6, eye3, eye3)
    law_p = (cm, eye4, np.array([1.0, -1.0]), eye4, eye4, o3, z3, -o3, o3)
    winch_u = (np.bool_(True), 0.0, np.ones(1), (0.0, 0.0), (z3, z3), (eye4, eye3, z6))
    deck1 = np.array([0.0, 0.0, 1.0, -1.0, 0.0, 0.0, -1.0, 2.0])
    world = (deck1, np.zeros((2, 3)), np.ones(1), np.array([2.0, 0, 0, 0, 0, 1, 0.8]), np.array([0.0, 0.0, -1.0]))
    command = (np.bool_(False), z3, z3, np.bool_(True), 1.0)
    guard_p = (cm, np.ones(5), (-o3, o3, o3, o3, o3, 0.05), np.array([0.15, 0.02, 0.5]))
    one = np.ones(1)
    drum = (one * 0.3, one * 4.0, one, one, 0.05)
    winch_guard_u = ((one, one), (one, one), (z3, z3), world, (eye4, eye3, eye4), (0.0, 0.0, 0.0, 0.0, 9.81))
    return [
        lambda: comau_law((), (MOTION_COMP, z3, z3, (z3, z3, z3, z3), view), law_p, 0.01),
        lambda: comau_guard((), (command, z3, z3, world), guard_p, 0.01),
        lambda: winch_guard((), winch_guard_u, (cm, np.ones(5), drum, np.array([0.15, 0.02, 0.5])), 0.01),
        lambda: winch_law((np.zeros(3), np.bool_(False)), winch_u, (eye4, np.ones(1)), 0.01),
    ]
