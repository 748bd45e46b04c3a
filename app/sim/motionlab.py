"""The Motion-Lab's plants: the Comau's joint drives, its winch drum and the hanging load.

Frames (Motion-Lab paper Table 4): world {g} (z-up), platform neutral frames {n1}, {n2} and body
frames {b1}, {b2} (z-down), robot base {r} (z-up), tool point {t}.  The pendulum is integrated in
{d}, the world turned half a turn about x (z-down, gravity along +z_d), where eq. (23) puts the
load below the tool at rest.

Each plant is a block (:mod:`app.models.block`) with its compiled kernel (:mod:`app.sim.kernels`) and its
NumPy reference here; the platforms are :mod:`app.sim.stewart`, the kinematics :mod:`app.models.comau` and
:mod:`app.models.stewart`, the controllers that command these plants :mod:`app.control.lab`, and the scene
that wires them :mod:`app.scenes.lab`.

* Pendulum eqs. (29)–(30) / (60)–(61) from the Lagrangian (25)–(28) in a z-down frame: the printed
  z̈_t terms have the wrong sign for that frame (a tool accelerating downwards must *lower* the
  effective gravity, g − z̈_t); derived again here, with a viscous damping term −c φ̇:

      L α̈ = ẍ cα + ÿ sα sβ + z̈ sα cβ − g sα cβ − 2 L̇ α̇ − L β̇² sα cα − c L α̇
      L cα β̈ = −ÿ cβ + z̈ sβ − g sβ − 2 L̇ β̇ cα + 2 L α̇ β̇ sα − c L cα β̇

  integrated with fixed-step RK4 (tool acceleration and wire speed held over the step).
* The drives: a motion filter per joint (speed, acceleration and position limits, the lab's velocity
  bound at the limits), or braking to rest at the acceleration limits (HOLD, E-STOP).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from app.models.block import Block
from app.models.pendulum import swing_derivative, swing_rk4
from app.sim import kernels as sim_kernels
from app.sim.stewart import MotionFilter, motion_filter_reference

G = 9.81
R_G_D = np.diag([1.0, -1.0, -1.0])  # {d} (z-down) in {g} (z-up): half a turn about x


# ----------------------------------------------------------------------------- pendulum
def _pendulum_reference(x, u, p, dt):
    """The NumPy reference of :data:`PENDULUM`: one RK4 step of :func:`app.models.pendulum.swing_rk4`."""
    a, b, ad, bd = (float(v) for v in swing_rk4(np.array(x, dtype=float), dt, u[0], u[1], u[2], p[0], p[1]))
    return (a, b, ad, bd), (a, b, ad, bd)


#: the suspended load as a block (app.models.block): the plant of eqs. (29)–(30), RK4 over a step
PENDULUM = Block(
    "load (spherical pendulum)",
    state=("alpha", "beta", "alpha_dot", "beta_dot"),
    inputs=("a_t_d", "L", "L_dot"),
    outputs=("alpha", "beta", "alpha_dot", "beta_dot"),
    params=("damping", "g"),
    reference=_pendulum_reference,
    kernel=sim_kernels.pendulum_block,
)


#: the load's model (the pendulum's angles) is lost within this of its pole, cos α = 0 (1.1°) …
SWING_POLE = 0.02
#: … or past this swing rate [rad/s] (a 0.3 m wire at 100 rad/s is the load at 30 m/s)
SWING_RATE_MAX = 100.0


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

    def in_model(self) -> bool:
        """Whether the swing is still one eqs. (29)–(30) can follow: in the angles α, β they are singular at
        cos α = 0 (the load level with the tool point), where β̇ grows without bound — finite, cos α at least
        :data:`SWING_POLE` and the rates under :data:`SWING_RATE_MAX` (safety H118)."""
        x = (self.alpha, self.beta, self.alpha_dot, self.beta_dot)
        return (
            all(math.isfinite(v) for v in x)
            and abs(math.cos(self.alpha)) >= SWING_POLE
            and max(abs(self.alpha_dot), abs(self.beta_dot)) <= SWING_RATE_MAX
        )

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


# ----------------------------------------------------------------------------- the Comau's drives
def _drives_reference(x, u, p, dt):
    """The NumPy reference of :func:`app.sim.kernels.drives_block` (new arrays; ``at_limit`` in place)."""
    q, qd, qdd, at_limit = x
    brake, q_ref, v_ref, use_v, scale = u
    lower, upper, speed, accel, _, _ = p
    if brake:  # to rest at the acceleration limits, then stay
        v = qd + np.clip(-qd, -accel * dt, accel * dt)
        q_new = np.clip(q + v * dt, lower, upper)
        return (q_new, v, (v - qd) / dt, at_limit), (q_new, v)
    q, qd, qdd = motion_filter_reference((q, qd, qdd), (q_ref, v_ref, use_v, scale), p, dt)
    tol = 1e-6
    at_limit[:3] = (q <= lower + tol) | (q >= upper - tol) | (np.abs(qd) >= speed * (1 - 1e-3))
    return (q, qd, qdd, at_limit), (q, qd)


#: the Comau's joint drives: the joint command of :data:`app.control.lab.COMAU_LAW` through the joint limits
COMAU_DRIVES = Block(
    "Comau drives",
    state=("q", "q_dot", "q_ddot", "at_limit"),
    inputs=("brake", "q_ref", "q_dot_ref", "use_q_dot_ref", "speed_scale"),
    outputs=("q", "q_dot"),
    params=("lower", "upper", "speed", "accel", "brake", "tau"),
    reference=_drives_reference,
    kernel=sim_kernels.drives_block,
)


# ----------------------------------------------------------------------------- the winch drum
def _drum_reference(x, u, p, dt):
    """The NumPy reference of :func:`app.sim.kernels.drum_block` (new arrays; ``at_limit`` in place)."""
    wl, wv, wa, at_limit = x
    lower, upper, speed, accel, tau = p
    wl, wv, wa = motion_filter_reference((wl, wv, wa), (u[0], u[1], True, 1.0), (*p[:4], accel, tau), dt)
    at_limit[3] = wl[0] <= lower[0] + 1e-6 or wl[0] >= upper[0] - 1e-6 or abs(wv[0]) >= speed[0] * (1 - 1e-3)
    return (wl, wv, wa, at_limit), (wl, wv)


#: the winch drum: the wire length following the reference of :data:`app.control.lab.WINCH_LAW`
WINCH_DRUM = Block(
    "winch drum",
    state=("L_w", "L_w_dot", "L_w_ddot", "at_limit"),
    inputs=("L_ref", "L_dot_ref"),
    outputs=("L_w", "L_w_dot"),
    params=("lower", "upper", "speed", "accel", "tau"),
    reference=_drum_reference,
    kernel=sim_kernels.drum_block,
)
