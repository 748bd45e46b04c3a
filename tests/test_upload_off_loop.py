"""Issue 27, item 2: a large valid RAO upload never stops the control loop.

A 780 × 72 table (3.8 MB, 64 ``set_vessel`` parts, within every limit) was parsed and the crane-head scene
rebuilt inside the tick: the crane-head and lab loops stood for 0.61 s (seconds on a busy machine), a
viewer's STOP sent meanwhile latched after 509–511 ms, and ``late_fraction`` said 0.03.  Now the parse and
the build run off the loop (:mod:`app.engine.jobs`, paced by the server's I/O window) and the result is
swapped in at a tick boundary; the longest tick of each second is in the state (``max_tick_ms``) and a
tick longer than ten periods raises ``loop_stall``.  Bounds are generous (a busy 2-core CI machine): the
figures are in the commit and the README's benchmarks, not asserted here.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest

from app.engine.lab_session import LabSession
from app.engine.server import STALL_MIN_S, EngineServer
from app.engine.session import Session
from app.engine.tac_session import TacSession
from app.marine.vessel import CSV_COLUMNS, load_rao_csv, parametric_rao, rao_to_csv
from app.net.transport import Client, TransportError

N_W, N_HEADINGS, PARTS, PART_MAX = 780, 72, 64, 60_000  # the table; the protocol's limits


@pytest.fixture(scope="module")
def big_table() -> str:
    """The issue's table: 780 frequencies × 72 headings of a parametric vessel, about 3.6 MB of CSV."""
    t = parametric_rao(w=np.linspace(0.05, 3.0, N_W), headings_deg=np.arange(0, 360, 360 / N_HEADINGS))
    cols = [np.repeat(t.w, N_HEADINGS), np.tile(np.rad2deg(t.headings), N_W)]
    for d in range(6):
        cols += [np.round(t.amp[d].ravel(), 5), np.round(t.phase[d].ravel(), 3)]
    rows = np.column_stack(cols).tolist()
    text = ",".join(CSV_COLUMNS) + "\n" + "".join(",".join(f"{v:g}" for v in r) + "\n" for r in rows)
    assert 3.0e6 < len(text) <= PARTS * PART_MAX
    return text


def _parts(text: str) -> list[str]:
    size = math.ceil(len(text) / PARTS)
    parts = [text[i : i + size] for i in range(0, len(text), size)]
    assert len(parts) == PARTS and max(map(len, parts)) <= PART_MAX
    return parts


def _small_table(n: int = 12) -> str:
    return rao_to_csv(parametric_rao(w=np.linspace(0.1, 3.0, n), headings_deg=np.arange(0, 360, 30)))


def _until(what, timeout: float = 60.0, keep=None) -> None:
    """Wait for ``what()``; ``keep()`` every 0.2 s meanwhile (an operator's ping: the role must not lapse)."""
    end, last = time.monotonic() + timeout, 0.0
    while not what():
        assert time.monotonic() < end, "timed out"
        if keep is not None and time.monotonic() - last > 0.2:
            keep()
            last = time.monotonic()
        time.sleep(0.01)


# ----------------------------------------------------------------------------- the case, end to end
@pytest.mark.slow
@pytest.mark.parametrize("scene", ["tac", "lab"])
def test_a_large_upload_holds_up_neither_the_loop_nor_a_stop(serve, big_table, scene):
    """The 780 × 72 table in 64 parts to a 50 Hz engine; a viewer's STOP the moment the loop takes the last
    part.  No tick spends more than 0.1 s of the loop's CPU (the old loop spent the whole parse in one);
    the STOP latches (14-35 ms measured; the old loop: after the parse, 0.5 s on the issue's machine, seconds
    here; the bound is 2 s so that a busy machine's scheduler does not fail it); the table is taken, the
    reply says so, and the swap leaves the STOP latched."""
    last_part = threading.Event()

    class Watched(TacSession if scene == "tac" else LabSession):
        def set_vessel(self, **fields):  # an override runs as the command (the scene's table takes it)
            if fields.get("part") == PARTS - 1:
                last_part.set()
            return super().set_vessel(**fields)

    ses = Watched()
    srv, _ = serve(ses, rate=50)
    ticks: list[tuple[float, float]] = []  # (wall, loop-thread CPU) of each tick
    step = srv.step

    def timed(now: float) -> None:
        w0, c0 = time.perf_counter(), time.thread_time()
        step(now)
        ticks.append((time.perf_counter() - w0, time.thread_time() - c0))

    srv.step = timed
    latched: list[float] = []
    estop = ses.estop

    def recording_estop(source: str = "operator") -> None:
        latched.append(time.monotonic())
        estop(source)

    ses.estop = recording_estop
    op = Client(srv.url, role="operator", name="op", timeout=20.0)
    viewer = Client(srv.url, role="viewer", name="viewer", timeout=20.0)
    try:
        _until(lambda: srv.stats.ticks > 50, keep=lambda: op.send("ping"))  # started (and compiled)
        n0 = len(ticks)
        for k, part in enumerate(_parts(big_table)):
            op.send("set_vessel", csv=part, part=k, parts=PARTS, label="big.csv")
        assert last_part.wait(30.0)
        sent = time.monotonic()
        viewer.send("estop", reason="during the upload")
        _until(lambda: bool(latched), timeout=30.0)
        latency = latched[0] - sent
        _until(lambda: "big.csv" in ses.vessel.label, timeout=120.0, keep=lambda: op.send("ping"))
        time.sleep(0.2)
        episode = ticks[n0:]
        # the defect, measured so that a busy machine does not change it: the loop thread's own CPU in a tick
        # (the old loop spent the whole parse, 0.6-1.5 s, in one tick)
        assert max(c for _, c in episode) < 0.1, f"a tick spent {max(c for _, c in episode):.2f} s of CPU"
        # wall-clock figures (14-35 ms and ticks of 5-13 ms on an idle 2-core VM; a CI run beside other jobs at
        # load 12 saw the scheduler hold the loop for longer): bounds only against a gross stall
        assert latency < 2.0, f"STOP latched {1e3 * latency:.0f} ms after it was sent"
        assert max(w for w, _ in episode) < 2.0, f"a tick lasted {max(w for w, _ in episode):.2f} s"
        assert ses.estop_latched, "the swap undid the STOP"
        table = ses.sim.vessel_rao if scene == "tac" else ses.plant._rao
        assert table.amp.shape == (6, N_W, N_HEADINGS)
        assert ses.describe().vessel == "RAO file big.csv"
    finally:
        op.close()
        viewer.close()


def test_the_reply_comes_when_the_table_is_taken_and_a_bad_one_is_refused_in_one_line(serve):
    """Over the protocol: a table's last part is answered once the table has been swapped in (a client that
    asks ``describe`` after the reply sees it), a table that does not parse with its line, the scene unchanged."""
    ses = LabSession()
    srv, _ = serve(ses, rate=50)
    op = Client(srv.url, role="operator", name="op", timeout=20.0)
    try:
        op.request("set_vessel", csv=_small_table(), label="mine.csv")
        assert op.describe().vessel == "RAO file mine.csv"
        bad = "\n".join(_small_table().splitlines()[:3]) + "\n1,2\n"
        with pytest.raises(TransportError, match=r"^bad.csv:4: expected 14 fields, got 2$"):
            op.request("set_vessel", csv=bad, label="bad.csv")
        assert op.describe().vessel == "RAO file mine.csv"
    finally:
        op.close()


# ----------------------------------------------------------------------------- max_tick_ms and loop_stall
@pytest.mark.slow
def test_a_long_tick_is_reported_whole_and_raises_loop_stall(serve):
    """A tick held up 0.4 s (injected) at 50 Hz: one late tick of fifty in ``late_fraction``, but the state's
    ``max_tick_ms`` reports it whole and ``loop_stall`` is raised, and stays through its off-delay."""
    ses = TacSession()
    srv, _ = serve(ses, rate=50)
    tick = ses.tick
    hold = threading.Event()

    def slow_tick(now, dt, solve_budget=None):
        if hold.is_set():
            hold.clear()
            time.sleep(0.4)
        tick(now, dt, solve_budget)

    ses.tick = slow_tick
    viewer = Client(srv.url, role="viewer", name="viewer", timeout=20.0)
    try:
        _until(lambda: srv.stats.ticks > 100)
        hold.set()
        deadline, st = time.monotonic() + 30.0, None
        while time.monotonic() < deadline:
            st = viewer.recv_state(1.0)
            if st is not None and st.engine.max_tick_ms >= 380:
                break
        assert st is not None and st.engine.max_tick_ms >= 380, st and st.engine
        _until(lambda: ses.alarms.active("loop_stall"), timeout=10.0)
        a = ses.alarms.items["loop_stall"]
        assert a.severity == "warning" and "control loop stalled: a tick took" in a.text
        time.sleep(2.5)
        assert ses.alarms.active("loop_stall") and srv.max_tick < 0.38  # the off-delay; the figure moved on
    finally:
        viewer.close()


@pytest.mark.parametrize("rate", [50.0, 1000.0])
def test_loop_stall_takes_ten_periods_and_a_tenth_of_a_second_and_does_not_chatter(rate):
    """Health seconds made by hand: an idle second raises nothing; at 1 kHz a 15 ms hiccup (15 periods, a busy
    computer's scheduler) is not a stall; a tick over ten periods and 0.1 s is, once; the alarm clears only
    after 30 s without one, and a stall within them does not raise it again."""
    ses = Session()
    srv = EngineServer(ses, bind="tcp://127.0.0.1:0", rate=rate)
    try:
        now = 1000.0
        srv._second = (now, 0, 0)

        def second(longest: float) -> None:
            nonlocal now
            now += 1.0
            srv.stats.ticks += round(rate)
            srv._longest = longest
            srv._health(now)

        for _ in range(5):
            second(1.2 / rate)
        assert srv.max_tick == pytest.approx(1.2 / rate)
        second(0.015)
        assert ses.alarms.raised == 0
        limit = max(10 / rate, STALL_MIN_S)
        second(0.9 * limit)
        assert ses.alarms.raised == 0
        second(1.5 * limit)
        assert ses.alarms.active("loop_stall") and ses.alarms.raised == 1
        assert f"a tick took {1e3 * 1.5 * limit:.0f} ms" in ses.alarms.items["loop_stall"].text
        for _ in range(20):
            second(1.0 / rate)
        second(2 * limit)  # within the off-delay: still the one alarm
        for _ in range(29):
            second(1.0 / rate)
        assert ses.alarms.active("loop_stall") and ses.alarms.raised == 1
        for _ in range(3):
            second(1.0 / rate)
        assert not ses.alarms.active("loop_stall") and ses.alarms.raised == 1
    finally:
        srv.close()


# ----------------------------------------------------------------------------- the jobs, tick by tick
def _gated(ses) -> threading.Event:
    """The scene's jobs paced by a gate the test opens (the server's pace is its I/O window)."""
    gate = threading.Event()
    ses.jobs.pace = gate.wait
    return gate


def _answers(ses, n: int = 1, timeout: float = 60.0) -> list[tuple[int, str]]:
    """The loop's side: poll at tick boundaries until ``n`` answers are there."""
    got: list[tuple[int, str]] = []

    def done() -> bool:
        ses.jobs.poll()
        while ses.jobs.answers:
            got.append(ses.jobs.answers.popleft())
        return len(got) >= n

    _until(done, timeout)
    return got


def _tick(ses, n: int = 5) -> None:
    for _ in range(n):
        ses.tick(time.monotonic(), 0.02)


def test_a_stop_or_reset_during_a_pending_build_stands_after_the_swap():
    ses = TacSession()
    gate = _gated(ses)
    ses.set_tac_mode("tac")
    _tick(ses)
    before = ses.sim
    d = ses.set_vessel(csv=_small_table(), label="a.csv")
    assert ses.jobs.pending == "set_vessel a.csv" and ses.sim is before and ses.vessel.label != "RAO file a.csv"
    ses.estop("the test")
    _tick(ses)
    k = ses.sim.k
    gate.set()
    assert _answers(ses) == [(d.ticket, "")]
    assert ses.sim is not before and ses.sim.k == k and ses.vessel.label == "RAO file a.csv"
    assert ses.sim.vessel_rao is ses.vessel.table
    assert ses.estop_latched, "the swap undid the STOP"
    gate.clear()
    d = ses.set_vessel(csv=_small_table(14), label="b.csv")
    ses.reset()  # during the build: the machine holds until a mode is chosen
    alpha = ses.sim.head_servo.alpha.copy()
    gate.set()
    assert _answers(ses) == [(d.ticket, "")]
    _tick(ses, 20)
    assert not ses.estop_latched and ses.holding and ses.vessel.label == "RAO file b.csv"
    np.testing.assert_array_equal(ses.sim.head_servo.alpha, alpha)  # nothing moved without a command


def test_a_second_upload_or_a_named_vessel_supersedes_a_pending_one():
    ses = TacSession()
    gate = _gated(ses)
    first = ses.set_vessel(csv=_small_table(), label="a.csv")
    second = ses.set_vessel(csv=_small_table(14), label="b.csv")
    gate.set()
    got = _answers(ses, 2)
    assert got[0][0] == first.ticket and got[0][1].startswith("set_vessel a.csv: superseded by set_vessel b.csv")
    assert got[1] == (second.ticket, "")
    assert ses.vessel.label == "RAO file b.csv" and ses.sim.vessel_rao.w.size == 14
    gate.clear()
    third = ses.set_vessel(csv=_small_table(), label="c.csv")
    ses.set_vessel(vessel="supply-closed-form")  # decided now: the pending table must not undo it later
    gate.set()
    got = _answers(ses)
    assert got[0][0] == third.ticket and "superseded by set_vessel supply-closed-form" in got[0][1]
    time.sleep(0.2)
    ses.jobs.poll()
    assert not ses.jobs.answers and ses.vessel.table is None and ses.vessel.label.startswith("supply-closed-form")


def test_a_failed_build_is_refused_in_one_line_and_leaves_the_scene():
    ses = TacSession()
    gate = _gated(ses)
    gate.set()
    before, label = ses.sim, ses.vessel.label
    bad = "\n".join(_small_table().splitlines()[:3]) + "\n1,2\n"
    d = ses.set_vessel(csv=bad, label="bad.csv")
    [(ticket, error)] = _answers(ses)
    assert ticket == d.ticket and error == "bad.csv:4: expected 14 fields, got 2"
    assert ses.sim is before and ses.vessel.label == label


def test_a_sea_or_mode_changed_during_the_build_is_kept_by_the_swap():
    """The simulator is built for the scenario of its command; a mode switched meanwhile is the running one's,
    a new sea makes the swap rebuild on the parsed table (as set_sea does).  Either way the vessel is the new
    table, scene time runs on, and the arms move within their speed (test_rebuild_continuity holds the fade)."""
    ses = TacSession()
    gate = _gated(ses)
    ses.set_tac_mode("tac")
    _tick(ses)
    d = ses.set_vessel(csv=_small_table(), label="a.csv")
    ses.set_tac_mode("cooperative")
    gate.set()
    assert _answers(ses) == [(d.ticket, "")]
    assert ses.sim.scenario.mode == "cooperative" and ses.mode == "cooperative"
    gate.clear()
    d = ses.set_vessel(csv=_small_table(14), label="b.csv")
    ses.set_sea("jonswap", 2.0, 7.0, 150.0)
    gate.set()
    assert _answers(ses) == [(d.ticket, "")]
    assert ses.sim.scenario.hs == 2.0 and ses.sim.scenario.heading == 150.0
    assert ses.sim.vessel_rao is ses.vessel.table and ses.vessel.table.w.size == 14
    t0 = ses.last["t"]
    _tick(ses, 10)
    assert ses.last["t"] > t0


def test_the_lab_takes_a_table_off_the_loop_and_keeps_its_stop():
    ses = LabSession()
    gate = _gated(ses)
    d = ses.set_vessel(csv=_small_table(), label="mine.csv")
    ses.estop("the test")
    assert ses.plant._rao is None and ses.vessel.label != "RAO file mine.csv"
    gate.set()
    assert _answers(ses) == [(d.ticket, "")]
    assert ses.plant._rao is ses.vessel.table and ses.describe().vessel == "RAO file mine.csv" and ses.estop_latched


# ----------------------------------------------------------------------------- the parser's steps
def test_the_parser_paces_in_small_steps_and_stops_when_told(big_table):
    """The megabyte parse comes in small steps (no single step holds the interpreter for long: the old parse
    had single calls of 20–200 ms), and a pace that raises stops it (a superseded job)."""
    gaps: list[float] = []
    last = [time.thread_time()]

    def pace() -> None:
        now = time.thread_time()
        gaps.append(now - last[0])
        last[0] = now

    table = load_rao_csv(big_table, "big.csv", pace=pace)
    assert table.amp.shape == (6, N_W, N_HEADINGS) and len(gaps) > 1000
    assert max(gaps) < 0.05, f"a step of {1e3 * max(gaps):.0f} ms CPU (step {int(np.argmax(gaps))} of {len(gaps)})"

    class StopError(Exception):
        pass

    calls = [0]

    def stop_soon() -> None:
        calls[0] += 1
        if calls[0] == 10:
            raise StopError

    with pytest.raises(StopError):
        load_rao_csv(big_table, "big.csv", pace=stop_soon)
    assert calls[0] == 10
