"""The two studies of the universal-architecture paper §IV, and the IK benchmark.

* Error distribution (Fig. 5): the n×n×n equally spaced targets of the box enclosing the
  workspace, each solved; per target the reached point, error, time and success.
* Trajectory tracking (Fig. 4): a smooth Cartesian path through the workspace followed
  target by target with one solver instance (the GA keeps its elite between targets).
* Benchmark: per robot and solver, median and p95 solve time and success rate over a
  fixed seeded set of reachable targets.

Qt-free; long runs take ``progress(done, total)`` and ``cancelled()`` callbacks so a GUI
or a terminal progress bar can follow and stop them.
"""

from __future__ import annotations

import csv
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, TypedDict, Unpack

import numpy as np
from numpy.typing import NDArray

from app.analysis.figures import pyplot, save_figure
from app.ik import make_solver
from app.models.workspace import workspace_box

Progress = Callable[[int, int], None] | None
Cancelled = Callable[[], bool] | None


class _CancelledError(Exception):
    """Internal signal: the caller asked to stop; never escapes this module."""


def _tick(progress: Progress, cancelled: Cancelled, done: int, total: int) -> None:
    if progress is not None:
        progress(done, total)
    if cancelled is not None and cancelled():
        raise _CancelledError


TARGET_REACHED = ["target_x", "target_y", "target_z", "reached_x", "reached_y", "reached_z"]


def _f6(values) -> list[str]:
    return [f"{v:.6f}" for v in values]


def _write_rows(path: Path, header: list[str], rows) -> None:
    """The CSV files of the studies: a header, then one row per target."""
    with open(path, "w", encoding="utf-8", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


class ReachabilityReference:
    """Is a target reachable at all?  Damped least squares from 1 + 10 starts gets within 1e-3 of the diagonal.

    A solver-independent reference (a strong local method with restarts), so a study can
    say how many targets of its grid the robot can reach, whatever solver is studied.
    """

    def __init__(self, robot, seed: int = 0) -> None:
        self.solver = make_solver("jacobian", robot, seed=seed, time_budget=None, restarts=10, tolerance=1e-4)
        self.tol = 1e-3 * self.solver.box.diagonal

    def __call__(self, x: NDArray[np.float64]) -> bool:
        return self.solver.solve_position(x).error <= self.tol


# ----------------------------------------------------------------------------- results
@dataclass
class _Solves:
    """One robot and solver over a sequence of targets: per target the tool point the solver reached, its
    error [m], solve time [s] and the solver's own success; the fields both studies share."""

    robot: str
    solver: str
    reached: NDArray[np.float64]
    error: NDArray[np.float64]
    time_s: NDArray[np.float64]
    success: NDArray[np.bool_]

    def to_wire(self) -> dict[str, Any]:
        return _result_to_wire(self)


class StudyRun(TypedDict, total=False):
    """How a study runs, the keyword arguments every study takes: the solver's ``seed`` (default 0) and
    ``solver_options``, and the ``progress(done, total)`` and ``cancelled()`` callbacks."""

    seed: int
    solver_options: dict[str, Any] | None
    progress: Progress
    cancelled: Cancelled


class _Record:
    """The :class:`_Solves` arrays of n targets and the joint values q (n, n_joints), one solve at a time."""

    def __init__(self, n: int, n_joints: int) -> None:
        self.reached, self.error, self.time_s = np.zeros((n, 3)), np.zeros(n), np.zeros(n)
        self.success = np.zeros(n, dtype=bool)
        self.q = np.zeros((n, n_joints))

    def add(self, i: int, res) -> None:
        """Target i's :class:`~app.ik.base.IKResult`."""
        self.reached[i], self.q[i], self.error[i] = res.position, res.q, res.error
        self.time_s[i], self.success[i] = res.time_s, res.success

    def solves(self, done: int) -> dict[str, NDArray]:
        """The :class:`_Solves` arrays of the first ``done`` targets, by field name."""
        return {name: getattr(self, name)[:done] for name in ("reached", "error", "time_s", "success")}


def _solve_each(robot, solver_name: str, targets, run: StudyRun, warm: bool, then=None) -> tuple[_Record, int]:
    """Solve ``targets`` in order with one solver instance (``warm``: each from the previous answer, as
    teleoperation does), recording each solve and calling ``then(i, x, result)`` after it, then ``run``'s
    progress and cancel callbacks.  Returns the record and how many targets were done (fewer if cancelled)."""
    solver = make_solver(solver_name, robot, seed=run.get("seed", 0), **(run.get("solver_options") or {}))
    record = _Record(len(targets), robot.n_joints)
    q, done = None, 0
    try:
        for i, x in enumerate(targets):
            res = solver.solve_position(x, q)
            q = res.q if warm else None
            record.add(i, res)
            if then is not None:
                then(i, x, res)
            done = i + 1
            _tick(run.get("progress"), run.get("cancelled"), done, len(targets))
    except _CancelledError:
        pass
    return record, done


# ----------------------------------------------------------------------------- error distribution
@dataclass
class ErrorDistribution(_Solves):
    STUDY = "distribution"
    """Result of :func:`error_distribution`; rows are targets."""

    grid: int
    targets: NDArray[np.float64]
    reachable: NDArray[np.bool_]
    box_lower: NDArray[np.float64]
    box_upper: NDArray[np.float64]
    complete: bool = True

    def summary(self) -> dict[str, Any]:
        n = len(self.error)
        reach = self.reachable
        return {
            "robot": self.robot,
            "solver": self.solver,
            "grid": self.grid,
            "targets": n,
            "complete": self.complete,
            "reachable": int(reach.sum()),
            "success": int(self.success.sum()),
            "success_rate": float(self.success.mean()) if n else 0.0,
            "success_rate_reachable": float(self.success[reach].mean()) if reach.any() else None,
            "error_m": _stats(self.error),
            "error_reachable_m": _stats(self.error[reach]) if reach.any() else None,
            "time_s": _stats(self.time_s),
            "box_lower": self.box_lower.tolist(),
            "box_upper": self.box_upper.tolist(),
        }

    def write_csv(self, path: Path) -> None:
        _write_rows(
            path,
            [*TARGET_REACHED, "error_m", "time_s", "success", "reachable"],
            (
                [
                    *_f6(self.targets[i]),
                    *_f6(self.reached[i]),
                    f"{self.error[i]:.6g}",
                    f"{self.time_s[i]:.6g}",
                    int(self.success[i]),
                    int(self.reachable[i]),
                ]
                for i in range(len(self.error))
            ),
        )


def _stats(x: NDArray[np.float64]) -> dict[str, float]:
    if len(x) == 0:
        return {"median": float("nan"), "p95": float("nan"), "max": float("nan")}
    return {
        "median": float(np.median(x)),
        "p95": float(np.percentile(x, 95)),
        "max": float(np.max(x)),
        "mean": float(np.mean(x)),
    }


def error_distribution(robot, solver_name: str, grid: int = 8, **run: Unpack[StudyRun]) -> ErrorDistribution:
    """Solve the grid³ targets of the workspace box (paper Fig. 5: 8³ = 512).

    Targets are visited in grid order with one solver instance, as an operator sweeping
    the box would.  A cancelled run returns the targets done so far with ``complete=False``.
    """
    if not 2 <= grid <= 40:
        raise ValueError(f"grid must be between 2 and 40, got {grid}")
    box = workspace_box(robot)
    targets = box.grid(grid)
    reference = ReachabilityReference(robot, seed=run.get("seed", 0))
    reachable = np.zeros(len(targets), dtype=bool)

    def check(i: int, x: NDArray[np.float64], res) -> None:
        reachable[i] = res.error <= reference.tol or reference(x)

    record, done = _solve_each(robot, solver_name, targets, run, False, check)
    return ErrorDistribution(
        robot=robot.name,
        solver=solver_name,
        **record.solves(done),
        grid=grid,
        targets=targets[:done],
        reachable=reachable[:done],
        box_lower=box.lower,
        box_upper=box.upper,
        complete=done == len(targets),
    )


def _result_to_wire(result) -> dict[str, Any]:
    """A study result as plain lists for the protocol (``study`` message); inverse: :func:`study_from_wire`."""
    out: dict[str, Any] = {"study": result.STUDY}
    for f in fields(result):
        v = getattr(result, f.name)
        out[f.name] = v.tolist() if isinstance(v, np.ndarray) else v
    return out


def study_from_wire(data: dict[str, Any]) -> ErrorDistribution | Tracking:
    """The result of a study sent by an engine (see :func:`_result_to_wire`)."""
    cls = {"distribution": ErrorDistribution, "tracking": Tracking}.get(data.get("study"))
    if cls is None:
        raise ValueError(f"unknown study {data.get('study')!r}")
    kw = {}
    for f in fields(cls):
        v = data[f.name]
        if isinstance(v, list):
            kind = bool if f.name in ("success", "reachable") else float
            v = np.asarray(v, dtype=kind)
            if v.ndim == 1 and f.name in ("targets", "reached", "target", "q") and v.size == 0:
                v = v.reshape(0, 3 if f.name != "q" else 0)
        kw[f.name] = v
    return cls(**kw)


def _headline(result: _Solves, text: str) -> str:
    """A study figure's title: "robot – solver: text"."""
    return f"{result.robot} – {result.solver}: {text}"


def plot_error_distribution(result: ErrorDistribution, path: Path) -> None:
    """3D scatter of the targets coloured by error (paper Fig. 5), saved as PNG."""
    plt = pyplot()
    fig = plt.figure(figsize=(7.5, 6.0), dpi=110)
    ax = fig.add_subplot(projection="3d")
    err = np.maximum(result.error, 1e-9)
    sc = ax.scatter(*result.targets.T, c=np.log10(err), cmap="viridis", s=14, depthshade=False)
    bad = ~result.reachable
    if bad.any():
        ax.scatter(
            *result.targets[bad].T, facecolors="none", edgecolors="red", s=40, linewidths=0.6, label="not reachable"
        )
        ax.legend(loc="upper left", fontsize=8)
    cb = fig.colorbar(sc, ax=ax, shrink=0.7, pad=0.1)
    cb.set_label("log10 position error [m]")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    s = result.summary()
    ax.set_title(
        _headline(result, f"{s['targets']} targets, {s['success']} solved, {s['reachable']} reachable"), fontsize=10
    )
    save_figure(plt, fig, path)


# ----------------------------------------------------------------------------- tracking
@dataclass
class Tracking(_Solves):
    STUDY = "tracking"
    t: NDArray[np.float64]
    target: NDArray[np.float64]
    q: NDArray[np.float64] = field(repr=False)

    def summary(self) -> dict[str, Any]:
        return {
            "robot": self.robot,
            "solver": self.solver,
            "samples": len(self.t),
            "duration_s": float(self.t[-1]) if len(self.t) else 0.0,
            "success_rate": float(self.success.mean()) if len(self.t) else 0.0,
            "rms_error_m": float(np.sqrt(np.mean(self.error**2))) if len(self.t) else float("nan"),
            "max_error_m": float(self.error.max()) if len(self.t) else float("nan"),
            "time_s": _stats(self.time_s),
        }

    def write_csv(self, path: Path) -> None:
        _write_rows(
            path,
            ["t", *TARGET_REACHED, "error_m", "solve_time_s", "success"]
            + [f"q{i + 1}" for i in range(self.q.shape[1])],
            (
                [
                    f"{self.t[i]:.3f}",
                    *_f6(self.target[i]),
                    *_f6(self.reached[i]),
                    f"{self.error[i]:.6g}",
                    f"{self.time_s[i]:.6g}",
                    int(self.success[i]),
                    *_f6(self.q[i]),
                ]
                for i in range(len(self.t))
            ),
        )


def tracking_path(robot, duration: float, dt: float, amplitude: float = 0.25) -> tuple[NDArray, NDArray]:
    """A smooth tool path inside the workspace: FK of a multi-sine joint motion about mid-range.

    Each joint moves ±``amplitude`` of its range at its own frequency (one to three slow
    cycles over the run), so every point of the path is reachable; the solver only sees
    the Cartesian points.  Returns (t, points), shapes (m,) and (m, 3).
    """
    t = np.arange(0.0, duration + 1e-9, dt)
    mid, span = 0.5 * (robot.lower + robot.upper), robot.upper - robot.lower
    k = np.arange(robot.n_joints)
    freq = (1.0 + 0.37 * k) / duration
    q = mid + amplitude * span * np.sin(2 * np.pi * freq * t[:, None] + 0.7 * k)
    return t, robot.position(q)


def track(robot, solver_name: str, *, duration: float = 20.0, dt: float = 0.1, **run: Unpack[StudyRun]) -> Tracking:
    """Follow :func:`tracking_path` target by target, warm-starting from the previous answer."""
    t, path = tracking_path(robot, duration, dt)
    record, done = _solve_each(robot, solver_name, path, run, True)
    return Tracking(
        robot=robot.name, solver=solver_name, **record.solves(done), t=t[:done], target=path[:done], q=record.q[:done]
    )


def plot_tracking(result: Tracking, path: Path) -> None:
    """X, Y and Z of target and reached point against time (paper Fig. 4b), saved as PNG."""
    plt = pyplot()
    fig, axes = plt.subplots(4, 1, figsize=(8, 8), dpi=110, sharex=True)
    for k, label in enumerate("XYZ"):
        ax = axes[k]
        ax.plot(result.t, result.target[:, k], color="0.3", lw=2.0, label="target")
        ax.plot(result.t, result.reached[:, k], color="tab:orange", lw=1.2, ls="--", label="reached")
        ax.set_ylabel(f"{label} [m]")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[3].semilogy(result.t, np.maximum(result.error, 1e-9), color="tab:red", lw=1.0)
    axes[3].set_ylabel("error [m]")
    axes[3].set_xlabel("time [s]")
    axes[3].grid(alpha=0.3)
    s = result.summary()
    fig.suptitle(_headline(result, f"rms error {s['rms_error_m']:.3g} m, max {s['max_error_m']:.3g} m"), fontsize=10)
    save_figure(plt, fig, path)


# ----------------------------------------------------------------------------- benchmark
BENCH_TOLERANCE = 1e-3  # m: a bench success is an error below 1 mm with every joint inside its limits


def warm_path(robot, n: int, rng: np.random.Generator, step: float = 0.01) -> NDArray[np.float64]:
    """n reachable targets, consecutive ones ``step`` (1 cm) apart along the tool path of a joint-space
    sweep between random configurations: what a teleoperated arm asks of its solver."""
    points: list[NDArray[np.float64]] = []
    q_a = rng.uniform(robot.lower, robot.upper)
    while len(points) < n:
        q_b = rng.uniform(robot.lower, robot.upper)
        P = robot.position(q_a + np.linspace(0.0, 1.0, 2000)[:, None] * (q_b - q_a))
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
        for s_k in np.arange(0.0, arc[-1], step):
            k = min(int(np.searchsorted(arc, s_k)), len(P) - 1)
            points.append(P[k])
        q_a = q_b
    return np.array(points[:n])


def bench_targets(robot, mode: str, targets: int, seed: int) -> NDArray[np.float64]:
    """The benchmark's targets: ``cold``, the FK of configurations drawn uniformly inside the joint
    limits (reachable by construction); ``warm``, a tool path with targets 1 cm apart."""
    rng = np.random.default_rng(seed)
    if mode == "cold":
        return robot.position(rng.uniform(robot.lower, robot.upper, size=(targets, robot.n_joints)))
    return warm_path(robot, targets, rng)


def bench_row(robot: str, solver: str, start: str, times, ok, err, own=None) -> dict[str, Any]:
    """One benchmark row: median/p95/p99 time [ms], success (and the solver's own test) and median error."""
    t_ms = np.array(times) * 1e3
    row = {
        "robot": robot,
        "solver": solver,
        "start": start,
        "targets": len(times),
        "median_ms": float(np.median(t_ms)),
        "p95_ms": float(np.percentile(t_ms, 95)),
        "p99_ms": float(np.percentile(t_ms, 99)),
        "success_rate": float(np.mean(ok)),
        "median_error_m": float(np.median(err)),
    }
    if own is not None:
        row["own_success_rate"] = float(np.mean(own))
    return row


def bench_ik(
    robots: list,
    *,
    targets: int = 500,
    seed: int = 7,
    progress: Progress = None,
) -> list[dict[str, Any]]:
    """Solve time and success per robot, solver and start (issue 14's benchmark).

    ``cold``: targets are the FK of configurations drawn uniformly inside the joint limits
    (reachable by construction), each solved from the solver's default start.  ``warm``:
    targets 1 cm apart along a tool path, each solved from the previous solution (teleoperation).
    One solver instance per row, default time budget (100 ms).  Success: error < 1 mm and every
    joint inside its limits, whatever the solver's own stop criterion (the GA's published stop is
    1 % of the workspace box per axis, so it rarely reaches 1 mm; ``own_success_rate`` is its own).
    """
    from app.ik import solvers_for

    jobs = [(r, s, mode) for r in robots for s in solvers_for(r) for mode in ("cold", "warm")]
    rows = []
    for j, (robot, name, mode) in enumerate(jobs):
        X = bench_targets(robot, mode, targets, seed)
        solver = make_solver(name, robot, seed=seed)
        times, ok, own, err = [], [], [], []
        q_prev = None
        for x in X:
            t0 = time.perf_counter()
            res = solver.solve_position(x, q_prev) if mode == "warm" else solver.solve_position(x)
            times.append(time.perf_counter() - t0)
            inside = bool(np.all(robot.within_limits(res.q)))
            ok.append(res.error < BENCH_TOLERANCE and inside)
            own.append(res.success)
            err.append(res.error)
            q_prev = res.q if mode == "warm" else None
        rows.append(bench_row(robot.name, name, mode, times, ok, err, own))
        if progress is not None:
            progress(j + 1, len(jobs))
    return rows


def write_json(obj: Any, path: Path) -> None:
    path.write_text(json.dumps(obj, indent=2, allow_nan=False) + "\n", encoding="utf-8")
