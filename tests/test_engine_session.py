"""Engine session: mapping to motion, safety rules, command errors, and the limits property."""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from app.engine.session import CommandError, Session
from app.sim.actuators import JointActuators
from app.teleop.devices import InputSample
from app.teleop.profiles import default_profile

ROOT = Path(__file__).resolve().parents[1]
DT = 0.002  # 500 Hz


def sample(x=0.0, y=0.0, z=0.0, enable=True, device="test stick"):
    # default profile: axes 0,1,2 -> x, -y, z; deadman on button 0
    return InputSample((x, -y, z), (enable, False), device)


def arm(session, t0=0.0):
    """The operator's arming gesture: stick at neutral with enable released, then enable pressed."""
    t = t0
    for en in (False, True):
        t += DT
        session.feed(sample(enable=en), t)
        session.tick(t, DT)
    assert session.snapshot().flags.enabled
    return t


def run(session, seconds, s=None, t0=0.0, feed=True):
    t = t0
    for _ in range(round(seconds / DT)):
        t += DT
        if feed:
            session.feed(s, t)
        session.tick(t, DT, solve_budget=0.4 * DT)  # as the engine loop gives it
    return t


def test_velocity_mode_moves_tool_along_the_stick():
    ses = Session(robot_name="comau_smart5_3dof", solver_name="jacobian", mode="velocity")
    p0 = np.array(ses.snapshot().tool)
    run(ses, 1.0, sample(x=1.0), t0=arm(ses))
    p1 = np.array(ses.snapshot().tool)
    d = p1 - p0
    assert d[0] > 0.2 and abs(d[1]) < 0.02 * d[0] and abs(d[2]) < 0.02 * d[0]  # straight along +x


def test_velocity_release_stops_and_holds():
    ses = Session(mode="velocity")
    t = run(ses, 0.5, sample(x=1.0), t0=arm(ses))
    t = run(ses, DT, sample(), t0=t)  # stick released: the reference is where the joints can stop
    q_ref = np.array(ses.snapshot().q_ref)
    t = run(ses, 0.5, sample(), t0=t)  # and no longer moves
    np.testing.assert_array_equal(ses.snapshot().q_ref, q_ref)
    p_a = np.array(ses.snapshot().tool)
    run(ses, 0.5, sample(), t0=t)
    # the first-order servo (tau 50 ms) has settled onto the held reference
    np.testing.assert_allclose(ses.snapshot().tool, p_a, atol=1e-5)
    np.testing.assert_allclose(ses.snapshot().q, q_ref, atol=1e-6)
    assert np.abs(ses.snapshot().qdot).max() < 1e-4


def test_position_mode_follows_and_returns_to_start():
    ses = Session(mode="velocity")
    ses.set_mode("position")
    start = np.array(ses.scaling.x_w)
    t = run(ses, 2.0, sample(z=0.5), t0=arm(ses))
    s = ses.snapshot().signal[2]
    assert s == pytest.approx((0.5 - 0.1) / 0.9)  # default profile: deadzone 0.1, rescaled
    np.testing.assert_allclose(ses.snapshot().tool, start + np.array([0, 0, s * ses.scaling.k_p[2]]), atol=1e-3)
    run(ses, 3.0, sample(), t0=t)  # released: back to the starting point
    np.testing.assert_allclose(ses.snapshot().tool, start, atol=1e-3)


def test_deadman_released_holds():
    ses = Session()
    t = run(ses, 0.3, sample(x=1.0), t0=arm(ses))
    t = run(ses, 0.5, sample(x=1.0, enable=False), t0=t)
    p = np.array(ses.snapshot().tool)
    run(ses, 0.5, sample(x=1.0, enable=False), t0=t)
    np.testing.assert_allclose(ses.snapshot().tool, p, atol=1e-9)
    assert not ses.snapshot().flags.enabled


def test_stale_input_stops_within_bound():
    ses = Session()
    t = run(ses, 0.5, sample(x=1.0), t0=arm(ses))
    v_before = np.abs(ses.actuators.qdot).max()
    assert v_before > 0
    # the device goes silent: no new samples are fed
    t_silent = t
    t = run(ses, 0.2, feed=False, t0=t)
    assert ses.snapshot().flags.stale_input
    p = np.array(ses.snapshot().tool)
    run(ses, 0.5, feed=False, t0=t)
    # the stop started at 200 ms; braking at the acceleration limit (Comau has none: immediate)
    np.testing.assert_allclose(ses.snapshot().tool, p, atol=1e-6)
    assert t - t_silent >= ses.stale_timeout


def test_unplugged_device_holds_and_warns():
    ses = Session()
    t = run(ses, 0.3, sample(x=1.0), t0=arm(ses))
    ses.feed(None, t)
    t = run(ses, 0.3, feed=False, t0=t)
    p = np.array(ses.snapshot().tool)
    run(ses, 0.3, feed=False, t0=t)
    np.testing.assert_allclose(ses.snapshot().tool, p, atol=1e-9)
    assert any("disconnected" in e.text for e in ses.log) and not ses.snapshot().flags.device


def test_estop_stops_in_one_tick_and_latches():
    ses = Session(robot_name="offshore_crane")
    t = run(ses, 1.0, sample(x=1.0), t0=arm(ses))
    assert np.abs(ses.actuators.qdot).max() > 0
    ses.estop()
    t += DT
    ses.feed(sample(x=1.0), t)
    ses.tick(t, DT)
    assert np.all(ses.actuators.qdot == 0)
    p = np.array(ses.snapshot().tool)
    t = run(ses, 0.5, sample(x=1.0), t0=t)  # input keeps pushing: nothing moves while latched
    np.testing.assert_allclose(ses.snapshot().tool, p, atol=0)
    assert ses.snapshot().estop
    with pytest.raises(CommandError, match="E-STOP is latched"):
        ses.set_robot("scara")
    ses.reset()
    t = run(ses, 0.5, sample(x=1.0), t0=t)  # the stick still deflected at the reset does not count
    assert not ses.snapshot().estop
    np.testing.assert_allclose(ses.snapshot().tool, p, atol=1e-9)
    run(ses, 0.5, sample(x=1.0), t0=arm(ses, t))
    assert np.linalg.norm(np.array(ses.snapshot().tool) - p) > 1e-3


def test_bad_commands_leave_state_unchanged(tmp_path):
    ses = Session(robot_name="scara", robots_dirs=(str(tmp_path),))
    bad = tmp_path / "bad.xml"
    bad.write_text("<robot>", encoding="utf-8")
    with pytest.raises(CommandError, match=r"bad\.xml:1: XML syntax error"):
        ses.set_robot(str(bad))
    with pytest.raises(CommandError, match="unknown robot"):
        ses.set_robot("nope")
    with pytest.raises(CommandError, match="unknown solver"):
        ses.set_solver("magic")
    with pytest.raises(CommandError, match="mode must be"):
        ses.set_mode("turbo")
    with pytest.raises(CommandError, match="k_v must be 3 finite"):
        ses.set_scaling(k_v=float("nan"))
    assert ses.robot_name == "scara" and ses.solver_name == "jacobian" and ses.mode == "velocity"


def test_switching_robot_and_solver_while_running():
    ses = Session(robot_name="comau_smart5_3dof", solver_name="analytic")
    t = run(ses, 0.2, sample(x=0.5), t0=arm(ses))
    q_moving = ses.actuators.q.copy()
    with pytest.raises(CommandError, match="the robot is moving"):  # issue 13: no reload mid-motion
        ses.set_robot("kuka_youbot")
    assert ses.robot_name == "comau_smart5_3dof"
    t = run(ses, 1.0, sample(enable=False), t0=t)  # released: the arm comes to rest
    assert not ses.moving() and np.linalg.norm(ses.actuators.q - q_moving) < 0.1
    ses.set_robot("kuka_youbot")  # no closed form: falls back to the Jacobian solver
    assert ses.robot_name == "kuka_youbot" and ses.solver_name == "jacobian"
    assert not ses.snapshot().flags.armed  # a robot change needs a fresh command
    ses.set_solver("ga")
    run(ses, 0.2, sample(z=0.5), t0=arm(ses, t))
    assert len(ses.snapshot().q) == 5


def test_reloading_the_same_robot_at_rest_keeps_the_arm_where_it_stands():
    ses = Session(robot_name="comau_smart5_3dof")
    t = run(ses, 0.5, sample(x=0.5, z=0.5), t0=arm(ses))
    t = run(ses, 1.0, sample(enable=False), t0=t)
    q = ses.actuators.q.copy()
    assert np.linalg.norm(q - 0.5 * (ses.robot.lower + ses.robot.upper)) > 1e-2  # it has moved
    ses.set_robot("comau_smart5_3dof")
    np.testing.assert_array_equal(ses.actuators.q, q)  # no jump to mid-range


def test_set_robot_reads_paths_only_inside_the_allowed_robot_folders(tmp_path, monkeypatch):
    """Issue 13, item 9: set_robot parsed /etc/shadow, echoed its content and told which files exist."""
    monkeypatch.delenv("BOSUN_ROBOTS_DIR", raising=False)
    secret = tmp_path / "outside" / "secret.xml"
    secret.parent.mkdir()
    secret.write_text("<robot>top secret content</robot>", encoding="utf-8")
    allowed = tmp_path / "robots"
    allowed.mkdir()
    (allowed / "arm.xml").write_text((ROOT / "robots" / "scara.xml").read_text(encoding="utf-8"), encoding="utf-8")
    (allowed / "escape.xml").symlink_to(secret)
    ses = Session(robot_name="comau_smart5_3dof", robots_dirs=(str(allowed),))
    for ref in [
        "/etc/shadow",
        "/etc/passwd.xml",
        str(secret),
        str(tmp_path / "outside" / "absent.xml"),
        str(allowed / ".." / "outside" / "secret.xml"),
        str(allowed / "escape.xml"),
        "../outside/secret.xml",
    ]:
        with pytest.raises(CommandError) as info:
            ses.set_robot(ref)
        assert "top secret" not in str(info.value)
        assert (
            "outside the allowed" in str(info.value)
            or "must end in .xml" in str(info.value)
            or "not found" in str(info.value)
        )
    # the same answer whether or not the outside file exists: no existence oracle
    msgs = []
    for ref in (str(secret), str(tmp_path / "outside" / "absent.xml")):
        with pytest.raises(CommandError) as info:
            ses.set_robot(ref)
        msgs.append(str(info.value).replace("secret", "X").replace("absent", "X"))
    assert msgs[0] == msgs[1]
    ses.set_robot(str(allowed / "arm.xml"))
    assert ses.robot_name == "scara"
    ses.set_robot("arm.xml")  # relative: looked up in the allowed folders
    assert ses.robot_name == "scara"


def test_set_robot_refusals_name_no_server_path_beyond_the_folder_names(tmp_path, monkeypatch):
    """Issue 27, item 10: every refusal of an outside path listed the server's absolute robot folders."""
    monkeypatch.delenv("BOSUN_ROBOTS_DIR", raising=False)
    from app.models.registry import LIBRARY_DIR

    allowed = tmp_path / "site" / "my_robots"
    allowed.mkdir(parents=True)
    (allowed / "broken.xml").write_text("<robot>", encoding="utf-8")
    ses = Session(robot_name="comau_smart5_3dof", robots_dirs=(str(allowed),))
    for ref in ("/etc/passwd.xml", str(tmp_path / "elsewhere.xml"), str(allowed / "broken.xml"), "broken.xml"):
        with pytest.raises(CommandError) as info:
            ses.set_robot(ref)
        msg = str(info.value).replace(repr(ref), "")  # the client's own path may be quoted back to it
        assert str(tmp_path) not in msg and str(LIBRARY_DIR) not in msg, msg
        assert str(LIBRARY_DIR.parent) not in msg and "/site/" not in msg, msg
    with pytest.raises(CommandError, match=r"outside the allowed robot folders \(robots, my_robots\)"):
        ses.set_robot("/etc/passwd.xml")
    with pytest.raises(CommandError, match=r"^my_robots/broken\.xml:1: XML syntax error"):
        ses.set_robot("broken.xml")


@pytest.mark.parametrize("ref", ["arm\x00.xml", "/tmp/a\x00b.xml", "scara\x00", "../x\x00/y.xml", "\x00"])
def test_a_nul_in_a_set_robot_path_is_a_one_line_refusal(ref):
    """Issue 27, item 10: a NUL in a ``set_robot`` path answered "internal error" (ValueError: embedded null byte)."""
    ses = Session(robot_name="scara")
    with pytest.raises(CommandError, match="NUL") as info:
        ses.set_robot(ref)
    assert "\n" not in str(info.value) and "\x00" not in str(info.value)
    assert ses.robot_name == "scara"


def test_robot_files_are_size_checked_before_reading(tmp_path):
    big = tmp_path / "big.xml"
    with open(big, "wb") as fh:
        fh.truncate(2_000_000_000)  # sparse: reading it whole would take seconds and 2 GB
    ses = Session(robot_name="scara", robots_dirs=(str(tmp_path),))
    with pytest.raises(CommandError, match="at most 1000000"):
        ses.set_robot(str(big))


def test_a_client_can_send_its_own_robot_file_as_text():
    ses = Session(robot_name="comau_smart5_3dof")
    ses.set_robot("my/arm.xml", xml=(ROOT / "robots" / "scara.xml").read_text(encoding="utf-8"))
    assert ses.robot_name == "scara"
    with pytest.raises(CommandError, match=r"^arm\.xml:1: XML syntax error"):
        ses.set_robot("/home/me/my/arm.xml", xml="<robot>")
    assert ses.robot_name == "scara"


def test_mode_button_toggles():
    from app.teleop.profiles import parse_profile

    ses = Session()
    ses.set_profile(parse_profile("name='p'\nmode_button=1\n[axes.x]\nindex=0\n"))
    ses.feed(InputSample((0.0,), (False, True), "x"), 0.001)
    ses.tick(0.001, DT)
    assert ses.mode == "position"
    ses.feed(InputSample((0.0,), (False, True), "x"), 0.002)
    ses.tick(0.002, DT)
    assert ses.mode == "position"  # held: one toggle per press


def test_actuator_braking_never_passes_limits():
    act = JointActuators([-1.0], [1.0], [2.0], [4.0], tau=0.01, q0=[0.0])
    prev_v = 0.0
    for _ in range(2000):
        act.step([5.0], 0.002)  # reference beyond the limit
        assert act.q[0] <= 1.0 and abs(act.qdot[0]) <= 2.0 + 1e-12
        assert abs(act.qdot[0] - prev_v) <= 4.0 * 0.002 + 1e-9
        prev_v = act.qdot[0]
    assert act.q[0] == pytest.approx(1.0, abs=1e-3)


_axis = st.floats(min_value=-1.0, max_value=1.0, allow_nan=False)
_event = st.tuples(_axis, _axis, _axis, st.booleans(), st.integers(min_value=1, max_value=60))


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    robot=st.sampled_from(["comau_smart5_3dof", "offshore_crane", "knuckle_boom_crane", "scara", "kuka_youbot"]),
    mode=st.sampled_from(["position", "velocity"]),
    solver=st.sampled_from(["jacobian", "ga"]),
    events=st.lists(_event, min_size=1, max_size=8),
)
def test_property_random_input_never_breaks_joint_limits(robot, mode, solver, events):
    ses = Session(robot_name=robot, solver_name=solver, mode=mode)
    ses.set_profile(default_profile())
    act = ses.actuators
    t, prev_v = 0.0, act.qdot.copy()
    for x, y, z, en, n in events:
        for _ in range(n):
            t += DT
            ses.feed(InputSample((x, y, z), (en,), "stick"), t)
            ses.tick(t, DT, solve_budget=0.002)
            q, v = act.q, act.qdot
            assert np.all(np.isfinite(q)) and np.all(q >= act.lower - 1e-12) and np.all(q <= act.upper + 1e-12)
            assert np.all(np.abs(v) <= act.speed * (1 + 1e-9))
            assert np.all(np.abs(v - prev_v) <= act.accel * DT * (1 + 1e-6) + 1e-9)
            prev_v = v.copy()


def test_braking_onto_a_position_limit_stays_within_the_acceleration_limit():
    """Issue 13, item 10: the continuous braking formula needed up to 12.5 % more than the accel limit
    (13 ticks in 1,050,000); the exact discrete bound (as the platform filter's) needs none."""
    rng = np.random.default_rng(5)
    worst = 0.0
    n = 200  # joints of one actuator set, each its own speed, acceleration and reference pattern
    for dt in (0.002, 0.005, 0.01, 0.02):
        speed, acc = rng.uniform(0.2, 3.0, n), rng.uniform(0.5, 20.0, n)
        act = JointActuators(-np.ones(n), np.ones(n), speed, acc, tau=0.05, q0=rng.uniform(-1, 1, n))
        for k in range(1500):
            if k % 150 == 0:
                ref = np.where(rng.random(n) < 0.7, rng.choice([-2.0, 2.0], n), rng.uniform(-1, 1, n))
            act.step(ref, dt)
            worst = max(worst, float(np.max(np.abs(act.qddot) / acc)))
            assert np.all(np.abs(act.q) <= 1.0) and np.all(np.abs(act.qdot) <= speed * (1 + 1e-12))
    assert worst <= 1 + 1e-5  # rounding only (1 + 6.4e-7 measured over 1,050,000 steps; 1.125 before)


def test_the_ga_task_is_set_through_the_protocol_and_disarms():
    """Issue 32, item 4 (H111): ``set_ga_task`` rebuilds a GA solver with the operator's weights and tool axis,
    reports them in the snapshot, and disarms the input (the next answer may lie elsewhere); the same task again
    changes nothing; a bad task is one line and leaves the task in force; other solvers keep it for later."""
    ses = Session(robot_name="comau_smart5_6dof", solver_name="ga-restart", mode="position")
    snap = ses.snapshot()
    assert snap.ga_weights == [1.0, 1.0, 1.0] and snap.ga_axis is None and snap.ga_axis_weight == 0.0
    arm(ses)
    ses.set_ga_task([1.0, 1.0, 4.0], [0.0, 0.0, -2.0])
    snap = ses.snapshot()
    assert not snap.flags.armed  # disarmed
    assert snap.ga_weights == [1.0, 1.0, 4.0] and snap.ga_axis == [0.0, 0.0, -1.0] and snap.ga_axis_weight == 1.0
    assert ses.solver.task.weights == (1.0, 1.0, 4.0) and ses.solver.name == "ga-restart"
    t = arm(ses, 1.0)
    assert ses.snapshot().flags.armed
    ses.set_ga_task([1.0, 1.0, 4.0], [0.0, 0.0, -1.0], 1.0)  # the same task: nothing happens
    assert ses.snapshot().flags.armed
    for bad, message in (([0.0, 0.0, 0.0], "not all 0"), ([1.0, 1.0, 101.0], r"in \[0, 100\]")):
        with pytest.raises(CommandError, match=message) as info:
            ses.set_ga_task(bad)
        assert "\n" not in str(info.value)
    with pytest.raises(CommandError, match="needs the axis"):
        ses.set_ga_task([1.0, 1.0, 1.0], None, 2.0)
    assert ses.solver.task.weights == (1.0, 1.0, 4.0) and ses.snapshot().flags.armed
    run(ses, 0.1, sample(), t0=t)
    ses.set_solver("jacobian")
    ses.set_ga_task([2.0, 1.0, 1.0])  # kept for the GA; the Jacobian solver is not rebuilt
    assert ses.solver.name == "jacobian" and ses.snapshot().ga_weights == [2.0, 1.0, 1.0]
    ses.set_solver("ga")
    assert ses.solver.task.weights == (2.0, 1.0, 1.0)
