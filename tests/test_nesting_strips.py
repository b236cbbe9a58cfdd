"""Strip stacking (irregular mode for beam plates): bent strips nest one inside the next, closer
than their bounding boxes allow; spacing always held; exact column profiles; the row fix."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from shapely.geometry import LineString, Polygon, box

from conftest import FULL
from fabrication.flatpart import FlatPart
from fabrication.nesting import NestingParams, nest, placed_outline, verify_nesting
from fabrication.nesting.catalog import build_catalog
from fabrication.nesting.registry import get_strategy
from fabrication.nesting.stack import column_extents
from ppfab.errors import NestingError

from test_nesting import bench_parts


def arc_strip(pid: str, chord: float, depth: float, sagitta: float, down: bool = False,
              n: int = 24) -> FlatPart:
    """An annular sector: inner arc of chord ``chord`` and rise ``sagitta``, ``depth`` thick.

    Bent up (∩) in its own frame, or down (∪) when ``down`` — then only a 180° turn stacks it
    with the others.
    """
    R = (chord ** 2 / 4 + sagitta ** 2) / (2 * sagitta)
    phi = math.asin(chord / (2 * R))
    a = np.linspace(math.pi / 2 - phi, math.pi / 2 + phi, n)
    outer = np.c_[(R + depth) * np.cos(a), (R + depth) * np.sin(a)]
    inner = np.c_[R * np.cos(a[::-1]), R * np.sin(a[::-1])]
    pts = np.vstack([outer, inner])
    if down:
        pts = -pts
    return FlatPart(pid, "beam", pts, mirror_allowed=True)


def bulges_up(outline: np.ndarray) -> bool:
    """Whether a placed strip is ∩: its highest point lies in the middle half of its length."""
    x0, x1 = outline[:, 0].min(), outline[:, 0].max()
    top_x = outline[np.argmax(outline[:, 1]), 0]
    return abs(top_x - 0.5 * (x0 + x1)) < 0.25 * (x1 - x0)


def test_bent_strips_stack_closer_than_their_boxes():
    """Seven strips 100 mm deep bent ~120 mm: their boxes (205–225 mm high) fit four to a 940 mm
    sheet; stacked, all seven fit."""
    chords = [1940, 1900, 1860, 1820, 1780, 1920, 1800]
    parts = [arc_strip(f"B-{k}", c, 100.0, 120.0 * (c / 1900) ** 2, down=bool(k % 2)) for k, c in enumerate(chords)]
    params = NestingParams(sheet=[2000, 940], margin=0, spacing=10, mode="irregular", time_budget=0.5)
    heights = np.sort([np.ptp(p.outline[:, 1]) for p in parts])
    assert heights.min() > 200 and np.ptp(parts[0].outline[:, 0]) + 1780 > 2000     # one strip per row
    assert heights[:5].sum() + 4 * 10 > 940          # as boxes no five fit one above the other: two sheets at least
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    assert res.sheets == 1 and res.mode == "irregular"
    rectangles = replace(params, mode="rectangles")
    assert nest(parts, rectangles).sheets >= 2

    by_id = {p.part_id: p for p in parts}
    placed = sorted((placed_outline(by_id[pl.part_id], pl) for pl in res.placements), key=lambda q: q[:, 1].min())
    # every strip bends the same way: the ∪ ones were turned by 180°
    assert len({bulges_up(q) for q in placed}) == 1
    turned = {pl.part_id for pl in res.placements if pl.rotation_deg % 360 == 180}
    assert turned in ({"B-1", "B-3", "B-5"}, {"B-0", "B-2", "B-4", "B-6"})
    for lower, upper in zip(placed, placed[1:]):
        # boxes overlap by most of the sagitta ...
        overlap = lower[:, 1].max() - upper[:, 1].min()
        assert overlap > 90.0
        # ... and the gap between neighbours stays near the spacing along the shorter strip's length
        lo_poly, up_poly = Polygon(lower), Polygon(upper)
        x0 = max(lower[:, 0].min(), upper[:, 0].min()) + 40
        x1 = min(lower[:, 0].max(), upper[:, 0].max()) - 40
        gaps = []
        for x in np.linspace(x0, x1, 25):
            cut = LineString([(x, -1e4), (x, 1e4)])
            top_of_lower = cut.intersection(lo_poly).bounds[3]
            bottom_of_upper = cut.intersection(up_poly).bounds[1]
            gaps.append(bottom_of_upper - top_of_lower)
        assert 10.0 - 1e-6 <= min(gaps) and max(gaps) < 10.0 + 12.0


def runs_of(parts, params, mode):
    cat = build_catalog(parts, params)
    return [(r.make.__name__, r.mode, round(r.share, 6)) for r in get_strategy(mode).runs(cat, params)]


def test_irregular_mode_picks_stacks_for_strips_and_rows_for_panels():
    params = NestingParams(sheet=[2500, 1250], spacing=5)
    strips = [arc_strip(f"S{k}", 1500 + 50 * k, 80, 60) for k in range(6)]
    panels = bench_parts(6)
    small = [FlatPart(f"Q{k}", "panel", np.array([[0, 0], [300, 0], [300, 300], [0, 300]], float)) for k in range(6)]
    assert runs_of(panels, NestingParams(), "irregular") == [("bands", "irregular", 1.0)]
    assert runs_of(strips, params, "irregular") == [("stacks", "irregular", 1.0)]
    assert runs_of(strips + small, params, "irregular") == [("bands", "irregular", 0.5), ("stacks", "irregular", 0.5)]
    # strips are not convex: no straight-cut rows, auto runs rectangles and stacks
    assert runs_of(strips, params, "auto") == [("stacks", "irregular", 0.714286), ("boxes", "rectangles", 0.285714)]
    assert runs_of(strips, params, "guillotine") == [("boxes", "rectangles", 1.0)]
    assert runs_of(panels, NestingParams(), "guillotine") == [("cut_bands", "guillotine", 1.0)]


@pytest.mark.parametrize("seed", range(6))
def test_stacks_keep_spacing_and_are_deterministic(seed):
    """Random bent strips (both ways, any length up to the sheet, very bent ones too) and loose squares."""
    rng = np.random.default_rng(seed)
    L, H = rng.uniform(1500, 3000), rng.uniform(700, 1500)
    parts = [arc_strip(f"S{k}", rng.uniform(150, 0.9 * L), rng.uniform(20, 150), rng.uniform(1, 300),
                       down=bool(rng.integers(2))) for k in range(int(rng.integers(8, 25)))]
    parts += [FlatPart(f"Q{k}", "panel", rng.uniform(20, 300) * np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]))
              for k in range(int(rng.integers(0, 4)))]
    params = NestingParams(sheet=[L, H], margin=float(rng.choice([0, 10])), spacing=float([0, 4, 20][seed % 3]),
                           free_rotation=seed == 5, rotations=[[0, 90, 180, 270], [0, 180]][seed % 2],
                           mode="irregular", time_budget=0.1, seed=seed)
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    again = nest(parts, params)
    assert again.placements == res.placements and again.work_units == res.work_units


def test_column_extents_match_shapely_slabs():
    rng = np.random.default_rng(7)
    polys = []
    for _ in range(5):
        a = np.sort(rng.uniform(0, 2 * np.pi, 12))
        r = rng.uniform(40, 100, 12)
        polys.append(np.c_[200 + r * np.cos(a), 100 + r * np.sin(a)])     # star-shaped: simple
    polys.append(arc_strip("A", 300, 30, 60).outline + [250, 0])
    q = 7.3
    x_from = np.array([90.0, 85.5, 100.0, 60.0, 120.0, -10.0])
    n = np.array([40, 45, 30, 50, 25, 60])
    ymin, ymax = column_extents(polys, q, x_from, n)
    assert ymin.shape == (6, 60)
    for i, p in enumerate(polys):
        P = Polygon(p)
        for c in range(60):
            cell = P.intersection(box(x_from[i] + c * q, -1e4, x_from[i] + (c + 1) * q, 1e4))
            if c >= n[i] or cell.is_empty:
                assert ymin[i, c] == np.inf and ymax[i, c] == -np.inf
            else:
                assert ymin[i, c] == pytest.approx(cell.bounds[1], abs=1e-9)
                assert ymax[i, c] == pytest.approx(cell.bounds[3], abs=1e-9)


def test_self_crossing_outline_is_named():
    crossed = np.array([[0, 0], [300, 0], [300, 100], [120, 100], [200, -40], [0, 100]], float)   # area > 0
    parts = bench_parts(2) + [FlatPart("BOW-1", "beam", crossed)]
    assert parts[-1].area > 0
    with pytest.raises(NestingError, match=r"BOW-1: outline is not a simple polygon \(Self-intersection"):
        nest(parts, NestingParams())


@pytest.mark.parametrize("spacing", [0.0, 5.0])
def test_row_piece_nestled_under_an_overhang_does_not_pull_the_next_into_it(spacing):
    """A small square slides under the arm of a Γ; the next block must start after the arm, not after the square."""
    gamma = np.array([[0, 0], [50, 0], [50, 250], [600, 250], [600, 300], [0, 300]], float)
    square = np.array([[0, 0], [100, 0], [100, 100], [0, 100]], float)
    block = np.array([[0, 0], [300, 0], [300, 280], [0, 280]], float)
    parts = [FlatPart("G", "panel", gamma, rotations=(0.0,)), FlatPart("S", "panel", square, rotations=(0.0,)),
             FlatPart("K", "panel", block, rotations=(0.0,))]
    params = NestingParams(sheet=[1200, 320], spacing=spacing, mode="irregular", time_budget=0.1)
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    pos = {p.part_id: p for p in res.placements}
    assert res.sheets == 1
    g, sq = pos["G"], pos["S"]
    assert g.x + 50 + spacing - 1e-6 <= sq.x and sq.x + 100 <= g.x + 600   # the square did nestle under the arm
    assert sq.y + 100 + spacing <= g.y + 250 + 1e-6


@pytest.mark.slow
def test_default_design_beam_plates_stack_on_plate_stock():
    """The bundled design's 219 beam plates: 33 sheets as box rows, 25 stacked (9 a sheet; see
    benchmarks/nesting.py).  CI runs every 4th plate."""
    from fabrication.beams import build_beams
    from fabrication.design import load_design
    from ppfab.geometry import build_geometry
    from ppfab.support.select import support_structure

    d = load_design(None)
    g = build_geometry(d.geometry, d.optimize, d.base_dir)
    s = support_structure(g.mesh, d.section("support"), planar_families=g.planar_families)
    parts = build_beams(s, d.section("beams")).flat_parts()
    params = d.section("beam_nesting")
    if not FULL:
        parts = parts[::4]
        params = replace(params, time_budget=0.5)
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    assert res.mode == "irregular"
    assert res.sheets <= math.ceil(len(parts) / 9)
    assert nest(parts, replace(params, mode="guillotine")).sheets > res.sheets
    if FULL:
        assert len(parts) == 219 and res.sheets <= 25
