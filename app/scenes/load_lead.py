"""The load lead: where to put the point a load hangs from so the load goes where it should (issue 30).

Compensation that holds the crane's tip still, or on a moving deck's spot, leaves the load on its wire a pendulum
driven by what the tip does.  Linearised (the Motion-Lab paper's eqs. 29–30, :mod:`app.models.pendulum`), the load
below a point x_t obeys L α̈ = ẍ_t − (g − z̈) α with the load at x_L = x_t − L α, so a load meant to move along
x_L(t) needs the point at x_t = x_L + L / (g − z̈) · ẍ_L (:func:`app.models.pendulum.suspension_lead`): the load is
the pendulum's flat output (Fliess, Lévine and Rouchon, "Flatness and defect of nonlinear systems", Int. J.
Control 61(6), 1995, the crane as their example).  Two accelerations go in:

* the **target's**: a landing spot on a second vessel's deck (its MRU's acceleration) — part of compensation: the
  sea moves the target, the machine moves the tip so the load moves with it (without it the 10 m pendulum, 6.3 s,
  driven by the deck's 9 s motion, overshoots the deck's sway by ω²/(ω₀² − ω²), nearly 100 %);
* the **operator's** (``shape``, the anti-swing mode's): the commanded path's acceleration, first smoothed by a
  first-order lag of ``tau`` (the operator's ramps step the acceleration, and a step in the lead is a step in the
  tip's target the head cannot take), as the field's anti-sway systems shape the operator's command.

The swing estimator and anti-swing law (:class:`app.scenes.crane_load.CraneSwingControl`) get the planned motion
as a reference, (f, ẍ_ref): the swing about it obeys the same pendulum (L δ̈ = (ẍ_t − ẍ_ref) − g δ), with ẍ_ref =
ẍ_L + f̈, f̈ the lead's second difference, so they damp the swing, not the lead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from app.models.pendulum import suspension_lead_xy
from app.scenes.tac_kernels import ease_in

__all__ = ["CRANE_LEAD_MAX", "SHAPE_TAU", "LoadLead"]

#: m: the crane's lead at most (assumed: within the crane head's reach around the crane's tip; the 10 m wire under a
#: deck accelerating 1 m/s² asks for 1.02 m)
CRANE_LEAD_MAX = 1.0

#: s: the operator's acceleration smoothed by this lag before it leads the tip (a sweep of 0.1–1.0 s on the crane's
#: platform transfer, Hs 3 m, seeds 1–2: anti-swing path error 0.063, 0.035, 0.030, 0.030, 0.034 m for 0.1, 0.2,
#: 0.4, 0.6, 1.0 s; residual swing 0.53, 0.30, 0.30, 0.32, 0.33°)
SHAPE_TAU = 0.4


@dataclass
class LoadLead:
    """The lead of one hanging load, stepped every ``dt`` (module text): :meth:`step` gives the tip's lead f (3,)
    and the swing law's reference.  ``cap``: f's horizontal length at most [m]; ``fade``: f faded in over this
    long from the first step [s] (the quintic of H108: the tip's target does not step when compensation starts);
    ``shape``: the operator's move led too.  Frames: any with z down (the crane's {n}, the lab's {n2})."""

    dt: float
    cap: float
    fade: float
    shape: bool = False
    tau: float = SHAPE_TAU
    t: float = 0.0
    _a_cmd: tuple = (0.0, 0.0, 0.0)  # the operator's acceleration through the lag
    _f: tuple = ((0.0, 0.0), (0.0, 0.0))  # f (x, y) a step ago and now

    def step(
        self, a_target: NDArray[np.float64], a_cmd: NDArray[np.float64], length: float, dt: float | None = None
    ) -> tuple[NDArray[np.float64], tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """One step: the target's acceleration ``a_target`` and the operator's commanded acceleration ``a_cmd``
        (3 each, m/s²; ``a_cmd`` ignored unless ``shape``), the wire's length [m]; ``dt`` this step's length when
        it is not ``self.dt`` (an engine's tick).  Returns (f, (f, ẍ_ref))."""
        if dt is not None:
            self.dt = dt
        dt = self.dt
        self.t += dt
        ax, ay, az = float(a_target[0]), float(a_target[1]), float(a_target[2])
        if self.shape:  # plain numbers: this runs every step of a transfer
            k = min(1.0, dt / self.tau)
            cx, cy, cz = self._a_cmd
            cx, cy, cz = (
                cx + (float(a_cmd[0]) - cx) * k,
                cy + (float(a_cmd[1]) - cy) * k,
                cz + (float(a_cmd[2]) - cz) * k,
            )
            self._a_cmd = (cx, cy, cz)
            ax, ay, az = ax + cx, ay + cy, az + cz
        fx, fy = suspension_lead_xy(ax, ay, az, length, self.cap)
        if self.t < self.fade:
            gain = ease_in(self.t / self.fade)[0]
            fx, fy = fx * gain, fy * gain
        (x2, y2), (x1, y1) = self._f  # f two steps and one step ago: f̈ the second difference
        self._f = ((x1, y1), (fx, fy))
        f = np.array((fx, fy, 0.0))
        a_ref = np.array((ax + (fx - 2.0 * x1 + x2) / (dt * dt), ay + (fy - 2.0 * y1 + y2) / (dt * dt), 0.0))
        return f, (f, a_ref)

    @property
    def rate(self) -> NDArray[np.float64]:
        """ḟ over the last step (the tip's feed-forward rate)."""
        (x1, y1), (x0, y0) = self._f
        return np.array(((x0 - x1) / self.dt, (y0 - y1) / self.dt, 0.0))
