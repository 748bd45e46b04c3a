"""The teleop scene's hazard guard for one tick (issue 32, item 5): the controller's direction-aware scaling
(:class:`app.control.guard.HazardGuard`) and the safe-braking rule on the plant's servo
(:class:`app.sim.actuators.JointActuators`), one compiled call (:func:`app.scenes.teleop_kernels.guard_tick`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.control import guard_kernels as gk
from app.control.guard import GuardReport, HazardGuard
from app.scenes import teleop_kernels as tk
from app.sim.actuators import JointActuators

__all__ = ["guard_tick"]


def guard_tick(
    guard: HazardGuard, q_ref: ArrayLike, dq: ArrayLike, act: JointActuators, dt: float
) -> tuple[NDArray[np.float64], GuardReport, int]:
    """The reference ``q_ref`` moved by ``dq`` scaled along the directions that bring a hazard nearer, with the
    capsules' margin for how far the servo ``act`` lags it, then kept only if the joints can still brake clear after
    it (else a gentler one, else the joints' stopping point).  Returns the new reference, the report and what the
    safe-braking rule did (0 kept, 1 gentler, 2 braked)."""
    servo = (
        act.q, act.qdot, act.qddot, act.lower, act.upper, act.speed, act.accel, act.tau, float(dt), guard.lever,
        guard.row_lever,
    )  # fmt: skip
    rep = guard.tick_report
    new = tk.guard_tick(
        guard.robot.kernel_record, guard._chain, guard._model, servo, np.ascontiguousarray(q_ref, dtype=float),
        np.ascontiguousarray(dq, dtype=float), guard._settings, rep,
    )  # fmt: skip
    action = int(rep[6])
    if action == 2 and rep[7] >= 0:  # braked for a clearance: name it
        k = int(rep[7])
        P = len(guard.pairs)
        kind, idx = (gk.PAIR, k) if k < P else (gk.PLANE, k - P)
        value = float(guard.values(act.q)[1 + k])
        report = GuardReport(kind="collision", name=guard.hazard_name(kind, idx), value=value, slowed=True, scale=0.0)
        return new, report, action
    return new, guard.report(rep[:6]), action
