"""Weighted planes: intersections, fits and the Minkowski product (§2.1)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from ppfab import planes as pl
from ppfab.errors import GeometryError

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


def test_intersect_three_is_vectorised_and_exact():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(50, 60, 3))
    normals = [rng.normal(size=(50, 60, 3)) for _ in range(3)]
    planes = [np.concatenate([n, -np.einsum("...i,...i->...", n, x)[..., None]], -1) for n in normals]
    got = pl.intersect_three(*planes)
    assert got.shape == (50, 60, 3)
    assert np.abs(got - x).max() < 1e-8


def test_parallel_planes_are_reported_with_index():
    a = np.array([[0, 0, 1, 0], [0, 0, 1, 0]], float)
    b = np.array([[1, 0, 0, 0], [1, 0, 0, 0]], float)
    c = np.array([[0, 1, 0, 0], [0, 0, 2, 1]], float)  # second triple: two parallel planes
    with pytest.raises(GeometryError, match=r"index \(1,\)"):
        pl.intersect_three(a, b, c)


def test_fit_plane_recovers_plane_and_residual():
    rng = np.random.default_rng(2)
    n = np.array([1.0, 2.0, -0.5])
    n /= np.linalg.norm(n)
    u = np.cross(n, [0, 0, 1.0])
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    pts = rng.normal(size=(30, 1)) * u + rng.normal(size=(30, 1)) * w + 3 * n
    plane, res = pl.fit_plane(pts)
    assert res < 1e-12
    assert abs(abs(plane[:3] @ n) - 1) < 1e-12
    pts[4] += 0.1 * n
    _, res = pl.fit_plane(pts)
    assert 0.05 < res < 0.1


def test_collinear_points_raise():
    with pytest.raises(GeometryError, match="collinear"):
        pl.plane_through_points(np.zeros(3), np.ones(3), 2 * np.ones(3))


def test_minkowski_inner_and_contact():
    # two spheres touching from inside with the same orientation: tangential distance 0
    s1 = np.array([0, 0, 0, 2.0])
    s2 = np.array([1, 0, 0, 1.0])
    assert abs(pl.tangential_distance_squared(s1, s2)) < 1e-15
    assert pl.minkowski_inner(s1, s1) == -4.0
    assert np.allclose(pl.J @ s1, [0, 0, 0, -2])


@settings(max_examples=60, deadline=None)
@given(arrays(float, (3, 3), elements=finite), arrays(float, 3, elements=finite))
def test_three_planes_through_a_point_meet_there(normals, point):
    det = abs(np.linalg.det(normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)))
    if not np.all(np.linalg.norm(normals, axis=1) > 1e-3) or det < 1e-3:
        return
    planes = np.concatenate([normals, -(normals @ point)[:, None]], axis=1)
    got = pl.intersect_three(planes[0], planes[1], planes[2])
    assert np.abs(got - point).max() < 1e-6 * (1 + np.abs(point).max()) / det


@settings(max_examples=60, deadline=None)
@given(arrays(float, 4, elements=finite), st.floats(0.1, 100))
def test_normalize_is_scale_invariant(p, k):
    if np.linalg.norm(p[:3]) < 1e-3:
        with pytest.raises(GeometryError):
            pl.normalize(np.zeros(4))
        return
    assert np.allclose(pl.normalize(p), pl.normalize(k * p))


def test_radical_plane_of_spheres_is_bisector_for_points():
    a, b = np.array([1.0, 2, 3]), np.array([-1.0, 0, 5])
    g = pl.sphere_to_plane_coordinates(np.r_[a, 0.0])
    h = pl.sphere_to_plane_coordinates(np.r_[b, 0.0])
    mid = 0.5 * (a + b)
    assert abs(pl.evaluate(g - h, mid)) < 1e-12
    # the radical plane of two spheres contains their intersection circle
    s1, s2 = np.r_[0, 0, 0, 2.0], np.r_[2.0, 0, 0, 1.5]
    x = (s1[3] ** 2 - s2[3] ** 2 + 4) / 4
    pt = np.array([x, np.sqrt(s1[3] ** 2 - x * x), 0])
    gp = pl.sphere_to_plane_coordinates(s1) - pl.sphere_to_plane_coordinates(s2)
    assert abs(pl.evaluate(gp, pt)) < 1e-12


def test_line_angle_matches_a_rotation_at_every_angle_and_reads_zero_directions_as_worst():
    """Directions built at a known angle θ by rotating ``u`` about a perpendicular axis (rotation formula,
    independent of the function): ``line_angle`` reads ``min(θ, π − θ)`` to 1e-15 rad even at θ = 1e-9,
    where ``arccos`` of the normalised dot product is off by more than the angle itself."""
    rng = np.random.default_rng(7)
    for theta in (0.0, 1e-12, 1e-9, 1e-4, 0.3, np.pi / 2, 2.0, np.pi - 1e-9):
        u = rng.normal(size=3)
        k = np.cross(u, rng.normal(size=3))
        k /= np.linalg.norm(k)
        w = u * np.cos(theta) + np.cross(k, u) * np.sin(theta)             # Rodrigues, k ⟂ u
        expect = min(theta, np.pi - theta)
        got = float(pl.line_angle(u, 3.7 * w))
        assert abs(got - expect) < 1e-15 + 1e-13 * expect, (theta, got)
    near = float(np.arccos(np.clip(np.dot([1.0, 0, 0], [np.cos(1e-9), np.sin(1e-9), 0]), -1, 1)))
    assert abs(near - 1e-9) >= 1e-9                                         # arccos reads 0: why it is not used
    assert np.allclose(pl.line_angle(np.zeros((2, 3)), np.eye(3)[:2]), np.pi / 2)
    batch = pl.line_angle(np.eye(3)[None, :, :], np.array([[[1.0, 1, 0], [0, 1, 0], [0, 0, -2]]]))
    assert batch.shape == (1, 3) and np.allclose(batch, [[np.pi / 4, 0, 0]])


def test_angle_between_planes_still_refuses_a_zero_normal():
    with pytest.raises(GeometryError):
        pl.angle_between(np.array([0.0, 0, 0, 1]), np.array([0.0, 0, 1, 0]))
    assert np.isclose(float(pl.angle_between(np.array([0.0, 0, 2, 1]), np.array([0.0, 1, 1, 0]))), np.pi / 4)
