"""Mesh files: quads kept, grid recovered from connectivity, clear errors, and the shared real meshes."""

import numpy as np
import pytest

from ppfab.errors import GeometryError, MeshFileError
from ppfab.io import grid_from_json, grid_to_json, load_mesh, read_mesh, write_obj, write_off
from ppfab.mesh import QuadGrid
from ppfab.metrics import quality

from conftest import shared_file, smooth_face_image

# file: (grid shape as a sorted pair or None, closed, δ_f max, δ_P max) from shared/data/README.md
README = {
    "DOS__conical1.obj": ((31, 37), False, 4.1e-5, 2.9e-2),
    "DOS__enneper2.obj": ((31, 31), False, 3.8e-4, 3.0e-5),
    "DOI__rot4_def1_sparse_rot.obj": ((33, 49), False, 1.5e-6, 3.2e-8),
    "DOI__rot4_def1_sparse.obj": ((33, 49), False, 5.2e-2, 1.9e-1),
    "DOI__undoloid2_cut2_remesh_SIR-diagCNC.obj": ((12, 48), True, 5.0e-5, 8.4e-5),
    "DOS__botanic-garden-bubble-0.obj": (None, False, 1.0e-2, 1.4e-1),
    "compas_libigl__inspired_mesh_quads_Conjugate.off": (None, False, 1.4e-2, 3.7e-2),
    "compas_libigl__tubemesh.off": ((10, 20), False, 9.5e-2, 4.1e-2),
}
COUNTS = {
    "DOS__conical1.obj": (1147, 1080), "DOS__enneper2.obj": (961, 900),
    "DOI__rot4_def1_sparse_rot.obj": (1617, 1536), "DOI__rot4_def1_sparse.obj": (1617, 1536),
    "DOI__undoloid2_cut2_remesh_SIR-diagCNC.obj": (576, 528), "DOS__botanic-garden-bubble-0.obj": (1121, 1076),
    "compas_libigl__inspired_mesh_quads_Conjugate.off": (1749, 1633), "compas_libigl__tubemesh.off": (200, 171),
}


@pytest.mark.parametrize("name", sorted(README))
def test_shared_meshes_load_and_agree_with_readme(name):
    mesh = load_mesh(shared_file(name))
    assert (len(mesh.vertices), len(mesh.faces)) == COUNTS[name]
    shape, closed, df, dp = README[name]
    q = quality(mesh)
    if shape is None:
        assert q.grid_shape is None
    else:
        assert tuple(sorted(q.grid_shape)) == shape
        assert q.closed == closed
    # the README rounds to two significant digits
    assert q.delta_f_max == pytest.approx(df, rel=0.05, abs=5e-8)
    assert max(q.delta_p_rows_max, q.delta_p_cols_max) == pytest.approx(dp, rel=0.05, abs=5e-9)


def test_conjugate_polylines_stop_at_jagged_boundary():
    mesh = load_mesh(shared_file("compas_libigl__inspired_mesh_quads_Conjugate.off"))
    lengths = [len(p) for p in mesh.polylines]
    assert min(lengths) == 2 and max(lengths) == 51
    # every edge lies on exactly one polyline
    assert sum(len(p) - 1 + p.closed for p in mesh.polylines) == len(mesh.edges)


def test_singular_vertices_stop_polylines():
    mesh = load_mesh(shared_file("DOS__botanic-garden-bubble-0.obj"))
    topo = mesh.topology
    singular = set(np.flatnonzero(~topo.boundary_vertices & (topo.valence != 4)).tolist())
    assert len(singular) == 4
    for p in mesh.polylines:
        inner = set(p.vertices[1:-1].tolist()) if not p.closed else set(p.vertices.tolist())
        assert not (inner & singular)
    assert sum(len(p) - 1 + p.closed for p in mesh.polylines) == len(mesh.edges)


def test_annulus_rows_close():
    mesh = load_mesh(shared_file("DOI__undoloid2_cut2_remesh_SIR-diagCNC.obj"))
    g = mesh.grid
    assert g.closed and g.shape == (12, 48)
    # recovered grid faces are exactly the file's faces with orientation kept
    faces = {tuple(np.roll(f, -int(np.argmin(f)))) for f in mesh.faces.tolist()}
    ids = g.vertex_ids
    for i in range(11):
        for j in range(48):
            quad = [ids[i, j], ids[i + 1, j], ids[i + 1, (j + 1) % 48], ids[i, (j + 1) % 48]]
            k = int(np.argmin(quad))
            assert tuple(np.roll(quad, -k)) in faces


def _shuffled(grid: QuadGrid, seed: int):
    """The grid's mesh with vertices and faces permuted and face start corners rotated."""
    rng = np.random.default_rng(seed)
    qm = grid.to_quadmesh()
    perm = rng.permutation(len(qm.vertices))
    inv = np.argsort(perm)
    faces = inv[qm.faces]
    faces = np.array([np.roll(f, rng.integers(4)) for f in faces])[rng.permutation(len(faces))]
    return qm.vertices[perm], faces


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_grid_recovered_whatever_the_vertex_order(tmp_path, seed):
    g, h = smooth_face_image(5, 8, seed)
    from ppfab.faceimage import pp_from_face_image

    grid = pp_from_face_image(g, h)
    v, f = _shuffled(grid, seed)
    from ppfab.mesh import QuadMesh

    write_obj(QuadMesh(v, f), tmp_path / "s.obj")
    back = load_mesh(tmp_path / "s.obj").grid
    assert back is not None
    got = back.vertices
    # the same grid up to the symmetries of a rectangle that keep orientation
    cands = [grid.vertices, grid.vertices[::-1, ::-1], grid.vertices.transpose(1, 0, 2)[::-1],
             grid.vertices.transpose(1, 0, 2)[:, ::-1]]
    assert any(c.shape == got.shape and np.allclose(c, got) for c in cands)


def test_obj_off_round_trip_row_major(tmp_path, pp_grid):
    for suffix, writer in ((".obj", write_obj), (".off", write_off)):
        path = tmp_path / f"m{suffix}"
        writer(pp_grid, path)
        mesh = read_mesh(path)
        assert np.array_equal(mesh.vertices, pp_grid.vertices.reshape(-1, 3))
        m1, n1 = pp_grid.shape
        assert mesh.faces[0].tolist() == [0, n1, n1 + 1, 1]
        assert len(mesh.faces) == (m1 - 1) * (n1 - 1)
        # recovered grid is the original (row-major file is already in canonical order)
        assert np.array_equal(load_mesh(path).grid.vertices, pp_grid.vertices)


def test_json_round_trip(tmp_path, pp_grid):
    import json

    path = tmp_path / "g.json"
    path.write_text(json.dumps(grid_to_json(pp_grid)))
    back = grid_from_json(path)
    assert np.array_equal(back.vertices, pp_grid.vertices)
    assert np.array_equal(back.support_u, pp_grid.support_u)
    assert np.array_equal(back.face_image, pp_grid.face_image)


BAD = {
    "triangle": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n", "not quads"),
    "nan": ("v 0 0 nan\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", "non-finite"),
    "out-of-range": ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 9\n", "does not exist"),
    "repeated-corner": ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 2 4\n", "repeats a corner"),
    "non-manifold": ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nv 1 -1 0\nv 1 -1 1\nv 1 1 1\n"
                     "f 1 2 3 4\nf 2 5 6 3\nf 2 3 9 8\n", "non-manifold"),
    "flipped": ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nf 1 2 3 4\nf 2 3 6 5\n",
                "inconsistent orientation"),
    "not-numbers": ("v 0 0 zero\n", "not numbers"),
    "duplicate-vertices": ("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 0 2 0\nv 1 2 0\nv 2 2 0\nv 1 1 0\nv 1 1 1\nv 2 1 1\nv 2 1 0.5\n"
                           "f 1 2 5 4\nf 2 3 6 5\nf 4 5 8 7\nf 5 6 9 8\nf 10 11 12 13\n", "coincide"),
    "zero-area": ("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 0 1 0\nf 1 2 3 4\n", "zero area"),
    "empty": ("# nothing\n", "no vertices"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_mesh_files_get_clear_errors(tmp_path, case):
    text, message = BAD[case]
    path = tmp_path / f"{case}.obj"
    path.write_text(text)
    with pytest.raises(MeshFileError, match=message) as info:
        read_mesh(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_missing_file_and_unknown_format(tmp_path):
    with pytest.raises(MeshFileError, match="cannot read"):
        read_mesh(tmp_path / "nope.obj")
    p = tmp_path / "x.stl"
    p.write_text("solid")
    with pytest.raises(MeshFileError, match="unknown mesh format"):
        read_mesh(p)


def test_general_mesh_is_not_a_grid():
    mesh = load_mesh(shared_file("DOS__botanic-garden-bubble-0.obj"))
    with pytest.raises(GeometryError, match="not a regular grid"):
        mesh.to_grid()


def test_trimesh_view_and_degenerate_edges(pp_grid):
    import trimesh

    tm = trimesh.Trimesh(*pp_grid.triangles(), process=False)
    assert len(tm.faces) == 2 * pp_grid.n_faces
    d1, d2 = pp_grid.diagonals()
    quad_area = 0.5 * np.linalg.norm(np.cross(d1, d2), axis=-1).sum()   # exact for planar quads
    assert tm.area == pytest.approx(quad_area, rel=1e-9)
    v = pp_grid.vertices.copy()
    v[0, 1] = v[0, 0]
    q = quality(pp_grid.with_vertices(v))
    assert q.degenerate_edges == 1


def test_folded_mesh_is_detected():
    x, y = np.meshgrid(np.linspace(0, 1, 6), np.linspace(0, 1, 5), indexing="ij")
    z = np.zeros_like(x)
    v = np.stack([x, y, z], -1)
    v[3:, :, 0] = 2 * v[2, :, 0][None] - v[3:, :, 0]   # fold the sheet back over itself at row 2
    v[3:, :, 2] = 0.01 * np.arange(1, 4)[:, None]
    q = quality(QuadGrid(v))
    assert q.flipped_edges > 0
