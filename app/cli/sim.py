"""``bosun sim tac|tac-sweep|vvmc|antisway``: the papers' simulations."""

from __future__ import annotations

import argparse

from app.cli.common import (
    _atomic_dir,
    _finite_float,
    _make_out,
    _Parser,
    _positive_float,
    _print_json,
    _progress_bar,
    _table,
)
from app.errors import BosunError


def _scenario(args: argparse.Namespace, **over):
    from app.scenarios.tac import ScenarioError, TacScenario

    try:
        return TacScenario(
            hs=over.get("hs", getattr(args, "hs", 3.0)),
            tp=args.tp,
            heading=args.heading,
            spectrum=args.spectrum,
            spreading=args.spreading,
            duration=args.duration,
            dt=args.dt,
            seed=args.seed,
            mode=over.get("mode", getattr(args, "mode", "tac")),
            rao=args.rao,
            roll_damping=args.roll_damping,
            crane_share=args.crane_share,
            crane_kp=args.crane_kp,
            mru_noise=args.mru_noise,
        )
    except ScenarioError as err:
        raise BosunError(str(err)) from None


def cmd_sim_vvmc(args: argparse.Namespace) -> int:
    import time

    from app.analysis.vvmc_report import save_runs
    from app.marine.vessels import vessel_label
    from app.scenarios.vvmc import VvmcError, VvmcScenario, simulate

    try:
        sc = VvmcScenario(
            hs=args.hs,
            tp=args.tp,
            spectrum=args.spectrum,
            heading1=args.heading1,
            heading2=args.heading2,
            duration=args.duration,
            dt=args.dt,
            seed=args.seed,
            rao=args.rao,
            sensors=args.sensors,
            antisway=args.antisway,
        )
    except VvmcError as err:
        raise BosunError(str(err)) from None
    out = _make_out(args, f"vvmc_hs{sc.hs:g}_seed{sc.seed}_{sc.sensors}" + ("_antisway" if sc.antisway else ""))
    n = round(sc.duration / sc.dt)
    bar = _progress_bar("sim vvmc", unit="step")
    t0 = time.perf_counter()
    on = simulate(sc, True, progress=lambda k: bar(k, 2 * n))
    off = simulate(sc, False, progress=lambda k: bar(n + k, 2 * n))
    speed = 2 * sc.duration / (time.perf_counter() - t0)
    with _atomic_dir(out) as tmp:
        doc = save_runs(sc, on, off, tmp, speed)
    if args.json:
        _print_json({**doc, "out": str(out)})
    else:
        c, u = doc["compensated"], doc["uncompensated"]
        print(
            f"VVMC: Hs {sc.hs:g} m, Tp {sc.tp:g} s, EM8000 heading {sc.heading1:g}°, EM1500 {sc.heading2:g}°, "
            f"{sc.duration:g} s, seed {sc.seed} (vessel {vessel_label(sc.rao)}); "
            f"the controllers see the platforms through: {_SENSOR_NAMES[sc.sensors]}"
            + ("; anti-swing on" if sc.antisway else "")
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

    try:
        sc = VvmcScenario(hs=args.hs, tp=args.tp, duration=args.duration, seed=args.seed, sensors=args.sensors)
    except VvmcError as err:
        raise BosunError(str(err)) from None
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
    with _atomic_dir(out) as tmp:
        doc = save_antisway(sc, free, study, tmp, wall)
    if args.json:
        _print_json({**doc, "out": str(out)})
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
    with _atomic_dir(out) as tmp:
        doc = save_run(result, tmp)
    if args.json:
        _print_json({**doc, "out": str(out)})
    else:
        print(
            f"TAC {sc.mode}: Hs {sc.hs:g} m, Tp {sc.tp:g} s, heading {sc.heading:g}°, {sc.duration:g} s "
            f"(vessel {vessel_label(sc.rao)})"
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
    with _atomic_dir(out) as tmp:
        doc = save_sweep(rows, base, tmp)
    if args.json:
        _print_json({**doc, "out": str(out)})
    else:
        table = [
            [f"{r['hs']:g}", r["mode"], f"{r['ratio_rms']:.2%}", f"{r['rms_e_c_m']:.3f}", f"{r['saturated_pct']:.1f}"]
            for r in rows
        ]
        print(_table(["Hs [m]", "mode", "rms e_c/e_s", "rms e_c [m]", "saturated %"], table))
        for m, v in doc["max_hs_ratio_le_5pct"].items():
            print(f"  {m}: ratio ≤ 5 % up to Hs = {'—' if v is None else f'{v:g} m'}")
        print(f"  wrote {out}/sweep.csv, sweep.png, sweep.json")
    return 0


def register(sub) -> None:
    """Add this group's commands to ``bosun``'s subparsers."""
    p = sub.add_parser(
        "sim", help="simulations: sim tac, sim tac-sweep (crane head), sim vvmc, sim antisway (Motion-Lab)"
    )
    sims = p.add_subparsers(dest="sim", metavar="WHAT", parser_class=_Parser, required=True)

    def add_sea_args(p: argparse.ArgumentParser) -> None:
        p.add_argument("--tp", type=_positive_float, default=9.0, help="peak period [s] (default 9)")
        p.add_argument(
            "--heading",
            type=_finite_float,
            default=90.0,
            help="wave heading [deg], 0 following, 90 beam, 180 head (default 90)",
        )
        p.add_argument(
            "--spectrum", choices=["jonswap", "pm", "torsethaugen"], default="jonswap", help="default jonswap"
        )
        p.add_argument(
            "--spreading", type=int, default=None, metavar="S", help="short-crested cos^2s sea (default long-crested)"
        )
        p.add_argument("--duration", type=_positive_float, default=600.0, help="simulated time [s] (default 600)")
        p.add_argument("--dt", type=_positive_float, default=0.01, help="time step [s] (default 0.01)")
        p.add_argument("--seed", type=int, default=1, help="seed of the wave phases (default 1)")
        p.add_argument(
            "--vessel",
            "--rao",
            dest="rao",
            default=None,
            metavar="NAME|FILE",
            help="vessel: supply (default: RAOs by boundary elements), supply-closed-form, or an RAO table "
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
        p.add_argument("--json", action="store_true", help="machine-readable output")

    b = sims.add_parser("tac", help="one run: vessel in waves, crane and Delta head (CSV, Figs. 8–12, JSON)")
    b.add_argument("--hs", type=_positive_float, default=3.0, help="significant wave height [m] (default 3)")
    b.add_argument("--mode", choices=["off", "tac", "cooperative"], default="tac", help="default tac")
    add_sea_args(b)
    b.add_argument("--out", default=None, help="output folder (default out/tac_MODE_hsHS)")
    b.set_defaults(func=cmd_sim_tac)
    b = sims.add_parser("tac-sweep", help="rms(e_c)/rms(e_s) against Hs for each mode (table and plot)")
    b.add_argument("--hs", default="0.5:5:0.5", help="START:STOP:STEP or a,b,c [m] (default 0.5:5:0.5)")
    b.add_argument("--modes", nargs="+", choices=["off", "tac", "cooperative"], default=["tac", "cooperative"])
    b.add_argument("--jobs", type=int, default=1, help="parallel runs (default 1)")
    add_sea_args(b)
    b.add_argument("--out", default=None, help="output folder (default out/tac_sweep)")
    b.set_defaults(func=cmd_sim_sweep)
    b = sims.add_parser("vvmc", help="vessel-to-vessel motion compensation in the Motion-Lab (CSV, plots, JSON)")
    b.add_argument("--hs", type=_positive_float, default=2.0, help="significant wave height [m] (default 2)")
    b.add_argument("--tp", type=_positive_float, default=8.0, help="peak period [s] (default 8)")
    b.add_argument("--spectrum", choices=["jonswap", "pm", "torsethaugen"], default="jonswap", help="default jonswap")
    b.add_argument("--heading1", type=_finite_float, default=150.0, help="EM8000 vessel wave heading [deg] (150)")
    b.add_argument("--heading2", type=_finite_float, default=90.0, help="EM1500 vessel wave heading [deg] (90)")
    b.add_argument("--duration", type=_positive_float, default=300.0, help="simulated time [s] (default 300)")
    b.add_argument(
        "--dt", type=_positive_float, default=0.005, help="time step [s] (default 0.005: the lab PLC's task)"
    )
    b.add_argument("--seed", type=int, default=1, help="seed of the wave phases (default 1)")
    b.add_argument(
        "--vessel", "--rao", dest="rao", default=None, metavar="NAME|FILE",
        help="the platforms' vessel: supply (default: RAOs by boundary elements), supply-closed-form, or an RAO file",
    )  # fmt: skip
    b.add_argument(
        "--sensors",
        choices=["true", "mru", "tracker"],
        default="true",
        help="what the controllers see of the platforms: the true states, an MRU H on each, or a laser tracker",
    )
    b.add_argument("--antisway", action="store_true", help="add the load-swing estimator and anti-swing law")
    b.add_argument("--out", default=None, help="output folder (default out/vvmc_hsHS_seedSEED_SENSORS)")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_sim_vvmc)
    b = sims.add_parser("antisway", help="load-swing estimator and anti-swing in the Motion-Lab (PNG, JSON)")
    b.add_argument("--hs", type=_positive_float, default=2.0, help="significant wave height [m] (default 2)")
    b.add_argument("--tp", type=_positive_float, default=8.0, help="peak period [s] (default 8)")
    b.add_argument("--duration", type=_positive_float, default=300.0, help="simulated time in waves [s] (300)")
    b.add_argument("--seed", type=int, default=1, help="seed of the wave phases (default 1)")
    b.add_argument("--sensors", choices=["true", "mru", "tracker"], default="true", help="as for sim vvmc")
    b.add_argument("--out", default=None, help="output folder (default out/antisway_hsHS_seedSEED)")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_sim_antisway)
