"""Stewart platform kinematics (Motion-Lab paper §6.1, eqs. 31–51).

Pose η = (x, y, z, φ, θ, ψ) of the body frame {b} in the neutral frame {n}: surge, sway, heave
[m] and roll, pitch, yaw [rad].  Both frames are z-down, as the lab's calibration frames.

Rotation convention.  Eq. (33) prints R_b^n(δ) = R_x(ψ) R_y(θ) R_z(φ), which pairs yaw with the x
axis; the angular-velocity map of eq. (44) settles which sequence is meant:

    R_b^n = R_x(φ) R_y(θ) R_z(ψ)        (roll about x first in {n}, yaw last about the body z)

is the only order whose body angular velocity ω_{n,b}^b = T(δ)⁻¹ δ̇ gives the printed T(δ)
(checked numerically in ``tests/test_stewart.py``).  It is *not* Fossen's zyx order used for the
ships of the TAC paper (:func:`app.geometry.euler_zyx_to_matrix`).

Legs: leg k joins the base joint a_k (fixed in {n}) to the platform joint b_k (fixed in {b});
its length is |p + R b_k − a_k| (inverse kinematics, closed form).  Forward kinematics solves the
six leg lengths for η by Newton's method.  Velocities and accelerations follow eqs. (40)–(51).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.errors import BosunError
from app.geometry import euler_to_matrix, skew
from app.models.model import Model
from app.models.spec import RobotSpec

__all__ = [
    "StewartError",
    "StewartFK",
    "StewartPlatform",
    "T_delta",
    "T_delta_dot",
    "rotation_xyz",
]


class StewartError(BosunError):
    """A Stewart platform cannot do what was asked (bad pose, no forward solution)."""


def rotation_xyz(delta: ArrayLike) -> NDArray[np.float64]:
    """R_b^n(δ) = R_x(φ) R_y(θ) R_z(ψ) (Motion-Lab eq. 33 with the order that eq. 44 implies) of roll, pitch,
    yaw δ (..., 3) [rad]; shape (..., 3, 3)."""
    return euler_to_matrix(delta, "xyz")


def T_delta(delta: ArrayLike) -> NDArray[np.float64]:
    """T(δ) of eq. (44): δ̇ = T(δ) ω_{n,b}^b; shape (..., 3, 3).  Singular at θ = ±90°."""
    d = np.asarray(delta, dtype=float)
    th, psi = d[..., 1], d[..., 2]
    ct, st, cp, sp = np.cos(th), np.sin(th), np.cos(psi), np.sin(psi)
    T = np.zeros(d.shape[:-1] + (3, 3))
    T[..., 0, 0], T[..., 0, 1] = cp / ct, -sp / ct
    T[..., 1, 0], T[..., 1, 1] = sp, cp
    T[..., 2, 0], T[..., 2, 1], T[..., 2, 2] = -st * cp / ct, st * sp / ct, 1.0
    return T


def T_inverse(delta: ArrayLike) -> NDArray[np.float64]:
    """T(δ)⁻¹: ω_{n,b}^b = T⁻¹ δ̇ (the body rates of R_x(φ) R_y(θ) R_z(ψ)); shape (..., 3, 3)."""
    d = np.asarray(delta, dtype=float)
    th, psi = d[..., 1], d[..., 2]
    ct, st, cp, sp = np.cos(th), np.sin(th), np.cos(psi), np.sin(psi)
    M = np.zeros(d.shape[:-1] + (3, 3))
    M[..., 0, 0], M[..., 0, 1] = ct * cp, sp
    M[..., 1, 0], M[..., 1, 1] = -ct * sp, cp
    M[..., 2, 0], M[..., 2, 2] = st, 1.0
    return M


def T_delta_dot(delta: ArrayLike, delta_dot: ArrayLike) -> NDArray[np.float64]:
    """d/dt T(δ) for eq. (49)–(50); shape (..., 3, 3)."""
    d = np.asarray(delta, dtype=float)
    dd = np.asarray(delta_dot, dtype=float)
    th, psi, dth, dpsi = d[..., 1], d[..., 2], dd[..., 1], dd[..., 2]
    ct, st, cp, sp = np.cos(th), np.sin(th), np.cos(psi), np.sin(psi)
    tt, sec = st / ct, 1.0 / ct
    Td = np.zeros(d.shape[:-1] + (3, 3))
    # ∂/∂θ and ∂/∂ψ of each entry of eq. (44), times θ̇ and ψ̇
    Td[..., 0, 0] = cp * sec * tt * dth - sp * sec * dpsi
    Td[..., 0, 1] = -sp * sec * tt * dth - cp * sec * dpsi
    Td[..., 1, 0] = cp * dpsi
    Td[..., 1, 1] = -sp * dpsi
    Td[..., 2, 0] = -cp * sec**2 * dth + tt * sp * dpsi
    Td[..., 2, 1] = sp * sec**2 * dth + tt * cp * dpsi
    return Td


@dataclass(frozen=True)
class StewartFK:
    """Forward-kinematics result: the pose, whether Newton converged, the leg-length residual [m]."""

    eta: NDArray[np.float64]
    success: bool
    residual: float
    iterations: int


class StewartPlatform(Model):
    """Kinematic model of a six-leg Stewart platform read from a ``type="stewart"`` robot file.

    Attributes
    ----------
    a_n : ndarray (6, 3)   base joints in {n} [m]
    b_b : ndarray (6, 3)   platform joints in {b} [m]
    pose_min, pose_max, speed_max, accel_max : ndarray (6,)   Table 8 limits [m, rad, /s, /s²]
    leg_min, leg_max : float   leg length range [m]
    """

    kind = "stewart"
    wrong_type = StewartError

    def __init__(self, spec: RobotSpec) -> None:
        super().__init__(spec)
        s = spec.stewart
        # C-contiguous float64: the compiled leg kernels have one signature
        self.a_n = np.ascontiguousarray(s.base_joints_n, dtype=float)
        self.b_b = np.ascontiguousarray(s.platform_joints_b, dtype=float)
        self.pose_min, self.pose_max = np.asarray(s.pose_min), np.asarray(s.pose_max)
        self.speed_max, self.accel_max = np.asarray(s.speed_max), np.asarray(s.accel_max)
        self.leg_min, self.leg_max = s.leg_min, s.leg_max
        self.leg_speed, self.leg_accel = s.leg_speed, s.leg_accel
        self.neutral_legs = self.leg_lengths(np.zeros(6))

    # ------------------------------------------------------------------ pose
    def within_limits(self, eta: ArrayLike, tol: float = 1e-9) -> NDArray[np.bool_]:
        """Whether each pose (..., 6) lies inside the Table 8 pose box."""
        eta = np.asarray(eta, dtype=float)
        return np.all((eta >= self.pose_min - tol) & (eta <= self.pose_max + tol), axis=-1)

    @staticmethod
    def pose_matrix(eta: ArrayLike) -> NDArray[np.float64]:
        """H_b^n of eq. (38); shape (..., 4, 4)."""
        eta = np.asarray(eta, dtype=float)
        H = np.zeros(eta.shape[:-1] + (4, 4))
        H[..., :3, :3] = rotation_xyz(eta[..., 3:6])
        H[..., :3, 3] = eta[..., :3]
        H[..., 3, 3] = 1.0
        return H

    # ------------------------------------------------------------------ legs
    def leg_vectors(self, eta: ArrayLike) -> NDArray[np.float64]:
        """l_k = p + R b_k − a_k in {n}; shape (..., 6, 3)."""
        eta = np.asarray(eta, dtype=float)
        R = rotation_xyz(eta[..., 3:6])
        return eta[..., None, :3] + np.einsum("...ij,kj->...ki", R, self.b_b) - self.a_n

    def leg_lengths(self, eta: ArrayLike) -> NDArray[np.float64]:
        """Inverse kinematics: the six leg lengths of pose(s) η; shape (..., 6) [m]."""
        return np.linalg.norm(self.leg_vectors(eta), axis=-1)

    def leg_jacobian(self, eta: ArrayLike) -> NDArray[np.float64]:
        """J_l with l̇ = J_l v, v = (ṗ_b^n, ω_{n,b}^b) of eq. (42); shape (..., 6, 6).

        l̇_k = u_kᵀ (ṗ + Ṙ b_k) = u_kᵀ ṗ + (R b_k × u_k)ᵀ R ω^b, u_k the unit leg vector.
        """
        eta = np.asarray(eta, dtype=float)
        R = rotation_xyz(eta[..., 3:6])
        L = self.leg_vectors(eta)
        u = L / np.linalg.norm(L, axis=-1, keepdims=True)
        rb = np.einsum("...ij,kj->...ki", R, self.b_b)
        J = np.empty(eta.shape[:-1] + (6, 6))
        J[..., :3] = u
        J[..., 3:] = np.einsum("...ki,...ij->...kj", np.cross(rb, u), R)
        return J

    def leg_rates(self, eta: ArrayLike, eta_dot: ArrayLike) -> NDArray[np.float64]:
        """Leg speeds l̇ [m/s] for pose rates η̇ (eq. 45 then :meth:`leg_jacobian`); shape (..., 6)."""
        v = self.body_velocity(eta, eta_dot)
        return np.einsum("...ij,...j->...i", self.leg_jacobian(eta), v)

    def fk(
        self, lengths: ArrayLike, eta0: ArrayLike | None = None, tol: float = 1e-10, max_iter: int = 30
    ) -> StewartFK:
        """Forward kinematics: the pose whose legs have ``lengths``, by Newton's method.

        Newton on f(η) = l(η) − l* with the analytic Jacobian ∂l/∂η = J_l J_s⁻¹ (eqs. 41–45),
        started from ``eta0`` (default: neutral).  Converges quadratically from any start in
        the pose box for these geometries; ``success=False`` with the residual when not.
        """
        target = np.asarray(lengths, dtype=float)
        if target.shape != (6,) or not np.all(np.isfinite(target)):
            raise StewartError(f"forward kinematics needs six finite leg lengths, got {lengths!r}")
        eta = np.zeros(6) if eta0 is None else np.array(eta0, dtype=float)
        res = np.inf
        for it in range(1, max_iter + 1):
            f = self.leg_lengths(eta) - target
            res = float(np.max(np.abs(f)))
            if res < tol:
                return StewartFK(eta, True, res, it - 1)
            Jl = self.leg_jacobian(eta)
            J_eta = Jl.copy()
            J_eta[:, 3:] = Jl[:, 3:] @ T_inverse(eta[3:])  # ∂l/∂δ = (∂l/∂ω) T⁻¹
            try:
                step = np.linalg.solve(J_eta, f)
            except np.linalg.LinAlgError:
                break
            eta = eta - step
            if not np.all(np.isfinite(eta)):
                break
        ok = bool(np.all(np.isfinite(eta))) and res < 1e3 * tol
        return StewartFK(eta if ok else np.zeros(6), ok, float(res), max_iter)

    # ------------------------------------------------------------------ velocity, acceleration
    @staticmethod
    def body_velocity(eta: ArrayLike, eta_dot: ArrayLike) -> NDArray[np.float64]:
        """v = J_s⁻¹ η̇ = (ṗ_b^n, ω_{n,b}^b) (eq. 45); shape (..., 6)."""
        eta, eta_dot = np.asarray(eta, dtype=float), np.asarray(eta_dot, dtype=float)
        w = np.einsum("...ij,...j->...i", T_inverse(eta[..., 3:6]), eta_dot[..., 3:6])
        return np.concatenate([eta_dot[..., :3], w], axis=-1)

    @staticmethod
    def body_acceleration(eta: ArrayLike, eta_dot: ArrayLike, eta_ddot: ArrayLike) -> NDArray[np.float64]:
        """v̇ = J_s⁻¹ (η̈ − J̇_s v) (eq. 50; the paper's η̇ in the bracket is v); shape (..., 6)."""
        eta = np.asarray(eta, dtype=float)
        eta_dot, eta_ddot = np.asarray(eta_dot, dtype=float), np.asarray(eta_ddot, dtype=float)
        d, dd = eta[..., 3:6], eta_dot[..., 3:6]
        w = np.einsum("...ij,...j->...i", T_inverse(d), dd)
        rhs = eta_ddot[..., 3:6] - np.einsum("...ij,...j->...i", T_delta_dot(d, dd), w)
        wd = np.einsum("...ij,...j->...i", T_inverse(d), rhs)
        return np.concatenate([eta_ddot[..., :3], wd], axis=-1)

    @staticmethod
    def rotation_rates(
        eta: ArrayLike, eta_dot: ArrayLike, eta_ddot: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """R_b^n, Ṙ = R S(ω) (eq. 47) and R̈ = R S(ω)² + R S(ω̇) (eq. 51), each (3, 3)."""
        eta = np.asarray(eta, dtype=float)
        v = StewartPlatform.body_velocity(eta, eta_dot)
        vd = StewartPlatform.body_acceleration(eta, eta_dot, eta_ddot)
        R = rotation_xyz(eta[3:6])
        Sw, Swd = skew(v[3:]), skew(vd[3:])
        return R, R @ Sw, R @ Sw @ Sw + R @ Swd

    def __repr__(self) -> str:
        return f"StewartPlatform({self.name!r}, legs {self.leg_min:g}–{self.leg_max:g} m)"
