"""Rotations, skew matrices, Euler angles and homogeneous transforms.

Small pure functions on numpy arrays.  Every function that builds a matrix from an
angle accepts scalars or arrays of angles and then returns a stack of matrices
with shape ``angle.shape + (3, 3)`` (or ``(4, 4)``), so whole populations of
configurations can be transformed in one call.

Conventions (see ``ARCHITECTURE.md``): radians, metres, right-handed frames.
``R_a_b`` maps a vector expressed in frame *b* into frame *a* (the papers' R_b^a).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "dh_transform",
    "euler_to_matrix",
    "euler_zyx_to_matrix",
    "homogeneous",
    "invert_transform",
    "is_rotation_matrix",
    "matrix_to_euler_zyx",
    "rot_x",
    "rot_y",
    "rot_z",
    "skew",
    "unskew",
]


def _basic_rotation(angle: ArrayLike, axis: int) -> NDArray[np.float64]:
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    R = np.zeros(a.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def rot_x(angle: ArrayLike) -> NDArray[np.float64]:
    """Rotation about x by ``angle`` [rad]; shape ``angle.shape + (3, 3)``."""
    return _basic_rotation(angle, 0)


def rot_y(angle: ArrayLike) -> NDArray[np.float64]:
    """Rotation about y by ``angle`` [rad]; shape ``angle.shape + (3, 3)``."""
    return _basic_rotation(angle, 1)


def rot_z(angle: ArrayLike) -> NDArray[np.float64]:
    """Rotation about z by ``angle`` [rad]; shape ``angle.shape + (3, 3)``."""
    return _basic_rotation(angle, 2)


def skew(v: ArrayLike) -> NDArray[np.float64]:
    """Skew-symmetric matrix S(v) with S(v) @ w == cross(v, w).

    Motion-Lab paper eq. (46).  ``v`` has shape (..., 3); returns (..., 3, 3).
    """
    v = np.asarray(v, dtype=float)
    if v.shape[-1] != 3:
        raise ValueError(f"skew needs vectors of length 3, got shape {v.shape}")
    S = np.zeros(v.shape[:-1] + (3, 3))
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    S[..., 0, 1], S[..., 0, 2] = -z, y
    S[..., 1, 0], S[..., 1, 2] = z, -x
    S[..., 2, 0], S[..., 2, 1] = -y, x
    return S


def unskew(S: ArrayLike) -> NDArray[np.float64]:
    """Vector v of a skew-symmetric matrix, the inverse of :func:`skew`."""
    S = np.asarray(S, dtype=float)
    return np.stack([S[..., 2, 1], S[..., 0, 2], S[..., 1, 0]], axis=-1)


def euler_to_matrix(angles: ArrayLike, order: str) -> NDArray[np.float64]:
    """The product of the rotations about x by roll φ, about y by pitch θ and about z by yaw ψ, in ``order``.

    ``order`` names the factors left to right: "zyx" is Rz(ψ) Ry(θ) Rx(φ), Fossen's
    (:func:`euler_zyx_to_matrix`); "xyz" is Rx(φ) Ry(θ) Rz(ψ), the Motion-Lab's
    (:func:`app.models.stewart.rotation_xyz`).

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        Roll φ, pitch θ, yaw ψ [rad], in this order whatever the order of the product.
    order : str
        A permutation of "xyz".

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    angles = np.asarray(angles, dtype=float)
    if angles.shape[-1] != 3:
        raise ValueError(f"roll, pitch, yaw needs 3 values, got shape {angles.shape}")
    first, second, third = (_basic_rotation(angles[..., axis], axis) for axis in map("xyz".index, order))
    return first @ second @ third


def euler_zyx_to_matrix(rpy: ArrayLike) -> NDArray[np.float64]:
    """Rotation R_n_b from roll, pitch, yaw (φ, θ, ψ) (..., 3) in Fossen's zyx convention; (..., 3, 3).

    R_b^n = Rz(ψ) Ry(θ) Rx(φ)  (Fossen 2011, eq. 2.18).  The TAC paper prints
    eq. (37) as Rx(φ)Ry(θ)Rz(ψ); that is the transpose order and, for the
    body-to-NED map it describes, a misprint: Fossen's book, which the paper
    cites, has Rz Ry Rx.
    """
    return euler_to_matrix(rpy, "zyx")


def matrix_to_euler_zyx(R: ArrayLike) -> NDArray[np.float64]:
    """Roll, pitch, yaw (φ, θ, ψ) [rad] of a rotation, inverse of :func:`euler_zyx_to_matrix`.

    Pitch is returned in [-π/2, π/2]; at the gimbal-lock pitch ±π/2 the roll is set
    to zero and the yaw carries the whole rotation about the vertical.
    """
    R = np.asarray(R, dtype=float)
    pitch = -np.arcsin(np.clip(R[..., 2, 0], -1.0, 1.0))
    roll = np.arctan2(R[..., 2, 1], R[..., 2, 2])
    yaw = np.arctan2(R[..., 1, 0], R[..., 0, 0])
    lock = np.abs(R[..., 2, 0]) > 1.0 - 1e-12
    if np.any(lock):
        roll = np.where(lock, 0.0, roll)
        yaw = np.where(lock, np.arctan2(-R[..., 0, 1], R[..., 1, 1]), yaw)
    return np.stack([roll, pitch, yaw], axis=-1)


def homogeneous(R: ArrayLike | None = None, p: ArrayLike | None = None) -> NDArray[np.float64]:
    """4×4 homogeneous transform [[R, p], [0, 1]] (TAC paper eq. 36)."""
    R = np.eye(3) if R is None else np.asarray(R, dtype=float)
    p = np.zeros(3) if p is None else np.asarray(p, dtype=float)
    batch = np.broadcast_shapes(R.shape[:-2], p.shape[:-1])
    T = np.zeros(batch + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T


def invert_transform(T: ArrayLike) -> NDArray[np.float64]:
    """Inverse of a homogeneous transform, using R^T instead of a general inverse."""
    T = np.asarray(T, dtype=float)
    R_t = np.swapaxes(T[..., :3, :3], -1, -2)
    p = T[..., :3, 3]
    return homogeneous(R_t, -np.einsum("...ij,...j->...i", R_t, p))


def dh_transform(theta: ArrayLike, d: ArrayLike, a: ArrayLike, alpha: ArrayLike) -> NDArray[np.float64]:
    """Standard Denavit–Hartenberg link transform A = Rz(θ) Tz(d) Tx(a) Rx(α).

    Motion-Lab paper eq. (1); TAC paper eq. (38), whose printed form says Rot_{z,α}
    but whose matrix is that of Rot_{x,α}, as here.  All arguments broadcast;
    returns shape ``broadcast.shape + (4, 4)``.
    """
    theta, d, a, alpha = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (theta, d, a, alpha)))
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    A = np.zeros(theta.shape + (4, 4))
    A[..., 0, 0] = ct
    A[..., 0, 1] = -st * ca
    A[..., 0, 2] = st * sa
    A[..., 0, 3] = a * ct
    A[..., 1, 0] = st
    A[..., 1, 1] = ct * ca
    A[..., 1, 2] = -ct * sa
    A[..., 1, 3] = a * st
    A[..., 2, 1] = sa
    A[..., 2, 2] = ca
    A[..., 2, 3] = d
    A[..., 3, 3] = 1.0
    return A


def is_rotation_matrix(R: ArrayLike, tol: float = 1e-9) -> bool:
    """True when every matrix in ``R`` is orthonormal with determinant +1."""
    R = np.asarray(R, dtype=float)
    eye = np.eye(3)
    ortho = np.abs(np.swapaxes(R, -1, -2) @ R - eye).max() <= tol
    return bool(ortho and np.all(np.abs(np.linalg.det(R) - 1.0) <= tol))
