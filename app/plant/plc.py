"""The real Motion-Lab behind its Beckhoff TwinCAT PLC (``bosun server --plant lab --plc AMS_NET_ID``).

Commands become writes of the lab PLC's symbols by name (:mod:`app.plc.symbols`, from the lab's own
HMI), handed to the ADS bridge thread (:class:`app.plc.bridge.AdsBridge`) through its queue; what the
bridge reads comes back through another queue, drained in :meth:`PlcLab.poll` at the start of every
tick, and is mirrored into the scene's :class:`~app.scenes.lab.MotionLab` (never stepped here), so
the scene draws, publishes and raises alarms on the real machines as on simulated ones.

Mapping (the lab PLC's FB_StewartInterface: ``eModeCmd`` selects SETTLED / NEUTRAL / SIMULATION /
GENERATOR / REMOTE; in the last three ``bStart`` engages, else the platform goes to NEUTRAL):

=================================  =====================================================================
``lab_platform`` neutral / settle  ``eModeCmd`` := NEUTRAL / SETTLED, ``bStart`` := FALSE
``lab_platform`` engage            ``eModeCmd`` := the chosen source's mode, ``bStart`` := TRUE
``lab_platform`` disengage         ``bStart`` := FALSE (the PLC returns to NEUTRAL)
``lab_source`` generator           ``sineAmplitude``, ``sineOmega`` (2π f), ``sinePhase`` (LREAL[6] each)
``lab_source`` simulation          ``hydro.stInput.w0 / lambda / sigma`` from the chosen sea, ``bResetScale`` pulsed
``lab_remote_pose``                ``uRemote`` (REAL[6])
``lab_comau_mode`` settled/remote  ``MAIN.comau.bStart`` := FALSE / TRUE
``lab_winch``                      ``MAIN.winch.eModeCmd``, ``bEnable`` := TRUE, ``u`` (LOCAL slider, ≤ 0.2 m/s)
``estop`` / ``reset``              ``MAIN.bStop`` := TRUE / (``MAIN.bStop`` := FALSE, ``MAIN.bReset`` pulsed)
``lab_plc_ack``                    ``MAIN.bReset`` pulsed; a platform in fault: ``bReset`` pulsed, SETTLED
=================================  =====================================================================

Motion is refused (issue 27, items 1 and 7) while the link is up but STOP cannot reach the PLC
(``MAIN.bStop`` missing or of another type) or the PLC sends invalid data (a number that is not finite or
lies outside the machine's physical range, :func:`value_ranges`): every command that could start motion is
refused with one line, nothing is sent; only writes that stop (``bStart`` := FALSE, the winch's ``u`` := 0)
and the E-STOP's reset (when STOP reaches the PLC) go out.  An invalid value is never used: the last valid
one is held (shown stale) until the symbol has sent valid values for :data:`VALID_AGAIN`.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from app.errors import BosunError, one_line
from app.marine.waves import check_sea
from app.marine.waves import spectrum as sea_spectrum
from app.net.snapshots import MachineLight, MotionStatus, PlantLink
from app.plant.base import BackendError, LabBackend, lab_generator
from app.plc.bridge import (
    STOP,
    AdsBridge,
    AdsState,
    Dropped,
    LinkDown,
    LinkUp,
    PlcTarget,
    StopConfirmed,
    Value,
    WriteFailed,
)
from app.plc.symbols import (
    COMAU_MODE,
    MAIN_STATE,
    PLATFORMS,
    PULSE,
    STEWART_MODE,
    STEWART_OPMODE,
    STEWART_STATE,
    STEWART_STATUS,
    WINCH_MODE,
    WINCH_SPEED_MAX,
    Range,
    check_value,
    decode_status,
    enum_name,
    wave_inputs,
)
from app.scenes.lab import MotionLab

DATA_STALE = 1.0  # s without a value from a connected PLC: the link is shown stale
MAX_UPDATES_PER_TICK = 5000
#: the platform's PLC state → Bosun's platform mode (others are shown as the PLC names them)
MODE_OF_STATE = {
    "SETTLED": "settled",
    "NEUTRAL": "neutral",
    "NEUTRAL_FREEZE": "neutral",
    "ENGAGED": "engaged",
    "ENGAGED_FREEZE": "engaged",
}
SOURCE_MODES = {"generator": "GENERATOR", "simulation": "SIMULATION", "remote": "REMOTE"}
ADS_STATES = {5: "RUN", 6: "STOP", 15: "CONFIG", 16: "RECONFIG"}
#: s of valid values after the last invalid one before a symbol counts as valid again (issue 27, item 7)
VALID_AGAIN = 1.0
#: margins beyond the physical ranges before a value is taken as invalid: the PLC's own filtering, a
#: calibration a little off; a value beyond them is a broken reading, not a machine there
POSE_MARGIN = (0.05, 0.05, 0.05, math.radians(3.0), math.radians(3.0), math.radians(3.0))  # m, rad
JOINT_MARGIN = math.radians(5.0)  # rad
SPEED_FACTOR = 1.5  # × the joint's datasheet speed
UTILISATION_MARGIN = 5.0  # % of the winch's soft-end range


#: symbols whose ranges hold only while another symbol is TRUE (the device reports; see :func:`value_ranges`)
RANGED_WHILE = {"MAIN.comau.txHmi": "MAIN.comau.bActive"}


def value_ranges(lab: MotionLab, names: Any = PLATFORMS) -> dict[str, dict[str, Range]]:
    """The physical range of every number Bosun reads from the lab's PLC, by symbol and field.

    * ``MAIN.<platform>.txHmi``: ``eta`` within the platform's stroke — its Table 8 pose box joined with the
      settled pose (``envelope_min/max``) — ± :data:`POSE_MARGIN`; ``etaRef`` within the operational box
      (the PLC limits it there: etaRef = LIMIT(etaRefMin, u, etaRefMax)) ± the same margin; ``cyl`` within
      ± the longest leg (the summary does not say where the cylinders' zero is: a stroke from either end
      or the length itself all lie there); ``dofScale`` finite only (its range is not known).
    * ``MAIN.comau.txHmi``: ``q`` of the first three joints within the robot file's (datasheet) limits
      ± :data:`JOINT_MARGIN`, ``u`` within :data:`SPEED_FACTOR` × their datasheet speed; joints 4–6 and
      ``qMin``/``qMax`` finite only.  The ranges hold while ``MAIN.comau.bActive`` (:data:`RANGED_WHILE`):
      the PLC has the Comau's joints from the robot's UDP interface, all zeros (q3 = 0 is beyond its
      −256…−10° range) until the robot talks; an inactive Comau's values are checked for finiteness only.
    * ``MAIN.winch.lengthUtilization``: 0 … 100 % of the soft-end range ± :data:`UTILISATION_MARGIN`.
    """
    margin = np.asarray(POSE_MARGIN)
    out: dict[str, dict[str, Range]] = {}
    for k, name in enumerate(names):
        p, m = lab.platforms[k], lab.models[k]
        out[f"MAIN.{name}.txHmi"] = {
            "eta": (tuple(p.envelope_min - margin), tuple(p.envelope_max + margin), "m/rad"),
            "etaRef": (tuple(p.command_min - margin), tuple(p.command_max + margin), "m/rad"),
            "cyl": ((-float(m.leg_max),) * 6, (float(m.leg_max),) * 6, "m"),
        }
    r = lab.robot
    n = min(3, r.lower.size)
    out["MAIN.comau.txHmi"] = {
        "q": (tuple(r.lower[:n] - JOINT_MARGIN), tuple(r.upper[:n] + JOINT_MARGIN), "rad"),
        "u": (tuple(-SPEED_FACTOR * r.speed[:n]), tuple(SPEED_FACTOR * r.speed[:n]), "rad/s"),
    }
    m_u = UTILISATION_MARGIN
    out["MAIN.winch.lengthUtilization"] = {"": ((-m_u,), (100.0 + m_u,), "%")}
    return out


class PlcLab(LabBackend):
    """The lab's machines behind the TwinCAT PLC, through the ADS bridge.

    Parameters
    ----------
    lab : MotionLab      the scene's model, set to the measured states every tick (never stepped)
    target : PlcTarget   the PLC (``--plc``, ``--plc-host``)
    bridge : AdsBridge   default: a new one for ``target`` with ``bridge_options``
    """

    NAME = "plc"

    def __init__(self, lab: MotionLab, target: PlcTarget, bridge: AdsBridge | None = None, **bridge_options) -> None:
        super().__init__(lab)
        self.target = target
        self.bridge = bridge if bridge is not None else AdsBridge(target, **bridge_options)
        self.values: dict[str, Any] = {}
        self.t_data: float | None = None  # monotonic time of the last value
        self.t0 = time.monotonic()
        self.state = "connecting"  # connecting | ok | lost
        self.last_error = ""
        self.reconnects = 0
        self.ads_state = 0
        self.problems: list[str] = []
        self.stop = False
        self.stop_written = False
        self.chosen = ["generator" for _ in self.names]  # the motion source chosen here (the mode ENGAGE asks for)
        self.winch_command = 0.0
        self.unusable: set[str] = set()  # symbols the PLC lacks or declares otherwise (never written)
        self._eta: list[tuple[float, NDArray[np.float64], NDArray[np.float64]] | None] = [None for _ in self.names]
        self._wire: tuple[float, float, float] | None = None  # time, utilisation [%], its rate [%/s]
        self._told = ""
        self.ranges = value_ranges(lab, self.names)
        self.invalid: dict[str, tuple[str, float]] = {}  # symbol → (what is wrong, time of its last bad value)
        self.t_valid: dict[str, float] = {}  # symbol → time of its last valid value
        self.bad_values = 0  # values refused since the start (each non-finite or out-of-range number counted)
        self._events: list[tuple[str, str]] = []
        lab.comau_mode = "hold"  # nothing known until the PLC says
        for p in lab.platforms:
            p.transition = "unknown"
        self.bridge.start()

    @property
    def winch_speed_max(self) -> float:
        return min(float(self.layout.winch["speed"]), WINCH_SPEED_MAX)  # the lab HMI's slider: ±0.2 m/s

    # ------------------------------------------------------------------ writes
    def ready(self) -> str:
        if self.state == "ok":
            return ""
        why = f": {self.last_error}" if self.last_error else ""
        if self.state == "connecting":
            return f"not connected to the PLC at {self.target} yet{why}"
        return f"the PLC link is lost{why}"

    def stop_path(self) -> str:
        """ "" when a STOP reaches the PLC now, else why not (one line)."""
        if self.ready():
            return self.ready()
        if STOP in self.unusable:
            return f"STOP does not reach the PLC ({self._problem(STOP)})"
        return ""

    def motion_block(self) -> str:
        """Why a command that could start motion is refused although the link is up (issue 27, items 1 and
        7): STOP cannot reach the PLC, or the PLC sends invalid data; "" when neither."""
        if self.state != "ok":
            return ""  # the link's own refusal (ready) says why
        if STOP in self.unusable:
            return f"STOP does not reach the PLC ({self._problem(STOP)})"
        if self.invalid:
            name = min(self.invalid, key=lambda n: self.invalid[n][1])
            more = f"; {len(self.invalid) - 1} more symbol(s)" if len(self.invalid) > 1 else ""
            return f"the PLC sends invalid data ({self.invalid[name][0]}{more})"
        age = None if self.t_data is None else time.monotonic() - self.t_data
        if age is None or age > DATA_STALE:  # the machines are not seen: nothing may start
            return "no data from the PLC yet" if age is None else f"no data from the PLC for {age:.1f} s"
        return ""

    def _check(self, *names: str, stopping: bool = False) -> None:
        """Refuse (nothing sent) unless the link is up and every symbol is usable on this PLC; unless
        ``stopping`` (the writes can only stop a machine), also while :meth:`motion_block` says why not."""
        why = self.ready()
        if why:
            raise BackendError(f"{why}; nothing was sent and nothing is queued")
        block = "" if stopping else self.motion_block()
        if block:
            raise BackendError(f"motion refused: {block}; nothing was sent")
        for name in names:
            if name in self.unusable:
                raise BackendError(f"{name} is not usable on this PLC ({self._problem(name)})")

    def _send(self, *writes: tuple, stopping: bool = False) -> None:
        """All of ``(name, value[, pulse])`` handed to the bridge in order, or none (refused)."""
        self._check(*(w[0] for w in writes), stopping=stopping)
        for name, value, *pulse in writes:
            self.bridge.write(name, value, *pulse)

    def _problem(self, name: str) -> str:
        return next((p for p in self.problems if p.startswith(name + ":")), "see the link's problems")

    def _state_of(self, k: int) -> str:
        """The platform's PLC state by name (eState, else the status word of txHmi), "" if none yet."""
        m = f"MAIN.{self.names[k]}"
        if f"{m}.eState" in self.values:
            return enum_name(STEWART_STATE, self.values[f"{m}.eState"])
        hmi = self.values.get(f"{m}.txHmi")
        return decode_status(hmi["status"])["state"] if hmi else ""

    # ------------------------------------------------------------------ commands
    def platform(self, k: int, action: str) -> None:
        m = f"MAIN.{self.names[k]}"
        if action in ("neutral", "settle", "engage"):
            self._check()  # the link and motion first: a refusal says why nothing may start
        if action in ("neutral", "settle"):
            mode = STEWART_MODE["NEUTRAL" if action == "neutral" else "SETTLED"]
            self._send((f"{m}.eModeCmd", mode), (f"{m}.bStart", False))
        elif action == "engage":
            state = self._state_of(k)
            if state and MODE_OF_STATE.get(state) != "neutral":
                raise BackendError(f"{self.names[k]}: ENGAGE needs NEUTRAL (the PLC reports {state})")
            self._send((f"{m}.eModeCmd", STEWART_MODE[SOURCE_MODES[self.chosen[k]]]), (f"{m}.bStart", True))
        elif action == "disengage":
            self._send((f"{m}.bStart", False), stopping=True)  # back to NEUTRAL: the wave motion stops
        else:
            raise BackendError(f"platform action must be neutral, settle, engage or disengage, got {action!r}")

    def source(self, k: int, source: str, p: dict[str, Any]) -> dict[str, Any]:
        name, m = self.names[k], f"MAIN.{self.names[k]}"
        self._check()
        if MODE_OF_STATE.get(self._state_of(k)) == "engaged":
            raise BackendError(f"{name} is ENGAGED; disengage before changing the motion source")
        plat = self.lab.platforms[k]
        if source == "generator":
            g = lab_generator(plat, p)
            omega = (2.0 * math.pi * g.frequency).tolist()
            self._send(
                (f"{m}.sineAmplitude", g.amplitude.tolist()),
                (f"{m}.sineOmega", omega),
                (f"{m}.sinePhase", g.phase.tolist()),
            )
            info: dict[str, Any] = {"amplitude": g.amplitude.tolist(), "frequency": g.frequency.tolist()}
        elif source == "simulation":
            kind, hs, tp = p.get("spectrum", "jonswap"), float(p.get("hs", 2.0)), float(p.get("tp", 8.0))
            try:
                check_sea(hs, tp)
            except BosunError as err:
                raise BackendError(str(err)) from None
            omega = np.linspace(0.1, 3.0, 600)
            w = wave_inputs(omega, sea_spectrum(kind, omega, hs, tp), hs)
            self._send(
                (f"{m}.hydro.stInput.w0", w.w0),
                (f"{m}.hydro.stInput.lambda", w.lam),
                (f"{m}.hydro.stInput.sigma", w.sigma),
                (f"{m}.bResetScale", True, PULSE),  # the PLC scales the DOFs anew (SETTLED/NEUTRAL only)
            )
            info = {"hs": hs, "tp": tp, "w0": w.w0, "lambda": w.lam, "sigma": w.sigma, "scale": "PLC"}
        elif source == "remote":
            self._check(f"{m}.uRemote", f"{m}.eModeCmd")
            info = {}
        else:
            raise BackendError(f"the lab PLC has no {source} source (generator, simulation or remote)")
        self.chosen[k] = source
        return info

    def remote_pose(self, k: int, eta: Any) -> None:
        e = np.asarray(eta, dtype=float).reshape(-1)
        if e.shape != (6,) or not np.all(np.isfinite(e)):
            raise BackendError(f"remote pose needs six finite numbers, got {np.asarray(eta).tolist()}")
        plat = self.lab.platforms[k]
        self._send((f"MAIN.{self.names[k]}.uRemote", np.clip(e, plat.command_min, plat.command_max).tolist()))

    def comau_mode(self, mode: str) -> None:
        if mode not in ("settled", "remote"):
            raise BackendError(
                f"Comau {mode.upper()}: over ADS the lab PLC only starts (REMOTE) or stops (SETTLED) the Comau"
            )
        self._send(("MAIN.comau.bStart", mode == "remote"), stopping=mode == "settled")

    def winch_mode(self, mode: str) -> None:
        key = mode.upper()
        if key not in WINCH_MODE or key == "SETTLED":
            raise BackendError(f"winch mode must be local, remote or motion_comp, got {mode!r}")
        self._send(("MAIN.winch.u", 0.0), ("MAIN.winch.eModeCmd", WINCH_MODE[key]), ("MAIN.winch.bEnable", True))
        self.winch_command = 0.0

    def winch_speed(self, speed: float) -> None:
        u = float(np.clip(speed, -self.winch_speed_max, self.winch_speed_max))
        if u != 0.0:  # a speed, also one repeated, is refused while nothing may move (each resend)
            self._check("MAIN.winch.u")
        if abs(u - self.winch_command) < 1e-6 or self.ready():
            return  # only changes go out; the slider is zeroed on reconnect by the bridge
        self._send(("MAIN.winch.u", u), stopping=u == 0.0)  # letting go is always taken
        self.winch_command = u

    def vvmc(self, on: bool) -> None:
        if on:
            raise BackendError(
                "VVMC is Bosun's simulated controller; on the lab the PLC compensates (winch MOTION_COMP)"
            )

    def drive(self, tool_velocity_r: NDArray[np.float64], winch_speed: float) -> None:
        """The stick does not reach the PLC over ADS: the lab takes Comau joint speeds and the REMOTE
        winch speed from its UDP remote interface, which Bosun does not drive."""

    def comau_jog(self, qd: NDArray[np.float64]) -> None:
        """Refused (a stop, all zeros, is a no-op): the lab PLC takes Comau joint speeds only from its UDP
        remote interface (``qDotRef``), which Bosun does not drive (issue 16, item 5)."""
        if np.any(np.asarray(qd) != 0.0):
            raise BackendError(
                "Comau jog: the lab PLC takes Comau joint speeds only from its UDP remote interface (qDotRef), "
                "which Bosun does not drive; nothing was sent"
            )

    def estop(self) -> None:
        self.stop = True
        self.winch_command = 0.0
        self.bridge.set_stop(True)  # written now if connected, and on every reconnect until reset

    def reset(self) -> None:
        why = self.ready()
        if why:
            raise BackendError(f"{why}: the STOP stays latched until the PLC can take the reset")
        self._check(STOP, "MAIN.bReset", stopping=True)  # a reset starts nothing; STOP must be usable
        self.bridge.set_stop(False)
        self.stop = False
        self.stop_written = False
        self._send((STOP, False), ("MAIN.bReset", True, PULSE), stopping=True)

    def faults(self) -> list[str]:
        """What the PLC reports wrong, one phrase each: its main state, each platform's status and error."""
        out = []
        if STOP in self.unusable:
            out.append("MAIN.bStop not usable: STOP does not reach the PLC")
        main = self.values.get("MAIN.eState")
        if main is not None and main != MAIN_STATE["NORMAL"]:
            out.append(f"PLC in {enum_name(MAIN_STATE, main)}")
        if self.ads_state and self.ads_state != 5:
            out.append(f"ADS state {ADS_STATES.get(self.ads_state, self.ads_state)} (not RUN)")
        for k, name in enumerate(self.names):
            status = self._platform_fault(k)
            if status:
                out.append(f"{name} {status}")
        return out

    def _platform_fault(self, k: int) -> str:
        m = f"MAIN.{self.names[k]}"
        status = self.values.get(f"{m}.eStatus")
        if status is None and f"{m}.txHmi" in self.values:
            s = decode_status(self.values[f"{m}.txHmi"]["status"])["status"]
        else:
            s = enum_name(STEWART_STATUS, status)
        if s and s != "SYSTEM_OK":
            return s
        return "ERROR" if self.values.get(f"{m}.bError") else ""

    def acknowledge(self, k: int | None) -> str:
        if self.stop:
            raise BackendError("the E-STOP is latched: its reset resets the PLC (MAIN.bReset)")
        self._check()  # its eModeCmd := SETTLED moves a platform: refused as motion is
        main = self.values.get("MAIN.eState")
        writes: list[tuple] = []
        done = []
        if main is not None and main != MAIN_STATE["NORMAL"]:
            writes.append(("MAIN.bReset", True, PULSE))
            done.append("MAIN.bReset")
        for j, name in enumerate(self.names):
            if (k is None or j == k) and self._platform_fault(j):
                m = f"MAIN.{name}"
                writes += [
                    (f"{m}.bStart", False),
                    (f"{m}.bReset", True, PULSE),
                    (f"{m}.eModeCmd", STEWART_MODE["SETTLED"]),
                ]
                done.append(f"{m}.bReset, {m}.eModeCmd := SETTLED")
        if not done:
            raise BackendError("the PLC reports no error to acknowledge")
        self._send(*writes)
        return "PLC error acknowledged: " + "; ".join(done)

    # ------------------------------------------------------------------ loop
    def poll(self, now: float) -> list[tuple[str, str]]:
        out: list[tuple[str, str]] = []
        q = self.bridge.updates
        for _ in range(MAX_UPDATES_PER_TICK):
            try:
                u = q.get_nowait()
            except Exception:
                break
            if isinstance(u, Value):
                self._value(u)
            elif isinstance(u, LinkUp):
                out += self._up(u)
            elif isinstance(u, LinkDown):
                out += self._down(u)
            elif isinstance(u, StopConfirmed):
                self.stop_written = u.value and self.stop
                if self.stop and not u.value:
                    out.append(("error", "PLC: MAIN.bStop read back FALSE after Bosun wrote TRUE"))
                elif self.stop:
                    out.append(("info", "PLC: MAIN.bStop = TRUE written and read back"))
            elif isinstance(u, WriteFailed):
                out.append(("warning", one_line(f"PLC: {u.name} not written: {u.error}", 300)))
            elif isinstance(u, Dropped):
                names = ", ".join(sorted(set(u.names)))
                out.append(("warning", one_line(f"PLC: not sent ({u.reason}): {names}", 300)))
            elif isinstance(u, AdsState):
                self.ads_state = u.ads_state
        out += self._events
        self._events = []
        self._valid_again(time.monotonic(), out)
        self._mirror(now)
        return out

    def _valid_again(self, t: float, out: list[tuple[str, str]]) -> None:
        """A symbol flagged invalid counts as valid again once it sent valid values for :data:`VALID_AGAIN`."""
        for name, (_, t_bad) in list(self.invalid.items()):
            if self.t_valid.get(name, -math.inf) > t_bad and t - t_bad >= VALID_AGAIN:
                del self.invalid[name]
                out.append(("info", f"PLC data valid again: {name} (valid values for {VALID_AGAIN:g} s)"))

    def _up(self, u: LinkUp) -> list[tuple[str, str]]:
        was = self.state
        self.state, self.reconnects, self.ads_state = "ok", u.reconnects, u.ads_state
        self.problems, self.unusable = list(u.problems), set(u.unusable)
        self._eta = [None for _ in self.names]  # no speed across the gap
        self._wire = None
        self.winch_command = 0.0  # the bridge set u := 0 on connect
        what = "reconnected" if was == "lost" else "connected"
        text = f"PLC {what}: {self.target} (ADS state {ADS_STATES.get(u.ads_state, u.ads_state)})"
        if self.stop:
            text += "; the latched STOP was written again (MAIN.bStop)"
        for name in [n for n in self.invalid if n in self.unusable]:  # not read any more: nothing to hold
            del self.invalid[name]
        out = [("link_up", text)]
        out += [("warning", one_line(f"PLC symbol not used: {p}", 300)) for p in u.problems]
        if STOP in self.unusable:
            out.append(
                ("error", one_line(f"STOP does not reach the PLC ({self._problem(STOP)}): every command that "
                                   "could start motion is refused; use the lab's hardware emergency stop", 300))
            )  # fmt: skip
        out += [("info", one_line(f"PLC: {n}", 300)) for n in u.notes]
        return out

    def _down(self, u: LinkDown) -> list[tuple[str, str]]:
        first = self.state == "ok"
        self.last_error = u.error
        self.stop_written = False
        if self.state == "ok":
            self.state = "lost"
        if first:
            self._told = u.error
            stop = "; STOP latched here, written to MAIN.bStop when the link is back" if self.stop else ""
            return [("link_lost", f"PLC link lost: {u.error}{stop}; nothing is replayed after the gap")]
        if u.error != self._told:  # a new reason while retrying: said once
            self._told = u.error
            return [("warning", one_line(f"PLC at {self.target} not reachable: {u.error}; retrying", 300))]
        return []

    def _value(self, u: Value) -> None:
        sym = self.bridge.symbols.get(u.name)
        flag = RANGED_WHILE.get(u.name)
        ranges = self.ranges.get(u.name) if flag is None or self.values.get(flag) else None  # None: finite only
        bad, why = check_value(sym, u.value, ranges) if sym is not None else (0, "")
        if bad:  # never used: the last valid value is held (issue 27, item 7)
            self.bad_values += bad
            if u.name not in self.invalid:
                self._events.append(
                    ("error", one_line(f"PLC data invalid: {why}; holding the last valid value, motion refused", 300))
                )
            self.invalid[u.name] = (one_line(why, 200), u.t)
            return
        self.t_valid[u.name] = u.t
        self.values[u.name] = u.value
        self.t_data = u.t
        for k, name in enumerate(self.names):
            if u.name == f"MAIN.{name}.txHmi":  # η̇ by the difference of two polls (the struct has no speed)
                eta, prev = np.asarray(u.value["eta"], dtype=float), self._eta[k]
                rate = (eta - prev[1]) / (u.t - prev[0]) if prev is not None and u.t - prev[0] > 1e-3 else np.zeros(6)
                self._eta[k] = (u.t, eta, rate)
        if u.name == "MAIN.winch.lengthUtilization":
            util, prev = float(u.value), self._wire
            rate = (util - prev[1]) / (u.t - prev[0]) if prev is not None and u.t - prev[0] > 1e-3 else 0.0
            self._wire = (u.t, util, rate)

    def _mirror(self, now: float) -> None:
        """Set the scene's model to what the PLC reported (only what it reported; the rest stays)."""
        lab, v = self.lab, self.values
        lab.t = now - self.t0
        for k, name in enumerate(self.names):
            p = lab.platforms[k]
            m = f"MAIN.{name}"
            if self._eta[k] is not None:
                _, eta, eta_dot = self._eta[k]
                p.filter.x[:] = eta
                p.filter.v[:] = eta_dot
                p.filter.a[:] = 0.0
            state = self._state_of(k)
            if state:
                mode = MODE_OF_STATE.get(state)
                p.mode = mode or p.mode
                p.transition = "" if mode else state.lower()
                p.gain = 1.0 if mode == "engaged" else 0.0
            src = enum_name(STEWART_MODE, v.get(f"{m}.eMode")).lower()
            p.source_name = src if src in SOURCE_MODES else self.chosen[k]
            p.leg_clamped = False
        hmi = v.get("MAIN.comau.txHmi")
        f = lab.joints
        if hmi is not None:
            n = f.x.size
            q, qd = np.asarray(hmi["q"][:n], dtype=float), np.asarray(hmi["u"][:n], dtype=float)
            f.x[:], f.v[:], f.a[:] = q, qd, 0.0
            lo, hi = np.asarray(hmi["qMin"][:n]), np.asarray(hmi["qMax"][:n])
            lab.at_limit[:n] = (q <= lo + 1e-3) | (q >= hi - 1e-3)
        mode = enum_name(COMAU_MODE, v.get("MAIN.comau.eMode")).lower()
        if mode in ("settled", "remote", "motion_comp"):
            lab.comau_mode = mode
        lab.tool_velocity_cmd = np.zeros(3)
        w, spec = lab.winch, lab.winch.spec
        if self._wire is not None:  # the PLC's length is measured from its lower soft end: % of the range
            _, util, util_rate = self._wire
            span = spec["max_length"] - spec["min_length"]
            w.filter.x[0] = spec["min_length"] + util / 100.0 * span
            w.filter.v[0] = util_rate / 100.0 * span
            lab.at_limit[3] = not 0.1 < util < 99.9
        wmode = enum_name(WINCH_MODE, v.get("MAIN.winch.eMode")).lower()
        if wmode:
            w.mode = wmode
        w.speed_command = self.winch_command
        pd = lab.pendulum  # the load's swing is not measured through the PLC: shown hanging straight
        pd.alpha = pd.beta = pd.alpha_dot = pd.beta_dot = 0.0
        lab.payload_target_b2 = None
        lab.refresh()

    def step(self, dt: float, n: int) -> None:
        """Nothing to step: the real lab moves by itself (the model follows it in :meth:`poll`)."""

    # ------------------------------------------------------------------ state
    def devices(self) -> dict[str, dict[str, Any]]:
        """The PLC's own states per device, by name (what the lab HMI's state LEDs show)."""
        v = self.values
        out: dict[str, dict[str, Any]] = {"main": {"state": enum_name(MAIN_STATE, v.get("MAIN.eState"))}}
        for name in self.names:
            m = f"MAIN.{name}"
            out[name] = {
                "state": enum_name(STEWART_STATE, v.get(f"{m}.eState")),
                "status": enum_name(STEWART_STATUS, v.get(f"{m}.eStatus")),
                "opmode": enum_name(STEWART_OPMODE, v.get(f"{m}.eOpMode")),
                "mode": enum_name(STEWART_MODE, v.get(f"{m}.eMode")),
                "active": bool(v.get(f"{m}.bActive", False)),
                "error": bool(v.get(f"{m}.bError", False)),
                "busy": bool(v.get(f"{m}.bBusy", False)),
            }
        out["comau"] = {
            "mode": enum_name(COMAU_MODE, v.get("MAIN.comau.eMode")),
            "active": bool(v.get("MAIN.comau.bActive", False)),
        }
        util = v.get("MAIN.winch.lengthUtilization")
        out["winch"] = {
            "mode": enum_name(WINCH_MODE, v.get("MAIN.winch.eMode")),
            "active": bool(v.get("MAIN.winch.bActive", False)),
            "utilization": None if util is None else float(util),
        }
        for mru in ("mru1", "mru2"):
            out[mru] = {"active": bool(v.get(f"MAIN.{mru}.bActive", False))}
        return out

    def motion_status(self, k: int) -> MotionStatus | None:
        """The platform's Rexroth status as the PLC reports it: eState / eStatus / eOpMode (notified), each
        missing one from the status word of ``txHmi`` (bits 0–3, 4–7, 24–31); the word made of the three shown.
        None while the link is not up or nothing came yet."""
        if self.state != "ok":
            return None
        v, m = self.values, f"MAIN.{self.names[k]}"
        hmi = v.get(f"{m}.txHmi")
        polled = int(hmi["status"]) & 0xFFFFFFFF if hmi else None
        names, word, known = {}, 0, False
        for key, table, symbol, shift, mask in (
            ("state", STEWART_STATE, "eState", 0, 0xF),
            ("status", STEWART_STATUS, "eStatus", 4, 0xF),
            ("opmode", STEWART_OPMODE, "eOpMode", 24, 0xFF),
        ):
            raw = v.get(f"{m}.{symbol}")
            if raw is None and polled is not None:
                raw = (polled >> shift) & mask
            known |= raw is not None
            names[key] = enum_name(table, raw)
            word |= (int(raw or 0) & mask) << shift
        return MotionStatus(**names, word=word) if known else None

    def machines(self, now: float) -> list[MachineLight]:
        """``MAIN.<dev>.bActive`` of the platforms, the Comau and the MRUs, as the lab HMI's lights; the laser
        tracker's and the remote interface's are not read (motionlab_plc.json names no symbol for them)."""
        out = []
        for dev in ("em8000", "em1500", "comau", "mru1", "mru2"):
            name = f"MAIN.{dev}.bActive"
            if self.state != "ok":
                out.append(MachineLight(name=dev, state="unknown", detail=f"PLC link {self.state}"))
            elif name in self.unusable:
                out.append(MachineLight(name=dev, state="unknown", detail=f"{name} not usable on this PLC"))
            elif held := self._held(f"MAIN.{dev}", now):
                out.append(MachineLight(name=dev, state="stale", detail=held))
            elif name not in self.values:
                out.append(MachineLight(name=dev, state="unknown", detail=f"no {name} yet"))
            else:
                on = bool(self.values[name])
                out.append(MachineLight(name=dev, state="active" if on else "inactive", detail=f"{name} {on}"))
        for dev in ("tracker", "remote"):
            out.append(MachineLight(name=dev, state="unknown", detail="not read over ADS (no symbol known)"))
        return out

    def _held(self, prefix: str, now: float) -> str:
        """One line for the device's symbols flagged invalid (their last valid values held), "" if none."""
        return "; ".join(self._invalid_line(n, now) for n in sorted(self.invalid) if n.startswith(prefix + "."))

    def _invalid_line(self, name: str, now: float) -> str:
        t = self.t_valid.get(name)
        held = "no valid value yet" if t is None else f"holding the last valid value, {max(0.0, now - t):.1f} s old"
        return one_line(f"{self.invalid[name][0]}: {held}", 300)

    def link(self, now: float) -> PlantLink:
        age = -1.0 if self.t_data is None else max(0.0, now - self.t_data)
        state = self.state
        if state == "ok" and self.invalid:
            state = "invalid"
        elif state == "ok" and (age < 0 or age > DATA_STALE):
            state = "stale"
        return PlantLink(
            backend=self.NAME,
            target=str(self.target),
            link=state,
            connected=self.state == "ok",
            plc_state=enum_name(MAIN_STATE, self.values.get("MAIN.eState")),
            ads_state=self.ads_state,
            plc_error=one_line("; ".join(self.faults()), 300),
            last_error=self.last_error,
            reconnects=self.reconnects,
            data_age=round(age, 3),
            stop_written=self.stop_written,
            problems=list(self.problems),
            devices=self.devices(),
            invalid=[self._invalid_line(n, now) for n in sorted(self.invalid)],
            motion_refused=self.motion_block(),
        )

    def close(self) -> None:
        self.bridge.close()
