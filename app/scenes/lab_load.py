"""The Motion-Lab's load on its wire, with EM1500's deck to land on (issue 30, items 4–5).

The lab's own load model (:class:`app.sim.motionlab.Pendulum`, eqs. 29–30) is an inextensible pendulum: it cannot
go slack, land or snatch.  For a landing the load is the crane's (:data:`app.sim.load.LOAD`, reused: a point mass
on an elastic wire that pulls only while taut, with a spring–damper deck and friction), hung from the Comau's tool
point on the lab winch's wire, and the lab's pendulum becomes what the lab's controllers see of it: after each step
its angles and rates are set from the wire (:meth:`LabLoad.sync`), as a wire-angle sensor would report them; the
winch's heave compensation (eq. 58 at its capture) and the anti-swing estimator (:mod:`app.scenarios.swing`) read
them there.  Frames: the load lives in {d} axes (the world {g} turned half a turn about x: z down, the frame of
the lab's pendulum), so gravity is +z as in the crane's {n}.

The deck is EM1500's top plate, z = 0 of its body frame {b2} (z down; the engine's *Load below the EM1500 deck*
uses the same plane): a disc of the platform's upper joints' radius (0.80 m).  Over it, the load's deck record is
the plane through the deck point under the load, moving with that point of the platform over the step (its
velocity from the platform's pose at the step's start and end), with the plate's up normal.

Assumed values (:data:`LAB_LOAD`), as the crane's are in :mod:`app.sim.load`: the payload's 5 kg and damping
0.02 /s are the lab file's; the wire is taken as a 3 mm steel wire rope with the crane's fill and rope modulus
(metallic area 0.58·π·(3 mm)²/4 = 4.1 mm², E ≈ 100 kN/mm², Feyrer, *Wire Ropes*, §3.3): EA = 4.1·10⁵ N; the
deck is a rubber-padded steel plate on which the 5 kg load sinks 1 mm (k_c = 5·10⁴ N/m), critically damped, μ 0.3.
The wire's axial mode (√(EA/(L m)) ≈ 210 rad/s at 1.8 m) asks for sub-steps of 0.5 ms: ten in the lab's 5 ms step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from app.models.pendulum import G
from app.sim.load import LOAD, LoadSpec, hanging, no_deck
from app.sim.motionlab import R_G_D

__all__ = ["LAB_LOAD", "LabLoad"]

#: the lab's load, wire and deck (assumed values: module text)
LAB_LOAD = LoadSpec(
    mass=5.0, ea=4.1e5, wire_damping=0.05, air_damping=0.02, contact_stiffness=5.0e4, contact_damping=1.0,
    friction=0.3, slip_speed=0.01, substeps=10,
)  # fmt: skip


@dataclass
class LabLoad:
    """The load under a :class:`~app.scenes.lab.MotionLab`'s tool point, stepped after each lab step (:meth:`step`).

    After each step: ``state`` (r, v in {d} axes), ``tension``, ``contact_force``, ``gap`` (the load's height
    above EM1500's deck along its normal; inf while not over it), ``deck_v`` and ``n_up`` (the deck's velocity
    under the load and its up normal, in {d} axes): the interface :class:`app.scenes.crane_load.LandingWatch`
    reads."""

    lab: object
    spec: LoadSpec = LAB_LOAD
    use_kernels: bool | None = None
    state: tuple = field(init=False)

    def __post_init__(self) -> None:
        lab = self.lab
        lab.pendulum_is_load = False  # the pendulum reports this load's wire now (sync): not a model of its own
        lay = lab.layout  # the payload's mass and damping are the lab file's
        self.spec = replace(self.spec, mass=float(lay.payload_mass), air_damping=float(lay.payload_damping))
        self._p = self.spec.record(G)
        self._s = R_G_D.T @ lab.p_t_g
        self._L = float(lab.winch.length)
        self.state = hanging(self._s, self._L, self.spec, G)
        self.tension = self.static_tension()
        self.contact_force = 0.0
        self.gap = math.inf
        self.deck_v = np.zeros(3)
        self.n_up = np.array([0.0, 0.0, -1.0])
        self.radius = float(np.max(np.linalg.norm(lab.models[1].b_b[:, :2], axis=1)))
        self._H2 = lab.platform_pose(1)

    def static_tension(self) -> float:
        return self.spec.mass * G

    @property
    def length(self) -> float:
        return float(self.lab.winch.length)

    def position_g(self) -> NDArray[np.float64]:
        """The load in the world {g}."""
        return R_G_D @ self.state[0]

    def in_b2(self, H2: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """The load in EM1500's body frame {b2} (z down: z < 0 above the deck)."""
        H = self.lab.platform_pose(1) if H2 is None else H2
        return H[:3, :3].T @ (self.position_g() - H[:3, 3])

    def wire(self) -> tuple[NDArray[np.float64], float]:
        """The wire from the tool point to the load in {d} axes, and its length."""
        e = self.state[0] - self._s
        return e, math.sqrt(float(e @ e))

    def _deck(self, H0: NDArray[np.float64], H1: NDArray[np.float64], dt: float) -> tuple:
        """The deck record over the step: the deck point under the load (at the step's start), moved with EM1500."""
        p_b2 = H0[:3, :3].T @ (R_G_D @ self.state[0] - H0[:3, 3])
        if math.hypot(p_b2[0], p_b2[1]) > self.radius:
            return no_deck()
        m = np.array([p_b2[0], p_b2[1], 0.0])
        d0, d1 = (R_G_D.T @ (H[:3, :3] @ m + H[:3, 3]) for H in (H0, H1))
        n_up = R_G_D.T @ (-H1[:3, 2])
        return (True, d0, n_up, (d1 - d0) / dt)

    def step(self, dt: float) -> None:
        """The load over the lab's last step (the tool point and the wire's length moved from where they were), then
        the lab's pendulum set from it (:meth:`sync`)."""
        lab = self.lab
        s1, L1 = R_G_D.T @ lab.p_t_g, float(lab.winch.length)
        H1 = lab.platform_pose(1)
        deck = self._deck(self._H2, H1, dt)
        self.deck_v = deck[3] if deck[0] else np.zeros(3)
        self.n_up = deck[2]
        u = (self._s, s1, self._L, L1, deck)
        self.state, (T, Fn, gap) = LOAD.step(self.state, u, self._p, dt, self.use_kernels)
        self.tension, self.contact_force = float(T), float(Fn)
        self.gap = float(gap) if deck[0] else math.inf
        self._s, self._L, self._H2 = s1, L1, H1
        self.sync()

    def sync(self) -> None:
        """The lab's pendulum as a wire-angle sensor sees the load: α = −asin(u_x), β = atan2(u_y, u_z) of the
        wire's unit vector u in {d} (eq. 23), and their rates from the load's velocity relative to the tool."""
        pd, lab = self.lab.pendulum, self.lab
        e, ell = self.wire()
        u = e / ell
        ed = self.state[1] - R_G_D.T @ lab.v_t_g
        ud = (ed - u * float(u @ ed)) / ell
        ca = math.sqrt(max(1e-12, 1.0 - u[0] * u[0]))
        pd.alpha = -math.asin(max(-1.0, min(1.0, float(u[0]))))
        pd.beta = math.atan2(float(u[1]), float(u[2]))
        pd.alpha_dot = -float(ud[0]) / ca
        pd.beta_dot = float(u[2] * ud[1] - u[1] * ud[2]) / max(1e-12, float(u[1] ** 2 + u[2] ** 2))

    def kick(self, alpha: float, beta: float, alpha_dot: float = 0.0, beta_dot: float = 0.0) -> None:
        """Put the load at the swing angles (and rates) of eq. (23) from the tool point, on its wire as stretched
        now (a swing to start from: tests, and a training kick); the lab's pendulum reports it at once."""
        _, ell = self.wire()
        sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
        u = np.array([-sa, ca * sb, ca * cb])
        u_dot = np.array(
            [-alpha_dot * ca, -alpha_dot * sa * sb + beta_dot * ca * cb, -alpha_dot * sa * cb - beta_dot * ca * sb]
        )
        v_tool = R_G_D.T @ self.lab.v_t_g
        self.state = (self._s + ell * u, v_tool + ell * u_dot)
        self.sync()
