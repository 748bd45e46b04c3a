"""Compiled vessel motion at one instant (the per-step source of a wave-driven Stewart platform).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path); :meth:`app.marine.vessel.VesselMotion.eta_derivatives` stays the reference, tested equal in
``tests/test_sim_kernels.py``.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit

__all__ = ["ENABLED", "body_velocities", "vessel_motion"]


@_jit
def vessel_motion(w, c0_re, c0_im, c1_re, c1_im, t, scale):
    """η(t) and η̇(t) (6,) of a sea of regular components (module doc of :mod:`app.marine.vessel`),
    each times ``scale`` per DOF:

        η_j(t) = Re Σ_k c_jk e^{iω_k t},   η̇_j(t) = Re Σ_k (iω_k c_jk) e^{iω_k t}

    with c_jk = a_k H_j(ω_k, β_k) e^{iε_k} (``c0``) and iω_k c_jk (``c1``), each given as real and
    imaginary parts (6, n): Re(e^{iωt} c) = cos(ωt) Re c − sin(ωt) Im c.
    """
    n = w.shape[0]
    cos_wt, sin_wt = np.empty(n), np.empty(n)
    for k in range(n):
        arg = t * w[k]
        cos_wt[k], sin_wt[k] = math.cos(arg), math.sin(arg)
    eta, eta_dot = np.empty(6), np.empty(6)
    for j in range(6):
        e, d = 0.0, 0.0
        for k in range(n):
            e += cos_wt[k] * c0_re[j, k] - sin_wt[k] * c0_im[j, k]
            d += cos_wt[k] * c1_re[j, k] - sin_wt[k] * c1_im[j, k]
        eta[j], eta_dot[j] = e * scale[j], d * scale[j]
    return eta, eta_dot


@_jit
def body_velocities(eta, deta, ddeta):
    """ν and ν̇ in {b} from η, η̇, η̈, each (n, 6): :func:`app.marine.vessel.body_velocities` (Fossen
    2011, eqs. 2.18, 2.29, 2.40) row by row, the same formulas in the same order.

    R = Rz(ψ) Ry(θ) Rx(φ);  v = Rᵀ ṗ;  ω = (φ̇ − sθ ψ̇,  cφ θ̇ + cθ sφ ψ̇,  −sφ θ̇ + cθ cφ ψ̇);
    v̇ = Rᵀ p̈ − ω × v;  ω̇ the time derivative of ω."""
    n = eta.shape[0]
    nu, nu_dot = np.empty((n, 6)), np.empty((n, 6))
    for i in range(n):
        phi, th, psi = eta[i, 3], eta[i, 4], eta[i, 5]
        dphi, dth, dpsi = deta[i, 3], deta[i, 4], deta[i, 5]
        sf, cf, st, ct = math.sin(phi), math.cos(phi), math.sin(th), math.cos(th)
        sp, cp = math.sin(psi), math.cos(psi)
        R = np.array(
            [
                [cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf],
                [sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf],
                [-st, ct * sf, ct * cf],
            ]
        )
        p = dphi - st * dpsi
        q = cf * dth + ct * sf * dpsi
        r = -sf * dth + ct * cf * dpsi
        for j in range(3):
            nu[i, j] = R[0, j] * deta[i, 0] + R[1, j] * deta[i, 1] + R[2, j] * deta[i, 2]
        vx, vy, vz = nu[i, 0], nu[i, 1], nu[i, 2]
        a = np.empty(3)
        for j in range(3):
            a[j] = R[0, j] * ddeta[i, 0] + R[1, j] * ddeta[i, 1] + R[2, j] * ddeta[i, 2]
        nu_dot[i, 0] = a[0] - (q * vz - r * vy)
        nu_dot[i, 1] = a[1] - (r * vx - p * vz)
        nu_dot[i, 2] = a[2] - (p * vy - q * vx)
        nu[i, 3], nu[i, 4], nu[i, 5] = p, q, r
        ddphi, ddth, ddpsi = ddeta[i, 3], ddeta[i, 4], ddeta[i, 5]
        nu_dot[i, 3] = ddphi - st * ddpsi - ct * dth * dpsi
        nu_dot[i, 4] = cf * ddth - sf * dphi * dth + ct * sf * ddpsi + (-st * dth * sf + ct * cf * dphi) * dpsi
        nu_dot[i, 5] = -sf * ddth - cf * dphi * dth + ct * cf * ddpsi + (-st * dth * cf - ct * sf * dphi) * dpsi
    return nu, nu_dot


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel of this file with the argument types its
    callers pass (for :func:`app.warmup.warm_up`)."""
    ones = np.ones(6)
    return [
        lambda: vessel_motion(np.ones(2), *(np.ones((6, 2)) for _ in range(4)), 0.5, ones),
        lambda: body_velocities(np.ones((2, 6)), np.ones((2, 6)), np.ones((2, 6))),
    ]
