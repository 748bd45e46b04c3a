"""Compiled vessel motion at one instant (the per-step source of a wave-driven Stewart platform).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted
path); :meth:`app.marine.vessel.VesselMotion.eta_derivatives` stays the reference, tested equal in
``tests/test_sim_kernels.py``.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _jit

__all__ = ["ENABLED", "vessel_motion"]


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
