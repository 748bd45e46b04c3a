"""The Comau's closed-form kinematics on its moving platform (Motion-Lab paper eqs. 3–21, 54–57).

NumPy, vectorised; the references of the compiled :mod:`app.models.lab_kernels`.  Shared by the plant
(the tool-point sensor of :mod:`app.sim.motionlab`) and the controllers (MOTION_COMP in
:mod:`app.control.lab`).

* Comau tool point eq. (3) with L = d4 + d6 + d_tp, Jacobian eq. (5), acceleration eq. (6) — closed
  form, checked against the DH chain and finite differences (``tests/test_motionlab.py``).
* Tool point on the moving platform eqs. (54)–(57).  The paper says ṗ^g = ṗ^n1 because H^g_n1 is
  constant; constant, but not the identity (the calibration swaps x, y and flips z), so
  ṗ^g = R^g_n1 ṗ^n1 and p̈^g = R^g_n1 p̈^n1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.models.closed_form import ComauArm
from app.models.stewart import StewartPlatform


# ----------------------------------------------------------------------------- Comau
@dataclass(frozen=True)
class ComauKinematics:
    """Closed-form kinematics of the 3-DOF Comau with extension arm (Motion-Lab eqs. 3–6).

    Joint variables q are the controller's (θ1..θ3 of eq. 3); the tool point is in the robot
    base frame {r}.  Vectorised over leading axes of q.
    """

    a1: float
    d1: float
    a2: float
    a3: float
    L: float

    @staticmethod
    def from_arm(arm: ComauArm) -> ComauKinematics:
        return ComauKinematics(arm.a1, arm.d1, arm.a2, arm.a3, arm.L)

    def _terms(self, q):
        q = np.asarray(q, dtype=float)
        s1, c1 = np.sin(q[..., 0]), np.cos(q[..., 0])
        s2, c2 = np.sin(q[..., 1]), np.cos(q[..., 1])
        s3, c3 = np.sin(q[..., 2]), np.cos(q[..., 2])
        u = self.a1 - self.L * s3 - self.a3 * c3 + self.a2 * s2  # radial reach
        z = self.d1 + self.L * c3 + self.a2 * c2 - self.a3 * s3
        return s1, c1, s2, c2, s3, c3, u, z

    def position(self, q: ArrayLike) -> NDArray[np.float64]:
        """p_t^r of eq. (3); shape (..., 3)."""
        s1, c1, _, _, _, _, u, z = self._terms(q)
        return np.stack([c1 * u, -s1 * u, z], axis=-1)

    def jacobian(self, q: ArrayLike) -> NDArray[np.float64]:
        """J = ∂p_t^r/∂q of eq. (5); shape (..., 3, 3)."""
        s1, c1, s2, c2, s3, c3, u, _ = self._terms(q)
        u2, u3 = self.a2 * c2, -self.L * c3 + self.a3 * s3
        z2, z3 = -self.a2 * s2, -self.L * s3 - self.a3 * c3
        J = np.zeros(np.shape(u) + (3, 3))
        J[..., 0, 0], J[..., 0, 1], J[..., 0, 2] = -s1 * u, c1 * u2, c1 * u3
        J[..., 1, 0], J[..., 1, 1], J[..., 1, 2] = -c1 * u, -s1 * u2, -s1 * u3
        J[..., 2, 1], J[..., 2, 2] = z2, z3
        return J

    def jdot_qdot(self, q: ArrayLike, qd: ArrayLike) -> NDArray[np.float64]:
        """J̇ q̇ of eq. (6) (the velocity-product part of p̈_t^r); shape (..., 3)."""
        s1, c1, s2, c2, s3, c3, u, _ = self._terms(q)
        qd = np.asarray(qd, dtype=float)
        d1, d2, d3 = qd[..., 0], qd[..., 1], qd[..., 2]
        u2, u3 = self.a2 * c2, -self.L * c3 + self.a3 * s3
        ud = u2 * d2 + u3 * d3
        udd = -self.a2 * s2 * d2**2 + (self.L * s3 + self.a3 * c3) * d3**2
        zdd = -self.a2 * c2 * d2**2 + (-self.L * c3 + self.a3 * s3) * d3**2
        x = -c1 * d1**2 * u - 2 * s1 * d1 * ud + c1 * udd
        y = s1 * d1**2 * u - 2 * c1 * d1 * ud - s1 * udd
        return np.stack([x, y, zdd], axis=-1)

    def velocity(self, q: ArrayLike, qd: ArrayLike) -> NDArray[np.float64]:
        """ṗ_t^r = J q̇ (eq. 4)."""
        return np.einsum("...ij,...j->...i", self.jacobian(q), np.asarray(qd, dtype=float))

    def acceleration(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> NDArray[np.float64]:
        """p̈_t^r = J̇ q̇ + J q̈ (eq. 6)."""
        return self.jdot_qdot(q, qd) + np.einsum("...ij,...j->...i", self.jacobian(q), np.asarray(qdd, dtype=float))


def tool_on_platform(
    comau: ComauKinematics,
    T_b1_r: NDArray[np.float64],
    platform: tuple[NDArray, NDArray, NDArray],
    joints: tuple[NDArray, NDArray, NDArray],
    rates: tuple[NDArray, NDArray, NDArray] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Tool-point position, velocity, acceleration in the platform's neutral frame {n1}.

    Eqs. (54), (56), (57): p = p_b + R (p_r + R_r p_t^r), ṗ = ṗ_b + Ṙ(p_r + R_r p_t^r) + R R_r ṗ_t^r,
    p̈ = p̈_b + R̈(p_r + R_r p_t^r) + 2Ṙ R_r ṗ_t^r + R R_r p̈_t^r, with Ṙ, R̈ of eqs. (47), (51)
    (``rates`` = (R, Ṙ, R̈) when the caller has them already).  The records of the compiled
    :func:`app.models.lab_kernels.tool_on_platform`: ``platform`` = (η, η̇, η̈) of the platform carrying the
    robot, ``joints`` = (q, q̇, q̈) of the Comau.
    """
    eta, eta_dot, eta_ddot = platform
    q, qd, qdd = joints
    R, Rd, Rdd = StewartPlatform.rotation_rates(eta, eta_dot, eta_ddot) if rates is None else rates
    R_r, p_r = T_b1_r[:3, :3], T_b1_r[:3, 3]
    p_tr, v_tr, a_tr = comau.position(q), comau.velocity(q, qd), comau.acceleration(q, qd, qdd)
    arm = p_r + R_r @ p_tr
    p = eta[:3] + R @ arm
    v = eta_dot[:3] + Rd @ arm + R @ (R_r @ v_tr)
    a = eta_ddot[:3] + Rdd @ arm + 2 * Rd @ (R_r @ v_tr) + R @ (R_r @ a_tr)
    return p, v, a


def nearest_ik(
    arm: ComauArm,
    p_tr: NDArray[np.float64],
    q_near: NDArray[np.float64],
    lower: NDArray[np.float64],
    upper: NDArray[np.float64],
    use_kernels: bool,
) -> NDArray[np.float64] | None:
    """Analytic IK (eqs. 7–20): the exact candidate inside [lower, upper] nearest ``q_near``, q1 wrapped to
    within half a turn of it; None if there is none.  (Compiled whole: :func:`app.models.lab_kernels.comau_ik`.)"""
    best, best_d = None, np.inf
    if use_kernels:  # the compiled eqs. (7)–(20), tested equal
        Q, flags = arm.kernel_candidates(p_tr, float(q_near[0]), np.array(arm.SIGNS["auto"]))
        candidates = zip(Q, flags, strict=True)
    else:
        candidates = arm.candidates(p_tr, float(q_near[0]), "auto")
    for q, exact in candidates:
        q = q.copy()
        q[0] = q_near[0] + math.remainder(q[0] - q_near[0], 2 * math.pi)
        if not exact or not np.all((q >= lower - 1e-9) & (q <= upper + 1e-9)):
            continue
        d = float(np.sum((q - q_near) ** 2))
        if d < best_d:
            best, best_d = q, d
    return best
