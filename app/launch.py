"""The ``bosun`` and ``python -m app`` entry point.

It imports nothing heavy itself, so Ctrl-C at any moment, even while NumPy, ZeroMQ or Qt are
still loading, ends the program with one line and status 130, never a traceback."""

from __future__ import annotations

import os
import sys

INTERRUPTED = 130


def main() -> int:
    import faulthandler
    import signal

    def terminated(*_):  # SIGTERM while the modules still load (seconds on a busy machine) is Ctrl-C too: one
        raise KeyboardInterrupt  # line, 130; a command with its own SIGTERM handling sets it later

    signal.signal(signal.SIGTERM, terminated)
    if hasattr(signal, "SIGUSR1"):  # ``kill -USR1 PID`` prints every thread's stack (a hung process explains itself)
        faulthandler.register(signal.SIGUSR1, all_threads=True)
    try:
        from app.cli import main as cli_main

        code = cli_main()
    except KeyboardInterrupt:
        print("bosun: interrupted", file=sys.stderr)
        code = INTERRUPTED
    if code == INTERRUPTED:
        # A KeyboardInterrupt raised while C code ran Python (an extension module's import runs its
        # code through PyRun_*) marks it "unhandled" inside CPython even when caught, and the
        # interpreter then kills itself with SIGINT at exit (status -2, seen in CI). Everything is
        # already written or removed (studies write atomically), so leave with the documented status.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(INTERRUPTED)
    return code
