"""Heavy command work off the control loop (issue 27, item 2): a scene's job runs in a thread of its own and
its result is swapped in at a tick boundary.

A 780 × 72 RAO table (3.8 MB in 64 ``set_vessel`` parts) parsed and built inside the tick stopped the
crane-head and lab loops for 0.6 s (seconds on a busy machine): a STOP sent meanwhile latched only after
it.  Now the command that completes such a table only starts a :class:`Jobs` job and its reply waits
(:class:`Deferred`); the work runs in a thread that calls ``pace`` between small steps.  The server's
``pace`` is its I/O window: the thread takes a step only while the loop sleeps (unlike the I/O thread,
never while a tick runs, however long), so the ticks keep their time and an E-STOP its latency.  The loop
then, at the start of a tick (after the E-STOPs and commands that came in), takes what finished
(:meth:`Jobs.poll`): the job's ``apply`` runs there, on the loop's thread, and is cheap (a swap of
prepared state); the deferred reply goes out with it.

One job at a time: a new one supersedes the one pending (its reply: refused, superseded; its thread stops
at its next ``pace``), and so does any command that decides the same thing at once (:meth:`Jobs.supersede`).
A job that fails is refused in one line and changes nothing.  Without a ``pace`` (a scene used on its own,
by a script or a test) there are no jobs: scenes do the work in the command, as before.
"""

from __future__ import annotations

import itertools
import logging
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from app.errors import BosunError, error_line

log = logging.getLogger("bosun.engine")


@dataclass(frozen=True)
class Deferred:
    """A command's reply comes later: ``(ticket, error)`` in :attr:`Jobs.answers` when its job is done
    (``error`` "" when it succeeded)."""

    ticket: int
    what: str = ""


class SupersededError(Exception):
    """Raised by a job's ``step`` once a newer job or command has taken its place: the thread stops there."""


@dataclass
class _Job:
    ticket: int
    what: str
    apply: Callable[[Any], None]
    cancelled: threading.Event
    result: Any = None
    error: str | None = None  # None: still running; "" done; else the one-line refusal
    thread: threading.Thread | None = None


class Jobs:
    """A scene's work off the loop (see the module text).  ``pace``: set by the server; None runs nothing here."""

    def __init__(self) -> None:
        self.pace: Callable[[], None] | None = None
        self.answers: deque[tuple[int, str]] = deque()  # (ticket, error) of finished commands, for the server
        self._tickets = itertools.count(1)
        self._lock = threading.Lock()
        self._pending: _Job | None = None
        self._finished: list[_Job] = []

    @property
    def background(self) -> bool:
        """Whether heavy work goes to a job (a server runs the scene) or happens in the command."""
        return self.pace is not None

    @property
    def pending(self) -> str:
        """What the pending job does ("" when none)."""
        job = self._pending
        return job.what if job is not None else ""

    def start(self, what: str, work: Callable[[Callable[[], None]], Any], apply: Callable[[Any], None]) -> Deferred:
        """Run ``work(step)`` in a thread (``step()`` between small pieces of it: it waits for the loop's idle
        time and raises :class:`SupersededError` once the job is superseded); ``apply(result)`` then runs on the
        loop's thread at a tick boundary (:meth:`poll`).  ``work`` and ``apply`` raise
        :class:`~app.errors.BosunError` to refuse.  A pending job is superseded."""
        if self.pace is None:
            raise RuntimeError("Jobs.start needs a pace (the server's); without one do the work in the command")
        self.supersede(what)
        job = _Job(next(self._tickets), what, apply, threading.Event())
        job.thread = threading.Thread(target=self._run, args=(job, work), name=f"bosun-job-{job.ticket}", daemon=True)
        with self._lock:
            self._pending = job
        job.thread.start()
        return Deferred(job.ticket, what)

    def supersede(self, by: str) -> None:
        """The pending job (if any, also one finished but not yet applied) is no longer wanted: ``by`` decided the
        same thing later.  Its reply is a refusal that says so; its thread stops at its next step."""
        with self._lock:
            gone = [*self._finished, *([self._pending] if self._pending is not None else [])]
            self._pending, self._finished = None, []  # also one done but not yet applied: the later choice holds
        for job in gone:
            job.cancelled.set()
            self.answers.append((job.ticket, f"{job.what}: superseded by {by} (nothing of it taken)"))

    def _run(self, job: _Job, work: Callable[[Callable[[], None]], Any]) -> None:
        # not niced below the loop: the thread takes turns with it on the interpreter lock, and a thread the
        # scheduler passes over while it holds the lock holds the loop up (priority inversion: ticks of 0.8 s)
        pace = self.pace

        def step() -> None:
            if job.cancelled.is_set():
                raise SupersededError
            if pace is not None:
                pace()
            if job.cancelled.is_set():
                raise SupersededError

        try:
            result, error = work(step), ""
        except SupersededError:
            return
        except BosunError as err:
            result, error = None, error_line(err, 500) or type(err).__name__
        except Exception as err:  # a bug: refused in one line, logged, the scene unchanged
            log.exception("%s failed", job.what)
            result, error = None, f"refused: internal error ({type(err).__name__})"
        with self._lock:
            if self._pending is not job:  # superseded while it finished: already answered
                return
            self._pending = None
            job.result, job.error = result, error
            self._finished.append(job)

    def poll(self) -> None:
        """On the loop's thread, at a tick boundary: apply what finished; its answer goes to :attr:`answers`."""
        if not self._finished:
            return
        with self._lock:
            done, self._finished = self._finished, []
        for job in done:
            error = job.error or ""
            if not error:
                try:
                    job.apply(job.result)
                except BosunError as err:
                    error = error_line(err, 500) or type(err).__name__
                except Exception as err:  # a bug in a swap: refused, logged; the loop goes on
                    log.exception("%s: applying its result failed", job.what)
                    error = f"refused: internal error ({type(err).__name__})"
            self.answers.append((job.ticket, error))

    def close(self) -> None:
        """Stop the pending job (the engine is closing)."""
        with self._lock:
            job, self._pending = self._pending, None
        if job is not None:
            job.cancelled.set()
