"""The ``bosun`` command line: one module per command group, each registering its own subcommands.

Every user mistake (bad robot file, unknown name, wrong number of joint values, a
value that is not a number) ends in one line on stderr and exit status 2, never a
traceback.
"""

from __future__ import annotations

import argparse
import sys
import threading
from collections.abc import Sequence

from app import __version__
from app.cli import bench, engine, plugins, reference, robots, sim, study, vessel
from app.cli.common import EXIT_USAGE, _Parser
from app.cli.reference import _subparsers, cli_reference_markdown
from app.errors import BosunError, interrupted

__all__ = ["_subparsers", "build_parser", "cli_reference_markdown", "main"]

# the order of ``bosun --help`` and of docs/cli.md
GROUPS = (
    robots.register,
    bench.register,
    reference.register_alarms,
    reference.register_describe,
    study.register,
    vessel.register,
    sim.register,
    plugins.register,
    engine.register,
    reference.register,
)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="bosun",
        description="Operator HMI and universal-input teleoperation for maritime cranes and robots.",
    )
    parser.add_argument("--version", action="version", version=f"bosun {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for register in GROUPS:
        register(sub)
    return parser


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
