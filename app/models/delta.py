"""Delta parallel robot used as a three-axis crane head (TAC paper §2–6).

Frames: {t} has its origin at the base-plate centre and x from the base towards the top
plate; arm i has the frame {t_i} = R_x(rot_i) {t} (eq. 1).  Arm angle α_i; the indented knee
(eq. 4, which agrees with eqs. 9 and 28; eq. 3 writes the knee with α replaced by π/2 − α):

    c_i^t = R_{t_i}^t [l_a sin α_i,  a − l_a cos α_i,  0]ᵀ,   a = l_p − l_k,

and the loop closure |p_c^t − c_i^t| = l_r (eq. 6).

* Inverse kinematics (eqs. 8–16): in {t_i} the closure is E cos α + F sin α + G = 0 with
  E = 2 l_a (y − a), F = −2 l_a x, G = x² + (y − a)² + z² + l_a² − l_r², the form of eq. (11).
  Instead of the tangent half-angle quadratic (eqs. 13–15), which divides by G − E, it is
  solved as cos(α − φ) = −G/√(E² + F²), φ = atan2(F, E): the same two roots, no division by
  a vanishing number.  The knees-out root (the smaller α, |α| < π/2) is taken (eq. 16).
* Forward kinematics (eqs. 17–25): the intersection of three spheres of radius l_r about
  c_i, by trilateration (two plane differences give a line, one quadratic gives the points);
  the solution above the base, larger x, is returned.  Equivalent to eqs. (22)–(25) but it
  needs no inverse of C (eq. 21), which is singular whenever the c_i are coplanar with o_t.
* Jacobian (eq. 32): ṗ = A⁻¹ B α̇, rows of A = (p − c_i)ᵀ, B = diag((p − c_i)·d_i), d_i = ∂c_i/∂α_i (eq. 28);
  its inverse α̇ = B⁻¹ A ṗ row by row (:meth:`DeltaHead.arm_rates`).
* Workspace (§6): a grid of step h over the box of eq. (33), IK-feasible points within the
  joint limits, their convex hull, an inside test, and saturation of a reference onto the hull
  along the ray from the workspace centre.

The inverse and forward kinematics run compiled (:mod:`app.models.crane_head_kernels`) unless
``use_kernels`` is False; the NumPy code here is their reference.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.geometry import rot_x
from app.models import crane_head_kernels as kern
from app.models.model import JointModel
from app.models.spec import RobotSpec

if TYPE_CHECKING:  # scipy.spatial takes 0.45 s to import: only the workspace study needs it, not every engine
    from scipy.spatial import ConvexHull


@dataclass(frozen=True, eq=False)
class DeltaIK:
    """Arm angles for a TCP position; ``reachable`` per arm (False: the sphere misses the arm circle)."""

    alpha: NDArray[np.float64]
    reachable: NDArray[np.bool_]
    within_limits: NDArray[np.bool_]

    @property
    def ok(self) -> bool:
        return bool(self.reachable.all() and self.within_limits.all())


class DeltaHead(JointModel):
    """Kinematics of a Delta mechanism from a ``delta`` robot spec (any geometry)."""

    kind = "delta"

    def __init__(self, spec: RobotSpec) -> None:
        super().__init__(spec)
        d = spec.delta
        self.l_k, self.l_a, self.l_r, self.l_p = d.l_k, d.l_a, d.l_r, d.l_p
        self.a = d.l_p - d.l_k
        self.R = rot_x(d.arm_rotations)  # (3, 3, 3): R_{t_i}^t
        self.n_joints = 3
        self.joint_names = ["alpha1", "alpha2", "alpha3"]
        self.joint_kinds = ["revolute"] * 3
        self.lower = np.full(3, d.alpha_min)
        self.upper = np.full(3, d.alpha_max)
        self.speed = np.full(3, d.speed)
        self.accel = np.full(3, np.inf if d.accel is None else d.accel)
        self._workspace: dict[float, DeltaWorkspace] = {}
        # the compiled kernels' constants (app/control/kern.py); use_kernels=False: the NumPy reference
        self.kernel_args = (
            float(self.l_a), float(self.a), float(self.l_r), kern.c_array(self.R),
            kern.c_array(self.lower), kern.c_array(self.upper),
        )  # fmt: skip
        self.use_kernels = kern.ENABLED

    # ------------------------------------------------------------------ geometry
    def knees(self, alpha: ArrayLike) -> NDArray[np.float64]:
        """Indented knee points c_i^t, eq. (4); alpha shape (..., 3) → (..., 3, 3) (arm, xyz)."""
        alpha = np.asarray(alpha, dtype=float)
        local = np.stack([self.l_a * np.sin(alpha), self.a - self.l_a * np.cos(alpha), np.zeros_like(alpha)], axis=-1)
        return np.einsum("ijk,...ik->...ij", self.R, local)

    def knee_rates(self, alpha: ArrayLike) -> NDArray[np.float64]:
        """d_i^t = ∂c_i/∂α_i, eq. (28); shape (..., 3, 3)."""
        alpha = np.asarray(alpha, dtype=float)
        local = np.stack([self.l_a * np.cos(alpha), self.l_a * np.sin(alpha), np.zeros_like(alpha)], axis=-1)
        return np.einsum("ijk,...ik->...ij", self.R, local)

    # ------------------------------------------------------------------ inverse kinematics
    def ik(self, p_t: ArrayLike) -> DeltaIK:
        """Arm angles reaching TCP position(s) p_t (shape (..., 3)), knees out (eqs. 8–16)."""
        p = np.asarray(p_t, dtype=float)
        if self.use_kernels and p.shape[-1:] == (3,):
            out = kern.delta_ik(self.kernel_args, kern.c_array(p.reshape(-1, 3)))
            alpha, reachable, within = (x.reshape(p.shape) for x in out)
            return DeltaIK(alpha, reachable, within)
        p_i = np.einsum("ikj,...k->...ij", self.R, p)  # p in each {t_i}: R^T p, eq. (2)
        x, y, z = p_i[..., 0], p_i[..., 1], p_i[..., 2]
        E = 2.0 * self.l_a * (y - self.a)
        F = -2.0 * self.l_a * x
        G = x**2 + (y - self.a) ** 2 + z**2 + self.l_a**2 - self.l_r**2
        R = np.hypot(E, F)
        ratio = np.divide(-G, R, out=np.full_like(G, np.inf), where=R > 1e-12)
        reachable = np.abs(ratio) <= 1.0
        phi = np.arctan2(F, E)
        delta = np.arccos(np.clip(ratio, -1.0, 1.0))
        roots = np.stack([phi - delta, phi + delta], axis=-1)
        roots = (roots + np.pi) % (2 * np.pi) - np.pi  # into (−π, π]
        # knees out: the root nearer the arm's zero (|α| < π/2), i.e. the smaller |α|
        alpha = np.take_along_axis(roots, np.argmin(np.abs(roots), axis=-1)[..., None], axis=-1)[..., 0]
        return DeltaIK(alpha, reachable, self.within_limits(alpha) & reachable)

    # ------------------------------------------------------------------ forward kinematics
    def fk(self, alpha: ArrayLike) -> NDArray[np.float64]:
        """TCP position p_c^t for arm angles, the sphere intersection above the base.

        Raises
        ------
        ValueError
            When the three spheres do not meet (no assembly exists for these angles).
        """
        alpha = np.asarray(alpha, dtype=float)
        if self.use_kernels and alpha.shape[-1:] == (3,):
            p = kern.delta_fk(self.kernel_args, kern.c_array(alpha.reshape(-1, 3)))
            return p.reshape(alpha.shape)
        c = self.knees(alpha)
        c1, c2, c3 = c[..., 0, :], c[..., 1, :], c[..., 2, :]
        # (p − c_j)² − (p − c_1)² = 0  ⇒  2 (c_1 − c_j)·p = |c_1|² − |c_j|²,  j = 2, 3
        u, v = c2 - c1, c3 - c1
        n = np.cross(u, v)
        nn = np.sum(n * n, axis=-1)
        if np.any(nn < 1e-18):
            raise ValueError("knee points are collinear: forward kinematics undefined")
        b2 = 0.5 * (np.sum(c2 * c2, -1) - np.sum(c1 * c1, -1))
        b3 = 0.5 * (np.sum(c3 * c3, -1) - np.sum(c1 * c1, -1))
        # point on the line: p0 = (b2 (v × n) + b3 (n × u)) / |n|² satisfies u·p0 = b2, v·p0 = b3, n·p0 = 0
        p0 = (b2[..., None] * np.cross(v, n) + b3[..., None] * np.cross(n, u)) / nn[..., None]
        w = p0 - c1
        nu = n / np.sqrt(nn)[..., None]
        # |w + t nu|² = l_r²
        bq = np.sum(w * nu, -1)
        cq = np.sum(w * w, -1) - self.l_r**2
        disc = bq**2 - cq
        if np.any(disc < -1e-9):
            raise ValueError("the rods cannot meet for these arm angles")
        root = np.sqrt(np.maximum(disc, 0.0))
        t1, t2 = -bq + root, -bq - root
        p1 = p0 + t1[..., None] * nu
        p2 = p0 + t2[..., None] * nu
        above = p1[..., 0] >= p2[..., 0]  # the solution above the base plate (larger x)
        return np.where(above[..., None], p1, p2)

    def position(self, alpha: ArrayLike) -> NDArray[np.float64]:
        return self.fk(alpha)

    # ------------------------------------------------------------------ velocity kinematics
    def jacobian(self, alpha: ArrayLike, p_t: ArrayLike | None = None) -> NDArray[np.float64]:
        """J(p, α) of eq. (32): ṗ_c^t = J α̇; alpha (..., 3) → shape (..., 3, 3)."""
        alpha = np.asarray(alpha, dtype=float)
        p = self.fk(alpha) if p_t is None else np.asarray(p_t, dtype=float)
        c = self.knees(alpha)
        d = self.knee_rates(alpha)
        s = p[..., None, :] - c  # s_i = p − c_i, eq. (5)
        B = np.sum(s * d, axis=-1)[..., None] * np.eye(3)
        return np.linalg.solve(s, B)

    def arm_rates(self, alpha: ArrayLike, p_dot: ArrayLike, p_t: ArrayLike | None = None) -> NDArray[np.float64]:
        """α̇ for a TCP velocity ṗ_c^t: eq. (32) solved for α̇ = B⁻¹ A ṗ, i.e. α̇_i = (p − c_i)·ṗ / ((p − c_i)·d_i).

        The same as ``solve(jacobian(alpha, p), p_dot)`` without forming J = A⁻¹ B; shapes (..., 3).
        """
        alpha = np.asarray(alpha, dtype=float)
        p = self.fk(alpha) if p_t is None else np.asarray(p_t, dtype=float)
        s = p[..., None, :] - self.knees(alpha)
        num = np.sum(s * np.asarray(p_dot, dtype=float)[..., None, :], axis=-1)
        return num / np.sum(s * self.knee_rates(alpha), axis=-1)

    # ------------------------------------------------------------------ workspace
    def workspace(self, h: float = 0.25) -> DeltaWorkspace:
        """Workspace of §6 on a grid of step h [m] (cached per h)."""
        if not h > 0:
            raise ValueError("grid step h must be positive")
        if h not in self._workspace:
            self._workspace[h] = DeltaWorkspace.compute(self, h)
        return self._workspace[h]


@dataclass(eq=False)
class DeltaWorkspace:
    """IK-feasible grid points, their convex hull, an inside test and saturation (TAC §6)."""

    points: NDArray[np.float64]
    hull: ConvexHull
    h: float
    center: NDArray[np.float64]

    @staticmethod
    def compute(head: DeltaHead, h: float) -> DeltaWorkspace:
        x_max = head.l_a + head.l_r  # eq. (33)
        yz = head.l_r + head.l_p - head.l_k
        xs = np.arange(0.0, x_max + 1e-9, h)
        ys = np.arange(-yz, yz + 1e-9, h)
        X, Y, Z = np.meshgrid(xs, ys, ys, indexing="ij")
        grid = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
        sol = head.ik(grid)
        ok = np.all(sol.reachable & sol.within_limits, axis=-1)
        pts = grid[ok]
        if len(pts) < 4:
            raise ValueError(f"no workspace found with grid step {h} m; use a smaller step")
        from scipy.spatial import ConvexHull

        hull = ConvexHull(pts)
        ws = DeltaWorkspace(pts, hull, h, np.zeros(3))
        ws.center = np.array([ws.best_x_on_axis(), 0.0, 0.0])
        return ws

    @property
    def equations(self) -> NDArray[np.float64]:
        return self.hull.equations  # rows (n, b): n·x + b ≤ 0 inside, |n| = 1

    def depth(self, p: ArrayLike) -> NDArray[np.float64]:
        """Signed distance to the hull boundary: positive inside [m]."""
        p = np.asarray(p, dtype=float)
        eq = self.equations
        return -np.max(p @ eq[:, :3].T + eq[:, 3], axis=-1)

    def inside(self, p: ArrayLike, tol: float = 1e-9) -> NDArray[np.bool_]:
        return self.depth(p) >= -tol

    def best_x_on_axis(self, n: int = 400) -> float:
        """x_d: the point (x, 0, 0) deepest inside the hull (largest free motion in all directions)."""
        xs = np.linspace(self.points[:, 0].min(), self.points[:, 0].max(), n)
        depth = self.depth(np.column_stack([xs, np.zeros(n), np.zeros(n)]))
        return float(xs[int(np.argmax(depth))])

    def saturate(self, p: ArrayLike, center: ArrayLike | None = None) -> tuple[NDArray[np.float64], bool]:
        """A reference inside the hull: p itself, or the hull point on the segment from the centre to p.

        Returns (point, saturated).
        """
        p = np.asarray(p, dtype=float)
        c = self.center if center is None else np.asarray(center, dtype=float)
        if self.inside(p):
            return p.copy(), False
        eq = self.equations
        n, b = eq[:, :3], eq[:, 3]
        direction = p - c
        num = -(n @ c + b)  # > 0 for a centre inside
        den = n @ direction
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(den > 1e-15, num / den, np.inf)
        t_exit = float(np.clip(np.min(t), 0.0, 1.0))
        return c + t_exit * direction, True

    def saturate_many(self, p: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """:meth:`saturate` for points of shape (n, 3) towards ``self.center``; returns (points, saturated)."""
        p = np.atleast_2d(np.asarray(p, dtype=float))
        c = self.center
        eq = self.equations
        n, b = eq[:, :3], eq[:, 3]
        outside = ~self.inside(p)
        out = p.copy()
        if np.any(outside):
            direction = p[outside] - c
            num = -(n @ c + b)
            den = direction @ n.T
            with np.errstate(divide="ignore", invalid="ignore"):
                t = np.where(den > 1e-15, num / den, np.inf)
            t_exit = np.clip(np.min(t, axis=1), 0.0, 1.0)
            out[outside] = c + t_exit[:, None] * direction
        return out, outside


def default_center(head: DeltaHead, h: float = 0.25) -> NDArray[np.float64]:
    """p_d^t = [x_d, 0, 0] of §8, from the workspace."""
    return head.workspace(h).center


def workspace_radius_on_axis(ws: DeltaWorkspace) -> float:
    """Free motion around the centre in every direction [m] (depth of the centre)."""
    return float(ws.depth(ws.center))


__all__ = ["DeltaHead", "DeltaIK", "DeltaWorkspace", "default_center", "workspace_radius_on_axis"]
