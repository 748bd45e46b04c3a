"""A forecast plan (issue 31, item 5): ``bosun plan --forecast FILE.csv --study DIR``.

Reads a sea-state forecast and the cached cells of an operability study (:mod:`app.analysis.operability`, its
``DIR/summary.json`` and ``DIR/cells/``) and answers, for each forecast time, whether the planned lift is workable
there and, if not, which criterion fails — by looking the forecast's sea up in the study's cells, not by
simulating again (the cells *are* the simulations: a test recomputes one and finds the same numbers).

Forecast CSV: a header row ``time,hs,tp,heading`` (or ``tz`` for the zero up-crossing period) and one row per
forecast time: an ISO 8601 date-time (``2026-11-30T06:00``, with ``Z`` or an offset, or none: kept as written),
Hs [m], the period [s] and the wave heading relative to the vessel [deg] (the study's convention); ``#`` lines are
comments; times strictly increasing, at most :data:`MAX_FORECAST_ROWS` rows.  A forecast's time holds until the next
one (the last for the median step).

The lookup (conservative where it must choose):

* **Hs**: the study's smallest Hs at or above the forecast's (a sea between two rows counts as the rougher);
* **period**: the nearest of the study's columns, within half a column step beyond the first and last; a forecast
  in Tp against a study in Tz (the IACS scatter's) is turned into Tz with the study's spectrum, and back;
* **heading**: the nearest of the study's headings, within :data:`HEADING_TOLERANCE`;
* the cell must have been simulated (a probability above zero in the study's scatter); a breaking sea is not
  workable, with its reason.

A forecast outside the study (Hs above its largest, a period or heading beyond its reach, a cell it did not
simulate, a cell missing from its cache) is refused in one line naming the forecast's line.

A **load-chart study** (:mod:`app.analysis.loadchart`, issue 31, item 4) plans a lift of ``payload`` tonnes at
``radius`` metres in one of its modes: a forecast time is workable when the payload is at most its SWL there,
SWL = C(r) / ψ, read as the chart is (conservative at every choice):

* **Hs**: the study's smallest Hs at or above the forecast's; **radius and payload**: ψ the largest of the
  study's radii and payloads on either side of the lift's (ψ is not monotone in either: off, Hs 3 m, 22 / 16 / 22
  at 20 / 25 / 30 m), a lift outside the studied radii or payloads refused; the capacity the crane's rating at
  the lift's own radius (the next rating out), as the study stored it;
* **period**: ψ is the largest over the study's periods at that Hs (and all seeds), as in its chart; the forecast's
  period must lie among them (within half their smallest step beyond the first and last; a study of one period
  answers within :data:`PERIOD_TOLERANCE` of it); **heading**: within :data:`HEADING_TOLERANCE` of the study's.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np

from app.csvtext import cells, content_lines, finite_number
from app.errors import BosunError, shown

__all__ = ["Forecast", "PlanError", "StudyCells", "load_forecast", "load_study", "make_plan", "save_plan"]

MAX_FORECAST_ROWS = 10_000  # 14 months of hourly forecast
MAX_FORECAST_BYTES = 2_000_000
#: deg: a forecast heading within this of one of the study's (half the 45° spacing of the usual 8 headings)
HEADING_TOLERANCE = 22.5
#: s: a load-chart study of one period answers a forecast period this close to it
PERIOD_TOLERANCE = 0.5


class PlanError(BosunError):
    """A forecast or study that cannot be planned with (one line: file, line, field)."""


@dataclass
class Forecast:
    source: str
    lines: list[int]
    times: list[datetime]
    hs: np.ndarray
    period: np.ndarray
    kind: str  # "tp" or "tz"
    heading: np.ndarray


def load_forecast(path: str | Path) -> Forecast:
    """The forecast CSV (module text), every mistake refused in one line with its file, line and field."""
    path = Path(path)
    try:
        if not path.is_file():
            raise PlanError(f"{path}: no such forecast file")
        if path.stat().st_size > MAX_FORECAST_BYTES:
            raise PlanError(f"{path}: a forecast is at most {MAX_FORECAST_BYTES:,} bytes")
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as err:
        raise PlanError(f"{path}: not UTF-8 text (byte {err.start}): save it as CSV UTF-8") from None
    except OSError as err:
        raise PlanError(f"{path}: cannot be read: {err.strerror or err}") from None
    numbers, lines = content_lines(text)
    if len(lines) < 2:
        raise PlanError(f"{path}: a header row (time,hs,tp,heading) and at least one forecast row are needed")
    head = [c.strip().lower() for c in cells(lines[0])]
    kinds = [k for k in ("tp", "tz") if k in head]
    if len(kinds) != 1 or not {"time", "hs", "heading"} <= set(head):
        raise PlanError(
            f"{path}:{numbers[0]}: the header names time, hs, tp (or tz) and heading, got {shown(lines[0])}"
        )
    kind = kinds[0]
    col = {name: head.index(name) for name in ("time", "hs", kind, "heading")}
    if len(lines) - 1 > MAX_FORECAST_ROWS:
        raise PlanError(f"{path}: {len(lines) - 1:,} forecast rows; at most {MAX_FORECAST_ROWS:,}")
    times, values, rows = [], [], []
    for n, line in zip(numbers[1:], lines[1:], strict=True):
        row = cells(line)
        if len(row) != len(head):
            raise PlanError(f"{path}:{n}: expected {len(head)} fields, got {len(row)}")
        try:
            t = datetime.fromisoformat(row[col["time"]].strip())
        except ValueError:
            raise PlanError(
                f"{path}:{n}: time: {shown(row[col['time']])} is not an ISO 8601 date-time (2026-11-30T06:00)"
            ) from None
        v = []
        for name in ("hs", kind, "heading"):
            try:
                x = finite_number(row[col[name]])
            except ValueError as err:
                raise PlanError(f"{path}:{n}: {name}: {shown(row[col[name]])} is {err}") from None
            if name != "heading" and x <= 0:
                raise PlanError(f"{path}:{n}: {name}: {x:g} must be positive")
            v.append(x)
        if times and (t.tzinfo is None) != (times[0].tzinfo is None):
            raise PlanError(f"{path}:{n}: time: every time has a zone (Z, +01:00) or none does")
        if times and t <= times[-1]:
            raise PlanError(f"{path}:{n}: time: {t.isoformat()} is not after the row before ({times[-1].isoformat()})")
        times.append(t)
        values.append(v)
        rows.append(n)
    a = np.array(values)
    return Forecast(str(path), rows, times, a[:, 0], a[:, 1], kind, a[:, 2])


@dataclass
class StudyCells:
    """An operability study's settings, scatter and cell cache (:func:`load_study`)."""

    out: Path
    study: Any  # OperabilityStudy
    scatter: Any  # Scatter
    tps: np.ndarray
    why: dict
    vessel_id: str | None


@dataclass
class ChartCells:
    """A load-chart study's settings, seas and cell cache, and the planned lift (:func:`load_study`)."""

    out: Path
    study: Any  # LoadChartStudy
    seas: list[tuple[float, float]]
    payload: float  # t
    radius: float  # m
    mode: str
    vessel_id: str | None
    rating: Any = None  # RatedCapacity: the crane's chart as the study stored it
    crane_id: str | None = None  # the crane file's hash the cells were made with


def load_study(
    out: str | Path,
    criterion: float | None = None,
    payload: float | None = None,
    radius: float | None = None,
    mode: str | None = None,
) -> StudyCells | ChartCells:
    """The study in ``out``: its ``summary.json`` (the settings and the scatter it was run over) and its cells'
    cache; refused in one line when it is not a finished operability or load-chart study.  ``criterion``: the
    lift's own rms(e_c) limit [m] instead of the operability study's (the cells hold the rms, not the verdict);
    ``payload`` [t], ``radius`` [m] and ``mode``: a load-chart study's planned lift (module text)."""
    out = Path(out)
    summary = out / "summary.json"
    if summary.is_file():
        try:
            kind = "loadchart" if "rated_capacity" in json.loads(summary.read_text(encoding="utf-8")) else "operability"
        except (OSError, ValueError):
            kind = "operability"  # refused below with its reason
        if kind == "loadchart":
            if criterion is not None:
                raise PlanError(f"{out}: a load-chart study plans by SWL: --criterion is an operability study's")
            return _load_chart(out, summary, payload, radius, mode)
    if payload is not None or radius is not None or mode is not None:
        raise PlanError(f"{out}: --payload, --radius and --mode plan a lift with a load-chart study's cells "
                        "(bosun study loadchart); this is not one")  # fmt: skip
    return _load_operability(out, summary, criterion)


def _load_chart(out: Path, summary: Path, payload: float | None, radius: float | None, mode: str | None) -> ChartCells:
    from app.analysis.loadchart import LoadChartStudy
    from app.analysis.operability import OperabilityError, vessel_id
    from app.models.spec import RatedCapacity

    if payload is None or radius is None:
        raise PlanError(f"{out}: a load-chart study plans a lift: give its --payload T and --radius M")
    try:
        doc = json.loads(summary.read_text(encoding="utf-8"))
        st = dict(doc["study"])
        for k in ("radii", "payloads", "modes"):
            st[k] = tuple(st[k])
        study = LoadChartStudy(**st)
        seas = [(float(h), float(t)) for h, t in doc["seas"]]
        rc = doc["rated_capacity"]
        rating = RatedCapacity(
            np.array(rc["radius_m"], float), 1000.0 * np.array(rc["capacity_t"], float), rc["source"]
        )
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise PlanError(f"{summary}: not a load-chart study's summary ({one_reason(err)})") from None
    except OperabilityError as err:
        raise PlanError(f"{summary}: {err}") from None
    mode = mode or ("compensated" if "compensated" in study.modes else study.modes[0])
    if mode not in study.modes:
        raise PlanError(f"{out}: mode {mode} is not in the study (its modes: {', '.join(study.modes)})")
    lo, hi = min(study.payloads), max(study.payloads)
    if not lo <= payload <= hi:
        raise PlanError(f"{out}: payload {payload:g} t is outside the study's payloads ({lo:g}–{hi:g} t)")
    lo, hi = min(study.radii), max(study.radii)
    if not lo <= radius <= hi:
        raise PlanError(f"{out}: radius {radius:g} m is outside the study's radii ({lo:g}–{hi:g} m)")
    cid = doc.get("crane_id")
    vid = doc["vessel_id"] if "vessel_id" in doc else vessel_id(study.vessel)  # as the study hashed it (its file
    # may be named relative to where the study ran)
    return ChartCells(out, study, seas, float(payload), float(radius), mode, vid, rating, cid)


def _load_operability(out: Path, summary: Path, criterion: float | None) -> StudyCells:
    from app.analysis.operability import (
        OperabilityError,
        OperabilityStudy,
        cell_periods,
        load_scatter,
        vessel_id,
    )

    if not summary.is_file():
        raise PlanError(f"{out}: not a study's folder (no summary.json: bosun study operability … --out {out})")
    try:
        doc = json.loads(summary.read_text(encoding="utf-8"))
        st = dict(doc["study"])
        st["headings"] = tuple(st["headings"])
        if criterion is not None:
            st["criterion"] = float(criterion)
        study = OperabilityStudy(**st)
        scatter = load_scatter(doc["scatter"])
        tps, why = cell_periods(scatter, study.spectrum)
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise PlanError(f"{summary}: not an operability study's summary ({one_reason(err)})") from None
    except OperabilityError as err:
        raise PlanError(f"{summary}: {err}") from None
    vid = doc["vessel_id"] if "vessel_id" in doc else vessel_id(study.vessel)  # as the study hashed it
    return StudyCells(out, study, scatter, tps, why, vid)


def one_reason(err: BaseException) -> str:
    return f"{type(err).__name__}: {err}" if str(err) else type(err).__name__


def _angle(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def lookup_chart(cache: ChartCells, hs: float, period: float, kind: str, heading: float, where: str) -> dict:
    """A load-chart study's answer for one forecast sea and the planned lift (module text): the cells it reads,
    ψ, the SWL and whether the payload fits."""
    from app.analysis.loadchart import cell_key, cell_params
    from app.marine.waves import SeaStateError, tp_from_tz

    st = cache.study
    hs_rows = sorted({h for h, _ in cache.seas})
    above = [h for h in hs_rows if h >= hs - 1e-9]
    if not above:
        raise PlanError(f"{where}: Hs {hs:g} m is above the study's largest ({hs_rows[-1]:g} m)")
    h_row = above[0]
    tps = sorted(t for h, t in cache.seas if h == h_row)
    p = period
    if kind == "tz":
        try:
            p = tp_from_tz(st.spectrum, h_row, period)
        except (SeaStateError, ValueError) as err:
            raise PlanError(f"{where}: Tz {period:g} s: {err}") from None
    half = 0.5 * float(np.min(np.diff(tps))) if len(tps) > 1 else PERIOD_TOLERANCE
    if p < tps[0] - half or p > tps[-1] + half:
        span = f"{tps[0]:g}–{tps[-1]:g} s" if len(tps) > 1 else f"{tps[0]:g} ± {PERIOD_TOLERANCE:g} s"
        raise PlanError(f"{where}: Tp {p:.3g} s is outside the study's periods at Hs {h_row:g} m ({span})")
    if _angle(heading, st.heading) > HEADING_TOLERANCE:
        raise PlanError(f"{where}: heading {heading:g}° is more than {HEADING_TOLERANCE:g}° from the study's "
                        f"({st.heading:g}°)")  # fmt: skip
    radii = _bracket(st.radii, cache.radius)
    payloads = _bracket(st.payloads, cache.payload)
    psi = 0.0
    for r_row in radii:
        for m_row in payloads:
            for tp in tps:
                for seed in range(1, st.seeds + 1):
                    key = cell_key(cell_params(st, cache.mode, m_row, r_row, h_row, tp, seed, cache.vessel_id,
                                               cache.crane_id))  # fmt: skip
                    try:
                        text = (cache.out / "cells" / f"{key}.json").read_text(encoding="utf-8")
                        psi = max(psi, float(json.loads(text)["psi"]))
                    except (OSError, ValueError, KeyError):
                        raise PlanError(
                            f"{where}: the study's cell {cache.mode}, {m_row:g} t, {r_row:g} m, Hs {h_row:g} m, "
                            f"Tp {tp:g} s (seed {seed}) is not in {cache.out}/cells: run the study again to finish it"
                        ) from None
    swl = cache.rating.at(cache.radius) / 1000.0 / psi
    fits = cache.payload <= swl
    return {
        "cell_hs": h_row, "cell_radii": radii, "cell_payloads": payloads, "psi": psi, "swl_t": swl,
        "workable": fits, "why_not": "" if fits else f"over its SWL: {cache.payload:g} t > {swl:.2f} t (ψ {psi:.2f})",
    }  # fmt: skip


def _bracket(values, x: float) -> list[float]:
    """The study's values on either side of ``x`` (one when it is one of them)."""
    below = max(v for v in values if v <= x + 1e-9)
    above = min(v for v in values if v >= x - 1e-9)
    return [float(below)] if below == above else [float(below), float(above)]


def lookup(cache: StudyCells, hs: float, period: float, kind: str, heading: float, where: str) -> dict[str, Any]:
    """The study's cell for one forecast sea (module text): its Hs, period and heading, whether it is workable,
    the mean rms(e_c) of its seeds and the reason when not.  ``where``: the forecast's file and line, for the
    refusal."""
    from app.analysis.operability import cell_key, cell_params
    from app.marine.waves import SeaStateError, tp_from_tz, zero_crossing_period

    st, sc = cache.study, cache.scatter
    above = np.nonzero(sc.hs >= hs - 1e-9)[0]
    if above.size == 0:
        raise PlanError(f"{where}: Hs {hs:g} m is above the study's largest ({sc.hs[-1]:g} m)")
    i = int(above[0])
    p = period  # in the study's kind: turned with the study's spectrum at the cell's Hs when the kinds differ
    try:
        if kind == "tp" and sc.period == "tz":
            p = zero_crossing_period(st.spectrum, float(sc.hs[i]), period)
        elif kind == "tz" and sc.period == "tp":
            p = tp_from_tz(st.spectrum, float(sc.hs[i]), period)
    except (SeaStateError, ValueError) as err:
        raise PlanError(f"{where}: {kind.capitalize()} {period:g} s: {err}") from None
    t = sc.t
    half = 0.5 * (float(np.min(np.diff(t))) if t.size > 1 else float(t[0]))
    if p < t[0] - half or p > t[-1] + half:
        raise PlanError(f"{where}: {sc.period_label} {p:.3g} s is outside the study's periods ({t[0]:g}–{t[-1]:g} s)")
    j = int(np.argmin(np.abs(t - p)))
    gaps = [_angle(heading, h) for h in st.headings]
    k = int(np.argmin(gaps))
    if gaps[k] > HEADING_TOLERANCE:
        heads = ", ".join(f"{h:g}" for h in st.headings)
        raise PlanError(
            f"{where}: heading {heading:g}° is more than {HEADING_TOLERANCE:g}° from the study's ({heads}°)"
        )
    cell = {
        "cell_hs": float(sc.hs[i]), f"cell_{sc.period}": float(t[j]), "cell_heading": float(st.headings[k]),
        "rms_e_c_m": None, "workable": False, "why_not": "",
    }  # fmt: skip
    if sc.prob[i, j] <= 0:
        raise PlanError(
            f"{where}: the study did not simulate Hs {sc.hs[i]:g} m, {sc.period_label} {t[j]:g} s (probability 0 in "
            f"its scatter {sc.source})"
        )
    if (i, j) in cache.why:
        cell["why_not"] = f"breaking sea ({cache.why[(i, j)]})"
        return cell
    tp = float(cache.tps[i, j])
    rms = []
    for seed in range(1, st.seeds + 1):
        key = cell_key(cell_params(st, float(sc.hs[i]), tp, float(st.headings[k]), seed, cache.vessel_id))
        f = cache.out / "cells" / f"{key}.json"
        try:
            rms.append(float(json.loads(f.read_text(encoding="utf-8"))["rms_e_c_m"]))
        except (OSError, ValueError, KeyError):
            raise PlanError(
                f"{where}: the study's cell Hs {sc.hs[i]:g} m, {sc.period_label} {t[j]:g} s, {st.headings[k]:g}° "
                f"(seed {seed}) is not in {cache.out}/cells: run the study again to finish it"
            ) from None
    m = float(np.mean(rms))
    cell["rms_e_c_m"] = m
    cell["workable"] = m <= st.criterion
    if not cell["workable"]:
        cell["why_not"] = f"rms(e_c) {m:.4g} m > {st.criterion:g} m"
    return cell


def make_plan(forecast: Forecast, cache: StudyCells | ChartCells) -> list[dict[str, Any]]:
    """One row per forecast time: the forecast, the study's cell it falls in, workable and why not."""
    look = lookup_chart if isinstance(cache, ChartCells) else lookup
    steps = [(b - a).total_seconds() / 3600.0 for a, b in zip(forecast.times, forecast.times[1:], strict=False)]
    last = float(np.median(steps)) if steps else 1.0
    rows = []
    for r in range(len(forecast.times)):
        where = f"{forecast.source}:{forecast.lines[r]}"
        cell = look(cache, float(forecast.hs[r]), float(forecast.period[r]), forecast.kind,
                      float(forecast.heading[r]), where)  # fmt: skip
        rows.append({
            "time": forecast.times[r].isoformat(), "hours": steps[r] if r < len(steps) else last,
            "hs": float(forecast.hs[r]), forecast.kind: float(forecast.period[r]),
            "heading": float(forecast.heading[r]), **cell,
        })  # fmt: skip
    return rows


def save_plan(
    rows: list[dict[str, Any]], forecast: Forecast, cache: StudyCells | ChartCells, out: str | Path
) -> dict[str, Any]:
    """plan.csv, plan.json and plan.png (a Gantt-style chart: workable hours green, the others red with their
    reason, the forecast's Hs below)."""
    from app.analysis.figures import pyplot, save_figure

    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise PlanError(f"cannot create output folder {out}: {err.strerror or err}") from None
    cols = list(rows[0])
    with open(out / "plan.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for row in rows:
            w.writerow(["" if row[c] is None else f"{row[c]:.6g}" if isinstance(row[c], float) else row[c]
                        for c in cols])  # fmt: skip
    hours = sum(r["hours"] for r in rows)
    good = sum(r["hours"] for r in rows if r["workable"])
    st = cache.study
    chart = isinstance(cache, ChartCells)
    crit = (
        {"lift": {"payload_t": cache.payload, "radius_m": cache.radius}, "criterion": "payload ≤ SWL"}
        if chart
        else {"criterion_rms_e_c_m": st.criterion}
    )
    doc = {
        "forecast": forecast.source, "study": str(cache.out), "mode": cache.mode if chart else st.mode, **crit,
        "hours": hours, "workable_hours": good, "workable_share": good / hours if hours else 0.0,
        "windows": _windows(rows), "rows": rows,
    }  # fmt: skip
    (out / "plan.json").write_text(json.dumps(doc, indent=2), encoding="utf-8")
    plt = pyplot()
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(10, 4.2), sharex=True, gridspec_kw={"height_ratios": [1, 2]})
    t0 = forecast.times[0]
    x = [(t - t0).total_seconds() / 3600.0 for t in forecast.times]
    reasons = sorted({r["why_not"].split(" (")[0].split(" ")[0] for r in rows if not r["workable"]})
    reasons = ["over its SWL" if r == "over" else r for r in reasons]
    span = x[-1] + rows[-1]["hours"]
    runs: list[list] = []  # consecutive times with the same verdict (and the same failing criterion): one bar
    for r, xi in zip(rows, x, strict=True):
        what = "workable" if r["workable"] else r["why_not"].split(" (")[0].split(" ")[0]
        if runs and runs[-1][0] == what:
            runs[-1][2] += r["hours"]
        else:
            runs.append([what, xi, r["hours"]])
    for what, xi, h in runs:
        ax.broken_barh([(xi, h)], (0, 1), color="tab:green" if what == "workable" else "tab:red", lw=0)
        if h >= 0.06 * span:  # the verdict on its bar where it fits
            label = {"workable": "workable", "over": "over its SWL"}.get(what) or (
                f"rms(e_c) > {st.criterion:g} m" if what == "rms(e_c)" else "breaking sea"
            )
            label = f"{label}\n{h:g} h"
            ax.text(xi + h / 2, 0.5, label, ha="center", va="center", fontsize=8, color="white")
    ax.set_yticks([0.5], ["lift"])
    ax.set_ylim(0, 1)
    rule = (
        f"{cache.mode}, {cache.payload:g} t at {cache.radius:g} m ≤ its SWL"
        if chart
        else f"{st.mode}, rms(e_c) ≤ {st.criterion:g} m"
    )
    ax.set_title(
        f"workable ({rule}): {good:g} of {hours:g} h green; red: " + (", ".join(reasons) if reasons else "none"),
        fontsize=9,
    )
    ax2.step(x + [x[-1] + rows[-1]["hours"]], list(forecast.hs) + [forecast.hs[-1]], where="post", color="tab:blue")
    ax2.set_ylabel("Hs [m]")
    ax2.set_xlabel(f"hours from {t0.isoformat()}")
    ax2.grid(alpha=0.3)
    save_figure(plt, fig, out / "plan.png")
    return doc


def _windows(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The workable stretches: start time and hours."""
    out: list[dict[str, Any]] = []
    for r in rows:
        if r["workable"] and out and out[-1]["open"]:
            out[-1]["hours"] += r["hours"]
        elif r["workable"]:
            out.append({"start": r["time"], "hours": r["hours"], "open": True})
        elif out:
            out[-1]["open"] = False
    return [{"start": w["start"], "hours": w["hours"]} for w in out]
