"""Online prediction of a vessel-borne point's motion from the motion sensor's signal alone (issue 31, item 1).

An autoregressive model fitted online (the method the wave-energy and heave-compensation literature uses for
predictions of a few seconds: e.g. Fusco and Ringwood, "A study of the prediction requirements in real-time
control of wave energy converters", IEEE Trans. Sustainable Energy 3(1), 176–184, 2012; the prediction and its
error variance as in Box, Jenkins, Reinsel and Ljung, *Time Series Analysis*, 5th ed., §5.1–5.2).  No RAO or
vessel model goes in (a real vessel's are rarely known well): only the signal.

Per channel, on the signal averaged over Δ = ``dt`` × ``decimate`` and sampled every Δ (the engines' 10 Hz to 2 Hz:
the waves' periods are 4–20 s; the average takes √decimate off the sensor's noise and delays the signal by exactly
(decimate − 1) dt / 2, which the prediction adds to its horizon), with its window mean μ removed:

    y_k − μ = Σ_{i=1}^{p} a_i (y_{k−i} − μ) + e_k,   var e_k = σ_e²                            (AR(p))

the coefficients a by least squares over the last ``window`` seconds, again every ``refit`` seconds.  Since the
coefficients do not care where the Δ grid starts, the prediction at any sample uses the history ending at that
sample (y_k, y_{k−Δ}, …): iterating the model h steps ahead is linear in that history, ŷ_{k+h} = μ + g_hᵀ (y − μ),
with the rows g_h computed once per fit; horizons between the grid points are interpolated (cubic, through the
last sample and the predicted points).  The ±2σ band is the model's own prediction error (Box et al. eq. 5.1.16):
σ²(h) = σ_e² Σ_{j<h} ψ_j², ψ the model's impulse response (ψ_0 = 1).

Tried first, and dropped: the harmonic model of Küchler et al. (IEEE/ASME Trans. Mechatronics 16(2), 2011: the N
dominant FFT peaks of a sliding window, their amplitudes and phases tracked by a Kalman filter).  On the crane
tip's heave at JONSWAP Hs 3 m, Tp 9 s (seed 5, not a test seed) it gave nrmse 0.95–1.42 at 5 s for N = 4–16 (0.40–
0.95 at 1 s), worse than the mean: a few lines cannot hold a continuous spectrum's phase over the fit's memory.
The AR(30) at 2 Hz gave 0.46 at 5 s and 0.14 at 1 s on the same record.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.control import predict_kernels
from app.errors import BosunError

__all__ = [
    "Foresight", "LiftWindow", "MotionPredictor", "PredictError", "PredictorSpec", "ar_fit", "ar_rows", "window_count",
]  # fmt: skip


class PredictError(BosunError):
    """A bad predictor setting (names the setting)."""


@dataclass(frozen=True)
class PredictorSpec:
    """The predictor's settings (SI; chosen on JONSWAP Hs 3 m, Tp 9 s, seeds 5–6: not the test seeds 1–4)."""

    dt: float = 0.1  # s: the samples fed (the engines' and sim predict's)
    decimate: int = 5  # the model's grid: every 5th sample (Δ = 0.5 s)
    order: int = 30  # p: 15 s of memory at Δ = 0.5 s
    window: float = 300.0  # s: the fit's window
    refit: float = 10.0  # s: fitted again this often
    max_horizon: float = 20.0  # s
    ridge: float = 1e-6  # the fit's Tikhonov term, a share of the regressors' mean square (ar_fit)

    def __post_init__(self) -> None:
        checks = [
            (self.dt > 0 and math.isfinite(self.dt), f"dt must be positive, got {self.dt}"),
            (self.decimate >= 1, f"decimate must be at least 1, got {self.decimate}"),
            (1 <= self.order <= 200, f"order must be 1..200, got {self.order}"),
            (
                self.window >= 4 * self.order * self.step,
                f"window must hold 4 × order model steps ({4 * self.order * self.step:g} s), got {self.window}",
            ),
            (self.refit >= self.dt, f"refit must be at least dt, got {self.refit}"),
            (0 < self.max_horizon <= 600, f"max_horizon must be in (0, 600] s, got {self.max_horizon}"),
        ]
        for ok, text in checks:
            if not ok:
                raise PredictError(f"predictor: {text}")

    @property
    def step(self) -> float:
        """Δ [s], the model's sample time."""
        return self.dt * self.decimate


def ar_fit(y: NDArray[np.float64], p: int, ridge: float = 0.0) -> tuple[NDArray[np.float64], float]:
    """AR(p) coefficients a (p,) by least squares on the de-meaned ``y`` (covariance method), with a ridge λ =
    ``ridge`` × mean(diag XᵀX) (Tikhonov: a smooth, noiseless record makes XᵀX nearly singular and the plain fit's
    coefficients huge), and σ_e² (the residuals' mean square)."""
    n = y.size
    X = np.lib.stride_tricks.sliding_window_view(y, p)[:-1, ::-1]  # rows (y_{k−1}, …, y_{k−p}) for k = p … n−1
    X = np.ascontiguousarray(X)
    A = X.T @ X
    lam = ridge * float(np.trace(A)) / p
    # the normal equations, made definite by the ridge; without one the minimum-norm least squares (a record of a
    # few pure tones is rank-deficient)
    a = np.linalg.solve(A + lam * np.eye(p), X.T @ y[p:]) if lam > 0 else np.linalg.lstsq(X, y[p:], rcond=None)[0]
    e = y[p:] - X @ a
    return a, float(e @ e) / max(1, n - 2 * p)


def ar_rows(a: NDArray[np.float64], h: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """G (h, p): row j gives the prediction j + 1 steps ahead from the history (newest first), ŷ = G @ y; and ψ
    (h,): the model's impulse response ψ_0 … ψ_{h−1} (Box et al. §5.2)."""
    p = a.size
    G = np.zeros((h, p))
    hist = np.eye(p)  # the history's rows as functions of itself: newest first
    rows = list(hist)
    for j in range(h):
        nxt = a @ np.array(rows[:p])
        G[j] = nxt
        rows.insert(0, nxt)
    psi = np.zeros(h)
    psi[0] = 1.0
    for j in range(1, h):
        psi[j] = sum(a[i] * psi[j - 1 - i] for i in range(min(p, j)))
    return G, psi


class MotionPredictor:
    """The online predictor of ``channels`` signals sampled every ``spec.dt`` (module text).

    Feed each sample with :meth:`update`; :meth:`predict` gives the prediction at any horizons up to
    ``spec.max_horizon`` and its σ (NaN for all before the first fit, once ``window`` / 2 is in)."""

    def __init__(self, spec: PredictorSpec | None = None, channels: int = 1) -> None:
        self.spec = sp = spec or PredictorSpec()
        self.m = int(channels)
        self._L = round(sp.window / sp.dt)
        self._ring = np.zeros((self._L, self.m))  # the samples averaged over Δ, the newest at _ring[k % L]
        self._raw = np.zeros((sp.decimate, self.m))  # the last Δ's samples, likewise
        self.delay = 0.5 * (sp.decimate - 1) * sp.dt  # the average's delay (a linear-phase FIR's: exact)
        self.k = 0
        self._h = math.ceil(sp.max_horizon / sp.step) + 1  # model steps predicted
        self._next_fit = 0.5 * sp.window
        # per channel, stacked: μ (m,), G (m, H, p), σ on the grid (m, H); None before the first fit
        self._fit_rec: tuple | None = None
        self.coefficients: NDArray[np.float64] | None = None  # (m, p)
        self._grid = np.arange(-1, self._h + 1) * sp.step  # −Δ, 0, Δ, … on which the cubic runs
        self._lags = np.arange(sp.order + 2) * sp.decimate  # the history's ages in samples: newest first

    @property
    def t(self) -> float:
        return self.k * self.spec.dt

    @property
    def ready(self) -> bool:
        return self._fit_rec is not None

    @property
    def mean(self) -> NDArray[np.float64]:
        """The fit's mean μ per channel (NaN before the first fit)."""
        return np.full(self.m, np.nan) if self._fit_rec is None else self._fit_rec[0]

    def update(self, y: ArrayLike) -> None:
        """Take the next sample (``channels`` values, ``spec.dt`` after the last)."""
        y = np.asarray(y, dtype=float).reshape(self.m)
        sp = self.spec
        if predict_kernels.ENABLED:  # compiled, one call (the engines' per-tick use: a tenth of the NumPy's time)
            if not predict_kernels.ring_update(self._ring, self._raw, self.k + 1, y):
                raise PredictError("predictor: a sample is not finite")
            self.k += 1
        else:
            if not np.all(np.isfinite(y)):
                raise PredictError("predictor: a sample is not finite")
            self.k += 1
            self._raw[self.k % sp.decimate] = y
            n = min(self.k, sp.decimate)
            self._ring[self.k % self._L] = self._raw.sum(axis=0) / n if n == sp.decimate else self._mean_raw(n)
        if self.t >= self._next_fit - 1e-9:
            self._next_fit += sp.refit
            self._fit()

    def prime(self, samples: ArrayLike) -> None:
        """Take a run of past samples (n, channels) at once and fit once at its end (a predictor started on the
        sensor's recent past: one fit instead of one every ``refit`` seconds of it)."""
        Y = np.asarray(samples, dtype=float).reshape(-1, self.m)
        if not np.all(np.isfinite(Y)):
            raise PredictError("predictor: a sample is not finite")
        fit_at = self._next_fit
        self._next_fit = math.inf
        if self.k == 0 and Y.shape[0] >= self.spec.decimate:
            self._fill(Y)  # a fresh predictor: its ring filled at once
        else:
            for y in Y:
                self.update(y)
        if self.t >= fit_at - 1e-9:
            self._fit()
            self._next_fit = fit_at + self.spec.refit * math.ceil((self.t - fit_at + 1e-9) / self.spec.refit)
        else:
            self._next_fit = fit_at

    def _fill(self, Y: NDArray[np.float64]) -> None:
        """:meth:`update` with every row of ``Y`` in turn, on a fresh predictor, vectorised (the same ring, raw
        samples and count; the averages summed in another order: equal to rounding)."""
        sp = self.spec
        n, dec = Y.shape[0], sp.decimate
        k = np.arange(1, n + 1)
        keep = k[-self._L :]  # the samples whose averages stay in the ring
        cs = np.vstack([np.zeros((1, self.m)), np.cumsum(Y, axis=0)])
        lo = np.maximum(keep - dec, 0)
        self._ring[keep % self._L] = (cs[keep] - cs[lo]) / np.minimum(keep, dec)[:, None]
        last = k[-dec:]
        self._raw[last % dec] = Y[last - 1]
        self.k = n

    def _mean_raw(self, n: int) -> NDArray[np.float64]:
        """The average of the first ``n`` < decimate samples (the start)."""
        return self._raw[[(self.k - i) % self.spec.decimate for i in range(n)]].mean(axis=0)

    def _fit(self) -> None:
        sp = self.spec
        n = min(self.k, self._L)
        ages = np.arange(0, n, sp.decimate)[::-1]  # the grid ending at the newest sample, oldest first
        Y = self._ring[(self.k - ages) % self._L]
        mu = Y.mean(axis=0)
        G = np.empty((self.m, self._h, sp.order))
        sigma = np.empty((self.m, self._h))
        coef = np.empty((self.m, sp.order))
        psis: list[tuple[NDArray[np.float64], float]] = []
        for j in range(self.m):
            a, var_e = ar_fit(Y[:, j] - mu[j], sp.order, sp.ridge)
            G[j], psi = ar_rows(a, self._h)
            sigma[j] = np.sqrt(var_e * np.cumsum(psi**2))  # σ(h), h = 1 … H model steps (Box et al. eq. 5.1.16)
            coef[j] = a
            psis.append((psi, var_e))
        self._fit_rec, self.coefficients = (mu, G, np.hstack([np.zeros((self.m, 1)), sigma])), coef
        self._psi = psis
        self._errors: dict[tuple[int, int, int], tuple] = {}  # window_probability's draws and G rows, this fit's

    def window_probability(self, channel: int, half_width: float, length: float, draws: int = 2000) -> float:
        """The probability that ``channel`` stays within ±``half_width`` of its mean for the next ``length`` s, by
        the model: its predicted path on the model's grid and the joint distribution of its errors there,
        Cov(e_i, e_j) = σ_e² Σ_{l<min(i,j)} ψ_l ψ_{l+|i−j|} (Box et al. §5.2: the errors of one origin's forecasts
        at several lead times are correlated through the impulse response ψ), integrated by Monte Carlo over
        ``draws`` fixed standard normal draws (the same each call: a decision does not flicker with the dice).
        NaN before the first fit.  The model runs on the signal averaged over Δ: the window's points are its grid
        points from the one that covers now (the average's delay) to the one past ``length``."""
        made = self.window_draws(channel, length, draws)
        if made is None:
            return math.nan
        path, errors = made
        return window_count(path, errors, 0, errors.shape[0], half_width) / errors.shape[0]

    def window_draws(
        self, channel: int, length: float, draws: int = 2000
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """What :meth:`window_probability` counts: ``channel``'s predicted deviations from its mean at the window's
        J grid points (J,) and the model's error draws there (draws, J), the draws made once a fit; None before
        the first fit.  The share of rows with |path + row| ≤ half-width everywhere is the probability
        (:func:`window_count`, which can count a share of the rows at a time)."""
        if self._fit_rec is None:
            return None
        sp = self.spec
        mu, G, _ = self._fit_rec
        J = min(self._h, math.ceil((length + self.delay) / sp.step) + 1)
        made = self._errors.get((channel, J, draws))
        if made is None:  # the errors' draws and the rows of G they go with depend on the fit alone: once a fit
            made = self._errors[(channel, J, draws)] = (
                self._error_draws(channel, J, draws),
                np.ascontiguousarray(G[channel, :J, : sp.order]),
            )
        errors, G_c = made
        if predict_kernels.ENABLED:  # compiled, one call (the engine's 2 Hz tick)
            return predict_kernels.window_path(self._ring, self.k, self._lags, float(mu[channel]), G_c, channel), errors
        hist = self._ring[(self.k - self._lags) % self._L]
        x = hist[: sp.order, channel] - mu[channel]
        return G_c @ x, errors  # deviations from the mean at grid steps 1 … J

    def _error_draws(self, channel: int, J: int, draws: int) -> NDArray[np.float64]:
        """``draws`` samples of the model's forecast errors at grid steps 1 … J (rows), jointly Gaussian."""
        psi, var_e = self._psi[channel]
        i = np.arange(J)
        d = np.abs(i[:, None] - i[None, :])
        lo = np.minimum(i[:, None], i[None, :]) + 1  # Σ over l < min(i, j) + 1 (steps counted from 1)
        # Σ_{l<n} ψ_l ψ_{l+d}: built per lag d from the products (J ≤ 60: a small loop)
        cov = np.empty((J, J))
        for lag in range(J):
            prod = np.concatenate([[0.0], np.cumsum(psi[: J - lag] * psi[lag:J])])
            mask = d == lag
            cov[mask] = prod[lo[mask]]
        cov *= var_e
        L = np.linalg.cholesky(cov + 1e-12 * np.eye(J) * max(1.0, float(np.trace(cov)) / J))
        return _normal_draws(draws, J) @ L.T

    def path(self, horizons: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """The prediction alone at ``horizons`` [s] (n,) → (n, channels), compiled
        (:func:`app.control.predict_kernels.ar_predict`: the engines' per-tick use); None before the first fit.
        Equal to :meth:`predict`'s first output (tested)."""
        if self._fit_rec is None:
            return None
        mu, G, _ = self._fit_rec
        h = np.asarray(horizons, dtype=float) + self.delay
        out = np.empty((h.size, self.m))
        predict_kernels.ar_predict(self._ring, self.k, self._lags, mu, G, self.spec.step, h, out)
        return out

    def predict(self, horizons: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The prediction at ``horizons`` [s] ahead of the last sample, (len, channels), and its σ (same shape).
        NaN before the first fit; a horizon past ``spec.max_horizon`` is an error."""
        sp = self.spec
        h = np.atleast_1d(np.asarray(horizons, dtype=float))
        if np.any(h < 0) or np.any(h > sp.max_horizon + 1e-9):
            raise PredictError(f"predictor: horizons must be in [0, {sp.max_horizon:g}] s")
        h = h + self.delay  # the averaged signal lags the signal by the delay
        if self._fit_rec is None:
            out = np.full((h.size, self.m), np.nan)
            return out, out.copy()
        mu, G, sigma = self._fit_rec
        hist = self._ring[(self.k - self._lags) % self._L]  # (p + 2, m), newest first
        x = hist[: sp.order] - mu
        path = np.empty((self._grid.size, self.m))
        path[0], path[1] = hist[1], hist[0]
        path[2:] = mu + np.einsum("mhp,pm->hm", G, x)
        out = _cubic(self._grid, path, h)
        step = self._grid[1] - self._grid[0]
        s = np.clip(h / step, 0.0, self._h)
        i = np.minimum(np.floor(s).astype(int), self._h - 1)
        u = (s - i)[:, None]
        sig = (1 - u) * sigma[:, i].T + u * sigma[:, i + 1].T  # linear between the grid's σ
        return out, sig


class Foresight:
    """A delay hidden by prediction (issue 31, item 2): fed, once per simulation step ``dt``, the sample that arrives
    ``delay`` late, it returns the motion predicted ``delay`` ahead instead.  Every ``spec.dt`` (the steps whose
    number is a multiple of it) the late sample goes to the predictor; the steps until the next use the prediction
    at delay + their age.  Before the predictor's first fit the late sample itself.  Used by the crane head's
    simulator (η, ν) and the lab's late view of its platforms (η, η̇, η̈)."""

    def __init__(self, channels: int, delay: float, dt: float, spec: PredictorSpec | None = None) -> None:
        self.predictor = MotionPredictor(spec or PredictorSpec(), channels)
        self.delay, self.dt = float(delay), float(dt)
        self.every = round(self.predictor.spec.dt / dt)
        self._ahead: tuple[int, NDArray[np.float64]] | None = None

    def step(self, k: int, late: NDArray[np.float64]) -> NDArray[np.float64]:
        """Simulation step number ``k``'s view: ``late`` (channels,) replaced by the prediction when there is one."""
        if k % self.every == 0:
            self.predictor.update(late)
            path = self.predictor.path(self.delay + np.arange(self.every) * self.dt)
            self._ahead = None if path is None else (k, path)
        a = self._ahead
        if a is not None and 0 <= k - a[0] < self.every:
            return a[1][k - a[0]]
        return late


_DRAWS: dict[tuple[int, int], NDArray[np.float64]] = {}


def _normal_draws(n: int, m: int) -> NDArray[np.float64]:
    """n × m standard normal draws, the same for every call (seeded; kept)."""
    z = _DRAWS.get((n, m))
    if z is None:
        z = _DRAWS[(n, m)] = np.random.default_rng(31_3).standard_normal((n, m))
    return z


def _cubic(grid: NDArray[np.float64], y: NDArray[np.float64], h: NDArray[np.float64]) -> NDArray[np.float64]:
    """Catmull–Rom cubic through the evenly spaced points (grid, y), at h (within grid[1] … grid[-2]); y (len(grid),)
    or (len(grid), m) for m curves at once."""
    step = grid[1] - grid[0]
    s = (h - grid[0]) / step
    i = np.clip(np.floor(s).astype(int), 1, grid.size - 3)
    u = s - i
    if y.ndim == 2:
        u = u[:, None]
    p0, p1, p2, p3 = y[i - 1], y[i], y[i + 1], y[i + 2]
    return p1 + 0.5 * u * (p2 - p0 + u * (2 * p0 - 5 * p1 + 4 * p2 - p3 + u * (3 * (p1 - p2) + p3 - p0)))


def window_count(path: NDArray[np.float64], errors: NDArray[np.float64], lo: int, hi: int, half_width: float) -> int:
    """How many of the error draws ``lo`` … ``hi`` − 1 (rows of ``errors``) keep ``path`` + draw within
    ±``half_width`` at every point (:meth:`MotionPredictor.window_draws`): compiled
    (:func:`app.control.predict_kernels.within_count`, each draw left at its first point outside) or NumPy."""
    if predict_kernels.ENABLED:
        return int(predict_kernels.within_count(path, errors, int(lo), int(hi), float(half_width)))
    return int(np.count_nonzero(np.all(np.abs(path + errors[lo:hi]) <= half_width, axis=1)))


class LiftWindow:
    """The lift-window indicator an engine runs (issue 31, item 3): a :class:`MotionPredictor` on one signal (the
    crane tip's heave, or the tip's heave over a target deck) fed the engine's samples every ``dt`` s, and at each
    model sample (2 Hz) the prediction over the next ``ahead`` s with its σ and the probability that the signal
    stays within ±``threshold`` of its mean for the next ``length`` s (:meth:`MotionPredictor.window_probability`);
    *open* when that is at least ``probability``.  :meth:`state` is what the GUI's strip draws."""

    STEP = 0.5  # s between the strip's points
    DRAWS_PER_CALL = 700  # the window's Monte Carlo draws counted per call (2000 in three of the engine's ticks)

    def __init__(
        self, dt: float, threshold: float = 1.5, length: float = 10.0, probability: float = 0.95, ahead: float = 20.0
    ) -> None:
        self.predictor = MotionPredictor(PredictorSpec(), 1)
        self.every = max(1, round(self.predictor.spec.dt / dt))
        self.threshold, self.length, self.probability_min, self.ahead = threshold, length, probability, ahead
        self._n = 0
        self._h = np.arange(0.0, ahead + 1e-9, self.STEP)
        self.mean: NDArray[np.float64] | None = None  # the predicted deviation from the mean at _h
        self.sigma: NDArray[np.float64] | None = None
        self.probability = math.nan
        self.primed = False
        self._fit_seen: tuple | None = None  # the fit the σ was computed for
        self._sigma_fit: NDArray[np.float64] | None = None  # and that σ
        self._due = False  # a refresh fell due at the last call's last model sample (feed)
        self._pending: tuple | None = None  # the refresh under way: mean, σ, path, draws, half-width, counted, inside
        self._queued: float | None = None  # a model sample that arrived at the last call, taken at the next

    def feed(self, z: NDArray[np.float64]) -> None:
        """The signal's samples since the last call, ``dt`` apart (any number, also none).

        The work is spread over the calls (the engine's ticks) so that none carries much of it: a model sample is
        taken into the predictor at the next call (the tick after it arrives, which in the crane-head engine is the
        delay predictor's own model sample), and the refresh that falls due then goes over the calls after that —
        the path, σ and the first :data:`DRAWS_PER_CALL` of the window's Monte Carlo draws, then the rest — and
        publishes the strip's prediction and probability together once the last draw is counted (four ticks,
        80 ms, after the model sample at the engine's 50 Hz); whatever is still open when the next model sample is
        taken is finished first, so the numbers are those of a refresh made at once.  Made whole on the model
        sample's tick, the refresh and both predictors' model samples shared one tick, and that tick's cost was
        the predictors' p99 (``bosun bench loop --plant tac``)."""
        self._advance(self.DRAWS_PER_CALL)
        if self._queued is not None:
            self._take(self._queued)
            self._queued = None
        z = np.asarray(z, dtype=float).ravel()
        first = (-self._n - 1) % self.every  # the first of these samples on the predictor's grid
        self._n += z.size
        for v in z[first :: self.every]:
            if self._queued is not None:  # more than one model sample in a call: the earlier one now
                self._take(self._queued)
            self._queued = float(v)

    def _take(self, v: float) -> None:
        """One model sample into the predictor, after any refresh still open (it is of the samples before)."""
        self._advance(None)
        p = self.predictor
        p.update((v,))
        self._due = p.ready and p.k % p.spec.decimate == 0

    def prime(self, past: NDArray[np.float64]) -> None:
        """Start on the signal's past (oldest first, ``spec.dt`` apart, ending now): a real sensor has run all along
        (:meth:`MotionPredictor.prime`); the first refresh made at once."""
        self.predictor.prime(np.asarray(past, dtype=float).reshape(-1, 1))
        self.primed = True
        self._pending = self._queued = None  # the past ends now: a sample not yet taken is in it
        self._due = self.predictor.ready
        self._advance(None)

    def _advance(self, budget: int | None) -> None:
        """The refresh due or under way, by ``budget`` more Monte Carlo draws (None: to its end): begun with the
        path (compiled), the σ (the fit's alone: once a fit) and the window's draws; published when all are
        counted."""
        p = self.predictor
        if self._due:
            self._due = False
            if p._fit_rec is not self._fit_seen:
                self._sigma_fit = p.predict(self._h)[1][:, 0]
                self._fit_seen = p._fit_rec
            mean = p.path(self._h)[:, 0] - p.mean[0]
            path, errors = p.window_draws(0, self.length)
            self._pending = (mean, self._sigma_fit, path, errors, float(self.threshold), 0, 0)
        if self._pending is None:
            return
        mean, sigma, path, errors, half, done, inside = self._pending
        n = errors.shape[0]
        upto = n if budget is None else min(n, done + budget)
        inside += window_count(path, errors, done, upto, half)
        if upto < n:
            self._pending = (mean, sigma, path, errors, half, upto, inside)
            return
        self._pending = None
        self.mean, self.sigma, self.probability = mean, sigma, inside / n

    @property
    def open(self) -> bool:
        return bool(self.probability >= self.probability_min)  # NaN (learning): never open

    @property
    def learning_s(self) -> float:
        """Seconds until the first fit (0 once fitted)."""
        p = self.predictor
        return 0.0 if p.ready else max(0.0, 0.5 * p.spec.window - p.t)
