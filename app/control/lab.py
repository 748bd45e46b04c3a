"""The Motion-Lab's controllers as blocks (:mod:`app.models.block`): the Comau's modes and the winch's heave
compensation (Motion-Lab paper §§4–6).

* :data:`COMAU_LAW`: SETTLED (to the park joints at a quarter speed), REMOTE (the operator's tool velocity
  through q̇ = J⁺ ṗ, eq. 21) and MOTION_COMP (VVMC: the work point fixed on EM1500, eqs. 54–56 inverted for the
  tool point in the robot base, the analytic IK of eqs. 7–20 and the feed-forward q̇ = J⁺ ṗ_t^r of eq. 21),
  or BRAKE (HOLD, E-STOP).  Its output is the joint command of the drives (:data:`app.sim.motionlab.COMAU_DRIVES`).
* :data:`WINCH_LAW`: active heave compensation, the wire length that keeps the load's height fixed relative
  to EM1500 (with the relative vertical speed as feed-forward), or the operator's speed; its output is the
  length reference of the drum (:data:`app.sim.motionlab.WINCH_DRUM`).

The functions here are the NumPy references of the compiled :mod:`app.control.lab_kernels`, on the same
records (tested equal in ``tests/test_blocks.py``).  A controller sees the platforms as its sensor reports
them: ``view`` = (η1, η̇1, R1, Ṙ1, η2, η̇2, R2, Ṙ2).
"""

from __future__ import annotations

import math

import numpy as np

from app.control import lab_kernels
from app.control.lab_kernels import BRAKE, MOTION_COMP, REMOTE, SETTLED
from app.models.block import Block
from app.models.closed_form import ComauArm
from app.models.comau import ComauKinematics, nearest_ik

__all__ = ["BRAKE", "COMAU_LAW", "MOTION_COMP", "REMOTE", "SETTLED", "WINCH_LAW"]


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
