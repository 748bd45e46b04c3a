"""Issue 16, item 4 (first part): the swing estimator and the anti-swing law on the load model of the
Motion-Lab paper, eqs. (23)–(30) (app/models/pendulum.py), without the rest of the lab.

The lab's design point: L = 3 m, c = 0.1 1/s, T_s = 5 ms (issue 16).  Seeded runs, generous bounds."""

import math

import numpy as np
import pytest
from scipy.stats import chi2

from app.control.antisway import (
    AntiSwing,
    AntiSwingDesign,
    AntiSwingError,
    GainSchedule,
    SwingEkf,
    axis_model,
    discretise,
    lqr_gain,
)
from app.models.pendulum import swing_derivative, swing_direction, swing_rk4

DESIGN = AntiSwingDesign()


def _swing_deg(x) -> float:
    return math.degrees(math.acos(math.cos(x[0]) * math.cos(x[1])))


def test_linear_model_is_the_pendulum_linearised_at_rest():
    """axis_model is the Jacobian of eqs. (29)–(30) at the hanging rest (α plane with ẍ, β plane with ÿ)."""
    L, c = 2.0, 0.1
    for plane, sign, axis in ((0, 1.0, 0), (1, -1.0, 1)):
        A, B = axis_model(L, c, sign=sign)
        h = 1e-6
        x = np.zeros(4)
        x[plane] = h
        d_angle = swing_derivative(x, np.zeros(3), L, 0.0, c)[2 + plane] / h
        x = np.zeros(4)
        x[2 + plane] = h
        d_rate = swing_derivative(x, np.zeros(3), L, 0.0, c)[2 + plane] / h
        a = np.zeros(3)
        a[axis] = h
        d_input = swing_derivative(np.zeros(4), a, L, 0.0, c)[2 + plane] / h
        assert A[1, 0] == pytest.approx(d_angle, rel=1e-6)
        assert A[1, 1] == pytest.approx(d_rate, rel=1e-6)
        assert B[1, 0] == pytest.approx(d_input, rel=1e-6)


@pytest.mark.parametrize("L", [0.3, 0.8, 2.0, 3.0, 4.7, 6.0])
def test_lqr_closed_loop_is_stable_over_the_wire_lengths(L):
    sched = GainSchedule(DESIGN)
    for sign, K in zip((1.0, -1.0), sched.gains(L), strict=True):
        Ad, Bd = discretise(*axis_model(L, DESIGN.c, sign=sign), DESIGN.Ts)
        rho = max(abs(np.linalg.eigvals(Ad - Bd @ K[None, :])))
        assert rho < 1.0
        # the interpolated gain is close to the gain solved at this length
        assert np.allclose(K, lqr_gain(L, DESIGN, sign), rtol=0.05, atol=1e-3)


def test_the_two_planes_differ_only_in_the_sign_of_the_swing_terms():
    ka, kb = lqr_gain(2.0, DESIGN, 1.0), lqr_gain(2.0, DESIGN, -1.0)
    assert np.allclose(ka[:2], -kb[:2]) and np.allclose(ka[2:], kb[2:])


def _free_swing(active: bool, L: float = 2.0, T: float = 60.0, dt: float = 0.005, ekf: SwingEkf | None = None, seed=0):
    """A 4° swing at L, tool following the anti-swing offset exactly; returns (settle time, max offset)."""
    rng = np.random.default_rng(seed)
    x = np.array([math.radians(4.0), 0.0, 0.0, 0.0])
    ctl = AntiSwing(active=active)
    settled, worst = None, 0.0
    for k in range(int(T / dt)):
        p, _, a = ctl.step(ekf.x if ekf else x, L, dt)
        worst = max(worst, float(np.abs(p).max()))
        x = swing_rk4(x, dt, a, L, 0.0, DESIGN.c)
        if ekf is not None:
            ekf.predict(dt, a + rng.normal(0, ekf.sigma_accel, 3), L)
            ekf.update(x[:2] + rng.normal(0, ekf.sigma_angle, 2), L)
        if _swing_deg(x) >= 0.5:
            settled = None
        elif settled is None:
            settled = (k + 1) * dt
    return settled, worst


@pytest.mark.slow
def test_a_4_degree_swing_at_2_m_is_damped_below_half_a_degree_within_10_s():
    """The issue's aim on the load model alone: ≤ 10 s with anti-swing; the uncontrolled decay (c = 0.1,
    envelope e^{-ct/2}) takes 2 ln 8 / c ≈ 42 s."""
    t_off, _ = _free_swing(False, T=80.0)
    t_on, worst = _free_swing(True, T=20.0)
    assert t_off == pytest.approx(2 * math.log(8) / DESIGN.c, rel=0.05)
    assert t_on is not None and t_on <= 10.0
    assert worst <= DESIGN.offset_max
    # with the estimate in the loop (noisy wire angle and tool acceleration), starting from "no swing"
    t_ekf, _ = _free_swing(True, T=20.0, ekf=SwingEkf(c=DESIGN.c))
    assert t_ekf is not None and t_ekf <= 10.0


def test_commands_and_offsets_stay_within_their_limits():
    design = AntiSwingDesign(a_max=0.5, offset_max=0.02)
    ctl = AntiSwing(design=design, active=True)
    worst_p = worst_a = 0.0
    x = np.array([math.radians(10.0), math.radians(-8.0), 0.0, 0.0])
    for _ in range(4000):
        p, _, a = ctl.step(x, 2.0, 0.005)
        x = swing_rk4(x, 0.005, a, 2.0, 0.0, design.c)
        worst_p, worst_a = max(worst_p, np.abs(p).max()), max(worst_a, np.abs(a).max())
    assert worst_p <= 0.02 + 1e-12 and worst_a <= 0.5 + 1e-12 and ctl.saturated in (True, False)
    ctl.active = False
    for _ in range(4000):  # deactivated: the offset goes back to zero
        ctl.step(x, 2.0, 0.005)
    assert np.abs(ctl.p).max() < 1e-3


def _ekf_run(measurement: str, seed: int = 3, T: float = 60.0, dt: float = 0.005):
    rng = np.random.default_rng(seed)
    L = 2.0
    x = np.array([math.radians(3.0), math.radians(-2.0), 0.0, 0.0])
    f = SwingEkf(c=0.1, measurement=measurement)
    a_true, nees = np.zeros(3), []
    for k in range(int(T / dt)):
        a_true = a_true * math.exp(-dt) + rng.normal(0, 0.3, 3) * math.sqrt(dt)  # smooth random tool motion
        Ld = 0.05 * math.sin(0.2 * k * dt)
        x = swing_rk4(x, dt, a_true, L, Ld, 0.1)
        f.predict(dt, a_true + rng.normal(0, f.sigma_accel, 3), L, Ld)
        L += Ld * dt
        if measurement == "angles":
            z = x[:2] + rng.normal(0, f.sigma_angle, 2)
        else:
            z = L * swing_direction(x[0], x[1]) + rng.normal(0, f.sigma_pos, 3)
        f.update(z, L)
        if k * dt > 2.0:  # after the start-up transient from the wrong initial estimate
            nees.append(f.nees(x))
    return np.array(nees), f


@pytest.mark.slow
@pytest.mark.parametrize("measurement", ["angles", "payload"])
def test_estimator_errors_agree_with_its_covariance(measurement):
    """NEES (4 states) inside its two-sided 95 % χ² bounds for ≥ 90 % of the samples of a seeded run."""
    nees, f = _ekf_run(measurement)
    lo, hi = chi2.ppf([0.025, 0.975], 4)
    inside = np.mean((nees > lo) & (nees < hi))
    assert inside >= 0.90, (inside, nees.mean())
    assert 2.0 < nees.mean() < 6.0  # and not merely wide: the mean is near the 4 degrees of freedom
    assert np.degrees(f.sigma()[:2]).max() < 0.5  # tighter than the wire-angle sensor itself


def test_bad_settings_are_refused_by_name():
    with pytest.raises(AntiSwingError, match="offset_max"):
        AntiSwingDesign(offset_max=0.0)
    with pytest.raises(AntiSwingError, match="damping c"):
        AntiSwingDesign(c=-1.0)
    with pytest.raises(AntiSwingError, match="measurement"):
        SwingEkf(measurement="laser")
    with pytest.raises(AntiSwingError, match="sigma_angle"):
        SwingEkf(sigma_angle=float("nan"))
    with pytest.raises(AntiSwingError, match="wire length"):
        axis_model(0.0, 0.1)
