"""Compiled swing estimator and anti-swing law (issue 30): the EKF of :class:`app.control.antisway.SwingEkf`
as one step on records, to give the NumPy reference's numbers bit for bit.

Records (every array C-contiguous float64):

* ``x`` = (x̂ (4,), P (4, 4)): the estimate (α, β, α̇, β̇) and its covariance, in place;
* ``u`` = (a_t^d (3,), L_prev, L̇, z (2,) or (3,), L): the measured tool acceleration in {d}, the wire length
  over the prediction and its rate, the measurement and the wire length at it;
* ``p`` = (c, g, σ_a, σ_model, payload, σ_angle, σ_pos): payload False measures the angles (α, β), True the
  load minus the tool in {d}.

Returns (x', y) with y = (innovation, NIS).
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import _jit
from app.models.pendulum_kernels import _pendulum_derivative, pendulum_step

__all__ = ["ekf_block"]


@_jit
def _deriv(x, a, L, Ld, c, g):
    d0, d1, d2, d3 = _pendulum_derivative((x[0], x[1], x[2], x[3]), (a[0], a[1], a[2]), L, Ld, c, g)
    return np.array([d0, d1, d2, d3])


@_jit
def _predict(xh, P, a, L, Ld, p, dt):
    """SwingEkf.predict, the same operations in the same order."""
    c, g, sigma_accel, sigma_model = p[0], p[1], p[2], p[3]
    J = np.empty((4, 4))
    for j in range(4):
        e = np.zeros(4)
        e[j] = 1e-6
        J[:, j] = (_deriv(xh + e, a, L, Ld, c, g) - _deriv(xh - e, a, L, Ld, c, g)) / 2e-6
    Ja = np.empty((4, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1e-4
        Ja[:, j] = (_deriv(xh, a + e, L, Ld, c, g) - _deriv(xh, a - e, L, Ld, c, g)) / 2e-4
    Jdt = J * dt
    F = np.eye(4) + Jdt + (0.5 * Jdt) @ Jdt
    Fa = (np.eye(4) * dt + 0.5 * Jdt * dt) @ Ja
    n0, n1, n2, n3 = pendulum_step((xh[0], xh[1], xh[2], xh[3]), (a[0], a[1], a[2]), L, Ld, c, g, dt)
    xh[0], xh[1], xh[2], xh[3] = n0, n1, n2, n3
    q = sigma_model**2 * dt
    Qm = np.diag(np.array([q * dt * dt / 3, q * dt * dt / 3, q, q]))
    Qm[0, 2] = Qm[2, 0] = Qm[1, 3] = Qm[3, 1] = q * dt / 2
    P[:, :] = (F @ P) @ F.T + sigma_accel**2 * (Fa @ Fa.T) + Qm


@_jit
def _h_payload(x, L):
    sa, ca, sb, cb = math.sin(x[0]), math.cos(x[0]), math.sin(x[1]), math.cos(x[1])
    return L * np.array([-sa, ca * sb, ca * cb])


@_jit
def _update(xh, P, z, L, p):
    """SwingEkf.update, the same operations in the same order; returns (innovation, NIS)."""
    payload, sigma_angle, sigma_pos = p[4], p[5], p[6]
    if not payload:
        H = np.zeros((2, 4))
        H[0, 0] = H[1, 1] = 1.0
        Rm = sigma_angle**2 * np.eye(2)
        y = z - xh[:2].copy()
    else:
        H = np.zeros((3, 4))
        for j in range(2):
            e = np.zeros(4)
            e[j] = 1e-7
            H[:, j] = (_h_payload(xh + e, L) - _h_payload(xh - e, L)) / 2e-7
        Rm = sigma_pos**2 * np.eye(3)
        y = z - _h_payload(xh, L)
    S = (H @ P) @ H.T + Rm
    K = np.linalg.solve(S, H @ P).T  # F-ordered, as NumPy's: the same BLAS path (FMA order) for K @ y
    m = y.shape[0]
    for i in range(4):  # K @ y as NumPy sums it (numba's gemv call rounds differently)
        s = 0.0
        for j in range(m):
            s += K[i, j] * y[j]
        xh[i] = xh[i] + s
    IKH = np.eye(4) - K @ H
    P[:, :] = (IKH @ P) @ IKH.T + (K @ Rm) @ K.T
    w = np.linalg.solve(S, y)
    nis = 0.0
    for j in range(m):
        nis += y[j] * w[j]
    return y, nis


@_jit
def ekf_block(x, u, p, dt):
    """One EKF step: predict over dt with the measured tool acceleration, then correct with z (module text)."""
    xh, P = x
    a, L_prev, Ld, z, L = u
    _predict(xh, P, a, L_prev, Ld, p, dt)
    y, nis = _update(xh, P, z, L, p)
    return x, (y, nis)


@_jit
def _interp_gains(L, grid, K):
    """GainSchedule.gains for one plane: each of the 4 gains interpolated at L clipped to the grid."""
    Lc = min(max(L, grid[0]), grid[-1])
    k = np.empty(4)
    for j in range(4):
        k[j] = np.interp(Lc, grid, K[:, j])
    return k


@_jit
def _dot4(k, s0, s1, s2, s3):
    s = np.array([s0, s1, s2, s3])
    return -k @ s


@_jit
def law_block(x, u, p, dt):
    """AntiSwing.step (gain schedule on): x = (p, v, a) (2,) each, in place; u = (x̂ (4,), L, active);
    p = (grid (n,), K_α (n, 4), K_β (n, 4), a_max, offset_max).  Returns (x, (saturated,))."""
    pos, vel, acc = x
    xh, L, active = u
    grid, K_alpha, K_beta, a_max, p_max = p
    ka = _interp_gains(L, grid, K_alpha)
    kb = _interp_gains(L, grid, K_beta)
    finite = True
    for i in range(4):
        if not math.isfinite(xh[i]):
            finite = False
    cmd = np.empty(2)
    if active and finite:
        cmd[0] = _dot4(ka, xh[0], xh[2], pos[0], vel[0])
        cmd[1] = _dot4(kb, xh[1], xh[3], pos[1], vel[1])
    else:
        cmd[0] = -ka[2:] @ np.array([pos[0], vel[0]])
        cmd[1] = -kb[2:] @ np.array([pos[1], vel[1]])
    saturated = abs(cmd[0]) > a_max or abs(cmd[1]) > a_max
    for i in range(2):
        cmd[i] = min(max(cmd[i], -a_max), a_max)
        vel[i] = vel[i] + cmd[i] * dt
    for i in range(2):
        pos[i] = pos[i] + vel[i] * dt
    for i in range(2):
        if abs(pos[i]) > p_max:
            pos[i] = math.copysign(p_max, pos[i])
            if vel[i] * pos[i] > 0:
                vel[i] = 0.0
            saturated = True
        acc[i] = cmd[i]
    return x, (saturated,)


@_jit
def swing_control_block(x, u, p, dt):
    """The estimator, the quasi-static tilt and the law in one step (see :data:`app.control.antisway.SWING_CONTROL`):
    x = (x̂, P, tilt, tilt_rate, p, v, a, L_prev), u = (a_t^d, z, L, L̇, active), p = (EKF record, law record,
    g, τ_tilt).  Returns (x', (p_d (3,), v_d (3,), saturated, innovation, NIS)) with p_d, v_d in {d}."""
    xh, P, tilt, tilt_rate, lp, lv, la, L_prev = x
    a_d, z, L, Ld, active = u
    ekf_p, law_p, g, tau = p
    _predict(xh, P, a_d, L_prev, Ld, ekf_p, dt)
    y, nis = _update(xh, P, z, L, ekf_p)
    k = 1.0 - math.exp(-dt / tau)
    q0 = (a_d[0] - la[0]) / g
    q1 = (-(a_d[1] - la[1])) / g
    t0 = tilt[0] + k * (q0 - tilt[0])
    t1 = tilt[1] + k * (q1 - tilt[1])
    tilt_rate[0], tilt_rate[1] = (t0 - tilt[0]) / dt, (t1 - tilt[1]) / dt
    tilt[0], tilt[1] = t0, t1
    xs = np.array([xh[0] - t0, xh[1] - t1, xh[2] - tilt_rate[0], xh[3] - tilt_rate[1]])
    _, (saturated,) = law_block((lp, lv, la), (xs, L, active), law_p, dt)
    p_d = np.array([lp[0], lp[1], 0.0])
    v_d = np.array([lv[0], lv[1], 0.0])
    return (xh, P, tilt, tilt_rate, lp, lv, la, L), (p_d, v_d, saturated, y, nis)


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) the kernels as :class:`app.scenarios.swing.SwingControl` and the
    blocks call them (for :func:`app.warmup.warm_up`)."""
    z2, z3, z4, eye4 = np.zeros(2), np.zeros(3), np.zeros(4), np.eye(4)
    ekf_p = (0.1, 9.81, 0.05, 1e-3, False, 0.01, 0.005)
    law_p = (np.ones(2), np.zeros((2, 4)), np.zeros((2, 4)), 2.0, 0.3)
    x = (z4.copy(), eye4.copy(), z2.copy(), z2.copy(), z2.copy(), z2.copy(), z2.copy(), 3.0)
    return [
        lambda: ekf_block((z4.copy(), eye4.copy()), (z3, 3.0, 0.0, z2, 3.0), ekf_p, 0.005),
        lambda: law_block((z2.copy(), z2.copy(), z2.copy()), (z4, 3.0, False), law_p, 0.005),
        lambda: swing_control_block(x, (z3, z2, 3.0, 0.0, False), (ekf_p, law_p, 9.81, 0.2), 0.005),
    ]
