"""Crane-head (TAC) motion compensation: references of TAC paper §8 and the joint controllers.

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

Joint control: PID on α (eq. 57, Table 4: K_p 10, K_i 60, K_d 1) driving DC motors modelled as
α/u = K_DC/(T_DC s + 1) (eq. 58, T_DC 0.2 s, K_DC 1), discretised exactly (zero-order hold).

The batched references, the crane IK and both servos run compiled (:mod:`app.control.tac_kernels`)
unless ``use_kernels`` is False; the NumPy code here is their reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.control import tac_kernels
from app.geometry import euler_zyx_to_matrix
from app.ik.analytic import ElbowCrane
from app.models.delta import DeltaHead
from app.models.serial import SerialRobot


@dataclass(frozen=True)
class PidGains:
    """Joint PID and DC-motor constants (TAC paper Table 4)."""

    kp: float = 10.0
    ki: float = 60.0
    kd: float = 1.0
    t_dc: float = 0.2  # [s]
    k_dc: float = 1.0


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
    R_t_n: NDArray[np.float64]  # (n, 3, 3)
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
        # the compiled kernels' constants (app/control/tac_kernels.py)
        e = self.elbow_tcp
        self.kernel_elbow = (float(e.L0), float(e.L1), float(e.L2), tac_kernels.c_array(np.linalg.inv(e.T_world_1)))
        ws = self.workspace
        self.kernel_hull = (
            tac_kernels.c_array(ws.equations),
            tac_kernels.c_array(ws.center),
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
            return tac_kernels.crane_ik_tcp(self.kernel_elbow, tac_kernels.c_array(p_b), float(beta0_hint))
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

    def tcp_n(self, eta: ArrayLike, beta: ArrayLike, p_t: ArrayLike) -> NDArray[np.float64]:
        """A head point p^t expressed in {n}: o_t^n + R_b^n R_t^b p^t."""
        eta = np.asarray(eta, dtype=float)
        R_b_n = euler_zyx_to_matrix(eta[..., 3:6])
        o_t_b, R_t_b = self.crane_pose(beta)
        return _mv(R_b_n, o_t_b + _mv(R_t_b, np.asarray(p_t, dtype=float))) + eta[..., :3]

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
            args = (eta, nu, beta, beta_dot, p_d_n, p_d_n_dot, hold)
            out = tac_kernels.head_reference(
                self.crane.kernel_args, self.head.kernel_args, self.kernel_hull,
                *(tac_kernels.c_array(x) for x in args),
            )  # fmt: skip
            return HeadReference(*out)
        R_b_n = euler_zyx_to_matrix(eta[:, 3:6])
        o_t_b, R_t_b = self.crane_pose(beta)
        v_t_b, w_t_b = self.crane_twist(beta, beta_dot)
        o_t_n = _mv(R_b_n, o_t_b) + eta[:, :3]  # eq. (49)
        p_ref_n = p_d_n - o_t_n
        R_t_n = R_b_n @ R_t_b
        p_ref_t = _mtv(R_t_n, p_ref_n)  # eq. (50)
        w_b = nu[:, 3:6]
        # eqs. (52)–(55), exact form (see the module docstring)
        o_b_n_dot = _mv(R_b_n, nu[:, :3])
        p_ref_n_dot = p_d_n_dot - _mv(R_b_n, np.cross(w_b, o_t_b) + v_t_b) - o_b_n_dot
        R_n_t_dot = -np.swapaxes(R_t_b, 1, 2) @ (_skew_batch(w_t_b) + _skew_batch(w_b)) @ np.swapaxes(R_b_n, 1, 2)
        v_ref_t = _mv(R_n_t_dot, p_ref_n) + _mtv(R_t_n, p_ref_n_dot)
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
        return HeadReference(o_t_n, R_t_n, p_ref_t, p_cmd, v_ref_t, alpha_ref, alpha_dot_ref, limited)


# ----------------------------------------------------------------------------- joint servo
@dataclass
class HeadServo:
    """PID (eq. 57) + first-order DC motors (eq. 58) on the three arm angles.

    The D term uses the motor rate α̇ = (K_DC u − α)/T_DC of eq. (58) with the input being
    computed, so eq. (57) is solved for u:  u (1 + K_d K_DC/T_DC) = K_p α̃ + K_i ∫α̃ + K_d (α̇_ref
    + α/T_DC).  (Using the previous step's input instead puts a factor −K_d K_DC/T_DC = −5 on
    u_{k−1}: a discrete loop that oscillates and diverges.)  The input is limited to the joint range widened
    by ``u_margin`` and the integrator stops while the input is limited (anti-windup); the arm
    angles never leave [α_min, α_max] (mechanical stops).
    """

    gains: PidGains
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    alpha: NDArray[np.float64]
    u_margin: float = math.radians(10.0)
    use_kernels: bool = field(default=tac_kernels.ENABLED, repr=False)  # False: the NumPy reference

    def __post_init__(self) -> None:
        self.alpha = np.array(self.alpha, dtype=float)
        self.integral = np.zeros(3)
        self.u = self.alpha / self.gains.k_dc

    def kernel_args(self) -> tuple:
        """(K_p, K_i, K_d, T_DC, K_DC, u_min, u_max, α_min, α_max): the ``pid`` of :mod:`app.control.tac_kernels`."""
        g = self.gains
        u_lo, u_hi = (self.lower - self.u_margin) / g.k_dc, (self.upper + self.u_margin) / g.k_dc
        bounds = (u_lo, u_hi, self.lower, self.upper)
        return (float(g.kp), float(g.ki), float(g.kd), float(g.t_dc), float(g.k_dc)) + tuple(
            tac_kernels.c_array(x) for x in bounds
        )

    def reset(self, alpha: ArrayLike) -> None:
        self.alpha = np.array(alpha, dtype=float)
        self.integral = np.zeros(3)
        self.u = self.alpha / self.gains.k_dc

    def run(
        self, alpha_ref: NDArray[np.float64], alpha_dot_ref: NDArray[np.float64], dt: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Advance len(alpha_ref) steps; returns α (after each step) and u, each (n, 3)."""
        if self.use_kernels:
            alpha, integral, u = (np.array(x, dtype=float) for x in (self.alpha, self.integral, self.u))
            ref, ref_dot = tac_kernels.c_array(alpha_ref), tac_kernels.c_array(alpha_dot_ref)
            out = tac_kernels.head_servo(self.kernel_args(), float(dt), ref, ref_dot, alpha, integral, u)
            self.alpha, self.integral, self.u = alpha, integral, u
            return out
        g = self.gains
        a = math.exp(-dt / g.t_dc)
        b = (1.0 - a) * g.k_dc
        u_lo, u_hi = (self.lower - self.u_margin) / g.k_dc, (self.upper + self.u_margin) / g.k_dc
        lo, hi = self.lower, self.upper
        n = alpha_ref.shape[0]
        out_a = np.empty((n, 3))
        out_u = np.empty((n, 3))
        alpha, integral, u = self.alpha, self.integral, self.u
        implicit = 1.0 + g.kd * g.k_dc / g.t_dc
        kp, ki, kd, inv_t = g.kp, g.ki, g.kd, 1.0 / g.t_dc
        # plain floats per joint: three joints, so Python scalars beat small numpy arrays here
        ref, ref_dot = alpha_ref.tolist(), alpha_dot_ref.tolist()
        alpha, integral, u = self.alpha.tolist(), self.integral.tolist(), self.u.tolist()
        ulo, uhi, lo_, hi_ = u_lo.tolist(), u_hi.tolist(), lo.tolist(), hi.tolist()
        for k in range(n):
            rk, rdk = ref[k], ref_dot[k]
            for j in range(3):
                err = rk[j] - alpha[j]
                trial = integral[j] + err * dt
                u_new = (kp * err + ki * trial + kd * (rdk[j] + alpha[j] * inv_t)) / implicit  # eq. (57)
                if u_new < ulo[j]:
                    u_new = ulo[j]
                elif u_new > uhi[j]:
                    u_new = uhi[j]
                else:
                    integral[j] = trial  # anti-windup: integrate only while the input is free
                u[j] = u_new
                a_new = a * alpha[j] + b * u_new  # eq. (58), zero-order hold
                alpha[j] = lo_[j] if a_new < lo_[j] else hi_[j] if a_new > hi_[j] else a_new
            out_a[k] = alpha
            out_u[k] = u
        alpha, integral, u = np.array(alpha), np.array(integral), np.array(u)
        self.alpha, self.integral, self.u = alpha, integral, u
        return out_a, out_u


# ----------------------------------------------------------------------------- cooperative crane
@dataclass
class CraneServo:
    """Crane joints in cooperative mode: they take the slow, large part of the compensation.

    The crane follows a share ``share`` of the full-compensation configuration β_c (the elbow
    IK with L2 + x_d that keeps the TCP on p_d^n, §8) around the nominal β_d, with the target's
    rate as feed-forward and a proportional correction ``k_p`` [1/s]:

        β̇_cmd = s β̇_c + k_p (β_d + s (β_c − β_d) − β),

    limited to each joint's speed and acceleration and kept inside its position limits.  The head
    takes the rest, through the crane terms of eqs. (49)–(54).
    """

    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    speed: NDArray[np.float64]
    accel: NDArray[np.float64]
    beta: NDArray[np.float64]
    share: float = 1.0
    k_p: float = 1.0
    use_kernels: bool = field(default=tac_kernels.ENABLED, repr=False)  # False: the NumPy reference

    def __post_init__(self) -> None:
        self.beta = np.array(self.beta, dtype=float)
        self.beta_dot = np.zeros(3)

    def kernel_args(self) -> tuple:
        """(β_min, β_max, β̇_max, β̈_max, share, k_p): the ``crane`` of :mod:`app.control.tac_kernels`."""
        limits = (self.lower, self.upper, self.speed, self.accel)
        return tuple(tac_kernels.c_array(x) for x in limits) + (float(self.share), float(self.k_p))

    def run(
        self, beta_d: NDArray[np.float64], beta_c: NDArray[np.float64], beta_c_dot: NDArray[np.float64], dt: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Advance len(beta_c) steps; returns β and β̇ after each step, each (n, 3)."""
        if self.use_kernels:
            beta, beta_dot = np.array(self.beta, dtype=float), np.array(self.beta_dot, dtype=float)
            args = (tac_kernels.c_array(x) for x in (beta_d, beta_c, beta_c_dot))
            out = tac_kernels.crane_servo(self.kernel_args(), *args, float(dt), beta, beta_dot)
            self.beta, self.beta_dot = beta, beta_dot
            return out
        n = beta_c.shape[0]
        out_b = np.empty((n, 3))
        out_v = np.empty((n, 3))
        s, kp = self.share, self.k_p
        beta, bdot = self.beta, self.beta_dot
        dv = self.accel * dt
        for k in range(n):
            target = beta_d + s * (beta_c[k] - beta_d)
            cmd = s * beta_c_dot[k] + kp * (target - beta)
            cmd = np.minimum(np.maximum(cmd, -self.speed), self.speed)
            # braking distance: never run into a position limit faster than the deceleration allows
            room_hi = np.sqrt(2 * self.accel * np.maximum(self.upper - beta, 0.0))
            room_lo = -np.sqrt(2 * self.accel * np.maximum(beta - self.lower, 0.0))
            cmd = np.minimum(np.maximum(cmd, room_lo), room_hi)
            bdot = bdot + np.clip(cmd - bdot, -dv, dv)
            beta = np.minimum(np.maximum(beta + bdot * dt, self.lower), self.upper)
            out_b[k] = beta
            out_v[k] = bdot
        self.beta, self.beta_dot = beta, bdot
        return out_b, out_v
