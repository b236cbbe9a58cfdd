"""Circular meshes (§2.3.3, Remark 2.1): the optimiser's circular target and the support of the vertex offset.

Every property is checked apart from the code under test: concyclic corners by Ptolemy's theorem (a convex
quad is inscribed in a circle iff ``|ac|·|bd| = |ab|·|cd| + |bc|·|da|``) and planarity by an SVD of the
corners; torsion-free axes by the distance between the two axis lines of every edge; the constant-distance
offset by the lengths of the offset edges.  Real meshes: WWmore/DOS ``objs/obj_anet/enneper2.obj`` (a
curvature-line net), WWmore/DOI ``objs/undoloid2_cut2_remesh_SIR-diagCNC.obj`` (an annulus, closed rows) and
WWmore/DOS ``objs/obj_pq/conical1.obj`` (a conical mesh), from the shared data.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from conftest import shared_file, write_patch_obj
from ppfab.errors import GeometryError
from ppfab.io import load_mesh
from ppfab.mesh import QuadGrid
from ppfab.optimize import optimize
from ppfab.optimize.terms import face_angle_balance
from ppfab.support.circular import support_circular, vertex_offset


def ptolemy_defect(corners: np.ndarray) -> np.ndarray:
    """``(F,)`` relative defect of Ptolemy's equality ``|ac||bd| = |ab||cd| + |bc||da|`` of quads ``(F, 4, 3)``
    (0 exactly when the four corners lie on a circle in this order; second order in the distance from it)."""
    a, b, c, d = (corners[:, k] for k in range(4))
    n = lambda x: np.linalg.norm(x, axis=1)           # noqa: E731
    diag = n(c - a) * n(d - b)
    return np.abs(diag - (n(b - a) * n(d - c) + n(c - b) * n(a - d))) / diag


def off_circle(corners: np.ndarray) -> np.ndarray:
    """``(F,)`` distance of the fourth corner from the circle through the first three, over its radius (first
    order), with the circumcentre ``a + (|c−a|² (w × (b−a)) + |b−a|² ((c−a) × w)) / (2|w|²)``, ``w = (b−a)×(c−a)``."""
    a, b, c, d = (corners[:, k] for k in range(4))
    ab, ac = b - a, c - a
    w = np.cross(ab, ac)
    centre = a + (np.einsum("ij,ij->i", ac, ac)[:, None] * np.cross(w, ab)
                  + np.einsum("ij,ij->i", ab, ab)[:, None] * np.cross(ac, w)) / (2.0 * np.einsum("ij,ij->i", w, w))[:, None]
    radius = np.linalg.norm(a - centre, axis=1)
    return np.abs(np.linalg.norm(d - centre, axis=1) - radius) / radius


def flatness(corners: np.ndarray) -> np.ndarray:
    """``(F,)`` smallest singular value of the centred corners over the mean diagonal (0: planar)."""
    x = corners - corners.mean(axis=1, keepdims=True)
    s = np.linalg.svd(x, compute_uv=False)[:, 2]
    return s / np.linalg.norm(corners[:, 2] - corners[:, 0], axis=1)


def axis_line_gaps(vertices: np.ndarray, edges: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """``(E,)`` distance between the lines ``v_i + t a_i`` and ``v_j + t a_j`` of every edge (0: coplanar)."""
    d = vertices[edges[:, 1]] - vertices[edges[:, 0]]
    c = np.cross(axes[edges[:, 0]], axes[edges[:, 1]])
    cn = np.linalg.norm(c, axis=1)
    gap = np.abs(np.einsum("ij,ij->i", d, c)) / np.maximum(cn, 1e-300)
    parallel = cn < 1e-12                               # parallel axes: coplanar with the edge, gap 0
    return np.where(parallel, 0.0, gap)


def vertex_normals_of(qm) -> np.ndarray:
    """``(N, 3)`` unit normals at the vertices: the mean of the unit normals of the faces around each."""
    c = qm.face_corners
    n = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    acc = np.zeros((len(qm.vertices), 3))
    np.add.at(acc, qm.faces.ravel(), np.repeat(n, 4, axis=0))
    return acc / np.linalg.norm(acc, axis=1, keepdims=True)


def revolution_grid() -> QuadGrid:
    """A quad grid of meridians and parallels of a surface of revolution, unevenly spaced: every face is an
    isosceles trapezoid, so the mesh is exactly circular (and conical), in mm."""
    z = np.array([0.0, 700.0, 1500.0, 2100.0, 3000.0, 3600.0])
    r = 9000.0 - 0.0004 * (z - 1000.0) ** 2
    phi = np.radians([0.0, 9.0, 17.0, 28.0, 36.0, 47.0, 55.0])
    v = np.stack([r[:, None] * np.cos(phi)[None], r[:, None] * np.sin(phi)[None],
                  np.repeat(z[:, None], len(phi), axis=1)], axis=-1)
    return QuadGrid(v)


@pytest.fixture(scope="module")
def enneper_circular():
    mesh = load_mesh(shared_file("DOS__enneper2.obj"))
    return mesh, optimize(mesh, families="none", keep_circular=True)


def test_face_angle_balance_derivative_matches_finite_differences():
    rng = np.random.default_rng(3)
    v = rng.normal(size=(8, 3))
    faces = np.array([[0, 1, 2, 3], [4, 5, 6, 7]])
    r, jac = face_angle_balance(v, faces)
    h = 1e-6
    for f in range(2):
        for k in range(4):
            for d in range(3):
                up, down = v.copy(), v.copy()
                up[faces[f, k], d] += h
                down[faces[f, k], d] -= h
                fd = (face_angle_balance(up, faces)[0][f] - face_angle_balance(down, faces)[0][f]) / (2 * h)
                assert jac[f, k, d] == pytest.approx(fd, abs=1e-7)


def test_a_real_curvature_line_net_becomes_circular(enneper_circular):
    mesh, res = enneper_circular
    before = off_circle(mesh.to_quadmesh().face_corners if isinstance(mesh, QuadGrid) else mesh.face_corners)
    qm = res.mesh.to_quadmesh() if isinstance(res.mesh, QuadGrid) else res.mesh
    assert before.max() > 1e-2                          # the input's panels are not on circles
    assert res.targets_met and res.circular_max <= 1e-6
    assert off_circle(qm.face_corners).max() < 1e-6     # every panel's corners on a circle
    assert ptolemy_defect(qm.face_corners).max() < 1e-10
    assert flatness(qm.face_corners).max() < 1e-6       # and planar
    assert res.displacement_rel < 1e-3                  # a principal net moves little to become circular
    assert "max circular residual" in res.message


@pytest.mark.parametrize("name", ["DOI__undoloid2_cut2_remesh_SIR-diagCNC.obj", "DOS__conical1.obj"])
def test_real_meshes_become_circular_with_their_rows_planar(name):
    mesh = load_mesh(shared_file(name))
    res = optimize(mesh, families="rows", keep_circular=True)
    qm = res.mesh.to_quadmesh() if isinstance(res.mesh, QuadGrid) else res.mesh
    assert res.targets_met
    assert off_circle(qm.face_corners).max() < 5e-6
    rows = [qm.vertices[p.vertices] for p in qm.family(0) if len(p) >= 3]
    for pts in rows:                                    # each row in a plane (SVD, relative to its length)
        s = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
        assert s[2] / np.linalg.norm(pts[-1] - pts[0]) < 1e-5


def test_an_unmet_circular_target_is_reported():
    mesh = load_mesh(shared_file("DOS__enneper2.obj"))
    res = optimize(mesh, families="none", keep_circular=True, target_circular=1e-12, max_iterations=2)
    assert not res.targets_met
    assert "circular residual" in res.message and "> 1e-12 rad" in res.message


def test_an_exactly_circular_grid_has_exact_vertex_offset_axes():
    grid = revolution_grid()
    qm = grid.to_quadmesh()
    assert off_circle(qm.face_corners).max() < 1e-12
    off = vertex_offset(grid)
    assert off.closure_max < 1e-12
    s = support_circular(grid)
    gaps = axis_line_gaps(qm.vertices, qm.topology.edges, s.axes)
    assert gaps.max() <= 1e-9                           # mm: torsion-free to rounding
    # the offset at 200 mm along the unit vectors: every offset edge parallel to its edge (a parallel mesh)
    e = qm.topology.edges
    off_v = qm.vertices + 200.0 * off.unit
    d0 = qm.vertices[e[:, 1]] - qm.vertices[e[:, 0]]
    d1 = off_v[e[:, 1]] - off_v[e[:, 0]]
    sin = np.linalg.norm(np.cross(d0, d1), axis=1) / (np.linalg.norm(d0, axis=1) * np.linalg.norm(d1, axis=1))
    assert sin.max() < 1e-12
    assert s.meta["offset_length_spread"] < 1e-9          # the parallel solve keeps the unit offset


def test_the_support_of_an_optimised_real_mesh_is_torsion_free_with_unit_offsets(enneper_circular):
    _, res = enneper_circular
    qm = res.mesh.to_quadmesh() if isinstance(res.mesh, QuadGrid) else res.mesh
    s = support_circular(res.mesh)
    mm = 1500.0                                         # the mesh's units as the examples scale it
    gaps = axis_line_gaps(qm.vertices, qm.topology.edges, s.axes) * mm
    assert gaps.max() < 0.01                            # mm, on a mesh planar and circular to 1e-7
    assert s.meta["offset_length_spread"] < 1e-4        # a constant-distance vertex offset
    assert np.degrees(np.arccos(np.abs(np.einsum("ij,ij->i", s.axes, vertex_normals_of(qm))).min())) < 3.0


def test_a_mesh_that_is_not_circular_is_refused_naming_a_face():
    mesh = load_mesh(shared_file("DOS__enneper2.obj"))
    with pytest.raises(GeometryError, match=r"not circular: the corners of face \d+ are not on a circle"):
        support_circular(mesh)


def test_ppfab_build_refuses_circular_support_of_a_mesh_that_is_not_circular(tmp_path):
    design = tmp_path / "circ.toml"
    design.write_text(f'[geometry]\nmesh = "{shared_file("DOS__enneper2.obj").as_posix()}"\nscale = 1500.0\n'
                      '[support]\nmethod = "circular"\n')
    out = subprocess.run([sys.executable, "-m", "fabrication.cli", "build", str(design), "-o",
                          str(tmp_path / "out")], capture_output=True, text=True, timeout=300)
    assert out.returncode == 1, out.stderr           # a geometry error (docs/bad-input.md)
    last = out.stderr.strip().splitlines()[-1]
    assert "not circular" in last and "keep_circular" in last and "Traceback" not in out.stderr
    assert not (tmp_path / "out").exists()


def test_a_circular_p_patch_of_a_real_mesh_builds_verifies_and_stays_circular_in_its_files(tmp_path):
    """A 9 × 8 patch of DOS conical1 made a circular P mesh (rows planar, every panel on a circle) and built with
    the exact P support: the build's own verify passes, and the mesh it writes (``mesh.obj``, read here as plain
    text) keeps every panel on a circle and every row in a plane."""
    import tomllib

    from fabrication.design import parse_design
    from fabrication.pipeline.stages import build

    mesh = load_mesh(shared_file("DOS__conical1.obj"))
    assert mesh.grid_ids is not None
    ids = mesh.grid_ids[12:21, 10:18]
    rows, cols = ids.shape
    write_patch_obj(mesh.vertices, ids, tmp_path / "patch.obj")
    design = (f'[design]\nname = "circular_patch"\n[geometry]\nmesh = "{(tmp_path / "patch.obj").as_posix()}"\n'
              'scale = 1500.0\n[optimize]\nfamilies = "rows"\nkeep_circular = true\ntarget_delta_f = 1e-7\n'
              'target_delta_p = 1e-7\ntarget_circular = 1e-7\n[support]\nmethod = "p"\nfamily = "rows"\n'
              '[beams]\njoint = "segmented"\ncontinuous = "rows"\ndepth = 200.0\nthickness = 15.0\n'
              'fallback = "segmented"\n[panels]\nplanarity_tolerance = 0.5\ngap = 24.0\n[glazing]\n'
              'retention = "silicone"\nmax_tilt_deg = 13.5\n[nesting]\ntime_budget = 0.5\n[beam_nesting]\n'
              'time_budget = 0.5\n[output]\npanels_step = false\nreport = false\nifc = false\nrhino = false\n'
              'glb = false\n')
    b = build(parse_design(tomllib.loads(design), base_dir=tmp_path))
    out = b.write(tmp_path / "out")                    # runs every check of ppfab verify before it renames
    lines = (out / "mesh.obj").read_text().splitlines()
    verts = np.array([[float(x) for x in ln.split()[1:4]] for ln in lines if ln.startswith("v ")])
    faces = np.array([[int(x.split("/")[0]) - 1 for x in ln.split()[1:]] for ln in lines if ln.startswith("f ")])
    assert faces.shape == ((rows - 1) * (cols - 1), 4)
    corners = verts[faces]
    assert off_circle(corners).max() < 1e-5             # panels on circles, as written (mm coordinates)
    assert flatness(corners).max() < 1e-6
    row_pts: dict[int, set[int]] = {}                   # the rows, read from the faces in the patch's order
    for k, f in enumerate(faces):                       # face k lies between rows k // (cols - 1) and the next
        i = k // (cols - 1)
        row_pts.setdefault(i, set()).update((int(f[0]), int(f[3])))
        row_pts.setdefault(i + 1, set()).update((int(f[1]), int(f[2])))
    assert len(row_pts) == rows
    for pts in row_pts.values():
        p = verts[sorted(pts)]
        s = np.linalg.svd(p - p.mean(axis=0), compute_uv=False)
        assert s[2] < 0.01                              # mm: each row of the written mesh in its plane


def test_ppfab_optimize_keep_circular_writes_a_circular_mesh(tmp_path, capsys):
    """``ppfab optimize --keep-circular`` on the shared enneper2 OBJ: exit 0, the file read back through the
    real reader has every panel on a circle (its own circumcircle measure), and the summary line says so."""
    from fabrication.cli import main
    from ppfab.io import read_mesh

    src = shared_file("DOS__enneper2.obj")
    out = tmp_path / "circular.obj"
    assert main(["optimize", str(src), "-o", str(out), "--families", "none", "--keep-circular"]) == 0
    err = capsys.readouterr().err
    assert "max circular residual" in err and "circular residual max" in err
    mesh = read_mesh(out)
    assert off_circle(mesh.face_corners).max() < 1e-6
    assert off_circle(read_mesh(src).face_corners).max() > 1e-2
