"""Peer IK solvers on ``bosun bench ik``'s targets: robotics-toolbox-python and ikpy (extra ``bench``).

Each library robot is handed to the peers as the standard-DH chain of its *links*: link variable
u = u₀ + M q (θ for a revolute link, d for a prismatic one; M holds the joint signs and couplings,
:class:`~app.models.serial.SerialRobot`), with the robot's base and tool transforms.  A peer solves
for u; Bosun maps it back to joints (q = M⁺(u − u₀); exact where M is square, as in every library
robot) and judges it exactly as it judges its own solvers: the tool position from Bosun's forward
kinematics within 1 mm of the target, every joint inside its limits.  The peers see box limits on
u: the joint limits mapped through M (for a coupled arm, the Comau's parallelogram, the box around
the true limits, so a peer may return a pose outside them: it then fails, as ours would).

Peers, position only (the orientation masked out), residual tolerance about 0.05 mm:
``rtb ik_LM`` (the toolbox's C++ Levenberg–Marquardt, Chan's damping), ``rtb ikine_LM`` (its
Python implementation of the same), ``ikpy`` (scipy least squares).  Cold targets start from
Bosun's default start, warm ones from the previous solution, as for Bosun's solvers.
"""

from __future__ import annotations

import importlib.util
import time
import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

RTB_TOL = 1e-9  # ½‖e‖² < 1e-9: ‖e‖ < 0.045 mm (Bosun's own test is 0.1 mm)


def available() -> dict[str, bool]:
    """Which peer libraries are installed (``pip install -e '.[bench]'``)."""
    rtb = importlib.util.find_spec("roboticstoolbox") is not None
    ikpy = importlib.util.find_spec("ikpy") is not None
    return {"rtb ik_LM": rtb, "rtb ikine_LM": rtb, "ikpy": ikpy}


class LinkChain:
    """A serial robot as its chain of driven link variables u = u₀ + M q, with box limits on u.

    Links no joint drives are constant transforms for the peers."""

    def __init__(self, robot) -> None:
        self.robot = robot
        self.revolute = np.array([link.kind != "prismatic" for link in robot.links])
        M_all = np.where(self.revolute[:, None], robot._M_theta, robot._M_d)
        self.driven = np.any(M_all != 0.0, axis=1)
        self.u0 = np.where(self.revolute, robot._theta0, robot._d0)[self.driven]
        self.M = M_all[self.driven]
        self.M_pinv = np.linalg.pinv(self.M)
        lo = self.M.clip(min=0) @ robot.lower + self.M.clip(max=0) @ robot.upper
        hi = self.M.clip(min=0) @ robot.upper + self.M.clip(max=0) @ robot.lower
        self.lower, self.upper = self.u0 + lo, self.u0 + hi

    def u_of(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.u0 + self.M @ q

    def q_of(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.M_pinv @ (np.asarray(u, dtype=float) - self.u0)

    def steps(self):
        """Per DH row: (variable: 'theta' | 'd' | None, θ, d, a, α) with the constant parts."""
        r = self.robot
        for i in range(len(r.links)):
            var = ("theta" if self.revolute[i] else "d") if self.driven[i] else None
            yield var, float(r._theta0[i]), float(r._d0[i]), float(r._a[i]), float(r._alpha[i])


def rtb_model(chain: LinkChain):
    """robotics-toolbox-python Robot of the chain as an ETS: base · Π Rz(θ) tz(d) tx(a) Rx(α) · tool."""
    import roboticstoolbox as rtb

    r = chain.robot
    ets = rtb.ET.SE3(r.T_world_base)
    for var, theta, d, a, alpha in chain.steps():
        ets *= rtb.ET.Rz() if var == "theta" else rtb.ET.Rz(theta)
        ets *= rtb.ET.tz() if var == "d" else rtb.ET.tz(d)
        ets *= rtb.ET.tx(a) * rtb.ET.Rx(alpha)
    ets *= rtb.ET.SE3(r.T_flange_tool)
    model = rtb.Robot(ets, name=r.name)
    model.qlim = np.vstack([chain.lower, chain.upper])
    return model


def _rpy(R: NDArray[np.float64]) -> NDArray[np.float64]:
    """Roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)), as ikpy's URDF links take them."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_euler("xyz")


def _rz(t: float) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:2, :2] = [[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]]
    return T


def _const(theta: float | None, d: float | None, a: float, alpha: float) -> NDArray[np.float64]:
    """Rz(θ) Tz(d) Tx(a) Rx(α), θ or d left out (None) where the joint supplies it."""
    T = _rz(theta) if theta is not None else np.eye(4)
    if d is not None:
        T[:3, 3] += T[:3, 2] * d
    X = np.eye(4)
    X[0, 3] = a
    X[1:3, 1:3] = [[np.cos(alpha), -np.sin(alpha)], [np.sin(alpha), np.cos(alpha)]]
    return T @ X


def ikpy_chain(chain: LinkChain):
    """ikpy Chain of the link chain: URDF links (origin, then motion about or along z).

    A joint's motion Rz(u) or Tz(u) comes first in its DH row (Rz and Tz commute), so each driven
    link is a URDF joint whose origin collects every constant transform since the previous one."""
    from ikpy.chain import Chain
    from ikpy.link import URDFLink

    r = chain.robot
    origin = r.T_world_base.copy()
    links: list = []
    mask: list[bool] = []
    k = 0
    for var, theta, d, a, alpha in chain.steps():
        if var is None:
            origin = origin @ _const(theta, d, a, alpha)
            continue
        axis = np.array([0.0, 0.0, 1.0])
        links.append(
            URDFLink(
                f"u{k}",
                origin_translation=origin[:3, 3].copy(),
                origin_orientation=_rpy(origin[:3, :3]),
                rotation=axis if var == "theta" else None,
                translation=axis if var == "d" else None,
                bounds=(chain.lower[k], chain.upper[k]),
                joint_type="revolute" if var == "theta" else "prismatic",
            )
        )
        mask.append(True)
        k += 1
        origin = _const(None if var == "theta" else theta, None if var == "d" else d, a, alpha)
    end = origin @ r.T_flange_tool
    links.append(
        URDFLink("tool", origin_translation=end[:3, 3].copy(), origin_orientation=_rpy(end[:3, :3]), joint_type="fixed")
    )
    mask.append(False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Chain(links, active_links_mask=mask, name=r.name, jax_precompile=False)


class Peer:
    """One peer solver on one robot: ``solve(x, q0) -> q`` (joint values, Bosun's convention)."""

    def __init__(self, name: str, robot) -> None:
        self.name = name
        self.chain = LinkChain(robot)
        if name.startswith("rtb"):
            self.model = rtb_model(self.chain)
            self.mask = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
        else:
            self.model = ikpy_chain(self.chain)

    def solve(self, x: NDArray[np.float64], q0: NDArray[np.float64]) -> NDArray[np.float64]:
        u0 = np.clip(self.chain.u_of(q0), self.chain.lower, self.chain.upper)
        if self.name == "ikpy":
            full = np.concatenate([u0, [0.0]])
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                u = self.model.inverse_kinematics(target_position=x, initial_position=full)[:-1]
        else:
            T = np.eye(4)
            T[:3, 3] = x
            solve = self.model.ik_LM if self.name == "rtb ik_LM" else self.model.ikine_LM
            sol = solve(T, q0=u0, tol=RTB_TOL, mask=self.mask, joint_limits=True)
            u = sol[0] if isinstance(sol, tuple) else sol.q
        return self.chain.q_of(u)


def bench_peers(robots: list, *, targets: int = 500, seed: int = 7, progress=None) -> list[dict[str, Any]]:
    """Median, p95, success of each installed peer on the same targets and starts as ``bench_ik``."""
    from app.analysis.ik_studies import BENCH_TOLERANCE, bench_row, bench_targets
    from app.ik import make_solver

    names = [p for p, ok in available().items() if ok]
    jobs = [(r, p, mode) for r in robots for p in names for mode in ("cold", "warm")]
    rows = []
    for j, (robot, name, mode) in enumerate(jobs):
        X = bench_targets(robot, mode, targets, seed)
        peer = Peer(name, robot)
        q_default = make_solver("jacobian", robot, seed=seed).default_q0()
        times, ok, err = [], [], []
        q_prev = q_default
        for x in X:
            t0 = time.perf_counter()
            try:
                q = peer.solve(x, q_prev if mode == "warm" else q_default)
            except Exception:  # a peer's own failure (e.g. a singular step) counts as a miss, not a crash
                q = np.full(robot.n_joints, np.nan)
            times.append(time.perf_counter() - t0)
            finite = bool(np.all(np.isfinite(q)))
            e = float(np.linalg.norm(robot.position(q) - x)) if finite else np.inf
            ok.append(finite and e < BENCH_TOLERANCE and bool(np.all(robot.within_limits(q, tol=1e-9))))
            err.append(e)
            q_prev = robot.clip(q) if finite else q_default
        rows.append(bench_row(robot.name, name, mode, times, ok, err))
        if progress is not None:
            progress(j + 1, len(jobs))
    return rows
