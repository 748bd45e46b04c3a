"""Issue 17, item 1: a vessel computed, not guessed — the hull family, the boundary-element RAOs (Capytaine),
the shipped table of the default vessel, and the table against the ShipX/VERES reference (test data only)."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from app.marine.hull import HullError, HullForm, hull_panels
from app.marine.vessel import VesselError, VesselParticulars, load_rao_csv, significant_response
from app.marine.vessels import DEFAULT_VESSEL, VESSELS, shipped_table_path, vessel_label, vessel_rao
from app.marine.waves import G, jonswap

HEAVE, ROLL, PITCH = 2, 3, 4
SUPPLY = VesselParticulars()


# ----------------------------------------------------------------------------- the hull family
def test_hull_from_particulars_has_the_stated_volume_and_metacentric_heights():
    """The waterplane exponent is solved from GM_L − GM_T; integrating the surface numerically gives back
    L·B·T·C_B and BM_L − BM_T = GM_L − GM_T (the closed forms of app/marine/hull.py)."""
    v = SUPPLY
    form = HullForm.from_particulars(v.lpp, v.beam, v.draft, v.cb, v.gm_t, v.gm_l)
    x = np.linspace(-v.lpp / 2, v.lpp / 2, 4001)
    z = np.linspace(-v.draft, 0.0, 1201)
    X, Z = np.meshgrid(x, z, indexing="ij")
    vol = np.trapezoid(np.trapezoid(2 * form.half_breadth(X, Z), z, axis=1), x)
    b0 = form.half_breadth(x, np.zeros_like(x))
    i_l, i_t = np.trapezoid(2 * b0 * x**2, x), np.trapezoid(2 * b0**3 / 3, x)
    assert vol == pytest.approx(v.lpp * v.beam * v.draft * v.cb, rel=1e-4)
    assert (i_l - i_t) / vol == pytest.approx(v.gm_l - v.gm_t, rel=1e-4)
    assert 0.85 < form.cwp < 0.95 and form.cb / form.cwp == pytest.approx(form.q / (form.q + 1))
    verts, faces = hull_panels(form, 16, 4)
    assert faces.shape == (64, 4) and np.all(verts[:, 1] >= 0) and np.all(verts[:, 2] <= 0)


def test_hull_refuses_particulars_it_cannot_make_in_one_line():
    with pytest.raises(HullError, match=r"no waterplane of this family gives GM_L − GM_T = 101.456 m"):
        HullForm.from_particulars(82.8, 19.2, 6.0, 0.95, 2.144, 103.6)
    with pytest.raises(HullError, match="block coefficient"):
        HullForm(80, 20, 6, 0.9, cwp=0.8)


# ----------------------------------------------------------------------------- the BEM solver (coarse: seconds)
@pytest.fixture(scope="module")
def coarse():
    pytest.importorskip("capytaine")
    from app.marine.bem import BemInputs, compute_raos

    return compute_raos(BemInputs(nx=24, nz=6, w_min=0.05, w_max=1.2, n_w=24, heading_step=90.0))


def test_coarse_hull_long_wave_limits(coarse):
    """Very long waves: the hull rides the surface — heave 1 (z down: −ζ), surge 1 in head and following
    seas, sway 1 in beam seas, roll and pitch the wave slope."""
    t = coarse.table
    w0 = np.array(0.05)
    head, beam = t(w0, np.pi), t(w0, np.pi / 2)
    k = 0.05**2 / G
    assert abs(head[HEAVE] + 1.0) < 0.01 and abs(beam[HEAVE] + 1.0) < 0.01
    assert abs(abs(head[0]) - 1.0) < 0.02 and abs(abs(beam[1]) - 1.0) < 0.02
    assert abs(abs(head[PITCH]) - k) / k < 0.05 and abs(abs(beam[ROLL]) - k) / k < 0.05
    assert abs(head[ROLL]) < 1e-2 * k and abs(beam[PITCH]) < 1e-2 * k  # a symmetric hull (solver noise ~0.3 %)


def test_coarse_hull_rolls_at_the_natural_frequency_of_gm_t_and_r44(coarse):
    """The beam-sea roll RAO peaks at ω4 = √(ρg∇ GM_T / (m r44² + A44(ω4))) within 5 %, and that frequency
    is the closed form √(g GM_T) / (r44 √(1 + a44)) with the solver's added inertia; the total roll damping
    at ω4 is the stated 15 % of critical."""
    info, t = coarse.info, coarse.table
    v = SUPPLY
    w = np.linspace(0.3, 1.1, 801)
    roll = np.abs(t(w, np.full_like(w, np.pi / 2))[ROLL])
    peak = w[np.argmax(roll)]
    w4 = info["roll_natural_frequency_rad_s"]
    a44 = info["roll_added_inertia_kgm2"] / (v.mass * v.r44**2)
    assert w4 == pytest.approx(math.sqrt(G * v.gm_t) / (v.r44 * math.sqrt(1 + a44)), rel=1e-6)
    assert peak == pytest.approx(w4, rel=0.05)
    total = info["roll_radiation_damping"] + info["roll_viscous_damping"]
    assert total / info["roll_critical_damping"] == pytest.approx(0.15, rel=1e-9)
    assert info["roll_radiation_damping_ratio"] < 0.03  # potential flow alone: almost undamped


# ----------------------------------------------------------------------------- the shipped table
def _header(path) -> dict:
    lines = [ln[2:] for ln in path.read_text(encoding="utf-8").splitlines() if ln.startswith("# ")]
    start = next(i for i, ln in enumerate(lines) if ln == "{")
    return json.loads("\n".join(lines[start:]))


def test_the_shipped_table_loads_and_names_what_made_it():
    path = shipped_table_path()
    doc = _header(path)
    assert doc["command"].startswith("bosun vessel rao") and doc["inputs"]["cwp"] is None
    assert doc["vessel"]["lpp"] == 82.8 and doc["vessel"]["gm_l"] == 103.6 and doc["vessel"]["mass"] == 6.36e6
    table = vessel_rao()
    assert table.w.size == doc["inputs"]["n_w"] and table.headings.size == 36
    assert DEFAULT_VESSEL == "supply" and "boundary elements" in vessel_label(None)
    assert vessel_rao("supply-closed-form").amp[1].max() == 0.0  # the closed form: no sway
    with pytest.raises(VesselError, match=r"unknown vessel 'tanker': a vessel name \(supply, supply-closed-form\)"):
        vessel_rao("tanker")
    assert set(VESSELS) == {"supply", "supply-closed-form"}


@pytest.mark.slow
def test_the_shipped_table_is_what_the_command_makes(tmp_path):
    """``bosun vessel rao`` with the inputs in the shipped table's header gives the shipped table again."""
    pytest.importorskip("capytaine")
    shipped = shipped_table_path()
    doc = _header(shipped)
    out = tmp_path / "again.csv"
    argv = doc["command"].split()[1:]
    argv[argv.index("--out") + 1] = str(out)
    res = subprocess.run([sys.executable, "-m", "app", *argv], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    a = load_rao_csv(shipped.read_text(encoding="utf-8"), "shipped")
    b = load_rao_csv(out.read_text(encoding="utf-8"), "again")
    np.testing.assert_allclose(b.w, a.w) and np.testing.assert_allclose(b.headings, a.headings)
    np.testing.assert_allclose(b.amp, a.amp, rtol=1e-6, atol=1e-9)
    big = a.amp > 1e-4  # phases of vanishing amplitudes are noise
    np.testing.assert_allclose(np.exp(1j * b.phase[big]), np.exp(1j * a.phase[big]), atol=1e-5)


def test_vessel_rao_command_refuses_bad_particulars_in_one_line():
    res = subprocess.run(
        [sys.executable, "-m", "app", "vessel", "rao", "--cb", "0.95", "--out", "/tmp/never.csv"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and "no waterplane" in res.stderr


# ----------------------------------------------------------------------------- against ShipX/VERES (test data only)
W = np.linspace(0.1, 3.2, 2000)
# every ratio is reported in the README; the misses are strict xfails with the measured ratio
_MISSES = {
    (ROLL, 90, 8): 1.33, (ROLL, 90, 10): 1.36, (ROLL, 130, 8): 1.28, (ROLL, 130, 10): 1.34,
    (ROLL, 140, 8): 1.28, (ROLL, 140, 10): 1.34, (PITCH, 90, 8): 0.001, (PITCH, 90, 10): 0.001,
}  # fmt: skip
_WHY = {
    ROLL: "potential flow + ζ44 = 0.15 of critical (MSS osv.m, not tuned): 1.28-1.36x the table's roll",
    PITCH: "a fore-aft symmetric hull has no pitch in beam seas; the table has 0.020-0.026 rad",
}


def _case(dof, heading, tp):
    miss = _MISSES.get((dof, heading, tp))
    marks = [pytest.mark.xfail(strict=True, reason=f"{_WHY[dof]} (measured {miss:g})")] if miss else []
    return pytest.param(dof, heading, tp, marks=marks, id=f"{['', '', 'heave', 'roll', 'pitch'][dof]}-{heading}-Tp{tp}")


@pytest.mark.parametrize(
    ("dof", "heading", "tp"),
    [_case(d, h, tp) for d in (HEAVE, ROLL, PITCH) for h in (90, 130, 140, 180) for tp in (8, 10)],
)
def test_bem_vessel_within_15_percent_of_the_shipx_table(mss_table, dof, heading, tp):
    _, table = mss_table
    S = jonswap(W, 3.0, tp)
    beta = np.deg2rad(heading)
    mine = significant_response(vessel_rao(), S, W, beta)[dof]
    ref = significant_response(table, S, W, beta)[dof]
    if ref < 1e-3:  # roll in head seas: zero in both
        assert mine < 1e-3
    else:
        assert 0.85 <= mine / ref <= 1.15, f"BEM {mine:.4f} vs table {ref:.4f} (ratio {mine / ref:.3f})"


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"nx": 100000}, "nx must be a whole number from 4 to 200"),
        ({"nx": 200, "nz": 50}, r"200 × 50 = 10000 panels a side, more than 2000"),
        ({"n_w": 100000}, "n_w must be from 2 to 200"),
        ({"w_max": 1e300}, r"w_max ≤ 20 rad/s"),
        ({"heading_step": 0.001}, "heading step"),
    ],
)
def test_a_computation_out_of_bounds_is_refused_before_any_work(kw, match):
    """Issue 27, item 6: ``--nx 100000`` was accepted and ran without bound."""
    from app.marine.bem import BemError, BemInputs

    with pytest.raises(BemError, match=match):
        BemInputs(**kw)


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--lpp", "1e300"], r"lpp 1e\+300 m is outside 5 … 500 m"),
        (["--mass", "1e300"], r"mass 1e\+300 kg is outside"),
        (["--nx", "100000"], "nx must be a whole number from 4 to 200"),
    ],
)
def test_vessel_rao_refuses_absurd_particulars_and_meshes_in_one_line(tmp_path, argv, match):
    """Issue 27, item 6: ``--lpp 1e300`` was an OverflowError traceback, ``--mass 1e300`` four NumPy warnings
    and a whole computation before its error, ``--nx 100000`` ran without bound.  One line, exit 2, no file."""
    import re

    out = tmp_path / "r.csv"
    res = subprocess.run(
        [sys.executable, "-m", "app", "vessel", "rao", *argv, "--out", str(out)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1 and re.search(match, res.stderr), res.stderr
    assert "Traceback" not in res.stderr and "Warning" not in res.stderr and not out.exists()
