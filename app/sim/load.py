"""The crane's suspended load on an elastic wire, with a deck to land on (issue 30, items 3 and 5).

A point mass m (the load's underside, where it touches a deck) hangs from the suspension point s (the crane
head's TCP) on a wire paid out to the unstretched length L by the winch.  In {n} (NED, z down):

    m r̈ = m g ẑ − T û − m c_a ṙ + F_n n̂ − μ F_n v_t / √(|v_t|² + v_s²)

* the wire, û = (r − s)/|r − s|, stretch ε = |r − s| − L, pulls only while taut:
  T = max(0, k ε + 2 ζ_w √(k m) (û·(ṙ − ṡ) − L̇)) for ε > 0, else 0, with k = EA/L (Hooke's law on the wire's
  axial stiffness EA).  A wire at T = 0 is slack; a taut wire carrying the load alone at rest pulls m g.
* the deck, a plane through the point d (moving at v_d) with the unit normal n̂ pointing up, away from it: the
  gap h = n̂·(r − d); below it (h < 0) a spring–damper pushes back, F_n = max(0, k_c δ + 2 ζ_c √(k_c m) δ̇) with
  δ = −h (the Hunt–Crossley clamp: a contact pushes, never pulls), and Coulomb friction, regularised at the slip
  speed v_s, acts against the load's sliding on the deck v_t = (ṙ − v_d) − n̂ (n̂·(ṙ − v_d)).
* c_a is a small linear air damping of the load's motion.

Over a step of ``dt`` the suspension point moves linearly from s₀ to s₁ (so ṡ = (s₁ − s₀)/dt), the wire length
from L₀ to L₁ and the deck point at v_d; the state is integrated with RK4 in ``substeps`` sub-steps (the wire's
axial mode, √(k/m) ≈ 30 rad/s at 10 m, asks for about a millisecond).

Without wire stretch and contact this is the spherical pendulum of the Motion-Lab paper's eqs. (29)–(30) in
Cartesian form: its small-swing period is 2π√(L_e/g) with the wire's static stretch in L_e = L + m g/k (the
stretch is m g/EA = 0.1 % of L with the values below, so the period is 2π√(L/g) to 0.05 %: tests/test_wire_load.py).

Assumed values (:class:`LoadSpec`), with their sources:

* EA = 5.0·10⁷ N: a 32 mm six-strand steel wire rope, metallic area ≈ 0.58·π d²/4 = 4.7 cm², rope modulus
  ≈ 100 kN/mm² for six-strand ropes with a steel core (K. Feyrer, *Wire Ropes*, 2nd ed., Springer 2015, §3.3);
  its minimum breaking force (≈ 650 kN) carries the 5 t load with the factor 13;
* ζ_w = 0.05 of critical along the wire (a rope's internal friction; small);
* the landing: k_c = 2·10⁷ N/m (a 5 t load on timber dunnage sinks 2.5 mm: "penetration held to
  millimetres"), ζ_c = 1 (dunnage does not bounce back), μ = 0.3 (steel on wet timber), v_s = 0.01 m/s;
* c_a = 0.02 1/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from app.models.block import Block
from app.models.pendulum import G
from app.sim import kernels as sim_kernels

__all__ = ["LOAD", "LoadSpec", "hanging", "no_deck"]


@dataclass(frozen=True)
class LoadSpec:
    """The load, its wire and the landing (assumed values: module text)."""

    mass: float = 5000.0  # kg
    ea: float = 5.0e7  # N: the wire's axial stiffness EA
    wire_damping: float = 0.05  # ζ_w, of critical along the wire
    air_damping: float = 0.02  # c_a [1/s]
    contact_stiffness: float = 2.0e7  # k_c [N/m]
    contact_damping: float = 1.0  # ζ_c, of critical on the deck
    friction: float = 0.3  # μ
    slip_speed: float = 0.01  # v_s [m/s]
    substeps: int = 10

    def record(self, g: float = G) -> tuple:
        """The parameter record of :data:`LOAD`."""
        return (
            float(self.mass), float(self.ea), float(self.wire_damping), float(self.air_damping),
            float(self.contact_stiffness), float(self.contact_damping), float(self.friction), float(self.slip_speed),
            float(g), int(self.substeps),
        )  # fmt: skip


def no_deck() -> tuple:
    """The deck record of a load with nothing below it: (present, d, n̂, v_d)."""
    return (False, np.zeros(3), np.array([0.0, 0.0, -1.0]), np.zeros(3))


def _forces(r, v, s, sd, L, Ld, deck, p):
    """The load's acceleration, the wire tension, the deck's normal force and the gap (see the module text)."""
    m, ea, zeta_w, c_a, k_c, zeta_c, mu, v_s, g = p[:9]
    e = r - s
    ell = float(np.sqrt(e @ e))
    u = e / ell
    k = ea / L
    stretch = ell - L
    T = 0.0
    if stretch > 0.0:
        T = max(0.0, k * stretch + 2.0 * zeta_w * math.sqrt(k * m) * (float(u @ (v - sd)) - Ld))
    f = -T * u - m * c_a * v
    f[2] += m * g
    present, d, n, vd = deck
    Fn, gap = 0.0, math.inf
    if present:
        gap = float(n @ (r - d))
        if gap < 0.0:
            rel = v - vd
            rel_n = float(n @ rel)
            Fn = max(0.0, k_c * (-gap) + 2.0 * zeta_c * math.sqrt(k_c * m) * (-rel_n))
            vt = rel - n * rel_n
            f = f + Fn * n - mu * Fn * vt / math.sqrt(float(vt @ vt) + v_s * v_s)
    return f / m, T, Fn, gap


def _load_reference(x, u, p, dt):
    """The NumPy reference of :data:`LOAD` (the kernel: ``app.sim.kernels.load_block``)."""
    r, v = (np.array(a, dtype=float) for a in x)
    s0, s1, L0, L1, deck = u
    s0, s1 = np.asarray(s0, dtype=float), np.asarray(s1, dtype=float)
    present, d0, n, vd = deck
    n_sub = int(p[9])
    h = dt / n_sub
    sd, Ld = (s1 - s0) / dt, (L1 - L0) / dt

    d0, n, vd = (np.asarray(a, dtype=float) for a in (d0, n, vd))

    def acc(tau, r_, v_):
        return _forces(r_, v_, s0 + sd * tau, sd, L0 + Ld * tau, Ld, (bool(present), d0 + vd * tau, n, vd), p)[0]

    for i in range(n_sub):
        tau = i * h
        a1 = acc(tau, r, v)
        r2, v2 = r + 0.5 * h * v, v + 0.5 * h * a1
        a2 = acc(tau + 0.5 * h, r2, v2)
        r3, v3 = r + 0.5 * h * v2, v + 0.5 * h * a2
        a3 = acc(tau + 0.5 * h, r3, v3)
        r4, v4 = r + h * v3, v + h * a3
        a4 = acc(tau + h, r4, v4)
        r = r + (h / 6.0) * (v + 2.0 * v2 + 2.0 * v3 + v4)
        v = v + (h / 6.0) * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
    _, T, Fn, gap = _forces(r, v, s1, sd, L1, Ld, (bool(present), d0 + vd * dt, n, vd), p)
    return (r, v), (T, Fn, gap)


LOAD_PARAMS = (
    "mass", "ea", "wire_damping", "air_damping", "contact_stiffness", "contact_damping", "friction", "slip_speed",
    "g", "substeps",
)  # fmt: skip

#: the load on its wire, with a deck below, as a block (app.models.block): the plant of the module text
LOAD = Block(
    "load on an elastic wire, with a deck",
    state=("r", "v"),
    inputs=("s0", "s1", "L0", "L1", "deck"),
    outputs=("tension", "contact_force", "gap"),
    params=LOAD_PARAMS,
    reference=_load_reference,
    kernel=sim_kernels.load_block,
)


def hanging(s: NDArray[np.float64], L: float, spec: LoadSpec, g: float = G) -> tuple:
    """The state of a load hanging still below ``s`` on a wire of unstretched length ``L`` (stretched by m g/k)."""
    r = np.asarray(s, dtype=float) + np.array([0.0, 0.0, L + spec.mass * g * L / spec.ea])
    return (r, np.zeros(3))
