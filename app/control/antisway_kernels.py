"""Compiled swing estimator (issue 30, item 1 — work in progress): the EKF of :class:`app.control.antisway.SwingEkf`
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
