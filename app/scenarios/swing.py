"""The swing estimator and the anti-swing law on the simulated Motion-Lab (issue 16, item 4).

:class:`SwingControl` wires the estimator and the law of :mod:`app.control.antisway` to a
:class:`~app.scenes.lab.MotionLab`: after every step it feeds the EKF the tool acceleration the lab
knows (eq. 57 from the Comau's joints and the platform, with the noise ``sigma_accel``), then a wire
measurement (the true swing plus noise: a wire-angle sensor, or the load's position from a tracker),
and sets the law's offset for the next step (:meth:`MotionLab.set_tool_offset`, in {n1}).  The true
swing is used only for the measurement's truth and for scoring.

The law acts on the swing about its *quasi-static tilt*: while VVMC holds the tool on the moving work
point, the tool accelerates with EM1500 and the load leans by φ_qs ≈ (ẍ, −ÿ)/g in {d} (the linearised
eqs. 29–30 at ω ≪ √(g/L)).  That tilt is what compensation costs: removing it means moving the tool
off the work point by about L·φ_qs.  So the estimate minus the tilt of the compensation's own tool
acceleration (the measured acceleration minus the law's, low-passed with ``tilt_tau``) goes to the law,
which then damps the pendulum's own oscillation and leaves the forced lean alone.  (Fed the whole
swing, the law chased the forced lean: at Hs 2 m it moved the tool 20 mm rms off the work point and
the swing did not drop.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from app.control.antisway import SWING_CONTROL, AntiSwing, AntiSwingDesign, SwingEkf
from app.models.kernels import ENABLED
from app.scenes.lab import MotionLab
from app.sim.motionlab import R_G_D

__all__ = ["SwingControl"]


@dataclass
class SwingControl:
    """The swing estimator and the anti-swing law on a lab, stepped after each :meth:`MotionLab.step`.

    ``active`` False runs the estimator only (the law's offset returns to zero)."""

    lab: MotionLab
    rng: np.random.Generator
    design: AntiSwingDesign = field(default_factory=AntiSwingDesign)
    measurement: str = "angles"
    sigma_accel: float = 0.05  # m/s²: the tool acceleration the lab knows (joints + MRU), per axis
    sigma_angle: float = math.radians(0.5)  # rad: a wire-angle sensor (assumed)
    sigma_pos: float = 0.005  # m: the load's position from the tracker (assumed)
    tilt_tau: float = 0.2  # s: low-pass of the quasi-static tilt (assumed; well below the wave periods)
    active: bool = True
    use_kernels: bool = field(default=ENABLED, repr=False)
    ekf: SwingEkf = field(init=False)
    law: AntiSwing = field(init=False)

    def __post_init__(self) -> None:
        pd = self.lab.pendulum
        self.ekf = SwingEkf(
            c=pd.damping, g=pd.g, sigma_accel=self.sigma_accel, measurement=self.measurement,
            sigma_angle=self.sigma_angle, sigma_pos=self.sigma_pos,
        )  # fmt: skip
        self.law = AntiSwing(design=self.design, active=self.active)
        self.R_n1_d = self.lab.T_n1_g[:3, :3] @ R_G_D
        self._L_prev = self.lab.winch.length
        self.tilt = np.zeros(2)  # the quasi-static tilt (α, β) of the compensation's tool motion
        self.tilt_rate = np.zeros(2)
        self._record = (self.ekf.record(), self.law.record(), float(pd.g), float(self.tilt_tau))

    def reset(self) -> None:
        """Estimator back to "no swing", the law's offset to zero (call at rest)."""
        self.ekf.reset()
        self.law.reset()
        self.lab.set_tool_offset(np.zeros(3), np.zeros(3))
        self._L_prev = self.lab.winch.length
        self.tilt[:], self.tilt_rate[:] = 0.0, 0.0

    def truth(self) -> NDArray[np.float64]:
        pd = self.lab.pendulum
        return np.array([pd.alpha, pd.beta, pd.alpha_dot, pd.beta_dot])

    def step(self, dt: float, in_play: bool = True) -> None:
        """Estimate with what the step just taken showed; set the offset for the next step (one step of
        :data:`~app.control.antisway.SWING_CONTROL`, compiled unless ``use_kernels`` is False).  ``in_play`` False
        (the load landed, or its wire slack: the wire's angle is no swing) rests the law as ``active`` False does,
        without changing ``active`` (the operator's choice)."""
        lab, pd = self.lab, self.lab.pendulum
        L, Ld = lab.winch.length, lab.winch.speed
        a_d = R_G_D.T @ lab.a_t_g + self.rng.normal(0.0, self.sigma_accel, 3)
        ref = lab.lead_ref_d if lab.comau_mode == "motion_comp" else None
        if ref is not None:  # the tool leads the load (app.scenes.load_lead): the swing about that plan
            a_d = a_d - ref[1]
        if self.measurement == "angles":
            if ref is None:
                alpha, beta = pd.alpha, pd.beta
            else:
                e = L * pd.direction() + ref[0]
                ell = float(np.sqrt(e @ e))
                alpha, beta = -math.asin(min(1.0, max(-1.0, e[0] / ell))), math.atan2(e[1], e[2])
            z = np.array([alpha, beta]) + self.rng.normal(0.0, self.sigma_angle, 2)
        else:
            z = L * pd.direction() + self.rng.normal(0.0, self.sigma_pos, 3)
        ekf, law = self.ekf, self.law
        on = bool(self.active and in_play)
        law.active = on
        x = (ekf.x, ekf.P, self.tilt, self.tilt_rate, law.p, law.v, law.a, self._L_prev)
        x, (p_d, v_d, law.saturated, ekf.innovation, nis) = SWING_CONTROL.step(
            x, (a_d, z, float(L), float(Ld), on), self._record, dt, self.use_kernels
        )
        ekf.x, ekf.P, self.tilt, self.tilt_rate, law.p, law.v, law.a, self._L_prev = x
        ekf.nis = float(nis)
        lab.set_tool_offset(self.R_n1_d @ p_d, self.R_n1_d @ v_d)
