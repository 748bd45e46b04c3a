"""Issue 30, acceptance "checks against physics": the hanging load as Bosun integrates it (the PENDULUM block:
eqs. 29–30 by RK4, the step the crane's load takes, 0.01 s) swings with the period 2π√(L/g) and, undamped, keeps its
energy."""

import math

import numpy as np
import pytest

from app.sim.motionlab import PENDULUM

G = 9.81
DT = 0.01  # the crane-head scene's step


def _swing(L: float, alpha0: float, beta0: float, seconds: float, use_kernels: bool):
    x = (alpha0, beta0, 0.0, 0.0)
    u = (np.zeros(3), L, 0.0)  # the suspension point still, the wire fixed
    p = (0.0, G)  # undamped
    out = np.empty((round(seconds / DT) + 1, 4))
    out[0] = x
    for k in range(1, len(out)):
        x, _ = PENDULUM.step(x, u, p, DT, use_kernels)
        out[k] = x
    return out


def _energy(xs: np.ndarray, L: float) -> np.ndarray:
    """Per unit mass, eqs. (26)–(27) with the suspension point still: ½ L² (α̇² + cos²α β̇²) + g L (1 − cos α cos β)."""
    a, b, ad, bd = xs.T
    return 0.5 * L * L * (ad**2 + np.cos(a) ** 2 * bd**2) + G * L * (1.0 - np.cos(a) * np.cos(b))


@pytest.mark.parametrize("L", [2.0, 10.0, 30.0])
def test_the_small_swing_period_is_2pi_sqrt_L_over_g_to_a_thousandth(L):
    T0 = 2 * math.pi * math.sqrt(L / G)
    xs = _swing(L, 0.01, 0.0, 12 * T0, use_kernels=True)
    a = xs[:, 0]
    k = np.nonzero((a[:-1] > 0) & (a[1:] <= 0))[0]  # downward zero crossings, interpolated
    t = (k + a[k] / (a[k] - a[k + 1])) * DT
    period = float(np.mean(np.diff(t)))
    # amplitude 0.01 rad: the pendulum's own lengthening is (1 + θ²/16), 6e-6, far inside the tolerance
    assert abs(period / T0 - 1.0) < 1e-3, (period, T0)


@pytest.mark.parametrize("use_kernels", [True, False])
def test_an_undamped_swing_keeps_its_energy_over_100_periods(use_kernels):
    L = 10.0
    T0 = 2 * math.pi * math.sqrt(L / G)
    seconds = 100 * T0 if use_kernels else 10 * T0  # the NumPy reference is slow: 10 periods
    xs = _swing(L, 0.3, 0.2, seconds, use_kernels)  # a large, two-plane swing (17°, 11°)
    e = _energy(xs, L)
    drift = float(np.max(np.abs(e / e[0] - 1.0)))
    assert drift < 1e-6, drift
