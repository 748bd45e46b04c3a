"""Stewart platform plant as the Motion-Lab HMI runs it: modes, motion sources, motion filter.

Modes (the lab HMI's): ``settled`` (resting low on its end stops), ``neutral`` (raised to η = 0)
and ``engaged`` (following a motion source).  Transitions are commanded with :meth:`Platform.command`
(``neutral``, ``settle``, ``engage``, ``disengage``) and are ramped: raising and settling move at a
fifth of the Table 8 speeds, ENGAGE fades the source in over ``ramp_time`` with a smooth-step gain
and DISENGAGE fades it out back to neutral.  Whatever the source and the mode, every pose goes
through :class:`MotionFilter`, so pose, velocity and acceleration never pass the Table 8 limits.

Two boxes (issue 16).  The *command box* (the lab PLC's operational box etaRefMin/Max, from the lab
layout; the Table 8 box when none is given) limits every command: a source's pose is clipped to it
(etaRef = LIMIT(etaRefMin, u, etaRefMax), FB_StewartInterface) and it is the filter's position box
in NEUTRAL and ENGAGED, so no source can pass it.  SETTLED is the pose with all six legs at their
minimum length (the actuators on their lower end stops), found by forward kinematics: the lab's
platforms settle 0.9986 m / 0.4664 m below neutral, beyond Table 8's lowest heave (0.885 / 0.407 m).
Raising and settling therefore run in the *envelope*, Table 8 widened just enough to hold the
settled pose; the filter's box is widened when SETTLE is accepted and narrowed to the command box
only at rest at neutral, so no switch ever leaves the state outside its box.

Sources:

* ``simulation``: a vessel in irregular waves (:class:`app.marine.vessel.VesselMotion`), each DOF
  scaled (``scale``; ``auto`` fits the most probable largest response of a 3-hour sea to 80 % of
  the platform's limit);
* ``generator``: a sine per DOF, amplitude, frequency 0.01–1 Hz and phase;
* ``remote``: the pose last sent by a client;
* ``timeseries``: 6-DOF playback of a CSV with columns ``t,x,y,z,phi,theta,psi`` (s, m, deg).
"""

from __future__ import annotations

import io
import math
from dataclasses import InitVar, dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.csvtext import cells, content_lines, finite_number
from app.errors import BosunError
from app.marine.vessel import VesselMotion, significant_response
from app.marine.waves import spectrum as sea_spectrum
from app.marine.waves import wave_components
from app.models.stewart import StewartPlatform
from app.sim import kernels as sim_kernels
from app.sim.actuators import LimitedAxes, approach_speed, braking_speed

MODES = ("settled", "neutral", "engaged")
SOURCES = ("simulation", "generator", "remote", "timeseries")
ACTIONS = ("neutral", "settle", "engage", "disengage")
TIMESERIES_COLUMNS = ("t", "x", "y", "z", "phi", "theta", "psi")
GENERATOR_FREQ_RANGE = (0.01, 1.0)  # Hz, the lab HMI's sine generator
TRANSFER_SPEED_FRACTION = 0.2  # raising / settling speed as a fraction of the Table 8 speeds


class PlatformError(BosunError):
    """A platform command or a motion source is not valid (one-line message)."""


# ----------------------------------------------------------------------------- filter
@dataclass(eq=False)
class MotionFilter(LimitedAxes):
    """Per-DOF limiter: position, velocity and acceleration never pass their limits.

    Each step the new velocity v⁺ is the desired one (feed-forward v_ref + (x_ref − x)/τ, the
    correction bounded by the braking speed towards x_ref: :func:`~app.sim.actuators.approach_speed`)
    clipped to the intersection of
    [v − a·dt, v + a·dt] (acceleration), [−v_max, v_max] (speed) and the braking speed towards
    each position limit (:meth:`_braking`, exact for the discrete steps, last partial step
    included); then x⁺ = x + v⁺ dt.  Because the braking speed is exact, by induction the
    intersection is never empty: a state the filter produced can always be brought to rest
    inside the limits, and no step crosses a limit.

    The braking deceleration ``brake`` defaults to the acceleration limit; a smaller one is a
    velocity-boundary law of its own, |v⁺| ≤ b(d, A, dt) ≤ min(d/dt, √(2 A d)) with d the distance
    to the limit (the Motion-Lab's Comau program, A = 1 rad/s²: Flacco, De Luca and Khatib, IEEE
    T-RO 2015, eq. 13; here in its exact discrete form :func:`~app.sim.actuators.braking_speed`).
    It must not exceed ``accel``, or a stop along the bound would need more than the limit.

    Parameters
    ----------
    lower, upper, speed, accel : array_like (n,)
    tau : float   time constant of the tracking loop [s]
    brake : array_like (n,), optional   deceleration A of the bound at the position limits
        (default ``accel``; larger values are taken as ``accel``)
    """

    tau: float = 0.1
    brake: InitVar[ArrayLike | None] = None

    def __post_init__(self, brake: ArrayLike | None) -> None:
        super().__post_init__()
        b = self.accel if brake is None else np.minimum(np.asarray(brake, dtype=float), self.accel)
        self.brake = np.array(np.broadcast_to(b, self.accel.shape), dtype=float, order="C")
        self.x = np.zeros_like(self.lower)
        self.v = np.zeros_like(self.lower)
        self.a = np.zeros_like(self.lower)

    def reset(self, x: ArrayLike) -> None:
        self.x, self.v, self.a = self.rest_state(x)

    def set_limits(self, lower: ArrayLike, upper: ArrayLike) -> None:
        """New position limits, written into the same (C-contiguous) arrays.

        Only a box that holds the state and lets it stop inside keeps the filter's guarantee: widening
        always does; a platform narrows its box only at rest inside the new one (:class:`Platform`).
        """
        lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
        if not (np.all(self.x >= lo - 1e-12) and np.all(self.x <= hi + 1e-12)):
            raise PlatformError(f"limits {lo.tolist()} … {hi.tolist()} do not hold the state {self.x.tolist()}")
        self.lower[:] = lo
        self.upper[:] = hi

    def _braking(self, d: NDArray[np.float64], dt: float) -> NDArray[np.float64]:
        return braking_speed(d, self.brake, dt)

    def step(
        self, x_ref: ArrayLike, v_ref: ArrayLike | None, dt: float, speed_scale: float = 1.0
    ) -> NDArray[np.float64]:
        """Advance by ``dt`` toward ``x_ref`` (with feed-forward ``v_ref``); returns the new x.

        Compiled unless ``use_kernels`` is False; the compiled step updates ``x``, ``v`` and ``a`` in
        place (the returned x is the filter's own array: copy what you keep).
        """
        if self.use_kernels:
            use_v = v_ref is not None
            ref = (
                np.ascontiguousarray(x_ref, dtype=float), np.ascontiguousarray(v_ref, dtype=float) if use_v else self.x,
                use_v, float(speed_scale),
            )  # fmt: skip
            sim_kernels.motion_filter_update((self.x, self.v, self.a), ref, self.limits(), float(dt))
            return self.x
        return self._step_reference(x_ref, v_ref, dt, speed_scale)

    def limits(self) -> tuple:
        """The filter's parameter record (lower, upper, speed, accel, brake, τ) of
        :func:`app.sim.kernels.motion_filter_update` (the arrays themselves: limits set later are seen)."""
        return (self.lower, self.upper, self.speed, self.accel, self.brake, float(self.tau))

    def _step_reference(
        self, x_ref: ArrayLike, v_ref: ArrayLike | None, dt: float, speed_scale: float = 1.0
    ) -> NDArray[np.float64]:
        ref = (x_ref, v_ref, v_ref is not None, speed_scale)
        self.x, self.v, self.a = motion_filter_reference((self.x, self.v, self.a), ref, self.limits(), dt)
        return self.x


def motion_filter_reference(state: tuple, ref: tuple, limits: tuple, dt: float) -> tuple:
    """The NumPy reference of :func:`app.sim.kernels.motion_filter_update` on the same records, returning
    (x⁺, v⁺, a) as new arrays."""
    x, v, _ = state
    x_ref, v_ref, use_v, speed_scale = ref
    lower, upper, speed, accel, brake, tau = limits
    e = np.asarray(x_ref, dtype=float) - x
    v_des = approach_speed(e, braking_speed(np.abs(e), accel, dt), max(tau, dt))
    if use_v:
        v_des = v_des + np.asarray(v_ref, dtype=float)
    vmax = speed * speed_scale
    hi = np.minimum.reduce([v + accel * dt, vmax, braking_speed(upper - x, brake, dt)])
    lo = np.maximum.reduce([v - accel * dt, -vmax, -braking_speed(x - lower, brake, dt)])
    hi = np.maximum(hi, lo)  # rounding only
    v_new = np.clip(np.where(np.isfinite(v_des), v_des, 0.0), lo, hi)
    return np.clip(x + v_new * dt, lower, upper), v_new, (v_new - v) / dt


# ----------------------------------------------------------------------------- sources
@dataclass(frozen=True)
class Generator:
    """A sine per DOF: η_k(t) = A_k sin(2π f_k t + φ_k); amplitudes in m / rad, f in Hz, phase rad."""

    amplitude: NDArray[np.float64]
    frequency: NDArray[np.float64]
    phase: NDArray[np.float64]

    @staticmethod
    def make(
        amplitude: ArrayLike,
        frequency: ArrayLike,
        phase: ArrayLike,
        platform: StewartPlatform,
        box: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> Generator:
        """A checked generator: six finite amplitudes within the smaller side of ``box`` (the
        platform's command box (min, max) [m, rad]; default its Table 8 box, as the lab HMI's
        amplitude fields range over etaRefMin…etaRefMax), frequencies 0.01–1 Hz."""
        A, f, ph = (np.asarray(v, dtype=float).reshape(-1) for v in (amplitude, frequency, phase))
        for name, v in (("amplitude", A), ("frequency", f), ("phase", ph)):
            if v.shape != (6,) or not np.all(np.isfinite(v)):
                raise PlatformError(f"generator {name} needs six finite numbers, got {v.tolist()}")
        lo, hi = GENERATOR_FREQ_RANGE
        box_lo, box_hi = (platform.pose_min, platform.pose_max) if box is None else box
        what = "limit" if box is None else "operational box"
        for k, dof in enumerate(("surge", "sway", "heave", "roll", "pitch", "yaw")):
            if A[k] < 0:
                raise PlatformError(f"generator {dof} amplitude must not be negative")
            if A[k] > 0 and not lo <= f[k] <= hi:
                raise PlatformError(f"generator {dof} frequency {f[k]:g} Hz is outside {lo:g}–{hi:g} Hz")
            reach = min(-box_lo[k], box_hi[k])
            if A[k] > reach + 1e-12:
                unit, s = ("°", 180 / math.pi) if k >= 3 else ("m", 1.0)
                raise PlatformError(
                    f"generator {dof} amplitude {A[k] * s:.3g} {unit} exceeds "
                    f"the {platform.name} {what} {reach * s:.3g} {unit}"
                )
        return Generator(A, f, ph)

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        w = 2 * np.pi * self.frequency
        arg = w * t + self.phase
        return self.amplitude * np.sin(arg), self.amplitude * w * np.cos(arg)


@dataclass(frozen=True, eq=False)
class TimeSeries:
    """6-DOF playback: samples t [s] (strictly increasing, from 0) and η (n, 6) [m, rad]."""

    t: NDArray[np.float64]
    eta: NDArray[np.float64]

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        if t >= self.t[-1]:
            return self.eta[-1].copy(), np.zeros(6)
        i = int(np.searchsorted(self.t, t, side="right")) - 1
        i = max(i, 0)
        h = self.t[i + 1] - self.t[i]
        s = (t - self.t[i]) / h
        eta = self.eta[i] + s * (self.eta[i + 1] - self.eta[i])
        return eta, (self.eta[i + 1] - self.eta[i]) / h


def parse_timeseries_csv(text: str, where: str = "<csv>") -> TimeSeries:
    """Read a 6-DOF motion CSV: header ``t,x,y,z,phi,theta,psi`` (s, m, deg), one sample a row.

    Raises
    ------
    PlatformError
        ``where:line: what is wrong`` for a missing column, a non-number, NaN/inf, time that does
        not increase, fewer than two rows.
    """
    rows = [(n, cells(line)) for n, line in zip(*content_lines(text), strict=True)]
    if not rows:
        raise PlatformError(f"{where}: empty file; expected a header t,x,y,z,phi,theta,psi")
    line, header = rows[0]
    names = [c.strip().lower() for c in header]
    aliases = {"φ": "phi", "θ": "theta", "ψ": "psi", "time": "t"}
    names = [aliases.get(n, n) for n in names]
    missing = [c for c in TIMESERIES_COLUMNS if c not in names]
    if missing:
        raise PlatformError(
            f"{where}:{line}: missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
            f"(header must name t,x,y,z,phi,theta,psi; got {','.join(names)})"
        )
    idx = [names.index(c) for c in TIMESERIES_COLUMNS]
    data = []
    for line, r in rows[1:]:
        vals = []
        for col, k in zip(TIMESERIES_COLUMNS, idx, strict=True):
            if k >= len(r) or not r[k].strip():
                raise PlatformError(f"{where}:{line}: column {col} is empty")
            try:
                v = finite_number(r[k])
            except ValueError as err:
                raise PlatformError(f"{where}:{line}: column {col}: {r[k].strip()!r} is {err}") from None
            vals.append(v)
        if data and vals[0] <= data[-1][0]:
            raise PlatformError(
                f"{where}:{line}: time {vals[0]:g} s does not increase (previous row {data[-1][0]:g} s)"
            )
        data.append(vals)
    if len(data) < 2:
        raise PlatformError(f"{where}: needs at least two samples, got {len(data)}")
    a = np.array(data)
    eta = a[:, 1:].copy()
    eta[:, 3:] = np.radians(eta[:, 3:])
    return TimeSeries(a[:, 0] - a[0, 0], eta)


def timeseries_to_csv(t: ArrayLike, eta: ArrayLike) -> str:
    """The CSV :func:`parse_timeseries_csv` reads (angles written in degrees)."""
    t, eta = np.asarray(t, dtype=float), np.asarray(eta, dtype=float)
    out = io.StringIO()
    out.write(",".join(TIMESERIES_COLUMNS) + "\n")
    for ti, e in zip(t, eta, strict=True):
        out.write(",".join(f"{v:.6g}" for v in (ti, *e[:3], *np.degrees(e[3:]))) + "\n")
    return out.getvalue()


@dataclass
class WaveSimulation:
    """Vessel-in-waves source: η(t) of a vessel (RAO) in a random sea, scaled per DOF.

    The vessel's η (NED, z-down, zyx Euler angles) is played as the platform's η (z-down,
    eq. 33 angles): at these amplitudes the two angle conventions differ by second-order terms
    only, and the motion filter makes any pose admissible anyway.
    """

    rao: object
    spectrum: str
    hs: float
    tp: float
    heading_deg: float
    seed: int
    scale: NDArray[np.float64]
    motion: VesselMotion = field(init=False)
    significant: NDArray[np.float64] = field(init=False)

    def __post_init__(self) -> None:
        rng = np.random.default_rng(self.seed)
        heading = math.radians(self.heading_deg)
        sea = wave_components(self.spectrum, self.hs, self.tp, rng, heading=heading)
        self.motion = VesselMotion(self.rao, sea)
        w = np.linspace(0.2, 3.0, 400)
        self.significant = significant_response(self.rao, sea_spectrum(self.spectrum, w, self.hs, self.tp), w, heading)

    @staticmethod
    def auto_scale(
        significant: ArrayLike,
        platform: StewartPlatform,
        fill: float = 0.8,
        box: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> NDArray[np.float64]:
        """Per-DOF scale ≤ 1 fitting the most probable largest response of ~1000 cycles
        (≈ 0.93 H_s, Rayleigh) to ``fill`` of the smaller side of each limit of ``box`` (the
        command box (min, max); default the platform's Table 8 box)."""
        lo, hi = (platform.pose_min, platform.pose_max) if box is None else box
        reach = np.minimum(-np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
        peak = 0.93 * np.asarray(significant, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(peak > 1e-9, fill * reach / peak, 1.0)
        return np.minimum(s, 1.0)

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return self.motion.at(t, self.scale)


class Remote:
    """The pose last commanded by a client (``remote`` source); clipped to the command box
    ``box`` = (min, max) (default the platform's Table 8 box)."""

    def __init__(self, platform: StewartPlatform, box: tuple[ArrayLike, ArrayLike] | None = None) -> None:
        self.platform = platform
        self.box = (platform.pose_min, platform.pose_max) if box is None else box
        self.eta = np.zeros(6)

    def set(self, eta: ArrayLike) -> None:
        e = np.asarray(eta, dtype=float).reshape(-1)
        if e.shape != (6,) or not np.all(np.isfinite(e)):
            raise PlatformError(f"remote pose needs six finite numbers, got {np.asarray(eta).tolist()}")
        self.eta = np.clip(e, *self.box)

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return self.eta.copy(), np.zeros(6)


# ----------------------------------------------------------------------------- platform
def smoothstep(x: float) -> float:
    """0 → 1 with zero slope at both ends (3x² − 2x³)."""
    x = min(1.0, max(0.0, x))
    return x * x * (3.0 - 2.0 * x)


class Platform:
    """One Stewart platform with the lab HMI's modes, a motion source and the motion filter.

    Parameters
    ----------
    model : StewartPlatform
    ramp_time : float   ENGAGE / DISENGAGE fade time [s]; default 5
    start : str         initial mode, ``settled`` (default) or ``neutral``
    command_box : (min, max) of array_like (6,), optional
        The operational box every command is clipped to [m, rad] (the lab layout's
        ``<command_box>``); default the Table 8 box.  It must hold the neutral pose and lie inside
        Table 8.

    Attributes
    ----------
    settled_pose : ndarray (6,)   all legs at ``leg_min`` (forward kinematics)
    command_min, command_max : ndarray (6,)   the command box
    envelope_min, envelope_max : ndarray (6,)   Table 8 widened to hold the settled pose
    """

    def __init__(
        self,
        model: StewartPlatform,
        ramp_time: float = 5.0,
        start: str = "settled",
        command_box: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> None:
        self.model = model
        self.ramp_time = float(ramp_time)
        lo, hi = (model.pose_min, model.pose_max) if command_box is None else command_box
        self.command_min = np.array(lo, dtype=float).reshape(6)
        self.command_max = np.array(hi, dtype=float).reshape(6)
        if not (np.all(self.command_min < 0) and np.all(self.command_max > 0)):
            raise PlatformError(f"{model.name}: the command box must hold the neutral pose (every min < 0 < max)")
        if np.any(self.command_min < model.pose_min - 1e-12) or np.any(self.command_max > model.pose_max + 1e-12):
            raise PlatformError(f"{model.name}: the command box leaves the Table 8 pose limits")
        self.settled_pose = self._settled(model)
        self.envelope_min = np.minimum(model.pose_min, self.settled_pose)
        self.envelope_max = np.maximum(model.pose_max, self.settled_pose)
        self.mode = start
        self.transition = ""  # "raising", "settling", "engaging", "disengaging" or ""
        if start == "settled":
            self.filter = MotionFilter(self.envelope_min, self.envelope_max, model.speed_max, model.accel_max)
            self.filter.reset(self.settled_pose)
        else:
            self.filter = MotionFilter(self.command_min, self.command_max, model.speed_max, model.accel_max)
            self.filter.reset(np.zeros(6))
        self.source_name = "generator"
        self.source = Generator(np.zeros(6), np.full(6, 0.1), np.zeros(6))
        self.remote = Remote(model, (self.command_min, self.command_max))
        self.t_source = 0.0
        self.gain = 0.0
        self.frozen = False
        self.leg_clamped = False
        self.hold_pose: NDArray[np.float64] | None = None
        margin = 0.02 * (model.leg_max - model.leg_min)
        #: the leg lengths a target may ask for: the stroke less a 2 % margin at each end [m]
        self.leg_band = (float(model.leg_min + margin), float(model.leg_max - margin))

    @staticmethod
    def _settled(model: StewartPlatform) -> NDArray[np.float64]:
        """The settled pose: forward kinematics (eqs. 31–38 solved by Newton) of six legs at ``leg_min``,
        started below the lowest Table 8 heave (z-down)."""
        start = np.zeros(6)
        start[2] = model.pose_max[2]
        fk = model.fk(np.full(6, model.leg_min), start)
        if not fk.success:
            raise PlatformError(
                f"{model.name}: no pose has all legs at their minimum length (residual {fk.residual:.3g} m)"
            )
        return fk.eta

    @property
    def command_box(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(min, max) of the command box [m, rad]."""
        return self.command_min.copy(), self.command_max.copy()

    def place_at_neutral(self) -> None:
        """Put the platform at rest at neutral in NEUTRAL (a scenario's start; the operator raises instead)."""
        self.filter.reset(np.zeros(6))
        self.mode, self.transition, self.gain = "neutral", "", 0.0
        self._limit_to("command")

    def _limit_to(self, box: str) -> None:
        """The filter's position box: ``envelope`` (raising, settling, settled) or ``command``."""
        if box == "envelope":
            self.filter.set_limits(self.envelope_min, self.envelope_max)
        else:
            self.filter.set_limits(self.command_min, self.command_max)

    @property
    def use_kernels(self) -> bool:
        """Compiled filter, leg clamp and wave source (False: the NumPy reference of each)."""
        return self.filter.use_kernels

    @use_kernels.setter
    def use_kernels(self, on: bool) -> None:
        self.filter.use_kernels = bool(on)
        self._share_kernels(self.source)

    def _share_kernels(self, source: object) -> None:
        """A wave source computes its vessel motion the way the platform runs (compiled or reference)."""
        if isinstance(source, WaveSimulation):
            source.motion.use_kernels = self.use_kernels

    # ------------------------------------------------------------------ commands
    @property
    def status(self) -> str:
        return self.transition or self.mode

    def command(self, action: str) -> None:
        """``neutral`` (raise from settled), ``settle``, ``engage``, ``disengage``."""
        if action not in ACTIONS:
            raise PlatformError(f"platform action must be one of {', '.join(ACTIONS)}, got {action!r}")
        if self.frozen:
            raise PlatformError(f"{self.model.name} is stopped (E-STOP); reset first")
        busy = self.transition
        if action == "neutral":
            if self.mode not in ("settled", "holding") or busy:
                raise PlatformError(
                    f"{self.model.name}: NEUTRAL is reached from SETTLED or HOLDING (now {self.status.upper()})"
                )
            self.mode, self.transition = "settled" if self.mode == "settled" else "neutral", "raising"
        elif action == "settle":
            if self.mode not in ("neutral", "holding") or busy:
                raise PlatformError(
                    f"{self.model.name}: SETTLE is done from NEUTRAL or HOLDING (now {self.status.upper()})"
                )
            self.mode, self.transition = "neutral", "settling"
            self._limit_to("envelope")  # widening: the state is inside either way
        elif action == "engage":
            if self.mode != "neutral" or busy:
                raise PlatformError(f"{self.model.name}: ENGAGE needs NEUTRAL (now {self.status.upper()})")
            self.t_source, self.gain = 0.0, 0.0
            self.mode, self.transition = "engaged", "engaging"
        else:
            if self.mode != "engaged" or busy == "disengaging":
                raise PlatformError(f"{self.model.name}: DISENGAGE needs ENGAGED (now {self.status.upper()})")
            self.transition = "disengaging"

    def set_source(self, name: str, source=None) -> None:
        """Select a motion source (not while engaged: disengage first, as on the lab HMI)."""
        if name not in SOURCES:
            raise PlatformError(f"motion source must be one of {', '.join(SOURCES)}, got {name!r}")
        if self.mode == "engaged":
            raise PlatformError(f"{self.model.name} is ENGAGED; disengage before changing the motion source")
        if name == "remote":
            source = self.remote
        elif source is None:
            raise PlatformError(f"source {name} needs its parameters")
        self._share_kernels(source)
        self.source_name, self.source = name, source

    def estop(self) -> None:
        """Stop at the acceleration limit and hold (pose, speed and acceleration stay in their limits)."""
        self.frozen = True

    def reset(self) -> None:
        """After an E-STOP: the platform holds where it stands until the operator commands it.

        A platform that was SETTLED (at rest on its end stops) stays SETTLED; any other comes to
        rest (still braking at its acceleration limits if the reset is early) and is HOLDING there;
        from HOLDING the operator chooses NEUTRAL or SETTLE.
        """
        if self.frozen:
            self.frozen = False
            self.gain = 0.0
            if self.mode == "settled" and not self.transition:
                return
            self.mode, self.transition = "holding", ""
            self.hold_pose = None  # taken when the platform is at rest

    # ------------------------------------------------------------------ step
    def _clamp_to_legs(self, eta: NDArray[np.float64]) -> NDArray[np.float64]:
        """Scale a target toward neutral until every leg is inside its stroke (2 % margin)."""
        m = self.model
        lo, hi = self.leg_band
        if self.use_kernels:
            out, self.leg_clamped = sim_kernels.clamp_to_legs(m.a_n, m.b_b, np.ascontiguousarray(eta, float), lo, hi)
            return out

        def inside(e):
            L = m.leg_lengths(e)
            return bool(np.all((lo <= L) & (hi >= L)))

        if inside(eta):
            self.leg_clamped = False
            return eta
        a, b = 0.0, 1.0
        for _ in range(20):
            c = 0.5 * (a + b)
            a, b = (c, b) if inside(c * eta) else (a, c)
        self.leg_clamped = True
        return a * eta

    def step(self, dt: float) -> NDArray[np.float64]:
        """Advance by ``dt``; returns η (6,)."""
        f = self.filter
        speed_scale = 1.0
        target, v_ref = f.x.copy(), None
        if self.frozen:
            return self._stop_step(dt)
        if self.mode == "holding":
            if self.hold_pose is None:
                x = self._stop_step(dt)
                if np.all(f.v == 0.0):
                    self.hold_pose = x
                return x
            return f.step(self.hold_pose, None, dt, TRANSFER_SPEED_FRACTION).copy()
        if self.mode == "engaged":
            self.t_source += dt
            if self.transition == "engaging":
                self.gain = smoothstep(self.t_source / self.ramp_time) if self.ramp_time > 0 else 1.0
                if self.gain >= 1.0:
                    self.transition = ""
            elif self.transition == "disengaging":
                self.gain = max(0.0, self.gain - dt / self.ramp_time) if self.ramp_time > 0 else 0.0
            eta_s, v_s = self.source(self.t_source)
            g = smoothstep(self.gain) if self.transition == "disengaging" else self.gain
            # every source through the command box (the filter's box while engaged), as the lab
            # PLC's etaRef = LIMIT(etaRefMin, u, etaRefMax); a clipped DOF loses its feed-forward
            if self.use_kernels and not (self.transition == "disengaging" and self.gain <= 0.0):
                m = self.model  # the scaled source clamped to the legs and filtered, in one call
                source = (float(g), np.ascontiguousarray(eta_s, dtype=float), np.ascontiguousarray(v_s, dtype=float))
                self.leg_clamped = sim_kernels.follow_clamped(
                    (m.a_n, m.b_b, *self.leg_band), source, (f.x, f.v, f.a),
                    (f.lower, f.upper, f.speed, f.accel, float(f.tau)), float(dt),
                )  # fmt: skip
                return f.x.copy()
            u, u_dot = g * np.asarray(eta_s, dtype=float), g * np.asarray(v_s, dtype=float)
            eta_c = np.minimum(np.maximum(u, f.lower), f.upper)
            target, v_ref = self._clamp_to_legs(eta_c), np.where(eta_c == u, u_dot, 0.0)
            if self.transition == "disengaging" and self.gain <= 0.0:
                target, v_ref = np.zeros(6), None
                if np.all(np.abs(f.x) < 1e-6) and np.all(np.abs(f.v) < 1e-6):
                    self.mode, self.transition = "neutral", ""
        elif self.transition == "raising" or self.mode == "neutral":
            target, v_ref = np.zeros(6), None
            speed_scale = TRANSFER_SPEED_FRACTION
            if self.transition == "raising" and self._at_rest(0.0):
                self.mode, self.transition = "neutral", ""
                self._limit_to("command")  # at rest at neutral: inside the command box
        if self.transition == "settling" or (self.mode == "settled" and not self.transition):
            target, v_ref = self.settled_pose, None
            speed_scale = TRANSFER_SPEED_FRACTION
            if self.transition == "settling" and self._at_rest(self.settled_pose):
                self.mode, self.transition = "settled", ""
        return f.step(target, v_ref, dt, speed_scale).copy()

    def _at_rest(self, pose: ArrayLike) -> bool:
        """At ``pose`` and at rest: ``np.allclose(x, pose, atol=1e-6) and np.allclose(v, 0, atol=1e-6)``
        written out (|a − b| ≤ 1e-6 + 1e-5 |b|; a twentieth of allclose's cost)."""
        f = self.filter
        b = np.asarray(pose, dtype=float)
        return bool(np.all(np.abs(f.x - b) <= 1e-6 + 1e-5 * np.abs(b)) and np.all(np.abs(f.v) <= 1e-6))

    def _stop_step(self, dt: float) -> NDArray[np.float64]:
        """Brake every DOF at its acceleration limit until at rest (still through the limits)."""
        f = self.filter
        dv = np.clip(-f.v, -f.accel * dt, f.accel * dt)
        v_new = f.v + dv
        # braking toward a pose limit stays admissible: v_new is between v and 0
        f.a = (v_new - f.v) / dt
        f.v = v_new
        f.x = np.clip(f.x + v_new * dt, f.lower, f.upper)
        return f.x.copy()

    @property
    def eta(self) -> NDArray[np.float64]:
        return self.filter.x.copy()

    @property
    def eta_dot(self) -> NDArray[np.float64]:
        return self.filter.v.copy()

    @property
    def eta_ddot(self) -> NDArray[np.float64]:
        return self.filter.a.copy()
