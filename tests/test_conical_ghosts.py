"""Ghost faces of grids without stored ghosts (e.g. reloaded from JSON or a mesh file): conical boundary cones,
planar boundary polylines kept by Laguerre maps, offsets, isotropic Möbius maps and §4.3 edits."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ppfab.transforms import isotropic
from ppfab.conical.cones import laguerre_transform, axis_of_normals, conical_quality, extended_planes, ghost_planes, offset_faces, vertex_planes
from ppfab.conical.edit import edit_conical
from ppfab.constructions.conical_pp import Series, conical_pp_grid
from ppfab.constructions.conical_spheres import channel_mesh
from ppfab.errors import GeometryError
from ppfab.io import load_mesh
from ppfab.io.jsonio import grid_from_json, grid_to_json
from ppfab.transforms.isotropic import IsotropicMobius
from ppfab.transforms.laguerre import LaguerreMap, boost, spatial
from ppfab.metrics import polyline_planarity, quality

from conftest import conical_zoo

from conftest import shared_file  # noqa: E402
TOL = 1e-9
WAVY = np.array([[0, 0, 2, 5.0], [8, 3, 3, 6], [16, -2, 2.5, 5.5], [24, 0, 2, 4.5], [30, 2, 3, 5]])


def meshes():
    """Conical P and PP grids (open and closed) with the planar families of each."""
    return {
        **conical_zoo(),
        "P-tube-closed": (channel_mesh(WAVY, 10, 16, (0, 0), closed=True), ("rows",)),
        "PP-dome-closed": (conical_pp_grid(Series(), Series(cosh=[-12.0], poly=[0, 0, 1.5]), np.zeros(24),
                                           np.linspace(.2, 1.2, 7), case="rotational", closed=True), ("rows", "cols")),
    }


MESHES = meshes()
NAMES = list(MESHES)
LAG = LaguerreMap(boost([0.3, 0.5, 1.0], 0.4), 1.0, np.array([0.3, -0.2, 0.5, 0.7]))


def reloaded(name):
    grid, families = MESHES[name]
    bare = grid_from_json(grid_to_json(grid))
    assert bare.extended_face_image is None and bare.extended_face_planes is None   # the ghosts are gone
    return grid, bare, families


def boundary_delta_p(grid, families) -> float:
    """Largest δ_P of the boundary polylines of the planar families (rows 0, m; open columns 0, n)."""
    out = []
    if "rows" in families:
        out.append(polyline_planarity(grid.vertices[[0, -1]]).max())
    if "cols" in families and not grid.closed:
        out.append(polyline_planarity(grid.cols()[[0, -1]]).max())
    return max(out)


def all_delta_p(grid, families) -> float:
    q = conical_quality(grid)
    return max(q.delta_p_rows_max if "rows" in families else 0.0, q.delta_p_cols_max if "cols" in families else 0.0)


def boundary_cone_residual(grid) -> tuple[float, float]:
    """Largest distance of the four planes of a vertex from the vertex (relative to the size) and largest
    concyclicity residual of their normals, over all vertices (ghosts: the grid's extended planes)."""
    P = vertex_planes(grid)
    size = np.linalg.norm(np.ptp(grid.vertices.reshape(-1, 3), axis=0))
    through = np.abs(np.einsum("ijkl,ijl->ijk", P[..., :3], grid.vertices) + P[..., 3]).max() / size
    return float(through), float(axis_of_normals(P[..., :3])[2].max())


def assert_conical(grid, families, tol=TOL):
    q = conical_quality(grid)
    assert q.delta_f_max <= tol and q.angle_max <= tol and q.concyclic_max <= tol
    assert all_delta_p(grid, families) <= tol
    through, cyc = boundary_cone_residual(grid)
    assert through <= tol and cyc <= tol                             # boundary vertices conical too


# -- the ghosts themselves -----------------------------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_rebuilt_ghosts_are_conical_and_determine_every_vertex(name):
    grid, bare, _ = reloaded(name)
    E = extended_planes(bare)
    assert E.shape == (grid.shape[0] + 1, grid.shape[1] + 1, 4)
    assert np.allclose(E[1:-1, 1:] if grid.closed else E[1:-1, 1:-1], bare.face_planes, atol=1e-14)
    through, cyc = boundary_cone_residual(replace(bare, extended_face_planes=E))
    assert through < 1e-13 and cyc < 1e-12
    s = np.linalg.svd(vertex_planes(bare, E)[..., :3], compute_uv=False)
    assert (s[..., 2] / s[..., 0]).min() > 1e-6                       # four planes meet in one point


def test_planar_boundary_ghosts_are_minkowski_reflections_not_mirrors():
    """Rows of the P mesh are planar: their ghosts come from a reflection in H = (w, h₄) with h₄ ≠ 0; a
    Euclidean mirror (h₄ = 0) would be a different plane."""
    grid, bare, _ = reloaded("P-spheres")
    E = ghost_planes(bare)
    W = bare.support_u[0] / np.linalg.norm(bare.support_u[0, :3])
    n = E[1, 1:-1, :3]
    mirror = n - 2 * (n @ W[:3])[:, None] * W[:3]
    assert np.abs(E[0, 1:-1, :3] - mirror).max() > 1e-3
    # the boundary cones lie in one sphere-space hyperplane <(x, r) − (p, 0), (w, h₄)> = 0: one h₄ for the row
    a, c, _ = axis_of_normals(vertex_planes(bare, E)[0, :, :, :3])
    h4 = -(a @ W[:3]) / c
    assert np.ptp(h4) < 1e-12 and abs(h4[0]) > 1e-3


def test_stale_support_planes_fall_back_to_fitted_planes():
    grid, bare, families = reloaded("PP-eq11")
    wrong = replace(bare, support_u=bare.support_u + [0.0, 0.0, 0.0, 0.3])       # shifted: no longer through rows
    assert np.allclose(ghost_planes(wrong), ghost_planes(bare), atol=1e-9)
    assert boundary_delta_p(laguerre_transform(wrong, LAG), families) <= TOL


# -- transformations of reloaded grids ------------------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_laguerre_map_of_a_reloaded_grid_keeps_boundary_polylines_planar(name):
    grid, bare, families = reloaded(name)
    out = laguerre_transform(bare, LAG)
    assert np.abs(out.vertices - bare.vertices).max() > 0.1
    assert boundary_delta_p(out, families) <= TOL                     # was 1.6e-3 with repeated ghosts
    assert_conical(out, families)
    assert quality(out).flipped_edges == 0
    # the interior is the same as the image of the constructed grid (only boundary cones may differ)
    image = laguerre_transform(grid, LAG)
    inner = (slice(1, -1), slice(None)) if grid.closed else (slice(1, -1), slice(1, -1))
    assert np.abs(out.vertices[inner] - image.vertices[inner]).max() < 1e-9


@pytest.mark.parametrize("name", NAMES)
def test_offset_of_a_reloaded_grid_keeps_boundary_polylines_planar(name):
    _, bare, families = reloaded(name)
    out = offset_faces(bare, 0.5)
    assert boundary_delta_p(out, families) <= TOL
    assert_conical(out, families)
    # constant face–face distance, the stored ghosts shifted with the faces
    assert np.allclose(out.face_planes[..., 3] - bare.face_planes[..., 3], -0.5, atol=1e-9)
    assert np.allclose(out.extended_face_planes, extended_planes(bare) - [0, 0, 0, 0.5], atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_isotropic_maps_of_a_reloaded_grid(name):
    grid, bare, families = reloaded(name)
    size = np.linalg.norm(np.ptp(grid.vertices.reshape(-1, 3), axis=0))
    same = isotropic.isotropic_transform(bare, IsotropicMobius())
    assert np.abs(same.vertices - bare.vertices).max() < 1e-8 * size  # identity: the vertices stay (was 529)
    rot = np.linalg.qr(np.random.default_rng(2).normal(size=(3, 3)))[0]
    rot = rot * np.sign(np.linalg.det(rot))
    lag = IsotropicMobius.rotation(rot) @ IsotropicMobius.shear(1.0, [0.2, -0.1, 0.3], 0.5)
    out = isotropic.isotropic_transform(bare, lag)                         # Laguerre type: stays conical P / PP
    assert boundary_delta_p(out, families) <= 1e-8
    assert_conical(out, families, tol=1e-8)
    T = IsotropicMobius.special_conformal([0.02, -0.01, 0.01]) @ IsotropicMobius.shear(1.1, [0.02, 0.0, -0.03], 0.3)
    out = isotropic.isotropic_transform(bare, T)
    assert np.abs(out.vertices - bare.vertices).max() > 1e-3 * size
    assert quality(out).delta_f_max < 1e-9 and quality(out).flipped_edges == 0


def test_isotropic_map_rejects_vertices_whose_planes_meet_in_a_line():
    grid, _ = MESHES["PP-eq11"]
    f = grid.face_planes
    repeated = np.pad(f, ((1, 1), (1, 1), (0, 0)), mode="edge")      # each boundary face its own ghost
    bad = replace(grid, extended_face_planes=repeated)
    with pytest.raises(GeometryError, match=r"vertex \(0, 0\) do not meet in a single point"):
        isotropic.isotropic_transform(bad, IsotropicMobius())


@pytest.mark.parametrize("name", ["P-spheres", "PP-eq11", "P-tube-closed"])
def test_conical_edit_of_a_reloaded_grid(name):
    grid, bare, families = reloaded(name)
    res = edit_conical(bare, handles={(3, 4): bare.vertices[3, 4] + [0.0, 0.0, 0.3]})
    assert res.constraint_residual < 1e-9 and res.handle_residual < 0.3
    assert boundary_delta_p(res.grid, families) <= TOL
    assert_conical(res.grid, families)
    L = LaguerreMap(spatial(np.eye(3)) @ boost([0.2, 0.4, 1.0], 0.2))
    image = laguerre_transform(bare, L)
    fixed = edit_conical(bare, A=L.mobius_matrix(), fairness=0.0)     # fixed A: the Laguerre image itself
    assert np.abs(fixed.grid.vertices - image.vertices).max() < 1e-8


# -- real meshes: conical but not P, closed ----------------------------------------------------------------

def test_ghosts_of_a_published_conical_mesh_and_of_a_closed_non_planar_boundary():
    grid = load_mesh(shared_file("DOS__conical1.obj")).to_grid()          # no planar boundary: propagated ghosts
    E = ghost_planes(grid)
    P = vertex_planes(grid, E)
    a, c, res = axis_of_normals(P[..., :3])
    assert res.max() < 2e-5                                           # as conical as the file (interior 5e-6)
    s = np.linalg.svd(P[..., :3], compute_uv=False)
    assert (s[..., 2] / s[..., 0]).min() > 1e-4 and c.min() > 0.9
    out = offset_faces(grid, 0.01 * np.linalg.norm(np.ptp(grid.vertices.reshape(-1, 3), axis=0)))
    assert quality(out).flipped_edges == 0 and quality(out).nonconvex_faces == 0
    closed = load_mesh(shared_file("DOI__undoloid2_cut2_remesh_SIR-diagCNC.obj")).to_grid()
    assert closed.closed and polyline_planarity(closed.vertices[[0, -1]]).max() > 1e-6
    with pytest.raises(GeometryError, match="do not meet in a single point"):
        isotropic.isotropic_transform(closed, IsotropicMobius(), max_residual=1e-3)
