"""Files of a VVMC run: time series CSV, figures and the JSON summary (``bosun sim vvmc``)."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from app.analysis.figures import figure_saver, pyplot
from app.analysis.ik_studies import write_json
from app.scenarios.vvmc import VvmcRun, VvmcScenario, summarize

DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")


def write_timeseries(on: VvmcRun, off: VvmcRun, path: Path, every: int = 1) -> None:
    """Both runs side by side, one row per sample (SI units, angles in rad)."""
    names = ["t"]
    names += [f"em8000_{d}" for d in DOFS] + [f"em1500_{d}" for d in DOFS]
    names += [f"q{k + 1}" for k in range(3)] + [f"q{k + 1}_dot" for k in range(3)]
    names += [f"e_{a}_b2" for a in "xyz"] + ["L_w", "L_w_dot", "swing_alpha", "swing_beta", "payload_height_error"]
    names += [f"e_{a}_b2_uncomp" for a in "xyz"] + ["swing_alpha_uncomp", "swing_beta_uncomp"]
    n = min(on.t.size, off.t.size)
    cols = [on.t[:n, None], on.eta1[:n], on.eta2[:n], on.q[:n], on.qd[:n], on.e_t_b2[:n]]
    cols += [on.L_w[:n, None], on.L_w_dot[:n, None], on.swing[:n], on.height_error[:n, None]]
    cols += [off.e_t_b2[:n], off.swing[:n]]
    data = np.hstack(cols)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for row in data[::every]:
            w.writerow([f"{v:.6g}" for v in row])


def plot_runs(sc: VvmcScenario, on: VvmcRun, off: VvmcRun, out: Path) -> list[Path]:
    plt = pyplot()
    title = f"VVMC: Hs {sc.hs:g} m, Tp {sc.tp:g} s, headings {sc.heading1:g}°/{sc.heading2:g}°, seed {sc.seed}"
    paths: list[Path] = []
    save = figure_saver(plt, out, title, paths)

    t = on.t
    fig, ax = plt.subplots(2, 2, figsize=(11, 5.5), sharex=True)
    for k, (eta, name) in enumerate(((on.eta1, "EM8000"), (on.eta2, "EM1500"))):
        for i in range(3):
            ax[0, k].plot(t, eta[:, i], lw=0.8, label=DOFS[i])
            ax[1, k].plot(t, np.degrees(eta[:, 3 + i]), lw=0.8, label=DOFS[3 + i])
        ax[0, k].set_title(f"{name} η (platform frame, z down)")
        ax[0, k].set_ylabel("m")
        ax[1, k].set_ylabel("deg")
        ax[1, k].set_xlabel("t [s]")
        ax[0, k].legend(fontsize=7, loc="upper right")
        ax[1, k].legend(fontsize=7, loc="upper right")
    save(fig, "platforms.png")

    fig, ax = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    for i, a in enumerate("xyz"):
        ax[i].plot(off.t, 100 * off.e_t_b2[:, i], lw=0.8, color="0.6", label="without compensation")
        ax[i].plot(t, 100 * on.e_t_b2[:, i], lw=0.9, color="C3", label="VVMC")
        ax[i].set_ylabel(f"{a} in {{b2}} [cm]")
    ax[0].set_title("tool point relative to EM1500 (minus the work point)")
    ax[0].legend(fontsize=8, loc="upper right")
    ax[-1].set_xlabel("t [s]")
    save(fig, "tool_error.png")

    fig, ax = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    ax[0].plot(t, np.degrees(on.q), lw=0.8)
    ax[0].legend(["q1", "q2", "q3"], fontsize=8, loc="upper right")
    ax[0].set_ylabel("joints [deg]")
    ax[1].plot(t, on.L_w, lw=0.8, color="C2")
    ax[1].set_ylabel("wire L_w [m]")
    ax[2].plot(t, np.degrees(on.swing), lw=0.8)
    ax[2].plot(off.t, np.degrees(off.swing[:, 0]), lw=0.6, color="0.6")
    ax[2].legend(["φα (VVMC)", "φβ (VVMC)", "φα without"], fontsize=8, loc="upper right")
    ax[2].set_ylabel("swing [deg]")
    ax[-1].set_xlabel("t [s]")
    save(fig, "robot_winch_load.png")
    return paths


def save_runs(sc: VvmcScenario, on: VvmcRun, off: VvmcRun, out: Path, speed: float | None = None) -> dict[str, Any]:
    out.mkdir(parents=True, exist_ok=True)
    write_timeseries(on, off, out / "timeseries.csv")
    plot_runs(sc, on, off, out)
    doc = {"scenario": sc.to_dict(), "cancelled": on.cancelled or off.cancelled, **summarize(sc, on, off)}
    if speed is not None:
        doc["speed_x_realtime"] = speed
    write_json(doc, out / "summary.json")
    return doc
