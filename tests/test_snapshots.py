"""Protocol v2's typed state (app/net/snapshots.py) and studies run by the engine (issue 15).

Round trips take the snapshots and descriptions real scenes produce, encode them as the server does
(``to_wire`` inside a msgpack ``state`` message) and decode them as a client does; the study tests
drive a live engine over the protocol only, as the GUI's Analysis tab does.
"""

from __future__ import annotations

import copy
import dataclasses
import time

import msgpack
import numpy as np
import pytest

from app.analysis.ik_studies import ErrorDistribution, study_from_wire
from app.engine.lab_session import LabSession
from app.engine.session import Session
from app.engine.tac_session import TacSession
from app.models.registry import resolve
from app.net.codec import decode_engine, encode
from app.net.snapshots import (
    DESCRIPTIONS,
    SNAPSHOTS,
    LabSnapshot,
    SnapshotError,
    TacSnapshot,
    TeleopSnapshot,
    description_from_wire,
    snapshot_from_wire,
    to_wire,
)
from app.net.transport import Client, TransportError
from tests.helpers import wait_for


@pytest.fixture(scope="module")
def scenes():
    made = [Session(), TacSession(), LabSession()]
    for s in made:
        for _ in range(3):
            s.tick(time.monotonic(), 0.02)
    yield made
    for s in made:
        s.close()


def _over_the_wire(obj):
    """What a client receives: the server's msgpack bytes of ``to_wire(obj)``, decoded."""
    return decode_engine(encode("state", state=to_wire(obj))).state


def test_every_scene_has_one_snapshot_and_one_description_class():
    assert set(SNAPSHOTS) == set(DESCRIPTIONS) == {"teleop", "tac", "lab"}


@pytest.mark.parametrize("k, cls", [(0, TeleopSnapshot), (1, TacSnapshot), (2, LabSnapshot)])
def test_snapshot_round_trip_is_exact(scenes, k, cls):
    snap = scenes[k].snapshot()
    assert isinstance(snap, cls) and snap.kind == scenes[k].KIND
    back = snapshot_from_wire(_over_the_wire(snap))
    assert type(back) is cls
    assert to_wire(back) == to_wire(snap)  # every field, nested classes included
    # one E-STOP place and one flags block in every scene
    assert back.estop is False and back.flags.enabled is False


@pytest.mark.parametrize("k", [0, 1, 2])
def test_description_round_trip_is_exact(scenes, k):
    desc = scenes[k].describe()
    back = description_from_wire(_over_the_wire(desc))
    assert type(back) is type(desc) and back.kind == scenes[k].KIND
    assert to_wire(back) == to_wire(desc)


def test_static_data_is_not_in_the_snapshot(scenes):
    """Joint limits, robot file and workspace box travel in the description, not 50 times a second."""
    wire = to_wire(scenes[0].snapshot())
    desc = to_wire(scenes[0].describe())
    assert "robot_xml" in desc and "robot_xml" not in wire
    assert len(msgpack.packb(wire)) < len(msgpack.packb(desc))


def test_estop_shows_in_the_same_field_for_every_scene(scenes):
    for s in scenes:
        s.estop("test")
        assert snapshot_from_wire(_over_the_wire(s.snapshot())).estop is True
        s.reset()
        assert snapshot_from_wire(_over_the_wire(s.snapshot())).estop is False


def test_wrong_kind_missing_and_mistyped_fields_are_refused(scenes):
    wire = _over_the_wire(scenes[0].snapshot())
    with pytest.raises(SnapshotError, match="unknown kind 'crane'"):
        snapshot_from_wire({**wire, "kind": "crane"})
    with pytest.raises(SnapshotError, match="unknown kind None"):
        snapshot_from_wire({k: v for k, v in wire.items() if k != "kind"})
    bad = copy.deepcopy(wire)
    del bad["scaling"]["k_v"]
    with pytest.raises(SnapshotError, match=r"teleop\.scaling: missing field 'k_v'"):
        snapshot_from_wire(bad)
    # a field an older engine does not send takes its default (adding optional fields keeps v2)
    assert snapshot_from_wire({k: v for k, v in wire.items() if k != "study"}).study.status == "idle"
    bad = copy.deepcopy(wire)
    bad["flags"]["enabled"] = "yes"
    with pytest.raises(SnapshotError, match=r"teleop\.flags\.enabled: expected bool, got str"):
        snapshot_from_wire(bad)
    bad = copy.deepcopy(wire)
    bad["engine"] = [1, 2]
    with pytest.raises(SnapshotError, match=r"teleop\.engine: expected a map"):
        snapshot_from_wire(bad)
    with pytest.raises(SnapshotError, match="not a map"):
        snapshot_from_wire([wire])
    with pytest.raises(SnapshotError, match="expected a number, got bool"):
        snapshot_from_wire({**wire, "t": True})


def test_fields_a_newer_engine_adds_are_ignored(scenes):
    wire = _over_the_wire(scenes[2].snapshot())
    wire["new_field"] = {"anything": [1, 2]}
    wire["winch"]["new_sensor"] = 3.5
    back = snapshot_from_wire(wire)
    assert not hasattr(back, "new_field") and back.winch.length == scenes[2].snapshot().winch.length


def test_integers_on_the_wire_become_floats_where_the_class_says_float(scenes):
    wire = _over_the_wire(scenes[0].snapshot())
    wire["t"] = 3
    assert snapshot_from_wire(wire).t == 3.0 and isinstance(snapshot_from_wire(wire).t, float)


def test_snapshot_classes_are_slotted_dataclasses():
    """Typos in a reader fail loudly (no silent new attribute), as a dict's missing key would."""
    for cls in (*SNAPSHOTS.values(), *DESCRIPTIONS.values()):
        assert dataclasses.is_dataclass(cls)
    snap = TeleopSnapshot(t=0.0, robot="x", solver="y", mode="velocity")
    with pytest.raises(AttributeError):
        snap.estopp = True  # type: ignore[attr-defined]


# ------------------------------------------------------------------ studies over the protocol
def _study_messages(client: Client, until: float):
    """``study`` messages from the engine's stream until a final one (done/cancelled/failed)."""
    seen = []
    alive = 0.0
    while time.monotonic() < until:
        if time.monotonic() - alive > 1.0:  # an operator's client speaks (a GUI sends input at 50 Hz): on a
            client.send("ping")  # loaded machine a study can outlast the role's 5 s lease of silence
            alive = time.monotonic()
        if not client.sub.poll(200):
            continue
        msg = decode_engine(client.sub.recv())
        if msg.TYPE == "study":
            seen.append(msg.study)
            if msg.study["status"] in ("done", "cancelled", "failed"):
                return seen
    raise AssertionError(f"no final study message; seen {[m['status'] for m in seen]}")


@pytest.mark.slow
def test_custom_robot_by_path_then_a_study_runs_in_the_engine(serve, tmp_path):
    """Issue 15: a robot the client sent by file (not in the library) is the one the study runs on."""
    text = resolve("scara").read_text(encoding="utf-8").replace('name="scara"', 'name="custom_arm"', 1)
    srv, _ = serve(Session())
    op = Client(srv.url, role="operator", name="op", timeout=20.0)
    try:
        op.request("set_robot", robot=str(tmp_path / "custom_arm.xml"), xml=text)
        desc = op.describe()
        assert desc.robot == "custom_arm" and "custom_arm" in desc.robot_xml
        assert "jacobian" in desc.solvers
        op.request("study_start", study="distribution", solver="jacobian", grid=4)
        msgs = _study_messages(op, time.monotonic() + 240)
        final = msgs[-1]
        assert final["status"] == "done", final
        assert final["total"] == 4**3 and final["done"] == 4**3
        result = study_from_wire(final["result"])
        assert isinstance(result, ErrorDistribution)
        assert result.robot == "custom_arm" and result.solver == "jacobian" and result.targets.shape == (64, 3)
        assert np.all(np.isfinite(result.error[result.success]))
        # the state shows the study's progress in the same id
        st_ = op.latest_state(2.0)
        assert st_.study.id == final["id"] and st_.study.status == "done"
    finally:
        op.close()


@pytest.mark.slow
def test_a_study_can_be_cancelled_and_keeps_what_it_did(serve):
    srv, _ = serve(Session())
    op = Client(srv.url, role="operator", name="op", timeout=20.0)
    try:
        op.request("study_start", study="distribution", solver="ga", grid=12)  # 1728 GA targets: minutes
        with pytest.raises(TransportError, match="study is running; cancel it first"):
            op.request("study_start", study="distribution", solver="jacobian", grid=4)
        op.request("study_cancel")
        final = _study_messages(op, time.monotonic() + 120)[-1]
        assert final["status"] == "cancelled"
        assert final["done"] < 12**3
        with pytest.raises(TransportError, match="no study is running"):
            op.request("study_cancel")
    finally:
        op.close()


def test_a_viewer_cannot_start_a_study(serve):
    srv, _ = serve(Session())
    op = Client(srv.url, role="operator", name="op")
    viewer = Client(srv.url, role="viewer", name="v")
    try:
        with pytest.raises(TransportError, match="operator"):
            viewer.request("study_start", study="distribution", grid=4)
    finally:
        viewer.close()
        op.close()


# ------------------------------------------------------------------ pause (H49)
@pytest.mark.parametrize("make", [TacSession, LabSession], ids=["tac", "lab"])
def test_a_paused_scene_stands_still_but_stop_latches_and_is_confirmed(serve, make):
    srv, _ = serve(make(), rate=100)
    op = Client(srv.url, role="operator", name="op", timeout=20.0)
    try:
        op.request("pause", on=True)
        st_ = wait_for(op, lambda s: s.engine.paused)
        t0 = st_.t
        time.sleep(0.5)
        assert op.latest_state(2.0).t == t0  # the scene's time stands still
        op.send("estop", reason="paused STOP")
        st_ = wait_for(op, lambda s: s.estop)  # latched while paused
        assert st_.engine.paused and st_.engine.estops >= 1 and st_.t == t0
        op.request("reset")
        op.request("pause", on=False)
        st_ = wait_for(op, lambda s: not s.engine.paused and s.t > t0 + 0.2)
        assert not st_.estop
        assert not st_.flags.enabled and not st_.flags.armed  # resumed disarmed: nothing moves unbidden
    finally:
        op.close()


def test_only_the_operator_pauses(serve):
    srv, _ = serve(TacSession(), rate=100)
    op = Client(srv.url, role="operator", name="op")
    viewer = Client(srv.url, role="viewer", name="v")
    try:
        with pytest.raises(TransportError, match="operator"):
            viewer.request("pause", on=True)
        assert not op.latest_state(2.0).engine.paused
    finally:
        viewer.close()
        op.close()
