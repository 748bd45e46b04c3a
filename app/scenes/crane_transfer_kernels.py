"""The crane's compensated lift (``bosun sim transfer``, the crane scene) compiled between the crane-head
simulation's chunks: the steps of one chunk in one call.

:func:`crane_steps` runs, for each TCP sample of a chunk of :meth:`app.scenarios.tac.TacSimulator.advance`, what
:func:`app.scenarios.transfer.simulate`'s inner loop runs through the objects, in its order: the operator's command
(given, worked out ahead) into the commanded point; the target deck (given: the platform, or the second vessel's
deck at the step's time); the load lead (:class:`app.scenes.load_lead.LoadLead`, :func:`lead_step`); the winch's
heave compensation (:data:`app.control.tac.CRANE_AHC`, steady: on or off, not fading), its drum
(:func:`app.sim.kernels.drum_block`) and the load on its wire (:func:`app.sim.kernels.load_block`) —
:meth:`app.scenes.crane_load.CraneLoad.step`; the landing watch (:func:`watch_step`); in anti-swing the estimator and
law (:meth:`app.scenes.crane_load.CraneSwingControl.step`, :func:`app.control.antisway_kernels.swing_control_block`,
its sensors' noise given); the row of :data:`app.scenarios.transfer.COLUMNS`.  It stops right after the load's
first touch (the operator sees it).  The caller checks the state it covers (the load hanging with three TCP
samples, heave compensation not fading, no E-STOP) and otherwise steps the objects; tests/test_transfer.py checks
the two ways agree.

Records: ``load`` = (r, v, drum (L, L̇, L̈ (1,) each, at_limit (4,)), the drum's limits, the load's parameter
record, the last three TCP samples (3, 3) oldest first, ṗ_TCP, p̈_TCP, the deck's velocity, the deck point a step
ago); ``swing`` = (x̂, P, tilt, tilt rate, the law's p, v, a, the block's parameter record, P₀ of a fresh
estimator); ``lead`` = (the TCP's lead, the swing law's reference (f, ẍ_ref), the last command); ``run`` = (flags
(off, vessel target, lead, lead shapes the move, anti-swing, its law active), cmd (3,), R_deck, dt, the lead's
parameters of :func:`lead_step`, the watch's constants of :func:`watch_step`, the winch's top speed, the offset
(3,)); ``given`` = (V, TCP, D, N, A, W): per step the command, the TCP, the deck point and its up normal, the
deck spot's acceleration and the sensors' noise (5,); ``rows`` written; ``s`` the scalars (the slots of
:mod:`app.scenes.lab_transfer_kernels`).  Returns the number of steps taken.
"""

from __future__ import annotations

import math

import numpy as np

from app.control.antisway_kernels import swing_control_block
from app.models.kernels import _jit
from app.scenes.lab_transfer_kernels import (
    S_CONTACT_FORCE,
    S_CONTACTS,
    S_GAP,
    S_HAS_Z,
    S_L_PREV,
    S_L_RIDE,
    S_RESETS,
    S_SLACK,
    S_T,
    S_TENSION,
    S_TOUCHED,
    S_TRACK,
    S_WINCH_SPEED,
    S_Z_TARGET,
    S,
    lead_step,
    watch_step,
    write_row,
)
from app.sim.kernels import drum_block, load_block

__all__ = ["crane_steps", "warm_up_records", "warm_up_steps"]


@_jit
def _finite(a):
    """Every element finite (a loop: numba compiles it; a generator it would not)."""
    ok = True
    for x in a.flat:
        ok = ok and math.isfinite(x)
    return ok


@_jit
def crane_steps(load, swing, lead, run, given, rows, s):
    """Up to ``len(V)`` steps of the crane's transfer (module text); the number taken."""
    r, v, (wl, wv, wa, at_limit), drum_p, load_p, hist, tcp_v, tcp_a, deck_v, d_prev = load
    xh, P, tilt, tilt_rate, lp, lv, la, rec, P0 = swing
    lead_tcp, (ref_f, ref_a), v_prev = lead
    flags, cmd, R_deck, dt, lead_p, consts, top, offset = run
    off, vessel, led, _, antisway, active = flags
    V, TCP, D, N, A, W = given
    static = consts[3]
    n = V.shape[0]
    for k in range(n):
        vk, p, d, n_up = V[k], TCP[k], D[k], N[k]
        for i in range(3):
            cmd[i] = cmd[i] + vk[i] * dt
        s[S_T] = s[S_T] + dt
        for i in range(3):
            deck_v[i] = (d[i] - d_prev[i]) / dt
            d_prev[i] = d[i]
        if led:  # the deck's spot and the operator's commanded point accelerate
            a_cmd = np.array(((vk[0] - v_prev[0]) / dt, (vk[1] - v_prev[1]) / dt, 0.0))
            a_spot = np.zeros(3)
            if vessel:
                a_w = np.empty(3)
                for i in range(3):
                    a_w[i] = R_deck[i, 0] * a_cmd[0] + R_deck[i, 1] * a_cmd[1] + R_deck[i, 2] * a_cmd[2]
                a_cmd = a_w
                a_spot = A[k]
            fx, fy, ax, ay, x1, y1, x2, y2 = lead_step(s, a_spot, a_cmd, wl[0], lead_p)
            lead_tcp[0], lead_tcp[1], lead_tcp[2] = fx, fy, 0.0
            ref_f[0], ref_f[1], ref_f[2] = fx, fy, 0.0
            ref_a[0] = ax + (fx - 2.0 * x1 + x2) / (dt * dt)
            ref_a[1] = ay + (fy - 2.0 * y1 + y2) / (dt * dt)
            ref_a[2] = 0.0
            for i in range(3):
                v_prev[i] = vk[i]
        if off:
            s[S_WINCH_SPEED] = vk[2]
        else:
            s[S_WINCH_SPEED] = (R_deck[2, 0] * vk[0] + R_deck[2, 1] * vk[1] + R_deck[2, 2] * vk[2]) + deck_v[2]
        # ---- CraneLoad.step: the TCP's samples, the heave compensation, the drum, the load
        prev = hist[2].copy()
        for i in range(3):
            hist[0, i], hist[1, i], hist[2, i] = hist[1, i], hist[2, i], p[i]
        for i in range(3):
            tcp_v[i] = (hist[2, i] - hist[1, i]) / dt
            tcp_a[i] = (hist[2, i] - 2.0 * hist[1, i] + hist[0, i]) / (dt * dt)
        sp = min(max(s[S_WINCH_SPEED], -top), top)
        L = wl[0]
        if s[S_TRACK] == 0.0:  # app.control.tac._crane_ahc_reference, steady (gain 1 or not tracking)
            s[S_HAS_Z] = 0.0
            L_ref, Ld_ref = L + sp * dt, sp
        else:
            if s[S_HAS_Z] == 0.0:
                s[S_Z_TARGET], s[S_HAS_Z], s[S_L_RIDE] = p[2] + L, 1.0, L
            s[S_Z_TARGET] = s[S_Z_TARGET] + sp * dt
            L_ref, Ld_ref = s[S_Z_TARGET] - p[2], sp - tcp_v[2]
        drum_block((wl, wv, wa, at_limit), (np.array([L_ref]), np.array([Ld_ref])), drum_p, dt)
        _, (T, Fn, gap) = load_block((r, v), (prev, p, L, wl[0], (True, d, n_up, deck_v)), load_p, dt)
        s[S_TENSION], s[S_CONTACT_FORCE], s[S_GAP] = T, Fn, gap
        onset = watch_step(v, deck_v, n_up, s, consts)
        e = np.empty(3)
        for i in range(3):
            e[i] = r[i] - p[i]
        ell = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        swing_deg = math.degrees(math.acos(min(1.0, max(-1.0, e[2] / ell))))
        if antisway:  # CraneSwingControl.step
            w = W[k]
            a_d = np.empty(3)
            e2 = e.copy()
            for i in range(3):
                a_d[i] = tcp_a[i] + w[i]
            if led:
                for i in range(3):
                    e2[i] = e2[i] + ref_f[i]
                    a_d[i] = a_d[i] - ref_a[i]
            z = np.array((-math.asin(min(1.0, max(-1.0, e2[0] / ell))), math.atan2(e2[1], e2[2])))
            z[0], z[1] = z[0] + w[3], z[1] + w[4]
            on = active and s[S_TOUCHED] == 0.0 and s[S_SLACK] == 0.0
            x = (xh, P, tilt, tilt_rate, lp, lv, la, s[S_L_PREV])
            x2_, (p_d, _, _, _, _) = swing_control_block(x, (a_d, z, wl[0], wv[0], on), rec, dt)
            s[S_L_PREV] = x2_[7]
            if not (_finite(xh) and _finite(P)):  # the estimator lost the load: "no swing" again
                xh[:] = 0.0
                P[:, :] = P0
                tilt[:] = 0.0
                tilt_rate[:] = 0.0
                for arr in (lp, lv, la):
                    if not _finite(arr):
                        arr[:] = 0.0
                p_d = np.array((lp[0], lp[1], 0.0))
                s[S_L_PREV] = wl[0]
                s[S_RESETS] += 1.0
            for i in range(3):
                offset[i] = p_d[i]
        # ---- the row
        load_t = np.empty(3)
        for i in range(3):
            load_t[i] = r[i] - d[i]
        if vessel:
            q = load_t.copy()
            for i in range(3):
                load_t[i] = R_deck[0, i] * q[0] + R_deck[1, i] * q[1] + R_deck[2, i] * q[2]
        write_row(rows[k], s, (cmd, load_t, p, d), swing_deg, wl[0], (offset[0], offset[1]), static)
        if onset and s[S_CONTACTS] == 1.0:  # the operator sees the touch
            return k + 1
    return n


def warm_up_records(n: int = 0) -> tuple:
    """Records of :func:`crane_steps` with the argument types the transfer passes (for ``n`` steps; none by
    default: the types compile it)."""
    z3 = np.zeros(3)
    drum = (np.array([10.0]), np.zeros(1), np.zeros(1), np.zeros(4, dtype=np.bool_))
    drum_p = (np.array([3.0]), np.array([40.0]), np.array([1.5]), np.array([2.0]), 0.05)
    load_p = (500.0, 1e7, 0.05, 0.1, 1e6, 0.5, 0.3, 0.01, 9.81, 10)
    load = (np.array([0.0, 0.0, 10.0]), z3.copy(), drum, drum_p, load_p, np.zeros((3, 3)), z3.copy(), z3.copy(),
            z3.copy(), z3.copy())  # fmt: skip
    ekf_p = (0.1, 9.81, 0.05, 1e-3, False, 0.01, 0.005)
    law_p = (np.ones(1), np.zeros((1, 4)), np.zeros((1, 4)), 1.0, 1.5)
    z2 = np.zeros(2)
    swing = (np.zeros(4), np.eye(4), z2, z2.copy(), z2.copy(), z2.copy(), z2.copy(), (ekf_p, law_p, 9.81, 0.2),
             np.eye(4))  # fmt: skip
    lead = (z3.copy(), (z3.copy(), z3.copy()), z3.copy())
    flags = (False, False, True, True, True, True)
    run = (flags, z3.copy(), np.eye(3), 0.01, (0.01, 1.0, 5.0, 0.4, 9.81, True), (0.1, 1.5, 0.1, 4905.0), 1.5,
           z3.copy())  # fmt: skip
    given = (np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
             np.zeros((n, 5)))  # fmt: skip
    return load, swing, lead, run, given, np.zeros((n, 22)), np.zeros(S)


def warm_up_steps() -> list:
    """A zero-argument call that compiles (or loads) :func:`crane_steps` (for :func:`app.warmup.warm_up`)."""

    def step() -> None:
        crane_steps(*warm_up_records())

    return [step]
