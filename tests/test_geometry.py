import numpy as np
import pytest

from app.geometry import (
    dh_transform,
    euler_zyx_to_matrix,
    homogeneous,
    invert_transform,
    is_rotation_matrix,
    matrix_to_euler_zyx,
    rot_x,
    rot_y,
    rot_z,
    skew,
    unskew,
)


def test_basic_rotations_reference_values():
    c, s = np.cos(0.3), np.sin(0.3)
    np.testing.assert_allclose(rot_x(0.3), [[1, 0, 0], [0, c, -s], [0, s, c]])
    np.testing.assert_allclose(rot_y(0.3), [[c, 0, s], [0, 1, 0], [-s, 0, c]])
    np.testing.assert_allclose(rot_z(0.3), [[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_rotations_batch_shape_and_orthonormal(rng):
    a = rng.uniform(-np.pi, np.pi, size=(7, 5))
    for f in (rot_x, rot_y, rot_z):
        R = f(a)
        assert R.shape == (7, 5, 3, 3)
        assert is_rotation_matrix(R)


def test_skew_is_cross_product(rng):
    v, w = rng.normal(size=(2, 50, 3))
    np.testing.assert_allclose(np.einsum("nij,nj->ni", skew(v), w), np.cross(v, w), atol=1e-12)
    np.testing.assert_allclose(unskew(skew(v)), v)


def test_skew_rejects_wrong_length():
    with pytest.raises(ValueError, match="length 3"):
        skew([1.0, 2.0])


def test_euler_zyx_is_fossen_order():
    # Fossen (2011) eq. 2.18: R_b^n = Rz(psi) Ry(theta) Rx(phi)
    phi, theta, psi = 0.1, -0.2, 0.7
    np.testing.assert_allclose(
        euler_zyx_to_matrix([phi, theta, psi]), rot_z(psi) @ rot_y(theta) @ rot_x(phi), atol=1e-15
    )


def test_euler_round_trip(rng):
    rpy = np.column_stack(
        [rng.uniform(-np.pi, np.pi, 200), rng.uniform(-1.5, 1.5, 200), rng.uniform(-np.pi, np.pi, 200)]
    )
    np.testing.assert_allclose(matrix_to_euler_zyx(euler_zyx_to_matrix(rpy)), rpy, atol=1e-12)


def test_euler_gimbal_lock_keeps_rotation():
    R = euler_zyx_to_matrix([0.4, np.pi / 2, 0.9])
    np.testing.assert_allclose(euler_zyx_to_matrix(matrix_to_euler_zyx(R)), R, atol=1e-9)


def test_dh_transform_is_product_of_basic_transforms(rng):
    # Motion-Lab paper eq. (1): A = Rz(theta) Tz(d) Tx(a) Rx(alpha)
    for theta, d, a, alpha in rng.uniform(-3, 3, size=(20, 4)):
        Rz = homogeneous(rot_z(theta))
        Tz = homogeneous(p=[0, 0, d])
        Tx = homogeneous(p=[a, 0, 0])
        Rx = homogeneous(rot_x(alpha))
        np.testing.assert_allclose(dh_transform(theta, d, a, alpha), Rz @ Tz @ Tx @ Rx, atol=1e-12)


def test_invert_transform(rng):
    T = homogeneous(euler_zyx_to_matrix(rng.uniform(-1, 1, (10, 3))), rng.normal(size=(10, 3)))
    np.testing.assert_allclose(T @ invert_transform(T), np.broadcast_to(np.eye(4), T.shape), atol=1e-12)
