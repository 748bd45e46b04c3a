"""Issue 30, item 4: the lab's REMOTE under VVMC.  The stick moves the work point in EM1500's frame while VVMC
holds the tool on it relative to EM1500, and the winch's stick lowers the load relative to the EM1500 deck."""

import numpy as np
import pytest

from app.models.lab import load_lab
from app.scenarios.vvmc import VvmcScenario, _sources
from app.scenes.lab import R_B2_DECK, WORK_REACH_MARGIN, WORK_SHIFT_MAX, MotionLab


def _lab_in_waves(hs: float = 2.0, seed: int = 4) -> MotionLab:
    sc = VvmcScenario(hs=hs, seed=seed, ramp=2.0)
    lab = MotionLab(load_lab(sc.lab), at_work=True, comau_profile=sc.comau_profile)
    _sources(sc, lab)
    lab.set_vvmc(True)
    return lab


def _run(lab: MotionLab, seconds: float, tool=(0.0, 0.0, 0.0), winch: float = 0.0, dt: float = 0.005):
    """Steps with the stick held as the engine's plant.drive sets it (under VVMC: {b2} and the winch speed)."""
    errors, heights = [], []
    for _ in range(round(seconds / dt)):
        lab.tool_velocity_cmd = np.array(tool, dtype=float)
        lab.winch.speed_command = float(winch)
        s = lab.step(dt)
        errors.append(s.e_t_b2.copy())
        heights.append(s.payload_height_error)
    return np.array(errors), np.array(heights)


def test_a_push_out_of_reach_stops_the_shift_where_the_comau_still_reaches_it():
    """WORK_SHIFT_MAX and WORK_REACH_MARGIN are assumed, not the lab's: held against each direction, the shift
    stops (work_shift_limited) at a point the Comau reaches with the margin around it, platforms at neutral."""
    for axis in range(3):
        for sign in (-1.0, 1.0):
            lab = _lab_in_waves(hs=0.5)
            stick = np.zeros(3)
            stick[axis] = 0.5 * sign
            _run(lab, 6.0, tool=stick)
            assert lab.work_shift_limited, (axis, sign, lab.work_shift)
            assert lab._reachable(lab.work_shift) and np.all(np.abs(lab.work_shift) <= WORK_SHIFT_MAX)
            moved = R_B2_DECK @ lab.work_shift  # in the operator's deck frame: along the stick, nowhere else
            assert moved[axis] * sign > 0.05 and np.allclose(np.delete(moved, axis), 0.0), moved
    assert WORK_REACH_MARGIN > 0


def test_under_vvmc_the_stick_moves_the_work_point_on_em1500_and_compensation_holds():
    """Hs 2 m (scaled into the platforms' boxes, as sim vvmc does): 0.2 m/s along the deck's x for 2 s moves the
    work point 0.4 m on EM1500, and the tool follows it relative to EM1500 within the compensation's own error."""
    still = _lab_in_waves()
    e_still, _ = _run(still, 8.0)
    lab = _lab_in_waves()
    _run(lab, 3.0)  # the ramp: the same sea as `still`
    e_move, _ = _run(lab, 2.0, tool=(0.2, 0.0, 0.0))
    e_hold, _ = _run(lab, 2.0)
    np.testing.assert_allclose(lab.work_shift, [0.4, 0.0, 0.0], atol=1e-9)
    assert not lab.work_shift_limited
    assert np.all(lab.work_shift_rate == 0.0)
    rms_still = float(np.sqrt(np.mean(np.sum(e_still[600:] ** 2, axis=1))))
    rms_move = float(np.sqrt(np.mean(np.sum(e_move[100:] ** 2, axis=1))))  # after the first 0.5 s (the start)
    rms_hold = float(np.sqrt(np.mean(np.sum(e_hold[100:] ** 2, axis=1))))
    assert rms_still < 0.01, rms_still  # VVMC's own error in this sea
    assert rms_move < 3 * rms_still + 0.005, (rms_move, rms_still)  # moving on the deck: the tool stays on the point
    assert rms_hold < 3 * rms_still + 0.002, (rms_hold, rms_still)


def test_a_new_vvmc_starts_on_the_work_point():
    lab = _lab_in_waves(hs=0.5)
    _run(lab, 2.0, tool=(0.0, -0.2, 0.1))
    assert np.any(lab.work_shift != 0.0)
    lab.set_vvmc(False)
    lab.set_vvmc(True)
    assert np.all(lab.work_shift == 0.0) and not lab.work_shift_limited


def test_a_braked_or_stopped_lab_does_not_shift_the_work_point():
    lab = _lab_in_waves(hs=0.5)
    lab.estop()
    _run(lab, 1.0, tool=(0.3, 0.3, 0.0))
    assert np.all(lab.work_shift == 0.0)


@pytest.mark.parametrize("speed", [0.05, -0.05])
def test_the_winch_stick_under_vvmc_moves_the_load_relative_to_the_deck(speed):
    """Winch REMOTE under VVMC: 0.05 m/s paid out for 4 s lowers the load 0.2 m relative to EM1500, along the
    deck's normal, down in the world (hauled in: raises it), while the heave compensation keeps it on that
    moving target."""
    lab = _lab_in_waves()
    _run(lab, 3.0)
    target0 = lab.payload_target_b2.copy()
    R2 = lab.platform_pose(1)[:3, :3]
    _, h = _run(lab, 4.0, winch=speed)
    moved_g = R2 @ (lab.payload_target_b2 - target0)  # in the world, at about the same deck attitude
    assert moved_g[2] == pytest.approx(-speed * 4.0, abs=0.01), moved_g
    np.testing.assert_allclose(lab.payload_target_b2 - target0, [0.0, 0.0, speed * 4.0], atol=1e-9)
    assert float(np.sqrt(np.mean(h[200:] ** 2))) < 0.02  # the height error to the moving target (small swing)


def test_the_compiled_and_reference_lab_agree_while_the_operator_shifts_the_work_point():
    """The operator's shift and the winch's lowering take the same path in the compiled step and the reference."""
    labs = [_lab_in_waves(hs=1.0) for _ in range(2)]
    labs[1].use_kernels = False
    outs = [_run(lab, 1.5, tool=(0.1, -0.05, 0.02), winch=0.03) for lab in labs]
    np.testing.assert_allclose(outs[0][0], outs[1][0], atol=1e-9)
    np.testing.assert_allclose(outs[0][1], outs[1][1], atol=1e-9)
    np.testing.assert_allclose(labs[0].joints.x, labs[1].joints.x, atol=1e-9)


def test_the_lab_engine_drives_the_work_point_under_vvmc_by_the_sticks_rules():
    """Through the engine's input pipeline: switching VVMC disarms; armed (centred, enable held), the stick's x
    moves the work point on EM1500 and its w lowers the load relative to the deck; the stick gone stale, both
    hold (the compensation goes on)."""
    from app.engine.lab_session import LabSession
    from app.scenes.lab import REMOTE_TOOL_SPEED
    from tests.test_safety_engine import lab_sample, run_lab

    ses = LabSession()
    ses.input.axes = 4
    t = run_lab(ses, 0.1, lab_sample(enable=False))
    t = run_lab(ses, 0.1, lab_sample(enable=True), t0=t)
    ses.lab_vvmc(True)
    t = run_lab(ses, 0.5, lab_sample(x=1.0, w=1.0), t0=t)  # deflected across the switch: disarmed, nothing moves
    assert not ses.snapshot().flags.armed and np.all(ses.lab.work_shift == 0.0)
    t = run_lab(ses, 0.1, lab_sample(enable=False), t0=t)
    t = run_lab(ses, 0.1, lab_sample(enable=True), t0=t)  # centred with enable: armed
    target0 = ses.lab.payload_target_b2.copy()
    t = run_lab(ses, 1.0, lab_sample(x=1.0, w=0.5), t0=t)
    shift = R_B2_DECK @ ses.lab.work_shift  # in the operator's deck frame
    assert shift[0] == pytest.approx(REMOTE_TOOL_SPEED, rel=0.1) and abs(shift[1]) < 1e-12 and abs(shift[2]) < 1e-12
    assert ses.lab.payload_target_b2[2] - target0[2] > 0.02  # lowered (down is +z in {b2})
    # the device goes silent: stale, and both hold
    t = run_lab(ses, 0.5, t0=t)
    held, target1 = ses.lab.work_shift.copy(), ses.lab.payload_target_b2.copy()
    t = run_lab(ses, 1.0, t0=t)
    np.testing.assert_array_equal(ses.lab.work_shift, held)
    np.testing.assert_array_equal(ses.lab.payload_target_b2, target1)
    assert ses.snapshot().flags.stale_input
    assert ses.snapshot().scene.work_point != [] and ses.snapshot().comau.mode == "motion_comp"
