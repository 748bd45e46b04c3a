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
from app.scenarios.dynamic_factor import DynamicFactorError, DynamicFactorScenario, simulate

CRANE = parse_robot_file("robots/offshore_crane.xml")


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
    assert rc.at(11.9) is None and rc.at(34.1) is None and rc.at(math.nan) is None


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ('<rating radius="10" capacity="5"/><rating radius="12" capacity="6"/>', r":\d+: .*6 t at 12 m is more than 5 t"),
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


with open("robots/offshore_crane.xml", encoding="utf-8") as _f:
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


# ----------------------------------------------------------------------------- the study
pytest.importorskip("distributed")


def test_the_load_chart_study_falls_with_hs_lies_above_off_compensated_and_resumes(tmp_path):
    from app.analysis.loadchart import LoadChartStudy, run_cell, run_study, save

    study = LoadChartStudy(radii=(20.0, 30.0), payloads=(5.0,), modes=("off", "compensated"), seeds=1, duration=30.0)
    seas = [(0.0, 9.0), (1.0, 9.0), (2.0, 9.0)]
    res = run_study(study, seas, tmp_path / "lc", workers=2)
    doc = save(res, tmp_path / "lc")
    assert res.computed == 12 and doc["checks"]["falls_with_hs"] and doc["checks"]["compensated_above_off"]
    by = {(r["mode"], r["radius_m"], r["hs"]): r for r in res.table}
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
                                   "duration", "dt", "spectrum", "wire", "vessel")}  # fmt: skip
    assert run_cell(params)["psi"] == cell["psi"]
    again = run_study(study, seas, tmp_path / "lc", workers=1)
    assert again.computed == 0 and again.cached == 12 and again.table == res.table
    assert (tmp_path / "lc" / "loadchart.png").stat().st_size > 10_000
    summary = json.loads((tmp_path / "lc" / "summary.json").read_text(encoding="utf-8"))
    assert summary["rated_capacity"]["capacity_t"][0] == 25.0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--hs", "1", "--radii", "10"], "radius 10 m: the crane is rated from 12 to 34 m only"),
        (["--hs", "1", "--radii", "33"], "radius 33 m is out of the crane's reach"),
        (["--hs", "1", "--scatter", "north-atlantic"], "one of the two"),
        ([], "one of the two"),
        (["--hs", "1,x"], "--hs: 'x' is not a number"),
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
