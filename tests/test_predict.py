"""Issue 31, item 1: the crane tip's motion predicted from the motion sensor's signal alone (an AR model fitted
online, app/control/predict.py) and ``bosun sim predict``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from app.cli import main
from app.control import predict_kernels
from app.control.predict import LiftWindow, MotionPredictor, PredictError, PredictorSpec, ar_fit, ar_rows
from app.scenarios.predict import PredictScenario, PredictScenarioError, simulate_predict


def test_the_prediction_rows_iterate_the_model_and_psi_is_its_impulse_response():
    """G's rows are the model iterated on the history (newest first), ψ its impulse response: checked against a
    plain loop on a random stable AR(3)."""
    a = np.array([0.9, -0.3, 0.1])
    G, psi = ar_rows(a, 6)
    rng = np.random.default_rng(31_1)
    hist = list(rng.normal(size=3))  # newest first
    path = list(hist)
    for _ in range(6):
        path.insert(0, float(a @ np.array(path[:3])))
    np.testing.assert_allclose(G @ np.array(hist), path[:6][::-1], rtol=1e-12)
    impulse = [1.0]
    for j in range(1, 6):
        impulse.append(sum(a[i] * impulse[j - 1 - i] for i in range(min(3, j))))
    np.testing.assert_allclose(psi, impulse, rtol=1e-12)


def test_an_ar1_band_is_the_textbook_one():
    """For AR(1), σ²(h) = σ_e² (1 − a^{2h}) / (1 − a²) (Box et al. §5.2): the fit recovers a and σ_e on a long
    simulated record, and the band's rows follow."""
    rng = np.random.default_rng(31_2)
    a, sd = 0.8, 0.3
    y = np.zeros(20000)
    for k in range(1, y.size):
        y[k] = a * y[k - 1] + sd * rng.standard_normal()
    coef, var_e = ar_fit(y - y.mean(), 1)
    assert coef[0] == pytest.approx(a, abs=0.01) and math.sqrt(var_e) == pytest.approx(sd, rel=0.02)
    _, psi = ar_rows(coef, 5)
    h = np.arange(1, 6)
    np.testing.assert_allclose(np.cumsum(psi**2), (1 - coef[0] ** (2 * h)) / (1 - coef[0] ** 2), rtol=1e-12)


@pytest.mark.parametrize("ridge", [0.0, 1e-6])
def test_a_few_sines_are_predicted_seconds_ahead(ridge):
    """A sum of three sinusoids (0.6–0.9 rad/s) is an AR process of order 6.  The plain fit (no ridge) predicts it 1
    and 20 s ahead to about a hundredth of its size (what is left is the cubic between the model's 0.5 s grid
    points); the default ridge (which keeps a smooth sea record's fit well conditioned) damps the model's poles a
    little: a hundredth at 1 s, under a tenth at 5 s.  The average's delay is added to the horizon (without it the error
    would be 0.2 s of motion, about a tenth of the signal)."""
    dt = 0.1
    t = np.arange(1, 4001) * dt
    om, ph, A = np.array([0.6, 0.7, 0.9]), np.array([0.3, 1.2, 2.0]), np.array([1.0, 0.5, 0.3])
    y = (A * np.sin(np.outer(t, om) + ph)).sum(axis=1) + 5.0
    p = MotionPredictor(PredictorSpec(order=12, ridge=ridge), channels=1)
    far = 20.0 if ridge == 0 else 5.0
    errs = []
    for k in range(3000):
        p.update([y[k]])
        if k >= 2000:
            pred, _ = p.predict([1.0, far])
            errs.append(pred[:, 0] - y[[k + 10, k + round(far / dt)]])
    rms = np.sqrt(np.mean(np.square(errs), axis=0)) / np.std(y)
    assert rms[0] < 0.01 and rms[1] < (0.02 if ridge == 0 else 0.1), rms


def test_nothing_is_predicted_before_the_first_fit_and_bad_input_is_refused():
    p = MotionPredictor(PredictorSpec(), channels=2)
    p.update([0.0, 1.0])
    pred, sig = p.predict([1.0])
    assert np.all(np.isnan(pred)) and np.all(np.isnan(sig)) and not p.ready
    with pytest.raises(PredictError, match="not finite"):
        p.update([math.nan, 0.0])
    with pytest.raises(PredictError, match="horizons"):
        p.predict([25.0])
    with pytest.raises(PredictError, match="window"):
        PredictorSpec(window=20.0)


def test_the_crane_tip_is_predicted_as_the_issue_asks_on_a_short_run():
    """JONSWAP Hs 3 m, Tp 9 s, beam, seed 1, 600 s (300 scored): the error grows with the horizon, the heave and
    sway at 5 s stay under 0.55 of their size (the acceptance's 0.5 is measured on 1200 s runs, seeds 1–4, in
    docs/foresight.md), and the ±2σ band holds 85–99 % of the errors; x (along the beam sea's crests) barely moves
    and has no ratio."""
    res = simulate_predict(PredictScenario(seed=1, duration=600.0))
    s = res.summary
    z = [s["nrmse"][h]["z"] for h in ("1", "2", "5", "10", "20")]
    assert z == sorted(z) and z[0] < 0.2
    assert s["nrmse"]["5"]["z"] < 0.55 and s["nrmse"]["5"]["y"] < 0.55, s["nrmse"]["5"]
    for h in ("1", "5", "20"):
        assert 0.85 <= s["coverage"][h]["z"] <= 0.99, s["coverage"]
    assert s["nrmse"]["5"]["x"] is None and s["rms_true_m"]["x"] < 0.01


def test_sim_predict_writes_its_files_and_refuses_bad_input(capsys, tmp_path):
    code = main(["sim", "predict", "--duration", "400", "--out", str(tmp_path / "run"), "--json"])
    out, _ = capsys.readouterr()
    assert code == 0
    doc = json.loads(out)
    assert set(doc["nrmse"]) == {"1", "2", "5", "10", "20"} and doc["scenario"]["hs"] == 3.0
    for f in ("timeseries.csv", "summary.json", "predict.png"):
        assert (tmp_path / "run" / f).stat().st_size > 0
    code = main(["sim", "predict", "--duration", "100"])
    _, err = capsys.readouterr()
    assert code == 2 and "duration must be at least" in err and err.count("\n") == 1
    with pytest.raises(PredictScenarioError):
        PredictScenario(hs=-1.0)


def test_the_relative_motion_to_a_second_vessel_s_deck_is_predicted_too():
    """``target = "vessel"``: the signal is the tip less the second vessel's landing spot (its vectorised spots
    equal its pose, point by point); that spot moves, so the relative motion differs from the tip's own, and it is
    predicted as well (heave at 5 s under 0.55 on a short run)."""
    from app.scenarios.tac import TacScenario, TacSimulator
    from app.scenes.target_deck import TargetVessel

    sim = TacSimulator(TacScenario(duration=10.0))
    v = TargetVessel(None, 60.0, sim.vessel.sea, 90.0, np.array([10.0, 0.0, -8.0]))
    t = np.array([0.5, 3.0, 7.25])
    np.testing.assert_allclose(v.spots(t), [v.pose(float(x))[0] for x in t], atol=1e-12)
    own = simulate_predict(PredictScenario(seed=1, duration=500.0, warmup=300.0))
    rel = simulate_predict(PredictScenario(seed=1, duration=500.0, warmup=300.0, target="vessel"))
    assert abs(rel.summary["rms_true_m"]["z"] - own.summary["rms_true_m"]["z"]) > 0.1
    assert rel.summary["rms_true_m"]["x"] > 0.05  # the other vessel moves along x: not still
    assert rel.summary["nrmse"]["5"]["z"] < 0.55


def test_a_delay_costs_the_crane_head_its_compensation_and_prediction_gives_it_back():
    """Issue 31, item 2 in ``sim tac``: the controller seeing the MRU 0.2 s late compensates several times worse
    (the default vessel, Hs 3 m, 200 s: 0.64 % → 14.8 %); fed the motion predicted 0.2 s ahead instead, it takes
    back over nine tenths of what the delay cost (1.4 %)."""
    from app.scenarios.tac import TacScenario, simulate

    def ratio(**kw):
        return simulate(TacScenario(duration=200.0, **kw)).summary["ratio_rms"]

    r0, late, foreseen = ratio(), ratio(delay=0.2), ratio(delay=0.2, predict=True)
    assert late > 5 * r0, (r0, late)
    assert late - foreseen > 0.9 * (late - r0), (r0, late, foreseen)


def test_delay_and_predict_are_checked(capsys):
    from app.scenarios.tac import ScenarioError, TacScenario

    with pytest.raises(ScenarioError, match="delay must be in"):
        TacScenario(delay=3.0)
    with pytest.raises(ScenarioError, match="divides"):
        TacScenario(dt=0.03, predict=True)
    code = main(["sim", "tac", "--delay", "-1"])
    _, err = capsys.readouterr()
    assert code == 2 and "delay must be in [0, 2] s" in err


def test_the_crane_head_engine_takes_a_delay_and_the_prediction():
    """set_tac_delay (issue 31, item 2, the engine): Hs 3 m, tac; 0.2 s late the TCP strays several times more than
    on time; with the prediction most of it comes back; the snapshot says what is set.  The delay is set with the
    compensation off (refused while compensating: the references would jump under the machine), and switched on
    again it fades in without snatching the hanging load; a delay out of range is refused in one line."""
    from app.engine.scene import CommandError
    from tests.test_crane_target import Rig

    def stray(rig, seconds=30.0):
        e = []
        rig.run(seconds, each=lambda: e.append(rig.s.snapshot().sample.e_c))
        return float(np.sqrt(np.mean(np.square(e))))

    def switch(rig, **kw):
        rig.s.set_tac_mode("off")
        rig.run(1.0)
        rig.s.set_tac_delay(**kw)
        rig.s.set_tac_mode("tac")
        rig.run(8.0, each=lambda: tension.append(rig.s.load.tension / rig.s.load.static_tension()))

    rig = Rig(mode="tac")
    rig.run(5.0)
    on_time = stray(rig)
    with pytest.raises(CommandError, match="while the compensation is off"):
        rig.s.set_tac_delay(0.2)
    tension = []
    switch(rig, delay=0.2)
    late = stray(rig)
    snap = rig.s.snapshot()
    assert snap.delay == 0.2 and not snap.predict
    switch(rig, delay=0.2, predict=True)
    foreseen = stray(rig)
    assert rig.s.snapshot().predict
    assert late > 2.5 * on_time and foreseen < 0.5 * late, (on_time, late, foreseen)
    assert max(tension) < 1.5, max(tension)
    with pytest.raises(CommandError, match=r"delay must be in \[0, 2\] s"):
        rig.s.set_tac_delay(5.0)


def test_the_compiled_path_is_the_prediction_and_priming_is_feeding():
    """``path`` (compiled, the engines' per-tick call) equals ``predict``'s first output; ``prime`` (the past at
    once, one fit at its end) predicts as feeding the same samples one by one and fitting at the same instant."""
    rng = np.random.default_rng(31_3)
    t = np.arange(1, 3501) * 0.1
    Y = np.column_stack([np.sin(0.7 * t), np.cos(0.9 * t + 1.0)]) + 0.01 * rng.standard_normal((t.size, 2))
    a = MotionPredictor(PredictorSpec(), channels=2)
    for y in Y:
        a.update(y)
    h = np.array([0.0, 0.2, 0.27, 1.0, 5.0, 19.9])
    np.testing.assert_allclose(a.path(h), a.predict(h)[0], rtol=0, atol=1e-12)
    b = MotionPredictor(PredictorSpec(), channels=2)
    b.prime(Y)
    a._fit()  # the fed one fitted at its last sample too
    np.testing.assert_allclose(b.predict(h)[0], a.predict(h)[0], rtol=0, atol=1e-12)
    assert b._next_fit > b.t


def test_the_lab_s_vvmc_late_and_predicted():
    """Issue 31, item 2 in ``sim vvmc``: the controllers seeing both platforms 0.2 s late leave the tool tens of
    millimetres off the work point; fed the motion predicted 0.2 s ahead, about a millimetre (Hs 2 m, 40 s counted
    after the predictor's lead-in).  The lead-in is run with a delay or a prediction only."""
    from app.scenarios.vvmc import PREDICT_LEAD_IN, VvmcError, VvmcScenario, simulate

    def error(sc):
        run = simulate(sc, True)
        e = run.e_t_b2[run.t >= sc.ramp + sc.settle + sc.lead_in]
        return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))

    late = error(VvmcScenario(duration=55.0, delay=0.2))
    foreseen = error(VvmcScenario(duration=55.0, delay=0.2, predict=True))
    assert late > 0.01 and foreseen < 0.2 * late, (late, foreseen)
    assert VvmcScenario().lead_in == 0.0 and VvmcScenario(predict=True).lead_in == PREDICT_LEAD_IN
    with pytest.raises(VvmcError, match="--delay must be in"):
        VvmcScenario(delay=-0.1)


def test_lift_windows_are_scored_as_announced():
    """Issue 31, item 3's figures on a made-up record: the heave is quiet (within the threshold) from 400 to 430 s
    and from 500 to 505 s (too short for a 10 s window); the predictor said open at 405 s (right: quiet to 415 s
    and beyond) and at 600 s (wrong), and again at 407 s (inside the announced window: not a new one).  Precision
    1/2, recall 1/1 (the short quiet spell is no window), two announced."""
    from app.scenarios.predict import PredictResult, lift_windows

    sc = PredictScenario(duration=800.0, warmup=300.0)
    t = np.arange(1, 8001) * 0.1
    z = 2.0 * np.sin(0.7 * t)
    quiet = ((t >= 400) & (t < 430)) | ((t >= 500) & (t < 505))
    z[quiet] = 0.1
    true = np.column_stack([np.zeros_like(t), np.zeros_like(t), z])
    flags = np.zeros(t.size, dtype=bool)
    for at in (405.0, 407.0, 600.0):
        flags[round(at / 0.1) - 1] = True
    res = PredictResult(sc, t, true, true, np.zeros((t.size, 5, 3)), np.zeros((t.size, 5, 3)), predicted_open=flags)
    w = lift_windows(res)
    assert w["n"] == 2 and w["precision"] == 0.5 and w["n_actual"] == 1 and w["recall"] == 1.0, w


def test_the_late_sensor_reuses_the_states_already_computed():
    """With a delay of whole steps the simulator takes the late states from those it computed (the engine's tick:
    no second evaluation of the sea), equal to evaluating the sea at t − delay, across chunks smaller and larger
    than the delay."""
    from app.scenarios.tac import TacScenario, TacSimulator

    sim = TacSimulator(TacScenario(duration=60.0, delay=0.2))
    for n in (2, 2, 37, 5, 400, 1):
        t = (sim.k + 1 + np.arange(n)) * sim.scenario.dt
        got = sim._delayed(t, sim.vessel.state(t))
        want = sim.vessel.state(t - 0.2)
        np.testing.assert_allclose(got.eta, want.eta, rtol=0, atol=1e-9)
        np.testing.assert_allclose(got.nu, want.nu, rtol=0, atol=1e-9)
        sim.k += n


def test_the_lab_engine_takes_a_delay_and_the_prediction():
    """set_lab_delay (issue 31, item 2, the lab's engine): both platforms in a Hs 2 m sea, VVMC on: 0.2 s late the
    tool strays from its work point several times more than on time; with the prediction (fitted 150 s after the
    delay is set, blended in over 2 s) most of it comes back.  Set with VVMC off only (refused under it), on the
    simulated lab; the snapshot says what is set; out of range refused in one line."""
    from app.engine.lab_session import LabSession
    from app.engine.scene import CommandError
    from tests.test_safety_engine import run_lab

    def stray(ses, t, seconds=30.0):
        e = []
        for _ in range(round(seconds / 0.5)):
            t = run_lab(ses, 0.5, t0=t)
            e.append(np.asarray(ses.snapshot().tool_error_b2))
        return float(np.sqrt(np.mean(np.sum(np.square(e), axis=1)))), t

    ses = LabSession()
    try:
        for p in ses.names:
            ses.lab_platform(p, "neutral")
        t = run_lab(ses, 15.0)
        for k, p in enumerate(ses.names):
            ses.lab_source(p, "simulation", hs=2.0, tp=8.0, heading=150.0 - 60.0 * k, seed=7 + k)
            ses.lab_platform(p, "engage")
        t = run_lab(ses, 8.0, t0=t)
        ses.lab_vvmc(True)
        t = run_lab(ses, 6.0, t0=t)
        on_time, t = stray(ses, t)
        with pytest.raises(CommandError, match="while VVMC is off"):
            ses.set_lab_delay(0.2)
        with pytest.raises(CommandError, match=r"delay must be in \[0, 2\] s"):
            ses.lab_vvmc(False) or ses.set_lab_delay(5.0)
        ses.set_lab_delay(0.2)
        snap = ses.snapshot()
        assert snap.delay == 0.2 and not snap.predict
        ses.lab_vvmc(True)
        t = run_lab(ses, 6.0, t0=t)
        late, t = stray(ses, t)
        ses.lab_vvmc(False)
        ses.set_lab_delay(0.2, predict=True)
        assert ses.snapshot().predict
        ses.lab_vvmc(True)
        t = run_lab(ses, 160.0, t0=t)  # the first fit at 150 s, blended in over 2 s
        predicted, t = stray(ses, t)
        assert late > 3 * on_time, (late, on_time)
        assert predicted < 0.5 * late, (predicted, late, on_time)
    finally:
        ses.close()


def test_the_window_probability_is_the_model_s_own(monkeypatch):
    """Issue 31, item 3's rule: the probability that a signal stays within ±M for the next seconds, from the joint
    distribution of the fitted AR model's errors (their covariance through ψ), equals the share of the model's own
    simulated futures that do (an AR(2) record, 20 000 futures each way: within 0.01), for a narrow and a wide
    band; and it is NaN before the first fit."""
    rng = np.random.default_rng(1)
    sp = PredictorSpec(dt=0.1, decimate=1, order=2, window=60.0, refit=1000.0)
    y = np.zeros(700)
    for k in range(2, 700):
        y[k] = 1.6 * y[k - 1] - 0.8 * y[k - 2] + rng.normal()
    p = MotionPredictor(sp, 1)
    assert math.isnan(p.window_probability(0, 3.0, 1.0))
    for v in y[:600]:
        p.update([v])
    a, mu = p.coefficients[0], p.mean[0]
    var_e = p._psi[0][1]
    steps = math.ceil((1.0 + p.delay) / sp.step) + 1
    n = 20_000
    hist = np.tile((y[:600][::-1] - mu)[:2], (n, 1))  # newest first
    paths = np.empty((n, steps))
    for j in range(steps):
        nxt = hist @ a + rng.normal(0.0, math.sqrt(var_e), n)
        paths[:, j] = nxt
        hist = np.column_stack([nxt, hist[:, 0]])
    for half in (2.0, 4.0):
        sim = float(np.mean(np.all(np.abs(paths) <= half, axis=1)))
        model = p.window_probability(0, half, 1.0, draws=20_000)
        assert abs(model - sim) < 0.01, (half, model, sim)
        with monkeypatch.context() as m:  # the compiled call is the NumPy reference's number, draw for draw
            m.setattr(predict_kernels, "ENABLED", False)
            assert p.window_probability(0, half, 1.0, draws=20_000) == model
    with pytest.raises(PredictScenarioError, match=r"window probability must be in \[0.5, 1\)"):
        PredictScenario(window_probability=1.0)


def test_the_compiled_window_share_is_the_numpy_reference():
    """The Monte Carlo reduction of window_probability, compiled (each draw left at its first point outside), gives
    the reference's share exactly on the same draws."""
    from app.control import predict_kernels

    rng = np.random.default_rng(4)
    for J in (1, 5, 22):
        path, errors = rng.normal(0, 0.7, J), rng.normal(0, 1.0, (2000, J))
        for half in (0.1, 1.0, 2.5, 10.0):
            ref = float(np.mean(np.all(np.abs(path + errors) <= half, axis=1)))
            assert predict_kernels.within_share(path, errors, half) == ref
    path[0] = np.nan  # a NaN point is outside in both
    assert predict_kernels.within_share(path, errors, 10.0) == 0.0


def test_the_compiled_update_is_the_numpy_reference(monkeypatch):
    """``update``'s bookkeeping compiled (:func:`app.control.predict_kernels.ring_update`, the engines' per-tick
    call) leaves the ring, the last Δ's samples and the fit bit for bit as the NumPy reference does — from the
    start (fewer samples than an average's), over several channels, across refits — and a non-finite sample is
    refused by both, with nothing written."""
    if not predict_kernels.ENABLED:
        pytest.skip("numba is off (BOSUN_JIT=0): no compiled path to compare")
    sp = PredictorSpec(dt=0.1, decimate=5, order=6, window=30.0, refit=2.0, max_horizon=5.0)
    rng = np.random.default_rng(9)
    Y = np.cumsum(rng.normal(size=(400, 3)), axis=0) * 0.1
    compiled, ref = MotionPredictor(sp, 3), MotionPredictor(sp, 3)
    for i, y in enumerate(Y):
        compiled.update(y)
        with monkeypatch.context() as m:
            m.setattr(predict_kernels, "ENABLED", False)
            ref.update(y)
        if i in (0, 1, 3, 4, 5, 150, 399):
            assert compiled.k == ref.k
            assert np.array_equal(compiled._ring, ref._ring) and np.array_equal(compiled._raw, ref._raw), i
    assert compiled.ready and np.array_equal(compiled.coefficients, ref.coefficients)
    ring = compiled._ring.copy()
    for p in (compiled, ref):
        with monkeypatch.context() as m:
            m.setattr(predict_kernels, "ENABLED", p is compiled)
            with pytest.raises(PredictError, match="not finite"):
                p.update([0.0, np.nan, 0.0])
    assert compiled.k == 400 and np.array_equal(compiled._ring, ring)


def test_the_lift_window_spreads_its_refresh_over_the_ticks_after_a_model_sample(monkeypatch):
    """The lift window counts at most DRAWS_PER_CALL of its Monte Carlo draws a call (the engine's tick) and
    publishes, once all are counted, exactly the prediction and probability the model gave at its model sample —
    before the next model sample, and with the threshold in force when the refresh began."""
    import app.control.predict as predict

    rng = np.random.default_rng(12)
    t = np.arange(0.0, 420.0, 0.02)
    z = 1.2 * np.sin(0.7 * t + 0.3) + 0.5 * np.sin(1.05 * t) + 0.05 * rng.standard_normal(t.size)
    w = LiftWindow(0.02, threshold=1.5)
    w.prime(z[:15000:5])
    assert w.predictor.ready and w.probability == w.predictor.window_probability(0, 1.5, w.length)
    counted = []
    real = predict.window_count

    def spy(path, errors, lo, hi, half):
        counted.append(hi - lo)
        return real(path, errors, lo, hi, half)

    monkeypatch.setattr(predict, "window_count", spy)
    p, checked, n = w.predictor, 0, 0
    expect, began = None, False
    for i in range(15000, 17500):
        counted.clear()
        w.feed(z[i : i + 1])
        assert sum(counted) <= w.DRAWS_PER_CALL
        if w._due:  # a model sample just now: what a refresh made at once would publish
            assert expect is None and not counted  # the last refresh was published before it, on other calls
            n += 1
            w.threshold = 1.5 if n % 2 else 0.4  # the refresh begins at the next call, with this threshold
            expect, began = (p.path(w._h)[:, 0] - p.mean[0], p.window_probability(0, w.threshold, w.length)), False
        elif expect is not None and w._pending is not None and not began:
            began, w.threshold = True, 2.5  # changed while the refresh is under way: it keeps the one it began with
        elif expect is not None and w._pending is None:
            assert np.array_equal(w.mean, expect[0]) and w.probability == expect[1]
            checked, expect = checked + 1, None
    assert checked >= 8
