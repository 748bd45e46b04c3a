"""Crane-head compensation (TAC paper §7–10): references, joint servo, crane IK, simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.control.tac import PidGains
from app.geometry import euler_zyx_to_matrix
from app.models.crane_head import CraneHead
from app.models.registry import load_robot
from app.scenarios.tac import BETA_EQ60, ScenarioError, TacScenario, TacSimulator, simulate
from app.scenes.tac import HeadServo


@pytest.fixture(scope="module")
def system():
    return CraneHead(load_robot("offshore_crane"), load_robot("tac_delta_head"))


def test_desired_point_and_crane_ik_with_l2_plus_xd(system):
    """§8: x_d from the workspace (Table 4 geometry), and the elbow IK with L2 + x_d round trip."""
    assert system.x_d == pytest.approx(6.51, abs=0.01)
    p = system.tcp_n(np.zeros(6), BETA_EQ60, system.p_d_t)
    # eq. (60): jib level to starboard, TCP x_d beyond the jib tip
    o_t_b, R_b_t = system.crane_pose(BETA_EQ60)
    np.testing.assert_allclose(p, o_t_b + R_b_t @ system.p_d_t, atol=1e-12)
    beta = system.crane_ik_tcp(p)[0]
    np.testing.assert_allclose(beta, BETA_EQ60, atol=1e-9)
    rng = np.random.default_rng(5)
    for _ in range(20):
        b = BETA_EQ60 + rng.uniform(-0.3, 0.3, 3)
        target = system.tcp_n(np.zeros(6), b, system.p_d_t)
        np.testing.assert_allclose(
            system.tcp_n(np.zeros(6), system.crane_ik_tcp(target)[0], system.p_d_t), target, atol=1e-9
        )


AMP = np.array([0.3, -0.2, 0.8, 0.04, 0.03, 0.02])
OMEGA = np.array([0.6, 0.7, 0.8, 0.5, 0.9, 0.4])


def _motion(t, amp=AMP, w=OMEGA):
    eta = amp * np.sin(np.outer(t, w))
    deta = amp * w * np.cos(np.outer(t, w))
    from app.marine.vessel import body_velocities

    nu, _ = body_velocities(eta, deta, -amp * w**2 * np.sin(np.outer(t, w)))
    return eta, nu


def test_reference_velocity_is_the_derivative_of_the_reference(system):
    """eq. (52) with the exact eqs. (53)–(54): v_ref^t = d/dt p_ref^t, also with the crane moving."""
    dt = 1e-4
    t = np.arange(2.0, 4.0, dt)
    eta, nu = _motion(t)
    beta = BETA_EQ60 + 0.1 * np.sin(np.outer(t, [0.5, 0.8, 1.1]))
    beta_dot = 0.1 * np.array([0.5, 0.8, 1.1]) * np.cos(np.outer(t, [0.5, 0.8, 1.1]))
    ref = system.head_reference(eta, nu, beta, beta_dot, system.tcp_n(np.zeros(6), BETA_EQ60, system.p_d_t))
    fd = np.gradient(ref.p_ref_t, dt, axis=0)
    np.testing.assert_allclose(ref.v_ref_t[1:-1], fd[1:-1], atol=1e-6)
    ok = ~ref.saturated
    assert ok.mean() > 0.9
    afd = np.gradient(ref.alpha_ref, dt, axis=0)
    np.testing.assert_allclose(ref.alpha_dot_ref[1:-1][ok[1:-1]], afd[1:-1][ok[1:-1]], atol=1e-5)


def test_reference_puts_the_tcp_on_the_desired_point(system):
    t = np.linspace(0, 20, 200)
    eta, nu = _motion(t)
    beta = np.broadcast_to(BETA_EQ60, (t.size, 3))
    p_d_n = system.tcp_n(np.zeros(6), BETA_EQ60, system.p_d_t)
    ref = system.head_reference(eta, nu, beta, np.zeros_like(beta), p_d_n)
    assert not ref.saturated.any()
    p = system.tcp_n(eta, beta, system.head.fk(ref.alpha_ref))
    np.testing.assert_allclose(p, np.broadcast_to(p_d_n, p.shape), atol=1e-9)


def test_out_of_workspace_reference_is_saturated_onto_the_hull(system):
    t = np.array([0.0])
    eta = np.array([[0, 0, 6.0, 0, 0, 0]])  # 6 m heave: far beyond the head's 3 m
    ref = system.head_reference(
        eta, np.zeros((1, 6)), BETA_EQ60[None], np.zeros((1, 3)), system.tcp_n(np.zeros(6), BETA_EQ60, system.p_d_t)
    )
    assert ref.saturated[0] and t.size == 1
    assert abs(system.workspace.depth(ref.p_cmd_t[0])) < 1e-9
    assert np.all(system.head.within_limits(ref.alpha_ref[0]))
    assert np.all(ref.alpha_dot_ref == 0)


def test_servo_never_leaves_the_joint_limits(system):
    head = system.head
    servo = HeadServo(PidGains(), head.lower, head.upper, system.alpha_d)
    rng = np.random.default_rng(11)
    ref = rng.uniform(-3, 3, (3000, 3))  # wild, even out-of-range references
    alpha, u = servo.run(ref, rng.normal(0, 10, (3000, 3)), 0.01)
    assert np.all(alpha >= head.lower) and np.all(alpha <= head.upper)
    assert np.all(np.isfinite(u))


def test_servo_step_response_matches_the_continuous_closed_loop():
    """PID (eq. 57) on the motor (eq. 58): poles of 1.2 s² + 11 s + 60 (Table 4 gains)."""
    lo, hi = np.full(3, -1.0), np.full(3, 1.0)
    servo = HeadServo(PidGains(), lo, hi, np.zeros(3))
    dt = 1e-3
    alpha, _ = servo.run(np.full((3000, 3), 0.1), np.zeros((3000, 3)), dt)
    # with α̇_ref = 0 the D term acts on −α̇ only: α/α_ref = (K_p s + K_i) / ((T + K_d) s² + (1 + K_p) s + K_i)
    from scipy import signal

    sys_ = signal.TransferFunction([10.0, 60.0], [1.2, 11.0, 60.0])
    t = np.arange(1, 3001) * dt
    _, y = signal.step(sys_, T=t)
    np.testing.assert_allclose(alpha[:, 0], 0.1 * y, atol=2e-3)


def test_sinusoidal_heave_is_compensated_to_under_2_percent(system):
    """A pure sinusoidal heave inside the workspace (1.5 m, 10 s) leaves < 2 % residual."""
    sc = TacScenario(hs=1.0, tp=9.0, duration=60.0, mode="tac")
    sim = TacSimulator(sc, system)

    class Heave:
        def state(self, t):
            from app.marine.vessel import VesselState

            w = 2 * math.pi / 10.0
            eta = np.zeros((t.size, 6))
            deta = np.zeros_like(eta)
            eta[:, 2] = 1.5 * np.sin(w * t)
            deta[:, 2] = 1.5 * w * np.cos(w * t)
            return VesselState(t, eta, deta.copy(), np.zeros_like(eta))

    sim.vessel = Heave()
    data = sim.advance(sim.n_steps)
    steady = data.t > 20.0
    rms_c = np.sqrt(np.mean(data.e_c[steady] ** 2))
    rms_s = np.sqrt(np.mean(data.e_s[steady] ** 2))
    assert rms_s == pytest.approx(1.5 / math.sqrt(2), rel=0.01)
    assert not data.saturated.any()
    assert rms_c / rms_s < 0.02


@pytest.mark.parametrize("mode", ["off", "tac", "cooperative"])
def test_simulation_modes_run_and_are_reproducible(system, mode):
    sc = TacScenario(hs=2.0, tp=8.0, duration=20.0, mode=mode, seed=3)
    a = simulate(sc, system=system)
    b = simulate(sc, system=system)
    np.testing.assert_array_equal(a.data.e_c, b.data.e_c)
    s = a.summary
    assert s["steps"] == 2000 and np.all(np.isfinite(a.data.alpha))
    head = system.head
    assert np.all(a.data.alpha >= head.lower) and np.all(a.data.alpha <= head.upper)
    if mode == "off":
        np.testing.assert_allclose(a.data.e_c, a.data.e_s)
    else:
        assert s["ratio_rms"] < 0.05  # Hs 2 m stays inside the workspace
    crane = system.crane
    assert np.all(a.data.beta >= crane.lower - 1e-12) and np.all(a.data.beta <= crane.upper + 1e-12)


def test_cooperative_crane_respects_speed_and_acceleration(system):
    sc = TacScenario(hs=5.0, tp=9.0, duration=60.0, mode="cooperative", crane_share=1.0, crane_kp=4.0)
    d = simulate(sc, system=system).data
    v = np.diff(d.beta, axis=0) / sc.dt
    assert np.all(np.abs(v) <= system.crane.speed * (1 + 1e-9))
    a = np.diff(v, axis=0) / sc.dt
    assert np.all(np.abs(a) <= system.crane.accel * (1 + 1e-6))


def test_progress_and_cancel(system):
    calls = []
    res = simulate(TacScenario(duration=10.0), system=system, chunk=250, progress=lambda k, n: calls.append((k, n)))
    assert calls[-1] == (1000, 1000) and len(calls) == 4 and not res.cancelled
    res = simulate(TacScenario(duration=10.0), system=system, chunk=250, cancel=lambda: True)
    assert res.cancelled and res.data.t.size == 0


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"mode": "magic"}, "mode must be one of"),
        ({"hs": -1.0}, "Hs"),
        ({"duration": 0.0}, "duration must be positive"),
        ({"dt": 0.5}, "dt must be in"),
        ({"spectrum": "nope"}, "spectrum must be one of"),
        ({"crane_share": 2.0}, "crane share"),
    ],
)
def test_bad_scenarios(kw, match):
    with pytest.raises(ScenarioError, match=match):
        TacScenario(**kw)


def test_rotation_convention_in_tcp(system):
    """tcp_n uses R_b^n = Rz Ry Rx (Fossen zyx), the convention of the vessel model."""
    eta = np.array([1.0, 2.0, 3.0, 0.1, -0.05, 0.2])
    p = system.tcp_n(eta, BETA_EQ60, system.p_d_t)
    o_t_b, R_b_t = system.crane_pose(BETA_EQ60)
    np.testing.assert_allclose(p, euler_zyx_to_matrix(eta[3:]) @ (o_t_b + R_b_t @ system.p_d_t) + eta[:3])
