"""A monohull surface from main particulars, for the boundary-element RAO solver (issue 17, item 1).

The hull is a two-exponent family (z up, waterline at z = 0, midship at x = 0, bow at +x):

    y(x, z) = ± B/2 · (1 − |2x/L|^p) · (1 − |z/T|^q),    −L/2 ≤ x ≤ L/2,  −T ≤ z ≤ 0,

so the waterplane coefficient is C_WP = p/(p+1), the midship section coefficient C_M = q/(q+1) and the
block coefficient C_B = C_WP · C_M (each factor integrates separately); q = c/(1 − c) with c = C_B / C_WP.

The waterline exponent ``p`` comes from the two stated metacentric heights (:meth:`HullForm.from_particulars`):
both share the centre of gravity and the centre of buoyancy, so GM_L − GM_T = BM_L − BM_T =
(I_L − I_T)/∇ is a property of the waterplane alone, with (this family)

    I_L = B L³ p / (12 (p + 3)),    I_T = (2/3) (B/2)³ L Σ_k C(3,k) (−1)^k / (k p + 1),    ∇ = L B T C_B,

solved for p.  (A waterplane taken from elsewhere — e.g. C_WP = 0.80, the MSS toolbox's offshore supply
vessel model, Fossen's ``osv.m`` — would pair the stated GM_L's pitch stiffness with another hull's
pitch moments.)  The surface closes on itself at the keel line (z = −T) and at both ends (x = ±L/2).
This is a smooth stand-in for a hull whose lines are not known, not a hull design: its displaced
volume is L·B·T·C_B exactly, its waterplane area C_WP·L·B.

:func:`hull_panels` gives the starboard half (y ≥ 0) as quadrilateral panels with normals out of the
hull, longitudinally denser toward the ends (cosine spacing), vertically denser toward the waterline;
the solver mirrors it about the xz-plane.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from app.errors import BosunError

#: the default waterplane coefficient: the MSS toolbox's offshore supply vessel model (Fossen, ``osv.m``)
CWP_DEFAULT = 0.80


class HullError(BosunError):
    """Particulars from which no hull of this family can be made (one line)."""


@dataclass(frozen=True)
class HullForm:
    """The hull family's parameters (see the module docstring)."""

    lpp: float
    beam: float
    draft: float
    cb: float
    cwp: float = CWP_DEFAULT

    def __post_init__(self) -> None:
        for name in ("lpp", "beam", "draft", "cb", "cwp"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise HullError(f"hull: {name} must be a positive number, got {v}")
        if not self.cwp < 1:
            raise HullError(f"hull: the waterplane coefficient must be below 1, got {self.cwp:g}")
        if not self.cb < self.cwp:
            raise HullError(
                f"hull: the block coefficient ({self.cb:g}) must be below the waterplane coefficient ({self.cwp:g})"
            )

    @classmethod
    def from_particulars(cls, lpp: float, beam: float, draft: float, cb: float, gm_t: float, gm_l: float) -> HullForm:
        """The family's hull whose waterplane gives BM_L − BM_T = GM_L − GM_T (see the module)."""
        from scipy.optimize import brentq

        target = gm_l - gm_t
        vol = lpp * beam * draft * cb

        def gap(p: float) -> float:
            i_l = beam * lpp**3 * p / (12.0 * (p + 3.0))
            i_t = (2.0 / 3.0) * (0.5 * beam) ** 3 * lpp * sum((1, -3, 3, -1)[k] / (k * p + 1.0) for k in range(4))
            return (i_l - i_t) / vol - target

        lo, hi = 0.2, 200.0
        if not (math.isfinite(target) and gap(lo) < 0.0 < gap(hi)):
            raise HullError(
                f"hull: no waterplane of this family gives GM_L − GM_T = {target:g} m for Lpp {lpp:g} m, B {beam:g} m,"
                f" T {draft:g} m, C_B {cb:g} (possible: {gap(lo) + target:.3g} to {gap(hi) + target:.3g} m)"
            )
        p = brentq(gap, lo, hi, xtol=1e-12)
        cwp = p / (p + 1.0)
        if not cb < cwp:
            raise HullError(f"hull: the waterplane from GM_L − GM_T (C_WP {cwp:.3f}) is not fuller than C_B {cb:g}")
        return cls(lpp, beam, draft, cb, cwp)

    @property
    def p(self) -> float:
        """Waterline exponent: C_WP = p/(p+1)."""
        return self.cwp / (1.0 - self.cwp)

    @property
    def q(self) -> float:
        """Section exponent: C_M = q/(q+1) = C_B/C_WP."""
        c = self.cb / self.cwp
        return c / (1.0 - c)

    @property
    def volume(self) -> float:
        return self.lpp * self.beam * self.draft * self.cb

    @property
    def waterplane_area(self) -> float:
        return self.cwp * self.lpp * self.beam

    def half_breadth(self, x: NDArray[np.float64], z: NDArray[np.float64]) -> NDArray[np.float64]:
        xi = np.clip(np.abs(2.0 * np.asarray(x) / self.lpp), 0.0, 1.0)
        zeta = np.clip(np.abs(np.asarray(z) / self.draft), 0.0, 1.0)
        return 0.5 * self.beam * (1.0 - xi**self.p) * (1.0 - zeta**self.q)


def hull_panels(form: HullForm, nx: int = 40, nz: int = 8) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The starboard half-hull (y ≥ 0) as ``nx`` × ``nz`` quadrilaterals: vertices (n, 3) and faces (m, 4),
    normals pointing out of the hull into the water.  Longitudinal stations are cosine-spaced (denser at
    the ends, where the hull turns), vertical ones denser toward the waterline."""
    if nx < 4 or nz < 2:
        raise HullError(f"hull mesh: at least 4 × 2 panels, got {nx} × {nz}")
    s = np.linspace(0.0, np.pi, nx + 1)
    x = -0.5 * form.lpp * np.cos(s)  # stern (−L/2) to bow (+L/2)
    t = np.linspace(0.0, 1.0, nz + 1)
    z = -form.draft * (1.0 - (1.0 - t) ** 1.5)  # keel (−T) to waterline (0), denser at the top
    X, Z = np.meshgrid(x, z, indexing="ij")
    Y = form.half_breadth(X, Z)
    vertices = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    idx = np.arange(X.size).reshape(X.shape)
    a, b = idx[:-1, :-1], idx[1:, :-1]  # (x_i, z_j), (x_i+1, z_j)
    c, d = idx[1:, 1:], idx[:-1, 1:]  # (x_i+1, z_j+1), (x_i, z_j+1)
    faces = np.stack([a, b, c, d], axis=-1).reshape(-1, 4)  # counter-clockwise seen from the water: normals out
    return vertices, faces
