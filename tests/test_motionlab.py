"""Motion-Lab: calibration layout, Comau on the moving platform (eqs. 3–6, 54–57), the suspended
load (eqs. 23–30, 58–61), the winch and vessel-to-vessel motion compensation."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from app.errors import RobotXmlError
from app.models.lab import load_lab, parse_lab_xml, quat_to_matrix
from app.models.stewart import StewartPlatform
from app.scenarios.vvmc import VvmcError, VvmcScenario, simulate, summarize
from app.sim.motionlab import ComauKinematics, G, MotionLab, Pendulum, tool_on_platform


@pytest.fixture(scope="module")
def lab() -> MotionLab:
    return MotionLab(load_lab())


# ----------------------------------------------------------------------------- calibration
def test_layout_matches_the_lab_calibration(shared_data):
    """The transforms transcribed into robots/labs/motionlab.xml are the lab's H matrices."""
    calib = json.loads((shared_data / "motionlab_calib.json").read_text())
    layout = load_lab()
    for key, T in (
        ("WORLD_TO_EM8000", layout.T_world_n1),
        ("WORLD_TO_EM1500", layout.T_world_n2),
        ("EM8000_TO_COMAU", layout.T_b1_r),
    ):
        np.testing.assert_allclose(T, np.array(calib[key]["H"]), atol=1e-12)
    # and the chain agrees with the calibrated EM8000 → EM1500 transform
    np.testing.assert_allclose(
        np.linalg.inv(layout.T_world_n1) @ layout.T_world_n2, np.array(calib["EM8000_TO_EM1500"]["H"]), atol=1e-9
    )


def test_quaternion_convention():
    np.testing.assert_allclose(
        quat_to_matrix([math.cos(0.3), 0, 0, math.sin(0.3)])[:2, :2], [[0.8253, -0.5646], [0.5646, 0.8253]], atol=1e-4
    )


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (('quat="6.0198987883E-5', 'quat="0.5'), r"motionlab.xml:\d+: <frame> quat must be a unit quaternion"),
        (('start_length="0.8"', 'start_length="9"'), r"start_length must lie between"),
        (
            ('<crane robot="comau_smart5_3dof" on="em8000"', '<crane robot="comau_smart5_3dof" on="em1500"'),
            r"first platform",
        ),
        (('pos="-2.9696616227022652 1.976311036084776 2.6628450155926142"', 'pos="1 2"'), r"needs 3 finite numbers"),
    ],
)
def test_layout_errors_name_file_and_line(edit, message):
    from pathlib import Path

    xml = Path(load_lab().path).read_text(encoding="utf-8").replace(*edit)
    with pytest.raises(RobotXmlError, match=message):
        parse_lab_xml(xml, "motionlab.xml")


# ----------------------------------------------------------------------------- Comau
def test_eq3_against_the_dh_chain(lab, rng):
    """Eq. (3) with L = d4 + d6 + d_tp (Table 7: 2.269 m) equals the Table 3 DH chain."""
    assert pytest.approx(1.492 + 0.210 + 0.567) == lab.comau.L
    q = rng.uniform(lab.robot.lower, lab.robot.upper, (50, 3))
    np.testing.assert_allclose(lab.comau.position(q), lab.robot.position(q), atol=1e-12)


def test_comau_jacobian_and_acceleration_against_finite_differences(lab, rng):
    c: ComauKinematics = lab.comau
    for _ in range(20):
        q, qd, qdd = rng.uniform(lab.robot.lower, lab.robot.upper), rng.normal(size=3), rng.normal(size=3)
        h = 1e-5

        def traj(t, q=q, qd=qd, qdd=qdd):
            return q + qd * t + 0.5 * qdd * t * t

        v_fd = (c.position(traj(h)) - c.position(traj(-h))) / (2 * h)
        a_fd = (c.position(traj(h)) - 2 * c.position(traj(0)) + c.position(traj(-h))) / h**2
        np.testing.assert_allclose(c.velocity(q, qd), v_fd, atol=1e-8)
        np.testing.assert_allclose(c.acceleration(q, qd, qdd), a_fd, atol=2e-4)


def test_tool_point_on_a_moving_platform_against_finite_differences(lab, rng):
    """Eqs. (56)–(57): tool velocity and acceleration in {n1} with platform and joints moving."""
    T = lab.layout.T_b1_r
    for _ in range(10):
        eta0 = rng.uniform(-0.2, 0.2, 6)
        ed, edd = rng.normal(size=6) * 0.3, rng.normal(size=6) * 0.3
        q0 = lab.q_work + rng.normal(size=3) * 0.2
        qd, qdd = rng.normal(size=3) * 0.5, rng.normal(size=3) * 0.5

        def at(t, eta0=eta0, ed=ed, edd=edd, q0=q0, qd=qd, qdd=qdd):
            eta = eta0 + ed * t + 0.5 * edd * t * t
            q = q0 + qd * t + 0.5 * qdd * t * t
            return tool_on_platform(lab.comau, T, eta, ed + edd * t, edd, q, qd + qdd * t, qdd)

        p, v, a = at(0.0)
        h = 1e-4
        (pp, vp, _), (pm, vm, _) = at(h), at(-h)
        np.testing.assert_allclose(v, (pp - pm) / (2 * h), atol=1e-6)
        np.testing.assert_allclose(a, (vp - vm) / (2 * h), atol=1e-6)
        np.testing.assert_allclose(a, (pp - 2 * p + pm) / h**2, atol=1e-4)


# ----------------------------------------------------------------------------- pendulum
def _period(p: Pendulum, L: float, dt: float, seconds: float, a_t=None) -> float:
    a_t = np.zeros(3) if a_t is None else a_t
    t, prev, crossings = 0.0, p.alpha, []
    while t < seconds:
        p.step(dt, a_t, L, 0.0)
        t += dt
        if prev < 0 <= p.alpha:
            crossings.append(t - dt * p.alpha / (p.alpha - prev))
        prev = p.alpha
    return float(np.mean(np.diff(crossings)))


@pytest.mark.parametrize("L", [0.5, 1.0, 2.5])
def test_small_angle_period(L):
    p = Pendulum(alpha=0.01)
    T = _period(p, L, 0.01, 30.0)
    assert pytest.approx(2 * math.pi * math.sqrt(L / G), rel=0.005) == T


def test_vertical_tool_acceleration_changes_gravity_the_right_way():
    """Tool accelerating upwards at 3 m/s² (z_d = −3, {d} is z-down): period 2π√(L/(g+3)).
    The printed eqs. (29)–(30) give g − 3 here; the Lagrangian in a z-down frame gives g + 3."""
    L = 1.0
    p = Pendulum(beta=0.01)  # β swing, to test eq. (30) as well
    t_beta = []
    prev, t = p.beta, 0.0
    while t < 20:
        p.step(0.005, np.array([0, 0, -3.0]), L, 0.0)
        t += 0.005
        if prev < 0 <= p.beta:
            t_beta.append(t)
        prev = p.beta
    assert np.mean(np.diff(t_beta)) == pytest.approx(2 * math.pi * math.sqrt(L / (G + 3.0)), rel=0.005)
    T = _period(Pendulum(alpha=0.01), L, 0.005, 20.0, a_t=np.array([0, 0, -3.0]))
    assert pytest.approx(2 * math.pi * math.sqrt(L / (G + 3.0)), rel=0.005) == T


def test_energy_is_conserved_without_damping_and_wire_motion():
    p = Pendulum(alpha=0.6, beta=-0.4, alpha_dot=0.3, beta_dot=0.8)  # large, 3D (conical) swing
    L = 1.5
    E0 = p.energy(L)
    drift = 0.0
    for _ in range(6000):  # 60 s
        p.step(0.01, np.zeros(3), L, 0.0)
        drift = max(drift, abs(p.energy(L) - E0) / E0)
    assert drift < 1e-6


def test_damping_makes_the_swing_decay():
    """With −c φ̇ in each equation the swing energy decays like e^(−c t) (light damping)."""
    p = Pendulum(alpha=0.1, beta=0.05, damping=0.1)
    L = 1.0
    energies = [p.energy(L)]
    for _ in range(40):
        for _ in range(100):
            p.step(0.01, np.zeros(3), L, 0.0)
        energies.append(p.energy(L))
    assert all(b < a for a, b in itertools.pairwise(energies))  # never gains energy
    assert energies[-1] / energies[0] == pytest.approx(math.exp(-0.1 * 40), rel=0.1)


def test_hoisting_in_grows_the_swing_angle():
    """Shortening the wire (L̇ < 0) pumps energy into the swing (the −2 L̇ φ̇ terms)."""
    p = Pendulum(alpha=0.05)
    L, Ld = 2.0, -0.1
    for _ in range(1000):
        p.step(0.01, np.zeros(3), L, Ld)
        L += Ld * 0.01
    amp = max(abs(p.alpha), math.hypot(p.alpha, p.alpha_dot / math.sqrt(G / L)))
    assert amp > 0.055


# ----------------------------------------------------------------------------- winch
def test_winch_stays_inside_its_limits(lab):
    w = MotionLab(load_lab()).winch
    w.speed_command = 5.0  # far past the limit
    for _ in range(2000):
        w.step(0.01)
        assert w.spec["min_length"] - 1e-12 <= w.length <= w.spec["max_length"] + 1e-12
        assert abs(w.speed) <= w.spec["speed"] + 1e-12
    assert w.length == pytest.approx(w.spec["max_length"])


# ----------------------------------------------------------------------------- VVMC
@pytest.fixture(scope="module")
def vvmc_runs():
    """40 s with and without compensation: under a second each, compiled (issue 14, item 4)."""
    sc = VvmcScenario(hs=2.0, tp=8.0, duration=40.0, seed=1)
    return sc, simulate(sc, True), simulate(sc, False)


def test_vvmc_reduces_relative_tool_motion_by_90_percent(vvmc_runs):
    sc, on, off = vvmc_runs
    s = summarize(sc, on, off)
    assert s["uncompensated"]["rms_tool_error_m"] > 0.02  # the platforms really move relative to each other
    assert s["reduction_percent"] >= 90.0
    assert s["compensated"]["time_at_limit_s"] == 0.0  # inside limits


def test_vvmc_keeps_joints_inside_limits(vvmc_runs):
    _, on, _ = vvmc_runs
    lab = MotionLab(load_lab())
    assert np.all(on.q >= lab.robot.lower - 1e-9) and np.all(on.q <= lab.robot.upper + 1e-9)
    assert np.all(np.abs(on.qd) <= lab.robot.speed + 1e-9)
    assert np.all(np.isfinite(on.e_t_b2))


def test_vvmc_winch_holds_payload_height(vvmc_runs):
    sc, on, _ = vvmc_runs
    m = on.t > sc.ramp + sc.settle
    assert np.sqrt(np.mean(on.height_error[m] ** 2)) < 0.01


def test_vvmc_scenario_errors():
    with pytest.raises(VvmcError, match="--hs must be a positive number"):
        VvmcScenario(hs=-1)
    with pytest.raises(VvmcError, match="leaves nothing to measure"):
        VvmcScenario(duration=10)
    with pytest.raises(Exception, match="steep"):
        VvmcScenario(hs=8, tp=5)


def test_platform_pose_in_world_uses_eq39(lab):
    H = lab.platform_pose(0)
    np.testing.assert_allclose(H, lab.layout.T_world_n1 @ StewartPlatform.pose_matrix(lab.platforms[0].eta))
