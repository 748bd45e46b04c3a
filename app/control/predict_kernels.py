"""The motion predictor's prediction compiled (:mod:`app.control.predict`): the AR model's rows applied to the
history and the cubic between the grid points, for every channel at once.

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the interpreted path); the
reference is :meth:`app.control.predict.MotionPredictor.predict`'s NumPy code, tested equal on the same inputs
(``tests/test_predict.py``).
"""

from __future__ import annotations

import numpy as np

from app.models.kernels import ENABLED, _jit

__all__ = [
    "ENABLED", "ar_predict", "ring_update", "warm_up_steps", "window_path", "window_share", "within_count",
    "within_share",
]  # fmt: skip


@_jit
def ring_update(ring, raw, k, y):
    """:meth:`app.control.predict.MotionPredictor.update`'s bookkeeping in one call (its NumPy reference, tested
    equal): sample number ``k`` (counted from 1) ``y`` (m,) into the last Δ's samples ``raw`` (decimate, m) at
    k % decimate, and their average — of the first k < decimate at the start — into ``ring`` (L, m) at k % L, summed
    in the reference's order (the newest slot's row last within each pass of the rows).  False, and nothing
    written, when a value of ``y`` is not finite."""
    m = y.shape[0]
    for c in range(m):
        if not np.isfinite(y[c]):
            return False
    dec = raw.shape[0]
    L = ring.shape[0]
    r = k % dec
    for c in range(m):
        raw[r, c] = y[c]
    slot = k % L
    if k >= dec:
        for c in range(m):
            acc = 0.0
            for i in range(dec):
                acc += raw[i, c]
            ring[slot, c] = acc / dec
    else:  # the start: the mean of the first k, newest first (the reference's _mean_raw)
        for c in range(m):
            acc = 0.0
            for i in range(k):
                acc += raw[(k - i) % dec, c]
            ring[slot, c] = acc / k
    return True


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
def within_count(path, errors, lo, hi, half_width):
    """How many of the rows ``lo`` … ``hi`` − 1 of ``errors`` (draws, J) keep |path + row| ≤ half_width at every one
    of the J points: the Monte Carlo of :meth:`app.control.predict.MotionPredictor.window_probability` (its NumPy
    reference, tested equal) over a share of its draws (the engine's lift window spreads them over ticks), each
    draw left at its first point outside (looked at in order: from the last point, where the errors are largest,
    it was slower on most draws, which stay inside: 33 against 19 µs for 2000)."""
    J = errors.shape[1]
    inside = 0
    for i in range(lo, hi):
        ok = True
        for j in range(J):
            if not abs(path[j] + errors[i, j]) <= half_width:  # NaN is outside, as in the reference
                ok = False
                break
        if ok:
            inside += 1
    return inside


@_jit
def within_share(path, errors, half_width):
    """The share of all the rows of ``errors`` that :func:`within_count` counts."""
    n = errors.shape[0]
    return within_count(path, errors, 0, n, half_width) / n


@_jit
def window_path(ring, k, lags, mu_c, G_c, channel):
    """Channel ``channel``'s predicted deviations from its mean μ_c at the J grid steps of ``G_c`` (J, p) from the
    history in ``ring`` (as :func:`ar_predict`)."""
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
    return path


@_jit
def window_share(ring, k, lags, mu_c, G_c, channel, errors, half_width):
    """:meth:`app.control.predict.MotionPredictor.window_probability` in one call: :func:`window_path`, then the
    share of the error draws (draws, J) that keep it within ±half_width (:func:`within_share`)."""
    return within_share(window_path(ring, k, lags, mu_c, G_c, channel), errors, half_width)


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) this file's kernel with its callers' argument types."""
    ring, lags, mu, G = np.zeros((20, 2)), np.arange(4) * 2, np.zeros(2), np.zeros((2, 6, 2))
    return [
        lambda: ar_predict(ring, 7, lags, mu, G, 0.5, np.array([0.2, 1.0]), np.empty((2, 2))),
        lambda: within_share(np.zeros(3), np.zeros((4, 3)), 1.0),
        lambda: ring_update(ring, np.zeros((2, 2)), 7, np.zeros(2)),
        lambda: window_share(ring, 7, lags, 0.0, np.zeros((3, 2)), 0, np.zeros((4, 3)), 1.0),
        lambda: window_path(ring, 7, lags, 0.0, np.zeros((3, 2)), 0),
        lambda: within_count(np.zeros(3), np.zeros((4, 3)), 1, 3, 1.0),
    ]
