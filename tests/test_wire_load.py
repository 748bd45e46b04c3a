"""Issue 30, items 3 and 5, and its "checks against physics", on the crane's load as Bosun integrates it (the LOAD
block, app/sim/load.py: a point mass on an elastic wire with a deck below): the small-swing period, the energy of an
undamped swing over 100 periods, the still-hanging tension, the landing (penetration in millimetres, the wire going
slack), and the compiled kernel against its NumPy reference."""

import math
from dataclasses import replace

import numpy as np
import pytest

from app.models.pendulum import G
from app.sim.load import LOAD, LoadSpec, hanging, no_deck

DT = 0.01
S = np.array([0.0, 0.0, -20.0])  # the suspension point in {n} (NED)


def _swing(L: float, angle: float, spec: LoadSpec) -> tuple:
    r = S + (L + spec.mass * G * L / spec.ea) * np.array([math.sin(angle), 0.0, math.cos(angle)])
    return (r, np.zeros(3))


def _deck(z: float, vz: float = 0.0) -> tuple:
    return (np.bool_(True), np.array([0.0, 0.0, z]), np.array([0.0, 0.0, -1.0]), np.array([0.0, 0.0, vz]))


@pytest.mark.parametrize("L", [3.0, 10.0, 30.0])
def test_the_small_swing_period_is_2pi_sqrt_L_over_g_to_a_thousandth(L):
    spec = LoadSpec()
    p = spec.record(G)
    x, xs = _swing(L, 0.02, spec), []
    period = 2 * math.pi * math.sqrt(L / G)
    n = int(6 * period / DT)
    for _ in range(n):
        x, _ = LOAD.step(x, (S, S, L, L, no_deck()), p, DT)
        xs.append(x[0][0])
    xs = np.array(xs)
    t = (np.arange(n) + 1) * DT
    k = np.where((xs[:-1] > 0) & (xs[1:] <= 0))[0]
    crossings = t[k] + xs[k] / (xs[k] - xs[k + 1]) * DT
    measured = float(np.mean(np.diff(crossings)))
    assert measured == pytest.approx(period, rel=1e-3), (measured, period)
    # what is left is the wire's static stretch m g/EA (4.9e-4 of the period), the amplitude's θ₀²/16 (2.5e-5) and
    # the air damping's 1/√(1 − ζ²), ζ = c_a/2ω (up to 1.5e-4 at 30 m): with the three, to 1e-4
    zeta = spec.air_damping / (2 * math.sqrt(G / L))
    expected = period * math.sqrt(1 + spec.mass * G / spec.ea) * (1 + 0.02**2 / 16) / math.sqrt(1 - zeta**2)
    assert measured == pytest.approx(expected, rel=1e-4), (measured, expected)


def _energy(x, L, spec):
    r, v = x
    k = spec.ea / L
    stretch = max(0.0, float(np.linalg.norm(r - S)) - L)
    return 0.5 * spec.mass * float(v @ v) - spec.mass * G * float(r[2]) + 0.5 * k * stretch**2


def test_an_undamped_swing_keeps_its_energy_over_100_periods():
    """No wire or air damping, a 10° swing of 10 m: after 100 periods the energy is what it was to 1e-6 of the
    swing's energy (RK4 in 1 ms sub-steps)."""
    L = 10.0
    spec = replace(LoadSpec(), wire_damping=0.0, air_damping=0.0)
    p = spec.record(G)
    x = _swing(L, math.radians(10.0), spec)
    e0 = _energy(x, L, spec)
    swing_energy = spec.mass * G * (L * (1 - math.cos(math.radians(10.0))))
    n = int(100 * 2 * math.pi * math.sqrt(L / G) / DT)
    for _ in range(n):
        x, _ = LOAD.step(x, (S, S, L, L, no_deck()), p, DT)
    drift = abs(_energy(x, L, spec) - e0) / swing_energy
    assert drift < 1e-6, drift


def test_a_still_hanging_load_pulls_its_weight_and_the_kernel_equals_the_reference():
    spec = LoadSpec()
    p = spec.record(G)
    x = hanging(S, 10.0, spec)
    for _ in range(50):
        x, (T, Fn, gap) = LOAD.step(x, (S, S, 10.0, 10.0, no_deck()), p, DT)
    assert pytest.approx(spec.mass * G, rel=1e-9) == T
    assert Fn == 0.0 and gap == math.inf
    # a swing that lands on a deck and slides: the compiled step against the NumPy reference
    xr = _swing(10.0, 0.1, spec)
    xk = (xr[0].copy(), xr[1].copy())
    deck = _deck(-20.0 + 10.0)  # the deck 1 cm above where the load hangs: it touches down as it swings
    s1 = S + np.array([0.0, 0.0, 0.0])
    for k in range(400):
        L = 10.0 + 0.002 * k  # paying out: the wire goes slack
        xr, yr = LOAD.step(xr, (S, s1, L, L + 0.002, deck), p, DT, use_kernels=False)
        xk, yk = LOAD.step((xk[0].copy(), xk[1].copy()), (S, s1, L, L + 0.002, deck), p, DT, use_kernels=True)
    np.testing.assert_allclose(xk[0], xr[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(xk[1], xr[1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(yk, yr, rtol=1e-9, atol=1e-6)
    assert yr[0] == 0.0 and yr[1] == pytest.approx(spec.mass * G, rel=1e-3)  # slack; the deck carries it


def test_a_touchdown_at_0_2_m_per_s_sinks_millimetres_and_the_wire_goes_slack_as_it_pays_out():
    spec = LoadSpec()
    p = spec.record(G)
    L = 10.0
    x = hanging(S, L, spec)
    deck = _deck(float(x[0][2]) + 0.5)  # 0.5 m below the load
    pen, tension, contact = [], [], []
    for _ in range(600):  # 6 s paying out at 0.2 m/s: 0.5 m to the deck, then 0.7 m of slack
        x, (T, Fn, gap) = LOAD.step(x, (S, S, L, L + 0.002, deck), p, DT)
        L += 0.002
        pen.append(-gap)
        tension.append(T)
        contact.append(Fn)
    pen = np.array(pen)
    assert 0.0005 < pen.max() < 0.005, pen.max()  # 2.5 mm static on the dunnage, a little more on impact
    assert tension[-1] == 0.0 and contact[-1] == pytest.approx(spec.mass * G, rel=1e-3)
    first = int(np.argmax(np.array(contact) > 0))
    assert all(c > 0 for c in contact[first:])  # no bounce: one contact, no re-hit
