"""Rigid motions (geometry/rigid.py) against their definitions and scipy's rotations."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from steamtwin.geometry.rigid import (
    kabsch,
    pose_matrix,
    rotation_about,
    rotation_angle,
    rotation_from_vector,
    rotation_vector,
    skew,
    transform,
)

#: Rotation vectors of angle below π (|v| ≤ √3 · 1.8), where the logarithm is unique.
vectors = st.lists(st.floats(-1.8, 1.8), min_size=3, max_size=3).map(np.array)


@settings(max_examples=60, deadline=None)
@given(vector=vectors)
def test_rotation_vector_round_trip_and_scipy(vector):
    angle = float(np.linalg.norm(vector))
    rotation = rotation_from_vector(vector)
    assert np.allclose(rotation, Rotation.from_rotvec(vector).as_matrix(), atol=1e-12)
    assert np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
    assert math.isclose(rotation_angle(rotation), angle, abs_tol=1e-7)
    if angle > 1e-6:
        assert np.allclose(rotation_vector(rotation), vector, atol=1e-9)


def test_rotation_about_and_skew():
    a, b = np.array([0.3, -1.2, 2.0]), np.array([-0.7, 0.4, 1.1])
    assert np.allclose(skew(a) @ b, np.cross(a, b))
    quarter = rotation_about(np.array([0.0, 0.0, 1.0]), math.pi / 2)
    assert np.allclose(quarter @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    assert np.allclose(rotation_from_vector(np.zeros(3)), np.eye(3))


@settings(max_examples=40, deadline=None)
@given(vector=vectors, shift=vectors, seed=st.integers(0, 10_000))
def test_kabsch_recovers_a_rigid_motion(vector, shift, seed):
    points = np.random.default_rng(seed).normal(size=(30, 3)) * [0.05, 0.02, 0.01]
    pose = pose_matrix(rotation_from_vector(vector), shift)
    rotation, translation = kabsch(points, transform(points, pose))
    assert np.allclose(rotation, pose[:3, :3], atol=1e-9)
    assert np.allclose(translation, shift, atol=1e-9)


def test_kabsch_never_returns_a_reflection():
    """A mirrored target: the best proper rotation, det +1 (Umeyama 1991), not the mirror."""
    points = np.random.default_rng(1).normal(size=(50, 3)) * [3.0, 2.0, 1.0]
    mirrored = points * [1.0, 1.0, -1.0]
    rotation, _ = kabsch(points, mirrored)
    assert math.isclose(np.linalg.det(rotation), 1.0, abs_tol=1e-12)
    # the unconstrained least-squares fit would be the mirror itself
    assert not np.allclose(rotation, np.diag([1.0, 1.0, -1.0]))
