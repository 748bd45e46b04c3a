"""The solver interface of the universal architecture (Sanfilippo et al., eqs. 3–4).

A solver maps a desired tool position to joint values, θ_d = f_p⁻¹(x_ds) (eq. 3), and a
desired tool velocity to joint velocities, θ̇_d = f_v⁻¹(θ_a, ẋ_ds, Δt) (eq. 4).

The abstract :class:`Solver` owns everything the methods share: target validation, the
time budget, restarts, joint-limit enforcement on the answer, and the result record.
A method implements one search, :meth:`Solver._search`.  Guarantees, for every input:
the returned q is inside the joint limits and finite; an unreachable target gives
``success=False``, a reason, and the closest configuration found; a non-finite target
raises :class:`IKError`.
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from collections import deque
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.errors import BosunError
from app.models.workspace import WorkspaceBox, workspace_box

#: "use the solver's own time budget" (None means no limit, so it cannot be the default marker)
DEFAULT: Any = object()


#: solves whose clock decisions are kept for a recording (:meth:`Solver.take_work`): a bound, so nothing grows
#: where nobody takes them
WORK_KEPT = 64


@dataclass(frozen=True)
class Replayed:
    """A time budget replayed (issue 32, item 6): each solve's clock decisions as a recording holds them
    (:meth:`Solver.take_work`), one list per solve in the order they ran.  Passed as ``time_budget``, it stands
    for the clock: each decision a solve would take from it (spent or not; how many generations fit) is the
    recorded one, so a GA or a Jacobian with restarts takes the same steps on any machine."""

    seconds: float
    solves: tuple[tuple[int, ...], ...]


class IKError(BosunError):
    """A request no solver can take: non-finite target, wrong shape, unsupported robot."""


@dataclass(frozen=True, eq=False)
class IKResult:
    """Outcome of one solve.

    Attributes
    ----------
    q : ndarray, shape (n,)
        Joint values, always finite and inside the joint limits [rad, m].
    success : bool
        The solver's own convergence test passed (see each solver's ``tolerance``).
    error : float
        Distance from the target to the reached tool position [m].
    iterations : int
        Iterations or generations used.
    time_s : float
        Wall time of the solve [s].
    reason : str
        Why the solver stopped (converged, time budget, unreachable, ...).
    position : ndarray, shape (3,)
        Reached tool position, FK(q) [m].
    qdot : ndarray or None
        Joint velocities for a velocity solve (eq. 4), else None.
    cost : float
        The solver's own cost at exit (normalised for the GA, metres otherwise).
    """

    q: NDArray[np.float64]
    success: bool
    error: float
    iterations: int
    time_s: float
    reason: str
    position: NDArray[np.float64]
    qdot: NDArray[np.float64] | None = None
    cost: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        return {
            "q": [float(v) for v in self.q],
            "success": bool(self.success),
            "error_m": float(self.error),
            "iterations": int(self.iterations),
            "time_s": float(self.time_s),
            "reason": self.reason,
            "position": [float(v) for v in self.position],
            "qdot": None if self.qdot is None else [float(v) for v in self.qdot],
            "cost": None if not math.isfinite(self.cost) else float(self.cost),
        }


@dataclass
class SearchOutcome:
    """What a method's search returns to the base class."""

    q: NDArray[np.float64]
    iterations: int
    converged: bool
    reason: str
    cost: float = math.nan
    extra: dict[str, Any] = field(default_factory=dict)


class SolverOptions(TypedDict, total=False):
    """The keyword arguments of :class:`Solver` itself, which every method takes beside its own and passes on."""

    time_budget: float | object | None
    rng: np.random.Generator | None


class Solver(ABC):
    """Base of all IK solvers.

    Parameters
    ----------
    robot : SerialRobot
    time_budget : float or None
        Wall-time limit of one solve [s]; None means no limit (then a method's own
        iteration limits end the search).
    rng : numpy.random.Generator, optional
        Source of every random number; default a generator seeded with 0.
    """

    name: ClassVar[str] = ""
    #: default time budget [s]
    default_time_budget: ClassVar[float | None] = 0.1

    def __init__(
        self, robot, *, time_budget: float | object | None = DEFAULT, rng: np.random.Generator | None = None
    ) -> None:
        self.robot = robot
        self.time_budget = self.default_time_budget if time_budget is DEFAULT else time_budget
        if self.time_budget is not None and not (self.time_budget > 0 and math.isfinite(self.time_budget)):
            raise IKError(f"time budget must be a positive number of seconds, got {time_budget}")
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.box: WorkspaceBox = workspace_box(robot)
        self._revolute = np.array([k == "revolute" for k in robot.joint_kinds])
        #: each recent solve's clock decisions, oldest first (:meth:`take_work`)
        self.work: deque[list[int]] = deque(maxlen=WORK_KEPT)
        self._decisions: list[int] = []  # this solve's, as they are taken
        self._tape: list[int] | None = None  # a replayed solve's, still to take
        self._replayed: list[tuple[int, ...]] = []  # a replayed budget's solves still to run

    # ---------------------------------------------------------------- helpers
    def check_target(self, target: ArrayLike) -> NDArray[np.float64]:
        """A target as a finite float array of shape (3,), else :class:`IKError`."""
        if (
            type(target) is np.ndarray
            and target.shape == (3,)
            and target.dtype == np.float64
            and math.isfinite(target[0] + target[1] + target[2])
        ):
            return target  # the common case, without the general path's array calls
        try:
            x = np.asarray(target, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise IKError(f"target must be 3 numbers (x, y, z in metres), got {target!r}") from None
        if x.size != 3:
            raise IKError(f"target must be 3 numbers (x, y, z in metres), got {x.size}")
        if not np.all(np.isfinite(x)):
            raise IKError(f"target must be finite, got {x.tolist()}")
        return x

    def check_q0(self, q0: ArrayLike | None) -> NDArray[np.float64] | None:
        if q0 is None:
            return None
        if (
            type(q0) is np.ndarray
            and q0.shape == (self.robot.n_joints,)
            and q0.dtype == np.float64
            and math.isfinite(float(q0.sum()))
        ):
            return self.robot.clip(q0)
        try:
            q = self.robot.check_q(q0)
        except BosunError as err:
            raise IKError(f"q0: {err}") from None
        return self.robot.clip(q)

    def default_q0(self) -> NDArray[np.float64]:
        """Middle of the joint ranges."""
        return 0.5 * (self.robot.lower + self.robot.upper)

    def random_q(self, n: int | None = None) -> NDArray[np.float64]:
        size = (self.robot.n_joints,) if n is None else (n, self.robot.n_joints)
        return self.rng.uniform(self.robot.lower, self.robot.upper, size=size)

    def wrap_into_limits(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """Shift revolute joints by multiples of 2π to the equivalent angle inside the limits, if any."""
        q = np.array(q, dtype=float)
        lo, hi = self.robot.lower, self.robot.upper
        for i in np.flatnonzero(self._revolute):
            if lo[i] <= q[i] <= hi[i]:
                continue
            k = np.ceil((lo[i] - q[i]) / (2 * np.pi))
            cand = q[i] + 2 * np.pi * k
            if cand <= hi[i]:
                q[i] = cand
        return q

    def _deadline(self, time_budget: float | Replayed | None) -> float:
        """The solve's deadline (a perf_counter time; inf: none), called once as each solve starts.  A finite
        budget's solve keeps its clock decisions (:attr:`work`); a :class:`Replayed` budget's solve takes the
        recorded ones instead of reading the clock (its deadline is then inf: only the decisions end it)."""
        budget = self.time_budget if time_budget is DEFAULT else time_budget
        self._tape = None
        if isinstance(budget, Replayed):
            if self._replayed_of is not budget:  # the budget's first solve: its solves to run, in order
                self._replayed_of, self._replayed = budget, [list(d) for d in budget.solves]
            self._tape = self._replayed.pop(0) if self._replayed else []
            return math.inf
        self._decisions = []  # an unbudgeted solve's are kept nowhere: it reads no clock that could differ
        if budget is None:
            return math.inf
        self.work.append(self._decisions)
        return time.perf_counter() + budget

    _replayed_of: Replayed | None = None

    def _decide(self, measure, spent: int = 0) -> int:
        """One decision a solve takes from the clock (``measure()``: an int, a bool as 0/1): the replayed one
        where the budget is replayed (none left: ``spent``, the clock's answer once time is up), else measured
        and kept."""
        if self._tape is not None:
            return self._tape.pop(0) if self._tape else spent
        value = int(measure())
        self._decisions.append(value)
        return value

    def _expired(self, deadline: float) -> bool:
        """Whether the solve's time is up (a decision, :meth:`_decide`)."""
        if math.isinf(deadline) and self._tape is None:
            return False
        return self._decide(lambda: time.perf_counter() >= deadline, spent=1) != 0

    def take_work(self) -> list[list[int]]:
        """The clock decisions of the solves since the last call, oldest first (what a recording keeps, for
        :class:`Replayed`), and forgets them."""
        out = list(self.work)
        self.work.clear()
        return out

    # ---------------------------------------------------------------- interface
    def solve_position(
        self, target: ArrayLike, q0: ArrayLike | None = None, *, time_budget: float | object | None = DEFAULT
    ) -> IKResult:
        """Position mapping θ_d = f_p⁻¹(x_ds), eq. (3) / eq. (8).

        Parameters
        ----------
        target : array_like, shape (3,)
            Desired tool position in the world frame [m].
        q0 : array_like, shape (n,), optional
            Current joint values, used as the start of local methods.
        time_budget : float or None, optional
            Override of the solver's time budget for this call [s].
        """
        start = time.perf_counter()
        x_t = self.check_target(target)
        q_start = self.check_q0(q0)
        outcome = self._search(x_t, q_start, self._deadline(time_budget))
        return self._result(x_t, outcome, start)

    def solve_velocity(
        self, q_a: ArrayLike, xdot: ArrayLike, dt: float, *, time_budget: float | object | None = DEFAULT
    ) -> IKResult:
        """Velocity mapping θ̇_d = f_v⁻¹(θ_a, ẋ_ds, Δt), eq. (4).

        The default follows the GA case study: the target is x_t = x_a + ẋ_ds Δt (eq. 7),
        it is solved as a position, and θ̇_d = (θ_f − θ_a)/Δt (eq. 9), scaled down as a
        whole if any joint would exceed its speed limit.
        """
        start = time.perf_counter()
        q_a, v = self.check_velocity_request(q_a, xdot, dt)
        x_t = self.robot.position(q_a) + v * dt  # eq. (7)
        outcome = self._search(x_t, q_a, self._deadline(time_budget))
        q_f = self.robot.clip(outcome.q)
        qdot = self.limit_speed((q_f - q_a) / dt)  # eq. (9)
        outcome.q = self.robot.clip(q_a + qdot * dt)
        return self._result(x_t, outcome, start, qdot=qdot)

    def check_velocity_request(
        self, q_a: ArrayLike, xdot: ArrayLike, dt: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Validated (θ_a clipped into the limits, ẋ_ds) of a velocity solve, else :class:`IKError`."""
        q = self.check_q0(q_a)
        if q is None:
            raise IKError("velocity solve needs the actual joint values")
        v = self.check_target(xdot)
        if not (dt > 0 and math.isfinite(dt)):
            raise IKError(f"dt must be a positive number of seconds, got {dt}")
        return q, v

    def limit_speed(self, qdot: NDArray[np.float64]) -> NDArray[np.float64]:
        """Scale a joint-velocity vector uniformly so that no joint exceeds its speed limit."""
        ratio = np.max(np.abs(qdot) / self.robot.speed)
        return qdot / ratio if ratio > 1.0 else qdot

    def reset(self) -> None:  # noqa: B027 - a hook: stateless solvers keep the empty default
        """Forget state kept between calls (the GA's population); stateless solvers ignore it."""

    # ---------------------------------------------------------------- internals
    @abstractmethod
    def _search(self, x_t: NDArray[np.float64], q0: NDArray[np.float64] | None, deadline: float) -> SearchOutcome:
        """Find joint values reaching x_t before ``deadline`` (a perf_counter time)."""

    def _result(
        self, x_t: NDArray[np.float64], outcome: SearchOutcome, start: float, qdot: NDArray[np.float64] | None = None
    ) -> IKResult:
        q = np.asarray(outcome.q, dtype=float)
        if not math.isfinite(float(q.sum())):  # NaN or inf anywhere
            q = np.nan_to_num(q, nan=0.0, posinf=0.0, neginf=0.0)
        q = self.robot.clip(q)
        p = self.robot.position(q)
        d = p - x_t
        error = math.sqrt(float(d @ d))
        return IKResult(
            q=q,
            success=bool(outcome.converged),
            error=error,
            iterations=int(outcome.iterations),
            time_s=time.perf_counter() - start,
            reason=outcome.reason,
            position=p,
            qdot=qdot,
            cost=outcome.cost,
        )
