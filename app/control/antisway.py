"""Load-swing estimation and anti-swing control for the Motion-Lab's suspended load (issue 16, item 4).

The lab's HMI has a "Pendel Estimator" tab (pendulum states, damping parameter, error states;
anti-swing activate / deactivate / reset; an EKF on MRU or Stewart feedback — motionlab_plc.json,
``hmi_tabs``: Norwegian Motion-Laboratory repository, commit f5fbf84, MIT).  Bosun builds both from the
load model of Motion-Lab paper eqs. (23)–(30) (:mod:`app.models.pendulum`, frame {d}: z down):

* :class:`SwingEkf` — an extended Kalman filter of x = (α, β, α̇, β̇).  Prediction integrates the
  nonlinear eqs. (29)–(30) (RK4) with the *measured* tool acceleration a_t^d, the wire length and its
  rate; the measurement noise of that acceleration enters as process noise through ∂f/∂a (plus a small
  white angular-acceleration noise for what the model leaves out).  Measurements: the wire angles
  (α, β) from a wire-angle sensor, or the load's position relative to the tool, L·(−sα, cα sβ, cα cβ)
  (eq. 23, from a tracker).  Jacobians by central differences of eqs. (29)–(30); Joseph-form update.
* :class:`AntiSwing` — an LQR on the linearised pendulum with the tool's offset from its compensation
  target as extra states, one law per swing plane (they decouple at rest):

      per axis: s = (φ, φ̇, p, ṗ),  u = p̈ (tool acceleration along the axis, in {d})
      L φ̈ = σ u − g φ − c L φ̇,   σ = +1 for α (x_d), −1 for β (y_d)

  designed as the lab did (L = 3 m, c = 0.1 1/s, T_s = 5 ms, the PLC task) by a discrete algebraic
  Riccati equation on the zero-order-hold model, and scheduled over the wire length: gains solved on a
  grid of L and interpolated (:class:`GainSchedule`).  The command u is limited (``a_max``), integrated
  into the offset (p, ṗ) that is *added* to the VVMC tool target, and the offset is kept within
  ``offset_max``; penalising p makes the tool return to the target once the swing is gone.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from app.control import antisway_kernels
from app.errors import BosunError
from app.models.block import Block
from app.models.pendulum import G, swing_derivative, swing_direction, swing_rk4

__all__ = [
    "ANTISWAY_LAW", "SWING_CONTROL", "SWING_EKF", "AntiSwing", "AntiSwingDesign", "AntiSwingError", "GainSchedule",
    "SwingEkf", "axis_model", "lqr_gain",
]  # fmt: skip


class AntiSwingError(BosunError):
    """A bad estimator or controller setting (names it)."""


# ----------------------------------------------------------------------------- the linear model and LQR
def axis_model(L: float, c: float, g: float = G, sign: float = 1.0) -> tuple[NDArray, NDArray]:
    """Continuous (A, B) of one swing plane, state (φ, φ̇, p, ṗ), input u = p̈ [m/s²] (see module doc)."""
    if not (L > 0 and math.isfinite(L)):
        raise AntiSwingError(f"wire length must be positive, got {L!r}")
    A = np.array([[0.0, 1.0, 0.0, 0.0], [-g / L, -c, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])
    B = np.array([[0.0], [sign / L], [0.0], [1.0]])
    return A, B


def discretise(A: NDArray, B: NDArray, Ts: float) -> tuple[NDArray, NDArray]:
    """Zero-order-hold discretisation: one matrix exponential of [[A, B], [0, 0]] Ts."""
    n, m = A.shape[0], B.shape[1]
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = scipy.linalg.expm(M * Ts)
    return E[:n, :n], E[:n, n:]


def lqr_gain(L: float, design: AntiSwingDesign, sign: float = 1.0) -> NDArray[np.float64]:
    """The discrete LQR gain K (4,) of one plane at wire length L: u = −K s minimises Σ sᵀQs + uᵀRu."""
    Ad, Bd = discretise(*axis_model(L, design.c, design.g, sign), design.Ts)
    Q, R = np.diag(design.Q), np.array([[design.R]])
    P = scipy.linalg.solve_discrete_are(Ad, Bd, Q, R)
    K = np.linalg.solve(R + Bd.T @ P @ Bd, Bd.T @ P @ Ad)
    return K[0]


@dataclass(frozen=True)
class AntiSwingDesign:
    """LQR design of the anti-swing law (defaults: the lab's design point L = 3 m, c = 0.1, T_s = 5 ms).

    ``Q`` weighs (φ [rad], φ̇ [rad/s], p [m], ṗ [m/s]), ``R`` the tool acceleration [m/s²]; ``a_max`` and
    ``offset_max`` limit the command and the offset from the compensation target (within what the
    Comau's lab joint profile can follow)."""

    L: float = 3.0
    c: float = 0.1
    Ts: float = 0.005
    g: float = G
    Q: tuple[float, float, float, float] = (400.0, 40.0, 20.0, 4.0)
    R: float = 1.0
    a_max: float = 2.0
    offset_max: float = 0.3

    def __post_init__(self) -> None:
        for name in ("L", "Ts", "R", "a_max", "offset_max"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise AntiSwingError(f"anti-swing {name} must be positive, got {v!r}")
        if not (math.isfinite(self.c) and self.c >= 0):
            raise AntiSwingError(f"anti-swing damping c must be ≥ 0, got {self.c!r}")
        if len(self.Q) != 4 or not all(math.isfinite(q) and q >= 0 for q in self.Q):
            raise AntiSwingError(f"anti-swing Q must be four weights ≥ 0, got {self.Q!r}")


class GainSchedule:
    """LQR gains solved on a grid of wire lengths (geometric, ``L_min``…``L_max``) and interpolated linearly;
    lengths outside the grid take its end gains.  Both planes: ``gains(L)`` → (K_α, K_β)."""

    def __init__(self, design: AntiSwingDesign, L_min: float = 0.3, L_max: float = 6.0, n: int = 40) -> None:
        self.design = design
        self.L = np.geomspace(L_min, L_max, n)
        self.K_alpha = np.array([lqr_gain(L, design, +1.0) for L in self.L])
        self.K_beta = np.array([lqr_gain(L, design, -1.0) for L in self.L])

    def gains(self, L: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        Lc = float(np.clip(L, self.L[0], self.L[-1]))
        ka = np.array([np.interp(Lc, self.L, self.K_alpha[:, j]) for j in range(4)])
        kb = np.array([np.interp(Lc, self.L, self.K_beta[:, j]) for j in range(4)])
        return ka, kb


@functools.lru_cache(maxsize=16)
def _schedule(design: AntiSwingDesign, L_min: float, L_max: float) -> GainSchedule:
    """One gain schedule per design and lengths (80 Riccati equations: a tenth of a second; a study of many runs
    solves them once)."""
    return GainSchedule(design, L_min, L_max)


@dataclass
class AntiSwing:
    """The anti-swing law: the swing estimate (α, β, α̇, β̇) and the wire length in, the tool's offset
    from its compensation target out (position, velocity, acceleration in {d}; z is left to the winch).

    ``schedule`` False keeps the gains of the design length (the lab's fixed design); True re-reads them
    for the current wire length."""

    design: AntiSwingDesign = field(default_factory=AntiSwingDesign)
    schedule: bool = True
    active: bool = False
    lengths: tuple[float, float] = (0.3, 6.0)  # the gain schedule's wire lengths [m] (the lab's winch)
    p: NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    v: NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    a: NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    saturated: bool = False

    def __post_init__(self) -> None:
        self._schedule = _schedule(self.design, *self.lengths)
        self._fixed = (lqr_gain(self.design.L, self.design, +1.0), lqr_gain(self.design.L, self.design, -1.0))

    def gains(self, L: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return self._schedule.gains(L) if self.schedule else self._fixed

    def reset(self) -> None:
        """Offset and its rate to zero (the tool back on its target at once: call only at rest)."""
        self.p[:], self.v[:], self.a[:] = 0.0, 0.0, 0.0
        self.saturated = False

    def record(self) -> tuple:
        """The law's parameter record for :data:`ANTISWAY_LAW`: (grid, K_α, K_β, a_max, offset_max); the fixed
        design is a grid of one length (np.interp then gives its gains exactly)."""
        if self.schedule:
            sch = self._schedule
            grid, Ka, Kb = sch.L, sch.K_alpha, sch.K_beta
        else:
            grid, Ka, Kb = np.array([self.design.L]), self._fixed[0][None, :], self._fixed[1][None, :]
        return (grid, np.ascontiguousarray(Ka), np.ascontiguousarray(Kb), self.design.a_max, self.design.offset_max)

    def step(self, x_hat: ArrayLike, L: float, dt: float) -> tuple[NDArray, NDArray, NDArray]:
        """Advance the offset by dt with the command u = −K s of each plane; returns (p, ṗ, p̈) in {d} (3,)
        (one step of the NumPy reference of :data:`ANTISWAY_LAW`)."""
        x = np.asarray(x_hat, dtype=float)
        (self.p, self.v, self.a), (self.saturated,) = _law_reference(
            (self.p, self.v, self.a), (x, float(L), self.active), self.record(), dt
        )
        z = np.zeros(1)
        return np.concatenate([self.p, z]), np.concatenate([self.v, z]), np.concatenate([self.a, z])


def _interp_gains(L: float, grid: NDArray, K: NDArray) -> NDArray[np.float64]:
    Lc = float(np.clip(L, grid[0], grid[-1]))
    return np.array([np.interp(Lc, grid, K[:, j]) for j in range(4)])


def _law_reference(x, u, p, dt):
    """The NumPy reference of :data:`ANTISWAY_LAW` (see :class:`AntiSwing`)."""
    pos, vel, _ = x
    x_hat, L, active = u
    grid, K_alpha, K_beta, a_max, p_max = p
    ka, kb = _interp_gains(L, grid, K_alpha), _interp_gains(L, grid, K_beta)
    if active and np.all(np.isfinite(x_hat)):
        u_cmd = np.array(
            [-ka @ np.array([x_hat[0], x_hat[2], pos[0], vel[0]]), -kb @ np.array([x_hat[1], x_hat[3], pos[1], vel[1]])]
        )
    else:  # inactive (or no estimate): bring an offset that is left back to zero along the same law
        u_cmd = np.array([-ka[2:] @ np.array([pos[0], vel[0]]), -kb[2:] @ np.array([pos[1], vel[1]])])
    saturated = bool(np.any(np.abs(u_cmd) > a_max))
    u_cmd = np.clip(u_cmd, -a_max, a_max)
    vel = vel + u_cmd * dt
    pos = pos + vel * dt
    for k in range(2):  # at the offset limit: stop there (no speed further out)
        if abs(pos[k]) > p_max:
            pos[k] = math.copysign(p_max, pos[k])
            if vel[k] * pos[k] > 0:
                vel[k] = 0.0
            saturated = True
    return (pos, vel, u_cmd), (saturated,)


#: the anti-swing law as a block: the swing estimate in, the tool's offset from its target out (in {d})
ANTISWAY_LAW = Block(
    "anti-swing law (LQR, gain schedule)",
    state=("p", "v", "a"),
    inputs=("x_hat", "L", "active"),
    outputs=("saturated",),
    params=("grid", "K_alpha", "K_beta", "a_max", "offset_max"),
    reference=_law_reference,
    kernel=antisway_kernels.law_block,
)


# ----------------------------------------------------------------------------- the estimator
MEASUREMENTS = ("angles", "payload")


@dataclass
class SwingEkf:
    """Extended Kalman filter of the swing x = (α, β, α̇, β̇) (see module doc).

    Parameters
    ----------
    c, g : load damping [1/s] and gravity.
    sigma_accel : std of the tool-acceleration measurement [m/s²] (per axis).
    sigma_model : std of the white angular-acceleration noise the model leaves out [rad/s²/√Hz].
    measurement : "angles" (α, β with ``sigma_angle`` [rad]) or "payload" (load minus tool in {d}
        with ``sigma_pos`` [m]).
    """

    c: float = 0.1
    g: float = G
    sigma_accel: float = 0.05
    sigma_model: float = 1e-3
    measurement: str = "angles"
    sigma_angle: float = math.radians(0.5)
    sigma_pos: float = 0.01
    x: NDArray[np.float64] = field(default_factory=lambda: np.zeros(4))
    P: NDArray[np.float64] = field(default_factory=lambda: np.diag([0.05**2, 0.05**2, 0.1**2, 0.1**2]))
    innovation: NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    nis: float = 0.0  # normalised innovation squared of the last update

    def __post_init__(self) -> None:
        if self.measurement not in MEASUREMENTS:
            raise AntiSwingError(
                f"swing measurement must be one of {', '.join(MEASUREMENTS)}, got {self.measurement!r}"
            )
        for name in ("sigma_accel", "sigma_model", "sigma_angle", "sigma_pos"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise AntiSwingError(f"swing estimator {name} must be positive, got {v!r}")

    def reset(self, x0: ArrayLike | None = None, P0: ArrayLike | None = None) -> None:
        self.x = np.zeros(4) if x0 is None else np.array(x0, dtype=float)
        self.P = np.diag([0.05**2, 0.05**2, 0.1**2, 0.1**2]) if P0 is None else np.array(P0, dtype=float)

    def predict(self, dt: float, a_t_d: ArrayLike, L: float, Ld: float = 0.0) -> None:
        """Propagate by dt with the measured tool acceleration a_t^d (3,) [m/s²] in {d}, wire L, L̇.

        The mean by RK4 of eqs. (29)–(30); the covariance with the continuous Jacobians J = ∂f/∂x and
        J_a = ∂f/∂a (central differences) as F = I + J dt + (J dt)²/2 and F_a = (I dt + J dt²/2) J_a."""
        a = np.asarray(a_t_d, dtype=float)
        x0 = self.x
        J = np.empty((4, 4))
        for j in range(4):
            e = np.zeros(4)
            e[j] = 1e-6
            J[:, j] = (
                swing_derivative(x0 + e, a, L, Ld, self.c, self.g) - swing_derivative(x0 - e, a, L, Ld, self.c, self.g)
            ) / 2e-6
        Ja = np.empty((4, 3))
        for j in range(3):
            e = np.zeros(3)
            e[j] = 1e-4
            Ja[:, j] = (
                swing_derivative(x0, a + e, L, Ld, self.c, self.g) - swing_derivative(x0, a - e, L, Ld, self.c, self.g)
            ) / 2e-4
        Jdt = J * dt
        F = np.eye(4) + Jdt + 0.5 * Jdt @ Jdt
        Fa = (np.eye(4) * dt + 0.5 * Jdt * dt) @ Ja
        self.x = swing_rk4(x0, dt, a, L, Ld, self.c, self.g)
        q = self.sigma_model**2 * dt
        Qm = np.diag([q * dt * dt / 3, q * dt * dt / 3, q, q])  # white angular acceleration, integrated
        Qm[0, 2] = Qm[2, 0] = Qm[1, 3] = Qm[3, 1] = q * dt / 2
        self.P = F @ self.P @ F.T + self.sigma_accel**2 * (Fa @ Fa.T) + Qm

    def h(self, x: NDArray[np.float64], L: float) -> NDArray[np.float64]:
        if self.measurement == "angles":
            return x[:2].copy()
        return L * swing_direction(x[0], x[1])

    def update(self, z: ArrayLike, L: float) -> None:
        """Correct with one measurement z: (α, β) [rad] or the load minus the tool in {d} [m] (3,)."""
        z = np.asarray(z, dtype=float)
        if self.measurement == "angles":
            H = np.zeros((2, 4))
            H[0, 0] = H[1, 1] = 1.0
            Rm = self.sigma_angle**2 * np.eye(2)
        else:
            H = np.zeros((3, 4))
            for j in range(2):
                e = np.zeros(4)
                e[j] = 1e-7
                H[:, j] = (self.h(self.x + e, L) - self.h(self.x - e, L)) / 2e-7
            Rm = self.sigma_pos**2 * np.eye(3)
        y = z - self.h(self.x, L)
        S = H @ self.P @ H.T + Rm
        K = np.linalg.solve(S, H @ self.P).T  # P Hᵀ S⁻¹ (S symmetric)
        self.x = self.x + K @ y
        IKH = np.eye(4) - K @ H
        self.P = IKH @ self.P @ IKH.T + K @ Rm @ K.T  # Joseph form: stays symmetric positive definite
        self.innovation = y
        self.nis = float(y @ np.linalg.solve(S, y))

    def record(self) -> tuple:
        """The estimator's parameter record for :data:`SWING_EKF`."""
        return (
            self.c, self.g, self.sigma_accel, self.sigma_model, self.measurement == "payload",
            self.sigma_angle, self.sigma_pos,
        )  # fmt: skip

    def nees(self, x_true: ArrayLike) -> float:
        """Normalised estimation error squared eᵀP⁻¹e of the estimate against the true state."""
        e = np.asarray(x_true, dtype=float) - self.x
        return float(e @ np.linalg.solve(self.P, e))

    def sigma(self) -> NDArray[np.float64]:
        """Standard deviations of the state estimate (4,)."""
        return np.sqrt(np.clip(np.diag(self.P), 0.0, None))


def _ekf_reference(x, u, p, dt):
    """The NumPy reference of :data:`SWING_EKF`: :meth:`SwingEkf.predict` then :meth:`SwingEkf.update`."""
    c, g, sigma_accel, sigma_model, payload, sigma_angle, sigma_pos = p
    a_t_d, L_prev, L_dot, z, L = u
    f = SwingEkf(
        c=c, g=g, sigma_accel=sigma_accel, sigma_model=sigma_model, measurement=MEASUREMENTS[int(payload)],
        sigma_angle=sigma_angle, sigma_pos=sigma_pos, x=np.array(x[0], dtype=float), P=np.array(x[1], dtype=float),
    )  # fmt: skip
    f.predict(dt, a_t_d, L_prev, L_dot)
    f.update(z, L)
    return (f.x, f.P), (f.innovation, f.nis)


#: the swing estimator as a block: the measured tool acceleration and a wire measurement in, the swing out
SWING_EKF = Block(
    "swing estimator (EKF)",
    state=("x_hat", "P"),
    inputs=("a_t_d", "L_prev", "L_dot", "z", "L"),
    outputs=("innovation", "nis"),
    params=("c", "g", "sigma_accel", "sigma_model", "payload", "sigma_angle", "sigma_pos"),
    reference=_ekf_reference,
    kernel=antisway_kernels.ekf_block,
)


def _swing_control_reference(x, u, p, dt):
    """The NumPy reference of :data:`SWING_CONTROL`: :data:`SWING_EKF`, the tilt, :data:`ANTISWAY_LAW`."""
    x_hat, P, tilt, _, lp, lv, la, L_prev = x
    a_d, z, L, L_dot, active = u
    ekf_p, law_p, g, tau = p
    (x_hat, P), (y, nis) = _ekf_reference((x_hat, P), (a_d, L_prev, L_dot, z, L), ekf_p, dt)
    # the quasi-static tilt of the compensation's own tool acceleration (without the law's), low-passed
    a_comp = a_d[:2] - la
    k = 1.0 - math.exp(-dt / tau)
    new_tilt = tilt + k * (np.array([a_comp[0], -a_comp[1]]) / g - tilt)
    tilt_rate, tilt = (new_tilt - tilt) / dt, new_tilt
    x_swing = x_hat - np.concatenate([tilt, tilt_rate])
    (lp, lv, la), (saturated,) = _law_reference((lp, lv, la), (x_swing, L, active), law_p, dt)
    zero = np.zeros(1)
    out = (np.concatenate([lp, zero]), np.concatenate([lv, zero]), saturated, y, nis)
    return (x_hat, P, tilt, tilt_rate, lp, lv, la, L), out


#: the estimator, the quasi-static tilt (app.scenarios.swing) and the law composed: the lab's anti-swing
SWING_CONTROL = Block(
    "swing control (EKF, tilt, LQR)",
    state=("x_hat", "P", "tilt", "tilt_rate", "p", "v", "a", "L_prev"),
    inputs=("a_t_d", "z", "L", "L_dot", "active"),
    outputs=("p_d", "v_d", "saturated", "innovation", "nis"),
    params=("ekf", "law", "g", "tilt_tau"),
    reference=_swing_control_reference,
    kernel=antisway_kernels.swing_control_block,
)
