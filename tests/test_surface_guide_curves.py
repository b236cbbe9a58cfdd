"""Guide curves for the ``conjugate`` net (``[surface] row_guides`` / ``column_guides``): the rows follow curves
the designer draws, the columns stay conjugate to them.

The surface is a paraboloid of revolution, whose second form in plan coordinates is a multiple of the identity:
there a pair of directions is conjugate exactly when it is orthogonal in plan, so a conjugate net can follow any
guide curves and its columns are their orthogonal trajectories.  Checked apart from the code: the rows' edges
against the tangent of the circle through each face centre (the guides are arcs of circles about one centre),
conjugacy with the closed-form Hessian, heights on the closed-form surface."""

from __future__ import annotations

import numpy as np
import pytest

from ppfab.errors import DesignError
from test_surface_conjugate import _analytic_twist, _edges
from test_surface_nets import enneper  # noqa: F401 (a fixture)
from test_surface_nets import _height_mesh

R = 30000.0                                   # mm, the paraboloid's radius of curvature at its axis
CENTRE = np.array([0.0, -25000.0])            # the guide arcs' centre in plan, off the surface's axis


def _z(x, y):
    return 3000.0 - (x * x + y * y) / (2.0 * R)


def _hess(x, y):
    return np.broadcast_to(-np.eye(2) / R, (len(x), 2, 2))


def _arc(radius: float, n: int = 25) -> list[list[float]]:
    """An arc of the circle about ``CENTRE`` across the patch, as guide-curve points [x, y, z] (mm)."""
    t = np.linspace(-0.45, 0.45, n)
    x, y = CENTRE[0] + radius * np.sin(t), CENTRE[1] + radius * np.cos(t)
    return np.stack([x, y, _z(x, y)], axis=1).tolist()


def _off_circle_deg(mesh) -> np.ndarray:
    """Per face, the plan angle (degrees) between its mean row edge and the tangent of the circle about ``CENTRE``
    through the face's centre."""
    rows, _ = _edges(mesh)
    v = np.asarray(mesh.vertices).reshape(-1, 3)
    from test_surface_nets import _faces

    c = v[_faces(mesh)].mean(axis=1)[:, :2] - CENTRE
    tangent = np.stack([-c[:, 1], c[:, 0]], axis=1) / np.linalg.norm(c, axis=1, keepdims=True)
    r = rows[:, :2] / np.linalg.norm(rows[:, :2], axis=1, keepdims=True)
    return np.degrees(np.arccos(np.clip(np.abs(np.einsum("fi,fi->f", r, tangent)), 0.0, 1.0)))


@pytest.fixture(scope="module")
def dome(tmp_path_factory):
    from fabrication.surfacefile import read_surface

    return read_surface(_height_mesh(tmp_path_factory.mktemp("dome"), _z, half=7000.0, n=57), units="mm")


def test_rows_follow_guide_curves_and_stay_conjugate(dome):
    from ppfab.surface import SurfaceSpec, remesh

    spec = SurfaceSpec(path="d.ply", spacing=1500.0, net="conjugate", plane_normal=[1, 0, 0],
                       row_guides=[_arc(20000.0), _arc(32000.0)])
    r = remesh(dome.samples, spec)
    mesh = r.net.mesh
    assert r.net.grid_faces.sum() >= 30
    off = _off_circle_deg(mesh)
    assert np.median(off) < 2.0 and off.max() < 6.0, (np.median(off), off.max())
    twist = _analytic_twist(mesh, _hess)
    assert np.median(twist) < 0.02 and twist.max() < 0.06
    v = np.asarray(mesh.vertices).reshape(-1, 3)
    assert np.abs(v[:, 2] - _z(v[:, 0], v[:, 1])).max() < 1.0                  # on the surface, mm
    # the same surface with the guide directions alone (the plan axes): the rows run straight, up to the arcs'
    # turning off the circles
    straight = remesh(dome.samples, SurfaceSpec(path="d.ply", spacing=1500.0, net="conjugate", plane_normal=[1, 0, 0]))
    assert _off_circle_deg(straight.net.mesh).max() > 12.0


def test_column_guide_curves_turn_the_columns(dome):
    """Columns guided by the radii from the arcs' centre (straight lines through it) and the rows left free: the
    rows come out as the circles (their orthogonal trajectories on this surface)."""
    from ppfab.surface import SurfaceSpec, remesh

    radii = []
    for a in (-0.3, 0.0, 0.3):
        t = np.linspace(15000.0, 36000.0, 8)
        x, y = CENTRE[0] + t * np.sin(a), CENTRE[1] + t * np.cos(a)
        radii.append(np.stack([x, y, _z(x, y)], axis=1).tolist())
    r = remesh(dome.samples, SurfaceSpec(path="d.ply", spacing=1500.0, net="conjugate", plane_normal=[1, 0, 0],
                                         column_guides=radii))
    off = _off_circle_deg(r.net.mesh)
    assert r.net.grid_faces.sum() >= 30 and np.median(off) < 2.0 and off.max() < 6.0


@pytest.mark.parametrize("kwargs, words", [
    ({"net": "sections", "row_guides": [[[0, 0, 0], [1000, 0, 0]]]}, "only the conjugate net follows guide curves"),
    ({"net": "conjugate", "search_planes": True, "row_guides": [[[0, 0, 0], [1000, 0, 0]]]},
     "search_planes: turns the guide directions"),
])
def test_guide_curves_where_they_cannot_be_followed_are_refused(kwargs, words):
    from ppfab.schema import parse_params
    from ppfab.surface import SurfaceSpec

    with pytest.raises(DesignError, match=words) as err:
        parse_params(SurfaceSpec, {"path": "d.ply", **kwargs}, "surface")
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("curves, words", [
    ([[[0, 0, 0]]], "row_guides[0]: a guide curve is a list of at least two points"),
    ([[[0, 0, 0], [0, 0, 5000]]], "row_guides[0]: its points coincide in plan"),
    ([[[0, 0, 0], [np.nan, 0, 0]]], "a guide curve is a list of at least two points"),
])
def test_bad_guide_curves_are_named(dome, curves, words):
    from ppfab.surface import SurfaceSpec, remesh

    with pytest.raises(DesignError) as err:
        remesh(dome.samples, SurfaceSpec(path="d.ply", spacing=1500.0, net="conjugate", row_guides=curves))
    assert words in str(err.value) and "\n" not in str(err.value)


def test_row_and_column_curves_that_run_together_are_refused_with_the_place(dome):
    from ppfab.surface import SurfaceSpec, remesh

    rows = [[[-8000, 0, 0], [8000, 0, 0]]]
    cols = [[[-8000, -500, 0], [8000, 500, 0]]]                 # 3.6° from the rows
    with pytest.raises(DesignError, match=r"row and column guides are 3\.6° apart in plan at \(x, y\) = \(") as err:
        remesh(dome.samples, SurfaceSpec(path="d.ply", spacing=1500.0, net="conjugate", row_guides=rows,
                                         column_guides=cols))
    assert "\n" not in str(err.value)


def test_guide_curves_drawn_along_a_real_net_are_followed(enneper):
    """The Enneper patch of WWmore/DOS (resampled: see test_surface_nets), turned by 35° about the vertical so that
    its curvature lines no longer run along the plan axes.  Three of its original rows — curvature lines — given as
    row guides: the conjugate net's rows run along the original rows (each quad against the original directions
    nearest it), as conjugate as the original net by quadric fits to the resampled mesh; three of its original
    columns given as row guides instead: the rows run along the original columns."""
    from dataclasses import replace

    from scipy.spatial import cKDTree
    from test_surface_nets import _faces
    from test_surface_sections import quad_twist

    from ppfab.surface import SurfaceSpec, remesh

    original, sf = enneper
    t = np.radians(35.0)
    turn = np.array([[np.cos(t), -np.sin(t), 0.0], [np.sin(t), np.cos(t), 0.0], [0.0, 0.0, 1.0]])
    original = original @ turn.T
    samples = replace(sf.samples, points=sf.samples.points @ turn.T,
                      boundary=tuple(b @ turn.T for b in sf.samples.boundary))
    du = (original[2:, 1:-1] - original[:-2, 1:-1]).reshape(-1, 3)     # along the original columns
    dv = (original[1:-1, 2:] - original[1:-1, :-2]).reshape(-1, 3)     # along the original rows
    tree = cKDTree(original[1:-1, 1:-1].reshape(-1, 3))

    def off(mesh, along_rows: np.ndarray, along_cols: np.ndarray) -> np.ndarray:
        rows, cols = _edges(mesh)
        _, k = tree.query(np.asarray(mesh.vertices).reshape(-1, 3)[_faces(mesh)].mean(axis=1))

        def angle(p, q):
            cos = np.abs(np.einsum("ij,ij->i", p, q)) / (np.linalg.norm(p, axis=1) * np.linalg.norm(q, axis=1))
            return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))
        return np.maximum(angle(rows, along_rows[k]), angle(cols, along_cols[k]))

    spec = dict(path="patch.ply", spacing=1000.0, net="conjugate")
    r = remesh(samples, SurfaceSpec(**spec, row_guides=[original[i].tolist() for i in (0, 5, 10)]))
    a = off(r.net.mesh, dv, du)
    assert r.net.grid_faces.sum() >= 8
    # 15.9° measured at the four corner quads, where the surface is steepest and the plan-based preference for
    # open pairs pulls the pair off the curvature lines; 3–9° elsewhere
    assert np.median(a) < 8.0 and a.max() < 17.0, a
    assert np.median(quad_twist(samples.points, r.net.mesh, 1000.0)) < 0.05
    c = remesh(samples, SurfaceSpec(**spec, row_guides=[original[:, j].tolist() for j in (0, 5, 10)]))
    b = off(c.net.mesh, du, dv)
    assert c.net.grid_faces.sum() >= 8 and np.median(b) < 10.0 and b.max() < 17.0, b       # 8.4° / 15.9° measured
    assert np.median(off(c.net.mesh, dv, du)) > 60.0                   # the families have traded places


def _paraboloid_3dm(path, rows_layer: str = "Rows", polyline: bool = False) -> None:
    """A .3dm in mm: the paraboloid of revolution ``_z`` over 14 × 14 m centred at the origin as an exact bicubic
    Bézier surface (a quadratic's cubic Bernstein coefficients), and on layer ``rows_layer`` two arcs about
    ``CENTRE`` (NURBS curves from rhino3dm's arcs, or one of them as a polyline)."""
    import rhino3dm

    half = 7000.0
    ns = rhino3dm.NurbsSurface.Create(3, False, 4, 4, 4, 4)
    x = np.linspace(-half, half, 4)                    # control abscissae (linear precision)
    # Bernstein coefficients of x² on [−h, h] at cubic degree: x(t)² with x = −h + 2ht → [h², −h²/3, −h²/3, h²]
    sq = np.array([half ** 2, -half ** 2 / 3.0, -half ** 2 / 3.0, half ** 2])
    for i in range(4):
        for j in range(4):
            ns.Points[i, j] = rhino3dm.Point4d(x[i], x[j], 3000.0 - (sq[i] + sq[j]) / (2.0 * R), 1.0)
    for k, t in enumerate([0, 0, 0, 1, 1, 1]):
        ns.KnotsU[k] = t
        ns.KnotsV[k] = t
    model = rhino3dm.File3dm()
    model.Settings.ModelUnitSystem = rhino3dm.UnitSystem.Millimeters
    model.Objects.AddSurface(ns)
    layer = rhino3dm.Layer()
    layer.Name = rows_layer
    att = rhino3dm.ObjectAttributes()
    att.LayerIndex = model.Layers.Add(layer)
    for k, radius in enumerate((20000.0, 32000.0)):
        pts = _arc(radius, 25)
        if polyline and k == 1:
            model.Objects.AddPolyline([rhino3dm.Point3d(*p) for p in pts], att)
        else:
            arc = rhino3dm.Arc(rhino3dm.Point3d(*pts[0]), rhino3dm.Point3d(*pts[12]), rhino3dm.Point3d(*pts[-1]))
            model.Objects.AddCurve(arc.ToNurbsCurve(), att)
    model.Write(str(path), 7)


@pytest.mark.parametrize("polyline", [False, True])
def test_guide_curves_from_a_rhino_layer(tmp_path, capsys, polyline):
    """A designer draws the guide curves in Rhino on a layer: `ppfab remesh --guide-layers Rows` (and
    ``[surface] guide_layers``) reads them from the .3dm (arcs as NURBS curves, a polyline by its points) and the
    rows of the written net follow them; the NURBS is the paraboloid exactly (checked: heights on the closed
    form)."""
    from fabrication.cli import main
    from ppfab.io import read_mesh

    surface = tmp_path / "roof.3dm"
    _paraboloid_3dm(surface, polyline=polyline)
    out = tmp_path / "net.obj"
    assert main(["remesh", str(surface), "-o", str(out), "--net", "conjugate", "--guide-layers", "Rows"]) == 0
    mesh = read_mesh(out)
    v = np.asarray(mesh.vertices)
    assert np.abs(v[:, 2] - _z(v[:, 0], v[:, 1])).max() < 1.0
    off = _off_circle_deg(mesh)
    assert len(mesh.faces) >= 30 and np.median(off) < 2.0 and off.max() < 6.0, (np.median(off), off.max())


def test_guide_layers_that_do_not_exist_or_hold_no_curve_are_named(tmp_path, capsys):
    from fabrication.cli import main

    surface = tmp_path / "roof.3dm"
    _paraboloid_3dm(surface, rows_layer="Guides")
    for layers, words in ((["Rows"], "roof.3dm has no layer 'Rows' (its layers: 'Guides')"),
                          (["Guides", "Default"], "has no layer 'Default'")):
        out = tmp_path / "net.obj"
        assert main(["remesh", str(surface), "-o", str(out), "--net", "conjugate", "--guide-layers", *layers]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and words in err[0] and not out.exists()
    mesh_file = tmp_path / "roof.ply"
    _height_mesh(tmp_path, _z, half=7000.0, n=21).rename(mesh_file)
    assert main(["remesh", str(mesh_file), "-o", str(tmp_path / "n.obj"), "--net", "conjugate",
                 "--guide-layers", "Rows"]) == 2
    assert "only a Rhino file has layers" in capsys.readouterr().err
