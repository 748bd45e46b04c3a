"""Solid drawings of the machines (app/models/drawing.py): closed meshes, geometry where asked, every
machine the right way up, the Comau on its pedestal and the load above EM1500's deck."""

import math

import numpy as np
import pytest

from app.errors import RobotXmlError
from app.geometry import euler_zyx_to_matrix
from app.models import drawing as dr
from app.models.delta import DeltaHead
from app.models.registry import list_robots, load_spec
from app.models.serial import SerialRobot
from app.models.xml import parse_robot_xml
from app.scenes.lab import MotionLab


def _solids(rng):
    R = euler_zyx_to_matrix(rng.uniform(-np.pi, np.pi, 3))
    return [
        dr.cylinder(rng.normal(size=3), rng.normal(size=3) + 3, 0.3),
        dr.cylinder([0, 0, 0], [0, 0, -2], 0.1, n=5),
        dr.box(rng.normal(size=3), R, [0.5, 1.0, 2.0]),
        dr.sphere(rng.normal(size=3), 0.7),
        dr.sphere([0, 0, 0], 1.0, n=7),
        dr.disc([1, 2, 3], rng.normal(size=3), 1.0, 0.1),
        dr.plate(rng.normal(size=(6, 3)) * [1, 1, 0], [0, 0, 1], 0.1, margin=0.2),
        dr.hull_mesh(82.8, 19.2, -3.0, 6.0),
    ]


# ---------------------------------------------------------------------------------------------- primitives
def test_solids_are_closed_finite_and_face_outwards(rng):
    for _ in range(5):
        for m in _solids(rng):
            assert dr.is_closed(m), m.name
            assert np.all(np.isfinite(m.vertices))
            assert m.faces.min() >= 0 and m.faces.max() < len(m.vertices)
            assert dr.signed_volume(m) > 0, m.name  # outward normals


def test_cylinder_ends_where_asked_with_its_radius(rng):
    for _ in range(20):
        p0, p1 = rng.normal(size=3), rng.normal(size=3) * 3
        r, n = rng.uniform(0.01, 1.0), int(rng.integers(3, 30))
        m = dr.cylinder(p0, p1, r, n)
        np.testing.assert_allclose(m.vertices[-2], p0, atol=1e-12)  # the end-face centres
        np.testing.assert_allclose(m.vertices[-1], p1, atol=1e-12)
        axis = (p1 - p0) / np.linalg.norm(p1 - p0)
        rel = m.vertices[:-2] - p0
        along = rel @ axis
        np.testing.assert_allclose(np.sort(along), np.r_[np.zeros(n), np.full(n, np.linalg.norm(p1 - p0))], atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(rel - np.outer(along, axis), axis=1), r, rtol=1e-12)
        # a regular n-gon prism: V = n/2 r² sin(2π/n) L
        expected = n / 2 * r**2 * math.sin(2 * math.pi / n) * np.linalg.norm(p1 - p0)
        assert dr.signed_volume(m) == pytest.approx(expected, rel=1e-9)


def test_box_and_sphere_volumes():
    assert dr.signed_volume(dr.box([1, 2, 3], np.eye(3), [1, 2, 3])) == pytest.approx(6.0)
    v = dr.signed_volume(dr.sphere([0, 0, 0], 1.0, n=48))
    assert 0.97 * 4 / 3 * math.pi < v < 4 / 3 * math.pi


def test_merge_keeps_face_indices_valid(rng):
    parts = _solids(rng)
    m = dr.merge(parts)
    assert len(m.vertices) == sum(len(p.vertices) for p in parts)
    assert len(m.faces) == len(m.face_colors) == sum(len(p.faces) for p in parts)
    assert m.faces.min() == 0 and m.faces.max() == len(m.vertices) - 1
    start = 0
    for p in parts:  # every part's triangles are the same points after the merge
        f = m.faces[start : start + len(p.faces)]
        np.testing.assert_array_equal(m.vertices[f], p.vertices[p.faces])
        np.testing.assert_array_equal(m.face_colors[start : start + len(p.faces)], p.colors())
        start += len(p.faces)
    assert dr.is_closed(m)
    empty = dr.merge([])
    assert empty.vertices.shape == (0, 3) and empty.faces.shape == (0, 3)


def test_outline_is_the_convex_silhouette_without_a_repeated_point():
    m = dr.box([0, 0, 0], np.eye(3), [2, 4, 6])
    side = dr.outline(m, (0, 2))
    assert len(side) == 4 and len({tuple(p) for p in side}) == 4
    np.testing.assert_allclose(np.sort(np.abs(side), axis=0), [[1, 3]] * 4)
    flat = dr.outline(dr.cylinder([0, 0, 0], [0, 0, 1], 0.5), ((1, 0, 0), (0, 1, 0)))  # seen along its axis
    assert len(flat) == 12
    assert len(dr.outline(dr.Mesh(np.zeros((3, 3)), [[0, 1, 2]]))) == 1


def test_dedupe_drops_consecutive_repeats_only():
    p = np.array([[0, 0, 0], [0, 0, 0], [1, 0, 0], [1, 0, 0], [0, 0, 0]], float)
    np.testing.assert_array_equal(dr.dedupe(p), [[0, 0, 0], [1, 0, 0], [0, 0, 0]])


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: dr.cylinder([0, 0, 0], [0, 0, 0], 1.0), "zero length"),
        (lambda: dr.cylinder([0, 0, 0], [0, 0, 1], 0.0), "positive radius"),
        (lambda: dr.cylinder([0, 0, np.nan], [0, 0, 1], 1.0), "not finite"),
        (lambda: dr.box([0, 0, 0], np.eye(3), [1, -1, 1]), "positive edge"),
        (lambda: dr.sphere([0, 0, 0], -1.0), "positive radius"),
        (lambda: dr.plate(np.zeros((6, 3)), [0, 0, 1], 0.1), "around its centroid"),
        (lambda: dr.hull_mesh(80, 20, 6.0, -3.0), "keel below its deck"),
        (lambda: dr.up_rotation("down"), "up must be one of"),
        (lambda: dr.stewart_meshes(np.zeros((5, 3)), np.ones((6, 3))), "six base and six top"),
        (lambda: dr.serial_robot_meshes(load_spec("scara").serial.links, np.tile(np.eye(4), (2, 1, 1))), "frames"),
    ],
)
def test_bad_input_is_refused(call, match):
    with pytest.raises(ValueError, match=match):
        call()


# ---------------------------------------------------------------------------------------------- the right way up
def test_up_rotations_are_proper_and_turn_up_into_z():
    for axis, v in {"+x": [1, 0, 0], "-x": [-1, 0, 0], "+y": [0, 1, 0], "-y": [0, -1, 0], "-z": [0, 0, -1]}.items():
        R = dr.up_rotation(axis)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
        assert np.linalg.det(R) == pytest.approx(1.0)
        np.testing.assert_allclose(R @ v, [0, 0, 1], atol=1e-15)


def test_the_offshore_crane_file_says_its_frame_is_z_down():
    assert load_spec("offshore_crane").serial.up == "-z"
    assert load_spec("comau_smart5_3dof").serial.up == "+z"
    xml = load_spec("offshore_crane").path
    with open(xml, encoding="utf-8") as fh:
        text = fh.read().replace('up="-z"', 'up="down"')
    with pytest.raises(RobotXmlError, match="up"):
        parse_robot_xml(text, "bad.xml")


def _display_frames(name, q=None):
    spec = load_spec(name)
    robot = SerialRobot(spec)
    q = np.clip(np.zeros(robot.n_joints), robot.lower, robot.upper) if q is None else q
    T = np.eye(4)
    T[:3, :3] = dr.up_rotation(spec.serial.up)
    return spec, np.einsum("ij,kjl->kil", T, robot.frames(q))


def test_offshore_crane_at_zero_has_its_boom_tip_above_its_base():
    """TAC paper Table 3: frame 1 is the crane base on deck (3 m above CO), the boom foot 3 m higher (L_0),
    the jib tip at the boom's height at q = 0; drawn from the XML in a z-up frame they are above the base."""
    spec, F = _display_frames("offshore_crane", np.zeros(3))
    meshes = dr.serial_robot_meshes(spec.serial.links, F)
    by = {m.name: m for m in meshes}
    base_z = by["base"].vertices[:, 2].max()
    assert F[1, 2, 3] == pytest.approx(3.0)  # the deck is up, not down
    assert F[3, 2, 3] == pytest.approx(6.0) and F[4, 2, 3] == pytest.approx(6.0)  # boom and jib tips
    assert F[3, 2, 3] > base_z + 2.0
    assert by["link 3"].vertices[:, 2].max() > base_z + 2.0  # the boom's solid, not only its frame
    assert by["base"].vertices[:, 2].min() >= F[1, 2, 3] - 1.0  # the base plate sits on the deck
    # the same chain without the file's 'up' is upside down: the test can tell
    raw = SerialRobot(spec).frames(np.zeros(3))
    assert raw[3, 2, 3] < raw[1, 2, 3]


@pytest.mark.parametrize("name", [n for n in list_robots() if load_spec(n).serial is not None])
def test_every_serial_robot_stands_on_a_vertical_first_axis(name):
    spec, F = _display_frames(name)
    first = next(i for i, link in enumerate(spec.serial.links) if link.kind != "fixed")
    assert F[first, 2, 2] > 0.99  # its first joint turns about the display's up axis
    meshes = dr.serial_robot_meshes(spec.serial.links, F)
    assert all(dr.is_closed(m) and np.all(np.isfinite(m.vertices)) for m in meshes)
    base = next(m for m in meshes if m.name == "base")
    links = np.concatenate([m.vertices for m in meshes if m.name.startswith("link")])
    assert np.median(links[:, 2]) > base.vertices[:, 2].min()


def test_dh_link_with_d_and_a_is_drawn_as_an_l():
    spec, F = _display_frames("comau_smart5_3dof", np.zeros(3))
    link1 = [m for m in dr.serial_links(F, 0.1, [lk.kind for lk in spec.serial.links]) if m.name == "link 1"]
    cyl = [m for m in link1 if "bend" not in m.name]
    assert len(cyl) == 2  # d = 0.830 up, then a = 0.350 out
    np.testing.assert_allclose(np.linalg.norm(cyl[0].vertices[-1] - cyl[0].vertices[-2]), 0.830)
    np.testing.assert_allclose(np.linalg.norm(cyl[1].vertices[-1] - cyl[1].vertices[-2]), 0.350)
    origins = dr.serial_links(F[:, :3, 3], 0.1)  # only origins: straight links
    assert sum(m.name == "link 1" for m in origins) == 1


# ---------------------------------------------------------------------------------------------- parallel machines
def test_delta_rods_and_arms_have_their_lengths():
    """TAC Table 4 head at its simulated arm angles: arms l_a from the shoulders, rods l_r to the plate."""
    spec = load_spec("tac_delta_head")
    head = DeltaHead(spec)
    d = spec.delta
    for alpha in ([0.0, 0.0, 0.0], [0.3, -0.2, 0.5], [-0.05, -0.18, -0.05]):
        p = head.fk(np.array(alpha))
        meshes = dr.delta_meshes(d, alpha, p)
        arms = [m for m in meshes if m.name.startswith("head arm")]
        rods = [m for m in meshes if m.name.startswith("head rod")]
        assert len(arms) == 3 and len(rods) == 6
        for m in arms:
            assert np.linalg.norm(m.vertices[-1] - m.vertices[-2]) == pytest.approx(d.l_a)
            assert np.linalg.norm(m.vertices[-2]) == pytest.approx(d.l_k)  # the shoulder on the base circle
        for m in rods:
            assert np.linalg.norm(m.vertices[-1] - m.vertices[-2]) == pytest.approx(d.l_r, rel=1e-9)
        assert all(dr.is_closed(m) for m in meshes)


def test_stewart_legs_join_the_joints_and_the_deck_holds_the_top_joints():
    plat = load_spec("em1500").stewart
    base, top = plat.base_joints_n * [1, 1, -1], plat.platform_joints_b * [1, 1, -1] + [0, 0, -1.2]  # z up
    top = top + [0, 0, 2.4]
    meshes = dr.stewart_meshes(base, top, name="em1500")
    by = {m.name: m for m in meshes}
    for k in range(6):
        np.testing.assert_allclose(by[f"em1500 leg {k + 1}"].vertices[-2], base[k], atol=1e-12)
        np.testing.assert_allclose(by[f"em1500 rod {k + 1}"].vertices[-1], top[k], atol=1e-12)
    deck = by["em1500 deck"]
    assert deck.vertices[:, 2].max() == pytest.approx(top[0, 2])  # its top face in the joint plane
    assert deck.vertices[:, 2].min() < top[0, 2]  # the slab towards the base
    assert by["em1500 base"].vertices[:, 2].max() == pytest.approx(base[0, 2])
    assert all(dr.is_closed(m) for m in meshes)


# ---------------------------------------------------------------------------------------------- the lab
def _lab_scene(neutral: bool = False):
    from app.engine.lab_session import LabSession

    s = LabSession()
    if neutral:
        for name in s.names:
            s.lab_platform(name, "neutral")
        for _ in range(600):
            s.lab.step(0.01)
    return s, s.snapshot().scene


def _lab_meshes(s, sc):
    desc = s.describe()
    links = parse_robot_xml(desc.comau_xml).serial.links
    legs = {p.name: p.leg_range[0] for p in desc.platforms}
    plats = [(n, np.array(p["base"]), np.array(p["top"]), legs[n]) for n, p in sc.platforms.items()]
    return dr.lab_meshes(plats, links, np.array(sc.robot_frames), sc.payload)


def test_lab_scene_robot_points_repeat_nothing_and_match_its_frames():
    _, sc = _lab_scene()
    pts = np.array(sc.robot)
    assert np.all(np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-6)  # a repeat drew a stray bar
    F = np.array(sc.robot_frames)
    np.testing.assert_allclose(dr.dedupe(F[:, :3, 3]), pts, atol=1e-4)
    np.testing.assert_allclose(F[-1, :3, 3], sc.tool, atol=1e-3)  # the chain ends at the sim's tool point


@pytest.mark.parametrize("neutral", [False, True], ids=["settled", "neutral"])
def test_comau_stands_on_a_pedestal_that_meets_its_base(neutral):
    """The calibrated H^b1_r puts the Comau base 1.02 m above EM8000's platform frame (Motion-Lab Table 5):
    a pedestal fills the gap, from the deck plane to the base frame's origin."""
    s, sc = _lab_scene(neutral)
    meshes = {m.name: m for m in _lab_meshes(s, sc)}
    ped = meshes["pedestal"]
    F0 = np.array(sc.robot_frames)[0]
    np.testing.assert_allclose(ped.vertices[-1], F0[:3, 3], atol=1e-9)  # its top face centre is the robot base
    top = np.array(sc.platforms["em8000"]["top"])
    c = top.mean(axis=0)
    _, _, vt = np.linalg.svd(top - c)
    n = vt[-1] * np.sign(vt[-1][2])
    assert abs((ped.vertices[-2] - c) @ n) < 1e-9  # its foot in the deck's top plane
    assert (F0[:3, 3] - c) @ n == pytest.approx(1.02, abs=0.01)
    # on the drawn deck: the foot flange inside the deck's outline seen from above
    poly = dr.outline(meshes["em8000 deck"], (0, 1))
    for q in meshes["pedestal foot"].vertices[:, :2]:
        edges = np.roll(poly, -1, axis=0) - poly
        assert np.all(edges[:, 0] * (q[1] - poly[:, 1]) - edges[:, 1] * (q[0] - poly[:, 0]) >= -1e-9)
    assert dr.is_closed(ped)


@pytest.mark.parametrize("neutral", [False, True], ids=["settled", "neutral"])
def test_the_load_hangs_above_em1500s_deck_at_rest(neutral):
    s, sc = _lab_scene(neutral)
    meshes = {m.name: m for m in _lab_meshes(s, sc)}
    load, deck = meshes["load"], meshes["em1500 deck"]
    assert load.vertices[:, 2].min() > deck.vertices[:, 2].max()
    # and over the deck, not beside it
    top = np.array(sc.platforms["em1500"]["top"])
    assert np.linalg.norm(np.array(sc.payload[:2]) - top[:, :2].mean(axis=0)) < 0.8
    assert not s._payload_below_deck()


def test_lab_at_rest_matches_the_layout_file():
    """The wire of robots/labs/motionlab.xml starts at 1.8 m: with both platforms SETTLED (at the lab's
    settled heave) the tool is 2.77 m above EM1500's platform frame, so the load hangs 0.97 m above it
    (its assumptions)."""
    s, sc = _lab_scene()
    lab: MotionLab = s.lab
    H2 = lab.platform_pose(1)
    tool_b2 = H2[:3, :3].T @ (np.array(sc.tool) - H2[:3, 3])
    load_b2 = H2[:3, :3].T @ (np.array(sc.payload) - H2[:3, 3])
    assert -tool_b2[2] == pytest.approx(2.77, abs=0.01)  # z-down body frame
    assert -load_b2[2] == pytest.approx(0.97, abs=0.01)


# ---------------------------------------------------------------------------------------------- vessel and sea
def test_wave_elevation_matches_the_sea_model(rng):
    from app.marine.waves import wave_components

    sea = wave_components("jonswap", 3.0, 9.0, rng, heading=0.7)
    t = 12.3
    for x, y in rng.normal(scale=50, size=(5, 2)):
        ref = sea.elevation(np.array([t]), x, y)[0]
        mine = dr.wave_elevation(sea.amplitude, sea.omega, sea.wavenumber, sea.direction, sea.phase, t, x, y)
        assert mine == pytest.approx(ref, abs=1e-12)
    keep = dr.strongest_components(sea.amplitude, 0.99)
    assert np.sum(sea.amplitude[keep] ** 2) >= 0.99 * np.sum(sea.amplitude**2)


def test_sea_surface_is_a_finite_grid_in_the_display_frame(rng):
    from app.marine.waves import wave_components
    from app.net.snapshots import WaveField

    sea = wave_components("jonswap", 3.0, 9.0, rng, heading=0.7)
    field = WaveField(
        amplitude=sea.amplitude.tolist(), omega=sea.omega.tolist(), k=sea.wavenumber.tolist(),
        heading_rad=sea.direction.tolist(), phase=sea.phase.tolist(),
    )  # fmt: skip
    m = dr.sea_surface(field, 5.0, center=(10.0, -20.0), size=100.0, n=21, share=1.0)
    assert m.vertices.shape == (21 * 21, 3) and m.faces.shape == (2 * 20 * 20, 3)
    assert np.all(np.isfinite(m.vertices))
    i = int(np.argmax(m.vertices[:, 2]))
    north, west, z = m.vertices[i]
    assert z == pytest.approx(dr.wave_elevation(sea.amplitude, sea.omega, sea.wavenumber, sea.direction, sea.phase,
                                                5.0, north, -west))  # fmt: skip
    assert m.vertices[:, 0].min() == pytest.approx(-40.0) and m.vertices[:, 1].max() == pytest.approx(70.0)


def test_hull_spans_deck_to_keel():
    m = dr.hull_mesh(82.8, 19.2, -3.0, 6.0)
    assert m.vertices[:, 2].min() == pytest.approx(-3.0) and m.vertices[:, 2].max() == pytest.approx(6.0)
    assert m.vertices[:, 0].max() == pytest.approx(41.4) and np.abs(m.vertices[:, 1]).max() == pytest.approx(9.6)
    assert 0.6 * 82.8 * 19.2 * 9 < dr.signed_volume(m) < 82.8 * 19.2 * 9


def test_crane_head_scene_stands_on_the_deck_above_the_sea():
    from app.engine.tac_session import TacSession

    s = TacSession()
    s.tick(0.0, 0.2)
    smp, desc = s.snapshot().sample, s.describe()
    crane = SerialRobot(parse_robot_xml(desc.crane_xml))
    head = parse_robot_xml(desc.head_xml).delta
    meshes = dr.tac_meshes(crane.links, crane.frames(np.array(smp.beta)), head, smp.alpha, smp.p_c_t, smp.eta,
                           desc.ship)  # fmt: skip
    by = {m.name: m for m in meshes}
    hull, base = by["hull"], by["base"]
    assert not any(m.name.startswith("mount") for m in meshes)  # the deck link from CO is inside the hull
    eta = np.array(smp.eta)

    def to_b(p):  # display (x north, y west, z up) → {n} → the vessel's {b} (z down)
        return (p * [1, -1, -1] - eta[:3]) @ euler_zyx_to_matrix(eta[3:6])

    assert to_b(hull.vertices)[:, 2].min() == pytest.approx(desc.ship.deck_z)
    assert to_b(base.vertices)[:, 2].max() == pytest.approx(desc.ship.deck_z)  # the base plate on the deck
    assert hull.vertices[:, 2].min() < -5.0  # the keel under water
    tcp = by["head tcp"].vertices.mean(axis=0)
    p_c_n = np.array(smp.p_c_n)
    np.testing.assert_allclose(tcp, p_c_n * [1, -1, -1], atol=1e-6)  # the head's TCP where the sim has it
    assert tcp[2] > 10.0
