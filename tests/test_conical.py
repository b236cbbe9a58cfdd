"""Conical residuals, cone axes and fold detection helpers (ppfab.conical, ppfab.folds)."""

from __future__ import annotations


import numpy as np
import pytest

from ppfab.conical.cones import (axis_of_normals, concyclic_residual, conical_quality, extended_planes, offset_faces,
                           rigid_motion, vertex_planes)
from ppfab.constructions.conical_pp import Series, conical_pp_grid
from ppfab.errors import GeometryError
from ppfab.folds import folded_faces, largest_valid_block
from ppfab.io import load_mesh

from conftest import shared_file  # noqa: E402


def test_axis_of_concyclic_normals():
    rng = np.random.default_rng(0)
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    b1 = np.cross(a, [0.0, 0.0, 1.0])
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(a, b1)
    th = rng.uniform(0, 2 * np.pi, 4)
    n = 0.8 * a + 0.6 * (np.cos(th)[:, None] * b1 + np.sin(th)[:, None] * b2)
    axis, cos, res = axis_of_normals(n)
    assert np.allclose(axis, a) and abs(cos - 0.8) < 1e-12 and res < 1e-12


def test_axis_of_degenerate_normal_sets_is_the_bisector():
    n = np.array([[0.0, 0.6, 0.8], [0.0, 0.6, 0.8], [0.0, -0.6, 0.8], [0.0, -0.6, 0.8]])   # two distinct
    axis, cos, res = axis_of_normals(n)
    assert np.allclose(axis, [0, 0, 1]) and abs(cos - 0.8) < 1e-12 and res < 1e-12
    axis, cos, _ = axis_of_normals(np.tile([[0.0, 0.6, 0.8]], (4, 1)))                       # all equal
    assert np.allclose(axis, [0, 0.6, 0.8]) and abs(cos - 1) < 1e-12
    with pytest.raises(GeometryError, match="do not define a cone axis"):
        axis_of_normals(np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0]]))


def test_concyclic_residual_tells_conical_from_non_conical_data():
    conical = load_mesh(shared_file("DOS__conical1.obj")).to_grid()                 # a published conical mesh
    deformed = load_mesh(shared_file("DOI__rot4_def1_sparse.obj")).to_grid()        # planar-quad? no: deformed
    assert concyclic_residual(conical)[1:-1, 1:-1].max() < 1e-5
    assert concyclic_residual(deformed)[1:-1, 1:-1].max() > 1e-2
    assert conical_quality(conical).angle_max < 1e-3 < conical_quality(deformed).angle_max


def test_stale_ghost_planes_are_not_used():
    grid = conical_pp_grid(Series(cos=[-10.0]), Series(cosh=[-20.0]), np.linspace(-.5, .5, 6), np.linspace(-.3, .3, 5))
    stored = extended_planes(grid)
    assert np.allclose(stored[0], grid.extended_face_image[0] /
                       np.linalg.norm(grid.extended_face_image[0, :, :3], axis=-1, keepdims=True))
    moved = grid.with_vertices(grid.vertices * 1.1)
    padded = extended_planes(moved)
    assert np.allclose(padded[1:-1, 1:-1], moved.face_planes)
    P = vertex_planes(moved, padded)                                       # rebuilt ghosts: through the vertices
    assert np.abs(np.einsum("ijkl,ijl->ijk", P[..., :3], moved.vertices) + P[..., 3]).max() < 1e-12
    assert axis_of_normals(P[..., :3])[2].max() < 1e-12                  # and conical at the boundary
    P_stale = vertex_planes(moved, stored)
    assert np.abs(np.einsum("ijkl,ijl->ijk", P_stale[..., :3], moved.vertices) + P_stale[..., 3]).max() > 1e-3


def test_rigid_motion_keeps_planes_consistent():
    grid = conical_pp_grid(Series(cos=[-10.0]), Series(cosh=[-20.0]), np.linspace(-.5, .5, 6), np.linspace(-.3, .3, 5))
    R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    moved = rigid_motion(grid, R, [1.0, 2.0, 3.0])
    F = moved.extended_face_image
    P = np.stack([F[:-1, :-1], F[1:, :-1], F[1:, 1:], F[:-1, 1:]], axis=-2)
    assert np.abs(np.einsum("ijkl,ijl->ijk", P[..., :3], moved.vertices) + P[..., 3]).max() < 1e-9
    assert np.allclose(offset_faces(moved, 0.2).vertices, rigid_motion(offset_faces(grid, 0.2), R, [1.0, 2.0, 3.0]).vertices)
    with pytest.raises(GeometryError, match="proper"):
        rigid_motion(grid, np.diag([1.0, 1.0, -1.0]))


def test_largest_valid_block_and_folded_faces():
    bad = np.zeros((6, 8), bool)
    bad[2, 5] = True
    bad[4, 1] = True
    i0, i1, j0, j1 = largest_valid_block(bad)
    brute = max((b - a) * (d - c) for a in range(6) for b in range(a + 1, 7) for c in range(8)
                for d in range(c + 1, 9) if not bad[a:b, c:d].any())
    assert not bad[i0:i1, j0:j1].any() and (i1 - i0) * (j1 - j0) == brute == 20
    grid = conical_pp_grid(Series(cos=[-10.0]), Series(cosh=[-20.0]), np.linspace(-.5, .5, 6), np.linspace(-.3, .3, 5))
    assert not folded_faces(grid).any()
    v = grid.vertices.copy()
    v[2, 2], v[3, 2] = grid.vertices[3, 2], grid.vertices[2, 2]                  # swap two vertices: a fold
    assert folded_faces(grid.with_vertices(v), grid.face_image).sum() >= 2


def test_offset_refuses_a_mesh_that_is_not_conical():
    """A PP mesh with planar faces that is not conical has no constant-distance offset: moving its vertices
    along fitted axes would bend the faces (δ_f from 1e-15 to ~1e-6); offset_faces says so instead."""
    from conftest import smooth_face_image
    from ppfab.faceimage import pp_from_face_image
    from ppfab.metrics import face_planarity

    grid = pp_from_face_image(*smooth_face_image(6, 5, seed=3))
    assert face_planarity(grid.face_corners).max() < 1e-12
    residual = concyclic_residual(grid)
    assert residual.max() > 1e-4                                  # independent: the normals are not concyclic
    with pytest.raises(GeometryError, match=r"not conical, so no offset at constant face distance exists") as err:
        offset_faces(grid, 0.1)
    assert err.value.value == pytest.approx(residual.max())
