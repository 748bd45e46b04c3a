"""The Motion-Lab: two Stewart platforms, the Comau robot on EM8000, its winch and the hanging load.

Frames (Motion-Lab paper Table 4): world {g} (z-up), platform neutral frames {n1}, {n2} and body
frames {b1}, {b2} (z-down), robot base {r} (z-up), tool point {t}.  The pendulum is integrated in
{d}, the world turned half a turn about x (z-down, gravity along +z_d), where eq. (23) puts the
load below the tool at rest.

Equations and corrections (each checked by a test in ``tests/test_motionlab.py``):

* Comau tool point eq. (3) with L = d4 + d6 + d_tp, Jacobian eq. (5), acceleration eq. (6) — closed
  form, checked against the DH chain and finite differences.
* Tool point on the moving platform eqs. (54)–(57).  The paper says ṗ^g = ṗ^n1 because H^g_n1 is
  constant; constant, but not the identity (the calibration swaps x, y and flips z), so here
  ṗ^g = R^g_n1 ṗ^n1 and p̈^g = R^g_n1 p̈^n1.
* Pendulum eqs. (29)–(30) / (60)–(61) from the Lagrangian (25)–(28) in a z-down frame: the printed
  z̈_t terms have the wrong sign for that frame (a tool accelerating downwards must *lower* the
  effective gravity, g − z̈_t); derived again here, with a viscous damping term −c φ̇:

      L α̈ = ẍ cα + ÿ sα sβ + z̈ sα cβ − g sα cβ − 2 L̇ α̇ − L β̇² sα cα − c L α̇
      L cα β̈ = −ÿ cβ + z̈ sβ − g sβ − 2 L̇ β̇ cα + 2 L α̇ β̇ sα − c L cα β̇

  integrated with fixed-step RK4 (tool acceleration and wire speed held over the step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.errors import BosunError
from app.models.block import Block
from app.models.closed_form import ComauArm
from app.models.lab import LabLayout
from app.models.pendulum import swing_derivative, swing_rk4
from app.models.registry import load_robot
from app.models.stewart import StewartPlatform
from app.sim import kernels as sim_kernels
from app.sim.stewart import MotionFilter, Platform

G = 9.81
R_G_D = np.diag([1.0, -1.0, -1.0])  # {d} (z-down) in {g} (z-up): half a turn about x
COMAU_MODES = ("settled", "remote", "motion_comp", "hold")  # hold: after an E-STOP reset, until commanded
WINCH_MODES = ("local", "remote", "motion_comp")
REMOTE_TOOL_SPEED = 0.25  # m/s at full stick (Comau REMOTE)


class LabError(BosunError):
    """A Motion-Lab command that cannot be carried out (one line)."""


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
    eta: NDArray[np.float64],
    eta_dot: NDArray[np.float64],
    eta_ddot: NDArray[np.float64],
    q: NDArray[np.float64],
    qd: NDArray[np.float64],
    qdd: NDArray[np.float64],
    rates: tuple[NDArray, NDArray, NDArray] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Tool-point position, velocity, acceleration in the platform's neutral frame {n1}.

    Eqs. (54), (56), (57): p = p_b + R (p_r + R_r p_t^r), ṗ = ṗ_b + Ṙ(p_r + R_r p_t^r) + R R_r ṗ_t^r,
    p̈ = p̈_b + R̈(p_r + R_r p_t^r) + 2Ṙ R_r ṗ_t^r + R R_r p̈_t^r, with Ṙ, R̈ of eqs. (47), (51)
    (``rates`` = (R, Ṙ, R̈) when the caller has them already).
    """
    R, Rd, Rdd = StewartPlatform.rotation_rates(eta, eta_dot, eta_ddot) if rates is None else rates
    R_r, p_r = T_b1_r[:3, :3], T_b1_r[:3, 3]
    p_tr, v_tr, a_tr = comau.position(q), comau.velocity(q, qd), comau.acceleration(q, qd, qdd)
    arm = p_r + R_r @ p_tr
    p = eta[:3] + R @ arm
    v = eta_dot[:3] + Rd @ arm + R @ (R_r @ v_tr)
    a = eta_ddot[:3] + Rdd @ arm + 2 * Rd @ (R_r @ v_tr) + R @ (R_r @ a_tr)
    return p, v, a


# ----------------------------------------------------------------------------- pendulum
def _pendulum_reference(x, u, p, dt):
    """The NumPy reference of :data:`PENDULUM`: one RK4 step of :func:`app.models.pendulum.swing_rk4`."""
    a, b, ad, bd = (float(v) for v in swing_rk4(np.array(x, dtype=float), dt, u[0], u[1], u[2], p[0], p[1]))
    return (a, b, ad, bd), (a, b)


#: the suspended load as a block (app.models.block): the plant of eqs. (29)–(30), RK4 over a step
PENDULUM = Block(
    "load (spherical pendulum)",
    state=("alpha", "beta", "alpha_dot", "beta_dot"),
    inputs=("a_t_d", "L", "L_dot"),
    outputs=("alpha", "beta"),
    params=("damping", "g"),
    reference=_pendulum_reference,
    kernel=sim_kernels.pendulum_block,
)


@dataclass
class Pendulum:
    """The 2-DOF spherical pendulum of eqs. (29)–(30) (corrected z̈ sign, see module doc), RK4.

    State x = (α, β, α̇, β̇) [rad, rad/s]; α about ^φβ y, β about x (Fig. 16).  :meth:`step` is
    compiled unless ``use_kernels`` is False (then :meth:`derivative` in NumPy, the reference).
    """

    damping: float = 0.0  # c [1/s]
    g: float = G
    alpha: float = 0.0
    beta: float = 0.0
    alpha_dot: float = 0.0
    beta_dot: float = 0.0
    use_kernels: bool = field(default=sim_kernels.ENABLED, repr=False)

    def derivative(self, x: NDArray[np.float64], a_t: NDArray[np.float64], L: float, Ld: float) -> NDArray[np.float64]:
        """ẋ of eqs. (29)–(30) (:func:`app.models.pendulum.swing_derivative` with this load's c and g)."""
        return swing_derivative(x, a_t, L, Ld, self.damping, self.g)

    def step(self, dt: float, a_t_d: NDArray[np.float64], L: float, Ld: float) -> None:
        """Advance by dt: tool acceleration a_t_d in {d} held, wire length L + Ld·s over the step (one step of
        :data:`PENDULUM`, compiled unless ``use_kernels`` is False)."""
        x = (float(self.alpha), float(self.beta), float(self.alpha_dot), float(self.beta_dot))
        u = (np.ascontiguousarray(a_t_d, dtype=float), float(L), float(Ld))
        p = (float(self.damping), float(self.g))
        (self.alpha, self.beta, self.alpha_dot, self.beta_dot), _ = PENDULUM.step(x, u, p, float(dt), self.use_kernels)

    def direction(self) -> NDArray[np.float64]:
        """Unit wire vector in {d}: (−sα, cα sβ, cα cβ) of eq. (23)."""
        sa, ca, sb, cb = math.sin(self.alpha), math.cos(self.alpha), math.sin(self.beta), math.cos(self.beta)
        return np.array([-sa, ca * sb, ca * cb])

    def direction_rate(self) -> NDArray[np.float64]:
        """d/dt of :meth:`direction` (the bracket of eq. 24 / 59)."""
        a, b, ad, bd = self.alpha, self.beta, self.alpha_dot, self.beta_dot
        sa, ca, sb, cb = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
        return np.array([-ad * ca, -ad * sa * sb + bd * ca * cb, -ad * sa * cb - bd * ca * sb])

    def energy(self, L: float, v_t: NDArray[np.float64] | None = None, m: float = 1.0) -> float:
        """Kinetic + potential energy, eqs. (26)–(27), with the tool moving at v_t (in {d})."""
        v_p = (np.zeros(3) if v_t is None else v_t) + L * self.direction_rate()
        return 0.5 * m * float(v_p @ v_p) + m * self.g * L * (1 - math.cos(self.alpha) * math.cos(self.beta))

    @property
    def swing(self) -> float:
        """Angle of the wire from the vertical [rad]."""
        return math.acos(max(-1.0, min(1.0, math.cos(self.alpha) * math.cos(self.beta))))


# ----------------------------------------------------------------------------- winch
class Winch:
    """Wire length L_w within [min, max], speed and acceleration limits (a 1-DOF motion filter).

    Modes: ``local`` (speed from the operator's spring-return slider), ``remote`` (speed from a
    client or the joystick), ``motion_comp`` (length that keeps the payload height fixed
    relative to EM1500, with feed-forward).
    """

    def __init__(self, spec: dict) -> None:
        self.spec = spec
        self.filter = MotionFilter([spec["min_length"]], [spec["max_length"]], [spec["speed"]], [spec["accel"]], 0.05)
        self.filter.reset([spec["start_length"]])
        self.mode = "local"
        self.speed_command = 0.0

    @property
    def length(self) -> float:
        return float(self.filter.x[0])

    @property
    def speed(self) -> float:
        return float(self.filter.v[0])

    def step(self, dt: float, L_ref: float | None = None, Ld_ref: float = 0.0) -> None:
        if L_ref is None:  # speed control: integrate the commanded speed as the reference
            v = float(np.clip(self.speed_command, -self.spec["speed"], self.spec["speed"]))
            self.filter.step(self.filter.x + v * dt, [v], dt)
        else:
            self.filter.step([L_ref], [Ld_ref], dt)


# ----------------------------------------------------------------------------- the lab
@dataclass
class LabSample:
    """One instant of the lab (all vectors as lists in the JSON snapshot; arrays here)."""

    t: float
    eta1: NDArray[np.float64]
    eta2: NDArray[np.float64]
    legs1: NDArray[np.float64]
    legs2: NDArray[np.float64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64]
    p_t_g: NDArray[np.float64]
    v_t_g: NDArray[np.float64]
    p_p_g: NDArray[np.float64]
    p_w_g: NDArray[np.float64]
    e_t_b2: NDArray[np.float64]  # tool point minus work point, in {b2}
    L_w: float
    L_w_dot: float
    swing: tuple[float, float]
    payload_height_error: float


class MotionLab:
    """The whole lab, stepped at a fixed dt: platforms → robot control → winch → pendulum.

    With ``use_kernels`` (the default when numba is there) a step is a handful of compiled calls:
    per platform its source (the vessel motion) and its clamped, filtered target, then
    :func:`app.sim.kernels.lab_step` for the rest, which updates the state arrays (joints, winch,
    tool point, rates) in place; with ``use_kernels = False`` every part runs its NumPy reference
    method (the methods below), tested equal step by step (``tests/test_sim_kernels.py``).

    Parameters
    ----------
    layout : LabLayout
    at_work : bool   start with the tool on the work point (default: the park configuration)
    comau_profile : str, optional
        The Comau's joint-limit profile: ``datasheet`` (the robot file, Table 6) or one of the
        layout's ``<joint_limits>`` (``lab``: the lab's program limits with its velocity-boundary
        law); default the layout's ``<crane limits=…>``.

    Attributes
    ----------
    profile : JointLimitProfile   the profile in force (``joints`` is the filter built from it:
        its lower, upper, speed and the boundary deceleration ``brake``)
    """

    def __init__(self, layout: LabLayout, at_work: bool = False, comau_profile: str | None = None) -> None:
        self.layout = layout
        self.models = tuple(load_robot(robot) for _, robot in layout.platforms)
        try:
            self.platforms = tuple(
                Platform(m, command_box=box) for m, box in zip(self.models, layout.command_boxes, strict=True)
            )
        except BosunError as err:
            raise LabError(f"{layout.path}: {err}") from None
        self.robot = load_robot(layout.crane_robot)
        arm = ComauArm.match(self.robot)
        if arm is None:
            raise LabError(f"crane robot '{layout.crane_robot}' is not a Comau-type 3-DOF arm (Motion-Lab Table 3)")
        self.arm = arm
        self.comau = ComauKinematics.from_arm(arm)
        self.profile = layout.profile(comau_profile)
        prof = self.profile
        lo = self.robot.lower if prof.lower is None else prof.lower
        hi = self.robot.upper if prof.upper is None else prof.upper
        speed = self.robot.speed if prof.speed is None else prof.speed
        if np.any(lo < self.robot.lower - 1e-12) or np.any(hi > self.robot.upper + 1e-12):
            raise LabError(f"{layout.path}: Comau profile '{prof.name}' leaves the robot file's joint limits")
        accel = np.full(3, layout.crane_accel)
        brake = None if prof.boundary_accel is None else np.full(3, prof.boundary_accel)
        self.joints = MotionFilter(lo, hi, speed, accel, tau=0.05, brake=brake)
        if not np.all((layout.park_q >= lo) & (layout.park_q <= hi)):
            raise LabError(f"{layout.path}: the Comau's park configuration is outside its '{prof.name}' joint limits")
        self.joints.reset(layout.park_q)
        self.comau_mode = "remote"
        self.tool_velocity_cmd = np.zeros(3)  # REMOTE: in {r} [m/s]
        self.winch = Winch(layout.winch)
        self.pendulum = Pendulum(damping=layout.payload_damping)
        self.T_n1_g = np.linalg.inv(layout.T_world_n1)
        # constants and buffers of the compiled step (C-contiguous float64: one kernel signature)
        self._rates_buf = np.zeros((2, 3, 3, 3))
        self._rate_views = tuple((b[0], b[1], b[2]) for b in self._rates_buf)
        self._comau = np.array([arm.a1, arm.d1, arm.a2, arm.a3, arm.L], dtype=float)
        self._T_world_n = tuple(np.ascontiguousarray(T, dtype=float) for T in (layout.T_world_n1, layout.T_world_n2))
        self._consts = (
            *(np.ascontiguousarray(a, dtype=float) for a in (arm.T_world_base, ComauArm.SIGNS["auto"])),
            *self._T_world_n,
            *(
                np.ascontiguousarray(a, dtype=float)
                for a in (self.T_n1_g @ layout.T_world_n2, layout.T_b1_r, layout.work_point_b2, layout.park_q)
            ),
        )
        self._target = np.zeros(3)
        self._out = tuple(np.zeros(n) for n in (3, 3, 3, 6, 6))  # e_t_b2, p_w_g, p_p_g, legs1, legs2
        self._use_kernels = False  # the set-up below runs the reference; the flag is set at the end
        self.payload_target_b2: NDArray[np.float64] | None = None
        # what the controllers see of the platforms: None, the true states; else one streaming sensor per
        # platform (app/marine/sensors.py: MRU or tracker), measured after the platforms' step
        self.sensors: tuple | None = None
        self.measured: tuple[tuple[NDArray, NDArray, NDArray], ...] | None = None
        # an offset (position, velocity in {n1}) added to the work point the Comau tracks (anti-swing)
        self.tool_offset = (np.zeros(3), np.zeros(3))
        self.t = 0.0
        self.frozen = False
        self.at_limit = np.zeros(4, dtype=bool)  # joints 1–3, winch: at a position or speed limit
        self.q_work = self.work_configuration()
        if at_work:
            self.joints.reset(self.q_work)
        self._rates = self._rotation_rates()
        self.last: LabSample | None = None
        self._update_tool()
        self.last = self._sample()
        self.use_kernels = sim_kernels.ENABLED

    @property
    def use_kernels(self) -> bool:
        return self._use_kernels

    @use_kernels.setter
    def use_kernels(self, on: bool) -> None:
        """Compiled (True) or the NumPy reference (False) for the whole lab: step, platforms, filters,
        sources, load and the robot's IK candidates."""
        self._use_kernels = bool(on)
        for p in self.platforms:
            p.use_kernels = on
        self.joints.use_kernels = self.winch.filter.use_kernels = self.pendulum.use_kernels = bool(on)
        self.robot.use_kernels = bool(on)

    # ------------------------------------------------------------------ geometry
    def _rotation_rates(self) -> tuple[tuple[NDArray, NDArray, NDArray], ...]:
        """(R, Ṙ, R̈) of each platform body (eqs. 33, 47, 51), computed once per step."""
        return tuple(StewartPlatform.rotation_rates(p.eta, p.eta_dot, p.eta_ddot) for p in self.platforms)

    def platform_pose(self, k: int) -> NDArray[np.float64]:
        """H^g_bk: body frame of platform k (0 or 1) in the world, eq. (39)."""
        p = self.platforms[k]
        T_n = self.layout.T_world_n1 if k == 0 else self.layout.T_world_n2
        if self._use_kernels:
            return sim_kernels.pose_in(self._T_world_n[k], p.filter.x)
        return T_n @ StewartPlatform.pose_matrix(p.eta)

    def work_point(self, seen: bool = False) -> tuple[NDArray, NDArray, NDArray]:
        """The work point fixed in {b2}: position, velocity, acceleration in {n1} (``seen``: as the
        controllers see EM1500, :meth:`set_sensors`)."""
        if seen:
            eta, eta_dot, eta_ddot, (R, Rd, Rdd) = self._view(1)
        else:
            p2 = self.platforms[1]
            eta, eta_dot, eta_ddot, (R, Rd, Rdd) = p2.eta, p2.eta_dot, p2.eta_ddot, self._rates[1]
        w = self.layout.work_point_b2
        T_n1_n2 = self.T_n1_g @ self.layout.T_world_n2
        R12 = T_n1_n2[:3, :3]
        p = T_n1_n2[:3, 3] + R12 @ (eta[:3] + R @ w)
        v = R12 @ (eta_dot[:3] + Rd @ w)
        a = R12 @ (eta_ddot[:3] + Rdd @ w)
        return p, v, a

    def to_robot_base(self, p_n1, v_n1, seen: bool = False) -> tuple[NDArray, NDArray]:
        """Invert eqs. (54) and (56) for the tool point in {r} (position and velocity); ``seen``: with
        EM8000 as the controllers see it."""
        if seen:
            eta, eta_dot, _, (R, Rd, _) = self._view(0)
        else:
            p1 = self.platforms[0]
            eta, eta_dot, (R, Rd, _) = p1.eta, p1.eta_dot, self._rates[0]
        R_r, p_r = self.layout.T_b1_r[:3, :3], self.layout.T_b1_r[:3, 3]
        p_tr = R_r.T @ (R.T @ (p_n1 - eta[:3]) - p_r)
        arm = p_r + R_r @ p_tr
        v_tr = R_r.T @ (R.T @ (v_n1 - eta_dot[:3] - Rd @ arm))
        return p_tr, v_tr

    def work_configuration(self) -> NDArray[np.float64]:
        """Joint angles that put the tool on the work point with both platforms at neutral."""
        p_n1, _, _ = self._work_point_neutral()
        R_r, p_r = self.layout.T_b1_r[:3, :3], self.layout.T_b1_r[:3, 3]
        p_tr = R_r.T @ (p_n1 - p_r)
        q = self._ik(p_tr, self.layout.park_q)
        if q is None:
            raise LabError("the work point of the lab layout is out of the robot's reach within its joint limits")
        return q

    def _work_point_neutral(self):
        T_n1_n2 = self.T_n1_g @ self.layout.T_world_n2
        return T_n1_n2[:3, :3] @ self.layout.work_point_b2 + T_n1_n2[:3, 3], None, None

    def _ik(self, p_tr: NDArray[np.float64], q_near: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """Analytic IK (eqs. 7–20): the exact candidate inside the joint limits in force (the profile's)
        nearest ``q_near``."""
        best, best_d = None, np.inf
        if getattr(self.robot, "use_kernels", False):  # the compiled eqs. (7)–(20), tested equal
            Q, flags = self.arm.kernel_candidates(p_tr, float(q_near[0]), np.array(self.arm.SIGNS["auto"]))
            candidates = zip(Q, flags, strict=True)
        else:
            candidates = self.arm.candidates(p_tr, float(q_near[0]), "auto")
        for q, exact in candidates:
            q = q.copy()
            q[0] = q_near[0] + math.remainder(q[0] - q_near[0], 2 * math.pi)
            if not exact or not np.all((q >= self.joints.lower - 1e-9) & (q <= self.joints.upper + 1e-9)):
                continue
            d = float(np.sum((q - q_near) ** 2))
            if d < best_d:
                best, best_d = q, d
        return best

    # ------------------------------------------------------------------ commands
    def set_comau_mode(self, mode: str) -> None:
        if mode not in COMAU_MODES:
            raise LabError(f"Comau mode must be one of {', '.join(COMAU_MODES)}, got {mode!r}")
        self.comau_mode = mode
        self.tool_velocity_cmd = np.zeros(3)

    def set_winch_mode(self, mode: str) -> None:
        if mode not in WINCH_MODES:
            raise LabError(f"winch mode must be one of {', '.join(WINCH_MODES)}, got {mode!r}")
        self.winch.mode = mode
        self.winch.speed_command = 0.0
        self.payload_target_b2 = None  # captured on the next step

    def set_vvmc(self, on: bool) -> None:
        """VVMC on: Comau and winch in MOTION_COMP; off: both hold (Comau REMOTE, winch LOCAL, zero speed)."""
        self.set_comau_mode("motion_comp" if on else "remote")
        self.set_winch_mode("motion_comp" if on else "local")

    def estop(self) -> None:
        self.frozen = True
        for p in self.platforms:
            p.estop()
        self.tool_velocity_cmd = np.zeros(3)
        self.winch.speed_command = 0.0

    def reset(self) -> None:
        """After an E-STOP every machine holds where it stands until the operator commands it anew:
        platforms SETTLED stay so, others HOLDING; the Comau HOLD; the winch LOCAL at zero speed."""
        self.frozen = False
        for p in self.platforms:
            p.reset()
        self.set_comau_mode("hold")
        self.set_winch_mode("local")

    # ------------------------------------------------------------------ sensors and offsets
    def set_sensors(self, sensors: tuple | None) -> None:
        """Let the controllers see the platforms through ``sensors`` (one
        :class:`~app.marine.sensors.MotionSensor` per platform, EM8000 then EM1500), or the true
        states (None).  The plant, the load and every score keep the true states."""
        if sensors is not None and len(sensors) != len(self.platforms):
            raise LabError(f"one sensor per platform ({len(self.platforms)}), got {len(sensors)}")
        self.sensors = None if sensors is None else tuple(sensors)
        self.measured = None

    def set_tool_offset(self, p_n1: ArrayLike, v_n1: ArrayLike) -> None:
        """Offset (position [m], velocity [m/s] in {n1}) added to the work point the Comau tracks in
        MOTION_COMP, from the next step on (the anti-swing law's; zero: the work point itself)."""
        p, v = np.asarray(p_n1, dtype=float), np.asarray(v_n1, dtype=float)
        if p.shape != (3,) or v.shape != (3,) or not (np.all(np.isfinite(p)) and np.all(np.isfinite(v))):
            raise LabError("a tool offset is a finite position and velocity (3 values each)")
        self.tool_offset = (np.ascontiguousarray(p), np.ascontiguousarray(v))

    def _measure(self) -> None:
        if self.sensors is None:
            self.measured = None
            return
        self.measured = tuple(
            tuple(np.ascontiguousarray(a, dtype=float) for a in s.measure(p.eta, p.eta_dot, p.eta_ddot))
            for s, p in zip(self.sensors, self.platforms, strict=True)
        )

    def _view(self, k: int) -> tuple[NDArray, NDArray, NDArray, tuple[NDArray, NDArray, NDArray]]:
        """Platform k as the controllers see it: η, η̇, η̈ and (R, Ṙ, R̈)."""
        if self.measured is None:
            p = self.platforms[k]
            return p.eta, p.eta_dot, p.eta_ddot, self._rates[k]
        eta, eta_dot, eta_ddot = self.measured[k]
        return eta, eta_dot, eta_ddot, StewartPlatform.rotation_rates(eta, eta_dot, eta_ddot)

    # ------------------------------------------------------------------ step
    def step(self, dt: float) -> LabSample:
        self.t += dt
        for p in self.platforms:
            p.step(dt)
        self._measure()
        if self._use_kernels:
            self.last = self._step_compiled(dt)
            return self.last
        self._rates = self._rotation_rates()
        self._step_robot(dt)
        self._update_tool()
        self._step_winch(dt)
        a_t_d = R_G_D.T @ self.a_t_g
        self.pendulum.step(dt, a_t_d, self.winch.length, self.winch.speed)
        self.last = self._sample()
        return self.last

    def refresh(self) -> LabSample:
        """Recompute the derived state (rotation rates, tool point, the sample) from the machines' states
        as they are, without stepping: the ``plc`` plant backend sets platform poses, joints and wire
        length from the real lab's measurements and calls this (app/plant/plc.py)."""
        self._rates = self._rotation_rates()
        self._update_tool()
        self.last = self._sample()
        return self.last

    def _step_compiled(self, dt: float) -> LabSample:
        """Everything after the platforms in one :func:`app.sim.kernels.lab_step` call."""
        (p1, p2), (m1, m2), f, w, pd = self.platforms, self.models, self.joints, self.winch, self.pendulum
        wf = w.filter
        if self.frozen:
            w.speed_command = 0.0
        mode = 3 if self.frozen else COMAU_MODES.index(self.comau_mode)  # hold and E-STOP brake alike
        has = self.payload_target_b2 is not None
        target = self.payload_target_b2 if has else self._target
        e_b2, p_w_g, p_p_g, legs1, legs2 = self._out
        true = ((p1.filter.x, p1.filter.v, p1.filter.a), (p2.filter.x, p2.filter.v, p2.filter.a))
        seen = true if self.measured is None else self.measured
        has, pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot, h_err = sim_kernels.lab_step(
            *true[0], *true[1], self._rates_buf, *seen[0], *seen[1], self.measured is not None, *self.tool_offset,
            self._comau, *self._consts,
            f.x, f.v, f.a, f.lower, f.upper, f.speed, f.accel, f.brake, f.tau, mode,
            np.ascontiguousarray(self.tool_velocity_cmd, dtype=float),
            wf.x, wf.v, wf.a, wf.lower, wf.upper, wf.speed, wf.accel, wf.tau,
            not self.frozen and w.mode == "motion_comp", float(w.speed_command),
            target, has, float(pd.alpha), float(pd.beta), float(pd.alpha_dot), float(pd.beta_dot),
            float(pd.damping), float(pd.g), m1.a_n, m1.b_b, m2.a_n, m2.b_b,
            self.p_t_n1, self.p_t_g, self.v_t_g, self.a_t_g, self.at_limit, e_b2, p_w_g, p_p_g, legs1, legs2,
            float(dt),
        )  # fmt: skip
        if has and self.payload_target_b2 is None:
            self.payload_target_b2 = target.copy()
        self._rates = self._rate_views
        return LabSample(
            t=self.t,
            eta1=p1.filter.x.copy(),
            eta2=p2.filter.x.copy(),
            legs1=legs1.copy(),
            legs2=legs2.copy(),
            q=f.x.copy(),
            qd=f.v.copy(),
            p_t_g=self.p_t_g.copy(),
            v_t_g=self.v_t_g.copy(),
            p_p_g=p_p_g.copy(),
            p_w_g=p_w_g.copy(),
            e_t_b2=e_b2.copy(),
            L_w=float(wf.x[0]),
            L_w_dot=float(wf.v[0]),
            swing=(pd.alpha, pd.beta),
            payload_height_error=h_err,
        )

    def _step_robot(self, dt: float) -> None:
        f = self.joints
        if self.frozen or self.comau_mode == "hold":  # brake at the acceleration limits to rest, then stay
            v = f.v + np.clip(-f.v, -f.accel * dt, f.accel * dt)
            f.a, f.v = (v - f.v) / dt, v
            f.x = np.clip(f.x + v * dt, f.lower, f.upper)
            return
        if self.comau_mode == "settled":
            f.step(self.layout.park_q, None, dt, 0.25)
        elif self.comau_mode == "remote":
            J = self.comau.jacobian(f.x)
            qd = np.linalg.lstsq(J, self.tool_velocity_cmd, rcond=1e-6)[0]  # eq. (21)
            f.step(f.x + qd * dt, qd, dt)
        else:  # motion_comp: inverse kinematic control with feed-forward of both platforms, as measured
            p_n1, v_n1, _ = self.work_point(seen=True)
            p_off, v_off = self.tool_offset
            p_tr, v_tr = self.to_robot_base(p_n1 + p_off, v_n1 + v_off, seen=True)
            q_d = self._ik(p_tr, f.x)
            if q_d is None:  # out of reach: hold the nearest reachable direction, limits intact
                q_d = f.x.copy()
            qd_d = np.linalg.lstsq(self.comau.jacobian(q_d), v_tr, rcond=1e-6)[0]  # eq. (21)
            f.step(q_d, qd_d, dt)
        tol = 1e-6
        self.at_limit[:3] = (f.x <= f.lower + tol) | (f.x >= f.upper - tol) | (np.abs(f.v) >= f.speed * (1 - 1e-3))

    def _update_tool(self) -> None:
        p1 = self.platforms[0]
        f = self.joints
        p, v, a = tool_on_platform(
            self.comau, self.layout.T_b1_r, p1.eta, p1.eta_dot, p1.eta_ddot, f.x, f.v, f.a, self._rates[0]
        )
        T = self.layout.T_world_n1
        self.p_t_n1 = p
        self.p_t_g = T[:3, :3] @ p + T[:3, 3]  # eq. (55)
        self.v_t_g = T[:3, :3] @ v  # eq. (56), rotated into {g}
        self.a_t_g = T[:3, :3] @ a  # eq. (57), rotated into {g}

    def _b2_to_g(self) -> tuple[NDArray, NDArray]:
        H = self.platform_pose(1)
        return H[:3, :3], H[:3, 3]

    def _step_winch(self, dt: float) -> None:
        w = self.winch
        if self.frozen:
            w.speed_command = 0.0
            w.step(dt)
        elif w.mode == "motion_comp":  # EM1500 as the controllers see it
            eta2, eta_dot2, _, (_, Rd, _) = self._view(1)
            H2 = self.layout.T_world_n2 @ StewartPlatform.pose_matrix(eta2)  # eq. (39)
            R2, o2 = H2[:3, :3], H2[:3, 3]
            if self.payload_target_b2 is None:  # keep the payload where it is now, relative to EM1500
                self.payload_target_b2 = R2.T @ (self.p_p_g() - o2)
            target_g = R2 @ self.payload_target_b2 + o2
            R_g_n2 = self.layout.T_world_n2[:3, :3]
            v_target_g = R_g_n2 @ (eta_dot2[:3] + Rd @ self.payload_target_b2)
            # heights along gravity: z_d = −z_g; the load hangs L_w below the tool (small swing)
            L_ref = float(self.p_t_g[2] - target_g[2])
            Ld_ref = float(self.v_t_g[2] - v_target_g[2])
            w.step(dt, L_ref, Ld_ref)
        else:
            w.step(dt)
        sp = w.spec
        self.at_limit[3] = (
            w.length <= sp["min_length"] + 1e-6
            or w.length >= sp["max_length"] - 1e-6
            or abs(w.speed) >= sp["speed"] * (1 - 1e-3)
        )

    def p_p_g(self) -> NDArray[np.float64]:
        """Payload position in {g}, eq. (58)."""
        return self.p_t_g + R_G_D @ (self.winch.length * self.pendulum.direction())

    def _sample(self) -> LabSample:
        R2, o2 = self._b2_to_g()
        e_b2 = R2.T @ (self.p_t_g - o2) - self.layout.work_point_b2
        if self.payload_target_b2 is not None:
            target_g = R2 @ self.payload_target_b2 + o2
            h_err = float(self.p_p_g()[2] - target_g[2])
        else:
            h_err = 0.0
        p_w_g = R2 @ self.layout.work_point_b2 + o2
        return LabSample(
            t=self.t,
            eta1=self.platforms[0].eta,
            eta2=self.platforms[1].eta,
            legs1=self.models[0].leg_lengths(self.platforms[0].eta),
            legs2=self.models[1].leg_lengths(self.platforms[1].eta),
            q=self.joints.x.copy(),
            qd=self.joints.v.copy(),
            p_t_g=self.p_t_g.copy(),
            v_t_g=self.v_t_g.copy(),
            p_p_g=self.p_p_g(),
            p_w_g=p_w_g,
            e_t_b2=e_b2,
            L_w=self.winch.length,
            L_w_dot=self.winch.speed,
            swing=(self.pendulum.alpha, self.pendulum.beta),
            payload_height_error=h_err,
        )
