"""``bosun sim tac|tac-sweep|vvmc|antisway|transfer|predict``: the papers' simulations, the compensated lift and
the motion prediction."""

from __future__ import annotations

import argparse

from app.cli.args import (
    TAC_MODES,
    add_duration,
    add_hs,
    add_json,
    add_out,
    add_spectrum,
    add_tp,
    add_vessel,
    add_wave_seed,
    command,
    group,
)
from app.cli.common import (
    _as_usage_error,
    _fields,
    _finite_float,
    _make_out,
    _positive_float,
    _progress_bar,
    _table,
    _write_run,
)
from app.errors import BosunError

# the options of sim tac and tac-sweep that are TacScenario's fields by the same name (hs and mode aside)
_TAC_FIELDS = (
    "tp", "heading", "spectrum", "spreading", "duration", "dt", "seed", "rao", "roll_damping", "crane_share",
    "crane_kp", "mru_noise", "delay", "predict",
)  # fmt: skip
# those of sim vvmc, VvmcScenario's fields
_VVMC_FIELDS = (
    "hs", "tp", "spectrum", "heading1", "heading2", "duration", "dt", "seed", "rao", "sensors", "antisway", "delay",
    "predict",
)  # fmt: skip


def _scenario(args: argparse.Namespace, **over):
    from app.scenarios.tac import ScenarioError, TacScenario

    with _as_usage_error(ScenarioError):
        return TacScenario(
            **_fields(args, *_TAC_FIELDS),
            hs=over.get("hs", getattr(args, "hs", 3.0)),
            mode=over.get("mode", getattr(args, "mode", "tac")),
        )


def cmd_sim_vvmc(args: argparse.Namespace) -> int:
    import time

    from app.analysis.vvmc_report import save_runs
    from app.marine.vessels import vessel_label
    from app.scenarios.vvmc import VvmcError, VvmcScenario, simulate

    with _as_usage_error(VvmcError):
        sc = VvmcScenario(**_fields(args, *_VVMC_FIELDS))
    out = _make_out(args, f"vvmc_hs{sc.hs:g}_seed{sc.seed}_{sc.sensors}" + ("_antisway" if sc.antisway else ""))
    n = round((sc.duration + sc.lead_in) / sc.dt)
    bar = _progress_bar("sim vvmc", unit="step")
    t0 = time.perf_counter()
    on = simulate(sc, True, progress=lambda k: bar(k, 2 * n))
    off = simulate(sc, False, progress=lambda k: bar(n + k, 2 * n))
    speed = 2 * (sc.duration + sc.lead_in) / (time.perf_counter() - t0)
    doc = _write_run(args, out, lambda tmp: save_runs(sc, on, off, tmp, speed))
    if args.json:
        return 0
    c, u = doc["compensated"], doc["uncompensated"]
    print(
        f"VVMC: Hs {sc.hs:g} m, Tp {sc.tp:g} s, EM8000 heading {sc.heading1:g}°, EM1500 {sc.heading2:g}°, "
        f"{sc.duration:g} s, seed {sc.seed} (vessel {vessel_label(sc.rao)}); "
        f"the controllers see the platforms through: {_SENSOR_NAMES[sc.sensors]}"
        + ("; anti-swing on" if sc.antisway else "")
        + (f"; {sc.delay:g} s late" + (", predicted" if sc.predict else "") if sc.delay or sc.predict else "")
    )
    print(
        f"  tool point rel. EM1500, rms: {1000 * u['rms_tool_error_m']:.1f} mm without, "
        f"{1000 * c['rms_tool_error_m']:.2f} mm with VVMC  (reduction {doc['reduction_percent']:.1f} %)"
    )
    print(
        f"  payload swing rms {c['payload_swing_rms_deg']:.2f}° (max {c['payload_swing_max_deg']:.2f}°), "
        f"height error rms {1000 * c['rms_payload_height_error_m']:.1f} mm"
    )
    util = ", ".join(f"{100 * v:.0f}" for v in c["joint_speed_utilisation"])
    print(
        f"  joint speed use [%]: {util}; winch speed use {100 * c['winch_speed_utilisation']:.0f} %; "
        f"time at a limit {c['time_at_limit_s']:.1f} s"
    )
    print(
        f"  {speed:.1f}× real time; wrote {out}/timeseries.csv, platforms.png, tool_error.png, "
        "robot_winch_load.png, summary.json"
    )
    return 0


def _add_delay(p: argparse.ArgumentParser, seen: str, source: str) -> None:
    """``--delay S`` and ``--predict`` (issue 31, item 2): what the controllers see late, and from what."""
    p.add_argument("--delay", type=_finite_float, default=0.0, metavar="S", help=f"{seen} [s] (default 0)")
    p.add_argument(
        "--predict",
        action="store_true",
        help=f"feed the motion predicted --delay ahead from {source} (an online AR model, issue 31) instead",
    )


_SENSOR_NAMES = {
    "true": "the simulation's true states",
    "mru": "an MRU H on each platform",
    "tracker": "a laser tracker",
}


def cmd_sim_antisway(args: argparse.Namespace) -> int:
    """The anti-swing aims of issue 16: a 4° swing at L = 2 m (free) and VVMC at Hs (default 2 m)."""
    import time

    from app.analysis.antisway_report import save_antisway
    from app.scenarios.antisway import antisway_study, free_swing
    from app.scenarios.vvmc import VvmcError, VvmcScenario

    with _as_usage_error(VvmcError):
        sc = VvmcScenario(**_fields(args, "hs", "tp", "duration", "seed", "sensors"))
    out = _make_out(args, f"antisway_hs{sc.hs:g}_seed{sc.seed}")
    n = round(sc.duration / sc.dt)
    bar = _progress_bar("sim antisway", unit="step")
    t0 = time.perf_counter()
    free = [free_swing(active) for active in (False, True)]
    done = [0]

    def progress(k: int) -> None:
        bar(min(done[0] + k, 2 * n), 2 * n)
        if k == n:
            done[0] += n

    study = antisway_study(sc, progress=progress)
    wall = time.perf_counter() - t0
    doc = _write_run(args, out, lambda tmp: save_antisway(sc, free, study, tmp, wall))
    if args.json:
        return 0
    f0, f1 = doc["free_swing"]
    print("Anti-swing (LQR at L = 3 m, c = 0.1, Ts = 5 ms, scheduled over L; EKF on the wire angle):")
    t_off = (
        "not within {:.0f} s".format(f0["duration_s"])
        if f0["time_below_0_5_deg_s"] is None
        else (f"{f0['time_below_0_5_deg_s']:.1f} s")
    )
    t_on = "not reached" if f1["time_below_0_5_deg_s"] is None else f"{f1['time_below_0_5_deg_s']:.1f} s"
    print(f"  4° swing at L = 2 m below 0.5°: {t_on} with anti-swing, {t_off} without (aim ≤ 10 s)")
    a, b = doc["vvmc"], doc["vvmc_antisway"]
    print(
        f"  VVMC at Hs {sc.hs:g} m: swing rms {a['payload_swing_rms_deg']:.3f}° → {b['payload_swing_rms_deg']:.3f}° "
        f"({doc['swing_reduction_percent']:.0f} % less; aim ≥ 80 %), tool from the work point rms "
        f"{1000 * a['rms_tool_error_m']:.2f} → {1000 * b['rms_tool_error_m']:.2f} mm (aim ≤ 5 mm)"
    )
    print(
        f"  the pendulum's own oscillation (0.8-1.2 × √(g/L)/2π): {a['swing_pendulum_band_rms_deg']:.3f}° → "
        f"{b['swing_pendulum_band_rms_deg']:.3f}° rms ({doc['pendulum_band_reduction_percent']:.0f} % less); "
        "the rest is the forced lean φ ≈ a/g of the compensating tool"
    )
    print(f"  {wall:.0f} s; wrote {out}/free_swing.png, vvmc_swing.png, summary.json")
    return 0


def cmd_sim_tac(args: argparse.Namespace) -> int:
    from app.analysis.tac_report import save_run
    from app.marine.vessels import vessel_label
    from app.scenarios.tac import simulate

    sc = _scenario(args)
    out = _make_out(args, f"tac_{sc.mode}_hs{sc.hs:g}")
    bar = _progress_bar(f"sim tac {sc.mode}", unit="step")
    result = simulate(sc, progress=bar)
    doc = _write_run(args, out, lambda tmp: save_run(result, tmp))
    if args.json:
        return 0
    print(
        f"TAC {sc.mode}: Hs {sc.hs:g} m, Tp {sc.tp:g} s, heading {sc.heading:g}°, {sc.duration:g} s "
        + (f"(delay {sc.delay:g} s{', predicted' if sc.predict else ''}) " if sc.delay or sc.predict else "")
        + f"(vessel {vessel_label(sc.rao)})"
    )
    print(
        f"  e_c rms {doc['rms_e_c_m']:.3f} m (max {doc['max_e_c_m']:.3f})   e_s rms {doc['rms_e_s_m']:.3f} m "
        f"(max {doc['max_e_s_m']:.3f})   ratio {doc['ratio_rms']:.2%}   saturated {doc['saturated_pct']:.1f} %"
    )
    print(f"  x_d = {doc['x_d_m']:.3f} m   {doc['speed_x_realtime']:.0f}× real time")
    print(f"  wrote {out}/timeseries.csv, fig08–fig12 PNG, summary.json")
    return 0


def cmd_sim_sweep(args: argparse.Namespace) -> int:
    from app.analysis.tac_report import parse_range, save_sweep, sweep

    try:
        hs_values = parse_range(args.hs)
    except ValueError as err:
        raise BosunError(f"--hs: {err}") from None
    if not hs_values:
        raise BosunError("--hs: no values")
    modes = tuple(args.modes)
    base = _scenario(args, hs=hs_values[0], mode=modes[0])
    for hs in hs_values:  # check every sea state before any work
        _scenario(args, hs=hs)
    out = _make_out(args, "tac_sweep")
    rows = sweep(base, hs_values, modes, jobs=args.jobs, progress=_progress_bar("tac sweep", unit="run"))
    doc = _write_run(args, out, lambda tmp: save_sweep(rows, base, tmp))
    if args.json:
        return 0
    table = [
        [f"{r['hs']:g}", r["mode"], f"{r['ratio_rms']:.2%}", f"{r['rms_e_c_m']:.3f}", f"{r['saturated_pct']:.1f}"]
        for r in rows
    ]
    print(_table(["Hs [m]", "mode", "rms e_c/e_s", "rms e_c [m]", "saturated %"], table))
    for m, v in doc["max_hs_ratio_le_5pct"].items():
        print(f"  {m}: ratio ≤ 5 % up to Hs = {'—' if v is None else f'{v:g} m'}")
    print(f"  wrote {out}/sweep.csv, sweep.png, sweep.json")
    return 0


def cmd_sim_transfer(args: argparse.Namespace) -> int:
    """The compensated lift (issue 30, item 6): one transfer, and with ``--landings N`` N seeded landings."""
    import time

    from app.analysis.transfer_report import save_transfer
    from app.scenarios.transfer import TransferError, TransferScenario, landings, simulate

    if args.scene == "lab" and args.target is not None:
        raise BosunError("sim transfer --scene lab: --target is the crane's; the lab lands on EM1500's deck")
    if args.scene == "lab" and (args.target_vessel is not None):
        raise BosunError("sim transfer --scene lab: --target-vessel is the crane's; EM1500 plays --vessel too")
    if args.landings is not None and args.landings < 1:
        raise BosunError(f"--landings must be at least 1, got {args.landings}")
    with _as_usage_error(TransferError):
        sc = TransferScenario.for_scene(
            args.scene,
            **_fields(
                args, "hs", "tp", "heading", "spectrum", "seed", "rao", "target", "mode", "operator", "move_accel"
            ),
            target_rao=args.target_vessel,
            target_heading=args.target_heading,
            lead=not args.no_lead,
        )
        if sc.operator != "scripted":
            from app.scenarios.transfer import StickFile

            StickFile.read(sc.operator)  # a bad file is refused before anything runs
    out = _make_out(args, f"transfer_{sc.target}_{sc.mode}_hs{sc.hs:g}_seed{sc.seed}")
    bar = _progress_bar("sim transfer", unit="s")
    t0 = time.perf_counter()
    with _as_usage_error(TransferError):
        res = simulate(sc)
    wall = time.perf_counter() - t0
    speed = res.summary.get("duration_s", 0.0) / wall if wall > 0 else float("inf")
    many = None
    if args.landings:
        many = landings(sc, args.landings, progress=lambda k, n: bar(k, n))
    doc = _write_run(args, out, lambda tmp: save_transfer(res, tmp, many, speed))
    if args.json:
        return 0
    _print_transfer(sc, doc, out)
    return 0


def cmd_sim_predict(args: argparse.Namespace) -> int:
    """The crane tip's motion predicted from the MRU's signal alone (issue 31, item 1)."""
    import time

    from app.analysis.predict_report import save_predict
    from app.scenarios.predict import HORIZONS, PredictScenario, PredictScenarioError, simulate_predict

    with _as_usage_error(PredictScenarioError):
        sc = PredictScenario(
            **_fields(args, "hs", "tp", "heading", "spectrum", "seed", "duration", "rao", "target", "target_heading"),
            window_threshold=args.window_threshold,
            window_probability=args.window_probability,
            target_rao=args.target_vessel,
        )
    rel = "_relative" if sc.target == "vessel" else ""
    out = _make_out(args, f"predict{rel}_{sc.spectrum}_hs{sc.hs:g}_seed{sc.seed}")
    bar = _progress_bar("sim predict", unit="s")
    t0 = time.perf_counter()
    res = simulate_predict(sc, progress=lambda t, n: bar(t, n))
    wall = time.perf_counter() - t0
    doc = _write_run(args, out, lambda tmp: save_predict(res, tmp, wall))
    if args.json:
        return 0
    what = "crane tip over the second vessel's deck" if sc.target == "vessel" else "crane tip"
    print(
        f"{what} predicted from the MRU ({sc.spectrum}, Hs {sc.hs:g} m, Tp {sc.tp:g} s, heading {sc.heading:g}°, "
        f"seed {sc.seed}; scored {sc.duration - sc.warmup:g} s after a {sc.warmup:g} s warm-up)"
    )
    rms = doc["rms_true_m"]

    def cell(h: float, a: str) -> str:
        nr = doc["nrmse"][f"{h:g}"][a]
        return "still" if nr is None else f"{nr:.3f} / {doc['coverage'][f'{h:g}'][a]:.0%}"

    rows = [[f"{h:g} s", *(cell(h, a) for a in ("x", "y", "z"))] for h in HORIZONS]
    head = ["horizon", *(f"{a} ({rms[a]:.3g} m rms)" for a in ("x", "y", "z"))]
    print("  nrmse / ±2σ band coverage")
    for line in _table(head, rows).splitlines():
        print("  " + line)
    w = doc.get("windows")
    if w:
        prec = "—" if w["precision"] is None else f"{w['precision']:.0%}"
        rec = "—" if w["recall"] is None else f"{w['recall']:.0%}"
        print(
            f"  lift windows (heave within ±{w['threshold_m']:g} m for {w['length_s']:g} s): {w['n']} announced, "
            f"precision {prec}; {w['n_actual']} there were, recall {rec}"
        )
    print(f"  files in {out}")
    return 0


def _print_transfer(sc, doc: dict, out) -> None:
    where = "EM1500 (Motion-Lab)" if sc.scene == "lab" else f"the {sc.target}"

    def num(v, fmt):
        return "—" if v is None else format(v, fmt)

    print(
        f"transfer to {where}, {sc.mode}: Hs {sc.hs:g} m, Tp {sc.tp:g} s, heading {sc.heading:g}°, "
        f"seed {sc.seed}, operator {sc.operator}"
    )
    print(
        f"  path rms error {doc['path_rms_error_m']:.3f} m (target frame); touchdown at "
        f"{num(doc['touchdown_relative_speed_mps'], '.3f')} m/s relative (commanded "
        f"{num(doc['commanded_lowering_speed_mps'], 'g')}); re-hits {doc['rehits']}"
    )
    print(
        f"  swing peak {num(doc['peak_swing_deg'], '.2f')}°, residual {num(doc['residual_swing_deg'], '.2f')}° rms; "
        f"tension peak {doc['peak_tension_factor']:.2f}× static; {doc['duration_s']:.1f} s"
    )
    al = doc["alarms"]
    raised = [f"{k} {v:g}" for k, v in al.items() if v]
    print(f"  alarms: {', '.join(raised) if raised else 'none'}")
    if "landings" in doc:
        ld = doc["landings"]
        print(
            f"  {ld['n']} landings: touchdown speed error p95 {num(ld['touchdown_speed_error_p95_mps'], '.3f')} m/s, "
            f"re-hit free {num(ld['rehit_free_share'], '.0%')}"
        )
    print(f"  {doc['speed_x_realtime']:.0f}× real time; wrote {out}/timeseries.csv, transfer.png, summary.json")


def register(sub) -> None:
    """Add this group's commands to ``bosun``'s subparsers."""
    sims = group(
        sub,
        "sim",
        "simulations: sim tac, sim tac-sweep (crane head), sim vvmc, sim antisway (Motion-Lab), sim transfer (a lift)",
        "sim",
    )

    def add_sea_args(p: argparse.ArgumentParser) -> None:
        add_tp(p, 9.0)
        p.add_argument(
            "--heading",
            type=_finite_float,
            default=90.0,
            help="wave heading [deg], 0 following, 90 beam, 180 head (default 90)",
        )
        add_spectrum(p)
        p.add_argument(
            "--spreading", type=int, default=None, metavar="S", help="short-crested cos^2s sea (default long-crested)"
        )
        add_duration(p, 600.0)
        p.add_argument("--dt", type=_positive_float, default=0.01, help="time step [s] (default 0.01)")
        add_wave_seed(p)
        add_vessel(
            p,
            "vessel: supply (default: RAOs by boundary elements), supply-closed-form, or an RAO table "
            "(.mat MSS vessel or .csv); bosun vessel list",
        )
        p.add_argument(
            "--roll-damping", type=_positive_float, default=0.15, help="ζ44 of supply-closed-form (default 0.15)"
        )
        p.add_argument(
            "--crane-share",
            type=_finite_float,
            default=0.3,
            help="cooperative: share of the motion the crane takes (default 0.3)",
        )
        p.add_argument(
            "--crane-kp", type=_finite_float, default=1.0, help="cooperative: crane position gain [1/s] (default 1)"
        )
        p.add_argument(
            "--mru-noise", type=_finite_float, default=0.0, help="MRU noise scale, 1 = 2 cm / 0.05° (default 0: none)"
        )
        _add_delay(p, "the controller sees the MRU's η, ν this old", "the MRU")

    # the crane head's two take the sea's options, then --json, then --out
    tac_help = "one run: vessel in waves, crane and Delta head (CSV, Figs. 8–12, JSON)"
    with command(sims, "tac", cmd_sim_tac, json=False, help=tac_help) as b:
        add_hs(b, 3.0)
        b.add_argument("--mode", choices=list(TAC_MODES), default="tac", help="default tac")
        add_sea_args(b)
        add_json(b)
        add_out(b, "tac_MODE_hsHS")
    sweep_help = "rms(e_c)/rms(e_s) against Hs for each mode (table and plot)"
    with command(sims, "tac-sweep", cmd_sim_sweep, json=False, help=sweep_help) as b:
        b.add_argument("--hs", default="0.5:5:0.5", help="START:STOP:STEP or a,b,c [m] (default 0.5:5:0.5)")
        b.add_argument("--modes", nargs="+", choices=list(TAC_MODES), default=["tac", "cooperative"])
        b.add_argument("--jobs", type=int, default=1, help="parallel runs (default 1)")
        add_sea_args(b)
        add_json(b)
        add_out(b, "tac_sweep")
    vvmc_help = "vessel-to-vessel motion compensation in the Motion-Lab (CSV, plots, JSON)"
    with command(sims, "vvmc", cmd_sim_vvmc, help=vvmc_help) as b:
        add_hs(b, 2.0)
        add_tp(b, 8.0)
        add_spectrum(b)
        b.add_argument("--heading1", type=_finite_float, default=150.0, help="EM8000 vessel wave heading [deg] (150)")
        b.add_argument("--heading2", type=_finite_float, default=90.0, help="EM1500 vessel wave heading [deg] (90)")
        add_duration(b, 300.0)
        b.add_argument(
            "--dt", type=_positive_float, default=0.005, help="time step [s] (default 0.005: the lab PLC's task)"
        )
        add_wave_seed(b)
        add_vessel(
            b,
            "the platforms' vessel: supply (default: RAOs by boundary elements), supply-closed-form, or an RAO file",
        )
        b.add_argument(
            "--sensors",
            choices=list(_SENSOR_NAMES),
            default="true",
            help="what the controllers see of the platforms: the true states, an MRU H on each, or a laser tracker",
        )
        b.add_argument("--antisway", action="store_true", help="add the load-swing estimator and anti-swing law")
        _add_delay(b, "the controllers see the platforms this late (a 160 s lead-in, not counted)", "the platforms")
        add_out(b, "vvmc_hsHS_seedSEED_SENSORS")
    transfer_help = "the compensated lift: an operator lands a load on a platform or a vessel (CSV, PNG, JSON)"
    with command(sims, "transfer", cmd_sim_transfer, json=False, help=transfer_help) as b:
        b.add_argument(
            "--scene",
            choices=["crane", "lab"],
            default="crane",
            help="crane (default): the offshore crane and Delta head; lab: the Motion-Lab's Comau, winch and EM1500",
        )
        b.add_argument(
            "--hs", type=_positive_float, default=None, help="significant wave height [m] (default 3; lab 2)"
        )
        b.add_argument("--tp", type=_positive_float, default=None, help="peak period [s] (default 9; lab 8)")
        b.add_argument(
            "--heading",
            type=_finite_float,
            default=None,
            help="wave heading to the crane's vessel (lab: EM8000's) [deg] (default 90; lab 150)",
        )
        add_spectrum(b)
        add_wave_seed(b)
        add_vessel(b, "the crane's vessel: supply (default), supply-closed-form, or an RAO file")
        b.add_argument("--target", choices=["platform", "vessel"], default=None, help="crane: default platform")
        b.add_argument(
            "--target-vessel", default=None, metavar="NAME|FILE", help="--target vessel: its RAOs (default: --vessel's)"
        )
        b.add_argument(
            "--target-heading",
            type=_finite_float,
            default=None,
            help="--target vessel (lab: EM1500): wave heading to it [deg] (default 60; lab 90)",
        )
        b.add_argument(
            "--mode", choices=["off", "compensated", "antisway"], default="compensated", help="default compensated"
        )
        b.add_argument(
            "--operator",
            default="scripted",
            metavar="scripted|FILE",
            help="the scripted reference operator, or a stick file to replay (CSV t,x,y,z,w)",
        )
        b.add_argument(
            "--move-accel",
            type=_positive_float,
            default=None,
            metavar="A",
            help="the scripted operator's speed ramps [m/s²] (default 0.25; lab 0.1); 0.079 lasts one period of the "
            "crane's 10 m pendulum, a move that leaves no swing",
        )
        b.add_argument(
            "--no-lead",
            action="store_true",
            help="without the load lead: the tip follows a moving target's spot, not where the load needs it, and "
            "anti-swing does not lead the operator's move (docs/transfer.md)",
        )
        b.add_argument("--landings", type=int, default=None, metavar="N", help="also N seeded landings (statistics)")
        add_json(b)
        add_out(b, "transfer_TARGET_MODE_hsHS_seedSEED")
    predict_help = "the crane tip's motion predicted 1-20 s ahead from the MRU alone (issue 31)"
    with command(sims, "predict", cmd_sim_predict, help=predict_help) as b:
        add_hs(b, 3.0)
        add_tp(b, 9.0)
        b.add_argument("--heading", type=_finite_float, default=90.0, help="wave heading [deg] (default 90: beam)")
        add_spectrum(b)
        add_wave_seed(b)
        b.add_argument(
            "--duration", type=_positive_float, default=1200.0, help="simulated time [s] (1200; scored after 300)"
        )
        add_vessel(b, "the vessel: supply (default), supply-closed-form, or an RAO file")
        b.add_argument(
            "--target",
            choices=["none", "vessel"],
            default="none",
            help="vessel: the tip's motion relative to a second vessel's landing spot (default none: the tip's own)",
        )
        b.add_argument(
            "--target-vessel", default=None, metavar="NAME|FILE", help="--target vessel: its RAOs (default: --vessel's)"
        )
        b.add_argument(
            "--target-heading", type=_finite_float, default=60.0, help="wave heading to the second vessel [deg] (60)"
        )
        b.add_argument(
            "--window-threshold",
            type=_finite_float,
            default=1.0,
            metavar="M",
            help="a lift window: the heave within ±M m of its mean for 10 s (default 1)",
        )
        b.add_argument(
            "--window-probability",
            type=_finite_float,
            default=0.95,
            metavar="P",
            help="a window is announced when the model gives it this probability or more (0.5–1, default 0.95)",
        )
        add_out(b, "predict[_relative]_SPECTRUM_hsHS_seedSEED")
    antisway_help = "load-swing estimator and anti-swing in the Motion-Lab (PNG, JSON)"
    with command(sims, "antisway", cmd_sim_antisway, help=antisway_help) as b:
        add_hs(b, 2.0)
        add_tp(b, 8.0)
        b.add_argument("--duration", type=_positive_float, default=300.0, help="simulated time in waves [s] (300)")
        add_wave_seed(b)
        b.add_argument("--sensors", choices=list(_SENSOR_NAMES), default="true", help="as for sim vvmc")
        add_out(b, "antisway_hsHS_seedSEED")
