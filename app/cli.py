"""The ``bosun`` command line.

Every user mistake (bad robot file, unknown name, wrong number of joint values, a
value that is not a number) ends in one line on stderr and exit status 2, never a
traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from app import __version__
from app.errors import BosunError
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


def cmd_fk(args: argparse.Namespace) -> int:
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


# ---------------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="bosun",
        description="Operator HMI and universal-input teleoperation for maritime cranes and robots.",
    )
    parser.add_argument("--version", action="version", version=f"bosun {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    p = sub.add_parser("robots", help="list the robot library (name, type, DOF, source)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_robots)

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
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``bosun`` and ``python -m app``; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        # Until the GUI exists, running the app lists the robot library.
        args = parser.parse_args(["robots"])
    try:
        return args.func(args)
    except BosunError as err:
        print(f"bosun: error: {err}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0
