"""Alarm rates of a scripted session against EEMUA 191's benchmarks (issue 26, acceptance).

Three engines (teleop, crane head, Motion-Lab) run as their own processes at their own rates, as the GUI
starts them.  One scripted operator per engine, over the protocol:

* teleop: the arm driven in velocity mode for 20 s of every minute (a slow circle), an IK study
  (error distribution, 8³ targets) at 1:30;
* crane head: compensation (``tac``) on from the start;
* Motion-Lab: both platforms raised to NEUTRAL, EM8000 in waves (its wave simulator), EM1500 following a
  generator, then VVMC on (Comau and winch in MOTION_COMP);
* two STOP/reset cycles (STOP to every engine, 10 s, reset, every mode chosen again).

Every alarm raised is recorded from the engines' state streams (and a state gap over 1 s as the GUI's
"engine lost").  EEMUA 191 (3rd ed., 2013, Table 9 / ISA-18.2 §16.5): steady operation at most 1 alarm per
10 minutes (``acceptable``), at most 10 alarms in the 10 minutes after an upset, and no alarm chattering
(3 or more activations of one alarm in a minute).  The E-STOPs the operator pressed are counted apart.
"""

from __future__ import annotations

import math
import socket
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field

from app.net.transport import Client, TransportError

STOPS_AT = (0.33, 0.67)  # of the session: the two STOP/reset cycles
STOP_HOLD_S = 10.0  # STOP held this long before the reset
UPSET_S = 600.0  # EEMUA: the 10 minutes after an upset
CHATTER_N, CHATTER_S = 3, 60.0


@dataclass
class Raised:
    t: float  # s from the session's start
    engine: str
    key: str
    severity: str
    text: str
    operator: bool = False  # caused by the operator (the E-STOP itself)


@dataclass
class Session:
    """What the run recorded."""

    seconds: float
    alarms: list[Raised] = field(default_factory=list)
    stops: list[tuple[float, float]] = field(default_factory=list)  # (STOP, reset) times
    gaps: dict[str, float] = field(default_factory=dict)  # the longest state gap per engine [s]
    realtime: dict[str, float] = field(default_factory=dict)  # the lowest real-time factor seen

    def report(self) -> dict:
        others = [a for a in self.alarms if not a.operator]
        in_upset = [any(s <= a.t <= r + 60.0 for s, r in self.stops) for a in others]
        steady = [a for a, u in zip(others, in_upset, strict=True) if not u]
        steady_s = self.seconds - sum(min(self.seconds, r + 60.0) - s for s, r in self.stops)
        after = []
        for s, _ in self.stops:
            after.append(sum(1 for a in others if s <= a.t < s + UPSET_S))
        chatter = {}
        for a in others:
            k = (a.engine, a.key)
            n = sum(1 for b in others if (b.engine, b.key) == k and a.t <= b.t < a.t + CHATTER_S)
            chatter[f"{a.engine}:{a.key}"] = max(chatter.get(f"{a.engine}:{a.key}", 0), n)
        return {
            "seconds": self.seconds,
            "operator_estops": sum(a.operator for a in self.alarms),
            "alarms_not_by_the_operator": len(others),
            "steady_alarms": len(steady),
            "steady_seconds": steady_s,
            "steady_per_10_min": 600.0 * len(steady) / steady_s if steady_s > 0 else math.nan,
            "after_each_upset_10_min": after,
            "chattering": sorted(k for k, n in chatter.items() if n >= CHATTER_N),
            "longest_state_gap_s": self.gaps,
            "lowest_realtime_factor": self.realtime,
            "alarms": [asdict(a) for a in self.alarms],
            "stops": self.stops,
        }


def _free_url() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp://127.0.0.1:{s.getsockname()[1]}"


class _Engine:
    def __init__(self, plant: str, seconds: float) -> None:
        self.plant = plant
        self.url = _free_url()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "app", "server", "--plant", plant, "--bind", self.url, "--duration",
             str(seconds + 120)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        self.op = None

    def connect(self) -> None:
        """The operator's client (the engines start first, all of them: the role lapses after 5 s of silence)."""
        deadline = time.monotonic() + 120
        while True:
            try:
                self.op = Client(self.url, role="operator", name=f"script-{self.plant}")
                break
            except TransportError:
                if time.monotonic() > deadline or self.proc.poll() is not None:
                    self.close()
                    raise
        self.seen: dict[str, tuple[float, int]] = {}
        self.last_state = time.monotonic()
        self.gap = 0.0
        self.realtime = 1.0
        self.state = None

    def poll(self, t0: float, out: list[Raised]) -> None:
        while (st := self.op.recv_state(0.001)) is not None:
            now = time.monotonic()
            self.gap = max(self.gap, now - self.last_state)
            if now - self.last_state > 1.0:
                text = f"no state for {now - self.last_state:.1f} s"
                out.append(Raised(now - t0, self.plant, "lost", "critical", text))
            self.last_state = now
            self.state = st
            if st.t > 5.0:  # its first seconds: the process starts (kernels load)
                self.realtime = min(self.realtime, st.engine.realtime_factor)
            for a in st.alarms:
                mark = (a.t_raised, a.count)
                if a.active and self.seen.get(a.key) != mark:
                    self.seen[a.key] = mark
                    out.append(Raised(now - t0, self.plant, a.key, a.severity, a.text, operator=a.key == "estop"))

    def send(self, mtype: str, **fields) -> None:
        try:
            self.op.request(mtype, **fields)
        except TransportError as err:
            print(f"  {self.plant}: {mtype} refused: {err}", file=sys.stderr)

    def close(self) -> None:
        op = getattr(self, "op", None)
        if op is not None:
            op.close()
        self.proc.terminate()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()


def _start_lab(lab: _Engine) -> None:
    for name in ("em8000", "em1500"):
        lab.send("lab_platform", platform=name, action="neutral")


def _engage_lab(lab: _Engine) -> None:
    lab.send("lab_source", platform="em8000", source="simulation", hs=2.0, tp=8.0, heading=150.0, seed=1)
    lab.send("lab_source", platform="em1500", source="generator", amplitude=[0, 0, 0.1, 0, 0, 0],
             frequency=[0.1] * 6, phase=[0.0] * 6)  # fmt: skip
    for name in ("em8000", "em1500"):
        lab.send("lab_platform", platform=name, action="engage")
    lab.send("lab_vvmc", on=True)


def run(minutes: float = 10.0, progress=None) -> Session:
    """The scripted session in real time; a :class:`Session` (``progress(done_s, total_s)`` each second)."""
    seconds = 60.0 * minutes
    engines = {}
    try:
        for plant in ("teleop", "tac", "lab"):
            engines[plant] = _Engine(plant, seconds)
        for e in engines.values():
            e.connect()
        tele, tac, lab = engines["teleop"], engines["tac"], engines["lab"]
        rec = Session(seconds)
        t0 = time.monotonic()
        for e in engines.values():
            e.last_state = t0
        tac.send("set_tac_mode", mode="tac")
        _start_lab(lab)
        stops = [f * seconds for f in STOPS_AT]
        stopped_at = None
        engaged = False
        armed = False
        study_started = False
        next_second = 1.0
        while (t := time.monotonic() - t0) < seconds:
            for e in engines.values():
                e.poll(t0, rec.alarms)
            if stopped_at is None and stops and t >= stops[0]:
                stops.pop(0)
                for e in engines.values():
                    e.op.send("estop", reason="scripted STOP")
                stopped_at = t
            elif stopped_at is not None and t >= stopped_at + STOP_HOLD_S:
                for e in engines.values():
                    e.send("reset")
                rec.stops.append((stopped_at, t))
                stopped_at, engaged, armed = None, False, False
                tac.send("set_tac_mode", mode="tac")
                _start_lab(lab)
            ready = lab.state is not None and all(p.status == "neutral" for p in lab.state.platforms)
            if stopped_at is None and not engaged and ready:
                _engage_lab(lab)
                engaged = True
            if not study_started and t >= 90.0:
                tele.send("study_start", study="distribution", grid=8)
                study_started = True
            # the teleop operator: drives a slow circle for 20 s of every minute, else lets go
            phase = t % 60.0
            driving = stopped_at is None and 20.0 <= phase < 40.0
            if driving and not armed:
                for pressed in (False, True):
                    tele.op.send_input([0.0, 0.0, 0.0], [pressed], "script")
                    time.sleep(0.01)
                armed = True
            if driving:
                w = 2 * math.pi * phase / 20.0
                tele.op.send_input([0.6 * math.cos(w), 0.6 * math.sin(w), 0.0], [True], "script")
            else:
                armed = False
                tele.op.send_input([0.0, 0.0, 0.0], [False], "script")
            for e in (tac, lab):
                e.op.send("ping")
            if t >= next_second:
                next_second += 1.0
                if progress is not None:
                    progress(min(t, seconds), seconds)
            time.sleep(0.02)
        rec.gaps = {p: e.gap for p, e in engines.items()}
        rec.realtime = {p: e.realtime for p, e in engines.items()}
        return rec
    finally:
        for e in engines.values():
            e.close()
