"""The offshore crane carrying the Delta head: its kinematics and the head references of TAC paper §7–8.

Frames: {n} NED (fixed), {b} vessel body, {t} crane head at the jib tip (x from the base plate
towards the TCP).  The crane (``robots/offshore_crane.xml``) maps β to T_t^b (eq. 41); the
Delta head maps α to p_c^t (§3–4).

References (all functions are batched over time, arrays of shape (n, …)):

* o_t^n = R_b^n o_t^b + o_b^n                                        eq. (49)
* p_ref^t = R_n^t (p_d^n − o_t^n),  R_n^t = (R_t^b)ᵀ (R_b^n)ᵀ            eq. (50)
* α_ref = IPK(p_ref^t) after the workspace check (saturated onto the hull)   eq. (51)
* v_ref^t = Ṙ_n^t p_ref^n + R_n^t ṗ_ref^n                               eq. (52)
* α̇_ref = J⁻¹(p_ref^t, α_ref) v_ref^t                                  eq. (56)

Eqs. (53)–(54) as printed are not the exact derivatives for a p_d^n fixed in {n}: eq. (53)
writes −S(ω_t^b)(R_t^b)ᵀ where (d/dt R_t^b)ᵀ = −(R_t^b)ᵀ S(ω_t^b), and eq. (54) adds the terms
S(ω_t^b) R_t^b p_d^t + v_t^b, which belong to a desired point carried along by a commanded crane
motion.  Here, with ω_b the body angular rate ν₂ = [p q r] and ṗ_d^n the (optional) velocity
of the desired point:

    Ṙ_n^t = −(R_t^b)ᵀ [S(ω_t^b) + S(ω_b)] (R_b^n)ᵀ,
    ṗ_ref^n = ṗ_d^n − R_b^n (ω_b × o_t^b + v_t^b) − ȯ_b^n,     ȯ_b^n = R_b^n ν₁,

which tests check against finite differences; with ṗ_d^n = 0 and a still crane both reduce to
the paper's S(ω) R o_t^b and v_b^n terms.

The formulas above use the papers' R_b^n; the code names it ``R_n_b`` (:mod:`app.geometry`: from {b} to {n}).

The batched references and the crane IK run compiled (:mod:`app.models.crane_head_kernels`) unless
``use_kernels`` is False; the NumPy code here is their reference.  The joint servos that follow these
references are :mod:`app.control.tac` (the head's PID and the cooperative crane law) and :mod:`app.sim.head`
(the crane's joints and the head's motors), wired in :mod:`app.scenes.tac`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.geometry import euler_zyx_to_matrix
from app.models import crane_head_kernels as kern
from app.models.closed_form import ElbowCrane
from app.models.delta import DeltaHead
from app.models.serial import SerialRobot


def _skew_batch(w: NDArray[np.float64]) -> NDArray[np.float64]:
    S = np.zeros((*w.shape[:-1], 3, 3))
    S[..., 0, 1], S[..., 0, 2] = -w[..., 2], w[..., 1]
    S[..., 1, 0], S[..., 1, 2] = w[..., 2], -w[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -w[..., 1], w[..., 0]
    return S


def _mv(M: NDArray, v: NDArray) -> NDArray:
    return np.einsum("...ij,...j->...i", M, v)


def _mtv(M: NDArray, v: NDArray) -> NDArray:
    return np.einsum("...ji,...j->...i", M, v)


@dataclass(frozen=True, eq=False)
class HeadReference:
    """Time series of the head reference (each (n, 3) unless noted)."""

    o_t_n: NDArray[np.float64]
    R_n_t: NDArray[np.float64]  # (n, 3, 3), R_t^n
    p_ref_t: NDArray[np.float64]  # unsaturated, eq. (50)
    p_cmd_t: NDArray[np.float64]  # after the workspace check
    v_ref_t: NDArray[np.float64]  # eq. (52)
    alpha_ref: NDArray[np.float64]  # eq. (51)
    alpha_dot_ref: NDArray[np.float64]  # eq. (56), zero while saturated
    saturated: NDArray[np.bool_]  # (n,)


class CraneHead:
    """The offshore crane with the Delta head at its jib tip (TAC paper §7–8)."""

    def __init__(self, crane: SerialRobot, head: DeltaHead, h: float = 0.25) -> None:
        elbow = ElbowCrane.match(crane)
        if elbow is None:
            raise ValueError(f"{crane.name} is not an elbow crane (TAC paper §7, Table 3)")
        self.crane, self.head = crane, head
        self.workspace = head.workspace(h)
        self.p_d_t = self.workspace.center.copy()  # [x_d, 0, 0], §8
        self.x_d = float(self.p_d_t[0])
        # §8: the crane carrying the TCP at x_d: L2 → L2 + x_d in eqs. (43)–(44)
        self.elbow_tcp = replace(elbow, L2=elbow.L2 + self.x_d)
        sol = head.ik(self.p_d_t)
        self.alpha_d = sol.alpha
        # the compiled kernels' constants (app/models/crane_head_kernels.py)
        e = self.elbow_tcp
        self.kernel_elbow = (float(e.L0), float(e.L1), float(e.L2), kern.c_array(np.linalg.inv(e.T_world_1)))
        ws = self.workspace
        self.kernel_hull = (
            kern.c_array(ws.equations),
            kern.c_array(ws.center),
            float(ws.depth(ws.center)),
        )

    @property
    def use_kernels(self) -> bool:
        """Compiled references and IK (and the head's and crane's kinematics); False: the NumPy reference."""
        return self.head.use_kernels

    @use_kernels.setter
    def use_kernels(self, on: bool) -> None:
        self.head.use_kernels = self.crane.use_kernels = bool(on)

    # ------------------------------------------------------------------ crane
    def crane_pose(self, beta: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """o_t^b (…, 3) and R_t^b (…, 3, 3) of the jib tip, eq. (41)."""
        T = self.crane.fk(beta)
        return T[..., :3, 3], T[..., :3, :3]

    def crane_twist(self, beta: ArrayLike, beta_dot: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """v_t^b and ω_t^b from eq. (45) with the Jacobian of eq. (48)."""
        xi = _mv(self.crane.jacobian(beta), np.asarray(beta_dot, dtype=float))
        return xi[..., :3], xi[..., 3:]

    def crane_ik_tcp(self, p_b: ArrayLike, beta0_hint: float = -math.pi / 2) -> NDArray[np.float64]:
        """β placing the TCP (x_d beyond the jib tip) at p_b in {b}: eqs. (42)–(44), elbow up, L2 + x_d.

        Vectorised over rows of ``p_b``; the slew angle is unwrapped to stay continuous from
        ``beta0_hint``.  Targets out of reach give the stretched-towards configuration (|δ| ≤ 1).
        """
        e = self.elbow_tcp
        p_b = np.atleast_2d(np.asarray(p_b, dtype=float))
        if self.use_kernels:
            return kern.crane_ik_tcp(self.kernel_elbow, kern.c_array(p_b), float(beta0_hint))
        T1 = np.linalg.inv(e.T_world_1)
        p1 = p_b @ T1[:3, :3].T + T1[:3, 3]  # eq. (42)
        x, y, z = p1[:, 0], p1[:, 1], p1[:, 2]
        r = np.hypot(x, y)
        beta0 = np.unwrap(np.concatenate([[beta0_hint], np.arctan2(y, x)]))[1:]  # eq. (43)
        delta = (x**2 + y**2 + (z - e.L0) ** 2 - e.L1**2 - e.L2**2) / (2 * e.L1 * e.L2)  # eq. (44)
        delta = np.clip(delta, -1.0, 1.0)
        beta2 = np.arctan2(-np.sqrt(1.0 - delta**2), delta)  # elbow up: the negative root
        beta1 = np.arctan2(z - e.L0, r) - np.arctan2(e.L2 * np.sin(beta2), e.L1 + e.L2 * np.cos(beta2))
        return np.column_stack([beta0, beta1, beta2])

    def radius(self, beta: ArrayLike, p_t: ArrayLike | None = None) -> float:
        """The crane's radius at β: the TCP's (the head point ``p_t`` in {t}, by default x_d beyond the jib tip)
        horizontal distance from the slewing axis, r of eq. (43) (issue 31, item 4: the load chart's radius)."""
        o, R = self.crane_pose(np.asarray(beta, dtype=float))
        p_b = o + R @ (self.p_d_t if p_t is None else np.asarray(p_t, dtype=float))
        p1 = np.linalg.solve(self.elbow_tcp.T_world_1, np.r_[p_b, 1.0])[:3]
        return float(math.hypot(p1[0], p1[1]))

    def at_radius(self, radius: float, beta: ArrayLike) -> NDArray[np.float64]:
        """β with the TCP at ``radius`` from the slewing axis, at the slew angle and TCP height of ``beta`` (eqs.
        (42)–(44), elbow up); a radius the crane cannot reach there within its joint limits raises ValueError."""
        beta = np.asarray(beta, dtype=float)
        o, R = self.crane_pose(beta)
        T1 = self.elbow_tcp.T_world_1
        p1 = np.linalg.solve(T1, np.r_[o + R @ self.p_d_t, 1.0])[:3]
        phi = math.atan2(p1[1], p1[0])
        q1 = np.array([radius * math.cos(phi), radius * math.sin(phi), p1[2], 1.0])
        target = (T1 @ q1)[:3]
        new = self.crane_ik_tcp(target, float(beta[0]))[0]
        o2, R2 = self.crane_pose(new)
        lo, hi = self.crane.lower, self.crane.upper
        if np.linalg.norm(o2 + R2 @ self.p_d_t - target) > 1e-6 or np.any(new < lo - 1e-9) or np.any(new > hi + 1e-9):
            raise ValueError(f"radius {radius:g} m is out of the crane's reach at this height")
        return new

    def reach(self, beta: ArrayLike, step: float = 0.1) -> tuple[float, float]:
        """The radii [m] the crane reaches at the slew angle and TCP height of ``beta`` (on a ``step`` grid)."""
        ok = []
        for r in np.arange(step, self.elbow_tcp.L1 + self.elbow_tcp.L2 + step, step):
            try:
                self.at_radius(float(r), beta)
                ok.append(float(r))
            except ValueError:
                pass
        if not ok:
            raise ValueError("the crane reaches no radius at this height")
        return ok[0], ok[-1]

    def tcp_n(self, eta: ArrayLike, beta: ArrayLike, p_t: ArrayLike) -> NDArray[np.float64]:
        """A head point p^t expressed in {n}: o_t^n + R_b^n R_t^b p^t."""
        eta = np.asarray(eta, dtype=float)
        R_n_b = euler_zyx_to_matrix(eta[..., 3:6])  # R_b^n, Fossen eq. (2.18)
        o_t_b, R_b_t = self.crane_pose(beta)
        return _mv(R_n_b, o_t_b + _mv(R_b_t, np.asarray(p_t, dtype=float))) + eta[..., :3]

    # ------------------------------------------------------------------ references
    def head_reference(
        self,
        eta: NDArray[np.float64],
        nu: NDArray[np.float64],
        beta: NDArray[np.float64],
        beta_dot: NDArray[np.float64],
        p_d_n: ArrayLike,
        p_d_n_dot: ArrayLike | None = None,
        alpha_hold: NDArray[np.float64] | None = None,
    ) -> HeadReference:
        """Head references of eqs. (49)–(56) for vessel states η, ν (n, 6) and crane β, β̇ (n, 3)."""
        n = eta.shape[0]
        p_d_n = np.broadcast_to(np.asarray(p_d_n, dtype=float), (n, 3))
        p_d_n_dot = np.zeros((n, 3)) if p_d_n_dot is None else np.broadcast_to(p_d_n_dot, (n, 3))
        if self.use_kernels:
            hold = self.alpha_d if alpha_hold is None else alpha_hold
            eta, nu, beta, beta_dot, p_d_n, p_d_n_dot, hold = (
                kern.c_array(x) for x in (eta, nu, beta, beta_dot, p_d_n, p_d_n_dot, hold)
            )
            out = kern.head_reference(
                (self.crane.kernel_record, self.head.kernel_args, self.kernel_hull),
                (eta, nu),
                (beta, beta_dot),
                (p_d_n, p_d_n_dot),
                hold,
            )
            return HeadReference(*out)
        R_n_b = euler_zyx_to_matrix(eta[:, 3:6])  # R_b^n, Fossen eq. (2.18)
        o_t_b, R_b_t = self.crane_pose(beta)
        v_t_b, w_t_b = self.crane_twist(beta, beta_dot)
        o_t_n = _mv(R_n_b, o_t_b) + eta[:, :3]  # eq. (49)
        p_ref_n = p_d_n - o_t_n
        R_n_t = R_n_b @ R_b_t  # R_t^n = R_b^n R_t^b
        p_ref_t = _mtv(R_n_t, p_ref_n)  # eq. (50)
        w_b = nu[:, 3:6]
        # eqs. (52)–(55), exact form (see the module docstring)
        o_b_n_dot = _mv(R_n_b, nu[:, :3])
        p_ref_n_dot = p_d_n_dot - _mv(R_n_b, np.cross(w_b, o_t_b) + v_t_b) - o_b_n_dot
        # Ṙ_n^t (exact eq. 53)
        R_t_n_dot = -np.swapaxes(R_b_t, 1, 2) @ (_skew_batch(w_t_b) + _skew_batch(w_b)) @ np.swapaxes(R_n_b, 1, 2)
        v_ref_t = _mv(R_t_n_dot, p_ref_n) + _mtv(R_n_t, p_ref_n_dot)
        # workspace check and saturation onto the hull (§6, §8), then eq. (51)
        p_cmd, saturated = self.workspace.saturate_many(p_ref_t)
        sol = self.head.ik(p_cmd)
        bad = ~np.all(sol.reachable, axis=1)
        # the hull is convex, the reachable set is not quite: a point inside the hull can still
        # need an arm past its limit; that reference is clipped and counted as saturated
        clipped = ~np.all(sol.within_limits, axis=1) & ~bad
        alpha_ref = np.clip(sol.alpha, self.head.lower, self.head.upper)
        if np.any(bad):  # numerically outside the assembly: hold the last good reference
            hold = self.alpha_d if alpha_hold is None else alpha_hold
            for k in np.flatnonzero(bad):
                alpha_ref[k] = alpha_ref[k - 1] if k > 0 else hold
        # eq. (56) (no feed-forward while saturated: the reference is not moving with v_ref there)
        alpha_dot_ref = self.head.arm_rates(alpha_ref, v_ref_t, p_cmd)
        limited = saturated | bad | clipped
        alpha_dot_ref[limited] = 0.0
        return HeadReference(o_t_n, R_n_t, p_ref_t, p_cmd, v_ref_t, alpha_ref, alpha_dot_ref, limited)
