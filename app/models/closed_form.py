"""Closed-form kinematic families of the seed papers, recognised from a robot's DH structure.

* :class:`ComauArm`: the Comau SMART-5 3-DOF with extension arm (Motion-Lab paper §4.3, Table 3,
  eqs. 7–20), candidates of the inverse position kinematics for every elbow and base branch.
* :class:`ElbowCrane`: the offshore crane's elbow manipulator (TAC paper §7, Table 3, eqs. 42–44).

A family is matched from the robot's DH table, not its name, and its dimensions are read from the
XML, so any robot of the same shape gets the closed form.  The solver choosing among the candidates
is :class:`app.ik.analytic.AnalyticSolver`; the crane head (:mod:`app.models.crane_head`) and the
Motion-Lab (:mod:`app.scenes.lab`) use the families directly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from functools import cached_property
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from app.geometry import dh_transform, invert_transform
from app.models import kernels

__all__ = ["FAMILIES", "ComauArm", "ElbowCrane", "find_family"]


def _close(a: float, b: float, tol: float = 1e-9) -> bool:
    return abs(a - b) <= tol


class _Family:
    """What the closed-form families share: their compiled candidates.

    A family is a frozen dataclass of its dimensions [m] followed by the frame its equations hold in
    (4, 4); :attr:`kernel_record` is the same numbers in the kernel's types, the ``arm`` record of
    its ``CANDIDATES`` kernel (:mod:`app.models.kernels`).
    """

    #: the compiled candidates (app/models/kernels.py): (record, p (3,), hint, signs (k,)) → (q (2k, 3), exact (2k,))
    CANDIDATES: ClassVar

    @cached_property
    def kernel_record(self) -> tuple:
        """The dimensions as floats, then the frame C-contiguous: built on first use, then kept."""
        *dims, frame = (getattr(self, f.name) for f in fields(self))
        return (*(float(v) for v in dims), np.ascontiguousarray(frame, dtype=float))

    def kernel_candidates(self, p_world, hint: float, signs):
        """:meth:`candidates` compiled: (q (k, 3), exact (k,)); ``hint`` the first joint's angle where the
        point is on its axis, ``signs`` the elbow signs."""
        return self.CANDIDATES(
            self.kernel_record, np.ascontiguousarray(p_world, dtype=float), float(hint),
            np.ascontiguousarray(signs, dtype=float),
        )  # fmt: skip


@dataclass(frozen=True)
class ComauArm(_Family):
    """Dimensions of a Comau-type 3-DOF arm (Motion-Lab Table 3), read from its DH table."""

    a1: float
    d1: float
    a2: float
    a3: float
    L: float
    T_world_base: NDArray[np.float64]
    #: elbow branch → sign of the square root in eq. (13): + is elbow up (eq. 15)
    SIGNS: ClassVar[dict[str, tuple[float, ...]]] = {"auto": (1.0, -1.0), "up": (1.0,), "down": (-1.0,)}
    CANDIDATES = staticmethod(kernels.comau_candidates)

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
class ElbowCrane(_Family):
    """Elbow manipulator of TAC paper §7: β0 about the vertical, boom L1, jib L2, mast L0."""

    L0: float
    L1: float
    L2: float
    T_world_1: NDArray[np.float64]  # pose of the frame in which eqs. (43)–(44) hold
    #: elbow branch → sign of the root in eq. (43): the negative root is elbow up
    SIGNS: ClassVar[dict[str, tuple[float, ...]]] = {"auto": (-1.0, 1.0), "up": (-1.0,), "down": (1.0,)}
    CANDIDATES = staticmethod(kernels.crane_candidates)

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
