"""``bosun study operability``: crane-head compensation over a wave scatter diagram (Dask); ``bosun plan``: a
forecast looked up in such a study's cells (issue 31, item 5)."""

from __future__ import annotations

import argparse
from pathlib import Path

from app.cli.args import SPECTRA, TAC_MODES, command, group
from app.cli.common import _as_usage_error, _finite_float, _positive_float, _positive_int, _print_json, _progress_bar
from app.errors import BosunError


# ----------------------------------------------------------------------------- operability (issue 17)
def cmd_study_operability(args: argparse.Namespace) -> int:
    """The crane-head compensation's operability over a scatter diagram, one simulation per cell on Dask."""
    # Dask's own log lines are not the command's news, for the whole command: a Ctrl-C that ends the local
    # workers made the client's loop thread log "Batched Comm Closed" with a traceback after the study had
    # returned (the quiet context around the run had ended), before "bosun: interrupted" (CI, 2026-11-29, twice)
    # (after Dask's import, which sets its loggers' levels from its config: set before it, they were undone)
    import contextlib
    import logging

    from app.analysis.operability import (
        OperabilityError,
        OperabilityStudy,
        check_scheduler,
        check_study,
        load_scatter,
        run_study,
        save,
    )

    with contextlib.suppress(ImportError):  # without Dask, run_study says how to install it
        import distributed  # noqa: F401
    for name in ("distributed", "distributed.client", "distributed.gc"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
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


# ----------------------------------------------------------------------------- plan (issue 31, item 5)
def cmd_plan(args: argparse.Namespace) -> int:
    """Hour by hour, whether a forecast's seas are workable by a study's cached cells, and why not."""
    import time

    from app.analysis.plan import PlanError, load_forecast, load_study, make_plan, save_plan

    t0 = time.perf_counter()
    with _as_usage_error(PlanError):
        cache = load_study(args.study, args.criterion)
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
    print(
        f"plan: {forecast.source} against {cache.out} ({st.mode}, rms(e_c) ≤ {st.criterion:g} m): "
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
        sub, "study", "studies on a Dask cluster: study operability (scatter diagram × headings × seeds)", "study_cmd"
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
        sub,
        "plan",
        cmd_plan,
        help="a forecast plan: hour by hour, is the lift workable by an operability study's cached cells, and why "
        "not (issue 31)",
    ) as b:
        b.add_argument(
            "--forecast", required=True, metavar="FILE.csv",
            help="CSV: time,hs,tp,heading (or tz): ISO 8601 times, Hs [m], period [s], wave heading to the vessel "
            "[deg]",
        )  # fmt: skip
        b.add_argument("--study", required=True, metavar="DIR", help="an operability study's --out folder")
        b.add_argument(
            "--criterion", type=_positive_float, default=None, metavar="M",
            help="workable: rms(e_c) ≤ this [m] (default: the study's)",
        )  # fmt: skip
        b.add_argument("--out", default=None, help="output folder (default out/plan)")
