"""The compensated lift in the Motion-Lab (issue 30, items 4–6): ``bosun sim transfer --scene lab``.

The lab of ``sim vvmc`` (both platforms playing a vessel in the same sea, auto-scaled into their operational boxes,
:func:`app.scenarios.vvmc._sources`), with the load of :mod:`app.scenes.lab_load` (the crane's elastic wire and
deck, on the lab winch's wire) and EM1500's deck as the target.  Per 5 ms step (the PLC's task):

* ``compensated``: VVMC on (the Comau and the winch in MOTION_COMP); the operator's horizontal command moves the
  work point across EM1500 in its frame (REMOTE under VVMC, item 4: :meth:`MotionLab._shift_work_point`), the
  winch's w lowers the load relative to the deck (its height target moves along the deck's normal);
* ``antisway``: the same, with the lab's estimator and anti-swing law (:class:`app.scenarios.swing.SwingControl`),
  resting while the load is on the deck or the wire slack;
* ``off``: the same operator without compensation: the Comau in REMOTE (the stick's move turned into the robot's
  base frame {r} as it is in calm water, so the move is the same one), the winch in REMOTE at the operator's speed.

The target frame is EM1500's body frame {b2} (z down, as the crane's {n}), with its origin on the deck at the
landing spot.  The pick-up point: the work point moved by :data:`PICKUP_SHIFT_B2` (past the edge of EM1500's deck,
0.99 m from its centre; the deck's radius is 0.80 m); the scripted operator lifts 0.2 m, moves 1 m along y of {b2}
(to 0.49 m from the centre, the Comau in reach with its 0.15 m margin all the way: tests/test_lab_transfer.py),
waits, lowers at 0.05 m/s until the load touches the deck, pays out 5 cm and holds (module text of
:mod:`app.scenarios.transfer`).
"""

from __future__ import annotations

import copy
import math

import numpy as np

from app.models.kernels import ENABLED
from app.models.lab import load_lab
from app.models.pendulum import G
from app.scenarios.swing import SwingControl
from app.scenarios.transfer import (
    COLUMNS,
    ScriptedOperator,
    StickFile,
    TransferError,
    TransferResult,
    TransferScenario,
    summarise,
)
from app.scenarios.vvmc import VvmcScenario, _sources
from app.scenes import lab_transfer_kernels as tk
from app.scenes.crane_load import SIDEWAYS_SPEED, SLACK_FACTOR, SNAP_FACTOR, LandingWatch
from app.scenes.lab import COMAU_MODES, R_B2_DECK, REMOTE_TOOL_SPEED, WORK_SHIFT_MAX, LabError, MotionLab
from app.scenes.lab_load import LabLoad
from app.sim.motionlab import R_G_D

__all__ = ["BLOCK", "PICKUP_SHIFT_B2", "simulate_lab"]

#: where the scripted operator picks the load up: the lab's work point moved this much in {b2} (m)
PICKUP_SHIFT_B2 = np.array([-0.125, -0.875, 0.0])
MOVE_AXIS = 1  # the move is along +y of {b2}, onto the deck
BLOCK = 200  # steps a compiled call takes at most (1 s at the PLC's 5 ms)
T_MAX = 600.0  # s


def _landing_spot(sc: TransferScenario, lab: MotionLab) -> np.ndarray:
    """The landing spot on EM1500's deck, in {b2} (z = 0): the pick-up point moved ``sc.move`` along the move."""
    land = lab.layout.work_point_b2 + PICKUP_SHIFT_B2 + np.eye(3)[MOVE_AXIS] * sc.move
    land[2] = 0.0
    return land


def _lab(sc: TransferScenario) -> tuple[MotionLab, VvmcScenario]:
    vv = VvmcScenario(
        hs=sc.hs, tp=sc.tp, spectrum=sc.spectrum, heading1=sc.heading, heading2=sc.target_heading,
        duration=T_MAX, dt=sc.dt, seed=sc.seed, rao=sc.rao,
    )  # fmt: skip
    lab = MotionLab(load_lab(vv.lab), at_work=True)
    _sources(vv, lab)
    if sc.mode == "off":
        lab.set_comau_mode("remote")
        lab.set_winch_mode("remote")
    else:
        lab.set_work_frame("level", _landing_spot(sc, lab))
        lab.load_lead = sc.lead
        lab.lead_shape = sc.lead and sc.mode == "antisway"
        lab.set_vvmc(True)
    try:
        lab.place_work_point(PICKUP_SHIFT_B2)
    except LabError as err:
        raise TransferError(f"lab: {err}") from None
    return lab, vv


def simulate_lab(sc: TransferScenario, progress=None, cancel=None, compiled: bool | None = None) -> TransferResult:
    """One transfer in the Motion-Lab (module text); the result has :data:`app.scenarios.transfer.COLUMNS`, with
    the TCP (the Comau's tool point) and the deck point in {d} axes (z down).  ``compiled``: the steps in blocks
    of :data:`BLOCK` compiled (:mod:`app.scenes.lab_transfer_kernels`) wherever the lab is in the steady state
    they cover (True; default where numba is), or every step through the objects (False: the reference)."""
    if sc.operator == "scripted":
        operator = ScriptedOperator(sc, axis=MOVE_AXIS)
    else:  # the lab's stick: x, y the Comau's tool speed, z and w the winch's
        w_speed = 0.2
        operator = StickFile.read(sc.operator, (REMOTE_TOOL_SPEED, w_speed, w_speed))
    lab, _ = _lab(sc)
    run = _LabRun(sc, lab, operator)
    use = ENABLED if compiled is None else bool(compiled)
    done_rows = 0
    while not run.operator.done and run.t < T_MAX:
        if cancel is not None and cancel():
            break
        if not (use and run.steady() and run.block(run.next_block)):
            run.step()
        n_rows = len(run.phases)
        if progress is not None and n_rows // 1000 > done_rows // 1000:
            progress(run.t, T_MAX)
        done_rows = n_rows
    return run.result()


class _NormalStream:
    """A generator's standard normals drawn ahead in blocks and served in its order: ``normal(0, σ, n)`` gives what
    the generator's own ``normal(0, σ, n)`` gives (numpy computes loc + σ·z from the same stream), and
    :meth:`ahead` shows the compiled steps the next draws without taking them."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.buf = np.empty(0)
        self.i = 0

    def ahead(self, n: int) -> np.ndarray:
        if self.i + n > self.buf.size:
            more = self.rng.standard_normal(max(4096, n))
            self.buf = np.concatenate([self.buf[self.i :], more])
            self.i = 0
        return self.buf[self.i : self.i + n]

    def take(self, n: int) -> None:
        self.i += n

    def normal(self, loc: float, scale: float, size: int) -> np.ndarray:
        z = self.ahead(size)
        self.take(size)
        return loc + scale * z


class _LabRun:
    """One lab transfer's loop: :meth:`step` one step through the objects (the reference), :meth:`block` up to n
    steps compiled (:func:`app.scenes.lab_transfer_kernels.transfer_steps`), each leaving the objects as the other
    would (tests/test_lab_transfer.py)."""

    def __init__(self, sc: TransferScenario, lab: MotionLab, operator) -> None:
        self.sc, self.lab, self.operator = sc, lab, operator
        layout = lab.layout
        self.load = LabLoad(lab)
        self.watch = LandingWatch()
        self.noise = _NormalStream(np.random.default_rng([sc.seed, 30_4]))
        self.swing = SwingControl(lab, self.noise) if sc.mode == "antisway" else None
        # the landing spot on the deck, in {b2}; the stick's frame for REMOTE: {b2} turned into {r} as in calm water
        self.land = _landing_spot(sc, lab)
        R_g_r = layout.T_world_n1[:3, :3] @ layout.T_b1_r[:3, :3]
        self.R_r_n2 = R_g_r.T @ layout.T_world_n2[:3, :3]
        self.R_g_n2 = layout.T_world_n2[:3, :3]  # the target frame's axes: EM1500's level neutral frame (z down)
        H2 = lab.platform_pose(1)
        self.cmd = self.R_g_n2.T @ (self.load.position_g() - (H2[:3, :3] @ self.land + H2[:3, 3]))
        self.rows: list = []
        self.phases: list[str] = []
        self.counts = [0, 0, 0]  # slack, snap, sideways steps
        self.t = 0.0
        self.off = np.zeros(2)
        self.next_block = BLOCK  # the steps the next compiled call is given (fewer after one cut short)

    # ------------------------------------------------------------------ the reference
    def step(self) -> None:
        """One step through the objects."""
        sc, lab, load, watch, dt = self.sc, self.lab, self.load, self.watch, self.sc.dt
        v = self.operator.command(self.t, dt, watch.touched)
        self.cmd = self.cmd + v * dt
        horizontal = np.array([v[0], v[1], 0.0])
        if sc.mode == "off":
            lab.tool_velocity_cmd = self.R_r_n2 @ horizontal
        else:
            lab.tool_velocity_cmd = R_B2_DECK @ horizontal
        lab.winch.speed_command = float(v[2])  # paying out lowers the load (MOTION_COMP: relative to the deck)
        lab.step(dt)
        self.t = lab.t
        load.step(dt)
        watch.step(load, load.deck_v, load.n_up)
        self.counts = [c + bool(f) for c, f in zip(self.counts, (watch.slack, watch.snap, watch.sideways), strict=True)]
        if self.swing is not None:  # on the deck, or slack, the wire's angle is no swing: the law rests
            self.swing.step(dt, in_play=not watch.touched and not watch.slack)
            self.off = lab.platform_pose(1)[:3, :3].T @ (lab.layout.T_world_n1[:3, :3] @ lab.tool_offset[0])
        H2 = lab.platform_pose(1)
        spot = H2[:3, :3] @ self.land + H2[:3, 3]  # the landing spot on the deck, in {g}
        load_t = self.R_g_n2.T @ (load.position_g() - spot)
        err = load_t - self.cmd
        e, ell = load.wire()
        swing_deg = math.degrees(math.acos(min(1.0, max(-1.0, e[2] / ell))))
        deck = R_G_D.T @ spot
        row = (
            self.t, *self.cmd, *load_t, math.sqrt(float(err @ err)), *(R_G_D.T @ lab.p_t_g), *deck,
            load.gap, watch.rel_speed, swing_deg, load.tension / load.static_tension(), load.contact_force / 1e3,
            load.length, self.off[0], self.off[1],
        )  # fmt: skip
        self.rows.append(row)
        self.phases.append(self.operator.phase)

    def result(self) -> TransferResult:
        parts, pending = [], []
        for r in self.rows:  # a step's row (a tuple) or a block's (an array)
            if isinstance(r, np.ndarray):
                if pending:
                    parts.append(np.array(pending, dtype=float))
                    pending = []
                parts.append(r)
            else:
                pending.append(r)
        if pending:
            parts.append(np.array(pending, dtype=float))
        data = np.concatenate(parts) if parts else np.zeros((0, len(COLUMNS)))
        res = TransferResult(self.sc, list(COLUMNS), data, self.phases)
        w = self.watch
        res.summary = summarise(res, self.operator, w.touch_speed, w.contacts, *self.counts)
        res.summary["work_point_limited"] = bool(self.lab.work_shift_limited)
        return res

    # ------------------------------------------------------------------ compiled
    def steady(self) -> bool:
        """Whether the lab is in the state :func:`transfer_steps` covers: no E-STOP, no sensors, no engagement;
        both platforms engaged (ramping in or steady) on wave sources; the Comau and the winch in REMOTE, or in
        MOTION_COMP on the level frame with the winch's target and the lead set up; one landing (no relift);
        everything compiled."""
        lab, swing = self.lab, self.swing
        if lab.frozen or lab.sensors is not None or lab.measured is not None or lab._engage is not None:
            return False
        if self.watch.relift or (lab._lead is not None and lab._lead.dt != self.sc.dt):
            return False
        if not (lab.use_kernels and self.load.use_kernels is not False and (swing is None or swing.use_kernels)):
            return False
        for p in lab.platforms:
            motion = getattr(p.source, "motion", None)
            if not (p.mode == "engaged" and not p.frozen and p.transition in ("", "engaging") and p.use_kernels):
                return False
            if p.source_name != "simulation" or motion is None or not motion.use_kernels:
                return False
        if swing is not None and swing.measurement != "angles":
            return False
        if swing is not None and lab.lead_ref_d is not None and not lab.load_lead:
            return False  # the swing law would take a lead's reference the steps do not keep
        if lab.comau_mode == "remote":
            return lab.winch.mode == "remote" and swing is None
        level = lab.comau_mode == "motion_comp" and lab.work_frame == "level" and lab.winch.mode == "motion_comp"
        return (
            level and lab.payload_target_b2 is not None and lab._level_load is not None
            and (lab._lead is not None or not lab.load_lead)
        )  # fmt: skip

    def block(self, n: int) -> int:
        """Up to ``n`` steps compiled (the operator's commands worked out ahead, the noise drawn ahead); the number
        taken (0: the next step needs the objects, :meth:`step`)."""
        watch, swing, dt = self.watch, self.swing, self.sc.dt
        ahead, touched, t0 = copy.copy(self.operator), watch.touched, self.t
        V, phases, t = [], [], t0
        while len(V) < n and not ahead.done and t < T_MAX:
            V.append(ahead.command(t, dt, touched))
            phases.append(ahead.phase)
            t = t + dt
        if not V:
            return 0
        V = np.ascontiguousarray(V, dtype=float)
        k = len(V)
        Z = np.ascontiguousarray(self.noise.ahead(5 * k).reshape(k, 5)) if swing is not None else np.zeros((k, 5))
        rows = np.empty((k, len(COLUMNS)))
        records, s = self._records()
        taken = tk.transfer_steps(*records, (V, Z), rows, s)
        self._write_back(s, records, taken)
        if taken and math.isnan(rows[taken - 1, 0]):
            raise LabError("a tool offset is a finite position and velocity (3 values each)")
        if swing is not None:
            self.noise.take(5 * taken)
        if taken == k:
            self.operator.__dict__.update(ahead.__dict__)
        elif taken:  # the operator again up to where the steps stopped (it saw what they saw)
            again, t = copy.copy(self.operator), t0
            for _ in range(taken):
                again.command(t, dt, touched)
                t = t + dt
            self.operator.__dict__.update(again.__dict__)
        # cut short (a reach check, a touch): the next call is given about twice what this one took
        self.next_block = BLOCK if taken == k else min(BLOCK, max(8, 2 * taken))
        if taken:
            self.rows.append(rows[:taken])
            self.phases.extend(phases[:taken])
            self.cmd = self.cmd.copy()
        return taken

    def _records(self) -> tuple[tuple, np.ndarray]:
        """The kernel's records (:mod:`app.scenes.lab_transfer_kernels`) and its scalars.  The arrays the steps
        change in place are made the objects' own first (the objects replace theirs step by step, so a fresh
        copy is shared with nothing)."""
        lab, load, watch, swing, sc = self.lab, self.load, self.watch, self.swing, self.sc
        f, wf, pd, lead = lab.joints, lab.winch.filter, lab.pendulum, lab._lead
        for name in ("tool_velocity_cmd", "work_shift", "work_shift_rate", "level_offset", "_c_dot"):
            setattr(lab, name, np.array(getattr(lab, name), dtype=float))
        lab.tool_offset = tuple(np.array(a, dtype=float) for a in lab.tool_offset)
        level = lab.comau_mode == "motion_comp"
        if level:
            lab._level_load = np.array(lab._level_load, dtype=float)
        if lab.lead_ref_d is not None:
            lab.lead_ref_d = tuple(np.array(a, dtype=float) for a in lab.lead_ref_d)
        reach = getattr(lab, "_reach_ok", None)
        if reach is not None:
            lab._reach_ok = np.array(reach, dtype=float)
        for name in ("_s", "_H2", "deck_v", "n_up"):
            setattr(load, name, np.array(getattr(load, name), dtype=float))
        self.cmd = np.array(self.cmd, dtype=float)
        has = lab.payload_target_b2 is not None
        state = (
            (f.x, f.v, f.a), (wf.x, wf.v, wf.a), lab.payload_target_b2 if has else lab._target,
            lab.tool_velocity_cmd, lab.work_shift, lab.work_shift_rate, lab.level_offset,
            lab._level_load if level else np.zeros(3), lab.tool_offset, lab._c_dot,
            lab.lead_ref_d if lab.lead_ref_d is not None else (np.zeros(3), np.zeros(3)),
            lab._reach_ok if reach is not None else np.zeros(3),
        )  # fmt: skip
        wire = (wf.lower, wf.upper, wf.speed, wf.accel, float(wf.tau))
        params = (lab._geometry, f.limits(), wire, (float(pd.damping), float(pd.g)), lab._guard_p)
        y = (lab._rates_buf, lab.p_t_n1, lab.p_t_g, lab.v_t_g, lab.a_t_g, lab.at_limit, *lab._out, lab.guard_report)
        platforms = tuple(
            (
                (p.filter.x, p.filter.v, p.filter.a),
                (p.filter.lower, p.filter.upper, p.filter.speed, p.filter.accel, float(p.filter.tau)),
                (p.model.a_n, p.model.b_b, *p.leg_band),
                (p.source.motion.w, *p.source.motion._parts, np.ascontiguousarray(p.source.scale, dtype=float)),
                float(p.ramp_time),
            )
            for p in lab.platforms
        )
        loads = (*load.state, load._s, load._H2, load.deck_v, load.n_up, load._p, float(load.radius))
        if swing is not None:
            ekf, law = swing.ekf, swing.law
            sw = (ekf.x, ekf.P, swing.tilt, swing.tilt_rate, law.p, law.v, law.a, np.zeros(2), swing._record)
            sw += (np.ascontiguousarray(swing.R_n1_d), float(swing.sigma_accel), float(swing.sigma_angle))
        else:
            sw = tk.no_swing()
        flags = (
            COMAU_MODES.index(lab.comau_mode), bool(level), bool(level), bool(level and lab.load_lead),
            bool(level and lab.load_lead and lead.shape), swing is not None, bool(swing is not None and swing.active),
        )  # fmt: skip
        lead_p = (float(lead.cap), float(lead.fade), float(lead.tau)) if lead is not None else (0.0, 1.0, 1.0)
        run = (
            flags, self.cmd, np.ascontiguousarray(self.land, dtype=float), np.ascontiguousarray(self.R_g_n2),
            np.ascontiguousarray(lab.layout.T_world_n1[:3, :3]), lab._T_world_n[1],
            np.ascontiguousarray(lab.layout.work_point_b2, dtype=float), WORK_SHIFT_MAX, float(sc.dt), *lead_p,
            float(G), float(lab.winch.spec["speed"]), np.ascontiguousarray(lab._R_d_n2),
            np.ascontiguousarray(lab.level_spot, dtype=float),
            (float(SLACK_FACTOR), float(SNAP_FACTOR), float(SIDEWAYS_SPEED), float(load.static_tension())),
            np.ascontiguousarray(self.R_r_n2),
        )  # fmt: skip
        s = np.zeros(tk.S)
        s[tk.S_T], s[tk.S_ALPHA], s[tk.S_BETA] = lab.t, pd.alpha, pd.beta
        s[tk.S_ALPHA_DOT], s[tk.S_BETA_DOT], s[tk.S_HAS_TARGET] = pd.alpha_dot, pd.beta_dot, has
        s[tk.S_WINCH_SPEED] = lab.winch.speed_command
        for k, p in enumerate(lab.platforms):
            i = tk.S_PLATFORM + 4 * k
            s[i : i + 4] = p.t_source, p.gain, p.transition == "engaging", p.leg_clamped
        if lead is not None:
            (x2, y2), (x1, y1) = lead._f
            s[tk.S_LEAD_T], s[tk.S_LEAD_A : tk.S_LEAD_A + 3] = lead.t, lead._a_cmd
            s[tk.S_LEAD_F : tk.S_LEAD_F + 4] = x2, y2, x1, y1
        s[tk.S_LEVEL_PAY], s[tk.S_LIMITED] = lab._level_pay, lab.work_shift_limited
        s[tk.S_RANGE_HELD] = lab._range_held
        s[tk.S_REACH_OK] = reach is not None
        s[tk.S_TENSION], s[tk.S_CONTACT_FORCE], s[tk.S_GAP] = load.tension, load.contact_force, load.gap
        s[tk.S_TOUCHED], s[tk.S_TOUCH_SPEED] = (
            watch.touched,
            math.nan if watch.touch_speed is None else watch.touch_speed,
        )
        s[tk.S_CONTACTS], s[tk.S_REL_SPEED] = watch.contacts, watch.rel_speed
        s[tk.S_IN_CONTACT] = watch.in_contact
        s[tk.S_REHIT], s[tk.S_SLACK], s[tk.S_SNAP], s[tk.S_SIDEWAYS] = (
            watch.rehit,
            watch.slack,
            watch.snap,
            watch.sideways,
        )
        s[tk.S_SLACK_N : tk.S_SLACK_N + 3] = self.counts
        if swing is not None:
            s[tk.S_L_PREV], s[tk.S_SATURATED], s[tk.S_NIS] = swing._L_prev, swing.law.saturated, swing.ekf.nis
            s[tk.S_LAW_ACTIVE] = swing.law.active
        s[tk.S_LOAD_L] = load._L
        return ((state, params, y), platforms, loads, sw, run), s

    def _write_back(self, s: np.ndarray, records: tuple, taken: int) -> None:
        """The scalars the steps changed, back into the objects (the arrays were changed in place)."""
        lab, load, watch, swing = self.lab, self.load, self.watch, self.swing
        pd, lead = lab.pendulum, lab._lead
        if not taken:  # stopped before its first step: nothing changed
            return
        lab.t = self.t = float(s[tk.S_T])
        pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot = (float(v) for v in s[tk.S_ALPHA : tk.S_BETA_DOT + 1])
        if s[tk.S_HAS_TARGET] and lab.payload_target_b2 is None:
            lab.payload_target_b2 = lab._target.copy()
        lab.winch.speed_command = float(s[tk.S_WINCH_SPEED])
        for k, p in enumerate(lab.platforms):
            i = tk.S_PLATFORM + 4 * k
            p.t_source, p.gain, p.leg_clamped = float(s[i]), float(s[i + 1]), bool(s[i + 3])
            if p.transition == "engaging" and not s[i + 2]:
                p.transition = ""
        if lead is not None and lab.load_lead and lab.comau_mode == "motion_comp":
            x2, y2, x1, y1 = (float(v) for v in s[tk.S_LEAD_F : tk.S_LEAD_F + 4])
            lead.t, lead._f = float(s[tk.S_LEAD_T]), ((x2, y2), (x1, y1))
            lead._a_cmd = tuple(float(v) for v in s[tk.S_LEAD_A : tk.S_LEAD_A + 3])
        lab._level_pay = float(s[tk.S_LEVEL_PAY])
        lab.work_shift_limited, lab._range_held = bool(s[tk.S_LIMITED]), bool(s[tk.S_RANGE_HELD])
        if s[tk.S_HAZARD_SET]:
            axis = int(s[tk.S_HAZ_AXIS])
            lab.work_hazard = (axis, float(s[tk.S_HAZ_GAP]), bool(s[tk.S_HAZ_SLOWED])) if axis >= 0 else None
        load.tension, load.contact_force, load.gap = (float(v) for v in s[tk.S_TENSION : tk.S_GAP + 1])
        load._L = float(s[tk.S_LOAD_L])
        watch.touched = bool(s[tk.S_TOUCHED])
        watch.touch_speed = None if math.isnan(s[tk.S_TOUCH_SPEED]) else float(s[tk.S_TOUCH_SPEED])
        watch.contacts, watch.rel_speed = int(s[tk.S_CONTACTS]), float(s[tk.S_REL_SPEED])
        watch.in_contact, watch.rehit, watch.slack = bool(s[tk.S_IN_CONTACT]), bool(s[tk.S_REHIT]), bool(s[tk.S_SLACK])
        watch.snap, watch.sideways = bool(s[tk.S_SNAP]), bool(s[tk.S_SIDEWAYS])
        self.counts = [int(v) for v in s[tk.S_SLACK_N : tk.S_SLACK_N + 3]]
        if swing is not None:
            swing._L_prev, swing.law.saturated, swing.ekf.nis = float(s[tk.S_L_PREV]), bool(s[tk.S_SATURATED]), float(
                s[tk.S_NIS])  # fmt: skip
            swing.law.active = bool(s[tk.S_LAW_ACTIVE])
            swing.ekf.innovation = records[3][7].copy()
            self.off = lab.platform_pose(1)[:3, :3].T @ (lab.layout.T_world_n1[:3, :3] @ lab.tool_offset[0])
        lab._rates = lab._rate_views  # as MotionLab._step_compiled leaves them
        lab.last = lab._compiled_sample(float(s[tk.S_H_ERR]), (float(s[tk.S_SAMPLE_ALPHA]), float(s[tk.S_SAMPLE_BETA])))
