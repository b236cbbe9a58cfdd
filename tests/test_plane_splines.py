"""Plane splines (§3.2.2, Fig. 11, Remark 3.3): re-weighting, tangent continuity, side condition, cusps."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from ppfab.constructions import build_construction
from ppfab.constructions.plane_splines import (CuspWarning, knot_line, plane_from_entry, plane_spline,
                                               plane_spline_mesh)
from ppfab.errors import DesignError
from ppfab.metrics import face_planarity, plane_residual, polyline_planarity, quality


def paraboloid_arrangement(a=50.0, b=30.0, knots_u=(-15, -5, 5, 15), knots_v=(-10, -10 / 3, 10 / 3, 10),
                           tilt_u=(0, 0, 0, 0), tilt_v=(0, 0, 0, 0)):
    """Planes of the translational paraboloid z = 8 − x²/a − y²/b along its edges y = −10 (u) and x = −15 (v):
    knot planes = tangent planes, inner planes = chord planes through consecutive knot lines (which are
    parallel, so the side condition holds exactly), tangents = cross sections through the knot lines
    (turned about them by ``tilt``, which keeps the condition)."""
    F = lambda x, y: 8 - x ** 2 / a - y ** 2 / b                                   # noqa: E731
    N = lambda x, y: np.array([2 * x / a, 2 * y / b, 1.0])                         # noqa: E731
    P = lambda x, y: np.array([x, y, F(x, y)])                                     # noqa: E731

    def chain(pts, ruling, section, tilt):
        planes, tangents = [], []
        for k, (x, y) in enumerate(pts):
            p, r = P(x, y), ruling(x, y)
            planes.append(np.concatenate([p, N(x, y)]))
            s = section / np.linalg.norm(section)
            n = np.cos(tilt[k]) * s + np.sin(tilt[k]) * np.cross(r / np.linalg.norm(r), s)
            tangents.append(np.concatenate([p, n]))
            if k + 1 < len(pts):
                q = P(*pts[k + 1])
                n = np.cross(q - p, r)
                planes.append(np.concatenate([p, n * np.sign(n[2])]))
        return planes, tangents

    y0, x0 = knots_v[0], knots_u[0]
    up, ut = chain([(x, y0) for x in knots_u], lambda x, y: np.array([0, 1, -2 * y / b]), np.array([1.0, 0, 0]), tilt_u)
    vp, vt = chain([(x0, y) for y in knots_v], lambda x, y: np.array([1, 0, -2 * x / a]), np.array([0, 1.0, 0]), tilt_v)
    return [p.tolist() for p in up], [p.tolist() for p in ut], [p.tolist() for p in vp], [p.tolist() for p in vt]


def assert_pp(grid, tol=1e-9):
    assert face_planarity(grid.face_corners).max() <= tol
    assert polyline_planarity(grid.rows()).max() <= tol and polyline_planarity(grid.cols()).max() <= tol
    assert plane_residual(grid.rows(), grid.support_u).max() <= tol
    assert plane_residual(grid.cols(), grid.support_w).max() <= tol
    q = quality(grid)
    assert q.flipped_edges == 0 and q.nonconvex_faces == 0


def _parallel(a, b):
    """Signed cosine between 4-vectors."""
    return float(a @ b / np.linalg.norm(a) / np.linalg.norm(b))


def test_reweighting_gives_tangent_continuous_spline_with_tangent_planes_at_knots():
    up, ut, _, _ = paraboloid_arrangement(tilt_u=(0.1, -0.2, 0.15, 0.0))
    g = plane_spline(up, ut, side_condition="strict")
    assert g.segments == 3 and g.cusps == []
    # control points are re-weighted copies of the user's planes (same planes)
    for k, ctrl in enumerate(g.inner):
        assert abs(abs(_parallel(ctrl, plane_from_entry(up[2 * k + 1], "x"))) - 1) <= 1e-12
    for k, knot in enumerate(g.knots):
        assert abs(abs(_parallel(knot, plane_from_entry(up[2 * k], "x"))) - 1) <= 1e-12
        # g' at the knot (from both sides) is the tangent plane tau_k: the support plane of the mesh there
        tau = plane_from_entry(ut[k], "x")
        left = g.derivative(np.array([k - 1e-12]))[0] if k > 0 else None
        right = g.derivative(np.array([k + 1e-12]))[0] if k < g.segments else None
        for d in (left, right):
            if d is not None:
                assert abs(abs(_parallel(d, tau)) - 1) <= 1e-9
        if left is not None and right is not None:               # G1: same direction, no cusp
            assert _parallel(left, right) >= 1 - 1e-9
    # each segment is the quadratic Bézier curve of its three control points (README correction)
    u = np.array([1.3])
    t = 0.3
    expect = (1 - t) ** 2 * g.knots[1] + 2 * t * (1 - t) * g.inner[1] + t ** 2 * g.knots[2]
    assert np.allclose(g(u)[0], expect)


@pytest.mark.parametrize("tilt", [(0, 0, 0, 0), (0.12, -0.2, 0.25, 0.05)], ids=["sections", "tilted-tangents"])
def test_plane_spline_mesh_is_pp_and_close_to_the_paraboloid(tilt):
    up, ut, vp, vt = paraboloid_arrangement(tilt_u=tilt, tilt_v=tilt[::-1])
    grid = build_construction("plane_splines", {"u_planes": up, "u_tangents": ut, "v_planes": vp, "v_tangents": vt,
                                                "side_condition": "strict", "faces_u": 20, "faces_v": 14})
    assert grid.shape == (21, 15)
    assert_pp(grid)
    x, y, z = np.moveaxis(grid.vertices, -1, 0)
    dev = np.abs(z - (8 - x ** 2 / 50 - y ** 2 / 30)).max()
    if tilt == (0, 0, 0, 0):
        assert dev < 0.05                       # within 5 cm of the paraboloid it was drawn from (30 m span)
        assert abs(x.min() + 15) < 0.1 and abs(x.max() - 15) < 0.1 and abs(y.min() + 10) < 0.1
    else:                                       # the support planes are real design handles
        assert dev > 0.1


def test_side_condition_strict_rejects_and_project_repairs():
    up, ut, vp, vt = paraboloid_arrangement()
    bad_t = [list(p) for p in ut]
    bad_t[1] = bad_t[1][:3] + [1.0, 0.0, 0.3]             # tau_1 turned out of the pencil of knot 1
    params = {"u_planes": up, "u_tangents": bad_t, "v_planes": vp, "v_tangents": vt, "faces_u": 8, "faces_v": 6}
    with pytest.raises(DesignError, match=r"geometry\.params\.u_tangents\[1\]: violates the side condition at knot 1"
                                          r".*gamma_01, gamma_1, gamma_12, tau_1 must share a line"):
        build_construction("plane_splines", dict(params, side_condition="strict"))
    bad_g = [list(p) for p in up]
    bad_g[4] = bad_g[4][:3] + [0.3, -0.5, 1.0]             # gamma_2 (knot plane) off the knot line
    with pytest.raises(DesignError, match=r"u_planes\[4\]: violates the side condition at knot 2"):
        build_construction("plane_splines", dict(params, u_planes=bad_g, u_tangents=ut, side_condition="strict"))
    grid = build_construction("plane_splines", dict(params, u_planes=bad_g))        # project (default)
    assert_pp(grid)
    # after projection all four planes of every interior knot share one line: rank 2 in R^4
    g = plane_spline(bad_g, bad_t)
    for i in range(1, g.segments):
        M = np.stack([g.inner[i - 1], g.knots[i], g.inner[i], g.tangents[i]])
        sv = np.linalg.svd(M / np.linalg.norm(M, axis=1, keepdims=True), compute_uv=False)
        assert sv[2] <= 1e-12 * sv[0]


def test_default_tangents_are_orthogonal_to_the_knot_planes():
    up, _, vp, _ = paraboloid_arrangement()
    g = plane_spline(up)
    for i in range(g.segments + 1):
        knot = g.knots[i][:3] / np.linalg.norm(g.knots[i][:3])
        tau = g.tangents[i][:3]
        assert abs(knot @ tau) <= 1e-12
    grid = build_construction("plane_splines", {"u_planes": up, "v_planes": vp, "faces_u": 9, "faces_v": 7})
    assert_pp(grid)


def test_cusp_is_reported_naming_the_knot():
    """Remark 3.3: tau_1 inside the arc gamma_01..gamma_1 (on gamma_1's side of the pair gamma_01, gamma_12)
    reverses the order of the control points on their line: a cusp at knot 1."""
    up, ut, vp, vt = paraboloid_arrangement()
    p, d = knot_line(plane_from_entry(up[1], "a"), plane_from_entry(up[3], "b"), "knot 1")
    n01 = plane_from_entry(up[1], "a")[:3]
    n1 = plane_from_entry(up[2], "a")[:3]
    n = n01 + n1
    n -= (n @ d) * d
    cusp_t = [list(t) for t in ut]
    cusp_t[1] = list(p) + list(n / np.linalg.norm(n))
    with pytest.warns(CuspWarning, match=r"plane spline u: cusp at knot 1 \(Remark 3\.3\)"):
        g = plane_spline(up, cusp_t, side_condition="strict")
    assert g.cusps == [1]
    left, right = g.derivative(np.array([1 - 1e-12, 1 + 1e-12]))
    assert _parallel(left, right) <= -1 + 1e-9                           # the derivative flips: a cusp
    with warnings.catch_warnings():
        warnings.simplefilter("error", CuspWarning)
        plane_spline(up, ut)                                              # the regular arrangement: no warning
    with pytest.warns(CuspWarning, match="knot 1"):
        grid = build_construction("plane_splines", {"u_planes": up, "u_tangents": cusp_t, "v_planes": vp,
                                                    "v_tangents": vt, "faces_u": 8, "faces_v": 6})
    assert grid.meta["cusps_u"] == [1]


def test_plane_spline_input_errors():
    up, ut, vp, vt = paraboloid_arrangement()
    base = {"u_planes": up, "v_planes": vp}
    with pytest.raises(DesignError, match=r"v_planes\[0\]: must be the same plane as u_planes\[0\]"):
        build_construction("plane_splines", dict(base, v_planes=[vp[1]] + vp[1:]))
    with pytest.raises(DesignError, match=r"u_planes: needs an odd number >= 3 of planes"):
        build_construction("plane_splines", dict(base, u_planes=up[:4]))
    bad = [list(p) for p in up]
    bad[2] = [1.0, 2.0, 3.0, 0.0, 0.0, 0.0]
    with pytest.raises(DesignError, match=r"u_planes\[2\]: degenerate plane: its normal vector is zero"):
        build_construction("plane_splines", dict(base, u_planes=bad))
    bad = [list(p) for p in up]
    bad[3] = bad[1]                                              # gamma_01 == gamma_12: knot 1 has no line
    with pytest.raises(DesignError, match=r"u_planes: knot 1 .*the planes are parallel"):
        build_construction("plane_splines", dict(base, u_planes=bad))
    with pytest.raises(DesignError, match=r"u_tangents: needs one tangent plane per knot: 4, got 3"):
        build_construction("plane_splines", dict(base, u_tangents=ut[:3]))
    with pytest.raises(DesignError, match=r"u_planes\[1\]: a plane needs 4 numbers"):
        build_construction("plane_splines", dict(base, u_planes=[up[0], [1.0, 2.0], up[2]]))


def test_mesh_from_python_api_matches_design_file():
    up, ut, vp, vt = paraboloid_arrangement(tilt_u=(0, 0.1, 0, 0))
    g = plane_spline(up, ut)
    h = plane_spline(vp, vt, g0=g.knots[0], name="v")
    a = plane_spline_mesh(g, h, 10, 7)
    b = build_construction("plane_splines", {"u_planes": up, "u_tangents": ut, "v_planes": vp, "v_tangents": vt,
                                             "faces_u": 10, "faces_v": 7})
    assert np.abs(a.vertices - b.vertices).max() <= 1e-12
