"""A load chart derated by the sea (issue 31, item 4): ``bosun study loadchart``.

The crane's rated capacity per radius C(r) (its robot file's ``<rated_capacity>``: a static chart, in calm water)
derated by the dynamic factor ψ the sea gives the load (:mod:`app.scenarios.dynamic_factor`: the wire's peak
tension over the load's weight, simulated with the crane holding its load hanging):

    SWL(r, Hs) = C(r) / ψ(r, Hs, mode, payload)

One simulation per mode × payload × radius × sea × seed, as tasks on a Dask cluster (the operability study's
machinery, :mod:`app.analysis.operability`: a local cluster or a scheduler, each cell cached in ``OUT/cells`` at
once, a study resumed with what is missing).  Per cell ψ is the largest peak of its seeds (the load chart must hold
the worst the seeds showed).  The seas: ``--hs`` values at one ``--tp``, or a scatter diagram's cells with a
probability (``--scatter``), where the chart at one Hs takes the worst period the diagram holds at that Hs.

A payload *fits* where it is at most its SWL.  The summary says whether each payload's chart falls as Hs grows and
whether the compensated chart lies above the uncompensated one (the issue's acceptance), cell by cell where not.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from app.analysis.figures import pyplot, save_figure
from app.analysis.operability import (
    MAX_RUNS,
    MAX_WORKERS,
    RUNS_CEILING,
    OperabilityError,
    Scatter,
    cell_key,
    cell_periods,
    run_missing,
    take_cell,
    vessel_id,
)
from app.errors import BosunError

CELL_VERSION = 1  # bump when a cell's simulation changes: older cached cells are not used
MAX_AXIS = 50  # radii, payloads or Hs values a study takes
CRANE = "offshore_crane"  # the crane of the crane-head scene (app.scenarios.tac.TacScenario.crane)
#: two charts are compared to this share (0.5 %: 0.05 t of a 10 t rating, under the 0.1 t a chart is printed to): the
#: anti-swing's noisy sensors move the TCP by millimetres even in flat water (ψ 1.001 over 600 s), no chart's
#: difference
PSI_TOLERANCE = 5e-3


class LoadChartError(OperabilityError):
    """A load chart that cannot be made (one line)."""


@dataclass(frozen=True)
class LoadChartStudy:
    radii: tuple[float, ...] = (20.0, 25.0, 30.0)  # m
    payloads: tuple[float, ...] = (2.0, 5.0, 10.0)  # t
    modes: tuple[str, ...] = ("off", "compensated", "antisway")
    heading: float = 90.0
    seeds: int = 2
    duration: float = 600.0
    vessel: str | None = None
    spectrum: str = "jonswap"
    wire: float = 10.0
    dt: float = 0.01

    def __post_init__(self) -> None:
        from app.scenarios.dynamic_factor import MODES

        for name, values in (("radii", self.radii), ("payloads", self.payloads), ("modes", self.modes)):
            if not values:
                raise LoadChartError(f"at least one of {name} is needed")
            if len(values) > MAX_AXIS:
                raise LoadChartError(f"{name}: at most {MAX_AXIS}, got {len(values)}")
            if len(set(values)) != len(values):
                raise LoadChartError(f"{name} repeated: {', '.join(str(v) for v in values)}")
        for m in self.modes:
            if m not in MODES:
                raise LoadChartError(f"mode must be one of {', '.join(MODES)}, got {m!r}")
        if not 1 <= self.seeds <= 1000:
            raise LoadChartError(f"seeds must be 1 to 1000, got {self.seeds}")


def crane_rating(crane: str = CRANE):
    """The crane's :class:`~app.models.spec.RatedCapacity` (its robot file's); one line when it has none."""
    from app.models.registry import load_spec

    spec = load_spec(crane)
    if spec.rated_capacity is None:
        raise LoadChartError(f"{spec.path}: the crane has no <rated_capacity> (robots/README.md): no load chart")
    return spec.rated_capacity


def crane_id(crane: str = CRANE) -> str:
    """What the cells depend on of the crane: its robot file's content (its hash; an edited crane is a new study)."""
    import hashlib

    from app.models.registry import resolve

    return hashlib.sha256(resolve(crane).read_bytes()).hexdigest()[:16]


def cell_params(study: LoadChartStudy, mode: str, payload: float, radius: float, hs: float, tp: float, seed: int,
                vessel: str | None, crane: str | None = None) -> dict[str, Any]:  # fmt: skip
    return {
        "crane": crane,
        "v": CELL_VERSION, "kind": "loadchart", "mode": mode, "payload": float(payload), "radius": float(radius),
        "hs": float(hs), "tp": float(tp), "heading": float(study.heading), "seed": int(seed),
        "duration": float(study.duration), "dt": float(study.dt), "spectrum": study.spectrum, "wire": study.wire,
        "vessel": vessel,
    }  # fmt: skip


def run_cell(params: dict[str, Any], vessel: str | None = None) -> dict[str, Any]:
    """One simulation (a Dask task: a module-level function of plain data); ``vessel`` the name or file."""
    from app.scenarios.dynamic_factor import DynamicFactorScenario, simulate

    sc = DynamicFactorScenario(
        hs=params["hs"], tp=params["tp"], heading=params["heading"], spectrum=params["spectrum"], seed=params["seed"],
        rao=vessel, mode=params["mode"], payload=params["payload"], radius=params["radius"], wire=params["wire"],
        duration=params["duration"], dt=params["dt"],
    )  # fmt: skip
    return {**params, **simulate(sc)}


def check_study(study: LoadChartStudy, seas: list[tuple[float, float]], max_runs: int = MAX_RUNS) -> None:
    """The study's size, the crane's rating at every radius, the radii's reach and one cell's scenario, before
    any work (one line each)."""
    if not 1 <= max_runs <= RUNS_CEILING:
        raise LoadChartError(f"the run limit must be 1 to {RUNS_CEILING:,}, got {max_runs:,}")
    runs = len(study.modes) * len(study.payloads) * len(study.radii) * len(seas) * study.seeds
    if runs > max_runs:
        raise LoadChartError(
            f"{len(study.modes)} modes × {len(study.payloads)} payloads × {len(study.radii)} radii × {len(seas)} seas "
            f"× {study.seeds} seeds = {runs:,} simulations, more than the limit of {max_runs:,} (--max-runs N)"
        )
    rating = crane_rating()
    for r in study.radii:
        if rating.at(r) is None:
            raise LoadChartError(
                f"radius {r:g} m is beyond the crane's rated chart (its last rating: {rating.radius[-1]:g} m)"
            )
    from app.marine.vessels import vessel_rao
    from app.scenarios.dynamic_factor import DynamicFactorScenario, _setup

    try:
        vessel_rao(study.vessel)
        for r in study.radii:  # the reach (the crane's inverse kinematics: milliseconds)
            _setup(DynamicFactorScenario(hs=0, duration=1.0, radius=r, rao=study.vessel))
        hs, tp = seas[0]
        DynamicFactorScenario(
            hs=hs, tp=tp, heading=study.heading, spectrum=study.spectrum, rao=study.vessel, mode=study.modes[0],
            payload=study.payloads[0], radius=study.radii[0], wire=study.wire, duration=study.duration, dt=study.dt,
        )  # fmt: skip
        for p in study.payloads:
            DynamicFactorScenario(payload=p)
    except BosunError as err:
        raise LoadChartError(str(err)) from None


def scatter_seas(scatter: Scatter, spectrum: str) -> tuple[list[tuple[float, float]], float]:
    """The (Hs, Tp) of a scatter diagram's cells with a probability; (seas, probability of breaking seas left
    out)."""
    tps, why = cell_periods(scatter, spectrum)
    seas = sorted({
        (float(hs), float(tps[i, j])) for i, hs in enumerate(scatter.hs) for j in range(scatter.t.size)
        if scatter.prob[i, j] > 0 and (i, j) not in why
    })  # fmt: skip
    return seas, float(sum(scatter.prob[ij] for ij in why))


@dataclass
class LoadChartResult:
    study: LoadChartStudy
    seas: list[tuple[float, float]]
    source: str
    table: list[dict[str, Any]]  # per mode × payload × radius × Hs
    checks: dict[str, Any]
    computed: int = 0
    cached: int = 0
    wall_s: float = 0.0
    workers: int = 0
    scheduler: str = ""
    cells: list[dict[str, Any]] = field(default_factory=list)


def run_study(
    study: LoadChartStudy,
    seas: list[tuple[float, float]],
    out: str | Path,
    source: str = "",
    scheduler: str | None = None,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    max_runs: int = MAX_RUNS,
) -> LoadChartResult:
    """Run (or resume) the study: every finished cell is in ``out/cells`` at once (module text)."""
    check_study(study, seas, max_runs)
    if workers is not None and not 1 <= workers <= MAX_WORKERS:
        raise LoadChartError(f"workers must be 1 to {MAX_WORKERS}, got {workers}")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise LoadChartError(f"output folder {out} is a file")
    cache = out / "cells"
    vid, cid = vessel_id(study.vessel), crane_id()
    todo, done = [], []
    for mode in study.modes:
        for payload in study.payloads:
            for radius in study.radii:
                for hs, tp in seas:
                    for seed in range(1, study.seeds + 1):
                        p = cell_params(study, mode, payload, radius, hs, tp, seed, vid, cid)
                        take_cell(cache, cell_key(p), p, done, todo)
    cached = len(done)
    n_workers, address, wall = run_missing(study, todo, done, cache, scheduler, workers, progress, run_cell)
    table = aggregate(study, seas, done)
    return LoadChartResult(
        study, seas, source, table, chart_checks(study, table), len(todo), cached, wall,
        n_workers, address, done,
    )  # fmt: skip


def aggregate(study: LoadChartStudy, seas: list[tuple[float, float]], cells: list[dict[str, Any]]) -> list[dict]:
    """Per mode × payload × radius × Hs: ψ (the largest of the seeds' peaks over the Hs's periods, and the period
    that gave it), the rated capacity, SWL = C/ψ and whether the payload fits."""
    rating = crane_rating()
    by: dict[tuple, list[dict[str, Any]]] = {}
    for c in cells:
        by.setdefault((c["mode"], c["payload"], c["radius"], c["hs"]), []).append(c)
    table = []
    for mode in study.modes:
        for payload in study.payloads:
            for radius in study.radii:
                cap = rating.at(radius) / 1000.0
                for hs in sorted({h for h, _ in seas}):
                    runs = by.get((mode, float(payload), float(radius), hs), [])
                    want = study.seeds * sum(1 for h, _ in seas if h == hs)
                    if len(runs) != want:
                        raise LoadChartError(
                            f"{mode}, {payload:g} t, {radius:g} m, Hs {hs:g} m: {len(runs)} of {want} runs"
                        )
                    worst = max(runs, key=lambda c: c["psi"])
                    psi = float(worst["psi"])
                    swl = cap / psi
                    table.append({
                        "mode": mode, "payload_t": float(payload), "radius_m": float(radius), "hs": hs,
                        "tp": float(worst["tp"]), "psi": psi, "capacity_t": cap, "swl_t": swl,
                        "percent_of_swl": 100.0 * payload / swl, "fits": bool(payload <= swl),
                        "slack_s": float(max(c["slack_s"] for c in runs)),
                        "snap_s": float(max(c["snap_s"] for c in runs)),
                        "peak_swing_deg": float(max(c["peak_swing_deg"] for c in runs)),
                    })  # fmt: skip
    return table


def chart_checks(study: LoadChartStudy, table: list[dict[str, Any]]) -> dict[str, Any]:
    """The acceptance's two properties, to :data:`PSI_TOLERANCE`: each payload's chart falls (does not rise) as Hs
    grows, and the compensated charts lie on or above the uncompensated one; the cells where not."""
    swl = {(r["mode"], r["payload_t"], r["radius_m"], r["hs"]): r["swl_t"] for r in table}
    rises = []
    for mode in study.modes:
        for payload in study.payloads:
            for radius in study.radii:
                hs = sorted(h for (m, p, r, h) in swl if (m, p, r) == (mode, payload, radius))
                for a, b in itertools.pairwise(hs):
                    if swl[(mode, payload, radius, b)] > swl[(mode, payload, radius, a)] * (1 + PSI_TOLERANCE):
                        rises.append(f"{mode}, {payload:g} t, {radius:g} m: Hs {a:g} → {b:g} m")
    below = []
    if "off" in study.modes:
        for mode in (m for m in study.modes if m != "off"):
            for (m, p, r, h), v in swl.items():
                if m == mode and v < swl[("off", p, r, h)] * (1 - PSI_TOLERANCE):
                    below.append(f"{mode} below off at {p:g} t, {r:g} m, Hs {h:g} m")
    return {
        "falls_with_hs": not rises, "rises": rises,
        "compensated_above_off": not below if "off" in study.modes else None, "below_off": below,
    }  # fmt: skip


COLUMNS = (
    "mode", "payload_t", "radius_m", "hs", "tp", "psi", "capacity_t", "swl_t", "percent_of_swl", "fits", "slack_s",
    "snap_s", "peak_swing_deg",
)  # fmt: skip


def save(result: LoadChartResult, out: str | Path) -> dict[str, Any]:
    """loadchart.csv, summary.json, loadchart.png (a panel per payload and mode: SWL against radius, a line per Hs,
    the rated capacity and the payload)."""
    out = Path(out)
    st = result.study
    with open(out / "loadchart.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for row in result.table:
            w.writerow([f"{row[c]:.6g}" if isinstance(row[c], float) else row[c] for c in COLUMNS])
    rating = crane_rating()
    doc = {
        "study": asdict(st), "seas": [list(s) for s in result.seas], "source": result.source,
        "vessel_id": vessel_id(st.vessel), "crane": CRANE, "crane_id": crane_id(),
        "rated_capacity": {
            "radius_m": rating.radius.tolist(), "capacity_t": (rating.capacity / 1000).tolist(),
            "source": rating.source,
        },
        "checks": result.checks, "rows": len(result.table), "simulations": len(result.cells),
        "computed": result.computed, "cached": result.cached, "wall_s": result.wall_s, "workers": result.workers,
        "scheduler": result.scheduler,
    }  # fmt: skip
    (out / "summary.json").write_text(json.dumps(doc, indent=2), encoding="utf-8")
    plt = pyplot()
    n_p, n_m = len(st.payloads), len(st.modes)
    fig, axes = plt.subplots(n_p, n_m, figsize=(3.6 * n_m + 1.6, 2.9 * n_p + 0.6), squeeze=False, sharey=True)
    hs_all = sorted({r["hs"] for r in result.table})
    colours = plt.get_cmap("viridis_r")(np.linspace(0.1, 0.9, max(2, len(hs_all))))
    rr = np.linspace(min(st.radii), max(st.radii), 200)
    cap_line = [rating.at(float(r)) / 1000 for r in rr]
    for i, payload in enumerate(st.payloads):
        for j, mode in enumerate(st.modes):
            ax = axes[i, j]
            ax.plot(rr, cap_line, color="k", lw=1.2, ls="--", label="rated (calm)")
            for k, hs in enumerate(hs_all):
                rows = sorted(
                    (r for r in result.table if (r["mode"], r["payload_t"], r["hs"]) == (mode, payload, hs)),
                    key=lambda r: r["radius_m"],
                )
                # between two simulated radii the lower of their SWLs (ψ is not monotone in the radius: no figure
                # between them is drawn above what either end gives)
                xs, ys = [r["radius_m"] for r in rows], [r["swl_t"] for r in rows]
                sx, sy = [xs[0]], [ys[0]]
                for a, b, ya, yb in zip(xs, xs[1:], ys, ys[1:], strict=False):
                    sx += [a, b, b]
                    sy += [min(ya, yb), min(ya, yb), yb]
                ax.plot(sx, sy, "-", lw=1.1, color=colours[k], label=f"Hs {hs:g} m")
                ax.plot(xs, ys, "o", ms=3, color=colours[k])
            ax.axhline(payload, color="tab:red", lw=0.9, label=f"payload {payload:g} t")
            ax.set_title(f"{mode}, {payload:g} t", fontsize=9)
            ax.grid(alpha=0.3)
            if i == n_p - 1:
                ax.set_xlabel("radius [m]")
            if j == 0:
                ax.set_ylabel("SWL [t]")
            ax.set_ylim(bottom=0)
    axes[0, -1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    seeds = f"{st.seeds} seed{'s' if st.seeds > 1 else ''}"
    fig.suptitle(
        f"SWL = rated capacity / ψ, {st.spectrum}, heading {st.heading:g}°, {seeds} × {st.duration:g} s"
        f" ({result.source})",
        fontsize=10,
    )
    save_figure(plt, fig, out / "loadchart.png", dpi=110)
    return doc


def parse_list(text: str, what: str, zero: bool = False) -> tuple[float, ...]:
    """``"20,25,30"`` → (20.0, 25.0, 30.0): positive finite numbers (``zero``: or 0) (one line naming ``what``
    when not)."""
    values = []
    for part in text.split(","):
        try:
            v = float(part)
        except ValueError:
            raise LoadChartError(f"{what}: {part.strip()!r} is not a number (a comma-separated list)") from None
        if not (math.isfinite(v) and (v > 0 or (zero and v == 0))):
            raise LoadChartError(f"{what}: {part.strip()} must be a positive number" + (" or 0" if zero else ""))
        values.append(v)
    return tuple(values)
