"""Wave spectra, sea states and random-phase wave time series.

Spectra are one-sided, in m²·s per rad/s, as functions of the angular frequency ω [rad/s],
from the significant wave height Hs [m] and the peak period Tp [s]; ∫S dω = Hs²/16.

* Modified Pierson–Moskowitz (ITTC/ISSC, Bretschneider; DNV-RP-C205 §3.5.5.1):
  S_PM(ω) = 5/16 Hs² ωp⁴ ω⁻⁵ exp(−5/4 (ωp/ω)⁴), ωp = 2π/Tp.
* JONSWAP (DNV-RP-C205 §3.5.5.2): S_J = A_γ S_PM γ^exp(−(ω−ωp)²/(2σ²ωp²)), σ = 0.07 below
  ωp and 0.09 above, with DNV's normalisation A_γ = 1 − 0.287 ln γ and DNV's rule for γ
  from Tp/√Hs (§3.5.5.5): 5 up to 3.6, exp(5.75 − 1.15 Tp/√Hs) up to 5, then 1.
* Torsethaugen double-peaked spectrum (Torsethaugen 1996, SINTEF STF22 A96204; the
  parameter rules as published in Fossen's MSS toolbox, torsetSpectrum.m; DNV-RP-C205
  §3.5.6): wind sea and swell partitions (Hs_w, Tp_w, γ_w, N_w, M_w) and (Hs_s, Tp_s, γ_s,
  N_s, M_s), each a generalised JONSWAP shape (f Tp)^−N exp(−N/M (f Tp)^−M) γ^(…).  Each
  partition is normalised here so that it integrates exactly to Hs_i²/16 (numerically), in
  place of the report's empirical fit for A_γ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.errors import BosunError

G = 9.81

#: WMO sea state code 3700: (code, name, Hs_min, Hs_max) [m]; Fossen (2011) Table 8.3
WMO_SEA_STATES = (
    (0, "calm (glassy)", 0.0, 0.0),
    (1, "calm (rippled)", 0.0, 0.1),
    (2, "smooth (wavelets)", 0.1, 0.5),
    (3, "slight", 0.5, 1.25),
    (4, "moderate", 1.25, 2.5),
    (5, "rough", 2.5, 4.0),
    (6, "very rough", 4.0, 6.0),
    (7, "high", 6.0, 9.0),
    (8, "very high", 9.0, 14.0),
    (9, "phenomenal", 14.0, math.inf),
)


class SeaStateError(BosunError):
    """Sea-state parameters that cannot be used."""


class BreakingSeaError(SeaStateError):
    """A sea steeper than a sea can be (DNV-RP-C205 §3.5.5.4): in range, yet it would break."""


#: the sea states Bosun simulates: Hs [m] and Tp [s] (WMO 0–9 seas; beyond them no spectrum here applies,
#: and a vanishing Hs or Tp would only underflow the formulas below)
HS_RANGE = (0.01, 30.0)
TP_RANGE = (1.0, 40.0)


def check_sea(hs: float, tp: float) -> None:
    """The one check of a sea state (CLI, API and engine commands alike): ranges, then breaking."""
    if not (math.isfinite(hs) and HS_RANGE[0] <= hs <= HS_RANGE[1]):
        raise SeaStateError(f"Hs must be a positive number of metres in [{HS_RANGE[0]:g}, {HS_RANGE[1]:g}], got {hs}")
    if not (math.isfinite(tp) and TP_RANGE[0] <= tp <= TP_RANGE[1]):
        raise SeaStateError(f"Tp must be a positive number of seconds in [{TP_RANGE[0]:g}, {TP_RANGE[1]:g}], got {tp}")
    # DNV-RP-C205 §3.5.5.4: average steepness S_p = 2π Hs/(g Tp²) at most 1/15 for Tp ≤ 8 s,
    # 1/25 for Tp ≥ 15 s, linear between; steeper seas break
    sp = 2 * math.pi * hs / (G * tp**2)
    limit = 1 / 15 - (1 / 15 - 1 / 25) * min(1.0, max(0.0, (tp - 8.0) / 7.0))
    if sp > limit:
        raise BreakingSeaError(
            f"Hs {hs:g} m with Tp {tp:g} s is steeper than a sea can be "
            f"(2πHs/(gTp²) = {sp:.3f} > {limit:.3f}, DNV-RP-C205 §3.5.5.4)"
        )


def wmo_sea_state(hs: float) -> tuple[int, str]:
    """WMO code (3700) and name of the sea state with significant wave height hs [m]."""
    if not hs >= 0:
        raise SeaStateError(f"Hs must not be negative, got {hs}")
    if hs == 0:
        return 0, WMO_SEA_STATES[0][1]
    for code, name, lo, hi in WMO_SEA_STATES[1:]:
        if lo < hs <= hi or (code == 1 and hs <= hi):
            return code, name
    return 9, WMO_SEA_STATES[-1][1]


def pierson_moskowitz(w: ArrayLike, hs: float, tp: float) -> NDArray[np.float64]:
    """Modified Pierson–Moskowitz spectrum S(ω) [m² s]."""
    check_sea(hs, tp)
    return _pm(w, hs, tp)


def _pm(w: ArrayLike, hs: float, tp: float) -> NDArray[np.float64]:
    w = np.asarray(w, dtype=float)
    wp = 2 * np.pi / tp
    out = np.zeros_like(w)
    pos = w > 0
    out[pos] = 5.0 / 16.0 * hs**2 * wp**4 * w[pos] ** -5 * np.exp(-1.25 * (wp / w[pos]) ** 4)
    return out


def dnv_gamma(hs: float, tp: float) -> float:
    """JONSWAP peak enhancement γ from DNV-RP-C205 §3.5.5.5."""
    check_sea(hs, tp)
    return _dnv_gamma(hs, tp)


def _dnv_gamma(hs: float, tp: float) -> float:
    r = tp / math.sqrt(hs)
    if r <= 3.6:
        return 5.0
    if r < 5.0:
        return math.exp(5.75 - 1.15 * r)
    return 1.0


def jonswap(w: ArrayLike, hs: float, tp: float, gamma: float | None = None) -> NDArray[np.float64]:
    """JONSWAP spectrum S(ω) [m² s]; γ from the DNV rule when not given."""
    check_sea(hs, tp)
    g = _dnv_gamma(hs, tp) if gamma is None else float(gamma)
    if not 1.0 <= g <= 10.0:
        raise SeaStateError(f"JONSWAP gamma must be in [1, 10], got {g}")
    return _jonswap(w, hs, tp, g)


def _jonswap(w: ArrayLike, hs: float, tp: float, g: float) -> NDArray[np.float64]:
    w = np.asarray(w, dtype=float)
    wp = 2 * np.pi / tp
    sigma = np.where(w <= wp, 0.07, 0.09)
    peak = g ** np.exp(-((w - wp) ** 2) / (2 * sigma**2 * wp**2))
    return (1.0 - 0.287 * math.log(g)) * _pm(w, hs, tp) * peak


# ----------------------------------------------------------------------------- Torsethaugen
@dataclass(frozen=True)
class Partition:
    """One peak of a double-peaked sea: generalised JONSWAP with Hs, Tp, γ and shape exponents N, M."""

    hs: float
    tp: float
    gamma: float
    n: float
    m: float

    def shape(self, w: NDArray[np.float64]) -> NDArray[np.float64]:
        f_n = np.maximum(w, 1e-12) / (2 * np.pi) * self.tp  # f Tp
        sigma = np.where(f_n < 1.0, 0.07, 0.09)
        body = f_n ** (-self.n) * np.exp(-(self.n / self.m) * f_n ** (-self.m))
        return body * self.gamma ** np.exp(-((f_n - 1.0) ** 2) / (2 * sigma**2))


def torsethaugen_partitions(hs: float, tp: float) -> tuple[Partition, Partition]:
    """(wind sea, swell) partitions of the Torsethaugen (1996) model; constants as published (MSS)."""
    check_sea(hs, tp)
    tf = 6.6 * hs ** (1.0 / 3.0)  # peak period of a fully developed sea
    kg, kg0, kg1, r = 35.0, 3.5, 1.0, 0.857
    n_shape = 0.5 * math.sqrt(hs) + 3.2
    if tp < tf:  # wind sea dominates
        tl = 2.0 * math.sqrt(hs)
        eps = (tf - tp) / (tf - tl)
        rpw = 0.3 * math.exp(-((eps / 0.5) ** 2)) + 0.7
        hsw, hss = rpw * hs, math.sqrt(1.0 - rpw**2) * hs
        sp = 2 * math.pi / G * hsw / tp**2
        gw = max(1.0, kg * (1 + kg0 * math.exp(-hs / kg1)) * sp**r)
        return Partition(hsw, tp, gw, n_shape, 4.0), Partition(hss, tf + 2.0, 1.0, n_shape, 4.0)
    # swell dominates
    eps = (tp - tf) / (25.0 - tf)
    rps = 0.4 * math.exp(-((eps / 0.3) ** 2)) + 0.6
    hss, hsw = rps * hs, math.sqrt(1.0 - rps**2) * hs
    mw = 4.0 * (1 - 0.7 * math.exp(-hs / 3.0))
    s4 = 0.08 * (1 - math.exp(-hs / 3.0))
    g0w = 1.0 / ((1.0 / mw) * math.gamma((n_shape - 1) / mw) * (n_shape / mw) ** (-(n_shape - 1) / mw))
    tpw = (g0w * hsw**2 / (16 * s4 * 0.4**n_shape)) ** (1.0 / (n_shape - 1.0))
    sf = 2 * math.pi / G * hs / tf**2
    gs = max(1.0, kg * (1 + kg0 * math.exp(-hs / kg1)) * sf**r * (1 + 6.0 * eps))
    return Partition(hsw, tpw, 1.0, n_shape, mw), Partition(hss, tp, gs, n_shape, 4.0)


def _normalised(part: Partition, w: NDArray[np.float64]) -> NDArray[np.float64]:
    """The partition's shape scaled so that it integrates to Hs_i²/16 (on a fine reference grid)."""
    if part.hs <= 0:
        return np.zeros_like(w)
    wp = 2 * np.pi / part.tp
    ref = np.linspace(1e-3 * wp, 25 * wp, 20001)
    scale = part.hs**2 / 16.0 / np.trapezoid(part.shape(ref), ref)
    return scale * part.shape(w)


def torsethaugen(w: ArrayLike, hs: float, tp: float) -> NDArray[np.float64]:
    """Torsethaugen double-peaked spectrum S(ω) [m² s]."""
    w = np.asarray(w, dtype=float)
    wind, swell = torsethaugen_partitions(hs, tp)
    return _normalised(wind, w) + _normalised(swell, w)


SPECTRA = {"jonswap": jonswap, "pm": pierson_moskowitz, "torsethaugen": torsethaugen}


def spectrum(name: str, w: ArrayLike, hs: float, tp: float) -> NDArray[np.float64]:
    try:
        fn = SPECTRA[name]
    except KeyError:
        raise SeaStateError(f"unknown spectrum '{name}' (available: {', '.join(SPECTRA)})") from None
    return fn(w, hs, tp)


# ----------------------------------------------------------------------------- periods
def _tz(w: NDArray[np.float64], s: NDArray[np.float64]) -> float:
    """Tz = 2π √(m0/m2) from S on ``w`` (0.2 ωp … 12 ωp), with the ω⁻⁵ tail beyond the grid."""
    tail = s[-1] * w[-1] ** 5
    m0 = np.trapezoid(s, w) + tail / (4 * w[-1] ** 4)
    m2 = np.trapezoid(w**2 * s, w) + tail / (2 * w[-1] ** 2)
    return float(2 * np.pi * math.sqrt(m0 / m2))


def _grid(tp: float) -> NDArray[np.float64]:
    return (2 * np.pi / tp) * np.geomspace(0.2, 12.0, 4000)


def zero_crossing_period(name: str, hs: float, tp: float) -> float:
    """Mean zero up-crossing period Tz = 2π √(m0/m2) [s] of a spectrum (DNV-RP-C205 §3.5.2.3), m_n = ∫ωⁿ S dω.

    Integrated numerically from 0.2 ωp to 12 ωp on a geometric grid, with the ω⁻⁵ tail beyond (S ≈ A ω⁻⁵:
    m0 gets A/(4 ω_h⁴), m2 gets A/(2 ω_h²)); below 0.2 ωp every spectrum here is below 1e-100 of its peak
    (exp(−5/4 · 625)).  For Pierson–Moskowitz Tz = 0.710 Tp; for JONSWAP it matches DNV-RP-C205's fit
    Tz/Tp = 0.6673 + 0.05037 γ − 0.006230 γ² + 0.0003341 γ³ to 0.5 % (tests/test_scatter.py)."""
    w = _grid(tp)
    return _tz(w, spectrum(name, w, hs, tp))


def tp_from_tz(name: str, hs: float, tz: float) -> float:
    """The peak period Tp [s] whose ``name`` spectrum of height ``hs`` has the zero-crossing period ``tz``.

    Scatter diagrams of observed seas (IACS Rec. 34, Global Wave Statistics) give Tz; the spectra here are
    parametrised by Tp.  Single-peaked spectra only: Torsethaugen's Tz/Tp falls from 0.75 to below 0.2 as its
    swell grows (Hs 0.5 m, Tp 3–28 s), so one Tz stands for very different seas and is refused.  Tz/Tp of
    Pierson–Moskowitz and JONSWAP depends on the shape alone (γ from Tp/√Hs), so the root is found over the
    whole bracket Tp ∈ [Tz, 1.5 Tz] (Tp/Tz is 1.24–1.41 for γ 5…1; Tz rises with Tp) with Brent's method
    before the sea is checked: a result out of range raises SeaStateError, a breaking one BreakingSeaError."""
    from scipy.optimize import brentq

    if name not in ("pm", "jonswap"):
        raise SeaStateError(
            f"a Tz scatter diagram needs a single-peaked spectrum (pm or jonswap), not {name}: its Tz/Tp "
            "depends on the swell, so a Tz does not name one sea"
        )
    if not (math.isfinite(hs) and math.isfinite(tz) and hs > 0 and tz > 0):
        raise SeaStateError(f"Hs and Tz must be positive numbers, got Hs {hs}, Tz {tz}")

    def tz_of(tp: float) -> float:
        w = _grid(tp)
        s = _pm(w, hs, tp) if name == "pm" else _jonswap(w, hs, tp, _dnv_gamma(hs, tp))
        return _tz(w, s) - tz

    lo, hi = tz, 1.5 * tz
    f_lo, f_hi = tz_of(lo), tz_of(hi)
    if f_lo > 0 or f_hi < 0:  # cannot happen for γ in [1, 5]; said rather than guessed
        raise SeaStateError(f"no {name} sea of Hs {hs:g} m has Tz {tz:g} s (Tp searched in {lo:.3g}–{hi:.3g} s)")
    tp = lo if f_lo == 0 else hi if f_hi == 0 else float(brentq(tz_of, lo, hi, xtol=1e-7))
    try:
        check_sea(hs, tp)
    except BreakingSeaError:
        raise BreakingSeaError(
            f"Hs {hs:g} m with Tz {tz:g} s is steeper than a sea can be for the {name} spectrum "
            f"(its Tp would be {tp:.3g} s; DNV-RP-C205 §3.5.5.4)"
        ) from None
    except SeaStateError as err:
        raise SeaStateError(f"Tz {tz:g} s with Hs {hs:g} m: {err}") from None
    return tp


# ----------------------------------------------------------------------------- time series
@dataclass(frozen=True, eq=False)
class WaveComponents:
    """Regular wave components of a random sea: η(t, x, y) = Σ a_k cos(ω_k t − k_k (x cos β_k + y sin β_k) + φ_k).

    Attributes
    ----------
    omega : ndarray (n,)   angular frequencies [rad/s]
    amplitude : ndarray (n,)   a_k = sqrt(2 S(ω_k) Δω_k (D(β_k) Δβ)) [m]
    phase : ndarray (n,)   uniform random phases [rad]
    direction : ndarray (n,)   propagation directions β_k [rad] (wave heading, going towards)
    """

    omega: NDArray[np.float64]
    amplitude: NDArray[np.float64]
    phase: NDArray[np.float64]
    direction: NDArray[np.float64]

    @property
    def wavenumber(self) -> NDArray[np.float64]:
        return self.omega**2 / G  # deep water dispersion

    def elevation(self, t: ArrayLike, x: float = 0.0, y: float = 0.0) -> NDArray[np.float64]:
        t = np.asarray(t, dtype=float)
        k = self.wavenumber
        arg = np.multiply.outer(t, self.omega) - k * (x * np.cos(self.direction) + y * np.sin(self.direction))
        return np.cos(arg + self.phase) @ self.amplitude

    @property
    def variance(self) -> float:
        return float(np.sum(self.amplitude**2) / 2.0)


def wave_components(
    name: str,
    hs: float,
    tp: float,
    rng: np.random.Generator,
    *,
    n_freq: int = 200,
    w_min: float | None = None,
    w_max: float | None = None,
    heading: float = 0.0,
    spreading: int | None = None,
    n_dir: int = 15,
) -> WaveComponents:
    """Components of a long-crested (``spreading=None``) or short-crested sea.

    Frequencies: one random point in each of ``n_freq`` equal bins between w_min and w_max
    (default 0.25 ωp … 5 ωp), which avoids the repetition period of equal spacing.  Short-
    crested: D(β) ∝ cos^(2s)(β − heading) for |β − heading| < π/2, with ``spreading`` = s,
    over ``n_dir`` directions.
    """
    check_sea(hs, tp)
    if n_freq < 1:
        raise SeaStateError("n_freq must be at least 1")
    wp = 2 * np.pi / tp
    lo = 0.25 * wp if w_min is None else w_min
    hi = 5.0 * wp if w_max is None else w_max
    edges = np.linspace(lo, hi, n_freq + 1)
    dw = np.diff(edges)
    w = edges[:-1] + rng.uniform(0, 1, n_freq) * dw
    S = spectrum(name, w, hs, tp)
    if spreading is None:
        amp = np.sqrt(2 * S * dw)
        return WaveComponents(w, amp, rng.uniform(0, 2 * np.pi, n_freq), np.full(n_freq, heading))
    if spreading < 1:
        raise SeaStateError("spreading exponent s must be at least 1")
    beta = np.linspace(-np.pi / 2, np.pi / 2, n_dir + 2)[1:-1]
    D = np.cos(beta) ** (2 * spreading)
    D /= D.sum()
    W, Bd = np.meshgrid(w, beta, indexing="ij")
    amp = np.sqrt(2 * np.outer(S * dw, D)).ravel()
    return WaveComponents(W.ravel(), amp, rng.uniform(0, 2 * np.pi, amp.size), heading + Bd.ravel())
