"""Simulation of the supply vessel, crane and Delta head in irregular seas (TAC paper §9–10).

A :class:`TacSimulator` advances in chunks: vessel motion for the chunk (vectorised), the crane
joints (cooperative mode only), the head references of eqs. (49)–(56) (vectorised), then the PID
and DC motors step by step, and e_c, e_s of eq. (61).  The CLI runs whole scenarios through it;
the engine streams it to the GUI a tick at a time.

With ``use_kernels`` (the default when numba is there) a chunk after the vessel motion is one
compiled call, :func:`app.scenes.tac_kernels.tac_chunk` (the crane-head scene, :mod:`app.scenes.tac`); with
``use_kernels = False`` every part runs its NumPy reference (tested equal in ``tests/test_tac_kernels.py``).

Modes: ``off`` (head held at p_d^t = [x_d, 0, 0] by its servo: the uncompensated TCP), ``tac`` (the paper:
crane still in the configuration of eq. (60), head compensates), ``cooperative`` (crane joints
take a share of the motion within their speed and acceleration limits, head the rest).  Every arm and
joint moves within its robot file's speed limit, also when a mode changes (the head's motors saturate in
speed: :class:`~app.scenes.tac.HeadServo`).

Live changes (the engine's ``set_sea``, ``set_vessel``): a new simulator takes over from the running one
(:meth:`TacSimulator.continue_from`): its clock continues, the machine's states carry over, and the vessel's
motion fades from the old sea (or vessel) into the new over two peak periods (:class:`SeaTransition`), so the
head's reference stays continuous and the machine continues where it is.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.control.tac import PidGains
from app.errors import BosunError
from app.geometry import euler_zyx_to_matrix
from app.marine import kernels as marine_kernels
from app.marine.vessel import MRU, RAOTable, VesselMotion, VesselState, body_velocities
from app.marine.vessels import vessel_rao
from app.marine.waves import SPECTRA, check_sea, wave_components
from app.models.crane_head import CraneHead
from app.models.crane_head_kernels import c_array
from app.models.registry import load_robot
from app.scenes import tac_kernels
from app.scenes.tac import CraneServo, HeadServo

MODES = ("off", "tac", "cooperative")
BETA_EQ60 = np.array([-math.pi / 2, math.pi / 4, -math.pi / 4])  # eq. (60)
HOLD_RATE = 0.25  # rad/s: the head's arms return to α_d at this rate when the compensation goes off (assumed)
#: s: a change of the servos' references eases in over this time (H108): a resumption (after an E-STOP, or
#: compensation chosen in ``off``) from the pose the machine is in, a release (compensation switched off) from the
#: compensating references to the hold.  At once, head and crane jumped onto the new references and snatched the
#: hanging load (16x its weight resuming after a stop, 2.9x switching off at Hs 3 m).  Assumed: about a wave
#: period, so the TCP's velocity changes by the vessel's over seconds, not at once.
RESUME_TIME = 5.0
PREDICT_DT = 0.1  # s: the motion predictor's sample time (app.control.predict.PredictorSpec.dt)
SEA_BLEND_PERIODS = 2.0  # a live sea or vessel change fades the motions over this many peak periods


class ScenarioError(BosunError):
    """A bad simulation setting (names the setting)."""


@dataclass(frozen=True)
class TacScenario:
    """One simulation run; angles in degrees at this edge, SI elsewhere."""

    hs: float = 3.0
    tp: float = 9.0
    heading: float = 90.0  # wave heading [deg], 0 following, 90 beam, 180 head sea
    spectrum: str = "jonswap"
    spreading: int | None = None  # cos^2s short-crested sea; None = long-crested
    duration: float = 600.0  # [s]
    dt: float = 0.01  # [s]
    seed: int = 1
    mode: str = "tac"
    rao: str | None = None  # vessel name or RAO file (.mat or .csv); None = the default vessel (app/marine/vessels.py)
    roll_damping: float = 0.15  # ζ44 of the closed-form vessel (supply-closed-form)
    crane_share: float = 0.3  # chosen from a share × k_p sweep at Hs 4.5–5 m (README)
    crane_kp: float = 1.0
    mru_noise: float = 0.0  # scale of the MRU noise (1 = 2 cm, 0.05°, 2 cm/s, 0.1°/s)
    delay: float = 0.0  # s: the measurement-to-actuation delay (issue 31, item 2): the controller sees η, ν this old
    predict: bool = False  # feed the motion predicted ``delay`` ahead (app.control.predict) instead of the delayed
    n_freq: int = 200
    crane: str = "offshore_crane"
    head: str = "tac_delta_head"

    def __post_init__(self) -> None:
        try:
            check_sea(self.hs, self.tp)
        except BosunError as exc:
            raise ScenarioError(str(exc)) from None
        checks = [
            (self.mode in MODES, f"mode must be one of {', '.join(MODES)}, got '{self.mode}'"),
            (self.spectrum in SPECTRA, f"spectrum must be one of {', '.join(SPECTRA)}, got '{self.spectrum}'"),
            (math.isfinite(self.heading), "heading must be a number"),
            (math.isfinite(self.duration) and self.duration > 0, f"duration must be positive, got {self.duration}"),
            (math.isfinite(self.dt) and 0 < self.dt <= 0.05, f"dt must be in (0, 0.05] s, got {self.dt}"),
            (self.duration / self.dt <= 5e7, "duration / dt is too many steps"),
            (0.0 <= self.crane_share <= 1.0, f"crane share must be in [0, 1], got {self.crane_share}"),
            (self.crane_kp >= 0, "crane k_p must not be negative"),
            (self.mru_noise >= 0, "MRU noise scale must not be negative"),
            (math.isfinite(self.delay) and 0.0 <= self.delay <= 2.0, f"delay must be in [0, 2] s, got {self.delay}"),
            (
                not self.predict or abs(round(PREDICT_DT / self.dt) * self.dt - PREDICT_DT) < 1e-9,
                f"--predict needs a time step that divides {PREDICT_DT:g} s, got {self.dt}",
            ),
            (self.n_freq >= 1, "n_freq must be at least 1"),
        ]
        for ok, msg in checks:
            if not ok:
                raise ScenarioError(msg)

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class TacChunk:
    """Samples of one chunk; arrays have the chunk length as first axis."""

    t: NDArray[np.float64]
    eta: NDArray[np.float64]
    beta: NDArray[np.float64]
    p_ref_t: NDArray[np.float64]
    p_c_t: NDArray[np.float64]
    alpha_ref: NDArray[np.float64]
    alpha: NDArray[np.float64]
    u: NDArray[np.float64]
    p_c_n: NDArray[np.float64]
    p_s_n: NDArray[np.float64]
    e_c: NDArray[np.float64]
    e_s: NDArray[np.float64]
    saturated: NDArray[np.bool_]

    FIELDS = (
        ("t", ("t",)),
        ("eta", ("x", "y", "z", "phi", "theta", "psi")),
        ("beta", ("beta0", "beta1", "beta2")),
        ("p_ref_t", ("p_ref_x", "p_ref_y", "p_ref_z")),
        ("p_c_t", ("p_c_x", "p_c_y", "p_c_z")),
        ("alpha_ref", ("alpha_ref1", "alpha_ref2", "alpha_ref3")),
        ("alpha", ("alpha1", "alpha2", "alpha3")),
        ("u", ("u1", "u2", "u3")),
        ("p_c_n", ("p_c_n_x", "p_c_n_y", "p_c_n_z")),
        ("p_s_n", ("p_s_n_x", "p_s_n_y", "p_s_n_z")),
        ("e_c", ("e_c",)),
        ("e_s", ("e_s",)),
        ("saturated", ("saturated",)),
    )

    @staticmethod
    def concat(chunks: list[TacChunk]) -> TacChunk:
        return TacChunk(**{name: np.concatenate([getattr(c, name) for c in chunks]) for name, _ in TacChunk.FIELDS})

    def columns(self) -> tuple[list[str], NDArray[np.float64]]:
        """Column names and an (n, m) array for CSV export (angles in rad)."""
        names, cols = [], []
        for attr, labels in self.FIELDS:
            arr = np.asarray(getattr(self, attr), dtype=float).reshape(len(self.t), -1)
            names += list(labels)
            cols.append(arr)
        return names, np.hstack(cols)


@dataclass
class TacResult:
    scenario: TacScenario
    data: TacChunk
    x_d: float
    p_d_n: NDArray[np.float64]
    wall_time_s: float = 0.0
    cancelled: bool = False
    summary: dict = field(default_factory=dict)


def summarise(data: TacChunk, scenario: TacScenario, wall_time_s: float) -> dict:
    """rms and max of e_c, e_s, their ratio, % of time saturated, simulation speed."""
    e_c, e_s = data.e_c, data.e_s
    rms_c = float(np.sqrt(np.mean(e_c**2))) if e_c.size else 0.0
    rms_s = float(np.sqrt(np.mean(e_s**2))) if e_s.size else 0.0
    sim_time = float(data.t[-1] - data.t[0] + scenario.dt) if data.t.size else 0.0
    return {
        "rms_e_c_m": rms_c,
        "rms_e_s_m": rms_s,
        "max_e_c_m": float(e_c.max()) if e_c.size else 0.0,
        "max_e_s_m": float(e_s.max()) if e_s.size else 0.0,
        "ratio_rms": rms_c / rms_s if rms_s > 0 else 0.0,
        "saturated_pct": float(100.0 * np.mean(data.saturated)) if data.saturated.size else 0.0,
        "simulated_s": sim_time,
        "wall_time_s": wall_time_s,
        "speed_x_realtime": sim_time / wall_time_s if wall_time_s > 0 else float("inf"),
        "steps": int(data.t.size),
    }


class SeaTransition:
    """The vessel's motion while a live sea or vessel change takes effect: ``old`` fades into ``new`` over
    ``duration`` seconds from ``t0``, at constant power,

        η(t) = cos θ η_old(t) + sin θ η_new(t),   θ = (π/2) S((t − t0) / T),

    with S(x) = 6x⁵ − 15x⁴ + 10x³ (zero slope and curvature at both ends), η̇ and η̈ by the product rule, so
    η, η̇ and η̈ are continuous at both ends; ν and ν̇ follow from them by the kinematics (Fossen 2011, eq. 2.40)
    as in :class:`~app.marine.vessel.VesselMotion`, so the head's references (TAC paper eqs. 49–56) stay
    continuous and consistent.  Two independent realisations of one sea keep its variance (cos² + sin² = 1);
    between two seas it goes from one to the other.  A real sea changes over hours; a simulator's operator
    wants the new sea within a minute.  Over two peak periods the blend's own terms, θ̇ ≤ 2.95/T times the
    motion, stay under a quarter of the wave-induced rates (ω_p = 2π/T_p times the motion) at their peak.

    ``old`` and ``new`` give ``eta_derivatives(t)`` and ``sea`` (a :class:`~app.marine.vessel.VesselMotion` or
    another transition); ``sea`` here is the new one's.
    """

    def __init__(self, old, new, t0: float, duration: float) -> None:
        if not (math.isfinite(t0) and math.isfinite(duration) and duration > 0):
            raise ScenarioError(f"a sea transition needs a finite start and a positive duration, got {t0}, {duration}")
        self.old, self.new, self.t0, self.duration = old, new, float(t0), float(duration)
        self.use_kernels = bool(getattr(new, "use_kernels", False))

    @property
    def sea(self):
        return self.new.sea

    @property
    def end(self) -> float:
        return self.t0 + self.duration

    def settled(self, t: float):
        """The motion from time ``t`` on: ``new`` once the fade is over (the old ones dropped), else this one."""
        if t >= self.end:
            return self.new
        if isinstance(self.old, SeaTransition):
            self.old = self.old.settled(t)
        return self

    def angle(self, t: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
        """θ, θ̇, θ̈ at times ``t`` (each like t)."""
        T = self.duration
        x = np.clip((np.asarray(t, dtype=float) - self.t0) / T, 0.0, 1.0)
        h = 0.5 * math.pi
        theta = h * x**3 * (10.0 + x * (6.0 * x - 15.0))
        theta_dot = h * 30.0 * (x * (1.0 - x)) ** 2 / T
        theta_ddot = h * 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x) / T**2
        return theta, theta_dot, theta_ddot

    def eta_derivatives(self, t: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
        """η, η̇, η̈ at times ``t`` (s), each (len(t), 6)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        a0, a1, a2 = self.old.eta_derivatives(t)
        b0, b1, b2 = self.new.eta_derivatives(t)
        th, th1, th2 = (x[:, None] for x in self.angle(t))
        c, s = np.cos(th), np.sin(th)
        eta = c * a0 + s * b0
        quad = c * b0 - s * a0  # dη/dθ
        deta = c * a1 + s * b1 + th1 * quad
        ddeta = c * a2 + s * b2 + 2.0 * th1 * (c * b1 - s * a1) + th2 * quad - th1**2 * eta
        return eta, deta, ddeta

    def state(self, t: ArrayLike) -> VesselState:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        eta, deta, ddeta = self.eta_derivatives(t)
        if self.use_kernels:
            nu, nu_dot = marine_kernels.body_velocities(eta, deta, ddeta)
        else:
            nu, nu_dot = body_velocities(eta, deta, ddeta)
        return VesselState(t, eta, nu, nu_dot)


class TacSimulator:
    """Stepwise simulation of one scenario (see the module docstring)."""

    def __init__(self, scenario: TacScenario, system: CraneHead | None = None, rao: RAOTable | None = None) -> None:
        self.scenario = sc = scenario
        if system is None:
            system = CraneHead(load_robot(sc.crane), load_robot(sc.head))
        self.system = system
        rng = np.random.default_rng(sc.seed)
        if rao is None:  # the scenario's vessel (a name or a file); else a table handed over (an engine's upload)
            rao = vessel_rao(sc.rao, sc.roll_damping)
        sea = wave_components(
            sc.spectrum, sc.hs, sc.tp, rng, n_freq=sc.n_freq, heading=math.radians(sc.heading), spreading=sc.spreading
        )
        self.vessel_rao = rao
        self.vessel = VesselMotion(rao, sea)
        s = sc.mru_noise
        self.mru = (
            MRU(
                np.random.default_rng(sc.seed + 1),
                noise_eta=np.array([0.02, 0.02, 0.02, *np.radians([0.05, 0.05, 0.05])]) * s,
                noise_nu=np.array([0.02, 0.02, 0.02, *np.radians([0.1, 0.1, 0.1])]) * s,
            )
            if s > 0
            else None
        )
        self.beta_d = BETA_EQ60.copy()
        head = system.head
        self.p_d_n = system.tcp_n(np.zeros(6), self.beta_d, system.p_d_t)  # p_d^n: TCP in calm water
        self.p_d_n0 = self.p_d_n.copy()  # where the operator's moves of p_d^n start from (issue 30, item 2)
        self.n_steps = round(sc.duration / sc.dt)
        self.k = 0
        self.head_servo = HeadServo(PidGains(), head.lower, head.upper, system.alpha_d, head.speed)
        crane = system.crane
        self.crane_servo = CraneServo(
            crane.lower, crane.upper, crane.speed, crane.accel, self.beta_d, sc.crane_share, sc.crane_kp
        )
        # constants of the compiled chunk (C-contiguous float64)
        self._servo_args, self._crane_args = self.head_servo.kernel_args(), self.crane_servo.kernel_args()
        self._alpha_d, self._p_d_t = c_array(system.alpha_d), c_array(system.p_d_t)
        self._beta0_hint = float(self.beta_d[0])
        self._started = False
        self._beta_c_prev: NDArray[np.float64] | None = None
        self._use_kernels = tac_kernels.ENABLED
        #: steps of vessel motion computed at once and handed out by :meth:`advance` (0: each advance computes its
        #: own; a caller that advances a step or two at a time, ``sim transfer``, sets it: one vectorised call
        #: instead of hundreds)
        self.lookahead = 0
        #: what the head's servo holds in ``off``: α_d, reached at HOLD_RATE from where a mode change left the arms
        #: (H103: a step to α_d drove the motors at full speed, 5 m/s at the TCP, and snatched the hanging load)
        self._hold_ref = np.array(system.alpha_d, dtype=float)
        self._ahead: tuple[int, VesselState] | None = None
        #: a change of references easing in (H108): [time since it began, release, α_f, β_f, from cooperative];
        #: a resumption eases in from the pose α_f, β_f, a release from the compensating references; None: none
        self._fade: list | None = None
        self._was_frozen = False
        self._alpha_rate = np.zeros(3)  # the arms' rate at the end of the last chunk (a resumption starts from it)
        self._foresight = None  # the motion predictor hiding the delay, with scenario.predict (issue 31, item 2)
        self._past: VesselState | None = None  # the last ``delay`` of true states, with scenario.delay

    def continue_from(self, old: TacSimulator, blend: float) -> None:
        """Take over from ``old``, live (a sea or vessel change in the engine): its clock continues (this
        run's ``duration`` from its time on), the machine's states carry over (head servo α, ∫α̃, u; crane β,
        β̇ and the cooperative crane's last target), and ``old``'s vessel motion fades into this one's over
        ``blend`` seconds (:class:`SeaTransition`).  So nothing the machine does jumps: the head's reference is
        continuous and every arm and joint moves on within its limits."""
        if old.system is not self.system or old.scenario.dt != self.scenario.dt:
            raise ScenarioError("a simulator continues another only on the same crane head and time step")
        self.k = old.k
        self.n_steps = old.k + round(self.scenario.duration / self.scenario.dt)
        h, c, oh, oc = self.head_servo, self.crane_servo, old.head_servo, old.crane_servo
        h.alpha, h.integral, h.u = (np.array(x, dtype=float) for x in (oh.alpha, oh.integral, oh.u))
        c.beta, c.beta_dot = np.array(oc.beta, dtype=float), np.array(oc.beta_dot, dtype=float)
        self._beta_c_prev = None if old._beta_c_prev is None else np.array(old._beta_c_prev, dtype=float)
        self._beta0_hint = old._beta0_hint
        self.p_d_n = np.array(old.p_d_n, dtype=float)  # where the operator has moved the TCP target
        self._started = old._started
        self._hold_ref = np.array(old._hold_ref, dtype=float)
        self._fade = None if old._fade is None else list(old._fade)
        self._alpha_rate = old._alpha_rate.copy()
        self._was_frozen = old._was_frozen
        self.vessel = SeaTransition(old.vessel, self.vessel, old.k * self.scenario.dt, blend)
        self.use_kernels = old.use_kernels
        self._foresight, self._past = old._foresight, old._past  # the motion predictor runs on

    def move_target(self, dp_n: NDArray[np.float64], limit: NDArray[np.float64]) -> bool:
        """Move the TCP's target p_d^n by ``dp_n`` in {n} (the operator's stick, issue 30, item 2), its offset from
        the calm-water point kept within ±``limit`` per axis: a step that would take an axis further out is not
        taken on that axis (one already outside, after a mode change, may only come back).  True when a step
        was held back."""
        old = self.p_d_n - self.p_d_n0
        new = old + np.asarray(dp_n, dtype=float)
        out = (np.abs(new) > limit) & (np.abs(new) > np.abs(old))
        new[out] = old[out]
        self.p_d_n = self.p_d_n0 + new
        return bool(np.any(out))

    @property
    def use_kernels(self) -> bool:
        """One compiled call per chunk (and compiled parts); False: every part in its NumPy reference.

        Setting it sets the flag of the servos and of the (possibly shared) crane-head system too.
        """
        return self._use_kernels

    @use_kernels.setter
    def use_kernels(self, on: bool) -> None:
        self._use_kernels = bool(on)
        self.system.use_kernels = self.head_servo.use_kernels = self.crane_servo.use_kernels = bool(on)

    def set_mode(self, mode: str) -> None:
        """Switch the compensation mode live; the joints continue from where they are (the head servo restarts
        bumpless there), and the new references fade in over :data:`RESUME_TIME` (H108): compensation chosen in
        ``off`` from the pose the machine is in, ``off`` from the compensating references (tac and cooperative
        between themselves need none: the head's reference already follows the crane's pose)."""
        if mode not in MODES:
            raise ScenarioError(f"mode must be one of {', '.join(MODES)}, got '{mode}'")
        old = self.scenario.mode
        if mode == "off" and old != "off":
            self._hold_ref = np.array(self.head_servo.alpha, dtype=float)  # H103: the hold from where the arms are
            self._begin_fade(release=True, cooperative=old == "cooperative")  # H108: from the compensating references
        elif old == "off" and mode != "off":
            self._begin_fade()  # H108: the compensating references eased in from where head and crane are
        self.scenario = replace(self.scenario, mode=mode)
        self.head_servo.reset(self.head_servo.alpha)
        self._beta_c_prev = None

    def _begin_fade(self, release: bool = False, cooperative: bool = False) -> None:
        """Ease the servos' references in over :data:`RESUME_TIME` (H108): from the pose the machine is in now (a
        resumption), or from the compensating references of the mode left (a release; ``cooperative``: the
        crane's too)."""
        if self._started:
            pose = (np.array(self.head_servo.alpha, dtype=float), np.array(self.crane_servo.beta, dtype=float))
            self._fade = [0.0, release, *pose, cooperative, self._alpha_rate.copy()]

    def _resume_from(self, n: int) -> tuple[NDArray, NDArray]:
        """Where the resumption starts from at the next ``n`` steps, and its rate (n, 3) each: the pose α_f going on
        at the arms' rate when it began, dying away (:func:`app.scenes.tac_kernels.resume_start`)."""
        f, tk = self._fade, tac_kernels
        t = f[0] + (1 + np.arange(n)) * self.scenario.dt
        e = np.exp(-t / tk.RESUME_DRIFT)[:, None]
        return f[2] + f[5] * tk.RESUME_DRIFT * (1.0 - e), f[5] * e

    def _fade_gains(self, n: int) -> tuple[NDArray, NDArray, NDArray] | None:
        """The ease-in's s and ṡ for the next ``n`` steps, and whether each still eases (None: no fade)."""
        if self._fade is None:
            return None
        tau = (self._fade[0] + (1 + np.arange(n)) * self.scenario.dt) / RESUME_TIME
        tc = np.clip(tau, 0.0, 1.0)
        return tc**3 * (10.0 + tc * (6.0 * tc - 15.0)), 30.0 * (tc * (1.0 - tc)) ** 2 / RESUME_TIME, tau < 1.0

    def _fade_on(self, n: int) -> None:
        """The fade's clock after ``n`` steps; it ends once eased in."""
        if self._fade is not None:
            self._fade[0] += n * self.scenario.dt
            if self._fade[0] >= RESUME_TIME - 1e-9:
                self._fade = None

    @property
    def _releasing_crane(self) -> bool:
        """Whether the crane still runs the cooperative law, released to β_d (cooperative switched off)."""
        return self._fade is not None and self._fade[1] and self._fade[4]

    @property
    def done(self) -> bool:
        return self.k >= self.n_steps

    def _start(self, first_state) -> None:
        """Start the controllers on their references (no artificial transient at t = 0)."""
        sc, sys_ = self.scenario, self.system
        self._started = True
        if sc.mode == "cooperative":
            beta_c = sys_.crane_ik_tcp(self._target_b(first_state.eta), self._beta0_hint)[0]
            self.crane_servo.beta = self.beta_d + sc.crane_share * (beta_c - self.beta_d)
        if sc.mode != "off":
            ref = sys_.head_reference(
                first_state.eta, first_state.nu, self.crane_servo.beta[None], np.zeros((1, 3)), self.p_d_n
            )
            self.head_servo.reset(ref.alpha_ref[0], ref.alpha_dot_ref[0])

    def _target_b(self, eta: NDArray[np.float64]) -> NDArray[np.float64]:
        """p_d^n in {b}: where the TCP must be, seen from the vessel."""
        R_n_b = euler_zyx_to_matrix(eta[:, 3:6])  # R_b^n
        return np.einsum("nji,nj->ni", R_n_b, self.p_d_n - eta[:, :3])

    def advance(self, n: int, frozen: bool = False) -> TacChunk:
        """Simulate the next ``n`` steps (fewer at the end).

        ``frozen``: the head and crane joints stay where they are (E-STOP) while the vessel moves.
        """
        sc, sys_ = self.scenario, self.system
        n = max(0, min(n, self.n_steps - self.k))
        t = (self.k + 1 + np.arange(n)) * sc.dt
        if isinstance(self.vessel, SeaTransition) and n:
            self.vessel = self.vessel.settled(float(t[0]))
        true = self._vessel_state(t)
        meas = self._measure(t, true)
        if not self._started and n:
            first = self.vessel.state(np.array([self.k * sc.dt]))
            self._start(first)
        if frozen:
            self._fade, self._was_frozen = None, True
        elif self._was_frozen and n:
            self._was_frozen = False
            self._begin_fade()  # H108: out of an E-STOP, from the frozen pose
        if self._use_kernels:
            before = np.array(self.head_servo.alpha, dtype=float)
            chunk = self._advance_compiled(t, true, meas, frozen)
            self._fade_on(n)
            self._note_rate(chunk.alpha, before)
            return chunk
        ease, fade = self._fade_gains(n), self._fade
        alpha_before = np.array(self.head_servo.alpha, dtype=float)
        # crane
        crane = self.crane_servo
        if frozen:
            crane.beta_dot = np.zeros(3)
            beta = np.broadcast_to(crane.beta, (n, 3)).copy()
            beta_dot = np.zeros((n, 3))
        elif sc.mode == "cooperative" or self._releasing_crane:
            beta_c = sys_.crane_ik_tcp(self._target_b(meas.eta), self._beta0_hint)
            self._beta0_hint = float(beta_c[-1, 0])
            prev = beta_c[0] if self._beta_c_prev is None else self._beta_c_prev
            beta_c_dot = np.diff(np.vstack([prev[None], beta_c]), axis=0) / sc.dt
            self._beta_c_prev = beta_c[-1]
            beta, beta_dot = self._crane_run(beta_c, beta_c_dot, ease)
        elif np.any(crane.beta != self.beta_d) or np.any(crane.beta_dot != 0):
            # after cooperative mode: the crane drives back to the configuration of eq. (60)
            beta, beta_dot = self._crane_run(np.broadcast_to(self.beta_d, (n, 3)), np.zeros((n, 3)), ease)
            if np.allclose(crane.beta, self.beta_d, atol=1e-6) and np.allclose(crane.beta_dot, 0, atol=1e-6):
                crane.beta, crane.beta_dot = self.beta_d.copy(), np.zeros(3)
        else:
            beta = np.broadcast_to(self.beta_d, (n, 3)).copy()
            beta_dot = np.zeros((n, 3))
        # head
        ref = sys_.head_reference(meas.eta, meas.nu, beta, beta_dot, self.p_d_n)
        alpha_ref, p_ref_t = ref.alpha_ref, ref.p_ref_t
        if frozen:  # E-STOP: the arms locked where they are
            alpha = np.broadcast_to(self.head_servo.alpha, (n, 3)).copy()
            u = alpha.copy()
            saturated = np.zeros(n, dtype=bool)
        elif sc.mode == "off":  # the servo holds the head at p_d^t
            hold, hold_dot = np.broadcast_to(self._hold(n), (n, 3)), np.zeros((n, 3))
            if ease is not None and fade[1]:  # H108: released, from the compensating reference to the hold
                hold, hold_dot = self._eased(ref.alpha_ref, ref.alpha_dot_ref, hold, hold_dot, ease)
            elif ease is not None:  # H108: seen from α_f
                hold, hold_dot = self._eased(*self._resume_from(n), hold, hold_dot, ease)
            alpha, u = self.head_servo.run(hold, hold_dot, sc.dt)
            saturated = np.zeros(n, dtype=bool)
        else:
            alpha_dot_ref = ref.alpha_dot_ref
            if ease is not None and not fade[1]:  # H108: seen from α_f
                alpha_ref, alpha_dot_ref = self._eased(*self._resume_from(n), alpha_ref, alpha_dot_ref, ease)
            alpha, u = self.head_servo.run(alpha_ref, alpha_dot_ref, sc.dt)
            saturated = ref.saturated
        p_c_t = sys_.head.fk(alpha)
        p_c_n = sys_.tcp_n(true.eta, beta, p_c_t)
        # the uncompensated TCP: crane in its nominal configuration, head locked at p_d^t
        p_s_n = sys_.tcp_n(true.eta, np.broadcast_to(self.beta_d, (n, 3)), np.broadcast_to(sys_.p_d_t, (n, 3)))
        e_c = np.linalg.norm(self.p_d_n - p_c_n, axis=1)  # eq. (61)
        e_s = np.linalg.norm(self.p_d_n - p_s_n, axis=1)
        self.k += n
        self._fade_on(n)
        self._note_rate(alpha, alpha_before)
        return TacChunk(t, true.eta, beta, p_ref_t, p_c_t, alpha_ref, alpha, u, p_c_n, p_s_n, e_c, e_s, saturated)

    def _note_rate(self, alpha: NDArray, before: NDArray) -> None:
        """The arms' rate at the end of a chunk (α (n, 3) after its steps, ``before`` them)."""
        if alpha.shape[0]:
            prev = alpha[-2] if alpha.shape[0] >= 2 else before
            self._alpha_rate = (alpha[-1] - prev) / self.scenario.dt

    @staticmethod
    def _eased(a, a_dot, b, b_dot, ease: tuple) -> tuple[NDArray, NDArray]:
        """From the references a to b while a fade eases in (H108): a + s (b − a), its rate (1 − s) ȧ + s ḃ + ṡ (b −
        a) (the compiled chunk's order of operations); b on the steps after it ended.  (n, 3) or (3,) each."""
        s, s_dot, on = (x[:, None] for x in ease)
        a, b = np.broadcast_to(a, np.shape(b)), np.asarray(b)
        d = b - a
        rate = (1.0 - s) * a_dot + s * b_dot + s_dot * d if np.any(a_dot) else s * b_dot + s_dot * d
        return np.where(on, a + s * d, b), np.where(on, rate, b_dot)

    def _crane_run(self, beta_c: NDArray, beta_c_dot: NDArray, ease: tuple | None) -> tuple[NDArray, NDArray]:
        """The crane servo on β_d and β_c (n, 3); while a fade eases in, their references from β_f (a
        resumption) or from the cooperative law's to β_d (a release)."""
        crane, dt = self.crane_servo, self.scenario.dt
        if ease is None:
            return crane.run(self.beta_d, beta_c, beta_c_dot, dt)
        n, f = beta_c.shape[0], self._fade
        if f[1]:  # released: from the cooperative law's references to β_d
            b_d = np.broadcast_to(self.beta_d, (n, 3))
            b_c, b_c_dot = self._eased(beta_c, beta_c_dot, b_d, 0.0, ease)
        else:  # resumed: from β_f
            b_c, b_c_dot = self._eased(f[3], 0.0, beta_c, beta_c_dot, ease)
            b_d, _ = self._eased(f[3], 0.0, np.broadcast_to(self.beta_d, (n, 3)), 0.0, ease)
        out = [crane.run(b_d[k], b_c[k : k + 1], b_c_dot[k : k + 1], dt) for k in range(n)]
        return np.vstack([b for b, _ in out]), np.vstack([v for _, v in out])

    def _hold(self, n: int) -> NDArray[np.float64]:
        """The head's hold reference in ``off`` for the next ``n`` steps: α_d, approached at :data:`HOLD_RATE`
        (held over the chunk: the engine's is two steps)."""
        step = HOLD_RATE * n * self.scenario.dt
        d = self.system.alpha_d - self._hold_ref
        self._hold_ref = self._hold_ref + np.clip(d, -step, step)
        return self._hold_ref

    def _measure(self, t: NDArray[np.float64], true: VesselState) -> VesselState:
        """What the controller sees at the times ``t``: the MRU's η, ν of ``scenario.delay`` ago (issue 31, item 2:
        the sensor-to-actuation delay of real equipment), or with ``predict`` the motion predicted that far ahead
        from them (:class:`app.control.predict.MotionPredictor`, fed every :data:`PREDICT_DT` with η and ν)."""
        sc = self.scenario
        if sc.delay <= 0 and not sc.predict:
            return self.mru.measure(true) if self.mru is not None else true
        seen = self._delayed(t, true) if sc.delay > 0 else true
        meas = self.mru.measure(seen) if self.mru is not None else seen
        meas = VesselState(t, meas.eta, meas.nu, meas.nu_dot)
        return self._foresee(meas) if sc.predict else meas

    def _delayed(self, t: NDArray[np.float64], true: VesselState) -> VesselState:
        """The true motion ``scenario.delay`` before the times ``t``: when the delay is whole steps, the states this
        simulator already computed (the last steps' kept, then this chunk's ``true``: no second evaluation of the
        sea on the engine's tick), else evaluated again."""
        sc = self.scenario
        m = round(sc.delay / sc.dt)
        if m == 0 or abs(m * sc.dt - sc.delay) > 1e-9:
            return self.vessel.state(t - sc.delay)
        past = self._past
        if past is None or past.t.size != m or abs(past.t[-1] - (t[0] - sc.dt)) > 1e-9:
            past = self.vessel.state(t[0] - (m - np.arange(m)) * sc.dt)  # the start, or the delay changed
        rows = [np.vstack([a, b]) for a, b in ((past.eta, true.eta), (past.nu, true.nu), (past.nu_dot, true.nu_dot))]
        both_t = np.r_[past.t, true.t]
        n = t.size
        self._past = VesselState(both_t[-m:], *(r[-m:] for r in rows))
        return VesselState(both_t[:n], *(r[:n] for r in rows))

    def _foresee(self, meas: VesselState) -> VesselState:
        """The delayed measurement ``meas`` (at this chunk's steps) replaced by the motion predicted ``delay`` ahead
        (:class:`app.control.predict.Foresight` on η and ν).  The predictor has run on the sensor's last 300 s when
        the run starts (a real one runs all the time; its own noise draws, so the run's MRU noise is the same as
        without prediction)."""
        sc = self.scenario
        if self._foresight is None:
            from app.control.predict import Foresight, PredictorSpec

            spec = PredictorSpec(dt=PREDICT_DT)
            self._foresight = fs = Foresight(12, sc.delay, sc.dt, spec)
            last = (self.k // fs.every) * fs.every * sc.dt  # the last grid point: the feed goes on from the next one
            th = last + np.arange(1 - round(spec.window / PREDICT_DT), 1) * PREDICT_DT
            past = self.vessel.state(th - sc.delay)
            if self.mru is not None:
                m = self.mru
                past = MRU(np.random.default_rng(sc.seed + 2), m.noise_eta, m.noise_nu, m.noise_nu_dot).measure(past)
            fs.predictor.prime(np.hstack([past.eta, past.nu]))
        seen = np.hstack([meas.eta, meas.nu])
        for i in range(meas.t.size):
            seen[i] = self._foresight.step(self.k + 1 + i, seen[i])
        eta, nu = seen[:, :6], seen[:, 6:]
        return VesselState(meas.t, eta, nu, meas.nu_dot)

    def _vessel_state(self, t: NDArray[np.float64]) -> VesselState:
        """The vessel's motion at the next steps ``t``: computed now, or cut from the look-ahead block."""
        n = t.size
        if self.lookahead <= 0 or isinstance(self.vessel, SeaTransition) or n == 0:
            return self.vessel.state(t)
        k0 = self.k + 1
        a = self._ahead
        if a is None or k0 < a[0] or k0 + n > a[0] + a[1].t.size:
            m = max(self.lookahead, n)
            a = self._ahead = (k0, self.vessel.state((k0 + np.arange(m)) * self.scenario.dt))
        i, s = k0 - a[0], a[1]
        return VesselState(s.t[i : i + n], s.eta[i : i + n], s.nu[i : i + n], s.nu_dot[i : i + n])

    def _advance_compiled(self, t: NDArray[np.float64], true, meas, frozen: bool) -> TacChunk:
        """:meth:`advance` after the vessel motion in one call of :func:`~app.scenes.tac_kernels.tac_chunk`."""
        sc, sys_, tk = self.scenario, self.system, tac_kernels
        crane, head = self.crane_servo, self.head_servo
        beta_hold = self.beta_d
        if frozen:
            crane.beta_dot = np.zeros(3)
            crane_mode, beta_hold = tk.CRANE_HOLD, crane.beta
        elif sc.mode == "cooperative" or self._releasing_crane:
            crane_mode = tk.CRANE_COOPERATIVE
        elif np.any(crane.beta != self.beta_d) or np.any(crane.beta_dot != 0):
            crane_mode = tk.CRANE_RETURN  # after cooperative mode: back to the configuration of eq. (60)
        else:
            crane_mode = tk.CRANE_HOLD
        # head: locked where it is (E-STOP), held at p_d^t by its servo (off), or compensating
        head_mode = tk.HEAD_LOCK if frozen else tk.HEAD_HOLD if sc.mode == "off" else tk.HEAD_SERVO
        alpha_lock = head.alpha if frozen else self._hold(t.size) if sc.mode == "off" else sys_.alpha_d
        beta, beta_dot = np.array(crane.beta, dtype=float), np.array(crane.beta_dot, dtype=float)  # fresh: in place
        alpha, integral, u = (np.array(x, dtype=float) for x in (head.alpha, head.integral, head.u))
        has_prev = self._beta_c_prev is not None
        beta_c_prev = np.array(self._beta_c_prev, dtype=float) if has_prev else np.zeros(3)
        f = c_array
        x = ((beta, beta_dot, beta_c_prev, self._beta0_hint, has_prev), (alpha, integral, u))
        inputs = (f(true.eta), f(meas.eta), f(meas.nu), meas is not true)
        r = self._fade
        fade = (
            (0.0, 0.0, False, self._alpha_d, self.beta_d, self._alpha_d)
            if r is None
            else (r[0], RESUME_TIME, r[1], f(r[2]), f(r[3]), f(r[5]))
        )
        setpoints = (f(beta_hold), f(alpha_lock), self._alpha_d, self.beta_d, self.p_d_n, self._p_d_t, fade)
        kinematics = (sys_.crane.kernel_record, sys_.head.kernel_args, sys_.kernel_hull, sys_.kernel_elbow)
        p = ((crane_mode, head_mode, *setpoints), *kinematics, self._crane_args, *self._servo_args)
        out = tk.tac_chunk(x, inputs, p, float(sc.dt))
        n = t.size
        crane.beta, crane.beta_dot = beta, beta_dot
        if not frozen:
            head.alpha, head.integral, head.u = alpha, integral, u
        if crane_mode == tk.CRANE_COOPERATIVE and n:
            self._beta0_hint, self._beta_c_prev = float(beta_c_prev[0]), beta_c_prev
        elif (
            crane_mode == tk.CRANE_RETURN
            and np.allclose(crane.beta, self.beta_d, atol=1e-6)
            and np.allclose(crane.beta_dot, 0, atol=1e-6)
        ):
            crane.beta, crane.beta_dot = self.beta_d.copy(), np.zeros(3)
        self.k += n
        beta_out, p_ref_t, p_c_t, alpha_ref, alpha_out, u_out, p_c_n, p_s_n, e_c, e_s, saturated = out
        return TacChunk(
            t, true.eta, beta_out, p_ref_t, p_c_t, alpha_ref, alpha_out, u_out, p_c_n, p_s_n, e_c, e_s, saturated
        )


def simulate(
    scenario: TacScenario,
    *,
    progress: Callable[[int, int], None] | None = None,
    cancel: Callable[[], bool] | None = None,
    chunk: int = 2000,
    system: CraneHead | None = None,
    use_kernels: bool | None = None,
) -> TacResult:
    """Run a whole scenario; ``progress(done_steps, total_steps)`` after each chunk.

    ``use_kernels``: False runs every part in its NumPy reference (None: the default, compiled when numba
    is there).
    """
    import time

    t0 = time.perf_counter()
    sim = TacSimulator(scenario, system)
    if use_kernels is not None:
        sim.use_kernels = use_kernels
    chunks: list[TacChunk] = []
    cancelled = False
    while not sim.done:
        if cancel is not None and cancel():
            cancelled = True
            break
        chunks.append(sim.advance(chunk))
        if progress is not None:
            progress(sim.k, sim.n_steps)
    wall = time.perf_counter() - t0
    data = TacChunk.concat(chunks) if chunks else sim.advance(0)
    res = TacResult(scenario, data, sim.system.x_d, sim.p_d_n, wall, cancelled)
    res.summary = summarise(data, scenario, wall)
    return res
