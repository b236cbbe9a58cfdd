"""P and PP support structures on real quad meshes that are not regular grids: holes, singular vertices,
annuli, jagged boundaries, a flat mesh of straight polylines.

Each mesh (third-party files, provenance in tests/data/meshes/README.md and ../shared/data/README.md) is
optimised for planar faces and planar polylines, scaled to a 30 m roof (mm), and given its support structure
as a build does (beam depth 200 mm, torsion tolerance 0.5 mm).  The tests measure what a fabricator relies
on with formulas of their own:

* torsion of every edge: the angle between the two end axes projected onto the plane perpendicular to the
  edge, and the offset at beam depth as the distance of ``v_j + D a_j`` from the plane through ``v_i``,
  ``v_j`` and ``v_i + a_i`` (and the other way round);
* the angle between each axis and the surface normal, the normal from Newell's formula of each face;
* how far below the mesh the axes of every edge of a planar beam cross (closest points of the two axis
  lines), which must be beyond the beam depth;
* that the axis of a vertex lies in the plane of every planar beam through it, and where more than two meet
  it is the eigenvector of ``Σ n nᵀ`` for the smallest eigenvalue.
"""

from __future__ import annotations

import numpy as np
import pytest

from ppfab.io import load_mesh
from ppfab.mesh import QuadMesh
from ppfab.optimize import optimize
from ppfab.support.lines import polyline_planes, select_polylines
from ppfab.support.p import support_p
from ppfab.support.params import BeamContext
from ppfab.support.pp import support_pp
from ppfab.support.quality import check_axis_angles
from ppfab.support.structure import vertex_normals
from ppfab.errors import GeometryError
from ppfab.transforms.similarity import transform

from conftest import REPO, SHARED_DATA, shared_file

LOCAL = REPO / "tests" / "data" / "meshes"
DEPTH = 200.0
TOLERANCE = 0.5
SPAN = 30_000.0


def roof(path, families: str | None = "both") -> QuadMesh:
    """The mesh of ``path``, optimised for ``families`` (``None``: as it is), scaled to a ``SPAN`` mm roof."""
    mesh = load_mesh(path)
    if families is not None:
        res = optimize(mesh, {"families": families})
        assert res.targets_met, res.message
        mesh = res.mesh
    return transform(mesh, SPAN / float(np.ptp(mesh.vertices, axis=0).max()))


# -- independent measures -----------------------------------------------------------------------------

def newell_normals(mesh: QuadMesh) -> np.ndarray:
    """``(N, 3)`` unit vertex normals: the mean of the unit Newell normals of the faces at each vertex."""
    c = mesh.vertices[mesh.faces]
    nxt = np.roll(c, -1, axis=1)
    n = np.stack([((c[..., 1] - nxt[..., 1]) * (c[..., 2] + nxt[..., 2])).sum(1),
                  ((c[..., 2] - nxt[..., 2]) * (c[..., 0] + nxt[..., 0])).sum(1),
                  ((c[..., 0] - nxt[..., 0]) * (c[..., 1] + nxt[..., 1])).sum(1)], axis=1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    acc = np.zeros_like(mesh.vertices)
    for k in range(4):
        np.add.at(acc, mesh.faces[:, k], n)
    return acc / np.linalg.norm(acc, axis=1, keepdims=True)


def edges_of(mesh: QuadMesh) -> np.ndarray:
    f = mesh.faces
    return np.unique(np.sort(np.stack([f.ravel(), np.roll(f, -1, axis=1).ravel()], axis=1), axis=1), axis=0)


def torsion_angle(mesh: QuadMesh, axes: np.ndarray) -> np.ndarray:
    """``(E,)`` degrees: angle between the end axes projected onto the plane perpendicular to the edge."""
    e = edges_of(mesh)
    d = mesh.vertices[e[:, 1]] - mesh.vertices[e[:, 0]]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    pi = axes[e[:, 0]] - np.einsum("ij,ij->i", axes[e[:, 0]], d)[:, None] * d
    pj = axes[e[:, 1]] - np.einsum("ij,ij->i", axes[e[:, 1]], d)[:, None] * d
    cos = np.abs(np.einsum("ij,ij->i", pi, pj)) / (np.linalg.norm(pi, axis=1) * np.linalg.norm(pj, axis=1))
    return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))


def torsion_mm(mesh: QuadMesh, axes: np.ndarray, depth: float) -> np.ndarray:
    """``(E,)`` the larger distance of one axis' point at ``depth`` from the plane of the edge and the other
    axis (through the three points ``v_i``, ``v_j``, ``v_i + a_i``)."""
    e = edges_of(mesh)
    out = np.zeros(len(e))
    for s, (i, j) in enumerate(e):
        for a, b in ((i, j), (j, i)):
            p0, p1, p2 = mesh.vertices[a], mesh.vertices[b], mesh.vertices[a] + axes[a]
            n = np.cross(p1 - p0, p2 - p0)
            n /= np.linalg.norm(n)
            out[s] = max(out[s], abs(float((mesh.vertices[b] + depth * axes[b] - p0) @ n)))
    return out


def axis_normal_angle(mesh: QuadMesh, axes: np.ndarray) -> np.ndarray:
    c = np.abs(np.einsum("ij,ij->i", axes, newell_normals(mesh)))
    return np.degrees(np.arccos(np.clip(c, 0.0, 1.0)))


def crossing_depth(mesh: QuadMesh, axes: np.ndarray, lines: list) -> np.ndarray:
    """For every edge of the given polylines: how far along the axes (from the mesh) their two axis lines
    come closest, when both points lie below the mesh (``inf`` where the axes part)."""
    out = []
    for p in lines:
        vs = p.vertices
        pairs = list(zip(vs[:-1], vs[1:])) + ([(vs[-1], vs[0])] if p.closed else [])
        for i, j in pairs:
            a, b = axes[i], axes[j]
            w = mesh.vertices[i] - mesh.vertices[j]
            A = np.array([[a @ a, -a @ b], [a @ b, -b @ b]])
            if abs(np.linalg.det(A)) < 1e-12:
                out.append(np.inf)
                continue
            s, t = np.linalg.solve(A, [-(a @ w), -(b @ w)])
            out.append(min(s, t) if s > 0 and t > 0 else np.inf)
    return np.asarray(out)


def check_structure(mesh: QuadMesh, s, max_angle: float = 75.0) -> dict:
    """The common assertions; returns the measures for mesh-specific ones."""
    a = s.axes
    assert np.allclose(np.linalg.norm(a, axis=1), 1.0)
    tors = torsion_mm(mesh, a, DEPTH)
    assert tors.max() <= TOLERANCE, f"torsion {tors.max():.3g} mm"
    np.testing.assert_allclose(np.sort(tors), np.sort(s.torsion_offset(DEPTH)), atol=1e-6)
    ang = torsion_angle(mesh, a)
    assert ang.max() <= np.degrees(np.arcsin(TOLERANCE / DEPTH)) * 1.01
    normal = axis_normal_angle(mesh, a)
    assert normal.max() <= max_angle
    assert np.all(np.einsum("ij,ij->i", a, newell_normals(mesh)) < 0)        # into the structure
    planar = [p for k, p in enumerate(mesh.polylines) if s.polyline_planar[k]]
    cross = crossing_depth(mesh, a, planar)
    assert cross.min() > DEPTH, f"axes cross {cross.min():.0f} mm below the mesh"
    # every axis lies in the plane of each planar beam through its vertex (exactly where two meet)
    at = s.planes_at
    for k, p in enumerate(mesh.polylines):
        if s.polyline_planar[k]:
            n = s.polyline_planes[k, :3]
            two = p.vertices[at[p.vertices] == 2]
            assert np.abs(a[two] @ n).max(initial=0.0) < 1e-9
            assert np.abs(mesh.vertices[p.vertices] @ n + s.polyline_planes[k, 3]).max() < 0.5   # mm
    return {"torsion": tors, "normal": normal, "cross": cross}


def multi_plane_axes_are_least_squares(mesh: QuadMesh, s) -> int:
    """At every vertex with more than two planar beams the axis is the eigenvector of Σ n nᵀ for the smallest
    eigenvalue; returns how many such vertices there are."""
    count = 0
    normals_at: dict[int, list[np.ndarray]] = {}
    for k, p in enumerate(mesh.polylines):
        if s.polyline_planar[k]:
            for v in set(p.vertices.tolist()):
                normals_at.setdefault(v, []).append(s.polyline_planes[k, :3])
    for v, ns in normals_at.items():
        if len(ns) >= 3 and s.planes_at[v] >= 3:
            n = np.array(ns)
            w, vec = np.linalg.eigh(n.T @ n)
            assert abs(abs(vec[:, 0] @ s.axes[v]) - 1.0) < 1e-8
            count += 1
    return count


CONTEXT = BeamContext(DEPTH, TOLERANCE)


def test_pp_dome_with_valence_3_vertices_has_exact_axes():
    """quad_dome: a disk whose polylines end at four valence-3 vertices; there the three planes share a
    line, so the least-squares axis lies in all three and the structure is torsion-free.  (The optimised
    dome's steepest boundary polyline plane is 31° from the normal at a corner: the limit of the 'tangent'
    rule is raised to 35° so that every polyline stays a planar beam.)"""
    mesh = roof(LOCAL / "DOS__quad_dome.obj")
    s = support_pp(mesh, beams=CONTEXT, max_normal_angle_deg=35.0)
    m = check_structure(mesh, s)
    assert not s.left_out and s.planar_families == (0, 1)
    assert multi_plane_axes_are_least_squares(mesh, s) == 4
    # the three planes share their line to a misfit of 2e-5 at the valence-3 vertices (the same with δ targets
    # of 1e-9: a property of this optimised dome, not of the tolerance); the torsion left is 2.6 µm
    assert s.misfit.max() < 5e-5 and m["torsion"].max() < 1e-2
    sing = np.flatnonzero(~mesh.topology.boundary_vertices & (mesh.topology.valence == 3))
    assert sorted(s.planes_at[sing].tolist()) == [3, 3, 3, 3]


def test_pp_minimal_surface_with_holes_and_valence_6():
    """complete01: five holes, eight valence-6 vertices (six polylines end at each)."""
    mesh = roof(LOCAL / "DOS__complete01.obj")
    assert mesh.grid is None and (mesh.topology.valence[~mesh.topology.boundary_vertices] == 6).sum() == 8
    s = support_pp(mesh, beams=CONTEXT)
    m = check_structure(mesh, s)
    assert multi_plane_axes_are_least_squares(mesh, s) == 8
    # polylines left out are exactly those whose plane cannot hold an axis within 30° of the normal
    planes = polyline_planes(mesh, vertex_normals(mesh))
    tangent = set(np.flatnonzero(select_polylines(mesh, ["tangent"], "t", planes, 30.0)).tolist())
    assert {k for k, _ in s.left_out} == tangent and len(tangent) > 0
    assert all("from the surface normal" in why for _, why in s.left_out)
    assert m["normal"].max() < 40.0


def test_pp_closed_torus_with_valence_3_and_5():
    mesh = roof(LOCAL / "libhedra__boxtoruscc2.off")
    assert not mesh.topology.boundary_vertices.any()
    s = support_pp(mesh, beams=CONTEXT)
    check_structure(mesh, s)
    assert multi_plane_axes_are_least_squares(mesh, s) >= 1


def test_p_tube_with_jagged_boundaries():
    """cmc1: a tube (two boundary loops) whose boundaries zig-zag: 64 polylines of one edge.  P support: the
    rows are the planar beams, every axis lies in its row's plane, the other edges are torsion-free."""
    mesh = roof(LOCAL / "DOS__cmc1.obj", "rows")
    s = support_p(mesh, "rows", beams=CONTEXT)
    check_structure(mesh, s)
    assert sum(len(p) == 2 for p in mesh.polylines) >= 60
    rows = [k for k, p in enumerate(mesh.polylines) if p.family == 0 and len(p) >= 3]
    assert all(s.polyline_planar[k] for k in rows if k not in dict(s.left_out))


def test_flat_mesh_of_straight_polylines():
    """bar2d: a flat 101 × 11 grid; every polyline is straight, so its plane is the one through it that holds
    the normal (vertical), and both P and PP supports are the normals with no torsion."""
    mesh = roof(LOCAL / "libhedra__bar2d.off", None)
    for s in (support_pp(mesh, beams=CONTEXT), support_p(mesh, "rows", beams=CONTEXT)):
        check_structure(mesh, s, max_angle=1e-6)
        assert np.abs(s.polyline_planes[:, 2]).max() < 1e-12            # vertical planes
        assert s.meta["straight_polylines"] == len(mesh.polylines)


@pytest.mark.slow
@pytest.mark.parametrize("name, families, method", [
    ("DOS__planarizednormalized_six_quad.obj", "both", "pp"),                 # annulus, two valence-6 vertices
    ("compas_libigl__inspired_mesh_quads_Conjugate.off", "both", "pp"),       # jagged boundary
    ("compas_libigl__inspired_mesh_quads_Smooth.off", "both", "pp"),          # jagged boundary, non-conjugate
    ("libhedra__0-static.off", "rows", "p"),                                  # valence 3, P
], ids=["six_quad-annulus", "Conjugate-jagged", "Smooth-jagged", "0-static-P"])
def test_general_meshes(name, families, method):
    path = SHARED_DATA / name if (SHARED_DATA / name).exists() else LOCAL / name
    mesh = roof(path, families)
    s = support_pp(mesh, beams=CONTEXT) if method == "pp" else support_p(mesh, "rows", beams=CONTEXT)
    m = check_structure(mesh, s)
    multi_plane_axes_are_least_squares(mesh, s)
    assert np.median(m["normal"]) < 30.0


@pytest.mark.slow
def test_mesh_with_holes_whose_solved_axes_lie_in_the_surface_is_refused():
    """gitter (four holes, flat around them): the polylines curving in its flat parts lie in the tangent
    plane and are left out; the axes solved for there turn into the surface.  Wherever the axes stay within
    75° of the normal the support is torsion-free; where they lie in the surface the solve cannot close the
    torsion of every edge (0.9 mm at 200 mm measured), and the axis check refuses the structure, naming the
    vertices and the reason."""
    mesh = roof(shared_file("libhedra__gitter.off"))
    s = support_pp(mesh, beams=CONTEXT)
    angle = axis_normal_angle(mesh, s.axes)
    both_near_normal = (angle[edges_of(mesh)] <= 75.0).all(axis=1)
    assert both_near_normal.mean() > 0.9
    assert torsion_mm(mesh, s.axes, DEPTH)[both_near_normal].max() <= TOLERANCE
    worst = int(np.argmax(axis_normal_angle(mesh, s.axes)))
    assert axis_normal_angle(mesh, s.axes)[worst] > 75.0 and s.planes_at[worst] <= 1
    with pytest.raises(GeometryError, match=r"more than support\.max_axis_angle_deg = 75°: N\d{4} (8|9)\d°.*axes "
                                            r"were solved to make the polylines left out"):
        check_axis_angles(s, 75.0)
