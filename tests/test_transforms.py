"""Face-image transforms: F-transforms / parallel meshes and offsets (§2.2.3), 4D projective maps (§2.3.5),
multi-net deletion (Remark 3.2)."""

from __future__ import annotations

import numpy as np
import pytest

from ppfab import planes as pl
from ppfab.transforms import pp as tf
from ppfab.constructions import build_construction
from ppfab.errors import GeometryError
from ppfab.faceimage import pp_from_face_image
from ppfab.mesh import QuadGrid
from ppfab.metrics import face_planarity, plane_residual, polyline_planarity

from conftest import smooth_face_image

TOL = 1e-9


def face_image_grid():
    return pp_from_face_image(*smooth_face_image(8, 9, seed=1))


def profile_grid():
    xs, ys = np.linspace(-15, 15, 9), np.linspace(-10, 10, 9)
    return build_construction("profile_curves", {"c_points": [[x, 8 - x ** 2 / 45] for x in xs],
                                                 "d_points": [[y, 8 - y ** 2 / 22] for y in ys],
                                                 "faces_u": 12, "faces_v": 9})


def bare_cauchy_grid():
    """A PP grid with nothing but its vertices (no face image, no support planes): from Cauchy data."""
    U = np.array([[40.0, 0, x, -40 * x] for x in np.linspace(-6, 6, 7)])
    W = np.array([[0, 40.0, y, -40 * y] for y in np.linspace(-4, 4, 6)])
    on = lambda x, y, z: [(40 - z) / 40 * x, (40 - z) / 40 * y, z]            # noqa: E731
    col = [on(x, -4, 3 + (1 - (x / 6) ** 2)) for x in np.linspace(-6, 6, 7)]
    row = [on(-6, y, 3 + 0.8 * (1 - (y / 4) ** 2)) for y in np.linspace(-4, 4, 6)]
    g = build_construction("cauchy", {"support_u": U.tolist(), "support_w": W.tolist(),
                                      "boundary_u": col, "boundary_w": row})
    return QuadGrid(g.vertices)


GRIDS = {"face-image": face_image_grid, "profile-curves": profile_grid, "bare-vertices": bare_cauchy_grid}


@pytest.fixture(params=list(GRIDS), ids=list(GRIDS))
def grid(request):
    return GRIDS[request.param]()


def size(g):
    v = g.vertices.reshape(-1, 3)
    return float(np.linalg.norm(np.ptp(v, axis=0)))


def assert_pp(g, tol=TOL):
    assert face_planarity(g.face_corners).max() <= tol
    assert polyline_planarity(g.rows()).max() <= tol
    assert polyline_planarity(g.cols()).max() <= tol
    assert plane_residual(g.rows(), g.support_u).max() <= tol
    assert plane_residual(g.cols(), g.support_w).max() <= tol


def test_extended_image_rebuilds_the_grid(grid):
    F = tf.extended_face_image_of(grid)
    m1, n1 = grid.shape
    assert F.shape == (m1 + 1, n1 + 1, 4)
    again = tf.grid_from_extended(F)
    assert np.abs(again.vertices - grid.vertices).max() <= TOL * size(grid)
    assert_pp(again)
    full = tf.with_face_image(grid)
    assert full.face_image.shape == (m1 - 1, n1 - 1, 4) and full.axes.shape == (m1, n1, 3)


def test_non_pp_grid_is_rejected():
    g = face_image_grid()
    v = np.array(g.vertices)
    v[4, 5] += 0.01 * pl.normalize(g.support_u[4])[:3]        # off its row plane
    with pytest.raises(GeometryError, match=r"not a PP mesh: row polyline 4 deviates 0\.00"):
        tf.f_transform(QuadGrid(v), np.zeros(4))
    v = np.array(g.vertices)
    v[4, 5] += 0.01 * np.cross(pl.normalize(g.support_u[4])[:3], pl.normalize(g.support_w[5])[:3])
    with pytest.raises(GeometryError, match=r"not a PP mesh: rebuilding vertex \(4, 5\) .* moves it by 0\.01"):
        tf.f_transform(QuadGrid(v), np.zeros(4))          # along its node axis: rows stay planar, faces do not
    closed = QuadGrid(g.vertices, closed=True)
    with pytest.raises(GeometryError, match="open patch"):
        tf.parallel_mesh(closed, 0.1)


def test_f_transform_shares_the_support_structure(grid):
    rng = np.random.default_rng(7)
    F = tf.extended_face_image_of(grid)
    t = 0.05 * np.abs(F).max() * rng.normal(size=4)
    out = tf.f_transform(grid, t)
    assert_pp(out)
    assert np.abs(out.vertices - grid.vertices).max() > 1e-3 * size(grid)
    base = tf.with_face_image(grid)
    # same support planes: the new rows and columns lie in the old planes U_i, W_j ...
    assert plane_residual(out.rows(), base.support_u).max() <= TOL
    assert plane_residual(out.cols(), base.support_w).max() <= TOL
    # ... so corresponding edges are coplanar (Fig. 4)
    for e0, e1, d in ((grid.edges_u(), out.edges_u(), out.vertices[:, :-1] - grid.vertices[:, :-1]),
                      (grid.edges_v(), out.edges_v(), out.vertices[:-1] - grid.vertices[:-1])):
        vol = np.abs(np.einsum("...i,...i->...", np.cross(e0, e1), d))
        assert vol.max() <= TOL * size(grid) ** 3


def test_parallel_mesh_keeps_edge_directions(grid):
    F = tf.extended_face_image_of(grid)
    out = tf.parallel_mesh(grid, 0.03 * np.abs(F[..., 3]).max())
    assert_pp(out)
    for e0, e1 in ((grid.edges_u(), out.edges_u()), (grid.edges_v(), out.edges_v())):
        c = np.linalg.norm(np.cross(e0, e1), axis=-1)
        assert (c <= TOL * np.linalg.norm(e0, axis=-1) * np.linalg.norm(e1, axis=-1) + 1e-15).all()
    assert np.abs(out.face_planes[..., :3] - grid.face_planes[..., :3]).max() <= 1e-9


@pytest.mark.parametrize("mode", ["parallel", "f_transform"])
def test_offset_moves_vertices_along_node_axes(grid, mode):
    depth = 0.02 * size(grid)
    out = tf.offset_along_axes(grid, depth, mode=mode)
    assert_pp(out)
    axes = tf.with_face_image(grid).axes
    d = out.vertices - grid.vertices
    assert np.abs(np.cross(d, axes)).max() <= TOL * size(grid)          # along the node axes
    stats = out.meta["offset"]
    s = np.einsum("...i,...i->...", d, axes)
    assert stats["min"] == pytest.approx(s.min()) and stats["max"] == pytest.approx(s.max())
    assert abs(stats["mean"] - depth) <= 0.1 * depth
    if mode == "parallel":
        assert np.abs(out.face_planes[..., :3] - grid.face_planes[..., :3]).max() <= 1e-9


def test_offset_is_uniform_where_it_can_be_and_f_transform_is_closer_elsewhere():
    xs, ys = np.linspace(-15, 15, 7), np.linspace(-10, 10, 5)
    tr = build_construction("translational", {"a_points": [[x, 8 - x * x / 40] for x in xs],
                                              "b_points": [[y, -y * y / 40] for y in ys]})
    o = tf.offset_along_axes(tr, 0.25)                 # vertical axes: a vertical shift is an exact parallel offset
    assert o.meta["offset"]["max"] - o.meta["offset"]["min"] <= 1e-9
    assert np.abs(o.vertices - tr.vertices - 0.25 * tr.axes).max() <= 1e-9
    g = profile_grid()
    par, ftr = tf.offset_along_axes(g, 0.3), tf.offset_along_axes(g, 0.3, mode="f_transform")
    spread = lambda o: o.meta["offset"]["max"] - o.meta["offset"]["min"]    # noqa: E731
    assert spread(ftr) <= spread(par) + 1e-12


def random_projective(seed, strength=0.08):
    rng = np.random.default_rng(seed)
    return np.eye(5) + strength * rng.normal(size=(5, 5))


@pytest.mark.parametrize("seed", [0, 1])
def test_projective_map_keeps_pp_and_gives_a_torsion_free_support_structure(grid, seed):
    F = tf.extended_face_image_of(grid)
    T = random_projective(seed)
    T[4, :4] /= np.abs(F).max()              # keep the weights away from zero on this image
    out = tf.projective_map(grid, T)
    assert_pp(out)
    assert np.abs(out.vertices - grid.vertices).max() > 1e-3 * size(grid)
    # Prop. 2.5 for the projective image itself: every vertex lies on its four planes T(f) ...
    Fh = np.concatenate([F, np.ones(F.shape[:2] + (1,))], -1) @ T.T
    Fp = Fh[..., :4] / Fh[..., 4:]
    v = out.vertices
    m1, n1 = out.shape
    for da in (0, 1):
        for db in (0, 1):
            assert np.abs(pl.signed_distance(Fp[da:da + m1, db:db + n1], v)).max() <= TOL * size(out)
    # ... and the re-weighted edge planes (differences of F/w) contain both end points and their axes
    a, w = tf.reweighted_axes(grid, T)
    s = Fp[1:-1, 1:] - Fp[1:-1, :-1]         # across column polylines j: faces (a, j), (a, j+1), a = 1..m
    s = pl.normalize(s)
    for di in (0, 1):                         # the edge v[i, j] v[i+1, j] has both ends in the plane
        pts = v[di:di + s.shape[0], :]
        ax = a[di:di + s.shape[0], :]
        assert np.abs(pl.signed_distance(s, pts)).max() <= 1e-8 * size(out)
        assert np.abs(np.einsum("...i,...i->...", s[..., :3], ax)).max() <= 1e-8
    assert np.ptp(w) > 1e-3                   # a genuinely projective (not affine) map


def test_affine_and_identity_maps():
    g = face_image_grid()
    same = tf.projective_map(g, np.eye(5))
    assert np.abs(same.vertices - g.vertices).max() <= TOL * size(g)
    t = np.array([0.01, -0.02, 0.015, 0.03])
    T = np.eye(5)
    T[:4, 4] = t                                 # a translation of R^4 is the F-transform by t
    assert np.abs(tf.projective_map(g, T).vertices - tf.f_transform(g, t).vertices).max() <= TOL * size(g)
    T = np.eye(5) * 2.5
    T[4, 4] = 1.0                               # scaling the weighted image keeps the mesh
    assert np.abs(tf.projective_map(g, T).vertices - g.vertices).max() <= TOL * size(g)


def test_projective_map_errors():
    g = face_image_grid()
    F = tf.extended_face_image_of(g)
    T = np.eye(5)
    T[4, :4] = -F[3, 4] / (F[3, 4] @ F[3, 4])    # c·f + 1 = 0 at F[3, 4]: that face goes to infinity
    with pytest.raises(GeometryError, match=r"sends face image point F\[3, 4\] to infinity"):
        tf.projective_map(g, T)
    with pytest.raises(GeometryError, match=r"singular"):
        tf.projective_map(g, np.zeros((5, 5)))
    with pytest.raises(GeometryError, match=r"5x5"):
        tf.projective_map(g, np.eye(4))


def test_deleting_face_rows_and_columns_gives_a_pp_mesh_on_the_remaining_planes(grid):
    m, n = grid.face_shape
    rows, cols = [1, m // 2], [n - 2]
    out = tf.delete_face_cols(tf.delete_face_rows(grid, rows), cols)
    assert out.face_shape == (m - 2, n - 1)
    assert_pp(out)
    keep_r = [i for i in range(m) if i not in rows]
    keep_c = [j for j in range(n) if j not in cols]
    old = grid.face_planes[np.ix_(keep_r, keep_c)]
    new = out.face_planes
    assert np.abs(np.abs(np.einsum("...i,...i->...", old[..., :3], new[..., :3])) - 1).max() <= 1e-9
    # the face planes are the same planes: the new face corners lie on the old planes
    assert np.abs(pl.signed_distance(old[..., None, :], out.face_corners)).max() <= TOL * size(grid)


def test_multinet_and_deletion_errors():
    g = face_image_grid()
    coarse = tf.multinet(g, 2, 3)
    assert coarse.face_shape == (4, 3)
    assert_pp(coarse)
    assert np.abs(pl.signed_distance(g.face_planes[::2, ::3][..., None, :], coarse.face_corners)).max() <= TOL
    with pytest.raises(GeometryError, match=r"face row 8 does not exist \(the mesh has 8 face rows"):
        tf.delete_face_rows(g, [8])
    with pytest.raises(GeometryError, match=r"deleting all 9 face columns leaves no mesh"):
        tf.delete_face_cols(g, range(9))
    with pytest.raises(GeometryError, match=r"step_u must be a positive integer"):
        tf.multinet(g, 0, 1)
