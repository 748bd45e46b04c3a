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
    assert times == sorted(times) and times[-1] == round(1e9 * states[-1]["t"])  # on the session's own clock


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
