"""An engine session on record (issue 32, item 6, first part): ``bosun server --record FILE.mcap`` writes an MCAP
file the ``mcap`` reader opens, with JSON schemas on every channel, holding every tick, input, command and E-STOP
the loop applied and every state it published — the states a viewer received, equal."""

from __future__ import annotations

import json
import threading
import time

import pytest

from app.engine.record import RecordError, json_schema
from app.engine.server import EngineServer
from app.engine.session import Session
from app.net.snapshots import TeleopSnapshot
from app.net.transport import Client
from tests.helpers import arm_and_hold, wait_for

mcap_reader = pytest.importorskip("mcap.reader", reason="mcap")


def _read(path):
    with open(path, "rb") as f:
        reader = mcap_reader.make_reader(f)
        summary = reader.get_summary()
        out = {}
        for schema, channel, message in reader.iter_messages():
            assert schema.encoding == "jsonschema" and channel.message_encoding == "json"
            out.setdefault(channel.topic, []).append((message.log_time, json.loads(message.data)))
        return summary, out


def test_a_recorded_teleop_session_holds_every_input_command_and_published_state(tmp_path):
    session = Session(robot_name="comau_smart5_3dof", solver_name="jacobian", mode="velocity")
    srv = EngineServer(session, bind="tcp://127.0.0.1:0", rate=200, publish_rate=50)
    path = tmp_path / "session.mcap"
    srv.record(str(path), seed=0)
    th = threading.Thread(target=srv.run, kwargs={"duration": 60.0}, daemon=True)
    th.start()
    op = Client(srv.url, role="operator", name="op", timeout=20.0)
    viewer = Client(srv.url, role="viewer", name="viewer", timeout=20.0)
    seen = []
    try:
        st = arm_and_hold(op, [0.5, 0.0, 0.0], op.latest_state, "enabled")
        assert st.flags.enabled
        t0 = time.monotonic()
        while time.monotonic() - t0 < 1.0:
            op.send_input([0.5, 0.0, 0.0], [True], "stick")
            s = viewer.recv_state(0.005)
            if s is not None:
                seen.append(s)
        op.request("set_mode", mode="position")
        with pytest.raises(Exception, match="unknown solver"):
            op.request("set_solver", solver="newton")
        op.send("estop", reason="test stop")
        wait_for(viewer, lambda s: s.estop, timeout=20.0)
    finally:
        srv.stop()
        th.join(timeout=10)
        srv.close()
        op.close()
        viewer.close()
    summary, topics = _read(path)
    assert {"/session", "/description", "/tick", "/input", "/command", "/estop", "/state"} <= set(topics)
    names = {s.name for s in summary.schemas.values()}
    assert {"bosun.TeleopSnapshot", "bosun.TeleopDescription", "bosun.Input", "bosun.Command"} <= names
    state_schema = next(json.loads(s.data) for s in summary.schemas.values() if s.name == "bosun.TeleopSnapshot")
    assert state_schema["properties"]["q"] == {"type": "array", "items": {"type": "number"}}
    session_rec = topics["/session"][0][1]
    assert session_rec["kind"] == "teleop" and session_rec["rate_hz"] == 200 and session_rec["publish_rate_hz"] == 50
    ticks = [m for _, m in topics["/tick"]]
    assert [m["tick"] for m in ticks] == list(range(len(ticks))) and all(m["dt"] == 0.005 for m in ticks)
    states = [m for _, m in topics["/state"]]
    assert abs(len(states) - len(ticks) / 4) <= 2  # published every 4th tick (200 Hz, 50 Hz)
    assert all(s["kind"] == "teleop" for s in states)
    recorded = {round(s["t"], 9): s for s in states}
    assert seen and all(round(s.t, 9) in recorded for s in seen)  # what the viewer got is on record, equal
    for s in seen:
        r = recorded[round(s.t, 9)]
        assert r["q"] == s.q and r["tool"] == s.tool and r["flags"]["enabled"] == s.flags.enabled
    inputs = [m for _, m in topics["/input"]]
    assert len(inputs) > 20 and all(m["device"] == "stick" and len(m["axes"]) == 3 for m in inputs)
    commands = [(m["type"], m["ok"]) for _, m in topics["/command"]]
    assert ("set_mode", True) in commands and ("set_solver", False) in commands
    refused = next(m for _, m in topics["/command"] if m["type"] == "set_solver")
    assert refused["fields"] == {"solver": "newton"} and "unknown solver" in refused["error"] and refused["by"] == "op"
    estops = [m["source"] for _, m in topics["/estop"]]
    assert estops == ["op"], estops  # who stopped it
    times = [t for t, _ in topics["/state"]]
    assert times == sorted(times) and times[1] - times[0] == round(1e9 * 4 * 0.005)  # the loop's clock: tick × Δt


def test_a_recording_refuses_a_bad_file_name_in_one_line(tmp_path):
    with pytest.raises(RecordError, match=r"ends in \.mcap"):
        EngineServer(Session(), bind="tcp://127.0.0.1:0").record(str(tmp_path / "x.json"))
    with pytest.raises(RecordError, match="cannot write") as info:
        EngineServer(Session(), bind="tcp://127.0.0.1:0").record(str(tmp_path / "missing" / "x.mcap"))
    assert "\n" not in str(info.value)


def test_the_schemas_follow_the_protocol_s_dataclasses():
    schema = json_schema(TeleopSnapshot, "bosun.TeleopSnapshot")
    props = schema["properties"]
    assert schema["title"] == "bosun.TeleopSnapshot" and props["t"] == {"type": "number"}
    assert props["tick"] == {"type": "integer"} and props["robot"] == {"type": "string"}
    assert props["flags"]["type"] == "object" and props["flags"]["properties"]["enabled"] == {"type": "boolean"}
    assert props["ga_axis"] == {"anyOf": [{"type": "array", "items": {"type": "number"}}, {"type": "null"}]}


def _record(tmp_path, session, rate, seconds=1.5, n_axes=3, extra=None):
    """A session driven by an operator for ``seconds`` (armed, stick deflected), then an E-STOP, on record."""
    srv = EngineServer(session, bind="tcp://127.0.0.1:0", rate=rate, publish_rate=min(rate, 50))
    path = tmp_path / f"{session.KIND}.mcap"
    srv.record(str(path))
    th = threading.Thread(target=srv.run, kwargs={"duration": 60.0}, daemon=True)
    th.start()
    op = Client(srv.url, role="operator", name="op", timeout=20.0)
    try:
        axes = [0.5, 0.2, 0.0, 0.0][:n_axes]
        assert arm_and_hold(op, axes, op.latest_state, "enabled").flags.enabled
        t0 = time.monotonic()
        while time.monotonic() - t0 < seconds:
            op.send_input(axes, [True], "stick")
            time.sleep(0.01)
        if extra is not None:
            extra(op)
        op.send("estop", reason="end")
        wait_for(op, lambda s: s.estop, timeout=20.0)
    finally:
        srv.stop()
        th.join(timeout=10)
        srv.close()
        op.close()
    return path


def test_a_recorded_session_replays_to_every_published_state(tmp_path, capsys):
    """The acceptance's check, on short sessions: the teleop engine (the Jacobian solver) and the crane-head engine
    (vessel, crane, head, load, predictors) run again from their recordings give every published state equal to
    1e-12 (the solver's wall time and the server's bookkeeping aside); ``bosun replay --check`` says so (exit 0),
    and names the first difference of a recording whose state was altered (exit 1)."""
    from app.cli import main
    from app.engine.replay import replay
    from app.engine.tac_session import TacSession

    teleop = _record(tmp_path, Session(robot_name="comau_smart5_3dof", solver_name="jacobian", mode="velocity"), 100,
                     extra=lambda op: op.request("set_mode", mode="position"))  # fmt: skip
    crane = _record(tmp_path, TacSession(), 50, n_axes=4)
    for path, kind in ((teleop, "teleop"), (crane, "tac")):
        report = replay(path)
        assert report.kind == kind and report.states > 20 and report.inputs > 20 and report.estops == 1
        assert report.equal, report.first
    assert main(["replay", str(crane), "--check"]) == 0
    assert "published states equal to the recording" in capsys.readouterr().out
    altered = tmp_path / "altered.mcap"
    _alter_one_state(teleop, altered)
    assert main(["replay", str(altered), "--check", "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["differing"] == 1 and ", q[0]: recorded" in out["first"], out


def test_a_recorded_ga_session_replays_to_every_published_state(tmp_path):
    """The GA's time budget on record (issue 32, item 6: GA sessions were not replayable): its solves take their
    decisions from the clock (time up or not, how many generations fit), which the recording keeps with each tick
    (``/tick``'s ``work``) and the replay gives back instead of the clock.  A GA session at 500 Hz (0.8 ms a
    solve), driven in velocity then position mode, replays to every published state; without them (the clock
    read again) it does not."""
    from app.engine.replay import replay

    session = Session(robot_name="comau_smart5_3dof", solver_name="ga", mode="velocity")
    path = _record(tmp_path, session, 500, extra=lambda op: op.request("set_mode", mode="position"))
    _, msgs = _read(path)
    solves = [d for _, m in msgs["/tick"] for d in m["work"]]
    assert len(solves) > 100 and any(d and d[-1] == 1 and len(d) >= 3 for d in solves)  # time ran out, mid-search
    report = replay(path)
    assert report.states > 20 and report.equal, report.first
    stripped = tmp_path / "no-work.mcap"
    _copy(path, stripped, lambda topic, data: json.dumps({**json.loads(data), "work": []}).encode()
          if topic == "/tick" else data)  # fmt: skip
    assert not replay(stripped).equal


def _copy(src, dst, change):
    """The recording copied message by message, each one's data through ``change(topic, data)`` (None: left out)."""
    from mcap.writer import Writer

    with open(src, "rb") as f, open(dst, "wb") as g:
        reader = mcap_reader.make_reader(f)
        w = Writer(g)
        w.start()
        schemas, channels = {}, {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(channel.topic, channel.message_encoding, schemas[schema.id])
            data = change(channel.topic, message.data)
            if data is not None:
                w.add_message(channels[channel.id], message.log_time, data, message.publish_time, message.sequence)
        w.finish()


def _alter_one_state(src, dst):
    """The recording copied, with the 10th state's first joint moved by 1e-9 rad."""
    n = [0]

    def change(topic, data):
        if topic == "/state":
            n[0] += 1
            if n[0] == 10:
                m = json.loads(data)
                m["q"][0] += 1e-9
                return json.dumps(m).encode()
        return data

    _copy(src, dst, change)


def test_a_replay_refuses_what_it_cannot_reproduce_in_one_line(tmp_path):
    """Work the loop did off its thread (its result came on a tick the machine chose), a file that is no
    recording: refused in one line."""
    from mcap.writer import Writer

    from app.engine.replay import ReplayError, replay

    path = tmp_path / "deferred.mcap"
    with open(path, "wb") as g:
        w = Writer(g)
        w.start()
        sid = w.register_schema("s", "jsonschema", b"{}")
        chans = {t: w.register_channel(t, "json", sid) for t in ("/session", "/command")}
        session = {"kind": "lab", "rate_hz": 50, "publish_rate_hz": 25, "seed": 0, "version": "x", "argv": [],
                   "scene": {"plc": False}}  # fmt: skip
        w.add_message(chans["/session"], 0, json.dumps(session).encode(), 0)
        cmd = {"tick": 3, "type": "set_vessel", "fields": {"vessel": "supply"}, "by": "op", "ok": True, "error": "",
               "deferred": True}  # fmt: skip
        w.add_message(chans["/command"], 1, json.dumps(cmd).encode(), 1)
        w.finish()
    with pytest.raises(ReplayError, match="'set_vessel', whose work ran off the loop") as info:
        replay(path)
    assert "\n" not in str(info.value)
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file at all")
    with pytest.raises(ReplayError, match="not a readable MCAP recording"):
        replay(junk)


def _write_recording(path, kind, states, estops=()):
    """A recording made by hand: /session, then /state messages (and /estop after the state numbers given)."""
    from mcap.writer import Writer

    with open(path, "wb") as g:
        w = Writer(g)
        w.start()
        sid = w.register_schema("s", "jsonschema", b"{}")
        ch = {t: w.register_channel(t, "json", sid) for t in ("/session", "/state", "/estop")}
        head = {"kind": kind, "rate_hz": 50, "publish_rate_hz": 10, "seed": 0, "version": "x", "argv": [], "scene": {}}
        w.add_message(ch["/session"], 0, json.dumps(head).encode(), 0)
        for i, s in enumerate(states):
            w.add_message(ch["/state"], i + 1, json.dumps(s).encode(), i + 1)
            if i in estops:
                w.add_message(ch["/estop"], i + 1, json.dumps({"tick": i, "source": "op"}).encode(), i + 1)
        w.finish()


def test_the_score_sheet_counts_what_the_states_say(tmp_path, capsys):
    """Issue 32, item 6's score sheet on a hand-made crane-head recording (0.1 s apart): the peak tension factor and
    ψ, the swing while hanging (a landed load's angle is no swing), the time over SWL, STOPs, saturation episodes and
    their time, touchdown speeds and re-hits; ``bosun score`` writes score.json and score.png; a teleop recording
    is refused in one line."""
    from app.analysis.score import score_recording
    from app.cli import main

    states = []
    for i in range(40):
        landed = 20 <= i < 30 or i >= 35
        swing = 3.0 if i == 5 else (50.0 if landed else 1.0)
        speed = 0.3 if i == 19 else (0.1 if i == 34 else 0.0)
        load = {
            "tension_factor": 1.0 + (2.4 if i == 12 else 0.0), "psi": 1.0 + 0.01 * i, "swing_deg": swing,
            "swl_percent": 120.0 if 10 <= i < 15 else 80.0, "landed": landed, "rel_speed": speed,
            "rehits": 2 if 25 <= i < 30 else 0,
        }  # fmt: skip
        states.append({"kind": "tac", "t": 0.1 * i, "load": load, "sample": {"saturated": i in (3, 4, 8)}})
    path = tmp_path / "made.mcap"
    _write_recording(path, "tac", states, estops=(7, 30))
    sheet = score_recording(path)
    assert sheet.peak_tension_factor == 3.4 and sheet.peak_psi == pytest.approx(1.39)
    assert sheet.peak_swing_deg == 3.0  # the 50° of a landed load is not swing
    assert sheet.time_over_swl_s == pytest.approx(0.5) and sheet.peak_swl_percent == 120.0
    assert sheet.estops == 2 and sheet.saturations == 2 and sheet.saturated_s == pytest.approx(0.3)
    assert sheet.landing_speeds_mps == [0.3, 0.1] and sheet.rehits == 2
    assert sheet.duration_s == pytest.approx(4.0)
    assert main(["score", str(path), "--out", str(tmp_path / "sheet")]) == 0
    assert "peak_tension_factor" in capsys.readouterr().out
    data = json.loads((tmp_path / "sheet" / "score.json").read_text(encoding="utf-8"))
    assert data["max_landing_speed_mps"] == 0.3 and (tmp_path / "sheet" / "score.png").read_bytes()[:4] == b"\x89PNG"
    teleop = tmp_path / "teleop.mcap"
    _write_recording(teleop, "teleop", [{"kind": "teleop", "t": 0.0}])
    assert main(["score", str(teleop)]) == 2
    err = capsys.readouterr().err
    assert "no hanging load to score" in err and len(err.strip().splitlines()) == 1


def test_a_replay_is_served_to_viewers_as_it_ran(tmp_path):
    """``bosun replay --serve``: the recording played back in an engine loop; a viewer receives the recorded states
    (equal, in order), an operator's command is refused in one line, and STOP freezes the playback with the E-STOP
    latched."""
    from app.engine.replay import MEASURED, Replayer, ReplayScene
    from app.engine.tac_session import TacSession

    path = _record(tmp_path, TacSession(), 50, seconds=2.0, n_axes=4)
    recorded = {}
    for _, m in _read(path)[1]["/state"]:
        recorded.setdefault(round(m["t"], 9), m)
    replayer = Replayer(path, check=False)
    srv = EngineServer(ReplayScene(replayer), bind="tcp://127.0.0.1:0", rate=replayer.rate,
                       publish_rate=replayer.publish_rate)  # fmt: skip
    th = threading.Thread(target=srv.run, kwargs={"duration": 60.0}, daemon=True)
    th.start()
    viewer = Client(srv.url, role="viewer", name="viewer", timeout=20.0)
    op = Client(srv.url, role="operator", name="op", timeout=20.0)
    try:
        got = []
        t0 = time.monotonic()
        while time.monotonic() - t0 < 2.0 and len(got) < 40:
            s = viewer.recv_state(0.05)
            if s is not None:
                got.append(s)
        assert "replay of tac.mcap" in viewer.describe().title  # never taken for a live engine
        with pytest.raises(Exception, match="replays a recording; commands are refused"):
            op.request("set_tac_mode", mode="off")
        op.send("estop", reason="stop the replay")
        stopped = wait_for(viewer, lambda s: s.estop, timeout=20.0)
        time.sleep(0.3)
        assert viewer.latest_state().t == stopped.t  # frozen
    finally:
        srv.stop()
        th.join(timeout=10)
        srv.close()
        replayer.close()
        viewer.close()
        op.close()
    assert len(got) >= 10 and [s.t for s in got] == sorted(s.t for s in got)
    matched = 0
    from app.net.snapshots import to_wire

    for s in got:
        r = recorded.get(round(s.t, 9))
        if r is None:
            continue
        w = to_wire(s)
        for key in r.keys() - MEASURED - {"alarms"}:  # alarms: the serving loop sets its own health
            assert w[key] == r[key] or key == "t", key
        matched += 1
    assert matched >= 10
