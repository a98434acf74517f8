"""Rigid motions of point clouds: 4×4 transformations, rotation vectors and the least-squares
rigid fit — written once for the scanner, the reference spheres, the registration, the blade
frame and the fidelity checks.

A pose is a 4×4 homogeneous matrix ``T`` acting on column vectors: ``x' = R x + t`` with
``R = T[:3, :3]`` and ``t = T[:3, 3]`` (lengths in m). Rotation vectors are ``angle × unit axis``
(rad), the exponential coordinates of SO(3) (Murray, Li & Sastry 1994, "A Mathematical
Introduction to Robotic Manipulation", §2.2).
"""

from __future__ import annotations

import math

import numpy as np


def transform(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4×4 rigid transformation to (n, 3) points (m)."""
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def pose_matrix(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """The 4×4 homogeneous matrix of ``x' = rotation · x + translation`` (translation in m)."""
    matrix = np.eye(4)
    matrix[:3, :3], matrix[:3, 3] = rotation, translation
    return matrix


def skew(vector: np.ndarray) -> np.ndarray:
    """The matrix of the cross product: ``skew(a) @ b == np.cross(a, b)``."""
    x, y, z = vector
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix by ``angle`` (rad) about the unit ``axis`` — Rodrigues' formula
    R = I + sin θ K + (1 − cos θ) K², K = skew(axis) (Murray, Li & Sastry 1994, eq. 2.14)."""
    k = skew(axis)
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k


def rotation_from_vector(vector: np.ndarray) -> np.ndarray:
    """Rotation matrix of a rotation vector (rad; the exponential map, Rodrigues)."""
    angle = float(np.linalg.norm(vector))
    if angle < 1e-15:
        return np.eye(3)
    return rotation_about(vector / angle, angle)


def rotation_angle(rotation: np.ndarray) -> float:
    """Angle (rad, in [0, π]) of a rotation matrix: cos θ = (trace R − 1) / 2."""
    cosine = 0.5 * (np.trace(rotation) - 1.0)
    return math.acos(max(-1.0, min(1.0, cosine)))


def rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """Rotation vector (rad) of a rotation matrix — the logarithm map, inverse of
    :func:`rotation_from_vector` for angles below π (Murray, Li & Sastry 1994, eq. 2.17);
    near zero the first-order vee of (R − Rᵀ)/2."""
    angle = rotation_angle(rotation)
    axis = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0],
                     rotation[1, 0] - rotation[0, 1]])
    return axis * (0.5 * angle / math.sin(angle)) if angle > 1e-12 else 0.5 * axis


def kabsch(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation (m) of the least-squares rigid fit of ``source`` onto
    ``target`` (matched (n, 3) points): minimises Σ |R s_i + t − q_i|².

    The rotation is V diag(1, 1, d) Uᵀ from the SVD U Σ Vᵀ of the cross-covariance of the
    centred points, d = sign det(V Uᵀ) so that a reflection is never returned (Kabsch 1976,
    Acta Cryst. A32:922; the reflection guard of Umeyama 1991, IEEE PAMI 13(4):376); the
    translation carries the rotated source centroid onto the target's.
    """
    cs, ct = source.mean(axis=0), target.mean(axis=0)
    u, _, vt = np.linalg.svd((source - cs).T @ (target - ct))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rotation = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return rotation, ct - rotation @ cs
