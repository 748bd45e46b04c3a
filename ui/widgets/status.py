"""Status area as in the lab's HMI: a light per subsystem, the alarm list, a timestamped log, a big STOP.

Every light is made from what an engine's state reports about its machines, never from what was asked
of them ("a light never contradicts the machine", docs/safety.md H71-H74).  The rules are small pure
functions of a typed snapshot (:func:`scene_lights`); :class:`SceneLights` shows one engine's lights in a
row named after it.  The status area's own row is the teleop engine's (the main window feeds it); the
crane-head and Motion-Lab pages carry their own engine's row, so no light speaks for another engine.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QFont
from PyQt5.QtWidgets import (
    QHBoxLayout,
    QLabel,
    QPlainTextEdit,
    QSplitter,
    QVBoxLayout,
    QWidget,
)

from ui.widgets.alarms import AlarmPanel
from ui.widgets.buttons import button
from ui.widgets.labels import ElidedLabel

LIGHT = {"ok": "#3c9d3c", "warn": "#e0a020", "error": "#d9534f", "off": "#666666", "unknown": "#8a8aa0"}


class StatusLight(ElidedLabel):
    """A light: "● name: detail"; a detail too long for its room ends in "…" (whole in the tool tip),
    it never widens the window."""

    def __init__(self, name: str, tooltip: str, parent=None, padding: str = "2px 6px") -> None:
        super().__init__("", parent)
        self.name = name
        self.padding = padding  # CSS padding around the text (a page's row of lights: less height)
        self.tooltip = tooltip
        self.setToolTip(tooltip)
        self.setMinimumWidth(120)
        self.state = "off"
        self.set("off")

    def set(self, state: str, detail: str = "", tip: str = "") -> None:
        if tip != getattr(self, "_tip", ""):
            self._tip = tip
            self.setToolTip(f"{self.tooltip}\n{tip}" if tip else self.tooltip)
        if (state, detail) == getattr(self, "_shown", None):
            return  # restyling a label relayouts the window: only on change
        self._shown = (state, detail)
        self.state = state
        self.setText(f"● {self.name}{': ' + detail if detail else ''}")
        self.setStyleSheet(f"color: {LIGHT[state]}; font-weight: bold; padding: {self.padding};")


# ---------------------------------------------------------------------------------------------- rules
MOVING = 1e-4  # a speed above this is motion [m/s, rad/s] (snapshots round speeds to 1e-6)


@dataclass(frozen=True)
class Light:
    """What a light shows: ``look`` (a key of :data:`LIGHT`) and one line of ``detail``."""

    look: str
    detail: str = ""
    tip: str = ""  # a diagnostic for the tool tip (added to the light's own)


LOST = {"engine": Light("error", "LOST"), "input": Light("unknown", "unknown"), "plant": Light("unknown", "unknown")}


def engine_light(state) -> Light:
    """The engine's loop as its state reports it.  Its timing is a diagnostic, in the tool tip (issue 26): the
    light turns amber only when the engine raises ``engine_slow`` (control suffers: below 90 % of real time
    for 5 s, or input gone stale while it lagged); paused (no client shows its scene) or connected."""
    e = state.engine
    tip = (
        f"loop: {100 * e.realtime_factor:.0f} % of real time, {100 * e.late_fraction:.1f} % of ticks late, "
        f"longest tick {getattr(e, 'max_tick_ms', 0.0):.0f} ms (1 s)"
    )
    if any(a.key == "engine_slow" and a.active for a in state.alarms):
        return Light("warn", f"too slow: {100 * e.realtime_factor:.0f} % of real time", tip)
    if e.paused:
        return Light("off", "paused (its tab is not shown)", tip)
    return Light("ok", "connected", tip)


def _stick_light(flags, takers: list[str]) -> Light:
    """The operator's stick (pipeline flags) for the machines in ``takers`` that take it."""
    dev = flags.device_name[:32] or "input"
    # amber only where the operator must act; idle (no device, enable let go) is grey: not an abnormal state
    # (a lost device that was driving is the device_lost alarm)
    if not flags.device:
        return Light("off", "no input device")
    if flags.stale_input:
        return Light("warn" if flags.armed else "off", f"no fresh input: {dev}")
    if flags.enabled:
        return Light("ok", f"enabled: {dev} drives {' and '.join(takers)}" if takers else f"enabled: {dev}")
    if not flags.deadman:
        return Light("off", f"idle: {dev} (enable released)")
    return Light("warn", f"not armed: {flags.input_reason or dev}"[:80])


def _braking(moving: list[str]) -> Light:
    """Under a latched E-STOP: what still brakes, else stopped."""
    return Light("error", f"E-STOP: braking {', '.join(moving)}" if moving else "E-STOP: stopped")


# teleop ----------------------------------------------------------------------------------------------------
def teleop_lights(state) -> dict[str, Light]:
    """The teleoperated arm: it moves while a joint speed is not zero (also braking after enable was let go);
    at rest it is ready while the input is enabled, else holding."""
    moving = any(abs(v) > 1e-6 for v in state.qdot)
    f = state.flags
    if state.estop:
        plant = _braking(["the arm"] if moving else [])
    elif moving:
        plant = Light("ok", "moving")
    elif f.enabled and not f.stale_input:
        plant = Light("ok", "ready")
    else:
        plant = Light("off", "at rest (holding)")  # the normal idle state: grey, not amber
    return {"engine": engine_light(state), "input": _stick_light(f, []), "plant": plant}


# crane head ------------------------------------------------------------------------------------------------
def tac_lights(state) -> dict[str, Light]:
    """Vessel, crane and Delta head: the head compensates in ``tac`` and ``cooperative`` unless an E-STOP or a
    reset froze it (the engine's ``holding``); ``off`` locks it.  In ``tac`` and ``cooperative`` the stick moves the
    TCP's target in the world (issue 30, item 2): its light is the stick's, as in the other scenes."""
    if state.estop:
        plant = Light("error", "E-STOP: head and crane stopped")
    elif state.holding:
        plant = Light("warn", "holding: choose a compensation mode")
    elif state.sample is None:
        plant = Light("unknown", "no state yet")
    elif state.tac_mode == "off":
        plant = Light("off", "head locked (mode off): not compensating")
    else:
        how = "crane and head" if state.tac_mode == "cooperative" else "head"
        sat = state.sample.saturated
        detail = f"compensating: {how} ({state.tac_mode})" + (", SATURATED" if sat else "")
        plant = Light("warn" if sat else "ok", detail)
    f = state.flags
    if state.tac_mode == "off" or state.estop or state.holding:  # the stick moves nothing here (issue 30, item 2)
        why = "E-STOP" if state.estop else "holding" if state.holding else "mode off"
        inp = Light("off", f"not used ({why}): {f.device_name[:32] or 'no input device'}")
    else:
        inp = _stick_light(f, ["the TCP's target"])
    return {"engine": engine_light(state), "input": inp, "plant": plant}


# Motion-Lab ------------------------------------------------------------------------------------------------
def _lab_moving(state) -> list[str]:
    """The lab's machines moving now, by name (speeds above :data:`MOVING`)."""
    out = [p.name.upper() for p in state.platforms if max(map(abs, p.eta_dot), default=0.0) > MOVING]
    if state.comau is not None and max(map(abs, state.comau.qd), default=0.0) > MOVING:
        out.append("Comau")
    if state.winch is not None and abs(state.winch.speed) > MOVING:
        out.append("winch")
    return out


def _lab_activity(state) -> list[str]:
    """What each machine is doing, one short phrase each (engaged platforms, transits, jog, moving arm)."""
    out = []
    moving = _lab_moving(state)
    for p in state.platforms:
        name = p.name.upper()
        if p.mode == "engaged":
            out.append(f"{name} {p.status}")
        elif p.status in ("raising", "settling") or name in moving:
            out.append(f"{name} {p.status if p.status in ('raising', 'settling') else 'moving'}")
    jog = state.comau_jog
    if jog is not None and jog.joint:
        out.append(f"Comau jog q{jog.joint}")
    elif "Comau" in moving and not state.vvmc:
        out.append(f"Comau {state.comau.mode.upper()}")
    if "winch" in moving and not state.vvmc:
        out.append(f"winch {state.winch.mode.upper()}")
    return out


def lab_plant_light(state) -> Light:
    """The Motion-Lab's machines: E-STOP (braking, then stopped), compensating (VVMC on: the Comau and winch
    track the work point), moving (a platform engaged or in transit, a jog, any machine in motion), holding
    (a platform HOLDING or the Comau in HOLD after a reset: waiting for the operator) or at rest; unknown while
    the PLC link is down."""
    pl = state.plant
    if pl is not None and pl.backend == "plc" and pl.link in ("lost", "connecting"):
        return Light("unknown", f"unknown: PLC link {pl.link}")
    if state.estop:
        return _braking(_lab_moving(state))
    doing = _lab_activity(state)
    held = [p.name.upper() for p in state.platforms if p.status == "holding"]
    if state.comau is not None and state.comau.mode == "hold":
        held.append("Comau")
    waiting = f"; holding: {', '.join(held)}" if held else ""  # the others still wait for the operator
    if state.vvmc:
        light = Light("ok", "compensating: " + ", ".join(["VVMC", *doing]) + waiting)
    elif doing:
        light = Light("ok", "moving: " + ", ".join(doing) + waiting)
    elif held:
        light = Light("warn", f"holding: {', '.join(held)}: choose a mode")
    else:
        light = Light("off", "at rest")
    if any(p.leg_clamped for p in state.platforms):
        light = Light("warn", light.detail + ", LEG LIMIT")
    if pl is not None and pl.link == "stale":
        light = Light("warn", f"{light.detail} (PLC data {pl.data_age:.1f} s old)")
    if pl is not None and pl.link == "invalid":  # issue 27: what is drawn is the last valid value, held
        light = Light("warn", f"{light.detail} (PLC data invalid: the last valid values, held)")
    return light


def lab_input_light(state) -> Light:
    """The input that drives a lab machine: a joint jog, the stick (Comau or winch REMOTE; under VVMC the work point
    on EM1500 and the load to the deck, issue 30, item 4, on the simulated plant), or none (LOCAL, HOLD, SETTLED,
    VVMC over the lab's PLC: no machine takes it)."""
    if state.estop:
        return Light("off", "not taken: E-STOP latched")
    jog = state.comau_jog
    if jog is not None and jog.joint:
        return Light("ok", f"jog q{jog.joint} {100 * jog.speed:+.0f} % ({state.flags.device_name[:32] or 'GUI'})")
    modes = [(n, m.mode if m is not None else "?") for n, m in (("Comau", state.comau), ("winch", state.winch))]
    simulated = state.plant is None or state.plant.backend != "plc"  # the PLC's MOTION_COMP takes no stick
    names = {"remote": "REMOTE", "motion_comp": "VVMC"}
    takers = [f"{n} {names[m]}" for n, m in modes if m == "remote" or (m == "motion_comp" and simulated)]
    if not takers:
        return Light("off", "not used (" + ", ".join(f"{n} {m.upper()}" for n, m in modes) + ")")
    return _stick_light(state.flags, takers)


def lab_plc_light(state) -> Light:
    """The lab's PLC link: none (the plant is simulated), connecting, lost, invalid data, stale, the PLC's error, or
    its state."""
    pl = state.plant
    if pl is None or pl.backend != "plc":
        return Light("off", "none: simulated plant")
    if pl.link == "lost":
        return Light("error", f"LOST: {pl.last_error}")
    if pl.link == "connecting":
        return Light("warn", f"connecting: {pl.last_error or pl.target}")
    if pl.link == "invalid":  # issue 27: values refused as they arrived; motion refused
        first = pl.invalid[0] if pl.invalid else "a value refused"
        return Light("error", f"INVALID DATA: {first}")
    if pl.plc_error:
        return Light("error", f"ERROR: {pl.plc_error}")
    if pl.link == "stale":
        return Light("warn", f"no data for {pl.data_age:.1f} s")
    return Light("ok", pl.plc_state or "connected")


def lab_lights(state) -> dict[str, Light]:
    return {
        "engine": engine_light(state),
        "input": lab_input_light(state),
        "plant": lab_plant_light(state),
        "plc": lab_plc_light(state),
    }


#: the lights of each scene (``Snapshot.kind``)
RULES: dict[str, Callable[[object], dict[str, Light]]] = {"teleop": teleop_lights, "tac": tac_lights, "lab": lab_lights}


def scene_lights(state) -> dict[str, Light]:
    """Every light of the scene ``state`` comes from (a typed snapshot): name -> :class:`Light`."""
    return RULES[state.kind](state)


ROOM = {"engine": 2, "input": 3, "plant": 4, "plc": 2}  # the longest details get the most of a row's width


class SceneLights(QWidget):
    """One engine's lights in a row, headed by the engine's name; fed by its states (:meth:`show_state`) and
    its link (:meth:`show_lost`).  ``lights``: (key, shown name, tool tip) of each light; ``padding``: the
    lights' CSS padding (a page's row: "1px 6px", as low as a line of text)."""

    def __init__(
        self, title: str, lights: tuple[tuple[str, str, str], ...], parent=None, padding: str = "2px 6px"
    ) -> None:
        super().__init__(parent)
        row = QHBoxLayout(self)
        row.setContentsMargins(0, 0, 0, 0)
        self.title = QLabel(f"<b>{title}</b>")
        if not title:
            self.title.hide()
        row.addWidget(self.title)
        self.lights = {key: StatusLight(name, tip, padding=padding) for key, name, tip in lights}
        for key, w in self.lights.items():
            w.setMinimumWidth(90)
            row.addWidget(w, ROOM.get(key, 1))

    def set_lights(self, lights: dict[str, Light]) -> None:
        for key, light in lights.items():
            if key in self.lights:
                self.lights[key].set(light.look, light.detail, light.tip)

    def show_state(self, state) -> None:
        self.set_lights(scene_lights(state))

    def show_lost(self) -> None:
        """The engine is out of reach: nothing is known of its input or machines."""
        self.set_lights({**LOST, "plc": Light("unknown", "unknown")})


TELEOP_LIGHTS = (
    ("engine", "teleop engine", "the teleop engine: connection and loop"),
    ("input", "teleop input", "the teleop arm's input: joystick, on-screen stick or keyboard"),
    ("plant", "teleop arm", "the teleoperated arm: moving, ready, holding, E-STOP (braking, stopped)"),
)


class StatusPanel(QWidget):
    stop_clicked = pyqtSignal()
    reset_clicked = pyqtSignal()
    role_clicked = pyqtSignal()  # release the operator role, or take it when free

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(4, 2, 4, 2)
        self.setMaximumHeight(230)  # the machines stay in view on a 800-px screen
        left = QVBoxLayout()
        # the teleop engine's lights, named so (the crane-head and Motion-Lab pages show their own engine's):
        # a light here never speaks for a machine on another tab (issue 26, item 6)
        self.row = SceneLights("", TELEOP_LIGHTS)
        self.lights = dict(self.row.lights)
        # the lab's PLC light is on the Motion-Lab page (here it said "PLC: simulated" on the crane-head tab)
        left.addWidget(self.row)
        split = QSplitter(Qt.Horizontal)
        self.alarms = AlarmPanel()
        split.addWidget(self.alarms)
        self.log_view = QPlainTextEdit()
        self.log_view.setReadOnly(True)
        self.log_view.setMaximumBlockCount(2000)
        self.log_view.setToolTip("event log (UTC time stamps); always scrolled to the newest line")
        self.log_view.setFocusPolicy(Qt.NoFocus)
        split.addWidget(self.log_view)
        split.setSizes([560, 440])
        left.addWidget(split, 1)
        lay.addLayout(left, 1)
        right = QVBoxLayout()
        # the column's buttons never take the keyboard: Space stays STOP everywhere
        self.stop = button(
            "STOP",
            "E-STOP: stops every machine within one engine tick and latches (Space from any tab or dialog, except "
            "in a text field that has the keyboard, where Space types; Ctrl+Space everywhere; the joystick's stop "
            "button)",
            keyboard=False,
        )
        self.stop.setMinimumSize(150, 80)
        f = QFont()
        f.setPointSize(22)
        f.setBold(True)
        self.stop.setFont(f)
        self.stop.setStyleSheet(
            "QPushButton { background: #c9302c; color: white; border-radius: 8px; }"
            "QPushButton:pressed { background: #8b1e1b; }"
        )
        self.stop.pressed.connect(self.stop_clicked)  # on press: a press that slides off still stops
        right.addWidget(self.stop)
        self.latched = QLabel("")
        self.latched.setStyleSheet("color: #d9534f; font-weight: bold;")
        right.addWidget(self.latched)
        self.reset = button(
            "Reset E-STOP",
            "clear a latched E-STOP (operator only); every machine keeps holding until you command it anew: "
            "centre the stick and press enable, or choose a mode",
            self.reset_clicked,
            keyboard=False,
        )
        self.reset.setEnabled(False)
        right.addWidget(self.reset)
        self.role = QLabel("role: –")
        self.role.setWordWrap(True)
        # a fixed room for three engines' lines: the STOP column never widens or grows when an engine connects
        self.role.setFixedWidth(190)
        self.role.setFixedHeight(3 * self.role.fontMetrics().lineSpacing() + 4)
        self.role.setAlignment(Qt.AlignLeft | Qt.AlignTop)
        self.role.setToolTip("who holds the operator role of each engine; viewers see everything and may STOP")
        right.addWidget(self.role)
        self.role_button = button(
            "Release operator role",
            "release: the engines hold and another console may take over; take: become the operator where the "
            "role is free (you start disarmed)",
            self.role_clicked,
            keyboard=False,
        )
        right.addWidget(self.role_button)
        right.addStretch(1)
        lay.addLayout(right)

    def add_log(self, level: str, text: str) -> None:
        stamp = time.strftime("%H:%M:%S", time.gmtime())
        self.log_view.appendPlainText(f"{stamp}  {level.upper():7s} {text}")
        bar = self.log_view.verticalScrollBar()
        bar.setValue(bar.maximum())  # always the newest entry, also after the operator scrolled up

    def show_estop(self, latched: bool) -> None:
        if latched == getattr(self, "_latched_shown", None):
            return
        self._latched_shown = latched
        self.latched.setText("E-STOP LATCHED" if latched else "")
        self.reset.setEnabled(latched)

    def show_roles(self, rows: list[tuple[str, str, str]]) -> None:
        """``rows``: (engine, this console's role, operator name) per engine."""
        text = "<br>".join(
            f"{origin}: <b>{'you operate' if role == 'operator' else 'viewer'}</b>"
            + ("" if role == "operator" else f" (operator: {op or 'free'})")
            for origin, role, op in rows
        )
        if text != self.role.text():
            self.role.setText(text or "role: –")
        mine = any(role == "operator" for _, role, _ in rows)
        label = "Release operator role" if mine else "Take operator role"
        if self.role_button.text() != label:
            self.role_button.setText(label)
        free = any(role != "operator" and not op for _, role, op in rows)
        self.role_button.setEnabled(mine or free)

    def show_teleop(self, state) -> None:
        """The teleop engine's lights from its state (:func:`teleop_lights`)."""
        self.row.show_state(state)

    def set_lost(self) -> None:
        """The engine is out of reach: nothing is known about input or plant."""
        self.row.show_lost()
