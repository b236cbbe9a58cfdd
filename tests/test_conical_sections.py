"""Conical PP meshes designed by their principal planar sections (§4.1.2, eqs. 14–15)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from ppfab.conical.cones import conical_quality
from ppfab.constructions import build_construction
from ppfab.constructions.conical_pp import FRAMES, Series, appendix_surface, normal_field
from ppfab.constructions.conical_sections import polar_radius, sections_grid
from ppfab.errors import DesignError
from ppfab.metrics import quality
from ppfab.curves import ConvexSection, PlanarCurve, support_values

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "conical_sections.toml"
TOL = 1e-9

X = np.linspace(-15, 15, 9)
ARCH_A = np.c_[X, 8 - X ** 2 / 30]
Y = np.linspace(-10, 10, 7)
ARCH_B = np.c_[Y, 8 - Y ** 2 / 20]
HANG_B = np.c_[Y, 8 + 2.5 * (Y / 10) ** 2 + 0.5 * (Y / 10) ** 4]


def _matched_bspline_b() -> np.ndarray:
    """Control points of a hanging section B whose B-spline crest has the height of section A's."""
    za = PlanarCurve.from_control_points(ARCH_A)(np.array([0.5]))[0, 1]
    zb = PlanarCurve.from_control_points(HANG_B)(np.array([0.5]))[0, 1]
    return HANG_B + [0.0, za - zb]


SETS = {
    "case1-dome-arclength": dict(section_a=ARCH_A, section_b=ARCH_B, case="case1", d=3.0, sampling="arclength"),
    "case1-saddle-angle": dict(section_a=ARCH_A, section_b=HANG_B, case="case1", d=6.0, sampling="angle"),
    "case2-dome-angle": dict(section_a=ARCH_A, section_b=ARCH_B, case="case2", sampling="angle"),
    "case2-saddle-bspline": dict(section_a=ARCH_A, section_b=_matched_bspline_b(), case="case2", curve="bspline"),
}


@pytest.mark.parametrize("name", list(SETS), ids=list(SETS))
def test_sections_give_conical_pp_meshes(name):
    grid = sections_grid(faces_a=16, faces_b=11, **SETS[name])
    q = conical_quality(grid)
    assert q.delta_f_max <= TOL
    assert q.delta_p_rows_max <= TOL and q.delta_p_cols_max <= TOL
    assert q.support_u_max <= TOL and q.support_w_max <= TOL
    assert q.angle_max <= TOL and q.concyclic_max <= TOL
    qq = quality(grid)
    assert qq.flipped_edges == 0 and qq.nonconvex_faces == 0
    z = 8.0 if SETS[name].get("curve") != "bspline" else PlanarCurve.from_control_points(ARCH_A)(np.array([0.5]))[0, 1]
    assert np.allclose(grid.meta["crest"], [0.0, 0.0, z], atol=1e-9)


def test_polar_radii_agree_with_the_paper_forms():
    d = 2.7
    e2 = d * d - 1
    phi = np.linspace(-1.4, 4.5, 50)
    assert np.allclose(polar_radius("case1", "a", phi, d), e2 * (np.sin(phi) + d) / (e2 + np.cos(phi) ** 2))
    psi = np.linspace(-0.9 * np.arccos(1 / d), 0.9 * np.arccos(1 / d), 40)
    assert np.allclose(polar_radius("case1", "b", psi, d),
                       e2 * (d * np.cos(psi) + 1) / (e2 * np.cos(psi) ** 2 - np.sin(psi) ** 2))
    phi2 = np.linspace(-1.5, 1.4, 30)
    assert np.allclose(polar_radius("case2", "a", phi2), (np.sin(phi2) + 1) / np.cos(phi2) ** 2)


def test_reparametrised_normal_image_is_eq_11():
    """ñ(φ(u), ψ(v)) = n(u, v), with n(u, 0) = (e sin u, d cos u + 1, 0) the ellipse (README correction)."""
    d = 2.2
    e = np.sqrt(d * d - 1)
    u, v = np.meshgrid(np.linspace(-2.5, 2.5, 11), np.linspace(-1.2, 1.2, 9), indexing="ij")
    ell = np.stack([e * np.sin(u), d * np.cos(u) + 1], -1)
    phi = np.arctan2(ell[..., 1], ell[..., 0])
    assert np.allclose(np.linalg.norm(ell, axis=-1), polar_radius("case1", "a", phi, d))
    hyp = np.stack([d + np.cosh(v), e * np.sinh(v)], -1)
    psi = np.arctan2(hyp[..., 1], hyp[..., 0])
    r, s = polar_radius("case1", "a", phi, d), polar_radius("case1", "b", psi, d)
    n_tilde = np.stack([r * np.cos(phi), r * np.sin(phi) + s * np.cos(psi) - d - 1, s * np.sin(psi)], -1)
    n, _, _ = normal_field("case1", u, v, d)
    assert np.allclose(n_tilde, n, atol=1e-12)


def test_sections_of_an_eq_11_surface_give_back_its_face_image():
    """Take the principal sections x(u, 0), x(0, v) of the Appendix surface, design with them, and recover
    the face planes of eq. (11) at the corresponding parameters (up to the spline fit of the sections)."""
    d = 2.5
    e = np.sqrt(d * d - 1)
    g, h = Series(cos=[-10.0], poly=[0, 0.5, 0.3]), Series(cosh=[-25.0], poly=[0.5, 0, 1.0])
    ud, vd = np.linspace(-0.7, 0.7, 400), np.linspace(-0.5, 0.5, 400)
    xa = appendix_surface("case1", g, h, ud, 0 * ud, d)
    xb = appendix_surface("case1", g, h, 0 * vd, vd, d)
    assert np.ptp(xa[:, 2]) < 1e-12 and np.ptp(xb[:, 0]) < 1e-12        # planar principal sections
    A = np.c_[xa[:, 0], xa[:, 1]]                  # output frame: x = x1, z = x2
    B = np.c_[-xb[:, 2], xb[:, 1]]                 # y = −x3
    for sampling in ("arclength", "angle"):
        grid = sections_grid(A, B, 10, 8, case="case1", d=d, sampling=sampling)
        phi, psi = grid.meta["phi"][1:-1], grid.meta["psi"][1:-1]
        r, s = polar_radius("case1", "a", phi, d), polar_radius("case1", "b", psi, d)
        u = np.arctan2(r * np.cos(phi) / e, (r * np.sin(phi) - 1) / d)
        v = np.arcsinh(s * np.sin(psi) / e)
        n, _, _ = normal_field("case1", u[:, None], v[None, :], d)
        f = np.concatenate([n, (g(u)[:, None] + h(v)[None, :])[..., None]], -1)
        F = grid.face_image.copy()
        F[..., :3] = F[..., :3] @ FRAMES["case1"]                        # back to the paper's frame
        assert np.abs(F - f).max() <= 1e-8 * np.abs(f).max()


def test_cylinders_over_the_sections_touch_the_faces_through_the_crest():
    """At ψ = 0 the planes are x1 cos φ + x2 sin φ + g̃(φ) = 0 (eq. 14): tangent lines of section A."""
    grid = sections_grid(ARCH_A, ARCH_B, 16, 10, case="case1", d=3.0)
    phi, ga = grid.meta["phi"], grid.meta["support_a"]
    sec = PlanarCurve.from_points(ARCH_A)
    t = np.linspace(sec.t0, sec.t1, 20001)
    pts = sec(t)
    # each line x cos φ + z sin φ + g̃ = 0 touches the arch: max over the curve of −(p·n) equals g̃
    n = np.stack([np.cos(phi), np.sin(phi)], -1)
    assert np.allclose((-(pts @ n.T)).min(axis=0)[1:-1], ga[1:-1], atol=1e-6)    # ghosts touch the extension


@pytest.mark.parametrize("sampling", ["arclength", "angle"])
def test_boundary_vertices_reach_the_section_ends(sampling):
    grid = sections_grid(ARCH_A, ARCH_B, 20, 14, case="case1", d=3.0, sampling=sampling)
    x = grid.vertices[..., 0]
    assert abs(x.min() + 15) < 0.5 and abs(x.max() - 15) < 0.5


def test_non_convex_section_is_rejected():
    s_curve = np.c_[X, 8 - X ** 2 / 30 + 0.02 * X ** 3 / 15]
    with pytest.raises(DesignError, match=r"section_a: is not strictly convex"):
        sections_grid(s_curve, ARCH_B, 10, 8, case="case1", d=3.0)


def test_sections_must_meet_at_the_crest():
    with pytest.raises(DesignError, match=r"section_b: the sections do not meet.*z = 8.*z = 8.5"):
        sections_grid(ARCH_A, ARCH_B + [0.0, 0.5], 10, 8, case="case1", d=3.0)


def test_section_without_horizontal_point_is_rejected():
    ramp = np.c_[X, 8 + 0.5 * X - X ** 2 / 200]
    with pytest.raises(DesignError, match="no point where its normal is the crest direction"):
        sections_grid(ramp, ARCH_B, 10, 8, case="case1", d=3.0)


def test_case1_limits_the_turn_of_section_b():
    with pytest.raises(DesignError, match=r"section_b: turns its normal by .* at most 48.19°"):
        sections_grid(ARCH_A, ARCH_B, 10, 8, case="case1", d=1.5)       # arccos(1/1.5) = 48.19°
    with pytest.raises(DesignError, match="d > 1"):
        build_construction("conical_sections", {"section_a": ARCH_A.tolist(), "section_b": ARCH_B.tolist(), "d": 1.0})


def test_support_values_of_a_circle():
    t = np.linspace(0, 2 * np.pi, 30, endpoint=False)
    circle = PlanarCurve.from_points(np.c_[1 + 3 * np.cos(t), -2 + 3 * np.sin(t)], closed=True)
    w = np.stack([np.cos(np.linspace(0, 6, 13)), np.sin(np.linspace(0, 6, 13))], -1)
    h, _ = support_values(circle, w)
    assert np.allclose(h, w @ [1.0, -2.0] + 3.0, atol=1e-4)               # spline through 30 points
    arch = PlanarCurve.from_points(ARCH_A)
    sec = ConvexSection.prepare(arch, np.pi / 2)
    assert abs(sec.crest_t - 0.5 * (arch.t0 + arch.t1)) < 1e-9                  # symmetric arch: crest in the middle
    assert np.allclose(sec.crest_point, [0.0, 8.0], atol=1e-9)


def test_example_builds_conical_pp():
    doc = tomllib.loads(EXAMPLE.read_text())
    grid = build_construction(doc["geometry"]["method"], doc["geometry"].get("params"))
    q = conical_quality(grid)
    assert max(q.delta_f_max, q.delta_p_rows_max, q.delta_p_cols_max, q.angle_max, q.concyclic_max) <= TOL
    edges = np.concatenate([np.linalg.norm(grid.edges_u(), axis=-1).ravel(),
                            np.linalg.norm(grid.edges_v(), axis=-1).ravel()])
    assert 1.0 < edges.min() and edges.max() < 2.0
