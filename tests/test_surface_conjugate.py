"""The ``conjugate`` net: the conjugate net of a surface nearest two guide directions (ppfab.surface.conjugate).

Checked apart from the code under test: conjugacy with the Hessian of the analytic height field (paraboloids,
a cylinder, a hyperbolic paraboloid: known in closed form) or of a quadric fitted to the samples of a real
surface (``quad_twist`` of test_surface_sections, not the height-field spline); angles from the net's 3D edges;
distances to the surface by the reader's own closest point.  The real surface: patches of the botanic-garden
bubble of WWmore/DOS (``objs/obj_equilibrium/botanic-garden-bubble-0.obj`` @ f15cff51, the shared data),
resampled into triangle meshes whose edges do not follow the original net; the principal net is refused on
every one of them (umbilics of a funicular shell).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from conftest import shared_file
from surface_cases import resample_quad_mesh, write_nurbs
from test_surface_nets import _faces, _height_mesh
from test_surface_sections import DOME, SADDLE, plan_grid_twist, quad_twist


def _edges(mesh) -> tuple[np.ndarray, np.ndarray]:
    """Per face its mean row and mean column edge, world (F, 3) each."""
    v = np.asarray(mesh.vertices).reshape(-1, 3)
    c = v[_faces(mesh)]
    return 0.5 * ((c[:, 3] - c[:, 0]) + (c[:, 2] - c[:, 1])), 0.5 * ((c[:, 1] - c[:, 0]) + (c[:, 2] - c[:, 3]))


def _analytic_twist(mesh, hessian) -> np.ndarray:
    """``|a·H·b| / (|a||b| max|eig H|)`` per face with the closed-form Hessian ``hessian(x, y) -> (F, 2, 2)``
    of the height field at the face centres (plan parts of the edges: a height field's II is ∝ H)."""
    a, b = _edges(mesh)
    v = np.asarray(mesh.vertices).reshape(-1, 3)
    centre = v[_faces(mesh)].mean(axis=1)
    H = hessian(centre[:, 0], centre[:, 1])
    k = np.abs(np.linalg.eigvalsh(H)).max(axis=1)
    return np.abs(np.einsum("fi,fij,fj->f", a[:, :2], H, b[:, :2])) / (
        np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1) * k)


def _plan_angle(d: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Plan angle in degrees between the lines of ``d (F, 3)`` and the direction ``g (2,)``."""
    p = d[:, :2] / np.linalg.norm(d[:, :2], axis=1, keepdims=True)
    return np.degrees(np.arccos(np.clip(np.abs(p @ (g / np.linalg.norm(g))), 0.0, 1.0)))


def test_the_pair_is_conjugate_in_closed_form():
    """On random second forms (elliptic, hyperbolic, parabolic) and guides the pair satisfies d1ᵀ II d2 = 0, and
    no conjugate pair found by brute force over a fine grid of angles is nearer the guides."""
    from ppfab.surface.conjugate import OPEN, TIE, conjugate_pair

    rng = np.random.default_rng(4)
    k = 200
    A = rng.normal(size=(k, 2, 2))
    II = 0.5 * (A + np.swapaxes(A, 1, 2))
    II[:20, 1, 1] = II[:20, 0, 1] ** 2 / II[:20, 0, 0]                  # parabolic: det = 0
    for _ in range(3):
        g1 = rng.normal(size=2)
        g1 /= np.linalg.norm(g1)
        turn = np.radians(rng.uniform(40, 140))
        g2 = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]]) @ g1
        d1, d2, e = conjugate_pair(np.broadcast_to(np.eye(2), II.shape), II, g1, g2)
        scale = np.abs(np.linalg.eigvalsh(II)).max(axis=1)
        assert np.all(np.abs(np.einsum("ki,kij,kj->k", d1, II, d2)) <= 1e-9 * scale)
        assert np.allclose(np.linalg.norm(d1, axis=1), 1.0) and np.allclose(np.linalg.norm(d2, axis=1), 1.0)
        # brute force: every family-1 direction t, its conjugate by the null space of (II t)ᵀ, both orders
        t = np.linspace(0.0, np.pi, 3601)
        u = np.stack([np.cos(t), np.sin(t)], axis=1)
        best = np.full(k, np.inf)
        for i in range(k):
            iu = u @ II[i]
            ok = np.linalg.norm(iu, axis=1) > 0.05 * np.linalg.norm(II[i])
            w = np.stack([-iu[:, 1], iu[:, 0]], axis=1)[ok]
            w /= np.linalg.norm(w, axis=1, keepdims=True)
            for p, q in ((u[ok], w), (w, u[ok])):
                cost = 2.0 - (p @ g1) ** 2 - (q @ g2) ** 2 + OPEN * np.einsum("ij,ij->i", p, q) ** 2 \
                    + TIE * np.maximum(0.0, -(p @ g1) * (p @ g2))
                best[i] = min(best[i], float(cost.min()))
        assert np.all(e <= best + 1e-5)


def test_along_the_principal_axes_the_net_is_the_plan_grid(tmp_path):
    """An elliptic paraboloid with principal axes along x and y: with the plan axes as guides (the default) the
    net's edges run along x and y (the curvature lines); turned guides give a conjugate net that follows them."""
    from fabrication.surfacefile import read_surface
    from ppfab.surface import SurfaceSpec, remesh

    a, b = 1.0 / 40000.0, 1.0 / 60000.0

    def hess(x, y):
        return np.broadcast_to(np.array([[-2 * a, 0.0], [0.0, -2 * b]]), (len(x), 2, 2))

    sf = read_surface(_height_mesh(tmp_path, lambda x, y: 3000.0 - a * x * x - b * y * y, half=7000.0, n=57),
                      units="mm")
    r = remesh(sf.samples, SurfaceSpec(path="p.ply", spacing=1500.0, net="conjugate", plane_normal=[1, 0, 0]))
    rows, cols = _edges(r.net.mesh)
    assert r.net.grid_faces.sum() >= 30 and r.net.planar_family == "none"
    assert _plan_angle(rows, np.array([1.0, 0.0])).max() < 1.0 and _plan_angle(cols, np.array([0.0, 1.0])).max() < 1.0
    assert r.guide_deviation_deg is not None and r.guide_deviation_deg < 1.0
    assert _analytic_twist(r.net.mesh, hess).max() < 0.01
    # guides turned by 30°: still conjugate in closed form, and the rows follow their guide more closely than
    # the curvature lines do
    g1, g2 = [np.cos(np.radians(30)), np.sin(np.radians(30)), 0.0], [-np.sin(np.radians(30)), np.cos(np.radians(30)), 0.0]
    t = remesh(sf.samples, SurfaceSpec(path="p.ply", spacing=1500.0, net="conjugate", plane_normal=[1, 0, 0],
                                       guides=[g1, g2]))
    rows, cols = _edges(t.net.mesh)
    assert t.net.grid_faces.sum() >= 30
    assert np.median(_analytic_twist(t.net.mesh, hess)) < 0.02 and _analytic_twist(t.net.mesh, hess).max() < 0.06
    assert np.median(_plan_angle(rows, np.array(g1[:2]))) < 15.0
    v = np.asarray(t.net.mesh.vertices).reshape(-1, 3)
    assert np.abs(v[:, 2] - (3000.0 - a * v[:, 0] ** 2 - b * v[:, 1] ** 2)).max() < 1.0   # on the surface, mm


def test_a_cylinder_gets_its_rulings_as_one_family(tmp_path):
    """A parabolic surface (a cylinder along y): every direction is conjugate to the ruling y, so with guides at
    20° from the axes the net takes the rulings as one family (columns within 1° of y); the other is free, and
    lies at the angle θ that minimises ``sin²(θ − 20°) + OPEN · cos²∠(u, y) + TIE · max(0, −(u·g1)(u·g2))`` (found
    here by brute force)."""
    from fabrication.surfacefile import read_surface
    from ppfab.surface import SurfaceSpec, remesh

    R = 20000.0
    sf = read_surface(_height_mesh(tmp_path, lambda x, y: np.sqrt(R * R - x * x) - R + 3000.0, half=7000.0, n=57),
                      units="mm")
    c, s = np.cos(np.radians(20)), np.sin(np.radians(20))
    r = remesh(sf.samples, SurfaceSpec(path="c.ply", spacing=1500.0, net="conjugate", plane_normal=[1, 0, 0],
                                       guides=[[c, s, 0.0], [-s, c, 0.0]]))
    rows, cols = _edges(r.net.mesh)
    assert r.net.grid_faces.sum() >= 30
    assert _plan_angle(cols, np.array([0.0, 1.0])).max() < 1.0                 # the rulings
    from ppfab.surface.conjugate import OPEN, TIE

    t = np.radians(np.linspace(0.0, 90.0, 90001))
    cost = np.sin(t - np.radians(20)) ** 2 + OPEN * np.sin(t) ** 2 \
        + TIE * np.maximum(0.0, -np.cos(t - np.radians(20)) * np.cos(t - np.radians(110)))
    best = np.degrees(t[np.argmin(cost)])
    assert 5.0 < best < 20.0
    assert abs(np.median(_plan_angle(rows, np.array([1.0, 0.0]))) - best) < 0.5


def test_guides_along_the_asymptotic_directions_give_the_most_open_pair(tmp_path, capsys, monkeypatch):
    """z = x·y / R: the plan axes are its asymptotic directions (each conjugate to itself) and every conjugate
    pair is (θ, π − θ), all equally near x and y; the pair chosen is the most open one, the principal directions
    at 45° (closed form).  Without that preference (``OPEN = 0``) the pair closes up and the net is refused in
    one line with a place on the surface, and no file is written."""
    import ppfab.surface.conjugate as conjugate
    from fabrication.cli import main
    from ppfab.io import read_mesh

    R = 30000.0
    src = _height_mesh(tmp_path, lambda x, y: 2000.0 + x * y / R)
    out = tmp_path / "net.obj"
    args = ["remesh", str(src), "-o", str(out), "--net", "conjugate", "--units", "mm", "--plane-normal", "1", "0", "0"]
    assert main(args) == 0
    mesh = read_mesh(out)
    rows, cols = _edges(mesh)
    twist = _analytic_twist(mesh, lambda x, y: np.broadcast_to(np.array([[0.0, 1 / R], [1 / R, 0.0]]),
                                                               (len(x), 2, 2)))
    assert len(mesh.faces) >= 30 and twist.max() < 0.02
    assert np.abs(_plan_angle(rows, np.array([1.0, 0.0])) - 45.0).max() < 1.0
    assert np.abs(_plan_angle(cols, np.array([1.0, 0.0])) - 45.0).max() < 1.0
    out.unlink()
    capsys.readouterr()
    monkeypatch.setattr(conjugate, "OPEN", 0.0)
    code = main(args)
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and not out.exists() and len(err) == 1 and "Traceback" not in err[0]
    m = re.search(r"closes to ([\d.]+)° at \(x, y\) = \((-?\d+), (-?\d+)\) mm", err[0])
    assert m is not None and float(m.group(1)) < 15.0 and max(abs(float(m.group(2))), abs(float(m.group(3)))) <= 6000
    assert "[surface] guides" in err[0]


@pytest.mark.parametrize("guides, what", [([[1, 0, 0], [1, 0.1, 0]], "apart in plan"),
                                          ([[0, 0, 1], [0, 1, 0]], "vertical"),
                                          ([[1, 0, 0], [np.nan, 1, 0]], "finite")])
def test_bad_guides_are_refused(guides, what):
    from ppfab.errors import DesignError
    from ppfab.surface import SurfaceSpec, remesh
    from ppfab.surface.samples import SurfaceSamples

    x, y = np.meshgrid(np.linspace(-6000, 6000, 21), np.linspace(-6000, 6000, 21), indexing="ij")
    ids = np.arange(441).reshape(21, 21)
    tri = np.concatenate([np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:]], -1).reshape(-1, 3),
                          np.stack([ids[:-1, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 3)])
    pts = np.stack([x.ravel(), y.ravel(), (3000 - (x * x + 2 * y * y) / 50000).ravel()], axis=1)
    with pytest.raises(DesignError, match=what):
        remesh(SurfaceSamples(pts, tri), SurfaceSpec(path="s.obj", spacing=1500.0, net="conjugate", guides=guides))


def test_nurbs_surfaces_become_conjugate_nets(tmp_path):
    """The NURBS dome (12 × 9 m) and saddle (40 × 28 ft Brep) of the other surface tests, written with rhino3dm:
    conjugate by quadric fits to the NURBS samples, on the NURBS (rhino3dm's closest point), edges near the
    spacing."""
    from fabrication.surfacefile import read_surface
    from ppfab.surface import SurfaceSpec, remesh

    write_nurbs(tmp_path / "dome.3dm", DOME, 12.0, 9.0, "Meters")
    write_nurbs(tmp_path / "saddle.3dm", SADDLE, 40.0, 28.0, "Feet", as_brep=True)
    for name in ("dome", "saddle"):
        sf = read_surface(tmp_path / f"{name}.3dm")
        r = remesh(sf.samples, SurfaceSpec(path=f"{name}.3dm", spacing=1500.0, net="conjugate"))
        mesh = r.net.mesh
        twist = quad_twist(sf.samples.points, mesh, 1500.0)
        assert r.net.grid_faces.sum() >= 15 and np.median(twist) < 0.01 and twist.max() < 0.02
        assert sf.distance(np.asarray(mesh.vertices).reshape(-1, 3)).max() < 0.5
        assert 0.85 <= r.panel_size_min and r.panel_size_max <= 1.3


@pytest.fixture(scope="module")
def bubble(tmp_path_factory):
    """Three 10 m patches of the botanic-garden bubble, resampled (m): one with a 1.5 m hole."""
    from fabrication.surfacefile import read_surface

    path = shared_file("DOS__botanic-garden-bubble-0.obj")
    folder = tmp_path_factory.mktemp("bubble_conjugate")
    out = {}
    for name, kw in (("hole", {"hole": (9.0, 11.5, 1.5), "crop": (8.0, 11.0, 5.0)}),
                     ("west", {"crop": (0.0, -3.0, 5.0)}), ("east", {"crop": (8.0, 4.0, 5.0)})):
        resample_quad_mesh(path, 1500, 3, **kw).export(folder / f"{name}.ply")
        out[name] = read_surface(folder / f"{name}.ply", units="m")
    return out


@pytest.mark.parametrize("name", ["hole", "west", "east"])
def test_a_real_shell_where_the_principal_net_is_refused_gets_a_conjugate_net(bubble, name):
    """Each patch has umbilics inside (the principal net is refused); the conjugate net nearest the plan axes is
    built, conjugate by quadric fits to the resampled mesh (several times less twisted than the plan grid at the
    same places), and on the surface."""
    from ppfab.errors import GeometryError
    from ppfab.surface import SurfaceSpec, remesh

    sf = bubble[name]
    with pytest.raises(GeometryError, match="umbilic"):
        remesh(sf.samples, SurfaceSpec(path="b.ply", spacing=1500.0, net="principal"))
    r = remesh(sf.samples, SurfaceSpec(path="b.ply", spacing=1500.0, net="conjugate"))
    mesh = r.net.mesh
    twist = quad_twist(sf.samples.points, mesh, 1500.0)
    naive = plan_grid_twist(sf.samples.points, mesh, 1500.0)
    assert r.net.grid_faces.sum() >= 8
    assert np.median(twist) < 0.05 and np.median(naive) > 2 * np.median(twist)
    assert sf.distance(np.asarray(mesh.vertices).reshape(-1, 3)).max() < 25.0          # mm


@pytest.mark.parametrize("name, families, mm", [("hole", "rows", 25.0), ("hole", "both", 25.0),
                                                ("west", "rows", 80.0)])
def test_conjugate_nets_of_a_real_shell_become_p_and_pp(bubble, name, families, mm):
    """P (and PP) optimisation of the conjugate net with closeness to the surface as read: faces and the planar
    families to 1e-6 (measured by SVD here), within ``mm`` of the resampled mesh."""
    from ppfab.optimize import optimize
    from ppfab.surface import SurfaceSpec, remesh

    sf = bubble[name]
    r = remesh(sf.samples, SurfaceSpec(path="b.ply", spacing=1500.0, net="conjugate"))
    res = optimize(r.net.mesh, {"families": families, "target_delta_f": 1e-7, "target_delta_p": 1e-7,
                                "fairness": "relative", "weight_close": 1.0},
                   reference=(sf.samples.points, sf.samples.triangles))
    assert res.targets_met
    mesh = res.mesh
    v = np.asarray(mesh.vertices).reshape(-1, 3)
    c = v[_faces(mesh)]
    diag = np.linalg.norm(c[:, 2] - c[:, 0], axis=1) + np.linalg.norm(c[:, 3] - c[:, 1], axis=1)
    flat = np.array([np.linalg.svd(q - q.mean(axis=0))[1][2] for q in c]) / (0.5 * diag)
    assert flat.max() <= 1e-6
    from ppfab.mesh import as_quadmesh

    qm = as_quadmesh(mesh)
    verts = np.asarray(qm.vertices)
    extent = float(np.linalg.norm(verts.max(axis=0) - verts.min(axis=0)))
    planar = {"rows": (0,), "both": (0, 1)}[families]
    checked = 0
    for pl in qm.polylines:
        p = verts[np.asarray(pl.vertices)]
        if pl.family in planar and len(p) >= 3:
            q = p - p.mean(axis=0)
            assert float(np.abs(q @ np.linalg.svd(q)[2][-1]).max()) <= 1e-6 * extent
            checked += 1
    assert checked >= 2
    assert sf.distance(v).max() < mm


def _worst_edge(mesh, spacing: float) -> float:
    """``max |log(edge / spacing)|`` over the mesh's edges, from its vertices."""
    from ppfab.mesh import as_quadmesh

    return float(np.abs(np.log(np.asarray(as_quadmesh(mesh).edge_lengths()) / spacing)).max())


def _tilt_deg(sf, mesh, normal: np.ndarray) -> float:
    """The largest angle between the vertical plane with unit ``normal`` and the surface's normal at the mesh's
    vertices, the normal of the triangle nearest each vertex (trimesh, on the mesh as read)."""
    import trimesh

    v = np.asarray(mesh.vertices).reshape(-1, 3)                          # the mesh as read is in mm
    _, _, tri = trimesh.proximity.closest_point_naive(sf.native, v)
    n = sf.native.face_normals[tri]
    return float(np.degrees(np.arcsin(np.clip(np.abs(n @ normal), 0.0, 1.0))).max())


@pytest.mark.parametrize("name", ["hole", "west", "east"])
def test_searched_section_planes_keep_the_rows_beams_and_the_edges_near_the_spacing(bubble, name):
    """``search_planes`` on the real shell patches: the sections net over turned vertical planes keeps its
    section planes within 30° of the surface normals where the default's are not (rows the P support keeps as
    planar beams; measured here against the normals of the triangles nearest the vertices) and narrows the
    edges' range (default 0.53–1.48, 0.15–1.61, 0.26–2.29 × the spacing), and P optimisation then meets its
    targets within 35 mm of the surface."""
    from ppfab.optimize import optimize
    from ppfab.surface import SurfaceSpec, remesh

    sf, spacing = bubble[name], 1500.0
    plain = remesh(sf.samples, SurfaceSpec(path="b.ply", spacing=spacing))
    r = remesh(sf.samples, SurfaceSpec(path="b.ply", spacing=spacing, search_planes=True))
    assert r.planes_tried >= 20 and abs(r.frame.axes[0, 2]) < 1e-12                       # vertical planes
    assert _worst_edge(r.net.mesh, spacing) < _worst_edge(plain.net.mesh, spacing)
    assert 0.55 < r.panel_size_min and r.panel_size_max < 1.8
    before, after = _tilt_deg(sf, plain.net.mesh, plain.frame.axes[0]), _tilt_deg(sf, r.net.mesh, r.frame.axes[0])
    # the triangles' normals scatter by a few degrees about the fitted surface's (a faceted resampled mesh)
    assert after <= max(30.0, before) + 6.0 and (before <= 30.0 or after < before)
    assert abs(after - r.tilt_max_deg) < 10.0                    # the fit's normals against the triangles'
    res = optimize(r.net.mesh, {"families": "rows", "target_delta_f": 1e-7, "target_delta_p": 1e-7,
                                "fairness": "relative", "weight_close": 1.0},
                   reference=(sf.samples.points, sf.samples.triangles))
    assert res.targets_met and sf.distance(np.asarray(res.mesh.vertices).reshape(-1, 3)).max() < 35.0


def test_remesh_command_searches_the_planes(tmp_path, capsys):
    import json

    from fabrication.cli import main

    src = tmp_path / "saddle.3dm"
    write_nurbs(src, SADDLE, 40.0, 28.0, "Feet", as_brep=True)
    out = tmp_path / "net.obj"
    assert main(["remesh", str(src), "-o", str(out), "--net", "conjugate", "--search-planes", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["planes_tried"] >= 20 and summary["guide_deviation_deg"] is not None
    assert 0.75 <= summary["panel_size_min"] and summary["panel_size_max"] <= 1.25


@pytest.mark.parametrize("name, units", [("DOS__pillow_1.obj", "m"), ("DOS__conical1.obj", "m")])
def test_a_surface_that_is_no_height_field_is_refused_with_the_place(tmp_path, capsys, name, units):
    """A closed pillow and an overhanging cone (WWmore/DOS, shared data) are no roofs over their plan: every net
    is refused in one line naming a point of the surface (checked to be one of its samples' places), no file
    written — the conjugate net built one 31 m off the surface before."""
    from fabrication.cli import main
    from fabrication.surfacefile import read_surface

    src = shared_file(name)
    pts = read_surface(src, units=units).samples.points
    for net in ("sections", "conjugate", "principal"):
        out = tmp_path / f"{net}.obj"
        code = main(["remesh", str(src), "-o", str(out), "--units", units, "--net", net])
        err = capsys.readouterr().err.strip().splitlines()
        assert code != 0 and not out.exists() and len(err) == 1 and "Traceback" not in err[0]
        m = re.search(r"not a height field .* up to (\d+) mm \(at \((-?\d+), (-?\d+), (-?\d+)\) mm", err[0])
        assert m is not None, err[0]
        where = np.array([float(m.group(k)) for k in (2, 3, 4)])
        assert np.linalg.norm(pts - where, axis=1).min() < 1.0 and float(m.group(1)) > 225.0
