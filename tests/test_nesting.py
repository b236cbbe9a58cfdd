"""Nesting: every part once, inside the usable area, spacing held, deterministic, errors name the part."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from conftest import shared_file
from fabrication.flatpart import FlatPart, Placement, place_points
from fabrication.nesting import NestingParams, lower_bound, nest, verify_nesting
from ppfab.errors import DesignError, NestingError
from ppfab.schema import parse_params


def bench_parts(n: int, start: int = 0) -> list[FlatPart]:
    data = json.loads((shared_file("bench_panels_500.json")).read_text())
    return [FlatPart(f"P{i:03d}", "panel", np.array(p, dtype=float)) for i, p in enumerate(data[start:start + n])]


def notched_strip(pid: str, length: float, depth: float, notches: int, bend: float = 0.0) -> FlatPart:
    """A beam-plate-like outline: a long strip with rectangular notches on its top edge, optionally bent."""
    xs = np.linspace(0, length, 2 * notches + 2)
    top = []
    for k in range(len(xs) - 1, 0, -1):
        x_hi, x_lo = xs[k], xs[k - 1]
        y = depth if k % 2 == 0 else depth * 0.6
        top += [(x_hi, y), (x_lo, y)]
    pts = np.array([(0.0, 0.0), (length, 0.0)] + top)
    pts = pts[np.r_[True, np.any(np.diff(pts, axis=0) != 0, axis=1)]]
    if bend:
        pts[:, 1] += bend * np.sin(np.pi * pts[:, 0] / length)
    return FlatPart(pid, "beam", pts)


def guillotine_separable(boxes: list[tuple[float, float, float, float]]) -> bool:
    """Whether boxes (x0, y0, x1, y1) are cut apart by recursive edge-to-edge straight cuts."""
    if len(boxes) <= 1:
        return True
    for axis in (0, 1):
        lo = sorted(boxes, key=lambda b: b[axis])
        reach = -np.inf
        for k in range(len(lo) - 1):
            reach = max(reach, lo[k][axis + 2])
            if reach <= lo[k + 1][axis] + 1e-9:        # a cut line between the groups touches no box
                return guillotine_separable(lo[:k + 1]) and guillotine_separable(lo[k + 1:])
    return False


def straight_cut_separable(polys: list[np.ndarray], depth: int = 0) -> bool:
    """Whether convex polygons are cut apart by recursive straight edge-to-edge cuts (any direction).

    A cut along direction ``d`` exists when the polygons' extents across ``d`` leave a gap; the
    directions tried are the horizontal and every edge direction of the polygons (a separating
    line of two convex groups can be taken along one of the polygons' edges in these layouts).
    """
    if len(polys) <= 1:
        return True
    dirs = [np.array([1.0, 0.0])] + [e / np.linalg.norm(e) for q in polys for e in (np.roll(q, -1, 0) - q)
                                     if np.linalg.norm(e) > 1e-9]
    for d in dirs:
        n = np.array([-d[1], d[0]])
        ext = sorted(((float((q @ n).min()), float((q @ n).max()), k) for k, q in enumerate(polys)))
        reach = -np.inf
        for i in range(len(ext) - 1):
            reach = max(reach, ext[i][1])
            if reach <= ext[i + 1][0] + 1e-6:
                lo = [polys[e[2]] for e in ext[:i + 1]]
                hi = [polys[e[2]] for e in ext[i + 1:]]
                return straight_cut_separable(lo, depth + 1) and straight_cut_separable(hi, depth + 1)
    return False


@pytest.mark.parametrize("mode", ["rectangles", "guillotine", "irregular", "auto"])
def test_panels_nest_and_verify(mode):
    parts = bench_parts(40)
    params = NestingParams(mode=mode, time_budget=1.0, margin=[15, 10, 20, 5])
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    assert sorted(p.part_id for p in res.placements) == sorted(p.part_id for p in parts)
    assert res.sheets >= lower_bound(parts, params) == res.lower_bound
    assert res.utilisation == pytest.approx(sum(p.area for p in parts) / (res.sheets * 6000 * 3210))
    assert len({p.nest_tag for p in res.placements}) == len(parts)
    assert all(p.rotation_deg in (0.0, 90.0, 180.0, 270.0) and not p.mirrored for p in res.placements)
    assert res.mode in ("rectangles", "guillotine", "irregular")
    if mode != "auto":
        assert res.mode == mode
    by_id = {p.part_id: p for p in parts}
    for group in res.by_sheet():
        placed = [place_points(by_id[pl.part_id].outline, pl) for pl in group]
        if res.mode == "rectangles":
            boxes = [(*(q.min(0) - 5.0), *(q.max(0) + 5.0)) for q in placed]   # box plus half the spacing
            assert guillotine_separable(boxes)
        if res.mode == "guillotine":
            assert straight_cut_separable(placed)


def test_deterministic_for_seed_and_budget():
    parts = bench_parts(30, 100)
    params = NestingParams(mode="irregular", time_budget=0.5, seed=3)
    a, b = nest(parts, params), nest(parts, params)
    assert a.placements == b.placements and a.sheets == b.sheets
    assert a.work_units == b.work_units


def test_search_beats_the_greedy_start_on_the_benchmark_slice():
    """Ruin and recreate only ever keeps fewer or fuller sheets; with a budget it reaches the bound here."""
    parts = bench_parts(60, 200)
    params = NestingParams(mode="irregular", time_budget=3.0)
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    first = res.history[0][1]
    assert res.sheets <= first
    assert res.sheets <= res.lower_bound + 1
    assert min(res.sheet_fill[:-1]) > 0.75          # every sheet but the last is well filled


def test_beam_plates_nest_on_plate_stock():
    parts = [notched_strip(f"B-{k:02d}", 900 + 97 * k, 120 + 9 * k, 3 + k % 4, bend=60.0 * (k % 3))
             for k in range(14)]
    params = NestingParams(sheet=[2500, 1250], margin=10, spacing=6, mode="auto", time_budget=1.0)
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    assert res.sheets >= 1 and len(res.placements) == 14


def test_free_rotation_and_mirroring():
    # four squares turned by 30°: their boxes are 1.37 times wider; only free rotation packs them on one sheet
    sq = np.array([[0, 0], [1000, 0], [1000, 1000], [0, 1000]], dtype=float)
    a = np.radians(30)
    rot = sq @ np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    parts = [FlatPart(f"Q{k}", "panel", rot) for k in range(4)]
    fixed = NestingParams(sheet=[2100, 2100], spacing=10, time_budget=0.3)
    free = replace(fixed, free_rotation=True)
    assert nest(parts, fixed).sheets > 1
    res = nest(parts, free)
    verify_nesting(parts, res, free)
    assert res.sheets == 1
    # mirroring only where the part allows it
    tri = np.array([[0, 0], [1500, 0], [200, 900]], dtype=float)
    mparts = [FlatPart(f"M{k}", "panel", tri, mirror_allowed=True) for k in range(6)]
    params = NestingParams(sheet=[3200, 2000], time_budget=0.5, mode="irregular")
    res = nest(mparts, params)
    verify_nesting(mparts, res, params)
    flipped = [replace(p, mirrored=True) for p in res.placements]
    bad = replace(res, placements=flipped)
    nomirror = [replace(p, mirror_allowed=False) for p in mparts]
    with pytest.raises(NestingError, match="mirrored"):
        verify_nesting(nomirror, bad, params)


def test_part_that_fits_no_sheet_is_named():
    parts = bench_parts(3) + [FlatPart("HUGE-1", "panel", np.array([[0, 0], [7000, 0], [7000, 500], [0, 500]], float))]
    with pytest.raises(NestingError, match=r"HUGE-1 \(7000.0 x 500.0 mm\) fits no sheet"):
        nest(parts, NestingParams())


def test_verify_catches_every_kind_of_fault():
    parts = bench_parts(12)
    params = NestingParams(time_budget=0.3, margin=20)
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    pl = res.placements
    same = [p for p in pl if p.sheet == pl[0].sheet]
    assert len(same) >= 2
    # overlap: move the second part of a sheet onto the first
    moved = [replace(p, x=same[0].x, y=same[0].y, rotation_deg=same[0].rotation_deg) if p is same[1] else p for p in pl]
    with pytest.raises(NestingError, match=rf"{same[1].part_id}|{same[0].part_id}"):
        verify_nesting(parts, replace(res, placements=moved), params)
    with pytest.raises(NestingError, match="not placed"):
        verify_nesting(parts, replace(res, placements=pl[1:]), params)
    with pytest.raises(NestingError, match="placed 2 times"):
        verify_nesting(parts, replace(res, placements=pl + [replace(pl[0], nest_tag="X")]), params)
    with pytest.raises(NestingError, match="nest tag"):
        verify_nesting(parts, replace(res, placements=[replace(pl[0], nest_tag=pl[1].nest_tag)] + pl[1:]), params)
    with pytest.raises(NestingError, match=rf"{pl[0].part_id} .*leaves the usable area of sheet 1 by 15 mm"):
        outside = replace(pl[0], x=pl[0].x - (min(place_points(parts[0].outline, pl[0])[:, 0]) - 20) - 15)
        verify_nesting(parts, replace(res, placements=[outside] + pl[1:]), params)
    with pytest.raises(NestingError, match="rotated by 45"):
        verify_nesting(parts, replace(res, placements=[replace(pl[0], rotation_deg=45.0)] + pl[1:]), params)


def test_spacing_violation_is_measured():
    parts = [FlatPart(f"R{k}", "panel", np.array([[0, 0], [500, 0], [500, 400], [0, 400]], float)) for k in range(2)]
    params = NestingParams(sheet=[2000, 1000], spacing=10)
    pls = [Placement("R0", 0, 0, 0, 0, nest_tag="S01-001"), Placement("R1", 0, 507, 0, 0, nest_tag="S01-002")]
    from fabrication.nesting import Nesting
    res = Nesting(pls, 1, 0.2, 1, "guillotine", (2000.0, 1000.0), params.usable())
    with pytest.raises(NestingError, match=r"R0 and R1 on sheet 1 are 7 mm apart, spacing is 10 mm"):
        verify_nesting(parts, res, params)
    ok = replace(res, placements=[pls[0], replace(pls[1], x=510.0)])
    verify_nesting(parts, ok, params)


def test_params_validation():
    p = parse_params(NestingParams, {"margin": 12, "mode": "guillotine", "time_budget": 5}, "nesting")
    assert p.usable() == (12.0, 12.0, 5988.0, 3198.0)
    with pytest.raises(DesignError, match="nesting.margin"):
        parse_params(NestingParams, {"margin": [1, 2, 3]}, "nesting")
    with pytest.raises(DesignError, match="did you mean 'spacing'"):
        parse_params(NestingParams, {"spaceing": 3}, "nesting")
    with pytest.raises(DesignError, match="nesting.mode"):
        parse_params(NestingParams, {"mode": "fast"}, "nesting")


def test_the_lower_bound_counts_half_the_spacing_around_every_part_and_is_met_by_a_grid():
    """100 squares of 100 mm, 10 mm apart, on 1000 × 1000 sheets: a 9 × 9 grid (9·100 + 8·10 = 980 mm) holds 81,
    so 2 sheets are needed and enough.  The plain area bound says 1; grown by 5 mm each square covers
    100² + 5·400 + 25π = 12,078.5 mm² of (1000 + 10)² per sheet: 100 of them need 1.18 sheets, so the bound
    is 2, and the nesting meets it."""
    sq = np.array([[0.0, 0], [100, 0], [100, 100], [0, 100]])
    parts = [FlatPart(f"Q{i:03d}", "panel", sq + i) for i in range(100)]
    params = NestingParams(sheet=[1000.0, 1000.0], spacing=10.0, margin=0.0, time_budget=1.0, mode="rectangles")
    assert int(np.ceil(sum(p.area for p in parts) / 1e6)) == 1
    assert lower_bound(parts, params) == 2
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    assert res.sheets == res.lower_bound == 2
    # a trim shrinks the usable area: 1000 − 2·150 = 700 mm leaves 710² per sheet for the grown squares
    assert lower_bound(parts, replace(params, margin=150.0)) == int(np.ceil(100 * 12078.5398 / 710 ** 2)) == 3


def test_grown_area_is_steiners_formula_and_never_above_the_true_grown_area():
    """Convex: ``A + r·P + π r²`` against a fine buffer.  Non-convex (an L of six corners, one reflex): the true
    grown area is the L's area, plus ``r`` times its perimeter, plus a quarter disc at each of the five convex
    corners, minus the ``r × r`` square the two offset edges at the reflex corner would count twice; the value
    may be below it by the chords of the arcs only."""
    from fabrication.nesting.result import grown_area

    r = 5.0
    quad = np.array([[0.0, 0], [1300, 40], [1250, 1500], [-30, 1460]])
    per = np.linalg.norm(np.roll(quad, -1, axis=0) - quad, axis=1).sum()
    from shapely.geometry import Polygon

    steiner = Polygon(quad).area + r * per + np.pi * r * r
    assert grown_area(quad, r) == pytest.approx(steiner, rel=1e-12)
    assert Polygon(quad).buffer(r, quad_segs=256).area == pytest.approx(steiner, abs=0.01)
    ell = np.array([[0.0, 0], [1000, 0], [1000, 400], [400, 400], [400, 1000], [0, 1000]])
    true = 640_000 + r * 4000 + 5 * np.pi * r * r / 4 - r * r
    got = grown_area(ell, r)
    assert true - 0.5 <= got <= true
    assert grown_area(ell, 0.0) == 640_000
    from fabrication.nesting.result import grown_areas

    mixed = [quad, ell, quad[::-1] + 7.0, ell[:4]]                      # batched by vertex count, order kept
    assert grown_areas(mixed, r) == pytest.approx([grown_area(q, r) for q in mixed], rel=1e-12)
