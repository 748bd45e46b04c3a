"""Viscous roll damping by Ikeda's component method (issue 31, item 6), zero forward speed.

Ikeda's method sums the roll damping of a ship from components: friction, wave making, eddy making, lift and
bilge keels (Ikeda, Himeno & Tanaka 1978; Himeno 1981, "Prediction of ship roll damping — state of the art";
the ITTC Recommended Procedure 7.5-02-07-04.5, 2011).  Here:

* **wave making** is the boundary-element solver's own radiation damping (:mod:`app.marine.bem`), not added;
* **lift** is proportional to the forward speed (B_L ∝ U): zero for a vessel holding station;
* **friction, eddy making and bilge keels** in the form of Kawahara, Maekawa & Ikeda (2011), "A simple
  prediction formula of roll damping of conventional cargo ships on the basis of Ikeda's method and its
  limitation" (in *Contemporary Ideas on Ship Stability and Capsizing in Waves*, Springer, pp. 465–486): Kato's
  frictional formula as Ikeda uses it, and the eddy and bilge-keel components of Ikeda's method fitted over
  conventional cargo ships as closed formulas of B/d, C_B, C_M, OG/d, the bilge keels' size and the roll
  amplitude.  The formulas are the paper's, as its authors coded them (Ikeda, Kawahara & Maekawa,
  ``Roll_Damping.for``, 2009); tests/test_roll_damping.py checks them against that program's output for the
  paper's base ship.  Non-dimensional damping B̂ = B44 / (ρ ∇ B²) · √(B/(2g)), frequency ω̂ = ω √(B/(2g)).

The sectional form of Ikeda's eddy and bilge-keel components (Lewis sections, the hull-pressure integrals) is not
built: its formulas could not be read in the ITTC procedure or in Himeno (1981) (the open copies stop at their
contents), and the open implementations of it disagree with each other (docs/foresight.md).

Sign: OG is the distance from the still-water level down to the roll axis G (positive down, as in the authors'
program: a ship whose G lies above the waterline has OG < 0).

The components depend on the roll amplitude φ_a (eddy making and the bilge keels' drag grow with it): each is
the equivalent linear coefficient of a harmonic roll of amplitude φ_a.  In a random sea the amplitude is taken
as the significant roll amplitude's equivalent — the stochastic linearisation of a quadratic damping gives
B_eq = B1 + √(8/π) σ_φ̇ B2 where a harmonic roll gives B1 + (8/(3π)) ω φ_a B2, so the components are evaluated
at φ_a = (3π/8)·√(8/π)·σ_φ̇/ω = √(9π/8)·σ_φ̇/ω (iterated with the response, :mod:`app.marine.bem`).

The method's range (the paper's, checked by its program): 2.5 ≤ B/d ≤ 4.5, 0.5 ≤ C_B ≤ 0.85,
0.9 ≤ C_M ≤ 0.99, −1.5 ≤ OG/d ≤ 0.2, ω̂ ≤ 1, and with bilge keels 0.05 ≤ l_BK/L ≤ 0.4, 0.01 ≤ b_BK/B ≤ 0.06.
Outside it the formulas are extrapolated; :func:`out_of_range` names each parameter outside (reported, not
refused: a hull is what it is).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from app.errors import BosunError

__all__ = ["NU", "RANGE", "BilgeKeels", "IkedaHull", "RollDampingError", "components", "out_of_range"]

NU = 1.14e-6  # m²/s: sea water's kinematic viscosity at 15 °C (the authors' program's value)
#: the simplified formula's range (Kawahara, Maekawa & Ikeda 2011; their program's checks)
RANGE = {
    "B/d": (2.5, 4.5), "C_B": (0.5, 0.85), "C_M": (0.9, 0.99), "OG/d": (-1.5, 0.2), "omega_hat": (0.0, 1.0),
    "l_BK/L": (0.05, 0.4), "b_BK/B": (0.01, 0.06),
}  # fmt: skip


class RollDampingError(BosunError):
    """Particulars the method cannot take (one line)."""


@dataclass(frozen=True)
class BilgeKeels:
    """A pair of bilge keels: their length along the hull and their breadth (depth) [m]."""

    length: float
    breadth: float


@dataclass(frozen=True)
class IkedaHull:
    """What the method reads of a hull: length between perpendiculars, beam, draught [m], block and midship
    section coefficients, OG [m] (down positive), and its bilge keels (None: a naked hull)."""

    lpp: float
    beam: float
    draft: float
    cb: float
    cm: float
    og: float
    keels: BilgeKeels | None = None

    def __post_init__(self) -> None:
        for name in ("lpp", "beam", "draft", "cb", "cm"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise RollDampingError(f"roll damping: {name} must be a positive number, got {v}")
        if not (self.cb < 1 and self.cm <= 1 and math.isfinite(self.og)):
            raise RollDampingError("roll damping: C_B < 1, C_M ≤ 1 and a finite OG are needed")
        k = self.keels
        if k is not None and not (0 < k.length <= self.lpp and 0 < k.breadth < self.beam / 2):
            raise RollDampingError(
                f"roll damping: bilge keels {k.length:g} m × {k.breadth:g} m: the length within (0, Lpp], the "
                "breadth within (0, B/2)"
            )

    @property
    def volume(self) -> float:
        return self.lpp * self.beam * self.draft * self.cb


def out_of_range(hull: IkedaHull, omega: float) -> list[str]:
    """The parameters outside the method's range (:data:`RANGE`), each as "name value (range lo–hi)"."""
    values = {
        "B/d": hull.beam / hull.draft, "C_B": hull.cb, "C_M": hull.cm, "OG/d": hull.og / hull.draft,
        "omega_hat": omega * math.sqrt(hull.beam / (2 * 9.81)),
    }  # fmt: skip
    if hull.keels is not None:
        values["l_BK/L"] = hull.keels.length / hull.lpp
        values["b_BK/B"] = hull.keels.breadth / hull.beam
    return [
        f"{name} {v:.3g} (range {RANGE[name][0]:g}–{RANGE[name][1]:g})"
        for name, v in values.items()
        if not RANGE[name][0] <= v <= RANGE[name][1]
    ]


def components(hull: IkedaHull, omega: float, phi_a: float, rho: float = 1025.0, g: float = 9.81) -> dict[str, float]:
    """The friction, eddy-making, lift and bilge-keel roll damping [N m s/rad] of ``hull`` rolling at ``omega``
    [rad/s] with amplitude ``phi_a`` [rad] (module text), with their non-dimensional values (``*_hat``)."""
    if not (math.isfinite(omega) and omega > 0 and math.isfinite(phi_a) and phi_a > 0):
        raise RollDampingError(f"roll damping: ω and φ_a must be positive, got {omega:g} rad/s, {phi_a:g} rad")
    L, B, d, cb, cm = hull.lpp, hull.beam, hull.draft, hull.cb, hull.cm
    bd, ogd = B / d, hull.og / d
    w_hat = omega * math.sqrt(B / (2 * g))
    scale = rho * hull.volume * B**2 * math.sqrt(2 * g / B)  # B44 = B̂ · ρ∇B² √(2g/B)
    phi_deg = math.degrees(phi_a)
    # friction (Kato 1958, as Ikeda): the mean radius r_f of the wetted surface S_f about G, the laminar C_f
    r_f = d * ((0.887 + 0.145 * cb) * (1.7 + cb * bd) - 2.0 * ogd) / math.pi
    s_f = L * (1.75 * d + cb * B)  # the authors' S_f (their r_f above takes 1.7 d: both as published)
    period = 2 * math.pi / omega
    c_f = 1.328 * (3.22 * r_f**2 * phi_a**2 / (period * NU)) ** -0.5
    b_f = 4.0 / (3.0 * math.pi) * rho * s_f * r_f**3 * phi_a * omega * c_f
    # eddy making of the naked hull: C_R fitted over C_B, B/d, OG/d, C_M
    f_e1 = (-0.0182 * cb + 0.0155) * (bd - 1.8) ** 3
    f_e2 = -79.414 * cb**4 + 215.695 * cb**3 - 215.883 * cb**2 + 93.894 * cb - 14.848
    b_e1 = (
        (3.98 * cb - 5.1525)
        * (-0.2 * bd + 1.6)
        * ogd
        * ((0.9717 * cb**2 - 1.55 * cb + 0.723) * ogd + 0.04567 * cb + 0.9408)
    )
    b_e2 = (0.25 * ogd + 0.95) * ogd - 219.2 * cb**3 + 443.7 * cb**2 - 283.3 * cb + 59.6
    b_e3 = -15.0 * cb * bd + 46.5 * cb + 11.2 * bd - 28.6
    c_r = (f_e1 + f_e2) * math.exp(b_e1 + b_e2 * cm**b_e3)
    e_hat = 4.0 * w_hat * phi_a / (3.0 * math.pi * cb * bd**3) * c_r
    # bilge keels (normal force and hull pressure together), fitted over their breadth and length, φ_a in degrees
    bk_hat = 0.0
    if hull.keels is not None:
        bbkb, lbkl = hull.keels.breadth / B, hull.keels.length / L
        f1 = (-0.3651 * cb + 0.3907) * (bd - 2.83) ** 2 - 2.21 * cb + 2.632
        f2 = 0.00255 * phi_deg**2 + 0.122 * phi_deg + 0.4794
        f3 = (-0.8913 * bbkb**2 - 0.0733 * bbkb) * lbkl**2 + (5.2857 * bbkb**2 - 0.01185 * bbkb + 0.00189) * lbkl
        e1 = (5.0 * bbkb + 0.3 * bd - 0.2 * lbkl + 0.00125 * phi_deg**2 - 0.0425 * phi_deg - 1.86) * ogd
        e2 = -15.0 * bbkb + 1.2 * cb - 0.1 * bd - 0.0657 * ogd**2 + 0.0586 * ogd + 1.6164
        e3 = 2.5 * ogd + 15.75
        bk_hat = f1 * f2 * f3 * math.exp(e1 + e2 * cm**e3) * w_hat
    f_hat = b_f / scale
    return {
        "friction": b_f, "eddy": e_hat * scale, "lift": 0.0, "bilge_keels": bk_hat * scale,
        "friction_hat": f_hat, "eddy_hat": e_hat, "lift_hat": 0.0, "bilge_keels_hat": bk_hat,
        "omega_hat": w_hat,
    }  # fmt: skip
