"""Issue 30, item 1: command frames in the universal mapping (eqs. 1, 2 and 7 in the frame the operator picks).

The teleop scene takes ``world`` (earth-fixed: the papers' mapping, the default), ``base`` and ``tool``; it has no
target deck (the lab's REMOTE under VVMC commands in EM1500's frame: tests/test_lab_remote_vvmc.py)."""

from pathlib import Path

import numpy as np
import pytest

from app.engine.session import CommandError, Session
from app.teleop.mapping import in_frame
from tests.test_engine_session import arm, run, sample

ROOT = Path(__file__).resolve().parents[1]


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def test_in_frame_rotates_the_command_and_the_world_frame_leaves_it_as_it_is():
    v = np.array([0.3, -0.2, 0.1])
    assert in_frame(v, None) is not None and np.array_equal(in_frame(v, None), v)
    Rz = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90° about z
    np.testing.assert_allclose(in_frame([1.0, 0.0, 0.0], Rz), [0.0, 1.0, 0.0], atol=1e-15)


def test_tool_frame_velocity_moves_the_tool_along_its_own_x():
    """Velocity mode, stick x: in the world frame the tool moves along world x; in the tool frame along the tool's
    x axis as it was (the 6-DOF Comau's tool points elsewhere than world x at its mid-range pose)."""
    ses = Session(robot_name="comau_smart5_6dof", solver_name="jacobian", mode="velocity")
    tool_x = ses.robot.fk(ses.q_ref)[:3, 0]
    assert abs(tool_x @ [1.0, 0.0, 0.0]) < 0.9  # a pose whose tool x is not world x: the frames differ
    ses.set_frame("tool")
    p0 = np.array(ses.snapshot().tool)
    run(ses, 0.3, sample(x=1.0), t0=arm(ses))
    d = np.array(ses.snapshot().tool) - p0
    assert np.linalg.norm(d) > 0.02 and _unit(d) @ tool_x > 0.97, (d, tool_x)
    assert ses.snapshot().frame == "tool"


def test_base_frame_follows_the_robots_base_turned_on_its_mounting():
    """A robot file whose base is turned 90° about z: the stick's x moves the tool along the base's x, world y."""
    xml = (ROOT / "robots" / "comau_smart5_3dof.xml").read_text(encoding="utf-8")
    xml = xml.replace("  <serial>", '  <serial>\n    <base xyz="0 0 0" rpy="0 0 90"/>', 1)
    ses = Session(mode="velocity", solver_name="jacobian")
    ses.set_robot("turned_base", xml=xml)
    np.testing.assert_allclose(ses.robot.T_world_base[:3, 0], [0.0, 1.0, 0.0], atol=1e-12)
    ses.set_frame("base")
    p0 = np.array(ses.snapshot().tool)
    run(ses, 0.5, sample(x=1.0), t0=arm(ses))
    d = np.array(ses.snapshot().tool) - p0
    assert np.linalg.norm(d) > 0.05 and _unit(d) @ [0.0, 1.0, 0.0] > 0.97, d


def test_position_mode_in_the_tool_frame_uses_the_frame_at_arming():
    """Eq. (1) in the tool frame: x_ds = x_w + R_w^tool(at arming) (k_p ⊙ s), the frame held while armed."""
    ses = Session(robot_name="comau_smart5_6dof", solver_name="jacobian", mode="velocity")
    ses.set_mode("position")
    ses.set_frame("tool")
    R0 = ses.robot.fk(ses.q_ref)[:3, :3]
    start = np.array(ses.scaling.x_w)
    run(ses, 2.0, sample(x=0.5), t0=arm(ses))
    s = ses.snapshot().signal[0]
    expected = start + R0 @ np.array([s * ses.scaling.k_p[0], 0.0, 0.0])
    np.testing.assert_allclose(ses.command_point, expected, atol=1e-12)


def test_changing_the_frame_disarms_and_a_deflected_stick_moves_nothing():
    """Safety H96: the frame changed while the stick is deflected stops the arm as a released stick does (the
    same stopping point), and nothing moves until the operator re-arms at neutral."""
    stops = []
    for change in (True, False):
        ses = Session(mode="velocity", solver_name="jacobian")
        t = run(ses, 0.2, sample(x=1.0), t0=arm(ses))
        assert ses.snapshot().flags.armed
        if change:
            ses.set_frame("tool")
            t = run(ses, 0.5, sample(x=1.0), t0=t)  # still deflected, enable held
            assert not ses.snapshot().flags.armed
        else:
            t = run(ses, 0.5, sample(), t0=t)  # the stick released instead
        stops.append(np.array(ses.snapshot().q_ref))
        run(ses, 0.5, sample(x=1.0) if change else sample(), t0=t)
        np.testing.assert_array_equal(ses.snapshot().q_ref, stops[-1])  # and it holds there
    np.testing.assert_allclose(stops[0], stops[1], atol=1e-9)


def test_a_frame_the_scene_lacks_or_does_not_know_is_refused_with_a_reason():
    ses = Session()
    with pytest.raises(CommandError, match="no target deck"):
        ses.set_frame("target")
    with pytest.raises(CommandError, match="frame must be one of"):
        ses.set_frame("sideways")
    assert ses.frame == "world"


def test_the_crane_and_lab_scenes_answer_a_frame_request_with_their_frame():
    """The crane-head scene commands the TCP in the world, the vessel's (base) or the target deck's frame (the
    tool frame refused with the reason); the lab's frames follow its mode (REMOTE: the Comau's base; VVMC: EM1500's
    deck, the target, or the lab's world), so a request for another says which it may be."""
    from app.engine.lab_session import LabSession
    from app.engine.tac_session import TacSession

    tac = TacSession()
    tac.set_tac_mode("cooperative")  # the base frame follows the vessel: it needs the crane (H107)
    tac.set_frame("world")
    tac.set_frame("target")
    tac.set_frame("base")
    with pytest.raises(CommandError, match="the head's frame is not in this scene"):
        tac.set_frame("tool")
    lab = LabSession()
    lab.set_frame("base")
    with pytest.raises(CommandError, match=r"now REMOTE: base \(turn VVMC on for target or world\)"):
        lab.set_frame("world")
    lab.lab_vvmc(True)
    assert lab.snapshot().frame == "target"
    with pytest.raises(CommandError, match="now VVMC on: target or world"):
        lab.set_frame("base")
    lab.set_frame("world")
    assert lab.snapshot().frame == "world" and lab.lab.work_frame == "world"
    lab.lab_vvmc(False)
    lab.lab_vvmc(True)
    assert lab.snapshot().frame == "target"  # a VVMC starts in EM1500's frame
