"""Support structures: node axes, support planes and torsion (§2.2, Def. 2.3)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import shared_file

from fabrication.beams.samples import sample_conical_grid, sample_p_grid, sample_pp_grid
from ppfab import planes as pl
from ppfab.errors import DesignError, GeometryError
from ppfab.io import load_mesh
from ppfab.mesh import QuadMesh
from ppfab.metrics import polyline_planarity, quality
from ppfab.schema import parse_params
from ppfab.support.conical import conical_axis_residual, support_conical
from ppfab.support.p import support_p
from ppfab.support.parallel import support_parallel
from ppfab.support.params import SupportParams
from ppfab.support.pp import support_pp
from ppfab.support.select import support_structure
from ppfab.support.structure import torsion, torsion_offset, vertex_normals


def _independent_torsion(mesh, axes):
    """|det(ê, a_i, a_j)| / (|ê × a_i| |ê × a_j|) = sine of the torsion angle."""
    e = mesh.topology.edges
    d = mesh.vertices[e[:, 1]] - mesh.vertices[e[:, 0]]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ai, aj = axes[e[:, 0]], axes[e[:, 1]]
    det = np.abs(np.einsum("ij,ij->i", d, np.cross(ai, aj)))
    return det / (np.linalg.norm(np.cross(d, ai), axis=1) * np.linalg.norm(np.cross(d, aj), axis=1))


def _check_basic(s):
    a = s.axes
    assert np.allclose(np.linalg.norm(a, axis=1), 1.0, atol=1e-12)
    n = vertex_normals(s.mesh)
    assert np.all(np.einsum("ij,ij->i", a, n) < 0), "axes must point to the inside"
    _check_planes(s)


def _check_planes(s):
    a = s.axes
    # every edge lies in its support plane, and its support plane contains both axes where torsion is 0
    e = s.edges
    v = s.vertices
    scale = float(np.ptp(v, axis=0).max())
    dist = np.abs(pl.signed_distance(s.edge_planes[:, None, :], v[e]))
    assert dist.max() <= 1e-9 * scale + 1e-9 + float(s.polyline_deviation.max())
    assert np.allclose(np.sin(s.torsion), _independent_torsion(s.mesh, a), atol=1e-12)


def test_pp_axes_are_intersections_of_the_support_planes(pp_grid):
    s = support_pp(pp_grid)
    if quality(pp_grid).flipped_edges:      # two zoo patches fold: "inside" flips across the fold
        _check_planes(s)
    else:
        _check_basic(s)
    g = pp_grid
    U, W = pl.normalize(g.support_u), pl.normalize(g.support_w)
    a = s.axes[g.vertex_index]
    assert np.abs(np.einsum("ijk,ik->ij", a, U[:, :3])).max() < 1e-12
    assert np.abs(np.einsum("ijk,jk->ij", a, W[:, :3])).max() < 1e-12
    assert s.torsion.max() < 1e-9
    assert s.kind == "pp" and s.planar_families == (0, 1)
    # the grid's own axes (orient_axes of the face image) agree up to sign
    assert np.allclose(np.abs(np.einsum("ijk,ijk->ij", a, g.axes)), 1.0, atol=1e-12)


def test_pp_from_fitted_planes_of_a_real_mesh():
    mesh = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj"))
    s = support_pp(mesh)
    _check_basic(s)
    assert s.meta["planes"] == "least squares"
    diag = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    assert s.polyline_deviation.max() < 1e-6 * diag
    # edges are off their planes by at most ~1e-7 of the size: torsion stays tiny
    assert np.degrees(s.torsion.max()) < 1e-3


def test_parallel_mesh_on_a_pp_grid_reproduces_the_pp_axes():
    g = sample_pp_grid(6, 7)
    s = support_parallel(g)
    pp = support_pp(g)
    _check_basic(s)
    assert s.meta["exact"] and s.planar_families == (0, 1)
    assert np.abs(np.einsum("ij,ij->i", s.axes, pp.axes)).min() > 1 - 1e-12
    assert s.torsion.max() < 1e-9


def test_p_mesh_axes_lie_in_the_planar_family():
    g = sample_p_grid(8, 10)
    cols = polyline_planarity(g.cols())
    assert cols.max() > 1e-3           # the columns really are not planar
    s = support_p(g, "rows")
    _check_basic(s)
    U = pl.normalize(g.support_u)
    rows_fit = s.polyline_planes[: g.shape[0]]
    assert np.abs(np.abs(np.einsum("ij,ij->i", rows_fit[:, :3], U[:, :3])) - 1).max() < 1e-12
    a = s.axes[g.vertex_index]
    assert np.abs(np.einsum("ijk,ik->ij", a, U[:, :3])).max() < 1e-12
    assert s.torsion.max() < 1e-9
    assert s.normal_angle_deg.max() < 30
    assert support_structure(g).kind == "p"
    hinted = support_structure(g, planar_families=("rows",))
    assert hinted.kind == "p" and np.allclose(hinted.axes, s.axes)
    assert support_structure(sample_pp_grid(3, 4), planar_families=["rows", "cols"]).kind == "pp"
    assert support_p(g, 0, planes=g.support_u).torsion.max() < 1e-9


def test_conical_axes_make_equal_angles_with_the_faces():
    g = sample_conical_grid()
    s = support_conical(g)
    _check_basic(s)
    res = conical_axis_residual(s.mesh, s.axes)
    assert np.nanmax(res) < 1e-10
    assert np.isnan(res).sum() == 2 * (g.shape[0] + g.shape[1]) - 4   # boundary vertices (< 3 faces)
    # by symmetry the cone axes lie in the meridian planes (boundary columns: free, not symmetric)
    merid = np.cross(np.array([0.0, 0.0, 1.0]), g.vertices[0] / np.linalg.norm(g.vertices[0], axis=1)[:, None])
    a = s.axes[g.vertex_index]
    assert np.abs(np.einsum("ijk,jk->ij", a, merid))[:, 1:-1].max() < 1e-9
    assert s.torsion.max() < 1e-9                  # boundary axes from the parallel mesh too


def test_conical_real_mesh():
    mesh = load_mesh(shared_file("DOS__conical1.obj"))
    s = support_conical(mesh)
    _check_basic(s)
    assert np.nanmax(conical_axis_residual(mesh, s.axes)) < 2e-4      # the file is conical to ~1e-4
    assert np.degrees(s.torsion).max() < 0.02
    assert np.degrees(np.median(s.torsion)) < 1e-3


@pytest.mark.parametrize("name", ["DOS__conical1.obj", "DOI__undoloid2_cut2_remesh_SIR-diagCNC.obj",
                                  "DOS__enneper2.obj"])
def test_parallel_mesh_of_planar_quad_meshes_is_torsion_free(name):
    mesh = load_mesh(shared_file(name))
    s = support_parallel(mesh)
    _check_basic(s)
    assert s.meta["exact"]
    assert np.degrees(s.torsion).max() < 5e-3
    assert s.meta["normal_angle_max_deg"] < 30


@pytest.mark.parametrize("name", ["DOS__botanic-garden-bubble-0.obj",
                                  "compas_libigl__inspired_mesh_quads_Conjugate.off", "compas_libigl__tubemesh.off"])
def test_non_planar_meshes_get_a_reported_compromise(name):
    mesh = load_mesh(shared_file(name))
    s = support_parallel(mesh)
    _check_basic(s)
    assert not s.meta["exact"]       # no parallel mesh near the normal offset exists
    assert s.meta["normal_angle_max_deg"] <= 30 + 1e-9
    assert np.degrees(s.torsion).max() < 10
    summary = s.summary()
    assert summary["torsion_max_deg"] == pytest.approx(np.degrees(s.torsion.max()))


def test_singular_vertices_keep_axes():
    mesh = load_mesh(shared_file("DOS__botanic-garden-bubble-0.obj"))
    topo = mesh.topology
    sing = np.flatnonzero(~topo.boundary_vertices & (topo.valence != 4))
    assert len(sing) == 4
    s = support_structure(mesh)
    assert s.kind == "parallel" and s.mesh.grid is None
    assert np.all(np.isfinite(s.axes[sing]))


def test_rigid_motion_invariance():
    mesh = load_mesh(shared_file("DOS__conical1.obj"))
    rng = np.random.default_rng(5)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    t = rng.normal(size=3) * 10
    moved = QuadMesh(mesh.vertices @ q.T + t, mesh.faces)
    for fn in (support_parallel, support_conical):
        a, b = fn(mesh), fn(moved)
        assert np.abs(a.axes @ q.T - b.axes).max() < 1e-7
        assert np.abs(a.torsion - b.torsion).max() < 1e-9


def test_torsion_of_a_known_twist():
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    mesh = QuadMesh(v, np.array([[0, 1, 2, 3]]))
    alpha = 0.3
    axes = np.array([[0, 0, -1], [0, np.sin(alpha), -np.cos(alpha)], [0, 0, -1], [0, 0, -1]], float)
    t = torsion(mesh, axes)
    e = mesh.topology.edges.tolist()
    k = e.index([0, 1])
    assert t[k] == pytest.approx(alpha, abs=1e-14)
    assert torsion_offset(mesh, axes, 200.0)[k] == pytest.approx(200 * np.sin(alpha), abs=1e-9)
    # the other edges: along y the tilted axis stays in the plane spanned by y and z; along x both are -z
    others = [i for i, ed in enumerate(e) if ed != [0, 1]]
    assert np.abs(t[others]).max() < 1e-15
    # flipping an axis does not change torsion (lines, not vectors)
    assert np.allclose(torsion(mesh, axes * np.array([[1], [-1], [1], [-1]])), t)


def test_flip_turns_the_axes():
    g = sample_pp_grid(4, 5)
    a = support_structure(g).axes
    b = support_structure(g, SupportParams(flip=True)).axes
    assert np.allclose(a, -b)


def test_bad_input_is_rejected():
    g = sample_pp_grid(3, 3)
    qm = g.to_quadmesh()
    with pytest.raises(GeometryError, match="axes need shape"):
        torsion(qm, np.zeros((3, 3)))
    axes = support_pp(g).axes.copy()
    e0 = qm.topology.edges[0]
    d = qm.vertices[e0[1]] - qm.vertices[e0[0]]
    axes[e0[0]] = d / np.linalg.norm(d)
    with pytest.raises(GeometryError, match=rf"edge \({e0[0]}, {e0[1]}\): a node axis runs along the edge"):
        torsion(qm, axes)
    with pytest.raises(DesignError, match=r"support\.method: unknown support method .*did you mean 'parallel'"):
        parse_params(SupportParams, {"method": "paralel"}, "support")
    with pytest.raises(DesignError, match="support.family"):
        support_p(g, "diagonals")
    with pytest.raises(GeometryError, match=r"planes need shape \(4, 4\)"):
        support_p(g, 0, planes=np.zeros((2, 4)))
    # U_i parallel to W_j: no axis
    bad = g.with_vertices(g.vertices, support_u=g.support_u, support_w=np.repeat(g.support_u[:1], 4, axis=0))
    with pytest.raises(GeometryError, match=r"vertex \(0, 0\): support planes U_0 and W_0 are parallel"):
        support_pp(bad)
