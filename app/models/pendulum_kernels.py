"""The load's swing (Motion-Lab paper eqs. 29–30, :mod:`app.models.pendulum`) compiled: its derivative and one
RK4 step.  On the models floor because both the plant (the load, :data:`app.sim.motionlab.PENDULUM`) and the
swing estimator (:mod:`app.control.antisway_kernels`) integrate it.  Same scheme as :mod:`app.models.kernels`."""

from __future__ import annotations

import math

from app.models.kernels import _jit

__all__ = ["_pendulum_derivative", "pendulum_step"]


@_jit
def _pendulum_derivative(x, acc, L, Ld, c, g):
    """Eqs. (29)–(30) / (60)–(61) with the z̈ sign of a z-down frame and damping −c φ̇
    (:func:`app.models.pendulum.swing_derivative`): x = (α, β, α̇, β̇), acc = (ẍ, ÿ, z̈) of the tool in {d}."""
    a, b, ad, bd = x
    ax, ay, az = acc
    sa, ca, sb, cb = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
    add = (ax * ca + ay * sa * sb + az * sa * cb - g * sa * cb - 2 * Ld * ad - L * bd * bd * sa * ca) / L - c * ad
    ca_safe = ca if abs(ca) > 1e-6 else math.copysign(1e-6, ca)
    bdd = (-ay * cb + az * sb - g * sb - 2 * Ld * bd * ca + 2 * L * ad * bd * sa) / (L * ca_safe) - c * bd
    return ad, bd, add, bdd


@_jit
def pendulum_step(x, acc, L, Ld, c, g, dt):
    """One RK4 step of the load (eqs. 29–30 / 60–61, :meth:`Pendulum.step`): x = (α, β, α̇, β̇), the tool
    acceleration ``acc`` = (ẍ, ÿ, z̈) in {d} held, wire length L + Ld·s: (α, β, α̇, β̇)."""
    x0, x1, x2, x3 = x
    h = 0.5 * dt
    k10, k11, k12, k13 = _pendulum_derivative(x, acc, L, Ld, c, g)
    Lh = L + h * Ld
    k20, k21, k22, k23 = _pendulum_derivative(
        (x0 + h * k10, x1 + h * k11, x2 + h * k12, x3 + h * k13), acc, Lh, Ld, c, g
    )  # fmt: skip
    k30, k31, k32, k33 = _pendulum_derivative(
        (x0 + h * k20, x1 + h * k21, x2 + h * k22, x3 + h * k23), acc, Lh, Ld, c, g
    )  # fmt: skip
    k40, k41, k42, k43 = _pendulum_derivative(
        (x0 + dt * k30, x1 + dt * k31, x2 + dt * k32, x3 + dt * k33), acc, L + dt * Ld, Ld, c, g
    )  # fmt: skip
    f = dt / 6.0
    return (
        x0 + f * (k10 + 2 * k20 + 2 * k30 + k40),
        x1 + f * (k11 + 2 * k21 + 2 * k31 + k41),
        x2 + f * (k12 + 2 * k22 + 2 * k32 + k42),
        x3 + f * (k13 + 2 * k23 + 2 * k33 + k43),
    )
