"""The ``bosun`` and ``python -m app`` entry point.

It imports nothing heavy itself, so Ctrl-C at any moment, even while NumPy, ZeroMQ or Qt are
still loading, ends the program with one line and status 130, never a traceback."""

from __future__ import annotations

import sys


def main() -> int:
    try:
        from app.cli import main as cli_main

        return cli_main()
    except KeyboardInterrupt:
        print("bosun: interrupted", file=sys.stderr)
        return 130
