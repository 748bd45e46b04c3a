"""Issue 32, item 5: direction-aware scaling at the loop rate (app/control/guard.py, app/control/guard_kernels.py,
Session._guarded and Session._supervise).  `bosun bench guard` runs the acceptance's 1 000 streams a robot."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from app.bench.guard import DIRECTION_STEP, run_stream, summarise
from app.control import guard_kernels as gk
from app.control.guard import GuardSettings, HazardGuard
from app.engine.session import Session
from app.errors import RobotXmlError
from app.models.registry import load_robot, load_robot_text
from app.teleop.devices import InputSample

ROBOTS = ["comau_smart5_3dof", "comau_smart5_6dof", "franka_panda", "kuka_youbot", "scara", "ur5"]


def test_segment_distance_is_the_least_distance_of_their_points():
    rng = np.random.default_rng(5)
    s = np.linspace(0.0, 1.0, 401)
    for k in range(200):
        p1, q1, p2, q2 = rng.normal(size=(4, 3))
        if k % 5 == 0:
            q2 = p2 + 0.3 * (q1 - p1)  # parallel
        if k % 7 == 0:
            q1 = p1.copy()  # a point
        a = p1 + s[:, None] * (q1 - p1)
        b = p2 + s[:, None] * (q2 - p2)
        brute = np.min(np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1))
        d = gk._segment_distance(p1, q1, p2, q2)
        assert d <= brute + 1e-12
        assert brute - d < 5e-3 * max(1.0, np.linalg.norm(q1 - p1) + np.linalg.norm(q2 - p2))


@pytest.mark.parametrize("name", ROBOTS)
def test_the_sigma_ratio_is_the_speed_scaled_jacobians(name):
    robot = load_robot(name)
    guard = HazardGuard.for_robot(robot)
    rng = np.random.default_rng(1)
    for q in rng.uniform(robot.lower, robot.upper, size=(50, robot.n_joints)):
        sv = np.linalg.svd(robot.jacobian(q)[:3] * robot.speed, compute_uv=False)
        assert guard.values(q)[0] == pytest.approx(sv[2] / sv[0], abs=1e-12)


def _floor_pose(guard):
    """A pose with a link near the floor and no other hazard in its zone, found by a seeded search."""
    robot = guard.robot
    rng = np.random.default_rng(3)
    for q in rng.uniform(robot.lower, robot.upper, size=(20000, robot.n_joints)):
        v = guard.values(q)
        floor = v[1 + len(guard.pairs) :]
        zone = np.concatenate(([guard.settings.sigma_zone], np.full(v.size - 1, guard.settings.clear_zone)))
        lim = np.minimum(q - robot.lower, robot.upper - q) < guard.settings.limit_zone * (robot.upper - robot.lower)
        if np.all(v[1:] > 0.02) and floor.min() < 0.05 and np.sum(v < zone) == 1 and not lim.any():
            return q
    raise AssertionError("no pose near the floor found")


def _tool_metric(robot, q):
    """W = JᵀJ + λI, λ = 10⁻³ tr(JᵀJ): the metric the guard corrects a step in (J: the tool point's, 3 × n)."""
    J = robot.jacobian(q)[:3]
    W = J.T @ J
    return W + (1e-3 * np.trace(W) + 1e-12) * np.eye(len(q))


def _one_hazard_step(robot, q, dq, g, rate):
    """What the guard makes of ``dq`` for one hazard of gradient g whose rate must be ``rate``: the least change in
    the tool's metric, dq + c W⁻¹g, then the whole step scaled if a joint would need longer at its speed limit."""
    h = np.linalg.solve(_tool_metric(robot, q), g)
    out = dq + (rate - g @ dq) / (g @ h) * h
    t0, t1 = np.max(np.abs(dq) / robot.speed), np.max(np.abs(out) / robot.speed)
    return out * (t0 / t1 if t1 > t0 else 1.0), t1 > t0


def test_a_step_that_opens_every_hazard_is_not_touched_and_one_that_approaches_loses_only_that_component():
    """Approaching the one hazard in its zone, the step loses only what the damper's bound asks of its rate, taken
    where it changes the tool's motion least: the removed part is W⁻¹g (W the tool's metric), not g itself."""
    robot = load_robot("comau_smart5_6dof")
    guard = HazardGuard.for_robot(robot)
    q = _floor_pose(guard)
    v0 = guard.values(q)
    n = robot.n_joints
    h = 1e-6
    grads = np.array([(guard.values(q + h * e) - guard.values(q - h * e)) / (2 * h) for e in np.eye(n)]).T
    zone = np.concatenate(([guard.settings.sigma_zone], np.full(v0.size - 1, guard.settings.clear_zone)))
    active = np.flatnonzero(v0 < zone)
    assert active.size == 1
    rng = np.random.default_rng(0)
    opened = approached = retimed = 0
    for _ in range(400):
        dq = rng.normal(size=n) * 2e-3
        rates = grads[active] @ dq
        lim = np.minimum(q - robot.lower, robot.upper - q) < guard.settings.limit_zone * (robot.upper - robot.lower)
        if lim.any():
            continue
        out, rep = guard.step(q, dq)
        if np.all(rates > 1e-9):  # opens every hazard in its zone: untouched, bit for bit
            assert np.array_equal(out, dq) and not rep.slowed and rep.scale == 1.0
            opened += 1
        elif active.size == 1 and rates[0] < -1e-9:  # approaches the one hazard: only its component goes
            g = grads[active[0]]
            assert g @ out >= g @ dq - 1e-12  # slower approach, never a faster one
            st = guard.settings  # … to exactly the damper's rate: −min(s |r⁰|, ½ (d − stop)), s the zone's share left
            d = v0[active[0]]
            share = (d - st.clear_stop) / (st.clear_zone - st.clear_stop)
            bound = -min(share * -rates[0], 0.5 * (d - st.clear_stop))
            want, timed = _one_hazard_step(robot, q, dq, g, bound)
            np.testing.assert_allclose(out, want, rtol=1e-4, atol=1e-4 * np.linalg.norm(dq))
            if not timed:
                assert g @ out == pytest.approx(bound, rel=1e-4)
            retimed += timed
            assert rep.slowed and rep.kind == "collision" and "floor" in rep.name
            approached += 1
    assert opened > 20 and approached > 20 and retimed < approached
    print(f"{opened} opening, {approached} approaching ({retimed} retimed)")


def test_inside_the_stop_a_command_carries_the_clearance_back_out_and_a_centred_stick_holds():
    """A braking overshoot can leave a capsule inside the scaling's stop (between it and the safe-braking rule's
    clearance). There the damper's bound turns positive (Kanoun et al. eq. 10 with d < d_s): a command along the
    floor gains a lift of min(½(stop − d), ⅕ |g||dq|) in the clearance's rate, taken where it changes the tool's
    motion least, not reported as slowed; a centred stick (dq = 0) still holds (the Panda's stuck tool of
    `bosun bench guard`)."""
    robot = load_robot("comau_smart5_6dof")
    guard = HazardGuard.for_robot(robot)
    q = _floor_pose(guard)
    n, h = robot.n_joints, 1e-7
    k = 1 + len(guard.pairs) + int(np.argmin(guard.values(q)[1 + len(guard.pairs) :]))  # the floor's row
    for _ in range(20):  # Newton along the floor's gradient to a clearance of 3 mm (inside the 5 mm stop)
        g = np.array([(guard.values(q + h * e)[k] - guard.values(q - h * e)[k]) / (2 * h) for e in np.eye(n)])
        q = q - (guard.values(q)[k] - 0.003) * g / (g @ g)
    d = guard.values(q)[k]
    assert abs(d - 0.003) < 1e-9
    g = np.array([(guard.values(q + h * e)[k] - guard.values(q - h * e)[k]) / (2 * h) for e in np.eye(n)])
    rng = np.random.default_rng(2)
    for scale in (1e-4, 1e-3, 1e-2):
        dq = rng.normal(size=n)
        dq = scale * (dq - (dq @ g) / (g @ g) * g) / np.linalg.norm(dq)  # along the floor
        dq += 1e-6 * scale * g / np.linalg.norm(g)  # and a hair up (opening, beyond the gradients' rounding)
        out, rep = guard.step(q, dq)
        push = min(0.5 * (guard.settings.clear_stop - d), 0.2 * np.linalg.norm(g) * np.linalg.norm(dq))
        want, timed = _one_hazard_step(robot, q, dq, g, push)  # lifted by the recovery's rate, in the tool's metric
        np.testing.assert_allclose(out, want, rtol=1e-5, atol=1e-9 * np.linalg.norm(dq))
        assert g @ out > 0.0 and (timed or g @ out == pytest.approx(push, rel=1e-5))
        assert not rep.slowed
    out, rep = guard.step(q, np.zeros(n))
    assert not out.any() and not rep.slowed  # a centred stick: nothing moves
    out, _ = guard.step(q, -1e-3 * g / np.linalg.norm(g))  # straight down: the approach goes, the lift comes
    assert g @ out > 0.0


def test_a_tool_caught_on_the_floor_slides_out_at_the_sticks_speed():
    """Two of the Panda's streams in `bosun bench guard` where a braking overshoot left the tool at the safe-braking
    rule's 2.5 mm and the stick, along the floor and a hair up, moved it at 8–13 % of its speed for up to 0.8 s
    (190 and 81 slow opening ticks): the reference's lead still pointed at the floor. Now a few ticks as the tool
    arrives, each one where the arm, with the command as asked, would have gone on closing on the floor."""
    for seed, before in ((349, 190), (427, 81)):
        run = run_stream("franka_panda", seed, rate=250.0)
        assert run.opening > 400 and run.opening_slow <= 10 < before, run
        assert run.opening_slow_closing == run.opening_slow, run
        assert run.penetration == 0.0 and run.limit_excess <= 1e-12, run


def test_at_the_stop_an_approach_is_taken_out_and_a_retreat_is_kept():
    robot = load_robot("scara")
    guard = HazardGuard.for_robot(robot, GuardSettings())
    q = 0.5 * (robot.lower + robot.upper)
    q[2] = robot.lower[2]  # the prismatic joint at its lower limit
    dq = np.zeros(robot.n_joints)
    dq[2] = -1e-3  # further down: into the limit
    out, rep = guard.step(q, dq)
    assert out[2] == pytest.approx(0.0, abs=1e-12)
    assert rep.kind == "joint limit" and rep.name.endswith("lower limit") and rep.slowed
    out, rep = guard.step(q, -dq)
    assert np.array_equal(out, -dq) and not rep.slowed


def test_capsules_come_from_the_robot_file_and_a_bad_radius_is_one_line():
    from app.models.registry import robots_dir

    xml = (robots_dir() / "scara.xml").read_text(encoding="utf-8")
    first = xml.index("</link>")
    with_radius = xml[:first] + '<collision radius="0.07"/>' + xml[first:]
    guard = HazardGuard.for_robot(load_robot_text(with_radius, "scara-capsules.xml"))
    default = HazardGuard.for_robot(load_robot("scara"))
    link1 = [k for k, label in enumerate(guard.labels) if label == "link 1"]
    assert link1 and all(guard.radii[k] == 0.07 for k in link1)
    assert all(default.radii[k] != 0.07 for k in link1)
    bad = xml[:first] + '<collision radius="-1"/>' + xml[first:]
    with pytest.raises(RobotXmlError) as err:
        load_robot_text(bad, "bad.xml")
    line = str(err.value)
    assert "\n" not in line and "bad.xml:" in line and "radius" in line


def test_pairs_touching_at_mid_range_are_listed_not_checked():
    guard = HazardGuard.for_robot(load_robot("ur5"))
    assert any("floor" in why and "not checked" in why for why in guard.ignored)
    q = 0.5 * (guard.robot.lower + guard.robot.upper)
    assert guard.min_clearance(q) > guard.settings.clear_stop  # what is checked starts clear


def _drive(ses, stick, seconds, t, dt=0.004):
    for _ in range(round(seconds / dt)):
        t += dt
        ses.feed(InputSample(tuple(stick), (True,), "test"), t)
        ses.tick(t, dt)
    return t


def test_the_stick_drives_the_panda_down_to_the_floor_it_stops_clear_names_it_and_lets_the_arm_out():
    ses = Session(robot_name="franka_panda", solver_name="jacobian", mode="velocity")
    guard = ses.guard
    t = 0.0
    for en in (False, True):
        t += 0.004
        ses.feed(InputSample((0.0, 0.0, 0.0), (en,), "test"), t)
        ses.tick(t, 0.004)
    t = _drive(ses, (-1.0, 0.0, -1.0), 6.0, t)  # back and down, full stick, for 6 s
    least = guard.min_clearance(ses.actuators.q)
    assert 0.0 <= least < guard.settings.clear_zone, least  # reached the zone, never through
    snap = ses.snapshot()
    assert snap.hazard.kind == "collision" and snap.hazard.name == "tool ↔ floor", snap.hazard
    assert any(a.key == "hazard_slowed" and a.active and "clearance" in a.text for a in snap.alarms), snap.alarms
    p0 = ses.robot.position(ses.actuators.q)
    floor = guard.values(ses.actuators.q)[1 + len(guard.pairs) :]
    t = _drive(ses, (0.0, 0.0, 1.0), 0.5, t)  # up again: away from the floor, at the stick's speed
    rise = ses.robot.position(ses.actuators.q)[2] - p0[2]
    assert rise > 0.5 * 0.5 * ses.scaling.k_v[2], rise  # half a second at k_v, less the servo's start
    # the floor falls away; the tool, come down beside the base's column (link 1), rises along it, clear of it
    assert guard.values(ses.actuators.q)[1 + len(guard.pairs) :].min() > floor.min() + 0.5 * rise
    assert guard.min_clearance(ses.actuators.q) > guard.settings.clear_stop


@pytest.mark.parametrize("name", ROBOTS)
def test_random_stick_streams_never_penetrate_never_pass_a_limit_and_never_slow_an_opening_command(name):
    """The acceptance in miniature (two streams a robot; `bosun bench guard` runs 1 000)."""
    for seed in (0, 1):
        run = run_stream(name, seed, rate=250.0)
        assert run.penetration <= 1e-3, run
        assert run.limit_excess <= 1e-12, run
        assert run.min_opening_speed >= 0.9, run
        assert math.isfinite(run.least_clearance)


def test_the_direction_step_is_small_against_every_zone():
    s = GuardSettings()
    assert 1e-3 * min(s.clear_zone, s.sigma_zone, s.limit_zone) > DIRECTION_STEP


def test_scale_in_box_slows_only_the_outward_part_near_a_face():
    from app.control.guard import scale_in_box

    limit = np.array([1.0, 1.0, 1.0])
    step = np.array([0.01, -0.01, 0.01])
    out, axis, gap = scale_in_box(step, [0.9, 0.9, 0.0], limit)  # x and y in the zone (outer quarter)
    assert out[0] == pytest.approx(0.01 * 0.1 / 0.25)  # outward: slowed to the share of the zone left
    assert out[1] == step[1] and out[2] == step[2]  # y inward, z far from its faces: as asked
    assert axis == 0 and gap == pytest.approx(0.1)
    out, axis, _ = scale_in_box(step, [1.0, 0.0, 0.0], limit)
    assert out[0] == 0.0 and axis == 0  # at the face: nothing outward
    out, _, _ = scale_in_box(-step, [1.0, 0.0, 0.0], limit)
    np.testing.assert_array_equal(out, -step)  # back in: never slowed


def test_the_crane_heads_target_slows_into_its_range_and_comes_back_at_full_speed():
    """The crane-head scene's workspace (the head's reach alone in tac mode): the stick's outward part slows
    through the range's outer quarter; the hazard is named with its distance; the way back is at the stick's
    speed (0.5 m/s)."""
    from app.engine.tac_session import TCP_SPEED
    from tests.test_crane_stick import DT, arm, run, session, stick

    ses = session("tac", hs=0.5)
    t = arm(ses, run(ses, 0.5))
    limit = ses.target_range["tac"][1]
    t = run(ses, 5.0, stick(y=1.0), t)
    off = np.array(ses.sim.p_d_n) - ses.sim.p_d_n0
    assert 0.0 < limit - off[1] < 0.25 * limit
    hz = ses.snapshot().hazard
    assert hz.kind == "workspace" and hz.name == "tac range y" and hz.slowed and "m to its edge" in hz.text
    before = np.array(ses.sim.p_d_n)
    t = run(ses, 0.4, stick(y=-1.0), t)
    back = np.array(ses.sim.p_d_n) - before
    assert back[1] == pytest.approx(-TCP_SPEED * 0.4, abs=TCP_SPEED * DT + 1e-9)


@pytest.mark.parametrize("name", ROBOTS)
def test_every_gradient_in_closed_form_equals_central_differences(name):
    """The σ ratio's gradient (the derivative of a simple singular value through the chain's second derivatives)
    and each clearance's (its closest points' rates along the line between them) against central differences of
    the values, at seeded random poses with every hazard counted (zones wide open)."""
    robot = load_robot(name)
    guard = HazardGuard.for_robot(robot)
    n = robot.n_joints
    settings = guard._settings.copy()
    settings[0] = 0.0  # no joint-limit rows
    settings[2], settings[4] = 2.0, 1e9  # every σ and clearance in its zone
    m = 1 + len(guard.pairs) + len(guard.plane_caps)
    rng = np.random.default_rng(11)
    h = 1e-6
    checked = 0
    for q in rng.uniform(robot.lower, robot.upper, size=(40, n)):
        G = np.zeros((n + m, n))
        rows = (np.zeros(n + m), np.zeros(n + m), np.zeros(n + m), np.zeros(n + m, np.int64), np.zeros(n + m, np.int64))
        na = gk._active(robot.kernel_record, guard._chain, guard._model, guard._limits, q, settings, G, rows)
        assert na == m
        v0 = guard.values(q)
        fd = np.array([(guard.values(q + h * e) - guard.values(q - h * e)) / (2 * h) for e in np.eye(n)]).T
        if v0[0] < 1e-6:
            continue  # at a singularity the ratio has a kink: no gradient to compare
        for r in range(na):
            k = 0 if rows[3][r] == gk.SINGULAR else 1 + rows[4][r] + (len(guard.pairs) if rows[3][r] == gk.PLANE else 0)
            # a kink where a clearance's closest points jump ends the comparison there; elsewhere they agree
            if np.linalg.norm(fd[k]) < 1e-9 and np.linalg.norm(G[r]) < 1e-9:
                continue
            assert np.allclose(G[r], fd[k], rtol=1e-4, atol=1e-6), (name, r, G[r], fd[k])
            checked += 1
    assert checked > 40


def test_the_labs_work_point_slows_into_its_range_and_comes_back_at_full_speed():
    """The Motion-Lab under VVMC: the stick's work-point shift on EM1500 slows through the outer quarter of its
    ±1 m range (direction-aware), the engine's snapshot names the edge and its distance; back in at full speed."""
    from app.engine.lab_session import LabSession
    from app.scenes.lab import R_B2_DECK, WORK_SHIFT_MAX
    from tests.test_lab_remote_vvmc import _lab_in_waves, _run

    lab = _lab_in_waves(hs=0.5)
    _run(lab, 0.5)
    deck_x = R_B2_DECK.T @ np.array([1.0, 0.0, 0.0])  # the operator's deck x in {b2}
    axis = int(np.argmax(np.abs(deck_x)))
    _run(lab, 6.0, tool=(0.25, 0.0, 0.0))  # 1.5 m asked: through the outer quarter (from 0.75 m) to the edge
    shift = float(abs(lab.work_shift[axis]))
    assert 0.95 < shift < WORK_SHIFT_MAX[axis]  # slowed, never past
    assert lab.work_shift_limited  # at its range: the flag the engine's alarm reads
    assert lab.work_hazard is not None and lab.work_hazard[0] == axis and lab.work_hazard[2]
    before = lab.work_shift.copy()
    _run(lab, 0.2, tool=(-0.25, 0.0, 0.0))
    assert abs(lab.work_shift[axis] - before[axis]) == pytest.approx(0.05, abs=1e-9)  # back: 0.25 m/s × 0.2 s
    ses = LabSession.__new__(LabSession)  # the engine's reading of the lab's hazard, on this lab
    ses.lab = lab
    _run(lab, 1.0, tool=(0.25, 0.0, 0.0))
    hz = ses._hazard()
    assert hz.kind == "workspace" and hz.name == f"work point range {'xyz'[axis]}" and hz.slowed
    assert "m to its edge" in hz.text


def test_random_sticks_on_the_crane_head_never_leave_its_range_and_never_slow_an_inward_command():
    """The crane-head scene under seeded random sticks (tac mode, the head's range alone; axes at full deflection
    or centred): the TCP target's offset
    never passes its range, and each tick's step keeps every inward (or along-edge) component of the stick's
    command whole; outward ones only shrink."""
    from app.engine.tac_session import STICK_TO_NED, TCP_SPEED
    from tests.test_crane_stick import DT, arm, run, session, stick

    ses = session("tac", hs=0.5)
    t = arm(ses, run(ses, 0.5))
    limit = ses.target_range["tac"]
    rng = np.random.default_rng(32)
    inward = outward = 0
    for _ in range(12):
        s = rng.integers(-1, 2, 3).astype(float)  # full deflections or centred: the profile's shaping keeps them
        for _ in range(int(rng.uniform(0.5, 3.0) / DT)):
            off0 = np.array(ses.sim.p_d_n) - ses.sim.p_d_n0
            t = run(ses, DT, stick(*s), t)
            off1 = np.array(ses.sim.p_d_n) - ses.sim.p_d_n0
            want = STICK_TO_NED @ (TCP_SPEED * s) * DT
            got = off1 - off0
            assert np.all(np.abs(off1) <= limit + 1e-12)
            for i in range(3):
                if want[i] * off0[i] <= 0.0:  # inward (or from the centre)
                    assert got[i] == pytest.approx(want[i], abs=1e-12)
                    inward += 1
                else:
                    assert 0.0 <= got[i] / want[i] <= 1.0 + 1e-12
                    outward += 1
    assert inward > 100 and outward > 100


def test_crane_head_streams_never_pass_the_range_and_keep_inward_steps_whole():
    """The crane-head scene's share of the acceptance (``bosun bench guard --scene crane``): the TCP's target never
    passes its mode's range, and a step with no outward part in the zone is kept whole."""
    from app.bench.crane_guard import run_stream as crane_stream

    runs = [crane_stream(seed) for seed in (0, 1, 2)]  # tac, cooperative, tac
    assert sum(r.opening for r in runs) > 100 and sum(r.slowed for r in runs) > 100
    for r in runs:
        assert r.excess <= 1e-12 and r.min_opening_speed >= 1.0 - 1e-9, r


def test_bench_guard_prints_the_opening_ticks_kept_under_90_percent(capsys):
    from app.cli import main

    assert main(["bench", "guard", "--streams", "1", "--robots", "franka_panda", "comau_smart5_6dof"]) == 0
    out = capsys.readouterr().out
    assert "under 90 %" in out and "closing as asked)" in out and "franka_panda" in out, out
    # H121's measure: a share where the guard slowed the stream, a dash where it never did
    assert "across" in out and re.search(r"comau_smart5_6dof .* \d+\.\d % ", out), out


def test_the_bench_measures_the_guarded_motion_across_the_command():
    """``bosun bench guard``'s *across* (H121): over the slowed ticks, the travel the solver's steps asked for and the
    guarded steps' motion across their directions; a stream that never reaches a hazard has neither."""
    run = run_stream("comau_smart5_6dof", 0, rate=250.0)
    assert run.slowed > 0 and run.slowed_travel > 0.0 and 0.0 <= run.slowed_across < run.slowed_travel, run
    row = summarise("comau_smart5_6dof", [run])
    assert row["slowed_travel_m"] == run.slowed_travel and row["slowed_across_m"] == run.slowed_across
    far = run_stream("offshore_crane", 0, rate=250.0)
    assert far.slowed == 0 and far.slowed_travel == 0.0 and far.slowed_across == 0.0


def test_bench_guard_in_the_lab_prints_the_slow_opening_steps_whose_drives_would_close(capsys):
    from app.cli import main

    assert main(["bench", "guard", "--scene", "lab", "--streams", "1"]) == 0
    out = capsys.readouterr().out
    assert "under 90 %" in out and "0 (0 closing as asked, 0 ahead, 0 carried, 0 unexplained)" in out, out
    row = out.strip().splitlines()[-2].split()  # stream 0 keeps every opening step, and is slowed: its across
    assert row[0] == "1" and re.fullmatch(r"\d+\.\d", row[row.index("unexplained)") + 2]), out


def test_a_joint_limit_is_named_with_its_distance_in_the_joints_unit():
    """Seen driving the Panda under Xvfb: the hazard line read "q5 lower limit: 0.015 to go" with no unit.
    A revolute joint's distance reads in degrees (as the joint plots), a prismatic one's in millimetres; the
    protocol's value stays SI."""
    crane = load_robot("knuckle_boom_crane")
    guard = HazardGuard.for_robot(crane)
    n = crane.n_joints
    jib = crane.joint_kinds.index("prismatic")
    rev = crane.joint_kinds.index("revolute")
    report = guard.report(np.array([gk.LIMIT, n + jib, 0.015, 0.5, 1.0, 0.5, 0.0, 0.0]))
    assert report.value == 0.015 and report.unit == "m"
    assert report.text() == f"{crane.joint_names[jib]} upper limit: 15 mm to go"
    report = guard.report(np.array([gk.LIMIT, rev, math.radians(0.9), 0.5, 1.0, 0.5, 0.0, 0.0]))
    assert report.unit == "rad" and report.text() == f"{crane.joint_names[rev]} lower limit: 0.9° to go"
    collision = guard.report(np.array([gk.PLANE, 0, 0.043, 0.5, 1.0, 0.5, 0.0, 0.0]))
    assert collision.unit == "" and collision.text().endswith("clearance 43 mm")


@pytest.mark.parametrize(("name", "share"), [("comau_smart5_6dof", 0.02), ("franka_panda", 0.02), ("ur5", 0.05)])
def test_pushed_straight_down_onto_the_floor_the_tool_stops_and_does_not_slide_away(name, share):
    """Safety H121: the guard took from a step only the part that closed on a hazard, but in the joints' metric, and
    what it left went elsewhere: pushed straight down onto the floor for 8 s, the Comau 6-DOF's tool slid 1.14 m
    sideways (33 % of the travel asked in the slowed ticks), the Panda's 0.29 m (36 %), the UR5's 0.12 m (9 %).
    Corrected in the tool's metric the tool stops over the floor: its motion across the command is under 2 % of
    that travel (measured 0.1 % and 0.9 %); the UR5's elbow, not its tool, meets the floor, and keeping the tool
    going down beside it costs a little across (measured 3.1 %: under 5 %)."""
    ses = Session(robot_name=name, solver_name="jacobian", mode="velocity")
    r, tick = ses.robot, ses.guard_tick
    asked = across = 0.0
    u = np.array([0.0, 0.0, -1.0])

    def spy(guard, q_ref, dq, act, dt):
        nonlocal asked, across
        new, rep, action = tick(guard, q_ref, dq, act, dt)
        if rep.slowed:
            p0 = r.position(q_ref)
            asked += float(np.linalg.norm(r.position(np.clip(q_ref + dq, r.lower, r.upper)) - p0))
            got = r.position(new) - p0
            across += float(np.linalg.norm(got - (got @ u) * u))
        return new, rep, action

    ses.guard_tick = spy
    t = 0.0
    for en in (False, True):
        t += 0.004
        ses.feed(InputSample((0.0, 0.0, 0.0), (en,), "test"), t)
        ses.tick(t, 0.004)
    _drive(ses, (0.0, 0.0, -1.0), 8.0, t)
    assert asked > 0.3, asked  # the floor slowed it for most of the way
    assert across < share * asked, (across, asked)
    assert ses.guard.min_clearance(ses.actuators.q) >= 0.0


def test_h124_the_hazard_line_names_what_is_near_when_nobody_drives():
    """H124: the teleop engine's hazard report was what the guard did to the last step, and empty whenever the arm
    held: with the Panda's tool driven 5 mm over the floor and the deadman released (or the stick centred, or an
    E-STOP), the *hazard* line read "none near".  Now, with no command, it names the hazard nearest its stop where
    the joints are, with its clearance, not slowing."""
    ses = Session(robot_name="franka_panda", solver_name="jacobian", mode="velocity")
    t, dt = 0.0, 0.002

    def run(stick, enable: bool, seconds: float) -> None:
        nonlocal t
        for _ in range(round(seconds / dt)):
            t += dt
            ses.feed(InputSample(stick, (enable,), "test"), t)
            ses.tick(t, dt)

    run((0.0, 0.0, 0.0), False, 0.05)
    run((0.0, 0.0, 0.0), True, 0.05)  # armed: enable pressed with the stick centred
    run((0.0, 0.0, -1.0), True, 8.0)  # straight down onto the floor
    assert ses.hazard.name == "tool ↔ floor" and ses.hazard.slowed
    for stick, enable, then in (
        ((0.0, 0.0, 0.0), True, "centred"),
        ((0.0, 0.0, 0.0), False, "released"),
        (None, False, "E-STOP"),
    ):
        if stick is None:
            ses.estop("test")
            stick = (0.0, 0.0, 0.0)
        run(stick, enable, 0.5)
        floor = ses.guard.values(ses.actuators.q)[-len(ses.guard.plane_caps) :].min()
        hz = ses.hazard
        assert (hz.kind, hz.name, hz.slowed) == ("collision", "tool ↔ floor", False), then
        assert 0.0 < hz.value < 0.02 and hz.value == pytest.approx(floor, abs=1e-12), then
        assert ses.snapshot().hazard.text == f"tool ↔ floor: clearance {hz.value * 1e3:.0f} mm", then
