"""True-shape nesting: rotation policy per material, trapezoids paired by 180° turns, the strategy table,
the work budget and determinism."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO, shared_file
from fabrication.flatpart import FlatPart, place_points
from fabrication.nesting import STRATEGIES, NestingParams, get_strategy, nest, strategy, verify_nesting
from fabrication.nesting.rows import SheetFiller
from fabrication.panels import PanelParams, make_panels
from ppfab.errors import DesignError, NestingError
from ppfab.io import load_mesh

from test_nesting import straight_cut_separable

FREEFORM = REPO / "benchmarks" / "data"


def freeform_parts(name: str, n: int, free: bool = True) -> list[FlatPart]:
    """The first ``n`` panels of a panel set made from a real mesh (``benchmarks/make_panel_sets.py``)."""
    doc = json.loads((FREEFORM / f"{name}.json").read_text())
    return [FlatPart(f"F{i:04d}", "panel", np.array(p, dtype=float), free_rotation=free)
            for i, p in enumerate(doc["panels"][:n])]


def trapezoid(pid: str, base: float, top: float, height: float, shift: float = 0.0) -> FlatPart:
    pts = np.array([[0, 0], [base, 0], [0.5 * (base + top) + shift, height], [0.5 * (base - top) + shift, height]])
    return FlatPart(pid, "panel", pts)


def angle_in(rot: float, allowed: tuple[float, ...]) -> bool:
    return any(abs(((rot - a) + 180.0) % 360.0 - 180.0) < 1e-6 for a in allowed)


def test_trapezoids_pair_by_half_turns_where_boxes_cannot():
    """Ten trapezoids (base 1000, top 400, 900 high): turned 180° every other one they tile a strip,
    so 5 fit a 4100 mm row; their boxes (1000 wide) fit only 4."""
    parts = [trapezoid(f"T{k}", 1000.0, 400.0, 900.0) for k in range(10)]
    params = NestingParams(sheet=[4100, 1900], spacing=10, time_budget=0.5, rotations=[0.0, 180.0])
    boxes = nest(parts, replace(params, mode="rectangles"))
    shapes = nest(parts, replace(params, mode="irregular"))
    verify_nesting(parts, shapes, params)
    assert boxes.sheets == 2 and shapes.sheets == 1
    rots = sorted(p.rotation_deg % 360 for p in shapes.placements)
    assert rots.count(180.0) >= 4 and rots.count(0.0) >= 4            # neighbours turned against each other
    cut = nest(parts, replace(params, mode="guillotine"))
    verify_nesting(parts, cut, params)
    assert cut.sheets == 1
    by_id = {p.part_id: p for p in parts}
    assert straight_cut_separable([place_points(by_id[pl.part_id].outline, pl) for pl in cut.placements])


def test_freeform_panels_need_fewer_sheets_as_true_shapes_than_as_rectangles():
    """300 sheared quads of the P-optimised conjugate roof: true-shape rows beat bounding rectangles."""
    parts = freeform_parts("conjugate_roof_P", 300)
    params = NestingParams(time_budget=2.0)
    rect = nest(parts, replace(params, mode="rectangles"))
    shape = nest(parts, replace(params, mode="irregular"))
    verify_nesting(parts, shape, params)
    assert shape.sheets < rect.sheets


@pytest.mark.parametrize("rotation", ["grain", "quarter", "free"])
def test_rotation_policy_of_the_glass_is_respected(rotation):
    """Coated or patterned glass (grain) stays at 0/180°, quarter turns at multiples of 90°; free glass
    may take any angle, and does take others on a real mesh."""
    mesh = load_mesh(shared_file("DOS__conical1.obj"))
    panels = make_panels(mesh, PanelParams(gap=20.0, planarity_tolerance=50.0, rotation=rotation), scale=1500.0)
    parts = [p.flat_part() for p in panels[:80]]
    params = NestingParams(time_budget=1.0, mode="irregular")
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    allowed = {"grain": (0.0, 180.0), "quarter": (0.0, 90.0, 180.0, 270.0)}
    if rotation == "free":
        assert all(p.free_rotation and p.rotations is None for p in parts)
        assert any(not angle_in(pl.rotation_deg, (0.0, 90.0, 180.0, 270.0)) for pl in res.placements)
    else:
        assert all(angle_in(pl.rotation_deg, allowed[rotation]) for pl in res.placements)
        turned = replace(res, placements=[replace(res.placements[0], rotation_deg=37.0)] + res.placements[1:])
        with pytest.raises(NestingError, match="rotated by 37"):
            verify_nesting(parts, turned, params)
    assert not any(pl.mirrored for pl in res.placements)


def test_free_panel_outline_maps_back_to_the_face():
    """The minimum-area frame is still an isometry of the face plane: the outline maps back to 3D onto
    the inset face, and the nested placement of that outline is what the sheet shows."""
    mesh = load_mesh(shared_file("DOS__conical1.obj"))
    panels = make_panels(mesh, PanelParams(gap=20.0, planarity_tolerance=50.0), scale=1500.0)[:20]
    ref = make_panels(mesh, PanelParams(gap=20.0, planarity_tolerance=50.0, rotation="quarter"), scale=1500.0)[:20]
    for p, r in zip(panels, ref):
        assert np.abs(p.outline_3d() - r.outline_3d()).max() < 1e-6        # same 3D points, another frame
        w, h = np.ptp(p.outline, axis=0)
        assert w * h <= np.prod(np.ptp(r.outline, axis=0)) + 1e-6


@pytest.mark.parametrize("mode", ["irregular", "guillotine"])
def test_same_seed_and_work_count_give_the_same_layout(mode):
    parts = freeform_parts("gitter_PP", 60)
    params = NestingParams(time_budget=1.0, seed=5, mode=mode)
    a, b = nest(parts, params), nest(parts, params)
    assert a.placements == b.placements and a.work_units == b.work_units and a.work_budget == b.work_budget
    assert a.seed == 5 and a.summary()["work_units"] == int(round(a.work_units))


def test_the_budget_is_spent_in_work_units_not_seconds():
    """The search stops on the work count: with a budget the first solution does not exhaust, the count
    ends within one search step of the budget (a step is not begun when the mean step would pass it);
    a budget of 0 still pays one first solution, on the cheapest rung of the cost ladder."""
    parts = freeform_parts("conjugate_roof_P", 80)
    zero = nest(parts, NestingParams(time_budget=0.0, mode="irregular"))
    assert zero.work_budget == 0.0 and zero.work_units > 0 and len(zero.history) == 1
    budget = 4.0 * zero.work_units / 1e6                                # seconds: several first solutions
    res = nest(parts, NestingParams(time_budget=budget, mode="irregular"))
    steps = [b[0] - a[0] for a, b in zip(res.history, res.history[1:])]
    assert len(steps) >= 2
    if res.sheets > res.lower_bound:                                    # stopped by the budget, not the bound
        assert res.work_budget - max(steps) <= res.work_units <= res.work_budget + max(steps)
    assert res.sheets <= zero.sheets


def test_the_strategy_table():
    assert {"rectangles", "guillotine", "irregular", "auto"} <= set(get_strategy("auto") and STRATEGIES)
    with pytest.raises(DesignError, match=r"unknown nesting mode 'guilotine' \(did you mean 'guillotine'\?\)"):
        NestingParams(mode="guilotine")
    # a new strategy is one registration: here box rows that report themselves under a new name
    from fabrication.nesting.registry import Run

    @strategy("boxes_test", "box rows (test)", rank=9)
    def boxes_test(cat, params):
        return [Run(lambda c, w: SheetFiller(c, w), "boxes_test", 1.0)]

    try:
        parts = freeform_parts("conical1_PP", 30)
        params = NestingParams(mode="boxes_test", time_budget=0.2)
        res = nest(parts, params)
        verify_nesting(parts, res, params)
        assert res.mode == "boxes_test"
        with pytest.raises(RuntimeError, match="registered twice"):
            strategy("boxes_test", "again", rank=9)(boxes_test)
    finally:
        STRATEGIES.pop("boxes_test", None)


def test_panel_sets_record_their_provenance():
    for path in sorted(Path(FREEFORM).glob("*.json")):
        doc = json.loads(path.read_text())
        src = doc["source"]
        assert src["repository"] and src["path"] and len(src["sha256"]) == 64
        assert doc["count"] == len(doc["panels"]) > 500
        q = [np.array(p) for p in doc["panels"]]
        area = sum(0.5 * abs(float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - p[:, 1] * np.roll(p[:, 0], -1)))) for p in q)
        assert area / 1e6 == pytest.approx(doc["area_m2"], rel=1e-4)
