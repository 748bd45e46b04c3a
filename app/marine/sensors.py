"""Motion sensors as a controller sees them: sampled, late, band-limited, noisy and biased.

A :class:`MotionSensor` turns the true motion of a platform or vessel (η, η̇, η̈: 6 DOF each, SI,
Fossen's order x, y, z, φ, θ, ψ) into what the PLC reads every cycle.  Each output sample is taken
from the true signal ``latency`` seconds ago, passed through a first-order low-pass of ``bandwidth``
(the sensor's own filtering), held until the next sample (``rate``), and carries a constant bias
(drawn once per run), white noise, and — for the displacements an inertial sensor integrates — a slow
error with the accuracy figure as its rms and the sensor's heave period as its time scale.

Two specifications ship, with the source of every figure (the rest are assumptions, named):

* :data:`MRU5` — a Kongsberg Seatex MRU 5 (5th generation).  Kongsberg Seatex, "5th generation MRU"
  product overview (2013): roll/pitch accuracy 0.02° (the MRU 5+: 0.01°), heave 5 cm or 5 % whichever
  is higher, heave period up to 25 s, acceleration 0.01 m/s², output data rate 200 Hz.  The lab reads
  two such MRUs over UDP into its 5 ms PLC task (motionlab_plc.json, ``network``/``mru_rx_struct``:
  Norwegian Motion-Laboratory repository, commit f5fbf84, MIT).  Assumed: latency one output sample
  (5 ms), bandwidth 20 Hz, yaw 0.1° (an MRU has no heading reference of its own), surge/sway like heave,
  angular rates 0.02°/s.
* :data:`TRACKER` — a Leica AT960 laser tracker measuring the tool's pose relative to EM1500: transverse
  maximum permissible error ±(15 µm + 6 µm/m), typical results half of it (Leica Absolute Tracker user
  manual, ISO 10360-10 specifications); assumed 1 kHz, 2 ms latency, 0.02 mm noise, no slow error.

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

    ``accuracy``: rms of the displacement error (split into a per-run bias, ``bias_share`` of the
    variance, white noise and, where ``slow`` is set, a slow error of that rms with ``slow_period``);
    ``rate_noise``, ``accel_noise``: white noise on η̇ and η̈."""

    name: str
    source: str
    rate: float  # Hz
    latency: float  # s
    bandwidth: float  # Hz (first-order low-pass; inf: none)
    accuracy: tuple[float, ...]
    rate_noise: tuple[float, ...]
    accel_noise: tuple[float, ...]
    slow: tuple[float, ...] = (0.0,) * 6  # rms of the slow displacement error per DOF
    slow_relative: float = 0.0  # ... at least this share of the signal's own rms ("5 % whichever is higher")
    slow_period: float = 25.0  # s
    bias_share: float = 0.5

    def __post_init__(self) -> None:
        for name in ("rate", "bandwidth"):
            v = getattr(self, name)
            if not (v > 0):
                raise SensorError(f"sensor {name} must be positive, got {v!r}")
        if not (math.isfinite(self.latency) and self.latency >= 0):
            raise SensorError(f"sensor latency must be ≥ 0 s, got {self.latency!r}")
        for name in ("accuracy", "rate_noise", "accel_noise", "slow"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (6,) or not np.all(np.isfinite(v)) or np.any(v < 0):
                raise SensorError(f"sensor {name} must be six finite numbers ≥ 0")
        if not (0.0 <= self.bias_share <= 1.0) or not (0.0 <= self.slow_relative < 1.0):
            raise SensorError("sensor bias_share must be in [0, 1] and slow_relative in [0, 1)")
        if not (self.slow_period > 0):
            raise SensorError(f"sensor slow_period must be positive, got {self.slow_period!r}")


_DEG = math.pi / 180.0
MRU5 = SensorSpec(
    name="Kongsberg Seatex MRU 5 (5th generation)",
    source="Kongsberg Seatex 5th generation MRU overview (2013): roll/pitch 0.02°, heave 5 cm or 5 %, 25 s, "
    "0.01 m/s², 200 Hz; latency, bandwidth, yaw and rate noise assumed",
    rate=200.0,
    latency=0.005,
    bandwidth=20.0,
    accuracy=_six([0.0, 0.0, 0.0, 0.02 * _DEG, 0.02 * _DEG, 0.1 * _DEG]),
    rate_noise=_six([0.01, 0.01, 0.01, 0.02 * _DEG, 0.02 * _DEG, 0.02 * _DEG]),
    accel_noise=_six([0.01, 0.01, 0.01, 0.05 * _DEG, 0.05 * _DEG, 0.05 * _DEG]),
    slow=_six([0.05, 0.05, 0.05, 0.0, 0.0, 0.0]),
    slow_relative=0.05,
    slow_period=25.0,
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
        Draws the run's biases and every noise sample (a seeded run repeats exactly).
    dt : float
        The simulation step [s] (≤ the sample period; the latency is rounded to whole steps).
    signal_rms : array_like (6,), optional
        The expected rms of η per DOF, for ``slow_relative`` ("5 % whichever is higher").
    """

    def __init__(self, spec: SensorSpec, rng: np.random.Generator, dt: float, signal_rms: ArrayLike | None = None):
        if not (dt > 0 and math.isfinite(dt)):
            raise SensorError(f"sensor step must be positive, got {dt!r}")
        self.spec, self.rng, self.dt = spec, rng, float(dt)
        acc = np.asarray(spec.accuracy)
        self.bias = rng.standard_normal(6) * acc * math.sqrt(spec.bias_share)
        self.noise = acc * math.sqrt(1.0 - spec.bias_share)
        rms = np.zeros(6) if signal_rms is None else np.abs(np.asarray(signal_rms, dtype=float))
        self.slow_rms = np.maximum(np.asarray(spec.slow), spec.slow_relative * rms) * (np.asarray(spec.slow) > 0)
        self.slow_state = rng.standard_normal(6) * self.slow_rms
        self._tau_slow = spec.slow_period / (2 * math.pi)
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
        # the slow error evolves with the simulation (first-order Gauss–Markov of rms slow_rms)
        if np.any(self.slow_rms > 0):
            phi = math.exp(-self.dt / self._tau_slow)
            self.slow_state = phi * self.slow_state + math.sqrt(
                1 - phi * phi
            ) * self.slow_rms * self.rng.standard_normal(6)
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
        eta_m = self._lp[:6] + self.bias + self.noise * n[:6] + self.slow_state
        eta_dot_m = self._lp[6:12] + np.asarray(s.rate_noise) * n[6:12]
        eta_ddot_m = self._lp[12:] + np.asarray(s.accel_noise) * n[12:]
        self.out = (eta_m, eta_dot_m, eta_ddot_m)
        self.samples += 1
        return self.out
