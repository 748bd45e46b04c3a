"""Issue 16, item 1: the Motion-Lab's PLC bridge against pyads' own ADS test server on loopback.

The test server (``pyads.testserver.AdsTestServer`` with its ``AdvancedHandler``, set up in
:mod:`app.plc.testplc`) plays the lab's TwinCAT PLC: it serves the lab's symbols with the lab's types
(from the lab's HMI and PLC project as summarised in motionlab_plc.json, Norwegian Motion-Laboratory
repository, commit f5fbf84, MIT: structs as bytes), on its own loopback address (127.77.x.y, port 48898
as ADS has it).  The real bridge and a real :class:`LabSession` (and, once, a real ``bosun server``
process) talk to it.  The module's docstring names the server's quirks it works around (notifications
in-process: the ``bosun server`` process sees a value through the bridge's 1 s refresh reads).
"""

from __future__ import annotations

import json
import math
import re
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from app.engine.scene import CommandError
from app.net.snapshots import to_wire
from app.plc.testplc import STATE, LabPlc, lab_declarations, size_of
from tests.helpers import ROOT, needs_qt

REFERENCE = ROOT.parent / "shared" / "data" / "motionlab_plc.json"

SETTLED, NEUTRAL, GENERATOR, SIMULATION = 0, 1, 3, 2  # E_StewartMode


def free_loopback() -> str:
    """A loopback address of its own for each test server; the test skips when there is none."""
    from app.plc.testplc import TestPlcError
    from app.plc.testplc import free_loopback as free

    try:
        return free()
    except TestPlcError as err:
        pytest.skip(str(err))


@pytest.fixture
def lab_plc():
    pytest.importorskip("pyads")
    plc = LabPlc(free_loopback())
    plc.start()
    try:
        yield plc
    finally:
        plc.stop()


def make_session(plc: LabPlc):
    from app.engine.lab_session import LabSession
    from app.plc.bridge import PlcTarget

    target = PlcTarget.parse(f"{plc.ip}.1.1:851")
    return LabSession(plc=target, plc_options={"backoff": (0.2, 1.6), "connect_timeout": 1.0, "ads_timeout": 0.5})


@pytest.fixture
def session(lab_plc):
    ses = make_session(lab_plc)
    try:
        yield ses
    finally:
        ses.close()


def pump(ses, until, timeout: float = 20.0, dt: float = 0.02, sample=None):
    """Tick the scene in real time (feeding ``sample`` as the operator's stick, if given) until
    ``until(snapshot)`` holds; the snapshot."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if sample is not None:
            ses.feed(sample, time.monotonic())
        ses.tick(time.monotonic(), dt)
        snap = ses.snapshot()
        if until(snap):
            return snap
        time.sleep(dt)
    raise AssertionError(f"condition not met in {timeout} s; plant: {ses.snapshot().plant}")


def stick(enable: bool):
    from app.teleop.devices import InputSample

    return InputSample((0.0, 0.0, 0.0, 0.0), (enable,), "test stick")


def arm(ses) -> None:
    """The arming gesture: stick at neutral, enable released, then pressed."""
    t0 = time.monotonic()
    pump(ses, lambda s: time.monotonic() - t0 > 0.1, sample=stick(False))
    pump(ses, lambda s: s.flags.armed, sample=stick(True))


def settle_until(until, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not until():
        assert time.monotonic() < deadline, "condition not met"
        time.sleep(0.02)


def connected(snap) -> bool:
    return snap.plant is not None and snap.plant.link == "ok"


def written(ses, name: str) -> list:
    """What the bridge wrote to ``name`` (values in order, from its log of the last 64 writes)."""
    return [v for n, v in ses.plant.bridge.stats.written if n == name]


# ---------------------------------------------------------------------------- fast: tables and CLI
def test_symbol_table_matches_the_lab_reference():
    """Names, types, enumerations and rates of the bridge against the lab's own (motionlab_plc.json)."""
    from app.plc import symbols as sy

    if not REFERENCE.is_file():
        pytest.skip("../shared/data/motionlab_plc.json is not here (a fresh clone has no ../shared)")
    ref = json.loads(REFERENCE.read_text(encoding="utf-8"))
    table = sy.lab_symbols()
    hmi = ref["ads_hmi"]
    assert (hmi["ams_net_id"], hmi["port"]) == (sy.AMS_NET_ID, sy.AMS_PORT)
    assert "0.005" in hmi["plc_task"] and sy.PLC_CYCLE == 0.005
    for entry, rate in hmi["polled_structs"].items():
        name = entry.split(" ")[0].replace("<stewart>", "em8000")
        if name in table:
            assert table[name].period == pytest.approx(float(rate.split()[0]) / 1000)
    for write in hmi["writes"]:
        head = write.split(" ")[0]  # "MAIN.<stewart>.sineAmplitude[i]/sineOmega[i]/sinePhase[i]"
        first, *more = head.split("/")
        prefix = first.rsplit(".", 1)[0]
        for name in (first, *(f"{prefix}.{w}" for w in more)):
            name = re.sub(r"\[i\]$", "", name)  # written whole: all six at once
            if name == "GVL.logMessage":
                continue  # the lab HMI's log line into the PLC: Bosun keeps its own log
            for p in ("em8000", "em1500"):
                assert name.replace("<stewart>", p) in table, name
    assert table["MAIN.em8000.eModeCmd"].plc_type.endswith("(SINT)")  # "eModeCmd (SINT)"
    assert table["MAIN.em1500.sineAmplitude"].plc_type.endswith("LREAL")  # "sineAmplitude[i] … (LREAL)"
    main_state, active, device = hmi["notifications"]  # MAIN.eState, MAIN.<dev>.bActive, MAIN.<dev>.eState/…
    assert table[main_state].access == "notify"
    for dev in ("em8000", "em1500", "comau", "winch", "mru1", "mru2"):
        assert table[active.replace("<dev>", dev)].access == "notify"
    for field in device.split("<dev>.")[1].split("/"):
        for p in ("em8000", "em1500"):
            assert table[f"MAIN.{p}.{field}"].access == "notify"
    st = ref["stewart"]
    assert {k: v for k, v in st["modes_E_StewartMode"].items() if k != "file"} == sy.STEWART_MODE
    assert st["state_E_StewartState (Rexroth motion status bits 0-3)"] == sy.STEWART_STATE
    assert st["status_E_StewartStatus (bits 4-7)"] == sy.STEWART_STATUS
    assert ref["comau"]["modes_E_ComauMode"] == sy.COMAU_MODE
    assert ref["winch"]["modes_E_WinchMode"] == sy.WINCH_MODE
    assert "0.2 m/s" in ref["winch"]["hmi_velocity_slider"] and sy.WINCH_SPEED_MAX == 0.2
    # the test server below declares the same sizes as the bridge expects
    for name, iec in lab_declarations().items():
        assert table[name].size == size_of(iec), name


def test_plc_addresses_are_checked_with_one_line():
    from app.plc.bridge import PlcTarget, PlcTargetError

    t = PlcTarget.parse("192.168.90.150.1.1")
    assert (t.net_id, t.port, t.host) == ("192.168.90.150.1.1", 851, "192.168.90.150")
    assert PlcTarget.parse("5.6.7.8.1.1:852", "plc.lab").host == "plc.lab"
    for bad, msg in (("1.2.3", "six numbers"), ("1.2.3.4.1.1:x", "must be a number"), ("1.2.3.4.1.300", "six")):
        with pytest.raises(PlcTargetError, match=msg):
            PlcTarget.parse(bad)
    with pytest.raises(PlcTargetError, match="out of range"):
        PlcTarget.parse("1.2.3.4.1.1:0")


def test_without_pyads_plc_says_how_to_install(monkeypatch, capsys):
    from app.cli import main

    monkeypatch.setitem(sys.modules, "pyads", None)  # import pyads raises ImportError
    assert main(["server", "--plant", "lab", "--plc", "192.168.90.150.1.1", "--duration", "0.1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "pip install 'bosun[plc]'" in err
    assert main(["server", "--plc", "192.168.90.150.1.1", "--duration", "0.1"]) == 2
    assert "--plant lab" in capsys.readouterr().err


def test_wave_inputs_match_the_sea_they_stand_for():
    """ω0 at the spectrum's peak, σ² its peak value, λ the variance πλω0σ² = Hs²/16 (unit white noise)."""
    from app.marine.waves import spectrum
    from app.plc.symbols import wave_inputs

    omega = np.linspace(0.1, 3.0, 3000)
    for hs, tp in ((2.0, 8.0), (4.0, 11.0)):
        w = wave_inputs(omega, spectrum("jonswap", omega, hs, tp), hs)
        assert w.w0 == pytest.approx(2 * math.pi / tp, rel=0.01)
        assert w.sigma**2 == pytest.approx(spectrum("jonswap", np.array([w.w0]), hs, tp)[0])
        assert math.pi * w.lam * w.w0 * w.sigma**2 == pytest.approx(hs**2 / 16)
        # the model's response |h(jω)|² integrates to the same variance (numerically)
        k_w = 2 * w.lam * w.w0 * w.sigma
        wide = np.linspace(1e-4, 60 * w.w0, 400_000)
        h2 = (k_w * wide) ** 2 / ((w.w0**2 - wide**2) ** 2 + (2 * w.lam * w.w0 * wide) ** 2)
        assert np.trapezoid(h2, wide) == pytest.approx(hs**2 / 16, rel=0.01)


def test_simulated_lab_has_no_plc_to_acknowledge():
    from app.engine.lab_session import LabSession

    ses = LabSession()
    with pytest.raises(CommandError, match="no PLC"):
        ses.command("lab_plc_ack")
    snap = ses.snapshot()
    assert snap.plant.backend == "simulated" and snap.plant.link == "simulated"
    assert ses.describe().backend == "simulated"


def test_no_plc_at_the_address_commands_refused_stop_latched_here():
    """Nothing answers: the engine runs on (the ADS thread waits, never the loop), says why, refuses
    commands without queueing them, latches STOP locally and keeps it latched."""
    pytest.importorskip("pyads")
    from app.engine.lab_session import LabSession
    from app.plc.bridge import PlcTarget

    ses = LabSession(plc=PlcTarget.parse(f"{free_loopback()}.1.1"), plc_options={"backoff": (0.2, 0.4)})
    try:
        snap = pump(ses, lambda s: "refused" in s.plant.last_error, timeout=10)
        assert snap.plant.link == "connecting" and not snap.plant.connected
        assert any(a.key == "plc_link" and a.active and a.severity == "critical" for a in snap.alarms)
        with pytest.raises(CommandError, match=r"not connected to the PLC.*nothing is queued"):
            ses.command("lab_platform", platform="em8000", action="neutral")
        ses.estop("test")
        assert ses.snapshot().estop and ses.plant.bridge.stats.writes == 0
        with pytest.raises(CommandError, match="reset refused"):
            ses.reset()
        assert ses.snapshot().estop
        assert any("not reachable" in e.text for e in ses.log)
    finally:
        ses.close()
    assert not ses.plant.bridge.alive


# ---------------------------------------------------------------------------- against the test server
@pytest.mark.slow
def test_commands_arrive_by_name_with_the_lab_types(lab_plc, session):
    ses, plc = session, lab_plc
    pump(ses, connected)
    assert ses.plant.problems == []
    assert ses.describe().backend == "plc" and ses.describe().winch.speed_max == pytest.approx(0.2)
    amp, freq, phase = [0.0, 0.0, 0.1, 0.02, 0.0, 0.0], [0.1, 0.1, 0.2, 0.25, 0.1, 0.1], [0, 0, 0.5, 0, 0, 0]
    ses.command("lab_source", platform="em8000", source="generator", amplitude=amp, frequency=freq, phase=phase)
    ses.command("lab_platform", platform="em8000", action="neutral")
    settle_until(lambda: plc.get("MAIN.em8000.eModeCmd", "<b") == NEUTRAL)
    assert plc.get("MAIN.em8000.sineAmplitude", "<6d") == pytest.approx(amp)  # LREAL[6]
    assert plc.get("MAIN.em8000.sineOmega", "<6d") == pytest.approx([2 * math.pi * f for f in freq])  # rad/s
    assert plc.get("MAIN.em8000.sinePhase", "<6d") == pytest.approx(phase)
    assert plc.get("MAIN.em8000.bStart", "<?") is False
    plc.set("MAIN.em8000.eState", "<b", STATE["NEUTRAL"])  # the PLC reached NEUTRAL
    pump(ses, lambda s: s.platforms[0].status == "neutral")
    ses.command("lab_platform", platform="em8000", action="engage")
    settle_until(lambda: plc.get("MAIN.em8000.bStart", "<?"))
    assert plc.get("MAIN.em8000.eModeCmd", "<b") == GENERATOR  # SINT: one byte
    # the wave simulator: w0, lambda, sigma (LREAL) and the scale reset pulsed on the other platform
    ses.command("lab_source", platform="em1500", source="simulation", spectrum="jonswap", hs=2.0, tp=8.0)
    settle_until(lambda: plc.get("MAIN.em1500.hydro.stInput.w0", "<d") > 0)
    assert plc.get("MAIN.em1500.hydro.stInput.w0", "<d") == pytest.approx(2 * math.pi / 8.0, rel=0.01)
    assert 0.01 <= plc.get("MAIN.em1500.hydro.stInput.lambda", "<d") <= 1.0
    assert plc.get("MAIN.em1500.hydro.stInput.sigma", "<d") > 0
    pump(ses, lambda s: written(ses, "MAIN.em1500.bResetScale")[-2:] == [True, False])
    with pytest.raises(CommandError, match="no timeseries source"):
        ses.command("lab_source", platform="em1500", source="timeseries", csv="t,x\n")
    # remote setpoint (REAL[6], clipped to the operational box), Comau start, winch mode and slider speed
    ses.command("lab_source", platform="em1500", source="remote")
    ses.command("lab_remote_pose", platform="em1500", eta=[0.01, 0.0, 0.05, 0.0, 0.01, 5.0])
    ses.command("lab_comau_mode", mode="remote")
    ses.command("lab_winch", mode="local")
    plc.set("MAIN.winch.eMode", "<b", 1)  # LOCAL
    pump(ses, lambda s: s.winch.mode == "local")
    ses.command("lab_winch", speed=0.5)
    settle_until(lambda: plc.get("MAIN.winch.u", "<f") > 0)
    u = plc.get("MAIN.em1500.uRemote", "<6f")
    assert u[:5] == pytest.approx([0.01, 0.0, 0.05, 0.0, 0.01], abs=1e-6) and 0 < u[5] < 5.0
    assert plc.get("MAIN.comau.bStart", "<?") is True
    assert plc.get("MAIN.winch.eModeCmd", "<b") == 1 and plc.get("MAIN.winch.bEnable", "<?") is True
    assert plc.get("MAIN.winch.u", "<f") == pytest.approx(0.2)  # the lab's slider: 0.2 m/s at most
    pump(ses, lambda s: plc.get("MAIN.winch.u", "<f") == 0.0)  # let go: back to zero (spring return)
    with pytest.raises(CommandError, match="VVMC"):
        ses.command("lab_vvmc", on=True)
    # STOP and reset by name: MAIN.bStop BOOL, MAIN.bReset pulsed (TRUE, then FALSE after 0.2 s)
    ses.estop("test")
    settle_until(lambda: plc.get("MAIN.bStop", "<?"))
    assert pump(ses, lambda s: s.plant.stop_written).estop
    ses.reset()
    settle_until(lambda: not plc.get("MAIN.bStop", "<?"))
    pump(ses, lambda s: written(ses, "MAIN.bReset")[-2:] == [True, False])
    assert not plc.get("MAIN.bReset", "<?")


@pytest.mark.slow
def test_states_written_by_the_plc_appear_in_the_snapshot(lab_plc, session):
    from app.net.snapshots import snapshot_from_wire, to_wire

    ses, plc = session, lab_plc
    pump(ses, connected)
    eta = [0.01, -0.02, 0.05, 0.01, -0.02, 0.03]
    plc.set("MAIN.em8000.eState", "<b", STATE["ENGAGED"])
    plc.set("MAIN.em8000.eMode", "<b", GENERATOR)
    plc.set("MAIN.em8000.txHmi", "<i24f", STATE["ENGAGED"], *eta, *eta, *[0.3] * 6, *[1.0] * 6)
    q = [0.1, -0.2, 0.3, 0.0, 0.0, 0.0]
    plc.set("MAIN.comau.txHmi", "<24f", *q, *[0.05] * 6, *[-2.0] * 6, *[2.0] * 6)
    plc.set("MAIN.comau.eMode", "<b", 1)  # REMOTE
    plc.set("MAIN.winch.lengthUtilization", "<f", 50.0)
    plc.set("MAIN.winch.eMode", "<b", 3)  # MOTION_COMP
    plc.set("MAIN.mru1.bActive", "<?", True)
    snap = pump(ses, lambda s: s.platforms[0].status == "engaged" and abs(s.comau.q[0] - 0.1) < 1e-6)
    w = ses.layout.winch
    half = w["min_length"] + 0.5 * (w["max_length"] - w["min_length"])
    snap = pump(ses, lambda s: s.winch.mode == "motion_comp" and abs(s.winch.length - half) < 1e-6)  # polled
    # EM8000's struct is polled apart from eState (a notification): a poll that read it just before it was
    # written gives η at the next poll, 50 ms on (seen at load 5)
    snap = pump(ses, lambda s: max(abs(a - b) for a, b in zip(s.platforms[0].eta, eta, strict=True)) < 1e-6)
    assert snap.plant.devices["mru1"]["active"]
    p = snap.platforms[0]
    assert p.mode == "engaged" and p.source == "generator" and p.eta == pytest.approx(eta, abs=1e-6)
    assert snap.comau.mode == "remote" and snap.comau.q == pytest.approx(q[:3], abs=1e-6)
    dev = snap.plant.devices
    assert dev["em8000"]["state"] == "ENGAGED" and dev["em8000"]["mode"] == "GENERATOR"
    assert dev["main"]["state"] == "NORMAL" and snap.plant.plc_state == "NORMAL" and snap.plant.plc_error == ""
    assert 0 <= snap.plant.data_age < 5 and snap.plant.ads_state == 5
    # the scene draws the measured machines: EM8000's top moved with η, the tool with the joints
    assert snap.scene.platforms["em8000"]["top"] != ses.snapshot().scene.platforms["em1500"]["top"]
    back = snapshot_from_wire(to_wire(snap))  # typed over the wire, the link included
    assert back.plant.devices["em8000"]["state"] == "ENGAGED" and back.plant.link == "ok"


@pytest.mark.slow
def test_the_lab_hmis_status_word_lights_and_a_refused_jog_over_the_plc(lab_plc, session):
    """Issue 16, item 5: the Rexroth status (eState, eStatus, eOpMode) and the machine and sensor lights
    (``MAIN.<dev>.bActive``) appear in the snapshot as the PLC reports them, in the same fields the
    simulation fills; the tracker's and the remote interface's are unknown (no symbol); a Comau jog is
    refused with the reason (the PLC takes joint speeds only from its UDP remote interface), nothing written."""
    from app.net.snapshots import snapshot_from_wire, to_wire

    ses, plc = session, lab_plc
    pump(ses, connected)
    plc.set("MAIN.em8000.eState", "<b", STATE["ENGAGED"])
    plc.set("MAIN.em8000.eStatus", "<b", 4)  # WARNING
    plc.set("MAIN.em8000.eOpMode", "<b", 1)  # NORMAL
    plc.set("MAIN.em8000.bActive", "<?", True)
    plc.set("MAIN.mru1.bActive", "<?", True)
    plc.set("MAIN.comau.eMode", "<b", 1)  # REMOTE

    def shown(s) -> bool:
        m = s.platforms[0].motion
        return m is not None and (m.state, m.status, m.opmode) == ("ENGAGED", "WARNING", "NORMAL")

    snap = pump(ses, lambda s: shown(s) and s.comau.mode == "remote")
    assert snap.platforms[0].motion.word == 8 | 4 << 4 | 1 << 24
    assert snap.platforms[1].motion.state == "SETTLED"
    lights = {m.name: m.state for m in snap.machines}
    assert lights == {"em8000": "active", "em1500": "inactive", "comau": "inactive", "mru1": "active",
                      "mru2": "inactive", "tracker": "unknown", "remote": "unknown"}  # fmt: skip
    back = snapshot_from_wire(to_wire(snap))
    assert back.platforms[0].motion.status == "WARNING" and back.machines[0].detail == "MAIN.em8000.bActive True"
    arm(ses)
    before = list(ses.plant.bridge.stats.written)
    with pytest.raises(CommandError, match="UDP remote interface"):
        ses.command("lab_comau_jog", joint=1, speed=0.5)
    ses.command("lab_comau_jog", joint=1, speed=0.0)  # a stop is taken (nothing to send)
    pump(ses, lambda s: True)
    assert list(ses.plant.bridge.stats.written) == before and ses.snapshot().comau_jog.joint == 0
    # issue 16, item 4: the estimator and anti-swing run on the simulated lab only (the lab's runs in its PLC)
    with pytest.raises(CommandError, match="anti-swing: the plc plant has none"):
        ses.command("lab_antisway", action="activate")
    assert ses.snapshot().swing is None
    # issue 17, item 2: the PLC's wave simulator takes w0, lambda, sigma only
    with pytest.raises(CommandError, match="takes no RAO table"):
        ses.command("set_vessel", vessel="supply-closed-form")
    assert ses.describe().vessels == []


@pytest.mark.slow
def test_link_loss_and_recovery_stop_latched_and_resent_nothing_replayed(lab_plc, session):
    ses, plc = session, lab_plc
    pump(ses, connected)
    ses.command("lab_platform", platform="em8000", action="neutral")  # written before the gap
    settle_until(lambda: plc.get("MAIN.em8000.eModeCmd", "<b") == NEUTRAL)
    arm(ses)
    plc.stop()  # the PLC is gone
    snap = pump(ses, lambda s: s.plant.link == "lost", sample=stick(True))  # enable held throughout
    assert not snap.plant.connected and snap.plant.last_error
    assert any(a.key == "plc_link" and a.active for a in snap.alarms)
    assert not snap.flags.armed  # disarmed on link loss
    arm(ses)  # the operator arms again during the gap
    with pytest.raises(CommandError, match=r"link is lost.*nothing is queued"):
        ses.command("lab_platform", platform="em1500", action="neutral")
    ses.estop("test during the gap")  # latched here at once
    assert ses.snapshot().estop
    with pytest.raises(CommandError, match="reset refused"):
        ses.reset()
    t_lost = time.monotonic()
    pump(ses, lambda s: time.monotonic() - t_lost > 3.0)
    tries = [t for t in ses.plant.bridge.stats.attempts if t >= t_lost - 1.0]
    gaps = np.diff(tries)  # the first includes the failing attempt's own timeout; the waits then double
    assert 3 <= len(tries) <= 8 and gaps[-1] >= 1.5 * gaps[1]
    # the PLC comes back having forgotten the STOP; what was written before the gap was changed meanwhile
    plc.set_quietly("MAIN.bStop", "<?", False)
    plc.set_quietly("MAIN.em8000.eModeCmd", "<b", SETTLED)
    before = {n: plc.var(n).value for n in lab_declarations()}
    plc.start()
    snap = pump(ses, lambda s: connected(s) and s.plant.stop_written, sample=stick(True))
    assert snap.plant.reconnects == 1 and snap.estop and not snap.flags.armed  # disarmed on reconnect too
    assert plc.get("MAIN.bStop", "<?") is True  # STOP re-sent on reconnect
    changed = {n for n in lab_declarations() if plc.var(n).value != before[n]}
    assert changed <= {"MAIN.bStop", "MAIN.winch.u"}  # and nothing else: eModeCmd not replayed
    assert plc.get("MAIN.em8000.eModeCmd", "<b") == SETTLED
    ses.reset()
    settle_until(lambda: not plc.get("MAIN.bStop", "<?"))
    assert not ses.snapshot().estop


@pytest.mark.slow
def test_a_plc_error_is_shown_and_acknowledged_as_the_lab_hmi_does(lab_plc, session):
    ses, plc = session, lab_plc
    pump(ses, connected)
    with pytest.raises(CommandError, match="no error"):
        ses.command("lab_plc_ack")
    plc.set("MAIN.eState", "<h", 0)  # STOP: not NORMAL
    plc.set("MAIN.em1500.eStatus", "<b", 8)  # ERROR
    plc.set("MAIN.em1500.bError", "<?", True)
    plc.set_quietly("MAIN.em1500.eModeCmd", "<b", GENERATOR)
    snap = pump(ses, lambda s: "em1500 ERROR" in s.plant.plc_error and "PLC in STOP" in s.plant.plc_error)
    assert any(a.key == "plc_error" and a.active and a.severity == "critical" for a in snap.alarms)
    ses.estop("test")
    with pytest.raises(CommandError, match="E-STOP is latched"):  # an acknowledgement never undoes a STOP
        ses.command("lab_plc_ack")
    ses.reset()
    ses.command("lab_plc_ack", platform="em1500")
    settle_until(lambda: plc.get("MAIN.em1500.eModeCmd", "<b") == SETTLED)
    assert plc.get("MAIN.em1500.bStart", "<?") is False
    pump(ses, lambda s: written(ses, "MAIN.em1500.bReset")[-2:] == [True, False])
    resets = written(ses, "MAIN.bReset")  # the E-STOP's reset and the acknowledgement: pulses, FALSE at the end
    assert resets.count(True) == 2 and resets[-1] is False and not plc.get("MAIN.bReset", "<?")
    assert any("PLC error acknowledged" in e.text for e in ses.log)
    plc.set("MAIN.eState", "<h", 1)
    plc.set("MAIN.em1500.eStatus", "<b", 0)
    plc.set("MAIN.em1500.bError", "<?", False)
    snap = pump(ses, lambda s: s.plant.plc_error == "")
    assert not any(a.key == "plc_error" and a.active for a in snap.alarms)


@pytest.mark.slow
def test_a_symbol_of_another_size_is_named_and_never_written():
    pytest.importorskip("pyads")
    decl = lab_declarations()
    decl["MAIN.em8000.sineAmplitude"] = "ARRAY[1..6] OF REAL"  # 24 bytes: not what Bosun writes
    decl["MAIN.em1500.eModeCmd"] = "INT"  # an enumeration declared 2 bytes wide: taken from the PLC
    del decl["MAIN.mru2.bActive"]  # a PLC without the second MRU
    plc = LabPlc(free_loopback(), decl)
    plc.start()
    ses = make_session(plc)
    try:
        snap = pump(ses, connected)
        problems = sorted(snap.plant.problems)
        assert len(problems) == 2 and "MAIN.em8000.sineAmplitude: 24 bytes" in problems[0]
        assert problems[1].startswith("MAIN.mru2.bActive: not on the PLC")
        assert any(a.key == "plc_symbols" and a.active for a in snap.alarms)
        with pytest.raises(CommandError, match="sineAmplitude is not usable"):
            ses.command("lab_source", platform="em8000", source="generator", amplitude=[0, 0, 0.1, 0, 0, 0])
        ses.command("lab_platform", platform="em1500", action="neutral")
        settle_until(lambda: plc.get("MAIN.em1500.eModeCmd", "<h") == NEUTRAL)  # two bytes written
        assert plc.get("MAIN.em8000.sineAmplitude", "<6f") == [0.0] * 6
    finally:
        ses.close()
        plc.stop()


@pytest.mark.slow
def test_bosun_server_drives_the_plc_end_to_end(lab_plc):
    """``bosun server --plant lab --plc …`` as its own process; this test is the operator."""
    from app.net.transport import Client
    from tests.helpers import reported_url, wait_for

    plc = lab_plc
    exe = str(Path(sys.executable).with_name("bosun"))
    cmd = [exe, "server", "--plant", "lab", "--bind", "tcp://127.0.0.1:0", "--duration", "120"]
    cmd += ["--plc", f"{plc.ip}.1.1:851"]
    srv = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = reported_url(srv, lines=8)
        op = Client(url, role="operator", name="test-operator", timeout=10)
        try:
            assert op.describe().backend == "plc"
            wait_for(op, lambda s: s.plant is not None and s.plant.link == "ok", timeout=30)
            op.request("lab_platform", platform="em8000", action="neutral")
            settle_until(lambda: plc.get("MAIN.em8000.eModeCmd", "<b") == NEUTRAL)
            plc.set_quietly("MAIN.em8000.eState", "<b", STATE["NEUTRAL"])  # seen by the 1 s refresh read
            wait_for(op, lambda s: s.platforms[0].status == "neutral", timeout=15)
            op.request("estop", reason="test")
            settle_until(lambda: plc.get("MAIN.bStop", "<?"))
            assert wait_for(op, lambda s: s.estop and s.plant.stop_written, timeout=15).estop
            op.request("reset")
            settle_until(lambda: not plc.get("MAIN.bStop", "<?"))
        finally:
            op.close()
    finally:
        srv.terminate()
        _, err = srv.communicate(timeout=20)
    assert srv.returncode == 0, err


# ---------------------------------------------------------------------------- issue 27: STOP unusable, invalid data
def nonfinite(wire, path: str = "") -> list[str]:
    """The paths of every number in a wire form that is not finite."""
    if isinstance(wire, dict):
        return [p for k, v in wire.items() for p in nonfinite(v, f"{path}.{k}")]
    if isinstance(wire, list | tuple):
        return [p for i, v in enumerate(wire) for p in nonfinite(v, f"{path}[{i}]")]
    if isinstance(wire, float) and not math.isfinite(wire):
        return [path]
    return []


REST_WRITES = {"bStart": b"\x00", "bReset": b"\x00", "bResetScale": b"\x00", "u": struct.pack("<f", 0.0)}


def motion_writes(plc: LabPlc) -> list[str]:
    """What a client wrote to the test server that could start motion: anything but a stop or a rest value."""
    return [f"{n} := {v.hex()}" for _, n, v in plc.writes if REST_WRITES.get(n.rsplit(".", 1)[1]) != v]


@pytest.mark.slow
def test_item27_1_a_stop_that_cannot_reach_the_plc_refuses_every_motion_command():
    """Issue 27, item 1: ``MAIN.bStop`` declared INT.  Bosun names it (problem, plc_error, alarm) and, the
    link up, refuses with one line every command that could start motion; the stick cannot be armed; an
    E-STOP says it latched here only and its reset is refused.  Stops (DISENGAGE, Comau SETTLED, the winch let
    go) are taken.  The server's log holds no write but those stops and the rest values of the connect."""
    pytest.importorskip("pyads")
    decl = lab_declarations()
    decl["MAIN.bStop"] = "INT"
    plc = LabPlc(free_loopback(), decl)
    plc.start()
    ses = make_session(plc)
    try:
        plc.set("MAIN.winch.eMode", "<b", 1)  # LOCAL: the slider would drive it
        snap = pump(ses, lambda s: connected(s) and s.winch.mode == "local")
        assert snap.plant.problems == ["MAIN.bStop: 2 bytes (INT) on the PLC, Bosun expects 1 (BOOL)"]
        assert "STOP does not reach the PLC" in snap.plant.plc_error
        assert any(a.key == "plc_error" and a.active and a.severity == "critical" for a in snap.alarms)
        refused = [
            ("lab_platform", {"platform": "em8000", "action": "neutral"}),
            ("lab_platform", {"platform": "em1500", "action": "settle"}),
            ("lab_platform", {"platform": "em1500", "action": "engage"}),
            ("lab_comau_mode", {"mode": "remote"}),
            ("lab_winch", {"mode": "local"}),
            ("lab_winch", {"speed": 0.5}),
            ("lab_source", {"platform": "em8000", "source": "generator"}),
            ("lab_source", {"platform": "em1500", "source": "simulation", "hs": 2.0, "tp": 8.0}),
            ("lab_remote_pose", {"platform": "em8000", "eta": [0.0, 0.0, 0.05, 0.0, 0.0, 0.0]}),
            ("lab_plc_ack", {}),
        ]
        for name, fields in refused:
            with pytest.raises(CommandError, match=r"^motion refused: STOP does not reach the PLC") as err:
                ses.command(name, **fields)
            assert "\n" not in str(err.value) and "nothing was sent" in str(err.value), name
        assert snap.plant.motion_refused.startswith("STOP does not reach the PLC (MAIN.bStop: 2 bytes (INT)")
        # the stick: the arming gesture (neutral, enable released, then pressed) does not arm it
        t0 = time.monotonic()
        pump(ses, lambda s: time.monotonic() - t0 > 0.3, sample=stick(False))
        snap = pump(ses, lambda s: time.monotonic() - t0 > 1.0, sample=stick(True))
        assert not snap.flags.armed and not snap.flags.enabled and "motion refused" in snap.flags.input_reason
        with pytest.raises(CommandError, match="Comau jog"):  # (never taken over ADS in any case)
            ses.command("lab_comau_jog", joint=1, speed=0.5)
        # stops are taken
        ses.command("lab_platform", platform="em8000", action="disengage")
        ses.command("lab_comau_mode", mode="settled")
        pump(ses, lambda s: written(ses, "MAIN.comau.bStart") == [False])
        # the E-STOP latches here and says it does not reach the PLC; its reset is refused
        ses.estop("test")
        snap = pump(ses, lambda s: s.estop)
        assert not snap.plant.stop_written
        assert any("E-STOP latched here only: STOP does not reach the PLC" in e.text for e in ses.log)
        with pytest.raises(CommandError, match=r"MAIN\.bStop is not usable"):
            ses.reset()
        assert ses.snapshot().estop
        assert motion_writes(plc) == [] and plc.get("MAIN.em8000.eModeCmd", "<b") == SETTLED
        assert plc.get("MAIN.bStop", "<h") == 0  # never written: Bosun does not write what it would misread
    finally:
        ses.close()
        plc.stop()


def stewart_hmi(eta, state: str = "NEUTRAL") -> tuple:
    """``ST_TxHmiStewart``: status, eta, etaRef (0), cyl, dofScale."""
    return (STATE[state], *eta, *[0.0] * 6, *[0.3] * 6, *[1.0] * 6)


def comau_hmi(q) -> tuple:
    return (*q, *[0.0] * 6, *[-2.0] * 6, *[2.0] * 6)


@pytest.mark.slow
def test_item27_7_invalid_plc_values_are_held_flagged_and_refuse_motion(lab_plc, session):
    """Issue 27, item 7: a NaN, an infinity or a value beyond the machine's physical range (a pose beyond
    the platform's stroke, a joint beyond its limit, the wire beyond its soft ends) is refused as it
    arrives: the link reads ``invalid``, the symbol is named, a critical alarm is raised, the last valid
    value is held (its device's light stale), no snapshot carries a non-finite number, and motion commands
    are refused; once the value is valid again for 1 s the link is ``ok`` and commands are taken."""
    ses, plc = session, lab_plc
    eta = [0.01, -0.02, 0.05, 0.01, -0.02, 0.03]
    q = [0.1, -0.2, -1.5, 0.0, 0.0, 0.0]
    plc.set_quietly("MAIN.em8000.txHmi", "<i24f", *stewart_hmi(eta))
    plc.set_quietly("MAIN.comau.txHmi", "<24f", *comau_hmi(q))
    plc.set_quietly("MAIN.winch.lengthUtilization", "<f", 50.0)
    plc.set("MAIN.comau.bActive", "<?", True)  # the Comau talks: its joints' ranges hold
    w = ses.layout.winch
    half = w["min_length"] + 0.5 * (w["max_length"] - w["min_length"])
    snap = pump(ses, lambda s: connected(s) and abs(s.winch.length - half) < 1e-6 and abs(s.comau.q[0] - 0.1) < 1e-6)
    assert snap.platforms[0].eta == pytest.approx(eta, abs=1e-6)
    cases = [
        ("MAIN.em8000.txHmi", "<i24f", stewart_hmi([*eta[:3], math.nan, *eta[4:]]), "eta[4] = nan", "em8000"),
        ("MAIN.em8000.txHmi", "<i24f", stewart_hmi([*eta[:2], 2.0, *eta[3:]]), "eta[3] = 2 m/rad, outside", "em8000"),
        ("MAIN.em8000.txHmi", "<i24f", stewart_hmi([math.inf, *eta[1:]]), "eta[1] = inf", "em8000"),
        ("MAIN.comau.txHmi", "<24f", comau_hmi([math.inf, *q[1:]]), "q[1] = inf", "comau"),
        ("MAIN.comau.txHmi", "<24f", comau_hmi([q[0], 2.5, *q[2:]]), "q[2] = 2.5 rad, outside", "comau"),
        ("MAIN.winch.lengthUtilization", "<f", (-math.inf,), "lengthUtilization = -inf", None),
        ("MAIN.winch.lengthUtilization", "<f", (250.0,), "lengthUtilization = 250 %, outside", None),
    ]
    good = {"MAIN.em8000.txHmi": stewart_hmi(eta), "MAIN.comau.txHmi": comau_hmi(q)}
    good["MAIN.winch.lengthUtilization"] = (50.0,)
    for name, fmt, values, text, light in cases:
        plc.set_quietly(name, fmt, *values)
        snap = pump(ses, lambda s: s.plant.link == "invalid")  # before issue 27: "ok", the value passed on
        assert len(snap.plant.invalid) == 1 and snap.plant.invalid[0].startswith(f"{name}")
        assert text in snap.plant.invalid[0] and "holding the last valid value" in snap.plant.invalid[0]
        assert nonfinite(to_wire(snap)) == []
        assert snap.platforms[0].eta == pytest.approx(eta, abs=1e-6) and snap.comau.q == pytest.approx(q[:3], abs=1e-6)
        assert snap.winch.length == pytest.approx(half, abs=1e-6)  # the last valid values, held
        alarm = next(a for a in snap.alarms if a.key == "plc_invalid")
        assert alarm.active and alarm.severity == "critical" and text in alarm.text
        if light is not None:
            assert next(m for m in snap.machines if m.name == light).state == "stale"
        assert snap.plant.motion_refused.startswith("the PLC sends invalid data")
        with pytest.raises(CommandError, match=r"^motion refused: the PLC sends invalid data \(MAIN\.") as err:
            ses.command("lab_platform", platform="em1500", action="neutral")
        assert "\n" not in str(err.value)
        assert any(e.text.startswith("PLC data invalid:") for e in ses.log)
        plc.set_quietly(name, fmt, *good[name])
        snap = pump(ses, lambda s: s.plant.link == "ok")
        assert not any(a.key == "plc_invalid" and a.active for a in snap.alarms) and snap.plant.invalid == []
    assert nonfinite(to_wire(ses.snapshot())) == [] and ses.plant.bad_values >= len(cases)  # each read counted
    assert not [v for _, n, v in lab_plc.writes if n == "MAIN.em1500.eModeCmd"]  # every refusal: nothing sent
    ses.command("lab_platform", platform="em1500", action="neutral")  # valid again: taken
    settle_until(lambda: plc.get("MAIN.em1500.eModeCmd", "<b") == NEUTRAL)


def test_item27_7_values_are_checked_against_the_machines_ranges():
    """The check itself: finite, and within the platform's stroke, the joints' limits and the wire's range."""
    from app.engine.lab_session import LabSession
    from app.plant.plc import value_ranges
    from app.plc.symbols import check_value, lab_symbols

    lab = LabSession().lab
    ranges, syms = value_ranges(lab, ("em8000", "em1500")), lab_symbols()
    hmi = syms["MAIN.em8000.txHmi"]
    settled = lab.platforms[0].settled_pose.tolist()
    value = {"status": 2, "eta": settled, "etaRef": [0.0] * 6, "cyl": [0.0] * 6, "dofScale": [1.0] * 6}
    assert check_value(hmi, value, ranges[hmi.name]) == (0, "")  # the settled pose is within the stroke
    top = lab.models[0].pose_max.tolist()
    assert check_value(hmi, value | {"eta": top}, ranges[hmi.name]) == (0, "")  # so is the Table 8 box's edge
    bad, text = check_value(hmi, value | {"eta": [0.0, 0.0, top[2] + 0.2, 0, 0, 0]}, ranges[hmi.name])
    assert bad == 1 and text.startswith("MAIN.em8000.txHmi.eta[3] = 1.085 m/rad, outside")
    bad, text = check_value(hmi, value | {"etaRef": [math.nan] * 6, "dofScale": [math.inf, 1, 1, 1, 1, 1]})
    assert bad == 7 and text == "MAIN.em8000.txHmi.etaRef[1] = nan (not a finite number) (and 6 more)"
    comau = syms["MAIN.comau.txHmi"]
    q = {"q": [0.0, 0.0, -1.5, 9.0, -9.0, 30.0], "u": [0.1] * 6, "qMin": [-1.0] * 6, "qMax": [1.0] * 6}
    assert check_value(comau, q, ranges[comau.name]) == (0, "")  # joints 4-6: finite only
    r = lab.robot
    for i, v in ((0, r.upper[0] + 0.2), (2, r.lower[2] - 0.2)):
        qq = list(q["q"])
        qq[i] = float(v)
        assert check_value(comau, q | {"q": qq}, ranges[comau.name])[1].startswith(f"MAIN.comau.txHmi.q[{i + 1}]")
    assert check_value(comau, q | {"u": [5.0, 0, 0, 0, 0, 0]}, ranges[comau.name])[0] == 1  # faster than possible
    util = syms["MAIN.winch.lengthUtilization"]
    assert check_value(util, 100.0, ranges[util.name]) == (0, "")
    text = "MAIN.winch.lengthUtilization = 120 %, outside -5 … 105 %"
    assert check_value(util, 120.0, ranges[util.name]) == (1, text)
    assert check_value(syms["MAIN.eState"], 7) == (0, "")  # integers are always finite


# ---------------------------------------------------------------------------- the GUI's part
@needs_qt
@pytest.mark.gui
def test_lab_tab_shows_the_plc_link_and_its_error_with_acknowledge(qtbot):
    """A light for the link, a bar (never a modal box) with Acknowledge while the PLC reports an error."""
    import dataclasses

    from PyQt5.QtCore import Qt

    from app.engine.lab_session import LabSession
    from app.net.snapshots import PlantLink
    from ui.lab_tab import MotionLabTab

    class Link:
        def __init__(self) -> None:
            self.sent: list = []

        def send(self, mtype, **fields):
            self.sent.append((mtype, fields))

    tab = MotionLabTab(use_gl=False)
    qtbot.addWidget(tab)
    tab.link = Link()
    lights = []
    tab.plc_link.connect(lambda state, detail: lights.append((state, detail)))
    ses = LabSession()
    tab.on_description(ses.describe())
    snap = ses.snapshot()
    tab.on_state(snap)
    # no PLC: the plant is simulated (it read "PLC: simulated", as if a PLC were simulated; issue 26, item 6)
    assert lights[-1] == ("off", "none: simulated plant") and tab.plc_bar.isHidden()
    err = PlantLink(backend="plc", link="ok", connected=True, plc_state="STOP", plc_error="PLC in STOP; em1500 ERROR")
    tab.on_state(dataclasses.replace(snap, plant=err))
    assert lights[-1][0] == "error" and "em1500 ERROR" in lights[-1][1]
    assert not tab.plc_bar.isHidden() and "em1500 ERROR" in tab.plc_text.text()
    assert tab.plc_ack.focusPolicy() == Qt.NoFocus and tab.plc_ack.isEnabled()
    qtbot.mouseClick(tab.plc_ack, Qt.LeftButton)
    assert tab.link.sent[-1] == ("lab_plc_ack", {})
    tab.on_state(dataclasses.replace(snap, plant=err, estop=True))
    assert not tab.plc_ack.isEnabled()  # the E-STOP's reset resets the PLC first
    lost = PlantLink(backend="plc", link="lost", last_error="the PLC did not answer within the ADS timeout")
    tab.on_state(dataclasses.replace(snap, plant=lost))
    assert lights[-1] == ("error", "LOST: the PLC did not answer within the ADS timeout") and tab.plc_bar.isHidden()
    page = tab.lights.lights  # the page's own row: the PLC light, and a plant nothing is known of
    assert page["plc"].state == "error" and page["plant"].text() == "● plant: unknown: PLC link lost"
    winch = dataclasses.replace(snap.winch, mode="settled")  # a PLC mode Bosun does not offer: shown, no crash
    tab.on_state(dataclasses.replace(snap, plant=err, winch=winch))
