"""Files of a transfer (``bosun sim transfer``): the time series, the figures and the summary."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from app.analysis.figures import figure_saver, pyplot
from app.analysis.ik_studies import write_json
from app.scenarios.transfer import SLACK_FACTOR, SNAP_FACTOR, TransferResult


def write_timeseries(res: TransferResult, path: Path) -> None:
    """One row per step: the columns of :data:`app.scenarios.transfer.COLUMNS` and the operator's phase."""
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow([*res.columns, "phase"])
        for row, phase in zip(res.rows, res.phases, strict=True):
            w.writerow([f"{v:.6g}" for v in row] + [phase])


def plot_transfer(res: TransferResult, out: Path) -> list[Path]:
    """transfer.png: the load's path against the commanded one in the target frame, its speed towards the deck, its
    swing and the wire's tension against their limits."""
    sc, d = res.scenario, res.rows
    c = {name: d[:, i] for i, name in enumerate(res.columns)}
    plt = pyplot()
    where = "EM1500" if sc.scene == "lab" else f"the {sc.target}"
    title = f"Transfer to {where}: {sc.mode}, Hs {sc.hs:g} m, Tp {sc.tp:g} s, heading {sc.heading:g}°, seed {sc.seed}"
    paths: list[Path] = []
    save = figure_saver(plt, out, title, paths)
    fig, ax = plt.subplots(2, 2, figsize=(11, 6.5))
    a = ax[0, 0]
    h = "y" if np.ptp(c["cmd_y"]) > np.ptp(c["cmd_x"]) else "x"  # the move's axis (the lab moves along y)
    a.plot(c[f"cmd_{h}"], -c["cmd_z"], color="0.3", lw=1.0, ls="--", label="commanded")
    a.plot(c[f"load_{h}"], -c["load_z"], color="C0", lw=0.9, label="load")
    a.axhline(0.0, color="C2", lw=2.0, label="deck")
    a.set_xlabel(f"{h} in the target frame [m]")
    a.set_ylabel("height above the deck [m]")
    a.set_title("the load's path (target frame)", fontsize=9)
    a.legend(fontsize=7)
    t = c["t"]
    a = ax[0, 1]
    a.plot(t, c["rel_speed_mps"], lw=0.8, color="C0", label="towards the deck")
    if sc.operator == "scripted":
        a.axhline(sc.lower_speed, color="0.3", lw=0.8, ls="--", label=f"commanded {sc.lower_speed:g} m/s")
    touch = np.flatnonzero(c["contact_kN"] > 0)
    if touch.size:
        a.axvline(t[touch[0]], color="C3", lw=0.8, label="touchdown")
    a.set_ylabel("m/s")
    a.set_title("the load's speed relative to the deck", fontsize=9)
    a.legend(fontsize=7)
    a = ax[1, 0]
    a.plot(t, c["swing_deg"], lw=0.8, color="C1")
    a.set_ylabel("deg")
    a.set_xlabel("t [s]")
    a.set_title("swing (the wire from the vertical)", fontsize=9)
    a = ax[1, 1]
    a.plot(t, c["tension_factor"], lw=0.8, color="C4", label="tension / static")
    a.axhline(SNAP_FACTOR, color="C3", lw=0.8, ls="--", label=f"snap {SNAP_FACTOR:g}×")
    a.axhline(SLACK_FACTOR, color="0.5", lw=0.8, ls=":", label=f"slack {SLACK_FACTOR:g}×")
    a.set_xlabel("t [s]")
    a.set_title("wire tension", fontsize=9)
    a.legend(fontsize=7)
    save(fig, "transfer.png")
    return paths


def save_transfer(res: TransferResult, out: Path, landings: dict | None, speed: float) -> dict:
    """timeseries.csv, transfer.png and summary.json in ``out``; returns the summary."""
    write_timeseries(res, out / "timeseries.csv")
    plot_transfer(res, out)
    doc = {**res.summary, "speed_x_realtime": speed}
    if landings is not None:
        doc["landings"] = landings
    write_json(doc, out / "summary.json")
    return doc
