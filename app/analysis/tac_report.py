"""Outputs of the crane-head simulations: CSV time series, figures like TAC paper Figs. 8–12, sweeps."""

from __future__ import annotations

import csv
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from app.analysis.figures import figure_saver, pyplot, save_figure
from app.analysis.ik_studies import write_json
from app.scenarios.tac import MODES, TacResult, TacScenario, simulate

FIGURES = ("fig08_vessel.png", "fig09_tcp_head.png", "fig10_tcp_ned.png", "fig11_error.png", "fig12_angles.png")


def write_timeseries(result: TacResult, path: Path, every: int = 1) -> None:
    """The run's samples as CSV (SI units, angles in rad); ``every`` keeps one row in ``every``."""
    names, data = result.data.columns()
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for row in data[::every]:
            w.writerow([f"{v:.6g}" for v in row])


def plot_run(result: TacResult, out: Path) -> list[Path]:
    """Figures 8–12 of the TAC paper for one run; returns the files written."""
    plt = pyplot()
    d, sc = result.data, result.scenario
    t = d.t
    title = f"Hs {sc.hs:g} m, Tp {sc.tp:g} s, heading {sc.heading:g}°, mode {sc.mode}"
    paths: list[Path] = []
    save = figure_saver(plt, out, title, paths)

    # Fig. 8: vessel η in {n}
    fig, ax = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True)
    for i, lab in enumerate(("x (surge)", "y (sway)", "z (heave)")):
        ax[0].plot(t, d.eta[:, i], lw=0.8, label=lab)
    for i, lab in enumerate(("φ (roll)", "θ (pitch)", "ψ (yaw)")):
        ax[1].plot(t, np.degrees(d.eta[:, 3 + i]), lw=0.8, label=lab)
    ax[0].set_ylabel("position [m]")
    ax[1].set_ylabel("angle [deg]")
    ax[1].set_xlabel("t [s]")
    for a in ax:
        a.legend(loc="upper right", fontsize=8, ncol=3)
        a.grid(alpha=0.3)
    save(fig, FIGURES[0])

    # Fig. 9: p_c^t and p_ref^t
    fig, ax = plt.subplots(3, 1, figsize=(9, 6.5), sharex=True)
    for i, lab in enumerate("xyz"):
        ax[i].plot(t, d.p_ref_t[:, i], lw=1.2, color="0.6", label=f"{lab}_ref^t")
        ax[i].plot(t, d.p_c_t[:, i], lw=0.8, label=f"{lab}_c^t")
        ax[i].set_ylabel(f"{lab} [m]")
        ax[i].legend(loc="upper right", fontsize=8)
        ax[i].grid(alpha=0.3)
    ax[-1].set_xlabel("t [s]")
    save(fig, FIGURES[1])

    # Fig. 10: p_c^n vs the uncompensated p_s^n, relative to p_d^n
    fig, ax = plt.subplots(3, 1, figsize=(9, 6.5), sharex=True)
    for i, lab in enumerate(("north", "east", "down")):
        ax[i].plot(t, d.p_s_n[:, i] - result.p_d_n[i], lw=0.8, color="tab:red", label="uncompensated p_s^n − p_d^n")
        ax[i].plot(t, d.p_c_n[:, i] - result.p_d_n[i], lw=0.8, label="compensated p_c^n − p_d^n")
        ax[i].set_ylabel(f"{lab} [m]")
        ax[i].legend(loc="upper right", fontsize=8)
        ax[i].grid(alpha=0.3)
    ax[-1].set_xlabel("t [s]")
    save(fig, FIGURES[2])

    # Fig. 11: e_c vs e_s (eq. 61)
    s = result.summary
    fig, ax = plt.subplots(figsize=(9, 3.8))
    ax.plot(t, d.e_s, lw=0.8, color="tab:red", label=f"e_s (rms {s['rms_e_s_m']:.3f} m)")
    ax.plot(t, d.e_c, lw=0.8, label=f"e_c (rms {s['rms_e_c_m']:.3f} m)")
    if d.saturated.any():
        ax.fill_between(t, 0, d.e_s.max(), where=d.saturated, color="orange", alpha=0.25, label="saturated")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("error [m]")
    ax.set_title(f"rms(e_c)/rms(e_s) = {s['ratio_rms']:.2%}", fontsize=9)
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3)
    save(fig, FIGURES[3])

    # Fig. 12: α and u_α
    fig, ax = plt.subplots(3, 1, figsize=(9, 6.5), sharex=True)
    for i in range(3):
        ax[i].plot(t, np.degrees(d.u[:, i]), lw=0.8, color="0.55", label=f"u_{i + 1}")
        ax[i].plot(t, np.degrees(d.alpha[:, i]), lw=0.8, label=f"α_{i + 1}")
        ax[i].set_ylabel("[deg]")
        ax[i].legend(loc="upper right", fontsize=8)
        ax[i].grid(alpha=0.3)
    ax[-1].set_xlabel("t [s]")
    save(fig, FIGURES[4])
    return paths


def save_run(result: TacResult, out: Path) -> dict[str, Any]:
    """timeseries.csv, the figures and summary.json in ``out``; returns the summary document."""
    out.mkdir(parents=True, exist_ok=True)
    write_timeseries(result, out / "timeseries.csv")
    plot_run(result, out)
    doc = {
        "scenario": result.scenario.to_dict(),
        "x_d_m": result.x_d,
        "p_d_n_m": [float(v) for v in result.p_d_n],
        "cancelled": result.cancelled,
        **result.summary,
    }
    write_json(doc, out / "summary.json")
    return doc


# ----------------------------------------------------------------------------- sweep
def parse_range(text: str) -> list[float]:
    """'a:b:step' (inclusive of b within rounding) or 'a,b,c' → values."""
    text = text.strip()
    try:
        if ":" in text:
            a, b, s = (float(x) for x in text.split(":"))
            if s <= 0 or b < a:
                raise ValueError
            n = int(np.floor((b - a) / s + 1e-9)) + 1
            return [round(a + i * s, 10) for i in range(n)]
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"'{text}' is not a range START:STOP:STEP (STEP > 0, STOP ≥ START) or a list a,b,c") from None


def _run_one(sc: TacScenario) -> dict[str, Any]:
    return {"hs": sc.hs, "mode": sc.mode, **simulate(sc).summary}


def sweep(
    base: TacScenario,
    hs_values: list[float],
    modes: tuple[str, ...] = MODES,
    *,
    jobs: int = 1,
    progress: Callable[[int, int], None] | None = None,
) -> list[dict[str, Any]]:
    """One run per (Hs, mode); rows with the summary of each."""
    scenarios = [replace(base, hs=hs, mode=m) for hs in hs_values for m in modes]
    rows: list[dict[str, Any]] = []
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as ex:
            for row in ex.map(_run_one, scenarios):
                rows.append(row)
                if progress:
                    progress(len(rows), len(scenarios))
    else:
        for sc in scenarios:
            rows.append(_run_one(sc))
            if progress:
                progress(len(rows), len(scenarios))
    return rows


def max_hs_within(rows: list[dict[str, Any]], mode: str, limit: float = 0.05) -> float | None:
    """The highest Hs up to which every run of ``mode`` has rms(e_c)/rms(e_s) ≤ limit."""
    best = None
    for r in sorted((r for r in rows if r["mode"] == mode), key=lambda r: r["hs"]):
        if r["ratio_rms"] > limit:
            break
        best = r["hs"]
    return best


def save_sweep(rows: list[dict[str, Any]], base: TacScenario, out: Path) -> dict[str, Any]:
    out.mkdir(parents=True, exist_ok=True)
    cols = ["hs", "mode", "ratio_rms", "rms_e_c_m", "rms_e_s_m", "max_e_c_m", "max_e_s_m", "saturated_pct"]
    with open(out / "sweep.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for r in rows:
            w.writerow([r[c] if isinstance(r[c], str) else f"{r[c]:.6g}" for c in cols])
    modes = sorted({r["mode"] for r in rows}, key=MODES.index)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for m in modes:
        rs = sorted((r for r in rows if r["mode"] == m), key=lambda r: r["hs"])
        ax.plot([r["hs"] for r in rs], [100 * r["ratio_rms"] for r in rs], marker="o", label=m)
    ax.axhline(5.0, color="0.4", ls="--", lw=0.8, label="5 %")
    ax.set_xlabel("Hs [m]")
    ax.set_ylabel("rms(e_c) / rms(e_s) [%]")
    ax.set_title(f"Tp {base.tp:g} s, heading {base.heading:g}°, {base.duration:g} s, seed {base.seed}", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend()
    save_figure(plt, fig, out / "sweep.png", dpi=110)
    doc = {
        "scenario": base.to_dict(),
        "rows": rows,
        "max_hs_ratio_le_5pct": {m: max_hs_within(rows, m) for m in modes},
    }
    write_json(doc, out / "sweep.json")
    return doc
