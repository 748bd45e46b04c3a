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

import math

import numpy as np

from app.models.lab import load_lab
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
from app.scenes.crane_load import LandingWatch
from app.scenes.lab import R_B2_DECK, REMOTE_TOOL_SPEED, LabError, MotionLab
from app.scenes.lab_load import LabLoad
from app.sim.motionlab import R_G_D

__all__ = ["PICKUP_SHIFT_B2", "simulate_lab"]

#: where the scripted operator picks the load up: the lab's work point moved this much in {b2} (m)
PICKUP_SHIFT_B2 = np.array([-0.125, -0.875, 0.0])
MOVE_AXIS = 1  # the move is along +y of {b2}, onto the deck
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


def simulate_lab(sc: TransferScenario, progress=None, cancel=None) -> TransferResult:
    """One transfer in the Motion-Lab (module text); the result has :data:`app.scenarios.transfer.COLUMNS`, with
    the TCP (the Comau's tool point) and the deck point in {d} axes (z down)."""
    if sc.operator == "scripted":
        operator = ScriptedOperator(sc, axis=MOVE_AXIS)
    else:  # the lab's stick: x, y the Comau's tool speed, z and w the winch's
        w_speed = 0.2
        operator = StickFile.read(sc.operator, (REMOTE_TOOL_SPEED, w_speed, w_speed))
    lab, _ = _lab(sc)
    layout = lab.layout
    load = LabLoad(lab)
    watch = LandingWatch()
    rng = np.random.default_rng([sc.seed, 30_4])
    swing = SwingControl(lab, rng) if sc.mode == "antisway" else None
    # the landing spot on the deck, in {b2}; the stick's frame for REMOTE: {b2} turned into {r} as in calm water
    land = _landing_spot(sc, lab)
    R_g_r = layout.T_world_n1[:3, :3] @ layout.T_b1_r[:3, :3]
    R_r_n2 = R_g_r.T @ layout.T_world_n2[:3, :3]
    R_g_n2 = layout.T_world_n2[:3, :3]  # the target frame's axes: EM1500's level neutral frame (z down)
    H2 = lab.platform_pose(1)
    cmd = R_g_n2.T @ (load.position_g() - (H2[:3, :3] @ land + H2[:3, 3]))  # the load's commanded point there
    dt = sc.dt
    rows, phases = [], []
    slack_n = snap_n = sideways_n = 0
    t = 0.0
    off = np.zeros(2)
    while not operator.done and t < T_MAX:
        if cancel is not None and cancel():
            break
        v = operator.command(t, dt, watch.touched)
        cmd = cmd + v * dt
        horizontal = np.array([v[0], v[1], 0.0])
        if sc.mode == "off":
            lab.tool_velocity_cmd = R_r_n2 @ horizontal
        else:
            lab.tool_velocity_cmd = R_B2_DECK @ horizontal
        lab.winch.speed_command = float(v[2])  # paying out lowers the load (MOTION_COMP: relative to the deck)
        lab.step(dt)
        t = lab.t
        load.step(dt)
        watch.step(load, load.deck_v, load.n_up)
        slack_n, snap_n, sideways_n = slack_n + watch.slack, snap_n + watch.snap, sideways_n + watch.sideways
        if swing is not None:  # on the deck, or slack, the wire's angle is no swing: the law rests
            swing.step(dt, in_play=not watch.touched and not watch.slack)
            off = lab.platform_pose(1)[:3, :3].T @ (layout.T_world_n1[:3, :3] @ lab.tool_offset[0])
        H2 = lab.platform_pose(1)
        spot = H2[:3, :3] @ land + H2[:3, 3]  # the landing spot on the deck, in {g}
        load_t = R_g_n2.T @ (load.position_g() - spot)
        err = load_t - cmd
        e, ell = load.wire()
        swing_deg = math.degrees(math.acos(min(1.0, max(-1.0, e[2] / ell))))
        deck = R_G_D.T @ spot
        row = (
            t, *cmd, *load_t, math.sqrt(float(err @ err)), *(R_G_D.T @ lab.p_t_g), *deck,
            load.gap, watch.rel_speed, swing_deg, load.tension / load.static_tension(), load.contact_force / 1e3,
            load.length, off[0], off[1],
        )  # fmt: skip
        rows.append(row)
        phases.append(operator.phase)
        if progress is not None and len(rows) % 1000 == 0:
            progress(t, T_MAX)
    data = np.array(rows, dtype=float) if rows else np.zeros((0, len(COLUMNS)))
    res = TransferResult(sc, list(COLUMNS), data, phases)
    res.summary = summarise(res, operator, watch.touch_speed, watch.contacts, slack_n, snap_n, sideways_n)
    res.summary["work_point_limited"] = bool(lab.work_shift_limited)
    return res
