"""Motion sensors as a controller sees them: sampled, late, band-limited, noisy and biased.

A :class:`MotionSensor` turns the true motion of a platform or vessel (η, η̇, η̈: 6 DOF each, SI,
Fossen's order x, y, z, φ, θ, ψ) into what the PLC reads every cycle.  Each output sample is taken
from the true signal ``latency`` seconds ago, passed through a first-order low-pass of ``bandwidth``
(the sensor's own filtering), held until the next sample (``rate``), and carries a constant bias
(drawn once per run) and white noise.  The displacements an inertial sensor integrates (surge, sway,
heave) carry instead the errors of that integration: a per-run scale error (the "5 %" of an MRU's
heave accuracy) and its accelerometer error integrated twice through the heave filter (a leaky double
integrator with the sensor's heave period), the long-period error behind the "5 cm" — at a Stewart
platform's wave periods (5–12 s) it comes to millimetres; its velocities the same integrated once.

Two specifications ship, with the source of every figure (the rest are assumptions, named):

* :data:`MRU5` — a Kongsberg Seatex MRU H (5th generation), the lab's own (Motion-Lab paper §2.5: one
  on each platform).  Kongsberg Seatex, "5th generation MRU" product overview (2013): MRU H roll/pitch
  accuracy 0.05° (MRU 5: 0.02°, MRU 5+: 0.01°), heave 5 cm or 5 % whichever is higher, heave period up
  to 25 s, acceleration 0.01 m/s², output data rate 200 Hz.  The lab reads
  two such MRUs over UDP into its 5 ms PLC task (motionlab_plc.json, ``network``/``mru_rx_struct``:
  Norwegian Motion-Laboratory repository, commit f5fbf84, MIT).  Assumed: latency one output sample
  (5 ms), bandwidth 20 Hz, yaw 0.1° (an MRU has no heading reference of its own), surge/sway like heave,
  angular rates 0.02°/s, the 5 % as the rms of the scale error, the heave filter with ζ = 1/√2 at the
  25 s period.
* :data:`TRACKER` — a Leica AT960 laser tracker measuring the tool's pose relative to EM1500: transverse
  maximum permissible error ±(15 µm + 6 µm/m), typical results half of it (Leica Absolute Tracker user
  manual, ISO 10360-10 specifications); assumed 1 kHz, 2 ms latency, 0.02 mm noise, nothing integrated.

The model is a statement of what the controller may know, not a sensor fusion: errors of the
displacement are independent of those of the rates and accelerations.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.errors import BosunError

__all__ = ["MRU5", "SENSORS", "TRACKER", "MotionSensor", "SensorError", "SensorSpec"]


class SensorError(BosunError):
    """A bad sensor setting (names it)."""


def _six(v) -> tuple[float, ...]:
    return tuple(float(x) for x in np.broadcast_to(np.asarray(v, dtype=float), (6,)))


@dataclass(frozen=True)
class SensorSpec:
    """What a sensor delivers (all 6-vectors in η's order x, y, z, φ, θ, ψ; SI units).

    ``accuracy``: rms of the error of η (a per-run bias, ``bias_share`` of the variance, and white
    noise); ``rate_noise``, ``accel_noise``: white noise on η̇ and η̈.  Where ``integrated`` is set, η
    and η̇ of that DOF are the sensor's integration of its own acceleration instead: a per-run scale
    error of rms ``scale_error`` and ``accel_noise`` through the heave filter (``heave_period``)."""

    name: str
    source: str
    rate: float  # Hz
    latency: float  # s
    bandwidth: float  # Hz (first-order low-pass; inf: none)
    accuracy: tuple[float, ...]
    rate_noise: tuple[float, ...]
    accel_noise: tuple[float, ...]
    integrated: tuple[bool, ...] = (False,) * 6  # η, η̇ integrated from the sensor's own acceleration
    scale_error: float = 0.0  # rms of the per-run scale error of the integrated DOFs
    heave_period: float = 25.0  # s: the heave filter's period
    bias_share: float = 0.5

    def __post_init__(self) -> None:
        for name in ("rate", "bandwidth"):
            v = getattr(self, name)
            if not (v > 0):
                raise SensorError(f"sensor {name} must be positive, got {v!r}")
        if not (math.isfinite(self.latency) and self.latency >= 0):
            raise SensorError(f"sensor latency must be ≥ 0 s, got {self.latency!r}")
        for name in ("accuracy", "rate_noise", "accel_noise"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (6,) or not np.all(np.isfinite(v)) or np.any(v < 0):
                raise SensorError(f"sensor {name} must be six finite numbers ≥ 0")
        if len(self.integrated) != 6:
            raise SensorError("sensor integrated must name six DOFs")
        if not (0.0 <= self.bias_share <= 1.0) or not (0.0 <= self.scale_error < 1.0):
            raise SensorError("sensor bias_share must be in [0, 1] and scale_error in [0, 1)")
        if not (self.heave_period > 0):
            raise SensorError(f"sensor heave_period must be positive, got {self.heave_period!r}")


_DEG = math.pi / 180.0
MRU5 = SensorSpec(
    name="Kongsberg Seatex MRU H (5th generation)",
    source="Kongsberg Seatex 5th generation MRU overview (2013): MRU H roll/pitch 0.05°, heave 5 cm or 5 %, "
    "25 s, 0.01 m/s², 200 Hz; latency, bandwidth, yaw, rate noise and the filter assumed",
    rate=200.0,
    latency=0.005,
    bandwidth=20.0,
    accuracy=_six([0.0, 0.0, 0.0, 0.05 * _DEG, 0.05 * _DEG, 0.1 * _DEG]),
    rate_noise=_six([0.01, 0.01, 0.01, 0.02 * _DEG, 0.02 * _DEG, 0.02 * _DEG]),
    accel_noise=_six([0.01, 0.01, 0.01, 0.05 * _DEG, 0.05 * _DEG, 0.05 * _DEG]),
    integrated=(True, True, True, False, False, False),
    scale_error=0.05,
    heave_period=25.0,
)
TRACKER = SensorSpec(
    name="Leica AT960 laser tracker (6-DOF probe)",
    source="Leica Absolute Tracker: transverse MPE ±(15 µm + 6 µm/m), typical half of it; 1 kHz, 2 ms assumed",
    rate=1000.0,
    latency=0.002,
    bandwidth=math.inf,
    accuracy=_six([2e-5, 2e-5, 2e-5, 0.001 * _DEG, 0.001 * _DEG, 0.001 * _DEG]),
    rate_noise=_six([1e-4, 1e-4, 1e-4, 0.01 * _DEG, 0.01 * _DEG, 0.01 * _DEG]),
    accel_noise=_six([0.01, 0.01, 0.01, 0.05 * _DEG, 0.05 * _DEG, 0.05 * _DEG]),
)
SENSORS = {"mru": MRU5, "tracker": TRACKER}


class MotionSensor:
    """A streaming sensor: call :meth:`measure` once per simulation step ``dt`` with the true motion.

    Parameters
    ----------
    spec : SensorSpec
    rng : numpy.random.Generator
        Draws the run's biases and scale errors and every noise sample (a seeded run repeats exactly).
    dt : float
        The simulation step [s] (≤ the sample period; the latency is rounded to whole steps).
    """

    def __init__(self, spec: SensorSpec, rng: np.random.Generator, dt: float):
        if not (dt > 0 and math.isfinite(dt)):
            raise SensorError(f"sensor step must be positive, got {dt!r}")
        self.spec, self.rng, self.dt = spec, rng, float(dt)
        acc = np.asarray(spec.accuracy)
        self.bias = rng.standard_normal(6) * acc * math.sqrt(spec.bias_share)
        self.noise = acc * math.sqrt(1.0 - spec.bias_share)
        self.integrated = np.asarray(spec.integrated, dtype=bool)
        self.scale = 1.0 + rng.standard_normal(6) * spec.scale_error * self.integrated
        self.int_err = np.zeros((2, 6))  # the heave filter's state: displacement and velocity error
        self._wc = 2 * math.pi / spec.heave_period
        self._delay = deque(maxlen=max(1, round(spec.latency / self.dt) + 1))
        self._period = 1.0 / spec.rate
        self._since = math.inf  # time since the last sample: the first call samples
        self._lp: NDArray[np.float64] | None = None
        self.out = (np.zeros(6), np.zeros(6), np.zeros(6))
        self.samples = 0

    def measure(self, eta: ArrayLike, eta_dot: ArrayLike, eta_ddot: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
        """The sensor's current output (η, η̇, η̈) after one more step of the true motion."""
        true = np.concatenate([np.asarray(eta, float), np.asarray(eta_dot, float), np.asarray(eta_ddot, float)])
        self._delay.append(true)
        self._since += self.dt
        if self._since + 1e-12 < self._period:
            return self.out
        sample_dt = self._since if math.isfinite(self._since) else self._period
        self._since = 0.0
        x = self._delay[0]  # latency steps ago (the oldest kept)
        if self._lp is None or not math.isfinite(self.spec.bandwidth):
            self._lp = x.copy()
        else:
            k = 1.0 - math.exp(-2 * math.pi * self.spec.bandwidth * sample_dt)
            self._lp = self._lp + k * (x - self._lp)
        s = self.spec
        n = self.rng.standard_normal(18)
        accel_err = np.asarray(s.accel_noise) * n[12:]
        eta_m = self._lp[:6] + self.bias + self.noise * n[:6]
        eta_dot_m = self._lp[6:12] + np.asarray(s.rate_noise) * n[6:12]
        eta_ddot_m = self._lp[12:] + accel_err
        m = self.integrated
        if np.any(m):
            # the accelerometer's error through the heave filter, ë = a_err − 2ζω_c ė − ω_c² e, ζ = 1/√2
            # (semi-implicit Euler at the sample period), and the per-run scale error of the integration
            e, ed = self.int_err
            ed = ed + sample_dt * (accel_err - math.sqrt(2.0) * self._wc * ed - self._wc**2 * e)
            e = e + sample_dt * ed
            self.int_err = np.array([e, ed])
            eta_m[m] = (self.scale * self._lp[:6] + e)[m]
            eta_dot_m[m] = (self.scale * self._lp[6:12] + ed)[m]
        self.out = (eta_m, eta_dot_m, eta_ddot_m)
        self.samples += 1
        return self.out
