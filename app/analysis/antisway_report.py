"""``bosun sim antisway``: the figures and the JSON summary of the anti-swing study (issue 16, item 4)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from app.analysis.figures import figure_saver, pyplot
from app.analysis.ik_studies import write_json
from app.scenarios.vvmc import VvmcScenario


def _scalars(d: dict) -> dict:
    return {k: v for k, v in d.items() if not isinstance(v, np.ndarray)}


def save_antisway(sc: VvmcScenario, free: list[dict], study: dict, out: Path, wall_s: float) -> dict[str, Any]:
    """free_swing.png (the 4° swing with and without the law, estimate beside truth), vvmc_swing.png
    (the swing at Hs with VVMC, with and without anti-swing) and summary.json."""
    out.mkdir(parents=True, exist_ok=True)
    plt = pyplot()
    paths: list[Path] = []
    save = figure_saver(
        plt, out, f"anti-swing: LQR (L = 3 m, c = 0.1, Ts = 5 ms, scheduled) + EKF; seed {sc.seed}", paths
    )

    fig, ax = plt.subplots(1, 1, figsize=(9, 4))
    for run, colour in zip(free, ("0.5", "C3"), strict=True):
        label = "anti-swing" if run["anti_swing"] else "without"
        ax.plot(run["t"], run["swing_deg"], color=colour, lw=1.0, label=f"{label} (true)")
        if run["anti_swing"]:
            ax.plot(run["t"], run["estimate_deg"], color="C0", lw=0.8, ls="--", label="anti-swing (estimate)")
    ax.axhline(0.5, color="k", lw=0.6, ls=":", label="0.5°")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("swing from the vertical [deg]")
    ax.set_title(f"a {free[0]['initial_swing_deg']:g}° swing at L = {free[0]['wire_length_m']:g} m, platforms still")
    ax.legend(fontsize=8, loc="upper right")
    save(fig, "free_swing.png")

    plain, damped = study["runs"]
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for run, colour, label in ((plain, "0.5", "VVMC"), (damped, "C3", "VVMC + anti-swing")):
        ax[0].plot(run.t, np.degrees(run.swing[:, 0]), color=colour, lw=0.8, label=label)
        ax[1].plot(run.t, 1000 * np.linalg.norm(run.e_t_b2, axis=1), color=colour, lw=0.8, label=label)
    ax[0].set_ylabel("swing φα [deg]")
    ax[1].set_ylabel("|tool − work point| [mm]")
    ax[1].set_xlabel("t [s]")
    ax[0].set_title(f"VVMC at Hs {sc.hs:g} m, Tp {sc.tp:g} s")
    for a in ax:
        a.legend(fontsize=8, loc="upper right")
    save(fig, "vvmc_swing.png")

    doc = {
        "scenario": sc.to_dict(),
        "free_swing": [{**_scalars(r), "duration_s": float(r["t"][-1])} for r in free],
        "vvmc": study["vvmc"],
        "vvmc_antisway": study["vvmc_antisway"],
        "swing_reduction_percent": study["swing_reduction_percent"],
        "pendulum_band_reduction_percent": study["pendulum_band_reduction_percent"],
        "wall_time_s": wall_s,
        "figures": [p.name for p in paths],
    }
    write_json(doc, out / "summary.json")
    return doc
