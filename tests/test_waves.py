"""Wave spectra (DNV-RP-C205, Torsethaugen 1996), sea-state table, random-phase time series."""

import numpy as np
import pytest

from app.marine.waves import (
    SeaStateError,
    dnv_gamma,
    jonswap,
    pierson_moskowitz,
    spectrum,
    torsethaugen,
    torsethaugen_partitions,
    wave_components,
    wmo_sea_state,
)

W = np.linspace(1e-3, 10.0, 200_001)
SEAS = [
    (0.5, 4.0),
    (1.0, 5.0),
    (2.0, 7.0),
    (3.0, 6.0),
    (3.0, 8.0),
    (3.0, 9.0),
    (3.0, 12.0),
    (4.0, 7.0),
    (5.0, 10.0),
    (6.0, 11.0),
    (2.0, 16.0),
    (8.0, 14.0),
]


@pytest.mark.parametrize("name", ["pm", "jonswap", "torsethaugen"])
@pytest.mark.parametrize("hs, tp", SEAS)
def test_spectra_integrate_to_hs2_over_16(name, hs, tp):
    m0 = np.trapezoid(spectrum(name, W, hs, tp), W)
    assert m0 == pytest.approx(hs**2 / 16, rel=0.01)


def test_pm_peak_is_at_tp():
    w = np.linspace(0.2, 2.0, 20001)
    assert w[np.argmax(pierson_moskowitz(w, 3.0, 9.0))] == pytest.approx(2 * np.pi / 9.0, rel=1e-3)


def test_dnv_gamma_rule():
    assert dnv_gamma(4.0, 6.4) == 5.0  # Tp/sqrt(Hs) = 3.2 <= 3.6 (6.0 s would break: steeper than 1/15)
    assert dnv_gamma(1.0, 6.0) == 1.0  # 6 >= 5
    assert dnv_gamma(4.0, 8.6) == pytest.approx(np.exp(5.75 - 1.15 * 4.3))
    # the peak enhancement raises the peak against PM, with the same energy
    wp = 2 * np.pi / 6.4
    assert jonswap(wp, 4.0, 6.4) / pierson_moskowitz(wp, 4.0, 6.4) == pytest.approx((1 - 0.287 * np.log(5)) * 5)


def test_breaking_seas_are_refused():
    with pytest.raises(SeaStateError, match="steeper than a sea can be"):
        jonswap(1.0, 4.0, 6.0)  # 2πHs/(gTp²) = 0.071 > 1/15
    with pytest.raises(SeaStateError, match="steeper"):
        dnv_gamma(15.0, 15.0)  # 0.043 > 1/25
    assert dnv_gamma(8.0, 15.0) == 1.0  # 0.0228: fine


def test_torsethaugen_partitions():
    wind, swell = torsethaugen_partitions(3.0, 6.0)  # Tp < 6.6 Hs^(1/3) = 9.52 s: wind sea dominates
    assert wind.tp == 6.0 and swell.tp == pytest.approx(6.6 * 3 ** (1 / 3) + 2.0)
    assert wind.hs**2 + swell.hs**2 == pytest.approx(9.0)
    wind, swell = torsethaugen_partitions(2.0, 16.0)  # Tp > 6.6 Hs^(1/3): swell dominates
    assert swell.tp == 16.0 and wind.tp < swell.tp
    assert wind.hs**2 + swell.hs**2 == pytest.approx(4.0)
    w = np.linspace(0.05, 3.0, 5000)
    S = torsethaugen(w, 2.0, 16.0)
    peaks = np.flatnonzero((S[1:-1] > S[:-2]) & (S[1:-1] > S[2:])) + 1
    assert len(peaks) == 2  # double peaked: swell at 16 s and a wind sea near its own peak
    assert 2 * np.pi / w[peaks].min() == pytest.approx(16.0, rel=0.01)


def test_wmo_sea_state_table():
    assert wmo_sea_state(3.0) == (5, "rough")  # the TAC paper: Hs 3.0 m is sea state 5 (rough)
    assert wmo_sea_state(0.0)[0] == 0 and wmo_sea_state(0.05)[0] == 1 and wmo_sea_state(1.25)[0] == 3
    assert wmo_sea_state(20.0) == (9, "phenomenal")


@pytest.mark.slow
@pytest.mark.parametrize("spreading", [None, 2])
def test_time_series_has_the_spectrum_variance(spreading):
    rng = np.random.default_rng(7)
    comps = wave_components("jonswap", 3.0, 9.0, rng, n_freq=300, spreading=spreading)
    assert comps.variance == pytest.approx(9.0 / 16, rel=0.03)  # the components carry the band's energy
    t = np.arange(0.0, 3 * 3600.0, 0.5)
    eta = comps.elevation(t)
    assert np.var(eta) == pytest.approx(9.0 / 16, rel=0.08)  # a 3 h record
    assert 4 * np.std(eta) == pytest.approx(3.0, rel=0.05)


def test_time_series_is_seeded():
    a = wave_components("torsethaugen", 2.0, 8.0, np.random.default_rng(1)).elevation(np.arange(0, 60, 0.1))
    b = wave_components("torsethaugen", 2.0, 8.0, np.random.default_rng(1)).elevation(np.arange(0, 60, 0.1))
    c = wave_components("torsethaugen", 2.0, 8.0, np.random.default_rng(2)).elevation(np.arange(0, 60, 0.1))
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: jonswap(W, -1.0, 8.0), "Hs must be a positive"),
        (lambda: pierson_moskowitz(W, 2.0, 0.0), "Tp must be a positive"),
        (lambda: jonswap(W, 2.0, 8.0, gamma=20), "gamma must be in"),
        (lambda: spectrum("ochi", W, 2.0, 8.0), "unknown spectrum 'ochi'"),
        (lambda: torsethaugen(W, float("nan"), 8.0), "Hs must be a positive"),
        (lambda: wmo_sea_state(-1), "must not be negative"),
    ],
)
def test_bad_sea_states(call, message):
    with pytest.raises(SeaStateError, match=message):
        call()
