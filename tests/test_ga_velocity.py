"""Velocity mode drives the tool the commanded way (issue 12, item 7).

A constant velocity command ẋ, k_v = 5 % of the workspace-box diagonal per second (the
engine's default scaling), is integrated for 2 s from the engine's start pose (mid-range
joints) with q ← result.q every tick, as the engine does.  The GA runs with
``time_budget=None`` and two generations per tick (about what fits in the engine's
0.4 × 2 ms budget), so the runs do not depend on the machine's speed.

Directions are ones the joints allow from that pose (checked with the Jacobian solver:
cosine ≥ 0.99).  A crane cannot keep up with 5 % of its diagonal per second, so the travel
is compared with what the joint speed limits allow along the command (a small linear
programme), not with |ẋ|·T alone.
"""

import numpy as np
import pytest
from scipy.optimize import linprog

from app.ik import make_solver, solvers_for
from app.models.registry import load_robot
from app.models.workspace import workspace_box

DURATION = 2.0
DT = 0.01
GA_GENERATIONS = 2

#: robot -> commanded directions feasible from the mid-range pose
DIRECTIONS = {
    "knuckle_boom_crane": [(1, 1, 0), (0, 0, 1)],  # (1, 1, 0): the reported case
    "kuka_youbot": [(1, 1, 0), (0, 0, -1)],  # mid-range is upright: +z is out of reach
    "comau_smart5_3dof": [(1, 1, 0), (0, 0, 1)],
}
CASES = [
    (robot, direction, solver)
    for robot, directions in DIRECTIONS.items()
    for direction in directions
    for solver in solvers_for(load_robot(robot))
]


def _solver(name, robot):
    if name == "ga":
        return make_solver("ga", robot, seed=0, time_budget=None, max_generations=GA_GENERATIONS)
    return make_solver(name, robot, seed=0, time_budget=None)


def _command(robot, direction):
    box = workspace_box(robot)
    u = np.asarray(direction, dtype=float)
    u /= np.linalg.norm(u)
    return u, 0.05 * box.diagonal * u  # app.teleop.mapping.default_scaling: k_v = 5 % of the diagonal per second


def _drive(solver, q, v, dt=DT, duration=DURATION):
    """Integrate q ← result.q for ``duration`` seconds; check eq. (9) and the speed limits each tick."""
    robot = solver.robot
    results = []
    for _ in range(round(duration / dt)):
        res = solver.solve_velocity(q, v, dt)
        np.testing.assert_allclose(res.q, robot.clip(q + res.qdot * dt), atol=1e-12)  # eq. (9)
        assert np.all(np.abs(res.qdot) <= robot.speed * (1 + 1e-9))
        assert np.all(robot.within_limits(res.q))
        results.append(res)
        q = res.q
    return q, results


def _speed_limited_rate(robot, q, u):
    """Fastest tool speed along u at q with every |θ̇_i| ≤ its speed limit [m/s] (LP: max s, J θ̇ = s u)."""
    J = robot.jacobian(q)[:3]
    n = robot.n_joints
    res = linprog(
        c=np.r_[np.zeros(n), -1.0],
        A_eq=np.hstack([J, -u[:, None]]),
        b_eq=np.zeros(3),
        bounds=[(-s, s) for s in robot.speed] + [(0, None)],
    )
    assert res.success
    return float(res.x[-1])


@pytest.mark.parametrize("robot_name, direction, solver_name", CASES)
def test_constant_velocity_command_moves_the_tool_that_way(robot_name, direction, solver_name):
    robot = load_robot(robot_name)
    u, v = _command(robot, direction)
    q0 = 0.5 * (robot.lower + robot.upper)  # the engine's start pose
    q, _ = _drive(_solver(solver_name, robot), q0, v)
    d = robot.position(q) - robot.position(q0)
    length = float(np.linalg.norm(d))
    cosine = float(d @ u) / length if length > 0 else float("nan")
    assert cosine >= 0.95, f"tool moved {np.round(d, 3).tolist()} for a command along {direction}"
    # The speed limits' rate along u depends on the pose (tiny at the youBot's upright start, a
    # singularity): take the larger of the start and end poses' rates.
    rate = max(_speed_limited_rate(robot, q0, u), _speed_limited_rate(robot, q, u))
    possible = min(float(np.linalg.norm(v)), rate) * DURATION
    assert length >= 0.3 * possible, f"moved {length:.3f} m of the {possible:.3f} m the joint speeds allow"


@pytest.mark.parametrize("robot_name", list(DIRECTIONS))
@pytest.mark.parametrize("direction", [(1, 0, 0), (0, 0, 1)])
def test_ga_holds_when_the_command_points_out_of_the_workspace(robot_name, direction):
    """At the workspace boundary along u (a joint or the reach at its limit) the GA must not wander."""
    robot = load_robot(robot_name)
    u, v = _command(robot, direction)
    q_mid = 0.5 * (robot.lower + robot.upper)
    far = robot.position(q_mid) + 10 * workspace_box(robot).diagonal * u
    q_edge = make_solver("jacobian", robot, time_budget=None).solve_position(far, q_mid).q  # closest point to far
    q, results = _drive(_solver("ga", robot), q_edge, v)
    d = robot.position(q) - robot.position(q_edge)
    travel = np.linalg.norm(v) * DURATION
    assert d @ u >= -1e-9 * travel  # never against the command
    assert np.linalg.norm(d) <= 0.02 * travel  # hardly any motion (the boundary point is only nearly extremal)
    assert np.linalg.norm(d - (d @ u) * u) <= 0.005 * travel  # and no sideways drift
    holds = [r for r in results if not np.any(r.qdot)]
    assert holds, "at the boundary some ticks find no motion towards the target"
    for r in holds:
        assert not r.success and "holding" in r.reason


def test_ga_velocity_step_is_never_against_the_command(rng):
    """Any single tick from a random pose: the accepted motion lies in a cone about ẋ (cos ≥ 0.94)."""
    robot = load_robot("comau_smart5_3dof")
    solver = make_solver("ga", robot, seed=4, time_budget=None, max_generations=GA_GENERATIONS)
    k_v = 0.05 * workspace_box(robot).diagonal
    for _ in range(40):
        q = rng.uniform(robot.lower, robot.upper)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        res = solver.solve_velocity(q, k_v * u, 0.002)
        d = res.position - robot.position(q)
        if np.any(res.qdot):
            assert float(d @ u) >= 0.94 * np.linalg.norm(d)
        else:
            np.testing.assert_array_equal(res.q, q)
            assert not res.success


def test_ga_velocity_zero_command_and_spent_budget():
    robot = load_robot("kuka_youbot")
    solver = make_solver("ga", robot, seed=0)
    q0 = 0.5 * (robot.lower + robot.upper)
    still = solver.solve_velocity(q0, [0, 0, 0], 0.002)
    assert still.success and not np.any(still.qdot)
    np.testing.assert_array_equal(still.q, q0)
    # A budget already spent: no generation runs; the answer is still valid (initial population only).
    res = solver.solve_velocity(q0, [0.0, 0.0, -0.08], 0.002, time_budget=1e-9)
    assert res.iterations == 0
    assert np.all(robot.within_limits(res.q)) and np.all(np.abs(res.qdot) <= robot.speed * (1 + 1e-9))
    assert float((res.position - robot.position(q0)) @ [0, 0, -1]) >= -1e-12


def test_position_mode_keeps_the_published_rules():
    """Velocity solves keep their own state; the position mode's population and stop cost are untouched."""
    robot = load_robot("comau_smart5_3dof")
    solver = make_solver("ga", robot, seed=1, time_budget=None, max_generations=50)
    assert solver.target_cost == 0.01 and solver.population_size == 125 and solver.default_time_budget == 0.1
    solver.solve_velocity(0.5 * (robot.lower + robot.upper), [0.3, 0.3, 0.0], 0.01)
    assert solver.population is None and solver.velocity_elite is not None
    solver.reset()
    assert solver.velocity_elite is None
