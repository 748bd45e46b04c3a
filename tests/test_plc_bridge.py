"""Issue 16, item 1: the Motion-Lab's PLC bridge against pyads' own ADS test server on loopback.

The test server (``pyads.testserver.AdsTestServer`` with its ``AdvancedHandler``) plays the lab's
TwinCAT PLC: it serves the lab's symbols with the lab's types (declared below, from the lab's HMI and
PLC project as summarised in motionlab_plc.json, Norwegian Motion-Laboratory repository, commit
f5fbf84, MIT: structs as bytes), on its own loopback address (127.77.x.y, port 48898 as ADS has it).
The real bridge and a real :class:`LabSession` (and, once, a real ``bosun server`` process) talk to it.

pyads' test server quirks the fixtures work around: it delivers device notifications by calling the
client's callbacks in-process (so a value the "PLC" sets reaches a subscriber in this process; the
``bosun server`` process sees it through the bridge's 1 s refresh reads) and numbers every symbol's
notifications from 10, which would collide in pyads' callback store: each symbol gets its own range.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from app.engine.scene import CommandError
from tests.helpers import ROOT, needs_qt

REFERENCE = ROOT.parent / "shared" / "data" / "motionlab_plc.json"

BASE_SIZE = {"BOOL": 1, "SINT": 1, "INT": 2, "DINT": 4, "REAL": 4, "LREAL": 8}
STRUCT_SIZE = {"ST_TxHmiStewart": 4 + 4 * 6 * 4, "ST_TxHmiComau": 4 * 6 * 4}
SETTLED, NEUTRAL, GENERATOR, SIMULATION = 0, 1, 3, 2  # E_StewartMode
STATE = {"SETTLED": 2, "NEUTRAL": 4, "ENGAGED": 8}  # E_StewartState


def lab_declarations() -> dict[str, str]:
    """The PLC side: every symbol the lab's HMI uses, with its IEC type (the test server's variables).

    Names and given types from motionlab_plc.json (``ads_hmi``); the rest as the bridge assumes
    (enumerations SINT like eModeCmd, MAIN.eState INT, REAL speeds and utilisation)."""
    d = {"MAIN.eState": "INT", "MAIN.bStop": "BOOL", "MAIN.bReset": "BOOL"}
    for p in ("em8000", "em1500"):
        m = f"MAIN.{p}"
        d |= {f"{m}.{n}": "BOOL" for n in ("bActive", "bError", "bBusy", "bStart", "bReset", "bResetScale")}
        d |= {f"{m}.{n}": "SINT" for n in ("eState", "eStatus", "eOpMode", "eMode", "eModeCmd")}
        d[f"{m}.txHmi"] = "ST_TxHmiStewart"
        d |= {f"{m}.{n}": "ARRAY[1..6] OF LREAL" for n in ("sineAmplitude", "sineOmega", "sinePhase")}
        d |= {f"{m}.hydro.stInput.{n}": "LREAL" for n in ("w0", "lambda", "sigma")}
        d[f"{m}.uRemote"] = "ARRAY[1..6] OF REAL"
    d |= {"MAIN.comau.bActive": "BOOL", "MAIN.comau.eMode": "SINT", "MAIN.comau.txHmi": "ST_TxHmiComau"}
    d |= {"MAIN.comau.bStart": "BOOL", "MAIN.winch.bActive": "BOOL", "MAIN.winch.eMode": "SINT"}
    d |= {"MAIN.winch.lengthUtilization": "REAL", "MAIN.winch.eModeCmd": "SINT", "MAIN.winch.bEnable": "BOOL"}
    d |= {"MAIN.winch.u": "REAL", "MAIN.mru1.bActive": "BOOL", "MAIN.mru2.bActive": "BOOL"}
    return d


def size_of(iec: str) -> int:
    if iec in BASE_SIZE:
        return BASE_SIZE[iec]
    if iec in STRUCT_SIZE:
        return STRUCT_SIZE[iec]
    m = re.fullmatch(r"ARRAY\[1\.\.(\d+)\] OF (\w+)", iec)
    return int(m.group(1)) * BASE_SIZE[m.group(2)]


_next_address = [0]


def free_loopback() -> str:
    """A loopback address of its own for each test server (port 48898 is fixed by ADS)."""
    for _ in range(200):
        _next_address[0] += 1
        ip = f"127.77.{os.getpid() % 200 + 1}.{_next_address[0] % 250 + 1}"
        with socket.socket() as s:
            try:
                s.bind((ip, 48898))
                return ip
            except OSError:
                continue
    pytest.skip("no free loopback address for an ADS test server")


def symbol_handler():
    """pyads' AdvancedHandler answering a name it does not hold as TwinCAT does (ADS error 0x710, symbol
    not found) instead of raising in its connection thread (which leaves the client to time out)."""
    from pyads import constants
    from pyads.testserver import AdvancedHandler
    from pyads.testserver.handler import AmsResponseData

    class Handler(AdvancedHandler):
        def handle_request(self, request):
            head = request.ams_header
            if struct.unpack("<H", head.command_id)[0] == constants.ADSCOMMAND_READWRITE:
                group, _, _, n = struct.unpack("<IIII", head.data[:16])
                if group in (constants.ADSIGRP_SYM_INFOBYNAMEEX, constants.ADSIGRP_SYM_HNDBYNAME):
                    name = head.data[16 : 16 + n].decode().strip("\x00")
                    if not any(v.name == name for v in self._data.values()):
                        state = struct.pack("<H", struct.unpack("<H", head.state_flags)[0] | 1)
                        return AmsResponseData(state, head.error_code, struct.pack("<II", 0x710, 0))
            return super().handle_request(request)

    return Handler()


class LabPlc:
    """pyads' ADS test server serving the lab's symbols; ``stop`` and ``start`` again on the same address."""

    def __init__(self, ip: str, declarations: dict[str, str] | None = None) -> None:
        from pyads import constants
        from pyads.testserver import PLCVariable

        adst = {
            "BOOL": constants.ADST_BIT,
            "SINT": constants.ADST_INT8,
            "INT": constants.ADST_INT16,
            "REAL": constants.ADST_REAL32,
            "LREAL": constants.ADST_REAL64,
        }
        self.ip, self.server = ip, None
        self.handler = symbol_handler()
        for k, (name, iec) in enumerate((declarations or lab_declarations()).items()):
            var = PLCVariable(name, bytes(size_of(iec)), adst.get(iec, constants.ADST_BIGTYPE), iec)
            var.notification_count = 1000 * (k + 1)  # see the module's docstring
            self.handler.add_variable(var)
        self.set("MAIN.eState", "<h", 1)  # NORMAL
        for p in ("em8000", "em1500"):
            self.set(f"MAIN.{p}.eState", "<b", STATE["SETTLED"])

    def start(self) -> None:
        from pyads.testserver import AdsTestServer

        self.server = AdsTestServer(handler=self.handler, ip_address=self.ip, logging=False)
        self.server.start()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:  # listening (the server thread calls listen() a moment later)
            with contextlib.suppress(OSError), socket.create_connection((self.ip, 48898), timeout=0.5):
                return
            time.sleep(0.05)
        raise AssertionError("the ADS test server did not start")

    def stop(self) -> None:
        if self.server is not None:
            self.server.stop()
            self.server.join(timeout=5)
            self.server = None

    def var(self, name: str):
        return self.handler.get_variable_by_name(name)

    def get(self, name: str, fmt: str):
        raw = self.var(name).value
        assert len(raw) == struct.calcsize(fmt), f"{name}: {len(raw)} bytes written, {fmt} expected"
        v = struct.unpack(fmt, raw)
        return v[0] if len(v) == 1 else list(v)

    def set(self, name: str, fmt: str, *values) -> None:
        """The PLC changes a value: subscribers in this process are notified (as on change)."""
        self.var(name).write(struct.pack(fmt, *values))

    def set_quietly(self, name: str, fmt: str, *values) -> None:
        self.var(name).value = struct.pack(fmt, *values)


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
    from tests.helpers import wait_for

    plc = lab_plc
    exe = str(Path(sys.executable).with_name("bosun"))
    cmd = [exe, "server", "--plant", "lab", "--bind", "tcp://127.0.0.1:0", "--duration", "120"]
    cmd += ["--plc", f"{plc.ip}.1.1:851"]
    srv = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = None
        for _ in range(8):
            m = re.search(r"requests on (tcp://\S+),", srv.stdout.readline())
            if m:
                url = m.group(1)
                break
        assert url, "server did not report its address"
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
