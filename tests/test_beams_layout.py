"""Beam plates, joints, checks and flat parts (no CAD kernel involved)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from conftest import shared_file
from shapely.geometry import LineString, Point, Polygon

from fabrication.beams import BeamParams, build_beams, slot_width
from fabrication.beams.flat import congruent_outlines
from fabrication.beams.samples import sample_conical_grid, sample_p_grid, sample_pp_grid
from ppfab import planes as pl
from ppfab.errors import DesignError, FabricationError
from ppfab.io import load_mesh
from ppfab.schema import parse_params
from ppfab.transforms.similarity import transform
from ppfab.support.p import support_p
from ppfab.support.pp import support_pp
from ppfab.support.select import support_structure


@pytest.fixture(scope="module")
def pp():
    s = support_pp(sample_pp_grid(5, 7))
    return s, build_beams(s, BeamParams(max_length=0))


def _line_distance(x, p, d):
    """Distance of points ``x (k, 3)`` from the line ``p + t d``."""
    r = np.asarray(x) - p
    return np.linalg.norm(r - np.outer(r @ d, d), axis=1)


def test_plates_lie_in_their_support_planes_with_top_and_bottom_edges(pp):
    s, bs = pp
    v, a = s.vertices, s.axes
    assert len(bs.plates) == sum(s.mesh.grid.shape)          # one plate per row and column
    for p in bs.plates:
        f = p.frame
        assert np.allclose(np.c_[f.ex, f.ey, f.normal].T @ np.c_[f.ex, f.ey, f.normal], np.eye(3), atol=1e-14)
        plane = s.polyline_planes[p.polyline]
        assert np.abs(pl.signed_distance(plane, f.to3d(p.outline))).max() < 1e-8
        top = f.to3d(p.top[p.chain])
        bottom = f.to3d(p.bottom[p.chain])
        assert np.abs(top - v[p.nodes]).max() < 1e-8                                  # top edge = polyline
        assert np.abs(bottom - (v[p.nodes] + p.depth * a[p.nodes])).max() < 1e-8      # moved along the axes
        assert p.area > 0 and Polygon(p.outline).is_valid


def test_halflap_slots_share_the_node_axis(pp):
    s, bs = pp
    prm = bs.params
    m1, n1 = s.mesh.grid.shape
    halflaps = [j for j in bs.joints if j.kind == "halflap"]
    assert len(halflaps) == (m1 - 2) * (n1 - 2)            # every interior node
    for j in halflaps:
        v, a = s.vertices[j.vertex], s.axes[j.vertex]
        slots = [(bs.by_id[pid], sl) for pid in j.parts for sl in bs.by_id[pid].slots if sl.node == j.vertex]
        assert len(slots) == 2
        (pa, sa), (pb, sb) = sorted(slots, key=lambda t: t[0].family)
        assert sa.from_top and not sb.from_top and pa.family == 0 and pb.family == 1
        cos = abs(pa.plane[:3] @ pb.plane[:3])
        assert sa.width == pytest.approx(prm.slot_thickness * (1 + cos) / np.sqrt(1 - cos * cos) + prm.fit, abs=1e-12)
        for p, sl in ((pa, sa), (pb, sb)):
            pts = p.frame.to3d(np.array([sl.origin, sl.origin + sl.length * sl.direction]))
            assert _line_distance(pts, v, a).max() < 1e-8
            # the closed end of each slot is the axis point slot_play past half depth from its edge
            at = 0.5 * prm.depth + (prm.slot_play if sl.from_top else -prm.slot_play)
            assert np.abs(p.frame.to3d(sl.end_center) - (v + at * a)).max() < 1e-8
            poly = Polygon(p.outline)
            inside = sl.end_center - 1.0 * sl.direction if sl.from_top else sl.end_center + 1.0 * sl.direction
            beyond = sl.end_center + 1.0 * sl.direction if sl.from_top else sl.end_center - 1.0 * sl.direction
            assert not poly.contains(Point(inside)) and poly.contains(Point(beyond))


def test_right_angle_slot_is_thickness_plus_clearance():
    s = support_pp(sample_pp_grid(3, 4, bend=0.0, tilt=0.0))
    bs = build_beams(s, BeamParams(thickness=15.0, clearance=0.5, max_length=0))
    widths = {sl.width for p in bs.plates for sl in p.slots}
    assert len(widths) == 1 and widths.pop() == pytest.approx(15.5, abs=1e-9)
    assert slot_width(15.0, np.cos(np.radians(60)), 0.0) == pytest.approx(15.0 / np.tan(np.radians(30)))


def _check_ends_clear(bs, s):
    """Every end cut sits at its set-back; its corners clear every other plate at the node by
    exactly half the clearance (times the sine of the angle) — the set-back formula is tight."""
    prm = bs.params
    t, cl = prm.slot_thickness, prm.fit          # the thickest plate EN 10029 allows, and its fit
    checked = 0
    for j in bs.joints:
        for pid, c in j.trims:
            p = bs.by_id[pid]
            T, sdir, m = p.node_top(j.vertex), p.node_axis(j.vertex), p.body_direction(j.vertex)
            rel = p.outline - T
            near = np.abs(rel @ sdir) < 2 * prm.depth
            beta = rel[near] @ m
            assert beta.min() == pytest.approx(c, abs=1e-7)
            corners2 = p.outline[near][np.abs(beta - c) < 1e-7]
            c3 = p.frame.to3d(corners2)
            faces = np.concatenate([c3 + 0.5 * t * p.frame.normal, c3 - 0.5 * t * p.frame.normal])
            for other, role in zip(j.parts, j.roles):
                if other == pid or role != "through":
                    continue
                q = bs.by_id[other]
                dist = faces @ q.plane[:3] + q.plane[3]
                sin = np.sqrt(1 - (p.plane[:3] @ q.plane[:3]) ** 2)
                assert np.all(np.sign(dist) == np.sign(dist[0]))
                assert np.abs(dist).min() == pytest.approx(0.5 * t + 0.5 * cl * sin, abs=1e-7)
                checked += 1
    return checked


def test_butt_ends_clear_the_plates_they_meet(pp):
    s, bs = pp
    m1, n1 = s.mesh.grid.shape
    # boundary nodes except corners: one plate runs through, the other ends there
    assert _check_ends_clear(bs, s) == 2 * (m1 - 2) + 2 * (n1 - 2)
    for j in bs.joints:
        if j.roles == ("end", "end"):           # corners: both stop short of the bisector
            (pa, ca), (pb, cb) = j.trims
            ma = bs.by_id[pa].frame.vec3d(bs.by_id[pa].body_direction(j.vertex))
            mb = bs.by_id[pb].frame.vec3d(bs.by_id[pb].body_direction(j.vertex))
            phi = np.arccos(np.clip(ma @ mb, -1, 1))
            assert ca == pytest.approx(0.5 * bs.params.slot_thickness / np.tan(phi / 2) + 0.5 * bs.params.fit)


def test_segmented_joints_on_a_p_mesh():
    g = sample_p_grid(6, 8)
    s = support_p(g, "rows")
    bs = build_beams(s, BeamParams(joint="segmented", max_length=0))
    m1, n1 = g.shape
    rows = [p for p in bs.plates if p.family == 0]
    cols = [p for p in bs.plates if p.family == 1]
    assert sorted(p.part_id for p in rows) == [f"B-U{i:02d}" for i in range(m1)]
    assert len(cols) == n1 * (m1 - 1) and all(len(p.nodes) == 2 for p in cols)
    assert "B-W03-S02" in bs.by_id and not any(p.slots for p in bs.plates)
    assert all(len(p.trims) == 2 for p in cols + rows)     # rows end at the boundary columns
    # each segment lies in the support plane of its edge, which contains both end axes
    for p in cols:
        a3 = p.frame.to3d(p.top[p.chain])
        assert np.abs(a3 - s.vertices[p.nodes]).max() < 1e-7
        assert np.abs(s.axes[p.nodes] @ p.plane[:3]).max() < 1e-9
    assert _check_ends_clear(bs, s) == 2 * (n1 - 2) * (m1 - 1)      # rows run through all but the boundary columns
    with pytest.raises(FabricationError, match=r"B-W\d\d: its vertices lie up to .* off the beam plane.*half-lap"):
        build_beams(s, BeamParams(joint="halflap"))


def test_depth_beyond_the_crossing_of_axes_is_reported():
    s = support_pp(sample_pp_grid(4, 5, tilt=3.0))
    prm = BeamParams(depth=60000.0, max_length=0, min_segment=0)
    bs = build_beams(s, prm, strict=False)
    found = [d for d in bs.report.defects if d.code == "axis_crossing"]
    assert found
    for d in found:
        p = bs.by_id[d.element]
        k = int(re.search(r"ends of edge (\d+) ", d.message).group(1))
        va, vb = s.vertices[p.nodes[k]], s.vertices[p.nodes[k + 1]]
        aa, ab = s.axes[p.nodes[k]], s.axes[p.nodes[k + 1]]
        st = np.linalg.lstsq(np.c_[aa, -ab], vb - va, rcond=None)[0]   # the two axes meet (torsion 0)
        assert np.linalg.norm(va + st[0] * aa - vb - st[1] * ab) < 1e-6
        assert d.value == pytest.approx(st.min(), rel=1e-9) and d.value < prm.depth
        assert d.limit == prm.depth
    with pytest.raises(FabricationError, match=rf"{found[0].element}: the node axes at the ends of edge \d+ cross"):
        build_beams(s, prm)


def test_small_angles_and_short_segments_are_reported_by_part_id(pp):
    s, _ = pp
    bs = build_beams(s, BeamParams(min_angle_deg=89.0, min_segment=1300.0, max_length=0), strict=False)
    angles = [d for d in bs.report.defects if d.code == "small_angle"]
    assert angles
    for d in angles:
        a, b = d.message.split(" meet ")[0].split(" and ")
        pa, pb = bs.by_id[a], bs.by_id[b]
        expect = np.degrees(pl.angle_between(s.polyline_planes[pa.polyline], s.polyline_planes[pb.polyline]))
        assert d.value == pytest.approx(expect, abs=1e-9) and d.value < 89
    short = [d for d in bs.report.defects if d.code == "short_segment" and " of its top edge is " in d.message]
    edges = np.linalg.norm(s.vertices[s.edges[:, 1]] - s.vertices[s.edges[:, 0]], axis=1)
    assert len(short) == int((edges < 1300).sum())
    for d in short:
        p = bs.by_id[d.element]
        k = int(re.search(r": edge (\d+) of its top edge", d.message).group(1))
        assert d.value == pytest.approx(np.linalg.norm(s.vertices[p.nodes[k + 1]] - s.vertices[p.nodes[k]]), abs=1e-6)
    with pytest.raises(FabricationError, match=r"beam defect\(s\): B-[UW]\d\d"):
        build_beams(s, BeamParams(min_angle_deg=89.0, max_length=0))


@pytest.mark.parametrize("tilt", [0.0, 2.0])
def test_assembly_by_sliding(tilt):
    s = support_pp(sample_pp_grid(4, 6, tilt=tilt))
    prm = BeamParams(max_length=0, clearance=1.0)
    bs = build_beams(s, prm)
    for rec in bs.report.records:
        p = bs.by_id[rec.part_id]
        if not p.slots:
            assert rec.slidable and rec.sliding_play_mm == 0
            continue
        ax = s.axes[[sl.node for sl in p.slots]]
        spread = max(np.arccos(np.clip(x @ y, -1, 1)) for x in ax for y in ax)
        assert rec.slot_spread_deg == pytest.approx(np.degrees(spread), abs=1e-7)
        play = max(sl.length for sl in p.slots) * np.sin(spread / 2)    # at the slots' bisector
        if not p.trims:                            # no end cut to tilt the way in off the bisector
            assert rec.sliding_play_mm == pytest.approx(play, rel=1e-6, abs=1e-7)
            assert rec.slidable == (play <= 0.5 * prm.clearance + 1e-9 or p.family == 0)   # c/2 each side
        else:                                      # the bisector has the least travel of any direction
            assert rec.sliding_play_mm >= play - 1e-7
        if p.family == 0:                          # the rows go in first, into nothing
            assert rec.slidable and rec.extra_clearance_mm == 0
            continue
        if rec.slidable:
            assert rec.sliding_play_mm <= 0.5 * prm.clearance + 1e-7
        assert rec.extra_clearance_mm == pytest.approx(max(0.0, rec.sliding_play_mm - 0.5 * prm.clearance), abs=1e-7)
    n_bad = bs.report.totals()["not_slidable"]
    assert (n_bad == 0) if tilt == 0 else (n_bad > 0)


def test_long_beams_are_split_into_pieces():
    s = support_pp(sample_pp_grid(3, 12))
    bs = build_beams(s, BeamParams(max_length=5000.0))
    for beam in {p.beam_id for p in bs.plates}:
        pieces = sorted((p for p in bs.plates if p.beam_id == beam), key=lambda p: p.piece)
        assert all(np.ptp(p.outline[:, 0]) <= 5000.0 for p in pieces)      # the flat part fits 5 m
        line = s.polylines[pieces[0].polyline]
        if sum(np.linalg.norm(np.diff(s.vertices[line.vertices], axis=0), axis=1)) > 5000:
            assert len(pieces) > 1 and pieces[0].part_id == f"{beam}-S00"
        assert np.concatenate([p.nodes for p in pieces]).tolist() == line.vertices.tolist()
        for a, b in zip(pieces[:-1], pieces[1:]):      # neighbouring pieces share their cut
            assert np.abs(a.frame.to3d(a.top[-1]) - b.frame.to3d(b.top[0])).max() < 1e-8
            assert np.abs(a.frame.to3d(a.bottom[-1]) - b.frame.to3d(b.bottom[0])).max() < 1e-8


def test_beams_that_cannot_be_split_short_enough_are_reported():
    s = support_pp(sample_pp_grid(3, 4))
    bs = build_beams(s, BeamParams(max_length=1000.0), strict=False)
    long = [d for d in bs.report.defects if d.code == "too_long"]
    assert sorted(d.element for d in long) == sorted({p.beam_id for p in bs.plates})   # edges > 1 m
    for d in long:
        assert d.value > 1000.0 and d.value == pytest.approx(
            max(np.ptp(p.raw_outline[:, 0]) for p in bs.plates if p.beam_id == d.element), abs=1e-6)


def test_closed_rows_are_cut_into_pieces():
    g = sample_conical_grid(4, 16, sweep_deg=360.0)
    s = support_structure(g)
    bs = build_beams(s, BeamParams(max_length=0))
    for i in range(g.shape[0]):
        pieces = sorted((p for p in bs.plates if p.beam_id == f"B-U{i:02d}"), key=lambda p: p.piece)
        assert len(pieces) == 2
        ring = g.vertices[i]
        perim = np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1).sum()
        assert sum(p.length for p in pieces) == pytest.approx(perim, rel=1e-12)
        assert sorted(np.concatenate([p.nodes for p in pieces]).tolist()) == sorted(g.vertex_index[i].tolist())
        assert np.abs(pieces[0].frame.to3d(pieces[0].top[-1]) - pieces[1].frame.to3d(pieces[1].top[0])).max() < 1e-8
        assert np.abs(pieces[1].frame.to3d(pieces[1].top[-1]) - pieces[0].frame.to3d(pieces[0].top[0])).max() < 1e-8


def test_general_mesh_plates_stop_at_singular_vertices():
    mesh = transform(load_mesh(shared_file("DOS__botanic-garden-bubble-0.obj")), scale=1000.0)
    s = support_structure(mesh)
    bs = build_beams(s, BeamParams(joint="none", max_length=0), strict=False)
    topo = mesh.topology
    sing = set(np.flatnonzero(~topo.boundary_vertices & (topo.valence != 4)).tolist())
    assert len(sing) == 4
    for j in bs.joints:
        if j.vertex in sing:
            assert set(j.roles) == {"end"} and len(j.parts) == topo.valence[j.vertex]
    assert all(p.part_id.startswith("B-R") for p in bs.plates)
    # the polylines are far from planar here: each edge is its own plate, in its support plane
    assert len(bs.plates) == len(s.edges)
    assert not any(d.code in ("axis_crossing", "outline") for d in bs.report.defects)


def test_flat_parts(pp):
    s, bs = pp
    parts = bs.flat_parts()
    assert [f.part_id for f in parts] == [p.part_id for p in bs.plates]
    for f, p in zip(parts, bs.plates):
        assert f.kind == "beam" and f.area > 0 and f.label == p.part_id and f.mirror_allowed
        poly = Polygon(f.outline).buffer(1e-6)
        assert all(poly.covers(LineString(m)) for m in f.marks)
        for m in f.marks:        # marks run along node axes
            d = (m[1] - m[0]) / np.linalg.norm(m[1] - m[0])
            assert any(abs(abs(d @ p.node_axis(v)) - 1) < 1e-9 for v in p.nodes)
        through = int(p.through.sum())
        assert len(f.marks) == through
        assert f.meta["mass_kg"] == pytest.approx(p.area * p.thickness * 7850e-9)
    # a translational vault: the interior rows are congruent, so are the interior columns
    t = build_beams(support_pp(sample_pp_grid(5, 7, bend=0.0, tilt=0.0)), BeamParams(max_length=0))
    assert t.types["B-U01"] == t.types["B-U02"] == t.types["B-U04"]
    assert t.types["B-W01"] == t.types["B-W03"]
    assert len(set(t.types.values())) <= 6
    rot = np.array([[0.6, -0.8], [0.8, 0.6]])
    o = t.by_id["B-U02"].outline
    assert congruent_outlines(o, o @ rot.T + [5, -7]) and congruent_outlines(o, o * [-1, 1])
    assert not congruent_outlines(o, o * [1.01, 1])
    ell = np.array([[0, 0], [300, 0], [300, 50], [60, 50], [60, 200], [0, 200]], float)
    assert not congruent_outlines(ell, ell * [-1, 1], mirror=False)
    assert congruent_outlines(ell, ell * [-1, 1])


def test_rigid_motion_keeps_the_plates(pp):
    s, bs = pp
    g = sample_pp_grid(5, 7)
    moved = transform(g, rotate_z_deg=37.0, translate=(1000.0, -250.0, 40.0))
    bm = build_beams(support_pp(moved), BeamParams(max_length=0))
    for p in bs.plates:
        q = bm.by_id[p.part_id]
        assert np.abs(p.outline - q.outline).max() < 1e-6


def test_bad_parameters():
    with pytest.raises(DesignError, match=r"beams\.joint: unknown joint .*did you mean 'halflap'"):
        parse_params(BeamParams, {"joint": "halflapp"}, "beams")
    with pytest.raises(DesignError, match=r"beams\.depth: must be > 0"):
        parse_params(BeamParams, {"depth": 0}, "beams")
    with pytest.raises(DesignError, match=r"beams\.max_length: must be 0 or at least twice min_segment"):
        parse_params(BeamParams, {"max_length": 5.0}, "beams")
    with pytest.raises(DesignError, match=r"beams\.thikness: unknown key \(did you mean 'thickness'"):
        parse_params(BeamParams, {"thikness": 5.0}, "beams")


def test_congruent_plates_astride_a_rounding_boundary_share_a_type():
    """Two plates congruent to 1e-6 mm whose principal-axes coordinates straddle a rounding boundary of the
    0.1 mm grid the types were once keyed by (rounding splits them: the default's columns became two types that
    way under another numpy) are one type, turned, shifted or mirrored; a plate 0.2 mm longer, or one with
    holes, is another."""
    from types import SimpleNamespace

    from fabrication.beams.flat import _poses, type_ids

    o = np.array([[0.0, 0.0], [1486.3, 0.0], [1486.3, 150.0], [700.0, 180.0], [0.0, 150.0]])
    pose = _poses(o, True)[0]
    j = int(np.argmax(np.abs(pose[:, 0])))
    target = (np.floor(pose[j, 0] / 0.1) + 0.5) * 0.1                    # a rounding boundary of the grid
    a = pose * [(target - 1e-7) / pose[j, 0], 1.0]
    b = pose * [(target + 1e-7) / pose[j, 0], 1.0]
    assert np.abs(a - b).max() < 1e-6 and not np.array_equal(np.round(a / 0.1), np.round(b / 0.1))

    def plate(pid, outline, holes=0):
        return SimpleNamespace(part_id=pid, flat_outline=outline, holes=np.zeros((holes, 3)), bevels=())

    t = np.radians(31.0)
    rot = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    longer = a * [1.0 + 0.2 / 1486.3, 1.0]
    ids = type_ids([plate("a", a), plate("b", b @ rot.T + [500.0, -80.0]), plate("c", (a * [-1, 1])[::-1]),
                    plate("d", longer), plate("e", a, holes=4)])
    assert ids["a"] == ids["b"] == ids["c"]
    assert len({ids["a"], ids["d"], ids["e"]}) == 3
