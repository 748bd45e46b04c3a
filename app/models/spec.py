"""Robot specifications: what a robot XML file says, in SI units and radians.

These are plain data.  Kinematics live in the model classes (``serial.py`` and, for
the parallel mechanisms, their own modules) built from a spec.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

ROBOT_TYPES = ("serial", "delta", "stewart")
JOINT_KINDS = ("revolute", "prismatic", "fixed")
STEWART_DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")


@dataclass(frozen=True, eq=False)
class JointSpec:
    """One actuated joint of a serial chain.

    The DH variable of its link (θ for revolute, d for prismatic) is
    ``sign * q + offset + sum(factor_j * q_j for j, factor_j in coupling)``.

    Attributes
    ----------
    name : str
        The user's name of the joint variable q.
    kind : {"revolute", "prismatic"}
    link : int
        0-based index of the link whose DH variable this joint drives.
    lower, upper : float
        Position limits of q [rad or m].
    speed : float
        Speed limit |q̇| [rad/s or m/s].
    accel : float or None
        Acceleration limit |q̈| [rad/s² or m/s²], None when the file gives none.
    sign : float
        +1 or -1.
    offset : float
        Constant added to the DH variable [rad or m].
    coupling : tuple of (int, float)
        (0-based joint index, factor) pairs; factors are SI ratios (rad/rad, m/m, rad/m).
    """

    name: str
    kind: str
    link: int
    lower: float
    upper: float
    speed: float
    accel: float | None = None
    sign: float = 1.0
    offset: float = 0.0
    coupling: tuple[tuple[int, float], ...] = ()

    @property
    def unit(self) -> str:
        return "rad" if self.kind == "revolute" else "m"


@dataclass(frozen=True, eq=False)
class LinkSpec:
    """One row of a standard DH table, A = Rz(θ) Tz(d) Tx(a) Rx(α) (or, in :attr:`SerialSpec.written` of a modified
    table, one row as the file wrote it: a_{i−1}, α_{i−1}, d_i, θ_i).

    ``theta`` and ``d`` hold the constant parts; the joint (if any) adds to the
    variable one.  ``joint`` is the 0-based index of the joint driving this link,
    or None for a fixed link.
    """

    name: str
    kind: str
    theta: float
    d: float
    a: float
    alpha: float
    joint: int | None = None
    radius: float | None = None  # the link's collision capsule radius [m] (``<collision radius>``; None: as drawn)


@dataclass(frozen=True, eq=False)
class SerialSpec:
    """An open kinematic chain: DH links, joints, fixed base and tool transforms.

    ``up`` names the world axis that points up ("+z" by default, "-z" for a z-down world such as a
    vessel's body frame {b}); only drawings use it, to show the machine the right way up.

    ``links`` is always the standard DH table of the chain.  A file written in the modified convention
    (``convention="modified"``, Craig) is turned into it when read (:func:`standard_from_modified`): the same
    chain to rounding, so every kernel, solver, drawing and study runs on it unchanged; ``convention`` says how
    the file wrote it and ``written`` keeps the rows as written.
    """

    links: tuple[LinkSpec, ...]
    joints: tuple[JointSpec, ...]
    T_world_base: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    T_flange_tool: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    up: str = "+z"
    convention: str = "standard"
    written: tuple[LinkSpec, ...] = ()


def standard_from_modified(
    rows: tuple[LinkSpec, ...], T_world_base: NDArray[np.float64]
) -> tuple[tuple[LinkSpec, ...], NDArray[np.float64]]:
    """The standard DH table and base of a chain written in the modified convention (Craig, *Introduction to
    Robotics*, 3rd ed., §3.4: row i holds a_{i−1}, α_{i−1}, d_i, θ_i and ᶦ⁻¹T_i = Rx(α_{i−1}) Tx(a_{i−1}) Rz(θ_i)
    Tz(d_i)).

    Rx(α) and Tx(a) commute (a rotation about x and a translation along it), so the chain

        B · Rx(α₀)Tx(a₀) · Rz(θ₁)Tz(d₁) · Rx(α₁)Tx(a₁) · Rz(θ₂)Tz(d₂) ⋯ Rz(θₙ)Tz(dₙ)

    regroups into standard links Rz(θ_i)Tz(d_i)Tx(a_i)Rx(α_i) — each row's θ and d with the *next* row's a and α
    (the last link's a = α = 0) — behind the base B · Rx(α₀)Tx(a₀).  Exact but for rounding; the joints keep
    their rows (a joint drives θ_i or d_i of its own row in both)."""
    from dataclasses import replace

    if not rows:
        return rows, T_world_base
    a0, al0 = rows[0].a, rows[0].alpha
    c, s = math.cos(al0), math.sin(al0)
    first = np.array([[1.0, 0.0, 0.0, a0], [0.0, c, -s, 0.0], [0.0, s, c, 0.0], [0.0, 0.0, 0.0, 1.0]])
    after = (*((r.a, r.alpha) for r in rows[1:]), (0.0, 0.0))  # each row's next row's a and α
    links = tuple(replace(row, a=a, alpha=alpha) for row, (a, alpha) in zip(rows, after, strict=True))
    return links, np.asarray(T_world_base, dtype=float) @ first


@dataclass(frozen=True, eq=False)
class DeltaSpec:
    """A three-arm Delta parallel mechanism (TAC paper §2, Table 1 and Table 4).

    Attributes
    ----------
    l_k, l_a, l_r, l_p : float
        Base-centre-to-arm, arm, rod and top-plate-centre-to-rod lengths [m].
    arm_rotations : ndarray, shape (3,)
        Angle of R_x for each arm frame {t_i} in {t}, TAC eq. (1) [rad].
    alpha_min, alpha_max, speed : float
        Arm angle limits [rad] and arm speed limit [rad/s].
    accel : float or None
        Arm acceleration limit [rad/s²].
    motor_time_constant, motor_gain : float or None
        First-order DC-motor model T_DC [s] and K_DC [-], TAC eq. (58).
    pid : tuple of float or None
        (K_p, K_i, K_d) of the arm-angle PID, TAC eq. (57).
    """

    l_k: float
    l_a: float
    l_r: float
    l_p: float
    arm_rotations: NDArray[np.float64]
    alpha_min: float
    alpha_max: float
    speed: float
    accel: float | None = None
    motor_time_constant: float | None = None
    motor_gain: float | None = None
    pid: tuple[float, float, float] | None = None


@dataclass(frozen=True, eq=False)
class StewartSpec:
    """A six-leg Stewart platform.

    Attributes
    ----------
    base_joints_n : ndarray, shape (6, 3)
        Lower leg joints in the neutral frame {n} [m].
    platform_joints_b : ndarray, shape (6, 3)
        Upper leg joints in the platform body frame {b} [m].
    leg_min, leg_max : float
        Leg length limits, joint centre to joint centre [m].
    leg_speed : float
        Leg speed limit [m/s].
    leg_accel : float or None
        Leg acceleration limit [m/s²].
    pose_min, pose_max : ndarray, shape (6,)
        Limits on η = (surge, sway, heave, roll, pitch, yaw) [m, rad].
    speed_max, accel_max : ndarray, shape (6,)
        Symmetric limits on η̇ and η̈ [m/s, rad/s; m/s², rad/s²].
    """

    base_joints_n: NDArray[np.float64]
    platform_joints_b: NDArray[np.float64]
    leg_min: float
    leg_max: float
    leg_speed: float
    leg_accel: float | None
    pose_min: NDArray[np.float64]
    pose_max: NDArray[np.float64]
    speed_max: NDArray[np.float64]
    accel_max: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class RatedCapacity:
    """A crane's rated capacity per radius in calm water (its static load chart, issue 31 item 4): ``radius``
    [m] increasing, ``capacity`` [kg] not rising with it, and where the numbers come from.  Between two ratings
    the capacity is the lower of the two (a load chart is read at the next radius out, as on a crane's own
    chart: never an interpolated figure above the one printed); inside the first rating's radius that rating's (the
    next one out); beyond the last the crane is not rated (None)."""

    radius: NDArray[np.float64]
    capacity: NDArray[np.float64]
    source: str

    def at(self, r: float) -> float | None:
        """The rated capacity [kg] at radius ``r`` [m] (the next rating out), or None beyond the last rating."""
        if not (math.isfinite(r) and 0.0 <= r <= self.radius[-1] + 1e-9):
            return None
        k = int(np.searchsorted(self.radius, r - 1e-9, side="left"))
        return float(self.capacity[min(k, self.capacity.size - 1)])


@dataclass(frozen=True, eq=False)
class RobotSpec:
    """Everything a robot file says: identity, provenance and one mechanism."""

    name: str
    type: str
    description: str
    source: str
    assumptions: str = ""
    path: str | None = None
    serial: SerialSpec | None = None
    delta: DeltaSpec | None = None
    stewart: StewartSpec | None = None
    rated_capacity: RatedCapacity | None = None  # a crane's load chart (<rated_capacity>), if the file gives one

    @property
    def dof(self) -> int:
        """Number of actuated degrees of freedom."""
        if self.serial is not None:
            return len(self.serial.joints)
        if self.delta is not None:
            return 3
        return 6
