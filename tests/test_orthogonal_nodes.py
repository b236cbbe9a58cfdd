"""Orthogonal nodes (§2.3.4): where a planar row and a planar column of a PP mesh cross, their support planes meet
at a right angle.

Checked apart from the optimiser: the planes are fitted here by an SVD of each polyline's vertices and the node
angle is the angle between the two fitted normals; the PP support structure built from the result (the axes
``U ∩ W``) is checked for torsion by the distance between the two axis lines of every edge.  Real meshes:
WWmore/DOI ``objs/obj_rot/rot4_def1_sparse_rot.obj`` (a surface of revolution: meridians and parallels, its
nodes orthogonal as published) and WWmore/DOS ``objs/obj_anet/enneper2.obj`` (nodes up to 44° off).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import shared_file
from ppfab.errors import DesignError
from ppfab.io import load_mesh
from ppfab.mesh import QuadGrid
from ppfab.optimize import optimize
from ppfab.optimize.terms import node_pairs
from ppfab.support.pp import support_pp


def fitted_normals(grid: QuadGrid) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals of the SVD planes of the rows ``(m, 3)`` and the columns ``(n, 3)`` of a grid."""
    def normal(pts: np.ndarray) -> np.ndarray:
        return np.linalg.svd(pts - pts.mean(axis=0))[2][2]
    v = grid.vertices
    return (np.array([normal(v[i]) for i in range(v.shape[0])]),
            np.array([normal(v[:, j]) for j in range(v.shape[1])]))


def node_angle_deviation(grid: QuadGrid) -> np.ndarray:
    """``(m, n)`` deviation from 90° (degrees) of the angle between the row and the column plane at each node."""
    r, c = fitted_normals(grid)
    return np.degrees(np.arcsin(np.clip(np.abs(r @ c.T), 0.0, 1.0)))


def lattice_grid() -> QuadGrid:
    """A PP grid whose nodes are not orthogonal: a translational surface of two planar curves in planes 60°
    apart (rows in parallel planes, columns in parallel planes), 7 × 6 vertices, mm."""
    s = np.linspace(-3000.0, 3000.0, 7)
    t = np.linspace(-2500.0, 2500.0, 6)
    g = np.stack([s, np.zeros_like(s), -s ** 2 / 12000.0], axis=1)                      # in the plane y = 0
    d = np.array([np.cos(np.radians(60.0)), np.sin(np.radians(60.0)), 0.0])
    h = t[:, None] * d + np.stack([np.zeros_like(t), np.zeros_like(t), -t ** 2 / 9000.0], axis=1)
    return QuadGrid(g[:, None, :] + h[None, :, :])


def test_node_pairs_lists_every_crossing_of_a_row_and_a_column():
    grid = lattice_grid()
    qm = grid.to_quadmesh()
    pairs, verts = node_pairs(qm.polylines)
    assert len(pairs) == 7 * 6
    for (a, b), v in zip(pairs, verts):
        assert qm.polylines[a].family == 0 and qm.polylines[b].family == 1
        assert v in qm.polylines[a].vertices and v in qm.polylines[b].vertices


def test_a_surface_of_revolution_has_orthogonal_nodes_and_keeps_them():
    mesh = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj"))
    res = optimize(mesh, families="both", orthogonal_nodes=True)
    assert res.targets_met
    assert res.node_angle_max_input < 1e-4 and res.node_angle_max < 1e-4          # degrees
    assert res.displacement_rel < 1e-6                                               # nothing to change


def test_a_translational_lattice_becomes_orthogonal_and_stays_pp():
    grid = lattice_grid()
    before = node_angle_deviation(grid)
    assert before.max() > 25.0                          # the two families of planes are 60° apart
    res = optimize(grid, families="both", orthogonal_nodes=True, target_nodes=1e-8)
    assert res.targets_met, res.message
    out = res.mesh
    assert isinstance(out, QuadGrid)
    assert node_angle_deviation(out).max() < 1e-5       # degrees, fitted independently
    assert res.node_angle_max == pytest.approx(node_angle_deviation(out).max(), abs=1e-6)
    r, c = fitted_normals(out)
    v = out.vertices
    for i in range(v.shape[0]):                         # PP: every row and column in its plane (mm)
        assert np.abs((v[i] - v[i].mean(axis=0)) @ r[i]).max() < 1e-3
    for j in range(v.shape[1]):
        assert np.abs((v[:, j] - v[:, j].mean(axis=0)) @ c[j]).max() < 1e-3
    # the PP support's axes are the lines U ∩ W; at an orthogonal node the row plane, the column plane and the
    # axis form a right-angled frame, and the structure is torsion-free
    s = support_pp(out)
    qm = out.to_quadmesh()
    e = qm.topology.edges
    d = qm.vertices[e[:, 1]] - qm.vertices[e[:, 0]]
    cr = np.cross(s.axes[e[:, 0]], s.axes[e[:, 1]])
    cn = np.linalg.norm(cr, axis=1)
    gap = np.where(cn < 1e-12, 0.0, np.abs(np.einsum("ij,ij->i", d, cr)) / np.maximum(cn, 1e-300))
    assert gap.max() < 0.01                             # mm (the planes are planar to 1e-7 of the size)
    axes = s.axes.reshape(v.shape)
    assert np.abs(np.einsum("ijk,ik->ij", axes, r)).max() < 1e-6     # each axis in its row plane
    assert np.abs(np.einsum("ijk,jk->ij", axes, c)).max() < 1e-6     # and in its column plane


def test_a_real_pp_patch_gets_orthogonal_nodes():
    """An 11 × 11 patch of DOS enneper2 (PP, nodes up to 17° off a right angle).  With both families planar,
    orthogonal nodes put the normals of one family's planes in a plane and the other's along its normal
    (§2.3.4): the patch moves 3 % of its size, and its panels skew (nothing asks for right corner angles)."""
    mesh = load_mesh(shared_file("DOS__enneper2.obj"))
    assert mesh.grid_ids is not None
    patch = QuadGrid(mesh.vertices[mesh.grid_ids[10:21, 10:21]])
    assert node_angle_deviation(patch).max() > 15.0
    res = optimize(patch, families="both", orthogonal_nodes=True)
    assert res.targets_met, res.message
    assert isinstance(res.mesh, QuadGrid)
    assert node_angle_deviation(res.mesh).max() < 1e-4
    assert res.displacement_rel < 0.05


def test_an_unmet_node_target_is_reported():
    res = optimize(lattice_grid(), families="both", orthogonal_nodes=True, max_iterations=2)
    assert not res.targets_met
    assert "node cosine" in res.message


def test_orthogonal_nodes_need_both_families():
    with pytest.raises(DesignError, match="orthogonal_nodes.*families = \"both\""):
        optimize(lattice_grid(), families="rows", orthogonal_nodes=True)
