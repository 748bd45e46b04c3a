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
        (('start_length="1.8"', 'start_length="9"'), r"start_length must lie between"),
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
    lab = MotionLab(load_lab())  # the layout's profile: the lab's own limits (issue 16)
    assert lab.profile.name == "lab"
    assert np.all(on.q >= lab.joints.lower - 1e-9) and np.all(on.q <= lab.joints.upper + 1e-9)
    assert np.all(np.abs(on.qd) <= lab.joints.speed + 1e-9)
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


# ----------------------------------------------------------------------------- the lab's own numbers (issue 16)
# motionlab_plc.json (Norwegian Motion-Laboratory repository, commit f5fbf84, MIT), FB_StewartInterface.FB_init:
# the settled heave (the PLC's initial Actual_platform_position_heave) and the operational box etaRefMin/Max
LAB_SETTLED_HEAVE = {"em8000": 0.9986208, "em1500": 0.4663845}
LAB_BOX = {
    "em8000": ([-0.2, -0.2, -0.6, -5, -5, -10], [0.2, 0.2, 0.6, 5, 5, 10]),
    "em1500": ([-0.15, -0.15, -0.3, -5, -5, -5], [0.15, 0.15, 0.3, 5, 5, 5]),
}  # m, m, m, deg, deg, deg


def _si(values) -> np.ndarray:
    """(x, y, z [m], φ, θ, ψ [deg]) → SI."""
    v = np.array(values, dtype=float)
    v[3:] = np.radians(v[3:])
    return v


def _tick(ses, seconds: float, t0: float = 0.0, dt: float = 0.02, check=None) -> float:
    t = t0
    for _ in range(round(seconds / dt)):
        t += dt
        ses.tick(t, dt)
        if check is not None:
            check(ses.snapshot())
    return t


def test_settled_heave_and_the_operational_box_from_the_engine():
    """Issue 16: a running lab engine reports both platforms SETTLED at the lab's heave (within 5 mm) with
    every leg at its minimum length, and describes the lab's operational box as each platform's command
    limit (Table 8 stays ``pose_min``/``pose_max``)."""
    from app.engine.lab_session import LabSession

    ses = LabSession()
    _tick(ses, 1.0)
    snap, desc = ses.snapshot(), ses.describe()
    for p, info in zip(snap.platforms, desc.platforms, strict=True):
        assert p.status == "settled" and p.name == info.name
        assert p.eta[2] == pytest.approx(LAB_SETTLED_HEAVE[p.name], abs=0.005)
        assert info.settled[2] == pytest.approx(p.eta[2], abs=1e-6)
        np.testing.assert_allclose(p.legs, info.leg_range[0], atol=2e-5)
        lo, hi = LAB_BOX[p.name]
        np.testing.assert_allclose(info.command_min, _si(lo), atol=1e-12)
        np.testing.assert_allclose(info.command_max, _si(hi), atol=1e-12)
        assert np.all(np.array(info.command_min) > np.array(info.pose_min))  # strictly inside Table 8
        assert np.all(np.array(info.command_max) < np.array(info.pose_max))
    assert desc.winch.speed_max == pytest.approx(0.2)  # the lab's winch slider, u = value/100 · 0.2 m/s


def test_the_numbers_are_those_of_the_labs_plc_file(shared_data):
    """The settled heaves and boxes above against motionlab_plc.json itself (skipped without ../shared)."""
    plc = json.loads((shared_data / "motionlab_plc.json").read_text(encoding="utf-8"))["stewart"]
    settled = next(v for k, v in plc.items() if k.startswith("settled_heave_m"))
    boxes = plc["etaRef_limits_rad_m"]

    def si(values):
        return [math.radians(float(v.split()[0])) if isinstance(v, str) else float(v) for v in values]

    for name in ("em8000", "em1500"):
        assert settled[name] == pytest.approx(LAB_SETTLED_HEAVE[name], abs=1e-9)
        np.testing.assert_allclose(si(boxes[name]["min"]), _si(LAB_BOX[name][0]), atol=1e-12)
        np.testing.assert_allclose(si(boxes[name]["max"]), _si(LAB_BOX[name][1]), atol=1e-12)


def _timeseries_beyond(lo: np.ndarray, hi: np.ndarray) -> str:
    from app.sim.stewart import timeseries_to_csv

    t = np.arange(0.0, 30.01, 0.5)
    s = np.sin(2 * np.pi * t / 10.0)
    eta = np.where(s[:, None] > 0, 2.5 * hi[None, :], -2.5 * lo[None, :]) * s[:, None]  # ±2.5 × the box
    return timeseries_to_csv(t, eta)


@pytest.mark.parametrize("source", ["generator", "simulation", "remote", "timeseries"])
def test_every_motion_source_is_held_to_the_operational_box(source):
    """Issue 16: each source driven beyond the lab's operational box (a generator at the box, refused
    beyond it as on the lab HMI; waves scaled ×10; a remote pose and a time series at 2–2.5× the box): no
    snapshot of either platform ever leaves the box, and the platform does reach it.  (The input stick
    drives only the Comau and the winch; platform poses come from these four sources.)"""
    from app.engine.lab_session import LabSession
    from app.engine.scene import CommandError

    ses = LabSession()
    boxes = {i.name: (np.array(i.command_min), np.array(i.command_max)) for i in ses.describe().platforms}
    for name in ses.names:
        ses.lab_platform(name, "neutral")
    t = _tick(ses, 15.0)  # raised at a fifth of the Table 8 speeds
    assert all(p.status == "neutral" for p in ses.snapshot().platforms)
    for name, (lo, hi) in boxes.items():
        reach = np.minimum(-lo, hi)
        if source == "generator":
            with pytest.raises(CommandError, match="operational box"):
                ses.lab_source(name, "generator", amplitude=(1.5 * reach).tolist(), frequency=[0.1] * 6, phase=[0] * 6)
            ses.lab_source(name, "generator", amplitude=reach.tolist(), frequency=[0.1] * 6, phase=[0.0] * 6)
        elif source == "simulation":
            ses.lab_source(name, "simulation", hs=6.0, tp=11.0, heading=120.0, seed=3, scale=[10.0] * 6)
        elif source == "remote":
            ses.lab_source(name, "remote")
            ses.lab_remote_pose(name, (2.0 * hi).tolist())
        else:
            ses.lab_source(name, "timeseries", csv=_timeseries_beyond(lo, hi), name="beyond.csv")
        ses.lab_platform(name, "engage")
    peak = {name: np.zeros(6) for name in boxes}

    def check(snap):
        for p in snap.platforms:
            lo, hi = boxes[p.name]
            eta = np.array(p.eta)
            assert np.all(eta >= lo - 1e-6) and np.all(eta <= hi + 1e-6), (p.name, p.status, eta)
            peak[p.name] = np.maximum(peak[p.name], np.abs(eta) / np.minimum(-lo, hi))

    t = _tick(ses, 25.0, t, check=check)
    if source == "remote":
        for name, (lo, _) in boxes.items():
            ses.lab_remote_pose(name, (2.0 * lo).tolist())
        t = _tick(ses, 15.0, t, check=check)
    for name in boxes:
        assert peak[name].max() > 0.98, (name, peak[name])


def test_the_comau_has_the_labs_profile_and_the_datasheet_one_by_name():
    """Issue 16: the Motion-Lab runs the Comau with the lab program's limits (comau/setup.json: q1 ±45°,
    q2 ±30°, q3 −135…−45°, 5 rpm; A = 1 rad/s² of comau/callbackFunction.cpp); ``datasheet`` (Table 6)
    by name; an unknown name is refused."""
    from app.engine.lab_session import LabSession

    lab = MotionLab(load_lab())
    assert lab.profile.name == "lab" and set(lab.layout.crane_profiles) == {"lab", "datasheet"}
    np.testing.assert_allclose(np.degrees(lab.joints.lower), [-45, -30, -135], atol=1e-12)
    np.testing.assert_allclose(np.degrees(lab.joints.upper), [45, 30, -45], atol=1e-12)
    np.testing.assert_allclose(lab.joints.speed, 5 * 2 * math.pi / 60, rtol=1e-12)  # 5 rpm = 0.5236 rad/s
    np.testing.assert_allclose(lab.joints.brake, 1.0, rtol=1e-7)  # A = 1 rad/s² (written 57.29578°/s²)
    np.testing.assert_allclose(lab.joints.accel, math.radians(120))  # the assumed joint acceleration
    ds = MotionLab(load_lab(), comau_profile="datasheet")
    np.testing.assert_allclose(ds.joints.lower, ds.robot.lower)
    np.testing.assert_allclose(ds.joints.upper, ds.robot.upper)
    np.testing.assert_allclose(ds.joints.speed, ds.robot.speed)
    np.testing.assert_allclose(ds.joints.brake, ds.joints.accel)
    with pytest.raises(RobotXmlError, match="unknown crane joint-limit profile 'fast'"):
        MotionLab(load_lab(), comau_profile="fast")
    assert LabSession().describe().comau_profile == "lab"
    d = LabSession(comau_profile="datasheet").describe()
    assert d.comau_profile == "datasheet" and d.comau_upper == pytest.approx(ds.robot.upper.tolist())


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (('<command_box min="-0.2 ', '<command_box min="0.2 '), "must contain the neutral pose"),
        (('limits="lab"', 'limits="fast"'), "names no profile"),
        (('boundary_accel="57.29578"', 'boundary_accel="500"'), "must not exceed the crane's accel"),
        (('max="45 30 -45"', 'max="45 30 -200"'), "every min must be below its max"),
    ],
)
def test_layout_profile_and_box_errors_name_file_and_line(edit, message):
    from pathlib import Path

    xml = Path(load_lab().path).read_text(encoding="utf-8")
    assert edit[0] in xml
    with pytest.raises(RobotXmlError, match=rf"motionlab\.xml:\d+: .*{message}"):
        parse_lab_xml(xml.replace(*edit), "motionlab.xml")


def _velocity_bound_holds(q0, qd, lo, hi, A, V, dt):
    """The lab's law (comau/velocityBound.cpp; Flacco, De Luca, Khatib, IEEE T-RO 2015, eq. 13) from the
    position before the step: −min(V, (q − qMin)/Ts, √(2A(q − qMin))) ≤ q̇ ≤ min(V, (qMax − q)/Ts, √(2A(qMax − q)))."""
    up = np.minimum(np.minimum(V, (hi - q0) / dt), np.sqrt(2 * A * np.maximum(hi - q0, 0)))
    down = np.minimum(np.minimum(V, (q0 - lo) / dt), np.sqrt(2 * A * np.maximum(q0 - lo, 0)))
    return bool(np.all(qd <= up + 1e-9) and np.all(qd >= -down - 1e-9))


def test_lab_profile_holds_in_a_long_remote_run_with_the_velocity_boundary_law(rng):
    """Issue 16: 300 s of the stick in REMOTE, full deflection in random directions held 3 s each, so the
    arm keeps running into its limits: never past the lab's limits or 5 rpm, and every step obeys the lab's
    velocity-boundary law with A = 1 rad/s² (Bosun's exact discrete bound is the stricter)."""
    from app.sim.motionlab import REMOTE_TOOL_SPEED

    lab = MotionLab(load_lab(), at_work=True)
    f, dt = lab.joints, 0.01
    lo, hi, V = f.lower.copy(), f.upper.copy(), 5 * 2 * math.pi / 60
    lab.set_comau_mode("remote")
    at_limit = 0
    for k in range(30000):
        if k % 300 == 0:
            d = rng.normal(size=3)
            lab.tool_velocity_cmd = REMOTE_TOOL_SPEED * d / np.linalg.norm(d)
        q0 = f.x.copy()
        lab.step(dt)
        assert np.all(f.x >= lo - 1e-12) and np.all(f.x <= hi + 1e-12)
        assert np.all(np.abs(f.v) <= V * (1 + 1e-12))
        assert _velocity_bound_holds(q0, f.v, lo, hi, 1.0, V, dt), (k, q0, f.v)
        at_limit += bool(np.any((f.x - lo < 1e-3) | (hi - f.x < 1e-3)))
    assert at_limit > 1000  # it did run into its limits (and stayed there while pushed)


def test_lab_profile_holds_in_a_vvmc_run_in_a_high_sea():
    """VVMC at Hs 6 m (the platforms at their operational boxes): inside the lab's limits, at most 5 rpm,
    the velocity-boundary law at every step, and still compensating (1 cm)."""
    sc = VvmcScenario(hs=6.0, tp=11.0, duration=120.0, seed=2)
    on = simulate(sc, True)
    lab = MotionLab(load_lab())
    lo, hi, V = lab.joints.lower, lab.joints.upper, 5 * 2 * math.pi / 60
    assert np.all(on.q >= lo - 1e-12) and np.all(on.q <= hi + 1e-12)
    for k in range(1, len(on.t)):
        assert _velocity_bound_holds(on.q[k - 1], on.qd[k], lo, hi, 1.0, V, sc.dt)
    m = on.t > sc.ramp + sc.settle
    assert np.linalg.norm(on.e_t_b2[m], axis=1).max() < 0.01


def _lab_eq3(q: np.ndarray, L: float = 2.2692) -> np.ndarray:
    """The lab's own forward kinematics, matlab/+comau/forward.m (motion-lab repository, MIT): eq. (3) in
    the controller's q with L = d4 + d6 + dtp, d4 = 1.4922, d6 = 0.210, dtp = 0.567 (2.2692 m)."""
    a1, a2, a3, d1 = 0.350, 1.160, 0.250, 0.830
    q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2]
    u = a1 - L * np.sin(q3) - a3 * np.cos(q3) + a2 * np.sin(q2)
    return np.stack([np.cos(q1) * u, -np.sin(q1) * u, d1 + L * np.cos(q3) + a2 * np.cos(q2) - a3 * np.sin(q3)], -1)


def test_the_labs_comau_code_uses_bosuns_joint_convention_and_which_L():
    """Issue 16: the lab's joint limits are in the convention of Table 6 and comau_smart5_3dof.xml (θ1 = −q1,
    θ2 = π/2 − q2, θ3 = q3 + π/2 + q2): the lab's eq. (3) equals the robot file's DH chain over the lab's
    joint box, to the 0.2 mm between the lab code's L = 2.2692 m and Table 7's 2.269 m that Bosun uses
    (exactly with the same L); the box's centre (0°, 0°, −90°) is the upper arm vertical and the extension
    arm horizontal along x, and q1 > 0 turns the arm clockwise seen from above (y < 0)."""
    from app.models.closed_form import ComauArm
    from app.models.registry import load_robot

    robot = load_robot("comau_smart5_3dof")
    lab = MotionLab(load_lab())
    assert abs(ComauArm.match(robot).L - (1.492 + 0.210 + 0.567)) < 1e-12  # Table 7: 2.269 m
    assert abs(lab.comau.L - 2.269) < 1e-12  # what the lab scene computes with
    grid = [np.linspace(a, b, 9) for a, b in zip(lab.joints.lower, lab.joints.upper, strict=True)]
    Q = np.stack(np.meshgrid(*grid, indexing="ij"), -1).reshape(-1, 3)
    p = robot.position(Q)
    np.testing.assert_allclose(p, _lab_eq3(Q, L=2.269), atol=1e-9)
    gap = np.linalg.norm(p - _lab_eq3(Q), axis=1)
    assert gap.max() == pytest.approx(0.0002, abs=1e-9)  # the two L, along the extension arm
    F = robot.frames(np.radians([0.0, 0.0, -90.0]))[:, :3, 3]
    np.testing.assert_allclose(F[2] - F[1], [0, 0, 1.160], atol=1e-12)  # upper arm a2 vertical
    np.testing.assert_allclose(F[4] - F[3], [2.269, 0, 0], atol=1e-12)  # extension arm L horizontal along x
    assert robot.position(np.radians([45.0, 0.0, -90.0]))[1] < 0
