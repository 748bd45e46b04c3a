"""``bosun study operability``: crane-head compensation over a wave scatter diagram (Dask); ``bosun plan``: a
forecast looked up in such a study's cells (issue 31, item 5)."""

from __future__ import annotations

import argparse
from pathlib import Path

from app.cli.args import SPECTRA, TAC_MODES, command, group
from app.cli.common import _as_usage_error, _finite_float, _positive_float, _positive_int, _print_json, _progress_bar
from app.errors import BosunError


def _quiet_dask() -> None:
    """Dask's own log lines are not a study command's news, for the whole command: a Ctrl-C that ends the local
    workers made the client's loop thread log "Batched Comm Closed" with a traceback after the study had returned
    (the quiet context around the run had ended), before "bosun: interrupted" (CI, 2026-11-29, twice).  Set after
    Dask's import, which sets its loggers' levels from its config (set before it, they were undone); without Dask
    the study says how to install it."""
    import contextlib
    import logging

    with contextlib.suppress(ImportError):
        import distributed  # noqa: F401
    for name in ("distributed", "distributed.client", "distributed.gc"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


# ----------------------------------------------------------------------------- operability (issue 17)
def cmd_study_operability(args: argparse.Namespace) -> int:
    """The crane-head compensation's operability over a scatter diagram, one simulation per cell on Dask."""
    from app.analysis.operability import (
        OperabilityError,
        OperabilityStudy,
        check_scheduler,
        check_study,
        load_scatter,
        run_study,
        save,
    )

    _quiet_dask()
    with _as_usage_error(OperabilityError):
        # a bad scheduler first: refused within seconds, before the vessel and the simulation are loaded
        scheduler = check_scheduler(args.scheduler) if args.scheduler else None
        scatter = load_scatter(args.scatter)
        # by default the spectrum a diagram's kind is stated with: Pierson–Moskowitz for a Tz diagram (IACS
        # Rec. 34 pairs its table with it), JONSWAP for a Tp one
        spectrum = args.spectrum or ("pm" if scatter.period == "tz" else "jonswap")
        study = OperabilityStudy(
            mode=args.mode, headings=tuple(args.headings), seeds=args.seeds, duration=args.duration,
            criterion=args.criterion, vessel=args.vessel, spectrum=spectrum,
        )  # fmt: skip
        check_study(study, scatter, args.max_runs)  # its size, vessel and scenario, before any file or process
        out = Path(args.out)
        if out.exists() and not out.is_dir():
            raise BosunError(f"output folder {out} is a file")
        result = run_study(
            study, scatter, out, scheduler=scheduler, workers=args.workers,
            progress=_progress_bar("study operability", unit="sim"), max_runs=args.max_runs,
        )  # fmt: skip
        doc = save(result, out)
    if args.json:
        _print_json({**doc, "out": str(out)})
        return 0
    where = "cache" if not result.computed else f"{result.workers} workers at {result.scheduler}"
    n_cells = len(result.table) // len(study.headings)
    print(
        f"operability of {study.mode} over {scatter.source} ({study.spectrum} spectrum), rms(e_c) ≤ "
        f"{study.criterion:g} m: {n_cells} cells × {len(study.headings)} headings × {study.seeds} seeds, "
        f"{result.computed} simulated ({where}), {result.cached} from the cache, {result.wall_s:.0f} s"
    )
    if result.unsimulated > 0:
        n_broken = sum(1 for row in result.table if row["rms_e_c_m"] is None) // len(study.headings)
        print(
            f"  {n_broken} cells ({100 * result.unsimulated:.2f} % of the time) are breaking seas for this spectrum "
            "(DNV-RP-C205 §3.5.5.4): not simulated, counted as not workable"
        )
    for h, v in result.operability.items():
        print(f"  heading {h:5g}°: {100 * v:5.1f} % workable")
    if doc["cells_per_minute"]:
        print(f"  {doc['cells_per_minute']:.1f} simulations per minute")
    print(f"wrote {out}/table.csv, summary.json, operability_polar.png, heatmap.png (cells cached in {out}/cells)")
    return 0


# ----------------------------------------------------------------------------- load chart (issue 31, item 4)
def cmd_study_loadchart(args: argparse.Namespace) -> int:
    """SWL(radius, Hs) = the crane's rated capacity / the simulated dynamic factor, per mode and payload (Dask)."""

    from app.analysis.loadchart import (
        LoadChartError,
        LoadChartStudy,
        check_study,
        parse_list,
        run_study,
        save,
        scatter_seas,
    )
    from app.analysis.operability import check_scheduler, load_scatter

    _quiet_dask()
    with _as_usage_error(LoadChartError):
        scheduler = check_scheduler(args.scheduler) if args.scheduler else None
        radii = parse_list(args.radii, "--radii")
        payloads = parse_list(args.payloads, "--payloads")
        modes = tuple(m.strip() for m in args.modes.split(","))
        if (args.hs is None) == (args.scatter is None):
            raise LoadChartError("give the seas as --hs H1,H2,… (at --tp) or as --scatter NAME|FILE, one of the two")
        if args.scatter is not None:
            scatter = load_scatter(args.scatter)
            spectrum = args.spectrum or ("pm" if scatter.period == "tz" else "jonswap")
            seas, broken = scatter_seas(scatter, spectrum)
            source = scatter.source + (f" ({100 * broken:.2f} % breaking seas left out)" if broken else "")
        else:
            spectrum = args.spectrum or "jonswap"
            heights = parse_list(args.hs, "--hs", zero=True)
            if len(set(heights)) != len(heights):
                raise LoadChartError(f"--hs: a height repeated ({args.hs})")
            seas = [(h, args.tp) for h in heights]
            source = f"Tp {args.tp:g} s"
        study = LoadChartStudy(
            radii=radii, payloads=payloads, modes=modes, heading=args.heading, seeds=args.seeds,
            duration=args.duration, vessel=args.vessel, spectrum=spectrum,
        )  # fmt: skip
        check_study(study, seas, args.max_runs)
        out = Path(args.out)
        if out.exists() and not out.is_dir():
            raise BosunError(f"output folder {out} is a file")
        result = run_study(
            study, seas, out, source=source, scheduler=scheduler, workers=args.workers,
            progress=_progress_bar("study loadchart", unit="sim"), max_runs=args.max_runs,
        )  # fmt: skip
        doc = save(result, out)
    if args.json:
        _print_json({**doc, "out": str(out)})
        return 0
    where = f"{result.computed} run on {result.workers} workers at {result.scheduler}, " if result.computed else ""
    print(
        f"load chart, {source}, heading {study.heading:g}°: {len(result.cells)} simulations ({where}{result.cached} "
        f"from the cache), {result.wall_s:.0f} s"
    )
    hs_all = sorted({r["hs"] for r in result.table})
    cell = {(r["mode"], r["payload_t"], r["radius_m"], r["hs"]): r for r in result.table}
    print("  SWL [t] (ψ); * the payload is over its SWL")
    for mode in study.modes:
        for payload in study.payloads:
            head = f"{mode}, {payload:g} t"
            print(f"  {head:16s}" + "".join(f"{'Hs ' + format(h, 'g') + ' m':>16s}" for h in hs_all))
            for radius in study.radii:
                rows = [cell[(mode, payload, radius, h)] for h in hs_all]
                text = "".join(f"{r['swl_t']:9.1f}{'*' if not r['fits'] else ' '}({r['psi']:.2f})" for r in rows)
                print(f"  {radius:14g} m" + text)
    ch = result.checks
    falls = "yes" if ch["falls_with_hs"] else "no: " + "; ".join(ch["rises"])
    print(f"  each payload's chart falls as Hs grows: {falls}")
    if ch["compensated_above_off"] is not None:
        verdict = "yes" if ch["compensated_above_off"] else "no: " + "; ".join(ch["below_off"])
        print(f"  compensated on or above off: {verdict}")
    print(f"wrote {out}/loadchart.csv, summary.json, loadchart.png (cells cached in {out}/cells)")
    return 0


# ----------------------------------------------------------------------------- plan (issue 31, item 5)
def cmd_plan(args: argparse.Namespace) -> int:
    """Hour by hour, whether a forecast's seas are workable by a study's cached cells, and why not."""
    import time

    from app.analysis.plan import PlanError, load_forecast, load_study, make_plan, save_plan

    t0 = time.perf_counter()
    with _as_usage_error(PlanError):
        cache = load_study(args.study, args.criterion, args.payload, args.radius, args.mode)
        forecast = load_forecast(args.forecast)
        rows = make_plan(forecast, cache)
        out = Path(args.out) if args.out else Path("out") / "plan"
        if out.exists() and not out.is_dir():
            raise BosunError(f"output folder {out} is a file")
        doc = save_plan(rows, forecast, cache, out)
    wall = time.perf_counter() - t0
    if args.json:
        _print_json({**doc, "out": str(out), "wall_s": wall})
        return 0
    st = cache.study
    rule = (
        f"{cache.mode}, {cache.payload:g} t at {cache.radius:g} m ≤ its SWL"
        if "lift" in doc
        else f"{st.mode}, rms(e_c) ≤ {st.criterion:g} m"
    )
    print(
        f"plan: {forecast.source} against {cache.out} ({rule}): "
        f"{doc['workable_hours']:g} of {doc['hours']:g} h workable ({100 * doc['workable_share']:.0f} %)"
    )
    for r in rows:
        period = f"{forecast.kind.capitalize()} {r[forecast.kind]:g} s"
        verdict = "workable" if r["workable"] else f"NOT workable: {r['why_not']}"
        print(f"  {r['time']}  Hs {r['hs']:g} m, {period}, {r['heading']:g}°  {verdict}")
    for w in doc["windows"]:
        print(f"  window: {w['start']} for {w['hours']:g} h")
    print(f"wrote {out}/plan.csv, plan.json, plan.png ({wall:.1f} s)")
    return 0


# app.analysis.operability's MAX_RUNS and RUNS_CEILING (tests/test_cli.py keeps them equal): constants here, so
# that building the parser does not import the study (NumPy, Dask's set-up) at every start
MAX_STUDY_RUNS = 10_000
STUDY_RUNS_CEILING = 100_000


def register(sub) -> None:
    """Add this group's commands to ``bosun``'s subparsers."""
    stu = group(
        sub,
        "study",
        "studies on a Dask cluster: study operability (scatter diagram × headings × seeds), study loadchart (SWL "
        "per radius and sea)",
        "study_cmd",
    )
    with command(
        stu,
        "operability",
        cmd_study_operability,
        help="crane-head compensation over a wave scatter diagram: one simulation per cell (Dask)",
    ) as b:
        b.add_argument("--mode", choices=list(TAC_MODES), default="tac", help="compensation (default tac)")
        b.add_argument(
            "--scatter", required=True, metavar="NAME|FILE",
            help="north-atlantic (IACS Rec. 34, Hs × Tz) or a CSV: hs\\tp,TP1,… (or hs\\tz,TZ1,…) then HS,p1,…",
        )  # fmt: skip
        b.add_argument(
            "--headings", type=_finite_float, nargs="+", default=[90.0, 135.0, 180.0],
            help="[deg], each within ±360 (default 90 135 180)",
        )  # fmt: skip
        b.add_argument(
            "--seeds", type=_positive_int, default=2, help="wave seeds per cell and heading, 1–1000 (default 2)"
        )
        b.add_argument(
            "--max-runs", type=_positive_int, default=MAX_STUDY_RUNS, metavar="N",
            help=f"the largest study run: cells with a probability × headings × seeds (default {MAX_STUDY_RUNS}; "
            f"at most {STUDY_RUNS_CEILING}); a bigger one is refused before any work",
        )  # fmt: skip
        b.add_argument(
            "--duration", type=_positive_float, default=300.0, help="simulated time per run [s], ≤ 10800 (300)"
        )
        b.add_argument("--criterion", type=_positive_float, default=0.1, help="workable: rms(e_c) ≤ this [m] (0.1)")
        b.add_argument("--vessel", default=None, metavar="NAME|FILE", help="vessel (default supply); bosun vessel list")
        b.add_argument(
            "--spectrum", choices=list(SPECTRA), default=None,
            help="default: pm for a Tz diagram (as IACS Rec. 34 states it), jonswap for a Tp one",
        )  # fmt: skip
        b.add_argument(
            "--scheduler", default=None, metavar="tcp://HOST:8786",
            help="a Dask scheduler (default: a local cluster); a peer that does not answer as a scheduler within 4 s "
            "is refused",
        )  # fmt: skip
        b.add_argument(
            "--workers",
            type=_positive_int,
            default=None,
            help="local cluster's worker processes, 1–64 (default: cores)",
        )
        b.add_argument("--out", default="out/operability", help="output folder; its cells/ are the resume cache")
    with command(
        stu,
        "loadchart",
        cmd_study_loadchart,
        help="a load chart derated by the sea: SWL(radius, Hs) = rated capacity / simulated dynamic factor (Dask)",
    ) as b:
        b.add_argument("--radii", default="20,25,30", metavar="R1,R2,…", help="crane radii [m] (default 20,25,30)")
        b.add_argument("--payloads", default="2,5,10", metavar="M1,M2,…", help="payloads [t] (default 2,5,10)")
        b.add_argument("--hs", default=None, metavar="H1,H2,…", help="sea heights Hs [m] at --tp (0: flat)")
        b.add_argument("--tp", type=_positive_float, default=9.0, help="peak period with --hs [s] (default 9)")
        b.add_argument(
            "--scatter", default=None, metavar="NAME|FILE",
            help="instead of --hs: a scatter diagram's cells (north-atlantic or a CSV as study operability's); the "
            "chart at an Hs takes its worst period",
        )  # fmt: skip
        b.add_argument("--heading", type=_finite_float, default=90.0, help="wave heading [deg] (default 90, beam)")
        b.add_argument(
            "--modes", default="off,compensated,antisway", metavar="M1,M2,…",
            help="off, compensated, antisway (default all three)",
        )  # fmt: skip
        b.add_argument("--seeds", type=_positive_int, default=2, help="wave seeds per cell (2); ψ: their largest")
        b.add_argument(
            "--duration", type=_positive_float, default=600.0,
            help="simulated time per run after a 60 s lead-in [s], ≤ 10800 (default 600)",
        )  # fmt: skip
        b.add_argument("--vessel", default=None, metavar="NAME|FILE", help="vessel (default supply); bosun vessel list")
        b.add_argument("--spectrum", choices=list(SPECTRA), default=None, help="default jonswap (pm for a Tz diagram)")
        b.add_argument(
            "--max-runs", type=_positive_int, default=MAX_STUDY_RUNS, metavar="N",
            help=f"the largest study run (default {MAX_STUDY_RUNS}; at most {STUDY_RUNS_CEILING})",
        )  # fmt: skip
        b.add_argument(
            "--scheduler", default=None, metavar="tcp://HOST:8786", help="a Dask scheduler (default: a local cluster)"
        )
        b.add_argument("--workers", type=_positive_int, default=None, help="local cluster's workers, 1–64 (cores)")
        b.add_argument("--out", default="out/loadchart", help="output folder; its cells/ are the resume cache")
    with command(
        sub,
        "plan",
        cmd_plan,
        help="a forecast plan: hour by hour, is the lift workable by an operability or load-chart study's cached "
        "cells, and why not (issue 31)",
    ) as b:
        b.add_argument(
            "--forecast", required=True, metavar="FILE.csv",
            help="CSV: time,hs,tp,heading (or tz): ISO 8601 times, Hs [m], period [s], wave heading to the vessel "
            "[deg]",
        )  # fmt: skip
        b.add_argument(
            "--study", required=True, metavar="DIR", help="an operability or load-chart study's --out folder"
        )
        b.add_argument(
            "--criterion", type=_positive_float, default=None, metavar="M",
            help="workable: rms(e_c) ≤ this [m] (default: the study's; an operability study's)",
        )  # fmt: skip
        b.add_argument("--payload", type=_positive_float, default=None, metavar="T",
                       help="a load-chart study's lift: the load [t]")  # fmt: skip
        b.add_argument("--radius", type=_positive_float, default=None, metavar="M",
                       help="a load-chart study's lift: the crane's radius [m]")  # fmt: skip
        b.add_argument("--mode", choices=["off", "compensated", "antisway"], default=None,
                       help="a load-chart study's lift: its mode (default compensated when studied)")  # fmt: skip
        b.add_argument("--out", default=None, help="output folder (default out/plan)")
