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
reproducible from its seed.
"""

from __future__ import annotations

import math
import time

import numpy as np
from numpy.typing import NDArray

from app.ik.base import DEFAULT, SearchOutcome, Solver

POPULATION = 125
ELITE_FRACTION = 0.10
CROSSOVER_SINGLE_POINT_PROBABILITY = 0.5
MUTATION_PROBABILITY = 0.005
MUTATION_AMPLITUDE = 0.05
TARGET_COST = 0.01
PENALTY_FACTOR = 100.0
#: generations allowed when neither a time budget nor max_generations bounds a call
HARD_GENERATION_CAP = 20_000


def stochastic_universal_sampling(fitness: NDArray[np.float64], n: int, rng: np.random.Generator) -> NDArray[np.intp]:
    """Indices of n individuals chosen by SUS (Baker 1987).

    n equally spaced pointers, one random offset in [0, F/n) with F the total fitness;
    individual i is chosen once for each pointer inside its slice of the cumulative
    fitness, so it gets floor or ceil of n·f_i/F copies.
    """
    fitness = np.asarray(fitness, dtype=float)
    if np.any(fitness < 0) or not np.all(np.isfinite(fitness)):
        raise ValueError("fitness must be finite and non-negative")
    total = fitness.sum()
    if total <= 0:
        return rng.integers(0, fitness.size, size=n)
    step = total / n
    pointers = rng.uniform(0.0, step) + step * np.arange(n)
    idx = np.searchsorted(np.cumsum(fitness), pointers, side="right")
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


def elite_count(population: int, fraction: float = ELITE_FRACTION) -> int:
    """Number of elites: fraction of the population, rounded half up, at least 1 (13 of 125)."""
    return max(1, math.floor(fraction * population + 0.5))


class GeneticSolver(Solver):
    """GA position mapping; the velocity mapping uses eqs. (7) and (9) through the base class.

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
    rng : numpy.random.Generator
    """

    name = "ga"
    default_time_budget = 0.1

    def __init__(
        self,
        robot,
        *,
        time_budget: float | object | None = DEFAULT,
        rng: np.random.Generator | None = None,
        target_cost: float = TARGET_COST,
        population: int = POPULATION,
        max_generations: int | None = None,
    ) -> None:
        super().__init__(robot, time_budget=time_budget, rng=rng)
        if population < 4:
            raise ValueError("population must be at least 4")
        self.target_cost = target_cost
        self.population_size = population
        self.n_elite = elite_count(population)
        self.max_generations = max_generations
        self.span = robot.upper - robot.lower
        self.population: NDArray[np.float64] | None = None
        self._last_target: NDArray[np.float64] | None = None

    def reset(self) -> None:
        self.population = None
        self._last_target = None

    # ---------------------------------------------------------------- cost
    def cost(self, genes: NDArray[np.float64], x_t: NDArray[np.float64]) -> NDArray[np.float64]:
        """Normalised distance |x̂_t − x̂_a| (eq. 5 on normalised positions), penalised outside limits."""
        reached = self.box.normalise(self.robot.position(genes))
        d = np.linalg.norm(reached - self.box.normalise(x_t), axis=-1)
        outside = np.any((genes < self.robot.lower) | (genes > self.robot.upper), axis=-1)
        return np.where(outside, np.maximum(d * PENALTY_FACTOR, d + 1.0), d)

    # ---------------------------------------------------------------- evolution
    def evolve(self, pop: NDArray[np.float64], cost: NDArray[np.float64]) -> NDArray[np.float64]:
        """One generation: elites unaltered, the rest by SUS, hybrid crossover and mutation."""
        order = np.argsort(cost, kind="stable")
        elites = pop[order[: self.n_elite]]
        fitness = 1.0 / np.maximum(cost, 1e-12)
        n_children = self.population_size - self.n_elite
        parents = pop[stochastic_universal_sampling(fitness, n_children, self.rng)]
        parents = parents[self.rng.permutation(n_children)]  # SUS output is ordered; pair at random
        children = mutate(hybrid_crossover(parents, self.rng), self.span, self.rng)
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

    def _search(self, x_t, q0, deadline) -> SearchOutcome:
        pop = self.initial_population(x_t)
        self._last_target = np.array(x_t)
        cost = self.cost(pop, x_t)
        generations = 0
        reason = "time budget spent"
        cap = self.max_generations
        if cap is None and math.isinf(deadline):
            cap = HARD_GENERATION_CAP
        while True:
            if cost.min() < self.target_cost:
                reason = "converged"
                break
            if time.perf_counter() >= deadline:
                break
            if cap is not None and generations >= cap:
                reason = "generation limit"
                break
            pop = self.evolve(pop, cost)
            cost = self.cost(pop, x_t)
            generations += 1
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
            reason=reason if feasible[best] else "no chromosome within limits; clipped",
            cost=best_cost,
        )
