"""Running glazing strips meet at a node on the mitre plane of their two spans: strip and gasket of one span stay on
its side (``fabrication.glazing.strips.mitre_setback``), so consecutive strips and gaskets never overlap — checked
with manifold3d's intersection of the boxes as convex solids, not with the formula that sets them back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
H, B = 11.0, 30.0                    # strip 8 + gasket 3 mm, half of a 60 mm strip


def _box(node: np.ndarray, into: np.ndarray, up: np.ndarray, start: float, length: float = 400.0):
    """The box ``start ≤ x ≤ start + length, |y| ≤ B, 0 ≤ z ≤ H`` of the frame (into, up × into, up) at ``node``,
    as a manifold3d hull."""
    import manifold3d as m3d

    ey = np.cross(up, into)
    pts = [node + x * into + y * ey + z * up for x in (start, start + length) for y in (-B, B) for z in (0.0, H)]
    return m3d.Manifold.hull_points(np.array(pts))


def _frame_up(into: np.ndarray, lean: np.ndarray) -> np.ndarray:
    up = lean - (lean @ into) * into
    return up / np.linalg.norm(up)


@pytest.mark.parametrize("kink_deg", [0.0, 5.0, 12.0, 20.0, 29.0])
@pytest.mark.parametrize("valley", [True, False])
def test_planar_kink_closed_form(kink_deg, valley):
    """In the polyline's plane: ``H·tan(κ/2)`` in a valley (the spans bend towards the glass side), 0 on a ridge."""
    from fabrication.glazing.strips import mitre_setback

    k = np.radians(kink_deg)
    s = 1.0 if valley else -1.0
    o_e = np.array([1.0, 0.0, 0.0])
    o_f = np.array([-np.cos(k), 0.0, s * np.sin(k)])          # into the next span: up (valley) or down (ridge)
    up = np.array([0.0, 0.0, 1.0])
    ey = np.cross(up, o_e)
    got = mitre_setback(o_e, o_f, up, ey, H, B)
    want = H * np.tan(k / 2) if valley else 0.0
    assert got == pytest.approx(want, abs=1e-12)


def test_boxes_so_set_back_touch_but_never_overlap():
    """Random spans kinking up to 30° in any direction, strips square to leaning glass (up tilted up to 25° out of
    the polyline's plane): the two boxes intersect in no volume; set back 0.3 mm less where the setback is that
    large, they do (the setback is the least that separates them)."""
    from fabrication.glazing.strips import mitre_setback

    rng = np.random.default_rng(28)
    tight = 0
    for _ in range(120):
        o_e = rng.normal(size=3)
        o_e /= np.linalg.norm(o_e)
        axis = np.cross(o_e, rng.normal(size=3))
        axis /= np.linalg.norm(axis)
        k = np.radians(rng.uniform(0.5, 30.0))
        o_f = -(np.cos(k) * o_e + np.sin(k) * np.cross(axis, o_e))   # the next span, kinked by k about axis
        lean = np.cross(axis, o_e) + np.tan(np.radians(rng.uniform(-25, 25))) * axis
        up_e, up_f = _frame_up(o_e, lean), _frame_up(o_f, lean)
        node = rng.normal(size=3) * 100
        s_e = mitre_setback(o_e, o_f, up_e, np.cross(up_e, o_e), H, B)
        s_f = mitre_setback(o_f, o_e, up_f, np.cross(up_f, o_f), H, B)
        both = _box(node, o_e, up_e, s_e) ^ _box(node, o_f, up_f, s_f)
        assert both.volume() < 1e-6, (np.degrees(k), s_e, s_f, both.volume())
        if min(s_e, s_f) > 0.3:
            tight += 1
            closer = _box(node, o_e, up_e, s_e - 0.3) ^ _box(node, o_f, up_f, s_f - 0.3)
            assert closer.volume() > 1e-3
    assert tight >= 20


def test_no_strip_or_gasket_of_a_built_roof_overlaps_another():
    """Every pair of strips (with their gaskets) of ``smallest_roof`` (panes kinking by up to 20°) meeting at a
    node: no common volume above 1 mm³ (manifold3d); before the mitre rule the gaskets of four valley nodes ran
    0.73 mm into the next strip."""
    import manifold3d as m3d

    from fabrication import build, load_design

    b = build(load_design(ROOT / "examples" / "smallest_roof.toml"))
    assert b.glazing is not None
    strips = b.glazing.strips
    tg = b.glazing.params.gasket_thickness
    solids = []
    for s in strips:
        f = s.frame
        corners = f.to3d(s.outline())
        pts = np.concatenate([corners + z * f.normal for z in (0.0, s.thickness + tg)])
        solids.append(m3d.Manifold.hull_points(pts))
    at: dict[int, list[int]] = {}
    for k, s in enumerate(strips):
        for node in s.vertices:
            at.setdefault(node, []).append(k)
    worst, pairs = 0.0, 0
    for ks in at.values():
        for a in range(len(ks)):
            for c in range(a + 1, len(ks)):
                pairs += 1
                worst = max(worst, (solids[ks[a]] ^ solids[ks[c]]).volume())
    assert pairs > 50
    assert worst < 1.0
