"""The Motion-Lab's diagram (:data:`app.scenes.lab.LAB_DIAGRAM`) compiled as one step.

:func:`lab_step` does what :meth:`app.scenes.lab.MotionLab.step` does after the platforms, calling the blocks
in the diagram's order: the platforms' body rates (eqs. 33, 47, 51) as true and as the controllers see them
(the sensor), the Comau's law (:func:`app.control.lab_kernels.comau_law`), its guard
(:func:`app.control.lab_kernels.comau_guard`: the obstacles from :func:`guard_world`) and drives
(:func:`app.sim.kernels.drives_block`), the tool point (eqs. 54–57), the winch's law
(:func:`app.control.lab_kernels.winch_law`) and drum (:func:`app.sim.kernels.drum_block`), the load
(:func:`app.models.pendulum_kernels.pendulum_step`) and the sample.  The reference is the same diagram run block
by block in NumPy (``MotionLab(use_kernels=False)``), tested equal in ``tests/test_sim_kernels.py``.

Records (every array C-contiguous float64, bool for ``at_limit``; updated in place where marked):

* ``x`` = (joints, wire, load, target): joints (q, q̇, q̈) and wire (L_w, L̇_w, L̈_w) in place; load (α, β, α̇, β̇);
  target (the load's height target in {b2} (3,) in place, whether it is set);
* ``u`` = (true, seen, command): true (η1, η̇1, η̈1, η2, η̇2, η̈2) of EM8000 and EM1500; seen (measured, η1, η̇1,
  η̈1, η2, η̇2, η̈2) as the sensors report them, used by the controllers when ``measured``; command (Comau mode
  of :mod:`app.control.lab_kernels`, tool velocity in {r}, offset (p, ṗ in {n1}, the operator's shift d, ḋ of the
  work point in {b2}), winch tracks, winch speed);
* ``p`` = (geometry, joints, wire, load, guard): geometry (cm, T_base, signs, T_g_n1, T_g_n2, T_n1_n2, T_b1_r,
  w_b2, park_q, a_n1, b_b1, a_n2, b_b2); the drives' (lower, upper, speed, accel, brake, τ); the drum's (lower,
  upper, speed, accel, τ); the load's (c, g); the Comau's guard (its capsules' radii (3,), EM8000's deck (4,),
  the pedestal (2, 3) and its radius (1,), EM1500's deck radius (1,), settings (zone, stop, braking share)):
  :class:`app.control.lab.ComauGuard`;
* ``y`` (written): (rates (2, 3, 3, 3): R, Ṙ, R̈ of both bodies; p_t^n1, p_t^g, ṗ_t^g, p̈_t^g; at_limit (4,);
  e_b2 (tool minus work point in {b2}); the work point and the load (eq. 58) in {g}; both platforms' legs; the
  guard's report (5,) of :func:`app.control.lab_kernels.comau_guard`).

Returns (has_target, α, β, α̇, β̇, payload height error).
"""

from __future__ import annotations

import math

import numpy as np

from app.control.lab_kernels import comau_guard, comau_law, swing_hang, winch_guard, winch_law
from app.models.kernels import _jit
from app.models.lab_kernels import comau_tool, leg_lengths, mtv, mv, pose_in, stewart_rates, tool_on_platform
from app.sim.kernels import drives_block, drum_block, pendulum_step

__all__ = ["guard_world", "lab_step", "warm_up_steps"]


@_jit
def guard_world(guard_p, frames, cx1, cR1, cx2, cR2, swing, v_arm):
    """The Comau's obstacles in its base {r} (:func:`app.control.lab_kernels.guard_hazards`): EM8000's deck and the
    pedestal, fixed there, and EM1500's deck (z = 0 of {b2}, up = −z, a disc) where the controller sees it (eq. 39
    through {n1}, eq. 54 inverted); and the wire from the tool point to the load, eq. (58)'s L·(−sα, −cα sβ,
    −cα cβ) in {g}, and the load's swing envelope (its centre from the tool point, its radius: module text of
    :func:`app.control.lab_kernels.guard_hazards`), turned into {r} the same way.  ``frames`` = (T_g_n1, T_n1_n2,
    T_b1_r); ``swing`` = (α, β, α̇, β̇, L, g); ``v_arm`` the tool point's velocity from the arm's joints in {r}
    (the envelope holds the load however the arm stops: :func:`app.control.lab_kernels.swing_hang`)."""
    T_g_n1, T_n1_n2, T_b1_r = frames
    _, deck1, ped, ped_r, deck_r, _ = guard_p
    deck2 = np.empty(7)
    cn = mv(T_n1_n2, cx2[0], cx2[1], cx2[2])
    nz = mv(cR2, 0.0, 0.0, -1.0)
    nn = mv(T_n1_n2, nz[0], nz[1], nz[2])
    b = mtv(cR1, T_n1_n2[0, 3] + cn[0] - cx1[0], T_n1_n2[1, 3] + cn[1] - cx1[1], T_n1_n2[2, 3] + cn[2] - cx1[2])
    cr = mtv(T_b1_r, b[0] - T_b1_r[0, 3], b[1] - T_b1_r[1, 3], b[2] - T_b1_r[2, 3])
    nb = mtv(cR1, nn[0], nn[1], nn[2])
    nr = mtv(T_b1_r, nb[0], nb[1], nb[2])
    for i in range(3):
        deck2[i], deck2[3 + i] = cr[i], nr[i]
    deck2[6] = deck_r[0]
    return (deck1, ped, ped_r, deck2, swing_hang((T_g_n1, cR1, T_b1_r), swing, v_arm))


@_jit
def lab_step(x, u, p, y, dt):
    """One Motion-Lab step after the platforms (see the module text for the records)."""
    joints, wire, load, (target, has_target) = x
    (x1, v1, a1, x2, v2, a2), seen, command = u
    geometry, joint_p, wire_p, (damping, g), guard_p = p
    rates, p_t_n1, p_t_g, v_t_g, a_t_g, at_limit, e_b2, p_w_g, p_p_g, legs1, legs2, hazard = y
    cm, T_base, signs, T_g_n1, T_g_n2, T_n1_n2, T_b1_r, w_b2, park_q, a_n1, b_b1, a_n2, b_b2 = geometry
    comau_mode, v_cmd, offset, track, speed_cmd = command
    measured, cx1, cv1, ca1, cx2, cv2, ca2 = seen
    # ---- the platforms' body rates (eqs. 33, 45, 47, 50, 51), true and as the controllers see them
    R1, Rd1, Rdd1 = stewart_rates(x1, v1, a1)
    R2b, Rd2, Rdd2 = stewart_rates(x2, v2, a2)
    for i in range(3):
        for j in range(3):
            rates[0, 0, i, j], rates[0, 1, i, j], rates[0, 2, i, j] = R1[i, j], Rd1[i, j], Rdd1[i, j]
            rates[1, 0, i, j], rates[1, 1, i, j], rates[1, 2, i, j] = R2b[i, j], Rd2[i, j], Rdd2[i, j]
    if measured:
        cR1, cRd1, _ = stewart_rates(cx1, cv1, ca1)
        cR2, cRd2, _ = stewart_rates(cx2, cv2, ca2)
    else:
        cx1, cv1, cx2, cv2 = x1, v1, x2, v2
        cR1, cRd1, cR2, cRd2 = R1, Rd1, R2b, Rd2
    # ---- the Comau: its law, then its drives
    q, qd, qdd = joints
    law_p = (cm, T_base, signs, T_n1_n2, T_b1_r, w_b2, park_q, joint_p[0], joint_p[1])
    view = (cx1, cv1, cR1, cRd1, cx2, cv2, cR2, cRd2)
    _, joint_cmd = comau_law((), (comau_mode, q, v_cmd, offset, view), law_p, dt)
    swing = (load[0], load[1], load[2], load[3], wire[0][0], g)
    v_arm = comau_tool(cm, q, qd, qdd)[1]  # the tool point's velocity from the joints in {r} (eq. 5)
    world = guard_world(guard_p, (T_g_n1, T_n1_n2, T_b1_r), cx1, cR1, cx2, cR2, swing, v_arm)
    _, (joint_cmd, report) = comau_guard((), (joint_cmd, q, qd, world), (cm, guard_p[0], joint_p, guard_p[5]), dt)
    for i in range(5):
        hazard[i] = report[i]
    drives_block((q, qd, qdd, at_limit), joint_cmd, joint_p, dt)
    # ---- the tool point (eqs. 54–57)
    pt, vt, at = tool_on_platform(cm, T_b1_r, (x1, v1, a1), (R1, Rd1, Rdd1), joints)
    pg, vg, ag = mv(T_g_n1, pt[0], pt[1], pt[2]), mv(T_g_n1, vt[0], vt[1], vt[2]), mv(T_g_n1, at[0], at[1], at[2])
    for i in range(3):
        p_t_n1[i] = pt[i]
        p_t_g[i] = pg[i] + T_g_n1[i, 3]  # eq. (55)
        v_t_g[i] = vg[i]
        a_t_g[i] = ag[i]
    # ---- the winch: its law (heave compensation sees EM1500 as measured), then its drum
    wl, wv, wa = wire
    alpha, beta, alpha_dot, beta_dot = load
    H2 = pose_in(T_g_n2, x2)  # H^g_b2, eq. (39)
    cH2 = pose_in(T_g_n2, cx2) if measured else H2
    winch_u = (track, speed_cmd, wl, (alpha, beta), (p_t_g, v_t_g), (cH2, cRd2, cv2))
    (target, has_target), wire_ref = winch_law((target, has_target), winch_u, (T_g_n2, wire_p[2]), dt)
    # ---- the winch's guard: its pay-out slowed along the approaches of the wire and the load
    guard_u = (wire_ref, (wl, wv), (q, qd), world, (T_g_n1, cR1, T_b1_r), (alpha, beta, alpha_dot, beta_dot, g))
    _, (wire_ref, wreport) = winch_guard((), guard_u, (cm, guard_p[0], wire_p, guard_p[5]), dt)
    if wreport[4] > hazard[4]:  # the arm's guard's report first; else the winch's, where it slowed the pay-out
        for i in range(5):
            hazard[i] = wreport[i]
    drum_block((wl, wv, wa, at_limit), wire_ref, wire_p, dt)
    # ---- the load (eqs. 29–30 / 60–61 with p̈_t^g of eq. 57, in {d}: (x, −y, −z))
    alpha, beta, alpha_dot, beta_dot = pendulum_step(
        load, (a_t_g[0], -a_t_g[1], -a_t_g[2]), wl[0], wv[0], damping, g, dt
    )  # fmt: skip
    # ---- the sample
    sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
    L0 = wl[0]
    p_p_g[0] = p_t_g[0] + L0 * -sa  # eq. (58)
    p_p_g[1] = p_t_g[1] - L0 * (ca * sb)
    p_p_g[2] = p_t_g[2] - L0 * (ca * cb)
    e = mtv(H2, p_t_g[0] - H2[0, 3], p_t_g[1] - H2[1, 3], p_t_g[2] - H2[2, 3])
    d = offset[2]  # the operator's shift of the work point in {b2}
    wd = np.array([w_b2[0] + d[0], w_b2[1] + d[1], w_b2[2] + d[2]])
    wg = mv(H2, wd[0], wd[1], wd[2])
    for i in range(3):
        e_b2[i] = e[i] - wd[i]
        p_w_g[i] = wg[i] + H2[i, 3]
    h_err = 0.0
    if has_target:
        tg = mv(H2, target[0], target[1], target[2])
        h_err = p_p_g[2] - (tg[2] + H2[2, 3])
    l1, l2 = leg_lengths(a_n1, b_b1, x1), leg_lengths(a_n2, b_b2, x2)
    for k in range(6):
        legs1[k], legs2[k] = l1[k], l2[k]
    return has_target, alpha, beta, alpha_dot, beta_dot, h_err


def warm_up_steps() -> list:
    """A zero-argument call that compiles (or loads) :func:`lab_step` with the argument types the lab passes
    (for :func:`app.warmup.warm_up`)."""
    z3, z6, o3, eye = np.zeros(3), np.zeros(6), np.ones(3), np.eye(4)
    a_n, b_b = np.ones((6, 3)), np.full((6, 3), 0.5)
    cm = np.array([0.35, 0.83, 1.16, 0.25, 2.269])  # any numbers compile; these are Tables 3/7 (L = 2.269 m)
    signs = np.array([1.0, -1.0])

    def vec(n: int, value: float = 0.0) -> np.ndarray:
        return np.full(n, value)

    def step() -> None:
        x = ((vec(3), vec(3), vec(3)), (vec(1, 1.0), vec(1), vec(1)), (0.0, 0.0, 0.0, 0.0), (vec(3), False))
        seen = (True, z6, z6, z6, z6, z6, z6)
        u = ((z6, z6, z6, z6, z6, z6), seen, (2, z3, (z3, z3, z3, z3), True, 0.0))
        geometry = (cm, eye, signs, eye, eye, eye, eye, o3, z3, a_n, b_b, a_n, b_b)
        joints = (vec(3, -3.0), vec(3, 3.0), o3, o3, o3, 0.05)
        wire = (vec(1, 0.3), vec(1, 2.5), vec(1, 0.5), vec(1, 1.5), 0.05)
        guard = (
            vec(5, 1.0),
            np.array([0.0, 0.0, 1.0, -1.0, 0.0, 0.0, -1.0, 2.0]),
            np.zeros((2, 3)),
            vec(1, 0.2),
            vec(1, 0.8),
            np.array([0.15, 0.02, 0.5]),
        )
        p = (geometry, joints, wire, (0.1, 9.81), guard)
        y = (np.zeros((2, 3, 3, 3)), *(vec(3) for _ in range(4)), np.zeros(4, dtype=np.bool_))
        y = y + (vec(3), vec(3), vec(3), vec(6), vec(6), vec(5))
        lab_step(x, u, p, y, 0.01)

    return [step]
