"""Conical P meshes from sphere families (§4.2.3 Steps 1–4) and the conical PP special case (§4.2.4)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from ppfab import planes as pl
from ppfab.conical.cones import cone_axes, conical_quality, offset_faces
from ppfab.constructions import build_construction
from ppfab.constructions.conical_spheres import channel_mesh, pp_column_planes, touching_radii
from ppfab.errors import DesignError, FoldError, GeometryError
from ppfab.metrics import quality
from ppfab.curves import PlanarCurve
from ppfab.conical.spheres import SphereSpline, bisector_normals, tangential_distances, w_planes

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
TOL = 1e-9

WAVY = np.array([[0, 0, 2, 5.0], [8, 3, 3, 6], [16, -2, 2.5, 5.5], [24, 0, 2, 4.5], [30, 2, 3, 5]])
ARCHED = np.array([[0, 0, 0, 7.0], [6, 2, 3, 6.0], [14, 1, 5, 6.5], [22, -3, 3, 7.5], [28, -1, 0, 7.0],
                   [34, 2, -1, 6.0]])
SETS = {
    "wavy-open": dict(spheres=WAVY, faces_spine=16, faces_profile=12, angle_range=(-80, 80)),
    "arched-open-quadratic": dict(spheres=ARCHED, faces_spine=20, faces_profile=9, angle_range=(-60, 100), degree=2),
    "wavy-closed-tube": dict(spheres=WAVY, faces_spine=12, faces_profile=16, angle_range=(0, 0), closed=True),
}


def spheres_tangent(grid):
    """Largest |n·c + d + r| of the strip planes E[a] against the spheres Z_{a−1}, Z_a they should touch."""
    Z, E = grid.meta["spheres"], grid.extended_face_planes
    inner = E[1:-1]
    lo = np.einsum("akn,an->ak", inner[..., :3], Z[:-1, :3]) + inner[..., 3] + Z[:-1, 3:4]
    hi = np.einsum("akn,an->ak", inner[..., :3], Z[1:, :3]) + inner[..., 3] + Z[1:, 3:4]
    return max(np.abs(lo).max(), np.abs(hi).max())


@pytest.mark.parametrize("name", list(SETS), ids=list(SETS))
def test_channel_mesh_is_conical_p(name):
    grid = channel_mesh(**SETS[name])
    q = conical_quality(grid)
    assert q.delta_f_max <= TOL
    assert q.delta_p_rows_max <= TOL and q.support_u_max <= TOL         # row i lies in W_i (eq. 16)
    assert q.angle_max <= TOL and q.concyclic_max <= TOL
    assert spheres_tangent(grid) <= 1e-9 * 30                            # faces touch Z_i, Z_{i+1}
    assert q.delta_p_cols_max > 1e-4                                     # a P mesh, not PP
    qq = quality(grid)
    assert qq.flipped_edges == 0 and qq.nonconvex_faces == 0


def test_spheres_are_sampled_uniformly_in_tangential_distance():
    spline = SphereSpline(WAVY)
    Z, t = spline.sample_uniform(25)
    d = tangential_distances(Z)
    assert np.ptp(d) / d.mean() < 1e-10                                  # equal Minkowski distances (Remark 4.4)
    assert t[0] == 0.0 and t[-1] == 1.0 and np.all(np.diff(t) > 0)


def test_w_planes_carry_the_intersection_of_consecutive_cones():
    """Eq. (16): a point of W_j on a tangent plane of C_{j−1} lies on the same-ruling tangent plane of C_j."""
    grid = channel_mesh(**SETS["wavy-open"])
    Z = grid.meta["spheres"]
    W = w_planes(Z, grid.meta["H"])
    assert np.allclose(pl.normalize(W), pl.normalize(grid.support_u))
    E = grid.extended_face_planes
    v = grid.vertices
    # vertex v[i, j] is on the two planes of strip i−1 and of strip i around it, and in W_i
    for a in (0, 1):
        s = E[a:a + grid.shape[0]]
        assert np.abs(pl.evaluate(s[:, :-1], v)).max() < 1e-9 and np.abs(pl.evaluate(s[:, 1:], v)).max() < 1e-9
    H = bisector_normals(Z)
    assert np.allclose(H[1:-1], grid.meta["H"][1:-1])                    # interior H_j = E_j + E_{j+1}


def test_cone_axes_pass_through_the_sphere_centres():
    grid = channel_mesh(**SETS["arched-open-quadratic"])
    axes, _ = cone_axes(grid)
    to_centre = grid.meta["spheres"][:, None, :3] - grid.vertices
    to_centre /= np.linalg.norm(to_centre, axis=-1, keepdims=True)
    assert np.abs(np.abs(np.einsum("ijk,ijk->ij", axes, to_centre)) - 1).max() < 1e-9
    assert np.abs(np.einsum("ijk,ijk->ij", axes, grid.axes) - 1).max() < 1e-9


def test_offset_of_channel_mesh_stays_conical_p():
    grid = channel_mesh(**SETS["wavy-open"])
    off = offset_faces(grid, -0.3)
    q = conical_quality(off)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.angle_max) <= TOL


ELLIPSE = np.c_[6.5 * np.cos(np.linspace(0, 2 * np.pi, 24, endpoint=False)),
                8.0 * np.sin(np.linspace(0, 2 * np.pi, 24, endpoint=False))]


@pytest.mark.parametrize("plane", [0, 8, 16])
def test_profile_change_keeps_the_mesh_parallel_conical_and_p(plane):
    base = channel_mesh(**SETS["wavy-open"], profile_plane=plane)
    prof = PlanarCurve.from_points(ELLIPSE, closed=True, name="profile")
    grid = channel_mesh(**SETS["wavy-open"], profile=prof, profile_plane=plane)
    q = conical_quality(grid)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.support_u_max, q.angle_max, q.concyclic_max) <= TOL
    for e0, e1 in ((base.edges_u(), grid.edges_u()), (base.edges_v(), grid.edges_v())):
        cross = np.linalg.norm(np.cross(e0, e1), axis=-1) / (np.linalg.norm(e0, axis=-1) * np.linalg.norm(e1, axis=-1))
        assert cross.max() < 1e-9                                       # edgewise parallel (Step 4)
    assert np.allclose(pl.normalize(grid.support_u), pl.normalize(base.support_u))   # same planes W_i
    # the new profile polygon in W_plane circumscribes the ellipse: every edge line touches it
    frame = grid.meta["profile_frame"]
    poly = frame.to2d(grid.vertices[plane])
    dense = prof(np.linspace(prof.t0, prof.t1, 20001))
    for a, b in zip(poly[:-1], poly[1:]):
        n = np.array([b[1] - a[1], a[0] - b[0]]) / np.linalg.norm(b - a)
        dist = (dense - a) @ n
        assert min(abs(dist.max()), abs(dist.min())) < 1e-5 and dist.max() * dist.min() >= -1e-10


def angle_balance_of(v: np.ndarray) -> np.ndarray:
    """``|α_0 − α_1 + α_2 − α_3|`` at the interior vertices of a grid ``(m, n, 3)``, the angles between
    consecutive edges around each vertex (its own formula, for the conical property)."""
    c = v[1:-1, 1:-1]
    e = [v[1:-1, 2:] - c, v[2:, 1:-1] - c, v[1:-1, :-2] - c, v[:-2, 1:-1] - c]
    unit = [x / np.linalg.norm(x, axis=-1, keepdims=True) for x in e]
    ang = [np.arccos(np.clip(np.einsum("...i,...i->...", unit[k], unit[(k + 1) % 4]), -1, 1)) for k in range(4)]
    return np.abs(ang[0] - ang[1] + ang[2] - ang[3])


@pytest.mark.parametrize("shape", ["open wave", "closed flower"])
def test_a_profile_with_inflections_gives_an_inscribed_conical_p_mesh(shape):
    """Remark 4.2: a designed profile with inflections.  The mesh's row in W_k is the polygon inscribed in the
    curve at equal arclength, its profile angles run to and fro, and the mesh is still planar-faced, P and
    conical (measured here by an SVD per face and per row and the vertex angles)."""
    if shape == "open wave":
        q = np.linspace(-7.5, 7.5, 13)
        pts = np.c_[5.5 - 0.05 * q ** 2 + 0.45 * np.cos(0.9 * q), q]
        params = {"spheres": WAVY.tolist(), "faces_spine": 12, "faces_profile": 24, "profile": pts.tolist()}
    else:
        t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
        pts = np.c_[(6 + 1.5 * np.cos(5 * t)) * np.cos(t), (6 + 1.5 * np.cos(5 * t)) * np.sin(t)]
        params = {"spheres": WAVY.tolist(), "faces_spine": 12, "faces_profile": 40, "profile": pts.tolist(),
                  "profile_closed": True, "closed": True}
    prof = PlanarCurve.from_points(pts, closed=shape != "open wave", name="profile")
    grid = build_construction("conical_spheres", params)
    v = grid.vertices
    theta = grid.meta["theta_deg"]
    turns = np.diff(np.sign(np.diff(theta)))
    assert np.count_nonzero(turns) >= 2                              # the source profile runs to and fro
    quads = np.stack([v[:-1, :-1], v[1:, :-1], v[1:, 1:], v[:-1, 1:]], axis=2).reshape(-1, 4, 3)
    if grid.closed:
        wrap = np.stack([v[:-1, -1], v[1:, -1], v[1:, 0], v[:-1, 0]], axis=1)
        quads = np.concatenate([quads, wrap])
    centred = quads - quads.mean(axis=1, keepdims=True)
    assert (np.linalg.svd(centred, compute_uv=False)[:, 2]).max() < 1e-9       # planar faces
    for row in v:
        assert np.linalg.svd(row - row.mean(axis=0), compute_uv=False)[2] < 1e-9   # rows in planes (P)
    ext = np.concatenate([v[:, -1:], v, v[:, :1]], axis=1) if grid.closed else v
    assert angle_balance_of(ext).max() < 1e-9                         # conical
    k = grid.meta["profile_plane"]
    poly = grid.meta["profile_frame"].to2d(v[k])
    dense = prof(np.linspace(prof.t0, prof.t1, 200001))
    dist = np.min(np.linalg.norm(poly[:, None, :] - dense[None, :, :], axis=2), axis=1)
    assert dist.max() < 1e-3                                          # the polygon is inscribed in the curve
    seg = np.linalg.norm(np.diff(poly, axis=0), axis=1)
    assert seg.max() < 1.5 * seg.min()                                # at (nearly) equal arclength


def test_open_profile_must_cover_the_face_directions():
    arc = np.c_[6 * np.cos(np.linspace(-0.5, 0.5, 12)), 6 * np.sin(np.linspace(-0.5, 0.5, 12))]
    with pytest.raises(DesignError, match="profile: has no tangent with outward normal direction"):
        channel_mesh(WAVY, 8, 12, (-80, 80), profile=PlanarCurve.from_points(arc, name="profile"))


def test_spheres_not_spacelike_are_named():
    bad = WAVY.copy()
    bad[2, 3] = 20.0                                   # sphere 2 swallows sphere 1 and sphere 3
    with pytest.raises(DesignError, match=r"geometry\.params\.spheres\[1\]: spheres 1 and 2 are not in spacelike "
                                          r"position: \|Δr\| = 14 ≥ \|Δcenter\| = 9\.447"):
        build_construction("conical_spheres", {"spheres": bad.tolist()})


def test_family_not_spacelike_between_spacelike_controls():
    controls = np.array([[0, 0, 0, 1.0], [1, 0, 0, 1.9], [0, 0, 0, 2.8]])       # pairs spacelike, curve is not
    with pytest.raises(GeometryError, match=r"not spacelike at t = .*control spheres 0\.\.2"):
        channel_mesh(controls, 8, 6)


def test_fold_names_face_and_valid_range():
    bend = np.array([[0, 0, 0, 6.0], [6, 0, 0, 6], [8, 2, 0, 6], [8, 8, 0, 6]])   # bend tighter than the radius
    with pytest.raises(FoldError, match=r"conical_spheres folds over .*face \(\d+, \d+\).*stay valid"):
        channel_mesh(bend, 16, 12, (-90, 90))


# -- §4.2.4: the PP special case ---------------------------------------------------------------------

PP_SETS = {
    "ground-tangent": (np.array([[0, 0, 6.0], [10, 0, 8], [20, 0, 7.5], [30, 0, 6]]), np.array([0, 0, 1.0, 0]),
                       (-80, 80)),
    "tilted-plane": (np.array([[0, 1, 0.0], [8, 1, 2.0], [16, 1, 3.0], [26, 1, 1.0], [32, 1, -1.0]]),
                     np.array([0.2, 0.0, 1.0, -9.0]), (-70, 50)),
}


@pytest.mark.parametrize("name", list(PP_SETS), ids=list(PP_SETS))
def test_planar_spine_and_common_tangent_plane_give_pp(name):
    centers, plane, angles = PP_SETS[name]
    spheres = np.c_[centers, touching_radii(centers, plane)]
    grid = channel_mesh(spheres, 16, 12, angles)
    q = conical_quality(grid)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.delta_p_cols_max, q.angle_max, q.concyclic_max) <= TOL
    _, res = pp_column_planes(grid)
    assert res <= 1e-9 * np.ptp(grid.vertices.reshape(-1, 3), axis=0).max()
    # the column planes share the line M ∩ T
    P, _ = pp_column_planes(grid)
    M, _ = pl.fit_plane(centers)
    point, direction = pl.line_of_two_planes(M, pl.normalize(plane))
    assert np.abs(pl.signed_distance(P, point)).max() < 1e-8
    assert np.abs(P[:, :3] @ direction).max() < 1e-9


def test_pp_method_checks_its_input():
    base = {"centers": [[0, 0, 6.0], [10, 0, 8], [20, 0, 7.5]], "touch_plane": [0, 0, 1.0, 0]}
    grid = build_construction("conical_spheres_pp", base)
    assert grid.support_w is not None and grid.meta["planar_families"] == ("rows", "cols")
    with pytest.raises(DesignError, match=r"centers: the centres are not coplanar"):
        build_construction("conical_spheres_pp", {**base, "centers": [[0, 0, 6.0], [10, 0, 8], [20, 1, 7.5],
                                                                        [30, -1, 6.0]]})
    with pytest.raises(DesignError, match=r"touch_plane: control centre \d lies on or across the plane"):
        build_construction("conical_spheres_pp", {**base, "touch_plane": [0, 0, 1.0, -7.0]})


@pytest.mark.parametrize("path", [EXAMPLES / "conical_spheres.toml", EXAMPLES / "conical_spheres_pp.toml"],
                         ids=["P", "PP"])
def test_examples_build(path):
    doc = tomllib.loads(path.read_text())
    grid = build_construction(doc["geometry"]["method"], doc["geometry"].get("params"))
    q = conical_quality(grid)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.support_u_max, q.angle_max, q.concyclic_max) <= TOL
    if doc["geometry"]["method"] == "conical_spheres_pp":
        assert q.delta_p_cols_max <= TOL and q.support_w_max <= TOL
    else:
        assert grid.meta["profile_reference"] is not None                # Step 4 was applied
    edges = np.concatenate([np.linalg.norm(grid.edges_u(), axis=-1).ravel(),
                            np.linalg.norm(grid.edges_v(), axis=-1).ravel()])
    assert 0.8 < edges.min() and edges.max() < 2.2


@pytest.mark.parametrize("plane", [0, 8])
def test_axes_after_a_profile_change_are_the_torsion_free_cone_axes(plane):
    """Step 4 moves the vertices but keeps the normals: the grid's axes are the cone axes of its faces
    (equal angles with the four unit normals), not the lines to the sphere centres, and the support
    structure has no torsion along them."""
    from ppfab.support.structure import torsion

    prof = PlanarCurve.from_points(ELLIPSE, closed=True, name="profile")
    grid = channel_mesh(**SETS["wavy-open"], profile=prof, profile_plane=plane)
    n = grid.extended_face_planes[..., :3] / np.linalg.norm(grid.extended_face_planes[..., :3], axis=-1, keepdims=True)
    around = np.stack([n[:-1, :-1], n[1:, :-1], n[1:, 1:], n[:-1, 1:]], axis=-2)        # (rows, cols, 4, 3)
    cosines = np.einsum("ijkl,ijl->ijk", around, grid.axes)
    assert np.ptp(cosines, axis=-1).max() < 1e-9                                          # equal angles
    to_centre = grid.meta["spheres"][:, None, :3] - grid.vertices
    to_centre /= np.linalg.norm(to_centre, axis=-1, keepdims=True)
    assert np.degrees(np.arccos(np.clip(np.einsum("ijk,ijk->ij", grid.axes, to_centre), -1, 1))).max() > 1.0
    assert torsion(grid, grid.axes.reshape(-1, 3)).max() < 1e-8


@pytest.mark.parametrize("faces", [None, 30])
def test_strip_planes_are_the_reflections_applied_strip_by_strip(faces):
    """Step 3 (Remark 4.4): each strip's planes are the previous strip's reflected in ``σ_a``
    (``T_a = σ_a(T_{a−1})`` beyond the designed strip, ``σ_{a+1}`` before it), one reflection at a time by
    :meth:`LaguerreMap.planes`, on the bundled example with its Step 4 profile."""
    from ppfab.conical.spheres import reflections

    params = tomllib.loads((EXAMPLES / "conical_spheres.toml").read_text(encoding="utf-8"))["geometry"]["params"]
    if faces:
        params = {**params, "faces_spine": faces, "faces_profile": faces}
    grid = build_construction("conical_spheres", params)
    E, meta = grid.extended_face_planes, grid.meta
    sigma = reflections(meta["spheres"], meta["H"])
    N = len(sigma) - 1
    s0 = min(meta["profile_plane"], N - 1)
    worst = 0.0
    for a in range(-1, N + 1):
        if a == s0:
            continue
        step = sigma[a].planes(E[a]) if a > s0 else sigma[a + 1].planes(E[a + 2])
        worst = max(worst, float(np.abs(step - E[a + 1]).max()))
    assert worst < 1e-12 * float(np.abs(E[..., 3]).max())
    # and the rows lie in the planes W_i (the vault is about 32 m long)
    W = pl.normalize(grid.support_u)
    assert np.abs(np.einsum("ijk,ik->ij", grid.vertices, W[:, :3]) + W[:, None, 3]).max() < 1e-12 * 32
