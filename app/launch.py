"""The ``bosun`` and ``python -m app`` entry point.

It imports nothing heavy itself, so Ctrl-C at any moment, even while NumPy, ZeroMQ or Qt are
still loading, ends the program with one line and status 130, never a traceback."""

from __future__ import annotations

import os
import sys

INTERRUPTED = 130


#: the processes that run a fixed-rate loop or a screen: one BLAS thread each (see :func:`_one_blas_thread`)
REALTIME_COMMANDS = ("server", "gui", "view", "joystick")


def _one_blas_thread(argv: list[str]) -> None:
    """An engine, the GUI, a viewer and the joystick client use one BLAS thread (unless the user set it).

    Their matrices are small (6 × 6 Jacobians, the anti-sway's 4-state Riccati equations): a second OpenBLAS
    thread only spins against the control loop and the other processes on the machine.  Measured on the
    2-core VM beside a busy process, the Motion-Lab engine's anti-sway gain schedule (82 Riccati solves at
    start) took 0.32 s with two threads and 0.12 s with one; in a profile, 1.7 s.  Studies, benchmarks and
    ``vessel rao`` (Capytaine's dense BEM solves) keep OpenBLAS's default.  Set before NumPy loads."""
    cmd = argv[0] if argv and not argv[0].startswith("-") else "gui"
    if cmd in REALTIME_COMMANDS:
        for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(var, "1")


def main() -> int:
    try:
        _one_blas_thread(sys.argv[1:])
        # inside the try: Ctrl-C 50 ms after start landed in ``import signal`` (its enums), a traceback
        import faulthandler
        import signal

        if hasattr(signal, "SIGUSR1"):  # ``kill -USR1 PID`` prints every thread's stack (a hung process says where)
            faulthandler.register(signal.SIGUSR1, all_threads=True)
        # SIGTERM is Ctrl-C from the first moment: one line and status 130 also while the CLI still loads (it
        # ended the process silently with -15 before app.cli set its own handler; issue 27, item 10)
        from app.errors import keep_dropped_interrupts, raise_interrupt

        sys.unraisablehook = keep_dropped_interrupts  # H93
        signal.signal(signal.SIGTERM, raise_interrupt)
        signal.signal(signal.SIGINT, raise_interrupt)  # Python's own raises inside numba's callbacks too (H92)
        code = _import_cli()()
    except KeyboardInterrupt:
        print("bosun: interrupted", file=sys.stderr)
        code = INTERRUPTED
    except Exception as err:
        from app.errors import interrupted

        if not interrupted(err):  # an interrupt inside a compiled kernel's call surfaces as a SystemError
            raise
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
    return _finish(code)


def _import_cli():
    """``app.cli.main``, imported with the signals that arrive meanwhile written down by CPython's C handler.

    A Ctrl-C that lands while an extension module's import runs its C code (NumPy's, when it imports
    ``datetime`` through a capsule) is turned by that code into an error of its own, an ImportError with no
    trace of the KeyboardInterrupt (seen once in about 1,140 CI tests: a traceback through Bosun's start-up).
    :func:`signal.set_wakeup_fd` makes the C-level handler write each signal's number to a pipe, with no
    Python frame involved; an error of the import with SIGINT or SIGTERM in the pipe is the interrupt."""
    import signal

    wanted = {int(signal.SIGINT), int(signal.SIGTERM)}
    read_fd, write_fd = os.pipe()
    os.set_blocking(read_fd, False)
    os.set_blocking(write_fd, False)
    previous = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
    try:
        from app.cli import main as cli_main

        return cli_main
    except Exception as err:
        try:
            arrived = set(os.read(read_fd, 512))
        except BlockingIOError:
            arrived = set()
        if arrived & wanted:
            raise KeyboardInterrupt from err
        raise
    finally:
        signal.set_wakeup_fd(previous)
        os.close(read_fd)
        os.close(write_fd)


def _finish(code: int) -> int:
    """Leave with ``code`` once the command is done, an interrupt still answered until the very end.

    The interpreter's own teardown clears its modules after it has put the default signal handlers back:
    a SIGTERM there (up to a second after a study printed its result, with Dask, numba and matplotlib
    loaded) killed the process with status −15 and no line (issue 27, item 10).  So the teardown's parts
    that matter run here, each interruptible with one line and status 130: other non-daemon threads are
    joined and the exit functions run (multiprocessing's, Dask's, logging's); then the process leaves
    without clearing modules (the operating system frees their memory; every file is closed and written)."""
    import atexit
    import signal
    import threading

    def stop_now(*_):
        sys.stdout.flush()
        print("bosun: interrupted", file=sys.stderr, flush=True)
        os._exit(INTERRUPTED)

    if threading.current_thread() is not threading.main_thread():
        return code
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, stop_now)
    for t in threading.enumerate():
        if t is not threading.current_thread() and not t.daemon:
            t.join()
    atexit._run_exitfuncs()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
