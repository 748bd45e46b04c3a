"""Error types for mistakes a user can make; each renders as one clear line."""

from __future__ import annotations

import sys
from typing import Any

#: Python functions that machine code calls back, (module file, function): numba's runtime unpickling of the objects
#: a kernel boxes (``numba_unpickle`` in numba's _helperlib.c calls it on every call that returns an array) and
#: llvmlite's object-cache callbacks (ctypes).  An exception raised inside one is not passed on: the caller goes on
#: with a NULL object and the process dies with SIGSEGV (numba issue #2324, "interrupting … sometimes gives a
#: segmentation fault"; here: ``sim tac`` interrupted while the Delta head's workspace was computed).
CALLBACKS = frozenset(
    {
        ("serialize.py", "_numba_unpickle"),
        ("executionengine.py", "_raw_object_cache_notify"),
        ("executionengine.py", "_raw_object_cache_getbuffer"),
    }
)


def inside_a_callback(frame: Any) -> bool:
    """True when ``frame`` or a caller of it is one of :data:`CALLBACKS`."""
    while frame is not None:
        code = frame.f_code
        if (code.co_filename.rsplit("/", 1)[-1], code.co_name) in CALLBACKS:
            return True
        frame = frame.f_back
    return False


class InterruptsDeferred:
    """SIGINT and SIGTERM held off on the main thread for a while, and raised again when it ends (re-entrant: the
    outermost :meth:`exit` raises them).  Used where an interrupt would leave something half done that cannot be
    undone (numba's compiler lock, safety H91; matplotlib's renderer, H94).  Another thread's use is a no-op
    (Python runs signal handlers on the main thread only)."""

    SIGNALS = ("SIGINT", "SIGTERM")

    def __init__(self) -> None:
        self._depth = 0
        self._saved: dict[int, Any] = {}
        self._noted: list[int] = []

    def _note(self, signum: int, _frame: Any) -> None:
        if signum not in self._noted:
            self._noted.append(signum)

    @staticmethod
    def _main() -> bool:
        import threading

        return threading.current_thread() is threading.main_thread()

    def enter(self) -> None:
        import signal

        if not self._main():
            return
        self._depth += 1
        if self._depth == 1:
            for name in self.SIGNALS:
                num = getattr(signal, name, None)
                previous = signal.getsignal(num) if num is not None else None
                if previous is not None:  # None: a handler set outside Python, left as it is
                    self._saved[num] = previous
                    signal.signal(num, self._note)

    def exit(self) -> None:
        import signal

        if not self._main() or self._depth == 0:
            return
        self._depth -= 1
        if self._depth == 0:
            saved, self._saved = self._saved, {}
            for num, handler in saved.items():
                signal.signal(num, handler)
            noted, self._noted = self._noted, []
            for num in noted:
                signal.raise_signal(num)  # its own handler runs now, at a safe point

    def __enter__(self) -> InterruptsDeferred:
        self.enter()
        return self

    def __exit__(self, *_: object) -> None:
        self.exit()


#: the process's one deferral (nested uses share its depth)
DEFERRED = InterruptsDeferred()


def _again_later(signum: int, delay: float = 0.01) -> None:
    """The signal ``signum`` pending again in ``delay`` seconds, from a helper thread: re-raised at once (by
    ``signal.raise_signal`` or ``_thread.interrupt_main``) its handler ran again right away, still inside the
    callback, until the recursion limit."""
    import _thread
    import threading

    timer = threading.Timer(delay, _thread.interrupt_main, args=(signum,))
    timer.daemon = True  # never keeps the process alive
    timer.start()


def raise_interrupt(signum: int | None = None, frame: Any = None) -> None:
    """The SIGINT and SIGTERM handler of the ``bosun`` command: the signal ends the program as Ctrl-C does (one
    line, status 130, a study's partial output removed).  Set by the entry point (app/launch.py) and by
    :func:`app.cli.main`.

    A signal that lands inside a callback from machine code (:data:`CALLBACKS`) is raised again instead, so
    the KeyboardInterrupt comes once the compiled code has returned to Python (safety H92)."""
    if signum is not None and inside_a_callback(frame):
        _again_later(signum)
        return
    raise KeyboardInterrupt


def keep_dropped_interrupts(unraisable: Any) -> None:
    """``sys.unraisablehook`` of the ``bosun`` command: a KeyboardInterrupt that Python had to drop (raised in a
    weakref callback, a ``__del__`` or a ctypes callback, where an exception cannot be passed on) is made pending
    again 10 ms later, so Ctrl-C is never lost (safety H93: a SIGINT that landed in matplotlib's weakref
    callback printed "Exception ignored" and the study ran to its end); anything else goes to Python's hook."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        import signal

        _again_later(int(signal.SIGINT))
        return
    sys.__unraisablehook__(unraisable)


def one_line(text: str, limit: int) -> str:
    """A message for one log or error line: whitespace runs (newlines too) as one space, at most
    ``limit`` characters (cut with "…")."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 1] + "…"


def printable(text: str, limit: int) -> str:
    """A name from outside (a client's, a file's) as it may appear in a line: every character that
    is not printable (newline, escape, …) shown as "?", at most ``limit`` characters."""
    return "".join(ch if ch.isprintable() else "?" for ch in str(text))[:limit]


def printable_path(text: str, limit: int) -> str:
    """:func:`printable` for a path: a long one loses its middle ("…"), never its end, so the line still
    names the file (a refusal that ended ".../outside/s" said nothing of which file it refused, and its
    length depended on the machine's temporary folder: issue 28)."""
    s = printable(text, len(str(text)))
    if len(s) <= limit:
        return s
    head = max(1, (limit - 1) // 3)
    return s[:head] + "…" + s[len(s) - (limit - 1 - head) :]


class BosunError(Exception):
    """Base class of user-facing errors: the CLI prints ``str(err)`` and exits 2."""


class MissingExtraError(BosunError):
    """A command needs an optional part of Bosun that is not installed (``pip install 'bosun[EXTRA]'``)."""

    def __init__(self, what: str, module: str, extra: str) -> None:
        self.module, self.extra = module, extra
        super().__init__(
            f"{what} needs {module}, which is not installed: pip install 'bosun[{extra}]' "
            "(scripts/setup.sh installs every extra)"
        )


def require(module: str, extra: str, what: str):
    """Import ``module`` for ``what``, or raise :class:`MissingExtraError` naming the extra to install."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingExtraError(what, module.split(".")[0], extra) from None


class RobotXmlError(BosunError):
    """A robot file that cannot be used: syntax, schema or a value out of range.

    Parameters
    ----------
    path : str
        The file (or ``"<string>"`` for text that came from no file).
    line : int or None
        1-based line of the offending element, when known.
    message : str
        What is wrong, naming the element and attribute.
    """

    def __init__(self, path: str, line: int | None, message: str) -> None:
        self.path = path
        self.line = line
        self.message = message = one_line(message, 300)  # one line: parser messages end in newlines
        where = f"{path}:{line}" if line else path
        super().__init__(f"{where}: {message}")


def error_line(err: BaseException, limit: int) -> str:
    """``str(err)`` as one line of at most ``limit`` characters that still names what it refused: a
    :class:`RobotXmlError`'s ``file:line`` is kept whole when it fits in half the line, else its path loses
    its middle (:func:`printable_path`), and the message is cut instead (cutting the whole line at its end
    dropped the line number, or the file name itself, of a refusal under a long path: issue 28)."""
    if isinstance(err, RobotXmlError):
        where = printable_path(err.path, max(20, limit // 2))
        if err.line:
            where += f":{err.line}"
        return f"{where}: {one_line(err.message, max(1, limit - len(where) - 2))}"
    return one_line(str(err), limit)


class RobotNotFoundError(BosunError):
    """A robot name or path that names no robot file."""


class RobotTypeError(BosunError):
    """A robot whose mechanism type has no model for the requested operation."""


class JointInputError(BosunError):
    """Joint values that do not fit the robot: wrong count or not finite."""


def shown(text: str, limit: int = 80) -> str:
    """A field from a file quoted for an error line so that what is in it is unambiguous: control characters
    (a TAB, a newline, …) as ``<TAB>``, ``<LF>``, ``<U+0007>``, a backslash as itself, at most ``limit``
    characters.  ``repr`` showed a real TAB as ``'hs\\tp'``, which reads as the backslash-t a user meant to
    type (issue 27, item 10)."""
    names = {"\t": "<TAB>", "\n": "<LF>", "\r": "<CR>", "\ufeff": "<BOM>"}
    out = "".join(names.get(ch, ch if ch.isprintable() else f"<U+{ord(ch):04X}>") for ch in str(text))
    if len(out) > limit:
        out = out[: limit - 1] + "…"
    return f"'{out}'"


def interrupted(exc: BaseException | None) -> bool:
    """True when ``exc`` is a KeyboardInterrupt or was raised while one was being handled or by one.

    Ctrl-C (or SIGTERM, which the CLI raises as KeyboardInterrupt) that lands while a compiled numba kernel
    boxes or unboxes its arguments in Python code surfaces as ``SystemError: CPUDispatcher(…) returned a
    result with an exception set``, the KeyboardInterrupt as its cause (issue 27, item 10)."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False
