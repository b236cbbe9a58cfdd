"""PP meshes from the weighted face image (Prop. 3.1, eq. 7) and back (Prop. 2.4/2.5)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.faceimage import (face_image, grid_from_face_image, pp_face_image, pp_from_curves,
                             pp_from_face_image)
from ppfab.metrics import face_planarity, plane_residual, polyline_planarity, quality

from conftest import smooth_face_image

TOL = 1e-9


def test_pp_mesh_is_planar_and_polylines_lie_in_support_planes(pp_grid):
    g = pp_grid
    assert face_planarity(g.face_corners).max() <= TOL
    assert plane_residual(g.rows(), g.support_u).max() <= TOL
    assert plane_residual(g.cols(), g.support_w).max() <= TOL
    if min(g.shape) >= 3:
        assert polyline_planarity(g.rows()).max() <= TOL
        assert polyline_planarity(g.cols()).max() <= TOL
    # node axes are unit, lie in both support planes' directions
    a = g.axes
    assert np.allclose(np.linalg.norm(a, axis=-1), 1)
    nu = pl.normalize(g.support_u)[:, None, :3]
    nw = pl.normalize(g.support_w)[None, :, :3]
    assert np.abs(np.einsum("...i,...i->...", a, nu)).max() < 1e-12
    assert np.abs(np.einsum("...i,...i->...", a, nw)).max() < 1e-12


def test_shape_and_ghost_faces():
    g, h = smooth_face_image(6, 9)
    grid = pp_from_face_image(g, h)
    assert grid.shape == (7, 10)
    assert grid.face_image.shape == (6, 9, 4)
    assert grid.support_u.shape == (7, 4) and grid.support_w.shape == (10, 4)
    # every vertex (boundary ones too) lies on all four surrounding extended face planes
    F = grid.extended_face_image
    v = grid.vertices
    for da in (0, 1):
        for db in (0, 1):
            assert np.abs(pl.signed_distance(F[da:da + 7, db:db + 10], v)).max() < 1e-12


def test_face_image_round_trip(pp_grid):
    """face image → mesh → face image recovers the image up to one global factor (Prop. 2.4/2.5)."""
    g = pp_grid
    F, U, W = pp_face_image(g)
    ref = g.face_image
    mask = np.abs(ref) > 1e-8 * np.abs(ref).max()
    k = F[mask] / ref[mask]
    assert np.ptp(k) <= 1e-9 * np.abs(k).mean()
    # and back: vertices from the recovered face image and support planes
    again = grid_from_face_image(F, U, W)
    assert np.abs(again.vertices - g.vertices).max() <= 1e-9 * np.ptp(g.vertices)


def test_general_face_image_with_axes_matches_pp_image(pp_grid):
    g = pp_grid
    mesh = g.to_quadmesh()
    F = face_image(mesh, g.axes.reshape(-1, 3)).reshape(g.face_image.shape)
    mask = np.abs(g.face_image) > 1e-8 * np.abs(g.face_image).max()
    ratio = F[mask] / g.face_image[mask]
    assert np.ptp(ratio) <= 1e-9 * np.abs(ratio).mean()
    # eq. (5): the difference across row i (faces (i-1, j), (i, j)) contains the axes at both
    # ends of the edge v[i, j] v[i, j+1]
    if F.shape[0] > 1:
        n = pl.normalize(F[1:] - F[:-1])[..., :3]          # (m-1, n, 3)
        a = g.axes[1:-1]
        assert np.abs(np.einsum("...i,...i->...", n, a[:, :-1])).max() < 1e-9
        assert np.abs(np.einsum("...i,...i->...", n, a[:, 1:])).max() < 1e-9


def test_pp_from_curves_samples_eq8():
    g = lambda t: np.stack([np.sin(t), 0.3 * t ** 2, np.ones_like(t), -0.5 * t ** 2], -1)
    h = lambda t: np.stack([0.2 * t ** 2, np.sin(t), np.zeros_like(t), -0.5 * t ** 2 - 1], -1)
    u = np.linspace(-0.6, 0.6, 13)
    v = np.linspace(-0.4, 0.4, 8)
    grid = pp_from_curves(g, h, u, v)
    assert grid.shape == (14, 9)
    expect = g(u)[:, None] + h(v)[None]
    assert np.allclose(grid.face_image, expect)
    q = quality(grid)
    assert q.delta_f_max <= TOL and q.delta_p_rows_max <= TOL and q.delta_p_cols_max <= TOL
    assert q.flipped_edges == 0 and q.nonconvex_faces == 0


def test_degenerate_generators_are_named():
    g, h = smooth_face_image(4, 4)
    g[2, :3] = g[1, :3]       # U_1 has no normal
    with pytest.raises(GeometryError, match="U_1"):
        pp_from_face_image(g, h)


def test_parallel_support_planes_break_vertex_definition():
    g, _ = smooth_face_image(3, 3)
    h = g.copy()  # identical families: U_i == W_i, the node axis is undefined
    with pytest.raises(GeometryError, match="vertex"):
        pp_from_face_image(g, h)


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 12), st.integers(1, 12), st.integers(0, 10_000))
def test_random_face_images_give_small_pp_residual(m, n, seed):
    rng = np.random.default_rng(seed)
    g = np.cumsum(rng.normal(size=(m + 2, 4)), axis=0)
    h = np.cumsum(rng.normal(size=(n + 2, 4)), axis=0)
    try:
        grid = pp_from_face_image(g, h, min_sine=1e-6)
    except GeometryError:
        return  # a random image may put a vertex at infinity: reported, never NaN
    assert np.all(np.isfinite(grid.vertices))
    scale = max(1.0, float(np.abs(grid.vertices).max()))
    assert np.abs(pl.signed_distance(grid.support_u[:, None], grid.vertices)).max() <= 1e-7 * scale
    assert np.abs(pl.signed_distance(grid.support_w[None, :], grid.vertices)).max() <= 1e-7 * scale


def test_zoo_meshes_are_fair(pp_grid):
    """The shared test meshes are what they claim: no folds, convex faces."""
    q = quality(pp_grid)
    assert q.flipped_edges == 0 and q.nonconvex_faces == 0
