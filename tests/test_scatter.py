"""Issue 17, item 3: the shipped scatter diagram (IACS Rec. 34, North Atlantic, Hs × Tz) and the Tz → Tp
conversion that lets a Tz diagram drive spectra parametrised by Tp.

The table is a transcription of a published one; two checks that could each catch a mistyped cell or row:
its counts sum to 100 000 observations (the published total), and it agrees with the North Atlantic joint
model of DNV-RP-C205 §3.6 — 3-parameter Weibull Hs (α 3.041, β 1.484, γ 0.661) and lognormal Tz given Hs
(μ = 0.70 + 1.27 Hs^0.131, σ = 0.1334 + 0.0264 exp(−0.1906 Hs)) — the model fitted to the same data."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from app.analysis.operability import (
    SCATTERS,
    OperabilityError,
    OperabilityStudy,
    aggregate,
    cell_periods,
    load_scatter,
    scatter_path,
)
from app.marine.waves import SeaStateError, dnv_gamma, tp_from_tz, zero_crossing_period


def _counts() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    lines = [ln for ln in scatter_path("north-atlantic").read_text(encoding="utf-8").splitlines() if ln[:1] != "#"]
    tz = np.array([float(c) for c in lines[0].split(",")[1:]])
    rows = np.array([[float(c) for c in ln.split(",")] for ln in lines[1:]])
    return rows[:, 0], tz, rows[:, 1:]


def test_north_atlantic_is_shipped_whole_and_loads_by_name():
    sc = load_scatter("north-atlantic")
    assert set(SCATTERS) == {"north-atlantic"} and sc.source == "north-atlantic" and sc.period == "tz"
    assert sc.hs.tolist() == [0.5 + k for k in range(17)] and sc.t.tolist() == [1.5 + k for k in range(18)]
    assert sc.prob.sum() == pytest.approx(1.0)
    _, _, n = _counts()
    assert n.sum() == pytest.approx(100_000, abs=1.0)  # the published total, to the table's rounding (0.1)


def test_north_atlantic_agrees_with_dnv_joint_model_fitted_to_the_same_data():
    hs, tz, n = _counts()
    a, b, c = 3.041, 1.484, 0.661
    model = np.zeros_like(n)
    for i, h in enumerate(hs):
        hh = np.linspace(h - 0.5, h + 0.5, 401)[1:-1]
        f_hs = stats.weibull_min.pdf(hh, b, loc=c, scale=a)
        mu, sig = 0.70 + 1.27 * hh**0.131, 0.1334 + 0.0264 * np.exp(-0.1906 * hh)
        for j, t in enumerate(tz):
            p_t = stats.norm.cdf((math.log(t + 0.5) - mu) / sig) - stats.norm.cdf((math.log(t - 0.5) - mu) / sig)
            model[i, j] = np.trapezoid(f_hs * p_t, hh) * 1e5
    # Hs marginal: every class from 1 m up holding over 10 per 100 000 within 5 % (the 0–1 m class is below the
    # Weibull's 0.661 m location; the rarest, 7.7, 2.6 and 0.9, are sums of cells rounded to 0.1)
    rows = n.sum(axis=1)
    used = (hs > 1) & (rows > 10)
    assert used.sum() == 13 and np.all(np.abs(model.sum(axis=1)[used] / rows[used] - 1) < 0.05)
    # the cells that carry the table (26 over 1 000 per 100 000: 85 % of the time) within 20 %, median within 2 %
    big = n > 1000
    ratio = model[big] / n[big]
    assert big.sum() >= 20 and np.all(np.abs(ratio - 1) < 0.2) and abs(np.median(ratio) - 1) < 0.02
    # the two most likely sea states are the same two cells (Hs 1.5 m / Tz 7.5 s and 2.5 m / 8.5 s)
    assert set(np.argsort(n, axis=None)[-2:]) == set(np.argsort(model, axis=None)[-2:])


@pytest.mark.parametrize("hs,tp", [(3.0, 10.0), (4.0, 8.0), (4.0, 9.0), (2.0, 5.2), (6.0, 11.0)])
def test_zero_crossing_period_matches_dnv_fit_for_jonswap_and_pm_theory(hs, tp):
    g = dnv_gamma(hs, tp)
    fit = 0.6673 + 0.05037 * g - 0.006230 * g**2 + 0.0003341 * g**3  # DNV-RP-C205 §3.5.5
    assert zero_crossing_period("jonswap", hs, tp) / tp == pytest.approx(fit, rel=0.005)
    # Pierson–Moskowitz in closed form: m_n ∝ Γ(1 − n/4), so Tz/Tp = (5π/4)^(−1/4) = 0.7104
    assert zero_crossing_period("pm", hs, tp) / tp == pytest.approx((5 * math.pi / 4) ** -0.25, rel=1e-3)


def test_tp_from_tz_inverts_and_refuses_breaking_seas_and_double_peaks():
    for spec in ("pm", "jonswap"):
        for hs, tz in [(0.5, 3.5), (2.5, 7.5), (8.5, 9.5), (0.5, 18.5)]:
            tp = tp_from_tz(spec, hs, tz)
            assert 1.2 * tz < tp < 1.45 * tz and zero_crossing_period(spec, hs, tp) == pytest.approx(tz, rel=1e-5)
    with pytest.raises(SeaStateError, match="steeper than a sea can be"):
        tp_from_tz("jonswap", 3.5, 4.5)
    with pytest.raises(SeaStateError, match="single-peaked spectrum"):
        tp_from_tz("torsethaugen", 2.0, 6.0)


def test_a_tz_study_simulates_convertible_cells_and_counts_breaking_ones_as_not_workable(tmp_path):
    sc = load_scatter("north-atlantic")
    tps, why = cell_periods(sc, "jonswap")
    nonzero = int((sc.prob > 0).sum())
    assert 0 < len(why) < nonzero and all("steeper than a sea can be" in w for w in why.values())
    broken = sum(sc.prob[ij] for ij in why)
    assert 0 < broken < 0.01  # steep corners of the table: rare, yet there
    assert all(np.isfinite(tps[i, j]) == ((i, j) not in why) for i, j in zip(*np.nonzero(sc.prob > 0), strict=True))
    # aggregate with every simulable cell at rms 0 (workable): operability is 1 − the breaking share
    st = OperabilityStudy(headings=(90.0,), seeds=1, criterion=0.1)
    cells = [
        {"hs": float(sc.hs[i]), "tp": float(tps[i, j]), "heading": 90.0, "seed": 1, "rms_e_c_m": 0.0,
         "max_e_c_m": 0.0, "ratio": 0.0, "saturated_percent": 0.0}
        for i, j in zip(*np.nonzero(sc.prob > 0), strict=True) if (i, j) not in why
    ]  # fmt: skip
    table, oper = aggregate(st, sc, cells, tps, why)
    assert len(table) == nonzero and oper[90.0] == pytest.approx(1.0 - broken)
    assert sum(1 for r in table if r["tp"] is None and not r["workable"] and r["note"]) == len(why)
    # a Torsethaugen study of a Tz diagram is refused in one line
    with pytest.raises(OperabilityError, match="single-peaked"):
        cell_periods(sc, "torsethaugen")


def test_scatter_loader_needs_the_period_named(tmp_path):
    bad = tmp_path / "s.csv"
    bad.write_text("hs,7,9\n1.5,1,2\n", encoding="utf-8")
    with pytest.raises(OperabilityError, match=r"s.csv:1: the first field names the periods"):
        load_scatter(bad)
    bad.write_text("Hs / Tz,5,6\n1.5,1,2\n", encoding="utf-8")
    assert load_scatter(bad).period == "tz"
    with pytest.raises(OperabilityError, match="shipped one: north-atlantic"):
        load_scatter("north-sea")


def test_cli_refuses_a_double_peaked_spectrum_for_a_tz_diagram_in_one_line(tmp_path):
    import subprocess
    import sys

    res = subprocess.run(
        [sys.executable, "-m", "app", "study", "operability", "--scatter", "north-atlantic", "--spectrum",
         "torsethaugen", "--out", str(tmp_path / "o")],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and "single-peaked spectrum" in res.stderr
    assert not (tmp_path / "o").exists()  # refused before any file is made


def test_a_breaking_cell_is_one_whose_own_peak_period_breaks_and_no_other():
    """Review finding: the root was searched only between grid points where the sea did not break, so cells
    next to the limit were called breaking (Hs 11.5 m, Tz 8.5 s with Pierson–Moskowitz: Tp 11.97 s is a sea)."""
    from scipy.optimize import brentq

    from app.marine.waves import BreakingSeaError, _dnv_gamma, _grid, _jonswap, _pm, _tz, check_sea

    assert tp_from_tz("pm", 11.5, 8.5) == pytest.approx(11.966, abs=1e-3)
    assert tp_from_tz("pm", 1.0, 28.2) == pytest.approx(39.70, abs=0.01)  # near the top of the Tp range
    with pytest.raises(SeaStateError, match=r"Tp must be .* \[1, 40\]") as err:
        tp_from_tz("pm", 0.01, 0.7)  # Tp below 1 s: out of range, not "breaking"
    assert not isinstance(err.value, BreakingSeaError)
    sc = load_scatter("north-atlantic")
    for spec in ("pm", "jonswap"):
        _, why = cell_periods(sc, spec)
        for i, j in zip(*np.nonzero(sc.prob > 0), strict=True):
            hs, tz = float(sc.hs[i]), float(sc.t[j])

            def f(tp, hs=hs, tz=tz, spec=spec):
                w = _grid(tp)
                s = _pm(w, hs, tp) if spec == "pm" else _jonswap(w, hs, tp, _dnv_gamma(hs, tp))
                return _tz(w, s) - tz

            root = brentq(f, tz, 1.5 * tz, xtol=1e-9)  # the sea this cell names, breaking or not
            try:
                check_sea(hs, root)
                breaks = False
            except BreakingSeaError:
                breaks = True
            assert ((i, j) in why) == breaks, (spec, hs, tz, root)


def test_save_places_unsimulated_cells_of_tp_and_tz_diagrams(tmp_path):
    from app.analysis.operability import StudyResult, save

    tp_file = tmp_path / "tp.csv"
    tp_file.write_text("hs\\tp,3,9\n3,1,2\n", encoding="utf-8")  # Hs 3 m at Tp 3 s breaks
    tz_file = tmp_path / "tz.csv"
    tz_file.write_text("hs\\tz,4.5,7.5\n3.5,1,2\n", encoding="utf-8")  # Hs 3.5 m at Tz 4.5 s breaks (JONSWAP)
    for path in (tp_file, tz_file):
        sc = load_scatter(path)
        st = OperabilityStudy(headings=(90.0, 180.0), seeds=1, spectrum="jonswap")
        tps, why = cell_periods(sc, "jonswap")
        assert list(why) == [(0, 0)]
        cells = [
            {"hs": float(sc.hs[0]), "tp": float(tps[0, 1]), "heading": h, "seed": 1, "rms_e_c_m": 0.05,
             "max_e_c_m": 0.1, "ratio": 0.02, "saturated_percent": 0.0}
            for h in (90.0, 180.0)
        ]  # fmt: skip
        table, oper = aggregate(st, sc, cells, tps, why)
        assert oper == {90.0: pytest.approx(2 / 3), 180.0: pytest.approx(2 / 3)}
        out = tmp_path / path.stem
        out.mkdir()
        doc = save(StudyResult(st, sc, table, oper, 2, 0, 1.0, 1, "test", cells, 1 / 3), out)
        rows = (out / "table.csv").read_text(encoding="utf-8").splitlines()
        assert len(rows) == 5 and doc["unsimulated_probability"] == pytest.approx(1 / 3) and doc["cells"] == 2
        broken = [r for r in rows[1:] if "steeper than a sea can be" in r]
        assert len(broken) == 2 and all(",False," in r for r in broken)
        if sc.period == "tp":  # the cell keeps its Tp in the table
            assert all(r.startswith("3,3,") for r in broken)
        assert (out / "heatmap.png").stat().st_size > 0 and (out / "operability_polar.png").stat().st_size > 0


def test_a_cell_out_of_range_refuses_the_study_and_a_bom_file_loads(tmp_path):
    f = tmp_path / "s.csv"
    f.write_text("hs\\tp,9,50\n2,1,1\n", encoding="utf-8")  # Tp 50 s: no spectrum here goes there
    with pytest.raises(OperabilityError, match=r"cell Hs 2 m, Tp 50 s: Tp must be"):
        cell_periods(load_scatter(f), "jonswap")
    f.write_bytes("\ufeffhs\\tp,9\n2,1\n".encode())  # a spreadsheet's CSV UTF-8
    assert load_scatter(f).period == "tp"
    f.write_bytes(b"# caf\xe9\nhs\\tp,9\n2,1\n")  # Latin-1
    with pytest.raises(OperabilityError, match="not UTF-8 text"):
        load_scatter(f)


def test_a_real_tab_in_the_header_is_shown_as_a_tab_not_as_backslash_t(tmp_path):
    """Issue 27, item 10: a header "hs<TAB>p" was quoted back as 'hs\\tp', which reads as the hs\\tp asked for."""
    f = tmp_path / "s.csv"
    f.write_text("hs\tp,7\n1,1\n", encoding="utf-8")
    with pytest.raises(OperabilityError, match=r"with a backslash, got 'hs<TAB>p'") as err:
        load_scatter(f)
    assert "\\t" not in str(err.value).split("got")[1]
    f.write_text("hs\\tp,7\n1,x\u0007\n", encoding="utf-8")
    with pytest.raises(OperabilityError, match=r"s.csv:2: Tp 7 s: 'x<U\+0007>' is not a number"):
        load_scatter(f)


def test_a_scatter_file_over_its_bound_is_refused_before_it_is_read(tmp_path):
    """Issue 27, item 4: a 3 000 × 800 diagram (4.8 MB) drove a study to 8.7 GB."""
    f = tmp_path / "big.csv"
    with open(f, "w", encoding="utf-8") as fh:
        fh.write("hs\\tp," + ",".join(f"{3 + 0.01 * j:.2f}" for j in range(800)) + "\n")
        row = ",".join(["1"] * 800)
        for i in range(3000):
            fh.write(f"{0.5 + 0.001 * i:.3f},{row}\n")
    bound = r"big.csv: 4,8\d\d,\d\d\d bytes; a scatter diagram is at most 1,000,000 bytes"
    with pytest.raises(OperabilityError, match=bound):
        load_scatter(f)
