"""Glass panels: planarity check, inset by gap/2, exact flattening, ids, flags, congruence types."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import shared_file, smooth_face_image
from fabrication.panels import PanelParams, congruence_distance, make_panels, panel_types
from ppfab.errors import DesignError, FabricationError, NonPlanarPanelError
from ppfab.faceimage import pp_from_face_image
from ppfab.schema import parse_params


def pp_grid(m=6, n=5, seed=0):
    g, h = smooth_face_image(m, n, seed)
    return pp_from_face_image(g, h)


def inset_3d(corners: np.ndarray, planes_normal: np.ndarray, delta: float) -> np.ndarray:
    """Independent 3D construction: edge lines of the projected face moved inwards by delta in the
    face plane, consecutive lines intersected (closest points of two coplanar lines)."""
    c = corners - np.outer((corners - corners.mean(0)) @ planes_normal, planes_normal)
    out = []
    for k in range(4):
        a0, a1 = c[k - 1], c[k]          # edge k-1: c[k-1] -> c[k]
        b0, b1 = c[k], c[(k + 1) % 4]    # edge k:   c[k] -> c[k+1]
        da, db = (a1 - a0) / np.linalg.norm(a1 - a0), (b1 - b0) / np.linalg.norm(b1 - b0)
        na, nb = np.cross(planes_normal, da), np.cross(planes_normal, db)   # inward for CCW about n
        pa, pb = a0 + delta * na, b0 + delta * nb
        # solve pa + s da = pb + t db (least squares, exact for coplanar lines)
        M = np.stack([da, -db], axis=1)
        st = np.linalg.lstsq(M, pb - pa, rcond=None)[0]
        out.append(pa + st[0] * da)
    return np.array(out)


def shape_measures(poly: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    e = np.roll(poly, -1, axis=0) - poly
    lengths = np.linalg.norm(e, axis=1)
    ein = poly - np.roll(poly, 1, axis=0)
    cosang = np.einsum("ij,ij->i", -ein, e) / (np.linalg.norm(ein, axis=1) * lengths)
    return lengths, np.arccos(np.clip(cosang, -1, 1))


@pytest.mark.parametrize("outside,rotation", [("normal", "quarter"), ("reverse", "grain"), ("auto", "free"),
                                              ("normal", "free")])
def test_outline_is_the_face_inset_by_half_the_gap(outside, rotation):
    from shapely.geometry import Polygon

    grid = pp_grid()
    gap = 12.0
    panels = make_panels(grid, PanelParams(gap=gap, outside=outside, rotation=rotation), scale=4000.0)
    assert len(panels) == grid.n_faces
    corners = grid.face_corners.reshape(-1, 4, 3) * 4000.0
    for p in panels:
        f = p.face
        # the face plane's normal oriented by corner order
        n = np.cross(corners[f, 2] - corners[f, 0], corners[f, 3] - corners[f, 1])
        n /= np.linalg.norm(n)
        # face is planar: its inset in 3D, independently
        ref = inset_3d(corners[f], n, gap / 2)[p.corner_index]
        l3, a3 = shape_measures(ref)
        l2, a2 = shape_measures(p.outline)
        assert np.abs(l3 - l2).max() < 1e-6
        assert np.abs(a3 - a2).max() < 1e-6
        assert np.abs(p.outline_3d() - ref).max() < 1e-6          # the frame maps the flat outline back
        assert np.allclose(p.frame.to2d(p.outline_3d()), p.outline, atol=1e-9)
        F = np.stack([p.frame.ex, p.frame.ey, p.frame.normal])
        assert np.allclose(F @ F.T, np.eye(3), atol=1e-12)
        if rotation == "free":      # laid out in its minimum-area rectangle (shapely's, independently), long side on x
            w, h = np.ptp(p.outline, axis=0)
            assert p.outline.min(axis=0) == pytest.approx([0, 0], abs=1e-9) and w >= h - 1e-9
            assert w * h == pytest.approx(Polygon(p.outline).minimum_rotated_rectangle.area, rel=1e-9)
        else:                       # reference corner at the origin, reference edge along +x
            assert p.outline[0] == pytest.approx([0, 0]) and abs(p.outline[1, 1]) < 1e-9 and p.outline[1, 0] > 0
        x, y = p.outline.T
        assert 0.5 * (x @ np.roll(y, -1) - y @ np.roll(x, -1)) == pytest.approx(p.area_mm2)
        assert p.area_mm2 > 0
        if outside == "normal":
            assert p.frame.normal @ n > 0.999
        if outside == "reverse":
            assert p.frame.normal @ n < -0.999


def test_ids_faces_and_parts_list_fields():
    grid = pp_grid(4, 11)
    panels = make_panels(grid, PanelParams(), scale=3000.0)
    ij = [p.face_ij for p in panels]
    assert ij == [(i, j) for i in range(4) for j in range(11)]
    assert [p.face for p in panels] == list(range(44))
    assert panels[13].part_id == "P-U01-V02"
    fp = panels[13].flat_part()
    assert fp.kind == "panel" and fp.part_id == "P-U01-V02" and fp.type_id == panels[13].type_id
    assert (fp.meta["face"], fp.meta["face_i"], fp.meta["face_j"]) == (13, 1, 2)
    assert fp.meta["material"] == PanelParams().makeup
    w = panels[13].area_mm2 * 1e-6 * (0.016 * 2500 + 0.00152 * 1070)     # 8 HS / 1.52 PVB / 8 HS
    assert panels[13].weight_kg == pytest.approx(w)
    # the reference-corner mark lies inside the outline
    from shapely.geometry import LineString, Polygon
    assert Polygon(fp.outline).contains(LineString(fp.marks[0]))


def test_real_mesh_grid_ids_and_revolution_types():
    from ppfab.io import load_mesh

    mesh = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj"))
    panels = make_panels(mesh, PanelParams(gap=4.0, congruence_tolerance=0.5), scale=1000.0)
    assert len(panels) == len(mesh.faces)
    assert sorted(p.face for p in panels) == list(range(len(mesh.faces)))
    assert sorted(p.mesh_face for p in panels) == list(range(len(mesh.faces)))   # every file face used once
    for p in panels[:50]:   # corners are the input mesh's face corners
        assert set(map(tuple, np.round(p.corners_3d / 1000.0, 9))) == \
            set(map(tuple, np.round(mesh.vertices[mesh.faces[p.mesh_face]], 9)))
    assert max(p.deviation_mm for p in panels) < 1e-2
    types = panel_types(panels)
    # a surface of revolution: the panels of one ring are congruent, so at most one type per ring
    rows = {p.face_ij[0] for p in panels}
    assert len(types) <= len(rows)
    by_id = {p.part_id: p for p in panels}
    for members in types.values():
        a = by_id[members[0]].outline
        for m in members[1:]:
            assert congruence_distance(a, by_id[m].outline) <= 0.5 + 1e-9


def test_nonplanar_panels_stop_before_anything_is_written():
    from ppfab.io import load_mesh

    mesh = load_mesh(shared_file("compas_libigl__tubemesh.off"))
    with pytest.raises(NonPlanarPanelError) as err:
        make_panels(mesh, PanelParams(planarity_tolerance=1.0), scale=1000.0)
    e = err.value
    assert len(e.offenders) > 10 and all(o.value > 1.0 == o.limit and o.code == "planarity" for o in e.offenders)
    assert "mm" in str(e) and e.offenders[0].element.startswith("P-")


def test_collapsing_inset_is_an_error_naming_the_panel():
    grid = pp_grid(3, 3)
    with pytest.raises(FabricationError, match=r"collapses .*P-U\d\d-V\d\d"):
        make_panels(grid, PanelParams(gap=5000.0), scale=3000.0)


def test_processing_flags():
    grid = pp_grid(3, 4)
    panels = make_panels(grid, PanelParams(min_corner_angle_deg=89.9, min_size=[3000, 3000]), scale=3000.0)
    for p in panels:
        assert ("acute_corner" in p.flags) == (min(p.corner_angles_deg) < 89.9)
        assert "too_small" in p.flags
    big = make_panels(grid, PanelParams(max_size=[300, 300]), scale=3000.0)
    assert all(("too_large" in p.flags) == (p.min_rect[0] > 300) for p in big)


def test_rigid_motion_invariance():
    grid = pp_grid(6, 5, seed=0)
    rng = np.random.default_rng(7)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    moved = grid.with_vertices(grid.vertices @ q.T + rng.normal(size=3))
    a = make_panels(grid, PanelParams(outside="normal"), scale=2500.0)
    b = make_panels(moved, PanelParams(outside="normal"), scale=2500.0)
    assert [p.type_id for p in a] == [p.type_id for p in b]
    assert max(np.abs(p.outline - r.outline).max() for p, r in zip(a, b)) < 1e-6


def test_params_validation():
    assert parse_params(PanelParams, {"gap": 8, "min_size": [100, 200]}, "panels").min_size == [100.0, 200.0]
    with pytest.raises(DesignError, match="panels.gap"):
        parse_params(PanelParams, {"gap": -1}, "panels")
    with pytest.raises(DesignError, match="panels.outside"):
        parse_params(PanelParams, {"outside": "up"}, "panels")
    with pytest.raises(DesignError, match="min_size"):
        parse_params(PanelParams, {"min_size": [7000, 7000]}, "panels")
