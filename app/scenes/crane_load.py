"""A suspended load on the offshore crane (issue 30, item 3): a wire from the Delta head's TCP over a winch, the hook
and payload as a 3-D pendulum driven by the TCP's acceleration (Motion-Lab paper eqs. 29–30, generalised to any
suspension point), and the winch's active heave compensation beside the head.

The blocks are the lab's, reused (not copied): the drum :data:`app.sim.motionlab.WINCH_DRUM` (the wire length
following its reference within the winch's length, speed and acceleration limits) and the load
:data:`app.sim.motionlab.PENDULUM`; the controller is :data:`app.control.tac.CRANE_AHC`.  Frames: {n} is NED
(z down), the pendulum's {d} frame is any z-down frame, so the TCP's acceleration in {n} drives it as it is.  The
load hangs from the TCP and does not act back on the crane or the head (the crane-head paper's model: the load's
inertia against the crane's is left out; the paper asks for the load to be added, not for the crane to feel it).

Assumed values (stated, not from a source): the winch pays out at up to 1.5 m/s with 2 m/s², the wire 3–40 m,
10 m at the start; the load's damping 0.02 1/s (air drag of a compact payload, small); its mass 5 t (for the
tension; the swing does not depend on it).  The acceleration matters: a heave of 1 m at 9 s asks 0.49 m/s² of the
drum, and at 0.5 m/s² the drum fell behind by 1.3 m (tests/test_crane_load.py measures 7 mm at 2 m/s²).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from app.control.tac import CRANE_AHC
from app.models.pendulum import G, swing_direction
from app.sim.motionlab import PENDULUM, WINCH_DRUM

__all__ = ["CraneLoad", "WinchSpec"]


@dataclass(frozen=True)
class WinchSpec:
    """The crane winch and its load (assumed values, module text)."""

    min_length: float = 3.0
    max_length: float = 40.0
    start_length: float = 10.0
    speed: float = 1.5  # m/s
    accel: float = 2.0  # m/s²
    tau: float = 0.05  # s: the drum's servo
    mass: float = 5000.0  # kg
    damping: float = 0.02  # 1/s


@dataclass
class CraneLoad:
    """The wire, the winch and the hanging load under the crane head's TCP, stepped with the scene's TCP samples.

    :meth:`step` takes the TCP's position in {n} at each simulation step; the TCP's velocity and acceleration come
    from its samples (backward differences: the load sees the acceleration of the step just taken).  ``ahc``
    switches the winch's heave compensation; ``speed_command`` is the operator's winch axis (positive pays out,
    lowering the hook)."""

    spec: WinchSpec = field(default_factory=WinchSpec)
    ahc: bool = True
    speed_command: float = 0.0
    use_kernels: bool | None = None

    def __post_init__(self) -> None:
        s = self.spec
        self.drum = (np.array([s.start_length]), np.zeros(1), np.zeros(1), np.zeros(4, dtype=bool))
        self._drum_p = tuple(np.array([v]) for v in (s.min_length, s.max_length, s.speed, s.accel)) + (s.tau,)
        self.swing = (0.0, 0.0, 0.0, 0.0)  # α, β, α̇, β̇ in {n} (z down)
        self.law = (0.0, False)  # the hook's height target in {n}, whether set
        self._tcp: list[NDArray[np.float64]] = []  # the last three TCP positions
        self.tcp_v = np.zeros(3)
        self.tcp_a = np.zeros(3)

    @property
    def length(self) -> float:
        return float(self.drum[0][0])

    @property
    def length_rate(self) -> float:
        return float(self.drum[1][0])

    def hook(self, tcp_n: NDArray[np.float64]) -> NDArray[np.float64]:
        """The hook (the load) in {n}: L along the wire below the TCP (eq. 23)."""
        return np.asarray(tcp_n, dtype=float) + self.length * swing_direction(self.swing[0], self.swing[1])

    def swing_angle(self) -> float:
        """The wire's angle from the vertical [rad]."""
        a, b = self.swing[0], self.swing[1]
        return float(np.arccos(np.clip(np.cos(a) * np.cos(b), -1.0, 1.0)))

    def tension(self) -> float:
        """The wire's tension [N]: the load's mass times the specific force along the wire, m (g ŵ_z − a_tcp·ŵ +
        L φ̇² − L̈) with φ̇² the wire's angular rate squared (the pendulum's centripetal term)."""
        a, b, ad, bd = self.swing
        w = swing_direction(a, b)
        rate2 = ad * ad + (np.cos(a) * bd) ** 2
        along = G * w[2] - float(self.tcp_a @ w) + self.length * rate2 - float(self.drum[2][0])
        return self.spec.mass * along

    def static_tension(self) -> float:
        return self.spec.mass * G

    def step(self, tcp_n: NDArray[np.float64], dt: float) -> None:
        """One step of ``dt`` with the TCP at ``tcp_n`` (in {n}) at its end: the winch law, the drum, the load."""
        p = np.asarray(tcp_n, dtype=float)
        self._tcp = [*self._tcp[-2:], p.copy()]
        if len(self._tcp) >= 2:
            self.tcp_v = (self._tcp[-1] - self._tcp[-2]) / dt
        if len(self._tcp) == 3:
            self.tcp_a = (self._tcp[-1] - 2.0 * self._tcp[-2] + self._tcp[-3]) / (dt * dt)
        u = (self.ahc, self.speed_command, self.length, (float(p[2]), float(self.tcp_v[2])))
        self.law, (L_ref, Ld_ref) = CRANE_AHC.step(self.law, u, (self.spec.speed,), dt, use_kernels=False)
        L0, Ld0 = self.length, self.length_rate
        self.drum, _ = WINCH_DRUM.step(
            self.drum, (np.array([L_ref]), np.array([Ld_ref])), self._drum_p, dt, self.use_kernels
        )
        Ld = (self.length - L0) / dt if dt > 0 else Ld0
        u_load = (np.ascontiguousarray(self.tcp_a), L0, Ld)
        self.swing, _ = PENDULUM.step(self.swing, u_load, (self.spec.damping, G), dt, self.use_kernels)
