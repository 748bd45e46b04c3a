"""Issue 31, item 6: viscous roll damping by Ikeda's components (app.marine.roll_damping), in the BEM solve as
``bosun vessel rao --roll-damping ikeda``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.marine.roll_damping import BilgeKeels, IkedaHull, RollDampingError, components, out_of_range

#: the base ship of Kawahara, Maekawa & Ikeda (2011): L/B 6, B/d 4, C_B 0.65, C_M 0.98, φ_a 10°, b_BK/B 0.025,
#: l_BK/L 0.2 (Lpp 300 m); the non-dimensional friction, eddy and bilge-keel damping the authors' own program
#: (Ikeda, Kawahara & Maekawa, Roll_Damping.for, 2009) gives at OG/d and ω̂
BASE = [
    (-0.2, 0.4, 1.2149e-5, 0.000663353, 0.00376847),
    (-0.2, 0.6, 1.4880e-5, 0.00099503, 0.0056527),
    (-1.5, 0.8, 4.1966e-5, 0.00554521, 0.0214074),
    (-1.5, 1.0, 4.6920e-5, 0.00693151, 0.0267593),
]


def _base(og_d: float, keels: bool = True) -> IkedaHull:
    L, B, d = 300.0, 50.0, 12.5
    return IkedaHull(L, B, d, 0.65, 0.98, og_d * d, BilgeKeels(0.2 * L, 0.025 * B) if keels else None)


@pytest.mark.parametrize(("og_d", "w_hat", "f", "e", "bk"), BASE)
def test_the_components_are_the_published_method_s_for_its_base_ship(og_d, w_hat, f, e, bk):
    hull = _base(og_d)
    w = w_hat / math.sqrt(hull.beam / (2 * 9.81))
    c = components(hull, w, math.radians(10.0))
    assert c["friction_hat"] == pytest.approx(f, rel=1e-4)
    assert c["eddy_hat"] == pytest.approx(e, rel=1e-5) and c["bilge_keels_hat"] == pytest.approx(bk, rel=1e-5)
    assert c["lift"] == 0.0  # zero speed
    scale = 1025.0 * hull.volume * hull.beam**2 * math.sqrt(2 * 9.81 / hull.beam)
    assert c["eddy"] == pytest.approx(c["eddy_hat"] * scale, rel=1e-12)
    assert out_of_range(hull, w) == []


def test_eddy_and_keels_grow_with_the_roll_friction_barely_and_a_naked_hull_has_no_keel_damping():
    hull, w = _base(-0.2), 0.4
    small, big = components(hull, w, math.radians(5)), components(hull, w, math.radians(15))
    assert big["eddy"] == pytest.approx(3 * small["eddy"], rel=1e-9)  # B_E ∝ φ_a: the quadratic drag linearised
    assert big["bilge_keels"] > 1.5 * small["bilge_keels"]
    assert big["friction"] == pytest.approx(small["friction"], rel=1e-9)  # laminar Kato: independent of φ_a
    assert components(_base(-0.2, keels=False), w, math.radians(10))["bilge_keels"] == 0.0


def test_out_of_range_names_each_parameter_and_bad_input_is_one_line():
    hull = IkedaHull(82.8, 19.2, 6.0, 0.651, 0.728, -1.88, BilgeKeels(16.56, 0.48))  # the supply vessel's BEM hull
    assert out_of_range(hull, 0.633) == ["C_M 0.728 (range 0.9–0.99)"]
    for kw, msg in ((dict(cb=1.2), "C_B < 1"), (dict(lpp=-1), "lpp must be a positive"),
                    (dict(keels=BilgeKeels(100.0, 0.5)), "bilge keels")):  # fmt: skip
        with pytest.raises(RollDampingError, match=msg):
            IkedaHull(**{**dict(lpp=82.8, beam=19.2, draft=6.0, cb=0.651, cm=0.95, og=-1.0), **kw})
    with pytest.raises(RollDampingError, match="must be positive"):
        components(hull, 0.0, 0.1)


def test_the_bem_solve_takes_ikeda_s_damping_linearised_in_its_sea():
    """A coarse solve (fast): with Ikeda's components the viscous roll damping at ω₄ is the components' sum at
    the linearised amplitude, that amplitude is the roll the vessel makes in the sea (the fixed point), and the
    roll RAO peak is higher than with ζ44 = 0.15 (the method gives the supply vessel's hull 1–3 % of critical)."""
    pytest.importorskip("capytaine")
    from app.marine.bem import BemInputs, compute_raos
    from app.marine.roll_damping import components as comp

    coarse = dict(nx=24, nz=6, w_min=0.2, w_max=1.4, n_w=25, heading_step=90.0)
    ik = compute_raos(BemInputs(viscous="ikeda", **coarse))
    zeta = compute_raos(BemInputs(**coarse))
    info = ik.info["ikeda"]
    assert info["bilge_keels_m"] == pytest.approx([0.2 * 82.8, 0.025 * 19.2])
    assert 1 <= info["iterations"] < 100 and info["linearise_sea"] == {
        "hs": 3.0,
        "tp": 9.0,
        "heading": 90.0,
        "spectrum": "jonswap",
    }
    at = info["at_roll_natural_frequency"]
    assert ik.info["roll_viscous_damping"] == pytest.approx(sum(at.values()), rel=1e-12)  # one value, ω4's
    assert 0.005 < ik.info["roll_viscous_damping_ratio"] < 0.05
    assert info["outside_the_method_s_range"] == ["C_M 0.728 (range 0.9–0.99)"]
    hull = IkedaHull(82.8, 19.2, 6.0, 0.651, info["midship_section_coefficient"], info["og_m"],
                     BilgeKeels(*info["bilge_keels_m"]))  # fmt: skip
    w4 = ik.info["roll_natural_frequency_rad_s"]
    again = comp(hull, w4, math.radians(info["roll_amplitude_deg"]))
    assert again["eddy"] == pytest.approx(at["eddy"], rel=1e-9)
    beam = np.array([math.pi / 2])
    w = np.linspace(0.3, 1.2, 400)
    assert np.abs(ik.table(w, beam)[3]).max() > 2 * np.abs(zeta.table(w, beam)[3]).max()
    with pytest.raises(Exception, match="viscous roll damping must be one of zeta, ikeda"):
        BemInputs(viscous="tank")
    with pytest.raises(Exception, match="bilge keels 100 m"):  # refused before any solve
        BemInputs(viscous="ikeda", bilge_keels=(100.0, 0.5))
