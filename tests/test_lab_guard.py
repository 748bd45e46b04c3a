"""Issue 32, item 5 in the Motion-Lab: the Comau's guard against the platforms (app/control/lab.py ``ComauGuard``,
``COMAU_GUARD``; compiled ``app.control.lab_kernels.comau_guard`` inside ``lab_step``).  The lab's capsules: the
upper arm, forearm and extension arm; its obstacles: EM8000's deck under the robot, the robot's pedestal and column,
EM1500's deck.  On the robot file's (data sheet) limits the arm reaches all three; the lab's own program limits
keep it clear of them."""

import math

import numpy as np
import pytest

from app.bench.lab_guard import run_stream
from app.control import lab_kernels as ck
from app.control.lab import COMAU_GUARD, ComauGuard, guard_hazards_reference
from app.engine.lab_session import LabSession
from app.models.lab import load_lab
from app.models.lab_kernels import comau_tool
from app.scenes.lab import MotionLab
from app.teleop.devices import InputSample

DT = 0.005
DOWN = (-0.1, 0.0, -0.25)  # [m/s in {r}]: from the park pose, down and in, 10 s: the tool 0.43 m into EM8000's deck


def _lab(**kw) -> MotionLab:
    lab = MotionLab(load_lab("motionlab"), comau_profile="datasheet", **kw)
    lab.set_comau_mode("remote")
    return lab


def _clearances(lab: MotionLab, q) -> np.ndarray:
    return guard_hazards_reference(lab._comau, lab.guard.radii, lab.guard_world(), np.asarray(q, dtype=float))[1]


def test_the_arm_points_are_eq_3_and_its_jacobian_eq_5_at_the_tool():
    lab = _lab()
    rng = np.random.default_rng(5)
    P, J = np.zeros((4, 3)), np.zeros((4, 3, 3))
    for q in rng.uniform(lab.joints.lower, lab.joints.upper, size=(200, 3)):
        p, _, _, Jt = comau_tool(lab._comau, q, np.zeros(3), np.zeros(3))
        ck.arm_points(lab._comau, q, P, J)
        np.testing.assert_allclose(P[3], p, atol=1e-12)
        np.testing.assert_allclose(J[3], Jt, atol=1e-12)
        np.testing.assert_allclose(P[3], lab.comau.position(q), atol=1e-12)
        # the elbow is where the upper arm ends: a2 from the shoulder
        assert math.isclose(np.linalg.norm(P[1] - P[0]), lab.arm.a2, rel_tol=1e-12)


def test_the_clearances_gradients_are_their_derivatives_and_the_kernel_is_the_reference():
    lab = _lab()
    world = lab.guard_world()
    rng = np.random.default_rng(32)
    G, val = np.zeros((ck.ROWS, 3)), np.zeros(ck.ROWS)
    kind, cap = np.zeros(ck.ROWS, np.int64), np.zeros(ck.ROWS, np.int64)
    worst = 0.0
    for q in rng.uniform(lab.joints.lower, lab.joints.upper, size=(300, 3)):
        Gr, vr, kr, cr = guard_hazards_reference(lab._comau, lab.guard.radii, world, q)
        assert ck.guard_hazards(lab._comau, lab.guard.radii, world, q, G, val, kind, cap) == ck.ROWS == len(vr)
        np.testing.assert_allclose(val, vr, atol=1e-12)
        assert np.array_equal(kind, kr) and np.array_equal(cap, cr)
        # the nearest point on a segment comes from a golden-section search: its place agrees to its tolerance
        np.testing.assert_allclose(G, Gr, atol=1e-6)
        h = 1e-6
        for j in range(3):
            dq = np.zeros(3)
            dq[j] = h
            up = guard_hazards_reference(lab._comau, lab.guard.radii, world, q + dq)[1]
            down = guard_hazards_reference(lab._comau, lab.guard.radii, world, q - dq)[1]
            fd = (up - down) / (2 * h)
            smooth = np.abs(up - vr) + np.abs(vr - down) < 10 * h * (np.abs(Gr[:, j]) + 1.0)  # no kink in the step
            worst = max(worst, float(np.max(np.abs(fd - Gr[:, j])[smooth], initial=0.0)))
    assert worst < 1e-5


def test_the_guard_kernel_is_its_reference_and_an_opening_command_passes_bit_for_bit():
    lab = _lab()
    f = lab.joints
    world = lab.guard_world()
    params = (lab._comau, lab.guard.radii, f.limits(), np.array([lab.guard.zone, lab.guard.stop, lab.guard.braking]))
    rng = np.random.default_rng(7)
    slowed = passed = 0
    for _ in range(3000):
        q = rng.uniform(f.lower, f.upper)
        qd = rng.uniform(-1.0, 1.0, 3) * f.speed * rng.uniform(0.0, 0.5)
        rate = rng.uniform(-1.0, 1.0, 3)
        command = (np.bool_(False), q + rate * DT, rate, np.bool_(True), 1.0)
        _, (got, rep) = ck.comau_guard((), (command, q, qd, world), params, DT)
        _, (ref, rep_ref) = COMAU_GUARD.step((), (command, q, qd, world), params, DT, use_kernels=False)
        assert rep[4] == rep_ref[4] and rep[0] == rep_ref[0]
        np.testing.assert_allclose(got[2], ref[2], atol=1e-6)
        if rep[4]:
            slowed += 1
            assert np.array_equal(got[1], q) and got[3]  # a slowed command is a pure rate from where the arm is
        else:
            passed += 1
            for a, b in zip(got, command, strict=True):
                assert np.array_equal(a, b)  # as it came, bit for bit
    assert slowed > 100 and passed > 100  # both cases were met


def _drive(lab: MotionLab, v_cmd, seconds: float) -> tuple[float, list[str]]:
    """REMOTE at ``v_cmd`` [m/s in {r}]; the least clearance at the actual joints, and the hazards reported."""
    least, named = math.inf, []
    lab.tool_velocity_cmd = np.asarray(v_cmd, dtype=float)
    for _ in range(round(seconds / DT)):
        lab.step(DT)
        least = min(least, float(_clearances(lab, lab.joints.x).min()))
        if lab.guard_report[4]:
            named.append(ComauGuard.text(lab.guard_report))
    return least, named


@pytest.mark.parametrize("kernels", [True, False])
def test_driving_the_tool_into_em8000s_deck_stops_short_of_it(kernels):
    """Safety H115: on its data-sheet limits the Comau's tool went 0.43 m through EM8000's deck in REMOTE."""
    lab = _lab()
    lab.use_kernels = kernels
    least, named = _drive(lab, DOWN, 10.0)
    assert least >= lab.guard.stop - 1e-3, least
    assert named and all(n.startswith("extension arm ↔ EM8000 deck") for n in named[:5]), named[:5]
    # back up: never slowed
    lab.step(DT)
    q0 = lab.joints.x.copy()
    _, named_up = _drive(lab, (0.0, 0.0, 0.25), 1.0)
    assert not named_up and np.linalg.norm(lab.joints.x - q0) > 0.05


def test_without_the_guard_the_same_drive_goes_through_the_deck():
    """The regression's other half: the guard switched off (its zone moved inside the deck), the tool goes through."""
    lab = _lab()
    radii, deck1, ped, ped_r, deck_r, _ = lab._guard_p
    lab._guard_p = (radii, deck1, ped, ped_r, deck_r, np.array([-10.0, -11.0, 0.5]))
    least, _ = _drive(lab, DOWN, 10.0)
    assert least < -0.3


def test_the_lab_profile_keeps_the_arm_clear_and_the_guard_quiet():
    lab = MotionLab(load_lab("motionlab"))
    rng = np.random.default_rng(3)
    Q = rng.uniform(lab.joints.lower, lab.joints.upper, size=(2000, 3))
    assert min(float(_clearances(lab, q).min()) for q in Q) > lab.guard.zone


def test_random_streams_never_penetrate_and_never_slow_an_opening_command():
    # streams that went through in the benchmark's first runs: 19 and 29 (the extension arm's far end swinging onto
    # the pedestal at speed), 324 and 612 (an opening joint reaching its own limit while another closed the gap)
    runs = [run_stream(seed) for seed in (19, 29, 324, 612)]
    assert all(r.slowed > 0 for r in runs)
    for r in runs:
        assert r.penetration <= 1e-3 and r.limit_excess <= 1e-9, r
        assert r.min_opening_speed >= 0.9, r


@pytest.mark.slow
def test_the_lab_engine_names_the_hazard_and_raises_the_alarm():
    s = LabSession(comau_profile="datasheet")
    t = 0.0

    def run(seconds, axes=(0.0, 0.0, 0.0, 0.0), enable=False):
        nonlocal t
        for _ in range(round(seconds / 0.02)):
            t += 0.02
            s.feed(InputSample(tuple(axes), (enable, False), "test"), t)
            s.tick(t, 0.02)

    run(0.1)
    run(0.4, enable=True)  # armed on the press, centred
    seen = None
    for _ in range(60):
        run(0.5, axes=(0.0, 0.0, -1.0, 0.0), enable=True)  # the tool straight down in {r}, at full stick
        hz = s.snapshot().hazard
        if hz.slowed:
            seen = hz
            break
    assert seen is not None and seen.kind == "collision" and "EM8000 deck" in seen.text, seen
    assert seen.value is not None and 0.0 < seen.value < 0.5 and seen.share is not None and seen.share <= 1.0
    run(1.0, axes=(0.0, 0.0, -1.0, 0.0), enable=True)
    alarms = {a.key: a for a in s.snapshot().alarms if a.active}
    assert "hazard_slowed" in alarms and "EM8000 deck" in alarms["hazard_slowed"].text
    assert float(_clearances(s.lab, s.lab.joints.x).min()) >= s.lab.guard.stop - 1e-3


def test_the_profile_is_chosen_on_the_command_line_and_kept_for_a_replay():
    import argparse

    from app.cli.engine import _make_session
    from app.engine.replay import _scene
    from app.errors import BosunError

    args = argparse.Namespace(plant="lab", comau_limits="datasheet", plc=None, plc_host=None, plc_local_id=None)
    ses = _make_session(args)
    assert ses.lab.profile.name == "datasheet" and ses.replay_args()["comau_profile"] == "datasheet"
    assert _scene("lab", ses.replay_args(), 0).lab.profile.name == "datasheet"
    assert _scene("lab", {"plc": False}, 0).lab.profile.name == "lab"  # a recording from before: the default
    with pytest.raises(BosunError, match="add --plant lab"):
        _make_session(argparse.Namespace(plant="tac", comau_limits="datasheet"))
