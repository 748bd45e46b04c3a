"""The lab's PLC played by pyads' own ADS test server, for the tests and ``bosun bench plc-soak``.

pyads' test server (``pyads.testserver.AdsTestServer`` with its ``AdvancedHandler``) serves the lab's
symbols with the lab's types (:func:`lab_declarations`, from the lab's HMI and PLC project as summarised in
motionlab_plc.json, Norwegian Motion-Laboratory repository, commit f5fbf84, MIT: structs as bytes), on a
loopback address of its own (127.77.x.y, port 48898 as ADS has it).  Nothing here speaks ADS itself: the
handler below only answers a name it does not hold as TwinCAT does, can answer late (a slow PLC), and logs
what clients write.

The server's quirks worked around: it delivers device notifications by calling the client's callbacks
in-process (so a value the "PLC" sets reaches a subscriber in this process; another process sees it
through the bridge's 1 s refresh reads) and numbers every symbol's notifications from 10, which would
collide in pyads' callback store: each symbol gets its own range.

Needs the ``plc`` extra (pyads); imported only by those who use it.
"""

from __future__ import annotations

import contextlib
import os
import re
import socket
import struct
import time
from typing import Any

from app.errors import BosunError

BASE_SIZE = {"BOOL": 1, "SINT": 1, "INT": 2, "DINT": 4, "REAL": 4, "LREAL": 8}
STRUCT_SIZE = {"ST_TxHmiStewart": 4 + 4 * 6 * 4, "ST_TxHmiComau": 4 * 6 * 4}
STATE = {"SETTLED": 2, "NEUTRAL": 4, "ENGAGED": 8}  # E_StewartState


class TestPlcError(BosunError):
    """The test server could not be started (no free loopback address, or it did not listen)."""

    __test__ = False  # not a pytest test class


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
    """Bytes of an IEC type of :func:`lab_declarations`."""
    if iec in BASE_SIZE:
        return BASE_SIZE[iec]
    if iec in STRUCT_SIZE:
        return STRUCT_SIZE[iec]
    m = re.fullmatch(r"ARRAY\[1\.\.(\d+)\] OF (\w+)", iec)
    if m is None:
        raise TestPlcError(f"unknown IEC type {iec!r}")
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
    raise TestPlcError("no free loopback address for an ADS test server")


def symbol_handler() -> Any:
    """pyads' AdvancedHandler answering a name it does not hold as TwinCAT does (ADS error 0x710, symbol
    not found) instead of raising in its connection thread (which leaves the client to time out); it waits
    ``delay`` seconds before each answer (a slow PLC) and logs every value a client writes in ``writes``
    as ``(time.monotonic(), name, bytes)``."""
    from pyads import constants
    from pyads.testserver import AdvancedHandler
    from pyads.testserver.handler import AmsResponseData

    class Handler(AdvancedHandler):
        delay = 0.0
        writes: list[tuple[float, str, bytes]]

        def handle_request(self, request):
            if self.delay > 0:
                time.sleep(self.delay)
            head = request.ams_header
            command = struct.unpack("<H", head.command_id)[0]
            if command == constants.ADSCOMMAND_READWRITE:
                group, _, _, n = struct.unpack("<IIII", head.data[:16])
                if group in (constants.ADSIGRP_SYM_INFOBYNAMEEX, constants.ADSIGRP_SYM_HNDBYNAME):
                    name = head.data[16 : 16 + n].decode().strip("\x00")
                    if not any(v.name == name for v in self._data.values()):
                        state = struct.pack("<H", struct.unpack("<H", head.state_flags)[0] | 1)
                        return AmsResponseData(state, head.error_code, struct.pack("<II", 0x710, 0))
            return super().handle_request(request)

    h = Handler()
    h.writes = []
    return h


class LabPlc:
    """pyads' ADS test server serving the lab's symbols; ``stop`` and ``start`` again on the same address.

    Parameters
    ----------
    ip : str              its loopback address (:func:`free_loopback`)
    declarations : dict   symbol name → IEC type (default :func:`lab_declarations`)
    """

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
        handler = symbol_handler()

        class Variable(PLCVariable):
            def write(self, value: bytes, request: Any = None) -> None:
                if request is not None:  # a client wrote it (the "PLC" itself sets values without a request)
                    handler.writes.append((time.monotonic(), self.name, bytes(value)))
                super().write(value, request)

        self.ip, self.server = ip, None
        self.handler = handler
        self.declarations = dict(declarations or lab_declarations())
        for k, (name, iec) in enumerate(self.declarations.items()):
            var = Variable(name, bytes(size_of(iec)), adst.get(iec, constants.ADST_BIGTYPE), iec)
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
        raise TestPlcError("the ADS test server did not start")

    def stop(self) -> None:
        if self.server is not None:
            self.server.stop()
            self.server.join(timeout=5)
            self.server = None

    @property
    def delay(self) -> float:
        """Seconds the server waits before each answer (0: at once)."""
        return float(self.handler.delay)

    @delay.setter
    def delay(self, seconds: float) -> None:
        self.handler.delay = float(seconds)

    @property
    def writes(self) -> list[tuple[float, str, bytes]]:
        """What clients wrote: ``(time.monotonic(), name, bytes)`` in order."""
        return self.handler.writes

    def var(self, name: str) -> Any:
        return self.handler.get_variable_by_name(name)

    def get(self, name: str, fmt: str) -> Any:
        raw = self.var(name).value
        if len(raw) != struct.calcsize(fmt):
            raise TestPlcError(f"{name}: {len(raw)} bytes written, {fmt} expected")
        v = struct.unpack(fmt, raw)
        return v[0] if len(v) == 1 else list(v)

    def set(self, name: str, fmt: str, *values: Any) -> None:
        """The PLC changes a value: subscribers in this process are notified (as on change)."""
        self.var(name).write(struct.pack(fmt, *values))

    def set_quietly(self, name: str, fmt: str, *values: Any) -> None:
        self.var(name).value = struct.pack(fmt, *values)
