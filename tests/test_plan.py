"""Issue 31, item 5: ``bosun plan --forecast FILE.csv --study DIR`` (app/analysis/plan.py) — a forecast looked up
in an operability study's cached cells: the lookup is the cells' own numbers (a recomputation agrees), the
conservative choices (the rougher Hs, the nearest period and heading), why a time is not workable, every refusal
in one line naming the forecast's line, and the command's files."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from app.analysis.operability import OperabilityStudy, cell_params, load_scatter, run_cell, run_study, save
from app.analysis.plan import PlanError, load_forecast, load_study, make_plan

pytest.importorskip("distributed")

STUDY = OperabilityStudy(mode="tac", headings=(90.0, 135.0), seeds=1, duration=20.0, criterion=0.004)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """A 2 × 2 Tp diagram (the cell Hs 3 m, Tp 9 s has probability 0: not simulated), two headings, run once."""
    d = tmp_path_factory.mktemp("plan")
    path = d / "scatter.csv"
    path.write_text("hs\\tp,7,9\n1.5,30,20\n3.0,30,\n", encoding="utf-8")
    out = d / "study"
    save(run_study(STUDY, load_scatter(path), out, workers=1), out)
    return out


def _forecast(tmp_path, rows: str, head: str = "time,hs,tp,heading"):
    f = tmp_path / "forecast.csv"
    f.write_text(f"# test forecast\n{head}\n{rows}", encoding="utf-8")
    return f


def test_each_forecast_time_is_its_study_cell_and_the_cell_is_the_simulation(study, tmp_path):
    """Hs 1.2 m falls in the 1.5 m row (the rougher), Tp 7.6 s in the 7 s column, heading 100° on 90°; 2.0 m in the
    3 m row, 120° on 135°.  The cell's rms(e_c) is the cached simulation's, and simulating the cell again gives
    the same number."""
    f = _forecast(tmp_path, "2026-11-30T00:00Z,1.2,7.6,100\n2026-11-30T03:00Z,2.0,7.2,120\n")
    rows = make_plan(load_forecast(f), load_study(study))
    assert [(r["cell_hs"], r["cell_tp"], r["cell_heading"]) for r in rows] == [(1.5, 7.0, 90.0), (3.0, 7.0, 135.0)]
    assert [r["hours"] for r in rows] == [3.0, 3.0]  # the last time holds for the median step
    again = run_cell(cell_params(STUDY, 3.0, 7.0, 135.0, 1, None))
    assert rows[1]["rms_e_c_m"] == again["rms_e_c_m"]
    assert rows[1]["workable"] == (again["rms_e_c_m"] <= STUDY.criterion)


def test_why_not_is_the_criterion_and_the_lift_may_bring_its_own(study, tmp_path):
    f = _forecast(tmp_path, "2026-11-30T00:00,1.2,7,90\n2026-11-30T01:00,2.9,7,90\n2026-11-30T02:00,1.0,7,90\n")
    rms = [r["rms_e_c_m"] for r in make_plan(load_forecast(f), load_study(study))]
    assert rms[1] > rms[0]  # the rougher sea compensated less well
    limit = (rms[0] + rms[1]) / 2
    rows = make_plan(load_forecast(f), load_study(study, criterion=limit))
    assert [r["workable"] for r in rows] == [True, False, True]
    assert rows[1]["why_not"] == f"rms(e_c) {rms[1]:.4g} m > {limit:g} m"


@pytest.mark.parametrize(
    ("row", "message"),
    [
        ("2026-11-30T00:00,3.5,7,90", r"forecast.csv:3: Hs 3.5 m is above the study's largest \(3 m\)"),
        ("2026-11-30T00:00,1.0,12,90", r"forecast.csv:3: Tp 12 s is outside the study's periods \(7–9 s\)"),
        ("2026-11-30T00:00,1.0,7,30", r"forecast.csv:3: heading 30° is more than 22.5° from the study's \(90, 135°\)"),
        ("2026-11-30T00:00,2.5,9,90", r"forecast.csv:3: the study did not simulate Hs 3 m, Tp 9 s"),
        ("tomorrow,1.0,7,90", r"forecast.csv:3: time: 'tomorrow' is not an ISO 8601 date-time"),
        ("2026-11-30T00:00,1.0,x,90", r"forecast.csv:3: tp: 'x' is not a number"),
        ("2026-11-30T00:00,-1,7,90", r"forecast.csv:3: hs: -1 must be positive"),
        ("2026-11-30T00:00,1,7,90\n2026-11-30T00:00,1,7,90", r"forecast.csv:4: time: .* is not after the row before"),
        ("2026-11-30T00:00Z,1,7,90\n2026-11-30T01:00,1,7,90", r"forecast.csv:4: time: every time has a zone"),
    ],
)
def test_a_forecast_outside_the_study_or_malformed_is_refused_with_its_line(study, tmp_path, row, message):
    with pytest.raises(PlanError, match=message):
        make_plan(load_forecast(_forecast(tmp_path, row + "\n")), load_study(study))


def test_a_study_missing_a_cell_or_a_folder_that_is_none_is_refused(study, tmp_path):
    import shutil

    broken = tmp_path / "broken"
    shutil.copytree(study, broken)
    next((broken / "cells").glob("*.json")).unlink()
    f = _forecast(tmp_path, "".join(f"2026-11-30T0{k}:00,{hs},7,{h}\n" for k, (hs, h) in
                                    enumerate([(1, 90), (1, 135), (3, 90), (3, 135)])))  # fmt: skip
    with pytest.raises(PlanError, match=r"is not in .*cells: run the study again to finish it"):
        make_plan(load_forecast(f), load_study(broken))
    with pytest.raises(PlanError, match=r"not a study's folder \(no summary.json"):
        load_study(tmp_path)
    with pytest.raises(PlanError, match="the header names time, hs, tp"):
        load_forecast(_forecast(tmp_path, "2026-11-30T00:00,1,7,90\n", head="time,hs,heading"))


def test_bosun_plan_writes_its_files_and_refuses_a_bad_forecast_in_one_line(study, tmp_path):
    """A forecast in Tz against the study's Tp diagram: the Tz of the study's spectrum at the cell's Hs is turned
    into its Tp (9 s, not the nearest column to the Tz); the files; a bad forecast: exit 2 and one line."""
    from app.marine.waves import zero_crossing_period

    tz9 = zero_crossing_period("jonswap", 1.5, 9.0)
    f = _forecast(tmp_path, f"2026-11-30T00:00,1.2,{tz9:.4f},90\n2026-11-30T06:00,1.0,{tz9:.4f},90\n",
                  head="time,hs,tz,heading")  # fmt: skip
    out = tmp_path / "plan"
    done = subprocess.run(
        [sys.executable, "-m", "app", "plan", "--forecast", str(f), "--study", str(study), "--out", str(out),
         "--json"], capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert 6.0 < tz9 < 8.0 and [r["cell_tp"] for r in doc["rows"]] == [9.0, 9.0]  # Tz turned into the Tp column
    assert doc["hours"] == 12.0 and {p.name for p in out.iterdir()} == {"plan.csv", "plan.json", "plan.png"}
    bad = _forecast(tmp_path, "2026-11-30T00:00,9,7,90\n")
    done = subprocess.run(
        [sys.executable, "-m", "app", "plan", "--forecast", str(bad), "--study", str(study)],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.strip().count("\n") == 0 and "forecast.csv:3: Hs 9 m is above" in done.stderr
