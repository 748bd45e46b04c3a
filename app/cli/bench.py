"""``bosun bench ik|loop|sim|hold|guard|alarms|plc-soak``: benchmarks, not tests."""

from __future__ import annotations

import argparse
import math

from app.cli.args import command, group
from app.cli.common import (
    _kernels_on,
    _machine,
    _positive_float,
    _positive_int,
    _print_json,
    _progress_bar,
    _rt_priority,
    _table,
)
from app.errors import BosunError


def _serial_robots(names: list[str] | None) -> list[str]:
    """The robots given, or by default every serial robot of the library."""
    from app.models.registry import list_robots, load_spec

    return names or [n for n in list_robots() if load_spec(n).type == "serial"]


def _print_bench_json(benchmark: str, fields: dict) -> None:
    _print_json({"benchmark": benchmark, "machine": _machine(), **fields})


def _machine_line() -> str:
    return f"machine: {_machine()}; compiled kernels: {'on' if _kernels_on() else 'off'}"


def cmd_bench(args: argparse.Namespace) -> int:
    from app.analysis.ik_studies import bench_ik
    from app.models.registry import load_robot
    from app.warmup import warm_up

    robots = [load_robot(n) for n in _serial_robots(args.robots)]
    warm_up()  # compiled (or loaded) before the clock runs, never inside a timed solve
    rows = bench_ik(robots, targets=args.targets, seed=args.seed, progress=_progress_bar("bench ik"))
    peers_missing: list[str] = []
    if args.peers:
        from app.analysis.ik_peers import available, bench_peers

        peers_missing = [p for p, ok in available().items() if not ok]
        rows += bench_peers(robots, targets=args.targets, seed=args.seed, progress=_progress_bar("bench ik peers"))
        ref = {(r["robot"], r["start"]): r["median_ms"] for r in rows if r["solver"] == "rtb ik_LM"}
        for r in rows:
            base = ref.get((r["robot"], r["start"]))
            r["ratio_to_rtb_cpp"] = r["median_ms"] / base if base else None
    if args.json:
        _print_bench_json(
            "ik",
            {
                "kernels": _kernels_on(),
                "targets": args.targets,
                "seed": args.seed,
                "peers_missing": peers_missing,
                "results": rows,
            },
        )
        return 0
    print(
        f"bosun bench ik: {args.targets} seeded reachable targets per robot; cold = default start, warm = targets "
        "1 cm apart from the previous solution; success = error < 1 mm inside the limits; budget 100 ms"
    )
    print(_machine_line())
    if peers_missing:
        print(f"peers not installed (pip install -e '.[bench]'): {', '.join(peers_missing)}")
    header = ["robot", "solver", "start", "median [ms]", "p95 [ms]", "p99 [ms]", "success", "own test", "median err"]
    if args.peers:
        header.append("× RTB C++")

    def row(r: dict) -> list[str]:
        cells = [
            r["robot"],
            r["solver"],
            r["start"],
            f"{r['median_ms']:.3f}",
            f"{r['p95_ms']:.2f}",
            f"{r['p99_ms']:.2f}",
            f"{r['success_rate']:.1%}",
            f"{r['own_success_rate']:.1%}" if "own_success_rate" in r else "-",
            f"{r['median_error_m']:.1e}",
        ]
        if args.peers:
            ratio = r.get("ratio_to_rtb_cpp")
            cells.append(f"{ratio:.2f}" if ratio is not None else "-")
        return cells

    rows.sort(key=lambda r: (r["robot"], r["start"]))
    print(_table(header, [row(r) for r in rows]))
    return 0


def cmd_bench_sim(args: argparse.Namespace) -> int:
    from app.bench.sim_speed import engine_speed

    cases = [(k, m, False) for k in args.kinds for m in ((False, True) if k == "lab" else (False,))]
    cases += [("tac", False, True)] if "tac" in args.kinds else []
    rows = [engine_speed(kind, seconds=args.seconds, motion=motion, predict=pr) for kind, motion, pr in cases]
    if args.json:
        _print_bench_json("sim", {"results": rows})
        return 0
    print(f"bosun bench sim: engine plants ticked back to back at their default rate, {args.seconds:g} s simulated")
    print(_machine_line())
    labels = {
        ("lab", False, False): "lab (as it starts)",
        ("lab", True, False): "lab (VVMC in waves)",
        ("tac", False, False): "crane head",
        ("tac", False, True): "crane head, 0.2 s delay predicted",
    }

    def predictor(r: dict) -> str:
        c = r.get("predictor_ms")
        return "-" if c is None else f"{c['p50']:.3f} / {c['p99']:.3f} / {c['max']:.1f}"

    print(
        _table(
            ["engine", "ticks", "wall [s]", "× real time", "predictor per tick p50 / p99 / max [ms]"],
            [
                [
                    labels[(r["kind"], r["motion"], r["predict"])],
                    str(r["ticks"]),
                    f"{r['wall_s']:.2f}",
                    f"{r['speed_x_realtime']:.0f}",
                    predictor(r),
                ]
                for r in rows
            ],
        )
    )
    return 0


def _lab_slow_cell(row: dict) -> str:
    """The lab table's "under 90 %" cell: the count and why (the split of :mod:`app.bench.lab_guard`)."""
    n = row["opening_slow_ticks"]
    ahead, carried = row.get("opening_slow_ahead_ticks", 0), row.get("opening_slow_carried_ticks", 0)
    return (f"{n} ({row.get('opening_slow_closing_ticks', 0)} closing as asked, {ahead} ahead, {carried} carried, "
            f"{n - ahead - carried} unexplained)")  # fmt: skip


def _lab_guard_table(args: argparse.Namespace, row: dict) -> tuple[list[str], list[str], list[str]]:
    """``bosun bench guard --scene lab``'s header, columns and cells (app/bench/lab_guard.py)."""
    head = [
        f"bosun bench guard --scene lab: {args.streams} seeded stick streams, the Comau in REMOTE on its data-sheet "
        "limits, the platforms held at random poses, 5 ms steps",
        "penetration: the deepest overlap of the arm's capsules, the winch's wire or the hanging load with EM8000,",
        "its pedestal or EM1500's deck, at the actual joints; opening: steps whose command opens every clearance in",
        "the zone, and the least drive step kept on them (the acceptance: ≥ 0.9); closing as asked: of those under",
        "90 %, the steps whose drive step with the command as the law gave it would itself close a clearance there;",
        "ahead: those whose drives, following it as asked and then braked, would pass below the stop distance;",
        "carried: of the rest, those the arm's own motion carries into the zone of a hazard the command closes on;",
        "across: the guarded drive steps' tool motion across the direction asked, a share of the travel asked",
    ]
    columns = ["streams", "steps", "max penetration [mm]", "least clearance [mm]", "wire and load: least [mm]",
               "past a limit", "opening steps", "least step kept", "under 90 %", "slowed steps", "across",
               "in the zone: EM8000 deck / pedestal / EM1500 deck", "of them the wire or load",
               "streams stopped: load model lost"]  # fmt: skip
    cells = [str(row["streams"]), str(row["ticks"]), f"{row['max_penetration_m'] * 1e3:.2f}",
             f"{row['least_clearance_m'] * 1e3:.1f}", f"{row.get('load_least_clearance_m', math.inf) * 1e3:.1f}",
             f"{row['max_limit_excess']:.2g}", str(row["opening_ticks"]), f"{row['min_opening_speed']:.3f}",
             _lab_slow_cell(row), str(row["slowed_ticks"]),
             _share(row.get("slowed_across_m", 0.0), row.get("slowed_travel_m", 0.0)),
             " / ".join(str(v) for v in row["nearest_in_zone_ticks"].values()),
             str(row.get("load_nearest_ticks", 0)), str(row.get("streams_load_model_lost", 0))]  # fmt: skip
    return head, columns, cells


def _crane_guard_table(args: argparse.Namespace, row: dict) -> tuple[list[str], list[str], list[str]]:
    """``bosun bench guard --scene crane``'s header, columns and cells (app/bench/crane_guard.py)."""
    head = [
        f"bosun bench guard --scene crane: {args.streams} seeded stick streams through the crane-head engine (50 Hz), "
        "tac and cooperative by turns, Hs 1 m beam",
        "past its range: how far the TCP's target went past its mode's range; opening: ticks whose step has no",
        "outward part on an axis in the outer quarter, and the least share of it kept (the acceptance: ≥ 0.9)",
    ]
    columns = ["streams", "ticks", "past its range [mm]", "opening ticks", "least kept", "under 90 %", "slowed ticks"]
    cells = [str(row["streams"]), str(row["ticks"]), f"{row['max_excess_m'] * 1e3:.2f}", str(row["opening_ticks"]),
             f"{row['min_opening_speed']:.3f}", str(row["opening_slow_ticks"]), str(row["slowed_ticks"])]  # fmt: skip
    return head, columns, cells


def _bench_scene_guard(args: argparse.Namespace) -> int:
    """``bosun bench guard --scene lab|crane``: the scene's own guard under seeded streams, one row."""
    if args.robots is not None:
        raise BosunError(f"--robots is for the teleop scene; --scene {args.scene} drives its own machine")
    if args.scene == "lab":
        from app.bench.lab_guard import bench_lab_guard as run

        table = _lab_guard_table
    else:
        from app.bench.crane_guard import bench_crane_guard as run

        table = _crane_guard_table
    row = run(args.streams, workers=args.workers, progress=_progress_bar("guard", unit="stream"))
    if args.json:
        _print_bench_json("guard", {"scene": args.scene, "results": [row]})
        return 0
    head, columns, cells = table(args, row)
    print("\n".join(head))
    print(_table(columns, [cells]))
    print(_machine_line())
    return 0


def _share(part: float, whole: float) -> str:
    return f"{100.0 * part / whole:.1f} %" if whole > 0.0 else "–"


def cmd_bench_guard(args: argparse.Namespace) -> int:
    from app.bench import guard as bench

    if args.scene != "teleop":
        return _bench_scene_guard(args)
    robots = _serial_robots(args.robots)
    if not 10.0 <= args.rate <= 1000.0:
        raise BosunError(f"--rate must be between 10 and 1000 Hz, got {args.rate:g}")
    bench.SPEED = args.speed
    rows = bench.bench_guard(
        robots, args.streams, rate=args.rate, workers=args.workers, progress=_progress_bar("guard", unit="stream"),
        speed=args.speed,
    )  # fmt: skip
    if args.json:
        _print_bench_json("guard", {"rate": args.rate, "speed": args.speed, "results": rows})
        return 0
    print(
        f"bosun bench guard: {args.streams} seeded random stick streams per robot, velocity mode, jacobian, "
        f"{args.rate:g} Hz, {args.speed:g}× the default stick speed"
    )
    print("penetration: the deepest capsule overlap of the actual joints; opening: ticks whose command's direction")
    print("opens every hazard in its zone, and the least tool speed kept on them (the acceptance: ≥ 0.9; a tick the")
    print("safe-braking rule braked counts 0); closing as asked: of those under 90 %, the ticks whose servo step with")
    print("the command as asked would itself close a clearance in its zone; braked: ticks that rule braked the joints")
    print("(opening ones among them); across: in the slowed ticks, the tool's guarded motion across each step's")
    print("direction, as a share of the travel the steps asked for")
    print(
        _table(
            [
                "robot",
                "streams",
                "max penetration [mm]",
                "least clearance [mm]",
                "past a limit",
                "opening ticks",
                "least speed kept",
                "under 90 %",
                "slowed ticks",
                "across",
                "braked ticks",
            ],
            [
                [
                    r["robot"],
                    str(r["streams"]),
                    f"{r['max_penetration_m'] * 1e3:.2f}",
                    f"{r['least_clearance_m'] * 1e3:.1f}",
                    f"{r['max_limit_excess']:.2g}",
                    str(r["opening_ticks"]),
                    f"{r['min_opening_speed']:.3f}",
                    f"{r['opening_slow_ticks']} ({r['opening_slow_closing_ticks']} closing as asked)",
                    str(r["slowed_ticks"]),
                    _share(r["slowed_across_m"], r["slowed_travel_m"]),
                    f"{r['braked_ticks']} ({r['opening_braked_ticks']} opening)",
                ]
                for r in rows
            ],
        )
    )
    print(_machine_line())
    return 0


def cmd_bench_hold(args: argparse.Namespace) -> int:
    from app.bench.hold import HOLD_TOLERANCE, bench_hold

    robots = _serial_robots(args.robots)
    if not 1.0 <= args.rate <= 1000.0:
        raise BosunError(f"--rate must be between 1 and 1000 Hz, got {args.rate:g}")
    solvers = None
    if args.solvers:
        from app.ik import solver_names

        unknown = [s for s in args.solvers if s not in solver_names()]
        if unknown:
            raise BosunError(f"--solvers: unknown solver {unknown[0]!r} (solvers: {', '.join(solver_names())})")
        solvers = tuple(args.solvers)
    rows = bench_hold(
        robots, tuple(args.modes), args.sequences, seed=args.seed, rate=args.rate, workers=args.workers,
        progress=_progress_bar("hold", unit="sequence"), solvers=solvers,
    )  # fmt: skip
    if not rows:
        raise BosunError("no case to run: none of --solvers applies to the robots chosen")
    if args.json:
        _print_bench_json("hold", {"rate": args.rate, "results": rows})
        return 0
    print(f"bosun bench hold: {args.sequences} seeded stick sequences per case ending still, {args.rate:g} Hz")
    print(f"held: overrun past the braking stop and drift once at rest both < {HOLD_TOLERANCE * 100:g} cm")
    print(
        _table(
            [
                "robot",
                "solver",
                "mode",
                "held",
                "max overrun [mm]",
                "max drift [mm]",
                "slowest settle [s]",
                "never at rest",
            ],
            [
                [
                    r["robot"],
                    r["solver"],
                    r["mode"],
                    f"{r['held']}/{r['sequences']}",
                    f"{r['max_overrun_m'] * 1e3:.3f}",
                    f"{r['max_drift_m'] * 1e3:.3f}",
                    "never" if r["max_settle_s"] is None else f"{r['max_settle_s']:.2f}",
                    str(r["never_settled"]),
                ]
                for r in rows
            ],
        )
    )
    return 0 if all(r["held"] == r["sequences"] for r in rows) else 1


def cmd_bench_alarms(args: argparse.Namespace) -> int:
    from app.bench.alarm_rates import run

    rep = run(args.minutes, progress=_progress_bar("session", unit="s")).report()
    if args.json:
        _print_bench_json("alarms", rep)
        return 0
    print(f"bosun bench alarms: a scripted {args.minutes:g}-minute session, three engines (machine: {_machine()})")
    print(f"  E-STOPs by the operator (counted apart): {rep['operator_estops']}")
    print(f"  alarms not caused by the operator: {rep['alarms_not_by_the_operator']}")
    print(
        f"  steady operation: {rep['steady_alarms']} in {rep['steady_seconds']:.0f} s = "
        f"{rep['steady_per_10_min']:.1f} per 10 min (EEMUA 191: at most 1)"
    )
    print(f"  after each upset (10 min): {rep['after_each_upset_10_min']} (EEMUA 191: at most 10)")
    print(f"  chattering (3 or more in a minute): {', '.join(rep['chattering']) or 'none'}")
    for a in rep["alarms"]:
        who = " (operator)" if a["operator"] else ""
        print(f"    {a['t']:7.1f} s  {a['engine']:6s} {a['severity']:8s} {a['key']}{who}: {a['text']}")
    gaps = ", ".join(f"{k} {v:.2f} s" for k, v in rep["longest_state_gap_s"].items())
    rt = ", ".join(f"{k} {v:.2f}" for k, v in rep["lowest_realtime_factor"].items())
    print(f"  longest state gap: {gaps}; lowest real-time factor: {rt}")
    return 0


def cmd_bench_plc_soak(args: argparse.Namespace) -> int:
    from app.bench.plc_soak import run

    rep = run(args.minutes * 60.0, seed=args.seed, progress=_progress_bar("soak", unit="s"))
    if args.json:
        _print_bench_json("plc-soak", rep.to_dict())
        return 0 if rep.ok else 1
    print(f"bosun bench plc-soak: the lab engine against a misbehaving PLC (pyads' test server), {rep.seconds:g} s")
    print(f"  phases: {rep.phases} (normal, NaN/inf/out of range, wrong sizes + STOP unusable, link gone, slow)")
    print(f"  injections: {', '.join(f'{k} {v}' for k, v in sorted(rep.injections.items()))}")
    print(f"  snapshots: {rep.snapshots}, numbers checked: {rep.fields_checked}, non-finite: {rep.nonfinite_fields}")
    by = ", ".join(f"{k} {v}" for k, v in sorted(rep.refused_by.items()))
    print(f"  operator commands: {rep.commands}, accepted {rep.accepted}, refused {rep.refused} ({by})")
    taken = len(rep.motion_accepted_while_not_ok)
    print(f"  motion commands taken while the link was not ok or STOP unusable: {taken}")
    print(
        f"  PLC connects with STOP unusable: {rep.stop_unusable_connects}; writes that could start motion there: "
        f"{len(rep.motion_writes_while_stop_unusable)}"
    )
    print(
        f"  E-STOPs there: {rep.estops} (resets refused {rep.resets_refused}; STOP written and read back on the "
        f"sound PLC before the reset: {rep.stop_rewritten_after_fix})"
    )
    print(f"  link states [s]: {', '.join(f'{k} {v:g}' for k, v in rep.link_seconds.items())}")
    print(f"  alarms raised: {', '.join(f'{k} {v}' for k, v in rep.alarms_raised.items())}")
    print(f"  longest tick + snapshot: {rep.max_tick_s * 1e3:.1f} ms; result: {'OK' if rep.ok else 'FAILED'}")
    for line in rep.nonfinite_paths + rep.motion_accepted_while_not_ok + rep.motion_writes_while_stop_unusable:
        print(f"    {line}")
    return 0 if rep.ok else 1


def cmd_bench_loop(args: argparse.Namespace) -> int:
    from app.bench.loop import PUBLISH_RATE, bench_loop

    plant = getattr(args, "plant", "teleop")
    rate = args.rate if args.rate is not None else (50.0 if plant == "tac" else 500.0)
    if (plant == "tac") != (rate == 50.0):
        raise BosunError(f"--rate {rate:g}: the crane-head engine (--plant tac) runs at 50 Hz, teleop at 500 or 1000")
    result = bench_loop(
        rate=rate, seconds=args.seconds, robot=args.robot, solver=args.solver, flood=args.flood, burn=args.burn,
        plant=plant, realtime=args.realtime,
    )  # fmt: skip
    result["machine"] = _machine()
    if args.json:
        _print_json(result)
        return 0
    extra = (f", {args.flood} junk messages/s from one client" if args.flood else "") + (
        ", one core kept busy by another process" if args.burn else ""
    )
    if args.realtime:
        granted = result["loop"].get("realtime", 0)
        extra += f", the loop on SCHED_FIFO {args.realtime}" if granted else ", SCHED_FIFO asked for and NOT granted"
    what = (
        "the crane-head engine with a 0.2 s delay predicted and its lift window"
        if plant == "tac"
        else f"{args.robot} / {args.solver}"
    )
    print(
        f"bosun bench loop: {what}, {rate:g} Hz for {args.seconds:g} s, one viewer and "
        f"one input client at 500 Hz over tcp://127.0.0.1{extra}"
    )
    print(f"machine: {result['machine']}")
    lp = result["loop"]
    print(
        f"  tick period  p50 {lp['period_p50_ms']:.3f} ms   p99 {lp['period_p99_ms']:.3f} ms   "
        f"max {lp['period_max_ms']:.3f} ms   jitter p99 {lp['jitter_p99_ms']:.3f} ms"
    )
    print(f"  missed deadlines {lp['missed_deadlines']} of {lp['ticks']} ticks;  work p99 {lp['work_p99_ms']:.3f} ms")
    print(
        f"  input -> joint command latency  p50 {lp['latency_p50_ms']:.3f} ms   p99 {lp['latency_p99_ms']:.3f} ms "
        f"({lp['latency_samples']} samples)"
    )
    print(
        f"  tick rate {lp['tick_rate_hz']:.1f} Hz ({100 * result['tick_rate_fraction']:.1f} % of nominal);  "
        f"viewer received {result['viewer_states']} states ({result['viewer_rate_hz']:.1f} /s, "
        f"{100 * result['viewer_fraction']:.1f} % of the nominal {min(PUBLISH_RATE, rate):g}/s)"
    )
    if args.flood:
        print(f"  flood: {result['flood_sent']} sent; engine dropped {lp['dropped']} unread, rejected {lp['rejected']}")
    print(
        f"  E-STOP: {len(result['estop_ticks'])} of {result['estops_sent']} applied, at most "
        f"{result['estop_ticks_max']} tick(s) after receipt; joint speed after: {result['speed_after_estop']}"
    )
    if "predictor_ms" in lp:
        pm = lp["predictor_ms"]
        print(
            f"  predictors (the delay's and the lift window's) per tick: p50 {pm['p50']:.3f} ms   "
            f"p99 {pm['p99']:.3f} ms   max {pm['max']:.3f} ms ({pm['ticks']} ticks; the max: a refit every 10 s)"
        )
        if "cpu" in pm:
            print(f"    {_cpu_line(pm['cpu'])}")
        for key, name in (("delay", "the delay's"), ("lift_window", "the lift window's")):
            if key in pm:
                q = pm[key]
                print(f"    {name} alone: p50 {q['p50']:.3f} ms   p99 {q['p99']:.3f} ms   max {q['max']:.3f} ms")
    if "guard_ms" in lp:
        gm = lp["guard_ms"]
        print(
            f"  hazard checks (direction-aware scaling and safe braking) per tick: p50 {gm['p50']:.3f} ms   "
            f"p99 {gm['p99']:.3f} ms   max {gm['max']:.3f} ms; a hazard in its zone {100 * gm['in_zone']:.0f} % of "
            "the ticks"
        )
        if "cpu" in gm:
            print(f"    {_cpu_line(gm['cpu'])}")
    if "machine_ms" in lp:
        mt = lp["machine_ms"]
        b, r = mt["back_to_back"], mt["in_rhythm"]
        print(
            f"  the machine itself: arithmetic alone of that length (p50 {b['p50']:.3f} ms, p99 {b['p99']:.3f} ms back "
            f"to back) in the loop's rhythm, after it: p50 {r['p50']:.3f} ms   p99 {r['p99']:.3f} ms (CPU time)"
        )
    return 0


def _cpu_line(c: dict) -> str:
    """The CPU-time line under a cost timed by the clock (app/bench/loop.py's ``cpu``)."""
    return (
        f"the loop thread's CPU time in them: p50 {c['p50']:.3f} ms   p99 {c['p99']:.3f} ms   max {c['max']:.3f} ms "
        "(without the time the machine gave to other work)"
    )


def register(sub) -> None:
    """Add this group's commands to ``bosun``'s subparsers."""
    bench = group(sub, "bench", "benchmarks (not tests): bench ik, loop, sim, hold, guard, alarms, plc-soak", "bench")
    with command(bench, "ik", cmd_bench, help="median/p95 solve time and success per robot and solver") as b:
        b.add_argument("--targets", type=int, default=500, help="seeded reachable targets per robot (default 500)")
        b.add_argument("--seed", type=int, default=7, help="seed of targets and solvers (default 7)")
        b.add_argument("--robots", nargs="+", default=None, help="robots to bench (default: every serial robot)")
        b.add_argument(
            "--peers",
            action="store_true",
            help="also robotics-toolbox-python (ik_LM, ikine_LM) and ikpy on the same targets (extra 'bench')",
        )
    loop_help = "engine tick period, jitter, missed deadlines and input latency"
    with command(bench, "loop", cmd_bench_loop, help=loop_help) as b:
        b.add_argument(
            "--rate", type=float, choices=[50.0, 500.0, 1000.0], default=None,
            help="loop rate [Hz]: 500 or 1000 for teleop (default 500), 50 for tac",
        )  # fmt: skip
        b.add_argument(
            "--plant", choices=["teleop", "tac"], default="teleop",
            help="teleop (a library robot's engine) or tac (the crane-head engine with its predictors, issue 31)",
        )  # fmt: skip
        b.add_argument("--seconds", type=_positive_float, default=30.0, help="duration [s] (default 30)")
        b.add_argument("--robot", default="comau_smart5_3dof", help="robot (default comau_smart5_3dof)")
        b.add_argument("--solver", default="jacobian", help="solver (default jacobian)")
        b.add_argument(
            "--flood", type=int, default=0, metavar="N", help="one more client sending N junk messages a second"
        )
        b.add_argument("--burn", action="store_true", help="another process keeps one core busy")
        b.add_argument(
            "--realtime", type=_rt_priority, nargs="?", const=50, default=0, metavar="PRIORITY",
            help="the engine's loop on SCHED_FIFO at PRIORITY (default 50), as bosun server --realtime",
        )  # fmt: skip
    with command(bench, "sim", cmd_bench_sim, help="how fast the lab and crane-head engines run unthrottled") as b:
        b.add_argument(
            "--kinds", nargs="+", choices=["lab", "tac"], default=["lab", "tac"], help="engines (default both)"
        )
        b.add_argument("--seconds", type=_positive_float, default=20.0, help="simulated time [s] (default 20)")
    hold_help = "hold means hold: seeded stick sequences ending still, tool drift after braking (issue 26)"
    with command(bench, "hold", cmd_bench_hold, help=hold_help) as b:
        b.add_argument("--sequences", type=_positive_int, default=1000, help="sequences per robot × solver × mode")
        b.add_argument("--robots", nargs="+", default=None, help="robots (default: every serial robot)")
        b.add_argument("--solvers", nargs="+", default=None, help="solvers (default: every one that applies)")
        b.add_argument("--modes", nargs="+", choices=["velocity", "position"], default=["velocity", "position"])
        b.add_argument("--rate", type=float, default=1000.0, help="engine rate [Hz] (default 1000, as the engine runs)")
        b.add_argument("--seed", type=int, default=0, help="seed of the stick sequences (default 0)")
        b.add_argument("--workers", type=_positive_int, default=1, help="processes (default 1)")
    guard_help = "direction-aware scaling: random stick streams into the arms' hazards (issue 32, item 5)"
    with command(bench, "guard", cmd_bench_guard, help=guard_help) as b:
        b.add_argument("--streams", type=_positive_int, default=1000, help="streams per robot (default 1000)")
        b.add_argument(
            "--scene", choices=["teleop", "lab", "crane"], default="teleop",
            help="teleop: the library arms (default); lab: the Motion-Lab's Comau against the platforms; crane: the "
            "crane head's TCP target against its range",
        )  # fmt: skip
        b.add_argument("--robots", nargs="+", default=None, help="robots (default: every serial robot)")
        b.add_argument("--rate", type=float, default=250.0, help="engine rate [Hz] (default 250)")
        b.add_argument("--speed", type=_positive_float, default=1.0, help="stick speed × the default k_v (default 1)")
        b.add_argument("--workers", type=_positive_int, default=1, help="processes (default 1)")
    alarms_help = "alarm rates of a scripted session (three engines, a study, VVMC, two STOPs) vs EEMUA 191"
    with command(bench, "alarms", cmd_bench_alarms, help=alarms_help) as b:
        b.add_argument("--minutes", type=_positive_float, default=10.0, help="session length (default 10)")
    soak_help = "the lab engine against a PLC test server injecting NaN, wrong sizes, link loss, slowness"
    with command(bench, "plc-soak", cmd_bench_plc_soak, help=soak_help) as b:
        b.add_argument("--minutes", type=_positive_float, default=10.0, help="soak length (default 10)")
        b.add_argument("--seed", type=int, default=27, help="seed of the injections and commands (default 27)")
