"""Serial-chain kinematics: paper closed forms, finite differences, reference poses."""

import numpy as np
import pytest

from app.errors import JointInputError
from app.models import list_robots, load_robot, load_spec
from tests.helpers import random_q

SERIAL_ROBOTS = [n for n in list_robots() if load_spec(n).type == "serial"]

# Motion-Lab paper, Table 7 [m]
A1, D1, A2, A3, D4, D6, DTP = 0.350, 0.830, 1.160, 0.250, 1.492, 0.210, 0.567


def comau_closed_form(q: np.ndarray, L: float) -> np.ndarray:
    """Motion-Lab paper eq. (3), with the joint values of the Comau convention."""
    q1, q2, q3 = q
    r = A1 - L * np.sin(q3) - A3 * np.cos(q3) + A2 * np.sin(q2)
    return np.array([np.cos(q1) * r, -np.sin(q1) * r, D1 + L * np.cos(q3) + A2 * np.cos(q2) - A3 * np.sin(q3)])


def test_serial_library_is_not_empty():
    assert {
        "comau_smart5_3dof",
        "comau_smart5_6dof",
        "offshore_crane",
        "knuckle_boom_crane",
        "scara",
        "kuka_youbot",
    } <= set(SERIAL_ROBOTS)


def test_comau_3dof_fk_matches_eq3(rng):
    # eq. (3) prints L = d5 + d6 + d_tp; Tables 3 and 7 mean d4 + d6 + d_tp.
    robot = load_robot("comau_smart5_3dof")
    L = D4 + D6 + DTP
    qs = random_q(robot, rng, 25)
    batch = robot.position(qs)
    for q, p in zip(qs, batch, strict=True):
        np.testing.assert_allclose(p, comau_closed_form(q, L), atol=1e-12)
        np.testing.assert_allclose(robot.position(q), p, atol=1e-12)


def test_comau_3dof_rotation_matches_paper(rng):
    # Motion-Lab paper, R_t^0 under eq. (2): it depends on q1 and q3 only.
    robot = load_robot("comau_smart5_3dof")
    for q1, q2, q3 in random_q(robot, rng, 10):
        c1, s1, c3, s3 = np.cos(q1), np.sin(q1), np.cos(q3), np.sin(q3)
        R = np.array([[c1 * c3, s1, -c1 * s3], [-c3 * s1, c1, s1 * s3], [s3, 0, c3]])
        np.testing.assert_allclose(robot.fk([q1, q2, q3])[:3, :3], R, atol=1e-12)


def test_comau_6dof_with_locked_wrist_matches_eq3(rng):
    # Table 2 without the extension arm: with q4 = q5 = q6 = 0 the flange is eq. (3) with L = d4 + d6.
    robot = load_robot("comau_smart5_6dof")
    arm = load_robot("comau_smart5_3dof")
    for q in random_q(arm, rng, 20):
        np.testing.assert_allclose(robot.position(np.r_[q, 0, 0, 0]), comau_closed_form(q, D4 + D6), atol=1e-12)


def test_comau_coupling_gives_table3_dh_variables(rng):
    robot = load_robot("comau_smart5_3dof")
    q1, q2, q3 = rng.uniform(-1, 1, 3)
    theta, d = robot.dh_variables([q1, q2, q3])
    np.testing.assert_allclose(theta, [-q1, np.pi / 2 - q2, q3 + np.pi / 2 + q2, np.pi])
    np.testing.assert_allclose(d, [D1, 0, 0, D4 + D6 + DTP])


def test_offshore_crane_stationary_configuration_eq60():
    # TAC paper eq. (60): boom up 45 deg, jib level, pointing to starboard; Table 4 dimensions.
    robot = load_robot("offshore_crane")
    T = robot.fk(np.deg2rad([-90, 45, -45]))
    reach = 19.20 * np.cos(np.pi / 4) + 9.60
    np.testing.assert_allclose(T[:3, 3], [-20.70, reach, -(3.00 + 3.00 + 19.20 * np.sin(np.pi / 4))], atol=1e-9)
    np.testing.assert_allclose(T[:3, 0], [0, 1, 0], atol=1e-12)  # x_t along the jib, to starboard
    np.testing.assert_allclose(T[:3, 2], [0, 0, -1], atol=1e-12)  # z_t up ({b} is z-down)


def test_youbot_candle_pose():
    robot = load_robot("kuka_youbot")
    np.testing.assert_allclose(robot.position(np.zeros(5)), [0.033, 0, 0.147 + 0.155 + 0.135 + 0.2175], atol=1e-12)


def test_prismatic_columns():
    scara = load_robot("scara")
    J = scara.jacobian([0.3, -0.4, 0.1, 0.2])
    np.testing.assert_allclose(J[:, 2], [0, 0, -1, 0, 0, 0], atol=1e-12)  # quill moves straight down
    crane = load_robot("knuckle_boom_crane")
    q = np.array([0.4, 0.5, -0.9, 1.5])
    F = crane.frames(q)
    jib_dir = F[-1, :3, 3] - F[3, :3, 3]
    J = crane.jacobian(q)
    np.testing.assert_allclose(J[:3, 3], jib_dir / np.linalg.norm(jib_dir), atol=1e-12)
    np.testing.assert_allclose(J[3:, 3], 0, atol=1e-15)


def _fd_jacobian(robot, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    J = np.zeros((6, robot.n_joints))
    R0 = robot.fk(q)[:3, :3]
    for j in range(robot.n_joints):
        dq = np.zeros(robot.n_joints)
        dq[j] = h
        Tp, Tm = robot.fk(q + dq), robot.fk(q - dq)
        J[:3, j] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        S = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ R0.T  # dR/dq R^T = S(omega)
        J[3:, j] = [S[2, 1], S[0, 2], S[1, 0]]
    return J


@pytest.mark.parametrize("name", SERIAL_ROBOTS)
def test_jacobian_matches_central_differences(name, rng):
    robot = load_robot(name)
    scale = max(1.0, float(np.abs(robot.position(np.zeros(robot.n_joints))).max()))
    for q in random_q(robot, rng, 8):
        np.testing.assert_allclose(robot.jacobian(q), _fd_jacobian(robot, q), atol=1e-7 * scale)


@pytest.mark.parametrize("name", SERIAL_ROBOTS)
def test_batch_equals_single(name, rng):
    robot = load_robot(name)
    qs = random_q(robot, rng, 6)
    J = robot.jacobian(qs)
    assert J.shape == (6, 6, robot.n_joints)
    for i, q in enumerate(qs):
        np.testing.assert_allclose(J[i], robot.jacobian(q), atol=1e-12)


def test_crane_jacobian_is_tac_eq48():
    # TAC eq. (48): columns z_{i-1} x (o_4 - o_{i-1}) over z_{i-1}, skipping the fixed link 1.
    robot = load_robot("offshore_crane")
    q = np.deg2rad([-70, 30, -60])
    F = robot.frames(q)
    o4 = F[4, :3, 3]
    expected = np.column_stack([np.r_[np.cross(F[i, :3, 2], o4 - F[i, :3, 3]), F[i, :3, 2]] for i in (1, 2, 3)])
    np.testing.assert_allclose(robot.jacobian(q), expected, atol=1e-12)


def test_check_q_errors():
    robot = load_robot("scara")
    with pytest.raises(JointInputError, match=r"scara has 4 joints .* got 3"):
        robot.check_q([0, 0, 0])
    with pytest.raises(JointInputError, match="j2 is not a finite number"):
        robot.check_q([0, np.nan, 0, 0])


def test_limits_flags():
    robot = load_robot("comau_smart5_3dof")
    assert robot.within_limits(np.deg2rad([0, 20, -60])).all()
    assert list(robot.within_limits(np.deg2rad([0, 20, 0]))) == [True, True, False]
    np.testing.assert_allclose(robot.clip(np.deg2rad([0, 200, 0])), np.deg2rad([0, 95, -10]))
