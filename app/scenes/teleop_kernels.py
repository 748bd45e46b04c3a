"""The teleop scene's hazard guard for one tick, compiled: the controller's scaling
(:func:`app.control.guard_kernels.guard_step`) and the safe-braking rule, which predicts the plant's servo
(:func:`app.sim.kernels.actuator_block`) — the scene's floor, where a controller and its plant meet (the
controllers and plants never import each other: pyproject.toml's import contracts).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` runs the same code interpreted).
"""

from __future__ import annotations

import math

import numpy as np

from app.control.guard_kernels import _clearances, guard_step, warm_up_records
from app.models.kernels import ENABLED, _jit
from app.sim.kernels import actuator_block

__all__ = ["ENABLED", "guard_tick", "warm_up_steps"]


@_jit
def _stopping_point(q, qdot, accel, lower, upper, dt):
    """Where the joints come to rest braking at their acceleration limits from now (app.sim.actuators'
    ``braking_distance``, within the limits)."""
    n = q.shape[0]
    out = np.empty(n)
    for i in range(n):
        d = 0.0
        a = accel[i]
        if np.isfinite(a) and a > 0.0:
            h = a * dt
            s = abs(qdot[i])
            m = math.floor(s / h)
            d = max(dt * (m * s - 0.5 * h * m * (m + 1.0)), 0.0)
            if qdot[i] < 0.0:
                d = -d
        out[i] = min(max(q[i] + d, lower[i]), upper[i])
    return out


@_jit
def _braking_least(robot, model, q, v, accel, pts, buf, least):
    """Every clearance's least value over five points of the joints' braking from (q, v), each joint at its
    acceleration limit until it stops, into ``least``."""
    n = q.shape[0]
    T = 0.0
    for i in range(n):
        if np.isfinite(accel[i]) and accel[i] > 0.0:
            T = max(T, abs(v[i]) / accel[i])
    qs = np.empty(n)
    for k in range(5):
        t = T * k / 4.0
        for i in range(n):
            a = accel[i]
            if np.isfinite(a) and a > 0.0:
                tau = min(t, abs(v[i]) / a)
                sgn = 1.0 if v[i] > 0.0 else (-1.0 if v[i] < 0.0 else 0.0)
                qs[i] = q[i] + v[i] * tau - 0.5 * a * sgn * tau * tau
            else:
                qs[i] = q[i]
        _clearances(robot, model, qs, pts, buf, 0)
        for c in range(least.shape[0]):
            if k == 0 or buf[c] < least[c]:
                least[c] = buf[c]


@_jit
def _proven_clear(now, row_lever, path, hard):
    """Whether every clearance stays above ``hard`` from q, through one servo step to q1 and the joints' braking
    from there (path: q, q1, v1, accel; the path :func:`_braking_least` samples), by the clearances' Lipschitz
    bound (``HazardGuard.row_lever``): along that path each joint moves one way per part, |q1 − q| then its
    braking distance v1²/2a (none where its acceleration is not finite: :func:`_braking_least` holds it), so a
    clearance changes by at most Σ_j W[c, j]·(|q1_j − q_j| + v1_j²/2a_j).  True only where every clearance's
    bound is met with 1 nm to spare (NaN never is)."""
    q, q1, v1, accel = path
    n = q.shape[0]
    travel = np.empty(n)
    for i in range(n):
        t = abs(q1[i] - q[i])
        a = accel[i]
        if np.isfinite(a) and a > 0.0:
            t += v1[i] * v1[i] / (2.0 * a)
        travel[i] = t
    for c in range(now.shape[0]):
        worst = now[c]
        for i in range(n):
            worst -= row_lever[c, i] * travel[i]
        if not worst > hard + 1e-9:
            return False
    return True


@_jit
def _keeps_clear(robot, model, plant, ref, work, floor):
    """Whether, after one servo step towards ``ref`` (plant: the servo's state x, parameters p, dt and the joints'
    accelerations), the joints can still brake to rest with every clearance at least ``floor`` (work: scratch
    points and clearances, and ``after``, which gets each clearance's least over the braking path)."""
    x, p, dt, accel = plant
    pts, buf, after = work
    (q1, v1, _), _ = actuator_block(x, (ref,), p, dt)
    _braking_least(robot, model, q1, v1, accel, pts, buf, after)
    for c in range(after.shape[0]):  # noqa: SIM110 (a loop: numba compiles no generator, and NaN passes as before)
        if after[c] < floor[c] - 1e-9:
            return False
    return True


@_jit
def guard_tick(robot, chain, model, servo, q_ref, dq, settings, report):
    """One tick of the teleop engine's hazard guard (``Session._guarded``) in one call: the joint reference
    ``q_ref`` moved by the step ``dq``, scaled (:func:`guard_step`) and supervised, returned.

    servo: the joint actuators' state and parameters (q, q̇, q̈, lower, upper, speed, accel, τ, dt), each
    joint's lever [m/rad] (:meth:`app.control.guard.HazardGuard.margin`) and each clearance's per joint
    (``HazardGuard.row_lever``).  The scaling's margin is how far the arm
    can be from the reference: Σ lever |q_ref − q_stop| (q_stop the joints' stopping point).  The supervision
    (safe braking): the new reference is kept if, after one servo step towards it, the joints can still brake to
    rest with every capsule clearance at least ``hard`` (settings[9]) — or, where the braking the joints can do now
    leaves less, at least that; else the command planned within the servo's reach (every joint's speed moved
    towards the command's by one share, the largest one tick of acceleration allows each, and the reference
    q + τ·v that asks the servo for exactly that speed) if it passes the same test; else the reference nearer
    the stopping point that the servo follows in proportion (each joint's change of speed within its acceleration
    limit) if it passes; else the stopping
    point (the joints brake now; the caller holds that reference while they brake: recomputed each tick it would
    move a tick's travel ahead of a servo that brakes towards it).  The check's five clearance evaluations are
    skipped where a bound proves it would pass (:func:`_proven_clear`: the clearances' Lipschitz bounds over the
    step and its braking), the same answer without them.

    report (8,): :func:`guard_step`'s six, then what the supervision did (0 kept, 1 gentler, 2 braked) and the
    clearance it acted for (its index among the pairs then the floor's, −1 none)."""
    q, qdot, qddot, lower, upper, speed, accel, tau, dt, lever, row_lever = servo
    n = q.shape[0]
    q_stop = _stopping_point(q, qdot, accel, lower, upper, dt)
    margin = 0.0
    for i in range(n):
        margin += lever[i] * abs(q_ref[i] - q_stop[i])
    st = settings.copy()
    st[8] = margin
    step = guard_step(robot, chain, model, (lower, upper), q_ref, dq, st, report)
    new = np.empty(n)
    for i in range(n):
        new[i] = min(max(q_ref[i] + step[i], lower[i]), upper[i])
    report[6] = 0.0
    report[7] = -1.0
    caps, pairs, plane_caps = model[0], model[2], model[4]
    m = pairs.shape[0] + plane_caps.shape[0]
    if m == 0:
        return new
    pts = np.empty((caps.shape[0], 2, 3))
    now = np.empty(m)
    _clearances(robot, model, q, pts, now, 0)
    hard = settings[9]
    x = (q, qdot, qddot)
    p = (lower, upper, speed, accel, tau)
    (q1, v1, _), _ = actuator_block(x, (new,), p, dt)
    if _proven_clear(now, row_lever, (q, q1, v1, accel), hard):
        return new  # the check below would pass: no clearance can fall to ``hard`` on the step or its braking
    buf = np.empty(m)
    after = np.empty(m)
    _braking_least(robot, model, q1, v1, accel, pts, buf, after)
    ok = True
    for c in range(m):
        if after[c] < hard:
            ok = False
    if ok:
        return new
    floor = np.empty(m)
    _braking_least(robot, model, q, qdot, accel, pts, buf, floor)  # the braking the joints can do now
    worst, worst_c = 0.0, -1
    for c in range(m):
        floor[c] = min(hard, floor[c])
        if after[c] - floor[c] < worst:
            worst, worst_c = after[c] - floor[c], c
    if worst_c < 0 or worst >= -1e-9:
        return new
    report[7] = float(worst_c)
    # the command planned within the servo's reach: every joint's speed moved towards the command's by the same
    # share of its change, the largest one tick of each joint's acceleration allows, and the reference that asks
    # the servo for exactly that (e = τ·v: the servo's proportional law).  Not the command's reference, whose lead
    # still carries the arm's last motion (into the floor, sliding along it: the Panda's stuck tool of the bench)
    share = 1.0
    for i in range(n):
        change = abs((new[i] - q_ref[i]) / dt - qdot[i])
        if change > 0.0 and np.isfinite(accel[i]):
            share = min(share, accel[i] * dt / change)
    planned = np.empty(n)
    for i in range(n):
        v1 = qdot[i] + share * ((new[i] - q_ref[i]) / dt - qdot[i])
        v1 = min(max(v1, -speed[i]), speed[i])
        planned[i] = min(max(q[i] + tau * v1, lower[i]), upper[i])
    if _keeps_clear(robot, model, (x, p, dt, accel), planned, (pts, buf, after), floor):
        report[6] = 1.0
        return planned
    # nearer the stopping point: the reference the servo follows in proportion
    alpha = 1.0
    for i in range(n):
        need = abs(new[i] - q_stop[i]) / tau
        if need > 0.0 and np.isfinite(accel[i]):
            alpha = min(alpha, accel[i] * dt / need)
    if 0.0 < alpha < 1.0:
        gentle = np.empty(n)
        for i in range(n):
            gentle[i] = q_stop[i] + alpha * (new[i] - q_stop[i])
        if _keeps_clear(robot, model, (x, p, dt, accel), gentle, (pts, buf, after), floor):
            report[6] = 1.0
            return gentle
    report[6] = 2.0
    return q_stop


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) :func:`guard_tick` with the argument types
    :func:`app.scenes.teleop_guard.guard_tick` passes (for :func:`app.warmup.warm_up`): a three-link chain."""
    robot, chain, model, _, settings, q, dq = warm_up_records()
    n, ones = q.size, np.ones(q.size)
    m = model[2].shape[0] + model[4].shape[0]
    servo = (q, np.zeros(n), np.zeros(n), -ones, ones, ones, np.full(n, 10.0), 0.05, 0.002, ones, np.ones((m, n)))
    return [lambda: guard_tick(robot, chain, model, servo, q, dq, settings, np.zeros(8))]
