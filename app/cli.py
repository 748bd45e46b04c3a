"""The ``bosun`` command line.

Every user mistake (bad robot file, unknown name, wrong number of joint values, a
value that is not a number) ends in one line on stderr and exit status 2, never a
traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import shutil
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from app import __version__
from app.errors import BosunError, interrupted, require
from app.geometry import matrix_to_euler_zyx

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage error in one line (no usage dump) with exit 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def _finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"'{text}' is not a finite number")
    return value


def _positive_float(text: str) -> float:
    value = _finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be positive")
    return value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be positive")
    return value


# ---------------------------------------------------------------------------- output
def _print_json(obj: Any) -> None:
    print(json.dumps(obj, indent=2, allow_nan=False))


def _fmt_row(cells: Sequence[str], widths: Sequence[int]) -> str:
    return "  ".join(c.ljust(w) for c, w in zip(cells, widths, strict=True)).rstrip()


def _table(header: Sequence[str], rows: Sequence[Sequence[str]], last_col_max: int | None = None) -> str:
    rows = [list(r) for r in rows]
    if last_col_max is not None:
        for r in rows:
            if len(r[-1]) > last_col_max:
                r[-1] = r[-1][: last_col_max - 1] + "…"
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    lines = [_fmt_row(header, widths), _fmt_row(["-" * w for w in widths], widths)]
    lines += [_fmt_row(r, widths) for r in rows]
    return "\n".join(lines)


# ---------------------------------------------------------------------------- commands
def cmd_robots(args: argparse.Namespace) -> int:
    from app.models.registry import list_robots, load_spec, robots_dir

    if args.schema_markdown:
        from app.models.schema_doc import schema_markdown

        sys.stdout.write(schema_markdown())
        return 0
    rows, records, problems = [], [], []
    for name in list_robots():
        try:
            spec = load_spec(name)
        except BosunError as err:
            problems.append(str(err))
            continue
        rows.append([spec.name, spec.type, str(spec.dof), spec.source])
        records.append(
            {"name": spec.name, "type": spec.type, "dof": spec.dof, "source": spec.source, "path": spec.path}
        )
    if args.json:
        _print_json({"robots_dir": str(robots_dir()), "robots": records, "invalid": problems})
    else:
        width = shutil.get_terminal_size((120, 20)).columns
        fixed = (
            sum(max(len(h), *(len(r[i]) for r in rows)) + 2 for i, h in enumerate(["name", "type", "DOF"]))
            if rows
            else 0
        )
        print(_table(["name", "type", "DOF", "source"], rows, last_col_max=max(30, width - fixed)))
        print(f"\n{len(rows)} robot(s) in {robots_dir()}")
    for p in problems:
        print(f"bosun: invalid robot file: {p}", file=sys.stderr)
    return EXIT_USAGE if problems else 0


def _serial_robot_and_q(args: argparse.Namespace):
    from app.models.registry import load_robot

    robot = load_robot(args.robot)
    if getattr(robot, "kind", "serial") != "serial":
        raise BosunError(f"{robot.name} is a {robot.kind} mechanism; this command takes a serial arm")
    q = robot.check_q(args.q)
    if args.deg:
        q = np.where(np.array(robot.joint_kinds) == "revolute", np.deg2rad(q), q)
    return robot, q


def _joint_report(robot, q: np.ndarray) -> list[dict[str, Any]]:
    ok = robot.within_limits(q)
    report = []
    for i, name in enumerate(robot.joint_names):
        revolute = robot.joint_kinds[i] == "revolute"
        report.append(
            {
                "name": name,
                "value": float(q[i]),
                "unit": "rad" if revolute else "m",
                "min": float(robot.lower[i]),
                "max": float(robot.upper[i]),
                "within_limits": bool(ok[i]),
            }
        )
    return report


def _num(v: float, digits: int) -> str:
    """Fixed-point text without a negative zero."""
    return f"{round(float(v), digits) + 0.0: .{digits}f}"


def _show_value(v: float, unit: str) -> str:
    return f"{math.degrees(v):9.3f}°" if unit == "rad" else f"{v:9.4f} m"


def _delta_fk(args: argparse.Namespace, head) -> int:
    q = head.check_q(args.q)
    if args.deg:
        q = np.deg2rad(q)
    try:
        p = head.fk(q)
    except ValueError as err:
        raise BosunError(f"{head.name}: {err}") from None
    ok = head.within_limits(q)
    if args.json:
        _print_json(
            {
                "robot": head.name,
                "q": [float(v) for v in q],
                "position": [float(v) for v in p],
                "rotation": np.eye(3).tolist(),
                "within_limits": bool(ok.all()),
            }
        )
    else:
        x, y, z = (_num(v, 4) for v in p)
        print(f"{head.name}: tool centre point in {{t}} (plates stay parallel)")
        print(f"  position [m]    x = {x}   y = {y}   z = {z}")
    if not ok.all():
        print("bosun: warning: arm angles outside the limits", file=sys.stderr)
    return 0


def cmd_check(args: argparse.Namespace) -> int:
    """Validate robot files as the engine will: one line per file, exit 2 when any is refused."""
    from app.models.registry import MODEL_FACTORIES, load_spec

    failed = 0
    for ref in args.robots:
        try:
            spec = load_spec(ref)
            MODEL_FACTORIES[spec.type](spec)
        except BosunError as err:
            failed += 1
            print(f"refused  {err}")
            continue
        print(f"ok       {spec.path}: {spec.name}, {spec.type}, {spec.dof} DOF")
    if len(args.robots) > 1:
        print(f"{len(args.robots) - failed} ok, {failed} refused", file=sys.stderr)
    return EXIT_USAGE if failed else 0


def cmd_fk(args: argparse.Namespace) -> int:
    from app.models.delta import DeltaHead
    from app.models.registry import load_robot

    model = load_robot(args.robot)
    if isinstance(model, DeltaHead):
        return _delta_fk(args, model)
    robot, q = _serial_robot_and_q(args)
    frames = robot.frames(q)
    T = frames[-1]
    rpy = matrix_to_euler_zyx(T[:3, :3])
    joints = _joint_report(robot, q)
    violations = [j["name"] for j in joints if not j["within_limits"]]
    if args.json:
        _print_json(
            {
                "robot": robot.name,
                "q": [float(v) for v in q],
                "q_units": [j["unit"] for j in joints],
                "joints": joints,
                "within_limits": not violations,
                "position": [float(v) for v in T[:3, 3]],
                "rotation": T[:3, :3].tolist(),
                "rpy_deg": [math.degrees(v) for v in rpy],
                "frame_origins": frames[:, :3, 3].tolist(),
            }
        )
    else:
        print(f"{robot.name}: tool point")
        x, y, z = (_num(v, 4) for v in T[:3, 3])
        print(f"  position [m]    x = {x}   y = {y}   z = {z}")
        roll, pitch, yaw = (_num(v, 3) for v in np.degrees(rpy))
        print(f"  rpy (zyx) [deg] roll = {roll}   pitch = {pitch}   yaw = {yaw}")
        print("  rotation")
        for row in T[:3, :3]:
            print("    " + "  ".join(_num(v, 5) for v in row))
        rows = [
            [
                j["name"],
                _show_value(j["value"], j["unit"]),
                f"[{_show_value(j['min'], j['unit']).strip()}, {_show_value(j['max'], j['unit']).strip()}]",
                "yes" if j["within_limits"] else "NO",
            ]
            for j in joints
        ]
        print(_table(["joint", "value", "limits", "in limits"], rows))
    if violations:
        print(f"bosun: warning: {', '.join(violations)} outside the joint limits", file=sys.stderr)
    return 0


def cmd_jacobian(args: argparse.Namespace) -> int:
    robot, q = _serial_robot_and_q(args)
    J = robot.jacobian(q)
    sv = np.linalg.svd(J[:3], compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 1e-12 * max(sv[0], 1e-300) else None
    if args.json:
        _print_json(
            {
                "robot": robot.name,
                "q": [float(v) for v in q],
                "rows": ["vx", "vy", "vz", "wx", "wy", "wz"],
                "columns": robot.joint_names,
                "matrix": J.tolist(),
                "position_singular_values": sv.tolist(),
                "position_condition": cond,
            }
        )
        return 0
    print(f"{robot.name}: geometric Jacobian of the tool point (world frame; v [m/s], ω [rad/s] per unit q̇)")
    rows = [[label] + [_num(v, 5) for v in J[i]] for i, label in enumerate(["vx", "vy", "vz", "ωx", "ωy", "ωz"])]
    print(_table([""] + robot.joint_names, rows))
    print(
        f"  position singular values: {', '.join(f'{v:.4g}' for v in sv)}"
        f"   condition: {'singular' if cond is None else f'{cond:.4g}'}"
    )
    return 0


def _progress_bar(desc: str, unit: str = "target"):
    """A tqdm bar on stderr (hidden when stderr is not a terminal) as a progress(done, total) callback."""
    from tqdm import tqdm

    bar = None

    def update(done: int, total: int) -> None:
        nonlocal bar
        if bar is None:
            bar = tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, disable=None, leave=False)
        bar.n = done
        bar.refresh()
        if done >= total:
            bar.close()

    return update


def _solver_options(args: argparse.Namespace) -> dict[str, Any]:
    opts: dict[str, Any] = {}
    if getattr(args, "time_budget", None) is not None:
        opts["time_budget"] = args.time_budget
    if getattr(args, "elbow", None) is not None:
        if args.solver != "analytic":
            raise BosunError("--elbow applies to --solver analytic only")
        opts["elbow"] = args.elbow
    return opts


def _out_dir(args: argparse.Namespace, kind: str) -> Path:
    return _make_out(args, f"{kind}_{args.robot_name}_{args.solver}")


def _make_out(args: argparse.Namespace, default: str) -> Path:
    """``--out`` (or out/DEFAULT): its parent created now, the folder itself only by :func:`_atomic_dir`
    when the study is complete; a folder that cannot be made is a one-line error."""
    out = Path(args.out) if args.out else Path("out") / default
    if out.exists() and not out.is_dir():
        raise BosunError(f"output folder {out} is a file")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise BosunError(f"cannot create output folder {out}: {err.strerror or err}") from None
    return out


@contextlib.contextmanager
def _atomic_dir(out: Path):
    """Write a study's files into a hidden ``.NAME.partial-XXXX`` folder beside ``out``; rename it to
    ``out`` only when every file is written.  An interrupted or failed run leaves ``out`` as it was
    (the previous complete run, or nothing) and removes its partial folder; only a SIGKILL can leave
    one, and its name says it is partial."""
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    except OSError as err:
        raise BosunError(f"cannot create output folder {out}: {err.strerror or err}") from None
    try:
        yield tmp
        old = None
        if out.exists():
            old = out.with_name(f".{out.name}.old-{os.getpid()}")
            out.rename(old)
        tmp.rename(out)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def cmd_ik(args: argparse.Namespace) -> int:
    from app.ik import make_solver
    from app.models.registry import load_robot

    robot = load_robot(args.robot)
    solver = make_solver(args.solver, robot, seed=args.seed, **_solver_options(args))
    q0 = None
    if args.q0 is not None:
        q0 = robot.check_q(args.q0)
        if args.deg:
            q0 = np.where(np.array(robot.joint_kinds) == "revolute", np.deg2rad(q0), q0)
    res = solver.solve_position(args.target, q0)
    joints = _joint_report(robot, res.q)
    if args.json:
        _print_json(
            {
                "robot": robot.name,
                "solver": args.solver,
                "target": list(map(float, args.target)),
                "joints": joints,
                **res.to_dict(),
            }
        )
    else:
        status = "solved" if res.success else "NOT solved"
        print(f"{robot.name} / {args.solver}: {status} ({res.reason})")
        x, y, z = (_num(v, 4) for v in res.position)
        print(f"  reached [m]  x = {x}   y = {y}   z = {z}   error = {res.error:.3g} m")
        print(f"  {res.iterations} iteration(s) in {res.time_s * 1e3:.1f} ms")
        print(_table(["joint", "value"], [[j["name"], _show_value(j["value"], j["unit"])] for j in joints]))
    return 0 if res.success else 1


def _study_setup(args: argparse.Namespace, kind: str):
    """Robot, solver options (checked against the robot before any work) and output folder of a study."""
    from app.ik import make_solver
    from app.models.registry import load_robot

    robot = load_robot(args.robot)
    args.robot_name = robot.name
    opts = _solver_options(args)
    make_solver(args.solver, robot, **opts)  # fail fast on a solver that does not apply
    return robot, opts, _out_dir(args, kind)


def _save_study(result, out: Path, stem: str, plot) -> dict[str, Any]:
    """Write a study's STEM.csv, STEM.png and summary.json into ``out``; returns the summary."""
    from app.analysis.ik_studies import write_json

    result.write_csv(out / f"{stem}.csv")
    plot(result, out / f"{stem}.png")
    summary = result.summary()
    write_json(summary, out / "summary.json")
    return summary


def cmd_analyze(args: argparse.Namespace) -> int:
    from app.analysis.ik_studies import error_distribution, plot_error_distribution

    robot, opts, out = _study_setup(args, "analyze")
    result = error_distribution(
        robot,
        args.solver,
        args.grid,
        seed=args.seed,
        solver_options=opts,
        progress=_progress_bar(f"{robot.name}/{args.solver}"),
    )
    with _atomic_dir(out) as tmp:
        summary = _save_study(result, tmp, "error_distribution", plot_error_distribution)
    if args.json:
        _print_json({**summary, "out": str(out)})
    else:
        e = summary["error_m"]
        print(
            f"{robot.name} / {args.solver}: {summary['targets']} targets ({args.grid}³), "
            f"{summary['reachable']} reachable, {summary['success']} solved "
            f"({summary['success_rate']:.0%}; {summary['success_rate_reachable'] or 0:.0%} of reachable)"
        )
        print(f"  error [m]  median {e['median']:.3g}   p95 {e['p95']:.3g}   max {e['max']:.3g}")
        tm = summary["time_s"]
        print(f"  time [ms]  median {tm['median'] * 1e3:.3g}   p95 {tm['p95'] * 1e3:.3g}")
        print(f"  wrote {out}/error_distribution.csv, error_distribution.png, summary.json")
    return 0


def cmd_track(args: argparse.Namespace) -> int:
    from app.analysis.ik_studies import plot_tracking, track

    robot, opts, out = _study_setup(args, "track")
    result = track(
        robot,
        args.solver,
        duration=args.duration,
        dt=args.dt,
        seed=args.seed,
        solver_options=opts,
        progress=_progress_bar(f"{robot.name}/{args.solver}"),
    )
    with _atomic_dir(out) as tmp:
        summary = _save_study(result, tmp, "tracking", plot_tracking)
    if args.json:
        _print_json({**summary, "out": str(out)})
    else:
        print(
            f"{robot.name} / {args.solver}: {summary['samples']} targets over {summary['duration_s']:.1f} s, "
            f"rms error {summary['rms_error_m']:.3g} m, max {summary['max_error_m']:.3g} m, "
            f"solved {summary['success_rate']:.0%}"
        )
        print(f"  wrote {out}/tracking.csv, tracking.png, summary.json")
    return 0


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

    try:
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
    except OperabilityError as err:
        raise BosunError(str(err)) from None
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


# ----------------------------------------------------------------------------- vessels (issue 17)
def cmd_vessel_list(args: argparse.Namespace) -> int:
    from app.marine.vessels import DEFAULT_VESSEL, VESSELS

    if args.json:
        _print_json({"default": DEFAULT_VESSEL, "vessels": VESSELS})
        return 0
    for name, text in VESSELS.items():
        print(f"{name:20s} {text}{'  (default)' if name == DEFAULT_VESSEL else ''}")
    print("or any RAO file: --vessel FILE.mat|FILE.csv")
    return 0


def cmd_vessel_rao(args: argparse.Namespace) -> int:
    """6-DOF motion RAOs of a monohull from its main particulars (Capytaine BEM + viscous roll damping)."""
    import dataclasses
    import shlex

    from app.marine.bem import BemError, BemInputs, compute_raos
    from app.marine.hull import HullError
    from app.marine.vessel import VesselError, VesselParticulars, rao_to_csv

    names = ("lpp", "beam", "draft", "cb", "gm_t", "gm_l", "r44", "r55", "r66", "mass")
    given = {n: getattr(args, n) for n in names if getattr(args, n) is not None}
    try:
        name = args.name or ("MSS supply vessel" if not given else "monohull")
        vessel = VesselParticulars(**given, name=name)
        inputs = BemInputs(
            vessel=vessel, cwp=args.cwp, roll_damping=args.roll_damping, nx=args.nx, nz=args.nz,
            w_min=args.w_min, w_max=args.w_max, n_w=args.n_w, heading_step=args.heading_step,
        )  # fmt: skip
        out = Path(args.out)
        if out.is_dir():
            raise BosunError(f"--out {out} is a folder; give a .csv file")
        result = compute_raos(inputs, progress=_progress_bar("vessel rao", unit="frequency"))
    except (BemError, HullError, VesselError) as err:
        raise BosunError(str(err)) from None
    argv = getattr(args, "argv", None) or []
    command = "bosun " + " ".join(shlex.quote(a) for a in argv) if argv else "bosun vessel rao"
    header = {
        "command": command,
        "inputs": inputs.to_dict(),
        "vessel": dataclasses.asdict(vessel),
        "info": result.info,
    }
    text = rao_to_csv(result.table)
    lines = text.splitlines(keepends=True)
    meta = "".join(f"# {line}\n" for line in json.dumps(header, indent=1, sort_keys=True).splitlines())
    body = lines[0] + "# made by: " + command + "\n" + meta + "".join(lines[1:])
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_name(f".{out.name}.partial")
        tmp.write_text(body, encoding="utf-8")
        tmp.replace(out)
    except OSError as err:
        raise BosunError(f"cannot write {out}: {err.strerror or err}") from None
    info = result.info
    if args.json:
        _print_json({"out": str(out), **header})
        return 0
    t = result.table
    print(f"{vessel.name}: {t.w.size} frequencies × {t.headings.size} headings, {info['panels']} panels", end="")
    print(f" (+{info['lid_panels']} lid), {info['wall_s']:.0f} s")
    cwp, cm = info["waterplane_coefficient"], info["midship_section_coefficient"]
    origin = "given" if inputs.cwp is not None else "from GM_L − GM_T"
    print(f"  hull: C_WP {cwp:.3f} ({origin}), C_M {cm:.3f}, z_G {info['z_g_m']:+.2f} m above the waterline")
    ratio = 100 * info["roll_radiation_damping_ratio"]
    print(
        f"  roll: ω4 {info['roll_natural_frequency_rad_s']:.3f} rad/s, radiation damping {ratio:.2f} % of critical,",
        end="",
    )
    print(f" viscous added to {100 * inputs.roll_damping:g} %")
    print(f"wrote {out}")
    return 0


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


def _machine() -> str:
    import os
    import platform

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), cpu)
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}"


def cmd_bench(args: argparse.Namespace) -> int:
    from app.analysis.ik_studies import bench_ik
    from app.models.registry import list_robots, load_robot, load_spec
    from app.warmup import warm_up

    names = args.robots or [n for n in list_robots() if load_spec(n).type == "serial"]
    robots = [load_robot(n) for n in names]
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
        _print_json(
            {
                "benchmark": "ik",
                "machine": _machine(),
                "kernels": _kernels_on(),
                "targets": args.targets,
                "seed": args.seed,
                "peers_missing": peers_missing,
                "results": rows,
            }
        )
        return 0
    print(
        f"bosun bench ik: {args.targets} seeded reachable targets per robot; cold = default start, warm = targets "
        "1 cm apart from the previous solution; success = error < 1 mm inside the limits; budget 100 ms"
    )
    print(f"machine: {_machine()}; compiled kernels: {'on' if _kernels_on() else 'off'}")
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


def _kernels_on() -> bool:
    from app.models import kernels

    return kernels.ENABLED


def _make_session(args: argparse.Namespace):
    if getattr(args, "plant", "teleop") == "tac":
        from app.engine.tac_session import TacSession

        return TacSession()
    if getattr(args, "plant", "teleop") == "lab":
        from app.engine.lab_session import LabSession

        return LabSession(plc=_plc_target(args))
    from app.engine.session import Session

    folders = list(getattr(args, "robots_dir", None) or [])
    if args.robot.endswith(".xml") or "/" in args.robot:  # the start-up robot's folder is allowed too
        folders.append(str(Path(args.robot).expanduser().resolve().parent))
    for folder in folders:
        if not Path(folder).is_dir():
            raise BosunError(f"--robots-dir {folder}: not a folder")
    return Session(robot_name=args.robot, solver_name=args.solver, mode=args.mode, seed=0, robots_dirs=tuple(folders))


def _plc_target(args: argparse.Namespace):
    """The PLC of ``--plc`` (None without it); pyads must be there (the extra ``plc``)."""
    if getattr(args, "plc", None) is None:
        if getattr(args, "plc_host", None) or getattr(args, "plc_local_id", None):
            raise BosunError("--plc-host and --plc-local-id go with --plc AMS_NET_ID[:PORT]")
        return None
    if getattr(args, "plant", "teleop") != "lab":
        raise BosunError("--plc drives the Motion-Lab's PLC: use it with --plant lab")
    require("pyads", "plc", "bosun server --plc")
    from app.plc.bridge import PlcTarget

    return PlcTarget.parse(args.plc, args.plc_host, args.plc_local_id)


def cmd_server(args: argparse.Namespace) -> int:
    import signal

    from app.engine.server import DEFAULT_RATE, EngineServer
    from app.net.security import ENV_OPERATOR_SECRET, ServerCurve
    from app.net.transport import check_url, is_local

    running: list = []  # the server, once it exists
    if getattr(args, "exit_with_parent", False):
        # watched from the first moment, not after the kernels load: an engine whose GUI went while it was
        # still starting ran on for seconds on a busy machine (the GUI's SIGTERM test, 2026-11-28)
        parent = os.getppid()

        def watch_parent() -> None:
            while os.getppid() == parent:  # re-parented: the GUI is gone (killed, crashed)
                time.sleep(0.5)
            if running:
                running[0].stop()
            else:  # still starting: ended as SIGTERM ends it (one line, status 130)
                os.kill(os.getpid(), signal.SIGTERM)

        threading.Thread(target=watch_parent, daemon=True).start()
    check_url(args.bind)
    if (args.curve_secret is None) != (args.curve_clients is None):
        raise BosunError("--curve-secret and --curve-clients go together")
    curve = ServerCurve.from_files(args.curve_secret, args.curve_clients) if args.curve_secret else None
    if not is_local(args.bind) and curve is None:
        raise BosunError(
            f"binding to the non-local address {args.bind} needs CURVE keys (--curve-secret, --curve-clients); "
            "make them with 'bosun keys' (README: remote operation)"
        )
    plc = _plc_target(args)  # before the kernels compile: a missing extra or a bad address says so at once
    # the launch secret of a GUI's own engine comes in the environment, never on the command line
    operator_secret = os.environ.pop(ENV_OPERATOR_SECRET, None) or None
    from app.warmup import warm_up

    # compile (or load from the on-disk cache) before the first tick: never in the control loop
    compile_s = warm_up(
        progress=lambda k, n: print(f"bosun server: compiled kernels {k}/{n}", flush=True) if k == n else None
    )
    if compile_s > 1.0:
        print(f"bosun server: kernels compiled in {compile_s:.1f} s (cached for the next start)", flush=True)
    session = _make_session(args)
    rate = args.rate if args.rate is not None else (50.0 if args.plant in ("tac", "lab") else DEFAULT_RATE)
    pub = (
        min(args.publish_rate, rate)
        if args.publish_rate is not None
        else (25.0 if args.plant in ("tac", "lab") else 50.0)
    )
    server = EngineServer(
        session,
        bind=args.bind,
        rate=rate,
        publish_rate=pub,
        token=args.token,
        curve=curve,
        operator_secret=operator_secret,
        operator_timeout=args.operator_timeout,
    )
    signal.signal(signal.SIGTERM, lambda *_: server.stop())
    running.append(server)  # from now on the parent watcher stops the loop
    print(f"bosun server: {session.robot_name} / {session.solver_name} / {session.mode} at {rate:g} Hz", flush=True)
    print(f"  requests on {server.url}, state on {server.state_url}", flush=True)
    if curve is not None:
        n_keys = len(list(curve.clients_dir.glob("*.key")))
        print(f"  CURVE: encrypted; {n_keys} allowed client key(s) in {curve.clients_dir}", flush=True)
    if operator_secret:
        print("  the operator role needs this engine's launch secret", flush=True)
    if plc is not None:
        print(f"  plant: the Motion-Lab's PLC at {plc} over ADS (pyads); STOP writes MAIN.bStop", flush=True)
    try:
        server.run(duration=args.duration)
    except KeyboardInterrupt:
        pass
    finally:
        server.close()
    st = server.stats.summary()
    print(f"bosun server: stopped after {st['ticks']} ticks, {st['missed_deadlines']} missed deadlines", flush=True)
    return 0


def cmd_keys(args: argparse.Namespace) -> int:
    from app.net.security import create_keys, load_public

    public, secret = create_keys(args.dir, args.name)
    print(f"public key  {public}  ({load_public(public).decode()}): give it to the other side")
    print(f"secret key  {secret}  (mode 0600): keep it on this machine")
    print("an engine uses its secret key and a folder of allowed client public keys:")
    print("  bosun server --bind tcp://0.0.0.0:5555 --curve-secret ENGINE.key_secret --curve-clients ALLOWED_DIR")
    print("a client uses its secret key and the engine's public key:")
    print("  bosun joystick --connect tcp://HOST:5555 --curve-secret CLIENT.key_secret --server-key ENGINE.key")
    return 0


def cmd_joystick(args: argparse.Namespace) -> int:
    from app.net.transport import TransportError, check_url
    from app.teleop.client import run_joystick_client

    check_url(args.connect)
    virtual = None
    if args.virtual:
        from app.teleop.devices import PygameJoysticks
        from app.teleop.virtual import VirtualJoystick

        PygameJoysticks()  # initialise SDL's joystick subsystem before attaching
        virtual = VirtualJoystick(n_axes=4, n_buttons=8)

        def operator(vj=virtual) -> None:
            """The arming gesture an operator makes: stick centred, press the deadman, then deflect."""
            time.sleep(0.5)
            vj.set_button(0, True)
            time.sleep(0.3)
            vj.set_axis(0, 0.5)

        threading.Thread(target=operator, daemon=True).start()
        print(
            "bosun joystick: a virtual joystick stands in for hardware (centred, deadman pressed at 0.5 s, "
            "x = 0.5 from 0.8 s)",
            flush=True,
        )
    import signal

    from app.net.security import ClientCurve

    if (args.curve_secret is None) != (args.server_key is None):
        raise BosunError("--curve-secret and --server-key go together")
    curve = ClientCurve.from_files(args.curve_secret, args.server_key) if args.curve_secret else None
    stop = threading.Event()  # SIGTERM and Ctrl-C stop streaming cleanly: the client says bye, the engine holds
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    try:
        sent = run_joystick_client(
            args.connect,
            token=args.token,
            curve=curve,
            device=args.device,
            rate=args.rate,
            duration=args.duration,
            stop=stop,
            on_event=lambda t: print(f"bosun joystick: {t}", flush=True),
        )
    except TransportError as err:
        raise BosunError(str(err)) from None
    except RuntimeError as err:
        raise BosunError(str(err)) from None
    except KeyboardInterrupt:
        sent = 0
    finally:
        if virtual is not None:
            virtual.detach()
    print(f"bosun joystick: sent {sent} input messages", flush=True)
    return 0


def cmd_bench_sim(args: argparse.Namespace) -> int:
    from app.bench.sim_speed import engine_speed

    cases = [(k, m) for k in args.kinds for m in ((False, True) if k == "lab" else (False,))]
    rows = [engine_speed(kind, seconds=args.seconds, motion=motion) for kind, motion in cases]
    if args.json:
        _print_json({"benchmark": "sim", "machine": _machine(), "results": rows})
        return 0
    print(f"bosun bench sim: engine plants ticked back to back at their default rate, {args.seconds:g} s simulated")
    print(f"machine: {_machine()}; compiled kernels: {'on' if _kernels_on() else 'off'}")
    labels = {("lab", False): "lab (as it starts)", ("lab", True): "lab (VVMC in waves)", ("tac", False): "crane head"}
    print(
        _table(
            ["engine", "ticks", "wall [s]", "× real time"],
            [
                [
                    labels[(r["kind"], r["motion"])],
                    str(r["ticks"]),
                    f"{r['wall_s']:.2f}",
                    f"{r['speed_x_realtime']:.0f}",
                ]
                for r in rows
            ],
        )
    )
    return 0


def cmd_bench_hold(args: argparse.Namespace) -> int:
    from app.bench.hold import HOLD_TOLERANCE, bench_hold
    from app.models.registry import list_robots, load_spec

    robots = args.robots or [n for n in list_robots() if load_spec(n).type == "serial"]
    if not 1.0 <= args.rate <= 1000.0:
        raise BosunError(f"--rate must be between 1 and 1000 Hz, got {args.rate:g}")
    rows = bench_hold(
        robots, tuple(args.modes), args.sequences, seed=args.seed, rate=args.rate, workers=args.workers,
        progress=_progress_bar("hold", unit="sequence"),
    )  # fmt: skip
    if args.json:
        _print_json({"benchmark": "hold", "machine": _machine(), "rate": args.rate, "results": rows})
        return 0
    print(f"bosun bench hold: {args.sequences} seeded stick sequences per case ending still, {args.rate:g} Hz")
    print(f"held: overrun past the braking stop and drift once at rest both < {HOLD_TOLERANCE * 100:g} cm")
    print(
        _table(
            ["robot", "solver", "mode", "held", "max overrun [mm]", "max drift [mm]", "slowest settle [s]"],
            [
                [
                    r["robot"],
                    r["solver"],
                    r["mode"],
                    f"{r['held']}/{r['sequences']}",
                    f"{r['max_overrun_m'] * 1e3:.3f}",
                    f"{r['max_drift_m'] * 1e3:.3f}",
                    f"{r['max_settle_s']:.2f}",
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
        _print_json({"benchmark": "alarms", "machine": _machine(), **rep})
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
        _print_json({"benchmark": "plc-soak", "machine": _machine(), **rep.to_dict()})
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


def cmd_alarms(args: argparse.Namespace) -> int:
    from dataclasses import asdict

    from app.engine.alarm_catalog import CATALOG, SOURCES, reference_markdown

    if args.markdown:
        sys.stdout.write(reference_markdown())
        return 0
    if args.json:
        _print_json({"alarms": [asdict(a) for a in CATALOG]})
        return 0
    print(
        _table(
            ["key", "priority", "source", "alarm", "operator action"],
            [[a.key, a.priority, ", ".join(SOURCES[s] for s in a.sources), a.title, a.action] for a in CATALOG],
            last_col_max=70,
        )
    )
    return 0


def cmd_bench_loop(args: argparse.Namespace) -> int:
    from app.bench.loop import bench_loop

    result = bench_loop(
        rate=args.rate, seconds=args.seconds, robot=args.robot, solver=args.solver, flood=args.flood, burn=args.burn
    )
    result["machine"] = _machine()
    if args.json:
        _print_json(result)
        return 0
    extra = (f", {args.flood} junk messages/s from one client" if args.flood else "") + (
        ", one core kept busy by another process" if args.burn else ""
    )
    print(
        f"bosun bench loop: {args.robot} / {args.solver}, {args.rate:g} Hz for {args.seconds:g} s, one viewer and "
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
        f"{100 * result['viewer_fraction']:.1f} % of those published)"
    )
    if args.flood:
        print(f"  flood: {result['flood_sent']} sent; engine dropped {lp['dropped']} unread, rejected {lp['rejected']}")
    print(
        f"  E-STOP: {len(result['estop_ticks'])} of {result['estops_sent']} applied, at most "
        f"{result['estop_ticks_max']} tick(s) after receipt; joint speed after: {result['speed_after_estop']}"
    )
    return 0


# ---------------------------------------------------------------------------- plug-in commands
PLUGIN_GROUP = "bosun.commands"
HELPERS = {"positive_float": None, "finite_float": None}  # filled below, handed to plug-ins


def _load_plugin_commands(sub) -> None:
    """Commands other packages register under the ``bosun.commands`` entry-point group.

    The GUI (package ``ui``) adds ``bosun gui`` this way, so the Qt-free core never imports
    the GUI; each plug-in gets ``register(subparsers, helpers)``.
    """
    from importlib.metadata import entry_points

    HELPERS.update(positive_float=_positive_float, finite_float=_finite_float)
    for ep in entry_points(group=PLUGIN_GROUP):
        try:
            register = ep.load()
        except ImportError:
            continue  # the plug-in's package is not installed here
        register(sub, HELPERS)


# ---------------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    from app.analysis.operability import MAX_RUNS as MAX_STUDY_RUNS
    from app.analysis.operability import RUNS_CEILING as STUDY_RUNS_CEILING

    parser = _Parser(
        prog="bosun",
        description="Operator HMI and universal-input teleoperation for maritime cranes and robots.",
    )
    parser.add_argument("--version", action="version", version=f"bosun {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    p = sub.add_parser("robots", help="list the robot library (name, type, DOF, source)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--schema-markdown", action="store_true",
        help="the robot file reference from robot.xsd (docs/robot-files.md, as generated)",
    )  # fmt: skip
    p.set_defaults(func=cmd_robots)

    p = sub.add_parser(
        "check",
        help="validate robot files (schema, physical bounds, geometry) as the engine loads them",
        description="One line per file: ok, or why it is refused (file:line: what is wrong). "
        "Exit 0 when every file loads, 2 when any is refused.",
    )
    p.add_argument("robots", nargs="+", metavar="ROBOT", help="library names or paths to XML files")
    p.set_defaults(func=cmd_check)

    for name, func, text in [
        ("fk", cmd_fk, "forward kinematics: tool pose for joint values"),
        ("jacobian", cmd_jacobian, "geometric Jacobian of the tool point for joint values"),
    ]:
        p = sub.add_parser(name, help=text, description=text)
        p.add_argument("robot", help="robot name from the library (see 'bosun robots') or path to an XML file")
        p.add_argument(
            "--q",
            nargs="+",
            type=_finite_float,
            required=True,
            metavar="Q",
            help="joint values in joint order: rad and m (or degrees for revolute joints with --deg)",
        )
        p.add_argument("--deg", action="store_true", help="revolute joint values are in degrees")
        p.add_argument("--json", action="store_true", help="machine-readable output")
        p.set_defaults(func=func)

    from app.ik import solver_names

    def add_solver_args(p: argparse.ArgumentParser) -> None:
        p.add_argument("robot", help="robot name from the library or path to an XML file")
        p.add_argument("--solver", choices=solver_names(), default="ga", help="IK solver (default: ga)")
        p.add_argument("--seed", type=int, default=0, help="seed of the solver's random generator (default 0)")
        p.add_argument(
            "--time-budget",
            type=_positive_float,
            default=None,
            metavar="S",
            help="time budget of one solve [s] (default: the solver's, 0.1 s)",
        )
        p.add_argument(
            "--elbow",
            choices=["auto", "up", "down"],
            default=None,
            help="branch for --solver analytic (default auto: the valid one nearest the start)",
        )
        p.add_argument("--json", action="store_true", help="machine-readable output")

    p = sub.add_parser(
        "ik",
        help="inverse kinematics: joint values reaching a tool position",
        description="Solve one target. Exit 0 when solved, 1 when not (the closest solution is "
        "printed), 2 on a usage error.",
    )
    add_solver_args(p)
    p.add_argument(
        "--target",
        nargs=3,
        type=_finite_float,
        required=True,
        metavar=("X", "Y", "Z"),
        help="tool position in the world frame [m]",
    )
    p.add_argument(
        "--q0",
        nargs="+",
        type=_finite_float,
        default=None,
        metavar="Q",
        help="start configuration (rad/m, or degrees with --deg)",
    )
    p.add_argument("--deg", action="store_true", help="--q0 revolute values are in degrees")
    p.set_defaults(func=cmd_ik)

    p = sub.add_parser("analyze", help="error distribution over the grid³ targets of the workspace box (Fig. 5)")
    add_solver_args(p)
    p.add_argument(
        "--grid",
        type=int,
        default=8,
        choices=range(2, 41),
        metavar="N",
        help="targets per axis, 2..40 (default 8: 512 targets)",
    )
    p.add_argument("--out", default=None, help="output folder (default out/analyze_ROBOT_SOLVER)")
    p.set_defaults(func=cmd_analyze)

    p = sub.add_parser("track", help="trajectory tracking: X, Y, Z target vs reached (Fig. 4)")
    add_solver_args(p)
    p.add_argument("--duration", type=_positive_float, default=20.0, help="path duration [s] (default 20)")
    p.add_argument("--dt", type=_positive_float, default=0.1, help="time between targets [s] (default 0.1)")
    p.add_argument("--out", default=None, help="output folder (default out/track_ROBOT_SOLVER)")
    p.set_defaults(func=cmd_track)

    p = sub.add_parser("bench", help="benchmarks (not tests): bench ik, loop, sim, hold, alarms, plc-soak")
    bench = p.add_subparsers(dest="bench", metavar="WHAT", parser_class=_Parser, required=True)
    b = bench.add_parser("ik", help="median/p95 solve time and success per robot and solver")
    b.add_argument("--targets", type=int, default=500, help="seeded reachable targets per robot (default 500)")
    b.add_argument("--seed", type=int, default=7, help="seed of targets and solvers (default 7)")
    b.add_argument("--robots", nargs="+", default=None, help="robots to bench (default: every serial robot)")
    b.add_argument(
        "--peers",
        action="store_true",
        help="also robotics-toolbox-python (ik_LM, ikine_LM) and ikpy on the same targets (extra 'bench')",
    )
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_bench)
    b = bench.add_parser("loop", help="engine tick period, jitter, missed deadlines and input latency")
    b.add_argument("--rate", type=float, choices=[500.0, 1000.0], default=500.0, help="loop rate [Hz] (500 or 1000)")
    b.add_argument("--seconds", type=_positive_float, default=30.0, help="duration [s] (default 30)")
    b.add_argument("--robot", default="comau_smart5_3dof", help="robot (default comau_smart5_3dof)")
    b.add_argument("--solver", default="jacobian", help="solver (default jacobian)")
    b.add_argument("--flood", type=int, default=0, metavar="N", help="one more client sending N junk messages a second")
    b.add_argument("--burn", action="store_true", help="another process keeps one core busy")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_bench_loop)
    b = bench.add_parser("sim", help="how fast the lab and crane-head engines run unthrottled")
    b.add_argument("--kinds", nargs="+", choices=["lab", "tac"], default=["lab", "tac"], help="engines (default both)")
    b.add_argument("--seconds", type=_positive_float, default=20.0, help="simulated time [s] (default 20)")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_bench_sim)
    b = bench.add_parser(
        "hold", help="hold means hold: seeded stick sequences ending still, tool drift after braking (issue 26)"
    )
    b.add_argument("--sequences", type=_positive_int, default=1000, help="sequences per robot × solver × mode")
    b.add_argument("--robots", nargs="+", default=None, help="robots (default: every serial robot)")
    b.add_argument("--modes", nargs="+", choices=["velocity", "position"], default=["velocity", "position"])
    b.add_argument("--rate", type=float, default=1000.0, help="engine rate [Hz] (default 1000, as the engine runs)")
    b.add_argument("--seed", type=int, default=0, help="seed of the stick sequences (default 0)")
    b.add_argument("--workers", type=_positive_int, default=1, help="processes (default 1)")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_bench_hold)
    b = bench.add_parser(
        "alarms", help="alarm rates of a scripted session (three engines, a study, VVMC, two STOPs) vs EEMUA 191"
    )
    b.add_argument("--minutes", type=_positive_float, default=10.0, help="session length (default 10)")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_bench_alarms)
    b = bench.add_parser(
        "plc-soak", help="the lab engine against a PLC test server injecting NaN, wrong sizes, link loss, slowness"
    )
    b.add_argument("--minutes", type=_positive_float, default=10.0, help="soak length (default 10)")
    b.add_argument("--seed", type=int, default=27, help="seed of the injections and commands (default 27)")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_bench_plc_soak)
    p = sub.add_parser("alarms", help="the alarm reference: every alarm, its cause, consequence and action")
    p.add_argument("--markdown", action="store_true", help="docs/alarms.md, as generated")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_alarms)

    p = sub.add_parser(
        "study", help="studies on a Dask cluster: study operability (scatter diagram × headings × seeds)"
    )
    stu = p.add_subparsers(dest="study_cmd", metavar="WHAT", parser_class=_Parser, required=True)
    b = stu.add_parser(
        "operability", help="crane-head compensation over a wave scatter diagram: one simulation per cell (Dask)"
    )
    b.add_argument("--mode", choices=["off", "tac", "cooperative"], default="tac", help="compensation (default tac)")
    b.add_argument(
        "--scatter", required=True, metavar="NAME|FILE",
        help="north-atlantic (IACS Rec. 34, Hs × Tz) or a CSV: hs\\tp,TP1,… (or hs\\tz,TZ1,…) then HS,p1,…",
    )  # fmt: skip
    b.add_argument(
        "--headings", type=_finite_float, nargs="+", default=[90.0, 135.0, 180.0],
        help="[deg], each within ±360 (default 90 135 180)",
    )  # fmt: skip
    b.add_argument("--seeds", type=_positive_int, default=2, help="wave seeds per cell and heading, 1–1000 (default 2)")
    b.add_argument(
        "--max-runs", type=_positive_int, default=MAX_STUDY_RUNS, metavar="N",
        help=f"the largest study run: cells with a probability × headings × seeds (default {MAX_STUDY_RUNS}; "
        f"at most {STUDY_RUNS_CEILING}); a bigger one is refused before any work",
    )  # fmt: skip
    b.add_argument("--duration", type=_positive_float, default=300.0, help="simulated time per run [s], ≤ 10800 (300)")
    b.add_argument("--criterion", type=_positive_float, default=0.1, help="workable: rms(e_c) ≤ this [m] (0.1)")
    b.add_argument("--vessel", default=None, metavar="NAME|FILE", help="vessel (default supply); bosun vessel list")
    b.add_argument(
        "--spectrum", choices=["jonswap", "pm", "torsethaugen"], default=None,
        help="default: pm for a Tz diagram (as IACS Rec. 34 states it), jonswap for a Tp one",
    )  # fmt: skip
    b.add_argument(
        "--scheduler", default=None, metavar="tcp://HOST:8786",
        help="a Dask scheduler (default: a local cluster); a peer that does not answer as a scheduler within 4 s "
        "is refused",
    )  # fmt: skip
    b.add_argument(
        "--workers", type=_positive_int, default=None, help="local cluster's worker processes, 1–64 (default: cores)"
    )
    b.add_argument("--out", default="out/operability", help="output folder; its cells/ are the resume cache")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_study_operability)

    p = sub.add_parser("vessel", help="vessels: vessel list, vessel rao (RAOs from main particulars, Capytaine)")
    ves = p.add_subparsers(dest="vessel_cmd", metavar="WHAT", parser_class=_Parser, required=True)
    b = ves.add_parser("list", help="the vessels known by name (the default first)")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_vessel_list)
    b = ves.add_parser(
        "rao", help="6-DOF motion RAOs of a monohull from its main particulars (boundary elements, extra 'marine')"
    )
    for flag, unit, what in (
        ("--lpp", "m", "length between perpendiculars"), ("--beam", "m", "beam"), ("--draft", "m", "draft"),
        ("--cb", "", "block coefficient"), ("--gm-t", "m", "transverse metacentric height"),
        ("--gm-l", "m", "longitudinal metacentric height"), ("--r44", "m", "roll radius of gyration"),
        ("--r55", "m", "pitch radius of gyration"), ("--r66", "m", "yaw radius of gyration"), ("--mass", "kg", "mass"),
    ):  # fmt: skip
        b.add_argument(
            flag, dest=flag[2:].replace("-", "_"), type=_positive_float, default=None,
            help=f"{what}{' [' + unit + ']' if unit else ''} (default: the MSS supply vessel's; "
            "physical range: README)",
        )  # fmt: skip
    b.add_argument("--name", default=None, help="the vessel's name (in the table's header)")
    b.add_argument(
        "--cwp", type=_positive_float, default=None, help="waterplane coefficient (default: from GM_L − GM_T)"
    )
    b.add_argument(
        "--roll-damping", type=_positive_float, default=0.15, help="total ζ44 at the roll natural frequency (0.15)"
    )
    b.add_argument("--nx", type=int, default=40, help="panels along the half hull, 4–200 (default 40)")
    b.add_argument("--nz", type=int, default=8, help="panels down its girth, 2–50; nx × nz ≤ 2000 (default 8)")
    b.add_argument("--w-min", type=_positive_float, default=0.1, help="lowest wave frequency [rad/s], ≥ 0.01 (0.1)")
    b.add_argument("--w-max", type=_positive_float, default=2.0, help="highest wave frequency [rad/s], ≤ 20 (2.0)")
    b.add_argument("--n-w", type=int, default=40, help="number of frequencies, 2–200 (default 40)")
    b.add_argument(
        "--heading-step", type=_positive_float, default=10.0, help="heading step [deg], 1–180, divides 360 (10)"
    )
    b.add_argument("--out", default="out/vessel_rao.csv", help="the RAO table (CSV; default out/vessel_rao.csv)")
    b.add_argument("--json", action="store_true", help="machine-readable output")
    b.set_defaults(func=cmd_vessel_rao)

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
    _load_plugin_commands(sub)

    def add_engine_args(p: argparse.ArgumentParser) -> None:
        p.add_argument("--robot", default="comau_smart5_3dof", help="robot to load (default comau_smart5_3dof)")
        p.add_argument("--solver", default="jacobian", help="solver (default jacobian)")
        p.add_argument("--mode", choices=["position", "velocity"], default="velocity", help="default velocity")
        p.add_argument(
            "--robots-dir",
            action="append",
            metavar="DIR",
            help="a folder whose robot files clients may load by path (repeatable; the library and "
            "$BOSUN_ROBOTS_DIR always are)",
        )

    p = sub.add_parser("server", help="run the engine headless (fixed-rate loop, ZeroMQ protocol)")
    p.add_argument(
        "--bind",
        default="tcp://127.0.0.1:5555",
        help="request URL: tcp://HOST:PORT or ipc://PATH (default tcp://127.0.0.1:5555); "
        "a non-local address needs CURVE keys (--curve-secret and --curve-clients)",
    )
    add_engine_args(p)
    p.add_argument(
        "--plant",
        choices=["teleop", "tac", "lab"],
        default="teleop",
        help="teleop (a library manipulator), tac (vessel, crane, Delta head), lab (Motion-Lab); default teleop",
    )
    p.add_argument(
        "--rate",
        type=_positive_float,
        default=None,
        help="control rate [Hz], up to 1000 (default 1000; tac and lab 50)",
    )
    p.add_argument(
        "--publish-rate", type=_positive_float, default=None, help="state messages per second (default 50; tac 25)"
    )
    p.add_argument("--token", default=None, help="shared token every client must present (loopback testing only)")
    p.add_argument(
        "--curve-secret", default=None, metavar="FILE", help="the engine's CURVE secret key file (bosun keys)"
    )
    p.add_argument(
        "--curve-clients", default=None, metavar="DIR", help="folder of the client public keys (*.key) allowed in"
    )
    p.add_argument(
        "--operator-timeout",
        type=_positive_float,
        default=5.0,
        help="seconds without a message before the operator role lapses (default 5; a warning at 2)",
    )
    p.add_argument(
        "--plc",
        default=None,
        metavar="AMS_NET_ID[:PORT]",
        help="with --plant lab: drive the real Motion-Lab through its TwinCAT PLC over ADS (needs the extra "
        "plc: pip install 'bosun[plc]'), e.g. 192.168.90.150.1.1:851 (port default 851)",
    )
    p.add_argument(
        "--plc-host", default=None, metavar="HOST", help="the PLC's IP or name (default: the Net ID's first 4 numbers)"
    )
    p.add_argument(
        "--plc-local-id",
        default=None,
        metavar="AMS_NET_ID",
        help="this machine's AMS Net ID, if the PLC's route to it names another (default: the ADS library's)",
    )
    p.add_argument("--duration", type=_positive_float, default=None, help="stop after this many seconds")
    p.add_argument(
        "--exit-with-parent",
        action="store_true",
        help="stop when the process that started this engine ends (the GUI's own engines use it)",
    )
    p.set_defaults(func=cmd_server)

    p = sub.add_parser("joystick", help="stream a local joystick to an engine (the input client)")
    p.add_argument("--connect", required=True, help="the engine's request URL, e.g. tcp://127.0.0.1:5555")
    p.add_argument("--token", default=None, help="shared token of the engine (loopback testing)")
    p.add_argument("--curve-secret", default=None, metavar="FILE", help="this client's CURVE secret key (bosun keys)")
    p.add_argument("--server-key", default=None, metavar="FILE", help="the engine's CURVE public key")
    p.add_argument("--device", default=None, help="use the first joystick whose name contains this")
    p.add_argument("--rate", type=_positive_float, default=100.0, help="input messages per second (default 100)")
    p.add_argument("--duration", type=_positive_float, default=None, help="stop after this many seconds")
    p.add_argument("--virtual", action="store_true", help="attach an SDL virtual joystick (no hardware needed)")
    p.set_defaults(func=cmd_joystick)

    p = sub.add_parser(
        "keys",
        help="make a CURVE key pair for remote operation (NAME.key public, NAME.key_secret secret)",
        description="Writes NAME.key (public: give it to the other side) and NAME.key_secret (keep it; mode "
        "0600) in ZeroMQ's certificate format. The engine needs its own secret key and a folder with each "
        "allowed client's public key; a client needs its own secret key and the engine's public key.",
    )
    p.add_argument("name", help="name of the pair, e.g. engine or operator-laptop")
    p.add_argument("--dir", default="keys", help="folder to write into (default ./keys)")
    p.set_defaults(func=cmd_keys)

    p = sub.add_parser("cli-reference", help="this command line's reference in Markdown (docs/cli.md, as generated)")
    p.set_defaults(func=cmd_cli_reference)
    return parser


def cmd_cli_reference(args: argparse.Namespace) -> int:
    sys.stdout.write(cli_reference_markdown(build_parser()))
    return 0


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:  # argparse keeps subcommands on its private action list
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _subcommand_help(parser: argparse.ArgumentParser) -> dict[str, str]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return {a.dest: a.help or "" for a in action._choices_actions}
    return {}


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def cli_reference_markdown(parser: argparse.ArgumentParser) -> str:
    """The command line reference (docs/cli.md): every command and option, walked from the parser itself.

    Usage lines are formatted at a fixed width, so the page does not depend on the terminal."""
    out = [
        "# Command line reference",
        "",
        "<!-- generated by `bosun cli-reference > docs/cli.md`; tests/test_docs.py keeps it equal -->",
        "",
        "Every command and option of `bosun`, generated from its argument parser (`python -m app` is the same).",
        "Commands that need an extra (`gui`, `joystick`, `plc`, `marine`, `study`, `bench`) say in one line",
        "what to install when it is missing.",
        "",
    ]

    def usage(p: argparse.ArgumentParser) -> str:
        f = argparse.HelpFormatter(p.prog, width=100)
        f.add_usage(p.usage, p._actions, p._mutually_exclusive_groups)
        return f.format_help().strip()

    def section(p: argparse.ArgumentParser, level: int, help_text: str) -> None:
        f = argparse.HelpFormatter(p.prog, width=100)
        out.extend([f"{'#' * level} `{p.prog}`", ""])
        if help_text:
            text = _cell(help_text)
            out.extend([text[:1].upper() + text[1:] + ("" if text.endswith(".") else "."), ""])
        if p.description and p.description != help_text:
            out.extend([_cell(p.description), ""])
        out.extend(["```text", usage(p), "```", ""])
        rows = []
        for a in p._actions:
            if a.help == argparse.SUPPRESS or isinstance(a, argparse._SubParsersAction):
                continue
            if a.option_strings:
                name = ", ".join(a.option_strings)
                if a.nargs != 0:
                    name += " " + f._format_args(a, f._get_default_metavar_for_optional(a))
            else:
                name = f._format_args(a, f._get_default_metavar_for_positional(a))
            choices = ", ".join(f"`{c}`" for c in a.choices) if a.choices and not isinstance(a.choices, dict) else ""
            rows.append(f"| `{' '.join(name.split())}` | {_cell(f._expand_help(a)) if a.help else ''} | {choices} |")
        if rows:
            out.extend(["| argument | meaning | choices |", "|---|---|---|", *rows, ""])
        children = _subparsers(p)
        helps = _subcommand_help(p)
        for name, child in children.items():
            section(child, min(level + 1, 4), helps.get(name, ""))

    section(parser, 2, "")
    return "\n".join(out).rstrip() + "\n"


def _commands(parser: argparse.ArgumentParser) -> set[str]:
    for action in parser._actions:  # argparse keeps subcommands on its private action list
        if isinstance(action, argparse._SubParsersAction):
            return set(action.choices)
    return set()


TOP_LEVEL_OPTIONS = ("-h", "--help", "--version")  # the options ``bosun`` itself takes before a command


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``bosun`` and ``python -m app``; returns the exit status."""
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0].startswith("-") and argv[0] not in TOP_LEVEL_OPTIONS and "gui" in _commands(parser):
        # the README's synopsis, ``bosun [gui] [--connect URL] ... [--robot R]``: options without a command are
        # the GUI's (``bosun --robot knuckle_boom_crane`` was "invalid choice" for COMMAND, issue 26, item 10)
        argv = ["gui", *argv]
    args = parser.parse_args(argv)
    args.argv = argv  # what made an output (vessel rao writes it)
    from app.models.kernels import clear_stale

    clear_stale()  # before any kernel loads its cached machine code (build_parser has imported the kernels)
    if args.command is None:
        # the GUI when it is installed, else the robot library
        args = parser.parse_args(["gui"] if "gui" in _commands(parser) else ["robots"])
    import signal

    from app.errors import raise_interrupt

    main_thread = threading.current_thread() is threading.main_thread()
    # SIGTERM ends a study like Ctrl-C (main() is also called in-process); server, joystick, GUI set their own
    previous = signal.signal(signal.SIGTERM, raise_interrupt) if main_thread else None
    try:
        return args.func(args)
    except BosunError as err:
        print(f"bosun: error: {err}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("bosun: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as err:
        if interrupted(err):  # Ctrl-C or SIGTERM inside a compiled kernel's call: a SystemError caused by it
            print("bosun: interrupted", file=sys.stderr)
            return 130
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
