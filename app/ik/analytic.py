"""Closed-form inverse kinematics for the two arm families of the seed papers.

* Comau SMART-5 3-DOF with extension arm (Motion-Lab paper §4.3, eqs. 7–20), with joint
  velocities and accelerations by eqs. (21)–(22).
* The offshore crane's elbow manipulator (TAC paper eqs. 42–44).

A family is recognised from the robot's DH structure, not its name, and its dimensions
are read from the XML, so any robot of the same shape gets the closed form.  Candidates
are the elbow branches (the paper's sign of the square root: + is "elbow up" in eq. 15,
− is "elbow up" in eq. 43) and the reach-over-the-base branch of the first joint; the
valid one nearest the start configuration is returned.  When no exact candidate is
inside the joint limits (or the target is out of reach), the best clipped candidate is
refined by damped least squares and the result reports ``success=False``.
"""

from __future__ import annotations

import math
import time
from typing import Unpack

import numpy as np
from numpy.typing import NDArray

from app.ik.base import DEFAULT, IKError, IKResult, Replayed, SearchOutcome, Solver, SolverOptions
from app.ik.jacobian import JacobianSolver
from app.models import kernels
from app.models.closed_form import find_family

ELBOWS = ("auto", "up", "down")


class AnalyticSolver(Solver):
    """Closed-form position IK for the Comau 3-DOF and elbow-crane families.

    Parameters
    ----------
    robot : SerialRobot
    elbow : {"auto", "up", "down"}
        Branch to return; "auto" takes the valid one nearest the start configuration.
    tolerance : float
        Success threshold on the position error [m]; default 1e-6.
    """

    name = "analytic"

    def __init__(
        self,
        robot,
        *,
        elbow: str = "auto",
        tolerance: float = 1e-6,
        **common: Unpack[SolverOptions],
    ) -> None:
        super().__init__(robot, **common)
        self.arm = find_family(robot)
        if self.arm is None:
            raise IKError(
                f"no closed-form solution for {robot.name}: the analytic solver covers Comau-type 3-DOF arms "
                "(comau_smart5_3dof) and elbow cranes (offshore_crane); use --solver ga or jacobian"
            )
        if elbow not in ELBOWS:
            raise IKError(f"elbow must be one of {', '.join(ELBOWS)}, got {elbow!r}")
        self.elbow = elbow
        self._signs = np.array(self.arm.SIGNS[elbow])
        self._mid = self.default_q0()
        self.tolerance = tolerance
        self._refiner: JacobianSolver | None = None
        # the candidate selection's limits record (app/models/kernels.py), built once
        self._limits = (robot.lower, robot.upper, self._revolute)

    def _closed_form(self, x_t, ref):
        """The best candidate: (q clipped, tool point or None, error, exact, inside)."""
        r = self.robot
        if getattr(r, "use_kernels", False):
            Q, ex = self.arm.kernel_candidates(x_t, float(ref[0]), self._signs)
            return kernels.select_candidate(
                r.kernel_record, self._limits, Q, ex, np.ascontiguousarray(ref, dtype=float),
                np.ascontiguousarray(x_t, dtype=float),
            )  # fmt: skip
        best, best_key = None, None
        for q, exact in self.arm.candidates(x_t, float(ref[0]), self.elbow):
            q = self.wrap_into_limits(q)
            inside = bool(self.robot.within_limits(q, tol=1e-9).all())
            q_c = self.robot.clip(q)
            err = float(np.linalg.norm(self.robot.position(q_c) - x_t))
            # valid first, then the smaller error, then the nearest to the reference
            key = (not (exact and inside), round(err, 9), float(np.linalg.norm(q_c - ref)))
            if best_key is None or key < best_key:
                best, best_key = (q_c, None, err, exact, inside), key
        return best

    def solve_position(self, target, q0=None, *, time_budget=DEFAULT) -> IKResult:
        """As :meth:`Solver.solve_position`; an exact solution inside the limits comes from compiled
        candidates and selection in one pass (no refinement needed)."""
        if getattr(self.robot, "use_kernels", False):
            start = time.perf_counter()
            x_t = self.check_target(target)
            q_s = self.check_q0(q0)
            ref = q_s if q_s is not None else self._mid
            q, p, err, exact, inside = self._closed_form(x_t, ref)
            if exact and inside and err <= self.tolerance:
                return IKResult(q=q, success=True, error=float(err), iterations=1, time_s=time.perf_counter() - start,
                                reason="closed form", position=p, cost=float(err))  # fmt: skip
        return super().solve_position(target, q0, time_budget=time_budget)

    def _search(self, x_t, q0, deadline) -> SearchOutcome:
        ref = q0 if q0 is not None else self.default_q0()
        q, _, err, exact, inside = self._closed_form(x_t, ref)
        if exact and inside and err <= self.tolerance:
            return SearchOutcome(q=q, iterations=1, converged=True, reason="closed form", cost=err)
        # No exact solution within limits: the closest reachable point, by damped least squares.
        if self._refiner is None:
            self._refiner = JacobianSolver(
                self.robot, time_budget=None, rng=self.rng, restarts=4, tolerance=self.tolerance
            )
        remaining = None if math.isinf(deadline) else max(1e-3, deadline - time.perf_counter())
        if self._tape is not None:  # a replayed budget: the refiner takes this solve's recorded decisions
            budget, self._tape = Replayed(0.0, (tuple(self._tape),)), []
            refined = self._refiner.solve_position(x_t, q, time_budget=budget)
        else:
            refined = self._refiner.solve_position(x_t, q, time_budget=remaining)
            for d in self._refiner.take_work():  # its clock decisions are this solve's
                self._decisions.extend(d)
        why = "target out of reach" if not exact else "closed-form solution outside the joint limits"
        ok = refined.error <= self.tolerance
        return SearchOutcome(
            q=refined.q,
            iterations=1 + refined.iterations,
            converged=ok,
            reason="reached by damped least squares within limits" if ok else f"{why}; closest point returned",
            cost=refined.error,
        )

    # ------------------------------------------------ Motion-Lab eqs. (21)–(22)
    def joint_velocity(self, q: NDArray[np.float64], pdot: NDArray[np.float64]) -> NDArray[np.float64]:
        """θ̇ = J⁻¹ ṗ (Motion-Lab eq. 21), J the position Jacobian of eq. (5)."""
        J = self.robot.jacobian(q)[:3]
        return np.linalg.solve(J, np.asarray(pdot, dtype=float))

    def jacobian_rate(self, q: NDArray[np.float64], qdot: NDArray[np.float64], h: float = 1e-6) -> NDArray[np.float64]:
        """J̇ = Σ_i ∂J/∂q_i q̇_i, by a central difference along q̇ (exact to O(h²))."""
        qdot = np.asarray(qdot, dtype=float)
        Jp = self.robot.jacobian(q + h * qdot)[:3]
        Jm = self.robot.jacobian(q - h * qdot)[:3]
        return (Jp - Jm) / (2 * h)

    def joint_acceleration(
        self, q: NDArray[np.float64], qdot: NDArray[np.float64], pddot: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """θ̈ = J⁻¹ (p̈ − J̇ θ̇) (Motion-Lab eq. 22)."""
        J = self.robot.jacobian(q)[:3]
        return np.linalg.solve(J, np.asarray(pddot, dtype=float) - self.jacobian_rate(q, qdot) @ qdot)
