"""Compiled generation loop of the GA mapping (Sanfilippo et al., §III-B, steps 5–8).

Same scheme as :mod:`app.models.kernels` (numba, cached on disk, ``BOSUN_JIT=0`` for the
interpreted path).  The NumPy methods and operator functions of :mod:`app.ik.genetic` stay the
reference: ``tests/test_ga_kernels.py`` runs both on the same seeded inputs and asserts equal
results.  To make that possible the kernels draw from the solver's own ``numpy.random.Generator``
(numba shares its bit generator, so both paths advance one stream), with the same calls, shapes and
order as the reference operators (``uniform``, ``permutation``, ``random``, ``integers``), and
compute every cost with the reference's formula, summed in the reference's order (the tool points
agree with the NumPy FK to an ulp, as :mod:`app.models.kernels`' do).

Nothing here reads a clock (numba cannot): a call runs at most ``generations`` generations and
stops early at the target cost; the solver checks its time budget between calls.

No kernel takes more than 8 arguments (issue 29): the constants and the per-call values come in
records, tuples that numba takes as one argument, each built where its values stop changing (every
array C-contiguous float64, one numba specialisation):

* ``chain`` (the robot; ``SerialRobot.kernel_record``, built once per robot, the record of
  :mod:`app.models.kernels`): dh (5, L), the DH links' θ₀ [rad], d₀ [m], a [m], cos α, sin α
  (A = Rz(θ) Tz(d) Tx(a) Rx(α), TAC paper eq. 39); M (2, L, n), the joint maps M_θ, M_d (θ = θ₀ + M_θ q,
  d = d₀ + M_d q); T (2, 4, 4), T_world_base, T_flange_tool [m];
* ``limits`` (the position cost's constants; built once per solver and task): lower, upper (n,), the joint
  limits [rad, m] a gene must keep to; box_lower, box_extent (3,) [m], the workspace box that
  normalises positions (step 2: x̂ = (x − box_lower) / box_extent); penalty, the factor (100) on the
  cost of a chromosome with a gene outside its limits (at least +1); the task (issue 32, item 4:
  :class:`app.ik.genetic.GaTask`): weights (3,) on the normalised error per axis (1, 1, 1 published),
  axis_weight and axis (3,), the tool-axis term's weight (0: none, published) and the wanted tool z;
* ``rules`` (the operators of steps 5–7; built once per solver and mapping): span (n,), the range the
  mutation amplitude refers to (the joint ranges [rad, m] in the position mapping, the one-tick speed
  window 2 × speed [rad/s, m/s] in the velocity mapping); n_elite, the individuals kept unaltered
  (13 of 125); single_point_probability (½), the chance a pair is crossed single-point rather than
  uniform; mutation_probability (0.5 %), the chance a gene mutates; amplitude (5 %), the mutation's
  U(±amplitude)·span;
* ``target`` (a velocity solve's local target; per call, from the tick's values): θ_a (n,) [rad, m],
  the joint position the genes θ̇ start from; Δt [s], the tick; x_t (3,) [m], the local target
  x_a + ẋ_ds Δt (eq. 7); u (3,), the unit commanded direction; w (``CROSS_TRACK_WEIGHT``, 3.0), the
  weight of the error across u in the cost c(e) = |e·u| + w |e − (e·u)u| [m];
* ``window`` (a velocity solve's; per call): lo, hi (n,) [rad/s, m/s], the bounds the genes θ̇ are
  kept in (``GeneticSolver.velocity_window``: ±8 × speed, and θ_a + θ̇Δt within the joint limits);
* ``stop`` (per call): the stop cost (the normalised target cost, or the velocity tolerance [m]) and
  the number of generations this call may run.

The per-call state stays in plain arguments: the population ``pop`` (m, n), its costs ``cost`` (m,),
the target position ``x_t`` (3,) [m] of the position mapping, and the solver's generator ``rng``.
"""

from __future__ import annotations

import math

import numpy as np

from app.models.kernels import ENABLED, _chain, _jit

__all__ = ["ENABLED", "evolve_position", "evolve_velocity", "position_costs", "velocity_costs"]


@_jit
def _tool_points(chain, Q):
    """Tool points (m, 3) of configurations Q (m, n) of the ``chain``: :func:`app.models.kernels.position`
    row by row in one loop (θ = θ₀ + M_θ q, d = d₀ + M_d q), with cos θ, sin θ of a link that no joint
    turns (a prismatic joint's or a fixed link) computed once instead of once per row."""
    theta0, d0, a, ca, sa, M_theta, M_d, T_base, T_tool = _chain(chain)
    L, n = M_theta.shape
    c0, s0, turns = np.empty(L), np.empty(L), np.zeros(L, dtype=np.bool_)
    for i in range(L):
        for j in range(n):
            turns[i] = turns[i] or M_theta[i, j] != 0.0
        c0[i], s0[i] = math.cos(theta0[i] + 0.0), math.sin(theta0[i] + 0.0)
    P = np.empty((Q.shape[0], 3))
    for k in range(Q.shape[0]):
        x, y, z = T_tool[0, 3], T_tool[1, 3], T_tool[2, 3]
        for i in range(L - 1, -1, -1):
            dd = 0.0
            for j in range(n):
                dd += M_d[i, j] * Q[k, j]
            y, z = ca[i] * y - sa[i] * z, sa[i] * y + ca[i] * z + (d0[i] + dd)
            x = x + a[i]
            c, s = c0[i], s0[i]
            if turns[i]:
                th = 0.0
                for j in range(n):
                    th += M_theta[i, j] * Q[k, j]
                c, s = math.cos(theta0[i] + th), math.sin(theta0[i] + th)
            x, y = c * x - s * y, s * x + c * y
        for r in range(3):
            P[k, r] = T_base[r, 0] * x + T_base[r, 1] * y + T_base[r, 2] * z + T_base[r, 3]
    return P


@_jit
def _tool_axes(chain, Q):
    """The tool's z axis (m, 3) in the world for configurations Q (m, n): :func:`_tool_points`' recursion on a
    direction (the links' rotations only)."""
    theta0, _, _, ca, sa, M_theta, _, T_base, T_tool = _chain(chain)
    L, n = M_theta.shape
    V = np.empty((Q.shape[0], 3))
    for k in range(Q.shape[0]):
        x, y, z = T_tool[0, 2], T_tool[1, 2], T_tool[2, 2]
        for i in range(L - 1, -1, -1):
            y, z = ca[i] * y - sa[i] * z, sa[i] * y + ca[i] * z
            th = 0.0
            for j in range(n):
                th += M_theta[i, j] * Q[k, j]
            c, s = math.cos(theta0[i] + th), math.sin(theta0[i] + th)
            x, y = c * x - s * y, s * x + c * y
        for r in range(3):
            V[k, r] = T_base[r, 0] * x + T_base[r, 1] * y + T_base[r, 2] * z
    return V


@_jit
def position_costs(chain, pop, x_t, limits):
    """``GeneticSolver.cost``: normalised distance to x_t (eq. 5 on the workspace box), with the task's per-axis
    weights w (√(Σ w e²): the published cost at w = 1) and its tool-axis term w_a (1 − z·z_t)/2 (none at w_a = 0),
    × ``penalty`` (at least +1) for a chromosome with a gene outside its limits.  pop (m, n) → (m,)."""
    lower, upper, box_lower, box_extent, penalty, weights, axis_weight, axis = limits
    m, n = pop.shape
    P = _tool_points(chain, pop)
    Z = _tool_axes(chain, pop) if axis_weight > 0.0 else P
    t0 = (x_t[0] - box_lower[0]) / box_extent[0]
    t1 = (x_t[1] - box_lower[1]) / box_extent[1]
    t2 = (x_t[2] - box_lower[2]) / box_extent[2]
    out = np.empty(m)
    for k in range(m):
        e0 = (P[k, 0] - box_lower[0]) / box_extent[0] - t0
        e1 = (P[k, 1] - box_lower[1]) / box_extent[1] - t1
        e2 = (P[k, 2] - box_lower[2]) / box_extent[2] - t2
        d = math.sqrt(weights[0] * (e0 * e0) + weights[1] * (e1 * e1) + weights[2] * (e2 * e2))
        if axis_weight > 0.0:
            d += axis_weight * 0.5 * (1.0 - (Z[k, 0] * axis[0] + Z[k, 1] * axis[1] + Z[k, 2] * axis[2]))
        outside = False
        for j in range(n):
            outside = outside or pop[k, j] < lower[j] or pop[k, j] > upper[j]
        out[k] = max(d * penalty, d + 1.0) if outside else d
    return out


@_jit
def velocity_costs(chain, pop, target):
    """``GeneticSolver.velocity_cost``: c(x(θ_a + θ̇Δt) − x_t) with c(e) = |e·u| + w|e − (e·u)u| (eqs. 5, 7).
    pop (m, n) of joint velocities θ̇ → (m,) [m]."""
    q_a, dt, x_t, u, cross_weight = target
    m, n = pop.shape
    Q = np.empty((m, n))
    for k in range(m):
        for j in range(n):
            Q[k, j] = q_a[j] + pop[k, j] * dt
    P = _tool_points(chain, Q)
    out = np.empty(m)
    for k in range(m):
        e0, e1, e2 = P[k, 0] - x_t[0], P[k, 1] - x_t[1], P[k, 2] - x_t[2]
        along = e0 * u[0] + e1 * u[1] + e2 * u[2]
        p0, p1, p2 = e0 - along * u[0], e1 - along * u[1], e2 - along * u[2]
        out[k] = abs(along) + cross_weight * math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    return out


@_jit
def _evolve(pop, cost, rules, rng):
    """One generation as ``GeneticSolver.evolve`` (steps 5–7): the n_elite best unaltered, then children
    of SUS-selected parents (Baker 1987, on fitness 1/cost) paired at random, crossed single-point or
    uniform 50/50, each gene mutated with probability 0.5 % by U(±5 %)·span (the ``rules`` record)."""
    span, n_elite, single_point_probability, mutation_probability, amplitude = rules
    size, n = pop.shape
    n_children = size - n_elite
    out = np.empty((size, n))
    order = np.argsort(cost, kind="mergesort")  # stable, as the reference's argsort(kind="stable")
    for k in range(n_elite):
        out[k] = pop[order[k]]
    # stochastic_universal_sampling
    cum = np.empty(size)
    total = 0.0
    for k in range(size):
        total += 1.0 / max(cost[k], 1e-12)
        cum[k] = total
    if total <= 0:
        chosen = rng.integers(0, size, size=n_children)
    else:
        step = total / n_children
        offset = rng.uniform(0.0, step)
        chosen = np.empty(n_children, dtype=np.int64)
        i = 0
        for k in range(n_children):
            pointer = offset + step * k
            while i < size and cum[i] <= pointer:  # searchsorted(cum, pointer, side="right")
                i += 1
            chosen[k] = min(i, size - 1)
    perm = rng.permutation(n_children)  # SUS output is ordered; pair at random
    parents = np.empty((n_children, n))
    for k in range(n_children):
        parents[k] = pop[chosen[perm[k]]]
    # hybrid_crossover: consecutive parents pair up; an odd last one passes unchanged
    pairs = n_children // 2
    use_single = rng.random(pairs)
    # single-point: children swap genes j >= cut, 1 <= cut <= n − 1 (one gene: no cut, nothing drawn)
    cut = rng.integers(1, n, size=(pairs, 1)) if n >= 2 else np.full((pairs, 1), n)
    swap = rng.random((pairs, n))  # uniform: gene j swapped where < ½
    children = out[n_elite:]
    for p in range(pairs):
        for j in range(n):
            exchange = j >= cut[p, 0] if use_single[p] < single_point_probability else swap[p, j] < 0.5
            a, b = parents[2 * p, j], parents[2 * p + 1, j]
            children[2 * p, j], children[2 * p + 1, j] = (b, a) if exchange else (a, b)
    if n_children % 2:
        children[n_children - 1] = parents[n_children - 1]
    # mutate
    hit = rng.random((n_children, n))
    delta = rng.uniform(-amplitude, amplitude, size=(n_children, n))
    for k in range(n_children):
        for j in range(n):
            if hit[k, j] < mutation_probability:
                children[k, j] = children[k, j] + delta[k, j] * span[j]
    return out


@_jit
def evolve_position(chain, pop, cost, x_t, limits, rules, stop, rng):
    """Up to ``generations`` generations of the position mapping, stopping when the best cost is below
    ``target_cost`` (step 8; ``stop`` = (target_cost, generations)): (population, cost, generations run)."""
    target_cost, generations = stop
    ran = 0
    while ran < generations and cost.min() >= target_cost:
        pop = _evolve(pop, cost, rules, rng)
        cost = position_costs(chain, pop, x_t, limits)
        ran += 1
    return pop, cost, ran


@_jit
def evolve_velocity(chain, pop, cost, target, window, rules, stop, rng):
    """Up to ``generations`` generations of the velocity mapping (genes θ̇, kept inside the window
    [lo, hi]), stopping when the best cost is below ``tolerance`` (``stop`` = (tolerance, generations)):
    (population, cost, generations run)."""
    lo, hi = window
    tolerance, generations = stop
    ran = 0
    while ran < generations and cost.min() >= tolerance:
        pop = _evolve(pop, cost, rules, rng)
        for k in range(pop.shape[0]):
            for j in range(pop.shape[1]):
                pop[k, j] = min(max(pop[k, j], lo[j]), hi[j])
        cost = velocity_costs(chain, pop, target)
        ran += 1
    return pop, cost, ran


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel of this file with the argument types the
    GA passes (for :func:`app.warmup.warm_up`)."""
    L, n = 3, 3
    dh = np.stack([np.zeros(L), np.zeros(L), np.ones(L), np.ones(L), np.zeros(L)])
    chain = (dh, np.stack([np.eye(L, n), np.zeros((L, n))]), np.stack([np.eye(4), np.eye(4)]))  # a robot record
    pop, cost, rng = np.zeros((4, n)), np.ones(4), np.random.default_rng(0)
    # joint limits, workspace box, penalty, the task's axis weights, tool-axis weight and direction
    limits = (-np.ones(n), np.ones(n), -np.ones(3), np.ones(3), 100.0, np.ones(3), 0.0, np.zeros(3))
    rules = (np.ones(n), 1, 0.5, 0.005, 0.05)  # mutation span, elite, operators
    target = (np.zeros(n), 0.01, np.zeros(3), np.ones(3), 3.0)  # θ_a, Δt, x_t, u, w
    window, stop = (-np.ones(n), np.ones(n)), (0.01, 1)  # velocity window; stop cost, generations
    return [
        lambda: position_costs(chain, pop, np.zeros(3), limits),
        lambda: velocity_costs(chain, pop, target),
        lambda: evolve_position(chain, pop, cost, np.zeros(3), limits, rules, stop, rng),
        lambda: evolve_velocity(chain, pop, cost, target, window, rules, stop, rng),
    ]
