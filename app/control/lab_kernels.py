"""Compiled controllers of the Motion-Lab: the Comau's modes (REMOTE, MOTION_COMP) and the winch's heave
compensation, as blocks (:mod:`app.models.block`).  Their NumPy references are :mod:`app.control.lab`, tested
equal in ``tests/test_blocks.py``; the scene wiring them to the plants is :mod:`app.scenes.lab_kernels`.

A controller sees the platforms through ``view`` = (η1, η̇1, R1, Ṙ1, η2, η̇2, R2, Ṙ2): EM8000's and EM1500's
poses, rates and body rotations (eqs. 33, 47) as measured (an MRU or a tracker) or true.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import _jit
from app.models.lab_kernels import comau_ik, comau_tool, lstsq3, mtv, mv

__all__ = ["comau_law", "winch_law"]

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


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) the laws as their blocks call them from Python (for
    :func:`app.warmup.warm_up`; the lab's step compiles them into its own code)."""
    z3, z6, o3, eye3, eye4 = np.zeros(3), np.zeros(6), np.ones(3), np.eye(3), np.eye(4)
    cm = np.array([0.35, 0.83, 1.16, 0.25, 2.269])  # any numbers compile; these are Tables 3/7 (L = 2.269 m)
    view = (z6, z6, eye3, eye3, z6, z6, eye3, eye3)
    law_p = (cm, eye4, np.array([1.0, -1.0]), eye4, eye4, o3, z3, -o3, o3)
    winch_u = (np.bool_(True), 0.0, np.ones(1), (0.0, 0.0), (z3, z3), (eye4, eye3, z6))
    return [
        lambda: comau_law((), (MOTION_COMP, z3, z3, (z3, z3, z3, z3), view), law_p, 0.01),
        lambda: winch_law((np.zeros(3), np.bool_(False)), winch_u, (eye4, np.ones(1)), 0.01),
    ]
