"""Files of ``bosun sim predict``: the figure (the prediction 5 s ahead with its ±2σ band against the truth, and
the error per horizon), ``timeseries.csv`` and ``summary.json``."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from app.analysis.figures import figure_saver, pyplot
from app.analysis.ik_studies import write_json
from app.scenarios.predict import AXES, HORIZONS, PredictResult


def write_timeseries(res: PredictResult, path: Path) -> None:
    """Every sample: t, the tip in {n} (true and measured), and per horizon and axis the prediction made then for
    that far ahead, and its σ."""
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        head = ["t", *(f"true_{a}" for a in AXES), *(f"measured_{a}" for a in AXES)]
        for h in HORIZONS:
            head += [f"pred{h:g}s_{a}" for a in AXES] + [f"sigma{h:g}s_{a}" for a in AXES]
        w.writerow(head)
        for k in range(res.t.size):
            row = [res.t[k], *res.true[k], *res.measured[k]]
            for i in range(len(HORIZONS)):
                row += [*res.predicted[k, i], *res.sigma[k, i]]
            w.writerow([f"{v:.6g}" for v in row])


def plot_predict(res: PredictResult, out: Path) -> list[Path]:
    """predict.png: the heave (z) 5 s ahead against the truth with the band over 120 s of the scored span, and the
    nrmse per horizon for each axis."""
    sc = res.scenario
    plt = pyplot()
    paths: list[Path] = []
    title = (
        f"Crane-tip motion predicted from the MRU: {sc.spectrum}, Hs {sc.hs:g} m, Tp {sc.tp:g} s, heading "
        f"{sc.heading:g}°, seed {sc.seed}"
    )
    save = figure_saver(plt, out, title, paths)
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [2.2, 1]})
    i5 = HORIZONS.index(5.0)
    lag = round(5.0 / sc.spec.dt)
    k0 = round(sc.warmup / sc.spec.dt)
    k1 = min(res.t.size - lag, k0 + round(120.0 / sc.spec.dt))
    k = np.arange(k0, k1)
    t_at = res.t[k + lag]
    up = -1.0  # NED z down: draw heave up
    p, s = up * res.predicted[k, i5, 2], res.sigma[k, i5, 2]
    a = ax[0]
    a.fill_between(t_at, p - 2 * s, p + 2 * s, color="C0", alpha=0.2, lw=0, label="±2σ band")
    a.plot(t_at, up * res.true[k + lag, 2], color="0.2", lw=1.0, label="true")
    a.plot(t_at, p, color="C0", lw=1.0, label="predicted 5 s before")
    a.set_xlabel("t [s]")
    a.set_ylabel("crane tip heave, up [m]")
    a.legend(fontsize=8, loc="upper right")
    a.set_title("heave 5 s ahead", fontsize=9)
    a = ax[1]
    for name in AXES:
        nr = [res.summary["nrmse"][f"{h:g}"][name] for h in HORIZONS]
        if None not in nr:  # an axis that barely moves has none
            a.plot(HORIZONS, nr, marker="o", label=f"{name}")
    a.axhline(0.5, color="0.5", lw=0.8, ls="--", label="0.5 (issue 31, at 5 s)")
    a.set_xlabel("horizon [s]")
    a.set_ylabel("nrmse")
    a.set_xscale("log")
    a.set_xticks(HORIZONS, [f"{h:g}" for h in HORIZONS])
    a.legend(fontsize=8)
    a.set_title("error per horizon", fontsize=9)
    save(fig, "predict.png")
    return paths


def save_predict(res: PredictResult, out: Path, wall_s: float) -> dict:
    """All files into ``out``; returns summary.json's document."""
    out.mkdir(parents=True, exist_ok=True)
    write_timeseries(res, out / "timeseries.csv")
    figures = plot_predict(res, out)
    sc = res.scenario
    doc = {
        "scenario": {k: v for k, v in sc.to_dict().items() if k != "spec"},
        "predictor": sc.spec.__dict__ | {"method": "AR(p) fitted online by least squares (Box et al. §5)"},
        **res.summary,
        "wall_s": round(wall_s, 3),
        "files": ["timeseries.csv", "summary.json", *(p.name for p in figures)],
    }
    write_json(doc, out / "summary.json")
    return doc
