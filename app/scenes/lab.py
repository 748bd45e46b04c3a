"""The Motion-Lab scene: two Stewart platforms, the Comau robot on EM8000, its winch and the hanging load,
wired with their controllers as one diagram (issue 29, items 2–3).

Plants (:mod:`app.sim`): the platforms (:mod:`app.sim.stewart`), the Comau's drives, the winch drum and the load
(:mod:`app.sim.motionlab`).  Controllers (:mod:`app.control.lab`): the Comau's law (REMOTE, MOTION_COMP) and the
winch's heave compensation.  Sensors: the controllers see the platforms as measured (an MRU or a tracker,
:meth:`MotionLab.set_sensors`) or true.  :data:`LAB_DIAGRAM` names the blocks and their connections;
:meth:`MotionLab.step` runs it, compiled in one call (:func:`app.scenes.lab_kernels.lab_step`) or block by
block in NumPy (the reference), tested equal in ``tests/test_sim_kernels.py``.

Frames (Motion-Lab paper Table 4): world {g} (z-up), platform neutral frames {n1}, {n2} and body frames {b1},
{b2} (z-down), robot base {r} (z-up), tool point {t}; the load in {d} (see :mod:`app.sim.motionlab`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.control.guard import scale_in_box
from app.control.lab import BRAKE, COMAU_GUARD, COMAU_LAW, WINCH_GUARD, WINCH_LAW, ComauGuard, guard_world_reference
from app.errors import BosunError
from app.models import lab_kernels as model_kernels
from app.models.closed_form import ComauArm
from app.models.comau import ComauKinematics, nearest_ik, tool_on_platform
from app.models.lab import LabLayout
from app.models.registry import load_robot
from app.models.stewart import StewartPlatform
from app.scenes import lab_kernels
from app.scenes.load_lead import LoadLead
from app.sim import kernels as sim_kernels
from app.sim.motionlab import COMAU_DRIVES, R_G_D, WINCH_DRUM, Pendulum, Winch
from app.sim.stewart import MotionFilter, Platform

__all__ = ["COMAU_MODES", "REMOTE_TOOL_SPEED", "WINCH_MODES", "LabError", "LabSample", "MotionLab"]

COMAU_MODES = ("settled", "remote", "motion_comp", "hold")  # hold: after an E-STOP reset, until commanded
WINCH_MODES = ("local", "remote", "motion_comp")
#: how far the operator may shift the work point from its place on EM1500 in MOTION_COMP, per axis [m]; within
#: it, the shifted point must stay in the Comau's reach with both platforms at neutral and WORK_REACH_MARGIN
#: around it (the sea moves the platforms): assumed values, checked in tests/test_lab_remote_vvmc.py
WORK_SHIFT_MAX = np.array([1.0, 1.0, 1.0])
WORK_REACH_MARGIN = 0.15
#: the operator's deck frame in EM1500's body frame {b2} (z down, as the platforms' frames): x along {b2}'s x,
#: z up, so the stick's z raises the work point as it raises the tool in REMOTE (where {r} has z up)
R_B2_DECK = np.diag([1.0, -1.0, -1.0])
REMOTE_TOOL_SPEED = 0.25  # m/s at full stick (Comau REMOTE)
#: the frames VVMC can hold the work point in: ``deck``, fixed on EM1500 (the paper's: the point rolls with the
#: deck), or ``level``, over a spot on EM1500's deck along gravity (the landing frame, issue 30: :meth:`set_work_frame`)
WORK_FRAMES = ("deck", "level", "world")
#: VVMC's engagement (H106): the tool goes from where it is, at the speed it has, onto the work point along a cubic
#: lasting at least ENGAGE_TIME and long enough that its offset's own rate stays about ENGAGE_SPEED (assumed values;
#: stepping onto the point jerked the load on its wire to 1.6–1.9× its weight and slack between, at Hs 2.5 m)
ENGAGE_TIME, ENGAGE_SPEED = 3.0, 0.1
#: the load lead of the level work frame (issue 30, :meth:`MotionLab._lead_step`): at most this far [m] (within
#: WORK_REACH_MARGIN, which the reach check keeps around the operator's point), faded in over LEAD_FADE [s] from
#: the frame's capture (the quintic of H108: no step in the tool's target when VVMC engages)
LEAD_MAX, LEAD_FADE = 0.10, 2.0


class LabError(BosunError):
    """A Motion-Lab command that cannot be carried out (one line)."""


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
        self.tool_velocity_cmd = np.zeros(3)  # REMOTE: in {r} [m/s]; MOTION_COMP: the work point's in {b2}
        self.work_hazard: tuple | None = None  # the work point's range edge near (issue 32, item 5)
        self._range_held = False
        # the operator's shift of the work point in {b2} under VVMC (issue 30, item 4) and its rate
        self.work_shift, self.work_shift_rate = np.zeros(3), np.zeros(3)
        self.work_shift_limited = False  # the last shift was stopped by WORK_SHIFT_MAX or the Comau's reach
        # the level work frame: the spot on EM1500's deck (in {b2}, z = 0) and the point's offset from it in {n2}
        self.work_frame = "deck"
        self._level_load, self._level_pay = None, 0.0
        self._engage: tuple | None = None  # VVMC's engagement: (e₀, ė₀ in {b2}, its duration, time since it began)
        self.level_spot, self.level_offset = np.zeros(3), np.zeros(3)
        # the level frame leads the spot so the load hanging below follows the deck (issue 30: _lead_step)
        self.load_lead = False
        self.lead_shape = False  # the operator's move led too (the anti-swing's shaping)
        self._lead: LoadLead | None = None
        self._c_dot = np.zeros(3)
        self.lead_ref_d: tuple | None = None  # the lead and the tool's planned acceleration in {d}, for the swing law
        self._R_d_n2 = R_G_D.T @ layout.T_world_n2[:3, :3]
        self.winch = Winch(layout.winch)
        self.pendulum = Pendulum(damping=layout.payload_damping)
        self.T_n1_g = np.linalg.inv(layout.T_world_n1)
        # constants and buffers of the compiled step (C-contiguous float64: one kernel signature)
        self._rates_buf = np.zeros((2, 3, 3, 3))
        self._rate_views = tuple((b[0], b[1], b[2]) for b in self._rates_buf)
        self._comau = np.array([arm.a1, arm.d1, arm.a2, arm.a3, arm.L], dtype=float)
        self._T_world_n = tuple(np.ascontiguousarray(T, dtype=float) for T in (layout.T_world_n1, layout.T_world_n2))
        T_n1_n2 = self.T_n1_g @ layout.T_world_n2
        c = tuple(np.ascontiguousarray(a, dtype=float) for a in (arm.T_world_base, ComauArm.SIGNS["auto"]))
        c += (*self._T_world_n,)
        c += tuple(np.ascontiguousarray(a, dtype=float) for a in (T_n1_n2, layout.T_b1_r, layout.work_point_b2))
        c += (np.ascontiguousarray(layout.park_q, dtype=float),)
        # the geometry record of lab_step: (cm, T_base, signs, T_g_n1, T_g_n2, T_n1_n2, T_b1_r, w_b2, park_q, legs…)
        m1, m2 = self.models
        self._geometry = (self._comau, *c, m1.a_n, m1.b_b, m2.a_n, m2.b_b)
        self._target = np.zeros(3)
        self._out = tuple(np.zeros(n) for n in (3, 3, 3, 6, 6))  # e_t_b2, p_w_g, p_p_g, legs1, legs2
        # the Comau's guard against the platforms (issue 32, item 5) and its report of the last step
        self.guard = ComauGuard.for_lab(self.robot, self._comau, layout.T_b1_r, (m1, m2))
        self._guard_p = self.guard.record()
        self.guard_report = np.array([-1.0, -1.0, np.nan, np.nan, 0.0])
        self._use_kernels = False  # the set-up below runs the reference; the flag is set at the end
        self.payload_target_b2: NDArray[np.float64] | None = None
        # what the controllers see of the platforms: None, true; else a sensor per platform (MRU or tracker)
        self.sensors: tuple | None = None
        self.measured: tuple[tuple[NDArray, NDArray, NDArray], ...] | None = None
        self.tool_offset = (np.zeros(3), np.zeros(3))  # added to the work point the Comau tracks (p, v in {n1})
        self.t, self.frozen = 0.0, False
        # the swing left its model (H118); the pendulum is the load's model (else a wire-angle sensor's view of one)
        self.load_model_lost, self.pendulum_is_load = False, True
        self.at_limit = np.zeros(4, dtype=bool)  # joints 1–3, winch: at a position or speed limit
        self.q_work = self.work_configuration()
        if at_work:
            self.joints.reset(self.q_work)
        self._rates = self._rotation_rates()
        self._update_tool()
        self.last: LabSample | None = self._sample()
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
        w, wd = self.layout.work_point_b2 + self.work_shift, self.work_shift_rate
        T_n1_n2 = self.T_n1_g @ self.layout.T_world_n2
        R12 = T_n1_n2[:3, :3]
        p = T_n1_n2[:3, 3] + R12 @ (eta[:3] + R @ w)
        v = R12 @ (eta_dot[:3] + Rd @ w + R @ wd)
        a = R12 @ (eta_ddot[:3] + Rdd @ w + 2.0 * Rd @ wd)
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
        use = bool(getattr(self.robot, "use_kernels", False))
        return nearest_ik(self.arm, p_tr, q_near, self.joints.lower, self.joints.upper, use)

    def place_work_point(self, shift_b2: ArrayLike) -> None:
        """Start with the work point moved by ``shift_b2`` (in {b2}) and the Comau's tool on it, both platforms at
        neutral (a transfer's pick-up point, :mod:`app.scenarios.lab_transfer`); a shift past
        :data:`WORK_SHIFT_MAX` or out of the Comau's reach (with its margin) is refused."""
        shift = np.asarray(shift_b2, dtype=float)
        if shift.shape != (3,) or not np.all(np.isfinite(shift)):
            raise LabError("a work point shift is 3 finite numbers (m, in EM1500's frame)")
        if np.any(np.abs(shift) > WORK_SHIFT_MAX) or not self._reachable(shift):
            raise LabError(f"the work point shifted by {np.round(shift, 3).tolist()} m is out of the Comau's reach")
        T_n1_n2 = self.T_n1_g @ self.layout.T_world_n2
        R_r, p_r = self.layout.T_b1_r[:3, :3], self.layout.T_b1_r[:3, 3]
        p_n1 = T_n1_n2[:3, :3] @ (self.layout.work_point_b2 + shift) + T_n1_n2[:3, 3]
        q = self._ik(R_r.T @ (p_n1 - p_r), self.q_work)
        assert q is not None  # _reachable said so
        self.work_shift, self.work_shift_rate = shift.copy(), np.zeros(3)
        if self.work_frame != "deck":
            self._capture_level()
        self._engage = None  # the tool is put on the point: nothing to engage
        self.joints.reset(q)
        self.refresh()

    # ------------------------------------------------------------------ commands
    def set_comau_mode(self, mode: str) -> None:
        if mode not in COMAU_MODES:
            raise LabError(f"Comau mode must be one of {', '.join(COMAU_MODES)}, got {mode!r}")
        self.comau_mode = mode
        self.tool_velocity_cmd = np.zeros(3)
        if mode == "motion_comp":  # VVMC starts on the work point itself (no shift left from before)
            self.work_shift, self.work_shift_rate = np.zeros(3), np.zeros(3)
            self.work_shift_limited = False
            if self.work_frame != "deck":
                self._capture_level()
            self._start_engagement()
        else:
            self._engage = None

    def _start_engagement(self) -> None:
        """H106: from where the tool is, and how it moves, relative to the work point (e₀ and ė₀ in {b2}) onto the
        work point along the cubic Hermite e(τ) = (2τ³ − 3τ² + 1) e₀ + (τ³ − 2τ² + τ) T ė₀, τ = t/T, which starts
        at e₀ with the rate ė₀ (no step in the tool's position or velocity: the stiff wire rang to 1.87× the
        load's weight at a velocity step of a few cm/s) and ends on the point at rest relative to it;
        T = max(ENGAGE_TIME, 1.5 |e₀| / ENGAGE_SPEED)."""
        self._rates = self._rotation_rates()  # the tool where the machines are now (a scenario may have moved them)
        self._update_tool()
        p2 = self.platforms[1]
        T_g_n2 = self.layout.T_world_n2
        R, Rd, _ = StewartPlatform.rotation_rates(p2.eta, p2.eta_dot, p2.eta_ddot)
        R2, Rd2 = T_g_n2[:3, :3] @ R, T_g_n2[:3, :3] @ Rd
        o2 = T_g_n2[:3, :3] @ p2.eta[:3] + T_g_n2[:3, 3]
        r = self.p_t_g - o2
        e0 = R2.T @ r - (self.layout.work_point_b2 + self.work_shift)
        e0_dot = Rd2.T @ r + R2.T @ (self.v_t_g - T_g_n2[:3, :3] @ p2.eta_dot[:3])
        size = float(np.linalg.norm(e0))
        if size < 1e-9 and float(np.linalg.norm(e0_dot)) < 1e-9:
            self._engage = None
            return
        self._engage = (e0, e0_dot, max(ENGAGE_TIME, 1.5 * size / ENGAGE_SPEED), 0.0)

    def engagement(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The engagement's offset of the work point in {b2} and its rate now (zeros once it is done)."""
        if self._engage is None:
            return np.zeros(3), np.zeros(3)
        e0, e0_dot, T, t = self._engage
        tau = min(1.0, t / T)
        t2, t3 = tau * tau, tau * tau * tau
        e = (2.0 * t3 - 3.0 * t2 + 1.0) * e0 + (t3 - 2.0 * t2 + tau) * T * e0_dot
        e_dot = (6.0 * t2 - 6.0 * tau) * e0 / T + (3.0 * t2 - 4.0 * tau + 1.0) * e0_dot
        return e, e_dot

    def set_work_frame(self, frame: str, spot_b2: ArrayLike | None = None) -> None:
        """Hold the work point, under VVMC, in ``frame`` (:data:`WORK_FRAMES`).  ``deck``: fixed on EM1500 (the
        paper's VVMC; 3.3 m above the deck, the point sweeps 0.29 m sideways at 5° of roll, and a load hanging from
        it swings).  ``level``: over a spot on EM1500's deck along gravity: the spot (below the work point, on the
        top plate) moves with the deck, the point's offset from it stays in EM1500's level neutral frame {n2}, so
        the tool follows the spot's heave, surge and sway but not the deck's tilt (what a hanging load can follow).
        ``world``: fixed in the lab's world (EM1500's neutral frame {n2}, so only EM8000's motion is compensated:
        the lab's version of the crane-head paper's TAC; the winch holds the load's height in the world too).
        ``spot_b2``: the level frame's spot on the deck (x, y in {b2}; a landing spot), else the one under the work
        point.  The switch keeps the work point where it is."""
        if frame not in WORK_FRAMES:
            raise LabError(f"work frame must be one of {', '.join(WORK_FRAMES)}, got {frame!r}")
        if self.comau_mode == "motion_comp" and frame != self.work_frame:
            self._keep_point()  # the frame changes under VVMC: the point stays where it is, its shift in {b2} now
        self.work_frame = frame
        self._spot_given = None
        if spot_b2 is not None:
            spot = np.asarray(spot_b2, dtype=float)
            if spot.shape != (3,) or not np.all(np.isfinite(spot)):
                raise LabError("a spot on the deck is 3 finite numbers (m, in EM1500's frame)")
            self._spot_given = np.array([spot[0], spot[1], 0.0])
        if frame in ("level", "world"):
            self._capture_level()

    def _keep_point(self) -> None:
        """The deck frame's shift is the work point's place on EM1500: keep it at the moving frame's present value
        (the level and world frames recompute theirs each step)."""
        self.work_shift_rate = np.zeros(3)

    def _capture_level(self) -> None:
        """The level frame's spot (the deck point under the work point) and the offset that keeps the point; the
        world frame's: the point itself, fixed in {n2}'s coordinates (the lab's world), and no offset."""
        w = self.layout.work_point_b2 + self.work_shift
        self._level_load, self._level_pay = None, 0.0  # the winch's target in the level frame, from its capture
        self._lead, self.lead_ref_d = None, None  # the load lead fades in again from here
        eta = self._seen_state(1)[0]
        R = StewartPlatform.rotation_rates(*self._seen_state(1))[0]
        if self.work_frame == "world":
            self.level_spot, self.level_offset = eta[:3] + R @ w, np.zeros(3)
            return
        given = getattr(self, "_spot_given", None)
        self.level_spot = np.array([w[0], w[1], 0.0]) if given is None else given.copy()
        self.level_offset = R @ (w - self.level_spot)

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
        self.load_model_lost = False
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
        self._shift_work_point(dt)
        if self._engage is not None:  # the engagement at the step's end (the law's target is for the step's end)
            self._engage = (*self._engage[:3], self._engage[3] + dt)
        self.last = self._step_compiled(dt) if self._use_kernels else self._step_reference(dt)
        if self._engage is not None and (self._engage[3] >= self._engage[2] or self.comau_mode != "motion_comp"):
            self._engage = None
        if self.pendulum_is_load and not self.pendulum.in_model():
            self._lose_load_model()
        return self.last

    def _lose_load_model(self) -> None:
        """The swing left its model (H118): the lab stops, says so, and hangs the load at rest (no number downstream
        the model no longer means)."""
        self.pendulum.alpha = self.pendulum.beta = self.pendulum.alpha_dot = self.pendulum.beta_dot = 0.0
        self.load_model_lost = True
        self.estop()
        self.refresh()

    def _law_shift(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The work point's shift the Comau's law tracks: the operator's (and the level frame's) and the
        engagement's (H106)."""
        if self._engage is None:
            return self.work_shift, self.work_shift_rate
        d, dd = self.engagement()
        return np.ascontiguousarray(self.work_shift + d), np.ascontiguousarray(self.work_shift_rate + dd)

    def _shift_work_point(self, dt: float) -> None:
        """REMOTE under VVMC (issue 30, item 4): in MOTION_COMP the operator's velocity (``tool_velocity_cmd``, in
        the deck frame: EM1500's {b2} turned by :data:`R_B2_DECK`, z up) moves the work point on EM1500, within
        :data:`WORK_SHIFT_MAX` and the Comau's reach; the law holds the tool on the moved point relative to EM1500
        (its feed-forward has the shift's rate).  Stopped, braked or in any other mode the shift holds."""
        cmd = self.tool_velocity_cmd
        if self.work_frame in ("level", "world") and self.comau_mode == "motion_comp" and dt > 0:
            self._shift_level(dt)
            return
        if self.comau_mode != "motion_comp" or self.frozen or not (cmd[0] or cmd[1] or cmd[2]) or dt <= 0:
            if self.work_shift_rate[0] or self.work_shift_rate[1] or self.work_shift_rate[2]:
                self.work_shift_rate = np.zeros(3)  # the shift holds (the common case costs no array work)
            return
        rate = R_B2_DECK @ np.asarray(cmd, dtype=float)
        rate = self._scaled_in_range(rate, self.work_shift, dt)
        shift = self.work_shift
        if np.any(rate != 0.0):
            want = self.work_shift + rate * dt
            shift = np.clip(want, -WORK_SHIFT_MAX, WORK_SHIFT_MAX)
            self.work_shift_limited = bool(np.any(shift != want)) or self._range_held
            if not self._reachable(shift):  # the last reachable point holds
                shift, self.work_shift_limited = self.work_shift, True
        self.work_shift_rate = (shift - self.work_shift) / dt
        self.work_shift = shift

    def _scaled_in_range(self, rate: NDArray[np.float64], shift: NDArray[np.float64], dt: float) -> NDArray:
        """The operator's rate of the work point's shift [m/s], its outward part slowed through the outer quarter
        of ±WORK_SHIFT_MAX (issue 32, item 5: direction-aware, :func:`app.control.guard.scale_in_box`; inward and
        along an edge never); :attr:`work_hazard` says which edge is near: (axis, distance [m], slowed) or None."""
        step, axis, gap = scale_in_box(rate * dt, shift, WORK_SHIFT_MAX)
        slowed = bool(np.any(np.abs(step) < np.abs(rate * dt) - 1e-15))
        self.work_hazard = (axis, gap, slowed) if axis >= 0 else None
        # at its range (work_shift_limited): an axis asked outward keeps under a fifth of its step (5 cm from it)
        self._range_held = bool(np.any(np.abs(step) < 0.2 * np.abs(rate * dt)))
        return step / dt

    def _seen_state(self, k: int) -> tuple[NDArray, NDArray, NDArray]:
        """Platform k's η, η̇, η̈ as the controllers see it (the sensor's, or true)."""
        if self.measured is not None:
            return self.measured[k]
        p = self.platforms[k]
        return p.eta, p.eta_dot, p.eta_ddot

    def _shift_level(self, dt: float) -> None:
        """The level work frame (:meth:`set_work_frame`): the operator's velocity (deck axes, z up) moves the point's
        offset c from the spot s in {n2} (z down), within WORK_SHIFT_MAX and the Comau's reach, checked at neutral,
        where the shift is s + c − w.  The shift in {b2} is then d = s − w + Rᵀ c and its rate ḋ = Ṙᵀ c + Rᵀ ċ, with
        EM1500's rotation R and its rate Ṙ as the controllers see them (eqs. 33, 47), so the tool point is at
        s + c in {n2}'s axes: it follows the spot's heave, surge and sway, not the deck's tilt."""
        w0 = self.layout.work_point_b2
        R, Rd, Rdd = self._tilt(1)
        if self.work_frame == "world":  # the spot fixed in {n2}: seen from EM1500 it moves, d/dt Rᵀ(P − η)
            eta, eta_dot = self._seen_state(1)[:2]
            r = self.level_spot - eta[:3]
            spot, spot_dot, neutral = R.T @ r, Rd.T @ r - R.T @ eta_dot[:3], self.level_spot
        else:
            spot, spot_dot = self.level_spot, np.zeros(3)
            neutral = spot
        cmd = self.tool_velocity_cmd
        c_dot = np.zeros(3)
        if not self.frozen and (cmd[0] or cmd[1] or cmd[2]):
            c_dot = R_B2_DECK @ np.asarray(cmd, dtype=float)  # {n2} has {b2}'s axes at neutral (z down)
            c_dot = self._scaled_in_range(c_dot, neutral + self.level_offset - w0, dt)
            want = neutral + self.level_offset + c_dot * dt - w0
            shift = np.clip(want, -WORK_SHIFT_MAX, WORK_SHIFT_MAX)
            self.work_shift_limited = bool(np.any(shift != want)) or self._range_held
            if bool(np.any(shift != want)) or not self._reachable_near(shift):
                c_dot, self.work_shift_limited = np.zeros(3), True
            else:
                self.level_offset = self.level_offset + c_dot * dt
        c = self.level_offset
        if self.load_lead and self.work_frame == "level":
            f, f_dot = self._lead_step(dt, spot, Rdd, c_dot)
            self.work_shift = spot - w0 + R.T @ (c + f)
            self.work_shift_rate = spot_dot + Rd.T @ (c + f) + R.T @ (c_dot + f_dot)
        else:
            self.work_shift = spot - w0 + R.T @ c
            self.work_shift_rate = spot_dot + Rd.T @ c + R.T @ c_dot
        if self.payload_target_b2 is not None and self.winch.mode == "motion_comp":
            # the winch's target in the level frame too: under the tool, at its height above the spot in {n2} (the
            # operator's lowering, which the law adds along {b2}'s z within the step, carried over step by step)
            if self._level_load is None:
                self._level_load = R @ (self.payload_target_b2 - spot)
            else:
                self._level_load[2] += self._level_pay
            self._level_load[:2] = c[:2]
            self.payload_target_b2[:] = spot + R.T @ self._level_load
            top = self.winch.spec["speed"]
            self._level_pay = float(np.clip(self.winch.speed_command, -top, top)) * dt
        else:
            self._level_load = None

    def _lead_step(
        self, dt: float, spot: NDArray, Rdd: NDArray, c_dot: NDArray
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The load lead f (in {n2}) and its rate: the tool held at spot + c + f so that the load hanging L below it
        follows the spot + c, not the tool (:class:`app.scenes.load_lead.LoadLead`), with the spot's acceleration
        ẍ_spot = η̈₁₋₃ + R̈ s (eq. 51's R̈, the spot s in {b2}) and, with ``lead_shape``, the operator's (ċ's
        difference).  Without it the 2 m pendulum (2.8 s) driven by the deck's 8 s motion overshoots the spot by
        ω²/(ω₀² − ω²), 8 % of the deck's sway (the path error VVMC left, docs/transfer.md).  Capped at LEAD_MAX and
        faded in over LEAD_FADE from the frame's capture."""
        if self._lead is None:
            self._lead = LoadLead(dt, LEAD_MAX, LEAD_FADE, shape=self.lead_shape)
            self._c_dot = c_dot
        a = self._seen_state(1)[2][:3] + Rdd @ spot
        f, (_, a_ref) = self._lead.step(a, (c_dot - self._c_dot) / dt, float(self.winch.length))
        self._c_dot = c_dot
        R_d_n2 = self._R_d_n2
        self.lead_ref_d = (R_d_n2 @ f, R_d_n2 @ a_ref)
        return f, self._lead.rate

    def _tilt(self, k: int) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Platform k's R, Ṙ and R̈ (eqs. 33, 47, 51) as the controllers see it (compiled with the lab's kernels)."""
        eta, eta_dot, eta_ddot = self._seen_state(k)
        if self._use_kernels:
            R, Rd, Rdd = model_kernels.stewart_rates(
                *(np.ascontiguousarray(a, dtype=float) for a in (eta, eta_dot, eta_ddot))
            )
        else:
            R, Rd, Rdd = StewartPlatform.rotation_rates(eta, eta_dot, eta_ddot)
        return R, Rd, Rdd

    def _reachable_near(self, shift: NDArray[np.float64]) -> bool:
        """:meth:`_reachable`, checked again once the shift has moved 10 mm from the last shift found reachable (the
        0.15 m margin of the check holds far more than that in between)."""
        last = getattr(self, "_reach_ok", None)
        if last is not None and float(np.max(np.abs(shift - last))) <= 0.01:
            return True
        ok = self._reachable(shift)
        self._reach_ok = shift.copy() if ok else None
        return ok

    def _reachable(self, shift: NDArray[np.float64]) -> bool:
        """The work point shifted by ``shift`` (in {b2}), and WORK_REACH_MARGIN around it along each axis, in
        the Comau's reach with both platforms at neutral (the analytic IK within the joint limits in force)."""
        T_n1_n2 = self.T_n1_g @ self.layout.T_world_n2
        R_r, p_r = self.layout.T_b1_r[:3, :3], self.layout.T_b1_r[:3, 3]
        w = self.layout.work_point_b2 + shift
        for k in range(7):
            d = np.zeros(3)
            if k:
                d[(k - 1) // 2] = WORK_REACH_MARGIN if k % 2 else -WORK_REACH_MARGIN
            p_n1 = T_n1_n2[:3, :3] @ (w + d) + T_n1_n2[:3, 3]
            if self._ik(R_r.T @ (p_n1 - p_r), self.q_work) is None:
                return False
        return True

    def refresh(self) -> LabSample:
        """Recompute the derived state (rotation rates, tool point, the sample) from the machines' states
        as they are, without stepping: the ``plc`` plant backend sets platform poses, joints and wire
        length from the real lab's measurements and calls this (app/plant/plc.py)."""
        self._rates = self._rotation_rates()
        self._update_tool()
        self.last = self._sample()
        return self.last

    def _records(self, dt: float) -> tuple[int, bool]:
        """The Comau's mode for its law and whether the winch tracks (E-STOP: brake, winch at zero speed)."""
        if self.frozen:
            self.winch.speed_command = 0.0
        mode = BRAKE if self.frozen else COMAU_MODES.index(self.comau_mode)  # hold and E-STOP brake alike
        return mode, not self.frozen and self.winch.mode == "motion_comp"

    def _step_compiled(self, dt: float) -> LabSample:
        """The diagram after the platforms in one :func:`app.scenes.lab_kernels.lab_step` call."""
        (p1, p2), f, w, pd = self.platforms, self.joints, self.winch, self.pendulum
        wf = w.filter
        mode, track = self._records(dt)
        has = self.payload_target_b2 is not None
        target = self.payload_target_b2 if has else self._target
        e_b2, p_w_g = self._out[:2]
        true = (p1.filter.x, p1.filter.v, p1.filter.a, p2.filter.x, p2.filter.v, p2.filter.a)
        seen = (False, *true) if self.measured is None else (True, *self.measured[0], *self.measured[1])
        v_cmd = np.ascontiguousarray(self.tool_velocity_cmd, dtype=float)
        x = ((f.x, f.v, f.a), (wf.x, wf.v, wf.a), (pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot), (target, has))
        offset = (*self.tool_offset, *self._law_shift())
        u = (true, seen, (mode, v_cmd, offset, track, float(w.speed_command)))
        wire = (wf.lower, wf.upper, wf.speed, wf.accel, float(wf.tau))
        p = (self._geometry, f.limits(), wire, (float(pd.damping), float(pd.g)), self._guard_p)
        y = (self._rates_buf, self.p_t_n1, self.p_t_g, self.v_t_g, self.a_t_g, self.at_limit, *self._out)
        y = y + (self.guard_report,)
        has, pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot, h_err = lab_kernels.lab_step(x, u, p, y, float(dt))
        if has and self.payload_target_b2 is None:
            self.payload_target_b2 = target.copy()
        self._rates = self._rate_views
        if self._engage is not None:  # the sample's work point is the operator's, not the engagement's way to it
            d = offset[2] - self.work_shift
            e_b2 += d
            R2 = self._rates_buf[1, 0]
            T_g_n2 = self._T_world_n[1]
            p_w_g[:] = p_w_g - T_g_n2[:3, :3] @ (R2 @ d)
        return self._compiled_sample(h_err)

    def _compiled_sample(self, h_err: float, swing: tuple[float, float] | None = None) -> LabSample:
        """The sample after a compiled step (its records hold the step's outputs; ``h_err`` the payload height
        error it returned; ``swing`` the pendulum's angles it left, where something has set them since)."""
        (p1, p2), f, wf, pd = self.platforms, self.joints, self.winch.filter, self.pendulum
        e_b2, p_w_g, p_p_g, legs1, legs2 = self._out
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
            swing=(pd.alpha, pd.beta) if swing is None else swing,
            payload_height_error=h_err,
        )

    def _step_reference(self, dt: float) -> LabSample:
        """The diagram after the platforms block by block, each block's NumPy reference ."""
        self._rates = self._rotation_rates()
        f, wf, pd = self.joints, self.winch.filter, self.pendulum
        mode, track = self._records(dt)
        (e1, ed1, _, (R1, Rd1, _)), (e2, ed2, _, (R2, Rd2, _)) = self._view(0), self._view(1)
        g = self._geometry
        # the Comau: its law, then its drives
        v_cmd = np.asarray(self.tool_velocity_cmd, dtype=float)
        offset = (*self.tool_offset, *self._law_shift())
        u = (mode, f.x, v_cmd, offset, (e1, ed1, R1, Rd1, e2, ed2, R2, Rd2))
        law_p = (*g[:3], *g[5:9], f.lower, f.upper)
        _, command = COMAU_LAW.step((), u, law_p, dt, use_kernels=False)
        world = self._guard_world(e1, R1, e2, R2)
        guard_p = (g[0], self._guard_p[0], f.limits(), self._guard_p[5])
        _, (command, report) = COMAU_GUARD.step((), (command, f.x, f.v, world), guard_p, dt, use_kernels=False)
        self.guard_report[:] = report
        (f.x, f.v, f.a, _), _ = COMAU_DRIVES.step((f.x, f.v, f.a, self.at_limit), command, f.limits(), dt, False)
        self._update_tool()
        # the winch: its law (EM1500 as the controllers see it, eq. 39), then its drum
        H2 = self.layout.T_world_n2 @ StewartPlatform.pose_matrix(e2)
        has = self.payload_target_b2 is not None
        tool, swing = (self.p_t_g, self.v_t_g), (pd.alpha, pd.beta)
        u = (track, float(self.winch.speed_command), wf.x, swing, tool, (H2, Rd2, ed2))
        (target, has), ref = WINCH_LAW.step((self.payload_target_b2, has), u, (g[4], wf.speed), dt, False)
        if has:
            self.payload_target_b2 = target
        wire = (wf.lower, wf.upper, wf.speed, wf.accel, wf.tau)
        u = (ref, (wf.x, wf.v), (f.x, f.v), world, (self._T_world_n[0], R1, self.layout.T_b1_r),
             (pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot, pd.g))  # fmt: skip
        _, (ref, rep) = WINCH_GUARD.step((), u, (g[0], self._guard_p[0], wire, self._guard_p[5]), dt, False)
        self.guard_report[:] = rep if rep[4] > self.guard_report[4] else self.guard_report  # the arm's first
        (wf.x, wf.v, wf.a, _), _ = WINCH_DRUM.step((wf.x, wf.v, wf.a, self.at_limit), ref, wire, dt, False)
        # the load
        self.pendulum.step(dt, R_G_D.T @ self.a_t_g, self.winch.length, self.winch.speed)
        return self._sample()

    def guard_world(self) -> tuple:
        """The Comau's obstacles in {r} now, as its controller sees the platforms (:meth:`_guard_world`)."""
        (e1, _, _, (R1, _, _)), (e2, _, _, (R2, _, _)) = self._view(0), self._view(1)
        return self._guard_world(e1, R1, e2, R2)

    def _guard_world(self, e1, R1, e2, R2) -> tuple:
        """The Comau's obstacles in {r} (:func:`app.control.lab.guard_world_reference`), the arm moving as it is."""
        pd, v_arm = self.pendulum, self.comau.velocity(self.joints.x, self.joints.v)  # the tool's J q̇ (eq. 5)
        swing = (pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot, float(self.winch.filter.x[0]), pd.g)
        frames = (self._T_world_n[0], self._geometry[5], self.layout.T_b1_r)
        return guard_world_reference(self._guard_p, frames, e1, R1, e2, R2, swing, v_arm)

    def _update_tool(self) -> None:
        p1 = self.platforms[0]
        f = self.joints
        p, v, a = tool_on_platform(
            self.comau, self.layout.T_b1_r, (p1.eta, p1.eta_dot, p1.eta_ddot), (f.x, f.v, f.a), self._rates[0]
        )
        T = self.layout.T_world_n1
        self.p_t_n1 = p
        self.p_t_g = T[:3, :3] @ p + T[:3, 3]  # eq. (55)
        self.v_t_g = T[:3, :3] @ v  # eq. (56), rotated into {g}
        self.a_t_g = T[:3, :3] @ a  # eq. (57), rotated into {g}

    def _b2_to_g(self) -> tuple[NDArray, NDArray]:
        H = self.platform_pose(1)
        return H[:3, :3], H[:3, 3]

    def p_p_g(self) -> NDArray[np.float64]:
        """Payload position in {g}, eq. (58)."""
        return self.p_t_g + R_G_D @ (self.winch.length * self.pendulum.direction())

    def _sample(self) -> LabSample:
        R2, o2 = self._b2_to_g()
        w = self.layout.work_point_b2 + self.work_shift  # where the operator has the work point on EM1500
        e_b2 = R2.T @ (self.p_t_g - o2) - w
        if self.payload_target_b2 is not None:
            target_g = R2 @ self.payload_target_b2 + o2
            h_err = float(self.p_p_g()[2] - target_g[2])
        else:
            h_err = 0.0
        p_w_g = R2 @ w + o2
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
