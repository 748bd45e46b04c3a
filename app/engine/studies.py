"""IK studies (error distribution, trajectory tracking) in a worker process the engine owns.

A study solves hundreds of targets and takes seconds to minutes: in the engine's process it would
take the interpreter lock from the control loop.  The teleop scene starts one worker process per
study (``spawn``: nothing of the engine is inherited but the robot file's text, the solver name
and the grid), reads its progress from a queue when it publishes state, and hands the result to
the server as a ``study`` message.  One study at a time; ``cancel`` keeps the targets done so far.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import queue
import time
from typing import Any

from app.errors import BosunError, error_line, one_line

STUDIES = ("distribution", "tracking")
PROGRESS_EVERY = 0.1  # s: the worker reports progress at most this often
STUDY_NICE = 10  # the worker's scheduling priority below the engines' (background work)


class StudyError(BosunError):
    """A study that cannot start (another runs, unknown kind)."""


def _work(kind: str, xml: str, label: str, solver: str, grid: int, out, cancel) -> None:
    """The worker process: parse the robot, run the study, put progress and the result on ``out``.

    It runs at a lower scheduling priority (nice +10): a study is background work, and on a machine with
    fewer cores than busy processes it took the CPU from the engines' control loops and state streams
    (issue 26, item 9: a teleop study held the crane-head and lab engines' states back for up to a second,
    and the GUI called the engines lost)."""
    with contextlib.suppress(OSError, AttributeError):
        os.nice(STUDY_NICE)
    try:
        from app.analysis.ik_studies import error_distribution, track
        from app.models.registry import load_robot_text

        robot = load_robot_text(xml, label)
        last = [0.0]

        def progress(done: int, total: int) -> None:
            now = time.monotonic()
            if now - last[0] >= PROGRESS_EVERY or done == total:
                last[0] = now
                out.put(("progress", done, total))

        hooks = {"progress": progress, "cancelled": cancel.is_set}
        if kind == "distribution":
            result = error_distribution(robot, solver, grid, **hooks)
        else:
            result = track(robot, solver, **hooks)
        out.put(("done", result.to_wire()))
    except (BosunError, ValueError) as err:
        out.put(("failed", error_line(err, 300)))
    except Exception as err:  # a bug: say which, never a silent worker
        out.put(("failed", f"internal error ({type(err).__name__}: {one_line(str(err), 200)})"))


class StudyRunner:
    """One study at a time in a worker process; :meth:`poll` returns the ``study`` messages to publish."""

    def __init__(self) -> None:
        self.ctx = mp.get_context("spawn")
        self.proc = None
        self.out = None
        self.cancel_event = None
        self.seq = 0
        self.state: dict[str, Any] = {"id": 0, "kind": "", "status": "idle", "done": 0, "total": 0, "error": ""}

    @property
    def running(self) -> bool:
        return self.state["status"] == "running"

    def start(self, kind: str, xml: str, label: str, solver: str, grid: int) -> int:
        if kind not in STUDIES:
            raise StudyError(f"unknown study {kind!r} (studies: {', '.join(STUDIES)})")
        if self.running:
            raise StudyError(f"a {self.state['kind']} study is running; cancel it first")
        if not 2 <= grid <= 40:
            raise StudyError(f"grid must be between 2 and 40, got {grid}")
        self.close()
        self.seq += 1
        self.out = self.ctx.Queue()
        self.cancel_event = self.ctx.Event()
        self.proc = self.ctx.Process(
            target=_work,
            args=(kind, xml, label, solver, grid, self.out, self.cancel_event),
            name=f"bosun-study-{self.seq}",
            daemon=True,
        )
        self.proc.start()
        self.state = {"id": self.seq, "kind": kind, "status": "running", "done": 0, "total": 0, "error": ""}
        return self.seq

    def cancel(self) -> None:
        if self.running and self.cancel_event is not None:
            self.cancel_event.set()

    def poll(self) -> list[dict[str, Any]]:
        """Progress and results that arrived (cheap when nothing did); the messages to publish."""
        if not self.running or self.out is None:
            return []
        msgs = []
        while True:
            try:
                item = self.out.get_nowait()
            except queue.Empty:
                break
            except (OSError, EOFError, ValueError):  # the queue's pipe closed under us
                item = ("failed", "the study worker ended without a result")
            if item[0] == "progress":
                self.state.update(done=item[1], total=item[2])
                msgs.append(dict(self.state))
            elif item[0] == "done":
                result = item[1]
                n = len(result.get("error", result.get("t", [])))
                status = "done" if result.get("complete", True) else "cancelled"
                self.state.update(status=status, done=n, total=max(self.state["total"], n))
                msgs.append({**self.state, "result": result})
                break
            else:
                self.state.update(status="failed", error=item[1])
                msgs.append(dict(self.state))
                break
        if self.running and self.proc is not None and not self.proc.is_alive() and self.out.empty():
            code = self.proc.exitcode
            self.state.update(status="failed", error=f"the study worker exited (code {code}) without a result")
            msgs.append(dict(self.state))
        return msgs

    def close(self) -> None:
        """End the worker (if any) and free its queue."""
        if self.proc is not None:
            if self.proc.is_alive():
                if self.cancel_event is not None:
                    self.cancel_event.set()
                self.proc.join(timeout=0.5)
                if self.proc.is_alive():
                    self.proc.terminate()
                    self.proc.join(timeout=2)
            self.proc = None
        if self.out is not None:
            self.out.close()
            self.out.join_thread()
            self.out = None
