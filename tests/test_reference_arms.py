"""Reference arms from their makers' published tables (issue 32, items 2–3): the Franka Panda in the modified DH
convention (Craig), the UR5 in the standard one — their kinematics against robotics-toolbox-python's DH models,
the modified convention against Craig's link transforms, and both driven in teleop by every solver that applies."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.engine.session import Session, library_entries
from app.errors import BosunError
from app.models.registry import build_model, load_robot
from app.models.xml import parse_robot_xml
from app.resources import robot_library
from app.teleop.devices import InputSample

N_CONFIGS = 1000


def _configs(robot, n=N_CONFIGS, seed=32):
    return np.random.default_rng(seed).uniform(robot.lower, robot.upper, (n, robot.n_joints))


def _rtb(name):
    rtb = pytest.importorskip("roboticstoolbox", reason="robotics-toolbox-python (bosun[bench])")
    from spatialmath import SE3

    if name == "franka_panda":
        ref = rtb.models.DH.Panda()
        # Franka's Hand frame is 0.1034 m along the flange's z (FCI docs); the toolbox rounds it to 0.103
        ref.tool = SE3.Tz(0.1034) * SE3.Rz(-math.pi / 4)
        assert all(link.mdh for link in ref.links)  # the toolbox's Panda is a modified-DH model too
    else:
        ref = rtb.models.DH.UR5()
        ref.links[0].d = 0.089159  # UR's published d1 (the toolbox has 0.089459)
    return ref


@pytest.mark.parametrize("name", ["franka_panda", "ur5"])
@pytest.mark.parametrize("kernels", [False, True])
def test_the_reference_arms_are_the_toolbox_s_to_1e12(name, kernels):
    """FK (the tool's pose), the tool point and the geometric Jacobian equal robotics-toolbox-python's DH models
    over 1,000 seeded configurations, compiled and NumPy."""
    ref = _rtb(name)
    robot = load_robot(name)
    robot.use_kernels = kernels
    Q = _configs(robot)
    fk = max(float(np.abs(robot.fk(q) - ref.fkine(q).A).max()) for q in Q)
    pos = float(np.abs(robot.position(Q) - np.array([ref.fkine(q).A[:3, 3] for q in Q])).max())
    jac = max(float(np.abs(robot.jacobian(q) - ref.jacob0(q)).max()) for q in Q[:200])
    assert fk < 1e-12 and pos < 1e-12 and jac < 1e-12, (fk, pos, jac)


def _craig(rows, q):
    """Craig's modified DH product, link by link: ⁱ⁻¹Tᵢ = Rx(α_{i−1}) Tx(a_{i−1}) Rz(θᵢ) Tz(dᵢ)."""
    T = np.eye(4)
    for (a, alpha, d, theta, kind), v in zip(rows, q, strict=True):
        th, dd = (theta + v, d) if kind == "revolute" else (theta, d + v)
        ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(th), math.sin(th)
        Rx = np.array([[1, 0, 0, a], [0, ca, -sa, 0], [0, sa, ca, 0], [0, 0, 0, 1.0]])
        Rz = np.array([[ct, -st, 0, 0], [st, ct, 0, 0], [0, 0, 1, dd], [0, 0, 0, 1.0]])
        T = T @ Rx @ Rz
    return T


def test_a_modified_table_is_craig_s_chain():
    """A random modified table (revolute and prismatic joints, every a, α, d, θ nonzero) read from a robot file is
    Craig's chain of link transforms, its Jacobian the chain's own (finite differences), and its standard table
    is what the file says in the other convention."""
    rng = np.random.default_rng(5)
    rows = []
    for i in range(6):
        kind = "prismatic" if i == 2 else "revolute"
        rows.append((rng.uniform(-0.5, 0.5), rng.uniform(-math.pi, math.pi), rng.uniform(0.05, 0.4),
                     rng.uniform(-1, 1), kind))  # fmt: skip
    links = []
    for i, (a, alpha, d, theta, kind) in enumerate(rows):
        dh = f'a="{a!r}" alpha="{alpha!r}" ' + (f'd="{d!r}"' if kind == "revolute" else f'theta="{theta!r}"')
        off = f'offset="{theta!r}"' if kind == "revolute" else f'offset="{d!r}"'
        lim = 'min="-3" max="3" speed="1"' if kind == "revolute" else 'min="-0.2" max="0.2" speed="1"'
        joint = f'<joint name="j{i}" {off}><limits {lim}/></joint>'
        links.append(f'<link name="{i}" joint="{kind}"><dh {dh}/>{joint}</link>')
    text = _robot("craig", "modified", "".join(links))
    spec = parse_robot_xml(text, "craig.xml")
    assert spec.serial.convention == "modified" and len(spec.serial.written) == 6
    assert spec.serial.written[3].a == rows[3][0] and spec.serial.links[2].a == rows[3][0]  # the next row's a
    robot = build_model(spec)
    for kernels in (False, True):
        robot.use_kernels = kernels
        for q in _configs(robot, 200):
            assert np.abs(robot.fk(q) - _craig(rows, q)).max() < 1e-12
    q, h = _configs(robot, 1)[0], 1e-6
    J = robot.jacobian(q)
    for j in range(6):
        dq = np.zeros(6)
        dq[j] = h
        dp = (_craig(rows, q + dq)[:3, 3] - _craig(rows, q - dq)[:3, 3]) / (2 * h)
        np.testing.assert_allclose(J[:3, j], dp, atol=1e-8)


def _robot(name, convention, links):
    return (
        f'<robot name="{name}" type="serial" angle_unit="rad"><description>{name}</description><source>test</source>'
        f'<serial convention="{convention}">{links}</serial></robot>'
    )


def test_a_bad_convention_is_one_line():
    link = '<link joint="revolute"><dh a="0" alpha="0" d="0"/><joint name="q"><limits min="-1" max="1" speed="1"/>'
    text = _robot("x", "craig", link + "</joint></link>")
    with pytest.raises(BosunError) as info:
        parse_robot_xml(text, "x.xml")
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("x.xml:1") and "convention" in msg, msg


def _sample(x=0.0, enable=True):
    return InputSample((x, 0.0, 0.0), (enable, False), "test stick")


@pytest.mark.parametrize("name", ["franka_panda", "ur5"])
def test_the_reference_arms_are_driven_in_teleop_by_every_solver_that_applies(name):
    """In the engine's teleop session each arm, with each solver the engine offers for it, moves its tool along
    the stick's x in velocity mode once armed, and holds still with the stick centred."""
    entry = next(e for e in library_entries(str(robot_library())) if e.name == name)
    assert set(entry.solvers) >= {"jacobian", "ga"} and "analytic" not in entry.solvers
    dt = 0.002
    for solver in entry.solvers:
        ses = Session(robot_name=name, solver_name=solver, mode="velocity")
        # No clock: a GA's time budget fits fewer generations on a loaded machine (CI once saw 25 mm of sideways
        # drift in 0.5 s when some ticks' budgets ran none), so the GA runs a fixed number of generations a tick,
        # the 10 a 0.8 ms budget fits on an idle machine (app/ik/genetic.py): the same ticks on any machine.
        ses.solver.time_budget = None
        if hasattr(ses.solver, "max_generations"):
            ses.solver.max_generations = 10
        t = 0.0
        for en in (False, True):  # the arming gesture: centred and released, then the deadman pressed
            t += dt
            ses.feed(_sample(enable=en), t)
            ses.tick(t, dt)
        p0 = np.array(ses.snapshot().tool)
        for _ in range(250):  # 0.5 s, full stick along x
            t += dt
            ses.feed(_sample(x=1.0), t)
            ses.tick(t, dt)
        d = np.array(ses.snapshot().tool) - p0
        assert d[0] > 0.02 and abs(d[1]) < 0.2 * d[0] and abs(d[2]) < 0.2 * d[0], (solver, d)
        for _ in range(300):  # centred: the reference stops, then the servo settles on it
            t += dt
            ses.feed(_sample(), t)
            ses.tick(t, dt)
        q = np.array(ses.snapshot().q_ref)
        for _ in range(100):
            t += dt
            ses.feed(_sample(), t)
            ses.tick(t, dt)
        np.testing.assert_array_equal(ses.snapshot().q_ref, q)
