"""The genetic-algorithm mapping of Sanfilippo et al., §III-B, vectorised with numpy.

As published:

1. chromosome = joint values within their limits, one gene per joint;
   cost = Euclidean distance between target and reached position (eq. 5), with the
   target normalised to the workspace (step 2): positions are mapped into the unit
   cube of the robot's workspace box, (x − box_min) / box_extent per axis, so a cost of
   0.01 is 1 % of the workspace in every direction and means the same on a youBot as on
   a 30 m crane; genes outside their limits multiply the cost by 100 (at least +1);
2. 125 individuals, randomly generated for each new target (step 3 sits inside the main
   loop, after the target is acquired), except that
   the 10 % elite of the previous target's population is carried over (step 7: elitism
   "between successive iterations and consecutive target positions"), so continuous
   operator motion starts next to the answer while 90 % fresh individuals keep diversity;
   a target within 5× the stop cost of the previous one is the same target still being
   worked on (the engine's control ticks), and its population simply evolves on;
3. parents by stochastic universal sampling (Baker 1987) on fitness 1/cost (the
   Watchmaker framework's rule for a cost to minimise);
4. crossover: for each pair of parents, 50 % single-point, 50 % uniform;
5. mutation: each gene, with probability 0.5 %, gets a uniform random value within
   ±5 % of its joint range added;
6. elitism: the best 10 % (13 of 125) survive unaltered from generation to generation;
7. stop when the best cost is below 0.01 or the time budget (100 ms) is spent.

The whole population's FK runs as one batch.  Operators are module functions so each
can be tested against its rule.  With a time budget the number of generations depends
on the machine's speed; ``max_generations`` with ``time_budget=None`` makes a run
reproducible from its seed, and so does a recorded run's clock: each solve keeps the decisions
it took from the clock (time up or not, the generations of each batch; :meth:`Solver.take_work`),
and a :class:`~app.ik.base.Replayed` budget gives them back (``bosun replay``).

Compiled loop (issue 14).  Steps 5–8 (selection, crossover, mutation, elitism, cost, stop)
run as numba kernels, :mod:`app.ik.ga_kernels`, unless ``robot.use_kernels`` is False; then
the NumPy operators here run, and they are the reference: both paths draw from ``self.rng``
in the same order and give equal results (``tests/test_ga_kernels.py``).  A kernel cannot
read the clock, so the loop runs in batches of generations with the time budget checked
between them (:meth:`GeneticSolver._batch`: half of what still fits, so the budget is
overrun by about one generation, as with a check before every generation).

Velocity mapping (eqs. 4, 7, 9).  The paper solves the velocity mode as a position:
x_t = x_a + ẋ_ds Δt (eq. 7), then θ̇_d = (θ_f − θ_a)/Δt (eq. 9).  One control tick's step
|ẋ_ds Δt| is millimetres (e.g. 3.7 m/s × 2 ms on a 75 m-diagonal crane), far below the
position mode's stop cost (1 % of the workspace box, 0.46 m on that crane), so run with
the position rules the start pose already "converges" and whatever a random population
drifts to is sent to the joints: the tool moved against the command (issue 12, item 7).
:meth:`GeneticSolver.solve_velocity` therefore makes x_t a local target that the GA must
actually reach, with the same operators (SUS, hybrid crossover, mutation, elitism):

* genes are joint velocities θ̇, i.e. chromosomes θ_f = θ_a + θ̇ Δt, inside a window
  around θ_a: |θ̇| ≤ 8 × the joint speed limit, and θ_f within the joint limits.  An
  answer faster than the speed limits is scaled down as a whole by eq. (9) afterwards (the
  base class's rule), which keeps the direction of the tool motion; the ×8 lets the GA
  find the exact local solution even when the limits will slow it (the cranes);
* cost = distance to x_t in metres (eq. 5 about the target of eq. 7, not normalised to the
  box), measured in the norm c(e) = |e_∥| + 3 |e_⊥|, e = x(θ_f) − x_t split along and
  across the command (:meth:`GeneticSolver.command_distance`; c ≥ |e|, equal along the
  command).  Stop when the best cost is below 10 % of the step |ẋ_ds Δt|
  (``velocity_tolerance``), when one more generation would overrun the time budget, or at
  the generation limit;
* population: θ̇ = 0 (θ_a, "no motion", so the GA only improves from there), the 10 %
  elite of the previous tick's population as joint velocities re-applied at the new θ_a
  (elitism between consecutive targets, step 7: a steady command needs nearly the same θ̇
  again, so the search goes on across ticks), and fresh individuals
  θ̇ = U(−1, 1) · 8 · speed · 2^−k, k uniform in 0..9, so some are on the scale of any step
  from 8 × the speed limit down to 1/64 of it (a single scale cannot resolve a 0.2 rad/s
  answer inside a 15 rad/s window in two generations); mutation amplitude is ±5 % of the
  one-tick speed window (2 × speed), not of the joint range;
* the answer moves the robot only if it is closer to x_t than x_a is: c(x_f − x_t) <
  c(x_a − x_t) = |ẋ_ds Δt|, evaluated after the eq. (9) speed scaling.  That implies the
  Euclidean "closer than x_a" and keeps every accepted tick's displacement inside a cone
  of cos ≥ 1/√(1 + 1/9) ≈ 0.95 about the command, so the tool cannot wander sideways at a
  singularity or against a joint limit.  Otherwise θ_a is returned with θ̇ = 0,
  ``success=False`` and a reason ending in "holding".  (With the plain Euclidean cost
  the GA settled on sideways moves: ~3 cm of drift over 2 s pushing a youBot upwards from
  its upright mid-range pose, and stalls pulling it down from there, where a pure
  vertical motion is second order.)

Measured per generation (125 individuals, 3–6 joints): 21–36 µs compiled (0.25–0.4 ms with
NumPy), plus about 0.2 ms per call for the first population and the answer, so at 500 Hz
(0.8 ms budget) a tick runs up to 10–20 generations (0–2 with NumPy); the carried elite
makes that enough for a steady command.

``success`` of a velocity solve means the returned position's cost is below the 10 %
tolerance; a step slowed by the speed limits moves (in the commanded direction) but reports
``success=False``.  The position mode keeps the published rules above unchanged, and the
two modes keep separate populations.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from typing import Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.ik import ga_kernels
from app.ik.base import DEFAULT, IKResult, SearchOutcome, Solver, SolverOptions

POPULATION = 125
ELITE_FRACTION = 0.10
CROSSOVER_SINGLE_POINT_PROBABILITY = 0.5
MUTATION_PROBABILITY = 0.005
MUTATION_AMPLITUDE = 0.05
TARGET_COST = 0.01
PENALTY_FACTOR = 100.0
#: generations allowed when neither a time budget nor max_generations bounds a call
HARD_GENERATION_CAP = 20_000

# Velocity mapping (see the module docstring)
#: stop cost of a velocity solve, as a fraction of the step |ẋ Δt| [m/m]
VELOCITY_TOLERANCE = 0.10
#: genes θ̇ may ask for up to this many times the joint speed limit (eq. 9 scales the answer down)
VELOCITY_WINDOW = 8.0
#: fresh individuals are spread over this many halvings of the window (8·speed down to speed/64)
VELOCITY_SCALES = 10
#: weight of the error across the commanded direction, in the velocity cost and its accept-the-motion test
CROSS_TRACK_WEIGHT = 3.0
#: generations per velocity solve when neither a time budget nor max_generations bounds it
VELOCITY_GENERATION_CAP = 100

# The re-seeding extension (RestartGeneticSolver, issue 32, item 4): not in the paper
#: a position search whose best cost has not fallen by STALL_IMPROVEMENT in this many generations starts afresh
STALL_GENERATIONS = 25
STALL_IMPROVEMENT = 0.01


def stochastic_universal_sampling(fitness: NDArray[np.float64], n: int, rng: np.random.Generator) -> NDArray[np.intp]:
    """Indices of n individuals chosen by SUS (Baker 1987).

    n equally spaced pointers, one random offset in [0, F/n) with F the total fitness;
    individual i is chosen once for each pointer inside its slice of the cumulative
    fitness, so it gets floor or ceil of n·f_i/F copies.
    """
    fitness = np.asarray(fitness, dtype=float)
    if np.any(fitness < 0) or not np.all(np.isfinite(fitness)):
        raise ValueError("fitness must be finite and non-negative")
    cumulative = np.cumsum(fitness)
    total = cumulative[-1]  # the sum in the cumulative order (the compiled path's, not numpy's pairwise sum)
    if total <= 0:
        return rng.integers(0, fitness.size, size=n)
    step = total / n
    pointers = rng.uniform(0.0, step) + step * np.arange(n)
    idx = np.searchsorted(cumulative, pointers, side="right")
    return np.minimum(idx, fitness.size - 1)


def single_point_crossover(
    a: NDArray[np.float64], b: NDArray[np.float64], rng: np.random.Generator
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Row-wise single-point crossover: children swap all genes after a random cut 1..n−1."""
    m, n = a.shape
    if n < 2:
        return a.copy(), b.copy()
    cut = rng.integers(1, n, size=(m, 1))
    tail = np.arange(n)[None, :] >= cut
    return np.where(tail, b, a), np.where(tail, a, b)


def uniform_crossover(
    a: NDArray[np.float64], b: NDArray[np.float64], rng: np.random.Generator
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Row-wise uniform crossover: every gene is swapped between the children with probability ½."""
    swap = rng.random(a.shape) < 0.5
    return np.where(swap, b, a), np.where(swap, a, b)


def hybrid_crossover(parents: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
    """Pairs consecutive parents (0–1, 2–3, …); each pair is crossed single-point or uniform, 50/50.

    An odd last parent passes unchanged.
    """
    m = parents.shape[0] - parents.shape[0] % 2
    a, b = parents[0:m:2], parents[1:m:2]
    use_single = rng.random(a.shape[0]) < CROSSOVER_SINGLE_POINT_PROBABILITY
    s1, s2 = single_point_crossover(a, b, rng)
    u1, u2 = uniform_crossover(a, b, rng)
    c1 = np.where(use_single[:, None], s1, u1)
    c2 = np.where(use_single[:, None], s2, u2)
    children = np.empty_like(parents)
    children[0:m:2], children[1:m:2] = c1, c2
    if m < parents.shape[0]:
        children[-1] = parents[-1]
    return children


def mutate(
    genes: NDArray[np.float64],
    span: NDArray[np.float64],
    rng: np.random.Generator,
    probability: float = MUTATION_PROBABILITY,
    amplitude: float = MUTATION_AMPLITUDE,
) -> NDArray[np.float64]:
    """Each gene, with ``probability``, gets U(−amplitude, +amplitude)·span added (span = joint range)."""
    hit = rng.random(genes.shape) < probability
    delta = rng.uniform(-amplitude, amplitude, size=genes.shape) * span
    return np.where(hit, genes + delta, genes)


@dataclass(frozen=True)
class GaTask:
    """A task's weighting of the GA's position cost (issue 32, item 4; the universal-architecture paper's future
    work: "heavier weighing of selected tasks that require higher accuracy").  The cost of eq. (5) on the
    normalised workspace becomes

        c = √(w_x ê_x² + w_y ê_y² + w_z ê_z²) + w_a (1 − z_tool · a) / 2

    — per-axis weights w on the normalised error ê (an axis weighted 4 must be met twice as closely for the same
    stop cost), and an optional tool-axis term: 0 when the tool's z points along the unit ``axis`` a, w_a when it
    points against it.  The default, weights (1, 1, 1) and no axis term, is the published cost, bit for bit.  The
    task shapes the position mapping (and the studies that use it); the velocity mapping's cost is its own."""

    weights: tuple[float, float, float] = (1.0, 1.0, 1.0)
    axis: tuple[float, float, float] | None = None
    axis_weight: float = 0.0

    def __post_init__(self) -> None:
        w = tuple(float(v) for v in self.weights)
        if len(w) != 3 or not all(math.isfinite(v) and 0.0 <= v <= 100.0 for v in w) or max(w) <= 0.0:
            raise ValueError(f"GA task weights must be 3 numbers in [0, 100], not all 0; got {list(self.weights)}")
        object.__setattr__(self, "weights", w)
        wa = float(self.axis_weight)
        if not (math.isfinite(wa) and 0.0 <= wa <= 100.0):
            raise ValueError(f"GA task tool-axis weight must be in [0, 100], got {self.axis_weight}")
        object.__setattr__(self, "axis_weight", wa)
        if self.axis is None:
            if wa > 0.0:
                raise ValueError("GA task: a tool-axis weight needs the axis (3 numbers)")
            return
        a = np.asarray(self.axis, dtype=float)
        norm = float(np.linalg.norm(a)) if a.shape == (3,) else math.nan
        if not (math.isfinite(norm) and norm > 1e-9):
            raise ValueError(f"GA task tool axis must be 3 finite numbers, not all 0; got {list(self.axis)}")
        object.__setattr__(self, "axis", tuple(float(v) for v in a / norm))

    @property
    def published(self) -> bool:
        return self.weights == (1.0, 1.0, 1.0) and self.axis_weight == 0.0

    def to_dict(self) -> dict:
        return {"weights": list(self.weights), "axis": None if self.axis is None else list(self.axis),
                "axis_weight": self.axis_weight}  # fmt: skip


def elite_count(population: int, fraction: float = ELITE_FRACTION) -> int:
    """Number of elites: fraction of the population, rounded half up, at least 1 (13 of 125)."""
    return max(1, math.floor(fraction * population + 0.5))


class GeneticSolver(Solver):
    """GA position mapping as published; GA velocity mapping on a local target (eqs. 4, 7, 9; module docstring).

    Parameters
    ----------
    robot : SerialRobot
    time_budget : float or None
        Stop after this long [s]; default 0.1 (the paper's 100 ms).
    target_cost : float
        Stop when the best normalised cost is below this; default 0.01.
    population : int
        Number of individuals; default 125.
    max_generations : int or None
        Optional cap on generations per call (for reproducible runs).
    velocity_tolerance : float
        Stop cost of a velocity solve as a fraction of the step |ẋ Δt|; default 0.1.
    rng : numpy.random.Generator
    """

    name = "ga"

    def __init__(
        self,
        robot,
        *,
        target_cost: float = TARGET_COST,
        population: int = POPULATION,
        max_generations: int | None = None,
        velocity_tolerance: float = VELOCITY_TOLERANCE,
        task: GaTask | None = None,
        **common: Unpack[SolverOptions],
    ) -> None:
        super().__init__(robot, **common)
        if population < 4:
            raise ValueError("population must be at least 4")
        self.target_cost = target_cost
        self.population_size = population
        self.n_elite = elite_count(population)
        self.max_generations = max_generations
        self.span = robot.upper - robot.lower
        # C-contiguous float64 copies for the compiled loop (app/ik/ga_kernels.py): one numba specialisation
        self._lower, self._upper = np.array(robot.lower, dtype=float), np.array(robot.upper, dtype=float)
        self._box_lower = np.array(self.box.lower, dtype=float)
        self._box_extent = np.array(self.box.extent, dtype=float)
        # ... and the kernels' records (module docstring of ga_kernels), made once: the robot's limits and speeds
        # are fixed once it is loaded (the chain record is the robot's own kernel_record)
        self.task = task or GaTask()
        t = self.task
        axis = np.zeros(3) if t.axis is None else np.array(t.axis, dtype=float)
        self._weights, self._axis = np.array(t.weights, dtype=float), axis
        self._limits = (self._lower, self._upper, self._box_lower, self._box_extent, PENALTY_FACTOR,
                        self._weights, float(t.axis_weight), axis)  # fmt: skip
        operators = (self.n_elite, CROSSOVER_SINGLE_POINT_PROBABILITY, MUTATION_PROBABILITY, MUTATION_AMPLITUDE)
        self._position_rules = (self.span, *operators)
        self._velocity_rules = (np.ascontiguousarray(2.0 * robot.speed, dtype=float), *operators)
        if not 0.0 < velocity_tolerance < 1.0:
            raise ValueError("velocity_tolerance must be between 0 and 1 (a fraction of the step)")
        self.velocity_tolerance = velocity_tolerance
        self.population: NDArray[np.float64] | None = None
        self._last_target: NDArray[np.float64] | None = None
        #: the published GA never re-seeds (None); :class:`RestartGeneticSolver` does after this many generations
        self.stall_generations: int | None = None
        #: elite of the last velocity solve, as joint velocities θ̇ [rad/s, m/s], best first
        self.velocity_elite: NDArray[np.float64] | None = None

    def reset(self) -> None:
        self.population = None
        self._last_target = None
        self.velocity_elite = None

    @property
    def compiled(self) -> bool:
        """Whether the generation loop runs compiled (:mod:`app.ik.ga_kernels`): the robot's ``use_kernels``."""
        return bool(getattr(self.robot, "use_kernels", False))

    # ---------------------------------------------------------------- cost
    def cost(self, genes: NDArray[np.float64], x_t: NDArray[np.float64]) -> NDArray[np.float64]:
        """Normalised distance |x̂_t − x̂_a| (eq. 5 on normalised positions), penalised outside limits."""
        if self.compiled and np.ndim(genes) == 2:
            return ga_kernels.position_costs(
                self.robot.kernel_record, np.ascontiguousarray(genes, dtype=float),
                np.ascontiguousarray(x_t, dtype=float), self._limits,
            )  # fmt: skip
        reached = self.box.normalise(self.robot.position(genes))
        e = reached - self.box.normalise(x_t)
        if self.task.published:
            d = np.linalg.norm(e, axis=-1)
        else:  # the task's weights and tool-axis term (GaTask)
            d = np.sqrt(self._weights[0] * e[..., 0] ** 2 + self._weights[1] * e[..., 1] ** 2
                        + self._weights[2] * e[..., 2] ** 2)  # fmt: skip
            if self.task.axis_weight > 0.0:
                z = self.robot.fk(genes)[..., :3, 2]
                d = d + self.task.axis_weight * 0.5 * (1.0 - z @ self._axis)
        outside = np.any((genes < self.robot.lower) | (genes > self.robot.upper), axis=-1)
        return np.where(outside, np.maximum(d * PENALTY_FACTOR, d + 1.0), d)

    # ---------------------------------------------------------------- evolution
    def evolve(
        self, pop: NDArray[np.float64], cost: NDArray[np.float64], span: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """One generation: elites unaltered, the rest by SUS, hybrid crossover and mutation.

        ``span`` is the range the mutation amplitude refers to: the joint ranges (default) or,
        for a velocity solve, the one-tick speed window 2 × speed (genes are θ̇ there).
        """
        order = np.argsort(cost, kind="stable")
        elites = pop[order[: self.n_elite]]
        fitness = 1.0 / np.maximum(cost, 1e-12)
        n_children = self.population_size - self.n_elite
        parents = pop[stochastic_universal_sampling(fitness, n_children, self.rng)]
        parents = parents[self.rng.permutation(n_children)]  # SUS output is ordered; pair at random
        children = mutate(hybrid_crossover(parents, self.rng), self.span if span is None else span, self.rng)
        return np.vstack([elites, children])

    def initial_population(self, x_t: NDArray[np.float64]) -> NDArray[np.float64]:
        """A fresh random population, with the previous call's elite (ranked for x_t) carried over."""
        if self.population is not None and self._last_target is not None:
            moved = np.linalg.norm(self.box.normalise(x_t) - self.box.normalise(self._last_target))
            if moved < 5 * self.target_cost:
                return self.population
        fresh = self.random_q(self.population_size)
        if self.population is None:
            return fresh
        kept = self.population[np.argsort(self.cost(self.population, x_t), kind="stable")[: self.n_elite]]
        fresh[: self.n_elite] = kept
        return fresh

    @staticmethod
    def _batch(now: float, deadline: float, per_generation: float, left: int | None) -> int:
        """Generations for the next run of the loop, which reads the clock only between runs.

        Half of those that still fit before the deadline at the measured time per generation (at
        least one), so a generation slower than measured overruns the budget by about one generation
        at most, as a check before every generation would; at most ``left`` (the generation cap).
        """
        fit = (deadline - now) / max(per_generation, 1e-9)
        if math.isinf(fit):  # no time budget: the generation cap bounds the run
            return left
        k = max(1, int(fit) // 2)
        return k if left is None else min(k, left)

    def _evolve_position(
        self, pop: NDArray[np.float64], cost: NDArray[np.float64], x_t: NDArray[np.float64], generations: int
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
        """Up to ``generations`` generations (steps 5–7), stopping at the target cost (step 8):
        (population, cost, generations run); compiled unless ``robot.use_kernels`` is False."""
        if self.compiled:
            pop, cost = np.ascontiguousarray(pop, dtype=float), np.ascontiguousarray(cost, dtype=float)
            return ga_kernels.evolve_position(
                self.robot.kernel_record, pop, cost, np.ascontiguousarray(x_t, dtype=float), self._limits,
                self._position_rules, (float(self.target_cost), generations), self.rng,
            )  # fmt: skip
        ran = 0
        while ran < generations and cost.min() >= self.target_cost:
            pop = self.evolve(pop, cost)
            cost = self.cost(pop, x_t)
            ran += 1
        return pop, cost, ran

    def _search(self, x_t, q0, deadline) -> SearchOutcome:
        start = time.perf_counter()
        pop = self.initial_population(x_t)
        self._last_target = np.array(x_t)
        cost = self.cost(pop, x_t)
        generations = 0
        reason = "time budget spent"
        cap = self.max_generations
        if cap is None and math.isinf(deadline) and self._tape is None:  # (a replayed budget ends as recorded)
            cap = HARD_GENERATION_CAP
        # A generation costs at least one population evaluation: the first estimate of its time.
        per_generation = time.perf_counter() - start
        stall = self.stall_generations
        best, since, restarts = float(cost.min()), 0, 0
        kept: tuple[NDArray[np.float64], float] | None = None  # the best individual of the populations re-seeded
        while True:
            if cost.min() < self.target_cost:
                reason = "converged"
                break
            now = time.perf_counter()
            if self._expired(deadline):
                break
            if cap is not None and generations >= cap:
                reason = "generation limit"
                break
            left = None if cap is None else cap - generations
            k = self._decide(functools.partial(self._batch, now, deadline, per_generation, left))
            if k <= 0:  # a replayed budget spent
                break
            pop, cost, ran = self._evolve_position(pop, cost, x_t, k if stall is None else min(k, stall))
            generations += ran
            per_generation = (time.perf_counter() - now) / ran
            if stall is not None:  # the re-seeding extension (RestartGeneticSolver): not the published GA
                if cost.min() < best * (1.0 - STALL_IMPROVEMENT):
                    best, since = float(cost.min()), 0
                else:
                    since += ran
                if since >= stall and cost.min() >= self.target_cost:
                    i = int(np.argmin(cost))
                    if kept is None or cost[i] < kept[1]:
                        kept = (pop[i].copy(), float(cost[i]))
                    pop, cost = self._reseed(pop, cost, x_t)
                    best, since, restarts = float(cost.min()), 0, restarts + 1
        if kept is not None and kept[1] < cost.min():  # the best before a re-seeding: the answer never got worse
            worst = int(np.argmax(cost))
            pop, cost = pop.copy(), cost.copy()
            pop[worst], cost[worst] = kept
        self.population = pop
        # The fittest chromosome within limits (the penalty keeps violators behind feasible ones).
        feasible = np.all((pop >= self.robot.lower) & (pop <= self.robot.upper), axis=1)
        ranked = np.where(feasible, cost, np.inf)
        best = int(np.argmin(ranked)) if feasible.any() else int(np.argmin(cost))
        best_cost = float(cost[best])
        return SearchOutcome(
            q=self.robot.clip(pop[best]),
            iterations=generations,
            converged=reason == "converged" and feasible[best],
            reason=(reason if feasible[best] else "no chromosome within limits; clipped")
            + (f" after {restarts} re-seeding{'s' if restarts > 1 else ''}" if restarts else ""),
            cost=best_cost,
        )

    def _reseed(
        self, pop: NDArray[np.float64], cost: NDArray[np.float64], x_t: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """A stalled population (:class:`RestartGeneticSolver`) replaced by a fresh random one (step 3 again).  It
        keeps none of the old: the stalled best would draw the new population back to where it stuck (kept, one
        Comau target in 120 never left 1.02 % in 57 re-seedings); the search remembers it instead (``_search``)."""
        fresh = self.random_q(self.population_size)
        return fresh, self.cost(fresh, x_t)

    # ---------------------------------------------------------------- velocity mapping
    def velocity_window(self, q_a: NDArray[np.float64], dt: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Bounds of the genes θ̇ at θ_a: ±VELOCITY_WINDOW × speed, and θ_a + θ̇Δt within the joint limits."""
        reach = VELOCITY_WINDOW * self.robot.speed
        lo = np.minimum(np.maximum((self.robot.lower - q_a) / dt, -reach), 0.0)
        hi = np.maximum(np.minimum((self.robot.upper - q_a) / dt, reach), 0.0)
        return lo, hi

    def fresh_velocities(self, n: int, lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.float64]:
        """n random θ̇ = U(−1, 1) · VELOCITY_WINDOW · speed · 2^−k, k uniform in 0..VELOCITY_SCALES−1, clipped."""
        u = self.rng.uniform(-1.0, 1.0, size=(n, self.robot.n_joints))
        k = self.rng.integers(0, VELOCITY_SCALES, size=(n, 1))
        return np.clip(u * 0.5**k * (VELOCITY_WINDOW * self.robot.speed), lo, hi)

    def velocity_population(self, lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.float64]:
        """θ̇ = 0 first, then the previous tick's elite (clipped into this window), then fresh individuals."""
        pop = self.fresh_velocities(self.population_size, lo, hi)
        pop[0] = 0.0  # θ_f = θ_a: the GA starts at "no motion"
        if self.velocity_elite is not None:
            kept = np.clip(self.velocity_elite[: self.n_elite], lo, hi)
            pop[1 : 1 + len(kept)] = kept
        return pop

    @staticmethod
    def command_distance(e: NDArray[np.float64], u: NDArray[np.float64]) -> NDArray[np.float64]:
        """|e·u| + CROSS_TRACK_WEIGHT |e − (e·u)u| [m] for errors e = x − x_t (..., 3) and the unit command u.

        A norm: the distance to x_t with the error across the commanded direction counted
        CROSS_TRACK_WEIGHT times; never less than the Euclidean distance |e|.
        """
        along = e[..., 0] * u[0] + e[..., 1] * u[1] + e[..., 2] * u[2]  # e·u, summed in the compiled path's order
        return np.abs(along) + CROSS_TRACK_WEIGHT * np.linalg.norm(e - along[..., None] * u, axis=-1)

    @staticmethod
    def velocity_target(q_a: NDArray[np.float64], dt: float, x_t: NDArray[np.float64], u: NDArray[np.float64]) -> tuple:
        """A velocity solve's local target as the record of :mod:`app.ik.ga_kernels` (θ_a, Δt, x_t, u, w):
        the tick's start θ_a, the tick Δt, the local target x_t (eq. 7), the unit command u and the
        cross-track weight w of :meth:`command_distance`; made once per solve."""
        q_a, x_t, u = (np.ascontiguousarray(v, dtype=float) for v in (q_a, x_t, u))
        return (q_a, float(dt), x_t, u, CROSS_TRACK_WEIGHT)

    def velocity_cost(self, qdot: NDArray[np.float64], target: tuple) -> NDArray[np.float64]:
        """Cost of joint velocities: the distance from x(θ_a + θ̇Δt) to the local target x_t (eqs. 5, 7) [m];
        ``target`` from :meth:`velocity_target`."""
        if self.compiled and np.ndim(qdot) == 2:
            return ga_kernels.velocity_costs(self.robot.kernel_record, np.ascontiguousarray(qdot, dtype=float), target)
        q_a, dt, x_t, u, _ = target
        return self.command_distance(self.robot.position(q_a + qdot * dt) - x_t, u)

    def _evolve_velocity(
        self, pop: NDArray[np.float64], cost: NDArray[np.float64], target: tuple, window: tuple, stop: tuple
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
        """Up to ``generations`` generations on joint velocities inside the ``window`` (lo, hi), mutation
        amplitude on the one-tick speed window 2 × speed, stopping below ``tolerance`` (``stop`` = (tolerance,
        generations)): (population, cost, generations run); compiled unless ``robot.use_kernels`` is False."""
        if self.compiled:
            pop, cost = np.ascontiguousarray(pop, dtype=float), np.ascontiguousarray(cost, dtype=float)
            return ga_kernels.evolve_velocity(
                self.robot.kernel_record, pop, cost, target, window, self._velocity_rules, stop, self.rng
            )
        (lo, hi), (tolerance, generations) = window, stop
        mutation_span = 2.0 * self.robot.speed  # the one-tick speed window, in θ̇ units
        ran = 0
        while ran < generations and cost.min() >= tolerance:
            pop = np.clip(self.evolve(pop, cost, mutation_span), lo, hi)
            cost = self.velocity_cost(pop, target)
            ran += 1
        return pop, cost, ran

    def solve_velocity(
        self, q_a: ArrayLike, xdot: ArrayLike, dt: float, *, time_budget: float | object | None = DEFAULT
    ) -> IKResult:
        """Velocity mapping θ̇_d = f_v⁻¹(θ_a, ẋ_ds, Δt), eq. (4), by a GA on a local target.

        See the module docstring: x_t = x_a + ẋ_ds Δt (eq. 7) must be reached to 10 % of the
        step by joint velocities searched in a window around θ_a; θ̇_d = (θ_f − θ_a)/Δt
        (eq. 9), scaled down as a whole to the speed limits; no motion unless the answer is
        closer to x_t than x_a.  ``cost`` is :meth:`command_distance` of the returned q [m],
        and ``success`` means cost < ``velocity_tolerance`` × |ẋ_ds Δt|.
        """
        start = time.perf_counter()
        q_a, v = self.check_velocity_request(q_a, xdot, dt)
        deadline = self._deadline(time_budget)
        step_vec = v * dt
        step = float(np.linalg.norm(step_vec))
        if step == 0.0:
            x_a = self.robot.position(q_a)
            return self._velocity_result(q_a, np.zeros_like(q_a), x_a, x_a, True, 0, "no motion commanded", 0.0, start)
        u = step_vec / step
        tol = self.velocity_tolerance * step
        lo, hi = self.velocity_window(q_a, dt)
        pop = self.velocity_population(lo, hi)
        x_a = self.robot.position(q_a)
        x_t = x_a + step_vec  # Sanfilippo et al. eq. (7): the local target of this tick
        target = self.velocity_target(q_a, dt, x_t, u)
        cost = self.velocity_cost(pop, target)  # eq. (5) about x_t, metres
        cap = self.max_generations
        if cap is None and math.isinf(deadline) and self._tape is None:  # (a replayed budget ends as recorded)
            cap = VELOCITY_GENERATION_CAP
        # A generation costs at least one population evaluation: the first estimate of its time.
        generations, reason, per_generation = 0, "time budget spent", time.perf_counter() - start
        while True:
            if cost.min() < tol:
                reason = "converged"
                break
            now = time.perf_counter()
            if self._expired(deadline - per_generation):  # do not start a generation that would overrun the budget
                break
            if cap is not None and generations >= cap:
                reason = "generation limit"
                break
            left = None if cap is None else cap - generations
            k = self._decide(functools.partial(self._batch, now, deadline, per_generation, left))
            if k <= 0:  # a replayed budget spent
                break
            pop, cost, ran = self._evolve_velocity(pop, cost, target, (lo, hi), (float(tol), k))
            generations += ran
            per_generation = (time.perf_counter() - now) / ran
        order = np.argsort(cost, kind="stable")
        self.velocity_elite = pop[order[: self.n_elite]].copy()
        best = pop[order[0]]

        qdot = self.limit_speed(best)  # Sanfilippo et al. eq. (9), scaled down as a whole to the speed limits
        q_f = self.robot.clip(q_a + qdot * dt)
        x_f = self.robot.position(q_f)
        final = float(self.command_distance(x_f - x_t, u))
        if not np.any(qdot) or final >= step:  # step = the cost of θ_a
            # Not closer to x_t than x_a is: do not move.
            reason = f"no motion found that brings the tool closer to the target ({reason}); holding"
            return self._velocity_result(q_a, np.zeros_like(q_a), x_a, x_t, False, generations, reason, step, start)
        converged = final < tol
        if converged:
            reason = "converged"
        elif not np.array_equal(qdot, best):
            reason = "slowed by the joint speed limits (eq. 9)"
        return self._velocity_result(q_f, qdot, x_f, x_t, converged, generations, reason, final, start)

    @staticmethod
    def _velocity_result(q, qdot, x, x_t, success, generations, reason, cost, start) -> IKResult:
        return IKResult(
            q=q,
            success=bool(success),
            error=float(np.linalg.norm(x - x_t)),
            iterations=int(generations),
            time_s=time.perf_counter() - start,
            reason=reason,
            position=x,
            qdot=qdot,
            cost=float(cost),
        )


class RestartGeneticSolver(GeneticSolver):
    """``ga-restart``: the published GA (:class:`GeneticSolver`, unchanged in every rule) with one extension, named
    apart so that ``ga`` stays as published (issue 32, item 4).  Within the published stop the GA reaches 96–98 %
    on some arms: the misses are stagnation, the population collapsed against a joint limit while another seed
    solves the same target in 8–92 generations (docs/benchmarks.md).  So a position search whose best cost has not
    fallen by :data:`STALL_IMPROVEMENT` (1 %) in :data:`STALL_GENERATIONS` (25) generations is re-seeded: a fresh
    random population (step 3 again), the best individual so far remembered apart and returned if nothing better
    is found — a restart strategy of the evolutionary-computation literature (e.g. Auger & Hansen's restarts of
    CMA-ES, 2005).  The velocity mapping
    is the GA's.  A result's ``reason`` ends "after N re-seedings" when there were any."""

    name = "ga-restart"

    def __init__(self, robot, **options) -> None:
        super().__init__(robot, **options)
        self.stall_generations = STALL_GENERATIONS
