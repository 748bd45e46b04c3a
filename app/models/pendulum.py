"""The suspended load as a model: the 2-DOF spherical pendulum of Motion-Lab paper eqs. (23)–(30).

Pure functions shared by the plant (:class:`app.sim.motionlab.Pendulum`, which integrates them) and the
controllers that must predict it (:mod:`app.control.antisway`: the swing estimator and the anti-swing
law), so neither imports the other.

Frame {d}: the world {g} turned half a turn about x (z down, gravity along +z_d), where eq. (23) puts
the load below the tool at rest.  State x = (α, β, α̇, β̇): α about ^φβy, β about x (Fig. 16); wire
direction (−sα, cα sβ, cα cβ).  The equations are eqs. (29)–(30) derived again from the Lagrangian
(25)–(28) in this z-down frame (the printed z̈ terms have the wrong sign for it; see
app/sim/motionlab.py) with a viscous damping term −c φ̇:

    L α̈ = ẍ cα + ÿ sα sβ + z̈ sα cβ − g sα cβ − 2 L̇ α̇ − L β̇² sα cα − c L α̇
    L cα β̈ = −ÿ cβ + z̈ sβ − g sβ − 2 L̇ β̇ cα + 2 L α̇ β̇ sα − c L cα β̇

Linearised about the hanging rest (α = β = 0, L̇ = 0, z̈ ≪ g) the two swings decouple:
L α̈ = ẍ − g α − c L α̇ and L β̈ = −ÿ − g β − c L β̇.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

G = 9.81

__all__ = ["G", "suspension_lead", "suspension_lead_xy", "swing_derivative", "swing_direction", "swing_rk4"]


def swing_derivative(
    x: NDArray[np.float64], a_t_d: NDArray[np.float64], L: float, Ld: float, c: float = 0.0, g: float = G
) -> NDArray[np.float64]:
    """ẋ of the load for state x = (α, β, α̇, β̇), tool acceleration a_t^d (3,) in {d}, wire length L [m]
    and its rate L̇ [m/s], damping c [1/s] (eqs. 29–30 as above)."""
    a, b, ad, bd = x
    sa, ca, sb, cb = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
    ax, ay, az = a_t_d
    add = (ax * ca + ay * sa * sb + az * sa * cb - g * sa * cb - 2 * Ld * ad - L * bd * bd * sa * ca) / L - c * ad
    ca_safe = ca if abs(ca) > 1e-6 else math.copysign(1e-6, ca)
    bdd = (-ay * cb + az * sb - g * sb - 2 * Ld * bd * ca + 2 * L * ad * bd * sa) / (L * ca_safe) - c * bd
    return np.array([ad, bd, add, bdd])


def swing_rk4(
    x: NDArray[np.float64], dt: float, a_t_d: NDArray[np.float64], L: float, Ld: float, c: float = 0.0, g: float = G
) -> NDArray[np.float64]:
    """x after dt by classical RK4, the tool acceleration held and the wire length L + L̇ s over the step."""
    k1 = swing_derivative(x, a_t_d, L, Ld, c, g)
    k2 = swing_derivative(x + 0.5 * dt * k1, a_t_d, L + 0.5 * dt * Ld, Ld, c, g)
    k3 = swing_derivative(x + 0.5 * dt * k2, a_t_d, L + 0.5 * dt * Ld, Ld, c, g)
    k4 = swing_derivative(x + dt * k3, a_t_d, L + dt * Ld, Ld, c, g)
    return x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def swing_direction(alpha: float, beta: float) -> NDArray[np.float64]:
    """Unit wire vector from the tool to the load in {d}: (−sα, cα sβ, cα cβ), eq. (23)."""
    sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
    return np.array([-sa, ca * sb, ca * cb])


def suspension_lead(accel: NDArray[np.float64], length: float, cap: float = math.inf) -> NDArray[np.float64]:
    """Where the point a load hangs from must be, relative to the load, for the load to move with the horizontal
    acceleration of ``accel`` (3,) [m/s²] in a z-down frame (the load lead of issue 30's compensated lift).

    The linearised swing above (eqs. 29–30 with the tool's vertical acceleration kept, L α̈ = ẍ_t − (g − z̈) α and
    the load at x_L = x_t − L α) carries the load with the point only when x_t = x_L + L / (g − z̈) · ẍ_L: a load
    that is to move with a deck accelerating at ẍ must hang that far behind the point.  Returns (f_x, f_y, 0),
    its horizontal length capped at ``cap`` [m]; g − z̈ is kept above g / 2 (a point falling at half g or more
    gives no lead worth having)."""
    fx, fy = suspension_lead_xy(float(accel[0]), float(accel[1]), float(accel[2]), length, cap)
    return np.array([fx, fy, 0.0])


def suspension_lead_xy(ax: float, ay: float, az: float, length: float, cap: float = math.inf) -> tuple[float, float]:
    """:func:`suspension_lead` in plain numbers (a step's hot path): (f_x, f_y)."""
    k = length / max(G - az, 0.5 * G)
    fx, fy = ax * k, ay * k
    n = math.hypot(fx, fy)
    if n > cap:
        fx, fy = fx * cap / n, fy * cap / n
    return fx, fy
