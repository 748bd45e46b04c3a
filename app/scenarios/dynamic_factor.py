"""The dynamic factor of a lift (issue 31, item 4): ψ = the wire's peak tension / the load's static weight, with the
supply vessel's crane holding its load hanging at a radius in a sea — ``bosun study loadchart``'s one cell.

The crane scene's blocks, as ``sim transfer`` wires them (:mod:`app.scenarios.transfer`), with the operator's hands
off the stick: the vessel, crane and Delta head (:class:`~app.scenarios.tac.TacSimulator`), the winch and the load
on its elastic wire (:class:`~app.scenes.crane_load.CraneLoad`, ``payload`` tonnes on ``wire`` metres), and in
``antisway`` the swing estimator and law (:class:`~app.scenes.crane_load.CraneSwingControl`).

* ``off``: the TCP rides the vessel (the head held), the winch holds the wire's length;
* ``compensated``: the crane and head hold the TCP still in the world (cooperative, TAC paper §8) and the winch's
  heave compensation holds the hook's height;
* ``antisway``: compensated, with the swing law moving the TCP's target.

The crane stands at ``radius`` from its slewing axis (:meth:`app.models.crane_head.CraneHead.at_radius`: at the
slew angle and TCP height of the paper's eq. (60) configuration).  A hanging load that starts still under a moving
TCP would be snatched (its wire's axial mode rings at √(EA/(L m)) ≈ 32 rad/s): the sea fades in from flat water over
:data:`FADE_IN` s (:class:`~app.scenarios.tac.SeaTransition`) and ψ is taken after :data:`LEAD_IN` s, over
``duration`` s.  Hs 0 is flat water (the calm check: ψ = 1).

ψ's definition is DNV-ST-0378's and EN 13852-1's (the dynamic coefficient: the largest hoist load over the static
one); the rules' own formulas for it are not used (docs/foresight.md says why).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, replace

import numpy as np

from app.errors import BosunError
from app.marine.vessel import VesselMotion
from app.marine.waves import HS_RANGE, SPECTRA, check_sea
from app.models.pendulum import G
from app.scenarios.tac import SeaTransition, TacScenario, TacSimulator
from app.scenes.crane_load import SLACK_FACTOR, SNAP_FACTOR, CraneLoad, CraneSwingControl, WinchSpec
from app.sim.load import LoadSpec

__all__ = ["FADE_IN", "LEAD_IN", "MODES", "DynamicFactorError", "DynamicFactorScenario", "simulate"]

MODES = ("off", "compensated", "antisway")
FADE_IN = 30.0  # s: the sea fades in from flat water over this (two to four peak periods)
LEAD_IN = 60.0  # s: ψ is measured from here (the fade, then a pendulum period's ten times over)
CHUNK = 2  # steps the crane and head advance with the TCP's target held (the crane-head engine's 50 Hz tick)
MAX_PAYLOAD = 1000.0  # t
MAX_DURATION = 10_800.0  # s: a stationary sea state (DNV-RP-C205 §3.3.1)


class DynamicFactorError(BosunError):
    """A bad dynamic-factor setting (names it)."""


@dataclass(frozen=True)
class DynamicFactorScenario:
    """One cell: the sea, the mode, the payload and the radius; angles in degrees at this edge."""

    hs: float = 3.0  # m; 0: flat water
    tp: float = 9.0
    heading: float = 90.0  # wave heading relative to the vessel [deg]
    spectrum: str = "jonswap"
    seed: int = 1
    rao: str | None = None  # the vessel (None: the default vessel)
    mode: str = "off"
    payload: float = 5.0  # t
    radius: float | None = None  # m from the slewing axis (None: the eq. (60) configuration's, 29.7 m)
    wire: float = 10.0  # m of wire paid out
    duration: float = 600.0  # s, after the lead-in
    dt: float = 0.01
    n_freq: int = 200

    def __post_init__(self) -> None:
        if self.hs != 0:
            try:
                check_sea(self.hs, self.tp)
            except BosunError as err:
                raise DynamicFactorError(str(err)) from None
        w = WinchSpec()
        checks = [
            (self.mode in MODES, f"mode must be one of {', '.join(MODES)}, got {self.mode!r}"),
            (self.spectrum in SPECTRA, f"spectrum must be one of {', '.join(SPECTRA)}, got {self.spectrum!r}"),
            (math.isfinite(self.hs) and self.hs >= 0, f"hs must be 0 (flat water) or a sea's, got {self.hs}"),
            (math.isfinite(self.heading), "heading must be a number"),
            (
                math.isfinite(self.payload) and 0 < self.payload <= MAX_PAYLOAD,
                f"payload must be in (0, {MAX_PAYLOAD:g}] t, got {self.payload:g}",
            ),
            (
                self.radius is None or (math.isfinite(self.radius) and self.radius > 0),
                f"radius must be a positive number of metres, got {self.radius}",
            ),
            (
                math.isfinite(self.wire) and w.min_length <= self.wire <= w.max_length,
                f"wire must be in [{w.min_length:g}, {w.max_length:g}] m (the winch's), got {self.wire:g}",
            ),
            (
                math.isfinite(self.duration) and 0 < self.duration <= MAX_DURATION,
                f"duration must be in (0, {MAX_DURATION:g}] s, got {self.duration:g}",
            ),
            (math.isfinite(self.dt) and 0 < self.dt <= 0.02, f"dt must be in (0, 0.02] s, got {self.dt}"),
        ]
        for ok, msg in checks:
            if not ok:
                raise DynamicFactorError(msg)

    def to_dict(self) -> dict:
        return asdict(self)


def _setup(sc: DynamicFactorScenario) -> tuple[TacSimulator, float]:
    """The simulator with the crane at the scenario's radius and the sea fading in; (simulator, radius)."""
    tac = TacScenario(
        hs=sc.hs if sc.hs > 0 else HS_RANGE[0], tp=sc.tp, heading=sc.heading, spectrum=sc.spectrum, seed=sc.seed,
        rao=sc.rao, dt=sc.dt, n_freq=sc.n_freq, mode="off" if sc.mode == "off" else "cooperative",
        duration=LEAD_IN + sc.duration + 1.0,
    )  # fmt: skip
    sim = TacSimulator(tac)
    sim.lookahead = 500
    system = sim.system
    if sc.radius is not None:
        try:
            beta = system.at_radius(sc.radius, sim.beta_d)
        except ValueError:
            lo, hi = system.reach(sim.beta_d)
            raise DynamicFactorError(
                f"radius {sc.radius:g} m is out of the crane's reach at its working height ({lo:g}–{hi:g} m)"
            ) from None
        sim.beta_d, sim.crane_servo.beta = beta.copy(), beta.copy()
        sim._beta0_hint = float(beta[0])
        sim.p_d_n = system.tcp_n(np.zeros(6), beta, system.p_d_t)
        sim.p_d_n0 = sim.p_d_n.copy()
    flat = VesselMotion(sim.vessel_rao, replace(sim.vessel.sea, amplitude=np.zeros_like(sim.vessel.sea.amplitude)))
    sim.vessel = flat if sc.hs == 0 else SeaTransition(flat, sim.vessel, 0.0, FADE_IN)
    return sim, system.radius(sim.beta_d)


def simulate(sc: DynamicFactorScenario, cancel=None) -> dict:
    """One cell (module text): ψ and what the wire did, as plain numbers."""
    t_wall = time.perf_counter()
    sim, radius = _setup(sc)
    load = CraneLoad(WinchSpec(start_length=sc.wire), LoadSpec(mass=1000.0 * sc.payload))
    load.ahc = sc.mode != "off"
    dt = sc.dt
    swing = None
    if sc.mode == "antisway":
        swing = CraneSwingControl(load, dt, np.random.default_rng(sc.seed + 30_000))
    p0 = sim.p_d_n0.copy()
    offset = np.zeros(3)
    n_lead = round(LEAD_IN / dt)
    n_total = n_lead + round(sc.duration / dt)
    factors = np.empty(n_total)
    swing_deg = np.empty(n_total)
    k = 0
    while k < n_total:
        if cancel is not None and cancel():
            raise DynamicFactorError("cancelled")
        if swing is not None:
            sim.p_d_n = np.array([p0[0] + offset[0], p0[1] + offset[1], p0[2]])
        c = sim.advance(min(CHUNK, n_total - k))
        for tcp in c.p_s_n if sc.mode == "off" else c.p_c_n:
            load.step(tcp, dt)
            e = load.state[0] - tcp
            ell = math.sqrt(float(e @ e))
            factors[k] = load.tension / load.static_tension()
            swing_deg[k] = math.degrees(math.acos(min(1.0, max(-1.0, e[2] / ell))))
            if swing is not None:
                offset = swing.step(e, ell, factors[k] >= SLACK_FACTOR)
            k += 1
    f, s = factors[n_lead:], swing_deg[n_lead:]
    return {
        "psi": float(np.max(f)),
        "min_tension_factor": float(np.min(f)),
        "std_tension_factor": float(np.std(f)),
        "slack_s": float(np.count_nonzero(f < SLACK_FACTOR) * dt),
        "snap_s": float(np.count_nonzero(f > SNAP_FACTOR) * dt),
        "peak_swing_deg": float(np.max(s)),
        "radius_m": radius,
        "g": G,
        "wall_s": time.perf_counter() - t_wall,
    }
