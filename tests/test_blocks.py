"""The block shape (issue 29, item 1): named records, one pure step(x, u, p, dt) -> (x', y), the compiled
kernel and the NumPy reference two implementations of it, chosen in one place."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from app.models.block import Block
from app.sim import kernels as sim_kernels
from app.sim.actuators import JOINT_ACTUATORS, JointActuators


def _limits(n=3):
    return np.array([-1.0, -2.0, 0.1])[:n], np.array([1.0, 0.5, 2.0])[:n], np.array([0.8, 1.5, 0.3])[:n]


def test_the_actuator_block_kernel_and_reference_give_the_same_numbers():
    lower, upper, speed = _limits()
    accel = np.array([4.0, 10.0, 1.0])
    p = JOINT_ACTUATORS.record("params", lower=lower, upper=upper, speed=speed, accel=accel, tau=0.05)
    rng = np.random.default_rng(29)
    x_k = x_r = (np.array([0.0, -0.5, 1.0]), np.zeros(3), np.zeros(3))
    for k in range(400):
        u = (rng.uniform(-3.0, 3.0, 3) if k % 40 == 0 else x_k[0] + rng.normal(0.0, 0.2, 3),)
        x_k, y_k = JOINT_ACTUATORS.step(x_k, u, p, 0.002, use_kernels=True)
        x_r, y_r = JOINT_ACTUATORS.step(x_r, u, p, 0.002, use_kernels=False)
        for a, b in zip((*x_k, *y_k), (*x_r, *y_r), strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
        assert np.all((x_k[0] >= lower) & (x_k[0] <= upper))  # never past a limit
        assert np.all(np.abs(x_k[1]) <= speed * (1 + 1e-12))
    assert JOINT_ACTUATORS.named("outputs", y_k)["q"] is y_k[0]


def test_the_block_is_the_one_place_that_chooses_the_implementation():
    assert JOINT_ACTUATORS.implementation(use_kernels=False) is JOINT_ACTUATORS.reference
    assert JOINT_ACTUATORS.implementation(use_kernels=True) is sim_kernels.actuator_block
    ref_only = Block("r", (), (), (), (), reference=lambda x, u, p, dt: (x, ()))
    assert ref_only.implementation(use_kernels=True) is ref_only.reference
    # the shape: four arguments, whatever the block (issue 29: no compiled step with more than 8)
    assert list(inspect.signature(JOINT_ACTUATORS.reference).parameters) == ["x", "u", "p", "dt"]


def test_a_record_names_every_field_or_is_refused():
    with pytest.raises(ValueError, match="expected lower, upper, speed, accel, tau"):
        JOINT_ACTUATORS.record("params", lower=1, upper=2)


@pytest.mark.parametrize("use_kernels", [True, False])
def test_joint_actuators_step_through_the_block_as_before(use_kernels):
    """JointActuators is the block's holder: its steps are the block's, bit for bit."""
    lower, upper, speed = _limits()
    act = JointActuators(lower, upper, speed, [4.0, 10.0, 1.0], tau=0.05, q0=[0.0, -0.5, 1.0])
    act.use_kernels = use_kernels
    x = (act.q.copy(), act.qdot.copy(), act.qddot.copy())
    for k in range(50):
        q_ref = np.array([0.9, 0.4, 0.2]) if k < 30 else np.array([-0.9, -1.9, 1.9])
        act.step(q_ref, 0.002)
        x, _ = JOINT_ACTUATORS.step(x, (q_ref,), act.params, 0.002, use_kernels=use_kernels)
        np.testing.assert_array_equal(act.q, x[0])
        np.testing.assert_array_equal(act.qdot, x[1])


def test_the_load_block_kernel_and_reference_agree_and_the_plant_steps_through_it():
    """The second block: the suspended load of Motion-Lab eqs. (29)–(30), its reference the models' RK4
    (app.models.pendulum.swing_rk4, which the controllers predict with), its kernel the lab's."""
    from app.sim.motionlab import PENDULUM, Pendulum

    p = PENDULUM.record("params", damping=0.05, g=9.81)
    x_k = x_r = (0.2, -0.1, 0.0, 0.3)
    rng = np.random.default_rng(30)
    for _ in range(500):
        u = (rng.normal(0.0, 1.0, 3), 2.0 + rng.uniform(-0.5, 0.5), rng.uniform(-0.2, 0.2))
        x_k, _ = PENDULUM.step(x_k, u, p, 0.005, use_kernels=True)
        x_r, y_r = PENDULUM.step(x_r, u, p, 0.005, use_kernels=False)
        np.testing.assert_allclose(x_k, x_r, rtol=1e-11, atol=1e-12)
    assert y_r == x_r  # the angles and their rates (the winch guard reads the rates: LAB_DIAGRAM)
    for use_kernels in (True, False):
        load = Pendulum(damping=0.05, alpha=0.2, beta=-0.1, use_kernels=use_kernels)
        x = (0.2, -0.1, 0.0, 0.0)
        for k in range(100):
            a_t = np.array([0.5, -0.2, 0.1 * k / 100])
            load.step(0.005, a_t, 2.0, 0.01)
            x, _ = PENDULUM.step(x, (a_t, 2.0, 0.01), p, 0.005, use_kernels=use_kernels)
        assert (load.alpha, load.beta, load.alpha_dot, load.beta_dot) == x


# ------------------------------------------------------------------------------------- the Motion-Lab's blocks
def _lab_view(rng, lab):
    """A random (η1, η̇1, R1, Ṙ1, η2, η̇2, R2, Ṙ2) near the lab's neutral poses (eqs. 33, 47)."""
    from app.models.stewart import StewartPlatform

    out = []
    for _ in range(2):
        eta = np.r_[rng.normal(0.0, 0.05, 3) + [0.0, 0.0, -0.1], rng.normal(0.0, 0.05, 3)]
        eta_dot, eta_ddot = rng.normal(0.0, 0.1, 6), rng.normal(0.0, 0.3, 6)
        R, Rd, _ = StewartPlatform.rotation_rates(eta, eta_dot, eta_ddot)
        out += [eta, eta_dot, R, Rd]
    return tuple(np.ascontiguousarray(a) for a in out)


@pytest.mark.skipif(not sim_kernels.ENABLED, reason="numba not installed or BOSUN_JIT=0")
def test_the_lab_controllers_and_plants_are_blocks_whose_kernels_equal_their_references():
    """Issue 29, items 1–2: the Comau's law and the winch's heave compensation (control floor), the Comau's
    drives and the winch drum (simulation floor), each a block whose kernel gives its NumPy reference's numbers
    over seeded random inputs in every mode."""
    from app.control.lab import COMAU_LAW, WINCH_LAW
    from app.control.lab_kernels import BRAKE, MOTION_COMP, REMOTE, SETTLED
    from app.models.lab import load_lab
    from app.models.stewart import StewartPlatform
    from app.scenes.lab import MotionLab
    from app.sim.motionlab import COMAU_DRIVES, WINCH_DRUM

    lab = MotionLab(load_lab(), at_work=True)
    g, f, wf = lab._geometry, lab.joints, lab.winch.filter
    law_p = (*g[:3], *g[5:9], f.lower, f.upper)
    rng = np.random.default_rng(2029)
    seen_modes = set()
    for k in range(240):
        mode = (SETTLED, REMOTE, MOTION_COMP, BRAKE)[k % 4]
        q = np.ascontiguousarray(lab.q_work + rng.normal(0.0, 0.05, 3))
        view = _lab_view(rng, lab)
        offset = tuple(rng.normal(0.0, 0.02, 3) for _ in range(4))  # anti-swing (p, ṗ), the operator's shift (d, ḋ)
        u = COMAU_LAW.record("inputs", mode=mode, q=q, v_cmd=rng.normal(0.0, 0.1, 3), offset=offset, view=view)
        _, y_k = COMAU_LAW.step((), u, law_p, 0.005, use_kernels=True)
        _, y_r = COMAU_LAW.step((), u, law_p, 0.005, use_kernels=False)
        assert bool(y_k[0]) == bool(y_r[0]) and bool(y_k[3]) == bool(y_r[3]) and y_k[4] == y_r[4]
        if not y_k[0]:
            np.testing.assert_allclose(y_k[1], y_r[1], rtol=0, atol=1e-10)
            if y_k[3]:
                np.testing.assert_allclose(y_k[2], y_r[2], rtol=1e-8, atol=1e-10)
        seen_modes.add(mode)
        # the drives take the command, from the same random state, both ways
        x0 = (q, rng.normal(0.0, 0.2, 3), np.zeros(3))
        x_k, _ = COMAU_DRIVES.step((*(a.copy() for a in x0), np.zeros(4, bool)), y_r, f.limits(), 0.005, True)
        x_r, _ = COMAU_DRIVES.step((*(a.copy() for a in x0), np.zeros(4, bool)), y_r, f.limits(), 0.005, False)
        for a, b in zip(x_k, x_r, strict=True):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
        assert np.all((x_k[0] >= f.lower) & (x_k[0] <= f.upper))
        # the winch: heave compensation from a fresh capture and with a target, then the drum
        track, has = bool(k % 3), bool(k % 2)
        target = rng.normal(0.0, 0.5, 3)
        wl = np.array([1.0 + rng.uniform(0.0, 0.5)])
        H2 = lab.layout.T_world_n2 @ StewartPlatform.pose_matrix(view[4])
        tool = (rng.normal(0.0, 1.0, 3) + [0.0, 0.0, 3.0], rng.normal(0.0, 0.2, 3))
        wu = (track, rng.uniform(-1.0, 1.0), wl, (0.1, -0.05), tool, (np.ascontiguousarray(H2), view[7], view[5]))
        wp = (g[4], wf.speed)
        (t_k, h_k), r_k = WINCH_LAW.step((target.copy(), has), wu, wp, 0.005, True)
        (t_r, h_r), r_r = WINCH_LAW.step((target.copy(), has), wu, wp, 0.005, False)
        assert bool(h_k) == bool(h_r) == (has or track)
        np.testing.assert_allclose(r_k, r_r, rtol=0, atol=1e-12)
        if track:
            np.testing.assert_allclose(t_k, t_r, rtol=0, atol=1e-12)
        drum_p = (wf.lower, wf.upper, wf.speed, wf.accel, wf.tau)
        w0 = (wl, np.array([rng.normal(0.0, 0.1)]), np.zeros(1))
        d_k, _ = WINCH_DRUM.step((*(a.copy() for a in w0), np.zeros(4, bool)), r_r, drum_p, 0.005, True)
        d_r, _ = WINCH_DRUM.step((*(a.copy() for a in w0), np.zeros(4, bool)), r_r, drum_p, 0.005, False)
        for a, b in zip(d_k, d_r, strict=True):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    assert seen_modes == {SETTLED, REMOTE, MOTION_COMP, BRAKE}


# ----------------------------------------------------------------------------- the crane head's servo
def _head_params():
    """(pid, motors) records of the crane head (TAC paper Table 4: K_p 10, K_i 60, K_d 1, T_DC 0.2 s, K_DC 1;
    the head file's 90°/s arm speed), as HeadServo makes them."""
    from app.control.tac import HEAD_PID
    from app.sim.head import HEAD_MOTORS

    lower, upper = np.radians([-60.0, -60.0, -60.0]), np.radians([80.0, 80.0, 80.0])
    margin = np.radians(10.0)
    pid = HEAD_PID.record(
        "params", kp=10.0, ki=60.0, kd=1.0, t_dc=0.2, k_dc=1.0, u_min=lower - margin, u_max=upper + margin
    )
    motors = HEAD_MOTORS.record("params", t_dc=0.2, k_dc=1.0, lower=lower, upper=upper, speed=np.full(3, np.pi / 2))
    return pid, motors


def test_the_head_motor_block_kernel_and_reference_give_the_same_numbers():
    """The crane head's plant: the DC motors of TAC eq. (58), speed-limited, inside the mechanical stops."""
    from app.sim.head import HEAD_MOTORS

    _, p = _head_params()
    rng = np.random.default_rng(58)
    x_k, x_r = (np.zeros(3),), (np.zeros(3),)
    seen = set()
    for k in range(600):
        spread = 0.05 if k % 3 else 3.0  # near the arms (eq. 58 alone) and far (the speed limit, the stops)
        u = (x_r[0] + rng.normal(0.0, spread, 3),)
        x_k, y_k = HEAD_MOTORS.step((x_k[0].copy(),), u, p, 0.01, use_kernels=True)
        x_r, y_r = HEAD_MOTORS.step(x_r, u, p, 0.01, use_kernels=False)
        np.testing.assert_allclose(x_k[0], x_r[0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(y_k[0], y_r[0], rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(y_k[1], y_r[1])
        assert np.all(x_r[0] >= p[2]) and np.all(x_r[0] <= p[3])
        seen.update(bool(f) for f in y_r[1])
    assert seen == {True, False}  # both branches of eq. (58) ran
    assert HEAD_MOTORS.implementation(use_kernels=True).__name__ == "head_motors_block"


def test_the_head_pid_block_kernel_and_reference_give_the_same_numbers():
    """The crane head's controller: the PID of TAC eq. (57) solved for u with eq. (58)'s motor rate; its
    state is committed by the scene (anti-windup), so a step returns its integral unchanged."""
    from app.control.tac import HEAD_PID

    p, _ = _head_params()
    rng = np.random.default_rng(57)
    integral = np.zeros(3)
    seen = set()
    for k in range(600):
        spread = 0.05 if k % 3 else 3.0
        alpha = rng.uniform(-1.0, 1.3, 3)
        u = (alpha + rng.normal(0.0, spread, 3), rng.normal(0.0, 10 * spread, 3), alpha)
        x_k, y_k = HEAD_PID.step((integral.copy(),), u, p, 0.01, use_kernels=True)
        x_r, y_r = HEAD_PID.step((integral.copy(),), u, p, 0.01, use_kernels=False)
        np.testing.assert_array_equal(x_k[0], integral)
        np.testing.assert_array_equal(x_r[0], integral)
        for a, b in zip(y_k[:2], y_r[:2], strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(y_k[2], y_r[2])
        seen.update(bool(f) for f in y_r[2])
        integral = np.where(y_r[2], integral, y_r[1])
    assert seen == {True, False}  # limited and free
    assert HEAD_PID.named("outputs", y_r)["limited"] is y_r[2]


@pytest.mark.parametrize("use_kernels", [True, False])
def test_the_head_servo_steps_through_the_pid_and_motor_blocks(use_kernels):
    """HeadServo (app.scenes.tac) is PID → motors → the integral committed unless the input was limited or
    the motor saturated in that step, bit for bit, compiled and in the reference."""
    from app.control.tac import HEAD_PID, PidGains
    from app.scenes.tac import HeadServo
    from app.sim.head import HEAD_MOTORS

    pid, motors = _head_params()
    servo = HeadServo(PidGains(), motors[2], motors[3], np.zeros(3), motors[4], use_kernels=use_kernels)
    rng = np.random.default_rng(29)
    ref = rng.uniform(-1.0, 1.3, (300, 3))
    ref_dot = rng.normal(0.0, 5.0, (300, 3))
    x = (servo.alpha.copy(), servo.integral.copy())
    alpha, u = servo.run(ref, ref_dot, 0.01)
    for k in range(300):
        _, (u_k, trial, limited) = HEAD_PID.step((x[1],), (ref[k], ref_dot[k], x[0]), pid, 0.01, use_kernels)
        (a_k,), (_, saturated) = HEAD_MOTORS.step((x[0].copy(),), (u_k,), motors, 0.01, use_kernels)
        x = (a_k, np.where(limited | saturated, x[1], trial))
        np.testing.assert_array_equal(alpha[k], a_k)
        np.testing.assert_array_equal(u[k], u_k)
    np.testing.assert_array_equal(servo.integral, x[1])


# ----------------------------------------------------------------------------- the cooperative crane
def _crane_params():
    """(law, joints) records of the crane in robots/tac_crane.xml-like limits, as CraneServo makes them."""
    from app.control.tac import CRANE_LAW
    from app.sim.head import CRANE_JOINTS

    lower, upper = np.radians([-720.0, -20.0, -150.0]), np.radians([720.0, 80.0, -20.0])
    speed, accel = np.radians([6.0, 4.0, 4.0]), np.radians([3.0, 2.0, 2.0])
    law = CRANE_LAW.record("params", lower=lower, upper=upper, speed=speed, accel=accel, share=0.3, k_p=1.0)
    joints = CRANE_JOINTS.record("params", lower=lower, upper=upper, accel=accel)
    return law, joints


def test_the_crane_law_and_joint_blocks_kernel_and_reference_give_the_same_numbers():
    """The crane's law (share of β_c, its rate, a P correction, within speed and braking limits) and its
    joints (rate drives, acceleration-limited, inside the limits): compiled and reference agree, and the
    joints never leave their limits nor change rate faster than they may."""
    from app.control.tac import CRANE_LAW
    from app.sim.head import CRANE_JOINTS

    law, joints = _crane_params()
    lower, upper, speed, accel = law[:4]
    rng = np.random.default_rng(42)
    x = (np.radians([0.0, 70.0, -30.0]), np.zeros(3))  # boom and jib 10° from their upper limits
    beta_d = x[0].copy()
    near_limit = 0
    for k in range(2000):
        spread = 0.02 if k % 5 else 2.0  # small moves, and jumps to the speed, braking and position limits
        beta_c = upper + 3.0 if 1000 <= k < 1600 else x[0] + rng.normal(0.0, spread, 3)  # a while beyond the limits
        u = (beta_d, beta_c, rng.normal(0.0, 0.1, 3), x[0])
        _, (c_k,) = CRANE_LAW.step((), u, law, 0.01, use_kernels=True)
        _, (c_r,) = CRANE_LAW.step((), u, law, 0.01, use_kernels=False)
        np.testing.assert_array_equal(c_k, c_r)
        assert np.all(np.abs(c_r) <= speed)
        x_k, _ = CRANE_JOINTS.step(tuple(a.copy() for a in x), (c_r,), joints, 0.01, use_kernels=True)
        x_r, _ = CRANE_JOINTS.step(x, (c_r,), joints, 0.01, use_kernels=False)
        for a, b in zip(x_k, x_r, strict=True):
            np.testing.assert_array_equal(a, b)
        assert np.all(np.abs(x_r[1] - x[1]) <= accel * 0.01 * (1 + 1e-12))
        assert np.all(x_r[0] >= lower) and np.all(x_r[0] <= upper)
        near_limit += bool(np.any(np.minimum(x_r[0] - lower, upper - x_r[0]) < 0.05))
        x = x_r
    assert near_limit > 0  # the run reached a position limit
    assert CRANE_LAW.implementation(use_kernels=True).__name__ == "crane_law_block"
    assert CRANE_JOINTS.implementation(use_kernels=True).__name__ == "crane_joints_block"


@pytest.mark.parametrize("use_kernels", [True, False])
def test_the_crane_servo_steps_through_the_law_and_joint_blocks(use_kernels):
    """CraneServo (app.scenes.tac) is law → joints, bit for bit, compiled and in the reference."""
    from app.control.tac import CRANE_LAW
    from app.scenes.tac import CraneServo
    from app.sim.head import CRANE_JOINTS

    law, joints = _crane_params()
    beta_d = np.radians([0.0, 30.0, -90.0])
    servo = CraneServo(*law[:4], beta_d, share=0.3, k_p=1.0, use_kernels=use_kernels)
    rng = np.random.default_rng(44)
    beta_c = beta_d + np.cumsum(rng.normal(0.0, 0.02, (300, 3)), axis=0)
    rate = rng.normal(0.0, 0.2, (300, 3))
    out_b, out_v = servo.run(beta_d, beta_c, rate, 0.01)
    x = (beta_d.copy(), np.zeros(3))
    for k in range(300):
        _, cmd = CRANE_LAW.reference((), (beta_d, beta_c[k], rate[k], x[0]), law, 0.01)
        x, _ = CRANE_JOINTS.reference(x, cmd, joints, 0.01)
        np.testing.assert_array_equal(out_b[k], x[0])
        np.testing.assert_array_equal(out_v[k], x[1])
    np.testing.assert_array_equal(servo.beta, x[0])
    np.testing.assert_array_equal(servo.beta_dot, x[1])
