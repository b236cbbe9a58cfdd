"""PP design methods: Cauchy data (Fig. 7), bisector/radical planes (§3.1.3), profile curves (§3.2.1),
translational surfaces, and the bundled examples (plane splines: test_plane_splines.py)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from ppfab import planes as pl
from ppfab.constructions import build_construction
from ppfab.constructions.bisector import bisector_mesh
from ppfab.constructions.cauchy import cauchy_pp_mesh
from ppfab.constructions.profile_curves import profile_surface
from ppfab.constructions.translational import translational_mesh
from ppfab.errors import DesignError, GeometryError
from ppfab.faceimage import pp_from_face_image
from ppfab.metrics import face_planarity, plane_residual, polyline_planarity, quality

from conftest import REPO, smooth_face_image

TOL = 1e-9
EXAMPLES = sorted((REPO / "examples").glob("pp_*.toml"))


def assert_pp(grid, tol=TOL):
    """Planar faces (δ_f), planar rows and columns (δ_P), polylines in the grid's support planes."""
    assert face_planarity(grid.face_corners).max() <= tol
    if grid.shape[1] >= 3:
        assert polyline_planarity(grid.rows()).max() <= tol
    if grid.shape[0] >= 3:
        assert polyline_planarity(grid.cols()).max() <= tol
    if grid.support_u is not None:
        assert plane_residual(grid.rows(), grid.support_u).max() <= tol
    if grid.support_w is not None:
        assert plane_residual(grid.cols(), grid.support_w).max() <= tol
    q = quality(grid)
    assert q.flipped_edges == 0 and q.nonconvex_faces == 0


# -- Cauchy data ---------------------------------------------------------------------------------

def central_dome_data(m=8, n=6, z0=40.0):
    """Support planes through the lines {x = 0, z = z0} and {y = 0, z = z0} (all node axes meet at
    (0, 0, z0)) and two arched initial polylines on the node axes."""
    xi, yj = np.linspace(-15, 15, m + 1), np.linspace(-10, 10, n + 1)
    U = np.array([[z0, 0, x, -z0 * x] for x in xi])
    W = np.array([[0, z0, y, -z0 * y] for y in yj])

    def on_axis(x, y, z):
        s = (z0 - z) / z0
        return [s * x, s * y, z]

    col = np.array([on_axis(x, yj[0], 3 + 4 * (1 - (x / 15) ** 2)) for x in xi])
    row = np.array([on_axis(xi[0], y, 3 + 3 * (1 - (y / 10) ** 2)) for y in yj])
    return U, W, col, row


def test_cauchy_central_dome_is_pp_with_axes_through_the_centre():
    U, W, col, row = central_dome_data()
    grid = cauchy_pp_mesh(U, W, col, row)
    assert grid.shape == (9, 7)
    assert_pp(grid)
    # every node axis passes through (0, 0, 40)
    c = np.array([0.0, 0.0, 40.0])
    r = grid.vertices - c
    assert np.abs(np.cross(r, grid.axes)).max() <= 1e-9 * np.abs(r).max()
    # the initial polylines are kept
    assert np.abs(grid.vertices[:, 0] - col).max() < 1e-9 and np.abs(grid.vertices[0] - row).max() < 1e-9


def test_cauchy_recovers_a_known_pp_mesh_from_its_boundary():
    """Oracle: the support planes and first row/column of a face-image PP mesh determine it (Fig. 7)."""
    g, h = smooth_face_image(7, 6, seed=1)
    ref = pp_from_face_image(g, h)
    v = ref.vertices
    grid = cauchy_pp_mesh(ref.support_u, ref.support_w, v[:, 0], v[0, :])
    assert np.abs(grid.vertices - v).max() <= 1e-8 * np.ptp(v)
    assert_pp(grid)


def test_cauchy_breakdown_names_vertex_and_angle():
    # U_1 (z = 0) and W_1 (y = 1) meet in a line along x; the plane through v00, v10, v01 contains
    # the x direction, so the line U_1 ∩ W_1 never meets it.
    U = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    W = np.array([[0, 1.0, 0, 0], [0, 1.0, 0, -1.0]])
    col = np.array([[0.0, 0, 0], [2.0, 0, 0]])
    row = np.array([[0.0, 0, 0], [0.0, 1, 1]])
    with pytest.raises(GeometryError, match=r"vertex \(1, 1\).*at 0°") as exc:
        cauchy_pp_mesh(U, W, col, row)
    assert exc.value.element == "vertex (1, 1)" and exc.value.value == pytest.approx(0.0, abs=1e-9)
    # v00 lifted: the plane turns by about 0.5°, still below the 1° threshold; the angle is reported
    col[0] = row[0] = [0.0, 0.0, 0.025]
    with pytest.raises(GeometryError, match=r"vertex \(1, 1\).*at 0\.51\d°") as exc:
        cauchy_pp_mesh(U, W, col, row)
    assert exc.value.value == pytest.approx(0.513, abs=0.005)
    assert cauchy_pp_mesh(U, W, col, row, min_angle_deg=0.25).shape == (2, 2)


def test_cauchy_rejects_nearly_parallel_support_planes_and_off_axis_points():
    U, W, col, row = central_dome_data(4, 3)
    W2 = W.copy()
    W2[2] = U[3] + [0, 1e-4, 0, 0]
    with pytest.raises(GeometryError, match=r"U_3 and W_2 are nearly parallel"):
        cauchy_pp_mesh(U, W2, col, row)
    col2 = col.copy()
    col2[2] += [0.5, 0, 0]
    with pytest.raises(GeometryError, match=r"v_2,0.*away from its node axis"):
        cauchy_pp_mesh(U, W, col2, row)


def test_cauchy_design_file_errors_name_the_key():
    U, W, col, row = central_dome_data(4, 3)
    params = dict(support_u=U.tolist(), support_w=W.tolist(), boundary_u=col.tolist(), boundary_w=row.tolist())
    grid = build_construction("cauchy", params)
    assert_pp(grid)
    bad = dict(params, boundary_u=[list(p) for p in col])
    bad["boundary_u"][3] = (col[3] + [0.0, 2.0, 0.0]).tolist()
    with pytest.raises(DesignError, match=r"geometry\.params\.boundary_u\[3\]: vertex is 1\.9.* away"):
        build_construction("cauchy", bad)
    bad = dict(params, support_w=[list(p) for p in W])
    bad["support_w"][1] = [0.0, 0.0, 0.0, 1.0]
    with pytest.raises(DesignError, match=r"support_w\[1\]: plane has a zero normal"):
        build_construction("cauchy", bad)
    with pytest.raises(DesignError, match=r"boundary_w: needs one vertex per plane"):
        build_construction("cauchy", dict(params, boundary_w=row[:-1].tolist()))


# -- bisector / radical planes ------------------------------------------------------------------

def hypar_points(a=3.0):
    g = np.array([[s, 0.0, a] for s in np.linspace(-4, 4, 10)])
    h = np.array([[0.0, t, -a] for t in np.linspace(-3, 3, 8)])
    return g, h


def curved_points():
    s = np.linspace(-1, 1, 9)
    t = np.linspace(-1, 1, 7)
    g = np.stack([4 * s, 0.4 * s ** 2, 3 + 0.3 * s ** 2 + 0.1 * s ** 3], axis=1)
    h = np.stack([0.5 * t ** 2, 3 * t, -3 - 0.2 * t ** 2], axis=1)
    return g, h


@pytest.mark.parametrize("data", [hypar_points, curved_points], ids=["skew-lines", "curved"])
def test_bisector_faces_are_bisector_planes_and_mesh_is_pp(data):
    g, h = data()
    grid = bisector_mesh(g, h)
    assert grid.shape == (len(g) - 1, len(h) - 1)
    assert_pp(grid)
    # every corner of face (i, j) is equidistant from g_{i+1} and h_{j+1}
    c = grid.face_corners                                           # (m, n, 4, 3)
    dg = np.linalg.norm(c - g[1:-1, None, None, :], axis=-1)
    dh = np.linalg.norm(c - h[None, 1:-1, None, :], axis=-1)
    assert np.abs(dg - dh).max() <= 1e-9 * np.ptp(g)


def test_bisector_of_skew_lines_is_the_hyperbolic_paraboloid():
    """Remark 3.1: the bisector of the lines (s, 0, a) and (0, t, −a) is z = (y² − x²) / 4a, and face (i, j) is
    its tangent plane at (s_{i+1}, t_{j+1}).  Vertex (i, j) lies on U_i: x = (s_i + s_{i+1}) / 2 and W_j, and
    the tangent plane there misses the surface by (δs_i² − δt_j²) / 16a (zero for equal steps)."""
    a = 3.0
    s = np.linspace(-2, 2, 10)
    t = np.linspace(-1.5, 1.5, 8) ** 3 / 1.5 ** 2            # uneven steps
    grid = bisector_mesh(np.stack([s, 0 * s, a + 0 * s], 1), np.stack([0 * t, t, -a + 0 * t], 1))
    x, y, z = np.moveaxis(grid.vertices, -1, 0)
    assert np.abs(x - 0.5 * (s[1:] + s[:-1])[:, None]).max() <= 1e-12
    assert np.abs(y - 0.5 * (t[1:] + t[:-1])[None, :]).max() <= 1e-12
    expect = (np.diff(s)[:, None] ** 2 - np.diff(t)[None, :] ** 2) / (16 * a)
    assert np.abs(z - (y ** 2 - x ** 2) / (4 * a) - expect).max() <= 1e-12
    assert np.abs(expect).max() > 1e-3
    even = bisector_mesh(np.stack([s, 0 * s, a + 0 * s], 1), np.stack([0 * s, s, -a + 0 * s], 1))
    x, y, z = np.moveaxis(even.vertices, -1, 0)
    assert np.abs(z - (y ** 2 - x ** 2) / (4 * a)).max() <= 1e-12


def test_radii_change_gives_a_parallel_mesh():
    """Fig. 8 right: changing the sphere radii keeps the face normals, the mesh is a parallel mesh."""
    g, h = curved_points()
    base = bisector_mesh(g, h)
    rg = 0.2 + 0.05 * np.sin(np.arange(len(g)))
    rh = 0.1 + 0.03 * np.cos(np.arange(len(h)))
    par = bisector_mesh(np.concatenate([g, rg[:, None]], 1), np.concatenate([h, rh[:, None]], 1))
    assert_pp(par)
    assert np.abs(par.vertices - base.vertices).max() > 1e-3          # really moved
    for e0, e1 in ((base.edges_u(), par.edges_u()), (base.edges_v(), par.edges_v())):
        cross = np.linalg.norm(np.cross(e0, e1), axis=-1)
        assert (cross <= 1e-9 * np.linalg.norm(e0, axis=-1) * np.linalg.norm(e1, axis=-1) + 1e-15).all()
        assert (np.einsum("...i,...i->...", e0, e1) > 0).all()
    assert np.abs(par.face_planes[..., :3] - base.face_planes[..., :3]).max() <= 1e-9
    # and the radical plane property: equal power of each corner w.r.t. both spheres
    c = par.face_corners
    pg = np.linalg.norm(c - g[1:-1, None, None], axis=-1) ** 2 - rg[1:-1, None, None] ** 2
    ph = np.linalg.norm(c - h[None, 1:-1, None], axis=-1) ** 2 - rh[None, 1:-1, None] ** 2
    assert np.abs(pg - ph).max() <= 1e-9 * np.ptp(g) ** 2


def test_bisector_design_errors():
    g, h = hypar_points()
    params = {"g": g.tolist(), "h": h.tolist()}
    grid = build_construction("bisector", params)
    par = build_construction("bisector", dict(params, g_radius=0.5))
    assert np.abs(par.face_planes[..., :3] - grid.face_planes[..., :3]).max() <= 1e-9
    bad = dict(params, h=h.tolist())
    bad["h"][4] = g[3].tolist()                 # h_4 coincides with g_3: no bisector plane
    with pytest.raises(DesignError, match=r"geometry\.params\.g\[3\]: g_3 and h_4 have the same centre"):
        build_construction("bisector", bad)
    bad = dict(params, g=g.tolist())
    bad["g"][5] = bad["g"][4]
    with pytest.raises(DesignError, match=r"g\[4\]: points g_4 and g_5 have the same centre.*U_4"):
        build_construction("bisector", bad)
    with pytest.raises(DesignError, match=r"h\[2\]: needs \[x, y, z\] or \[x, y, z, r\]"):
        build_construction("bisector", dict(params, h=[[0, 0, 1], [0, 1, 1], [0, 2], [0, 3, 1]]))


# -- profile curves ------------------------------------------------------------------------------

def arches(scale_x=15.0, scale_y=10.0, k=9):
    xs, ys = np.linspace(-scale_x, scale_x, k), np.linspace(-scale_y, scale_y, k)
    return [[x, 8 - x ** 2 / 45] for x in xs], [[y, 8 - y ** 2 / 22] for y in ys]


def rotated_frames():
    """A generic placement: eps and phi turned about a tilted axis, moved away from the origin."""
    ax = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
    th = 0.7
    K = np.array([[0, -ax[2], ax[1]], [ax[2], 0, -ax[0]], [-ax[1], ax[0], 0]])
    R = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K
    o = np.array([5.0, -3.0, 2.0])
    return dict(eps_origin=o.tolist(), eps_axes=[(R @ [1, 0, 0]).tolist(), (R @ [0, 0, 1]).tolist()],
                phi_origin=o.tolist(), phi_axes=[(R @ [0, 1, 0]).tolist(), (R @ [0, 0, 1]).tolist()])


@pytest.mark.parametrize("frames", [{}, rotated_frames()], ids=["default-frames", "rotated-frames"])
def test_profile_formula_interpolates_both_curves(frames):
    """Corrected §3.2.1 formula: f(u, v0) is the tangent plane along c, f(u0, v) along d, and the limit
    surface x = f ∩ f_u ∩ f_v (eq. 9) passes through both curves."""
    c_pts, d_pts = arches()
    S = profile_surface(c_pts, d_pts, **frames)
    u = np.linspace(S.c_curve.t0, S.c_curve.t1, 41)
    v = np.linspace(S.d_curve.t0, S.d_curve.t1, 37)
    c = S.c_curve.point(u)
    d = S.d_curve.point(v)
    f_c = S.f(u, np.full_like(u, S.v0))
    m = S.c_curve.unit_normal(u, S.sign_c)
    assert np.abs(f_c[:, :3] - m).max() <= 1e-12
    assert np.abs(pl.evaluate(f_c, c)).max() <= 1e-9
    assert np.abs(pl.evaluate(S.g_prime(u), c)).max() <= 1e-9        # f_u contains c(u) (m ⊥ c')
    assert np.abs(S.limit_point(u, np.full_like(u, S.v0)) - c).max() <= 1e-9 * 30
    assert np.abs(S.limit_point(np.full_like(v, S.u0), v) - d).max() <= 1e-9 * 30
    grid = S.mesh(12, 9)
    assert_pp(grid)


def _point_triangle_distance(p, a, b, c):
    """Distance of points ``p (P, 3)`` from triangles ``(T, 3)`` each → ``(P, T)`` (Ericson, closest point
    on a triangle by Voronoi regions; vectorised)."""
    p = p[:, None, :]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    den = np.where(va + vb + vc == 0, 1.0, va + vb + vc)
    q = a + (vb / den)[..., None] * ab + (vc / den)[..., None] * ac                          # interior
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ab = np.clip(d1 / (d1 - d3), 0, 1)
        t_ac = np.clip(d2 / (d2 - d6), 0, 1)
        t_bc = np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)
    cand = np.stack([q, a + np.nan_to_num(t_ab)[..., None] * ab, a + np.nan_to_num(t_ac)[..., None] * ac,
                     b + np.nan_to_num(t_bc)[..., None] * (c - b), np.broadcast_to(a, q.shape),
                     np.broadcast_to(b, q.shape), np.broadcast_to(c, q.shape)])
    inside = (va >= 0) & (vb >= 0) & (vc >= 0)
    dist = np.linalg.norm(cand - p[None], axis=-1)
    dist[0] = np.where(inside, dist[0], np.inf)          # edges and corners are always valid candidates
    return dist.min(axis=0)


def _distance_to_mesh(grid, points, near=24):
    """Distance of points from the triangulated mesh (exact over the ``near`` triangles with the closest
    centroids, which contain the closest one on a fair mesh)."""
    import trimesh

    tri = trimesh.Trimesh(*grid.triangles(), process=False)
    t = tri.vertices[tri.faces]                                              # (T, 3, 3)
    cd = np.linalg.norm(points[:, None, :] - t.mean(axis=1)[None], axis=-1)
    idx = np.argpartition(cd, near, axis=1)[:, :near]                        # (P, near)
    out = np.empty(len(points))
    for k, p in enumerate(points):
        sub = t[idx[k]]
        out[k] = _point_triangle_distance(p[None], sub[:, 0], sub[:, 1], sub[:, 2]).min()
    return out


@pytest.mark.parametrize("fit", ["interpolate", "control"])
def test_profile_mesh_converges_to_both_curves(fit):
    """The input curves lie on the mesh's limit surface: their distance from the mesh shrinks ~h²."""
    c_pts, d_pts = arches()
    S = profile_surface(c_pts, d_pts, fit=fit, meet_tolerance=1e-3)
    if fit == "control":        # a control polygon misses its apex point: lift d onto c's apex
        lift = S.c_curve.point([S.u0])[0, 2] - S.d_curve.point([S.v0])[0, 2]
        assert 0.005 < abs(lift) < 0.02
        S = profile_surface(c_pts, [[y, z + lift] for y, z in d_pts], fit=fit)
    assert S.gap <= 1e-9
    lo_u, hi_u = S.c_curve.t0, S.c_curve.t1
    lo_v, hi_v = S.d_curve.t0, S.d_curve.t1
    c = S.c_curve.point(np.linspace(lo_u + 0.1 * (hi_u - lo_u), hi_u - 0.1 * (hi_u - lo_u), 60))
    d = S.d_curve.point(np.linspace(lo_v + 0.1 * (hi_v - lo_v), hi_v - 0.1 * (hi_v - lo_v), 60))
    errs = []
    for faces in ((20, 14), (40, 28), (80, 56)):
        grid = S.mesh(*faces)
        assert_pp(grid)
        errs.append(max(_distance_to_mesh(grid, c).max(), _distance_to_mesh(grid, d).max()))
    assert errs[1] < errs[0] / 2.5 and errs[2] < errs[1] / 2.5, errs
    assert errs[2] < 1.5e-2                      # 15 mm on a 30 m roof with 0.75 m panels


def test_profile_design_file_and_preconditions():
    c_pts, d_pts = arches()
    grid = build_construction("profile_curves", {"c_points": c_pts, "d_points": d_pts, "faces_u": 10, "faces_v": 8})
    assert grid.shape == (11, 9)
    assert_pp(grid)
    base = {"c_points": c_pts, "d_points": d_pts}
    tilted = dict(base, phi_axes=[[np.sin(np.radians(10)), np.cos(np.radians(10)), 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(DesignError, match=r"geometry\.params\.phi_axes: planes eps and phi are not orthogonal: "
                                          r"they meet at 80°"):
        build_construction("profile_curves", tilted)
    lifted = dict(base, d_points=[[y, z + 0.5] for y, z in d_pts])
    with pytest.raises(DesignError, match=r"d_points: the curves do not meet.* 0\.5 apart"):
        build_construction("profile_curves", lifted)
    sloped = dict(base, c_points=[[x, z + 0.05 * x] for x, z in c_pts])
    with pytest.raises(DesignError, match=r"c_points: curve c has no common normal.*makes 2\.86\d°"):
        build_construction("profile_curves", sloped)
    wavy = dict(base, c_points=[[x, 8 + np.sin(x / 4)] for x in np.linspace(-15, 15, 13)])
    with pytest.raises(DesignError, match=r"c_points: curve c has an inflection"):
        build_construction("profile_curves", wavy)
    half = dict(base, c_points=[[x, 8 - x ** 2 / 45] for x in np.linspace(1, 15, 6)])
    with pytest.raises(DesignError, match=r"c_points: curve c does not reach the plane phi: it stays 1 away"):
        build_construction("profile_curves", half)
    ang = np.radians(np.linspace(-95, 265, 25))          # a convex arc through the bottom and the top
    loop = dict(base, c_points=[[5 * np.cos(a), 3 + 5 * np.sin(a)] for a in ang])
    with pytest.raises(DesignError, match=r"c_points: curve c crosses the plane phi 2 times"):
        build_construction("profile_curves", loop)
    with pytest.raises(DesignError, match=r"c_points\[1\]: needs 2 numbers"):
        build_construction("profile_curves", dict(base, c_points=[[0, 1], [1, 2, 3], [2, 1]]))


# -- translational -------------------------------------------------------------------------------

def test_translational_default_and_general_frames():
    xs, ys = np.linspace(-15, 15, 7), np.linspace(-10, 10, 5)
    a_pts = [[x, 8 - 5.5 * (x / 15) ** 2] for x in xs]
    b_pts = [[y, -2.5 * (y / 10) ** 2] for y in ys]
    g1 = build_construction("translational", {"a_points": a_pts, "b_points": b_pts, "faces_u": 12, "faces_v": 8})
    # non-orthogonal, non-vertical profile planes and control-polygon fit
    g2 = build_construction("translational", {
        "a_points": a_pts, "b_points": b_pts, "fit": "control", "faces_u": 9, "faces_v": 11,
        "eps_axes": [[1, 0.2, 0], [0, 0.1, 1]], "phi_axes": [[0.3, 1, 0], [0.1, 0, 1]],
        "phi_origin": [1, 2, 3]})
    for grid in (g1, g2):
        assert_pp(grid)
        v = grid.vertices
        # translational: every column is a translate of the first, every row of the first row
        assert np.abs((v - v[:, :1]) - (v[:1] - v[:1, :1])).max() <= 1e-12 * np.ptp(v)
        # both families of support planes are parallel; all node axes share one direction
        for planes in (grid.support_u, grid.support_w):
            n = pl.normalize(planes)[:, :3]
            assert np.abs(np.cross(n, n[0])).max() <= 1e-12
        a = grid.axes.reshape(-1, 3)
        assert np.abs(np.cross(a, a[0])).max() <= 1e-12
    assert np.abs(np.cross(g1.axes[0, 0], [0, 0, 1])).max() <= 1e-12      # vertical with the default frames
    assert np.allclose(g1.vertices[0, 0], [-15, -10, 0.0], atol=1e-9)      # corner: a(-15) + b(-10) = 2.5 - 2.5


def test_translational_errors():
    pts = [[x, 1 - x * x / 10] for x in range(-3, 4)]
    with pytest.raises(DesignError, match=r"phi_axes: planes eps and phi are parallel"):
        build_construction("translational", {"a_points": pts, "b_points": pts,
                                              "phi_axes": [[1, 0, 0], [0, 0, 1]]})
    with pytest.raises(DesignError, match=r"eps_axes: the two axes are parallel"):
        build_construction("translational", {"a_points": pts, "b_points": pts, "eps_axes": [[1, 0, 0], [2, 0, 0]]})
    with pytest.raises(DesignError, match=r"a_points\[3\]: repeats point 2"):
        build_construction("translational", {"a_points": pts[:3] + pts[2:], "b_points": pts})
    bent = np.array([[x, 0, 0.1 * x * x] for x in range(5)], float)
    bent[2, 1] = 0.3
    with pytest.raises(GeometryError, match=r"profile a is not planar"):
        translational_mesh(bent, np.array([[0, y, -0.1 * y * y] for y in range(4)], float))


# -- bundled examples ----------------------------------------------------------------------------

def test_every_method_has_an_example():
    methods = {tomllib.loads(p.read_text())["geometry"]["method"] for p in EXAMPLES}
    assert {"cauchy", "bisector", "profile_curves", "plane_splines", "translational"} <= methods


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_builds_as_an_architectural_pp_mesh(path: Path):
    doc = tomllib.loads(path.read_text())
    grid = build_construction(doc["geometry"]["method"], doc["geometry"].get("params"))
    assert_pp(grid)
    v = grid.vertices.reshape(-1, 3)
    extent = np.ptp(v, axis=0)
    assert 25 <= extent[0] <= 32 and 15 <= extent[1] <= 22          # a 30 m x 20 m roof (metres)
    e = np.concatenate([np.linalg.norm(grid.edges_u(), axis=-1).ravel(),
                        np.linalg.norm(grid.edges_v(), axis=-1).ravel()])
    assert 0.8 <= e.min() and e.max() <= 2.2                          # panels of about 1.2-1.8 m
    assert float(doc["geometry"]["scale"]) == 1000.0

