"""Issue 14, item 4: the compiled crane head (app/models/crane_head_kernels.py: kinematics and references;
app/control/tac_kernels.py: the crane servo and the head's PID; app/sim/head_kernels.py: the head's motors;
app/scenes/tac_kernels.py: the head servo and the simulation step) against the NumPy reference methods on the
same seeded random inputs and states (equal to 1e-12), and whole simulations both ways
(equal to 1e-9): every mode, MRU noise, and live mode changes, E-STOP and the crane's return in the
engine's small chunks."""

import math
from pathlib import Path

import numpy as np
import pytest

from app.control.tac import PidGains
from app.models.crane_head import CraneHead
from app.models.delta import DeltaHead
from app.models.registry import load_robot, load_spec
from app.models.xml import parse_robot_xml
from app.scenarios.tac import BETA_EQ60, MODES, TacChunk, TacScenario, TacSimulator, simulate
from app.scenes import tac_kernels
from app.scenes.tac import CraneServo, HeadServo

pytestmark = pytest.mark.skipif(not tac_kernels.ENABLED, reason="numba not installed or BOSUN_JIT=0")
ATOL = 1e-12


def close(a, b, atol: float = ATOL) -> None:
    np.testing.assert_allclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float), rtol=0, atol=atol)


def make_system(compiled: bool) -> CraneHead:
    system = CraneHead(load_robot("offshore_crane"), load_robot("tac_delta_head"))
    system.use_kernels = compiled
    return system


@pytest.fixture(scope="module")
def systems() -> tuple[CraneHead, CraneHead]:
    """(compiled, reference): separate instances, so that the flags never mix."""
    return make_system(True), make_system(False)


def random_motion(rng: np.random.Generator, n: int, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Vessel states η, ν (n, 6): metres and tenths of radians, some far beyond the head's reach."""
    eta = rng.normal(0.0, 1.0, (n, 6)) * np.array([1.0, 1.0, 1.5, 0.08, 0.05, 0.05]) * scale
    nu = rng.normal(0.0, 1.0, (n, 6)) * np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]) * scale
    return eta, nu


# ----------------------------------------------------------------------------- Delta head
def test_delta_ik_and_fk(systems, rng):
    compiled, reference = (s.head for s in systems)
    ws = compiled.workspace(0.25)
    pts = np.vstack(
        [
            ws.points[rng.choice(len(ws.points), 400, replace=False)] + rng.uniform(-0.5, 0.5, (400, 3)),
            rng.uniform(-12.0, 12.0, (200, 3)),  # many unreachable
        ]
    )
    a, b = compiled.ik(pts), reference.ik(pts)
    close(a.alpha, b.alpha)
    assert np.array_equal(a.reachable, b.reachable) and np.array_equal(a.within_limits, b.within_limits)
    assert not a.reachable.all() and a.reachable.mean() > 0.5
    one = compiled.ik(pts[0])
    assert one.alpha.shape == (3,) and one.reachable.shape == (3,)
    close(one.alpha, b.alpha[0])
    alpha = rng.uniform(compiled.lower, compiled.upper, (500, 3))
    close(compiled.fk(alpha), reference.fk(alpha))
    close(compiled.fk(alpha.reshape(5, 100, 3)), reference.fk(alpha).reshape(5, 100, 3))
    close(compiled.fk(alpha[0]), reference.fk(alpha[0]))


ON_AXIS = math.acos(-0.75 / 3.25)  # a − l_a cos α = 0: the knee on the head's axis (Table 4 geometry)


@pytest.mark.parametrize(
    ("rods", "alpha", "match"),
    [
        ("3.95", [0.0, 0.0, 0.0], "the rods cannot meet"),  # knees 4 m off the axis, rods 3.95 m
        ("7.00", [ON_AXIS, ON_AXIS, 0.1], "knee points are collinear"),  # two knees on one another
    ],
)
def test_delta_fk_errors_are_the_same(rods, alpha, match):
    text = Path(load_spec("tac_delta_head").path).read_text(encoding="utf-8").replace('l_r="7.00"', f'l_r="{rods}"')
    heads = [DeltaHead(parse_robot_xml(text, "delta.xml")) for _ in range(2)]
    heads[1].use_kernels = False
    for head in heads:
        with pytest.raises(ValueError, match=match):
            head.fk(np.array([[0.1, 0.1, 0.1], alpha]))


def test_workspace_is_the_same_both_ways():
    heads = [load_robot("tac_delta_head") for _ in range(2)]
    heads[1].use_kernels = False
    a, b = (h.workspace(0.25) for h in heads)
    assert np.array_equal(a.points, b.points)
    assert np.array_equal(a.center, b.center)
    close(a.equations, b.equations)


# ----------------------------------------------------------------------------- crane
def test_crane_ik_tcp_with_the_slew_unwrapped(systems, rng):
    compiled, reference = systems
    p0 = compiled.tcp_n(np.zeros(6), BETA_EQ60, compiled.p_d_t)
    turn = np.linspace(0.0, 4.5 * math.pi, 300)  # the slew crosses ±π twice: unwrapping matters
    r = math.hypot(p0[0] + 20.7, p0[1])
    circle = np.column_stack([-20.7 + r * np.cos(turn), r * np.sin(turn), np.full(turn.size, p0[2])])
    pts = np.vstack([circle, p0 + rng.normal(0.0, 6.0, (300, 3)), p0 + rng.normal(0.0, 40.0, (50, 3))])
    for hint in (-math.pi / 2, 3.0, -9.0):
        close(compiled.crane_ik_tcp(pts, hint), reference.crane_ik_tcp(pts, hint))
    beta0 = compiled.crane_ik_tcp(circle)[:, 0]
    assert np.all(np.abs(np.diff(beta0)) < 0.2) and abs(beta0[-1] - beta0[0]) > 4 * math.pi


def test_crane_servo(systems, rng):
    crane = systems[0].crane
    args = (crane.lower, crane.upper, crane.speed, crane.accel, BETA_EQ60)
    for share, k_p in ((0.3, 1.0), (1.0, 4.0)):
        a = CraneServo(*args, share, k_p)
        b = CraneServo(*args, share, k_p, use_kernels=False)
        for _ in range(3):
            beta_c = BETA_EQ60 + np.cumsum(rng.normal(0.0, 0.02, (500, 3)), axis=0)
            beta_c[::97] += 2.0  # jumps: speed, acceleration and position limits
            rate = rng.normal(0.0, 0.2, (500, 3))
            for x, y in zip(a.run(BETA_EQ60, beta_c, rate, 0.01), b.run(BETA_EQ60, beta_c, rate, 0.01), strict=True):
                close(x, y)
            close(a.beta, b.beta)
            close(a.beta_dot, b.beta_dot)


# ----------------------------------------------------------------------------- references and servo
def test_head_reference(systems, rng):
    compiled, reference = systems
    p_d_n = compiled.tcp_n(np.zeros(6), BETA_EQ60, compiled.p_d_t)
    for scale in (0.5, 1.0, 3.0):  # inside the workspace, partly saturated, mostly saturated
        eta, nu = random_motion(rng, 400, scale)
        beta = BETA_EQ60 + rng.normal(0.0, 0.05, (400, 3))
        beta_dot = rng.normal(0.0, 0.05, (400, 3))
        p_d_dot = rng.normal(0.0, 0.3, (400, 3))
        hold = rng.uniform(-0.5, 0.5, 3)
        a = compiled.head_reference(eta, nu, beta, beta_dot, p_d_n, p_d_dot, alpha_hold=hold)
        b = reference.head_reference(eta, nu, beta, beta_dot, p_d_n, p_d_dot, alpha_hold=hold)
        for name in ("o_t_n", "R_n_t", "p_ref_t", "p_cmd_t", "v_ref_t", "alpha_ref", "alpha_dot_ref"):
            close(getattr(a, name), getattr(b, name), atol=1e-12 * max(1.0, float(np.abs(getattr(b, name)).max())))
        assert np.array_equal(a.saturated, b.saturated)
        if scale > 1:
            assert a.saturated.mean() > 0.3
    one = compiled.head_reference(eta[:1], nu[:1], BETA_EQ60[None], np.zeros((1, 3)), p_d_n)
    close(one.alpha_ref, reference.head_reference(eta[:1], nu[:1], BETA_EQ60[None], np.zeros((1, 3)), p_d_n).alpha_ref)


@pytest.mark.parametrize("limited", [True, False])
def test_head_servo(systems, rng, limited):
    """Both ways alike, with the motors' speed limit (the head file's 90°/s: issue 26, item 4) and without."""
    head = systems[0].head
    speed = head.speed if limited else None
    a = HeadServo(PidGains(), head.lower, head.upper, systems[0].alpha_d, speed)
    b = HeadServo(PidGains(), head.lower, head.upper, systems[0].alpha_d, speed, use_kernels=False)
    for spread in (0.1, 3.0):  # following, then wild references that saturate the input (and the motor speed)
        ref = systems[0].alpha_d + rng.normal(0.0, spread, (1000, 3))
        ref_dot = rng.normal(0.0, 10 * spread, (1000, 3))
        for x, y in zip(a.run(ref, ref_dot, 0.01), b.run(ref, ref_dot, 0.01), strict=True):
            close(x, y)
        for name in ("alpha", "integral", "u"):
            close(getattr(a, name), getattr(b, name))


# ----------------------------------------------------------------------------- whole runs
def assert_same_chunks(a: TacChunk, b: TacChunk, atol: float = 1e-9) -> None:
    for name, _ in TacChunk.FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        if x.dtype == bool:
            assert np.array_equal(x, y), name
        else:
            close(x, y, atol)


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("mru_noise", [0.0, 1.0])
def test_whole_simulation_both_ways(mode, mru_noise):
    # the closed-form vessel: its beam-sea roll saturates the head at Hs 4.5 m within 20 s (the default
    # vessel's does not), so the saturation branches are compared too
    sc = TacScenario(hs=4.5, tp=9.0, duration=20.0, mode=mode, seed=4, mru_noise=mru_noise, rao="supply-closed-form")
    a = simulate(sc, system=make_system(True), use_kernels=True)
    b = simulate(sc, system=make_system(False), use_kernels=False)
    assert_same_chunks(a.data, b.data)
    for key in ("rms_e_c_m", "rms_e_s_m", "max_e_c_m", "saturated_pct"):
        assert a.summary[key] == pytest.approx(b.summary[key], rel=0, abs=1e-9)
    if mode != "off":
        assert a.summary["saturated_pct"] > 0  # Hs 4.5 m: the saturation branches ran too


@pytest.mark.slow
def test_live_changes_in_small_chunks_both_ways():
    """The engine's use: two steps a tick, modes switched live, E-STOP, the crane driving back to eq. (60), and the
    fades of H108 between them (resumed from a pose, released from cooperative and from tac)."""
    sims, fades = [], set()
    for compiled in (True, False):
        sim = TacSimulator(TacScenario(hs=3.0, duration=1e5, mode="cooperative", seed=2), make_system(compiled))
        sim.use_kernels = compiled
        sims.append(sim)
    plan = [("cooperative", False, 400), ("tac", False, 300), ("tac", True, 50), ("off", False, 100)]
    plan += [("cooperative", False, 200), ("cooperative", True, 30), ("cooperative", False, 300)]
    plan += [("off", False, 300), ("tac", False, 300), ("off", False, 300)]
    for mode, frozen, ticks in plan:
        for sim in sims:
            if sim.scenario.mode != mode:
                sim.set_mode(mode)
        away = np.abs(sims[0].crane_servo.beta - BETA_EQ60).max()
        for _ in range(ticks):
            f = sims[0]._fade
            if f is not None:
                fades.add(("release" if f[1] else "resume", mode, bool(f[4])))
            a, b = (sim.advance(2, frozen=frozen) for sim in sims)
            assert_same_chunks(a, b)
        close(sims[0].crane_servo.beta, sims[1].crane_servo.beta, 1e-9)
        close(sims[0].head_servo.alpha, sims[1].head_servo.alpha, 1e-9)
        if mode == "tac" and not frozen:  # the crane drove back towards eq. (60)
            assert np.abs(sims[0].crane_servo.beta - BETA_EQ60).max() < away
    assert fades >= {("resume", "off", False), ("resume", "cooperative", False), ("resume", "tac", False)}
    assert fades >= {("release", "off", True), ("release", "off", False)}, fades


def test_use_kernels_reaches_every_part():
    sim = TacSimulator(TacScenario(duration=1.0), make_system(True))
    sim.use_kernels = False
    parts = (sim.system, sim.system.head, sim.system.crane, sim.head_servo, sim.crane_servo)
    assert not sim.use_kernels and not any(p.use_kernels for p in parts)
    sim.use_kernels = True
    assert all(p.use_kernels for p in parts)
