"""Damped-least-squares Jacobian solver with joint-limit clamping and limit avoidance.

Step (Wampler 1986; Nakamura & Hanafusa 1986; Maciejewski & Klein 1988 for the damping):

    Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e  +  (I − J⁺J) (−k ∇H(q)),

with the damping growing only near a singularity,
λ² = λ_max² (1 − (σ_min/ε)²) when σ_min < ε, else 0, where σ_min is the smallest singular
value of J, and fading with the remaining error, × min(1, (|e|/e_ref)²), so that close to the
target (where the linearisation is good) the step becomes Gauss–Newton and converges
quadratically even beside a singularity (Levenberg–Marquardt idea; Sugihara 2011).
Joints at a limit that the step would push further are taken out of the active set and
the step recomputed (clamping); H(q) = Σ ((q − q_mid)/range)² pulls the
other joints towards mid-range in the null space (limit avoidance, arms with more joints
than task rows).  Position only for arms with fewer than 6 joints; arms with 6 or more
can also be given a target orientation.  The velocity solve uses the same damped inverse:
θ̇ = J⁺_λ ẋ, clamped so that q + θ̇Δt stays inside the limits and scaled to the speed
limits.
"""

from __future__ import annotations

import math
import time
from typing import Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.ik.base import DEFAULT, IKResult, SearchOutcome, Solver, SolverOptions
from app.models import kernels

SEEDS = 256  # restart table size: its tool positions cover the workspace to a few centimetres
NEAREST_SEEDS = 8  # restarts from the nearest table entries before uniform random ones
SEED_TABLE_SEED = 14


class JacobianSolver(Solver):
    """Damped least squares with restarts.

    Parameters
    ----------
    robot : SerialRobot
    tolerance : float
        Success when the position error is below this [m]; default 1e-4 m.
    max_iterations : int
        Iterations per start; default 200.
    restarts : int
        Restarts after the first start fails (the 8 seed-table configurations whose tool is nearest the
        target, then uniform random ones); default 20 (the time budget may end them sooner).
    time_budget : float or None
        Default 0.1 s.
    """

    name = "jacobian"

    def __init__(
        self,
        robot,
        *,
        tolerance: float = 1e-4,
        max_iterations: int = 200,
        restarts: int = 20,
        limit_avoidance_gain: float = 0.05,
        **common: Unpack[SolverOptions],
    ) -> None:
        super().__init__(robot, **common)
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        self.restarts = restarts
        self.k_avoid = limit_avoidance_gain
        scale = 0.5 * self.box.diagonal
        self.epsilon = 0.02 * scale  # singular region: σ_min below 2 % of the workspace half-diagonal
        self.lambda_max = 0.1 * scale
        self.e_ref = 0.05 * scale
        self.max_step = np.where(np.array(robot.joint_kinds) == "revolute", 0.3, 0.1 * (robot.upper - robot.lower))
        # the compiled kernels' settings record (app/models/kernels.py), in their types: built once here (the
        # settings are fixed after construction), not on every solve
        self.kernel_settings = (
            robot.lower, robot.upper, np.ascontiguousarray(self.max_step, dtype=float), float(self.lambda_max),
            float(self.epsilon), float(self.e_ref), float(self.k_avoid), float(self.tolerance),
            int(self.max_iterations),
        )  # fmt: skip
        self._seed_table: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None

    # ---------------------------------------------------------------- damped inverse
    def damped_step(
        self, J: NDArray[np.float64], e: NDArray[np.float64], q: NDArray[np.float64], avoid: bool = True
    ) -> NDArray[np.float64]:
        """One DLS step with active-set clamping at the joint limits (compiled: the same steps in
        :func:`app.models.kernels.damped_step`, unless ``robot.use_kernels`` is False)."""
        if getattr(self.robot, "use_kernels", False):
            return kernels.damped_step(
                np.ascontiguousarray(J, dtype=float),
                np.ascontiguousarray(e, dtype=float),
                np.ascontiguousarray(q, dtype=float),
                self.kernel_settings,
                bool(avoid),
            )
        n = J.shape[1]
        active = np.ones(n, dtype=bool)
        lo, hi = self.robot.lower, self.robot.upper
        dq = np.zeros(n)
        for _ in range(n + 1):
            Ja = J * active
            U, s, Vt = np.linalg.svd(Ja, full_matrices=False)
            rank_rows = max(1, min(int(active.sum()), J.shape[0]))
            s_min = s[:rank_rows].min()
            lam2 = self.lambda_max**2 * (1.0 - (s_min / self.epsilon) ** 2) if s_min < self.epsilon else 0.0
            lam2 *= min(1.0, float(e @ e) / self.e_ref**2)
            denom = s**2 + lam2
            s_inv = np.divide(s, denom, out=np.zeros_like(s), where=denom > 1e-24 * max(s.max(), 1.0) ** 2)
            J_pinv = (Vt.T * s_inv) @ U.T
            dq = J_pinv @ e
            if avoid and self.k_avoid > 0:
                # -k (span²/2) ∇H with H = Σ((q − q_mid)/span)², projected into the null space of J
                N = np.eye(n) - J_pinv @ Ja
                dq += N @ (-self.k_avoid * (q - 0.5 * (lo + hi)) * active)
            dq *= active
            # Step limit: keep the linearisation honest.
            ratio = np.max(np.abs(dq) / self.max_step)
            if ratio > 1:
                dq /= ratio
            pushing_out = ((q <= lo + 1e-12) & (dq < 0)) | ((q >= hi - 1e-12) & (dq > 0))
            if not (pushing_out & active).any():
                break
            active &= ~pushing_out
        return dq

    # ---------------------------------------------------------------- errors
    def _task_error(self, q: NDArray[np.float64], x_t: NDArray[np.float64]):
        T = self.robot.fk(q)
        J = self.robot.jacobian(q)
        e_p = x_t - T[:3, 3]
        return J[:3], e_p, float(np.linalg.norm(e_p))

    def _descend(self, q: NDArray[np.float64], x_t: NDArray[np.float64], deadline: float):
        """Iterate DLS steps from q; (best q, its error, iterations).

        Position targets run in the compiled kernel (:func:`app.models.kernels.descend`, the same
        steps); it checks no clock, so the time budget is checked between descents (one descent
        is at most ``max_iterations`` steps of a few microseconds).  ``robot.use_kernels = False`` runs the
        NumPy reference below."""
        if getattr(self.robot, "use_kernels", False):
            best_q, best_err, iterations = kernels.descend(
                self.robot.kernel_record,
                self.kernel_settings,
                np.ascontiguousarray(q, dtype=float),
                np.ascontiguousarray(x_t, dtype=float),
            )
            return best_q, float(best_err), int(iterations)
        return self._descend_reference(q, x_t, deadline)

    def solve_position(
        self, target: ArrayLike, q0: ArrayLike | None = None, *, time_budget: float | object | None = DEFAULT
    ) -> IKResult:
        """As :meth:`Solver.solve_position`; a warm start (q0 given, position only) that converges in
        its first descent is answered from one compiled call (teleoperation's common case: tens of
        microseconds); anything else takes the general path (restarts, time budget)."""
        if q0 is not None and getattr(self.robot, "use_kernels", False):
            start = time.perf_counter()
            x_t = self.check_target(target)
            q_s = self.check_q0(q0)
            q, p, error, cost, iterations = kernels.descend_to(
                self.robot.kernel_record, self.kernel_settings, np.ascontiguousarray(q_s), np.ascontiguousarray(x_t)
            )
            if cost <= self.tolerance:
                return IKResult(
                    q=q,
                    success=True,
                    error=float(error),
                    iterations=int(iterations),
                    time_s=time.perf_counter() - start,
                    reason="converged",
                    position=p,
                    cost=float(cost),
                )
        return super().solve_position(target, q0, time_budget=time_budget)

    def _descend_reference(self, q: NDArray[np.float64], x_t: NDArray[np.float64], deadline: float):
        best_q, best_err, iterations = q, math.inf, 0
        stall = 0
        while iterations < self.max_iterations:
            iterations += 1
            J, e, err = self._task_error(q, x_t)
            if err < best_err - 1e-12:
                stall = 0 if err < 0.999 * best_err else stall + 1
                best_q, best_err = q, err
            else:
                stall += 1
            if err <= self.tolerance or stall > 15 or self._expired(deadline):
                break
            q = self.robot.clip(q + self.damped_step(J, e, q))
        return best_q, best_err, iterations

    def _seeds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """A fixed table of SEEDS configurations (uniform in the limits, its own seeded generator, so
        the solver's random stream is untouched) and their tool positions, built on first use."""
        if self._seed_table is None:
            Q = np.random.default_rng(SEED_TABLE_SEED).uniform(
                self.robot.lower, self.robot.upper, size=(SEEDS, self.robot.n_joints)
            )
            self._seed_table = (Q, self.robot.position(Q))
        return self._seed_table

    def _restart_points(self, x_t: NDArray[np.float64]):
        """Restart configurations: the seed table's, nearest tool position to the target first (a
        descent from there has centimetres, not metres, to go), then uniform random ones."""
        Q, P = self._seeds()
        for k in np.argsort(np.einsum("ij,ij->i", P - x_t, P - x_t))[:NEAREST_SEEDS]:
            yield Q[k]
        while True:
            yield self.random_q()

    def _search(self, x_t, q0, deadline) -> SearchOutcome:
        starts = [q0 if q0 is not None else self.default_q0()]
        restarts = self._restart_points(x_t)
        best_q, best_err, total_it = starts[0], math.inf, 0
        attempt = 0
        reason = "iteration limit"
        while True:
            q, err, it = self._descend(starts[-1], x_t, deadline)
            total_it += it
            if err < best_err:
                best_q, best_err = q, err
            if best_err <= self.tolerance:
                reason = "converged"
                break
            if self._expired(deadline):
                reason = "time budget spent"
                break
            if attempt >= self.restarts:
                reason = "not reached after restarts (target may be outside the workspace)"
                break
            attempt += 1
            starts.append(next(restarts))
        return SearchOutcome(
            q=best_q, iterations=total_it, converged=best_err <= self.tolerance, reason=reason, cost=best_err
        )

    # ---------------------------------------------------------------- interface
    def solve_velocity(self, q_a, xdot, dt, *, time_budget: float | object | None = DEFAULT) -> IKResult:
        """θ̇ = J⁺_λ ẋ with the same damped, clamped inverse (eq. 4)."""
        start = time.perf_counter()
        q_a, v = self.check_velocity_request(q_a, xdot, dt)
        J = self.robot.jacobian(q_a)[:3]
        dq = self.damped_step(J, v * dt, q_a, avoid=False)
        q_new = self.robot.clip(q_a + dq)
        qdot = self.limit_speed((q_new - q_a) / dt)
        x_t = self.robot.position(q_a) + v * dt
        q_next = self.robot.clip(q_a + qdot * dt)
        miss = float(np.linalg.norm(self.robot.position(q_next) - x_t))
        ok = miss <= 0.1 * float(np.linalg.norm(v)) * dt + self.tolerance
        outcome = SearchOutcome(
            q=q_next,
            iterations=1,
            converged=ok,
            reason="damped least squares step" if ok else "step limited by limits or singularity",
        )
        return self._result(x_t, outcome, start, qdot=qdot)
