"""The motion predictor's prediction compiled (:mod:`app.control.predict`): the AR model's rows applied to the
history and the cubic between the grid points, for every channel at once.

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted path); the
reference is :meth:`app.control.predict.MotionPredictor.predict`'s NumPy code, tested equal on the same inputs
(``tests/test_predict.py``).
"""

from __future__ import annotations

import numpy as np

from app.models.kernels import ENABLED, _jit

__all__ = ["ENABLED", "ar_predict", "warm_up_steps", "window_share", "within_share"]


@_jit
def ar_predict(ring, k, lags, mu, G, step, h, out):
    """The prediction at horizons ``h`` (n,) [s, the average's delay included] into ``out`` (n, m).

    ring (L, m): the averaged samples, the newest at ring[k % L]; lags (p + 2,): the history's ages in samples,
    newest first; mu (m,), G (m, H, p): the fit; step: Δ [s].  Only the grid points the horizons need are computed
    (the path −Δ, 0, Δ, …: the two newest samples, then μ + G_j x), then the Catmull–Rom cubic through them."""
    L, m = ring.shape
    p = G.shape[2]
    H = G.shape[1]
    top = 0.0
    for i in range(h.shape[0]):
        top = max(top, h[i])
    need = min(H, int(top / step) + 2)  # the grid points ahead the cubic reaches
    path = np.empty(need + 2)
    x = np.empty(p)
    for c in range(m):
        for i in range(p):
            x[i] = ring[(k - lags[i]) % L, c] - mu[c]
        path[0] = ring[(k - lags[1]) % L, c]
        path[1] = ring[(k - lags[0]) % L, c]
        for j in range(need):
            acc = 0.0
            for i in range(p):
                acc += G[c, j, i] * x[i]
            path[2 + j] = mu[c] + acc
        for r in range(h.shape[0]):
            s = h[r] / step + 1.0  # in grid units from −Δ
            i0 = int(np.floor(s))
            i0 = min(max(i0, 1), need - 1)
            u = s - i0
            p0, p1, p2, p3 = path[i0 - 1], path[i0], path[i0 + 1], path[i0 + 2]
            out[r, c] = p1 + 0.5 * u * (p2 - p0 + u * (2 * p0 - 5 * p1 + 4 * p2 - p3 + u * (3 * (p1 - p2) + p3 - p0)))


@_jit
def within_share(path, errors, half_width):
    """The share of the rows of ``errors`` (draws, J) for which |path + row| ≤ half_width at every one of the J
    points: the Monte Carlo of :meth:`app.control.predict.MotionPredictor.window_probability` (its NumPy
    reference, tested equal), each draw left at its first point outside (looked at in order: from the last point,
    where the errors are largest, it was slower on most draws, which stay inside: 33 against 19 µs)."""
    n, J = errors.shape
    inside = 0
    for i in range(n):
        ok = True
        for j in range(J):
            if not abs(path[j] + errors[i, j]) <= half_width:  # NaN is outside, as in the reference
                ok = False
                break
        if ok:
            inside += 1
    return inside / n


@_jit
def window_share(ring, k, lags, mu_c, G_c, channel, errors, half_width):
    """:meth:`app.control.predict.MotionPredictor.window_probability` in one call: channel ``channel``'s predicted
    deviations from its mean μ_c at the J grid steps of ``G_c`` (J, p) from the history in ``ring`` (as
    :func:`ar_predict`), and the share of the error draws (draws, J) that keep them within ±half_width."""
    L = ring.shape[0]
    J, p = G_c.shape
    x = np.empty(p)
    for i in range(p):
        x[i] = ring[(k - lags[i]) % L, channel] - mu_c
    path = np.empty(J)
    for j in range(J):
        acc = 0.0
        for i in range(p):
            acc += G_c[j, i] * x[i]
        path[j] = acc
    return within_share(path, errors, half_width)


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) this file's kernel with its callers' argument types."""
    ring, lags, mu, G = np.zeros((20, 2)), np.arange(4) * 2, np.zeros(2), np.zeros((2, 6, 2))
    return [
        lambda: ar_predict(ring, 7, lags, mu, G, 0.5, np.array([0.2, 1.0]), np.empty((2, 2))),
        lambda: within_share(np.zeros(3), np.zeros((4, 3)), 1.0),
        lambda: window_share(ring, 7, lags, 0.0, np.zeros((3, 2)), 0, np.zeros((4, 3)), 1.0),
    ]
