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
        self.file = open(self.path, "w", encoding="utf-8", newline="", buffering=1)  # noqa: SIM115 - kept open while logging
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


# ---------------------------------------------------------------------------------------------- Motion-Lab
#: the lab HMI's CSV logger takes 1 to 1200 s (motionlab_plc.json ``hmi_tabs``: Norwegian Motion-Laboratory
#: repository, commit f5fbf84, MIT)
LAB_DURATION_RANGE = (1.0, 1200.0)
_ETA = ("x_m", "y_m", "z_m", "phi_rad", "theta_rad", "psi_rad")
#: the Motion-Lab logger's columns: time since the start and the engine's, both platforms' η (platform frames,
#: z down), the Comau's q, the winch's wire, the load's swing (eqs. 29-30), tool − work point in EM1500's frame
LAB_LOG_COLUMNS = (
    "t_s",
    "engine_t_s",
    *(f"em8000_{c}" for c in _ETA),
    *(f"em1500_{c}" for c in _ETA),
    "q1_rad",
    "q2_rad",
    "q3_rad",
    "wire_m",
    "swing_alpha_rad",
    "swing_beta_rad",
    "swing_rad",
    "vvmc_err_x_m",
    "vvmc_err_y_m",
    "vvmc_err_z_m",
    "vvmc",
    "estop",
)


class LabCsvLogger:
    """Every published Motion-Lab state to ``path`` for ``duration`` seconds of engine time (issue 16, item 5:
    the lab HMI's CSV logger with its file, duration, progress and sample count).

    Rows are flushed as written (a logger stopped, an engine lost or a GUI closed mid-run leaves a complete
    file of the rows so far).  States of a paused engine (its time stands still) add no rows; a state whose
    time runs backwards (another engine on the link) ends the log.  ``reason`` says why it ended.
    """

    def __init__(self, path: str | Path, duration: float) -> None:
        lo, hi = LAB_DURATION_RANGE
        if not (math.isfinite(duration) and lo <= duration <= hi):
            raise ValueError(f"duration must be {lo:g} to {hi:g} s, got {duration:g}")
        self.path = Path(path)
        self.duration = float(duration)
        self.file = open(self.path, "w", encoding="utf-8", newline="", buffering=1)  # noqa: SIM115 - kept open while logging
        self.writer = csv.writer(self.file)
        self.writer.writerow(LAB_LOG_COLUMNS)
        self.t0: float | None = None
        self.t_last: float | None = None
        self.rows = 0
        self.done = False
        self.reason = ""

    @property
    def elapsed(self) -> float:
        return 0.0 if self.t0 is None or self.t_last is None else self.t_last - self.t0

    @property
    def progress(self) -> float:
        """0…1 of the duration (1 once it is reached, as the log ends there)."""
        return 1.0 if self.elapsed >= self.duration - 1e-9 else self.elapsed / self.duration

    def add(self, state) -> bool:
        """Write one lab state; False once the log has ended (the file is then closed)."""
        if self.done:
            return False
        if getattr(state, "kind", None) != "lab" or len(state.platforms) < 2 or state.comau is None:
            return True
        t = float(state.t)
        if self.t_last is not None and t < self.t_last - 1e-9:
            self.close("the engine's time went back (another engine)")
            return False
        if self.t_last is not None and t <= self.t_last:
            return True  # paused (time stands still) or a state seen before
        if self.t0 is None:
            self.t0 = t
        if t - self.t0 > self.duration + 1e-9:
            self.close("duration reached")
            return False
        pend, w = state.pendulum, state.winch
        row = [t - self.t0, t, *state.platforms[0].eta, *state.platforms[1].eta, *state.comau.q[:3]]
        row += [w.length if w is not None else math.nan]
        row += [pend.alpha, pend.beta, pend.swing] if pend is not None else [math.nan] * 3
        err = list(state.tool_error_b2) if len(state.tool_error_b2) == 3 else [math.nan] * 3
        row += [*err, int(state.vvmc), int(state.estop)]
        self.writer.writerow([f"{v:.9g}" if isinstance(v, float) else v for v in row])
        self.rows += 1
        self.t_last = t
        if t - self.t0 >= self.duration - 1e-9:
            self.close("duration reached")
            return False
        return True

    def close(self, reason: str = "stopped") -> None:
        if not self.done:
            self.done = True
            self.reason = reason
            self.file.close()
