"""The argument groups several commands share, each defined once: the same flag, type, default and help text
wherever it appears (docs/cli.md is generated from them).

The choices are constants here rather than imports of the modules that define them, so that building the
parser (every ``bosun`` start) loads no simulation code; tests/test_cli.py keeps each equal to its source.
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Callable, Iterator

from app.cli.common import _Parser, _positive_float

SPECTRA = ("jonswap", "pm", "torsethaugen")  # app.marine.waves.SPECTRA
TAC_MODES = ("off", "tac", "cooperative")  # app.scenarios.tac.MODES


def group(sub, name: str, help: str, dest: str):
    """A command with subcommands (``bosun NAME WHAT``); returns the subparsers to add them to."""
    p = sub.add_parser(name, help=help)
    return p.add_subparsers(dest=dest, metavar="WHAT", parser_class=_Parser, required=True)


@contextlib.contextmanager
def command(
    sub, name: str, func: Callable[[argparse.Namespace], int], *, json: bool = True, **kwargs
) -> Iterator[argparse.ArgumentParser]:
    """A subcommand NAME that runs FUNC: its options are added in the ``with`` block, then ``--json`` last
    (``json=False``: the block adds it where the command has it, or the command has none)."""
    p = sub.add_parser(name, **kwargs)
    yield p
    if json:
        add_json(p)
    p.set_defaults(func=func)


def add_json(p) -> None:
    """``--json``; ``p`` is a parser or a group of one (a mutually exclusive one too)."""
    p.add_argument("--json", action="store_true", help="machine-readable output")


def add_out(p: argparse.ArgumentParser, default: str) -> None:
    """``--out`` of a command that writes a folder of results (out/DEFAULT when not given)."""
    p.add_argument("--out", default=None, help=f"output folder (default out/{default})")


# ---------------------------------------------------------------------------- the sea of a simulation
def add_hs(p: argparse.ArgumentParser, default: float) -> None:
    p.add_argument(
        "--hs", type=_positive_float, default=default, help=f"significant wave height [m] (default {default:g})"
    )


def add_tp(p: argparse.ArgumentParser, default: float) -> None:
    p.add_argument("--tp", type=_positive_float, default=default, help=f"peak period [s] (default {default:g})")


def add_spectrum(p: argparse.ArgumentParser) -> None:
    p.add_argument("--spectrum", choices=list(SPECTRA), default="jonswap", help="default jonswap")


def add_duration(p: argparse.ArgumentParser, default: float) -> None:
    p.add_argument(
        "--duration", type=_positive_float, default=default, help=f"simulated time [s] (default {default:g})"
    )


def add_wave_seed(p: argparse.ArgumentParser) -> None:
    p.add_argument("--seed", type=int, default=1, help="seed of the wave phases (default 1)")


def add_vessel(p: argparse.ArgumentParser, help: str) -> None:
    """``--vessel`` (alias ``--rao``): a vessel by name or an RAO file."""
    p.add_argument("--vessel", "--rao", dest="rao", default=None, metavar="NAME|FILE", help=help)
