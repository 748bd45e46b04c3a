"""Issue 30, item 2: the crane-head scene takes the stick.  The operator moves the TCP's target in the world while
the head (tac) or the crane and head (cooperative) cancel the vessel's motion; the stick's rules (arming, deadman,
stale halt), the mode's range with its alarm, and nothing in ``off`` or while stopped."""

import numpy as np
import pytest

from app.engine.tac_session import TCP_SPEED, TacSession
from app.scenarios.tac import TacScenario
from app.teleop.devices import InputSample
from tests.test_safety_engine import run_lab as run  # the engines' tick loop at 50 Hz (DT)

DT = 0.02  # the engine's 50 Hz


def stick(x=0.0, y=0.0, z=0.0, enable=True):
    return InputSample((x, -y, z, 0.0), (enable, False), "test stick")  # default profile: axis 1 is -y


def arm(ses, t0=0.0):
    t = run(ses, 0.1, stick(enable=False), t0)
    return run(ses, 0.1, stick(enable=True), t)


def session(mode: str, hs: float = 3.0) -> TacSession:
    return TacSession(scenario=TacScenario(duration=1e5, hs=hs, mode=mode))  # its input has 4 axes: x, y, z, w


@pytest.mark.parametrize("mode", ["tac", "cooperative"])
def test_the_stick_moves_the_tcp_in_the_world_while_the_machine_cancels_the_sea(mode):
    """Hs 3 m, beam sea: 1 s of full stick along x moves the target 0.5 m north (in {n}); the TCP follows it
    and holds it, its error to the moving target a small part of what the sea does to an uncompensated TCP."""
    ses = session(mode)
    t = run(ses, 5.0)  # the sea builds, the machine compensates
    t = arm(ses, t)
    p0 = np.array(ses.sim.p_d_n)
    t = run(ses, 1.0, stick(x=1.0), t)
    moved = np.array(ses.sim.p_d_n) - p0
    np.testing.assert_allclose(moved, [TCP_SPEED * 1.0, 0.0, 0.0], atol=1e-9)
    e_c, e_s = [], []
    for _ in range(150):  # 3 s, stick centred: the target holds in the world
        t = run(ses, DT, stick(), t)
        e_c.append(ses.last["e_c"])
        e_s.append(ses.last["e_s"])
    np.testing.assert_allclose(np.array(ses.sim.p_d_n) - p0, moved, atol=0)
    assert np.sqrt(np.mean(np.square(e_c))) < 0.1 * np.sqrt(np.mean(np.square(e_s))), (np.mean(e_c), np.mean(e_s))


def test_stick_up_raises_the_target_and_y_moves_it_east():
    ses = session("cooperative", hs=0.5)
    t = arm(ses, run(ses, 1.0))
    p0 = np.array(ses.sim.p_d_n)
    run(ses, 0.4, stick(y=1.0, z=1.0), t)
    d = np.array(ses.sim.p_d_n) - p0
    assert d[1] > 0.15 and d[2] < -0.15 and abs(d[0]) < 1e-12  # NED: east is +y, up is −z


def test_nothing_moves_the_target_in_off_unarmed_stale_or_stopped():
    ses = session("off", hs=0.5)
    p0 = np.array(ses.sim.p_d_n)
    t = run(ses, 0.5, stick(x=1.0), arm(ses))  # off: the head is held, the stick does nothing
    np.testing.assert_array_equal(ses.sim.p_d_n, p0)
    ses.set_tac_mode("tac")  # a mode change disarms: the held stick moves nothing
    t = run(ses, 0.5, stick(x=1.0), t)
    np.testing.assert_array_equal(ses.sim.p_d_n, p0)
    assert not ses.snapshot().flags.armed
    t = arm(ses, t)
    t = run(ses, 0.2, stick(x=1.0), t)
    p1 = np.array(ses.sim.p_d_n)
    assert p1[0] - p0[0] > 0.05
    t = run(ses, 0.5, None, t)  # the device goes silent: stale after 0.2 s, and the target holds
    assert np.array(ses.sim.p_d_n)[0] - p1[0] <= TCP_SPEED * 0.24  # at most the stale time's travel
    p1 = np.array(ses.sim.p_d_n)
    t = run(ses, 1.0, None, t)
    np.testing.assert_array_equal(ses.sim.p_d_n, p1)
    assert ses.snapshot().flags.stale_input
    ses.estop()
    run(ses, 0.5, stick(x=1.0), t)
    np.testing.assert_array_equal(ses.sim.p_d_n, p1)


def test_the_target_stops_at_the_modes_range_with_its_alarm_and_survives_a_sea_change():
    ses = session("tac", hs=0.5)
    t = arm(ses, run(ses, 0.5))
    t = run(ses, 4.0, stick(x=1.0), t)  # 2 m asked for: beyond the head's range (a quarter of its workspace)
    off = np.array(ses.sim.p_d_n) - ses.sim.p_d_n0
    # issue 32, item 5: slowed through the range's outer quarter, it comes up to the edge and never past it
    assert 0.0 < ses.target_range["tac"][0] - off[0] < 0.2 * 0.25 * ses.target_range["tac"][0]
    assert ses.target_limited
    assert ses.snapshot().hazard.kind == "workspace" and ses.snapshot().hazard.name == "tac range x"
    t = run(ses, 0.5, stick(x=1.0), t)
    assert "target_limit" in {a["key"] for a in ses.alarms.snapshot()}
    held = np.array(ses.sim.p_d_n)
    ses.set_sea("jonswap", 1.0, 8.0, 90.0)  # a new sea continues the run: the operator's target stays
    np.testing.assert_array_equal(ses.sim.p_d_n, held)


def test_h124_at_rest_the_hazard_line_still_names_the_range_edge_the_target_stands_near():
    """H124 in the crane head: the hazard was the stick's last command's, emptied whenever it rested, so a target
    held 2 cm from its range's edge read "none near".  At rest (centred, released, E-STOP) it names that edge, not
    slowing; away from every edge, nothing."""
    ses = session("tac", hs=0.5)
    assert ses.snapshot().hazard.kind == ""  # the target at the range's centre
    t = arm(ses, run(ses, 0.5))
    t = run(ses, 4.0, stick(x=1.0), t)  # up to the edge of x (test above)
    assert ses.snapshot().hazard.slowed
    gap = ses.target_range["tac"][0] - (ses.sim.p_d_n[0] - ses.sim.p_d_n0[0])
    for rest in ("centred", "E-STOP"):
        if rest == "E-STOP":
            ses.estop()
        t = run(ses, 0.5, stick(), t)
        hz = ses.snapshot().hazard
        assert (hz.kind, hz.name, hz.slowed) == ("workspace", "tac range x", False), rest
        assert hz.value == pytest.approx(gap, abs=1e-9) and hz.text == f"tac range x: {gap:.2f} m to its edge", rest
