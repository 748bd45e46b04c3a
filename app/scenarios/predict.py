"""``bosun sim predict`` (issue 31, item 1): the crane tip's motion predicted from the motion sensor's signal alone.

The crane-head scene's vessel in its sea (:class:`app.scenarios.tac.TacSimulator`'s vessel and MRU: the RAOs
make the truth, nothing of them goes into the prediction); the crane tip is the uncompensated TCP (the crane at
eq. 60's configuration, the head locked at p_d^t), a point fixed in {b}.  Its position in {n} computed from the
MRU's measured η (rigid-body kinematics, what a real system does with its MRU) is fed every ``spec.dt`` to
:class:`app.control.predict.MotionPredictor`; each prediction at the horizons is scored against the true
position that far ahead.

Figures, per axis of {n} (x north, y east, z down) and horizon τ:

* ``nrmse`` = rms(ŷ(t + τ | t) − y(t + τ)) / rms(y − mean y), over the scored span (from ``warmup`` on);
With ``target = "vessel"`` the signal is the tip's position relative to a second vessel's landing spot (its own RAOs
and heading in the same sea, :class:`app.scenes.target_deck.TargetVessel`): what a lift onto a moving deck must
foresee.  Its own motion is taken as measured without noise (a second MRU's link is issue 30's H105).

* ``coverage``: the share of those predictions whose error lies within the ±2σ band given with them;

both None for an axis that moves less than :data:`STILL` (a beam sea moves the tip along x by tenths of a
millimetre: the ratio would be the MRU's noise over nothing).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np
from numpy.typing import NDArray

from app.control.predict import MotionPredictor, PredictorSpec
from app.errors import BosunError
from app.geometry import euler_zyx_to_matrix
from app.marine.waves import SPECTRA, check_sea
from app.scenarios.tac import TacScenario, TacSimulator

__all__ = ["HORIZONS", "PredictResult", "PredictScenario", "lift_windows", "simulate_predict", "tip_in_body"]

HORIZONS = (1.0, 2.0, 5.0, 10.0, 20.0)  # s: the issue's
AXES = ("x", "y", "z")
#: the second vessel's landing spot from the tip in calm water (m, {n}): sim transfer's, 10 m across and 12 m
#: below (the hook 10 m down, 2 m above the deck)
TARGET_OFFSET = np.array([10.0, 0.0, 12.0])
STILL = 0.01  # m rms: an axis moving less is reported as still (no nrmse): beam seas barely move the tip along x


class PredictScenarioError(BosunError):
    """A bad ``sim predict`` setting."""


@dataclass(frozen=True)
class PredictScenario:
    hs: float = 3.0
    tp: float = 9.0
    heading: float = 90.0  # deg: 90 beam
    spectrum: str = "jonswap"
    seed: int = 1
    duration: float = 1200.0  # s
    warmup: float = 300.0  # s: scored from here on (the first fit at 150 s, the window full at 300 s)
    rao: str | None = None  # the vessel (None: the default)
    mru_noise: float = 1.0  # the MRU's noise scale (1 = 2 cm, 0.05°)
    target: str = "none"  # "vessel": predict the tip's motion relative to a second vessel's landing spot
    target_rao: str | None = None  # the second vessel (None: the crane's vessel's RAOs)
    target_heading: float = 60.0  # deg: the waves' heading to the second vessel (sim transfer's default)
    window_threshold: float = 1.0  # m: a lift window is open while the heave stays within this of its mean
    window_length: float = 10.0  # s: ... for at least this long (issue 31, item 3)
    window_probability: float = 0.95  # predicted open when the model gives the window this probability or more
    spec: PredictorSpec = field(default_factory=PredictorSpec)

    def __post_init__(self) -> None:
        try:
            check_sea(self.hs, self.tp)
        except BosunError as exc:
            raise PredictScenarioError(str(exc)) from None
        checks = [
            (self.spectrum in SPECTRA, f"spectrum must be one of {', '.join(SPECTRA)}, got '{self.spectrum}'"),
            (math.isfinite(self.heading), "heading must be a number"),
            (math.isfinite(self.warmup) and self.warmup >= 0, f"warm-up must not be negative, got {self.warmup}"),
            (
                math.isfinite(self.duration) and self.duration >= self.warmup + 2 * max(HORIZONS),
                f"duration must be at least the warm-up + 40 s ({self.warmup + 40:g} s), got {self.duration}",
            ),
            (self.duration <= 86400.0, f"duration must be at most a day, got {self.duration}"),
            (math.isfinite(self.mru_noise) and self.mru_noise >= 0, "MRU noise scale must not be negative"),
            (self.target in ("none", "vessel"), f"target must be none or vessel, got '{self.target}'"),
            (math.isfinite(self.target_heading), "target heading must be a number"),
            (
                math.isfinite(self.window_threshold) and self.window_threshold > 0,
                f"window threshold must be positive, got {self.window_threshold}",
            ),
            (
                math.isfinite(self.window_probability) and 0.5 <= self.window_probability < 1.0,
                f"window probability must be in [0.5, 1), got {self.window_probability}",
            ),
            (
                math.isfinite(self.window_length) and 1.0 <= self.window_length <= 20.0,
                f"window length must be in [1, 20] s (the prediction's reach), got {self.window_length}",
            ),
        ]
        for ok, text in checks:
            if not ok:
                raise PredictScenarioError(text)

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class PredictResult:
    scenario: PredictScenario
    t: NDArray[np.float64]  # (n,) s
    true: NDArray[np.float64]  # (n, 3) the tip in {n}
    measured: NDArray[np.float64]  # (n, 3) from the MRU
    predicted: NDArray[np.float64]  # (n, len(HORIZONS), 3): made at t for t + τ (NaN before the first fit)
    sigma: NDArray[np.float64]  # likewise, the band's σ given with each
    predicted_open: NDArray[np.bool_] | None = None  # (n,): a lift window predicted open from this sample on
    summary: dict = field(default_factory=dict)


def tip_in_body(sim: TacSimulator) -> NDArray[np.float64]:
    """The crane tip in {b}: the uncompensated TCP, the crane at eq. (60), the head at p_d^t."""
    o_t_b, R_b_t = sim.system.crane_pose(sim.beta_d)
    return o_t_b + R_b_t @ sim.system.p_d_t


def simulate_predict(
    sc: PredictScenario,
    progress: Callable[[float, float], None] | None = None,
    cancel: Callable[[], bool] | None = None,
) -> PredictResult:
    """Run the predictor over the scenario (module text)."""
    sp = sc.spec
    tac = TacScenario(
        hs=sc.hs, tp=sc.tp, heading=sc.heading, spectrum=sc.spectrum, seed=sc.seed, duration=sc.duration + 60.0,
        rao=sc.rao, mru_noise=sc.mru_noise,
    )  # fmt: skip
    sim = TacSimulator(tac)
    r_b = tip_in_body(sim)
    n = round(sc.duration / sp.dt)
    t = (1 + np.arange(n)) * sp.dt
    true_state = sim.vessel.state(t)
    meas_state = sim.mru.measure(true_state) if sim.mru is not None else true_state

    def tip(eta: NDArray[np.float64]) -> NDArray[np.float64]:
        return eta[:, :3] + np.einsum("nij,j->ni", euler_zyx_to_matrix(eta[:, 3:6]), r_b)

    true, measured = tip(true_state.eta), tip(meas_state.eta)
    if sc.target == "vessel":  # the relative motion: the tip over the second vessel's landing spot
        from app.scenes.target_deck import TargetVessel

        place = tip(np.zeros((1, 6)))[0] + TARGET_OFFSET
        spots = TargetVessel(sc.target_rao, sc.target_heading, sim.vessel.sea, sc.heading, place).spots(t)
        true, measured = true - spots, measured - spots  # its own motion sensor's noise aside
    pred = MotionPredictor(sp, channels=3)
    h = np.asarray(HORIZONS)
    P = np.full((n, h.size, 3), np.nan)
    S = np.full((n, h.size, 3), np.nan)
    opens = np.zeros(n, dtype=bool)
    for k in range(n):
        if cancel is not None and cancel():
            break
        pred.update(measured[k])
        P[k], S[k] = pred.predict(h)
        if pred.ready and k % sp.decimate == 0:  # open: the model's probability that the heave stays within
            # the threshold of its mean for the whole window (a decision on each model sample, 2 Hz)
            opens[k] = pred.window_probability(2, sc.window_threshold, sc.window_length) >= sc.window_probability
        elif pred.ready:
            opens[k] = opens[k - 1]
        if progress is not None and k % 1000 == 0:
            progress(float(t[k]), sc.duration)
    res = PredictResult(sc, t, true, measured, P, S, predicted_open=opens)
    res.summary = summarise(res)
    return res


def summarise(res: PredictResult) -> dict:
    """The figures of the module text, per horizon and axis."""
    sc, dt = res.scenario, res.scenario.spec.dt
    n = res.t.size
    k0 = round(sc.warmup / dt)
    out: dict = {"horizons_s": list(HORIZONS), "nrmse": {}, "coverage": {}, "scored_s": {}}
    for i, tau in enumerate(HORIZONS):
        lag = round(tau / dt)
        made = np.arange(k0, n - lag)
        err = res.predicted[made, i] - res.true[made + lag]
        ok = np.all(np.isfinite(err), axis=1)
        e = err[ok]
        ref = res.true[k0:] - res.true[k0:].mean(axis=0)
        rms_true = np.sqrt(np.mean(ref**2, axis=0))
        nr = np.sqrt(np.mean(e**2, axis=0)) / np.where(rms_true > 0, rms_true, np.nan)
        sig = res.sigma[made, i][ok]
        banded = np.isfinite(sig)
        inside = (np.abs(e) <= 2 * sig) & banded
        cov = inside.sum(axis=0) / np.maximum(banded.sum(axis=0), 1)
        key = f"{tau:g}"
        moves = rms_true >= STILL  # an axis that barely moves: its error is the sensor's noise, no ratio is meaningful
        out["nrmse"][key] = {a: round(float(v), 4) if m else None for a, v, m in zip(AXES, nr, moves, strict=True)}
        out["coverage"][key] = {a: round(float(v), 4) if m else None for a, v, m in zip(AXES, cov, moves, strict=True)}
        out["scored_s"][key] = round(float(ok.sum() * dt), 1)
    out["rms_true_m"] = {a: round(float(v), 4) for a, v in zip(AXES, np.sqrt(np.mean(ref**2, axis=0)), strict=True)}
    if res.predicted_open is not None:
        out["windows"] = lift_windows(res)
    return out


def _runs(flags: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """The maximal runs of True in ``flags``: (first, last + 1) each."""
    d = np.diff(np.r_[0, flags.astype(np.int8), 0])
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(), strict=True))


def _announced(flags: NDArray[np.bool_], span: int) -> list[int]:
    """The samples at which a window is announced: the first predicted-open sample, then the first after the
    announced window's end (an operator told "open for the next 10 s" is not told again within them)."""
    out: list[int] = []
    nxt = 0
    for k in np.flatnonzero(flags).tolist():
        if k >= nxt:
            out.append(k)
            nxt = k + span
    return out


def lift_windows(res: PredictResult) -> dict:
    """The lift windows (issue 31, item 3) over the scored span: a window is *open* at a sample when the heave (z)
    stays within ``window_threshold`` of its mean for the next ``window_length`` seconds; *predicted open* when
    the model gives that at least ``window_probability`` (:meth:`MotionPredictor.window_probability`: the joint
    distribution of its errors over the window; decided at that sample from what the predictor knew then).

    A predicted window is announced at the first predicted-open sample (and again only after the announced one's
    end): it is right when the heave was open from there (precision = right / announced).  An actual window is a
    run of open samples: it is found when a window was announced inside it (recall = found / actual).  ``n``
    counts the announced windows."""
    sc, dt = res.scenario, res.scenario.spec.dt
    k0, n = round(sc.warmup / dt), res.t.size
    span = round(sc.window_length / dt)
    z = res.true[:, 2]
    dev = np.abs(z - z[k0:].mean()) <= sc.window_threshold
    # open at k: every sample k … k + span within the threshold (a running count of the samples outside it)
    outside = np.r_[0, np.cumsum(~dev)]
    last = n - span
    actual = np.zeros(n, dtype=bool)
    actual[:last] = (outside[span + 1 : n + 1] - outside[:last]) == 0
    predicted = res.predicted_open.copy()
    predicted[:k0] = False
    predicted[last:] = False
    actual[:k0] = False
    pw, aw = _announced(predicted, span), _runs(actual)
    right = sum(bool(actual[a]) for a in pw)
    found = sum(any(a <= p < b for p in pw) for a, b in aw)
    return {
        "threshold_m": sc.window_threshold,
        "length_s": sc.window_length,
        "n": len(pw),
        "precision": round(right / len(pw), 4) if pw else None,
        "n_actual": len(aw),
        "recall": round(found / len(aw), 4) if aw else None,
        "open_share_actual": round(float(actual[k0:last].mean()), 4) if last > k0 else None,
    }
