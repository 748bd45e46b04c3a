"""Vessel-to-vessel motion compensation (VVMC) in the simulated Motion-Lab.

Both platforms play a vessel in the same irregular sea (EM8000 the supply vessel at
``heading1``, EM1500 the receiving vessel at ``heading2``, each DOF auto-scaled into its
platform's limits).  With compensation the Comau keeps its tool point on the work point fixed
in EM1500's body frame by inverse kinematic control (analytic IK, eqs. 7–20, plus the
feed-forward joint velocity J⁻¹ ṗ of eq. 21 computed from both platforms' velocities, eqs. 54–56),
and the winch keeps the payload's height relative to EM1500.  Without compensation the robot and
winch hold still.  The same seas drive both runs, so the two are directly comparable.

``sensors`` chooses what the controllers see of the platforms (issue 16, item 3): ``true`` (the
simulation's states), ``mru`` (a Kongsberg MRU 5 on each platform) or ``tracker`` (a laser tracker),
each a :class:`~app.marine.sensors.MotionSensor` sampled at its own rate inside the PLC's 5 ms step;
scores always use the true states.  ``antisway`` adds the load-swing estimator and the anti-swing law
(:mod:`app.scenarios.swing`) to the Comau's command.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from app.errors import BosunError
from app.marine.sensors import SENSORS, MotionSensor
from app.marine.vessels import vessel_rao
from app.marine.waves import SPECTRA, check_sea
from app.models.lab import load_lab
from app.models.registry import load_robot
from app.scenarios.swing import SwingControl
from app.scenes.lab import MotionLab
from app.scenes.tac_kernels import ease_in
from app.sim.stewart import WaveSimulation

PREDICT_DT = 0.1  # s: the predictor's sample time
PREDICT_LEAD_IN = 160.0  # s: the predictor fits first at 150 s (half its 300 s window)
#: s: a late view goes over to the prediction along the quintic of H108 once the predictor has fitted (a lab
#: engine's delay is set with no past: the first fit comes 150 s later, perhaps under VVMC, and the view must not
#: step by the motion of a delay's length)
PREDICT_BLEND = 2.0


class LateView:
    """What the lab's controllers see of one platform ``delay`` s late (issue 31, item 2), or with ``predict`` the
    motion predicted that far ahead from those late samples (:class:`app.control.predict.MotionPredictor` on η, η̇
    and η̈, fed every :data:`PREDICT_DT`; the steps between use the prediction at delay + their age).  ``inner``:
    the platform's sensor, or None for the true states.  Duck-types a :class:`~app.marine.sensors.MotionSensor`
    (``measure`` once per step) for :meth:`app.scenes.lab.MotionLab.set_sensors`."""

    def __init__(self, inner: MotionSensor | None, delay: float, dt: float, predict: bool) -> None:
        from collections import deque

        from app.control.predict import Foresight, PredictorSpec

        self.inner = inner
        self.dt = float(dt)
        self._late: deque = deque(maxlen=round(delay / dt) + 1)
        self.foresight = Foresight(18, delay, dt, PredictorSpec(dt=PREDICT_DT)) if predict else None
        self.k = 0
        self._predicted_for = 0.0  # s the prediction has been in use: it blends in over PREDICT_BLEND

    def measure(self, eta, eta_dot, eta_ddot) -> tuple[NDArray, NDArray, NDArray]:
        seen = self.inner.measure(eta, eta_dot, eta_ddot) if self.inner is not None else (eta, eta_dot, eta_ddot)
        self._late.append(np.concatenate([np.asarray(x, dtype=float) for x in seen]))
        late = self._late[0]  # delay ago (at the start, the oldest there is)
        self.k += 1
        if self.foresight is not None:
            ahead = self.foresight.step(self.k, late)
            if ahead is not late:  # the predictor has fitted: from the late view to the prediction, eased (H108)
                self._predicted_for += self.dt
                w = ease_in(self._predicted_for / PREDICT_BLEND)[0]
                late = ahead if w >= 1.0 else late + w * (ahead - late)
        return late[:6], late[6:12], late[12:]


class VvmcError(BosunError):
    """A VVMC scenario that cannot run (one line)."""


@dataclass(frozen=True)
class VvmcScenario:
    """Sea, vessels and run length.  Angles in degrees (they come from the CLI)."""

    hs: float = 2.0
    tp: float = 8.0
    spectrum: str = "jonswap"
    heading1: float = 150.0  # EM8000 vessel: bow quartering sea
    heading2: float = 90.0  # EM1500 vessel: beam sea
    duration: float = 300.0
    dt: float = 0.005  # the lab PLC's task (motionlab_plc.json, ads_hmi.plc_task)
    seed: int = 1
    ramp: float = 5.0  # platform ENGAGE fade [s]
    settle: float = 10.0  # not counted in the statistics [s] (after the ramp)
    rao: str | None = None
    lab: str = "motionlab"
    comau_profile: str | None = None  # the Comau's joint-limit profile; None: the layout's (``lab``)
    sensors: str = "true"  # what the controllers see of the platforms: true | mru | tracker
    antisway: bool = False  # the load-swing estimator and anti-swing law on the Comau's command
    swing_measurement: str = "angles"  # the estimator's measurement: angles (wire sensor) | payload (tracker)
    delay: float = 0.0  # s: the controllers see the platforms this late (issue 31, item 2)
    predict: bool = False  # ... or the motion predicted that far ahead from the late samples (app.control.predict)

    def __post_init__(self) -> None:
        if self.spectrum not in SPECTRA:
            raise VvmcError(f"spectrum must be one of {', '.join(SPECTRA)}, got {self.spectrum!r}")
        for name in ("hs", "tp", "duration", "dt"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise VvmcError(f"--{name} must be a positive number, got {v}")
        if self.dt > 0.05:
            raise VvmcError(f"--dt {self.dt:g} s is too coarse for the pendulum and servo loops (at most 0.05 s)")
        if self.duration <= self.ramp + self.settle:
            raise VvmcError(
                f"--duration {self.duration:g} s leaves nothing to measure after the "
                f"{self.ramp + self.settle:g} s start-up"
            )
        check_sea(self.hs, self.tp)
        if self.sensors not in ("true", *SENSORS):
            raise VvmcError(f"--sensors must be one of true, {', '.join(SENSORS)}; got {self.sensors!r}")
        if self.swing_measurement not in ("angles", "payload"):
            raise VvmcError(f"the swing measurement must be angles or payload, got {self.swing_measurement!r}")
        if not (math.isfinite(self.delay) and 0.0 <= self.delay <= 2.0):
            raise VvmcError(f"--delay must be in [0, 2] s, got {self.delay}")
        every = PREDICT_DT / self.dt
        if self.predict and abs(every - round(every)) > 1e-9:
            raise VvmcError(f"--predict needs a time step that divides {PREDICT_DT:g} s, got {self.dt:g}")

    @property
    def lead_in(self) -> float:
        """Seconds run before the ramp and settle with a delay or prediction (not counted: the predictor's first fit
        needs its window's half, and the runs with and without prediction are scored over the same span)."""
        return PREDICT_LEAD_IN if (self.delay > 0 or self.predict) else 0.0

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(eq=False)
class VvmcRun:
    """Time series of one run (n samples); arrays, SI units, angles in rad."""

    compensated: bool
    t: NDArray[np.float64]
    eta1: NDArray[np.float64]
    eta2: NDArray[np.float64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64]
    e_t_b2: NDArray[np.float64]
    L_w: NDArray[np.float64]
    L_w_dot: NDArray[np.float64]
    swing: NDArray[np.float64]
    height_error: NDArray[np.float64]
    at_limit: NDArray[np.bool_]
    leg_clamped: NDArray[np.bool_]
    cancelled: bool = False
    offset_b2: NDArray[np.float64] | None = None  # the anti-swing offset of the tool target, in {b2}
    swing_estimate: NDArray[np.float64] | None = None  # the estimator's (α, β)


def _sources(sc: VvmcScenario, lab: MotionLab) -> list[NDArray[np.float64]]:
    """Both platforms in the sea; returns the expected rms of each platform's motion (6,) per DOF."""
    rao = vessel_rao(sc.rao)  # a name or a file; None: the default vessel (issue 17)
    rms = []
    for p, heading in zip(lab.platforms, (sc.heading1, sc.heading2), strict=True):
        src = WaveSimulation(rao, sc.spectrum, sc.hs, sc.tp, heading, sc.seed, np.ones(6))
        scale = WaveSimulation.auto_scale(src.significant, p.model, box=p.command_box)
        src = WaveSimulation(rao, sc.spectrum, sc.hs, sc.tp, heading, sc.seed, scale)
        rms.append(src.significant * scale / 4.0)  # significant = 4σ
        p.place_at_neutral()
        p.ramp_time = sc.ramp
        p.set_source("simulation", src)
        p.command("engage")
    return rms


def _sensors(sc: VvmcScenario, lab: MotionLab, rms: list[NDArray[np.float64]]) -> None:
    late = sc.delay > 0 or sc.predict
    if sc.sensors == "true":
        lab.set_sensors(tuple(LateView(None, sc.delay, sc.dt, sc.predict) for _ in rms) if late else None)
        return
    spec = SENSORS[sc.sensors]
    rng = np.random.default_rng([sc.seed, 16_3])  # its own stream: the seas are the same as without
    sensors = tuple(MotionSensor(spec, rng, sc.dt) for _ in rms)
    lab.set_sensors(tuple(LateView(s, sc.delay, sc.dt, sc.predict) for s in sensors) if late else sensors)


def simulate(
    sc: VvmcScenario,
    compensate: bool,
    progress: Callable[[int], None] | None = None,
    cancel: Callable[[], bool] | None = None,
    use_kernels: bool | None = None,
) -> VvmcRun:
    """One run; ``progress(n_steps_done)`` is called every 100 steps.  ``use_kernels``: compiled
    (True) or the NumPy reference (False) lab; default the lab's own (compiled when numba is there)."""
    layout = load_lab(sc.lab)
    lab = MotionLab(layout, at_work=True, comau_profile=sc.comau_profile)
    if use_kernels is not None:
        lab.use_kernels = use_kernels
    rms = _sources(sc, lab)
    _sensors(sc, lab, rms)
    lab.set_vvmc(compensate)
    swing_ctl = None
    if sc.antisway and compensate:
        swing_ctl = SwingControl(lab, np.random.default_rng([sc.seed, 16_4]), measurement=sc.swing_measurement)
    n = round((sc.duration + sc.lead_in) / sc.dt)
    t, L, Ld, h = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    eta1, eta2, q, qd, e, swing = (np.empty((n, k)) for k in (6, 6, 3, 3, 3, 2))
    off_b2, est = np.zeros((n, 3)), np.zeros((n, 2))
    at_limit = np.zeros((n, 4), dtype=bool)
    clamped = np.zeros((n, 2), dtype=bool)
    p1, p2 = lab.platforms
    R_g_n1 = layout.T_world_n1[:3, :3]
    done = n
    for i in range(n):
        s = lab.step(sc.dt)
        t[i], eta1[i], eta2[i], q[i], qd[i], e[i] = s.t, s.eta1, s.eta2, s.q, s.qd, s.e_t_b2
        L[i], Ld[i], swing[i], h[i] = s.L_w, s.L_w_dot, s.swing, s.payload_height_error
        if swing_ctl is not None:
            off_b2[i] = lab.platform_pose(1)[:3, :3].T @ (R_g_n1 @ lab.tool_offset[0])  # the offset in force
            swing_ctl.step(sc.dt)
            est[i] = swing_ctl.ekf.x[:2]
        at_limit[i] = lab.at_limit
        clamped[i, 0], clamped[i, 1] = p1.leg_clamped, p2.leg_clamped
        if progress is not None and (i + 1) % 100 == 0:
            progress(i + 1)
        if cancel is not None and cancel():
            done = i + 1
            break
    sl = slice(0, done)
    series = (t, eta1, eta2, q, qd, e, L, Ld, swing, h, at_limit, clamped)
    extra = {"offset_b2": off_b2[sl], "swing_estimate": est[sl]} if swing_ctl is not None else {}
    return VvmcRun(compensate, *(x[sl] for x in series), cancelled=done < n, **extra)


def _rms(x: NDArray[np.float64]) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else 0.0


def summarize(sc: VvmcScenario, on: VvmcRun, off: VvmcRun) -> dict:
    """The JSON summary: rms relative tool-point error with and without VVMC, swing, utilisation."""
    layout = load_lab(sc.lab)
    robot = load_robot(layout.crane_robot)
    prof = layout.profile(sc.comau_profile)  # utilisation of the limits in force
    lower = robot.lower if prof.lower is None else prof.lower
    upper = robot.upper if prof.upper is None else prof.upper
    speed = robot.speed if prof.speed is None else prof.speed
    t0 = sc.ramp + sc.settle + sc.lead_in

    def stats(run: VvmcRun) -> dict:
        m = run.t >= t0
        e = run.e_t_b2[m]
        e0 = e  # from the work point, the same measure for both runs
        swing = np.degrees(np.arccos(np.clip(np.cos(run.swing[m, 0]) * np.cos(run.swing[m, 1]), -1, 1)))
        q_range = upper - lower
        target = e0 if run.offset_b2 is None else e0 - run.offset_b2[m]  # from the target the Comau tracks
        est = {}
        if run.swing_estimate is not None:
            err = np.degrees(run.swing_estimate[m] - run.swing[m])
            est = {"swing_estimate_rms_error_deg": [_rms(err[:, 0]), _rms(err[:, 1])]}
        return {
            **est,
            "rms_tool_error_m": _rms(np.linalg.norm(e0, axis=1)),
            "rms_tool_tracking_error_m": _rms(np.linalg.norm(target, axis=1)),
            "rms_tool_error_xyz_m": [_rms(e0[:, k]) for k in range(3)],
            "max_tool_error_m": float(np.max(np.linalg.norm(e0, axis=1))) if e0.size else 0.0,
            "mean_tool_offset_m": [float(v) for v in e.mean(axis=0)],
            "rms_payload_height_error_m": _rms(run.height_error[m]) if run.compensated else None,
            "payload_swing_rms_deg": _rms(swing),
            "payload_swing_max_deg": float(swing.max()) if swing.size else 0.0,
            "joint_speed_utilisation": [float(v) for v in np.max(np.abs(run.qd[m]), axis=0) / speed],
            "joint_range_utilisation": [float(v) for v in np.ptp(run.q[m], axis=0) / q_range],
            "winch_speed_utilisation": float(np.max(np.abs(run.L_w_dot[m])) / layout.winch["speed"]),
            "winch_length_range_m": [float(run.L_w[m].min()), float(run.L_w[m].max())],
            "time_at_limit_s": float(np.sum(run.at_limit[m].any(axis=1)) * sc.dt),
            "time_at_limit_per_axis_s": [float(v) for v in run.at_limit[m].sum(axis=0) * sc.dt],
            "time_leg_clamped_s": float(np.sum(run.leg_clamped[m].any(axis=1)) * sc.dt),
        }

    s_on, s_off = stats(on), stats(off)
    off_rms = s_off["rms_tool_error_m"]
    return {
        "sensors": sc.sensors,
        "antisway": sc.antisway,
        "delay_s": sc.delay,
        "predict": sc.predict,
        "measured_from_s": t0,
        "compensated": s_on,
        "uncompensated": s_off,
        "reduction_percent": 100.0 * (1.0 - s_on["rms_tool_error_m"] / off_rms) if off_rms > 0 else None,
    }
