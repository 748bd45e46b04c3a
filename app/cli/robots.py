"""``bosun robots``, ``check``, ``import urdf``, ``fk``, ``jacobian``, ``ik``, ``analyze``, ``track``: the robot
library, its kinematics and its solvers."""

from __future__ import annotations

import argparse
import math
import shutil
import sys
from pathlib import Path
from typing import Any

import numpy as np

from app.cli.args import add_json, add_out, command
from app.cli.common import (
    EXIT_USAGE,
    _finite_float,
    _out_dir,
    _positive_float,
    _print_json,
    _progress_bar,
    _solver_options,
    _table,
    _write_run,
)
from app.errors import BosunError
from app.geometry import matrix_to_euler_zyx


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


def _joint_values(robot, values: list[float], deg: bool) -> np.ndarray:
    """``--q`` or ``--q0`` of a serial arm, checked against it; with ``--deg`` its revolute values are degrees."""
    q = robot.check_q(values)
    return np.where(np.array(robot.joint_kinds) == "revolute", np.deg2rad(q), q) if deg else q


def _serial_robot_and_q(args: argparse.Namespace):
    from app.models.registry import load_robot

    robot = load_robot(args.robot)
    if getattr(robot, "kind", "serial") != "serial":
        raise BosunError(f"{robot.name} is a {robot.kind} mechanism; this command takes a serial arm")
    return robot, _joint_values(robot, args.q, args.deg)


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


def cmd_import_urdf(args: argparse.Namespace) -> int:
    """A URDF's serial chain as a Bosun robot file (:mod:`app.models.urdf`), checked by loading what it wrote."""
    from app.models.registry import build_model
    from app.models.urdf import robot_xml_from_urdf
    from app.models.xml import parse_robot_xml, read_robot_file, urdf_root

    out = Path(args.out)
    if out.suffix != ".xml":
        raise BosunError(f"--out {args.out}: a robot file's name ends in .xml")
    name = out.stem
    if not name.isidentifier() or not name.isascii():
        raise BosunError(f"--out {args.out}: the robot's name is the file's ('{name}'): use letters, digits and _")
    label = str(args.file)
    root = urdf_root(read_robot_file(Path(args.file), label), label)
    text = robot_xml_from_urdf(root, label, base=args.base, tip=args.tip, name=name)
    robot = build_model(parse_robot_xml(text, str(out)))  # what it wrote loads as a robot file
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")
    print(f"wrote {out}: {name}, {robot.n_joints} joints ({', '.join(robot.joint_names)})")
    return 0


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


def cmd_ik(args: argparse.Namespace) -> int:
    from app.ik import make_solver
    from app.models.registry import load_robot

    robot = load_robot(args.robot)
    solver = make_solver(args.solver, robot, seed=args.seed, **_solver_options(args))
    q0 = None if args.q0 is None else _joint_values(robot, args.q0, args.deg)
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


def _run_study(args: argparse.Namespace, kind: str, stem: str, plot, study):
    """An IK study from its command's options: ``study(robot, solver_options, progress)`` gives the result,
    written as STEM.csv, STEM.png and summary.json into the output folder (printed with --json).
    Returns the robot, the summary and the folder."""
    from app.analysis.ik_studies import write_json

    robot, opts, out = _study_setup(args, kind)
    result = study(robot, opts, _progress_bar(f"{robot.name}/{args.solver}"))

    def save(tmp: Path) -> dict[str, Any]:
        result.write_csv(tmp / f"{stem}.csv")
        plot(result, tmp / f"{stem}.png")
        summary = result.summary()
        write_json(summary, tmp / "summary.json")
        return summary

    return robot, _write_run(args, out, save), out


def cmd_analyze(args: argparse.Namespace) -> int:
    from app.analysis.ik_studies import error_distribution, plot_error_distribution

    def study(robot, opts, progress):
        return error_distribution(robot, args.solver, args.grid, seed=args.seed, solver_options=opts, progress=progress)

    robot, summary, out = _run_study(args, "analyze", "error_distribution", plot_error_distribution, study)
    if args.json:
        return 0
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

    def study(robot, opts, progress):
        return track(
            robot, args.solver, duration=args.duration, dt=args.dt, seed=args.seed, solver_options=opts,
            progress=progress,
        )  # fmt: skip

    robot, summary, out = _run_study(args, "track", "tracking", plot_tracking, study)
    if args.json:
        return 0
    print(
        f"{robot.name} / {args.solver}: {summary['samples']} targets over {summary['duration_s']:.1f} s, "
        f"rms error {summary['rms_error_m']:.3g} m, max {summary['max_error_m']:.3g} m, "
        f"solved {summary['success_rate']:.0%}"
    )
    print(f"  wrote {out}/tracking.csv, tracking.png, summary.json")
    return 0


def _add_joint_values(p: argparse.ArgumentParser, flag: str, help: str, deg_help: str, required: bool) -> None:
    """FLAG Q [Q ...], joint values in joint order (read by :func:`_joint_values`), and --deg."""
    p.add_argument(flag, nargs="+", type=_finite_float, required=required, default=None, metavar="Q", help=help)
    p.add_argument("--deg", action="store_true", help=deg_help)


def register(sub) -> None:
    """Add this group's commands to ``bosun``'s subparsers."""
    with command(sub, "robots", cmd_robots, json=False, help="list the robot library (name, type, DOF, source)") as p:
        add_json(p)
        p.add_argument(
            "--schema-markdown", action="store_true",
            help="the robot file reference from robot.xsd (docs/robot-files.md, as generated)",
        )  # fmt: skip

    with command(
        sub,
        "check",
        cmd_check,
        json=False,
        help="validate robot files (schema, physical bounds, geometry) as the engine loads them",
        description="One line per file: ok, or why it is refused (file:line: what is wrong). "
        "Exit 0 when every file loads, 2 when any is refused.",
    ) as p:
        p.add_argument("robots", nargs="+", metavar="ROBOT", help="library names or paths to XML files")

    imp = sub.add_parser("import", help="import a robot from another format (URDF) as a Bosun robot file")
    imp_sub = imp.add_subparsers(dest="format", metavar="FORMAT", required=True)
    with command(
        imp_sub, "urdf", cmd_import_urdf, json=False,
        help="a URDF's serial chain as a Bosun robot file (standard DH, base and tool)",
        description="Reads FILE with yourdfpy and writes the chain from --base to --tip as a robot file (its DH "
        "frames from the joint axes at q = 0; joint names, directions, zeros and limits the URDF's). Revolute, "
        "continuous, prismatic and fixed joints; <mimic>, floating and planar joints and closed loops are refused "
        "in one line (exit 2). A .urdf also loads directly wherever a robot file is accepted.",
    ) as p:  # fmt: skip
        p.add_argument("file", metavar="FILE", help="the URDF file")
        p.add_argument("--base", metavar="LINK", help="the chain's first link (default: the URDF's root link)")
        p.add_argument("--tip", metavar="LINK", help="the chain's last link, the tool (default: the only leaf)")
        p.add_argument("--out", required=True, metavar="ROBOT.xml", help="the robot file to write (its name: ROBOT)")

    for name, func, text in [
        ("fk", cmd_fk, "forward kinematics: tool pose for joint values"),
        ("jacobian", cmd_jacobian, "geometric Jacobian of the tool point for joint values"),
    ]:
        with command(sub, name, func, help=text, description=text) as p:
            p.add_argument("robot", help="robot name from the library (see 'bosun robots') or path to an XML file")
            _add_joint_values(
                p, "--q", "joint values in joint order: rad and m (or degrees for revolute joints with --deg)",
                "revolute joint values are in degrees", required=True,
            )  # fmt: skip

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
        task = p.add_argument_group("GA task (--solver ga or ga-restart; issue 32: the published cost by default)")
        task.add_argument(
            "--ga-weights", nargs=3, type=_finite_float, metavar=("WX", "WY", "WZ"), default=None,
            help="weights of the normalised position error per world axis (default 1 1 1, the published cost)",
        )  # fmt: skip
        task.add_argument(
            "--ga-axis", nargs=3, type=_finite_float, metavar=("AX", "AY", "AZ"), default=None,
            help="the direction the tool's z should point along (with --ga-axis-weight)",
        )  # fmt: skip
        task.add_argument(
            "--ga-axis-weight", type=_finite_float, metavar="W", default=None,
            help="weight of the tool-axis term w (1 - z·a)/2 (default 1 with --ga-axis)",
        )  # fmt: skip
        add_json(p)

    with command(
        sub,
        "ik",
        cmd_ik,
        json=False,
        help="inverse kinematics: joint values reaching a tool position",
        description="Solve one target. Exit 0 when solved, 1 when not (the closest solution is "
        "printed), 2 on a usage error.",
    ) as p:
        add_solver_args(p)
        p.add_argument(
            "--target",
            nargs=3,
            type=_finite_float,
            required=True,
            metavar=("X", "Y", "Z"),
            help="tool position in the world frame [m]",
        )
        _add_joint_values(
            p, "--q0", "start configuration (rad/m, or degrees with --deg)", "--q0 revolute values are in degrees",
            required=False,
        )  # fmt: skip

    analyze_help = "error distribution over the grid³ targets of the workspace box (Fig. 5)"
    with command(sub, "analyze", cmd_analyze, json=False, help=analyze_help) as p:
        add_solver_args(p)
        p.add_argument(
            "--grid",
            type=int,
            default=8,
            choices=range(2, 41),
            metavar="N",
            help="targets per axis, 2..40 (default 8: 512 targets)",
        )
        add_out(p, "analyze_ROBOT_SOLVER")

    track_help = "trajectory tracking: X, Y, Z target vs reached (Fig. 4)"
    with command(sub, "track", cmd_track, json=False, help=track_help) as p:
        add_solver_args(p)
        p.add_argument("--duration", type=_positive_float, default=20.0, help="path duration [s] (default 20)")
        p.add_argument("--dt", type=_positive_float, default=0.1, help="time between targets [s] (default 0.1)")
        add_out(p, "track_ROBOT_SOLVER")
