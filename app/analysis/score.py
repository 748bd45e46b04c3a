"""A training score sheet from a recorded session (issue 32, item 6): ``bosun score FILE.mcap``.

Read from the recording's published states (:mod:`app.engine.record`) of the crane-head or the Motion-Lab
engine — what the operator saw — and its E-STOPs:

* **peak dynamic factor**: the wire's largest tension over the load's weight (``load.tension_factor``), and the
  largest ψ the load chart's watch reported (``load.psi``, crane head);
* **swing**: the largest and the rms wire angle from the vertical while the load hung (not landed);
* **time over SWL**: seconds with the load at or over its safe working load in that sea (``load.swl_percent`` ≥
  100, crane head) and the largest share;
* **STOPs**: the E-STOPs applied (the recording's ``/estop``);
* **saturations**: the crane head's time saturated (``sample.saturated``) and how many times it began;
* **landings**: each touchdown's speed towards the deck (``load.rel_speed`` when ``load.landed`` rose), and the
  re-hits (``load.rehits`` at the landing's end).

Each state counts for the time to the next (the publication's period).  ``score.json`` and a one-page figure,
``score.png``.  A recording of the teleop engine has no load: refused in one line.
"""

from __future__ import annotations

import itertools
import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

from app.errors import BosunError

__all__ = ["ScoreError", "ScoreSheet", "score_figure", "score_recording", "write_score"]


class ScoreError(BosunError):
    """A recording that cannot be scored (one line)."""


@dataclass
class ScoreSheet:
    path: str
    kind: str
    duration_s: float = 0.0
    peak_tension_factor: float | None = None
    peak_psi: float | None = None
    peak_swing_deg: float | None = None
    rms_swing_deg: float | None = None
    time_over_swl_s: float | None = None
    peak_swl_percent: float | None = None
    estops: int = 0
    saturated_s: float | None = None
    saturations: int | None = None
    landing_speeds_mps: list[float] = field(default_factory=list)
    rehits: int = 0
    # the time series the figure draws (not in the JSON)
    series: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        d = asdict(self)
        d.pop("series")
        d["max_landing_speed_mps"] = max(self.landing_speeds_mps) if self.landing_speeds_mps else None
        return d


def _states(path: Path):
    from app.net.recording import RecordingError, read_recording

    try:
        yield from read_recording(path)
    except RecordingError as err:
        raise ScoreError(str(err)) from None


def score_recording(path: str | Path) -> ScoreSheet:
    """The score sheet of the recording at ``path`` (module text)."""
    path = Path(path)
    kind, estops = "", 0
    t, tension, psi, swing, swl, sat, landed, speed, rehits, estop_t = ([] for _ in range(10))
    for topic, m in _states(path):
        if topic == "/session":
            kind = m.get("kind", "")
            if kind not in ("tac", "lab"):
                raise ScoreError(f"{path}: a {kind or 'non-Bosun'} recording has no hanging load to score (the crane "
                                 "head's and the Motion-Lab's have)")  # fmt: skip
        elif topic == "/estop":
            estops += 1
            estop_t.append(t[-1] if t else 0.0)
        elif topic == "/state":
            load = m.get("load")
            if load is None:
                continue
            t.append(float(m["t"]))
            tension.append(load.get("tension_factor"))
            psi.append(load.get("psi"))
            landed.append(bool(load.get("landed")))
            swing.append(None if load.get("landed") else load.get("swing_deg"))
            swl.append(load.get("swl_percent"))
            speed.append(load.get("rel_speed", 0.0))
            rehits.append(int(load.get("rehits", 0)))
            sample = m.get("sample") or {}
            sat.append(sample.get("saturated") if kind == "tac" else None)
    if not kind:
        raise ScoreError(f"{path}: not a Bosun recording (no /session)")
    if len(t) < 2:
        raise ScoreError(f"{path}: fewer than two states with the load: nothing to score")
    dt = [b - a for a, b in itertools.pairwise(t)] + [t[-1] - t[-2]]
    sheet = ScoreSheet(str(path), kind, duration_s=t[-1] - t[0] + dt[-1], estops=estops)

    def peak(values):
        finite = [v for v in values if v is not None and math.isfinite(v)]
        return max(finite) if finite else None

    sheet.peak_tension_factor, sheet.peak_psi, sheet.peak_swing_deg = peak(tension), peak(psi), peak(swing)
    hung = [(v, d) for v, d in zip(swing, dt, strict=True) if v is not None]
    if hung:
        sheet.rms_swing_deg = math.sqrt(sum(v * v * d for v, d in hung) / max(1e-12, sum(d for _, d in hung)))
    if any(v is not None for v in swl):
        sheet.time_over_swl_s = sum(d for v, d in zip(swl, dt, strict=True) if v is not None and v >= 100.0)
        sheet.peak_swl_percent = peak(swl)
    if kind == "tac":
        flags = [bool(v) for v in sat]
        sheet.saturated_s = sum(d for v, d in zip(flags, dt, strict=True) if v)
        sheet.saturations = sum(1 for a, b in zip([False, *flags], flags, strict=False) if b and not a)
    for i in range(1, len(landed)):
        if landed[i] and not landed[i - 1]:
            sheet.landing_speeds_mps.append(abs(float(speed[i - 1] or 0.0)))  # the speed the touchdown came at
        if landed[i - 1] and not landed[i]:
            sheet.rehits += rehits[i - 1]
    if landed and landed[-1]:
        sheet.rehits += rehits[-1]
    sheet.series = {"t": t, "tension": tension, "swing": swing, "swl": swl, "sat": sat, "estops": estop_t,
                    "landings": [t[i] for i in range(1, len(landed)) if landed[i] and not landed[i - 1]]}  # fmt: skip
    return sheet


def score_figure(sheet: ScoreSheet, out: Path) -> Path:
    """The one-page figure: the numbers above, the wire's tension, the swing and the SWL share against time,
    the E-STOPs and touchdowns marked, the head's saturations shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = sheet.series
    t0 = s["t"][0]
    t = [v - t0 for v in s["t"]]
    fig, axes = plt.subplots(4, 1, figsize=(8.27, 11.0), gridspec_kw={"height_ratios": [1.1, 1, 1, 1]})
    head = axes[0]
    head.axis("off")
    fmt = lambda v, unit="", f="{:.2f}": "—" if v is None else f.format(v) + unit  # noqa: E731
    rows = [
        ("session", f"{Path(sheet.path).name} ({sheet.kind}), {sheet.duration_s:.0f} s"),
        ("peak dynamic factor", f"{fmt(sheet.peak_tension_factor, '×')} (wire), ψ {fmt(sheet.peak_psi)}"),
        ("swing", f"peak {fmt(sheet.peak_swing_deg, '°', '{:.1f}')}, rms {fmt(sheet.rms_swing_deg, '°', '{:.1f}')}"),
        (
            "time over SWL",
            f"{fmt(sheet.time_over_swl_s, ' s', '{:.0f}')} (peak {fmt(sheet.peak_swl_percent, ' %', '{:.0f}')})",
        ),
        ("STOPs", str(sheet.estops)),
        ("saturations", "—" if sheet.saturations is None else f"{sheet.saturations} ({sheet.saturated_s:.1f} s)"),
        ("landings", ", ".join(f"{v:.2f} m/s" for v in sheet.landing_speeds_mps) or "none"),
        ("re-hits", str(sheet.rehits)),
    ]
    for i, (k, v) in enumerate(rows):
        head.text(0.0, 1.0 - 0.12 * i, k, fontsize=10, weight="bold", va="top")
        head.text(0.32, 1.0 - 0.12 * i, v, fontsize=10, va="top")
    head.set_title("Bosun training score sheet", loc="left", fontsize=13)
    series = [
        (axes[1], s["tension"], "wire tension / weight", 1.5, "snap 1.5×"),
        (axes[2], s["swing"], "swing [deg]", 5.0, "limit 5°"),
        (axes[3], s["swl"], "SWL [%]", 100.0, "SWL"),
    ]
    for ax, ys, label, limit, name in series:
        pts = [(a, b) for a, b in zip(t, ys, strict=True) if b is not None]
        if pts:
            ax.plot([a for a, _ in pts], [b for _, b in pts], lw=0.8)
        ax.axhline(limit, color="tab:red", ls="--", lw=0.8, label=name)
        ax.set_ylabel(label)
        for e in s["estops"]:
            ax.axvline(e - t0, color="k", lw=1.0)
        for land in s["landings"]:
            ax.axvline(land - t0, color="tab:green", lw=0.8, ls=":")
        if any(s["sat"]):
            on = [a for a, v in zip(t, s["sat"], strict=True) if v]
            ax.plot(on, [limit] * len(on), "|", color="tab:orange", ms=6)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time [s] (black: STOP, green dotted: touchdown, orange ticks: head saturated)")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)
    plt.close(fig)
    return out


def write_score(sheet: ScoreSheet, out_dir: Path) -> tuple[Path, Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    j = out_dir / "score.json"
    j.write_text(json.dumps(sheet.to_dict(), indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return j, score_figure(sheet, out_dir / "score.png")
