"""The Motion-Lab's compensated lift (``bosun sim transfer --scene lab``) compiled: many steps in one call.

:func:`transfer_steps` runs, step after step, what :func:`app.scenarios.lab_transfer.simulate_lab`'s loop runs
through the objects' methods — the same blocks in the same order, the compiled ones called as they are:

1. the operator's command (given: the rows of ``V``, worked out ahead by the operator itself) into the Comau's
   tool velocity and the winch's speed;
2. :meth:`app.scenes.lab.MotionLab.step`: both platforms on their wave sources (:meth:`Platform.step`, engaged:
   the source of :func:`app.marine.kernels.vessel_motion` through :func:`app.sim.kernels.follow_clamped`), the
   level work frame (:meth:`MotionLab._shift_level`, with the load lead of :class:`app.scenes.load_lead.LoadLead`)
   and the diagram after the platforms (:func:`app.scenes.lab_kernels.lab_step`);
3. the load on its elastic wire with EM1500's deck (:meth:`app.scenes.lab_load.LabLoad.step`,
   :func:`app.sim.kernels.load_block`) and the wire-angle sensor's pendulum (:meth:`LabLoad.sync`);
4. the landing watch (:meth:`app.scenes.crane_load.LandingWatch.step`, ``relift`` off);
5. in anti-swing, the estimator and law (:meth:`app.scenarios.swing.SwingControl.step`,
   :func:`app.control.antisway_kernels.swing_control_block`) with the sensors' noise given (the rows of ``Z``:
   the same standard normals the generator would have drawn, in its order);
6. the row of :data:`app.scenarios.transfer.COLUMNS`.

It stops early, leaving the objects as they were before that step, where a step needs what only Python does
(the Comau's inverse kinematics for the work point's reach, :meth:`MotionLab._reachable`), and right after a step
the operator must see (the load's first touch) or that captures the winch's target.  The caller checks that the
lab is in the steady state this covers (VVMC engaged on the level frame, or REMOTE; no sensors; no E-STOP; both
platforms engaged on wave sources) and otherwise steps it through the objects; ``tests/test_lab_transfer.py``
checks the two ways agree.

Records (float64 arrays C-contiguous, updated in place where the objects' are):

* ``lab`` = (state, params, y): state (joints (q, q̇, q̈), wire (L, L̇, L̈), the winch's target (3,), the tool
  velocity command (3,), the work shift and its rate, the level offset c, the winch's target in the level frame,
  the tool offset (p, v in {n1}), ċ a step ago, the lead's reference in {d} (f, ẍ_ref), the last shift found
  reachable); params and y: :func:`app.scenes.lab_kernels.lab_step`'s (geometry, joint limits, the drum's limits,
  the pendulum's (c, g); rates, p_t^n1, p_t^g, ṗ_t^g, p̈_t^g, at_limit, e_b2, p_w^g, p_p^g, legs);
* ``platforms``: per platform (filter (x, v, a) (6,) each; limits (lower, upper, speed, accel, τ); legs (a_n, b_b,
  stroke min, max); source (ω, c0 re, c0 im, c1 re, c1 im, scale); ramp time [s]);
* ``load`` = (r, v, s (3,), H^g_b2 a step ago (4, 4), deck velocity, deck normal, the load's parameter record of
  :data:`app.sim.load.LOAD`, the deck's radius);
* ``swing`` = (x̂, P, tilt, tilt rate, the law's p, v, a, innovation (2,), the block's parameter record, R_n1_d,
  σ_accel, σ_angle) (:func:`no_swing` without the anti-swing);
* ``run`` = (flags, cmd (3,), the landing spot in {b2}, R_g_n2, R_g_n1, T_g_n2, w_b2, WORK_SHIFT_MAX, dt, the
  lead's cap, fade and lag, g, the winch's top speed, R_d_n2, the level frame's spot, (slack factor, snap factor,
  sideways speed, static tension), R_r_n2), flags = (the Comau's mode for lab_step, the winch tracks, the level
  frame (VVMC), the load lead, the lead shapes the operator's move, anti-swing, its law active);
* ``given`` = (V, Z): the operator's commanded velocity (n, 3) and the standard normals of the anti-swing's
  sensors (n, 5: three for the acceleration, two for the angles);
* ``rows`` (n, 22) written; ``s`` the scalars (the ``S_*`` slots below), in place.

Returns the number of steps taken.
"""

from __future__ import annotations

import math

import numpy as np

from app.control.antisway_kernels import swing_control_block
from app.marine.kernels import vessel_motion
from app.models.kernels import _jit
from app.models.lab_kernels import pose_in, stewart_rates
from app.scenes.lab_kernels import lab_step
from app.scenes.tac_kernels import ease_in
from app.sim.kernels import follow_clamped, load_block

__all__ = [
    "ROW", "S", "lead_step", "no_swing", "transfer_steps", "warm_up_records", "warm_up_steps", "watch_step",
    "write_row",
]  # fmt: skip

# the scalars' slots (``s``)
S_T, S_ALPHA, S_BETA, S_ALPHA_DOT, S_BETA_DOT, S_HAS_TARGET, S_WINCH_SPEED = 0, 1, 2, 3, 4, 5, 6
S_PLATFORM = 7  # per platform k: S_PLATFORM + 4k + (t_source, gain, engaging, leg clamped)
S_LEAD_T, S_LEAD_A, S_LEAD_F = 15, 16, 19  # the lead's time, its lagged a_cmd (3), f (x, y) a step ago and now (4)
S_LEVEL_PAY, S_LIMITED, S_RANGE_HELD, S_HAZ_AXIS, S_HAZ_GAP, S_HAZ_SLOWED, S_REACH_OK = 23, 24, 25, 26, 27, 28, 29
S_TENSION, S_CONTACT_FORCE, S_GAP, S_TOUCHED, S_TOUCH_SPEED, S_CONTACTS, S_REL_SPEED = 30, 31, 32, 33, 34, 35, 36
S_IN_CONTACT, S_REHIT, S_SLACK, S_SNAP, S_SIDEWAYS, S_SLACK_N, S_SNAP_N, S_SIDEWAYS_N = 37, 38, 39, 40, 41, 42, 43, 44
S_L_PREV, S_SATURATED, S_NIS, S_LAW_ACTIVE, S_H_ERR, S_LOAD_L, S_HAZARD_SET = 45, 46, 47, 48, 49, 50, 51
S_Z_TARGET, S_HAS_Z, S_L_RIDE, S_TRACK, S_RESETS = 52, 53, 54, 55, 56  # the crane's (crane_transfer_kernels)
S_SAMPLE_ALPHA, S_SAMPLE_BETA = 57, 58  # the lab's pendulum as its step left it (the sample's), before the sync
S = 59  # slots
ROW = 22  # the row's columns (app.scenarios.transfer.COLUMNS)

R_B2_DECK = np.diag(np.array([1.0, -1.0, -1.0]))  # app.scenes.lab.R_B2_DECK
R_G_D = np.diag(np.array([1.0, -1.0, -1.0]))  # app.sim.motionlab.R_G_D


@_jit
def _mtv3(R, x):
    """R[:3, :3]ᵀ @ x."""
    out = np.empty(3)
    for i in range(3):
        out[i] = R[0, i] * x[0] + R[1, i] * x[1] + R[2, i] * x[2]
    return out


@_jit
def _mv3(R, x):
    """R[:3, :3] @ x."""
    out = np.empty(3)
    for i in range(3):
        out[i] = R[i, 0] * x[0] + R[i, 1] * x[1] + R[i, 2] * x[2]
    return out


@_jit
def _platform_step(plat, s, k, dt):
    """:meth:`app.sim.stewart.Platform.step`, engaged (ramping in or steady) on a wave source, in place."""
    (x, v, a), limits, legs, (w, c0r, c0i, c1r, c1i, scale), ramp = plat
    i = S_PLATFORM + 4 * k
    s[i] += dt
    if s[i + 2] != 0.0:  # engaging: smoothstep(t / ramp) (app.sim.stewart.smoothstep)
        if ramp > 0:
            xr = min(1.0, max(0.0, s[i] / ramp))
            s[i + 1] = xr * xr * (3.0 - 2.0 * xr)
        else:
            s[i + 1] = 1.0
        if s[i + 1] >= 1.0:
            s[i + 2] = 0.0
    eta_s, v_s = vessel_motion(w, c0r, c0i, c1r, c1i, s[i], scale)
    clamped = follow_clamped(legs, (s[i + 1], eta_s, v_s), (x, v, a), limits, dt)
    s[i + 3] = 1.0 if clamped else 0.0


@_jit
def _scale_in_box(rate, offset, lim, dt):
    """:meth:`MotionLab._scaled_in_range` (with :func:`app.control.guard.scale_in_box`, zone a quarter): the rate,
    and (axis, gap, slowed, range held)."""
    step = np.empty(3)
    asked = np.empty(3)
    axis, least = -1, math.inf
    for i in range(3):
        asked[i] = rate[i] * dt
        step[i] = asked[i]
        gap = max(lim[i] - abs(offset[i]), 0.0)
        zone = 0.25 * lim[i]
        if gap < zone and gap < least:
            axis, least = i, gap
        outward = step[i] * offset[i] > 0.0 or (offset[i] == 0.0 and gap <= 0.0)
        if outward and gap < zone:
            step[i] *= gap / zone
    slowed, held = False, False
    for i in range(3):
        if abs(step[i]) < abs(asked[i]) - 1e-15:
            slowed = True
        if abs(step[i]) < 0.2 * abs(asked[i]):
            held = True
    out = np.empty(3)
    for i in range(3):
        out[i] = step[i] / dt
    return out, axis, least, slowed, held


@_jit
def _level_plan(lab, run, s, cmd):
    """The first part of :meth:`MotionLab._shift_level` (the operator's ċ and the new offset), without changing
    anything: (go on, ċ, new level offset, limited, hazard (set, axis, gap, slowed, held)).  ``go on`` False: the
    shift needs the reach check of :meth:`MotionLab._reachable` (Python's)."""
    level_offset, reach_ok = lab[0][6], lab[0][11]
    spot, w0, lim = run[15], run[6], run[7]
    c_dot = np.zeros(3)
    new_offset = level_offset.copy()
    limited = s[S_LIMITED] != 0.0
    hazard = (False, -1, 0.0, False, False)
    if cmd[0] != 0.0 or cmd[1] != 0.0 or cmd[2] != 0.0:
        c_dot = _mv3(R_B2_DECK, cmd)
        off = np.empty(3)
        for i in range(3):
            off[i] = spot[i] + level_offset[i] - w0[i]
        c_dot, axis, gap, slowed, held = _scale_in_box(c_dot, off, lim, run[8])
        hazard = (True, axis, gap, slowed, held)
        dt = run[8]
        want, shift = np.empty(3), np.empty(3)
        clipped = False
        for i in range(3):
            want[i] = spot[i] + level_offset[i] + c_dot[i] * dt - w0[i]
            shift[i] = min(max(want[i], -lim[i]), lim[i])
            clipped = clipped or shift[i] != want[i]
        limited = clipped or held
        if clipped:
            c_dot, limited = np.zeros(3), True
        else:
            near = s[S_REACH_OK] != 0.0
            if near:
                for i in range(3):
                    near = near and abs(shift[i] - reach_ok[i]) <= 0.01
            if not near:
                return False, c_dot, new_offset, limited, hazard
            for i in range(3):
                new_offset[i] = level_offset[i] + c_dot[i] * dt
    return True, c_dot, new_offset, limited, hazard


@_jit
def write_row(row, s, points, swing_deg, wire, offset, static):
    """A row of :data:`app.scenarios.transfer.COLUMNS` from the step's scalars: ``points`` = (the commanded point
    and the load, in the target frame; the TCP and the deck point), the swing angle [deg], the wire's length, the
    anti-swing's offset (x, y) and the static tension."""
    cmd, load_t, tcp, deck = points
    err = 0.0
    for i in range(3):
        err += (load_t[i] - cmd[i]) ** 2
    row[0] = s[S_T]
    for i in range(3):
        row[1 + i], row[4 + i], row[8 + i], row[11 + i] = cmd[i], load_t[i], tcp[i], deck[i]
    row[7] = math.sqrt(err)
    row[14], row[15], row[16] = s[S_GAP], s[S_REL_SPEED], swing_deg
    row[17], row[18], row[19] = s[S_TENSION] / static, s[S_CONTACT_FORCE] / 1e3, wire
    row[20], row[21] = offset[0], offset[1]


@_jit
def lead_step(s, a, a_cmd, length, p):
    """:meth:`app.scenes.load_lead.LoadLead.step` on the scalars' lead slots: the target's acceleration ``a`` (3,),
    the operator's commanded acceleration ``a_cmd`` (3,; led only with ``shape``), the wire's length; ``p`` = (dt,
    cap, fade, the lag τ, g, shape).  Returns (f_x, f_y, ẍ_x, ẍ_y, f_x and f_y a step ago, two steps ago) with ẍ the
    acceleration led (the target's plus the lagged operator's)."""
    dt, cap, fade, tau, g, shape = p
    s[S_LEAD_T] += dt
    ax, ay, az = a[0], a[1], a[2]
    if shape:
        kk = min(1.0, dt / tau)
        for i in range(3):
            s[S_LEAD_A + i] = s[S_LEAD_A + i] + (a_cmd[i] - s[S_LEAD_A + i]) * kk
        ax, ay, az = ax + s[S_LEAD_A], ay + s[S_LEAD_A + 1], az + s[S_LEAD_A + 2]
    kl = length / max(g - az, 0.5 * g)  # app.models.pendulum.suspension_lead_xy
    fx, fy = ax * kl, ay * kl
    nf = math.hypot(fx, fy)
    if nf > cap:
        fx, fy = fx * cap / nf, fy * cap / nf
    if s[S_LEAD_T] < fade:
        gain = ease_in(s[S_LEAD_T] / fade)[0]
        fx, fy = fx * gain, fy * gain
    x2, y2, x1, y1 = s[S_LEAD_F], s[S_LEAD_F + 1], s[S_LEAD_F + 2], s[S_LEAD_F + 3]
    s[S_LEAD_F], s[S_LEAD_F + 1], s[S_LEAD_F + 2], s[S_LEAD_F + 3] = x1, y1, fx, fy
    return fx, fy, ax, ay, x1, y1, x2, y2


@_jit
def _level_step(lab, run, s, c_dot, rates, x2a, wire_len):
    """The rest of :meth:`MotionLab._shift_level` with :meth:`MotionLab._lead_step`: the work shift and its rate,
    the lead, the winch's target in the level frame (in place)."""
    _, _, target, _, shift, shift_rate, c, level_load, _, c_dot_prev, (ref_f, ref_a), _ = lab[0]
    R, Rd, Rdd = rates
    flags, spot, w0, dt = run[0], run[15], run[6], run[8]
    lead_cap, lead_fade, lead_tau, g, top, R_d_n2 = run[9], run[10], run[11], run[12], run[13], run[14]
    if flags[3]:  # the load lead (LoadLead.step)
        a = np.empty(3)
        Rs = _mv3(Rdd, spot)
        a_cmd = np.empty(3)
        for i in range(3):
            a[i] = x2a[i] + Rs[i]
            a_cmd[i] = (c_dot[i] - c_dot_prev[i]) / dt
        lead_p = (dt, lead_cap, lead_fade, lead_tau, g, flags[4])
        fx, fy, ax, ay, x1, y1, x2, y2 = lead_step(s, a, a_cmd, wire_len, lead_p)
        f = np.array((fx, fy, 0.0))
        a_ref = np.array((ax + (fx - 2.0 * x1 + x2) / (dt * dt), ay + (fy - 2.0 * y1 + y2) / (dt * dt), 0.0))
        f_dot = np.array(((fx - x1) / dt, (fy - y1) / dt, 0.0))
        for i in range(3):
            c_dot_prev[i] = c_dot[i]
        rf, ra = _mv3(R_d_n2, f), _mv3(R_d_n2, a_ref)
        for i in range(3):
            ref_f[i], ref_a[i] = rf[i], ra[i]
        cf = np.empty(3)
        cdf = np.empty(3)
        for i in range(3):
            cf[i] = c[i] + f[i]
            cdf[i] = c_dot[i] + f_dot[i]
        A, B = _mtv3(R, cf), _mtv3(Rd, cf)
        C = _mtv3(R, cdf)
        for i in range(3):
            shift[i] = spot[i] - w0[i] + A[i]
            shift_rate[i] = B[i] + C[i]  # the spot's rate is zero in the level frame
    else:
        A, B, C = _mtv3(R, c), _mtv3(Rd, c), _mtv3(R, c_dot)
        for i in range(3):
            shift[i] = spot[i] - w0[i] + A[i]
            shift_rate[i] = B[i] + C[i]
    if flags[1]:  # the winch's target in the level frame (payload_target_b2 set, winch in MOTION_COMP)
        level_load[2] += s[S_LEVEL_PAY]
        level_load[0], level_load[1] = c[0], c[1]
        t = _mtv3(R, level_load)
        for i in range(3):
            target[i] = spot[i] + t[i]
        s[S_LEVEL_PAY] = min(max(s[S_WINCH_SPEED], -top), top) * dt


@_jit
def _load_step(lab_out, load, run, s, x2, L1, dt):
    """:meth:`LabLoad.step` and :meth:`LabLoad.sync` (in place); returns H^g_b2 now."""
    p_t_g, v_t_g = lab_out
    r, v, s0, H0, deck_v, n_up, lp, radius = load
    T_g_n2 = run[5]
    s1 = _mtv3(R_G_D, p_t_g)
    H1 = pose_in(T_g_n2, x2)
    # the deck under the load (LabLoad._deck)
    rg = _mv3(R_G_D, r)
    p_b2 = np.empty(3)
    for i in range(3):
        p_b2[i] = H0[0, i] * (rg[0] - H0[0, 3]) + H0[1, i] * (rg[1] - H0[1, 3]) + H0[2, i] * (rg[2] - H0[2, 3])
    present = math.hypot(p_b2[0], p_b2[1]) <= radius
    d0, nn, vd = np.zeros(3), np.array((0.0, 0.0, -1.0)), np.zeros(3)
    if present:
        m = np.array((p_b2[0], p_b2[1], 0.0))
        a0, a1 = _mv3(H0, m), _mv3(H1, m)
        for i in range(3):
            a0[i] += H0[i, 3]
            a1[i] += H1[i, 3]
        d0, d1 = _mtv3(R_G_D, a0), _mtv3(R_G_D, a1)
        nn = _mtv3(R_G_D, np.array((-H1[0, 2], -H1[1, 2], -H1[2, 2])))
        for i in range(3):
            vd[i] = (d1[i] - d0[i]) / dt
    for i in range(3):
        deck_v[i] = vd[i] if present else 0.0
        n_up[i] = nn[i]
    _, (T, Fn, gap) = load_block((r, v), (s0, s1, s[S_LOAD_L], L1, (present, d0, nn, vd)), lp, dt)
    s[S_TENSION], s[S_CONTACT_FORCE] = T, Fn
    s[S_GAP] = gap if present else math.inf
    for i in range(3):
        s0[i] = s1[i]
    s[S_LOAD_L] = L1
    for i in range(4):
        for j in range(4):
            H0[i, j] = H1[i, j]
    # LabLoad.sync: the wire-angle sensor's pendulum
    e = np.empty(3)
    for i in range(3):
        e[i] = r[i] - s0[i]
    ell = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    u = e / ell
    vt = _mtv3(R_G_D, v_t_g)
    ed = np.empty(3)
    for i in range(3):
        ed[i] = v[i] - vt[i]
    ue = u[0] * ed[0] + u[1] * ed[1] + u[2] * ed[2]
    ud = np.empty(3)
    for i in range(3):
        ud[i] = (ed[i] - u[i] * ue) / ell
    ca = math.sqrt(max(1e-12, 1.0 - u[0] * u[0]))
    s[S_ALPHA] = -math.asin(max(-1.0, min(1.0, u[0])))
    s[S_BETA] = math.atan2(u[1], u[2])
    s[S_ALPHA_DOT] = -ud[0] / ca
    s[S_BETA_DOT] = (u[2] * ud[1] - u[1] * ud[2]) / max(1e-12, u[1] ** 2 + u[2] ** 2)
    return H1


@_jit
def watch_step(v, deck_v, n_up, s, consts):
    """:meth:`app.scenes.crane_load.LandingWatch.step` (``relift`` off) into the scalars, from the load's velocity,
    the deck's velocity and up normal; ``consts`` = (slack factor, snap factor, sideways speed, static tension);
    returns whether a contact began."""
    slack_factor, snap_factor, sideways_speed, static = consts
    rel = np.empty(3)
    for i in range(3):
        rel[i] = v[i] - deck_v[i]
    rel_n = n_up[0] * rel[0] + n_up[1] * rel[1] + n_up[2] * rel[2]
    before = s[S_REL_SPEED]
    s[S_REL_SPEED] = -rel_n
    contact = s[S_CONTACT_FORCE] > 0.0
    onset = contact and s[S_IN_CONTACT] == 0.0
    s[S_IN_CONTACT] = 1.0 if contact else 0.0
    if onset:
        s[S_CONTACTS] += 1.0
        if s[S_TOUCHED] == 0.0:
            s[S_TOUCHED], s[S_TOUCH_SPEED] = 1.0, before
    s[S_REHIT] = 1.0 if onset and s[S_CONTACTS] > 1.0 else 0.0
    ratio = s[S_TENSION] / static
    s[S_SLACK] = 1.0 if ratio < slack_factor and not contact else 0.0
    s[S_SNAP] = 1.0 if ratio > snap_factor else 0.0
    sideways = False
    if contact:
        t0, t1, t2 = rel[0] - n_up[0] * rel_n, rel[1] - n_up[1] * rel_n, rel[2] - n_up[2] * rel_n
        sideways = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2) > sideways_speed
    s[S_SIDEWAYS] = 1.0 if sideways else 0.0
    s[S_SLACK_N] += s[S_SLACK]
    s[S_SNAP_N] += s[S_SNAP]
    s[S_SIDEWAYS_N] += s[S_SIDEWAYS]
    return onset


@_jit
def _swing_step(lab_rec, swing, run, s, z5, wire, dt):
    """:meth:`app.scenarios.swing.SwingControl.step` (angles measured; the lead as reference under VVMC) and
    :meth:`MotionLab.set_tool_offset`; False when the offset is not finite (the caller raises)."""
    xh, P, tilt, tilt_rate, lp, lv, la, innovation, rec, R_n1_d, sigma_accel, sigma_angle = swing
    (_, _, _, _, _, _, _, _, (tool_p, tool_v), _, (ref_f, ref_a), _) = lab_rec
    flags = run[0]
    a_t_g, wl, wv = wire
    a_d = _mtv3(R_G_D, a_t_g)
    for i in range(3):
        a_d[i] = a_d[i] + sigma_accel * z5[i]
    L = wl
    if flags[3]:  # the lead's reference (MOTION_COMP with the load lead)
        for i in range(3):
            a_d[i] = a_d[i] - ref_a[i]
        sa, ca = math.sin(s[S_ALPHA]), math.cos(s[S_ALPHA])
        sb, cb = math.sin(s[S_BETA]), math.cos(s[S_BETA])
        e = np.array((L * -sa + ref_f[0], L * (ca * sb) + ref_f[1], L * (ca * cb) + ref_f[2]))
        ell = float(np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]))
        alpha, beta = -math.asin(min(1.0, max(-1.0, e[0] / ell))), math.atan2(e[1], e[2])
    else:
        alpha, beta = s[S_ALPHA], s[S_BETA]
    z = np.array((alpha + sigma_angle * z5[3], beta + sigma_angle * z5[4]))
    on = flags[6] and s[S_TOUCHED] == 0.0 and s[S_SLACK] == 0.0
    s[S_LAW_ACTIVE] = 1.0 if on else 0.0
    x = (xh, P, tilt, tilt_rate, lp, lv, la, s[S_L_PREV])
    x2, (p_d, v_d, saturated, y, nis) = swing_control_block(x, (a_d, z, L, wv, on), rec, dt)
    s[S_L_PREV] = x2[7]
    s[S_SATURATED] = 1.0 if saturated else 0.0
    s[S_NIS] = nis
    for i in range(innovation.shape[0]):
        innovation[i] = y[i]
    pp, vv = _mv3(R_n1_d, p_d), _mv3(R_n1_d, v_d)
    ok = True
    for i in range(3):
        ok = ok and math.isfinite(pp[i]) and math.isfinite(vv[i])
        tool_p[i], tool_v[i] = pp[i], vv[i]
    return ok


@_jit
def transfer_steps(lab, platforms, load, swing, run, given, rows, s):
    """Up to ``len(V)`` steps of the lab's transfer (module text), ``given`` = (V, Z); the number taken."""
    V, Z = given
    state, (geometry, joint_p, wire_p, load_p, guard_p), y = lab
    (q, qd, qdd), (wl, wv, wa), target, tool_cmd, shift, shift_rate, _, _, (tool_p, tool_v), _, _, _ = state
    p_t_g, v_t_g, a_t_g = y[2], y[3], y[4]
    flags, cmd, land, R_g_n2, R_g_n1, dt, R_r_n2 = run[0], run[1], run[2], run[3], run[4], run[8], run[17]
    mode, track, level, antisway = flags[0], flags[1], flags[2], flags[5]
    x1, v1, a1 = platforms[0][0]
    x2, v2, a2 = platforms[1][0]
    r, _, s_tool, _, _, _, _, _ = load
    n = V.shape[0]
    for k in range(n):
        vk = V[k]
        horizontal = np.array((vk[0], vk[1], 0.0))
        go, c_dot, new_offset, limited, hazard = (
            True,
            np.zeros(3),
            state[6],
            s[S_LIMITED] != 0.0,
            (False, -1, 0.0, False, False),
        )
        if level:  # the operator's move of the level frame's offset, checked before anything moves
            tc = _mv3(R_B2_DECK, horizontal)
            go, c_dot, new_offset, limited, hazard = _level_plan(lab, run, s, tc)
            if not go:
                return k
        for i in range(3):
            cmd[i] = cmd[i] + vk[i] * dt
        tc = _mv3(R_r_n2, horizontal) if not level else _mv3(R_B2_DECK, horizontal)
        for i in range(3):
            tool_cmd[i] = tc[i]
        s[S_WINCH_SPEED] = vk[2]
        # ---- MotionLab.step: the clock, the platforms, the work point, the diagram
        s[S_T] += dt
        _platform_step(platforms[0], s, 0, dt)
        _platform_step(platforms[1], s, 1, dt)
        if level:
            if hazard[0]:
                s[S_HAZARD_SET], s[S_HAZ_AXIS], s[S_HAZ_GAP] = 1.0, hazard[1], hazard[2]
                s[S_HAZ_SLOWED], s[S_RANGE_HELD] = 1.0 if hazard[3] else 0.0, 1.0 if hazard[4] else 0.0
            s[S_LIMITED] = 1.0 if limited else 0.0
            lo = state[6]
            for i in range(3):
                lo[i] = new_offset[i]
            R, Rd, Rdd = stewart_rates(x2, v2, a2)
            _level_step(lab, run, s, c_dot, (R, Rd, Rdd), a2, wl[0])
        else:
            for i in range(3):
                shift_rate[i] = 0.0
        x = ((q, qd, qdd), (wl, wv, wa), (s[S_ALPHA], s[S_BETA], s[S_ALPHA_DOT], s[S_BETA_DOT]),
             (target, s[S_HAS_TARGET] != 0.0))  # fmt: skip
        true = (x1, v1, a1, x2, v2, a2)
        u = (true, (False, x1, v1, a1, x2, v2, a2), (mode, tool_cmd, (tool_p, tool_v, shift, shift_rate), track,
                                                     s[S_WINCH_SPEED]))  # fmt: skip
        had = s[S_HAS_TARGET] != 0.0
        has, s[S_ALPHA], s[S_BETA], s[S_ALPHA_DOT], s[S_BETA_DOT], s[S_H_ERR] = lab_step(
            x, u, (geometry, joint_p, wire_p, load_p, guard_p), y, dt
        )
        s[S_HAS_TARGET] = 1.0 if has else 0.0
        s[S_SAMPLE_ALPHA], s[S_SAMPLE_BETA] = s[S_ALPHA], s[S_BETA]
        # ---- the load, the watch, the swing law
        H2 = _load_step((p_t_g, v_t_g), load, run, s, x2, wl[0], dt)
        onset = watch_step(load[1], load[4], load[5], s, run[16])
        first_touch = onset and s[S_CONTACTS] == 1.0
        off0, off1 = 0.0, 0.0
        if antisway:
            if not _swing_step(state, swing, run, s, Z[k], (a_t_g, wl[0], wv[0]), dt):
                rows[k, 0] = math.nan
                return k + 1
            o = _mtv3(H2, _mv3(R_g_n1, tool_p))
            off0, off1 = o[0], o[1]
        # ---- the row
        spot = _mv3(H2, land)
        for i in range(3):
            spot[i] += H2[i, 3]
        rg = _mv3(R_G_D, r)
        d = np.empty(3)
        for i in range(3):
            d[i] = rg[i] - spot[i]
        load_t = _mtv3(R_g_n2, d)
        e = np.empty(3)
        for i in range(3):
            e[i] = r[i] - s_tool[i]
        ell = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        swing_deg = math.degrees(math.acos(min(1.0, max(-1.0, e[2] / ell))))
        tcp, deck = _mtv3(R_G_D, p_t_g), _mtv3(R_G_D, spot)
        write_row(rows[k], s, (cmd, load_t, tcp, deck), swing_deg, wl[0], (off0, off1), run[16][3])
        if first_touch or (has and not had):  # the operator sees the touch; Python keeps the winch's target
            return k + 1
    return n


def no_swing() -> tuple:
    """The swing record of a run without the anti-swing (never read; the types of a real one, so one kernel
    signature serves every mode)."""
    ekf_p = (0.1, 9.81, 0.05, 1e-3, False, 0.01, 0.005)
    law_p = (np.ones(1), np.zeros((1, 4)), np.zeros((1, 4)), 2.0, 0.3)
    z2 = np.zeros(2)
    return (np.zeros(4), np.eye(4), z2, z2.copy(), z2.copy(), z2.copy(), z2.copy(), z2.copy(),
            (ekf_p, law_p, 9.81, 0.2), np.eye(3), 0.05, 0.01)  # fmt: skip


def warm_up_records(n: int = 0) -> tuple:
    """Records of :func:`transfer_steps` with the argument types a lab transfer passes, for ``n`` steps (the types
    compile it; none taken by default: these numbers are no lab): (lab, platforms, load, swing, run, (V, Z),
    rows, s)."""
    z3, z6, eye3, eye4 = np.zeros(3), np.zeros(6), np.eye(3), np.eye(4)
    a_n, b_b = np.ones((6, 3)), np.full((6, 3), 0.5)

    def vec(k: int, value: float = 0.0) -> np.ndarray:
        return np.full(k, value)

    cm = np.array([0.35, 0.83, 1.16, 0.25, 2.269])
    geometry = (cm, eye4, np.array([1.0, -1.0]), eye4, eye4, eye4, eye4, vec(3), vec(3), a_n, b_b, a_n, b_b)
    joint_p = (vec(3, -3.0), vec(3, 3.0), vec(3, 1.0), vec(3, 1.0), vec(3, 1.0), 0.05)
    wire_p = (vec(1, 0.3), vec(1, 2.5), vec(1, 0.5), vec(1, 1.5), 0.05)
    state = (
        (vec(3), vec(3), vec(3)), (vec(1, 1.0), vec(1), vec(1)), vec(3), vec(3), vec(3), vec(3), vec(3), vec(3),
        (vec(3), vec(3)), vec(3), (vec(3), vec(3)), vec(3),
    )  # fmt: skip
    y = (np.zeros((2, 3, 3, 3)), vec(3), vec(3), vec(3), vec(3), np.zeros(4, dtype=np.bool_))
    y += (vec(3), vec(3), vec(3), vec(6), vec(6), vec(5))
    guard = (vec(3, 0.1), np.array([0.0, 0.0, 1.0, -1.0]), np.zeros((2, 3)), vec(1, 0.2), vec(1, 0.8),
             np.array([0.15, 0.02, 0.5]))  # fmt: skip
    lab = (state, (geometry, joint_p, wire_p, (0.1, 9.81), guard), y)
    w = np.array([0.5, 0.6])
    parts = tuple(np.zeros((6, 2)) for _ in range(4))
    platforms = tuple(
        ((z6.copy(), z6.copy(), z6.copy()), (vec(6, -1.0), vec(6, 1.0), vec(6, 1.0), vec(6, 1.0), 0.05),
         (a_n, b_b, 0.5, 3.0), (w, *parts, vec(6, 1.0)), 10.0)
        for _ in range(2)
    )  # fmt: skip
    load_p = (5.0, 1e6, 0.05, 0.1, 1e5, 0.5, 0.3, 0.01, 9.81, 2)
    load = (np.array([0.0, 0.0, 1.0]), vec(3), vec(3), eye4.copy(), vec(3), np.array([0.0, 0.0, -1.0]), load_p, 0.8)
    flags = (2, True, True, True, True, True, True)
    run = (
        flags, vec(3), vec(3), eye3, eye3, eye4, vec(3), vec(3, 1.0), 0.005, 0.1, 2.0, 0.4, 9.81, 0.2, eye3, z3,
        (0.1, 1.5, 0.1, 49.05), eye3,
    )  # fmt: skip
    s = np.zeros(S)
    s[S_LOAD_L] = 1.0
    return lab, platforms, load, no_swing(), run, (np.zeros((n, 3)), np.zeros((n, 5))), np.zeros((n, ROW)), s


def warm_up_steps() -> list:
    """A zero-argument call that compiles (or loads) :func:`transfer_steps` with the argument types
    :func:`app.scenarios.lab_transfer.simulate_lab` passes (for :func:`app.warmup.warm_up`)."""

    def step() -> None:
        transfer_steps(*warm_up_records())

    return [step]
