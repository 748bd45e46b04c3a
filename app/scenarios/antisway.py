"""Load-swing estimation and anti-swing in the simulated Motion-Lab (issue 16, item 4).

The estimator and the law run on the lab through :class:`app.scenarios.swing.SwingControl`.

:func:`free_swing` is the issue's first aim (a 4° swing at L = 2 m with the platforms still and the
Comau holding the work point, with and without the law); :func:`antisway_study` the second (VVMC at
Hs 2 m with and without anti-swing: the swing rms and the VVMC error).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict

import numpy as np

from app.models.lab import load_lab
from app.scenarios.swing import SwingControl
from app.scenarios.vvmc import VvmcScenario, simulate, summarize
from app.scenes.lab import MotionLab

__all__ = ["antisway_study", "free_swing", "pendulum_band_rms"]


def _swing_deg(x) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, math.cos(x[0]) * math.cos(x[1])))))


def free_swing(
    active: bool, swing_deg: float = 4.0, L: float = 2.0, duration: float = 30.0, dt: float = 0.005, seed: int = 1
) -> dict:
    """A ``swing_deg`` swing (in the α plane) at wire length L with both platforms still and the Comau in
    MOTION_COMP on the work point; the time until the swing stays below 0.5°, with or without the law."""
    lab = MotionLab(load_lab(), at_work=True)
    for p in lab.platforms:  # both platforms still at neutral, the Comau on the work point
        p.place_at_neutral()
    lab.set_comau_mode("motion_comp")
    lab.winch.filter.x[0] = L
    for _ in range(round(2.0 / dt)):  # let the Comau settle on the work point, the load at rest
        lab.step(dt)
    pd = lab.pendulum
    pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot = math.radians(swing_deg), 0.0, 0.0, 0.0
    lab.t = 0.0
    ctl = SwingControl(lab, np.random.default_rng(seed), active=active)
    ctl.ekf.reset()
    n = round(duration / dt)
    t, swing, est, offset, err = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    settled = None
    for i in range(n):
        s = lab.step(dt)
        ctl.step(dt)
        t[i], swing[i] = s.t, _swing_deg(ctl.truth())
        est[i] = _swing_deg(ctl.ekf.x)
        offset[i] = float(np.linalg.norm(ctl.law.p))
        err[i] = float(np.linalg.norm(s.e_t_b2))
        if swing[i] >= 0.5:
            settled = None
        elif settled is None:
            settled = float(s.t)
    return {
        "anti_swing": active,
        "initial_swing_deg": swing_deg,
        "wire_length_m": L,
        "time_below_0_5_deg_s": settled,
        "swing_at_end_deg": float(swing[-1]),
        "max_offset_m": float(offset.max()),
        "max_tool_from_work_point_m": float(err.max()),
        "estimate_rms_error_deg": float(np.sqrt(np.mean((est - swing) ** 2))),
        "t": t,
        "swing_deg": swing,
        "estimate_deg": est,
    }


def antisway_study(
    sc: VvmcScenario, progress: Callable[[int], None] | None = None, cancel: Callable[[], bool] | None = None
) -> dict:
    """VVMC in waves without and with anti-swing (same seas): the swing rms, its reduction, and the
    tool's distance from the work point (the anti-swing offset included) and from its target."""
    plain = simulate(sc, True, progress=progress, cancel=cancel)
    swing_sc = VvmcScenario(**{**asdict(sc), "antisway": True})
    damped = simulate(swing_sc, True, progress=progress, cancel=cancel)
    off = summarize(sc, plain, plain)["compensated"]
    on = summarize(swing_sc, damped, damped)["compensated"]
    t0 = sc.ramp + sc.settle
    for doc, run in ((off, plain), (on, damped)):
        doc["swing_pendulum_band_rms_deg"] = pendulum_band_rms(run, sc.dt, t0)
    base, band = off["payload_swing_rms_deg"], off["swing_pendulum_band_rms_deg"]
    return {
        "scenario": sc.to_dict(),
        "vvmc": off,
        "vvmc_antisway": on,
        "swing_reduction_percent": 100.0 * (1.0 - on["payload_swing_rms_deg"] / base) if base > 0 else None,
        "pendulum_band_reduction_percent": (
            100.0 * (1.0 - on["swing_pendulum_band_rms_deg"] / band) if band > 0 else None
        ),
        "runs": (plain, damped),
    }


def pendulum_band_rms(run, dt: float, t0: float) -> float:
    """rms [deg] of the swing (both planes) in the band 0.8–1.2 × the pendulum's own frequency √(g/L)/2π
    (the oscillation a law can damp; the rest at the wave frequencies is the forced lean)."""
    m = run.t >= t0
    if np.count_nonzero(m) < 16:
        return 0.0
    f = np.fft.rfftfreq(int(np.count_nonzero(m)), dt)
    fn = math.sqrt(9.81 / float(run.L_w[m].mean())) / (2 * math.pi)
    band = (f > 0.8 * fn) & (f < 1.2 * fn)
    total = 0.0
    for k in range(2):
        x = np.degrees(run.swing[m, k] - run.swing[m, k].mean())
        X = np.fft.rfft(x)
        total += 2.0 * float(np.sum(np.abs(X[band]) ** 2)) / x.size**2  # Parseval (one-sided)
    return math.sqrt(total)
