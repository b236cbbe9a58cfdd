"""The sections net on a designer's surface (ppfab.surface, fabrication.surfacefile, ``ppfab remesh``).

Checked independently of the code under test: the rows' planarity against the section planes; the distance
of every vertex to the surface as read (Gauss–Newton on the NURBS through rhino3dm, trimesh's exhaustive
closest point on a mesh); the conjugacy of the net's two directions with the second fundamental form of a
local quadric fitted to the surface's own samples (not the height-field spline); trimming against shapely.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import shared_file
from surface_cases import resample_quad_mesh, write_nurbs

# two NURBS surfaces (4 × 4 Bézier control nets): a dome with a twist in metres, a saddle in feet as a Brep
DOME = [[0.0, 0.5, 0.5, 0.0], [0.5, 1.3, 1.2, 0.5], [0.5, 1.2, 1.3, 0.5], [0.0, 0.5, 0.5, 0.0]]
SADDLE = [[0.0, 4.0, 4.0, 0.0], [-3.0, 0.5, 0.5, -3.0], [-3.0, 0.5, 0.5, -3.0], [1.0, 4.5, 4.5, 0.0]]
# case: control heights, size, unit, written as a Brep, mm per unit, spacing mm, largest edge / spacing measured
NURBS = {"dome_m": (DOME, 12.0, 9.0, "Meters", False, 1000.0, 1500.0, 1.25),
         "saddle_ft_brep": (SADDLE, 40.0, 28.0, "Feet", True, 304.8, 1500.0, 1.25)}


def quad_twist(points: np.ndarray, mesh, radius: float) -> np.ndarray:
    """Per face: |II(a, b)| / (|a| |b| max |κ|) with ``a``, ``b`` the face's mean row and column edges and II the
    Hessian of a quadric ``z(x, y)`` fitted (least squares) to the surface samples within ``radius`` of the
    face centre in plan; 0 for a conjugate pair."""
    from scipy.spatial import cKDTree

    v = np.asarray(mesh.vertices).reshape(-1, 3)
    f = np.asarray(mesh.to_quadmesh().faces if hasattr(mesh, "to_quadmesh") else mesh.faces)
    c = v[f]
    a = 0.5 * ((c[:, 3] - c[:, 0]) + (c[:, 2] - c[:, 1]))       # along the rows (sections)
    b = 0.5 * ((c[:, 1] - c[:, 0]) + (c[:, 2] - c[:, 3]))       # along the columns (conjugate curves)
    tree = cKDTree(points[:, :2])
    out = np.empty(len(f))
    for k, centre in enumerate(c.mean(axis=1)):
        near = points[tree.query_ball_point(centre[:2], radius)]
        u, w = near[:, 0] - centre[0], near[:, 1] - centre[1]
        A = np.stack([np.ones_like(u), u, w, u * u, u * w, w * w], axis=1)
        q = np.linalg.lstsq(A, near[:, 2], rcond=None)[0]
        H = np.array([[2 * q[3], q[4]], [q[4], 2 * q[5]]])
        g = np.array([q[1], q[2]])
        # tangent vectors' plan parts suffice for a height field: II(a, b) ∝ a_xy·H·b_xy
        ax, bx = a[k, :2], b[k, :2]
        scale = np.sqrt(1 + g @ g)
        kmax = np.abs(np.linalg.eigvalsh(H)).max() / scale
        out[k] = abs(ax @ H @ bx) / scale / (np.linalg.norm(a[k]) * np.linalg.norm(b[k]) * max(kmax, 1e-300))
    return out


def plan_grid_twist(points: np.ndarray, mesh, radius: float) -> np.ndarray:
    """The same measure for the plan directions x and y at the same places (a net that ignores conjugacy)."""
    from ppfab.mesh import QuadMesh

    v = np.asarray(mesh.vertices).reshape(-1, 3)
    f = np.asarray(mesh.to_quadmesh().faces if hasattr(mesh, "to_quadmesh") else mesh.faces)
    centre = v[f].mean(axis=1)
    h = 100.0
    corners = centre[:, None, :] + np.array([[0, 0, 0], [h, 0, 0], [h, h, 0], [0, h, 0.0]])[None]
    fake = QuadMesh(corners.reshape(-1, 3), np.arange(4 * len(f)).reshape(-1, 4)[:, [0, 3, 2, 1]])
    return quad_twist(points, fake, radius)


def _rows_in_planes(net) -> float:
    v = np.asarray(net.mesh.vertices).reshape(-1, 3)
    pl = net.planes[net.row_of_vertex]
    return float(np.max(np.abs(np.einsum("ij,ij->i", v, pl[:, :3]) + pl[:, 3])))


@pytest.mark.parametrize("case", sorted(NURBS))
def test_nurbs_surface_becomes_a_sections_net(tmp_path, case):
    from fabrication.surfacefile import read_surface
    from ppfab.surface import SurfaceSpec, remesh

    heights, sx, sy, unit, brep, factor, spacing, largest = NURBS[case]
    path = tmp_path / f"{case}.3dm"
    write_nurbs(path, heights, sx, sy, unit, as_brep=brep)
    sf = read_surface(path)
    assert sf.kind == "nurbs" and sf.factor == factor
    ext = sf.samples.points.max(axis=0) - sf.samples.points.min(axis=0)
    assert ext[:2] == pytest.approx([sx * factor, sy * factor], rel=1e-9)        # the file's units → mm
    r = remesh(sf.samples, SurfaceSpec(path=str(path), spacing=spacing))
    net = r.net
    assert _rows_in_planes(net) <= 1e-9                                          # sections planar exactly
    v = np.asarray(net.mesh.vertices).reshape(-1, 3)
    assert sf.distance(v).max() < 0.5                                            # on the NURBS (mm)
    assert 0.75 <= r.panel_size_min and r.panel_size_max <= largest              # ±25 % of the spacing
    assert net.grid_faces.sum() >= 20
    twist = quad_twist(sf.samples.points, net.mesh, spacing)
    naive = plan_grid_twist(sf.samples.points, net.mesh, spacing)
    assert np.median(twist) < 0.03 and twist.max() < 0.1
    assert np.median(naive) > 5 * np.median(twist)                               # the test can tell
    _p_optimised_close(net, sf, 2.0)


def _p_optimised_close(net, sf, mm: float) -> None:
    """The net P-optimised with closeness to the surface as read: planar faces, planar rows, and every vertex
    within ``mm`` of the surface (measured by the reader's independent distance)."""
    from ppfab.metrics import quality
    from ppfab.optimize import optimize

    res = optimize(net.mesh, {"families": "rows", "target_delta_f": 1e-7, "target_delta_p": 1e-7,
                              "fairness": "relative", "weight_close": 1.0},
                   reference=(sf.samples.points, sf.samples.triangles))
    q = quality(res.mesh)
    assert res.targets_met and q.delta_f_max <= 1e-6 and q.delta_p_rows_max <= 1e-6
    assert sf.distance(np.asarray(res.mesh.vertices).reshape(-1, 3)).max() < mm


@pytest.fixture(scope="module")
def bubble_patch(tmp_path_factory):
    """A 10 m wide patch of the botanic-garden bubble (WWmore/DOS), resampled into a triangle mesh in m, with
    a hole of 1.5 m radius."""
    path = shared_file("DOS__botanic-garden-bubble-0.obj")
    mesh = resample_quad_mesh(path, 1500, 3, hole=(9.0, 11.5, 1.5), crop=(8.0, 11.0, 5.0))
    out = tmp_path_factory.mktemp("bubble") / "bubble_patch.ply"
    mesh.export(out)
    return out, path


def test_real_mesh_patch_becomes_a_sections_net(bubble_patch):
    from fabrication.surfacefile import read_surface
    from ppfab.io import read_mesh
    from ppfab.surface import SurfaceSpec, remesh

    out, original = bubble_patch
    sf = read_surface(out, units="m")
    orig = np.asarray(read_mesh(original).vertices) * 1000.0
    # no edge follows the original net: almost no vertex of the triangle mesh is one of the original's
    from scipy.spatial import cKDTree
    d, _ = cKDTree(orig).query(sf.samples.points)
    assert np.mean(d < 1.0) < 0.01
    r = remesh(sf.samples, SurfaceSpec(path=str(out), spacing=1500.0))
    net = r.net
    assert _rows_in_planes(net) <= 1e-9
    v = np.asarray(net.mesh.vertices).reshape(-1, 3)
    assert sf.distance(v).max() < 20.0                                           # mm, to the mesh as read
    twist = quad_twist(sf.samples.points, net.mesh, 1500.0)
    naive = plan_grid_twist(sf.samples.points, net.mesh, 1500.0)
    assert np.median(twist) < 0.1 and np.median(naive) > 2 * np.median(twist)
    assert net.grid_faces.sum() >= 15
    _p_optimised_close(net, sf, 30.0)


def test_trimmed_to_the_outline_and_its_hole(bubble_patch):
    import shapely

    from fabrication.surfacefile import read_surface
    from ppfab.surface import SurfaceSpec, remesh

    out, _ = bubble_patch
    sf = read_surface(out, units="m")
    loops = sorted(sf.samples.boundary, key=lambda lp: -shapely.Polygon(lp[:, :2]).area)
    assert len(loops) == 2                                                       # the outline and the hole
    region = shapely.Polygon(loops[0][:, :2], [loops[1][:, :2]])
    r = remesh(sf.samples, SurfaceSpec(path=str(out), spacing=1500.0))
    m = r.net.mesh
    v = np.asarray(m.vertices).reshape(-1, 3)
    faces = np.asarray(m.to_quadmesh().faces if hasattr(m, "to_quadmesh") else m.faces)
    quads = [shapely.Polygon(v[f, :2]) for f in faces]
    assert all(region.buffer(1e-6).contains(q) for q in quads)
    hole = shapely.Polygon(loops[1][:, :2])
    assert not any(q.intersection(hole).area > 1e-6 for q in quads)
    assert r.net.dropped_outside > 0


def test_parabolic_line_is_refused_with_its_place(tmp_path, capsys):
    """The inspired roof (compas_libigl) is synclastic on one side, anticlastic on the other: the conjugate
    direction of the sections degenerates; ppfab remesh says where, in one line, and writes nothing."""
    from fabrication.cli import main

    path = shared_file("compas_libigl__inspired_mesh_quads_Conjugate.off")
    src = tmp_path / "roof.ply"
    resample_quad_mesh(path, 2500, 5).export(src)
    out = tmp_path / "net.obj"
    code = main(["remesh", str(src), "-o", str(out), "--units", "m", "--spacing", "3000"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and not out.exists()
    assert len(err) == 1 and "degenerates at (x, y) = (" in err[0] and "mm" in err[0]
    assert "Traceback" not in err[0]


def test_remesh_command_writes_a_quad_obj_and_never_its_input(tmp_path, capsys):
    import json

    from fabrication.cli import main
    from ppfab.io import read_mesh

    src = tmp_path / "dome.3dm"
    write_nurbs(src, DOME, 12.0, 9.0, "Meters")
    before = src.read_bytes()
    out = tmp_path / "net.obj"
    assert main(["remesh", str(src), "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    m = read_mesh(out)
    assert len(m.faces) == summary["faces"] and summary["planarity_mm"] <= 1e-9
    assert summary["deviation_mm"] < 0.5 and summary["units"] == "m"
    assert main(["remesh", str(src), "-o", str(src)]) != 0                      # never its input
    assert src.read_bytes() == before
    assert main(["remesh", str(src), "-o", str(out)]) != 0                      # exists: needs --force
    assert main(["remesh", str(src), "-o", str(out), "--force"]) == 0


def test_units_of_a_mesh_are_declared_and_a_3dm_disagreeing_is_refused(tmp_path):
    import trimesh

    from fabrication.surfacefile import read_surface
    from ppfab.errors import DesignError

    tri = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0.2]], [[0, 1, 2]])
    p = tmp_path / "t.stl"
    tri.export(p)
    in_m, in_mm, guessed = read_surface(p, units="m"), read_surface(p, units="mm"), read_surface(p)
    assert np.allclose(in_m.samples.points, 1000.0 * in_mm.samples.points)
    assert not in_mm.note and not in_m.note
    # no units stated: a mesh 1 unit wide is no roof in mm, so it is read as metres and the note says so
    assert guessed.samples.units == "m" and np.allclose(guessed.samples.points, in_m.samples.points)
    assert "read as m " in guessed.note
    wide = tmp_path / "wide.stl"
    trimesh.Trimesh([[0, 0, 0], [12000, 0, 0], [0, 9000, 2000]], [[0, 1, 2]]).export(wide)
    w = read_surface(wide)
    assert w.samples.units == "mm" and "read as mm" in w.note and np.ptp(w.samples.points[:, 0]) == 12000
    src = tmp_path / "dome.3dm"
    write_nurbs(src, DOME, 12.0, 9.0, "Meters")
    with pytest.raises(DesignError, match="disagrees"):
        read_surface(src, units="ft")


@pytest.mark.parametrize("case", ["missing", "garbage_stl", "not_a_surface", "no_surface_in_3dm", "spacing",
                                  "vertical_normal", "not_obj", "too_coarse"])
def test_remesh_refuses_bad_input_in_one_line(tmp_path, capsys, case):
    import rhino3dm

    from fabrication.cli import main

    dome = tmp_path / "dome.3dm"
    write_nurbs(dome, DOME, 12.0, 9.0, "Meters")
    out = tmp_path / "net.obj"
    args = {"missing": [str(tmp_path / "nothere.3dm")],
            "garbage_stl": [str(tmp_path / "bad.stl")],
            "not_a_surface": [str(tmp_path / "design.toml")],
            "no_surface_in_3dm": [str(tmp_path / "point.3dm")],
            "spacing": [str(dome), "--spacing", "-5"],
            "vertical_normal": [str(dome), "--plane-normal", "0", "0", "1"],
            "not_obj": [str(dome)],
            "too_coarse": [str(dome), "--spacing", "50000"]}[case]
    (tmp_path / "bad.stl").write_text("garbage\n")
    (tmp_path / "design.toml").write_text("[design]\n")
    model = rhino3dm.File3dm()
    model.Objects.AddPoint(rhino3dm.Point3d(0, 0, 0))
    model.Write(str(tmp_path / "point.3dm"), 7)
    target = tmp_path / "net.txt" if case == "not_obj" else out
    code = main(["remesh", *args, "-o", str(target)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code in (1, 2) and len(err) == 1 and err[0].startswith("ppfab: error: ") and not target.exists()


def test_trimmed_brep_face_keeps_inside_its_trim_loop(tmp_path):
    """A flat roof disc: a plane Brep trimmed by a 5 m circle (rhino3dm). The trim loop is read from the Brep's
    edges; every kept vertex lies inside the circle, the corners of the square beyond it are dropped, and a
    flat surface (no curvature at all) gives the plan grid, without NaN."""
    import rhino3dm

    from fabrication.surfacefile import read_surface
    from ppfab.surface import SurfaceSpec, remesh

    circle = rhino3dm.Circle(rhino3dm.Point3d(0, 0, 3.0), 5.0).ToNurbsCurve()
    plane = rhino3dm.Plane(rhino3dm.Point3d(0, 0, 3.0), rhino3dm.Vector3d(0, 0, 1))
    model = rhino3dm.File3dm()
    model.Settings.ModelUnitSystem = rhino3dm.UnitSystem.Meters
    model.Objects.AddBrep(rhino3dm.Brep.CreateTrimmedPlane(plane, circle))
    path = tmp_path / "disc.3dm"
    model.Write(str(path), 7)
    sf = read_surface(path)
    assert len(sf.samples.boundary) == 1
    assert np.allclose(np.hypot(*sf.samples.boundary[0][:, :2].T), 5000.0, atol=1e-6)
    r = remesh(sf.samples, SurfaceSpec(path=str(path), spacing=1500.0))
    v = np.asarray(r.net.mesh.vertices).reshape(-1, 3)
    assert np.isfinite(v).all() and np.allclose(v[:, 2], 3000.0, atol=1e-6)
    assert np.hypot(v[:, 0], v[:, 1]).max() <= 5000.0 and r.net.dropped_outside > 0
    assert r.panel_size_min == pytest.approx(1.0, abs=1e-9) and r.panel_size_max == pytest.approx(1.0, abs=1e-9)
