"""Vessel motion: RAO tables, loaders, the closed-form model against the MSS reference data, time series, MRU."""

from __future__ import annotations

import numpy as np
import pytest

from app.marine.vessel import (
    MRU,
    RAOTable,
    VesselError,
    VesselMotion,
    VesselParticulars,
    load_rao,
    load_rao_csv,
    parametric_complex_rao,
    parametric_rao,
    rao_to_csv,
    significant_response,
)
from app.marine.waves import G, jonswap, wave_components

W = np.linspace(0.1, 3.2, 2000)
HEAVE, ROLL, PITCH = 2, 3, 4


# ----------------------------------------------------------------------------- reference data
def test_mss_loader_reproduces_the_table_at_its_grid_points(mss_table):
    import scipy.io

    path, table = mss_table
    raw = scipy.io.loadmat(str(path), squeeze_me=True, struct_as_record=False)["vessel"]
    w, hd = raw.motionRAO.w, raw.headings
    assert table.w.shape == (36,) and table.headings.shape == (36,)
    Wg, Hg = np.meshgrid(w, hd, indexing="ij")
    got = table(Wg, Hg)
    for dof in range(6):
        want = raw.motionRAO.amp[dof][:, :, 0] * np.exp(1j * raw.motionRAO.phase[dof][:, :, 0])
        np.testing.assert_allclose(got[dof], want, rtol=1e-12, atol=1e-12)


# Closed-form model vs the ShipX/VERES table (TAC paper's supply vessel), Hs 3 m, JONSWAP.
# Cases the closed form cannot represent are strict xfails with the measured ratio, so the
# numbers stay visible and an improved model has to update them.
_ROLL_XFAIL = (
    "1-DOF roll (ζ44 = 0.15, not tuned) gives 1.87-1.95x the table: the table's roll RAO is flat "
    "(≈0.05 rad/m over 0.4-0.75 rad/s) and 3x the wave slope at 0.3 rad/s, not a single-DOF resonance"
)
_PITCH_XFAIL = "closed form has no pitch in beam seas (k_e = 0); the table has 0.020-0.026 rad from hull asymmetry"


def _case(dof, heading, tp):
    marks = []
    if dof == ROLL and heading in (90, 135):
        marks = [pytest.mark.xfail(strict=True, reason=_ROLL_XFAIL)]
    if dof == PITCH and heading == 90:
        marks = [pytest.mark.xfail(strict=True, reason=_PITCH_XFAIL)]
    return pytest.param(dof, heading, tp, marks=marks, id=f"{['', '', 'heave', 'roll', 'pitch'][dof]}-{heading}-Tp{tp}")


@pytest.mark.parametrize(
    ("dof", "heading", "tp"),
    [_case(d, h, tp) for d in (HEAVE, ROLL, PITCH) for h in (90, 135, 180) for tp in (8, 10)],
)
def test_parametric_model_within_30_percent_of_the_mss_table(mss_table, dof, heading, tp):
    _, table = mss_table
    model = parametric_rao()
    S = jonswap(W, 3.0, tp)
    beta = np.deg2rad(heading)
    mine = significant_response(model, S, W, beta)[dof]
    ref = significant_response(table, S, W, beta)[dof]
    if ref < 1e-3:  # roll in head seas: zero in both
        assert mine < 1e-3
    else:
        assert 0.7 <= mine / ref <= 1.3, f"model {mine:.4f} vs table {ref:.4f} (ratio {mine / ref:.3f})"


# ----------------------------------------------------------------------------- closed form
def test_closed_form_long_wave_limits():
    """Very long waves: the hull follows the surface (heave 1, pitch and roll = wave slope)."""
    p = VesselParticulars()
    w = np.array([0.05])
    k = w**2 / G
    head = parametric_complex_rao(p, w, np.pi)
    assert abs(head[HEAVE, 0] - (-1.0)) < 0.01  # z down = −ζ
    assert abs(abs(head[PITCH, 0]) - k[0]) / k[0] < 0.02
    assert abs(head[ROLL, 0]) < 1e-12
    beam = parametric_complex_rao(p, w, np.pi / 2)
    assert abs(abs(beam[ROLL, 0]) - k[0]) / k[0] < 0.02
    assert abs(beam[PITCH, 0]) < 1e-12


def test_roll_peaks_at_the_natural_frequency():
    p = VesselParticulars()
    w = np.linspace(0.2, 1.5, 2001)
    roll = np.abs(parametric_complex_rao(p, w, np.full_like(w, np.pi / 2))[ROLL])
    wn = np.sqrt(G * p.gm_t) / (p.r44 * np.sqrt(1 + p.roll_added_inertia))
    assert p.roll_natural_frequency == pytest.approx(wn)
    assert abs(w[np.argmax(roll)] - wn) < 0.05


def test_more_roll_damping_means_less_roll():
    S = jonswap(W, 3.0, 9.0)
    lo = significant_response(parametric_rao(VesselParticulars(roll_damping=0.1)), S, W, np.pi / 2)[ROLL]
    hi = significant_response(parametric_rao(VesselParticulars(roll_damping=0.3)), S, W, np.pi / 2)[ROLL]
    assert hi < 0.8 * lo


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [("beam", -1.0, "beam must be a positive"), ("cb", 1.5, "cb must be in"), ("roll_damping", 0.0, "roll_damping")],
)
def test_bad_particulars(field, value, match):
    with pytest.raises(VesselError, match=match):
        VesselParticulars(**{field: value})


# ----------------------------------------------------------------------------- CSV format
def test_csv_round_trip_reproduces_the_table():
    t = parametric_rao(w=np.linspace(0.2, 2.0, 12), headings_deg=np.arange(0, 360, 30))
    back = load_rao_csv(rao_to_csv(t), "rt.csv")
    np.testing.assert_allclose(back.w, t.w, rtol=1e-6)
    np.testing.assert_allclose(back.headings, t.headings, atol=1e-9)
    Wg, Hg = np.meshgrid(t.w, t.headings, indexing="ij")
    np.testing.assert_allclose(back(Wg, Hg), t(Wg, Hg), rtol=1e-6, atol=1e-9)


def test_interpolation_is_periodic_in_heading():
    t = parametric_rao(w=np.linspace(0.2, 2.0, 12), headings_deg=np.arange(0, 360, 30))
    w = np.full(3, 0.7)
    a = t(w, np.deg2rad([345.0, -15.0, 705.0]))
    np.testing.assert_allclose(a[:, 0], a[:, 1])
    np.testing.assert_allclose(a[:, 0], a[:, 2])


def _csv(rows):
    head = "w,heading_deg," + ",".join(f"{d}_amp,{d}_phase" for d in ("surge", "sway", "heave", "roll", "pitch", "yaw"))
    return head + "\n" + "\n".join(rows) + "\n"


GOOD = "0.5,0," + ",".join(["0.1,0"] * 6)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "empty RAO file"),
        ("w,heading_deg\n1,2\n", r"<t>:1: missing column\(s\) surge_amp"),
        (
            _csv([GOOD, "0.6,0," + ",".join(["abc,0"] + ["0.1,0"] * 5)]),
            r"<t>:3: field surge_amp: 'abc' is not a number",
        ),
        (_csv([GOOD, "0.6,0," + ",".join(["-1,0"] + ["0.1,0"] * 5)]), r"<t>:3: field surge_amp: amplitude must not"),
        (_csv([GOOD, "0.6,0," + ",".join(["nan,0"] + ["0.1,0"] * 5)]), r"<t>:3: field surge_amp: 'nan' is not a fin"),
        (_csv([GOOD, "0.6,0,1"]), r"<t>:3: expected 14 fields, got 3"),
        (_csv([GOOD, "0.6,0," + ",".join(["0.1,0"] * 6), "0.6,90," + ",".join(["0.1,0"] * 6)]), "full grid"),
        (_csv([GOOD, GOOD]), "full grid|duplicate"),
    ],
)
def test_csv_errors_name_line_and_field(text, match):
    with pytest.raises(VesselError, match=match):
        load_rao_csv(text, "<t>")


def test_load_rao_file_errors(tmp_path):
    with pytest.raises(VesselError, match="no such RAO file"):
        load_rao(tmp_path / "none.csv")
    bad = tmp_path / "x.txt"
    bad.write_text("1", encoding="utf-8")
    with pytest.raises(VesselError, match="unknown RAO file type"):
        load_rao(bad)
    junk = tmp_path / "junk.mat"
    junk.write_bytes(b"not a mat file at all")
    with pytest.raises(VesselError, match=r"junk\.mat"):
        load_rao(junk)


def test_table_validation():
    w, h = np.array([0.5, 1.0]), np.array([0.0])
    with pytest.raises(VesselError, match="strictly increasing"):
        RAOTable(w[::-1], h, np.zeros((6, 2, 1)), np.zeros((6, 2, 1)))
    with pytest.raises(VesselError, match="shape"):
        RAOTable(w, h, np.zeros((6, 3, 1)), np.zeros((6, 2, 1)))


# ----------------------------------------------------------------------------- time series
@pytest.fixture(scope="module")
def motion():
    sea = wave_components("jonswap", 3.0, 9.0, np.random.default_rng(7), heading=np.deg2rad(120))
    return VesselMotion(parametric_rao(), sea)


def test_time_series_variance_matches_the_spectral_integral(motion):
    t = np.arange(0, 3600.0, 0.1)
    eta, _, _ = motion.eta_derivatives(t)
    H = parametric_rao()(motion.w, motion.sea.direction)
    want = 0.5 * np.sum((motion.sea.amplitude * np.abs(H)) ** 2, axis=1)
    for dof in (HEAVE, ROLL, PITCH):
        assert np.var(eta[:, dof]) == pytest.approx(want[dof], rel=0.05)


def test_derivatives_and_body_velocities_are_consistent(motion):
    dt = 1e-3
    t = np.arange(100.0, 130.0, dt)
    s = motion.state(t)
    _, deta, _ = motion.eta_derivatives(t)
    np.testing.assert_allclose(np.gradient(s.eta, dt, axis=0)[1:-1], deta[1:-1], atol=2e-5)
    np.testing.assert_allclose(np.gradient(s.nu, dt, axis=0)[1:-1], s.nu_dot[1:-1], atol=2e-5)
    # ν maps back to η̇ by Fossen's kinematics: ṗ = R_b^n ν₁, Θ̇ = T(Θ) ν₂
    from app.geometry import euler_zyx_to_matrix

    R = euler_zyx_to_matrix(s.eta[:, 3:6])
    np.testing.assert_allclose(np.einsum("nij,nj->ni", R, s.nu[:, :3]), deta[:, :3], atol=1e-12)
    phi, th = s.eta[:, 3], s.eta[:, 4]
    p, q, r = s.nu[:, 3], s.nu[:, 4], s.nu[:, 5]
    dpsi = (np.sin(phi) * q + np.cos(phi) * r) / np.cos(th)
    dth = np.cos(phi) * q - np.sin(phi) * r
    dphi = p + np.sin(phi) * np.tan(th) * q + np.cos(phi) * np.tan(th) * r
    np.testing.assert_allclose(np.stack([dphi, dth, dpsi], axis=1), deta[:, 3:], atol=1e-12)
    assert s.eta.shape == (t.size, 6) and np.all(np.isfinite(s.nu_dot))


def test_mru_adds_seeded_bias_and_noise(motion):
    t = np.arange(0, 200.0, 0.01)
    true = motion.state(t)
    bias = np.array([0, 0, 0.1, 0.01, 0, 0])
    sd = np.array([0, 0, 0.05, 0.002, 0.002, 0])
    m1 = MRU(np.random.default_rng(3), noise_eta=sd, bias_eta=bias).measure(true)
    m2 = MRU(np.random.default_rng(3), noise_eta=sd, bias_eta=bias).measure(true)
    np.testing.assert_array_equal(m1.eta, m2.eta)
    err = m1.eta - true.eta
    np.testing.assert_allclose(err.mean(axis=0), bias, atol=3e-3)
    np.testing.assert_allclose(err.std(axis=0), sd, rtol=0.05, atol=1e-12)
    np.testing.assert_array_equal(m1.nu, true.nu)
    with pytest.raises(VesselError, match="noise_eta must not be negative"):
        MRU(np.random.default_rng(0), noise_eta=[-1, 0, 0, 0, 0, 0])
    with pytest.raises(VesselError, match="6 finite numbers"):
        MRU(np.random.default_rng(0), bias_nu=[0, 0])


def test_a_uniform_time_grid_gives_the_direct_sum_to_rounding():
    """Issue 14, item 4: on t₀ + jΔt the motion is summed from one table of e^{iωjΔt} with e^{iωt₀} moved
    into the coefficients (a product instead of an exp per time and component); the same η, η̇, η̈ as the
    direct sum, chunk by chunk, also on a chunk shorter than the table and on an irregular grid."""
    from app.marine.vessel import VesselMotion, VesselParticulars, parametric_rao
    from app.marine.waves import wave_components

    sea = wave_components("jonswap", 3.0, 9.0, np.random.default_rng(4), n_freq=120, heading=np.radians(135))
    vessel = VesselMotion(parametric_rao(VesselParticulars()), sea)
    iw = 1j * vessel.w

    def direct(t):
        E = np.exp(1j * np.multiply.outer(t, vessel.w))
        return [(E @ (vessel._c * (iw**k)[:, None])).real for k in range(3)]

    for t in [
        (7 + np.arange(5000)) * 0.01,
        123.4 + 0.05 * np.arange(300),
        np.sort(np.random.default_rng(1).uniform(0, 90, 500)),
    ]:
        for got, want in zip(vessel.eta_derivatives(t, chunk=2048), direct(t), strict=True):
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-11 * np.abs(want).max())


def test_compiled_body_velocities_equal_the_reference():
    """ν, ν̇ from η, η̇, η̈ (Fossen eqs. 2.18, 2.29, 2.40), compiled and NumPy, on random large motions."""
    from app.marine import kernels
    from app.marine.vessel import body_velocities

    if not kernels.ENABLED:
        pytest.skip("numba off")
    rng = np.random.default_rng(9)
    eta, deta, ddeta = (rng.normal(scale=s, size=(200, 6)) for s in (0.8, 1.5, 3.0))
    for got, want in zip(kernels.body_velocities(eta, deta, ddeta), body_velocities(eta, deta, ddeta), strict=True):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


# ----------------------------------------------------------------------------- bounds (issue 27, items 6, 8, 10)
def _row(w="0.5", heading="0", heave="0.1", phase="0"):
    cells = ["0.1,0"] * 6
    cells[2] = f"{heave},{phase}"
    return f"{w},{heading}," + ",".join(cells)


@pytest.mark.parametrize(
    ("rows", "match"),
    [
        ([_row(), _row(w="0.6", heave="1e300")], r"<t>:3: field heave_amp: 1e300 m/m is outside 0 … 100 m/m"),
        ([_row(), _row(w="1e300")], r"<t>:3: field w: 1e300 rad/s is outside 0.01 … 20 rad/s"),
        ([_row(w="5e-324"), _row()], r"<t>:2: field w: 5e-324 rad/s is outside 0.01 … 20 rad/s"),
        ([_row(), _row(w="0.6", phase="1e300")], r"<t>:3: field heave_phase: 1e300 rad is outside"),
        ([_row(), _row(w="0.6", heading="1e300")], r"<t>:3: field heading_deg: 1e300 deg is outside"),
    ],
)
def test_absurd_rao_values_are_refused_with_line_and_field(rows, match):
    """Issue 27, item 8: a heave RAO of 1e300 m/m and frequencies of 1e300 or 5e-324 rad/s loaded, and the
    crane-head state went infinite.  The CSV loader (files and the protocol's set_vessel upload) names the
    line and field; the table itself (an MSS .mat file) refuses them too."""
    with pytest.raises(VesselError, match=match):
        load_rao_csv(_csv(rows), "<t>")


def test_the_rao_table_refuses_values_out_of_the_physical_bounds_whatever_its_source():
    w, h = np.array([0.5, 1.0]), np.array([0.0])
    amp, phase = np.full((6, 2, 1), 0.1), np.zeros((6, 2, 1))
    RAOTable(w, h, amp, phase)
    big = amp.copy()
    big[2, 1, 0] = 1e300
    with pytest.raises(VesselError, match=r"heave amplitude 1e\+300 m/m at w = 1 rad/s, heading 0° is above 100"):
        RAOTable(w, h, big, phase, source="v.mat")
    big = amp.copy()
    big[3, 0, 0] = 11.0
    with pytest.raises(VesselError, match=r"roll amplitude 11 rad/m .* above 10 rad/m"):
        RAOTable(w, h, big, phase)
    for bad in (np.array([5e-324, 1.0]), np.array([0.5, 1e300])):
        with pytest.raises(VesselError, match=r"outside 0\.01 … 20 rad/s"):
            RAOTable(bad, h, amp, phase)


def test_the_set_vessel_upload_refuses_an_absurd_table():
    from app.engine.scene import CommandError
    from app.engine.vessel_upload import VesselChoice

    choice = VesselChoice()
    whole = choice.take(csv=_csv([_row(), _row(w="0.6", heave="1e300")]), label="up.csv")
    with pytest.raises(CommandError, match=r"up.csv:3: field heave_amp: 1e300 m/m is outside"):
        whole.parse()  # the scene's job (off the loop in an engine) parses the whole table
    assert choice.table is None  # nothing changed


def test_an_rao_csv_with_a_byte_order_mark_loads(tmp_path):
    """Excel's "CSV UTF-8" starts the file with a BOM: it was refused ("missing column(s) w")."""
    t = parametric_rao(w=np.linspace(0.2, 2.0, 4), headings_deg=[0, 90])
    f = tmp_path / "excel.csv"
    f.write_bytes(b"\xef\xbb\xbf" + rao_to_csv(t).encode())
    np.testing.assert_allclose(load_rao(f).amp, t.amp, atol=1e-7)
    np.testing.assert_allclose(load_rao_csv("\ufeff" + rao_to_csv(t), "upload").amp, t.amp, atol=1e-7)
    f.write_bytes(b"w,caf\xe9\n")
    with pytest.raises(VesselError, match="not UTF-8 text"):
        load_rao(f)
    # the other CSV readers: a Stewart platform's motion file (the scatter diagram's: test_scatter.py)
    from app.sim.stewart import parse_timeseries_csv

    ts = parse_timeseries_csv("\ufefft,x,y,z,phi,theta,psi\n0,0,0,0,0,0,0\n1,0.1,0,0,0,0,0\n", "m.csv")
    assert ts.t.tolist() == [0.0, 1.0]


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("lpp", 1e300, r"lpp 1e\+300 m is outside 5 … 500 m"),
        ("mass", 1e300, r"mass 1e\+300 kg is outside 1000 … 1e\+09 kg"),
        ("beam", 0.01, r"beam 0.01 m is outside 1 … 100 m"),
        ("gm_l", 1e7, r"gm_l 1e\+07 m is outside"),
    ],
)
def test_particulars_have_physical_ranges(field, value, match):
    with pytest.raises(VesselError, match=match):
        VesselParticulars(**{field: value})
