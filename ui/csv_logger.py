"""CSV logging of engine states: chosen signals, a duration, no samples lost on close.

The writer is plain Python (no Qt); the GUI feeds it every state it receives.  Each row is
flushed as it is written, so a logger stopped or a GUI closed mid-run leaves a complete,
readable file of the rows so far.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path


def _names(s, names) -> list[str]:
    """Joint names from the engine's description, or q1…qn when it does not match this state's robot."""
    return list(names) if names is not None and len(names) == len(s.q) else [str(i + 1) for i in range(len(s.q))]


#: signal name -> (column names and values of a typed teleop snapshot, given the joint names)
SIGNALS = {
    "q": lambda s, names: [(f"q_{n}", v) for n, v in zip(_names(s, names), s.q, strict=True)],
    "qdot": lambda s, names: [(f"qdot_{n}", v) for n, v in zip(_names(s, names), s.qdot, strict=True)],
    "tool": lambda s, names: list(zip(("tool_x", "tool_y", "tool_z"), s.tool, strict=True)),
    "target": lambda s, names: list(zip(("target_x", "target_y", "target_z"), s.target, strict=True)),
    "signal": lambda s, names: list(zip(("s_x", "s_y", "s_z"), s.signal, strict=True)),
    "solver": lambda s, names: [("solver_error", s.solver_error), ("solver_time", s.solver_time)],
    "flags": lambda s, names: [
        ("estop", int(s.estop)),
        ("stale", int(s.flags.stale_input)),
        ("enabled", int(s.flags.enabled)),
    ],
}


class StateCsvLogger:
    """Write chosen signals of each state to ``path`` for ``duration`` seconds of engine time."""

    def __init__(self, path: str | Path, signals: list[str], duration: float | None = None, joint_names=None) -> None:
        unknown = [s for s in signals if s not in SIGNALS]
        if unknown or not signals:
            raise ValueError(f"unknown or no signals: {unknown or signals}; choose from {', '.join(SIGNALS)}")
        if duration is not None and not (duration > 0 and math.isfinite(duration)):
            raise ValueError("duration must be a positive number of seconds")
        self.path = Path(path)
        self.signals = list(signals)
        self.duration = duration
        self.joint_names = joint_names  # from the engine's description (column names)
        self.file = open(self.path, "w", newline="", buffering=1)  # noqa: SIM115 - kept open while logging
        self.writer = csv.writer(self.file)
        self.header: list[str] | None = None
        self.t0: float | None = None
        self.rows = 0
        self.done = False

    def add(self, state) -> bool:
        """Write one state; returns False once the duration is over (the file is then closed)."""
        if self.done:
            return False
        if self.t0 is None:
            self.t0 = state.t
        t = state.t - self.t0
        if self.duration is not None and t > self.duration:
            self.close()
            return False
        cols = [("t", t)] + [c for sig in self.signals for c in SIGNALS[sig](state, self.joint_names)]
        if self.header is None:
            self.header = [c[0] for c in cols]
            self.writer.writerow(self.header)
        elif [c[0] for c in cols] != self.header:
            self.close()  # the robot changed: a new file is needed for new columns
            return False
        self.writer.writerow(["" if v is None else (f"{v:.6g}" if isinstance(v, float) else v) for _, v in cols])
        self.file.flush()
        self.rows += 1
        return True

    def close(self) -> None:
        if not self.done:
            self.done = True
            self.file.close()
