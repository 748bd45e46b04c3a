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
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from app.geometry import dh_transform, invert_transform
from app.ik.base import DEFAULT, IKError, IKResult, SearchOutcome, Solver
from app.ik.jacobian import JacobianSolver
from app.models import kernels

ELBOWS = ("auto", "up", "down")


def _close(a: float, b: float, tol: float = 1e-9) -> bool:
    return abs(a - b) <= tol


@dataclass(frozen=True)
class ComauArm:
    """Dimensions of a Comau-type 3-DOF arm (Motion-Lab Table 3), read from its DH table."""

    a1: float
    d1: float
    a2: float
    a3: float
    L: float
    T_world_base: NDArray[np.float64]
    #: elbow branch → sign of the square root in eq. (13): + is elbow up (eq. 15)
    SIGNS: ClassVar[dict[str, tuple[float, ...]]] = {"auto": (1.0, -1.0), "up": (1.0,), "down": (-1.0,)}

    def kernel_candidates(self, p_world, q1_hint: float, signs):
        """:meth:`candidates` compiled: (q (k, 3), exact (k,))."""
        return kernels.comau_candidates(
            float(self.a1), float(self.d1), float(self.a2), float(self.a3), float(self.L),
            np.ascontiguousarray(self.T_world_base, dtype=float), np.ascontiguousarray(p_world, dtype=float),
            float(q1_hint), np.ascontiguousarray(signs, dtype=float),
        )  # fmt: skip

    @staticmethod
    def match(robot) -> ComauArm | None:
        links, joints = robot.links, robot.joints
        if len(joints) != 3 or len(links) != 4 or any(j.kind != "revolute" for j in joints):
            return None
        l1, l2, l3, l4 = links
        j1, j2, j3 = joints
        shape_ok = (
            [j.link for j in joints] == [0, 1, 2]
            and l4.kind == "fixed"
            and _close(l4.theta, math.pi)
            and _close(l4.a, 0)
            and _close(l4.alpha, 0)
            and _close(l1.alpha, math.pi / 2)
            and _close(l2.alpha, 0)
            and _close(l3.alpha, math.pi / 2)
            and _close(l2.d, 0)
            and _close(l3.d, 0)
            and (j1.sign, j2.sign, j3.sign) == (-1.0, -1.0, 1.0)
            and _close(j1.offset, 0)
            and _close(j2.offset, math.pi / 2)
            and _close(j3.offset, math.pi / 2)
            and j1.coupling == ()
            and j2.coupling == ()
            and j3.coupling == ((1, 1.0),)
            and np.allclose(robot.T_flange_tool, np.eye(4))
        )
        if not shape_ok:
            return None
        return ComauArm(l1.a, l1.d, l2.a, l3.a, l4.d, robot.T_world_base)

    def candidates(self, p_world: NDArray[np.float64], q1_hint: float, elbow: str) -> list[tuple[NDArray, bool]]:
        """Joint candidates (q, exact) for a tool position; exact=False when the point is out of reach."""
        x, y, z = (invert_transform(self.T_world_base) @ np.r_[p_world, 1.0])[:3]
        q1_front = -math.atan2(y, x) if math.hypot(x, y) > 1e-9 else q1_hint  # eq. (7)
        B = math.hypot(self.a3, self.L)  # eq. (8)
        phi = math.atan2(self.a3, self.L)  # eq. (19)
        signs = self.SIGNS[elbow]
        out = []
        for q1 in (q1_front, q1_front + math.pi):
            A1 = dh_transform(-q1, self.d1, self.a1, math.pi / 2)  # θ1 = −q1 (Table 3)
            xp, yp, _ = (invert_transform(A1) @ np.r_[x, y, z, 1.0])[:3]  # eq. (9)
            C = math.hypot(xp, yp)  # eq. (11)
            D = (C**2 - self.a2**2 - B**2) / (2 * self.a2 * B)  # eq. (12)
            exact = abs(D) <= 1.0
            D = min(1.0, max(-1.0, D))
            for s in signs:
                alpha = math.atan2(s * math.sqrt(1.0 - D**2), D)  # eqs. (13)–(15)
                theta_a = math.atan2(yp, xp)  # eq. (16)
                theta_b = math.atan2(B * math.sin(alpha), self.a2 + B * math.cos(alpha))  # eq. (17)
                q2 = math.pi / 2 - (theta_a - theta_b)  # eq. (18)
                q3 = alpha - phi - q2  # eq. (20)
                out.append((np.array([q1, q2, q3]), exact))
        return out


@dataclass(frozen=True)
class ElbowCrane:
    """Elbow manipulator of TAC paper §7: β0 about the vertical, boom L1, jib L2, mast L0."""

    L0: float
    L1: float
    L2: float
    T_world_1: NDArray[np.float64]  # pose of the frame in which eqs. (43)–(44) hold
    #: elbow branch → sign of the root in eq. (43): the negative root is elbow up
    SIGNS: ClassVar[dict[str, tuple[float, ...]]] = {"auto": (-1.0, 1.0), "up": (-1.0,), "down": (1.0,)}

    def kernel_candidates(self, p_world, beta0_hint: float, signs):
        """:meth:`candidates` compiled: (q (k, 3), exact (k,))."""
        return kernels.crane_candidates(
            float(self.L0), float(self.L1), float(self.L2), np.ascontiguousarray(self.T_world_1, dtype=float),
            np.ascontiguousarray(p_world, dtype=float), float(beta0_hint), np.ascontiguousarray(signs, dtype=float),
        )  # fmt: skip

    @staticmethod
    def match(robot) -> ElbowCrane | None:
        joints, links = robot.joints, robot.links
        if len(joints) != 3 or any(j.kind != "revolute" for j in joints):
            return None
        first = joints[0].link
        moving = [j.link for j in joints]
        if moving != [first, first + 1, first + 2] or len(links) != first + 3:
            return None
        l1, l2, l3 = links[first : first + 3]
        shape_ok = (
            all(links[i].kind == "fixed" for i in range(first))
            and all(j.sign == 1.0 and _close(j.offset, 0) and j.coupling == () for j in joints)
            and _close(l1.a, 0)
            and _close(l1.alpha, math.pi / 2)
            and _close(l2.alpha, 0)
            and _close(l2.d, 0)
            and _close(l3.d, 0)
            and np.allclose(robot.T_flange_tool[:3, 3], 0)
        )
        if not shape_ok:
            return None
        T_world_1 = robot.frames(np.zeros(3))[first]  # fixed links only before the first joint
        return ElbowCrane(l1.d, l2.a, l3.a, T_world_1)

    def candidates(self, p_world: NDArray[np.float64], beta0_hint: float, elbow: str) -> list[tuple[NDArray, bool]]:
        # eq. (42): the target in the frame of the first joint
        x, y, z = (invert_transform(self.T_world_1) @ np.r_[p_world, 1.0])[:3]
        r = math.hypot(x, y)
        beta0_front = math.atan2(y, x) if r > 1e-9 else beta0_hint  # eq. (43)
        delta = (x**2 + y**2 + (z - self.L0) ** 2 - self.L1**2 - self.L2**2) / (2 * self.L1 * self.L2)  # eq. (44)
        exact = abs(delta) <= 1.0
        delta = min(1.0, max(-1.0, delta))
        # eq. (43): the negative root is elbow up, the positive elbow down
        signs = self.SIGNS[elbow]
        out = []
        for beta0, radial in ((beta0_front, r), (beta0_front + math.pi, -r)):
            for s in signs:
                beta2 = math.atan2(s * math.sqrt(1.0 - delta**2), delta)
                beta1 = math.atan2(z - self.L0, radial) - math.atan2(
                    self.L2 * math.sin(beta2), self.L1 + self.L2 * math.cos(beta2)
                )
                out.append((np.array([beta0, beta1, beta2]), exact))
        return out


FAMILIES = (ComauArm, ElbowCrane)


def find_family(robot):
    """The closed-form family matching the robot's DH structure, or None."""
    for family in FAMILIES:
        arm = family.match(robot)
        if arm is not None:
            return arm
    return None


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
    default_time_budget = 0.1

    def __init__(
        self,
        robot,
        *,
        time_budget: float | object | None = DEFAULT,
        rng: np.random.Generator | None = None,
        elbow: str = "auto",
        tolerance: float = 1e-6,
    ) -> None:
        super().__init__(robot, time_budget=time_budget, rng=rng)
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

    def _closed_form(self, x_t, ref):
        """The best candidate: (q clipped, tool point or None, error, exact, inside)."""
        r = self.robot
        if getattr(r, "use_kernels", False):
            Q, ex = self.arm.kernel_candidates(x_t, float(ref[0]), self._signs)
            return kernels.select_candidate(
                *r.kernel_args, Q, ex, r.lower, r.upper, self._revolute, np.ascontiguousarray(ref, dtype=float),
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
        refined = self._refiner.solve_position(x_t, q, time_budget=remaining)
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
