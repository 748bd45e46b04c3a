"""The Motion-Lab PLC's ADS symbols: names, types, enumerations and the rates the lab's HMI uses.

Source: motionlab_plc.json (Norwegian Motion-Laboratory repository, commit f5fbf84, MIT), a summary of
the lab's TwinCAT project ``plc/MotionLab/LabController`` (``POUs/Interfaces/E_StewartMode.TcDUT``,
``FB_StewartInterface.TcPOU``, ``FB_WinchInterface.TcPOU``, the MAIN state chart) and of its PyQt HMI
``hmi/src`` (pyads: notifications for enums and flags, ``txHmi`` structs polled every 50 ms, writes by
name).  Every name, type and number below is from that summary unless marked **assumed**: the summary
does not give it, the value here is the most likely one, and the bridge checks each symbol's size
against the PLC's symbol table when it connects (:func:`check_size`), so a wrong guess is reported by
name and that symbol is never written.

Bosun needs none of the reference files at run time: this module is the table.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from typing import Any

#: the lab's CX2040 (``ads_hmi.ams_net_id``, ``ads_hmi.port``: the TwinCAT 3 PLC runtime 1)
AMS_NET_ID = "192.168.90.150.1.1"
AMS_PORT = 851
ADS_TCP_PORT = 48898  # the AMS router's TCP port (0xBF02), fixed by ADS
PLC_CYCLE = 0.005  # s: the lab PLC's task (``ads_hmi.plc_task``: Ts = 0.005 s)
POLL_STRUCT = 0.050  # s: ``MAIN.<dev>.txHmi`` (``ads_hmi.polled_structs``)
POLL_WINCH = 0.100  # s: ``MAIN.winch.lengthUtilization``
#: a momentary flag (``bReset``, ``bResetScale``) is held TRUE this long, then written FALSE: 40 PLC cycles
PULSE = 0.2
WINCH_SPEED_MAX = 0.2  # m/s: the HMI's winch slider, -100..100 → u = value/100 · 0.2 m/s (``winch``)
PLATFORMS = ("em8000", "em1500")

# ----------------------------------------------------------------------------- enumerations
#: E_StewartMode (the platform's ``eModeCmd``/``eMode``)
STEWART_MODE = {"SETTLED": 0, "NEUTRAL": 1, "SIMULATION": 2, "GENERATOR": 3, "REMOTE": 4}
#: E_StewartState (Rexroth motion status bits 0-3)
STEWART_STATE = {
    "TRANSIT": 0,
    "OFF": 1,
    "SETTLED": 2,
    "OIL_HEATING": 3,
    "NEUTRAL": 4,
    "NEUTRAL_FREEZE": 5,
    "ENGAGED": 8,
    "ENGAGED_FREEZE": 9,
}
#: E_StewartStatus (bits 4-7); anything but SYSTEM_OK sets the platform's bError
STEWART_STATUS = {"SYSTEM_OK": 0, "WARNING": 4, "ERROR": 8}
#: E_StewartOpMode (bits 24-31)
STEWART_OPMODE = {"MANUAL": 0, "NORMAL": 1}
COMAU_MODE = {"SETTLED": 0, "REMOTE": 1, "MOTION_COMP": 2}
WINCH_MODE = {"SETTLED": 0, "LOCAL": 1, "REMOTE": 2, "MOTION_COMP": 3}
#: MAIN.eState: the summary names NORMAL (the HMI raises its error box when eState <> NORMAL) and the
#: chart's STOP state; their values are **assumed** (the order of the chart: STOP, then NORMAL)
MAIN_STATE = {"STOP": 0, "NORMAL": 1}


def enum_name(table: dict[str, int], value: Any) -> str:
    """The name of an enumeration value, ``"?<value>"`` for one the table does not know, ``""`` for None."""
    if value is None:
        return ""
    for name, v in table.items():
        if v == value:
            return name
    return f"?{value}"


def decode_status(status: int) -> dict[str, str]:
    """The Rexroth motion status word of ``txHmi.status``: state (bits 0-3), status (4-7), op mode (24-31)."""
    s = int(status) & 0xFFFFFFFF
    return {
        "state": enum_name(STEWART_STATE, s & 0xF),
        "status": enum_name(STEWART_STATUS, (s >> 4) & 0xF),
        "opmode": enum_name(STEWART_OPMODE, (s >> 24) & 0xFF),
    }


def encode_status(state: str, status: str = "SYSTEM_OK", opmode: str = "NORMAL") -> int:
    """The status word :func:`decode_status` reads, from the three names (issue 16, item 5: the simulated
    platforms report their state in the same word as the Rexroth controllers)."""
    return STEWART_STATE[state] | (STEWART_STATUS[status] << 4) | (STEWART_OPMODE[opmode] << 24)


# ----------------------------------------------------------------------------- types
#: IEC 61131-3 elementary types as little-endian struct formats (TwinCAT on x86 / ARM: little endian)
TYPES = {"BOOL": "?", "SINT": "b", "INT": "h", "DINT": "i", "REAL": "f", "LREAL": "d"}
INTEGER_FORMATS = {1: "b", 2: "h", 4: "i"}


@dataclass(frozen=True)
class Symbol:
    """One PLC variable as Bosun uses it.

    Parameters
    ----------
    name : str        the ADS symbol name, e.g. ``MAIN.em8000.eModeCmd``
    plc_type : str    its IEC type as declared (``SINT``, ``ARRAY[1..6] OF LREAL``, ``ST_TxHmiStewart``)
    fmt : str         little-endian struct format of its bytes (``"<b"``, ``"<6d"``, ``"<i24f"``)
    access : str      ``notify`` (device notification on change), ``poll`` (read every ``period``), ``write``
    period : float    poll period [s] (``poll`` only)
    fields : tuple    for a struct: (field name, count) in order, decoded into a dict
    enum : bool       an enumeration (integer whose width the PLC may declare otherwise: 1, 2 or 4 bytes)
    """

    name: str
    plc_type: str
    fmt: str
    access: str
    period: float = 0.0
    fields: tuple[tuple[str, int], ...] = ()
    enum: bool = False

    @property
    def size(self) -> int:
        """Bytes on the PLC."""
        return struct.calcsize(self.fmt)

    def with_size(self, size: int) -> Symbol:
        """The same enumeration symbol with the integer width the PLC declares (1, 2 or 4 bytes)."""
        return Symbol(self.name, self.plc_type, "<" + INTEGER_FORMATS[size], self.access, self.period, (), True)

    def encode(self, value: Any) -> bytes:
        """The symbol's bytes for ``value`` (a scalar, a sequence for arrays, a dict for structs)."""
        if self.fields:
            flat: list[Any] = []
            for name, n in self.fields:
                v = value[name]
                flat.extend(v if n > 1 else [v])
            return struct.pack(self.fmt, *flat)
        if isinstance(value, list | tuple):
            return struct.pack(self.fmt, *value)
        return struct.pack(self.fmt, value)

    def decode(self, raw: bytes) -> Any:
        """A Python value from the symbol's bytes: bool, int, float, a list (arrays) or a dict (structs)."""
        vals = struct.unpack(self.fmt, bytes(raw[: self.size]))
        if self.fields:
            out: dict[str, Any] = {}
            i = 0
            for name, n in self.fields:
                out[name] = list(vals[i : i + n]) if n > 1 else vals[i]
                i += n
            return out
        return vals[0] if len(vals) == 1 else list(vals)


def check_size(sym: Symbol, plc_size: int, plc_type: str) -> tuple[Symbol | None, str]:
    """Compare a symbol with the PLC's declaration: (the symbol to use or None, a note or "").

    An enumeration may be declared 1, 2 or 4 bytes wide on the PLC: its width is taken from there.  Any
    other difference in size is refused: the bridge never reads or writes a symbol it would misread.
    """
    if plc_size == sym.size:
        return sym, ""
    if sym.enum and plc_size in INTEGER_FORMATS:
        return sym.with_size(plc_size), f"{sym.name}: {plc_type} is {plc_size} bytes on the PLC; taken as such"
    return None, f"{sym.name}: {plc_size} bytes ({plc_type}) on the PLC, Bosun expects {sym.size} ({sym.plc_type})"


# ----------------------------------------------------------------------------- values as they arrive
#: a range per element: (lows, highs, unit); ``-inf``/``inf`` where only finiteness is checked
Range = tuple[tuple[float, ...], tuple[float, ...], str]


def check_value(sym: Symbol, value: Any, ranges: dict[str, Range] | None = None) -> tuple[int, str]:
    """Check a decoded value (issue 27, item 7): every number finite, and within ``ranges`` where given.

    Parameters
    ----------
    sym : Symbol      the symbol the value was read from
    value : Any       :meth:`Symbol.decode`'s result: a scalar, a list (arrays) or a dict (structs)
    ranges : dict     field name (``""`` for a scalar or an array) → (lows, highs, unit), one bound per
                      element (a shorter tuple: the rest unbounded); absent fields are checked for
                      finiteness only

    Returns
    -------
    (bad, text) : (int, str)   how many numbers are wrong and one line naming the first, ``(0, "")`` when
                               the value can be used.  Integers and booleans are always finite.
    """
    ranges = ranges or {}
    fields = value.items() if isinstance(value, dict) else [("", value)]
    bad, first = 0, ""
    for field, v in fields:
        items = v if isinstance(v, list | tuple) else [v]
        lo, hi, unit = ranges.get(field, ((), (), ""))
        for i, x in enumerate(items):
            if isinstance(x, bool) or not isinstance(x, int | float):
                continue
            where = sym.name + (f".{field}" if field else "") + (f"[{i + 1}]" if isinstance(v, list | tuple) else "")
            if not math.isfinite(x):
                why = f"{where} = {x} (not a finite number)"
            elif i < len(lo) and not lo[i] <= x <= hi[i]:
                u = f" {unit}" if unit else ""
                why = f"{where} = {x:.4g}{u}, outside {lo[i]:.4g} … {hi[i]:.4g}{u}"
            else:
                continue
            bad += 1
            first = first or why
    if bad > 1:
        first += f" (and {bad - 1} more)"
    return bad, first


# ----------------------------------------------------------------------------- the lab's table
#: ST_TxHmiStewart: status DINT, eta REAL[6], etaRef REAL[6], cyl REAL[6], dofScale REAL[6]
TX_HMI_STEWART = (("status", 1), ("eta", 6), ("etaRef", 6), ("cyl", 6), ("dofScale", 6))
#: MAIN.comau.txHmi: **assumed** layout (the summary names its use: joint bars (q − qMin)/(qMax − qMin),
#: plots of the joint speed setpoint u and of q): q, u, qMin, qMax, REAL[6] each [rad, rad/s]
TX_HMI_COMAU = (("q", 6), ("u", 6), ("qMin", 6), ("qMax", 6))


def _sym(name: str, plc_type: str, access: str, period: float = 0.0) -> Symbol:
    if plc_type in TYPES:
        return Symbol(name, plc_type, "<" + TYPES[plc_type], access, period)
    raise ValueError(plc_type)  # pragma: no cover - a typo in the table below


def _enum(name: str, enum_type: str, base: str, access: str) -> Symbol:
    return Symbol(name, f"{enum_type} ({base})", "<" + TYPES[base], access, enum=True)


def _array(name: str, base: str, n: int, access: str) -> Symbol:
    return Symbol(name, f"ARRAY[1..{n}] OF {base}", f"<{n}{TYPES[base]}", access)


def lab_symbols() -> dict[str, Symbol]:
    """The Motion-Lab's symbols by name (``ads_hmi`` of motionlab_plc.json; types **assumed** where marked).

    Enumerations: ``eModeCmd`` is SINT (given); the other enumerations of the devices are taken as
    SINT too (assumed: E_StewartMode is declared SINT) and MAIN.eState as INT (assumed: TwinCAT's
    default base type) — the width of an enumeration is corrected from the PLC at connect.
    """
    syms: list[Symbol] = [
        _enum("MAIN.eState", "E_MainState", "INT", "notify"),
        _sym("MAIN.bStop", "BOOL", "write"),
        _sym("MAIN.bReset", "BOOL", "write"),
    ]
    for p in PLATFORMS:
        m = f"MAIN.{p}"
        syms += [
            _sym(f"{m}.bActive", "BOOL", "notify"),
            _enum(f"{m}.eState", "E_StewartState", "SINT", "notify"),
            _enum(f"{m}.eStatus", "E_StewartStatus", "SINT", "notify"),
            _enum(f"{m}.eOpMode", "E_StewartOpMode", "SINT", "notify"),
            _enum(f"{m}.eMode", "E_StewartMode", "SINT", "notify"),
            _sym(f"{m}.bError", "BOOL", "notify"),
            _sym(f"{m}.bBusy", "BOOL", "notify"),
            Symbol(f"{m}.txHmi", "ST_TxHmiStewart", "<i24f", "poll", POLL_STRUCT, TX_HMI_STEWART),
            _enum(f"{m}.eModeCmd", "E_StewartMode", "SINT", "write"),
            _sym(f"{m}.bStart", "BOOL", "write"),
            _sym(f"{m}.bReset", "BOOL", "write"),
            _sym(f"{m}.bResetScale", "BOOL", "write"),
            _array(f"{m}.sineAmplitude", "LREAL", 6, "write"),  # m, rad
            _array(f"{m}.sineOmega", "LREAL", 6, "write"),  # rad/s
            _array(f"{m}.sinePhase", "LREAL", 6, "write"),  # rad
            # the wave simulator's inputs (a Simulink TcCOM module: double, assumed LREAL)
            _sym(f"{m}.hydro.stInput.w0", "LREAL", "write"),  # peak frequency [rad/s]
            _sym(f"{m}.hydro.stInput.lambda", "LREAL", "write"),  # damping ratio [-]
            _sym(f"{m}.hydro.stInput.sigma", "LREAL", "write"),  # intensity [m/√s]
            # the REMOTE pose setpoint (FB input uRemote; REAL[6] assumed like the remote interface's f32)
            _array(f"{m}.uRemote", "REAL", 6, "write"),
        ]
    syms += [
        _sym("MAIN.comau.bActive", "BOOL", "notify"),
        _enum("MAIN.comau.eMode", "E_ComauMode", "SINT", "notify"),
        Symbol("MAIN.comau.txHmi", "ST_TxHmiComau", "<24f", "poll", POLL_STRUCT, TX_HMI_COMAU),
        _sym("MAIN.comau.bStart", "BOOL", "write"),
        _sym("MAIN.winch.bActive", "BOOL", "notify"),
        _enum("MAIN.winch.eMode", "E_WinchMode", "SINT", "notify"),
        _sym("MAIN.winch.lengthUtilization", "REAL", "poll", POLL_WINCH),  # % of the soft-end range (assumed REAL)
        _enum("MAIN.winch.eModeCmd", "E_WinchMode", "SINT", "write"),
        _sym("MAIN.winch.bEnable", "BOOL", "write"),
        _sym("MAIN.winch.u", "REAL", "write"),  # speed setpoint [m/s] (assumed REAL)
        _sym("MAIN.mru1.bActive", "BOOL", "notify"),
        _sym("MAIN.mru2.bActive", "BOOL", "notify"),
    ]
    return {s.name: s for s in syms}


# ----------------------------------------------------------------------------- the wave simulator
@dataclass(frozen=True)
class WaveInputs:
    """Inputs of the PLC's wave simulator (``MAIN.<platform>.hydro.stInput``), read here as the linear
    wave-response model of Fossen (2011, *Handbook of Marine Craft Hydrodynamics and Motion Control*, ch. 8)

    h(s) = K_w s / (s² + 2 λ ω0 s + ω0²),  K_w = 2 λ ω0 σ,

    driven by white noise: ``w0`` = ω0 [rad/s], ``lam`` = λ [-], ``sigma`` = σ [m/√s].
    """

    w0: float
    lam: float
    sigma: float


def wave_inputs(omega: Any, s: Any, hs: float) -> WaveInputs:
    """ω0, λ and σ of the linear wave model for a sea spectrum S(ω) of significant height ``hs``.

    ω0 is the spectrum's peak, σ² = max S(ω) (Fossen's choice: the model's peak equals the spectrum's),
    and λ makes the model's variance equal the sea's: for unit white noise
    ∫₀^∞ |h(jω)|² dω = π λ ω0 σ², set to m0 = Hs²/16, so λ = Hs² / (16 π ω0 σ²) (clipped to 0.01–1).

    Parameters
    ----------
    omega : (n,) array   frequencies [rad/s], increasing
    s : (n,) array       S(ω) [m² s]
    hs : float           significant wave height [m]
    """
    k = max(range(len(s)), key=lambda i: s[i])
    w0, smax = float(omega[k]), float(s[k])
    sigma = math.sqrt(max(smax, 0.0))
    lam = hs * hs / (16.0 * math.pi * w0 * sigma * sigma) if sigma > 0 else 0.1
    return WaveInputs(w0=w0, lam=min(1.0, max(0.01, lam)), sigma=sigma)


# ----------------------------------------------------------------------------- the lab HMI's sine generator
# Issue 16, item 5.  FB_StewartInterface.FB_init's defaults and the lab HMI's field ranges
# (motionlab_plc.json: Norwegian Motion-Laboratory repository, commit f5fbf84, MIT: ``stewart.
# sine_generator_defaults``); the amplitude fields range over the operational box (etaRefMin..etaRefMax).
GENERATOR_AMPLITUDE = (0.0, 0.0, 0.2, math.radians(2.0), math.radians(2.0), 0.0)  # sineAmplitude [m, rad]
GENERATOR_OMEGA = (0.6283,) * 6  # sineOmega [rad/s] (0.1 Hz)
GENERATOR_PHASE = (0.0,) * 6  # sinePhase [rad]
GENERATOR_FREQUENCY_HZ = (0.01, 1.0, 0.02)  # the HMI's frequency field: min, max, step [Hz]
GENERATOR_PHASE_DEG = (-180.0, 180.0, 10.0)  # the HMI's phase field: min, max, step [deg]
