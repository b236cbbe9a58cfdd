"""Conical PP meshes from the explicit face images of eqs. (11)–(13) and the Appendix surface."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from ppfab.conical.cones import concyclic_residual, cone_axes, conical_quality, offset_faces, vertex_planes
from ppfab.constructions import build_construction
from ppfab.constructions.conical_pp import (FRAMES, Series, appendix_surface, conical_pp_grid, envelope,
                                            normal_field)
from ppfab.errors import DesignError, FoldError, GeometryError
from ppfab.metrics import quality

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
TOL = 1e-9

# two parameter sets per case: (g, h, u, v, d)
CASES = {
    "case1-sphere-like": ("case1", Series(cos=[-10.0]), Series(cosh=[-20.0], poly=[0, 0, 1.0]),
                          np.linspace(-0.6, 0.6, 14), np.linspace(-0.4, 0.4, 10), 2.0),
    "case1-wavy": ("case1", Series(cos=[-8.0, 0.4], sin=[0.3]), Series(cosh=[-30.0], sinh=[0.5], poly=[0, 0, 2.0]),
                   np.linspace(-0.9, 0.7, 17), np.linspace(-0.3, 0.5, 9), 3.5),
    "rotational-dome": ("rotational", Series(), Series(cosh=[-12.0], poly=[0, 0, 1.5]),
                        np.linspace(-1.0, 1.0, 16), np.linspace(0.2, 1.3, 9), 2.0),
    "rotational-twisted": ("rotational", Series(sin=[0.8], cos=[0.0, 0.3]), Series(cosh=[-9.0], poly=[0.5, 0.2]),
                           np.linspace(-0.8, 1.1, 12), np.linspace(-0.5, 0.9, 11), 2.0),
    "case2-sphere-like": ("case2", Series(poly=[-7.5, 0, -15.0]), Series(poly=[-7.5, 0, -15.0]),
                          np.linspace(-0.27, 0.27, 14), np.linspace(-0.17, 0.17, 10), 2.0),
    "case2-asymmetric": ("case2", Series(poly=[-5.0, 0.3, -8.0, 2.0]), Series(poly=[-6.0, -0.2, -9.0, 0, -8.0]),
                         np.linspace(-0.3, 0.35, 13), np.linspace(-0.25, 0.2, 11), 2.0),
}


def build(name, **kw):
    case, g, h, u, v, d = CASES[name]
    return conical_pp_grid(g, h, u, v, case=case, d=d, **kw)


@pytest.mark.parametrize("name", list(CASES), ids=list(CASES))
def test_conical_pp_is_planar_pp_and_conical(name):
    grid = build(name)
    q = conical_quality(grid)
    assert q.delta_f_max <= TOL
    assert q.delta_p_rows_max <= TOL and q.delta_p_cols_max <= TOL
    assert q.support_u_max <= TOL and q.support_w_max <= TOL          # rows in U_i, columns in W_j
    assert q.angle_max <= TOL                                          # α1 + α3 = α2 + α4
    assert q.concyclic_max <= TOL                                      # unit normals concyclic
    qq = quality(grid)
    assert qq.flipped_edges == 0 and qq.nonconvex_faces == 0


@pytest.mark.parametrize("case", ["case1", "rotational", "case2"])
def test_normal_length_is_a_sum_of_functions(case):
    """|n(u, v)| = a(u) + b(v) (d cosh v + cos u, cosh v, (u² + v² + 1)/2): the reason for concyclic normals."""
    u, v = np.meshgrid(np.linspace(-1, 1, 7), np.linspace(-1, 1, 5), indexing="ij")
    n, _, _ = normal_field(case, u, v, 2.5)
    expected = {"case1": 2.5 * np.cosh(v) + np.cos(u), "rotational": np.cosh(v),
                "case2": 0.5 * (u * u + v * v + 1)}[case]
    assert np.allclose(np.linalg.norm(n, axis=-1), expected, rtol=1e-13)


def test_any_sampling_works():
    rng = np.random.default_rng(7)
    u = np.sort(rng.uniform(-0.7, 0.7, 12))
    v = np.sort(rng.uniform(-0.4, 0.4, 9))
    grid = conical_pp_grid(Series(cos=[-10.0]), Series(cosh=[-20.0]), u, v, case="case1", d=2.0)
    q = conical_quality(grid)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.delta_p_cols_max, q.angle_max) <= TOL


@pytest.mark.parametrize("case", ["case1", "rotational"])
def test_closed_meshes(case):
    g, h = (Series(cos=[-10.0, 0.5]), Series(cosh=[-20.0])) if case == "case1" else \
        (Series(), Series(cosh=[-12.0], poly=[0, 0, 1.5]))
    v = np.linspace(-0.3, 0.3, 7) if case == "case1" else np.linspace(0.2, 1.2, 7)
    grid = conical_pp_grid(g, h, np.zeros(24), v, case=case, d=3.0, closed=True)
    assert grid.closed and grid.shape == (8, 24)
    q = conical_quality(grid)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.delta_p_cols_max, q.angle_max, q.concyclic_max) <= TOL
    assert quality(grid).flipped_edges == 0


def test_closed_needs_periodic_g():
    with pytest.raises(GeometryError, match="periodic"):
        conical_pp_grid(Series(poly=[0, 1.0]), Series(cosh=[-20.0]), np.zeros(12), np.linspace(-.2, .2, 5),
                        case="case1", closed=True)


def test_series_derivative_matches_finite_differences():
    s = Series(poly=[1.0, -2.0, 0.5, 0.1], cos=[0.3, -0.2], sin=[0.4], cosh=[0.7], sinh=[0.0, 0.2])
    t = np.linspace(-1.2, 1.3, 9)
    h = 1e-6
    assert np.allclose(s.derivative(t), (s(t + h) - s(t - h)) / (2 * h), atol=1e-8)


@pytest.mark.parametrize("case", ["case1", "case2"])
def test_appendix_closed_form_is_the_envelope(case):
    g, h = Series(cos=[-10.0], poly=[0, 0.5, 0.3]), Series(cosh=[-20.0], poly=[0.5, 0, 1.0, 0.2])
    u, v = np.meshgrid(np.linspace(-0.6, 0.6, 9), np.linspace(-0.4, 0.4, 7), indexing="ij")
    x = appendix_surface(case, g, h, u, v, 2.0)
    assert np.allclose(x, envelope(case, g, h, u, v, 2.0), atol=1e-10)
    # and it lies on the tangent planes f, f_u, f_v (eq. 9)
    n, nu, nv = normal_field(case, u, v, 2.0)
    assert np.abs(np.einsum("...i,...i->...", n, x) + g(u) + h(v)).max() < 1e-10
    assert np.abs(np.einsum("...i,...i->...", nu, x) + g.derivative(u)).max() < 1e-10
    assert np.abs(np.einsum("...i,...i->...", nv, x) + h.derivative(v)).max() < 1e-10


@pytest.mark.parametrize("case", ["case1", "rotational", "case2"])
def test_mesh_converges_to_the_appendix_surface(case):
    """Interior vertices approach x(ū, v̄) at the midpoints of the face parameters at second order."""
    g, h = (Series(cos=[-10.0], poly=[0, 0.5]), Series(cosh=[-20.0], poly=[0, 0, 1.0])) if case != "case2" else \
        (Series(poly=[-5, 0.3, 1]), Series(poly=[-5, 0, 0.5, 0.2]))
    errors = []
    for m in (8, 16, 32):
        grid = conical_pp_grid(g, h, np.linspace(-.6, .6, m), np.linspace(-.4, .4, m), case=case, d=2.0,
                               frame="paper")
        u, v = grid.meta["u"], grid.meta["v"]
        um, vm = 0.5 * (u[1:] + u[:-1]), 0.5 * (v[1:] + v[:-1])
        x = envelope(case, g, h, um[:, None], vm[None, :], 2.0)
        errors.append(np.abs(grid.vertices[1:-1, 1:-1] - x).max())
    assert errors[2] < errors[1] < errors[0]
    assert errors[0] / errors[1] > 3.5 and errors[1] / errors[2] > 3.5


def test_z_up_frame_turns_the_central_normal_up():
    grid = build("case1-sphere-like", frame="z_up")
    m, n = grid.face_shape
    normal = grid.face_planes[m // 2, n // 2, :3]
    assert normal[2] > 0.99
    assert np.allclose(FRAMES["case1"] @ FRAMES["case1"].T, np.eye(3))


def test_faces_are_oriented_like_their_planes_and_axes_point_inward():
    grid = build("case1-wavy")
    corner = grid.face_planes[..., :3]
    image = grid.face_image[..., :3] / np.linalg.norm(grid.face_image[..., :3], axis=-1, keepdims=True)
    assert np.all(np.einsum("...i,...i->...", corner, image) > 0.99)
    mean = corner.mean(axis=(0, 1))
    assert np.all(grid.axes @ mean < 0)


def test_cone_axes_make_equal_angles_with_the_four_faces():
    grid = build("case2-asymmetric")
    axes, cos = cone_axes(grid, inward=False)
    n = vertex_planes(grid)[..., :3]
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    angles = np.einsum("...ki,...i->...k", n, axes)
    assert np.abs(angles - cos[..., None]).max() <= TOL
    assert concyclic_residual(grid).max() <= TOL


@pytest.mark.parametrize("name", ["case1-wavy", "rotational-dome", "case2-asymmetric"])
def test_offset_at_constant_face_distance(name):
    grid = build(name)
    off = offset_faces(grid, 0.35)
    # every face plane moved by exactly 0.35 along its normal
    n = grid.face_planes[..., :3]
    d0 = np.einsum("...i,...i->...", n, grid.face_corners.mean(axis=-2))
    d1 = np.einsum("...i,...i->...", n, off.face_corners.mean(axis=-2))
    assert np.allclose(d1 - d0, 0.35, atol=1e-9)
    q = conical_quality(off)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.delta_p_cols_max, q.angle_max) <= TOL


def test_case1_needs_d_above_one():
    with pytest.raises(DesignError, match=r"geometry\.params\.d: case1 needs d > 1"):
        build_construction("conical_pp", {"case": "case1", "d": 0.8, "g": {"cos": [-10.0]}})
    with pytest.raises(GeometryError, match="d > 1"):
        conical_pp_grid(Series(), Series(), np.linspace(0, 1, 3), np.linspace(0, 1, 3), case="case1", d=1.0)


def test_bad_sampling_and_keys_are_named():
    with pytest.raises(GeometryError, match="strictly monotone"):
        conical_pp_grid(Series(), Series(cosh=[-2.0]), np.array([0.0, 0.2, 0.1]), np.linspace(0, .2, 3))
    with pytest.raises(DesignError, match=r"geometry\.params\.g\.cosine: unknown key .*valid keys: cos, cosh"):
        build_construction("conical_pp", {"g": {"cosine": [1.0]}})
    with pytest.raises(DesignError, match="geometry.params.case"):
        build_construction("conical_pp", {"case": "case3"})


def test_fold_is_reported_with_the_valid_range():
    g, h = Series(), Series(poly=[0, 0, -6.0, 0, 2.0])
    v = np.linspace(-0.2, 1.2, 10)
    with pytest.raises(FoldError) as exc:
        conical_pp_grid(g, h, np.zeros(40), v, case="rotational", closed=True)
    msg = str(exc.value)
    assert "folds over" in msg and "is flipped" in msg and exc.value.element.startswith("face (")
    lo, hi = (float(x) for x in re.search(r"v in \[([-\d.e]+), ([-\d.e]+)\]", msg).groups())
    ok = v[(v >= lo - 1e-9) & (v <= hi + 1e-9)]
    grid = conical_pp_grid(g, h, np.zeros(40), ok, case="rotational", closed=True)   # the valid range builds
    assert quality(grid).flipped_edges == 0


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("conical_pp_*.toml")), ids=lambda p: p.stem)
def test_examples_build_conical_pp(path):
    doc = tomllib.loads(path.read_text())
    assert doc["geometry"]["method"] == "conical_pp" and doc["geometry"]["scale"] == 1000.0
    grid = build_construction(doc["geometry"]["method"], doc["geometry"].get("params"))
    q = conical_quality(grid)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.delta_p_cols_max, q.angle_max, q.concyclic_max) <= TOL
    edges = np.concatenate([np.linalg.norm(grid.edges_u(), axis=-1).ravel(),
                            np.linalg.norm(grid.edges_v(), axis=-1).ravel()])
    assert 0.5 < edges.min() and edges.max() < 2.5                    # architectural panels, metres
    extent = np.ptp(grid.vertices.reshape(-1, 3), axis=0)
    assert 15.0 < extent[:2].max() < 40.0
