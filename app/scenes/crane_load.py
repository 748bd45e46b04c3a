"""A suspended load on the offshore crane (issue 30, items 3 and 5): a wire from the Delta head's TCP over a winch,
the load on it (:data:`app.sim.load.LOAD`: a point mass on an elastic wire, which can go slack, with a deck to land
on), and the winch's active heave compensation beside the head.

The blocks are reused (not copied): the drum :data:`app.sim.motionlab.WINCH_DRUM` (the lab's: the wire length
following its reference within the winch's length, speed and acceleration limits), the load
:data:`app.sim.load.LOAD` (taut and clear of a deck, the spherical pendulum of the Motion-Lab paper's eqs. 29–30 in
Cartesian form) and the controller :data:`app.control.tac.CRANE_AHC`.  Frames: {n} is NED (z down).  The load
hangs from the TCP and does not act back on the crane or the head (the crane-head paper's model: the load's
inertia against the crane's is left out; the paper asks for the load to be added, not for the crane to feel it).

Assumed values (stated, not from a source): the winch pays out at up to 1.5 m/s with 2 m/s², the wire 3–40 m,
10 m at the start.  The acceleration matters: a heave of 1 m at 9 s asks 0.49 m/s² of the drum, and at 0.5 m/s²
the drum fell behind by 1.3 m (tests/test_crane_load.py measures 7 mm at 2 m/s²).  The load's values (5 t, the
wire's EA, the landing) are :class:`app.sim.load.LoadSpec`'s, with their sources.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from app.control.antisway import SWING_CONTROL, AntiSwing, AntiSwingDesign, SwingEkf
from app.control.tac import CRANE_AHC
from app.models.pendulum import G
from app.scenes.tac_kernels import ease_in
from app.sim.load import LOAD, LoadSpec, hanging, no_deck
from app.sim.motionlab import WINCH_DRUM

__all__ = [
    "CRANE_ANTISWAY", "CraneLoad", "CraneSwingControl", "LandingWatch", "LoadChartWatch", "Platform", "WinchSpec",
]  # fmt: skip

SLACK_FACTOR = 0.1  # a wire pulling under 10 % of the load's weight while no deck carries the load is slack
SNAP_FACTOR = 1.5  # tension over 1.5 × static is a snap load (issue 30, item 5)
SIDEWAYS_SPEED = 0.1  # m/s: contact while the load slides faster than this over the deck (assumed)
SWING_LIMIT_DEG = 5.0  # the landing panel's swing limit (assumed: a load swinging more is not landed)
LIFT_OFF = 0.5  # m: a landed load this far above the deck again has been lifted: the next contact is a new landing


@dataclass(frozen=True)
class WinchSpec:
    """The crane winch and its load (assumed values, module text)."""

    min_length: float = 3.0
    max_length: float = 40.0
    start_length: float = 10.0
    speed: float = 1.5  # m/s
    accel: float = 2.0  # m/s²
    tau: float = 0.05  # s: the drum's servo
    ahc_ease: float = 5.0  # s: heave compensation switched on under a hanging load eases in over this (H108; assumed)


@dataclass
class CraneLoad:
    """The wire, the winch and the hanging load under the crane head's TCP, stepped with the scene's TCP samples.

    :meth:`step` takes the TCP's position in {n} at the end of each simulation step; the TCP's velocity and
    acceleration come from its samples (backward differences).  ``ahc`` switches the winch's heave compensation;
    ``speed_command`` is the operator's winch axis (positive pays out, lowering the hook); ``deck`` is the deck
    below the load (:func:`app.sim.load.no_deck` for none; the scene sets it each step).  After each step:
    ``tension``, ``contact_force`` and ``gap`` (the load's height above the deck, along its normal)."""

    spec: WinchSpec = field(default_factory=WinchSpec)
    load_spec: LoadSpec = field(default_factory=LoadSpec)
    ahc: bool = True
    stopped: bool = False  # an E-STOP: the heave compensation stops at once (no fade) and the drum brakes
    speed_command: float = 0.0
    use_kernels: bool | None = None

    def __post_init__(self) -> None:
        s = self.spec
        self.drum = (np.array([s.start_length]), np.zeros(1), np.zeros(1), np.zeros(4, dtype=bool))
        self._drum_p = tuple(np.array([v]) for v in (s.min_length, s.max_length, s.speed, s.accel)) + (s.tau,)
        self._load_p = self.load_spec.record(G)
        self.state: tuple | None = None  # (r, v) of the load in {n}, from the first step on
        self.deck = no_deck()
        self.law = (0.0, False, 0.0)  # the hook's height target in {n}, whether set, the length riding the TCP
        #: the heave compensation's fade (H108): ((time since it was switched, the gain it goes to, the gain it started
        #: from) or None, the gain of the last step: 1 tracking, 0 not)
        self._ahc: tuple[tuple | None, float] = (None, 1.0 if self.ahc else 0.0)
        self._tcp: list[NDArray[np.float64]] = []  # the last three TCP positions
        self.tcp_v = np.zeros(3)
        self.tcp_a = np.zeros(3)
        self.tension = self.static_tension()
        self.contact_force = 0.0
        self.gap = float("inf")

    @property
    def length(self) -> float:
        """The wire paid out (unstretched) [m]."""
        return float(self.drum[0][0])

    @property
    def length_rate(self) -> float:
        return float(self.drum[1][0])

    def hook(self, tcp_n: NDArray[np.float64]) -> NDArray[np.float64]:
        """The load in {n} (before the first step: hanging still below ``tcp_n``)."""
        if self.state is None:
            return hanging(np.asarray(tcp_n, dtype=float), self.length, self.load_spec, G)[0]
        return self.state[0].copy()

    def velocity(self) -> NDArray[np.float64]:
        return np.zeros(3) if self.state is None else self.state[1].copy()

    def wire(self) -> NDArray[np.float64]:
        """The wire's unit vector from the TCP to the load in {n}."""
        if self.state is None or not self._tcp:
            return np.array([0.0, 0.0, 1.0])
        e = self.state[0] - self._tcp[-1]
        return e / float(np.linalg.norm(e))

    def swing_angles(self) -> tuple[float, float]:
        """The wire's angles (α, β) of the Motion-Lab paper's eq. (23), û = (−sα, cα sβ, cα cβ), in {n}."""
        u = self.wire()
        return float(-np.arcsin(np.clip(u[0], -1.0, 1.0))), float(np.arctan2(u[1], u[2]))

    def swing_angle(self) -> float:
        """The wire's angle from the vertical [rad]."""
        return float(np.arccos(np.clip(self.wire()[2], -1.0, 1.0)))

    def static_tension(self) -> float:
        return self.load_spec.mass * G

    def _ahc_gain(self, dt: float, first: bool) -> tuple[bool, tuple[float, float]]:
        """Whether the heave compensation tracks this step, and its gain (g, ġ) (H108).  Switched on while the load
        hangs (not at the first step) it eases in, g from where it was to 1 over ``spec.ahc_ease``
        (:func:`app.scenes.tac_kernels.ease_in`); switched off it eases out the same way, from holding the hook in
        the world to riding the TCP, and then stops tracking.  ``stopped`` (an E-STOP) ends it at once."""
        T, (fade, g_last) = self.spec.ahc_ease, self._ahc
        want = 1.0 if self.ahc and not self.stopped else 0.0
        if self.stopped or T <= 0 or first:  # at once: a stop, no fade, or the first step (nothing swings yet)
            self._ahc = (None, want)
            return want == 1.0, (1.0, 0.0)
        if want != g_last and (fade is None or fade[1] != want):
            fade = (0.0, want, g_last)
            if want == 0.0 and self.law[1]:
                self.law = (self.law[0], True, self.length)  # from here the hook rides the TCP
        if fade is None:
            return g_last == 1.0, (1.0, 0.0)
        t, target, g0 = fade
        t += dt
        if t >= T - 1e-9:
            self._ahc = (None, target)
            return target == 1.0, (1.0, 0.0)
        e, e_dot = ease_in(t / T)
        g = g0 + (target - g0) * float(e)
        self._ahc = ((t, target, g0), g)
        return True, (g, (target - g0) * float(e_dot) / T)

    def step(self, tcp_n: NDArray[np.float64], dt: float) -> None:
        """One step of ``dt`` with the TCP at ``tcp_n`` (in {n}) at its end: the winch law, the drum, the load."""
        p = np.asarray(tcp_n, dtype=float)
        prev = self._tcp[-1] if self._tcp else p
        self._tcp = [*self._tcp[-2:], p.copy()]
        if len(self._tcp) >= 2:
            self.tcp_v = (self._tcp[-1] - self._tcp[-2]) / dt
        if len(self._tcp) == 3:
            self.tcp_a = (self._tcp[-1] - 2.0 * self._tcp[-2] + self._tcp[-3]) / (dt * dt)
        first = self.state is None
        if first:
            self.state = hanging(p, self.length, self.load_spec, G)
        track, ease = self._ahc_gain(dt, first)
        u = (track, self.speed_command, self.length, (float(p[2]), float(self.tcp_v[2])), ease)
        self.law, (L_ref, Ld_ref) = CRANE_AHC.step(self.law, u, (self.spec.speed,), dt, use_kernels=False)
        L0 = self.length
        self.drum, _ = WINCH_DRUM.step(
            self.drum, (np.array([L_ref]), np.array([Ld_ref])), self._drum_p, dt, self.use_kernels
        )
        u_load = (prev, p, L0, self.length, self.deck)
        self.state, (T, Fn, gap) = LOAD.step(self.state, u_load, self._load_p, dt, self.use_kernels)
        self.tension, self.contact_force, self.gap = float(T), float(Fn), float(gap)


@dataclass(frozen=True)
class Platform:
    """A fixed platform's deck: a horizontal rectangle in {n} (NED) centred at ``centre`` (its surface), ±``half``
    along x and y.  :meth:`deck` is the load's deck record: present only while the load is over it."""

    centre: tuple[float, float, float]
    half: tuple[float, float] = (4.0, 4.0)

    def over(self, r: NDArray[np.float64]) -> bool:
        c = self.centre
        return abs(float(r[0]) - c[0]) <= self.half[0] and abs(float(r[1]) - c[1]) <= self.half[1]

    def deck(self, r: NDArray[np.float64]) -> tuple:
        return (self.over(r), np.array(self.centre, dtype=float), np.array([0.0, 0.0, -1.0]), np.zeros(3))

    def corners(self) -> list[list[float]]:
        (x, y, z), (hx, hy) = self.centre, self.half
        return [[x - hx, y - hy, z], [x + hx, y - hy, z], [x + hx, y + hy, z], [x - hx, y + hy, z]]


@dataclass
class LandingWatch:
    """What a landing does, step by step, from the load after its step and the deck's velocity and up normal: the
    speed towards the deck, the first contact (and the speed just before it), every contact after it (a re-hit),
    and this step's slack wire, snap load and sideways contact (issue 30, item 5).

    ``relift``: a landed load lifted :data:`LIFT_OFF` clear of the deck starts a new landing (the engine, where the
    operator lifts again); off, every contact of the run counts (``sim transfer``: one landing a run)."""

    relift: bool = False
    touched: bool = False
    touch_speed: float | None = None
    contacts: int = 0
    rel_speed: float = 0.0
    in_contact: bool = False
    rehit: bool = False
    slack: bool = False
    snap: bool = False
    sideways: bool = False

    def report(self) -> dict:
        """The landing's fields of a snapshot's load state (``app.net.snapshots.CraneLoadState``), with the limits
        they are shown against."""
        return {
            "rel_speed": round(self.rel_speed, 4),
            "contact": self.in_contact,
            "landed": self.touched,
            "rehits": max(0, self.contacts - 1),
            "swing_limit_deg": SWING_LIMIT_DEG,
            "slack_factor": SLACK_FACTOR,
            "snap_factor": SNAP_FACTOR,
        }

    def step(self, load: CraneLoad, deck_v: NDArray[np.float64], n_up: NDArray[np.float64]) -> None:
        rel = load.state[1] - deck_v
        rel_n = float(n_up @ rel)
        before = self.rel_speed
        self.rel_speed = -rel_n  # towards the deck, positive
        contact = load.contact_force > 0.0
        onset = contact and not self.in_contact
        self.in_contact = contact
        if self.relift and self.touched and load.gap > LIFT_OFF:
            self.touched, self.touch_speed, self.contacts = False, None, 0
        if onset:
            self.contacts += 1
            if not self.touched:
                self.touched, self.touch_speed = True, before
        self.rehit = onset and self.contacts > 1
        ratio = load.tension / load.static_tension()
        self.slack = ratio < SLACK_FACTOR and not contact
        self.snap = ratio > SNAP_FACTOR
        if contact:
            v_t = rel - n_up * rel_n
            self.sideways = math.sqrt(float(v_t @ v_t)) > SIDEWAYS_SPEED
        else:
            self.sideways = False


@dataclass
class LoadChartWatch:
    """This load in this sea as a share of its SWL (issue 31, item 4): SWL = C(r) / ψ, with C(r) the crane's rated
    capacity at its radius (the robot file's, :class:`app.models.spec.RatedCapacity`) and ψ the dynamic factor seen
    live: the wire's peak tension over the load's weight in the last ``window`` seconds (at least 1: a landed load
    weighs its weight when lifted).  ``percent`` = 100 · m ψ / C(r), what a crane's load-moment indicator shows
    with the sea's dynamic load in it.  The peak is a running maximum over the window (a monotonic queue: O(1) a
    tick)."""

    rating: object | None  # RatedCapacity, or None: the crane has no load chart
    window: float = 120.0  # s: about thirteen 9 s waves
    _peaks: deque = field(default_factory=deque)  # (time, factor), factors falling
    _start: float | None = None

    def step(self, t: float, factor: float) -> None:
        """The tick at time ``t`` with its peak tension factor ``factor``."""
        q = self._peaks
        while q and q[-1][1] <= factor:
            q.pop()
        q.append((t, factor))
        while q[0][0] < t - self.window:
            q.popleft()
        if self._start is None:
            self._start = t

    def beyond(self, radius: float) -> bool:
        """The crane has a chart and ``radius`` is past its last rating: not rated there (an alarm, not a blank)."""
        return self.rating is not None and self.rating.at(radius) is None

    def report(self, mass: float, radius: float, t: float) -> dict:
        """The snapshot's fields (``app.net.snapshots.CraneLoadState``)."""
        cap = None if self.rating is None else self.rating.at(radius)
        psi = max(1.0, self._peaks[0][1]) if self._peaks else None
        seen = 0.0 if self._start is None else min(self.window, t - self._start)
        pct = None if cap is None or psi is None else 100.0 * mass * psi / cap
        return {
            "payload_t": round(mass / 1000.0, 3), "radius": round(radius, 3),
            "capacity_t": None if cap is None else round(cap / 1000.0, 3),
            "psi": None if psi is None else round(psi, 4), "psi_window": round(seen, 1),
            "swl_percent": None if pct is None else round(pct, 2), "rated": self.rating is not None,
        }  # fmt: skip


#: the anti-swing law's design for the crane's load at L = 10 m: five times the lab's weight on the swing, a tenth on
#: the offset.  Chosen from a sweep of six weight sets on seeds 1–2 of ``sim transfer`` (residual swing against
#: compensated only: the lab's 0.34–0.41, this 0.17, others 0.2–1.24): the result is sensitive to the weights,
#: because the law assumes the TCP takes its acceleration at once while the head follows its target with its
#: servo's lag.
CRANE_ANTISWAY = AntiSwingDesign(L=10.0, Q=(2000.0, 200.0, 2.0, 1.0), a_max=1.0, offset_max=1.5)

#: the anti-swing's sensors (the lab's, app.scenarios.swing): the TCP's acceleration 0.05 m/s² per axis (the
#: crane's joints and the MRU), the wire's angles 0.5° (a wire-angle sensor); one standard deviation
NOISE = np.array([0.05, 0.05, 0.05, math.radians(0.5), math.radians(0.5)])


@dataclass
class CraneSwingControl:
    """The Motion-Lab's swing estimator and anti-swing law (:data:`app.control.antisway.SWING_CONTROL`), reused on
    the crane's load (issue 30, item 3): the TCP's measured acceleration and the wire's measured angles in, an
    offset of the TCP's target in {n} out (:meth:`step`, after each of the load's steps).

    The design: :data:`CRANE_ANTISWAY` with the load's air damping, T_s the scene's step, the gains scheduled over
    the winch's wire lengths; the offset within the head's reach (1.5 m).  ``active`` False runs the estimator only
    (the offset returns to zero along the law).  An estimator that loses the load (a flailing load far outside its
    pendulum model) starts again from "no swing", counted in ``resets``."""

    load: CraneLoad
    dt: float
    rng: np.random.Generator
    noise: bool = True
    active: bool = True
    resets: int = 0

    def __post_init__(self) -> None:
        self.x, self.record = self._fresh()
        self._noise: list = []
        self.offset = np.zeros(3)

    def _fresh(self):
        ld = self.load
        design = replace(CRANE_ANTISWAY, c=ld.load_spec.air_damping, Ts=self.dt)
        law = AntiSwing(design=design, lengths=(ld.spec.min_length, ld.spec.max_length), active=True)
        ekf = SwingEkf(
            c=ld.load_spec.air_damping, g=G, sigma_accel=0.05, measurement="angles", sigma_angle=math.radians(0.5)
        )
        x = (ekf.x, ekf.P, np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2), float(ld.length))
        return x, (ekf.record(), law.record(), G, 0.2)

    def step(self, e: NDArray[np.float64], ell: float, in_play: bool, lead: tuple | None = None) -> NDArray[np.float64]:
        """One step with the wire ``e`` = load − TCP (of length ``ell``); ``in_play`` False (landed, slack) rests
        the law.  Returns the TCP target's offset in {n} (3,).

        ``lead``: (f, ẍ_ref) when the TCP leads a moving target by f so the load follows it (the load lead,
        :func:`app.models.pendulum.suspension_lead`), ẍ_ref the TCP's planned acceleration.  The swing about that
        planned motion obeys the same pendulum (L δ̈ = (ẍ_t − ẍ_ref) − g δ, linearised), so the estimator and law
        see the wire less the lead and the TCP's acceleration less the planned one: they damp the swing, not the
        lead."""
        ld = self.load
        if not self._noise:  # the sensors' noise, drawn a block at a time
            self._noise = list(self.rng.normal(0.0, 1.0, (1000, 5)) * NOISE) if self.noise else [np.zeros(5)] * 1000
        w = self._noise.pop()
        a_d = ld.tcp_a + w[:3]
        if lead is not None:
            e = e + lead[0]
            a_d = a_d - lead[1]
        z = np.array([-math.asin(min(1.0, max(-1.0, e[0] / ell))), math.atan2(e[1], e[2])]) + w[3:]
        u = (np.ascontiguousarray(a_d), z, float(ld.length), float(ld.length_rate), self.active and in_play)
        self.x, (p_d, _, _, _, _) = SWING_CONTROL.step(self.x, u, self.record, self.dt)
        if not (np.all(np.isfinite(self.x[0])) and np.all(np.isfinite(self.x[1]))):
            fresh = self._fresh()[0]
            law = tuple(v if np.all(np.isfinite(v)) else np.zeros(2) for v in self.x[4:7])
            self.x = (*fresh[:4], *law, fresh[7])
            p_d = np.array([*law[0], 0.0])
            self.resets += 1
        self.offset = np.asarray(p_d, dtype=float)
        return self.offset
