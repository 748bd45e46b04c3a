"""Lights from what the machine reports (issue 26, items 5-6; docs/safety.md H71-H74): the rules of
ui/widgets/status.py fed by the real engines' states, in process, each state through the wire
(``to_wire`` → ``snapshot_from_wire``) as a client receives it.  The GUI shows these lights
(tests/test_gui_lights.py)."""

import pytest

pytest.importorskip("PyQt5")

from app.engine.lab_session import LabSession
from app.engine.session import Session
from app.engine.tac_session import TacSession
from app.net.snapshots import snapshot_from_wire, to_wire
from app.teleop.devices import InputSample
from ui.widgets.status import Light, lab_input_light, lab_plant_light, lab_plc_light, scene_lights, tac_lights

DT = 0.02


def _wire(ses):
    """The state a client receives."""
    return snapshot_from_wire(to_wire(ses.snapshot()))


def _run(ses, t: float, seconds: float, enable: bool | None = None, jog=None) -> float:
    """Tick ``seconds`` of engine time; ``enable``: feed a centred stick with the deadman so every tick (None:
    no input); ``jog``: ``(joint, speed)`` refreshed every tick, as the GUI's held button does."""
    for _ in range(round(seconds / DT)):
        t += DT
        if jog is not None:
            ses.lab_comau_jog(*jog)
        if enable is not None:
            ses.feed(InputSample((0.0, 0.0, 0.0, 0.0), (enable,), "test stick"), t)
        ses.tick(t, DT)
    return t


def _lab_at_neutral() -> LabSession:
    """A lab engine with both platforms at rest at NEUTRAL (a scenario's start: no 0.9 m raise to wait for)."""
    ses = LabSession()
    for p in ses.lab.platforms:
        p.place_at_neutral()
    return ses


def test_lab_plant_light_engaged_vvmc_estop_and_reset():
    """Item 6: both platforms engaged with VVMC on is "compensating", never "holding"; item 5's E-STOP is
    red, braking then stopped; after the reset the machines wait for the operator: "holding"."""
    ses = _lab_at_neutral()
    t = _run(ses, 0.0, 0.2)
    light = lab_plant_light(_wire(ses))
    assert (light.look, light.detail) == ("off", "at rest")
    for name in ("em8000", "em1500"):
        ses.lab_platform(name, "engage")
    t = _run(ses, t, 1.0)
    light = lab_plant_light(_wire(ses))
    assert light.look == "ok" and light.detail == "moving: EM8000 engaging, EM1500 engaging"
    ses.lab_vvmc(True)
    t = _run(ses, t, 5.0)
    st = _wire(ses)
    assert [p.status for p in st.platforms] == ["engaged", "engaged"] and st.vvmc
    light = lab_plant_light(st)
    assert light.look == "ok" and light.detail == "compensating: VVMC, EM8000 engaged, EM1500 engaged"
    ses.estop()
    t = _run(ses, t, DT)
    light = lab_plant_light(_wire(ses))
    assert light.look == "error" and light.detail.startswith("E-STOP: braking") and "EM8000" in light.detail
    t = _run(ses, t, 4.0)
    assert lab_plant_light(_wire(ses)) == Light("error", "E-STOP: stopped")
    ses.reset()
    _run(ses, t, 0.5)
    light = lab_plant_light(_wire(ses))
    assert light.look == "warn" and light.detail == "holding: EM8000, EM1500, Comau: choose a mode"


def test_lab_input_light_names_the_jog_the_stick_and_none():
    """Item 6: a running joint jog is the operator's input ("jog q2 +50 %"), never "no input"; the armed
    stick drives the Comau in REMOTE; with VVMC on it drives the work point and the load (issue 30, item 4: "Comau
    VVMC and winch VVMC"), disarmed by the switch; under E-STOP none is taken."""
    ses = LabSession()
    t = _run(ses, 0.0, 0.1, enable=False)
    light = lab_input_light(_wire(ses))
    assert light.look == "off" and light.detail.startswith("idle")  # nothing to act on: grey, not amber
    t = _run(ses, t, 0.1, enable=True)  # enable pressed at neutral: armed
    light = lab_input_light(_wire(ses))
    assert light.look == "ok" and light.detail == "enabled: test stick drives Comau REMOTE"
    t = _run(ses, t, 0.3, enable=True, jog=(2, 0.5))
    st = _wire(ses)
    assert st.comau_jog.joint == 2 and abs(st.comau.qd[1]) > 0.0
    light = lab_input_light(st)
    assert light.look == "ok" and light.detail == "jog q2 +50 % (test stick)"
    assert lab_plant_light(st).detail == "moving: Comau jog q2"
    ses.lab_comau_jog(2, 0.0)
    t = _run(ses, t, 0.1, enable=False)
    light = lab_input_light(_wire(ses))
    assert light.look == "off" and light.detail == "idle: test stick (enable released)"  # released: disarmed
    ses.lab_vvmc(True)
    t = _run(ses, t, 0.1, enable=False)
    assert lab_input_light(_wire(ses)).detail == "idle: test stick (enable released)"
    t = _run(ses, t, 0.1, enable=True)  # armed again at neutral: the stick drives under VVMC
    assert lab_input_light(_wire(ses)).detail == "enabled: test stick drives Comau VVMC and winch VVMC"
    ses.estop()
    _run(ses, t, 0.1, enable=False)
    assert lab_input_light(_wire(ses)).detail == "not taken: E-STOP latched"


def test_lab_plc_light_says_the_plant_is_simulated():
    """Item 6: without a PLC the light does not call anything a PLC: "none: simulated plant"."""
    light = lab_plc_light(_wire(LabSession()))
    assert (light.look, light.detail) == ("off", "none: simulated plant")


def test_crane_head_lights_compensating_estop_holding_and_off():
    """Item 6: the head compensating in tac mode is "compensating", not "holding"; E-STOP red; after the
    reset it holds until a mode is chosen; mode off locks the head.  The stick's light follows the stick's rules
    where it moves the TCP's target (tac, cooperative: issue 30, item 2), and says "not used" where it moves
    nothing; no PLC light."""
    ses = TacSession()
    t = _run(ses, 0.0, 1.0)
    lights = tac_lights(_wire(ses))
    assert set(lights) == {"engine", "input", "plant"}  # no PLC: the crane head has none
    assert lights["plant"].look in ("ok", "warn") and lights["plant"].detail.startswith("compensating: head (tac)")
    assert (lights["input"].look, lights["input"].detail) == ("off", "no input device")
    ses.set_tac_mode("cooperative")
    t = _run(ses, t, 0.2)
    assert tac_lights(_wire(ses))["plant"].detail.startswith("compensating: crane and head (cooperative)")
    ses.estop()
    t = _run(ses, t, 0.2)
    plant = tac_lights(_wire(ses))["plant"]
    assert (plant.look, plant.detail) == ("error", "E-STOP: head and crane stopped")
    assert tac_lights(_wire(ses))["input"].detail.startswith("not used (E-STOP)")
    ses.reset()
    t = _run(ses, t, 0.2)
    plant = tac_lights(_wire(ses))["plant"]
    assert (plant.look, plant.detail) == ("warn", "holding: choose a compensation mode")
    ses.set_tac_mode("off")
    _run(ses, t, 0.2)
    plant = tac_lights(_wire(ses))["plant"]
    assert (plant.look, plant.detail) == ("off", "head locked (mode off): not compensating")


def test_teleop_arm_light_follows_the_joint_speeds():
    """The teleop arm's light (the status area's row): E-STOP red, braking then stopped; a held arm
    "at rest (holding)", grey (the idle state is not abnormal); no PLC light for this engine either."""
    ses = Session(robot_name="comau_smart5_3dof")
    t = 0.0
    for _ in range(5):
        t += DT
        ses.tick(t, DT)
    lights = scene_lights(_wire(ses))
    assert set(lights) == {"engine", "input", "plant"}
    assert (lights["plant"].look, lights["plant"].detail) == ("off", "at rest (holding)")
    ses.estop()
    ses.tick(t + DT, DT)
    plant = scene_lights(_wire(ses))["plant"]
    assert plant.look == "error" and plant.detail == "E-STOP: stopped"


def test_lab_lights_say_the_plc_data_is_invalid_and_held():
    """Issue 27, item 7: a link whose values were refused as they arrived (NaN, beyond the machine's range) is
    not "ok": the PLC light is red with the first refused value, the plant light says what is drawn is held."""
    import dataclasses

    from app.net.snapshots import PlantLink

    snap = _wire(LabSession())
    bad = "MAIN.em8000.txHmi.eta[4] = nan (not a finite number): holding the last valid value, 0.4 s old"
    link = PlantLink(backend="plc", link="invalid", connected=True, plc_state="NORMAL", invalid=[bad])
    state = snapshot_from_wire(to_wire(dataclasses.replace(snap, plant=link)))  # the new fields over the wire
    assert state.plant.invalid == [bad]
    plc = lab_plc_light(state)
    assert (plc.look, plc.detail) == ("error", f"INVALID DATA: {bad}")
    plant = lab_plant_light(state)
    assert plant.look == "warn" and plant.detail.endswith("(PLC data invalid: the last valid values, held)")
