"""Issue 14, items 1–2: the GA's compiled generation loop (app/ik/ga_kernels.py) against the NumPy reference.

Two copies of a robot, one with ``use_kernels`` on and one off, each with a GA seeded alike: the same
targets (or velocity commands) must give the same answers, generations, reasons and populations, to
1e-12.  Both paths draw from their own ``numpy.random.Generator`` in the same order (numba shares the
bit generator), so the streams stay in step for as long as the results agree."""

import ast
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from app.ik import ga_kernels, make_solver
from app.ik.genetic import CROSSOVER_SINGLE_POINT_PROBABILITY, MUTATION_AMPLITUDE, MUTATION_PROBABILITY
from app.models import kernels
from app.models.registry import list_robots, load_robot, load_spec
from app.models.workspace import workspace_box
from app.warmup import warm_up
from tests.test_kernels import random_chain

SERIAL = [n for n in list_robots() if load_spec(n).type == "serial"]
pytestmark = pytest.mark.skipif(not kernels.ENABLED, reason="numba not installed or BOSUN_JIT=0")


def twins(name, seed, **options):
    """(compiled solver, reference solver) on two copies of the robot, seeded alike."""
    compiled, reference = load_robot(name), load_robot(name)
    reference.use_kernels = False
    return (make_solver("ga", r, seed=seed, time_budget=None, **options) for r in (compiled, reference))


def assert_same(a, b):
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.position, b.position, rtol=0, atol=1e-12)
    assert a.iterations == b.iterations and a.reason == b.reason and a.success == b.success
    assert abs(a.cost - b.cost) <= 1e-12 and abs(a.error - b.error) <= 1e-12


@pytest.mark.parametrize("name", SERIAL)
@settings(max_examples=6, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31))
def test_compiled_position_solves_equal_the_reference(name, seed):
    """Cold targets, a target moved a little (the population evolves on), one repeated, and one out of
    reach (penalised genes and the generation cap): the same answers and the same populations."""
    ga, ref = twins(name, seed, max_generations=40)
    robot = ga.robot
    rng = np.random.default_rng(seed)
    X = robot.position(rng.uniform(robot.lower, robot.upper, size=(5, robot.n_joints)))
    box = workspace_box(robot)
    targets = [*X, X[-1] + 0.004 * box.extent, X[-1] + 0.004 * box.extent, box.upper + box.extent]
    for x in targets:
        a, b = ga.solve_position(x), ref.solve_position(x)
        assert_same(a, b)
        np.testing.assert_allclose(ga.population, ref.population, rtol=0, atol=1e-12)
    assert ga.rng.random() == ref.rng.random()  # the streams are still in step


@pytest.mark.parametrize("name", SERIAL)
@settings(max_examples=4, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31))
def test_compiled_velocity_solves_equal_the_reference(name, seed):
    """Velocity mode (local target of eq. 7, genes θ̇ in the speed window, eq. 9 scaling): a drive of
    ticks with random commands from a random pose, q ← result.q, as the engine does."""
    ga, ref = twins(name, seed, max_generations=8)
    robot = ga.robot
    rng = np.random.default_rng(seed)
    k_v = 0.05 * workspace_box(robot).diagonal
    qa = qb = rng.uniform(robot.lower, robot.upper)
    for tick in range(25):
        v = k_v * rng.normal(size=3) if tick % 8 else np.zeros(3)
        dt = 0.002 if tick % 2 else 0.02
        a, b = ga.solve_velocity(qa, v, dt), ref.solve_velocity(qb, v, dt)
        assert_same(a, b)
        np.testing.assert_allclose(a.qdot, b.qdot, rtol=0, atol=1e-12)
        if ga.velocity_elite is not None:
            np.testing.assert_allclose(ga.velocity_elite, ref.velocity_elite, rtol=0, atol=1e-12)
        qa, qb = a.q, b.q
    assert ga.rng.random() == ref.rng.random()


@pytest.mark.parametrize("population", [4, 5, 24, 125])
def test_one_compiled_generation_is_the_reference_generation(population):
    """Steps 5–7 alone, also with odd numbers of children (the last parent passes unchanged) and a
    one-joint chain (no single-point cut): the same next population from the same stream."""
    for n, robot in [
        (1, random_chain(1, 1)),
        (3, load_robot("comau_smart5_3dof")),
        (6, load_robot("comau_smart5_6dof")),
    ]:
        robot.use_kernels = False
        ga = make_solver("ga", robot, seed=n, population=population)
        twin = np.random.default_rng(n)
        for _ in range(5):
            pop = ga.random_q(population)
            twin.uniform(robot.lower, robot.upper, size=pop.shape)  # the twin stream follows
            x = robot.position(ga.random_q())
            twin.uniform(robot.lower, robot.upper)
            cost = ga.cost(pop, x)
            rules = (ga.span, ga.n_elite, CROSSOVER_SINGLE_POINT_PROBABILITY, MUTATION_PROBABILITY, MUTATION_AMPLITUDE)
            compiled = ga_kernels._evolve(pop, cost, rules, twin)
            np.testing.assert_array_equal(compiled, ga.evolve(pop, cost))


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 8))
def test_compiled_costs_equal_the_reference_on_random_chains(seed, n):
    """Couplings, prismatic joints, a rotated base and genes outside the limits (the ×100 penalty): the
    compiled costs equal the reference's (the full solves are compared on the library robots above)."""
    robot = random_chain(seed, n)
    ga = make_solver("ga", robot, seed=seed)
    rng = np.random.default_rng(seed)
    span = robot.upper - robot.lower
    pop = rng.uniform(robot.lower - 0.1 * span, robot.upper + 0.1 * span, size=(125, n))
    x, q_a = robot.position(ga.random_q()), ga.random_q()
    u = rng.normal(size=3)
    u /= np.linalg.norm(u)
    qdot = rng.normal(size=(125, n))
    costs = []
    for flag in (True, False):
        robot.use_kernels = flag
        costs.append((ga.cost(pop, x), ga.velocity_cost(qdot, ga.velocity_target(q_a, 0.01, x, u))))
    for a, b in zip(*costs, strict=True):
        # relative too: the FK paths agree to an ulp of the position, and a short chain's box is a few cm
        # (the normalised cost divides by it) while a penalised cost is 100 × that
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
    assert np.any(costs[0][0] >= 1.0)  # some chromosomes were penalised


def test_no_compiled_function_takes_more_than_8_arguments():
    """Issue 29: the constants and per-call values come in records (tuples, one argument each)."""
    tree = ast.parse(Path(ga_kernels.__file__).read_text(encoding="utf-8"))
    jitted = {
        f.name: len(f.args.args)
        for f in tree.body
        if isinstance(f, ast.FunctionDef) and any(getattr(d, "id", None) == "_jit" for d in f.decorator_list)
    }
    kernels_ = {"_tool_points", "position_costs", "velocity_costs", "_evolve", "evolve_position", "evolve_velocity"}
    assert kernels_ <= set(jitted) and max(jitted.values()) <= 8, jitted


def test_compiled_solve_keeps_the_time_budget():
    """The loop reads the clock only between runs of generations; it still stops near 100 ms."""
    warm_up()  # compiled (or loaded) before the clock starts
    robot = load_robot("kuka_youbot")
    ga = make_solver("ga", robot, seed=0)
    box = workspace_box(robot)
    res = ga.solve_position(box.upper + box.extent)  # out of reach: only the budget ends it
    assert not res.success and res.reason == "time budget spent"
    assert res.iterations > 100 and 0.1 <= res.time_s < 0.2
