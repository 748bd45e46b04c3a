"""Delta crane head (TAC paper §2–6): IK/FK round trips, Jacobian, workspace and saturation."""

from pathlib import Path

import numpy as np
import pytest

from app.models.delta import DeltaHead
from app.models.registry import load_robot, load_spec
from app.models.xml import parse_robot_xml


@pytest.fixture(scope="module")
def head() -> DeltaHead:
    return load_robot("tac_delta_head")


def test_table4_geometry(head):
    assert (head.l_k, head.l_a, head.l_r, head.l_p) == (2.0, 3.25, 7.0, 1.25)
    np.testing.assert_allclose(np.rad2deg([head.lower[0], head.upper[0]]), [-40, 70])


def test_eq3_is_eq4_with_complementary_angle(head):
    # the seed note: eqs. (4), (9), (28) agree; eq. (3) writes the knee with alpha -> pi/2 - alpha
    for al in np.deg2rad([-30, 0, 25, 60]):
        c = head.knees(np.full(3, al))
        for i in range(3):
            knee_eq3 = head.R[i] @ np.array(
                [head.l_a * np.cos(np.pi / 2 - al), -head.l_k - head.l_a * np.sin(np.pi / 2 - al), 0.0]
            )
            np.testing.assert_allclose(knee_eq3, c[i] - head.R[i] @ np.array([0, head.l_p, 0]), atol=1e-12)
        # eq. (9): |c_i|^2 = l_a^2 + a^2 - 2 a l_a cos(alpha)
        np.testing.assert_allclose(np.sum(c**2, axis=1), head.l_a**2 + head.a**2 - 2 * head.a * head.l_a * np.cos(al))


def test_ik_of_fk_on_a_grid_covering_the_joint_range(head):
    g = np.linspace(head.lower[0], head.upper[0], 9)
    A = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T  # 729 configurations, corners included
    P = head.fk(A)
    c = head.knees(A)
    np.testing.assert_allclose(np.linalg.norm(P[:, None, :] - c, axis=-1), head.l_r, atol=1e-9)  # eq. (6)
    assert np.all(P[:, 0] > c[..., 0].max(axis=1))  # the solution above the base: x_c > x_i
    sol = head.ik(P)
    assert sol.reachable.all() and sol.within_limits.all()
    np.testing.assert_allclose(sol.alpha, A, atol=1e-9)
    assert np.all(np.abs(sol.alpha) < np.pi / 2)  # knees out


def test_fk_of_ik_at_random_points(head, rng):
    ws = head.workspace(0.25)
    pts = ws.points[rng.choice(len(ws.points), 300, replace=False)] + rng.uniform(-0.1, 0.1, (300, 3))
    sol = head.ik(pts)
    ok = sol.reachable.all(axis=1)
    assert ok.mean() > 0.95
    np.testing.assert_allclose(head.fk(sol.alpha[ok]), pts[ok], atol=1e-9)


def test_unreachable_point_is_reported(head):
    sol = head.ik([30.0, 0.0, 0.0])  # far beyond l_a + l_r
    assert not sol.reachable.any() and not sol.ok


def test_jacobian_matches_finite_differences(head, rng):
    for al in rng.uniform(head.lower, head.upper, size=(20, 3)):
        J = head.jacobian(al)
        h = 1e-6
        J_fd = np.column_stack([(head.fk(al + h * e) - head.fk(al - h * e)) / (2 * h) for e in np.eye(3)])
        np.testing.assert_allclose(J, J_fd, atol=1e-6)


def test_arm_rates_invert_the_jacobian(head, rng):
    """eq. (32) solved for α̇ row by row equals solving J α̇ = ṗ."""
    alpha = rng.uniform(head.lower, head.upper, size=(50, 3))
    p_dot = rng.normal(0.0, 1.0, size=(50, 3))
    expected = np.linalg.solve(head.jacobian(alpha), p_dot[..., None])[..., 0]
    np.testing.assert_allclose(head.arm_rates(alpha, p_dot), expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(head.arm_rates(alpha, p_dot, head.fk(alpha)), expected, rtol=1e-9, atol=1e-12)


def test_workspace_hull_inside_test_and_saturation(head):
    ws = head.workspace(0.25)
    assert ws.inside(ws.points).all()  # every feasible grid point is in its hull
    assert not ws.inside(np.array([0.0, 0.0, 0.0])) and not ws.inside(np.array([20.0, 0.0, 0.0]))
    assert ws.inside(ws.center) and ws.depth(ws.center) > 2.0  # x_d leaves > 2 m of free motion
    assert ws.center[1] == ws.center[2] == 0.0
    p_in = ws.center + np.array([0.5, -0.4, 0.3])
    same, sat = ws.saturate(p_in)
    assert not sat and np.array_equal(same, p_in)
    for far in ([20.0, 0, 0], [6.5, 9.0, -9.0], [0.0, 0.0, 0.0], [7.0, 0.0, 12.0]):
        far = np.array(far)
        q, sat = ws.saturate(far)
        assert sat and abs(ws.depth(q)) < 1e-9  # on the hull
        # on the segment from the centre towards the reference
        d = far - ws.center
        t = np.dot(q - ws.center, d) / np.dot(d, d)
        np.testing.assert_allclose(q, ws.center + t * d, atol=1e-9)
        assert 0.0 <= t < 1.0


def test_workspace_step_is_checked(head):
    with pytest.raises(ValueError, match="grid step h must be positive"):
        head.workspace(0.0)


def test_any_delta_geometry_from_xml(rng):
    text = Path(load_spec("tac_delta_head").path).read_text(encoding="utf-8")
    small = text.replace('l_k="2.00" l_a="3.25" l_r="7.00" l_p="1.25"', 'l_k="0.20" l_a="0.30" l_r="0.80" l_p="0.05"')
    small = (
        small.replace('rot_x="150"', 'rot_x="90"')
        .replace('rot_x="270"', 'rot_x="210"')
        .replace('rot_x="30"', 'rot_x="330"')
    )
    head = DeltaHead(parse_robot_xml(small, "small_delta.xml"))
    A = rng.uniform(head.lower, head.upper, size=(200, 3))
    np.testing.assert_allclose(head.ik(head.fk(A)).alpha, A, atol=1e-9)
    ws = head.workspace(0.02)
    assert ws.inside(ws.center)
