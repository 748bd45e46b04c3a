"""Serial chains from standard DH tables: forward kinematics and the geometric Jacobian.

The DH variables are an affine function of the user's joint vector q:

    θ = θ₀ + M_θ q,    d = d₀ + M_d q,

where row i of M_θ (or M_d) carries the joint's sign and its coupling factors (robot
XML format, ``robots/README.md``).  The geometric Jacobian with respect to q is
therefore the chain rule of the Jacobian with respect to (θ, d):

    J_q = J_θ M_θ + J_d M_d,

with the columns of TAC paper eq. (47): [z_{i-1} × (o_n − o_{i-1}); z_{i-1}] for θ_i
and [z_{i-1}; 0] for d_i.  Every function accepts a batch of configurations
q with shape (..., n) so that a whole GA population is evaluated in one call.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.geometry import dh_transform
from app.models import kernels
from app.models.model import JointModel
from app.models.spec import RobotSpec


class SerialRobot(JointModel):
    """Kinematic model of a serial manipulator.

    Parameters
    ----------
    spec : RobotSpec
        A spec of type ``serial``.

    Attributes
    ----------
    name : str
    n_joints : int
    lower, upper : ndarray, shape (n,)
        Joint position limits [rad or m].
    speed : ndarray, shape (n,)
        Joint speed limits.
    accel : ndarray, shape (n,)
        Joint acceleration limits; ``inf`` where the file gives none.
    """

    kind = "serial"

    def __init__(self, spec: RobotSpec) -> None:
        super().__init__(spec)
        s = spec.serial
        self.links = s.links
        self.joints = s.joints
        self.n_links = len(s.links)
        self.n_joints = len(s.joints)
        self.joint_names = [j.name for j in s.joints]
        self.joint_kinds = [j.kind for j in s.joints]
        self.lower = np.array([j.lower for j in s.joints], dtype=float)
        self.upper = np.array([j.upper for j in s.joints], dtype=float)
        self.speed = np.array([j.speed for j in s.joints])
        self.accel = np.array([np.inf if j.accel is None else j.accel for j in s.joints])
        self.T_world_base = np.array(s.T_world_base)
        self.T_flange_tool = np.array(s.T_flange_tool)

        self._theta0 = np.array([link.theta for link in s.links])
        self._d0 = np.array([link.d for link in s.links])
        self._a = np.array([link.a for link in s.links])
        self._alpha = np.array([link.alpha for link in s.links])
        self._cos_alpha, self._sin_alpha = np.cos(self._alpha), np.sin(self._alpha)
        self._ca_list = [float(v) for v in self._cos_alpha]
        self._sa_list = [float(v) for v in self._sin_alpha]
        self._a_list = [float(v) for v in self._a]
        self._M_theta = np.zeros((self.n_links, self.n_joints))
        self._M_d = np.zeros((self.n_links, self.n_joints))
        for j, joint in enumerate(s.joints):
            M = self._M_theta if joint.kind == "revolute" else self._M_d
            offset = self._theta0 if joint.kind == "revolute" else self._d0
            M[joint.link, j] += joint.sign
            offset[joint.link] += joint.offset
            for k, factor in joint.coupling:
                M[joint.link, k] += factor
        # the chain's constants for compiled kernels, built once here (use_kernels=False: the NumPy reference):
        # the robot record of app/models/kernels.py, passed whole as one argument, dh (5, L) θ₀, d₀, a, cos α,
        # sin α; M (2, L, n) M_θ, M_d; T (2, 4, 4) T_world_base, T_flange_tool (three arrays, not nine: numba's
        # per-call type check of a tuple grows with its elements)
        self.kernel_record = tuple(
            np.ascontiguousarray(np.stack(x), dtype=float)
            for x in ((self._theta0, self._d0, self._a, self._cos_alpha, self._sin_alpha), (self._M_theta, self._M_d),
                      (self.T_world_base, self.T_flange_tool))
        )  # fmt: skip
        self.use_kernels = kernels.ENABLED

    # ------------------------------------------------------------ kinematics
    def dh_variables(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """θ and d of every link, shapes (..., n_links), from q with shape (..., n_joints)."""
        q = np.asarray(q, dtype=float)
        theta = self._theta0 + q @ self._M_theta.T
        d = self._d0 + q @ self._M_d.T
        return theta, d

    def frames(self, q: ArrayLike) -> NDArray[np.float64]:
        """World poses of every DH frame and of the tool.

        Returns
        -------
        ndarray, shape (..., n_links + 2, 4, 4)
            Index 0 is frame 0 (the base, ``T_world_base``), index i the frame after
            link i (TAC paper eq. 39, premultiplied by the base transform), and the
            last index the tool frame (flange · ``T_flange_tool``).
        """
        q = np.asarray(q, dtype=float)
        if self.use_kernels and q.ndim == 1 and q.shape[0] == self.n_joints:
            return kernels.frames(self.kernel_record, np.ascontiguousarray(q))
        theta, d = self.dh_variables(q)
        A = dh_transform(theta, d, self._a, self._alpha)  # (..., L, 4, 4)
        batch = A.shape[:-3]
        out = np.empty(batch + (self.n_links + 2, 4, 4))
        T = np.broadcast_to(self.T_world_base, batch + (4, 4))
        out[..., 0, :, :] = T
        for i in range(self.n_links):
            T = T @ A[..., i, :, :]
            out[..., i + 1, :, :] = T
        out[..., -1, :, :] = T @ self.T_flange_tool
        return out

    def fk(self, q: ArrayLike) -> NDArray[np.float64]:
        """World pose of the tool, shape (..., 4, 4)."""
        return self.frames(q)[..., -1, :, :]

    def position(self, q: ArrayLike) -> NDArray[np.float64]:
        """World position of the tool point [m], shape (..., 3).

        Same result as ``fk(q)[..., :3, 3]`` but applies the links to the tool point as a
        vector, last link first (A_i p = Rz(θ_i)(Tz(d_i)(Tx(a_i)(Rx(α_i) p)))), which skips
        building 4×4 matrices: several times faster on a GA population.
        """
        q = np.asarray(q, dtype=float)
        if self.use_kernels and q.shape[-1:] == (self.n_joints,) and q.ndim <= 2:
            if q.ndim == 1:
                return kernels.position(self.kernel_record, np.ascontiguousarray(q))
            return kernels.positions(self.kernel_record, np.ascontiguousarray(q))
        if q.ndim == 1:
            return self._position_one(q)
        theta, d = self.dh_variables(q)
        ct, st = np.cos(theta), np.sin(theta)
        p_tool = self.T_flange_tool[:3, 3]
        x = np.full(theta.shape[:-1], p_tool[0])
        y = np.full(theta.shape[:-1], p_tool[1])
        z = np.full(theta.shape[:-1], p_tool[2])
        for i in range(self.n_links - 1, -1, -1):
            ca, sa = self._cos_alpha[i], self._sin_alpha[i]
            y, z = ca * y - sa * z, sa * y + ca * z + d[..., i]
            x = x + self._a[i]
            c, s = ct[..., i], st[..., i]
            x, y = c * x - s * y, s * x + c * y
        p = np.stack([x, y, z], axis=-1)
        return p @ self.T_world_base[:3, :3].T + self.T_world_base[:3, 3]

    def _position_one(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """The same recursion on Python floats: one configuration costs microseconds, not numpy calls."""
        theta, d = self.dh_variables(q)
        x, y, z = (float(v) for v in self.T_flange_tool[:3, 3])
        for i in range(self.n_links - 1, -1, -1):
            ca, sa = self._ca_list[i], self._sa_list[i]
            y, z = ca * y - sa * z, sa * y + ca * z + d[i]
            x += self._a_list[i]
            c, s = math.cos(theta[i]), math.sin(theta[i])
            x, y = c * x - s * y, s * x + c * y
        R, t = self.T_world_base[:3, :3], self.T_world_base[:3, 3]
        return R @ np.array([x, y, z]) + t

    def jacobian(self, q: ArrayLike) -> NDArray[np.float64]:
        """Geometric Jacobian of the tool with respect to q, in the world frame.

        Rows are (v_x, v_y, v_z, ω_x, ω_y, ω_z): ξ = J q̇ (TAC paper eqs. 45–47),
        with prismatic joints and couplings handled through M_θ and M_d.

        Returns
        -------
        ndarray, shape (..., 6, n_joints)
        """
        q = np.asarray(q, dtype=float)
        if self.use_kernels and q.ndim == 1 and q.shape[0] == self.n_joints:
            F = kernels.frames(self.kernel_record, np.ascontiguousarray(q))
            return kernels.jacobian_from_frames(F, self._M_theta, self._M_d)
        F = self.frames(q)
        z = F[..., :-2, :3, 2]  # z_{i-1} for links i = 1..L, shape (..., L, 3)
        o = F[..., :-2, :3, 3]  # o_{i-1}
        o_tool = F[..., -1:, :3, 3]
        J_theta = np.concatenate([np.cross(z, o_tool - o), z], axis=-1)  # (..., L, 6)
        J_d = np.concatenate([z, np.zeros_like(z)], axis=-1)
        J = np.swapaxes(J_theta, -1, -2) @ self._M_theta + np.swapaxes(J_d, -1, -2) @ self._M_d
        return J

    def __repr__(self) -> str:
        return f"SerialRobot({self.name!r}, joints={self.joint_names})"
