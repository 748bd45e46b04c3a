"""Motion-Lab: calibration layout, Comau on the moving platform (eqs. 3–6, 54–57), the suspended
load (eqs. 23–30, 58–61), the winch and vessel-to-vessel motion compensation."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from app.errors import RobotXmlError
from app.models.comau import ComauKinematics, tool_on_platform
from app.models.lab import load_lab, parse_lab_xml, quat_to_matrix
from app.models.stewart import StewartPlatform
from app.scenarios.vvmc import VvmcError, VvmcScenario, simulate, summarize
from app.scenes.lab import MotionLab
from app.sim.motionlab import G, Pendulum


@pytest.fixture(scope="module")
def lab() -> MotionLab:
    return MotionLab(load_lab())


# ----------------------------------------------------------------------------- calibration
def test_layout_matches_the_lab_calibration(shared_data):
    """The transforms transcribed into robots/labs/motionlab.xml are the lab's H matrices."""
    calib = json.loads((shared_data / "motionlab_calib.json").read_text(encoding="utf-8"))
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
            return tool_on_platform(lab.comau, T, (eta, ed + edd * t, edd), (q, qd + qdd * t, qdd))

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
    from app.scenes.lab import REMOTE_TOOL_SPEED

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


# ----------------------------------------------------------------------------- the lab HMI's parity (issue 16, item 5)
def _stick(enable: bool):
    from app.teleop.devices import InputSample

    return InputSample((0.0, 0.0, 0.0, 0.0), (enable,), "test stick")


def _armed_lab(**kw):
    """A lab engine with the operator's input armed (stick at neutral, enable released, then held)."""
    from app.engine.lab_session import LabSession

    ses, t = LabSession(**kw), 0.0
    for pressed in (False, True):
        for _ in range(3):
            t += 0.02
            ses.feed(_stick(pressed), t)
            ses.tick(t, 0.02)
    assert ses.snapshot().flags.armed
    return ses, t


def _drive(ses, t: float, seconds: float, jog=None, enable: bool = True, check=None) -> float:
    """Tick with the enable held (fresh input every tick), the jog ``(joint, speed)`` refreshed every tick."""
    for _ in range(round(seconds / 0.02)):
        t += 0.02
        if jog is not None:
            ses.lab_comau_jog(*jog)
        ses.feed(_stick(enable), t)
        ses.tick(t, 0.02)
        if check is not None:
            check(ses.snapshot())
    return t


def test_comau_jog_moves_one_joint_within_the_labs_profile():
    """Item 5: a held jog moves only its joint, at the chosen share of the profile's 30°/s, and runs into the
    lab's limit under its velocity-boundary law (A = 1 rad/s²) without passing it; the other joints stay."""
    ses, t = _armed_lab()
    f = ses.lab.joints
    lo, hi, V = f.lower.copy(), f.upper.copy(), float(f.speed[0])
    q0 = f.x.copy()
    t = _drive(ses, t, 1.0, jog=(2, -0.5))
    snap = ses.snapshot()
    assert snap.comau_jog.joint == 2 and snap.comau_jog.speed == -0.5
    # at the commanded speed (app/plant/simulated.py divides out the REMOTE step's 1 + dt/τ)
    assert snap.comau.qd[1] == pytest.approx(-0.5 * V, rel=1e-6)
    assert snap.comau_jog.qd == pytest.approx(-0.5 * V)
    prev = {"q": f.x.copy()}

    def holds(s):
        q, qd = np.array(s.comau.q), np.array(s.comau.qd)
        assert np.all(q >= lo - 1e-12) and np.all(q <= hi + 1e-12) and np.all(np.abs(qd) <= V * (1 + 1e-12))
        assert _velocity_bound_holds(prev["q"], qd, lo, hi, 1.0, V, 0.01)
        np.testing.assert_allclose(q[[0, 2]], q0[[0, 2]], atol=1e-9)  # only q2 moves
        prev["q"] = q

    t = _drive(ses, t, 6.0, jog=(2, -1.0), check=holds)  # into q2's lower limit (−30°) at full speed
    assert f.x[1] == pytest.approx(lo[1], abs=1e-3) and abs(f.v[1]) < 1e-6


def test_comau_jog_not_refreshed_within_0_3_s_returns_to_zero():
    """Item 5 (regression, safety H62): a jog whose refresh stops (the GUI froze or went away, a lost release)
    halts on its own after 0.3 s like the winch's spring-return slider; releasing the enable halts it at
    once; a zero speed (the button let go) stops it and is never refused."""
    import time

    from app.engine.lab_session import JOG_TIMEOUT

    ses, t = _armed_lab()
    t = _drive(ses, t, 0.5, jog=(1, 0.5))
    assert ses.snapshot().comau.qd[0] > 0.2
    time.sleep(JOG_TIMEOUT + 0.05)  # no refresh for longer than the timeout (engine receive clock)
    t = _drive(ses, t, 0.5)  # fresh stick input, enable held: only the jog is stale
    snap = ses.snapshot()
    assert snap.comau_jog.joint == 0 and "not refreshed" in snap.comau_jog.reason
    assert snap.comau.qd == [0.0, 0.0, 0.0]
    q = list(snap.comau.q)
    t = _drive(ses, t, 1.0)
    assert ses.snapshot().comau.q == q  # it stays stopped
    t = _drive(ses, t, 0.2, jog=(3, 0.5))  # enable released mid-jog: stops at once, input disarmed
    t = _drive(ses, t, 0.3, enable=False)
    snap = ses.snapshot()
    assert snap.comau_jog.joint == 0 and "input not enabled" in snap.comau_jog.reason and snap.comau.qd == [0, 0, 0]
    ses.lab_comau_jog(3, 0.0)  # a release is taken even now
    assert ses.snapshot().comau_jog.reason == ""


def test_comau_jog_is_refused_outside_remote_under_estop_and_unarmed():
    """Item 5: refused (one line, nothing moves) while the E-STOP is latched, in MOTION_COMP (VVMC), SETTLED
    or HOLD, and while the operator's input is not armed; an E-STOP during a jog stops it."""
    from app.engine.lab_session import LabSession
    from app.engine.scene import CommandError

    unarmed = LabSession()
    with pytest.raises(CommandError, match="not armed"):
        unarmed.lab_comau_jog(1, 0.5)
    with pytest.raises(CommandError, match="joint must be 1, 2 or 3"):
        unarmed.lab_comau_jog(0, 0.5)
    ses, t = _armed_lab()
    t = _drive(ses, t, 0.3, jog=(1, 0.5))
    ses.estop("test")
    assert ses.snapshot().comau_jog.joint == 0
    with pytest.raises(CommandError, match="E-STOP is latched"):
        ses.lab_comau_jog(1, 0.5)
    ses.lab_comau_jog(1, 0.0)  # a stop is always taken
    t = _drive(ses, t, 0.5)
    assert ses.snapshot().comau.qd == [0.0, 0.0, 0.0]
    ses.reset()  # the Comau is in HOLD
    with pytest.raises(CommandError, match=r"needs REMOTE \(the Comau is HOLD\)"):
        ses.lab_comau_jog(1, 0.5)
    ses.lab_vvmc(True)
    with pytest.raises(CommandError, match=r"needs REMOTE .*MOTION_COMP with VVMC on"):
        ses.lab_comau_jog(2, 0.5)
    ses.lab_vvmc(False)
    ses.lab_comau_mode("settled")
    with pytest.raises(CommandError, match="SETTLED"):
        ses.lab_comau_jog(2, 0.5)


def test_simulated_platforms_report_the_rexroth_status_word():
    """Item 5: the simulated platforms give the status word the PLC reads from the Rexroth controllers
    (state bits 0–3, status 4–7, op mode 24–31), mapped from the model: SETTLED, TRANSIT while raising,
    NEUTRAL, ENGAGED, the FREEZE states under an E-STOP and while holding after it; WARNING while a target
    is scaled back to the strokes; typed over the wire."""
    from app.engine.lab_session import LabSession
    from app.net.snapshots import snapshot_from_wire, to_wire
    from app.plant.simulated import motion_status
    from app.plc.symbols import decode_status

    ses = LabSession()
    t = _tick(ses, 0.1)

    def motion(k):
        m = ses.snapshot().platforms[k].motion
        assert decode_status(m.word) == {"state": m.state, "status": m.status, "opmode": m.opmode}
        return m.state, m.status, m.opmode

    assert motion(0) == motion(1) == ("SETTLED", "SYSTEM_OK", "NORMAL")
    assert ses.snapshot().platforms[0].motion.word == 0x01000002
    ses.lab_platform("em8000", "neutral")
    t = _tick(ses, 1.0, t)
    assert motion(0)[0] == "TRANSIT" and motion(1)[0] == "SETTLED"
    t = _tick(ses, 15.0, t)
    assert motion(0) == ("NEUTRAL", "SYSTEM_OK", "NORMAL")
    ses.lab_platform("em8000", "engage")  # the lab's default generator (0.2 m heave, 2° roll and pitch)
    t = _tick(ses, 2.0, t)
    assert motion(0)[0] == "ENGAGED"
    ses.estop("test")
    t = _tick(ses, 1.0, t)
    assert motion(0)[0] == "ENGAGED_FREEZE" and motion(1)[0] == "SETTLED"
    ses.reset()
    t = _tick(ses, 1.0, t)
    assert ses.snapshot().platforms[0].status == "holding" and motion(0)[0] == "NEUTRAL_FREEZE"
    back = snapshot_from_wire(to_wire(ses.snapshot()))
    assert back.platforms[0].motion.state == "NEUTRAL_FREEZE" and back.platforms[0].motion.word == 0x01000005
    plat = ses.lab.platforms[1]
    plat.leg_clamped = True  # LEG LIMIT: a target scaled back to the strokes
    assert (motion_status(plat).status, motion_status(plat).word) == ("WARNING", 0x01000042)


def test_the_status_word_bits_are_the_labs(shared_data):
    """The enumerations behind the status word against motionlab_plc.json (skipped without ../shared)."""
    from app.plc.symbols import STEWART_OPMODE, STEWART_STATE, STEWART_STATUS

    ref = json.loads((shared_data / "motionlab_plc.json").read_text(encoding="utf-8"))["stewart"]

    def table(prefix):
        return next(v for k, v in ref.items() if k.startswith(prefix))

    assert table("state_E_StewartState (Rexroth motion status bits 0-3)") == STEWART_STATE
    assert table("status_E_StewartStatus (bits 4-7)") == STEWART_STATUS
    assert table("opmode_E_StewartOpMode (bits 24-31)") == STEWART_OPMODE


def test_machine_lights_and_generator_defaults_of_the_simulated_lab():
    """Item 5: the lab HMI's "Machine and Sensor States" in its order: platforms, Comau and MRUs active while
    the model runs, no laser tracker, "remote" active while remote poses arrive (within the lab remote
    interface's 0.5 s); the sine generator's defaults and ranges are the lab's (motionlab_plc.json), the
    platforms start with them."""
    import time

    from app.engine.lab_session import LabSession

    ses = LabSession()
    lights = {m.name: m.state for m in ses.snapshot().machines}
    assert [m.name for m in ses.snapshot().machines] == [
        "em8000",
        "em1500",
        "comau",
        "mru1",
        "mru2",
        "tracker",
        "remote",
    ]
    assert lights == {**dict.fromkeys(("em8000", "em1500", "comau", "mru1", "mru2"), "active"),
                      "tracker": "absent", "remote": "absent"}  # fmt: skip
    ses.lab_remote_pose("em1500", [0.0] * 6)
    assert {m.name: m.state for m in ses.snapshot().machines}["remote"] == "active"
    time.sleep(0.55)
    assert {m.name: m.state for m in ses.snapshot().machines}["remote"] == "absent"
    from app.marine.sensors import MRU5, TRACKER, MotionSensor

    rng = np.random.default_rng(5)  # the controllers read an MRU on EM8000 and a laser tracker on EM1500
    ses.lab.set_sensors((MotionSensor(MRU5, rng, 0.01), MotionSensor(TRACKER, rng, 0.01)))
    shown = {m.name: m for m in ses.snapshot().machines}
    assert shown["tracker"].state == "active" and "AT960" in shown["tracker"].detail
    assert "MRU H" in shown["mru1"].detail and shown["mru2"].detail == "simulated: EM1500"
    desc = ses.describe()
    for info in desc.platforms:
        g = info.generator
        np.testing.assert_allclose(g.amplitude, [0, 0, 0.2, math.radians(2), math.radians(2), 0], atol=1e-12)
        np.testing.assert_allclose(g.frequency, 0.6283 / (2 * math.pi), rtol=1e-12)
        assert g.phase == [0.0] * 6 and g.frequency_range == [0.01, 1.0, 0.02]
        np.testing.assert_allclose(g.phase_range, np.radians([-180, 180, 10]), atol=1e-12)
    assert desc.comau_jog_timeout == pytest.approx(0.3)
    src = ses.lab.platforms[0].source
    np.testing.assert_allclose(src.amplitude, desc.platforms[0].generator.amplitude, atol=1e-12)


def test_the_generator_defaults_are_the_labs(shared_data):
    """Against motionlab_plc.json itself (skipped without ../shared)."""
    from app.engine.lab_session import LabSession

    ref = json.loads((shared_data / "motionlab_plc.json").read_text(encoding="utf-8"))["stewart"]
    sine = ref["sine_generator_defaults"]
    g = LabSession().describe().platforms[0].generator
    amp = [math.radians(float(v.split()[0])) if isinstance(v, str) else float(v) for v in sine["sineAmplitude"]]
    np.testing.assert_allclose(g.amplitude, amp, atol=1e-12)
    np.testing.assert_allclose(2 * np.pi * np.array(g.frequency), sine["sineOmega_rad_s"], rtol=1e-12)
    np.testing.assert_allclose(g.phase, sine["sinePhase"], atol=1e-12)
    f_lo, f_hi, f_step = sine["hmi_ranges"]["freq_Hz"]
    assert g.frequency_range == [f_lo, f_hi, float(f_step.split()[1])]
    p_lo, p_hi, p_step = sine["hmi_ranges"]["phase_deg"]
    np.testing.assert_allclose(np.degrees(g.phase_range), [p_lo, p_hi, float(p_step.split()[1])], atol=1e-9)


# ------------------------------------------------------------------------ load swing in the engine (issue 16, item 4)
def _swing_lab(swing_deg: float = 4.0, L: float = 2.0):
    """A lab engine with VVMC on (platforms still, the Comau on the work point), then the load given a swing
    (a kick the estimator's model has no cause for, so it is reset as the operator would)."""
    from app.engine.lab_session import LabSession

    ses = LabSession()
    ses.lab_vvmc(True)
    ses.lab.winch.filter.x[0] = L
    t = _tick(ses, 2.0)
    while ses.lab.engagement()[0].any():  # VVMC's engagement (H106) brings the tool onto the work point gently
        t = _tick(ses, 0.5, t)
    t = _tick(ses, 2.0, t)  # the Comau settles on the work point, the load at rest
    ses.load.kick(math.radians(swing_deg), 0.0)  # the load on its wire (app/scenes/lab_load.py)
    ses.lab_antisway("reset")  # the estimator converged on "no swing": told to expect one again (the HMI's Reset)
    return ses, t


def _swing_deg(ses) -> float:
    """The swing's amplitude [deg] (the engine's, from the swing's energy): the angle itself passes through zero
    twice a period, so a sample of it says little (with the load on its elastic wire, the angle at 12 s was 1.75°
    of a 3.1° amplitude)."""
    return math.degrees(ses._swing_amplitude())


def test_antisway_in_the_engine_damps_a_swing_the_estimate_follows_it():
    """Item 4 in the engine (the lab HMI's "Pendel Estimator" tab): with the law off a 4° swing at L = 2 m
    is still > 2° after 10 s; activated, it is below 0.5° within 10 s (the engine's 10 ms steps, the LQR
    designed at 5 ms) with the tool offset within its 0.3 m; the estimate follows the true swing to within
    a few tenths of a degree after its first second and its error stays inside ~4σ of its own covariance."""
    ses, t = _swing_lab()
    t = _tick(ses, 10.0, t)
    snap = ses.snapshot()
    assert snap.swing is not None and not snap.swing.active and _swing_deg(ses) > 2.0
    assert snap.swing.offset == [0.0, 0.0]
    ses, t = _swing_lab()
    ses.lab_antisway("activate")
    worst = {"err": 0.0, "z": 0.0, "off": 0.0}

    def watch(s):
        worst["off"] = max(worst["off"], float(np.abs(s.swing.offset).max()))
        if s.t - t0 < 1.0:  # the estimator starts at "no swing" (σ 2.9°): judged once it has seen a second
            return
        e, sig = np.abs(s.swing.error[:2]), np.array(s.swing.sigma[:2])
        worst["err"] = max(worst["err"], float(np.degrees(e).max()))
        worst["z"] = max(worst["z"], float((e / sig).max()))

    t0 = ses.snapshot().t
    t = _tick(ses, 10.0, t, check=watch)
    snap = ses.snapshot()
    assert snap.swing.active and snap.swing.reason == ""
    assert _swing_deg(ses) < 0.5, _swing_deg(ses)
    assert 0.005 < worst["off"] <= 0.3 and worst["err"] < 0.6 and worst["z"] < 4.0, worst
    assert np.linalg.norm(snap.tool_error_b2) < 0.01  # back on the work point as the swing dies


def test_antisway_is_refused_without_vvmc_dropped_by_estop_and_vvmc_off_reset_needs_rest():
    """Item 4 (safety H63): the law acts only while VVMC holds the work point: refused without it and under
    E-STOP; an E-STOP or VVMC off switches it off with the reason (its offset returns to zero along the
    law, no jump); reset (the estimator) only with the law off and the tool back; deactivate is always
    taken; an unknown action is refused in one line."""
    from app.engine.lab_session import LabSession
    from app.engine.scene import CommandError

    ses = LabSession()
    with pytest.raises(CommandError, match="turn VVMC on first"):
        ses.lab_antisway("activate")
    with pytest.raises(CommandError, match="action must be"):
        ses.lab_antisway("kick")
    ses, t = _swing_lab()
    ses.lab_antisway("activate")
    t = _tick(ses, 0.5, t)
    assert np.abs(ses.snapshot().swing.offset).max() > 1e-3
    with pytest.raises(CommandError, match="deactivate first"):
        ses.lab_antisway("reset")
    ses.lab_vvmc(False)
    t = _tick(ses, 0.1, t)
    snap = ses.snapshot()
    assert not snap.swing.active and snap.swing.reason == "VVMC off"
    with pytest.raises(CommandError, match="deactivate first"):  # the offset is still on its way back
        ses.lab_antisway("reset")
    t = _tick(ses, 10.0, t)
    assert np.abs(ses.snapshot().swing.offset).max() < 1e-3
    ses.lab_antisway("reset")
    assert ses.snapshot().swing.estimate == [0.0, 0.0, 0.0, 0.0]
    ses.lab_vvmc(True)
    ses.lab_antisway("activate")
    ses.lab_vvmc(False)  # off and on again within one tick: the law is off at once, and stays off
    ses.lab_vvmc(True)
    assert not ses.snapshot().swing.active and ses.snapshot().swing.reason == "VVMC off"
    ses.lab_antisway("activate")
    ses.lab_comau_mode("remote")  # the Comau out of MOTION_COMP: off at once too
    assert not ses.snapshot().swing.active and "REMOTE" in ses.snapshot().swing.reason
    ses.lab_vvmc(True)
    ses.lab_antisway("activate")
    ses.estop("test")
    snap = ses.snapshot()
    assert not snap.swing.active and snap.swing.reason == "E-STOP"
    with pytest.raises(CommandError, match="E-STOP is latched"):
        ses.lab_antisway("activate")
    ses.lab_antisway("deactivate")  # always taken


# --------------------------------------------------------------------------- the wave simulator's vessel (issue 17)
def test_the_lab_wave_simulator_takes_a_vessel_by_name_or_table():
    """Issue 17, item 2: the lab engine's wave simulator runs the default vessel (RAOs by boundary elements:
    it sways in a beam sea), another by name (the closed form: no sway) or an uploaded table, from the next
    SIMULATION source on; the description names it."""
    from app.engine.lab_session import LabSession
    from app.engine.scene import CommandError
    from app.marine.vessel import parametric_rao, rao_to_csv

    ses = LabSession()
    assert ses.describe().vessel.startswith("supply: ") and ses.describe().vessels == ["supply", "supply-closed-form"]

    def sway():
        ses.lab_source("em1500", "simulation", hs=2.0, tp=8.0, heading=90.0, seed=1)
        return ses.lab.platforms[1].source.significant[1]

    assert sway() > 0.1
    ses.set_vessel(vessel="supply-closed-form")
    assert ses.describe().vessel.startswith("supply-closed-form: ") and sway() == 0.0
    text = rao_to_csv(parametric_rao(w=np.linspace(0.1, 3.0, 20), headings_deg=np.arange(0, 360, 30)))
    ses.set_vessel(csv=text, label="mine.csv")
    assert ses.describe().vessel == "RAO file mine.csv" and sway() == 0.0
    with pytest.raises(CommandError, match="unknown vessel"):
        ses.set_vessel(vessel="tanker")
