"""Issue 31, item 4: the dynamic factor ψ = peak wire tension / static weight, simulated with the crane holding its
load in a sea, and the load chart SWL(radius, Hs) = rated capacity / ψ on Dask (``bosun study loadchart``), the
rated capacity from the crane's robot file."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys

import numpy as np
import pytest

from app.errors import RobotXmlError
from app.models.xml import parse_robot_file, parse_robot_xml
from app.resources import robot_library
from app.scenarios.dynamic_factor import DynamicFactorError, DynamicFactorScenario, simulate

CRANE_FILE = robot_library() / "offshore_crane.xml"  # the installed library's (the hostile lane runs elsewhere)
CRANE = parse_robot_file(CRANE_FILE)


def test_a_load_hanging_still_in_a_calm_sea_gives_psi_one_in_every_mode():
    for mode in ("off", "compensated", "antisway"):
        r = simulate(DynamicFactorScenario(hs=0, mode=mode, duration=20.0))
        assert abs(r["psi"] - 1.0) < 1e-3, (mode, r)
        assert r["min_tension_factor"] > 0.999 and r["slack_s"] == 0.0


def test_psi_grows_with_the_sea_uncompensated_and_compensation_holds_it_near_one():
    off = [simulate(DynamicFactorScenario(hs=hs, mode="off", duration=60.0))["psi"] for hs in (0.5, 1.0, 2.0)]
    assert 1.0 < off[0] < off[1] < off[2], off
    comp = simulate(DynamicFactorScenario(hs=2.0, mode="compensated", duration=60.0))["psi"]
    assert 1.0 <= comp < off[2] and comp < 1.01  # the head holds the TCP, the winch the hook's height


def test_a_stiff_wire_s_psi_hardly_depends_on_the_payload():
    """Hs 1 m, off: 5 t and 20 t see the same sea's factor to 0.05 (the wire's axial mode, √(EA/(L m)), rings at
    16–32 rad/s, far above the waves: the hook's motion is imposed and the tension scales with the mass)."""
    r = simulate(DynamicFactorScenario(hs=1.0, mode="off", duration=60.0, payload=5.0))
    r20 = simulate(DynamicFactorScenario(hs=1.0, mode="off", duration=60.0, payload=20.0))
    assert abs(r["psi"] - r20["psi"]) < 0.05  # a stiff wire: the sea's factor hardly depends on the mass
    assert r["psi"] > 1.05


def test_the_crane_stands_at_the_radius_asked_and_refuses_one_it_cannot_reach():
    r = simulate(DynamicFactorScenario(hs=0, radius=22.5, duration=1.0))
    assert abs(r["radius_m"] - 22.5) < 1e-6
    with pytest.raises(DynamicFactorError, match=r"radius 40 m is out of the crane's reach .*18\.6.*32\.5 m"):
        simulate(DynamicFactorScenario(hs=0, radius=40.0, duration=1.0))
    for bad, msg in ((dict(payload=0), "payload"), (dict(hs=-1), "Hs|hs"), (dict(wire=50), "wire"),
                     (dict(mode="tac"), "mode")):  # fmt: skip
        with pytest.raises(DynamicFactorError, match=msg):
            DynamicFactorScenario(**bad)


def test_the_crane_s_rated_capacity_is_read_from_its_robot_file_conservatively():
    rc = CRANE.rated_capacity
    assert rc is not None and "assumed" in rc.source
    assert rc.at(12.0) == 25_000.0 and rc.at(30.0) == 10_000.0
    assert rc.at(29.7) == 10_000.0  # between 28 m (10.7 t) and 30 m: the next radius out's, never more
    assert rc.at(5.0) == 25_000.0  # inside the first rating's radius: that rating's (the next one out)
    assert rc.at(34.1) is None and rc.at(math.nan) is None and rc.at(-1.0) is None


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ('<rating radius="10" capacity="5"/><rating radius="12" capacity="6"/>', r":\d+: .*6 t at 12 m is more"),
        ('<rating radius="10" capacity="5"/><rating radius="10" capacity="4"/>', r":\d+: .*radius 10 m must be more"),
        ('<rating radius="10" capacity="5"/><rating radius="12" capacity="nan"/>', r":\d+: "),
        ('<rating radius="10" capacity="5"/>', r":\d+: "),
    ],
)
def test_a_bad_rating_is_refused_in_one_line_with_its_line(rows, message):
    text = CRANE_TEXT.replace(CRANE_RATINGS, rows)
    with pytest.raises(RobotXmlError, match=message) as err:
        parse_robot_xml(text, "crane.xml")
    assert "\n" not in str(err.value) and str(err.value).startswith("crane.xml:")


def test_a_rating_without_a_source_is_refused():
    text = re.sub(r'<rated_capacity source="[^"]*"', '<rated_capacity source=" "', CRANE_TEXT)
    assert text != CRANE_TEXT
    with pytest.raises(RobotXmlError, match="needs a source"):
        parse_robot_xml(text, "crane.xml")


with open(CRANE_FILE, encoding="utf-8") as _f:
    CRANE_TEXT = _f.read()
CRANE_RATINGS = "\n".join(line for line in CRANE_TEXT.splitlines() if "<rating " in line)


def test_the_radius_of_a_configuration_round_trips():
    from app.models.crane_head import CraneHead
    from app.models.registry import load_robot
    from app.scenarios.tac import BETA_EQ60

    system = CraneHead(load_robot("offshore_crane"), load_robot("tac_delta_head"))
    assert abs(system.radius(BETA_EQ60) - 29.684) < 1e-3
    for r in (19.0, 25.0, 32.0):
        beta = system.at_radius(r, BETA_EQ60)
        assert abs(system.radius(beta) - r) < 1e-6 and beta[0] == pytest.approx(BETA_EQ60[0])
        assert np.all(beta >= system.crane.lower) and np.all(beta <= system.crane.upper)


# ----------------------------------------------------------------------------- the live indicator
def test_the_watch_keeps_the_window_s_peak_and_gives_the_share_of_swl():
    from app.scenes.crane_load import LoadChartWatch

    w = LoadChartWatch(CRANE.rated_capacity, window=10.0)
    assert w.report(5000.0, 29.7, 0.0)["swl_percent"] is None  # nothing seen yet: no figure, not 50 %
    for t, f in ((0.0, 1.0), (1.0, 1.6), (2.0, 1.1), (9.0, 1.2)):
        w.step(t, f)
    r = w.report(5000.0, 29.7, 9.0)
    assert r["psi"] == 1.6 and r["capacity_t"] == 10.0 and r["swl_percent"] == pytest.approx(80.0)
    w.step(11.5, 0.9)  # the 1.6 at 1 s has left the 10 s window: the 1.2 at 9 s is the peak
    assert w.report(5000.0, 29.7, 11.5)["psi"] == 1.2
    w.step(30.0, 0.2)  # a landed load: ψ is at least 1 (lifted, it weighs its weight)
    assert w.report(5000.0, 29.7, 30.0)["psi"] == 1.0
    assert w.report(5000.0, 40.0, 30.0)["swl_percent"] is None and w.beyond(40.0)  # past the chart: not rated
    assert not w.beyond(30.0) and not LoadChartWatch(None).beyond(40.0)  # no chart at all: nothing to be beyond


def test_the_crane_engine_shows_this_load_in_this_sea_as_a_share_of_its_swl_and_alarms_over_it():
    """The crane-head engine, Hs 3 m: the snapshot's share is 100 · m ψ / C(r) with ψ at least every tension factor
    it published in the window and C the rating at the TCP's own radius (the head's arms move it about the nominal
    29.7 m: 10 t inside 30 m, 9.3 t past it); off, a 9 t load in that sea is over its SWL: the overload alarm
    (critical) is raised.  Compensating, the same load in the same sea stays under it."""
    from app.engine.tac_session import TacSession
    from app.scenarios.tac import TacScenario
    from app.scenes.crane_load import CraneLoad
    from app.sim.load import LoadSpec
    from tests.test_crane_stick import run

    results = {}
    for mode in ("off", "tac"):
        ses = TacSession(scenario=TacScenario(duration=1e5, hs=3.0, mode=mode))
        ses.load = CraneLoad(load_spec=LoadSpec(mass=9000.0))
        t, seen = 0.0, []
        for _ in range(40):  # off, the swing grows: ψ 1.1 after 30 s, 1.2 after 40 s
            t = run(ses, 1.0, None, t)
            ld = ses.snapshot().load
            seen.append(ld.tension_factor)
        assert ld.payload_t == 9.0 and ld.rated and abs(ld.radius - 29.684) < 1.0
        assert ld.capacity_t == CRANE.rated_capacity.at(ld.radius) / 1000.0
        assert ld.psi >= max(seen) - 1e-4 and ld.psi_window == pytest.approx(40.0, abs=1.0)
        assert ld.swl_percent == pytest.approx(100 * 9.0 * ld.psi / ld.capacity_t, rel=1e-3)
        results[mode] = (ld.swl_percent, ses.alarms.active("overload"))
    assert results["off"][0] >= 100.0 and results["off"][1], results
    assert results["tac"][0] < 100.0 and not results["tac"][1], results


# ----------------------------------------------------------------------------- the study
pytest.importorskip("distributed")


STUDY_SEAS = [(0.0, 9.0), (1.0, 9.0), (2.0, 9.0)]


@pytest.fixture(scope="module")
def chart(tmp_path_factory):
    """A small load chart: 2 modes × 5 and 9 t × 20 and 30 m × Hs 0, 1, 2 m at Tp 9 s, one seed of 30 s."""
    from app.analysis.loadchart import LoadChartStudy, run_study, save

    study = LoadChartStudy(
        radii=(20.0, 30.0), payloads=(5.0, 9.0), modes=("off", "compensated"), seeds=1, duration=30.0
    )
    out = tmp_path_factory.mktemp("chart") / "lc"
    res = run_study(study, STUDY_SEAS, out, workers=2)
    return study, out, res, save(res, out)


def test_the_load_chart_study_falls_with_hs_lies_above_off_compensated_and_resumes(chart):
    from app.analysis.loadchart import run_cell, run_study

    study, out, res, doc = chart
    seas = STUDY_SEAS
    assert res.computed == 24 and doc["checks"]["falls_with_hs"] and doc["checks"]["compensated_above_off"]
    by = {(r["mode"], r["radius_m"], r["hs"]): r for r in res.table if r["payload_t"] == 5.0}
    for radius, cap in ((20.0, 15.0), (30.0, 10.0)):
        calm = by[("off", radius, 0.0)]
        assert calm["capacity_t"] == cap and abs(calm["swl_t"] - cap) < 1e-3 * cap  # ψ = 1: the rated chart
        assert by[("off", radius, 2.0)]["swl_t"] < by[("off", radius, 1.0)]["swl_t"] < calm["swl_t"]
        assert by[("compensated", radius, 2.0)]["swl_t"] > by[("off", radius, 2.0)]["swl_t"]
    for row in res.table:
        assert row["swl_t"] == pytest.approx(row["capacity_t"] / row["psi"], rel=1e-12)
        assert row["fits"] == (row["payload_t"] <= row["swl_t"])
    # a cached cell is the simulation's number: recomputed, it is the same
    cell = next(c for c in res.cells if c["mode"] == "off" and c["hs"] == 2.0 and c["radius"] == 30.0)
    params = {k: cell[k] for k in ("v", "kind", "mode", "payload", "radius", "hs", "tp", "heading", "seed",
                                   "duration", "dt", "spectrum", "wire", "vessel", "crane")}  # fmt: skip
    assert run_cell(params)["psi"] == cell["psi"]
    again = run_study(study, seas, out, workers=1)
    assert again.computed == 0 and again.cached == 24 and again.table == res.table
    assert (out / "loadchart.png").stat().st_size > 10_000
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["rated_capacity"]["capacity_t"][0] == 25.0


def _forecast(tmp_path, rows: str):
    path = tmp_path / "forecast.csv"
    path.write_text("time,hs,tp,heading\n" + rows, encoding="utf-8")
    return path


def test_the_plan_reads_a_load_chart_study_as_its_chart_conservatively(chart, tmp_path):
    """A lift of 5 t at 25 m: each forecast hour is the study's rougher Hs row, ψ the larger of the studied radii on
    either side (20 and 30 m: ψ need not be monotone in the radius), the capacity the rating at 25 m itself (the
    next rating out, 26 m: 11.5 t); a forecast or lift outside the study is refused in one line."""
    from app.analysis.plan import PlanError, load_forecast, load_study, make_plan

    _, out, res, _ = chart
    table = {(r["mode"], r["radius_m"], r["hs"]): r for r in res.table if r["payload_t"] == 5.0}
    f = load_forecast(_forecast(tmp_path, "2026-12-01T00:00,0.6,9.2,80\n2026-12-01T01:00,1.5,8.8,95\n"))
    for mode in ("off", "compensated"):
        rows = make_plan(f, load_study(out, payload=5.0, radius=25.0, mode=mode))
        for row, h in zip(rows, (1.0, 2.0), strict=True):
            psi = max(table[(mode, 20.0, h)]["psi"], table[(mode, 30.0, h)]["psi"])
            assert (row["cell_hs"], row["cell_radii"], row["cell_payloads"]) == (h, [20.0, 30.0], [5.0])
            assert row["psi"] == psi and row["swl_t"] == pytest.approx(11.5 / psi, rel=1e-12)
            assert row["workable"] == (row["swl_t"] >= 5.0)
    assert load_study(out, payload=5.0, radius=25.0).mode == "compensated"  # the default where studied
    between = make_plan(f, load_study(out, payload=7.0, radius=20.0, mode="off"))  # between the 5 and 9 t rows
    assert all(r["cell_radii"] == [20.0] and r["cell_payloads"] == [5.0, 9.0] for r in between)
    for rows, message in (
        ("2026-12-01T00:00,2.5,9,90\n", "Hs 2.5 m is above the study's largest (2 m)"),
        ("2026-12-01T00:00,1,10,90\n", "Tp 10 s is outside the study's periods at Hs 1 m (9 ± 0.5 s)"),
        ("2026-12-01T00:00,1,9,0\n", "heading 0° is more than 22.5° from the study's (90°)"),
    ):
        fc = load_forecast(_forecast(tmp_path, rows))
        with pytest.raises(PlanError, match=re.escape(message)):
            make_plan(fc, load_study(out, payload=5.0, radius=25.0))
    for kw, message in (
        (dict(), "give its --payload T and --radius M"),
        (dict(payload=9.5, radius=25.0), "payload 9.5 t is outside the study's payloads (5–9 t)"),
        (dict(payload=4.0, radius=25.0), "payload 4 t is outside the study's payloads (5–9 t)"),
        (dict(payload=5.0, radius=31.0), "radius 31 m is outside the study's radii (20–30 m)"),
        (dict(payload=5.0, radius=5.0), "radius 5 m is outside the study's radii (20–30 m)"),
        (dict(payload=5.0, radius=25.0, mode="antisway"), "mode antisway is not in the study"),
        (dict(payload=5.0, radius=25.0, criterion=0.1), "--criterion is an operability study's"),
    ):
        with pytest.raises(PlanError, match=re.escape(message)):
            load_study(out, **kw)


def test_bosun_plan_with_a_load_chart_study_prints_the_lift_and_its_verdicts(chart, tmp_path):
    """9 t at 30 m (rated 10 t) uncompensated: over its SWL wherever the sea's ψ passes 10/9 (Hs 1 m gives about
    1.2), and the command's verdicts are the table's, hour by hour."""
    _, out, res, _ = chart
    swl = {r["hs"]: r["swl_t"] for r in res.table if (r["mode"], r["radius_m"], r["payload_t"]) == ("off", 30.0, 9.0)}
    fits = [swl[h] >= 9.0 for h in (1.0, 2.0)]
    assert not all(fits), swl  # the chart derates 9 t below its weight in these seas: the refusal is exercised
    fc = _forecast(tmp_path, "2026-12-01T00:00,1,9,90\n2026-12-01T01:00,2,9,90\n")
    plan = tmp_path / "plan"
    res2 = subprocess.run(
        [sys.executable, "-m", "app", "plan", "--forecast", str(fc), "--study", str(out), "--payload", "9",
         "--radius", "30", "--mode", "off", "--out", str(plan)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert res2.returncode == 0, res2.stderr
    assert "off, 9 t at 30 m ≤ its SWL" in res2.stdout and f"{sum(fits)} of 2 h workable" in res2.stdout
    assert f"NOT workable: over its SWL: 9 t > {min(swl[1.0], swl[2.0]):.2f} t" in res2.stdout
    doc = json.loads((plan / "plan.json").read_text(encoding="utf-8"))
    assert doc["lift"] == {"payload_t": 9.0, "radius_m": 30.0} and (plan / "plan.png").is_file()
    assert [r["workable"] for r in doc["rows"]] == fits


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--hs", "1", "--radii", "35"], "radius 35 m is beyond the crane's rated chart (its last rating: 34 m)"),
        (["--hs", "1", "--radii", "33"], "radius 33 m is out of the crane's reach"),
        (["--hs", "1", "--scatter", "north-atlantic"], "one of the two"),
        ([], "one of the two"),
        (["--hs", "1,x"], "--hs: 'x' is not a number"),
        (["--hs", "1,1"], "--hs: a height repeated (1,1)"),
        (["--hs", "1", "--payloads", "-2"], "--payloads: -2 must be a positive number"),
        (["--hs", "1", "--modes", "off,tac"], "mode must be one of off, compensated, antisway"),
        (["--hs", "1", "--max-runs", "3"], "more than the limit of 3"),
    ],
)
def test_the_cli_refuses_a_bad_load_chart_in_one_line_before_any_work(tmp_path, extra, message):
    res = subprocess.run(
        [sys.executable, "-m", "app", "study", "loadchart", "--out", str(tmp_path / "o"), *extra],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1 and message in res.stderr, res.stderr
    assert not (tmp_path / "o").exists()


def test_a_scatter_diagram_s_hs_row_takes_its_worst_period(tmp_path):
    """``--scatter``: every cell with a probability is simulated; the chart at one Hs is the worst of its periods
    (the row names which), and the source says the diagram."""
    path = tmp_path / "scatter.csv"
    path.write_text("hs\\tp,6,10\n1.0,3,1\n", encoding="utf-8")
    out = tmp_path / "lc"
    res = subprocess.run(
        [sys.executable, "-m", "app", "study", "loadchart", "--scatter", str(path), "--radii", "30", "--payloads", "5",
         "--modes", "off", "--seeds", "1", "--duration", "10", "--workers", "1", "--out", str(out), "--json"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["seas"] == [[1.0, 6.0], [1.0, 10.0]] and doc["source"].endswith("scatter.csv")
    cells = [json.loads(f.read_text(encoding="utf-8")) for f in (out / "cells").glob("*.json")]
    worst = max(cells, key=lambda c: c["psi"])
    row = (out / "loadchart.csv").read_text(encoding="utf-8").splitlines()[1].split(",")
    assert len(cells) == 2 and float(row[4]) == worst["tp"] and float(row[5]) == pytest.approx(worst["psi"], rel=1e-5)


def test_a_study_made_with_a_vessel_file_named_relatively_is_planned_from_anywhere(tmp_path):
    """The cells' key holds the vessel file's hash; the summary keeps it, so ``bosun plan`` run from another folder
    finds the cells (it used to hash the file again by the name the study was given, relative to where it ran)."""
    from app.marine.vessels import shipped_table_path

    here = tmp_path / "made_here"
    here.mkdir()
    (here / "v.csv").write_bytes(shipped_table_path().read_bytes())
    run = [sys.executable, "-m", "app", "study", "loadchart", "--hs", "1", "--radii", "30", "--payloads", "5",
           "--modes", "off", "--seeds", "1", "--duration", "5", "--workers", "1", "--vessel", "v.csv",
           "--out", "lc"]  # fmt: skip
    res = subprocess.run(run, capture_output=True, text=True, timeout=300, cwd=here)
    assert res.returncode == 0, res.stderr
    fc = _forecast(tmp_path, "2026-12-01T00:00,0.8,9,90\n")
    plan = subprocess.run(
        [sys.executable, "-m", "app", "plan", "--forecast", str(fc), "--study", str(here / "lc"), "--payload", "5",
         "--radius", "30", "--mode", "off", "--out", str(tmp_path / "plan")],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )  # fmt: skip
    assert plan.returncode == 0, plan.stderr
    assert "1 of 1 h workable" in plan.stdout or "0 of 1 h workable" in plan.stdout
